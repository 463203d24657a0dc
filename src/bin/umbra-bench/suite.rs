//! The speed/accuracy suite: every method on each scene, its GPU time (timestamps, after a
//! warm-up, median of repeats) against its error to a converged path-traced reference of the same
//! scene, written as JSON, CSV and one log–log chart per scene.
//!
//! Methods:
//! - `pathtrace`: progressive path tracing, the error read at 1, 2, 4, … samples per pixel of
//!   one accumulation; the time is the accumulated GPU time of the samples so far.
//! - `hybrid`: G-buffer, SSAO, deferred lighting (direct light with ray-traced shadows, split-sum
//!   IBL × AO) at a sweep of shadow rays per pixel, also without SSAO and without IBL, and at a
//!   sweep of SSAO kernel sizes; the time is the median over repeats of the sum of its per-frame
//!   passes (the IBL precomputation, once per scene, is reported apart).
//! - `hybrid, <filter> shadow maps` (scenes with punctual lights): the hybrid at 4 shadow rays
//!   with its punctual lights shadowed by maps (hard, PCF, PCSS, moments) at a sweep of map
//!   sizes; the time includes rendering the maps every frame (a moving light; a static one pays
//!   only the lighting pass). With them, `hybrid, rt sized shadows`: the hybrid with its punctual
//!   lights' shadows ray-traced as sized lights at a sweep of rays per light. These series and
//!   the hybrid's also get the shadow term's error: against the same hybrid with the sized lights'
//!   shadows ray-traced with 256 rays per light ([`ShadowReference`], the truth PCSS's soft
//!   shadows approximate; the path tracer's lights are points).
//! - `hybrid, supersampled`: the hybrid at 4 shadow rays with SSAO and IBL, anti-aliased by a
//!   sweep of sub-frames per image ([`umbra::render::HybridSettings::samples`]; the path
//!   tracer's pixels integrate their area, the one-sample hybrid's see their centres); the time
//!   is every sub-frame's and the centres' G-buffer for the AOVs.
//! - `hybrid + probes`: the hybrid at 4 shadow rays with irradiance probes baked at a sweep of
//!   spacings (the scene's longest side / n) lighting its diffuse lobe; the bake is reported
//!   apart, as precomputation.
//! - `ssao` and `rtao` on a second chart: ambient occlusion against a many-ray RTAO reference.
//!
//! A third chart per scene plots the mean LDR-FLIP (NVIDIA's perceptual difference of the
//! tone-mapped images) instead of the relative MSE: the two can disagree.
//!
//! The reference uses another seed than the measured runs, so its remaining noise is
//! independent of theirs: with `R` reference samples a method's relative MSE has a floor of
//! about the path tracer's relative MSE at `R` spp (reported as `reference_rel_mse_floor`).

use super::chart::{self, Chart, ChartPoint};
use super::num;
use super::rays::{median, warm_up};
use crate::scenes::bench_camera;
use crate::scenes::load_gltf;
use crate::scenes::sponza_under_a_sun;
use anyhow::Context as _;
use anyhow::{bail, Result};
use glam::Vec3;
use serde_json::json;
use std::path::{Path, PathBuf};
use umbra::embed::Renderer;
use umbra::passes::ao::{AoResolution, AoSettings};
use umbra::passes::deferred::LightingSettings;
use umbra::passes::pathtrace::PathTarget;
use umbra::passes::shadow::{ShadowMethod, ShadowSettings};
use umbra::render::{AoMethod, HybridSettings, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::vk::ContextDesc;
use umbra::vk::{raw, Context, GpuTimer, Image};

/// What the suite runs.
#[derive(Clone)]
pub struct SuiteSettings {
    /// Image size of every render.
    pub size: (u32, u32),
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    /// Largest path-traced sample count measured (a power of two).
    pub max_spp: u32,
    /// Shadow-ray counts of the hybrid sweeps.
    pub shadow_rays: Vec<u32>,
    /// Shadow-map sizes of the hybrid's shadow-map series (scenes with punctual lights).
    pub shadow_map_sizes: Vec<u32>,
    /// Sub-frame counts of the hybrid's supersampling series (`hybrid, supersampled`, 4 shadow
    /// rays, SSAO 16, IBL: anti-aliasing by [`umbra::render::HybridSettings::samples`]).
    pub hybrid_samples: Vec<u32>,
    /// SSAO kernel sizes of the hybrid's SSAO sweep and of the AO chart.
    pub ssao_samples: Vec<u32>,
    /// Probe spacings of the hybrid's probe series, as the scene's longest side / n.
    pub probes_per_side: Vec<u32>,
    /// GTAO slice counts of the AO chart (3 steps a side), at full and at half resolution.
    pub gtao_slices: Vec<u32>,
    /// RTAO ray counts of the AO chart.
    pub rtao_rays: Vec<u32>,
    /// Rays per pixel of the RTAO reference.
    pub ao_reference_rays: u32,
    /// AO radius (scene units) for SSAO and RTAO.
    pub ao_radius: f32,
    /// Timed repeats of each hybrid setting (after the warm-up).
    pub repeats: usize,
    /// Constant environment (sky) radiance around every scene: what the hybrid's image-based
    /// lighting and SSAO approximate.
    pub env: [f32; 3],
    /// Where JSON, CSV, charts and cached references go.
    pub out: PathBuf,
}

/// One measured point: a method at one setting.
#[derive(Clone, Debug)]
pub struct Point {
    /// Method (`pathtrace`, `hybrid`, `ssao`, `rtao`, ...).
    pub method: String,
    /// What `value` counts (`spp`, `shadow_rays`, `ssao_samples`, `rays`).
    pub unit: &'static str,
    /// The setting's number: the chart's point label.
    pub value: u32,
    /// GPU milliseconds per frame (precomputation excluded).
    pub ms: f64,
    /// Root-mean-square error over pixels and channels (linear radiance, or AO).
    pub rmse: f64,
    /// Images: mean over pixels and channels of (x − ref)² / (ref² + 0.01). AO: plain MSE.
    pub rel_mse: f64,
    /// Images: mean LDR-FLIP (NVIDIA's perceptual difference, 0–1) of the tone-mapped image
    /// (Khronos PBR Neutral, sRGB) against the tone-mapped reference. AO: none.
    pub flip: Option<f64>,
    /// The shadow term's relative MSE: the hybrid image against the hybrid with ray-traced
    /// shadows of the sized lights ([`ShadowReference`]), where the scene has punctual lights and
    /// the point is a hybrid at 4 shadow rays or a shadow-map or sized-light series.
    pub shadow_rel_mse: Option<f64>,
}

/// The shadow term's reference of a scene with punctual lights: the hybrid (SSAO 16, IBL) with
/// ray-traced shadows of its punctual lights as sized lights (a sphere of `light_radius`, a cone
/// of `sun_angle`: the size PCSS softens by), `rays` rays per light and pixel in `frames`
/// frames of another seed, averaged; everything but the shadows as in the measured hybrids.
#[derive(Clone, Debug)]
pub struct ShadowReference {
    /// Rays per light and pixel in all.
    pub rays: u32,
    /// Frames averaged.
    pub frames: u32,
    /// Radius of point and spot lights, metres.
    pub light_radius: f32,
    /// Angular radius of directional lights, radians.
    pub sun_angle: f32,
}

/// Rays per light and pixel of the shadow term's reference.
pub const SHADOW_REFERENCE_RAYS: u32 = 256;

/// Shadow rays per light one frame may trace for sized lights with `punctual` punctual lights.
fn sized_rays_per_frame(punctual: u32) -> u32 {
    (LightingSettings::MAX_SHADOW_RAYS / punctual.clamp(1, umbra::gpu::layout::PUNCTUAL_ALL)).max(1)
}

/// The shadow term's reference image of the scene ([`ShadowReference`]), the hybrid's `settings`
/// but for the shadows and the light samples' seed and count.
fn shadow_reference(
    renderer: &Renderer,
    camera: &Camera,
    settings: &HybridSettings,
) -> Result<(Vec<[f32; 4]>, ShadowReference)> {
    let scene = renderer.scene();
    let per_frame = sized_rays_per_frame(scene.punctual_count);
    let frames = SHADOW_REFERENCE_RAYS.div_ceil(per_frame);
    let shadows = ShadowSettings { method: ShadowMethod::RayTraced, sized_rays: true, ..settings.shadows };
    let mut sum = vec![[0.0f32; 4]; (settings.size.0 * settings.size.1) as usize];
    for frame in 0..frames {
        let lighting = LightingSettings { shadow_rays: per_frame, frame, seed: 2, ..settings.lighting };
        let image = renderer.passes().hybrid(
            scene,
            camera,
            &HybridSettings { lighting, shadows, ..settings.clone() },
        )?;
        for (s, p) in sum.iter_mut().zip(&image.color) {
            for c in 0..4 {
                s[c] += p[c] / frames as f32;
            }
        }
    }
    let reference = ShadowReference {
        rays: per_frame * frames,
        frames,
        light_radius: shadows.light_radius,
        sun_angle: shadows.sun_angle,
    };
    Ok((sum, reference))
}

/// One scene's results.
pub struct SceneResult {
    /// The scene's key: its charts' file names (`suite-{key}…`) and `--only`'s name for it.
    pub key: String,
    /// Scene name.
    pub name: String,
    /// Triangles.
    pub triangles: usize,
    /// Every measured point of the image chart.
    pub points: Vec<Point>,
    /// The reference's own expected relative MSE (its per-pixel variance of the mean, relative).
    pub reference_rel_mse_floor: f64,
    /// Ambient occlusion: SSAO and RTAO against an RTAO reference (MSE over surface pixels).
    pub ao_points: Vec<Point>,
    /// The AO reference's own expected MSE (Bernoulli variance a(1 − a)/N per pixel, averaged).
    pub ao_reference_mse_floor: f64,
    /// One-off GPU work per scene (IBL tables and prefiltering), milliseconds by pass.
    pub precompute_ms: Vec<(String, f64)>,
    /// The shadow term's reference (scenes with punctual lights).
    pub shadow_reference: Option<ShadowReference>,
    /// Samples per pixel of the scene's path-traced reference.
    pub reference_spp: u32,
}

/// Relative MSE's ε: keeps dark pixels from dominating (as in the denoising literature).
pub const REL_EPSILON: f64 = 0.01;

/// Mean LDR-FLIP of `image` against `reference` (both linear RGBA of `size`), each tone-mapped
/// with Khronos PBR Neutral and sRGB-encoded first; 67 pixels per degree (a 0.7 m wide monitor of
/// 3840 pixels seen from 0.7 m, FLIP's default).
pub fn flip_mean(image: &[[f32; 4]], reference: &[[f32; 4]], (w, h): (u32, u32)) -> f64 {
    let rgb8 = |v: &[[f32; 4]]| -> nv_flip::FlipImageRgb8 {
        let flat: Vec<f32> = v.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let rgba = umbra::color::to_display8(&flat, 1.0, umbra::color::ToneCurve::KhronosPbrNeutral);
        let rgb: Vec<u8> = rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
        nv_flip::FlipImageRgb8::with_data(w, h, &rgb)
    };
    let map = nv_flip::flip(rgb8(reference), rgb8(image), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&map).mean() as f64
}

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
    let image = renderer
        .passes()
        .path_trace(renderer.scene(), camera, settings, |done, _| bar.set_position(done as u64))?;
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
    umbra::atomic::write(&path, bytemuck::cast_slice(&values))?;
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
    let env = s.env;
    let renderer = Renderer::new(ctx, scene)?;
    let path_settings = reference_settings(s);
    let (reference, floor) = reference(&renderer, camera, key, &path_settings, &s.out)?;
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
        elapsed_ms +=
            trace_until(ctx, &renderer, camera, &target, &measured, &mut timer, &mut done, level, &bar)?;
        ctx.submit(|cmd| renderer.record_path_resolve(cmd, &target, output.view))?;
        let image = output.read(ctx)?;
        let (rmse, rel_mse) = errors(&image, &reference);
        let flip = Some(flip_mean(&image, &reference, s.size));
        points.push(Point {
            method: "pathtrace".into(),
            unit: "spp",
            value: level,
            ms: elapsed_ms,
            rmse,
            rel_mse,
            flip,
            shadow_rel_mse: None,
        });
        level *= 2;
    }
    bar.finish_and_clear();

    // Hybrid: sweeps of shadow rays (with SSAO and IBL, without SSAO, without IBL) and of the
    // SSAO kernel size at 4 shadow rays.
    let ssao = |samples| AoSettings { samples, radius: s.ao_radius, seed: 1, ..AoSettings::default() };
    let mut precompute_ms = Vec::new();
    /// One hybrid setting: its series, what its value counts, the value, SSAO, IBL, shadows,
    /// sub-frames.
    struct Sweep(String, &'static str, u32, Option<AoSettings>, bool, ShadowSettings, u32);
    let rt = ShadowSettings::default();
    let mut sweeps: Vec<Sweep> = Vec::new();
    for &rays in &s.shadow_rays {
        sweeps.push(Sweep("hybrid".into(), "shadow_rays", rays, Some(ssao(16)), true, rt, 1));
        sweeps.push(Sweep("hybrid, no SSAO".into(), "shadow_rays", rays, None, true, rt, 1));
        sweeps.push(Sweep("hybrid, no IBL".into(), "shadow_rays", rays, Some(ssao(16)), false, rt, 1));
    }
    for &samples in &s.hybrid_samples {
        let label = "hybrid, supersampled".to_string();
        sweeps.push(Sweep(label, "hybrid_samples", samples, Some(ssao(16)), true, rt, samples));
    }
    for &samples in &s.ssao_samples {
        sweeps.push(Sweep(
            "hybrid, SSAO sweep".into(),
            "ssao_samples",
            samples,
            Some(ssao(samples)),
            true,
            rt,
            1,
        ));
    }
    let punctual = renderer.scene().punctual_count;
    if punctual > 0 {
        // Ray-traced shadows of the sized lights, as many rays as one frame may trace.
        for &rays in s.shadow_rays.iter().filter(|&&r| r <= sized_rays_per_frame(punctual)) {
            let shadows = ShadowSettings { sized_rays: true, ..rt };
            sweeps.push(Sweep(
                "hybrid, rt sized shadows".into(),
                "shadow_rays",
                rays,
                Some(ssao(16)),
                true,
                shadows,
                1,
            ));
        }
        for method in [ShadowMethod::Hard, ShadowMethod::Pcf, ShadowMethod::Pcss, ShadowMethod::Moments] {
            for &map_size in &s.shadow_map_sizes {
                let shadows = ShadowSettings { method, map_size, ..rt };
                let label = format!("hybrid, {} shadow maps", method.name());
                sweeps.push(Sweep(label, "map_size", map_size, Some(ssao(16)), true, shadows, 1));
            }
        }
    }
    // The shadow term's reference: the hybrid at 4 shadow rays with SSAO and IBL, its punctual
    // lights' shadows ray-traced as sized lights with many rays.
    let shadow_base = HybridSettings {
        size: s.size,
        lighting: LightingSettings { shadow_rays: 4, seed: 1, env, ibl: true, ..LightingSettings::default() },
        ao: Some(ssao(16)),
        shadows: rt,
        ..HybridSettings::default()
    };
    let shadow_ref = match punctual > 0 {
        true => Some(shadow_reference(&renderer, camera, &shadow_base)?),
        false => None,
    };
    for Sweep(method, unit, value, ao, ibl, shadows, samples) in sweeps {
        let rays = if unit == "shadow_rays" { value } else { 4 };
        // The shadow term's error where everything but the shadows (and the emissive triangles'
        // sample count) is the reference's.
        let same_but_shadows = ao.is_some_and(|a| a.samples == 16) && ibl && samples == 1;
        let settings = HybridSettings {
            size: s.size,
            lighting: LightingSettings {
                shadow_rays: rays,
                seed: 1,
                env,
                ibl,
                ..LightingSettings::default()
            },
            ao,
            shadows,
            samples,
            ..HybridSettings::default()
        };
        let (ms, image) =
            timed(s.repeats, || renderer.passes().hybrid(renderer.scene(), camera, &settings), frame_ms)?;
        if precompute_ms.is_empty() {
            precompute_ms = image.pass_ms.iter().filter(|(name, _)| is_once(name)).cloned().collect();
        }
        let (rmse, rel_mse) = errors(&image.color, &reference);
        let flip = Some(flip_mean(&image.color, &reference, s.size));
        let shadow_rel_mse = match &shadow_ref {
            Some((shadow_image, _)) if same_but_shadows => Some(errors(&image.color, shadow_image).1),
            _ => None,
        };
        points.push(Point { method, unit, value, ms, rmse, rel_mse, flip, shadow_rel_mse });
    }
    // Irradiance probes, baked once per scene and spacing.
    for p in super::probes::series(ctx, &renderer, camera, &reference, s, &s.probes_per_side)? {
        precompute_ms.push((format!("probes bake 1/{} ({} probes)", p.point.value, p.probes), p.bake_ms));
        points.push(p.point);
    }
    // Ambient occlusion: SSAO (blurred) and RTAO against a many-ray RTAO reference.
    let (ao_points, ao_floor) = ambient_occlusion_sweep(&renderer, camera, s)?;

    let result = SceneResult {
        key: key.to_string(),
        name: scene.name.clone(),
        triangles: renderer.scene().bvh_stats.triangles,
        points,
        reference_rel_mse_floor: floor,
        ao_points,
        ao_reference_mse_floor: ao_floor,
        precompute_ms,
        shadow_reference: shadow_ref.map(|(_, r)| r),
        reference_spp: s.reference_spp,
    };
    SceneCharts::of(&result, &ctx.info().name, s.size, s.ao_radius).write(&s.out)?;
    Ok(result)
}

/// Accumulates `target`'s samples from `*done` up to `level` in submissions of at most 16,
/// advancing `*done` and `bar`; the GPU milliseconds they took.
#[allow(clippy::too_many_arguments)]
pub fn trace_until(
    ctx: &Context,
    renderer: &Renderer,
    camera: &Camera,
    target: &PathTarget,
    settings: &PathSettings,
    timer: &mut GpuTimer,
    done: &mut u32,
    level: u32,
    bar: &indicatif::ProgressBar,
) -> Result<f64> {
    let mut ms = 0.0;
    while *done < level {
        let (first, count) = (*done, (level - *done).min(16));
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "pathtrace")?;
            renderer.record_path_samples(cmd, camera, target, settings, first, count)?;
            timer.end(cmd)
        })?;
        ms += timer.read()?.iter().map(|t| t.ms).sum::<f64>();
        *done += count;
        bar.set_position(*done as u64);
    }
    Ok(ms)
}

/// Whether `pass` runs once per scene, not per frame (the IBL tables and prefiltered maps).
fn is_once(pass: &str) -> bool {
    pass.starts_with("ibl")
}

/// A hybrid frame's GPU milliseconds: its passes less the once-per-scene precomputation.
pub fn frame_ms(image: &umbra::render::HybridImage) -> f64 {
    image.pass_ms.iter().filter(|(name, _)| !is_once(name)).map(|(_, ms)| ms).sum()
}

/// The path tracer's settings of the suite's references.
fn reference_settings(s: &SuiteSettings) -> PathSettings {
    PathSettings { size: s.size, spp: s.reference_spp, seed: 0x5eed, env: s.env, ..PathSettings::default() }
}

/// The suite's reference of a scene (`key` names its cache file in `s.out`): the image and its
/// own relative MSE.
pub fn reference_for(
    renderer: &Renderer,
    camera: &Camera,
    key: &str,
    s: &SuiteSettings,
) -> Result<(Vec<[f32; 4]>, f64)> {
    reference(renderer, camera, key, &reference_settings(s), &s.out)
}

/// Runs `run` for half a second of warm-up, then `repeats` times (at least once): the median of
/// `frame_ms` over the repeats, and the last result.
pub fn timed<T>(
    repeats: usize,
    mut run: impl FnMut() -> umbra::Result<T>,
    frame_ms: impl Fn(&T) -> f64,
) -> Result<(f64, T)> {
    warm_up(|| run().map(|_| ()))?;
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let result = run()?;
        times.push(frame_ms(&result));
        last = Some(result);
    }
    let Some(last) = last else { bail!("no timed run") };
    Ok((median(&mut times), last))
}

/// SSAO at each kernel size, GTAO at each slice count (full and half resolution) and RTAO at each
/// ray count against an RTAO reference; the error is the MSE over pixels with a surface, the time
/// the AO passes' (G-buffer excluded).
fn ambient_occlusion_sweep(
    renderer: &Renderer,
    camera: &Camera,
    s: &SuiteSettings,
) -> Result<(Vec<Point>, f64)> {
    let (passes, scene) = (renderer.passes(), renderer.scene());
    let settings =
        |method, samples, seed| AoSettings { samples, radius: s.ao_radius, seed, ..AoSettings::of(method) };
    let reference = passes.ambient_occlusion(
        scene,
        camera,
        s.size,
        &AoSettings { blur: false, ..settings(AoMethod::Rtao, s.ao_reference_rays, 99) },
    )?;
    let surface: Vec<bool> = reference.gbuffer.depth.iter().map(|&d| d > 0.0).collect();
    let count = surface.iter().filter(|&&x| x).count().max(1) as f64;
    let floor = reference
        .values
        .iter()
        .zip(&surface)
        .filter(|(_, &on)| on)
        .map(|(&a, _)| (a as f64 * (1.0 - a as f64)) / s.ao_reference_rays as f64)
        .sum::<f64>()
        / count;
    let mut runs: Vec<(&str, &'static str, u32, AoSettings)> = Vec::new();
    for &n in &s.ssao_samples {
        runs.push(("ssao", "ssao_samples", n, settings(AoMethod::Ssao, n, 1)));
    }
    for &n in &s.gtao_slices {
        let gtao = settings(AoMethod::Gtao, n, 1);
        runs.push(("gtao", "slices", n, gtao));
        runs.push(("gtao half", "slices", n, AoSettings { resolution: AoResolution::Half, ..gtao }));
    }
    for &n in &s.rtao_rays {
        runs.push(("rtao", "rays", n, AoSettings { blur: false, ..settings(AoMethod::Rtao, n, 1) }));
    }
    let mut points = Vec::new();
    for (method, unit, value, run_settings) in runs {
        let (ms, image) = timed(
            s.repeats,
            || passes.ambient_occlusion(scene, camera, s.size, &run_settings),
            |image| image.pass_ms.iter().filter(|(name, _)| name != "gbuffer").map(|(_, ms)| ms).sum(),
        )?;
        let mse = image
            .values
            .iter()
            .zip(&reference.values)
            .zip(&surface)
            .filter(|(_, &on)| on)
            .map(|((&a, &r), _)| (a as f64 - r as f64).powi(2))
            .sum::<f64>()
            / count;
        points.push(Point {
            method: method.into(),
            unit,
            value,
            ms,
            rmse: mse.sqrt(),
            rel_mse: mse,
            flip: None,
            shadow_rel_mse: None,
        });
    }
    Ok((points, floor))
}

/// A point as a scene's charts read it: a measured [`Point`], or one of a suite JSON.
struct Plotted<'a> {
    method: &'a str,
    unit: &'a str,
    value: u32,
    ms: f64,
    /// Relative MSE (image points) or MSE (AO points).
    error: f64,
    /// Mean LDR-FLIP (image points).
    flip: Option<f64>,
}

impl Point {
    fn plotted(&self) -> Plotted<'_> {
        Plotted {
            method: &self.method,
            unit: self.unit,
            value: self.value,
            ms: self.ms,
            error: self.rel_mse,
            flip: self.flip,
        }
    }
}

/// What one scene's three charts show: drawn by [`SceneCharts::write`] alike after a run
/// ([`SceneCharts::of`]) and from a suite JSON ([`redraw`]).
struct SceneCharts<'a> {
    /// The scene's key (file names).
    key: String,
    /// The scene's name (titles).
    scene: &'a str,
    /// The device measured on.
    device: &'a str,
    size: (u32, u32),
    ao_radius: f32,
    /// The path-traced reference's own relative MSE.
    floor: f64,
    points: Vec<Plotted<'a>>,
    /// The AO reference's own MSE.
    ao_floor: f64,
    ao_points: Vec<Plotted<'a>>,
}

impl<'a> SceneCharts<'a> {
    /// The charts of a scene just measured on `device` at `size`, AO of `ao_radius`.
    fn of(r: &'a SceneResult, device: &'a str, size: (u32, u32), ao_radius: f32) -> Self {
        SceneCharts {
            key: r.key.clone(),
            scene: &r.name,
            device,
            size,
            ao_radius,
            floor: r.reference_rel_mse_floor,
            points: r.points.iter().map(Point::plotted).collect(),
            ao_floor: r.ao_reference_mse_floor,
            ao_points: r.ao_points.iter().map(Point::plotted).collect(),
        }
    }

    /// Writes `suite-{key}` (relative MSE against the path-traced reference, its noise floor
    /// drawn), `suite-{key}-flip` (mean LDR-FLIP) and `suite-{key}-ao` (AO's MSE against the RTAO
    /// reference, its noise floor drawn) into `out`, each as .svg and .png; their stems.
    fn write(&self, out: &Path) -> Result<[PathBuf; 3]> {
        let (w, h) = self.size;
        let chart_points = |points: &[Plotted<'a>], error: fn(&Plotted) -> Option<f64>| -> Vec<ChartPoint> {
            points
                .iter()
                .filter_map(|p| {
                    error(p).map(|error| ChartPoint {
                        method: p.method,
                        unit: p.unit,
                        value: p.value,
                        ms: p.ms,
                        error,
                    })
                })
                .collect()
        };
        let title = format!("{} — {w}×{h} on {}", self.scene, self.device);
        let stems = [
            out.join(format!("suite-{}", self.key)),
            out.join(format!("suite-{}-flip", self.key)),
            out.join(format!("suite-{}-ao", self.key)),
        ];
        let chart = Chart {
            title: &title,
            y_desc: "relative MSE vs converged path tracing (log)",
            floor: self.floor,
        };
        chart::write(&stems[0], &chart, &chart_points(&self.points, |p| Some(p.error)))?;
        let flip_chart =
            Chart { title: &title, y_desc: "mean LDR-FLIP vs converged path tracing (log)", floor: 0.0 };
        chart::write(&stems[1], &flip_chart, &chart_points(&self.points, |p| p.flip))?;
        let ao_title = format!("ambient occlusion, r = {} — {} — {w}×{h}", self.ao_radius, self.scene);
        let ao_chart =
            Chart { title: &ao_title, y_desc: "MSE vs ray-traced AO reference (log)", floor: self.ao_floor };
        chart::write(&stems[2], &ao_chart, &chart_points(&self.ao_points, |p| Some(p.error)))?;
        Ok(stems)
    }
}

/// Redraws the three charts of every scene of the suite JSON `file` (as `run_suite` writes it)
/// into `out`, rendering and measuring nothing (no Vulkan device); the charts' stems. A scene's
/// file names take its `key`, or where the file has none (written before the suite recorded it)
/// the key the run gives a scene of its name ([`key_of_name`]); the AO chart's radius is the
/// file's `ao_radius`, else `ao_radius`. Every scene is read before any chart is written: a
/// missing file, text that is not JSON, or a missing or mistyped field is an error naming the
/// file and the field, and writes nothing.
pub fn redraw(file: &Path, out: &Path, ao_radius: f32) -> Result<Vec<PathBuf>> {
    let text = std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {} as JSON", file.display()))?;
    let charts = charts_of_json(&doc, ao_radius).with_context(|| format!("reading {}", file.display()))?;
    umbra::atomic::create_dir(out)?;
    let mut stems = Vec::new();
    for c in &charts {
        stems.extend(c.write(out).with_context(|| format!("drawing the charts of {}", c.scene))?);
    }
    Ok(stems)
}

/// The charts of every scene of a suite JSON (see [`redraw`]).
fn charts_of_json(doc: &serde_json::Value, ao_radius: f32) -> Result<Vec<SceneCharts<'_>>> {
    let device = json_str(doc, "", "device")?;
    let size = json_list(doc, "", "size")?;
    let size = match size {
        [w, h] => (json_u32(w, "size[0]")?, json_u32(h, "size[1]")?),
        _ => bail!("field `size` is not [width, height]"),
    };
    let ao_radius = match doc.get("ao_radius") {
        Some(_) => json_f64(doc, "", "ao_radius")? as f32,
        None => ao_radius,
    };
    let mut charts = Vec::new();
    for (i, scene) in json_list(doc, "", "scenes")?.iter().enumerate() {
        let at = format!("scenes[{i}]");
        let name = json_str(scene, &at, "scene")?;
        let key = match scene.get("key") {
            Some(_) => {
                let key = json_str(scene, &at, "key")?;
                if key.is_empty() || key.contains(['/', '\\']) {
                    bail!("field `{at}.key` ({key:?}) is not a file-name part");
                }
                key.to_string()
            }
            None => key_of_name(name),
        };
        let points = json_list(scene, &at, "points")?
            .iter()
            .enumerate()
            .map(|(j, p)| json_point(p, &format!("{at}.points[{j}]"), "rel_mse", true))
            .collect::<Result<_>>()?;
        let ao_points = json_list(scene, &at, "ao_points")?
            .iter()
            .enumerate()
            .map(|(j, p)| json_point(p, &format!("{at}.ao_points[{j}]"), "mse", false))
            .collect::<Result<_>>()?;
        charts.push(SceneCharts {
            key,
            scene: name,
            device,
            size,
            ao_radius,
            floor: json_f64(scene, &at, "reference_rel_mse_floor")?,
            points,
            ao_floor: json_f64(scene, &at, "ao_reference_mse_floor")?,
            ao_points,
        });
    }
    Ok(charts)
}

/// A point of a suite JSON's `points` (`error` its `rel_mse`, `flip` its `flip`) or `ao_points`
/// (`error` its `mse`, no FLIP); `at` names it in errors.
fn json_point<'a>(p: &'a serde_json::Value, at: &str, error: &str, flip: bool) -> Result<Plotted<'a>> {
    Ok(Plotted {
        method: json_str(p, at, "method")?,
        unit: json_str(p, at, "unit")?,
        value: json_u32(json_field(p, at, "value")?, &field_path(at, "value"))?,
        ms: json_f64(p, at, "gpu_ms")?,
        error: json_f64(p, at, error)?,
        // Written for every image point, null where there is none.
        flip: match flip {
            true => Some(json_f64(p, at, "flip")?).filter(|f| !f.is_nan()),
            false => None,
        },
    })
}

/// `at.key`, or `key` at the top level (`at` empty).
fn field_path(at: &str, key: &str) -> String {
    match at {
        "" => key.to_string(),
        at => format!("{at}.{key}"),
    }
}

/// The field `key` of the object `v` (at `at`).
fn json_field<'a>(v: &'a serde_json::Value, at: &str, key: &str) -> Result<&'a serde_json::Value> {
    v.get(key).ok_or_else(|| anyhow::anyhow!("field `{}` is missing", field_path(at, key)))
}

fn json_str<'a>(v: &'a serde_json::Value, at: &str, key: &str) -> Result<&'a str> {
    let field = json_field(v, at, key)?;
    field.as_str().ok_or_else(|| anyhow::anyhow!("field `{}` is not a string: {field}", field_path(at, key)))
}

fn json_list<'a>(v: &'a serde_json::Value, at: &str, key: &str) -> Result<&'a [serde_json::Value]> {
    let field = json_field(v, at, key)?;
    match field.as_array() {
        Some(list) => Ok(list),
        None => bail!("field `{}` is not a list: {field}", field_path(at, key)),
    }
}

/// A number field; null reads as NaN (serde_json writes a NaN as null).
fn json_f64(v: &serde_json::Value, at: &str, key: &str) -> Result<f64> {
    match json_field(v, at, key)? {
        serde_json::Value::Null => Ok(f64::NAN),
        field => field
            .as_f64()
            .ok_or_else(|| anyhow::anyhow!("field `{}` is not a number: {field}", field_path(at, key))),
    }
}

/// `v` (the field `path`) as a u32.
fn json_u32(v: &serde_json::Value, path: &str) -> Result<u32> {
    v.as_u64()
        .and_then(|n| u32::try_from(n).ok())
        .ok_or_else(|| anyhow::anyhow!("field `{path}` is not a whole number below 2³²: {v}"))
}

/// The key [`suite_scenes`] gives the scene it names `name`, for a suite JSON that does not record
/// its scenes' keys: `cornell` for the embedded Cornell box, `cornell-point` for its point-light
/// variant ([`cornell_point_light`]), `sponza-sun` for Sponza under a sun (`<stem> under a sun`,
/// [`sponza_under_a_sun`]), else the file stem of the name: the scenes loaded from a file
/// (`scenes/<key>.glb`, `--gltf` files) are named by its path.
fn key_of_name(name: &str) -> String {
    if name == umbra::scene::Scene::cornell_box().name {
        "cornell".into()
    } else if name == cornell_point_light().name {
        "cornell-point".into()
    } else if name.ends_with(" under a sun") {
        "sponza-sun".into()
    } else {
        Path::new(name).file_stem().map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
    }
}

/// The CSV of every scene's points.
pub fn csv(results: &[SceneResult]) -> String {
    let mut text = String::from("scene,chart,method,unit,value,gpu_ms,rmse,error,flip\n");
    for r in results {
        for (chart, points) in [("image", &r.points), ("ao", &r.ao_points)] {
            for p in points {
                text.push_str(&format!(
                    "{},{chart},{},{},{},{:.6},{:.6e},{:.6e},{}\n",
                    r.name.replace(',', ";"),
                    p.method.replace(',', ";"),
                    p.unit,
                    p.value,
                    p.ms,
                    p.rmse,
                    p.rel_mse,
                    p.flip.map_or(String::new(), |f| format!("{f:.5}"))
                ));
            }
        }
    }
    text
}

/// The Markdown tables of a run's JSON (what BENCHMARKS.md shows): per scene, path tracing at
/// 1, 8, 32 and 256 spp, the hybrid at 4 shadow rays (with SSAO and IBL, without each, and with
/// 1024² PCF shadow maps where the scene has punctual lights), each as GPU time, relative MSE (r)
/// and mean LDR-FLIP (F); then ambient occlusion's MSE.
pub fn table(doc: &serde_json::Value) -> String {
    let time = |ms: f64| match ms {
        ms if ms >= 1000.0 => format!("{:.1} s", ms / 1000.0),
        ms if ms >= 10.0 => format!("{ms:.0} ms"),
        ms => format!("{ms:.1} ms"),
    };
    // `n` significant digits, written out (0.48, 0.060, 0.0021).
    let sig = |x: f64, n: i32| {
        let digits = (n - 1 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    };
    let two = |x: f64| sig(x, 2);
    fn find<'a>(
        points: &'a serde_json::Value,
        method: &str,
        unit: &str,
        value: u64,
    ) -> Option<&'a serde_json::Value> {
        points.as_array().and_then(|ps| {
            ps.iter()
                .find(|p| p["method"] == method && p["unit"] == unit && p["value"].as_u64() == Some(value))
        })
    }
    let mut out = format!(
        "{}×{}, {}-spp references, {}:\n\n\
         | scene | path 1 spp | path 8 spp | path 32 spp | path 256 spp | hybrid (4 shadow rays, SSAO 16, IBL) | without SSAO | without IBL | with PCF maps 1024² |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        doc["size"][0],
        doc["size"][1],
        doc["reference_spp"],
        doc["device"].as_str().unwrap_or("?"),
    );
    let scenes = doc["scenes"].as_array().cloned().unwrap_or_default();
    for scene in &scenes {
        let points = &scene["points"];
        let cell = |method: &str, unit: &str, value: u64| {
            find(points, method, unit, value).map_or("—".to_string(), |p| {
                format!(
                    "{}: r {}, F {:.3}",
                    time(num(&p["gpu_ms"])),
                    two(num(&p["rel_mse"])),
                    num(&p["flip"])
                )
            })
        };
        let mut row = format!("| {} |", scene["scene"].as_str().unwrap_or("?"));
        if scene["reference_spp"].is_u64() && scene["reference_spp"] != doc["reference_spp"] {
            row.pop();
            row += &format!("({}-spp reference) |", scene["reference_spp"]);
        }
        for spp in [1, 8, 32, 256] {
            row += &format!(" {} |", cell("pathtrace", "spp", spp));
        }
        for method in ["hybrid", "hybrid, no SSAO", "hybrid, no IBL"] {
            row += &format!(" {} |", cell(method, "shadow_rays", 4));
        }
        row += &format!(" {} |\n", cell("hybrid, pcf shadow maps", "map_size", 1024));
        out += &row;
    }
    out += "\nAmbient occlusion, MSE against the RTAO reference (surface pixels):\n\n\
            | scene | SSAO 4 / 16 / 32 directions (+ blur) | GTAO 1 / 2 / 3 slices (+ blur) | GTAO half resolution 1 / 2 / 3 slices (+ upsample) | RTAO 1 / 4 / 16 / 64 rays |\n|---|---|---|---|---|\n";
    for scene in &scenes {
        let points = &scene["ao_points"];
        let cells = |method: &str, unit: &str, values: &[u64]| {
            let cells: Vec<String> = values
                .iter()
                .map(|&v| {
                    find(points, method, unit, v).map_or("—".to_string(), |p| {
                        format!("{} {}", time(num(&p["gpu_ms"])), sig(num(&p["mse"]), 3))
                    })
                })
                .collect();
            cells.join(" / ")
        };
        out += &format!(
            "| {} | {} | {} | {} | {} |\n",
            scene["scene"].as_str().unwrap_or("?"),
            cells("ssao", "ssao_samples", &[4, 16, 32]),
            cells("gtao", "slices", &[1, 2, 3]),
            cells("gtao half", "slices", &[1, 2, 3]),
            cells("rtao", "rays", &[1, 4, 16, 64])
        );
    }
    let shadowed: Vec<&serde_json::Value> =
        scenes.iter().filter(|s| s["shadow_reference"].is_object()).collect();
    if shadowed.is_empty() {
        return out;
    }
    out += "\nThe shadow term: relative MSE of the hybrid (SSAO 16, IBL) against the same hybrid with \
            ray-traced shadows of the sized lights (the reference), GPU time per frame:\n\n\
            | scene | reference | rt, points, 4 rays | rt sized 1 / 4 / 16 rays | hard 1024² | PCF 1024² | PCSS 1024² | moments 1024² |\n\
            |---|---|---|---|---|---|---|---|\n";
    for scene in shadowed {
        let points = &scene["points"];
        let cell = |method: &str, unit: &str, value: u64| {
            find(points, method, unit, value).map_or("—".to_string(), |p| {
                format!("{}: r {}", time(num(&p["gpu_ms"])), sig(num(&p["shadow_rel_mse"]), 2))
            })
        };
        let r = &scene["shadow_reference"];
        let sized: Vec<String> =
            [1, 4, 16].iter().map(|&n| cell("hybrid, rt sized shadows", "shadow_rays", n)).collect();
        let mut row = format!(
            "| {} | radius {} m, sun {:.2}°, {} rays per light | {} | {} |",
            scene["scene"].as_str().unwrap_or("?"),
            num(&r["light_radius"]) as f32,
            num(&r["sun_angle"]).to_degrees(),
            r["rays"],
            cell("hybrid", "shadow_rays", 4),
            sized.join(" / ")
        );
        for method in ["hard", "pcf", "pcss", "moments"] {
            row += &format!(" {} |", cell(&format!("hybrid, {method} shadow maps"), "map_size", 1024));
        }
        out += &row;
        out += "\n";
    }
    out
}

/// The Cornell box with its ceiling lamp replaced by a point light of the same on-axis intensity
/// (radiance × area) just below the lamp's centre: the shadow maps' test scene (a cube map).
pub(crate) fn cornell_point_light() -> umbra::scene::Scene {
    let mut scene = umbra::scene::Scene::cornell_box();
    scene.name = "Cornell box, point light".into();
    let (mut area, mut centre, mut radiance) = (0.0f32, Vec3::ZERO, [0.0f32; 3]);
    for &t in &scene.emissive.triangles {
        let [a, b, c] = scene.triangles[t as usize].map(|i| Vec3::from(scene.positions[i as usize]));
        let da = 0.5 * (b - a).cross(c - a).length();
        area += da;
        centre += da * (a + b + c) / 3.0;
        radiance = scene.materials[scene.triangle_material[t as usize] as usize].emissive;
    }
    let centre = centre / area.max(1e-12);
    for &t in &scene.emissive.triangles.clone() {
        let m = scene.triangle_material[t as usize] as usize;
        scene.materials[m].emissive = [0.0; 3];
    }
    scene.update_emissive();
    let peak = radiance.iter().copied().fold(1e-12f32, f32::max);
    scene.lights.push(umbra::scene::Light {
        name: "lamp".into(),
        kind: umbra::scene::LightKind::Point,
        position: (centre - Vec3::Y * 0.01).into(),
        direction: [0.0, -1.0, 0.0],
        color: radiance.map(|c| c / peak),
        intensity: peak * area,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    });
    scene
}

/// Samples per pixel of Sponza's reference and most measured in the suite (a path through
/// Sponza costs about 3× one through the other scenes: this keeps its run to a few minutes).
pub(crate) const SPONZA_SUITE_SPP: (u32, u32) = (512, 64);

/// The suite's scenes, each with its key: the embedded Cornell box (`cornell`), its point-light
/// variant (`cornell-point`), the repository's `scenes/spheres.glb` and `scenes/textured.glb`
/// (by their stems), Sponza under a sun (`sponza-sun`) and the `gltf` files (by their stems);
/// `quick` keeps the Cornell box and the sphere grid, `only` (where not empty) the scenes of those
/// keys.
fn suite_scenes(
    quick: bool,
    gltf: &[PathBuf],
    sponza: Option<&std::path::Path>,
    only: &[String],
) -> Result<Vec<(String, Scene)>> {
    let mut scenes = vec![("cornell".to_string(), umbra::scene::Scene::cornell_box())];
    if !quick {
        scenes.push(("cornell-point".to_string(), cornell_point_light()));
    }
    let repo_scenes: &[&str] = if quick { &["spheres"] } else { &["spheres", "textured"] };
    for name in repo_scenes {
        let path = PathBuf::from("scenes").join(format!("{name}.glb"));
        match umbra::scene::Scene::load(&path) {
            Ok(scene) => scenes.push((name.to_string(), scene)),
            Err(e) => log::warn!("skipping {}: {e} (run from the repository root)", path.display()),
        }
    }
    if !quick {
        scenes.extend(sponza_under_a_sun(sponza));
    }
    scenes.extend(load_gltf(gltf)?);
    if !only.is_empty() {
        scenes.retain(|(key, _)| only.contains(key));
        if scenes.is_empty() {
            anyhow::bail!("--only {}: none of the suite's scenes has that key", only.join(","));
        }
    }
    Ok(scenes)
}

pub(crate) fn run_suite(
    settings: &SuiteSettings,
    quick: bool,
    gltf: &[PathBuf],
    sponza: Option<&std::path::Path>,
    only: &[String],
) -> Result<()> {
    let scenes = suite_scenes(quick, gltf, sponza, only)?;
    let ctx = Context::new(&ContextDesc::default())?;
    umbra::atomic::create_dir(&settings.out)?;
    let mut results = Vec::new();
    for (key, scene) in &scenes {
        let camera = bench_camera(scene);
        let capped;
        let scene_settings = if key == "sponza-sun" {
            capped = SuiteSettings {
                reference_spp: settings.reference_spp.min(SPONZA_SUITE_SPP.0),
                max_spp: settings.max_spp.min(SPONZA_SUITE_SPP.1),
                ..settings.clone()
            };
            &capped
        } else {
            settings
        };
        let result =
            run_scene(&ctx, key, scene, &camera, scene_settings).with_context(|| scene.name.clone())?;
        println!(
            "\n{} ({} triangles), reference noise floor {:.2e}:",
            result.name, result.triangles, result.reference_rel_mse_floor
        );
        for p in &result.points {
            let setting = format!("{}={}", p.unit, p.value);
            println!(
                "  {:20} {:16} {:10.3} ms  RMSE {:.4e}  relMSE {:.4e}  FLIP {:.4}",
                p.method,
                setting,
                p.ms,
                p.rmse,
                p.rel_mse,
                p.flip.unwrap_or(f64::NAN)
            );
        }
        println!(
            "  ambient occlusion vs RTAO reference (noise floor {:.2e}):",
            result.ao_reference_mse_floor
        );
        for p in &result.ao_points {
            let setting = format!("{}={}", p.unit, p.value);
            println!("  {:20} {:16} {:10.3} ms  MSE {:.4e}", p.method, setting, p.ms, p.rel_mse);
        }
        for (pass, ms) in &result.precompute_ms {
            println!("  once per scene: {pass} {ms:.3} ms");
        }
        results.push(result);
    }
    let doc = json!({
        "device": ctx.info().name,
        "size": [settings.size.0, settings.size.1],
        "ao_radius": settings.ao_radius,
        "reference_spp": settings.reference_spp,
        "repeats": settings.repeats,
        "scenes": results.iter().map(|r| json!({
            "scene": r.name,
            "key": r.key,
            "triangles": r.triangles,
            "reference_rel_mse_floor": r.reference_rel_mse_floor,
            "reference_spp": r.reference_spp,
            "shadow_reference": r.shadow_reference.as_ref().map(|s| json!({
                "kind": "rt sized", "rays": s.rays, "frames": s.frames,
                "light_radius": s.light_radius, "sun_angle": s.sun_angle,
            })),
            "points": r.points.iter().map(|p| {
                let mut point = json!({
                    "method": p.method, "unit": p.unit, "value": p.value, "gpu_ms": p.ms,
                    "rmse": p.rmse, "rel_mse": p.rel_mse, "flip": p.flip,
                });
                if let Some(shadow) = p.shadow_rel_mse {
                    point["shadow_rel_mse"] = json!(shadow);
                }
                point
            }).collect::<Vec<_>>(),
            "ao_reference_mse_floor": r.ao_reference_mse_floor,
            "ao_points": r.ao_points.iter().map(|p| json!({
                "method": p.method, "unit": p.unit, "value": p.value, "gpu_ms": p.ms, "mse": p.rel_mse,
            })).collect::<Vec<_>>(),
            "precompute_ms": r.precompute_ms.iter().map(|(pass, ms)| json!({"pass": pass, "ms": ms})).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    });
    let path = settings.out.join("suite.json");
    umbra::atomic::write(&path, serde_json::to_string_pretty(&doc)?.as_bytes())?;
    let csv = settings.out.join("suite.csv");
    umbra::atomic::write(&csv, self::csv(&results).as_bytes())?;
    println!("wrote {}, {} and suite-<scene>.svg/.png", path.display(), csv.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A suite JSON that does not record its scenes' keys redraws under the run's: every scene of
    /// the full suite (a glTF file standing in for Sponza) and a `--gltf` file get back the key
    /// the run gave them from their names alone.
    #[test]
    fn the_keys_of_scene_names_are_the_runs() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let sponza = root.join("scenes/textured.glb");
        let gltf = [root.join("scenes/cornell-box.glb")];
        let scenes = suite_scenes(false, &gltf, Some(&sponza), &[]).unwrap();
        let keys: Vec<&str> = scenes.iter().map(|(key, _)| key.as_str()).collect();
        assert_eq!(keys, ["cornell", "cornell-point", "spheres", "textured", "sponza-sun", "cornell-box"]);
        for (key, scene) in &scenes {
            assert_eq!(&key_of_name(&scene.name), key, "{}", scene.name);
        }
    }
}
