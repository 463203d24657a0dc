//! The progressive path-tracing pass (`spirv/pathtrace.comp`): one sample per pixel per
//! dispatch into a running mean and second moment.

pub use super::wavefront::Integrator;
use super::wavefront::WaveState;
use crate::error::{Error, Result};
use crate::gpu::cache::Cache;
use crate::gpu::kernels::{pathtrace, resolve};
use crate::gpu::layout::{GpuCamera, GpuPathReservoir, PathParams, PathStats, ResolveParams};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, MemoryLocation, Recorder};

/// The microfacet distribution of the specular lobes, and how their half vectors are sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Microfacet {
    /// GGX (the glTF specification) with visible-normal sampling (Heitz 2018).
    #[default]
    Ggx,
    /// The same GGX BSDF with Walter et al. 2007's sampling: noisier, the same mean.
    ///
    /// Half vectors from D(h) cos θh, blind to the outgoing direction (for reflection and
    /// transmission alike), so some face away from it and are discarded. Noisier than
    /// [`Microfacet::Ggx`]; the same mean.
    GgxWalter,
    /// Beckmann with Walter et al.'s half-vector sampling.
    Beckmann,
}

impl Microfacet {
    /// Every value, for tests and benchmarks that try each.
    pub const ALL: [Microfacet; 3] = [Microfacet::Ggx, Microfacet::GgxWalter, Microfacet::Beckmann];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Microfacet::Ggx => "ggx",
            Microfacet::GgxWalter => "ggx-walter",
            Microfacet::Beckmann => "beckmann",
        }
    }
}

/// How light sampling and BSDF sampling are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Heuristic {
    /// Veach's power heuristic (β = 2).
    #[default]
    Power,
    /// The balance heuristic.
    Balance,
    /// Deliberately biased, for tests that must catch it: emission found by BSDF sampling
    /// counts without its MIS weight (light sampling keeps its power-heuristic weight).
    #[cfg(feature = "testing")]
    #[doc(hidden)]
    #[cfg_attr(feature = "cli", value(skip))]
    UnweightedBsdfHits,
}

impl Heuristic {
    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Heuristic::Power => "power",
            Heuristic::Balance => "balance",
            #[cfg(feature = "testing")]
            Heuristic::UnweightedBsdfHits => "unweighted-bsdf-hits",
        }
    }
}

/// Which sampling strategies find the emitters (emissive triangles and the environment map). Each
/// is unbiased on its own; they differ in noise (BENCHMARKS.md and docs/history/2026-12-05.md, "The
/// estimators side by side").
///
/// Under every strategy, punctual lights (delta lights, which no ray can hit) are found by light
/// sampling alone, and emission that light sampling cannot find (a constant environment, the
/// environment map with [`PathSettings::env_nee`] off) by BSDF sampling alone. Camera rays see
/// emitters directly under every strategy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Strategy {
    /// Light sampling (next-event estimation) and BSDF sampling, weighted by multiple importance
    /// sampling.
    ///
    /// The weights are the [`Heuristic`]'s.
    #[default]
    Mis,
    /// BSDF sampling alone: emission counts where a BSDF-sampled ray hits it; no next-event
    /// estimation but for punctual lights. The heuristic is not used.
    Bsdf,
    /// Light sampling alone: next-event estimation; emission that a BSDF-sampled ray hits is not
    /// counted (where light sampling could have found it). The heuristic is not used.
    Light,
}

impl Strategy {
    /// Every value, for tests and benchmarks that try each.
    pub const ALL: [Strategy; 3] = [Strategy::Mis, Strategy::Bsdf, Strategy::Light];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Mis => "mis",
            Strategy::Bsdf => "bsdf",
            Strategy::Light => "light",
        }
    }

    /// The kernel's (`light_sampling`, `bsdf_hits`): which strategies run.
    pub(super) fn spec(self) -> (bool, bool) {
        (self != Strategy::Bsdf, self != Strategy::Light)
    }
}

/// How the path tracer samples the direct light of the emissive triangles and punctual lights
/// at a path's scattering vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DirectSampling {
    /// As at every vertex: one emissive sample by power (a uniform point on the triangle picked),
    /// weighed by MIS against BSDF sampling ([`Strategy`]), and every punctual light with its
    /// shadow ray (up to 16; beyond, 16 picked by power).
    #[default]
    Power,
    /// Resampled importance sampling (Talbot et al. 2005; the candidates and target of the
    /// hybrid's ReSTIR DI, [`crate::passes::restir`]): this many candidates, each an emissive
    /// sample or a punctual light (half and half where the scene has both, each pool by
    /// power), resampled into one by the target p̂ = the luminance of the unshadowed f·cos·Lₑ·G;
    /// one shadow ray for the kept sample, its contribution f·Lₑ·G·V·W; at every vertex.
    /// An emissive point RIS keeps and an emissive triangle a BSDF-sampled ray from that vertex
    /// hits are weighed by MIS with a stand-in for RIS's density (which is not known in closed
    /// form): the candidates × their source density, a deterministic weight, so both estimates
    /// stay unbiased. The environment map keeps its next-event estimation and MIS. The
    /// megakernel only; 1 to [`DirectSampling::MAX_CANDIDATES`] candidates, and at most
    /// [`PathTracePass::RIS_CANDIDATES_PER_DISPATCH`] over a path's vertices (the candidates ×
    /// the bounces).
    Ris(u32),
}

impl DirectSampling {
    /// Most RIS candidates (each one a loop iteration of a binary search over a light table;
    /// llvmpipe ends an invocation's loops after 65,535 iterations in all).
    pub const MAX_CANDIDATES: u32 = 256;

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            DirectSampling::Power => "power",
            DirectSampling::Ris(_) => "ris",
        }
    }

    /// The RIS candidates (0 for power sampling): the kernel's `ris_candidates`.
    pub fn candidates(self) -> u32 {
        match self {
            DirectSampling::Power => 0,
            DirectSampling::Ris(m) => m,
        }
    }
}

/// Reuse for the first hit's RIS ([`DirectSampling::Ris`], the megakernel only): which first-hit
/// reservoirs of the previous sample index a pixel's first hit merges after its fresh candidates
/// (`spirv/include/ris_reuse.glsl`). Each pixel's reservoir (the light sample kept, its W and
/// M, and the first hit it was built for) is written to a per-pixel buffer, two of them swapped
/// between sample indices, so a render with reuse traces one sample per dispatch. A reused
/// sample is weighed by its target p̂ at this pixel's first hit; the combination is unbiased by
/// pairwise MIS (each reused reservoir against the pixel's fresh one, the balance heuristic of
/// their M·p̂, a reused one's p̂ at its own first hit, whose surface is rebuilt for it; then
/// W = w_sum / p̂(y)); the merged M is capped at
/// [`crate::gpu::layout::RIS_REUSE_CAP`] × the candidates. Reservoirs are merged where their
/// first hit is similar (distance from the camera within 10 %, normals within about 25°). No
/// visibility enters the reuse: the kept sample has the one shadow ray RIS traces anyway. The
/// samples of one render are correlated across sample indices (each index's reservoirs feed the
/// next), so a render with reuse cannot be split into sample ranges or tiles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum RisReuse {
    /// No reuse: every sample's RIS from its own candidates.
    #[default]
    Off,
    /// The pixel's own reservoir of the previous sample index (another point of the pixel).
    Samples,
    /// Random nearby pixels' reservoirs of the previous sample index.
    ///
    /// [`crate::gpu::layout::RIS_REUSE_NEIGHBOURS`] pixels within
    /// [`crate::gpu::layout::RIS_REUSE_RADIUS`] pixels.
    Spatial,
    /// Both: the pixel's own and its neighbours' reservoirs.
    Both,
}

impl RisReuse {
    /// Every value, for tests and benchmarks that try each.
    pub const ALL: [RisReuse; 4] = [RisReuse::Off, RisReuse::Samples, RisReuse::Spatial, RisReuse::Both];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            RisReuse::Off => "off",
            RisReuse::Samples => "samples",
            RisReuse::Spatial => "spatial",
            RisReuse::Both => "both",
        }
    }

    /// The kernel's (`ris_temporal`, `ris_spatial`).
    fn spec(self) -> (bool, bool) {
        (
            matches!(self, RisReuse::Samples | RisReuse::Both),
            matches!(self, RisReuse::Spatial | RisReuse::Both),
        )
    }
}

/// How next-event estimation draws a point on the emissive triangle it picked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum EmitterSampling {
    /// Uniform on the triangle's area, Mitsuba's choice.
    ///
    /// The pdf is pmf / area × r² / cos at the light: the light's 1/r² and cosine stay in the
    /// estimate, so a surface near a large emitter is noisy.
    #[default]
    Area,
    /// Uniform in the solid angle the triangle subtends where that is at least 0.2 sr, by area
    /// elsewhere.
    ///
    /// Arvo 1995, as pbrt-v4 samples triangles; pdf pmf / Ω. Next to a large emitter it takes the
    /// 1/r² and cosine out (a floor 0.15 under a 2×2 emitter: 2.8× less time at equal error); on
    /// llvmpipe it costs 2-21 % more time on every scene with emitters (both branches run for all
    /// SIMD lanes), so it is asked for (docs/history/2026-12-05.md, twelfth session).
    SolidAngle,
}

impl EmitterSampling {
    /// Both ways.
    pub const ALL: [EmitterSampling; 2] = [EmitterSampling::Area, EmitterSampling::SolidAngle];
}

/// The numbers a path draws its samples from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Sampler {
    /// Shuffled, Owen-scrambled 2D Sobol points per pixel and use (Burley 2020).
    ///
    /// `random.glsl`'s `qmc4`: every pair of numbers a path vertex draws (a BSDF direction, a
    /// point on a light, the pixel's footprint) is stratified over the pixel's samples, so the error falls
    /// faster than 1/spp where the integrand allows (the Cornell box and DamagedHelmet at
    /// 64-256 spp: 0.5-0.6 of independent numbers' relative MSE at the same samples). Each number
    /// is still uniform, and pixels are scrambled independently (the error is white noise).
    #[default]
    LowDiscrepancy,
    /// Independent numbers: the error falls as 1/spp.
    ///
    /// A hash of pixel, sample, bounce and use. A pixel's sample variance estimates its error
    /// without bias (stratified samples make it an over-estimate).
    Independent,
}

impl Sampler {
    /// Every sampler.
    pub const ALL: [Sampler; 2] = [Sampler::LowDiscrepancy, Sampler::Independent];
}

/// What the path tracer's pipeline is specialised on: the estimator, apart from the scene (the
/// key its passes are cached by).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PathOptions {
    /// Microfacet distribution and its sampling.
    pub microfacet: Microfacet,
    /// MIS heuristic (used by [`Strategy::Mis`] only).
    pub heuristic: Heuristic,
    /// Sampling strategies.
    pub strategy: Strategy,
    /// The direct light by RIS ([`DirectSampling::Ris`]; the candidates' count is a push
    /// constant): the megakernel only.
    pub ris: bool,
    /// Reuse for the first hit's RIS ([`RisReuse`]; with `ris` only).
    pub ris_reuse: RisReuse,
    /// The numbers the samples are drawn from.
    pub sampler: Sampler,
    /// Points on the emissive triangles for next-event estimation.
    pub emitter_sampling: EmitterSampling,
}

/// A kernel's `Spec` with the sampling constants of `options` (a [`PathOptions`]), which both
/// integrators' kernels (`pathtrace`, `wavefront`) declare; the rest from `$rest` (`..rest`).
macro_rules! sampling_spec {
    ($spec:path, $options:expr $(, $rest:expr)?) => {{
        let PathOptions { microfacet, heuristic, strategy, sampler, emitter_sampling, .. } = $options;
        let (light_sampling, bsdf_hits) = strategy.spec();
        $spec {
            beckmann: microfacet == Microfacet::Beckmann,
            ggx_walter: microfacet == Microfacet::GgxWalter,
            power_heuristic: heuristic != Heuristic::Balance,
            #[cfg(feature = "testing")]
            unweighted_bsdf_hits: heuristic == Heuristic::UnweightedBsdfHits,
            #[cfg(not(feature = "testing"))]
            unweighted_bsdf_hits: false,
            light_sampling,
            bsdf_hits,
            low_discrepancy: sampler == $crate::passes::pathtrace::Sampler::LowDiscrepancy,
            solid_angle_emitters: emitter_sampling == $crate::passes::pathtrace::EmitterSampling::SolidAngle,
            $(..$rest)?
        }
    }};
}
pub(super) use sampling_spec;

/// Settings of a path-traced render.
#[derive(Debug, Clone, PartialEq)]
pub struct PathSettings {
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel.
    pub spp: u32,
    /// Scattering events per path (1 = direct lighting only).
    pub max_bounces: u32,
    /// Russian roulette starts once a path has scattered this many times.
    pub rr_depth: u32,
    /// Seed of the counter-based random numbers.
    pub seed: u32,
    /// The numbers the samples are drawn from (low-discrepancy by default).
    pub sampler: Sampler,
    /// Points on the emissive triangles for next-event estimation (by area by default).
    pub emitter_sampling: EmitterSampling,
    /// Microfacet distribution and its sampling.
    pub microfacet: Microfacet,
    /// MIS heuristic.
    pub heuristic: Heuristic,
    /// Sampling strategies (MIS of both, or either alone).
    pub strategy: Strategy,
    /// The light sampling at every scattering vertex: by power, or RIS.
    pub direct: DirectSampling,
    /// Reuse for the first hit's RIS ([`RisReuse`]; with [`DirectSampling::Ris`] only, the
    /// megakernel, no tile and no sample range after 0).
    pub ris_reuse: RisReuse,
    /// Constant environment radiance (linear rgb) seen by rays that leave the scene, or, when
    /// the scene has an environment map, the map's multiplier.
    pub env: [f32; 3],
    /// Sample the environment map for next-event estimation (with MIS); off leaves only BSDF
    /// sampling to find it (a check of the two strategies against each other).
    pub env_nee: bool,
    /// Stop before `spp` once [`crate::render::PathImage::relative_error`] is at most this (checked
    /// after each batch, from 16 samples per pixel on).
    pub target_error: Option<f32>,
    /// The render's first sample in the counter-based sequence: it traces samples
    /// `first_sample .. first_sample + spp`, exactly those a render from 0 traces there, so
    /// renders of disjoint ranges merge into the render of their union (`umbra merge`).
    pub first_sample: u32,
    /// Render only a region of a larger image: `size` pixels from [`Tile::origin`] of a
    /// [`Tile::image`]-sized image, each pixel (ray and random numbers) as the whole image has it.
    pub tile: Option<Tile>,
    /// The megakernel or the wavefront path tracer: the same samples, laid out differently on
    /// the device.
    pub integrator: Integrator,
    /// Split each sample's radiance by the lobes it left the first hit through, diffuse and
    /// specular, for the denoiser (a target [`PathTarget::with_lobe_split`];
    /// [`crate::render::PathImage::lobe_split`]), through either integrator.
    pub lobe_split: bool,
}

/// A region of a larger image (`umbra render --tile`): the render's `size` pixels from `origin`
/// of an image of `image` pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    /// Width and height of the whole image.
    pub image: (u32, u32),
    /// Its pixel where the region starts (left column, top row).
    pub origin: (u32, u32),
}

impl Default for PathSettings {
    fn default() -> Self {
        Self {
            size: (256, 256),
            spp: 64,
            max_bounces: 8,
            rr_depth: 3,
            seed: 0,
            sampler: Sampler::LowDiscrepancy,
            emitter_sampling: EmitterSampling::Area,
            microfacet: Microfacet::Ggx,
            heuristic: Heuristic::Power,
            strategy: Strategy::Mis,
            direct: DirectSampling::Power,
            ris_reuse: RisReuse::Off,
            env: [0.0; 3],
            env_nee: true,
            target_error: None,
            first_sample: 0,
            tile: None,
            integrator: Integrator::Megakernel,
            lobe_split: false,
        }
    }
}

impl PathSettings {
    /// The options the pipeline is specialised on.
    pub fn options(&self) -> PathOptions {
        PathOptions {
            microfacet: self.microfacet,
            heuristic: self.heuristic,
            strategy: self.strategy,
            ris: matches!(self.direct, DirectSampling::Ris(_)),
            ris_reuse: self.ris_reuse,
            sampler: self.sampler,
            emitter_sampling: self.emitter_sampling,
        }
    }

    /// The camera's raster: the whole image and the region rendered (`size` from the tile's
    /// origin, or the whole image).
    pub fn camera(&self, camera: &Camera) -> GpuCamera {
        match self.tile {
            Some(tile) => GpuCamera::region(camera, tile.image, tile.origin),
            None => GpuCamera::new(camera, self.size),
        }
    }

    /// An error unless the settings describe a render: at least one sample, a sample range
    /// within the sequence's 2^32 indices, a tile inside its image, at most
    /// [`super::wavefront::MAX_BOUNCES`] bounces for the wavefront integrator, RIS with the
    /// megakernel, light sampling and 1 to [`DirectSampling::MAX_CANDIDATES`] candidates, at most
    /// [`PathTracePass::RIS_CANDIDATES_PER_DISPATCH`] over a path's bounces.
    pub fn validate(&self) -> Result<()> {
        if self.spp == 0 {
            return Err(Error::Invalid("samples per pixel must be at least 1".into()));
        }
        if self.first_sample.checked_add(self.spp).is_none() {
            return Err(Error::Invalid(format!(
                "samples {}..{} run past the sequence's last index ({})",
                self.first_sample,
                self.first_sample as u64 + self.spp as u64,
                u32::MAX
            )));
        }
        if self.integrator == Integrator::Wavefront && self.max_bounces > super::wavefront::MAX_BOUNCES {
            return Err(Error::Invalid(format!(
                "the wavefront integrator traces at most {} bounces (three dispatches a bounce), not {}",
                super::wavefront::MAX_BOUNCES,
                self.max_bounces
            )));
        }
        if let DirectSampling::Ris(m) = self.direct {
            if m == 0 || m > DirectSampling::MAX_CANDIDATES {
                return Err(Error::Invalid(format!(
                    "{m} RIS candidates: must be 1 to {}",
                    DirectSampling::MAX_CANDIDATES
                )));
            }
            let per_path = u64::from(m) * u64::from(self.max_bounces.max(1));
            if per_path > u64::from(PathTracePass::RIS_CANDIDATES_PER_DISPATCH) {
                return Err(Error::Invalid(format!(
                    "{m} RIS candidates at each of up to {} bounces is {per_path} a path: at most {} \
                     (llvmpipe cuts an invocation's loops short); fewer candidates or bounces",
                    self.max_bounces,
                    PathTracePass::RIS_CANDIDATES_PER_DISPATCH
                )));
            }
            if self.integrator == Integrator::Wavefront {
                return Err(Error::Invalid(
                    "RIS (--direct ris) runs in the megakernel only, not the wavefront integrator".into(),
                ));
            }
            if self.strategy == Strategy::Bsdf {
                return Err(Error::Invalid(
                    "RIS (--direct ris) is light sampling: not with --strategy bsdf".into(),
                ));
            }
        }
        if self.ris_reuse != RisReuse::Off {
            let refuse = |why: &str| {
                Err(Error::Invalid(format!("RIS reuse (--ris-reuse {}) {why}", self.ris_reuse.name())))
            };
            if !matches!(self.direct, DirectSampling::Ris(_)) {
                return refuse("reuses the first hit's RIS reservoirs: it needs --direct ris");
            }
            if self.integrator == Integrator::Wavefront {
                return refuse("runs in the megakernel only, not the wavefront integrator");
            }
            if self.tile.is_some() {
                return refuse("takes neighbours across the whole image: not with --tile");
            }
            if self.first_sample != 0 {
                return refuse(
                    "chains each sample index to the one before: a sample range must start at 0 (--sample-range)",
                );
            }
        }
        if let Some(Tile { image, origin }) = self.tile {
            let fits = |o: u32, s: u32, i: u32| o.checked_add(s).is_some_and(|end| end <= i);
            if !fits(origin.0, self.size.0, image.0) || !fits(origin.1, self.size.1, image.1) {
                return Err(Error::Invalid(format!(
                    "tile {}x{} at ({}, {}) does not fit in the {}x{} image",
                    self.size.0, self.size.1, origin.0, origin.1, image.0, image.1
                )));
            }
        }
        Ok(())
    }
}

/// The per-pixel buffers a path-traced image accumulates into.
pub struct PathTarget {
    /// Width and height.
    pub size: (u32, u32),
    /// vec4 per pixel: running mean rgb, sample count.
    pub accum: Buffer,
    /// vec4 per pixel: running mean of the squared samples rgb.
    pub moment: Buffer,
    /// vec4 per pixel: base colour at the first hit, mean over the samples (alpha: the fraction
    /// of samples that hit something).
    pub albedo: Buffer,
    /// vec4 per pixel: shading normal xyz at the first hit, distance in w (inf for a miss).
    pub normal_depth: Buffer,
    /// vec4 per pixel: radiance emitted at the first hit (or the environment seen), mean over
    /// the samples.
    pub emission: Buffer,
    /// [`PathStats`].
    pub stats: Buffer,
    /// The lobe split's buffers, in a target made by [`PathTarget::with_lobe_split`]: either
    /// integrator then splits each sample's radiance for the denoiser.
    pub lobe_split: Option<LobeSplit>,
    /// The wavefront path tracer's queues and path states, made at its first render into this
    /// target.
    pub wave: std::sync::OnceLock<WaveState>,
    /// The first hit's RIS reservoirs for reuse ([`RisReuse`]; one
    /// [`crate::gpu::layout::GpuPathReservoir`] per pixel each, the previous sample index's and
    /// this one's, swapped between dispatches), made at the first render with reuse into this
    /// target.
    pub ris_reservoirs: std::sync::OnceLock<[Buffer; 2]>,
    /// Whether the megakernel counts how busy its SIMD lanes are in the BVH walks, into
    /// [`PathStats`]' `walk_*` counters (a diagnostic: [`PathTarget::with_lane_counts`]).
    pub lane_counts: bool,
}

/// A path target's split of the radiance by the lobes it left the first hit through (the
/// denoiser filters the two parts apart, each over its own albedo): the diffuse lobe's part and
/// the rest, the specular part (reflection, transmission, sheen, clear coat). At the first hit a
/// light sample's contribution splits by the lobes' shares of the BSDF, and all a path gathers
/// beyond it by those shares at the direction it was sampled in.
pub struct LobeSplit {
    /// vec4 per pixel: the mean of the specular part rgb; the mean of the diffuse part's
    /// (the radiance less the first hit's emission and the specular part) luminance squared
    /// over the first hit's base colour.
    pub specular: Buffer,
    /// vec4 per pixel: the mean of the first hit's specular albedo rgb (1 for a dielectric or a
    /// miss, the base colour for a metal: the specular part's divisor); the mean of the specular
    /// part's luminance squared over it.
    pub split: Buffer,
}

impl PathTarget {
    /// How every buffer of a target is used: by the kernels, read back, cleared.
    const USAGE: raw::BufferUsageFlags = raw::BufferUsageFlags::from_raw(
        raw::BufferUsageFlags::STORAGE_BUFFER.as_raw()
            | raw::BufferUsageFlags::TRANSFER_SRC.as_raw()
            | raw::BufferUsageFlags::TRANSFER_DST.as_raw(),
    );

    /// A device-local buffer of one vec4 per pixel.
    fn pixel_buffer(ctx: &Context, name: &str, (w, h): (u32, u32)) -> Result<Buffer> {
        Buffer::new(ctx, name, w as u64 * h as u64 * 16, Self::USAGE, MemoryLocation::GpuOnly)
    }

    /// Allocates the buffers (device-local; read back through staging).
    pub fn new(ctx: &Context, size: (u32, u32)) -> Result<Self> {
        let make = |name| Self::pixel_buffer(ctx, name, size);
        Ok(Self {
            size,
            accum: make("path accum")?,
            moment: make("path moment")?,
            albedo: make("path albedo")?,
            normal_depth: make("path normal depth")?,
            emission: make("path emission")?,
            stats: Buffer::upload(ctx, "path stats", &[PathStats::default()], Self::USAGE)?,
            lobe_split: None,
            wave: std::sync::OnceLock::new(),
            ris_reservoirs: std::sync::OnceLock::new(),
            lane_counts: false,
        })
    }

    /// This target, its renders by the megakernel counting the BVH walks' busy SIMD lanes
    /// ([`PathStats::busy_lanes`]) through a pipeline of their own that also runs subgroup
    /// reductions per trace: the same image, more slowly. The wavefront integrator does not count.
    pub fn with_lane_counts(self) -> Self {
        Self { lane_counts: true, ..self }
    }

    /// [`PathTarget::new`] with the buffers of the lobe split ([`LobeSplit`]; two more vec4s
    /// per pixel), which either integrator then fills for the denoiser.
    pub fn with_lobe_split(ctx: &Context, size: (u32, u32)) -> Result<Self> {
        let make = |name| Self::pixel_buffer(ctx, name, size);
        let lobe_split = LobeSplit { specular: make("path specular")?, split: make("path split")? };
        Ok(Self { lobe_split: Some(lobe_split), ..Self::new(ctx, size)? })
    }

    /// Makes the wavefront path tracer's state now (else its first render does, holding up to
    /// [`super::wavefront::MAX_PATHS`] paths): for `scene`'s renders of at most `max_bounces`,
    /// holding at most `max_paths` paths (a host bounding its memory; fewer paths, more waves).
    /// An error if the target has one already.
    pub fn init_wave(&self, ctx: &Context, scene: &GpuScene, max_bounces: u32, max_paths: u64) -> Result<()> {
        let state = WaveState::new(ctx, scene, self.size, max_bounces, max_paths, self.lobe_split.is_some())?;
        self.wave
            .set(state)
            .map_err(|_| Error::Invalid("the path target has a wavefront state already".into()))
    }

    /// Records the clearing of the running mean and second moment (a new render starts: the
    /// kernel counts the samples accumulated so far in the mean's alpha).
    pub fn record_clear(&self, rec: &mut Recorder<'_>) {
        rec.fill(&self.accum, 0);
        rec.fill(&self.moment, 0);
        // A render with RIS reuse starts without reservoirs (count 0).
        if let Some(reservoirs) = self.ris_reservoirs.get() {
            Self::record_clear_reservoirs(rec, reservoirs);
        }
    }

    /// Records the clearing of the RIS reservoirs (every count 0: no reservoir).
    fn record_clear_reservoirs(rec: &mut Recorder<'_>, reservoirs: &[Buffer; 2]) {
        for buffer in reservoirs {
            rec.fill(buffer, 0);
        }
    }

    /// The RIS reservoirs for reuse, made (and their clearing recorded) if the target has none
    /// yet; an error when one would exceed the device's storage-buffer range.
    fn ris_reservoirs(&self, rec: &mut Recorder<'_>) -> Result<&[Buffer; 2]> {
        if let Some(reservoirs) = self.ris_reservoirs.get() {
            return Ok(reservoirs);
        }
        // (Buffer::new refuses a buffer over the device's storage-buffer range, naming it.)
        let bytes = self.size.0 as u64 * self.size.1 as u64 * std::mem::size_of::<GpuPathReservoir>() as u64;
        let make = |name| Buffer::new(rec.ctx(), name, bytes, Self::USAGE, MemoryLocation::GpuOnly);
        let reservoirs = [make("path RIS reservoirs 0")?, make("path RIS reservoirs 1")?];
        Self::record_clear_reservoirs(rec, &reservoirs);
        Ok(self.ris_reservoirs.get_or_init(|| reservoirs))
    }
}

/// `pathtrace.comp`, specialised for one scene's features and the chosen sampling.
pub struct PathTracePass {
    /// The kernel specialised with or without the lobe split and with or without lane counts,
    /// each made at its first use (a record into a target with or without them), or by
    /// [`PathTracePass::prepare`].
    pipelines: Cache<pathtrace::Spec, Pipeline<pathtrace::Kernel>>,
    options: PathOptions,
}

impl PathTracePass {
    /// The pipeline for `scene` and `options`: specialised so that what the scene lacks
    /// (emissive triangles, punctual lights, an environment map, textures, transmission, alpha,
    /// vertex colours, unlit materials) and what the options leave out cost nothing.
    pub fn for_scene(ctx: &Context, scene: &GpuScene, options: PathOptions) -> Result<Self> {
        let pass = Self::lazy(options);
        pass.prepare(ctx, scene, false)?;
        Ok(pass)
    }

    /// The pass for `options` with no pipeline built yet: each is built at its first use.
    pub fn lazy(options: PathOptions) -> Self {
        Self { pipelines: Cache::new(), options }
    }

    /// The pipeline for `scene`, specialised for the lobe split or not (built now if it was not:
    /// pipeline creation takes 1.5–1.7 s on lavapipe, so a render builds only the one it uses).
    pub fn prepare(
        &self,
        ctx: &Context,
        scene: &GpuScene,
        lobe_split: bool,
    ) -> Result<&Pipeline<pathtrace::Kernel>> {
        self.variant(ctx, &scene.features(), lobe_split, false)
    }

    /// [`PathTracePass::prepare`] for a scene with `features`, before it is uploaded.
    pub fn prepare_for(
        &self,
        ctx: &Context,
        features: &SceneFeatures,
        lobe_split: bool,
    ) -> Result<&Pipeline<pathtrace::Kernel>> {
        self.variant(ctx, features, lobe_split, false)
    }

    /// The pipeline for `features`, the lobe split and the lane counts.
    fn variant(
        &self,
        ctx: &Context,
        features: &SceneFeatures,
        lobe_split: bool,
        lane_counts: bool,
    ) -> Result<&Pipeline<pathtrace::Kernel>> {
        let spec = sampling_spec!(
            pathtrace::Spec,
            self.options,
            pathtrace::Spec {
                split_lobes: lobe_split,
                ris: self.options.ris,
                ris_temporal: self.options.ris_reuse.spec().0,
                ris_spatial: self.options.ris_reuse.spec().1,
                count_lanes: lane_counts,
                ..Default::default()
            }
        );
        self.pipelines.get_or_try_init(spec, || Pipeline::new(ctx, &spec, Some(features)))
    }

    /// Samples per pixel one dispatch traces at most ([`PathTracePass::record`] splits longer
    /// runs). Lanes whose paths end early start their next sample within the dispatch, so the
    /// longer the run, the less a SIMD group idles (lavapipe, Cornell box, 1 core: 1, 4, 8, 16, 32
    /// samples per dispatch took 100, 88, 83, 80, 79 % of the time; docs/history/2026-12-02.md,
    /// path regeneration).
    pub const SAMPLES_PER_DISPATCH: u32 = 16;

    /// [`PathTracePass::SAMPLES_PER_DISPATCH`] in scenes with implicit shapes: each march takes
    /// up to [`crate::gpu::layout::IMPLICIT_MAX_STEPS`] loop iterations (and each distance one
    /// per instruction), and llvmpipe cuts an invocation's loops short past 65,535 iterations.
    pub const SAMPLES_PER_DISPATCH_IMPLICIT: u32 = 2;

    /// RIS candidates one dispatch resamples at most, over its samples' vertices (each one a
    /// binary search of a light table: llvmpipe's loop limit): a dispatch with
    /// [`DirectSampling::Ris`] traces at most this ÷ (the candidates × the bounces) samples (at
    /// least one; [`PathSettings::validate`] refuses a path of more).
    pub const RIS_CANDIDATES_PER_DISPATCH: u32 = 512;

    /// The push constants for sample 0 of `settings` seen from `camera` (`sample_index` and
    /// `sample_count`: set them per dispatch).
    pub fn params(scene: &GpuScene, camera: &Camera, settings: &PathSettings) -> PathParams {
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        PathParams {
            camera: settings.camera(camera),
            env: settings.env,
            ris_candidates: settings.direct.candidates(),
            size: [settings.size.0, settings.size.1],
            sample_index: 0,
            seed: settings.seed,
            max_bounces: settings.max_bounces,
            rr_depth: settings.rr_depth,
            light_count: scene.light_count,
            punctual_count: scene.punctual_count,
            env_size: [env_w, env_h],
            sample_count: 1,
            env_pick: Self::env_pick(scene, settings),
        }
    }

    /// The probability that a light sample comes from the environment map rather than the
    /// emissive triangles (one light sample per scattering event serves both): 1 or 0 where the
    /// path tracer samples only one of them; where it samples both, their shares of the power
    /// reaching the scene (the map's 4π²R²·L̄ through the scene's bounding sphere of radius R,
    /// pbrt-v4's estimate for an infinite light, against the triangles' Σ π·L·A), kept within
    /// [0.1, 0.9] so that neither kind is starved where the estimate misjudges which lights a
    /// point sees.
    pub fn env_pick(scene: &GpuScene, settings: &PathSettings) -> f32 {
        let env = scene.env_size.is_some() && settings.env_nee;
        match (env, scene.light_count > 0) {
            (false, _) => 0.0,
            (true, false) => 1.0,
            (true, true) => {
                let [lo, hi] = scene.bounds.map(glam::Vec3::from);
                let radius = 0.5 * (hi - lo).length();
                let env_power = 4.0
                    * std::f32::consts::PI
                    * std::f32::consts::PI
                    * radius
                    * radius
                    * scene.env_luminance
                    * crate::color::luminance(settings.env);
                let total = env_power + scene.emissive_power;
                if total > 0.0 && total.is_finite() {
                    (env_power / total).clamp(0.1, 0.9)
                } else {
                    0.5
                }
            }
        }
    }

    /// Records samples `params.sample_index .. + params.sample_count` per pixel, in dispatches
    /// of at most [`PathTracePass::SAMPLES_PER_DISPATCH`] each. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        target: &PathTarget,
        params: &PathParams,
    ) -> Result<()> {
        // Without the split its bindings hold buffers the kernel then never reads.
        let (aov_specular, aov_split) = match &target.lobe_split {
            Some(split) => (&split.specular, &split.split),
            None => (&target.albedo, &target.emission),
        };
        let reuse = self.options.ris_reuse != RisReuse::Off;
        // Without reuse the reservoir bindings hold buffers the kernel never reads or writes.
        let reservoirs = if reuse { Some(target.ris_reservoirs(rec)?) } else { None };
        let mut resources = pathtrace::Resources {
            scene,
            accum: &target.accum,
            moment: &target.moment,
            aov_albedo: &target.albedo,
            aov_normal_depth: &target.normal_depth,
            aov_emission: &target.emission,
            aov_specular,
            aov_split,
            stats: &target.stats,
            ris_prev: &target.accum,
            ris_next: &target.moment,
        };
        if self.options.ris && !(1..=DirectSampling::MAX_CANDIDATES).contains(&params.ris_candidates) {
            return Err(Error::Invalid(format!(
                "the path tracer was built for RIS, with {} candidates: must be 1 to {}",
                params.ris_candidates,
                DirectSampling::MAX_CANDIDATES
            )));
        }
        let pipeline =
            self.variant(rec.ctx(), &scene.features(), target.lobe_split.is_some(), target.lane_counts)?;
        let end = params.sample_index + params.sample_count;
        let mut dispatch = *params;
        while dispatch.sample_index < end {
            let mut most = if scene.has_implicit {
                Self::SAMPLES_PER_DISPATCH_IMPLICIT
            } else {
                Self::SAMPLES_PER_DISPATCH
            };
            if self.options.ris {
                let per_sample = dispatch.ris_candidates.max(1).saturating_mul(dispatch.max_bounces.max(1));
                most = most.min((Self::RIS_CANDIDATES_PER_DISPATCH / per_sample).max(1));
            }
            if let Some(reservoirs) = reservoirs {
                // One sample index per dispatch: it reads the reservoirs of the one before.
                most = 1;
                let next = (dispatch.sample_index & 1) as usize;
                resources.ris_next = &reservoirs[next];
                resources.ris_prev = &reservoirs[next ^ 1];
            }
            dispatch.sample_count = most.min(end - dispatch.sample_index);
            pipeline.record(rec, &resources, &dispatch, [target.size.0, target.size.1, 1])?;
            dispatch.sample_index += dispatch.sample_count;
        }
        Ok(())
    }
}

/// `resolve.comp`: a [`PathTarget`]'s running mean into an `R32G32B32A32_SFLOAT` storage image.
pub struct ResolvePass {
    pipeline: Pipeline<resolve::Kernel>,
}

impl ResolvePass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records the copy of `target`'s mean into `output` (a storage image of the target's size
    /// in `GENERAL` layout). Never submits.
    pub fn record(&self, rec: &mut Recorder<'_>, target: &PathTarget, output: raw::ImageView) -> Result<()> {
        self.pipeline.record(
            rec,
            &resolve::Resources { accum: &target.accum, out_color: &output },
            &ResolveParams { size: [target.size.0, target.size.1], ..Default::default() },
            [target.size.0, target.size.1, 1],
        )?;
        Ok(())
    }
}
