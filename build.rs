//! Compiles every `spirv/*.comp` kernel to SPIR-V 1.6 (Vulkan 1.3) with the vendored glslang and
//! embeds the words in the binary. A kernel error fails the build with `file:line: message`.

use glslang::include::{IncludeHandler, IncludeResult, IncludeType};
use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderSource, ShaderStage, SpirvVersion, Target, VulkanVersion,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Resolves `#include "x.glsl"` against the includer's folder, then `spirv/include/`.
struct Includes {
    include_dir: PathBuf,
    kernel_dir: PathBuf,
}

impl IncludeHandler for Includes {
    fn include(
        &mut self,
        _ty: IncludeType,
        header: &str,
        includer: &str,
        _depth: usize,
    ) -> Option<IncludeResult> {
        let includer_dir = Path::new(includer)
            .parent()
            .map(|p| self.kernel_dir.join(p))
            .unwrap_or_else(|| self.kernel_dir.clone());
        [includer_dir.join(header), self.include_dir.join(header)].into_iter().find(|p| p.is_file()).and_then(
            |path| {
                let data = std::fs::read_to_string(&path).ok()?;
                let name =
                    path.strip_prefix(&self.kernel_dir).unwrap_or(&path).to_string_lossy().into_owned();
                Some(IncludeResult { name, data })
            },
        )
    }
}

/// glslang names the top-level source `0`; name the kernel's file instead so every message
/// reads `spirv/x.comp:LINE: ...` or `spirv/include/y.glsl:LINE: ...`.
fn format_log(label: &str, log: &str) -> String {
    log.lines()
        .filter(|l| !l.trim().is_empty() && !l.contains("compilation errors.  No code generated"))
        .map(|line| {
            let body =
                line.strip_prefix("ERROR: ").or_else(|| line.strip_prefix("WARNING: ")).unwrap_or(line);
            let body = match body.strip_prefix("0:") {
                Some(rest) => format!("{label}:{rest}"),
                None if body.starts_with("include/") => format!("spirv/{body}"),
                None => body.to_string(),
            };
            body.trim().to_string()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Compiles `dir/file`; includes resolve against the includer's folder, then `include_dir`.
fn compile(compiler: &Compiler, dir: &Path, include_dir: &Path, file: &str) -> Result<Vec<u32>, String> {
    let folder = dir.file_name().map_or("spirv".into(), |f| f.to_string_lossy().into_owned());
    let label = format!("{folder}/{file}");
    let text = std::fs::read_to_string(dir.join(file)).map_err(|e| format!("{label}: {e}"))?;
    let source = ShaderSource::from(text);
    let options = CompilerOptions {
        target: Target::Vulkan { version: VulkanVersion::Vulkan1_3, spirv_version: SpirvVersion::SPIRV1_6 },
        ..CompilerOptions::default()
    };
    let mut includes = Includes { include_dir: include_dir.to_path_buf(), kernel_dir: dir.to_path_buf() };
    let input = ShaderInput::new(
        &source,
        ShaderStage::Compute,
        &options,
        None::<&[(&str, Option<&str>)]>,
        Some(&mut includes),
    )
    .map_err(|e| format!("{label}: {e}"))?;
    let describe = |e: glslang::error::GlslangError| -> String {
        use glslang::error::GlslangError as G;
        match e {
            G::PreprocessError(log) | G::ParseError(log) | G::LinkError(log) | G::MapIoError(log) => {
                format_log(&label, &log.log)
            }
            other => format!("{label}: {other}"),
        }
    };
    let shader = compiler.create_shader(input).map_err(describe)?;
    shader.compile().map_err(describe)
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    let dir = root.join("spirv");
    println!("cargo:rerun-if-changed=spirv");

    let mut kernels: Vec<String> = std::fs::read_dir(&dir)
        .expect("spirv/ exists")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".comp"))
        .collect();
    kernels.sort();
    for entry in std::fs::read_dir(dir.join("include")).into_iter().flatten().flatten() {
        println!("cargo:rerun-if-changed={}", entry.path().display());
    }

    let compiler = Compiler::acquire().expect("glslang initialises");
    // Kernels are independent: compile them on all cores.
    let results: Vec<(String, Result<Vec<u32>, String>)> = std::thread::scope(|s| {
        let handles: Vec<_> = kernels
            .iter()
            .map(|k| (k.clone(), s.spawn(|| compile(compiler, &dir, &dir.join("include"), k))))
            .collect();
        handles
            .into_iter()
            .map(|(k, h)| (k, h.join().unwrap_or_else(|_| Err("glslang panicked".into()))))
            .collect()
    });

    let mut errors = Vec::new();
    let mut table = String::from(
        "/// Every kernel in `spirv/`, compiled by build.rs.\npub static KERNELS: &[Kernel] = &[\n",
    );
    for (file, result) in results {
        println!("cargo:rerun-if-changed=spirv/{file}");
        match result {
            Ok(words) => {
                let name = file.trim_end_matches(".comp");
                let spv = out.join(format!("{name}.spv"));
                std::fs::write(&spv, bytemuck_bytes(&words)).expect("write SPIR-V to OUT_DIR");
                writeln!(
                    table,
                    "    Kernel {{ name: {name:?}, spirv: words!({:?}) }},",
                    spv.display().to_string()
                )
                .unwrap();
            }
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        eprintln!("error: kernel compilation failed\n{}", errors.join("\n"));
        for e in &errors {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
        }
        std::process::exit(1);
    }
    table.push_str("];\n");
    std::fs::write(out.join("kernels.rs"), table).expect("write kernels.rs");

    // The example host engine's own kernels (examples/*.comp): compiled here too, since the
    // example is plain `ash` with no compiler of its own; written to OUT_DIR, not embedded in umbra.
    let examples = root.join("examples");
    println!("cargo:rerun-if-changed=examples");
    for entry in std::fs::read_dir(&examples).into_iter().flatten().flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        if let Some(name) = file.strip_suffix(".comp") {
            match compile(compiler, &examples, &dir.join("include"), &file) {
                Ok(words) => std::fs::write(out.join(format!("{name}.spv")), bytemuck_bytes(&words))
                    .expect("write SPIR-V to OUT_DIR"),
                Err(e) => {
                    for line in e.lines() {
                        println!("cargo:warning={line}");
                    }
                    std::process::exit(1);
                }
            }
        }
    }
}

fn bytemuck_bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}
