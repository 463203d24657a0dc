//! `umbra-bench`: umbra's measurements. `suite` charts every method's GPU time against its error
//! to a converged reference; `rays` is the ray-throughput mode (BVH build statistics and Mrays/s
//! for primary, shadow and diffuse rays, validated before timing); `passes` times each pass;
//! `build` times the BVH build alone (CPU only, no Vulkan); `shadows` compares shadow maps with
//! shadow rays; `mis` the path tracer's estimators against Mitsuba references; `paths` the path
//! tracer's throughput on a set of scenes; `peers` prints the tables of `peers.py`'s comparisons.
//!
//! Every measuring command writes JSON, and `--table FILE` prints the Markdown table of a written
//! file without measuring anything: BENCHMARKS.md's current figures are those tables, printed
//! from the JSON committed in docs/bench (tests/bench.rs checks that they still match).

mod animation;
mod antialias;
mod build;
mod chart;
mod denoise;
// Shared with `umbra`, which uses parsers this binary does not.
#[allow(dead_code)]
#[path = "../../cli.rs"]
mod cli;
mod implicit;
mod mis;
mod passes;
mod paths;
mod peers;
mod pipelines;
mod probes;
mod rays;
mod restir;
mod restir_pt;
mod scenes;
mod shadows;
mod suite;
mod temporal;

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use rays::{RayReport, RayScene, RaySettings};
use serde_json::json;
use serde_json::Value;
use std::path::PathBuf;
use umbra::vk::{Context, ContextDesc};

#[derive(Parser)]
#[command(name = "umbra-bench", version, about = "umbra's benchmarks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Speed against accuracy: every method on each scene, GPU time against error to a converged
    /// path-traced reference; JSON, CSV and one chart (SVG, PNG) per scene.
    Suite {
        /// A small run (Cornell box and sphere grid at 64×64, 256-spp references): a minute or
        /// two on lavapipe.
        #[arg(long)]
        quick: bool,
        /// Image size.
        #[arg(long, default_value = "128x128", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of each reference (cached in the output folder).
        #[arg(long, default_value_t = 2048)]
        reference_spp: u32,
        /// Largest path-traced sample count measured (1, 2, 4, … up to it).
        #[arg(long, default_value_t = 256)]
        max_spp: u32,
        /// Shadow-ray counts of the hybrid sweep.
        #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32")]
        shadow_rays: Vec<u32>,
        /// Timed repeats of each hybrid setting (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Constant environment (sky) radiance r,g,b around every scene, lighting it besides its
        /// own lights (the hybrid approximates it with split-sum IBL and SSAO).
        #[arg(long, value_parser = cli::parse_rgb, default_value = "0.5,0.5,0.5")]
        env_color: [f32; 3],
        /// AO radius in scene units for SSAO and RTAO.
        #[arg(long, default_value_t = 0.5, value_parser = cli::parse_positive)]
        ao_radius: f32,
        /// glTF scenes to run as well (their first camera, or one framing them).
        #[arg(long = "gltf")]
        gltf: Vec<PathBuf>,
        /// Dabrovic Sponza, lit by a sun along 0.25,-1,0.15 (not in --quick runs; default
        /// $UMBRA_ASSETS/gltf/SponzaDabrovic/sponza_dabrovic.glb; skipped with a message when
        /// neither names one).
        #[arg(long)]
        sponza: Option<PathBuf>,
        /// Run only the scenes of these keys (cornell, cornell-point, spheres, textured,
        /// sponza-sun, a --gltf file's stem); all when absent.
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Where to write suite.json, suite.csv, the charts and the cached references.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown tables of an earlier run's suite.json and exit (nothing is
        /// rendered).
        #[arg(long)]
        table: Option<PathBuf>,
        /// Redraw the charts of an earlier run's suite.json (every scene's three, SVG and PNG)
        /// into --out and exit: nothing is rendered or measured. The AO charts' radius is the
        /// file's, or --ao-radius where the file does not record it.
        #[arg(long, value_name = "FILE", conflicts_with = "table")]
        redraw: Option<PathBuf>,
    },
    /// BVH build statistics and ray throughput (Mrays/s) for primary, shadow and diffuse rays.
    Rays {
        /// A small, fast run (one 78k-triangle scene, 128×128 rays): checks the binary works.
        #[arg(long)]
        quick: bool,
        /// Rays per kind as a WIDTHxHEIGHT primary-ray image.
        #[arg(long, default_value = "512x512", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Timed repeats per ray kind (after one warm-up); the median is reported.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Also build with the full-sweep SAH to compare SAH cost (slow on large scenes).
        #[arg(long)]
        sweep: bool,
        /// glTF scenes to measure as well (their first camera, or one framing them).
        #[arg(long = "gltf")]
        gltf: Vec<PathBuf>,
        /// Where to write rays.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Primary rays in row order instead of 8×8 tiles (what ray order costs).
        #[arg(long)]
        row_order: bool,
        /// Only the `--gltf` scenes, not the generated terrains.
        #[arg(long)]
        no_terrain: bool,
        /// Write each scene's triangles, rays and umbra's hits to this folder, for a peer
        /// (`src/bin/umbra-bench/peers.py` traces the same rays with Embree).
        #[arg(long)]
        dump: Option<PathBuf>,
        /// Print the Markdown table of an earlier run's rays.json and exit (nothing is traced).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// GPU time per pass and per stage of the hybrid frame (G-buffer, ambient occlusion, deferred
    /// lighting) with each AO variant, and of one path-traced sample per pixel, on one scene,
    /// median over repeats after a warm-up.
    Passes {
        /// A glTF scene (its first camera, or one framing it); the Cornell box when absent.
        scene: Option<PathBuf>,
        /// Image size.
        #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Timed repeats (after one warm-up).
        #[arg(long, default_value_t = 10)]
        repeats: usize,
        /// Shadow rays per pixel for emissive triangles in the lighting pass.
        #[arg(long, default_value_t = 4)]
        shadow_rays: u32,
        /// Where to write passes.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of earlier runs' passes.json (repeat it: a column per file
        /// and frame variant, all measured with the same settings) and exit (nothing is
        /// rendered).
        #[arg(long)]
        table: Vec<PathBuf>,
        /// The hybrid frame's ambient occlusion variants timed, in turn within each repeat.
        #[arg(long, value_enum, value_delimiter = ',', default_value = "ssao,gtao,gtao-half")]
        ao: Vec<passes::AoVariant>,
        /// The G-buffers timed (each with every AO variant): ray-cast, rasterized.
        #[arg(long, value_enum, value_delimiter = ',', default_value = "raycast,raster")]
        gbuffer: Vec<umbra::passes::visibility::GBufferMethod>,
    },
    /// Shadow maps against shadow rays on one scene: the maps' GPU time by step, the lighting
    /// pass with each filter, and each lit image's error against the ray-traced one (JSON and a
    /// Markdown table).
    Shadows {
        /// A glTF scene (its first camera, or one framing it); the Cornell box when absent.
        scene: Option<PathBuf>,
        /// Image size.
        #[arg(long, default_value = "1920x1080", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Width = height of each map layer.
        #[arg(long, default_value_t = 2048)]
        map_size: u32,
        /// Cascades of a directional light.
        #[arg(long, default_value_t = 4)]
        cascades: u32,
        /// Add a sun shining along X,Y,Z (added anyway, along 0.25,-1,0.15, to a scene without
        /// punctual lights).
        #[arg(long, value_parser = cli::parse_direction)]
        sun: Option<[f32; 3]>,
        /// Radius of point and spot lights for PCSS and the sized lights' rays, metres.
        #[arg(long, default_value_t = umbra::passes::shadow::ShadowSettings::default().light_radius, value_parser = cli::parse_non_negative)]
        light_radius: f32,
        /// Angular radius of directional lights for PCSS and the sized lights' rays, degrees.
        #[arg(long, default_value_t = umbra::passes::shadow::ShadowSettings::default().sun_angle.to_degrees(), value_parser = cli::parse_non_negative)]
        sun_angle: f32,
        /// PCSS's largest filter radius, texels.
        #[arg(long, default_value_t = umbra::passes::shadow::ShadowSettings::default().max_radius, value_parser = cli::parse_positive)]
        max_radius: f32,
        /// Render the cascades' whole windows, not only the tiles the view's pixels read (the
        /// comparison for the marks' gain).
        #[arg(long)]
        no_view_marks: bool,
        /// Timed repeats (after a warm-up).
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Where to write shadows.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// Irradiance probes on the speed/accuracy chart: the hybrid without and with baked probes
    /// at a sweep of spacings, frame time and error against a converged path-traced reference
    /// (JSON and a Markdown table), on the Cornell box and Dabrovic Sponza under a sun.
    Probes {
        /// Dabrovic Sponza, a sun added (default $UMBRA_ASSETS/gltf/SponzaDabrovic/
        /// sponza_dabrovic.glb; skipped with a warning when neither names one).
        #[arg(long)]
        sponza: Option<PathBuf>,
        /// More glTF scenes (their first camera, or one framing them).
        #[arg(long = "gltf")]
        gltf: Vec<PathBuf>,
        /// Image size.
        #[arg(long, default_value = "192x144", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of each reference (cached in the output folder).
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// Probe spacings, as the scene's longest side / n.
        #[arg(long, value_delimiter = ',', default_value = "4,8,16")]
        per_side: Vec<u32>,
        /// Lightmap sizes (texels a side) on the Cornell box, its triangles unwrapped.
        #[arg(long, value_delimiter = ',', default_value = "32,64,128")]
        lightmap_sizes: Vec<u32>,
        /// Timed repeats (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Constant environment (sky) radiance r,g,b (as the suite's).
        #[arg(long, value_parser = cli::parse_rgb, default_value = "0.5,0.5,0.5")]
        env_color: [f32; 3],
        /// Where to write probes.json and the cached references.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// The denoiser's error against time: the path tracer's series (1, 2, 4, … spp of one
    /// accumulation) raw and denoised, relative MSE against the suite's references, the filter's
    /// GPU time against one sample's; JSON, one chart per scene.
    Denoise {
        /// A small run (Cornell box at 64×64, 256-spp reference, up to 32 spp).
        #[arg(long)]
        quick: bool,
        /// Image size.
        #[arg(long, default_value = "128x128", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of each reference (cached in the output folder, shared with the
        /// suite's).
        #[arg(long, default_value_t = 2048)]
        reference_spp: u32,
        /// Largest path-traced sample count measured (1, 2, 4, … up to it).
        #[arg(long, default_value_t = 256)]
        max_spp: u32,
        /// Timed repeats of the filter at each reading (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        /// Constant environment (sky) radiance r,g,b (as the suite's).
        #[arg(long, value_parser = cli::parse_rgb, default_value = "0.5,0.5,0.5")]
        env_color: [f32; 3],
        /// The filter's à-trous iterations.
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().iterations)]
        iterations: u32,
        /// The filter's luminance edge-stopping σ.
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().sigma_luminance, value_parser = cli::parse_positive)]
        sigma_luminance: f32,
        /// The filter's 3×3 prefilter of the variance (true or false).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().prefilter_variance, action = clap::ArgAction::Set)]
        prefilter: bool,
        /// Added to the albedo the filter divides by (0: texture edges exact).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().albedo_offset, value_parser = cli::parse_non_negative)]
        albedo_offset: f32,
        /// The filter's 5×5 taps (true) or 3×3 (false).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().wide, action = clap::ArgAction::Set)]
        wide: bool,
        /// The filter's spatial variance floor in its first iteration (true or false).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().spatial_variance, action = clap::ArgAction::Set)]
        spatial_variance: bool,
        /// Path trace with the lobe split and filter the diffuse and specular parts apart (true)
        /// or their sum (false).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().lobe_split, action = clap::ArgAction::Set)]
        lobe_split: bool,
        /// The filter's à-trous iterations on the specular part (with the lobe split).
        #[arg(long, default_value_t = umbra::render::DenoiseSettings::default().specular_iterations)]
        specular_iterations: u32,
        /// glTF scenes to run as well (their first camera, or one framing them).
        #[arg(long = "gltf")]
        gltf: Vec<PathBuf>,
        /// Where to write denoise.json, the charts and the cached references.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// The denoiser's temporal accumulation on a camera path (the Cornell box, a slow pan, one
    /// sample a frame): per frame the relative MSE of the raw sample, the spatial filter alone
    /// and the temporal denoiser against a reference of the frame's camera; then the filter's GPU
    /// time with and without the temporal step. Writes temporal.json and prints its table.
    Temporal {
        /// Image size.
        #[arg(long, default_value = "64x64", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Frames of the camera path.
        #[arg(long, default_value_t = 16)]
        frames: u32,
        /// How far the camera turns a frame, in pixels at the image's centre.
        #[arg(long, default_value_t = 0.5)]
        pan: f32,
        /// Samples per pixel of each frame's reference.
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// Timed repeats of each filter (after a warm-up); the medians are reported.
        #[arg(long, default_value_t = 11)]
        repeats: usize,
        /// Only the timings (no references, no errors).
        #[arg(long)]
        timing_only: bool,
        /// Also write each frame's reference, raw sample and filtered images to DIR/frameNN.exr
        /// (one layer each), to see where an error lies.
        #[arg(long, value_name = "DIR")]
        dump: Option<PathBuf>,
        /// Where to write temporal.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the table of an earlier run's JSON instead of measuring.
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// The path tracer's estimators side by side (the MIS figure, measured): each microfacet
    /// sampling × {MIS power, MIS balance, BSDF sampling alone, light sampling alone} on the
    /// scenes of Mitsuba references, relative MSE against the reference at one sample count
    /// (JSON and a Markdown table). Run from the repository root.
    Mis {
        /// Mitsuba references (NAME.json and NAME.exr in --reference-dir).
        #[arg(long, value_delimiter = ',', default_value = "spheres-sky,spheres-sky-beckmann,cornell")]
        references: Vec<String>,
        /// Folder of the references.
        #[arg(long, default_value = "tests/reference/mitsuba")]
        reference_dir: PathBuf,
        /// Samples per pixel of every render.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Independent renders per estimator (their relative MSEs are averaged).
        #[arg(long, default_value_t = 8)]
        seeds: u32,
        /// Where to write mis.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// The path tracer's throughput on a set of scenes: Msamples/s and path segments per second,
    /// median of timed submissions after a warm-up, and each scene's ratio to the median of the
    /// set (JSON and a Markdown table).
    Paths {
        /// glTF scenes; when none are given, the embedded Cornell box, scenes/*.glb and one glTF
        /// file of each model under --assets.
        scenes: Vec<PathBuf>,
        /// Sample models for the default set (of each subfolder its .glb, glTF-Binary/*.glb,
        /// .gltf or glTF/*.gltf, the first found); default $UMBRA_ASSETS/gltf, none without it.
        #[arg(long)]
        assets: Option<PathBuf>,
        /// Image size.
        #[arg(long, default_value = "128x128", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of each timed submission.
        #[arg(long, default_value_t = 16)]
        spp: u32,
        /// Timed submissions (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Scattering events per path.
        #[arg(long, default_value_t = 8)]
        max_bounces: u32,
        /// Russian roulette from this many scattering events (`umbra render`'s default).
        #[arg(long, default_value_t = 3)]
        rr_depth: u32,
        /// Constant environment radiance r,g,b around every scene (so scenes without lights are
        /// lit), or the --env map's multiplier.
        #[arg(long, value_parser = cli::parse_rgb, default_value = "0.5,0.5,0.5")]
        env_color: [f32; 3],
        /// An environment map (EXR or Radiance HDR) lighting every scene, importance-sampled.
        #[arg(long)]
        env: Option<PathBuf>,
        /// Integrators to time, each scene with each in turn (the table's main part is the
        /// first's; the others are compared with it).
        #[arg(long, value_enum, value_delimiter = ',', default_value = "megakernel")]
        integrator: Vec<umbra::passes::pathtrace::Integrator>,
        /// Also count how busy the SIMD lanes are in the megakernel's BVH walks (one more
        /// untimed submission per scene, through a pipeline of its own).
        #[arg(long)]
        lanes: bool,
        /// Where to write paths.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// What making a scene's pipelines costs: `vkCreateComputePipelines` for the path tracer's
    /// megakernel and wavefront kernel and the hybrid's G-buffer and lighting kernels, specialised
    /// on each scene, with the host folding their constants and without (JSON and a Markdown
    /// table).
    Pipelines {
        /// glTF scenes; when none are given, the embedded Cornell box, scenes/many-lights.glb and
        /// DamagedHelmet under --assets.
        scenes: Vec<PathBuf>,
        /// Sample models for the default set; default $UMBRA_ASSETS/gltf, none without it.
        #[arg(long)]
        assets: Option<PathBuf>,
        /// Folded pipelines made per kernel and scene (the median is reported); the unfolded one
        /// is made once.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Where to write pipelines.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is made).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// BVH build time and SAH cost only (CPU, no Vulkan): the generated terrains of `rays` and
    /// any glTF files, built repeatedly; prints the median and fastest build and the CPU time per
    /// build, and writes build.json.
    Build {
        /// Terrain resolutions n (2·n² + 15,360 triangles each): 351 is 262k, 704 is 1M.
        #[arg(long, value_delimiter = ',', default_value = "351,704")]
        terrain: Vec<u32>,
        /// glTF scenes to build as well.
        #[arg(long = "gltf")]
        gltf: Vec<PathBuf>,
        /// Builds per scene (after one warm-up build).
        #[arg(long, default_value_t = 5)]
        builds: usize,
        /// Also build with the full-sweep SAH and compare SAH cost (slow on large scenes).
        #[arg(long)]
        sweep: bool,
        /// Where to write build.json.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's build.json and exit (nothing is built).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// An implicit sphere (ray-marched) against tessellated spheres of rising triangle count: BVH
    /// memory and build time, path-tracing GPU time, and the geometric error (camera rays whose
    /// verdict differs from the analytic sphere's; the largest distance of a hit from it);
    /// writes implicit.json and a chart (implicit.svg, .png).
    Implicit {
        /// Image size of the timed path trace.
        #[arg(long, default_value = "64x64", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of the timed path trace.
        #[arg(long, default_value_t = 16)]
        spp: u32,
        /// Timed path traces per sphere (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Camera rays a side for the geometric errors.
        #[arg(long, default_value_t = 512)]
        rays: u32,
        /// Icosphere subdivisions (20·4^s triangles).
        #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5,6,7")]
        subdivisions: Vec<u32>,
        /// Where to write implicit.json and the chart.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// An animated scene's BVH following its pose frame by frame, refit against rebuild, for a
    /// skin, a rigid node, a morph target and all three: BVH and update time, SAH cost, the
    /// path-traced frame's GPU time; JSON and a table.
    Animation {
        /// The animated scene (its animations "bend", "turn" and "squash").
        #[arg(long, default_value = "scenes/animated.glb")]
        scene: PathBuf,
        /// Image size of the path-traced frames.
        #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of each frame.
        #[arg(long, default_value_t = 4)]
        spp: u32,
        /// Frames over the loop.
        #[arg(long, default_value_t = 24)]
        frames: u32,
        /// Path traces of each frame, the fastest kept.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Where to write `animation.json`.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// Anti-aliasing of the hybrid frame: one-shot supersampling at a sweep of sub-frames and
    /// TAA (embedding API, still camera) after each frame, mean LDR-FLIP against the path
    /// tracer against GPU time; JSON, a table and a chart.
    Antialias {
        /// The scene (default: scenes/spheres.glb).
        #[arg(long, default_value = "scenes/spheres.glb")]
        scene: PathBuf,
        /// Equirectangular environment map lighting the scene (else --env-color).
        #[arg(long)]
        env: Option<PathBuf>,
        /// Constant environment radiance r,g,b when there is no --env map.
        #[arg(long, value_parser = cli::parse_rgb, default_value = "0.5,0.5,0.5")]
        env_color: [f32; 3],
        /// Image size.
        #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of the reference.
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// Sub-frame counts of the supersampled series.
        #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16")]
        samples: Vec<u32>,
        /// Frames of the TAA series.
        #[arg(long, default_value_t = 16)]
        taa_frames: u32,
        /// Timed repeats of each supersampled render (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Where to write `antialias-<scene>.json` and the chart.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
        /// With --table: also redraw that run's chart into --out (`antialias-<stem>.svg`, `.png`,
        /// the stem the JSON file's own, less "antialias-").
        #[arg(long, requires = "table")]
        redraw: bool,
    },
    /// ReSTIR DI against power-sampled light sampling in the hybrid's lighting pass on a
    /// many-light scene: error against time of the direct light, and the equal-error speed-up.
    Restir {
        /// The scene (default: scenes/many-lights.glb).
        #[arg(long, default_value = "scenes/many-lights.glb")]
        scene: PathBuf,
        /// Image size.
        #[arg(long, default_value = "256x256", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Frames of 64 shadow rays averaged into the reference.
        #[arg(long, default_value_t = 32)]
        reference_frames: u32,
        /// Timed renders per point (after a warm-up); the median is reported.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// ReSTIR's frames with a still camera, the last measured (its temporal history).
        #[arg(long, default_value_t = 8)]
        frames: u32,
        /// Where to write restir.json and the chart.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// The path tracer's light sampling by RIS (at every vertex) against power sampling on a
    /// many-light scene: error of the whole image (direct and indirect light) against time, and
    /// the equal-error speed-up.
    RestirPt {
        /// The scene (default: scenes/many-lights.glb).
        #[arg(long, default_value = "scenes/many-lights.glb")]
        scene: PathBuf,
        /// Image size.
        #[arg(long, default_value = "64x64", value_parser = cli::parse_size)]
        size: (u32, u32),
        /// Samples per pixel of the reference (power sampling).
        #[arg(long, default_value_t = 1024)]
        reference_spp: u32,
        /// Scattering events per path.
        #[arg(long, default_value_t = 4)]
        max_bounces: u32,
        /// Timed renders per point (after a warm-up), each with its own seed: the median time and
        /// the mean error are reported.
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Where to write restir-pt.json and the chart.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Print the Markdown table of an earlier run's JSON and exit (nothing is rendered).
        #[arg(long)]
        table: Option<PathBuf>,
    },
    /// Print the Markdown table of a `peers.py` run's JSON: `peers.json` (umbra's rays against
    /// Embree's) or `path.json` (the path tracer against Mitsuba 3 at equal error). The
    /// measurements are `src/bin/umbra-bench/peers.py`'s (Python, Embree, Mitsuba).
    Peers {
        /// The JSON file.
        #[arg(long)]
        table: PathBuf,
    },
}

fn main() {
    START_LOAD.get_or_init(load_average);
    cli::main(|| run(Cli::parse()));
}

/// The machine's 1-minute load average when this process started (its other work; a run's own
/// threads add to it afterwards).
static START_LOAD: std::sync::OnceLock<Option<f64>> = std::sync::OnceLock::new();

/// The 1-minute load average from `/proc/loadavg`; `None` where there is no procfs.
fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg").ok()?.split_whitespace().next()?.parse().ok()
}

/// A JSON number as f64 (NaN where absent), for the `--table` printers.
fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// Adds the conditions of this run to its JSON: lavapipe's thread count (`LP_NUM_THREADS`, unset:
/// one per core), the load average when the run started and the process's nice value (on a
/// shared machine a niced run yields to the others, and its wall-clock timings with it).
fn add_conditions(doc: &mut Value) {
    doc["lp_num_threads"] = json!(std::env::var("LP_NUM_THREADS").ok());
    doc["load_average_at_start"] = json!(START_LOAD.get().copied().flatten());
    doc["nice"] = json!(nice_value());
}

/// This process's nice value from `/proc/self/stat` (field 19); `None` where there is no procfs.
fn nice_value() -> Option<i64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name start at field 3 (the state).
    stat.rsplit_once(')')?.1.split_whitespace().nth(19 - 3)?.parse().ok()
}

/// The conditions [`add_conditions`] recorded, for a table's caption.
fn conditions_text(doc: &Value) -> String {
    format!("LP_NUM_THREADS {}, {}", doc["lp_num_threads"].as_str().unwrap_or("unset"), load_text(doc))
}

/// The load average a run started under and its nice value, in words.
fn load_text(doc: &Value) -> String {
    let load = doc["load_average_at_start"]
        .as_f64()
        .map_or("load not recorded".into(), |load| format!("load average {load:.2} at the start"));
    match doc["nice"].as_i64() {
        Some(nice) if nice != 0 => format!("{load}, nice {nice}"),
        _ => load,
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Rays { table: Some(path), .. } => print!("{}", rays::table(&read_json(&path)?)),
        Command::Rays {
            quick,
            size,
            repeats,
            sweep,
            gltf,
            out,
            row_order,
            no_terrain,
            dump,
            table: None,
        } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let device = ctx.info().name.clone();
            let (scenes, settings) = if quick {
                (
                    vec![scenes::terrain_scene("terrain", 177)],
                    RaySettings {
                        size: (128, 128),
                        repeats: 3,
                        builds: 1,
                        sweep: true,
                        row_order,
                        dump: dump.clone(),
                    },
                )
            } else {
                (
                    vec![scenes::terrain_scene("terrain", 351), scenes::terrain_scene("terrain", 704)],
                    RaySettings { size, repeats, builds: 5, sweep, row_order, dump: dump.clone() },
                )
            };
            let mut scenes = if no_terrain { Vec::new() } else { scenes };
            for path in &gltf {
                scenes.push(scenes::gltf_scene(path)?);
            }
            let mut reports = Vec::new();
            for scene in &scenes {
                log::info!("{}: building and validating", scene.name);
                let report = rays::run(&ctx, scene, &settings).with_context(|| scene.name.clone())?;
                print_report(&report);
                reports.push(report);
            }
            let doc = rays::to_json(&device, &settings, &reports);
            print!("\n{}", rays::table(&doc));
            write_json(&out, "rays.json", &doc)?;
        }
        Command::Build { table: Some(path), .. } => print!("{}", build::table(&read_json(&path)?)),
        Command::Build { terrain, gltf, builds, sweep, out, table: None } => {
            let mut scenes: Vec<RayScene> =
                terrain.iter().map(|&n| scenes::terrain_scene("terrain", n)).collect();
            for path in &gltf {
                scenes.push(scenes::gltf_scene(path)?);
            }
            println!("{} rayon threads", rayon::current_num_threads());
            let mut rows = Vec::new();
            for scene in &scenes {
                let row = build::run(scene, builds, sweep)?;
                build::print(&row);
                rows.push(row);
            }
            write_json(&out, "build.json", &build::to_json(builds, &rows))?;
        }
        Command::Passes { table, .. } if !table.is_empty() => {
            let docs = table.iter().map(|path| read_json(path)).collect::<Result<Vec<_>>>()?;
            print!("{}", passes::table(&docs)?);
        }
        Command::Passes { scene, size, repeats, shadow_rays, out, table: _, ao, gbuffer } => {
            let variants: Vec<passes::FrameVariant> = gbuffer
                .iter()
                .flat_map(|&gbuffer| ao.iter().map(move |&ao| passes::FrameVariant { gbuffer, ao }))
                .collect();
            passes::run_passes(scene, size, repeats, shadow_rays, out, &variants)?
        }
        Command::Implicit { table: Some(path), .. } => print!("{}", implicit::table(&read_json(&path)?)),
        Command::Implicit { size, spp, repeats, rays, subdivisions, out, table: None } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let settings = implicit::ImplicitSettings { size, spp, repeats, rays, subdivisions };
            let rows = implicit::run(&ctx, &settings)?;
            let doc = implicit::to_json(&ctx.info().name, &settings, &rows);
            print!("{}", implicit::table(&doc));
            write_json(&out, "implicit.json", &doc)?;
            implicit::write_chart(&out, &rows)?;
        }
        Command::Animation { table: Some(path), .. } => print!("{}", animation::table(&read_json(&path)?)),
        Command::Animation { scene, size, spp, frames, repeats, out, table: None } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let settings = animation::AnimationBench { size, spp, frames, repeats };
            let mut doc = animation::run(&ctx, &scene, &settings)?;
            add_conditions(&mut doc);
            print!("{}", animation::table(&doc));
            write_json(&out, "animation.json", &doc)?;
        }
        Command::Antialias { table: Some(path), redraw, out, .. } => {
            let doc = read_json(&path)?;
            print!("{}", antialias::table(&doc));
            if redraw {
                let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
                umbra::atomic::create_dir(&out)?;
                antialias::write_chart(&out, stem.trim_start_matches("antialias-"), &doc)?;
            }
        }
        Command::Antialias {
            scene,
            env,
            env_color,
            size,
            reference_spp,
            samples,
            taa_frames,
            repeats,
            out,
            table: None,
            redraw: _,
        } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let mut loaded = umbra::scene::Scene::load(&scene)?;
            if loaded.animation.is_some() {
                let animations = umbra::scene::AnimationSelect::All;
                loaded.pose(&umbra::scene::PoseAt { time: antialias::ANIMATION_END, animations })?;
            }
            let mut gpu_scene = umbra::gpu::scene::GpuScene::upload(&ctx, &loaded)?;
            let env = match &env {
                Some(path) => {
                    gpu_scene.set_environment(&ctx, &umbra::environment::EnvironmentMap::load(path)?)?;
                    [1.0; 3]
                }
                None => env_color,
            };
            let mut renderer = umbra::embed::Renderer::with_gpu_scene(&ctx, gpu_scene)?;
            let settings =
                antialias::AntialiasBench { size, reference_spp, samples, taa_frames, repeats, env };
            let mut doc = antialias::run(&ctx, &mut renderer, &mut loaded, &settings)?;
            add_conditions(&mut doc);
            print!("{}", antialias::table(&doc));
            let stem = scene.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            write_json(&out, &format!("antialias-{stem}.json"), &doc)?;
            antialias::write_chart(&out, &stem, &doc)?;
        }
        Command::Restir { table: Some(path), .. } => print!("{}", restir::table(&read_json(&path)?)),
        Command::Restir { scene, size, reference_frames, repeats, frames, out, table: None } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let loaded = umbra::scene::Scene::load(&scene)?;
            let camera = loaded.camera(None)?;
            let settings = restir::RestirBench { size, reference_frames, repeats, frames };
            let (points, floor) = restir::run(&ctx, &loaded, &camera, &settings)?;
            let mut doc = restir::to_json(&ctx.info().name, &loaded.name, &settings, &points, floor);
            add_conditions(&mut doc);
            print!("{}", restir::table(&doc));
            write_json(&out, "restir.json", &doc)?;
            restir::write_chart(&out, &doc)?;
        }
        Command::RestirPt { table: Some(path), .. } => print!("{}", restir_pt::table(&read_json(&path)?)),
        Command::RestirPt { scene, size, reference_spp, max_bounces, repeats, out, table: None } => {
            let ctx = Context::new(&ContextDesc::default())?;
            let loaded = umbra::scene::Scene::load(&scene)?;
            let camera = loaded.camera(None)?;
            let settings = restir_pt::RestirPtBench { size, reference_spp, max_bounces, repeats };
            let (points, floor) = restir_pt::run(&ctx, &loaded, &camera, &settings)?;
            let mut doc = restir_pt::to_json(&ctx.info().name, &loaded.name, &settings, &points, floor);
            add_conditions(&mut doc);
            print!("{}", restir_pt::table(&doc));
            write_json(&out, "restir-pt.json", &doc)?;
            restir_pt::write_chart(&out, &doc)?;
        }
        Command::Peers { table } => print!("{}", peers::table(&read_json(&table)?)),
        Command::Shadows {
            scene,
            size,
            map_size,
            cascades,
            sun,
            light_radius,
            sun_angle,
            max_radius,
            no_view_marks,
            repeats,
            out,
            table,
        } => match table {
            Some(path) => print!("{}", shadows::table(&read_json(&path)?)),
            None => {
                let settings = umbra::passes::shadow::ShadowSettings {
                    map_size,
                    cascades,
                    light_radius,
                    sun_angle: sun_angle.to_radians(),
                    max_radius,
                    view_marks: !no_view_marks,
                    ..Default::default()
                };
                shadows::run_shadows(scene, size, &settings, sun, repeats, out)?
            }
        },
        Command::Denoise {
            quick,
            size,
            reference_spp,
            max_spp,
            repeats,
            env_color,
            iterations,
            sigma_luminance,
            prefilter,
            albedo_offset,
            wide,
            spatial_variance,
            lobe_split,
            specular_iterations,
            gltf,
            out,
            table,
        } => match table {
            Some(path) => print!("{}", denoise::table(&read_json(&path)?)),
            None => {
                let (size, reference_spp, max_spp) =
                    if quick { ((64, 64), 256, 32) } else { (size, reference_spp, max_spp) };
                let settings = suite::SuiteSettings {
                    size,
                    reference_spp,
                    max_spp,
                    shadow_rays: vec![],
                    shadow_map_sizes: vec![],
                    hybrid_samples: vec![],
                    probes_per_side: vec![],
                    ssao_samples: vec![],
                    gtao_slices: vec![],
                    rtao_rays: vec![],
                    ao_reference_rays: 0,
                    ao_radius: 0.5,
                    repeats,
                    env: env_color,
                    out,
                };
                let filter = umbra::render::DenoiseSettings {
                    iterations,
                    sigma_luminance,
                    prefilter_variance: prefilter,
                    albedo_offset,
                    wide,
                    spatial_variance,
                    lobe_split,
                    specular_iterations,
                    ..Default::default()
                };
                filter.validate()?;
                denoise::run_denoise(&settings, &filter, quick, &gltf)?
            }
        },
        Command::Temporal { table: Some(path), .. } => print!("{}", temporal::table(&read_json(&path)?)),
        Command::Temporal {
            size,
            frames,
            pan,
            reference_spp,
            repeats,
            timing_only,
            dump,
            out,
            table: None,
        } => {
            let mut doc =
                temporal::run(size, frames, pan, reference_spp, repeats, timing_only, dump.as_deref())?;
            add_conditions(&mut doc);
            print!("{}", temporal::table(&doc));
            write_json(&out, "temporal.json", &doc)?;
        }
        Command::Probes {
            sponza,
            gltf,
            size,
            reference_spp,
            per_side,
            lightmap_sizes,
            repeats,
            env_color,
            out,
            table,
        } => match table {
            Some(path) => print!("{}", probes::table(&read_json(&path)?)),
            None => {
                let settings = suite::SuiteSettings {
                    size,
                    reference_spp,
                    max_spp: 1,
                    shadow_rays: vec![4],
                    shadow_map_sizes: vec![],
                    hybrid_samples: vec![],
                    probes_per_side: per_side,
                    ssao_samples: vec![16],
                    gtao_slices: vec![],
                    rtao_rays: vec![],
                    ao_reference_rays: 0,
                    ao_radius: 0.5,
                    repeats,
                    env: env_color,
                    out,
                };
                probes::run_probes(&settings, sponza.as_deref(), &gltf, &lightmap_sizes)?
            }
        },
        Command::Paths {
            scenes,
            assets,
            size,
            spp,
            repeats,
            max_bounces,
            rr_depth,
            env_color,
            env,
            integrator,
            lanes,
            out,
            table,
        } => match table {
            Some(path) => print!("{}", paths::table(&read_json(&path)?)),
            None => {
                let ctx = Context::new(&ContextDesc::default())?;
                let settings = paths::PathsSettings {
                    size,
                    spp,
                    repeats,
                    max_bounces,
                    rr_depth,
                    env: env_color,
                    env_map: env,
                    integrators: integrator.clone(),
                    lanes,
                };
                let scenes = if scenes.is_empty() {
                    scenes::default_path_scenes(scenes::external(assets, "").as_deref())?
                } else {
                    scenes::named_path_scenes(&scenes)?
                };
                let rows = paths::run(&ctx, &scenes, &settings)?;
                let doc = paths::to_json(&ctx.info().name, ctx.info().subgroup_size, &settings, &rows);
                print!("{}", paths::table(&doc));
                write_json(&out, "paths.json", &doc)?;
            }
        },
        Command::Pipelines { scenes, assets, repeats, out, table } => match table {
            Some(path) => print!("{}", pipelines::table(&read_json(&path)?)),
            None => {
                let ctx = Context::new(&ContextDesc::default())?;
                let scenes = if scenes.is_empty() {
                    let mut set = vec![("cornell-box".to_string(), umbra::scene::Scene::cornell_box())];
                    set.extend(scenes::load_gltf(&[PathBuf::from("scenes/many-lights.glb")])?);
                    match scenes::external(assets, "DamagedHelmet/DamagedHelmet.glb") {
                        Some(helmet) => set.extend(scenes::load_gltf(&[helmet])?),
                        None => log::warn!("DamagedHelmet left out: give --assets DIR or set UMBRA_ASSETS"),
                    }
                    set
                } else {
                    scenes::load_gltf(&scenes)?
                };
                let rows = pipelines::run(&ctx, &scenes, repeats)?;
                let doc = pipelines::to_json(&ctx.info().name, repeats, &rows);
                print!("{}", pipelines::table(&doc));
                write_json(&out, "pipelines.json", &doc)?;
            }
        },
        Command::Mis { references, reference_dir, spp, seeds, out, table } => match table {
            Some(path) => print!("{}", mis::table(&read_json(&path)?)),
            None => {
                let ctx = Context::new(&ContextDesc::default())?;
                let measurements = mis::run(&ctx, &reference_dir, &references, spp, seeds)?;
                let doc = mis::to_json(&ctx.info().name, spp, seeds, &measurements);
                print!("{}", mis::table(&doc));
                write_json(&out, "mis.json", &doc)?;
            }
        },
        Command::Suite {
            quick,
            size,
            reference_spp,
            max_spp,
            shadow_rays,
            repeats,
            env_color,
            ao_radius,
            gltf,
            sponza,
            only,
            out,
            table,
            redraw,
        } => {
            if let Some(path) = table {
                print!("{}", suite::table(&read_json(&path)?));
                return Ok(());
            }
            if let Some(path) = redraw {
                let stems = suite::redraw(&path, &out, ao_radius)?;
                println!(
                    "redrew {} charts of {} in {} (.svg, .png)",
                    stems.len(),
                    path.display(),
                    out.display()
                );
                return Ok(());
            }
            let settings = if quick {
                suite::SuiteSettings {
                    size: (64, 64),
                    reference_spp: 256,
                    max_spp: 32,
                    shadow_rays: vec![1, 4, 16],
                    shadow_map_sizes: vec![128, 512],
                    hybrid_samples: vec![4],
                    probes_per_side: vec![4, 8],
                    ssao_samples: vec![4, 16],
                    gtao_slices: vec![1, 3],
                    rtao_rays: vec![1, 4, 16],
                    ao_reference_rays: 256,
                    ao_radius,
                    repeats: 3,
                    env: env_color,
                    out,
                }
            } else {
                suite::SuiteSettings {
                    size,
                    reference_spp,
                    max_spp,
                    shadow_rays,
                    shadow_map_sizes: vec![128, 256, 512, 1024, 2048],
                    hybrid_samples: vec![1, 2, 4, 8, 16],
                    probes_per_side: vec![4, 8, 16],
                    ssao_samples: vec![4, 8, 16, 32],
                    gtao_slices: vec![1, 2, 3, 4],
                    rtao_rays: vec![1, 2, 4, 8, 16, 32, 64],
                    ao_reference_rays: 1024,
                    ao_radius,
                    repeats,
                    env: env_color,
                    out,
                }
            };
            suite::run_suite(&settings, quick, &gltf, sponza.as_deref(), &only)?
        }
    }
    Ok(())
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg:28} {bar:40} {pos}/{len}  ETA {eta}") {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar
}

/// An earlier run's JSON (for `--table`).
fn read_json(path: &std::path::Path) -> Result<serde_json::Value> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
}

/// Writes `doc` to `out/name` (creating `out`) and says so.
fn write_json(out: &std::path::Path, name: &str, doc: &serde_json::Value) -> Result<()> {
    umbra::atomic::create_dir(out)?;
    let path = out.join(name);
    umbra::atomic::write(&path, serde_json::to_string_pretty(doc)?.as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}

fn print_report(r: &RayReport) {
    println!("\n{}", r.scene);
    let b = &r.binned;
    println!(
        "  binned SAH build: {:.1} ms (median), {} references, SAH cost {:.2}, {} nodes, {} leaves (mean {:.2}, max {}), depth {}",
        r.binned_build_ms_median,
        b.references,
        b.sah_cost,
        b.nodes,
        b.leaves,
        b.mean_leaf_size,
        b.max_leaf_size,
        b.depth
    );
    if let Some(s) = &r.sweep {
        println!(
            "  full-sweep SAH:   {:.1} ms, SAH cost {:.2} (binned is {:+.2} %)",
            s.build_ms,
            s.sah_cost,
            100.0 * (b.sah_cost / s.sah_cost - 1.0)
        );
    }
    for (kind, n, ms, mrays) in &r.kinds {
        println!("  {kind:8} {n:>8} rays  {ms:9.3} ms  {mrays:8.2} Mrays/s");
    }
}
