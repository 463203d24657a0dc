//! The first of [`Passes`]' three jobs: its pipelines, each built once, at first use (or ahead,
//! by the `prepare` calls, on threads of their own while a scene uploads), keyed by what
//! specialises them. [`super::record`] records frames from them; [`super::oneshot`] renders.

use super::*;

/// A lazily built pipeline.
pub(super) fn built<T>(cell: &OnceLock<T>, build: impl FnOnce() -> Result<T>) -> Result<&T> {
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
    pub(super) ctx: Context,
    pub(super) features: SceneFeatures,
    pub(super) gbuffer: OnceLock<GBufferPass>,
    /// The G-buffer kernel that resolves a visibility buffer, and the rasterizer's kernels.
    pub(super) gbuffer_raster: OnceLock<(GBufferPass, VisibilityPass)>,
    /// The lighting pass by its kernel's specialization ([`DeferredPass::spec`]: the shadow
    /// method, probes, lightmaps, ReSTIR, sized lights).
    pub(super) deferred: Cache<deferred::Spec, DeferredPass>,
    /// ReSTIR's kernels by (unbiased, temporal).
    pub(super) restir: Cache<(bool, bool), RestirPass>,
    pub(super) shadow: OnceLock<ShadowPass>,
    pub(super) probe: OnceLock<ProbePass>,
    pub(super) lightmap: OnceLock<LightmapPass>,
    pub(super) ssao: OnceLock<SsaoPass>,
    pub(super) gtao: OnceLock<GtaoPass>,
    pub(super) ao_blur: OnceLock<AoBlurPass>,
    pub(super) rtao: OnceLock<RtaoPass>,
    pub(super) tonemap: OnceLock<TonemapPass>,
    pub(super) taa: OnceLock<TaaPass>,
    /// The megakernel's pass by the estimator ([`PathOptions`]).
    pub(super) path: Cache<PathOptions, PathTracePass>,
    /// The wavefront path tracer's stages by the estimator.
    pub(super) wavefront: Cache<PathOptions, WavefrontPass>,
    pub(super) resolve: OnceLock<ResolvePass>,
    pub(super) denoise: OnceLock<DenoisePass>,
    pub(super) temporal: OnceLock<TemporalPass>,
    /// The frame graphs' transient images, kept from frame to frame.
    pub(super) transients: TransientPool,
}
impl Passes {
    /// The passes for `scene`'s features (no pipeline is built yet).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Self {
        Self::with_features(ctx, scene.features())
    }

    /// New passes for `scene` when these cannot render it ([`SceneFeatures::renders`]), made for
    /// a walk's stack that holds both its BVH and the one these were made for
    /// ([`SceneFeatures::widened_to`]): a moving scene's stack depth changes from frame to frame,
    /// and kernels made for the deepest so far serve the shallower ones without a recompile.
    /// `None` when these serve it. No pipeline is built yet.
    pub fn for_moved(&self, scene: &GpuScene) -> Option<Passes> {
        let features = scene.features();
        (!self.features.renders(&features))
            .then(|| Self::with_features(&self.ctx, self.features.widened_to(&features)))
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
            gbuffer_raster: OnceLock::new(),
            deferred: Cache::new(),
            restir: Cache::new(),
            shadow: OnceLock::new(),
            probe: OnceLock::new(),
            lightmap: OnceLock::new(),
            ssao: OnceLock::new(),
            gtao: OnceLock::new(),
            ao_blur: OnceLock::new(),
            rtao: OnceLock::new(),
            tonemap: OnceLock::new(),
            taa: OnceLock::new(),
            path: Cache::new(),
            wavefront: Cache::new(),
            resolve: OnceLock::new(),
            denoise: OnceLock::new(),
            temporal: OnceLock::new(),
            transients: TransientPool::new(),
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
    pub(super) fn check(&self, scene: &GpuScene) -> Result<()> {
        let features = scene.features();
        if !self.features.renders(&features) {
            return Err(Error::Invalid(format!(
                "the passes were built for a scene with {:?}, this one has {features:?}: build new passes",
                self.features
            )));
        }
        Ok(())
    }

    pub(super) fn gbuffer_pass(&self) -> Result<&GBufferPass> {
        built(&self.gbuffer, || GBufferPass::for_features(&self.ctx, &self.features))
    }

    /// The visibility buffer's kernels and the G-buffer kernel that resolves it.
    pub(super) fn gbuffer_raster_passes(&self) -> Result<&(GBufferPass, VisibilityPass)> {
        built(&self.gbuffer_raster, || {
            Ok((
                GBufferPass::with_raster(&self.ctx, &self.features, true)?,
                VisibilityPass::for_features(&self.ctx, &self.features)?,
            ))
        })
    }

    /// The lighting pass for `settings` and what the frame brings ([`DeferredPass::spec`]).
    pub(super) fn deferred_pass(
        &self,
        settings: &LightingSettings,
        method: ShadowMethod,
        probes: bool,
        lightmaps: bool,
        restir: bool,
    ) -> Result<&DeferredPass> {
        let spec = DeferredPass::spec(settings, method, probes, lightmaps, restir)?;
        self.deferred.get_or_try_init(spec, || DeferredPass::from_spec(&self.ctx, &self.features, spec))
    }

    /// Builds the two pipelines of [`Passes::hybrid_with`] that take longest on lavapipe (the
    /// G-buffer's and the lighting pass's for `settings`, with a probe volume and lightmaps or
    /// not) side by side, if they are not built yet. Needs no scene: a host can call this on a
    /// thread while the scene's BVH is built and uploaded, as [`Passes::prepare_path_trace`].
    pub fn prepare_hybrid(&self, settings: &HybridSettings, probes: bool, lightmaps: bool) -> Result<()> {
        let restir = settings.lighting.direct.restir().is_some();
        let lighting = settings.lighting_with_shadows();
        std::thread::scope(|s| {
            let lighting = s.spawn(|| {
                self.deferred_pass(&lighting, settings.shadows.method, probes, lightmaps, restir).map(|_| ())
            });
            let gbuffer = self.gbuffer_pass().map(|_| ());
            let lighting = lighting.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            gbuffer.and(lighting)
        })
    }

    pub(super) fn restir_pass(&self, scene: &GpuScene, settings: &RestirSettings) -> Result<&RestirPass> {
        let (unbiased, temporal) = (settings.unbiased, settings.temporal);
        self.restir
            .get_or_try_init((unbiased, temporal), || RestirPass::new(&self.ctx, scene, unbiased, temporal))
    }

    pub(super) fn probe_pass(&self, scene: &GpuScene) -> Result<&ProbePass> {
        built(&self.probe, || ProbePass::new(&self.ctx, scene))
    }

    pub(super) fn shadow_pass(&self, scene: &GpuScene) -> Result<&ShadowPass> {
        built(&self.shadow, || ShadowPass::new(&self.ctx, scene))
    }

    pub(super) fn ssao_pass(&self) -> Result<&SsaoPass> {
        built(&self.ssao, || SsaoPass::new(&self.ctx))
    }

    pub(super) fn gtao_pass(&self) -> Result<&GtaoPass> {
        built(&self.gtao, || GtaoPass::new(&self.ctx))
    }

    pub(super) fn blur_pass(&self) -> Result<&AoBlurPass> {
        built(&self.ao_blur, || AoBlurPass::new(&self.ctx))
    }

    pub(super) fn rtao_pass(&self, scene: &GpuScene) -> Result<&RtaoPass> {
        self.check(scene)?;
        self.rtao_stage()
    }

    pub(super) fn rtao_stage(&self) -> Result<&RtaoPass> {
        built(&self.rtao, || RtaoPass::for_features(&self.ctx, &self.features))
    }

    pub(super) fn tonemap_pass(&self) -> Result<&TonemapPass> {
        built(&self.tonemap, || TonemapPass::new(&self.ctx))
    }

    pub(super) fn taa_pass(&self) -> Result<&TaaPass> {
        built(&self.taa, || TaaPass::new(&self.ctx))
    }

    pub(super) fn resolve_pass(&self) -> Result<&ResolvePass> {
        built(&self.resolve, || ResolvePass::new(&self.ctx))
    }

    pub(super) fn denoise_pass(&self) -> Result<&DenoisePass> {
        built(&self.denoise, || DenoisePass::new(&self.ctx))
    }

    pub(super) fn temporal_pass(&self) -> Result<&TemporalPass> {
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
                .and_then(|_| {
                    self.deferred_pass(
                        &LightingSettings::default(),
                        ShadowMethod::RayTraced,
                        false,
                        false,
                        false,
                    )
                })
                .and_then(|_| self.rtao_stage())
                .and_then(|_| self.ssao_pass())
                .and_then(|_| self.gtao_pass())
                .and_then(|_| self.blur_pass())
                .and_then(|_| self.tonemap_pass())
                .and_then(|_| self.taa_pass())
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
    pub(super) fn lazy_path_pass(&self, scene: &GpuScene, options: PathOptions) -> Result<&PathTracePass> {
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
    pub(super) fn lazy_wavefront_pass(
        &self,
        scene: &GpuScene,
        options: PathOptions,
    ) -> Result<&WavefrontPass> {
        self.check(scene)?;
        Ok(self.wavefront_stages(options))
    }

    /// The wavefront path tracer's pass for `options`, no stage built yet.
    pub(super) fn wavefront_stages(&self, options: PathOptions) -> &WavefrontPass {
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
}
