//! The denoiser: an edge-avoiding à-trous wavelet filter of a path-traced image, the spatial
//! part of SVGF (Schied et al. 2017), guided by the first hit's normal and distance and by the
//! per-pixel variance the path tracer accumulates, on radiance divided by the first hit's albedo
//! (so texture and colour detail is not blurred: it is multiplied back at the end). What the
//! first hit emits (an emitter seen directly, the environment where camera rays miss) is left out
//! of the filter and added back: it has no noise to speak of, and an emitter's bright edge would
//! otherwise spread over the surfaces around it.
//!
//! With the path tracer's lobe split ([`crate::passes::pathtrace::LobeSplit`], a target made by
//! `PathTarget::with_lobe_split`, which `umbra render --denoise` uses) the radiance is filtered as
//! two images: the part that left the first hit through its diffuse lobe, divided by the base
//! colour, and the rest (glossy reflection, transmission, sheen, coat), divided by the specular
//! albedo (1 for a dielectric, the base colour for a metal), each with the variance of its own
//! luminance from the path tracer's per-sample squares. A highlight on a dark texel is then not
//! divided into a huge value that spreads onto bright texels, and a metal's texture stays sharp.
//!
//! Three kernels: `denoise_prepare.comp` (the path target's buffers into images: demodulated
//! radiance and the variance of its luminance; normal and distance; sample count),
//! `denoise_atrous.comp` ([`DenoiseSettings::iterations`] iterations, taps 1, 2, 4, ... pixels
//! apart, ping-ponging between two images; with the lobe split one dispatch filters both parts
//! while both have iterations left, [`DenoiseSettings::specular_iterations`] on the specular
//! part) and `denoise_remodulate.comp` (× albedo, + emission,
//! into the output image). Every image is in `GENERAL` layout; [`DenoisePass::record`] never
//! submits. One frame's samples are filtered
//! on their own; [`DenoisePass::record_temporal`] blends them with the previous frames' first
//! (temporal accumulation with reprojection, [`crate::passes::temporal`]).

use crate::error::{Error, Result};
use crate::gpu::kernels::{denoise_atrous, denoise_prepare, denoise_remodulate};
use crate::gpu::layout::GpuCamera;
use crate::gpu::layout::{
    DenoiseParams, DENOISE_BOTH, DENOISE_DEMODULATE, DENOISE_EDGE_STOPPING, DENOISE_PREFILTER,
    DENOISE_SPATIAL_VARIANCE, DENOISE_SPLIT, DENOISE_WIDE,
};
use crate::gpu::Pipeline;
use crate::passes::pathtrace::PathTarget;
use crate::passes::temporal::{TemporalHistory, TemporalPass};
use crate::vk::{raw, Buffer, Context, Image, Recorder};

/// The filter's settings. The σ's are SVGF's (σ_l 4, σ_n 128, σ_z 1); the rest were chosen on
/// `umbra-bench denoise` (BENCHMARKS.md; how the defaults were chosen: docs/history/2026-12-05.md):
/// four iterations of 3×3 taps, the variance not prefiltered, a spatial variance floor in the first
/// iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DenoiseSettings {
    /// À-trous iterations, 1 to [`DenoiseSettings::MAX_ITERATIONS`]: iteration i spaces its
    /// taps 2^i pixels apart, so four of 3×3 taps reach 15 pixels from the centre (of 5×5: 30).
    pub iterations: u32,
    /// Luminance edge-stopping: a tap whose luminance differs by this many standard deviations
    /// of the centre's weighs e^−1.
    pub sigma_luminance: f32,
    /// Normal edge-stopping exponent: a tap weighs max(0, n·n')^this.
    pub sigma_normal: f32,
    /// Depth edge-stopping: a tap whose distance differs from the centre's by this × what the
    /// local depth slope predicts (plus 0.1 % of the distance) weighs e^−1.
    pub sigma_depth: f32,
    /// Filter radiance divided by the albedo (multiplied back after). Off filters radiance
    /// itself, blurring texture detail: for comparison.
    pub demodulate: bool,
    /// Added to the albedo before dividing by it, 0 to 1. 0 keeps texture edges exact (a noisy
    /// 0.8 | 0.2 edge bleeds 0.2 %); glTF's dielectric specular reflectance, 0.04, keeps a
    /// glossy highlight on a dark texel from being divided into a huge value that the filter
    /// then spreads onto bright texels (scenes/textured.glb at 4 spp, 128², 1024-spp reference:
    /// 0.8× the raw relative MSE with 0, 1.1× with 0.04), at the price of texture edges (that
    /// edge bleeds 5 %).
    pub albedo_offset: f32,
    /// Read the centre's variance through a 3×3 Gaussian (a few samples' variance is noisy).
    pub prefilter_variance: bool,
    /// 5×5 taps per iteration (the B3 spline, as SVGF) instead of 3×3 ((1/4, 1/2, 1/4)²): 25
    /// taps against 9 (1.7× the filter's time, measured at 3 iterations).
    pub wide: bool,
    /// In the first iteration, take the variance to be at least the spread of the neighbours'
    /// luminance on the same surface (3×3) × min(1, 4 / samples): a few samples that happened
    /// to agree say 0, and the spread, which holds the signal's own variation, fades as the
    /// pixel's own estimate becomes reliable.
    pub spatial_variance: bool,
    /// Weigh taps by normal, depth and luminance. Off is a plain blur: for tests that must catch
    /// it.
    #[doc(hidden)]
    pub edge_stopping: bool,
    /// Filter the diffuse and the specular parts apart, each over its own albedo, where the
    /// inputs have the lobe split ([`DenoiseInputs::lobe_split`]) and `demodulate` is on: a
    /// highlight is then not divided by a dark texel's albedo and spread onto bright ones, and
    /// a metal's texture is not blurred. Off filters their sum as without the split.
    pub lobe_split: bool,
    /// À-trous iterations of the specular part, 0 (left unfiltered) to
    /// [`DenoiseSettings::MAX_ITERATIONS`]. Two: at 4 spp (`umbra-bench denoise`, 128²) 0, 2 and 4
    /// left the Cornell box's relative MSE 8.2×, 8.7×, 8.9× below the raw image's, the sphere
    /// grid's 3.2×, 3.7×, 3.8×, for 0, 2 and 4 more iterations' time (docs/history/2026-12-02.md,
    /// "the denoiser's lobe split").
    pub specular_iterations: u32,
}

impl Default for DenoiseSettings {
    fn default() -> Self {
        Self {
            iterations: 4,
            sigma_luminance: 4.0,
            sigma_normal: 128.0,
            sigma_depth: 1.0,
            demodulate: true,
            albedo_offset: 0.0,
            prefilter_variance: false,
            wide: false,
            spatial_variance: true,
            edge_stopping: true,
            lobe_split: true,
            specular_iterations: 2,
        }
    }
}

impl DenoiseSettings {
    /// Most iterations (taps 128 pixels apart in the last).
    pub const MAX_ITERATIONS: u32 = 8;

    /// Checks the settings: 1 to [`DenoiseSettings::MAX_ITERATIONS`] iterations, finite
    /// positive σ's.
    pub fn validate(&self) -> Result<()> {
        if !(1..=Self::MAX_ITERATIONS).contains(&self.iterations) {
            return Err(Error::Invalid(format!(
                "the denoiser runs 1 to {} iterations (got {})",
                Self::MAX_ITERATIONS,
                self.iterations
            )));
        }
        if self.specular_iterations > Self::MAX_ITERATIONS {
            return Err(Error::Invalid(format!(
                "the denoiser runs 0 to {} iterations on the specular part (got {})",
                Self::MAX_ITERATIONS,
                self.specular_iterations
            )));
        }
        if !(0.0..=1.0).contains(&self.albedo_offset) {
            return Err(Error::Invalid(format!(
                "denoiser albedo_offset {} must be between 0 and 1",
                self.albedo_offset
            )));
        }
        for (name, value) in [
            ("sigma_luminance", self.sigma_luminance),
            ("sigma_normal", self.sigma_normal),
            ("sigma_depth", self.sigma_depth),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::Invalid(format!("denoiser {name} {value} must be finite and positive")));
            }
        }
        Ok(())
    }

    fn params(&self, size: (u32, u32), step: u32, split: bool) -> DenoiseParams {
        let flags = if self.demodulate { DENOISE_DEMODULATE } else { 0 }
            | if split { DENOISE_SPLIT } else { 0 }
            | if self.prefilter_variance { DENOISE_PREFILTER } else { 0 }
            | if self.spatial_variance { DENOISE_SPATIAL_VARIANCE } else { 0 }
            | if self.wide { DENOISE_WIDE } else { 0 }
            | if self.edge_stopping { DENOISE_EDGE_STOPPING } else { 0 };
        DenoiseParams {
            size: [size.0, size.1],
            step,
            flags,
            sigma_luminance: self.sigma_luminance,
            sigma_normal: self.sigma_normal,
            sigma_depth: self.sigma_depth,
            albedo_offset: self.albedo_offset,
        }
    }
}

/// What the denoiser reads: a path target's five per-pixel buffers (row-major `vec4`s: the
/// running mean with the sample count in alpha, the mean of the squared samples, the first hit's
/// base colour, its normal and distance, the radiance it emits).
#[derive(Clone, Copy)]
pub struct DenoiseInputs<'a> {
    /// Width and height.
    pub size: (u32, u32),
    /// Running mean rgb, sample count.
    pub accum: &'a Buffer,
    /// Running mean of the squared samples rgb.
    pub moment: &'a Buffer,
    /// Base colour at the first hit (alpha 0 for a miss).
    pub albedo: &'a Buffer,
    /// Shading normal xyz and distance at the first hit (infinite for a miss).
    pub normal_depth: &'a Buffer,
    /// Radiance emitted at the first hit (left out of the filter, added back).
    pub emission: &'a Buffer,
    /// The path target's lobe split (`specular`, `split`: [`crate::passes::pathtrace::LobeSplit`]),
    /// where it has one.
    pub lobe_split: Option<(&'a Buffer, &'a Buffer)>,
}

impl<'a> From<&'a PathTarget> for DenoiseInputs<'a> {
    fn from(target: &'a PathTarget) -> Self {
        Self {
            size: target.size,
            accum: &target.accum,
            moment: &target.moment,
            albedo: &target.albedo,
            normal_depth: &target.normal_depth,
            emission: &target.emission,
            lobe_split: target.lobe_split.as_ref().map(|split| (&split.specular, &split.split)),
        }
    }
}

/// The denoiser's working images (`R32G32B32A32_SFLOAT` but for `samples`): two the iterations
/// ping-pong between, the guide (normal, distance), the sample counts, and what the remodulation
/// multiplies and adds back (the divisors, the first hit's emission).
pub struct DenoiseImages {
    /// Width and height.
    pub size: (u32, u32),
    /// Radiance and variance, even steps.
    pub ping: Image,
    /// Radiance and variance, odd steps.
    pub pong: Image,
    /// Unit normal xyz and distance (−1 for a miss).
    pub guide: Image,
    /// `R32_SFLOAT`: each pixel's sample count.
    pub samples: Image,
    /// What the radiance (diffuse part) is divided by and multiplied back by, rgb.
    pub albedo: Image,
    /// The first hit's emission, rgb (left out of the filter, added back).
    pub emission: Image,
    /// The specular part's ping and pong, in images made by
    /// [`DenoiseImages::with_lobe_split`].
    pub specular: Option<(Image, Image)>,
    /// The specular part's divisor, rgb, with [`DenoiseImages::with_lobe_split`].
    pub spec_albedo: Option<Image>,
}

impl DenoiseImages {
    /// Allocates the images (contents undefined until recorded; move them to `GENERAL` with
    /// [`DenoiseImages::init_general`] once).
    pub fn new(ctx: &Context, (w, h): (u32, u32)) -> Result<Self> {
        let make = |name| Image::storage_2d(ctx, name, w, h, raw::Format::R32G32B32A32_SFLOAT);
        Ok(Self {
            size: (w, h),
            ping: make("denoise ping")?,
            pong: make("denoise pong")?,
            guide: make("denoise guide")?,
            samples: Image::storage_2d(ctx, "denoise samples", w, h, raw::Format::R32_SFLOAT)?,
            albedo: make("denoise albedo")?,
            emission: make("denoise emission")?,
            specular: None,
            spec_albedo: None,
        })
    }

    /// [`DenoiseImages::new`] with two more for the specular part of a target with the lobe
    /// split.
    pub fn with_lobe_split(ctx: &Context, (w, h): (u32, u32)) -> Result<Self> {
        let make = |name| Image::storage_2d(ctx, name, w, h, raw::Format::R32G32B32A32_SFLOAT);
        let specular = Some((make("denoise specular ping")?, make("denoise specular pong")?));
        let spec_albedo = Some(make("denoise specular albedo")?);
        Ok(Self { specular, spec_albedo, ..Self::new(ctx, (w, h))? })
    }

    /// The specular part's divisor, or without the lobe split the diffuse part's, which then
    /// fills the binding of kernels that do not read it.
    pub(crate) fn spec_albedo_or_albedo(&self) -> &Image {
        self.spec_albedo.as_ref().unwrap_or(&self.albedo)
    }

    /// Records the move of every image from `UNDEFINED` to `GENERAL`.
    pub fn init_general(&self, ctx: &Context, cmd: raw::CommandBuffer) {
        for image in [&self.ping, &self.pong, &self.guide, &self.samples, &self.albedo, &self.emission] {
            image.init_general(ctx, cmd);
        }
        if let Some(image) = &self.spec_albedo {
            image.init_general(ctx, cmd);
        }
        if let Some((ping, pong)) = &self.specular {
            ping.init_general(ctx, cmd);
            pong.init_general(ctx, cmd);
        }
    }
}

/// The denoiser's three pipelines.
pub struct DenoisePass {
    prepare: Pipeline<denoise_prepare::Kernel>,
    atrous: Pipeline<denoise_atrous::Kernel>,
    remodulate: Pipeline<denoise_remodulate::Kernel>,
}

impl DenoisePass {
    /// Builds the pipelines.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self {
            prepare: Pipeline::plain(ctx)?,
            atrous: Pipeline::plain(ctx)?,
            remodulate: Pipeline::plain(ctx)?,
        })
    }

    /// Records the filter of `inputs` into `output` (an `R32G32B32A32_SFLOAT` storage image of
    /// the same size in `GENERAL` layout: denoised radiance, alpha 1), through `images`, in
    /// `iterations + 2` dispatches. Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        inputs: &DenoiseInputs<'_>,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        self.record_frame(rec, inputs, images, output, settings, None)
    }

    /// [`DenoisePass::record`] with the temporal step ([`crate::passes::temporal`]) between the
    /// preparation and the à-trous iterations: the frame, seen by `camera`, blended with
    /// `history`, which then holds this frame for the next (one more dispatch).
    pub fn record_temporal(
        &self,
        rec: &mut Recorder<'_>,
        inputs: &DenoiseInputs<'_>,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
        temporal: (&TemporalPass, &mut TemporalHistory, &GpuCamera),
    ) -> Result<()> {
        self.record_frame(rec, inputs, images, output, settings, Some(temporal))
    }

    fn record_frame(
        &self,
        rec: &mut Recorder<'_>,
        inputs: &DenoiseInputs<'_>,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
        temporal: Option<(&TemporalPass, &mut TemporalHistory, &GpuCamera)>,
    ) -> Result<()> {
        settings.validate()?;
        let size = inputs.size;
        if images.size != size {
            return Err(Error::Invalid(format!(
                "denoiser images are {:?} but the image to filter is {size:?}",
                images.size
            )));
        }
        let split = match (inputs.lobe_split, settings.lobe_split && settings.demodulate) {
            (Some(buffers), true) => match &images.specular {
                Some(specular) => Some((buffers, specular)),
                None => return Err(Error::Invalid(
                    "the image to denoise has the lobe split but the denoiser's images have no room for it \
                         (DenoiseImages::with_lobe_split)"
                        .into(),
                )),
            },
            _ => None,
        };
        // Without the split its bindings hold resources the kernels then never read.
        let (aov_specular, aov_split) =
            split.map_or((inputs.albedo, inputs.emission), |(buffers, _)| buffers);
        let params = |step| settings.params(size, step, split.is_some());
        let grid = [size.0, size.1, 1];
        self.prepare.record(
            rec,
            &denoise_prepare::Resources {
                accum: inputs.accum,
                moment: inputs.moment,
                aov_albedo: inputs.albedo,
                aov_normal_depth: inputs.normal_depth,
                aov_emission: inputs.emission,
                aov_specular,
                aov_split,
                dn_color: &images.ping.view,
                dn_specular: &split.map_or(&images.pong, |(_, (ping, _))| ping).view,
                dn_guide: &images.guide.view,
                dn_samples: &images.samples.view,
                dn_albedo: &images.albedo.view,
                dn_spec_albedo: &images.spec_albedo_or_albedo().view,
                dn_emission: &images.emission.view,
            },
            &params(0),
            grid,
        )?;
        // Where the iterations start (the prepared or the accumulated image) and, with the
        // history fed back after the first iteration, where that one writes.
        let (specular_ping, specular_pong) = split.map_or((&images.ping, &images.pong), |(_, (a, b))| (a, b));
        let mut starts = (&images.ping, None, specular_ping, None);
        if let Some((pass, history, camera)) = &temporal {
            let iterations = (settings.iterations, settings.specular_iterations);
            let out = pass.record(rec, images, history, camera, split.is_some(), iterations)?;
            starts = (out.diffuse, out.diffuse_first, out.specular, out.specular_first);
        }
        let (diffuse_src, diffuse_first, specular_src, specular_first) = starts;
        let diffuse_chain = Chain {
            src: diffuse_src,
            first: diffuse_first,
            pair: (&images.pong, &images.ping),
            iterations: settings.iterations,
        };
        let specular_chain = split.map(|_| Chain {
            src: specular_src,
            first: specular_first,
            pair: (specular_pong, specular_ping),
            iterations: settings.specular_iterations,
        });
        let (diffuse, specular) =
            self.record_iterations(rec, images, diffuse_chain, specular_chain, &params)?;
        let specular = specular.unwrap_or(&images.pong);
        self.remodulate.record(
            rec,
            &denoise_remodulate::Resources {
                dn_in: &diffuse.view,
                dn_specular: &specular.view,
                dn_albedo: &images.albedo.view,
                dn_spec_albedo: &images.spec_albedo_or_albedo().view,
                dn_emission: &images.emission.view,
                out_color: &output,
            },
            &params(0),
            grid,
        )?;
        if let Some((_, history, camera)) = temporal {
            TemporalPass::advance(history, camera, split.is_some());
        }
        Ok(())
    }

    /// Records the à-trous iterations of `first` and, with the lobe split, of `second`: while
    /// both have iterations left one dispatch filters both (`DENOISE_BOTH`: the guide read and
    /// the normal and depth weights once for the two), then the longer goes on alone. The images
    /// that hold the results.
    fn record_iterations<'i>(
        &self,
        rec: &mut Recorder<'_>,
        images: &DenoiseImages,
        mut first: Chain<'i>,
        mut second: Option<Chain<'i>>,
        params: &dyn Fn(u32) -> DenoiseParams,
    ) -> Result<(&'i Image, Option<&'i Image>)> {
        let size = images.size;
        let rounds = first.iterations.max(second.as_ref().map_or(0, |c| c.iterations));
        for i in 0..rounds {
            // The chains with an iteration `i`: (source, destination) of each.
            let a = (i < first.iterations).then(|| (first.src, first.dst(i)));
            let b = second.as_ref().filter(|c| i < c.iterations).map(|c| (c.src, c.dst(i)));
            let (one, two) = match (a, b) {
                (Some(a), b) => (a, b),
                (None, Some(b)) => (b, None),
                (None, None) => unreachable!("a round has a chain with an iteration"),
            };
            let mut p = params(1 << i);
            if two.is_some() {
                p.flags |= DENOISE_BOTH;
            }
            // Without a second image its bindings repeat the first's (never read or written).
            let (in2, out2) = two.unwrap_or(one);
            self.atrous.record(
                rec,
                &denoise_atrous::Resources {
                    dn_in: &one.0.view,
                    dn_guide: &images.guide.view,
                    dn_samples: &images.samples.view,
                    dn_out: &one.1.view,
                    dn_in2: &in2.view,
                    dn_out2: &out2.view,
                },
                &p,
                [size.0, size.1, 1],
            )?;
            if let Some((_, dst)) = a {
                first.src = dst;
            }
            if let (Some(c), Some((_, dst))) = (second.as_mut(), b) {
                c.src = dst;
            }
        }
        Ok((first.src, second.map(|c| c.src)))
    }
}

/// One image's à-trous iterations ([`DenoisePass::record_iterations`]): where they start (the
/// prepared or the accumulated image), where the first writes if not into `pair` (the temporal
/// step's feedback image), the two images the others alternate between, and how many.
struct Chain<'i> {
    src: &'i Image,
    first: Option<&'i Image>,
    pair: (&'i Image, &'i Image),
    iterations: u32,
}

impl<'i> Chain<'i> {
    /// Where iteration `i` writes, reading `self.src`.
    fn dst(&self, i: u32) -> &'i Image {
        match self.first {
            Some(first) if i == 0 => first,
            _ if self.src.raw == self.pair.0.raw => self.pair.1,
            _ => self.pair.0,
        }
    }
}
