#version 460
// Declares every struct of layout.glsl in a buffer so that tests/layout.rs can read their
// offsets from the SPIR-V, even those whose kernels naga cannot parse. Never dispatched.
#extension GL_GOOGLE_include_directive : require
#include "layout.glsl"

layout(local_size_x = 1) in;

layout(set = 0, binding = 0, std430) buffer PatternParamsBuffer { PatternParams pattern_params[]; };

layout(set = 0, binding = 1, std430) buffer BufferTestParamsBuffer { BufferTestParams buffer_test_params[]; };
layout(set = 0, binding = 2, std430) buffer BvhNodeBuffer { GpuBvhNode bvh_node_check[]; };
layout(set = 0, binding = 3, std430) buffer BvhTriBuffer { BvhTri bvh_tri_check[]; };
layout(set = 0, binding = 4, std430) buffer TraceRayBuffer { TraceRay trace_ray_check[]; };
layout(set = 0, binding = 5, std430) buffer TraceHitBuffer { TraceHit trace_hit_check[]; };
layout(set = 0, binding = 6, std430) buffer TraceParamsBuffer { TraceParams trace_params_check[]; };
layout(set = 0, binding = 7, std430) buffer GpuTriangleBuffer { GpuTriangle gpu_triangle_check[]; };
layout(set = 0, binding = 8, std430) buffer GpuVertexBuffer { GpuVertex gpu_vertex_check[]; };
layout(set = 0, binding = 9, std430) buffer GpuMaterialBuffer { GpuMaterial gpu_material_check[]; };
layout(set = 0, binding = 10, std430) buffer GpuLightTriBuffer { GpuLightTri gpu_light_tri_check[]; };
layout(set = 0, binding = 11, std430) buffer PathParamsBuffer { PathParams path_params_check[]; };
layout(set = 0, binding = 12, std430) buffer PathStatsBuffer { PathStats path_stats_check[]; };
layout(set = 0, binding = 13, std430) buffer GpuLightBuffer { GpuLight gpu_light_check[]; };
layout(set = 0, binding = 14, std430) buffer GpuTextureBuffer { GpuTexture gpu_texture_check[]; };
layout(set = 0, binding = 15, std430) buffer SampleTestParamsBuffer { SampleTestParams sample_test_check[]; };
layout(set = 0, binding = 16, std430) buffer GBufferParamsBuffer { GBufferParams gbuffer_params_check[]; };
layout(set = 0, binding = 17, std430) buffer DeferredParamsBuffer { DeferredParams deferred_params_check[]; };
layout(set = 0, binding = 18, std430) buffer TonemapParamsBuffer { TonemapParams tonemap_params_check[]; };
layout(set = 0, binding = 19, std430) buffer AoParamsBuffer { AoParams ao_params_check[]; };
layout(set = 0, binding = 20, std430) buffer AoBlurParamsBuffer { AoBlurParams ao_blur_params_check[]; };
layout(set = 0, binding = 21, std430) buffer IblParamsBuffer { IblParams ibl_params_check[]; };
layout(set = 0, binding = 22, std430) buffer LightTestParamsBuffer { LightTestParams light_test_params_check[]; };

void main() {
    pattern_params[0].seed += 1u;
    buffer_test_params[0].add += 1u;
    bvh_node_check[0].child[0] += 1u;
    bvh_tri_check[0].v0.x += 1.0;
    trace_ray_check[0].origin_tmin.x += 1.0;
    trace_hit_check[0].tri += 1u;
    trace_params_check[0].count += 1u;
    gpu_triangle_check[0].v0 += 1u;
    gpu_vertex_check[0].normal_u.x += 1.0;
    gpu_material_check[0].base_color.x += 1.0;
    gpu_light_tri_check[0].tri += 1u;
    path_params_check[0].cam_origin.x += 1.0;
    path_stats_check[0].nonfinite_samples += 1u;
    gpu_light_check[0].intensity.x += 1.0;
    gpu_texture_check[0].offset += 1u;
    sample_test_check[0].config.x += 1u;
    gbuffer_params_check[0].size.x += 1u;
    deferred_params_check[0].counts.x += 1u;
    tonemap_params_check[0].curve += 1u;
    ao_params_check[0].counts.x += 1u;
    ao_blur_params_check[0].size.x += 1u;
    ibl_params_check[0].dst.x += 1u;
    light_test_params_check[0].config.x += 1u;
}
