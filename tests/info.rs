//! `umbra info SCENE`: what a glTF file holds and what umbra reads, ignores or refuses of it,
//! read with no GPU at all (each run points the Vulkan loader at a driver that does not exist),
//! as text and as JSON. The expected values come from the file's JSON, not from the loader.

#[path = "support/generate.rs"]
mod generate;

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `umbra info` with `args` and no Vulkan driver: stdout, after checking it succeeded.
fn info(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .arg("info")
        .args(args)
        .env("VK_DRIVER_FILES", "/nonexistent/umbra_no_driver.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/umbra_no_driver.json")
        .output()
        .expect("run umbra");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "umbra info {args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    String::from_utf8(out.stdout).unwrap()
}

fn box_glb() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/khronos/Box/Box.glb")
}

/// Writes `json` + `bin` as a GLB in the temporary folder.
fn write(name: &str, json: &Value, bin: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("umbra-info-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, generate::glb(&serde_json::to_vec(json).unwrap(), bin)).unwrap();
    path
}

/// Box.glb: its triangles (the index accessor's count / 3), materials, meshes and cameras as its
/// JSON declares them.
#[test]
fn info_reports_what_a_file_holds_without_a_gpu() {
    let (root, _) = generate::split_glb(&std::fs::read(box_glb()).unwrap());
    let primitive = &root["meshes"][0]["primitives"][0];
    let indices = &root["accessors"][primitive["indices"].as_u64().unwrap() as usize];
    let triangles = indices["count"].as_u64().unwrap() / 3;
    let report: Value = serde_json::from_str(&info(&[box_glb().to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(report["container"], "glb");
    assert_eq!(report["loaded"]["triangles"].as_u64(), Some(triangles), "{report}");
    assert_eq!(report["materials"].as_array().unwrap().len(), root["materials"].as_array().unwrap().len());
    assert_eq!(report["meshes"], 1);
    assert_eq!(report["cameras"], json!([]));
    assert!(report["extensions"].as_array().unwrap().is_empty());
    let text = info(&[box_glb().to_str().unwrap()]);
    assert!(text.contains(&format!("{triangles} triangles")), "{text}");
    assert!(text.contains("cameras: none"), "{text}");
}

/// Extensions: one required that umbra lacks makes the file refused (with the loader's reason),
/// an optional one it lacks is ignored (and named in the warnings), a read one is read; the
/// variants' names and each animation's channels and duration (its input accessor's max) are
/// listed.
#[test]
fn info_names_what_umbra_reads_ignores_and_refuses() {
    let (mut root, mut bin) = generate::split_glb(&std::fs::read(box_glb()).unwrap());
    root["extensionsUsed"] = json!(["KHR_materials_variants", "EXT_lights_image_based"]);
    root["extensions"] =
        json!({"KHR_materials_variants": {"variants": [{"name": "oak"}, {"name": "walnut"}]}});
    // An animation: node 0 translated over 2.5 seconds.
    let at = bin.len();
    for x in [0.0f32, 2.5, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    root["buffers"][0]["byteLength"] = json!(bin.len());
    let views = root["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": 8}));
    views.push(json!({"buffer": 0, "byteOffset": at + 8, "byteLength": 24}));
    let (times, values) = (views.len() - 2, views.len() - 1);
    let accessors = root["accessors"].as_array_mut().unwrap();
    accessors.push(json!({"bufferView": times, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [2.5]}));
    accessors.push(json!({"bufferView": values, "componentType": 5126, "count": 2, "type": "VEC3"}));
    let (input, output) = (accessors.len() - 2, accessors.len() - 1);
    root["animations"] = json!([{"name": "slide", "samplers": [{"input": input, "output": output}],
        "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}]}]);
    let path = write("variants.glb", &root, &bin);
    let report: Value = serde_json::from_str(&info(&[path.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(report["variants"], json!(["oak", "walnut"]));
    assert_eq!(report["animations"], json!([{"name": "slide", "channels": 1, "duration": 2.5}]));
    let status = |name: &str| {
        report["extensions"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e["name"] == name)
            .map(|e| e["umbra"].clone())
    };
    assert_eq!(status("KHR_materials_variants"), Some(json!("read")));
    assert_eq!(status("EXT_lights_image_based"), Some(json!("ignored")));
    let warnings = report["loaded"]["warnings"].to_string();
    assert!(warnings.contains("EXT_lights_image_based") && warnings.contains("animated"), "{warnings}");

    root["extensionsRequired"] = json!(["EXT_texture_avif"]);
    root["extensionsUsed"] = json!(["EXT_texture_avif"]);
    let path = write("avif.glb", &root, &bin);
    let report: Value = serde_json::from_str(&info(&[path.to_str().unwrap(), "--json"])).unwrap();
    assert_eq!(report["extensions"][0]["umbra"], "refused", "{report}");
    let refused = report["loaded"]["refused"].as_str().expect("refused");
    assert!(refused.contains("avif.glb") && refused.contains("EXT_texture_avif"), "{refused}");
    let text = info(&[path.to_str().unwrap()]);
    assert!(text.contains("REFUSED") && text.contains("EXT_texture_avif (required): refused"), "{text}");

    // A Draco file (Google's encoder, tests/scene/draco/) is read, with the build's feature.
    let draco = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scene/draco/glass-draco.glb");
    let report: Value = serde_json::from_str(&info(&[draco.to_str().unwrap(), "--json"])).unwrap();
    let expected = if cfg!(feature = "draco") { "read" } else { "refused" };
    assert_eq!(report["extensions"][0]["umbra"], expected, "{report}");
    if cfg!(feature = "draco") {
        assert_eq!(report["loaded"]["triangles"], 2214, "{report}");
    }
}

/// Not glTF at all: an error naming the file, no report.
#[test]
fn info_of_a_file_that_is_not_gltf_is_an_error() {
    let path = write("notes.glb", &json!({}), &[]);
    std::fs::write(&path, b"hello").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(["info", path.to_str().unwrap()])
        .env("VK_DRIVER_FILES", "/nonexistent/umbra_no_driver.json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("notes.glb") && stderr.contains("not a glTF file"), "{stderr}");
}
