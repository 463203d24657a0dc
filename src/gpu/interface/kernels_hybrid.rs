// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The hybrid renderer's kernels: G-buffer, lighting, ReSTIR, AO, tone mapping, image-based lighting.

kernels! {
    kernels_hybrid;
    /// The ray-cast G-buffer.
    kernel gbuffer {
        scene: full [surface, clearcoat, implicit, parallax, diffuse_transmission, anisotropy, shallow_bvh],
        push: GBufferParams,
        local: [8, 8, 1],
        spec: {},
        bindings: {
            /// The G-buffer's images written (`gbuffer_format!` in interface.rs).
            gb: writeonly gbuffer [depth, normal, base, emission, material, layers, layers2],
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
