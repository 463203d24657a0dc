//! Texture mipmaps: the CPU mip chain (box filter in linear space, odd sizes, down to 1 × 1), the
//! G-buffer's ray-cone level of detail (a grazing checkerboard converges to its mean instead of
//! aliasing; magnified texels are untouched) and the path tracer's indifference to mips (it reads
//! level 0).

mod common;
#[path = "support/generate.rs"]
mod generate;

use common::Gpu;
use glam::Vec3;
use umbra::gpu::layout::GpuCamera;
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::passes::gbuffer::{GBuffer, GBufferData, GBufferPass};
use umbra::render::{path_trace, PathSettings};
use umbra::scene::{
    mip_level_count, texture_transform, Camera, Filter, Material, Sampler, Scene, Texture, TextureRef, Wrap,
    IDENTITY_TRANSFORM,
};

/// A `size` × `size` checker of single texels, black and white.
fn checker(size: u32, srgb: bool, sampler: Sampler) -> Texture {
    let rgba8 = (0..size * size)
        .flat_map(|i| {
            let v = if (i % size + i / size).is_multiple_of(2) { 0 } else { 255 };
            [v, v, v, 255]
        })
        .collect();
    Texture { name: "checker".into(), width: size, height: size, rgba8, srgb, sampler }
}

fn sampler(mipmaps: bool, mipmap_filter: Filter) -> Sampler {
    Sampler { mipmaps, mipmap_filter, ..Sampler::default() }
}

#[test]
fn mip_chain_of_a_checker_is_its_linear_mean() {
    // sRGB 0 and 255 average to linear 0.5, which encodes as 188 (a gamma-space average: 128).
    let srgb = checker(2, true, Sampler::default()).mip_chain();
    assert_eq!(srgb.len(), 1);
    assert_eq!((srgb[0].width, srgb[0].height), (1, 1));
    assert_eq!(srgb[0].rgba8, [188, 188, 188, 255]);
    // Linear data averages as stored: 127.5 rounds to 128.
    let linear = checker(8, false, Sampler::default()).mip_chain();
    let sizes: Vec<(u32, u32)> = linear.iter().map(|l| (l.width, l.height)).collect();
    assert_eq!(sizes, [(4, 4), (2, 2), (1, 1)]);
    for level in &linear {
        assert!(level.rgba8.chunks_exact(4).all(|t| t == [128, 128, 128, 255]), "{level:?}");
    }
}

#[test]
fn mip_chain_decodes_srgb_mid_tones_before_averaging() {
    // sRGB 188 is linear 0.5029; its average with 0 (0.2514) encodes as 137, where averaging the
    // codes as if linear gives 163. Codes 0 and 255 decode to themselves: the checker above cannot
    // tell.
    let rgba8 = [0, 0, 0, 255, 188, 188, 188, 255, 188, 188, 188, 255, 0, 0, 0, 255].to_vec();
    let texture =
        Texture { name: "grey".into(), width: 2, height: 2, rgba8, srgb: true, sampler: Sampler::default() };
    let chain = texture.mip_chain();
    assert_eq!(chain.len(), 1);
    assert_eq!(chain[0].rgba8, [137, 137, 137, 255]);
}

#[test]
fn mip_chain_of_odd_sizes_keeps_the_mean() {
    assert_eq!(mip_level_count(1, 1), 1);
    assert_eq!(mip_level_count(5, 3), 3);
    assert_eq!(mip_level_count(1, 64), 7);
    // A 5 × 3 texture of distinct values: 5 × 3 → 2 × 1 → 1 × 1, each level's mean that of level 0
    // (to the 8-bit rounding of each level).
    let (w, h) = (5u32, 3u32);
    let rgba8: Vec<u8> =
        (0..w * h).flat_map(|i| [(i * 17) as u8, (255 - i * 11) as u8, (i * i) as u8, 255]).collect();
    let texture = Texture {
        name: "odd".into(),
        width: w,
        height: h,
        rgba8: rgba8.clone(),
        srgb: false,
        sampler: Sampler::default(),
    };
    let mean = |texels: &[u8], c: usize| {
        texels.chunks_exact(4).map(|t| f64::from(t[c])).sum::<f64>() / (texels.len() / 4) as f64
    };
    let chain = texture.mip_chain();
    let sizes: Vec<(u32, u32)> = chain.iter().map(|l| (l.width, l.height)).collect();
    assert_eq!(sizes, [(2, 1), (1, 1)]);
    for level in &chain {
        assert_eq!(level.rgba8.len(), (level.width * level.height * 4) as usize);
        for c in 0..4 {
            let (m0, m) = (mean(&rgba8, c), mean(&level.rgba8, c));
            assert!(
                (m - m0).abs() <= 0.5,
                "channel {c}: mean {m} vs level 0 {m0} at {}x{}",
                level.width,
                level.height
            );
        }
    }
    // The first texel of level 1 covers columns [0, 2.5) of rows [0, 3): weights 0.4, 0.4, 0.2.
    let expected: f64 = (0..3)
        .map(|y| {
            let v = |x: u32| f64::from(rgba8[((y * w + x) * 4) as usize]);
            (0.4 * v(0) + 0.4 * v(1) + 0.2 * v(2)) / 3.0
        })
        .sum();
    assert_eq!(f64::from(chain[0].rgba8[0]), expected.round());
}

/// glTF minification filters map to the sampler: mipmaps for every *_MIPMAP_* mode and when
/// unspecified, the nearest level for *_MIPMAP_NEAREST, linear between levels otherwise.
#[test]
fn gltf_min_filters_choose_the_mip_mode() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join("textured.glb");
    let (mut json, bin) = generate::split_glb(&std::fs::read(path).unwrap());
    let expected = [
        (Some(9728), Filter::Nearest, false, Filter::Linear), // NEAREST
        (Some(9984), Filter::Nearest, true, Filter::Nearest), // NEAREST_MIPMAP_NEAREST
        (Some(9985), Filter::Linear, true, Filter::Nearest),  // LINEAR_MIPMAP_NEAREST
        (Some(9986), Filter::Nearest, true, Filter::Linear),  // NEAREST_MIPMAP_LINEAR
        (Some(9987), Filter::Linear, true, Filter::Linear),   // LINEAR_MIPMAP_LINEAR
        (None, Filter::Linear, true, Filter::Linear),         // left to the renderer
    ];
    for (min_filter, min, mipmaps, between) in expected {
        // Every sampler of the file gets the filter.
        for sampler in json["samplers"].as_array_mut().unwrap() {
            let sampler = sampler.as_object_mut().unwrap();
            match min_filter {
                Some(f) => sampler.insert("minFilter".into(), f.into()),
                None => sampler.remove("minFilter"),
            };
        }
        let glb = generate::glb(&serde_json::to_vec(&json).unwrap(), &bin);
        let scene = Scene::from_glb_bytes("filters.glb", &glb).unwrap();
        for texture in &scene.textures {
            let s = texture.sampler;
            assert_eq!(
                (s.min_filter, s.mipmaps, s.mipmap_filter),
                (min, mipmaps, between),
                "minFilter {min_filter:?}"
            );
        }
        let arrays = SceneArrays::new(&scene).unwrap();
        assert!(!arrays.textures.is_empty());
        for gpu in &arrays.textures {
            let levels = if mipmaps { mip_level_count(gpu.width, gpu.height) } else { 1 };
            assert_eq!(gpu.levels, levels, "minFilter {min_filter:?}");
        }
    }
}

/// A 400 m floor at y = 0 with an 8 × 8 single-texel sRGB checker repeating every metre (8 texels
/// per metre), seen from 1 m up, 20° down, 60° field of view. Nearest texels within a level, so a
/// sample at level 0 is black or white.
fn grazing_floor(sampler: Sampler) -> Scene {
    let sampler = Sampler { mag_filter: Filter::Nearest, min_filter: Filter::Nearest, ..sampler };
    let half = 200.0f32;
    let mut scene = Scene { name: "grazing checker floor".into(), ..Default::default() };
    let corners = [[-half, 0.0, -half], [half, 0.0, -half], [half, 0.0, half], [-half, 0.0, half]];
    scene.positions = corners.to_vec();
    scene.normals = vec![[0.0, 1.0, 0.0]; 4];
    scene.uv0 = corners.iter().map(|p| [p[0], p[2]]).collect();
    scene.triangles = vec![[0, 2, 1], [0, 3, 2]];
    scene.triangle_material = vec![0, 0];
    scene.textures.push(checker(8, true, sampler));
    scene.materials.push(Material {
        metallic: 0.0,
        base_color_texture: Some(TextureRef {
            texture: 0,
            tex_coord: 0,
            transform: IDENTITY_TRANSFORM,
            scale: 1.0,
        }),
        ..Default::default()
    });
    let down = 20f32.to_radians();
    scene.cameras.push(Camera {
        position: [0.0, 1.0, 0.0],
        forward: [0.0, -down.sin(), -down.cos()],
        up: [0.0, 1.0, 0.0],
        yfov: 60f32.to_radians(),
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    });
    scene.update_emissive();
    scene
}

const FLOOR_SIZE: (u32, u32) = (64, 64);
const FLOOR_TEXELS_PER_METRE: f32 = 8.0;

fn floor_gbuffer(gpu: &Gpu, scene: &Scene) -> GBufferData {
    gbuffer(gpu, scene, FLOOR_SIZE)
}

fn gbuffer(gpu: &Gpu, scene: &Scene, size: (u32, u32)) -> GBufferData {
    let camera = scene.camera(None).unwrap();
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let pass = GBufferPass::new(gpu, &gpu_scene).unwrap();
    let target = GBuffer::new(gpu, size).unwrap();
    let params = GBufferPass::params(&camera, size);
    gpu.record(|rec| pass.record(rec, &gpu_scene, &target.views(), &params, None)).unwrap();
    target.read(gpu).unwrap()
}

/// The ray cone's level of detail at each pixel of the grazing floor, computed on the CPU, with
/// the hit's uv (`None` above the horizon): log2 of the footprint t·α/|n·d| in texels.
fn floor_pixels(scene: &Scene) -> Vec<Option<(f32, [f32; 2])>> {
    let camera = scene.camera(None).unwrap();
    let (w, h) = FLOOR_SIZE;
    let c = GpuCamera::new(&camera, FLOOR_SIZE);
    let (origin, f, r, u) = (c.origin, c.forward, c.right, c.up);
    let v = Vec3::from;
    let spread = (2.0 * v(u).length() / h as f32).atan();
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let ndc = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / h as f32);
            let dir = (v(f) + ndc.0 * v(r) + ndc.1 * v(u)).normalize();
            let t = -origin[1] / dir.y;
            let p = v(origin) + t * dir;
            (dir.y < -1e-3 && t < 150.0)
                .then(|| ((t * spread / -dir.y * FLOOR_TEXELS_PER_METRE).log2(), [p.x, p.z]))
        })
        .collect()
}

fn floor_lods(scene: &Scene) -> Vec<Option<f32>> {
    floor_pixels(scene).iter().map(|p| p.map(|(lod, _)| lod)).collect()
}

/// The checker's level-0 texel (linear 0 or 1) at uv, or `None` within 0.02 texel of a texel
/// edge (where the GPU's and the CPU's hit points may pick different texels).
fn floor_texel(uv: [f32; 2]) -> Option<f32> {
    let s = uv.map(|c| c * FLOOR_TEXELS_PER_METRE);
    if s.iter().any(|c| (c - c.round()).abs() < 0.02) {
        return None;
    }
    let [x, y] = s.map(|c| c.floor() as i64);
    Some(if (x + y).rem_euclid(2) == 0 { 0.0 } else { 1.0 })
}

/// Pixels of the grazing floor between magnified and minified 2× (0 < lod < 1) have the base
/// colour of the level of detail the CPU computes for their ray cone: trilinear, the level-0
/// texel blended with level 1 (uniform sRGB 188) by the lod's fraction; nearest-level, level 0
/// below lod 0.5 and level 1 above; and through a texture transform that scales the uvs. Within 0.01 (half-float storage, lod to ~1e-3).
#[test]
fn gbuffer_lod_is_the_ray_cone_lod() {
    let gpu = Gpu::new();
    let grey = ((188.0f32 / 255.0 + 0.055) / 1.055).powf(2.4);
    for (mipmap_filter, transformed) in
        [(Filter::Linear, false), (Filter::Nearest, false), (Filter::Linear, true)]
    {
        let mut scene = grazing_floor(sampler(true, mipmap_filter));
        if transformed {
            // The same texels through KHR_texture_transform: uvs a quarter, scaled back up 4×
            // and offset by whole checks. The cone's lod accounts for the transform's scale.
            for uv in &mut scene.uv0 {
                *uv = uv.map(|c| c / 4.0);
            }
            let reference = scene.materials[0].base_color_texture.as_mut().unwrap();
            reference.transform = texture_transform([0.25, 0.5], 0.0, [4.0, 4.0]);
        }
        let g = floor_gbuffer(&gpu, &scene);
        let (mut checked, mut worst) = (0, 0.0f32);
        for (i, pixel) in floor_pixels(&scene).iter().enumerate() {
            let Some((lod, uv)) = *pixel else { continue };
            let Some(texel) = floor_texel(uv) else { continue };
            let expected = match mipmap_filter {
                _ if !(0.02..0.98).contains(&lod) => continue,
                Filter::Linear => texel + (grey - texel) * lod,
                Filter::Nearest if (lod - 0.5).abs() < 0.02 => continue,
                Filter::Nearest => {
                    if lod < 0.5 {
                        texel
                    } else {
                        grey
                    }
                }
            };
            let error = (g.base[i][0] - expected).abs();
            assert!(
                error < 0.01,
                "{mipmap_filter:?}: pixel {i}, lod {lod}: base {} vs {expected}",
                g.base[i][0]
            );
            worst = worst.max(error);
            checked += 1;
        }
        println!(
            "{mipmap_filter:?} between levels, transformed {transformed}: {checked} pixels with 0 < lod < 1, worst error {worst:.5}"
        );
        assert!(checked >= 50, "only {checked} pixels checked");
    }
}

/// Mean squared difference of the base colour's red channel between horizontal neighbours that
/// are both `far`, the number of such pairs, and the mean red over the far pixels.
fn neighbour_statistics(g: &GBufferData, far: &[bool]) -> (f64, usize, f64) {
    let w = g.size.0 as usize;
    let (mut sum, mut pairs) = (0.0f64, 0usize);
    for i in 0..far.len() {
        if i % w + 1 < w && far[i] && far[i + 1] {
            sum += f64::from(g.base[i][0] - g.base[i + 1][0]).powi(2);
            pairs += 1;
        }
    }
    let count = far.iter().filter(|&&f| f).count();
    let mean =
        (0..far.len()).filter(|&i| far[i]).map(|i| f64::from(g.base[i][0])).sum::<f64>() / count as f64;
    (sum / pairs.max(1) as f64, pairs, mean)
}

/// Far (minified at least 4×: lod > 2) pixels of the grazing floor: with mipmaps (trilinear, or
/// the nearest level) the base colour converges to the checker's linear mean 0.5, neighbours
/// differing by a mean squared difference below 0.002; without mipmaps it aliases, above 0.2 (a
/// full-contrast random pattern gives 0.5). Magnified pixels (lod < -0.5) are bit-identical
/// with and without mipmaps.
#[test]
fn gbuffer_ray_cones_filter_a_grazing_checkerboard() {
    let gpu = Gpu::new();
    let plain = grazing_floor(sampler(false, Filter::Linear));
    let lods = floor_lods(&plain);
    let far: Vec<bool> = lods.iter().map(|l| l.is_some_and(|l| l > 2.0)).collect();
    let near: Vec<bool> = lods.iter().map(|l| l.is_some_and(|l| l < -0.5)).collect();
    let near_count = near.iter().filter(|&&n| n).count();

    let aliased = floor_gbuffer(&gpu, &plain);
    let (msd, pairs, mean) = neighbour_statistics(&aliased, &far);
    println!(
        "no mipmaps: neighbour msd {msd:.4} over {pairs} pairs, mean {mean:.4}; {near_count} near pixels"
    );
    assert!(pairs >= 200 && near_count >= 200, "{pairs} far pairs, {near_count} near pixels");
    assert!(msd > 0.2, "without mipmaps the far floor should alias: neighbour msd {msd}");

    for mipmap_filter in [Filter::Linear, Filter::Nearest] {
        let filtered = floor_gbuffer(&gpu, &grazing_floor(sampler(true, mipmap_filter)));
        let (msd, _, mean) = neighbour_statistics(&filtered, &far);
        println!("mipmaps ({mipmap_filter:?} between levels): neighbour msd {msd:.6}, mean {mean:.4}");
        assert!(msd < 0.002, "{mipmap_filter:?}: far floor still aliases: neighbour msd {msd}");
        assert!(
            (mean - 0.5).abs() < 0.02,
            "{mipmap_filter:?}: far floor mean {mean}, not the linear mean 0.5"
        );
        for i in (0..near.len()).filter(|&i| near[i]) {
            assert_eq!(filtered.base[i], aliased.base[i], "{mipmap_filter:?}: magnified pixel {i} changed");
        }
        assert_eq!(filtered.depth, aliased.depth);
    }
}

/// A texture seen magnified everywhere (a 4 × 4 texture across a quad filling the view) gives the
/// same G-buffer, bit for bit, with or without its mip chain: lod ≤ 0 reads level 0.
#[test]
fn gbuffer_of_a_magnified_texture_ignores_mipmaps() {
    let gpu = Gpu::new();
    let scene_with = |mipmaps: bool| {
        let mut scene = Scene { name: "magnified".into(), ..Default::default() };
        scene.positions = vec![[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];
        scene.normals = vec![[0.0, 0.0, 1.0]; 4];
        scene.uv0 = scene.positions.iter().map(|p| [(p[0] + 1.0) / 2.0, (1.0 - p[1]) / 2.0]).collect();
        scene.triangles = vec![[0, 1, 2], [0, 2, 3]];
        scene.triangle_material = vec![0, 0];
        let rgba8 = (0..16u32)
            .flat_map(|i| [(i * 16) as u8, (255 - i * 13) as u8, (i * 40 % 256) as u8, 255])
            .collect();
        let sampler = Sampler {
            wrap_s: Wrap::ClampToEdge,
            wrap_t: Wrap::ClampToEdge,
            ..sampler(mipmaps, Filter::Linear)
        };
        scene.textures.push(Texture { name: "4x4".into(), width: 4, height: 4, rgba8, srgb: true, sampler });
        scene.materials.push(Material {
            base_color_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: IDENTITY_TRANSFORM,
                scale: 1.0,
            }),
            ..Default::default()
        });
        scene.cameras.push(Camera {
            position: [0.0, 0.0, 2.0],
            forward: [0.0, 0.0, -1.0],
            up: [0.0, 1.0, 0.0],
            yfov: 40f32.to_radians(),
            aspect: None,
            znear: 0.01,
            orthographic: None,
            jitter: [0.0; 2],
        });
        scene.update_emissive();
        scene
    };
    let (with, without) = (scene_with(true), scene_with(false));
    assert_eq!(SceneArrays::new(&with).unwrap().textures[0].levels, 3);
    let (a, b) = (gbuffer(&gpu, &with, (32, 32)), gbuffer(&gpu, &without, (32, 32)));
    assert!(a.material.iter().all(|m| m[0] == 0), "the quad fills the view");
    assert_eq!(a.base, b.base);
    assert_eq!(a.normal, b.normal);
}

/// The path tracer integrates a pixel's footprint by jittering its rays and reads level 0: its
/// image of the textured scene is bit-identical with and without mip chains in the texel buffer.
#[test]
fn path_tracer_reads_level_zero() {
    let gpu = Gpu::new();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join("textured.glb");
    let mipmapped = Scene::load(&path).unwrap();
    let mut flat = mipmapped.clone();
    for texture in &mut flat.textures {
        texture.sampler.mipmaps = false;
    }
    let arrays = SceneArrays::new(&mipmapped).unwrap();
    assert!(arrays.textures.iter().any(|t| t.levels > 1), "the textured scene should have mip chains");
    assert!(arrays.texels.len() > SceneArrays::new(&flat).unwrap().texels.len());
    let settings = PathSettings { size: (32, 32), spp: 2, ..Default::default() };
    let render = |scene: &Scene| {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        path_trace(&gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap()
    };
    let (a, b) = (render(&mipmapped), render(&flat));
    let bits = |v: &[[f32; 4]]| v.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&a.mean), bits(&b.mean));
    assert_eq!(bits(&a.albedo), bits(&b.albedo));
}
