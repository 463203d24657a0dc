//! The orchestrator. [`Passes`] owns the pipelines of every pass for one scene's features and
//! renders with them, in three files, one per job:
//! - `pipelines.rs`: each pipeline built once, on first use or ahead of it, cached by what
//!   specialises it;
//! - `frame.rs` and `record.rs`: recording into a command buffer, never submitting: umbra's
//!   passes in a frame graph, one `add_*` each, and the hybrid frame wired from them (G-buffer →
//!   SSAO → blur → deferred lighting → tonemap, [`Passes::add_hybrid`]); ambient occlusion,
//!   the lighting, the progressive path tracer, the denoiser;
//! - `oneshot.rs`: the one-shot renders and bakes ([`Passes::hybrid`], [`Passes::path_trace`],
//!   [`Passes::ambient_occlusion`], ...), which allocate the images, submit in batches and read
//!   back linear images; the free functions of the same names build a [`Passes`] for one render.
//!
//! The CLI, umbra-bench and the embedding API ([`crate::embed::Renderer`]) all go through it.
//! Dependencies run one way: the passes (`crate::passes`) know neither this module nor the
//! embedding API; this module knows the passes; the embedding API knows both
//! (tests/modules.rs keeps it so).

use crate::error::{Error, Result};
use crate::gpu::cache::Cache;
use crate::gpu::kernels::deferred;
use crate::gpu::layout::{GpuCamera, PathStats};
use crate::gpu::scene::GpuScene;
use crate::gpu::SceneFeatures;
use crate::passes::ao::{ao_params, AoBlurPass, AoSettings, GtaoPass, RtaoPass, SsaoPass};
use crate::passes::deferred::{DeferredPass, LightingInputs, LightingSettings, SizedLights};
pub use crate::passes::denoise::DenoiseSettings;
use crate::passes::denoise::{DenoiseImages, DenoiseInputs, DenoisePass};
use crate::passes::gbuffer::{GBuffer, GBufferData, GBufferImages, GBufferPass, GBufferViews};
use crate::passes::ibl::{IblResources, IblSettings};
use crate::passes::lightmap::{
    GpuLightmaps, LightmapLayout, LightmapPass, LightmapSettings, Lightmaps, OcclusionMaps,
};
pub use crate::passes::pathtrace::PathSettings;
use crate::passes::pathtrace::{Integrator, PathOptions, PathTarget, PathTracePass, ResolvePass};
use crate::passes::probes::{ProbePass, ProbeVolume};
use crate::passes::restir::{Reservoirs, RestirPass, RestirSettings};
use crate::passes::shadow::{ShadowMaps, ShadowMethod, ShadowPass, ShadowPlan, ShadowSettings, ShadowView};
use crate::passes::taa::{supersample_jitters, GeometryState, TaaHistory, TaaMode, TaaPass};
pub use crate::passes::temporal::{TemporalFeedback, TemporalSettings};
use crate::passes::temporal::{TemporalHistory, TemporalPass};
use crate::passes::tonemap::{ToneCurve, TonemapPass};
use crate::passes::visibility::VisibilityPass;
pub use crate::passes::visibility::{GBufferMethod, VisibilityBuffer};
use crate::passes::wavefront::WavefrontPass;
use crate::scene::Camera;
use crate::vk::{
    raw, Buffer, Context, GpuTimer, Graph, GraphImage, GraphStats, Image, ImageDesc, Recorder, TransientPool,
};
use std::sync::OnceLock;

mod frame;
mod oneshot;
mod pipelines;
mod record;

pub use frame::stage_of;
pub use oneshot::{ambient_occlusion, denoise, denoise_temporal, hybrid, path_trace};
pub use pipelines::Passes;

/// A path-traced image, linear, row-major from the top left.
#[derive(Debug, Clone)]
pub struct PathImage {
    /// Width and height.
    pub size: (u32, u32),
    /// Samples per pixel accumulated (fewer than asked when a target error was reached).
    pub spp: u32,
    /// Mean radiance rgb, and the sample count in alpha.
    pub mean: Vec<[f32; 4]>,
    /// Mean of the squared samples rgb.
    pub moment: Vec<[f32; 4]>,
    /// Base colour at the first hit, mean over the samples (alpha: the fraction that hit).
    pub albedo: Vec<[f32; 4]>,
    /// Shading normal and distance at the first hit of sample 0.
    pub normal_depth: Vec<[f32; 4]>,
    /// Radiance emitted at the first hit (or the environment seen), mean over the samples.
    pub emission: Vec<[f32; 4]>,
    /// With [`PathSettings::lobe_split`]: the split's per-pixel `specular` and `split`
    /// ([`crate::passes::pathtrace::LobeSplit`]), which the denoiser reads.
    pub lobe_split: Option<LobeSplitImage>,
    /// Samples that came out non-finite (replaced by zero); 0 unless something is wrong.
    pub nonfinite_samples: u32,
    /// Where they arose (see [`crate::gpu::layout::nonfinite_source_names`]).
    pub nonfinite_sources: u32,
    /// GPU time of all the path-tracing dispatches, in milliseconds.
    pub gpu_ms: f64,
    /// Path segments traced (closest-hit rays: camera rays and their continuations), over all
    /// samples.
    pub segments: u64,
    /// Implicit-shape marches that ran out of steps and were taken as misses
    /// ([`crate::gpu::layout::PathStats::marches_exhausted`]); 0 without implicit shapes.
    pub marches_exhausted: u32,
}

/// A path-traced image's lobe split, read back ([`crate::passes::pathtrace::LobeSplit`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LobeSplitImage {
    /// Mean of the specular part rgb; mean of the diffuse part's demodulated luminance squared.
    pub specular: Vec<[f32; 4]>,
    /// Mean of the specular albedo rgb; mean of the specular part's demodulated luminance
    /// squared.
    pub split: Vec<[f32; 4]>,
}

impl PathImage {
    /// The image's estimated relative error: √(relative MSE), the relative MSE being the mean
    /// over pixels and channels of var(pixel mean) / (pixel mean² + 0.01), the usual metric of
    /// the denoising literature (bright and dark regions count alike). The variance is estimated
    /// as if a pixel's samples were independent; the path tracer's are stratified (low-discrepancy
    /// numbers), whose mean varies less, so this over-estimates the error (at 64-256 spp the true
    /// relative MSE of the Cornell box and DamagedHelmet was 0.5-0.6 of independent samples').
    /// Where the error has a heavy tail (rare bright paths a render's samples mostly miss), one
    /// render's estimate is usually low, with either sampler (tests/pathtrace/).
    pub fn relative_error(&self) -> f32 {
        relative_error(&self.mean, &self.moment, self.spp)
    }

    /// Per pixel, the estimated variance of the mean rgb (sample variance / n).
    pub fn variance_of_mean(&self) -> Vec<[f32; 3]> {
        self.mean.iter().zip(&self.moment).map(|(m, s)| pixel_variance_of_mean(m, s, self.spp)).collect()
    }
}

/// A pixel's variance of the mean rgb from its running mean and second moment after `spp`
/// samples: the unbiased sample variance n/(n−1)·(E[x²] − E[x]²), divided by n.
fn pixel_variance_of_mean(mean: &[f32; 4], moment: &[f32; 4], spp: u32) -> [f32; 3] {
    let n = spp.max(2) as f32;
    [0, 1, 2].map(|c| (moment[c] - mean[c] * mean[c]).max(0.0) / (n - 1.0))
}

fn relative_error(mean: &[[f32; 4]], moment: &[[f32; 4]], spp: u32) -> f32 {
    let mut rel_mse = 0.0f64;
    for (m, s) in mean.iter().zip(moment) {
        for (c, var) in pixel_variance_of_mean(m, s, spp).into_iter().enumerate() {
            rel_mse += var as f64 / ((m[c] as f64).powi(2) + RELATIVE_EPSILON);
        }
    }
    (rel_mse / (mean.len().max(1) * 3) as f64).sqrt() as f32
}

/// The ε of the relative MSE, var / (mean² + ε): keeps dark pixels from dominating.
const RELATIVE_EPSILON: f64 = 0.01;

/// A denoised path-traced image ([`Passes::denoise`]).
#[derive(Debug, Clone)]
pub struct DenoisedImage {
    /// Width and height.
    pub size: (u32, u32),
    /// Denoised radiance rgb, alpha 1, row-major from the top left.
    pub color: Vec<[f32; 4]>,
    /// GPU time of the filter, in milliseconds.
    pub gpu_ms: f64,
}

/// One frame denoised with temporal accumulation ([`Passes::denoise_temporal`]).
#[derive(Debug, Clone)]
pub struct TemporalFrame {
    /// Denoised radiance rgb, alpha 1, row-major from the top left.
    pub color: Vec<[f32; 4]>,
    /// Each pixel's history length after the frame (frames; 1: it started afresh).
    pub history_length: Vec<f32>,
    /// GPU time of the filter, in milliseconds.
    pub gpu_ms: f64,
}

/// A path-traced image's buffers uploaded for the denoiser.
struct UploadedImage {
    size: (u32, u32),
    accum: Buffer,
    moment: Buffer,
    albedo: Buffer,
    normal_depth: Buffer,
    emission: Buffer,
    lobe_split: Option<(Buffer, Buffer)>,
}

impl UploadedImage {
    /// Uploads `image`: an error naming the buffer whose length is not the image's.
    fn new(ctx: &Context, image: &PathImage) -> Result<Self> {
        let (w, h) = image.size;
        let pixels = w as usize * h as usize;
        let (specular_len, split_len) =
            image.lobe_split.as_ref().map_or((pixels, pixels), |l| (l.specular.len(), l.split.len()));
        for (name, len) in [
            ("mean", image.mean.len()),
            ("moment", image.moment.len()),
            ("albedo", image.albedo.len()),
            ("normal_depth", image.normal_depth.len()),
            ("emission", image.emission.len()),
            ("lobe split's specular", specular_len),
            ("lobe split's split", split_len),
        ] {
            if len != pixels {
                return Err(Error::Invalid(format!(
                    "the image to denoise is {w}x{h} but its {name} has {len} pixels"
                )));
            }
        }
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            size: image.size,
            accum: Buffer::upload(ctx, "denoise mean", &image.mean, usage)?,
            moment: Buffer::upload(ctx, "denoise moment", &image.moment, usage)?,
            albedo: Buffer::upload(ctx, "denoise albedo", &image.albedo, usage)?,
            normal_depth: Buffer::upload(ctx, "denoise normal depth", &image.normal_depth, usage)?,
            emission: Buffer::upload(ctx, "denoise emission", &image.emission, usage)?,
            lobe_split: match &image.lobe_split {
                Some(l) => Some((
                    Buffer::upload(ctx, "denoise specular", &l.specular, usage)?,
                    Buffer::upload(ctx, "denoise split", &l.split, usage)?,
                )),
                None => None,
            },
        })
    }

    fn inputs(&self) -> DenoiseInputs<'_> {
        DenoiseInputs {
            size: self.size,
            accum: &self.accum,
            moment: &self.moment,
            albedo: &self.albedo,
            normal_depth: &self.normal_depth,
            emission: &self.emission,
            lobe_split: self.lobe_split.as_ref().map(|(a, b)| (a, b)),
        }
    }
}

/// Settings of a hybrid (deferred) render.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HybridSettings {
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// How the G-buffer finds each pixel's first surface: rasterized where the device and the
    /// scene allow ([`VisibilityBuffer::unsupported`]), else ray-cast.
    pub gbuffer: GBufferMethod,
    /// The lighting pass's settings.
    pub lighting: LightingSettings,
    /// Exposure of the display image, in stops.
    pub exposure: f32,
    /// Tone curve of the display image.
    pub curve: ToneCurve,
    /// The image-based lighting precomputation.
    pub ibl: IblSettings,
    /// SSAO (and its blur) multiplying the image-based (ambient) light; `None`: no occlusion.
    pub ao: Option<AoSettings>,
    /// How punctual lights are shadowed (shadow rays by default, or shadow maps).
    pub shadows: ShadowSettings,
    /// Sub-frames of a one-shot render ([`Passes::hybrid`]), each pixel sampled at
    /// [`crate::passes::taa::supersample_jitters`]' offsets and the frames averaged: anti-aliasing
    /// by supersampling. 0 and 1: one frame through the pixels' centres. (Frames recorded by
    /// [`Passes::record_hybrid`] are anti-aliased over time instead: [`HybridTargets::taa`].)
    pub samples: u32,
}

impl HybridSettings {
    /// The lighting settings with the shadows' sized lights: with ray-traced shadows and
    /// [`ShadowSettings::sized_rays`], the lights' size from [`ShadowSettings::light_radius`] and
    /// [`ShadowSettings::sun_angle`] (what PCSS softens by); else the lighting as set.
    pub fn lighting_with_shadows(&self) -> LightingSettings {
        let mut lighting = self.lighting;
        if self.shadows.sized_rays && !self.shadows.method.uses_maps() {
            lighting.sized_lights =
                Some(SizedLights { radius: self.shadows.light_radius, sun_angle: self.shadows.sun_angle });
        }
        lighting
    }
}

/// A hybrid render: the linear image, its G-buffer and the GPU time of each pass.
#[derive(Debug, Clone)]
pub struct HybridImage {
    /// Width and height.
    pub size: (u32, u32),
    /// Linear radiance rgb, alpha 1.
    pub color: Vec<[f32; 4]>,
    /// The display image from the GPU tonemap pass: sRGB RGBA8.
    pub display: Vec<[u8; 4]>,
    /// The G-buffer the lighting read (the AOVs).
    pub gbuffer: GBufferData,
    /// GPU milliseconds per pass, in order.
    pub pass_ms: Vec<(String, f64)>,
}

pub use crate::passes::ao::AoMethod;

/// An ambient occlusion image (1 = unoccluded), its G-buffer and the GPU time of each pass.
#[derive(Debug, Clone)]
pub struct AoImage {
    /// Width and height.
    pub size: (u32, u32),
    /// AO per pixel, row-major from the top left: blurred when the settings asked for it.
    pub values: Vec<f32>,
    /// The size of `unblurred`: `size`, or about half of it for half-resolution AO.
    pub ao_size: (u32, u32),
    /// The AO before the blur (equal to `values` when there was none), `ao_size` texels.
    pub unblurred: Vec<f32>,
    /// The G-buffer the AO was computed from.
    pub gbuffer: GBufferData,
    /// GPU milliseconds per pass, in order (`gbuffer`, `ssao`, `gtao` or `rtao`, and `ao_blur`).
    pub pass_ms: Vec<(String, f64)>,
}

/// What one frame's passes record against: the scene, its image-based lighting tables and the
/// camera.
#[derive(Clone, Copy)]
pub struct Frame<'a> {
    /// The scene on the GPU.
    pub scene: &'a GpuScene,
    /// Its image-based lighting tables.
    pub ibl: &'a IblResources,
    /// The camera.
    pub camera: &'a Camera,
}

/// The images one hybrid frame reads and writes, all storage images of one size in `GENERAL`
/// layout (umbra's or a host's).
pub struct HybridTargets<'a> {
    /// The G-buffer ([`crate::passes::gbuffer`] formats).
    pub gbuffer: &'a GBufferViews,
    /// The visibility buffer the G-buffer is rasterized into and resolved from ([`Passes::add_hybrid`]);
    /// `None`: the G-buffer is ray-cast.
    pub visibility: Option<&'a VisibilityBuffer>,
    /// `R32_SFLOAT` images for SSAO and its blur (used when the settings ask for AO), to read
    /// them after the frame; `None`: the frame graph's transient images.
    pub ao: Option<(raw::ImageView, raw::ImageView)>,
    /// `R32G32B32A32_SFLOAT` linear radiance.
    pub hdr: raw::ImageView,
    /// `R8G8B8A8_UNORM` display image (sRGB-encoded); `None`: no tonemap.
    pub ldr: Option<raw::ImageView>,
    /// The shadow maps, already recorded ([`Passes::record_shadow_maps`]), when the settings'
    /// shadow method reads maps.
    pub shadows: Option<&'a ShadowMaps>,
    /// A probe volume, already updated or baked, lighting the diffuse lobe; `None`: the
    /// environment's split-sum irradiance.
    pub probes: Option<&'a ProbeVolume>,
    /// Baked lightmaps lighting the diffuse lobe of the materials that have one.
    pub lightmaps: Option<&'a GpuLightmaps>,
    /// ReSTIR's reservoirs (and history) for this view, when the settings sample direct light
    /// by ReSTIR ([`crate::passes::deferred::DirectLight::Restir`]).
    pub reservoirs: Option<&'a Reservoirs>,
    /// Temporal anti-aliasing ([`crate::passes::taa`]): the frame's radiance (`hdr`, sampled at
    /// the camera's jitter: [`Camera::jittered`] by [`TaaHistory::jitter`]) resolved with this
    /// history into its next image ([`TaaHistory::resolved`]), which the tonemap then reads;
    /// `None`: `hdr` is the frame. ([`crate::embed::Renderer::record_hybrid`] jitters the camera.)
    pub taa: Option<&'a TaaHistory>,
}
