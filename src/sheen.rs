//! `KHR_materials_sheen`'s directional albedo table, shared by the kernels and the tests.
//!
//! The sheen lobe is the extension's: the "Charlie" distribution of Conty Estevez and Kulla
//! (2017) at α = sheenRoughness², with their fitted Λ for the visibility,
//!
//! ```text
//! f_sheen = sheenColor · D(h) / ((1 + Λ(n·v) + Λ(n·l)) · 4 |n·v| |n·l|)
//! D(h)    = (2 + 1/α) sin(θh)^(1/α) / (2π)
//! ```
//!
//! and the base under it is scaled by the albedo-scaling term
//! min(1 − max3(sheenColor) E(n·v), 1 − max3(sheenColor) E(n·l)), where E(μ, r) is the lobe's
//! directional albedo (sheenColor 1). E is tabulated here, [`TABLE_SIZE`]² entries over
//! (√μ, r) ∈ [0, 1]², edge to edge (√μ: E rises and falls within n·v < 0.02 for smooth sheens),
//! each a Gauss–Legendre quadrature over the hemisphere of light directions.
//!
//! The fitted Λ is not the distribution's exact Smith Λ: E exceeds 1 at grazing n·v for smooth
//! sheens (at n·v ≈ 0.005: 3.9 at r = 0.05, 1.19 at r = 0.2, 1.02 at r = 0.25; at most 0.92 from
//! r = 0.3 on). The kernels clamp the albedo scaling of the base at 0 there. build.rs includes this file (`#[path]`) and writes the table into the generated
//! `sheen_albedo.glsl`, which `bsdf.glsl` interpolates bilinearly.
//!
//! This file stands alone (std only), as build.rs compiles it too.

use std::f64::consts::PI;

/// Entries of the table per axis.
pub const TABLE_SIZE: usize = 32;
/// The least sheen roughness the kernels use (smaller ones are clamped to it): α = 0.0025,
/// D ∝ sin(θh)^400. The table's row 0 holds E at this roughness.
pub const ROUGHNESS_MIN: f64 = 0.05;
/// The least n·v the table is evaluated at (E diverges weakly as n·v → 0); column 0 holds E here.
pub const COSINE_MIN: f64 = 1e-4;
/// Quadrature nodes per axis and panel of the table's entries.
pub const TABLE_NODES: usize = 48;

/// The Charlie distribution at cos θh with α = roughness².
pub fn charlie_d(cos_h: f64, alpha: f64) -> f64 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI)
}

fn charlie_l(x: f64, alpha: f64) -> f64 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f64, b: f64| a + (b - a) * t;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let d = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Conty Estevez and Kulla's fitted Λ at cos θ (≥ 0).
pub fn charlie_lambda(cos: f64, alpha: f64) -> f64 {
    if cos < 0.5 {
        charlie_l(cos, alpha).exp()
    } else {
        (2.0 * charlie_l(0.5, alpha) - charlie_l(1.0 - cos, alpha)).exp()
    }
}

/// α for a sheen roughness, the kernels' clamp included.
pub fn alpha(roughness: f64) -> f64 {
    let r = roughness.max(ROUGHNESS_MIN);
    r * r
}

/// f_sheen |n·l| for sheenColor 1 between `v` and `l` (unit, z the normal, both above).
pub fn brdf_cos(v: [f64; 3], l: [f64; 3], roughness: f64) -> f64 {
    if v[2] <= 0.0 || l[2] <= 0.0 {
        return 0.0;
    }
    let a = alpha(roughness);
    let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
    let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let d = charlie_d(h[2] / len, a);
    d / ((1.0 + charlie_lambda(v[2], a) + charlie_lambda(l[2], a)) * 4.0 * v[2])
}

/// Gauss–Legendre nodes and weights on [0, 1]: `n` pairs (x, w).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            ((1.0 - x) * 0.5, 1.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// E(μ, roughness): the sheen lobe's directional albedo at n·v = μ, by Gauss–Legendre
/// quadrature with `n` nodes per panel in cos θl (panels graded towards the horizon, where a
/// smooth sheen's fibres reflect) and `n` in φl over [0, π] (the lobe is symmetric).
pub fn albedo(mu: f64, roughness: f64, n: usize) -> f64 {
    let mu = mu.clamp(COSINE_MIN, 1.0);
    let v = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let nodes = gauss_legendre(n);
    let cuts = [0.0, 0.01, 0.05, 0.2, 0.5, 1.0];
    let mut sum = 0.0;
    for w in cuts.windows(2) {
        for &(x, wz) in &nodes {
            let z = w[0] + (w[1] - w[0]) * x;
            let s = (1.0 - z * z).sqrt();
            let mut ring = 0.0;
            for &(y, wp) in &nodes {
                let phi = PI * y;
                ring += wp * brdf_cos(v, [s * phi.cos(), s * phi.sin(), z], roughness);
            }
            // dω = dz dφ; φ over [0, π] counted twice.
            sum += wz * (w[1] - w[0]) * ring * 2.0 * PI;
        }
    }
    sum
}

/// The (μ, roughness) of table entry j · TABLE_SIZE + i: √μ = i / (TABLE_SIZE − 1) and
/// roughness j / (TABLE_SIZE − 1).
pub fn table_coordinates(i: usize, j: usize) -> (f64, f64) {
    let step = 1.0 / (TABLE_SIZE - 1) as f64;
    let x = i as f64 * step;
    (x * x, j as f64 * step)
}

/// The table the kernels interpolate: entry j · TABLE_SIZE + i is [`albedo`] at
/// [`table_coordinates`]`(i, j)` with [`TABLE_NODES`] nodes.
pub fn table() -> Vec<f32> {
    (0..TABLE_SIZE * TABLE_SIZE)
        .map(|k| {
            let (mu, r) = table_coordinates(k % TABLE_SIZE, k / TABLE_SIZE);
            albedo(mu, r, TABLE_NODES) as f32
        })
        .collect()
}

/// The table bilinearly interpolated at (μ, roughness), as `sheen_albedo` in bsdf.glsl reads it.
pub fn table_lookup(table: &[f32], mu: f64, roughness: f64) -> f64 {
    let last = (TABLE_SIZE - 1) as f64;
    let x = mu.clamp(0.0, 1.0).sqrt() * last;
    let y = roughness.clamp(0.0, 1.0) * last;
    let (i, j) = ((x as usize).min(TABLE_SIZE - 2), (y as usize).min(TABLE_SIZE - 2));
    let (fx, fy) = (x - i as f64, y - j as f64);
    let at = |i: usize, j: usize| table[j * TABLE_SIZE + i] as f64;
    let a = at(i, j) + (at(i + 1, j) - at(i, j)) * fx;
    let b = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * fx;
    a + (b - a) * fy
}
