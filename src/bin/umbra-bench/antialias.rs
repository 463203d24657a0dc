//! `umbra-bench antialias`: the hybrid frame's anti-aliasing against a converged path-traced
//! reference, mean LDR-FLIP against GPU time: one-shot supersampling at a sweep of sub-frame
//! counts ([`umbra::render::HybridSettings::samples`]; the time is every sub-frame's, medians of
//! repeats after a warm-up), and temporal anti-aliasing through the embedding API
//! ([`umbra::render::HybridTargets::taa`]) on a still camera, read after each frame (the time is
//! the frames' so far), and on a camera turning into the reference's view, read after the last
//! frame of runs of 1, 2, 4, … frames, with each history filter ([`HistoryFilter`]); for an
//! animated scene also while its geometry moves (the camera still), read likewise. Every hybrid is the default one (raster G-buffer, SSAO, 4 shadow rays,
//! split-sum IBL). The reference's pixels integrate their area (a box filter), what both
//! anti-aliasing methods converge toward.

use std::path::{Path, PathBuf};

use super::chart::{self, Chart, ChartPoint};
use super::rays::median;
use super::suite;
use anyhow::Result;
use serde_json::{json, Value};
use umbra::embed::Renderer;
use umbra::gpu::scene::BvhUpdate;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::GBuffer;
use umbra::passes::taa::{HistoryFilter, TaaHistory, TaaSettings};
use umbra::render::{HybridSettings, HybridTargets, PathSettings};
use umbra::scene::{AnimationSelect, Camera, PoseAt, Scene};
use umbra::vk::{raw, Context, GpuTimer, Image};

/// How far the turning camera of the TAA series turns each frame, in pixels at the image's
/// centre (tests/antialias.rs' turning view).
const TURN_PX: f32 = 0.3;

/// What a run measures.
pub struct AntialiasBench {
    /// Image size.
    pub size: (u32, u32),
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    /// Sub-frame counts of the supersampled series.
    pub samples: Vec<u32>,
    /// Frames of the TAA series.
    pub taa_frames: u32,
    /// Timed repeats of each supersampled render (after a warm-up).
    pub repeats: usize,
    /// Environment radiance: a map's multiplier, or a constant sky.
    pub env: [f32; 3],
}

/// The animated scenes' pose: the still series and the reference at this time (seconds), and
/// the moving-geometry series' runs end at it.
pub const ANIMATION_END: f32 = 1.0;

/// The moving-geometry series' time step (seconds a frame).
const ANIMATION_STEP: f32 = 1.0 / 30.0;

/// Runs the series on `scene` (its environment map, if any, already set on `renderer`'s scene;
/// an animated scene posed at [`ANIMATION_END`], which the moving-geometry series leaves it at).
pub fn run(ctx: &Context, renderer: &mut Renderer, scene: &mut Scene, s: &AntialiasBench) -> Result<Value> {
    let camera = scene.camera(None)?;
    let size = s.size;
    let reference_settings =
        PathSettings { size, spp: s.reference_spp, seed: 0x5eed, env: s.env, ..PathSettings::default() };
    let reference =
        renderer.passes().path_trace(renderer.scene(), &camera, &reference_settings, |_, _| {})?;
    let floor = reference.relative_error() as f64;
    let reference = reference.mean;
    let settings = |samples: u32| HybridSettings {
        size,
        samples,
        lighting: LightingSettings {
            shadow_rays: 4,
            seed: 1,
            env: s.env,
            ibl: true,
            ..LightingSettings::default()
        },
        ao: Some(AoSettings::default()),
        ..HybridSettings::default()
    };

    let mut points = Vec::new();
    for &n in &s.samples {
        let (ms, image) = suite::timed(
            s.repeats,
            || renderer.passes().hybrid(renderer.scene(), &camera, &settings(n)),
            suite::frame_ms,
        )?;
        let (_, rel_mse) = suite::errors(&image.color, &reference);
        let flip = suite::flip_mean(&image.color, &reference, size);
        points.push(json!({"method": "supersampled", "unit": "sub-frames", "value": n, "ms": ms, "flip": flip, "rel_mse": rel_mse}));
    }

    // TAA: the embedding API's frames, each timed; the error of the resolve after each.
    let gbuffer = GBuffer::new(ctx, size)?;
    let views = gbuffer.views();
    let hdr = Image::storage_2d(ctx, "bench hdr", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
    let history = renderer.taa_history(size, TaaSettings::default())?;
    let bilinear = renderer
        .taa_history(size, TaaSettings { history: HistoryFilter::Bilinear, ..TaaSettings::default() })?;
    let frame_settings = settings(1);
    let mut visibility = renderer.visibility_buffer(size, frame_settings.gbuffer)?;
    ctx.submit(|cmd| {
        hdr.init_general(ctx, cmd);
        history.init_general(ctx, cmd);
        bilinear.init_general(ctx, cmd);
        Ok(())
    })?;
    let mut timer = GpuTimer::new(ctx, 16)?;
    let mut record = |renderer: &Renderer,
                      history: &TaaHistory,
                      camera: &Camera,
                      timed: bool,
                      visibility: Option<&umbra::render::VisibilityBuffer>|
     -> Result<f64> {
        let targets = HybridTargets {
            gbuffer: &views,
            visibility,
            ao: None,
            hdr: hdr.view,
            ldr: None,
            shadows: None,
            probes: None,
            lightmaps: None,
            reservoirs: None,
            taa: Some(history),
        };
        ctx.submit(|cmd| {
            timer.reset(cmd);
            renderer.record_hybrid(cmd, camera, &targets, &frame_settings, timed.then_some(&mut timer))
        })?;
        Ok(timer.read()?.iter().map(|t| t.ms).sum())
    };
    // A warm-up frame (which also grows the visibility buffer's tile lists to the view), then
    // the measured run from a fresh history.
    for _ in 0..3 {
        record(renderer, &history, &camera, false, visibility.as_ref())?;
        match visibility.as_mut().map(|v| v.check(ctx)).transpose()?.flatten() {
            Some(entries) => visibility.as_mut().expect("checked").reserve(ctx, entries)?,
            None => break,
        }
    }
    // A TAA series' point: `history`'s resolve after `k` frames that took `ms`, against the
    // reference.
    let taa_point = |method: &str, history: &TaaHistory, k: u32, ms: f64| -> Result<Value> {
        let resolved: Vec<[f32; 4]> = history.read(ctx)?;
        let (_, rel_mse) = suite::errors(&resolved, &reference);
        let flip = suite::flip_mean(&resolved, &reference, size);
        Ok(
            json!({"method": method, "unit": "frames", "value": k, "ms": ms, "flip": flip, "rel_mse": rel_mse}),
        )
    };
    history.reset();
    let (mut total, mut frame_ms) = (0.0, Vec::new());
    for k in 1..=s.taa_frames {
        let ms = record(renderer, &history, &camera, true, visibility.as_ref())?;
        total += ms;
        frame_ms.push(ms);
        points.push(taa_point("TAA, still camera", &history, k, total)?);
    }
    // The runs' lengths of the series below: 1, 2, 4, … up to the still series' length.
    let runs: Vec<u32> = (0..).map(|i| 1u32 << i).take_while(|&k| k <= s.taa_frames.max(1)).collect();

    // TAA while the camera turns about the vertical by TURN_PX pixels a frame: k frames that end
    // at the reference's camera (k in `runs`), each run from a fresh history, with each history
    // filter; the error of the last resolve.
    if camera.orthographic.is_none() {
        let pixel = 2.0 * (camera.yfov / 2.0).tan() / size.1 as f32;
        for (method, history) in
            [("TAA, turning camera", &history), ("TAA, turning camera, bilinear history", &bilinear)]
        {
            for &k in &runs {
                history.reset();
                let mut total = 0.0;
                for j in 0..k {
                    let turn = glam::Quat::from_rotation_y(-((k - 1 - j) as f32) * TURN_PX * pixel);
                    let cam = Camera {
                        forward: (turn * glam::Vec3::from(camera.forward)).to_array(),
                        up: (turn * glam::Vec3::from(camera.up)).to_array(),
                        ..camera
                    };
                    total += record(renderer, history, &cam, true, visibility.as_ref())?;
                }
                points.push(taa_point(method, history, k, total)?);
            }
        }
    }

    // TAA while an animated scene's geometry moves (every animation, ANIMATION_STEP a frame,
    // each frame posed and refitted: `Renderer::update_geometry`), the camera still: k frames
    // (k in `runs`) that end at the reference's pose, each run from a fresh history; the time is
    // the frames' GPU passes (the poses and refits are the host's, not timed here).
    if scene.animation.is_some() {
        for &k in &runs {
            history.reset();
            let mut total = 0.0;
            for j in 0..k {
                let time = ANIMATION_END - (k - 1 - j) as f32 * ANIMATION_STEP;
                scene.pose(&PoseAt { time, animations: AnimationSelect::All })?;
                renderer.update_geometry(scene, BvhUpdate::Refit)?;
                total += record(renderer, &history, &camera, true, visibility.as_ref())?;
            }
            points.push(taa_point("TAA, moving geometry", &history, k, total)?);
        }
    }
    Ok(json!({
        "device": ctx.info().name,
        "scene": scene.name,
        "size": [size.0, size.1],
        "reference_spp": s.reference_spp,
        "reference_rel_mse_floor": floor * floor,
        "repeats": s.repeats.max(1),
        "taa_frame_ms": median(&mut frame_ms),
        "points": points,
    }))
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// The scene's file name (the JSON keeps the path it was loaded from).
fn scene_name(doc: &Value) -> String {
    let path = doc["scene"].as_str().unwrap_or("?");
    Path::new(path).file_name().map_or(path.to_owned(), |n| n.to_string_lossy().into_owned())
}

/// The Markdown of a run's JSON ([`run`]).
pub fn table(doc: &Value) -> String {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let one = points.iter().find(|p| p["method"] == "supersampled" && p["value"] == 1);
    let (one_ms, one_flip) = one.map_or((f64::NAN, f64::NAN), |p| (num(&p["ms"]), num(&p["flip"])));
    let mut out = format!(
        "{} at {}x{} on {}, against the path tracer at {} spp (mean LDR-FLIP; relative MSE); time ÷ the one-sample frame's {one_ms:.1} ms:\n\n",
        scene_name(doc),
        doc["size"][0],
        doc["size"][1],
        doc["device"].as_str().unwrap_or("?"),
        doc["reference_spp"]
    );
    out += "| method | setting | GPU ms | ÷ one sample | FLIP | ÷ one sample's | relative MSE |\n";
    out += "|---|---:|---:|---:|---:|---:|---:|\n";
    for p in &points {
        // TAA: frames 1, 2, 4, 8, ... and the last.
        let k = p["value"].as_u64().unwrap_or(0);
        let last =
            p["method"] != "supersampled" && points.iter().rfind(|q| q["method"] == p["method"]) == Some(p);
        if p["method"] != "supersampled" && !k.is_power_of_two() && !last {
            continue;
        }
        out += &format!(
            "| {} | {} {} | {:.1} | {:.2} | {:.4} | {:.2} | {:.2e} |\n",
            p["method"].as_str().unwrap_or("?"),
            k,
            p["unit"].as_str().unwrap_or("?"),
            num(&p["ms"]),
            num(&p["ms"]) / one_ms,
            num(&p["flip"]),
            num(&p["flip"]) / one_flip,
            num(&p["rel_mse"]),
        );
    }
    out += &format!(
        "\nTAA: {:.1} ms a frame (median); the reference's own relative MSE {:.1e}.\n",
        num(&doc["taa_frame_ms"]),
        num(&doc["reference_rel_mse_floor"])
    );
    out
}

/// The FLIP-against-time chart of a run, `<out>/antialias-<stem>.svg` and `.png`.
pub fn write_chart(out: &Path, stem: &str, doc: &Value) -> Result<PathBuf> {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let chart_points: Vec<ChartPoint> = points
        .iter()
        .map(|p| ChartPoint {
            method: p["method"].as_str().unwrap_or("?"),
            unit: p["unit"].as_str().unwrap_or("?"),
            value: p["value"].as_u64().unwrap_or(0) as u32,
            ms: num(&p["ms"]),
            error: num(&p["flip"]),
        })
        .collect();
    let title = format!(
        "{}: anti-aliasing of the hybrid frame — {}",
        scene_name(doc),
        doc["device"].as_str().unwrap_or("?")
    );
    let chart = Chart { title: &title, y_desc: "mean LDR-FLIP against the path tracer (log)", floor: 0.0 };
    let path = out.join(format!("antialias-{stem}"));
    chart::write(&path, &chart, &chart_points)?;
    Ok(path)
}
