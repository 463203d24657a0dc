//! The rasterized G-buffer (visibility buffer and resolve) against the ray-cast one, on every
//! scene in `scenes/`: the visibility buffer's triangle that of a CPU traversal of the pixel's
//! ray, and the G-buffers identical bit for bit, on every pixel but ties, each tie justified on
//! the CPU (f64, independent of both kernels) and counted.

mod common;

use common::Gpu;
use glam::DVec3;
use umbra::gpu::layout::{GpuCamera, RASTER_NO_TRIANGLE};
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::passes::gbuffer::{GBuffer, GBufferData, VisibilityBuffer};
use umbra::render::Passes;
use umbra::scene::{Camera, Scene};

/// Every glTF file under `scenes/`.
fn scene_files() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files = Vec::new();
    let mut dirs = vec![root];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "glb" || e == "gltf") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The ray of pixel (x, y) in f64 (through its centre moved by the camera's jitter), from the
/// same f32 camera the kernels read.
fn centre_ray(c: &GpuCamera, (w, h): (u32, u32), (x, y): (u32, u32)) -> (DVec3, DVec3) {
    let v = |a: [f32; 3]| DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let [jx, jy] = c.jitter().map(f64::from);
    let ndc = (2.0 * (x as f64 + 0.5 + jx) / w as f64 - 1.0, 1.0 - 2.0 * (y as f64 + 0.5 + jy) / h as f64);
    let offset = ndc.0 * v(c.right) + ndc.1 * v(c.up);
    if c.orthographic() {
        (v(c.origin) + offset, v(c.forward))
    } else {
        (v(c.origin), (v(c.forward) + offset).normalize())
    }
}

/// The ray's meeting with triangle `tri`'s plane (BVH order): distance and the three barycentric
/// weights (negative outside), or `None` for a ray parallel to it.
fn plane_hit(arrays: &SceneArrays, tri: u32, (o, d): (DVec3, DVec3)) -> Option<(f64, [f64; 3])> {
    let [p0, p1, p2] = arrays.bvh.tris[tri as usize].vertices().map(|p| p.as_dvec3());
    let (e1, e2) = (p1 - p0, p2 - p0);
    let q = d.cross(e2);
    let det = e1.dot(q);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - p0;
    let b1 = s.dot(q) / det;
    let r = s.cross(e1);
    let b2 = d.dot(r) / det;
    Some((e2.dot(r) / det, [1.0 - b1 - b2, b1, b2]))
}

/// How far (in pixels at the hit's depth, `pixel` world units per unit of depth, plus `flat` for
/// an orthographic view) the ray passes from triangle `tri`'s nearest edge: inside or out, the
/// barycentric weight of a vertex times the triangle's height over the opposite edge.
fn edge_distance(arrays: &SceneArrays, tri: u32, ray: (DVec3, DVec3), pixel: (f64, f64)) -> f64 {
    let [p0, p1, p2] = arrays.bvh.tris[tri as usize].vertices().map(|p| p.as_dvec3());
    let Some((t, b)) = plane_hit(arrays, tri, ray) else { return 0.0 };
    let area2 = (p1 - p0).cross(p2 - p0).length();
    let heights = [area2 / (p2 - p1).length(), area2 / (p0 - p2).length(), area2 / (p1 - p0).length()];
    let world = (0..3).map(|k| b[k].abs() * heights[k]).fold(f64::MAX, f64::min);
    world / (pixel.0 * t + pixel.1)
}

/// One pixel of a G-buffer, every image's bits.
fn pixel_bits(g: &GBufferData, i: usize) -> Vec<u32> {
    let mut bits = vec![g.depth[i].to_bits()];
    for image in [&g.normal, &g.base, &g.emission] {
        bits.extend(image[i].map(f32::to_bits));
    }
    bits.extend(g.material[i]);
    bits.extend(g.layers[i]);
    bits.extend(g.layers2[i]);
    bits
}

/// A pixel centre this close to a triangle's edge (in pixels) is a tie: the rasterizer's f32
/// homogeneous edge functions and the traversal's watertight test may each decide it either way.
/// (A sub-pixel triangle's edge functions cancel large products: on TransmissionTest one put a
/// centre 0.002 pixels inside it outside.)
const EDGE_PIXELS: f64 = 1.0 / 64.0;

struct Outcome {
    surfaces: usize,
    ties: usize,
    unexplained: Vec<String>,
}

fn compare(gpu: &Gpu, scene: &Scene, camera: &Camera, size: (u32, u32)) -> Option<Outcome> {
    let arrays = SceneArrays::new(scene).unwrap();
    let gpu_scene = GpuScene::from_arrays(gpu, &arrays).unwrap();
    if VisibilityBuffer::unsupported(gpu, &gpu_scene).is_some() {
        return None;
    }
    let passes = Passes::new(gpu, &gpu_scene);
    // One G-buffer, written by both in turn: images a scene leaves unwritten (`layers`,
    // `layers2`) then hold the same bits in both reads.
    let target = GBuffer::new(gpu, size).unwrap();
    let mut vis = VisibilityBuffer::new(gpu, &gpu_scene, size).unwrap();
    gpu.record(|rec| passes.record_gbuffer(rec, &gpu_scene, camera, &target.views())).unwrap();
    let a = target.read(gpu).unwrap();
    loop {
        gpu.record(|rec| passes.record_gbuffer_with(rec, &gpu_scene, camera, &target.views(), Some(&vis)))
            .unwrap();
        match vis.check(gpu).unwrap() {
            Some(entries) => vis.reserve(gpu, entries).unwrap(),
            None => break,
        }
    }
    let b = target.read(gpu).unwrap();
    let visible = vis.read(gpu).unwrap();
    let cam = GpuCamera::new(camera, size);
    // A pixel's width in world units: per unit of distance along a pinhole's ray (roughly: the
    // centre ray's), or flat for an orthographic view.
    let width = 2.0 * glam::Vec3::from(cam.up).length() as f64 / size.1 as f64;
    let pixel = if cam.orthographic() { (0.0, width) } else { (width, 0.0) };
    let mut outcome = Outcome { surfaces: 0, ties: 0, unexplained: Vec::new() };
    for y in 0..size.1 {
        for x in 0..size.0 {
            let i = (y * size.0 + x) as usize;
            if a.material[i][0] != umbra::passes::gbuffer::GBUFFER_NO_SURFACE {
                outcome.surfaces += 1;
            }
            // The visibility buffer's triangle against a CPU traversal's (the same triangle may
            // sit at two BVH positions: compared by its vertices), and the G-buffers' bits: the
            // resolve ray-casts a pixel whose triangle its ray misses, which would hide a wrong
            // triangle in the G-buffer alone.
            let ray = centre_ray(&cam, size, (x, y));
            let tri = visible[i].0;
            let cast = arrays.bvh.closest(&umbra::bvh::traverse::Ray {
                origin: ray.0.as_vec3(),
                dir: ray.1.as_vec3(),
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
            let vertices = |t: u32| arrays.bvh.tris[t as usize].vertices();
            // (The CPU traversal has no alpha test: where it meets an alpha-tested triangle, the
            // G-buffers alone are compared.)
            let alpha_tested = |t: u32| arrays.bvh.tris[t as usize].v1[3].to_bits() != 0;
            let same_triangle = match cast {
                None => tri == RASTER_NO_TRIANGLE,
                Some(h) if alpha_tested(h.tri) => true,
                Some(h) => tri != RASTER_NO_TRIANGLE && vertices(tri) == vertices(h.tri),
            };
            if same_triangle && pixel_bits(&a, i) == pixel_bits(&b, i) {
                continue;
            }
            // A tie: the ray passes within rounding of the rasterized triangle's edge or of the
            // ray-cast one's (each found where the other is), or both lie equally far.
            let near_edge = |tri: u32| edge_distance(&arrays, tri, ray, pixel) < EDGE_PIXELS;
            let raster_edge = tri != RASTER_NO_TRIANGLE && near_edge(tri);
            let cast_edge = cast.is_some_and(|h| near_edge(h.tri));
            let equal_depth = match (cast, tri != RASTER_NO_TRIANGLE) {
                (Some(h), true) => match (plane_hit(&arrays, h.tri, ray), plane_hit(&arrays, tri, ray)) {
                    (Some((ta, _)), Some((tb, _))) => (ta - tb).abs() <= 1e-5 * ta.abs().max(tb.abs()),
                    _ => false,
                },
                _ => false,
            };
            if raster_edge || cast_edge || equal_depth {
                outcome.ties += 1;
            } else {
                outcome.unexplained.push(format!(
                    "{x},{y}: raster triangle {tri} (depth {}, {:.2e} px from an edge), ray cast {:?} ({:.2e} px); depth {} vs {}, material {:?} vs {:?}",
                    visible[i].1,
                    if tri == RASTER_NO_TRIANGLE { f64::NAN } else { edge_distance(&arrays, tri, ray, pixel) },
                    cast.map(|h| (h.tri, h.t)),
                    cast.map_or(f64::NAN, |h| edge_distance(&arrays, h.tri, ray, pixel)),
                    a.depth[i],
                    b.depth[i],
                    a.material[i],
                    b.material[i]
                ));
            }
        }
    }
    Some(outcome)
}

/// On every scene of `scenes/` at a size whose tiles do not divide it, the rasterized G-buffer
/// equals the ray-cast one on every pixel but ties (each justified, at most 1 % of the pixels);
/// the scenes the rasterizer does not draw are named.
#[test]
fn raster_gbuffer_equals_ray_cast_on_every_scene() {
    let gpu = Gpu::new();
    let size = (104, 72);
    let mut failures = Vec::new();
    let mut compared = 0;
    for path in scene_files() {
        let scene = Scene::load(&path).unwrap();
        let camera = scene.camera(None).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let Some(outcome) = compare(&gpu, &scene, &camera, size) else {
            eprintln!(
                "{name}: not rasterized (implicit shapes or blended materials): the G-buffer is ray-cast"
            );
            continue;
        };
        compared += 1;
        eprintln!(
            "{name}: {} surface pixels, {} ties, {} unexplained differences",
            outcome.surfaces,
            outcome.ties,
            outcome.unexplained.len()
        );
        if !outcome.unexplained.is_empty() || outcome.ties * 100 > (size.0 * size.1) as usize {
            failures.push(format!(
                "{name}: {} ties of {} surface pixels; unexplained:\n{}",
                outcome.ties,
                outcome.surfaces,
                outcome.unexplained.iter().take(20).cloned().collect::<Vec<_>>().join("\n")
            ));
        }
    }
    assert!(compared >= 10, "only {compared} scenes compared");
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// Views the rasterizer finds hardest, against the ray cast: from inside the Cornell box, where
/// walls pass behind the camera (a pinhole's triangles with vertices behind it, clipped by the
/// homogeneous edge functions alone) or behind an orthographic camera's plane (cut by depth);
/// each also jittered (anti-aliasing's sub-pixel offsets: the rasterizer covers the pixels'
/// moved sample positions, where the rays go).
#[test]
fn raster_gbuffer_equals_ray_cast_from_inside_the_box() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let (lo, hi) = scene.positions.iter().fold((glam::Vec3::MAX, glam::Vec3::MIN), |(lo, hi), p| {
        (lo.min(glam::Vec3::from(*p)), hi.max(glam::Vec3::from(*p)))
    });
    let centre = (lo + hi) / 2.0;
    let corner = glam::Vec3::new(lo.x, lo.y, hi.z);
    let pinhole = common::camera(
        centre + (corner - centre) * 0.8,
        centre + glam::Vec3::new(0.1, 0.2, -0.3) * (hi - lo),
    );
    let extent = (hi - lo).max_element() / 3.0;
    let orthographic = Camera {
        yfov: 0.0,
        aspect: None,
        orthographic: Some(umbra::scene::Orthographic { xmag: extent, ymag: extent, zfar: 100.0 }),
        ..common::camera(centre, centre + glam::Vec3::new(1.0, -0.2, 0.3))
    };
    let jitter = [0.3125, -0.4375];
    for (name, camera) in [
        ("pinhole", pinhole),
        ("orthographic", orthographic),
        ("jittered pinhole", pinhole.jittered(jitter)),
        ("jittered orthographic", orthographic.jittered(jitter)),
    ] {
        let outcome = compare(&gpu, &scene, &camera, (96, 80)).expect("the Cornell box rasterizes");
        eprintln!("{name}: {} surface pixels, {} ties", outcome.surfaces, outcome.ties);
        // (The box is open at the front.)
        assert!(outcome.surfaces * 3 > 96 * 80, "{name}: the walls fill much of the view");
        assert!(
            outcome.unexplained.is_empty() && outcome.ties * 100 < 96 * 80,
            "{name}: {} ties, unexplained:\n{}",
            outcome.ties,
            outcome.unexplained.join("\n")
        );
    }
}

/// The embedding API's raster G-buffer: a visibility buffer for the raster method (none for the
/// ray cast), recorded into a command buffer of the caller's, equal to the ray-cast G-buffer but
/// for ties (at most 1 % of the pixels); its tile lists held the view.
#[test]
fn embedding_api_records_the_raster_gbuffer() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let camera = scene.camera(None).unwrap();
    let size = (80, 56);
    let renderer = umbra::embed::Renderer::new(&gpu, &scene).unwrap();
    let method = umbra::passes::gbuffer::GBufferMethod::Raycast;
    assert!(renderer.visibility_buffer(size, method).unwrap().is_none(), "no buffer for the ray cast");
    let method = umbra::passes::gbuffer::GBufferMethod::Raster;
    let vis = renderer.visibility_buffer(size, method).unwrap().expect("lavapipe rasterizes");
    let target = GBuffer::new(&gpu, size).unwrap();
    gpu.submit(|cmd| renderer.record_gbuffer(cmd, &camera, &target.views())).unwrap();
    let cast = target.read(&gpu).unwrap();
    gpu.submit(|cmd| renderer.record_gbuffer_with(cmd, &camera, &target.views(), Some(&vis))).unwrap();
    assert_eq!(vis.check(&gpu).unwrap(), None, "the tile lists held the view");
    let raster = target.read(&gpu).unwrap();
    let pixels = (size.0 * size.1) as usize;
    let differ = (0..pixels).filter(|&i| pixel_bits(&cast, i) != pixel_bits(&raster, i)).count();
    let surfaces =
        raster.material.iter().filter(|m| m[0] != umbra::passes::gbuffer::GBUFFER_NO_SURFACE).count();
    assert!(surfaces * 2 > pixels && differ * 100 <= pixels, "{differ} of {pixels} pixels differ");
}
