//! glTF morph targets and skins in the one static pose umbra renders: morph targets at their
//! default weights (the mesh's `weights`, overridden by the node's), skins at the pose their
//! joints' default node transforms give (Σ weight · jointWorld · inverseBind; normals by the
//! inverse transpose; the skinned node's own transform ignored), one warning saying so, and
//! clear errors for malformed skins. The files are generated here, in memory.

mod common;

use common::{camera, Gpu};
use glam::{Mat4, Quat, Vec3};
use serde_json::{json, Value};
use umbra::gpu::scene::GpuScene;
use umbra::render::{hybrid, HybridSettings};
use umbra::scene::Scene;
use umbra::Error;

/// A glTF document with one buffer, written as a `data:` URI.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    fn new() -> Self {
        Self {
            json: json!({ "asset": { "version": "2.0" }, "accessors": [], "bufferViews": [] }),
            bin: Vec::new(),
        }
    }

    /// Appends `bytes` as a buffer view (4-byte aligned); returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        self.bin.resize(self.bin.len().div_ceil(4) * 4, 0);
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() }));
        self.bin.extend_from_slice(bytes);
        views.len() - 1
    }

    /// An accessor of `count` elements of `kind` over `bytes`; `extra` fields merged in.
    fn accessor(&mut self, bytes: &[u8], component: u32, count: usize, kind: &str, extra: Value) -> usize {
        let view = self.view(bytes);
        let mut accessor =
            json!({ "bufferView": view, "componentType": component, "count": count, "type": kind });
        for (k, v) in extra.as_object().unwrap() {
            accessor[k] = v.clone();
        }
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        accessors.push(accessor);
        accessors.len() - 1
    }

    fn floats<const N: usize>(&mut self, data: &[[f32; N]], extra: Value) -> usize {
        let bytes: Vec<u8> = data.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
        let kind = match N {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            4 => "VEC4",
            16 => "MAT4",
            _ => unreachable!(),
        };
        self.accessor(&bytes, 5126, data.len(), kind, extra)
    }

    /// Positions (with their bounds), normals and indices of a quad of corners `corners`.
    fn quad(&mut self, corners: &[[f32; 3]; 4], normal: [f32; 3]) -> Value {
        let lo = [0, 1, 2].map(|c| corners.iter().map(|p| p[c]).fold(f32::INFINITY, f32::min));
        let hi = [0, 1, 2].map(|c| corners.iter().map(|p| p[c]).fold(f32::NEG_INFINITY, f32::max));
        let position = self.floats(corners, json!({ "min": lo, "max": hi }));
        let normal = self.floats(&[normal; 4], json!({}));
        let indices: Vec<u8> = [0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = self.accessor(&indices, 5123, 6, "SCALAR", json!({}));
        json!({ "attributes": { "POSITION": position, "NORMAL": normal }, "indices": indices })
    }

    fn finish(mut self) -> Vec<u8> {
        let uri = format!("data:application/octet-stream;base64,{}", common::base64(&self.bin));
        self.json["buffers"] = json!([{ "byteLength": self.bin.len(), "uri": uri }]);
        serde_json::to_vec(&self.json).unwrap()
    }
}

const CORNERS: [[f32; 3]; 4] = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]];

/// A 2 m quad at z = 0 facing +Z with two morph targets: target 0 moves every vertex by +1 in z
/// and tilts the normals by (0.6, 0, −0.2); target 1 (a sparse accessor, no buffer view) moves
/// vertex 2 by (0.5, 0.5, 0). The mesh's weights are [0.5, 0]; node 0 places the mesh with
/// them, node 1 (translated by 10 in x) with its own weights [0, 1]. `scene_nodes` are the nodes
/// of the scene.
fn morph_file(scene_nodes: &[usize]) -> Vec<u8> {
    let mut doc = Doc::new();
    let mut primitive = doc.quad(&CORNERS, [0.0, 0.0, 1.0]);
    let dz = doc.floats(&[[0.0, 0.0, 1.0]; 4], json!({ "min": [0.0, 0.0, 1.0], "max": [0.0, 0.0, 1.0] }));
    let dn = doc.floats(&[[0.6, 0.0, -0.2]; 4], json!({}));
    let sparse_indices = doc.view(&2u16.to_le_bytes());
    let sparse_values =
        doc.view(&[0.5f32, 0.5, 0.0].iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<_>>());
    let accessors = doc.json["accessors"].as_array_mut().unwrap();
    accessors.push(json!({ "componentType": 5126, "count": 4, "type": "VEC3",
        "min": [0.0, 0.0, 0.0], "max": [0.5, 0.5, 0.0],
        "sparse": { "count": 1, "indices": { "bufferView": sparse_indices, "componentType": 5123 },
            "values": { "bufferView": sparse_values } } }));
    let moved = accessors.len() - 1;
    primitive["targets"] = json!([{ "POSITION": dz, "NORMAL": dn }, { "POSITION": moved }]);
    doc.json["meshes"] = json!([{ "name": "morphed", "primitives": [primitive], "weights": [0.5, 0.0] }]);
    doc.json["nodes"] =
        json!([{ "mesh": 0 }, { "mesh": 0, "weights": [0.0, 1.0], "translation": [10.0, 0.0, 0.0] }]);
    doc.json["scenes"] = json!([{ "nodes": scene_nodes }]);
    doc.json["scene"] = json!(0);
    doc.finish()
}

fn close(a: [f32; 3], b: Vec3) -> bool {
    (Vec3::from(a) - b).abs().max_element() < 1e-5
}

/// Morph targets at the mesh's default weight 0.5 move the quad by 0.5 in z and tilt its normals
/// by half the target's displacement; a node's own weights override the mesh's (target 1 alone:
/// the sparse displacement of vertex 2), and the same mesh placed with other weights is read
/// again, not shared. Fails if the weights are ignored, applied in full, or taken from the wrong
/// place.
#[test]
fn morph_targets_take_their_default_weights() {
    let scene = Scene::from_glb_bytes("morph.gltf", &morph_file(&[0, 1])).unwrap();
    assert_eq!(scene.positions.len(), 8);
    for (i, c) in CORNERS.iter().enumerate() {
        let expected = Vec3::from(*c) + Vec3::new(0.0, 0.0, 0.5);
        assert!(
            close(scene.positions[i], expected),
            "node 0 vertex {i}: {:?}, expected {expected}",
            scene.positions[i]
        );
        let normal = (Vec3::Z + 0.5 * Vec3::new(0.6, 0.0, -0.2)).normalize();
        assert!(
            close(scene.normals[i], normal),
            "node 0 normal {i}: {:?}, expected {normal}",
            scene.normals[i]
        );
        let moved = if i == 2 { Vec3::new(0.5, 0.5, 0.0) } else { Vec3::ZERO };
        let expected = Vec3::from(*c) + moved + Vec3::new(10.0, 0.0, 0.0);
        assert!(
            close(scene.positions[4 + i], expected),
            "node 1 vertex {i}: {:?}, expected {expected}",
            scene.positions[4 + i]
        );
        assert!(close(scene.normals[4 + i], Vec3::Z));
    }
    assert!(
        scene.warnings.iter().any(|w| w.contains("has morph targets (1 mesh)") && w.contains("static pose")),
        "{:?}",
        scene.warnings
    );
}

/// The morphed quad as rendered: the G-buffer's view depth from a camera 3 m away on +Z is
/// 2.5 m (the quad moved 0.5 towards it), not 3 m.
#[test]
fn morphed_quads_render_where_the_weights_put_them() {
    let gpu = Gpu::new();
    let scene = Scene::from_glb_bytes("morph.gltf", &morph_file(&[0])).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let size = (16, 16);
    let h = hybrid(
        &gpu,
        &gpu_scene,
        &camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO),
        &HybridSettings { size, ..Default::default() },
    )
    .unwrap();
    let centre = (size.1 / 2 * size.0 + size.0 / 2) as usize;
    let depth = h.gbuffer.depth[centre];
    assert!((depth - 2.5).abs() < 1e-4, "view depth {depth} at the centre, expected 2.5");
}

/// A `JOINTS_0` accessor of unsigned shorts (VEC4), one entry per vertex.
fn joints_accessor(doc: &mut Doc, joints: &[[u16; 4]]) -> usize {
    let bytes: Vec<u8> = joints.iter().flatten().flat_map(|j| j.to_le_bytes()).collect();
    doc.accessor(&bytes, 5123, 4, "VEC4", json!({}))
}

/// A skinned quad: vertices 0 and 1 bound to joint 0, vertex 2 to joint 1, vertex 3 half to
/// each; normals (1, 0, 1)/√2. Joint 0 (node 1) is the root, joint 1 (node 2) its child, bound
/// at (0, 1, 0) (inverse bind matrices: identity, translation (0, −1, 0)). At rest (the nodes'
/// default transforms), joint 0 is at (2, 0, 0) scaled (2, 1, 1) and joint 1 at (0, 1, 0) in its
/// parent, turned 90° about z. The skinned node 0 is translated by (100, 0, 0), which glTF says to
/// ignore; an animation of joint 1 exists and is not played. `edit` changes the document before
/// it is written.
fn skin_file(edit: impl FnOnce(&mut Doc)) -> Vec<u8> {
    let mut doc = Doc::new();
    let mut primitive =
        doc.quad(&CORNERS, [std::f32::consts::FRAC_1_SQRT_2, 0.0, std::f32::consts::FRAC_1_SQRT_2]);
    let joints = joints_accessor(&mut doc, &[[0, 0, 0, 0], [0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]]);
    let weights = doc.floats(
        &[[1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0]],
        json!({}),
    );
    primitive["attributes"]["JOINTS_0"] = json!(joints);
    primitive["attributes"]["WEIGHTS_0"] = json!(weights);
    let inverse_bind = doc.floats(
        &[Mat4::IDENTITY.to_cols_array(), Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0)).to_cols_array()],
        json!({}),
    );
    let times = doc.floats(&[[0.0], [1.0]], json!({ "min": [0.0], "max": [1.0] }));
    let turns = doc.floats(&[[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 0.0]], json!({}));
    doc.json["meshes"] = json!([{ "name": "skinned", "primitives": [primitive] }]);
    doc.json["skins"] = json!([{ "joints": [1, 2], "inverseBindMatrices": inverse_bind }]);
    let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    doc.json["nodes"] = json!([
        { "name": "skinned", "mesh": 0, "skin": 0, "translation": [100.0, 0.0, 0.0] },
        { "name": "root joint", "translation": [2.0, 0.0, 0.0], "scale": [2.0, 1.0, 1.0], "children": [2] },
        { "name": "child joint", "translation": [0.0, 1.0, 0.0], "rotation": quarter.to_array() }
    ]);
    doc.json["animations"] = json!([{ "channels": [{ "sampler": 0, "target": { "node": 2, "path": "rotation" } }],
        "samplers": [{ "input": times, "output": turns }] }]);
    doc.json["scenes"] = json!([{ "nodes": [0, 1] }]);
    doc.json["scene"] = json!(0);
    edit(&mut doc);
    doc.finish()
}

/// The skinned quad lands where the closed form puts it: joint 0's matrix is
/// T(2, 0, 0)·S(2, 1, 1), joint 1's T(2, 0, 0)·S(2, 1, 1)·T(0, 1, 0)·Rz(90°)·T(0, −1, 0), so
/// (−1, −1, 0) → (0, −1, 0), (1, −1, 0) → (4, −1, 0), (1, 1, 0) → (2, 2, 0) and the
/// half-and-half vertex (−1, 1, 0) at the mean of its two images (0, 1, 0) and (2, 0, 0); the
/// node's own translation by 100 is ignored. Normals go through the inverse transpose: (1, 0, 1) under S(2, 1, 1) becomes
/// (½, 0, 1), not (2, 0, 1). One warning names the animation and the skin. Fails if the node's
/// transform is applied, the inverse bind matrices or weights are left out, or normals are
/// transformed by the matrix itself.
#[test]
fn skins_take_the_pose_of_their_joints_default_transforms() {
    let scene = Scene::from_glb_bytes("skin.gltf", &skin_file(|_| {})).unwrap();
    // Closed forms, by hand: joint 0 maps (x, y, z) to (2x + 2, y, z). Joint 1 maps p to
    // joint0(T(0,1,0)·Rz90·(p − (0,1,0))): (1, 1, 0) → Rz90 (1, 0, 0) = (0, 1, 0) → (0, 2, 0)
    // → (2, 2, 0); (−1, 1, 0) → Rz90 (−1, 0, 0) = (0, −1, 0) → (0, 0, 0) → (2, 0, 0).
    let expected = [
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(4.0, -1.0, 0.0),
        Vec3::new(2.0, 2.0, 0.0),
        0.5 * (Vec3::new(0.0, 1.0, 0.0) + Vec3::new(2.0, 0.0, 0.0)),
    ];
    for (i, e) in expected.iter().enumerate() {
        assert!(close(scene.positions[i], *e), "vertex {i}: {:?}, expected {e}", scene.positions[i]);
    }
    // Joint 0's linear part is S(2, 1, 1): the normal (1, 0, 1) becomes (½, 0, 1) normalised.
    let n0 = Vec3::new(0.5, 0.0, 1.0).normalize();
    assert!(close(scene.normals[0], n0), "normal {:?}, expected {n0}", scene.normals[0]);
    // Joint 1's linear part is S(2, 1, 1)·Rz90: (1, 0, 1) → Rz90 (0, 1, 1) → inverse transpose
    // of the scale (0, 1, 1).
    let n2 = Vec3::new(0.0, 1.0, 1.0).normalize();
    assert!(close(scene.normals[2], n2), "normal {:?}, expected {n2}", scene.normals[2]);
    let warning = scene.warnings.iter().find(|w| w.contains("static pose")).expect("a static-pose warning");
    assert!(
        warning.starts_with("skin.gltf: ")
            && warning.contains("is animated (1 animation)")
            && warning.contains("is skinned (1 skinned node)"),
        "{warning}"
    );
    assert_eq!(
        scene.instances[0].transform,
        Mat4::IDENTITY.to_cols_array_2d(),
        "the skinned node's transform is not applied"
    );
}

/// Asserts `result` is an `Error::Scene` naming the file and saying `phrase`.
#[track_caller]
fn assert_error(result: umbra::Result<Scene>, phrase: &str) {
    match result {
        Err(error @ Error::Scene { .. }) => {
            let text = error.to_string();
            assert!(
                text.contains("bad-skin.gltf") && text.contains(phrase),
                "'{text}' should say '{phrase}'"
            );
        }
        other => panic!("expected an error saying '{phrase}', got {other:?}"),
    }
}

/// Malformed skins are clear errors naming the file, the primitive and the problem: a joint
/// index beyond the skin's joints, joints stored as floats, weights as VEC3, too few inverse
/// bind matrices, a skinned primitive without WEIGHTS_0; morph weights that do not match the
/// targets too.
#[test]
fn malformed_skins_and_morphs_are_clear_errors() {
    let load = |edit: fn(&mut Doc)| Scene::from_glb_bytes("bad-skin.gltf", &skin_file(edit));
    assert_error(
        load(|doc| {
            let bad = joints_accessor(doc, &[[0, 0, 0, 0], [5, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]]);
            doc.json["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(bad);
        }),
        "mesh 0 ('skinned') primitive 0 (skinned by node 0 ('skinned')): JOINTS_0 of vertex 1 refers to joint 5, but the skin has 2 joints",
    );
    assert_error(
        load(|doc| {
            let floats = doc.floats(&[[0.0f32; 4]; 4], json!({}));
            doc.json["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(floats);
        }),
        "(JOINTS_0 of mesh 0 ('skinned') primitive 0) has component type F32; joint indices must be unsigned bytes or shorts",
    );
    assert_error(
        load(|doc| {
            let vec3 = doc.floats(&[[1.0f32, 0.0, 0.0]; 4], json!({}));
            doc.json["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = json!(vec3);
        }),
        "(WEIGHTS_0 of mesh 0 ('skinned') primitive 0) has type Vec3 of F32; joint weights must be VEC4",
    );
    assert_error(
        load(|doc| {
            let one = doc.floats(&[Mat4::IDENTITY.to_cols_array()], json!({}));
            doc.json["skins"][0]["inverseBindMatrices"] = json!(one);
        }),
        "skin 0 of node 0 ('skinned'): inverseBindMatrices (accessor",
    );
    assert_error(
        load(|doc| {
            doc.json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("WEIGHTS_0");
        }),
        "mesh 0 ('skinned') primitive 0 is skinned (its node has a skin) but has no WEIGHTS_0 attribute",
    );
    let mut morph: Value = serde_json::from_slice(&morph_file(&[0])).unwrap();
    morph["meshes"][0]["weights"] = json!([0.5, 0.0, 0.25]);
    assert_error(
        Scene::from_glb_bytes("bad-skin.gltf", &serde_json::to_vec(&morph).unwrap()),
        "mesh 0 ('morphed') primitive 0 has 2 morph targets but 3 weights",
    );
}
