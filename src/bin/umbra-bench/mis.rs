//! The estimators side by side (the course's MIS figure, measured): on the scenes of Mitsuba
//! references (tests/reference/mitsuba), each microfacet sampling of the reference's distribution
//! × {MIS with the power heuristic, MIS with the balance heuristic, BSDF sampling alone, light
//! sampling alone} at one sample count, its relative MSE against the reference, averaged over
//! independent seeds. The reference's own noise is taken out: E[(x − r)²] = MSE(x) + var(r) for
//! independent x and r, and the reference stores var(r).
//!
//! Relative MSE: the mean over pixels and channels of ((x − r)² − var(r)) / (r² + 0.01), as the
//! other benchmarks' (shadows.rs) without the noise term.

use anyhow::{Context as _, Result};
use serde_json::{json, Value};
use std::path::Path;
use umbra::passes::pathtrace::{Heuristic, Microfacet, PathSettings, Strategy};
use umbra::vk::Context;

/// The estimators measured: (strategy, heuristic); the heuristic matters to MIS only.
const ESTIMATORS: [(Strategy, Heuristic); 4] = [
    (Strategy::Mis, Heuristic::Power),
    (Strategy::Mis, Heuristic::Balance),
    (Strategy::Bsdf, Heuristic::Power),
    (Strategy::Light, Heuristic::Power),
];

/// One estimator's measurement on one reference.
pub struct Measurement {
    /// The reference's name.
    pub reference: String,
    /// Microfacet sampling.
    pub microfacet: Microfacet,
    /// Strategy.
    pub strategy: Strategy,
    /// Heuristic (MIS only).
    pub heuristic: Heuristic,
    /// Relative MSE per seed.
    pub rel_mse: Vec<f64>,
    /// Median GPU milliseconds of a render.
    pub gpu_ms: f64,
}

/// A Mitsuba reference: its scene, environment, size and per-pixel mean and variance of the mean.
struct Reference {
    scene: umbra::scene::Scene,
    environment: Option<umbra::environment::EnvironmentMap>,
    microfacet: Microfacet,
    size: (u32, u32),
    bounces: u32,
    mean: Vec<[f64; 3]>,
    variance: Vec<[f64; 3]>,
}

/// Loads `dir/name.json` and `dir/name.exr`; the JSON's scene and environment paths are relative
/// to the working directory (the repository root).
fn load(dir: &Path, name: &str) -> Result<Reference> {
    let json_path = dir.join(format!("{name}.json"));
    let meta: Value = serde_json::from_str(
        &std::fs::read_to_string(&json_path).with_context(|| format!("reading {}", json_path.display()))?,
    )
    .with_context(|| format!("parsing {}", json_path.display()))?;
    let field =
        |key: &str| meta[key].as_str().with_context(|| format!("{}: no \"{key}\"", json_path.display()));
    let scene = umbra::scene::Scene::load(Path::new(field("scene")?))?;
    let environment = match meta["environment"].as_str() {
        Some(path) => Some(umbra::environment::EnvironmentMap::load(Path::new(path))?),
        None => None,
    };
    let microfacet = match field("microfacet")? {
        "beckmann" => Microfacet::Beckmann,
        _ => Microfacet::Ggx,
    };
    let exr = dir.join(format!("{name}.exr"));
    let (w, h, channels) = umbra::output::read_exr_channels(&exr)?;
    let channel = |c: &str| {
        channels
            .iter()
            .find(|(n, _)| n == c)
            .map(|(_, v)| v)
            .with_context(|| format!("{}: no channel {c}", exr.display()))
    };
    let rgb = |prefix: &str| -> Result<Vec<[f64; 3]>> {
        let [r, g, b] = ["R", "G", "B"].map(|c| channel(&format!("{prefix}{c}")));
        let (r, g, b) = (r?, g?, b?);
        Ok((0..w * h).map(|i| [r[i] as f64, g[i] as f64, b[i] as f64]).collect())
    };
    Ok(Reference {
        scene,
        environment,
        microfacet,
        size: (w as u32, h as u32),
        bounces: meta["umbra_max_bounces"].as_u64().unwrap_or(8) as u32,
        mean: rgb("")?,
        variance: rgb("variance.")?,
    })
}

/// The relative MSE of `image` against `reference`, its noise taken out.
fn rel_mse(image: &[[f32; 4]], reference: &Reference) -> f64 {
    let mut sum = 0.0;
    for ((p, r), v) in image.iter().zip(&reference.mean).zip(&reference.variance) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c];
            sum += (d * d - v[c]) / (r[c] * r[c] + 0.01);
        }
    }
    sum / (3 * image.len().max(1)) as f64
}

/// Renders every estimator on each of `references` (in `dir`) at `spp`, `seeds` times.
pub fn run(
    ctx: &Context,
    dir: &Path,
    references: &[String],
    spp: u32,
    seeds: u32,
) -> Result<Vec<Measurement>> {
    let mut out = Vec::new();
    for name in references {
        let reference = load(dir, name).with_context(|| format!("reference {name}"))?;
        let mut scene = umbra::gpu::scene::GpuScene::upload(ctx, &reference.scene)?;
        if let Some(map) = &reference.environment {
            scene.set_environment(ctx, map)?;
        }
        let camera = reference.scene.camera(None)?;
        let passes = umbra::render::Passes::new(ctx, &scene);
        let samplings: &[Microfacet] = match reference.microfacet {
            Microfacet::Beckmann => &[Microfacet::Beckmann],
            _ => &[Microfacet::Ggx, Microfacet::GgxWalter],
        };
        for &microfacet in samplings {
            for (strategy, heuristic) in ESTIMATORS {
                let mut rel = Vec::new();
                let mut ms = Vec::new();
                for seed in 0..seeds.max(1) {
                    let settings = PathSettings {
                        size: reference.size,
                        spp,
                        seed: 1000 + seed,
                        max_bounces: reference.bounces,
                        // Russian roulette off, as in the reference (it would add its own noise).
                        rr_depth: 1 << 20,
                        microfacet,
                        heuristic,
                        strategy,
                        env: if reference.environment.is_some() { [1.0; 3] } else { [0.0; 3] },
                        ..Default::default()
                    };
                    let image = passes.path_trace(&scene, &camera, &settings, |_, _| {})?;
                    rel.push(rel_mse(&image.mean, &reference));
                    ms.push(image.gpu_ms);
                }
                let m = Measurement {
                    reference: name.clone(),
                    microfacet,
                    strategy,
                    heuristic,
                    rel_mse: rel,
                    gpu_ms: super::rays::median(&mut ms),
                };
                let (mean, se) = mean_se(&m.rel_mse);
                log::info!(
                    "{name} {} {} {}: rel. MSE {mean:.3e} ± {se:.1e}",
                    microfacet.name(),
                    strategy.name(),
                    heuristic.name()
                );
                out.push(m);
            }
        }
    }
    Ok(out)
}

/// Mean and standard error of the mean.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// The JSON document of a run.
pub fn to_json(device: &str, spp: u32, seeds: u32, measurements: &[Measurement]) -> Value {
    json!({
        "device": device,
        "spp": spp,
        "seeds": seeds,
        "estimators": measurements.iter().map(|m| json!({
            "reference": m.reference,
            "microfacet": m.microfacet.name(),
            "strategy": m.strategy.name(),
            "heuristic": if m.strategy == Strategy::Mis { m.heuristic.name() } else { "-" },
            "rel_mse": m.rel_mse,
            "gpu_ms": m.gpu_ms,
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows): per estimator its relative
/// MSE (mean ± standard error over the seeds) and its ratio to the default's (GGX or Beckmann,
/// MIS, power heuristic) on the same reference.
pub fn table(doc: &Value) -> String {
    let rows = doc["estimators"].as_array().cloned().unwrap_or_default();
    let rel = |row: &Value| {
        let v: Vec<f64> = row["rel_mse"].as_array().into_iter().flatten().filter_map(Value::as_f64).collect();
        mean_se(&v)
    };
    let mut out = format!(
        "{} spp, {} seeds, {}:\n\n\
         | reference | microfacet sampling | strategy | heuristic | rel. MSE | ÷ MIS power | GPU ms |\n\
         |---|---|---|---|---:|---:|---:|\n",
        doc["spp"],
        doc["seeds"],
        doc["device"].as_str().unwrap_or("?"),
    );
    for row in &rows {
        let default = rows.iter().find(|d| {
            d["reference"] == row["reference"]
                && d["microfacet"] != "ggx-walter"
                && d["strategy"] == "mis"
                && d["heuristic"] == "power"
        });
        let (mean, se) = rel(row);
        let ratio = default.map_or(f64::NAN, |d| mean / rel(d).0);
        out += &format!(
            "| {} | {} | {} | {} | {mean:.2e} ± {se:.0e} | {ratio:.2} | {:.0} |\n",
            row["reference"].as_str().unwrap_or("?"),
            row["microfacet"].as_str().unwrap_or("?"),
            row["strategy"].as_str().unwrap_or("?"),
            row["heuristic"].as_str().unwrap_or("?"),
            row["gpu_ms"].as_f64().unwrap_or(f64::NAN),
        );
    }
    out
}
