//! The committed scenes: generated ones match their generator, every one loads with the counts
//! its JSON implies, bounds are the geometry's; the shared assets' larger scenes; the content
//! hash.

use crate::{committed_scenes, common, expected, generate, khronos, load, read_glb, scenes_dir, Expected};
use glam::{Mat4, Quat, Vec3};
use std::collections::HashSet;
use umbra::scene::Scene;

// ---------------------------------------------------------------------------------------------
// Committed scenes

#[test]
fn generated_scenes_match_the_committed_files() {
    for (name, bytes) in generate::all() {
        let committed = std::fs::read(scenes_dir().join(name)).unwrap();
        assert!(
            committed == bytes,
            "scenes/{name} differs from what tests/support/generate.rs makes: run `cargo run --example gen_scenes`"
        );
    }
}

#[test]
fn every_committed_scene_loads_with_the_counts_its_json_implies() {
    for path in committed_scenes() {
        let scene = load(&path);
        let (json, _) = read_glb(&path);
        let stats = scene.stats();
        let got = Expected {
            triangles: stats.triangles,
            materials: stats.materials,
            textures: stats.textures,
            instances: stats.instances,
        };
        assert_eq!(got, expected(&json), "{}", path.display());
        assert_eq!(scene.triangle_material.len(), scene.triangles.len());
        assert_eq!(scene.normals.len(), scene.positions.len());
        for attribute in [scene.uv0.len(), scene.uv1.len(), scene.colors.len(), scene.tangents.len()] {
            assert!(attribute == 0 || attribute == scene.positions.len(), "{}", path.display());
        }
        assert!(scene.triangles.iter().flatten().all(|&v| (v as usize) < scene.positions.len()));
        assert!(scene.triangle_material.iter().all(|&m| (m as usize) < scene.materials.len()));
        assert!(scene.positions.iter().flatten().all(|x| x.is_finite()));
        assert!(
            scene.normals.iter().all(|&n| (Vec3::from(n).length() - 1.0).abs() < 1e-4),
            "{}",
            path.display()
        );
        for texture in &scene.textures {
            assert_eq!(texture.rgba8.len(), (texture.width * texture.height * 4) as usize);
        }
    }
}

#[test]
fn the_embedded_cornell_box_loads() {
    let scene = Scene::cornell_box();
    let stats = scene.stats();
    assert_eq!((stats.triangles, stats.materials, stats.textures, stats.degenerate_triangles), (36, 4, 0, 0));
    assert_eq!(scene.cameras.len(), 1);
    assert_eq!(scene.emissive.triangles.len(), 2);
    let light = scene.materials.iter().find(|m| m.name == "light").unwrap();
    for (got, want) in light.emissive.iter().zip([17.0, 12.0, 4.0]) {
        assert!((got - want).abs() < 1e-4, "light radiance {:?}", light.emissive);
    }
    assert!(scene.materials.iter().all(|m| m.roughness == 1.0 && m.metallic == 0.0));
}

#[test]
fn bounds_are_those_of_the_geometry() {
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
    let (lo, hi) = load(&khronos("Box")).bounds();
    assert!(close(lo, [-0.5; 3]) && close(hi, [0.5; 3]), "{lo:?} {hi:?}");
    let (lo, hi) = Scene::cornell_box().bounds();
    assert!(close(lo, [0.0; 3]) && close(hi, [0.55; 3]), "{lo:?} {hi:?}");
    let (lo, hi) = load(&scenes_dir().join("spheres.glb")).bounds();
    assert!(close(lo, [-5.0, 0.0, -5.0]) && close(hi, [5.0, 0.8, 5.0]), "{lo:?} {hi:?}");
    // instanced.glb: the wedge under the transforms its nodes spell out.
    let (lo, hi) = load(&scenes_dir().join("instanced.glb")).bounds();
    let wedge = generate::Mesh::wedge().positions;
    let (mut want_lo, mut want_hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for transform in instanced_transforms().into_iter().map(|(_, m)| m) {
        for &p in &wedge {
            let p = transform.transform_point3(Vec3::from(p));
            (want_lo, want_hi) = (want_lo.min(p), want_hi.max(p));
        }
    }
    assert!(
        Vec3::from(lo).abs_diff_eq(want_lo, 1e-5) && Vec3::from(hi).abs_diff_eq(want_hi, 1e-5),
        "{lo:?} {hi:?}"
    );
}

/// The world transform of every instance in instanced.glb, from the generator's description.
pub(crate) fn instanced_transforms() -> Vec<(String, Mat4)> {
    let ring = Mat4::from_quat(Quat::from_rotation_y(30f32.to_radians()));
    let mut out: Vec<(String, Mat4)> = (0..8)
        .map(|k| {
            let angle = k as f32 * std::f32::consts::TAU / 8.0;
            let place = Vec3::new(2.0 * angle.cos(), 0.0, 2.0 * angle.sin());
            (
                format!("ring {k}"),
                ring * Mat4::from_scale_rotation_translation(Vec3::splat(0.5), Quat::IDENTITY, place),
            )
        })
        .collect();
    let arm = ring * Mat4::from_scale_rotation_translation(Vec3::splat(2.0), Quat::IDENTITY, Vec3::Y);
    let hand = arm
        * Mat4::from_rotation_translation(
            Quat::from_rotation_x(45f32.to_radians()),
            Vec3::new(0.0, 0.5, 0.0),
        );
    let finger = hand * Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0));
    let mirror = Mat4::from_scale_rotation_translation(
        Vec3::new(-1.0, 1.0, 1.0),
        Quat::IDENTITY,
        Vec3::new(-3.0, 0.0, 0.0),
    );
    let mirror_child = mirror * Mat4::from_translation(Vec3::Y);
    for (name, m) in [("hand", hand), ("finger", finger), ("mirror", mirror), ("mirror child", mirror_child)]
    {
        out.push((name.to_owned(), m));
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Larger scenes from the shared assets, when present

#[test]
fn shared_asset_scenes_load_with_their_known_counts() {
    let Some(assets) = common::external_gltf("shared_asset_scenes_load_with_their_known_counts") else {
        return;
    };
    let helmet = load(&assets.join("DamagedHelmet/DamagedHelmet.glb"));
    assert_eq!((helmet.stats().triangles, helmet.textures.len()), (15_452, 5));
    assert_eq!(helmet.tangents.len(), helmet.positions.len());
    let sponza = load(&assets.join("SponzaDabrovic/sponza_dabrovic.glb"));
    assert_eq!(sponza.stats().triangles, 66_454);
    let path = assets.join("MetalRoughSpheresNoTextures/MetalRoughSpheresNoTextures.glb");
    let spheres = load(&path);
    assert_eq!(spheres.stats().triangles, 1_040_409);
    // 98 file materials, plus the glTF default for the label meshes that have none.
    assert_eq!(spheres.materials.len(), 98 + 1);
    assert_eq!(expected(&read_glb(&path).0).materials, 98 + 1);
}

// ---------------------------------------------------------------------------------------------
// The content hash (what a probe bake records to refuse another scene)

#[test]
fn the_content_hash_follows_what_light_transport_reads() {
    let cornell = Scene::cornell_box();
    let hash = cornell.content_hash();
    // The same content: loaded again, from the committed file, renamed, seen by other cameras.
    assert_eq!(Scene::cornell_box().content_hash(), hash);
    assert_eq!(load(&scenes_dir().join("cornell-box.glb")).content_hash(), hash);
    let hash_after = |scene: &Scene, edit: &dyn Fn(&mut Scene)| {
        let mut s = scene.clone();
        edit(&mut s);
        s.content_hash()
    };
    let same = hash_after(&cornell, &|s| {
        s.name = "elsewhere.glb".into();
        s.materials[0].name = "renamed".into();
        s.cameras.clear();
    });
    assert_eq!(same, hash);
    // Any change the probes would see.
    let changes = |what: &str, edit: fn(&mut Scene)| {
        assert_ne!(hash_after(&cornell, &edit), hash, "{what}");
    };
    changes("a vertex moved", |s| s.positions[0][1] += 1e-3);
    changes("a normal turned", |s| s.normals[0][0] += 1e-3);
    changes("a material's colour", |s| s.materials[0].base_color_factor[0] *= 0.5);
    changes("a material's emission", |s| s.materials[0].emissive[0] += 1.0);
    changes("a triangle's material", |s| s.triangle_material[0] = (s.triangle_material[0] + 1) % 4);
    changes("a triangle's winding", |s| s.triangles[0].swap(1, 2));
    // Punctual lights and textures.
    let textured = load(&scenes_dir().join("textured.glb"));
    let hash = textured.content_hash();
    assert_ne!(hash_after(&textured, &|s| s.lights[0].intensity *= 2.0), hash, "a light's intensity");
    assert_ne!(hash_after(&textured, &|s| s.lights[0].position[2] += 0.1), hash, "a light moved");
    assert_ne!(hash_after(&textured, &|s| drop(s.lights.pop())), hash, "a light removed");
    assert_ne!(hash_after(&textured, &|s| s.textures[0].rgba8[0] ^= 1), hash, "a texel");
    assert_ne!(hash_after(&textured, &|s| s.textures[0].srgb ^= true), hash, "a texture's colour space");
    assert_eq!(hash_after(&textured, &|s| s.lights[0].name = "renamed".into()), hash, "a light's name");
    // Every committed scene hashes differently.
    let hashes: HashSet<u64> = committed_scenes().iter().map(|p| load(p).content_hash()).collect();
    assert_eq!(hashes.len(), committed_scenes().len());
}
