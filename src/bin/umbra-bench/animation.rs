//! `umbra-bench animation`: how an animated scene's BVH follows its pose frame by frame, refit
//! against rebuild ([`umbra::gpu::scene::BvhUpdate`]), for each kind of motion in
//! `scenes/animated.glb` playing alone (a skin, a rigid node, a morph target) and all at once.
//! Each frame of the 2-second loop is posed ([`umbra::scene::Scene::pose`]), taken by
//! [`umbra::embed::Renderer::update_geometry`] and path-traced at a fixed sample count: the BVH's
//! own time (the refit or the build, on the CPU), the whole update (BVH, layout, upload; the
//! kernels re-made where a deeper walk needs them), the tree's SAH cost and the frame's GPU time,
//! whose walk pays for a loosened tree. Medians over the loop's frames, after a warm-up frame.

use super::rays::median;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::Path;
use umbra::embed::Renderer;
use umbra::gpu::scene::BvhUpdate;
use umbra::render::PathSettings;
use umbra::scene::{AnimationSelect, PoseAt, Scene};
use umbra::vk::Context;

/// What a run measures.
pub struct AnimationBench {
    /// Image size of the path-traced frames.
    pub size: (u32, u32),
    /// Samples per pixel of each frame.
    pub spp: u32,
    /// Frames over the loop (its duration split evenly; the first at the first step, not 0).
    pub frames: u32,
    /// Path traces of each frame; the fastest is kept (the device's timing noise, ±10 % on
    /// lavapipe, is as large as the trees' differences).
    pub repeats: usize,
}

/// The motions measured: a name and the animation that plays (`None`: all).
const MOTIONS: [(&str, Option<&str>); 4] = [
    ("skin", Some("bend")),
    ("rigid node", Some("turn")),
    ("morph target", Some("squash")),
    ("all three", None),
];

/// Runs every motion with both BVH updates on the animated scene at `path`.
pub fn run(ctx: &Context, path: &Path, s: &AnimationBench) -> Result<Value> {
    let rest = Scene::load(path)?;
    let duration = 2.0f32;
    let mut points = Vec::new();
    for (motion, animation) in MOTIONS {
        for how in [BvhUpdate::Refit, BvhUpdate::Rebuild] {
            let mut scene = rest.clone();
            let camera = scene.camera(None)?;
            let mut renderer = Renderer::new(ctx, &scene)?;
            let settings = PathSettings { size: s.size, spp: s.spp, seed: 7, ..PathSettings::default() };
            // Warm-up: the path tracer's kernels made, caches filled.
            renderer.passes().path_trace(renderer.scene(), &camera, &settings, |_, _| {})?;
            let rest_sah = renderer.scene().bvh_stats.sah_cost as f64;
            let (mut bvh, mut update, mut sah, mut trace) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for f in 1..=s.frames {
                let time = duration * f as f32 / (s.frames + 1) as f32;
                let animations = animation.map_or(AnimationSelect::All, |a| AnimationSelect::Name(a.into()));
                scene.pose(&PoseAt { time, animations })?;
                let clock = std::time::Instant::now();
                renderer.update_geometry(&scene, how)?;
                update.push(clock.elapsed().as_secs_f64() * 1e3);
                bvh.push(renderer.scene().bvh_stats.build_ms);
                sah.push(renderer.scene().bvh_stats.sah_cost as f64);
                trace.push(
                    renderer.passes().path_trace(renderer.scene(), &camera, &settings, |_, _| {})?.gpu_ms,
                );
            }
            points.push(json!({
                "motion": motion,
                "animation": animation,
                "bvh": format!("{how:?}").to_lowercase(),
                "bvh_ms": median(&mut bvh),
                "update_ms": median(&mut update),
                "rest_sah": rest_sah,
                "sah": median(&mut sah),
                "max_sah": sah.iter().copied().fold(0.0, f64::max),
                "trace_ms": median(&mut trace),
            }));
        }
    }
    Ok(json!({
        "bench": "animation",
        "device": ctx.info().name,
        "scene": rest.name,
        "triangles": rest.triangles.len(),
        "size": [s.size.0, s.size.1],
        "spp": s.spp,
        "frames": s.frames,
        "repeats": s.repeats,
        "points": points,
    }))
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// The Markdown of a run's JSON ([`run`]).
pub fn table(doc: &Value) -> String {
    let points = doc["points"].as_array().cloned().unwrap_or_default();
    let mut out = format!(
        "{} ({} triangles) on {}: {} frames over the 2 s loop, each path-traced at {} spp (the fastest of {}), {}x{}, {}; medians over the frames:\n\n",
        doc["scene"].as_str().unwrap_or("?"),
        doc["triangles"],
        doc["device"].as_str().unwrap_or("?"),
        doc["frames"],
        doc["spp"],
        doc["repeats"],
        doc["size"][0],
        doc["size"][1],
        super::conditions_text(doc),
    );
    out += "| motion | BVH | BVH ms | update ms | SAH (at rest) | path trace GPU ms | update + trace ms | ÷ rebuild's |\n";
    out += "|---|---|---:|---:|---:|---:|---:|---:|\n";
    for p in &points {
        let total = |q: &Value| num(&q["update_ms"]) + num(&q["trace_ms"]);
        let rebuild = points.iter().find(|q| q["motion"] == p["motion"] && q["bvh"] == "rebuild");
        out += &format!(
            "| {} | {} | {:.2} | {:.2} | {:.2} ({:.2}) | {:.1} | {:.1} | {:.3} |\n",
            p["motion"].as_str().unwrap_or("?"),
            p["bvh"].as_str().unwrap_or("?"),
            num(&p["bvh_ms"]),
            num(&p["update_ms"]),
            num(&p["sah"]),
            num(&p["rest_sah"]),
            num(&p["trace_ms"]),
            total(p),
            rebuild.map_or(f64::NAN, |r| total(p) / total(r)),
        );
    }
    out
}
