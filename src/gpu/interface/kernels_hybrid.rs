// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The hybrid renderer's kernels: G-buffer, lighting, ReSTIR, AO, tone mapping, image-based lighting.

kernels! {
    kernels_hybrid;
    /// The G-buffer: ray-cast (`raster` false), or resolved from the visibility buffer
    /// `vis_bin` and `vis_raster` rasterized (`raster` true).
    kernel gbuffer {
        scene: full [surface, clearcoat, implicit, parallax, diffuse_transmission, anisotropy, shallow_bvh],
        push: GBufferParams,
        local: [8, 8, 1],
        spec: { raster: bool = false },
        bindings: {
            /// The G-buffer's images written (`gbuffer_format!` in interface.rs).
            gb: writeonly gbuffer [depth, normal, base, emission, material, layers, layers2, motion],
            /// The visibility buffer (`raster` only; one element otherwise): per pixel, row-major
            /// with [`GBufferParams::vis_stride`] a row, the nearest triangle's BVH index in x
            /// (`u32::MAX`: none) and its depth's bits in y.
            visibility: readonly buffer [uvec2],
            /// Each vertex's world-space motion since the previous geometry in xyz (read only
            /// with [`GBufferParams::motion`]; one element otherwise).
            vertex_motion: readonly buffer [vec4],
        }
    }

    /// The visibility buffer, steps 1 and 3 (`shadow_bin`'s binning with the camera as the
    /// layer): a small triangle rasterizes itself (`atomicMin` of depth and triangle into the
    /// visibility buffer); a larger one counts itself into (`fill` false) or enters itself in
    /// (`fill` true) the list of every tile its box overlaps.
    kernel vis_bin {
        scene: full [surface],
        push: ShadowRasterParams,
        local: [64, 1, 1],
        spec: { fill: bool = false },
        bindings: {
            /// The BVH positions to rasterize, one per scene triangle.
            raster_tris: readonly buffer [uint],
            /// Triangles per tile (counted, then filled again from 0).
            tile_count: readwrite buffer [uint],
            /// First entry of each tile's list.
            tile_start: readwrite buffer [uint],
            /// The lists: triangle indices in BVH order.
            tile_tris: readwrite buffer [uint],
            /// Per pixel (row-major, `size` a row), depth bits << 32 | triangle, the nearest
            /// kept (all ones where none).
            visibility: readwrite buffer [uint64_t],
            /// Per large triangle its oriented edge functions and vertex depths.
            tile_setup: readwrite buffer [vec4],
            /// Per tile, nonzero where the tile is rendered.
            tile_marks: readonly buffer [uint],
            /// The large triangles that enter some rendered tile's list.
            large_tris: readwrite buffer [uint],
            /// [`SHADOW_DISPATCH_WORDS`] words: the tiles' and the fill's indirect dispatches.
            tile_dispatch: readwrite buffer [uint],
        }
    }

    /// The visibility buffer, step 4 (`shadow_raster`'s tiles): each tile's pixels against the
    /// large triangles in its list, the nearest merged into the visibility buffer.
    kernel vis_raster {
        scene: full [surface],
        push: ShadowRasterParams,
        local: [SHADOW_TILE / SHADOW_QUAD, SHADOW_TILE / SHADOW_QUAD, 1],
        spec: {},
        bindings: {
            /// Triangles per tile (set back to 0 once read).
            tile_count: readwrite buffer [uint],
            /// First entry of each tile's list.
            tile_start: readonly buffer [uint],
            /// The lists.
            tile_tris: readonly buffer [uint],
            /// `vis_bin`'s `tile_setup`, read as RGBA32F texels.
            setup_texels: readonly texels rgba32f,
            /// The tiles rendered (one workgroup each).
            tile_list: readonly buffer [uint],
            /// Depth bits << 32 | triangle per pixel: the small triangles' nearest, merged with
            /// the large ones'.
            visibility: readwrite buffer [uint64_t],
        }
    }

    /// Deferred lighting of a G-buffer.
    kernel deferred {
        scene: full [surface, all_lights, transmission, unlit, clearcoat, implicit, parallax, sheen, iridescence, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
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
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal, base, emission, material, layers, layers2],
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
        scene: full [surface, lights, punctual, transmission, unlit, clearcoat, implicit, sheen, iridescence, diffuse_transmission, anisotropy, shallow_bvh],
        push: RestirParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            unbiased: bool = false,
            temporal: bool = true
        },
        bindings: {
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal, base, material, layers, layers2],
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
        scene: full [surface, lights, punctual, transmission, unlit, clearcoat, implicit, sheen, iridescence, diffuse_transmission, anisotropy, shallow_bvh],
        push: RestirParams,
        local: [8, 8, 1],
        spec: {
            beckmann: bool = false,
            unbiased: bool = false
        },
        bindings: {
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal, base, material, layers, layers2],
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
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal],
            /// AO (1 = unoccluded).
            out_ao: writeonly image r32f,
        }
    }

    /// Ground-truth-based ambient occlusion (GTAO), at full or half resolution.
    kernel gtao {
        scene: none,
        push: AoParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal],
            /// AO (1 = unoccluded), one texel per `scale`² G-buffer pixels.
            out_ao: writeonly image r32f,
        }
    }

    /// Ray-traced ambient occlusion (SSAO's ground truth).
    kernel rtao {
        scene: full [surface, implicit, shallow_bvh],
        push: AoParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal, material],
            /// AO, accumulated over batches of rays.
            out_ao: readwrite image r32f,
        }
    }

    /// The depth-aware AO blur (and half-resolution AO's upsample).
    kernel ao_blur {
        scene: none,
        push: AoBlurParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The AO to blur.
            ao_in: readonly image r32f,
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, normal],
            /// The blurred AO.
            out_ao: writeonly image r32f,
        }
    }

    /// Temporal anti-aliasing and sub-frame accumulation ([`crate::passes::taa`]).
    kernel taa {
        scene: none,
        push: TaaParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The frame's linear radiance (each pixel's sample at the camera's jitter).
            current: readonly image rgba32f,
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth, motion],
            /// The history: the last resolve (rgb) and the frames each pixel holds (a).
            history: readonly image rgba32f,
            /// The resolve (the next frame's history).
            resolved: writeonly image rgba32f,
            /// The camera `history` was resolved for.
            prev_camera: readonly buffer GpuCamera,
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
}
