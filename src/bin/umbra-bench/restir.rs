//! `umbra-bench restir`: ReSTIR DI against power-sampled light sampling in the hybrid renderer's
//! lighting pass (issue 22), on a many-light scene. The reference is the mean of many frames of
//! power sampling with 64 shadow rays (direct light only: no image-based light, no SSAO, so the
//! image is the direct-light estimate). Per method and setting: the GPU time of one frame's
//! direct light (the lighting pass, plus ReSTIR's passes; median of repeats after a warm-up
//! render) and the relative MSE of that frame against the reference (ReSTIR's frame is the last
//! of `frames` with a still camera, so its temporal reuse has a history). Equal error: power
//! sampling's time interpolated (log-log) at ReSTIR's error, over ReSTIR's time.

use super::chart::{self, Chart, ChartPoint};
use super::num;
use super::rays::median;
use super::suite::errors;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::Path;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::{DirectLight, LightingSettings};
use umbra::passes::restir::RestirSettings;
use umbra::render::{HybridSettings, Passes};
use umbra::scene::{Camera, Scene};
use umbra::vk::Context;

/// What the benchmark renders.
pub struct RestirBench {
    /// Image size.
    pub size: (u32, u32),
    /// Frames averaged into the reference.
    pub reference_frames: u32,
    /// Timed renders per point (the median is reported).
    pub repeats: usize,
    /// ReSTIR's frames with a still camera before the measured one is shown (its history).
    pub frames: u32,
}

/// One measured point.
pub struct Point {
    /// The method ("power", "ReSTIR biased", ...).
    pub method: String,
    /// What `value` counts (`shadow_rays` or `candidates`).
    pub unit: &'static str,
    /// Its setting.
    pub value: u32,
    /// GPU time of one frame's direct light, ms.
    pub ms: f64,
    /// Relative MSE against the reference.
    pub rel_mse: f64,
    /// Mean radiance over the reference's (bias shows here).
    pub mean_ratio: f64,
}

fn settings(s: &RestirBench, direct: DirectLight, shadow_rays: u32, seed: u32) -> HybridSettings {
    HybridSettings {
        size: s.size,
        lighting: LightingSettings { seed, shadow_rays, ibl: false, direct, ..Default::default() },
        ao: None,
        ..Default::default()
    }
}

fn mean(image: &[[f32; 4]]) -> f64 {
    image.iter().map(|c| (c[0] + c[1] + c[2]) as f64).sum::<f64>() / (3 * image.len().max(1)) as f64
}

/// Renders the reference and every point; returns the points and the reference's own relative
/// MSE (its noise floor).
pub fn run(ctx: &Context, scene: &Scene, camera: &Camera, s: &RestirBench) -> Result<(Vec<Point>, f64)> {
    let gpu_scene = GpuScene::upload(ctx, scene)?;
    let passes = Passes::new(ctx, &gpu_scene);
    // The reference: the mean of many frames of 64 shadow rays, and its variance of the mean.
    let bar = super::progress_bar(s.reference_frames as u64, "reference");
    let pixels = (s.size.0 * s.size.1) as usize;
    let (mut sum, mut sum2) = (vec![[0.0f64; 3]; pixels], vec![[0.0f64; 3]; pixels]);
    for f in 0..s.reference_frames {
        let image = passes.hybrid(&gpu_scene, camera, &settings(s, DirectLight::Power, 64, 1_000_000 + f))?;
        for (i, c) in image.color.iter().enumerate() {
            for k in 0..3 {
                sum[i][k] += c[k] as f64;
                sum2[i][k] += (c[k] as f64).powi(2);
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let n = s.reference_frames as f64;
    let reference: Vec<[f32; 4]> =
        sum.iter().map(|m| [(m[0] / n) as f32, (m[1] / n) as f32, (m[2] / n) as f32, 1.0]).collect();
    let floor = sum
        .iter()
        .zip(&sum2)
        .map(|(m, m2)| {
            (0..3)
                .map(|k| {
                    let mean = m[k] / n;
                    let var_of_mean = (m2[k] / n - mean * mean).max(0.0) / (n - 1.0).max(1.0);
                    var_of_mean / (mean * mean + super::suite::REL_EPSILON)
                })
                .sum::<f64>()
        })
        .sum::<f64>()
        / (3 * pixels) as f64;
    let reference_mean = mean(&reference);

    let restir = |candidates, unbiased, temporal, neighbours| {
        DirectLight::Restir(RestirSettings {
            candidates,
            unbiased,
            temporal,
            neighbours,
            frames: if temporal { s.frames } else { 1 },
            ..Default::default()
        })
    };
    let mut runs: Vec<(String, &'static str, u32, DirectLight, u32)> = Vec::new();
    for rays in [1, 4, 16, 64] {
        runs.push(("power".into(), "shadow_rays", rays, DirectLight::Power, rays));
    }
    for m in [4, 16, 32] {
        runs.push(("RIS alone".into(), "candidates", m, restir(m, true, false, 0), 1));
        runs.push(("ReSTIR unbiased".into(), "candidates", m, restir(m, true, true, 5), 1));
        runs.push(("ReSTIR biased".into(), "candidates", m, restir(m, false, true, 5), 1));
    }
    let bar = super::progress_bar(runs.len() as u64, "methods");
    let mut points = Vec::new();
    for (method, unit, value, direct, rays) in runs {
        let settings = settings(s, direct, rays, 7);
        passes.hybrid(&gpu_scene, camera, &settings)?; // warm-up: pipelines built, first dispatches
        let mut times = Vec::new();
        let mut image = None;
        for _ in 0..s.repeats.max(1) {
            let render = passes.hybrid(&gpu_scene, camera, &settings)?;
            times.push(
                render
                    .pass_ms
                    .iter()
                    .filter(|(name, _)| name == "restir" || name == "lighting")
                    .map(|(_, ms)| ms)
                    .sum(),
            );
            image = Some(render.color);
        }
        let image = image.expect("at least one repeat");
        let (_, rel_mse) = errors(&image, &reference);
        points.push(Point {
            method,
            unit,
            value,
            ms: median(&mut times),
            rel_mse,
            mean_ratio: mean(&image) / reference_mean,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok((points, floor))
}

/// Power sampling's time at relative MSE `error`, interpolated log-log between its two points
/// around it: `Within(ms)`; beyond its points, the bound they give: `Below(ms)` (its most
/// accurate point's error is still above `error`, so it would take longer than that point),
/// `Above(ms)` (its cheapest point is already better).
pub(super) enum PowerTime {
    Within(f64),
    Below(f64),
    Above(f64),
}

pub(super) fn power_time_at(points: &[&Value], error: f64) -> Option<PowerTime> {
    let mut pts: Vec<(f64, f64)> = points.iter().map(|p| (num(&p["rel_mse"]), num(&p["ms"]))).collect();
    pts.sort_by(|a, b| b.0.total_cmp(&a.0)); // decreasing error
    let (first, last) = (*pts.first()?, *pts.last()?);
    if error > first.0 {
        return Some(PowerTime::Above(first.1));
    }
    if error < last.0 {
        return Some(PowerTime::Below(last.1));
    }
    let w = pts.windows(2).find(|w| error <= w[0].0 && error >= w[1].0)?;
    let ((e0, t0), (e1, t1)) = ((w[0].0.ln(), w[0].1.ln()), (w[1].0.ln(), w[1].1.ln()));
    let t = if e0 == e1 { t0 } else { t0 + (error.ln() - e0) * (t1 - t0) / (e1 - e0) };
    Some(PowerTime::Within(t.exp()))
}

/// The last column of a table row `p`: power sampling's time at `p`'s error over `p`'s time,
/// or the bound power sampling's points give (`most`, `one`: what power sampling's setting
/// counts, plural and singular); "—" for power sampling's own rows.
pub(super) fn speedup_cell(power: &[&Value], p: &Value, most: &str, one: &str) -> String {
    if p["method"] == "power" {
        return "—".to_string();
    }
    let ms = num(&p["ms"]);
    match power_time_at(power, num(&p["rel_mse"])) {
        Some(PowerTime::Within(t)) => format!("{:.1}×", t / ms),
        Some(PowerTime::Below(t)) => format!("> {:.1}× (below power's error at its most {most})", t / ms),
        Some(PowerTime::Above(t)) => format!("< {:.1}× (above power's error at 1 {one})", t / ms),
        None => "—".into(),
    }
}

/// The JSON of a run.
pub fn to_json(device: &str, scene: &str, s: &RestirBench, points: &[Point], floor: f64) -> Value {
    json!({
        "device": device,
        "scene": scene,
        "size": [s.size.0, s.size.1],
        "reference_frames": s.reference_frames,
        "reference_rel_mse_floor": floor,
        "repeats": s.repeats,
        "frames": s.frames,
        "points": points.iter().map(|p| json!({
            "method": p.method,
            "unit": p.unit,
            "value": p.value,
            "ms": p.ms,
            "rel_mse": p.rel_mse,
            "mean_ratio": p.mean_ratio,
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run: per point its time, error, mean against the reference's, and
/// for ReSTIR power sampling's time at the same error over ReSTIR's.
pub fn table(doc: &Value) -> String {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let power: Vec<&Value> = points.iter().filter(|p| p["method"] == "power").collect();
    let mut out = format!(
        "{} at {}×{} on {} ({}), direct light only; reference: {} frames of power sampling with 64 shadow rays \
         (its own relative MSE {:.1e}); ReSTIR's frame is the last of {} with a still camera:\n\n\
         | method | setting | direct light ms | rel. MSE | mean / reference | power sampling's time at this error ÷ this |\n\
         |---|---|---:|---:|---:|---:|\n",
        doc["scene"].as_str().unwrap_or("?"),
        doc["size"][0],
        doc["size"][1],
        doc["device"].as_str().unwrap_or("?"),
        super::conditions_text(doc),
        doc["reference_frames"],
        num(&doc["reference_rel_mse_floor"]),
        doc["frames"],
    );
    for p in &points {
        let speedup = speedup_cell(&power, p, "rays", "ray");
        out += &format!(
            "| {} | {} {} | {:.1} | {:.3} | {:.3} | {speedup} |\n",
            p["method"].as_str().unwrap_or("?"),
            p["value"],
            p["unit"].as_str().unwrap_or("?").replace('_', " "),
            num(&p["ms"]),
            num(&p["rel_mse"]),
            num(&p["mean_ratio"]),
        );
    }
    out
}

/// The error-against-time chart of a run.
pub fn write_chart(out: &Path, doc: &Value) -> Result<()> {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let chart_points: Vec<ChartPoint> = points
        .iter()
        .map(|p| ChartPoint {
            method: p["method"].as_str().unwrap_or("?"),
            unit: if p["unit"] == "shadow_rays" { "shadow_rays" } else { "candidates" },
            value: p["value"].as_u64().unwrap_or(0) as u32,
            ms: num(&p["ms"]),
            error: num(&p["rel_mse"]),
        })
        .collect();
    let title = format!(
        "{}: ReSTIR DI against power sampling — {}",
        doc["scene"].as_str().unwrap_or("?"),
        doc["device"].as_str().unwrap_or("?")
    );
    let chart = Chart {
        title: &title,
        y_desc: "relative MSE of the direct light (log)",
        floor: num(&doc["reference_rel_mse_floor"]),
    };
    chart::write(&out.join("restir"), &chart, &chart_points)
}
