//! An implicit sphere (`UMBRA_implicit`, ray-marched) against tessellated ones of rising triangle
//! count (`umbra-bench implicit`): BVH memory and build time, path-tracing time, and the geometric
//! error at the silhouette and on the surface, measured with camera rays against the analytic
//! sphere; JSON, a Markdown table and a chart (surface error against render time).

use super::chart::{self, Chart, ChartPoint};
use super::num;
use anyhow::Result;
use glam::{Mat4, Vec3};
use serde_json::{json, Value};
use std::path::Path;
use umbra::bvh::{BuildOptions, Bvh};
use umbra::gpu::bvh::{GpuBvh, GpuBvhNode, Query, RayTracer};
use umbra::gpu::layout::{TraceHit, TraceRay};
use umbra::gpu::scene::{scene_boxes, GpuScene};
use umbra::procedural::icosphere;
use umbra::render::{path_trace, PathSettings};
use umbra::scene::{implicit, Camera, Light, LightKind, Material, Scene};
use umbra::vk::Context;

/// What the comparison renders.
pub struct ImplicitSettings {
    /// Image size of the timed path trace.
    pub size: (u32, u32),
    /// Its samples per pixel.
    pub spp: u32,
    /// Timed path traces (the median is reported).
    pub repeats: usize,
    /// Camera rays a side for the geometric errors.
    pub rays: u32,
    /// Icosphere subdivisions (20·4^s triangles each).
    pub subdivisions: Vec<u32>,
}

/// One sphere's figures.
pub struct Row {
    /// "implicit" or "tessellated".
    pub method: &'static str,
    /// Triangles (0 for the implicit sphere).
    pub triangles: usize,
    /// GPU BVH bytes: 4-wide nodes, triangle slots, implicit programs.
    pub bvh_bytes: usize,
    /// BVH build (ms, median of three).
    pub build_ms: f64,
    /// Path-tracing GPU time (ms, median).
    pub render_ms: f64,
    /// Camera rays whose hit-or-miss verdict differs from the analytic sphere's.
    pub silhouette_misses: usize,
    /// The largest |‖p‖ − r| over the camera rays' hits, relative to r.
    pub surface_error: f64,
    /// Marches that ran out of steps during the timed path trace.
    pub marches_exhausted: u32,
}

const RADIUS: f32 = 1.0;

/// The unit sphere at the origin over a floor, a point light and a grey sky: implicit (`None`) or
/// an icosphere of `Some(subdivisions)` with the sphere's normals.
fn scene(subdivisions: Option<u32>) -> Result<Scene> {
    let mut scene = Scene { name: "sphere".into(), ..Default::default() };
    let lambert = |a: f32| Material {
        base_color_factor: [a, a, a, 1.0],
        metallic: 0.0,
        roughness: 1.0,
        ..Default::default()
    };
    scene.materials = vec![lambert(0.5), lambert(0.8)];
    let mut add = |tris: Vec<[Vec3; 3]>, smooth: bool, material: u32| {
        for t in tris {
            let face = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            let base = scene.positions.len() as u32;
            for v in t {
                scene.positions.push(v.into());
                scene.normals.push((if smooth { v.normalize() } else { face }).into());
            }
            scene.triangles.push([base, base + 1, base + 2]);
            scene.triangle_material.push(material);
        }
    };
    let (y, h) = (-RADIUS, 4.0);
    let c = [Vec3::new(-h, y, -h), Vec3::new(h, y, -h), Vec3::new(h, y, h), Vec3::new(-h, y, h)];
    add(vec![[c[0], c[2], c[1]], [c[0], c[3], c[2]]], false, 0);
    match subdivisions {
        Some(s) => add(icosphere(s, Vec3::ZERO, RADIUS).soup(), true, 1),
        None => {
            let shape = json!({ "sphere": { "radius": RADIUS }, "material": 1 });
            scene.implicits.push(implicit::from_json("sphere", &shape, Mat4::IDENTITY, 2)?);
        }
    }
    scene.lights.push(Light {
        name: "bulb".into(),
        kind: LightKind::Point,
        position: [2.0, 3.0, 2.0],
        direction: [0.0, -1.0, 0.0],
        color: [1.0; 3],
        intensity: 20.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::FRAC_PI_4,
    });
    scene.cameras.push(camera());
    scene.update_emissive();
    Ok(scene)
}

fn camera() -> Camera {
    Camera {
        position: [0.0, 0.0, 3.0],
        forward: [0.0, 0.0, -1.0],
        up: [0.0, 1.0, 0.0],
        yfov: 45f32.to_radians(),
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    }
}

/// Camera rays through an n × n grid (pixel centres) of the camera's view.
fn camera_rays(n: u32) -> Vec<TraceRay> {
    let cam = camera();
    let tan = (cam.yfov * 0.5).tan();
    let o = Vec3::from(cam.position);
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let u = (2.0 * (x as f32 + 0.5) / n as f32 - 1.0) * tan;
            let v = (1.0 - 2.0 * (y as f32 + 0.5) / n as f32) * tan;
            let d = Vec3::new(u, v, -1.0).normalize();
            TraceRay { origin_tmin: o.extend(0.0).into(), dir_tmax: d.extend(f32::INFINITY).into() }
        })
        .collect()
}

/// Whether the analytic sphere is hit (f64).
fn sphere_hit(ray: &TraceRay) -> bool {
    let o = Vec3::from_slice(&ray.origin_tmin[..3]).as_dvec3();
    let d = Vec3::from_slice(&ray.dir_tmax[..3]).as_dvec3();
    let b = o.dot(d) / d.length_squared();
    let c = (o.length_squared() - (RADIUS as f64).powi(2)) / d.length_squared();
    b * b - c >= 0.0 && -b + (b * b - c).max(0.0).sqrt() > 0.0
}

/// One sphere measured.
fn measure(ctx: &Context, subdivisions: Option<u32>, settings: &ImplicitSettings) -> Result<Row> {
    let scene = scene(subdivisions)?;
    let soup = scene.triangle_soup();
    let boxes = scene_boxes(&scene)?;
    let mut builds: Vec<f64> = Vec::new();
    for _ in 0..3 {
        let start = std::time::Instant::now();
        let bvh = Bvh::build_mixed(&soup, &boxes, &BuildOptions::default())?;
        std::hint::black_box(&bvh);
        builds.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let build_ms = super::rays::median(&mut builds);
    let gpu_scene = GpuScene::upload(ctx, &scene)?;
    let arrays = umbra::gpu::scene::SceneArrays::new(&scene)?;
    let nodes = GpuBvhNode::from_bvh(&arrays.bvh)?.len();
    let bvh_bytes = nodes * 64 + arrays.bvh.tris.len() * 48 + arrays.bvh.implicit_texels.len() * 16;

    // Geometric error: the sphere alone (no floor), camera rays.
    let alone = {
        let mut s = scene.clone();
        let floor_tris = 2;
        s.triangles.drain(..floor_tris);
        s.triangle_material.drain(..floor_tris);
        s
    };
    let sphere_bvh = GpuBvh::upload(ctx, &umbra::gpu::scene::SceneArrays::new(&alone)?.bvh)?;
    let rays = camera_rays(settings.rays);
    let hits =
        RayTracer::with_implicit(ctx, sphere_bvh.implicit)?.trace(ctx, Query::Closest, &sphere_bvh, &rays)?;
    let mut silhouette_misses = 0;
    let mut surface_error = 0.0f64;
    for (h, ray) in hits.iter().zip(&rays) {
        let hit = h.tri != TraceHit::MISS;
        silhouette_misses += (hit != sphere_hit(ray)) as usize;
        if hit {
            let p = Vec3::from_slice(&ray.origin_tmin[..3]).as_dvec3()
                + h.t as f64 * Vec3::from_slice(&ray.dir_tmax[..3]).as_dvec3();
            surface_error = surface_error.max((p.length() - RADIUS as f64).abs() / RADIUS as f64);
        }
    }

    let path =
        PathSettings { size: settings.size, spp: settings.spp, env: [0.3; 3], ..PathSettings::default() };
    let cam = scene.camera(None)?;
    path_trace(ctx, &gpu_scene, &cam, &path, |_, _| {})?; // warm-up (kernel compilation)
    let mut times = Vec::new();
    let mut marches_exhausted = 0;
    for _ in 0..settings.repeats.max(1) {
        let image = path_trace(ctx, &gpu_scene, &cam, &path, |_, _| {})?;
        times.push(image.gpu_ms);
        marches_exhausted = image.marches_exhausted;
    }
    Ok(Row {
        method: if subdivisions.is_some() { "tessellated" } else { "implicit" },
        triangles: subdivisions.map_or(0, |_| soup.len() - 2),
        bvh_bytes,
        build_ms,
        render_ms: super::rays::median(&mut times),
        silhouette_misses,
        surface_error,
        marches_exhausted,
    })
}

/// Every sphere measured, the implicit one first.
pub fn run(ctx: &Context, settings: &ImplicitSettings) -> Result<Vec<Row>> {
    let mut rows = vec![measure(ctx, None, settings)?];
    for &s in &settings.subdivisions {
        log::info!("icosphere of {} triangles", 20 * 4usize.pow(s));
        rows.push(measure(ctx, Some(s), settings)?);
    }
    Ok(rows)
}

/// The run as JSON.
pub fn to_json(device: &str, settings: &ImplicitSettings, rows: &[Row]) -> Value {
    json!({
        "device": device,
        "size": [settings.size.0, settings.size.1],
        "spp": settings.spp,
        "rays": settings.rays * settings.rays,
        "rows": rows.iter().map(|r| json!({
            "method": r.method,
            "triangles": r.triangles,
            "bvh_bytes": r.bvh_bytes,
            "build_ms": r.build_ms,
            "render_ms": r.render_ms,
            "silhouette_misses": r.silhouette_misses,
            "surface_error": r.surface_error,
            "marches_exhausted": r.marches_exhausted,
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run's JSON.
pub fn table(doc: &Value) -> String {
    let mut out = format!(
        "Implicit sphere against tessellated spheres ({}; path trace {}×{} at {} spp, median; errors over {} camera rays)\n\n",
        doc["device"].as_str().unwrap_or("?"),
        num(&doc["size"][0]),
        num(&doc["size"][1]),
        num(&doc["spp"]),
        num(&doc["rays"])
    );
    out.push_str("| sphere | triangles | BVH KiB | build ms | render ms | silhouette rays wrong | max surface error (× r) | marches out of steps |\n");
    out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for r in doc["rows"].as_array().into_iter().flatten() {
        out.push_str(&format!(
            "| {} | {} | {:.1} | {:.2} | {:.1} | {} | {:.1e} | {} |\n",
            r["method"].as_str().unwrap_or("?"),
            num(&r["triangles"]),
            num(&r["bvh_bytes"]) / 1024.0,
            num(&r["build_ms"]),
            num(&r["render_ms"]),
            num(&r["silhouette_misses"]),
            num(&r["surface_error"]),
            num(&r["marches_exhausted"])
        ));
    }
    out
}

/// The chart: surface error against render time, the tessellated spheres labelled by their
/// triangle count.
pub fn write_chart(out: &Path, rows: &[Row]) -> Result<()> {
    let labels: Vec<String> = rows.iter().map(|r| r.method.to_string()).collect();
    let points: Vec<ChartPoint> = rows
        .iter()
        .zip(&labels)
        .map(|(r, m)| ChartPoint {
            method: m,
            unit: if r.triangles > 0 { "triangles" } else { "-" },
            value: r.triangles as u32,
            ms: r.render_ms,
            error: r.surface_error.max(1e-9),
        })
        .collect();
    umbra::atomic::create_dir(out)?;
    chart::write(
        &out.join("implicit"),
        &Chart {
            title: "Implicit sphere vs tessellated spheres: surface error against path-tracing time",
            y_desc: "max |‖p‖ − r| / r at camera-ray hits (log)",
            floor: 0.0,
        },
        &points,
    )
}
