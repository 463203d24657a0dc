//! Split-sum image-based lighting, precomputed once per scene and environment (layouts in
//! `spirv/include/ibl.glsl`): the BRDF table (`ibl_lut.comp`), the box chain of the environment
//! map (`ibl_downsample.comp`), its GGX-prefiltered roughness levels with filtered importance
//! sampling (`ibl_prefilter.comp`) and its SH9 irradiance (`ibl_sh.comp`). Without an
//! environment map (a constant environment) only the table is computed: the prefiltered
//! radiance and the irradiance of a constant are the constant (and π times it).

use crate::error::{Error, Result};
use crate::gpu::kernels::{ibl_downsample, ibl_lut, ibl_prefilter, ibl_sh};
use crate::gpu::layout::IblParams;
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::split_sum::{chain_level_sizes, prefiltered_level_sizes, IBL_LEVELS, LUT_SIZE};
use crate::vk::{raw, Buffer, Context, GpuTimer, Recorder};
use gpu_allocator::MemoryLocation;

/// What the precomputation spends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IblSettings {
    /// Midpoint samples per axis of each BRDF-table entry (the table is [`LUT_SIZE`]²).
    pub lut_samples: u32,
    /// GGX samples per prefiltered texel.
    pub prefilter_samples: u32,
}

impl Default for IblSettings {
    fn default() -> Self {
        Self { lut_samples: 128, prefilter_samples: 64 }
    }
}

impl IblSettings {
    /// Largest `lut_samples`: one invocation loops over its square, and llvmpipe breaks every loop
    /// of an invocation after 65,535 loop iterations in all (181² + 181 is within it).
    pub const MAX_LUT_SAMPLES: u32 = 181;
    /// Largest `prefilter_samples`, for the same limit.
    pub const MAX_PREFILTER_SAMPLES: u32 = 32_768;

    /// Both counts at least 1 and at most their maximum, else a clear error.
    pub fn validate(&self) -> Result<()> {
        for (name, value, max) in [
            ("lut_samples", self.lut_samples, Self::MAX_LUT_SAMPLES),
            ("prefilter_samples", self.prefilter_samples, Self::MAX_PREFILTER_SAMPLES),
        ] {
            if value == 0 || value > max {
                return Err(Error::Invalid(format!(
                    "IBL {name} is {value}: must be 1 to {max} (one kernel invocation loops over them, and \
                     CPU devices cut loops short past 65,535 iterations)"
                )));
            }
        }
        Ok(())
    }
}

/// The split-sum tables of one scene's environment, bound by the deferred lighting pass.
pub struct IblResources {
    /// BRDF table: [`LUT_SIZE`]² vec4 (A, B, C, D), see `ibl.glsl`.
    pub lut: Buffer,
    /// Prefiltered levels 1.. (level 0 is the scene's `env_texels`), vec4 rgb.
    pub prefiltered: Buffer,
    /// Box chain levels 1.. of the map, vec4 rgb.
    pub chain: Buffer,
    /// SH9 irradiance coefficients (× A_l), vec4 rgb.
    pub sh: Buffer,
    /// The environment map's size, or none for a constant environment.
    pub env_size: Option<(u32, u32)>,
    settings: IblSettings,
    lut_pipeline: Pipeline<ibl_lut::Kernel>,
    downsample: Pipeline<ibl_downsample::Kernel>,
    prefilter: Pipeline<ibl_prefilter::Kernel>,
    sh_pipeline: Pipeline<ibl_sh::Kernel>,
}

fn storage(ctx: &Context, name: &str, texels: usize) -> Result<Buffer> {
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER
        | raw::BufferUsageFlags::TRANSFER_SRC
        | raw::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(ctx, name, 16 * texels.max(1) as u64, usage, MemoryLocation::GpuOnly)
}

impl IblResources {
    /// Allocates the tables for `scene`'s environment (none when it has no map) and builds the
    /// pipelines; [`Self::record`] fills them.
    pub fn new(ctx: &Context, scene: &GpuScene, settings: &IblSettings) -> Result<Self> {
        settings.validate()?;
        let env_size = scene.env_size;
        let (chain_texels, prefiltered_texels) = match env_size {
            Some(size) => (
                chain_level_sizes(size).iter().skip(1).map(|&(w, h)| (w * h) as usize).sum(),
                prefiltered_level_sizes(size).iter().skip(1).map(|&(w, h)| (w * h) as usize).sum(),
            ),
            None => (1, 1),
        };
        Ok(Self {
            lut: storage(ctx, "ibl lut", (LUT_SIZE * LUT_SIZE) as usize)?,
            prefiltered: storage(ctx, "ibl prefiltered", prefiltered_texels)?,
            chain: storage(ctx, "ibl chain", chain_texels)?,
            sh: storage(ctx, "ibl sh", 9)?,
            env_size,
            settings: *settings,
            lut_pipeline: Pipeline::plain(ctx)?,
            downsample: Pipeline::for_scene(ctx, scene, &Default::default())?,
            prefilter: Pipeline::for_scene(ctx, scene, &Default::default())?,
            sh_pipeline: Pipeline::for_scene(ctx, scene, &Default::default())?,
        })
    }

    /// [`Self::new`], then records the precomputation and waits for it.
    pub fn build(ctx: &Context, scene: &GpuScene, settings: &IblSettings) -> Result<Self> {
        let ibl = Self::new(ctx, scene, settings)?;
        ctx.record(|rec| ibl.record(rec, scene, None))?;
        Ok(ibl)
    }

    /// Records the precomputation (`scene` must be the one given to [`Self::new`]), timing the
    /// table ("ibl lut"), the chain and prefiltered levels ("ibl prefilter") and the SH
    /// projection ("ibl sh") on `timer` when given (three passes). Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let cmd = rec.cmd();
        let begin = |timer: &mut Option<&mut GpuTimer>, name: &str| match timer {
            Some(t) => t.begin(cmd, name),
            None => Ok(()),
        };
        let end = |timer: &mut Option<&mut GpuTimer>| match timer {
            Some(t) => t.end(cmd),
            None => Ok(()),
        };
        begin(&mut timer, "ibl lut")?;
        let params = IblParams {
            dst_size: [LUT_SIZE, LUT_SIZE],
            samples: self.settings.lut_samples.max(1),
            ..Default::default()
        };
        let lut = ibl_lut::Resources { lut: &self.lut };
        self.lut_pipeline.record(rec, &lut, &params, [LUT_SIZE, LUT_SIZE, 1])?;
        end(&mut timer)?;
        let Some(size) = self.env_size else {
            return Ok(());
        };
        if scene.env_size != Some(size) {
            return Err(crate::Error::Invalid(format!(
                "IBL tables made for a {size:?} environment map, scene has {:?}",
                scene.env_size
            )));
        }
        let src_size = [size.0, size.1];

        begin(&mut timer, "ibl prefilter")?;
        let p = &self.downsample;
        p.bind(rec, &ibl_downsample::Resources { scene, chain: &self.chain })?;
        for (k, &(w, h)) in chain_level_sizes(size).iter().enumerate().skip(1) {
            p.push_constants(rec, &IblParams { src_size, src_level: k as u32, ..Default::default() })?;
            p.dispatch(rec, [w, h, 1])?;
        }
        let p = &self.prefilter;
        p.bind(rec, &ibl_prefilter::Resources { scene, chain: &self.chain, prefiltered: &self.prefiltered })?;
        let mut offset = 0;
        for (k, &(w, h)) in prefiltered_level_sizes(size).iter().enumerate().skip(1) {
            let roughness = k as f32 / (IBL_LEVELS - 1) as f32;
            p.push_constants(
                rec,
                &IblParams {
                    src_size,
                    dst_size: [w, h],
                    dst_offset: offset,
                    samples: self.settings.prefilter_samples.max(1),
                    roughness,
                    ..Default::default()
                },
            )?;
            p.dispatch(rec, [w, h, 1])?;
            offset += w * h;
        }
        end(&mut timer)?;

        begin(&mut timer, "ibl sh")?;
        // 128 rows per dispatch (one per invocation): see ibl_sh.comp on llvmpipe's loop limiter.
        let p = &self.sh_pipeline;
        p.bind(rec, &ibl_sh::Resources { scene, sh: &self.sh })?;
        for first_row in (0..src_size[1].max(1)).step_by(128) {
            p.push_constants(rec, &IblParams { src_size, first_row, ..Default::default() })?;
            p.dispatch(rec, [128, 1, 1])?;
        }
        end(&mut timer)
    }
}
