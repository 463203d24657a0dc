//! One mesh primitive as triangles in its own (object) space, read once and then placed by every
//! node that uses its mesh.
//!
//! Here the glTF geometry rules are applied: strips and fans become triangle lists, points and
//! lines are skipped, morph targets are applied at the weights given, triangles with a NaN or
//! infinite vertex are dropped, missing normals become flat normals (the vertices are unwelded),
//! and missing tangents are generated from the UVs. A skinned primitive also keeps its joints and
//! weights, for `skin.rs` to pose it.

use super::accessor::Reader;
use crate::error::Result;
use glam::{Vec2, Vec3, Vec4};
use gltf::accessor::Dimensions;
use gltf::mesh::Mode;
use gltf::Semantic;

/// A primitive's vertices and triangles in object space.
#[derive(Clone, Debug, Default)]
pub(super) struct LocalPrimitive {
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Unit tangents with the bitangent sign in w; empty unless asked for.
    pub tangents: Vec<Vec4>,
    pub uv0: Option<Vec<[f32; 2]>>,
    pub uv1: Option<Vec<[f32; 2]>>,
    pub colors: Option<Vec<[f32; 4]>>,
    /// `JOINTS_n` of a skinned primitive, one array per set `n` (empty unless asked for).
    pub joints: Vec<Vec<[u32; 4]>>,
    /// `WEIGHTS_n`, as `joints`.
    pub weights: Vec<Vec<[f32; 4]>>,
    pub triangles: Vec<[u32; 3]>,
    /// Whether the normals are flat ones umbra made (the file has none): every triangle has its
    /// own three vertices.
    pub flat: bool,
    /// The glTF material index (`None`: the default material).
    pub material: Option<usize>,
    /// Triangles dropped for NaN or infinite vertex positions.
    pub dropped: usize,
}

/// What the scene needs from a primitive besides its geometry.
#[derive(Clone, Copy, Debug)]
pub(super) struct Wanted<'w> {
    /// Produce tangents, generated from this UV set when the file has none.
    pub tangents_from_uv: Option<u32>,
    /// The morph targets' weights (the node's, else the mesh's; empty: all 0).
    pub morph_weights: &'w [f32],
    /// Read `JOINTS_n` and `WEIGHTS_n`: the node that places the mesh has a skin.
    pub skinned: bool,
}

/// Reads one primitive; `None` for points and lines, which umbra does not render.
pub(super) fn read_primitive(
    reader: &Reader,
    mesh: &gltf::Mesh,
    primitive: &gltf::Primitive,
    wanted: Wanted,
) -> Result<Option<LocalPrimitive>> {
    let source = Source { reader, primitive, label: label(mesh, primitive) };
    if matches!(primitive.mode(), Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
        log::warn!(
            "{}: {} is drawn as {:?}; skipping it (umbra renders triangles)",
            reader.origin.name(),
            source.label,
            primitive.mode()
        );
        return Ok(None);
    }
    let positions = source.positions()?;
    let count = positions.len();
    let normals = source.vectors::<3>(Semantic::Normals, "NORMAL", count)?;
    let tangents = match wanted.tangents_from_uv {
        Some(_) => source.vectors::<4>(Semantic::Tangents, "TANGENT", count)?,
        None => None,
    };
    let has_normals = normals.is_some();
    let mut local = LocalPrimitive {
        positions,
        normals: normals.unwrap_or_default().into_iter().map(Vec3::from).collect(),
        tangents: tangents.unwrap_or_default().into_iter().map(Vec4::from).collect(),
        uv0: source.vectors::<2>(Semantic::TexCoords(0), "TEXCOORD_0", count)?,
        uv1: source.vectors::<2>(Semantic::TexCoords(1), "TEXCOORD_1", count)?,
        colors: source.colors(count)?,
        joints: Vec::new(),
        weights: Vec::new(),
        triangles: source.triangles(count)?,
        flat: !has_normals,
        material: primitive.material().index(),
        dropped: 0,
    };
    source.morph(&mut local, wanted.morph_weights)?;
    if wanted.skinned {
        (local.joints, local.weights) = source.influences(count)?;
    }
    local.drop_non_finite(reader.origin.name(), &source.label);
    if !has_normals {
        local.flat_normals();
    }
    local.finish_frames(wanted);
    Ok(Some(local))
}

/// Reads one primitive's attributes and indices, naming it in errors.
struct Source<'r> {
    reader: &'r Reader<'r>,
    primitive: &'r gltf::Primitive<'r>,
    label: String,
}

impl Source<'_> {
    fn positions(&self) -> Result<Vec<Vec3>> {
        let Some(accessor) = self.primitive.get(&Semantic::Positions) else {
            return Err(self.reader.origin.error(format!("{} has no POSITION attribute", self.label)));
        };
        let positions = self.reader.vectors::<3>(&accessor, &format!("POSITION of {}", self.label))?;
        Ok(positions.into_iter().map(Vec3::from).collect())
    }

    /// An optional `N`-component attribute, which must have one element per vertex.
    fn vectors<const N: usize>(
        &self,
        semantic: Semantic,
        name: &str,
        count: usize,
    ) -> Result<Option<Vec<[f32; N]>>> {
        let Some(accessor) = self.primitive.get(&semantic) else { return Ok(None) };
        let values = self.reader.vectors::<N>(&accessor, &format!("{name} of {}", self.label))?;
        self.check_count(name, values.len(), count)?;
        Ok(Some(values))
    }

    /// Adds the morph targets' displacements at `weights` (glTF: POSITION, NORMAL and TANGENT,
    /// each where the primitive has the attribute; targets of weight 0 are not read).
    fn morph(&self, local: &mut LocalPrimitive, weights: &[f32]) -> Result<()> {
        let targets = self.primitive.morph_targets();
        if targets.len() == 0 || weights.iter().all(|&w| w == 0.0) {
            return Ok(());
        }
        if weights.len() != targets.len() {
            return Err(self.reader.origin.error(format!(
                "{} has {} morph targets but {} weights (the mesh's or its node's `weights`)",
                self.label,
                targets.len(),
                weights.len()
            )));
        }
        let count = local.positions.len();
        for (k, (target, &w)) in targets.zip(weights).enumerate() {
            if w == 0.0 {
                continue;
            }
            let read = |accessor: Option<gltf::Accessor>, name: &str| -> Result<Option<Vec<Vec3>>> {
                let Some(accessor) = accessor else { return Ok(None) };
                let name = format!("{name} of morph target {k}");
                let values = self.reader.vectors::<3>(&accessor, &format!("{name} of {}", self.label))?;
                self.check_count(&name, values.len(), count)?;
                Ok(Some(values.into_iter().map(Vec3::from).collect()))
            };
            if let Some(d) = read(target.positions(), "POSITION")? {
                local.positions.iter_mut().zip(d).for_each(|(p, d)| *p += w * d);
            }
            if !local.normals.is_empty() {
                if let Some(d) = read(target.normals(), "NORMAL")? {
                    local.normals.iter_mut().zip(d).for_each(|(n, d)| *n += w * d);
                }
            }
            if !local.tangents.is_empty() {
                if let Some(d) = read(target.tangents(), "TANGENT")? {
                    local.tangents.iter_mut().zip(d).for_each(|(t, d)| *t += (w * d).extend(0.0));
                }
            }
        }
        Ok(())
    }

    /// Every `JOINTS_n` / `WEIGHTS_n` pair of a skinned primitive (at least set 0, and the sets
    /// in pairs, as glTF requires).
    #[allow(clippy::type_complexity)]
    fn influences(&self, count: usize) -> Result<(Vec<Vec<[u32; 4]>>, Vec<Vec<[f32; 4]>>)> {
        let (mut joints, mut weights) = (Vec::new(), Vec::new());
        for set in 0.. {
            let j = self.primitive.get(&Semantic::Joints(set));
            let w = self.primitive.get(&Semantic::Weights(set));
            let (j, w) = match (j, w) {
                (Some(j), Some(w)) => (j, w),
                (None, None) if set > 0 => break,
                (j, _) => {
                    let missing = if j.is_none() { "JOINTS" } else { "WEIGHTS" };
                    return Err(self.reader.origin.error(format!(
                        "{} is skinned (its node has a skin) but has no {missing}_{set} attribute",
                        self.label
                    )));
                }
            };
            let name = format!("JOINTS_{set}");
            let values = self.reader.joints(&j, &format!("{name} of {}", self.label))?;
            self.check_count(&name, values.len(), count)?;
            joints.push(values);
            let name = format!("WEIGHTS_{set}");
            let values = self.reader.weights(&w, &format!("{name} of {}", self.label))?;
            self.check_count(&name, values.len(), count)?;
            weights.push(values);
        }
        Ok((joints, weights))
    }

    /// `COLOR_0` as RGBA (alpha 1 for an RGB attribute).
    fn colors(&self, count: usize) -> Result<Option<Vec<[f32; 4]>>> {
        let rgb = self.primitive.get(&Semantic::Colors(0)).map(|a| a.dimensions()) == Some(Dimensions::Vec3);
        if rgb {
            let colors = self.vectors::<3>(Semantic::Colors(0), "COLOR_0", count)?;
            return Ok(colors.map(|c| c.into_iter().map(|[r, g, b]| [r, g, b, 1.0]).collect()));
        }
        self.vectors::<4>(Semantic::Colors(0), "COLOR_0", count)
    }

    /// The triangles, every index checked against the vertex count.
    fn triangles(&self, count: usize) -> Result<Vec<[u32; 3]>> {
        let indices = match self.primitive.indices() {
            Some(accessor) => self.reader.indices(&accessor, &format!("indices of {}", self.label))?,
            None => (0..count as u32).collect(),
        };
        if let Some((at, &index)) = indices.iter().enumerate().find(|(_, &i)| i as usize >= count) {
            return Err(self.reader.origin.error(format!(
                "{}: index {index} (entry {at} of its indices) is out of range: the primitive has {count} vertices",
                self.label
            )));
        }
        Ok(assemble(self.primitive.mode(), &indices, self.reader.origin.name(), &self.label))
    }

    fn check_count(&self, name: &str, len: usize, count: usize) -> Result<()> {
        if len == count {
            return Ok(());
        }
        Err(self
            .reader
            .origin
            .error(format!("{}: {name} has {len} elements but POSITION has {count}", self.label)))
    }
}

/// "mesh 2 ('Wheel') primitive 0", for messages.
pub(super) fn label(mesh: &gltf::Mesh, primitive: &gltf::Primitive) -> String {
    match mesh.name() {
        Some(name) => format!("mesh {} ('{name}') primitive {}", mesh.index(), primitive.index()),
        None => format!("mesh {} primitive {}", mesh.index(), primitive.index()),
    }
}

/// Triangle lists from triangles, strips and fans, with the winding the glTF spec defines.
fn assemble(mode: Mode, v: &[u32], file: &str, label: &str) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..v.len().saturating_sub(2))
            .map(|i| if i % 2 == 0 { [v[i], v[i + 1], v[i + 2]] } else { [v[i], v[i + 2], v[i + 1]] })
            .collect(),
        Mode::TriangleFan => (0..v.len().saturating_sub(2)).map(|i| [v[i + 1], v[i + 2], v[0]]).collect(),
        _ => {
            if !v.len().is_multiple_of(3) {
                log::warn!("{file}: {label} has {} indices, not a multiple of 3; ignoring the rest", v.len());
            }
            v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
        }
    }
}

impl LocalPrimitive {
    /// Drops triangles with a NaN or infinite vertex, and the vertices only they used.
    fn drop_non_finite(&mut self, file: &str, label: &str) {
        let finite = |t: &[u32; 3]| t.iter().all(|&v| self.positions[v as usize].is_finite());
        let before = self.triangles.len();
        let kept: Vec<[u32; 3]> = self.triangles.iter().copied().filter(finite).collect();
        self.dropped = before - kept.len();
        if self.dropped == 0 {
            return;
        }
        log::warn!(
            "{file}: {label}: dropped {} of {before} triangles with NaN or infinite vertex positions",
            self.dropped
        );
        // Keep only the referenced vertices, renumbered in order.
        let mut new_index = vec![u32::MAX; self.positions.len()];
        let mut order = Vec::new();
        for &v in kept.iter().flatten() {
            if new_index[v as usize] == u32::MAX {
                new_index[v as usize] = order.len() as u32;
                order.push(v);
            }
        }
        self.triangles = kept.iter().map(|t| t.map(|v| new_index[v as usize])).collect();
        self.gather(&order);
    }

    /// glTF: "When normals are not specified, client implementations MUST calculate flat normals":
    /// every triangle gets its own three vertices carrying its face normal.
    fn flat_normals(&mut self) {
        let corners: Vec<u32> = self.triangles.iter().flatten().copied().collect();
        self.gather(&corners);
        self.triangles = (0..self.triangles.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        self.normals = self
            .triangles
            .iter()
            .flat_map(|t| {
                let [a, b, c] = t.map(|v| self.positions[v as usize]);
                [(b - a).cross(c - a).normalize_or(Vec3::Z); 3]
            })
            .collect();
    }

    /// Makes normals unit length and produces tangents when they are wanted.
    fn finish_frames(&mut self, wanted: Wanted) {
        for n in &mut self.normals {
            *n = n.normalize_or(Vec3::Z);
        }
        let Some(set) = wanted.tangents_from_uv else {
            self.tangents.clear();
            return;
        };
        if self.tangents.len() == self.positions.len() {
            for (t, &n) in self.tangents.iter_mut().zip(&self.normals) {
                let w = if t.w < 0.0 { -1.0 } else { 1.0 };
                *t = orthonormal_tangent(n, t.truncate()).extend(w);
            }
            return;
        }
        let uvs = if set == 1 { self.uv1.as_deref() } else { self.uv0.as_deref() };
        let uvs = uvs.or(self.uv0.as_deref());
        self.tangents = generate_tangents(&self.positions, &self.normals, uvs, &self.triangles);
    }

    /// Reorders (and repeats or drops) vertices: vertex `i` becomes the old vertex `order[i]`.
    fn gather(&mut self, order: &[u32]) {
        fn pick<T: Copy>(values: &[T], order: &[u32]) -> Vec<T> {
            order.iter().map(|&v| values[v as usize]).collect()
        }
        self.positions = pick(&self.positions, order);
        if !self.normals.is_empty() {
            self.normals = pick(&self.normals, order);
        }
        if !self.tangents.is_empty() {
            self.tangents = pick(&self.tangents, order);
        }
        for uv in [&mut self.uv0, &mut self.uv1].into_iter().flatten() {
            *uv = pick(uv, order);
        }
        if let Some(colors) = &mut self.colors {
            *colors = pick(colors, order);
        }
        for joints in &mut self.joints {
            *joints = pick(joints, order);
        }
        for weights in &mut self.weights {
            *weights = pick(weights, order);
        }
    }
}

/// Per-vertex tangents from UV derivatives, accumulated over the triangles around each vertex and
/// Gram-Schmidt orthonormalised against the normal (`w` = handedness). Without UVs, any tangent
/// with `w` = 0: no frame (a normal map reads its texel at UV 0 in it, as it did with `w` = 1;
/// anisotropy, which needs a direction, is dropped there).
fn generate_tangents(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: Option<&[[f32; 2]]>,
    triangles: &[[u32; 3]],
) -> Vec<Vec4> {
    let mut du = vec![Vec3::ZERO; positions.len()];
    let mut dv = vec![Vec3::ZERO; positions.len()];
    if let Some(uvs) = uvs {
        for t in triangles {
            let [a, b, c] = t.map(|v| v as usize);
            let uv = |v: usize| Vec2::from(uvs[v]);
            let (e1, e2) = (positions[b] - positions[a], positions[c] - positions[a]);
            let (d1, d2) = (uv(b) - uv(a), uv(c) - uv(a));
            let r = 1.0 / d1.perp_dot(d2);
            if !r.is_finite() {
                continue;
            }
            let (tu, tv) = ((e1 * d2.y - e2 * d1.y) * r, (e2 * d1.x - e1 * d2.x) * r);
            for v in [a, b, c] {
                du[v] += tu;
                dv[v] += tv;
            }
        }
    }
    if uvs.is_none() {
        return normals.iter().map(|&n| n.any_orthonormal_vector().extend(0.0)).collect();
    }
    // glTF UVs grow downwards in the image, so the normal map's "up" (+Y, the bitangent) is -dP/dv.
    (0..positions.len())
        .map(|v| {
            let t = orthonormal_tangent(normals[v], du[v]);
            let w = if normals[v].cross(t).dot(-dv[v]) < 0.0 { -1.0 } else { 1.0 };
            t.extend(w)
        })
        .collect()
}

/// `tangent` made unit and perpendicular to the unit `normal` (any perpendicular if it cannot be).
fn orthonormal_tangent(normal: Vec3, tangent: Vec3) -> Vec3 {
    let t = (tangent - normal * normal.dot(tangent)).normalize_or_zero();
    if t == Vec3::ZERO {
        normal.any_orthonormal_vector()
    } else {
        t
    }
}

/// Whether a triangle has (numerically) zero area: its height is below 1e-6 of its longest edge.
pub(super) fn is_degenerate(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let longest = (b - a).length_squared().max((c - a).length_squared()).max((c - b).length_squared());
    (b - a).cross(c - a).length() <= 1e-6 * longest
}
