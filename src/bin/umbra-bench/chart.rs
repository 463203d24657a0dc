//! One chart per scene: error (relative MSE, log) against GPU time (ms, log), every method a
//! series, as SVG and PNG (plotters; text drawn with the embedded DejaVu Sans).
//!
//! Every series has its own colour and marker ([`series_style`]); the legend is a column right of
//! the plot ([`layout`]), never over the data; each point's label goes to the first place around
//! the point that no label placed before it takes ([`place_labels`]), and is left out where none
//! is free. The three are pure functions of pixel sizes, tested without drawing.

use anyhow::{anyhow, Context as _, Result};
use image::ImageEncoder as _;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// DejaVu Sans (Bitstream Vera licence, `fonts/LICENSE-DejaVu`): the PNG's text needs a font and
/// a CI machine may have none installed.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

const SIZE: (u32, u32) = (900, 600);

/// Colours of the methods, in first-seen order: Tableau's (less its grey, which the noise floor
/// uses), then black, magenta and blue. Its length and [`MARKERS`]' are coprime, so the first
/// `PALETTE.len() * MARKERS.len()` series all differ in (colour, marker).
const PALETTE: [RGBColor; 12] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 0),
    RGBColor(255, 0, 255),
    RGBColor(0, 0, 255),
];

/// The noise floor's line.
const FLOOR_GREY: RGBColor = RGBColor(150, 150, 150);

/// A point's marker.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Marker {
    Circle,
    Triangle,
    Square,
    Diamond,
    Cross,
    InvertedTriangle,
    Plus,
}

/// The markers of the methods, in first-seen order (cycled alongside [`PALETTE`]).
const MARKERS: [Marker; 7] = [
    Marker::Circle,
    Marker::Triangle,
    Marker::Square,
    Marker::Diamond,
    Marker::Cross,
    Marker::InvertedTriangle,
    Marker::Plus,
];

/// A marker's half-width in pixels.
const MARKER_R: i32 = 5;

/// ChartBuilder's margin around the chart's area, and its axis label areas.
const MARGIN: i32 = 14;
const X_LABEL_AREA: i32 = 44;
const Y_LABEL_AREA: i32 = 72;
/// The caption's band across the top.
const CAPTION_H: i32 = 34;
/// The legend column's widest share of the width.
const LEGEND_MAX_SHARE: f64 = 0.4;
/// The legend's inner padding, its swatch's length and the gap after it.
const LEGEND_PAD: i32 = 8;
const SWATCH: i32 = 26;
const SWATCH_GAP: i32 = 8;
/// Legend rows: one line of text, or a series name with a line below it naming its labels' unit.
const ROW: i32 = 20;
const ROW_TWO_LINES: i32 = 33;

/// Point labels: the distance from the point to the nearest label box, the rings of candidates
/// around it, and the clearance kept between two labels.
const LABEL_GAP: i32 = 6;
const LABEL_RINGS: i32 = 3;
const LABEL_CLEARANCE: i32 = 1;

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
    register_font()?;
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

fn register_font() -> Result<()> {
    // Registering twice is harmless; the font is valid (it is compiled in).
    plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
        .map_err(|_| anyhow!("the embedded font does not load"))
}

/// A rectangle in pixels, half-open: `x0 <= x < x1`, `y0 <= y < y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    fn at((x, y): (i32, i32), (w, h): (i32, i32)) -> Self {
        Rect { x0: x, y0: y, x1: x + w, y1: y + h }
    }

    fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    /// Whether the two share a pixel (an empty rectangle shares none).
    fn intersects(&self, o: &Rect) -> bool {
        !self.is_empty()
            && !o.is_empty()
            && self.x0 < o.x1
            && o.x0 < self.x1
            && self.y0 < o.y1
            && o.y0 < self.y1
    }

    fn contains(&self, o: &Rect) -> bool {
        self.x0 <= o.x0 && o.x1 <= self.x1 && self.y0 <= o.y0 && o.y1 <= self.y1
    }

    fn grown(&self, d: i32) -> Rect {
        Rect { x0: self.x0 - d, y0: self.y0 - d, x1: self.x1 + d, y1: self.y1 + d }
    }
}

/// A series' colour and marker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SeriesStyle {
    colour: RGBColor,
    marker: Marker,
}

/// The style of the `k`-th series (first-seen order): colours and markers cycle with coprime
/// periods, so no two of the first `PALETTE.len()` series share a colour and no two of the first
/// `PALETTE.len() * MARKERS.len()` share both.
fn series_style(k: usize) -> SeriesStyle {
    SeriesStyle { colour: PALETTE[k % PALETTE.len()], marker: MARKERS[k % MARKERS.len()] }
}

/// Where the parts of a chart go, in pixels of the whole image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Layout {
    /// ChartBuilder's area: the plot with its axes' labels.
    chart: Rect,
    /// The plotting area ChartBuilder makes of `chart`.
    plot: Rect,
    /// The legend's box.
    legend: Rect,
}

/// The layout of a `size` image whose legend asks for `legend` (width, height) pixels: the legend
/// is a column at the right, level with the plot's top, as large as asked up to
/// `LEGEND_MAX_SHARE` of the width and the height below the caption; the chart takes the rest of
/// the width, the caption's band excepted.
fn layout(size: (u32, u32), legend: (i32, i32)) -> Layout {
    let (w, h) = (size.0 as i32, size.1 as i32);
    let top = CAPTION_H + MARGIN;
    let legend_w = legend.0.clamp(0, (w as f64 * LEGEND_MAX_SHARE) as i32);
    let legend_h = legend.1.clamp(0, (h - top - MARGIN).max(0));
    let legend = Rect { x0: w - MARGIN - legend_w, y0: top, x1: w - MARGIN, y1: top + legend_h };
    // With no legend, the chart's own margin is the right margin.
    let chart_x1 = if legend_w > 0 { legend.x0 } else { w };
    let chart = Rect { x0: 0, y0: CAPTION_H, x1: chart_x1, y1: h };
    let plot = Rect {
        x0: chart.x0 + MARGIN + Y_LABEL_AREA,
        y0: chart.y0 + MARGIN,
        x1: (chart.x1 - MARGIN).max(chart.x0 + MARGIN + Y_LABEL_AREA),
        y1: (chart.y1 - MARGIN - X_LABEL_AREA).max(chart.y0 + MARGIN),
    };
    Layout { chart, plot, legend }
}

/// A point label to place: the point (pixels) and its text's size.
#[derive(Clone, Copy, Debug)]
struct Label {
    at: (i32, i32),
    size: (i32, i32),
}

/// The boxes a label may take around its point, in order of preference: up-right (plotters'
/// habit), right, down-right, above, below, up-left, left, down-left; then the same a ring further
/// out, `LABEL_RINGS` rings in all. None covers a marker of `MARKER_R` at the point.
fn label_candidates(label: &Label) -> impl Iterator<Item = Rect> + '_ {
    let (x, y) = label.at;
    let (w, h) = label.size;
    (0..LABEL_RINGS).flat_map(move |ring| {
        let d = LABEL_GAP + ring * (h + 2);
        [
            (x + d, y - d - h + 4),
            (x + d + 2, y - h / 2),
            (x + d, y + d - 4),
            (x - w / 2, y - d - h),
            (x - w / 2, y + d),
            (x - d - w, y - d - h + 4),
            (x - d - 2 - w, y - h / 2),
            (x - d - w, y + d - 4),
        ]
        .into_iter()
        .map(move |corner| Rect::at(corner, (w, h)))
    })
}

/// Places `labels` in the order given (earlier labels win): each takes the first of its
/// candidates ([`label_candidates`]) inside `bounds` that keeps `LABEL_CLEARANCE` from every label
/// placed before it and covers none of `markers`; failing that, the free one covering the fewest
/// markers; failing that, it is dropped (`None`).
fn place_labels(labels: &[Label], bounds: Rect, markers: &[Rect]) -> Vec<Option<Rect>> {
    let mut placed: Vec<Rect> = Vec::new();
    labels
        .iter()
        .map(|label| {
            let mut best: Option<(usize, Rect)> = None;
            for candidate in label_candidates(label) {
                let grown = candidate.grown(LABEL_CLEARANCE);
                if !bounds.contains(&candidate) || placed.iter().any(|p| p.intersects(&grown)) {
                    continue;
                }
                let covered = markers.iter().filter(|m| m.intersects(&candidate)).count();
                if best.is_none_or(|(fewest, _)| covered < fewest) {
                    best = Some((covered, candidate));
                    if covered == 0 {
                        break;
                    }
                }
            }
            let chosen = best.map(|(_, rect)| rect);
            placed.extend(chosen);
            chosen
        })
        .collect()
}

/// The box a marker covers.
fn marker_box((x, y): (i32, i32)) -> Rect {
    Rect { x0: x - MARKER_R, y0: y - MARKER_R, x1: x + MARKER_R + 1, y1: y + MARKER_R + 1 }
}

/// One legend row.
struct LegendEntry {
    name: String,
    /// A second, smaller line (what the series' point labels count).
    sub: Option<String>,
    colour: RGBColor,
    marker: Option<Marker>,
    line_width: u32,
}

/// Where a drawing put its parts (what the tests check of a real drawing).
#[cfg_attr(not(test), allow(dead_code))]
#[derive(Debug)]
struct Drawn {
    /// The plotting area as plotters made it.
    plot: Rect,
    legend: Rect,
    /// The legend's widest text and the room it had.
    legend_text: (i32, i32),
    /// The placed point labels, and how many were dropped.
    labels: Vec<Rect>,
    dropped: usize,
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    spec: &Chart,
    points: &[ChartPoint],
) -> Result<Drawn>
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
    let mut methods: Vec<&str> = Vec::new();
    for p in &finite {
        if !methods.contains(&p.method) {
            methods.push(p.method);
        }
    }
    // Each series sorted by time.
    let series: Vec<Vec<&ChartPoint>> = methods
        .iter()
        .map(|method| {
            let mut s: Vec<&ChartPoint> = finite.iter().copied().filter(|p| p.method == *method).collect();
            s.sort_by(|a, b| a.ms.total_cmp(&b.ms));
            s
        })
        .collect();

    // The legend: what the point labels count once at the bottom if every series counts the same,
    // else under each series' name.
    let units: Vec<&str> = series.iter().map(|s| s[0].unit).collect();
    let shared_unit = units.iter().all(|u| *u == units[0]);
    let mut entries = Vec::new();
    if floor > 0.0 {
        entries.push(LegendEntry {
            name: "reference noise floor".into(),
            sub: None,
            colour: FLOOR_GREY,
            marker: None,
            line_width: 1,
        });
    }
    for (k, method) in methods.iter().enumerate() {
        let style = series_style(k);
        entries.push(LegendEntry {
            name: method.to_string(),
            sub: (!shared_unit).then(|| format!("labels: {}", units[k])),
            colour: style.colour,
            marker: Some(style.marker),
            line_width: 2,
        });
    }
    let footer = match (shared_unit, units.first()) {
        (true, Some(unit)) => Some(format!("point labels: {unit}")),
        _ => None,
    };
    let name_font = ("sans-serif", 13).into_font().color(&BLACK);
    let sub_font = ("sans-serif", 11).into_font().color(&RGBColor(90, 90, 90));
    let width = |text: &str, font: &TextStyle| -> Result<i32> {
        Ok(root.estimate_text_size(text, font).map_err(err)?.0 as i32)
    };
    let mut text_w = 0;
    for e in &entries {
        text_w = text_w.max(width(&e.name, &name_font)?);
        if let Some(sub) = &e.sub {
            text_w = text_w.max(width(sub, &sub_font)?);
        }
    }
    if let Some(footer) = &footer {
        text_w = text_w.max(width(footer, &sub_font)?);
    }
    let row = if entries.iter().any(|e| e.sub.is_some()) { ROW_TWO_LINES } else { ROW };
    let rows_h = row * entries.len() as i32 + if footer.is_some() { ROW } else { 0 };
    let text_x = LEGEND_PAD + SWATCH + SWATCH_GAP;
    let legend_ask = match entries.is_empty() {
        true => (0, 0),
        false => (text_x + text_w + LEGEND_PAD, rows_h + 2 * LEGEND_PAD - 4),
    };
    let layout = layout(root.dim_in_pixel(), legend_ask);
    let text_room = layout.legend.x1 - layout.legend.x0 - text_x - LEGEND_PAD;

    // The caption over the whole width.
    let caption = ("sans-serif", 18).into_font().color(&BLACK).pos(Pos::new(HPos::Center, VPos::Top));
    root.draw_text(spec.title, &caption, (root.dim_in_pixel().0 as i32 / 2, 8)).map_err(err)?;

    // The axes' ranges: the points' with room around them.
    let (xs, ys) = ((x0 / 1.5, x1 * 1.5), (y0 / 2.0, y1 * 2.0));
    let c = layout.chart;
    let chart_area = root.clone().shrink((c.x0, c.y0), (c.x1 - c.x0, c.y1 - c.y0));
    let mut chart = ChartBuilder::on(&chart_area)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
        .map_err(err)?;
    let (px, py) = chart.plotting_area().get_pixel_range();
    let plot = Rect { x0: px.start, y0: py.start, x1: px.end, y1: py.end };
    chart
        .configure_mesh()
        .x_desc("GPU time per frame (ms, log)")
        .y_desc(spec.y_desc)
        .label_style(("sans-serif", 13))
        .x_label_formatter(&|v| log_tick_label(*v, (xs.1 / xs.0).log10(), |v| format!("{v}")))
        .y_label_formatter(&|v| log_tick_label(*v, (ys.1 / ys.0).log10(), |v| format!("{v:.0e}")))
        .draw()
        .map_err(err)?;
    if floor > 0.0 {
        chart
            .draw_series(LineSeries::new([(xs.0, floor), (xs.1, floor)], FLOOR_GREY.stroke_width(1)))
            .map_err(err)?;
    }
    for (k, s) in series.iter().enumerate() {
        let colour = series_style(k).colour;
        chart
            .draw_series(LineSeries::new(s.iter().map(|p| (p.ms, p.error)), colour.stroke_width(2)))
            .map_err(err)?;
    }
    // Markers and labels in pixels: the labels placed around every marker.
    let mut anchors = Vec::new();
    let mut labels = Vec::new();
    let label_font = |colour: RGBColor| ("sans-serif", 12).into_font().color(&colour);
    for (k, s) in series.iter().enumerate() {
        let style = series_style(k);
        for (i, p) in s.iter().enumerate() {
            let at = chart.backend_coord(&(p.ms, p.error));
            draw_marker(&root, style, at).map_err(err)?;
            anchors.push(at);
            let text = p.value.to_string();
            let (w, h) = root.estimate_text_size(&text, &label_font(style.colour)).map_err(err)?;
            // Each series' ends first, then inwards, the series taking turns.
            let rank = i.min(s.len() - 1 - i);
            labels.push((rank, k, text, Label { at, size: (w as i32, h as i32) }));
        }
    }
    labels.sort_by_key(|(rank, k, _, _)| (*rank, *k));
    let markers: Vec<Rect> = anchors.iter().map(|&at| marker_box(at)).collect();
    let requests: Vec<Label> = labels.iter().map(|l| l.3).collect();
    let placed = place_labels(&requests, plot, &markers);
    for ((_, k, text, _), rect) in labels.iter().zip(&placed) {
        if let Some(r) = rect {
            // A veil keeps the text readable over lines and grid.
            root.draw(&Rectangle::new([(r.x0, r.y0), (r.x1 - 1, r.y1 - 1)], WHITE.mix(0.75).filled()))
                .map_err(err)?;
            root.draw_text(text, &label_font(series_style(*k).colour), (r.x0, r.y0)).map_err(err)?;
        }
    }

    // The legend, right of the chart.
    let l = layout.legend;
    if !entries.is_empty() {
        root.draw(&Rectangle::new([(l.x0, l.y0), (l.x1 - 1, l.y1 - 1)], WHITE.filled())).map_err(err)?;
        root.draw(&Rectangle::new([(l.x0, l.y0), (l.x1 - 1, l.y1 - 1)], BLACK.stroke_width(1)))
            .map_err(err)?;
        let fit =
            |text: &str, font: &TextStyle| -> Result<String> { shorten(text, text_room, |t| width(t, font)) };
        let mut y = l.y0 + LEGEND_PAD;
        for e in &entries {
            if y + ROW > l.y1 {
                break;
            }
            let mid = (l.x0 + LEGEND_PAD, y + 8);
            let end = (mid.0 + SWATCH, mid.1);
            root.draw(&PathElement::new(vec![mid, end], e.colour.stroke_width(e.line_width))).map_err(err)?;
            if let Some(marker) = e.marker {
                draw_marker(&root, SeriesStyle { colour: e.colour, marker }, (mid.0 + SWATCH / 2, mid.1))
                    .map_err(err)?;
            }
            root.draw_text(&fit(&e.name, &name_font)?, &name_font, (l.x0 + text_x, y)).map_err(err)?;
            if let Some(sub) = &e.sub {
                root.draw_text(&fit(sub, &sub_font)?, &sub_font, (l.x0 + text_x, y + 16)).map_err(err)?;
            }
            y += row;
        }
        if let Some(footer) = &footer {
            root.draw_text(&fit(footer, &sub_font)?, &sub_font, (l.x0 + LEGEND_PAD, y + 2)).map_err(err)?;
        }
    }
    root.present().map_err(err)?;
    debug_assert_eq!(plot, layout.plot, "plotters' plotting area is where the layout puts it");
    let dropped = placed.iter().filter(|p| p.is_none()).count();
    Ok(Drawn {
        plot,
        legend: layout.legend,
        legend_text: (text_w, text_room),
        labels: placed.into_iter().flatten().collect(),
        dropped,
    })
}

/// `text`, cut short with an ellipsis where `width` of it exceeds `room`.
fn shorten(text: &str, room: i32, width: impl Fn(&str) -> Result<i32>) -> Result<String> {
    if width(text)? <= room {
        return Ok(text.to_string());
    }
    let chars: Vec<char> = text.chars().collect();
    for n in (0..chars.len()).rev() {
        let cut: String = chars[..n].iter().collect::<String>() + "…";
        if width(&cut)? <= room {
            return Ok(cut);
        }
    }
    Ok(String::new())
}

/// Draws `style`'s marker centred at `(x, y)` (pixels of `area`).
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    style: SeriesStyle,
    (x, y): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let r = MARKER_R;
    let fill = style.colour.filled();
    let line = style.colour.stroke_width(2);
    let polygon = |points: Vec<(i32, i32)>| -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        area.draw(&Polygon::new(points.clone(), fill))?;
        // A white rim keeps overlapping markers apart.
        let mut rim = points;
        rim.push(rim[0]);
        area.draw(&PathElement::new(rim, WHITE.stroke_width(1)))
    };
    match style.marker {
        Marker::Circle => {
            area.draw(&Circle::new((x, y), r - 1, fill))?;
            area.draw(&Circle::new((x, y), r - 1, WHITE.stroke_width(1)))
        }
        Marker::Square => polygon(vec![
            (x - r + 1, y - r + 1),
            (x + r - 1, y - r + 1),
            (x + r - 1, y + r - 1),
            (x - r + 1, y + r - 1),
        ]),
        Marker::Diamond => polygon(vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)]),
        Marker::Triangle => polygon(vec![(x, y - r), (x + r, y + r - 1), (x - r, y + r - 1)]),
        Marker::InvertedTriangle => polygon(vec![(x, y + r), (x + r, y - r + 1), (x - r, y - r + 1)]),
        Marker::Cross => {
            area.draw(&PathElement::new(vec![(x - r + 1, y - r + 1), (x + r - 1, y + r - 1)], line))?;
            area.draw(&PathElement::new(vec![(x - r + 1, y + r - 1), (x + r - 1, y - r + 1)], line))
        }
        Marker::Plus => {
            area.draw(&PathElement::new(vec![(x - r, y), (x + r, y)], line))?;
            area.draw(&PathElement::new(vec![(x, y - r), (x, y + r)], line))
        }
    }
}

/// The label of a log axis's tick at `v` on an axis spanning `decades`: every tick on an axis of
/// under one decade; else only at 1, 2 and 5 times a power of ten, since plotters puts a tick at
/// every integer multiple and on a wide axis their labels (3 to 9 times, 10 to 30 px apart) run
/// together.
fn log_tick_label(v: f64, decades: f64, format: impl Fn(f64) -> String) -> String {
    if decades < 1.0 {
        return format(v);
    }
    let mantissa = v / 10f64.powf(v.log10().floor());
    let kept = [1.0, 2.0, 5.0, 10.0].iter().any(|m| (mantissa - m).abs() < 1e-6 * m);
    if kept {
        format(v)
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    /// CIE L*a*b* of an sRGB colour (D65).
    fn lab(c: RGBColor) -> [f64; 3] {
        let lin = |u: u8| {
            let u = u as f64 / 255.0;
            if u <= 0.04045 {
                u / 12.92
            } else {
                ((u + 0.055) / 1.055).powf(2.4)
            }
        };
        let (r, g, b) = (lin(c.0), lin(c.1), lin(c.2));
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
        let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
        let f = |t: f64| if t > 0.008856 { t.cbrt() } else { 7.787 * t + 16.0 / 116.0 };
        [116.0 * f(y) - 16.0, 500.0 * (f(x) - f(y)), 200.0 * (f(y) - f(z))]
    }

    /// CIE76 colour difference.
    fn delta_e(a: RGBColor, b: RGBColor) -> f64 {
        let (a, b) = (lab(a), lab(b));
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    fn overlapping(boxes: &[Rect]) -> Option<(Rect, Rect)> {
        for (i, a) in boxes.iter().enumerate() {
            for b in &boxes[i + 1..] {
                if a.intersects(b) {
                    return Some((*a, *b));
                }
            }
        }
        None
    }

    #[test]
    fn every_series_has_its_own_colour_and_marker() {
        let colours: HashSet<RGBColor> = (0..PALETTE.len()).map(|k| series_style(k).colour).collect();
        assert_eq!(colours.len(), PALETTE.len(), "the first {} series share a colour", PALETTE.len());
        let markers: HashSet<Marker> = (0..MARKERS.len()).map(|k| series_style(k).marker).collect();
        assert_eq!(markers.len(), MARKERS.len(), "the first {} series share a marker", MARKERS.len());
        let pairs = PALETTE.len() * MARKERS.len();
        let mut seen = HashSet::new();
        for k in 0..pairs {
            let s = series_style(k);
            assert!(seen.insert((s.colour, s.marker)), "series {k} repeats the style {s:?}");
        }
        assert!(PALETTE.len() >= 10, "a palette of at least 10 colours");
    }

    #[test]
    fn palette_colours_are_told_apart() {
        for (i, &a) in PALETTE.iter().enumerate() {
            assert!(delta_e(a, WHITE) > 40.0, "{a:?} is faint on white");
            assert!(delta_e(a, FLOOR_GREY) > 30.0, "{a:?} looks like the noise floor's grey");
            for &b in &PALETTE[i + 1..] {
                assert!(delta_e(a, b) > 25.0, "{a:?} and {b:?} are hard to tell apart: ΔE {}", delta_e(a, b));
            }
        }
    }

    #[test]
    fn labels_of_a_dense_cluster_do_not_overlap() {
        let bounds = Rect { x0: 0, y0: 0, x1: 600, y1: 400 };
        // 12 points within 3 pixels, labels 1 to 4 digits wide.
        let labels: Vec<Label> =
            (0..12).map(|i| Label { at: (300 + i % 4, 200 + i / 4), size: (8 + 7 * (i % 4), 14) }).collect();
        let markers: Vec<Rect> = labels.iter().map(|l| marker_box(l.at)).collect();
        let placed = place_labels(&labels, bounds, &markers);
        assert_eq!(placed.len(), labels.len());
        let boxes: Vec<Rect> = placed.iter().flatten().copied().collect();
        assert_eq!(overlapping(&boxes), None, "overlapping labels");
        for (label, rect) in labels.iter().zip(&placed) {
            if let Some(r) = rect {
                assert!(bounds.contains(r), "{r:?} outside the plot");
                assert_eq!((r.x1 - r.x0, r.y1 - r.y0), label.size, "the box is the text's size");
            }
        }
        assert!(boxes.len() >= 10, "only {} of 12 labels placed: {placed:?}", boxes.len());
    }

    #[test]
    fn labels_stay_inside_the_plot_and_off_markers() {
        let bounds = Rect { x0: 100, y0: 50, x1: 500, y1: 300 };
        let size = (24, 14);
        // Alone in the middle: up and to the right, clear of its marker.
        let mid = Label { at: (300, 150), size };
        let placed = place_labels(&[mid], bounds, &[marker_box(mid.at)]);
        let r = placed[0].expect("a lone label is placed");
        assert_eq!((r.x0, r.y1), (306, 148));
        // In the top right corner: turned down and left, inside the plot, off the marker.
        let corner = Label { at: (498, 52), size };
        let r = place_labels(&[corner], bounds, &[marker_box(corner.at)])[0].expect("placed");
        assert!(bounds.contains(&r) && !r.intersects(&marker_box(corner.at)), "{r:?}");
        // A label that fits nowhere is dropped, not squeezed in.
        let big = Label { at: (300, 150), size: (1000, 14) };
        assert_eq!(place_labels(&[big], bounds, &[]), vec![None]);
    }

    #[test]
    fn the_legend_is_beside_the_plot() {
        for size in [(900, 600), (640, 480), (1600, 900)] {
            for ask in [(0, 0), (120, 80), (260, 400), (2000, 2000)] {
                let l = layout(size, ask);
                let image = Rect { x0: 0, y0: 0, x1: size.0 as i32, y1: size.1 as i32 };
                assert!(!l.legend.intersects(&l.plot), "{size:?} {ask:?}: legend over the plot: {l:?}");
                assert!(!l.legend.intersects(&l.chart), "{size:?} {ask:?}: legend over the axes: {l:?}");
                assert!(image.contains(&l.legend) && image.contains(&l.chart), "{l:?}");
                assert!(l.chart.contains(&l.plot) && l.plot.x1 - l.plot.x0 > size.0 as i32 / 3, "{l:?}");
                let cap = (size.0 as f64 * LEGEND_MAX_SHARE) as i32;
                assert_eq!(l.legend.x1 - l.legend.x0, ask.0.min(cap), "{size:?} {ask:?}: legend width");
                if ask.1 <= 400 {
                    assert_eq!(l.legend.y1 - l.legend.y0, ask.1, "{size:?} {ask:?}: legend height");
                }
            }
        }
    }

    /// Fourteen series crowded together, drawn for real: plotters' plot is the layout's, the legend
    /// is beside it and holds every name, and the labels neither overlap nor leave the plot.
    #[test]
    fn a_drawn_chart_keeps_labels_apart_and_the_legend_outside() {
        register_font().unwrap();
        let names: Vec<String> =
            (0..14).map(|k| format!("hybrid, method number {k} with a long name")).collect();
        let units = ["spp", "shadow_rays"];
        let mut points = Vec::new();
        for (k, name) in names.iter().enumerate() {
            for i in 0..6 {
                points.push(ChartPoint {
                    method: name,
                    unit: units[k % 2],
                    value: 1 << (i + k % 3),
                    ms: 20.0 * (1.0 + 0.02 * (k + i) as f64),
                    error: 1.5 * (1.0 - 0.01 * (i as f64 + k as f64 / 3.0)),
                });
            }
        }
        let chart = Chart { title: "crowded", y_desc: "error", floor: 1e-3 };
        let mut pixels = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
        let drawn = draw(BitMapBackend::with_buffer(&mut pixels, SIZE).into_drawing_area(), &chart, &points)
            .expect("drawn");
        let (text_w, text_room) = drawn.legend_text;
        let ask = (LEGEND_PAD + SWATCH + SWATCH_GAP + text_w + LEGEND_PAD, 0);
        assert_eq!(drawn.plot, layout(SIZE, (ask.0, 0)).plot, "the plot is where the layout says");
        assert!(!drawn.legend.intersects(&drawn.plot), "{drawn:?}");
        assert!(text_w <= text_room, "the legend is too narrow for its names: {drawn:?}");
        assert_eq!(overlapping(&drawn.labels), None, "overlapping labels");
        assert!(drawn.labels.iter().all(|r| drawn.plot.contains(r)), "a label outside the plot");
        assert_eq!(drawn.labels.len() + drawn.dropped, points.len());
        assert!(drawn.labels.len() >= 14, "only {} labels placed", drawn.labels.len());
    }

    /// On a wide log axis only 1, 2 and 5 times a power of ten are labelled, so neighbouring
    /// labels stay apart; on a narrow one every tick is.
    #[test]
    fn wide_log_axes_label_one_two_and_five_only() {
        let labels = |decades: f64, ticks: &[f64]| -> Vec<String> {
            ticks.iter().map(|&v| log_tick_label(v, decades, |v| format!("{v}"))).collect()
        };
        let ticks = [3.0, 5.0, 7.0, 8.0, 9.0, 10.0, 20.0, 30.0, 50.0, 200.0, 0.5, 0.7];
        let wide = labels(2.5, &ticks);
        let kept: Vec<&str> = wide.iter().filter(|l| !l.is_empty()).map(|l| l.as_str()).collect();
        assert_eq!(kept, ["5", "10", "20", "50", "200", "0.5"]);
        // At 560 px for 2.5 decades the labels kept are at least log10(2) · 224 = 67 px apart.
        assert!(labels(0.6, &ticks).iter().all(|l| !l.is_empty()), "a narrow axis labels every tick");
    }
}
