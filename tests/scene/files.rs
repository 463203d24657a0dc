//! `.gltf` files with their data beside them or embedded; missing buffers and images named, or
//! (`MissingTextures::Warn`) warned about and neutralised.

use crate::{assert_scene_error, common, load, read_glb, scenes_dir, to_glb};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use umbra::scene::Scene;

/// A folder holding `textured.glb` as `scene.gltf` + `scene.bin`, optionally with edits.
fn write_gltf(folder: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("umbra-scene-{folder}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (mut json, bin) = read_glb(&scenes_dir().join("textured.glb"));
    json["buffers"][0]["uri"] = json!("scene.bin");
    edit(&mut json);
    std::fs::write(dir.join("scene.bin"), &bin).unwrap();
    std::fs::write(dir.join("scene.gltf"), serde_json::to_vec_pretty(&json).unwrap()).unwrap();
    dir.join("scene.gltf")
}

#[test]
fn gltf_files_resolve_external_and_embedded_data() {
    let reference = load(&scenes_dir().join("textured.glb"));
    let path = write_gltf("external", |_| {});
    let external = load(&path);
    assert_eq!(
        (external.positions.clone(), external.textures.clone()),
        (reference.positions.clone(), reference.textures.clone())
    );
    // The same buffer as a base64 data: URI needs no file.
    let bin = std::fs::read(path.with_file_name("scene.bin")).unwrap();
    let mut json: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    json["buffers"][0]["uri"] =
        json!(format!("data:application/octet-stream;base64,{}", common::base64(&bin)));
    let embedded = Scene::from_glb_bytes("embedded.gltf", &serde_json::to_vec(&json).unwrap()).unwrap();
    assert_eq!(embedded.positions, reference.positions);
    // An in-memory scene cannot reach files.
    assert_scene_error(
        Scene::from_glb_bytes("memory.gltf", &std::fs::read(&path).unwrap()),
        "memory.gltf",
        "in-memory scene cannot read",
    );
    std::fs::remove_dir_all(path.parent().unwrap()).ok();
}

#[test]
fn missing_files_are_named() {
    let path = write_gltf("missing-bin", |_| {});
    std::fs::remove_file(path.with_file_name("scene.bin")).unwrap();
    assert_scene_error(Scene::load(&path), "scene.gltf", "buffer 0: cannot read");
    assert_scene_error(Scene::load(&path), "scene.gltf", "scene.bin");
    std::fs::remove_dir_all(path.parent().unwrap()).ok();

    let path = write_gltf("missing-image", |json| json["images"][0] = json!({ "uri": "checker%20map.png" }));
    assert_scene_error(Scene::load(&path), "scene.gltf", "image 0 ('checker%20map.png'): cannot read");
    assert_scene_error(Scene::load(&path), "scene.gltf", "checker map.png");
    std::fs::remove_dir_all(path.parent().unwrap()).ok();

    assert_scene_error(
        Scene::load(Path::new("/nonexistent/umbra.glb")),
        "umbra.glb",
        "cannot read the scene file",
    );
}

/// `MissingTextures::Warn` (the CLI's `--missing-textures warn`): a texture file that cannot be
/// read, or an image that cannot be decoded, is named once in the scene's warnings and its
/// slots fall back to the material's factors (the specification's neutral value); every other
/// texture and slot stays. The default still refuses the scene.
#[test]
fn missing_textures_can_be_warned_about_and_neutralised() {
    use umbra::scene::{LoadOptions, MissingTextures};
    let warn = LoadOptions { missing_textures: MissingTextures::Warn, ..Default::default() };
    let reference = load(&scenes_dir().join("textured.glb"));
    let path = write_gltf("lenient", |json| json["images"][0] = json!({ "uri": "gone.png" }));
    assert_scene_error(Scene::load(&path), "scene.gltf", "gone.png");
    let scene = Scene::load_with(&path, &warn).expect("a missing texture is a warning");
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("scene.gltf") && scene.warnings[0].contains("gone.png"),
        "{:?}",
        scene.warnings
    );
    // Every slot that used image 0 is empty now; every other slot is as before.
    let image_of =
        |s: &Scene, t: u32| reference.textures[t as usize].name.clone() == s.textures[t as usize].name;
    let mut dropped = 0;
    for (m, r) in scene.materials.iter().zip(&reference.materials) {
        let slots = |m: &umbra::scene::Material| {
            [m.base_color_texture, m.metallic_roughness_texture, m.normal_texture, m.emissive_texture]
        };
        for (now, before) in slots(m).into_iter().zip(slots(r)) {
            match (now, before) {
                (Some(a), Some(b)) => {
                    assert_eq!(a, b);
                    assert!(image_of(&scene, a.texture), "a surviving slot changed image");
                }
                (None, Some(_)) => dropped += 1,
                (None, None) => {}
                (Some(_), None) => panic!("a slot appeared"),
            }
        }
    }
    assert!(dropped >= 1, "no slot used the missing image");
    assert_eq!(scene.positions, reference.positions);
    std::fs::remove_dir_all(path.parent().unwrap()).ok();

    // An undecodable image likewise.
    let (json, mut bin) = read_glb(&scenes_dir().join("textured.glb"));
    let view = &json["bufferViews"][json["images"][1]["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap() as usize;
    bin[at..at + 8].copy_from_slice(b"garbage!");
    let dir = std::env::temp_dir().join(format!("umbra-scene-garbage-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("garbage.glb");
    std::fs::write(&file, to_glb(&json, &bin)).unwrap();
    let scene = Scene::load_with(&file, &warn).expect("an undecodable texture is a warning");
    assert_eq!(scene.warnings.len(), 1);
    assert!(scene.warnings[0].contains("image 1 (embedded): cannot decode"), "{:?}", scene.warnings);
    std::fs::remove_dir_all(&dir).ok();
}
