// The interface between Rust and the kernels, written once: every struct the host and the GPU
// share, every constant both read, and per kernel its bindings, push constants and
// specialization constants. This file is read twice:
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
// format), `texels` (a storage texel buffer read as `uimageBuffer`, arg: its format). The scene's
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

gpu_structs! {
    /// A pinhole or orthographic camera as every kernel that casts rays from it reads it
    /// (`camera.glsl`), and the raster its rays cover: an `image_width` × `image_height` image of
    /// which a kernel renders the region from pixel `region` on. The path tracer honours the
    /// region (`--tile`: a tile's pixels and random numbers are those of the whole image's); the
    /// other kernels render whole images (region 0, the image their size).
    struct GpuCamera {
        /// Position (orthographic: the centre of the plane the rays start from).
        origin: vec3,
        /// Width of the whole image, pixels.
        image_width: uint,
        /// Unit forward.
        forward: vec3,
        /// Height of the whole image, pixels.
        image_height: uint,
        /// Pinhole: right × tan(yfov/2) × aspect; orthographic: right × half the view's width.
        right: vec3,
        /// The region's left column | its top row << 16 (both below 65,536).
        region: uint,
        /// Pinhole: up × tan(yfov/2); orthographic: up × half the view's height.
        up: vec3,
        /// 1: orthographic (rays parallel to `forward` from the plane through `origin`), 0: pinhole.
        orthographic: uint,
    }

    /// Push constants of `test_pattern.comp`.
    #[doc(hidden)]
    struct PatternParams {
        /// Image width and height.
        size: uvec2,
        /// Added to the hashed index.
        seed: uint,
        /// Added to the product channel.
        frame: uint,
    }

    /// Push constants of `test_buffer.comp` and `texture_wrap_test.comp`.
    test_struct BufferTestParams {
        /// Number of elements.
        count: uint,
        /// Added to each tripled element.
        add: uint,
    }

    /// What `spin_test.comp` shares with the host.
    test_struct SpinState {
        /// Set non-zero by the host to release the spinning invocations.
        release: uint,
        /// Iterations of all invocations.
        spun: uint,
        /// 1 once an invocation saw the release.
        released: uint,
    }

    /// The BVH as the GPU traverses it: a 4-wide tree collapsed from [`crate::bvh::Bvh::nodes`]
    /// (each node takes its binary node's two children and opens the largest-area inner child
    /// until it has four or only leaves), holding all children's boxes (Aila and Laine 2009) in 64
    /// bytes, four texels (bvh.glsl): the boxes quantized to 8 bits per plane on a per-node grid
    /// (after Ylitie, Karras and Laine 2017), so one step fetches half the bytes of
    /// full-precision boxes. Node 0 is the root.
    ///
    /// On each axis a node's grid has planes at `origin + q * step` for q in 0..=255, the first and
    /// last on the node's bounds (to a float's precision, outward), or, in the top levels, one of
    /// them and one of a child's planes inside, whichever grows the children's boxes least; a
    /// child's box is rounded outward to the grid, exactly, so it contains the child's true box.
    /// The traversal computes a plane's distance as `q * a + b` with `a = step / d` and `b =
    /// (origin - o) / d` per node, which is off by a small multiple of the node's size in ray
    /// units; `bvh.glsl` widens every interval by a bound on that. (docs/history/2026-12-01.md,
    /// third round: 3 % more node visits on Sponza than exact boxes with the camera on its symmetry
    /// plane, where the halves' boxes meet, 0.5 % off it.)
    struct GpuBvhNode {
        /// The grid's origin (texel 0).
        origin: vec3,
        /// The grid's step per axis (`step[0]` ends texel 0; 2^-64 on a flat axis).
        step: [float; 3],
        /// Lower planes, `lo[axis][child]`, in grid steps from the origin (from the middle of
        /// texel 1); the GPU reads each axis's four bytes as one `uint`.
        lo: [uint; 3] as [[u8; 4]; 3],
        /// Upper planes, `hi[axis][child]` (the rest of texel 2).
        hi: [uint; 3] as [[u8; 4]; 3],
        /// Per child (texel 3): `index << 4 | count`, count 0 for an inner child (index its node),
        /// 1 to [`GpuBvhNode::MAX_LEAF`] for a leaf (index its first triangle), or
        /// [`GpuBvhNode::NONE`] for a child that is not there.
        child: [uint; 4],
    }

    /// A triangle in BVH order: three vertices, and in `v0[3]` the bits of its index in the
    /// input; `v1[3]` holds its alpha mode bits (0 opaque, 1 mask, 2 blend, [`ALPHA_NEVER_HIT`]) for
    /// the traversal.
    struct BvhTri {
        /// First vertex; `w` holds the input index as `f32` bits.
        v0: vec4,
        /// Second vertex; `w` the alpha mode bits.
        v1: vec4,
        /// Third vertex.
        v2: vec4,
    }

    /// A ray for `trace.comp`: origin and `tmin`, direction and `tmax`.
    struct TraceRay {
        /// Origin xyz, `tmin` in w.
        origin_tmin: vec4,
        /// Direction xyz (need not be normalised), `tmax` in w.
        dir_tmax: vec4,
    }

    /// `trace.comp`'s answer for one ray.
    struct TraceHit {
        /// Hit distance (closest-hit mode); 1.0 for occluded, 0.0 for clear in any-hit mode.
        t: float,
        /// Triangle index in BVH order, [`TraceHit::MISS`] for none.
        tri: uint,
        /// Barycentric weight of the triangle's second vertex; of an implicit shape's hit, the
        /// octahedral encoding of its unit normal (with `v`). On a miss (closest-hit mode, and
        /// only where the trace kernel is specialised for implicit shapes), the number of
        /// marches that ran out of steps.
        u: float,
        /// Barycentric weight of the triangle's third vertex.
        v: float,
    }

    /// Push constants of `trace.comp`.
    struct TraceParams {
        /// Number of rays.
        count: uint,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Padding.
        pad2: uint,
    }

    /// A triangle of the GPU scene in BVH order.
    struct GpuTriangle {
        /// First vertex index.
        v0: uint,
        /// Second vertex index.
        v1: uint,
        /// Third vertex index.
        v2: uint,
        /// Material index.
        material: uint,
        /// Probability that light sampling picks this triangle (0 if it does not emit).
        light_pmf: float,
        /// Area in square metres.
        area: float,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
    }

    /// Shading attributes of a vertex (world space).
    struct GpuVertex {
        /// Normal xyz, uv0.x.
        normal_u: vec4,
        /// uv0.y, uv1.xy, then `COLOR_0` as the bits of sRGB-encoded RGBA8 (alpha linear;
        /// opaque white where a primitive has none).
        v_uv1: vec4,
        /// Tangent xyz, bitangent sign (all 0 when the scene has no tangents).
        tangent: vec4,
    }

    /// A glTF metallic-roughness material's factors and texture slots.
    struct GpuMaterial {
        /// baseColorFactor.
        base_color: vec4,
        /// Emission (strength applied) rgb, roughness.
        emissive_rough: vec4,
        /// specularColorFactor rgb, specularFactor.
        specular: vec4,
        /// metallic, ior, transmission, alpha cutoff.
        params: vec4,
        /// `x`: `MATERIAL_*` bits; `yzw`: the volume's attenuation coefficient rgb per unit
        /// length as `f32` bits ([`crate::scene::Material::attenuation`]; 0 without one).
        flags: uvec4,
        /// The texture of each slot (`MATERIAL_SLOT_*`; slot k is `textures[k / 4][k % 4]`):
        /// index + 1 (0: none). Base colour, metallic-roughness, emissive, normal, occlusion,
        /// height (parallax occlusion mapping), specular, specular colour, transmission, clear
        /// coat, clear coat roughness, clear coat normal, anisotropy, iridescence, iridescence
        /// thickness, sheen colour, sheen roughness, diffuse transmission, diffuse transmission
        /// colour, volume thickness.
        textures: [uvec4; 5],
        /// Per slot the two rows of the `KHR_texture_transform` (u' = row0 · (u, v, 1),
        /// v' = row1 · (u, v, 1)); the UV set (0 or 1) in row0.w; row1.w is the normal slot's
        /// normal scale (and the clear coat normal slot's) and the occlusion slot's strength (1 for
        /// the other slots).
        tex_transform: [vec4; 40] as TexTransforms,
        /// `KHR_materials_clearcoat`: the coat's weight (`clearcoatFactor`), its roughness
        /// (`clearcoatRoughnessFactor`), unused, unused. Read only by kernels specialised for
        /// it (`HAS_CLEARCOAT`).
        clearcoat: vec4,
        /// Parallax occlusion mapping (`UMBRA_implicit`'s `parallax` on the material; its height
        /// map in slot `MATERIAL_SLOT_HEIGHT`): the height scale in world units, the linear
        /// search's layer count, the binary refinement's step count, unused. Read only by
        /// kernels specialised for it (`HAS_PARALLAX`), and only where the height slot is filled.
        parallax: vec4,
        /// `KHR_materials_sheen`: `sheenColorFactor` rgb, `sheenRoughnessFactor`. Read only by
        /// kernels specialised for it (`HAS_SHEEN`).
        sheen: vec4,
        /// `KHR_materials_iridescence`: `iridescenceFactor`, `iridescenceIor`,
        /// `iridescenceThicknessMinimum`, `iridescenceThicknessMaximum` (nm). Read only by kernels
        /// specialised for it (`HAS_IRIDESCENCE`).
        iridescence: vec4,
        /// `KHR_materials_anisotropy`: `anisotropyStrength`, cos and sin of
        /// `anisotropyRotation`, unused. Read only by kernels specialised for it
        /// (`HAS_ANISOTROPY`).
        anisotropy: vec4,
        /// `KHR_materials_diffuse_transmission`: `diffuseTransmissionColorFactor` rgb,
        /// `diffuseTransmissionFactor`. Read only by kernels specialised for it
        /// (`HAS_DIFFUSE_TRANSMISSION`).
        diffuse_transmission: vec4,
        /// `KHR_materials_volume`: `thicknessFactor` (0 without a volume), then
        /// `KHR_materials_dispersion`'s `dispersion` (0 but for a transmitting volume), unused,
        /// unused. Read only by kernels specialised for transmission (`HAS_TRANSMISSION`; the
        /// dispersion only by those specialised for it, `HAS_DISPERSION`): the hybrid's
        /// attenuation of the transmitted environment, the indices of refraction per channel.
        volume: vec4,
    }

    /// A texture in the shared texel buffer (linear RGBA16, one RG32UI texel per texel,
    /// row-major).
    struct GpuTexture {
        /// First texel in the texel buffer.
        offset: uint,
        /// Width.
        width: uint,
        /// Height.
        height: uint,
        /// `TEXTURE_*` bits.
        flags: uint,
        /// Mip levels stored (1: level 0 only). Level k is `max(1, width >> k)` ×
        /// `max(1, height >> k)` texels and follows level k − 1 in the texel buffer.
        levels: uint,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Padding.
        pad2: uint,
    }

    /// One entry of the emissive-triangle sampling table.
    struct GpuLightTri {
        /// Triangle in BVH order.
        tri: uint,
        /// Inclusive prefix of the normalised power.
        cdf: float,
        /// Selection probability.
        pmf: float,
        /// Area in square metres.
        area: float,
    }

    /// A `KHR_lights_punctual` light in world space.
    struct GpuLight {
        /// Position xyz, range (0: infinite).
        position_range: vec4,
        /// Unit direction the light shines in, kind (`LIGHT_*`).
        direction_kind: vec4,
        /// Colour × intensity (candela; lux for directional lights), inclusive prefix of the
        /// selection probabilities (by power).
        intensity: vec4,
        /// cos(outer cone), 1 / max(cos(inner) − cos(outer), 1e-4), selection probability, unused.
        cone: vec4,
    }

    /// Push constants of `pathtrace.comp`.
    struct PathParams {
        /// The camera.
        camera: GpuCamera,
        /// Constant environment radiance rgb (or the environment map's multiplier).
        env: vec3,
        /// Candidates the first hit's light sample is resampled from (RIS, a kernel specialised
        /// for it: `ris`); unread otherwise. (The environment map's next-event estimation is on
        /// where `env_pick` > 0.)
        ris_candidates: uint,
        /// Width and height of the region rendered (the whole image unless the camera says
        /// otherwise) and of the accumulation buffers.
        size: uvec2,
        /// The first sample of this dispatch: the index in the counter-based sequence its random
        /// numbers are drawn for. The samples already accumulated are counted in the accumulation
        /// buffer's alpha (cleared to start a render).
        sample_index: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Scattering events per path.
        max_bounces: uint,
        /// Russian roulette starts once a path has scattered this many times.
        rr_depth: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Environment map width and height.
        env_size: uvec2,
        /// Samples per pixel in this dispatch (`sample_index ..`), at least 1.
        sample_count: uint,
        /// The probability that a light sample is drawn from the environment map rather than
        /// the emissive triangles: 1 or 0 where only one of them is sampled, by their power
        /// where both are ([`crate::passes::pathtrace::PathTracePass::params`]).
        env_pick: float,
    }

    /// Push constants of `wavefront.comp`: [`PathParams`] but for the camera (in its own
    /// buffer, `wf_camera`), and the wave's place.
    struct WaveParams {
        /// Constant environment radiance rgb (or the environment map's multiplier).
        env: vec3,
        /// [`PathParams::ris_candidates`]: unread (the wavefront path tracer does not resample).
        ris_candidates: uint,
        /// Width and height of the region rendered and of the accumulation buffers.
        size: uvec2,
        /// The wave's first sample: the index in the counter-based sequence.
        sample_index: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Scattering events per path.
        max_bounces: uint,
        /// Russian roulette starts once a path has scattered this many times.
        rr_depth: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Environment map width and height.
        env_size: uvec2,
        /// Samples per pixel in this wave (`sample_index ..`), at least 1.
        sample_count: uint,
        /// The probability that a light sample comes from the environment map.
        env_pick: float,
        /// The wave's round: the path segment each path of the ray queue traces (0: camera rays).
        round: uint,
        /// Paths the state holds (`wf_paths`' texels per field).
        capacity: uint,
        /// Shadow rays one path may queue in a round.
        shadows_per_path: uint,
        /// The region's row where the wave's rows start (a wave covers whole rows).
        first_row: uint,
    }

    /// Per-render counters written by `pathtrace.comp`.
    struct PathStats {
        /// Samples that came out NaN or infinite (replaced by 0; must stay 0).
        nonfinite_samples: uint,
        /// Where they arose: bits of [`NONFINITE_SOURCES`].
        nonfinite_sources: uint,
        /// Path segments traced (closest-hit rays: camera rays and continuations), modulo 2^32;
        /// with `segments_hi`, a 64-bit count.
        segments_lo: uint,
        /// The count's high word (the carries out of `segments_lo`).
        segments_hi: uint,
        /// Implicit-shape marches that ran out of steps ([`IMPLICIT_MAX_STEPS`]) before they
        /// reached the surface or left the shape's box: each was taken as a miss (grazing rays
        /// along a silhouette, mostly). 0 in scenes without implicit shapes.
        marches_exhausted: uint,
        /// A target with lane counts ([`crate::passes::pathtrace::PathTarget::with_lane_counts`],
        /// the megakernel), each count in two words (low, high; [`PathStats::walk_counts`]
        /// joins them): the closest-hit traces' walk-loop iterations, each active lane's summed.
        walk_lanes_closest: [uint; 2],
        /// The same traces' iterations as their SIMD groups ran them: per trace and subgroup,
        /// its slowest active lane's (the loop runs until that lane is done).
        walk_groups_closest: [uint; 2],
        /// `walk_lanes_closest` for the any-hit traces (shadow rays).
        walk_lanes_any: [uint; 2],
        /// `walk_groups_closest` for the any-hit traces.
        walk_groups_any: [uint; 2],
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Padding.
        pad2: uint,
    }

    /// Push constants of `gbuffer.comp`.
    struct GBufferParams {
        /// The camera.
        camera: GpuCamera,
        /// Image width and height.
        size: uvec2,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
    }

    /// Push constants of `deferred.comp`.
    struct DeferredParams {
        /// The camera.
        camera: GpuCamera,
        /// Constant environment radiance rgb (or the environment map's multiplier).
        env: vec3,
        /// Split-sum image-based lighting of the environment (0/1).
        ibl: uint,
        /// Image width and height.
        size: uvec2,
        /// Frame index (decorrelates successive frames' light samples).
        frame: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Shadow rays (light samples) per pixel for the emissive triangles.
        shadow_rays: uint,
        /// Read the prefiltered environment along the lobe's dominant direction (1) or the
        /// mirror direction (0).
        ibl_dominant: uint,
        /// Environment map width and height.
        env_size: uvec2,
        /// Radius of point and spot lights for ray-traced shadows of sized lights (`shadow_sized`),
        /// metres.
        light_radius: float,
        /// 1 − cos of directional lights' angular radius for ray-traced shadows of sized lights
        /// (`shadow_sized`).
        sun_one_minus_cos: float,
    }

    /// Push constants of the ReSTIR DI kernels (`restir_initial.comp`, `restir_spatial.comp`;
    /// [`crate::passes::restir`]).
    struct RestirParams {
        /// The camera.
        camera: GpuCamera,
        /// Image width and height.
        size: uvec2,
        /// Frame index (decorrelates successive frames' candidates).
        frame: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Candidates resampled per pixel (M).
        candidates: uint,
        /// Spatial neighbours merged per pixel.
        neighbours: uint,
        /// Radius of the spatial neighbourhood, pixels.
        radius: float,
        /// A reused reservoir counts at most this many times `candidates`.
        history_cap: float,
        /// Whether the history (the previous frame's reservoirs and camera) is valid (0/1).
        history: uint,
        /// Padding.
        pad0: uint,
    }

    /// A ReSTIR DI reservoir, one per pixel ([`crate::passes::restir`]).
    struct GpuReservoir {
        /// The light sample kept: an emissive-table entry, or `RESTIR_PUNCTUAL` | a punctual
        /// light; `RESTIR_NONE` (all bits) for none.
        light: uint,
        /// Its unbiased contribution weight W.
        weight: float,
        /// Its barycentrics on the emissive triangle.
        bary: vec2,
        /// The candidates it stands for (M).
        count: float,
        /// View depth of the surface it was built for (0: none).
        depth: float,
        /// That surface's shading normal, octahedral, `packSnorm2x16`.
        normal: uint,
        /// `RESTIR_VISIBLE`: `weight` includes the sample's visibility (0 when occluded), so the
        /// lighting pass traces no shadow ray.
        flags: uint,
    }

    /// The path tracer's first-hit reservoir of one pixel and sample index, with reuse
    /// (`--ris-reuse`, [`crate::passes::pathtrace::RisReuse`]): the light sample kept (as
    /// [`GpuReservoir`]'s), its W and M, and the first hit it was resampled for (the closest
    /// hit's triangle and barycentrics, its position and shading normal), from which a later
    /// sample index evaluates that surface's target function again.
    struct GpuPathReservoir {
        /// The light sample kept ([`GpuReservoir::light`]'s encoding).
        light: uint,
        /// Its unbiased contribution weight W.
        weight: float,
        /// Its barycentrics on the emissive triangle.
        bary: vec2,
        /// The candidates it stands for (M, capped); 0: no reservoir (a miss, an unlit surface,
        /// a cleared buffer).
        count: float,
        /// The first hit's triangle (the `Hit`'s `tri`).
        hit_tri: uint,
        /// The first hit's barycentrics (the `Hit`'s `bary`, after parallax mapping).
        hit_bary: vec2,
        /// The first hit's position.
        position: vec3,
        /// Its shading normal (facing the camera), octahedral, `packSnorm2x16`.
        normal: uint,
    }

    /// One shadow-map layer (a spot light's map, a cube face, a cascade) as the rasterizer and
    /// the lighting pass read it: six RGBA32UI texels in `shadow_texels` (float bits but for
    /// `offset`, `size`, `kind`).
    struct GpuShadowLayer {
        /// First row of the world → light-texel transform: `(x w, y w, depth, w)` = rows ·
        /// (p, 1), x and y in texels of the layer (texel centres at +0.5), depth the linear depth
        /// in world units (along the light's axis), w the perspective divisor (1 for orthographic
        /// layers; the depth itself for perspective ones).
        row0: vec4,
        /// Second row (y w).
        row1: vec4,
        /// Third row (linear depth).
        row2: vec4,
        /// Fourth row (w).
        row3: vec4,
        /// First texel of the layer in the map.
        offset: uint,
        /// Width = height in texels.
        size: uint,
        /// [`SHADOW_ORTHOGRAPHIC`] or [`SHADOW_PERSPECTIVE`].
        kind: uint,
        /// Padding.
        pad0: uint,
        /// World size of one texel: orthographic, its side; perspective, its side per unit of
        /// depth.
        texel_world: float,
        /// The moment map's depth range: depth 0 maps to 0, `depth_far` to 1.
        depth_far: float,
        /// Directional cascades: the view depth (along the camera's forward axis) this cascade
        /// covers up to; 0 for other layers.
        split: float,
        /// Padding.
        pad1: float,
    }

    /// Push constants of the shadow rasterizer's kernels (`shadow_bin`, `shadow_scan`,
    /// `shadow_raster`): one layer.
    struct ShadowRasterParams {
        /// The layer's transform, [`GpuShadowLayer::row0`]..`row3`.
        row0: vec4,
        /// Second row.
        row1: vec4,
        /// Third row.
        row2: vec4,
        /// Fourth row.
        row3: vec4,
        /// Width = height of the layer in texels.
        size: uint,
        /// Tiles per side ([`SHADOW_TILE`] texels each).
        tiles: uint,
        /// Triangles to rasterize (`raster_tris`).
        tri_count: uint,
        /// First texel of the layer in the map.
        offset: uint,
        /// Entries the tile lists hold.
        capacity: uint,
        /// The first tile rendered ([`crate::passes::shadow::ShadowPlan::windows`]): column |
        /// row << 16.
        window_lo: uint,
        /// The last tile rendered: column | row << 16.
        window_hi: uint,
        /// The layer's first entry in `tile_marks` and `tile_list` (layer × tiles²).
        list_at: uint,
    }

    /// Push constants of `shadow_mark.comp`: the view whose G-buffer marks the tiles its pixels
    /// read.
    struct ShadowMarkParams {
        /// The G-buffer's camera.
        camera: GpuCamera,
        /// G-buffer width and height.
        size: uvec2,
        /// Punctual lights (records in `shadow_texels`).
        lights: uint,
        /// Texel of `shadow_texels` where the layers start.
        layers_at: uint,
        /// Tiles per side of a layer.
        tiles: uint,
        /// Texels around a pixel's point marked (the filters' reach).
        reach: float,
        /// Tiles a lane a subgroup's box may hold to be marked together
        /// ([`crate::passes::shadow::ShadowSettings::mark_rounds`]).
        rounds: uint,
        /// Tiles a block's box may hold; beyond, and at 0, point by point
        /// ([`crate::passes::shadow::ShadowSettings::mark_box`]).
        box_limit: uint,
    }

    /// The probe volume's grid, the first [`PROBE_HEADER_TEXELS`] texels of `probe_texels`
    /// (`probes.glsl`): probe (i, j, k) sits at `origin + spacing * (i, j, k)`.
    struct GpuProbeGrid {
        /// Position of probe (0, 0, 0).
        origin: vec3,
        /// How far a shaded point moves along its normal before it samples the probes (world
        /// units).
        normal_bias: float,
        /// Distance between neighbouring probes per axis.
        spacing: vec3,
        /// How far a shaded point moves towards the viewer before it samples the probes.
        view_bias: float,
        /// Probes per axis.
        counts: uvec3,
        /// `PROBE_VISIBILITY` when the Chebyshev visibility test weighs the probes.
        flags: uint,
    }

    /// Push constants of `probe_trace.comp` and `probe_blend.comp`: one update of a range of
    /// probes.
    struct ProbeUpdateParams {
        /// The update's random rotation of the ray directions, row 0 (xyz).
        rotation0: vec4,
        /// Row 1.
        rotation1: vec4,
        /// Row 2.
        rotation2: vec4,
        /// Constant environment radiance, or the environment map's multiplier.
        env: vec3,
        /// Rays per probe (a multiple of [`PROBE_RAY_GROUP`], at most [`PROBE_MAX_RAYS`]).
        rays: uint,
        /// Environment map width and height.
        env_size: uvec2,
        /// The first probe updated (the range wraps around the volume).
        first_probe: uint,
        /// Probes updated.
        probe_count: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Seed of the random numbers (the update's index).
        seed: uint,
        /// The least weight of the new estimate against the old (1: replace, 0: running mean).
        blend_min: float,
        /// Distance a ray that misses records (and the cap of every recorded distance).
        max_distance: float,
        /// Updates of a probe's life that replace its maps instead of blending (each adds a
        /// bounce of light before any averaging starts).
        warmup: uint,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
    }

    /// Push constants of `lightmap_bake.comp`: one sample for every lightmap texel.
    struct LightmapParams {
        /// Constant environment radiance, or the environment map's multiplier.
        env: vec3,
        /// Texels of all the lightmaps.
        texel_count: uint,
        /// Environment map width and height.
        env_size: uvec2,
        /// The sample's index (0 restarts the running means).
        sample_index: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Emissive triangles in the sampling table.
        light_count: uint,
        /// Punctual lights.
        punctual_count: uint,
        /// Occlusion maps: the length of the occlusion rays (scene units).
        radius: float,
        /// Padding.
        pad0: uint,
    }

    /// What the shadow rasterizer reports: the largest need over the layers rendered.
    struct ShadowStats {
        /// Tile-list entries one layer needed.
        entries: uint,
        /// Triangles in the fullest tile.
        tile_max: uint,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
    }

    /// Push constants of `shadow_moments.comp`.
    struct ShadowMomentParams {
        /// First texel of the layer.
        offset: uint,
        /// Width = height of the layer.
        size: uint,
        /// Box-filter radius in texels.
        radius: uint,
        /// 0: depth → moments, filtered along x; 1: moments filtered along y.
        direction: uint,
        /// Depth mapped to moment depth 1 ([`GpuShadowLayer::depth_far`]).
        depth_far: float,
        /// The first texel filtered (the layer's window, [`crate::passes::shadow::ShadowPlan::windows`]):
        /// column | row << 16; the dispatch covers the window from there.
        first: uint,
        /// The window's last texel (column | row << 16): taps clamp to the window.
        last: uint,
        /// The layer's first entry in `tile_list` (layer × tiles²).
        list_at: uint,
    }

    /// Push constants of `tonemap.comp`.
    struct TonemapParams {
        /// Width, height.
        size: uvec2,
        /// Linear multiplier (2^stops).
        exposure: float,
        /// [`crate::color::ToneCurve::code`]: 0 clamp, 1 ACES (Hill's fit), 2 Khronos PBR Neutral.
        curve: uint,
    }

    /// Push constants of the denoiser's kernels (`denoise_*.comp`).
    struct DenoiseParams {
        /// Width, height.
        size: uvec2,
        /// The à-trous iteration's tap spacing in pixels (1, 2, 4, ...).
        step: uint,
        /// [`DENOISE_DEMODULATE`] | [`DENOISE_PREFILTER`] | [`DENOISE_SPATIAL_VARIANCE`] |
        /// [`DENOISE_WIDE`] | [`DENOISE_EDGE_STOPPING`] | [`DENOISE_SPLIT`] | [`DENOISE_BOTH`].
        flags: uint,
        /// Luminance edge-stopping: |Δl| over this × the standard deviation of l.
        sigma_luminance: float,
        /// Normal edge-stopping: max(0, n·n')^this.
        sigma_normal: float,
        /// Depth edge-stopping: |Δz| over this × (|∇z · offset| + 0.1 % of z).
        sigma_depth: float,
        /// Added to the albedo the radiance is divided by.
        albedo_offset: float,
    }

    /// Push constants of `denoise_temporal.comp`: the frame's camera and the previous frame's
    /// (each as [`GpuCamera`] has it: origin, unit forward, right and up scaled to the view's half
    /// extents), with the blend's settings in the spare lanes.
    struct TemporalParams {
        /// This frame's camera position.
        origin: vec3,
        /// [`TEMPORAL_HISTORY`] | [`TEMPORAL_SPLIT`] | [`TEMPORAL_ORTHOGRAPHIC`] |
        /// [`TEMPORAL_PREV_ORTHOGRAPHIC`].
        flags: uint,
        /// This frame's unit forward.
        forward: vec3,
        /// The colour's least blend weight (SVGF's α, 0.2).
        alpha: float,
        /// This frame's right × half extent.
        right: vec3,
        /// The moments' least blend weight (SVGF's α_μ, 0.2).
        alpha_moments: float,
        /// This frame's up × half extent.
        up: vec3,
        /// A history tap is rejected when its point lies farther than this × its distance (plus
        /// two pixel footprints) from the tangent plane of the pixel's point.
        depth_tolerance: float,
        /// The previous frame's camera position.
        prev_origin: vec3,
        /// A history tap is rejected when its normal's cosine with the pixel's is below this.
        normal_tolerance: float,
        /// The previous frame's unit forward.
        prev_forward: vec3,
        /// Image width.
        width: uint,
        /// The previous frame's right × half extent.
        prev_right: vec3,
        /// Image height.
        height: uint,
        /// The previous frame's up × half extent.
        prev_up: vec3,
        /// History length (frames) from which the variance is the temporal moments' (below it,
        /// the variance carried through the blend, with the à-trous' spatial floor).
        variance_frames: float,
    }

    /// Push constants of `resolve.comp`.
    struct ResolveParams {
        /// Width, height.
        size: uvec2,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
    }

    /// Push constants of `sample_test.comp` (the sampling tests' kernel).
    test_struct SampleTestParams {
        /// Outgoing direction (local frame).
        wo: vec3,
        /// Microfacet alpha.
        alpha: float,
        /// 0 sample, 1 evaluate the pdf, 2 evaluate the BSDF of opaque surfaces (tests/brdf.rs),
        /// 3 the BSDF and its pdf at given directions, 4 the thin-film Fresnel
        /// (tests/iridescence.rs), 5 sample weights (the white furnace), 6 and 7 the path
        /// tracer's numbers over one pixel's samples and across pixels (tests/sampling/).
        mode: uint,
        /// Number of samples or directions.
        count: uint,
        /// Seed.
        seed: uint,
        /// 0 cosine, 1 microfacet, 2-4 dielectric BSDF (2 reflection side, 3 inside, 4 thin),
        /// 5 and 7 coated, 6 sheened, 8 iridescent, 9 anisotropic (`anisotropy`;
        /// spirv/sample_test.comp).
        kind: uint,
        /// Kind 9's `KHR_materials_anisotropy`: strength, the direction's x and y in the
        /// shading frame, metallic.
        anisotropy: vec4,
        /// Kind 9's base colour (grey).
        anisotropy_base: float,
        /// Padding.
        pad0: float,
        /// Padding.
        pad1: float,
        /// Padding.
        pad2: float,
    }

    /// Push constants of `ssao.comp` and `rtao.comp`.
    struct AoParams {
        /// The camera.
        camera: GpuCamera,
        /// AO radius r (world units).
        radius: float,
        /// SSAO plane bias (world units).
        bias: float,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Image width and height.
        size: uvec2,
        /// Frame index.
        frame: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Directions (SSAO) or rays (RTAO) per pixel.
        samples: uint,
        /// SSAO steps per direction.
        steps: uint,
        /// RTAO: the first ray of this dispatch.
        first_ray: uint,
        /// RTAO: rays of this dispatch.
        batch_rays: uint,
    }

    /// Push constants of `ao_blur.comp`.
    struct AoBlurParams {
        /// The camera (its origin unused).
        camera: GpuCamera,
        /// Plane-distance sigma, a fraction of the view depth.
        depth_sigma: float,
        /// Normal exponent.
        normal_exponent: float,
        /// Image width and height.
        size: uvec2,
    }

    /// Push constants of the IBL precomputation kernels (`ibl_*.comp`).
    struct IblParams {
        /// Source width, height (the environment map).
        src_size: uvec2,
        /// Chain level read (`ibl_downsample`).
        src_level: uint,
        /// First row of this dispatch (`ibl_sh`).
        first_row: uint,
        /// Width and height of the level written.
        dst_size: uvec2,
        /// Texel offset of the level written.
        dst_offset: uint,
        /// Samples (per axis for the LUT).
        samples: uint,
        /// Perceptual roughness of the level (prefilter).
        roughness: float,
        /// Padding.
        pad0: float,
        /// Padding.
        pad1: float,
        /// Padding.
        pad2: float,
    }

    /// Push constants of `light_sample_test.comp` (tests only).
    test_struct LightTestParams {
        /// Shading point (world).
        point: vec3,
        /// Padding.
        pad0: float,
        /// Its unit normal (world).
        normal: vec3,
        /// Padding.
        pad1: float,
        /// Mode (see the kernel).
        mode: uint,
        /// Number of samples or directions.
        count: uint,
        /// Seed.
        seed: uint,
        /// 0 the renderer's pdf, 1 a deliberately wrong one.
        variant: uint,
        /// Environment width, height.
        env_size: uvec2,
        /// Emissive triangles.
        light_count: uint,
        /// Padding.
        pad2: uint,
    }
}

gpu_constants! {
    /// A triangle's alpha bits (`BvhTri::v1[3]`; 0 opaque, 1 mask, 2 blend) when its alpha is
    /// below the cutoff wherever a ray can hit it: the walk never hits it (`GpuScene`'s upload
    /// classifies each alpha-tested triangle from its texels and leaves such triangles out of
    /// the BVH, but for lights, whose table names their BVH slots).
    ALPHA_NEVER_HIT: uint = 3;
    /// The most traversal stack entries held in registers (`bvh.glsl`): a scene whose walk never
    /// holds more ([`crate::gpu::bvh::GpuBvhNode::stack_depth`]) has the feature `shallow_bvh`, and
    /// its kernels walk with as many registers as its walk holds (`BVH_STACK`) instead of a stack
    /// in memory.
    BVH_REGISTERS: uint = 16;
    /// `GpuMaterial::flags.x`: the material is double-sided.
    MATERIAL_DOUBLE_SIDED: uint = 1;
    /// `GpuMaterial::flags.x`: `KHR_materials_volume` with a thickness: transmission refracts
    /// (else it is thin-walled).
    MATERIAL_VOLUME: uint = 2;
    /// `GpuMaterial::flags.x`: `KHR_materials_unlit`: the surface shows its base colour, lit or
    /// not (its emission is packed as 0). Read only by kernels specialised for it (`HAS_UNLIT`).
    MATERIAL_UNLIT: uint = 4;
    /// Texels of one [`GpuMaterial`] in `material_texels` (its 912 bytes).
    MATERIAL_TEXELS: uint = 57;
    /// [`GpuMaterial::textures`] slot of the base colour texture.
    MATERIAL_SLOT_BASE_COLOR: uint = 0;
    /// Slot of the metallic-roughness texture.
    MATERIAL_SLOT_METALLIC_ROUGHNESS: uint = 1;
    /// Slot of the emissive texture.
    MATERIAL_SLOT_EMISSIVE: uint = 2;
    /// Slot of the normal map (its scale in `tex_transform`'s second row, w).
    MATERIAL_SLOT_NORMAL: uint = 3;
    /// Slot of the occlusion map (glTF `occlusionTexture`, R; its strength in `tex_transform`'s
    /// second row, w). Only the hybrid renderer reads it: the G-buffer stores 1 + strength (r − 1)
    /// and the lighting pass scales the image-based (ambient) light by it, never direct light. The
    /// path tracer ignores it: it traces the occlusion itself.
    MATERIAL_SLOT_OCCLUSION: uint = 4;
    /// Slot of the height map of parallax occlusion mapping (`UMBRA_implicit`'s
    /// `parallax.heightTexture`, R: 1 on the triangle, 0 at `scale` below it). Looked up only by
    /// kernels specialised for parallax (`HAS_PARALLAX`).
    MATERIAL_SLOT_HEIGHT: uint = 5;
    /// Slot of `KHR_materials_specular`'s `specularTexture` (A: × `specularFactor`). Looked up
    /// only by kernels specialised for it (`HAS_SPECULAR_MAP`, with the next slot).
    MATERIAL_SLOT_SPECULAR: uint = 6;
    /// Slot of `KHR_materials_specular`'s `specularColorTexture` (sRGB RGB:
    /// × `specularColorFactor`).
    MATERIAL_SLOT_SPECULAR_COLOR: uint = 7;
    /// Slot of `KHR_materials_transmission`'s `transmissionTexture` (R: × `transmissionFactor`;
    /// left empty where the factor is 0). Looked up only by kernels specialised for it
    /// (`HAS_TRANSMISSION_MAP`).
    MATERIAL_SLOT_TRANSMISSION: uint = 8;
    /// Slot of `KHR_materials_clearcoat`'s `clearcoatTexture` (R: × `clearcoatFactor`; this and
    /// the next two left empty where the factor is 0). Looked up only by kernels specialised for
    /// the group (`HAS_CLEARCOAT_MAP`).
    MATERIAL_SLOT_CLEARCOAT: uint = 9;
    /// Slot of `clearcoatRoughnessTexture` (G: × `clearcoatRoughnessFactor`).
    MATERIAL_SLOT_CLEARCOAT_ROUGHNESS: uint = 10;
    /// Slot of `clearcoatNormalTexture`, the coat's own normal map (its scale in `tex_transform`'s
    /// second row, w). Without it the coat lies on the interpolated normal, not the base's mapped
    /// one.
    MATERIAL_SLOT_CLEARCOAT_NORMAL: uint = 11;
    /// Slot of `KHR_materials_iridescence`'s `iridescenceTexture` (R: × `iridescenceFactor`; this
    /// and the next left empty where the factor is 0). Looked up only by kernels specialised for
    /// the group (`HAS_IRIDESCENCE_MAP`).
    MATERIAL_SLOT_IRIDESCENCE: uint = 13;
    /// Slot of `iridescenceThicknessTexture` (G: the film's thickness from
    /// `iridescenceThicknessMinimum` at 0 to `iridescenceThicknessMaximum` at 1).
    MATERIAL_SLOT_IRIDESCENCE_THICKNESS: uint = 14;
    /// The texel of [`GpuMaterial::clearcoat`] in a material's texels.
    MATERIAL_CLEARCOAT_TEXEL: uint = 50;
    /// The texel of [`GpuMaterial::parallax`] in a material's texels.
    MATERIAL_PARALLAX_TEXEL: uint = 51;
    /// The texel of [`GpuMaterial::sheen`] in a material's texels.
    MATERIAL_SHEEN_TEXEL: uint = 52;
    /// The texel of [`GpuMaterial::iridescence`] in a material's texels.
    MATERIAL_IRIDESCENCE_TEXEL: uint = 53;
    /// Slot of `KHR_materials_anisotropy`'s `anisotropyTexture` (RG: the direction in tangent
    /// space, `2 x - 1`; B: × `anisotropyStrength`; left empty where the strength is 0). Looked
    /// up only by kernels specialised for it (`HAS_ANISOTROPY_MAP`).
    MATERIAL_SLOT_ANISOTROPY: uint = 12;
    /// The texel of [`GpuMaterial::anisotropy`] in a material's texels.
    MATERIAL_ANISOTROPY_TEXEL: uint = 54;
    /// Slot of `KHR_materials_sheen`'s `sheenColorTexture` (sRGB RGB: × `sheenColorFactor`; this
    /// and the next left empty where the material has no sheen). Looked up only by kernels
    /// specialised for the group (`HAS_SHEEN_MAP`).
    MATERIAL_SLOT_SHEEN_COLOR: uint = 15;
    /// Slot of `sheenRoughnessTexture` (A: × `sheenRoughnessFactor`).
    MATERIAL_SLOT_SHEEN_ROUGHNESS: uint = 16;
    /// Slot of `KHR_materials_diffuse_transmission`'s `diffuseTransmissionTexture` (A:
    /// × `diffuseTransmissionFactor`; this and the next left empty where the factor is 0). Looked
    /// up only by kernels specialised for the group (`HAS_DIFFUSE_TRANSMISSION_MAP`).
    MATERIAL_SLOT_DIFFUSE_TRANSMISSION: uint = 17;
    /// Slot of `diffuseTransmissionColorTexture` (sRGB RGB: × `diffuseTransmissionColorFactor`).
    MATERIAL_SLOT_DIFFUSE_TRANSMISSION_COLOR: uint = 18;
    /// The texel of [`GpuMaterial::diffuse_transmission`] in a material's texels.
    MATERIAL_DIFFUSE_TRANSMISSION_TEXEL: uint = 55;
    /// Slot of `KHR_materials_volume`'s `thicknessTexture` (G: × `thicknessFactor`; left empty
    /// without a volume). Looked up only by kernels specialised for it (`HAS_THICKNESS_MAP`).
    MATERIAL_SLOT_THICKNESS: uint = 19;
    /// The texel of [`GpuMaterial::volume`] in a material's texels.
    MATERIAL_VOLUME_TEXEL: uint = 56;
    /// Texture slots a material has room for (each with two `tex_transform` rows).
    MATERIAL_TEXTURE_SLOTS: uint = 20;
    /// `GpuTexture::flags`: clamp s.
    TEXTURE_WRAP_S_CLAMP: uint = 1;
    /// `GpuTexture::flags`: mirror s.
    TEXTURE_WRAP_S_MIRROR: uint = 2;
    /// `GpuTexture::flags`: clamp t.
    TEXTURE_WRAP_T_CLAMP: uint = 4;
    /// `GpuTexture::flags`: mirror t.
    TEXTURE_WRAP_T_MIRROR: uint = 8;
    /// `GpuTexture::flags`: bilinear magnification (otherwise nearest).
    TEXTURE_LINEAR: uint = 16;
    /// `GpuTexture::flags`: the image is sRGB-encoded colour (its texels are decoded to linear
    /// when uploaded; no kernel reads this bit).
    TEXTURE_SRGB: uint = 32;
    /// `GpuTexture::flags`: bilinear within a level when minified (otherwise nearest).
    TEXTURE_MIN_LINEAR: uint = 64;
    /// `GpuTexture::flags`: blend the two nearest mip levels (otherwise the nearest level).
    TEXTURE_MIP_LINEAR: uint = 128;
    /// `GpuLight::direction_kind.w` of a point light.
    LIGHT_POINT: float = 0.0;
    /// `GpuLight::direction_kind.w` of a spot light.
    LIGHT_SPOT: float = 1.0;
    /// `GpuLight::direction_kind.w` of a directional light.
    LIGHT_DIRECTIONAL: float = 2.0;
    /// `GpuShadowLayer::kind`: an orthographic layer (directional lights).
    SHADOW_ORTHOGRAPHIC: uint = 0;
    /// `GpuShadowLayer::kind`: a perspective layer (spot lights, cube faces).
    SHADOW_PERSPECTIVE: uint = 1;
    /// A light's shadow record (`shadow_texels`): no map, shadow rays.
    SHADOW_LIGHT_NONE: uint = 0;
    /// A light's shadow record: one layer.
    SHADOW_LIGHT_SINGLE: uint = 1;
    /// A light's shadow record: six cube faces (+x, −x, +y, −y, +z, −z).
    SHADOW_LIGHT_CUBE: uint = 2;
    /// A light's shadow record: cascades over the view depth.
    SHADOW_LIGHT_CASCADES: uint = 3;
    /// Side of a shadow rasterizer tile in texels (its workgroup is one tile).
    SHADOW_TILE: uint = 16;
    /// Side of the block of a tile's texels one `shadow_raster` invocation tests (its workgroup
    /// is `SHADOW_TILE / SHADOW_QUAD` invocations a side).
    SHADOW_QUAD: uint = 2;
    /// The most cascades of a directional light.
    SHADOW_MAX_CASCADES: uint = 8;
    /// Side in pixels of the block of G-buffer pixels one `shadow_mark` invocation marks for.
    SHADOW_MARK_BLOCK: uint = 4;
    /// Words a layer in the shadow maps' indirect dispatches: 0–2 the rendered tiles' (one
    /// workgroup a tile), 3 a pad, 4–6 the fill's over the large triangles the count step listed
    /// (64 a workgroup), 7 their count.
    SHADOW_DISPATCH_WORDS: uint = 8;
    /// The largest box (texels a side) a triangle rasterizes itself in: smaller ones loop over
    /// their own texels, larger ones go through the tiles.
    SHADOW_DIRECT_SPAN: uint = 16;
    /// Texels of `shadow_texels` before the lights' records: the filter settings.
    SHADOW_HEADER_TEXELS: uint = 2;
    /// Texels of one [`GpuShadowLayer`] in `shadow_texels` (its 96 bytes).
    SHADOW_LAYER_TEXELS: uint = 6;
    /// Texels of `probe_texels` before the probes' states: the grid ([`GpuProbeGrid`]).
    PROBE_HEADER_TEXELS: uint = 3;
    /// Interior texels a side of a probe's octahedral irradiance map (one more each side is the
    /// border that makes bilinear filtering wrap).
    PROBE_IRRADIANCE_TEXELS: uint = 6;
    /// Interior texels a side of a probe's octahedral distance map.
    PROBE_DISTANCE_TEXELS: uint = 14;
    /// Rays of one `probe_trace` workgroup: rays per probe come in multiples of it.
    PROBE_RAY_GROUP: uint = 64;
    /// Most rays per probe and update (the blend keeps them in shared memory).
    PROBE_MAX_RAYS: uint = 256;
    /// A probe's state `x`: the probe is active (not inside geometry).
    PROBE_ACTIVE: uint = 1;
    /// [`GpuProbeGrid::flags`]: weigh probes by Chebyshev visibility.
    PROBE_VISIBILITY: uint = 1;
    /// [`DenoiseParams::flags`]: divide the radiance by the albedo before filtering and
    /// multiply it back after (the texture detail is not blurred).
    DENOISE_DEMODULATE: uint = 1;
    /// [`DenoiseParams::flags`]: the luminance weight reads a 3×3 Gaussian of the variance.
    DENOISE_PREFILTER: uint = 2;
    /// [`DenoiseParams::flags`]: in the first iteration, the luminance weight's variance is at
    /// least the spread of the neighbours' luminance on the same surface, × min(1, 4 / samples).
    DENOISE_SPATIAL_VARIANCE: uint = 8;
    /// [`DenoiseParams::flags`]: 5×5 taps (the B3 spline) per iteration instead of 3×3.
    DENOISE_WIDE: uint = 16;
    /// [`DenoiseParams::flags`]: weigh taps by normal, depth and luminance (else the plain
    /// B3-spline: a blur, for tests that must catch it).
    DENOISE_EDGE_STOPPING: uint = 4;
    /// [`DenoiseParams::flags`]: the path target split its radiance by the first hit's lobes
    /// (diffuse, specular); prepare and remodulate read the split's buffers.
    DENOISE_SPLIT: uint = 32;
    /// [`DenoiseParams::flags`]: the à-trous iteration filters two images at once (`dn_in` into
    /// `dn_out`, `dn_in2` into `dn_out2`: the lobe split's diffuse and specular parts), their
    /// taps' normal and depth weights computed once; else `dn_in2` and `dn_out2` are unread.
    DENOISE_BOTH: uint = 64;
    /// [`TemporalParams::flags`]: the history holds a previous frame (else every pixel starts
    /// afresh).
    TEMPORAL_HISTORY: uint = 1;
    /// [`TemporalParams::flags`]: the specular part of the lobe split is accumulated too.
    TEMPORAL_SPLIT: uint = 2;
    /// [`TemporalParams::flags`]: this frame's camera is orthographic.
    TEMPORAL_ORTHOGRAPHIC: uint = 4;
    /// [`TemporalParams::flags`]: the previous frame's camera is orthographic.
    TEMPORAL_PREV_ORTHOGRAPHIC: uint = 8;
    /// Longest history a pixel keeps (frames).
    TEMPORAL_MAX_LENGTH: float = 65536.0;
    /// Below this an albedo channel the radiance is divided by (denoiser, lobe split) is raised
    /// to it: a black surface (an emitter, a dark texel) is then divided by 0.01 and multiplied
    /// back by the same, so nothing is lost, and the filter's luminance weight keeps its
    /// amplified radiance apart from its neighbours'.
    DENOISE_MIN_ALBEDO: float = 0.01;
    /// The G-buffer's material index where no surface was hit.
    GBUFFER_NO_SURFACE: uint = 0xffffffff;
    /// [`GpuReservoir::light`]: the reservoir holds no sample.
    RESTIR_NONE: uint = 0xffffffff;
    /// [`GpuReservoir::light`]: the sample is punctual light `light & !RESTIR_PUNCTUAL` (else a
    /// point on emissive-table entry `light`).
    RESTIR_PUNCTUAL: uint = 0x80000000;
    /// [`GpuReservoir::flags`]: the weight includes the sample's visibility.
    RESTIR_VISIBLE: uint = 1;
    /// The path tracer's first-hit reuse (`ris_spatial`): neighbours whose previous reservoirs a
    /// pixel's first hit takes.
    RIS_REUSE_NEIGHBOURS: uint = 4;
    /// The path tracer's first-hit reuse (`ris_spatial`): radius of the neighbourhood, pixels.
    RIS_REUSE_RADIUS: float = 8.0;
    /// The path tracer's first-hit reuse: a reservoir counts at most this many times the
    /// candidates (M capped, as ReSTIR caps its history).
    RIS_REUSE_CAP: float = 4.0;
    /// Punctual lights a shading point evaluates at most (`punctual_direct`, `path_shade`): all of
    /// them up to this many, beyond it this many picked by power.
    PUNCTUAL_ALL: uint = 16;
    /// `wavefront.comp`: fields of a path's state in `wf_paths` (each `capacity` texels): origin
    /// and the pdf of the sample that made the ray; direction and depth; throughput and the
    /// shadow rays queued this round; radiance so far and its non-finite sources; the first hit's
    /// albedo, normal and distance, emission; the closest hit of this round's ray.
    WAVE_FIELDS: uint = 8;
    /// `wavefront.comp`: texels of one queued shadow ray (origin and tmax, direction, the
    /// contribution if unblocked and its non-finite source bit).
    WAVE_SHADOW_TEXELS: uint = 3;
    /// `wavefront.comp` with the denoiser's lobe split (`split_lobes`): fields of a path's state
    /// after the [`WAVE_FIELDS`]: the specular part of the radiance so far; the specular share
    /// of what the path gathers beyond the first hit and the first hit's metallic.
    WAVE_SPLIT_FIELDS: uint = 2;
    /// `wavefront.comp` with the lobe split: texels of a queued shadow ray after the
    /// [`WAVE_SHADOW_TEXELS`]: its contribution's specular part.
    WAVE_SPLIT_SHADOW_TEXELS: uint = 1;
    /// `wavefront.comp`: the closest hit's triangle where the ray left the scene.
    WAVE_MISS: uint = 0xffffffff;
    /// Implicit shapes (`implicit.glsl`): a sphere (params: radius).
    IMPLICIT_SPHERE: uint = 0;
    /// A box (params: half extents).
    IMPLICIT_BOX: uint = 1;
    /// A rounded box (params: half extents less the radius, radius).
    IMPLICIT_ROUNDED_BOX: uint = 2;
    /// A torus around Y (params: major, minor radius).
    IMPLICIT_TORUS: uint = 3;
    /// A capsule along Y (params: half height, radius).
    IMPLICIT_CAPSULE: uint = 4;
    /// A capped cylinder along Y (params: half height, radius).
    IMPLICIT_CYLINDER: uint = 5;
    /// A half-space (params: unit normal, offset).
    IMPLICIT_PLANE: uint = 6;
    /// The two distances on top of the stack combined by min (smooth with the instruction's
    /// smoothness > 0); this and the next two are operations, every lower kind a primitive.
    IMPLICIT_UNION: uint = 16;
    /// ... by max.
    IMPLICIT_INTERSECTION: uint = 17;
    /// ... by max(a, -b).
    IMPLICIT_SUBTRACTION: uint = 18;
    /// Texels of a shape's header in `bvh_tri_texels`: counts, step scale and hit threshold, then
    /// the world-to-node rows.
    IMPLICIT_HEADER_TEXELS: uint = 4;
    /// Texels per instruction: kind and scale (or smoothness), parameters, the node-to-primitive
    /// rows.
    IMPLICIT_INSTRUCTION_TEXELS: uint = 5;
    /// The distance stack's depth.
    IMPLICIT_MAX_STACK: uint = 8;
    /// Sphere-tracing steps per shape and ray; a march that runs out is taken as a miss and
    /// counted ([`PathStats::marches_exhausted`]).
    IMPLICIT_MAX_STEPS: uint = 128;
    /// Over-relaxation factor of the sphere tracer (Keinert et al. 2014), dropped to 1 at the
    /// first step whose bounding spheres do not overlap.
    IMPLICIT_RELAXATION: float = 1.2;
}

scene_bindings! {
    /// BVH nodes ([`GpuBvhNode`]), four RGBA32UI texels each.
    bvh_node_texels: readonly texels rgba32ui,
    /// BVH triangles ([`BvhTri`]), three RGBA32UI texels each.
    bvh_tri_texels: readonly texels rgba32ui,
    /// [`GpuTriangle`]s in BVH order, two RGBA32UI texels each (`shading.glsl` reads them:
    /// on llvmpipe a texel read is a gather, a storage-buffer read a loop over the lanes).
    triangle_texels: readonly texels rgba32ui,
    /// [`GpuVertex`]s, three RGBA32UI texels each (float bits).
    vertex_texels: readonly texels rgba32ui,
    /// [`GpuMaterial`]s, [`MATERIAL_TEXELS`] RGBA32UI texels each (float bits but for `flags`,
    /// `textures`).
    material_texels: readonly texels rgba32ui,
    /// [`GpuTexture`]s, two RGBA32UI texels each.
    texture_texels: readonly texels rgba32ui,
    /// The sRGB decoding table (an `f32`'s bits in each texel's first word), then every
    /// texture's texels as linear RGBA16 (unorm, sRGB decoded at upload), one RG32UI texel each.
    scene_texels: readonly texels rg32ui,
    /// The emissive-triangle sampling table ([`GpuLightTri`]), one RGBA32UI texel each.
    light_texels: readonly texels rgba32ui,
    /// Punctual lights ([`GpuLight`]), four RGBA32UI texels each.
    punctual_texels: readonly texels rgba32ui,
    /// Environment texels as RGBA32UI (float bits): rgb radiance, density over (u, v).
    env_texels: readonly texels rgba32ui,
    /// The environment's alias tables ([`crate::environment::AliasEntry`], RG32UI: the keep
    /// probability's bits, the alias): the rows' (one entry a row), then each row's (one a
    /// texel).
    env_alias: readonly texels rg32ui,
}

kernels! {
    /// The progressive path tracer.
    kernel pathtrace {
        scene: full [lights, punctual, env_map, textures, transmission, alpha, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, parallax, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
        push: PathParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            ggx_walter: bool = false,
            power_heuristic: bool = true,
            unweighted_bsdf_hits: bool = false,
            light_sampling: bool = true,
            bsdf_hits: bool = true,
            low_discrepancy: bool = true,
            solid_angle_emitters: bool = false,
            split_lobes: bool = false,
            ris: bool = false,
            ris_temporal: bool = false,
            ris_spatial: bool = false,
            count_lanes: bool = false
        },
        bindings: {
            /// Running mean rgb, sample count (vec4 per pixel).
            accum: readwrite buffer [vec4],
            /// Running mean of the squared samples rgb.
            moment: readwrite buffer [vec4],
            /// Base colour at the first hit, mean over the samples (a miss counts the
            /// environment's colour, alpha 0: alpha is the fraction of samples that hit).
            aov_albedo: readwrite buffer [vec4],
            /// Shading normal and distance at the first hit of the pixel's sample 0.
            aov_normal_depth: readwrite buffer [vec4],
            /// Radiance emitted at the first hit (or the environment a camera ray sees), mean
            /// over the samples: the part of the image the denoiser leaves unfiltered.
            aov_emission: readwrite buffer [vec4],
            /// `split_lobes`: the mean of the radiance's specular part rgb (what left the first
            /// hit through another lobe than the diffuse one), the mean of the diffuse part's
            /// luminance squared over the first hit's base colour. Unread otherwise.
            aov_specular: readwrite buffer [vec4],
            /// `split_lobes`: the mean of the first hit's specular albedo rgb (the specular
            /// part's divisor), the mean of the specular part's luminance squared over it.
            aov_split: readwrite buffer [vec4],
            /// Counters ([`PathStats`]).
            stats: readwrite buffer PathStats,
            /// `ris_temporal` or `ris_spatial`: the first-hit reservoirs of the previous sample
            /// index, one per pixel. Unread otherwise.
            ris_prev: readonly buffer [GpuPathReservoir],
            /// `ris_temporal` or `ris_spatial`: this sample index's first-hit reservoirs (every
            /// pixel writes its own). Unwritten otherwise.
            ris_next: readwrite buffer [GpuPathReservoir],
        }
    }

    /// The wavefront path tracer (Laine, Karras and Aila 2013): the path tracer's paths in
    /// queues, each stage a specialisation of this kernel (the `wf_*` constants, one true).
    kernel wavefront {
        scene: full [lights, punctual, env_map, textures, transmission, alpha, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, parallax, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
        push: WaveParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            ggx_walter: bool = false,
            power_heuristic: bool = true,
            unweighted_bsdf_hits: bool = false,
            light_sampling: bool = true,
            bsdf_hits: bool = true,
            low_discrepancy: bool = true,
            solid_angle_emitters: bool = false,
            wf_camera_rays: bool = false,
            wf_extend: bool = false,
            wf_shade: bool = false,
            wf_connect: bool = false,
            wf_accumulate: bool = false,
            split_lobes: bool = false
        },
        bindings: {
            /// The camera.
            wf_camera: readonly buffer GpuCamera,
            /// The paths' state: [`WAVE_FIELDS`] fields of `capacity` RGBA32UI texels each (and
            /// [`WAVE_SPLIT_FIELDS`] more with `split_lobes`), then the shadow rays,
            /// [`WAVE_SHADOW_TEXELS`] texels each (and [`WAVE_SPLIT_SHADOW_TEXELS`] more with
            /// `split_lobes`), `shadows_per_path` per path.
            wf_paths: readwrite texels rgba32ui,
            /// The queues: two of paths to extend (by round parity), then one of paths with
            /// shadow rays; `capacity` entries each.
            wf_queue: readwrite texels r32ui,
            /// Per queue and round, a `VkDispatchIndirectCommand` (workgroups x, 1, 1) and the
            /// entries: the ray queue of round r at 4 r, the shadow queue of round r at
            /// 4 (max_bounces + 2 + r).
            wf_counts: readwrite buffer [uint],
            /// Running mean rgb, sample count (vec4 per pixel).
            accum: readwrite buffer [vec4],
            /// Running mean of the squared samples rgb.
            moment: readwrite buffer [vec4],
            /// Base colour at the first hit, mean over the samples.
            aov_albedo: readwrite buffer [vec4],
            /// Shading normal and distance at the first hit of the pixel's sample 0.
            aov_normal_depth: readwrite buffer [vec4],
            /// Radiance emitted at the first hit, mean over the samples.
            aov_emission: readwrite buffer [vec4],
            /// `split_lobes`: the mean of the radiance's specular part rgb, the mean of the
            /// diffuse part's luminance squared over the first hit's base colour (as
            /// `pathtrace`'s). Unread otherwise.
            aov_specular: readwrite buffer [vec4],
            /// `split_lobes`: the mean of the first hit's specular albedo rgb, the mean of the
            /// specular part's luminance squared over it (as `pathtrace`'s).
            aov_split: readwrite buffer [vec4],
            /// Counters ([`PathStats`]).
            stats: readwrite buffer PathStats,
        }
    }

    /// A path target's running mean into an image.
    kernel resolve {
        scene: none,
        push: ResolveParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The running mean.
            accum: readonly buffer [vec4],
            /// The image written.
            out_color: writeonly image rgba32f,
        }
    }

    /// Denoiser, step 1: a path target's running mean less the first hit's emission, divided by
    /// its albedo, and the variance of its luminance, into an image; the normal and depth into
    /// another.
    kernel denoise_prepare {
        scene: none,
        push: DenoiseParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The running mean rgb, sample count.
            accum: readonly buffer [vec4],
            /// The running mean of the squared samples rgb.
            moment: readonly buffer [vec4],
            /// Base colour at the first hit (alpha 0 for a miss).
            aov_albedo: readonly buffer [vec4],
            /// Shading normal and distance at the first hit.
            aov_normal_depth: readonly buffer [vec4],
            /// Radiance emitted at the first hit.
            aov_emission: readonly buffer [vec4],
            /// With [`DENOISE_SPLIT`]: the path target's `aov_specular` (else unread).
            aov_specular: readonly buffer [vec4],
            /// With [`DENOISE_SPLIT`]: the path target's `aov_split` (else unread).
            aov_split: readonly buffer [vec4],
            /// Demodulated radiance rgb (with [`DENOISE_SPLIT`], its diffuse part), the variance
            /// of its luminance's mean.
            dn_color: writeonly image rgba32f,
            /// With [`DENOISE_SPLIT`]: the demodulated specular part and its variance (else
            /// unwritten).
            dn_specular: writeonly image rgba32f,
            /// Unit normal xyz and distance (−1 for a miss).
            dn_guide: writeonly image rgba32f,
            /// The pixel's sample count.
            dn_samples: writeonly image r32f,
            /// What the radiance (with [`DENOISE_SPLIT`], its diffuse part) was divided by, rgb.
            dn_albedo: writeonly image rgba32f,
            /// With [`DENOISE_SPLIT`]: what the specular part was divided by, rgb (else
            /// unwritten).
            dn_spec_albedo: writeonly image rgba32f,
            /// Radiance emitted at the first hit, rgb (left out of the filter, added back).
            dn_emission: writeonly image rgba32f,
        }
    }

    /// Denoiser, temporal step (between steps 1 and 2, [`crate::passes::temporal`]): the
    /// prepared frame blended with its reprojected history.
    kernel denoise_temporal {
        scene: none,
        push: TemporalParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// This frame's demodulated radiance (diffuse part) and its variance (step 1's).
            dn_color: readonly image rgba32f,
            /// With [`TEMPORAL_SPLIT`]: its specular part and variance (else unread).
            dn_specular: readonly image rgba32f,
            /// This frame's unit normal and distance (−1 for a miss).
            dn_guide: readonly image rgba32f,
            /// In: this frame's sample count; out: the accumulated estimate's effective count.
            dn_samples: readwrite image r32f,
            /// In: this frame's divisor of the colour (diffuse part); out: the accumulated one.
            dn_albedo: readwrite image rgba32f,
            /// With [`TEMPORAL_SPLIT`], in: this frame's divisor of the specular part; out: the
            /// accumulated one (else untouched).
            dn_spec_albedo: readwrite image rgba32f,
            /// In: this frame's first-hit emission; out: the accumulated one.
            dn_emission: readwrite image rgba32f,
            /// The history's colour (diffuse part) and variance.
            hist_color: readonly image rgba32f,
            /// The history's specular part and variance.
            hist_specular: readonly image rgba32f,
            /// The history's luminance moments: diffuse `E[l]`, `E[l²]`, specular `E[l]`, `E[l²]`.
            hist_moments: readonly image rgba32f,
            /// The history's normal and distance (its frame's guide).
            hist_guide: readonly image rgba32f,
            /// The history's length (frames) and the sum of its colour weights squared.
            hist_state: readonly image rgba32f,
            /// The history's divisor of the colour (diffuse part).
            hist_albedo: readonly image rgba32f,
            /// The history's divisor of the specular part.
            hist_spec_albedo: readonly image rgba32f,
            /// The history's first-hit emission.
            hist_emission: readonly image rgba32f,
            /// The accumulated colour (diffuse part) and its variance.
            out_color: writeonly image rgba32f,
            /// With [`TEMPORAL_SPLIT`]: the accumulated specular part and its variance.
            out_specular: writeonly image rgba32f,
            /// The next history's moments.
            out_moments: writeonly image rgba32f,
            /// The next history's guide (this frame's).
            out_guide: writeonly image rgba32f,
            /// The next history's length and weights squared.
            out_state: writeonly image rgba32f,
            /// The next history's divisor of the colour (diffuse part).
            out_albedo: writeonly image rgba32f,
            /// With [`TEMPORAL_SPLIT`]: the next history's divisor of the specular part.
            out_spec_albedo: writeonly image rgba32f,
            /// The next history's first-hit emission.
            out_emission: writeonly image rgba32f,
        }
    }

    /// Denoiser, step 2: one edge-avoiding à-trous iteration.
    kernel denoise_atrous {
        scene: none,
        push: DenoiseParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// Radiance rgb and its variance, from the previous step.
            dn_in: readonly image rgba32f,
            /// Unit normal xyz and distance (−1 for a miss).
            dn_guide: readonly image rgba32f,
            /// The pixel's sample count (read by the first iteration).
            dn_samples: readonly image r32f,
            /// Filtered radiance rgb and its variance.
            dn_out: writeonly image rgba32f,
            /// With [`DENOISE_BOTH`]: the second image's radiance and variance (else unread).
            dn_in2: readonly image rgba32f,
            /// With [`DENOISE_BOTH`]: the second image filtered (else unwritten).
            dn_out2: writeonly image rgba32f,
        }
    }

    /// Denoiser, step 3: the filtered radiance multiplied back by the albedo, the emission added.
    kernel denoise_remodulate {
        scene: none,
        push: DenoiseParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The filtered, demodulated radiance (with [`DENOISE_SPLIT`], its diffuse part).
            dn_in: readonly image rgba32f,
            /// With [`DENOISE_SPLIT`]: the filtered, demodulated specular part (else unread).
            dn_specular: readonly image rgba32f,
            /// What the radiance (diffuse part) was divided by (step 1's, or the temporal
            /// step's accumulated one).
            dn_albedo: readonly image rgba32f,
            /// With [`DENOISE_SPLIT`]: what the specular part was divided by (else unread).
            dn_spec_albedo: readonly image rgba32f,
            /// Radiance emitted at the first hit (added back).
            dn_emission: readonly image rgba32f,
            /// The denoised image: radiance rgb, alpha 1.
            out_color: writeonly image rgba32f,
        }
    }

    /// The ray-cast G-buffer.
    kernel gbuffer {
        scene: full [textures, alpha, colors, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, parallax, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, shallow_bvh],
        push: GBufferParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// View-space depth.
            gb_depth: writeonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: writeonly image rgba16f,
            /// Base colour, metallic.
            gb_base: writeonly image rgba16f,
            /// Emission, material occlusion.
            gb_emission: writeonly image rgba16f,
            /// Material index, octahedral geometric normal, UV1 (float bits).
            gb_material: writeonly image rgba32ui,
            /// The layer textures' texels, unorm8 × 4 a word (written only where the scene has them).
            gb_layers: writeonly image rgba32ui,
            /// More layer textures' texels (the sheen's, the diffuse transmission's), unorm8 × 4
            /// a word (written only where the scene has them).
            gb_layers2: writeonly image rgba32ui,
        }
    }

    /// Deferred lighting of a G-buffer.
    kernel deferred {
        scene: full [textures, lights, punctual, env_map, alpha, transmission, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, parallax, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
        push: DeferredParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            shadow_maps: bool = false,
            shadow_pcf: bool = false,
            shadow_pcss: bool = false,
            shadow_moments: bool = false,
            probes: bool = false,
            lightmaps: bool = false,
            restir: bool = false,
            shadow_sized: bool = false
        },
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// Base colour, metallic.
            gb_base: readonly image rgba16f,
            /// Emission, material occlusion.
            gb_emission: readonly image rgba16f,
            /// Material index, octahedral geometric normal, UV1 (float bits).
            gb_material: readonly image rgba32ui,
            /// The layer textures' texels, unorm8 × 4 a word (read only where the scene has them).
            gb_layers: readonly image rgba32ui,
            /// More layer textures' texels (the sheen's, the diffuse transmission's).
            gb_layers2: readonly image rgba32ui,
            /// Shadow maps: the filter settings, each punctual light's record, the layers
            /// ([`GpuShadowLayer`]); one texel when the lights cast shadow rays.
            shadow_texels: readonly texels rgba32ui,
            /// Shadow maps: linear depth per texel, every layer.
            shadow_depth: readonly texels r32f,
            /// Shadow maps: filtered depth moments per texel (`moments` only).
            shadow_moments: readonly texels rgba32f,
            /// The lit image.
            out_color: writeonly image rgba32f,
            /// The split-sum BRDF table.
            ibl_lut: readonly buffer [vec4],
            /// The prefiltered environment chain.
            ibl_prefiltered: readonly buffer [vec4],
            /// SH9 irradiance coefficients.
            ibl_sh: readonly buffer [vec4],
            /// Ambient occlusion multiplying the IBL term (1 = unoccluded); 1×1 for none.
            ao_image: readonly image r32f,
            /// Probe volume: the grid and the probes' states; one texel without probes.
            probe_texels: readonly texels rgba32ui,
            /// Probe volume: octahedral irradiance.
            probe_irradiance: readonly texels rgba32f,
            /// Probe volume: octahedral distance moments.
            probe_distance: readonly texels rgba32f,
            /// Lightmaps: the header (texels a side, materials), per material its map's index + 1
            /// (0: none), then every map's ambient irradiance (rgb); one texel without lightmaps.
            lightmap_texels: readonly texels rgba32f,
            /// ReSTIR DI: the frame's reservoirs (`restir` only; one element otherwise).
            reservoirs: readonly buffer [GpuReservoir],
        }
    }

    /// ReSTIR DI's candidates and temporal reuse ([`crate::passes::restir`]).
    kernel restir_initial {
        scene: full [textures, lights, punctual, alpha, transmission, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, shallow_bvh],
        push: RestirParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            unbiased: bool = false,
            temporal: bool = true
        },
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// Base colour, metallic.
            gb_base: readonly image rgba16f,
            /// Material index, octahedral geometric normal, UV1 (float bits).
            gb_material: readonly image rgba32ui,
            /// The layer textures' texels, unorm8 × 4 a word (read only where the scene has them).
            gb_layers: readonly image rgba32ui,
            /// More layer textures' texels (the sheen's, the diffuse transmission's).
            gb_layers2: readonly image rgba32ui,
            /// The previous frame's camera.
            prev_camera: readonly buffer GpuCamera,
            /// The previous frame's reservoirs.
            history: readonly buffer [GpuReservoir],
            /// This frame's reservoirs before spatial reuse.
            reservoirs: readwrite buffer [GpuReservoir],
        }
    }

    /// ReSTIR DI's spatial reuse ([`crate::passes::restir`]).
    kernel restir_spatial {
        scene: full [textures, lights, punctual, alpha, transmission, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, diffuse_transmission, anisotropy, shallow_bvh],
        push: RestirParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            unbiased: bool = false
        },
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// Base colour, metallic.
            gb_base: readonly image rgba16f,
            /// Material index, octahedral geometric normal, UV1 (float bits).
            gb_material: readonly image rgba32ui,
            /// The layer textures' texels, unorm8 × 4 a word (read only where the scene has them).
            gb_layers: readonly image rgba32ui,
            /// More layer textures' texels (the sheen's, the diffuse transmission's).
            gb_layers2: readonly image rgba32ui,
            /// The reservoirs before spatial reuse.
            reservoirs_in: readonly buffer [GpuReservoir],
            /// The frame's reservoirs.
            reservoirs_out: readwrite buffer [GpuReservoir],
        }
    }

    /// Screen-space ambient occlusion.
    kernel ssao {
        scene: none,
        push: AoParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// AO (1 = unoccluded).
            out_ao: writeonly image r32f,
        }
    }

    /// Ray-traced ambient occlusion (SSAO's ground truth).
    kernel rtao {
        scene: full [textures, alpha, colors, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, implicit, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, shallow_bvh],
        push: AoParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// Material index, octahedral geometric normal, UV1 (float bits).
            gb_material: readonly image rgba32ui,
            /// AO, accumulated over batches of rays.
            out_ao: readwrite image r32f,
        }
    }

    /// The depth-aware AO blur.
    kernel ao_blur {
        scene: none,
        push: AoBlurParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The AO to blur.
            ao_in: readonly image r32f,
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// Shading normal xyz, perceptual roughness.
            gb_normal: readonly image rgba16f,
            /// The blurred AO.
            out_ao: writeonly image r32f,
        }
    }

    /// HDR to display.
    kernel tonemap {
        scene: none,
        push: TonemapParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// Linear HDR input.
            src: readonly image rgba32f,
            /// sRGB-encoded output.
            dst: writeonly image rgba8,
        }
    }

    /// The split-sum BRDF table.
    kernel ibl_lut {
        scene: none,
        push: IblParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The table.
            lut: readwrite buffer [vec4],
        }
    }

    /// One level of the environment's box-filtered chain.
    kernel ibl_downsample {
        scene: full [],
        push: IblParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The chain (level 0 is the map itself, not stored).
            chain: readwrite buffer [vec4],
        }
    }

    /// One roughness level of the prefiltered environment.
    kernel ibl_prefilter {
        scene: full [],
        push: IblParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The box-filtered chain.
            chain: readonly buffer [vec4],
            /// The prefiltered levels.
            prefiltered: readwrite buffer [vec4],
        }
    }

    /// SH9 irradiance of the environment.
    kernel ibl_sh {
        scene: full [],
        push: IblParams,
        local: [128, 1, 1],
        spec: {},
        bindings: {
            /// The nine coefficients.
            sh: readwrite buffer [vec4],
        }
    }

    /// Shadow maps, step 1 and 3: a triangle whose box in the layer spans at most
    /// `SHADOW_DIRECT_SPAN` texels a side rasterizes itself (step 1, `atomicMin` into the
    /// scratch layer); a larger one counts itself into (`fill` false) or enters itself in (`fill`
    /// true) the list of every tile its box overlaps.
    kernel shadow_bin {
        scene: full [textures, alpha, colors, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map],
        push: ShadowRasterParams,
        local: [64, 1, 1],
        spec: { fill: bool = false },
        bindings: {
            /// The BVH positions to rasterize, one per scene triangle (the BVH repeats a split
            /// triangle once per piece).
            raster_tris: readonly buffer [uint],
            /// Triangles per tile (counted, then filled again from 0).
            tile_count: readwrite buffer [uint],
            /// First entry of each tile's list.
            tile_start: readwrite buffer [uint],
            /// The lists: triangle indices in BVH order.
            tile_tris: readwrite buffer [uint],
            /// One layer's depth bits from the small triangles (infinity's bits where none).
            shadow_scratch: readwrite buffer [uint],
            /// Per large triangle (by BVH index) its oriented edge functions and vertex depths,
            /// three `vec4`s (written by the fill, step 3).
            tile_setup: readwrite buffer [vec4],
            /// Per layer and tile, nonzero where the tile is rendered.
            tile_marks: readonly buffer [uint],
            /// The layer's large triangles that enter some rendered tile's list (the count step
            /// appends them, the fill runs over them).
            large_tris: readwrite buffer [uint],
            /// Per layer [`SHADOW_DISPATCH_WORDS`] words: the fill's indirect dispatch and the
            /// large triangles' count.
            tile_dispatch: readwrite buffer [uint],
        }
    }

    /// Shadow maps, step 0 for a view: the tiles of the cascades each G-buffer pixel reads,
    /// marked.
    kernel shadow_mark {
        scene: none,
        push: ShadowMarkParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// View-space depth.
            gb_depth: readonly image r32f,
            /// The lights' records and layers ([`GpuShadowLayer`]).
            shadow_texels: readonly texels rgba32ui,
            /// Per layer and tile, set to 1 where a pixel reads it.
            tile_marks: readwrite buffer [uint],
        }
    }

    /// Shadow maps, per layer: the window's marked tiles listed, their count an indirect dispatch.
    kernel shadow_tiles {
        scene: none,
        push: ShadowRasterParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// Per layer and tile, nonzero where the tile is rendered.
            tile_marks: readonly buffer [uint],
            /// Per layer, its rendered tiles (row-major tile indices).
            tile_list: readwrite buffer [uint],
            /// Per layer [`SHADOW_DISPATCH_WORDS`] words: the rendered tiles, 1, 1 (a
            /// `VkDispatchIndirectCommand`), a pad, then the fill's dispatch (its y and z set here).
            tile_dispatch: readwrite buffer [uint],
        }
    }

    /// Shadow maps, step 2: the tiles' list offsets (an exclusive prefix sum of the counts).
    kernel shadow_scan {
        scene: none,
        push: ShadowRasterParams,
        local: [256, 1, 1],
        spec: {},
        bindings: {
            /// Triangles per tile (set back to 0 for the fill).
            tile_count: readwrite buffer [uint],
            /// First entry of each tile's list.
            tile_start: readwrite buffer [uint],
            /// The largest need seen.
            stats: readwrite buffer ShadowStats,
        }
    }

    /// Shadow maps, step 4: each tile's texels against the triangles in its list (watertight
    /// homogeneous edge functions, a tie rule), nearest linear depth written.
    kernel shadow_raster {
        scene: full [textures, alpha, colors, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map],
        push: ShadowRasterParams,
        local: [SHADOW_TILE / SHADOW_QUAD, SHADOW_TILE / SHADOW_QUAD, 1],
        spec: {},
        bindings: {
            /// Triangles per tile (set back to 0 once read, for the next layer).
            tile_count: readwrite buffer [uint],
            /// First entry of each tile's list.
            tile_start: readonly buffer [uint],
            /// The lists.
            tile_tris: readonly buffer [uint],
            /// `shadow_bin`'s `tile_setup`, read as RGBA32F texels.
            setup_texels: readonly texels rgba32f,
            /// Per layer, the tiles rendered (one workgroup each).
            tile_list: readonly buffer [uint],
            /// The small triangles' depth bits (read, then reset to infinity's for the next layer).
            shadow_scratch: readwrite buffer [uint],
            /// The map: linear depth per texel (infinity where nothing is).
            shadow_depth: writeonly texels r32f,
        }
    }

    /// Moment shadow maps: depth to its four moments, box-filtered along x, then along y.
    kernel shadow_moments {
        scene: none,
        push: ShadowMomentParams,
        local: [16, 16, 1],
        spec: {},
        bindings: {
            /// The depth map.
            shadow_depth: readonly texels r32f,
            /// Moments filtered along x (written in direction 0, read in 1).
            moments_x: readwrite texels rgba32f,
            /// Moments filtered along both axes (written in direction 1).
            shadow_moments: writeonly texels rgba32f,
            /// Per layer, the tiles rendered (one workgroup each).
            tile_list: readonly buffer [uint],
        }
    }

    /// Lightmaps: one sample of each texel's irradiance.
    kernel lightmap_bake {
        scene: full [textures, alpha, lights, punctual, env_map, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, shallow_bvh],
        push: LightmapParams,
        local: [64, 1, 1],
        spec: { occlusion: bool = false },
        bindings: {
            /// Per texel two RGBA32F texels: the world position and 1 where a triangle covers the
            /// texel (0: none, skipped), then the unit normal.
            lightmap_texels: readonly texels rgba32f,
            /// A probe volume for the light beyond the first bounce (its states all inactive
            /// when there is none): the grid and states.
            probe_texels: readonly texels rgba32ui,
            /// The volume's irradiance maps.
            probe_irradiance: readonly texels rgba32f,
            /// The volume's distance maps.
            probe_distance: readonly texels rgba32f,
            /// Per texel the running means: emitters' irradiance rgb and the mean square of its
            /// red channel, then the same of the ambient irradiance (occlusion maps: the
            /// unoccluded fraction in the first's x).
            lightmap_accum: readwrite buffer [vec4],
        }
    }
    /// Irradiance probes, update step 1: each probe's rays traced and shaded.
    kernel probe_trace {
        scene: full [textures, alpha, lights, punctual, env_map, colors, unlit, base_color_map, metal_rough_map, emissive_map, normal_map, occlusion_map, specular_map, transmission_map, clearcoat_map, iridescence_map, clearcoat, implicit, sheen, iridescence, anisotropy_map, sheen_map, diffuse_transmission_map, thickness_map, shallow_bvh],
        push: ProbeUpdateParams,
        local: [PROBE_RAY_GROUP, 1, 1],
        spec: {},
        bindings: {
            /// The grid and each probe's state (active, updates since the last replacement,
            /// back-face hits, updates in all).
            probe_texels: readonly texels rgba32ui,
            /// Octahedral irradiance per probe (multi-bounce reads the previous update).
            probe_irradiance: readonly texels rgba32f,
            /// Octahedral mean and mean squared distance per probe.
            probe_distance: readonly texels rgba32f,
            /// Per ray of the update: radiance rgb, distance (negative on a back face).
            probe_rays: readwrite buffer [vec4],
        }
    }
    /// Irradiance probes, update step 2: the rays blended into each probe's maps and state.
    kernel probe_blend {
        scene: none,
        push: ProbeUpdateParams,
        local: [PROBE_DISTANCE_TEXELS + 2, PROBE_DISTANCE_TEXELS + 2, 1],
        spec: {},
        bindings: {
            /// The rays `probe_trace` traced.
            probe_rays: readonly buffer [vec4],
            /// The grid and the probes' states (updated).
            probe_texels: readwrite texels rgba32ui,
            /// Irradiance maps (blended).
            probe_irradiance: readwrite texels rgba32f,
            /// Distance maps (blended).
            probe_distance: readwrite texels rgba32f,
        }
    }
    /// Rays through the BVH (tests and the ray-throughput benchmark).
    kernel trace {
        scene: bvh [implicit, shallow_bvh],
        push: TraceParams,
        local: [64, 1, 1],
        spec: { trace_any: bool = false },
        bindings: {
            /// The rays.
            rays: readonly buffer [TraceRay],
            /// Their hits.
            hits: readwrite buffer [TraceHit],
        }
    }

    /// Test-only: a pattern into an image.
    #[doc(hidden)]
    kernel test_pattern {
        scene: none,
        push: PatternParams,
        local: [8, 8, 1],
        spec: { pattern_multiplier: uint = 1 },
        bindings: {
            /// The image.
            out_image: writeonly image rgba32f,
        }
    }

    /// Test-only: `out = 3 in + add`.
    test_kernel test_buffer {
        scene: none,
        push: BufferTestParams,
        local: [64, 1, 1],
        spec: {},
        bindings: {
            /// Input.
            values_in: readonly buffer [uint],
            /// Output.
            values_out: readwrite buffer [uint],
        }
    }

    /// Test-only: `out = ` bits of the branches taken on specialization constants in every form
    /// glslang emits them (plain, empty side, short-circuit with a runtime value, nested, around
    /// a call), for the test of the host-side folding (`src/vk/specialize.rs`).
    test_kernel fold_test {
        scene: none,
        push: BufferTestParams,
        local: [64, 1, 1],
        spec: { flag_a: bool = false, flag_b: bool = true },
        bindings: {
            /// Input.
            values_in: readonly buffer [uint],
            /// Output.
            values_out: readwrite buffer [uint],
        }
    }

    /// Test-only: hangs until released (the breadcrumb test).
    test_kernel spin_test {
        scene: none,
        push: (),
        local: [64, 1, 1],
        spec: { max_iterations: uint = 0x1000000 },
        bindings: {
            /// The shared flags.
            spin: coherent buffer SpinState,
        }
    }

    /// Test-only: samplers and pdfs of bsdf.glsl for the chi-square tests.
    test_kernel sample_test {
        scene: none,
        push: SampleTestParams,
        local: [64, 1, 1],
        spec: { beckmann: bool = false, ggx_walter: bool = false },
        bindings: {
            /// Directions at which to evaluate pdfs.
            directions: readonly buffer [vec4],
            /// Samples or pdfs.
            results: readwrite buffer [vec4],
        }
    }

    /// Test-only: light sampling of environment.glsl and shading.glsl.
    test_kernel light_sample_test {
        scene: full [],
        push: LightTestParams,
        local: [64, 1, 1],
        spec: {
            solid_angle_emitters: bool = false
        },
        bindings: {
            /// Directions at which to evaluate pdfs.
            directions: readonly buffer [vec4],
            /// Samples or pdfs.
            results: readwrite buffer [vec4],
        }
    }

    /// Test-only: texture.glsl's wrap modes.
    test_kernel texture_wrap_test {
        scene: none,
        push: BufferTestParams,
        local: [64, 1, 1],
        spec: {},
        bindings: {
            /// (texel coordinate, texture) cases.
            cases: readonly buffer [ivec2],
            /// The wrapped coordinates.
            wrapped: readwrite buffer [int],
            /// The textures, two RGBA32UI texels each.
            texture_texels: readonly texels rgba32ui,
            /// Their texels.
            scene_texels: readonly texels rg32ui,
        }
    }
}
