//! Shadow maps against shadow rays on one scene: per method (`rt`, `hard`, `pcf`, `pcss`,
//! `moments`) the GPU time of rendering the maps (by step: bin, scan, fill, raster, moments), of
//! the lighting pass that reads them, and the error of the lit image against the ray-traced one
//! (so the error is the shadow term's: everything else is the same), each a median over repeats
//! after a warm-up. The ray-traced shadows' own cost is the lighting pass's time with rays less
//! its time with a hard map (the same shading, one map read instead of a ray per light).

use super::num;
use anyhow::Result;
use serde_json::{json, Value};
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::shadow::{ShadowMethod, ShadowSettings};
use umbra::render::{HybridSettings, HybridTargets, Passes};
use umbra::scene::Camera;
use umbra::vk::{Context, GpuTimer};

/// One method's measurements.
pub struct ShadowTiming {
    /// The method's name.
    pub method: &'static str,
    /// Median GPU milliseconds of rendering every layer (0 for rays).
    pub maps_ms: f64,
    /// The maps' steps (kernel, milliseconds summed over the layers) of the last repeat.
    pub steps: Vec<(String, f64)>,
    /// Median GPU milliseconds of the lighting pass.
    pub lighting_ms: f64,
    /// Relative MSE of the lit image against the ray-traced one (mean over pixels and channels
    /// of d² / (ref² + 0.01)).
    pub rel_mse: f64,
    /// Fraction of pixels whose luminance differs from the ray-traced by more than 10 %.
    pub differing: f64,
}

/// Times every method on `scene` at `size` with maps of `shadows.map_size` (the other shadow
/// settings as given), `repeats` times after a warm-up.
pub fn run(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    repeats: usize,
    shadows: &ShadowSettings,
) -> Result<Vec<ShadowTiming>> {
    let passes = Passes::new(ctx, scene);
    let super::passes::FrameImages { gbuffer, output, ibl } =
        super::passes::FrameImages::new(ctx, scene, size)?;
    let views = gbuffer.views();
    let lighting = LightingSettings { env: [0.2; 3], ..LightingSettings::default() };
    let mut reference: Option<Vec<[f32; 4]>> = None;
    let mut out = Vec::new();
    for method in ShadowMethod::ALL {
        let settings = ShadowSettings { method, ..*shadows };
        let mut maps = match method.uses_maps() {
            true => Some(passes.shadow_maps(scene, camera, size, &settings)?),
            false => None,
        };
        // Maps: warm up (which also grows the tile lists once if they overflow), then time.
        let mut maps_ms = Vec::new();
        let mut steps = Vec::new();
        if let Some(maps) = maps.as_mut() {
            super::rays::warm_up(|| passes.render_shadow_maps(scene, maps).map(|_| ()))?;
            for _ in 0..repeats.max(1) {
                steps = passes.render_shadow_maps(scene, maps)?;
                maps_ms.push(steps.iter().map(|s| s.1).sum::<f64>());
            }
        }
        let targets = HybridTargets {
            gbuffer: &views,
            ao: None,
            hdr: output.view,
            ldr: None,
            shadows: maps.as_ref(),
            probes: None,
            lightmaps: None,
            reservoirs: None,
        };
        let hybrid = HybridSettings {
            size,
            lighting,
            ao: None::<AoSettings>,
            shadows: settings,
            ..HybridSettings::default()
        };
        let frame =
            || ctx.submit(|cmd| passes.record_hybrid(cmd, scene, &ibl, camera, &targets, &hybrid, None));
        super::rays::warm_up(frame)?;
        let mut timer = GpuTimer::new(ctx, 2)?;
        let mut lighting_ms = Vec::new();
        for _ in 0..repeats.max(1) {
            ctx.submit(|cmd| {
                timer.reset(cmd);
                passes.record_hybrid(cmd, scene, &ibl, camera, &targets, &hybrid, Some(&mut timer))
            })?;
            let times = timer.read()?;
            lighting_ms.extend(times.iter().filter(|t| t.name == "lighting").map(|t| t.ms));
        }
        let image: Vec<[f32; 4]> = output.read(ctx)?;
        let reference = reference.get_or_insert_with(|| image.clone());
        let (rel_mse, differing) = compare(&image, reference);
        out.push(ShadowTiming {
            method: method.name(),
            maps_ms: if maps_ms.is_empty() { 0.0 } else { super::rays::median(&mut maps_ms) },
            steps,
            lighting_ms: super::rays::median(&mut lighting_ms),
            rel_mse,
            differing,
        });
    }
    Ok(out)
}

/// (relative MSE, fraction of pixels more than 10 % off in luminance) of `image` against
/// `reference`.
fn compare(image: &[[f32; 4]], reference: &[[f32; 4]]) -> (f64, f64) {
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let (mut rel, mut differing) = (0.0, 0);
    for (p, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c] as f64;
            rel += d * d / (r[c] as f64 * r[c] as f64 + 0.01);
        }
        let (lp, lr) = (luminance(p), luminance(r));
        differing += ((lp - lr).abs() > 0.1 * lr.max(1e-3)) as usize;
    }
    let n = image.len().max(1) as f64;
    (rel / (3.0 * n), differing as f64 / n)
}

/// The JSON document of a run.
pub fn to_json(
    device: &str,
    scene: &str,
    triangles: usize,
    size: (u32, u32),
    settings: &ShadowSettings,
    layers: usize,
    timings: &[ShadowTiming],
) -> Value {
    json!({
        "device": device,
        "scene": scene,
        "triangles": triangles,
        "size": [size.0, size.1],
        "map_size": settings.map_size,
        "cascades": settings.cascades,
        "layers": layers,
        "methods": timings.iter().map(|t| json!({
            "method": t.method,
            "maps_ms": t.maps_ms,
            "steps": t.steps.iter().map(|(name, ms)| json!({"step": name, "ms": ms})).collect::<Vec<_>>(),
            "lighting_ms": t.lighting_ms,
            "rel_mse_vs_rt": t.rel_mse,
            "pixels_off_10pct": t.differing,
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows).
pub fn table(doc: &Value) -> String {
    let methods = doc["methods"].as_array().cloned().unwrap_or_default();
    let lighting = |name: &str| {
        methods.iter().find(|m| m["method"] == name).map_or(f64::NAN, |m| num(&m["lighting_ms"]))
    };
    // What the shadow rays themselves cost: lighting with rays less lighting with a hard map.
    let rays_ms = lighting("rt") - lighting("hard");
    let mut out = format!(
        "{} ({} triangles) at {}×{}, maps {}² ({} layers), {}:\n\n\
         | method | maps ms | lighting ms | maps ÷ shadow rays | rel. MSE vs rt | pixels > 10 % off |\n\
         |---|---:|---:|---:|---:|---:|\n",
        doc["scene"].as_str().unwrap_or("?"),
        doc["triangles"],
        doc["size"][0],
        doc["size"][1],
        doc["map_size"],
        doc["layers"],
        doc["device"].as_str().unwrap_or("?"),
    );
    for m in &methods {
        let maps = num(&m["maps_ms"]);
        let ratio = if m["method"] == "rt" { "—".to_string() } else { format!("{:.2}", maps / rays_ms) };
        out += &format!(
            "| {} | {:.1} | {:.1} | {} | {:.2e} | {:.2} % |\n",
            m["method"].as_str().unwrap_or("?"),
            maps,
            num(&m["lighting_ms"]),
            ratio,
            num(&m["rel_mse_vs_rt"]),
            100.0 * num(&m["pixels_off_10pct"]),
        );
    }
    out += &format!(
        "\nShadow rays alone (lighting with rays less lighting with a hard map): {rays_ms:.1} ms.\n"
    );
    out
}
