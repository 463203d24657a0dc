//! Shadow maps: the compute rasterizer against rays through the BVH, a closed mesh without
//! cracks, and the failure modes of the methods measured against ray-traced shadows (acne,
//! peter-panning, aliasing, the moments' light leaking, cube-map seams).

mod common;

use common::{build, camera, cuboid, light, quad, Gpu};
use glam::{Mat3, Vec3};
use umbra::bvh::traverse::Ray;
use umbra::gpu::layout::{GpuShadowLayer, SHADOW_PERSPECTIVE, SHADOW_TILE};
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::passes::deferred::LightingSettings;
use umbra::passes::shadow::{ShadowMethod, ShadowPlan, ShadowSettings};
use umbra::render::{HybridSettings, Passes};
use umbra::scene::{Camera, Light, LightKind, Scene};

/// The ray through layer `l`'s texel centre (px, py) and the factor turning its hit distance
/// into the layer's linear depth.
fn texel_ray(l: &GpuShadowLayer, px: f32, py: f32) -> (Ray, f32) {
    let a = |r: [f32; 4]| Vec3::new(r[0], r[1], r[2]);
    let (a0, a1, a2, a3) = (a(l.row0), a(l.row1), a(l.row2), a(l.row3));
    if l.kind == SHADOW_PERSPECTIVE {
        // The origin projects to (0, 0, 0, 0): rows · (o, 1) = 0; a direction d with a3 · d = 1
        // has depth 1 per unit of t.
        let m = Mat3::from_cols(a0, a1, a3).transpose();
        let o = m.inverse() * -Vec3::new(l.row0[3], l.row1[3], l.row3[3]);
        let d = m.inverse() * Vec3::new(px, py, 1.0);
        (Ray { origin: o, dir: d, tmin: 0.0, tmax: f32::INFINITY }, 1.0)
    } else {
        let m = Mat3::from_cols(a0, a1, a2).transpose();
        let o = m.inverse() * Vec3::new(px - l.row0[3], py - l.row1[3], -l.row2[3]);
        (Ray { origin: o, dir: a2, tmin: 0.0, tmax: f32::INFINITY }, 1.0 / a2.length())
    }
}

/// Hard shadow maps of `scene`'s lights (`size`² layers, `cascades` for a sun), seen from its
/// camera over a 64×64 image: the placement and every layer's depth, read back.
fn hard_maps(
    gpu: &Gpu,
    gpu_scene: &GpuScene,
    scene: &Scene,
    size: u32,
    cascades: u32,
) -> (ShadowPlan, Vec<f32>) {
    let passes = Passes::new(gpu, gpu_scene);
    let settings = ShadowSettings {
        method: ShadowMethod::Hard,
        map_size: size,
        cascades,
        max_radius: 4.0,
        ..Default::default()
    };
    let camera = scene.camera(None).unwrap();
    let mut maps = passes.shadow_maps(gpu_scene, &camera, (64, 64), &settings).unwrap();
    passes.render_shadow_maps(gpu_scene, &mut maps, None).unwrap();
    let depth = maps.read_depth(gpu).unwrap();
    (maps.plan.clone(), depth)
}

/// A floor, a box and an icosphere (large and small triangles), lit by a point light, a spot
/// light and `sun`.
fn mixed_scene(sun: Light) -> Scene {
    build(
        "mixed",
        &[
            quad(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -2.0)),
            cuboid(Vec3::new(-1.0, 0.0, -0.2), Vec3::new(-0.4, 0.7, 0.4)),
            umbra::procedural::icosphere(3, Vec3::new(0.6, 0.5, 0.1), 0.45).soup(),
        ],
        vec![
            light(LightKind::Point, Vec3::new(0.2, 1.6, 0.9), Vec3::NEG_Y, 5.0),
            light(LightKind::Spot, Vec3::new(-1.5, 2.0, 1.5), Vec3::new(0.6, -0.8, -0.6), 5.0),
            sun,
        ],
        camera(Vec3::new(0.0, 2.0, 3.5), Vec3::ZERO),
    )
}

/// Every texel of every layer's window (a point light's cube, a spot's map, a sun's two
/// cascades, each of those only over the tiles its slice of the view can read) holds
/// the depth of the first surface a ray from the light through the texel's centre meets in the
/// BVH (the reference), within 1e-4 of the depth plus 1e-5 of the layer's range; where they
/// differ, a ray 1e-3 texel away must agree (the centre lies on an edge: ties may go either
/// way) or the ray's triangle is within 3° of edge-on, and such texels are under 0.5 %. Four
/// scenes: textured.glb (large triangles: the tiled path), a floor, a box and an icosphere (small
/// triangles too: each rasterizes itself), a steep slope with a triangle floating 2 cm above part
/// of it (the raster step's depth cull: the slope covers whole tiles and bounds their depth, and
/// the triangle above it, farther than the slope at a tile's near corner but nearer at its far
/// one, must survive the cull), and a staircase of 96 long thin triangles (the fill's work list
/// spans workgroups: a fill dispatch of half the workgroups it needs fails it).
#[test]
fn rasterized_depth_matches_rays_through_the_bvh() {
    let gpu = Gpu::new();
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.3, -1.0, 0.2), 2.0);
    let mut textured =
        Scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/textured.glb")))
            .unwrap();
    textured.lights.push(sun.clone());
    let kinds: Vec<_> = textured.lights.iter().map(|l| l.kind).collect();
    assert!(kinds.contains(&LightKind::Point) && kinds.contains(&LightKind::Spot), "{kinds:?}");
    let mixed = mixed_scene(sun);
    let slope = |x: f32, z: f32, lift: f32| Vec3::new(x, -0.5 * x + lift, z);
    let stacked = build(
        "stacked",
        &[
            quad(slope(0.0, 0.0, 0.0), Vec3::new(1.5, -0.75, 0.0), Vec3::new(0.0, 0.0, 1.5)),
            vec![[slope(0.0, 1.0, 0.02), slope(1.2, 1.0, 0.02), slope(0.6, -1.0, 0.02)]],
        ],
        mixed.lights.clone(),
        camera(Vec3::new(0.0, 2.0, 3.5), Vec3::ZERO),
    );
    // 48 steps of 5 cm, each a long strip of two triangles: more large triangles than a workgroup
    // of the fill (64), every one seen from the lights.
    let steps: Vec<_> = (0..48)
        .map(|i| {
            let centre = Vec3::new(-1.175 + 0.05 * i as f32, 0.02 * i as f32, 0.0);
            quad(centre, Vec3::new(0.025, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0))
        })
        .collect();
    let stairs = build("stairs", &steps, mixed.lights.clone(), camera(Vec3::new(0.0, 2.0, 3.5), Vec3::ZERO));
    for scene in [textured, mixed, stacked, stairs] {
        let arrays = SceneArrays::new(&scene).unwrap();
        let gpu_scene = GpuScene::from_arrays(&gpu, &arrays).unwrap();
        let (plan, depth) = hard_maps(&gpu, &gpu_scene, &scene, 96, 2);
        let s = 96;
        let (mut covered, mut edges, mut bad) = (0, 0, Vec::new());
        for (li, l) in plan.layers.iter().enumerate() {
            let tolerance = |d: f32| 1e-4 * d.abs() + 1e-5 * l.depth_far;
            let hit = |px: f32, py: f32| {
                let (ray, scale) = texel_ray(l, px, py);
                arrays.bvh.closest(&ray).map_or((f32::INFINITY, 1.0), |h| {
                    let [a, b, c] = arrays.bvh.tris[h.tri as usize].vertices();
                    let cos = (b - a).cross(c - a).normalize_or_zero().dot(ray.dir.normalize()).abs();
                    ((h.t * scale).max(0.0), cos)
                })
            };
            let cast = |px: f32, py: f32| hit(px, py).0;
            let window = plan.windows[li].map(|t| t as usize);
            for y in 0..s {
                for x in 0..s {
                    let tile = (x / SHADOW_TILE as usize, y / SHADOW_TILE as usize);
                    if tile.0 < window[0] || tile.0 > window[2] || tile.1 < window[1] || tile.1 > window[3] {
                        continue;
                    }
                    let got = depth[li * s * s + y * s + x];
                    let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
                    let (want, cos) = hit(cx, cy);
                    covered += want.is_finite() as usize;
                    let agree =
                        |w: f32| (got.is_infinite() && w.is_infinite()) || (got - w).abs() <= tolerance(w);
                    if agree(want) {
                        continue;
                    }
                    let near = [(1e-3, 0.0), (-1e-3, 0.0), (0.0, 1e-3), (0.0, -1e-3)];
                    // On an edge, or on a triangle seen within 3° of edge-on (whose depth
                    // changes by tens of texels' worth across one texel).
                    if cos < 0.05 || near.iter().any(|(dx, dy)| agree(cast(cx + dx, cy + dy))) {
                        edges += 1;
                    } else {
                        bad.push((li, x, y, got, want));
                    }
                }
            }
        }
        eprintln!(
            "{}: {} layers of {s}²: {covered} texels covered, {edges} on edges, {} wrong",
            scene.name,
            plan.layers.len(),
            bad.len()
        );
        assert_eq!(plan.layers.len(), 6 + 1 + 2, "a cube, a spot map, two cascades");
        assert!(covered > s * s, "too little geometry in the maps: {covered}");
        assert!(
            bad.is_empty(),
            "{} texels differ from the ray cast, e.g. {:?}",
            bad.len(),
            &bad[..bad.len().min(5)]
        );
        assert!(edges * 200 < covered, "{edges} edge texels of {covered}");
    }
}

/// A closed icosphere (5,120 triangles sharing bit-identical vertices) leaves no texel inside
/// its outline empty, seen from a sun (orthographic) and from a point light (perspective): the
/// edge functions of a shared edge are exact negatives, and the tie rule gives each texel centre
/// on an edge to one triangle. Inside: more than 1.5 texels within the outline, computed
/// analytically.
#[test]
fn closed_mesh_rasterizes_without_cracks() {
    let gpu = Gpu::new();
    let centre = Vec3::new(0.1, 0.2, -0.3);
    let radius = 1.0;
    let sphere = umbra::procedural::icosphere(4, centre, radius).soup();
    // The icosphere's faces lie inside the sphere: the outline is that of the inscribed polyhedron,
    // at least radius · cos(the largest edge's half angle) from the centre; take radius · 0.995.
    let inner = radius * 0.995;
    let lights = vec![
        light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.37, -0.81, 0.45), 1.0),
        light(LightKind::Point, centre + Vec3::new(0.6, 2.5, 1.1), Vec3::NEG_Z, 10.0),
    ];
    let scene = build("icosphere", &[sphere], lights, camera(centre + Vec3::new(0.0, 0.5, 4.0), centre));
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let (plan, depth) = hard_maps(&gpu, &gpu_scene, &scene, 256, 1);
    let s = 256;
    let mut inside_total = 0;
    for (li, l) in plan.layers.iter().enumerate() {
        let (mut inside, mut holes) = (0, 0);
        for y in 0..s {
            for x in 0..s {
                let (ray, _) = texel_ray(l, x as f32 + 0.5, y as f32 + 0.5);
                // Distance from the centre to the texel's ray, less 1.5 texels at the sphere.
                let d = ray.dir.normalize();
                let o = ray.origin;
                let to_centre = centre - o;
                let miss = (to_centre - d * to_centre.dot(d)).length();
                let along = to_centre.dot(d);
                let texel = if l.kind == SHADOW_PERSPECTIVE { l.texel_world * along } else { l.texel_world };
                if along > 0.0 && miss < inner - 1.5 * texel {
                    inside += 1;
                    holes += depth[li * s * s + y * s + x].is_infinite() as usize;
                }
            }
        }
        assert_eq!(holes, 0, "layer {li}: {holes} empty texels of {inside} inside the outline");
        inside_total += inside;
    }
    eprintln!("{inside_total} texels inside outlines over {} layers, none empty", plan.layers.len());
    assert!(inside_total > 8_000, "the sphere covers too little of the maps: {inside_total}");
}

/// The floor scene of the failure-mode tests: a 6 m floor, a 0.6 m box standing on it (or the
/// given occluders), a sun 50° from the zenith, a camera looking down at 40°.
struct Stage {
    floor: Vec<[Vec3; 3]>,
    occluders: Vec<Vec<[Vec3; 3]>>,
    light: Light,
    camera: Camera,
}

impl Stage {
    fn sun_and_box() -> Self {
        Stage {
            floor: quad(Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -3.0)),
            occluders: vec![cuboid(Vec3::new(-0.3, 0.0, -0.3), Vec3::new(0.3, 0.6, 0.3))],
            light: light(LightKind::Directional, Vec3::ZERO, Vec3::new(-0.55, -0.64, -0.53), 3.0),
            camera: camera(Vec3::new(0.3, 2.6, 3.0), Vec3::new(-0.4, 0.0, -0.5)),
        }
    }

    /// Per pixel the visibility of the light on the floor (lit radiance over the radiance of the
    /// floor alone, which nothing shadows), `None` off the floor: each `settings`, and rays.
    fn visibility(
        &self,
        gpu: &Gpu,
        size: u32,
        settings: &[ShadowSettings],
    ) -> (Vec<Option<f32>>, Vec<Vec<Option<f32>>>) {
        self.visibility_with(gpu, size, settings, |_| {})
    }

    /// [`Stage::visibility`] with the full scene changed by `change` first.
    fn visibility_with(
        &self,
        gpu: &Gpu,
        size: u32,
        settings: &[ShadowSettings],
        change: impl Fn(&mut Scene),
    ) -> (Vec<Option<f32>>, Vec<Vec<Option<f32>>>) {
        let mut soups = vec![self.floor.clone()];
        soups.extend(self.occluders.iter().cloned());
        let mut full = build("stage", &soups, vec![self.light.clone()], self.camera);
        change(&mut full);
        let bare = build("floor", std::slice::from_ref(&self.floor), vec![self.light.clone()], self.camera);
        let render = |scene: &Scene, shadows: ShadowSettings| {
            let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
            let settings = HybridSettings { size: (size, size), ao: None, shadows, ..Default::default() };
            umbra::render::hybrid(gpu, &gpu_scene, &self.camera, &settings).unwrap()
        };
        let open = render(&bare, ShadowSettings::default());
        let ratio = |image: &umbra::render::HybridImage| -> Vec<Option<f32>> {
            (0..image.color.len())
                .map(|i| {
                    let on_floor = image.gbuffer.material[i][0] == 0 && open.gbuffer.material[i][0] == 0;
                    let lit = open.color[i][1];
                    (on_floor && lit > 1e-3).then(|| image.color[i][1] / lit)
                })
                .collect()
        };
        let rays = ratio(&render(&full, ShadowSettings::default()));
        let maps = settings.iter().map(|s| ratio(&render(&full, *s))).collect();
        (rays, maps)
    }
}

/// Fractions of floor pixels: lit by rays but (mostly) shadowed by the map, and shadowed by rays
/// but (mostly) lit by the map; over the pixels the rays light and shadow.
fn disagreement(rays: &[Option<f32>], map: &[Option<f32>]) -> (f64, f64) {
    let (mut lit, mut dark, mut acne, mut leak) = (0, 0, 0, 0);
    for (r, m) in rays.iter().zip(map) {
        if let (Some(r), Some(m)) = (r, m) {
            if *r > 0.5 {
                lit += 1;
                acne += (*m < 0.5) as usize;
            } else {
                dark += 1;
                leak += (*m > 0.5) as usize;
            }
        }
    }
    assert!(lit > 100 && dark > 100, "too few lit ({lit}) or shadowed ({dark}) floor pixels");
    (acne as f64 / lit as f64, leak as f64 / dark as f64)
}

/// Shadow acne: with no bias at all, the floor shadows itself where the rays light it (more than
/// a fifth of it; measured 0.72); the default biases leave under 1 % (0.06 %).
#[test]
fn zero_bias_shows_acne_and_the_default_bias_removes_it() {
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let hard =
        ShadowSettings { method: ShadowMethod::Hard, map_size: 512, cascades: 1, ..Default::default() };
    let none = ShadowSettings { depth_bias: 0.0, slope_bias: 0.0, normal_bias: 0.0, ..hard };
    let (rays, maps) = stage.visibility(&gpu, 96, &[none, hard]);
    let (acne_none, _) = disagreement(&rays, &maps[0]);
    let (acne_default, _) = disagreement(&rays, &maps[1]);
    eprintln!("self-shadowed lit floor: no bias {acne_none:.3}, default {acne_default:.4}");
    assert!(acne_none > 0.2, "no acne without bias: {acne_none}");
    assert!(acne_default < 0.01, "acne with the default bias: {acne_default}");
}

/// Peter-panning: a large bias (12 texels of normal offset and of depth) lifts the shadow off
/// the box's foot: the floor the rays shadow but the map lights grows well beyond the default
/// bias's (more than 3×).
#[test]
fn a_large_bias_detaches_the_contact_shadow() {
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let hard =
        ShadowSettings { method: ShadowMethod::Hard, map_size: 512, cascades: 1, ..Default::default() };
    let large = ShadowSettings { depth_bias: 12.0, normal_bias: 12.0, ..hard };
    let (rays, maps) = stage.visibility(&gpu, 96, &[hard, large]);
    let (_, leak_default) = disagreement(&rays, &maps[0]);
    let (acne_large, leak_large) = disagreement(&rays, &maps[1]);
    eprintln!("shadowed floor lit by the map: default bias {leak_default:.4}, large {leak_large:.4} (acne {acne_large:.4})");
    assert!(
        leak_large > 3.0 * leak_default && leak_large > 0.1,
        "no peter-panning: {leak_large} vs {leak_default}"
    );
}

/// Aliasing: the floor where a hard map disagrees with the rays shrinks as the map grows, about
/// as the texel's size (the disagreeing band along the shadow's outline is a texel or two
/// wide): over 128² to 1024², the log-log slope of the disagreeing fraction is within
/// [-1.5, -0.5], and each doubling lowers it.
#[test]
fn hard_shadow_error_falls_with_the_map_resolution() {
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let sizes = [128u32, 256, 512, 1024];
    let settings: Vec<_> = sizes
        .iter()
        .map(|&map_size| ShadowSettings {
            method: ShadowMethod::Hard,
            map_size,
            cascades: 1,
            ..Default::default()
        })
        .collect();
    let (rays, maps) = stage.visibility(&gpu, 128, &settings);
    let errors: Vec<f64> = maps
        .iter()
        .map(|m| {
            let (a, b) = disagreement(&rays, m);
            a + b
        })
        .collect();
    let xs: Vec<f64> = sizes.iter().map(|&s| (s as f64).ln()).collect();
    let ys: Vec<f64> = errors.iter().map(|e| e.max(1e-6).ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / 4.0, ys.iter().sum::<f64>() / 4.0);
    let slope = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    eprintln!("disagreement at {sizes:?}: {errors:.4?}, log-log slope {slope:.2}");
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "the error does not fall with resolution: {errors:?}");
    assert!((-1.5..=-0.5).contains(&slope), "slope {slope}");
}

/// Light leaking of the filterable method: under two stacked plates whose edges nearly meet,
/// the moment maps' filter windows see three depths (both plates and the lit floor), which four
/// moments cannot hold, and the bound 4MSM returns lets light through where the filtered truth
/// has less. Measured as moments' visibility less PCF's (a Poisson disk of the box window's area)
/// on the floor the rays shadow (3×3 neighbours shadowed too), under the two plates and under the
/// upper plate alone (two depths: 4MSM is exact there): the stacked plates leak more than
/// 0.05 beyond the single plate's difference.
#[test]
fn moment_shadow_maps_leak_light_under_stacked_occluders() {
    let gpu = Gpu::new();
    let upper = quad(Vec3::new(0.0, 1.2, 0.0), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.5));
    let lower = quad(Vec3::new(0.02, 0.45, 0.0), Vec3::new(0.6, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.6));
    let blur = 6u32;
    let base = ShadowSettings {
        map_size: 256,
        cascades: 1,
        pcf_radius: (2 * blur + 1) as f32 / std::f32::consts::PI.sqrt(),
        moment_blur: blur,
        ..Default::default()
    };
    let size = 128usize;
    let leak = |occluders: Vec<Vec<[Vec3; 3]>>| {
        let mut stage = Stage::sun_and_box();
        stage.occluders = occluders;
        stage.light = light(LightKind::Directional, Vec3::ZERO, Vec3::new(-0.2, -1.0, -0.15), 3.0);
        let methods =
            [ShadowMethod::Pcf, ShadowMethod::Moments].map(|method| ShadowSettings { method, ..base });
        let (rays, maps) = stage.visibility(&gpu, size as u32, &methods);
        let shadowed = |x: i64, y: i64| {
            (0..size as i64).contains(&x)
                && (0..size as i64).contains(&y)
                && rays[(y * size as i64 + x) as usize].is_some_and(|v| v < 0.5)
        };
        let umbra: Vec<usize> = (0..rays.len())
            .filter(|&i| {
                let (x, y) = ((i % size) as i64, (i / size) as i64);
                (-1..=1).all(|dy| (-1..=1).all(|dx| shadowed(x + dx, y + dy)))
            })
            .collect();
        assert!(umbra.len() > 200, "too small an umbra: {}", umbra.len());
        let vis = |m: &[Option<f32>], i: usize| m[i].unwrap_or(0.0) as f64;
        umbra.iter().map(|&i| vis(&maps[1], i) - vis(&maps[0], i)).sum::<f64>() / umbra.len() as f64
    };
    let stacked = leak(vec![upper.clone(), lower]);
    let single = leak(vec![upper]);
    eprintln!(
        "moments less PCF in the umbra: stacked plates {stacked:.4}, the upper plate alone {single:.4}"
    );
    assert!(stacked > single + 0.05, "no leaking shown: stacked {stacked}, single {single}");
}

/// Cube-map seams: a point light 1.5 m above the floor and a box towards a corner of the cube,
/// so the lit floor and the box's shadow both cross faces: PCF from the cube agrees with the
/// rays on all but the shadow's outline (under 1 % of the lit floor dark, under 5 % of the
/// shadowed floor lit), and along a line across the seam of the downward face every lit pixel
/// stays lit (no discontinuity where the face changes).
#[test]
fn cube_map_faces_meet_without_seams() {
    let gpu = Gpu::new();
    let mut stage = Stage::sun_and_box();
    stage.light = light(LightKind::Point, Vec3::new(0.0, 1.5, 0.0), Vec3::NEG_Y, 20.0);
    stage.occluders = vec![cuboid(Vec3::new(1.2, 0.0, 1.2), Vec3::new(1.6, 0.5, 1.6))];
    stage.camera = camera(Vec3::new(0.0, 4.5, 4.0), Vec3::new(0.5, 0.0, 0.5));
    let pcf =
        ShadowSettings { method: ShadowMethod::Pcf, map_size: 512, pcf_radius: 2.5, ..Default::default() };
    let (rays, maps) = stage.visibility(&gpu, 128, &[pcf]);
    let (acne, leak) = disagreement(&rays, &maps[0]);
    let lit_dim = rays
        .iter()
        .zip(&maps[0])
        .filter(|(r, m)| r.is_some_and(|r| r > 0.99) && m.is_some_and(|m| m < 0.99))
        .count();
    let lit = rays.iter().filter(|r| r.is_some_and(|r| r > 0.99)).count();
    eprintln!("cube PCF: lit floor dark {acne:.4}, shadowed floor lit {leak:.4}; {lit_dim} of {lit} lit pixels below 0.99");
    assert!(acne < 0.01 && leak < 0.05, "acne {acne}, leak {leak}");
    assert!(lit_dim * 100 < lit, "{lit_dim} of {lit} lit pixels dimmed by the cube's PCF");
}

/// PCSS: the penumbra widens with the light's size. The sun's angular radius from 0.25° to 3°
/// widens the band of the floor in partial shadow (visibility strictly between 0.05 and 0.95)
/// by more than 3× (the penumbra's width is proportional to the angle where the blocker search
/// finds the box; measured 5×: 26 → 131 pixels), and the umbra stays: the floor the rays shadow far from
/// the box's outline stays dark.
#[test]
fn pcss_penumbrae_widen_with_the_light_size() {
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let base =
        ShadowSettings { method: ShadowMethod::Pcss, map_size: 1024, cascades: 1, ..Default::default() };
    let small = ShadowSettings { sun_angle: 0.25f32.to_radians(), ..base };
    let large = ShadowSettings { sun_angle: 3f32.to_radians(), ..base };
    let (rays, maps) = stage.visibility(&gpu, 128, &[small, large]);
    let penumbra = |m: &[Option<f32>]| m.iter().filter(|v| v.is_some_and(|v| v > 0.05 && v < 0.95)).count();
    let (narrow, wide) = (penumbra(&maps[0]), penumbra(&maps[1]));
    let (_, leak) = disagreement(&rays, &maps[1]);
    eprintln!("PCSS penumbra pixels: sun 0.25° {narrow}, 3° {wide}; shadowed floor lit at 3°: {leak:.3}");
    assert!(narrow > 0 && wide > 3 * narrow, "penumbra {narrow} -> {wide}");
    assert!(leak < 0.5, "the umbra vanished: {leak}");
}

/// The embedding API's shadow maps (placed by `Renderer::shadow_maps`, recorded by
/// `record_shadow_maps` into the host's command buffer, read by `record_lighting`) give the
/// one-shot hybrid's image for the same settings, bit for bit; so do maps recorded for the
/// view between `record_gbuffer` and `record_hybrid_shading`, with fewer tiles.
#[test]
fn embedded_shadow_maps_match_the_one_shot_render() {
    use umbra::embed::Renderer;
    use umbra::passes::deferred::LightingSettings;
    use umbra::passes::gbuffer::GBuffer;
    use umbra::vk::{raw, Image};
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let mut soups = vec![stage.floor.clone()];
    soups.extend(stage.occluders.iter().cloned());
    let scene = build("stage", &soups, vec![stage.light.clone()], stage.camera);
    let size = (48, 48);
    let shadows = ShadowSettings { method: ShadowMethod::Pcf, map_size: 256, ..Default::default() };
    let lighting = LightingSettings::default();
    let settings = HybridSettings { size, ao: None, shadows, lighting, ..Default::default() };
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let one_shot = umbra::render::hybrid(&gpu, &gpu_scene, &stage.camera, &settings).unwrap().color;

    let renderer = Renderer::new(&gpu, &scene).unwrap();
    let maps = renderer.shadow_maps(&stage.camera, size, &shadows).unwrap();
    let gbuffer = GBuffer::new(&gpu, size).unwrap();
    let hdr = Image::storage_2d(&gpu, "hdr", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    gpu.submit(|cmd| {
        hdr.init_general(&gpu, cmd);
        renderer.record_shadow_maps(cmd, &maps, None)?;
        renderer.record_gbuffer(cmd, &stage.camera, &gbuffer.views())?;
        renderer.record_lighting(
            cmd,
            &stage.camera,
            &gbuffer.views(),
            hdr.view,
            &umbra::passes::deferred::LightingInputs { shadows: Some(&maps), ..Default::default() },
            &lighting,
        )
    })
    .unwrap();
    assert_eq!(maps.check(&gpu).unwrap(), None, "the tile lists overflowed");
    let embedded: Vec<[f32; 4]> = hdr.read(&gpu).unwrap();
    let lit = one_shot.iter().filter(|p| p[1] > 0.01).count();
    assert!(lit > 500, "only {lit} lit pixels");
    assert!(embedded == one_shot, "the embedded frame differs from the one-shot render");
    // The maps for the view (only the tiles its pixels read): G-buffer, maps, the rest of the
    // frame, all in one command buffer.
    let views = gbuffer.views();
    let view = umbra::passes::shadow::ShadowView { camera: &stage.camera, gbuffer: &views };
    let mut targets = umbra::render::HybridTargets {
        gbuffer: &views,
        visibility: None,
        ao: None,
        hdr: hdr.view,
        ldr: None,
        shadows: Some(&maps),
        probes: None,
        lightmaps: None,
        reservoirs: None,
        taa: None,
    };
    gpu.submit(|cmd| {
        renderer.record_gbuffer(cmd, &stage.camera, &views)?;
        renderer.record_shadow_maps(cmd, &maps, Some(view))?;
        renderer.record_hybrid_shading(cmd, &stage.camera, &targets, &settings, None)
    })
    .unwrap();
    assert_eq!(maps.check(&gpu).unwrap(), None, "the tile lists overflowed");
    let rendered: u32 = maps.rendered_tiles(&gpu).unwrap().iter().sum();
    let windows: u32 = maps.plan.windows.iter().map(|w| (w[2] - w[0] + 1) * (w[3] - w[1] + 1)).sum();
    assert!(rendered < windows, "the view marked {rendered} of the windows' {windows} tiles");
    let marked: Vec<[f32; 4]> = hdr.read(&gpu).unwrap();
    assert!(marked == one_shot, "the frame with maps for the view differs from the one-shot render");
    // A frame whose settings ask for maps but that is given none is refused, naming the method.
    targets.shadows = None;
    let refused = gpu.submit(|cmd| renderer.record_hybrid(cmd, &stage.camera, &targets, &settings, None));
    let message = refused.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(message.contains("'pcf'") && message.contains("no shadow maps"), "{message}");
}

/// A sun's cascades render only what the view reads. Their windows: the tiles around the box
/// their slice of the view makes in the layer, widened by the filters' reach and the normal
/// offset. Within those, for maps rendered for the view (its G-buffer's pixels mark the tiles
/// their lookups reach): the marked tiles. On the floor scene (128² pixels, a camera looking down
/// at 40°, four 256² cascades) the windows hold under 75 % of the layers' tiles (46 to 66 %
/// measured, by method) and the marks fewer (6 to 12 %), and with every map method, and PCF 12
/// texels wide, the lit image is bit for bit the one of whole layers. Test builds poison the maps
/// before rendering (depth 0, an occluder at the light), so a lookup of an unrendered texel
/// shadows a lit point: windows from the slices' near ends alone leave 2583 pixels different
/// (hard), marks of a reach of 0 texels 6 (hard: the normal offset), marks without the filter's
/// reach 3046 (the wide PCF).
#[test]
fn cascades_render_only_what_the_view_reads() {
    use umbra::passes::gbuffer::GBuffer;
    use umbra::passes::shadow::ShadowView;
    let gpu = Gpu::new();
    let stage = Stage::sun_and_box();
    let mut soups = vec![stage.floor.clone()];
    soups.extend(stage.occluders.iter().cloned());
    let scene = build("stage", &soups, vec![stage.light.clone()], stage.camera);
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let size = (128, 128);
    let passes = Passes::new(&gpu, &gpu_scene);
    let gbuffer = GBuffer::new(&gpu, size).unwrap();
    gpu.record(|rec| passes.record_gbuffer(rec, &gpu_scene, &stage.camera, &gbuffer.views())).unwrap();
    let base = ShadowSettings { map_size: 256, cascades: 4, ..Default::default() };
    // Each method at its defaults, and PCF 12 texels wide (its taps reach past a tile).
    let wide = ShadowSettings { method: ShadowMethod::Pcf, pcf_radius: 12.0, ..base };
    let methods = [ShadowMethod::Hard, ShadowMethod::Pcf, ShadowMethod::Pcss, ShadowMethod::Moments];
    for marked in methods.map(|method| ShadowSettings { method, ..base }).into_iter().chain([wide]) {
        let method = marked.method;
        let windowed = ShadowSettings { view_marks: false, ..marked };
        let whole = ShadowSettings { cascade_windows: false, ..windowed };
        let plan =
            ShadowPlan::new(&gpu_scene.punctual_lights, gpu_scene.bounds, &stage.camera, size, &windowed)
                .unwrap();
        let tiles: u32 = plan.windows.iter().map(|w| (w[2] - w[0] + 1) * (w[3] - w[1] + 1)).sum();
        let all = plan.layers.len() as u32 * (256 / SHADOW_TILE).pow(2);
        let mut maps = passes.shadow_maps(&gpu_scene, &stage.camera, size, &marked).unwrap();
        let view = ShadowView { camera: &stage.camera, gbuffer: &gbuffer.views() };
        passes.render_shadow_maps(&gpu_scene, &mut maps, Some(view)).unwrap();
        let rendered: u32 = maps.rendered_tiles(&gpu).unwrap().iter().sum();
        let render = |shadows: ShadowSettings| {
            let settings = HybridSettings { size, ao: None, shadows, ..Default::default() };
            umbra::render::hybrid(&gpu, &gpu_scene, &stage.camera, &settings).unwrap().color
        };
        // The marks made point by point alone (no box), as a block across a depth edge makes
        // them, and by each block's box alone (no subgroup box).
        let apart = ShadowSettings { mark_box: 0, ..marked };
        let boxes = ShadowSettings { mark_rounds: 0, ..marked };
        let (a, b, c) = (render(marked), render(windowed), render(whole));
        let (d, e) = (render(apart), render(boxes));
        let differ = |x: &[[f32; 4]]| x.iter().zip(&c).filter(|(x, c)| x != c).count();
        let shadowed = c.iter().filter(|p| p[1] < 0.5 * c.iter().map(|q| q[1]).fold(0.0, f32::max)).count();
        eprintln!(
            "{} (radius {}): windows hold {tiles} of {all} tiles ({:.0} %), the marks {rendered} ({:.0} %); {} and \
             {} pixels differ from whole layers; {shadowed} pixels under half the brightest",
            method.name(),
            marked.pcf_radius,
            100.0 * tiles as f64 / all as f64,
            100.0 * rendered as f64 / all as f64,
            differ(&a),
            differ(&b)
        );
        assert!(tiles * 4 < all * 3, "the windows cut too little: {tiles} of {all} tiles");
        assert!(rendered < tiles, "the marks cut nothing: {rendered} of the windows' {tiles} tiles");
        assert!(shadowed > 100, "too little shadow to compare: {shadowed} pixels");
        assert_eq!(differ(&b), 0, "{}: the windowed maps shade differently", method.name());
        assert_eq!(differ(&a), 0, "{}: the marked maps shade differently", method.name());
        assert_eq!(differ(&d), 0, "{}: the maps marked point by point shade differently", method.name());
        assert_eq!(differ(&e), 0, "{}: the maps marked block by block shade differently", method.name());
    }
}

/// A sun, a scene's bounds (40 × 15 × 24 m) and four hard 1024² cascades: the placement tests'
/// set-up.
fn cascade_setup() -> (umbra::gpu::layout::GpuLight, [[f32; 3]; 2], ShadowSettings) {
    let sun = umbra::gpu::layout::GpuLight {
        direction_kind: [0.3, -0.9, 0.2, umbra::gpu::layout::GpuLight::DIRECTIONAL],
        ..Default::default()
    };
    let bounds = [[-20.0, 0.0, -12.0], [20.0, 15.0, 12.0]];
    let settings =
        ShadowSettings { method: ShadowMethod::Hard, map_size: 1024, cascades: 4, ..Default::default() };
    (sun, bounds, settings)
}

/// Cascades are stable (no shimmering as the view changes): turning the camera keeps every
/// cascade's texel size (the bounding sphere of a frustum slice does not depend on its
/// orientation), and moving it shifts each cascade's grid by whole texels (the centre is
/// snapped), checked on the placement alone for 50 random turns and moves.
#[test]
fn cascades_keep_their_texel_size_and_move_by_whole_texels() {
    let (sun, bounds, settings) = cascade_setup();
    let place = |c: &Camera| ShadowPlan::new(&[sun], bounds, c, (1920, 1080), &settings).unwrap().layers;
    let base = camera(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 1.0, -2.0));
    let reference = place(&base);
    let mut rng = umbra::procedural::Rng::new(7);
    for _ in 0..50 {
        let turned = camera(Vec3::from(base.position), Vec3::from(base.position) + 5.0 * rng.on_sphere());
        for (a, b) in reference.iter().zip(&place(&turned)) {
            assert!(
                (a.texel_world - b.texel_world).abs() <= 1e-5 * a.texel_world,
                "{} vs {}",
                a.texel_world,
                b.texel_world
            );
        }
        let shift = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0));
        let moved = Camera { position: (Vec3::from(base.position) + shift).to_array(), ..base };
        for (a, b) in reference.iter().zip(&place(&moved)) {
            for (ra, rb) in [(a.row0, b.row0), (a.row1, b.row1)] {
                let offset = rb[3] - ra[3];
                assert!((offset - offset.round()).abs() < 1e-2, "the grid moved by {offset} texels");
            }
        }
    }
}

/// Each directional cascade holds its slice of the view: the eight corners of the slice between
/// its split depths (the last one's up to the scene's farthest view depth), of a pinhole's frustum
/// and of an orthographic camera's box (whose slices do not narrow towards the eye), fall inside
/// the cascade's map (texel coordinates within 1e-3 of [0, map size]); and the map is no wider
/// than it need be: the sphere it is fitted to (map size × texel / 2, less the guard band's
/// widening, taken as at most 5 %) is at most Jung's bound √(3/8) × the corners' diameter, which
/// every set's smallest enclosing sphere meets (all but the last cascade, which reaches beyond the
/// scene).
#[test]
fn cascades_cover_their_slice_of_a_pinhole_or_orthographic_view() {
    let (sun, bounds, settings) = cascade_setup();
    let (size, aspect) = ((1920, 1080), 1920.0 / 1080.0);
    let pinhole = camera(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-4.0, 1.0, -2.0));
    let box_view = umbra::scene::Orthographic { xmag: 6.0 * aspect, ymag: 6.0, zfar: 100.0 };
    let orthographic = Camera { yfov: 0.0, aspect: Some(aspect), orthographic: Some(box_view), ..pinhole };
    for cam in [pinhole, orthographic] {
        let layers = ShadowPlan::new(&[sun], bounds, &cam, size, &settings).unwrap().layers;
        let (eye, forward) = (Vec3::from(cam.position), Vec3::from(cam.forward));
        let (up, right) = (Vec3::from(cam.up), Vec3::from(cam.forward).cross(Vec3::from(cam.up)));
        let deepest = (0..8)
            .map(|i| Vec3::new(bounds[i & 1][0], bounds[i >> 1 & 1][1], bounds[i >> 2][2]))
            .map(|c| (c - eye).dot(forward))
            .fold(0.0, f32::max);
        let mut near = 0.0;
        for (k, layer) in layers.iter().enumerate() {
            let far = layer.split.min(deepest);
            let mut corners = Vec::new();
            for z in [near, far] {
                let (hx, hy) = cam.half_extent(z, aspect);
                for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let c = eye + forward * z + right * (sx * hx) + up * (sy * hy);
                    corners.push(c);
                    let texel = |row: [f32; 4]| Vec3::from_slice(&row[..3]).dot(c) + row[3];
                    let (tx, ty) = (texel(layer.row0), texel(layer.row1));
                    let inside = |t: f32| (-1e-3..=1024.0 * (1.0 + 1e-3)).contains(&t);
                    assert!(
                        inside(tx) && inside(ty),
                        "{:?} camera, cascade {k}: corner at depth {z} lands on texel {tx}, {ty}",
                        cam.orthographic
                    );
                }
            }
            let diameter =
                corners.iter().flat_map(|a| corners.iter().map(move |b| a.distance(*b))).fold(0.0, f32::max);
            let bound = 1.05 * (3.0f32 / 8.0).sqrt() * diameter;
            assert!(
                k + 1 == layers.len() || layer.texel_world * 512.0 <= bound,
                "{:?} camera, cascade {k}: fitted to a sphere of radius {} for a slice of diameter {diameter}",
                cam.orthographic,
                layer.texel_world * 512.0
            );
            near = layer.split;
        }
    }
}

/// Alpha cut-outs: a plate over the floor whose base colour texture's alpha is a checker of 8×8
/// holes (glTF MASK) casts the checker, through shadow rays (the traversal's alpha test) and
/// through the map (the rasterizer's, the same test) alike: the floor the plate's shadow covers
/// (where rays are blocked by the plate made opaque) is part lit, part dark under the rays (each
/// more than a fifth), and the map agrees on all but the holes' outlines (under 5 % of each). A
/// rasterizer that ignored alpha would darken every hole.
#[test]
fn alpha_masked_casters_cut_holes_in_the_map_as_in_the_rays() {
    use umbra::scene::{AlphaMode, Filter, Sampler, Texture, TextureRef};
    let gpu = Gpu::new();
    let mut stage = Stage::sun_and_box();
    stage.light = light(LightKind::Directional, Vec3::ZERO, Vec3::new(-0.1, -1.0, -0.05), 3.0);
    stage.occluders =
        vec![quad(Vec3::new(0.0, 0.6, 0.0), Vec3::new(0.8, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.8))];
    let n = 8u32;
    let rgba8: Vec<u8> = (0..n * n)
        .flat_map(|i| {
            let open = ((i % n) + (i / n)).is_multiple_of(2);
            [200, 200, 200, if open { 0 } else { 255 }]
        })
        .collect();
    let nearest = Sampler {
        mag_filter: Filter::Nearest,
        min_filter: Filter::Nearest,
        mipmaps: false,
        ..Default::default()
    };
    let (rays, maps) = {
        let hard =
            ShadowSettings { method: ShadowMethod::Hard, map_size: 1024, cascades: 1, ..Default::default() };
        let mask = |scene: &mut Scene| {
            scene.textures = vec![Texture {
                name: "holes".into(),
                width: n,
                height: n,
                rgba8: rgba8.clone(),
                srgb: true,
                sampler: nearest,
            }];
            let plate = &mut scene.materials[1];
            plate.alpha_mode = AlphaMode::Mask;
            plate.alpha_cutoff = 0.5;
            plate.double_sided = true;
            plate.base_color_texture = Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                scale: 1.0,
            });
            // UVs: the plate's corners map to the texture's; the floor's are unused.
            scene.uv0 = vec![[0.0; 2]; scene.positions.len()];
            let corner = |p: [f32; 3]| [(p[0] + 0.8) / 1.6, (p[2] + 0.8) / 1.6];
            for (i, p) in scene.positions.iter().enumerate().skip(6) {
                scene.uv0[i] = corner(*p);
            }
        };
        stage.visibility_with(&gpu, 128, &[hard], mask)
    };
    // The plate's whole footprint: where rays are blocked by the plate made opaque.
    let (opaque, _) = stage.visibility(&gpu, 128, &[]);
    let footprint: Vec<usize> = (0..opaque.len()).filter(|&i| opaque[i].is_some_and(|v| v < 0.5)).collect();
    let holes: Vec<usize> = footprint.iter().copied().filter(|&i| rays[i].is_some_and(|v| v > 0.5)).collect();
    let solid = footprint.len() - holes.len();
    let dark_holes = holes.iter().filter(|&&i| maps[0][i].is_some_and(|v| v < 0.5)).count();
    let lit_solid = footprint
        .iter()
        .filter(|&&i| rays[i].is_some_and(|v| v < 0.5) && maps[0][i].is_some_and(|v| v > 0.5))
        .count();
    eprintln!(
        "masked plate's footprint {}: {} holes (map dark in {dark_holes}), {solid} solid (map lit in {lit_solid})",
        footprint.len(),
        holes.len()
    );
    assert!(
        holes.len() * 5 > footprint.len() && solid * 5 > footprint.len(),
        "no checker in the rays' shadow"
    );
    assert!(dark_holes * 20 < holes.len(), "the map fills the holes: {dark_holes} of {}", holes.len());
    assert!(lit_solid * 20 < solid, "the map opens the solid cells: {lit_solid} of {solid}");
}

/// The hybrid's linear image of `scene` seen by `camera` (`size`², no SSAO, no ambient light)
/// with `shadows` and `rays` shadow rays, averaged over frames 0 to `frames` − 1 (sized lights'
/// rays continue one sequence over them), and the G-buffer's material per pixel.
fn hybrid_mean(
    gpu: &Gpu,
    scene: &Scene,
    camera: &Camera,
    size: u32,
    shadows: ShadowSettings,
    rays: u32,
    frames: u32,
) -> (Vec<[f32; 4]>, Vec<u32>) {
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let passes = Passes::new(gpu, &gpu_scene);
    let mut sum = vec![[0.0f32; 4]; (size * size) as usize];
    let mut material = Vec::new();
    for frame in 0..frames {
        let lighting = LightingSettings { shadow_rays: rays, frame, ..Default::default() };
        let settings =
            HybridSettings { size: (size, size), lighting, ao: None, shadows, ..Default::default() };
        let image = passes.hybrid(&gpu_scene, camera, &settings).unwrap();
        for (s, c) in sum.iter_mut().zip(&image.color) {
            for k in 0..4 {
                s[k] += c[k] / frames as f32;
            }
        }
        material = image.gbuffer.material.iter().map(|m| m[0]).collect();
    }
    (sum, material)
}

/// The fraction of a sized light a point sees past an occluding half-plane: the light's cone of
/// directions (axis `w` towards its centre, half-angle `theta_max`), uniform in solid angle,
/// and the directions d with d · m ≥ 0 unoccluded (m: the unit normal of the plane through the
/// point and the half-plane's edge, on the open side). Per ring of the cone at angle θ from its
/// axis the open share of the ring is exact, acos(−tan β / tan θ) / π with sin β = w · m; the
/// rings are integrated by Simpson's rule over 4,000 intervals (error below 1e-5).
fn open_fraction(w: glam::DVec3, m: glam::DVec3, theta_max: f64) -> f64 {
    let sin_b = w.dot(m).clamp(-1.0, 1.0);
    let tan_b = sin_b / (1.0 - sin_b * sin_b).sqrt().max(1e-300);
    let ring = |t: f64| {
        if t <= 0.0 {
            return if sin_b >= 0.0 { 1.0 } else { 0.0 };
        }
        (-tan_b / t.tan()).clamp(-1.0, 1.0).acos() / std::f64::consts::PI
    };
    let n = 4000;
    let h = theta_max / n as f64;
    let mut sum = 0.0;
    for i in 0..=n {
        let t = i as f64 * h;
        let weight = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        sum += weight * t.sin() * ring(t);
    }
    sum * h / 3.0 / (1.0 - theta_max.cos())
}

/// An occluding half-plane (y = `HALF_PLANE_H`, x < 0) over a floor (y = 0), seen from below the
/// half-plane by an orthographic camera 1 m across (`HALF_PLANE_PIXELS`² pixels): every pixel
/// is floor, and a light above casts the half-plane's straight edge across the view.
const HALF_PLANE_H: f32 = 1.0;
const HALF_PLANE_PIXELS: u32 = 64;

/// The floor, the half-plane and the camera of the half-plane stage.
fn half_plane() -> (Vec<[Vec3; 3]>, Vec<[Vec3; 3]>, Camera) {
    let h = HALF_PLANE_H;
    let floor = quad(Vec3::ZERO, Vec3::new(20.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -20.0));
    let blocker = quad(Vec3::new(-10.0, h, 0.0), Vec3::new(10.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -20.0));
    let view = Camera {
        position: [0.0, 0.5, 0.0],
        forward: [0.0, -1.0, 0.0],
        up: [0.0, 0.0, -1.0],
        yfov: 0.8,
        aspect: None,
        znear: 0.01,
        orthographic: Some(umbra::scene::Orthographic { xmag: 0.5, ymag: 0.5, zfar: 10.0 }),
        jitter: [0.0; 2],
    };
    (floor, blocker, view)
}

/// Per pixel of the half-plane stage the light's visibility on the floor (the lit floor over the
/// floor alone, which nothing shadows: the radiance term is the same), with `shadows` and `rays`
/// shadow rays per frame over `frames` frames.
fn half_plane_visibility(
    gpu: &Gpu,
    l: &Light,
    shadows: ShadowSettings,
    rays: u32,
    frames: u32,
) -> Vec<Option<f64>> {
    let (floor, blocker, view) = half_plane();
    let size = HALF_PLANE_PIXELS;
    let bare = build("floor", std::slice::from_ref(&floor), vec![l.clone()], view);
    let full = build("half-plane", &[floor, blocker], vec![l.clone()], view);
    let (open, _) = hybrid_mean(gpu, &bare, &view, size, ShadowSettings::default(), 1, 1);
    let (lit, material) = hybrid_mean(gpu, &full, &view, size, shadows, rays, frames);
    (0..lit.len())
        .map(|i| (material[i] == 0 && open[i][1] > 1e-4).then(|| (lit[i][1] / open[i][1]) as f64))
        .collect()
}

/// Ray-traced shadows of sized lights against the closed form: an occluding half-plane (y = 1,
/// x < 0) over a floor (y = 0), lit by a point light made a sphere of radius 0.5 at height 3 and,
/// apart, by a sun of angular radius 8° tilted 17° across the edge. Per floor pixel (64×64,
/// orthographic from below the half-plane, 1 m across the penumbra) the visibility (the lit
/// floor over the unoccluded floor) against the exact open fraction of the light (open_fraction)
/// at 256 rays (4 frames of 64): the mean error over the penumbra within 0.004 (no bias; measured
/// −0.0004 for the sphere, 0.00001 for the sun) and every pixel within 0.05 (a plain Monte Carlo
/// estimate's standard deviation is up to 0.031 at 256 rays: plain sampling would miss 0.05 in
/// some 10 % of the penumbra; the stratified sequence's largest errors measured 0.024 and 0.027).
/// The pixels' estimates are independent (each its own rotation of the sequence), so the mean's
/// standard deviation is below 0.031 / √1000: 0.004 is over 4 of them (significance < 10⁻⁴).
#[test]
fn sized_light_shadows_match_the_analytic_penumbra() {
    use glam::DVec3;
    let gpu = Gpu::new();
    let (h, size, rays, frames) = (HALF_PLANE_H, HALF_PLANE_PIXELS, 64u32, 4u32);
    let (_, _, view) = half_plane();
    let gpu_camera = umbra::gpu::layout::GpuCamera::new(&view, (size, size));
    let (right, up) = (Vec3::from(gpu_camera.right), Vec3::from(gpu_camera.up));
    // The floor point a pixel's (orthographic) ray meets.
    let floor_point = |i: usize| {
        let (x, y) = ((i as u32 % size) as f32 + 0.5, (i as u32 / size) as f32 + 0.5);
        let ndc = (2.0 * x / size as f32 - 1.0, 1.0 - 2.0 * y / size as f32);
        let o = Vec3::from(view.position) + ndc.0 * right + ndc.1 * up;
        DVec3::new(o.x as f64, 0.0, o.z as f64)
    };
    let (radius, centre) = (0.5f32, Vec3::new(0.0, 3.0, 0.0));
    let sun_angle = 8f32.to_radians();
    let sun_dir = Vec3::new(0.0, -1.0, 0.3).normalize();
    let cases = [
        ("sphere", light(LightKind::Point, centre, Vec3::NEG_Y, 5.0)),
        ("sun", light(LightKind::Directional, Vec3::ZERO, sun_dir, 3.0)),
    ];
    for (name, l) in cases {
        let sized =
            ShadowSettings { sized_rays: true, light_radius: radius, sun_angle, ..ShadowSettings::default() };
        let visibility = half_plane_visibility(&gpu, &l, sized, rays, frames);
        let (mut sum, mut count, mut worst, mut floor_pixels) = (0.0, 0, (0.0f64, 0usize), 0);
        for (i, got) in visibility.iter().enumerate() {
            let Some(got) = *got else { continue };
            floor_pixels += 1;
            let p = floor_point(i);
            let (w, theta_max) = if l.kind == LightKind::Point {
                let to = centre.as_dvec3() - p;
                (to.normalize(), (radius as f64 / to.length()).asin())
            } else {
                (-sun_dir.as_dvec3(), sun_angle as f64)
            };
            let m = DVec3::new(h as f64, p.x, 0.0).normalize();
            let want = open_fraction(w, m, theta_max);
            let err = got - want;
            if want > 1e-4 && want < 1.0 - 1e-4 {
                sum += err;
                count += 1;
            }
            if err.abs() > worst.0 {
                worst = (err.abs(), i);
            }
        }
        let mean = sum / count.max(1) as f64;
        eprintln!(
            "{name}: {floor_pixels} floor pixels, {count} in the penumbra: mean error {mean:.5}, largest {:.4} \
             (pixel {})",
            worst.0, worst.1
        );
        assert!(floor_pixels == (size * size) as usize, "{name}: {floor_pixels} floor pixels");
        assert!(count > 300, "{name}: too narrow a penumbra ({count} pixels)");
        assert!(mean.abs() < 0.004, "{name}: mean error over the penumbra {mean}");
        assert!(worst.0 < 0.05, "{name}: pixel {} off by {}", worst.1, worst.0);
    }
}

/// Sized lights of radius 0 and angle 0 are points: their kernel (rays to the sphere or cone)
/// gives today's hard ray-traced image bit for bit, for a point, a spot and a sun together (and
/// a radius above 0 does change it: the kernel is the one in use).
#[test]
fn sized_lights_of_size_zero_are_the_hard_ray_traced_shadows() {
    let gpu = Gpu::new();
    let scene = mixed_scene(light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.3, -1.0, 0.2), 2.0));
    let view = scene.camera(None).unwrap();
    let point = ShadowSettings::default();
    let zero = ShadowSettings { sized_rays: true, light_radius: 0.0, sun_angle: 0.0, ..point };
    let sized = ShadowSettings { sized_rays: true, light_radius: 0.2, sun_angle: 0.05, ..point };
    let (hard, _) = hybrid_mean(&gpu, &scene, &view, 96, point, 4, 1);
    let (zeroed, _) = hybrid_mean(&gpu, &scene, &view, 96, zero, 4, 1);
    let (soft, _) = hybrid_mean(&gpu, &scene, &view, 96, sized, 4, 1);
    let differing = |a: &[[f32; 4]], b: &[[f32; 4]]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    let (same, changed) = (differing(&hard, &zeroed), differing(&hard, &soft));
    eprintln!("pixels differing from hard rays: size 0: {same}; radius 0.2, angle 0.05: {changed}");
    assert_eq!(same, 0, "sized lights of size 0 differ from points in {same} pixels");
    assert!(changed > 200, "sized lights hardly change the image: {changed} pixels");
    // One invocation traces every light's rays: 3 lights × 32 rays is past the 64 it may.
    let sized_lights = Some(umbra::passes::deferred::SizedLights { radius: 0.2, sun_angle: 0.05 });
    let many = LightingSettings { shadow_rays: 32, sized_lights, ..Default::default() };
    let error = many.validate_sized_rays(3).unwrap_err().to_string();
    assert!(error.contains("32 shadow rays per sized light × 3 punctual lights"), "{error}");
    assert!(LightingSettings { shadow_rays: 16, ..many }.validate_sized_rays(3).is_ok());
}

/// What sized lights' rays are for: PCSS (1024² maps, filter radius up to 64 texels, a sun of 8°
/// across the half-plane's edge, so the penumbra spans a quarter of the view) is charted against
/// ray-traced shadows of the same sized sun, not of a point: its floor visibility's RMS error
/// against the sized rays (64 rays × 4 frames) is below half its error against the point's hard
/// shadow (measured 0.042 against 0.163). (With the default largest radius of 16 texels PCSS
/// cuts this penumbra short, and its errors are 0.088 and 0.083: the clamp looks harmless
/// against the point reference.)
#[test]
fn pcss_is_closer_to_sized_light_rays_than_to_point_rays() {
    let gpu = Gpu::new();
    let sun_angle = 8f32.to_radians();
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.0, -1.0, 0.3), 3.0);
    // The penumbra's radius, about 0.14 m, is some 30 texels of the cascade the floor falls in:
    // the default largest filter radius (16 texels) would cut it short.
    let pcss = ShadowSettings {
        method: ShadowMethod::Pcss,
        map_size: 1024,
        sun_angle,
        max_radius: 64.0,
        ..Default::default()
    };
    let sized = ShadowSettings { sized_rays: true, sun_angle, ..Default::default() };
    let point = half_plane_visibility(&gpu, &sun, ShadowSettings::default(), 1, 1);
    let soft = half_plane_visibility(&gpu, &sun, sized, 64, 4);
    let filtered = half_plane_visibility(&gpu, &sun, pcss, 1, 1);
    let rms = |a: &[Option<f64>]| {
        let d: Vec<f64> =
            a.iter().zip(&filtered).filter_map(|(a, f)| Some((a.as_ref()? - f.as_ref()?).powi(2))).collect();
        (d.iter().sum::<f64>() / d.len().max(1) as f64).sqrt()
    };
    let (against_sized, against_point) = (rms(&soft), rms(&point));
    let penumbra = soft.iter().filter(|v| v.is_some_and(|v| (0.05..0.95).contains(&v))).count();
    eprintln!(
        "{penumbra} of {} pixels in the sized rays' penumbra; PCSS RMS visibility error: against sized rays \
         {against_sized:.4}, against point rays {against_point:.4}",
        soft.len()
    );
    assert!(penumbra > 800, "too narrow a penumbra: {penumbra}");
    assert!(
        against_sized < 0.5 * against_point,
        "PCSS against sized rays {against_sized}, against point rays {against_point}"
    );
}
