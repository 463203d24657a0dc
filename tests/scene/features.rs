//! The scene features the kernels are specialised on, read before the upload, against those of
//! the uploaded scene.

use crate::{common, generate, scenes_dir};
use glam::{Mat4, Vec3};
use serde_json::json;
use std::path::{Path, PathBuf};
use umbra::scene::Scene;

// ---------------------------------------------------------------------------------------------
// The features the kernels are specialised on, read before the upload

/// Scenes built in code for [`features_before_the_upload_are_the_uploads`]: a textured square
/// with every material extension and texture slot on (tangents given), one with each extension's
/// textures where the extension itself is off (the upload drops those slots), one with tangent-
/// space textures and no tangents, a texture index past the list, vertex colours (one set that
/// packs to white), masked and blended triangles, emission, an implicit shape.
fn feature_scenes() -> Vec<Scene> {
    use common::quad;
    use umbra::scene::{AlphaMode, Material};
    let texture = || Some(common::row_texture("t", &[[200, 100, 50, 255], [10, 20, 30, 255]]));
    let every = Material {
        base_color_texture: quad::slot(),
        metallic_roughness_texture: quad::slot(),
        normal_texture: quad::slot(),
        occlusion_texture: quad::slot(),
        emissive_texture: quad::slot(),
        specular_texture: quad::slot(),
        specular_color_texture: quad::slot(),
        transmission_factor: 0.5,
        transmission_texture: quad::slot(),
        volume: true,
        thickness: 0.1,
        thickness_texture: quad::slot(),
        dispersion: 0.3,
        clearcoat: 0.5,
        clearcoat_texture: quad::slot(),
        clearcoat_roughness_texture: quad::slot(),
        clearcoat_normal_texture: quad::slot(),
        iridescence: 1.0,
        iridescence_texture: quad::slot(),
        iridescence_thickness_texture: quad::slot(),
        anisotropy_strength: 0.5,
        anisotropy_texture: quad::slot(),
        sheen_color: [0.5; 3],
        sheen_color_texture: quad::slot(),
        sheen_roughness_texture: quad::slot(),
        diffuse_transmission: 0.5,
        diffuse_transmission_texture: quad::slot(),
        diffuse_transmission_color_texture: quad::slot(),
        parallax: Some(umbra::scene::Parallax {
            height: quad::slot().unwrap(),
            scale: 0.1,
            layers: 8,
            refinement: 4,
        }),
        unlit: true,
        ..Default::default()
    };
    let off = Material {
        transmission_factor: 0.0,
        volume: false,
        clearcoat: 0.0,
        iridescence: 0.0,
        anisotropy_strength: 0.0,
        sheen_color: [0.0; 3],
        diffuse_transmission: 0.0,
        parallax: None,
        unlit: false,
        ..every.clone()
    };
    let mut scenes = Vec::new();
    let mut all = quad::scene("every feature", every.clone(), texture(), 1.0);
    all.tangents = vec![[1.0, 0.0, 0.0, 1.0]; all.positions.len()];
    scenes.push(all);
    let mut extensions_off = quad::scene("extension textures, extensions off", off, texture(), 1.0);
    extensions_off.tangents = vec![[1.0, 0.0, 0.0, 1.0]; extensions_off.positions.len()];
    scenes.push(extensions_off);
    scenes.push(quad::scene("no tangents", every, texture(), 0.0));
    let missing = umbra::scene::TextureRef { texture: 7, ..quad::slot().unwrap() };
    scenes.push(quad::scene(
        "a texture index past the list",
        Material { base_color_texture: Some(missing), ..Default::default() },
        texture(),
        1.0,
    ));
    for (name, color) in
        [("vertex colours", [0.5, 1.0, 1.0, 1.0]), ("vertex colours packing to white", [0.999; 4])]
    {
        let mut scene = quad::scene(name, Material::default(), None, 1.0);
        scene.colors = vec![color; scene.positions.len()];
        scenes.push(scene);
    }
    for (name, alpha_mode) in [("masked", AlphaMode::Mask), ("blended", AlphaMode::Blend)] {
        scenes.push(quad::scene(name, Material { alpha_mode, ..Default::default() }, None, 0.0));
    }
    let lamp = Material { emissive: [2.0; 3], ..Default::default() };
    let quad_soup = common::quad(Vec3::ZERO, Vec3::X, Vec3::Y);
    let camera = common::camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
    scenes.push(common::build_with("emissive", &[(quad_soup.clone(), lamp)], vec![], camera));
    let mut implicit = common::build("implicit", &[quad_soup], vec![], camera);
    let shape = json!({"sphere": {"radius": 0.5}, "material": 0});
    implicit.implicits.push(umbra::scene::implicit::from_json("ball", &shape, Mat4::IDENTITY, 1).unwrap());
    scenes.push(implicit);
    // A BVH deeper than the traversal's register stack (no `shallow_bvh`).
    let nested = umbra::procedural::nested_clusters(40, 16, 0.6, 1);
    scenes.push(common::build("nested clusters", &[nested], vec![], camera));
    scenes
}

/// `SceneFeatures::of_scene` (from the scene as loaded and its BVH, which `umbra render`
/// specialises the path tracer's pipeline on while the rest of the scene uploads) equals
/// `SceneFeatures::of` of the uploaded scene on every scene at hand: scenes/ (generated and
/// Khronos), the generated test squares, scenes built in code for the edge cases, and every
/// Khronos model in the shared assets; with and without an environment map. The register stack
/// is the uploaded BVH's stack depth (at least 1), or 0 beyond `BVH_REGISTERS` (the deep BVHs are
/// named). Every feature is on in some scene and off in another, so a feature computed wrongly
/// either way fails.
#[test]
fn features_before_the_upload_are_the_uploads() {
    use umbra::gpu::kernel::{BVH_REGISTERS, SCENE_FEATURES};
    use umbra::gpu::scene::{GpuScene, SceneBvh};
    use umbra::gpu::SceneFeatures;
    let gpu = common::Gpu::new();
    let mut scenes: Vec<Scene> =
        generate::all().into_iter().map(|(name, glb)| Scene::from_glb_bytes(name, &glb).unwrap()).collect();
    let step: Vec<u8> = (0..64).map(|i| (i * 4) as u8).collect();
    let pom = json!({ "heightTexture": { "index": 0 }, "scale": 0.1, "layers": 8, "refinement": 4 });
    scenes.push(
        Scene::from_glb_bytes("parallax", &generate::parallax_square(1.0, 8, 8, &step, false, Some(pom)))
            .unwrap(),
    );
    scenes.push(Scene::from_glb_bytes("occlusion", &generate::occlusion_square(Some(0.5), true)).unwrap());
    scenes.push(
        Scene::from_glb_bytes("emissive texture", &generate::emissive_square(&[255; 12], [1.0; 3], 2.0))
            .unwrap(),
    );
    scenes.extend(feature_scenes());
    let mut files: Vec<PathBuf> = Vec::new();
    gltf_files(&scenes_dir().join("khronos"), &mut files);
    if let Some(assets) = common::external_gltf("features_before_the_upload_are_the_uploads") {
        gltf_files(&assets, &mut files);
    }
    // Some of the shared models lack image files: their slots stay empty as in `umbra render
    // --missing-textures warn`, which is what the features must see.
    let options = umbra::scene::LoadOptions {
        missing_textures: umbra::scene::MissingTextures::Warn,
        ..Default::default()
    };
    // Those without their geometry (a .gltf whose .bin was not copied) are left out, named.
    for path in &files {
        match Scene::load_with(path, &options) {
            Ok(scene) => scenes.push(scene),
            Err(e) if e.to_string().contains("buffer 0: cannot read") => eprintln!("note: left out: {e}"),
            Err(e) => panic!("loading {}: {e}", path.display()),
        }
    }
    let map =
        umbra::environment::EnvironmentMap::load(&scenes_dir().join("../tests/reference/sky-128x64.exr"))
            .unwrap();
    let mut on = vec![false; SCENE_FEATURES.len()];
    let mut off = vec![false; SCENE_FEATURES.len()];
    for (i, scene) in scenes.iter().enumerate() {
        let env = i % 2 == 1;
        let bvh = SceneBvh::build(scene).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        let early = SceneFeatures::of_scene(scene, &bvh, env);
        let mut uploaded =
            GpuScene::upload_with(&gpu, scene, bvh).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        if env {
            uploaded.set_environment(&gpu, &map).unwrap();
        }
        let features = uploaded.features();
        let depth = uploaded.bvh.stack_depth;
        let stack = if depth > BVH_REGISTERS { 0 } else { depth.max(1) };
        assert_eq!(features.bvh_stack, stack, "{}: stack depth {depth}", scene.name);
        if depth > BVH_REGISTERS {
            eprintln!("{}: a BVH deeper than the register stack ({depth} entries)", scene.name);
        }
        assert_eq!(early, features, "{}", scene.name);
        for (k, name) in SCENE_FEATURES.iter().enumerate() {
            let value = features.get(name).unwrap();
            on[k] |= value;
            off[k] |= !value;
        }
    }
    for (k, name) in SCENE_FEATURES.iter().enumerate() {
        assert!(on[k] && off[k], "feature '{name}' is on in some scene: {}, off in some: {}", on[k], off[k]);
    }
}

/// The glTF files under `dir`, one per model folder (`X.glb`, `glTF-Binary/X.glb` or
/// `glTF/X.gltf`, in that order), sorted.
fn gltf_files(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut folders: Vec<PathBuf> =
        entries.filter_map(|e| e.ok()).map(|e| e.path()).filter(|p| p.is_dir()).collect();
    folders.sort();
    for folder in folders {
        let found = ["", "glTF-Binary", "glTF"].iter().find_map(|sub| {
            let mut names: Vec<PathBuf> = std::fs::read_dir(folder.join(sub))
                .ok()?
                .filter_map(|e| e.ok())
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|x| x == "glb" || x == "gltf"))
                .collect();
            names.sort();
            names.into_iter().next()
        });
        files.extend(found);
    }
}
