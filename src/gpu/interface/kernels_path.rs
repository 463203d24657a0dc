// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The path tracer's kernels (megakernel and wavefront), its resolve and the denoiser's.

kernels! {
    kernels_path;
    /// The progressive path tracer.
    kernel pathtrace {
        scene: full [all_lights, surface, transmission, unlit, clearcoat, implicit, parallax, sheen, iridescence, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
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
        scene: full [all_lights, surface, transmission, unlit, clearcoat, implicit, parallax, sheen, iridescence, diffuse_transmission, anisotropy, dispersion, shallow_bvh],
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
}
