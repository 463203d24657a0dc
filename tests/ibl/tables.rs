//! The kernels' tables against f64 references: the BRDF table, SH9 irradiance, the prefiltered
//! levels, and the sample counts' limits.

use crate::common::Gpu;
use crate::{scene_file, sky, synthetic_map, unit};
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ibl::{IblResources, IblSettings};
use umbra::split_sum::{
    irradiance_brute_force, lut_coordinates, lut_entry, lut_reference, sh9_irradiance,
    sh9_irradiance_coefficients, texel_direction, LUT_SIZE,
};

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
            let (nv, r) = lut_coordinates(i, j);
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
        "GPU LUT vs reference: max |error| {e:.2e} at (n·v, roughness) {:.3?}, channel {c} (GPU {:?}, CPU {:?})",
        lut_coordinates(k % s, k / s),
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

const NORMALS: [[f64; 3]; 6] = [
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 0.6, 0.8],
    [-0.48, 0.6, -0.64],
    [0.0, 0.0, -1.0],
];

/// The f64 SH9 projection of `map`, how far the kernel's coefficients are from it (relative to
/// the largest), and the IBL resources built.
fn sh9_gpu_error(
    gpu: &Gpu,
    scene: &mut GpuScene,
    map: &EnvironmentMap,
) -> ([[f64; 3]; 9], f64, IblResources) {
    let cpu = sh9_irradiance_coefficients(map);
    scene.set_environment(gpu, map).unwrap();
    let ibl = IblResources::build(gpu, scene, &IblSettings::default()).unwrap();
    let sh: Vec<[f32; 4]> = ibl.sh.read(gpu).unwrap();
    let largest = cpu.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = (0..9)
        .flat_map(|k| (0..3).map(move |c| (k, c)))
        .map(|(k, c)| (sh[k][c] as f64 - cpu[k][c]).abs())
        .fold(0.0, f64::max)
        / largest;
    (cpu, error, ibl)
}

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
        let (cpu, gpu_error, ibl) = sh9_gpu_error(&gpu, &mut scene, map);
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

/// Prefiltered levels against brute force: a 64 × 32 grey map (a dim gradient and a disc of
/// radiance 20 and radius 12°), every texel of the levels for roughness 0.4 (16 × 8) and 1.0
/// (8 × 4) against the f64 integral the kernel estimates, ∫ L(l) D(h)/4 (r·l) dl / ∫ D(h)/4 (r·l) dl
/// with n = v = r (the source taken piecewise constant, 4 × 4 exact-solid-angle cells per texel).
/// Expected error: the kernel's 64 Hammersley samples with filtered importance sampling should do
/// no worse than 64 independent samples of the same pdf D/4, whose ratio estimator has standard
/// error σ = √(∫ q (r·l)² (L − μ)² dl / 64) / ∫ q (r·l) dl (q = D/4; computed per texel by the
/// same quadrature). Tested: every texel within 3 σ (plus 1e-3 of its value for the texel
/// reconstruction: the kernel reads the source bilinearly).
///
/// The kernel's level of detail is 0.5 log2(Ωs / Ωtexel) − 1.5 (see ibl_prefilter.comp). Measured
/// (mean |error| / σ; worst texel's |error| / (3σ + 1e-3 μ)), roughness 0.4 and 1.0: with
/// Křivánek and Colbert's +1 bias 50 / 15 and 37 / 48 (the box chain blurs the disc, up to
/// +63 %); with 0: 12.5 / 3.0 and 15 / 12.5; −1: 0.86 / 0.57 and 0.58 / 1.47; −1.5 (kept):
/// 0.52 / 0.33 and 0.37 / 0.52; −2: 0.42 / 0.32, but the worst texels turn noisy (the sun
/// aliasing filtering exists to prevent; worst 2.03 against 1.02).
#[test]
fn prefiltered_levels_match_brute_force() {
    use std::f64::consts::PI;
    let (w, h) = (64usize, 32usize);
    let disc = unit([0.8, 0.5, -0.3]);
    let radiance = |d: [f64; 3]| {
        let cos = d[0] * disc[0] + d[1] * disc[1] + d[2] * disc[2];
        let l = if cos > 12f64.to_radians().cos() { 20.0 } else { 0.2 + 0.3 * d[1].max(0.0) };
        [l; 3]
    };
    let map = synthetic_map(w, h, radiance);
    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    scene.set_environment(&gpu, &map).unwrap();
    let settings = IblSettings::default();
    let ibl = IblResources::build(&gpu, &scene, &settings).unwrap();
    let levels: Vec<[f32; 4]> = ibl.prefiltered.read(&gpu).unwrap();
    let sizes = umbra::split_sum::prefiltered_level_sizes((w as u32, h as u32));
    // Source cells: direction, solid angle, radiance.
    let sub = 4usize;
    let mut cells = Vec::with_capacity(w * h * sub * sub);
    for y in 0..h * sub {
        let (t0, t1) = (PI * y as f64 / (h * sub) as f64, PI * (y + 1) as f64 / (h * sub) as f64);
        let d_omega = 2.0 * PI / (w * sub) as f64 * (t0.cos() - t1.cos());
        for x in 0..w * sub {
            let d = texel_direction(x, y, w * sub, h * sub).0;
            cells.push((d, d_omega, map.texels[(y / sub) * w + x / sub][0] as f64));
        }
    }
    let mut worst_ratio: f64 = 0.0;
    for (k, roughness) in [(2usize, 0.4f64), (5, 1.0)] {
        let a = roughness * roughness;
        let offset: u32 = sizes[1..k].iter().map(|&(w, h)| w * h).sum();
        let (lw, lh) = (sizes[k].0 as usize, sizes[k].1 as usize);
        let (mut worst, mut sum_ratio) = ((0.0f64, 0.0, 0.0, 0.0), 0.0);
        for t in 0..lw * lh {
            let r = texel_direction(t % lw, t / lw, lw, lh).0;
            let (mut wsum, mut lsum) = (0.0, 0.0);
            let weights: Vec<(f64, f64)> = cells
                .iter()
                .filter_map(|&(l, d_omega, radiance)| {
                    let c = r[0] * l[0] + r[1] * l[1] + r[2] * l[2];
                    if c <= 0.0 {
                        return None;
                    }
                    // n·h for h = (r + l)/|r + l| with r·l = c.
                    let nh2 = (1.0 + c) / 2.0;
                    let d = a * a / (PI * (nh2 * (a * a - 1.0) + 1.0).powi(2));
                    let q = d / 4.0 * d_omega;
                    wsum += q * c;
                    lsum += q * c * radiance;
                    Some((q * c * c, radiance))
                })
                .collect();
            let mu = lsum / wsum;
            let var: f64 = weights.iter().map(|&(qc2, l)| qc2 * (l - mu).powi(2)).sum::<f64>()
                / settings.prefilter_samples as f64;
            let sigma = var.sqrt() / wsum;
            let g = levels[offset as usize + t][1] as f64;
            let ratio = (g - mu).abs() / (3.0 * sigma + 1e-3 * mu);
            sum_ratio += (g - mu).abs() / sigma;
            if ratio > worst.0 {
                worst = (ratio, g, mu, sigma);
            }
        }
        let (ratio, g, mu, sigma) = worst;
        eprintln!(
            "roughness {roughness}: mean |GPU − brute| / σ {:.2}; worst texel GPU {g:.4} vs {mu:.4} (σ {sigma:.4}, |error| / (3σ + 1e-3 μ) = {ratio:.2})",
            sum_ratio / (lw * lh) as f64
        );
        worst_ratio = worst_ratio.max(ratio);
    }
    assert!(worst_ratio <= 1.0, "a prefiltered texel is further than 3σ from the brute-force integral");
}

/// The SH9 projection of a large map is not cut short: llvmpipe breaks every loop of an
/// invocation after 65,535 loop iterations in all, and one invocation of `ibl_sh.comp` used to
/// sum every 128th row in full (a 4096×2048 map, the largest lavapipe's storage buffers hold,
/// came out 98 % off). Its coefficients must equal the f64 projection (1e-4 relative to the
/// largest), as the small maps' do.
#[test]
fn sh9_of_a_large_map_is_not_cut_short() {
    let map = synthetic_map(4096, 2048, sky);
    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    let (_, error, _) = sh9_gpu_error(&gpu, &mut scene, &map);
    eprintln!("SH9 of a 4096×2048 map: GPU vs f64 projection {error:.2e} of the largest coefficient");
    assert!(error < 1e-4, "SH9 coefficients off by {error:e} of the largest");
}

/// Sample counts that one invocation could not finish on a CPU device are refused with a clear
/// error, and the largest allowed ones build.
#[test]
fn ibl_sample_counts_are_checked() {
    let gpu = Gpu::new();
    let scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    for settings in [
        IblSettings { lut_samples: 0, ..Default::default() },
        IblSettings { lut_samples: IblSettings::MAX_LUT_SAMPLES + 1, ..Default::default() },
        IblSettings { prefilter_samples: IblSettings::MAX_PREFILTER_SAMPLES + 1, ..Default::default() },
    ] {
        let message = IblResources::build(&gpu, &scene, &settings).err().expect("refused").to_string();
        assert!(message.contains("must be 1 to"), "{message}");
    }
    // The largest table is the default one's integral (not cut short): within the default's
    // quadrature error, 1e-3.
    let largest = IblSettings { lut_samples: IblSettings::MAX_LUT_SAMPLES, ..Default::default() };
    let big: Vec<[f32; 4]> = IblResources::build(&gpu, &scene, &largest).unwrap().lut.read(&gpu).unwrap();
    let default: Vec<[f32; 4]> =
        IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap().lut.read(&gpu).unwrap();
    let worst =
        big.iter().flatten().zip(default.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(
        worst < 1e-3,
        "the {}-sample table differs from the default by {worst}",
        IblSettings::MAX_LUT_SAMPLES
    );
}
