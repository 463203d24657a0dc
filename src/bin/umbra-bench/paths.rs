//! The path tracer's throughput on a set of scenes (`umbra-bench paths`): samples and path
//! segments (closest-hit rays) per second, each the median of timed submissions after a warm-up,
//! and each scene's ratio to the set's median (issue 25 asks that no scene fall more than 4×
//! below it).

use super::num;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::environment::EnvironmentMap;
use umbra::gpu::layout::PathStats;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{Integrator, PathTarget};
use umbra::render::{Passes, PathSettings};
use umbra::scene::Scene;
use umbra::vk::{Context, GpuTimer};

/// What every scene is rendered with.
pub struct PathsSettings {
    /// Image size.
    pub size: (u32, u32),
    /// Samples per pixel of each timed submission.
    pub spp: u32,
    /// Timed submissions (after the warm-up).
    pub repeats: usize,
    /// Scattering events per path.
    pub max_bounces: u32,
    /// Russian roulette from this many scattering events.
    pub rr_depth: u32,
    /// Constant environment radiance (or the map's multiplier).
    pub env: [f32; 3],
    /// An environment map lighting every scene.
    pub env_map: Option<PathBuf>,
    /// The integrators timed, each scene with each in turn (A/B in the same minutes).
    pub integrators: Vec<Integrator>,
    /// Also count, in one more untimed submission per scene, how busy the SIMD lanes are in
    /// the megakernel's BVH walks ([`PathTarget::with_lane_counts`]).
    pub lanes: bool,
}

/// One scene's throughput.
pub struct PathRow {
    /// The scene's file name.
    pub scene: String,
    /// The integrator.
    pub integrator: Integrator,
    /// Triangles in its BVH.
    pub triangles: usize,
    /// Median GPU milliseconds of one timed submission.
    pub median_ms: f64,
    /// Path segments traced per sample (over the warm-up and the timed submissions).
    pub segments_per_sample: f64,
    /// With [`PathsSettings::lanes`], the megakernel's: the share of the SIMD lanes its
    /// closest-hit and its any-hit traces' walks keep busy ([`PathStats::busy_lanes`]; `None`
    /// where it traced none of the kind).
    pub busy_lanes: Option<[Option<f64>; 2]>,
}

/// Times `settings.spp` samples per pixel of each scene, `settings.repeats` times after a
/// warm-up, with the same camera rule as the other benchmarks.
pub fn run(ctx: &Context, scenes: &[(String, Scene)], settings: &PathsSettings) -> Result<Vec<PathRow>> {
    let env_map = settings.env_map.as_deref().map(EnvironmentMap::load).transpose()?;
    let mut rows = Vec::new();
    for (name, scene) in scenes {
        log::info!("{name}: path tracing");
        let mut gpu_scene = GpuScene::upload(ctx, scene)?;
        if let Some(map) = &env_map {
            gpu_scene.set_environment(ctx, map)?;
        }
        let camera = super::scenes::bench_camera(scene);
        let passes = Passes::new(ctx, &gpu_scene);
        for &integrator in &settings.integrators {
            let target = PathTarget::new(ctx, settings.size)?;
            let path = PathSettings {
                size: settings.size,
                spp: settings.spp,
                max_bounces: settings.max_bounces,
                rr_depth: settings.rr_depth,
                env: settings.env,
                integrator,
                ..PathSettings::default()
            };
            let spp = settings.spp;
            let mut submitted = 0u32;
            let samples = |rec: &mut umbra::vk::Recorder<'_>, range| {
                passes.record_path_samples(rec, &gpu_scene, &camera, &target, &path, range)
            };
            super::rays::warm_up(|| {
                submitted += spp;
                ctx.record(|rec| samples(rec, submitted - spp..submitted))
            })?;
            let mut timer = GpuTimer::new(ctx, 1)?;
            let mut ms = Vec::new();
            for _ in 0..settings.repeats.max(1) {
                ctx.record(|rec| {
                    let cmd = rec.cmd();
                    timer.reset(cmd);
                    timer.begin(cmd, "pathtrace")?;
                    samples(rec, submitted..submitted + spp)?;
                    timer.end(cmd)
                })?;
                submitted += spp;
                ms.push(timer.read()?.iter().map(|t| t.ms).sum::<f64>());
            }
            let stats: Vec<PathStats> = target.stats.read(ctx)?;
            let samples = settings.size.0 as f64 * settings.size.1 as f64 * submitted as f64;
            let busy_lanes = if settings.lanes && integrator == Integrator::Megakernel {
                let counting = PathTarget::new(ctx, settings.size)?.with_lane_counts();
                ctx.record(|rec| {
                    passes.record_path_samples(rec, &gpu_scene, &camera, &counting, &path, 0..spp)
                })?;
                let stats: Vec<PathStats> = counting.stats.read(ctx)?;
                let subgroup = ctx.info().subgroup_size;
                Some([stats[0].busy_lanes(false, subgroup), stats[0].busy_lanes(true, subgroup)])
            } else {
                None
            };
            rows.push(PathRow {
                scene: name.clone(),
                integrator,
                triangles: gpu_scene.bvh_stats.triangles,
                median_ms: super::rays::median(&mut ms),
                segments_per_sample: stats[0].segments() as f64 / samples,
                busy_lanes,
            });
        }
    }
    Ok(rows)
}

/// The run as JSON: settings, the conditions ([`super::add_conditions`]), then per scene its
/// time, samples and segments per second.
pub fn to_json(device: &str, subgroup_size: u32, settings: &PathsSettings, rows: &[PathRow]) -> Value {
    let samples = settings.size.0 as f64 * settings.size.1 as f64 * settings.spp as f64;
    let mut doc = json!({
        "device": device,
        "size": [settings.size.0, settings.size.1],
        "spp": settings.spp,
        "repeats": settings.repeats,
        "max_bounces": settings.max_bounces,
        "rr_depth": settings.rr_depth,
        "env": settings.env,
        "env_map": settings.env_map.as_ref().map(|p| p.display().to_string()),
        "scenes": rows.iter().map(|r| {
            let mut row = json!({
                "scene": r.scene,
                "integrator": r.integrator.name(),
                "triangles": r.triangles,
                "median_ms": r.median_ms,
                "msamples_per_s": samples / (r.median_ms * 1e3),
                "segments_per_sample": r.segments_per_sample,
                "msegments_per_s": samples * r.segments_per_sample / (r.median_ms * 1e3),
            });
            if let Some([closest, any]) = r.busy_lanes {
                row["busy_lanes_closest"] = json!(closest);
                row["busy_lanes_any"] = json!(any);
            }
            row
        }).collect::<Vec<_>>(),
    });
    if settings.lanes {
        doc["subgroup_size"] = json!(subgroup_size);
    }
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows): each scene's throughput and
/// its ratio to the median of the set.
pub fn table(doc: &Value) -> String {
    // Runs before the wavefront integrator have no "integrator": the megakernel's.
    let integrator = |s: &Value| s["integrator"].as_str().unwrap_or("megakernel").to_string();
    let all = doc["scenes"].as_array().cloned().unwrap_or_default();
    let first = all.first().map(integrator).unwrap_or_default();
    let scenes: Vec<Value> = all.iter().filter(|s| integrator(s) == first).cloned().collect();
    let mut rates: Vec<f64> = scenes.iter().map(|s| num(&s["msamples_per_s"])).collect();
    let median = super::rays::median(&mut rates);
    let env = match doc["env_map"].as_str() {
        Some(map) => format!("environment map {map}"),
        None => format!("constant environment {}", doc["env"]),
    };
    let mut out = format!(
        "{}×{}, {} spp per timed submission (median of {}), {} bounces, Russian roulette from {}, {env}; \
         {} (LP_NUM_THREADS {}):\n\n\
         | scene | triangles | ms | Msamples/s | ÷ median | segments per sample | Msegments/s |\n\
         |---|---:|---:|---:|---:|---:|---:|\n",
        doc["size"][0],
        doc["size"][1],
        doc["spp"],
        doc["repeats"],
        doc["max_bounces"],
        doc["rr_depth"],
        doc["device"].as_str().unwrap_or("?"),
        doc["lp_num_threads"].as_str().unwrap_or("unset"),
    );
    for s in &scenes {
        out += &format!(
            "| {} | {} | {:.1} | {:.3} | {:.2} | {:.2} | {:.2} |\n",
            s["scene"].as_str().unwrap_or("?"),
            s["triangles"],
            num(&s["median_ms"]),
            num(&s["msamples_per_s"]),
            num(&s["msamples_per_s"]) / median,
            num(&s["segments_per_sample"]),
            num(&s["msegments_per_s"]),
        );
    }
    out += &format!("\nMedian of the set: {median:.3} Msamples/s.\n");
    let counted: Vec<&Value> = scenes.iter().filter(|s| s.get("busy_lanes_closest").is_some()).collect();
    if !counted.is_empty() {
        let share = |v: &Value| v.as_f64().map_or("—".to_string(), |f| format!("{:.0} %", 100.0 * f));
        out += &format!(
            "\nThe SIMD lanes the walks keep busy (`--lanes`: walk-loop iterations of the lanes over \
             those of their {}-lane groups, one more submission of the megakernel per scene):\n\n\
             | scene | closest-hit traces | any-hit traces (shadow rays) |\n|---|---:|---:|\n",
            doc["subgroup_size"]
        );
        for s in counted {
            out += &format!(
                "| {} | {} | {} |\n",
                s["scene"].as_str().unwrap_or("?"),
                share(&s["busy_lanes_closest"]),
                share(&s["busy_lanes_any"]),
            );
        }
    }
    let others: Vec<&Value> = all.iter().filter(|s| integrator(s) != first).collect();
    if !others.is_empty() {
        out += &format!(
            "\nThe same samples through the other integrator, each scene's two runs in turn:\n\n\
             | scene | integrator | ms | {first} ms | speed-up over the {first} |\n|---|---|---:|---:|---:|\n"
        );
        for o in others {
            if let Some(s) = scenes.iter().find(|s| s["scene"] == o["scene"]) {
                out += &format!(
                    "| {} | {} | {:.1} | {:.1} | {:.2}× |\n",
                    o["scene"].as_str().unwrap_or("?"),
                    integrator(o),
                    num(&o["median_ms"]),
                    num(&s["median_ms"]),
                    num(&s["median_ms"]) / num(&o["median_ms"]),
                );
            }
        }
    }
    out
}
