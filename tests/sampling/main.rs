//! Chi-square goodness of fit of the path tracer's direction samplers, through a test-only
//! kernel (`spirv/sample_test.comp`) that includes the renderer's own `sampling.glsl` and
//! `bsdf.glsl`: the histogram of sampled directions must match the pdf the same code reports,
//! integrated over each cell (Mitsuba's chi2 test, pbrt's bsdfs_test). Cells with an expected
//! count below 5 are pooled; significance 0.01 with a Šidák correction over all cases. Each
//! microfacet sampling is tested (GGX from visible normals, GGX from D(h) cos θh as Walter et al.
//! 2007 sample it, Beckmann), alone and inside the dielectric BSDF.
//! Light sampling goes through a second test kernel (`spirv/light_sample_test.comp`, the
//! renderer's environment.glsl and shading.glsl): `env_sample` against `env_pdf` on a real HDR
//! sky, and next-event estimation on emissive triangles against the light pdf the path tracer's
//! MIS uses, with their own Šidák family of four.
//! The path tracer's low-discrepancy numbers (`random.glsl`'s `qmc4`) are checked for their
//! stratification (nets at every power of two) and, where they are meant to be, uniformity and
//! independence.
//! `UMBRA_CHI2_DEBUG=1` prints each case's worst cells.

#[path = "../common/mod.rs"]
mod common;

mod bsdf;
mod kernel;
mod lights;
mod qmc;

use common::gamma_q;

/// How `bsdf_sample` spends its numbers: a lobe by u.x and its direction by (u.y, u.z), or (sample
/// reuse, the path tracer's with low-discrepancy numbers) a lobe by u.y, whose share of it,
/// stretched back over [0, 1), replaces u.y for the direction: sample_test's mode 0 or mode 8.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Numbers {
    Fresh,
    Reused,
}

/// Prints the six cells that contribute most to the chi-square statistic.
fn print_worst_cells(observed: &[f64], expected: &[f64], n: f64) {
    let mut worst: Vec<(f64, usize, f64, f64)> = observed
        .iter()
        .zip(expected)
        .enumerate()
        .map(|(i, (o, e))| ((o - e * n).powi(2) / (e * n).max(1e-9), i, *o, e * n))
        .collect();
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    for w in worst.iter().take(6) {
        eprintln!("  cell {}: observed {} expected {:.1}, chi2 {:.1}", w.1, w.2, w.3, w.0);
    }
}

/// Pearson's chi-square of `observed` counts against `expected` probabilities × `n`, cells with
/// an expected count below 5 pooled into one: (p-value, statistic, degrees of freedom).
fn pooled_chi_square(observed: &[f64], expected: &[f64], n: f64) -> (f64, f64, usize) {
    let (mut chi2, mut cells, mut pooled_o, mut pooled_e) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(expected) {
        let e = e * n;
        if e < 5.0 {
            pooled_o += o;
            pooled_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        chi2 += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        cells += 1;
    } else if pooled_o > 0.0 {
        // Samples where the pdf says none can land.
        chi2 = f64::INFINITY;
    }
    let dof = cells.saturating_sub(1).max(1);
    let p = if chi2.is_finite() { gamma_q(dof as f64 / 2.0, chi2 / 2.0) } else { 0.0 };
    (p, chi2, dof)
}
