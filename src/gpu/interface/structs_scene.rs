// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The structs of the camera, the BVH and the scene, and the path tracer's.

gpu_structs! {
    structs_scene;
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
        /// Bit 0: orthographic (rays parallel to `forward` from the plane through `origin`), else a
        /// pinhole. Bits 8..20 and 20..32: the sub-pixel offset of every pixel's sample position
        /// from its centre (x right, y down; anti-aliasing's jitter), each a signed 12-bit count of
        /// 1/4096 pixels ([`GpuCamera::jitter`]). The hybrid's kernels sample there (and the
        /// rasterizer covers there); the path tracer samples each pixel's whole area and ignores it.
        flags: uint,
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
    texel_struct GpuMaterial {
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
}
