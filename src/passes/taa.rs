//! Anti-aliasing of the hybrid frame (`spirv/taa.comp`): each frame samples every pixel at a
//! sub-pixel offset from its centre ([`crate::scene::Camera::jitter`], which every hybrid pass
//! honours, the rasterizer included), and a resolve blends it with a per-pixel history.
//!
//! - **Supersampling** of one-shot renders ([`crate::render::HybridSettings::samples`], `umbra
//!   render --hybrid-samples N`): N still sub-frames at [`supersample_jitters`]' offsets, resolved
//!   as their running mean ([`TaaMode::Accumulate`]): the mean of N samples of each pixel's area,
//!   the box filter the path tracer's pixels integrate.
//! - **Temporal anti-aliasing** (Karis 2014; Yang, Liu and Salvi 2020) for a host's frames
//!   ([`TaaMode::Reproject`], the embedding API's [`crate::render::HybridTargets::taa`]): one
//!   sample a frame along [`TaaHistory::jitter`]'s Halton (2, 3) sequence; the point each pixel's
//!   centre sees is projected into the previous frame's camera, the history read there
//!   ([`HistoryFilter`]: a Catmull-Rom spline by default, or bilinear), clipped to the box of
//!   the frame's 3×3 neighbourhood (mean ± [`TaaSettings::clip_sigma`] standard deviations,
//!   within the neighbours' range, in YCoCg: Salvi 2016's variance clipping)
//!   and blended with weight max(1/n, [`TaaSettings::blend`]) for the frame, n the history's
//!   length: a still camera's first frames average exactly, then the blend is exponential. The
//!   colours are blended as c / (1 + luma) (Karis), so one bright sample does not ring. Where
//!   the scene's geometry moved since the history's frame ([`GeometryState`]: one
//!   [`crate::gpu::scene::GpuScene::update_geometry`] between frames), each point is first moved
//!   back by the G-buffer's `motion`; a history that missed an update starts afresh.
//!
//! The history ([`TaaHistory`]: two `R32G32B32A32_SFLOAT` images the frames alternate between,
//! and the camera of the last) holds per pixel centre the resolved radiance and the frames it
//! holds. The resolve is the next frame's history and what the tonemap reads.

use std::cell::Cell;

use crate::error::{Error, Result};
use crate::gpu::kernel::GBufferViews;
use crate::gpu::kernels::taa;
use crate::gpu::layout::{GpuCamera, TaaParams, TAA_ACCUMULATE, TAA_CATMULL_ROM, TAA_HISTORY, TAA_MOTION};
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, Image, MemoryLocation, Recorder};

/// How the resolve treats the history.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TaaMode {
    /// Still sub-frames of one image: the running mean, read at each pixel (no reprojection, no
    /// clipping).
    Accumulate,
    /// A moving view's frames: reprojected, clipped to the neighbourhood, blended.
    Reproject,
}

/// How the reprojected history is read between its texels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HistoryFilter {
    /// Bilinear over the 2×2 texels around the point: each frame that moves the view blurs the
    /// history a little, and the blur adds up over the frames.
    Bilinear,
    /// A Catmull-Rom spline over the 4×4 texels around it (Karis 2014; Jimenez 2016's filmic
    /// SMAA): interpolating and nearly free of that blur; its overshoot is clipped with the rest
    /// of the history.
    #[default]
    CatmullRom,
}

/// Temporal anti-aliasing's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaaSettings {
    /// The least weight of a frame in the blend, 0 to 1 (Karis' 0.1): smaller converges further
    /// on a still view and trails more behind motion.
    pub blend: f32,
    /// The neighbourhood box's half width in standard deviations (Salvi's 1): smaller rejects
    /// more of the history (less ghosting, more flicker).
    pub clip_sigma: f32,
    /// How the reprojected history is read.
    pub history: HistoryFilter,
}

impl Default for TaaSettings {
    fn default() -> Self {
        Self { blend: 0.1, clip_sigma: 1.0, history: HistoryFilter::default() }
    }
}

impl TaaSettings {
    /// Checks the settings: a blend weight in (0, 1], a positive finite box.
    pub fn validate(&self) -> Result<()> {
        if !(self.blend > 0.0 && self.blend <= 1.0) {
            return Err(Error::Invalid(format!("TAA blend {} must lie in (0, 1]", self.blend)));
        }
        if !(self.clip_sigma > 0.0 && self.clip_sigma.is_finite()) {
            return Err(Error::Invalid(format!(
                "TAA clip_sigma {} must be positive and finite",
                self.clip_sigma
            )));
        }
        Ok(())
    }
}

/// The radical inverse of `i` in base `b` (Halton's sequence).
fn radical_inverse(mut i: u32, b: u32) -> f32 {
    let (mut x, mut scale) = (0.0f64, 1.0f64);
    while i > 0 {
        scale /= b as f64;
        x += (i % b) as f64 * scale;
        i /= b;
    }
    x as f32
}

/// The sub-pixel offsets (pixels, each coordinate in [-0.5, 0.5)) of `n` sub-frames that
/// supersample each pixel's area: for a square n = k², the centres of a k × k grid of equal
/// cells (the 1 × 1 grid's is the pixel's centre: n = 1 is the plain render); otherwise the first
/// n points of the Halton (2, 3) sequence from index 1, less ½. Each stratifies the pixel; the
/// grid also makes n = 4 the 2 × 2 downsample of an image of twice the size, exactly.
pub fn supersample_jitters(n: u32) -> Vec<[f32; 2]> {
    let k = (n as f64).sqrt().round() as u32;
    if k * k == n {
        let cell = |i: u32| (i as f32 + 0.5) / k as f32 - 0.5;
        (0..n).map(|i| [cell(i % k), cell(i / k)]).collect()
    } else {
        (1..=n).map(|i| [radical_inverse(i, 2) - 0.5, radical_inverse(i, 3) - 0.5]).collect()
    }
}

/// Frames in [`TaaHistory::jitter`]'s cycle.
pub const TAA_JITTER_CYCLE: u32 = 8;

/// The per-pixel history of temporal anti-aliasing for one view of one size. Keep it from frame
/// to frame; move its images to `GENERAL` once ([`TaaHistory::init_general`]).
pub struct TaaHistory {
    /// Width and height.
    pub size: (u32, u32),
    /// The settings of the resolve (may change between frames).
    pub settings: TaaSettings,
    images: [Image; 2],
    prev_camera: Buffer,
    /// The frames resolved since the last reset, the image the last wrote and its camera.
    state: Cell<(u32, usize, GpuCamera)>,
    /// The scene's geometry generation at the last frame ([`GeometryState`]).
    geometry: Cell<u64>,
}

/// Where a frame's scene geometry stands, for the history to follow it: the geometry's
/// generation ([`GpuScene::geometry_generation`]) and whether the G-buffer wrote the motion that
/// led to it ([`GpuScene::geometry_moved`]). A history made at generation g follows a frame at
/// g (nothing moved) or at g + 1 with motion (each point moved back by it); any other frame
/// starts it afresh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct GeometryState {
    /// Geometry updates of the scene since its upload.
    pub generation: u64,
    /// Whether the G-buffer holds the last update's motion.
    pub moved: bool,
}

impl GeometryState {
    /// Where `scene`'s geometry stands.
    pub fn of(scene: &GpuScene) -> Self {
        Self { generation: scene.geometry_generation(), moved: scene.geometry_moved() }
    }
}

impl TaaHistory {
    /// Allocates the history (contents undefined: the first frame starts afresh).
    pub fn new(ctx: &Context, (w, h): (u32, u32), settings: TaaSettings) -> Result<Self> {
        settings.validate()?;
        let make = |name: &str| Image::storage_2d(ctx, name, w, h, raw::Format::R32G32B32A32_SFLOAT);
        let prev_camera = Buffer::new(
            ctx,
            "taa previous camera",
            std::mem::size_of::<GpuCamera>() as u64,
            raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            size: (w, h),
            settings,
            images: [make("taa history 0")?, make("taa history 1")?],
            prev_camera,
            state: Cell::new((0, 1, GpuCamera::default())),
            geometry: Cell::new(0),
        })
    }

    /// Records the move of both images from `UNDEFINED` to `GENERAL`.
    pub fn init_general(&self, ctx: &Context, cmd: raw::CommandBuffer) {
        for image in &self.images {
            image.init_general(ctx, cmd);
        }
    }

    /// Forgets the history (a cut: the next frame starts afresh, and its jitter cycle too).
    pub fn reset(&self) {
        let (_, latest, camera) = self.state.get();
        self.state.set((0, latest, camera));
    }

    /// Reads the last resolve back (submits and waits).
    pub fn read(&self, ctx: &Context) -> Result<Vec<[f32; 4]>> {
        self.resolved().read(ctx)
    }

    /// Frames resolved since the history was made or reset.
    pub fn frames(&self) -> u32 {
        self.state.get().0
    }

    /// The next frame's sub-pixel offset: the Halton (2, 3) point of index frames mod
    /// [`TAA_JITTER_CYCLE`] + 1, less ½ (pixels, each coordinate in [-0.5, 0.5)). A frame's
    /// camera is [`Camera::jittered`] by it.
    pub fn jitter(&self) -> [f32; 2] {
        let i = self.frames() % TAA_JITTER_CYCLE + 1;
        [radical_inverse(i, 2) - 0.5, radical_inverse(i, 3) - 0.5]
    }

    /// The last resolve (`R32G32B32A32_SFLOAT`, `GENERAL`): rgb the anti-aliased radiance, a the
    /// frames each pixel holds.
    pub fn resolved(&self) -> &Image {
        &self.images[self.state.get().1]
    }

    /// The image the next resolve writes (the one the last did not).
    pub(crate) fn next_view(&self) -> raw::ImageView {
        self.images[1 - self.state.get().1].view
    }

    /// An error unless the history is for images of `size`.
    pub fn check_size(&self, size: (u32, u32)) -> Result<()> {
        if self.size != size {
            return Err(Error::Invalid(format!(
                "a TAA history of {}x{} for a {}x{} frame",
                self.size.0, self.size.1, size.0, size.1
            )));
        }
        Ok(())
    }
}

/// `taa.comp`.
pub struct TaaPass {
    pipeline: Pipeline<taa::Kernel>,
}

impl TaaPass {
    /// Builds the pipeline.
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Self { pipeline: Pipeline::plain(ctx)? })
    }

    /// Records the resolve of `current` (`R32G32B32A32_SFLOAT`, the frame's radiance sampled at
    /// `camera`'s jitter, over `gbuffer`'s pixels) with `history` into its other image, which
    /// becomes [`TaaHistory::resolved`]; `geometry` says where the scene's geometry stands (the
    /// history follows one update by the G-buffer's `motion`, else starts afresh). Never
    /// submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        gbuffer: &GBufferViews,
        current: raw::ImageView,
        history: &TaaHistory,
        camera: &Camera,
        mode: TaaMode,
        geometry: GeometryState,
    ) -> Result<()> {
        history.settings.validate()?;
        history.check_size(gbuffer.size)?;
        let (mut frames, latest, prev) = history.state.get();
        let last = history.geometry.replace(geometry.generation);
        let motion = geometry.generation == last + 1 && geometry.moved;
        if geometry.generation != last && !motion {
            frames = 0;
        }
        let size = gbuffer.size;
        let camera = GpuCamera::new(camera, size);
        if frames > 0 {
            rec.update(&history.prev_camera, 0, bytemuck::bytes_of(&prev));
        }
        let next = 1 - latest;
        let flags = if frames > 0 { TAA_HISTORY } else { 0 }
            | if mode == TaaMode::Accumulate { TAA_ACCUMULATE } else { 0 }
            | if history.settings.history == HistoryFilter::CatmullRom { TAA_CATMULL_ROM } else { 0 }
            | if motion { TAA_MOTION } else { 0 };
        let params = TaaParams {
            camera,
            size: [size.0, size.1],
            flags,
            blend: history.settings.blend,
            clip_sigma: history.settings.clip_sigma,
            ..Default::default()
        };
        let resources = taa::Resources {
            current: &current,
            gb: gbuffer,
            history: &history.images[latest].view,
            resolved: &history.images[next].view,
            prev_camera: &history.prev_camera,
        };
        self.pipeline.record(rec, &resources, &params, [size.0, size.1, 1])?;
        history.state.set((frames.saturating_add(1), next, camera));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_counts_are_grids_and_the_others_halton() {
        assert_eq!(supersample_jitters(1), vec![[0.0, 0.0]]);
        assert_eq!(supersample_jitters(4), vec![[-0.25, -0.25], [0.25, -0.25], [-0.25, 0.25], [0.25, 0.25]]);
        // Halton (2, 3) from index 1: (1/2, 1/3), (1/4, 2/3), (3/4, 1/9).
        let h = supersample_jitters(3);
        let expected = [[0.0, 1.0 / 3.0 - 0.5], [-0.25, 2.0 / 3.0 - 0.5], [0.25, 1.0 / 9.0 - 0.5]];
        for (a, b) in h.iter().zip(expected) {
            assert!((a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6, "{a:?} vs {b:?}");
        }
        for n in 1..=32 {
            let j = supersample_jitters(n);
            assert_eq!(j.len(), n as usize);
            assert!(j.iter().flatten().all(|x| (-0.5..0.5).contains(x)), "{n}: {j:?}");
        }
    }
}
