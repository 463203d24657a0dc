//! Implicit surfaces (`UMBRA_implicit`): the extension parsed and refused with clear errors; the
//! sphere tracer against closed forms (a sphere over 100,000 random rays, a box minus a sphere, a
//! non-uniformly scaled sphere whose step must be relaxed); the step budget running out on grazing
//! rays, counted; and a path-traced implicit sphere against a finely tessellated one.
//!
//! The grazing band: a ray whose chord through the solid is shorter than [`GRAZING_CHORD`] (or
//! that misses it by less than that much, see `gap`) may get the other verdict than the closed
//! form. Sphere tracing cannot resolve a surface it passes within its hit threshold of (2e-5 of
//! the box diagonal), and runs out of steps (128) on rays that skim along a silhouette.

mod common;

use common::Gpu;
use glam::{Mat4, Quat, Vec3};
use gltf::json::Value;
use umbra::gpu::bvh::{GpuBvh, Query, RayTracer};
use umbra::gpu::layout::{TraceHit, TraceRay};
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::procedural::{icosphere, Rng};
use umbra::render::{path_trace, PathImage, PathSettings};
use umbra::scene::{implicit, Camera, Material, Scene};

/// Chords (and near misses) shorter than this fraction of the shape's size are the grazing band.
const GRAZING_CHORD: f64 = 0.05;

/// Hit-distance tolerance outside the grazing band, relative to the shape's size.
const T_TOLERANCE: f64 = 2e-4;

/// The same for CSG: near a crease (a box face meeting the carved sphere) the distance is the
/// nearer of two surfaces', the hit test fires up to the threshold over the sine of the crease's
/// angle early, and the Newton step follows the blended gradient.
const CSG_T_TOLERANCE: f64 = 1e-3;

fn json(text: &str) -> Value {
    serde_json::from_str(text).expect("test JSON")
}

/// A glTF (JSON, no buffers) with one material and one node carrying `implicit`.
fn gltf_with(implicit: &str, node_extra: &str) -> Vec<u8> {
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["UMBRA_implicit"],
        "materials": [{{"pbrMetallicRoughness": {{"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}}}],
        "nodes": [{{"name": "ball" {node_extra}, "extensions": {{"UMBRA_implicit": {implicit}}}}}],
        "scenes": [{{"nodes": [0]}}], "scene": 0}}"#
    )
    .into_bytes()
}

#[test]
fn the_extension_is_parsed_and_bad_input_named() {
    let scene = Scene::from_glb_bytes(
        "ball.gltf",
        &gltf_with(r#"{"sphere": {"radius": 0.5}, "material": 0}"#, r#", "translation": [1, 2, 3]"#),
    )
    .unwrap();
    assert_eq!(scene.implicits.len(), 1);
    let shape = &scene.implicits[0];
    assert_eq!(shape.material, 0);
    assert!((shape.distance(Vec3::new(1.0, 2.0, 3.0)) + 0.5).abs() < 1e-6);
    assert!((shape.distance(Vec3::new(2.0, 2.0, 3.0)) - 0.5).abs() < 1e-6);
    let (lo, hi) = shape.world_bounds().unwrap();
    assert!(lo.cmple(Vec3::new(0.5, 1.5, 2.5)).all() && hi.cmpge(Vec3::new(1.5, 2.5, 3.5)).all());
    // No triangles, yet a scene: its bounds are the shape's.
    assert!(scene.triangles.is_empty());

    let cases = [
        (r#"{"sphere": {}}"#, "sphere.radius is missing"),
        (r#"{"sphere": {"radius": -1}}"#, "radius must be positive"),
        (r#"{"sphere": {"radius": 1}, "material": 1}"#, "'material' is 1, but the file has 1 material"),
        (r#"{"sphere": {"radius": 1}, "box": {"halfExtents": [1, 1, 1]}}"#, "give exactly one"),
        (r#"{"sphre": {"radius": 1}}"#, "unknown property 'sphre'"),
        (
            r#"{"subtraction": [{"box": {"halfExtents": [1, 1]}}, {"sphere": {"radius": 1}}]}"#,
            "subtraction[0].box.halfExtents must have 3",
        ),
        (r#"{"union": [{"sphere": {"radius": 1}}]}"#, "at least two"),
        (r#"{"plane": {"normal": [0, 1, 0]}}"#, "unbounded"),
        (r#"{"union": [{"sphere": {"radius": 1}, "scale": 0}, {"sphere": {"radius": 1}}]}"#, "uniform scale"),
    ];
    for (text, expected) in cases {
        let err = Scene::from_glb_bytes("bad.gltf", &gltf_with(text, "")).unwrap_err().to_string();
        assert!(err.contains("bad.gltf"), "{err}");
        assert!(err.contains("node 0 ('ball')"), "{err}");
        assert!(err.contains(expected), "{text}: {err}");
    }

    // A subtraction that removes the whole shape renders nothing: loaded with a warning naming
    // the node (an intersection of parts whose boxes do not meet is refused, above); a box minus
    // a smaller sphere, a union, and a thin slab warn of nothing.
    let warnings = |text: &str| Scene::from_glb_bytes("csg.gltf", &gltf_with(text, "")).unwrap().warnings;
    for empty in [
        r#"{"subtraction": [{"sphere": {"radius": 0.5}}, {"box": {"halfExtents": [1, 1, 1]}}]}"#,
        r#"{"subtraction": [{"box": {"halfExtents": [0.5, 0.5, 0.5]}}, {"sphere": {"radius": 1}}]}"#,
        r#"{"subtraction": [{"sphere": {"radius": 0.5}}, {"sphere": {"radius": 0.6}, "translation": [0.05, 0, 0]}]}"#,
    ] {
        let w = warnings(empty);
        assert!(
            w.iter().any(|w| w.contains("node 0 ('ball')") && w.contains("empty everywhere")),
            "{empty}: {w:?}"
        );
    }
    for solid in [
        r#"{"subtraction": [{"box": {"halfExtents": [1, 1, 1]}}, {"sphere": {"radius": 0.9}}]}"#,
        r#"{"union": [{"sphere": {"radius": 0.5}}, {"sphere": {"radius": 0.5}, "translation": [3, 0, 0]}]}"#,
        r#"{"intersection": [{"box": {"halfExtents": [1, 1, 1]}}, {"box": {"halfExtents": [1, 1, 0.001]}}]}"#,
    ] {
        let w = warnings(solid);
        assert!(!w.iter().any(|w| w.contains("empty everywhere")), "{solid}: {w:?}");
    }
}

/// A scene of one shape at `world` (no triangles).
fn shape_scene(text: &str, world: Mat4) -> Scene {
    let mut scene = Scene { name: "implicit test".into(), ..Default::default() };
    scene.materials.push(Material::default());
    scene.implicits.push(implicit::from_json("shape", &json(text), world, 1).unwrap());
    scene
}

/// Traces `rays` through `scene`'s BVH with the implicit shapes marched.
fn trace(gpu: &Gpu, scene: &Scene, rays: &[TraceRay], query: Query) -> Vec<TraceHit> {
    let arrays = SceneArrays::new(scene).unwrap();
    let bvh = GpuBvh::upload(gpu, &arrays.bvh).unwrap();
    assert!(bvh.implicit);
    RayTracer::with_implicit(gpu, true).unwrap().trace(gpu, query, &bvh, rays).unwrap()
}

/// Rays from a box around the shape (`half` each way), half aimed at a random point within
/// `aim` of the centre, half in a random direction; direction lengths vary.
fn random_rays(count: usize, half: f32, aim: f32, seed: u64) -> Vec<TraceRay> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|i| {
            let origin = rng.in_box(Vec3::splat(-half), Vec3::splat(half));
            let dir = if i % 2 == 0 {
                (rng.in_box(Vec3::splat(-aim), Vec3::splat(aim)) - origin).normalize_or(Vec3::X)
            } else {
                rng.on_sphere()
            };
            let scale = rng.range(0.5, 2.0);
            TraceRay {
                origin_tmin: origin.extend(0.0).into(),
                dir_tmax: (dir * scale).extend(f32::INFINITY).into(),
            }
        })
        .collect()
}

/// The closed form's answer for a ray: the first entry into the solid after tmin (`t`), and the
/// length of the solid interval it enters (or, for a miss, how near it came: negative).
#[derive(Clone, Copy, Debug)]
struct Exact {
    t: Option<f64>,
    chord: f64,
    /// In the grazing band for another reason (an edge of a CSG shape).
    band: bool,
}

/// The ray's interval inside the sphere of radius r at the origin (f64), and its nearest approach.
fn sphere_interval(o: [f64; 3], d: [f64; 3], r: f64) -> (Option<(f64, f64)>, f64) {
    let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let od = o[0] * d[0] + o[1] * d[1] + o[2] * d[2];
    let oo = o[0] * o[0] + o[1] * o[1] + o[2] * o[2];
    let b = od / dd;
    let c = (oo - r * r) / dd;
    let disc = b * b - c;
    let nearest = (oo - od * od / dd).max(0.0).sqrt();
    if disc < 0.0 {
        return (None, nearest);
    }
    let s = disc.sqrt();
    (Some((-b - s, -b + s)), nearest)
}

fn f64s(v: [f32; 4]) -> ([f64; 3], f64) {
    ([v[0] as f64, v[1] as f64, v[2] as f64], v[3] as f64)
}

/// The first entry into [a0, a1] (a solid's interval on the ray) at or after `tmin`, if any:
/// tmin itself when the ray starts inside, which the marcher reports as the exit (it starts on the
/// inside and hits the surface from there).
fn entry(interval: (f64, f64), tmin: f64) -> Option<(f64, f64)> {
    let (a0, a1) = interval;
    if a1 <= tmin {
        None
    } else if a0 > tmin {
        Some((a0, a1 - a0))
    } else {
        Some((a1, a1 - tmin)) // inside: the surface ahead is the exit
    }
}

/// Verdicts and distances of `hits` against `exact`, `size` the shape's size. Returns the
/// mismatches outside the band and a summary line.
fn compare(
    hits: &[TraceHit],
    rays: &[TraceRay],
    exact: &[Exact],
    size: f64,
    tolerance: f64,
) -> (usize, usize, String) {
    let mut bad = 0;
    let (mut in_band, mut disagree_in_band, mut max_err, mut max_err_band, mut both) =
        (0, 0, 0.0f64, 0.0f64, 0);
    let mut exhausted = 0.0f64;
    let mut out_of_steps = 0usize;
    let mut first_bad = None;
    for ((h, ray), e) in hits.iter().zip(rays).zip(exact) {
        let len = Vec3::from_slice(&ray.dir_tmax[..3]).length() as f64;
        let band = e.band || e.chord.abs() < GRAZING_CHORD * size;
        in_band += band as usize;
        let got = (h.tri != TraceHit::MISS).then_some(h.t as f64);
        if h.tri == TraceHit::MISS {
            exhausted += h.u as f64;
        }
        match (got, e.t) {
            (Some(t), Some(x)) => {
                both += 1;
                let err = (t - x).abs() * len / size;
                if band {
                    max_err_band = max_err_band.max(err);
                } else {
                    max_err = max_err.max(err);
                    if err > tolerance {
                        bad += 1;
                        if err >= max_err {
                            first_bad = Some((*ray, *h, *e));
                        }
                    }
                }
            }
            (None, None) => {}
            // A march out of steps: a miss by design, counted, not a wrong answer.
            (None, Some(_)) if h.u >= 1.0 => out_of_steps += 1,
            _ => {
                if band {
                    disagree_in_band += 1;
                } else {
                    bad += 1;
                    first_bad.get_or_insert((*ray, *h, *e));
                }
            }
        }
    }
    let summary = format!(
        "{} rays, {both} hit in both; outside the band: {bad} wrong, largest |Δt|·|d| {max_err:.2e} × size; \
         grazing band: {in_band} rays, {disagree_in_band} other verdicts, \
         largest |Δt| {max_err_band:.2e} × size; marches out of steps: {exhausted} ({out_of_steps} of them on rays \
         the closed form hits); worst or first wrong: {first_bad:?}",
        rays.len()
    );
    (bad, out_of_steps, summary)
}

fn sphere_exact(rays: &[TraceRay], r: f64) -> Vec<Exact> {
    rays.iter()
        .map(|ray| {
            let (o, tmin) = f64s(ray.origin_tmin);
            let (d, _) = f64s(ray.dir_tmax);
            let dl = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            match sphere_interval(o, d, r) {
                (Some(i), _) => match entry(i, tmin) {
                    Some((t, chord)) => Exact { t: Some(t), chord: chord * dl, band: false },
                    None => Exact { t: None, chord: f64::INFINITY, band: false },
                },
                (None, nearest) => Exact { t: None, chord: -(nearest - r), band: false },
            }
        })
        .collect()
}

#[test]
fn implicit_sphere_matches_the_analytic_sphere() {
    let gpu = Gpu::new();
    let scene = shape_scene(r#"{"sphere": {"radius": 1.0}}"#, Mat4::IDENTITY);
    let rays = random_rays(100_000, 2.5, 1.2, 1);
    let exact = sphere_exact(&rays, 1.0);
    let hits = trace(&gpu, &scene, &rays, Query::Closest);
    let (bad, out_of_steps, summary) = compare(&hits, &rays, &exact, 1.0, T_TOLERANCE);
    println!("sphere, closest hit: {summary}");
    assert_eq!(bad, 0, "{summary}");
    assert!(out_of_steps <= 100, "{summary}");
    // Any hit (shadow rays): occluded exactly where the closed form has a hit, outside the band.
    let any = trace(&gpu, &scene, &rays, Query::Any);
    let wrong = any
        .iter()
        .zip(&exact)
        .filter(|(h, e)| e.chord.abs() >= GRAZING_CHORD && (h.t == 1.0) != e.t.is_some())
        .count();
    println!("sphere, any hit: {wrong} other verdicts outside the band");
    assert_eq!(wrong, 0);
}

/// A box of half extents 1 minus a sphere of radius 1.3, both at the origin (the corners
/// remain): on a ray, the box's interval minus the sphere's, whose first piece is the answer.
#[test]
fn box_minus_sphere_matches_its_closed_form() {
    let gpu = Gpu::new();
    let scene = shape_scene(
        r#"{"subtraction": [{"box": {"halfExtents": [1, 1, 1]}}, {"sphere": {"radius": 1.3}}]}"#,
        Mat4::IDENTITY,
    );
    let rays = random_rays(100_000, 2.5, 1.0, 2);
    // A ray through an edge of the solid (where the box's faces meet the sphere) may go either
    // way: in the band when growing the solid by 1e-3 and shrinking it by 1e-3 disagree.
    let exact: Vec<Exact> = rays
        .iter()
        .map(|ray| {
            let (o, tmin) = f64s(ray.origin_tmin);
            let (d, _) = f64s(ray.dir_tmax);
            let dl = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            let at = |grow: f64| box_minus_sphere(o, d, tmin, 1.0 + grow, 1.3 - grow);
            let (grown, shrunk) = (at(1e-3), at(-1e-3));
            let band = match (grown, shrunk) {
                (Some((a, _)), Some((b, _))) => (a - b).abs() * dl > 0.01,
                (None, None) => false,
                _ => true,
            };
            match at(0.0) {
                Some((t, chord)) => Exact { t: Some(t), chord: chord * dl, band },
                None => Exact { t: None, chord: f64::INFINITY, band },
            }
        })
        .collect();
    let hits = trace(&gpu, &scene, &rays, Query::Closest);
    let (bad, out_of_steps, summary) = compare(&hits, &rays, &exact, 2.0, CSG_T_TOLERANCE);
    println!("box minus sphere: {summary}");
    assert_eq!(bad, 0, "{summary}");
    assert!(out_of_steps <= 100, "{summary}");
}

/// The first entry at or after tmin into the box of half extents `half` minus the sphere of
/// radius `r` (both at the origin) and its solid piece's length: the box's slab interval minus the
/// sphere's, in closed form.
fn box_minus_sphere(o: [f64; 3], d: [f64; 3], tmin: f64, half: f64, r: f64) -> Option<(f64, f64)> {
    let (mut a0, mut a1) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let (t0, t1) = ((-half - o[k]) / d[k], (half - o[k]) / d[k]);
        a0 = a0.max(t0.min(t1));
        a1 = a1.min(t0.max(t1));
    }
    if a0 > a1 {
        return None;
    }
    let mut pieces = Vec::new();
    match sphere_interval(o, d, r).0 {
        Some((b0, b1)) => {
            if a0 < b0 {
                pieces.push((a0, a1.min(b0)));
            }
            if b1 < a1 {
                pieces.push((a0.max(b1), a1));
            }
        }
        None => pieces.push((a0, a1)),
    }
    pieces.into_iter().filter(|&(p0, p1)| p1 > p0).find_map(|p| entry(p, tmin))
}

/// The ray in the sphere's local frame for a node scaled by `s` (axis-aligned): hits at the same t.
fn ellipsoid_exact(rays: &[TraceRay], s: Vec3) -> Vec<Exact> {
    rays.iter()
        .map(|ray| {
            let o = Vec3::from_slice(&ray.origin_tmin[..3]) / s;
            let d = Vec3::from_slice(&ray.dir_tmax[..3]) / s;
            let local = TraceRay {
                origin_tmin: o.extend(ray.origin_tmin[3]).into(),
                dir_tmax: d.extend(ray.dir_tmax[3]).into(),
            };
            let e = sphere_exact(&[local], 1.0)[0];
            // Chords in world units: the local chord scaled by the smallest and largest axes
            // brackets it; the smallest keeps the band conservative.
            Exact { t: e.t, chord: e.chord * s.min_element() as f64, band: false }
        })
        .collect()
}

/// A sphere squashed to an ellipsoid by its node (scale 1, 0.25, 1): the local distance is no
/// longer a bound of the world distance, and the march must step by it times the smallest scale
/// (the step relaxed by the transform's Lipschitz bound). Stepping by the local distance as if
/// it were exact overshoots: hits beyond the surface, and rays through it.
#[test]
fn a_non_uniform_scale_needs_the_relaxed_step() {
    let gpu = Gpu::new();
    let s = Vec3::new(1.0, 0.25, 1.0);
    let world = Mat4::from_scale_rotation_translation(s, Quat::IDENTITY, Vec3::ZERO);
    let mut scene = shape_scene(r#"{"sphere": {"radius": 1.0}}"#, world);
    assert!((scene.implicits[0].step_scale - 0.25).abs() < 1e-5, "{}", scene.implicits[0].step_scale);
    let rays = random_rays(20_000, 2.0, 0.8, 3);
    let exact = ellipsoid_exact(&rays, s);
    let hits = trace(&gpu, &scene, &rays, Query::Closest);
    let (bad, out_of_steps, summary) = compare(&hits, &rays, &exact, 1.0, T_TOLERANCE);
    println!("ellipsoid, relaxed step: {summary}");
    assert_eq!(bad, 0, "{summary}");
    assert!(out_of_steps <= 100, "{summary}");
    scene.implicits[0].step_scale = 1.0;
    let hits = trace(&gpu, &scene, &rays, Query::Closest);
    let (overshoot, _, summary) = compare(&hits, &rays, &exact, 1.0, T_TOLERANCE);
    println!("ellipsoid, step not relaxed: {summary}");
    assert!(overshoot > 100, "the unrelaxed step should overshoot: {summary}");
}

/// Rays that pass the unit sphere just outside its silhouette (1e-4 of the radius away) creep
/// along it in tiny steps: the budget runs out, the ray is taken as a miss, and the count says so.
#[test]
fn grazing_rays_exhaust_the_step_budget_and_are_counted() {
    let gpu = Gpu::new();
    let scene = shape_scene(r#"{"sphere": {"radius": 1.0}}"#, Mat4::IDENTITY);
    let mut rng = Rng::new(4);
    let rays: Vec<TraceRay> = (0..1000)
        .map(|i| {
            // Passing at distance b from the centre, tangent-ish, from far off.
            let b = if i % 2 == 0 { 1.0 + 1e-4 } else { 1.2 };
            let n = rng.on_sphere();
            let d = n.any_orthonormal_vector();
            let origin = n * b - d * 3.0;
            TraceRay { origin_tmin: origin.extend(0.0).into(), dir_tmax: d.extend(f32::INFINITY).into() }
        })
        .collect();
    let hits = trace(&gpu, &scene, &rays, Query::Closest);
    let close: Vec<&TraceHit> = hits.iter().step_by(2).collect();
    let far: Vec<&TraceHit> = hits.iter().skip(1).step_by(2).collect();
    let exhausted = close.iter().filter(|h| h.tri == TraceHit::MISS && h.u >= 1.0).count();
    println!("grazing at 1e-4: {exhausted} of {} marches ran out of steps", close.len());
    assert!(close.iter().chain(&far).all(|h| h.tri == TraceHit::MISS), "a grazing ray hit");
    assert!(exhausted >= close.len() * 9 / 10, "{exhausted} of {}", close.len());
    assert!(far.iter().all(|h| h.u == 0.0), "a ray 0.2 away ran out of steps");
}

// ---------------------------------------------------------------------------------------------
// The path tracer: an implicit sphere against a finely tessellated one.

fn lambert(albedo: f32) -> Material {
    Material {
        base_color_factor: [albedo, albedo, albedo, 1.0],
        metallic: 0.0,
        roughness: 1.0,
        ..Default::default()
    }
}

/// A unit sphere above a floor, a point light and a grey sky: the sphere `implicit`, or an
/// icosphere of `subdivisions` (20·4^s triangles) with the sphere's normals.
fn sphere_on_floor(implicit: bool, subdivisions: u32) -> Scene {
    let mut scene = Scene { name: "sphere on a floor".into(), ..Default::default() };
    scene.materials = vec![lambert(0.5), lambert(0.8)];
    let mut add = |tris: Vec<[Vec3; 3]>, normal: &dyn Fn(Vec3, Vec3) -> Vec3, material: u32| {
        for t in tris {
            let face = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let base = scene.positions.len() as u32;
            for v in t {
                scene.positions.push(v.into());
                scene.normals.push(normal(v, face).into());
            }
            scene.triangles.push([base, base + 1, base + 2]);
            scene.triangle_material.push(material);
        }
    };
    let floor = common::quad(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.0, 0.0, 4.0), Vec3::new(4.0, 0.0, 0.0));
    add(floor, &|_, f| f, 0);
    let centre = Vec3::new(0.0, 0.05, 0.0);
    if implicit {
        scene.implicits.push(
            implicit::from_json(
                "ball",
                &json(r#"{"sphere": {"radius": 1.0}, "material": 1}"#),
                Mat4::from_translation(centre),
                2,
            )
            .unwrap(),
        );
    } else {
        add(icosphere(subdivisions, centre, 1.0).soup(), &|v, _| (v - centre).normalize(), 1);
    }
    scene.lights.push(umbra::scene::Light {
        name: "bulb".into(),
        kind: umbra::scene::LightKind::Point,
        position: [2.0, 3.0, 2.0],
        direction: [0.0, -1.0, 0.0],
        color: [1.0; 3],
        intensity: 20.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::FRAC_PI_4,
    });
    scene.cameras.push(Camera {
        position: [0.0, 1.0, 4.5],
        forward: Vec3::new(0.0, -1.0, -4.5).normalize().into(),
        up: [0.0, 1.0, 0.0],
        yfov: 40f32.to_radians(),
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    });
    scene.update_emissive();
    scene
}

fn render(gpu: &Gpu, scene: &Scene, spp: u32, seed: u32) -> PathImage {
    let device_scene = GpuScene::upload(gpu, scene).unwrap();
    let settings = PathSettings {
        size: (48, 48),
        spp,
        seed,
        max_bounces: 4,
        env: [0.3, 0.3, 0.3],
        ..PathSettings::default()
    };
    let image = path_trace(gpu, &device_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0);
    image
}

/// Per-pixel z-scores of the difference of two images' means (luminance-free: the green channel,
/// all channels being grey here), from their per-pixel variances.
fn z_scores(a: &PathImage, b: &PathImage) -> Vec<f64> {
    a.mean
        .iter()
        .zip(&a.moment)
        .zip(b.mean.iter().zip(&b.moment))
        .map(|((ma, qa), (mb, qb))| {
            let var = |m: f32, q: f32, n: u32| ((q - m * m).max(0.0) as f64) / (n as f64 - 1.0).max(1.0);
            let v = var(ma[1], qa[1], a.spp) + var(mb[1], qb[1], b.spp);
            let d = (ma[1] - mb[1]) as f64;
            if v > 0.0 {
                d / v.sqrt()
            } else if d == 0.0 {
                0.0
            } else {
                f64::INFINITY
            }
        })
        .collect()
}

/// The two-sided p-value of a standard normal z.
fn p_value(z: f64) -> f64 {
    // erfc(|z| / √2) through the regularised incomplete gamma: Q(1/2, z²/2).
    common::gamma_q(0.5, 0.5 * z * z)
}

/// The path-traced implicit sphere and an icosphere of 327,680 triangles (its silhouette within
/// 7e-6 of the radius of the sphere's) give the same image within noise: per pixel z-test of the
/// means, significance 0.01 over the image with a Šidák correction.
#[test]
fn path_traced_implicit_sphere_matches_a_tessellated_one() {
    let gpu = Gpu::new();
    let spp = 64;
    let implicit = render(&gpu, &sphere_on_floor(true, 0), spp, 1);
    let mesh = render(&gpu, &sphere_on_floor(false, 7), spp, 2);
    let z = z_scores(&implicit, &mesh);
    let alpha = 1.0 - (1.0 - 0.01f64).powf(1.0 / z.len() as f64);
    let worst = z.iter().enumerate().map(|(i, z)| (p_value(*z), i, *z)).fold((1.0, 0, 0.0), |a, b| {
        if b.0 < a.0 {
            b
        } else {
            a
        }
    });
    let mean_z = z.iter().sum::<f64>() / (z.len() as f64).sqrt();
    println!(
        "implicit vs tessellated: {} pixels, worst p {:.3e} (z {:.2}) at pixel {}, Šidák threshold {alpha:.3e}; \
         sum of z / sqrt(n) = {mean_z:.2}; marches out of steps: {}; GPU ms implicit {:.0}, mesh {:.0}",
        z.len(),
        worst.0,
        worst.2,
        worst.1,
        implicit.marches_exhausted,
        implicit.gpu_ms,
        mesh.gpu_ms
    );
    assert!(worst.0 > alpha, "pixel {} differs beyond noise: z = {:.2}", worst.1, worst.2);
    assert!(mean_z.abs() < 4.0, "the images differ on the whole: {mean_z:.2}");
    assert_eq!(mesh.marches_exhausted, 0);
}

/// Every primitive and the smooth operations, against the CPU's distance (`ImplicitShape::distance`,
/// the same formulas): each hit lies on the surface (|distance| ≤ 1e-3), and sampling the ray
/// densely up to the hit (or through the whole box on a miss) finds no point deeper inside than
/// 1e-3, so the march skipped no surface.
#[test]
fn every_primitive_and_smooth_operation_is_marched() {
    let gpu = Gpu::new();
    let shapes = [
        r#"{"torus": {"majorRadius": 0.8, "minorRadius": 0.25}}"#,
        r#"{"capsule": {"halfHeight": 0.5, "radius": 0.3}}"#,
        r#"{"cylinder": {"halfHeight": 0.6, "radius": 0.5}}"#,
        r#"{"roundedBox": {"halfExtents": [0.8, 0.5, 0.6], "radius": 0.15}}"#,
        r#"{"intersection": [{"sphere": {"radius": 1}}, {"plane": {"normal": [1, 1, 0], "offset": 0.2}}]}"#,
        r#"{"union": [{"sphere": {"radius": 0.5}, "translation": [-0.4, 0, 0]},
                       {"box": {"halfExtents": [0.3, 0.3, 0.3]}, "translation": [0.4, 0, 0], "rotation": [0, 0, 0.38268343, 0.9238795]}],
            "smoothness": 0.3}"#,
        r#"{"subtraction": [{"cylinder": {"halfHeight": 0.5, "radius": 0.8}},
                             {"capsule": {"halfHeight": 1, "radius": 0.3}, "rotation": [0.7071068, 0, 0, 0.7071068], "scale": 1.5}],
            "smoothness": 0.2}"#,
    ];
    for (k, text) in shapes.iter().enumerate() {
        let world = Mat4::from_scale_rotation_translation(
            Vec3::splat(1.3),
            Quat::from_rotation_y(0.3 * k as f32),
            Vec3::new(0.1, -0.2, 0.05),
        );
        let scene = shape_scene(text, world);
        let shape = &scene.implicits[0];
        let (lo, hi) = shape.world_bounds().unwrap();
        let rays = random_rays(4000, 2.5, 0.8, 10 + k as u64);
        let hits = trace(&gpu, &scene, &rays, Query::Closest);
        let (mut off_surface, mut skipped, mut hit_count, mut out_of_steps) = (0, 0, 0, 0);
        for (h, ray) in hits.iter().zip(&rays) {
            let o = Vec3::from_slice(&ray.origin_tmin[..3]);
            let d = Vec3::from_slice(&ray.dir_tmax[..3]);
            // The ray's span in the box.
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            let (t0, t1) = (a.min(b).max_element().max(0.0), a.max(b).min_element());
            if h.tri == TraceHit::MISS && h.u >= 1.0 {
                out_of_steps += 1;
                continue;
            }
            let end = if h.tri != TraceHit::MISS {
                hit_count += 1;
                if shape.distance(o + h.t * d).abs() > 1e-3 {
                    off_surface += 1;
                }
                h.t
            } else {
                t1
            };
            // Starting inside, the first surface is the way out: only rays that start outside.
            if t0 < end && shape.distance(o + t0 * d) > 0.0 {
                let n = 2000;
                if (0..n).any(|i| shape.distance(o + (t0 + (end - t0) * i as f32 / n as f32) * d) < -1e-3) {
                    skipped += 1;
                }
            }
        }
        println!("shape {k}: {hit_count} hits of 4000 rays, {off_surface} off the surface, {skipped} skipped a surface, {out_of_steps} out of steps");
        assert!(hit_count > 500, "shape {k}: {hit_count} hits");
        assert_eq!(off_surface, 0, "shape {k}: {text}");
        assert_eq!(skipped, 0, "shape {k}: {text}");
        assert!(out_of_steps <= 20, "shape {k}: {out_of_steps} out of steps");
    }
}

/// Fraction of `a`'s surface pixels whose 3×3 neighbourhood is all surface in both G-buffers (away
/// from silhouettes, where one ray per pixel may hit one sphere and miss the other).
fn interior(a: &umbra::passes::gbuffer::GBufferData, b: &umbra::passes::gbuffer::GBufferData) -> Vec<bool> {
    use umbra::passes::gbuffer::GBUFFER_NO_SURFACE;
    let (w, h) = a.size;
    let surface = |g: &umbra::passes::gbuffer::GBufferData, x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < w as i64
            && y < h as i64
            && g.material[(y * w as i64 + x) as usize][0] != GBUFFER_NO_SURFACE
    };
    (0..(w * h) as i64)
        .map(|i| {
            let (x, y) = (i % w as i64, i / w as i64);
            (-1..=1).all(|dy| (-1..=1).all(|dx| surface(a, x + dx, y + dy) && surface(b, x + dx, y + dy)))
        })
        .collect()
}

/// The hybrid renderer sees the implicit sphere as it sees the tessellated one: the G-buffer's
/// depth, normal and material, the deferred lighting with its shadow ray, and ray-traced AO agree
/// pixel by pixel away from the silhouettes (one ray per pixel through the pixel centre, so no
/// noise: the tolerances are those of the 327,680-triangle tessellation and of half floats).
#[test]
fn hybrid_and_rtao_see_the_implicit_sphere() {
    use umbra::passes::ao::AoSettings;
    use umbra::render::{ambient_occlusion, hybrid, AoMethod, HybridSettings};
    let gpu = Gpu::new();
    let size = (48, 48);
    let scenes = [sphere_on_floor(true, 0), sphere_on_floor(false, 7)];
    let mut images = Vec::new();
    let mut aos = Vec::new();
    for scene in &scenes {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        let camera = scene.camera(None).unwrap();
        images
            .push(hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size, ..Default::default() }).unwrap());
        let settings = AoSettings { samples: 64, ..AoSettings::of(AoMethod::Rtao) };
        aos.push(ambient_occlusion(&gpu, &gpu_scene, &camera, size, &settings).unwrap());
    }
    let (a, b) = (&images[0], &images[1]);
    let keep = interior(&a.gbuffer, &b.gbuffer);
    let (mut compared, mut depth_bad, mut normal_bad, mut material_bad, mut color_bad, mut ao_bad) =
        (0, 0, 0, 0, 0, 0);
    let mut on_sphere = 0;
    for i in (0..keep.len()).filter(|&i| keep[i]) {
        compared += 1;
        let (ga, gb) = (&a.gbuffer, &b.gbuffer);
        on_sphere += (ga.material[i][0] == 1) as usize;
        depth_bad += ((ga.depth[i] - gb.depth[i]).abs() > 1e-3 * gb.depth[i]) as usize;
        let dot: f32 = (0..3).map(|c| ga.normal[i][c] * gb.normal[i][c]).sum();
        // Half floats: each stored normal is unit only to about 1e-3.
        let len = |n: &[f32; 4]| (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        normal_bad += (dot / (len(&ga.normal[i]) * len(&gb.normal[i])) < 0.9999) as usize;
        material_bad += (ga.material[i][0] != gb.material[i][0]) as usize;
        color_bad += (0..3).any(|c| (a.color[i][c] - b.color[i][c]).abs() > 0.02 * b.color[i][c].abs() + 1e-3)
            as usize;
        // RTAO: 64 rays per pixel from (nearly) the same point; its hash of the pixel and ray
        // index draws the same directions, so only rays skimming the sphere can differ.
        ao_bad += ((aos[0].unblurred[i] - aos[1].unblurred[i]).abs() > 0.05) as usize;
    }
    println!(
        "hybrid: {compared} interior pixels ({on_sphere} on the sphere): depth {depth_bad}, normal {normal_bad}, \
         material {material_bad}, colour {color_bad}, RTAO {ao_bad} differ"
    );
    assert!(on_sphere > 300, "{on_sphere} sphere pixels");
    assert_eq!(material_bad, 0);
    assert!(depth_bad + normal_bad <= compared / 100, "depth {depth_bad}, normal {normal_bad} of {compared}");
    assert!(color_bad <= compared / 100, "colour {color_bad} of {compared}");
    assert!(ao_bad <= compared / 50, "RTAO {ao_bad} of {compared}");
}
