//! Embedding umbra in a host Vulkan engine.
//!
//! The host keeps its instance, device, queue, allocator, images and command buffers; umbra
//! records its passes into the host's command buffer and never submits it.
//!
//! ```text
//! let ctx = Context::from_host(HostDevice { entry, instance, physical_device, device, queue,
//!                                           queue_family_index, allocator: Some(allocator),
//!                                           int64_atomics: false })?;
//! let mut renderer = Renderer::new(&ctx, &scene)?;          // uploads the scene once
//! // per frame, inside the host's command buffer:
//! renderer.record_gbuffer(cmd, &camera, &gbuffer_views)?;   // or the host writes its own
//! // (or rasterized: `renderer.visibility_buffer(size, GBufferMethod::Raster)?` once, then
//! // `renderer.record_gbuffer_with(cmd, &camera, &gbuffer_views, visibility.as_ref())?`)
//! let ao = renderer.record_ao(cmd, &camera, &gbuffer_views, ao_view, ao_blur_view, &ao_settings)?;
//! // (SSAO, GTAO at full or half resolution, or RTAO: `ao_settings.method`, `.resolution`)
//! renderer.record_lighting(cmd, &camera, &gbuffer_views, hdr_view,
//!     &LightingInputs { ao: Some(ao), ..Default::default() }, &lighting)?;
//! renderer.record_tonemap(cmd, hdr_view, ldr_view, size, 0.0, ToneCurve::KhronosPbrNeutral)?;
//! // or progressive path tracing, a few samples per frame, resolved into the host's image:
//! renderer.record_path_samples(cmd, &camera, &target, &path_settings, first_sample, count)?;
//! renderer.record_path_resolve(cmd, &target, hdr_view)?;
//! // or denoised into it (working images allocated once, moved to GENERAL once):
//! renderer.record_path_denoise(cmd, &target, &denoise_images, hdr_view, &DenoiseSettings::default())?;
//! // or accumulated over frames while the camera moves (a history kept from frame to frame,
//! // made once per view size, moved to GENERAL once; umbra keeps the previous frame's camera):
//! let mut history = renderer.temporal_history(size, TemporalSettings::default())?;
//! renderer.record_path_samples(cmd, &camera, &target, &path_settings_of_this_frame, 0, spp)?;
//! renderer.record_path_denoise_temporal(cmd, &camera, &target, &denoise_images, &mut history,
//!     hdr_view, &DenoiseSettings::default())?;
//! // or the whole hybrid frame in one call (the one wiring the one-shot renders use too):
//! renderer.record_hybrid(cmd, &camera, &HybridTargets { gbuffer: &gbuffer_views,
//!     visibility: None, ao: Some((ao_view, ao_blur_view)), hdr: hdr_view, ldr: Some(ldr_view), shadows: None,
//!     probes: None, lightmaps: None, reservoirs: None, taa: None },
//!     &settings, None)?;
//! // anti-aliased over frames (TAA): a history per view, made once, moved to GENERAL once;
//! // record_hybrid then jitters the camera and resolves; the result is `taa.resolved()`:
//! let taa = renderer.taa_history(size, TaaSettings::default())?;
//! // ... `taa: Some(&taa)` in the targets above
//! // shadow maps instead of shadow rays: placed once, re-recorded when a light, the geometry
//! // or (for a directional light's cascades) the camera changes:
//! let maps = renderer.shadow_maps(&camera, size, &shadow_settings)?;
//! renderer.record_shadow_maps(cmd, &maps, None)?;  // then `shadows: Some(&maps)` in the inputs
//! // or for the view, the cascades' tiles no pixel reads skipped: G-buffer, maps, the rest
//! renderer.record_gbuffer(cmd, &camera, &gbuffer_views)?;
//! renderer.record_shadow_maps(cmd, &maps, Some(ShadowView { camera: &camera, gbuffer: &gbuffer_views }))?;
//! renderer.record_hybrid_shading(cmd, &camera, &targets, &settings, None)?;
//! // many lights: ReSTIR DI, its reservoirs kept from frame to frame (their history):
//! let reservoirs = renderer.reservoirs(size)?;                       // once per view
//! renderer.record_restir(cmd, &camera, &gbuffer_views, &reservoirs, &restir, &lighting)?;
//! // then `restir: Some(&reservoirs)` in the inputs, `DirectLight::Restir(restir)` in `lighting`
//! // indirect diffuse light from irradiance probes: baked once, or a budget updated per frame:
//! let mut probes = renderer.probe_volume(&ProbeSettings::default())?;
//! renderer.record_probe_update(cmd, &mut probes, 64, &lighting)?;  // `probes: Some(&probes)`
//! // or baked offline (`umbra bake`, or `bake_probes` then `save_probes`) and loaded:
//! let hash = umbra::bake::scene_hash(&scene, environment_map.as_ref());  // once per scene
//! let probes = renderer.load_probes(Path::new("level.probes"), hash, &lighting)?;
//! // or the host's passes and umbra's in one recording, every barrier between them derived:
//! renderer.record(cmd, |rec| {
//!     let (passes, scene) = (renderer.passes(), renderer.scene());
//!     passes.record_gbuffer(rec, scene, &camera, &gbuffer_views)?;
//!     rec.access(&[(Resource::Image(gbuffer_views.normal), Use::ComputeRead),
//!                  (Resource::Image(host_view), Use::ComputeWrite)]);
//!     host_kernel.dispatch(rec.cmd());                  // the host's own, declared above
//!     passes.record_ao(rec, scene, &camera, &gbuffer_views, ao_view, ao_blur_view, &ao_settings)?;
//!     Ok(())
//! })?;
//! // or a frame graph (crate::vk::Graph): passes declare the images they read and write; the
//! // graph culls what nothing uses, allocates transient images, derives every barrier:
//! let mut graph = Graph::new();
//! let gbuffer = GBufferImages::import(&mut graph, &gbuffer_views);
//! graph.add_pass("host gbuffer").write_all(gbuffer.images).record_raw(|cmd, views| host_pass(cmd))?;
//! renderer.passes().add_hybrid_shading(&mut graph, renderer.frame(&camera), gbuffer, &targets, &settings)?;
//! renderer.record_graph(cmd, graph, None)?;            // SSAO's images transient (`ao: None`)
//! ```
//!
//! Every `record_*` goes through [`crate::render::Passes`], the orchestrator that owns the
//! pipelines, all built once, at construction (a path tracer with other sampling options than
//! the default's when first recorded, or ahead of time by [`Renderer::set_path_tracer`]).
//!
//! Contract:
//! - The device was created with Vulkan 1.3, `synchronization2` and `VK_KHR_push_descriptor`
//!   ([`crate::vk::HostDevice`]). umbra allocates its own buffers from the host's
//!   `gpu-allocator` (shared as `Arc<Mutex<Allocator>>`) and frees them when dropped; it never
//!   destroys a host object.
//! - Images passed in are storage images in `GENERAL` layout with the formats the pass
//!   documents ([`crate::passes::gbuffer`] for a G-buffer). Before a `record_*` call, the host
//!   makes its writes to them visible to compute-shader reads (for its own compute kernels, a
//!   compute → compute memory barrier), or records them inside [`Renderer::record`], declared.
//!   Within one `record_*` call or one [`Renderer::record`], umbra derives every barrier from
//!   what each operation reads and writes ([`crate::vk::Recorder`]); each ends with one barrier
//!   from the compute and transfer work it recorded to compute-shader, indirect and transfer
//!   reads and writes. A host that reads the output in another stage adds its own barrier from
//!   `COMPUTE_SHADER`/`SHADER_STORAGE_WRITE`. Layouts are never changed.
//! - `record_*` binds its own pipeline, push descriptors and push constants: the host re-binds
//!   its own state afterwards.
//! - No global state: two `Renderer`s (on one device or two) are independent.
//! - [`Renderer::update_scene`] (materials and lights changed) and construction upload through
//!   the context's queue and wait; call them while no command buffer using the renderer is
//!   pending (after the host's frame fence).

use crate::error::Result;
use crate::gpu::scene::{BvhUpdate, GpuScene, SceneBvh};
use crate::gpu::SceneFeatures;
use crate::passes::ao::AoSettings;
use crate::passes::deferred::{LightingInputs, LightingSettings};
use crate::passes::denoise::{DenoiseImages, DenoiseSettings};
use crate::passes::gbuffer::{GBufferMethod, GBufferViews, VisibilityBuffer};
use crate::passes::ibl::{IblResources, IblSettings};
use crate::passes::pathtrace::{PathOptions, PathSettings, PathTarget};
use crate::passes::probes::{ProbeSettings, ProbeVolume};
use crate::passes::restir::{Reservoirs, RestirSettings};
use crate::passes::shadow::{ShadowMaps, ShadowSettings, ShadowView};
use crate::passes::taa::{TaaHistory, TaaSettings};
use crate::passes::temporal::{TemporalHistory, TemporalSettings};
use crate::passes::tonemap::ToneCurve;
use crate::render::{Frame, HybridSettings, HybridTargets, Passes};
use crate::scene::{Camera, Scene};
use crate::vk::{raw, Context, GpuTimer, Graph, GraphStats, Recorder};
use std::path::Path;

/// umbra's passes and one scene on a (host's) device: the scene, its image-based lighting
/// tables and the pipelines ([`Passes`], each built once).
pub struct Renderer {
    ctx: Context,
    scene: GpuScene,
    ibl: IblResources,
    passes: Passes,
    path_options: PathOptions,
    /// Counts [`Renderer::update_scene`] calls: a temporal history made under another starts
    /// afresh.
    generation: u64,
}

impl Renderer {
    /// Builds the BVH, uploads the scene, precomputes its image-based lighting and creates every
    /// pipeline (on threads while the scene uploads, once the BVH is built:
    /// [`Passes::prepare_every`]).
    pub fn new(ctx: &Context, scene: &Scene) -> Result<Self> {
        let bvh = SceneBvh::build(scene)?;
        let passes = Passes::with_features(ctx, SceneFeatures::of_scene(scene, &bvh, false));
        let uploaded = std::thread::scope(|s| {
            let path = s.spawn(|| passes.prepare_every(PathOptions::default()));
            let uploaded = GpuScene::upload_with(ctx, scene, bvh);
            let prepared = path.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            prepared.and(uploaded)
        })?;
        Self::with_passes(ctx, uploaded, passes)
    }

    /// A renderer for a scene already on the GPU (with its environment map, if any).
    pub fn with_gpu_scene(ctx: &Context, scene: GpuScene) -> Result<Self> {
        let passes = Passes::new(ctx, &scene);
        Self::with_passes(ctx, scene, passes)
    }

    /// A renderer for `scene` with `passes`, some of their pipelines perhaps built (new ones if
    /// they were made for other features).
    fn with_passes(ctx: &Context, scene: GpuScene, mut passes: Passes) -> Result<Self> {
        if passes.features() != scene.features() {
            passes = Passes::new(ctx, &scene);
        }
        let path_options = PathOptions::default();
        // Built now, not at the first frame: a host records frames against a deadline.
        passes.prepare(&scene, path_options)?;
        Ok(Self {
            ibl: IblResources::build(ctx, &scene, &IblSettings::default())?,
            passes,
            path_options,
            scene,
            ctx: ctx.clone(),
            generation: 0,
        })
    }

    /// Records into the host's `cmd` through one [`Recorder`], which derives every barrier
    /// between what `record` records from what each operation reads and writes: umbra's passes
    /// ([`Renderer::passes`]' `record_*` with [`Renderer::scene`]) and the host's own, each
    /// declared with [`Recorder::access`] before the host records it into [`Recorder::cmd`].
    /// Ends with the one barrier of the contract. The `record_*` methods below are this with
    /// one pass each.
    pub fn record<T>(
        &self,
        cmd: raw::CommandBuffer,
        record: impl FnOnce(&mut Recorder<'_>) -> Result<T>,
    ) -> Result<T> {
        Recorder::run(&self.ctx, cmd, record)
    }

    /// Records a frame graph into the host's `cmd` ([`Passes::execute`]): umbra's passes
    /// ([`Passes::add_hybrid`], [`Passes::add_hybrid_shading`] with [`Renderer::frame`]) and
    /// the host's own ([`Graph::add_pass`], its reads and writes declared, then
    /// [`crate::vk::PassBuilder::record_raw`]), in one recording whose every barrier is derived,
    /// ended by the one barrier of the contract. Transient images come from the renderer's pool:
    /// reused by the next graph recorded, ordered after this one on the same queue.
    pub fn record_graph(
        &self,
        cmd: raw::CommandBuffer,
        graph: Graph<'_>,
        timer: Option<&mut GpuTimer>,
    ) -> Result<GraphStats> {
        self.record(cmd, |rec| self.passes.execute(rec, graph, timer))
    }

    /// What a frame of `camera` records against: this renderer's scene and image-based
    /// lighting tables.
    pub fn frame<'a>(&'a self, camera: &'a Camera) -> Frame<'a> {
        Frame { scene: &self.scene, ibl: &self.ibl, camera }
    }

    /// The scene on the GPU.
    pub fn scene(&self) -> &GpuScene {
        &self.scene
    }

    /// The scene's image-based lighting tables (for [`Passes::record_lighting`] inside
    /// [`Renderer::record`]).
    pub fn ibl(&self) -> &IblResources {
        &self.ibl
    }

    /// The pipelines (the orchestrator every `record_*` goes through).
    pub fn passes(&self) -> &Passes {
        &self.passes
    }

    /// Takes changed materials, textures or lights of `scene` (same geometry) without rebuilding
    /// the BVH. The pipelines are re-specialised only when what the scene has changes (textures,
    /// emitters, punctual lights, transmission): a recoloured material or a moved light keeps
    /// them, so an engine can update every frame without compiling a kernel.
    pub fn update_scene(&mut self, scene: &Scene) -> Result<()> {
        self.scene.update(&self.ctx, scene)?;
        self.generation += 1;
        if self.scene.features() != self.passes.features() {
            self.passes = Passes::new(&self.ctx, &self.scene);
            self.passes.prepare(&self.scene, self.path_options)?;
        }
        Ok(())
    }

    /// Takes `scene`'s moved geometry after [`Scene::pose`] (the same triangles and materials),
    /// its BVH refitted or rebuilt by `how` ([`BvhUpdate`]); lights and cameras move with it.
    /// The pipelines are re-specialised only when the moved tree needs a deeper walk than they
    /// were made for ([`Passes::for_moved`]). Each vertex's motion from the positions before
    /// (kept for a scene loaded with its animations, else known from the first update on) goes
    /// into the G-buffer's `motion`, which temporal anti-aliasing ([`HybridTargets::taa`])
    /// follows across one update a frame. The path tracer's temporal denoiser starts afresh, as
    /// after [`Renderer::update_scene`] (it reads no motion). No command buffer using the scene
    /// may be pending (wait for the host's frame fence first).
    pub fn update_geometry(&mut self, scene: &Scene, how: BvhUpdate) -> Result<()> {
        self.scene.update_geometry(&self.ctx, scene, how)?;
        self.generation += 1;
        if let Some(passes) = self.passes.for_moved(&self.scene) {
            self.passes = passes;
            self.passes.prepare(&self.scene, self.path_options)?;
        }
        Ok(())
    }

    /// Chooses the path tracer's default options (microfacet sampling, MIS heuristic, strategy:
    /// GGX, the power heuristic and MIS at first) and builds its pipeline now. Settings with other
    /// options also work: their pipeline is built when first recorded.
    pub fn set_path_tracer(&mut self, options: PathOptions) -> Result<()> {
        self.passes.path_pass(&self.scene, options)?;
        self.path_options = options;
        Ok(())
    }

    /// Accumulation buffers for progressive path tracing at `size` (owned by umbra, freed on
    /// drop).
    pub fn path_target(&self, size: (u32, u32)) -> Result<PathTarget> {
        PathTarget::new(&self.ctx, size)
    }

    /// [`Renderer::path_target`] for images to denoise: either integrator then splits each
    /// sample's radiance by the first hit's lobes, diffuse and specular, which the denoiser
    /// filters apart ([`crate::passes::pathtrace::LobeSplit`]; two more vec4s per pixel, and
    /// kernels of their own made at the first record).
    pub fn denoised_path_target(&self, size: (u32, u32)) -> Result<PathTarget> {
        PathTarget::with_lobe_split(&self.ctx, size)
    }

    /// Records path-traced samples `first .. first + count` of the render into `target` (its
    /// samples `settings.first_sample + first ..` of the sequence; `first` 0 clears the target
    /// and restarts the running mean: a moved camera or changed scene restarts at 0).
    /// `settings.size` must be the target's. RIS reuse ([`crate::passes::pathtrace::RisReuse`])
    /// works here too: the target's reservoir buffers (two per-pixel buffers of
    /// [`crate::gpu::layout::GpuPathReservoir`]) are made at its first record with reuse.
    pub fn record_path_samples(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &PathTarget,
        settings: &PathSettings,
        first: u32,
        count: u32,
    ) -> Result<()> {
        self.record(cmd, |rec| {
            self.passes.record_path_samples(rec, &self.scene, camera, target, settings, first..first + count)
        })
    }

    /// Records the copy of `target`'s running mean into `output`: the host's
    /// `R32G32B32A32_SFLOAT` storage image of the target's size, in `GENERAL` layout (then, like
    /// every `record_*`, the barrier of the contract).
    pub fn record_path_resolve(
        &self,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        output: raw::ImageView,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_path_resolve(rec, target, output))
    }

    /// Working images for [`Renderer::record_path_denoise`] at `size` (owned by umbra, freed on
    /// drop; with room for a target's lobe split, [`Renderer::denoised_path_target`]); move them to `GENERAL` once with [`DenoiseImages::init_general`] in a command buffer
    /// of the host's.
    pub fn denoise_images(&self, size: (u32, u32)) -> Result<DenoiseImages> {
        DenoiseImages::with_lobe_split(&self.ctx, size)
    }

    /// Records the denoiser ([`crate::passes::denoise`]) of `target`'s samples so far into
    /// `output`: the host's `R32G32B32A32_SFLOAT` storage image of the target's size, in `GENERAL`
    /// layout, through `images` (of the same size, in `GENERAL` layout): instead of
    /// [`Renderer::record_path_resolve`].
    pub fn record_path_denoise(
        &self,
        cmd: raw::CommandBuffer,
        target: &PathTarget,
        images: &DenoiseImages,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_denoise(rec, target, images, output, settings))
    }

    /// The history of the temporal denoiser ([`crate::passes::temporal`]) for a view of `size`
    /// (owned by umbra, freed on drop; keep it from frame to frame, one per view; move it to
    /// `GENERAL` once with [`TemporalHistory::init_general`] in a command buffer of the host's).
    /// A new size needs a new history.
    pub fn temporal_history(&self, size: (u32, u32), settings: TemporalSettings) -> Result<TemporalHistory> {
        let mut history = TemporalHistory::new(&self.ctx, size, settings)?;
        history.generation = self.generation;
        Ok(history)
    }

    /// [`Renderer::record_path_denoise`] with temporal accumulation: `target`'s samples (this
    /// frame's: the host restarts the target each frame, `first` 0), seen by `camera`, blended
    /// with `history` reprojected from the previous frame's camera (which `history` keeps), then
    /// filtered into `output`; `history` then holds this frame. It starts afresh at its first
    /// frame, after [`TemporalHistory::reset`] (a cut) and after [`Renderer::update_scene`].
    /// Records into the host's command buffer, never submits.
    #[allow(clippy::too_many_arguments)]
    pub fn record_path_denoise_temporal(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &PathTarget,
        images: &DenoiseImages,
        history: &mut TemporalHistory,
        output: raw::ImageView,
        settings: &DenoiseSettings,
    ) -> Result<()> {
        if history.generation != self.generation {
            history.reset();
            history.generation = self.generation;
        }
        self.record(cmd, |rec| {
            self.passes.record_denoise_temporal(rec, camera, target, images, history, output, settings)
        })
    }

    /// Records umbra's ray-cast G-buffer for `camera` into `target`.
    pub fn record_gbuffer(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &GBufferViews,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_gbuffer(rec, &self.scene, camera, target))
    }

    /// A visibility buffer for rasterized G-buffers of `size` ([`Self::record_gbuffer_with`],
    /// [`HybridTargets::visibility`]), when `method` rasterizes and the device (64-bit buffer
    /// atomics enabled: [`crate::vk::HostDevice::int64_atomics`]) and the scene allow it; `None`
    /// (ray-cast G-buffers) otherwise, the reason in the log. Make a new one after
    /// [`Self::update_scene`].
    pub fn visibility_buffer(
        &self,
        size: (u32, u32),
        method: GBufferMethod,
    ) -> Result<Option<VisibilityBuffer>> {
        self.passes.visibility_for(&self.scene, size, method)
    }

    /// Records umbra's G-buffer for `camera` into `target`: rasterized into `visibility` and
    /// resolved from it when given, ray-cast otherwise. After the host's submission completes,
    /// [`VisibilityBuffer::check`] says whether its tile lists held the view
    /// ([`VisibilityBuffer::reserve`] and record again if not).
    pub fn record_gbuffer_with(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        target: &GBufferViews,
        visibility: Option<&VisibilityBuffer>,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_gbuffer_with(rec, &self.scene, camera, target, visibility))
    }

    /// Records the ambient occlusion of `gbuffer` (umbra's or the host's) by `settings.method`
    /// (SSAO, GTAO or RTAO) into `raw_ao` and, when `settings.blur`, its depth-aware blur (for
    /// half-resolution GTAO also its upsample) into `blurred`: both `R32_SFLOAT` storage images
    /// of the G-buffer's size in `GENERAL` layout (1 = unoccluded). Returns the view holding the
    /// result, for [`Self::record_lighting`].
    pub fn record_ao(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        raw_ao: raw::ImageView,
        blurred: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<raw::ImageView> {
        self.record(cmd, |rec| {
            self.passes.record_ao(rec, &self.scene, camera, gbuffer, raw_ao, blurred, settings)
        })
    }

    /// Records ray-traced ambient occlusion of `gbuffer` (SSAO's ground truth: `settings.samples`
    /// rays of length `settings.radius` per pixel) into `output`, an `R32_SFLOAT` storage image of
    /// the G-buffer's size in `GENERAL` layout.
    pub fn record_rtao(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        settings: &AoSettings,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_rtao(rec, &self.scene, camera, gbuffer, output, settings))
    }

    /// Records deferred lighting of `gbuffer` (umbra's or the host's own) seen from `camera` into
    /// `output` (`R32G32B32A32_SFLOAT`, the G-buffer's size) with the optional `inputs`: ambient
    /// occlusion, shadow maps (recorded before; else shadow rays), a probe volume (updated
    /// before) and lightmaps lighting the diffuse lobe.
    pub fn record_lighting(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        inputs: &LightingInputs<'_>,
        settings: &LightingSettings,
    ) -> Result<()> {
        self.record(cmd, |rec| {
            self.passes.record_lighting(rec, self.frame(camera), gbuffer, output, inputs, settings)
        })
    }

    /// ReSTIR's reservoirs for a view of `size` (keep them from frame to frame: they hold the
    /// history temporal reuse builds on; [`Reservoirs::reset`] at a cut).
    pub fn reservoirs(&self, size: (u32, u32)) -> Result<Reservoirs> {
        Reservoirs::new(&self.ctx, size)
    }

    /// Records ReSTIR DI's candidates and reuse for `gbuffer` into `reservoirs` with the random
    /// numbers of `lighting`'s frame and seed; then [`Self::record_lighting`] with
    /// `restir: Some(&reservoirs)` in its inputs and
    /// [`crate::passes::deferred::DirectLight::Restir`] in its settings
    /// shades them. Never submits.
    pub fn record_restir(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        gbuffer: &GBufferViews,
        reservoirs: &Reservoirs,
        settings: &RestirSettings,
        lighting: &LightingSettings,
    ) -> Result<()> {
        self.record(cmd, |rec| {
            self.passes.record_restir(rec, &self.scene, camera, gbuffer, reservoirs, settings, lighting)
        })
    }

    /// A probe volume over the scene by `settings`, its probes inactive until updated
    /// ([`Self::record_probe_update`]) or baked ([`Self::bake_probes`]); or a loaded bake.
    pub fn probe_volume(&self, settings: &ProbeSettings) -> Result<ProbeVolume> {
        ProbeVolume::new(&self.ctx, &self.scene, settings)
    }

    /// Records an update of `budget` probes of `volume` (round robin over the volume), blended
    /// into their maps with the volume's hysteresis (a running mean over a probe's first
    /// updates), under the environment of `lighting`: indirect light that follows moved lights
    /// and changed materials over the next frames. Never submits.
    pub fn record_probe_update(
        &self,
        cmd: raw::CommandBuffer,
        volume: &mut ProbeVolume,
        budget: u32,
        lighting: &LightingSettings,
    ) -> Result<()> {
        let blend_min = 1.0 - volume.settings.hysteresis;
        self.record(cmd, |rec| {
            self.passes.record_probe_update(rec, &self.scene, volume, budget, blend_min, lighting)
        })
    }

    /// Bakes `volume` now (submits on the context's queue and waits; call it while no command
    /// buffer of the renderer is pending), under the environment of `lighting`.
    pub fn bake_probes(&self, volume: &mut ProbeVolume, lighting: &LightingSettings) -> Result<()> {
        self.passes.bake_probes(&self.scene, volume, lighting, |_, _| {}).map(|_| ())
    }

    /// Saves a baked `volume` to `path` (the format of [`crate::bake`]), recording `scene_hash`
    /// ([`crate::bake::scene_hash`] of the scene and environment map the renderer was given) and
    /// the environment radiance of `lighting` it was baked under.
    pub fn save_probes(
        &self,
        path: &Path,
        volume: &ProbeVolume,
        scene_hash: u64,
        lighting: &LightingSettings,
    ) -> Result<()> {
        crate::bake::save_probes(&self.ctx, path, volume, scene_hash, lighting.env)
    }

    /// Loads the bake at `path` as a probe volume for this renderer's frames; an error
    /// ([`crate::error::Error::Bake`]) unless the file is a whole bake made for `scene_hash`
    /// ([`crate::bake::scene_hash`]) under the environment radiance of `lighting`. Uploads
    /// through the context's queue and waits.
    pub fn load_probes(
        &self,
        path: &Path,
        scene_hash: u64,
        lighting: &LightingSettings,
    ) -> Result<ProbeVolume> {
        crate::bake::load_probes(&self.ctx, path, scene_hash, lighting.env)
    }

    /// Places and allocates shadow maps for the scene's punctual lights, seen by `camera` over an
    /// image of `size` (directional cascades follow the view), by `settings`. The placement is
    /// fixed: after a light or (with a directional light) the camera moves, or after
    /// [`Self::update_scene`] changes the lights, make new maps.
    pub fn shadow_maps(
        &self,
        camera: &Camera,
        size: (u32, u32),
        settings: &ShadowSettings,
    ) -> Result<ShadowMaps> {
        self.passes.shadow_maps(&self.scene, camera, size, settings)
    }

    /// Records the rendering of `maps` (when a light, the geometry or, for cascades, the camera
    /// changed), for a `view` whose G-buffer is recorded before when given (the cascades' tiles
    /// its pixels do not read are skipped: [`ShadowSettings::view_marks`]). After the host's
    /// submission completes, [`ShadowMaps::check`] says whether their tile lists sufficed
    /// ([`ShadowMaps::reserve`] and record again if not).
    pub fn record_shadow_maps(
        &self,
        cmd: raw::CommandBuffer,
        maps: &ShadowMaps,
        view: Option<ShadowView<'_>>,
    ) -> Result<()> {
        self.record(cmd, |rec| self.passes.record_shadow_maps(rec, &self.scene, maps, view))
    }

    /// Records a whole hybrid frame into the host's `targets` (G-buffer, SSAO and blur when
    /// `settings.ao`, lighting, the TAA resolve when `targets.taa`, tonemap when
    /// `targets.ldr`), timed into `timer` if given. With TAA the frame samples the pixels at
    /// the history's next offset ([`TaaHistory::jitter`]; pass the camera unjittered), and the
    /// anti-aliased radiance is then [`TaaHistory::resolved`] (`targets.hdr` holds the frame's
    /// own). The renderer's image-based lighting is the default [`IblSettings`]'
    /// (`settings.ibl` is not read here).
    pub fn record_hybrid(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let jittered = targets.taa.map(|history| camera.jittered(history.jitter()));
        let camera = jittered.as_ref().unwrap_or(camera);
        self.record(cmd, |rec| self.passes.record_hybrid(rec, self.frame(camera), targets, settings, timer))
    }

    /// The history of temporal anti-aliasing ([`crate::passes::taa`]) for a view of `size`
    /// (owned by umbra, freed on drop; keep it from frame to frame, one per view; move it to
    /// `GENERAL` once with [`TaaHistory::init_general`]; [`TaaHistory::reset`] at a cut): pass
    /// it as [`HybridTargets::taa`]. A new size needs a new history.
    pub fn taa_history(&self, size: (u32, u32), settings: TaaSettings) -> Result<TaaHistory> {
        TaaHistory::new(&self.ctx, size, settings)
    }

    /// [`Self::record_hybrid`] but its G-buffer, already recorded into `targets.gbuffer`
    /// ([`Self::record_gbuffer`] of `camera`; shadow maps for its view in between).
    pub fn record_hybrid_shading(
        &self,
        cmd: raw::CommandBuffer,
        camera: &Camera,
        targets: &HybridTargets<'_>,
        settings: &HybridSettings,
        timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        self.record(cmd, |rec| {
            self.passes.record_hybrid_shading(rec, self.frame(camera), targets, settings, timer)
        })
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
        self.record(cmd, |rec| self.passes.record_tonemap(rec, src, dst, size, exposure_stops, curve))
    }
}
