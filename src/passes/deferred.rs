//! Deferred lighting (`spirv/deferred.comp`): the G-buffer shaded with the path tracer's BSDF
//! (`shading.glsl`, `bsdf.glsl`): emission, punctual lights and emissive triangles with
//! ray-traced shadows, into a linear `R32G32B32A32_SFLOAT` image (`GENERAL` layout; alpha 1).
//! Pixels without a surface get the environment seen directly. Split-sum image-based lighting
//! ([`IblResources`], precomputed once per scene) times an ambient-occlusion image lights every
//! surface with the environment (a constant or the scene's map). Transmissive materials transmit
//! the prefiltered environment through their one interface (straight on when thin-walled,
//! refracted once into a volume); the G-buffer holds only the first surface, so a volume's exit
//! and anything behind a transmissive surface but the environment are not seen. With a probe
//! volume ([`ProbeVolume`]) the diffuse lobe takes its irradiance (indirect light and the
//! occluded environment) instead of the environment's.
//!
//! The material's occlusion map (glTF `occlusionTexture`, the G-buffer's `emission` alpha) scales
//! the image-based light and the probes' light too; direct light is never scaled by it nor by the
//! ambient-occlusion image.

use super::gbuffer::GBufferViews;
use super::ibl::IblResources;
use super::lightmap::GpuLightmaps;
use super::probes::ProbeVolume;
use super::restir::{Reservoirs, RestirSettings};
use super::shadow::{ShadowMaps, ShadowMethod};
use crate::error::{Error, Result};
use crate::gpu::kernels::deferred;
use crate::gpu::layout::{DeferredParams, GpuCamera, GpuReservoir};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, GraphImage, GraphViews, Image, Recorder, TexelBuffer};

/// What the lighting pass computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightingSettings {
    /// Shadow rays (light samples) per pixel for the emissive triangles; soft shadows converge as
    /// this grows (punctual lights always take one).
    pub shadow_rays: u32,
    /// Frame index, decorrelating the light samples of successive frames.
    pub frame: u32,
    /// Seed of the light samples.
    pub seed: u32,
    /// Constant environment radiance, or the environment map's multiplier (rgb).
    pub env: [f32; 3],
    /// Split-sum image-based lighting of the environment (times ambient occlusion).
    pub ibl: bool,
    /// Which direction the prefiltered environment is read along.
    pub ibl_lookup: IblLookup,
    /// How the direct light of the punctual lights and emissive triangles is sampled.
    pub direct: DirectLight,
    /// Ray-traced shadows of sized punctual lights: `None` (the default) shadows each punctual
    /// light as a point with one ray (what the path tracer's lights are); `Some` casts
    /// [`LightingSettings::shadow_rays`] rays per light to its sphere or cone and takes the
    /// unoccluded fraction. For shadow rays only (not with shadow maps nor ReSTIR);
    /// [`crate::render::Passes::record_hybrid`] sets it from
    /// [`crate::passes::shadow::ShadowSettings::sized_rays`].
    pub sized_lights: Option<SizedLights>,
}

/// The size of the punctual lights for ray-traced soft shadows ([`LightingSettings::sized_lights`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizedLights {
    /// Radius of point and spot lights' spheres, metres.
    pub radius: f32,
    /// Angular radius of directional lights' cones, radians (at most 0.5).
    pub sun_angle: f32,
}

impl SizedLights {
    /// 1 − cos of the sun's angular radius, without cos's rounding near 1.
    pub fn sun_one_minus_cos(&self) -> f32 {
        let s = (0.5 * self.sun_angle as f64).sin();
        (2.0 * s * s) as f32
    }
}

/// How the lighting pass samples direct light (punctual lights and emissive triangles).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DirectLight {
    /// Every punctual light (up to 16; beyond, 16 picked by power) with its shadow ray, and
    /// [`LightingSettings::shadow_rays`] samples of the emissive triangles by power.
    #[default]
    Power,
    /// ReSTIR DI ([`crate::passes::restir`]): one resampled light sample per pixel, one shadow
    /// ray (and one more for the biased combination's visibility reuse).
    Restir(RestirSettings),
}

impl DirectLight {
    /// ReSTIR's settings, if it is ReSTIR.
    pub fn restir(&self) -> Option<&RestirSettings> {
        match self {
            DirectLight::Power => None,
            DirectLight::Restir(r) => Some(r),
        }
    }
}

impl Default for LightingSettings {
    fn default() -> Self {
        Self {
            shadow_rays: 4,
            frame: 0,
            seed: 0,
            env: [0.0; 3],
            ibl: true,
            ibl_lookup: IblLookup::Dominant,
            direct: DirectLight::Power,
            sized_lights: None,
        }
    }
}

impl LightingSettings {
    /// Most shadow rays per pixel: one invocation traces them all, and CPU devices (llvmpipe)
    /// break every loop of an invocation after 65,535 loop iterations in all; 64 rays through a
    /// Sponza-class BVH stay well inside it.
    pub const MAX_SHADOW_RAYS: u32 = 64;

    /// Checks the settings: 1 to [`Self::MAX_SHADOW_RAYS`] shadow rays, a finite non-negative
    /// environment.
    pub fn validate(&self) -> Result<()> {
        if self.shadow_rays == 0 || self.shadow_rays > Self::MAX_SHADOW_RAYS {
            return Err(Error::Invalid(format!(
                "{} shadow rays per pixel: must be 1 to {} (one kernel invocation traces them all, and CPU \
                 devices cut loops short past 65,535 iterations)",
                self.shadow_rays,
                Self::MAX_SHADOW_RAYS
            )));
        }
        if !self.env.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(Error::Invalid(format!(
                "environment radiance {:?} must be finite and non-negative",
                self.env
            )));
        }
        if let Some(restir) = self.direct.restir() {
            restir.validate()?;
        }
        if let Some(sized) = self.sized_lights {
            if self.direct.restir().is_some() {
                return Err(Error::Invalid(
                    "ray-traced shadows of sized lights are for power sampling, not ReSTIR (its reservoirs \
                     test visibility to the lights' points)"
                        .into(),
                ));
            }
            for (name, value, max) in
                [("light radius", sized.radius, f32::MAX), ("sun angle", sized.sun_angle, 0.5)]
            {
                if !(value.is_finite() && (0.0..=max).contains(&value)) {
                    return Err(Error::Invalid(format!(
                        "sized lights: {name} {value} must be finite, at least 0 and at most {max}"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Checks the shadow rays of sized lights against the `punctual` lights a shading point
    /// evaluates: each casts [`Self::shadow_rays`], all in one invocation, so together at most
    /// [`Self::MAX_SHADOW_RAYS`] (CPU devices cut loops short past 65,535 iterations); more rays
    /// come from averaging frames (successive [`Self::frame`]s continue one sequence).
    pub fn validate_sized_rays(&self, punctual: u32) -> Result<()> {
        let lights = punctual.min(crate::gpu::layout::PUNCTUAL_ALL);
        if self.sized_lights.is_some() && lights * self.shadow_rays > Self::MAX_SHADOW_RAYS {
            return Err(Error::Invalid(format!(
                "{} shadow rays per sized light × {lights} punctual lights: at most {} rays per pixel in one \
                 frame (one kernel invocation traces them all, and CPU devices cut loops short past 65,535 \
                 iterations); average frames for more",
                self.shadow_rays,
                Self::MAX_SHADOW_RAYS
            )));
        }
        Ok(())
    }
}

/// What the lighting pass reads besides the G-buffer, each optional; the ambient occlusion
/// image by its view (`Ao` of a frame graph: [`crate::vk::GraphImage`]).
#[derive(Clone, Copy, Default)]
pub struct LightingInputs<'a, Ao = raw::ImageView> {
    /// Ambient occlusion (`R32_SFLOAT`, the G-buffer's size, `GENERAL`; 1 = unoccluded)
    /// multiplying the ambient light; `None`: unoccluded.
    pub ao: Option<Ao>,
    /// Shadow maps for the punctual lights (recorded before; their method picks the filter);
    /// `None`: shadow rays.
    pub shadows: Option<&'a ShadowMaps>,
    /// An irradiance probe volume (updated or baked before) lighting the diffuse lobe; `None`:
    /// the environment's split-sum irradiance.
    pub probes: Option<&'a ProbeVolume>,
    /// Baked lightmaps lighting the diffuse lobe of the materials that have one (over the
    /// probes), at the G-buffer's UV1.
    pub lightmaps: Option<&'a GpuLightmaps>,
    /// ReSTIR's reservoirs for this frame, recorded before ([`crate::passes::restir`]); the pass
    /// must have been built for them.
    pub restir: Option<&'a Reservoirs>,
}

impl<'a> LightingInputs<'a, GraphImage> {
    /// The inputs with the ambient occlusion's view while a frame graph records.
    pub fn resolve(&self, views: &GraphViews) -> LightingInputs<'a> {
        let Self { ao, shadows, probes, lightmaps, restir } = *self;
        LightingInputs { ao: ao.map(|ao| views[ao]), shadows, probes, lightmaps, restir }
    }
}

/// The direction along which the split sum reads its prefiltered environment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IblLookup {
    /// The mirror direction: the prefiltering's own n = v = r assumption (the textbook split sum).
    Mirror,
    /// The lobe's dominant direction, leaning from the mirror direction towards the normal as
    /// roughness grows (Lagarde and de Rousiers 2014): much closer for rough surfaces.
    #[default]
    Dominant,
}

/// `deferred.comp`, specialised for the scene's features and a shadow method.
pub struct DeferredPass {
    pipeline: Pipeline<deferred::Kernel>,
    /// What the pipeline is specialised on ([`DeferredPass::spec`]): the shadow method, and
    /// whether it reads probes, lightmaps, ReSTIR's reservoirs, and casts rays to sized lights.
    spec: deferred::Spec,
    /// 1×1 `R32_SFLOAT` of 1.0: the ambient occlusion when the caller has none.
    no_ao: Image,
    /// One-texel stand-ins for the shadow maps' bindings when the lights cast rays.
    no_shadow: [TexelBuffer; 3],
    /// One-texel stand-ins for the probe volume's bindings when there is none.
    no_probes: [TexelBuffer; 2],
    /// One reservoir standing in for them otherwise.
    no_reservoirs: Buffer,
}

impl DeferredPass {
    /// Builds the pipeline for what `scene` has (textures, emissive triangles, punctual lights,
    /// an environment map, unlit materials) and for `spec` ([`DeferredPass::spec`]).
    pub fn new(ctx: &Context, scene: &GpuScene, spec: deferred::Spec) -> Result<Self> {
        Self::from_spec(ctx, &scene.features(), spec)
    }

    /// The kernel's specialization (what a cache of these passes is keyed by): from the
    /// `settings`' own choices (shadow rays to sized lights, [`LightingSettings::sized_lights`];
    /// a new choice of the kernel is read here), and from what a frame brings: shadows by
    /// `method`, indirect diffuse light from a probe volume (`probes`) and from lightmaps
    /// (`lightmaps`), direct light from ReSTIR's reservoirs (`restir`; else by power sampling).
    /// An error for sized lights with shadow maps or ReSTIR.
    pub fn spec(
        settings: &LightingSettings,
        method: ShadowMethod,
        probes: bool,
        lightmaps: bool,
        restir: bool,
    ) -> Result<deferred::Spec> {
        let sized = settings.sized_lights.is_some();
        if sized && (method.uses_maps() || restir) {
            return Err(Error::Invalid(format!(
                "shadow rays to sized lights need the '{}' method without ReSTIR",
                ShadowMethod::RayTraced.name()
            )));
        }
        Ok(deferred::Spec {
            beckmann: false,
            shadow_maps: method.uses_maps(),
            shadow_pcf: method == ShadowMethod::Pcf,
            shadow_pcss: method == ShadowMethod::Pcss,
            shadow_moments: method == ShadowMethod::Moments,
            probes,
            lightmaps,
            restir,
            shadow_sized: sized,
        })
    }

    /// The pass for a [`DeferredPass::spec`] and a scene with `features`.
    pub fn from_spec(ctx: &Context, features: &SceneFeatures, spec: deferred::Spec) -> Result<Self> {
        let pipeline = Pipeline::new(ctx, &spec, Some(features))?;
        let no_ao = Image::storage_2d(ctx, "no ambient occlusion", 1, 1, raw::Format::R32_SFLOAT)?;
        no_ao.write(ctx, &[1.0f32])?;
        let no_shadow = [
            TexelBuffer::upload(ctx, "no shadow records", &[[0u32; 4]], raw::Format::R32G32B32A32_UINT, 16)?,
            TexelBuffer::upload(ctx, "no shadow depth", &[0.0f32], raw::Format::R32_SFLOAT, 4)?,
            TexelBuffer::upload(
                ctx,
                "no shadow moments",
                &[[0.0f32; 4]],
                raw::Format::R32G32B32A32_SFLOAT,
                16,
            )?,
        ];
        let no_probes = super::probes::no_probe_bindings(ctx)?;
        let no_reservoirs = Buffer::upload(
            ctx,
            "no reservoirs",
            &[GpuReservoir::default()],
            raw::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        Ok(Self { pipeline, spec, no_ao, no_shadow, no_probes, no_reservoirs })
    }

    /// The shadow method the pipeline is specialised for (the inverse of [`DeferredPass::spec`]'s).
    fn method(&self) -> ShadowMethod {
        match self.spec {
            deferred::Spec { shadow_maps: false, .. } => ShadowMethod::RayTraced,
            deferred::Spec { shadow_pcf: true, .. } => ShadowMethod::Pcf,
            deferred::Spec { shadow_pcss: true, .. } => ShadowMethod::Pcss,
            deferred::Spec { shadow_moments: true, .. } => ShadowMethod::Moments,
            _ => ShadowMethod::Hard,
        }
    }

    /// The push constants for `camera` over an image of `size`.
    pub fn params(
        scene: &GpuScene,
        camera: &Camera,
        size: (u32, u32),
        settings: &LightingSettings,
    ) -> DeferredParams {
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        DeferredParams {
            camera: GpuCamera::new(camera, size),
            env: settings.env,
            ibl: settings.ibl as u32,
            size: [size.0, size.1],
            frame: settings.frame,
            seed: settings.seed,
            light_count: scene.light_count,
            punctual_count: scene.punctual_count,
            shadow_rays: settings.shadow_rays.max(1),
            ibl_dominant: (settings.ibl_lookup == IblLookup::Dominant) as u32,
            env_size: [env_w, env_h],
            light_radius: settings.sized_lights.map_or(0.0, |s| s.radius),
            sun_one_minus_cos: settings.sized_lights.map_or(0.0, |s| s.sun_one_minus_cos()),
        }
    }

    /// Records the pass (G-buffer in, `output` written: an `R32G32B32A32_SFLOAT` storage image in
    /// `GENERAL` layout of the G-buffer's size). Never submits. `ibl` holds the scene's precomputed tables (recorded before this pass); `inputs`
    /// what else the pass was built to read (shadow maps for a map method, a probe volume,
    /// lightmaps), recorded before it.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        gbuffer: &GBufferViews,
        output: raw::ImageView,
        ibl: &IblResources,
        inputs: &LightingInputs<'_>,
        params: &DeferredParams,
    ) -> Result<()> {
        let LightingInputs { ao, shadows, probes, lightmaps, restir } = *inputs;
        let sized = params.light_radius > 0.0 || params.sun_one_minus_cos > 0.0;
        if sized && !self.spec.shadow_sized {
            return Err(Error::Invalid(
                "the lighting pass was built for point lights but was given sized lights".into(),
            ));
        }
        let reservoirs = match (self.spec.restir, restir) {
            (false, None) => &self.no_reservoirs,
            (true, Some(r)) => {
                r.check_size(gbuffer.size)?;
                r.frame()
            }
            (built, _) => {
                return Err(Error::Invalid(format!(
                    "the lighting pass was built {} ReSTIR but was given {}",
                    if built { "for" } else { "without" },
                    if built { "no reservoirs" } else { "reservoirs" }
                )))
            }
        };
        let [no_states, no_maps] = &self.no_probes;
        let lightmap_texels = match (self.spec.lightmaps, lightmaps) {
            (false, None) => no_maps,
            (true, Some(l)) => &l.texels,
            (built, _) => {
                return Err(Error::Invalid(format!(
                    "the lighting pass was built {} lightmaps but was given {}",
                    if built { "with" } else { "without" },
                    if built { "none" } else { "some" }
                )))
            }
        };
        let (probe_texels, probe_irradiance, probe_distance) = match (self.spec.probes, probes) {
            (false, None) => (no_states, no_maps, no_maps),
            (true, Some(v)) => (&v.texels, &v.irradiance, &v.distance),
            (built, _) => {
                return Err(Error::Invalid(format!(
                    "the lighting pass was built {} probes but was given {}",
                    if built { "with" } else { "without" },
                    if built { "none" } else { "a volume" }
                )))
            }
        };
        let [no_records, no_depth, no_moments] = &self.no_shadow;
        let method = self.method();
        let (shadow_texels, shadow_depth, shadow_moments) = match (method.uses_maps(), shadows) {
            (false, _) => (no_records, no_depth, no_moments),
            (true, Some(maps)) if maps.settings.method == method => {
                (&maps.texels, &maps.depth, &maps.moments)
            }
            (true, maps) => {
                return Err(Error::Invalid(format!(
                    "the lighting pass shadows by '{}' but was given {}",
                    method.name(),
                    maps.map_or("no shadow maps".to_string(), |m| format!(
                        "maps for '{}'",
                        m.settings.method.name()
                    ))
                )))
            }
        };
        let resources = deferred::Resources {
            scene,
            gb: gbuffer,
            shadow_texels,
            shadow_depth,
            shadow_moments,
            out_color: &output,
            ibl_lut: &ibl.lut,
            ibl_prefiltered: &ibl.prefiltered,
            ibl_sh: &ibl.sh,
            ao_image: &ao.unwrap_or(self.no_ao.view),
            probe_texels,
            probe_irradiance,
            probe_distance,
            lightmap_texels,
            reservoirs,
        };
        self.pipeline.record(rec, &resources, params, [gbuffer.size.0, gbuffer.size.1, 1])?;
        Ok(())
    }
}
