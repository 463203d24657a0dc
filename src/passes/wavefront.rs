//! The wavefront path tracer (`spirv/wavefront.comp`; Laine, Karras and Aila 2013): the
//! megakernel's samples ([`super::pathtrace`], the same estimator and random numbers) traced in
//! waves, each step of a path a kernel of its own over a queue of the paths that take it,
//! dispatched indirectly from the queue's count. [`crate::render::PathSettings::integrator`]
//! picks it.

use super::pathtrace::{sampling_spec, Heuristic, Microfacet, PathOptions, PathSettings, PathTarget};
use crate::error::{Error, Result};
use crate::gpu::kernels::wavefront;
use crate::gpu::layout::{
    GpuCamera, PathParams, WaveParams, WAVE_FIELDS, WAVE_SHADOW_TEXELS, WAVE_SPLIT_FIELDS,
    WAVE_SPLIT_SHADOW_TEXELS,
};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
use crate::vk::{raw, Buffer, Context, MemoryLocation, Recorder, TexelBuffer};
use std::sync::OnceLock;

/// Which integrator traces the path tracer's samples. Both trace the same samples (the same
/// paths, random numbers and estimator); they differ in how the work is laid out on the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum Integrator {
    /// One kernel: each lane traces its pixel's paths from the camera to their end, a run of
    /// samples per dispatch (`pathtrace.comp`).
    #[default]
    Megakernel,
    /// Paths in queues, one kernel per step (camera rays, closest hits, shading, shadow rays,
    /// accumulation), each dispatched over the paths that take it (`wavefront.comp`).
    Wavefront,
}

impl Integrator {
    /// Every value.
    pub const ALL: [Integrator; 2] = [Integrator::Megakernel, Integrator::Wavefront];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Megakernel => "megakernel",
            Integrator::Wavefront => "wavefront",
        }
    }
}

/// The texels a wave's state holds at most (256 MiB): it bounds the paths a wave holds (a view
/// past the device's `maxTexelBufferElements` is refused by [`TexelBuffer::new`]).
const MAX_STATE_TEXELS: u64 = 1 << 24;

/// The most paths a wave holds, however small their state.
pub const MAX_PATHS: u64 = 1 << 20;

/// Scattering events a wavefront path may have at most: each is a round of three dispatches,
/// and the queues' headers (32 bytes a round) are written by one `vkCmdUpdateBuffer` (64 KiB at
/// most).
pub const MAX_BOUNCES: u32 = 1000;

/// Samples per pixel a wave traces at most.
const MAX_WAVE_SAMPLES: u32 = 16;

/// The queues and path states of one [`PathTarget`]'s wavefront renders (made at its first).
pub struct WaveState {
    /// Paths the state holds.
    capacity: u32,
    /// Shadow rays a path may queue in one round.
    shadows_per_path: u32,
    /// Whether the paths carry the denoiser's lobe split (a target
    /// [`PathTarget::with_lobe_split`]'s state: [`WAVE_SPLIT_FIELDS`] more fields a path,
    /// [`WAVE_SPLIT_SHADOW_TEXELS`] more texels a shadow ray).
    lobe_split: bool,
    /// The region's rows a wave covers, and samples per pixel.
    rows: u32,
    samples: u32,
    paths: TexelBuffer,
    queue: TexelBuffer,
    counts: Buffer,
    camera: Buffer,
}

impl WaveState {
    /// Shadow rays one path queues in a round at most in `scene`: one light sample and one per
    /// punctual light evaluated.
    pub fn shadows_per_path(scene: &GpuScene) -> u32 {
        1 + scene.punctual_count.min(crate::gpu::layout::PUNCTUAL_ALL)
    }

    /// The texels of one path's state: its fields and its shadow rays', with or without the
    /// lobe split's.
    pub fn texels_per_path(shadows_per_path: u32, lobe_split: bool) -> u64 {
        let (fields, shadow) = if lobe_split {
            (WAVE_FIELDS + WAVE_SPLIT_FIELDS, WAVE_SHADOW_TEXELS + WAVE_SPLIT_SHADOW_TEXELS)
        } else {
            (WAVE_FIELDS, WAVE_SHADOW_TEXELS)
        };
        (fields + shadows_per_path * shadow) as u64
    }

    /// The state for waves over a `size` region of `scene`'s paths of at most `max_bounces`
    /// scattering events, holding at most `max_paths` paths (and at most 2^24 texels), with the
    /// lobe split's fields or not: a wave traces up to 16 samples of every pixel where they fit,
    /// else one sample of as many whole rows as fit.
    pub fn new(
        ctx: &Context,
        scene: &GpuScene,
        (w, h): (u32, u32),
        max_bounces: u32,
        max_paths: u64,
        lobe_split: bool,
    ) -> Result<Self> {
        let shadows_per_path = Self::shadows_per_path(scene);
        let per_path = Self::texels_per_path(shadows_per_path, lobe_split);
        let most = (MAX_STATE_TEXELS / per_path).min(max_paths).max(w as u64);
        let pixels = w as u64 * h as u64;
        let (rows, samples) = if pixels <= most {
            (h, (most / pixels.max(1)).min(MAX_WAVE_SAMPLES as u64) as u32)
        } else {
            ((most / w as u64).max(1) as u32, 1)
        };
        let capacity = (w as u64 * rows as u64 * samples as u64) as u32;
        let u32x4 = raw::Format::R32G32B32A32_UINT;
        let paths = TexelBuffer::new(
            ctx,
            "wavefront paths",
            capacity as u64 * per_path,
            u32x4,
            16,
            raw::BufferUsageFlags::empty(),
        )?;
        let queue = TexelBuffer::new(
            ctx,
            "wavefront queues",
            3 * capacity as u64,
            raw::Format::R32_UINT,
            4,
            raw::BufferUsageFlags::empty(),
        )?;
        let headers = 2 * (max_bounces as u64 + 2);
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER
            | raw::BufferUsageFlags::INDIRECT_BUFFER
            | raw::BufferUsageFlags::TRANSFER_DST;
        let counts = Buffer::new(ctx, "wavefront counts", headers * 16, usage, MemoryLocation::GpuOnly)?;
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        let camera = Buffer::new(
            ctx,
            "wavefront camera",
            std::mem::size_of::<GpuCamera>() as u64,
            usage,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self { capacity, shadows_per_path, lobe_split, rows, samples, paths, queue, counts, camera })
    }

    /// An error unless the state serves waves of `scene` with `max_bounces`, with the lobe split
    /// or not.
    fn check(&self, scene: &GpuScene, max_bounces: u32, lobe_split: bool) -> Result<()> {
        if lobe_split != self.lobe_split {
            return Err(Error::Invalid(format!(
                "the path target's wavefront state was made {} the lobe split's fields: use a new target",
                if self.lobe_split { "with" } else { "without" }
            )));
        }
        if max_bounces > MAX_BOUNCES {
            return Err(Error::Invalid(format!(
                "the wavefront integrator traces at most {MAX_BOUNCES} bounces, not {max_bounces}"
            )));
        }
        let headers = 2 * (max_bounces as u64 + 2);
        if Self::shadows_per_path(scene) > self.shadows_per_path || headers * 16 > self.counts.size {
            return Err(Error::Invalid(format!(
                "the path target's wavefront state was made for {} shadow rays per path and fewer bounces; \
                 this render needs {} shadow rays and {max_bounces} bounces: use a new target",
                self.shadows_per_path,
                Self::shadows_per_path(scene)
            )));
        }
        Ok(())
    }
}

/// The constants of `wavefront.comp`'s five stages from `base` (the sampling options): extend's
/// (the same with or without the lobe split), then camera rays, shade, connect and accumulate,
/// with the split or not.
pub fn stage_specs(base: wavefront::Spec, lobe_split: bool) -> (wavefront::Spec, [wavefront::Spec; 4]) {
    let split = wavefront::Spec { split_lobes: lobe_split, ..base };
    (
        wavefront::Spec { wf_extend: true, ..base },
        [
            wavefront::Spec { wf_camera_rays: true, ..split },
            wavefront::Spec { wf_shade: true, ..split },
            wavefront::Spec { wf_connect: true, ..split },
            wavefront::Spec { wf_accumulate: true, ..split },
        ],
    )
}

/// `wavefront.comp`'s five stages, specialised for one scene's features and the sampling options;
/// all but extend specialised for the lobe split or not.
pub struct WavefrontPass {
    options: PathOptions,
    /// Extend (the same with or without the split), built at the first use of either set.
    extend: OnceLock<Pipeline<wavefront::Kernel>>,
    /// The other stages without and with the lobe split, each set built at its first use (a
    /// record into a target without or with the split) or by [`WavefrontPass::prepare`].
    stages: [OnceLock<Stages>; 2],
}

/// The stages of one specialisation (lobe split or not) but extend.
struct Stages {
    camera_rays: Pipeline<wavefront::Kernel>,
    shade: Pipeline<wavefront::Kernel>,
    connect: Pipeline<wavefront::Kernel>,
    accumulate: Pipeline<wavefront::Kernel>,
}

impl WavefrontPass {
    /// The stages for `scene` and `options` (the specialisations of
    /// [`super::pathtrace::PathTracePass::for_scene`]), without the lobe split.
    pub fn for_scene(ctx: &Context, scene: &GpuScene, options: PathOptions) -> Result<Self> {
        Self::for_features(ctx, &scene.features(), options)
    }

    /// The stages for a scene with `features` (before it is uploaded) and `options`, without
    /// the lobe split.
    pub fn for_features(ctx: &Context, features: &SceneFeatures, options: PathOptions) -> Result<Self> {
        let pass = Self::lazy(options);
        pass.prepare_for(ctx, features, false)?;
        Ok(pass)
    }

    /// The pass for `options` with no pipeline built yet: each is built at its first use.
    pub fn lazy(options: PathOptions) -> Self {
        Self { options, extend: OnceLock::new(), stages: Default::default() }
    }

    /// Builds the stages for `scene`, specialised for the lobe split or not, if they were not
    /// (pipeline creation takes up to a second on lavapipe, so a render builds only the set it
    /// uses).
    pub fn prepare(&self, ctx: &Context, scene: &GpuScene, lobe_split: bool) -> Result<()> {
        self.prepare_for(ctx, &scene.features(), lobe_split)
    }

    /// [`WavefrontPass::prepare`] for a scene with `features` (before it is uploaded).
    pub fn prepare_for(&self, ctx: &Context, features: &SceneFeatures, lobe_split: bool) -> Result<()> {
        self.pipelines(ctx, features, lobe_split).map(|_| ())
    }

    /// Extend and the other stages for a scene with `features`, with the lobe split or not (the
    /// missing ones built now, side by side: each takes up to a second on lavapipe, on one thread).
    fn pipelines(
        &self,
        ctx: &Context,
        features: &SceneFeatures,
        lobe_split: bool,
    ) -> Result<(&Pipeline<wavefront::Kernel>, &Stages)> {
        if self.options.ris {
            return Err(Error::Invalid(
                "RIS (--direct ris) runs in the megakernel only, not the wavefront integrator".into(),
            ));
        }
        let (extend, split) =
            stage_specs(sampling_spec!(wavefront::Spec, self.options, Default::default()), lobe_split);
        let cell = &self.stages[lobe_split as usize];
        let mut specs = Vec::new();
        if self.extend.get().is_none() {
            specs.push(extend);
        }
        if cell.get().is_none() {
            specs.extend(split);
        }
        let built: Vec<Result<Pipeline<wavefront::Kernel>>> = std::thread::scope(|s| {
            let threads: Vec<_> =
                specs.iter().map(|spec| s.spawn(move || Pipeline::new(ctx, spec, Some(features)))).collect();
            threads
                .into_iter()
                .map(|t| t.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
                .collect::<Vec<_>>()
        });
        let mut built = built.into_iter().collect::<Result<Vec<_>>>()?.into_iter();
        if self.extend.get().is_none() {
            let extend = built.next().expect("extend was built");
            self.extend.get_or_init(|| extend);
        }
        if cell.get().is_none() {
            let mut next = || built.next().expect("four stages were built");
            let stages = Stages { camera_rays: next(), shade: next(), connect: next(), accumulate: next() };
            cell.get_or_init(|| stages);
        }
        Ok((self.extend.get().expect("extend is built"), cell.get().expect("the stages are built")))
    }

    /// Records samples `params.sample_index .. + params.sample_count` per pixel into `target`,
    /// in waves, through `target`'s wavefront state (made now if
    /// the target has none), splitting the radiance by lobes for the denoiser in a target with
    /// the split ([`PathTarget::with_lobe_split`]). Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        target: &PathTarget,
        settings: &PathSettings,
        params: &PathParams,
    ) -> Result<()> {
        let lobe_split = target.lobe_split.is_some();
        let state = match target.wave.get() {
            Some(state) => state,
            None => {
                let state = WaveState::new(
                    rec.ctx(),
                    scene,
                    target.size,
                    settings.max_bounces,
                    MAX_PATHS,
                    lobe_split,
                )?;
                target.wave.get_or_init(|| state)
            }
        };
        state.check(scene, params.max_bounces, lobe_split)?;
        let (extend, stages) = self.pipelines(rec.ctx(), &scene.features(), lobe_split)?;
        // Without the split its bindings hold buffers the stages then never read.
        let (aov_specular, aov_split) = match &target.lobe_split {
            Some(split) => (&split.specular, &split.split),
            None => (&target.albedo, &target.emission),
        };
        let resources = wavefront::Resources {
            scene,
            wf_camera: &state.camera,
            wf_paths: &state.paths,
            wf_queue: &state.queue,
            wf_counts: &state.counts,
            accum: &target.accum,
            moment: &target.moment,
            aov_albedo: &target.albedo,
            aov_normal_depth: &target.normal_depth,
            aov_emission: &target.emission,
            aov_specular,
            aov_split,
            stats: &target.stats,
        };
        let mut wave = WaveParams {
            env: params.env,
            ris_candidates: 0,
            size: params.size,
            sample_index: params.sample_index,
            seed: params.seed,
            max_bounces: params.max_bounces,
            rr_depth: params.rr_depth,
            light_count: params.light_count,
            punctual_count: params.punctual_count,
            env_size: params.env_size,
            sample_count: 1,
            env_pick: params.env_pick,
            round: 0,
            capacity: state.capacity,
            shadows_per_path: state.shadows_per_path,
            first_row: 0,
        };
        // Every header a wave uses: x workgroups, 1, 1, no entries.
        let headers: Vec<[u32; 4]> = vec![[0, 1, 1, 0]; 2 * (params.max_bounces as usize + 2)];
        let (w, h) = target.size;
        let end = params.sample_index + params.sample_count;
        let mut camera = params.camera;
        let (first_column, first_row) = camera.region_origin();
        while wave.sample_index < end {
            wave.sample_count = state.samples.min(end - wave.sample_index);
            for row in (0..h).step_by(state.rows as usize) {
                let rows = state.rows.min(h - row);
                // A wave over rows `row ..` of the region: a region of the region.
                wave.size = [w, rows];
                camera.set_region_origin((first_column, first_row + row));
                rec.update(&state.camera, 0, bytemuck::bytes_of(&camera));
                rec.update(&state.counts, 0, bytemuck::cast_slice(&headers));
                Self::wave(rec, extend, stages, state, &resources, &mut wave, row)?;
            }
            wave.sample_index += wave.sample_count;
        }
        Ok(())
    }

    /// Records one wave: `wave.sample_count` samples of the `wave.size` pixels from region row
    /// `row` (the accumulation buffers' rows).
    fn wave(
        rec: &mut Recorder<'_>,
        extend: &Pipeline<wavefront::Kernel>,
        stages: &Stages,
        state: &WaveState,
        resources: &wavefront::Resources<'_>,
        wave: &mut WaveParams,
        row: u32,
    ) -> Result<()> {
        wave.round = 0;
        wave.first_row = row;
        let [w, rows] = wave.size;
        stages.camera_rays.record(rec, resources, wave, [w, rows, wave.sample_count])?;
        for round in 0..=wave.max_bounces {
            wave.round = round;
            let rays = 16 * round as u64;
            let shadows = 16 * (wave.max_bounces as u64 + 2 + round as u64);
            for (stage, header) in [(extend, rays), (&stages.shade, rays), (&stages.connect, shadows)] {
                if std::ptr::eq(stage, &stages.connect) && round == wave.max_bounces {
                    // No light samples at the last round's hits.
                    continue;
                }
                stage.bind(rec, resources)?;
                stage.push_constants(rec, wave)?;
                stage.dispatch_indirect(rec, &state.counts, header);
            }
        }
        stages.accumulate.record(rec, resources, wave, [w, rows, 1])?;
        Ok(())
    }
}
