//! The glTF loader: every committed scene loads with the counts its JSON implies; transforms,
//! winding, samplers, emission, cameras and the emissive table are right; bad input gives a
//! precise `Error::Scene` and never a panic. CPU only.

#[path = "support/generate.rs"]
mod generate;

mod common;

use glam::{Mat4, Quat, Vec3};
use serde_json::{json, Value};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use umbra::scene::{texture_transform, Filter, LightKind, Scene, Wrap};
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
fn instanced_transforms() -> Vec<(String, Mat4)> {
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
// Transforms

/// Every (non-degenerate) triangle's winding agrees with its vertices' shading normals.
fn assert_winding_agrees(scene: &Scene, triangles: std::ops::Range<usize>, what: &str) {
    for t in triangles {
        let [a, b, c] = scene.triangles[t].map(|v| Vec3::from(scene.positions[v as usize]));
        let geometric = (b - a).cross(c - a);
        if geometric.length() < 1e-9 {
            continue;
        }
        let shading: Vec3 = scene.triangles[t].iter().map(|&v| Vec3::from(scene.normals[v as usize])).sum();
        assert!(geometric.dot(shading) > 0.0, "{what}: triangle {t} is wound against its normals");
    }
}

#[test]
fn negatively_scaled_instances_keep_front_faces_counter_clockwise() {
    for path in [khronos("NegativeScaleTest"), scenes_dir().join("instanced.glb")] {
        let scene = load(&path);
        let mirrored: Vec<_> = scene
            .instances
            .iter()
            .filter(|i| Mat4::from_cols_array_2d(&i.transform).determinant() < 0.0)
            .collect();
        assert!(!mirrored.is_empty(), "{} has mirrored instances", path.display());
        for instance in mirrored {
            let range = instance.first_triangle as usize
                ..(instance.first_triangle + instance.triangle_count) as usize;
            assert_winding_agrees(&scene, range, &format!("{} instance '{}'", path.display(), instance.name));
        }
    }
    // The generated scene's mirrored nodes are exactly the two under "mirror".
    let scene = load(&scenes_dir().join("instanced.glb"));
    let mut mirrored: Vec<&str> = scene
        .instances
        .iter()
        .filter(|i| Mat4::from_cols_array_2d(&i.transform).determinant() < 0.0)
        .map(|i| i.name.as_str())
        .collect();
    mirrored.sort();
    assert_eq!(mirrored, ["mirror", "mirror child"]);
    assert_winding_agrees(&scene, 0..scene.triangles.len(), "instanced.glb");
}

#[test]
fn nested_transforms_and_the_default_scene_are_honoured() {
    let scene = load(&scenes_dir().join("instanced.glb"));
    assert!(scene.instances.iter().all(|i| i.name != "not in the default scene"));
    let find = |name: &str| scene.instances.iter().find(|i| i.name == name).unwrap();
    let want = instanced_transforms();
    assert_eq!(scene.instances.len(), want.len());
    for (name, want) in &want {
        let got = Mat4::from_cols_array_2d(&find(name).transform);
        assert!(got.abs_diff_eq(*want, 1e-5), "{name}: {got} != {want}");
    }
    let finger = want.iter().find(|(n, _)| n == "finger").unwrap().1;
    // The triangles follow the transform: the instance's first vertex is the mesh's first, moved.
    let (json, bin) = read_glb(&scenes_dir().join("instanced.glb"));
    let local = read_vec3(
        &json,
        &bin,
        json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap(),
    );
    let finger_instance = find("finger");
    let v = scene.triangles[finger_instance.first_triangle as usize][0] as usize;
    let first =
        scene.triangles[finger_instance.first_triangle as usize..].iter().flatten().min().copied().unwrap()
            as usize;
    assert!(Vec3::from(scene.positions[v]).abs_diff_eq(finger.transform_point3(local[v - first]), 1e-5));
}

/// Reads a float VEC3 (or VEC4 with `N` = 4) accessor straight from the BIN chunk.
fn read_floats<const N: usize>(json: &Value, bin: &[u8], accessor: u64) -> Vec<[f32; N]> {
    let accessor = &json["accessors"][accessor as usize];
    assert_eq!(accessor["componentType"], 5126);
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    let stride = view["byteStride"].as_u64().unwrap_or(4 * N as u64) as usize;
    (0..accessor["count"].as_u64().unwrap() as usize)
        .map(|i| {
            std::array::from_fn(|c| {
                let at = start + i * stride + 4 * c;
                f32::from_le_bytes(bin[at..at + 4].try_into().unwrap())
            })
        })
        .collect()
}

fn read_vec3(json: &Value, bin: &[u8], accessor: u64) -> Vec<Vec3> {
    read_floats::<3>(json, bin, accessor).into_iter().map(Vec3::from).collect()
}

#[test]
fn gpu_instancing_places_every_instance_with_its_transform() {
    let path = khronos("SimpleInstancing");
    let scene = load(&path);
    let (json, bin) = read_glb(&path);
    let attributes = &json["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
    let translations = read_vec3(&json, &bin, attributes["TRANSLATION"].as_u64().unwrap());
    let rotations = read_floats::<4>(&json, &bin, attributes["ROTATION"].as_u64().unwrap());
    let scales = read_vec3(&json, &bin, attributes["SCALE"].as_u64().unwrap());
    let local = read_vec3(
        &json,
        &bin,
        json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap(),
    );
    assert_eq!(scene.instances.len(), 125);
    assert_eq!(translations.len(), 125);
    for (i, instance) in scene.instances.iter().enumerate() {
        let want = Mat4::from_scale_rotation_translation(
            scales[i],
            Quat::from_array(rotations[i]).normalize(),
            translations[i],
        );
        assert!(Mat4::from_cols_array_2d(&instance.transform).abs_diff_eq(want, 1e-5), "instance {i}");
        assert_eq!((instance.first_triangle, instance.triangle_count), (12 * i as u32, 12));
        // Each instance appends the cube's 24 vertices in order.
        for (j, &p) in local.iter().enumerate() {
            let got = Vec3::from(scene.positions[24 * i + j]);
            assert!(got.abs_diff_eq(want.transform_point3(p), 1e-4), "instance {i} vertex {j}");
        }
    }
}

#[test]
fn orientation_test_arrows_point_at_their_targets() {
    let scene = load(&khronos("OrientationTest"));
    let bounds = |name: &str| {
        let i =
            scene.instances.iter().find(|i| i.name == name).unwrap_or_else(|| panic!("no instance {name}"));
        let range = i.first_triangle as usize..(i.first_triangle + i.triangle_count) as usize;
        let points =
            scene.triangles[range].iter().flatten().map(|&v| Vec3::from(scene.positions[v as usize]));
        points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)))
    };
    let touch = |(a0, a1): (Vec3, Vec3), (b0, b1): (Vec3, Vec3)| {
        (a0 - 0.02).cmple(b1).all() && (b0 - 0.02).cmple(a1).all()
    };
    let pairs = ["X1", "X2", "Y1", "Y2", "Z1", "Z2"];
    for pair in pairs {
        let arrow = bounds(&format!("Arrow{pair}"));
        // ArrowX1 sits on +X, ArrowX2 on -X, and so on.
        let axis = ["X", "Y", "Z"].iter().position(|a| pair.starts_with(a)).unwrap();
        let side = if pair.ends_with('1') { 1.0 } else { -1.0 };
        assert!(
            ((arrow.0 + arrow.1) * 0.5)[axis] * side > 4.0,
            "Arrow{pair} is on the wrong side: {arrow:?}"
        );
        for other in pairs {
            let hits = touch(arrow, bounds(&format!("Target{other}")));
            assert_eq!(
                hits,
                other == pair,
                "Arrow{pair} {} Target{other}",
                if hits { "touches" } else { "misses" }
            );
        }
    }
}

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

// ---------------------------------------------------------------------------------------------
// Cameras and lights

#[test]
fn cameras_are_selected_by_index_or_default_or_framed() {
    let cornell = Scene::cornell_box();
    let camera = cornell.camera(None).unwrap();
    assert_eq!(camera, cornell.cameras[0]);
    assert_eq!(cornell.camera(Some(0)).unwrap(), camera);
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-5);
    assert!(close(camera.position, [0.275, 0.275, -0.8]), "{camera:?}");
    assert!(close(camera.forward, [0.0, 0.0, 1.0]) && close(camera.up, [0.0, 1.0, 0.0]), "{camera:?}");
    assert!((camera.yfov.to_degrees() - 39.3).abs() < 0.1 && camera.aspect == Some(1.0));
    match cornell.camera(Some(3)) {
        Err(Error::Scene { path, message }) => {
            assert!(path.to_string_lossy().contains("cornell-box.glb"));
            assert!(message.contains("no camera 3") && message.contains("1 camera"), "{message}");
        }
        other => panic!("expected an error, got {other:?}"),
    }

    // Box.glb has no camera: one is made that frames the bounds from +Z with a 45° yfov.
    let boxed = load(&khronos("Box"));
    assert!(boxed.cameras.is_empty());
    let framing = boxed.camera(None).unwrap();
    let (lo, hi) = boxed.bounds();
    let (centre, radius) =
        ((Vec3::from(lo) + Vec3::from(hi)) * 0.5, (Vec3::from(hi) - Vec3::from(lo)).length() * 0.5);
    assert_eq!((framing.forward, framing.up), ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]));
    assert!((framing.yfov.to_degrees() - 45.0).abs() < 1e-4);
    let eye = Vec3::from(framing.position);
    assert!(eye.x == centre.x && eye.y == centre.y && eye.z > centre.z);
    let half_angle = (radius / (eye - centre).length()).asin();
    assert!(half_angle <= framing.yfov * 0.5 + 1e-5, "the bounding sphere must fit");
    assert!(framing.znear > 0.0 && framing.znear < (eye - centre).length() - radius);
    assert!(
        matches!(boxed.camera(Some(0)), Err(Error::Scene { message, .. }) if message.contains("0 cameras"))
    );
}

#[test]
fn punctual_lights_are_placed_in_world_space() {
    let scene = load(&scenes_dir().join("textured.glb"));
    assert_eq!(scene.lights.len(), 2);
    let bulb = scene.lights.iter().find(|l| l.kind == LightKind::Point).unwrap();
    assert_eq!((bulb.position, bulb.intensity, bulb.range), ([1.0, 2.0, 1.0], 20.0, Some(10.0)));
    let spot = scene.lights.iter().find(|l| l.kind == LightKind::Spot).unwrap();
    assert!(Vec3::from(spot.direction).abs_diff_eq(-Vec3::Y, 1e-6), "{spot:?}");
    assert_eq!((spot.inner_cone_angle, spot.outer_cone_angle, spot.color), (0.2, 0.5, [1.0; 3]));
    let sun = &load(&scenes_dir().join("spheres.glb")).lights[0];
    assert_eq!(sun.kind, LightKind::Directional);
    assert!(Vec3::from(sun.direction).abs_diff_eq(Vec3::new(-0.4, -1.0, -0.6).normalize(), 1e-5));
}

// ---------------------------------------------------------------------------------------------
// The emissive table

#[test]
fn the_emissive_table_holds_exactly_the_lights_triangles() {
    let scene = Scene::cornell_box();
    let light = scene.materials.iter().position(|m| m.name == "light").unwrap() as u32;
    let want: Vec<u32> =
        (0..scene.triangles.len() as u32).filter(|&t| scene.triangle_material[t as usize] == light).collect();
    let table = &scene.emissive;
    assert_eq!(table.triangles, want);
    assert!(table.cdf.windows(2).all(|w| w[0] <= w[1]) && *table.cdf.last().unwrap() == 1.0);
    let soup = scene.triangle_soup();
    let areas: Vec<f32> = table
        .triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = soup[t as usize];
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    let total_area: f32 = areas.iter().sum();
    assert!((total_area - 0.13 * 0.105).abs() < 1e-6);
    for (i, area) in areas.iter().enumerate() {
        assert!((table.pmf(i) - area / total_area).abs() < 1e-5, "pmf of entry {i}");
    }
    let luminance = 0.2126 * 17.0 + 0.7152 * 12.0 + 0.0722 * 4.0;
    assert!((table.total_power - luminance * total_area * std::f32::consts::PI).abs() < 1e-4);
    // Sampling follows the cdf: u below the first step picks entry 0, above it entry 1.
    assert_eq!(table.sample(0.0).0, 0);
    assert_eq!(table.sample(table.cdf[0] * 0.99).0, 0);
    assert_eq!(table.sample(table.cdf[0] + 1e-3).0, 1);
    assert_eq!(table.sample(1.0).0, 1);
    let hits = (0..1000).filter(|i| table.sample((*i as f32 + 0.5) / 1000.0).0 == 0).count();
    assert!((hits as f32 / 1000.0 - table.pmf(0)).abs() < 2e-3);
    assert!(load(&khronos("Box")).emissive.is_empty());
}

// ---------------------------------------------------------------------------------------------
// Primitive modes and missing normals

/// A primitive for [`primitives_glb`]: mode, positions, optional indices.
type TestPrimitive<'a> = (u32, &'a [[f32; 3]], Option<&'a [u16]>);

/// A GLB whose single mesh has the given primitives (positions only).
fn primitives_glb(primitives: &[TestPrimitive]) -> Vec<u8> {
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut json_primitives) = (vec![], vec![], vec![]);
    for (mode, positions, indices) in primitives {
        let offset = bin.len();
        bin.extend(positions.iter().flatten().flat_map(|f| f.to_le_bytes()));
        views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset }));
        let lo = [0, 1, 2].map(|c| positions.iter().map(|p| p[c]).fold(f32::INFINITY, f32::min));
        let hi = [0, 1, 2].map(|c| positions.iter().map(|p| p[c]).fold(f32::NEG_INFINITY, f32::max));
        accessors.push(json!({ "bufferView": views.len() - 1, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi }));
        let mut primitive = json!({ "attributes": { "POSITION": accessors.len() - 1 }, "mode": mode });
        if let Some(indices) = indices {
            let offset = bin.len();
            bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
            bin.resize(bin.len().div_ceil(4) * 4, 0);
            views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": indices.len() * 2 }));
            accessors.push(json!({ "bufferView": views.len() - 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR" }));
            primitive["indices"] = json!(accessors.len() - 1);
        }
        json_primitives.push(primitive);
    }
    let json = json!({
        "asset": { "version": "2.0" }, "scene": 0, "scenes": [{ "nodes": [0] }], "nodes": [{ "mesh": 0 }],
        "meshes": [{ "name": "test", "primitives": json_primitives }],
        "accessors": accessors, "bufferViews": views, "buffers": [{ "byteLength": bin.len() }]
    });
    to_glb(&json, &bin)
}

const QUAD: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];

#[test]
fn strips_and_fans_become_counter_clockwise_triangles_and_points_are_skipped() {
    let fan: [[f32; 3]; 5] =
        [[0.5, 0.5, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
    let bytes = primitives_glb(&[
        (5, &QUAD, None),
        (5, &QUAD, Some(&[0, 1, 2, 3])),
        (6, &fan, None),
        (6, &QUAD, Some(&[0, 1, 3, 2])),
        (0, &QUAD, None),
        (1, &QUAD, None),
    ]);
    let scene = Scene::from_glb_bytes("modes.glb", &bytes).unwrap();
    assert_eq!(scene.triangles.len(), 2 + 2 + 3 + 2);
    for t in scene.triangle_soup() {
        assert!((t[1] - t[0]).cross(t[2] - t[0]).z > 0.0, "{t:?} faces -Z");
    }
    // No NORMAL attribute: flat normals, one vertex per triangle corner.
    assert_eq!(scene.positions.len(), 3 * 9);
    assert!(scene.normals.iter().all(|&n| n == [0.0, 0.0, 1.0]));
}

#[test]
fn zero_area_triangles_are_kept_and_counted() {
    let positions = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let scene = Scene::from_glb_bytes("sliver.glb", &primitives_glb(&[(4, &positions, None)])).unwrap();
    assert_eq!((scene.stats().triangles, scene.stats().degenerate_triangles), (2, 1));
    assert!(scene.normals.iter().all(|&n| (Vec3::from(n).length() - 1.0).abs() < 1e-6));
}

// ---------------------------------------------------------------------------------------------
// Bad input

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
        "KHR_draco_mesh_compression",
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
        vec!["optional.glb: ignoring optional glTF extensions KHR_draco_mesh_compression, EXT_unknown: rendered without them"]
    );
    json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    assert_scene_error(
        Scene::from_glb_bytes("draco.glb", &to_glb(&json, &bin)),
        "draco.glb",
        "does not support: KHR_draco_mesh_compression",
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
    let warn = LoadOptions { missing_textures: MissingTextures::Warn };
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

/// A small deterministic generator for the fuzz test.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Random mutations of every committed scene (bytes truncated or overwritten; one JSON number
/// replaced by an awkward value) load or give an error naming the file: never a panic. The
/// outcome counts are printed (and kept in docs/reliability.md).
#[test]
fn mutated_files_give_errors_not_panics() {
    let mut rng = XorShift(0x5eed_cafe);
    let odd_numbers = [
        json!(-1),
        json!(0),
        json!(1),
        json!(3),
        json!(255),
        json!(65536),
        json!(4_294_967_295u64),
        json!(1e30),
        json!(-0.5),
    ];
    // [raw bytes, JSON edits] × [loaded, rejected].
    let mut outcomes = [[0usize; 2]; 2];
    let mut tally = |kind: usize, result: umbra::Result<Scene>| match result {
        Ok(_) => outcomes[kind][0] += 1,
        Err(e) => {
            assert!(e.to_string().contains("fuzz.glb"), "the error does not name the file: {e}");
            outcomes[kind][1] += 1;
        }
    };
    let files = committed_scenes();
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let (json, bin) = generate::split_glb(&bytes);
        let mut numbers = Vec::new();
        collect_number_paths(&json, &mut Vec::new(), &mut numbers);
        for round in 0..120 {
            // Raw bytes: truncate, or overwrite a few bytes anywhere.
            let mut raw = bytes.clone();
            if round % 3 == 0 {
                raw.truncate(rng.next() as usize % raw.len());
            } else {
                for _ in 0..4 {
                    let at = rng.next() as usize % raw.len();
                    raw[at] = rng.next() as u8;
                }
            }
            tally(0, Scene::from_glb_bytes("fuzz.glb", &raw));
            // Structure: replace one number of the JSON with an awkward value.
            let mut edited = json.clone();
            let target = &numbers[rng.next() as usize % numbers.len()];
            *pointer_mut(&mut edited, target) = odd_numbers[rng.next() as usize % odd_numbers.len()].clone();
            tally(1, Scene::from_glb_bytes("fuzz.glb", &to_glb(&edited, &bin)));
        }
    }
    let [[raw_ok, raw_err], [json_ok, json_err]] = outcomes;
    eprintln!(
        "{} scenes: byte mutations {raw_ok} loaded, {raw_err} rejected; JSON edits {json_ok} loaded, \
         {json_err} rejected; no panic",
        files.len()
    );
    assert_eq!(raw_ok + raw_err + json_ok + json_err, files.len() * 240);
}

fn collect_number_paths(value: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match value {
        Value::Number(_) => out.push(path.clone()),
        Value::Array(items) => items.iter().enumerate().for_each(|(i, v)| {
            path.push(i.to_string());
            collect_number_paths(v, path, out);
            path.pop();
        }),
        Value::Object(map) => map.iter().for_each(|(k, v)| {
            path.push(k.clone());
            collect_number_paths(v, path, out);
            path.pop();
        }),
        _ => {}
    }
}

fn pointer_mut<'v>(value: &'v mut Value, path: &[String]) -> &'v mut Value {
    path.iter().fold(value, |v, key| match v {
        Value::Array(items) => &mut items[key.parse::<usize>().unwrap()],
        other => &mut other[key.as_str()],
    })
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

/// A triangle the BVH build splits into pieces (early split clipping) appears once per piece in
/// BVH order, and every reference must carry the same shading record, its light pmf included:
/// the path tracer's MIS reads the pmf of whichever reference a ray hits.
#[test]
fn split_triangles_carry_their_shading_in_every_reference() {
    let mut scene = Scene { name: "split".into(), ..Default::default() };
    scene.materials.push(umbra::scene::Material::default());
    scene.materials.push(umbra::scene::Material { emissive: [4.0; 3], ..Default::default() });
    let mut add = |corners: [Vec3; 3], material: u32| {
        let base = scene.positions.len() as u32;
        scene.positions.extend(corners.map(<[f32; 3]>::from));
        scene.normals.extend([[0.0, 1.0, 0.0]; 3]);
        scene.triangles.push([base, base + 1, base + 2]);
        scene.triangle_material.push(material);
    };
    // Small triangles on a floor, a few of them emissive, and one large emissive ceiling.
    for i in 0..400 {
        let p = Vec3::new((i % 20) as f32 * 0.1 - 1.0, 0.0, (i / 20) as f32 * 0.1 - 1.0);
        add([p, p + Vec3::new(0.05, 0.0, 0.0), p + Vec3::new(0.0, 0.0, 0.05)], u32::from(i % 50 == 0));
    }
    let big = 400;
    add([Vec3::new(-10.0, 5.0, -10.0), Vec3::new(10.0, 5.0, -10.0), Vec3::new(0.0, 5.0, 10.0)], 1);
    scene.update_emissive();
    let arrays = umbra::gpu::scene::SceneArrays::new(&scene).unwrap();
    let references: Vec<usize> =
        (0..arrays.triangles.len()).filter(|&i| arrays.bvh.prim_order[i] == big).collect();
    assert!(references.len() > 1, "the large triangle was not split: {:?}", arrays.bvh.stats);
    let record = arrays.triangles[references[0]];
    assert!(record.light_pmf > 0.5, "{record:?}");
    for &i in &references {
        assert_eq!(arrays.triangles[i], record, "reference {i} of the split triangle differs");
    }
    for (i, t) in arrays.triangles.iter().enumerate() {
        let input = arrays.bvh.prim_order[i];
        assert_eq!(t.light_pmf > 0.0, input == big || (input < 400 && input % 50 == 0), "reference {i}");
    }
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

/// KHR_materials_clearcoat's factors and three textures reach the material (0 and none without
/// the extension; the normal texture with its scale, UV set and transform), with no warning; a
/// factor outside [0, 1] or a texture index beyond the file's textures is refused naming it.
#[test]
fn clearcoat_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |coat: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_clearcoat": coat });
        Scene::from_glb_bytes("coat.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].clearcoat, plain.materials[0].clearcoat_roughness), (0.0, 0.0));
    let scene = load(json!({"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.25})).unwrap();
    assert_eq!((scene.materials[0].clearcoat, scene.materials[0].clearcoat_roughness), (0.75, 0.25));
    assert!(scene.warnings.iter().all(|w| !w.contains("clearcoat")), "{:?}", scene.warnings);
    assert!(plain.materials[0].clearcoat_normal_texture.is_none());
    let scene = load(json!({
        "clearcoatFactor": 1.0,
        "clearcoatTexture": {"index": 0},
        "clearcoatRoughnessTexture": {"index": 0, "texCoord": 1},
        "clearcoatNormalTexture": {
            "index": 0,
            "scale": 0.5,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0]}}
        }
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.clearcoat, 1.0);
    assert!(scene.warnings.iter().all(|w| !w.contains("clearcoat")), "{:?}", scene.warnings);
    let (coat, rough, normal) = (
        m.clearcoat_texture.expect("clearcoatTexture"),
        m.clearcoat_roughness_texture.expect("clearcoatRoughnessTexture"),
        m.clearcoat_normal_texture.expect("clearcoatNormalTexture"),
    );
    assert_eq!((coat.tex_coord, rough.tex_coord, normal.tex_coord), (0, 1, 0));
    assert_eq!((coat.scale, normal.scale), (1.0, 0.5));
    assert_eq!(normal.transform[0][2], 0.25, "the normal texture's KHR_texture_transform");
    assert!(!scene.textures[coat.texture as usize].srgb, "the coat's textures are linear");
    let error = load(json!({"clearcoatRoughnessFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("coat.glb") && error.contains("clearcoatRoughnessFactor is 1.5"), "{error}");
    let error =
        load(json!({"clearcoatFactor": 1.0, "clearcoatTexture": {"index": 7}})).unwrap_err().to_string();
    assert!(
        error.contains("coat.glb") && error.contains("KHR_materials_clearcoat.clearcoatTexture.index is 7"),
        "{error}"
    );
}

/// KHR_materials_sheen's factors and two textures reach the material (0 and none without the
/// extension), the colour texture decoded as sRGB and the roughness texture as linear, with no
/// warning; a factor outside [0, 1] or a texture index beyond the file's textures is refused
/// naming it.
#[test]
fn sheen_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |sheen: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_sheen": sheen });
        Scene::from_glb_bytes("sheen.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].sheen_color, plain.materials[0].sheen_roughness), ([0.0; 3], 0.0));
    let scene = load(json!({"sheenColorFactor": [0.75, 0.5, 0.25], "sheenRoughnessFactor": 0.125})).unwrap();
    assert_eq!(
        (scene.materials[0].sheen_color, scene.materials[0].sheen_roughness),
        ([0.75, 0.5, 0.25], 0.125)
    );
    assert!(scene.warnings.iter().all(|w| !w.contains("sheen")), "{:?}", scene.warnings);
    let scene = load(json!({
        "sheenColorFactor": [1.0, 1.0, 1.0],
        "sheenColorTexture": {"index": 0},
        "sheenRoughnessTexture": {"index": 0}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.sheen_color, [1.0; 3]);
    let (color, roughness) =
        (m.sheen_color_texture.as_ref().unwrap(), m.sheen_roughness_texture.as_ref().unwrap());
    assert!(scene.textures[color.texture as usize].srgb, "the colour texture is sRGB");
    assert!(!scene.textures[roughness.texture as usize].srgb, "the roughness texture is linear");
    assert!(scene.warnings.iter().all(|w| !w.contains("sheen")), "{:?}", scene.warnings);
    assert!(
        plain.materials[0].sheen_color_texture.is_none()
            && plain.materials[0].sheen_roughness_texture.is_none()
    );
    let error = load(json!({"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessTexture": {"index": 7}}))
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("sheen.glb") && error.contains("KHR_materials_sheen.sheenRoughnessTexture.index is 7"),
        "{error}"
    );
    let error = load(json!({"sheenRoughnessFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("sheen.glb") && error.contains("sheenRoughnessFactor is 1.5"), "{error}");
    let error = load(json!({"sheenColorFactor": [0.5, -0.25, 0.5]})).unwrap_err().to_string();
    assert!(error.contains("sheen.glb") && error.contains("sheenColorFactor[1] is -0.25"), "{error}");
}

/// KHR_materials_volume's `thicknessFactor` and `thicknessTexture` reach the material (0 and none
/// without the extension; the texture linear, its UV set kept), with no warning.
#[test]
fn volume_thickness_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].thickness, plain.materials[0].thickness_texture), (0.0, None));
    let mut json = base.clone();
    json["extensionsUsed"] = json!(["KHR_materials_volume"]);
    json["materials"][0]["extensions"] = json!({ "KHR_materials_volume": {
        "thicknessFactor": 0.25,
        "thicknessTexture": {"index": 0, "texCoord": 1}
    }});
    let scene = Scene::from_glb_bytes("volume.glb", &to_glb(&json, &bin)).unwrap();
    let m = &scene.materials[0];
    assert!(m.volume);
    assert_eq!(m.thickness, 0.25);
    let texture = m.thickness_texture.expect("thicknessTexture");
    assert_eq!(texture.tex_coord, 1);
    assert!(!scene.textures[texture.texture as usize].srgb, "the thickness texture is linear");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// KHR_materials_diffuse_transmission's factor, colour and two textures reach the material (0,
/// white and none without the extension), the colour texture decoded as sRGB and the factor's as
/// linear, with no warning and no longer among the ignored extensions; a factor or colour outside
/// [0, 1] or a texture index beyond the file's textures is refused naming it.
#[test]
fn diffuse_transmission_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |through: Value| {
        let mut json = base.clone();
        json["extensionsUsed"] = json!(["KHR_materials_diffuse_transmission"]);
        json["materials"][0]["extensions"] = json!({ "KHR_materials_diffuse_transmission": through });
        Scene::from_glb_bytes("through.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    let m = &plain.materials[0];
    assert_eq!((m.diffuse_transmission, m.diffuse_transmission_color), (0.0, [1.0; 3]));
    assert!(m.diffuse_transmission_texture.is_none() && m.diffuse_transmission_color_texture.is_none());
    let scene = load(json!({
        "diffuseTransmissionFactor": 0.75,
        "diffuseTransmissionColorFactor": [0.5, 0.25, 0.125],
        "diffuseTransmissionTexture": {"index": 0},
        "diffuseTransmissionColorTexture": {"index": 0, "texCoord": 1}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.diffuse_transmission, m.diffuse_transmission_color), (0.75, [0.5, 0.25, 0.125]));
    let (factor, colour) =
        (m.diffuse_transmission_texture.unwrap(), m.diffuse_transmission_color_texture.unwrap());
    assert_eq!(colour.tex_coord, 1);
    assert!(!scene.textures[factor.texture as usize].srgb, "the factor's texture is linear");
    assert!(scene.textures[colour.texture as usize].srgb, "the colour texture is sRGB");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let error = load(json!({"diffuseTransmissionFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("through.glb") && error.contains("diffuseTransmissionFactor is 1.5"), "{error}");
    let error = load(json!({"diffuseTransmissionColorFactor": [0.5, 2.0, 0.5]})).unwrap_err().to_string();
    assert!(
        error.contains("through.glb") && error.contains("diffuseTransmissionColorFactor[1] is 2"),
        "{error}"
    );
    let error =
        load(json!({"diffuseTransmissionFactor": 1.0, "diffuseTransmissionColorTexture": {"index": 7}}))
            .unwrap_err()
            .to_string();
    assert!(
        error.contains("through.glb")
            && error
                .contains("KHR_materials_diffuse_transmission.diffuseTransmissionColorTexture.index is 7"),
        "{error}"
    );
}

/// KHR_materials_iridescence's factor, ior, thickness range and two textures reach the material
/// (factor 0, ior 1.3, thickness 100–400 nm and no textures without the extension; the defaults
/// for the values the extension leaves out), with no warning; a value outside its range or a
/// texture index beyond the file's textures is refused naming it.
#[test]
fn iridescence_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |film: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_iridescence": film });
        Scene::from_glb_bytes("film.glb", &to_glb(&json, &bin))
    };
    let film = |m: &umbra::scene::Material| (m.iridescence, m.iridescence_ior, m.iridescence_thickness);
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!(film(&plain.materials[0]), (0.0, 1.3, [100.0, 400.0]));
    assert!(plain.materials[0].iridescence_texture.is_none());
    let scene = load(json!({"iridescenceFactor": 0.75})).unwrap();
    assert_eq!(film(&scene.materials[0]), (0.75, 1.3, [100.0, 400.0]), "the defaults");
    let scene = load(json!({
        "iridescenceFactor": 0.5,
        "iridescenceIor": 1.8,
        "iridescenceThicknessMinimum": 250.0,
        "iridescenceThicknessMaximum": 125.0,
        "iridescenceTexture": {"index": 0},
        "iridescenceThicknessTexture": {"index": 0, "texCoord": 1,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0]}}}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(film(m), (0.5, 1.8, [250.0, 125.0]), "the minimum may exceed the maximum");
    assert!(scene.warnings.iter().all(|w| !w.contains("iridescence")), "{:?}", scene.warnings);
    let (weight, thickness) = (
        m.iridescence_texture.expect("iridescenceTexture"),
        m.iridescence_thickness_texture.expect("thickness"),
    );
    assert_eq!((weight.tex_coord, thickness.tex_coord), (0, 1));
    assert_eq!(thickness.transform[0][2], 0.25, "the thickness texture's KHR_texture_transform");
    assert!(!scene.textures[weight.texture as usize].srgb, "the film's textures are linear");
    for (bad, named) in [
        (json!({"iridescenceFactor": 1.5}), "iridescenceFactor is 1.5"),
        (json!({"iridescenceIor": 0.5}), "iridescenceIor is 0.5"),
        (json!({"iridescenceThicknessMinimum": -1.0}), "iridescenceThicknessMinimum is -1"),
        (json!({"iridescenceThicknessMaximum": -2.0}), "iridescenceThicknessMaximum is -2"),
        (
            json!({"iridescenceFactor": 1.0, "iridescenceTexture": {"index": 7}}),
            "iridescenceTexture.index is 7",
        ),
    ] {
        let error = load(bad).unwrap_err().to_string();
        assert!(error.contains("film.glb") && error.contains(named), "{named}: {error}");
    }
}

/// KHR_materials_anisotropy's factors and texture reach the material (0 and none without the
/// extension), with no warning and no longer among the ignored extensions; a strength outside
/// [0, 1] or a texture index beyond the file's is refused naming it. A primitive of an
/// anisotropic material needs a tangent frame: from TANGENT, else generated from its UVs (w ±1);
/// with neither, its tangents' w is 0 (the kernels then shade it isotropic) and one warning names
/// the primitive.
#[test]
fn anisotropy_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let with = |json: &mut Value, anisotropy: Value| {
        json["extensionsUsed"] = json!(["KHR_materials_anisotropy"]);
        json["materials"][0]["extensions"] = json!({ "KHR_materials_anisotropy": anisotropy });
    };
    let load = |anisotropy: Value| {
        let mut json = base.clone();
        with(&mut json, anisotropy);
        Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    let m = &plain.materials[0];
    assert_eq!((m.anisotropy_strength, m.anisotropy_rotation, m.anisotropy_texture), (0.0, 0.0, None));
    let scene = load(json!({"anisotropyStrength": 0.75, "anisotropyRotation": -1.25})).unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.anisotropy_strength, m.anisotropy_rotation), (0.75, -1.25));
    assert!(scene.warnings.iter().all(|w| !w.contains("anisotropy")), "{:?}", scene.warnings);
    let scene =
        load(json!({"anisotropyStrength": 1.0, "anisotropyTexture": {"index": 0, "texCoord": 1}})).unwrap();
    let texture = scene.materials[0].anisotropy_texture.expect("anisotropyTexture");
    assert_eq!(texture.tex_coord, 1);
    assert!(!scene.textures[texture.texture as usize].srgb, "the anisotropy texture is linear");
    let error = load(json!({"anisotropyStrength": 1.5})).unwrap_err().to_string();
    assert!(error.contains("aniso.glb") && error.contains("anisotropyStrength is 1.5"), "{error}");
    let error =
        load(json!({"anisotropyStrength": 1.0, "anisotropyTexture": {"index": 9}})).unwrap_err().to_string();
    assert!(
        error.contains("aniso.glb")
            && error.contains("KHR_materials_anisotropy.anisotropyTexture.index is 9"),
        "{error}"
    );
    // The floor (material 0, mesh 0) has TANGENT: no warning, every w ±1.
    let scene = load(json!({"anisotropyStrength": 0.5})).unwrap();
    assert!(!scene.tangents.is_empty() && scene.tangents.iter().all(|t| t[3].abs() == 1.0));
    // Without TANGENT, the tangents come from the UVs.
    let mut json = base.clone();
    with(&mut json, json!({"anisotropyStrength": 0.5}));
    json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("TANGENT");
    let scene = Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin)).unwrap();
    assert!(scene.tangents.iter().all(|t| t[3].abs() == 1.0), "tangents from the UVs");
    assert!(scene.warnings.iter().all(|w| !w.contains("tangent frame")), "{:?}", scene.warnings);
    // Without TANGENT and UVs: w 0 on that primitive's vertices, and the warning.
    let attributes = json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap();
    attributes.remove("TEXCOORD_0");
    let scene = Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin)).unwrap();
    let floor: Vec<usize> = (0..scene.triangles.len())
        .filter(|&t| scene.triangle_material[t] == 0)
        .flat_map(|t| scene.triangles[t].map(|v| v as usize))
        .collect();
    assert!(!floor.is_empty() && floor.iter().all(|&v| scene.tangents[v][3] == 0.0), "{:?}", scene.tangents);
    let warned: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("tangent frame")).collect();
    assert_eq!(warned.len(), 1, "{:?}", scene.warnings);
    assert!(
        warned[0].contains("aniso.glb")
            && warned[0].contains("mesh 0 ('plane') primitive 0")
            && warned[0].contains("isotropic"),
        "{}",
        warned[0]
    );
}

/// KHR_materials_volume's attenuation reaches the material: colour and distance as written, the
/// coefficient −ln(colour)/distance, and none without a thickness (thin-walled) or a distance.
#[test]
fn volume_attenuation_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |volume: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": volume,
        });
        Scene::from_glb_bytes("volume.glb", &to_glb(&json, &bin)).unwrap().materials[0].clone()
    };
    let m = load(
        json!({"thicknessFactor": 1.0, "attenuationColor": [0.5, 0.25, 1.0], "attenuationDistance": 2.0}),
    );
    assert!(m.volume);
    assert_eq!((m.attenuation_color, m.attenuation_distance), ([0.5, 0.25, 1.0], 2.0));
    let sigma = m.attenuation();
    for (got, expected) in sigma.iter().zip([0.5f32.ln() / -2.0, 0.25f32.ln() / -2.0, 0.0]) {
        assert!((got - expected).abs() < 1e-6, "{sigma:?}");
    }
    let thin = load(json!({"attenuationColor": [0.5, 0.25, 1.0], "attenuationDistance": 2.0}));
    assert!(!thin.volume && thin.attenuation() == [0.0; 3], "no thickness: thin-walled, no attenuation");
    let clear = load(json!({"thicknessFactor": 1.0, "attenuationColor": [0.5, 0.25, 1.0]}));
    assert!(clear.attenuation_distance.is_infinite() && clear.attenuation() == [0.0; 3]);
}

/// An orthographic camera is read (xmag, ymag, znear, zfar, placed by its node) with no warning;
/// cameras keep the file's node order whatever their kind; a bad magnification or plane is an
/// error naming the camera.
#[test]
fn orthographic_cameras_are_read() {
    let (mut json, bin) = read_glb(&scenes_dir().join("textured.glb"));
    json["cameras"] = json!([
        {"type": "orthographic", "orthographic": {"xmag": 2.5, "ymag": 1.25, "znear": 0.1, "zfar": 10.0}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.2}},
    ]);
    let first_node = json["nodes"].as_array().unwrap().len();
    json["nodes"].as_array_mut().unwrap().push(json!({"camera": 0, "translation": [1.0, 2.0, 5.0]}));
    json["nodes"].as_array_mut().unwrap().push(json!({"camera": 1}));
    let scene_index = json["scene"].as_u64().unwrap_or(0) as usize;
    for node in [first_node, first_node + 1] {
        json["scenes"][scene_index]["nodes"].as_array_mut().unwrap().push(json!(node));
    }
    let scene = Scene::from_glb_bytes("ortho.glb", &to_glb(&json, &bin)).unwrap();
    assert!(scene.warnings.iter().all(|w| !w.contains("camera")), "{:?}", scene.warnings);
    let cameras: Vec<_> =
        scene.cameras.iter().filter(|c| c.position == [1.0, 2.0, 5.0] || c.yfov == 0.5).collect();
    assert_eq!(cameras.len(), 2, "{:?}", scene.cameras);
    let (ortho, perspective) = (cameras[0], cameras[1]);
    assert_eq!(ortho.orthographic, Some(umbra::scene::Orthographic { xmag: 2.5, ymag: 1.25, zfar: 10.0 }));
    assert_eq!((ortho.znear, ortho.aspect), (0.1, Some(2.0)));
    assert_eq!((ortho.forward, ortho.up), ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]));
    assert_eq!((perspective.orthographic, perspective.znear), (None, 0.2));

    for (orthographic, problem) in [
        (json!({"xmag": 0.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}), "xmag"),
        (json!({"xmag": 1.0, "ymag": 1.0, "znear": 2.0, "zfar": 1.0}), "zfar"),
    ] {
        json["cameras"][0]["orthographic"] = orthographic;
        let message = Scene::from_glb_bytes("ortho.glb", &to_glb(&json, &bin)).unwrap_err().to_string();
        assert!(
            message.contains("ortho.glb") && message.contains("camera 0") && message.contains(problem),
            "{message}"
        );
    }
}

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
    let options = umbra::scene::LoadOptions { missing_textures: umbra::scene::MissingTextures::Warn };
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

/// KHR_materials_dispersion's `dispersion` reaches the material (0 without the extension), with
/// no warning and no longer among the ignored extensions; a negative one is refused naming it.
#[test]
fn dispersion_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |dispersion: Value| {
        let mut json = base.clone();
        json["extensionsUsed"] = json!(["KHR_materials_dispersion", "KHR_materials_volume"]);
        json["materials"][0]["extensions"] = json!({
            "KHR_materials_dispersion": dispersion,
            "KHR_materials_volume": {"thicknessFactor": 0.5},
        });
        Scene::from_glb_bytes("prism.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!(plain.materials[0].dispersion, 0.0);
    let scene = load(json!({"dispersion": 0.33})).unwrap();
    assert_eq!(scene.materials[0].dispersion, 0.33);
    assert!(scene.materials[0].volume);
    assert!(scene.warnings.iter().all(|w| !w.contains("dispersion")), "{:?}", scene.warnings);
    let error = load(json!({"dispersion": -0.5})).unwrap_err().to_string();
    assert!(error.contains("prism.glb") && error.contains("dispersion is -0.5"), "{error}");
}
