//! Bad input: truncated or foreign bytes, JSON that breaks glTF's rules, unsupported extensions,
//! out-of-range indices and values, NaN vertices, undecodable images: each a precise
//! `Error::Scene`.

use crate::{assert_scene_error, khronos, read_glb, scenes_dir, to_glb};
use serde_json::{json, Value};
use umbra::scene::Scene;

// ---------------------------------------------------------------------------------------------
// Bad input

#[test]
fn truncated_and_foreign_bytes_are_rejected() {
    let glb = std::fs::read(scenes_dir().join("cornell-box.glb")).unwrap();
    assert_scene_error(Scene::from_glb_bytes("cut.glb", &glb[..glb.len() / 2]), "cut.glb", "truncated GLB");
    assert_scene_error(Scene::from_glb_bytes("cut.glb", &glb[..7]), "cut.glb", "truncated GLB");
    let png = b"\x89PNG\r\n\x1a\n not a scene";
    assert_scene_error(Scene::from_glb_bytes("picture.png", png), "picture.png", "not a glTF file");
    assert_scene_error(Scene::from_glb_bytes("empty.glb", b""), "empty.glb", "not a glTF file");
    assert_scene_error(
        Scene::from_glb_bytes("broken.gltf", b"{\"asset\": "),
        "broken.gltf",
        "invalid glTF JSON",
    );
}

#[test]
fn json_that_breaks_gltf_rules_is_rejected() {
    let (json, bin) = read_glb(&khronos("Box"));
    // Accessor 2 (POSITION) claims more vertices than its buffer view holds.
    let mut long = json.clone();
    long["accessors"][2]["count"] = json!(1000);
    assert_scene_error(
        Scene::from_glb_bytes("long.glb", &to_glb(&long, &bin)),
        "long.glb",
        "runs past the end of buffer view",
    );
    // A buffer view past the end of its buffer.
    let mut view = json.clone();
    view["bufferViews"][1]["byteLength"] = json!(100_000);
    assert_scene_error(
        Scene::from_glb_bytes("view.glb", &to_glb(&view, &bin)),
        "view.glb",
        "runs past the end of buffer 0",
    );
    // An index into a missing array (caught by glTF validation).
    let mut material = json.clone();
    material["meshes"][0]["primitives"][0]["material"] = json!(7);
    assert_scene_error(Scene::from_glb_bytes("mat.glb", &to_glb(&material, &bin)), "mat.glb", "invalid glTF");
    let mut position = json.clone();
    position["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    assert_scene_error(
        Scene::from_glb_bytes("pos.glb", &to_glb(&position, &bin)),
        "pos.glb",
        "POSITION refers to accessor 9",
    );
    // A cycle in the node tree.
    let mut cycle = json.clone();
    cycle["nodes"][1]["children"] = json!([0]);
    assert_scene_error(
        Scene::from_glb_bytes("cycle.glb", &to_glb(&cycle, &bin)),
        "cycle.glb",
        "reached twice",
    );
}

#[test]
fn unsupported_required_extensions_are_named_and_optional_ones_ignored() {
    let (mut json, bin) = read_glb(&khronos("Box"));
    json["extensionsUsed"] = json!([
        "EXT_texture_avif",
        "KHR_texture_transform",
        "KHR_materials_iridescence",
        "KHR_materials_anisotropy",
        "EXT_unknown"
    ]);
    let scene =
        Scene::from_glb_bytes("optional.glb", &to_glb(&json, &bin)).expect("optional extensions are ignored");
    // Named once, at warn level and in the scene's warnings; those umbra reads are not named.
    assert_eq!(
        scene.warnings,
        vec!["optional.glb: ignoring optional glTF extensions EXT_texture_avif, EXT_unknown: rendered without them"]
    );
    json["extensionsRequired"] = json!(["EXT_texture_avif"]);
    assert_scene_error(
        Scene::from_glb_bytes("avif.glb", &to_glb(&json, &bin)),
        "avif.glb",
        "does not support: EXT_texture_avif",
    );
    json["extensionsRequired"] = json!(["KHR_texture_transform", "KHR_materials_emissive_strength"]);
    Scene::from_glb_bytes("supported.glb", &to_glb(&json, &bin)).expect("required extensions umbra reads");
}

#[test]
fn out_of_range_indices_are_rejected() {
    let (json, mut bin) = read_glb(&khronos("Box"));
    let view = &json["bufferViews"][json["accessors"][0]["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap() as usize + 2 * 5;
    bin[at..at + 2].copy_from_slice(&99u16.to_le_bytes());
    assert_scene_error(
        Scene::from_glb_bytes("index.glb", &to_glb(&json, &bin)),
        "index.glb",
        "mesh 0 ('Mesh') primitive 0: index 99 (entry 5 of its indices) is out of range: the primitive has 24 vertices",
    );
}

#[test]
fn nan_vertices_drop_their_triangles() {
    let (json, bin) = read_glb(&khronos("Box"));
    let positions = &json["bufferViews"][json["accessors"][2]["bufferView"].as_u64().unwrap() as usize];
    let start = positions["byteOffset"].as_u64().unwrap() as usize
        + json["accessors"][2]["byteOffset"].as_u64().unwrap() as usize;
    // Vertex 0 is NaN: the triangles that use it go, the rest stay.
    let mut one = bin.clone();
    one[start..start + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let scene = Scene::from_glb_bytes("nan.glb", &to_glb(&json, &one)).unwrap();
    let indices = &json["bufferViews"][json["accessors"][0]["bufferView"].as_u64().unwrap() as usize];
    let first = indices["byteOffset"].as_u64().unwrap() as usize;
    let using_vertex_0 = (0..12)
        .filter(|t| (0..3).any(|c| bin[first + 6 * t + 2 * c..first + 6 * t + 2 * c + 2] == [0, 0]))
        .count();
    assert!(using_vertex_0 > 0);
    assert_eq!(scene.triangles.len(), 12 - using_vertex_0);
    assert_eq!(scene.normals.len(), scene.positions.len());
    assert!(scene.positions.iter().flatten().all(|x| x.is_finite()));
    assert!(scene.triangles.iter().flatten().all(|&v| (v as usize) < scene.positions.len()));
    // Every vertex infinite: nothing is left, which is an error.
    let mut all = bin.clone();
    for v in 0..24 {
        all[start + 12 * v..start + 12 * v + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    }
    assert_scene_error(
        Scene::from_glb_bytes("inf.glb", &to_glb(&json, &all)),
        "inf.glb",
        "all 12 triangles were dropped for NaN or infinite vertex positions",
    );
}

#[test]
fn undecodable_images_are_named() {
    let (json, mut bin) = read_glb(&scenes_dir().join("textured.glb"));
    let view = &json["bufferViews"][json["images"][1]["bufferView"].as_u64().unwrap() as usize];
    let at = view["byteOffset"].as_u64().unwrap() as usize;
    bin[at..at + 8].copy_from_slice(b"garbage!");
    assert_scene_error(
        Scene::from_glb_bytes("bad-image.glb", &to_glb(&json, &bin)),
        "bad-image.glb",
        "image 1 (embedded): cannot decode the image",
    );
}

/// One out-of-spec punctual light (a spot whose inner cone exceeds its outer, an absurd
/// intensity, a negative one) is an error naming the file, the light and the field: it once made
/// every light of the file vanish without a word (its infinite radiance turned each sample NaN,
/// and NaN samples are dropped).
#[test]
fn out_of_range_lights_are_errors_naming_them() {
    let with_light = |light: Value| {
        let (mut json, bin) = read_glb(&scenes_dir().join("spheres.glb"));
        json["extensions"]["KHR_lights_punctual"]["lights"].as_array_mut().unwrap().push(light);
        to_glb(&json, &bin)
    };
    let spot = with_light(json!({"type": "spot", "name": "lamp", "intensity": 10.0,
        "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}}));
    assert_scene_error(
        Scene::from_glb_bytes("spot.glb", &spot),
        "spot.glb",
        "KHR_lights_punctual light 1 ('lamp'): spot innerConeAngle 1 must be less than outerConeAngle 0.5",
    );
    let bright = with_light(json!({"type": "point", "intensity": 1e30}));
    assert_scene_error(
        Scene::from_glb_bytes("bright.glb", &bright),
        "bright.glb",
        "light 1: intensity is 1e+30, must be within [0, 100000000000000000000]",
    );
    let negative = with_light(json!({"type": "directional", "intensity": -2.0}));
    assert_scene_error(
        Scene::from_glb_bytes("negative.glb", &negative),
        "negative.glb",
        "light 1: intensity is -2.0, must be within [0,",
    );
    let wide = with_light(json!({"type": "spot", "spot": {"outerConeAngle": 2.0}}));
    assert_scene_error(
        Scene::from_glb_bytes("wide.glb", &wide),
        "wide.glb",
        "outerConeAngle is 2.0, must be within [0, 1.57",
    );
    let range = with_light(json!({"type": "point", "range": 0.0}));
    assert_scene_error(
        Scene::from_glb_bytes("range.glb", &range),
        "range.glb",
        "range is 0.0, must be greater than 0",
    );
    let colour = with_light(json!({"type": "point", "color": [1.0, 2.0, 0.5]}));
    assert_scene_error(
        Scene::from_glb_bytes("colour.glb", &colour),
        "colour.glb",
        "color[1] is 2.0, must be within [0, 1]",
    );
    // A zero scale on the light's node leaves it no direction: an error naming the node.
    let (mut json, bin) = read_glb(&scenes_dir().join("spheres.glb"));
    json["nodes"][51]["scale"] = json!([1.0, 0.0, 1.0]);
    assert_scene_error(Scene::from_glb_bytes("flat.glb", &to_glb(&json, &bin)), "flat.glb", "node 51");
    assert_scene_error(Scene::from_glb_bytes("flat.glb", &to_glb(&json, &bin)), "flat.glb", "degenerate");
    // The spheres' own light alone loads, and is there.
    let (json, bin) = read_glb(&scenes_dir().join("spheres.glb"));
    assert_eq!(Scene::from_glb_bytes("ok.glb", &to_glb(&json, &bin)).unwrap().lights.len(), 1);
}

/// Material factors, extension parameters, texture transforms, camera planes and node transforms
/// outside their specified ranges: each an error naming the element, its index and the field;
/// several at once are all named.
#[test]
fn out_of_range_values_are_errors_naming_the_element() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let case = |edit: &dyn Fn(&mut Value), phrase: &str| {
        let mut json = base.clone();
        edit(&mut json);
        assert_scene_error(Scene::from_glb_bytes("range.glb", &to_glb(&json, &bin)), "range.glb", phrase);
    };
    let material = |json: &mut Value| json["materials"][0].clone();
    let name = material(&mut base.clone())["name"].as_str().map(|n| format!(" ('{n}')")).unwrap_or_default();
    let m0 = format!("material 0{name}");
    case(
        &|j| j["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.5, 0.5, 0.5, 1.0]),
        &format!("{m0}: baseColorFactor[0] is 1.5, must be within [0, 1]"),
    );
    case(
        &|j| j["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(-0.1),
        &format!("{m0}: metallicFactor is -0.1"),
    );
    case(
        &|j| j["materials"][0]["emissiveFactor"] = json!([0.0, 3.0, 0.0]),
        &format!("{m0}: emissiveFactor[1] is 3.0"),
    );
    case(
        &|j| j["materials"][0]["extensions"] = json!({"KHR_materials_ior": {"ior": -1.5}}),
        &format!("{m0} KHR_materials_ior: ior is -1.5, must be at least 1 (or 0)"),
    );
    case(&|j| j["materials"][0]["extensions"] = json!({"KHR_materials_ior": {"ior": 0.5}}), "ior is 0.5");
    case(
        &|j| {
            j["materials"][0]["extensions"] =
                json!({"KHR_materials_transmission": {"transmissionFactor": 2.0}})
        },
        "KHR_materials_transmission: transmissionFactor is 2.0",
    );
    case(
        &|j| j["materials"][0]["extensions"] = json!({"KHR_materials_volume": {"attenuationDistance": 0.0}}),
        "KHR_materials_volume: attenuationDistance is 0.0, must be greater than 0",
    );
    case(
        &|j| {
            j["materials"][0]["extensions"] =
                json!({"KHR_materials_emissive_strength": {"emissiveStrength": -1.0}})
        },
        "emissiveStrength is -1.0, must be at least 0",
    );
    case(
        &|j| {
            j["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] =
                json!({"KHR_texture_transform": {"scale": [1.0, 1e39]}})
        },
        "baseColorTexture KHR_texture_transform: scale[1] is 1e+39, must be a finite 32-bit float",
    );
    case(
        &|j| {
            j["cameras"] =
                json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 1.0, "zfar": 0.5}}]);
        },
        "camera 0: zfar 0.5 must be greater than znear 1",
    );
    case(&|j| j["nodes"][0]["scale"] = json!([1.0, 1e39, 1.0]), "node 0");
    // Several problems: the first five named, the rest counted.
    case(
        &|j| {
            for k in ["metallicFactor", "roughnessFactor"] {
                j["materials"][0]["pbrMetallicRoughness"][k] = json!(7.0);
            }
            j["materials"][0]["alphaCutoff"] = json!(-1.0);
        },
        "roughnessFactor is 7.0",
    );
    // A node that puts a mesh beyond the BVH's reach is named, not a BVH node.
    case(&|j| j["nodes"][0]["translation"] = json!([0.0, 2e18, 0.0]), "node 0");
    case(
        &|j| j["nodes"][0]["translation"] = json!([0.0, 2e18, 0.0]),
        "umbra's BVH takes world coordinates within ±5e17",
    );
}
