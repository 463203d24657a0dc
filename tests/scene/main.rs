//! The glTF loader: every committed scene loads with the counts its JSON implies; transforms,
//! winding, samplers, emission, cameras and the emissive table are right; bad input gives a
//! precise `Error::Scene` and never a panic. CPU only.

#[path = "../support/generate.rs"]
mod generate;

#[path = "../common/mod.rs"]
mod common;

mod cameras_and_lights;
mod committed;
mod compressed;
#[cfg(feature = "draco")]
mod draco;
mod errors;
mod extensions;
mod features;
mod files;
mod fuzz;
mod geometry;
mod ktx2;
mod materials;

use serde_json::Value;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use umbra::scene::Scene;
use umbra::Error;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Every committed scene, generated ones first.
fn committed_scenes() -> Vec<PathBuf> {
    let khronos = [
        "Box",
        "BoxTextured",
        "SimpleInstancing",
        "NegativeScaleTest",
        "OrientationTest",
        "TextureSettingsTest",
        "EmissiveStrengthTest",
        "TextureCoordinateTest",
        "MultiUVTest",
    ];
    let generated = generate::all().into_iter().map(|(name, _)| scenes_dir().join(name));
    generated.chain(khronos.iter().map(|n| scenes_dir().join(format!("khronos/{n}/{n}.glb")))).collect()
}

fn load(path: &Path) -> Scene {
    Scene::load(path).unwrap_or_else(|e| panic!("loading {}: {e}", path.display()))
}

fn khronos(name: &str) -> PathBuf {
    scenes_dir().join(format!("khronos/{name}/{name}.glb"))
}

fn read_glb(path: &Path) -> (Value, Vec<u8>) {
    generate::split_glb(&std::fs::read(path).unwrap())
}

fn to_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    generate::glb(&serde_json::to_vec(json).unwrap(), bin)
}

// ---------------------------------------------------------------------------------------------
// Expected values computed from the JSON alone, independently of the loader.

#[derive(Debug, PartialEq)]
struct Expected {
    triangles: usize,
    materials: usize,
    textures: usize,
    instances: usize,
}

fn expected(root: &Value) -> Expected {
    let arr = |v: &Value, key: &str| v[key].as_array().cloned().unwrap_or_default();
    let scene = root["scene"].as_u64().unwrap_or(0) as usize;
    let mut stack: Vec<usize> =
        arr(&arr(root, "scenes")[scene], "nodes").iter().map(|n| n.as_u64().unwrap() as usize).collect();
    let (mut triangles, mut instances, mut default_material) = (0, 0, false);
    while let Some(n) = stack.pop() {
        let node = &root["nodes"][n];
        stack.extend(arr(node, "children").iter().map(|c| c.as_u64().unwrap() as usize));
        let Some(mesh) = node["mesh"].as_u64() else { continue };
        let copies = match node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"].as_object() {
            Some(attributes) => {
                let accessor = attributes.values().next().unwrap().as_u64().unwrap() as usize;
                root["accessors"][accessor]["count"].as_u64().unwrap() as usize
            }
            None => 1,
        };
        instances += copies;
        for primitive in arr(&root["meshes"][mesh as usize], "primitives") {
            let count = |a: &Value| {
                root["accessors"][a.as_u64().unwrap() as usize]["count"].as_u64().unwrap() as usize
            };
            let vertices = if primitive["indices"].is_null() {
                count(&primitive["attributes"]["POSITION"])
            } else {
                count(&primitive["indices"])
            };
            let per_copy = match primitive["mode"].as_u64().unwrap_or(4) {
                4 => vertices / 3,
                5 | 6 => vertices.saturating_sub(2),
                _ => 0,
            };
            triangles += per_copy * copies;
            default_material |= primitive["material"].is_null();
        }
    }
    Expected {
        triangles,
        materials: arr(root, "materials").len() + default_material as usize,
        textures: texture_uses(root).len(),
        instances,
    }
}

/// Distinct (image, sampler settings, sRGB) over every texture slot of every material.
fn texture_uses(root: &Value) -> HashSet<(u64, [u64; 4], bool)> {
    let mut uses = HashSet::new();
    for material in root["materials"].as_array().into_iter().flatten() {
        let pbr = &material["pbrMetallicRoughness"];
        let ext = &material["extensions"];
        let slots = [
            (&pbr["baseColorTexture"], true),
            (&pbr["metallicRoughnessTexture"], false),
            (&material["normalTexture"], false),
            (&material["occlusionTexture"], false),
            (&material["emissiveTexture"], true),
            (&ext["KHR_materials_specular"]["specularTexture"], false),
            (&ext["KHR_materials_specular"]["specularColorTexture"], true),
            (&ext["KHR_materials_transmission"]["transmissionTexture"], false),
        ];
        for (info, srgb) in slots {
            let Some(texture) = info["index"].as_u64() else { continue };
            let texture = &root["textures"][texture as usize];
            let sampler = &root["samplers"][texture["sampler"].as_u64().unwrap_or(u64::MAX) as usize];
            let field = |key: &str, default: u64| sampler[key].as_u64().unwrap_or(default);
            // Filters as the loader can express them: nearest or linear, mipmapped or not.
            let mag = (field("magFilter", 9729) == 9728) as u64;
            let min = field("minFilter", 9987);
            let min =
                u64::from([9728, 9984, 9986].contains(&min)) | u64::from(![9728, 9729].contains(&min)) << 1;
            let settings = [field("wrapS", 10497), field("wrapT", 10497), mag, min];
            uses.insert((texture["source"].as_u64().unwrap(), settings, srgb));
        }
    }
    uses
}

/// Flips one pseudo-random bit (xorshift from `seed`) of `bytes[start..start + length]` at a time,
/// `count` times, calling `load` with each flip: a robustness sweep (the test asserts, by running
/// to the end, that no flip panics or hangs; errors and wrong results are allowed).
fn flip_bits(start: usize, length: usize, seed: u32, count: usize, load: impl Fn(usize, u8)) {
    let mut state = seed;
    for _ in 0..count {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        load(start + state as usize % length, 1u8 << (state >> 29));
    }
}

/// Asserts `result` is an `Error::Scene` naming `file` whose message contains `phrase`.
#[track_caller]
fn assert_scene_error<T: std::fmt::Debug>(result: umbra::Result<T>, file: &str, phrase: &str) {
    match result {
        Err(error @ Error::Scene { .. }) => {
            let text = error.to_string();
            assert!(
                text.contains(file) && text.contains(phrase),
                "'{text}' should name '{file}' and say '{phrase}'"
            );
        }
        other => panic!("expected Error::Scene saying '{phrase}', got {other:?}"),
    }
}
