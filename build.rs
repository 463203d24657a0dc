//! Compiles every `spirv/*.comp` kernel to SPIR-V 1.6 (Vulkan 1.3) with the vendored glslang and
//! embeds the words in the binary. A kernel error fails the build with `file:line: message`.

use glslang::include::{IncludeHandler, IncludeResult, IncludeType};
use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderSource, ShaderStage, SpirvVersion, Target, VulkanVersion,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `KHR_materials_sheen`'s albedo table, as the library computes it.
#[allow(dead_code)]
#[path = "src/sheen.rs"]
mod sheen;

/// Resolves `#include "x.glsl"` against the includer's folder, then `spirv/include/`, then the
/// declarations generated from `src/gpu/interface.rs` (`layout.glsl`, `kernel/<name>.glsl`).
struct Includes {
    include_dir: PathBuf,
    kernel_dir: PathBuf,
    generated_dir: PathBuf,
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
        [includer_dir.join(header), self.include_dir.join(header), self.generated_dir.join(header)]
            .into_iter()
            .find(|p| p.is_file())
            .and_then(|path| {
                let data = std::fs::read_to_string(&path).ok()?;
                let name =
                    path.strip_prefix(&self.kernel_dir).unwrap_or(&path).to_string_lossy().into_owned();
                Some(IncludeResult { name, data })
            })
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

/// Compiles `dir/file`; includes resolve against the includer's folder, then `include_dir`, then
/// `generated_dir`.
fn compile(
    compiler: &Compiler,
    dir: &Path,
    include_dir: &Path,
    generated_dir: &Path,
    file: &str,
) -> Result<Vec<u32>, String> {
    let folder = dir.file_name().map_or("spirv".into(), |f| f.to_string_lossy().into_owned());
    let label = format!("{folder}/{file}");
    let text = std::fs::read_to_string(dir.join(file)).map_err(|e| format!("{label}: {e}"))?;
    compile_source(compiler, dir, include_dir, generated_dir, &label, text)
}

/// Compiles the kernel `text` named `label` (for messages).
fn compile_source(
    compiler: &Compiler,
    dir: &Path,
    include_dir: &Path,
    generated_dir: &Path,
    label: &str,
    text: String,
) -> Result<Vec<u32>, String> {
    let source = ShaderSource::from(text);
    let options = CompilerOptions {
        target: Target::Vulkan { version: VulkanVersion::Vulkan1_3, spirv_version: SpirvVersion::SPIRV1_6 },
        ..CompilerOptions::default()
    };
    let mut includes = Includes {
        include_dir: include_dir.to_path_buf(),
        kernel_dir: dir.to_path_buf(),
        generated_dir: generated_dir.to_path_buf(),
    };
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
                format_log(label, &log.log)
            }
            other => format!("{label}: {other}"),
        }
    };
    let shader = compiler.create_shader(input).map_err(describe)?;
    shader.compile().map_err(describe)
}

// ---- The GLSL side of `src/gpu/interface.rs` ----------------------------------------------
// The same file the library reads with its own macros (src/gpu/layout.rs); these turn it into
// GLSL text.

/// A GLSL declaration's comment lines from its doc attributes (as `stringify!` shows them:
/// `doc = "..."`, `doc = r"..."` or `/// ...`).
fn comment(metas: &[&str], indent: &str) -> String {
    metas
        .iter()
        .filter_map(|m| {
            if let Some(text) = m.strip_prefix("///") {
                return Some(text.to_string());
            }
            // `doc = "..."`, however the pretty-printer spaced or broke it.
            let rest = m.strip_prefix("doc")?;
            let (start, end) = (rest.find('"')?, rest.rfind('"')?);
            Some(rest[start + 1..end.max(start + 1)].replace("\\\"", "\"").replace("\\'", "'"))
        })
        .map(|text| format!("{indent}//{}\n", text.trim_end()))
        .collect()
}

struct GlslStruct {
    name: &'static str,
    metas: Vec<&'static str>,
    /// (doc attributes, declaration without the `;`)
    fields: Vec<(Vec<&'static str>, String)>,
    /// A `texel_struct`'s members and how many 16-byte texels each spans.
    texels: Option<Vec<(&'static str, usize)>>,
}

/// How many 16-byte texels a `texel_struct` member of GLSL type `ty` spans: its members are
/// 4-vectors of 32-bit values or arrays of them.
fn member_texels(ty: &str) -> usize {
    let (elem, n) = match ty.strip_prefix('[').and_then(|t| t.strip_suffix(']')) {
        Some(inner) => {
            let (elem, n) = inner.split_once(';').expect("an array type [T; N]");
            (elem.trim(), n.trim().parse().expect("an array length"))
        }
        None => (ty, 1),
    };
    assert!(
        matches!(elem, "vec4" | "uvec4" | "ivec4"),
        "a texel_struct's members are 4-vectors of 32-bit values (or arrays of them), not {elem}"
    );
    n
}

macro_rules! glsl_field {
    ([$t:tt; $n:literal], $f:ident) => {
        format!("{} {}[{}]", stringify!($t), stringify!($f), $n)
    };
    ($t:ident, $f:ident) => {
        format!("{} {}", stringify!($t), stringify!($f))
    };
}

macro_rules! gpu_structs {
    ($group:ident; $($(#[$meta:meta])* $role:ident $name:ident {
        $($(#[$fmeta:meta])* $field:ident : $ty:tt $(as $rust:ty)?),* $(,)?
    })*) => {
        mod $group {
            use super::*;
            pub fn structs() -> Vec<GlslStruct> {
                vec![$(GlslStruct {
                    name: stringify!($name),
                    metas: vec![$(stringify!($meta)),*],
                    fields: vec![$((vec![$(stringify!($fmeta)),*], glsl_field!($ty, $field))),*],
                    texels: (stringify!($role) == "texel_struct")
                        .then(|| vec![$((stringify!($field), member_texels(stringify!($ty)))),*]),
                }),*]
            }
        }
    };
}

macro_rules! struct_groups {
    ($($group:ident),* $(,)?) => {
        fn glsl_structs() -> Vec<GlslStruct> {
            let mut all = Vec::new();
            $(all.extend($group::structs());)*
            all
        }
    };
}

macro_rules! gpu_constants {
    ($($(#[$meta:meta])* $name:ident : $ty:tt = $value:expr;)*) => {
        fn glsl_constants() -> String {
            let mut out = String::new();
            $(
                out.push_str(&comment(&[$(stringify!($meta)),*], ""));
                let value = stringify!($value);
                let suffix = if stringify!($ty) == "uint" { "u" } else { "" };
                out.push_str(&format!("const {} {} = {value}{suffix};\n", stringify!($ty), stringify!($name)));
            )*
            out
        }
    };
}

/// One binding: name, access, kind, argument (element type or format).
#[derive(Clone)]
struct GlslBinding {
    name: &'static str,
    access: &'static str,
    kind: &'static str,
    arg: &'static str,
    array: bool,
}

macro_rules! glsl_binding {
    ($name:ident : $access:ident $kind:ident [$arg:tt]) => {
        GlslBinding {
            name: stringify!($name),
            access: stringify!($access),
            kind: stringify!($kind),
            arg: stringify!($arg),
            array: true,
        }
    };
    ($name:ident : $access:ident $kind:ident $arg:tt) => {
        GlslBinding {
            name: stringify!($name),
            access: stringify!($access),
            kind: stringify!($kind),
            arg: stringify!($arg),
            array: false,
        }
    };
}

/// The bindings of one entry of a kernel's bindings: a G-buffer group's members, or the one.
macro_rules! glsl_bindings {
    ($name:ident : $access:ident gbuffer [$($member:ident),* $(,)?]) => {
        vec![$(GlslBinding {
            name: concat!(stringify!($name), "_", stringify!($member)),
            access: stringify!($access),
            kind: "image",
            arg: gbuffer_format!($member),
            array: false,
        }),*]
    };
    ($name:ident : $access:ident $kind:ident $arg:tt) => {
        vec![glsl_binding!($name : $access $kind $arg)]
    };
}

macro_rules! scene_bindings {
    ($($(#[$meta:meta])* $name:ident : $access:ident $kind:ident $arg:tt),* $(,)?) => {
        fn glsl_scene_bindings() -> Vec<GlslBinding> {
            vec![$(glsl_binding!($name : $access $kind $arg)),*]
        }
    };
}

struct GlslKernel {
    name: &'static str,
    /// A `test_kernel`: compiled only with the `testing` feature.
    test: bool,
    scene: &'static str,
    features: Vec<&'static str>,
    push: &'static str,
    /// The workgroup size, as written (an expression of `layout.glsl`'s constants).
    local: [&'static str; 3],
    /// (name, type, default)
    spec: Vec<(&'static str, &'static str, &'static str)>,
    bindings: Vec<GlslBinding>,
}

macro_rules! kernels {
    ($family:ident; $($(#[$meta:meta])* $role:ident $kernel:ident {
        scene: $scene:ident $([$($feature:ident),* $(,)?])?,
        push: $push:ty,
        local: [$lx:expr, $ly:expr, $lz:expr],
        spec: { $($spec:ident : $sty:tt = $sdef:expr),* $(,)? },
        bindings: { $($(#[$bmeta:meta])* $name:ident : $access:ident $kind:ident $arg:tt),* $(,)? }
    })*) => {
        mod $family {
            use super::*;
            pub fn kernels() -> Vec<GlslKernel> {
                vec![$(GlslKernel {
                    name: stringify!($kernel),
                    test: stringify!($role) == "test_kernel",
                    scene: stringify!($scene),
                    features: expand_features(&[$($(stringify!($feature)),*)?]),
                    push: stringify!($push),
                    local: [stringify!($lx), stringify!($ly), stringify!($lz)],
                    spec: vec![$((stringify!($spec), stringify!($sty), stringify!($sdef))),*],
                    bindings: [$(glsl_bindings!($name : $access $kind $arg)),*].concat(),
                }),*]
            }
        }
    };
}

macro_rules! kernel_families {
    ($($family:ident),* $(,)?) => {
        fn glsl_kernels() -> Vec<GlslKernel> {
            let mut all = Vec::new();
            $(all.extend($family::kernels());)*
            all
        }
    };
}

include!("src/gpu/interface.rs");

const HEADER: &str =
    "// Generated by build.rs from src/gpu/interface.rs and interface/: edit those, not this.\n";

/// `layout.glsl`: every shared struct and constant.
fn layout_glsl() -> String {
    let mut out = format!("{HEADER}#ifndef UMBRA_LAYOUT_GLSL\n#define UMBRA_LAYOUT_GLSL\n\n");
    for s in glsl_structs() {
        out.push_str(&comment(&s.metas, ""));
        out.push_str(&format!("struct {} {{\n", s.name));
        for (metas, decl) in &s.fields {
            out.push_str(&comment(metas, "    "));
            out.push_str(&format!("    {decl};\n"));
        }
        out.push_str("};\n\n");
        if let Some(texels) = &s.texels {
            out.push_str(&texel_constants(s.name, texels));
        }
    }
    out.push_str(&glsl_constants());
    out.push_str("\n#endif\n");
    out
}

/// A `texel_struct`'s constants, for kernels that read it from a texel buffer: its texels
/// (`MATERIAL_TEXELS` for `GpuMaterial`) and each member's first (`MATERIAL_SHEEN_TEXEL`).
fn texel_constants(name: &str, members: &[(&str, usize)]) -> String {
    let prefix = name.strip_prefix("Gpu").unwrap_or(name);
    let mut snake = String::new();
    for (i, c) in prefix.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            snake.push('_');
        }
        snake.push(c.to_ascii_uppercase());
    }
    let total: usize = members.iter().map(|(_, n)| n).sum();
    let mut out = format!("// {name} as 16-byte texels: their count, and each member's first.\n");
    out.push_str(&format!("const uint {snake}_TEXELS = {total}u;\n"));
    let mut first = 0;
    for (member, n) in members {
        out.push_str(&format!("const uint {snake}_{}_TEXEL = {first}u;\n", member.to_uppercase()));
        first += n;
    }
    out.push('\n');
    out
}

/// Refuses a feature set (`FEATURE_SETS`) named like a scene feature or holding an unknown one.
fn check_feature_sets() -> Result<(), String> {
    if let Some((set, _)) = FEATURE_SETS.iter().find(|(set, _)| SCENE_FEATURES.contains(set)) {
        return Err(format!("src/gpu/interface.rs: feature set '{set}' is named like a scene feature"));
    }
    if let Some(f) = FEATURE_SETS.iter().flat_map(|(_, f)| *f).find(|f| !SCENE_FEATURES.contains(f)) {
        return Err(format!("src/gpu/interface.rs: a feature set holds '{f}', which is no scene feature"));
    }
    Ok(())
}

fn camel(name: &str) -> String {
    name.split('_').map(|w| w[..1].to_uppercase() + &w[1..]).collect()
}

/// One binding's declaration.
fn binding_glsl(kernel: &str, number: usize, b: &GlslBinding) -> Result<String, String> {
    let image_prefix = if b.arg.ends_with("ui") {
        "u"
    } else if b.arg.ends_with('i') {
        "i"
    } else {
        ""
    };
    let qualifier = match b.access {
        "readonly" => "readonly ",
        "writeonly" => "writeonly ",
        "readwrite" => "",
        "coherent" => "coherent ",
        other => return Err(format!("kernel {kernel}: binding {}: unknown access '{other}'", b.name)),
    };
    Ok(match b.kind {
        "buffer" => {
            if b.access == "writeonly" {
                return Err(format!("kernel {kernel}: buffer {}: naga rejects writeonly buffers", b.name));
            }
            let array = if b.array { "[]" } else { "" };
            format!(
                "layout(set = 0, binding = {number}, std430) {qualifier}buffer {} {{ {} {}{array}; }};\n",
                camel(b.name),
                b.arg,
                b.name
            )
        }
        "image" => format!(
            "layout(set = 0, binding = {number}, {}) uniform {qualifier}{image_prefix}image2D {};\n",
            b.arg, b.name
        ),
        "texels" => format!(
            "layout(set = 0, binding = {number}, {}) uniform {qualifier}{image_prefix}imageBuffer {};\n",
            b.arg, b.name
        ),
        other => return Err(format!("kernel {kernel}: binding {}: unknown kind '{other}'", b.name)),
    })
}

/// `kernel/<name>.glsl`: a kernel's specialization constants, bindings and push constants.
fn kernel_glsl(k: &GlslKernel, scene: &[GlslBinding]) -> Result<String, String> {
    let mut out = format!("{HEADER}// The interface of {}.comp.\n#include \"layout.glsl\"\n\n", k.name);
    // The workgroup size, which the kernel declares with `KERNEL_LOCAL_SIZE;` (where it stands
    // in the kernel's source decides the SPIR-V's id order, so the kernel places it). Sizes of 1
    // are left out, as GLSL's defaults.
    let mut size = format!("local_size_x = {}", k.local[0]);
    for (axis, n) in ["y", "z"].iter().zip(&k.local[1..]) {
        if *n != "1" {
            size.push_str(&format!(", local_size_{axis} = {n}"));
        }
    }
    out.push_str(&format!("#define KERNEL_LOCAL_SIZE layout({size}) in\n\n"));
    // Kernels that trace (`full` or `bvh`) see every feature: those they list as specialization
    // constants, the others as `false`.
    if k.scene != "none" {
        for (id, feature) in SCENE_FEATURES.iter().enumerate() {
            let name = format!("HAS_{}", feature.to_uppercase());
            if k.features.contains(feature) {
                out.push_str(&format!("layout(constant_id = {id}) const bool {name} = false;\n"));
            } else {
                out.push_str(&format!("const bool {name} = false;  // not specialised in this kernel\n"));
            }
        }
    }
    if k.scene != "none" {
        if k.features.contains(&"shallow_bvh") {
            out.push_str(&format!(
                "layout(constant_id = {BVH_STACK_SPEC_ID}) const uint BVH_STACK = BVH_REGISTERS;\n"
            ));
        } else {
            out.push_str("const uint BVH_STACK = BVH_REGISTERS;  // not specialised in this kernel\n");
        }
    }
    if let Some(f) = k.features.iter().find(|f| !SCENE_FEATURES.contains(f)) {
        return Err(format!("kernel {}: unknown scene feature '{f}'", k.name));
    }
    if k.features.contains(&"textures") {
        if let Some((f, _)) = TEXTURE_SLOT_FEATURES.iter().find(|(f, _)| !k.features.contains(f)) {
            return Err(format!(
                "kernel {}: specialised on textures but not on slot feature '{f}' (it would read no texture there)",
                k.name
            ));
        }
    }
    for (i, (name, ty, default)) in k.spec.iter().enumerate() {
        let suffix = if *ty == "uint" { "u" } else { "" };
        out.push_str(&format!(
            "layout(constant_id = {}) const {ty} {} = {default}{suffix};\n",
            FIRST_KERNEL_SPEC_ID as usize + i,
            name.to_uppercase()
        ));
    }
    out.push('\n');
    let scene_part: &[GlslBinding] = match k.scene {
        "full" => scene,
        "bvh" => &scene[..2],
        "none" => &[],
        other => return Err(format!("kernel {}: unknown scene use '{other}'", k.name)),
    };
    for (i, b) in scene_part.iter().enumerate() {
        out.push_str(&binding_glsl(k.name, i, b)?);
    }
    // The walls real GPUs enforce, checked here rather than found by a user's driver.
    let count = scene_part.len() + k.bindings.len();
    if count > MAX_KERNEL_BINDINGS as usize {
        return Err(format!(
            "kernel {}: {count} bindings ({} of the scene, {} its own), more than the \
             {MAX_KERNEL_BINDINGS} push descriptors a kernel may take (maxPushDescriptors on most GPUs)",
            k.name,
            scene_part.len(),
            k.bindings.len()
        ));
    }
    if k.spec.len() > KERNEL_SPEC_IDS as usize {
        return Err(format!(
            "kernel {}: {} specialization constants of its own, more than its id range's {KERNEL_SPEC_IDS}",
            k.name,
            k.spec.len()
        ));
    }
    let first = if k.scene == "none" { 0 } else { scene.len() };
    for (i, b) in k.bindings.iter().enumerate() {
        out.push_str(&binding_glsl(k.name, first + i, b)?);
    }
    if k.push != "()" {
        out.push_str(&format!("layout(push_constant) uniform Push {{ {} params; }};\n", k.push));
    }
    Ok(out)
}

/// A kernel that declares a runtime array of every shared struct, so tests/layout.rs can read
/// each struct's offsets and array stride from SPIR-V. Never dispatched.
fn layout_check_glsl() -> String {
    let mut out = format!("#version 460\n{HEADER}#extension GL_GOOGLE_include_directive : require\n");
    out.push_str("#include \"layout.glsl\"\nlayout(local_size_x = 1) in;\n");
    let structs = glsl_structs();
    for (i, s) in structs.iter().enumerate() {
        out.push_str(&format!(
            "layout(set = 0, binding = {i}, std430) buffer Check{i} {{ {} check_{i}[]; }};\n",
            s.name
        ));
    }
    out.push_str("void main() {\n");
    for i in 0..structs.len() {
        out.push_str(&format!("    check_{i}[0] = check_{i}[1];\n"));
    }
    out.push_str("}\n");
    out
}

/// `sheen_albedo.glsl`: the sheen lobe's directional albedo table (src/sheen.rs).
fn sheen_glsl() -> String {
    let n = sheen::TABLE_SIZE;
    let mut out = format!(
        "{HEADER}// KHR_materials_sheen's directional albedo E, by src/sheen.rs (see there): entry\n"
    );
    out.push_str("// j * SHEEN_TABLE_SIZE + i at sqrt(n.v) = i / (SHEEN_TABLE_SIZE - 1), sheen roughness\n");
    out.push_str("// j / (SHEEN_TABLE_SIZE - 1). A kernel including bsdf.glsl defines sheen_table_texel.\n");
    let _ = writeln!(out, "const uint SHEEN_TABLE_SIZE = {n}u;");
    let _ = writeln!(out, "const float SHEEN_ROUGHNESS_MIN = {:?};", sheen::ROUGHNESS_MIN as f32);
    out.push_str("// The table's texels (four entries each) at the end of the scene's material texels.\n");
    let _ = writeln!(out, "const uint SHEEN_TABLE_TEXELS = {}u;", n * n / 4);
    out
}

/// `sheen_table.rs`: the same table as a Rust array the library uploads (src/gpu/scene.rs).
fn sheen_rust() -> String {
    let values: Vec<String> = sheen::table().iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]\n", values.join(", "))
}

/// Writes the generated GLSL into `dir`; checks that every kernel of `spirv/` has an interface
/// and includes it, and every interface a kernel.
fn generate(dir: &Path, spirv: &Path, kernels: &[String]) -> Result<(), String> {
    let write = |path: PathBuf, text: String| -> Result<(), String> {
        // Unchanged files keep their time stamps.
        if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
            std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        Ok(())
    };
    std::fs::create_dir_all(dir.join("kernel")).map_err(|e| e.to_string())?;
    write(dir.join("layout.glsl"), layout_glsl())?;
    write(dir.join("sheen_albedo.glsl"), sheen_glsl())?;
    write(dir.join("sheen_table.rs"), sheen_rust())?;
    check_feature_sets()?;
    let scene = glsl_scene_bindings();
    let defs = glsl_kernels();
    for k in &defs {
        let file = format!("{}.comp", k.name);
        if !kernels.contains(&file) {
            return Err(format!("src/gpu/interface.rs: kernel {} has no spirv/{file}", k.name));
        }
        let include = format!("#include \"kernel/{}.glsl\"", k.name);
        let text = std::fs::read_to_string(spirv.join(&file)).map_err(|e| format!("spirv/{file}: {e}"))?;
        if !text.contains(&include) {
            return Err(format!("spirv/{file}: must `{include}` (its interface)"));
        }
        write(dir.join("kernel").join(format!("{}.glsl", k.name)), kernel_glsl(k, &scene)?)?;
    }
    for file in kernels {
        let name = file.trim_end_matches(".comp");
        if !defs.iter().any(|k| k.name == name) {
            return Err(format!(
                "spirv/{file}: no interface in src/gpu/interface/ (add it to a `kernels!` family)"
            ));
        }
    }
    Ok(())
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

    println!("cargo:rerun-if-changed=src/gpu/interface.rs");
    println!("cargo:rerun-if-changed=src/gpu/interface");
    println!("cargo:rerun-if-changed=src/sheen.rs");
    let generated = out.join("include");
    if let Err(e) = generate(&generated, &dir, &kernels) {
        eprintln!("error: {e}");
        println!("cargo:warning={e}");
        std::process::exit(1);
    }

    // The test kernels only for the library the tests build (the `testing` feature).
    if std::env::var_os("CARGO_FEATURE_TESTING").is_none() {
        let tests: Vec<String> =
            glsl_kernels().iter().filter(|k| k.test).map(|k| format!("{}.comp", k.name)).collect();
        kernels.retain(|k| !tests.contains(k));
    }

    let compiler = Compiler::acquire().expect("glslang initialises");
    let include = dir.join("include");
    // Kernels are independent: compile them on all cores.
    let mut results: Vec<(String, Result<Vec<u32>, String>)> = std::thread::scope(|s| {
        let handles: Vec<_> = kernels
            .iter()
            .map(|k| (k.clone(), s.spawn(|| compile(compiler, &dir, &include, &generated, k))))
            .collect();
        handles
            .into_iter()
            .map(|(k, h)| (k, h.join().unwrap_or_else(|_| Err("glslang panicked".into()))))
            .collect()
    });
    let check =
        compile_source(compiler, &dir, &include, &generated, "layout_check.comp", layout_check_glsl());
    results.push(("layout_check.comp".into(), check));

    let mut errors = Vec::new();
    let mut table = String::from(
        "/// Every kernel in `spirv/`, compiled by build.rs.\npub static KERNELS: &[Kernel] = &[\n",
    );
    for (file, result) in results {
        if file != "layout_check.comp" {
            println!("cargo:rerun-if-changed=spirv/{file}");
        }
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
            match compile(compiler, &examples, &include, &generated, &file) {
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
