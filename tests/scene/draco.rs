//! `KHR_draco_mesh_compression` against files made by Google's own Draco encoder: the files in
//! `tests/scene/draco/` are committed scenes compressed by glTF-Transform 4.5.1's `draco` command
//! (draco3dgltf 1.5.7, Google's encoder built to WebAssembly; its defaults: 14-bit positions,
//! 10-bit normals, 12-bit UVs and other attributes), edgebreaker unless the name says
//! `sequential`. Each must load as the plain scene it was made from, to the quantization's own
//! precision: what the test trusts is the plain file and the bit depths, not the decoder.

use crate::{assert_scene_error, scenes_dir, to_glb};
use glam::{Vec2, Vec3};
use serde_json::json;
use std::collections::HashMap;
use std::path::PathBuf;
use umbra::scene::Scene;

fn fixture(name: &str) -> PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scene/draco").join(name)
}

/// glTF-Transform's default bit depths.
const POSITION_BITS: i32 = 14;
const NORMAL_BITS: i32 = 10;
const TEXCOORD_BITS: i32 = 12;
const GENERIC_BITS: i32 = 12;

/// One grid step of `bits`-bit quantization over `range`.
fn step(range: f32, bits: i32) -> f32 {
    range / ((1 << bits) - 1) as f32
}

/// The largest differences between matched corners, against their bounds.
#[derive(Debug, Default)]
struct Worst {
    position: f32,
    normal: f32,
    uv0: f32,
    uv1: f32,
    tangent: f32,
}

fn extent<const N: usize>(v: &[[f32; N]]) -> f32 {
    (0..N)
        .map(|k| {
            let (lo, hi) = v.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[k]), hi.max(p[k])));
            hi - lo
        })
        .fold(0.0, f32::max)
}

fn angle(a: [f32; 3], b: [f32; 3]) -> f32 {
    Vec3::from(a).normalize().dot(Vec3::from(b).normalize()).clamp(-1.0, 1.0).acos()
}

/// Matches every triangle of `packed` to one of `plain` (the nearest centroid with the same
/// material, each used once) and its corners by the rotation that fits best (Draco may reorder
/// triangles and rotate their corners, never reverse their winding); returns the largest
/// differences of each attribute over all matched corners.
fn compare(plain: &Scene, packed: &Scene) -> Worst {
    assert_eq!(packed.triangles.len(), plain.triangles.len(), "triangle counts");
    assert!(packed.warnings.is_empty(), "{:?}", packed.warnings);
    for (what, a, b) in [
        ("uv0", plain.uv0.is_empty(), packed.uv0.is_empty()),
        ("uv1", plain.uv1.is_empty(), packed.uv1.is_empty()),
        ("tangents", plain.tangents.is_empty(), packed.tangents.is_empty()),
        ("colors", plain.colors.is_empty(), packed.colors.is_empty()),
    ] {
        assert_eq!(a, b, "{what} present in one scene only");
    }
    let centroid =
        |s: &Scene, t: [u32; 3]| t.iter().map(|&i| Vec3::from(s.positions[i as usize])).sum::<Vec3>() / 3.0;
    let cell = extent(&plain.positions) / 256.0;
    let key = |c: Vec3| (c / cell).floor().as_ivec3();
    let mut grid: HashMap<glam::IVec3, Vec<usize>> = HashMap::new();
    for (i, &t) in plain.triangles.iter().enumerate() {
        grid.entry(key(centroid(plain, t))).or_default().push(i);
    }
    let mut used = vec![false; plain.triangles.len()];
    let mut worst = Worst::default();
    for (j, &t) in packed.triangles.iter().enumerate() {
        let c = centroid(packed, t);
        let k = key(c);
        let material = packed.triangle_material[j];
        let candidates = (-1..=1)
            .flat_map(|x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| k + glam::IVec3::new(x, y, z))))
            .filter_map(|cell| grid.get(&cell))
            .flatten()
            .filter(|&&i| !used[i] && plain.triangle_material[i] == material);
        let &i = candidates
            .min_by(|&&a, &&b| {
                let d = |i: usize| centroid(plain, plain.triangles[i]).distance(c);
                d(a).total_cmp(&d(b))
            })
            .unwrap_or_else(|| panic!("triangle {j} ({c}) matches no unused triangle of the plain scene"));
        used[i] = true;
        let p = plain.triangles[i];
        let rotated = |r: usize| [t[r % 3], t[(r + 1) % 3], t[(r + 2) % 3]];
        let error = |q: [u32; 3]| {
            (0..3)
                .map(|v| {
                    Vec3::from(packed.positions[q[v] as usize])
                        .distance(Vec3::from(plain.positions[p[v] as usize]))
                })
                .fold(0.0, f32::max)
        };
        let q = (0..3).map(rotated).min_by(|&a, &b| error(a).total_cmp(&error(b))).unwrap();
        for v in 0..3 {
            let (a, b) = (p[v] as usize, q[v] as usize);
            let chebyshev =
                |x: &[f32], y: &[f32]| x.iter().zip(y).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max);
            worst.position = worst.position.max(chebyshev(&plain.positions[a], &packed.positions[b]));
            worst.normal = worst.normal.max(angle(plain.normals[a], packed.normals[b]));
            if !plain.uv0.is_empty() {
                worst.uv0 = worst.uv0.max(Vec2::from(plain.uv0[a]).distance(Vec2::from(packed.uv0[b])));
            }
            if !plain.uv1.is_empty() {
                worst.uv1 = worst.uv1.max(Vec2::from(plain.uv1[a]).distance(Vec2::from(packed.uv1[b])));
            }
            if !plain.tangents.is_empty() {
                let (x, y) = (plain.tangents[a], packed.tangents[b]);
                assert_eq!(x[3], y[3], "a tangent's bitangent sign differs");
                worst.tangent = worst.tangent.max(angle([x[0], x[1], x[2]], [y[0], y[1], y[2]]));
            }
        }
    }
    worst
}

/// Each Draco file loads as the plain scene it was made from, with no warning: the same
/// triangles with the same materials, every corner within the quantization's bounds. Draco
/// rounds to the nearest of 2^b - 1 steps over a primitive's largest extent, so a position is
/// within half a step of the scene-wide extent's grid per axis and a UV within half a step of its
/// diagonal (the bound used is one step, twice that); a normal on the 10-bit octahedral grid is
/// within a cell's half-diagonal stretched at most 2× by the map (2 steps of 2/(2^10 - 1)
/// radians); a tangent's components are 12-bit over [-1, 1] (√3 half-steps, bound 2 steps).
#[test]
fn draco_files_load_as_the_plain_scenes_they_were_made_from() {
    let cases = [
        ("glass-draco.glb", scenes_dir().join("glass.glb")),
        ("textured-draco-sequential.glb", scenes_dir().join("textured.glb")),
        ("multiuv-draco.glb", crate::khronos("MultiUVTest")),
        ("instanced-draco.glb", scenes_dir().join("instanced.glb")),
    ];
    for (name, source) in cases {
        let plain = crate::load(&source);
        let packed = crate::load(&fixture(name));
        let worst = compare(&plain, &packed);
        let bound_position = step(extent(&plain.positions), POSITION_BITS);
        let bound_normal = 2.0 * step(2.0, NORMAL_BITS);
        let bound_uv = |uv: &[[f32; 2]]| step(extent(uv), TEXCOORD_BITS) * std::f32::consts::SQRT_2;
        let bound_tangent = 2.0 * step(2.0, GENERIC_BITS);
        eprintln!("{name}: {worst:?}");
        assert!(worst.position <= bound_position, "{name}: positions {} > {bound_position}", worst.position);
        assert!(worst.normal <= bound_normal, "{name}: normals {} rad > {bound_normal}", worst.normal);
        assert!(worst.uv0 <= bound_uv(&plain.uv0), "{name}: uv0 {} > {}", worst.uv0, bound_uv(&plain.uv0));
        assert!(worst.uv1 <= bound_uv(&plain.uv1), "{name}: uv1 {} > {}", worst.uv1, bound_uv(&plain.uv1));
        assert!(worst.tangent <= bound_tangent, "{name}: tangents {} rad > {bound_tangent}", worst.tangent);
        assert_eq!(packed.materials.len(), plain.materials.len(), "{name}: materials");
        assert_eq!(packed.instances.len(), plain.instances.len(), "{name}: instances");
    }
}

/// A compressed primitive that is wrong is refused naming it: an attribute id the stream lacks,
/// a view that is not in the file, a stream cut short or with its bytes flipped (never a panic).
#[test]
fn broken_draco_primitives_are_refused_naming_them() {
    let (json, bin) = crate::read_glb(&fixture("textured-draco-sequential.glb"));
    let ext = "/meshes/0/primitives/0/extensions/KHR_draco_mesh_compression";
    let view = json.pointer(&format!("{ext}/bufferView")).unwrap().as_u64().unwrap();
    let load = |edit: &dyn Fn(&mut serde_json::Value, &mut Vec<u8>)| {
        let (mut j, mut b) = (json.clone(), bin.clone());
        edit(&mut j, &mut b);
        Scene::from_glb_bytes("broken.glb", &to_glb(&j, &b))
    };
    let label = "mesh 0 primitive 0: KHR_draco_mesh_compression";
    assert_scene_error(
        load(&|j, _| *j.pointer_mut(&format!("{ext}/attributes/POSITION")).unwrap() = json!(9)),
        "broken.glb",
        &format!("{label}: POSITION's Draco id 9 is not in the stream"),
    );
    assert_scene_error(
        load(&|j, _| *j.pointer_mut(&format!("{ext}/bufferView")).unwrap() = json!(99)),
        "broken.glb",
        &format!("{label}: bufferView 99 is not in the file"),
    );
    assert_scene_error(
        load(&|j, _| *j.pointer_mut(&format!("/bufferViews/{view}/byteLength")).unwrap() = json!(20)),
        "broken.glb",
        &format!("{label}: the Draco data does not decode"),
    );
    // Flipped bytes anywhere in the stream: an error or a (wrong) scene, never a panic or a hang.
    let view_json = json.pointer(&format!("/bufferViews/{view}")).unwrap().clone();
    let start = view_json["byteOffset"].as_u64().unwrap_or(0) as usize;
    let length = view_json["byteLength"].as_u64().unwrap() as usize;
    crate::flip_bits(start, length, 0x2545_f491, 400, |at, bit| {
        let _ = load(&|_, b| b[at] ^= bit);
    });
}
