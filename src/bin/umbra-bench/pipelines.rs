//! What making a scene's pipelines costs (`umbra-bench pipelines`): the wall time of
//! `vkCreateComputePipelines` for the path tracer's two integrators and the hybrid's two big
//! kernels, specialised on each scene's features, with the host folding their constants
//! (`umbra::vk::specialize`, the default) and without (the module as glslang compiled it).
//! On lavapipe this is what a short render or a test waits for before its first sample.

use super::num;
use anyhow::Result;
use serde_json::{json, Value};
use umbra::gpu::kernel::Kernel;
use umbra::gpu::kernels::{deferred, gbuffer, pathtrace, wavefront};
use umbra::gpu::scene::GpuScene;
use umbra::gpu::Pipeline;
use umbra::passes::wavefront::stage_specs;
use umbra::scene::Scene;
use umbra::vk::specialize::set_folding;
use umbra::vk::Context;

/// One kernel on one scene.
pub struct PipelineRow {
    /// The scene's file name.
    pub scene: String,
    /// The kernel.
    pub kernel: &'static str,
    /// Median milliseconds to make the pipeline with the constants folded.
    pub folded_ms: f64,
    /// Milliseconds to make it from the module as compiled (one run: it takes seconds).
    pub unfolded_ms: f64,
}

/// Milliseconds to make `K`'s pipelines of `specs` for `scene`, one after another.
fn time_specs<K: Kernel>(ctx: &Context, scene: &GpuScene, specs: &[K::Spec]) -> Result<f64> {
    let clock = std::time::Instant::now();
    let pipelines: Result<Vec<_>> =
        specs.iter().map(|spec| Ok(Pipeline::<K>::for_scene(ctx, scene, spec)?)).collect();
    let ms = clock.elapsed().as_secs_f64() * 1e3;
    drop(pipelines?);
    Ok(ms)
}

/// Times each kernel on each scene: `repeats` times folded (median), once unfolded.
pub fn run(ctx: &Context, scenes: &[(String, Scene)], repeats: usize) -> Result<Vec<PipelineRow>> {
    type Timer = fn(&Context, &GpuScene) -> Result<f64>;
    let kernels: [(&'static str, Timer); 4] = [
        ("pathtrace", |ctx, scene| time_specs::<pathtrace::Kernel>(ctx, scene, &[Default::default()])),
        // What a render with `--integrator wavefront` makes.
        ("wavefront (5 stages)", |ctx, scene| {
            let (extend, others) = stage_specs(Default::default(), false);
            let specs: Vec<_> = std::iter::once(extend).chain(others).collect();
            time_specs::<wavefront::Kernel>(ctx, scene, &specs)
        }),
        ("gbuffer", |ctx, scene| time_specs::<gbuffer::Kernel>(ctx, scene, &[Default::default()])),
        ("deferred", |ctx, scene| time_specs::<deferred::Kernel>(ctx, scene, &[Default::default()])),
    ];
    let mut rows = Vec::new();
    for (name, scene) in scenes {
        let gpu_scene = GpuScene::upload(ctx, scene)?;
        for (kernel, time) in kernels {
            log::info!("{name}: {kernel}");
            let folded: Result<Vec<f64>> = (0..repeats.max(1)).map(|_| time(ctx, &gpu_scene)).collect();
            set_folding(false);
            let unfolded = time(ctx, &gpu_scene);
            set_folding(true);
            let mut folded = folded?;
            rows.push(PipelineRow {
                scene: name.clone(),
                kernel,
                folded_ms: super::rays::median(&mut folded),
                unfolded_ms: unfolded?,
            });
        }
    }
    Ok(rows)
}

/// The run as JSON.
pub fn to_json(device: &str, repeats: usize, rows: &[PipelineRow]) -> Value {
    let mut doc = json!({
        "device": device,
        "repeats": repeats,
        "rows": rows.iter().map(|r| json!({
            "scene": r.scene,
            "kernel": r.kernel,
            "folded_ms": r.folded_ms,
            "unfolded_ms": r.unfolded_ms,
        })).collect::<Vec<_>>(),
    });
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows).
pub fn table(doc: &Value) -> String {
    let mut out = format!(
        "Wall time of `vkCreateComputePipelines`, each kernel specialised on the scene's features with \
         its default settings; folded: median of {}, as compiled: one run; {} (LP_NUM_THREADS {}):\n\n\
         | scene | kernel | folded ms | as compiled ms | ÷ |\n|---|---|---:|---:|---:|\n",
        doc["repeats"],
        doc["device"].as_str().unwrap_or("?"),
        doc["lp_num_threads"].as_str().unwrap_or("unset"),
    );
    for r in doc["rows"].as_array().into_iter().flatten() {
        out += &format!(
            "| {} | {} | {:.0} | {:.0} | {:.1}× |\n",
            r["scene"].as_str().unwrap_or("?"),
            r["kernel"].as_str().unwrap_or("?"),
            num(&r["folded_ms"]),
            num(&r["unfolded_ms"]),
            num(&r["unfolded_ms"]) / num(&r["folded_ms"]),
        );
    }
    out
}
