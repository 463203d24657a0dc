//! BVH build and traversal: structure, CPU and GPU traversal against a brute-force reference,
//! watertightness at shared edges and vertices, and the awkward inputs.

mod common;

use common::Gpu;
use glam::Vec3;
use std::path::Path;
use umbra::bvh::reference::{same_hit, Reference};
use umbra::bvh::{BuildOptions, Bvh, Hit, Ray};
use umbra::gpu::bvh::{GpuBvh, GpuBvhNode, Query, RayTracer};
use umbra::gpu::layout::{TraceHit, TraceRay};
use umbra::procedural::{icosphere, random_soup, terrain, Mesh, Rng};

/// Rays per scene for the GPU-against-reference tests.
const RAYS: usize = 100_000;

/// A mix of rays: a third from anywhere in any direction, a third aimed at a random point of a
/// random triangle, a third axis-aligned (zero direction components) or with a finite segment.
/// Direction lengths vary, since t is in units of the direction.
fn rays(triangles: &[[Vec3; 3]], count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let (lo, hi) =
        triangles.iter().flatten().fold((Vec3::MAX, Vec3::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    let pad = (hi - lo) * 0.2 + Vec3::splat(1e-3);
    let (lo, hi) = (lo - pad, hi + pad);
    (0..count)
        .map(|i| {
            let origin = rng.in_box(lo, hi);
            let scale = rng.range(0.25, 4.0);
            let (dir, tmin, tmax) = match i % 3 {
                0 => (rng.on_sphere(), 0.0, f32::INFINITY),
                1 => {
                    let target = point_on(&triangles[rng.below(triangles.len())], &mut rng);
                    ((target - origin).normalize_or(Vec3::X), 0.0, f32::INFINITY)
                }
                _ => {
                    let axis = Vec3::AXES[rng.below(3)] * if rng.f32() < 0.5 { -1.0 } else { 1.0 };
                    let dir = if rng.f32() < 0.5 { axis } else { rng.on_sphere() };
                    let tmin = rng.range(0.0, 0.5) * (hi - lo).length();
                    (dir, tmin, tmin + rng.range(0.0, 1.0) * (hi - lo).length())
                }
            };
            Ray { origin, dir: dir * scale, tmin: tmin / scale, tmax: tmax / scale }
        })
        .collect()
}

/// A uniformly random point of triangle `t`.
fn point_on(t: &[Vec3; 3], rng: &mut Rng) -> Vec3 {
    let (a, b) = (rng.f32(), rng.f32());
    let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
    t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b
}

/// Whether `got` (BVH order) answers a ray as the reference (input order) does.
fn agrees(bvh: &Bvh, got: Option<Hit>, expected: Option<Hit>) -> bool {
    same_hit(got, expected, |t| bvh.prim_order[t as usize])
}

/// Whether a triangle has zero area in exact arithmetic (checked in f64: its float vertices are
/// exact there): collinear or with coincident vertices.
fn zero_area(t: &[Vec3; 3]) -> bool {
    let [a, b, c] = t.map(|v| v.as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

/// Traces `rays` on the GPU (closest and any), the CPU BVH and the reference, and asserts they
/// all agree; returns the number of hits.
///
/// One tolerance, for the GPU only: a triangle of zero area (collinear vertices) is hit or missed
/// by rounding alone (its sheared projection is a sliver of rounding-error width), and GPUs may
/// divide with up to 2.5 ulp of error (Vulkan's precision rules; the ray's shear is a division),
/// where the CPU rounds correctly. So the GPU may also answer as if zero-area triangles were not
/// there, or hit one of them before the reference's hit; every other triangle must agree exactly.
fn check_scene(gpu: &Gpu, tracer: &RayTracer, name: &str, triangles: &[[Vec3; 3]], rays: &[Ray]) -> usize {
    check_scene_with(gpu, tracer, name, triangles, rays, &BuildOptions::default())
}

/// `check_scene` for a BVH built with `options`.
fn check_scene_with(
    gpu: &Gpu,
    tracer: &RayTracer,
    name: &str,
    triangles: &[[Vec3; 3]],
    rays: &[Ray],
    options: &BuildOptions,
) -> usize {
    let bvh = Bvh::build_with(triangles, options).unwrap();
    gpu_layout_is_valid(&bvh).unwrap_or_else(|e| panic!("{name}: GPU layout: {e}"));
    bvh.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
    let device_bvh = GpuBvh::upload(gpu, &bvh).unwrap();
    let trace_rays: Vec<TraceRay> = rays.iter().map(TraceRay::from).collect();
    let closest = tracer.trace(gpu, Query::Closest, &device_bvh, &trace_rays).unwrap();
    let any = tracer.trace(gpu, Query::Any, &device_bvh, &trace_rays).unwrap();
    let expected = Reference::new(triangles).closest_all(rays);
    let degenerate: Vec<bool> = triangles.iter().map(zero_area).collect();
    // The reference without the zero-area triangles (each replaced by a point, never hit).
    let without: Vec<[Vec3; 3]> =
        triangles.iter().zip(&degenerate).map(|(t, &d)| if d { [t[0]; 3] } else { *t }).collect();
    let expected_without = if degenerate.contains(&true) {
        Reference::new(&without).closest_all(rays)
    } else {
        expected.clone()
    };
    let gpu_agrees = |got: Option<Hit>, i: usize| {
        let on_degenerate = got.is_some_and(|h| degenerate[bvh.prim_order[h.tri as usize] as usize]);
        agrees(&bvh, got, expected[i])
            || agrees(&bvh, got, expected_without[i])
            || (on_degenerate && got.unwrap().t <= expected_without[i].map_or(f32::INFINITY, |h| h.t))
    };

    let mut failures = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let gpu_hit = closest[i].hit();
        let cpu_hit = bvh.closest(ray);
        if !gpu_agrees(gpu_hit, i) {
            failures.push(format!("ray {i} {ray:?}: GPU {gpu_hit:?}, reference {:?}", expected[i]));
        }
        // The CPU BVH does the reference's arithmetic, culls conservatively and keeps its tie
        // rule (the lowest input index of equally near hits), so it gives the very same hit.
        let exact = |h: Option<Hit>, order: &dyn Fn(u32) -> u32| h.map(|h| (order(h.tri), h.t.to_bits()));
        if exact(cpu_hit, &|t| bvh.prim_order[t as usize]) != exact(expected[i], &|t| t) {
            failures.push(format!("ray {i} {ray:?}: CPU BVH {cpu_hit:?}, reference {:?}", expected[i]));
        }
        if (any[i].t == 1.0) != gpu_hit.is_some() {
            failures.push(format!("ray {i} {ray:?}: any-hit {} but closest {gpu_hit:?}", any[i].t));
        }
        if let Some(h) = gpu_hit {
            let [u, v] = h.bary;
            if !(h.t > ray.tmin && h.t < ray.tmax && u >= 0.0 && v >= 0.0 && u + v <= 1.0 + 1e-6) {
                failures.push(format!("ray {i}: GPU hit {h:?} is outside the segment or triangle"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{name}: {} of {} rays disagree; first:\n{}",
        failures.len(),
        rays.len(),
        failures.iter().take(10).cloned().collect::<Vec<_>>().join("\n")
    );
    let hits = expected.iter().filter(|h| h.is_some()).count();
    eprintln!("{name}: {} triangles, {} rays, {hits} hits, {:?}", triangles.len(), rays.len(), bvh.stats);
    hits
}

/// `small` triangles of edge 0.05 in the box ±2 (`random_soup` with `soup_seed`), then `long`
/// slivers across it (0.05 wide, between random points drawn with `seed`).
fn slivers_in_a_cloud(small: usize, long: usize, soup_seed: u64, seed: u64) -> Vec<[Vec3; 3]> {
    let mut slivers = random_soup(small, Vec3::splat(-2.0), Vec3::splat(2.0), 0.05, soup_seed);
    let mut rng = Rng::new(seed);
    for _ in 0..long {
        let (a, b) = (
            rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0)),
            rng.in_box(Vec3::splat(-2.0), Vec3::splat(2.0)),
        );
        slivers.push([a, b, (a + b) * 0.5 + rng.on_sphere() * 0.05]);
    }
    slivers
}

#[test]
fn gpu_closest_hits_match_brute_force_on_several_scenes() {
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let sphere = icosphere(4, Vec3::new(0.2, -0.1, 0.3), 1.5).soup();
    let soup = random_soup(3000, Vec3::splat(-2.0), Vec3::splat(2.0), 0.6, 7);
    let mut big = terrain(300, 100.0, 3).soup(); // 180,000 triangles
    for k in 0..12 {
        let c = Vec3::new(-40.0 + 7.0 * k as f32, 12.0, (k as f32 * 1.7).sin() * 30.0);
        big.extend(icosphere(4, c, 2.0 + k as f32 * 0.3).soup()); // 5,120 each
    }
    assert!(big.len() >= 200_000, "{}", big.len());
    // Long thin triangles across the box among small ones: the case early split clipping is
    // for, so the walk meets pieces of one triangle in several leaves.
    let slivers = slivers_in_a_cloud(2000, 100, 8, 11);
    let split = Bvh::build(&slivers).unwrap().stats;
    assert!(split.references > split.triangles + 100, "{split:?}");
    let scenes = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let cornell = umbra::scene::Scene::cornell_box().triangle_soup();
    let spheres =
        umbra::scene::Scene::load(format!("{scenes}/spheres.glb").as_ref()).unwrap().triangle_soup();
    let instanced =
        umbra::scene::Scene::load(format!("{scenes}/instanced.glb").as_ref()).unwrap().triangle_soup();
    for (name, triangles, seed) in [
        ("icosphere", &sphere, 1),
        ("soup", &soup, 2),
        ("terrain", &big, 3),
        ("cornell box", &cornell, 4),
        ("spheres.glb", &spheres, 5),
        ("instanced.glb", &instanced, 6),
        ("slivers", &slivers, 7),
    ] {
        let rays = rays(triangles, RAYS, seed);
        let hits = check_scene(&gpu, &tracer, name, triangles, &rays);
        assert!(hits > RAYS / 4, "{name}: only {hits} hits; the rays do not exercise the scene");
    }
    // Leaves of up to 300 triangles (node visits made costly): the GPU layout splits each above
    // GpuBvhNode::MAX_LEAF into a subtree of GPU nodes (two levels above 56) sharing its box.
    let options = BuildOptions { max_leaf_size: 300, traversal_cost: 1000.0, ..Default::default() };
    let big_leaves = Bvh::build_with(&soup, &options).unwrap().stats;
    assert!(big_leaves.max_leaf_size > 4 * GpuBvhNode::MAX_LEAF as usize, "{big_leaves:?}");
    check_scene_with(&gpu, &tracer, "soup in large leaves", &soup, &rays(&soup, RAYS, 8), &options);
}

/// Axis-aligned walls (two halves of the scene meeting on z = 0.00149, as Sponza's do on its
/// symmetry plane) and rays that start on their planes or a float off them, many parallel to one
/// or two axes (direction components 0 or 1e-20): where the GPU's quantized boxes and their
/// widened slab test (`bvh.glsl`) are most likely to cut a box the ray touches. The GPU must find every hit
/// the brute-force reference finds beyond the rounding of the origin.
#[test]
fn grazing_and_axis_parallel_rays_on_axis_aligned_walls_match_brute_force() {
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let mut rng = Rng::new(21);
    let planes = [-7.8f32, -2.41851, -0.528511, 0.00149, 0.538988, 3.3, 7.8];
    let mut triangles = Vec::new();
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for &c in &planes {
            for _ in 0..24 {
                // A rectangle on plane `c`, ending on a plane in one direction at times.
                let (mut lo, mut hi) =
                    (rng.in_box(Vec3::splat(-8.0), Vec3::ZERO), rng.in_box(Vec3::ZERO, Vec3::splat(8.0)));
                if rng.f32() < 0.5 {
                    hi[v] = planes[3];
                } else if rng.f32() < 0.5 {
                    lo[v] = planes[3];
                }
                let corner = |a: f32, b: f32| {
                    let mut p = Vec3::splat(c);
                    (p[u], p[v]) = (a, b);
                    p
                };
                let [p00, p10, p11, p01] =
                    [corner(lo[u], lo[v]), corner(hi[u], lo[v]), corner(hi[u], hi[v]), corner(lo[u], hi[v])];
                triangles.extend([[p00, p10, p11], [p00, p11, p01]]);
            }
        }
    }
    let rays: Vec<Ray> = (0..RAYS)
        .map(|i| {
            let mut origin = rng.in_box(Vec3::splat(-9.0), Vec3::splat(9.0));
            // On a plane, or a float either side of it, on one or two axes.
            for _ in 0..1 + i % 2 {
                let (axis, c) = (rng.below(3), planes[rng.below(planes.len())]);
                origin[axis] = match rng.below(3) {
                    0 => c,
                    1 => f32::from_bits(c.to_bits() + 1),
                    _ => f32::from_bits(c.to_bits() - 1),
                };
            }
            // Components 0 or 1e-20 (parallel to an axis: never meeting its walls) or at least
            // 0.1 (a wall met at a grazing angle is ill-conditioned for any triangle test, and
            // the nearest hit there is a matter of rounding, not of the BVH).
            let mut dir = Vec3::from(std::array::from_fn(|_| {
                rng.range(0.1, 1.0) * if rng.f32() < 0.5 { -1.0 } else { 1.0 }
            }));
            for _ in 0..1 + (i / 2) % 2 {
                dir[rng.below(3)] = [0.0, 1e-20, -1e-20][rng.below(3)];
            }
            // tmin above the triangle test's rounding at the origin: a ray from a float off a
            // wall may "hit" it at t = 1e-8 going away from it, a hit no box test can expect.
            Ray { origin, dir, tmin: 1e-4, tmax: f32::INFINITY }
        })
        .collect();
    // Walls cross, and a ray near a crossing meets two of them at about one t, which the triangle
    // test computes only to a few ulps of the walls' coordinates (its t cancels the vertices'
    // distances, Woop et al. 2013), so either may come first: a hit counts as the reference's
    // when it is within 1e-5 (about ten ulps of the coordinates, at most 9) of it along the ray.
    // A box wrongly culled shows as a miss or a hit farther along.
    let bvh = Bvh::build(&triangles).unwrap();
    let device_bvh = GpuBvh::upload(&gpu, &bvh).unwrap();
    let trace_rays: Vec<TraceRay> = rays.iter().map(TraceRay::from).collect();
    let closest = tracer.trace(&gpu, Query::Closest, &device_bvh, &trace_rays).unwrap();
    let any = tracer.trace(&gpu, Query::Any, &device_bvh, &trace_rays).unwrap();
    let expected = Reference::new(&triangles).closest_all(&rays);
    let near = |got: Option<Hit>, want: Option<Hit>, ray: &Ray| match (got, want) {
        (None, None) => true,
        (Some(g), Some(w)) => (g.t - w.t).abs() * ray.dir.length() <= 1e-5,
        _ => false,
    };
    let mut failures = Vec::new();
    for (i, ray) in rays.iter().enumerate() {
        let (gpu_hit, cpu_hit) = (closest[i].hit(), bvh.closest(ray));
        if !near(gpu_hit, expected[i], ray) || !near(cpu_hit, expected[i], ray) {
            failures.push(format!(
                "ray {i} {ray:?}: GPU {gpu_hit:?}, CPU {cpu_hit:?}, reference {:?}",
                expected[i]
            ));
        }
        if (any[i].t == 1.0) != expected[i].is_some() {
            failures.push(format!("ray {i} {ray:?}: any-hit {}, reference {:?}", any[i].t, expected[i]));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} rays disagree; first:\n{}",
        failures.len(),
        rays.len(),
        failures[..failures.len().min(10)].join("\n")
    );
    let hits = expected.iter().filter(|h| h.is_some()).count();
    assert!(hits > RAYS / 2, "only {hits} hits; the rays do not exercise the walls");
}

/// Rays from inside a closed mesh through every vertex and every edge (at several points along
/// it) must hit: a watertight test never lets one slip between neighbouring triangles.
#[test]
fn rays_through_edges_and_vertices_never_leak() {
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let center = Vec3::new(0.31, -0.17, 0.05);
    let mesh: Mesh = icosphere(5, center, 2.0); // 20,480 triangles
    let mut targets: Vec<Vec3> = mesh.positions.clone();
    for [a, b] in mesh.edges() {
        let (a, b) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        targets.extend([0.5f32, 0.25, 0.001].iter().map(|&s| a + (b - a) * s));
    }
    let mut rays = Vec::new();
    for (i, &target) in targets.iter().enumerate() {
        // From the centre, and from points just inside towards the target (all directions).
        let origins = [center, center + (target - center) * 0.9, center + Vec3::new(0.1, 0.2, -0.3)];
        let o = origins[i % 3];
        rays.push(Ray { origin: o, dir: target - o, tmin: 0.0, tmax: f32::INFINITY });
        // From outside, straight at the target: must hit on the way in.
        let outside = center + (target - center) * 3.0;
        rays.push(Ray { origin: outside, dir: target - outside, tmin: 0.0, tmax: f32::INFINITY });
    }
    let soup = mesh.soup();
    let bvh = Bvh::build(&soup).unwrap();
    let device_bvh = GpuBvh::upload(&gpu, &bvh).unwrap();
    let trace_rays: Vec<TraceRay> = rays.iter().map(TraceRay::from).collect();
    let closest = tracer.trace(&gpu, Query::Closest, &device_bvh, &trace_rays).unwrap();
    let any = tracer.trace(&gpu, Query::Any, &device_bvh, &trace_rays).unwrap();
    let gpu_leaks = closest.iter().filter(|h| h.tri == TraceHit::MISS).count();
    let any_leaks = any.iter().filter(|h| h.t != 1.0).count();
    let cpu_leaks = rays.iter().filter(|r| bvh.closest(r).is_none()).count();
    let reference = Reference::new(&soup);
    let reference_leaks = rays.iter().filter(|r| reference.closest(r).is_none()).count();
    assert_eq!(
        (gpu_leaks, any_leaks, cpu_leaks, reference_leaks),
        (0, 0, 0, 0),
        "leaks (GPU closest, GPU any, CPU BVH, brute force) out of {} rays",
        rays.len()
    );
}

#[test]
fn empty_single_and_degenerate_scenes_behave() {
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let down = |x: f32, z: f32| Ray { origin: Vec3::new(x, 5.0, z), dir: -Vec3::Y, tmin: 0.0, tmax: 100.0 };

    // Empty: everything misses, and the BVH is the documented single inverted root.
    let empty = Bvh::build(&[]).unwrap();
    empty.validate().unwrap();
    let device_bvh = GpuBvh::upload(&gpu, &empty).unwrap();
    let hits = tracer.trace(&gpu, Query::Closest, &device_bvh, &[TraceRay::from(&down(0.0, 0.0))]).unwrap();
    assert_eq!(hits[0].tri, TraceHit::MISS);
    assert!(empty.closest(&down(0.0, 0.0)).is_none());

    // A single triangle: a leaf root; hit inside with the right t and barycentrics, miss outside.
    let tri = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 2.0)];
    let single = Bvh::build(&[tri]).unwrap();
    assert_eq!(single.nodes[0].tri_count, 1);
    let device_bvh = GpuBvh::upload(&gpu, &single).unwrap();
    let probe = [down(0.5, 0.5), down(1.5, 1.5), down(0.5, 0.5)];
    let mut probe_rays: Vec<TraceRay> = probe.iter().map(TraceRay::from).collect();
    probe_rays[2].dir_tmax[3] = 3.9; // the segment ends before the triangle at t = 4
    let hits = tracer.trace(&gpu, Query::Closest, &device_bvh, &probe_rays).unwrap();
    assert_eq!(hits[0].tri, 0);
    assert!(
        (hits[0].t - 4.0).abs() < 1e-6 && (hits[0].u - 0.25).abs() < 1e-6 && (hits[0].v - 0.25).abs() < 1e-6
    );
    assert_eq!((hits[1].tri, hits[2].tri), (TraceHit::MISS, TraceHit::MISS));

    // Degenerate triangles (a point, a segment, collinear, repeated) among ordinary ones: the
    // build stays valid, ones with coincident vertices are never hit (their determinant is exactly
    // zero), ordinary ones still are. A collinear triangle rounds to a sliver of non-zero
    // projected area and may be hit along its line; shading must cope with its zero normal.
    let mut triangles = random_soup(500, Vec3::splat(-1.0), Vec3::splat(1.0), 0.3, 11);
    let p = Vec3::new(0.1, 0.2, 0.3);
    for k in 0..200 {
        let q = p + Vec3::splat(k as f32 * 0.01);
        triangles.push(match k % 4 {
            0 => [q; 3],
            1 => [q, q + Vec3::X, q + Vec3::X],
            2 => [q, q + Vec3::X, q + Vec3::X * 2.0],
            _ => triangles[k],
        });
    }
    let rays = rays(&triangles, 30_000, 12);
    check_scene(&gpu, &tracer, "degenerate", &triangles, &rays);
    let bvh = Bvh::build(&triangles).unwrap();
    for ray in &rays {
        if let Some(h) = bvh.closest(ray) {
            let [a, b, c] = bvh.tris[h.tri as usize].vertices();
            assert!(a != b && b != c && c != a, "hit a triangle with coincident vertices: {ray:?}");
        }
    }
    // A scene beyond the GPU layout's reach (about 1e18 across) is refused with the reason.
    let huge =
        Bvh::build(&[tri, [Vec3::splat(-1e19), Vec3::new(1e19, -1e19, 0.0), Vec3::splat(1e19)]]).unwrap();
    let err = GpuBvh::upload(&gpu, &huge).err().expect("a 2e19-wide scene uploaded");
    assert!(err.to_string().contains("within about 1e18"), "{err}");
    // Non-finite input is refused, naming the triangle.
    let err = Bvh::build(&[tri, [Vec3::NAN, Vec3::ZERO, Vec3::ONE]]).unwrap_err();
    assert!(err.to_string().contains("triangle 1"), "{err}");
}

/// The most stack entries the walk of `nodes` from `node` holds along `dir` from the origin when
/// it finds no hit (a hit culls boxes beyond it): at a node, the inner children the ray meets
/// (exact boxes) are visited nearest first, and while the walk is below one of them but the last,
/// the node's entry holds the others. `GpuBvhNode::stack_depth` bounds this over every ray.
fn entries_along(nodes: &[GpuBvhNode], node: usize, dir: glam::DVec3) -> u32 {
    let entry = |(lo, hi): ([f64; 3], [f64; 3])| {
        let (mut near, mut far) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if lo[a] > 0.0 || hi[a] < 0.0 {
                    return None;
                }
                continue;
            }
            let (t0, t1) = (lo[a] / dir[a], hi[a] / dir[a]);
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        (near <= far).then_some(near)
    };
    let n = &nodes[node];
    let mut met: Vec<(f64, usize)> = (0..4)
        .filter(|&c| n.count(c) == 0)
        .filter_map(|c| entry(n.child_box(c).unwrap()).map(|t| (t, n.index(c) as usize)))
        .collect();
    met.sort_by(|a, b| a.0.total_cmp(&b.0));
    let last = met.len().saturating_sub(1);
    met.iter()
        .enumerate()
        .map(|(i, &(_, c))| entries_along(nodes, c, dir) + u32::from(i < last))
        .max()
        .unwrap_or(0)
}

/// Nested clusters (`procedural::nested_clusters`, ratio 0.6, 8, 16 or 32 triangles per level:
/// the first in that order) whose walk holds at most `depth` stack entries
/// (`GpuBvhNode::stack_depth`) and whose walks along some of `directions` (rays from the origin)
/// hold that many: the count of levels and the triangles.
fn nested_clusters_of_depth(depth: u32, directions: &[Vec3]) -> (usize, Vec<[Vec3; 3]>) {
    [8, 16, 32]
        .into_iter()
        .flat_map(|per_level| {
            (1..64).map(move |levels| (levels, umbra::procedural::nested_clusters(levels, per_level, 0.6, 1)))
        })
        .find(|(_, triangles)| {
            let nodes = GpuBvhNode::from_bvh(&Bvh::build(triangles).unwrap()).unwrap();
            GpuBvhNode::stack_depth(&nodes) == depth
                && directions.iter().any(|d| entries_along(&nodes, 0, d.as_dvec3()) == depth)
        })
        .expect("nested clusters of that depth")
}

/// Directions from the origin into the nested clusters (slopes up to 0.25 off +x, the clusters'
/// extent), mostly between their triangles: walks that find no hit, so hold every entry.
fn into_the_clusters(count: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    (0..count).map(|_| Vec3::new(1.0, rng.range(-0.25, 0.25), rng.range(-0.25, 0.25))).collect()
}

/// Both walks of `bvh.glsl`: a BVH whose walk holds at most `BVH_REGISTERS` stack entries is
/// traced with a stack of as many registers as it holds, a deeper one with the stack in memory
/// (`RayTracer` picks by `GpuBvh::register_stack`, as `SceneFeatures::bvh_stack` does for the
/// renderer). Nested clusters whose walks hold 3, 9 and `BVH_REGISTERS` entries (every register
/// used), and four more, must match brute force.
#[test]
fn walks_deeper_and_shallower_than_the_register_stack_match_brute_force() {
    use umbra::gpu::layout::BVH_REGISTERS;
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let directions = into_the_clusters(20_000, 5);
    for (want, deep) in [(3, false), (9, false), (BVH_REGISTERS, false), (BVH_REGISTERS + 4, true)] {
        let (levels, triangles) = nested_clusters_of_depth(want, &directions);
        let device_bvh = GpuBvh::upload(&gpu, &Bvh::build(&triangles).unwrap()).unwrap();
        let depth = device_bvh.stack_depth;
        assert_eq!(depth > BVH_REGISTERS, deep, "{levels} levels: stack depth {depth}");
        assert_eq!(device_bvh.register_stack(), if deep { 0 } else { want }, "{levels} levels");
        // Rays from the origin, at each triangle and into the clusters (some of which hold
        // `want` entries). Only from the origin: every coordinate is as well conditioned for them
        // as the first cluster's, where a ray from elsewhere that passes by the origin meets
        // clusters below its rounding (triangles degenerate in its frame).
        let mut rng = Rng::new(levels as u64);
        let from_origin = |dir| Ray { origin: Vec3::ZERO, dir, tmin: 0.0, tmax: f32::INFINITY };
        let rays: Vec<Ray> = (0..20)
            .flat_map(|_| triangles.iter())
            .map(|t| from_origin(point_on(t, &mut rng)))
            .chain(directions.iter().map(|&d| from_origin(d)))
            .collect();
        let name = format!("nested clusters, {levels} levels, stack depth {depth}");
        let hits = check_scene(&gpu, &tracer, &name, &triangles, &rays);
        assert!(hits >= triangles.len(), "{name}: only {hits} hits");
    }
}

/// The renderer's kernels walk a shallow BVH with a stack of as many registers as its walk holds
/// (`SceneFeatures::bvh_stack`); passes made for a deeper register stack, or for deep BVHs (the
/// stack in memory), walk it too: the three give the very same path traced and hybrid images
/// (G-buffer, ray-traced AO and shadows, lighting), to the bit, on the sphere grid and on nested
/// clusters whose walks fill 3 and every register, seen from the origin.
#[test]
fn register_and_memory_walks_render_the_same_images() {
    use umbra::gpu::layout::BVH_REGISTERS;
    use umbra::gpu::scene::GpuScene;
    use umbra::gpu::SceneFeatures;
    use umbra::passes::ao::AoSettings;
    use umbra::render::{HybridSettings, Passes, PathSettings};
    use umbra::scene::{LightKind, Scene};
    let gpu = Gpu::new();
    let spheres = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spheres.glb")).unwrap();
    // Primary rays from the origin (no near plane to speak of) into the clusters, one per pixel.
    let size = (64, 64);
    let camera = umbra::scene::Camera {
        yfov: 2.0 * 0.25f32.atan(),
        znear: 1e-12,
        ..common::camera(Vec3::ZERO, Vec3::X)
    };
    let directions: Vec<Vec3> = (0..size.0 * size.1)
        .map(|i| {
            let (x, y) = ((i % size.0) as f32 + 0.5, (i / size.0) as f32 + 0.5);
            Vec3::new(1.0, 0.25 - 0.5 * y / size.1 as f32, 0.25 - 0.5 * x / size.0 as f32)
        })
        .collect();
    let bulb = common::light(LightKind::Point, Vec3::new(0.3, 0.4, 0.2), Vec3::ZERO, 2.0);
    // Each with its walk's stack depth and the share of its pixels lit at least (so that no
    // comparison is of black images): the three levels of the shallow clusters fill less of the
    // view.
    let mut scenes = vec![(spheres, 8, 10)];
    for (depth, lit) in [(3, 50), (BVH_REGISTERS, 10)] {
        let (_, nested) = nested_clusters_of_depth(depth, &directions);
        scenes.push((common::build("nested clusters", &[nested], vec![bulb.clone()], camera), depth, lit));
    }
    for (scene, depth, lit_share) in scenes {
        let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let features = gpu_scene.features();
        assert_eq!(features.bvh_stack, depth, "{}", scene.name);
        let exact = Passes::new(&gpu, &gpu_scene);
        let all = Passes::with_features(&gpu, SceneFeatures { bvh_stack: BVH_REGISTERS, ..features });
        let memory = Passes::with_features(&gpu, SceneFeatures { bvh_stack: 0, ..features });
        let path = PathSettings { size, spp: 4, seed: 3, ..PathSettings::default() };
        let hybrid = HybridSettings { size, ao: Some(AoSettings::default()), ..Default::default() };
        let [a, b, c] =
            [&exact, &all, &memory].map(|p| p.path_trace(&gpu_scene, &camera, &path, |_, _| {}).unwrap());
        let lit = a.mean.iter().filter(|p| p[0] > 0.0).count();
        assert!(lit > a.mean.len() / lit_share, "{}: {lit} pixels lit", scene.name);
        let bits = |v: &[[f32; 4]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            bits(&a.mean) == bits(&b.mean),
            "{}: the path tracer's images differ (all registers)",
            scene.name
        );
        assert!(bits(&a.mean) == bits(&c.mean), "{}: the path tracer's images differ (memory)", scene.name);
        let [a, b, c] = [&exact, &all, &memory].map(|p| p.hybrid(&gpu_scene, &camera, &hybrid).unwrap());
        assert!(bits(&a.color) == bits(&b.color), "{}: the hybrid images differ (all registers)", scene.name);
        assert!(bits(&a.color) == bits(&c.color), "{}: the hybrid images differ (memory)", scene.name);
    }
}

/// Passes render a scene whose walk their register stack holds, or any under a stack in memory,
/// and refuse one whose walk needs more registers than they have (`SceneFeatures::renders`).
#[test]
fn passes_refuse_a_bvh_deeper_than_their_register_stack() {
    use umbra::gpu::scene::GpuScene;
    use umbra::gpu::SceneFeatures;
    use umbra::render::{Passes, PathSettings};
    use umbra::scene::Scene;
    let gpu = Gpu::new();
    let spheres = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/spheres.glb")).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &spheres).unwrap();
    let camera = spheres.camera(None).unwrap();
    let features = gpu_scene.features();
    let path = PathSettings { size: (8, 8), spp: 1, ..PathSettings::default() };
    for (stack, fits) in [(features.bvh_stack - 1, false), (features.bvh_stack, true), (0, true)] {
        assert_eq!(
            SceneFeatures { bvh_stack: stack, ..features }.renders(&features),
            fits,
            "{stack} registers"
        );
    }
    let short = Passes::with_features(&gpu, SceneFeatures { bvh_stack: features.bvh_stack - 1, ..features });
    let Err(err) = short.path_trace(&gpu_scene, &camera, &path, |_, _| {}) else {
        panic!("passes with a register short rendered the sphere grid");
    };
    assert!(err.to_string().contains("build new passes"), "{err}");
}

/// Alpha-masked triangles opaque wherever a ray can hit them lose their alpha test, and ones
/// transparent everywhere are never hit: classified from their texels at the upload, and left
/// out of the BVH. On Khronos' TransmissionTest, whose masked triangles fall in all three
/// classes, the path-traced and hybrid images equal those of the same scene with every triangle
/// in the BVH and every masked one tested, to the bit.
#[test]
fn alpha_classes_render_the_images_of_the_alpha_test() {
    use umbra::gpu::layout::ALPHA_NEVER_HIT;
    use umbra::gpu::scene::{GpuScene, SceneArrays};
    use umbra::passes::ao::AoSettings;
    use umbra::render::{HybridSettings, Passes, PathSettings};
    use umbra::scene::{AlphaMode, Scene};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/khronos/TransmissionTest/TransmissionTest.glb");
    let scene = Scene::load(&path).unwrap();
    let gpu = Gpu::new();
    let classified = SceneArrays::new(&scene).unwrap();
    let every = umbra::bvh::Bvh::build(&scene.triangle_soup()).unwrap();
    let mut tested = SceneArrays::with_bvh(&scene, every);
    // Input triangles by class (a triangle split into several references counted once).
    let mut classes = [0usize; 3]; // opaque, never hit, tested
    let mut counted = vec![false; scene.triangles.len()];
    for tri in tested.bvh.tris.iter_mut() {
        let input = tri.v0[3].to_bits() as usize;
        let Some(&m) = scene.triangle_material.get(input) else { continue };
        if scene.materials[m as usize].alpha_mode != AlphaMode::Mask {
            continue;
        }
        if !std::mem::replace(&mut counted[input], true) {
            classes[match tri.v1[3].to_bits() {
                0 => 0,
                ALPHA_NEVER_HIT => 1,
                _ => 2,
            }] += 1;
        }
        tri.v1[3] = f32::from_bits(1);
    }
    assert!(classes.iter().all(|&n| n > 1000), "opaque, never hit, tested: {classes:?}");
    assert_eq!(classified.bvh.stats.left_out, classes[1], "the never-hit triangles are left out");
    assert_eq!(classified.bvh.validate(), Ok(()));
    let [classified, tested] = [&classified, &tested].map(|a| GpuScene::from_arrays(&gpu, a).unwrap());
    let camera = scene.camera(None).unwrap();
    // Passes whose register stack holds both BVHs' walks.
    let stack = classified.features().bvh_stack.max(tested.features().bvh_stack);
    let passes =
        Passes::with_features(&gpu, umbra::gpu::SceneFeatures { bvh_stack: stack, ..classified.features() });
    let path = PathSettings { size: (64, 48), spp: 4, seed: 5, ..PathSettings::default() };
    let hybrid = HybridSettings { size: (64, 48), ao: Some(AoSettings::default()), ..Default::default() };
    let bits = |v: &[[f32; 4]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    let [a, b] = [&classified, &tested].map(|s| passes.path_trace(s, &camera, &path, |_, _| {}).unwrap());
    let differ = a.mean.iter().zip(&b.mean).filter(|(p, q)| bits(&[**p]) != bits(&[**q])).count();
    assert_eq!(differ, 0, "the path tracer's images differ in {differ} pixels");
    let [a, b] = [&classified, &tested].map(|s| passes.hybrid(s, &camera, &hybrid).unwrap());
    assert!(bits(&a.color) == bits(&b.color), "the hybrid images differ");
}

/// The alpha classes' bound on a masked quad (cutoff 0.9) whose texture transform maps it onto
/// texels 0.4 to 1.8 of a 4-texel row, bilinear: every texel it covers is opaque, but a lookup at
/// 1.8 blends in texel 2 (alpha 0.7 there), so it keeps its test; all-opaque texels make it
/// opaque (no test), all-transparent ones never hit. Nearest filtering reaches no further, and
/// the class must not depend on which.
#[test]
fn alpha_classes_bound_what_a_lookup_reads() {
    use umbra::gpu::layout::ALPHA_NEVER_HIT;
    use umbra::gpu::scene::SceneArrays;
    use umbra::scene::{AlphaMode, Filter, Material};
    let gpu = Gpu::new();
    for (texels, want) in [
        ([[255, 255, 255, 255], [255, 255, 255, 255], [255, 255, 255, 0], [255, 255, 255, 0]], 1),
        ([[255, 255, 255, 255]; 4], 0),
        ([[255, 255, 255, 0]; 4], ALPHA_NEVER_HIT),
    ] {
        for filter in [Filter::Linear, Filter::Nearest] {
            let mut texture = common::row_texture("alpha", &texels);
            texture.sampler.mag_filter = filter;
            let mut reference = common::quad::slot().unwrap();
            reference.transform = [[0.35, 0.0, 0.1], [0.0, 1.0, 0.0]];
            let material = Material {
                base_color_texture: Some(reference),
                alpha_mode: AlphaMode::Mask,
                alpha_cutoff: 0.9,
                ..Default::default()
            };
            let scene = common::quad::scene("masked quad", material, Some(texture), 0.0);
            let arrays = SceneArrays::new(&scene).unwrap();
            // Never-hit triangles are left out of the BVH; the others carry their class.
            let classes: Vec<u32> = arrays.alpha.iter().map(|a| a.unwrap_or(ALPHA_NEVER_HIT)).collect();
            assert!(
                classes.len() == 2 && classes.iter().all(|&m| m == want),
                "{texels:?}, {filter:?}: {classes:?}, not {want}"
            );
            let modes: Vec<u32> = arrays.bvh.tris.iter().map(|t| t.v1[3].to_bits()).collect();
            let held = if want == ALPHA_NEVER_HIT { 0 } else { 2 };
            assert!(
                modes.len() == held && modes.iter().all(|&m| m == want),
                "{filter:?}: the BVH holds {modes:?}"
            );
            assert_eq!(arrays.bvh.stats.left_out, 2 - held);
            if want == ALPHA_NEVER_HIT && filter == Filter::Linear {
                // The BVH of no triangles: both renderers see the sky alone, in every pixel.
                for (mode, image) in common::quad::MODES.iter().zip(common::quad::renders(&gpu, &scene, 0.5))
                {
                    assert!(
                        image.iter().all(|p| common::quad::same(p, &[0.5, 0.5, 0.5, 1.0])),
                        "{mode}: {:?}",
                        image[0]
                    );
                }
            }
        }
    }
}

/// A scene update that would move a triangle into or out of the BVH (a transparent masked quad
/// made opaque by its cutoff) or change its class is refused; one that keeps every class (a new
/// base colour) is taken.
#[test]
fn updates_that_move_an_alpha_class_are_refused() {
    use umbra::gpu::scene::GpuScene;
    use umbra::scene::{AlphaMode, Material};
    let gpu = Gpu::new();
    let material = Material {
        base_color_texture: common::quad::slot(),
        alpha_mode: AlphaMode::Mask,
        alpha_cutoff: 0.5,
        ..Default::default()
    };
    let texture = common::row_texture("alpha", &[[255, 255, 255, 0], [255, 255, 255, 100]]);
    let transparent = common::quad::scene("masked quad", material, Some(texture), 0.0);
    let mut gpu_scene = GpuScene::upload(&gpu, &transparent).unwrap();
    assert_eq!(gpu_scene.bvh_stats.left_out, 2);
    let mut recoloured = transparent.clone();
    recoloured.materials[0].base_color_factor = [0.2, 0.4, 0.6, 1.0];
    gpu_scene.update(&gpu, &recoloured).unwrap();
    for (cutoff, class) in [(0.0, "opaque"), (0.2, "tested")] {
        let mut changed = transparent.clone();
        changed.materials[0].alpha_cutoff = cutoff;
        let err =
            gpu_scene.update(&gpu, &changed).err().unwrap_or_else(|| panic!("{class}: taken")).to_string();
        assert!(err.contains("needs a new upload"), "{class}: {err}");
    }
}

/// Property test: random soups of many sizes and spreads (including all-identical triangles
/// and huge next to tiny ones) give valid BVHs: every triangle reachable from the root exactly
/// once, child boxes inside parents, triangles inside leaves, depth bounded.
#[test]
fn random_soups_build_valid_bvhs() {
    let mut rng = Rng::new(99);
    let mut split = 0;
    for case in 0..60 {
        let n = [1, 2, 3, 5, 17, 100, 1000, 5000][case % 8];
        let edge = [1e-4, 0.01, 0.5, 50.0][rng.below(4)];
        let mut triangles = random_soup(n, Vec3::splat(-1.0), Vec3::splat(1.0), edge, case as u64);
        if case % 5 == 0 {
            let t = triangles[0];
            triangles.iter_mut().for_each(|x| *x = t);
        }
        if case % 7 == 0 {
            triangles.push([Vec3::splat(-1e4), Vec3::new(1e4, -1e4, 0.0), Vec3::new(0.0, 1e4, 1e4)]);
        }
        for (full_sweep, spatial) in [(false, None), (true, None), (false, Some(0.0)), (false, Some(1.0))] {
            let defaults = BuildOptions::default();
            let options =
                BuildOptions { full_sweep, spatial: spatial.unwrap_or(defaults.spatial), ..defaults };
            let bvh = Bvh::build_with(&triangles, &options).unwrap();
            bvh.validate().unwrap_or_else(|e| {
                panic!("case {case} (n {n}, sweep {full_sweep}, spatial {spatial:?}): {e}")
            });
            assert_eq!(bvh.stats.triangles, triangles.len());
            assert_eq!(bvh.stats.references, bvh.tris.len());
            // Every input triangle once, or once per piece when pre-split.
            let mut order = bvh.prim_order.clone();
            order.sort_unstable();
            order.dedup();
            assert!(
                order.iter().enumerate().all(|(i, &p)| i as u32 == p),
                "case {case}: an input is missing"
            );
            for (t, &input) in bvh.tris.iter().zip(&bvh.prim_order) {
                assert_eq!(t.input_index(), input);
                assert_eq!(t.vertices(), triangles[input as usize]);
            }
            split += split_triangles_are_covered(&bvh, &mut rng)
                .unwrap_or_else(|e| panic!("case {case} (n {n}): {e}"));
            gpu_layout_is_valid(&bvh).unwrap_or_else(|e| panic!("case {case} (n {n}): GPU layout: {e}"));
        }
        // Built over every third triangle and renumbered: the input's indices, the rest counted
        // as left out, and validation still finds a triangle dropped from a leaf.
        let kept: Vec<u32> = (0..triangles.len() as u32).filter(|t| t % 3 == 1).collect();
        let subset: Vec<[Vec3; 3]> = kept.iter().map(|&t| triangles[t as usize]).collect();
        let mut bvh = Bvh::build(&subset).unwrap();
        bvh.renumber(&kept, triangles.len());
        bvh.validate().unwrap_or_else(|e| panic!("case {case} (n {n}), renumbered: {e}"));
        assert_eq!(
            (bvh.stats.triangles, bvh.stats.left_out),
            (triangles.len(), triangles.len() - kept.len())
        );
        for (t, &input) in bvh.tris.iter().zip(&bvh.prim_order) {
            assert!(input % 3 == 1 && t.input_index() == input && t.vertices() == triangles[input as usize]);
        }
        if bvh.stats.left_out > 0 {
            bvh.stats.left_out -= 1;
            assert!(bvh.validate().is_err(), "case {case}: a left-out triangle passed for a missing one");
        }
    }
    assert!(split > 0, "no case split a triangle: the pieces' coverage went untested");
}

/// Spatial splits (SBVH) on their own, early split clipping off: long thin triangles across a
/// cloud of small ones are cut at the build's planes, so the tree costs less by the SAH, the extra
/// references stay within the budget, every piece's leaf box covers its part of the triangle,
/// and the GPU walk of that tree finds what brute force finds.
#[test]
fn spatial_splits_cut_long_triangles_and_keep_every_piece_covered() {
    let slivers = slivers_in_a_cloud(3000, 150, 31, 32);
    let mut rng = Rng::new(34);
    let plain = BuildOptions { presplit: 0.0, spatial: 0.0, ..Default::default() };
    let unsplit = Bvh::build_with(&slivers, &plain).unwrap().stats;
    assert_eq!(unsplit.references, slivers.len());
    for budget in [0.02, 0.5] {
        let options = BuildOptions { spatial: budget, ..plain.clone() };
        let bvh = Bvh::build_with(&slivers, &options).unwrap();
        let s = &bvh.stats;
        eprintln!("budget {budget}: {s:?}; without spatial splits {unsplit:?}");
        assert!(s.references > slivers.len(), "budget {budget}: no reference was split: {s:?}");
        assert!(
            s.references <= slivers.len() + (slivers.len() as f64 * budget as f64) as usize,
            "budget {budget}: {} references for {} triangles",
            s.references,
            slivers.len()
        );
        assert!(
            s.sah_cost < unsplit.sah_cost,
            "budget {budget}: SAH {} against {}",
            s.sah_cost,
            unsplit.sah_cost
        );
        bvh.validate().unwrap_or_else(|e| panic!("budget {budget}: {e}"));
        let split =
            split_triangles_are_covered(&bvh, &mut rng).unwrap_or_else(|e| panic!("budget {budget}: {e}"));
        assert!(split > 0);
        gpu_layout_is_valid(&bvh).unwrap_or_else(|e| panic!("budget {budget}: GPU layout: {e}"));
    }
    let gpu = Gpu::new();
    let tracer = RayTracer::new(&gpu).unwrap();
    let options = BuildOptions { spatial: 0.5, ..plain };
    let hits = check_scene_with(
        &gpu,
        &tracer,
        "slivers, spatial splits",
        &slivers,
        &rays(&slivers, RAYS, 33),
        &options,
    );
    assert!(hits > RAYS / 4, "only {hits} hits");
}

/// Every point of a triangle split into pieces (its vertices, edge points and random inner
/// points) lies in the box of some leaf holding one of its pieces, so a ray that meets the
/// triangle reaches it. Returns how many triangles were split.
fn split_triangles_are_covered(bvh: &Bvh, rng: &mut Rng) -> Result<usize, String> {
    let mut leaf_boxes: Vec<Vec<(Vec3, Vec3)>> = vec![Vec::new(); bvh.stats.triangles];
    // One BVH position of each input triangle, for its vertices.
    let mut position = vec![0usize; bvh.stats.triangles];
    let mut stack = vec![0usize];
    while let Some(n) = stack.pop() {
        let node = &bvh.nodes[n];
        if node.is_leaf() {
            for t in node.left_first as usize..(node.left_first + node.tri_count) as usize {
                let input = bvh.prim_order[t] as usize;
                leaf_boxes[input].push((node.aabb_min.into(), node.aabb_max.into()));
                position[input] = t;
            }
        } else if node.aabb_min[0] <= node.aabb_max[0] {
            stack.extend([node.left_first as usize, node.left_first as usize + 1]);
        }
    }
    let mut split = 0;
    for (input, boxes) in leaf_boxes.iter().enumerate().filter(|(_, b)| b.len() > 1) {
        split += 1;
        let t = bvh.tris[position[input]].vertices();
        let mut points = t.to_vec();
        for k in 0..3 {
            for f in [0.5, 1.0 / 3.0, 0.999] {
                points.push(t[k] + (t[(k + 1) % 3] - t[k]) * f);
            }
        }
        points.extend((0..200).map(|_| point_on(&t, rng)));
        for p in points {
            if !boxes.iter().any(|&(lo, hi)| p.cmpge(lo).all() && p.cmple(hi).all()) {
                return Err(format!(
                    "point {p} of split triangle {input} {t:?} is in none of its {} leaves",
                    boxes.len()
                ));
            }
        }
    }
    Ok(split)
}

/// The 4-wide GPU layout of `bvh`: every node reachable from the root exactly once, every
/// triangle in exactly one leaf, each leaf's triangles within one leaf of the binary BVH, every
/// child's (quantized) box around all the binary leaves below it, so each box the GPU tests holds
/// all it must, and a node's inner children at consecutive indices (the traversal stack stores
/// the first and offsets).
fn gpu_layout_is_valid(bvh: &Bvh) -> Result<(), String> {
    let nodes = GpuBvhNode::from_bvh(bvh).map_err(|e| e.to_string())?;
    let mut check = LayoutCheck {
        seen_nodes: vec![false; nodes.len()],
        nodes,
        leaves: bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| (n.left_first, (n.tri_count, (n.aabb_min.map(f64::from), n.aabb_max.map(f64::from)))))
            .collect(),
        seen_tris: vec![0; bvh.tris.len()],
    };
    check.subtree(0)?;
    if let Some(n) = check.seen_nodes.iter().position(|s| !s) {
        return Err(format!("node {n} unreachable"));
    }
    match check.seen_tris.iter().position(|&c| c != 1) {
        Some(t) => Err(format!("triangle {t} in {} leaves", check.seen_tris[t])),
        None => Ok(()),
    }
}

type Box3 = ([f64; 3], [f64; 3]);

/// The walk of `gpu_layout_is_valid`.
struct LayoutCheck {
    nodes: Vec<GpuBvhNode>,
    /// The binary BVH's leaves by first triangle: (count, box).
    leaves: std::collections::BTreeMap<u32, (u32, Box3)>,
    seen_nodes: Vec<bool>,
    seen_tris: Vec<u32>,
}

impl LayoutCheck {
    /// Checks GPU node `n`'s subtree; the union of the binary leaves' boxes below it.
    fn subtree(&mut self, n: u32) -> Result<Box3, String> {
        let seen = self.seen_nodes.get_mut(n as usize).ok_or(format!("node {n} out of range"))?;
        if std::mem::replace(seen, true) {
            return Err(format!("node {n} reached twice"));
        }
        let node = self.nodes[n as usize];
        let mut inner: Vec<u32> = (0..4).filter(|&c| node.count(c) == 0).map(|c| node.index(c)).collect();
        inner.sort_unstable();
        if inner.windows(2).any(|w| w[1] != w[0] + 1) {
            return Err(format!("node {n}: inner children {inner:?} not consecutive"));
        }
        let mut all = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for c in 0..4 {
            let Some(quantized) = node.child_box(c) else { continue };
            let (index, count) = (node.index(c), node.count(c));
            let exact = if count == 0 {
                self.subtree(index)?
            } else {
                // A leaf of the binary BVH, or a part of one too large for a GPU leaf.
                let leaf = match self.leaves.range(..=index).next_back() {
                    Some((&first, &(size, leaf))) if index + count <= first + size => leaf,
                    _ => return Err(format!("child {c} of node {n}: triangles {index}+{count} in no leaf")),
                };
                for t in index..index + count {
                    *self.seen_tris.get_mut(t as usize).ok_or(format!("triangle {t} out of range"))? += 1;
                }
                leaf
            };
            if !(0..3).all(|k| quantized.0[k] <= exact.0[k] && exact.1[k] <= quantized.1[k]) {
                return Err(format!("child {c} of node {n}: box {quantized:?} misses {exact:?}"));
            }
            all = (
                std::array::from_fn(|k| all.0[k].min(exact.0[k])),
                std::array::from_fn(|k| all.1[k].max(exact.1[k])),
            );
        }
        Ok(all)
    }
}

/// The binned build's SAH cost stays close to the full-sweep build's on a realistic mesh.
#[test]
fn binned_sah_is_close_to_full_sweep() {
    let mut triangles = terrain(60, 20.0, 5).soup();
    for k in 0..8 {
        triangles.extend(icosphere(3, Vec3::new(k as f32 * 2.0 - 8.0, 2.0, 0.0), 0.7).soup());
    }
    let binned = Bvh::build(&triangles).unwrap();
    let sweep =
        Bvh::build_with(&triangles, &BuildOptions { full_sweep: true, ..Default::default() }).unwrap();
    let ratio = binned.stats.sah_cost / sweep.stats.sah_cost;
    eprintln!("SAH binned {} / sweep {} = {ratio}", binned.stats.sah_cost, sweep.stats.sah_cost);
    assert!(ratio < 1.05, "binned SAH cost {ratio} × the full sweep's");
}
