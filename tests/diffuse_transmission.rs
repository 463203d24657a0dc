//! `KHR_materials_diffuse_transmission`: the diffuse lobe split into reflection and a Lambertian
//! lobe through the back, tinted by its own colour. Its sampling's white furnace and its
//! directional albedo against the closed form (through `sample_test.comp`'s kind 10), and the
//! path tracer and the hybrid renderer on a quad lit from behind and under a constant sky against
//! the closed form. The chi-square test of its sampling is in tests/sampling/ (the
//! `DiffuseTransmission` cases), the loading in tests/scene/, its textures in
//! tests/layer_textures.rs.

mod common;

use common::quad::{renders, MODES};
use common::Gpu;
use glam::Vec3;
use umbra::gpu::kernels::sample_test;
use umbra::gpu::layout::SampleTestParams;
use umbra::gpu::Pipeline;
use umbra::scene::{LightKind, Material};

/// `bsdf_sample`'s mean weight f |cos| / pdf over 2^19 samples (sample_test's mode 5) on kind 10
/// (a grey dielectric of base `base`, α `alpha`, KHR_materials_specular's factor `specular`, a
/// share `share` of its diffuse lobe through the back tinted (1, b, b²), thin transmission
/// `transmission`), seen from θo: the directional albedo per channel with its standard error.
#[allow(clippy::too_many_arguments)]
fn albedo(
    gpu: &Gpu,
    pipeline: &Pipeline<sample_test::Kernel>,
    alpha: f32,
    share: f32,
    transmission: f32,
    specular: f32,
    base: f32,
    b: f32,
    theta_degrees: f32,
) -> ([f64; 3], [f64; 3]) {
    let count = 1u32 << 19;
    let t = theta_degrees.to_radians();
    let params = SampleTestParams {
        wo: [t.sin(), 0.0, t.cos()],
        alpha,
        mode: 5,
        count,
        seed: 777,
        kind: 10,
        anisotropy: [share, transmission, specular, base],
        anisotropy_base: b,
        ..Default::default()
    };
    let out = common::sample_test_run(gpu, pipeline, &params, &[]);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for w in &out {
        for c in 0..3 {
            let w = w[c] as f64;
            assert!(w.is_finite() && w >= 0.0, "weight {w}");
            sum[c] += w;
            sum2[c] += w * w;
        }
    }
    let n = count as f64;
    let mean = sum.map(|s| s / n);
    let se = [0, 1, 2].map(|c| ((sum2[c] / n - mean[c] * mean[c]).max(0.0) / n).sqrt());
    (mean, se)
}

/// Without Fresnel (`specularFactor` 0: F0 = F90 = 0, no specular lobe) the layering has a
/// closed form: the albedo is (1 − share) base + share colour per channel, the two Lambertian
/// lobes' (transmission 0). With it, the white furnace (white base and colour, specular 1): the
/// transmitted lobe takes 1 − F at the half vector of wo and wi mirrored, as the reflected one
/// takes it at theirs, so sending a share of the diffuse lobe through the back moves no energy:
/// the albedo equals the same surface's without it (share 0) within z·√(se² + se₀²), with and
/// without thin transmission beside it, sharp and rough, from the normal to grazing, and at
/// normal incidence it is at most 1 + z·se. (Towards grazing the glTF layering itself exceeds 1
/// by up to 0.2 at θo 80°, α 0.1, with or without the extension: tests/anisotropy.rs.) z = 3.9:
/// two-sided 0.01 with a Šidák correction over the 8 × 3 closed-form and 32 × 3 furnace
/// comparisons.
#[test]
fn furnace_and_closed_form_albedo() {
    let gpu = Gpu::new();
    let pipeline = Pipeline::<sample_test::Kernel>::new(&gpu, &sample_test::Spec::default(), None).unwrap();
    let z = 3.9;
    let mut failures = Vec::new();
    for share in [0.3f32, 1.0] {
        for (alpha, theta) in [(0.1f32, 0.0f32), (0.5, 0.0), (0.1, 60.0), (0.5, 80.0)] {
            let b = 0.5f32;
            let colour = [1.0, b, b * b];
            let (mean, se) = albedo(&gpu, &pipeline, alpha, share, 0.0, 0.0, 0.6, b, theta);
            for c in 0..3 {
                let expected = ((1.0 - share) * 0.6 + share * colour[c]) as f64;
                eprintln!(
                    "share {share}, α {alpha}, θo {theta}, channel {c}: {:.5} ± {:.5} vs {expected:.5}",
                    mean[c], se[c]
                );
                if (mean[c] - expected).abs() > z * se[c] + 1e-5 * expected {
                    failures.push(format!(
                        "closed form, share {share}, α {alpha}, θo {theta}, channel {c}: {} ± {} vs {expected}",
                        mean[c], se[c]
                    ));
                }
            }
        }
    }
    for transmission in [0.0f32, 0.5] {
        for alpha in [0.1f32, 0.5] {
            for theta in [0.0f32, 45.0, 80.0] {
                let (opaque, se0) = albedo(&gpu, &pipeline, alpha, 0.0, transmission, 1.0, 1.0, 1.0, theta);
                for share in [0.5f32, 1.0] {
                    let (mean, se) =
                        albedo(&gpu, &pipeline, alpha, share, transmission, 1.0, 1.0, 1.0, theta);
                    eprintln!(
                        "furnace share {share}, transmission {transmission}, α {alpha}, θo {theta}: {:.4} (share 0: {:.4})",
                        mean[0], opaque[0]
                    );
                    for c in 0..3 {
                        let name = format!(
                            "share {share}, transmission {transmission}, α {alpha}, θo {theta}, channel {c}"
                        );
                        if (mean[c] - opaque[c]).abs() > z * (se[c] * se[c] + se0[c] * se0[c]).sqrt() {
                            failures.push(format!(
                                "furnace, {name}: {} ± {} vs share 0: {} ± {}",
                                mean[c], se[c], opaque[c], se0[c]
                            ));
                        }
                        if theta == 0.0 && mean[c] > 1.0 + z * se[c] {
                            failures.push(format!("furnace, {name}: {} ± {} above 1", mean[c], se[c]));
                        }
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The material of the quad tests: a grey (0.6) dielectric without Fresnel (`specularFactor` 0),
/// roughness 0.5, double-sided, sending 0.7 of its diffuse lobe through the back tinted
/// (1, 0.5, 0.25).
fn through() -> Material {
    Material {
        base_color_factor: [0.6, 0.6, 0.6, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        specular_factor: 0.0,
        diffuse_transmission: 0.7,
        diffuse_transmission_color: [1.0, 0.5, 0.25],
        double_sided: true,
        ..Default::default()
    }
}

/// A quad lit from behind by a sun of 3 lux at 22° from its normal, seen from the front with no
/// sky: the path tracer (one bounce: the sun's light sample alone, no noise) and the hybrid
/// renderer (the sun through the same BSDF, a shadow ray from the back) both show the closed form
/// E cos θ · share · colour / π in every pixel, within 1e-4 relative.
#[test]
fn a_quad_lit_from_behind_matches_the_closed_form() {
    let gpu = Gpu::new();
    let m = through();
    let dir = Vec3::new(0.3, 0.2, 1.0).normalize();
    let mut scene = common::quad::scene("diffuse transmission", m.clone(), None, 0.0);
    scene.lights = vec![common::light(LightKind::Directional, Vec3::ZERO, dir, 3.0)];
    let images = renders(&gpu, &scene, 0.0);
    let expected: Vec<f32> = (0..3)
        .map(|c| {
            3.0 * dir.z * m.diffuse_transmission * m.diffuse_transmission_color[c] / std::f32::consts::PI
        })
        .collect();
    for (mode, image) in MODES.iter().zip(&images) {
        for (i, p) in image.iter().enumerate() {
            for c in 0..3 {
                assert!(
                    (p[c] - expected[c]).abs() <= 1e-4 * expected[c],
                    "{mode}: pixel {i} channel {c}: {} vs the closed form {}",
                    p[c],
                    expected[c]
                );
            }
        }
    }
}

/// The same quad under a constant sky of 0.5 from every side, no sun: the radiance towards the
/// camera is 0.5 ((1 − share) base + share colour) per channel. The hybrid's image-based light
/// (the irradiance in front on the reflected share, behind on the transmitted one) gives it in
/// every pixel within 1e-3 relative (its G-buffer holds the base colour as a half float); the
/// path tracer (4 samples a pixel, one bounce: a lobe picked per sample, each lobe's weight
/// constant) in its image mean within 4 standard errors of the pixels' mean.
#[test]
fn a_quad_under_the_sky_matches_the_closed_form() {
    let gpu = Gpu::new();
    let m = through();
    let scene = common::quad::scene("diffuse transmission", m.clone(), None, 0.0);
    let [traced, lit] = renders(&gpu, &scene, 0.5);
    let expected: Vec<f32> = (0..3)
        .map(|c| {
            0.5 * ((1.0 - m.diffuse_transmission) * 0.6
                + m.diffuse_transmission * m.diffuse_transmission_color[c])
        })
        .collect();
    for (i, p) in lit.iter().enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - expected[c]).abs() <= 1e-3 * expected[c],
                "hybrid: pixel {i} channel {c}: {} vs the closed form {}",
                p[c],
                expected[c]
            );
        }
    }
    let n = traced.len() as f64;
    for c in 0..3 {
        let mean = traced.iter().map(|p| p[c] as f64).sum::<f64>() / n;
        let var = traced.iter().map(|p| (p[c] as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        eprintln!("path tracer channel {c}: {mean:.5} ± {se:.5} vs {}", expected[c]);
        assert!(
            (mean - expected[c] as f64).abs() <= 4.0 * se + 1e-5,
            "path tracer channel {c}: mean {mean} ± {se} vs the closed form {}",
            expected[c]
        );
    }
}
