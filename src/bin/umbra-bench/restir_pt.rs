//! `umbra-bench restir-pt`: the path tracer's light sampling by RIS (at every vertex) against
//! power sampling (issue 22) on a many-light scene: per method (power; RIS with each candidate
//! count; RIS with reuse of the previous sample index's first-hit reservoirs, `--ris-reuse`, with
//! each reuse and candidate count of [`REUSE`]) a series over samples per pixel, each point the
//! path tracer's GPU time (median of repeats after a warm-up render) and the relative MSE of the
//! whole image (direct and indirect light) against a converged reference (power sampling at many
//! samples, its own noise subtracted from nothing: its relative MSE is charted as the floor).
//! Equal error: power sampling's time interpolated (log-log) at a RIS point's error, over that
//! point's time; power's series runs to [`POWER_SPP`] so that RIS's errors at 64 spp fall within it.

use super::chart::{self, Chart, ChartPoint};
use super::num;
use super::rays::median;
use super::restir::speedup_cell;
use super::suite::errors;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::Path;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{DirectSampling, RisReuse};
use umbra::render::{Passes, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::vk::Context;

/// What the benchmark renders.
pub struct RestirPtBench {
    /// Image size.
    pub size: (u32, u32),
    /// Samples per pixel of the reference (power sampling).
    pub reference_spp: u32,
    /// Scattering events per path.
    pub max_bounces: u32,
    /// Timed renders per point, each with its own seed (the median time and the mean error are
    /// reported).
    pub repeats: usize,
}

/// Samples per pixel of each RIS series' points.
const SPP: [u32; 7] = [1, 2, 4, 8, 16, 32, 64];
/// Samples per pixel of power sampling's points, the scale RIS's points are read against.
const POWER_SPP: [u32; 9] = [1, 2, 4, 8, 16, 32, 64, 128, 256];
/// The candidate counts of the RIS series without reuse.
const CANDIDATES: [u32; 2] = [16, 32];
/// The RIS series with reuse: what each reuses and its candidate count.
const REUSE: [(RisReuse, u32); 5] = [
    (RisReuse::Samples, 16),
    (RisReuse::Spatial, 16),
    (RisReuse::Both, 4),
    (RisReuse::Both, 16),
    (RisReuse::Both, 32),
];

/// One measured point.
pub struct Point {
    /// "power", "RIS M" or, with reuse, "RIS M + samples|spatial|both".
    pub method: String,
    /// RIS candidates (0 for power sampling).
    pub candidates: u32,
    /// The RIS's reuse (`RisReuse::name`: "off" without).
    pub reuse: &'static str,
    /// Samples per pixel.
    pub spp: u32,
    /// The path tracer's GPU time, ms.
    pub ms: f64,
    /// Relative MSE against the reference, the mean over the repeats' seeds.
    pub rel_mse: f64,
}

fn settings(s: &RestirPtBench, direct: DirectSampling, spp: u32, seed: u32) -> PathSettings {
    PathSettings { size: s.size, spp, seed, max_bounces: s.max_bounces, direct, ..PathSettings::default() }
}

/// Renders the reference and every point; returns the points and the reference's own relative
/// MSE (its noise floor).
pub fn run(ctx: &Context, scene: &Scene, camera: &Camera, s: &RestirPtBench) -> Result<(Vec<Point>, f64)> {
    let gpu_scene = GpuScene::upload(ctx, scene)?;
    let passes = Passes::new(ctx, &gpu_scene);
    let reference_settings = settings(s, DirectSampling::Power, s.reference_spp, 0x5eed);
    let reference = passes.path_trace(&gpu_scene, camera, &reference_settings, |_, _| {})?;
    let floor = f64::from(reference.relative_error()).powi(2);
    let mut runs = vec![(DirectSampling::Power, RisReuse::Off, "power".to_string())];
    runs.extend(CANDIDATES.map(|m| (DirectSampling::Ris(m), RisReuse::Off, format!("RIS {m}"))));
    runs.extend(
        REUSE.map(|(reuse, m)| (DirectSampling::Ris(m), reuse, format!("RIS {m} + {}", reuse.name()))),
    );
    let spps = |direct| if direct == DirectSampling::Power { &POWER_SPP[..] } else { &SPP[..] };
    let bar = super::progress_bar(runs.iter().map(|(direct, ..)| spps(*direct).len() as u64).sum(), "points");
    let mut points = Vec::new();
    for (direct, ris_reuse, method) in runs {
        for &spp in spps(direct) {
            let settings = PathSettings { ris_reuse, ..settings(s, direct, spp, 7) };
            passes.path_trace(&gpu_scene, camera, &settings, |_, _| {})?; // warm-up
            let mut times = Vec::new();
            let mut rel_mse = 0.0;
            let repeats = s.repeats.max(1);
            for repeat in 0..repeats {
                // Each repeat another seed: a light close to a surface that power picks rarely
                // gives rare, large samples, so one render's error is a poor estimate of the
                // expected error at few samples.
                let settings = PathSettings { seed: settings.seed + repeat as u32, ..settings.clone() };
                let render = passes.path_trace(&gpu_scene, camera, &settings, |_, _| {})?;
                times.push(render.gpu_ms);
                rel_mse += errors(&render.mean, &reference.mean).1 / repeats as f64;
            }
            points.push(Point {
                method: method.clone(),
                candidates: direct.candidates(),
                reuse: ris_reuse.name(),
                spp,
                ms: median(&mut times),
                rel_mse,
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    Ok((points, floor))
}

/// The JSON of a run.
pub fn to_json(device: &str, scene: &str, s: &RestirPtBench, points: &[Point], floor: f64) -> Value {
    json!({
        "device": device,
        "scene": scene,
        "size": [s.size.0, s.size.1],
        "reference_spp": s.reference_spp,
        "reference_rel_mse_floor": floor,
        "max_bounces": s.max_bounces,
        "repeats": s.repeats,
        "points": points.iter().map(|p| json!({
            "method": p.method,
            "candidates": p.candidates,
            "reuse": p.reuse,
            "spp": p.spp,
            "ms": p.ms,
            "rel_mse": p.rel_mse,
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run: per point its time and error, and for RIS power sampling's time
/// at the same error over RIS's.
pub fn table(doc: &Value) -> String {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let power: Vec<&Value> = points.iter().filter(|p| p["method"] == "power").collect();
    let mut out = format!(
        "{} at {}×{} on {} ({}), path tracer (megakernel), {} bounces; reference: {} spp of power sampling \
         (its own relative MSE {:.1e}):\n\n\
         | light sampling | spp | path tracer ms | rel. MSE (mean of {} seeds) | power sampling's time at this error ÷ this |\n\
         |---|---:|---:|---:|---:|\n",
        doc["scene"].as_str().unwrap_or("?"),
        doc["size"][0],
        doc["size"][1],
        doc["device"].as_str().unwrap_or("?"),
        super::conditions_text(doc),
        doc["max_bounces"],
        doc["reference_spp"],
        num(&doc["reference_rel_mse_floor"]),
        doc["repeats"],
    );
    for p in &points {
        let speedup = speedup_cell(&power, p, "spp", "spp");
        out += &format!(
            "| {} | {} | {:.1} | {:.4} | {speedup} |\n",
            p["method"].as_str().unwrap_or("?"),
            p["spp"],
            num(&p["ms"]),
            num(&p["rel_mse"]),
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
            unit: "spp",
            value: p["spp"].as_u64().unwrap_or(0) as u32,
            ms: num(&p["ms"]),
            error: num(&p["rel_mse"]),
        })
        .collect();
    let title = format!(
        "{}: path tracer, RIS against power sampling — {}",
        doc["scene"].as_str().unwrap_or("?"),
        doc["device"].as_str().unwrap_or("?")
    );
    let chart = Chart {
        title: &title,
        y_desc: "relative MSE of the image (log)",
        floor: num(&doc["reference_rel_mse_floor"]),
    };
    chart::write(&out.join("restir-pt"), &chart, &chart_points)
}
