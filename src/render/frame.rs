//! umbra's passes in a frame graph ([`crate::vk::Graph`]): one `add_*` per pass, each declaring
//! the images it reads and writes; the hybrid frame is wired from them ([`Passes::add_hybrid`]),
//! and a host adds its own passes to the same graph ([`crate::embed::Renderer::record_graph`]).

use super::*;

/// The stage of the hybrid frame a pass of this file belongs to, by the name its `add_*` gives
/// it: `"gbuffer"` (primary visibility and the surfaces' attributes), `"ao"` (ambient occlusion
/// with its blur or upsample), `"lighting"` (ReSTIR's reuse and the lighting itself),
/// `"antialias"` (the TAA resolve) or `"tonemap"`; `None` for a pass of another's (a host's). Benchmarks sum a stage's passes
/// whatever they are called, so a pass added here is given its stage here.
pub fn stage_of(pass: &str) -> Option<&'static str> {
    match pass {
        "visibility" | "gbuffer" => Some("gbuffer"),
        "ssao" | "gtao" | "rtao" | "ao_blur" => Some("ao"),
        "restir" | "lighting" => Some("lighting"),
        "taa" => Some("antialias"),
        "tonemap" => Some("tonemap"),
        _ => None,
    }
}

impl Passes {
    // Each `add_*` declares its pass's images and records through its `record_*` twin
    // (record.rs), which checks the settings and specialises the kernel.

    /// Adds the G-buffer of `scene` seen from `camera`, written into `gbuffer`: rasterized into
    /// `visibility` (the pass `visibility`) and resolved from it when given, ray-cast otherwise
    /// (the pass `gbuffer` either way).
    pub fn add_gbuffer<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        scene: &'g GpuScene,
        camera: &'g Camera,
        gbuffer: GBufferImages,
        visibility: Option<&'g VisibilityBuffer>,
    ) {
        if let Some(vis) = visibility {
            // The visibility buffer is no graph image: the recorder orders its writes before
            // the resolve's reads.
            graph
                .add_pass("visibility")
                .record(move |rec, _| self.record_visibility(rec, scene, camera, vis));
        }
        graph.add_pass("gbuffer").write_all(gbuffer.images).record(move |rec, views| {
            self.record_gbuffer_resolve(rec, scene, camera, &gbuffer.views(views), visibility)
        });
    }

    /// Adds the ambient occlusion of `gbuffer` (seen from `camera`) by `settings.method` into
    /// `output` (`R32_SFLOAT`, unblurred; half-resolution AO fills
    /// [`crate::passes::ao::AoResolution::ao_size`] of it). `scene` is read by RTAO alone. The
    /// pass is named after the method.
    pub fn add_ao<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        scene: &'g GpuScene,
        camera: &'g Camera,
        gbuffer: GBufferImages,
        output: GraphImage,
        settings: &AoSettings,
    ) {
        let settings = *settings;
        graph.add_pass(settings.method.name()).read_all(gbuffer.images).write(output).record(
            move |rec, views| {
                self.record_ao_unblurred(rec, scene, camera, &gbuffer.views(views), views[output], &settings)
            },
        );
    }

    /// Adds the depth-aware blur of `ao` (computed with `settings`; at half resolution the blur
    /// is its upsample too) into `blurred` (both `R32_SFLOAT`).
    pub fn add_ao_blur<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        camera: &'g Camera,
        gbuffer: GBufferImages,
        ao: GraphImage,
        blurred: GraphImage,
        settings: &AoSettings,
    ) {
        let settings = *settings;
        graph.add_pass("ao_blur").read_all(gbuffer.images).read(ao).write(blurred).record(
            move |rec, views| {
                self.record_ao_blur(rec, camera, &gbuffer.views(views), views[ao], views[blurred], &settings)
            },
        );
    }

    /// Adds ReSTIR's candidates, temporal and spatial reuse for `gbuffer` (seen from `camera`)
    /// into `reservoirs`, with the random numbers of `lighting`'s frame and seed and its
    /// [`crate::passes::deferred::DirectLight::Restir`] settings; the lighting pass then shades
    /// them ([`LightingInputs::restir`]).
    pub fn add_restir<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        scene: &'g GpuScene,
        camera: &'g Camera,
        gbuffer: GBufferImages,
        reservoirs: &'g Reservoirs,
        lighting: &LightingSettings,
    ) -> Result<()> {
        let lighting = *lighting;
        let Some(restir) = lighting.direct.restir().copied() else {
            return Err(Error::Invalid("ReSTIR was added but the lighting does not sample by it".into()));
        };
        graph.add_pass("restir").read_all(gbuffer.images).record(move |rec, views| {
            self.record_restir(rec, scene, camera, &gbuffer.views(views), reservoirs, &restir, &lighting)
        });
        Ok(())
    }

    /// Adds deferred lighting of `gbuffer` into `output` (`R32G32B32A32_SFLOAT`) with the
    /// frame's scene, camera and image-based lighting and the optional `inputs` (ambient
    /// occlusion by its graph image, written by an earlier pass; shadow maps, probes, lightmaps
    /// and ReSTIR's reservoirs, each recorded before).
    pub fn add_lighting<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        frame: Frame<'g>,
        gbuffer: GBufferImages,
        output: GraphImage,
        inputs: LightingInputs<'g, GraphImage>,
        settings: &LightingSettings,
    ) {
        let settings = *settings;
        graph.add_pass("lighting").read_all(gbuffer.images).read_all(inputs.ao).write(output).record(
            move |rec, views| {
                let gbuffer = gbuffer.views(views);
                self.record_lighting(rec, frame, &gbuffer, views[output], &inputs.resolve(views), &settings)
            },
        );
    }

    /// Adds the display transform of `hdr` (`R32G32B32A32_SFLOAT`) into `ldr` (`R8G8B8A8_UNORM`,
    /// sRGB-encoded values).
    pub fn add_tonemap<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        hdr: GraphImage,
        ldr: GraphImage,
        size: (u32, u32),
        exposure_stops: f32,
        curve: ToneCurve,
    ) {
        graph.add_pass("tonemap").read(hdr).write(ldr).record(move |rec, views| {
            self.record_tonemap(rec, views[hdr], views[ldr], size, exposure_stops, curve)
        });
    }

    /// Adds the anti-aliasing resolve of `current` (the frame's radiance, sampled at the frame
    /// camera's jitter) with `history`, following the frame scene's moved geometry, into its next
    /// image, imported as `resolved` (which
    /// [`TaaHistory::resolved`] names once the pass is recorded).
    pub fn add_taa<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        frame: Frame<'g>,
        gbuffer: GBufferImages,
        current: GraphImage,
        history: &'g TaaHistory,
        mode: TaaMode,
    ) -> GraphImage {
        // The image the resolve writes: the one the last did not (the graph needs it before the
        // pass records, when the history flips).
        let resolved = graph.import("taa resolved", history.next_view());
        graph.add_pass("taa").read_all(gbuffer.images).read(current).write(resolved).record(
            move |rec, views| {
                let gbuffer = gbuffer.views(views);
                self.record_taa(rec, frame, &gbuffer, views[current], history, mode)
            },
        );
        resolved
    }

    /// Adds the hybrid frame's passes to `graph`: the G-buffer into `targets.gbuffer`, then
    /// [`Passes::add_hybrid_shading`]. The one place the hybrid frame is wired.
    pub fn add_hybrid<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        frame: Frame<'g>,
        targets: &HybridTargets<'g>,
        settings: &HybridSettings,
    ) -> Result<GBufferImages> {
        let gbuffer = GBufferImages::import(graph, targets.gbuffer);
        self.add_gbuffer(graph, frame.scene, frame.camera, gbuffer, targets.visibility);
        self.add_hybrid_shading(graph, frame, gbuffer, targets, settings)?;
        Ok(gbuffer)
    }

    /// Adds the hybrid frame's passes after its G-buffer (`gbuffer`, written by an earlier pass
    /// of `graph` or imported) to `graph`: SSAO and its blur into `targets.ao` or, when `None`,
    /// into transient images; ReSTIR; the lighting into `targets.hdr`; the tonemap into
    /// `targets.ldr`.
    pub fn add_hybrid_shading<'g>(
        &'g self,
        graph: &mut Graph<'g>,
        frame: Frame<'g>,
        gbuffer: GBufferImages,
        targets: &HybridTargets<'g>,
        settings: &HybridSettings,
    ) -> Result<()> {
        let Frame { scene, camera, .. } = frame;
        self.check(scene)?;
        let lighting = settings.lighting_with_shadows();
        lighting.validate()?;
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
        let size = gbuffer.size;
        let ao = match &settings.ao {
            Some(ao) => {
                ao.validate()?;
                let (raw_ao, blurred) = match targets.ao {
                    Some((a, b)) => (graph.import("ao", a), graph.import("ao blurred", b)),
                    None => {
                        let format = raw::Format::R32_SFLOAT;
                        let unblurred = ImageDesc { size: ao.resolution.ao_size(size), format };
                        (
                            graph.transient("ao", unblurred),
                            graph.transient("ao blurred", ImageDesc { size, format }),
                        )
                    }
                };
                self.add_ao(graph, scene, camera, gbuffer, raw_ao, ao);
                if ao.blur {
                    self.add_ao_blur(graph, camera, gbuffer, raw_ao, blurred, ao);
                    Some(blurred)
                } else {
                    Some(raw_ao)
                }
            }
            None => None,
        };
        let restir = match (lighting.direct.restir(), targets.reservoirs) {
            (None, _) => None,
            (Some(_), Some(reservoirs)) => {
                self.add_restir(graph, scene, camera, gbuffer, reservoirs, &lighting)?;
                Some(reservoirs)
            }
            (Some(_), None) => {
                return Err(Error::Invalid("the settings ask for ReSTIR but no reservoirs were given".into()))
            }
        };
        let hdr = graph.import("hdr", targets.hdr);
        let inputs =
            LightingInputs { ao, shadows, probes: targets.probes, lightmaps: targets.lightmaps, restir };
        self.add_lighting(graph, frame, gbuffer, hdr, inputs, &lighting);
        let display = match targets.taa {
            Some(history) => {
                history.check_size(size)?;
                self.add_taa(graph, frame, gbuffer, hdr, history, TaaMode::Reproject)
            }
            None => hdr,
        };
        if let Some(ldr) = targets.ldr {
            let ldr = graph.import("ldr", ldr);
            self.add_tonemap(graph, display, ldr, size, settings.exposure, settings.curve);
        }
        Ok(())
    }
}
