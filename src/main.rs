//! The `umbra` command-line renderer.

mod cli;

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use umbra::color::ToneCurve;
use umbra::gpu::scene::{GpuScene, SceneBvh};
use umbra::passes::deferred::{DirectLight, LightingSettings};
use umbra::passes::pathtrace::{
    EmitterSampling, Heuristic, Integrator, Microfacet, RisReuse, Sampler, Strategy,
};
use umbra::passes::probes::{ProbeSettings, ProbeVolume};
use umbra::passes::restir::RestirSettings;
use umbra::passes::shadow::{ShadowMethod, ShadowSettings};
use umbra::render::{DenoiseSettings, Passes};
use umbra::vk::{self, raw, Context, ContextDesc, GpuTimer, Image};

#[derive(Parser)]
#[command(name = "umbra", version, about = "Physically based rendering with Vulkan compute kernels")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a glTF scene (or, without one, the embedded Cornell box).
    Render(RenderArgs),
    /// Bake the irradiance probes of a scene (or the embedded Cornell box) to a file, for
    /// `render --mode hybrid --probes FILE`.
    Bake(BakeArgs),
    /// Join path-traced parts of one render (EXRs of `render --sample-range` and/or `--tile`,
    /// e.g. from an array job) into the render one process would have made.
    Merge(MergeArgs),
    /// List the Vulkan devices and the one umbra would use.
    Info,
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
#[derive(clap::Args)]
struct SceneArgs {
    /// A .gltf or .glb file; the embedded Cornell box when absent.
    scene: Option<PathBuf>,
    /// Equirectangular environment map (EXR or Radiance HDR), importance-sampled.
    #[arg(long)]
    env: Option<PathBuf>,
    /// Multiplier of the environment map.
    #[arg(long, default_value_t = 1.0, value_parser = cli::parse_non_negative)]
    env_strength: f32,
    /// Constant environment radiance, as R,G,B (linear), when there is no --env map.
    #[arg(long, value_parser = cli::parse_rgb, default_value = "0,0,0")]
    env_color: [f32; 3],
    /// A texture image that cannot be read or decoded: refuse the scene (error), or warn once
    /// per image and render its slots with the material's factors alone (warn).
    #[arg(long, value_enum, default_value = "error")]
    missing_textures: umbra::scene::MissingTextures,
}

/// How the irradiance probes are baked (`bake`, and `render --probes bake`); unset: the
/// defaults of `ProbeSettings`.
#[derive(clap::Args)]
struct ProbeArgs {
    /// Probes: distance between neighbouring probes, metres (default: the scene's longest side / 8).
    #[arg(long, value_parser = cli::parse_positive)]
    probe_spacing: Option<f32>,
    /// Probes: rays per probe and sweep, a multiple of 64 up to 256 (default 128).
    #[arg(long)]
    probe_rays: Option<u32>,
    /// Probes: sweeps that average after the bounces (default 32).
    #[arg(long)]
    probe_sweeps: Option<u32>,
    /// Probes: sweeps that replace the maps, one bounce of light each (default 6).
    #[arg(long)]
    probe_bounces: Option<u32>,
}

impl ProbeArgs {
    fn settings(&self) -> ProbeSettings {
        let d = ProbeSettings::default();
        ProbeSettings {
            spacing: self.probe_spacing.or(d.spacing),
            rays: self.probe_rays.unwrap_or(d.rays),
            sweeps: self.probe_sweeps.unwrap_or(d.sweeps),
            bounces: self.probe_bounces.unwrap_or(d.bounces),
            ..d
        }
    }

    /// The flags given, for refusing them where nothing is baked.
    fn given(&self) -> Vec<&'static str> {
        let flags = [
            ("--probe-spacing", self.probe_spacing.is_some()),
            ("--probe-rays", self.probe_rays.is_some()),
            ("--probe-sweeps", self.probe_sweeps.is_some()),
            ("--probe-bounces", self.probe_bounces.is_some()),
        ];
        flags.into_iter().filter(|f| f.1).map(|f| f.0).collect()
    }
}

/// `--probes`: bake now, or load a file.
#[derive(Clone)]
enum ProbesArg {
    Bake,
    File(PathBuf),
}

fn parse_probes(s: &str) -> Result<ProbesArg, String> {
    match s {
        "" => Err("expected a bake file, or 'bake'".into()),
        "bake" => Ok(ProbesArg::Bake),
        _ => Ok(ProbesArg::File(s.into())),
    }
}

/// How lightmaps and occlusion maps are baked (`bake`, and `render --lightmaps bake`).
#[derive(clap::Args)]
struct LightmapArgs {
    /// Lightmaps and occlusion maps: texels a side of each material's map.
    #[arg(long, default_value_t = 128)]
    lightmap_size: u32,
    /// Lightmaps and occlusion maps: samples per texel.
    #[arg(long, default_value_t = 256)]
    lightmap_samples: u32,
    /// Give every triangle its own chart in a new TEXCOORD_1 set (for scenes without one; the
    /// scene's own set is replaced).
    #[arg(long)]
    unwrap: bool,
}

impl LightmapArgs {
    fn settings(&self) -> umbra::passes::lightmap::LightmapSettings {
        umbra::passes::lightmap::LightmapSettings {
            size: self.lightmap_size,
            samples: self.lightmap_samples,
            ..Default::default()
        }
    }
}

#[derive(clap::Args)]
struct BakeArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    probe: ProbeArgs,
    #[command(flatten)]
    lightmap: LightmapArgs,
    /// The probe bake file to write, NAME.probes (umbra's probe format, see the `umbra::bake`
    /// docs).
    #[arg(short, long, value_parser = cli::parse_probes_file)]
    output: Option<PathBuf>,
    /// Also bake lightmaps over TEXCOORD_1 into this folder: lightmap-<material>.exr, layers
    /// `emitters` (direct light of the emissive triangles) and `ambient` (the environment and
    /// reflected light; the bounces beyond the first from the probes when they are baked too).
    #[arg(long, value_name = "DIR")]
    lightmaps: Option<PathBuf>,
    /// Also bake ambient-occlusion maps over TEXCOORD_1 into this folder (occlusion-<material>.png,
    /// for glTF's occlusionTexture with texCoord 1), with occlusion rays of --occlusion-radius.
    #[arg(long, alias = "ao", value_name = "DIR")]
    ao_maps: Option<PathBuf>,
    /// Occlusion maps: the occlusion rays' length in scene units.
    #[arg(long, default_value_t = 0.5, value_parser = cli::parse_positive)]
    occlusion_radius: f32,
}

#[derive(clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Rendering method.
    #[arg(long, value_enum, default_value = "pathtrace")]
    mode: Mode,
    /// Samples per pixel (64 by default); with --sample-range, the whole render's, of which the
    /// part traces its range.
    #[arg(long)]
    spp: Option<u32>,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
    size: (u32, u32),
    /// Scattering events per path (1 = direct light only).
    #[arg(long, default_value_t = 8)]
    max_bounces: u32,
    /// Russian roulette starts after this many scattering events.
    #[arg(long, default_value_t = 3)]
    rr_depth: u32,
    /// Seed of the random numbers (same seed and device: identical output).
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Which of the file's cameras (0-based; default the first, or one framing the scene).
    #[arg(long)]
    camera: Option<usize>,
    /// Microfacet distribution of the specular lobes and its sampling: GGX from visible normals,
    /// GGX from D(h)·cos θh (Walter et al. 2007), Beckmann.
    #[arg(long, value_enum, default_value = "ggx")]
    microfacet: Microfacet,
    /// MIS heuristic.
    #[arg(long, value_enum, default_value = "power")]
    heuristic: Heuristic,
    /// The numbers the path tracer draws its samples from: low-discrepancy (per pixel, scrambled
    /// Sobol points: a lower error at the same samples) or independent (the error falls as 1/spp
    /// and the printed error estimate is unbiased; with low-discrepancy numbers it is high).
    #[arg(long, value_enum, default_value = "low-discrepancy")]
    sampler: Sampler,
    /// Points on emissive triangles for next-event estimation: uniform on the area, or uniform
    /// in the solid angle the triangle subtends where that is at least 0.2 sr (far less noise
    /// next to a large emitter, a few per cent more time on a CPU wherever there are emitters).
    #[arg(long, value_enum, default_value = "area")]
    emitter_sampling: EmitterSampling,
    /// Sampling strategies for emitters: light and BSDF sampling weighted by MIS, BSDF sampling
    /// alone, or light sampling alone (punctual lights are always light-sampled).
    #[arg(long, value_enum, default_value = "mis")]
    strategy: Strategy,
    /// How the path tracer lays out its work: one kernel per path (megakernel) or a kernel per
    /// step over queues of paths (wavefront); the same samples either way.
    #[arg(long, value_enum, default_value = "megakernel")]
    integrator: Integrator,
    /// Stop early once the image's estimated relative RMS error is below this (e.g. 0.01).
    #[arg(long, value_parser = cli::parse_positive)]
    target_error: Option<f32>,
    /// Path tracing: denoise the image (edge-avoiding à-trous filter guided by albedo, normal,
    /// depth and per-pixel variance; the diffuse and specular parts of the radiance filtered
    /// apart, with either integrator). The PNG and the EXR's main layer are denoised; the EXR
    /// keeps the raw estimate as layer `noisy`.
    #[arg(long)]
    denoise: bool,
    /// Path tracing with --denoise: à-trous iterations (1 to 8; taps 1, 2, 4, ... pixels apart).
    #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().iterations)]
    denoise_iterations: u32,
    /// Path tracer: trace only samples A..B of the whole render's --spp N (B at most N), exactly
    /// those a whole render traces there: one part of a render split across processes or
    /// machines, joined by `umbra merge`, which checks that the parts hold all N.
    #[arg(long, value_parser = cli::parse_sample_range, value_name = "A..B", requires = "spp", conflicts_with = "target_error")]
    sample_range: Option<(u32, u32)>,
    /// Path tracer: render only the W×H pixels from column X, row Y of the --size image, each as
    /// the whole image has it (one part for `umbra merge`).
    #[arg(long, value_parser = cli::parse_tile, value_name = "X,Y,W,H")]
    tile: Option<[u32; 4]>,
    /// Exposure in stops for the PNG.
    #[arg(long, default_value_t = 0.0, value_parser = cli::parse_finite)]
    exposure: f32,
    /// Tone curve for the PNG.
    #[arg(long, value_enum, default_value = "neutral")]
    tonemap: ToneCurve,
    /// Hybrid: shadow rays (light samples) per pixel for emissive triangles (and, with
    /// --rt-light-size, per punctual light).
    #[arg(long, default_value_t = 4)]
    shadow_rays: u32,
    /// How direct light (punctual lights, emissive triangles) is sampled. Hybrid: every punctual
    /// light and --shadow-rays emissive samples by power (power), or ReSTIR DI's one resampled
    /// sample per pixel, reused over --restir-frames frames and neighbouring pixels (restir).
    /// Path tracer: at every vertex, one emissive sample by power with MIS and the punctual
    /// lights (power), or one sample resampled from --ris-candidates (ris).
    #[arg(long, value_enum, default_value = "power")]
    direct: Direct,
    /// Path tracer, --direct ris: candidates resampled at each vertex (at most 512 over a path's
    /// --max-bounces).
    #[arg(long, default_value_t = 8)]
    ris_candidates: u32,
    /// Path tracer, --direct ris: reuse the previous sample index's first-hit reservoirs, the
    /// pixel's own (samples), neighbouring pixels' (spatial) or both (unbiased combination; one
    /// dispatch per sample).
    #[arg(long, value_enum, default_value = "off")]
    ris_reuse: RisReuse,
    /// Hybrid, ReSTIR: candidates resampled per pixel and frame.
    #[arg(long, default_value_t = RestirSettings::default().candidates)]
    restir_candidates: u32,
    /// Hybrid, ReSTIR: spatial neighbours merged per pixel (0 to 8).
    #[arg(long, default_value_t = RestirSettings::default().neighbours)]
    restir_neighbours: u32,
    /// Hybrid, ReSTIR: radius of the spatial neighbourhood, pixels.
    #[arg(long, default_value_t = RestirSettings::default().radius, value_parser = cli::parse_positive)]
    restir_radius: f32,
    /// Hybrid, ReSTIR: frames rendered with the camera still, the last one kept (temporal reuse
    /// builds on the earlier ones).
    #[arg(long, default_value_t = RestirSettings::default().frames)]
    restir_frames: u32,
    /// Hybrid, ReSTIR: no temporal reuse.
    #[arg(long)]
    restir_no_temporal: bool,
    /// Hybrid, ReSTIR: the unbiased combination (no visibility reuse; normalised by the
    /// reservoirs that could have produced the sample) instead of the biased one.
    #[arg(long)]
    restir_unbiased: bool,
    /// Hybrid: how punctual lights are shadowed: shadow rays (rt) or a shadow map read with the
    /// nearest texel (hard), percentage-closer filtering (pcf), percentage-closer soft shadows
    /// (pcss) or moment shadow maps (moments).
    #[arg(long, value_enum, default_value = "rt")]
    shadows: ShadowMethod,
    /// Hybrid shadow maps: width = height of each layer in texels (16 to 2048).
    #[arg(long, default_value_t = ShadowSettings::default().map_size)]
    shadow_map_size: u32,
    /// Hybrid shadow maps: constant depth bias, in texels.
    #[arg(long, default_value_t = ShadowSettings::default().depth_bias, value_parser = cli::parse_non_negative)]
    shadow_bias: f32,
    /// Hybrid shadow maps: slope-scaled depth bias, in texels per unit of tan(angle to the light).
    #[arg(long, default_value_t = ShadowSettings::default().slope_bias, value_parser = cli::parse_non_negative)]
    shadow_slope_bias: f32,
    /// Hybrid shadow maps: normal offset of the receiver, in texels.
    #[arg(long, default_value_t = ShadowSettings::default().normal_bias, value_parser = cli::parse_non_negative)]
    shadow_normal_bias: f32,
    /// Hybrid shadow maps: PCF filter radius in texels.
    #[arg(long, default_value_t = ShadowSettings::default().pcf_radius, value_parser = cli::parse_positive)]
    pcf_radius: f32,
    /// Hybrid shadow maps: the largest filter radius in texels, PCSS's blocker search and
    /// penumbra (a wider penumbra is cut to it); also the guard band of cube faces and spot maps.
    /// Default 16, at most an eighth of --shadow-map-size.
    #[arg(long, value_parser = cli::parse_positive)]
    shadow_max_radius: Option<f32>,
    /// Hybrid, rt shadows: shadow punctual lights as sized lights (a sphere of --light-radius, a
    /// cone of --sun-angle) with --shadow-rays rays each, the unoccluded fraction (soft shadows,
    /// what pcss approximates); without it rt shadows points, as the path tracer's lights are.
    #[arg(long)]
    rt_light_size: bool,
    /// Hybrid shadow maps (pcss) and --rt-light-size: radius of point and spot lights, metres.
    #[arg(long, default_value_t = ShadowSettings::default().light_radius, value_parser = cli::parse_non_negative)]
    light_radius: f32,
    /// Hybrid shadow maps (pcss) and --rt-light-size: angular radius of directional lights,
    /// degrees (the sun: 0.27).
    #[arg(long, default_value_t = ShadowSettings::default().sun_angle.to_degrees(), value_parser = cli::parse_non_negative)]
    sun_angle: f32,
    /// Hybrid shadow maps: cascades of a directional light.
    #[arg(long, default_value_t = ShadowSettings::default().cascades)]
    cascades: u32,
    /// Hybrid shadow maps: cascade split scheme, 0 uniform to 1 logarithmic.
    #[arg(long, default_value_t = ShadowSettings::default().cascade_split, value_parser = cli::parse_non_negative)]
    cascade_split: f32,
    /// Hybrid: indirect diffuse light from irradiance probes: a file from `umbra bake` (for this
    /// scene and environment), or `bake` to bake them now (with the --probe-* settings).
    #[arg(long, value_parser = parse_probes, value_name = "FILE|bake")]
    probes: Option<ProbesArg>,
    #[command(flatten)]
    probe: ProbeArgs,
    /// Hybrid: bake lightmaps now for the materials with TEXCOORD_1 charts (or, with --unwrap,
    /// every triangle) and light their diffuse lobe with them (over the probes).
    #[arg(long)]
    lightmaps: bool,
    #[command(flatten)]
    lightmap: LightmapArgs,
    /// Hybrid: no SSAO (the image-based light is not occluded).
    #[arg(long)]
    no_ao: bool,
    /// Hybrid: no image-based lighting (split-sum specular, SH9 diffuse).
    #[arg(long)]
    no_ibl: bool,
    /// AO modes and hybrid SSAO: kernel directions (ao) or rays (rtao) per pixel.
    #[arg(long, default_value_t = 16)]
    ao_samples: u32,
    /// AO modes and hybrid SSAO: the occlusion radius in scene units (metres).
    #[arg(long, default_value_t = 0.5, value_parser = cli::parse_positive)]
    ao_radius: f32,
    /// AO modes: skip the depth-aware blur (ao blurs by default, rtao never does).
    #[arg(long)]
    ao_no_blur: bool,
    /// PNG output (tonemapped sRGB); a name ending in .exr writes only the EXR (as --exr).
    #[arg(short, long, default_value = "umbra.png", value_parser = cli::parse_png_or_exr)]
    output: PathBuf,
    /// EXR output: linear colour, albedo, normal, depth, emission (at the first hit), variance
    /// and moment layers (and `noisy` with --denoise).
    #[arg(long, value_parser = cli::parse_exr)]
    exr: Option<PathBuf>,
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The parts: EXRs written by `umbra render` (path tracer) of one scene and settings.
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// The merged EXR (the same layers and attributes as a render's, so it merges further).
    #[arg(short, long, value_parser = cli::parse_exr)]
    output: PathBuf,
    /// Also a tonemapped PNG of the merged image.
    #[arg(long, value_parser = cli::parse_png)]
    png: Option<PathBuf>,
    /// Write what the parts hold even where they are not the whole render (samples or pixels of
    /// its plan missing: a lost part), with a warning naming what is missing; without it such a
    /// merge is refused.
    #[arg(long)]
    allow_partial: bool,
    /// Denoise the merged render as `umbra render --denoise` denoises one (parts rendered with
    /// --denoise carry the lobe split it filters apart): the PNG and the EXR's main layer are
    /// denoised, the EXR keeps the merged estimate as layer `noisy`.
    #[arg(long)]
    denoise: bool,
    /// With --denoise: à-trous iterations (1 to 8).
    #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().iterations)]
    denoise_iterations: u32,
    /// Exposure in stops for the PNG.
    #[arg(long, default_value_t = 0.0, value_parser = cli::parse_finite)]
    exposure: f32,
    /// Tone curve for the PNG.
    #[arg(long, value_enum, default_value = "neutral")]
    tonemap: ToneCurve,
}

fn merge(args: MergeArgs) -> Result<()> {
    use umbra::merge::PathExr;
    let parts: Vec<(&str, Option<&std::path::Path>)> =
        args.inputs.iter().map(|p| ("the part", Some(p.as_path()))).collect();
    cli::check_outputs(&[("-o", Some(&args.output)), ("--png", args.png.as_deref())], &parts)?;
    let parts = args
        .inputs
        .iter()
        .map(|path| Ok((path.clone(), PathExr::read(path)?)))
        .collect::<Result<Vec<_>>>()?;
    let mut merged = if args.allow_partial {
        let (merged, missing) = umbra::merge::merge_partial(&parts)?;
        for what in &missing {
            log::warn!("--allow-partial: the merge lacks {what}");
        }
        merged
    } else {
        umbra::merge::merge(&parts)?
    };
    if args.denoise {
        let settings = DenoiseSettings { iterations: args.denoise_iterations, ..Default::default() };
        settings.validate()?;
        let image = merged
            .to_image()
            .with_context(|| format!("denoising the merge of {}", args.inputs[0].display()))?;
        let ctx = Context::new(&ContextDesc::default())?;
        let denoised = umbra::render::denoise(&ctx, &image, &settings)?;
        println!(
            "denoise: {} iterations{} in {:.2} ms GPU",
            settings.iterations,
            if image.lobe_split.is_some() { ", diffuse and specular parts apart" } else { "" },
            denoised.gpu_ms
        );
        merged.denoised = Some(denoised.color.iter().map(|p| [p[0], p[1], p[2]]).collect());
    }
    merged.write(&args.output)?;
    let r = merged.region;
    println!(
        "merged {} parts: {r} of {}x{}, {} spp; wrote {}",
        parts.len(),
        merged.image.0,
        merged.image.1,
        merged.spp(),
        args.output.display()
    );
    if let Some(png) = &args.png {
        let shown = merged.denoised.as_ref().unwrap_or(&merged.mean);
        let rgba: Vec<f32> = shown.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
        let display = umbra::color::to_display8(&rgba, args.exposure.exp2(), args.tonemap);
        umbra::output::write_png(png, r.size.0, r.size.1, &display)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

/// `--direct`: one flag over the two modes' light sampling (the path tracer's
/// [`umbra::passes::pathtrace::DirectSampling`], the hybrid's [`DirectLight`]), whose
/// library types carry each method's settings.
#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum Direct {
    Power,
    Restir,
    Ris,
}

#[derive(Clone, Copy, PartialEq, clap::ValueEnum)]
enum Mode {
    /// Progressive path tracing (the ground truth).
    Pathtrace,
    /// Ray-cast G-buffer, deferred lighting with ray-traced shadows, tonemap (real-time style).
    Hybrid,
    /// Screen-space ambient occlusion of the ray-cast G-buffer, blurred (grey image, 1 = open).
    Ao,
    /// Ray-traced ambient occlusion (the ground truth for ao).
    Rtao,
}

fn render(args: RenderArgs) -> Result<()> {
    if args.direct == Direct::Restir && args.mode != Mode::Hybrid {
        anyhow::bail!("--direct restir applies to --mode hybrid (the path tracer's is --direct ris)");
    }
    if args.direct == Direct::Ris && args.mode != Mode::Pathtrace {
        anyhow::bail!("--direct ris applies to --mode pathtrace (the hybrid's is --direct restir)");
    }
    if args.ris_reuse != RisReuse::Off && args.direct != Direct::Ris {
        anyhow::bail!("--ris-reuse reuses the path tracer's first-hit RIS: it needs --direct ris");
    }
    if args.shadows != ShadowMethod::RayTraced && args.mode != Mode::Hybrid {
        anyhow::bail!("--shadows applies to --mode hybrid (the path tracer always traces its shadows)");
    }
    if (args.probes.is_some() || args.lightmaps) && args.mode != Mode::Hybrid {
        anyhow::bail!(
            "--probes and --lightmaps apply to --mode hybrid (the path tracer traces its indirect light)"
        );
    }
    if (args.denoise || args.denoise_iterations != DenoiseSettings::default().iterations)
        && args.mode != Mode::Pathtrace
    {
        anyhow::bail!(
            "--denoise applies to --mode pathtrace (it filters the path tracer's noise, guided by its \
             albedo, normal and variance)"
        );
    }
    let denoise = DenoiseSettings { iterations: args.denoise_iterations, ..Default::default() };
    denoise.validate()?;
    let given = args.probe.given();
    if !given.is_empty() && !matches!(args.probes, Some(ProbesArg::Bake)) {
        anyhow::bail!(
            "{} set{} how to bake probes: add --probes bake (a bake file keeps the settings it was made with)",
            given.join(", "),
            if given.len() == 1 { "s" } else { "" }
        );
    }
    if (args.sample_range.is_some() || args.tile.is_some()) && args.mode != Mode::Pathtrace {
        anyhow::bail!(
            "--sample-range and --tile apply to --mode pathtrace (its parts merge with umbra merge)"
        );
    }
    if let (Some((a, b)), Some(n)) = (args.sample_range, args.spp) {
        if b > n {
            anyhow::bail!(
                "--sample-range {a}..{b} reaches past the render's --spp {n}: a part traces samples of \
                 the whole render's 0..{n}"
            );
        }
    }
    shadow_settings(&args).validate()?;
    let (png, exr) = cli::outputs(&args.output, args.exr.as_ref());
    let probes_file = match &args.probes {
        Some(ProbesArg::File(path)) => Some(path.as_path()),
        _ => None,
    };
    let label = if png.is_some() { "--exr" } else { "-o" };
    cli::check_outputs(
        &[("-o", png.as_deref()), (label, exr.as_deref())],
        &[args.scene.inputs().as_slice(), &[("--probes", probes_file)]].concat(),
    )?;
    let mut stages = Stages::start();
    let mut loaded = args.scene.load()?;
    stages.lap("load");
    if args.lightmap.unwrap {
        umbra::passes::lightmap::unwrap_triangles(&mut loaded.scene, args.lightmap.lightmap_size);
    }
    let camera = loaded.scene.camera(args.camera)?;
    let ctx = Context::new(&ContextDesc::default())?;
    stages.lap("device");
    let planned_spp = args.spp.unwrap_or(64);
    let (first_sample, spp) = args.sample_range.map_or((0, planned_spp), |(a, b)| (a, b - a));
    let settings = umbra::render::PathSettings {
        size: args.tile.map_or(args.size, |t| (t[2], t[3])),
        spp,
        first_sample,
        tile: args.tile.map(|t| umbra::passes::pathtrace::Tile { image: args.size, origin: (t[0], t[1]) }),
        max_bounces: args.max_bounces,
        rr_depth: args.rr_depth,
        seed: args.seed,
        sampler: args.sampler,
        emitter_sampling: args.emitter_sampling,
        microfacet: args.microfacet,
        heuristic: args.heuristic,
        strategy: args.strategy,
        direct: match args.direct {
            Direct::Ris => umbra::passes::pathtrace::DirectSampling::Ris(args.ris_candidates),
            _ => umbra::passes::pathtrace::DirectSampling::Power,
        },
        ris_reuse: args.ris_reuse,
        env: args.scene.env_radiance(),
        env_nee: true,
        target_error: args.target_error,
        integrator: args.integrator,
        // The denoiser filters the diffuse and specular parts apart (either integrator splits
        // them).
        lobe_split: args.denoise,
    };
    if matches!(args.mode, Mode::Ao | Mode::Rtao) {
        let gpu_scene = loaded.upload(&ctx)?;
        stages.lap("BVH and upload");
        return render_ao(&ctx, &gpu_scene, &camera, &args);
    }
    if args.mode == Mode::Hybrid {
        let hybrid = hybrid_settings(&args);
        let (passes, gpu_scene) = upload_alongside(&ctx, &loaded, &mut stages, |passes| {
            passes.prepare_hybrid(&hybrid, args.probes.is_some(), args.lightmaps)
        })?;
        return render_hybrid(&ctx, &passes, &loaded, &gpu_scene, &camera, &hybrid, &args);
    }
    let (passes, gpu_scene) =
        upload_alongside(&ctx, &loaded, &mut stages, |passes| passes.prepare_path_trace(&settings))?;
    let bar = indicatif::ProgressBar::new(settings.spp as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {per_sec}  ETA {eta}")
            .expect("valid template"),
    );
    let start = std::time::Instant::now();
    let image = passes.path_trace(&gpu_scene, &camera, &settings, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    stages.lap("path tracing");
    let pixels = (settings.size.0 * settings.size.1) as f64 * image.spp as f64;
    println!(
        "pathtrace: {} spp at {}x{} in {:.2} s (GPU {:.1} ms, {:.2} Msamples/s, {:.2} segments per sample, {}), \
         estimated relative error {:.4}",
        image.spp,
        settings.size.0,
        settings.size.1,
        start.elapsed().as_secs_f64(),
        image.gpu_ms,
        pixels / (image.gpu_ms * 1e3),
        image.segments as f64 / pixels,
        settings.integrator.name(),
        image.relative_error()
    );
    if image.marches_exhausted > 0 {
        println!(
            "pathtrace: {} implicit-shape marches ran out of steps ({} each) and were taken as misses",
            image.marches_exhausted,
            umbra::gpu::layout::IMPLICIT_MAX_STEPS
        );
    }
    if image.nonfinite_samples > 0 {
        log::warn!(
            "{} samples were NaN or infinite and were dropped (arising in: {})",
            image.nonfinite_samples,
            umbra::gpu::layout::nonfinite_source_names(image.nonfinite_sources).join(", ")
        );
    }
    let (w, h) = settings.size;
    // The image shown: the denoised one with --denoise, else the estimate itself.
    let shown = if args.denoise {
        let denoised = umbra::render::denoise(&ctx, &image, &denoise)?;
        let split = match image.lobe_split {
            Some(_) => format!(
                ", diffuse and specular parts apart ({} on the specular)",
                denoise.specular_iterations
            ),
            None => String::new(),
        };
        println!(
            "denoise: {} iterations{split} in {:.2} ms GPU ({:.2} ms per sample of path tracing)",
            denoise.iterations,
            denoised.gpu_ms,
            image.gpu_ms / image.spp as f64
        );
        stages.lap("denoise");
        denoised.color
    } else {
        image.mean.clone()
    };
    let rgba: Vec<f32> = shown.iter().flat_map(|p| [p[0], p[1], p[2], 1.0]).collect();
    let display = umbra::color::to_display8(&rgba, args.exposure.exp2(), args.tonemap);
    if let Some(png) = png {
        umbra::output::write_png(&png, w, h, &display)?;
        println!("wrote {}", png.display());
    }
    stages.lap("PNG");
    if let Some(path) = &exr {
        let mut exr = umbra::merge::PathExr::new(&image, &settings, render_identity(&args, &loaded));
        if args.sample_range.is_some() {
            exr.planned_spp = Some(planned_spp);
        }
        if args.denoise {
            exr.denoised = Some(shown.iter().map(|p| [p[0], p[1], p[2]]).collect());
        }
        exr.write(path)?;
        println!("wrote {}", path.display());
        stages.lap("EXR");
    }
    stages.log();
    Ok(())
}

/// Wall-clock time of a render's stages, logged at the info level (the default; `RUST_LOG=warn`
/// hides it) to show where a render's time goes besides the GPU's. `RUST_LOG=umbra=debug` adds
/// the path tracer's own split (pipeline creation, each batch's wall and GPU time, readback).
struct Stages {
    clock: std::time::Instant,
    laps: Vec<(&'static str, f64)>,
}

impl Stages {
    fn start() -> Self {
        Self { clock: std::time::Instant::now(), laps: Vec::new() }
    }

    /// Ends the stage `name` now (the next one starts).
    fn lap(&mut self, name: &'static str) {
        self.laps.push((name, self.clock.elapsed().as_secs_f64() * 1e3));
        self.clock = std::time::Instant::now();
    }

    fn log(&self) {
        let laps: Vec<String> = self.laps.iter().map(|(name, ms)| format!("{name} {ms:.1}")).collect();
        log::info!("stages (wall ms): {}", laps.join(", "));
    }
}

/// What must agree between the parts of one path-traced render (`umbra merge` checks it): the
/// scene and environment (by content), the camera and every setting but the samples and tile.
fn render_identity(args: &RenderArgs, loaded: &LoadedScene) -> String {
    fn name<T: clap::ValueEnum>(v: &T) -> String {
        v.to_possible_value().map_or(String::new(), |p| p.get_name().to_string())
    }
    format!(
        "scene {:016x} env {:?} camera {:?} size {}x{} max-bounces {} rr-depth {} seed {} microfacet {} heuristic {} strategy {}",
        loaded.hash(),
        args.scene.env_radiance(),
        args.camera,
        args.size.0,
        args.size.1,
        args.max_bounces,
        args.rr_depth,
        args.seed,
        name(&args.microfacet),
        name(&args.heuristic),
        name(&args.strategy)
    ) + &match args.direct {
        // (Only RIS adds to it: renders made before it existed merge with today's.)
        Direct::Ris => format!(" direct ris {}", args.ris_candidates)
            + match args.ris_reuse {
                RisReuse::Off => "",
                RisReuse::Samples => " reuse samples",
                RisReuse::Spatial => " reuse spatial",
                RisReuse::Both => " reuse both",
            },
        _ => String::new(),
    } + match args.sampler {
        // (Only independent numbers add to it, as RIS does.)
        Sampler::Independent => " sampler independent",
        Sampler::LowDiscrepancy => "",
    } + match args.emitter_sampling {
        // (The same samples in expectation, not the same numbers: parts must agree.)
        EmitterSampling::SolidAngle => " emitter-sampling solid-angle",
        EmitterSampling::Area => "",
    }
}

/// A scene and its environment map, loaded, not yet on the GPU.
struct LoadedScene {
    scene: umbra::scene::Scene,
    env_map: Option<umbra::environment::EnvironmentMap>,
}

impl SceneArgs {
    /// The files read: the scene and the environment map, where given.
    fn inputs(&self) -> [(&'static str, Option<&std::path::Path>); 2] {
        [("the scene", self.scene.as_deref()), ("--env", self.env.as_deref())]
    }

    /// Loads the scene (or the embedded Cornell box) and the environment map.
    fn load(&self) -> Result<LoadedScene> {
        let scene = match &self.scene {
            Some(path) => {
                use umbra::scene::LoadOptions;
                let missing_textures = self.missing_textures;
                umbra::scene::Scene::load_with(path, &LoadOptions { missing_textures })?
            }
            None => umbra::scene::Scene::cornell_box(),
        };
        let env_map = match &self.env {
            Some(path) => {
                let map = umbra::environment::EnvironmentMap::load(path)?;
                log::info!("{}: {}×{} environment", path.display(), map.width, map.height);
                Some(map)
            }
            None => None,
        };
        Ok(LoadedScene { scene, env_map })
    }

    /// The lighting's environment radiance: the map's multiplier, or the constant colour.
    fn env_radiance(&self) -> [f32; 3] {
        if self.env.is_some() {
            [self.env_strength; 3]
        } else {
            self.env_color
        }
    }
}

impl LoadedScene {
    /// Builds the BVH and uploads the scene and its environment map.
    fn upload(&self, ctx: &Context) -> Result<GpuScene> {
        self.upload_with(ctx, SceneBvh::build(&self.scene)?)
    }

    /// Uploads the scene around its BVH, and its environment map.
    fn upload_with(&self, ctx: &Context, bvh: SceneBvh) -> Result<GpuScene> {
        let mut gpu_scene = GpuScene::upload_with(ctx, &self.scene, bvh)?;
        if let Some(map) = &self.env_map {
            gpu_scene.set_environment(ctx, map)?;
        }
        let stats = &gpu_scene.bvh_stats;
        log::info!(
            "{}: {} triangles, {} emissive, {} never hit; BVH {:.1} ms, {} references, {} nodes, SAH {:.2}, stack depth {}",
            self.scene.name,
            stats.triangles,
            gpu_scene.light_count,
            stats.left_out,
            stats.build_ms,
            stats.references,
            stats.nodes,
            stats.sah_cost,
            gpu_scene.bvh.stack_depth
        );
        Ok(gpu_scene)
    }

    /// The features the uploaded scene will have (known once its BVH is built, before the
    /// upload).
    fn features(&self, bvh: &SceneBvh) -> umbra::gpu::SceneFeatures {
        umbra::gpu::SceneFeatures::of_scene(&self.scene, bvh, self.env_map.is_some())
    }

    /// The hash a bake of this scene and environment records.
    fn hash(&self) -> u64 {
        umbra::bake::scene_hash(&self.scene, self.env_map.as_ref())
    }
}

/// Bakes a probe volume over `scene` by `settings` under `lighting`'s environment, with a
/// progress bar over the sweeps; prints the grid, the active probes and the GPU time.
fn bake_probes(
    ctx: &Context,
    passes: &Passes,
    scene: &GpuScene,
    settings: &ProbeSettings,
    lighting: &LightingSettings,
) -> Result<ProbeVolume> {
    let mut volume = ProbeVolume::new(ctx, scene, settings)?;
    let g = volume.grid;
    println!(
        "probes: {}x{}x{} = {} probes, spacing {}, origin {:?}; {} rays; sweeps: {} bouncing, then {} averaging",
        g.counts[0],
        g.counts[1],
        g.counts[2],
        g.count(),
        g.spacing[0],
        g.origin,
        settings.rays,
        settings.bounces,
        settings.sweeps
    );
    let sweeps = volume.bake_sweeps();
    let bar = indicatif::ProgressBar::new(sweeps as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} sweeps  ETA {eta}")
            .expect("valid template"),
    );
    let start = std::time::Instant::now();
    let gpu_ms = passes.bake_probes(scene, &mut volume, lighting, |done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let active = volume.read_active(ctx)?.iter().filter(|a| **a).count();
    println!(
        "baked: {active} of {} probes active, {sweeps} sweeps in {:.2} s (GPU {gpu_ms:.1} ms)",
        g.count(),
        start.elapsed().as_secs_f64()
    );
    Ok(volume)
}

fn bake(args: BakeArgs) -> Result<()> {
    if args.output.is_none() && args.lightmaps.is_none() && args.ao_maps.is_none() {
        anyhow::bail!("nothing to bake: give -o FILE (probes), --lightmaps DIR or --ao-maps DIR");
    }
    let settings = args.probe.settings();
    settings.validate()?;
    cli::check_outputs(&[("-o", args.output.as_deref())], &args.scene.inputs())?;
    for dir in [&args.lightmaps, &args.ao_maps].into_iter().flatten() {
        umbra::atomic::create_dir(dir)?;
    }
    let mut loaded = args.scene.load()?;
    if args.lightmap.unwrap {
        umbra::passes::lightmap::unwrap_triangles(&mut loaded.scene, args.lightmap.lightmap_size);
    }
    let ctx = Context::new(&ContextDesc::default())?;
    let gpu_scene = loaded.upload(&ctx)?;
    let lighting = LightingSettings { env: args.scene.env_radiance(), ..Default::default() };
    let passes = Passes::new(&ctx, &gpu_scene);
    let volume = match &args.output {
        Some(output) => {
            let volume = bake_probes(&ctx, &passes, &gpu_scene, &settings, &lighting)?;
            let hash = loaded.hash();
            umbra::bake::save_probes(&ctx, output, &volume, hash, lighting.env)?;
            println!("wrote {} (scene hash {hash:016x})", output.display());
            Some(volume)
        }
        None => None,
    };
    if let Some(dir) = &args.lightmaps {
        let maps =
            bake_lightmaps(&passes, &loaded.scene, &gpu_scene, &args.lightmap, &lighting, volume.as_ref())?;
        for path in maps.write_exr(dir)? {
            println!("wrote {}", path.display());
        }
    }
    if let Some(dir) = &args.ao_maps {
        let layout =
            umbra::passes::lightmap::LightmapLayout::new(&loaded.scene, args.lightmap.lightmap_size)?;
        let settings = args.lightmap.settings();
        let bar = indicatif::ProgressBar::new(settings.samples as u64);
        let maps =
            passes.bake_occlusion(&gpu_scene, &layout, &settings, args.occlusion_radius, |done, _| {
                bar.set_position(done as u64)
            })?;
        bar.finish_and_clear();
        for path in maps.write_png(dir)? {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// Bakes the lightmaps of `scene`'s TEXCOORD_1 charts with a progress bar over the samples.
fn bake_lightmaps(
    passes: &Passes,
    scene: &umbra::scene::Scene,
    gpu_scene: &GpuScene,
    args: &LightmapArgs,
    lighting: &LightingSettings,
    probes: Option<&ProbeVolume>,
) -> Result<umbra::passes::lightmap::Lightmaps> {
    let layout = umbra::passes::lightmap::LightmapLayout::new(scene, args.lightmap_size)?;
    let settings = args.settings();
    let bar = indicatif::ProgressBar::new(settings.samples as u64);
    let start = std::time::Instant::now();
    let maps = passes.bake_lightmaps(gpu_scene, &layout, &settings, lighting, probes, |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    println!(
        "lightmaps: {} maps of {}², {} samples per texel, in {:.2} s",
        maps.materials.len(),
        maps.size,
        maps.samples,
        start.elapsed().as_secs_f64()
    );
    Ok(maps)
}

/// The hybrid's shadow settings from the flags.
fn shadow_settings(args: &RenderArgs) -> ShadowSettings {
    let method = args.shadows;
    ShadowSettings {
        method,
        map_size: args.shadow_map_size,
        cascades: args.cascades,
        cascade_split: args.cascade_split,
        depth_bias: args.shadow_bias,
        slope_bias: args.shadow_slope_bias,
        normal_bias: args.shadow_normal_bias,
        pcf_radius: args.pcf_radius,
        max_radius: args
            .shadow_max_radius
            .unwrap_or(ShadowSettings::default_max_radius(args.shadow_map_size)),
        light_radius: args.light_radius,
        sun_angle: args.sun_angle.to_radians(),
        sized_rays: args.rt_light_size,
        ..Default::default()
    }
}

/// Builds the BVH, then uploads the rest of `loaded` while `prepare` makes pipelines on a thread
/// (up to a second each on lavapipe) for the features the scene has (the BVH tells its stack
/// depth, which the kernels' walk is specialised on); the passes for the uploaded scene (made again
/// if its features differ: `tests/scene.rs` checks that they do not).
fn upload_alongside(
    ctx: &Context,
    loaded: &LoadedScene,
    stages: &mut Stages,
    prepare: impl FnOnce(&Passes) -> umbra::Result<()> + Send,
) -> Result<(Passes, GpuScene)> {
    let bvh = SceneBvh::build(&loaded.scene)?;
    stages.lap("BVH");
    let passes = Passes::with_features(ctx, loaded.features(&bvh));
    let gpu_scene = std::thread::scope(|s| -> Result<_> {
        let pipelines = s.spawn(|| {
            let clock = std::time::Instant::now();
            let prepared = prepare(&passes);
            log::debug!("pipelines made alongside in {:.1} ms", clock.elapsed().as_secs_f64() * 1e3);
            prepared
        });
        let gpu_scene = loaded.upload_with(ctx, bvh);
        stages.lap("upload");
        let prepared = pipelines.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        let gpu_scene = gpu_scene?;
        prepared?;
        stages.lap("pipelines (the rest)");
        Ok(gpu_scene)
    })?;
    let features = gpu_scene.features();
    if passes.features() != features {
        log::warn!(
            "the features read before the upload, {:?}, differ from the upload's, {features:?}: making the pipelines again",
            passes.features()
        );
        return Ok((Passes::new(ctx, &gpu_scene), gpu_scene));
    }
    Ok((passes, gpu_scene))
}

fn hybrid_settings(args: &RenderArgs) -> umbra::render::HybridSettings {
    umbra::render::HybridSettings {
        size: args.size,
        lighting: LightingSettings {
            shadow_rays: args.shadow_rays,
            seed: args.seed,
            env: args.scene.env_radiance(),
            ibl: !args.no_ibl,
            direct: match args.direct {
                Direct::Power | Direct::Ris => DirectLight::Power,
                Direct::Restir => DirectLight::Restir(RestirSettings {
                    candidates: args.restir_candidates,
                    neighbours: args.restir_neighbours,
                    radius: args.restir_radius,
                    frames: args.restir_frames,
                    temporal: !args.restir_no_temporal,
                    unbiased: args.restir_unbiased,
                    ..Default::default()
                }),
            },
            ..Default::default()
        },
        exposure: args.exposure,
        curve: args.tonemap,
        ibl: Default::default(),
        ao: (!args.no_ao).then(|| umbra::passes::ao::AoSettings {
            samples: args.ao_samples,
            radius: args.ao_radius,
            blur: !args.ao_no_blur,
            seed: args.seed,
            ..Default::default()
        }),
        shadows: shadow_settings(args),
    }
}

fn render_hybrid(
    ctx: &Context,
    passes: &Passes,
    loaded: &LoadedScene,
    scene: &GpuScene,
    camera: &umbra::scene::Camera,
    settings: &umbra::render::HybridSettings,
    args: &RenderArgs,
) -> Result<()> {
    let probes = match &args.probes {
        None => None,
        Some(ProbesArg::Bake) => {
            Some(bake_probes(ctx, passes, scene, &args.probe.settings(), &settings.lighting)?)
        }
        Some(ProbesArg::File(path)) => {
            let volume = umbra::bake::load_probes(ctx, path, loaded.hash(), settings.lighting.env)?;
            let g = volume.grid;
            println!(
                "probes: {} ({}x{}x{} probes, {} rays)",
                path.display(),
                g.counts[0],
                g.counts[1],
                g.counts[2],
                volume.settings.rays
            );
            Some(volume)
        }
    };
    let lightmaps = match args.lightmaps {
        false => None,
        true => {
            let maps = bake_lightmaps(
                passes,
                &loaded.scene,
                scene,
                &args.lightmap,
                &settings.lighting,
                probes.as_ref(),
            )?;
            Some(umbra::passes::lightmap::GpuLightmaps::upload(ctx, &maps, loaded.scene.materials.len())?)
        }
    };
    let image = passes.hybrid_with(scene, camera, settings, probes.as_ref(), lightmaps.as_ref())?;
    let times: Vec<String> = image.pass_ms.iter().map(|(name, ms)| format!("{name} {ms:.3} ms")).collect();
    println!("hybrid: {}x{}; GPU {}", args.size.0, args.size.1, times.join(", "));
    let (w, h) = args.size;
    let bytes: Vec<u8> = image.display.iter().flatten().copied().collect();
    let (png, exr) = cli::outputs(&args.output, args.exr.as_ref());
    if let Some(png) = png {
        umbra::output::write_png(&png, w, h, &bytes)?;
        println!("wrote {}", png.display());
    }
    if let Some(path) = &exr {
        let g = &image.gbuffer;
        let rgb = |v: &[[f32; 4]]| -> Vec<f32> { v.iter().flat_map(|p| [p[0], p[1], p[2]]).collect() };
        let colour = rgb(&image.color);
        let normal = rgb(&g.normal);
        let base = rgb(&g.base);
        let emission = rgb(&g.emission);
        let metal_rough: Vec<f32> = g.base.iter().zip(&g.normal).flat_map(|(b, n)| [b[3], n[3]]).collect();
        let material: Vec<f32> = g
            .material
            .iter()
            .map(|m| if m[0] == umbra::passes::gbuffer::GBUFFER_NO_SURFACE { -1.0 } else { m[0] as f32 })
            .collect();
        use umbra::output::Layer;
        umbra::output::write_exr(
            path,
            w as usize,
            h as usize,
            &[
                Layer { name: "", channels: &["R", "G", "B"], data: &colour },
                Layer { name: "depth", channels: &["Z"], data: &g.depth },
                Layer { name: "normal", channels: &["X", "Y", "Z"], data: &normal },
                Layer { name: "albedo", channels: &["R", "G", "B"], data: &base },
                Layer {
                    name: "material",
                    channels: &["metallic", "roughness", "id"],
                    data: &{
                        metal_rough
                            .chunks(2)
                            .zip(&material)
                            .flat_map(|(mr, id)| [mr[0], mr[1], *id])
                            .collect::<Vec<f32>>()
                    },
                },
                Layer { name: "emission", channels: &["R", "G", "B"], data: &emission },
            ],
        )?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn render_ao(
    ctx: &Context,
    scene: &GpuScene,
    camera: &umbra::scene::Camera,
    args: &RenderArgs,
) -> Result<()> {
    use umbra::render::AoMethod;
    let (method, name) = match args.mode {
        Mode::Rtao => (AoMethod::Rtao, "rtao"),
        _ => (AoMethod::Ssao, "ao"),
    };
    let settings = umbra::passes::ao::AoSettings {
        samples: args.ao_samples,
        radius: args.ao_radius,
        blur: method == AoMethod::Ssao && !args.ao_no_blur,
        seed: args.seed,
        ..Default::default()
    };
    let image = umbra::render::ambient_occlusion(ctx, scene, camera, args.size, method, &settings)?;
    let times: Vec<String> = image.pass_ms.iter().map(|(name, ms)| format!("{name} {ms:.3} ms")).collect();
    println!("{name}: {}x{}; GPU {}", args.size.0, args.size.1, times.join(", "));
    let (w, h) = args.size;
    // AO is a linear fraction: stored as sRGB grey so the PNG shows the value it holds.
    let bytes: Vec<u8> = image
        .values
        .iter()
        .flat_map(|&v| {
            let g = (umbra::color::srgb_encode(v.clamp(0.0, 1.0)) * 255.0).round() as u8;
            [g, g, g, 255]
        })
        .collect();
    let (png, exr) = cli::outputs(&args.output, args.exr.as_ref());
    if let Some(png) = png {
        umbra::output::write_png(&png, w, h, &bytes)?;
        println!("wrote {}", png.display());
    }
    if let Some(path) = exr {
        use umbra::output::Layer;
        umbra::output::write_exr(
            &path,
            w as usize,
            h as usize,
            &[
                Layer { name: "", channels: &["Y"], data: &image.values },
                Layer { name: "unblurred", channels: &["Y"], data: &image.unblurred },
                Layer { name: "depth", channels: &["Z"], data: &image.gbuffer.depth },
            ],
        )?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn main() {
    cli::main(|| {
        use clap::{CommandFactory, FromArgMatches};
        let matches = Cli::command().get_matches();
        let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
        let given = matches.subcommand().map(|(_, m)| cli::given_flags(m)).unwrap_or_default();
        run(cli, &given)
    });
}

/// The render flags given that cannot apply to the render asked for, each with what it needs
/// (`--mode hybrid`, `--lightmaps`, ...): refused, never ignored. A flag's default never blocks
/// (only flags given on the command line are checked).
fn inapplicable_render_flags(args: &RenderArgs, given: &[String]) -> Vec<String> {
    let (pathtrace, hybrid) = (args.mode == Mode::Pathtrace, args.mode == Mode::Hybrid);
    let maps = hybrid && args.shadows != ShadowMethod::RayTraced;
    let ssao = hybrid && !args.no_ao;
    given
        .iter()
        .filter_map(|id| {
            let (applies, needs) = match id.as_str() {
                "spp" | "max_bounces" | "rr_depth" | "microfacet" | "heuristic" | "sampler"
                | "emitter_sampling" | "strategy" | "integrator" | "target_error" | "denoise"
                | "denoise_iterations" | "sample_range" | "tile" => (pathtrace, "--mode pathtrace"),
                "ris_candidates" => {
                    (pathtrace && args.direct == Direct::Ris, "--mode pathtrace --direct ris")
                }
                "exposure" | "tonemap" => (
                    pathtrace || hybrid,
                    "--mode pathtrace or hybrid (ao and rtao write the occlusion itself)",
                ),
                "shadow_rays" | "no_ao" | "no_ibl" | "shadows" | "probes" | "lightmaps" | "rt_light_size" => {
                    (hybrid, "--mode hybrid")
                }
                "restir_candidates" | "restir_neighbours" | "restir_radius" | "restir_frames"
                | "restir_no_temporal" | "restir_unbiased" => {
                    (hybrid && args.direct == Direct::Restir, "--mode hybrid --direct restir")
                }
                "shadow_map_size" | "shadow_bias" | "shadow_slope_bias" | "shadow_normal_bias"
                | "pcf_radius" | "shadow_max_radius" | "cascades" | "cascade_split" => {
                    (maps, "--mode hybrid with shadow maps (--shadows hard|pcf|pcss|moments)")
                }
                "light_radius" | "sun_angle" => (
                    hybrid && (args.shadows == ShadowMethod::Pcss || args.rt_light_size),
                    "--mode hybrid with sized lights (--shadows pcss, or --rt-light-size)",
                ),
                "lightmap_size" | "lightmap_samples" | "unwrap" => (args.lightmaps, "--lightmaps (hybrid)"),
                "ao_samples" | "ao_radius" => (
                    ssao || matches!(args.mode, Mode::Ao | Mode::Rtao),
                    "--mode ao or rtao, or hybrid's SSAO",
                ),
                "ao_no_blur" => {
                    (ssao || args.mode == Mode::Ao, "--mode ao, or hybrid's SSAO (rtao never blurs)")
                }
                _ => (true, ""),
            };
            (!applies).then(|| format!("{} applies to {needs}", cli::flag(id)))
        })
        .collect()
}

fn run(cli: Cli, given: &[String]) -> Result<()> {
    match cli.command {
        Command::Render(args) => {
            let refused = inapplicable_render_flags(&args, given);
            if !refused.is_empty() {
                anyhow::bail!("{}: such a flag would be ignored", refused.join("; "));
            }
            render(args)?
        }
        Command::Bake(args) => {
            let mut refused = Vec::new();
            for id in given {
                let (applies, needs) = match id.as_str() {
                    "probe_spacing" | "probe_rays" | "probe_sweeps" | "probe_bounces" => {
                        (args.output.is_some(), "a probe bake (-o FILE.probes)")
                    }
                    "lightmap_size" | "lightmap_samples" | "unwrap" => (
                        args.lightmaps.is_some() || args.ao_maps.is_some(),
                        "--lightmaps DIR or --ao-maps DIR",
                    ),
                    "occlusion_radius" => (args.ao_maps.is_some(), "--ao-maps DIR"),
                    _ => (true, ""),
                };
                if !applies {
                    refused.push(format!("{} applies to {needs}", cli::flag(id)));
                }
            }
            if !refused.is_empty() {
                anyhow::bail!("{}: such a flag would be ignored", refused.join("; "));
            }
            bake(args)?
        }
        Command::Merge(args) => merge(args)?,
        Command::Info => {
            for (name, ty) in Context::list_devices()? {
                println!("{name} ({ty:?})");
            }
            let ctx = Context::new(&ContextDesc::default())?;
            let info = ctx.info();
            println!(
                "umbra uses: {} ({:?}), subgroup size {}, max storage buffer {} MiB",
                info.name,
                info.device_type,
                info.subgroup_size,
                info.max_storage_buffer_range >> 20
            );
        }
        Command::Pattern { size: (w, h), output, exr } => {
            cli::check_outputs(&[("-o", Some(&output)), ("--exr", exr.as_deref())], &[])?;
            let ctx = Context::new(&ContextDesc::default())?;
            let image = Image::storage_2d(&ctx, "pattern", w, h, raw::Format::R32G32B32A32_SFLOAT)?;
            use umbra::gpu::kernels::test_pattern;
            let pipeline = umbra::gpu::Pipeline::<test_pattern::Kernel>::plain(&ctx)?;
            let mut timer = GpuTimer::new(&ctx, 1)?;
            ctx.submit(|cmd| {
                timer.reset(cmd);
                image.init_general(&ctx, cmd);
                timer.begin(cmd, "test_pattern")?;
                let params = umbra::gpu::layout::PatternParams { size: [w, h], seed: 0, frame: 0 };
                pipeline.record(
                    cmd,
                    &test_pattern::Resources { out_image: &image.view },
                    &params,
                    [w, h, 1],
                    [8, 8, 1],
                )?;
                timer.end(cmd)
            })?;
            for t in timer.read()? {
                println!("{}: {:.3} ms", t.name, t.ms);
            }
            let mut rgba: Vec<f32> = image.read(&ctx)?;
            // Normalise to a viewable picture: x → red, y → green, hash → blue.
            for p in rgba.chunks_exact_mut(4) {
                let (x, y, hsh) = (p[0] / w as f32, p[1] / h as f32, p[3] / 65535.0);
                p.copy_from_slice(&[x, y, hsh, 1.0]);
            }
            umbra::output::write_png(&output, w, h, &umbra::color::to_srgb8(&rgba, 1.0))?;
            if let Some(path) = exr {
                umbra::output::write_exr(
                    &path,
                    w as usize,
                    h as usize,
                    &[umbra::output::Layer { name: "", channels: &["R", "G", "B", "A"], data: &rgba }],
                )?;
            }
            let _ = vk::MemoryLocation::GpuOnly;
            println!("wrote {}", output.display());
        }
    }
    Ok(())
}
