//! `EXT_meshopt_compression`: buffer views compressed by meshoptimizer (gltfpack,
//! glTF-Transform), decoded at load by meshoptimizer's own decoder (the `meshopt` crate, which
//! builds its C++ from source) into a buffer of their own, which the views are then pointed at:
//! everything after reads them as plain views.
//!
//! Each compressed view names its data (`buffer`, `byteOffset`, `byteLength`), its `count` of
//! elements of `byteStride` bytes and a `mode`: `ATTRIBUTES` (the vertex codec, then an optional
//! `filter`: `OCTAHEDRAL` unit vectors, `QUATERNION` rotations, `EXPONENTIAL` floats), `TRIANGLES`
//! (the index codec) or `INDICES` (the index sequence codec). The view's own `buffer` is then the
//! fallback for readers without the extension, often a buffer with no data at all (marked
//! `fallback: true`), which umbra never reads.

use super::source::Origin;
use crate::error::Result;
use gltf::json;
use std::borrow::Cow;

const EXTENSION: &str = "EXT_meshopt_compression";

/// Whether buffer `buffer` is only the fallback of compressed views (no data to read).
pub(super) fn is_fallback(buffer: &json::Buffer) -> bool {
    buffer
        .extensions
        .as_ref()
        .and_then(|e| e.others.get(EXTENSION))
        .and_then(|e| e.get("fallback"))
        .and_then(json::Value::as_bool)
        == Some(true)
}

/// Whether any buffer view of `root` is compressed.
pub(super) fn any(root: &json::Root) -> bool {
    root.buffer_views.iter().any(|v| extension(v).is_some())
}

fn extension(view: &json::buffer::View) -> Option<&json::Value> {
    view.extensions.as_ref().and_then(|e| e.others.get(EXTENSION))
}

/// One compressed view's parameters, checked.
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: String,
    filter: String,
}

fn parse(origin: &Origin, index: usize, value: &json::Value) -> Result<Compressed> {
    let label = format!("buffer view {index}: {EXTENSION}");
    let int = |key: &str, default: Option<u64>| -> Result<usize> {
        match value.get(key) {
            Some(v) => v.as_u64().map(|v| v as usize).ok_or_else(|| {
                origin.error(format!("{label}: {key} must be a non-negative integer, not {v}"))
            }),
            None => {
                default.map(|d| d as usize).ok_or_else(|| origin.error(format!("{label}: {key} is missing")))
            }
        }
    };
    let text =
        |key: &str, default: &str| value.get(key).and_then(json::Value::as_str).unwrap_or(default).to_owned();
    Ok(Compressed {
        buffer: int("buffer", None)?,
        offset: int("byteOffset", Some(0))?,
        length: int("byteLength", None)?,
        stride: int("byteStride", None)?,
        count: int("count", None)?,
        mode: text("mode", ""),
        filter: text("filter", "NONE"),
    })
}

/// Decodes every compressed view of `root` from `buffers` into one new buffer, appended to
/// `root` (its data returned), and points each view at its decoded bytes. A view whose
/// parameters, data or filter are wrong is refused naming it.
pub(super) fn decode(origin: &Origin, root: &mut json::Root, buffers: &[Cow<[u8]>]) -> Result<Vec<u8>> {
    let mut out: Vec<u8> = Vec::new();
    let new_buffer = root.buffers.len() as u32;
    for (index, view) in root.buffer_views.iter_mut().enumerate() {
        let Some(value) = extension(view) else { continue };
        let c = parse(origin, index, value)?;
        let label = format!("buffer view {index}: {EXTENSION}");
        let source = buffers
            .get(c.buffer)
            .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
            .ok_or_else(|| {
                origin.error(format!(
                    "{label}: bytes {}..{} of buffer {} are not in the file",
                    c.offset,
                    c.offset as u128 + c.length as u128,
                    c.buffer
                ))
            })?;
        let decoded = decode_view(&c, source).map_err(|e| origin.error(format!("{label}: {e}")))?;
        // Views start 4-byte aligned in the new buffer (accessors' components need it).
        out.resize(out.len().next_multiple_of(4), 0);
        let at = out.len();
        out.extend_from_slice(&decoded);
        view.buffer = json::Index::new(new_buffer);
        view.byte_offset = Some((at as u64).into());
        view.byte_length = (decoded.len() as u64).into();
        if let Some(e) = view.extensions.as_mut() {
            e.others.remove(EXTENSION);
        }
    }
    push_decoded_buffer(root, EXTENSION, out.len());
    Ok(out)
}

/// Appends the buffer a decoder of `extension` fills with `length` decoded bytes (its data is
/// the decoder's, handed to the loader beside the file's buffers).
pub(super) fn push_decoded_buffer(root: &mut json::Root, extension: &str, length: usize) {
    root.buffers.push(json::Buffer {
        byte_length: (length as u64).into(),
        name: Some(format!("{extension} decoded")),
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
}

/// Decodes one view: `count` elements of `stride` bytes from `source`.
fn decode_view(c: &Compressed, source: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let size =
        c.count.checked_mul(c.stride).filter(|&s| s <= 1 << 31).ok_or("the decoded view is too large")?;
    // Decoded into 4-byte words: the filters read 16- and 32-bit components.
    let mut words = vec![0u32; size.div_ceil(4)];
    let dst = words.as_mut_ptr().cast::<std::ffi::c_void>();
    let status = match c.mode.as_str() {
        "ATTRIBUTES" => {
            if c.stride == 0 || !c.stride.is_multiple_of(4) || c.stride > 256 {
                return Err(format!(
                    "ATTRIBUTES need a byteStride that is a multiple of 4 up to 256, not {}",
                    c.stride
                ));
            }
            // SAFETY: `words` holds count × stride bytes; the decoder reads `source` within its
            // length and is safe on untrusted input (meshoptimizer's documentation).
            unsafe {
                meshopt::ffi::meshopt_decodeVertexBuffer(
                    dst,
                    c.count,
                    c.stride,
                    source.as_ptr(),
                    source.len(),
                )
            }
        }
        "TRIANGLES" | "INDICES" => {
            if c.stride != 2 && c.stride != 4 {
                return Err(format!("{} need a byteStride of 2 or 4, not {}", c.mode, c.stride));
            }
            if c.mode == "TRIANGLES" && !c.count.is_multiple_of(3) {
                return Err(format!("TRIANGLES need a count that is a multiple of 3, not {}", c.count));
            }
            // SAFETY: as above, for indices of `stride` bytes.
            unsafe {
                if c.mode == "TRIANGLES" {
                    meshopt::ffi::meshopt_decodeIndexBuffer(
                        dst,
                        c.count,
                        c.stride,
                        source.as_ptr(),
                        source.len(),
                    )
                } else {
                    meshopt::ffi::meshopt_decodeIndexSequence(
                        dst,
                        c.count,
                        c.stride,
                        source.as_ptr(),
                        source.len(),
                    )
                }
            }
        }
        other => return Err(format!("unknown mode '{other}' (ATTRIBUTES, TRIANGLES or INDICES)")),
    };
    if status != 0 {
        return Err(format!("the {} data does not decode (meshoptimizer's error {status})", c.mode));
    }
    let filter = c.filter.as_str();
    if filter != "NONE" && c.mode != "ATTRIBUTES" {
        return Err(format!("filter {filter} applies to ATTRIBUTES only, not {}", c.mode));
    }
    // SAFETY: each filter rewrites count elements of stride bytes in place, within `words`, whose
    // 4-byte alignment covers its 16- and 32-bit components.
    match (filter, c.stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4 | 8) => unsafe { meshopt::ffi::meshopt_decodeFilterOct(dst, c.count, c.stride) },
        ("QUATERNION", 8) => unsafe { meshopt::ffi::meshopt_decodeFilterQuat(dst, c.count, c.stride) },
        ("EXPONENTIAL", s) if s % 4 == 0 => unsafe {
            meshopt::ffi::meshopt_decodeFilterExp(dst, c.count, c.stride)
        },
        ("OCTAHEDRAL" | "QUATERNION" | "EXPONENTIAL", s) => {
            return Err(format!("filter {filter} cannot take a byteStride of {s}"))
        }
        (other, _) => {
            return Err(format!("unknown filter '{other}' (NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL)"))
        }
    }
    Ok(bytemuck::cast_slice::<u32, u8>(&words)[..size].to_vec())
}
