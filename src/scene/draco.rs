//! `KHR_draco_mesh_compression`: primitives compressed by Google's Draco (gltf-pipeline,
//! glTF-Transform, three.js and Cesium exporters), decoded at load by `draco-oxide-decoder` (pure
//! Rust) into a buffer of their own; the primitive's accessors are then pointed at the decoded
//! bytes, so everything after reads them as plain accessors.
//!
//! A compressed primitive names a `bufferView` holding one Draco mesh and maps each attribute
//! semantic to a Draco attribute id. Its accessors keep their `count`, `componentType`, `type` and
//! `normalized`, which describe the data *after* decompression; their own `bufferView`, when
//! present, is the uncompressed fallback for readers without the extension, which umbra replaces.
//! The primitive's `indices` accessor receives the Draco mesh's faces.

use super::source::Origin;
use crate::error::Result;
use draco_oxide_core::attribute::{Attribute, ComponentDataType};
use draco_oxide_core::types::PointIdx;
use gltf::json;
use gltf::json::accessor::{ComponentType, GenericComponentType};
use gltf::json::validation::Checked;
use std::borrow::Cow;
use std::collections::HashMap;

pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

fn extension(primitive: &json::mesh::Primitive) -> Option<&json::Value> {
    primitive.extensions.as_ref().and_then(|e| e.others.get(EXTENSION))
}

/// Whether any primitive of `root` is Draco-compressed.
pub(super) fn any(root: &json::Root) -> bool {
    root.meshes.iter().flat_map(|m| &m.primitives).any(|p| extension(p).is_some())
}

/// One compressed primitive's parameters: its Draco view and its (semantic, accessor, Draco
/// attribute id) triples; the indices accessor.
struct Compressed {
    view: usize,
    attributes: Vec<(String, usize, u64)>,
    indices: usize,
}

fn parse(origin: &Origin, label: &str, primitive: &json::mesh::Primitive) -> Result<Option<Compressed>> {
    let Some(value) = extension(primitive) else { return Ok(None) };
    let view = value.get("bufferView").and_then(json::Value::as_u64).ok_or_else(|| {
        origin.error(format!("{label}: bufferView is missing or not a non-negative integer"))
    })?;
    let ids = value
        .get("attributes")
        .and_then(json::Value::as_object)
        .ok_or_else(|| origin.error(format!("{label}: attributes is missing or not an object")))?;
    let mut attributes = Vec::with_capacity(ids.len());
    for (semantic, id) in ids {
        let id = id.as_u64().ok_or_else(|| {
            origin.error(format!(
                "{label}: the Draco id of {semantic} must be a non-negative integer, not {id}"
            ))
        })?;
        let accessor = primitive
            .attributes
            .iter()
            .find(|(s, _)| matches!(s, Checked::Valid(s) if s.to_string() == *semantic))
            .map(|(_, a)| a.value())
            .ok_or_else(|| {
                origin.error(format!(
                    "{label}: {semantic} is compressed but the primitive has no such attribute"
                ))
            })?;
        attributes.push((semantic.clone(), accessor, id));
    }
    if primitive.mode != Checked::Valid(json::mesh::Mode::Triangles) {
        return Err(origin.error(format!("{label}: Draco primitives must be TRIANGLES")));
    }
    let indices = primitive
        .indices
        .map(|i| i.value())
        .ok_or_else(|| origin.error(format!("{label}: a Draco primitive must have indices")))?;
    Ok(Some(Compressed { view: view as usize, attributes, indices }))
}

/// Decodes every compressed primitive of `root` from `buffers` into one new buffer, appended to
/// `root` (its data returned), with a view per decoded accessor, and points each accessor at it,
/// its count the decoded one.
/// A primitive whose stream, ids or accessors are wrong is refused naming it.
pub(super) fn decode(origin: &Origin, root: &mut json::Root, buffers: &[Cow<[u8]>]) -> Result<Vec<u8>> {
    let mut out: Vec<u8> = Vec::new();
    let new_buffer = json::Index::new(root.buffers.len() as u32);
    // Each accessor decoded once: by (Draco view, attribute id), `u64::MAX` for indices.
    let mut decoded: HashMap<usize, (usize, u64)> = HashMap::new();
    let mut decoder = draco_oxide_decoder::Decoder::new();
    for m in 0..root.meshes.len() {
        for p in 0..root.meshes[m].primitives.len() {
            let label = format!("mesh {m} primitive {p}: {EXTENSION}");
            let Some(c) = parse(origin, &label, &root.meshes[m].primitives[p])? else { continue };
            let view = root
                .buffer_views
                .get(c.view)
                .ok_or_else(|| origin.error(format!("{label}: bufferView {} is not in the file", c.view)))?;
            let (buffer, offset) = (view.buffer.value(), view.byte_offset.map_or(0, |o| o.0 as usize));
            let stream = buffers
                .get(buffer)
                .and_then(|b| b.get(offset..offset.checked_add(view.byte_length.0 as usize)?))
                .ok_or_else(|| {
                    origin.error(format!("{label}: bufferView {} lies outside its buffer's data", c.view))
                })?;
            let mesh = decode_stream(&mut decoder, stream)
                .map_err(|e| origin.error(format!("{label}: the Draco data does not decode: {e}")))?;
            let mut outputs = Vec::with_capacity(c.attributes.len() + 1);
            let mut points = None;
            for (semantic, accessor, id) in &c.attributes {
                let attribute =
                    mesh.get_attributes().iter().find(|a| a.get_id().as_usize() as u64 == *id).ok_or_else(
                        || origin.error(format!("{label}: {semantic}'s Draco id {id} is not in the stream")),
                    )?;
                let target = accessor_of(origin, root, &label, *accessor)?;
                let element = target.component.size() * target.components;
                let bytes = convert(attribute, target)
                    .map_err(|e| origin.error(format!("{label}: {semantic} (accessor {accessor}): {e}")))?;
                points = Some(attribute.len());
                // Vertex attributes' elements start 4-byte aligned (the glTF rule for strides).
                let (bytes, stride) = match element.is_multiple_of(4) {
                    true => (bytes, None),
                    false => {
                        let stride = element.next_multiple_of(4);
                        (bytes.chunks(element).flat_map(|e| pad(e, stride)).collect(), Some(stride))
                    }
                };
                outputs.push((*accessor, (c.view, *id), bytes, attribute.len(), stride));
            }
            let points =
                points.ok_or_else(|| origin.error(format!("{label}: no attribute is compressed")))?;
            let target = accessor_of(origin, root, &label, c.indices)?;
            let bytes = indices(mesh.get_faces(), points, target)
                .map_err(|e| origin.error(format!("{label}: indices (accessor {}): {e}", c.indices)))?;
            outputs.push((c.indices, (c.view, u64::MAX), bytes, mesh.get_faces().len() * 3, None));

            for (accessor, source, bytes, count, stride) in outputs {
                match decoded.insert(accessor, source) {
                    Some(previous) if previous == source => continue,
                    Some(_) => {
                        return Err(origin.error(format!(
                            "{label}: accessor {accessor} is also decoded from another Draco stream"
                        )))
                    }
                    None => {}
                }
                out.resize(out.len().next_multiple_of(4), 0);
                let at = out.len();
                out.extend_from_slice(&bytes);
                root.buffer_views.push(json::buffer::View {
                    buffer: new_buffer,
                    byte_length: (bytes.len() as u64).into(),
                    byte_offset: Some((at as u64).into()),
                    byte_stride: stride.map(json::buffer::Stride),
                    name: Some(format!("{EXTENSION} decoded, accessor {accessor}")),
                    target: None,
                    extensions: None,
                    extras: Default::default(),
                });
                let a = &mut root.accessors[accessor];
                a.buffer_view = Some(json::Index::new(root.buffer_views.len() as u32 - 1));
                a.byte_offset = None;
                a.sparse = None;
                // The stream's count stands: Draco's edgebreaker may split vertices, and decoders
                // differ in how many points they make of a seam (Google's, draco-oxide's).
                a.count = (count as u64).into();
            }
        }
    }
    super::meshopt::push_decoded_buffer(root, EXTENSION, out.len());
    Ok(out)
}

/// One Draco mesh. draco-oxide's decoder is an alpha that can panic on a corrupt stream (an
/// arithmetic or range assertion deep in its prediction schemes); the panic is caught here and
/// reported as the stream's error, so a bad file never takes a host's process down.
fn decode_stream(
    decoder: &mut draco_oxide_decoder::Decoder,
    stream: &[u8],
) -> std::result::Result<draco_oxide_core::mesh::Mesh, String> {
    let decoder = std::panic::AssertUnwindSafe(decoder);
    match std::panic::catch_unwind(move || { decoder }.0.decode_mesh(stream)) {
        Ok(Ok(mesh)) => Ok(mesh),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!(
            "the decoder stopped on it ({})",
            panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".into())
        )),
    }
}

fn pad(element: &[u8], stride: usize) -> impl Iterator<Item = u8> + '_ {
    element.iter().copied().chain(std::iter::repeat_n(0, stride - element.len()))
}

/// The accessor a compressed primitive names, with its count, component type and dimensions.
fn accessor_of<'r>(origin: &Origin, root: &'r json::Root, label: &str, index: usize) -> Result<Target<'r>> {
    let accessor = root
        .accessors
        .get(index)
        .ok_or_else(|| origin.error(format!("{label}: accessor {index} is not in the file")))?;
    let (Checked::Valid(GenericComponentType(component)), Checked::Valid(kind)) =
        (accessor.component_type, accessor.type_)
    else {
        return Err(origin.error(format!("{label}: accessor {index} has an invalid type")));
    };
    Ok(Target { accessor, component, components: kind.multiplicity() })
}

struct Target<'r> {
    accessor: &'r json::Accessor,
    component: ComponentType,
    components: usize,
}

/// One decoded attribute as `target`'s elements: point by point, each component converted from
/// the Draco stream's type (floats after dequantization, or integers) to the accessor's.
fn convert(attribute: &Attribute, target: Target) -> std::result::Result<Vec<u8>, String> {
    let points = attribute.len();
    let n = attribute.get_num_components();
    if n != target.components {
        return Err(format!(
            "the stream's values have {n} components but the accessor's type {:?} has {}",
            target.accessor.type_, target.components
        ));
    }
    let source = attribute.get_component_type();
    let size = source.size();
    let data = attribute.get_data_as_bytes();
    let read: fn(&[u8]) -> f64 = match source {
        ComponentDataType::F32 => |b| f32::from_le_bytes(b.try_into().unwrap()) as f64,
        ComponentDataType::U8 => |b| b[0] as f64,
        ComponentDataType::I8 => |b| b[0] as i8 as f64,
        ComponentDataType::U16 => |b| u16::from_le_bytes(b.try_into().unwrap()) as f64,
        ComponentDataType::I16 => |b| i16::from_le_bytes(b.try_into().unwrap()) as f64,
        ComponentDataType::U32 => |b| u32::from_le_bytes(b.try_into().unwrap()) as f64,
        ComponentDataType::I32 => |b| i32::from_le_bytes(b.try_into().unwrap()) as f64,
        other => return Err(format!("the stream's component type {other:?} is not one glTF has")),
    };
    let float = source == ComponentDataType::F32;
    let normalized = target.accessor.normalized;
    if float && target.component != ComponentType::F32 && !normalized {
        return Err(format!(
            "float values cannot fill a {:?} accessor that is not normalized",
            target.component
        ));
    }
    let mut out = Vec::with_capacity(points * n * target.component.size());
    for point in 0..points {
        let value = usize::from(attribute.get_unique_val_idx(PointIdx::from(point)));
        let at = value * n * size;
        let element =
            data.get(at..at + n * size).ok_or("a point's value lies outside the stream's values")?;
        for component in element.chunks_exact(size) {
            let mut v = read(component);
            if float && normalized {
                // The specification's inverse of its normalized-integer decoding.
                let max = match target.component {
                    ComponentType::I8 => 127.0,
                    ComponentType::U8 => 255.0,
                    ComponentType::I16 => 32767.0,
                    ComponentType::U16 => 65535.0,
                    _ => 1.0,
                };
                v = (v.clamp(-1.0, 1.0) * max).round();
            }
            write(&mut out, target.component, v)?;
        }
    }
    Ok(out)
}

/// The faces as `target`'s indices.
fn indices(faces: &[[PointIdx; 3]], points: usize, target: Target) -> std::result::Result<Vec<u8>, String> {
    let count = faces.len() * 3;
    if target.components != 1 || target.component == ComponentType::F32 {
        return Err("indices must be SCALAR unsigned integers".into());
    }
    let mut out = Vec::with_capacity(count * target.component.size());
    for &index in faces.iter().flatten() {
        let index = usize::from(index);
        if index >= points {
            return Err(format!("a face names point {index} of {points}"));
        }
        write(&mut out, target.component, index as f64)?;
    }
    Ok(out)
}

/// Appends `v` as one component of type `component`; an integer out of the type's range is an
/// error.
fn write(out: &mut Vec<u8>, component: ComponentType, v: f64) -> std::result::Result<(), String> {
    let range = |min: f64, max: f64| {
        if (min..=max).contains(&v) {
            Ok(v)
        } else {
            Err(format!("the value {v} does not fit the accessor's {component:?}"))
        }
    };
    match component {
        ComponentType::F32 => out.extend_from_slice(&(v as f32).to_le_bytes()),
        ComponentType::I8 => out.push(range(-128.0, 127.0)? as i8 as u8),
        ComponentType::U8 => out.push(range(0.0, 255.0)? as u8),
        ComponentType::I16 => out.extend_from_slice(&(range(-32768.0, 32767.0)? as i16).to_le_bytes()),
        ComponentType::U16 => out.extend_from_slice(&(range(0.0, 65535.0)? as u16).to_le_bytes()),
        ComponentType::U32 => out.extend_from_slice(&(range(0.0, u32::MAX as f64)? as u32).to_le_bytes()),
    }
    Ok(())
}
