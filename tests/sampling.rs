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

mod common;

use common::{gamma_q, Gpu};
use glam::Vec3;
use umbra::gpu::kernels::{light_sample_test, sample_test};
use umbra::gpu::layout::{LightTestParams, SampleTestParams};
use umbra::gpu::Pipeline;
use umbra::passes::pathtrace::{EmitterSampling, Microfacet};
use umbra::vk::{raw, Buffer, MemoryLocation};

const THETA_CELLS: usize = 16; // in cos θ over [−1, 1]
const PHI_CELLS: usize = 32;
const SUB: usize = 64; // pdf evaluations per cell side
const SAMPLES: u32 = 400_000;
/// The cap around wi = −wo integrated in polar coordinates for half-vector sampling from
/// D(h) cos θh (see `chi_square`):
/// radius (radians; the grid spacing is about 0.003), rings and spokes.
const CAP_RADIUS: f64 = 0.1;
const CAP_RINGS: usize = 512;
const CAP_SPOKES: usize = 4000;

#[derive(Clone, Copy, Debug)]
enum Sampler {
    Cosine,
    /// Uniform in solid angle over the cone about +z with 1 − cos θmax = `one_minus_cos`
    /// (sample_test's kind 11): the sized lights' shadow rays.
    Cone {
        one_minus_cos: f32,
    },
    Microfacet {
        microfacet: Microfacet,
        alpha: f32,
        theta_degrees: f32,
    },
    /// The whole BSDF of a white transmissive dielectric (GGX, either sampling): reflection +
    /// transmission.
    Dielectric {
        microfacet: Microfacet,
        kind: Dielectric,
        alpha: f32,
        theta_degrees: f32,
    },
    /// `KHR_materials_anisotropy` (sample_test's kind 9): a grey (0.8) surface of `metallic`
    /// (0: the dielectric's reflection over its diffuse lobe), α along the anisotropy direction
    /// mix(α, 1, strength²) and α across it, the direction `direction_degrees` from the frame's x
    /// towards y; wo in the xz plane.
    Anisotropic {
        alpha: f32,
        strength: f32,
        metallic: f32,
        direction_degrees: f32,
        theta_degrees: f32,
    },
    /// `KHR_materials_diffuse_transmission` (sample_test's kind 10): a grey (0.6) dielectric of
    /// α `alpha` whose diffuse lobe sends `share` through the back (tinted 1, 0.8, 0.64), thin
    /// transmission (`KHR_materials_transmission`) of `transmission` beside it; wo in the xz plane.
    DiffuseTransmission {
        alpha: f32,
        share: f32,
        transmission: f32,
        theta_degrees: f32,
    },
}

/// The transmissive dielectrics of `sample_test.comp` (its sampler numbers).
#[derive(Clone, Copy, Debug)]
enum Dielectric {
    /// Refracting into glass, η = 1.5.
    Entering = 2,
    /// Refracting out of glass, η = 1/1.5 (total internal reflection beyond 41.8°).
    Leaving = 3,
    /// Thin-walled: transmission without bending.
    Thin = 4,
    /// Not a dielectric boundary: an opaque grey dielectric (α 0.25) under a clear coat
    /// (`KHR_materials_clearcoat`, weight 1) of the case's α.
    Coated = 5,
    /// The grey dielectric under a coloured sheen (`KHR_materials_sheen`, colour (0.9, 0.6, 0.3),
    /// roughness √α of the case's α) under a clear coat of weight ½ and α 0.1: the three-level
    /// lobe choice (coat, sheen, material) and the sheen's cosine-hemisphere sampling.
    Sheened = 6,
    /// The coated dielectric with the coat's own normal tilted 28° from the shading normal
    /// (towards +x and +y): the coat's lobe evaluated and sampled in its own frame.
    CoatTilted = 7,
    /// Not a dielectric boundary: a half-metallic surface (base (0.8, 0.6, 0.4), metallic 0.3, the
    /// case's α) under a thin film (`KHR_materials_iridescence`: weight 1, ior 1.8, 350 nm), whose
    /// Fresnel sets the lobes' probabilities.
    Iridescent = 8,
}

/// The kernel specialised for each [`Microfacet`], in [`Microfacet::ALL`] order, and the sheen's
/// albedo table.
struct Kernel([Pipeline<sample_test::Kernel>; 3], Vec<f32>);

impl Kernel {
    fn new(gpu: &Gpu) -> Self {
        Self(
            Microfacet::ALL.map(|m| {
                let spec = sample_test::Spec {
                    beckmann: m == Microfacet::Beckmann,
                    ggx_walter: m == Microfacet::GgxWalter,
                };
                Pipeline::new(gpu, &spec, None).unwrap()
            }),
            umbra::sheen::table(),
        )
    }

    /// Runs the kernel: mode 0 samples `count` directions, mode 1 evaluates the pdf at `dirs`,
    /// mode 3 the dielectric's BSDF (rgb) and pdf (w) at `dirs`.
    fn run(
        &self,
        gpu: &Gpu,
        sampler: Sampler,
        pdf_alpha_scale: f32,
        mode: u32,
        dirs: &[[f32; 4]],
        count: u32,
    ) -> Vec<[f32; 4]> {
        let mut anisotropy = [0.0f32; 4];
        let (microfacet, wo, alpha, which) = match sampler {
            Sampler::Cosine => (Microfacet::Ggx, Vec3::Z, 1.0, 0),
            Sampler::Cone { one_minus_cos } => (Microfacet::Ggx, Vec3::Z, one_minus_cos, 11),
            Sampler::Microfacet { microfacet, alpha, theta_degrees } => {
                let t = theta_degrees.to_radians();
                (microfacet, Vec3::new(t.sin(), 0.0, t.cos()), alpha, 1)
            }
            Sampler::Dielectric { microfacet, kind, alpha, theta_degrees } => {
                let t = theta_degrees.to_radians();
                (microfacet, Vec3::new(t.sin(), 0.0, t.cos()), alpha, kind as u32)
            }
            Sampler::Anisotropic { alpha, strength, metallic, direction_degrees, theta_degrees } => {
                let t = theta_degrees.to_radians();
                let d = direction_degrees.to_radians();
                anisotropy = [strength, d.cos(), d.sin(), metallic];
                (Microfacet::Ggx, Vec3::new(t.sin(), 0.0, t.cos()), alpha, 9)
            }
            Sampler::DiffuseTransmission { alpha, share, transmission, theta_degrees } => {
                let t = theta_degrees.to_radians();
                anisotropy = [share, transmission, 1.0, 0.6];
                (Microfacet::Ggx, Vec3::new(t.sin(), 0.0, t.cos()), alpha, 10)
            }
        };
        // A deliberately wrong pdf evaluates with a scaled alpha (sampling keeps the true one).
        let alpha = if mode == 1 { alpha * pdf_alpha_scale } else { alpha };
        let params = SampleTestParams {
            wo: wo.into(),
            alpha,
            mode,
            count,
            seed: 12345,
            kind: which,
            anisotropy,
            anisotropy_base: 0.8,
            ..Default::default()
        };
        self.dispatch(gpu, microfacet, dirs, &params)
    }

    /// Runs the kernel specialised for `microfacet` on `params.count` invocations, `dirs` (and the
    /// sheen's albedo table) as its input.
    fn dispatch(
        &self,
        gpu: &Gpu,
        microfacet: Microfacet,
        dirs: &[[f32; 4]],
        params: &SampleTestParams,
    ) -> Vec<[f32; 4]> {
        let pipeline = &self.0[microfacet as usize];
        let count = params.count;
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
        // The sheen's albedo table after the directions, as the kernel reads it.
        let mut input: Vec<[f32; 4]> = dirs.to_vec();
        input.extend(self.1.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
        let input = Buffer::upload(gpu, "sample test directions", &input, usage).unwrap();
        let output =
            Buffer::new(gpu, "sample test results", count as u64 * 16, usage, MemoryLocation::GpuOnly)
                .unwrap();
        gpu.submit(|cmd| {
            let resources = sample_test::Resources { directions: &input, results: &output };
            pipeline.record(cmd, &resources, params, [count, 1, 1], [64, 1, 1])
        })
        .unwrap();
        output.read(gpu).unwrap()
    }
}

fn cell_of(d: Vec3) -> usize {
    let z = d.z.clamp(-1.0, 1.0);
    let t = (((z + 1.0) * 0.5 * THETA_CELLS as f32) as usize).min(THETA_CELLS - 1);
    let phi = d.y.atan2(d.x).rem_euclid(std::f32::consts::TAU);
    let p = ((phi / std::f32::consts::TAU * PHI_CELLS as f32) as usize).min(PHI_CELLS - 1);
    t * PHI_CELLS + p
}

/// How `bsdf_sample` spends its numbers: a lobe by u.x and its direction by (u.y, u.z), or (sample
/// reuse, the path tracer's with low-discrepancy numbers) a lobe by u.y, whose share of it,
/// stretched back over [0, 1), replaces u.y for the direction: sample_test's mode 0 or mode 8.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Numbers {
    Fresh,
    Reused,
}

/// The chi-square p-value of `sampler`'s samples (drawn with `numbers`) against its (possibly
/// deliberately wrong) pdf, and the pdf's total mass over the sphere.
fn chi_square(
    gpu: &Gpu,
    kernel: &Kernel,
    sampler: Sampler,
    numbers: Numbers,
    pdf_alpha_scale: f32,
    count: u32,
) -> (f64, f64, usize, f64) {
    let mode = if numbers == Numbers::Reused { 8 } else { 0 };
    let samples = kernel.run(gpu, sampler, 1.0, mode, &[], count);
    // Samples the code reports with pdf 0 are failures it discards (half vectors sampled from
    // D(h) cos θh can face away from wo): they form one more cell, expected to hold the pdf's
    // missing mass.
    let mut observed = vec![0.0f64; THETA_CELLS * PHI_CELLS];
    let mut discarded = 0.0;
    for s in &samples {
        let d = Vec3::new(s[0], s[1], s[2]);
        assert!(s[3].is_finite() && s[3] >= 0.0, "{sampler:?}: sample {s:?} has a bad pdf");
        if s[3] == 0.0 {
            discarded += 1.0;
            continue;
        }
        assert!(
            d.is_finite() && (d.length() - 1.0).abs() < 1e-3,
            "{sampler:?}: sample {s:?} is not a unit direction"
        );
        observed[cell_of(d)] += 1.0;
    }
    // Expected: the pdf integrated over each cell, midpoint rule on SUB × SUB points in (cos θ, φ).
    let mut dirs = Vec::with_capacity(THETA_CELLS * PHI_CELLS * SUB * SUB);
    for t in 0..THETA_CELLS * SUB {
        let z = -1.0 + 2.0 * (t as f32 + 0.5) / (THETA_CELLS * SUB) as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for p in 0..PHI_CELLS * SUB {
            let phi = std::f32::consts::TAU * (p as f32 + 0.5) / (PHI_CELLS * SUB) as f32;
            dirs.push([r * phi.cos(), r * phi.sin(), z, 0.0]);
        }
    }
    let pdfs = kernel.run(gpu, sampler, pdf_alpha_scale, 1, &dirs, dirs.len() as u32);
    let cell_area = 2.0 / (THETA_CELLS * SUB) as f64 * std::f64::consts::TAU / (PHI_CELLS * SUB) as f64;
    let mut expected = vec![0.0f64; THETA_CELLS * PHI_CELLS];
    // The half-vector pdf D(h) cos θ_h / (4 wo·h) of Beckmann and of GGX sampled as Walter does
    // has an integrable 1/r singularity at wi = −wo (wo·h → r/2 at angular distance r from −wo),
    // which the grid under-integrates: in a cap around −wo the pdf is integrated in polar
    // coordinates about −wo instead, where the Jacobian sin r cancels the singularity. (Inside the
    // dielectric, wi near −wo is transmission, whose pdf has no such singularity.)
    let cap = match sampler {
        Sampler::Microfacet {
            microfacet: Microfacet::Beckmann | Microfacet::GgxWalter,
            theta_degrees,
            ..
        } => {
            let t = (theta_degrees as f64).to_radians();
            Some(-glam::DVec3::new(t.sin(), 0.0, t.cos()))
        }
        _ => None,
    };
    let in_cap = |d: &[f32; 4]| {
        cap.is_some_and(|c| glam::DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64).dot(c) > CAP_RADIUS.cos())
    };
    for (d, p) in dirs.iter().zip(&pdfs) {
        if !in_cap(d) {
            expected[cell_of(Vec3::new(d[0], d[1], d[2]))] += p[3] as f64 * cell_area;
        }
    }
    if let Some(c) = cap {
        let (e1, e2) = c.any_orthonormal_pair();
        let (dr, dpsi) = (CAP_RADIUS / CAP_RINGS as f64, std::f64::consts::TAU / CAP_SPOKES as f64);
        let mut polar = Vec::with_capacity(CAP_RINGS * CAP_SPOKES);
        let mut weight = Vec::with_capacity(CAP_RINGS * CAP_SPOKES);
        for i in 0..CAP_RINGS {
            let r = (i as f64 + 0.5) * dr;
            for j in 0..CAP_SPOKES {
                let psi = (j as f64 + 0.5) * dpsi;
                let d = r.cos() * c + r.sin() * (psi.cos() * e1 + psi.sin() * e2);
                polar.push([d.x as f32, d.y as f32, d.z as f32, 0.0]);
                weight.push(r.sin() * dr * dpsi);
            }
        }
        let pdfs = kernel.run(gpu, sampler, pdf_alpha_scale, 1, &polar, polar.len() as u32);
        for ((d, p), w) in polar.iter().zip(&pdfs).zip(&weight) {
            expected[cell_of(Vec3::new(d[0], d[1], d[2]))] += p[3] as f64 * w;
        }
    }
    let mass: f64 = expected.iter().sum();
    let n = samples.len() as f64;
    // Only sampling from D(h) cos θh (Beckmann, GGX as Walter) and the dielectric (a reflection
    // leaving its side, a refraction beyond the critical angle) can discard; VNDF sampling never
    // may. The discarded fraction is the pdf's missing mass (checked loosely: the mass comes from
    // quadrature).
    if matches!(
        sampler,
        Sampler::Microfacet { microfacet: Microfacet::Beckmann | Microfacet::GgxWalter, .. }
            | Sampler::Dielectric { .. }
            | Sampler::Anisotropic { .. }
            | Sampler::DiffuseTransmission { .. }
    ) {
        let missing = 1.0 - mass;
        assert!(
            (discarded / n - missing).abs() < 0.02,
            "{sampler:?}: discarded {} vs missing mass {missing}",
            discarded / n
        );
    } else {
        assert_eq!(discarded, 0.0, "{sampler:?} discarded samples");
    }
    if std::env::var("UMBRA_CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, n);
    }
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, n);
    (p, chi2, dof, mass)
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

fn cases() -> Vec<Sampler> {
    // Cones whose edge falls on a cell boundary in cos θ (cells 1/8 wide): the pdf is a step.
    let mut cases = vec![Sampler::Cosine];
    cases.extend([0.125, 0.5, 1.0].map(|one_minus_cos| Sampler::Cone { one_minus_cos }));
    for microfacet in Microfacet::ALL {
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            for theta_degrees in [0.0, 30.0, 60.0, 85.0] {
                cases.push(Sampler::Microfacet { microfacet, alpha, theta_degrees });
            }
        }
    }
    for microfacet in [Microfacet::Ggx, Microfacet::GgxWalter] {
        for kind in [
            Dielectric::Entering,
            Dielectric::Leaving,
            Dielectric::Thin,
            Dielectric::Coated,
            Dielectric::Sheened,
            Dielectric::CoatTilted,
            Dielectric::Iridescent,
        ] {
            for alpha in [0.1, 0.5] {
                for theta_degrees in [30.0, 60.0] {
                    cases.push(Sampler::Dielectric { microfacet, kind, alpha, theta_degrees });
                }
            }
        }
    }
    // KHR_materials_anisotropy: weak to total anisotropy (strength 1: α 1 along the direction),
    // the direction off the frame's axes and off wo's plane, metal and dielectric.
    for (alpha, strength) in [(0.05, 0.6), (0.2, 1.0), (0.5, 0.8)] {
        for metallic in [1.0, 0.0] {
            for theta_degrees in [30.0, 70.0] {
                cases.push(Sampler::Anisotropic {
                    alpha,
                    strength,
                    metallic,
                    direction_degrees: 30.0,
                    theta_degrees,
                });
            }
        }
    }
    // KHR_materials_diffuse_transmission: part and all of the diffuse lobe through the back,
    // alone and beside thin specular transmission.
    for (share, transmission) in [(0.5, 0.0), (1.0, 0.0), (0.6, 0.5)] {
        for alpha in [0.1, 0.5] {
            for theta_degrees in [30.0, 70.0] {
                cases.push(Sampler::DiffuseTransmission { alpha, share, transmission, theta_degrees });
            }
        }
    }
    cases
}

#[test]
fn samplers_match_their_pdfs() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    let cases = cases();
    let alpha = 1.0 - 0.99f64.powf(1.0 / cases.len() as f64);
    let failures = chi_square_failures(&gpu, &kernel, &cases, Numbers::Fresh, alpha);
    assert!(failures.is_empty(), "significance {alpha} per case:\n{}", failures.join("\n"));
}

/// Each of `cases` drawn with `numbers` through the chi-square: the cases whose p-value falls
/// below `alpha` or whose pdf integrates to more than 1 over the sphere (up to quadrature error).
fn chi_square_failures(
    gpu: &Gpu,
    kernel: &Kernel,
    cases: &[Sampler],
    numbers: Numbers,
    alpha: f64,
) -> Vec<String> {
    let mut failures = Vec::new();
    for case in cases {
        let (p, chi2, dof, mass) = chi_square(gpu, kernel, *case, numbers, 1.0, SAMPLES);
        eprintln!("{case:?} ({numbers:?} numbers): chi2 {chi2:.1}, dof {dof}, p {p:.4}, pdf mass {mass:.4}");
        if p < alpha {
            failures.push(format!("{case:?}: p = {p} < {alpha}"));
        }
        if mass > 1.01 {
            failures.push(format!("{case:?}: pdf mass {mass}"));
        }
    }
    failures
}

/// Sample reuse keeps `bsdf_sample`'s density: every case of [`samplers_match_their_pdfs`] that
/// chooses among lobes (the dielectric's, coated, sheened, iridescent, anisotropic and diffusely
/// transmitting cases) again with the lobe chosen by u.y and u.y's share stretched back as the
/// direction's first number (`SAMPLE_REUSE`), at the same significance per case (0.01, Šidák over
/// that test's cases). A stretch off its lobe's interval (its start or its width) puts the
/// directions elsewhere than the pdf: with the coat's stretch missing (u.y left as it was), the
/// coated cases fail. The reused numbers must also give other directions than fresh ones (the
/// reuse is live).
#[test]
fn sample_reuse_keeps_the_bsdf_pdfs() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    let cases = cases();
    let alpha = 1.0 - 0.99f64.powf(1.0 / cases.len() as f64);
    let lobed: Vec<Sampler> = cases
        .into_iter()
        .filter(|c| {
            matches!(
                c,
                Sampler::Dielectric { .. }
                    | Sampler::Anisotropic { .. }
                    | Sampler::DiffuseTransmission { .. }
            )
        })
        .collect();
    let failures = chi_square_failures(&gpu, &kernel, &lobed, Numbers::Reused, alpha);
    assert!(failures.is_empty(), "significance {alpha} per case:\n{}", failures.join("\n"));
    let case = Sampler::Dielectric {
        microfacet: Microfacet::Ggx,
        kind: Dielectric::Coated,
        alpha: 0.5,
        theta_degrees: 30.0,
    };
    let fresh = kernel.run(&gpu, case, 1.0, 0, &[], 4096);
    let reused = kernel.run(&gpu, case, 1.0, 8, &[], 4096);
    let same = fresh.iter().zip(&reused).filter(|(a, b)| a == b).count();
    assert!(same < 4096 / 2, "{same} of 4096 directions the same with and without reuse");
}

/// The tilted clear coat (its normal 28° from the shading normal), α 0.5, wo at 60°, under both GGX
/// samplings, at ten times the samples of [`samplers_match_their_pdfs`]: a coat sample whose
/// reflection in the coat's frame lies below the coat while wi is still above the shading frame
/// lies where `coat_pdf` is 0, and was once accepted: those directions were sampled more often
/// than the pdf said (p = 0.0008 for Walter's sampling at 400,000 samples, which passed the suite's
/// level; far below this test's at 4,000,000). Significance 0.001, Šidák over the two.
#[test]
fn the_tilted_coat_samples_only_where_its_pdf_is() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    let alpha = 1.0 - 0.999f64.powf(1.0 / 2.0);
    for microfacet in [Microfacet::GgxWalter, Microfacet::Ggx] {
        let case =
            Sampler::Dielectric { microfacet, kind: Dielectric::CoatTilted, alpha: 0.5, theta_degrees: 60.0 };
        let (p, chi2, dof, mass) = chi_square(&gpu, &kernel, case, Numbers::Fresh, 1.0, 10 * SAMPLES);
        eprintln!("{case:?}: chi2 {chi2:.1}, dof {dof}, p {p:.3e}, pdf mass {mass:.4}");
        assert!(p >= alpha, "{case:?}: p = {p} < {alpha}");
    }
}

/// The dielectric samples every direction it scatters light into: wherever `bsdf_eval` is above
/// 0, so is `bsdf_pdf` (the share of f |cos| over directions of pdf 0 is below 10⁻⁵ of the
/// albedo, the grid's rounding at the support's edges). Leaving glass beyond the critical angle,
/// the Fresnel at the normal is 1, yet microfacets tilted towards wo still refract: a lobe choice
/// by that Fresnel alone never sampled them (at α 0.1, 37 % of the albedo at 45°, 5 % at 60°), so
/// paths out through a rough sphere's rim lost that light to everything next-event estimation
/// does not find. Entering, leaving and thin-walled glass, either GGX sampling, α 0.1 and 0.5, wo at 30°,
/// 45°, 60° and 80°.
#[test]
fn the_dielectric_samples_wherever_it_scatters() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    // A grid uniform in (cos θ, φ) over the sphere: each point stands for 2 · 2π / n steradians.
    let (rows, columns) = (512usize, 1024usize);
    let mut dirs = Vec::with_capacity(rows * columns);
    for t in 0..rows {
        let z = -1.0 + 2.0 * (t as f32 + 0.5) / rows as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for p in 0..columns {
            let phi = std::f32::consts::TAU * (p as f32 + 0.5) / columns as f32;
            dirs.push([r * phi.cos(), r * phi.sin(), z, 0.0]);
        }
    }
    let solid_angle = 2.0 * std::f64::consts::TAU / (rows * columns) as f64;
    let mut failures = Vec::new();
    for microfacet in [Microfacet::Ggx, Microfacet::GgxWalter] {
        for kind in [
            Dielectric::Entering,
            Dielectric::Leaving,
            Dielectric::Thin,
            Dielectric::Coated,
            Dielectric::Sheened,
            Dielectric::CoatTilted,
        ] {
            for alpha in [0.1, 0.5] {
                for theta_degrees in [30.0, 45.0, 60.0, 80.0] {
                    let case = Sampler::Dielectric { microfacet, kind, alpha, theta_degrees };
                    let values = kernel.run(&gpu, case, 1.0, 3, &dirs, dirs.len() as u32);
                    let (mut albedo, mut unsampled) = (0.0f64, 0.0f64);
                    for (d, v) in dirs.iter().zip(&values) {
                        let f_cos = v[0] as f64 * (d[2] as f64).abs() * solid_angle;
                        albedo += f_cos;
                        if v[3] <= 0.0 {
                            unsampled += f_cos;
                        }
                    }
                    eprintln!("{case:?}: albedo {albedo:.4}, of it never sampled {unsampled:.2e}");
                    if unsampled > 1e-5 * albedo.max(1e-3) {
                        failures
                            .push(format!("{case:?}: {unsampled:.3e} of albedo {albedo:.4} never sampled"));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The test has power: sampling but reporting the pdf of a 10 % larger alpha is rejected, for
/// each microfacet sampling, for the dielectric with either GGX sampling and for an anisotropic
/// metal.
#[test]
fn a_wrong_pdf_is_rejected() {
    let gpu = Gpu::new();
    let kernel = Kernel::new(&gpu);
    let alpha = 1.0 - 0.99f64.powf(1.0 / cases().len() as f64);
    for case in [
        Sampler::Cone { one_minus_cos: 0.5 },
        Sampler::Microfacet { microfacet: Microfacet::Ggx, alpha: 0.5, theta_degrees: 30.0 },
        Sampler::Microfacet { microfacet: Microfacet::GgxWalter, alpha: 0.5, theta_degrees: 30.0 },
        Sampler::Microfacet { microfacet: Microfacet::Beckmann, alpha: 0.2, theta_degrees: 60.0 },
        Sampler::Dielectric {
            microfacet: Microfacet::Ggx,
            kind: Dielectric::Entering,
            alpha: 0.5,
            theta_degrees: 30.0,
        },
        Sampler::Dielectric {
            microfacet: Microfacet::GgxWalter,
            kind: Dielectric::Entering,
            alpha: 0.5,
            theta_degrees: 30.0,
        },
        Sampler::Anisotropic {
            alpha: 0.2,
            strength: 0.8,
            metallic: 1.0,
            direction_degrees: 30.0,
            theta_degrees: 30.0,
        },
    ] {
        let (p, chi2, dof, _) = chi_square(&gpu, &kernel, case, Numbers::Fresh, 1.1, SAMPLES);
        eprintln!("wrong pdf {case:?}: chi2 {chi2:.1}, dof {dof}, p {p:.2e}");
        assert!(p < alpha, "{case:?}: a 10 % wrong alpha in the pdf was not rejected (p = {p})");
    }
}

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

// ---------------------------------------------------------------------------------------------
// Light sampling: the environment map and the emissive triangles, through
// `spirv/light_sample_test.comp` (the renderer's environment.glsl and shading.glsl).
/// The light-sampling cases (environment, light pick, point on a triangle, emissive solid angle
/// with fresh and with reused numbers, by area and by solid angle, next to two huge emitters,
/// and the irradiance by area against by solid angle) form their own family: significance 0.01
/// with a Šidák correction over these twelve.
fn light_alpha() -> f64 {
    1.0 - 0.99f64.powf(1.0 / 12.0)
}

/// An emissive triangle of a light test scene: its corners and its radiance.
type LightTriangle = ([[f32; 3]; 3], f32);

/// The emissive triangles of the light test scene, as seen from the shading point at the origin
/// (normal +Y): five triangles of different sizes, orientations and radiances, none hiding
/// another, each facing the origin. Light sampling draws the points of the first, which subtends
/// 0.3 sr there, by solid angle, those of the others (0.015 to 0.06 sr, and a small far one under
/// 1e-4 sr) by area (`emissive_point`).
const LIGHT_TRIANGLES: [LightTriangle; 5] = [
    ([[-0.3, 1.5, -0.8], [-1.05, 1.5, 0.8], [-1.8, 1.5, -0.8]], 1.0),
    ([[0.6, 1.0, -0.8], [0.9, 1.0, -0.8], [0.75, 1.0, -0.5]], 20.0),
    ([[0.0, 2.0, 0.8], [0.8, 2.2, 0.8], [0.4, 1.6, 1.4]], 5.0),
    ([[1.2, 0.6, 0.6], [1.6, 0.9, 0.3], [1.5, 0.3, 1.0]], 3.0),
    ([[-1.02, 2.0, -1.62], [-0.99, 2.0, -1.62], [-1.0, 2.02, -1.58]], 2000.0),
];

fn light_scene() -> umbra::scene::Scene {
    scene_of_lights(&LIGHT_TRIANGLES)
}

/// A scene of emissive triangles (corners, radiance), each wound to face the origin.
fn scene_of_lights(lights: &[LightTriangle]) -> umbra::scene::Scene {
    let mut scene = umbra::scene::Scene { name: "light test".into(), ..Default::default() };
    for (i, (corners, radiance)) in lights.iter().enumerate() {
        let [a, b, c] = corners.map(Vec3::from);
        // Wind every triangle to face the origin.
        let n = (b - a).cross(c - a).normalize();
        let (b, c) = if n.dot(-(a + b + c) / 3.0) > 0.0 { (b, c) } else { (c, b) };
        let n = (b - a).cross(c - a).normalize();
        let base = scene.positions.len() as u32;
        for v in [a, b, c] {
            scene.positions.push(v.into());
            scene.normals.push(n.into());
        }
        scene.triangles.push([base, base + 1, base + 2]);
        scene.triangle_material.push(i as u32);
        scene.materials.push(umbra::scene::Material { emissive: [*radiance; 3], ..Default::default() });
    }
    scene.update_emissive();
    scene
}

/// One light-test dispatch's settings.
#[derive(Clone, Copy)]
struct LightRun {
    mode: u32,
    variant: u32,
    count: u32,
}

struct LightKernel {
    pipeline: Pipeline<light_sample_test::Kernel>,
    scene: umbra::gpu::scene::GpuScene,
    arrays: umbra::gpu::scene::SceneArrays,
}

impl LightKernel {
    fn new(gpu: &Gpu, env: Option<&umbra::environment::EnvironmentMap>) -> Self {
        Self::with_scene(gpu, env, &light_scene(), EmitterSampling::Area)
    }

    fn with_scene(
        gpu: &Gpu,
        env: Option<&umbra::environment::EnvironmentMap>,
        lights: &umbra::scene::Scene,
        emitters: EmitterSampling,
    ) -> Self {
        let arrays = umbra::gpu::scene::SceneArrays::new(lights).unwrap();
        let mut scene = umbra::gpu::scene::GpuScene::from_arrays(gpu, &arrays).unwrap();
        if let Some(env) = env {
            scene.set_environment(gpu, env).unwrap();
        }
        let spec = light_sample_test::Spec { solid_angle_emitters: emitters == EmitterSampling::SolidAngle };
        let pipeline = Pipeline::for_scene(gpu, &scene, &spec).unwrap();
        Self { pipeline, scene, arrays }
    }

    fn run(&self, gpu: &Gpu, run: LightRun, dirs: &[[f32; 4]]) -> Vec<[f32; 4]> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
        let input = Buffer::upload(
            gpu,
            "light test directions",
            if dirs.is_empty() { &[[0.0f32; 4]] } else { dirs },
            usage,
        )
        .unwrap();
        let output =
            Buffer::new(gpu, "light test results", run.count as u64 * 16, usage, MemoryLocation::GpuOnly)
                .unwrap();
        let (w, h) = self.scene.env_size.unwrap_or((1, 1));
        let params = LightTestParams {
            point: [0.0; 3],
            normal: [0.0, 1.0, 0.0],
            mode: run.mode,
            count: run.count,
            seed: 4242,
            variant: run.variant,
            env_size: [w, h],
            light_count: self.scene.light_count,
            ..Default::default()
        };
        gpu.submit(|cmd| {
            let resources =
                light_sample_test::Resources { scene: &self.scene, directions: &input, results: &output };
            self.pipeline.record(cmd, &resources, &params, [run.count, 1, 1], [64, 1, 1])
        })
        .unwrap();
        output.read(gpu).unwrap()
    }
}

/// `env_uv` of environment.glsl, in f64.
fn env_uv(d: [f32; 4]) -> (f64, f64) {
    let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
    let u = x.atan2(-z) / std::f64::consts::TAU + 0.5;
    let v = y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
    (u, v)
}

/// Chi-square of `env_sample` against `env_pdf` (or a deliberately wrong pdf, `variant` 1) on
/// `map`. Cells are the texels split 2 × 2 in (u, v): the sampled density is constant over a
/// texel in (u, v), and env_pdf × the Jacobian 2π² sin θ is constant there too, so the
/// quadrature below is exact for the true pdf whatever its points. Returns (p, chi2, dof, mass).
fn env_chi_square(
    gpu: &Gpu,
    kernel: &LightKernel,
    map: &umbra::environment::EnvironmentMap,
    variant: u32,
    samples: u32,
) -> (f64, f64, usize, f64) {
    const SPLIT: usize = 2; // cells per texel side
    const QUAD: usize = 2; // quadrature points per cell side
    let (cw, ch) = (map.width * SPLIT, map.height * SPLIT);
    let cell = |d: [f32; 4]| {
        let (u, v) = env_uv(d);
        let x = ((u * cw as f64) as usize).min(cw - 1);
        let y = ((v * ch as f64) as usize).min(ch - 1);
        y * cw + x
    };
    let drawn = kernel.run(gpu, LightRun { mode: 0, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; cw * ch];
    for d in &drawn {
        assert!(d[3].is_finite() && d[3] > 0.0, "env_sample gave {d:?}");
        observed[cell(*d)] += 1.0;
    }
    // Quadrature points at the centres of QUAD × QUAD sub-cells of every cell.
    let (qw, qh) = (cw * QUAD, ch * QUAD);
    let mut points = Vec::with_capacity(qw * qh);
    let mut jacobian = Vec::with_capacity(qw * qh);
    for y in 0..qh {
        let theta = std::f64::consts::PI * (y as f64 + 0.5) / qh as f64;
        for x in 0..qw {
            let phi = (((x as f64 + 0.5) / qw as f64) - 0.5) * std::f64::consts::TAU;
            let s = theta.sin();
            points.push([(s * phi.sin()) as f32, theta.cos() as f32, (-s * phi.cos()) as f32, 0.0]);
            jacobian.push(2.0 * std::f64::consts::PI * std::f64::consts::PI * s / (qw * qh) as f64);
        }
    }
    let pdfs = kernel.run(gpu, LightRun { mode: 1, variant, count: points.len() as u32 }, &points);
    let mut expected = vec![0.0f64; cw * ch];
    for (i, p) in pdfs.iter().enumerate() {
        let (x, y) = (i % qw / QUAD, i / qw / QUAD);
        expected[y * cw + x] += p[3] as f64 * jacobian[i];
    }
    let mass = expected.iter().sum();
    let n = samples as f64;
    if std::env::var("UMBRA_CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, n);
    }
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, n);
    (p, chi2, dof, mass)
}

/// Environment importance sampling on a real HDR sky (tests/reference/sky-128x64.exr, a
/// downsampled Poly Haven sunrise whose sun peaks near 2,100): the directions `env_sample` draws
/// follow `env_pdf`, and a pdf that forgets the sin θ of the (u, v) → sphere Jacobian is rejected.
#[test]
fn environment_sampling_on_a_real_hdr() {
    let gpu = Gpu::new();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(&path).unwrap();
    let peak = map.texels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    assert!(peak > 1000.0, "the test map should have a sun above 1000 (peak {peak})");
    let kernel = LightKernel::new(&gpu, Some(&map));
    let alpha = light_alpha();
    let (p, chi2, dof, mass) = env_chi_square(&gpu, &kernel, &map, 0, 1 << 20);
    eprintln!("env_sample vs env_pdf: chi2 {chi2:.1}, dof {dof}, p {p:.4}, pdf mass {mass:.6}");
    assert!((mass - 1.0).abs() < 1e-4, "env_pdf integrates to {mass}");
    assert!(p >= alpha, "env_sample does not follow env_pdf: p = {p} < {alpha}");
    let (p, chi2, dof, mass) = env_chi_square(&gpu, &kernel, &map, 1, 1 << 20);
    eprintln!("env_sample vs a pdf without 1/sin θ: chi2 {chi2:.1}, dof {dof}, p {p:.2e}, mass {mass:.4}");
    assert!(p < alpha, "a pdf without 1/sin θ was not rejected (p = {p})");
}

/// Cell of barycentrics (b1, b2) among the K² congruent sub-triangles of a triangle split by
/// lines parallel to its edges (equal areas; the split is the same whatever the vertex order).
/// Cells are numbered (i K + j) 2 + upper; half of the 2K² numbers are unused.
fn sub_triangle(b1: f64, b2: f64, k: usize) -> usize {
    let (x, y) = (b1.clamp(0.0, 1.0) * k as f64, b2.clamp(0.0, 1.0) * k as f64);
    let (mut i, mut j) = ((x as usize).min(k - 1), (y as usize).min(k - 1));
    while i + j > k - 1 {
        if i > j {
            i -= 1;
        } else {
            j -= 1;
        }
    }
    let upper = i + j < k - 1 && (x - i as f64) + (y - j as f64) > 1.0;
    (i * k + j) * 2 + upper as usize
}

/// The centroid (b1, b2) of sub-triangle `cell` (as [`sub_triangle`] numbers them), if used.
fn sub_triangle_centroid(cell: usize, k: usize) -> Option<(f64, f64)> {
    let (i, j, upper) = (cell / 2 / k, cell / 2 % k, cell % 2 == 1);
    let offset = if upper { 2.0 / 3.0 } else { 1.0 / 3.0 };
    let valid = if upper { i + j + 1 < k } else { i + j < k };
    valid.then(|| ((i as f64 + offset) / k as f64, (j as f64 + offset) / k as f64))
}

/// The solid angle of the spherical triangle with unit corners a, b, c (Van Oosterom and
/// Strackee, as `spherical_triangle_area` in spirv/include/sampling.glsl), in f64.
fn solid_angle(a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> f64 {
    (2.0 * a.dot(b.cross(c)).atan2(1.0 + a.dot(b) + a.dot(c) + b.dot(c))).abs()
}

/// The corners (b1, b2) of sub-triangle `cell` (as [`sub_triangle`] numbers them; a used one).
fn sub_triangle_corners(cell: usize, k: usize) -> [(f64, f64); 3] {
    let (i, j, upper) = ((cell / 2 / k) as f64, (cell / 2 % k) as f64, cell % 2 == 1);
    let k = k as f64;
    if upper {
        [((i + 1.0) / k, (j + 1.0) / k), (i / k, (j + 1.0) / k), ((i + 1.0) / k, j / k)]
    } else {
        [(i / k, j / k), ((i + 1.0) / k, j / k), (i / k, (j + 1.0) / k)]
    }
}

/// The nearest of a light scene's triangles a ray from the origin along `d` hits: (scene
/// triangle, b1, b2), Möller–Trumbore in f64.
fn hit_light(scene: &umbra::scene::Scene, d: [f64; 3]) -> Option<(usize, f64, f64)> {
    let d = glam::DVec3::from(d);
    let mut best: Option<(f64, usize, f64, f64)> = None;
    for (t, tri) in scene.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| Vec3::from(scene.positions[v as usize]).as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let pv = d.cross(e2);
        let det = e1.dot(pv);
        if det.abs() < 1e-12 {
            continue;
        }
        let tv = -a;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = d.dot(qv) / det;
        let dist = e2.dot(qv) / det;
        let eps = 1e-6;
        if u >= -eps && v >= -eps && u + v <= 1.0 + eps && dist > 0.0 && best.is_none_or(|b| dist < b.0) {
            best = Some((dist, t, u, v));
        }
    }
    best.map(|(_, t, u, v)| (t, u, v))
}

/// The emissive-triangle pick (`pick_light`) follows the table's pmf, and that pmf is each
/// triangle's share of the emitted power (radiance × area × π), the same in the lights table and
/// in the triangles the path tracer's MIS reads.
#[test]
fn light_pick_follows_the_power_pmf() {
    let gpu = Gpu::new();
    let kernel = LightKernel::new(&gpu, None);
    let lights = &kernel.arrays.lights;
    assert_eq!(lights.len(), LIGHT_TRIANGLES.len());
    let power: Vec<f64> = LIGHT_TRIANGLES
        .iter()
        .map(|(c, l)| {
            let [a, b, c] = c.map(|v| Vec3::from(v).as_dvec3());
            *l as f64 * 0.5 * (b - a).cross(c - a).length() * std::f64::consts::PI
        })
        .collect();
    let total: f64 = power.iter().sum();
    let scene = light_scene();
    for (k, light) in lights.iter().enumerate() {
        // BVH order to scene order: find the scene triangle with the same area and pmf.
        let tri = &kernel.arrays.triangles[light.tri as usize];
        assert_eq!(tri.light_pmf, light.pmf, "entry {k}: the MIS pmf differs from the pick pmf");
        let entry = scene.emissive.triangles.iter().position(|&t| {
            let share = power[t as usize] / total;
            (share - light.pmf as f64).abs() < 1e-6 && (tri.area - light.area).abs() < 1e-6
        });
        assert!(entry.is_some(), "entry {k} ({light:?}) matches no triangle's power share");
    }
    let samples = 1u32 << 18;
    let drawn = kernel.run(&gpu, LightRun { mode: 2, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; lights.len()];
    for d in &drawn {
        let k = d[0] as usize;
        assert_eq!(d[1], lights[k].pmf);
        observed[k] += 1.0;
    }
    let expected: Vec<f64> = lights.iter().map(|l| l.pmf as f64).collect();
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    eprintln!("pick_light: observed {observed:?}, pmf {expected:?}: chi2 {chi2:.2}, dof {dof}, p {p:.4}");
    assert!(p >= light_alpha(), "pick_light does not follow the pmf: p = {p}");
}

/// `sample_triangle` is uniform: chi-square over the 256 congruent sub-triangles of a 16-way split.
#[test]
fn triangle_sampling_is_uniform() {
    const K: usize = 16;
    let gpu = Gpu::new();
    let kernel = LightKernel::new(&gpu, None);
    let samples = 1u32 << 18;
    let drawn = kernel.run(&gpu, LightRun { mode: 3, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; 2 * K * K];
    for d in &drawn {
        assert!(d[0] >= 0.0 && d[1] >= 0.0 && d[0] + d[1] <= 1.0 + 1e-6, "barycentrics {d:?}");
        observed[sub_triangle(d[0] as f64, d[1] as f64, K)] += 1.0;
    }
    let expected: Vec<f64> = (0..2 * K * K)
        .map(|c| if sub_triangle_centroid(c, K).is_some() { 1.0 / (K * K) as f64 } else { 0.0 })
        .collect();
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    eprintln!("sample_triangle: chi2 {chi2:.1}, dof {dof}, p {p:.4}");
    assert!(p >= light_alpha(), "sample_triangle is not uniform: p = {p}");
}

/// Chi-square of the directions `sample_emissive` draws from the origin against the solid-angle
/// light pdf the path tracer's MIS gives a BSDF ray in the same direction (`variant` 1: a
/// deliberately wrong one). Cells: each light's K² sub-triangles, seen from the origin; a sample
/// is binned by tracing its direction to the lights (f64, on the CPU). The expected count is
/// ∫ pdf dω over the cell: the pdf at the cell's centroid times the cell's exact solid angle (exact
/// where the pdf is constant in solid angle, as where a light is sampled by solid angle; where it
/// is sampled by area, the pdf varies as r² / cos across a cell, which for these far, small lights
/// is within 1e-3 of constant). Returns (p, chi2, dof, mass, the largest
/// relative difference between a sample's pdf and the MIS pdf in its direction, the fraction of
/// samples whose direction the MIS ray misses).
fn emissive_chi_square(
    gpu: &Gpu,
    kernel: &LightKernel,
    scene: &umbra::scene::Scene,
    numbers: Numbers,
    variant: u32,
) -> (f64, f64, usize, f64, f64, f64) {
    const K: usize = 8;
    let lights = scene.triangles.len();
    let samples = 1u32 << 19;
    let mode = if numbers == Numbers::Reused { 6 } else { 4 };
    let drawn = kernel.run(gpu, LightRun { mode, variant: 0, count: samples }, &[]);
    let mut observed = vec![0.0f64; lights * 2 * K * K];
    for d in &drawn {
        assert!(d[3].is_finite() && d[3] > 0.0, "sample_emissive failed or gave a bad pdf: {d:?}");
        let dir = [d[0] as f64, d[1] as f64, d[2] as f64];
        let Some((t, b1, b2)) = hit_light(scene, dir) else {
            panic!("sample_emissive gave {d:?}, which points at no light");
        };
        observed[t * 2 * K * K + sub_triangle(b1, b2, K)] += 1.0;
    }
    // The NEE pdf of each sample against the MIS pdf of its direction.
    let check: Vec<[f32; 4]> = drawn.iter().take(1 << 15).map(|d| [d[0], d[1], d[2], 0.0]).collect();
    let mis = kernel.run(gpu, LightRun { mode: 5, variant, count: check.len() as u32 }, &check);
    // A direction through a light's very edge may miss it when traced back (f32 rounding): those
    // are counted apart; every other sample must agree.
    let misses = mis.iter().filter(|m| m[3] == 0.0).count() as f64 / mis.len() as f64;
    let mismatch = drawn
        .iter()
        .zip(&mis)
        .filter(|(_, b)| b[3] > 0.0)
        .map(|(a, b)| ((a[3] - b[3]) / a[3]).abs() as f64)
        .fold(0.0, f64::max);
    // Expected: the MIS pdf at each cell's centroid times the cell's solid angle.
    let mut points = Vec::new();
    let mut solid_angles = Vec::new();
    let mut cells = Vec::new();
    for (t, tri) in scene.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| Vec3::from(scene.positions[v as usize]).as_dvec3());
        for cell in 0..2 * K * K {
            if let Some((b1, b2)) = sub_triangle_centroid(cell, K) {
                let w = ((1.0 - b1 - b2) * a + b1 * b + b2 * c).normalize();
                points.push([w.x as f32, w.y as f32, w.z as f32, 0.0]);
                let [ca, cb, cc] = sub_triangle_corners(cell, K)
                    .map(|(u, v)| ((1.0 - u - v) * a + u * b + v * c).normalize());
                solid_angles.push(solid_angle(ca, cb, cc));
                cells.push(t * 2 * K * K + cell);
            }
        }
    }
    let pdfs = kernel.run(gpu, LightRun { mode: 5, variant, count: points.len() as u32 }, &points);
    let mut expected = vec![0.0f64; observed.len()];
    for ((p, omega), &cell) in pdfs.iter().zip(&solid_angles).zip(&cells) {
        expected[cell] += p[3] as f64 * omega;
    }
    let mass = expected.iter().sum();
    if std::env::var("UMBRA_CHI2_DEBUG").is_ok() {
        print_worst_cells(&observed, &expected, samples as f64);
    }
    let (p, chi2, dof) = pooled_chi_square(&observed, &expected, samples as f64);
    (p, chi2, dof, mass, mismatch, misses)
}

/// [`emissive_chi_square`] with fresh and with reused numbers (`what` names the case): the MIS
/// light pdf integrates to 1 over the lights, agrees with each sample's NEE pdf, is found again
/// by tracing the sample's direction, and the directions follow it at [`light_alpha`].
fn assert_emissive_follows_the_mis_pdf(
    gpu: &Gpu,
    kernel: &LightKernel,
    scene: &umbra::scene::Scene,
    what: &str,
) {
    let alpha = light_alpha();
    for numbers in [Numbers::Fresh, Numbers::Reused] {
        let (p, chi2, dof, mass, mismatch, misses) = emissive_chi_square(gpu, kernel, scene, numbers, 0);
        eprintln!(
            "sample_emissive ({what}, {numbers:?} numbers) vs MIS pdf: chi2 {chi2:.1}, dof {dof}, p {p:.4}, \
             mass {mass:.6}, largest NEE/MIS pdf difference {mismatch:.2e}, MIS rays missing the light {misses:.1e}"
        );
        assert!((mass - 1.0).abs() < 1e-3, "{what}: the MIS light pdf integrates to {mass}");
        assert!(mismatch < 1e-3, "{what}: NEE and MIS disagree on a sample's pdf by {mismatch}");
        assert!(misses < 1e-3, "{what}: {misses} of the NEE directions miss their light when traced");
        assert!(
            p >= alpha,
            "sample_emissive ({what}, {numbers:?} numbers) does not follow the MIS light pdf: p = {p} < {alpha}"
        );
    }
}

/// Next-event estimation on emissive triangles (`sample_emissive`: pick by power, then a point
/// uniform in the triangle's solid angle, pdf pmf / Ω, or for those that subtend less uniform
/// on its area, pdf pmf / area × r² / cos) draws directions with the density the path tracer's MIS
/// assigns them (`emissive_pdf` at a BSDF ray's hit), with fresh numbers and with sample reuse
/// (the triangle picked by u.y, its share stretched back as the point's first number: a stretch
/// off the triangle's interval of the CDF makes the points non-uniform on it, which the
/// sub-triangle cells see). Rejected: a MIS pdf that forgets the cosine at the light, and one that
/// gives the area-sampling density where the points are drawn by solid angle (the sub-triangles
/// then see the r² and cosine area sampling has and solid-angle sampling has not).
#[test]
fn emissive_sampling_matches_the_mis_light_pdf() {
    // Each triangle clearly in its regime (`emissive_solid_angle`, spirv/include/shading.glsl: by
    // solid angle where both its area over its first corner's squared distance and its solid
    // angle reach SPHERICAL_MIN, 0.2 sr): light 0 by solid angle, the others by area.
    const SPHERICAL_MIN: f64 = 0.2;
    for (k, (corners, _)) in LIGHT_TRIANGLES.iter().enumerate() {
        let v = corners.map(|v| Vec3::from(v).as_dvec3());
        let [a, b, c] = v.map(|v| v.normalize());
        let omega = solid_angle(a, b, c);
        let near = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length() / v[0].length_squared();
        let clear = |x: f64| !(SPHERICAL_MIN / 1.2..SPHERICAL_MIN * 1.2).contains(&x);
        let by_solid_angle = near >= SPHERICAL_MIN && omega >= SPHERICAL_MIN;
        assert!(
            by_solid_angle == (k == 0) && clear(omega) && clear(near),
            "light {k} (solid angle {omega}, area over distance² {near}) is not clearly in its regime"
        );
    }
    let gpu = Gpu::new();
    let scene = light_scene();
    let alpha = light_alpha();
    for emitters in EmitterSampling::ALL {
        let kernel = LightKernel::with_scene(&gpu, None, &scene, emitters);
        assert_emissive_follows_the_mis_pdf(&gpu, &kernel, &scene, &format!("{emitters:?}"));
        let mut wrong = vec![(1, "without the light's cosine")];
        if emitters == EmitterSampling::SolidAngle {
            wrong.push((2, "by area where sampled by solid angle"));
        }
        for (variant, wrong) in wrong {
            let (p, chi2, dof, mass, ..) =
                emissive_chi_square(&gpu, &kernel, &scene, Numbers::Fresh, variant);
            eprintln!(
                "sample_emissive ({emitters:?}) vs a MIS pdf {wrong}: chi2 {chi2:.1}, dof {dof}, p {p:.2e}, mass {mass:.4}"
            );
            assert!(p < alpha, "a MIS pdf {wrong} was not rejected (p = {p})");
        }
    }
}

/// A triangle 0.1 above the origin, subtending 5.6 sr there: area sampling's failure case.
const HUGE_EMITTER: LightTriangle = ([[-1.0, 0.1, -1.0], [1.5, 0.1, -0.5], [-0.5, 0.1, 1.5]], 1.0);

/// Light sampling next to a huge emitter (the failure case of area sampling: its 1/r² and cosine
/// swing across the triangle), from the origin (normal +Y): a triangle 0.1 above it, subtending
/// 5.6 sr; and one standing on the origin's horizon (as the light of Khronos' CornellBox-Original
/// stands on its floor), 0.3 sr. Their points are drawn by solid angle; the directions follow the
/// MIS light pdf as the far lights' do, and the area-sampling density is rejected.
#[test]
fn emissive_sampling_next_to_a_huge_emitter() {
    let scenes: [&[LightTriangle]; 2] =
        [&[HUGE_EMITTER], &[([[-0.3, 0.002, -0.2], [-0.3, 0.8, -0.6], [-0.3, 0.002, -1.0]], 4.0)]];
    let gpu = Gpu::new();
    let alpha = light_alpha();
    for lights in scenes {
        let scene = scene_of_lights(lights);
        let kernel = LightKernel::with_scene(&gpu, None, &scene, EmitterSampling::SolidAngle);
        assert_emissive_follows_the_mis_pdf(&gpu, &kernel, &scene, "by a huge emitter");
        let (p, ..) = emissive_chi_square(&gpu, &kernel, &scene, Numbers::Fresh, 2);
        assert!(
            p < alpha,
            "a MIS pdf by area where sampled by solid angle was not rejected by a huge emitter (p = {p})"
        );
    }
}

/// What solid-angle sampling buys next to a huge emitter: the irradiance at the origin (normal +Y)
/// from a triangle 0.1 above it, estimated per sample as L cos θ / pdf. Both ways estimate the
/// same irradiance (a z-test at the light family's significance), and by area the estimates'
/// relative standard deviation is over three times that by solid angle, whose estimates vary
/// only with cos θ (measured: 5.6 and 0.47).
#[test]
fn solid_angle_sampling_quiets_a_huge_emitter() {
    let gpu = Gpu::new();
    let scene = scene_of_lights(&[HUGE_EMITTER]);
    let samples = 1u32 << 19;
    let moments = EmitterSampling::ALL.map(|emitters| {
        let kernel = LightKernel::with_scene(&gpu, None, &scene, emitters);
        let drawn = kernel.run(&gpu, LightRun { mode: 4, variant: 0, count: samples }, &[]);
        let estimates: Vec<f64> =
            drawn.iter().map(|d| if d[3] > 0.0 { d[1] as f64 / d[3] as f64 } else { 0.0 }).collect();
        let n = estimates.len() as f64;
        let mean = estimates.iter().sum::<f64>() / n;
        let var = estimates.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / (n - 1.0);
        (mean, var, n)
    });
    let [(mean_a, var_a, n_a), (mean_s, var_s, n_s)] = moments;
    let (rel_a, rel_s) = (var_a.sqrt() / mean_a, var_s.sqrt() / mean_s);
    let z = (mean_a - mean_s) / (var_a / n_a + var_s / n_s).sqrt();
    eprintln!(
        "irradiance under a huge emitter: by area {mean_a:.5} (rel. std {rel_a:.3}), by solid angle {mean_s:.5} \
         (rel. std {rel_s:.3}), z {z:.2}"
    );
    // Two-sided normal p-value: P(|Z| > |z|) = erfc(|z| / √2) = Q(1/2, z² / 2).
    let p = gamma_q(0.5, z * z / 2.0);
    assert!(p >= light_alpha(), "the two ways estimate different irradiances: z = {z}, p = {p}");
    assert!(
        rel_a > 3.0 * rel_s,
        "solid-angle sampling is not quieter next to a huge emitter: {rel_s} vs {rel_a}"
    );
}
