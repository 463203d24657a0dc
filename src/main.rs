//! The `umbra` command-line renderer.

mod args;
mod cli;

use anyhow::{Context as _, Result};
use args::*;
use umbra::gpu::scene::{GpuScene, SceneBvh};
use umbra::passes::deferred::LightingSettings;
use umbra::passes::pathtrace::{EmitterSampling, RisReuse, Sampler};
use umbra::passes::probes::{ProbeSettings, ProbeVolume};
use umbra::render::{DenoiseSettings, Passes};
use umbra::vk::{self, raw, Context, ContextDesc, GpuTimer, Image};

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

/// `--frames A..B`: one render per frame, the scene posed at frame / fps seconds, each written
/// to the outputs with the frame number in their printf field.
fn render_frames(args: RenderArgs, (first, end): (u32, u32)) -> Result<()> {
    let frame_path = |pattern: &std::path::Path, flag: &str, frame: u32| -> Result<std::path::PathBuf> {
        let text = pattern.to_string_lossy();
        let field = frame_field(&text).ok_or_else(|| {
            anyhow::anyhow!(
                "{flag} {text}: --frames needs a frame number field in the name, such as frame-%04d.png"
            )
        })?;
        let (start, len, width) = field;
        let number = format!("{frame:0width$}");
        Ok(format!("{}{number}{}", &text[..start], &text[start + len..]).into())
    };
    // Checked before the first frame renders.
    frame_path(&args.output, "-o", first)?;
    if let Some(exr) = &args.exr {
        frame_path(exr, "--exr", first)?;
    }
    let bar = indicatif::ProgressBar::new((end - first) as u64).with_style(
        indicatif::ProgressStyle::with_template("frames {bar:40} {pos}/{len}  ETA {eta}")
            .expect("valid template"),
    );
    // The device, the loaded file and the GPU scene with its kernels carry from frame to frame.
    let mut reuse = None;
    for frame in first..end {
        let mut one = args.clone();
        one.frames = None;
        one.scene.time = Some(frame as f32 / args.fps);
        one.output = frame_path(&args.output, "-o", frame)?;
        one.exr = args.exr.as_deref().map(|e| frame_path(e, "--exr", frame)).transpose()?;
        bar.suspend(|| render_with(one, &mut reuse))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!("rendered frames {first}..{end} at {} fps", args.fps);
    Ok(())
}

/// The printf field of a frame pattern (`%d` or `%0Nd`): its byte offset, length and width.
fn frame_field(text: &str) -> Option<(usize, usize, usize)> {
    let start = text.find('%')?;
    let rest = &text[start + 1..];
    let digits = rest.find('d')?;
    let spec = &rest[..digits];
    if !spec.chars().all(|c| c.is_ascii_digit()) {
        return None;
    }
    let width = if spec.is_empty() { 0 } else { spec.trim_start_matches('0').parse().unwrap_or(0) };
    Some((start, digits + 2, width))
}

fn render(args: RenderArgs) -> Result<()> {
    render_with(args, &mut None)
}

/// What `--frames` keeps from one frame's render to the next: the device, the loaded scene
/// (posed anew each frame, [`umbra::scene::Scene::pose`]) and the GPU scene with its kernels
/// (its BVH refitted or rebuilt, `--bvh`).
struct Reuse {
    ctx: Context,
    loaded: LoadedScene,
    gpu: Option<(Passes, GpuScene)>,
}

/// One render; with `reuse`, of a scene already loaded (posed at `args.scene.time`) on a device
/// and GPU scene already made, which it fills at the first frame.
fn render_with(args: RenderArgs, reuse: &mut Option<Reuse>) -> Result<()> {
    if args.direct == Direct::Restir && args.mode != Mode::Hybrid {
        anyhow::bail!("--direct restir applies to --mode hybrid (the path tracer's is --direct ris)");
    }
    if args.direct == Direct::Ris && args.mode != Mode::Pathtrace {
        anyhow::bail!("--direct ris applies to --mode pathtrace (the hybrid's is --direct restir)");
    }
    let denoise = DenoiseSettings { iterations: args.path.denoise_iterations, ..Default::default() };
    denoise.validate()?;
    if let (Some((a, b)), Some(n)) = (args.path.sample_range, args.path.spp) {
        if b > n {
            anyhow::bail!(
                "--sample-range {a}..{b} reaches past the render's --spp {n}: a part traces samples of \
                 the whole render's 0..{n}"
            );
        }
    }
    args.shadow_settings().validate()?;
    let (png, exr) = cli::outputs(&args.output, args.exr.as_ref());
    let probes_file = match &args.hybrid.probes {
        Some(ProbesArg::File(path)) => Some(path.as_path()),
        _ => None,
    };
    let label = if png.is_some() { "--exr" } else { "-o" };
    cli::check_outputs(
        &[("-o", png.as_deref()), (label, exr.as_deref())],
        &[args.scene.inputs().as_slice(), &[("--probes", probes_file)]].concat(),
    )?;
    let mut stages = Stages::start();
    match reuse {
        // A still scene (no animations: `SceneArgs::load` warned) renders the same every frame.
        Some(r) if r.loaded.scene.animation.is_some() => {
            let at = args.scene.pose().expect("--frames sets the time");
            r.loaded.scene.pose(&at)?;
            stages.lap("pose");
        }
        Some(_) => {}
        None => {
            let loaded = args.scene.load()?;
            stages.lap("load");
            let ctx = Context::new(&ContextDesc::default())?;
            stages.lap("device");
            *reuse = Some(Reuse { ctx, loaded, gpu: None });
        }
    }
    let Reuse { ctx, loaded, gpu } = reuse.as_mut().expect("made above");
    if args.lightmap.unwrap {
        umbra::passes::lightmap::unwrap_triangles(&mut loaded.scene, args.lightmap.lightmap_size);
    }
    let camera = loaded.scene.camera(args.camera)?;
    let ctx = &*ctx;
    let loaded = &*loaded;
    let planned_spp = args.path.spp.unwrap_or(64);
    let (first_sample, spp) = args.path.sample_range.map_or((0, planned_spp), |(a, b)| (a, b - a));
    let settings = umbra::render::PathSettings {
        size: args.path.tile.map_or(args.size, |t| (t[2], t[3])),
        spp,
        first_sample,
        tile: args
            .path
            .tile
            .map(|t| umbra::passes::pathtrace::Tile { image: args.size, origin: (t[0], t[1]) }),
        max_bounces: args.path.max_bounces,
        rr_depth: args.path.rr_depth,
        seed: args.seed,
        sampler: args.path.sampler,
        emitter_sampling: args.path.emitter_sampling,
        microfacet: args.path.microfacet,
        heuristic: args.path.heuristic,
        strategy: args.path.strategy,
        direct: match args.direct {
            Direct::Ris => umbra::passes::pathtrace::DirectSampling::Ris(args.ris.ris_candidates),
            _ => umbra::passes::pathtrace::DirectSampling::Power,
        },
        ris_reuse: args.ris.ris_reuse,
        env: args.scene.env_radiance(),
        env_nee: true,
        target_error: args.path.target_error,
        integrator: args.path.integrator,
        // The denoiser filters the diffuse and specular parts apart (either integrator splits
        // them).
        lobe_split: args.path.denoise,
    };
    let hybrid = args.hybrid_settings();
    let prepare = |passes: &Passes| match args.mode {
        Mode::Ao | Mode::Rtao => Ok(()),
        Mode::Hybrid => passes.prepare_hybrid(&hybrid, args.hybrid.probes.is_some(), args.hybrid.lightmaps),
        Mode::Pathtrace => passes.prepare_path_trace(&settings),
    };
    let (passes, gpu_scene) = match gpu {
        // A still scene's GPU scene stands as it is.
        Some((passes, gpu_scene)) if loaded.scene.animation.is_none() => (&*passes, &*gpu_scene),
        Some((passes, gpu_scene)) => {
            gpu_scene.update_geometry(ctx, &loaded.scene, args.bvh)?;
            stages.lap(match args.bvh {
                umbra::gpu::scene::BvhUpdate::Refit => "BVH refit and upload",
                umbra::gpu::scene::BvhUpdate::Rebuild => "BVH rebuild and upload",
            });
            let ms = gpu_scene.bvh_stats.build_ms;
            log::info!("{}: BVH {:?} in {ms:.2} ms", loaded.scene.name, args.bvh);
            if let Some(moved) = passes.for_moved(gpu_scene) {
                *passes = moved;
                prepare(passes)?;
                stages.lap("pipelines");
            }
            (&*passes, &*gpu_scene)
        }
        None => {
            let made = upload_alongside(ctx, loaded, &mut stages, prepare)?;
            let (passes, gpu_scene) = gpu.insert(made);
            (&*passes, &*gpu_scene)
        }
    };
    if matches!(args.mode, Mode::Ao | Mode::Rtao) {
        return render_ao(ctx, gpu_scene, &camera, &args);
    }
    if args.mode == Mode::Hybrid {
        return render_hybrid(ctx, passes, loaded, gpu_scene, &camera, &hybrid, &args);
    }
    let bar = indicatif::ProgressBar::new(settings.spp as u64).with_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {per_sec}  ETA {eta}")
            .expect("valid template"),
    );
    let start = std::time::Instant::now();
    let image = passes.path_trace(gpu_scene, &camera, &settings, |done, _| bar.set_position(done as u64))?;
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
    let shown = if args.path.denoise {
        let denoised = umbra::render::denoise(ctx, &image, &denoise)?;
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
    let display = umbra::color::to_display8(&rgba, args.display.exposure.exp2(), args.display.tonemap);
    if let Some(png) = png {
        umbra::output::write_png(&png, w, h, &display)?;
        println!("wrote {}", png.display());
    }
    stages.lap("PNG");
    if let Some(path) = &exr {
        let mut exr = umbra::merge::PathExr::new(&image, &settings, render_identity(&args, loaded));
        if args.path.sample_range.is_some() {
            exr.planned_spp = Some(planned_spp);
        }
        if args.path.denoise {
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
        args.path.max_bounces,
        args.path.rr_depth,
        args.seed,
        name(&args.path.microfacet),
        name(&args.path.heuristic),
        name(&args.path.strategy)
    ) + &match args.direct {
        // (Only RIS adds to it: renders made before it existed merge with today's.)
        Direct::Ris => format!(" direct ris {}", args.ris.ris_candidates)
            + match args.ris.ris_reuse {
                RisReuse::Off => "",
                RisReuse::Samples => " reuse samples",
                RisReuse::Spatial => " reuse spatial",
                RisReuse::Both => " reuse both",
            },
        _ => String::new(),
    } + match args.path.sampler {
        // (Only independent numbers add to it, as RIS does.)
        Sampler::Independent => " sampler independent",
        Sampler::LowDiscrepancy => "",
    } + match args.path.emitter_sampling {
        // (The same samples in expectation, not the same numbers: parts must agree.)
        EmitterSampling::SolidAngle => " emitter-sampling solid-angle",
        EmitterSampling::Area => "",
    }
}

/// `umbra info SCENE --json`.
fn info_json(info: &umbra::scene::info::SceneInfo) -> serde_json::Value {
    use serde_json::json;
    let loaded = match &info.loaded {
        Ok(l) => json!({
            "triangles": l.stats.triangles,
            "vertices": l.stats.vertices,
            "instances": l.stats.instances,
            "degenerate_triangles": l.stats.degenerate_triangles,
            "implicit_shapes": l.implicit_shapes,
            "bounds": {"min": l.bounds.0, "max": l.bounds.1},
            "warnings": l.warnings,
        }),
        Err(reason) => json!({"refused": reason}),
    };
    json!({
        "file": info.file,
        "container": info.container,
        "generator": info.generator,
        "extensions": info.extensions.iter().map(|e| json!({
            "name": e.name, "required": e.required, "umbra": e.status.name()
        })).collect::<Vec<_>>(),
        "nodes": info.nodes,
        "meshes": info.meshes,
        "primitives": info.primitives,
        "materials": info.materials.iter().map(|m| json!({"name": m.name, "extensions": m.extensions})).collect::<Vec<_>>(),
        "images": info.images.iter().map(|i| json!({
            "name": i.name, "format": i.format, "size": i.size.map(|(w, h)| [w, h])
        })).collect::<Vec<_>>(),
        "cameras": info.cameras,
        "lights": info.lights.iter().map(|(kind, name)| json!({"type": kind, "name": name})).collect::<Vec<_>>(),
        "variants": info.variants,
        "animations": info.animations.iter().map(|a| json!({
            "name": a.name, "channels": a.channels, "duration": a.duration
        })).collect::<Vec<_>>(),
        "skins": info.skins,
        "morphed_meshes": info.morphed_meshes,
        "loaded": loaded,
    })
}

/// `umbra info SCENE`: the same as text.
fn info_text(info: &umbra::scene::info::SceneInfo) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let named = |name: &str, i: usize| if name.is_empty() { format!("#{i}") } else { format!("'{name}'") };
    let _ = writeln!(
        out,
        "{} ({}{})",
        info.file,
        info.container,
        info.generator.as_ref().map_or(String::new(), |g| format!(", by {g}"))
    );
    match &info.loaded {
        Ok(l) => {
            let _ = writeln!(
                out,
                "{} triangles, {} vertices, {} placed instances of {} meshes ({} primitives), {} nodes{}",
                l.stats.triangles,
                l.stats.vertices,
                l.stats.instances,
                info.meshes,
                info.primitives,
                info.nodes,
                if l.implicit_shapes > 0 {
                    format!(", {} implicit shapes", l.implicit_shapes)
                } else {
                    String::new()
                }
            );
            let _ = writeln!(out, "bounds {:?} to {:?}", l.bounds.0, l.bounds.1);
        }
        Err(reason) => {
            let _ = writeln!(out, "REFUSED: {reason}");
            let _ = writeln!(
                out,
                "{} meshes ({} primitives), {} nodes",
                info.meshes, info.primitives, info.nodes
            );
        }
    }
    for e in &info.extensions {
        let _ = writeln!(
            out,
            "extension {}{}: {}",
            e.name,
            if e.required { " (required)" } else { "" },
            e.status.name()
        );
    }
    let _ = writeln!(out, "{} materials", info.materials.len());
    for (i, m) in info.materials.iter().enumerate() {
        let ext =
            if m.extensions.is_empty() { String::new() } else { format!(": {}", m.extensions.join(", ")) };
        let _ = writeln!(out, "  {}{ext}", named(&m.name, i));
    }
    let _ = writeln!(out, "{} images", info.images.len());
    for i in &info.images {
        let size = i.size.map_or("not decoded".to_owned(), |(w, h)| format!("{w}x{h}"));
        let _ = writeln!(out, "  {} ({}) {size}", i.name, if i.format.is_empty() { "?" } else { &i.format });
    }
    let _ = writeln!(
        out,
        "cameras: {}",
        if info.cameras.is_empty() {
            "none (umbra frames the bounds)".into()
        } else {
            info.cameras.join(", ")
        }
    );
    let lights: Vec<String> = info
        .lights
        .iter()
        .map(|(k, n)| if n.is_empty() { k.clone() } else { format!("{k} '{n}'") })
        .collect();
    let _ = writeln!(out, "lights: {}", if lights.is_empty() { "none".into() } else { lights.join(", ") });
    if !info.variants.is_empty() {
        let _ = writeln!(out, "variants (--variant NAME): {}", info.variants.join(", "));
    }
    for (i, a) in info.animations.iter().enumerate() {
        let _ =
            writeln!(out, "animation {}: {} channels, {:.3} s", named(&a.name, i), a.channels, a.duration);
    }
    if info.skins > 0 || info.morphed_meshes > 0 {
        let _ = writeln!(out, "{} skins, {} meshes with morph targets", info.skins, info.morphed_meshes);
    }
    if let Ok(l) = &info.loaded {
        for w in &l.warnings {
            let _ = writeln!(out, "warning: {w}");
        }
    }
    out
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
    /// The pose `--time` and `--animation` ask for.
    fn pose(&self) -> Option<umbra::scene::PoseAt> {
        use umbra::scene::{AnimationSelect, PoseAt};
        self.time.map(|time| PoseAt {
            time,
            animations: match &self.animation {
                None => AnimationSelect::All,
                Some(a) => {
                    a.parse().map_or_else(|_| AnimationSelect::Name(a.clone()), AnimationSelect::Index)
                }
            },
        })
    }

    fn load(&self) -> Result<LoadedScene> {
        use umbra::scene::LoadOptions;
        let pose = self.pose();
        let mut scene = match &self.scene {
            Some(path) => {
                let options = LoadOptions { missing_textures: self.missing_textures, pose };
                umbra::scene::Scene::load_with(path, &options)?
            }
            None if pose.is_some() => anyhow::bail!("--time: the embedded Cornell box has no animations"),
            None => umbra::scene::Scene::cornell_box(),
        };
        if self.time.is_some() && scene.animation.is_none() {
            log::warn!("{}: the file has no animations: --time and --frames pose nothing", scene.name);
        }
        if let Some(name) = &self.variant {
            let index = scene.variant_index(name)?;
            scene.select_variant(Some(index))?;
            log::info!("{}: variant '{name}'", scene.name);
        }
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

/// Builds the BVH, then uploads the rest of `loaded` while `prepare` makes pipelines on a thread
/// (up to a second each on lavapipe) for the features the scene has (the BVH tells its stack
/// depth, which the kernels' walk is specialised on); the passes for the uploaded scene (made again
/// if its features differ: `tests/scene/` checks that they do not).
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

fn render_hybrid(
    ctx: &Context,
    passes: &Passes,
    loaded: &LoadedScene,
    scene: &GpuScene,
    camera: &umbra::scene::Camera,
    settings: &umbra::render::HybridSettings,
    args: &RenderArgs,
) -> Result<()> {
    let probes = match &args.hybrid.probes {
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
    let lightmaps = match args.hybrid.lightmaps {
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
    let settings = args.ao_settings();
    let name = settings.method.name();
    let image = umbra::render::ambient_occlusion(ctx, scene, camera, args.size, &settings)?;
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
        let mut layers = vec![
            Layer { name: "", channels: &["Y"], data: &image.values },
            Layer { name: "depth", channels: &["Z"], data: &image.gbuffer.depth },
        ];
        // Half-resolution AO's texels are not the image's pixels: no such layer then.
        if image.ao_size == image.size {
            layers.insert(1, Layer { name: "unblurred", channels: &["Y"], data: &image.unblurred });
        }
        umbra::output::write_exr(&path, w as usize, h as usize, &layers)?;
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

fn run(cli: Cli, given: &[String]) -> Result<()> {
    match cli.command {
        Command::Render(args) => {
            cli::refuse_inapplicable(given, &render_flag_groups(&args))?;
            match args.frames {
                Some(frames) => render_frames(args, frames)?,
                None => render(args)?,
            }
        }
        Command::Bake(args) => {
            let (probes, maps) = (args.output.is_some(), args.lightmaps.is_some() || args.ao_maps.is_some());
            let groups = [
                (cli::arg_ids::<ProbeArgs>(), probes, "a probe bake (-o FILE.probes)"),
                (cli::arg_ids::<LightmapArgs>(), maps, "--lightmaps DIR or --ao-maps DIR"),
                (vec!["occlusion_radius".into()], args.ao_maps.is_some(), "--ao-maps DIR"),
            ];
            cli::refuse_inapplicable(given, &groups)?;
            bake(args)?
        }
        Command::Merge(args) => merge(args)?,
        Command::Info { scene: Some(path), json } => {
            let info = umbra::scene::info::SceneInfo::read(&path, &Default::default())?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info_json(&info))?);
            } else {
                print!("{}", info_text(&info));
            }
        }
        Command::Info { scene: None, .. } => {
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
            ctx.record(|rec| {
                let cmd = rec.cmd();
                timer.reset(cmd);
                image.init_general(&ctx, cmd);
                timer.begin(cmd, "test_pattern")?;
                let params = umbra::gpu::layout::PatternParams { size: [w, h], seed: 0, frame: 0 };
                pipeline.record(
                    rec,
                    &test_pattern::Resources { out_image: &image.view },
                    &params,
                    [w, h, 1],
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
