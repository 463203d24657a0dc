//! The third of [`Passes`]' jobs: one-shot renders and bakes, which allocate their images,
//! submit in batches, wait and read back; and the free functions that build a [`Passes`] for
//! one render.

use super::pipelines::built;
use super::*;

/// GPU milliseconds by pass name, in the order the passes first ran.
type PassTimes = Vec<(String, f64)>;

/// `times` summed by name (a pass recorded several times: layers, sub-frames), in the order
/// each name first ran.
fn summed_by_name(times: Vec<crate::vk::PassTime>) -> PassTimes {
    let mut summed: PassTimes = Vec::new();
    for t in times {
        match summed.iter_mut().find(|(name, _)| *name == t.name) {
            Some(pass) => pass.1 += t.ms,
            None => summed.push((t.name, t.ms)),
        }
    }
    summed
}

impl Passes {
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
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                timer.begin(cmd, "probes")?;
                self.record_probe_update(rec, scene, volume, count, 0.0, settings)?;
                timer.end(cmd)
            })?;
            ms += timer.read()?.iter().map(|t| t.ms).sum::<f64>();
            progress(sweep, sweeps);
        }
        Ok(ms)
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
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                self.shadow_pass(scene)?.record(rec, scene, maps, view, Some(&mut timer))
            })?;
            let steps = summed_by_name(timer.read()?);
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
        ctx.record(|rec| {
            let cmd = rec.cmd();
            images.init_general(ctx, cmd);
            output.init_general(ctx, cmd);
            timer.reset(cmd);
            timer.begin(cmd, "denoise")?;
            pass.record(rec, &uploaded.inputs(), &images, output.view, settings)?;
            timer.end(cmd)
        })?;
        let gpu_ms = timer.read()?.iter().map(|t| t.ms).sum();
        Ok(DenoisedImage { size: image.size, color: output.read(ctx)?, gpu_ms })
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
        ctx.record(|rec| {
            let cmd = rec.cmd();
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
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                timer.begin(cmd, "denoise")?;
                let temporal = (temporal_pass, &mut history, &camera);
                pass.record_temporal(rec, &uploaded.inputs(), &images, output.view, settings, temporal)?;
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
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                timer.begin(cmd, "pathtrace")?;
                self.record_path_samples(rec, scene, camera, &target, settings, done..done + count)?;
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

    /// A visibility buffer for a G-buffer of `size` when `method` rasterizes and the device and
    /// `scene` allow it ([`VisibilityBuffer::unsupported`]); `None` (a ray-cast G-buffer, said in
    /// the log) otherwise.
    pub fn visibility_for(
        &self,
        scene: &GpuScene,
        size: (u32, u32),
        method: GBufferMethod,
    ) -> Result<Option<VisibilityBuffer>> {
        if method != GBufferMethod::Raster {
            return Ok(None);
        }
        if let Some(why) = VisibilityBuffer::unsupported(&self.ctx, scene) {
            log::info!("the G-buffer is ray-cast: {why}");
            return Ok(None);
        }
        VisibilityBuffer::new(&self.ctx, scene, size).map(Some)
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
        let views = gbuffer.views();
        // The environment's tables and the G-buffer first (the shadow maps render for its
        // view), then the rest of the frame.
        let mut first_timer = GpuTimer::new(ctx, 10)?;
        let mut visibility = self.visibility_for(scene, size, settings.gbuffer)?;
        let mut visibility_ms = None;
        ctx.record(|rec| {
            let cmd = rec.cmd();
            first_timer.reset(cmd);
            ibl.record(rec, scene, Some(&mut first_timer))?;
            if let Some(vis) = &visibility {
                first_timer.begin(cmd, "visibility")?;
                self.record_visibility(rec, scene, camera, vis)?;
                first_timer.end(cmd)?;
            }
            first_timer.begin(cmd, "gbuffer")?;
            self.record_gbuffer_resolve(rec, scene, camera, &views, visibility.as_ref())?;
            first_timer.end(cmd)
        })?;
        // Tile lists too short for this view: grown, and the G-buffer rendered again.
        while let Some(vis) = visibility.as_mut() {
            let Some(entries) = vis.check(ctx)? else { break };
            vis.reserve(ctx, entries)?;
            let mut timer = GpuTimer::new(ctx, 1)?;
            ctx.record(|rec| {
                timer.reset(rec.cmd());
                timer.begin(rec.cmd(), "visibility")?;
                self.record_visibility(rec, scene, camera, vis)?;
                timer.end(rec.cmd())?;
                self.record_gbuffer_resolve(rec, scene, camera, &views, Some(vis))
            })?;
            visibility_ms = timer.read()?.first().map(|t| t.ms);
        }
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
            visibility: None,
            ao: None,
            hdr: output.view,
            ldr: Some(display.view),
            shadows: shadows.as_ref(),
            probes,
            lightmaps,
            reservoirs: reservoirs.as_ref(),
            taa: None,
        };
        // ReSTIR's one-shot render runs its frames with the camera still (its history), timing
        // the last.
        let frames = settings.lighting.direct.restir().map_or(1, |r| r.frames);
        let frame = Frame { scene, ibl: &ibl, camera };
        let (color, shading_ms) = if settings.samples > 1 {
            // The G-buffer above (through the pixels' centres) is the AOVs' and the shadow
            // maps' view; the sub-frames render their own.
            let sub = GBuffer::new(ctx, size)?;
            let sub_views = sub.views();
            let targets = HybridTargets { gbuffer: &sub_views, ldr: None, ..targets };
            ctx.record(|rec| {
                output.init_general(ctx, rec.cmd());
                display.init_general(ctx, rec.cmd());
                Ok(())
            })?;
            self.supersample(frame, &targets, settings, frames, visibility.as_mut(), &display)?
        } else {
            let mut timer = GpuTimer::new(ctx, 8)?;
            ctx.record(|rec| {
                let cmd = rec.cmd();
                output.init_general(ctx, cmd);
                display.init_general(ctx, cmd);
                timer.reset(cmd);
                self.record_shading_frames(rec, frame, &targets, settings, frames, Some(&mut timer))
            })?;
            (output.read(ctx)?, timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect())
        };
        // In the order they ran: the environment's tables and the G-buffer, the maps, the rest.
        let mut pass_ms: PassTimes = first_timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect();
        if let Some(ms) = visibility_ms {
            for (name, t) in &mut pass_ms {
                if name == "visibility" {
                    *t = ms;
                }
            }
        }
        pass_ms.extend(shadow_ms);
        pass_ms.extend(shading_ms);
        Ok(HybridImage { size, color, display: display.read(ctx)?, gbuffer: gbuffer.read(ctx)?, pass_ms })
    }

    /// Records the hybrid frame's shading of `frame` (its G-buffer in `targets`) `restir_frames`
    /// times with the camera still: ReSTIR's one-shot render builds its history over them, each
    /// with its own random numbers (1 without ReSTIR). Only the last is timed into `timer`.
    fn record_shading_frames(
        &self,
        rec: &mut Recorder<'_>,
        frame: Frame<'_>,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        restir_frames: u32,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        for f in 0..restir_frames {
            let mut one = settings.clone();
            one.lighting.frame = settings.lighting.frame.wrapping_mul(restir_frames).wrapping_add(f);
            let timer = if f + 1 == restir_frames { timer.as_deref_mut() } else { None };
            self.record_hybrid_shading(rec, frame, targets, &one, timer)?;
        }
        Ok(())
    }

    /// The sub-frames of a supersampled one-shot hybrid render ([`HybridSettings::samples`]):
    /// each a G-buffer into `targets.gbuffer` (rasterized into `visibility` when given) and the
    /// shading into `targets.hdr` for the frame's camera jittered, then their running mean
    /// ([`TaaMode::Accumulate`]), tonemapped into `display`. Returns the mean radiance and the
    /// GPU milliseconds of each pass summed over the sub-frames (ReSTIR's: its last frame of
    /// each).
    fn supersample(
        &self,
        frame: Frame<'_>,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        restir_frames: u32,
        mut visibility: Option<&mut VisibilityBuffer>,
        display: &Image,
    ) -> Result<(Vec<[f32; 4]>, PassTimes)> {
        let ctx = &self.ctx;
        let size = settings.size;
        let history = TaaHistory::new(ctx, size, Default::default())?;
        let cameras: Vec<Camera> =
            supersample_jitters(settings.samples).into_iter().map(|j| frame.camera.jittered(j)).collect();
        // Per sub-frame: visibility, G-buffer, the shading's passes (at most 6), the resolve.
        let mut timer = GpuTimer::new(ctx, 10 * settings.samples + 1)?;
        loop {
            history.reset();
            ctx.record(|rec| {
                let cmd = rec.cmd();
                history.init_general(ctx, cmd);
                timer.reset(cmd);
                for camera in &cameras {
                    let mut t = Some(&mut timer);
                    if let Some(vis) = visibility.as_deref() {
                        GpuTimer::time(&mut t, cmd, "visibility", || {
                            self.record_visibility(rec, frame.scene, camera, vis)
                        })?;
                    }
                    GpuTimer::time(&mut t, cmd, "gbuffer", || {
                        self.record_gbuffer_resolve(
                            rec,
                            frame.scene,
                            camera,
                            targets.gbuffer,
                            visibility.as_deref(),
                        )
                    })?;
                    let sub_frame = Frame { camera, ..frame };
                    self.record_shading_frames(
                        rec,
                        sub_frame,
                        targets,
                        settings,
                        restir_frames,
                        t.as_deref_mut(),
                    )?;
                    GpuTimer::time(&mut t, cmd, "taa", || {
                        self.record_taa(
                            rec,
                            sub_frame,
                            targets.gbuffer,
                            targets.hdr,
                            &history,
                            TaaMode::Accumulate,
                        )
                    })?;
                }
                let view = history.resolved().view;
                GpuTimer::time(&mut Some(&mut timer), cmd, "tonemap", || {
                    self.record_tonemap(rec, view, display.view, size, settings.exposure, settings.curve)
                })
            })?;
            // The jittered views' tile lists may overflow where the centres' did not: grown,
            // and every sub-frame rendered again.
            match visibility.as_deref_mut() {
                Some(vis) => match vis.check(ctx)? {
                    Some(entries) => vis.reserve(ctx, entries)?,
                    None => break,
                },
                None => break,
            }
        }
        Ok((history.resolved().read(ctx)?, summed_by_name(timer.read()?)))
    }

    /// Renders the G-buffer of `scene` seen by `camera` at `size` and its ambient occlusion by
    /// `settings.method` (see [`crate::passes::ao`] for the definition they all estimate),
    /// blurred (and at half resolution upsampled) when `settings.blur`.
    pub fn ambient_occlusion(
        &self,
        scene: &GpuScene,
        camera: &Camera,
        size: (u32, u32),
        settings: &AoSettings,
    ) -> Result<AoImage> {
        let ctx = &self.ctx;
        settings.validate()?;
        let gbuffer = GBuffer::new(ctx, size)?;
        let ao_size = settings.resolution.ao_size(size);
        let make = |name, (w, h)| Image::storage_2d(ctx, name, w, h, raw::Format::R32_SFLOAT);
        let raw_ao = make("ambient occlusion", ao_size)?;
        let blurred = make("ambient occlusion blurred", size)?;
        let mut graph = Graph::new();
        let views = GBufferImages::import(&mut graph, &gbuffer.views());
        let unblurred = graph.import("ambient occlusion", raw_ao.view);
        self.add_gbuffer(&mut graph, scene, camera, views, None);
        self.add_ao(&mut graph, scene, camera, views, unblurred, settings);
        if settings.blur {
            let output = graph.import("ambient occlusion blurred", blurred.view);
            self.add_ao_blur(&mut graph, camera, views, unblurred, output, settings);
        }
        let mut timer = GpuTimer::new(ctx, 3)?;
        ctx.record(|rec| {
            let cmd = rec.cmd();
            raw_ao.init_general(ctx, cmd);
            blurred.init_general(ctx, cmd);
            timer.reset(cmd);
            self.execute(rec, graph, Some(&mut timer)).map(drop)
        })?;
        let pass_ms = timer.read()?.into_iter().map(|t| (t.name, t.ms)).collect();
        let unblurred: Vec<f32> = raw_ao.read(ctx)?;
        let values = if settings.blur { blurred.read(ctx)? } else { unblurred.clone() };
        Ok(AoImage { size, ao_size, values, unblurred, gbuffer: gbuffer.read(ctx)?, pass_ms })
    }
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
    settings: &AoSettings,
) -> Result<AoImage> {
    Passes::new(ctx, scene).ambient_occlusion(scene, camera, size, settings)
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
