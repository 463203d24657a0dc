//! The direction samplers' test kernel (`spirv/sample_test.comp`) and the chi-square of a
//! sampler's directions against its pdf.

use crate::common::Gpu;
use crate::{pooled_chi_square, print_worst_cells, Numbers};
use glam::Vec3;
use umbra::gpu::kernels::sample_test;
use umbra::gpu::layout::SampleTestParams;
use umbra::gpu::Pipeline;
use umbra::passes::pathtrace::Microfacet;
use umbra::vk::{raw, Buffer, MemoryLocation};

const THETA_CELLS: usize = 16; // in cos θ over [−1, 1]
const PHI_CELLS: usize = 32;
const SUB: usize = 64; // pdf evaluations per cell side
pub(crate) const SAMPLES: u32 = 400_000;
/// The cap around wi = −wo integrated in polar coordinates for half-vector sampling from
/// D(h) cos θh (see `chi_square`):
/// radius (radians; the grid spacing is about 0.003), rings and spokes.
const CAP_RADIUS: f64 = 0.1;
const CAP_RINGS: usize = 512;
const CAP_SPOKES: usize = 4000;

#[derive(Clone, Copy, Debug)]
pub(crate) enum Sampler {
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
pub(crate) enum Dielectric {
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
pub(crate) struct Kernel([Pipeline<sample_test::Kernel>; 3], Vec<f32>);

impl Kernel {
    pub(crate) fn new(gpu: &Gpu) -> Self {
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
    pub(crate) fn run(
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
    pub(crate) fn dispatch(
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
        gpu.record(|rec| {
            let resources = sample_test::Resources { directions: &input, results: &output };
            pipeline.record(rec, &resources, params, [count, 1, 1])
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

/// The chi-square p-value of `sampler`'s samples (drawn with `numbers`) against its (possibly
/// deliberately wrong) pdf, and the pdf's total mass over the sphere.
pub(crate) fn chi_square(
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
