//! The CPU side of split-sum image-based lighting (GPU passes in [`crate::passes::ibl`], layouts
//! in `spirv/include/ibl.glsl`): the level sizes both sides share, and f64 references of the
//! BRDF table and of SH9 irradiance that the tests hold the kernels to.

use crate::environment::EnvironmentMap;
use std::f64::consts::PI;

/// Prefiltered levels: level k holds perceptual roughness k / (IBL_LEVELS − 1).
pub const IBL_LEVELS: u32 = 6;
/// The BRDF table is LUT_SIZE × LUT_SIZE over (n·v, perceptual roughness): n·v at texel
/// centres, roughness edge to edge (see [`lut_coordinates`]).
pub const LUT_SIZE: u32 = 32;
/// Prefiltered level 1 is at most half this wide (the source is halved until it fits).
pub const IBL_MAX_WIDTH: u32 = 1024;

/// Sizes of the prefiltered levels 0..IBL_LEVELS for a source of `size` (level 0 is the source).
pub fn prefiltered_level_sizes((w, h): (u32, u32)) -> Vec<(u32, u32)> {
    let (mut sw, mut sh) = (w, h);
    while sw > IBL_MAX_WIDTH {
        sw = (sw >> 1).max(1);
        sh = (sh >> 1).max(1);
    }
    let mut sizes = vec![(w, h)];
    sizes.extend((1..IBL_LEVELS).map(|k| ((sw >> k).max(8), (sh >> k).max(4))));
    sizes
}

/// Sizes of the box chain's levels (level 0 the source), halving down to 1×1.
pub fn chain_level_sizes((w, h): (u32, u32)) -> Vec<(u32, u32)> {
    let levels = 32 - w.max(h).leading_zeros();
    (0..levels).map(|k| ((w >> k).max(1), (h >> k).max(1))).collect()
}

/// Gauss–Legendre nodes and weights on [0, 1] (one implementation, in [`crate::sheen`], which
/// build.rs compiles on its own).
pub use crate::sheen::gauss_legendre;

fn ggx_g1(cos: f64, a: f64) -> f64 {
    let c = cos.abs();
    2.0 * c / (c + (a * a + (1.0 - a * a) * c * c).sqrt())
}

/// One BRDF-table entry (A, B, C, D) at `n·v` and perceptual `roughness`, by Gauss–Legendre
/// quadrature with `n` nodes per axis, independent of the kernel's visible-normal sampling:
/// the specular integral over half vectors distributed as D(h) cos θh (u ↦ tan²θh = α² u / (1 − u),
/// φ restricted analytically to where l is above the horizon), the diffuse one over the
/// cosine-weighted hemisphere.
pub fn lut_entry(nv: f64, roughness: f64, n: usize) -> [f64; 4] {
    let a = (roughness * roughness).max(1e-4);
    let nodes = gauss_legendre(n);
    let sv = (1.0 - nv * nv).sqrt();
    let v = [sv, 0.0, nv];
    let pow5 = |x: f64| x * x * x * x * x;
    let (mut spec_a, mut spec_b) = (0.0, 0.0);
    // u panels graded towards u = 1, where θh sweeps to grazing.
    let panels: Vec<(f64, f64)> = {
        let cuts = [0.0, 0.5, 0.75, 0.9, 0.97, 0.99, 0.997, 0.999, 0.9999, 1.0];
        cuts.windows(2).map(|w| (w[0], w[1])).collect()
    };
    for &(u0, u1) in &panels {
        for &(x, wu) in &nodes {
            let u = u0 + (u1 - u0) * x;
            let tan2 = a * a * u / (1.0 - u);
            let ch = 1.0 / (1.0 + tan2).sqrt();
            let shh = (1.0 - ch * ch).max(0.0).sqrt();
            // l.z > 0 ⟺ cos φ > c.
            let c = if sv * shh > 0.0 { (nv / (2.0 * ch) - nv * ch) / (sv * shh) } else { f64::NEG_INFINITY };
            let phi_max = if c <= -1.0 {
                PI
            } else if c >= 1.0 {
                continue;
            } else {
                c.acos()
            };
            let (mut ia, mut ib) = (0.0, 0.0);
            for &(y, wp) in &nodes {
                let phi = phi_max * y;
                let h = [shh * phi.cos(), shh * phi.sin(), ch];
                let vh = v[0] * h[0] + v[2] * h[2];
                let lz = 2.0 * vh * h[2] - v[2];
                if lz <= 0.0 || vh <= 0.0 {
                    continue;
                }
                let f = ggx_g1(nv, a) * ggx_g1(lz, a) * vh / (nv * ch);
                let fc = pow5(1.0 - vh);
                ia += wp * f * (1.0 - fc);
                ib += wp * f * fc;
            }
            // (1 / 2π) · 2 (φ symmetric) · φmax (the φ interval) · (u1 − u0) (the u panel).
            let scale = wu * (u1 - u0) * phi_max / PI;
            spec_a += scale * ia;
            spec_b += scale * ib;
        }
    }
    let (mut dc, mut dd) = (0.0, 0.0);
    for &(x, wu) in &nodes {
        let r = x.sqrt();
        let lz = (1.0 - x).sqrt();
        for &(y, wp) in &nodes {
            let phi = PI * y;
            let vl = sv * r * phi.cos() + nv * lz;
            let vh = ((1.0 + vl) * 0.5).max(0.0).sqrt();
            let fc = pow5(1.0 - vh);
            dc += wu * wp * (1.0 - fc);
            dd += wu * wp * fc;
        }
    }
    [spec_a, spec_b, dc, dd]
}

/// The (n·v, perceptual roughness) of BRDF-table entry j · LUT_SIZE + i: n·v = (i + ½) / LUT_SIZE
/// (n·v = 0 is degenerate) and roughness j / (LUT_SIZE − 1), so roughness 1, common and where
/// A + B falls fastest, is an entry rather than clamped to the last texel centre.
pub fn lut_coordinates(i: usize, j: usize) -> (f64, f64) {
    ((i as f64 + 0.5) / LUT_SIZE as f64, j as f64 / (LUT_SIZE - 1) as f64)
}

/// The whole BRDF table by [`lut_entry`], entry j · LUT_SIZE + i at [`lut_coordinates`]`(i, j)`.
pub fn lut_reference(n: usize) -> Vec<[f64; 4]> {
    let s = LUT_SIZE as usize;
    (0..s * s)
        .map(|k| {
            let (nv, roughness) = lut_coordinates(k % s, k / s);
            lut_entry(nv, roughness, n)
        })
        .collect()
}

/// The real SH basis of bands 0..2 at unit `d` (the order of `sh9_basis` in ibl.glsl).
pub fn sh9_basis(d: [f64; 3]) -> [f64; 9] {
    let [x, y, z] = d;
    [
        0.282_094_791_773_878_1,
        0.488_602_511_902_919_9 * y,
        0.488_602_511_902_919_9 * z,
        0.488_602_511_902_919_9 * x,
        1.092_548_430_592_079_2 * x * y,
        1.092_548_430_592_079_2 * y * z,
        0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
        1.092_548_430_592_079_2 * x * z,
        0.546_274_215_296_039_6 * (x * x - y * y),
    ]
}

/// The clamped-cosine convolution factor A_l of SH coefficient `i` (π, 2π/3, π/4).
pub fn sh9_band_factor(i: usize) -> f64 {
    match i {
        0 => PI,
        1..=3 => 2.0 * PI / 3.0,
        _ => PI / 4.0,
    }
}

/// Direction of the centre of texel (x, y) of a `w` × `h` map (`env_direction` in
/// environment.glsl) and its exact solid angle.
pub fn texel_direction(x: usize, y: usize, w: usize, h: usize) -> ([f64; 3], f64) {
    let (u, v) = ((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
    let (phi, theta) = ((u - 0.5) * 2.0 * PI, v * PI);
    let s = theta.sin();
    let d_omega =
        2.0 * PI / w as f64 * ((PI * y as f64 / h as f64).cos() - (PI * (y + 1) as f64 / h as f64).cos());
    ([s * phi.sin(), theta.cos(), -s * phi.cos()], d_omega)
}

/// The SH basis integrated exactly over the lat-long cell [θ0, θ1] × [φ0, φ1] (`sh9_cell` in
/// ibl.glsl), so a piecewise-constant map projects exactly.
pub fn sh9_cell(t0: f64, t1: f64, p0: f64, p1: f64) -> [f64; 9] {
    let dp = p1 - p0;
    let (ps, pc) = (p0.cos() - p1.cos(), p1.sin() - p0.sin());
    let s2 = 0.25 * ((2.0 * p1).sin() - (2.0 * p0).sin());
    let (pss, pcc) = (0.5 * dp - s2, 0.5 * dp + s2);
    let psc = 0.5 * (p1.sin().powi(2) - p0.sin().powi(2));
    let (c0, c1, n0, n1) = (t0.cos(), t1.cos(), t0.sin(), t1.sin());
    let t1_ = c0 - c1;
    let ts = 0.5 * (t1 - t0) - 0.25 * ((2.0 * t1).sin() - (2.0 * t0).sin());
    let tc = 0.5 * (n1 * n1 - n0 * n0);
    let tss = (c0 - c0.powi(3) / 3.0) - (c1 - c1.powi(3) / 3.0);
    let tcc = (c0.powi(3) - c1.powi(3)) / 3.0;
    let tsc = (n1.powi(3) - n0.powi(3)) / 3.0;
    [
        0.282_094_791_773_878_1 * t1_ * dp,
        0.488_602_511_902_919_9 * tc * dp,
        -0.488_602_511_902_919_9 * ts * pc,
        0.488_602_511_902_919_9 * ts * ps,
        1.092_548_430_592_079_2 * tsc * ps,
        -1.092_548_430_592_079_2 * tsc * pc,
        0.315_391_565_252_520_05 * (3.0 * tss * pcc - t1_ * dp),
        -1.092_548_430_592_079_2 * tss * psc,
        0.546_274_215_296_039_6 * (tss * pss - tcc * dp),
    ]
}

/// SH9 irradiance coefficients of `map` (× A_l), as `ibl_sh.comp` computes them, in f64.
pub fn sh9_irradiance_coefficients(map: &EnvironmentMap) -> [[f64; 3]; 9] {
    let (w, h) = (map.width as f64, map.height as f64);
    let mut c = [[0.0; 3]; 9];
    for y in 0..map.height {
        let (t0, t1) = (PI * y as f64 / h, PI * (y + 1) as f64 / h);
        for x in 0..map.width {
            let (p0, p1) = ((x as f64 / w - 0.5) * 2.0 * PI, ((x + 1) as f64 / w - 0.5) * 2.0 * PI);
            let l = map.texels[y * map.width + x];
            for (k, b) in sh9_cell(t0, t1, p0, p1).into_iter().enumerate() {
                for ch in 0..3 {
                    c[k][ch] += l[ch] as f64 * b;
                }
            }
        }
    }
    for (k, ck) in c.iter_mut().enumerate() {
        *ck = ck.map(|v| v * sh9_band_factor(k));
    }
    c
}

/// Irradiance E(n) from SH9 coefficients.
pub fn sh9_irradiance(c: &[[f64; 3]; 9], n: [f64; 3]) -> [f64; 3] {
    let b = sh9_basis(n);
    std::array::from_fn(|ch| (0..9).map(|k| c[k][ch] * b[k]).sum())
}

/// Irradiance E(n) = ∫ L(ω) max(0, n·ω) dω by summing over every texel of `map`.
pub fn irradiance_brute_force(map: &EnvironmentMap, n: [f64; 3]) -> [f64; 3] {
    let mut e = [0.0; 3];
    for y in 0..map.height {
        for x in 0..map.width {
            let (d, d_omega) = texel_direction(x, y, map.width, map.height);
            let cos = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]).max(0.0);
            let l = map.texels[y * map.width + x];
            for ch in 0..3 {
                e[ch] += l[ch] as f64 * cos * d_omega;
            }
        }
    }
    e
}
