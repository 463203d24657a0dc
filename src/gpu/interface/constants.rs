// Part of the interface between Rust and the kernels: see `src/gpu/interface.rs`, which includes
// this file, for the rules it is written in.
//
// The constants both sides read, and the scene's binding block.

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
    /// Slot of `KHR_materials_anisotropy`'s `anisotropyTexture` (RG: the direction in tangent
    /// space, `2 x - 1`; B: × `anisotropyStrength`; left empty where the strength is 0). Looked
    /// up only by kernels specialised for it (`HAS_ANISOTROPY_MAP`).
    MATERIAL_SLOT_ANISOTROPY: uint = 12;
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
    /// Slot of `KHR_materials_volume`'s `thicknessTexture` (G: × `thicknessFactor`; left empty
    /// without a volume). Looked up only by kernels specialised for it (`HAS_THICKNESS_MAP`).
    MATERIAL_SLOT_THICKNESS: uint = 19;
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
    /// The triangle of a texel no triangle covers, in the compute rasterizer (shadow maps, the
    /// visibility buffer, whose empty pixels read as all ones).
    RASTER_NO_TRIANGLE: uint = 0xffffffff;
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
    /// [`GpuCamera::flags`]: an orthographic camera (else a pinhole).
    CAMERA_ORTHOGRAPHIC: uint = 1;
    /// [`GpuCamera::flags`]: 1/4096 pixel, the unit of the jitter in its bits 8..32.
    CAMERA_JITTER_UNIT: float = 1.0 / 4096.0;
    /// [`TaaParams::flags`]: the history holds a frame (else the resolve is the current frame).
    TAA_HISTORY: uint = 1;
    /// [`TaaParams::flags`]: the running mean of still sub-frames: each pixel's history read at the
    /// pixel, not reprojected nor clipped, weighted by its length (one-shot supersampling).
    TAA_ACCUMULATE: uint = 2;
    /// [`TaaParams::flags`]: the reprojected history is read by a Catmull-Rom spline over the
    /// 4x4 texels around it (else bilinear over the 2x2).
    TAA_CATMULL_ROM: uint = 4;
    /// [`TaaParams::flags`]: the geometry moved since the history's frame: each surface point is
    /// moved back by the G-buffer's `motion` before it is projected into the previous camera.
    TAA_MOTION: uint = 8;
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
    /// [`GpuMaterial`]s, [`GpuMaterial::TEXELS`] RGBA32UI texels each (float bits but for `flags`,
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
