//! One chart per scene: error (relative MSE, log) against GPU time (ms, log), every method a
//! series, as SVG and PNG (plotters; text drawn with the embedded DejaVu Sans).

use anyhow::{anyhow, Context as _, Result};
use image::ImageEncoder as _;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// DejaVu Sans (Bitstream Vera licence, `fonts/LICENSE-DejaVu`): the PNG's text needs a font and
/// a CI machine may have none installed.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

const SIZE: (u32, u32) = (900, 600);

/// Colours of the methods, in first-seen order.
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
];

/// One point of a chart: a method at one setting.
pub struct ChartPoint<'a> {
    /// The series (method) it belongs to.
    pub method: &'a str,
    /// What the point label counts (`spp`, `shadow_rays`, ...).
    pub unit: &'a str,
    /// The label.
    pub value: u32,
    /// GPU milliseconds (x).
    pub ms: f64,
    /// Error (y).
    pub error: f64,
}

/// A chart: title, y-axis description and an optional horizontal noise floor.
pub struct Chart<'a> {
    /// Title.
    pub title: &'a str,
    /// What the y axis measures.
    pub y_desc: &'a str,
    /// A horizontal line (the reference's own error), if positive.
    pub floor: f64,
}

/// Writes `<stem>.svg` and `<stem>.png`.
pub fn write(stem: &Path, chart: &Chart, points: &[ChartPoint]) -> Result<()> {
    // Registering twice is harmless; the font is valid (it is compiled in).
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow!("the embedded font does not load"))?;
    // Both drawn in memory, then written atomically (umbra::atomic).
    let svg = stem.with_extension("svg");
    let mut text = String::new();
    draw(SVGBackend::with_string(&mut text, SIZE).into_drawing_area(), chart, points)
        .with_context(|| format!("drawing {}", svg.display()))?;
    umbra::atomic::write(&svg, text.as_bytes())?;
    let mut pixels = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area(), chart, points)
        .context("drawing the PNG chart")?;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&pixels, SIZE.0, SIZE.1, image::ExtendedColorType::Rgb8)
        .context("encoding the PNG chart")?;
    umbra::atomic::write(&stem.with_extension("png"), &png)?;
    Ok(())
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, spec: &Chart, points: &[ChartPoint]) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("{e}");
    root.fill(&WHITE).map_err(err)?;
    let floor = spec.floor;
    let finite: Vec<&ChartPoint> = points.iter().filter(|p| p.ms > 0.0 && p.error > 0.0).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &finite {
        (x0, x1, y0, y1) = (x0.min(p.ms), x1.max(p.ms), y0.min(p.error), y1.max(p.error));
    }
    if floor > 0.0 {
        (y0, y1) = (y0.min(floor), y1.max(floor));
    }
    if finite.is_empty() {
        (x0, x1, y0, y1) = (0.1, 1.0, 0.1, 1.0);
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(spec.title, ("sans-serif", 18))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(72)
        .build_cartesian_2d((x0 / 1.5..x1 * 1.5).log_scale(), (y0 / 2.0..y1 * 2.0).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("GPU time per frame (ms, log)")
        .y_desc(spec.y_desc)
        .label_style(("sans-serif", 13))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(err)?;
    if floor > 0.0 {
        let grey = RGBColor(150, 150, 150);
        chart
            .draw_series(LineSeries::new([(x0 / 1.5, floor), (x1 * 1.5, floor)], grey.stroke_width(1)))
            .map_err(err)?
            .label("reference noise floor")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey));
    }
    let mut methods: Vec<&str> = Vec::new();
    for p in &finite {
        if !methods.contains(&p.method) {
            methods.push(p.method);
        }
    }
    for (k, method) in methods.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        let mut series: Vec<&&ChartPoint> = finite.iter().filter(|p| p.method == *method).collect();
        series.sort_by(|a, b| a.ms.total_cmp(&b.ms));
        // The legend names what the point labels count (`spp`, `shadow_rays`, ...).
        let label = format!("{method} (labels: {})", series[0].unit);
        chart
            .draw_series(LineSeries::new(series.iter().map(|p| (p.ms, p.error)), colour.stroke_width(2)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart
            .draw_series(series.iter().map(|p| Circle::new((p.ms, p.error), 4, colour.filled())))
            .map_err(err)?;
        chart
            .draw_series(series.iter().map(|p| {
                let style = ("sans-serif", 12).into_font().color(&colour);
                EmptyElement::at((p.ms, p.error)) + Text::new(format!("{}", p.value), (6, -16), style)
            }))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    root.present().map_err(err)?;
    Ok(())
}
