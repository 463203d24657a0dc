//! Shadow maps against shadow rays on one scene: per method (`rt`, `hard`, `pcf`, `pcss`,
//! `moments`) the GPU time of rendering the maps (by step: bin, scan, fill, raster, moments), of
//! the lighting pass that reads them, and the error of the lit image against the ray-traced one
//! (so the error is the shadow term's: everything else is the same), each a median over repeats
//! after a warm-up. The ray-traced shadows' own cost is the lighting pass's time with rays less
//! its time with a hard map (the same shading, one map read instead of a ray per light).
//!
//! PCSS and the other filters soften shadows by the lights' size (`light_radius`, `sun_angle`),
//! so when the lights have one, every method is also measured against ray-traced shadows of
//! those sized lights with [`REFERENCE_RAYS`] rays per light (the [`Reference`], recorded in the
//! JSON), and ray-traced sized lights themselves are timed at [`SIZED_RAYS`] rays.

use super::num;
use crate::scenes::add_sun;
use crate::scenes::bench_camera;
use crate::scenes::DEFAULT_SUN;
use crate::write_json;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::GBufferViews;
use umbra::passes::shadow::{ShadowMaps, ShadowMethod, ShadowSettings, ShadowView};
use umbra::render::{Frame, HybridSettings, HybridTargets, Passes};
use umbra::scene::Camera;
use umbra::vk::ContextDesc;
use umbra::vk::{raw, Context, GpuTimer};

/// One method's measurements.
pub struct ShadowTiming {
    /// The method's name (`rt sized`: ray-traced shadows of the sized lights).
    pub method: &'static str,
    /// Shadow rays per light and pixel (`rt sized`; 1 otherwise).
    pub rays: u32,
    /// Median GPU milliseconds of rendering every layer (0 for rays).
    pub maps_ms: f64,
    /// The maps' steps (kernel, milliseconds summed over the layers) of the last repeat.
    pub steps: Vec<(String, f64)>,
    /// Fraction of the layers' tiles rendered (the windows', or the view's marked ones).
    pub tiles: f64,
    /// Median GPU milliseconds of the lighting pass.
    pub lighting_ms: f64,
    /// Relative MSE of the lit image against the ray-traced one of point lights (mean over
    /// pixels and channels of d² / (ref² + 0.01)).
    pub rel_mse: f64,
    /// Fraction of pixels whose luminance differs from the point lights' ray-traced by more
    /// than 10 %.
    pub differing: f64,
    /// Relative MSE against the [`Reference`].
    pub ref_rel_mse: f64,
    /// Fraction of pixels more than 10 % off the [`Reference`] in luminance.
    pub ref_differing: f64,
}

/// What the methods' errors are measured against: ray-traced shadows of the sized lights (a
/// sphere of `light_radius`, a cone of `sun_angle`) with `rays` rays per light and pixel, the
/// mean of `frames` frames of another seed than the measured ones; or, when the lights have no
/// size, the point lights' ray-traced image (`rays` 1).
pub struct Reference {
    /// `rt sized` or `rt` (points).
    pub kind: &'static str,
    /// Rays per light and pixel in all.
    pub rays: u32,
    /// Frames averaged.
    pub frames: u32,
    /// Radius of point and spot lights, metres.
    pub light_radius: f32,
    /// Angular radius of directional lights, radians.
    pub sun_angle: f32,
}

/// Rays per light and pixel of the sized lights' reference.
pub const REFERENCE_RAYS: u32 = 256;
/// Shadow-ray counts of the `rt sized` series.
pub const SIZED_RAYS: [u32; 3] = [1, 4, 16];

/// Times every method on `scene` at `size` with maps of `shadows.map_size` (the other shadow
/// settings as given), `repeats` times after a warm-up; then ray-traced shadows of the sized
/// lights at [`SIZED_RAYS`]; and measures each against the point lights' ray-traced image and
/// the [`Reference`].
pub fn run(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    repeats: usize,
    shadows: &ShadowSettings,
) -> Result<(Vec<ShadowTiming>, Reference)> {
    let passes = Passes::new(ctx, scene);
    let super::passes::FrameImages { gbuffer, output, ibl } =
        super::passes::FrameImages::new(ctx, scene, size)?;
    let views = gbuffer.views();
    // The view's G-buffer, which the maps' marks read (record_hybrid renders the same again).
    ctx.record(|rec| passes.record_gbuffer(rec, scene, camera, &views))?;
    let view = Some(ShadowView { camera, gbuffer: &views });
    let lighting = LightingSettings { env: [0.2; 3], ..LightingSettings::default() };
    let mut point: Option<Vec<[f32; 4]>> = None;
    let mut measured = Vec::new();
    let mut runs: Vec<(ShadowMethod, u32)> = ShadowMethod::ALL.iter().map(|&m| (m, 1)).collect();
    let sized = shadows.light_radius > 0.0 || shadows.sun_angle > 0.0;
    if sized {
        runs.extend(SIZED_RAYS.iter().map(|&rays| (ShadowMethod::RayTraced, rays)));
    }
    fn targets<'a>(
        views: &'a GBufferViews,
        hdr: raw::ImageView,
        maps: Option<&'a ShadowMaps>,
    ) -> HybridTargets<'a> {
        HybridTargets {
            gbuffer: views,
            visibility: None,
            ao: None,
            hdr,
            ldr: None,
            shadows: maps,
            probes: None,
            lightmaps: None,
            reservoirs: None,
            taa: None,
        }
    }
    for (i, &(method, rays)) in runs.iter().enumerate() {
        let sized_rays = i >= ShadowMethod::ALL.len();
        let settings = ShadowSettings { method, sized_rays, ..*shadows };
        let mut maps = match method.uses_maps() {
            true => Some(passes.shadow_maps(scene, camera, size, &settings)?),
            false => None,
        };
        // Maps: warm up (which also grows the tile lists once if they overflow), then time.
        let mut maps_ms = Vec::new();
        let mut steps = Vec::new();
        let mut tiles = 0.0;
        if let Some(maps) = maps.as_mut() {
            super::rays::warm_up(|| passes.render_shadow_maps(scene, maps, view).map(|_| ()))?;
            for _ in 0..repeats.max(1) {
                steps = passes.render_shadow_maps(scene, maps, view)?;
                maps_ms.push(steps.iter().map(|s| s.1).sum::<f64>());
            }
            let rendered: u32 = maps.rendered_tiles(ctx)?.iter().sum();
            let per_layer = settings.map_size.div_ceil(umbra::gpu::layout::SHADOW_TILE).pow(2);
            tiles = rendered as f64 / (per_layer as f64 * maps.plan.layers.len() as f64);
        }
        let targets = targets(&views, output.view, maps.as_ref());
        let hybrid = HybridSettings {
            size,
            lighting: LightingSettings { shadow_rays: rays, ..lighting },
            ao: None::<AoSettings>,
            shadows: settings,
            ..HybridSettings::default()
        };
        if sized_rays && hybrid.lighting_with_shadows().validate_sized_rays(scene.punctual_count).is_err() {
            continue;
        }
        let frame = || {
            ctx.record(|rec| {
                passes.record_hybrid(rec, Frame { scene, ibl: &ibl, camera }, &targets, &hybrid, None)
            })
        };
        super::rays::warm_up(frame)?;
        let mut timer = GpuTimer::new(ctx, 2)?;
        let mut lighting_ms = Vec::new();
        for _ in 0..repeats.max(1) {
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                passes.record_hybrid(
                    rec,
                    Frame { scene, ibl: &ibl, camera },
                    &targets,
                    &hybrid,
                    Some(&mut timer),
                )
            })?;
            let times = timer.read()?;
            lighting_ms.extend(times.iter().filter(|t| t.name == "lighting").map(|t| t.ms));
        }
        let image: Vec<[f32; 4]> = output.read(ctx)?;
        let point = point.get_or_insert_with(|| image.clone());
        let (rel_mse, differing) = compare(&image, point);
        measured.push((
            image,
            ShadowTiming {
                method: if sized_rays { "rt sized" } else { method.name() },
                rays,
                maps_ms: if maps_ms.is_empty() { 0.0 } else { super::rays::median(&mut maps_ms) },
                steps,
                tiles,
                lighting_ms: super::rays::median(&mut lighting_ms),
                rel_mse,
                differing,
                ref_rel_mse: 0.0,
                ref_differing: 0.0,
            },
        ));
    }
    // The reference: the sized lights' rays, as many per frame as one invocation may trace,
    // frames averaged (their rays continue one sequence), another seed.
    let lights = scene.punctual_count.clamp(1, umbra::gpu::layout::PUNCTUAL_ALL);
    let per_frame = (LightingSettings::MAX_SHADOW_RAYS / lights).max(1);
    let frames = if sized { REFERENCE_RAYS.div_ceil(per_frame) } else { 1 };
    let reference = Reference {
        kind: if sized { "rt sized" } else { "rt" },
        rays: if sized { per_frame * frames } else { 1 },
        frames,
        light_radius: shadows.light_radius,
        sun_angle: shadows.sun_angle,
    };
    let reference_image = match sized {
        false => point.clone().unwrap_or_default(),
        true => {
            let settings = ShadowSettings { method: ShadowMethod::RayTraced, sized_rays: true, ..*shadows };
            let targets = targets(&views, output.view, None);
            let mut sum = vec![[0.0f32; 4]; (size.0 * size.1) as usize];
            for f in 0..frames {
                let hybrid = HybridSettings {
                    size,
                    lighting: LightingSettings { shadow_rays: per_frame, frame: f, seed: 1, ..lighting },
                    ao: None::<AoSettings>,
                    shadows: settings,
                    ..HybridSettings::default()
                };
                ctx.record(|rec| {
                    passes.record_hybrid(rec, Frame { scene, ibl: &ibl, camera }, &targets, &hybrid, None)
                })?;
                let image: Vec<[f32; 4]> = output.read(ctx)?;
                for (s, p) in sum.iter_mut().zip(&image) {
                    for c in 0..4 {
                        s[c] += p[c] / frames as f32;
                    }
                }
            }
            sum
        }
    };
    let out = measured
        .into_iter()
        .map(|(image, mut t)| {
            (t.ref_rel_mse, t.ref_differing) = compare(&image, &reference_image);
            t
        })
        .collect();
    Ok((out, reference))
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
#[allow(clippy::too_many_arguments)]
pub fn to_json(
    device: &str,
    scene: &str,
    triangles: usize,
    size: (u32, u32),
    settings: &ShadowSettings,
    layers: usize,
    timings: &[ShadowTiming],
    reference: &Reference,
) -> Value {
    json!({
        "device": device,
        "scene": scene,
        "triangles": triangles,
        "size": [size.0, size.1],
        "map_size": settings.map_size,
        "cascades": settings.cascades,
        "max_radius": settings.max_radius,
        "view_marks": settings.view_marks,
        "layers": layers,
        "reference": {
            "kind": reference.kind,
            "rays": reference.rays,
            "frames": reference.frames,
            "light_radius": reference.light_radius,
            "sun_angle": reference.sun_angle,
        },
        "methods": timings.iter().map(|t| json!({
            "method": t.method,
            "rays": t.rays,
            "maps_ms": t.maps_ms,
            "steps": t.steps.iter().map(|(name, ms)| json!({"step": name, "ms": ms})).collect::<Vec<_>>(),
            "tiles_rendered": t.tiles,
            "lighting_ms": t.lighting_ms,
            "rel_mse_vs_rt": t.rel_mse,
            "pixels_off_10pct": t.differing,
            "rel_mse_vs_reference": t.ref_rel_mse,
            "pixels_off_10pct_vs_reference": t.ref_differing,
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
    let r = &doc["reference"];
    let reference = match r["kind"].as_str() {
        Some("rt sized") => format!(
            "ray-traced shadows of the sized lights (radius {} m, sun {:.2}°), {} rays per light in {} frames",
            num(&r["light_radius"]) as f32,
            num(&r["sun_angle"]).to_degrees(),
            r["rays"],
            r["frames"]
        ),
        _ => "ray-traced shadows of the point lights".to_string(),
    };
    let mut out = format!(
        "{} ({} triangles) at {}×{}, maps {}² ({} layer{}), {}; reference: {reference}:\n\n\
         | method | maps ms | tiles rendered | lighting ms | maps ÷ shadow rays | rel. MSE vs rt (points) | pixels > 10 % off | rel. MSE vs reference | pixels > 10 % off the reference |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        doc["scene"].as_str().unwrap_or("?"),
        doc["triangles"],
        doc["size"][0],
        doc["size"][1],
        doc["map_size"],
        doc["layers"],
        if doc["layers"] == 1 { "" } else { "s" },
        doc["device"].as_str().unwrap_or("?"),
    );
    for m in &methods {
        let maps = num(&m["maps_ms"]);
        let name = match m["method"].as_str().unwrap_or("?") {
            "rt sized" => format!("rt sized, {} ray{}", m["rays"], if m["rays"] == 1 { "" } else { "s" }),
            other => other.to_string(),
        };
        let ratio = if m["maps_ms"] == 0.0 { "—".to_string() } else { format!("{:.2}", maps / rays_ms) };
        let tiles = match m["tiles_rendered"].as_f64() {
            Some(t) if m["maps_ms"] != 0.0 => format!("{:.1} %", 100.0 * t),
            _ => "—".to_string(),
        };
        out += &format!(
            "| {name} | {:.1} | {tiles} | {:.1} | {} | {:.2e} | {:.2} % | {:.2e} | {:.2} % |\n",
            maps,
            num(&m["lighting_ms"]),
            ratio,
            num(&m["rel_mse_vs_rt"]),
            100.0 * num(&m["pixels_off_10pct"]),
            num(&m["rel_mse_vs_reference"]),
            100.0 * num(&m["pixels_off_10pct_vs_reference"]),
        );
    }
    out += &format!(
        "\nShadow rays alone (lighting with rays less lighting with a hard map): {rays_ms:.1} ms.\n"
    );
    out
}

pub(crate) fn run_shadows(
    scene: Option<PathBuf>,
    size: (u32, u32),
    settings: &umbra::passes::shadow::ShadowSettings,
    sun: Option<[f32; 3]>,
    repeats: usize,
    out: PathBuf,
) -> Result<()> {
    let ctx = Context::new(&ContextDesc::default())?;
    let mut loaded = match &scene {
        Some(path) => umbra::scene::Scene::load(path)?,
        None => umbra::scene::Scene::cornell_box(),
    };
    if sun.is_some() || loaded.lights.is_empty() {
        add_sun(&mut loaded, sun.unwrap_or(DEFAULT_SUN));
    }
    let camera = bench_camera(&loaded);
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(&ctx, &loaded)?;
    let layers = umbra::passes::shadow::ShadowPlan::new(
        &gpu_scene.punctual_lights,
        gpu_scene.bounds,
        &camera,
        size,
        settings,
    )?
    .layers
    .len();
    settings.validate()?;
    let (timings, reference) = run(&ctx, &gpu_scene, &camera, size, repeats, settings)?;
    let doc = to_json(
        &ctx.info().name,
        &loaded.name,
        gpu_scene.bvh_stats.triangles,
        size,
        settings,
        layers,
        &timings,
        &reference,
    );
    print!("{}", table(&doc));
    for t in &timings {
        let steps: Vec<String> = t.steps.iter().map(|(name, ms)| format!("{name} {ms:.1} ms")).collect();
        if !steps.is_empty() {
            println!("  {}: {}", t.method, steps.join(", "));
        }
    }
    write_json(&out, "shadows.json", &doc)
}
