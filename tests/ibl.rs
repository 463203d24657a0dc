//! Split-sum image-based lighting: the kernels' tables against f64 references, and the hybrid
//! renderer's IBL against the path tracer.

mod common;

use common::Gpu;
use umbra::gpu::scene::GpuScene;
use umbra::ibl::{lut_entry, lut_reference, LUT_SIZE};
use umbra::passes::ibl::{IblResources, IblSettings};
use umbra::scene::Scene;

fn scene_file(name: &str) -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .expect("scene loads")
}

/// The kernel's BRDF table (128² midpoint samples of visible normals and of the cosine
/// hemisphere per entry) equals the f64 Gauss–Legendre reference within 1e-3 in every entry and
/// channel; the reference's own error, estimated by doubling its nodes on a sample of entries,
/// is below 1e-5.
#[test]
fn brdf_lut_matches_cpu_quadrature() {
    let s = LUT_SIZE as usize;
    // The reference's own error: 64 against 128 nodes per axis, at the table's corners and on a
    // sparse grid.
    let mut self_error: f64 = 0.0;
    for j in (0..s).step_by(5).chain([s - 1]) {
        for i in (0..s).step_by(5).chain([s - 1]) {
            let (nv, r) = ((i as f64 + 0.5) / s as f64, (j as f64 + 0.5) / s as f64);
            let (a, b) = (lut_entry(nv, r, 64), lut_entry(nv, r, 128));
            self_error = self_error.max((0..4).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max));
        }
    }
    eprintln!("reference: 64 vs 128 nodes differ by at most {self_error:.2e}");
    assert!(self_error < 1e-5, "the reference quadrature has not converged: {self_error:e}");
    let reference = lut_reference(64);

    let gpu = Gpu::new();
    let scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    let ibl = IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap();
    let lut: Vec<[f32; 4]> = ibl.lut.read(&gpu).unwrap();
    let mut worst = (0.0f64, 0, 0);
    for (k, (g, r)) in lut.iter().zip(&reference).enumerate() {
        for c in 0..4 {
            let e = (g[c] as f64 - r[c]).abs();
            if e > worst.0 {
                worst = (e, k, c);
            }
        }
    }
    let (e, k, c) = worst;
    eprintln!(
        "GPU LUT vs reference: max |error| {e:.2e} at n·v {:.3}, roughness {:.3}, channel {c} (GPU {:?}, CPU {:?})",
        ((k % s) as f64 + 0.5) / s as f64,
        ((k / s) as f64 + 0.5) / s as f64,
        lut[k],
        reference[k]
    );
    for j in [0, s / 2, s - 1] {
        for i in [0, s / 2, s - 1] {
            eprintln!("  nv {i:2} r {j:2}: {:?}", lut[j * s + i]);
        }
    }
    assert!(e < 1e-3, "GPU BRDF table differs from the reference by {e:e}");
}

use umbra::environment::EnvironmentMap;
use umbra::ibl::{irradiance_brute_force, sh9_irradiance, sh9_irradiance_coefficients, texel_direction};

/// A synthetic map of `w` × `h` from a radiance function of direction.
fn synthetic_map(w: usize, h: usize, f: impl Fn([f64; 3]) -> [f64; 3]) -> EnvironmentMap {
    let texels = (0..w * h).map(|i| f(texel_direction(i % w, i / w, w, h).0).map(|v| v as f32)).collect();
    EnvironmentMap::from_texels("synthetic", w, h, texels).unwrap()
}

/// Unit vector.
fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

/// A sky: nothing below the horizon, 0.5 sin(elevation) above it, and a disc of radiance 30
/// within 10° of elevation 50° towards +z (the sphere grid's camera side).
fn sky(d: [f64; 3]) -> [f64; 3] {
    if d[1] < 0.0 {
        return [0.0; 3];
    }
    let sun = unit([0.0, 50f64.to_radians().sin(), 50f64.to_radians().cos()]);
    let cos = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    let disc = if cos > 10f64.to_radians().cos() { 30.0 } else { 0.0 };
    [0.5 * d[1] + disc, 0.45 * d[1] + disc, 0.4 * d[1] + disc]
}

const NORMALS: [[f64; 3]; 6] = [
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 0.6, 0.8],
    [-0.48, 0.6, -0.64],
    [0.0, 0.0, -1.0],
];

/// SH9 irradiance: the kernel's coefficients equal the f64 projection (1e-4 relative to the
/// largest); for a constant map the SH irradiance is exactly π L (the texel-integrated basis
/// has no band 1–2 content; the brute-force sum over texel centres is within 1e-3); for a map of bands 0–2 only, SH9
/// is exact, so it equals the brute-force integral up to the map's quadrature error (measured at
/// 128×64: below 1e-3 relative); for the sky with a bright disc, the truncation error stays
/// within the Cauchy–Schwarz bound |E − E₉| ≤ ‖K‖₂ ‖L‖₂, ‖K‖₂² = 2π/3 − (π/4 + π/3 + 5π/64) =
/// π/192 being the energy of the clamped cosine beyond band 2.
#[test]
fn sh9_irradiance_matches_brute_force() {
    let (w, h) = (128, 64);
    let constant = synthetic_map(w, h, |_| [0.7, 1.0, 1.3]);
    let banded = synthetic_map(w, h, |d| {
        let v = 1.0 + 0.5 * d[1] - 0.3 * d[0] + 0.4 * d[0] * d[2] + 0.2 * (3.0 * d[1] * d[1] - 1.0);
        [v, 0.5 * v, 0.25 * v]
    });
    let bright = synthetic_map(w, h, sky);

    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    for (name, map) in [("constant", &constant), ("banded", &banded), ("sky", &bright)] {
        let cpu = sh9_irradiance_coefficients(map);
        scene.set_environment(&gpu, map).unwrap();
        let ibl = IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap();
        let sh: Vec<[f32; 4]> = ibl.sh.read(&gpu).unwrap();
        let largest = cpu.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let gpu_error = (0..9)
            .flat_map(|k| (0..3).map(move |c| (k, c)))
            .map(|(k, c)| (sh[k][c] as f64 - cpu[k][c]).abs())
            .fold(0.0, f64::max)
            / largest;
        let l2 = map.texels.iter().enumerate().map(|(i, t)| {
            let d_omega = texel_direction(i % w, i / w, w, h).1;
            t.map(|v| (v as f64).powi(2) * d_omega)
        });
        let norm: [f64; 3] = l2.fold([0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]).map(f64::sqrt);
        let k_norm = (std::f64::consts::PI / 192.0).sqrt();
        let (mut worst_rel, mut worst_ratio): (f64, f64) = (0.0, 0.0);
        for n in NORMALS.map(unit) {
            let (e9, exact) = (sh9_irradiance(&cpu, n), irradiance_brute_force(map, n));
            for c in 0..3 {
                let err = (e9[c] - exact[c]).abs();
                worst_rel = worst_rel.max(err / exact[c].max(1e-3 * norm[c]));
                worst_ratio = worst_ratio.max(err / (k_norm * norm[c]));
                match name {
                    "constant" => {
                        let expected = std::f64::consts::PI * [0.7f32, 1.0, 1.3][c] as f64;
                        assert!(
                            (e9[c] - expected).abs() < 1e-9 * expected,
                            "{name}: E {} vs π L {expected}",
                            e9[c]
                        );
                        assert!(
                            (exact[c] - expected).abs() < 1e-3 * expected,
                            "{name}: brute force {}",
                            exact[c]
                        );
                    }
                    "banded" => {
                        assert!(err < 1e-3 * exact[c], "{name} n {n:?}: SH9 {} vs {}", e9[c], exact[c])
                    }
                    _ => assert!(
                        err <= k_norm * norm[c],
                        "{name} n {n:?}: |{} − {}| > bound {}",
                        e9[c],
                        exact[c],
                        k_norm * norm[c]
                    ),
                }
            }
        }
        eprintln!(
            "{name}: GPU vs f64 coefficients {gpu_error:.2e} (of the largest); SH9 vs brute force: worst relative {worst_rel:.2e}, worst |error| / (‖K‖‖L‖) {worst_ratio:.3}"
        );
        assert!(gpu_error < 1e-4, "{name}: GPU SH coefficients differ from f64 by {gpu_error:e}");
        if name == "constant" {
            // The prefiltered levels of a constant are the constant.
            let levels: Vec<[f32; 4]> = ibl.prefiltered.read(&gpu).unwrap();
            let worst = levels.iter().map(|t| (t[1] - 1.0).abs()).fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "prefiltered constant map off by {worst}");
        }
    }
}

use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};

/// spheres.glb for IBL: no sun, no floor, and each sphere shrunk about its centre to radius 0.3
/// (neighbours then hide at most ~25° of elevation from a sphere's lower side, where the sky is
/// dim), so the path tracer's direct environment light differs from IBL by the split sum alone.
fn ibl_spheres() -> Scene {
    let mut scene = scene_file("spheres.glb");
    scene.lights.clear();
    let floor = scene.materials.iter().position(|m| m.name == "floor").expect("floor material") as u32;
    let keep: Vec<usize> =
        (0..scene.triangles.len()).filter(|&t| scene.triangle_material[t] != floor).collect();
    scene.triangles = keep.iter().map(|&t| scene.triangles[t]).collect();
    scene.triangle_material = keep.iter().map(|&t| scene.triangle_material[t]).collect();
    for p in &mut scene.positions {
        if p[1] > 0.0 || p[0].abs() < 3.5 {
            let c = [(p[0] + 3.0).round() - 3.0, 0.4, (p[2] + 3.0).round() - 3.0];
            for k in 0..3 {
                p[k] = c[k] + 0.75 * (p[k] - c[k]);
            }
        }
    }
    scene
}

/// Per material: (sum of hybrid, sum of path traced, sum of path-traced variance of the mean,
/// pixel count) over interior pixels, in luminance; `bin` picks which pixels count (by n·v).
fn per_material(
    g: &umbra::passes::gbuffer::GBufferData,
    hyb: &[[f32; 4]],
    pt: &umbra::render::PathImage,
    view: &[glam::Vec3],
    bin: impl Fn(f32) -> bool,
) -> std::collections::BTreeMap<u32, [f64; 4]> {
    let lum = |c: &[f32]| (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f64;
    let var = pt.variance_of_mean();
    let (w, h) = (g.size.0 as usize, g.size.1 as usize);
    let mut out = std::collections::BTreeMap::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let m = g.material[i][0];
            let interior = (0..9).all(|k| g.material[(y + k / 3 - 1) * w + x + k % 3 - 1][0] == m);
            if m == umbra::passes::gbuffer::GBUFFER_NO_SURFACE || !interior {
                continue;
            }
            let nv = -glam::Vec3::from_slice(&g.normal[i][..3]).dot(view[i]);
            if !bin(nv) {
                continue;
            }
            let e = out.entry(m).or_insert([0.0; 4]);
            e[0] += lum(&hyb[i]);
            e[1] += lum(&pt.mean[i]);
            e[2] += 0.2126f64.powi(2) * var[i][0] as f64
                + 0.7152f64.powi(2) * var[i][1] as f64
                + 0.0722f64.powi(2) * var[i][2] as f64;
            e[3] += 1.0;
        }
    }
    out
}

/// Hybrid (IBL only; colour box-filtered from 4×4 samples per pixel) and path-traced (one scattering event: direct environment light) renders of
/// the IBL sphere grid under `env`, with the per-pixel view directions.
fn render_pair(
    gpu: &Gpu,
    scene: &Scene,
    map: Option<&EnvironmentMap>,
    env: [f32; 3],
    size: (u32, u32),
    spp: u32,
) -> (umbra::render::HybridImage, umbra::render::PathImage, Vec<glam::Vec3>) {
    let camera = scene.camera(None).unwrap();
    let mut gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    if let Some(map) = map {
        gpu_scene.set_environment(gpu, map).unwrap();
    }
    let lighting = LightingSettings { env, shadow_rays: 1, ibl: true, ..Default::default() };
    let mut hyb =
        hybrid(gpu, &gpu_scene, &camera, &HybridSettings { size, lighting, ..Default::default() }).unwrap();
    // The colour box-filtered like the path tracer's pixels: 4×4 centre samples per pixel (a
    // mirror's sharp reflections would otherwise differ by the pixel filter alone).
    let big = (4 * size.0, 4 * size.1);
    let fine =
        hybrid(gpu, &gpu_scene, &camera, &HybridSettings { size: big, lighting, ..Default::default() })
            .unwrap();
    for (i, c) in hyb.color.iter_mut().enumerate() {
        let (x, y) = (4 * (i as u32 % size.0), 4 * (i as u32 / size.0));
        let mut sum = [0.0f32; 4];
        for k in 0..16 {
            let f = fine.color[((y + k / 4) * big.0 + x + k % 4) as usize];
            for ch in 0..4 {
                sum[ch] += f[ch] / 16.0;
            }
        }
        *c = sum;
    }
    let settings = PathSettings { size, spp, max_bounces: 1, env, ..Default::default() };
    let pt = path_trace(gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let cam = umbra::render::camera_params(&camera, size);
    let v = |a: [f32; 4]| glam::Vec3::new(a[0], a[1], a[2]);
    let view = (0..size.0 * size.1)
        .map(|i| {
            let (x, y) = (i % size.0, i / size.0);
            let ndc =
                (2.0 * (x as f32 + 0.5) / size.0 as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / size.1 as f32);
            (v(cam.1) + ndc.0 * v(cam.2) + ndc.1 * v(cam.3)).normalize()
        })
        .collect();
    (hyb, pt, view)
}

/// Split-sum IBL against the path tracer's direct environment light on the sphere grid under a
/// sky with a bright disc: per sphere (interior pixels, luminance), relative error
/// |hybrid − path| / path of the sphere's mean. (a) the error grows with roughness: the mean
/// error of the roughest column exceeds the smoothest column's by more than 3 standard errors of
/// the path tracer's noise (one-sided z-test, significance ≈ 0.0013); (b) it grows towards
/// grazing angles: over the spheres of roughness ≥ 0.5, the pooled relative error of the pixels
/// with n·v < 0.6 (the small spheres keep few interior pixels nearer grazing) exceeds that of n·v > 0.85 by more than 3 standard errors.
#[test]
fn split_sum_error_grows_with_roughness_and_grazing_angle() {
    let gpu = Gpu::new();
    let scene = ibl_spheres();
    let map = synthetic_map(128, 64, sky);
    let start = std::time::Instant::now();
    let (size, spp) = ((160, 112), 128);
    let (hyb, pt, view) = render_pair(&gpu, &scene, Some(&map), [1.0; 3], size, spp);
    eprintln!("renders: {:.1} s", start.elapsed().as_secs_f64());
    let spheres = per_material(&hyb.gbuffer, &hyb.color, &pt, &view, |_| true);
    // Error and its standard error (from the path tracer's noise) of one material's sums.
    let rel = |e: &[f64; 4]| ((e[0] - e[1]).abs() / e[1], e[2].sqrt() * e[0] / (e[1] * e[1]));
    let mut columns = [(0.0, 0.0, 0); 7];
    eprintln!("roughness metallic  pixels  hybrid    path      rel. error");
    for (&m, e) in &spheres {
        let mat = &scene.materials[m as usize];
        let (err, se) = rel(e);
        let col = (mat.roughness * 6.0).round() as usize;
        eprintln!(
            "{:9.2} {:8.2} {:7} {:9.4} {:9.4} {:7.4} ± {:.4}",
            mat.roughness,
            mat.metallic,
            e[3],
            e[0] / e[3],
            e[1] / e[3],
            err,
            se
        );
        columns[col].0 += err;
        columns[col].1 += se * se;
        columns[col].2 += 1;
    }
    let column = |c: usize| (columns[c].0 / columns[c].2 as f64, columns[c].1.sqrt() / columns[c].2 as f64);
    for c in 0..7 {
        eprintln!(
            "column roughness {:.2}: mean rel. error {:.4} ± {:.4}",
            c as f64 / 6.0,
            column(c).0,
            column(c).1
        );
    }
    assert!(spheres.len() >= 45, "the camera should see most of the 49 spheres ({})", spheres.len());
    let ((smooth, s_se), (rough, r_se)) = (column(0), column(6));
    assert!(
        rough - smooth > 3.0 * (s_se * s_se + r_se * r_se).sqrt(),
        "roughest column error {rough:.4} ± {r_se:.4} vs smoothest {smooth:.4} ± {s_se:.4}"
    );

    let pooled = |bin: &dyn Fn(f32) -> bool| {
        let sums = per_material(&hyb.gbuffer, &hyb.color, &pt, &view, bin);
        let mut t = [0.0; 4];
        for (&m, e) in &sums {
            if scene.materials[m as usize].roughness >= 0.5 {
                for k in 0..4 {
                    t[k] += e[k];
                }
            }
        }
        (rel(&t), t[3])
    };
    let ((frontal, f_se), nf) = pooled(&|nv| nv > 0.85);
    let ((grazing, g_se), ng) = pooled(&|nv| nv < 0.6);
    eprintln!("roughness >= 0.5: n·v > 0.85: {frontal:.4} ± {f_se:.4} ({nf} px); n·v < 0.6: {grazing:.4} ± {g_se:.4} ({ng} px)");
    assert!(
        grazing - frontal > 3.0 * (f_se * f_se + g_se * g_se).sqrt(),
        "grazing error {grazing:.4} should exceed frontal {frontal:.4}"
    );
}
