//! GPU time per pass of each method on one scene: the hybrid passes (G-buffer, SSAO (16
//! directions × 4 steps, radius 0.5) and its blur, deferred lighting with IBL × AO) and one
//! path-traced sample per pixel, each a median over repeats after a warm-up
//! ([`super::rays::warm_up`]),
//! from GPU timestamps.

use anyhow::Result;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::{AoBlurPass, AoSettings, SsaoPass};
use umbra::passes::deferred::{DeferredPass, LightingSettings};
use umbra::passes::gbuffer::{GBuffer, GBufferPass};
use umbra::passes::pathtrace::{Heuristic, Microfacet, PathTarget, PathTracePass};
use umbra::render::PathSettings;
use umbra::scene::Camera;
use umbra::vk::{raw, Context, GpuTimer, Image};

/// A pass's median GPU time.
pub struct PassTiming {
    /// The pass.
    pub name: String,
    /// Median GPU milliseconds over the repeats.
    pub median_ms: f64,
    /// Fastest repeat.
    pub min_ms: f64,
}

/// Times every pass at `size`, `repeats` times after one warm-up submission.
pub fn run(
    ctx: &Context,
    scene: &GpuScene,
    camera: &Camera,
    size: (u32, u32),
    repeats: usize,
    lighting: &LightingSettings,
) -> Result<Vec<PassTiming>> {
    let gbuffer = GBuffer::new(ctx, size)?;
    let output = Image::storage_2d(ctx, "bench colour", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT)?;
    let gbuffer_pass = GBufferPass::new(ctx, scene)?;
    let deferred = DeferredPass::new(ctx, scene)?;
    let ibl = umbra::passes::ibl::IblResources::build(ctx, scene, &Default::default())?;
    let pathtrace = PathTracePass::for_scene(ctx, scene, Microfacet::Ggx, Heuristic::Power)?;
    let target = PathTarget::new(ctx, size)?;
    let gbuffer_params = GBufferPass::params(camera, size);
    let deferred_params = DeferredPass::params(scene, camera, size, lighting);
    let path_settings = PathSettings { size, env: lighting.env, ..PathSettings::default() };
    let mut path_params = PathTracePass::params(scene, camera, &path_settings);
    let ao_settings = AoSettings::default();
    let make = |name| Image::storage_2d(ctx, name, size.0, size.1, raw::Format::R32_SFLOAT);
    let (ao_raw, ao_blurred) = (make("bench ssao")?, make("bench ssao blurred")?);
    let (ssao, blur) = (SsaoPass::new(ctx)?, AoBlurPass::new(ctx)?);
    let ssao_params = SsaoPass::params(camera, size, &ao_settings);
    let blur_params = AoBlurPass::params(camera, size);
    ctx.submit(|cmd| {
        output.init_general(ctx, cmd);
        ao_raw.init_general(ctx, cmd);
        ao_blurred.init_general(ctx, cmd);
        Ok(())
    })?;
    let views = gbuffer.views();
    let ao_view = Some(ao_blurred.view);
    super::rays::warm_up(|| {
        ctx.submit(|cmd| {
            gbuffer_pass.record(ctx, cmd, scene, &views, &gbuffer_params)?;
            ssao.record(ctx, cmd, &views, ao_raw.view, &ssao_params)?;
            blur.record(ctx, cmd, &views, ao_raw.view, ao_blurred.view, &blur_params)?;
            deferred.record(ctx, cmd, scene, &views, output.view, &ibl, ao_view, &deferred_params)?;
            pathtrace.record(ctx, cmd, scene, &target, &path_params)
        })
    })?;
    let mut timer = GpuTimer::new(ctx, 5)?;
    let mut samples: Vec<Vec<f64>> = vec![Vec::new(); 5];
    let mut names = Vec::new();
    for repeat in 0..=repeats {
        path_params.sample_index = repeat as u32;
        ctx.submit(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "gbuffer")?;
            gbuffer_pass.record(ctx, cmd, scene, &views, &gbuffer_params)?;
            timer.end(cmd)?;
            timer.begin(cmd, "ssao")?;
            ssao.record(ctx, cmd, &views, ao_raw.view, &ssao_params)?;
            timer.end(cmd)?;
            timer.begin(cmd, "ao_blur")?;
            blur.record(ctx, cmd, &views, ao_raw.view, ao_blurred.view, &blur_params)?;
            timer.end(cmd)?;
            timer.begin(cmd, "lighting")?;
            deferred.record(ctx, cmd, scene, &views, output.view, &ibl, ao_view, &deferred_params)?;
            timer.end(cmd)?;
            timer.begin(cmd, "pathtrace 1 spp")?;
            pathtrace.record(ctx, cmd, scene, &target, &path_params)?;
            timer.end(cmd)
        })?;
        let times = timer.read()?;
        if repeat == 0 {
            names = times.iter().map(|t| t.name.clone()).collect();
            continue; // warm-up
        }
        for (k, t) in times.iter().enumerate() {
            samples[k].push(t.ms);
        }
    }
    Ok(names
        .into_iter()
        .zip(samples)
        .map(|(name, mut ms)| PassTiming {
            name,
            min_ms: ms.iter().copied().fold(f64::INFINITY, f64::min),
            median_ms: super::rays::median(&mut ms),
        })
        .collect())
}
