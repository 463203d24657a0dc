//! The scene on the GPU: the BVH, triangles in BVH order, vertex attributes, materials and the
//! emissive-triangle sampling table, uploaded once as storage buffers.

use super::kernel::SceneFeatures;
use super::layout::{
    GpuLight, GpuLightTri, GpuMaterial, GpuTexture, GpuTriangle, GpuVertex, SceneResources, TexTransforms,
    ALPHA_NEVER_HIT, MATERIAL_SLOT_HEIGHT, MATERIAL_TEXTURE_SLOTS,
};
use crate::bvh::{Bvh, BvhStats};
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::gpu::bvh::{register_stack, GpuBvh, GpuBvhNode};
use crate::scene::{AlphaMode, Material, Scene, Texture, TextureRef};
use crate::vk::{raw, Buffer, Context, DeviceInfo, TexelBuffer};
use glam::Vec3;
use rayon::prelude::*;

/// Storage-buffer usage.
const STORAGE: raw::BufferUsageFlags = raw::BufferUsageFlags::STORAGE_BUFFER;

/// Storage buffers for one scene.
pub struct GpuScene {
    /// BVH nodes and triangles.
    pub bvh: GpuBvh,
    /// `GpuTriangle`s in BVH order, as RGBA32UI texels (two each).
    pub triangles: TexelBuffer,
    /// `GpuVertex`s, as RGBA32UI texels (three each).
    pub vertices: TexelBuffer,
    /// `GpuMaterial`s, as RGBA32UI texels (`GpuMaterial::TEXELS` each).
    pub materials: TexelBuffer,
    /// `GpuLightTri`s as RGBA32UI texels (an empty list still gets one texel).
    pub lights: TexelBuffer,
    /// Emissive triangles in the sampling table.
    pub light_count: u32,
    /// Their total power (`EmissiveTable::total_power`: luminance × area × π summed).
    pub emissive_power: f32,
    /// `GpuLight`s as RGBA32UI texels (four each).
    pub punctual: TexelBuffer,
    /// Punctual lights.
    pub punctual_count: u32,
    /// The punctual lights as uploaded (shadow maps are placed from them on the host).
    pub punctual_lights: Vec<GpuLight>,
    /// The geometry's bounding box (min, max), from the BVH's root.
    pub bounds: [[f32; 3]; 2],
    /// Environment texels as RGBA32UI texels: rgb radiance, density over (u, v) (a dummy texel
    /// when there is none).
    pub env_texels: TexelBuffer,
    /// The environment's alias tables as RG32UI texels: the rows', then each row's.
    pub env_alias: TexelBuffer,
    /// `GpuTexture`s as RGBA32UI texels (two each).
    pub textures: TexelBuffer,
    /// `scene_texels`, RG32UI texels (`texture.glsl` reads them with `imageLoad`): the sRGB
    /// decoding table (256 `f32` bits, for vertex colours), then every texture's texels as
    /// linear RGBA16.
    pub texels: TexelBuffer,
    /// Textures the materials use.
    pub texture_count: u32,
    /// Bit k: some material has a texture in slot k (`MATERIAL_SLOT_*`): the shading kernels
    /// look up only these slots.
    pub texture_slots: u32,
    /// Whether some material transmits (`KHR_materials_transmission`): the path tracer is
    /// specialised for it only then.
    pub has_transmission: bool,
    /// Whether some triangle's material is alpha-masked or blended: the traversal in the shading
    /// kernels is specialised for the alpha test only then.
    pub has_alpha: bool,
    /// Whether some triangle's material is blended: its stochastic coverage hashes the ray, which
    /// the rasterized G-buffer does not have (such scenes' G-buffers are ray-cast).
    pub has_blend: bool,
    /// Whether some vertex has a `COLOR_0` other than opaque white: the shading kernels read
    /// vertex colours only then.
    pub has_colors: bool,
    /// Whether some material is unlit (`KHR_materials_unlit`): the path tracer, the lighting
    /// pass and the probe and lightmap gathers test for it only then.
    pub has_unlit: bool,
    /// Whether some material has a clear coat (`KHR_materials_clearcoat`): the shading kernels
    /// evaluate and sample the coat only then.
    pub has_clearcoat: bool,
    /// Whether some material has a sheen (`KHR_materials_sheen`): the shading kernels evaluate
    /// and sample the sheen only then.
    pub has_sheen: bool,
    /// Whether some material has a thin film (`KHR_materials_iridescence`): the shading kernels
    /// mix its Fresnel in only then.
    pub has_iridescence: bool,
    /// Whether some material is anisotropic (`KHR_materials_anisotropy`): the shading kernels
    /// evaluate and sample anisotropic specular lobes only then.
    pub has_anisotropy: bool,
    /// Whether some material transmits diffusely (`KHR_materials_diffuse_transmission`): the
    /// shading kernels evaluate and sample its lobe only then.
    pub has_diffuse_transmission: bool,
    /// Whether some transmitting volume disperses (`KHR_materials_dispersion`): the path tracer
    /// follows one colour channel through it, the hybrid refracts per channel, only then.
    pub has_dispersion: bool,
    /// Whether the BVH holds implicit shapes (`UMBRA_implicit`): the tracing kernels march them
    /// only then.
    pub has_implicit: bool,
    /// Whether some material has parallax occlusion mapping (`UMBRA_implicit`'s `parallax`, its
    /// height map in `MATERIAL_SLOT_HEIGHT`): the shading kernels look up the height slot and
    /// march height fields only then.
    pub has_parallax: bool,
    /// Width and height of the environment map, if the scene has one.
    pub env_size: Option<(u32, u32)>,
    /// The environment map's mean luminance over the sphere of directions (0 without one).
    pub env_luminance: f32,
    /// Statistics of the BVH built for the scene.
    pub bvh_stats: BvhStats,
    /// `prim_order[i]`: the scene triangle at BVH position i (kept for [`GpuScene::update`]).
    prim_order: Vec<u32>,
    /// Each scene triangle's alpha bits, `None` where the BVH leaves it out ([`bvh_alpha`];
    /// kept for `update`).
    alpha: Vec<Option<u32>>,
    /// The host-side BVH, kept for [`GpuScene::update_geometry`]'s refit when the scene was
    /// uploaded with an animation source ([`Scene::animation`]); `None` otherwise.
    host_bvh: Option<Bvh>,
    /// The vertices' positions, kept where the geometry may move (an animation source, or after
    /// an update), for the next update's motion.
    positions: Option<Vec<[f32; 3]>>,
    /// Each vertex's motion from the previous geometry to this one (xyz, w 0) after an update
    /// that knew the previous positions; else one zero element, which the kernels do not read.
    vertex_motion: Buffer,
    /// Whether `vertex_motion` holds the last update's motion.
    moved: bool,
    /// Geometry updates since the upload ([`GpuScene::update_geometry`]).
    geometry_generation: u64,
}

/// How [`GpuScene::update_geometry`] brings the BVH to moved triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum BvhUpdate {
    /// Keep the tree and refit its boxes bottom-up: O(n), but the tree degrades as things move
    /// far from the pose it was built for.
    #[default]
    Refit,
    /// Build a new tree: O(n log n), the best tree for every pose.
    Rebuild,
}

/// The host-side arrays [`GpuScene`] uploads (also what tests inspect).
pub struct SceneArrays {
    /// The BVH.
    pub bvh: Bvh,
    /// Triangles in BVH order.
    pub triangles: Vec<GpuTriangle>,
    /// Vertex attributes.
    pub vertices: Vec<GpuVertex>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emissive sampling table.
    pub lights: Vec<GpuLightTri>,
    /// Punctual lights.
    pub punctual: Vec<GpuLight>,
    /// The textures the GPU materials use.
    pub textures: Vec<GpuTexture>,
    /// The sRGB decoding table (the linear value of each 8-bit code, as `f32` bits in the first
    /// word; present when there is any texture or vertex colour), then the textures' texels as
    /// linear RGBA16 unorm (sRGB decoded), red and green in the first word, low halves first.
    pub texels: Vec<[u32; 2]>,
    /// The emissive triangles' total power (`EmissiveTable::total_power`).
    pub emissive_power: f32,
    /// Each scene triangle's alpha bits in the BVH, `None` for one left out of it as never hit.
    pub alpha: Vec<Option<u32>>,
}

/// A scene's BVH, built ahead of the rest of its upload ([`GpuScene::upload_with`]), with what
/// only it tells of the kernels' features ([`SceneFeatures::of_scene`]): each triangle's alpha
/// class and the walk's stack depth. `umbra render` and [`crate::embed::Renderer`] build it
/// first, then make the pipelines while the rest (textures, the upload) runs.
pub struct SceneBvh {
    bvh: Bvh,
    /// Each scene triangle's alpha bits in the BVH, `None` for one left out of it as never hit.
    alpha: Vec<Option<u32>>,
    /// Its GPU layout, which tells the stack depth and is uploaded as it is.
    nodes: Vec<GpuBvhNode>,
    stack_depth: u32,
}

impl SceneBvh {
    /// Builds the BVH of `scene`'s triangles and implicit shapes and its GPU layout. Triangles no
    /// ray may hit (transparent wherever they can be hit: their alpha classes) are left out of it.
    pub fn build(scene: &Scene) -> Result<Self> {
        let (bvh, alpha) = build_scene_bvh(scene)?;
        let nodes = GpuBvhNode::from_bvh(&bvh)?;
        let stack_depth = GpuBvhNode::stack_depth(&nodes);
        Ok(Self { bvh, alpha, nodes, stack_depth })
    }
}

/// The BVH of `scene`'s triangles but those no ray may hit, and each scene triangle's alpha
/// class ([`bvh_alpha`]). An animated scene's ([`Scene::animation`]) is built without split
/// references (early split clipping, spatial splits), so that a refit keeps it tight: a split
/// piece's box bounds only its part of the triangle, which a refit cannot follow (it would have
/// to bound the whole moved triangle in every piece's leaf: a 4,090-triangle early version of
/// `scenes/animated.glb` then path-traced 4–8× slower after one refit).
fn build_scene_bvh(scene: &Scene) -> Result<(Bvh, Vec<Option<u32>>)> {
    let boxes = scene_boxes(scene)?;
    let alpha = bvh_alpha(scene);
    let soup = scene.triangle_soup();
    let options = match scene.animation {
        Some(_) => crate::bvh::BuildOptions { presplit: 0.0, spatial: 0.0, ..Default::default() },
        None => crate::bvh::BuildOptions::default(),
    };
    let kept: Vec<u32> = (0..soup.len() as u32).filter(|&t| alpha[t as usize].is_some()).collect();
    let bvh = if kept.len() == soup.len() {
        Bvh::build_mixed(&soup, &boxes, &options)?
    } else {
        let built: Vec<[Vec3; 3]> = kept.iter().map(|&t| soup[t as usize]).collect();
        let mut bvh = Bvh::build_mixed(&built, &boxes, &options)?;
        bvh.renumber(&kept, soup.len());
        bvh
    };
    Ok((bvh, alpha))
}

impl SceneArrays {
    /// Builds the BVH and lays the scene out for the GPU. Triangles no ray may hit (transparent
    /// wherever they can be hit: their alpha classes) are left out of the BVH.
    pub fn new(scene: &Scene) -> Result<Self> {
        let (bvh, alpha) = build_scene_bvh(scene)?;
        Ok(Self::with_alpha(scene, bvh, alpha))
    }

    /// The name and size in bytes of each buffer [`GpuScene::from_arrays`] uploads (the BVH's
    /// two, the triangles, vertices, materials and lights are texel buffers of 16-byte texels, the scene
    /// texels one of 4-byte texels, the others storage buffers).
    pub fn buffer_sizes(&self) -> [(&'static str, u64); 8] {
        fn bytes<T>(v: &[T]) -> u64 {
            std::mem::size_of_val(v) as u64
        }
        [
            ("bvh nodes", bytes(&self.bvh.nodes)),
            ("bvh triangles", bytes(&self.bvh.tris) + bytes(&self.bvh.implicit_texels)),
            ("scene triangles", bytes(&self.triangles)),
            ("scene vertices", bytes(&self.vertices)),
            ("scene materials", bytes(&material_texels(&self.materials))),
            ("scene lights", bytes(&self.lights)),
            ("scene punctual lights", bytes(&self.punctual)),
            ("scene texels", bytes(&self.texels)),
        ]
    }

    /// Checks that every buffer of the scene `name` fits `device`'s `maxStorageBufferRange`
    /// (128 MiB on lavapipe), or for the BVH, triangles, vertices, materials and lights
    /// `maxTexelBufferElements` texels of 16 bytes (2 GiB on lavapipe), or for the scene texels
    /// `maxTexelBufferElements` texels of 8 bytes (1 GiB on lavapipe): one error naming the
    /// scene, the buffer, both sizes and what to reduce, before anything is allocated. [`GpuScene::upload`] calls it; a test can pass a
    /// [`DeviceInfo`] with a lowered limit.
    pub fn check_limits(&self, name: &str, device: &DeviceInfo) -> Result<()> {
        fits(name, &self.buffer_sizes(), device)
    }

    /// Lays the scene out for the GPU around a BVH already built for its triangles (and its
    /// implicit shapes' boxes, [`scene_boxes`], after them).
    pub fn with_bvh(scene: &Scene, bvh: Bvh) -> Self {
        Self::with_alpha(scene, bvh, bvh_alpha(scene))
    }

    /// [`Self::with_bvh`] with each scene triangle's alpha bits ([`bvh_alpha`]) known.
    fn with_alpha(scene: &Scene, mut bvh: Bvh, alpha: Vec<Option<u32>>) -> Self {
        if bvh.procedurals > 0 {
            let programs: Vec<Vec<[u32; 4]>> = scene.implicits.iter().map(super::implicit::program).collect();
            bvh.attach_implicit(&programs);
        }
        // The traversal's alpha test reads each triangle's alpha bits from v1.w (0 opaque, 1 mask,
        // 2 blend, ALPHA_NEVER_HIT), so opaque triangles never pay for it. A triangle the scene
        // would leave out but this BVH holds is never hit; an implicit shape's slot (past the
        // triangles) is opaque.
        for (tri, &input) in bvh.tris.iter_mut().zip(&bvh.prim_order) {
            let bits = alpha.get(input as usize).map_or(0, |a| a.unwrap_or(ALPHA_NEVER_HIT));
            tri.v1[3] = f32::from_bits(bits);
        }
        let shading = ShadingArrays::new(scene, &bvh.prim_order);
        Self {
            bvh,
            triangles: shading.triangles,
            vertices: shading.vertices,
            materials: shading.materials,
            lights: shading.lights,
            punctual: shading.punctual,
            textures: shading.textures,
            texels: shading.texels,
            emissive_power: shading.emissive_power,
            alpha,
        }
    }
}

/// The world box of each of `scene`'s implicit shapes, the BVH's procedural primitives.
pub fn scene_boxes(scene: &Scene) -> Result<Vec<[Vec3; 2]>> {
    scene
        .implicits
        .iter()
        .map(|s| {
            s.world_bounds().map(|(lo, hi)| [lo, hi]).ok_or_else(|| Error::Scene {
                path: scene.name.clone().into(),
                message: format!("{}: UMBRA_implicit: the shape is unbounded", s.label),
            })
        })
        .collect()
}

/// What each buffer holds, for the error of [`fits`].
fn remedy(buffer: &str) -> &'static str {
    match buffer {
        "scene texels" => "use smaller or fewer textures",
        "environment texels" | "environment alias" => "downsample the environment map",
        _ => "split the scene or simplify its meshes",
    }
}

/// The largest size `device` binds for `buffer`, and the limit's name: the BVH's two buffers and
/// the triangles, vertices, materials, lights and environment texels are storage texel buffers
/// of 16-byte texels, the scene texels and the environment's alias tables ones of 8-byte texels,
/// every other one a storage buffer.
fn limit(buffer: &str, device: &DeviceInfo) -> (u64, &'static str, &'static str) {
    if buffer.starts_with("bvh ")
        || [
            "scene triangles",
            "scene vertices",
            "scene materials",
            "scene lights",
            "scene punctual lights",
            "environment texels",
        ]
        .contains(&buffer)
    {
        (device.max_texel_buffer_elements as u64 * 16, "texel", "maxTexelBufferElements × 16 bytes")
    } else if buffer == "scene texels" || buffer == "environment alias" {
        (device.max_texel_buffer_elements as u64 * 8, "texel", "maxTexelBufferElements × 8 bytes")
    } else {
        (device.max_storage_buffer_range, "storage", "maxStorageBufferRange")
    }
}

/// Checks `(buffer, bytes)` pairs of `name` against `device`'s buffer limits.
fn fits(name: &str, buffers: &[(&'static str, u64)], device: &DeviceInfo) -> Result<()> {
    for &(buffer, bytes) in buffers {
        let (limit, kind, what) = limit(buffer, device);
        if bytes > limit {
            return Err(Error::Scene {
                path: name.into(),
                message: format!(
                    "too large for device '{}': its {buffer} need {bytes} bytes ({:.1} MiB) in one {kind} \
                     buffer, but the device binds at most {limit} bytes ({:.1} MiB, {what}); {}",
                    device.name,
                    bytes as f64 / 1048576.0,
                    limit as f64 / 1048576.0,
                    remedy(buffer)
                ),
            });
        }
    }
    Ok(())
}

/// Checks that `device` binds `map`'s two texel buffers ([`GpuScene::set_environment`] calls it
/// before anything is allocated; a test can pass a [`DeviceInfo`] with a lowered limit): its
/// texels (RGBA32UI) and its alias tables (RG32UI, a row's entry and a texel's each), at most
/// `maxTexelBufferElements` each. One error naming the map, the buffer and both sizes.
pub fn check_environment_limits(map: &EnvironmentMap, device: &DeviceInfo) -> Result<()> {
    let count = (map.width * map.height) as u64;
    fits(
        &map.name,
        &[("environment texels", count * 16), ("environment alias", (count + map.height as u64) * 8)],
        device,
    )
}

/// Everything of a scene's GPU layout but its BVH: what changes when materials or lights do.
struct ShadingArrays {
    triangles: Vec<GpuTriangle>,
    vertices: Vec<GpuVertex>,
    materials: Vec<GpuMaterial>,
    lights: Vec<GpuLightTri>,
    punctual: Vec<GpuLight>,
    textures: Vec<GpuTexture>,
    texels: Vec<[u32; 2]>,
    emissive_power: f32,
}

impl ShadingArrays {
    /// `prim_order[i]`: the scene triangle at BVH position i.
    fn new(scene: &Scene, prim_order: &[u32]) -> Self {
        let n = scene.triangles.len();
        let mut bvh_index = vec![0u32; n];
        for (i, &input) in prim_order.iter().enumerate() {
            if let Some(slot) = bvh_index.get_mut(input as usize) {
                *slot = i as u32;
            }
        }
        let area = |t: [u32; 3]| {
            let p = t.map(|i| Vec3::from(scene.positions[i as usize]));
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        };
        let mut triangles: Vec<GpuTriangle> = prim_order
            .iter()
            .map(|&input| {
                // An implicit shape's slot: its material; no vertices, no area (never a light).
                let Some(&t) = scene.triangles.get(input as usize) else {
                    let shape = &scene.implicits[input as usize - n];
                    return GpuTriangle { material: shape.material, ..Default::default() };
                };
                GpuTriangle {
                    v0: t[0],
                    v1: t[1],
                    v2: t[2],
                    material: scene.triangle_material[input as usize],
                    area: area(t),
                    ..Default::default()
                }
            })
            .collect();
        let table = &scene.emissive;
        // A light's pmf goes to every BVH reference of its triangle (a split triangle has
        // several): whichever one a ray hits, MIS weighs it by the same pdf.
        let mut light_pmf = vec![0.0f32; scene.triangles.len()];
        let lights: Vec<GpuLightTri> = table
            .triangles
            .iter()
            .enumerate()
            .map(|(k, &input)| {
                let tri = bvh_index[input as usize];
                let pmf = table.pmf(k);
                light_pmf[input as usize] = pmf;
                GpuLightTri { tri, cdf: table.cdf[k], pmf, area: triangles[tri as usize].area }
            })
            .collect();
        for (t, &input) in triangles.iter_mut().zip(prim_order) {
            t.light_pmf = light_pmf.get(input as usize).copied().unwrap_or(0.0);
        }
        let vertices: Vec<GpuVertex> = (0..scene.positions.len())
            .map(|i| {
                let n = scene.normals.get(i).copied().unwrap_or([0.0; 3]);
                let uv0 = scene.uv0.get(i).copied().unwrap_or([0.0; 2]);
                let uv1 = scene.uv1.get(i).copied().unwrap_or([0.0; 2]);
                let color = scene.colors.get(i).copied().unwrap_or(WHITE);
                GpuVertex {
                    normal_u: [n[0], n[1], n[2], uv0[0]],
                    v_uv1: [uv0[1], uv1[0], uv1[1], f32::from_bits(pack_color(color))],
                    tangent: scene.tangents.get(i).copied().unwrap_or([0.0; 4]),
                }
            })
            .collect();
        let mut gpu_textures = GpuTextures::default();
        let materials =
            scene.materials.iter().map(|m| gpu_material(scene, m, |r| gpu_textures.slot(scene, r))).collect();
        let punctual = punctual_lights(scene);
        if colored(&vertices) {
            gpu_textures.srgb_table();
        }
        let GpuTextures { textures, texels, .. } = gpu_textures;
        let emissive_power = table.total_power;
        Self { triangles, vertices, materials, lights, punctual, textures, texels, emissive_power }
    }
}

/// Material `m` of `scene` laid out for the GPU, each texture slot `slot`'s value for the
/// reference the slot uses (0 for none; the texture's index + 1 on upload). The one place that
/// decides which slots a material fills and which of its lobes are on: the upload and
/// [`SceneFeatures::of_scene`] both read their features from what it gives.
fn gpu_material(
    scene: &Scene,
    m: &Material,
    mut slot: impl FnMut(Option<&TextureRef>) -> u32,
) -> GpuMaterial {
    let sigma = m.attenuation();
    // A transmission texture scales a factor of 0 to nothing: no slot, no lookup.
    let transmission_texture = m.transmission_texture.as_ref().filter(|_| m.transmission_factor > 0.0);
    // So do the clear coat's to a coat of 0.
    let coated = m.clearcoat > 0.0;
    let coat_texture = m.clearcoat_texture.as_ref().filter(|_| coated);
    let coat_roughness_texture = m.clearcoat_roughness_texture.as_ref().filter(|_| coated);
    let coat_normal_texture = m.clearcoat_normal_texture.as_ref().filter(|_| coated);
    // And the film's to a film of weight 0.
    let film = m.iridescence > 0.0;
    let film_texture = m.iridescence_texture.as_ref().filter(|_| film);
    let film_thickness_texture = m.iridescence_thickness_texture.as_ref().filter(|_| film);
    // And the anisotropy texture to a strength of 0 (or a scene without tangents).
    let anisotropy_texture =
        m.anisotropy_texture.as_ref().filter(|_| m.anisotropic() && !scene.tangents.is_empty());
    // And the sheen's to no sheen (a colour of 0).
    let sheened = m.sheen_color.iter().any(|&c| c > 0.0);
    let sheen_color_texture = m.sheen_color_texture.as_ref().filter(|_| sheened);
    let sheen_roughness_texture = m.sheen_roughness_texture.as_ref().filter(|_| sheened);
    // And the diffuse transmission's to a factor of 0.
    let through = m.diffuse_transmission > 0.0;
    let through_texture = m.diffuse_transmission_texture.as_ref().filter(|_| through);
    let through_color_texture = m.diffuse_transmission_color_texture.as_ref().filter(|_| through);
    // And the volume's thickness texture without a volume.
    let thickness_texture = m.thickness_texture.as_ref().filter(|_| m.volume);
    GpuMaterial {
        // In MATERIAL_SLOT_* order.
        textures: [
            [
                slot(m.base_color_texture.as_ref()),
                slot(m.metallic_roughness_texture.as_ref()),
                slot(m.emissive_texture.as_ref()),
                if scene.tangents.is_empty() { 0 } else { slot(m.normal_texture.as_ref()) },
            ],
            [
                slot(m.occlusion_texture.as_ref()),
                slot(m.parallax.as_ref().map(|p| &p.height)),
                slot(m.specular_texture.as_ref()),
                slot(m.specular_color_texture.as_ref()),
            ],
            [
                slot(transmission_texture),
                slot(coat_texture),
                slot(coat_roughness_texture),
                if scene.tangents.is_empty() { 0 } else { slot(coat_normal_texture) },
            ],
            [
                slot(anisotropy_texture),
                slot(film_texture),
                slot(film_thickness_texture),
                slot(sheen_color_texture),
            ],
            [
                slot(sheen_roughness_texture),
                slot(through_texture),
                slot(through_color_texture),
                slot(thickness_texture),
            ],
        ],
        tex_transform: TexTransforms(transforms([
            m.base_color_texture.as_ref(),
            m.metallic_roughness_texture.as_ref(),
            m.emissive_texture.as_ref(),
            m.normal_texture.as_ref(),
            m.occlusion_texture.as_ref(),
            m.parallax.as_ref().map(|p| &p.height),
            m.specular_texture.as_ref(),
            m.specular_color_texture.as_ref(),
            transmission_texture,
            coat_texture,
            coat_roughness_texture,
            coat_normal_texture,
            anisotropy_texture,
            film_texture,
            film_thickness_texture,
            sheen_color_texture,
            sheen_roughness_texture,
            through_texture,
            through_color_texture,
            thickness_texture,
        ])),
        base_color: m.base_color_factor,
        emissive_rough: {
            let e = m.emission();
            [e[0], e[1], e[2], m.roughness]
        },
        specular: [
            m.specular_color_factor[0],
            m.specular_color_factor[1],
            m.specular_color_factor[2],
            m.specular_factor,
        ],
        params: [m.metallic, m.ior, m.transmission_factor, m.alpha_cutoff],
        clearcoat: [m.clearcoat, m.clearcoat_roughness, 0.0, 0.0],
        parallax: m.parallax.map_or([0.0; 4], |p| [p.scale, p.layers as f32, p.refinement as f32, 0.0]),
        sheen: [m.sheen_color[0], m.sheen_color[1], m.sheen_color[2], m.sheen_roughness],
        iridescence: [
            m.iridescence,
            m.iridescence_ior,
            m.iridescence_thickness[0],
            m.iridescence_thickness[1],
        ],
        diffuse_transmission: [
            m.diffuse_transmission_color[0],
            m.diffuse_transmission_color[1],
            m.diffuse_transmission_color[2],
            m.diffuse_transmission,
        ],
        volume: [
            if m.volume { m.thickness } else { 0.0 },
            if m.disperses() { m.dispersion } else { 0.0 },
            0.0,
            0.0,
        ],
        anisotropy: if m.anisotropic() {
            let (sin, cos) = m.anisotropy_rotation.sin_cos();
            [m.anisotropy_strength, cos, sin, 0.0]
        } else {
            [0.0; 4]
        },
        flags: [
            if m.double_sided { GpuMaterial::DOUBLE_SIDED } else { 0 }
                | if m.volume { GpuMaterial::VOLUME } else { 0 }
                | if m.unlit { GpuMaterial::UNLIT } else { 0 },
            sigma[0].to_bits(),
            sigma[1].to_bits(),
            sigma[2].to_bits(),
        ],
    }
}

impl SceneFeatures {
    /// The features of `scene`, lit by an environment map if `env_map`, from the scene as
    /// loaded: what [`SceneFeatures::of`] gives for its upload ([`GpuScene::upload`], then
    /// [`GpuScene::set_environment`] if `env_map`), known before the BVH is built and the scene
    /// uploaded, so that the pipelines specialised on them can be created meanwhile. The
    /// materials' features come from `gpu_material` as the upload's do; the rest from the
    /// scene's lists the upload's arrays are made from (tests/scene/ checks that the two agree
    /// on every scene at hand); the alpha classes and the register stack from `bvh`, the BVH
    /// built for the upload.
    pub fn of_scene(scene: &Scene, bvh: &SceneBvh, env_map: bool) -> Self {
        let materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .map(|m| gpu_material(scene, m, |r| used_texture(scene, r).is_some() as u32))
            .collect();
        let slots = texture_slots(&materials);
        Self {
            textures: slots != 0,
            // The BVH's triangles with their alpha bits as classified (implicit shapes are never
            // alpha-tested).
            alpha: bvh.alpha.iter().any(|a| a.is_some_and(|bits| bits != 0)),
            lights: !scene.emissive.triangles.is_empty(),
            punctual: !scene.lights.is_empty(),
            env_map,
            transmission: transmits(&materials),
            // The vertices past the colour list are white.
            colors: scene.colors.iter().take(scene.positions.len()).any(|&c| pack_color(c) != OPAQUE_WHITE),
            unlit: unlit(&materials),
            clearcoat: coated(&materials),
            texture_slots: slots,
            implicit: !scene.implicits.is_empty(),
            parallax: parallax(&materials),
            sheen: sheened(&materials),
            iridescence: iridescent(&materials),
            anisotropy: anisotropic(&materials),
            diffuse_transmission: diffusely_transmits(&materials),
            dispersion: disperses(&materials),
            bvh_stack: register_stack(bvh.stack_depth),
        }
    }
}

impl GpuScene {
    /// The scene's binding block, by name: the same numbers in every kernel that reads the
    /// scene (`interface.rs`, `scene_bindings!`).
    pub fn resources(&self) -> SceneResources<'_> {
        SceneResources {
            bvh_node_texels: &self.bvh.nodes,
            bvh_tri_texels: &self.bvh.tris,
            triangle_texels: &self.triangles,
            vertex_texels: &self.vertices,
            material_texels: &self.materials,
            texture_texels: &self.textures,
            scene_texels: &self.texels,
            light_texels: &self.lights,
            punctual_texels: &self.punctual,
            env_texels: &self.env_texels,
            env_alias: &self.env_alias,
        }
    }

    /// One BVH position per scene triangle (its first): the BVH holds the pieces a build split
    /// off a large triangle as copies of the whole triangle, which a rasterizer must draw once.
    pub fn unique_triangles(&self) -> Vec<u32> {
        let mut seen = vec![false; self.bvh_stats.triangles];
        let mut out = Vec::with_capacity(self.bvh_stats.triangles);
        for (position, &input) in self.prim_order.iter().enumerate() {
            if let Some(first) = seen.get_mut(input as usize).filter(|s| !**s) {
                *first = true;
                out.push(position as u32);
            }
        }
        out
    }

    /// What the scene has, for the kernels specialised on it.
    pub fn features(&self) -> super::kernel::SceneFeatures {
        super::kernel::SceneFeatures::of(self)
    }

    /// Lights the scene with an environment map (replacing any previous one), uploading it
    /// with its importance-sampling tables.
    pub fn set_environment(&mut self, ctx: &Context, map: &EnvironmentMap) -> Result<()> {
        check_environment_limits(map, ctx.info())?;
        let table = map.distribution();
        let texels: Vec<[f32; 4]> =
            map.texels.iter().zip(&table.pdf_uv).map(|(t, &pdf)| [t[0], t[1], t[2], pdf]).collect();
        let alias: Vec<[u32; 2]> = table.rows.iter().chain(&table.columns).map(|e| e.texel()).collect();
        self.env_texels = upload_rgba32ui(ctx, "environment texels", &texels)?;
        self.env_alias = upload_rg32ui(ctx, "environment alias", &alias)?;
        self.env_size = Some((map.width as u32, map.height as u32));
        self.env_luminance = table.mean_luminance;
        Ok(())
    }

    /// Builds the BVH and uploads everything.
    /// A scene too large for the device's storage buffers is one [`Error::Scene`] naming it.
    pub fn upload(ctx: &Context, scene: &Scene) -> Result<Self> {
        Self::upload_with(ctx, scene, SceneBvh::build(scene)?)
    }

    /// [`GpuScene::upload`] around a BVH already built for `scene` (its GPU layout uploaded as
    /// it is).
    pub fn upload_with(ctx: &Context, scene: &Scene, bvh: SceneBvh) -> Result<Self> {
        let SceneBvh { bvh, alpha, nodes, .. } = bvh;
        let arrays = SceneArrays::with_alpha(scene, bvh, alpha);
        arrays.check_limits(&scene.name, ctx.info())?;
        let bvh = GpuBvh::upload_nodes(ctx, &arrays.bvh, nodes)?;
        let mut uploaded = Self::with_gpu_bvh(ctx, &arrays, bvh)?;
        // An animated scene keeps its host BVH for refits, and its positions for the motion.
        uploaded.host_bvh = scene.animation.is_some().then_some(arrays.bvh);
        uploaded.positions = scene.animation.is_some().then(|| scene.positions.clone());
        Ok(uploaded)
    }

    /// Uploads arrays already laid out (tests keep them to compare against).
    pub fn from_arrays(ctx: &Context, arrays: &SceneArrays) -> Result<Self> {
        Self::with_gpu_bvh(ctx, arrays, GpuBvh::upload(ctx, &arrays.bvh)?)
    }

    /// Uploads `arrays` around their BVH already uploaded.
    fn with_gpu_bvh(ctx: &Context, arrays: &SceneArrays, bvh: GpuBvh) -> Result<Self> {
        Ok(Self {
            bvh,
            triangles: upload_rgba32ui(ctx, "scene triangles", &arrays.triangles)?,
            vertices: upload_rgba32ui(ctx, "scene vertices", &arrays.vertices)?,
            materials: upload_rgba32ui(ctx, "scene materials", &material_texels(&arrays.materials))?,
            lights: upload_rgba32ui(ctx, "scene lights", &arrays.lights)?,
            light_count: arrays.lights.len() as u32,
            emissive_power: arrays.emissive_power,
            punctual: upload_rgba32ui(ctx, "scene punctual lights", &arrays.punctual)?,
            punctual_count: arrays.punctual.len() as u32,
            punctual_lights: arrays.punctual.clone(),
            bounds: arrays.bvh.nodes.first().map_or([[0.0; 3]; 2], |n| [n.aabb_min, n.aabb_max]),
            textures: upload_rgba32ui(ctx, "scene textures", &arrays.textures)?,
            texels: upload_rg32ui(ctx, "scene texels", &arrays.texels)?,
            texture_count: arrays.textures.len() as u32,
            texture_slots: texture_slots(&arrays.materials),
            has_transmission: transmits(&arrays.materials),
            // The alpha bits with_bvh wrote into the BVH triangles.
            has_alpha: arrays.bvh.tris.iter().any(|t| t.v1[3].to_bits() != 0),
            has_blend: arrays.bvh.tris.iter().any(|t| t.v1[3].to_bits() == 2),
            has_colors: colored(&arrays.vertices),
            has_unlit: unlit(&arrays.materials),
            has_clearcoat: coated(&arrays.materials),
            has_sheen: sheened(&arrays.materials),
            has_iridescence: iridescent(&arrays.materials),
            has_anisotropy: anisotropic(&arrays.materials),
            has_diffuse_transmission: diffusely_transmits(&arrays.materials),
            has_dispersion: disperses(&arrays.materials),
            has_implicit: arrays.bvh.procedurals > 0,
            has_parallax: parallax(&arrays.materials),
            env_texels: upload_rgba32ui(ctx, "environment texels", &[[0.0f32; 4]])?,
            env_alias: upload_rg32ui(ctx, "environment alias", &[[0u32; 2]])?,
            env_size: None,
            env_luminance: 0.0,
            bvh_stats: arrays.bvh.stats.clone(),
            prim_order: arrays.bvh.prim_order.clone(),
            alpha: arrays.alpha.clone(),
            host_bvh: None,
            positions: None,
            vertex_motion: Buffer::upload(ctx, "no vertex motion", &[[0.0f32; 4]], STORAGE)?,
            moved: false,
            geometry_generation: 0,
        })
    }

    /// Takes `scene`'s moved geometry (the same triangles, posed anew: [`Scene::pose`]) and
    /// brings the BVH to it by `how`, then re-uploads what shading reads as
    /// [`GpuScene::update`] does; the environment stays. A refit needs the scene to have been
    /// uploaded with its animation source (the host BVH is kept only then). The triangle count
    /// and each triangle's alpha class must not change. `bvh_stats.build_ms` is then the refit's
    /// or the rebuild's time. Either may change the walk's stack depth (the 4-wide collapse
    /// follows the boxes), which the kernels are specialised for: [`crate::render::Passes::for_moved`].
    /// Replaces buffers, so no command buffer using this scene may be pending.
    pub fn update_geometry(&mut self, ctx: &Context, scene: &Scene, how: BvhUpdate) -> Result<()> {
        self.check_same_triangles(scene)?;
        let clock = std::time::Instant::now();
        let (bvh, alpha) = match how {
            BvhUpdate::Refit => {
                let boxes = scene_boxes(scene)?;
                let mut bvh = self.host_bvh.take().ok_or_else(|| {
                    Error::Invalid(format!(
                        "scene '{}' was uploaded without an animation source: its BVH can only be rebuilt",
                        scene.name
                    ))
                })?;
                // A refit checks its input before it moves anything: on an error the tree stays.
                if let Err(e) = bvh.refit(&scene.triangle_soup(), &boxes) {
                    self.host_bvh = Some(bvh);
                    return Err(e);
                }
                (bvh, self.alpha.clone())
            }
            BvhUpdate::Rebuild => build_scene_bvh(scene)?,
        };
        let ms = clock.elapsed().as_secs_f64() * 1e3;
        let arrays = SceneArrays::with_alpha(scene, bvh, alpha);
        arrays.check_limits(&scene.name, ctx.info())?;
        let gpu_bvh = GpuBvh::upload(ctx, &arrays.bvh)?;
        let mut next = Self::with_gpu_bvh(ctx, &arrays, gpu_bvh)?;
        next.bvh_stats.build_ms = ms;
        // The vertices' motion from the positions this scene had (known where it kept them, and
        // meaningful for the same vertices only).
        if let Some(before) = self.positions.as_ref().filter(|p| p.len() == scene.positions.len()) {
            let motion: Vec<[f32; 4]> = scene
                .positions
                .iter()
                .zip(before)
                .map(|(p, q)| [p[0] - q[0], p[1] - q[1], p[2] - q[2], 0.0])
                .collect();
            next.vertex_motion = Buffer::upload(ctx, "vertex motion", &motion, STORAGE)?;
            next.moved = true;
        }
        next.positions = Some(scene.positions.clone());
        next.geometry_generation = self.geometry_generation + 1;
        std::mem::swap(&mut next.env_texels, &mut self.env_texels);
        std::mem::swap(&mut next.env_alias, &mut self.env_alias);
        next.env_size = self.env_size;
        next.env_luminance = self.env_luminance;
        next.host_bvh = Some(arrays.bvh);
        *self = next;
        Ok(())
    }

    /// Whether the last [`GpuScene::update_geometry`] knew the positions before it: the G-buffer
    /// then writes each surface point's motion from them (its `motion` image), which temporal
    /// anti-aliasing follows. A scene uploaded without an animation source learns its positions
    /// at its first update, so it has motion from the second on.
    pub fn geometry_moved(&self) -> bool {
        self.moved
    }

    /// Geometry updates since the upload: a frame's history made at generation g follows the
    /// motion of generation g + 1 only.
    pub fn geometry_generation(&self) -> u64 {
        self.geometry_generation
    }

    /// The vertices' motion buffer the G-buffer kernel binds (one unread element when the
    /// geometry has not moved).
    pub(crate) fn vertex_motion(&self) -> &Buffer {
        &self.vertex_motion
    }

    /// The checks [`GpuScene::update`] and [`GpuScene::update_geometry`] share: the same
    /// triangle count and alpha classes as uploaded.
    fn check_same_triangles(&self, scene: &Scene) -> Result<()> {
        if scene.triangles.len() != self.bvh_stats.triangles {
            return Err(Error::Invalid(format!(
                "scene '{}' has {} triangles but was uploaded with {}: geometry changes need a new upload",
                scene.name,
                scene.triangles.len(),
                self.bvh_stats.triangles
            )));
        }
        if bvh_alpha(scene) != self.alpha {
            return Err(Error::Invalid(format!(
                "scene '{}' changes a material's alpha mode (opaque, mask, blend), an alpha-tested triangle's class (opaque or transparent wherever it can be hit) or whether a transparent one is a light: that needs a new upload",
                scene.name
            )));
        }
        Ok(())
    }

    /// Re-uploads what shading reads (materials, textures, vertex attributes, the emissive and
    /// punctual lights) from `scene`, keeping the BVH: for materials or lights changed after
    /// loading. The geometry must be the same (same triangles and positions), and so must each
    /// triangle's alpha bits in the BVH (its material's alpha mode and, for an alpha-tested one,
    /// its class from the texels: a new alpha factor or texture may move it, and a triangle
    /// transparent everywhere is not in the BVH at all, unless it is a light). Replaces buffers, so
    /// no command buffer using this scene may be pending (wait for the host's frame fence first).
    pub fn update(&mut self, ctx: &Context, scene: &Scene) -> Result<()> {
        self.check_same_triangles(scene)?;
        let arrays = ShadingArrays::new(scene, &self.prim_order);
        self.triangles = upload_rgba32ui(ctx, "scene triangles", &arrays.triangles)?;
        self.vertices = upload_rgba32ui(ctx, "scene vertices", &arrays.vertices)?;
        self.materials = upload_rgba32ui(ctx, "scene materials", &material_texels(&arrays.materials))?;
        self.lights = upload_rgba32ui(ctx, "scene lights", &arrays.lights)?;
        self.light_count = arrays.lights.len() as u32;
        self.emissive_power = arrays.emissive_power;
        self.punctual = upload_rgba32ui(ctx, "scene punctual lights", &arrays.punctual)?;
        self.punctual_count = arrays.punctual.len() as u32;
        self.punctual_lights = arrays.punctual.clone();
        self.textures = upload_rgba32ui(ctx, "scene textures", &arrays.textures)?;
        self.texels = upload_rg32ui(ctx, "scene texels", &arrays.texels)?;
        self.texture_count = arrays.textures.len() as u32;
        self.texture_slots = texture_slots(&arrays.materials);
        self.has_transmission = transmits(&arrays.materials);
        self.has_colors = colored(&arrays.vertices);
        self.has_unlit = unlit(&arrays.materials);
        self.has_clearcoat = coated(&arrays.materials);
        self.has_parallax = parallax(&arrays.materials);
        self.has_sheen = sheened(&arrays.materials);
        self.has_iridescence = iridescent(&arrays.materials);
        self.has_anisotropy = anisotropic(&arrays.materials);
        self.has_diffuse_transmission = diffusely_transmits(&arrays.materials);
        self.has_dispersion = disperses(&arrays.materials);
        Ok(())
    }
}

/// Whether some vertex's colour (as [`pack_color`] packed it) differs from opaque white.
fn colored(vertices: &[GpuVertex]) -> bool {
    vertices.iter().any(|v| v.v_uv1[3].to_bits() != OPAQUE_WHITE)
}

/// Opaque white, linear.
const WHITE: [f32; 4] = [1.0; 4];

/// Opaque white as [`pack_color`] packs it (a vertex without a `COLOR_0` gets it).
const OPAQUE_WHITE: u32 = u32::MAX;

/// A linear `COLOR_0` as the GPU vertex keeps it: RGBA8, rgb sRGB-encoded (8 bits hold dark
/// colours better so), alpha linear, red in the low byte (`unpackUnorm4x8`'s order).
fn pack_color(c: [f32; 4]) -> u32 {
    let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
    let rgb = [0, 1, 2].map(|k| byte(crate::color::srgb_encode(c[k])));
    rgb[0] | rgb[1] << 8 | rgb[2] << 16 | byte(c[3]) << 24
}

/// Uploads 16-byte-aligned structs as a storage texel buffer of RGBA32UI texels.
fn upload_rgba32ui<T: bytemuck::Pod>(ctx: &Context, name: &str, items: &[T]) -> Result<TexelBuffer> {
    TexelBuffer::upload(ctx, name, items, raw::Format::R32G32B32A32_UINT, 16)
}

/// The 16-bit unorm a texture channel's 8-bit `code` is stored as on the GPU: its linear value
/// (sRGB-decoded when `srgb`), rounded to the nearest 65535th (`texture.glsl` reads it back as
/// `value / 65535`). A linear code v is stored as v·257, which reads back as v/255 exactly.
pub fn texel_unorm16(code: u8, srgb: bool) -> u32 {
    let c = f32::from(code) / 255.0;
    let linear = if srgb { crate::color::srgb_decode(c) } else { c };
    (linear * 65535.0 + 0.5) as u32
}

/// Uploads `items` as a storage texel buffer of RG32UI texels (the scene texels, the
/// environment's alias tables).
fn upload_rg32ui(ctx: &Context, name: &str, items: &[[u32; 2]]) -> Result<TexelBuffer> {
    TexelBuffer::upload(ctx, name, items, raw::Format::R32G32_UINT, 8)
}

/// Each scene triangle's alpha bits in the BVH ([`triangle_alpha`]), or `None` for one the BVH
/// leaves out: never hit ([`ALPHA_NEVER_HIT`]) and not a light (the emissive table names its
/// triangles' BVH slots; a never-hit light keeps its slot and the walk rejects it).
pub(crate) fn bvh_alpha(scene: &Scene) -> Vec<Option<u32>> {
    let mut emissive = vec![false; scene.triangles.len()];
    for &t in &scene.emissive.triangles {
        if let Some(e) = emissive.get_mut(t as usize) {
            *e = true;
        }
    }
    (0..scene.triangles.len())
        .into_par_iter()
        .map(|t| {
            let bits = triangle_alpha(scene, t);
            (bits != ALPHA_NEVER_HIT || emissive[t]).then_some(bits)
        })
        .collect()
}

/// The traversal's alpha bits of triangle `t` (scene order): 0 opaque, 1 mask, 2 blend as its
/// material's alpha mode, but 0 for a masked triangle whose alpha is above the cutoff wherever a
/// ray can hit it, and [`ALPHA_NEVER_HIT`] for a masked or blended one whose alpha is below the
/// cutoff (blend: zero) everywhere, which the walk then never hits: the coarse form of opacity
/// micromaps. `bvh_alpha_opaque` (shading.glsl) multiplies the base colour factor's alpha, the
/// base colour texture's at the hit (level 0, its sampler's wrap and filter) and the vertex
/// colours' (8-bit, interpolated); bounded here by the factor, the texels a lookup within the
/// triangle's UVs can read (their box widened by one texel, wrapped as the sampler wraps) and the
/// three vertices' colours, with a margin of 1e-4 on the cutoff for the lookups' rounding. A
/// blended triangle keeps its test unless it is transparent: alpha 1 passes the stochastic test
/// but for a rounding of the filter's weights.
fn triangle_alpha(scene: &Scene, t: usize) -> u32 {
    const MARGIN: f32 = 1e-4;
    let Some(&m) = scene.triangle_material.get(t) else { return 0 };
    let bits = alpha_bits(scene, m);
    let (Some(material), Some(tri)) = (scene.materials.get(m as usize), scene.triangles.get(t)) else {
        return bits;
    };
    if bits == 0 {
        return 0;
    }
    let factor = material.base_color_factor[3];
    let colour =
        |v: u32| (pack_color(scene.colors.get(v as usize).copied().unwrap_or(WHITE)) >> 24) as f32 / 255.0;
    let colours = tri.map(colour);
    let mut lo = factor * colours.iter().copied().fold(f32::INFINITY, f32::min);
    let mut hi = factor * colours.iter().copied().fold(0.0f32, f32::max);
    if let Some((r, texture)) = used_texture(scene, material.base_color_texture.as_ref()) {
        let Some((a, b)) = texel_alpha_range(scene, tri, r, texture) else { return bits };
        lo *= a;
        hi *= b;
    }
    match bits {
        1 if lo > material.alpha_cutoff + MARGIN => 0,
        1 if hi < material.alpha_cutoff - MARGIN => ALPHA_NEVER_HIT,
        2 if hi <= 0.0 => ALPHA_NEVER_HIT,
        _ => bits,
    }
}

/// The least and greatest alpha (0 to 1) of the texels of `texture` a lookup at a point of
/// triangle `tri` can read (`None` for a texture without texels, or UVs not finite or spanning
/// more texels than are worth scanning).
fn texel_alpha_range(scene: &Scene, tri: &[u32; 3], r: &TextureRef, texture: &Texture) -> Option<(f32, f32)> {
    let uvs = if r.tex_coord == 1 { &scene.uv1 } else { &scene.uv0 };
    let (w, h) = (texture.width as i64, texture.height as i64);
    if w == 0 || h == 0 {
        return None;
    }
    let t = r.transform;
    let mut bounds = [[f64::INFINITY, f64::NEG_INFINITY]; 2];
    for &v in tri {
        let [u, v] = uvs.get(v as usize).copied().unwrap_or([0.0; 2]);
        let st = [t[0][0] * u + t[0][1] * v + t[0][2], t[1][0] * u + t[1][1] * v + t[1][2]];
        for (axis, &x) in st.iter().enumerate() {
            let x = x as f64 * [w, h][axis] as f64;
            bounds[axis] = [bounds[axis][0].min(x), bounds[axis][1].max(x)];
        }
    }
    // Texel k covers [k, k + 1); a bilinear lookup at x reads floor(x - 1/2) and the next.
    let span = |[lo, hi]: [f64; 2], size: i64| -> Option<(i64, i64)> {
        (lo.is_finite() && hi.is_finite() && hi - lo < 4.0 * size as f64 + 4.0)
            .then(|| (lo.floor() as i64 - 1, hi.floor() as i64 + 1))
    };
    let (x0, x1) = span(bounds[0], w)?;
    let (y0, y1) = span(bounds[1], h)?;
    let wrap = |k: i64, size: i64, mode: crate::scene::Wrap| match mode {
        crate::scene::Wrap::Repeat => k.rem_euclid(size),
        crate::scene::Wrap::ClampToEdge => k.clamp(0, size - 1),
        crate::scene::Wrap::MirroredRepeat => {
            let m = k.rem_euclid(2 * size);
            if m < size {
                m
            } else {
                2 * size - 1 - m
            }
        }
    };
    if (x1 - x0 + 1).min(2 * w + 1) * (y1 - y0 + 1).min(2 * h + 1) > 1 << 22 {
        return None;
    }
    let (mut lo, mut hi) = (u8::MAX, u8::MIN);
    let columns: Vec<i64> = (x0..=x1.min(x0 + 2 * w)).map(|x| wrap(x, w, texture.sampler.wrap_s)).collect();
    for y in y0..=y1.min(y0 + 2 * h) {
        let row = wrap(y, h, texture.sampler.wrap_t);
        for &x in &columns {
            let a = *texture.rgba8.get(((row * w + x) * 4 + 3) as usize)?;
            lo = lo.min(a);
            hi = hi.max(a);
        }
    }
    Some((lo as f32 / 255.0, hi as f32 / 255.0))
}

/// The traversal's alpha bits of material `material` (0 opaque, 1 mask, 2 blend).
fn alpha_bits(scene: &Scene, material: u32) -> u32 {
    match scene.materials.get(material as usize).map(|m| m.alpha_mode) {
        Some(AlphaMode::Mask) => 1,
        Some(AlphaMode::Blend) => 2,
        _ => 0,
    }
}

/// The reference and its texture when `reference` names a texture `scene` has (a slot that
/// names none stays empty).
fn used_texture<'a, 'r>(
    scene: &'a Scene,
    reference: Option<&'r TextureRef>,
) -> Option<(&'r TextureRef, &'a Texture)> {
    let r = reference?;
    Some((r, scene.textures.get(r.texture as usize)?))
}

fn transmits(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.params[2] > 0.0)
}

/// The texture slots some material fills, bit k for `MATERIAL_SLOT_*` k.
fn texture_slots(materials: &[GpuMaterial]) -> u32 {
    let slots = MATERIAL_TEXTURE_SLOTS as usize;
    materials.iter().fold(0, |bits, m| {
        (0..slots).filter(|&k| m.textures[k / 4][k % 4] != 0).fold(bits, |b, k| b | 1 << k)
    })
}

fn unlit(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.flags[0] & GpuMaterial::UNLIT != 0)
}

fn coated(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.clearcoat[0] > 0.0)
}

/// `KHR_materials_sheen`'s albedo table (src/sheen.rs), computed by build.rs.
const SHEEN_TABLE: [f32; crate::sheen::TABLE_SIZE * crate::sheen::TABLE_SIZE] =
    include!(concat!(env!("OUT_DIR"), "/include/sheen_table.rs"));

/// The material texels: the materials, then, when some material has a sheen, the sheen's albedo
/// table (`sheen_table_texel` in shading.glsl reads it from the end; only kernels specialised for
/// the sheen do).
fn material_texels(materials: &[GpuMaterial]) -> Vec<[u32; 4]> {
    let mut texels: Vec<[u32; 4]> = bytemuck::cast_slice(materials).to_vec();
    if sheened(materials) {
        texels.extend(SHEEN_TABLE.chunks(4).map(|c| [0, 1, 2, 3].map(|k| c[k].to_bits())));
    }
    texels
}

/// Whether some material has a thin film (an iridescence factor above 0).
fn iridescent(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.iridescence[0] > 0.0)
}

/// Whether some material has a sheen (a sheen colour above 0).
fn sheened(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.sheen[..3].iter().any(|&c| c > 0.0))
}

/// Whether some material transmits diffusely (a diffuse transmission factor above 0).
fn diffusely_transmits(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.diffuse_transmission[3] > 0.0)
}

/// Whether some material disperses (a transmitting volume's dispersion above 0).
fn disperses(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.volume[1] > 0.0)
}

/// Whether some material is anisotropic (a strength above 0).
fn anisotropic(materials: &[GpuMaterial]) -> bool {
    materials.iter().any(|m| m.anisotropy[0] > 0.0)
}

fn parallax(materials: &[GpuMaterial]) -> bool {
    let slot = MATERIAL_SLOT_HEIGHT as usize;
    materials.iter().any(|m| m.textures[slot / 4][slot % 4] != 0)
}

/// The scene's punctual lights with their selection table: by power (KHR_lights_punctual's
/// intensity × colour luminance, times 4π for a point light, the cone's solid angle for a spot,
/// and the scene's cross-section πr² for a directional light, as pbrt's `Phi`), uniform if all
/// are black. Shading evaluates every light up to a few and samples that many by this table
/// beyond (`punctual_direct` in `shading.glsl`).
fn punctual_lights(scene: &Scene) -> Vec<GpuLight> {
    use crate::scene::LightKind;
    use std::f32::consts::PI;
    let (lo, hi) = scene.bounds();
    let radius = 0.5 * (glam::Vec3::from(hi) - glam::Vec3::from(lo)).length();
    let mut lights: Vec<GpuLight> = scene.lights.iter().map(gpu_light).collect();
    let power: Vec<f64> = scene
        .lights
        .iter()
        .map(|light| {
            let [r, g, b] = light.color.map(|c| c * light.intensity);
            let luminance = crate::color::luminance([r, g, b]).max(0.0);
            let cone = 0.5 * (light.inner_cone_angle.cos() + light.outer_cone_angle.cos());
            f64::from(luminance)
                * f64::from(match light.kind {
                    LightKind::Point => 4.0 * PI,
                    LightKind::Spot => 2.0 * PI * (1.0 - cone),
                    LightKind::Directional => PI * radius * radius,
                })
        })
        .collect();
    // In f64: with many lights an f32 sum would be off by more than a single light's share.
    let total: f64 = power.iter().sum();
    let n = lights.len() as f64;
    let mut cdf = 0.0;
    for (light, &p) in lights.iter_mut().zip(&power) {
        let pmf = if total > 0.0 && total.is_finite() { p / total } else { 1.0 / n };
        cdf += pmf;
        light.intensity[3] = cdf as f32;
        light.cone[2] = pmf as f32;
    }
    if let Some(last) = lights.last_mut() {
        last.intensity[3] = 1.0;
    }
    lights
}

fn gpu_light(light: &crate::scene::Light) -> GpuLight {
    use crate::scene::LightKind;
    let kind = match light.kind {
        LightKind::Point => GpuLight::POINT,
        LightKind::Spot => GpuLight::SPOT,
        LightKind::Directional => GpuLight::DIRECTIONAL,
    };
    let (cos_outer, cos_inner) = (light.outer_cone_angle.cos(), light.inner_cone_angle.cos());
    let p = light.position;
    let d = light.direction;
    let c = light.color.map(|c| c * light.intensity);
    GpuLight {
        position_range: [p[0], p[1], p[2], light.range.unwrap_or(0.0)],
        direction_kind: [d[0], d[1], d[2], kind],
        intensity: [c[0], c[1], c[2], 0.0],
        cone: [cos_outer, 1.0 / (cos_inner - cos_outer).max(1e-4), 0.0, 0.0],
    }
}

/// The textures materials use, each uploaded once, in first-use order.
#[derive(Default)]
struct GpuTextures {
    index: std::collections::HashMap<u32, u32>,
    textures: Vec<GpuTexture>,
    texels: Vec<[u32; 2]>,
}

impl GpuTextures {
    /// Starts the texel buffer with the sRGB decoding table if it is not there yet (shading.glsl
    /// reads it for vertex colours: a table lookup costs CPU devices far less than pow, and is
    /// exact for 8-bit codes).
    fn srgb_table(&mut self) {
        if self.texels.is_empty() {
            self.texels
                .extend((0..256).map(|code| [crate::color::srgb_decode(code as f32 / 255.0).to_bits(), 0]));
        }
    }

    /// The GPU slot value (texture index + 1, or 0 for none) of a material's texture reference.
    fn slot(&mut self, scene: &Scene, reference: Option<&crate::scene::TextureRef>) -> u32 {
        let Some((r, texture)) = used_texture(scene, reference) else { return 0 };
        if let Some(&i) = self.index.get(&r.texture) {
            return i + 1;
        }
        self.srgb_table();
        use crate::scene::{Filter, Wrap};
        let wrap = |w: Wrap, clamp: u32, mirror: u32| match w {
            Wrap::Repeat => 0,
            Wrap::ClampToEdge => clamp,
            Wrap::MirroredRepeat => mirror,
        };
        let sampler = &texture.sampler;
        let flags = wrap(sampler.wrap_s, GpuTexture::WRAP_S_CLAMP, GpuTexture::WRAP_S_MIRROR)
            | wrap(sampler.wrap_t, GpuTexture::WRAP_T_CLAMP, GpuTexture::WRAP_T_MIRROR)
            | if sampler.mag_filter == Filter::Linear { GpuTexture::LINEAR } else { 0 }
            | if sampler.min_filter == Filter::Linear { GpuTexture::MIN_LINEAR } else { 0 }
            | if sampler.mipmap_filter == Filter::Linear { GpuTexture::MIP_LINEAR } else { 0 }
            | if texture.srgb { GpuTexture::SRGB } else { 0 };
        // The mip chain follows level 0, only where the sampler asks for mipmaps.
        let chain = if sampler.mipmaps { texture.mip_chain() } else { Vec::new() };
        let i = self.textures.len() as u32;
        self.textures.push(GpuTexture {
            offset: self.texels.len() as u32,
            width: texture.width,
            height: texture.height,
            flags,
            levels: 1 + chain.len() as u32,
            ..Default::default()
        });
        // Linear RGBA16 (unorm): an 8-bit code v is v·257 / 65535 = v / 255 exactly, an sRGB
        // code its decoded value within 2^-17. One texel read per texel on the GPU, where an
        // sRGB RGBA8 texel took four (the texel and three table entries).
        let decode: [u32; 256] = std::array::from_fn(|v| texel_unorm16(v as u8, texture.srgb));
        // Packed straight into the texel list (no list per level copied in after: fresh memory
        // costs a page fault per 4 KiB, a 2048² texture 32 MB).
        let pack = |p: &[u8]| {
            let [r, g, b] = [0, 1, 2].map(|c| decode[p[c] as usize]);
            [r | g << 16, b | (u32::from(p[3]) * 257) << 16]
        };
        let count = texture.rgba8.len() + chain.iter().map(|l| l.rgba8.len()).sum::<usize>();
        self.texels.reserve(count / 4);
        self.texels.extend(texture.rgba8.chunks_exact(4).map(pack));
        for level in &chain {
            self.texels.extend(level.rgba8.chunks_exact(4).map(pack));
        }
        self.index.insert(r.texture, i);
        i + 1
    }
}

/// The UV transforms of the texture slots (`MATERIAL_SLOT_*` order) as GPU rows (identity for an
/// empty slot), with the UV set in the first row's `w` and the slot's scale (the normal scale, the
/// occlusion strength; 1 otherwise) in the second's.
fn transforms(
    slots: [Option<&crate::scene::TextureRef>; MATERIAL_TEXTURE_SLOTS as usize],
) -> [[f32; 4]; 2 * MATERIAL_TEXTURE_SLOTS as usize] {
    let mut rows = [[0.0; 4]; 2 * MATERIAL_TEXTURE_SLOTS as usize];
    for (k, slot) in slots.iter().enumerate() {
        let (m, set, scale) = match slot {
            Some(r) => (r.transform, r.tex_coord as f32, r.scale),
            None => (crate::scene::IDENTITY_TRANSFORM, 0.0, 1.0),
        };
        rows[2 * k] = [m[0][0], m[0][1], m[0][2], set];
        rows[2 * k + 1] = [m[1][0], m[1][1], m[1][2], scale];
    }
    rows
}
