//! GPU time per pass of each method on one scene: the hybrid passes (G-buffer, SSAO (16
//! directions × 4 steps, radius 0.5) and its blur, deferred lighting with IBL × AO) and one
//! path-traced sample per pixel, each a median over repeats after a warm-up
//! ([`super::rays::warm_up`]),
//! from GPU timestamps.

use super::num;
use crate::scenes::bench_camera;
use crate::write_json;
use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::GBuffer;
use umbra::passes::pathtrace::PathTarget;
use umbra::render::{Frame, HybridSettings, HybridTargets, Passes, PathSettings};
use umbra::scene::Camera;
use umbra::vk::ContextDesc;
use umbra::vk::{raw, Context, GpuTimer, Image};

/// A pass's median GPU time.
pub struct PassTiming {
    /// The pass.
    pub name: String,
    /// Median GPU milliseconds over the repeats.
    pub median_ms: f64,
    /// Fastest repeat.
    pub min_ms: f64,
}

/// What a benchmarked hybrid frame renders into: a G-buffer, a linear colour image (in `GENERAL`
/// layout) and the scene's image-based lighting tables (the default settings).
pub struct FrameImages {
    /// The G-buffer.
    pub gbuffer: GBuffer,
    /// `R32G32B32A32_SFLOAT` linear colour.
    pub output: Image,
    /// The split-sum tables.
    pub ibl: umbra::passes::ibl::IblResources,
}

impl FrameImages {
    /// The images for frames of `size` and `scene`'s IBL tables.
    pub fn new(ctx: &Context, scene: &GpuScene, size: (u32, u32)) -> Result<Self> {
        let gbuffer = GBuffer::new(ctx, size)?;
        let output =
            Image::storage_2d(ctx, "bench colour", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
        let ibl = umbra::passes::ibl::IblResources::build(ctx, scene, &Default::default())?;
        ctx.submit(|cmd| {
            output.init_general(ctx, cmd);
            Ok(())
        })?;
        Ok(Self { gbuffer, output, ibl })
    }
}

/// Times every pass at `size`, `repeats` times after one warm-up submission.
pub fn run(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    repeats: usize,
    lighting: &LightingSettings,
) -> Result<Vec<PassTiming>> {
    let passes = Passes::new(ctx, scene);
    let FrameImages { gbuffer, output, ibl } = FrameImages::new(ctx, scene, size)?;
    let target = PathTarget::new(ctx, size)?;
    let path_settings = PathSettings { size, env: lighting.env, ..PathSettings::default() };
    let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
    let (ao_raw, ao_blurred) = (make("bench ssao")?, make("bench ssao blurred")?);
    ctx.submit(|cmd| {
        ao_raw.init_general(ctx, cmd);
        ao_blurred.init_general(ctx, cmd);
        Ok(())
    })?;
    let views = gbuffer.views();
    // The hybrid frame without its tonemap, as the renderer records it.
    let targets = HybridTargets {
        gbuffer: &views,
        ao: Some((ao_raw.view, ao_blurred.view)),
        hdr: output.view,
        ldr: None,
        shadows: None,
        probes: None,
        lightmaps: None,
        reservoirs: None,
    };
    let settings = HybridSettings {
        size,
        lighting: *lighting,
        ao: Some(AoSettings::default()),
        ..HybridSettings::default()
    };
    super::rays::warm_up(|| {
        ctx.record(|rec| {
            passes.record_hybrid(rec, Frame { scene, ibl: &ibl, camera }, &targets, &settings, None)?;
            passes.record_path_samples(rec, scene, camera, &target, &path_settings, 0..1)
        })
    })?;
    let mut timer = GpuTimer::new(ctx, 5)?;
    let mut samples: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut names = Vec::new();
    for repeat in 0..=repeats {
        ctx.record(|rec| {
            let cmd = rec.cmd();
            timer.reset(cmd);
            passes.record_hybrid(
                rec,
                Frame { scene, ibl: &ibl, camera },
                &targets,
                &settings,
                Some(&mut timer),
            )?;
            timer.begin(cmd, "pathtrace 1 spp")?;
            passes.record_path_samples(
                rec,
                scene,
                camera,
                &target,
                &path_settings,
                repeat as u32..repeat as u32 + 1,
            )?;
            timer.end(cmd)
        })?;
        let times = timer.read()?;
        if repeat == 0 {
            names = times.iter().map(|t| t.name.clone()).collect();
            continue; // warm-up
        }
        for (k, t) in times.iter().enumerate() {
            samples[k].push(t.ms);
        }
    }
    Ok(names
        .into_iter()
        .zip(samples)
        .map(|(name, mut ms)| PassTiming {
            name,
            min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
            median_ms: super::rays::median(&mut ms),
        })
        .collect())
}

/// The run as JSON (`passes.json`): the scene, the settings, the conditions
/// ([`super::add_conditions`]) and each pass's median and fastest GPU time.
pub fn to_json(
    device: &str,
    scene: &str,
    triangles: usize,
    size: (u32, u32),
    repeats: usize,
    shadow_rays: u32,
    timings: &[PassTiming],
) -> Value {
    let mut doc = json!({
        "device": device,
        "scene": scene,
        "triangles": triangles,
        "size": [size.0, size.1],
        "repeats": repeats,
        "shadow_rays": shadow_rays,
        "passes": timings.iter().map(|t| json!({"pass": t.name, "median_ms": t.median_ms, "min_ms": t.min_ms})).collect::<Vec<_>>(),
    });
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of one or more runs' JSON (what BENCHMARKS.md shows): a row per pass, a
/// column per run (scene), median GPU milliseconds with the fastest repeat in brackets. The runs
/// must share their settings (size, repeats, shadow rays, device, lavapipe threads); the load
/// each started under is listed under the table.
pub fn table(docs: &[Value]) -> Result<String> {
    let Some(first) = docs.first() else { bail!("no passes.json given") };
    for doc in docs {
        for key in ["size", "repeats", "shadow_rays", "device", "lp_num_threads"] {
            if doc[key] != first[key] {
                bail!("the runs differ in {key} ({} and {}): print their tables apart", first[key], doc[key]);
            }
        }
    }
    // Three significant digits (0.0790, 4.12, 15.6, 135).
    let sig3 = |x: f64| {
        let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    };
    let mut out = format!(
        "{}×{}, GPU ms per pass, median of {} timed submissions after a warm-up (the fastest in brackets); \
         lighting with {} shadow rays per pixel for emissive triangles; {}, LP_NUM_THREADS {}:\n\n| pass |",
        first["size"][0],
        first["size"][1],
        first["repeats"],
        first["shadow_rays"],
        first["device"].as_str().unwrap_or("?"),
        first["lp_num_threads"].as_str().unwrap_or("unset"),
    );
    for doc in docs {
        out += &format!(" {}, {} triangles |", doc["scene"].as_str().unwrap_or("?"), doc["triangles"]);
    }
    out += &format!("\n|---|{}\n", "---:|".repeat(docs.len()));
    let mut passes: Vec<&str> = Vec::new();
    for doc in docs {
        for p in doc["passes"].as_array().into_iter().flatten() {
            let name = p["pass"].as_str().unwrap_or("?");
            if !passes.contains(&name) {
                passes.push(name);
            }
        }
    }
    for pass in passes {
        out += &format!("| {pass} |");
        for doc in docs {
            let timing = doc["passes"].as_array().and_then(|ps| ps.iter().find(|p| p["pass"] == pass));
            out += &timing.map_or(" — |".to_string(), |t| {
                format!(" {} ({}) |", sig3(num(&t["median_ms"])), sig3(num(&t["min_ms"])))
            });
        }
        out += "\n";
    }
    let loads: Vec<String> = docs
        .iter()
        .map(|doc| format!("{}: {}", doc["scene"].as_str().unwrap_or("?"), super::load_text(doc)))
        .collect();
    out += &format!("\nConditions of each run: {}.\n", loads.join("; "));
    Ok(out)
}

pub(crate) fn run_passes(
    scene: Option<PathBuf>,
    size: (u32, u32),
    repeats: usize,
    shadow_rays: u32,
    out: PathBuf,
) -> Result<()> {
    let ctx = Context::new(&ContextDesc::default())?;
    let loaded = match &scene {
        Some(path) => umbra::scene::Scene::load(path)?,
        None => umbra::scene::Scene::cornell_box(),
    };
    let camera = bench_camera(&loaded);
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(&ctx, &loaded)?;
    let lighting = umbra::passes::deferred::LightingSettings { shadow_rays, ..Default::default() };
    let timings = run(&ctx, &gpu_scene, &camera, size, repeats, &lighting)?;
    let pixels = size.0 as f64 * size.1 as f64;
    println!(
        "{} ({} triangles) at {}x{} on {}:",
        loaded.name,
        gpu_scene.bvh_stats.triangles,
        size.0,
        size.1,
        ctx.info().name
    );
    for t in &timings {
        println!(
            "  {:18} {:9.3} ms median  {:9.3} ms min  {:9.1} Mpixels/s",
            t.name,
            t.median_ms,
            t.min_ms,
            pixels / (t.median_ms * 1e3)
        );
    }
    let doc = to_json(
        &ctx.info().name,
        &loaded.name,
        gpu_scene.bvh_stats.triangles,
        size,
        repeats,
        shadow_rays,
        &timings,
    );
    write_json(&out, "passes.json", &doc)
}
