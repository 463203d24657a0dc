// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The ray-tracing kernel of the BVH benchmark, the test pattern, and the tests' kernels.

kernels! {
    kernels_tools;
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
