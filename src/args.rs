//! `umbra`'s arguments: the subcommands, and the render's flags in groups by what they apply to
//! (the path tracer, the hybrid, its shadow maps, ...), each group with one condition
//! ([`render_flag_groups`]) so that a flag of another mode is refused, never ignored.

use crate::cli;
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use umbra::color::ToneCurve;
use umbra::passes::ao::{AoMethod, AoResolution, AoSettings};
use umbra::passes::deferred::{DirectLight, LightingSettings};
use umbra::passes::pathtrace::{
    EmitterSampling, Heuristic, Integrator, Microfacet, RisReuse, Sampler, Strategy,
};
use umbra::passes::probes::ProbeSettings;
use umbra::passes::restir::RestirSettings;
use umbra::passes::shadow::{ShadowMethod, ShadowSettings};
use umbra::passes::visibility::GBufferMethod;

#[derive(Parser)]
#[command(name = "umbra", version, about = "Physically based rendering with Vulkan compute kernels")]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

// Parsed once per run: the render variant's size costs nothing worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
pub(crate) enum Command {
    /// Render a glTF scene (or, without one, the embedded Cornell box).
    Render(RenderArgs),
    /// Bake the irradiance probes of a scene (or the embedded Cornell box) to a file, for
    /// `render --mode hybrid --probes FILE`.
    Bake(BakeArgs),
    /// Join path-traced parts of one render (EXRs of `render --sample-range` and/or `--tile`,
    /// e.g. from an array job) into the render one process would have made.
    Merge(MergeArgs),
    /// What a glTF file holds (triangles, materials and their extensions, textures, cameras,
    /// lights, variants, animations, bounds) and what umbra reads, ignores or refuses of it, with
    /// no GPU work; without a scene, the Vulkan devices and the one umbra would use.
    Info {
        /// A .gltf or .glb file.
        scene: Option<PathBuf>,
        /// Print JSON (for scripts) instead of text.
        #[arg(long, requires = "scene")]
        json: bool,
    },
    /// Render the foundation test pattern (a known function of the pixel) to PNG and/or EXR.
    Pattern {
        /// Image size as WIDTHxHEIGHT.
        #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// PNG output path.
        #[arg(short, long, default_value = "pattern.png", value_parser = cli::parse_png)]
        output: PathBuf,
        /// Optional EXR output path (linear values).
        #[arg(long, value_parser = cli::parse_exr)]
        exr: Option<PathBuf>,
    },
}

/// The scene and the environment that lights it: what `render` and `bake` share.
#[derive(Clone, clap::Args)]
pub(crate) struct SceneArgs {
    /// A .gltf or .glb file; the embedded Cornell box when absent.
    pub(crate) scene: Option<PathBuf>,
    /// Equirectangular environment map (EXR or Radiance HDR), importance-sampled.
    #[arg(long)]
    pub(crate) env: Option<PathBuf>,
    /// Multiplier of the environment map.
    #[arg(long, default_value_t = 1.0, value_parser = cli::parse_non_negative)]
    pub(crate) env_strength: f32,
    /// Constant environment radiance, as R,G,B (linear), when there is no --env map.
    #[arg(long, value_parser = cli::parse_rgb, default_value = "0,0,0")]
    pub(crate) env_color: [f32; 3],
    /// KHR_materials_variants: render the file's variant of this name (its materials on the
    /// primitives it maps); without it, each primitive's own material.
    #[arg(long, value_name = "NAME")]
    pub(crate) variant: Option<String>,
    /// Pose the scene by its animations at this time, seconds (node transforms, morph weights,
    /// and skins through their joints); without it every node keeps its default transform.
    #[arg(long, value_name = "SECONDS")]
    pub(crate) time: Option<f32>,
    /// With --time: the animation that plays, by index or name (default: all of them).
    #[arg(long, value_name = "N|NAME", requires = "time")]
    pub(crate) animation: Option<String>,
    /// A texture image that cannot be read or decoded: refuse the scene (error), or warn once
    /// per image and render its slots with the material's factors alone (warn).
    #[arg(long, value_enum, default_value = "error")]
    pub(crate) missing_textures: umbra::scene::MissingTextures,
}

/// How the irradiance probes are baked (`bake`, and `render --probes bake`); unset: the
/// defaults of `ProbeSettings`.
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Probe bakes (render --probes bake, and umbra bake)")]
pub(crate) struct ProbeArgs {
    /// Probes: distance between neighbouring probes, metres (default: the scene's longest side / 8).
    #[arg(long, value_parser = cli::parse_positive)]
    pub(crate) probe_spacing: Option<f32>,
    /// Probes: rays per probe and sweep, a multiple of 64 up to 256 (default 128).
    #[arg(long)]
    pub(crate) probe_rays: Option<u32>,
    /// Probes: sweeps that average after the bounces (default 32).
    #[arg(long)]
    pub(crate) probe_sweeps: Option<u32>,
    /// Probes: sweeps that replace the maps, one bounce of light each (default 6).
    #[arg(long)]
    pub(crate) probe_bounces: Option<u32>,
}

impl ProbeArgs {
    pub(crate) fn settings(&self) -> ProbeSettings {
        let d = ProbeSettings::default();
        ProbeSettings {
            spacing: self.probe_spacing.or(d.spacing),
            rays: self.probe_rays.unwrap_or(d.rays),
            sweeps: self.probe_sweeps.unwrap_or(d.sweeps),
            bounces: self.probe_bounces.unwrap_or(d.bounces),
            ..d
        }
    }
}

/// `--probes`: bake now, or load a file.
#[derive(Clone)]
pub(crate) enum ProbesArg {
    Bake,
    File(PathBuf),
}

pub(crate) fn parse_probes(s: &str) -> Result<ProbesArg, String> {
    match s {
        "" => Err("expected a bake file, or 'bake'".into()),
        "bake" => Ok(ProbesArg::Bake),
        _ => Ok(ProbesArg::File(s.into())),
    }
}

/// How lightmaps and occlusion maps are baked (`bake`, and `render --lightmaps bake`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Lightmap bakes (render --lightmaps, and umbra bake)")]
pub(crate) struct LightmapArgs {
    /// Lightmaps and occlusion maps: texels a side of each material's map.
    #[arg(long, default_value_t = 128)]
    pub(crate) lightmap_size: u32,
    /// Lightmaps and occlusion maps: samples per texel.
    #[arg(long, default_value_t = 256)]
    pub(crate) lightmap_samples: u32,
    /// Give every triangle its own chart in a new TEXCOORD_1 set (for scenes without one; the
    /// scene's own set is replaced).
    #[arg(long)]
    pub(crate) unwrap: bool,
}

impl LightmapArgs {
    pub(crate) fn settings(&self) -> umbra::passes::lightmap::LightmapSettings {
        umbra::passes::lightmap::LightmapSettings {
            size: self.lightmap_size,
            samples: self.lightmap_samples,
            ..Default::default()
        }
    }
}

#[derive(Clone, clap::Args)]
pub(crate) struct BakeArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// The probe bake file to write, NAME.probes (umbra's probe format, see the `umbra::bake`
    /// docs).
    #[arg(short, long, value_parser = cli::parse_probes_file)]
    pub(crate) output: Option<PathBuf>,
    /// Also bake lightmaps over TEXCOORD_1 into this folder: lightmap-<material>.exr, layers
    /// `emitters` (direct light of the emissive triangles) and `ambient` (the environment and
    /// reflected light; the bounces beyond the first from the probes when they are baked too).
    #[arg(long, value_name = "DIR")]
    pub(crate) lightmaps: Option<PathBuf>,
    /// Also bake ambient-occlusion maps over TEXCOORD_1 into this folder (occlusion-<material>.png,
    /// for glTF's occlusionTexture with texCoord 1), with occlusion rays of --occlusion-radius.
    #[arg(long, alias = "ao", value_name = "DIR")]
    pub(crate) ao_maps: Option<PathBuf>,
    /// Occlusion maps: the occlusion rays' length in scene units.
    #[arg(long, default_value_t = 0.5, value_parser = cli::parse_positive)]
    pub(crate) occlusion_radius: f32,
    #[command(flatten)]
    pub(crate) probe: ProbeArgs,
    #[command(flatten)]
    pub(crate) lightmap: LightmapArgs,
}

#[derive(Clone, clap::Args)]
pub(crate) struct RenderArgs {
    #[command(flatten)]
    pub(crate) scene: SceneArgs,
    /// Rendering method.
    #[arg(long, value_enum, default_value = "pathtrace")]
    pub(crate) mode: Mode,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
    pub(crate) size: (u32, u32),
    /// Seed of the random numbers (same seed and device: identical output).
    #[arg(long, default_value_t = 0)]
    pub(crate) seed: u32,
    /// Which of the file's cameras (0-based; default the first, or one framing the scene).
    #[arg(long)]
    pub(crate) camera: Option<usize>,
    /// How direct light (punctual lights, emissive triangles) is sampled. Hybrid: every punctual
    /// light and --shadow-rays emissive samples by power (power), or ReSTIR DI's one resampled
    /// sample per pixel, reused over --restir-frames frames and neighbouring pixels (restir).
    /// Path tracer: at every vertex, one emissive sample by power with MIS and the punctual
    /// lights (power), or one sample resampled from --ris-candidates (ris).
    #[arg(long, value_enum, default_value = "power")]
    pub(crate) direct: Direct,
    /// PNG output (tonemapped sRGB); a name ending in .exr writes only the EXR (as --exr).
    #[arg(short, long, default_value = "umbra.png", value_parser = cli::parse_png_or_exr)]
    pub(crate) output: PathBuf,
    /// EXR output: linear colour, albedo, normal, depth, emission (at the first hit), variance
    /// and moment layers (and `noisy` with --denoise).
    #[arg(long, value_parser = cli::parse_exr)]
    pub(crate) exr: Option<PathBuf>,
    /// Render frames A up to B (B excluded) of the scene's animations, frame f posed at f / --fps
    /// seconds, each into -o (and --exr) with the frame number in place of a printf field such as
    /// %04d: `-o frame-%04d.png`. The file is read and the device and kernels made once; each
    /// frame poses the scene anew and brings its BVH along by --bvh.
    #[arg(long, value_parser = cli::parse_sample_range, value_name = "A..B", conflicts_with = "time")]
    pub(crate) frames: Option<(u32, u32)>,
    /// With --frames: how each frame's BVH follows the moved triangles: refit the first frame's
    /// tree (fast; the tree loosens as things move far) or rebuild it.
    #[arg(long, value_enum, default_value_t = umbra::gpu::scene::BvhUpdate::Refit, requires = "frames")]
    pub(crate) bvh: umbra::gpu::scene::BvhUpdate,
    /// Frames per second of --frames.
    #[arg(long, default_value_t = 24.0, value_parser = cli::parse_positive)]
    pub(crate) fps: f32,
    #[command(flatten)]
    pub(crate) path: PathArgs,
    #[command(flatten)]
    pub(crate) ris: RisArgs,
    #[command(flatten)]
    pub(crate) display: DisplayArgs,
    #[command(flatten)]
    pub(crate) hybrid: HybridArgs,
    #[command(flatten)]
    pub(crate) restir: RestirArgs,
    #[command(flatten)]
    pub(crate) shadow_map: ShadowMapArgs,
    #[command(flatten)]
    pub(crate) sized_light: SizedLightArgs,
    #[command(flatten)]
    pub(crate) probe: ProbeArgs,
    #[command(flatten)]
    pub(crate) lightmap: LightmapArgs,
    #[command(flatten)]
    pub(crate) ao: AoArgs,
    #[command(flatten)]
    pub(crate) screen_ao: ScreenAoArgs,
    #[command(flatten)]
    pub(crate) gtao: GtaoArgs,
}

/// The library's settings from the flags: a flag and what it sets sit in this one file.
impl RenderArgs {
    /// The hybrid's shadow settings.
    pub(crate) fn shadow_settings(&self) -> ShadowSettings {
        let method = self.hybrid.shadows;
        ShadowSettings {
            method,
            map_size: self.shadow_map.shadow_map_size,
            cascades: self.shadow_map.cascades,
            cascade_split: self.shadow_map.cascade_split,
            depth_bias: self.shadow_map.shadow_bias,
            slope_bias: self.shadow_map.shadow_slope_bias,
            normal_bias: self.shadow_map.shadow_normal_bias,
            pcf_radius: self.shadow_map.pcf_radius,
            max_radius: self
                .shadow_map
                .shadow_max_radius
                .unwrap_or(ShadowSettings::default_max_radius(self.shadow_map.shadow_map_size)),
            light_radius: self.sized_light.light_radius,
            sun_angle: self.sized_light.sun_angle.to_radians(),
            sized_rays: self.hybrid.rt_light_size,
            ..Default::default()
        }
    }

    /// The hybrid's settings.
    pub(crate) fn hybrid_settings(&self) -> umbra::render::HybridSettings {
        umbra::render::HybridSettings {
            size: self.size,
            gbuffer: self.hybrid.gbuffer,
            samples: self.hybrid.hybrid_samples,
            lighting: LightingSettings {
                shadow_rays: self.hybrid.shadow_rays,
                seed: self.seed,
                env: self.scene.env_radiance(),
                ibl: !self.hybrid.no_ibl,
                direct: match self.direct {
                    Direct::Power | Direct::Ris => DirectLight::Power,
                    Direct::Restir => DirectLight::Restir(RestirSettings {
                        candidates: self.restir.restir_candidates,
                        neighbours: self.restir.restir_neighbours,
                        radius: self.restir.restir_radius,
                        frames: self.restir.restir_frames,
                        temporal: !self.restir.restir_no_temporal,
                        unbiased: self.restir.restir_unbiased,
                        ..Default::default()
                    }),
                },
                ..Default::default()
            },
            exposure: self.display.exposure,
            curve: self.display.tonemap,
            ibl: Default::default(),
            ao: (!self.hybrid.no_ao).then(|| self.ao_settings()),
            shadows: self.shadow_settings(),
        }
    }

    /// The ambient occlusion's settings (`--mode ao` or `rtao`, or the hybrid's AO): each
    /// method's own defaults ([`AoSettings::of`]) where a flag is not given.
    pub(crate) fn ao_settings(&self) -> AoSettings {
        let method = match (self.mode, self.screen_ao.ao) {
            (Mode::Rtao, _) => AoMethod::Rtao,
            (_, ScreenAo::Ssao) => AoMethod::Ssao,
            (_, ScreenAo::Gtao) => AoMethod::Gtao,
        };
        let defaults = AoSettings::of(method);
        AoSettings {
            samples: self.ao.ao_samples.unwrap_or(defaults.samples),
            steps: self.screen_ao.ao_steps.unwrap_or(defaults.steps),
            radius: self.ao.ao_radius,
            blur: method != AoMethod::Rtao && !self.screen_ao.ao_no_blur,
            resolution: self.gtao.ao_resolution.into(),
            falloff: self.gtao.ao_falloff,
            seed: self.seed,
            ..defaults
        }
    }
}

/// `umbra render`: the path tracer's flags (`--mode pathtrace`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Path tracer (--mode pathtrace)")]
pub(crate) struct PathArgs {
    /// Samples per pixel (64 by default); with --sample-range, the whole render's, of which the
    /// part traces its range.
    #[arg(long)]
    pub(crate) spp: Option<u32>,
    /// Scattering events per path (1 = direct light only).
    #[arg(long, default_value_t = 8)]
    pub(crate) max_bounces: u32,
    /// Russian roulette starts after this many scattering events.
    #[arg(long, default_value_t = 3)]
    pub(crate) rr_depth: u32,
    /// Microfacet distribution of the specular lobes and its sampling: GGX from visible normals,
    /// GGX from D(h)·cos θh (Walter et al. 2007), Beckmann.
    #[arg(long, value_enum, default_value = "ggx")]
    pub(crate) microfacet: Microfacet,
    /// MIS heuristic.
    #[arg(long, value_enum, default_value = "power")]
    pub(crate) heuristic: Heuristic,
    /// The numbers the path tracer draws its samples from: low-discrepancy (per pixel, scrambled
    /// Sobol points: a lower error at the same samples) or independent (the error falls as 1/spp
    /// and the printed error estimate is unbiased; with low-discrepancy numbers it is high).
    #[arg(long, value_enum, default_value = "low-discrepancy")]
    pub(crate) sampler: Sampler,
    /// Points on emissive triangles for next-event estimation: uniform on the area, or uniform
    /// in the solid angle the triangle subtends where that is at least 0.2 sr (far less noise
    /// next to a large emitter, a few per cent more time on a CPU wherever there are emitters).
    #[arg(long, value_enum, default_value = "area")]
    pub(crate) emitter_sampling: EmitterSampling,
    /// Sampling strategies for emitters: light and BSDF sampling weighted by MIS, BSDF sampling
    /// alone, or light sampling alone (punctual lights are always light-sampled).
    #[arg(long, value_enum, default_value = "mis")]
    pub(crate) strategy: Strategy,
    /// How the path tracer lays out its work: one kernel per path (megakernel) or a kernel per
    /// step over queues of paths (wavefront); the same samples either way.
    #[arg(long, value_enum, default_value = "megakernel")]
    pub(crate) integrator: Integrator,
    /// Stop early once the image's estimated relative RMS error is below this (e.g. 0.01).
    #[arg(long, value_parser = cli::parse_positive)]
    pub(crate) target_error: Option<f32>,
    /// Path tracing: denoise the image (edge-avoiding à-trous filter guided by albedo, normal,
    /// depth and per-pixel variance; the diffuse and specular parts of the radiance filtered
    /// apart, with either integrator). The PNG and the EXR's main layer are denoised; the EXR
    /// keeps the raw estimate as layer `noisy`.
    #[arg(long)]
    pub(crate) denoise: bool,
    /// Path tracing with --denoise: à-trous iterations (1 to 8; taps 1, 2, 4, ... pixels apart).
    #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().iterations)]
    pub(crate) denoise_iterations: u32,
    /// Path tracer: trace only samples A..B of the whole render's --spp N (B at most N), exactly
    /// those a whole render traces there: one part of a render split across processes or
    /// machines, joined by `umbra merge`, which checks that the parts hold all N.
    #[arg(long, value_parser = cli::parse_sample_range, value_name = "A..B", requires = "spp", conflicts_with = "target_error")]
    pub(crate) sample_range: Option<(u32, u32)>,
    /// Path tracer: render only the W×H pixels from column X, row Y of the --size image, each as
    /// the whole image has it (one part for `umbra merge`).
    #[arg(long, value_parser = cli::parse_tile, value_name = "X,Y,W,H")]
    pub(crate) tile: Option<[u32; 4]>,
}

/// `umbra render`: the path tracer's RIS (`--mode pathtrace --direct ris`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Path tracer, --direct ris")]
pub(crate) struct RisArgs {
    /// Path tracer, --direct ris: candidates resampled at each vertex (at most 512 over a path's
    /// --max-bounces).
    #[arg(long, default_value_t = 8)]
    pub(crate) ris_candidates: u32,
    /// Path tracer, --direct ris: reuse the previous sample index's first-hit reservoirs, the
    /// pixel's own (samples), neighbouring pixels' (spatial) or both (unbiased combination; one
    /// dispatch per sample).
    #[arg(long, value_enum, default_value = "off")]
    pub(crate) ris_reuse: RisReuse,
}

/// `umbra render`: the PNG's exposure and tone curve (`--mode pathtrace` or `hybrid`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Display (--mode pathtrace or hybrid)")]
pub(crate) struct DisplayArgs {
    /// Exposure in stops for the PNG.
    #[arg(long, default_value_t = 0.0, value_parser = cli::parse_finite)]
    pub(crate) exposure: f32,
    /// Tone curve for the PNG.
    #[arg(long, value_enum, default_value = "neutral")]
    pub(crate) tonemap: ToneCurve,
}

/// `umbra render`: the hybrid's flags (`--mode hybrid`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Hybrid (--mode hybrid)")]
pub(crate) struct HybridArgs {
    /// Hybrid: how the G-buffer finds each pixel's first surface: rasterized into a visibility
    /// buffer and resolved (raster; ray-cast where the device has no 64-bit buffer atomics or
    /// the scene has implicit shapes or blended materials), or one ray per pixel (raycast).
    #[arg(long, value_enum, default_value = "raster")]
    pub(crate) gbuffer: GBufferMethod,
    /// Hybrid: anti-aliasing by supersampling: N sub-frames, each pixel sampled at N offsets
    /// within it (a k x k grid when N = k², else Halton points), averaged; the EXR's AOVs stay
    /// those of the pixels' centres. 1: one sample through each pixel's centre.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub(crate) hybrid_samples: u32,
    /// Hybrid: shadow rays (light samples) per pixel for emissive triangles (and, with
    /// --rt-light-size, per punctual light).
    #[arg(long, default_value_t = 4)]
    pub(crate) shadow_rays: u32,
    /// Hybrid: how punctual lights are shadowed: shadow rays (rt) or a shadow map read with the
    /// nearest texel (hard), percentage-closer filtering (pcf), percentage-closer soft shadows
    /// (pcss) or moment shadow maps (moments).
    #[arg(long, value_enum, default_value = "rt")]
    pub(crate) shadows: ShadowMethod,
    /// Hybrid, rt shadows: shadow punctual lights as sized lights (a sphere of --light-radius, a
    /// cone of --sun-angle) with --shadow-rays rays each, the unoccluded fraction (soft shadows,
    /// what pcss approximates); without it rt shadows points, as the path tracer's lights are.
    #[arg(long)]
    pub(crate) rt_light_size: bool,
    /// Hybrid: indirect diffuse light from irradiance probes: a file from `umbra bake` (for this
    /// scene and environment), or `bake` to bake them now (with the --probe-* settings).
    #[arg(long, value_parser = parse_probes, value_name = "FILE|bake")]
    pub(crate) probes: Option<ProbesArg>,
    /// Hybrid: bake lightmaps now for the materials with TEXCOORD_1 charts (or, with --unwrap,
    /// every triangle) and light their diffuse lobe with them (over the probes).
    #[arg(long)]
    pub(crate) lightmaps: bool,
    /// Hybrid: no SSAO (the image-based light is not occluded).
    #[arg(long)]
    pub(crate) no_ao: bool,
    /// Hybrid: no image-based lighting (split-sum specular, SH9 diffuse).
    #[arg(long)]
    pub(crate) no_ibl: bool,
}

/// `umbra render`: the hybrid's ReSTIR (`--mode hybrid --direct restir`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Hybrid, --direct restir")]
pub(crate) struct RestirArgs {
    /// Hybrid, ReSTIR: candidates resampled per pixel and frame.
    #[arg(long, default_value_t = RestirSettings::default().candidates)]
    pub(crate) restir_candidates: u32,
    /// Hybrid, ReSTIR: spatial neighbours merged per pixel (0 to 8).
    #[arg(long, default_value_t = RestirSettings::default().neighbours)]
    pub(crate) restir_neighbours: u32,
    /// Hybrid, ReSTIR: radius of the spatial neighbourhood, pixels.
    #[arg(long, default_value_t = RestirSettings::default().radius, value_parser = cli::parse_positive)]
    pub(crate) restir_radius: f32,
    /// Hybrid, ReSTIR: frames rendered with the camera still, the last one kept (temporal reuse
    /// builds on the earlier ones).
    #[arg(long, default_value_t = RestirSettings::default().frames)]
    pub(crate) restir_frames: u32,
    /// Hybrid, ReSTIR: no temporal reuse.
    #[arg(long)]
    pub(crate) restir_no_temporal: bool,
    /// Hybrid, ReSTIR: the unbiased combination (no visibility reuse; normalised by the
    /// reservoirs that could have produced the sample) instead of the biased one.
    #[arg(long)]
    pub(crate) restir_unbiased: bool,
}

/// `umbra render`: the hybrid's shadow maps (`--shadows hard|pcf|pcss|moments`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Hybrid shadow maps (--shadows hard|pcf|pcss|moments)")]
pub(crate) struct ShadowMapArgs {
    /// Hybrid shadow maps: width = height of each layer in texels (16 to 2048).
    #[arg(long, default_value_t = ShadowSettings::default().map_size)]
    pub(crate) shadow_map_size: u32,
    /// Hybrid shadow maps: constant depth bias, in texels.
    #[arg(long, default_value_t = ShadowSettings::default().depth_bias, value_parser = cli::parse_non_negative)]
    pub(crate) shadow_bias: f32,
    /// Hybrid shadow maps: slope-scaled depth bias, in texels per unit of tan(angle to the light).
    #[arg(long, default_value_t = ShadowSettings::default().slope_bias, value_parser = cli::parse_non_negative)]
    pub(crate) shadow_slope_bias: f32,
    /// Hybrid shadow maps: normal offset of the receiver, in texels.
    #[arg(long, default_value_t = ShadowSettings::default().normal_bias, value_parser = cli::parse_non_negative)]
    pub(crate) shadow_normal_bias: f32,
    /// Hybrid shadow maps: PCF filter radius in texels.
    #[arg(long, default_value_t = ShadowSettings::default().pcf_radius, value_parser = cli::parse_positive)]
    pub(crate) pcf_radius: f32,
    /// Hybrid shadow maps: the largest filter radius in texels, PCSS's blocker search and
    /// penumbra (a wider penumbra is cut to it); also the guard band of cube faces and spot maps.
    /// Default 16, at most an eighth of --shadow-map-size.
    #[arg(long, value_parser = cli::parse_positive)]
    pub(crate) shadow_max_radius: Option<f32>,
    /// Hybrid shadow maps: cascades of a directional light.
    #[arg(long, default_value_t = ShadowSettings::default().cascades)]
    pub(crate) cascades: u32,
    /// Hybrid shadow maps: cascade split scheme, 0 uniform to 1 logarithmic.
    #[arg(long, default_value_t = ShadowSettings::default().cascade_split, value_parser = cli::parse_non_negative)]
    pub(crate) cascade_split: f32,
}

/// `umbra render`: the size of punctual lights (`--shadows pcss`, or `--rt-light-size`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Sized lights (--shadows pcss, or --rt-light-size)")]
pub(crate) struct SizedLightArgs {
    /// Hybrid shadow maps (pcss) and --rt-light-size: radius of point and spot lights, metres.
    #[arg(long, default_value_t = ShadowSettings::default().light_radius, value_parser = cli::parse_non_negative)]
    pub(crate) light_radius: f32,
    /// Hybrid shadow maps (pcss) and --rt-light-size: angular radius of directional lights,
    /// degrees (the sun: 0.27).
    #[arg(long, default_value_t = ShadowSettings::default().sun_angle.to_degrees(), value_parser = cli::parse_non_negative)]
    pub(crate) sun_angle: f32,
}

/// `umbra render`: ambient occlusion (`--mode ao` or `rtao`, or the hybrid's AO).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Ambient occlusion (--mode ao or rtao, or the hybrid's AO)")]
pub(crate) struct AoArgs {
    /// AO modes and hybrid AO: kernel directions (ssao, 16 by default), slices (gtao, 3) or rays
    /// (rtao, 16) per pixel.
    #[arg(long)]
    pub(crate) ao_samples: Option<u32>,
    /// AO modes and hybrid AO: the occlusion radius in scene units (metres).
    #[arg(long, default_value_t = 0.5, value_parser = cli::parse_positive)]
    pub(crate) ao_radius: f32,
}

/// `--ao`: the screen-space estimators.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum ScreenAo {
    /// Screen-space AO: a hemisphere kernel marched through the depth buffer (the baseline).
    Ssao,
    /// Ground-truth-based AO (Jimenez et al. 2016): horizons in a few slices, integrated in
    /// closed form.
    Gtao,
}

/// `umbra render`: the screen-space AO (`--mode ao`, or the hybrid's AO; rtao casts rays).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Ambient occlusion (--mode ao or rtao, or the hybrid's AO)")]
pub(crate) struct ScreenAoArgs {
    /// --mode ao and hybrid AO: the estimator.
    #[arg(long, value_enum, default_value = "ssao")]
    pub(crate) ao: ScreenAo,
    /// --mode ao and hybrid AO: points per direction (ssao, 4 by default) or each side of the
    /// pixel per slice (gtao, 3).
    #[arg(long)]
    pub(crate) ao_steps: Option<u32>,
    /// --mode ao and hybrid AO: skip the depth-aware blur (ao blurs by default, rtao never does).
    #[arg(long)]
    pub(crate) ao_no_blur: bool,
}

/// `umbra render`: GTAO's own flags (`--ao gtao`).
#[derive(Clone, clap::Args)]
#[command(next_help_heading = "Ambient occlusion (--mode ao or rtao, or the hybrid's AO)")]
pub(crate) struct GtaoArgs {
    /// --ao gtao: compute the AO at every pixel, or at one of each 2x2 block and upsample it
    /// with the depth-aware blur.
    #[arg(long, value_enum, default_value = "full")]
    pub(crate) ao_resolution: AoResolutionArg,
    /// --ao gtao: the fraction of the radius over which an occluder's weight fades out (0: a
    /// hard cut-off at the radius, as RTAO's rays).
    #[arg(long, default_value_t = AoSettings::GTAO_FALLOFF, value_parser = cli::parse_unit)]
    pub(crate) ao_falloff: f32,
}

/// `--ao-resolution`.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum AoResolutionArg {
    Full,
    Half,
}

impl From<AoResolutionArg> for AoResolution {
    fn from(r: AoResolutionArg) -> Self {
        match r {
            AoResolutionArg::Full => AoResolution::Full,
            AoResolutionArg::Half => AoResolution::Half,
        }
    }
}

#[derive(Clone, clap::Args)]
pub(crate) struct MergeArgs {
    /// The parts: EXRs written by `umbra render` (path tracer) of one scene and settings.
    #[arg(required = true)]
    pub(crate) inputs: Vec<PathBuf>,
    /// The merged EXR (the same layers and attributes as a render's, so it merges further).
    #[arg(short, long, value_parser = cli::parse_exr)]
    pub(crate) output: PathBuf,
    /// Also a tonemapped PNG of the merged image.
    #[arg(long, value_parser = cli::parse_png)]
    pub(crate) png: Option<PathBuf>,
    /// Write what the parts hold even where they are not the whole render (samples or pixels of
    /// its plan missing: a lost part), with a warning naming what is missing; without it such a
    /// merge is refused.
    #[arg(long)]
    pub(crate) allow_partial: bool,
    /// Denoise the merged render as `umbra render --denoise` denoises one (parts rendered with
    /// --denoise carry the lobe split it filters apart): the PNG and the EXR's main layer are
    /// denoised, the EXR keeps the merged estimate as layer `noisy`.
    #[arg(long)]
    pub(crate) denoise: bool,
    /// With --denoise: à-trous iterations (1 to 8).
    #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().iterations)]
    pub(crate) denoise_iterations: u32,
    /// Exposure in stops for the PNG.
    #[arg(long, default_value_t = 0.0, value_parser = cli::parse_finite)]
    pub(crate) exposure: f32,
    /// Tone curve for the PNG.
    #[arg(long, value_enum, default_value = "neutral")]
    pub(crate) tonemap: ToneCurve,
}

/// `--direct`: one flag over the two modes' light sampling (the path tracer's
/// [`umbra::passes::pathtrace::DirectSampling`], the hybrid's [`DirectLight`]), whose
/// library types carry each method's settings.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum Direct {
    Power,
    Restir,
    Ris,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
pub(crate) enum Mode {
    /// Progressive path tracing (the ground truth).
    Pathtrace,
    /// Ray-cast G-buffer, deferred lighting with ray-traced shadows, tonemap (real-time style).
    Hybrid,
    /// Screen-space ambient occlusion of the ray-cast G-buffer, blurred (grey image, 1 = open).
    Ao,
    /// Ray-traced ambient occlusion (the ground truth for ao).
    Rtao,
}

/// The groups of render flags ([`PathArgs`], [`HybridArgs`], ...), each with whether it applies
/// to the render `args` asks for and what it needs otherwise (`--mode hybrid`, `--lightmaps`,
/// ...). A flag added to a group is refused outside it with no further line here.
pub(crate) fn render_flag_groups(args: &RenderArgs) -> Vec<cli::FlagGroup> {
    let (pathtrace, hybrid) = (args.mode == Mode::Pathtrace, args.mode == Mode::Hybrid);
    let ao_modes = matches!(args.mode, Mode::Ao | Mode::Rtao);
    let ssao = hybrid && !args.hybrid.no_ao;
    let screen_ao = ssao || args.mode == Mode::Ao;
    let shadows = args.hybrid.shadows;
    let groups = vec![
        (cli::arg_ids::<PathArgs>(), pathtrace, "--mode pathtrace"),
        (cli::arg_ids::<RisArgs>(), pathtrace && args.direct == Direct::Ris, "--mode pathtrace --direct ris"),
        (
            cli::arg_ids::<DisplayArgs>(),
            pathtrace || hybrid,
            "--mode pathtrace or hybrid (ao and rtao write the occlusion itself)",
        ),
        (cli::arg_ids::<HybridArgs>(), hybrid, "--mode hybrid"),
        (
            cli::arg_ids::<RestirArgs>(),
            hybrid && args.direct == Direct::Restir,
            "--mode hybrid --direct restir",
        ),
        (
            cli::arg_ids::<ShadowMapArgs>(),
            hybrid && shadows.uses_maps(),
            "--mode hybrid with shadow maps (--shadows hard|pcf|pcss|moments)",
        ),
        (
            cli::arg_ids::<SizedLightArgs>(),
            hybrid && (shadows == ShadowMethod::Pcss || args.hybrid.rt_light_size),
            "--mode hybrid with sized lights (--shadows pcss, or --rt-light-size)",
        ),
        (
            cli::arg_ids::<ProbeArgs>(),
            hybrid && matches!(args.hybrid.probes, Some(ProbesArg::Bake)),
            "--mode hybrid --probes bake (a bake file keeps the settings it was made with)",
        ),
        (cli::arg_ids::<LightmapArgs>(), args.hybrid.lightmaps, "--lightmaps (hybrid)"),
        (cli::arg_ids::<AoArgs>(), ssao || ao_modes, "--mode ao or rtao, or hybrid's AO"),
        (cli::arg_ids::<ScreenAoArgs>(), screen_ao, "--mode ao, or hybrid's AO (rtao casts rays)"),
        (
            cli::arg_ids::<GtaoArgs>(),
            screen_ao && args.screen_ao.ao == ScreenAo::Gtao,
            "--ao gtao (with --mode ao, or hybrid's AO)",
        ),
    ];
    groups
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// Every render flag is in a group with a condition ([`render_flag_groups`]) but those that
    /// apply to every render: a flag added beside these fails here until it joins a group (or
    /// this list, if it truly applies to every mode).
    #[test]
    fn every_render_flag_but_the_common_ones_is_in_a_group() {
        let cli = Cli::command();
        let render = cli.find_subcommand("render").expect("render");
        let args = Cli::try_parse_from(["umbra", "render"]).expect("parses");
        let Command::Render(args) = args.command else { panic!("render") };
        let grouped: Vec<String> = render_flag_groups(&args).into_iter().flat_map(|g| g.0).collect();
        let mut common: Vec<String> = render
            .get_arguments()
            .map(|a| a.get_id().to_string())
            .filter(|id| !grouped.contains(id) && id != "help")
            .collect();
        common.sort();
        assert_eq!(
            common,
            [
                "animation",
                "bvh",
                "camera",
                "direct",
                "env",
                "env_color",
                "env_strength",
                "exr",
                "fps",
                "frames",
                "missing_textures",
                "mode",
                "output",
                "scene",
                "seed",
                "size",
                "time",
                "variant"
            ]
        );
    }
}
