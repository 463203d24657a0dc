//! Skins at the pose their joints' default transforms give (glTF's linear blend skinning; umbra
//! renders no animation): a skinned primitive's vertices are moved to world space by
//! Σ weight · jointWorld · inverseBind, its normals by that matrix's inverse transpose. The
//! node that places a skinned mesh contributes nothing but the mesh, as the specification says.

use super::accessor::Reader;
use super::geometry::LocalPrimitive;
use crate::error::Result;
use glam::{Mat3, Mat4, Vec3};

/// The world transform of every node of the document, from every root (a node nobody lists as
/// a child), parents before children; `None` for a node no root reaches (one on a cycle).
pub(super) fn node_worlds(
    document: &gltf::Document,
    local: impl Fn(&gltf::Node) -> Mat4,
) -> Vec<Option<Mat4>> {
    let mut is_child = vec![false; document.nodes().len()];
    for child in document.nodes().flat_map(|n| n.children()) {
        is_child[child.index()] = true;
    }
    let mut worlds = vec![None; document.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> =
        document.nodes().filter(|n| !is_child[n.index()]).map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        if worlds[node.index()].is_some() {
            continue;
        }
        let world = parent * local(&node);
        worlds[node.index()] = Some(world);
        stack.extend(node.children().map(|c| (c, world)));
    }
    worlds
}

/// Skin `skin`'s joint matrices, jointWorld · inverseBind, one per joint; `label` names the node
/// that uses it in messages.
pub(super) fn joint_matrices(
    reader: &Reader,
    skin: &gltf::Skin,
    worlds: &[Option<Mat4>],
    label: &str,
) -> Result<Vec<Mat4>> {
    let what = format!("skin {} of {label}", skin.index());
    let joints: Vec<gltf::Node> = skin.joints().collect();
    let inverse_bind = match skin.inverse_bind_matrices() {
        Some(accessor) => {
            let matrices = reader.matrices(&accessor, &format!("inverseBindMatrices of {what}"))?;
            if matrices.len() < joints.len() {
                return Err(reader.origin.error(format!(
                    "{what}: inverseBindMatrices (accessor {}) has {} matrices for {} joints",
                    accessor.index(),
                    matrices.len(),
                    joints.len()
                )));
            }
            matrices.iter().map(Mat4::from_cols_array).collect()
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    joints
        .iter()
        .zip(inverse_bind)
        .map(|(joint, inverse_bind)| {
            let world = worlds.get(joint.index()).copied().flatten().ok_or_else(|| {
                reader.origin.error(format!(
                    "{what}: joint node {} is not reachable from a root node (the hierarchy has a cycle)",
                    joint.index()
                ))
            })?;
            let matrix = world * inverse_bind;
            if !matrix.is_finite() {
                return Err(reader.origin.error(format!(
                    "{what}: joint node {}'s world transform times its inverse bind matrix is not finite",
                    joint.index()
                )));
            }
            Ok(matrix)
        })
        .collect()
}

/// `local` posed by the joint matrices `joints`, in world space: each vertex moved by
/// Σ weight · joint matrix (the weights as given, not renormalised), its normal by the inverse
/// transpose and its tangent by the linear part; where the blended matrix mirrors (a negative
/// determinant, summed over a triangle's corners) the triangle's winding and the tangents'
/// handedness flip, as for a mirroring node. Flat normals (the file had none) are made again from
/// the posed triangles. `Err` names the first vertex that refers to a joint the skin lacks.
pub(super) fn pose(local: &LocalPrimitive, joints: &[Mat4]) -> std::result::Result<LocalPrimitive, String> {
    let mut matrices = vec![Mat4::ZERO; local.positions.len()];
    for (set, (indices, weights)) in local.joints.iter().zip(&local.weights).enumerate() {
        for (v, (index, weight)) in indices.iter().zip(weights).enumerate() {
            for (&j, &w) in index.iter().zip(weight) {
                let Some(joint) = joints.get(j as usize) else {
                    return Err(format!(
                        "JOINTS_{set} of vertex {v} refers to joint {j}, but the skin has {} joints",
                        joints.len()
                    ));
                };
                if w != 0.0 {
                    matrices[v] += *joint * w;
                }
            }
        }
    }
    let linear: Vec<Mat3> = matrices.iter().map(|&m| Mat3::from_mat4(m)).collect();
    let mut posed = local.clone();
    posed.joints.clear();
    posed.weights.clear();
    posed.positions = local.positions.iter().zip(&matrices).map(|(&p, m)| m.transform_point3(p)).collect();
    if let Some(v) = posed.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {v} is not finite once skinned (check its WEIGHTS)"));
    }
    posed.normals = local
        .normals
        .iter()
        .zip(&linear)
        .map(|(&n, l)| (l.inverse().transpose() * n).normalize_or(Vec3::Z))
        .collect();
    posed.tangents = local
        .tangents
        .iter()
        .zip(&linear)
        .map(|(t, l)| {
            let w = if l.determinant() < 0.0 { -t.w } else { t.w };
            (*l * t.truncate()).extend(w)
        })
        .collect();
    for t in &mut posed.triangles {
        if t.iter().map(|&v| linear[v as usize].determinant()).sum::<f32>() < 0.0 {
            t.swap(1, 2);
        }
    }
    if posed.flat {
        for t in &posed.triangles {
            let [a, b, c] = t.map(|v| posed.positions[v as usize]);
            let n = (b - a).cross(c - a).normalize_or(Vec3::Z);
            for &v in t {
                posed.normals[v as usize] = n;
            }
        }
    }
    Ok(posed)
}
