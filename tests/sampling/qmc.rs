//! The path tracer's low-discrepancy numbers: stratification, uniformity and independence.

use crate::common::Gpu;
use crate::kernel::Kernel;
use crate::pooled_chi_square;
use umbra::gpu::layout::SampleTestParams;
use umbra::passes::pathtrace::Microfacet;

/// Four numbers per sample of the path tracer (`random.glsl`'s `qmc4`, sample_test's modes 6
/// and 7): mode 6 the first `count` samples of pixel (`pixel`, 0) in one stream, mode 7 sample 5
/// of pixels (0, `pixel`) to (`count` − 1, `pixel`).
fn qmc(gpu: &Gpu, kernel: &Kernel, mode: u32, pixel: u32, count: u32) -> Vec<[f32; 4]> {
    let params = SampleTestParams { mode, count, seed: 12345, kind: pixel, ..Default::default() };
    kernel.dispatch(gpu, Microfacet::Ggx, &[], &params)
}

/// The path tracer's numbers stratify at every sample count that is a power of two: in a pixel's
/// stream, each of its two pairs, (y, z) and (x, w), over the first 2^m samples is a (0, m, 2)-net
/// for every m up to 12, that is every box 2^-k wide and 2^-(m-k) tall holds exactly one point
/// (Owen-scrambled Sobol points, shuffled). Independent random numbers fail this at m = 1 with
/// probability 1/2 per pair, and all but surely by m = 4.
#[test]
fn the_path_tracers_numbers_stratify_at_every_power_of_two() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    const M: usize = 12;
    for pixel in [0, 1, 77] {
        let u = qmc(&gpu, &kernel, 6, pixel, 1 << M);
        for (a, b) in [(1, 2), (0, 3)] {
            for m in 0..=M {
                for k in 0..=m {
                    let mut seen = vec![false; 1 << m];
                    for (s, p) in u[..1 << m].iter().enumerate() {
                        // Exact: the numbers are multiples of 2^-24.
                        let cx = (p[a] * (1u32 << k) as f32) as usize;
                        let cy = (p[b] * (1u32 << (m - k)) as f32) as usize;
                        let cell = (cx << (m - k)) + cy;
                        assert!(
                            !seen[cell],
                            "pixel {pixel}, components ({a}, {b}), {} samples: sample {s} shares its \
                             2^-{k} × 2^-{} box with an earlier one",
                            1 << m,
                            m - k
                        );
                        seen[cell] = true;
                    }
                }
            }
        }
    }
}

/// The path tracer's numbers are uniform and independent where they are not stratified: across
/// pixels (each pixel's own scrambles, so a pixel's error is independent of its neighbours'), every
/// component and both pairs are uniform; within a pixel's stream the two pairs are shuffled apart
/// (padding), so a number of one pair is independent of the other pair's. Chi-square on 64 cells
/// each (a component in 64 bins, a pair in 8 × 8), significance 0.01 with a Šidák correction
/// over the family. Fails if a pixel's scrambles do not depend on the pixel, or if the pairs share
/// one shuffle of the sample index (their points then fall in matching strata).
#[test]
fn the_path_tracers_numbers_are_uniform_across_pixels_and_pairs_independent() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    let n = 4096u32;
    let uniform = vec![1.0 / 64.0; 64];
    let histogram = |u: &[[f32; 4]], a: usize, b: Option<usize>| {
        let mut cells = vec![0.0; 64];
        for p in u {
            let cell = match b {
                None => (p[a] * 64.0) as usize,
                Some(b) => (p[a] * 8.0) as usize * 8 + (p[b] * 8.0) as usize,
            };
            cells[cell] += 1.0;
        }
        cells
    };
    let mut cases = Vec::new();
    for row in [0, 3] {
        let u = qmc(&gpu, &kernel, 7, row, n);
        for a in 0..4 {
            cases.push((format!("pixel row {row}: component {a} across pixels"), histogram(&u, a, None)));
        }
        for (a, b) in [(1, 2), (0, 3)] {
            cases
                .push((format!("pixel row {row}: pair ({a}, {b}) across pixels"), histogram(&u, a, Some(b))));
        }
    }
    for pixel in [0, 5] {
        let u = qmc(&gpu, &kernel, 6, pixel, n);
        for (a, b) in [(0, 1), (0, 2), (3, 1), (3, 2)] {
            cases.push((
                format!("pixel {pixel}: components {a} and {b} over its samples"),
                histogram(&u, a, Some(b)),
            ));
        }
    }
    let alpha = 1.0 - 0.99f64.powf(1.0 / cases.len() as f64);
    let mut failures = Vec::new();
    for (name, cells) in &cases {
        let (p, chi2, dof) = pooled_chi_square(cells, &uniform, n as f64);
        eprintln!("{name}: chi2 {chi2:.1}, dof {dof}, p {p:.4}");
        if p < alpha {
            failures.push(format!("{name}: p = {p} < {alpha}"));
        }
    }
    assert!(failures.is_empty(), "significance {alpha} per case:\n{}", failures.join("\n"));
}
