#version 460
// Denoiser, temporal step (src/passes/temporal.rs; SVGF's temporal accumulation, Schied et al.
// 2017): this frame's prepared (demodulated) radiance blended with the history reprojected from
// the previous frame.
//
// Reprojection: the pixel's first hit is taken on the ray through the pixel's centre at the
// first sample's distance (the path tracer jitters that sample inside the pixel: the point can
// be off the surface by half a pixel's footprint, which the tolerance below allows), projected
// into the previous frame's camera. Of the four history pixels around it (bilinear taps; a
// fraction within 1e-3 of a pixel centre snaps to it, so a still camera reads its own pixel) a
// tap counts when its frame saw a surface there whose normal is within `normal_tolerance`
// (cosine) of the pixel's and whose point (its frame's ray at its distance) lies within
// `depth_tolerance` × distance + two pixel footprints of the pixel's tangent plane. No tap
// counts (a disocclusion, the image's edge, a miss, no history): the pixel starts afresh.
//
// Blend: the frame's divisors (what step 1 divided its radiance by: the first hit's albedo, mean of
// the pixel's samples) and first-hit emission are blended like the colour and written back for the
// remodulation, and the colour is the blend of the numerators (colour × its divisor) over the
// blended divisor. The path tracer jitters each sample's first hit inside the pixel, so at a
// sub-pixel edge (an emitter's rim, a texture's or a wall's edge) a frame's one sample gives a
// divisor and an emission of one side only; remodulating the accumulated colour by them would give
// each frame that side's colour (the flicker of the temporal spikes, docs/history/2026-12-03.md,
// seventh session); with a still camera the result is the pooled frames' own (numerator and divisor
// both the frames' means).
//
// n the history's length + 1, α = max(1/n, alpha) for the colour and max(1/n,
// alpha_moments) for the luminance moments E[l], E[l²] (per part with the lobe split). The sum
// of the colour's weights squared, s (1/n while α = 1/n), gives the accumulated mean's variance:
// from `variance_frames` frames on, (E[l²] − E[l]²) × s (the temporal variance); before, the
// variance carried through the blend, (1 − α)² var_history + α² var_frame, and dn_samples
// becomes the frame's sample count / s, so the à-trous' spatial variance floor (its first
// iteration) covers the first frames and fades after them.
#extension GL_GOOGLE_include_directive : require
#include "kernel/denoise_temporal.glsl"
#include "camera.glsl"

KERNEL_LOCAL_SIZE;

const vec3 LUMA = vec3(0.2126, 0.7152, 0.0722);

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    uvec2 size = uvec2(params.width, params.height);
    if (any(greaterThanEqual(uvec2(pixel), size))) {
        return;
    }
    bool split = (params.flags & TEMPORAL_SPLIT) != 0u;
    vec4 color = imageLoad(dn_color, pixel);
    vec4 specular = split ? imageLoad(dn_specular, pixel) : vec4(0.0);
    vec4 g0 = imageLoad(dn_guide, pixel);
    float spp = imageLoad(dn_samples, pixel).x;

    // The history at the reprojected point: weighted sums over the taps that count.
    vec4 h_color = vec4(0.0);
    vec4 h_specular = vec4(0.0);
    vec4 h_moments = vec4(0.0);
    vec2 h_state = vec2(0.0);
    // The history's divisors and emission, and whether it is read at one pixel (no resampling).
    bool whole = false;
    vec3 h_albedo = vec3(0.0);
    vec3 h_spec_albedo = vec3(0.0);
    vec3 h_emission = vec3(0.0);
    float h_weight = 0.0;
    if ((params.flags & TEMPORAL_HISTORY) != 0u && g0.w >= 0.0) {
        vec3 origin;
        vec3 dir;
        camera_ray(params.origin, params.forward, params.right, params.up,
                   (params.flags & TEMPORAL_ORTHOGRAPHIC) != 0u, vec2(pixel) + 0.5, size, origin, dir);
        vec3 p = origin + dir * g0.w;
        bool prev_ortho = (params.flags & TEMPORAL_PREV_ORTHOGRAPHIC) != 0u;
        vec2 pos;
        float depth;
        if (camera_project(params.prev_origin, params.prev_forward, params.prev_right, params.prev_up, prev_ortho,
                           p, size, pos, depth)) {
            // A pixel's footprint at the point: the view's height over the image's, × the
            // distance for a pinhole.
            float footprint = 2.0 * length(params.up) / float(size.y) * ((params.flags & TEMPORAL_ORTHOGRAPHIC) != 0u ? 1.0 : g0.w);
            float tolerance = params.depth_tolerance * g0.w + 2.0 * footprint;
            vec2 b = pos - 0.5;
            vec2 base = floor(b);
            vec2 f = b - base;
            f = mix(f, vec2(0.0), lessThan(f, vec2(1e-3)));
            base += mix(vec2(0.0), vec2(1.0), greaterThan(f, vec2(1.0 - 1e-3)));
            f = mix(f, vec2(0.0), greaterThan(f, vec2(1.0 - 1e-3)));
            whole = all(equal(f, vec2(0.0)));
            for (int j = 0; j <= 1; ++j) {
                for (int i = 0; i <= 1; ++i) {
                    float w = (i == 0 ? 1.0 - f.x : f.x) * (j == 0 ? 1.0 - f.y : f.y);
                    ivec2 q = ivec2(base) + ivec2(i, j);
                    if (!(w > 0.0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(uvec2(q), size))) {
                        continue;
                    }
                    vec4 g = imageLoad(hist_guide, q);
                    if (g.w < 0.0 || dot(g.xyz, g0.xyz) < params.normal_tolerance) {
                        continue;
                    }
                    vec3 q_origin;
                    vec3 q_dir;
                    camera_ray(params.prev_origin, params.prev_forward, params.prev_right, params.prev_up, prev_ortho,
                               vec2(q) + 0.5, size, q_origin, q_dir);
                    vec3 pq = q_origin + q_dir * g.w;
                    if (abs(dot(pq - p, g0.xyz)) > tolerance) {
                        continue;
                    }
                    h_color += w * imageLoad(hist_color, q);
                    h_albedo += w * imageLoad(hist_albedo, q).rgb;
                    h_emission += w * imageLoad(hist_emission, q).rgb;
                    if (split) {
                        h_specular += w * imageLoad(hist_specular, q);
                        h_spec_albedo += w * imageLoad(hist_spec_albedo, q).rgb;
                    }
                    h_moments += w * imageLoad(hist_moments, q);
                    h_state += w * imageLoad(hist_state, q).xy;
                    h_weight += w;
                }
            }
        }
    }
    bool history = h_weight > 1e-3;
    if (history) {
        h_color /= h_weight;
        h_specular /= h_weight;
        h_moments /= h_weight;
        h_state /= h_weight;
        h_albedo /= h_weight;
        h_spec_albedo /= h_weight;
        h_emission /= h_weight;
    }
    float n = history ? min(h_state.x + 1.0, TEMPORAL_MAX_LENGTH) : 1.0;
    float alpha = history ? max(1.0 / n, params.alpha) : 1.0;
    float alpha_m = history ? max(1.0 / n, params.alpha_moments) : 1.0;
    float s = history ? (1.0 - alpha) * (1.0 - alpha) * h_state.y + alpha * alpha : 1.0;

    float l = dot(LUMA, color.rgb);
    float ls = dot(LUMA, specular.rgb);
    vec4 frame_moments = vec4(l, l * l, ls, ls * ls);
    vec4 moments = history ? mix(h_moments, frame_moments, alpha_m) : frame_moments;
    vec3 frame_albedo = imageLoad(dn_albedo, pixel).rgb;
    vec3 frame_spec_albedo = split ? imageLoad(dn_spec_albedo, pixel).rgb : vec3(1.0);
    vec3 albedo = frame_albedo;
    vec3 spec_albedo = frame_spec_albedo;
    vec3 emission = imageLoad(dn_emission, pixel).rgb;
    vec3 rgb = history ? mix(h_color.rgb, color.rgb, alpha) : color.rgb;
    vec3 spec = history ? mix(h_specular.rgb, specular.rgb, alpha) : specular.rgb;
    if (history && whole) {
        // Read at one pixel: the divisors and the emission blended, the colour the blend of the
        // numerators (colour × divisor) over the blended divisor.
        albedo = mix(h_albedo, frame_albedo, alpha);
        rgb = mix(h_color.rgb * h_albedo, color.rgb * frame_albedo, alpha) / albedo;
        emission = mix(h_emission, emission, alpha);
        if (split) {
            spec_albedo = mix(h_spec_albedo, frame_spec_albedo, alpha);
            spec = mix(h_specular.rgb * h_spec_albedo, specular.rgb * frame_spec_albedo, alpha) / spec_albedo;
        }
    }
    float carried = (1.0 - alpha) * (1.0 - alpha);
    float var = carried * h_color.a + alpha * alpha * color.a;
    float var_s = carried * h_specular.a + alpha * alpha * specular.a;
    if (n >= params.variance_frames) {
        var = max(moments.y - moments.x * moments.x, 0.0) * s;
        var_s = max(moments.w - moments.z * moments.z, 0.0) * s;
    }
    imageStore(out_color, pixel, vec4(rgb, var));
    if (split) {
        imageStore(out_specular, pixel, vec4(spec, var_s));
    }
    imageStore(out_moments, pixel, moments);
    imageStore(out_guide, pixel, g0);
    imageStore(out_state, pixel, vec4(n, s, 0.0, 0.0));
    imageStore(dn_samples, pixel, vec4(spp / s));
    imageStore(out_albedo, pixel, vec4(albedo, 0.0));
    imageStore(dn_albedo, pixel, vec4(albedo, 0.0));
    imageStore(out_emission, pixel, vec4(emission, 0.0));
    imageStore(dn_emission, pixel, vec4(emission, 0.0));
    if (split) {
        imageStore(out_spec_albedo, pixel, vec4(spec_albedo, 0.0));
        imageStore(dn_spec_albedo, pixel, vec4(spec_albedo, 0.0));
    }
}
