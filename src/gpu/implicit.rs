//! Implicit shapes as `implicit.glsl` reads them: each [`ImplicitShape`] as a program of RGBA32UI
//! texels, uploaded after the BVH's triangles in `bvh_tri_texels` ([`crate::bvh::Bvh::attach_implicit`]).
//!
//! Layout from the shape's first texel: a header (instruction count, material, step scale and hit
//! threshold as float bits), the world → node rows (three texels), then
//! [`IMPLICIT_INSTRUCTION_TEXELS`] texels per instruction in postfix order: a primitive (kind and
//! uniform scale; its four parameters; the node → primitive rows), or an operation (kind and
//! smoothness; the rest unused).

use super::layout::*;
use crate::scene::implicit::{CsgOp, Primitive, SdfNode, MAX_STACK};
use crate::scene::ImplicitShape;
use glam::{Mat4, Quat, Vec3};

const _: () = assert!(MAX_STACK == IMPLICIT_MAX_STACK as usize);

/// `shape`'s program (see the module docs).
pub fn program(shape: &ImplicitShape) -> Vec<[u32; 4]> {
    let world = Mat4::from_cols_array_2d(&shape.world);
    let mut out = vec![[
        shape.root.instructions() as u32,
        shape.material,
        shape.step_scale.to_bits(),
        shape.epsilon().to_bits(),
    ]];
    out.extend(rows(&world.inverse()));
    emit(&shape.root, &mut out);
    debug_assert_eq!(
        out.len(),
        (IMPLICIT_HEADER_TEXELS + IMPLICIT_INSTRUCTION_TEXELS * shape.root.instructions() as u32) as usize
    );
    out
}

/// Appends `node`'s postfix program.
fn emit(node: &SdfNode, out: &mut Vec<[u32; 4]>) {
    match node {
        SdfNode::Primitive { primitive, translation, rotation, scale } => {
            let (kind, params) = gpu_primitive(primitive);
            let m = Mat4::from_scale_rotation_translation(
                Vec3::splat(*scale),
                Quat::from_array(*rotation),
                Vec3::from(*translation),
            )
            .inverse();
            out.push([kind, scale.to_bits(), 0, 0]);
            out.push(params.map(f32::to_bits));
            out.extend(rows(&m));
        }
        SdfNode::Csg { op, smoothness, children } => {
            let kind = match op {
                CsgOp::Union => IMPLICIT_UNION,
                CsgOp::Intersection => IMPLICIT_INTERSECTION,
                CsgOp::Subtraction => IMPLICIT_SUBTRACTION,
            };
            emit(&children[0], out);
            for c in &children[1..] {
                emit(c, out);
                out.push([kind, smoothness.to_bits(), 0, 0]);
                out.extend([[0; 4]; IMPLICIT_INSTRUCTION_TEXELS as usize - 1]);
            }
        }
    }
}

/// The GPU kind (`IMPLICIT_*`) and four parameters of a primitive.
fn gpu_primitive(p: &Primitive) -> (u32, [f32; 4]) {
    match *p {
        Primitive::Sphere { radius } => (IMPLICIT_SPHERE, [radius, 0.0, 0.0, 0.0]),
        Primitive::Box { half_extents: b } => (IMPLICIT_BOX, [b[0], b[1], b[2], 0.0]),
        Primitive::RoundedBox { half_extents: b, radius } => {
            (IMPLICIT_ROUNDED_BOX, [b[0] - radius, b[1] - radius, b[2] - radius, radius])
        }
        Primitive::Torus { major_radius, minor_radius } => {
            (IMPLICIT_TORUS, [major_radius, minor_radius, 0.0, 0.0])
        }
        Primitive::Capsule { half_height, radius } => (IMPLICIT_CAPSULE, [half_height, radius, 0.0, 0.0]),
        Primitive::Cylinder { half_height, radius } => (IMPLICIT_CYLINDER, [half_height, radius, 0.0, 0.0]),
        Primitive::Plane { normal: n, offset } => (IMPLICIT_PLANE, [n[0], n[1], n[2], offset]),
    }
}

/// The first three rows of an affine matrix, as float bits.
fn rows(m: &Mat4) -> [[u32; 4]; 3] {
    [m.row(0), m.row(1), m.row(2)].map(|r| r.to_array().map(f32::to_bits))
}
