//! GPU time per pass of each method on one scene: the hybrid frame's passes (the G-buffer, ray-cast
//! or rasterized, the ambient occlusion of each [`AoVariant`] asked for (SSAO, GTAO at full or
//! half resolution, radius 0.5) and its blur, deferred lighting with IBL × AO) and their stages'
//! totals, and one path-traced sample per pixel, each a median over repeats after a warm-up
//! ([`super::rays::warm_up`]), from GPU timestamps.

use super::num;
use crate::scenes::bench_camera;
use crate::write_json;
use anyhow::{bail, Result};
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::{AoMethod, AoResolution, AoSettings};
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::{GBuffer, GBufferMethod, VisibilityBuffer};
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

/// One hybrid frame's variant: its label and its ambient occlusion (`None`: none).
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub enum AoVariant {
    /// No ambient occlusion.
    None,
    /// SSAO, 16 directions × 4 steps, and its blur.
    Ssao,
    /// GTAO at full resolution (its defaults) and its blur.
    Gtao,
    /// GTAO at half resolution and its upsampling blur.
    GtaoHalf,
}

impl AoVariant {
    /// The label in passes.json and the table.
    pub fn label(self) -> &'static str {
        match self {
            Self::None => "no AO",
            Self::Ssao => "ssao",
            Self::Gtao => "gtao",
            Self::GtaoHalf => "gtao half",
        }
    }

    /// The AO settings of the variant.
    pub fn settings(self) -> Option<AoSettings> {
        match self {
            Self::None => None,
            Self::Ssao => Some(AoSettings::default()),
            Self::Gtao => Some(AoSettings::of(AoMethod::Gtao)),
            Self::GtaoHalf => {
                Some(AoSettings { resolution: AoResolution::Half, ..AoSettings::of(AoMethod::Gtao) })
            }
        }
    }
}

/// One hybrid frame's variant: its G-buffer and its ambient occlusion.
#[derive(Clone, Copy, PartialEq)]
pub struct FrameVariant {
    /// Ray-cast or rasterized.
    pub gbuffer: GBufferMethod,
    /// The AO.
    pub ao: AoVariant,
}

impl FrameVariant {
    /// The G-buffer's label in passes.json and the table.
    pub fn gbuffer_label(self) -> &'static str {
        match self.gbuffer {
            GBufferMethod::Raycast => "raycast",
            GBufferMethod::Raster => "raster",
        }
    }
}

/// The timings of one hybrid frame variant: each pass's, and each stage's
/// ([`umbra::render::stage_of`]; `frame` all of them), medians over the repeats of their sums.
pub struct FrameTiming {
    /// The variant.
    pub variant: FrameVariant,
    /// Each pass, in recording order.
    pub passes: Vec<PassTiming>,
    /// `gbuffer`, `ao`, `lighting` and `frame`.
    pub stages: Vec<(&'static str, PassTiming)>,
}

/// What [`run`] measured: each frame variant's timings, and one path-traced sample's.
pub struct PassesRun {
    /// Per variant.
    pub frames: Vec<FrameTiming>,
    /// One path-traced sample per pixel.
    pub path: PassTiming,
}

/// The stages passes.json reports, `frame` the sum of every pass.
pub const STAGES: [&str; 4] = ["gbuffer", "ao", "lighting", "frame"];

fn timing(name: &str, mut ms: Vec<f64>) -> PassTiming {
    PassTiming {
        name: name.to_string(),
        min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
        median_ms: super::rays::median(&mut ms),
    }
}

/// Times every pass of the hybrid frame (without its tonemap) in each of `variants`, and one
/// path-traced sample per pixel, at `size`, `repeats` times after a warm-up; the variants take
/// turns within each repeat, so a change of the machine's load reaches them alike.
pub fn run(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    repeats: usize,
    lighting: &LightingSettings,
    variants: &[FrameVariant],
) -> Result<PassesRun> {
    let passes = Passes::new(ctx, scene);
    let FrameImages { gbuffer, output, ibl } = FrameImages::new(ctx, scene, size)?;
    let mut visibility = None;
    if variants.iter().any(|v| v.gbuffer == GBufferMethod::Raster) {
        if let Some(why) = VisibilityBuffer::unsupported(ctx, scene) {
            bail!("the raster G-buffer cannot be timed: {why}");
        }
        let mut vis = VisibilityBuffer::new(ctx, scene, size)?;
        // Tile lists that hold this view's entries before anything is timed.
        loop {
            ctx.record(|rec| passes.record_gbuffer_with(rec, scene, camera, &gbuffer.views(), Some(&vis)))?;
            match vis.check(ctx)? {
                Some(entries) => vis.reserve(ctx, entries)?,
                None => break,
            }
        }
        visibility = Some(vis);
    }
    let target = PathTarget::new(ctx, size)?;
    let path_settings = PathSettings { size, env: lighting.env, ..PathSettings::default() };
    let views = gbuffer.views();
    // The hybrid frame without its tonemap, as the renderer records it (the AO's images
    // transient).
    let targets = |v: FrameVariant| HybridTargets {
        gbuffer: &views,
        visibility: visibility.as_ref().filter(|_| v.gbuffer == GBufferMethod::Raster),
        ao: None,
        hdr: output.view,
        ldr: None,
        shadows: None,
        probes: None,
        lightmaps: None,
        reservoirs: None,
        taa: None,
    };
    let settings = |v: FrameVariant| HybridSettings {
        size,
        gbuffer: v.gbuffer,
        lighting: *lighting,
        ao: v.ao.settings(),
        ..HybridSettings::default()
    };
    let frame = Frame { scene, ibl: &ibl, camera };
    super::rays::warm_up(|| {
        ctx.record(|rec| {
            for &v in variants {
                passes.record_hybrid(rec, frame, &targets(v), &settings(v), None)?;
            }
            passes.record_path_samples(rec, scene, camera, &target, &path_settings, 0..1)
        })
    })?;
    let mut timers = variants.iter().map(|_| GpuTimer::new(ctx, 8)).collect::<Result<Vec<_>, _>>()?;
    let mut path_timer = GpuTimer::new(ctx, 1)?;
    // Per variant, per pass: the name and the repeats' times.
    let mut samples: Vec<Vec<(String, Vec<f64>)>> = vec![Vec::new(); variants.len()];
    let mut path_ms = Vec::new();
    for repeat in 0..=repeats {
        for (k, &v) in variants.iter().enumerate() {
            let timer = &mut timers[k];
            ctx.record(|rec| {
                timer.reset(rec.cmd());
                passes.record_hybrid(rec, frame, &targets(v), &settings(v), Some(&mut *timer))
            })?;
            let times = timer.read()?;
            if repeat == 0 {
                samples[k] = times.iter().map(|t| (t.name.clone(), Vec::new())).collect();
                continue; // warm-up
            }
            for (slot, t) in samples[k].iter_mut().zip(&times) {
                slot.1.push(t.ms);
            }
        }
        ctx.record(|rec| {
            let cmd = rec.cmd();
            path_timer.reset(cmd);
            path_timer.begin(cmd, "pathtrace 1 spp")?;
            let r = repeat as u32;
            passes.record_path_samples(rec, scene, camera, &target, &path_settings, r..r + 1)?;
            path_timer.end(cmd)
        })?;
        if repeat > 0 {
            path_ms.push(path_timer.read()?[0].ms);
        }
    }
    let frames = variants
        .iter()
        .zip(samples)
        .map(|(&variant, passes)| {
            let stages = STAGES
                .iter()
                .map(|&stage| {
                    let sums = (0..repeats)
                        .map(|r| {
                            passes
                                .iter()
                                .filter(|(name, _)| {
                                    stage == "frame" || umbra::render::stage_of(name) == Some(stage)
                                })
                                .map(|(_, ms)| ms[r])
                                .sum()
                        })
                        .collect();
                    (stage, timing(stage, sums))
                })
                .collect();
            FrameTiming {
                variant,
                passes: passes.into_iter().map(|(name, ms)| timing(&name, ms)).collect(),
                stages,
            }
        })
        .collect();
    Ok(PassesRun { frames, path: timing("pathtrace 1 spp", path_ms) })
}

/// The run as JSON (`passes.json`): the scene, the settings, the conditions
/// ([`super::add_conditions`]), per frame variant each pass's and each stage's median and fastest
/// GPU time, and one path-traced sample's.
pub fn to_json(
    device: &str,
    scene: &str,
    triangles: usize,
    size: (u32, u32),
    repeats: usize,
    shadow_rays: u32,
    run: &PassesRun,
) -> Value {
    let (frames, path) = (&run.frames, &run.path);
    let time = |t: &PassTiming| json!({"median_ms": t.median_ms, "min_ms": t.min_ms});
    let mut doc = json!({
        "device": device,
        "scene": scene,
        "triangles": triangles,
        "size": [size.0, size.1],
        "repeats": repeats,
        "shadow_rays": shadow_rays,
        "frames": frames.iter().map(|f| json!({
            "gbuffer": f.variant.gbuffer_label(),
            "ao": f.variant.ao.label(),
            "passes": f.passes.iter().map(|t| json!({"pass": t.name, "median_ms": t.median_ms, "min_ms": t.min_ms})).collect::<Vec<_>>(),
            "stages": f.stages.iter().map(|(stage, t)| (stage.to_string(), time(t))).collect::<serde_json::Map<_, _>>(),
        })).collect::<Vec<_>>(),
        "pathtrace": time(path),
    });
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of one or more runs' JSON (what BENCHMARKS.md shows): a row per pass and
/// per stage, a column per run (scene) and frame variant, median GPU milliseconds with the
/// fastest repeat in brackets. The runs must share their settings (size, repeats, shadow rays,
/// device, lavapipe threads); the load each started under is listed under the table.
pub fn table(docs: &[Value]) -> Result<String> {
    let Some(first) = docs.first() else { bail!("no passes.json given") };
    for doc in docs {
        for key in ["size", "repeats", "shadow_rays", "device", "lp_num_threads"] {
            if doc[key] != first[key] {
                bail!("the runs differ in {key} ({} and {}): print their tables apart", first[key], doc[key]);
            }
        }
        if !doc["frames"].is_array() {
            bail!("a passes.json without frames (written before the stages were): run it again");
        }
    }
    // Three significant digits (0.0790, 4.12, 15.6, 135).
    let sig3 = |x: f64| {
        let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    };
    let cell = |t: &Value| format!(" {} ({}) |", sig3(num(&t["median_ms"])), sig3(num(&t["min_ms"])));
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
    let columns: Vec<(&Value, &Value)> = docs
        .iter()
        .flat_map(|doc| doc["frames"].as_array().into_iter().flatten().map(move |f| (doc, f)))
        .collect();
    for (doc, frame) in &columns {
        out += &format!(
            " {}, {} triangles: {}, {} |",
            doc["scene"].as_str().unwrap_or("?"),
            doc["triangles"],
            gbuffer_of(frame),
            frame["ao"].as_str().unwrap_or("?")
        );
    }
    out += &format!("\n|---|{}\n", "---:|".repeat(columns.len()));
    let mut passes: Vec<&str> = Vec::new();
    for (_, frame) in &columns {
        for p in frame["passes"].as_array().into_iter().flatten() {
            let name = p["pass"].as_str().unwrap_or("?");
            if !passes.contains(&name) {
                passes.push(name);
            }
        }
    }
    for pass in passes {
        out += &format!("| {pass} |");
        for (_, frame) in &columns {
            let timing = frame["passes"].as_array().and_then(|ps| ps.iter().find(|p| p["pass"] == pass));
            out += &timing.map_or(" — |".to_string(), cell);
        }
        out += "\n";
    }
    for stage in STAGES {
        out += &format!("| **{stage}** |");
        for (_, frame) in &columns {
            out += &cell(&frame["stages"][stage]);
        }
        out += "\n";
    }
    // Each stage against the same run's frame with a ray-cast G-buffer and SSAO (the seed's):
    // what the other variants buy.
    for stage in ["gbuffer", "ao", "frame"] {
        out += &format!("| {stage} ÷ ray-cast + ssao's |");
        for (doc, frame) in &columns {
            let ssao = doc["frames"]
                .as_array()
                .into_iter()
                .flatten()
                .find(|f| f["ao"] == "ssao" && gbuffer_of(f) == "raycast");
            out += &ssao.map_or(" — |".to_string(), |ssao| {
                format!(
                    " {:.2} |",
                    num(&frame["stages"][stage]["median_ms"]) / num(&ssao["stages"][stage]["median_ms"])
                )
            });
        }
        out += "\n";
    }
    out += "| pathtrace 1 spp |";
    for (doc, _) in &columns {
        out += &cell(&doc["pathtrace"]);
    }
    out += "\n";
    let loads: Vec<String> = docs
        .iter()
        .map(|doc| format!("{}: {}", doc["scene"].as_str().unwrap_or("?"), super::load_text(doc)))
        .collect();
    out += &format!("\nConditions of each run: {}.\n", loads.join("; "));
    Ok(out)
}

/// A frame's G-buffer in passes.json (runs before the raster G-buffer had only ray-cast ones).
fn gbuffer_of(frame: &Value) -> &str {
    frame["gbuffer"].as_str().unwrap_or("raycast")
}

pub(crate) fn run_passes(
    scene: Option<PathBuf>,
    size: (u32, u32),
    repeats: usize,
    shadow_rays: u32,
    out: PathBuf,
    variants: &[FrameVariant],
) -> Result<()> {
    let ctx = Context::new(&ContextDesc::default())?;
    let loaded = match &scene {
        Some(path) => umbra::scene::Scene::load(path)?,
        None => umbra::scene::Scene::cornell_box(),
    };
    let camera = bench_camera(&loaded);
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(&ctx, &loaded)?;
    let lighting = umbra::passes::deferred::LightingSettings { shadow_rays, ..Default::default() };
    let measured = run(&ctx, &gpu_scene, &camera, size, repeats, &lighting, variants)?;
    let pixels = size.0 as f64 * size.1 as f64;
    println!(
        "{} ({} triangles) at {}x{} on {}:",
        loaded.name,
        gpu_scene.bvh_stats.triangles,
        size.0,
        size.1,
        ctx.info().name
    );
    let line = |t: &PassTiming| {
        println!(
            "  {:18} {:9.3} ms median  {:9.3} ms min  {:9.1} Mpixels/s",
            t.name,
            t.median_ms,
            t.min_ms,
            pixels / (t.median_ms * 1e3)
        )
    };
    for f in &measured.frames {
        println!(" hybrid frame, {} G-buffer, {}:", f.variant.gbuffer_label(), f.variant.ao.label());
        f.passes.iter().for_each(line);
        f.stages.iter().for_each(|(_, t)| line(t));
    }
    line(&measured.path);
    let (buffer64, image64) = ctx.info().int64_atomics;
    println!("64-bit atomics: storage buffers {buffer64}, storage images {image64}");
    let mut doc = to_json(
        &ctx.info().name,
        &loaded.name,
        gpu_scene.bvh_stats.triangles,
        size,
        repeats,
        shadow_rays,
        &measured,
    );
    doc["int64_atomics"] = json!({"buffer": buffer64, "image": image64});
    write_json(&out, "passes.json", &doc)
}
