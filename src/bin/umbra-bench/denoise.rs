//! `umbra-bench denoise`: the denoiser's error against time. Each scene is path traced in one
//! accumulation read at 1, 2, 4, … spp (the suite's path-tracing series), and each reading is
//! also denoised: two series, raw and denoised, of relative MSE against the suite's converged
//! reference (another seed) against GPU time (the samples so far, plus the filter for the
//! denoised one). Where the denoised series meets the raw one the filter's bias is the larger
//! error: past it, denoising no longer helps. The filter's own GPU time (median of repeats after
//! a warm-up) is set against one sample's (the accumulated time over the sample count).

use super::chart::{self, Chart, ChartPoint};
use super::num;
use super::rays::{median, warm_up};
use super::suite::{self, SuiteSettings};
use crate::add_conditions;
use crate::scenes::bench_camera;
use crate::scenes::load_gltf;
use crate::write_json;
use anyhow::Context as _;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::embed::Renderer;
use umbra::render::{DenoiseSettings, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::vk::ContextDesc;
use umbra::vk::{raw, Context, GpuTimer, Image};

/// One reading: the sample count, and GPU time and relative MSE of the raw and denoised images.
pub struct Reading {
    /// Samples per pixel.
    pub spp: u32,
    /// GPU time of the samples so far.
    pub raw_ms: f64,
    /// Relative MSE of the running mean.
    pub raw_rel_mse: f64,
    /// `raw_ms` plus the filter's time.
    pub denoised_ms: f64,
    /// Relative MSE of the denoised image.
    pub denoised_rel_mse: f64,
}

/// One scene's series.
pub struct SceneResult {
    /// The scene's name.
    pub name: String,
    /// The readings, by sample count.
    pub readings: Vec<Reading>,
    /// The filter's GPU time (median over repeats and readings).
    pub filter_ms: f64,
    /// One sample per pixel's GPU time (accumulated time over the sample count).
    pub sample_ms: f64,
    /// The reference's own relative MSE.
    pub reference_rel_mse_floor: f64,
}

/// Runs the two series on `scene` (named `key` in file names) with the suite's references.
pub fn run_scene(
    ctx: &Context,
    key: &str,
    scene: &Scene,
    camera: &Camera,
    s: &SuiteSettings,
    filter: &DenoiseSettings,
) -> Result<SceneResult> {
    let renderer = Renderer::new(ctx, scene)?;
    let (reference, floor) = suite::reference_for(&renderer, camera, key, s)?;
    let measured =
        PathSettings { size: s.size, spp: s.max_spp, seed: 1, env: s.env, ..PathSettings::default() };
    let target = if filter.lobe_split {
        renderer.denoised_path_target(s.size)?
    } else {
        renderer.path_target(s.size)?
    };
    let images = renderer.denoise_images(s.size)?;
    let make = |name| Image::storage_2d(ctx, name, s.size.0, s.size.1, raw::Format::R32G32B32A32_SFLOAT);
    let (resolved, denoised) = (make("bench resolve")?, make("bench denoised")?);
    ctx.submit(|cmd| {
        images.init_general(ctx, cmd);
        resolved.init_general(ctx, cmd);
        denoised.init_general(ctx, cmd);
        Ok(())
    })?;
    warm_up(|| ctx.submit(|cmd| renderer.record_path_samples(cmd, camera, &target, &measured, 0, 1)))?;
    warm_up(|| ctx.submit(|cmd| renderer.record_path_denoise(cmd, &target, &images, denoised.view, filter)))?;
    let mut timer = GpuTimer::new(ctx, 1)?;
    let (mut done, mut elapsed_ms) = (0u32, 0.0);
    let mut readings = Vec::new();
    let mut filter_times = Vec::new();
    let bar = super::progress_bar(s.max_spp as u64, &format!("{key}: path tracing"));
    let mut level = 1;
    while level <= s.max_spp {
        elapsed_ms += suite::trace_until(
            ctx, &renderer, camera, &target, &measured, &mut timer, &mut done, level, &bar,
        )?;
        ctx.submit(|cmd| renderer.record_path_resolve(cmd, &target, resolved.view))?;
        let (_, raw_rel_mse) = suite::errors(&resolved.read(ctx)?, &reference);
        let mut times = Vec::new();
        for _ in 0..s.repeats.max(1) {
            ctx.submit(|cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "denoise")?;
                renderer.record_path_denoise(cmd, &target, &images, denoised.view, filter)?;
                timer.end(cmd)
            })?;
            times.push(timer.read()?.iter().map(|t| t.ms).sum::<f64>());
        }
        let filter_ms = median(&mut times);
        filter_times.push(filter_ms);
        let (_, denoised_rel_mse) = suite::errors(&denoised.read(ctx)?, &reference);
        readings.push(Reading {
            spp: level,
            raw_ms: elapsed_ms,
            raw_rel_mse,
            denoised_ms: elapsed_ms + filter_ms,
            denoised_rel_mse,
        });
        level *= 2;
    }
    bar.finish_and_clear();
    let name = scene.name.clone();
    let title = format!("{name}, denoised and raw — {}×{} on {}", s.size.0, s.size.1, ctx.info().name);
    let mut points = Vec::new();
    for r in &readings {
        points.push(ChartPoint {
            method: "path tracing",
            unit: "spp",
            value: r.spp,
            ms: r.raw_ms,
            error: r.raw_rel_mse,
        });
        points.push(ChartPoint {
            method: "path tracing + denoiser",
            unit: "spp",
            value: r.spp,
            ms: r.denoised_ms,
            error: r.denoised_rel_mse,
        });
    }
    let chart = Chart { title: &title, y_desc: "relative MSE vs converged path tracing (log)", floor };
    chart::write(&s.out.join(format!("denoise-{key}")), &chart, &points)?;
    Ok(SceneResult {
        name,
        sample_ms: elapsed_ms / done.max(1) as f64,
        filter_ms: median(&mut filter_times),
        readings,
        reference_rel_mse_floor: floor,
    })
}

/// The JSON of a run.
pub fn to_json(device: &str, s: &SuiteSettings, filter: &DenoiseSettings, results: &[SceneResult]) -> Value {
    json!({
        "device": device,
        "size": [s.size.0, s.size.1],
        "reference_spp": s.reference_spp,
        "repeats": s.repeats,
        "iterations": filter.iterations,
        "sigma_luminance": filter.sigma_luminance,
        "prefilter_variance": filter.prefilter_variance,
        "spatial_variance": filter.spatial_variance,
        "wide": filter.wide,
        "albedo_offset": filter.albedo_offset,
        "lobe_split": filter.lobe_split,
        "specular_iterations": filter.specular_iterations,
        "scenes": results.iter().map(|r| json!({
            "scene": r.name,
            "reference_rel_mse_floor": r.reference_rel_mse_floor,
            "filter_ms": r.filter_ms,
            "sample_ms": r.sample_ms,
            "readings": r.readings.iter().map(|p| json!({
                "spp": p.spp,
                "raw_ms": p.raw_ms,
                "raw_rel_mse": p.raw_rel_mse,
                "denoised_ms": p.denoised_ms,
                "denoised_rel_mse": p.denoised_rel_mse,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// Two significant digits (three below 0.01), as the suite's tables print errors.
fn short(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}")
    } else if x >= 1.0 {
        format!("{x:.1}")
    } else if x >= 0.01 {
        format!("{x:.2}")
    } else {
        format!("{x:.1e}")
    }
}

/// The Markdown table of a run: per scene the filter's time against one sample's, relative MSE
/// raw → denoised (and the factor) at 1, 4, 16, 64 and 256 spp, and where denoising stops
/// helping.
pub fn table(doc: &Value) -> String {
    let columns = [1u64, 4, 16, 64, 256];
    let mut out = format!(
        "{}×{}, {}-spp references, {}, {} à-trous iterations{} ({}); relative MSE raw → denoised (÷):\n\n\
         | scene | filter | one sample | {} | denoising stops helping |\n|---|---:|---:|{}---|\n",
        doc["size"][0],
        doc["size"][1],
        doc["reference_spp"],
        doc["device"].as_str().unwrap_or("?"),
        doc["iterations"],
        match doc["lobe_split"].as_bool() {
            Some(true) =>
                format!(", the lobe split with {} on the specular part", doc["specular_iterations"]),
            Some(false) => ", no lobe split".to_string(),
            None => String::new(),
        },
        super::conditions_text(doc),
        columns.map(|c| format!("{c} spp")).join(" | "),
        "---|".repeat(columns.len()),
    );
    for scene in doc["scenes"].as_array().cloned().unwrap_or_default() {
        let readings = scene["readings"].as_array().cloned().unwrap_or_default();
        let cell = |spp: u64| {
            readings.iter().find(|r| r["spp"].as_u64() == Some(spp)).map_or("—".to_string(), |r| {
                let (raw, den) = (num(&r["raw_rel_mse"]), num(&r["denoised_rel_mse"]));
                format!("{} → {} ({:.1}×)", short(raw), short(den), raw / den)
            })
        };
        let stops = readings
            .iter()
            .find(|r| num(&r["denoised_rel_mse"]) >= num(&r["raw_rel_mse"]))
            .map_or("beyond the last reading".to_string(), |r| format!("at {} spp", r["spp"]));
        out += &format!(
            "| {} | {:.2} ms | {:.2} ms | {} | {stops} |\n",
            scene["scene"].as_str().unwrap_or("?"),
            num(&scene["filter_ms"]),
            num(&scene["sample_ms"]),
            columns.map(cell).join(" | "),
        );
    }
    let floors: Vec<String> = doc["scenes"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .map(|scene| {
            format!(
                "{} {:.1e}",
                scene["scene"].as_str().unwrap_or("?"),
                num(&scene["reference_rel_mse_floor"])
            )
        })
        .collect();
    out += &format!("\nThe references' own noise (relative MSE): {}.\n", floors.join(", "));
    out
}

pub(crate) fn run_denoise(
    settings: &suite::SuiteSettings,
    filter: &umbra::render::DenoiseSettings,
    quick: bool,
    gltf: &[PathBuf],
) -> Result<()> {
    let ctx = Context::new(&ContextDesc::default())?;
    umbra::atomic::create_dir(&settings.out)?;
    let mut scenes = vec![("cornell".to_string(), umbra::scene::Scene::cornell_box())];
    if !quick {
        for name in ["spheres", "textured"] {
            let path = PathBuf::from("scenes").join(format!("{name}.glb"));
            match umbra::scene::Scene::load(&path) {
                Ok(scene) => scenes.push((name.to_string(), scene)),
                Err(e) => log::warn!("skipping {}: {e} (run from the repository root)", path.display()),
            }
        }
    }
    scenes.extend(load_gltf(gltf)?);
    let mut results = Vec::new();
    for (key, scene) in &scenes {
        let camera = bench_camera(scene);
        results.push(
            run_scene(&ctx, key, scene, &camera, settings, filter).with_context(|| scene.name.clone())?,
        );
    }
    let mut doc = to_json(&ctx.info().name, settings, filter, &results);
    add_conditions(&mut doc);
    print!("{}", table(&doc));
    write_json(&settings.out, "denoise.json", &doc)
}
