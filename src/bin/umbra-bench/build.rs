//! The BVH build alone (`umbra-bench build`, CPU only, no Vulkan): each scene built after one
//! warm-up build, the median and fastest wall time and the process's CPU time per build (steadier
//! than wall time on a shared machine), the SAH cost and, on request, the full-sweep build's.

use super::num;
use super::rays::RayScene;
use anyhow::Result;
use serde_json::{json, Value};
use umbra::bvh::{BuildOptions, Bvh};

/// One scene's builds.
pub struct BuildRow {
    /// The scene (with its triangle count).
    pub scene: String,
    /// Input triangles.
    pub triangles: usize,
    /// Median wall milliseconds of the timed builds.
    pub median_ms: f64,
    /// Fastest timed build.
    pub fastest_ms: f64,
    /// Process CPU milliseconds per build (all threads), where procfs tells it.
    pub cpu_ms: Option<f64>,
    /// The last build's statistics.
    pub stats: umbra::bvh::BvhStats,
    /// The full-sweep build's SAH cost, when measured.
    pub sweep_sah_cost: Option<f32>,
}

/// A warm-up build of `scene`, then `builds` timed ones, validated; the full-sweep build too when
/// `sweep`.
pub fn run(scene: &RayScene, builds: usize, sweep: bool) -> Result<BuildRow> {
    let mut bvh = Bvh::build(&scene.triangles)?;
    let cpu_before = process_cpu_seconds();
    let mut ms: Vec<f64> = (0..builds.max(1))
        .map(|_| {
            bvh = Bvh::build(&scene.triangles)?;
            Ok(bvh.stats.build_ms)
        })
        .collect::<Result<_>>()?;
    let cpu_ms = cpu_before.zip(process_cpu_seconds()).map(|(a, b)| (b - a) * 1e3 / ms.len() as f64);
    bvh.validate().map_err(anyhow::Error::msg)?;
    let sweep_sah_cost = if sweep {
        let options = BuildOptions { full_sweep: true, ..Default::default() };
        Some(Bvh::build_with(&scene.triangles, &options)?.stats.sah_cost)
    } else {
        None
    };
    let median_ms = super::rays::median(&mut ms); // sorts
    Ok(BuildRow {
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        median_ms,
        fastest_ms: ms[0],
        cpu_ms,
        stats: bvh.stats,
        sweep_sah_cost,
    })
}

/// What `umbra-bench build` prints for a scene.
pub fn print(r: &BuildRow) {
    let s = &r.stats;
    println!(
        "{}: build median {:.1} ms, fastest {:.1} ms, CPU time {} ms per build; SAH cost {:.2}, {} nodes, depth {}",
        r.scene,
        r.median_ms,
        r.fastest_ms,
        r.cpu_ms.map_or("?".into(), |t| format!("{t:.0}")),
        s.sah_cost,
        s.nodes,
        s.depth
    );
    if let Some(full) = r.sweep_sah_cost {
        println!("  full-sweep SAH cost {full:.2}: binned is {:+.2} %", (s.sah_cost / full - 1.0) * 100.0);
    }
}

/// The run as JSON (`build.json`): the settings, the conditions ([`super::add_conditions`]), a row
/// per scene.
pub fn to_json(builds: usize, rows: &[BuildRow]) -> Value {
    let mut doc = json!({
        "threads": rayon::current_num_threads(),
        "builds": builds,
        "scenes": rows.iter().map(|r| json!({
            "scene": r.scene,
            "triangles": r.triangles,
            "references": r.stats.references,
            "nodes": r.stats.nodes,
            "depth": r.stats.depth,
            "median_ms": r.median_ms,
            "fastest_ms": r.fastest_ms,
            "cpu_ms_per_build": r.cpu_ms,
            "sah_cost": r.stats.sah_cost,
            "sweep_sah_cost": r.sweep_sah_cost,
        })).collect::<Vec<_>>(),
    });
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows).
pub fn table(doc: &Value) -> String {
    let mut out = format!(
        "{} timed builds per scene after a warm-up, {} rayon threads, {}:\n\n\
         | scene | triangles | references | build ms (median) | fastest ms | CPU ms per build | SAH cost | binned vs full sweep | nodes | depth |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        doc["builds"],
        doc["threads"],
        super::load_text(doc),
    );
    for s in doc["scenes"].as_array().into_iter().flatten() {
        let name = s["scene"].as_str().unwrap_or("?");
        let name = name.rsplit_once(" (").map_or(name, |(n, _)| n);
        let cpu = s["cpu_ms_per_build"].as_f64().map_or("?".to_string(), |t| format!("{t:.0}"));
        let sweep = s["sweep_sah_cost"].as_f64().map_or("—".to_string(), |full| {
            format!("{:+.2} %", 100.0 * (num(&s["sah_cost"]) / full - 1.0))
        });
        out += &format!(
            "| {name} | {} | {} | {:.1} | {:.1} | {cpu} | {:.2} | {sweep} | {} | {} |\n",
            s["triangles"],
            s["references"],
            num(&s["median_ms"]),
            num(&s["fastest_ms"]),
            num(&s["sah_cost"]),
            s["nodes"],
            s["depth"],
        );
    }
    out
}

/// User + system CPU time of this process (all threads) from `/proc/self/stat`, in seconds at
/// the kernel's 10 ms tick; `None` where there is no procfs. Steadier than wall-clock time on a
/// shared machine.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name: state is field 3, utime 14, stime 15.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i - 3)?.parse::<f64>().ok();
    Some((ticks(14)? + ticks(15)?) / 100.0)
}
