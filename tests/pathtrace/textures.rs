//! Textures in the path tracer: wrap modes and transforms, normal maps, each slot on its own.

use crate::common::Gpu;
use crate::{camera, common, facing_quad, pixel_ray, render, scene_of};
use glam::Vec3;
use umbra::render::{PathImage, PathSettings};
use umbra::scene::Material;

/// A base-colour texture on a Lambert quad facing the camera under a constant environment of 1:
/// each pixel is exactly the linearised texel its UV selects, through each glTF wrap mode
/// (UVs run from −0.5 to 1.5 across the quad) and a KHR_texture_transform offset.
#[test]
fn textures_wrap_decode_and_transform() {
    use umbra::scene::{Filter, Sampler, Texture, TextureRef, Wrap};
    let gpu = Gpu::new();
    // 2×2 texels: red, green / blue, white (sRGB 200 = linear 0.578).
    let texels: [[u8; 4]; 4] = [[200, 0, 0, 255], [0, 200, 0, 255], [0, 0, 200, 255], [200, 200, 200, 255]];
    let linear = |c: u8| umbra::color::srgb_decode(c as f32 / 255.0);
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0); // sees x, y in about ±0.83
    for (wrap, offset) in
        [(Wrap::Repeat, 0.0), (Wrap::ClampToEdge, 0.0), (Wrap::MirroredRepeat, 0.0), (Wrap::Repeat, 0.5)]
    {
        let material = Material {
            metallic: 0.0,
            specular_factor: 0.0,
            base_color_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: umbra::scene::texture_transform([offset, 0.0], 0.0, [1.0, 1.0]),
                scale: 1.0,
            }),
            ..Default::default()
        };
        let mut scene = scene_of(&[(&quad, material, false)], cam);
        // UV = (x + 1) - 0.5 across, v downwards: (−0.5, −0.5) at the top left.
        scene.uv0 = scene.positions.iter().map(|p| [p[0] + 0.5, 0.5 - p[1]]).collect();
        scene.textures.push(Texture {
            name: "checker".into(),
            width: 2,
            height: 2,
            rgba8: texels.concat(),
            srgb: true,
            sampler: Sampler {
                wrap_s: wrap,
                wrap_t: wrap,
                mag_filter: Filter::Nearest,
                min_filter: Filter::Nearest,
                mipmaps: false,
                mipmap_filter: Filter::Nearest,
            },
        });
        let settings =
            PathSettings { size: (32, 32), spp: 4, env: [1.0; 3], max_bounces: 1, ..Default::default() };
        let image = render(&gpu, &scene, &settings);
        let mut checked = 0;
        for y in 0..32u32 {
            for x in 0..32u32 {
                let d = pixel_ray(&cam, settings.size, x, y);
                let p = Vec3::from(cam.position) + d * (cam.position[2] / -d.z);
                let uv = [p.x + 0.5 + offset, 0.5 - p.y];
                // Skip pixels whose footprint (±1 pixel) straddles a texel edge.
                let pixel = 2.0 * 0.83 / 32.0;
                let near_edge = uv.iter().any(|c| ((c * 2.0).round() - c * 2.0).abs() < 2.0 * pixel);
                if near_edge {
                    continue;
                }
                let wrap_coord = |c: f32| -> usize {
                    let i = (c * 2.0).floor() as i32;
                    let i = match wrap {
                        Wrap::Repeat => i.rem_euclid(2),
                        Wrap::ClampToEdge => i.clamp(0, 1),
                        Wrap::MirroredRepeat => {
                            let m = i.rem_euclid(4);
                            if m < 2 {
                                m
                            } else {
                                3 - m
                            }
                        }
                    };
                    i as usize
                };
                let t = texels[wrap_coord(uv[1]) * 2 + wrap_coord(uv[0])];
                let got = image.mean[(y * 32 + x) as usize];
                for c in 0..3 {
                    let expected = linear(t[c]);
                    assert!(
                        (got[c] - expected).abs() < 1e-4,
                        "{wrap:?} offset {offset} pixel ({x},{y}) uv {uv:?}: {got:?} vs texel {t:?}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 300, "{wrap:?}: only {checked} pixels checked");
    }
}

/// A white directional light shining along `direction` with `intensity`.
fn sun(direction: [f32; 3], intensity: f32) -> umbra::scene::Light {
    umbra::scene::Light {
        name: String::new(),
        kind: umbra::scene::LightKind::Directional,
        position: [0.0; 3],
        direction,
        color: [1.0; 3],
        intensity,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    }
}

/// A normal map on a quad facing the camera, lit by a directional light from the +x side: the
/// shading normal is the map's tangent-space normal through (tangent, bitangent, normal), so the
/// Lambert radiance follows the closed form for the tilted normal, scaled as `normalTexture.scale`
/// says; tilting towards the tangent's +x brightens, towards −x darkens.
#[test]
fn normal_maps_tilt_the_shading_normal() {
    use umbra::scene::{TextureRef, IDENTITY_TRANSFORM};
    let gpu = Gpu::new();
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0);
    let light_dir = Vec3::new(1.0, 0.0, 1.0).normalize(); // towards the light
    let albedo = 0.8f32;
    for (tilt, scale) in [(0.5f32, 1.0f32), (-0.5, 1.0), (0.5, 0.5)] {
        let texel = [
            ((tilt.sin() * 0.5 + 0.5) * 255.0).round() as u8,
            128,
            ((tilt.cos() * 0.5 + 0.5) * 255.0).round() as u8,
            255,
        ];
        let material = Material {
            metallic: 0.0,
            specular_factor: 0.0,
            base_color_factor: [albedo, albedo, albedo, 1.0],
            normal_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: IDENTITY_TRANSFORM,
                scale,
            }),
            ..Default::default()
        };
        let mut scene = scene_of(&[(&quad, material, false)], cam);
        scene.uv0 = scene.positions.iter().map(|p| [p[0] * 0.5 + 0.5, 0.5 - p[1] * 0.5]).collect();
        scene.tangents = vec![[1.0, 0.0, 0.0, 1.0]; scene.positions.len()];
        scene.textures.push(common::row_texture("tilt", &[texel]));
        scene.lights.push(sun((-light_dir).into(), 2.0));
        let settings = PathSettings { size: (16, 16), spp: 2, max_bounces: 1, ..Default::default() };
        let image = render(&gpu, &scene, &settings);
        let decoded = Vec3::new(texel[0] as f32, texel[1] as f32, texel[2] as f32) / 255.0 * 2.0 - Vec3::ONE;
        let mapped = Vec3::new(decoded.x * scale, decoded.y * scale, decoded.z).normalize();
        let expected = albedo / std::f32::consts::PI * 2.0 * mapped.dot(light_dir).max(0.0);
        let got = image.mean[8 * 16 + 8][0];
        eprintln!(
            "tilt {tilt} scale {scale}: {got} (flat would be {})",
            albedo / std::f32::consts::PI * 2.0 * light_dir.z
        );
        assert!((got - expected).abs() < 1e-3 * expected, "tilt {tilt} scale {scale}: {got} vs {expected}");
    }
}

/// Each texture slot is read on its own: a quad whose material has a constant texture in one
/// slot only (base colour, metallic-roughness or emissive) renders as the same material with the
/// texel folded into the slot's factor. The kernels are specialised per slot (a slot no material
/// fills is compiled out), so a slot left out of the specialisation would render the factor alone.
#[test]
fn each_texture_slot_is_read_alone() {
    use umbra::scene::{TextureRef, IDENTITY_TRANSFORM};
    let gpu = Gpu::new();
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0);
    // Linear texels: n/255 is exact as the stored unorm16 (257 n / 65535).
    let texel = [128u8, 64, 200, 255];
    let t = texel.map(|c| c as f32 / 255.0);
    let slot = || Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 });
    let base = Material {
        base_color_factor: [0.9, 0.8, 0.7, 1.0],
        metallic: 0.5,
        roughness: 0.6,
        emissive: [0.0; 3],
        ..Default::default()
    };
    let cases = [
        (
            "base colour",
            Material { base_color_texture: slot(), ..base.clone() },
            Material { base_color_factor: [0.9 * t[0], 0.8 * t[1], 0.7 * t[2], 1.0], ..base.clone() },
        ),
        (
            "metallic-roughness",
            Material { metallic: 1.0, roughness: 1.0, metallic_roughness_texture: slot(), ..base.clone() },
            Material { metallic: t[2], roughness: t[1], ..base.clone() },
        ),
        (
            "emissive",
            Material { emissive: [2.0, 1.0, 0.5], emissive_texture: slot(), ..base.clone() },
            Material { emissive: [2.0 * t[0], t[1], 0.5 * t[2]], ..base.clone() },
        ),
    ];
    for (name, textured, folded) in cases {
        let images: Vec<PathImage> = [textured, folded]
            .into_iter()
            .map(|material| {
                let mut scene = scene_of(&[(&quad, material, false)], cam);
                scene.uv0 = scene.positions.iter().map(|p| [p[0] * 0.5 + 0.5, 0.5 - p[1] * 0.5]).collect();
                scene.textures.push(common::row_texture("constant", &[texel]));
                scene.lights.push(sun([-0.5, -0.3, -1.0], 3.0));
                let settings = PathSettings { size: (16, 16), spp: 4, max_bounces: 1, ..Default::default() };
                render(&gpu, &scene, &settings)
            })
            .collect();
        let centre = images[1].mean[8 * 16 + 8];
        assert!(centre[0] > 0.01, "{name}: the quad is lit ({centre:?})");
        for (i, (a, b)) in images[0].mean.iter().zip(&images[1].mean).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-4 * b[c].abs().max(1e-3),
                    "{name}: pixel {i} channel {c}: textured {} vs factor {}",
                    a[c],
                    b[c]
                );
            }
        }
    }
}
