//! Ray throughput in the style of tinybvh's speedtest: build the BVH (binned, and full-sweep SAH
//! for the quality comparison), make primary, shadow and diffuse-bounce rays, validate the GPU's
//! answers against the CPU traversal and a brute-force reference, then time each ray kind with
//! GPU timestamps (warm-up, median of repeats).

use super::num;
use anyhow::{bail, Result};
use glam::Vec3;
use rayon::prelude::*;
use serde_json::{json, Value};
use std::time::Instant;
use umbra::bvh::reference::{same_hit, Reference};
use umbra::bvh::{BuildOptions, Bvh, BvhStats, Ray};
use umbra::gpu::bvh::{GpuBvh, Query, RayBatch, RayTracer};
use umbra::gpu::layout::{TraceHit, TraceRay};
use umbra::procedural::Rng;
use umbra::vk::{Context, GpuTimer};

/// A scene to trace: triangles and a view.
pub struct RayScene {
    pub name: String,
    pub triangles: Vec<[Vec3; 3]>,
    pub eye: Vec3,
    pub target: Vec3,
    pub yfov: f32,
    /// A point light for the shadow rays.
    pub light: Vec3,
}

/// What one scene measured.
pub struct RayReport {
    pub scene: String,
    pub triangles: usize,
    pub binned: BvhStats,
    pub binned_build_ms_median: f64,
    pub sweep: Option<BvhStats>,
    /// (kind, rays, median ms, Mrays/s)
    pub kinds: Vec<(String, usize, f64, f64)>,
}

pub struct RaySettings {
    pub size: (u32, u32),
    pub repeats: usize,
    pub builds: usize,
    pub sweep: bool,
    /// Primary rays in row order instead of 8×8 tiles (to measure what ray order costs).
    pub row_order: bool,
    /// Write the scene's triangles, each kind's rays and umbra's answers here, for a peer to
    /// trace exactly the same rays (`peers.py`).
    pub dump: Option<std::path::PathBuf>,
}

pub fn run(ctx: &Context, scene: &RayScene, settings: &RaySettings) -> Result<RayReport> {
    let mut build_ms = Vec::new();
    let mut bvh = None;
    for _ in 0..settings.builds.max(1) {
        let b = Bvh::build(&scene.triangles)?;
        build_ms.push(b.stats.build_ms);
        bvh = Some(b);
    }
    let bvh = bvh.expect("at least one build");
    bvh.validate().map_err(anyhow::Error::msg)?;
    let sweep = if settings.sweep {
        let options = BuildOptions { full_sweep: true, ..Default::default() };
        Some(Bvh::build_with(&scene.triangles, &options)?.stats)
    } else {
        None
    };

    let device_bvh = GpuBvh::upload(ctx, &bvh)?;
    let tracer = RayTracer::new(ctx)?;
    let reference = Reference::new(&scene.triangles);
    let validated =
        |query, rays: &[Ray]| trace_validated(ctx, &tracer, &device_bvh, &bvh, &reference, query, rays);
    let primary = primary_rays(scene, settings.size, settings.row_order);
    let (primary_batch, primary_hits) = validated(Query::Closest, &primary)?;
    let (shadow, diffuse) = secondary_rays(scene, &bvh, &primary, &primary_hits);
    let (shadow_batch, _) = validated(Query::Any, &shadow)?;
    let (diffuse_batch, _) = validated(Query::Closest, &diffuse)?;

    if let Some(dir) = &settings.dump {
        let hits = |batch: &RayBatch| batch.read_hits(ctx);
        dump(
            dir,
            scene,
            &bvh,
            [
                ("primary", &primary, hits(&primary_batch)?),
                ("shadow", &shadow, hits(&shadow_batch)?),
                ("diffuse", &diffuse, hits(&diffuse_batch)?),
            ],
        )?;
    }

    let mut kinds = Vec::new();
    for (kind, query, batch) in [
        ("primary", Query::Closest, &primary_batch),
        ("shadow", Query::Any, &shadow_batch),
        ("diffuse", Query::Closest, &diffuse_batch),
    ] {
        let ms = time_trace(ctx, &tracer, &device_bvh, query, batch, settings.repeats)?;
        let count = batch.count as usize;
        kinds.push((kind.to_string(), count, ms, count as f64 / (ms * 1e3)));
    }
    Ok(RayReport {
        scene: scene.name.clone(),
        triangles: scene.triangles.len(),
        binned: bvh.stats.clone(),
        binned_build_ms_median: median(&mut build_ms),
        sweep,
        kinds,
    })
}

/// The run as JSON (`rays.json`): the settings, the conditions ([`super::add_conditions`]), then per
/// scene its BVH's statistics and each ray kind's median time and throughput.
pub fn to_json(device: &str, settings: &RaySettings, reports: &[RayReport]) -> Value {
    let stats = |s: &BvhStats| {
        json!({
            "references": s.references, "nodes": s.nodes, "leaves": s.leaves, "depth": s.depth,
            "max_leaf_size": s.max_leaf_size, "mean_leaf_size": s.mean_leaf_size, "sah_cost": s.sah_cost,
            "build_ms": s.build_ms,
        })
    };
    let mut doc = json!({
        "device": device,
        "threads": rayon::current_num_threads(),
        "size": [settings.size.0, settings.size.1],
        "repeats": settings.repeats,
        "builds": settings.builds,
        "row_order": settings.row_order,
        "scenes": reports.iter().map(|r| json!({
            "scene": r.scene,
            "triangles": r.triangles,
            "binned": stats(&r.binned),
            "binned_build_ms_median": r.binned_build_ms_median,
            "sweep": r.sweep.as_ref().map(stats),
            "rays": r.kinds.iter().map(|(kind, n, ms, mrays)| json!({
                "kind": kind, "rays": n, "median_ms": ms, "mrays_per_s": mrays,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    });
    super::add_conditions(&mut doc);
    doc
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows): per scene its BVH (references
/// after early split clipping, nodes, depth, SAH cost, and against the full-sweep build when
/// measured) and each ray kind's throughput.
pub fn table(doc: &Value) -> String {
    let scenes = doc["scenes"].as_array().cloned().unwrap_or_default();
    let kinds: Vec<String> = scenes
        .first()
        .and_then(|s| s["rays"].as_array())
        .map(|rays| rays.iter().map(|r| r["kind"].as_str().unwrap_or("?").to_string()).collect())
        .unwrap_or_default();
    let sweep = scenes.iter().any(|s| s["sweep"].is_object());
    let order = if doc["row_order"] == true { "in rows" } else { "in 8×8 tiles" };
    let mut out = format!(
        "{}×{} rays per kind (primary rays {order}), median of {} after a warm-up; {}, {}; BVH built on {} \
         threads:\n\n| scene | triangles | BVH references | nodes | depth | SAH cost |",
        doc["size"][0],
        doc["size"][1],
        doc["repeats"],
        doc["device"].as_str().unwrap_or("?"),
        super::conditions_text(doc),
        doc["threads"],
    );
    if sweep {
        out += " binned vs full sweep |";
    }
    for kind in &kinds {
        out += &format!(" {kind} Mrays/s |");
    }
    out += &format!("\n|---|{}\n", "---:|".repeat(5 + sweep as usize + kinds.len()));
    for s in &scenes {
        let b = &s["binned"];
        let name = s["scene"].as_str().unwrap_or("?");
        // The scene's name ends with its triangle count, which has a column of its own.
        let name = name.rsplit_once(" (").map_or(name, |(n, _)| n);
        out += &format!(
            "| {name} | {} | {} | {} | {} | {:.2} |",
            s["triangles"],
            b["references"],
            b["nodes"],
            b["depth"],
            num(&b["sah_cost"])
        );
        if sweep {
            let full = num(&s["sweep"]["sah_cost"]);
            out += &if full.is_nan() {
                " — |".to_string()
            } else {
                format!(" {:+.2} % |", 100.0 * (num(&b["sah_cost"]) / full - 1.0))
            };
        }
        for kind in &kinds {
            let rays = s["rays"].as_array().and_then(|r| r.iter().find(|r| r["kind"] == kind.as_str()));
            out += &rays.map_or(" — |".to_string(), |r| format!(" {:.2} |", num(&r["mrays_per_s"])));
        }
        out += "\n";
    }
    out
}

/// A file-name stem for `name`: letters and digits, the rest `-`.
pub fn slug(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '-' }).collect()
}

/// Writes, little-endian, `<slug>-triangles.f32` (9 floats per triangle, input order) and per
/// kind `<slug>-<kind>.f32` (8 floats per ray: origin, tmin, direction, tmax) and
/// `<slug>-<kind>.u32` (umbra's answer per ray: the input triangle hit or 0xffffffff; any hit:
/// 1 occluded, 0 clear).
fn dump(
    dir: &std::path::Path,
    scene: &RayScene,
    bvh: &Bvh,
    kinds: [(&str, &Vec<Ray>, Vec<TraceHit>); 3],
) -> Result<()> {
    umbra::atomic::create_dir(dir)?;
    let stem = slug(&scene.name);
    let write = |name: String, bytes: &[u8]| {
        let path = dir.join(name);
        umbra::atomic::write(&path, bytes)
    };
    let triangles: Vec<f32> =
        scene.triangles.iter().flat_map(|t| t.iter().flat_map(|v| v.to_array())).collect();
    write(format!("{stem}-triangles.f32"), bytemuck::cast_slice(&triangles))?;
    for (kind, rays, hits) in kinds {
        let floats: Vec<f32> = rays
            .iter()
            .flat_map(|r| [r.origin.x, r.origin.y, r.origin.z, r.tmin, r.dir.x, r.dir.y, r.dir.z, r.tmax])
            .collect();
        write(format!("{stem}-{kind}.f32"), bytemuck::cast_slice(&floats))?;
        let answers: Vec<u32> = hits
            .iter()
            .map(|h| match kind {
                "shadow" => h.t as u32,
                _ if h.tri == TraceHit::MISS => u32::MAX,
                _ => bvh.tris[h.tri as usize].v0[3].to_bits(),
            })
            .collect();
        write(format!("{stem}-{kind}.u32"), bytemuck::cast_slice(&answers))?;
    }
    Ok(())
}

fn primary_rays(scene: &RayScene, (w, h): (u32, u32), row_order: bool) -> Vec<Ray> {
    let forward = (scene.target - scene.eye).normalize();
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let tan = (scene.yfov * 0.5).tan();
    let aspect = w as f32 / h as f32;
    // In 8×8 tiles: with trace.comp's 64-wide workgroups each workgroup is one tile, ordered as
    // the renderer's 8×8 kernels order it (`pixel.glsl`: 8-lane SIMD batches on 4×2 blocks, a
    // 32-lane warp an 8×4 block). Row order (a warp on a 32×1 strip) measured 3.9× slower on
    // Sponza on an H100 (docs/history/2026-11-22.md, "NVIDIA H100, first figures").
    let tiles = (w.div_ceil(8), h.div_ceil(8));
    (0..tiles.0 * tiles.1 * 64)
        .map(|i| {
            if row_order {
                return (i % w, i / w);
            }
            let (tile, k) = (i / 64, i % 64);
            let (kx, ky) = ((k & 3) | ((k >> 1) & 4), ((k >> 2) & 1) | ((k >> 3) & 6));
            ((tile % tiles.0) * 8 + kx, (tile / tiles.0) * 8 + ky)
        })
        .filter(|&(x, y)| x < w && y < h)
        .map(|(x, y)| {
            let sx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan;
            Ray {
                origin: scene.eye,
                dir: (forward + right * sx + up * sy).normalize(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

/// From every primary hit: a shadow ray to the light (any hit, segment ends at the light) and a
/// cosine-distributed diffuse bounce about the geometric normal facing the camera.
fn secondary_rays(scene: &RayScene, bvh: &Bvh, primary: &[Ray], hits: &[TraceHit]) -> (Vec<Ray>, Vec<Ray>) {
    let (lo, hi) = bvh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let eps = (hi - lo).length() * 1e-5;
    let mut rng = Rng::new(17);
    let mut shadow = Vec::new();
    let mut diffuse = Vec::new();
    for (ray, hit) in primary.iter().zip(hits) {
        let Some(hit) = hit.hit() else { continue };
        let [a, b, c] = bvh.tris[hit.tri as usize].vertices();
        let mut n = (b - a).cross(c - a).normalize_or(Vec3::Y);
        if n.dot(ray.dir) > 0.0 {
            n = -n;
        }
        let p = ray.origin + ray.dir * hit.t + n * eps;
        shadow.push(Ray { origin: p, dir: scene.light - p, tmin: 0.0, tmax: 1.0 });
        let (t, s) = n.any_orthonormal_pair();
        let (r, phi) = (rng.f32().sqrt(), rng.range(0.0, std::f32::consts::TAU));
        let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).max(0.0).sqrt());
        let dir = t * local.x + s * local.y + n * local.z;
        diffuse.push(Ray { origin: p, dir, tmin: 0.0, tmax: f32::INFINITY });
    }
    (shadow, diffuse)
}

/// Uploads and traces `rays` on the GPU and checks every answer against the CPU BVH traversal,
/// and a sample against brute force; fails on any disagreement. Returns the uploaded batch (for
/// timing) and its hits.
fn trace_validated(
    ctx: &Context,
    tracer: &RayTracer,
    device_bvh: &GpuBvh,
    bvh: &Bvh,
    reference: &Reference,
    query: Query,
    rays: &[Ray],
) -> Result<(RayBatch, Vec<TraceHit>)> {
    let trace_rays: Vec<TraceRay> = rays.iter().map(TraceRay::from).collect();
    let batch = RayBatch::new(ctx, &trace_rays)?;
    ctx.record(|rec| tracer.record(rec, query, device_bvh, &batch))?;
    let hits = batch.read_hits(ctx)?;
    let bad = rays
        .par_iter()
        .zip(&hits)
        .filter(|(ray, hit)| match query {
            Query::Closest => !same_hit(hit.hit(), bvh.closest(ray), |t| t),
            Query::Any => (hit.t == 1.0) != bvh.any(ray),
        })
        .count();
    let step = (rays.len() / 2000).max(1);
    let bad_reference = (0..rays.len())
        .into_par_iter()
        .step_by(step)
        .filter(|&i| match query {
            Query::Closest => {
                !same_hit(hits[i].hit(), reference.closest(&rays[i]), |t| bvh.prim_order[t as usize])
            }
            Query::Any => (hits[i].t == 1.0) != reference.any(&rays[i]),
        })
        .count();
    if bad + bad_reference > 0 {
        bail!(
            "{query:?} validation failed: {bad} of {} rays differ from the CPU BVH, {bad_reference} of \
             {} from brute force",
            rays.len(),
            rays.len().div_ceil(step)
        );
    }
    Ok((batch, hits))
}

/// Median GPU time of one trace dispatch over `repeats` timed submissions after a warm-up
/// ([`warm_up`]).
fn time_trace(
    ctx: &Context,
    tracer: &RayTracer,
    bvh: &GpuBvh,
    query: Query,
    batch: &RayBatch,
    repeats: usize,
) -> Result<f64> {
    let mut timer = GpuTimer::new(ctx, 1)?;
    warm_up(|| ctx.record(|rec| tracer.record(rec, query, bvh, batch)))?;
    let mut times = Vec::new();
    for i in 0..=repeats {
        let start = Instant::now();
        ctx.record(|rec| {
            let cmd = rec.cmd();
            timer.reset(cmd);
            timer.begin(cmd, "trace")?;
            tracer.record(rec, query, bvh, batch)?;
            timer.end(cmd)
        })?;
        let ms = timer.read()?[0].ms;
        log::debug!("{query:?} repeat {i}: GPU {ms:.3} ms, wall {:?}", start.elapsed());
        if i > 0 {
            times.push(ms);
        }
    }
    Ok(median(&mut times))
}

/// Repeats `submit` (one submission, waited for) for at least half a second of wall time, so a
/// GPU that idles at low clocks has ramped up before anything is timed: on an H100 fresh from
/// idle, sub-millisecond dispatches timed 1.5–3.6× slower than the same dispatches warm.
pub fn warm_up(mut submit: impl FnMut() -> umbra::Result<()>) -> Result<()> {
    let start = Instant::now();
    while start.elapsed().as_secs_f64() < 0.5 {
        submit()?;
    }
    Ok(())
}

pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}
