//! Light sampling through `spirv/light_sample_test.comp`: the environment map and the emissive
//! triangles.

use crate::common::{gamma_q, Gpu};
use crate::{pooled_chi_square, print_worst_cells, Numbers};
use glam::Vec3;
use umbra::gpu::kernels::light_sample_test;
use umbra::gpu::layout::LightTestParams;
use umbra::gpu::Pipeline;
use umbra::passes::pathtrace::EmitterSampling;
use umbra::vk::{raw, Buffer, MemoryLocation};

// ---------------------------------------------------------------------------------------------
// Light sampling: the environment map and the emissive triangles, through
// `spirv/light_sample_test.comp` (the renderer's environment.glsl and shading.glsl).
/// The light-sampling cases (environment, light pick, point on a triangle, emissive solid angle
/// with fresh and with reused numbers, by area and by solid angle, next to two huge emitters,
/// and the irradiance by area against by solid angle) form their own family: significance 0.01
/// with a Šidák correction over these twelve.
fn light_alpha() -> f64 {
    1.0 - 0.99f64.powf(1.0 / 12.0)
}

/// An emissive triangle of a light test scene: its corners and its radiance.
type LightTriangle = ([[f32; 3]; 3], f32);

/// The emissive triangles of the light test scene, as seen from the shading point at the origin
/// (normal +Y): five triangles of different sizes, orientations and radiances, none hiding
/// another, each facing the origin. Light sampling draws the points of the first, which subtends
/// 0.3 sr there, by solid angle, those of the others (0.015 to 0.06 sr, and a small far one under
/// 1e-4 sr) by area (`emissive_point`).
const LIGHT_TRIANGLES: [LightTriangle; 5] = [
    ([[-0.3, 1.5, -0.8], [-1.05, 1.5, 0.8], [-1.8, 1.5, -0.8]], 1.0),
    ([[0.6, 1.0, -0.8], [0.9, 1.0, -0.8], [0.75, 1.0, -0.5]], 20.0),
    ([[0.0, 2.0, 0.8], [0.8, 2.2, 0.8], [0.4, 1.6, 1.4]], 5.0),
    ([[1.2, 0.6, 0.6], [1.6, 0.9, 0.3], [1.5, 0.3, 1.0]], 3.0),
    ([[-1.02, 2.0, -1.62], [-0.99, 2.0, -1.62], [-1.0, 2.02, -1.58]], 2000.0),
];

fn light_scene() -> umbra::scene::Scene {
    scene_of_lights(&LIGHT_TRIANGLES)
}

/// A scene of emissive triangles (corners, radiance), each wound to face the origin.
fn scene_of_lights(lights: &[LightTriangle]) -> umbra::scene::Scene {
    let mut scene = umbra::scene::Scene { name: "light test".into(), ..Default::default() };
    for (i, (corners, radiance)) in lights.iter().enumerate() {
        let [a, b, c] = corners.map(Vec3::from);
        // Wind every triangle to face the origin.
        let n = (b - a).cross(c - a).normalize();
        let (b, c) = if n.dot(-(a + b + c) / 3.0) > 0.0 { (b, c) } else { (c, b) };
        let n = (b - a).cross(c - a).normalize();
        let base = scene.positions.len() as u32;
        for v in [a, b, c] {
            scene.positions.push(v.into());
            scene.normals.push(n.into());
        }
        scene.triangles.push([base, base + 1, base + 2]);
        scene.triangle_material.push(i as u32);
        scene.materials.push(umbra::scene::Material { emissive: [*radiance; 3], ..Default::default() });
    }
    scene.update_emissive();
    scene
}

/// One light-test dispatch's settings.
#[derive(Clone, Copy)]
struct LightRun {
    mode: u32,
    variant: u32,
    count: u32,
}

struct LightKernel {
    pipeline: Pipeline<light_sample_test::Kernel>,
    scene: umbra::gpu::scene::GpuScene,
    arrays: umbra::gpu::scene::SceneArrays,
}

impl LightKernel {
    fn new(gpu: &Gpu, env: Option<&umbra::environment::EnvironmentMap>) -> Self {
        Self::with_scene(gpu, env, &light_scene(), EmitterSampling::Area)
    }

    fn with_scene(
        gpu: &Gpu,
        env: Option<&umbra::environment::EnvironmentMap>,
        lights: &umbra::scene::Scene,
        emitters: EmitterSampling,
    ) -> Self {
        let arrays = umbra::gpu::scene::SceneArrays::new(lights).unwrap();
        let mut scene = umbra::gpu::scene::GpuScene::from_arrays(gpu, &arrays).unwrap();
        if let Some(env) = env {
            scene.set_environment(gpu, env).unwrap();
        }
        let spec = light_sample_test::Spec { solid_angle_emitters: emitters == EmitterSampling::SolidAngle };
        let pipeline = Pipeline::for_scene(gpu, &scene, &spec).unwrap();
        Self { pipeline, scene, arrays }
    }

    fn run(&self, gpu: &Gpu, run: LightRun, dirs: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
        let input = Buffer::upload(
            gpu,
            "light test directions",
            if dirs.is_empty() { &[[0.0f32; 4]] } else { dirs },
            usage,
        )
        .unwrap();
        let output =
            Buffer::new(gpu, "light test results", run.count as u64 * 16, usage, MemoryLocation::GpuOnly)
                .unwrap();
        let (w, h) = self.scene.env_size.unwrap_or((1, 1));
        let params = LightTestParams {
            point: [0.0; 3],
            normal: [0.0, 1.0, 0.0],
            mode: run.mode,
            count: run.count,
            seed: 4242,
            variant: run.variant,
            env_size: [w, h],
            light_count: self.scene.light_count,
            ..Default::default()
        };
        gpu.record(|rec| {
            let resources =
                light_sample_test::Resources { scene: &self.scene, directions: &input, results: &output };
            self.pipeline.record(rec, &resources, &params, [run.count, 1, 1])
        })
        .unwrap();
        output.read(gpu).unwrap()
    }
}

/// `env_uv` of environment.glsl, in f64.
fn env_uv(d: [f32; 4]) -> (f64, f64) {
    let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
    let u = x.atan2(-z) / std::f64::consts::TAU + 0.5;
    let v = y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
    (u, v)
}

/// Chi-square of `env_sample` against `env_pdf` (or a deliberately wrong pdf, `variant` 1) on
/// `map`. Cells are the texels split 2 × 2 in (u, v): the sampled density is constant over a
/// texel in (u, v), and env_pdf × the Jacobian 2π² sin θ is constant there too, so the
/// quadrature below is exact for the true pdf whatever its points. Returns (p, chi2, dof, mass).
fn env_chi_square(
    gpu: &Gpu,
    kernel: &LightKernel,
    map: &umbra::environment::EnvironmentMap,
    variant: u32,
    samples: u32,
) -> (f64, f64, usize, f64) {
    const SPLIT: usize = 2; // cells per texel side
    const QUAD: usize = 2; // quadrature points per cell side
    let (cw, ch) = (map.width * SPLIT, map.height * SPLIT);
    let cell = |d: [f32; 4]| {
        let (u, v) = env_uv(d);
        let x = ((u * cw as f64) as usize).min(cw - 1);
        let y = ((v * ch as f64) as usize).min(ch - 1);
        y * cw + x
    };
    let drawn = kernel.run(gpu, LightRun { mode: 0, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; cw * ch];
    for d in &drawn {
        assert!(d[3].is_finite() && d[3] > 0.0, "env_sample gave {d:?}");
        observed[cell(*d)] += 1.0;
    }
    // Quadrature points at the centres of QUAD × QUAD sub-cells of every cell.
    let (qw, qh) = (cw * QUAD, ch * QUAD);
    let mut points = Vec::with_capacity(qw * qh);
    let mut jacobian = Vec::with_capacity(qw * qh);
    for y in 0..qh {
        let theta = std::f64::consts::PI * (y as f64 + 0.5) / qh as f64;
        for x in 0..qw {
            let phi = (((x as f64 + 0.5) / qw as f64) - 0.5) * std::f64::consts::TAU;
            let s = theta.sin();
            points.push([(s * phi.sin()) as f32, theta.cos() as f32, (-s * phi.cos()) as f32, 0.0]);
            jacobian.push(2.0 * std::f64::consts::PI * std::f64::consts::PI * s / (qw * qh) as f64);
        }
    }
    let pdfs = kernel.run(gpu, LightRun { mode: 1, variant, count: points.len() as u32 }, &points);
    let mut expected = vec![0.0f64; cw * ch];
    for (i, p) in pdfs.iter().enumerate() {
        let (x, y) = (i % qw / QUAD, i / qw / QUAD);
        expected[y * cw + x] += p[3] as f64 * jacobian[i];
    }
    let mass = expected.iter().sum();
    let n = samples as f64;
    if std::env::var("UMBRA_CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, n);
    }
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, n);
    (p, chi2, dof, mass)
}

/// Environment importance sampling on a real HDR sky (tests/reference/sky-128x64.exr, a
/// downsampled Poly Haven sunrise whose sun peaks near 2,100): the directions `env_sample` draws
/// follow `env_pdf`, and a pdf that forgets the sin θ of the (u, v) → sphere Jacobian is rejected.
#[test]
fn environment_sampling_on_a_real_hdr() {
    let gpu = Gpu::new();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(&path).unwrap();
    let peak = map.texels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    assert!(peak > 1000.0, "the test map should have a sun above 1000 (peak {peak})");
    let kernel = LightKernel::new(&gpu, Some(&map));
    let alpha = light_alpha();
    let (p, chi2, dof, mass) = env_chi_square(&gpu, &kernel, &map, 0, 1 << 20);
    eprintln!("env_sample vs env_pdf: chi2 {chi2:.1}, dof {dof}, p {p:.4}, pdf mass {mass:.6}");
    assert!((mass - 1.0).abs() < 1e-4, "env_pdf integrates to {mass}");
    assert!(p >= alpha, "env_sample does not follow env_pdf: p = {p} < {alpha}");
    let (p, chi2, dof, mass) = env_chi_square(&gpu, &kernel, &map, 1, 1 << 20);
    eprintln!("env_sample vs a pdf without 1/sin θ: chi2 {chi2:.1}, dof {dof}, p {p:.2e}, mass {mass:.4}");
    assert!(p < alpha, "a pdf without 1/sin θ was not rejected (p = {p})");
}

/// Cell of barycentrics (b1, b2) among the K² congruent sub-triangles of a triangle split by
/// lines parallel to its edges (equal areas; the split is the same whatever the vertex order).
/// Cells are numbered (i K + j) 2 + upper; half of the 2K² numbers are unused.
fn sub_triangle(b1: f64, b2: f64, k: usize) -> usize {
    let (x, y) = (b1.clamp(0.0, 1.0) * k as f64, b2.clamp(0.0, 1.0) * k as f64);
    let (mut i, mut j) = ((x as usize).min(k - 1), (y as usize).min(k - 1));
    while i + j > k - 1 {
        if i > j {
            i -= 1;
        } else {
            j -= 1;
        }
    }
    let upper = i + j < k - 1 && (x - i as f64) + (y - j as f64) > 1.0;
    (i * k + j) * 2 + upper as usize
}

/// The centroid (b1, b2) of sub-triangle `cell` (as [`sub_triangle`] numbers them), if used.
fn sub_triangle_centroid(cell: usize, k: usize) -> Option<(f64, f64)> {
    let (i, j, upper) = (cell / 2 / k, cell / 2 % k, cell % 2 == 1);
    let offset = if upper { 2.0 / 3.0 } else { 1.0 / 3.0 };
    let valid = if upper { i + j + 1 < k } else { i + j < k };
    valid.then(|| ((i as f64 + offset) / k as f64, (j as f64 + offset) / k as f64))
}

/// The solid angle of the spherical triangle with unit corners a, b, c (Van Oosterom and
/// Strackee, as `spherical_triangle_area` in spirv/include/sampling.glsl), in f64.
fn solid_angle(a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> f64 {
    (2.0 * a.dot(b.cross(c)).atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c))).abs()
}

/// The corners (b1, b2) of sub-triangle `cell` (as [`sub_triangle`] numbers them; a used one).
fn sub_triangle_corners(cell: usize, k: usize) -> [(f64, f64); 3] {
    let (i, j, upper) = ((cell / 2 / k) as f64, (cell / 2 % k) as f64, cell % 2 == 1);
    let k = k as f64;
    if upper {
        [((i + 1.0) / k, (j + 1.0) / k), (i / k, (j + 1.0) / k), ((i + 1.0) / k, j / k)]
    } else {
        [(i / k, j / k), ((i + 1.0) / k, j / k), (i / k, (j + 1.0) / k)]
    }
}

/// The nearest of a light scene's triangles a ray from the origin along `d` hits: (scene
/// triangle, b1, b2), Möller–Trumbore in f64.
fn hit_light(scene: &umbra::scene::Scene, d: [f64; 3]) -> Option<(usize, f64, f64)> {
    let d = glam::DVec3::from(d);
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for (t, tri) in scene.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| Vec3::from(scene.positions[v as usize]).as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-12 {
            continue;
        }
        let tv = -a;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = d.dot(qv) / det;
        let dist = e2.dot(qv) / det;
        let eps = 1e-6;
        if u >= -eps && v >= -eps && u + v <= 1.0 + eps && dist > 0.0 && best.is_none_or(|b| dist < b.0) {
            best = Some((dist, t, u, v));
        }
    }
    best.map(|(_, t, u, v)| (t, u, v))
}

/// The emissive-triangle pick (`pick_light`) follows the table's pmf, and that pmf is each
/// triangle's share of the emitted power (radiance × area × π), the same in the lights table and
/// in the triangles the path tracer's MIS reads.
#[test]
fn light_pick_follows_the_power_pmf() {
    let gpu = Gpu::new();
    let kernel = LightKernel::new(&gpu, None);
    let lights = &kernel.arrays.lights;
    assert_eq!(lights.len(), LIGHT_TRIANGLES.len());
    let power: Vec<f64> = LIGHT_TRIANGLES
        .iter()
        .map(|(c, l)| {
            let [a, b, c] = c.map(|v| Vec3::from(v).as_dvec3());
            *l as f64 * 0.5 * (b - a).cross(c - a).length() * std::f64::consts::PI
        })
        .collect();
    let total: f64 = power.iter().sum();
    let scene = light_scene();
    for (k, light) in lights.iter().enumerate() {
        // BVH order to scene order: find the scene triangle with the same area and pmf.
        let tri = &kernel.arrays.triangles[light.tri as usize];
        assert_eq!(tri.light_pmf, light.pmf, "entry {k}: the MIS pmf differs from the pick pmf");
        let entry = scene.emissive.triangles.iter().position(|&t| {
            let share = power[t as usize] / total;
            (share - light.pmf as f64).abs() < 1e-6 && (tri.area - light.area).abs() < 1e-6
        });
        assert!(entry.is_some(), "entry {k} ({light:?}) matches no triangle's power share");
    }
    let samples = 1u32 << 18;
    let drawn = kernel.run(&gpu, LightRun { mode: 2, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; lights.len()];
    for d in &drawn {
        let k = d[0] as usize;
        assert_eq!(d[1], lights[k].pmf);
        observed[k] += 1.0;
    }
    let expected: Vec<f64> = lights.iter().map(|l| l.pmf as f64).collect();
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    eprintln!("pick_light: observed {observed:?}, pmf {expected:?}: chi2 {chi2:.2}, dof {dof}, p {p:.4}");
    assert!(p >= light_alpha(), "pick_light does not follow the pmf: p = {p}");
}

/// `sample_triangle` is uniform: chi-square over the 256 congruent sub-triangles of a 16-way split.
#[test]
fn triangle_sampling_is_uniform() {
    const K: usize = 16;
    let gpu = Gpu::new();
    let kernel = LightKernel::new(&gpu, None);
    let samples = 1u32 << 18;
    let drawn = kernel.run(&gpu, LightRun { mode: 3, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; 2 * K * K];
    for d in &drawn {
        assert!(d[0] >= 0.0 && d[1] >= 0.0 && d[0] + d[1] <= 1.0 + 1e-6, "barycentrics {d:?}");
        observed[sub_triangle(d[0] as f64, d[1] as f64, K)] += 1.0;
    }
    let expected: Vec<f64> = (0..2 * K * K)
        .map(|c| if sub_triangle_centroid(c, K).is_some() { 1.0 / (K * K) as f64 } else { 0.0 })
        .collect();
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    eprintln!("sample_triangle: chi2 {chi2:.1}, dof {dof}, p {p:.4}");
    assert!(p >= light_alpha(), "sample_triangle is not uniform: p = {p}");
}

/// Chi-square of the directions `sample_emissive` draws from the origin against the solid-angle
/// light pdf the path tracer's MIS gives a BSDF ray in the same direction (`variant` 1: a
/// deliberately wrong one). Cells: each light's K² sub-triangles, seen from the origin; a sample
/// is binned by tracing its direction to the lights (f64, on the CPU). The expected count is
/// ∫ pdf dω over the cell: the pdf at the cell's centroid times the cell's exact solid angle (exact
/// where the pdf is constant in solid angle, as where a light is sampled by solid angle; where it
/// is sampled by area, the pdf varies as r² / cos across a cell, which for these far, small lights
/// is within 1e-3 of constant). Returns (p, chi2, dof, mass, the largest
/// relative difference between a sample's pdf and the MIS pdf in its direction, the fraction of
/// samples whose direction the MIS ray misses).
fn emissive_chi_square(
    gpu: &Gpu,
    kernel: &LightKernel,
    scene: &umbra::scene::Scene,
    numbers: Numbers,
    variant: u32,
) -> (f64, f64, usize, f64, f64, f64) {
    const K: usize = 8;
    let lights = scene.triangles.len();
    let samples = 1u32 << 19;
    let mode = if numbers == Numbers::Reused { 6 } else { 4 };
    let drawn = kernel.run(gpu, LightRun { mode, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; lights * 2 * K * K];
    for d in &drawn {
        assert!(d[3].is_finite() && d[3] > 0.0, "sample_emissive failed or gave a bad pdf: {d:?}");
        let dir = [d[0] as f64, d[1] as f64, d[2] as f64];
        let Some((t, b1, b2)) = hit_light(scene, dir) else {
            panic!("sample_emissive gave {d:?}, which points at no light");
        };
        observed[t * 2 * K * K + sub_triangle(b1, b2, K)] += 1.0;
    }
    // The NEE pdf of each sample against the MIS pdf of its direction.
    let check: Vec<[f32; 4]> = drawn.iter().take(1 << 15).map(|d| [d[0], d[1], d[2], 0.0]).collect();
    let mis = kernel.run(gpu, LightRun { mode: 5, variant, count: check.len() as u32 }, &check);
    // A direction through a light's very edge may miss it when traced back (f32 rounding): those
    // are counted apart; every other sample must agree.
    let misses = mis.iter().filter(|m| m[3] == 0.0).count() as f64 / mis.len() as f64;
    let mismatch = drawn
        .iter()
        .zip(&mis)
        .filter(|(_, b)| b[3] > 0.0)
        .map(|(a, b)| ((a[3] - b[3]) / a[3]).abs() as f64)
        .fold(0.0, f64::max);
    // Expected: the MIS pdf at each cell's centroid times the cell's solid angle.
    let mut points = Vec::new();
    let mut solid_angles = Vec::new();
    let mut cells = Vec::new();
    for (t, tri) in scene.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| Vec3::from(scene.positions[v as usize]).as_dvec3());
        for cell in 0..2 * K * K {
            if let Some((b1, b2)) = sub_triangle_centroid(cell, K) {
                let w = ((1.0 - b1 - b2) * a + b1 * b + b2 * c).normalize();
                points.push([w.x as f32, w.y as f32, w.z as f32, 0.0]);
                let [ca, cb, cc] = sub_triangle_corners(cell, K)
                    .map(|(u, v)| ((1.0 - u - v) * a + u * b + v * c).normalize());
                solid_angles.push(solid_angle(ca, cb, cc));
                cells.push(t * 2 * K * K + cell);
            }
        }
    }
    let pdfs = kernel.run(gpu, LightRun { mode: 5, variant, count: points.len() as u32 }, &points);
    let mut expected = vec![0.0f64; observed.len()];
    for ((p, omega), &cell) in pdfs.iter().zip(&solid_angles).zip(&cells) {
        expected[cell] += p[3] as f64 * omega;
    }
    let mass = expected.iter().sum();
    if std::env::var("UMBRA_CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, samples as f64);
    }
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    (p, chi2, dof, mass, mismatch, misses)
}

/// [`emissive_chi_square`] with fresh and with reused numbers (`what` names the case): the MIS
/// light pdf integrates to 1 over the lights, agrees with each sample's NEE pdf, is found again
/// by tracing the sample's direction, and the directions follow it at [`light_alpha`].
fn assert_emissive_follows_the_mis_pdf(
    gpu: &Gpu,
    kernel: &LightKernel,
    scene: &umbra::scene::Scene,
    what: &str,
) {
    let alpha = light_alpha();
    for numbers in [Numbers::Fresh, Numbers::Reused] {
        let (p, chi2, dof, mass, mismatch, misses) = emissive_chi_square(gpu, kernel, scene, numbers, 0);
        eprintln!(
            "sample_emissive ({what}, {numbers:?} numbers) vs MIS pdf: chi2 {chi2:.1}, dof {dof}, p {p:.4}, \
             mass {mass:.6}, largest NEE/MIS pdf difference {mismatch:.2e}, MIS rays missing the light {misses:.1e}"
        );
        assert!((mass - 1.0).abs() < 1e-3, "{what}: the MIS light pdf integrates to {mass}");
        assert!(mismatch < 1e-3, "{what}: NEE and MIS disagree on a sample's pdf by {mismatch}");
        assert!(misses < 1e-3, "{what}: {misses} of the NEE directions miss their light when traced");
        assert!(
            p >= alpha,
            "sample_emissive ({what}, {numbers:?} numbers) does not follow the MIS light pdf: p = {p} < {alpha}"
        );
    }
}

/// Next-event estimation on emissive triangles (`sample_emissive`: pick by power, then a point
/// uniform in the triangle's solid angle, pdf pmf / Ω, or for those that subtend less uniform
/// on its area, pdf pmf / area × r² / cos) draws directions with the density the path tracer's MIS
/// assigns them (`emissive_pdf` at a BSDF ray's hit), with fresh numbers and with sample reuse
/// (the triangle picked by u.y, its share stretched back as the point's first number: a stretch
/// off the triangle's interval of the CDF makes the points non-uniform on it, which the
/// sub-triangle cells see). Rejected: a MIS pdf that forgets the cosine at the light, and one that
/// gives the area-sampling density where the points are drawn by solid angle (the sub-triangles
/// then see the r² and cosine area sampling has and solid-angle sampling has not).
#[test]
fn emissive_sampling_matches_the_mis_light_pdf() {
    // Each triangle clearly in its regime (`emissive_solid_angle`, spirv/include/shading.glsl: by
    // solid angle where both its area over its first corner's squared distance and its solid
    // angle reach SPHERICAL_MIN, 0.2 sr): light 0 by solid angle, the others by area.
    const SPHERICAL_MIN: f64 = 0.2;
    for (k, (corners, _)) in LIGHT_TRIANGLES.iter().enumerate() {
        let v = corners.map(|v| Vec3::from(v).as_dvec3());
        let [a, b, c] = v.map(|v| v.normalize());
        let omega = solid_angle(a, b, c);
        let near = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length() / v[0].length_squared();
        let clear = |x: f64| !(SPHERICAL_MIN / 1.2..SPHERICAL_MIN * 1.2).contains(&x);
        let by_solid_angle = near >= SPHERICAL_MIN && omega >= SPHERICAL_MIN;
        assert!(
            by_solid_angle == (k == 0) && clear(omega) && clear(near),
            "light {k} (solid angle {omega}, area over distance² {near}) is not clearly in its regime"
        );
    }
    let gpu = Gpu::new();
    let scene = light_scene();
    let alpha = light_alpha();
    for emitters in EmitterSampling::ALL {
        let kernel = LightKernel::with_scene(&gpu, None, &scene, emitters);
        assert_emissive_follows_the_mis_pdf(&gpu, &kernel, &scene, &format!("{emitters:?}"));
        let mut wrong = vec![(1, "without the light's cosine")];
        if emitters == EmitterSampling::SolidAngle {
            wrong.push((2, "by area where sampled by solid angle"));
        }
        for (variant, wrong) in wrong {
            let (p, chi2, dof, mass, ..) =
                emissive_chi_square(&gpu, &kernel, &scene, Numbers::Fresh, variant);
            eprintln!(
                "sample_emissive ({emitters:?}) vs a MIS pdf {wrong}: chi2 {chi2:.1}, dof {dof}, p {p:.2e}, mass {mass:.4}"
            );
            assert!(p < alpha, "a MIS pdf {wrong} was not rejected (p = {p})");
        }
    }
}

/// A triangle 0.1 above the origin, subtending 5.6 sr there: area sampling's failure case.
const HUGE_EMITTER: LightTriangle = ([[-1.0, 0.1, -1.0], [1.5, 0.1, -0.5], [-0.5, 0.1, 1.5]], 1.0);

/// Light sampling next to a huge emitter (the failure case of area sampling: its 1/r² and cosine
/// swing across the triangle), from the origin (normal +Y): a triangle 0.1 above it, subtending
/// 5.6 sr; and one standing on the origin's horizon (as the light of Khronos' CornellBox-Original
/// stands on its floor), 0.3 sr. Their points are drawn by solid angle; the directions follow the
/// MIS light pdf as the far lights' do, and the area-sampling density is rejected.
#[test]
fn emissive_sampling_next_to_a_huge_emitter() {
    let scenes: [&[LightTriangle]; 2] =
        [&[HUGE_EMITTER], &[([[-0.3, 0.002, -0.2], [-0.3, 0.8, -0.6], [-0.3, 0.002, -1.0]], 4.0)]];
    let gpu = Gpu::new();
    let alpha = light_alpha();
    for lights in scenes {
        let scene = scene_of_lights(lights);
        let kernel = LightKernel::with_scene(&gpu, None, &scene, EmitterSampling::SolidAngle);
        assert_emissive_follows_the_mis_pdf(&gpu, &kernel, &scene, "by a huge emitter");
        let (p, ..) = emissive_chi_square(&gpu, &kernel, &scene, Numbers::Fresh, 2);
        assert!(
            p < alpha,
            "a MIS pdf by area where sampled by solid angle was not rejected by a huge emitter (p = {p})"
        );
    }
}

/// What solid-angle sampling buys next to a huge emitter: the irradiance at the origin (normal +Y)
/// from a triangle 0.1 above it, estimated per sample as L cos θ / pdf. Both ways estimate the
/// same irradiance (a z-test at the light family's significance), and by area the estimates'
/// relative standard deviation is over three times that by solid angle, whose estimates vary
/// only with cos θ (measured: 5.6 and 0.47).
#[test]
fn solid_angle_sampling_quiets_a_huge_emitter() {
    let gpu = Gpu::new();
    let scene = scene_of_lights(&[HUGE_EMITTER]);
    let samples = 1u32 << 19;
    let moments = EmitterSampling::ALL.map(|emitters| {
        let kernel = LightKernel::with_scene(&gpu, None, &scene, emitters);
        let drawn = kernel.run(&gpu, LightRun { mode: 4, variant: 0, count: samples }, &[]);
        let estimates: Vec<f64> =
            drawn.iter().map(|d| if d[3] > 0.0 { d[1] as f64 / d[3] as f64 } else { 0.0 }).collect();
        let n = estimates.len() as f64;
        let mean = estimates.iter().sum::<f64>() / n;
        let var = estimates.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / (n - 1.0);
        (mean, var, n)
    });
    let [(mean_a, var_a, n_a), (mean_s, var_s, n_s)] = moments;
    let (rel_a, rel_s) = (var_a.sqrt() / mean_a, var_s.sqrt() / mean_s);
    let z = (mean_a - mean_s) / (var_a / n_a + var_s / n_s).sqrt();
    eprintln!(
        "irradiance under a huge emitter: by area {mean_a:.5} (rel. std {rel_a:.3}), by solid angle {mean_s:.5} \
         (rel. std {rel_s:.3}), z {z:.2}"
    );
    // Two-sided normal p-value: P(|Z| > |z|) = erfc(|z| / √2) = Q(1/2, z² / 2).
    let p = gamma_q(0.5, z * z / 2.0);
    assert!(p >= light_alpha(), "the two ways estimate different irradiances: z = {z}, p = {p}");
    assert!(
        rel_a > 3.0 * rel_s,
        "solid-angle sampling is not quieter next to a huge emitter: {rel_s} vs {rel_a}"
    );
}
