// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The kernels of shadow maps, lightmaps and irradiance probes.

kernels! {
    kernels_baked;
    /// Shadow maps, step 1 and 3: a triangle whose box in the layer spans at most
    /// `SHADOW_DIRECT_SPAN` texels a side rasterizes itself (step 1, `atomicMin` into the
    /// scratch layer); a larger one counts itself into (`fill` false) or enters itself in (`fill`
    /// true) the list of every tile its box overlaps.
    kernel shadow_bin {
        scene: full [surface],
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
            /// The G-buffer's images read (`gbuffer_format!` in interface.rs).
            gb: readonly gbuffer [depth],
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
        scene: full [surface],
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
        scene: full [surface, all_lights, unlit, clearcoat, implicit, sheen, iridescence, shallow_bvh],
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
        scene: full [surface, all_lights, unlit, clearcoat, implicit, sheen, iridescence, shallow_bvh],
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
}
