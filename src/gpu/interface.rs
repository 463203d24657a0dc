// The interface between Rust and the kernels, written once: every struct the host and the GPU
// share, every constant both read, and per kernel its bindings, push constants and
// specialization constants. This file (the rules, the limits, and the list of the files it
// includes from `interface/`: structs, constants and kernels by family) is read twice:
//
// - by the library (`src/gpu/layout.rs`), whose macros turn each struct into a `#[repr(C)]`,
//   `bytemuck::Pod` Rust struct, each constant into a `pub const`, and each kernel into a module
//   with its typed resources (`Resources`, one field per binding, by name), its push-constant
//   type and its specialization constants (`Spec`);
// - by `build.rs`, whose macros of the same names turn the same text into GLSL:
//   `layout.glsl` (structs and constants) and `kernel/<name>.glsl` per kernel (its binding,
//   push-constant and specialization-constant declarations), which the kernel includes.
//
// Why Rust is the source and GLSL is generated: the Rust side needs more than the GLSL side
// (types the compiler checks, `Pod`, docs, resource structs), macro_rules reads this text as
// tokens without a parser of its own, and rust-analyzer and rustdoc see it. GLSL is generated with
// the same names, so kernels read `params.camera.origin` and `triangles[i]` as before.
// tests/layout.rs reads every compiled kernel with naga and checks each struct's offsets and
// each binding's set, number, name and type against this file: the generator cannot drift either.
//
// Kernels specialised on the scene list their features (`scene: full [...]`) by name or by the
// name of a set of them (`FEATURE_SETS`).
//
// Types are GLSL's names (`float`, `uint`, `int`, `vec2`..`vec4`, `uvec2`..`uvec4`, `ivec2`,
// `[T; N]` for `T name[N]`, a struct's name). std430 rules apply: a `vec3` or `uvec2` must sit
// on its own alignment, which the Rust `[f32; 3]`/`[u32; 2]` does not enforce: the naga test
// and each struct's size assertion catch a misplaced one. `as` gives a field another Rust type of
// the same size (bytes read on the GPU as `uint`s).
//
// Items marked `test_struct` and `test_kernel` exist only for umbra's own tests: the library
// has them (hidden from its docs) only with the `testing` feature, which the tests turn on, and
// build.rs compiles those kernels only then.
//
// Bindings: `name: access kind arg`, access `readonly`, `writeonly`, `readwrite` or `coherent`;
// kind `buffer` (arg `[T]`: a runtime array, or `T`: one struct), `image` (arg: its storage
// format), `texels` (a storage texel buffer read as `uimageBuffer`, arg: its format), `gbuffer`
// (arg `[depth, normal, ...]`: those G-buffer images, `<name>_<member>` in GLSL, in the members'
// order and formats of `gbuffer_format!` below; one `&GBufferViews` in Rust). The scene's
// bindings are one block with the same numbers in every kernel that uses the scene (`scene: full`)
// or only its BVH (`scene: bvh`); a kernel's own bindings follow from `SCENE_BINDINGS` on (from 0
// without a scene), in the order written.

/// The scene features a kernel can be specialised on (`scene: full [...]` below): `HAS_<NAME>` in
/// GLSL, its specialization-constant id the index here; a feature a kernel does not list is a
/// plain `false` there. A kernel specialised on `textures` is on every texture slot's feature too
/// ([`TEXTURE_SLOT_FEATURES`]; build.rs refuses one that is not): a slot no material fills costs
/// no lookup.
pub const SCENE_FEATURES: [&str; 30] = [
    "textures",
    "alpha",
    "lights",
    "punctual",
    "env_map",
    "transmission",
    "colors",
    "unlit",
    "base_color_map",
    "metal_rough_map",
    "emissive_map",
    "normal_map",
    "occlusion_map",
    "clearcoat",
    "implicit",
    "parallax",
    "sheen",
    "specular_map",
    "transmission_map",
    "clearcoat_map",
    "iridescence",
    "iridescence_map",
    "anisotropy",
    "anisotropy_map",
    "sheen_map",
    "diffuse_transmission",
    "diffuse_transmission_map",
    "thickness_map",
    "dispersion",
    "shallow_bvh",
];

/// Named sets of scene features, written by name in the kernels' `scene: full [...]` lists:
/// `surface`, what every kernel that shades or cuts out a surface reads (its textures, each slot's
/// feature, alpha and vertex colours); `all_lights`, every kind of light (emissive triangles,
/// punctual lights, the environment map). [`expand_features`] spells a list out, the same for
/// the Rust side and build.rs, which refuses a set named like a feature or holding an unknown one.
pub const FEATURE_SETS: [(&str, &[&str]); 2] = [
    (
        "surface",
        &[
            "textures",
            "alpha",
            "colors",
            "base_color_map",
            "metal_rough_map",
            "emissive_map",
            "normal_map",
            "occlusion_map",
            "specular_map",
            "transmission_map",
            "clearcoat_map",
            "iridescence_map",
            "anisotropy_map",
            "sheen_map",
            "diffuse_transmission_map",
            "thickness_map",
        ],
    ),
    ("all_lights", &["lights", "punctual", "env_map"]),
];

// The G-buffer's images as a binding group, named once: in a kernel's bindings,
// `gb: readonly gbuffer [depth, normal]` declares `gb_depth` and `gb_normal` in that order (a
// subset in this order), each a storage image of its member's format below (the images are
// documented in src/passes/gbuffer.rs); the Rust side takes them as one `&GBufferViews`.
macro_rules! gbuffer_format {
    (depth) => {
        "r32f"
    };
    (normal) => {
        "rgba16f"
    };
    (base) => {
        "rgba16f"
    };
    (emission) => {
        "rgba16f"
    };
    (material) => {
        "rgba32ui"
    };
    (layers) => {
        "rgba32ui"
    };
    (layers2) => {
        "rgba32ui"
    };
    (motion) => {
        "rgba16f"
    };
}

/// A kernel's feature list spelled out: each set's name ([`FEATURE_SETS`]) replaced by its
/// features, each feature once, in the order written.
pub fn expand_features(list: &[&'static str]) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = Vec::new();
    for &name in list {
        let set = FEATURE_SETS.iter().find(|(set, _)| *set == name);
        for &feature in set.map_or(&[name][..], |(_, features)| features) {
            if !out.contains(&feature) {
                out.push(feature);
            }
        }
    }
    out
}

/// The scene features of the texture slots, each with the `MATERIAL_SLOT_*` slots it covers (bit k
/// for slot k): some material has a texture in one of them. One feature per slot of the core
/// material; one per extension's texture group (`KHR_materials_specular`'s two textures share
/// `specular_map`), whose textures come together in the files seen (docs/history/2026-12-02.md,
/// fifth session, "the extensions' layer textures": a scene with one of them pays for the others'
/// lookups). The height slot is `parallax`'s.
pub const TEXTURE_SLOT_FEATURES: [(&str, u32); 13] = [
    ("base_color_map", 1 << 0),
    ("metal_rough_map", 1 << 1),
    ("emissive_map", 1 << 2),
    ("normal_map", 1 << 3),
    ("occlusion_map", 1 << 4),
    ("specular_map", 1 << 6 | 1 << 7),
    ("transmission_map", 1 << 8),
    ("clearcoat_map", 1 << 9 | 1 << 10 | 1 << 11),
    ("iridescence_map", 1 << 13 | 1 << 14),
    ("anisotropy_map", 1 << 12),
    ("sheen_map", 1 << 15 | 1 << 16),
    ("diffuse_transmission_map", 1 << 17 | 1 << 18),
    ("thickness_map", 1 << 19),
];

// Specialization-constant ids come in named ranges with room to grow, each checked below when
// umbra is compiled: the scene features `0..FEATURE_SPEC_IDS` (one per `SCENE_FEATURES` entry, its
// index), scene-wide constants from `BVH_STACK_SPEC_ID` up to `FIRST_KERNEL_SPEC_ID`, then each
// kernel's own, at most `KERNEL_SPEC_IDS` of them (build.rs refuses a kernel with more).

/// The ids reserved for scene features: [`SCENE_FEATURES`] may grow to this many.
pub const FEATURE_SPEC_IDS: u32 = 64;

/// The specialization-constant id of `BVH_STACK` in kernels specialised on `shallow_bvh`: the
/// entries of the walk's register stack, the BVH's stack depth
/// ([`crate::gpu::bvh::GpuBvhNode::stack_depth`], at least 1), so that a shallow BVH's walk moves
/// no more registers than it fills (`bvh.glsl`). A plain constant, [`BVH_REGISTERS`], in the
/// other kernels that trace. The first of the scene-wide constants' range.
pub const BVH_STACK_SPEC_ID: u32 = FEATURE_SPEC_IDS;

/// The specialization-constant id of a kernel's first own constant (`spec: {...}` below); the
/// others follow in order. Ids from [`BVH_STACK_SPEC_ID`] up to here are for scene-wide
/// constants to come.
pub const FIRST_KERNEL_SPEC_ID: u32 = FEATURE_SPEC_IDS + 32;

/// The most specialization constants of a kernel's own.
pub const KERNEL_SPEC_IDS: u32 = 64;

/// The most bindings (the scene's and its own) a kernel may declare: umbra binds a kernel's
/// resources as one push-descriptor set, and `maxPushDescriptors` is 32 on most GPUs
/// ([`crate::vk::REQUIRED_PUSH_DESCRIPTORS`], which a device must offer). build.rs refuses a kernel
/// with more.
pub const MAX_KERNEL_BINDINGS: u32 = 32;

/// The most bytes of push constants a kernel may take: Vulkan's guaranteed
/// `maxPushConstantsSize`. Checked for every kernel when umbra is compiled (`gpu/layout.rs`).
pub const MAX_PUSH_CONSTANT_BYTES: u32 = 128;

const _: () = assert!(SCENE_FEATURES.len() as u32 <= FEATURE_SPEC_IDS, "scene features past their id range");
const _: () = assert!(BVH_STACK_SPEC_ID < FIRST_KERNEL_SPEC_ID, "scene-wide ids past their range");

// The items, by topic, in the order the generated GLSL keeps. A new kernel goes into its
// family's file; a new family is a file here and a name in `kernel_families!` below (each name
// becomes a private module of the library's and build.rs's generated code).
include!("interface/structs_scene.rs");
include!("interface/structs_passes.rs");
include!("interface/constants.rs");
include!("interface/kernels_path.rs");
include!("interface/kernels_hybrid.rs");
include!("interface/kernels_baked.rs");
include!("interface/kernels_tools.rs");

// The groups above, in order: `gpu_layouts()` and `kernels::all()` list their items in it.
struct_groups!(structs_scene, structs_passes);
kernel_families!(kernels_path, kernels_hybrid, kernels_baked, kernels_tools);
