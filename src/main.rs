//! The `umbra` command-line renderer.

use anyhow::{Context as _, Result};
use clap::{Parser, Subcommand};
use std::path::PathBuf;
use umbra::vk::{
    self, raw, ComputePipeline, Context, ContextDesc, Descriptor, GpuTimer, Image, PipelineDesc,
};

#[derive(Parser)]
#[command(name = "umbra", version, about = "Physically based rendering with Vulkan compute kernels")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the Vulkan devices and the one umbra would use.
    Info,
    /// Render the foundation test pattern (a known function of the pixel) to PNG and/or EXR.
    Pattern {
        /// Image size as WIDTHxHEIGHT.
        #[arg(long, default_value = "256x256", value_parser = umbra::cli::parse_size)]
        size: (u32, u32),
        /// PNG output path.
        #[arg(short, long, default_value = "pattern.png")]
        output: PathBuf,
        /// Optional EXR output path (linear values).
        #[arg(long)]
        exr: Option<PathBuf>,
    },
}

fn main() {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("info"))
        .format_timestamp(None)
        .init();
    if let Err(e) = run(Cli::parse()) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
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
            let ctx = Context::new(&ContextDesc::default())?;
            let image = Image::storage_2d(&ctx, "pattern", w, h, raw::Format::R32G32B32A32_SFLOAT)?;
            let pipeline = ComputePipeline::new(
                &ctx,
                "test_pattern",
                &PipelineDesc {
                    bindings: &[raw::DescriptorType::STORAGE_IMAGE],
                    push_constant_size: 16,
                    specialization: &[(0, 1)],
                },
            )?;
            let mut timer = GpuTimer::new(&ctx, 1)?;
            ctx.submit(|cmd| {
                timer.reset(cmd);
                image.init_general(&ctx, cmd);
                timer.begin(cmd, "test_pattern")?;
                pipeline.bind(cmd);
                pipeline.push_descriptors(cmd, &[Descriptor::StorageImage(&image)])?;
                pipeline.push_constants(
                    cmd,
                    &umbra::gpu::layout::PatternParams { size: [w, h], seed: 0, frame: 0 },
                )?;
                pipeline.dispatch(cmd, [w, h, 1], [8, 8, 1])?;
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
            umbra::output::write_png(&output, w, h, &umbra::output::to_srgb8(&rgba, 1.0))
                .with_context(|| format!("writing {}", output.display()))?;
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
