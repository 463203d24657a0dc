//! The GPU BRDF (`bsdf_eval` in bsdf.glsl, which the path tracer and the hybrid both use)
//! against a CPU implementation written here, in f64, from the glTF 2.0 specification's
//! Appendix B text and nothing of umbra's: a shared error in shading.glsl or bsdf.glsl cannot
//! pass both. A grid of outgoing and incoming angles, azimuths, roughnesses, metalness values and
//! base colours; and deliberately wrong CPU variants that the comparison must reject.

mod common;

use common::Gpu;
use std::f64::consts::PI;

/// One evaluation: unit vectors in the shading frame (z the normal), α = roughness², metalness,
/// linear base colour.
#[derive(Clone, Copy)]
struct Case {
    wo: [f64; 3],
    wi: [f64; 3],
    alpha: f64,
    metallic: f64,
    base: [f64; 3],
}

/// What the CPU reference gets deliberately wrong (the check must notice each).
#[derive(Clone, Copy, PartialEq)]
enum Variant {
    Spec,
    /// The diffuse lobe not weighted by (1 − F): energy from nowhere at grazing angles.
    DiffuseUnweighted,
    /// The height-correlated Smith term instead of the separable one glTF's Appendix B gives.
    HeightCorrelated,
    /// The metal's Fresnel with F0 = 0.04 instead of the base colour.
    MetalF0,
}

/// glTF 2.0, Appendix B (BRDF implementation), for metallic-roughness materials without
/// extensions: material = mix(dielectric_brdf, metal_brdf, metallic) with
/// metal_brdf = specular_brdf(α) · (baseColor + (1 − baseColor)(1 − |V·H|)⁵),
/// dielectric_brdf = mix(baseColor/π, specular_brdf(α), 0.04 + 0.96(1 − |V·H|)⁵),
/// specular_brdf = V · D with V = G / (4 |N·L| |N·V|), G the separable Smith
/// G1(L) G1(V), G1(X) = 2 |N·X| / (|N·X| + √(α² + (1 − α²)(N·X)²)), and
/// D = α² χ⁺(N·H) / (π ((N·H)²(α² − 1) + 1)²).
fn gltf_brdf(c: &Case, variant: Variant) -> [f64; 3] {
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (v, l) = (c.wo, c.wi);
    let sum = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
    let len = dot(sum, sum).sqrt();
    let h = sum.map(|x| x / len);
    let (nl, nv, nh, vh) = (l[2], v[2], h[2], dot(v, h).abs());
    let a2 = c.alpha * c.alpha;
    let d = if nh > 0.0 { a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2)) } else { 0.0 };
    let g1 = |x: f64| 2.0 * x.abs() / (x.abs() + (a2 + (1.0 - a2) * x * x).sqrt());
    let vis = if variant == Variant::HeightCorrelated {
        let lambda = |x: f64| 0.5 * ((a2 + (1.0 - a2) * x * x).sqrt() / x.abs() - 1.0);
        1.0 / (1.0 + lambda(nl) + lambda(nv)) / (4.0 * nl.abs() * nv.abs())
    } else {
        g1(nl) * g1(nv) / (4.0 * nl.abs() * nv.abs())
    };
    let specular = vis * d;
    let schlick = (1.0 - vh).powi(5);
    let f_dielectric = 0.04 + 0.96 * schlick;
    let diffuse_weight = if variant == Variant::DiffuseUnweighted { 1.0 } else { 1.0 - f_dielectric };
    let metal_f0 = |b: f64| if variant == Variant::MetalF0 { 0.04 } else { b };
    c.base.map(|b| {
        let dielectric = diffuse_weight * b / PI + f_dielectric * specular;
        let metal = specular * (metal_f0(b) + (1.0 - metal_f0(b)) * schlick);
        (1.0 - c.metallic) * dielectric + c.metallic * metal
    })
}

fn direction(theta_degrees: f64, phi_degrees: f64) -> [f64; 3] {
    let (t, p) = (theta_degrees.to_radians(), phi_degrees.to_radians());
    [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
}

fn grid() -> Vec<Case> {
    let mut cases = Vec::new();
    for theta_o in [0.0, 20.0, 45.0, 70.0, 85.0] {
        for theta_i in [5.0, 30.0, 60.0, 80.0, 88.0] {
            for phi in [0.0, 60.0, 180.0] {
                for roughness in [0.1, 0.3, 0.6, 1.0] {
                    for metallic in [0.0, 0.5, 1.0] {
                        for base in [[0.8, 0.4, 0.1], [1.0, 1.0, 1.0]] {
                            cases.push(Case {
                                wo: direction(theta_o, 0.0),
                                wi: direction(theta_i, phi),
                                alpha: roughness * roughness,
                                metallic,
                                base,
                            });
                        }
                    }
                }
            }
        }
    }
    cases
}

/// `bsdf_eval` on the GPU for every case.
fn gpu_brdf(gpu: &Gpu, cases: &[Case]) -> Vec<[f64; 3]> {
    let f = |a: [f64; 3], w: f64| [a[0] as f32, a[1] as f32, a[2] as f32, w as f32];
    let input: Vec<[f32; 4]> =
        cases.iter().flat_map(|c| [f(c.wo, c.alpha), f(c.wi, c.metallic), f(c.base, 0.0)]).collect();
    common::sample_test_rgb(gpu, "brdf", 2, &input, cases.len() as u32)
}

/// Cases where GPU and CPU differ by more than f32 rounding allows: relative 1e-4 of the value,
/// plus 1e-5 absolute for values near 0.
fn mismatches(cases: &[Case], gpu: &[[f64; 3]], variant: Variant) -> Vec<String> {
    cases
        .iter()
        .zip(gpu)
        .filter_map(|(c, g)| {
            let cpu = gltf_brdf(c, variant);
            let bad = (0..3).any(|k| (g[k] - cpu[k]).abs() > 1e-4 * cpu[k].abs() + 1e-5);
            bad.then(|| {
                format!(
                    "wo {:?} wi {:?} alpha {} metallic {} base {:?}: GPU {g:?}, glTF {cpu:?}",
                    c.wo, c.wi, c.alpha, c.metallic, c.base
                )
            })
        })
        .collect()
}

#[test]
fn gpu_brdf_matches_the_gltf_specification() {
    let gpu = Gpu::new();
    let cases = grid();
    let values = gpu_brdf(&gpu, &cases);
    let bad = mismatches(&cases, &values, Variant::Spec);
    assert!(
        bad.is_empty(),
        "{} of {} cases differ:\n{}",
        bad.len(),
        cases.len(),
        bad[..bad.len().min(10)].join("\n")
    );
    // The grid reaches the interesting values: glossy peaks well above the diffuse level.
    let peak = values.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
    assert!(peak > 10.0, "the grid never met a specular peak (max {peak})");
}

/// Each deliberately wrong reference is told apart from the GPU on many cases.
#[test]
fn the_brdf_comparison_rejects_wrong_references() {
    let gpu = Gpu::new();
    let cases = grid();
    let values = gpu_brdf(&gpu, &cases);
    for variant in [Variant::DiffuseUnweighted, Variant::HeightCorrelated, Variant::MetalF0] {
        let bad = mismatches(&cases, &values, variant);
        assert!(bad.len() > cases.len() / 20, "a wrong reference passed on all but {} cases", bad.len());
    }
}
