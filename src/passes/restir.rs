//! ReSTIR DI (Bitterli et al. 2020, "Spatiotemporal reservoir resampling for real-time ray
//! tracing with dynamic direct lighting") for the hybrid renderer's direct light, a setting beside
//! power-sampled light sampling ([`crate::passes::deferred::DirectLight`]). Per G-buffer pixel and
//! frame:
//!
//! 1. **Candidates** (`restir_initial.comp`): [`RestirSettings::candidates`] light samples — a
//!    point on an emissive triangle (the table by power) or a punctual light (by power), the two
//!    pools half and half where the scene has both — resampled into one by RIS with the target
//!    function p̂ = luminance of the unshadowed contribution f·cos·Lₑ·G.
//! 2. **Temporal reuse** (same kernel, [`RestirSettings::temporal`]): the previous frame's
//!    reservoir at the point's reprojected pixel (the previous camera), where it was built for a
//!    similar surface (view depth within 10 %, normals within about 25°), its count capped at
//!    [`RestirSettings::history_cap`] × the candidates.
//! 3. **Spatial reuse** (`restir_spatial.comp`): [`RestirSettings::neighbours`] random pixels
//!    within [`RestirSettings::radius`] whose surfaces are similar.
//! 4. **Shading** (`deferred.comp`): the reservoir's one sample with one shadow ray, times its
//!    unbiased contribution weight W.
//!
//! Two combinations ([`RestirSettings::unbiased`]):
//! - **biased** (the default, Bitterli et al.'s fast one): after step 1 the kept sample's shadow
//!   ray is traced and an occluded sample loses its weight (visibility reuse), and merged
//!   reservoirs are normalised by their total count (1/M). Bias: a neighbour's or the history's
//!   visibility and domain stand in for the pixel's own, so shadows bleed a little across
//!   edges and where the neighbours' surfaces differ; it darkens or brightens by a few percent
//!   where visibility changes within the neighbourhood (measured in BENCHMARKS.md's restir
//!   table, analysed in docs/history/2026-12-02.md).
//! - **unbiased**: no visibility before shading (p̂ has none), and merged reservoirs are
//!   normalised by the counts of only those reservoirs whose surface could have produced the kept
//!   sample (p̂ > 0 there: the 1/Z of Bitterli et al.'s algorithm 6). Unbiased for a static camera
//!   and scene; under motion the history's domain is approximated by this frame's surface at its
//!   reprojected pixel. Noisier in shadows: occluded samples keep their weight.
//!
//! The passes record into the host's command buffer like every other; the reservoirs live in
//! [`Reservoirs`], which the caller keeps from frame to frame (its history) and passes to the
//! lighting pass.

use crate::error::{Error, Result};
use crate::gpu::kernels::{restir_initial, restir_spatial};
use crate::gpu::layout::{GpuCamera, GpuReservoir, RestirParams};
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::passes::gbuffer::GBufferViews;
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, MemoryLocation, Recorder};
use std::cell::Cell;

/// ReSTIR DI's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestirSettings {
    /// Candidates resampled per pixel and frame (M).
    pub candidates: u32,
    /// Reuse the previous frame's reservoirs.
    pub temporal: bool,
    /// Neighbours merged per pixel (0: no spatial reuse).
    pub neighbours: u32,
    /// Radius of the spatial neighbourhood, pixels. Small: neighbours further away see other
    /// occluders, and the biased combination darkens the more (docs/history/2026-12-02.md, fourth session: on
    /// many-lights.glb at 192², −3 % at 3 pixels, −10 % at 10, −13 % at 30).
    pub radius: f32,
    /// A reused reservoir counts at most this many times `candidates` (the history's weight
    /// against a new frame's: Bitterli et al. use 20).
    pub history_cap: f32,
    /// The unbiased combination (else the biased one with visibility reuse).
    pub unbiased: bool,
    /// Frames a one-shot render ([`crate::render::Passes::hybrid`], `umbra render`) runs with a
    /// still camera, showing the last: the history temporal reuse builds on. An embedding host
    /// records its own frames and ignores this.
    pub frames: u32,
}

impl Default for RestirSettings {
    fn default() -> Self {
        Self {
            candidates: 32,
            temporal: true,
            neighbours: 5,
            radius: 10.0,
            history_cap: 20.0,
            unbiased: false,
            frames: 8,
        }
    }
}

impl RestirSettings {
    /// Most candidates per pixel (one invocation evaluates them all; llvmpipe ends an
    /// invocation's loops after 65,535 iterations in all).
    pub const MAX_CANDIDATES: u32 = 256;
    /// Most spatial neighbours per pixel (the kernel's array).
    pub const MAX_NEIGHBOURS: u32 = 8;

    /// An error naming the setting out of range.
    pub fn validate(&self) -> Result<()> {
        let fail = |what: String| Err(Error::Invalid(format!("ReSTIR: {what}")));
        if self.candidates == 0 || self.candidates > Self::MAX_CANDIDATES {
            return fail(format!(
                "{} candidates per pixel: must be 1 to {}",
                self.candidates,
                Self::MAX_CANDIDATES
            ));
        }
        if self.neighbours > Self::MAX_NEIGHBOURS {
            return fail(format!(
                "{} spatial neighbours: must be 0 to {}",
                self.neighbours,
                Self::MAX_NEIGHBOURS
            ));
        }
        if !(self.radius.is_finite() && self.radius >= 1.0) {
            return fail(format!("spatial radius {} pixels: must be at least 1", self.radius));
        }
        if !(self.history_cap.is_finite() && self.history_cap >= 1.0) {
            return fail(format!("history cap {}: must be at least 1", self.history_cap));
        }
        if self.frames == 0 {
            return fail("0 frames: a render needs at least one".into());
        }
        Ok(())
    }
}

/// The reservoirs of one image size: this frame's before spatial reuse, and the frame's result
/// (which the lighting pass shades and the next frame reuses), with the camera they were made
/// for. Keep one per view from frame to frame.
pub struct Reservoirs {
    /// Width and height.
    pub size: (u32, u32),
    /// The candidates' (and history's) reservoirs, before spatial reuse.
    initial: Buffer,
    /// The frame's reservoirs.
    frame: Buffer,
    /// The camera `frame` was made for.
    prev_camera: Buffer,
    /// Whether `frame` holds a previous frame's reservoirs (and for which camera).
    history: Cell<Option<GpuCamera>>,
}

impl Reservoirs {
    /// Reservoirs for images of `size`, with no history.
    pub fn new(ctx: &Context, size: (u32, u32)) -> Result<Self> {
        let bytes = size.0 as u64 * size.1 as u64 * std::mem::size_of::<GpuReservoir>() as u64;
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER
            | raw::BufferUsageFlags::TRANSFER_DST
            | raw::BufferUsageFlags::TRANSFER_SRC;
        let make = |name| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        let prev_camera = Buffer::new(
            ctx,
            "restir previous camera",
            std::mem::size_of::<GpuCamera>() as u64,
            raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            size,
            initial: make("restir reservoirs")?,
            frame: make("restir frame reservoirs")?,
            prev_camera,
            history: Cell::new(None),
        })
    }

    /// Forgets the history (a cut: the next frame starts afresh).
    pub fn reset(&self) {
        self.history.set(None);
    }

    /// An error unless they are for images of `size` (the G-buffer's).
    pub fn check_size(&self, size: (u32, u32)) -> Result<()> {
        if self.size != size {
            return Err(Error::Invalid(format!(
                "ReSTIR reservoirs of {}x{} for a {}x{} G-buffer",
                self.size.0, self.size.1, size.0, size.1
            )));
        }
        Ok(())
    }

    /// The frame's reservoirs (read by the lighting pass).
    pub fn frame(&self) -> &Buffer {
        &self.frame
    }

    /// Reads the frame's reservoirs back (tests).
    pub fn read(&self, ctx: &Context) -> Result<Vec<GpuReservoir>> {
        self.frame.read(ctx)
    }
}

/// The two ReSTIR kernels, specialised for a scene and a combination.
pub struct RestirPass {
    initial: Pipeline<restir_initial::Kernel>,
    spatial: Pipeline<restir_spatial::Kernel>,
    unbiased: bool,
    temporal: bool,
}

impl RestirPass {
    /// The pipelines for `scene`, the combination (`unbiased`) and whether frames reuse their
    /// history (`temporal`).
    pub fn new(ctx: &Context, scene: &GpuScene, unbiased: bool, temporal: bool) -> Result<Self> {
        Ok(Self {
            initial: Pipeline::for_scene(
                ctx,
                scene,
                &restir_initial::Spec { beckmann: false, unbiased, temporal },
            )?,
            spatial: Pipeline::for_scene(ctx, scene, &restir_spatial::Spec { beckmann: false, unbiased })?,
            unbiased,
            temporal,
        })
    }

    /// Records one frame's reservoirs for the G-buffer seen by `camera` into `reservoirs` (its
    /// size), reusing their history when `settings.temporal`. `frame` and `seed` pick the random numbers. Never submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        reservoirs: &Reservoirs,
        settings: &RestirSettings,
        frame: u32,
        seed: u32,
    ) -> Result<()> {
        settings.validate()?;
        if settings.unbiased != self.unbiased || settings.temporal != self.temporal {
            return Err(Error::Invalid("the ReSTIR pass was built for other settings".into()));
        }
        reservoirs.check_size(gbuffer.size)?;
        let size = gbuffer.size;
        let history = reservoirs.history.get();
        if let Some(prev) = history {
            // The previous camera for reprojection (GpuCamera is 64 bytes: within
            // vkCmdUpdateBuffer's limits).
            rec.update(&reservoirs.prev_camera, 0, bytemuck::bytes_of(&prev));
        }
        let gpu_camera = GpuCamera::new(camera, size);
        let params = RestirParams {
            camera: gpu_camera,
            size: [size.0, size.1],
            frame,
            seed,
            light_count: scene.light_count,
            punctual_count: scene.punctual_count,
            candidates: settings.candidates,
            neighbours: settings.neighbours,
            radius: settings.radius,
            history_cap: settings.history_cap,
            history: (settings.temporal && history.is_some()) as u32,
            ..Default::default()
        };
        let initial = restir_initial::Resources {
            scene,
            gb: gbuffer,
            prev_camera: &reservoirs.prev_camera,
            history: &reservoirs.frame,
            reservoirs: &reservoirs.initial,
        };
        self.initial.record(rec, &initial, &params, [size.0, size.1, 1])?;
        let spatial = restir_spatial::Resources {
            scene,
            gb: gbuffer,
            reservoirs_in: &reservoirs.initial,
            reservoirs_out: &reservoirs.frame,
        };
        self.spatial.record(rec, &spatial, &params, [size.0, size.1, 1])?;
        reservoirs.history.set(Some(gpu_camera));
        Ok(())
    }
}
