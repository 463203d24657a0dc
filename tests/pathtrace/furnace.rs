//! White furnaces of opaque spheres: a Lambert sphere is exactly 1, metal spheres converge to
//! their numerically integrated directional albedo.

use crate::common::Gpu;
use crate::{camera, render, scene_of, sphere_cosines};
use glam::Vec3;
use umbra::passes::pathtrace::Microfacet;
use umbra::procedural::icosphere;
use umbra::render::PathSettings;
use umbra::scene::Material;

/// A Lambert sphere of albedo 1 (specular off) under a constant environment of 1 reflects
/// exactly 1 everywhere: the furnace test of throughput, sampling weights and the environment.
#[test]
fn white_furnace_lambert_sphere_is_one() {
    let gpu = Gpu::new();
    let sphere = icosphere(4, Vec3::ZERO, 1.0);
    let white =
        Material { metallic: 0.0, specular_factor: 0.0, base_color_factor: [1.0; 4], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 35.0);
    let scene = scene_of(&[(&sphere, white, false)], cam);
    let settings =
        PathSettings { size: (48, 48), spp: 16, env: [1.0; 3], max_bounces: 8, ..Default::default() };
    let image = render(&gpu, &scene, &settings);
    let cosines = sphere_cosines(&cam, settings.size);
    let mut checked = 0;
    for (i, p) in image.mean.iter().enumerate() {
        // Away from the silhouette (and from the polygonal outline of the icosphere).
        if cosines[i].is_some_and(|c| c > 0.3)
            || cosines[i].is_none() && image.normal_depth[i][3].is_infinite()
        {
            for (c, v) in p[..3].iter().enumerate() {
                assert!((v - 1.0).abs() <= 0.005, "pixel {i} channel {c}: {v}");
            }
            checked += 1;
        }
    }
    assert!(checked > 1500, "only {checked} pixels checked");
}

/// Directional albedo of a metal with F = 1 at cos θ_o = mu: ∫ D G1(o) G1(i) / (4 μ_o) dω_i over
/// the upper hemisphere, by midpoint quadrature in (θ_i, φ_i), for GGX or Beckmann (with the
/// same G1 approximations the kernel uses).
fn metal_albedo(mu: f64, alpha: f64, microfacet: Microfacet) -> f64 {
    use std::f64::consts::PI;
    let a2 = alpha * alpha;
    let d = |hz: f64| match microfacet {
        Microfacet::Ggx | Microfacet::GgxWalter => a2 / (PI * (hz * hz * (a2 - 1.0) + 1.0).powi(2)),
        Microfacet::Beckmann => {
            let c2 = hz * hz;
            (-(1.0 - c2) / c2 / a2).exp() / (PI * a2 * c2 * c2)
        }
    };
    let g1 = |c: f64| match microfacet {
        Microfacet::Ggx | Microfacet::GgxWalter => 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt()),
        Microfacet::Beckmann => {
            let b = c / (alpha * (1.0 - c * c).sqrt());
            if b >= 1.6 {
                1.0
            } else {
                (3.535 * b + 2.181 * b * b) / (1.0 + 2.276 * b + 2.577 * b * b)
            }
        }
    };
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let (nt, np) = (400, 400);
    let mut sum = 0.0;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        let (st, ct) = theta.sin_cos();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let wi = [st * phi.cos(), st * phi.sin(), ct];
            let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
            let hz = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            sum += d(hz) * g1(mu) * g1(ct) / (4.0 * mu * ct) * ct * st;
        }
    }
    sum * (std::f64::consts::FRAC_PI_2 / nt as f64) * (std::f64::consts::TAU / np as f64)
}

/// A metal sphere (base colour 1, so F = 1) under a constant environment of 1, GGX (VNDF
/// sampling and Walter's D(h) cos θh sampling) and Beckmann (half-vector sampling): each pixel
/// converges to the numerically integrated directional albedo at its view angle. A wrong pdf or
/// sampling weight shifts the mean. Pixels are pooled in bins of view angle (single pixels at
/// 64 spp are too skewed for a z-test: most samples are near 1 with a rare tail) and each bin
/// is z-tested at significance 0.01 with a Šidák correction over the bins.
#[test]
fn metal_spheres_match_integrated_albedo() {
    for microfacet in Microfacet::ALL {
        metal_sphere_matches_integrated_albedo(microfacet);
    }
}

fn metal_sphere_matches_integrated_albedo(microfacet: Microfacet) {
    let gpu = Gpu::new();
    let sphere = icosphere(6, Vec3::ZERO, 1.0);
    let roughness = 0.5f32;
    let metal = Material { metallic: 1.0, roughness, base_color_factor: [1.0; 4], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 32.0);
    let scene = scene_of(&[(&sphere, metal, true)], cam);
    let settings = PathSettings {
        size: (40, 40),
        spp: 64,
        env: [1.0; 3],
        max_bounces: 1,
        microfacet,
        ..Default::default()
    };
    let image = render(&gpu, &scene, &settings);
    let variance = image.variance_of_mean();
    let alpha = (roughness * roughness) as f64;
    const BINS: usize = 6;
    let (lo, hi) = (0.35f32, 1.0f32);
    let mut bins = [(0usize, 0.0f64, 0.0f64, 0.0f64); BINS]; // pixels, Σ got, Σ expected, Σ var
    for (i, mu) in sphere_cosines(&cam, settings.size).iter().enumerate() {
        let Some(mu) = mu.filter(|&c| c > lo) else { continue };
        let bin = (((mu - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1);
        let b = &mut bins[bin];
        b.0 += 1;
        b.1 += image.mean[i][1] as f64;
        b.2 += metal_albedo(mu as f64, alpha, microfacet);
        b.3 += variance[i][1] as f64;
    }
    // Two-sided critical z for α = 1 − 0.99^(1/6) ≈ 0.00167.
    let z_crit = 3.144;
    for (k, &(n, got, expected, var)) in bins.iter().enumerate() {
        assert!(n >= 20, "bin {k} has only {n} pixels");
        let z = (got - expected) / var.sqrt();
        eprintln!(
            "{microfacet:?} metal bin {k}: {n} px, mean {:.4} expected {:.4}, z {z:.2}",
            got / n as f64,
            expected / n as f64
        );
        assert!(z.abs() < z_crit, "bin {k}: mean {} vs {}, z = {z}", got / n as f64, expected / n as f64);
    }
}
