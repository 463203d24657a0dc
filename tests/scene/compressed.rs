//! Geometry as asset pipelines ship it: `EXT_meshopt_compression` (every mode and filter) and
//! `KHR_mesh_quantization` (every normalized type on every attribute it allows). Each file is
//! built here twice from one mesh, plain (floats, plain indices) and in the form under test; the
//! loaded scenes must agree to the encoding's own precision. The compressed files are encoded by
//! meshoptimizer's encoder (the `meshopt` crate); what the test trusts is the mesh it started
//! from, not the decoder under test.

use crate::generate;
use serde_json::{json, Value};
use umbra::scene::Scene;

/// A bumpy grid: positions, unit normals, UVs, and triangles (counter-clockwise from +y).
struct Mesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    indices: Vec<u32>,
}

fn bumpy_grid(n: u32) -> Mesh {
    let mut m = Mesh { positions: Vec::new(), normals: Vec::new(), uvs: Vec::new(), indices: Vec::new() };
    let h = |x: f32, z: f32| 0.3 * (2.0 * x).sin() * (1.5 * z).cos();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            let (x, z) = (2.0 * u - 1.0, 2.0 * v - 1.0);
            m.positions.push([x, h(x, z), z]);
            // The surface's normal: (-dh/dx, 1, -dh/dz), normalised.
            let (dx, dz) =
                (0.6 * (2.0 * x).cos() * (1.5 * z).cos(), -0.45 * (2.0 * x).sin() * (1.5 * z).sin());
            let l = (dx * dx + 1.0 + dz * dz).sqrt();
            m.normals.push([-dx / l, 1.0 / l, -dz / l]);
            m.uvs.push([u, v]);
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            m.indices.extend([a, a + n, a + 1, a + 1, a + n, a + n + 1]);
        }
    }
    m
}

/// Builds a GLB from views, accessors and meshes: each view `(bytes, stride, compression)` is
/// plain in buffer 0, or, with `Some((mode, filter, count, element))`, meshopt-compressed in
/// buffer 0 with a data-less fallback buffer 1.
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    fallback: usize,
}

impl Builder {
    fn new() -> Self {
        Self { bin: Vec::new(), views: Vec::new(), accessors: Vec::new(), fallback: 0 }
    }

    fn align(&mut self) {
        self.bin.resize(self.bin.len().next_multiple_of(4), 0);
    }

    /// A plain view of `bytes` (vertex views with their stride; index views without).
    fn plain(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        self.align();
        let mut view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(s) = stride {
            view["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(view);
        self.views.len() - 1
    }

    /// A compressed view: `encoded` decodes to `count` elements of `stride` bytes.
    fn compressed(
        &mut self,
        encoded: &[u8],
        count: usize,
        stride: usize,
        mode: &str,
        filter: &str,
        vertex: bool,
    ) -> usize {
        self.align();
        let length = count * stride;
        let mut view = json!({
            "buffer": 1, "byteOffset": self.fallback, "byteLength": length,
            "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": self.bin.len(), "byteLength": encoded.len(),
                "byteStride": stride, "count": count, "mode": mode, "filter": filter,
            }},
        });
        if vertex {
            view["byteStride"] = json!(stride);
        }
        self.fallback += length.next_multiple_of(4);
        self.bin.extend_from_slice(encoded);
        self.views.push(view);
        self.views.len() - 1
    }

    fn accessor(&mut self, view: usize, component: u32, normalized: bool, count: usize, ty: &str) -> usize {
        let mut a = json!({"bufferView": view, "componentType": component, "count": count, "type": ty});
        if normalized {
            a["normalized"] = json!(true);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    /// The GLB: one mesh of `primitives` placed by node 0 with `instancing` (its attributes), and
    /// `extensions` used and required.
    fn glb(
        mut self,
        primitives: Value,
        instancing: Value,
        extensions: &[&str],
        min_max: ([f32; 3], [f32; 3]),
    ) -> Vec<u8> {
        self.align();
        // POSITION accessors need their bounds.
        for p in primitives.as_array().unwrap() {
            let a = p["attributes"]["POSITION"].as_u64().unwrap() as usize;
            self.accessors[a]["min"] = json!(min_max.0);
            self.accessors[a]["max"] = json!(min_max.1);
        }
        let mut buffers = vec![json!({"byteLength": self.bin.len()})];
        if self.fallback > 0 {
            buffers.push(json!({"byteLength": self.fallback, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}));
        }
        let json = json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": extensions,
            "extensionsRequired": extensions,
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": instancing}}}],
            "meshes": [{"primitives": primitives}],
            "buffers": buffers,
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        generate::glb(&serde_json::to_vec(&json).unwrap(), &self.bin)
    }
}

fn bytes<T: bytemuck::Pod>(data: &[T]) -> Vec<u8> {
    bytemuck::cast_slice(data).to_vec()
}

/// Three instances: translations and rotations (about tilted axes).
fn instances() -> (Vec<[f32; 3]>, Vec<[f32; 4]>) {
    let translations = vec![[0.0, 0.0, 0.0], [3.0, 0.5, 0.0], [-2.0, 1.0, 2.5]];
    let rotations = [(0.3f32, [0.0f32, 1.0, 0.0]), (1.1, [1.0, 1.0, 0.0]), (-2.0, [0.2, 0.5, 1.0])]
        .iter()
        .map(|&(angle, axis)| {
            glam::Quat::from_axis_angle(glam::Vec3::from(axis).normalize(), angle).to_array()
        })
        .collect();
    (translations, rotations)
}

/// Triangles as a sorted list of index triples each rotated to start at its smallest (the index
/// codec may rotate a triangle's vertices, never its winding).
fn triangle_set(scene: &Scene) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = scene
        .triangles
        .iter()
        .map(|&[a, b, c]| match a.min(b).min(c) {
            m if m == a => [a, b, c],
            m if m == b => [b, c, a],
            _ => [c, a, b],
        })
        .collect();
    t.sort();
    t
}

fn bounds(m: &Mesh) -> ([f32; 3], [f32; 3]) {
    m.positions.iter().fold(([f32::MAX; 3], [f32::MIN; 3]), |(lo, hi), p| {
        (std::array::from_fn(|k| lo[k].min(p[k])), std::array::from_fn(|k| hi[k].max(p[k])))
    })
}

/// The plain file: floats, two primitives (the triangles split in two: 16-bit, then 32-bit
/// indices), three float instances.
fn plain_file(m: &Mesh) -> Vec<u8> {
    let mut b = Builder::new();
    let n = m.positions.len();
    let half = m.indices.len() / 6 * 3;
    let p = b.plain(&bytes(&m.positions), Some(12));
    let nn = b.plain(&bytes(&m.normals), Some(12));
    let uv = b.plain(&bytes(&m.uvs), Some(8));
    let short: Vec<u16> = m.indices[..half].iter().map(|&i| i as u16).collect();
    let i16v = b.plain(&bytes(&short), None);
    let i32v = b.plain(&bytes(&m.indices[half..]), None);
    let (translations, rotations) = instances();
    let t = b.plain(&bytes(&translations), None);
    let r = b.plain(&bytes(&rotations), None);
    let attributes = json!({
        "POSITION": b.accessor(p, 5126, false, n, "VEC3"),
        "NORMAL": b.accessor(nn, 5126, false, n, "VEC3"),
        "TEXCOORD_0": b.accessor(uv, 5126, false, n, "VEC2"),
    });
    let primitives = json!([
        {"attributes": attributes, "indices": b.accessor(i16v, 5123, false, half, "SCALAR")},
        {"attributes": attributes, "indices": b.accessor(i32v, 5125, false, m.indices.len() - half, "SCALAR")},
    ]);
    let instancing = json!({"TRANSLATION": b.accessor(t, 5126, false, 3, "VEC3"), "ROTATION": b.accessor(r, 5126, false, 3, "VEC4")});
    b.glb(primitives, instancing, &["EXT_mesh_gpu_instancing"], bounds(m))
}

/// The meshopt file: positions by the exponential filter (floats), normals by the octahedral
/// filter into 8-bit snorm (`KHR_mesh_quantization`), UVs unfiltered, the first primitive's
/// 16-bit indices by TRIANGLES, the second's 32-bit by INDICES, the instances' rotations by the
/// quaternion filter into 16-bit snorm.
fn meshopt_file(m: &Mesh) -> Vec<u8> {
    use meshopt::encoding::*;
    let mut b = Builder::new();
    let n = m.positions.len();
    let half = m.indices.len() / 6 * 3;
    let exp = encode_filter_exp(&m.positions, 23, EncodeExpMode::Separate);
    let p = b.compressed(&encode_vertex_buffer(&exp).unwrap(), n, 12, "ATTRIBUTES", "EXPONENTIAL", true);
    let normals: Vec<[f32; 4]> = m.normals.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
    let oct = encode_filter_oct::<i8>(&normals, 8);
    let nn = b.compressed(&encode_vertex_buffer(&oct).unwrap(), n, 4, "ATTRIBUTES", "OCTAHEDRAL", true);
    let uv = b.compressed(&encode_vertex_buffer(&m.uvs).unwrap(), n, 8, "ATTRIBUTES", "NONE", true);
    let tri = encode_index_buffer(&m.indices[..half], n).unwrap();
    let i16v = b.compressed(&tri, half, 2, "TRIANGLES", "NONE", false);
    let seq = encode_index_sequence(&m.indices[half..], n).unwrap();
    let i32v = b.compressed(&seq, m.indices.len() - half, 4, "INDICES", "NONE", false);
    let (translations, rotations) = instances();
    let t = b.compressed(&encode_vertex_buffer(&translations).unwrap(), 3, 12, "ATTRIBUTES", "NONE", true);
    let quat = encode_filter_quat(&rotations, 16);
    let r = b.compressed(&encode_vertex_buffer(&quat).unwrap(), 3, 8, "ATTRIBUTES", "QUATERNION", true);
    let attributes = json!({
        "POSITION": b.accessor(p, 5126, false, n, "VEC3"),
        "NORMAL": b.accessor(nn, 5120, true, n, "VEC3"),
        "TEXCOORD_0": b.accessor(uv, 5126, false, n, "VEC2"),
    });
    let primitives = json!([
        {"attributes": attributes, "indices": b.accessor(i16v, 5123, false, half, "SCALAR")},
        {"attributes": attributes, "indices": b.accessor(i32v, 5125, false, m.indices.len() - half, "SCALAR")},
    ]);
    let instancing = json!({"TRANSLATION": b.accessor(t, 5126, false, 3, "VEC3"), "ROTATION": b.accessor(r, 5122, true, 3, "VEC4")});
    let extensions = ["EXT_meshopt_compression", "KHR_mesh_quantization", "EXT_mesh_gpu_instancing"];
    b.glb(primitives, instancing, &extensions, bounds(m))
}

/// Largest difference of a component between two vector lists.
fn max_diff<const N: usize>(a: &[[f32; N]], b: &[[f32; N]]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).flat_map(|(p, q)| (0..N).map(move |k| (p[k] - q[k]).abs())).fold(0.0, f32::max)
}

/// A meshopt-compressed file (every mode and filter) loads as the plain one: the same triangles
/// (up to the index codec's rotation of a triangle's vertices), positions to the exponential
/// filter's 23 bits and the 16-bit quaternions' rotation (2e-4 over the scene's few units),
/// normals to the 8-bit octahedral grid (1.5°: its cells' diagonal, stretched at most 2.2× by
/// the map), UVs exactly; with no warning and without the data-less fallback buffer.
#[test]
fn meshopt_compressed_geometry_loads_as_the_plain_file() {
    let mesh = bumpy_grid(17);
    let plain = Scene::from_glb_bytes("plain.glb", &plain_file(&mesh)).unwrap();
    let packed = Scene::from_glb_bytes("packed.glb", &meshopt_file(&mesh)).unwrap();
    // Three instances of every triangle.
    assert_eq!((packed.triangles.len(), plain.triangles.len()), (mesh.indices.len(), mesh.indices.len()));
    assert!(packed.warnings.is_empty(), "{:?}", packed.warnings);
    assert_eq!(triangle_set(&packed), triangle_set(&plain));
    let positions = max_diff(&packed.positions, &plain.positions);
    assert!(positions <= 2e-4, "positions differ by {positions}");
    assert_eq!(packed.uv0, plain.uv0, "UVs are not exact");
    let worst = packed
        .normals
        .iter()
        .zip(&plain.normals)
        .map(|(a, b)| glam::Vec3::from(*a).dot(glam::Vec3::from(*b)).clamp(-1.0, 1.0).acos().to_degrees())
        .fold(0.0f32, f32::max);
    eprintln!("meshopt: positions within {positions:.2e}, normals within {worst:.3}°");
    assert!(worst <= 1.5, "normals differ by {worst}°");
}

/// A compressed view that is wrong is refused naming it: an unknown mode, a filter with a stride
/// it cannot take, data cut short.
#[test]
fn broken_meshopt_views_are_refused_naming_them() {
    let mesh = bumpy_grid(5);
    let (json, bin) = generate::split_glb(&meshopt_file(&mesh));
    let load = |edit: &dyn Fn(&mut Value)| {
        let mut j = json.clone();
        edit(&mut j);
        Scene::from_glb_bytes("broken.glb", &generate::glb(&serde_json::to_vec(&j).unwrap(), &bin))
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let ext = "/extensions/EXT_meshopt_compression";
    let e = load(&|j| *j.pointer_mut(&format!("/bufferViews/0{ext}/mode")).unwrap() = json!("VERTICES"));
    assert!(
        e.contains("broken.glb") && e.contains("buffer view 0") && e.contains("unknown mode 'VERTICES'"),
        "{e}"
    );
    let e = load(&|j| *j.pointer_mut(&format!("/bufferViews/1{ext}/filter")).unwrap() = json!("QUATERNION"));
    assert!(e.contains("buffer view 1") && e.contains("QUATERNION cannot take a byteStride of 4"), "{e}");
    let e = load(&|j| *j.pointer_mut(&format!("/bufferViews/0{ext}/byteLength")).unwrap() = json!(5));
    assert!(e.contains("buffer view 0") && e.contains("does not decode"), "{e}");
}

/// `KHR_mesh_quantization`: every normalized type on every attribute the extension allows, and
/// the plain integer types it allows for positions and UVs, decode to the values the
/// specification's formulas give (signed normalized: max(c / (2^(b-1) - 1), -1); unsigned: c /
/// (2^b - 1)), computed here from the integers written.
#[test]
fn quantized_attributes_decode_by_the_specification() {
    // Two triangles over four vertices; each case writes one attribute in one type.
    let indices: Vec<u16> = vec![0, 1, 2, 0, 2, 3];
    let base_positions: [[f32; 3]; 4] =
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, -1.0], [0.0, 0.0, -1.0]];
    // Component values per vertex, as integers of each type (within every type's range).
    let ints: [[i32; 4]; 4] = [[-128, 5, 127, 1], [0, -64, 33, -1], [100, 7, -127, 1], [-3, 90, 12, 1]];
    let uints: [[i32; 4]; 4] = [[0, 5, 255, 200], [17, 64, 33, 1], [100, 7, 127, 9], [3, 90, 12, 250]];
    // (attribute, componentType, normalized, type, components)
    let cases: &[(&str, u32, bool, &str, usize)] = &[
        ("POSITION", 5120, false, "VEC3", 3),
        ("POSITION", 5120, true, "VEC3", 3),
        ("POSITION", 5121, false, "VEC3", 3),
        ("POSITION", 5121, true, "VEC3", 3),
        ("POSITION", 5122, false, "VEC3", 3),
        ("POSITION", 5122, true, "VEC3", 3),
        ("POSITION", 5123, false, "VEC3", 3),
        ("POSITION", 5123, true, "VEC3", 3),
        ("NORMAL", 5120, true, "VEC3", 3),
        ("NORMAL", 5122, true, "VEC3", 3),
        ("TEXCOORD_0", 5120, false, "VEC2", 2),
        ("TEXCOORD_0", 5120, true, "VEC2", 2),
        ("TEXCOORD_0", 5121, false, "VEC2", 2),
        ("TEXCOORD_0", 5121, true, "VEC2", 2),
        ("TEXCOORD_0", 5122, false, "VEC2", 2),
        ("TEXCOORD_0", 5122, true, "VEC2", 2),
        ("TEXCOORD_0", 5123, false, "VEC2", 2),
        ("TEXCOORD_0", 5123, true, "VEC2", 2),
    ];
    for &(attribute, component, normalized, ty, n) in cases {
        let signed = component == 5120 || component == 5122;
        let bits = if component <= 5121 { 8 } else { 16 };
        let values = if signed { ints } else { uints };
        // 16-bit values: the 8-bit ones scaled, so both ranges are used.
        let scale = if bits == 16 { 200 } else { 1 };
        let raw: Vec<Vec<i32>> = values.iter().map(|v| v[..n].iter().map(|c| c * scale).collect()).collect();
        let expect = |c: i32| -> f32 {
            if !normalized {
                c as f32
            } else if signed {
                (c as f32 / ((1 << (bits - 1)) - 1) as f32).max(-1.0)
            } else {
                c as f32 / ((1 << bits) - 1) as f32
            }
        };
        // Elements padded to 4 bytes, as glTF requires of vertex attributes.
        let size = if bits == 8 { 1 } else { 2 };
        let stride = (n * size).next_multiple_of(4);
        let mut data = Vec::new();
        for v in &raw {
            let start = data.len();
            for &c in v {
                if bits == 8 {
                    data.push(c as u8);
                } else {
                    data.extend_from_slice(&(c as u16).to_le_bytes());
                }
            }
            data.resize(start + stride, 0);
        }
        let mut b = Builder::new();
        let view = b.plain(&data, Some(stride));
        let quantized = b.accessor(view, component, normalized, 4, ty);
        let p = if attribute == "POSITION" {
            quantized
        } else {
            let v = b.plain(&bytes(&base_positions), Some(12));
            b.accessor(v, 5126, false, 4, "VEC3")
        };
        let iv = b.plain(&bytes(&indices), None);
        let mut attributes = json!({"POSITION": p});
        if attribute != "POSITION" {
            attributes[attribute] = json!(quantized);
        }
        let primitives =
            json!([{"attributes": attributes, "indices": b.accessor(iv, 5123, false, 6, "SCALAR")}]);
        // One instance at the origin: the placed values are the decoded ones.
        let t = b.plain(&bytes(&[[0.0f32; 3]]), None);
        let instancing = json!({"TRANSLATION": b.accessor(t, 5126, false, 1, "VEC3")});
        let decoded: Vec<[f32; 3]> =
            raw.iter().map(|v| std::array::from_fn(|k| v.get(k).map_or(0.0, |&c| expect(c)))).collect();
        let lo: [f32; 3] = std::array::from_fn(|k| decoded.iter().map(|d| d[k]).fold(f32::MAX, f32::min));
        let hi: [f32; 3] = std::array::from_fn(|k| decoded.iter().map(|d| d[k]).fold(f32::MIN, f32::max));
        let glb =
            b.glb(primitives, instancing, &["KHR_mesh_quantization", "EXT_mesh_gpu_instancing"], (lo, hi));
        let label = format!("{attribute} as {component}{}", if normalized { " normalized" } else { "" });
        let scene = Scene::from_glb_bytes("quantized.glb", &glb).unwrap_or_else(|e| panic!("{label}: {e}"));
        // Corner by corner (the loader may lay the vertices out anew).
        let corners: Vec<u32> = scene.triangles.iter().flatten().copied().collect();
        assert_eq!(corners.len(), indices.len(), "{label}");
        for (&c, &index) in corners.iter().zip(&indices) {
            let (i, d) = (c as usize, &decoded[index as usize]);
            match attribute {
                "POSITION" => assert_eq!(scene.positions[i], *d, "{label}, vertex {index}"),
                "NORMAL" => {
                    let expected = glam::Vec3::from(*d).normalize();
                    let got = glam::Vec3::from(scene.normals[i]);
                    assert!((got - expected).length() < 1e-6, "{label}, vertex {index}: {got} vs {expected}");
                }
                _ => assert_eq!(scene.uv0[i], [d[0], d[1]], "{label}, vertex {index}"),
            }
        }
    }
}
