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
