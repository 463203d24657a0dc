//! The orchestrator. [`Passes`] owns the pipelines of every pass for one scene's features, each
//! built once, on first use, and records the frames: the hybrid frame (G-buffer → SSAO → blur →
//! deferred lighting → tonemap, [`Passes::record_hybrid`]), ambient occlusion and the progressive
//! path tracer. The one-shot renders ([`Passes::hybrid`], [`Passes::path_trace`],
//! [`Passes::ambient_occlusion`], which allocate the images, submit in batches and read back
//! linear images; the free functions of the same names build a [`Passes`] for one render), the
//! CLI, umbra-bench and the embedding API ([`crate::embed::Renderer`]) all go through it.
//!
//! Dependencies run one way: the passes (`crate::passes`) know neither this module nor the
//! embedding API; this module knows the passes; the embedding API knows both
//! (tests/modules.rs keeps it so).

use crate::error::{Error, Result};
use crate::gpu::cache::Cache;
use crate::gpu::kernels::deferred;
use crate::gpu::layout::{GpuCamera, PathStats};
use crate::gpu::scene::GpuScene;
use crate::gpu::SceneFeatures;
use crate::passes::ao::{AoBlurPass, AoSettings, RtaoPass, SsaoPass};
use crate::passes::deferred::{DeferredPass, LightingInputs, LightingSettings, SizedLights};
pub use crate::passes::denoise::DenoiseSettings;
use crate::passes::denoise::{DenoiseImages, DenoiseInputs, DenoisePass};
use crate::passes::gbuffer::{GBuffer, GBufferData, GBufferPass, GBufferViews};
use crate::passes::ibl::{IblResources, IblSettings};
use crate::passes::lightmap::{
    GpuLightmaps, LightmapLayout, LightmapPass, LightmapSettings, Lightmaps, OcclusionMaps,
};
pub use crate::passes::pathtrace::PathSettings;
use crate::passes::pathtrace::{Integrator, PathOptions, PathTarget, PathTracePass, ResolvePass};
use crate::passes::probes::{ProbePass, ProbeVolume};
use crate::passes::restir::{Reservoirs, RestirPass, RestirSettings};
use crate::passes::shadow::{ShadowMaps, ShadowMethod, ShadowPass, ShadowPlan, ShadowSettings, ShadowView};
pub use crate::passes::temporal::{TemporalFeedback, TemporalSettings};
use crate::passes::temporal::{TemporalHistory, TemporalPass};
use crate::passes::tonemap::{ToneCurve, TonemapPass};
use crate::passes::wavefront::WavefrontPass;
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, GpuTimer, Image};
use std::sync::OnceLock;

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
    /// render's estimate is usually low, with either sampler (tests/pathtrace.rs).
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

/// Which ambient occlusion estimator [`Passes::ambient_occlusion`] runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AoMethod {
    /// Screen-space AO from the G-buffer ([`crate::passes::ao::SsaoPass`]).
    Ssao,
    /// Ray-traced AO through the BVH ([`crate::passes::ao::RtaoPass`]), the ground truth.
    Rtao,
}

/// An ambient occlusion image (1 = unoccluded), its G-buffer and the GPU time of each pass.
#[derive(Debug, Clone)]
pub struct AoImage {
    /// Width and height.
    pub size: (u32, u32),
    /// AO per pixel, row-major from the top left: blurred when the settings asked for it.
    pub values: Vec<f32>,
    /// The AO before the blur (equal to `values` when there was none).
    pub unblurred: Vec<f32>,
    /// The G-buffer the AO was computed from.
    pub gbuffer: GBufferData,
    /// GPU milliseconds per pass, in order (`gbuffer`, `ssao` or `rtao`, and `ao_blur`).
    pub pass_ms: Vec<(String, f64)>,
}

/// The images one hybrid frame reads and writes, all storage images of one size in `GENERAL`
/// layout (umbra's or a host's).
pub struct HybridTargets<'a> {
    /// The G-buffer ([`crate::passes::gbuffer`] formats).
    pub gbuffer: &'a GBufferViews,
    /// `R32_SFLOAT` images for SSAO and its blur (used when the settings ask for AO).
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
}

/// A lazily built pipeline.
fn built<T>(cell: &OnceLock<T>, build: impl FnOnce() -> Result<T>) -> Result<&T> {
    if let Some(pass) = cell.get() {
        return Ok(pass);
    }
    let pass = build()?;
    Ok(cell.get_or_init(|| pass))
}

/// Every pass's pipeline for scenes with one set of features ([`SceneFeatures`]: what the
/// kernels are specialised on), each built once, on first use; and the recording of whole
/// frames from them. Never submits in `record_*`; the one-shot renders submit and read back.
pub struct Passes {
    ctx: Context,
    features: SceneFeatures,
    gbuffer: OnceLock<GBufferPass>,
    /// The lighting pass by its kernel's specialization ([`DeferredPass::spec`]: the shadow
    /// method, probes, lightmaps, ReSTIR, sized lights).
    deferred: Cache<deferred::Spec, DeferredPass>,
    /// ReSTIR's kernels by (unbiased, temporal).
    restir: Cache<(bool, bool), RestirPass>,
    shadow: OnceLock<ShadowPass>,
    probe: OnceLock<ProbePass>,
    lightmap: OnceLock<LightmapPass>,
    ssao: OnceLock<SsaoPass>,
    ao_blur: OnceLock<AoBlurPass>,
    rtao: OnceLock<RtaoPass>,
    tonemap: OnceLock<TonemapPass>,
    /// The megakernel's pass by the estimator ([`PathOptions`]).
    path: Cache<PathOptions, PathTracePass>,
    /// The wavefront path tracer's stages by the estimator.
    wavefront: Cache<PathOptions, WavefrontPass>,
    resolve: OnceLock<ResolvePass>,
    denoise: OnceLock<DenoisePass>,
    temporal: OnceLock<TemporalPass>,
}

impl Passes {
    /// The passes for `scene`'s features (no pipeline is built yet).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Self {
        Self::with_features(ctx, scene.features())
    }

    /// The passes for a scene with `features`, known before it is uploaded
    /// ([`SceneFeatures::of_scene`]): their pipelines can be built while the scene uploads
    /// ([`Passes::prepare_path_trace`] on another thread); they render only a scene with these
    /// features.
    pub fn with_features(ctx: &Context, features: SceneFeatures) -> Self {
        Self {
            ctx: ctx.clone(),
            features,
            gbuffer: OnceLock::new(),
            deferred: Cache::new(),
            restir: Cache::new(),
            shadow: OnceLock::new(),
            probe: OnceLock::new(),
            lightmap: OnceLock::new(),
            ssao: OnceLock::new(),
            ao_blur: OnceLock::new(),
            rtao: OnceLock::new(),
            tonemap: OnceLock::new(),
            path: Cache::new(),
            wavefront: Cache::new(),
            resolve: OnceLock::new(),
            denoise: OnceLock::new(),
            temporal: OnceLock::new(),
        }
    }

    /// The scene features the pipelines are specialised for.
    pub fn features(&self) -> SceneFeatures {
        self.features
    }

    /// Refuses a scene whose features differ from the pipelines' (its textures, lights or
    /// transmission would be silently ignored, or paid for without being there), but for a
    /// shallower BVH than the pipelines' register stack holds, or any under pipelines made for
    /// deep ones (the stack in memory walks any BVH): [`SceneFeatures::renders`].
    fn check(&self, scene: &GpuScene) -> Result<()> {
        let features = scene.features();
        if !self.features.renders(&features) {
            return Err(Error::Invalid(format!(
                "the passes were built for a scene with {:?}, this one has {features:?}: build new passes",
                self.features
            )));
        }
        Ok(())
    }

    fn gbuffer_pass(&self) -> Result<&GBufferPass> {
        built(&self.gbuffer, || GBufferPass::for_features(&self.ctx, &self.features))
    }

    fn deferred_pass(
        &self,
        method: ShadowMethod,
        probes: bool,
        lightmaps: bool,
        restir: bool,
        sized: bool,
    ) -> Result<&DeferredPass> {
        let spec = DeferredPass::spec(method, probes, lightmaps, restir, sized)?;
        self.deferred.get_or_try_init(spec, || DeferredPass::from_spec(&self.ctx, &self.features, spec))
    }

    /// Builds the two pipelines of [`Passes::hybrid_with`] that take longest on lavapipe (the
    /// G-buffer's and the lighting pass's for `settings`, with a probe volume and lightmaps or
    /// not) side by side, if they are not built yet. Needs no scene: a host can call this on a
    /// thread while the scene's BVH is built and uploaded, as [`Passes::prepare_path_trace`].
    pub fn prepare_hybrid(&self, settings: &HybridSettings, probes: bool, lightmaps: bool) -> Result<()> {
        let restir = settings.lighting.direct.restir().is_some();
        let sized = settings.lighting_with_shadows().sized_lights.is_some();
        std::thread::scope(|s| {
            let lighting = s.spawn(|| {
                self.deferred_pass(settings.shadows.method, probes, lightmaps, restir, sized).map(|_| ())
            });
            let gbuffer = self.gbuffer_pass().map(|_| ());
            let lighting = lighting.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            gbuffer.and(lighting)
        })
    }

    fn restir_pass(&self, scene: &GpuScene, settings: &RestirSettings) -> Result<&RestirPass> {
        let (unbiased, temporal) = (settings.unbiased, settings.temporal);
        self.restir
            .get_or_try_init((unbiased, temporal), || RestirPass::new(&self.ctx, scene, unbiased, temporal))
    }

    fn probe_pass(&self, scene: &GpuScene) -> Result<&ProbePass> {
        built(&self.probe, || ProbePass::new(&self.ctx, scene))
    }

    fn shadow_pass(&self, scene: &GpuScene) -> Result<&ShadowPass> {
        built(&self.shadow, || ShadowPass::new(&self.ctx, scene))
    }

    fn ssao_pass(&self) -> Result<&SsaoPass> {
        built(&self.ssao, || SsaoPass::new(&self.ctx))
    }

    fn blur_pass(&self) -> Result<&AoBlurPass> {
        built(&self.ao_blur, || AoBlurPass::new(&self.ctx))
    }

    fn rtao_pass(&self, scene: &GpuScene) -> Result<&RtaoPass> {
        self.check(scene)?;
        self.rtao_stage()
    }

    fn rtao_stage(&self) -> Result<&RtaoPass> {
        built(&self.rtao, || RtaoPass::for_features(&self.ctx, &self.features))
    }

    fn tonemap_pass(&self) -> Result<&TonemapPass> {
        built(&self.tonemap, || TonemapPass::new(&self.ctx))
    }

    fn resolve_pass(&self) -> Result<&ResolvePass> {
        built(&self.resolve, || ResolvePass::new(&self.ctx))
    }

    fn denoise_pass(&self) -> Result<&DenoisePass> {
        built(&self.denoise, || DenoisePass::new(&self.ctx))
    }

    fn temporal_pass(&self) -> Result<&TemporalPass> {
        built(&self.temporal, || TemporalPass::new(&self.ctx))
    }

    /// Builds every pipeline now (the path tracer's for `options`), not at first use: for a host
    /// that records frames against a deadline.
    pub fn prepare(&self, scene: &GpuScene, options: PathOptions) -> Result<()> {
        self.check(scene)?;
        self.prepare_every(options)
    }

    /// [`Passes::prepare`] with no scene yet (from the passes' features): a host can call it
    /// on a thread while the scene's BVH is built and uploaded. The path tracer's pipeline is
    /// made on a thread of its own beside the others (the G-buffer's, the lighting pass's and
    /// RTAO's take a second or more each on lavapipe).
    pub fn prepare_every(&self, options: PathOptions) -> Result<()> {
        std::thread::scope(|s| {
            let path = s.spawn(|| self.megakernel(options, false).map(|_| ()));
            let rest = self
                .gbuffer_pass()
                .and_then(|_| self.deferred_pass(ShadowMethod::RayTraced, false, false, false, false))
                .and_then(|_| self.rtao_stage())
                .and_then(|_| self.ssao_pass())
                .and_then(|_| self.blur_pass())
                .and_then(|_| self.tonemap_pass())
                .and_then(|_| self.resolve_pass())
                .and_then(|_| self.denoise_pass())
                .and_then(|_| self.temporal_pass())
                .map(|_| ());
            let path = path.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            rest.and(path)
        })
    }

    /// The path tracer's pipeline for `options` (built now if it was not: an embedding host
    /// calls this before recording a frame).
    pub fn path_pass(&self, scene: &GpuScene, options: PathOptions) -> Result<&PathTracePass> {
        let pass = self.lazy_path_pass(scene, options)?;
        pass.prepare(&self.ctx, scene, false)?;
        Ok(pass)
    }

    /// The path tracer's pass for `options`, its pipelines built at their first use.
    fn lazy_path_pass(&self, scene: &GpuScene, options: PathOptions) -> Result<&PathTracePass> {
        self.check(scene)?;
        Ok(self.path.get_or_init(options, || PathTracePass::lazy(options)))
    }

    /// The wavefront path tracer's stages for `options`, without the lobe split (built now if
    /// they were not).
    pub fn wavefront_pass(&self, scene: &GpuScene, options: PathOptions) -> Result<&WavefrontPass> {
        let pass = self.lazy_wavefront_pass(scene, options)?;
        pass.prepare(&self.ctx, scene, false)?;
        Ok(pass)
    }

    /// The wavefront path tracer's pass for `options`, its stages built at their first use.
    fn lazy_wavefront_pass(&self, scene: &GpuScene, options: PathOptions) -> Result<&WavefrontPass> {
        self.check(scene)?;
        Ok(self.wavefront_stages(options))
    }

    /// The wavefront path tracer's pass for `options`, no stage built yet.
    fn wavefront_stages(&self, options: PathOptions) -> &WavefrontPass {
        self.wavefront.get_or_init(options, || WavefrontPass::lazy(options))
    }

    /// Builds the pipelines [`Passes::path_trace`] with `settings` uses (the megakernel's or the
    /// wavefront's stages, with the lobe split or not), if they are not built yet. Needs no
    /// scene: pipeline creation takes up to a second on lavapipe, and a host can call this on a
    /// thread (`std::thread::scope`) while the scene's BVH is built and uploaded.
    pub fn prepare_path_trace(&self, settings: &PathSettings) -> Result<()> {
        let options = settings.options();
        match settings.integrator {
            Integrator::Megakernel => self.megakernel(options, settings.lobe_split).map(|_| ()),
            Integrator::Wavefront => {
                self.wavefront_stages(options).prepare_for(&self.ctx, &self.features, settings.lobe_split)
            }
        }
    }

    /// The megakernel's pass for `options` with its pipeline for `lobe_split` built.
    pub(crate) fn megakernel(&self, options: PathOptions, lobe_split: bool) -> Result<&PathTracePass> {
        let pass = self.path.get_or_init(options, || PathTracePass::lazy(options));
        pass.prepare_for(&self.ctx, &self.features, lobe_split)?;
        Ok(pass)
    }

    /// Records the ray-cast G-buffer of `scene` seen from `camera` into `target`.
    pub fn record_gbuffer(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        camera: &Camera,
        target: &GBufferViews,
    ) -> Result<()> {
        self.check(scene)?;
        let params = GBufferPass::params(camera, target.size);
        self.gbuffer_pass()?.record(&self.ctx, cmd, scene, target, &params)
    }

    /// Records SSAO of `gbuffer` into `raw_ao` and, when `settings.blur`, its depth-aware blur
    /// into `blurred` (`R32_SFLOAT`, the G-buffer's size). Returns the view holding the result.
    pub fn record_ssao(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        raw_ao: raw::ImageView,
        blurred: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<raw::ImageView> {
        self.record_ssao_timed(cmd, camera, gbuffer, (raw_ao, blurred), settings, None)
    }

    fn record_ssao_timed(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        (raw_ao, blurred): (raw::ImageView, raw::ImageView),
        settings: &AoSettings,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<raw::ImageView> {
        settings.validate()?;
        let size = gbuffer.size;
        timed(&mut timer, cmd, "ssao", || {
            self.ssao_pass()?.record(
                &self.ctx,
                cmd,
                gbuffer,
                raw_ao,
                &SsaoPass::params(camera, size, settings),
            )
        })?;
        if !settings.blur {
            return Ok(raw_ao);
        }
        timed(&mut timer, cmd, "ao_blur", || {
            let params = AoBlurPass::params(camera, size);
            self.blur_pass()?.record(&self.ctx, cmd, gbuffer, raw_ao, blurred, &params)
        })?;
        Ok(blurred)
    }

    /// Records ray-traced AO of `gbuffer` (`settings.samples` rays of length `settings.radius`
    /// per pixel) into `output` (`R32_SFLOAT`, the G-buffer's size).
    pub fn record_rtao(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        self.check(scene)?;
        settings.validate()?;
        let params = RtaoPass::params(camera, gbuffer.size, settings);
        self.rtao_pass(scene)?.record(&self.ctx, cmd, scene, gbuffer, output, &params)
    }

    /// Records deferred lighting of `gbuffer` into `output` (`R32G32B32A32_SFLOAT`), with the
    /// scene's precomputed `ibl` and the optional `inputs` (ambient occlusion, shadow maps
    /// instead of shadow rays, a probe volume and lightmaps for the diffuse lobe), each recorded
    /// before.
    #[allow(clippy::too_many_arguments)]
    pub fn record_lighting(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        ibl: &IblResources,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        inputs: &LightingInputs<'_>,
        settings: &LightingSettings,
    ) -> Result<()> {
        self.check(scene)?;
        settings.validate()?;
        settings.validate_sized_rays(scene.punctual_count)?;
        let params = DeferredPass::params(scene, camera, gbuffer.size, settings);
        let method = inputs.shadows.map_or(ShadowMethod::RayTraced, |m| m.settings.method);
        let (probes, lightmaps, restir) =
            (inputs.probes.is_some(), inputs.lightmaps.is_some(), inputs.restir.is_some());
        let sized = settings.sized_lights.is_some();
        if sized && method.uses_maps() {
            return Err(Error::Invalid(format!(
                "sized lights' ray-traced shadows were asked for, but the lighting is given '{}' shadow maps",
                method.name()
            )));
        }
        self.deferred_pass(method, probes, lightmaps, restir, sized)?
            .record(&self.ctx, cmd, scene, gbuffer, output, ibl, inputs, &params)
    }

    /// Records ReSTIR's candidates, temporal and spatial reuse for `gbuffer` (seen by `camera`)
    /// into `reservoirs`, with the random numbers of `lighting`'s frame and seed; the lighting
    /// pass then shades them ([`LightingInputs::restir`]). Never submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record_restir(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        reservoirs: &Reservoirs,
        settings: &RestirSettings,
        lighting: &LightingSettings,
    ) -> Result<()> {
        self.check(scene)?;
        self.restir_pass(scene, settings)?.record(
            &self.ctx,
            cmd,
            scene,
            camera,
            gbuffer,
            reservoirs,
            settings,
            lighting.frame,
            lighting.seed,
        )
    }

    /// Records one update of `count` probes of `volume` (from where the last update stopped,
    /// wrapping): a probe's first [`crate::passes::probes::ProbeSettings::bounces`] updates
    /// replace its maps, later ones weigh the new estimate at least `blend_min` against the old
    /// (0: a running mean), under the environment of `settings` (the lighting's). Never submits.
    pub fn record_probe_update(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        volume: &mut ProbeVolume,
        count: u32,
        blend_min: f32,
        settings: &LightingSettings,
    ) -> Result<()> {
        self.check(scene)?;
        settings.validate()?;
        self.probe_pass(scene)?.record(&self.ctx, cmd, scene, volume, count, blend_min, settings.env)
    }

    /// Bakes `volume` now (submits and waits): [`ProbeVolume::bake_sweeps`] sweeps over every
    /// probe, a running mean after the replacing ones, under the environment of `settings`,
    /// calling `progress(done, total)` after each sweep. Returns the GPU milliseconds of all
    /// sweeps.
    pub fn bake_probes(
        &self,
        scene: &GpuScene,
        volume: &mut ProbeVolume,
        settings: &LightingSettings,
        mut progress: impl FnMut(u32, u32),
    ) -> Result<f64> {
        let ctx = &self.ctx;
        let sweeps = volume.bake_sweeps();
        let count = volume.grid.count();
        let mut timer = GpuTimer::new(ctx, 1)?;
        let mut ms = 0.0;
        for sweep in 1..=sweeps {
            ctx.submit(|cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "probes")?;
                self.record_probe_update(cmd, scene, volume, count, 0.0, settings)?;
                timer.end(cmd)
            })?;
            ms += timer.read()?.iter().map(|t| t.ms).sum::<f64>();
            progress(sweep, sweeps);
        }
        Ok(ms)
    }

    /// Places and allocates the shadow maps of `scene`'s punctual lights for `camera` over an
    /// image of `size` (nothing is recorded: [`Passes::record_shadow_maps`] renders them).
    pub fn shadow_maps(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        size: (u32, u32),
        settings: &ShadowSettings,
    ) -> Result<ShadowMaps> {
        let plan = ShadowPlan::new(&scene.punctual_lights, scene.bounds, camera, size, settings)?;
        ShadowMaps::new(&self.ctx, plan, settings, scene)
    }

    /// Records the rendering of every layer of `maps` (after a light, the geometry or, for
    /// directional cascades, the camera changed); for a `view` whose G-buffer is recorded before
    /// (with [`ShadowSettings::view_marks`]: its cascades' tiles that no pixel reads are skipped,
    /// so the G-buffer must change no more often than the maps are recorded). Never submits.
    /// After the submission, [`ShadowMaps::check`] says whether the tile lists sufficed.
    pub fn record_shadow_maps(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        maps: &ShadowMaps,
        view: Option<ShadowView<'_>>,
    ) -> Result<()> {
        self.check(scene)?;
        self.shadow_pass(scene)?.record(&self.ctx, cmd, scene, maps, view, None)
    }

    /// Renders `maps` now (submits and waits) for `view` (its G-buffer already rendered), as
    /// [`Passes::record_shadow_maps`] records them, growing their tile lists and rendering
    /// again when they overflowed; returns the GPU milliseconds of each step of the last
    /// rendering (summed over the layers, by kernel).
    pub fn render_shadow_maps(
        &self,
        scene: &GpuScene,
        maps: &mut ShadowMaps,
        view: Option<ShadowView<'_>>,
    ) -> Result<Vec<(String, f64)>> {
        let ctx = &self.ctx;
        self.check(scene)?;
        for _ in 0..2 {
            let mut timer = GpuTimer::new(ctx, ShadowPass::timer_entries(maps))?;
            ctx.submit(|cmd| {
                timer.reset(cmd);
                self.shadow_pass(scene)?.record(ctx, cmd, scene, maps, view, Some(&mut timer))
            })?;
            let mut steps: Vec<(String, f64)> = Vec::new();
            for t in timer.read()? {
                match steps.iter_mut().find(|(name, _)| *name == t.name) {
                    Some(step) => step.1 += t.ms,
                    None => steps.push((t.name, t.ms)),
                }
            }
            match maps.check(ctx)? {
                None => return Ok(steps),
                Some(entries) => maps.reserve(ctx, entries)?,
            }
        }
        Err(Error::Invalid("shadow maps: the tile lists overflowed twice".into()))
    }

    /// Bakes the lightmaps of `layout` (see [`crate::passes::lightmap`]) now (submits and
    /// waits) under the environment of `lighting`, the bounces beyond the first from `probes`
    /// when given, calling `progress(done, total)` samples; returns them read back and dilated.
    pub fn bake_lightmaps(
        &self,
        scene: &GpuScene,
        layout: &LightmapLayout,
        settings: &LightmapSettings,
        lighting: &LightingSettings,
        probes: Option<&ProbeVolume>,
        progress: impl FnMut(u32, u32),
    ) -> Result<Lightmaps> {
        self.check(scene)?;
        lighting.validate()?;
        let pass = built(&self.lightmap, || LightmapPass::new(&self.ctx, scene))?;
        pass.bake(&self.ctx, scene, layout, settings, lighting.env, probes, progress)
    }

    /// Bakes ambient-occlusion maps over `layout`'s charts (rays of length `radius`, RTAO's
    /// estimator) now, calling `progress(done, total)` samples; returns them dilated.
    pub fn bake_occlusion(
        &self,
        scene: &GpuScene,
        layout: &LightmapLayout,
        settings: &LightmapSettings,
        radius: f32,
        progress: impl FnMut(u32, u32),
    ) -> Result<OcclusionMaps> {
        self.check(scene)?;
        let pass = built(&self.lightmap, || LightmapPass::new(&self.ctx, scene))?;
        pass.bake_occlusion(&self.ctx, scene, layout, settings, radius, progress)
    }

    /// Records the display transform of `src` (`R32G32B32A32_SFLOAT`) into `dst`
    /// (`R8G8B8A8_UNORM`, sRGB-encoded values).
    pub fn record_tonemap(
        &self,
        cmd: raw::CommandBuffer,
        src: raw::ImageView,
        dst: raw::ImageView,
        size: (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) -> Result<()> {
        self.tonemap_pass()?.record(&self.ctx, cmd, src, dst, size, exposure_stops, curve)
    }

    /// Records one hybrid frame into `targets`: G-buffer, SSAO and its blur (when
    /// `settings.ao`), deferred lighting with `ibl` × AO, tonemap (when `targets.ldr`), each
    /// timed under its name when a `timer` is given. The one place the hybrid frame is wired.
    #[allow(clippy::too_many_arguments)]
    pub fn record_hybrid(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        ibl: &IblResources,
        camera: &Camera,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        self.check(scene)?;
        settings.lighting_with_shadows().validate()?;
        timed(&mut timer, cmd, "gbuffer", || self.record_gbuffer(cmd, scene, camera, targets.gbuffer))?;
        self.record_hybrid_shading(cmd, scene, ibl, camera, targets, settings, timer)
    }

    /// [`Passes::record_hybrid`] after its G-buffer, which `targets.gbuffer` already holds
    /// ([`Passes::record_gbuffer`] of `camera`): for shadow maps rendered for the view between
    /// the two ([`crate::passes::shadow::ShadowView`]).
    #[allow(clippy::too_many_arguments)]
    pub fn record_hybrid_shading(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        ibl: &IblResources,
        camera: &Camera,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        self.check(scene)?;
        settings.lighting_with_shadows().validate()?;
        let shadows = match (settings.shadows.method.uses_maps(), targets.shadows) {
            (false, _) => None,
            (true, Some(maps)) if maps.settings.method == settings.shadows.method => Some(maps),
            (true, Some(maps)) => {
                return Err(Error::Invalid(format!(
                    "the settings shadow by '{}' but the maps given were made for '{}'",
                    settings.shadows.method.name(),
                    maps.settings.method.name()
                )))
            }
            (true, None) => {
                return Err(Error::Invalid(format!(
                    "the settings shadow by '{}' but no shadow maps were given",
                    settings.shadows.method.name()
                )))
            }
        };
        let gbuffer = targets.gbuffer;
        let ao = match (&settings.ao, targets.ao) {
            (Some(ao), Some(images)) => {
                Some(self.record_ssao_timed(cmd, camera, gbuffer, images, ao, timer.as_deref_mut())?)
            }
            (Some(_), None) => {
                return Err(Error::Invalid("the settings ask for SSAO but no AO images were given".into()))
            }
            (None, _) => None,
        };
        let restir = match (settings.lighting.direct.restir(), targets.reservoirs) {
            (None, _) => None,
            (Some(restir), Some(reservoirs)) => {
                timed(&mut timer, cmd, "restir", || {
                    self.record_restir(cmd, scene, camera, gbuffer, reservoirs, restir, &settings.lighting)
                })?;
                Some(reservoirs)
            }
            (Some(_), None) => {
                return Err(Error::Invalid("the settings ask for ReSTIR but no reservoirs were given".into()))
            }
        };
        timed(&mut timer, cmd, "lighting", || {
            let inputs =
                LightingInputs { ao, shadows, probes: targets.probes, lightmaps: targets.lightmaps, restir };
            let lighting = settings.lighting_with_shadows();
            self.record_lighting(cmd, scene, ibl, camera, gbuffer, targets.hdr, &inputs, &lighting)
        })?;
        if let Some(ldr) = targets.ldr {
            timed(&mut timer, cmd, "tonemap", || {
                self.record_tonemap(cmd, targets.hdr, ldr, gbuffer.size, settings.exposure, settings.curve)
            })?;
        }
        Ok(())
    }

    /// Records path-traced samples `first .. first + count` of `settings`' render into `target`
    /// (its samples `settings.first_sample + first ..` of the sequence; `first` 0 records the
    /// target's clearing first and restarts the running mean). `settings.size` must be the
    /// target's. With RIS reuse ([`crate::passes::pathtrace::RisReuse`]) the target's reservoirs
    /// are made at the first such record, and the samples continue from those the last record
    /// left (`first` 0 clears them too).
    #[allow(clippy::too_many_arguments)]
    pub fn record_path_samples(
        &self,
        cmd: raw::CommandBuffer,
        scene: &GpuScene,
        camera: &Camera,
        target: &PathTarget,
        settings: &PathSettings,
        first: u32,
        count: u32,
    ) -> Result<()> {
        if settings.ris_reuse != crate::passes::pathtrace::RisReuse::Off {
            // (Reuse chains the samples: the settings that cannot be split are refused.)
            settings.validate()?;
        }
        if settings.size != target.size {
            return Err(Error::Invalid(format!(
                "path settings are for {:?} but the target is {:?}",
                settings.size, target.size
            )));
        }
        let mut params = PathTracePass::params(scene, camera, settings);
        params.sample_index =
            settings.first_sample.checked_add(first).filter(|s| s.checked_add(count).is_some()).ok_or_else(
                || {
                    Error::Invalid(format!(
                        "samples {first}..+{count} from {} run past the sequence's last index",
                        settings.first_sample
                    ))
                },
            )?;
        params.sample_count = count;
        if first == 0 {
            target.record_clear(&self.ctx, cmd);
        }
        match settings.integrator {
            Integrator::Megakernel => {
                self.lazy_path_pass(scene, settings.options())?.record(&self.ctx, cmd, scene, target, &params)
            }
            Integrator::Wavefront => self
                .lazy_wavefront_pass(scene, settings.options())?
                .record(&self.ctx, cmd, scene, target, settings, &params),
        }
    }

    /// Records the copy of `target`'s running mean into `output` (`R32G32B32A32_SFLOAT`, the
    /// target's size).
    pub fn record_path_resolve(
        &self,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        output: raw::ImageView,
    ) -> Result<()> {
        self.resolve_pass()?.record(&self.ctx, cmd, target, output)
    }

    /// Records the denoiser ([`crate::passes::denoise`]) of `target`'s samples so far into
    /// `output` (`R32G32B32A32_SFLOAT`, the target's size, `GENERAL` layout) through `images`
    /// (the target's size, already in `GENERAL` layout).
    pub fn record_denoise(
        &self,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        self.denoise_pass()?.record(&self.ctx, cmd, &DenoiseInputs::from(target), images, output, settings)
    }

    /// Denoises a path-traced `image` (uploaded, filtered, read back): the denoised radiance and
    /// the filter's GPU time. The image's AOVs must be there (as [`Passes::path_trace`] returns
    /// them); a test may make them up.
    pub fn denoise(&self, image: &PathImage, settings: &DenoiseSettings) -> Result<DenoisedImage> {
        let ctx = &self.ctx;
        settings.validate()?;
        let uploaded = UploadedImage::new(ctx, image)?;
        let images = match image.lobe_split {
            Some(_) => DenoiseImages::with_lobe_split(ctx, image.size)?,
            None => DenoiseImages::new(ctx, image.size)?,
        };
        let (w, h) = image.size;
        let output = Image::storage_2d(ctx, "denoised", w, h, raw::Format::R32G32B32A32_SFLOAT)?;
        let pass = self.denoise_pass()?;
        let mut timer = GpuTimer::new(ctx, 1)?;
        ctx.submit(|cmd| {
            images.init_general(ctx, cmd);
            output.init_general(ctx, cmd);
            timer.reset(cmd);
            timer.begin(cmd, "denoise")?;
            pass.record(ctx, cmd, &uploaded.inputs(), &images, output.view, settings)?;
            timer.end(cmd)
        })?;
        let gpu_ms = timer.read()?.iter().map(|t| t.ms).sum();
        Ok(DenoisedImage { size: image.size, color: output.read(ctx)?, gpu_ms })
    }

    /// Records the denoiser of `target`'s samples with temporal accumulation
    /// ([`crate::passes::temporal`]): the frame, seen by `camera`, blended with `history` (which
    /// then holds it), filtered into `output` (`R32G32B32A32_SFLOAT`, the target's size,
    /// `GENERAL` layout) through `images`.
    #[allow(clippy::too_many_arguments)]
    pub fn record_denoise_temporal(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &PathTarget,
        images: &DenoiseImages,
        history: &mut TemporalHistory,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        let camera = GpuCamera::new(camera, target.size);
        let temporal = (self.temporal_pass()?, history, &camera);
        self.denoise_pass()?.record_temporal(
            &self.ctx,
            cmd,
            &DenoiseInputs::from(target),
            images,
            output,
            settings,
            temporal,
        )
    }

    /// Denoises a sequence of path-traced frames, each `(image, camera)`, with temporal
    /// accumulation (uploaded, filtered one frame per submission, read back; the history starts
    /// afresh at the first frame): per frame, the denoised radiance, each pixel's history length
    /// after it and the filter's GPU time. The frames' AOVs must be there (as
    /// [`Passes::path_trace`] returns them); a test may make them up.
    pub fn denoise_temporal(
        &self,
        frames: &[(&PathImage, &Camera)],
        settings: &DenoiseSettings,
        temporal: &TemporalSettings,
    ) -> Result<Vec<TemporalFrame>> {
        let ctx = &self.ctx;
        settings.validate()?;
        let Some((first, _)) = frames.first() else { return Ok(Vec::new()) };
        let size = first.size;
        let images = DenoiseImages::with_lobe_split(ctx, size)?;
        let mut history = TemporalHistory::new(ctx, size, *temporal)?;
        let output = Image::storage_2d(ctx, "denoised", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
        let (pass, temporal_pass) = (self.denoise_pass()?, self.temporal_pass()?);
        ctx.submit(|cmd| {
            images.init_general(ctx, cmd);
            history.init_general(ctx, cmd);
            output.init_general(ctx, cmd);
            Ok(())
        })?;
        let mut timer = GpuTimer::new(ctx, 1)?;
        let mut out = Vec::new();
        for (image, camera) in frames {
            if image.size != size {
                return Err(Error::Invalid(format!(
                    "the frames to denoise change size: {:?}, then {:?}",
                    size, image.size
                )));
            }
            let uploaded = UploadedImage::new(ctx, image)?;
            let camera = GpuCamera::new(camera, size);
            ctx.submit(|cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "denoise")?;
                let temporal = (temporal_pass, &mut history, &camera);
                pass.record_temporal(ctx, cmd, &uploaded.inputs(), &images, output.view, settings, temporal)?;
                timer.end(cmd)
            })?;
            let gpu_ms = timer.read()?.iter().map(|t| t.ms).sum();
            out.push(TemporalFrame {
                color: output.read(ctx)?,
                history_length: history.lengths(ctx)?,
                gpu_ms,
            });
        }
        Ok(out)
    }

    /// Path traces `settings.spp` samples per pixel, calling `progress(done, total)` after each
    /// submitted batch.
    pub fn path_trace(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        settings: &PathSettings,
        mut progress: impl FnMut(u32, u32),
    ) -> Result<PathImage> {
        let ctx = &self.ctx;
        settings.validate()?;
        let clock = std::time::Instant::now();
        self.check(scene)?;
        self.prepare_path_trace(settings)?;
        let pipeline_ms = clock.elapsed().as_secs_f64() * 1e3;
        let target = if settings.lobe_split {
            PathTarget::with_lobe_split(ctx, settings.size)?
        } else {
            PathTarget::new(ctx, settings.size)?
        };
        // Batches of about 2^22 pixel-samples keep each submission short (progress, timeouts).
        let pixels = settings.size.0 as u64 * settings.size.1 as u64;
        let batch = ((1u64 << 22) / pixels.max(1)).clamp(1, 64) as u32;
        let mut timer = GpuTimer::new(ctx, 1)?;
        let mut gpu_ms = 0.0;
        let mut done = 0;
        let clock = std::time::Instant::now();
        while done < settings.spp {
            let count = batch.min(settings.spp - done);
            let submitted = std::time::Instant::now();
            ctx.submit(|cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "pathtrace")?;
                self.record_path_samples(cmd, scene, camera, &target, settings, done, count)?;
                timer.end(cmd)
            })?;
            let batch_ms = timer.read()?.iter().map(|t| t.ms).sum::<f64>();
            log::debug!(
                "path tracing samples {done}..{}: {:.1} ms wall, {batch_ms:.1} ms GPU",
                done + count,
                submitted.elapsed().as_secs_f64() * 1e3
            );
            gpu_ms += batch_ms;
            done += count;
            progress(done, settings.spp);
            if let Some(goal) = settings.target_error {
                if done >= 16 && done < settings.spp {
                    let error = relative_error(&target.accum.read(ctx)?, &target.moment.read(ctx)?, done);
                    if error <= goal {
                        log::info!("relative error {error:.4} <= {goal} after {done} spp: stopping");
                        break;
                    }
                }
            }
        }
        let trace_ms = clock.elapsed().as_secs_f64() * 1e3;
        let clock = std::time::Instant::now();
        let stats: Vec<PathStats> = target.stats.read(ctx)?;
        let image = PathImage {
            size: settings.size,
            spp: done,
            mean: target.accum.read(ctx)?,
            moment: target.moment.read(ctx)?,
            albedo: target.albedo.read(ctx)?,
            normal_depth: target.normal_depth.read(ctx)?,
            emission: target.emission.read(ctx)?,
            lobe_split: match &target.lobe_split {
                Some(split) => Some(LobeSplitImage {
                    specular: split.specular.read(ctx)?,
                    split: split.split.read(ctx)?,
                }),
                None => None,
            },
            nonfinite_samples: stats[0].nonfinite_samples,
            nonfinite_sources: stats[0].nonfinite_sources,
            gpu_ms,
            segments: stats[0].segments(),
            marches_exhausted: stats[0].marches_exhausted,
        };
        log::debug!(
            "path tracing: pipeline {pipeline_ms:.1} ms, batches {trace_ms:.1} ms wall ({gpu_ms:.1} ms GPU), \
             readback {:.1} ms",
            clock.elapsed().as_secs_f64() * 1e3
        );
        Ok(image)
    }

    /// Renders `scene` with the hybrid pipeline: the IBL precomputation (BRDF table, prefiltered
    /// environment, SH irradiance) for `settings.ibl`, then [`Passes::record_hybrid`].
    pub fn hybrid(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        settings: &HybridSettings,
    ) -> Result<HybridImage> {
        self.hybrid_with_probes(scene, camera, settings, None)
    }

    /// [`Passes::hybrid`] with the diffuse lobe lit by a (baked) probe volume.
    pub fn hybrid_with_probes(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        settings: &HybridSettings,
        probes: Option<&ProbeVolume>,
    ) -> Result<HybridImage> {
        self.hybrid_with(scene, camera, settings, probes, None)
    }

    /// [`Passes::hybrid`] with the diffuse lobe lit by a (baked) probe volume and by lightmaps
    /// where the materials have them.
    pub fn hybrid_with(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        settings: &HybridSettings,
        probes: Option<&ProbeVolume>,
        lightmaps: Option<&GpuLightmaps>,
    ) -> Result<HybridImage> {
        let ctx = &self.ctx;
        self.check(scene)?;
        settings.lighting_with_shadows().validate()?;
        settings.lighting_with_shadows().validate_sized_rays(scene.punctual_count)?;
        if let Some(ao) = &settings.ao {
            ao.validate()?;
        }
        let size = settings.size;
        let gbuffer = GBuffer::new(ctx, size)?;
        let output =
            Image::storage_2d(ctx, "hybrid colour", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
        let display = Image::storage_2d(ctx, "hybrid display", size.0, size.1, raw::Format::R8G8B8A8_UNORM)?;
        let ibl = IblResources::new(ctx, scene, &settings.ibl)?;
        let ao_images = match &settings.ao {
            Some(_) => {
                let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
                Some((make("hybrid ssao")?, make("hybrid ssao blurred")?))
            }
            None => None,
        };
        let views = gbuffer.views();
        // The environment's tables and the G-buffer first (the shadow maps render for its
        // view), then the rest of the frame.
        let mut first_timer = GpuTimer::new(ctx, 8)?;
        ctx.submit(|cmd| {
            first_timer.reset(cmd);
            ibl.record(ctx, cmd, scene, Some(&mut first_timer))?;
            first_timer.begin(cmd, "gbuffer")?;
            self.record_gbuffer(cmd, scene, camera, &views)?;
            first_timer.end(cmd)
        })?;
        let mut shadow_ms = Vec::new();
        let shadows = if settings.shadows.method.uses_maps() {
            let mut maps = self.shadow_maps(scene, camera, size, &settings.shadows)?;
            let view = ShadowView { camera, gbuffer: &views };
            shadow_ms = self.render_shadow_maps(scene, &mut maps, Some(view))?;
            Some(maps)
        } else {
            None
        };
        let reservoirs = match settings.lighting.direct.restir() {
            Some(_) => Some(Reservoirs::new(ctx, size)?),
            None => None,
        };
        let targets = HybridTargets {
            gbuffer: &views,
            ao: ao_images.as_ref().map(|(a, b)| (a.view, b.view)),
            hdr: output.view,
            ldr: Some(display.view),
            shadows: shadows.as_ref(),
            probes,
            lightmaps,
            reservoirs: reservoirs.as_ref(),
        };
        // ReSTIR's one-shot render runs its frames with the camera still (its history), timing
        // the last.
        let frames = settings.lighting.direct.restir().map_or(1, |r| r.frames);
        let mut timer = GpuTimer::new(ctx, 8)?;
        ctx.submit(|cmd| {
            output.init_general(ctx, cmd);
            display.init_general(ctx, cmd);
            if let Some((a, b)) = &ao_images {
                a.init_general(ctx, cmd);
                b.init_general(ctx, cmd);
            }
            timer.reset(cmd);
            for f in 0..frames {
                let mut frame = settings.clone();
                frame.lighting.frame = settings.lighting.frame.wrapping_mul(frames).wrapping_add(f);
                let timer = if f + 1 == frames { Some(&mut timer) } else { None };
                self.record_hybrid_shading(cmd, scene, &ibl, camera, &targets, &frame, timer)?;
            }
            Ok(())
        })?;
        // In the order they ran: the environment's tables and the G-buffer, the maps, the rest.
        let named = |t: crate::vk::PassTime| (t.name, t.ms);
        let mut pass_ms: Vec<(String, f64)> = first_timer.read()?.into_iter().map(named).collect();
        pass_ms.extend(shadow_ms);
        pass_ms.extend(timer.read()?.into_iter().map(named));
        Ok(HybridImage {
            size,
            color: output.read(ctx)?,
            display: display.read(ctx)?,
            gbuffer: gbuffer.read(ctx)?,
            pass_ms,
        })
    }

    /// Renders the G-buffer of `scene` seen by `camera` at `size` and its ambient occlusion by
    /// `method` (see [`crate::passes::ao`] for the definition both estimate), blurred when
    /// `settings.blur`.
    pub fn ambient_occlusion(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        size: (u32, u32),
        method: AoMethod,
        settings: &AoSettings,
    ) -> Result<AoImage> {
        let ctx = &self.ctx;
        settings.validate()?;
        let gbuffer = GBuffer::new(ctx, size)?;
        let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
        let raw_ao = make("ambient occlusion")?;
        let blurred = make("ambient occlusion blurred")?;
        let views = gbuffer.views();
        let mut timer = GpuTimer::new(ctx, 3)?;
        ctx.submit(|cmd| {
            raw_ao.init_general(ctx, cmd);
            blurred.init_general(ctx, cmd);
            timer.reset(cmd);
            timer.begin(cmd, "gbuffer")?;
            self.record_gbuffer(cmd, scene, camera, &views)?;
            timer.end(cmd)?;
            match method {
                AoMethod::Ssao => {
                    // SSAO without its blur; the blur follows for both methods.
                    let unblurred = AoSettings { blur: false, ..*settings };
                    self.record_ssao_timed(
                        cmd,
                        camera,
                        &views,
                        (raw_ao.view, blurred.view),
                        &unblurred,
                        Some(&mut timer),
                    )?;
                }
                AoMethod::Rtao => {
                    timer.begin(cmd, "rtao")?;
                    self.record_rtao(cmd, scene, camera, &views, raw_ao.view, settings)?;
                    timer.end(cmd)?;
                }
            }
            if settings.blur {
                timer.begin(cmd, "ao_blur")?;
                let params = AoBlurPass::params(camera, size);
                self.blur_pass()?.record(ctx, cmd, &views, raw_ao.view, blurred.view, &params)?;
                timer.end(cmd)?;
            }
            Ok(())
        })?;
        let pass_ms = timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect();
        let unblurred: Vec<f32> = raw_ao.read(ctx)?;
        let values = if settings.blur { blurred.read(ctx)? } else { unblurred.clone() };
        Ok(AoImage { size, values, unblurred, gbuffer: gbuffer.read(ctx)?, pass_ms })
    }
}

/// Runs `record` between `timer.begin(name)` and `timer.end()` when there is a timer.
fn timed(
    timer: &mut Option<&mut GpuTimer>,
    cmd: raw::CommandBuffer,
    name: &str,
    record: impl FnOnce() -> Result<()>,
) -> Result<()> {
    if let Some(t) = timer.as_deref_mut() {
        t.begin(cmd, name)?;
    }
    record()?;
    if let Some(t) = timer.as_deref_mut() {
        t.end(cmd)?;
    }
    Ok(())
}

/// Path traces `scene` once ([`Passes::path_trace`] with passes built for this render).
pub fn path_trace(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    settings: &PathSettings,
    progress: impl FnMut(u32, u32),
) -> Result<PathImage> {
    Passes::new(ctx, scene).path_trace(scene, camera, settings, progress)
}

/// Renders `scene` once with the hybrid pipeline ([`Passes::hybrid`] with passes built for this
/// render).
pub fn hybrid(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    settings: &HybridSettings,
) -> Result<HybridImage> {
    Passes::new(ctx, scene).hybrid(scene, camera, settings)
}

/// Renders ambient occlusion once ([`Passes::ambient_occlusion`] with passes built for this
/// render).
pub fn ambient_occlusion(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    method: AoMethod,
    settings: &AoSettings,
) -> Result<AoImage> {
    Passes::new(ctx, scene).ambient_occlusion(scene, camera, size, method, settings)
}

/// Denoises a sequence of frames with temporal accumulation ([`Passes::denoise_temporal`] with
/// passes built for this filter).
pub fn denoise_temporal(
    ctx: &Context,
    frames: &[(&PathImage, &Camera)],
    settings: &DenoiseSettings,
    temporal: &TemporalSettings,
) -> Result<Vec<TemporalFrame>> {
    Passes::with_features(ctx, SceneFeatures::default()).denoise_temporal(frames, settings, temporal)
}

/// Denoises a path-traced image once ([`Passes::denoise`] with passes built for this filter).
pub fn denoise(ctx: &Context, image: &PathImage, settings: &DenoiseSettings) -> Result<DenoisedImage> {
    // The denoiser reads no scene: passes for a scene without features.
    Passes::with_features(ctx, SceneFeatures::default()).denoise(image, settings)
}
