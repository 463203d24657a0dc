//! Reading accessors with every byte range checked, so a file whose accessors point past their
//! data gets a precise error instead of a panic or silently short data.
//!
//! Handles strided views, normalized integer components (and the plain integer positions and
//! UVs `KHR_mesh_quantization` allows), sparse accessors, and accessors without a buffer view.

use super::source::{view_bytes, Origin};
use crate::error::Result;
use gltf::accessor::{DataType, Dimensions};
use gltf::Accessor;
use std::borrow::Cow;

/// Elements an accessor without a buffer view (all zeros, then sparse values) may declare.
const MAX_IMPLICIT_ELEMENTS: usize = 1 << 26;

/// Reads accessors from one file's buffers.
pub(super) struct Reader<'a> {
    pub origin: &'a Origin,
    pub buffers: &'a [Cow<'a, [u8]>],
}

impl Reader<'_> {
    /// Reads an `N`-component accessor (`VEC2`, `VEC3`, `VEC4`) as floats; `what` says what the
    /// accessor is for, in messages.
    pub fn vectors<const N: usize>(&self, accessor: &Accessor, what: &str) -> Result<Vec<[f32; N]>> {
        let what = describe(accessor, what);
        if accessor.dimensions().multiplicity() != N || accessor.dimensions() == Dimensions::Mat2 {
            return Err(self.origin.error(format!(
                "{what} has type {:?}, expected a {N}-component vector",
                accessor.dimensions()
            )));
        }
        let flat = self.components(accessor, &what, float_decoder(accessor))?;
        Ok(flat.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i])).collect())
    }

    /// Reads a `SCALAR` accessor of unsigned integers (vertex indices).
    pub fn indices(&self, accessor: &Accessor, what: &str) -> Result<Vec<u32>> {
        let what = describe(accessor, what);
        let decode: fn(&[u8]) -> u32 = match accessor.data_type() {
            DataType::U8 => |b| u32::from(b[0]),
            DataType::U16 => |b| u32::from(u16::from_le_bytes([b[0], b[1]])),
            DataType::U32 => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            other => {
                return Err(self.origin.error(format!(
                    "{what} has component type {other:?}; indices must be unsigned integers"
                )))
            }
        };
        if accessor.dimensions() != Dimensions::Scalar {
            return Err(self
                .origin
                .error(format!("{what} has type {:?}; indices must be SCALAR", accessor.dimensions())));
        }
        self.components(accessor, &what, decode)
    }

    /// Reads a `JOINTS_n` accessor: `VEC4` of unsigned bytes or shorts (not normalized), joint
    /// indices into the skin's `joints`.
    pub fn joints(&self, accessor: &Accessor, what: &str) -> Result<Vec<[u32; 4]>> {
        let described = describe(accessor, what);
        let decode: fn(&[u8]) -> u32 = match (accessor.data_type(), accessor.normalized()) {
            (DataType::U8, false) => |b| u32::from(b[0]),
            (DataType::U16, false) => |b| u32::from(u16::from_le_bytes([b[0], b[1]])),
            (other, normalized) => {
                return Err(self.origin.error(format!(
                    "{described} has component type {other:?}{}; joint indices must be unsigned bytes or \
                     shorts, not normalized",
                    if normalized { " (normalized)" } else { "" }
                )))
            }
        };
        if accessor.dimensions() != Dimensions::Vec4 {
            return Err(self.origin.error(format!(
                "{described} has type {:?}; joint indices must be VEC4",
                accessor.dimensions()
            )));
        }
        let flat = self.components(accessor, &described, decode)?;
        Ok(flat.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect())
    }

    /// Reads a `WEIGHTS_n` accessor: `VEC4` of floats, or of normalized unsigned bytes or shorts.
    pub fn weights(&self, accessor: &Accessor, what: &str) -> Result<Vec<[f32; 4]>> {
        let allowed = match accessor.data_type() {
            DataType::F32 => true,
            DataType::U8 | DataType::U16 => accessor.normalized(),
            _ => false,
        };
        if !allowed || accessor.dimensions() != Dimensions::Vec4 {
            return Err(self.origin.error(format!(
                "{} has type {:?} of {:?}{}; joint weights must be VEC4 of floats or of normalized \
                 unsigned bytes or shorts",
                describe(accessor, what),
                accessor.dimensions(),
                accessor.data_type(),
                if accessor.normalized() { " (normalized)" } else { "" }
            )));
        }
        self.vectors::<4>(accessor, what)
    }

    /// Reads a `MAT4` accessor of floats (a skin's inverse bind matrices), column-major.
    pub fn matrices(&self, accessor: &Accessor, what: &str) -> Result<Vec<[f32; 16]>> {
        if accessor.dimensions() != Dimensions::Mat4 || accessor.data_type() != DataType::F32 {
            return Err(self.origin.error(format!(
                "{} has type {:?} of {:?}; it must be MAT4 of floats",
                describe(accessor, what),
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        self.vectors::<16>(accessor, what)
    }

    /// Every component of every element, in order, each decoded by `decode` from its bytes.
    fn components<T: Copy + Default>(
        &self,
        accessor: &Accessor,
        what: &str,
        decode: fn(&[u8]) -> T,
    ) -> Result<Vec<T>> {
        let size = accessor.data_type().size();
        let n = accessor.dimensions().multiplicity();
        let count = accessor.count();
        let mut out = match accessor.view() {
            Some(view) => {
                let stride = view.stride().unwrap_or(size * n);
                let bytes = self.element_bytes(accessor, &view, stride, what)?;
                let mut out = Vec::with_capacity(count * n);
                for element in 0..count {
                    let start = element * stride;
                    out.extend((0..n).map(|c| decode(&bytes[start + c * size..start + (c + 1) * size])));
                }
                out
            }
            None if count <= MAX_IMPLICIT_ELEMENTS => vec![T::default(); count * n],
            None => {
                return Err(self.origin.error(format!(
                    "{what} declares {count} elements without a buffer view (more than umbra accepts)"
                )))
            }
        };
        if let Some(sparse) = accessor.sparse() {
            self.apply_sparse(accessor, &sparse, what, decode, &mut out)?;
        }
        Ok(out)
    }

    /// The bytes of an accessor's elements inside its view, after checking they fit.
    fn element_bytes<'v>(
        &'v self,
        accessor: &Accessor,
        view: &gltf::buffer::View,
        stride: usize,
        what: &str,
    ) -> Result<&'v [u8]> {
        let element = accessor.data_type().size() * accessor.dimensions().multiplicity();
        if stride < element {
            return Err(self.origin.error(format!(
                "{what}: buffer view {} has byteStride {stride}, less than the element size {element}",
                view.index()
            )));
        }
        let bytes = view_bytes(view, self.buffers);
        let start = accessor.offset();
        let end = match accessor.count() {
            0 => Some(start),
            count => (count - 1).checked_mul(stride).and_then(|s| s.checked_add(start)?.checked_add(element)),
        };
        match end.and_then(|end| bytes.get(start..end)) {
            Some(elements) => Ok(elements),
            None => Err(self.origin.error(format!(
                "{what} ({} elements from byte {start}, stride {stride}) runs past the end of buffer \
                 view {}, which has {} bytes",
                accessor.count(),
                view.index(),
                bytes.len()
            ))),
        }
    }

    /// Overwrites the elements a sparse accessor substitutes.
    fn apply_sparse<T: Copy>(
        &self,
        accessor: &Accessor,
        sparse: &gltf::accessor::sparse::Sparse,
        what: &str,
        decode: fn(&[u8]) -> T,
        out: &mut [T],
    ) -> Result<()> {
        let (size, n) = (accessor.data_type().size(), accessor.dimensions().multiplicity());
        let count = sparse.count();
        let (indices, values) = (sparse.indices(), sparse.values());
        let index_size = indices.index_type().size();
        let slice = |view: gltf::buffer::View, offset: usize, len: Option<usize>, part: &str| {
            let bytes = view_bytes(&view, self.buffers);
            len.and_then(|len| bytes.get(offset..offset.checked_add(len)?)).ok_or_else(|| {
                self.origin.error(format!(
                    "{what}: the sparse {part} ({count} entries from byte {offset}) run past the end of \
                     buffer view {}",
                    view.index()
                ))
            })
        };
        let index_bytes = slice(indices.view(), indices.offset(), count.checked_mul(index_size), "indices")?;
        let value_bytes = slice(values.view(), values.offset(), count.checked_mul(size * n), "values")?;
        for (k, raw) in index_bytes.chunks_exact(index_size).enumerate() {
            let target = raw.iter().rev().fold(0usize, |acc, &b| acc << 8 | usize::from(b));
            if target >= accessor.count() {
                return Err(self.origin.error(format!(
                    "{what}: sparse index {target} is out of range (the accessor has {} elements)",
                    accessor.count()
                )));
            }
            for c in 0..n {
                let at = (k * n + c) * size;
                out[target * n + c] = decode(&value_bytes[at..at + size]);
            }
        }
        Ok(())
    }
}

/// "accessor 3 (NORMAL of mesh 'Box' primitive 0)".
fn describe(accessor: &Accessor, what: &str) -> String {
    format!("accessor {} ({what})", accessor.index())
}

/// Decodes one component to `f32`, applying the glTF normalization rules when `normalized`.
fn float_decoder(accessor: &Accessor) -> fn(&[u8]) -> f32 {
    match (accessor.data_type(), accessor.normalized()) {
        (DataType::F32, _) => |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        (DataType::U8, true) => |b| f32::from(b[0]) / 255.0,
        (DataType::U8, false) => |b| f32::from(b[0]),
        (DataType::I8, true) => |b| (f32::from(b[0] as i8) / 127.0).max(-1.0),
        (DataType::I8, false) => |b| f32::from(b[0] as i8),
        (DataType::U16, true) => |b| f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
        (DataType::U16, false) => |b| f32::from(u16::from_le_bytes([b[0], b[1]])),
        (DataType::I16, true) => |b| (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0),
        (DataType::I16, false) => |b| f32::from(i16::from_le_bytes([b[0], b[1]])),
        (DataType::U32, true) => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32 / u32::MAX as f32,
        (DataType::U32, false) => |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}
