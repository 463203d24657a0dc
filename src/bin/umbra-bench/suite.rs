//! The speed/accuracy suite: every method on each scene, its GPU time (timestamps, after a
//! warm-up, median of repeats) against its error to a converged path-traced reference of the same
//! scene, written as JSON, CSV and one log–log chart per scene.
//!
//! Methods:
//! - `pathtrace`: progressive path tracing, the error read at 1, 2, 4, … samples per pixel of
//!   one accumulation; the time is the accumulated GPU time of the samples so far.
//! - `hybrid`: G-buffer + deferred lighting (direct light with ray-traced shadows) at a sweep of
//!   shadow rays per pixel; the time is the median over repeats of the sum of its passes.
//!
//! The reference uses another seed than the measured runs, so its remaining noise is
//! independent of theirs: with `R` reference samples a method's relative MSE has a floor of
//! about the path tracer's relative MSE at `R` spp (reported as `reference_rel_mse_floor`).

use super::chart;
use super::rays::{median, warm_up};
use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};
use umbra::embed::Renderer;
use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::vk::{raw, Context, GpuTimer, Image};

/// What the suite runs.
pub struct SuiteSettings {
    /// Image size of every render.
    pub size: (u32, u32),
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    /// Largest path-traced sample count measured (a power of two).
    pub max_spp: u32,
    /// Shadow-ray counts of the hybrid sweep.
    pub shadow_rays: Vec<u32>,
    /// Timed repeats of each hybrid setting (after the warm-up).
    pub repeats: usize,
    /// Constant environment radiance for scenes without lights of their own.
    pub env: [f32; 3],
    /// Where JSON, CSV, charts and cached references go.
    pub out: PathBuf,
}

/// One measured point: a method at one setting.
#[derive(Clone, Debug)]
pub struct Point {
    /// Method (`pathtrace`, `hybrid`).
    pub method: String,
    /// The setting, e.g. `spp=16` or `shadow_rays=4`.
    pub setting: String,
    /// The setting's number (spp, shadow rays): the chart's point label.
    pub value: u32,
    /// GPU milliseconds.
    pub ms: f64,
    /// Root-mean-square error over pixels and channels (linear radiance).
    pub rmse: f64,
    /// Mean over pixels and channels of (x − ref)² / (ref² + 0.01).
    pub rel_mse: f64,
}

/// One scene's results.
pub struct SceneResult {
    /// Scene name.
    pub name: String,
    /// Triangles.
    pub triangles: usize,
    /// Every measured point.
    pub points: Vec<Point>,
    /// The reference's own expected relative MSE (its per-pixel variance of the mean, relative).
    pub reference_rel_mse_floor: f64,
}

/// Relative MSE's ε: keeps dark pixels from dominating (as in the denoising literature).
const REL_EPSILON: f64 = 0.01;

/// (RMSE, relative MSE) of `image` against `reference` (RGBA, alpha ignored).
pub fn errors(image: &[[f32; 4]], reference: &[[f32; 4]]) -> (f64, f64) {
    let (mut se, mut rel) = (0.0, 0.0);
    for (p, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c] as f64;
            se += d * d;
            rel += d * d / (r[c] as f64 * r[c] as f64 + REL_EPSILON);
        }
    }
    let n = 3.0 * image.len().max(1) as f64;
    ((se / n).sqrt(), rel / n)
}

/// A reference render, cached in `out` as a raw little-endian f32 file keyed by its settings.
fn reference(
    ctx: &Context,
    renderer: &Renderer,
    camera: &Camera,
    key: &str,
    settings: &PathSettings,
    out: &Path,
) -> Result<(Vec<[f32; 4]>, f64)> {
    let path =
        out.join(format!("reference-{key}-{}x{}-{}spp.f32", settings.size.0, settings.size.1, settings.spp));
    let pixels = (settings.size.0 * settings.size.1) as usize;
    if let Ok(bytes) = std::fs::read(&path) {
        if bytes.len() == (pixels * 4 + 1) * 4 {
            let values: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
            let floor = values[pixels * 4] as f64;
            let image = values[..pixels * 4].chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
            log::info!("{key}: reusing the cached reference {}", path.display());
            return Ok((image, floor));
        }
    }
    let bar = super::progress_bar(settings.spp as u64, &format!("{key}: reference"));
    let image = path_trace(ctx, renderer.scene(), camera, settings, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    // The reference's own error: its variance of the mean, relative, as `errors` weighs it.
    let variance = image.variance_of_mean();
    let floor = variance
        .iter()
        .zip(&image.mean)
        .map(|(v, m)| (0..3).map(|c| v[c] as f64 / (m[c] as f64 * m[c] as f64 + REL_EPSILON)).sum::<f64>())
        .sum::<f64>()
        / (3.0 * pixels as f64);
    let mut values: Vec<f32> = image.mean.iter().flatten().copied().collect();
    values.push(floor as f32);
    std::fs::write(&path, bytemuck::cast_slice(&values))
        .with_context(|| format!("writing {}", path.display()))?;
    Ok((image.mean, floor))
}

/// Runs every method on `scene` (named `key` in file names).
pub fn run_scene(
    ctx: &Context,
    key: &str,
    scene: &Scene,
    camera: &Camera,
    s: &SuiteSettings,
) -> Result<SceneResult> {
    let has_lights = !scene.emissive.is_empty() || !scene.lights.is_empty();
    let env = if has_lights { [0.0; 3] } else { s.env };
    let renderer = Renderer::new(ctx, scene)?;
    let path_settings =
        PathSettings { size: s.size, spp: s.reference_spp, seed: 0x5eed, env, ..PathSettings::default() };
    let (reference, floor) = reference(ctx, &renderer, camera, key, &path_settings, &s.out)?;
    let mut points = Vec::new();

    // Path tracing: one accumulation, read at every power of two.
    let measured = PathSettings { seed: 1, ..path_settings };
    let target = renderer.path_target(s.size)?;
    let output =
        Image::storage_2d(ctx, "suite resolve", s.size.0, s.size.1, raw::Format::R32G32B32A32_SFLOAT)?;
    ctx.submit(|cmd| {
        output.init_general(ctx, cmd);
        Ok(())
    })?;
    warm_up(|| ctx.submit(|cmd| renderer.record_path_samples(cmd, camera, &target, &measured, 0, 1)))?;
    let mut timer = GpuTimer::new(ctx, 1)?;
    let (mut done, mut elapsed_ms) = (0u32, 0.0);
    let bar = super::progress_bar(s.max_spp as u64, &format!("{key}: path tracing"));
    let mut level = 1;
    while level <= s.max_spp {
        while done < level {
            let count = (level - done).min(16);
            ctx.submit(|cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "pathtrace")?;
                renderer.record_path_samples(cmd, camera, &target, &measured, done, count)?;
                timer.end(cmd)
            })?;
            elapsed_ms += timer.read()?.iter().map(|t| t.ms).sum::<f64>();
            done += count;
            bar.set_position(done as u64);
        }
        ctx.submit(|cmd| renderer.record_path_resolve(cmd, &target, output.view))?;
        let (rmse, rel_mse) = errors(&output.read(ctx)?, &reference);
        points.push(Point {
            method: "pathtrace".into(),
            setting: format!("spp={level}"),
            value: level,
            ms: elapsed_ms,
            rmse,
            rel_mse,
        });
        level *= 2;
    }
    bar.finish_and_clear();

    // Hybrid: a sweep of shadow rays.
    for &rays in &s.shadow_rays {
        let settings = HybridSettings {
            size: s.size,
            lighting: LightingSettings { shadow_rays: rays, seed: 1, env, ..LightingSettings::default() },
            ..HybridSettings::default()
        };
        warm_up(|| hybrid(ctx, renderer.scene(), camera, &settings).map(|_| ()))?;
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..s.repeats.max(1) {
            let image = hybrid(ctx, renderer.scene(), camera, &settings)?;
            times.push(image.pass_ms.iter().map(|(_, ms)| ms).sum::<f64>());
            last = Some(image);
        }
        let Some(image) = last else { bail!("no hybrid run") };
        let (rmse, rel_mse) = errors(&image.color, &reference);
        points.push(Point {
            method: "hybrid".into(),
            setting: format!("shadow_rays={rays}"),
            value: rays,
            ms: median(&mut times),
            rmse,
            rel_mse,
        });
    }
    let stem = s.out.join(format!("suite-{key}"));
    chart::write(
        &stem,
        &format!("{} — {}×{} on {}", scene.name, s.size.0, s.size.1, ctx.info().name),
        &points,
        floor,
    )?;
    Ok(SceneResult {
        name: scene.name.clone(),
        triangles: renderer.scene().bvh_stats.triangles,
        points,
        reference_rel_mse_floor: floor,
    })
}

/// The CSV of every scene's points.
pub fn csv(results: &[SceneResult]) -> String {
    let mut text = String::from("scene,method,setting,gpu_ms,rmse,rel_mse\n");
    for r in results {
        for p in &r.points {
            text.push_str(&format!(
                "{},{},{},{:.6},{:.6e},{:.6e}\n",
                r.name.replace(',', ";"),
                p.method,
                p.setting,
                p.ms,
                p.rmse,
                p.rel_mse
            ));
        }
    }
    text
}
