//! The denoiser's temporal accumulation with reprojection (SVGF's temporal part, Schied et al.
//! 2017), for a host that path traces a few samples per frame while its camera moves: each
//! frame's prepared (demodulated) radiance is blended with the history reprojected from the
//! previous frame, then filtered by the à-trous iterations as before ([`crate::passes::denoise`]).
//!
//! The history ([`TemporalHistory`], two slots the frames alternate between) holds per pixel the
//! demodulated colour (both parts of the lobe split when the target has it) and its variance, the
//! first and second moments of each part's luminance, the frame's normal and distance, the
//! history's length, and what the remodulation multiplies and adds back: each part's divisor (the
//! first hit's albedo) and the first hit's emission. These are blended like the colour, and the
//! colour is the blend of the numerators (colour × divisor) over the blended divisor: a frame of
//! one sample a pixel sees one side of a sub-pixel edge (the path tracer jitters its first hits),
//! and remodulating with that frame's divisor and emission alone made edge pixels flicker (an
//! emitter's rim, the spikes of BENCHMARKS.md's temporal table; docs/history/2026-12-03.md, "where
//! the temporal denoiser's spikes lie"). umbra keeps the previous frame's camera in the history
//! (the host passes only the frame's camera): each frame's first hits (the ray through the pixel's
//! centre at the first sample's distance) are projected into it, and the four history pixels around
//! the projection (bilinear) count when their normal and depth agree
//! (`spirv/denoise_temporal.comp`; no mesh id: the path target does not record one). The blend
//! weight is max(1/n, α) for the colour and for the moments, n the history's length (SVGF's α =
//! 0.2). From four frames on, the variance the à-trous' luminance weight reads is the temporal
//! moments'; before, the variance carried through the blend with the filter's spatial floor.
//!
//! What is fed back as the next frame's history is by default the accumulated colour
//! ([`TemporalFeedback::Accumulated`]: a still camera then converges to the mean of all the
//! frames' samples, filtered once), or SVGF's choice, the output of the first à-trous
//! iteration ([`TemporalFeedback::FirstIteration`]), whose blur compounds from frame to frame
//! (measured: [`TemporalFeedback`]).
//!
//! The history starts afresh (every pixel) after [`TemporalHistory::reset`], at its first
//! frame, when the lobe split is turned on or off, and, through the embedding API, after
//! [`crate::embed::Renderer::update_scene`]; a new size needs a new history.

use crate::error::{Error, Result};
use crate::gpu::kernels::denoise_temporal;
use crate::gpu::layout::{
    GpuCamera, TemporalParams, TEMPORAL_HISTORY, TEMPORAL_ORTHOGRAPHIC, TEMPORAL_PREV_ORTHOGRAPHIC,
    TEMPORAL_SPLIT,
};
use crate::gpu::Pipeline;
use crate::passes::denoise::DenoiseImages;
use crate::vk::{raw, Context, Image, Recorder};

/// What the history keeps of a frame for the next.
///
/// umbra's default is the accumulated colour, not SVGF's first iteration: on a plane with bands
/// of light 8 pixels wide (tests/temporal.rs, 64², 1 spp a frame, still camera) the first
/// iteration's blur compounds frame after frame and the MSE stalls at 8.2e-3 from the fourth
/// frame on (with α = 0 it even rises again, to 1.3e-2 at 16 frames), while the accumulated
/// colour reaches 3.4e-3 at 16 frames (one frame filtered alone: 1.3e-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TemporalFeedback {
    /// The first à-trous iteration's output (SVGF): a smoother history, whose blur compounds
    /// over the frames.
    FirstIteration,
    /// The accumulated colour before filtering: a still camera converges to the mean of every
    /// frame's samples, filtered once.
    #[default]
    Accumulated,
}

/// The temporal accumulation's settings (SVGF's values by default, but for the feedback).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemporalSettings {
    /// The colour's least blend weight, 0 to 1 (0: the running mean of every frame).
    pub alpha: f32,
    /// The luminance moments' least blend weight, 0 to 1.
    pub alpha_moments: f32,
    /// History length (frames) from which the temporal variance is used, at least 1.
    pub variance_frames: u32,
    /// A history tap counts when the cosine of its normal with the pixel's is at least this.
    pub normal_tolerance: f32,
    /// A history tap counts when its point lies within this × the distance (plus two pixel
    /// footprints, the first sample's jitter) of the pixel's tangent plane.
    pub depth_tolerance: f32,
    /// What the next frame's history is.
    pub feedback: TemporalFeedback,
}

impl Default for TemporalSettings {
    fn default() -> Self {
        Self {
            alpha: 0.2,
            alpha_moments: 0.2,
            variance_frames: 4,
            normal_tolerance: 0.9,
            depth_tolerance: 0.01,
            feedback: TemporalFeedback::Accumulated,
        }
    }
}

impl TemporalSettings {
    /// Checks the settings: weights and the normal tolerance in range, a finite non-negative
    /// depth tolerance, at least one frame for the temporal variance.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [("alpha", self.alpha), ("alpha_moments", self.alpha_moments)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(Error::Invalid(format!(
                    "temporal denoiser {name} {value} must be between 0 and 1"
                )));
            }
        }
        if !(-1.0..=1.0).contains(&self.normal_tolerance) {
            return Err(Error::Invalid(format!(
                "temporal denoiser normal_tolerance {} must be a cosine, -1 to 1",
                self.normal_tolerance
            )));
        }
        if !(self.depth_tolerance.is_finite() && self.depth_tolerance >= 0.0) {
            return Err(Error::Invalid(format!(
                "temporal denoiser depth_tolerance {} must be finite and not negative",
                self.depth_tolerance
            )));
        }
        if self.variance_frames == 0 {
            return Err(Error::Invalid("temporal denoiser variance_frames must be at least 1".into()));
        }
        Ok(())
    }
}

/// One frame's history (`R32G32B32A32_SFLOAT` images).
pub struct HistorySlot {
    /// Demodulated colour (the diffuse part with the lobe split) and its variance.
    pub color: Image,
    /// The lobe split's specular part and its variance.
    pub specular: Image,
    /// Luminance moments: diffuse `E[l]`, `E[l²]`, specular `E[l]`, `E[l²]`.
    pub moments: Image,
    /// The frame's unit normal and distance (−1 for a miss).
    pub guide: Image,
    /// History length in frames, sum of the colour's blend weights squared.
    pub state: Image,
    /// What the colour (diffuse part) is divided by: the blended divisors of the frames.
    pub albedo: Image,
    /// What the specular part is divided by, likewise.
    pub spec_albedo: Image,
    /// The first hit's emission, blended.
    pub emission: Image,
}

/// The per-pixel history of the temporal denoiser, for one view of one size: two slots, the
/// frame's camera and settings. Keep it from frame to frame; move its images to `GENERAL` once
/// ([`TemporalHistory::init_general`]).
pub struct TemporalHistory {
    /// Width and height.
    pub size: (u32, u32),
    /// The accumulation's settings (may change between frames).
    pub settings: TemporalSettings,
    slots: [HistorySlot; 2],
    /// The slot the last frame wrote.
    latest: usize,
    /// The last frame's camera and whether it had the lobe split; `None`: start afresh.
    previous: Option<(GpuCamera, bool)>,
    /// The renderer's scene generation the history was made under (embedding API).
    pub(crate) generation: u64,
}

impl TemporalHistory {
    /// Allocates the history (contents undefined: the first frame starts afresh).
    pub fn new(ctx: &Context, (w, h): (u32, u32), settings: TemporalSettings) -> Result<Self> {
        settings.validate()?;
        let make = |name: &str| Image::storage_2d(ctx, name, w, h, raw::Format::R32G32B32A32_SFLOAT);
        let slot = |i: usize| -> Result<HistorySlot> {
            Ok(HistorySlot {
                color: make(&format!("history {i} colour"))?,
                specular: make(&format!("history {i} specular"))?,
                moments: make(&format!("history {i} moments"))?,
                guide: make(&format!("history {i} guide"))?,
                state: make(&format!("history {i} state"))?,
                albedo: make(&format!("history {i} albedo"))?,
                spec_albedo: make(&format!("history {i} specular albedo"))?,
                emission: make(&format!("history {i} emission"))?,
            })
        };
        Ok(Self {
            size: (w, h),
            settings,
            slots: [slot(0)?, slot(1)?],
            latest: 0,
            previous: None,
            generation: 0,
        })
    }

    /// Records the move of every image from `UNDEFINED` to `GENERAL`.
    pub fn init_general(&self, ctx: &Context, cmd: raw::CommandBuffer) {
        for slot in &self.slots {
            for image in [
                &slot.color,
                &slot.specular,
                &slot.moments,
                &slot.guide,
                &slot.state,
                &slot.albedo,
                &slot.spec_albedo,
                &slot.emission,
            ] {
                image.init_general(ctx, cmd);
            }
        }
    }

    /// Forgets the history: the next frame starts afresh (a cut, a changed scene).
    pub fn reset(&mut self) {
        self.previous = None;
    }

    /// Whether the next frame has a history to blend with.
    pub fn has_history(&self) -> bool {
        self.previous.is_some()
    }

    /// The slot the last frame wrote.
    pub fn latest(&self) -> &HistorySlot {
        &self.slots[self.latest]
    }

    /// Reads each pixel's history length (frames) from the last frame's slot. Waits for the GPU:
    /// call while no command buffer writing the history is pending.
    pub fn lengths(&self, ctx: &Context) -> Result<Vec<f32>> {
        let state: Vec<[f32; 4]> = self.latest().state.read(ctx)?;
        Ok(state.iter().map(|s| s[0]).collect())
    }
}

/// Where a frame's temporal step writes: the images the à-trous iterations start from and, for
/// [`TemporalFeedback::FirstIteration`], where their first iteration writes (the history's).
pub(crate) struct TemporalOutputs<'a> {
    pub diffuse: &'a Image,
    pub diffuse_first: Option<&'a Image>,
    pub specular: &'a Image,
    pub specular_first: Option<&'a Image>,
}

/// The temporal step's pipeline.
pub struct TemporalPass {
    pipeline: Pipeline<denoise_temporal::Kernel>,
}

impl TemporalPass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records the blend of the prepared frame in `images` (diffuse part in `ping`, specular in
    /// the specular ping when `split`) with `history`, seen by `camera`, into the next slot of
    /// `history` and `images` as [`TemporalOutputs`] says (with the à-trous iteration counts
    /// `iterations` of the two parts). The caller calls
    /// [`TemporalPass::advance`] once the frame is recorded.
    pub(crate) fn record<'a>(
        &self,
        rec: &mut Recorder<'_>,
        images: &'a DenoiseImages,
        history: &'a TemporalHistory,
        camera: &GpuCamera,
        split: bool,
        iterations: (u32, u32),
    ) -> Result<TemporalOutputs<'a>> {
        let settings = &history.settings;
        settings.validate()?;
        if history.size != images.size || (camera.image_width, camera.image_height) != images.size {
            return Err(Error::Invalid(format!(
                "the temporal history is {:?} and the camera's image {:?}, but the image to denoise is {:?} \
                 (make a new history for a new size)",
                history.size,
                (camera.image_width, camera.image_height),
                images.size
            )));
        }
        let previous = history.previous.filter(|(_, had_split)| *had_split == split);
        let prev = &history.slots[history.latest];
        let next = &history.slots[1 - history.latest];
        let (spec_ping, spec_pong) = match (&images.specular, split) {
            (Some((ping, pong)), true) => (ping, pong),
            _ => (&images.guide, &next.specular),
        };
        let first = settings.feedback == TemporalFeedback::FirstIteration;
        let outputs = TemporalOutputs {
            diffuse: if first { &images.pong } else { &next.color },
            diffuse_first: first.then_some(&next.color),
            specular: if first && iterations.1 > 0 { spec_pong } else { &next.specular },
            specular_first: (first && iterations.1 > 0).then_some(&next.specular),
        };
        let prev_camera = previous.map_or(*camera, |(c, _)| c);
        let flags = if previous.is_some() { TEMPORAL_HISTORY } else { 0 }
            | if split { TEMPORAL_SPLIT } else { 0 }
            | if camera.orthographic() { TEMPORAL_ORTHOGRAPHIC } else { 0 }
            | if prev_camera.orthographic() { TEMPORAL_PREV_ORTHOGRAPHIC } else { 0 };
        let params = TemporalParams {
            origin: camera.origin,
            flags,
            forward: camera.forward,
            alpha: settings.alpha,
            right: camera.right,
            alpha_moments: settings.alpha_moments,
            up: camera.up,
            depth_tolerance: settings.depth_tolerance,
            prev_origin: prev_camera.origin,
            normal_tolerance: settings.normal_tolerance,
            prev_forward: prev_camera.forward,
            width: images.size.0,
            prev_right: prev_camera.right,
            height: images.size.1,
            prev_up: prev_camera.up,
            variance_frames: settings.variance_frames as f32,
        };
        self.pipeline.record(
            rec,
            &denoise_temporal::Resources {
                dn_color: &images.ping.view,
                dn_specular: &spec_ping.view,
                dn_guide: &images.guide.view,
                dn_samples: &images.samples.view,
                dn_albedo: &images.albedo.view,
                dn_spec_albedo: &images.spec_albedo_or_albedo().view,
                dn_emission: &images.emission.view,
                hist_color: &prev.color.view,
                hist_specular: &prev.specular.view,
                hist_moments: &prev.moments.view,
                hist_guide: &prev.guide.view,
                hist_state: &prev.state.view,
                hist_albedo: &prev.albedo.view,
                hist_spec_albedo: &prev.spec_albedo.view,
                hist_emission: &prev.emission.view,
                out_color: &outputs.diffuse.view,
                out_specular: &outputs.specular.view,
                out_moments: &next.moments.view,
                out_guide: &next.guide.view,
                out_state: &next.state.view,
                out_albedo: &next.albedo.view,
                out_spec_albedo: &next.spec_albedo.view,
                out_emission: &next.emission.view,
            },
            &params,
            [images.size.0, images.size.1, 1],
        )?;
        Ok(outputs)
    }

    /// Makes the slot the frame just recorded wrote the history of the next, seen by `camera`.
    pub(crate) fn advance(history: &mut TemporalHistory, camera: &GpuCamera, split: bool) {
        history.latest = 1 - history.latest;
        history.previous = Some((*camera, split));
    }
}
