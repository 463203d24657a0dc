//! Geometry: node transforms, winding under mirroring, GPU instancing, primitive modes and
//! degenerate triangles.

use crate::committed::instanced_transforms;
use crate::{khronos, load, read_glb, scenes_dir, to_glb};
use glam::{Mat4, Quat, Vec3};
use serde_json::{json, Value};
use umbra::scene::Scene;

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
