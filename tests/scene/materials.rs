//! Materials and textures: samplers, colour spaces, texture transforms, emission, tangents and
//! optional vertex attributes.

use crate::{generate, khronos, load, read_glb, scenes_dir, texture_uses};
use glam::{Mat4, Vec3};
use std::collections::HashSet;
use umbra::scene::{texture_transform, Filter, Wrap};

// ---------------------------------------------------------------------------------------------
// Materials and textures

#[test]
fn texture_settings_test_samplers_are_decoded() {
    let path = khronos("TextureSettingsTest");
    let scene = load(&path);
    let got: HashSet<(Wrap, Wrap)> =
        scene.textures.iter().map(|t| (t.sampler.wrap_s, t.sampler.wrap_t)).collect();
    let wrap = |gl: u64| match gl {
        33071 => Wrap::ClampToEdge,
        33648 => Wrap::MirroredRepeat,
        _ => Wrap::Repeat,
    };
    let want: HashSet<(Wrap, Wrap)> =
        texture_uses(&read_glb(&path).0).iter().map(|(_, s, _)| (wrap(s[0]), wrap(s[1]))).collect();
    assert_eq!(got, want);
    for pair in [
        (Wrap::Repeat, Wrap::ClampToEdge),
        (Wrap::ClampToEdge, Wrap::Repeat),
        (Wrap::Repeat, Wrap::MirroredRepeat),
        (Wrap::MirroredRepeat, Wrap::Repeat),
    ] {
        assert!(got.contains(&pair), "{pair:?}");
    }
}

#[test]
fn generated_textures_have_their_colour_space_sampler_and_transform() {
    let scene = load(&scenes_dir().join("textured.glb"));
    assert_eq!(scene.textures.len(), 4);
    let floor = scene.materials.iter().find(|m| m.name == "floor").unwrap();
    let cube = scene.materials.iter().find(|m| m.name == "cube").unwrap();
    let base = floor.base_color_texture.unwrap();
    let checker = &scene.textures[base.texture as usize];
    assert!(checker.srgb && (checker.width, checker.height) == (128, 128));
    assert_eq!(&checker.rgba8[..4], &[230, 230, 230, 255]);
    assert_eq!((checker.sampler.wrap_s, checker.sampler.wrap_t), (Wrap::MirroredRepeat, Wrap::ClampToEdge));
    assert_eq!(
        (checker.sampler.mag_filter, checker.sampler.min_filter, checker.sampler.mipmaps),
        (Filter::Nearest, Filter::Linear, false)
    );
    assert_eq!(base.transform, texture_transform([0.5, 0.25], 0.3, [4.0, 4.0]));
    // The same image with the default sampler on the cube is a second texture.
    let cube_base = cube.base_color_texture.unwrap();
    assert_ne!(cube_base.texture, base.texture);
    assert_eq!(scene.textures[cube_base.texture as usize].rgba8, checker.rgba8);
    assert!(scene.textures[cube_base.texture as usize].sampler.mipmaps);
    // Normal and metallic-roughness maps are linear; the normal map is shared by both materials.
    let normal = floor.normal_texture.unwrap();
    assert!(!scene.textures[normal.texture as usize].srgb);
    assert!(!scene.textures[floor.metallic_roughness_texture.unwrap().texture as usize].srgb);
    assert_eq!(cube.normal_texture.unwrap().texture, normal.texture);
    assert_eq!(cube.normal_texture.unwrap().scale, 0.5);
    assert_eq!(cube.normal_texture.unwrap().transform, texture_transform([0.0, 0.0], 0.0, [2.0, 2.0]));
}

#[test]
fn texture_transform_matches_the_extension_example() {
    // KHR_texture_transform's example: offset [0, 1], rotation π/2, scale ½ "utilizes only the
    // lower left quadrant of the source image, rotated clockwise 90°".
    let t = umbra::scene::TextureRef {
        texture: 0,
        tex_coord: 0,
        transform: texture_transform([0.0, 1.0], std::f32::consts::FRAC_PI_2, [0.5, 0.5]),
        scale: 1.0,
    };
    for (uv, want) in [
        ([0.0, 0.0], [0.0, 1.0]),
        ([1.0, 0.0], [0.0, 0.5]),
        ([0.0, 1.0], [0.5, 1.0]),
        ([1.0, 1.0], [0.5, 0.5]),
    ] {
        let got = t.transform_uv(uv);
        assert!(
            (got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6,
            "{uv:?} -> {got:?}, want {want:?}"
        );
    }
    // Offset, rotation and scale compose as translation · rotation · scale.
    let m = texture_transform([0.25, 0.5], 0.3, [2.0, 3.0]);
    let (s, c) = 0.3f32.sin_cos();
    let want = [[2.0 * c, 3.0 * s, 0.25], [-2.0 * s, 3.0 * c, 0.5]];
    assert!(m.iter().flatten().zip(want.iter().flatten()).all(|(a, b)| (a - b).abs() < 1e-6), "{m:?}");
}

#[test]
fn emissive_strength_multiplies_the_emissive_factor() {
    let path = khronos("EmissiveStrengthTest");
    let scene = load(&path);
    let (json, _) = read_glb(&path);
    let mut strengthened = 0;
    for (i, material) in json["materials"].as_array().unwrap().iter().enumerate() {
        let factor = material["emissiveFactor"]
            .as_array()
            .map_or([0.0; 3], |f| [0, 1, 2].map(|c| f[c].as_f64().unwrap() as f32));
        let strength = material["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"].as_f64();
        strengthened += strength.is_some_and(|s| s > 1.0) as usize;
        let want = factor.map(|f| f * strength.unwrap_or(1.0) as f32);
        assert_eq!(scene.materials[i].emissive, want, "material {i}");
    }
    assert!(strengthened > 0);
}

#[test]
fn tangents_are_generated_for_normal_maps_and_follow_the_uvs() {
    assert!(load(&khronos("Box")).tangents.is_empty(), "no normal map, no tangents");
    let scene = load(&scenes_dir().join("textured.glb"));
    assert_eq!(scene.tangents.len(), scene.positions.len());
    for (t, n) in scene.tangents.iter().zip(&scene.normals) {
        let (t3, n) = (Vec3::new(t[0], t[1], t[2]), Vec3::from(*n));
        assert!((t3.length() - 1.0).abs() < 1e-4 && t3.dot(n).abs() < 1e-4 && t[3].abs() == 1.0);
    }
    // The cube has no TANGENT attribute: the generated tangents must equal the generator's
    // analytic ones (+u along each face, w = +1), rotated by the node.
    let cube = scene.instances.iter().find(|i| i.name == "cube").unwrap();
    let transform = Mat4::from_cols_array_2d(&cube.transform);
    let range = cube.first_triangle as usize..(cube.first_triangle + cube.triangle_count) as usize;
    let first = scene.triangles[range.clone()].iter().flatten().min().copied().unwrap() as usize;
    let analytic = generate::Mesh::cuboid().tangents;
    for &v in scene.triangles[range].iter().flatten() {
        let want = analytic[v as usize - first];
        let want3 = transform.transform_vector3(Vec3::new(want[0], want[1], want[2])).normalize();
        let got = scene.tangents[v as usize];
        assert!(
            Vec3::new(got[0], got[1], got[2]).abs_diff_eq(want3, 1e-4) && got[3] == want[3],
            "vertex {v}: {got:?} vs {want3}"
        );
    }
}

#[test]
fn optional_vertex_attributes_are_all_or_nothing() {
    let multi = load(&khronos("MultiUVTest"));
    assert_eq!((multi.uv0.len(), multi.uv1.len()), (multi.positions.len(), multi.positions.len()));
    let plain = load(&khronos("Box"));
    assert!(plain.uv0.is_empty() && plain.uv1.is_empty() && plain.colors.is_empty());
}
