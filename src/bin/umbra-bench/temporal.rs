//! `umbra-bench temporal`: the denoiser's temporal accumulation ([`umbra::passes::temporal`])
//! on a camera path, through the embedding API: the Cornell box, a slow pan (the camera turned
//! by a fraction of a pixel a frame), one sample per pixel a frame. Per frame the relative MSE
//! against a converged reference of that frame's camera, for the raw sample, the spatial filter
//! alone and the temporal denoiser (the accumulated colour fed back, and SVGF's first-iteration
//! feedback); then the filter's GPU time with and without the temporal step (medians of
//! alternating repeats after a warm-up).

use super::rays::{median, warm_up};
use super::suite;
use anyhow::Result;
use serde_json::{json, Value};
use umbra::embed::Renderer;
use umbra::passes::temporal::{TemporalFeedback, TemporalSettings};
use umbra::render::{path_trace, DenoiseSettings, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::vk::{raw, Context, GpuTimer, Image};

/// `base` turned about its up axis by `angle` radians.
fn turned(base: &Camera, angle: f32) -> Camera {
    let up = glam::Vec3::from(base.up).normalize();
    let forward = glam::Quat::from_axis_angle(up, angle) * glam::Vec3::from(base.forward);
    Camera { forward: forward.into(), ..*base }
}

/// Runs the camera path: the per-frame errors (unless `timing_only`) and the timings, as JSON
/// ([`table`] prints it).
pub fn run(
    size: (u32, u32),
    frames: u32,
    pan_pixels: f32,
    reference_spp: u32,
    repeats: usize,
    timing_only: bool,
    dump: Option<&std::path::Path>,
) -> Result<Value> {
    let ctx = Context::new(&umbra::vk::ContextDesc::default())?;
    let scene = Scene::cornell_box();
    let base = scene.camera(None)?;
    let renderer = Renderer::new(&ctx, &scene)?;
    // The angle of a pixel at the image's centre.
    let pixel_angle = 2.0 * (base.yfov * 0.5).tan() / size.1 as f32;
    let cameras: Vec<Camera> =
        (0..frames).map(|k| turned(&base, -(k as f32) * pan_pixels * pixel_angle)).collect();

    let target = renderer.denoised_path_target(size)?;
    let images = renderer.denoise_images(size)?;
    let mut accumulated = renderer.temporal_history(size, TemporalSettings::default())?;
    let first = TemporalSettings { feedback: TemporalFeedback::FirstIteration, ..Default::default() };
    let mut svgf = renderer.temporal_history(size, first)?;
    let make = |name| Image::storage_2d(&ctx, name, size.0, size.1, raw::Format::R32G32B32A32_SFLOAT);
    let (raw_image, output) = (make("bench raw")?, make("bench denoised")?);
    ctx.submit(|cmd| {
        images.init_general(&ctx, cmd);
        accumulated.init_general(&ctx, cmd);
        svgf.init_general(&ctx, cmd);
        raw_image.init_general(&ctx, cmd);
        output.init_general(&ctx, cmd);
        Ok(())
    })?;
    let filter = DenoiseSettings::default();
    let settings = |k: u32| PathSettings {
        size,
        spp: 1,
        seed: 1,
        first_sample: k,
        lobe_split: true,
        ..Default::default()
    };

    let mut rows = Vec::new();
    if !timing_only {
        for (k, camera) in cameras.iter().enumerate() {
            let reference_settings =
                PathSettings { size, spp: reference_spp, seed: 1000 + k as u32, ..Default::default() };
            let reference = path_trace(&ctx, renderer.scene(), camera, &reference_settings, |_, _| {})?;
            let floor = reference.relative_error() as f64;
            let k = k as u32;
            let mut errors = [0.0f64; 4];
            // Each estimate of the frame, for --dump.
            let mut frames: Vec<(&str, Vec<[f32; 4]>)> = vec![("reference", reference.mean.clone())];
            let mut score = |name: &'static str, image: Vec<[f32; 4]>| {
                let error = suite::errors(&image, &reference.mean).1;
                frames.push((name, image));
                error
            };
            ctx.submit(|cmd| {
                renderer.record_path_samples(cmd, camera, &target, &settings(k), 0, 1)?;
                renderer.record_path_resolve(cmd, &target, raw_image.view)
            })?;
            errors[0] = score("raw", raw_image.read(&ctx)?);
            ctx.submit(|cmd| renderer.record_path_denoise(cmd, &target, &images, output.view, &filter))?;
            errors[1] = score("spatial", output.read(&ctx)?);
            for (i, history) in [&mut accumulated, &mut svgf].into_iter().enumerate() {
                ctx.submit(|cmd| {
                    renderer.record_path_denoise_temporal(
                        cmd,
                        camera,
                        &target,
                        &images,
                        history,
                        output.view,
                        &filter,
                    )
                })?;
                errors[2 + i] = score(["temporal", "temporal_first_iteration"][i], output.read(&ctx)?);
            }
            if let Some(dir) = dump {
                umbra::atomic::create_dir(dir)?;
                let data: Vec<Vec<f32>> = frames
                    .iter()
                    .map(|(_, image)| image.iter().flat_map(|p| p[..3].to_vec()).collect())
                    .collect();
                let layers: Vec<umbra::output::Layer<'_>> = frames
                    .iter()
                    .zip(&data)
                    .map(|((name, _), data)| umbra::output::Layer { name, channels: &["R", "G", "B"], data })
                    .collect();
                let path = dir.join(format!("frame{:02}.exr", k + 1));
                umbra::output::write_exr(&path, size.0 as usize, size.1 as usize, &layers)?;
            }
            rows.push(json!({
                "frame": k + 1,
                "raw": errors[0],
                "spatial": errors[1],
                "temporal": errors[2],
                "temporal_first_iteration": errors[3],
                "reference_rel_mse": floor * floor,
            }));
        }
    } else {
        ctx.submit(|cmd| renderer.record_path_samples(cmd, &cameras[0], &target, &settings(0), 0, 1))?;
    }

    // Timing: the filter alone, spatial and temporal alternating, on the last frame's samples.
    let camera = cameras.last().expect("at least one frame");
    let record_spatial = |cmd| renderer.record_path_denoise(cmd, &target, &images, output.view, &filter);
    let mut record_temporal = |cmd| {
        renderer.record_path_denoise_temporal(
            cmd,
            camera,
            &target,
            &images,
            &mut accumulated,
            output.view,
            &filter,
        )
    };
    warm_up(|| ctx.submit(record_spatial))?;
    warm_up(|| ctx.submit(&mut record_temporal))?;
    let mut timer = GpuTimer::new(&ctx, 1)?;
    let (mut spatial, mut temporal) = (Vec::new(), Vec::new());
    for _ in 0..repeats.max(1) {
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "spatial")?;
            record_spatial(cmd)?;
            timer.end(cmd)
        })?;
        spatial.push(timer.read()?.iter().map(|t| t.ms).sum::<f64>());
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "temporal")?;
            record_temporal(cmd)?;
            timer.end(cmd)
        })?;
        temporal.push(timer.read()?.iter().map(|t| t.ms).sum::<f64>());
    }
    let mut one_sample = Vec::new();
    for _ in 0..repeats.max(1) {
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "sample")?;
            renderer.record_path_samples(cmd, camera, &target, &settings(0), 0, 1)?;
            timer.end(cmd)
        })?;
        one_sample.push(timer.read()?.iter().map(|t| t.ms).sum::<f64>());
    }
    let (s, t, o) = (median(&mut spatial), median(&mut temporal), median(&mut one_sample));
    Ok(json!({
        "device": ctx.info().name,
        "size": [size.0, size.1],
        "frames": frames,
        "pan_pixels": pan_pixels,
        "reference_spp": reference_spp,
        "repeats": repeats.max(1),
        "rows": rows,
        "filter_spatial_ms": s,
        "filter_temporal_ms": t,
        "one_sample_ms": o,
    }))
}

/// The Markdown of a run's JSON ([`run`]): the per-frame errors (and their means), then the
/// timings.
pub fn table(doc: &Value) -> String {
    let num = |v: &Value| v.as_f64().unwrap_or(f64::NAN);
    let mut out = String::new();
    let rows = doc["rows"].as_array().cloned().unwrap_or_default();
    let columns = ["raw", "spatial", "temporal", "temporal_first_iteration"];
    if !rows.is_empty() {
        out += "| frame | raw 1 spp | spatial only | temporal (accumulated fed back) | temporal (first iteration fed back) | reference's own |\n";
        out += "|---:|---:|---:|---:|---:|---:|\n";
        for row in &rows {
            let e: Vec<String> = columns.iter().map(|c| format!("{:.2e}", num(&row[*c]))).collect();
            out += &format!(
                "| {} | {} | {:.1e} |\n",
                row["frame"],
                e.join(" | "),
                num(&row["reference_rel_mse"])
            );
        }
        let n = rows.len() as f64;
        let means: Vec<String> = columns
            .iter()
            .map(|c| format!("{:.2e}", rows.iter().map(|r| num(&r[*c])).sum::<f64>() / n))
            .collect();
        out += &format!("| mean | {} | |\n", means.join(" | "));
    }
    let (s, t) = (num(&doc["filter_spatial_ms"]), num(&doc["filter_temporal_ms"]));
    out += &format!(
        "\n{}x{}, the camera turned {} pixels a frame, on {}: filter {s:.2} ms spatial, {t:.2} ms temporal (+{:.2} ms, \
         {:.2}x); one sample {:.2} ms (medians of {})\n",
        doc["size"][0],
        doc["size"][1],
        doc["pan_pixels"],
        doc["device"].as_str().unwrap_or("?"),
        t - s,
        t / s,
        num(&doc["one_sample_ms"]),
        doc["repeats"]
    );
    out
}
