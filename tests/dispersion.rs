//! `KHR_materials_dispersion`: a dispersive volume refracts each colour channel at its own index
//! of refraction, the extension's Cauchy fit at the Fraunhofer line of the channel, its Fresnel
//! reflectance the material's own (the extension's implementation note). So channel c of a
//! dispersive glass is, exactly, channel c of a plain glass of the channel's index whose F0 is
//! kept at the dispersive glass's (its specular colour scaled): the path tracer's (which follows
//! one channel per path, picked at random) in expectation, the hybrid's (which refracts the
//! environment once per channel) up to float rounding.
//!
//! The scene: a faceted glass ball (an icosphere of 80 flat faces, each a prism) before an
//! environment of bright and dark stripes, so the channels' different bending moves the stripes'
//! edges by pixels (checked: the test tells the red channel's index from the blue's).

mod common;

use common::{gamma_q, Gpu};
use glam::Vec3;
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::pathtrace::Integrator;
use umbra::render::{hybrid, path_trace, HybridSettings, PathImage, PathSettings};
use umbra::scene::{Material, Scene, DISPERSION_WAVELENGTHS};
use umbra::split_sum::texel_direction;

const IOR: f32 = 1.5;
/// 20 / Abbe number: 2 is rutile's (V = 9.8), the extension's own extreme example.
const DISPERSION: f32 = 2.0;
const SIZE: (u32, u32) = (40, 40);

/// The extension's index of refraction at wavelength `lambda` (nm), as its text writes it.
fn cauchy(ior: f64, dispersion: f64, lambda: f64) -> f64 {
    let abbe = 20.0 / dispersion;
    (ior + (ior - 1.0) / abbe * (523_655.0 / (lambda * lambda) - 1.5168)).max(1.0)
}

/// Smooth glass, a volume, of index `ior` and dispersion `dispersion`, its F0 that of index
/// `f0_ior` (through the specular colour).
fn glass(ior: f32, dispersion: f32, f0_ior: f32) -> Material {
    let f0 = |n: f32| ((n - 1.0) / (n + 1.0)).powi(2);
    Material {
        metallic: 0.0,
        roughness: 0.0,
        transmission_factor: 1.0,
        volume: true,
        thickness: 1.0,
        ior,
        dispersion,
        specular_color_factor: [f0(f0_ior) / f0(ior); 3],
        ..Default::default()
    }
}

/// The faceted ball of `material` seen from 3.2 m, and a striped environment.
fn scene(gpu: &Gpu, material: Material) -> (Scene, GpuScene) {
    let ball = umbra::procedural::icosphere(1, Vec3::ZERO, 1.0).soup();
    let camera = common::camera(Vec3::new(0.0, 0.0, 3.2), Vec3::ZERO);
    let scene = common::build_with("dispersive ball", &[(ball, material)], vec![], camera);
    let mut gpu_scene = GpuScene::upload(gpu, &scene).unwrap();
    // Twelve bright and twelve dark stripes around the vertical axis, softened over a few texels
    // (the map is bilinear; a hard edge would only alias).
    let (w, h) = (256, 128);
    let texels = (0..w * h)
        .map(|i| {
            let d = texel_direction(i % w, i / w, w, h).0;
            let s = (12.0 * d[0].atan2(d[2])).sin();
            let v = (0.2 + 2.0 * (0.5 + 0.5 * (4.0 * s).tanh())) as f32;
            [v; 3]
        })
        .collect();
    let map = EnvironmentMap::from_texels("stripes", w, h, texels).unwrap();
    gpu_scene.set_environment(gpu, &map).unwrap();
    (scene, gpu_scene)
}

/// The index of refraction of each channel for the test's glass, from the extension's text.
fn channel_iors() -> [f32; 3] {
    DISPERSION_WAVELENGTHS.map(|l| cauchy(IOR as f64, DISPERSION as f64, l as f64) as f32)
}

#[test]
fn the_channels_indices_are_the_extensions_cauchy_fit() {
    let material = glass(IOR, DISPERSION, IOR);
    let iors = material.dispersion_iors();
    for (c, (&got, want)) in iors.iter().zip(channel_iors()).enumerate() {
        assert!((got - want).abs() < 1e-6, "channel {c}: {got} against the extension's {want}");
    }
    // Red to blue spans the Abbe number's n_F − n_C = (n_d − 1) / V_d; green is the ior.
    let spread = (IOR - 1.0) * DISPERSION / 20.0;
    assert!((iors[2] - iors[0] - spread).abs() < 1e-3 * spread, "{iors:?}");
    assert!((iors[1] - IOR).abs() < 1e-3 * spread, "{iors:?}");
    // A thin wall, a material that does not transmit, or a dispersion of 0 does not disperse.
    for m in [
        Material { volume: false, ..material.clone() },
        Material { transmission_factor: 0.0, ..material.clone() },
        Material { dispersion: 0.0, ..material.clone() },
    ] {
        assert_eq!(m.dispersion_iors(), [IOR; 3]);
    }
}

/// Path-traces the ball (the environment found by BSDF sampling alone: the smooth glass makes
/// light samples spiky), no Russian roulette.
fn traced(gpu: &Gpu, material: Material, seed: u32, integrator: Integrator) -> PathImage {
    let (scene, gpu_scene) = scene(gpu, material);
    let settings = PathSettings {
        size: SIZE,
        spp: 256,
        max_bounces: 8,
        rr_depth: 100,
        env: [1.0; 3],
        env_nee: false,
        seed,
        integrator,
        ..Default::default()
    };
    let image = path_trace(gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0, "NaN/Inf samples");
    image
}

/// Chi-square of channel `a` of `x` against channel `b` of `y` over the pixels whose means are
/// uncertain, each pixel's difference over its standard error (the images' own second moments),
/// and its p-value.
fn chi_square(x: &PathImage, a: usize, y: &PathImage, b: usize) -> (f64, usize, f64) {
    let variance = |img: &PathImage, i: usize, c: usize| {
        let n = img.mean[i][3] as f64;
        let m = img.mean[i][c] as f64;
        ((img.moment[i][c] as f64 - m * m) * n / (n - 1.0)).max(0.0) / n
    };
    let (mut chi2, mut k) = (0.0, 0usize);
    for i in 0..x.mean.len() {
        let v = variance(x, i, a) + variance(y, i, b);
        if v > 1e-12 {
            let d = x.mean[i][a] as f64 - y.mean[i][b] as f64;
            chi2 += d * d / v;
            k += 1;
        }
    }
    (chi2, k, gamma_q(k as f64 / 2.0, chi2 / 2.0))
}

/// The path tracer, megakernel and wavefront: each channel of the dispersive ball agrees with that
/// channel of the plain glass of its index, within noise (α = 0.001, each test); the red channel
/// against the blue channel's glass is rejected, so the scene tells the indices apart.
#[test]
fn the_path_tracer_follows_each_channel_at_its_own_index() {
    let gpu = Gpu::new();
    let iors = channel_iors();
    let plain: Vec<PathImage> =
        iors.iter().map(|&n| traced(&gpu, glass(n, 0.0, IOR), 2, Integrator::Megakernel)).collect();
    for integrator in Integrator::ALL {
        let dispersive = traced(&gpu, glass(IOR, DISPERSION, IOR), 1, integrator);
        for c in 0..3 {
            let (chi2, k, p) = chi_square(&dispersive, c, &plain[c], c);
            eprintln!(
                "{} channel {c} (ior {}): chi2 {chi2:.1} over {k} pixels, p {p:.3}",
                integrator.name(),
                iors[c]
            );
            assert!(k > 500, "{k} pixels see the ball");
            assert!(
                p > 1e-3,
                "{}: channel {c} differs from ior {}'s glass: p = {p:e}",
                integrator.name(),
                iors[c]
            );
        }
        // Sensitivity: red against the blue index's glass (its red channel) is far off.
        let (chi2, k, p) = chi_square(&dispersive, 0, &plain[2], 0);
        eprintln!("{} red against blue's index: chi2 {chi2:.1} over {k} pixels, p {p:e}", integrator.name());
        assert!(p < 1e-9, "the scene does not tell red's index from blue's: p = {p}");
    }
}

/// The hybrid: each channel of the dispersive ball is that channel of the plain glass of its
/// index, up to float rounding (the environment refracted once per channel at the surface).
#[test]
fn the_hybrid_refracts_each_channel_at_its_own_index() {
    let gpu = Gpu::new();
    let lit = |material: Material| {
        let (scene, gpu_scene) = scene(&gpu, material);
        let settings = HybridSettings {
            size: SIZE,
            lighting: LightingSettings { env: [1.0; 3], ..Default::default() },
            ao: None,
            ..Default::default()
        };
        hybrid(&gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings).unwrap().color
    };
    let dispersive = lit(glass(IOR, DISPERSION, IOR));
    let iors = channel_iors();
    let mut moved = 0;
    for c in 0..3 {
        let plain = lit(glass(iors[c], 0.0, IOR));
        let mut worst = 0.0f32;
        for (d, p) in dispersive.iter().zip(&plain) {
            worst = worst.max((d[c] - p[c]).abs() / p[c].abs().max(1e-2));
        }
        assert!(
            worst < 1e-3,
            "channel {c}: the dispersive ball differs from ior {}'s by {worst} (relative)",
            iors[c]
        );
        if c == 2 {
            let red = lit(glass(iors[0], 0.0, IOR));
            moved = red.iter().zip(&plain).filter(|(r, b)| (r[2] - b[2]).abs() > 0.05 * b[2]).count();
        }
    }
    // Sensitivity: red's index and blue's move the stripes' edges by pixels.
    assert!(moved > 20, "only {moved} pixels tell red's index from blue's");
}
