// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The structs of the hybrid renderer's passes, the baked lighting's, the denoiser's and the tests'.

gpu_structs! {
    structs_passes;
    /// Push constants of `gbuffer.comp`.
    struct GBufferParams {
        /// The camera.
        camera: GpuCamera,
        /// Image width and height.
        size: uvec2,
        /// The visibility buffer's row length in pixels (`raster` only).
        vis_stride: uint,
        /// 1: the scene's geometry moved; write each surface point's motion (the vertices'
        /// `vertex_motion` at its barycentrics) into the G-buffer's `motion`.
        motion: uint,
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

    /// Push constants of `taa.comp` ([`crate::passes::taa`]).
    struct TaaParams {
        /// This frame's camera (the pixels' centres are reprojected; its jitter is not read).
        camera: GpuCamera,
        /// Width, height.
        size: uvec2,
        /// [`TAA_HISTORY`] | [`TAA_ACCUMULATE`] | [`TAA_CATMULL_ROM`] | [`TAA_MOTION`].
        flags: uint,
        /// The least weight of the frame in the blend with the reprojected history (before, the
        /// frame's weight is 1 / the history's length).
        blend: float,
        /// The neighbourhood's box: its mean ± this × its standard deviation, per channel (YCoCg).
        clip_sigma: float,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Padding.
        pad2: uint,
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

    /// Push constants of `ssao.comp`, `gtao.comp` and `rtao.comp`.
    struct AoParams {
        /// The camera.
        camera: GpuCamera,
        /// AO radius r (world units).
        radius: float,
        /// SSAO plane bias (world units).
        bias: float,
        /// GTAO: the fraction of r over which an occluder's weight fades to 0 at r (0: cut off
        /// at r).
        falloff: float,
        /// GTAO: G-buffer pixels per AO texel along each axis (1 or 2); the AO image is the
        /// G-buffer's size divided by it, rounded up.
        scale: uint,
        /// G-buffer width and height.
        size: uvec2,
        /// Frame index.
        frame: uint,
        /// Seed of the random numbers.
        seed: uint,
        /// Directions (SSAO), slices (GTAO) or rays (RTAO) per pixel.
        samples: uint,
        /// SSAO: steps per direction; GTAO: steps each side of the pixel per slice.
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
        /// Padding (the normal weight's exponent is 8, `ao_blur.comp`).
        pad3: float,
        /// G-buffer (and output) width and height.
        size: uvec2,
        /// G-buffer pixels per texel of the AO read (1, or 2 for half-resolution AO: the blur
        /// is then its depth-aware upsample too).
        scale: uint,
        /// Padding.
        pad0: uint,
        /// Padding.
        pad1: uint,
        /// Padding.
        pad2: uint,
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
