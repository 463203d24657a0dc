//! The second of [`Passes`]' jobs: recording passes and whole frames into a command buffer
//! (umbra's or a host's). Nothing here submits.

use super::*;

impl Passes {
    /// Records the ray-cast G-buffer of `scene` seen from `camera` into `target`.
    pub fn record_gbuffer(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        target: &GBufferViews,
    ) -> Result<()> {
        self.record_gbuffer_with(rec, scene, camera, target, None)
    }

    /// Records the G-buffer of `scene` seen from `camera` into `target`: rasterized into
    /// `visibility` and resolved from it when given (made for this scene and `target`'s size),
    /// ray-cast otherwise.
    pub fn record_gbuffer_with(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        target: &GBufferViews,
        visibility: Option<&VisibilityBuffer>,
    ) -> Result<()> {
        if let Some(vis) = visibility {
            self.record_visibility(rec, scene, camera, vis)?;
        }
        self.record_gbuffer_resolve(rec, scene, camera, target, visibility)
    }

    /// Records the visibility buffer of `scene` seen from `camera` into `vis`, for
    /// [`Self::record_gbuffer_resolve`].
    pub fn record_visibility(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        vis: &VisibilityBuffer,
    ) -> Result<()> {
        self.check(scene)?;
        self.gbuffer_raster_passes()?.1.record(rec, scene, camera, vis, None)
    }

    /// Records the G-buffer of `scene` seen from `camera` into `target`, resolved from
    /// `visibility` (recorded before for this camera) when given, ray-cast otherwise.
    pub fn record_gbuffer_resolve(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        target: &GBufferViews,
        visibility: Option<&VisibilityBuffer>,
    ) -> Result<()> {
        self.check(scene)?;
        let params = GBufferPass::params(camera, target.size);
        match visibility {
            Some(vis) => self.gbuffer_raster_passes()?.0.record(rec, scene, target, &params, Some(vis)),
            None => self.gbuffer_pass()?.record(rec, scene, target, &params, None),
        }
    }

    /// Records the ambient occlusion of `gbuffer` by `settings.method` into `raw_ao` and, when
    /// `settings.blur`, its depth-aware blur (or half-resolution AO's upsample) into `blurred`
    /// (`R32_SFLOAT`, the G-buffer's size; `scene` is read by RTAO alone). Returns the view
    /// holding the result.
    #[allow(clippy::too_many_arguments)]
    pub fn record_ao(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        raw_ao: raw::ImageView,
        blurred: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<raw::ImageView> {
        self.record_ao_unblurred(rec, scene, camera, gbuffer, raw_ao, settings)?;
        if !settings.blur {
            return Ok(raw_ao);
        }
        self.record_ao_blur(rec, camera, gbuffer, raw_ao, blurred, settings)?;
        Ok(blurred)
    }

    /// The ambient occlusion of `gbuffer` by `settings.method` into `output`, without its blur.
    pub(super) fn record_ao_unblurred(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        settings.validate()?;
        let params = ao_params(camera, gbuffer.size, settings);
        match settings.method {
            AoMethod::Ssao => self.ssao_pass()?.record(rec, gbuffer, output, &params),
            AoMethod::Gtao => self.gtao_pass()?.record(rec, gbuffer, output, &params),
            AoMethod::Rtao => {
                self.check(scene)?;
                self.rtao_pass(scene)?.record(rec, scene, gbuffer, output, &params)
            }
        }
    }

    /// The depth-aware blur of `ao` (computed with `settings`) into `blurred`.
    pub(super) fn record_ao_blur(
        &self,
        rec: &mut Recorder<'_>,
        camera: &Camera,
        gbuffer: &GBufferViews,
        ao: raw::ImageView,
        blurred: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        let params = AoBlurPass::params(camera, gbuffer.size, settings.resolution);
        self.blur_pass()?.record(rec, gbuffer, ao, blurred, &params)
    }

    /// Records ray-traced AO of `gbuffer` (`settings.samples` rays of length `settings.radius`
    /// per pixel) into `output` (`R32_SFLOAT`, the G-buffer's size), whatever `settings.method`.
    pub fn record_rtao(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        let settings = AoSettings { method: AoMethod::Rtao, ..*settings };
        self.record_ao_unblurred(rec, scene, camera, gbuffer, output, &settings)
    }

    /// Records deferred lighting of `gbuffer` into `output` (`R32G32B32A32_SFLOAT`), with the
    /// `frame`'s scene, camera and precomputed image-based lighting and the optional `inputs`
    /// (ambient occlusion, shadow maps instead of shadow rays, a probe volume and lightmaps for
    /// the diffuse lobe), each recorded before.
    pub fn record_lighting(
        &self,
        rec: &mut Recorder<'_>,
        frame: Frame<'_>,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        inputs: &LightingInputs<'_>,
        settings: &LightingSettings,
    ) -> Result<()> {
        let Frame { scene, ibl, camera } = frame;
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
        self.deferred_pass(settings, method, probes, lightmaps, restir)?
            .record(rec, scene, gbuffer, output, ibl, inputs, &params)
    }

    /// Records ReSTIR's candidates, temporal and spatial reuse for `gbuffer` (seen by `camera`)
    /// into `reservoirs`, with the random numbers of `lighting`'s frame and seed; the lighting
    /// pass then shades them ([`LightingInputs::restir`]). Never submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record_restir(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        gbuffer: &GBufferViews,
        reservoirs: &Reservoirs,
        settings: &RestirSettings,
        lighting: &LightingSettings,
    ) -> Result<()> {
        self.check(scene)?;
        self.restir_pass(scene, settings)?.record(
            rec,
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
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        volume: &mut ProbeVolume,
        count: u32,
        blend_min: f32,
        settings: &LightingSettings,
    ) -> Result<()> {
        self.check(scene)?;
        settings.validate()?;
        self.probe_pass(scene)?.record(rec, scene, volume, count, blend_min, settings.env)
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
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        maps: &ShadowMaps,
        view: Option<ShadowView<'_>>,
    ) -> Result<()> {
        self.check(scene)?;
        self.shadow_pass(scene)?.record(rec, scene, maps, view, None)
    }

    /// Records the display transform of `src` (`R32G32B32A32_SFLOAT`) into `dst`
    /// (`R8G8B8A8_UNORM`, sRGB-encoded values).
    pub fn record_tonemap(
        &self,
        rec: &mut Recorder<'_>,
        src: raw::ImageView,
        dst: raw::ImageView,
        size: (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) -> Result<()> {
        self.tonemap_pass()?.record(rec, src, dst, size, exposure_stops, curve)
    }

    /// Records the anti-aliasing resolve of `current` (the frame's radiance, sampled at the
    /// frame camera's jitter over `gbuffer`'s pixels) with `history` ([`crate::passes::taa`]),
    /// following the frame scene's moved geometry ([`GeometryState`]).
    pub fn record_taa(
        &self,
        rec: &mut Recorder<'_>,
        frame: Frame<'_>,
        gbuffer: &GBufferViews,
        current: raw::ImageView,
        history: &TaaHistory,
        mode: TaaMode,
    ) -> Result<()> {
        let geometry = GeometryState::of(frame.scene);
        self.taa_pass()?.record(rec, gbuffer, current, history, frame.camera, mode, geometry)
    }

    /// Records one hybrid frame into `targets`: G-buffer, SSAO and its blur (when
    /// `settings.ao`), deferred lighting with the frame's image-based light × AO, tonemap (when
    /// `targets.ldr`), each timed under its name when a `timer` is given:
    /// [`Passes::add_hybrid`]'s frame graph.
    pub fn record_hybrid(
        &self,
        rec: &mut Recorder<'_>,
        frame: Frame<'_>,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let mut graph = Graph::new();
        self.add_hybrid(&mut graph, frame, targets, settings)?;
        self.execute(rec, graph, timer).map(drop)
    }

    /// [`Passes::record_hybrid`] after its G-buffer, which `targets.gbuffer` already holds
    /// ([`Passes::record_gbuffer`] of the frame's camera): for shadow maps rendered for the view
    /// between the two ([`crate::passes::shadow::ShadowView`]).
    pub fn record_hybrid_shading(
        &self,
        rec: &mut Recorder<'_>,
        frame: Frame<'_>,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let mut graph = Graph::new();
        let gbuffer = GBufferImages::import(&mut graph, targets.gbuffer);
        self.add_hybrid_shading(&mut graph, frame, gbuffer, targets, settings)?;
        self.execute(rec, graph, timer).map(drop)
    }

    /// Records `graph` into `rec` ([`Graph::execute`]), its transient images from these passes'
    /// pool (kept from frame to frame), each pass timed under its name with `timer` when given.
    pub fn execute(
        &self,
        rec: &mut Recorder<'_>,
        graph: Graph<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> Result<GraphStats> {
        graph.execute(rec, &self.transients, timer)
    }

    /// Records path-traced samples `samples` of `settings`' render into `target` (its samples
    /// `settings.first_sample + samples.start ..` of the sequence; starting at 0 records the
    /// target's clearing first and restarts the running mean). `settings.size` must be the
    /// target's. With RIS reuse ([`crate::passes::pathtrace::RisReuse`]) the target's reservoirs
    /// are made at the first such record, and the samples continue from those the last record
    /// left (starting at 0 clears them too).
    pub fn record_path_samples(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        target: &PathTarget,
        settings: &PathSettings,
        samples: std::ops::Range<u32>,
    ) -> Result<()> {
        let (first, count) = (
            samples.start,
            samples
                .end
                .checked_sub(samples.start)
                .ok_or_else(|| Error::Invalid(format!("samples {samples:?}: the end is before the start")))?,
        );
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
            target.record_clear(rec);
        }
        match settings.integrator {
            Integrator::Megakernel => {
                self.lazy_path_pass(scene, settings.options())?.record(rec, scene, target, &params)
            }
            Integrator::Wavefront => self
                .lazy_wavefront_pass(scene, settings.options())?
                .record(rec, scene, target, settings, &params),
        }
    }

    /// Records the copy of `target`'s running mean into `output` (`R32G32B32A32_SFLOAT`, the
    /// target's size).
    pub fn record_path_resolve(
        &self,
        rec: &mut Recorder<'_>,
        target: &PathTarget,
        output: raw::ImageView,
    ) -> Result<()> {
        self.resolve_pass()?.record(rec, target, output)
    }

    /// Records the denoiser ([`crate::passes::denoise`]) of `target`'s samples so far into
    /// `output` (`R32G32B32A32_SFLOAT`, the target's size, `GENERAL` layout) through `images`
    /// (the target's size, already in `GENERAL` layout).
    pub fn record_denoise(
        &self,
        rec: &mut Recorder<'_>,
        target: &PathTarget,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        self.denoise_pass()?.record(rec, &DenoiseInputs::from(target), images, output, settings)
    }

    /// Records the denoiser of `target`'s samples with temporal accumulation
    /// ([`crate::passes::temporal`]): the frame, seen by `camera`, blended with `history` (which
    /// then holds it), filtered into `output` (`R32G32B32A32_SFLOAT`, the target's size,
    /// `GENERAL` layout) through `images`.
    #[allow(clippy::too_many_arguments)]
    pub fn record_denoise_temporal(
        &self,
        rec: &mut Recorder<'_>,
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
            rec,
            &DenoiseInputs::from(target),
            images,
            output,
            settings,
            temporal,
        )
    }
}
