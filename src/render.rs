//! Whole renders: the passes in order, submitted in batches, read back as linear images.

use crate::error::{Error, Result};
use crate::gpu::layout::PathStats;
use crate::gpu::scene::GpuScene;
use crate::passes::ao::{ao_params, AoBlurPass, AoSettings, RtaoPass, SsaoPass};
use crate::passes::deferred::{DeferredPass, LightingSettings};
use crate::passes::gbuffer::{GBuffer, GBufferData, GBufferPass};
use crate::passes::ibl::{IblResources, IblSettings};
pub use crate::passes::pathtrace::PathSettings;
use crate::passes::pathtrace::{PathTarget, PathTracePass};
use crate::passes::tonemap::{ToneCurve, TonemapPass};
use crate::scene::Camera;
use crate::vk::{raw, Context, GpuTimer, Image};

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
    /// Base colour at the first hit.
    pub albedo: Vec<[f32; 4]>,
    /// Shading normal and distance at the first hit.
    pub normal_depth: Vec<[f32; 4]>,
    /// Samples that came out non-finite (replaced by zero); 0 unless something is wrong.
    pub nonfinite_samples: u32,
    /// Where they arose (see [`crate::gpu::layout::nonfinite_source_names`]).
    pub nonfinite_sources: u32,
    /// GPU time of all the path-tracing dispatches, in milliseconds.
    pub gpu_ms: f64,
}

impl PathImage {
    /// The image's estimated relative error: √(relative MSE), the relative MSE being the mean
    /// over pixels and channels of var(pixel mean) / (pixel mean² + 0.01), the usual metric of
    /// the denoising literature (bright and dark regions count alike).
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

/// Path traces `settings.spp` samples per pixel, calling `progress(done, total)` after each
/// submitted batch.
pub fn path_trace(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    settings: &PathSettings,
    mut progress: impl FnMut(u32, u32),
) -> Result<PathImage> {
    if settings.spp == 0 {
        return Err(Error::Invalid("samples per pixel must be at least 1".into()));
    }
    let pass = PathTracePass::for_scene(ctx, scene, settings.microfacet, settings.heuristic)?;
    let target = PathTarget::new(ctx, settings.size)?;
    let mut params = PathTracePass::params(scene, camera, settings);
    // Batches of about 2^22 pixel-samples keep each submission short (progress, timeouts).
    let pixels = settings.size.0 as u64 * settings.size.1 as u64;
    let batch = ((1u64 << 22) / pixels.max(1)).clamp(1, 64) as u32;
    let mut timer = GpuTimer::new(ctx, 1)?;
    let mut gpu_ms = 0.0;
    let mut done = 0;
    while done < settings.spp {
        let count = batch.min(settings.spp - done);
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "pathtrace")?;
            for s in done..done + count {
                params.sample_index = s;
                pass.record(ctx, cmd, scene, &target, &params)?;
            }
            timer.end(cmd)
        })?;
        gpu_ms += timer.read()?.iter().map(|t| t.ms).sum::<f64>();
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
    let stats: Vec<PathStats> = target.stats.read(ctx)?;
    Ok(PathImage {
        size: settings.size,
        spp: done,
        mean: target.accum.read(ctx)?,
        moment: target.moment.read(ctx)?,
        albedo: target.albedo.read(ctx)?,
        normal_depth: target.normal_depth.read(ctx)?,
        nonfinite_samples: stats[0].nonfinite_samples,
        nonfinite_sources: stats[0].nonfinite_sources,
        gpu_ms,
    })
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

/// Renders `scene` with the hybrid pipeline: the IBL precomputation (BRDF table, prefiltered
/// environment, SH irradiance), G-buffer, deferred lighting, tonemap.
pub fn hybrid(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    settings: &HybridSettings,
) -> Result<HybridImage> {
    settings.lighting.validate()?;
    let size = settings.size;
    let gbuffer = GBuffer::new(ctx, size)?;
    let output = Image::storage_2d(ctx, "hybrid colour", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
    let gbuffer_pass = GBufferPass::new(ctx, scene)?;
    let display = Image::storage_2d(ctx, "hybrid display", size.0, size.1, raw::Format::R8G8B8A8_UNORM)?;
    let deferred = DeferredPass::new(ctx, scene)?;
    let tonemap = TonemapPass::new(ctx)?;
    let gbuffer_params = GBufferPass::params(camera, size);
    let deferred_params = DeferredPass::params(scene, camera, size, &settings.lighting);
    let ibl = IblResources::new(ctx, scene, &settings.ibl)?;
    // SSAO into `ao_raw`, blurred into `ao` (when the settings ask for it).
    let ao_images = match &settings.ao {
        Some(ao) => {
            ao.validate()?;
            let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
            Some((
                make("hybrid ssao")?,
                make("hybrid ssao blurred")?,
                SsaoPass::new(ctx)?,
                AoBlurPass::new(ctx)?,
            ))
        }
        None => None,
    };
    let mut timer = GpuTimer::new(ctx, 8)?;
    ctx.submit(|cmd| {
        output.init_general(ctx, cmd);
        display.init_general(ctx, cmd);
        timer.reset(cmd);
        ibl.record(ctx, cmd, scene, Some(&mut timer))?;
        timer.begin(cmd, "gbuffer")?;
        gbuffer_pass.record(ctx, cmd, scene, &gbuffer.views(), &gbuffer_params)?;
        timer.end(cmd)?;
        let mut ao_view = None;
        if let (Some(ao), Some((ao_raw, ao_blurred, ssao, blur))) = (&settings.ao, &ao_images) {
            ao_raw.init_general(ctx, cmd);
            ao_blurred.init_general(ctx, cmd);
            timer.begin(cmd, "ssao")?;
            ssao.record(ctx, cmd, &gbuffer.views(), ao_raw.view, &SsaoPass::params(camera, size, ao))?;
            timer.end(cmd)?;
            ao_view = Some(ao_raw.view);
            if ao.blur {
                timer.begin(cmd, "ao_blur")?;
                let blur_params = AoBlurPass::params(camera, size);
                blur.record(ctx, cmd, &gbuffer.views(), ao_raw.view, ao_blurred.view, &blur_params)?;
                timer.end(cmd)?;
                ao_view = Some(ao_blurred.view);
            }
        }
        timer.begin(cmd, "lighting")?;
        deferred.record(ctx, cmd, scene, &gbuffer.views(), output.view, &ibl, ao_view, &deferred_params)?;
        timer.end(cmd)?;
        timer.begin(cmd, "tonemap")?;
        tonemap.record(ctx, cmd, output.view, display.view, size, settings.exposure, settings.curve)?;
        timer.end(cmd)
    })?;
    let pass_ms = timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect();
    Ok(HybridImage {
        size,
        color: output.read(ctx)?,
        display: display.read(ctx)?,
        gbuffer: gbuffer.read(ctx)?,
        pass_ms,
    })
}

/// Which ambient occlusion estimator [`ambient_occlusion`] runs.
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

/// Renders the G-buffer of `scene` seen by `camera` at `size` and its ambient occlusion by
/// `method` (see [`crate::passes::ao`] for the definition both estimate), blurred when
/// `settings.blur`.
pub fn ambient_occlusion(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    method: AoMethod,
    settings: &AoSettings,
) -> Result<AoImage> {
    settings.validate()?;
    let gbuffer = GBuffer::new(ctx, size)?;
    let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
    let raw_ao = make("ambient occlusion")?;
    let blurred = make("ambient occlusion blurred")?;
    let gbuffer_pass = GBufferPass::new(ctx, scene)?;
    let ssao = SsaoPass::new(ctx)?;
    let rtao = RtaoPass::new(ctx, scene)?;
    let blur = AoBlurPass::new(ctx)?;
    let gbuffer_params = GBufferPass::params(camera, size);
    let params = ao_params(camera, size, settings);
    let blur_params = AoBlurPass::params(camera, size);
    let views = gbuffer.views();
    let mut timer = GpuTimer::new(ctx, 3)?;
    ctx.submit(|cmd| {
        raw_ao.init_general(ctx, cmd);
        blurred.init_general(ctx, cmd);
        timer.reset(cmd);
        timer.begin(cmd, "gbuffer")?;
        gbuffer_pass.record(ctx, cmd, scene, &views, &gbuffer_params)?;
        timer.end(cmd)?;
        match method {
            AoMethod::Ssao => {
                timer.begin(cmd, "ssao")?;
                ssao.record(ctx, cmd, &views, raw_ao.view, &params)?;
            }
            AoMethod::Rtao => {
                timer.begin(cmd, "rtao")?;
                rtao.record(ctx, cmd, scene, &views, raw_ao.view, &params)?;
            }
        }
        timer.end(cmd)?;
        if settings.blur {
            timer.begin(cmd, "ao_blur")?;
            blur.record(ctx, cmd, &views, raw_ao.view, blurred.view, &blur_params)?;
            timer.end(cmd)?;
        }
        Ok(())
    })?;
    let pass_ms = timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect();
    let unblurred: Vec<f32> = raw_ao.read(ctx)?;
    let values = if settings.blur { blurred.read(ctx)? } else { unblurred.clone() };
    Ok(AoImage { size, values, unblurred, gbuffer: gbuffer.read(ctx)?, pass_ms })
}
