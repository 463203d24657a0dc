//! Implicit surfaces: signed distance functions given on glTF nodes by the vendor extension
//! `UMBRA_implicit` (schema: `docs/UMBRA_implicit.schema.json`, docs/gltf.md "Implicit surfaces").
//!
//! A node's shape is a tree of primitives (sphere, box, rounded box, torus, capsule, cylinder,
//! plane), each with its own translation, rotation and uniform scale, combined by union,
//! intersection and subtraction (smooth with a `smoothness` > 0), in the node's frame. Its
//! simplest form is `{"sphere": {"radius": R}, "material": M}`: a sphere of radius R at the
//! node's origin. Each shape has one glTF material and one world box, which enters the BVH as a
//! procedural primitive; the traversal sphere-traces the distance inside that box (`bvh.glsl`,
//! `implicit.glsl`).
//!
//! Distances: every primitive's is exact (Quilez's formulas), a uniform scale keeps it exact, and
//! the polynomial smooth minimum and maximum keep a 1-Lipschitz bound (not exact near the blend).
//! The node's world transform may scale non-uniformly: the local distance times the transform's
//! smallest singular value is then a lower bound of the world distance ([`ImplicitShape::step_scale`]),
//! which is what the marcher steps by.

use crate::error::{Error, Result};
use glam::{Mat3, Mat4, Quat, Vec3};
use gltf::json::Value;

/// The most instructions a shape's program may have (primitives plus operations).
pub const MAX_INSTRUCTIONS: usize = 32;

/// The deepest distance stack a shape's program may need (`IMPLICIT_MAX_STACK` on the GPU).
pub const MAX_STACK: usize = 8;

/// A signed distance primitive in its own frame (centred on the origin; axes along Y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Primitive {
    /// A sphere.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// An axis-aligned box.
    Box {
        /// Half its size per axis.
        half_extents: [f32; 3],
    },
    /// A box with rounded edges (`radius` inside the half extents).
    RoundedBox {
        /// Half its size per axis, the rounding included.
        half_extents: [f32; 3],
        /// Edge radius.
        radius: f32,
    },
    /// A torus around the Y axis.
    Torus {
        /// Distance from the centre to the tube's centre.
        major_radius: f32,
        /// The tube's radius.
        minor_radius: f32,
    },
    /// A capsule along Y: a segment from −h to +h, swept by a sphere.
    Capsule {
        /// Half the segment's length.
        half_height: f32,
        /// Radius.
        radius: f32,
    },
    /// A capped cylinder along Y.
    Cylinder {
        /// Half its height.
        half_height: f32,
        /// Radius.
        radius: f32,
    },
    /// The half-space below a plane: `dot(p, normal) − offset` (unbounded: only inside an
    /// intersection or subtraction with something bounded).
    Plane {
        /// Unit normal (pointing out of the solid).
        normal: [f32; 3],
        /// Signed distance of the plane from the origin along the normal.
        offset: f32,
    },
}

/// How a CSG node combines its children.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CsgOp {
    /// min.
    Union,
    /// max.
    Intersection,
    /// The first child minus every other one: max(a, −b).
    Subtraction,
}

/// A node of a shape's tree.
#[derive(Clone, Debug, PartialEq)]
pub enum SdfNode {
    /// A primitive placed by `translation · rotation · scale` (uniform scale).
    Primitive {
        /// The primitive.
        primitive: Primitive,
        /// Translation.
        translation: [f32; 3],
        /// Rotation quaternion (x, y, z, w).
        rotation: [f32; 4],
        /// Uniform scale.
        scale: f32,
    },
    /// Children combined left to right.
    Csg {
        /// The operation.
        op: CsgOp,
        /// Blend radius of the polynomial smooth minimum (0: sharp).
        smoothness: f32,
        /// At least two.
        children: Vec<SdfNode>,
    },
}

/// One implicit shape of the scene, in world space through its node's transform.
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitShape {
    /// "node 3 ('Ball')", for messages.
    pub label: String,
    /// The glTF node.
    pub node: u32,
    /// Index into the scene's materials.
    pub material: u32,
    /// The distance tree, in the node's frame.
    pub root: SdfNode,
    /// Node frame → world (column-major).
    pub world: [[f32; 4]; 4],
    /// What a local distance is multiplied by to step in world space: the world transform's
    /// smallest singular value (1 for a rigid transform, the scale for a similarity), so the step
    /// never exceeds the world distance. [`ImplicitShape::new`] sets it; a test may set it
    /// wrongly on purpose (no relaxation for a non-uniform scale) to show the marcher overshoot.
    pub step_scale: f32,
}

/// Hit threshold of the marcher relative to the shape's world box diagonal.
pub const EPSILON_RELATIVE: f32 = 2e-5;

impl Primitive {
    fn distance(&self, p: Vec3) -> f32 {
        match *self {
            Primitive::Sphere { radius } => p.length() - radius,
            Primitive::Box { half_extents } => box_distance(p, Vec3::from(half_extents)),
            Primitive::RoundedBox { half_extents, radius } => {
                box_distance(p, Vec3::from(half_extents) - radius) - radius
            }
            Primitive::Torus { major_radius, minor_radius } => {
                let q = glam::Vec2::new(glam::Vec2::new(p.x, p.z).length() - major_radius, p.y);
                q.length() - minor_radius
            }
            Primitive::Capsule { half_height, radius } => {
                let mut q = p;
                q.y -= q.y.clamp(-half_height, half_height);
                q.length() - radius
            }
            Primitive::Cylinder { half_height, radius } => {
                let d = glam::Vec2::new(glam::Vec2::new(p.x, p.z).length(), p.y).abs()
                    - glam::Vec2::new(radius, half_height);
                d.x.max(d.y).min(0.0) + d.max(glam::Vec2::ZERO).length()
            }
            Primitive::Plane { normal, offset } => p.dot(Vec3::from(normal)) - offset,
        }
    }

    /// The box in the primitive's frame (infinite for a plane).
    fn bounds(&self) -> (Vec3, Vec3) {
        let e = match *self {
            Primitive::Sphere { radius } => Vec3::splat(radius),
            Primitive::Box { half_extents } | Primitive::RoundedBox { half_extents, .. } => {
                Vec3::from(half_extents)
            }
            Primitive::Torus { major_radius, minor_radius } => {
                Vec3::new(major_radius + minor_radius, minor_radius, major_radius + minor_radius)
            }
            Primitive::Capsule { half_height, radius } => Vec3::new(radius, half_height + radius, radius),
            Primitive::Cylinder { half_height, radius } => Vec3::new(radius, half_height, radius),
            Primitive::Plane { .. } => Vec3::INFINITY,
        };
        (-e, e)
    }
}

fn box_distance(p: Vec3, b: Vec3) -> f32 {
    let q = p.abs() - b;
    q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
}

/// Polynomial smooth minimum (Quilez): min(a, b) lowered by at most k/4 where |a − b| < k.
pub fn smooth_min(a: f32, b: f32, k: f32) -> f32 {
    if k <= 0.0 {
        return a.min(b);
    }
    let h = (k - (a - b).abs()).max(0.0) / k;
    a.min(b) - h * h * k * 0.25
}

impl SdfNode {
    /// The signed distance (a lower bound where smooth) in the node's frame.
    pub fn distance(&self, p: Vec3) -> f32 {
        match self {
            SdfNode::Primitive { primitive, translation, rotation, scale } => {
                let q = Quat::from_array(*rotation).inverse() * (p - Vec3::from(*translation)) / *scale;
                scale * primitive.distance(q)
            }
            SdfNode::Csg { op, smoothness, children } => {
                let mut d = children[0].distance(p);
                for c in &children[1..] {
                    d = combine(*op, *smoothness, d, c.distance(p));
                }
                d
            }
        }
    }

    /// A box holding the surface in the node's frame (infinite where unbounded).
    fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            SdfNode::Primitive { primitive, translation, rotation, scale } => {
                let (lo, hi) = primitive.bounds();
                if !lo.is_finite() || !hi.is_finite() {
                    return (Vec3::NEG_INFINITY, Vec3::INFINITY);
                }
                let m = Mat4::from_scale_rotation_translation(
                    Vec3::splat(*scale),
                    Quat::from_array(*rotation),
                    Vec3::from(*translation),
                );
                transform_box(&m, lo, hi)
            }
            SdfNode::Csg { op, smoothness, children } => {
                // A smooth union lowers the field by at most k/4 near the blend: grow by that.
                let grow = if *smoothness > 0.0 { Vec3::splat(0.25 * smoothness) } else { Vec3::ZERO };
                let mut b = children[0].bounds();
                for c in &children[1..] {
                    let cb = c.bounds();
                    b = match op {
                        CsgOp::Union => (b.0.min(cb.0), b.1.max(cb.1)),
                        CsgOp::Intersection => (b.0.max(cb.0), b.1.min(cb.1)),
                        CsgOp::Subtraction => b,
                    };
                }
                (b.0 - grow, b.1 + grow)
            }
        }
    }

    /// Whether the shape is empty everywhere, as far as a 33³ grid of points over its box tells:
    /// its box is empty (an intersection of disjoint parts), or at every point the distance (a
    /// lower bound of the true one) exceeds half a cell's diagonal, so that balls holding no
    /// surface cover the box. A shape with any solid part is never called empty; an empty one
    /// whose field comes closer to 0 than the grid's spacing may pass as not empty.
    pub fn is_empty(&self) -> bool {
        let (lo, hi) = self.bounds();
        if !(lo.is_finite() && hi.is_finite()) {
            return false;
        }
        if lo.cmpgt(hi).any() {
            return true;
        }
        const N: u32 = 32;
        let step = (hi - lo) / N as f32;
        let reach = 0.5 * step.length();
        let grid = (0..=N).flat_map(|i| (0..=N).flat_map(move |j| (0..=N).map(move |k| (i, j, k))));
        grid.map(|(i, j, k)| lo + step * Vec3::new(i as f32, j as f32, k as f32))
            .all(|p| self.distance(p) > reach)
    }

    /// The stack depth its postfix program needs.
    pub fn stack_depth(&self) -> usize {
        match self {
            SdfNode::Primitive { .. } => 1,
            SdfNode::Csg { children, .. } => {
                children[1..].iter().fold(children[0].stack_depth(), |d, c| d.max(1 + c.stack_depth()))
            }
        }
    }

    /// Its primitives and operations: the length of its postfix program.
    pub fn instructions(&self) -> usize {
        match self {
            SdfNode::Primitive { .. } => 1,
            SdfNode::Csg { children, .. } => {
                children.iter().map(SdfNode::instructions).sum::<usize>() + children.len() - 1
            }
        }
    }
}

/// `a` and `b` combined by `op` (smooth with `k` > 0).
pub fn combine(op: CsgOp, k: f32, a: f32, b: f32) -> f32 {
    match op {
        CsgOp::Union => smooth_min(a, b, k),
        CsgOp::Intersection => -smooth_min(-a, -b, k),
        CsgOp::Subtraction => -smooth_min(-a, b, k),
    }
}

fn transform_box(m: &Mat4, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let mut out = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let p = m.transform_point3(c);
        out = (out.0.min(p), out.1.max(p));
    }
    out
}

impl ImplicitShape {
    /// A shape placed by `world`, its step scale from the transform's singular values.
    pub fn new(label: String, node: u32, material: u32, root: SdfNode, world: Mat4) -> Self {
        Self {
            label,
            node,
            material,
            root,
            world: world.to_cols_array_2d(),
            step_scale: min_singular_value(&world),
        }
    }

    /// A lower bound of the distance from world point `p` to the surface (negative inside), as
    /// the marcher steps by it.
    pub fn distance(&self, p: Vec3) -> f32 {
        let world = Mat4::from_cols_array_2d(&self.world);
        self.step_scale * self.root.distance(world.inverse().transform_point3(p))
    }

    /// The world box of the surface, padded by a few hit thresholds; `None` if unbounded.
    pub fn world_bounds(&self) -> Option<(Vec3, Vec3)> {
        let (lo, hi) = self.root.bounds();
        if !lo.is_finite() || !hi.is_finite() || lo.cmpgt(hi).any() {
            return None;
        }
        let (lo, hi) = transform_box(&Mat4::from_cols_array_2d(&self.world), lo, hi);
        let pad = 4.0 * self.epsilon_for(lo, hi);
        Some((lo - pad, hi + pad))
    }

    /// The marcher's hit threshold (world units): [`EPSILON_RELATIVE`] of the box's diagonal.
    pub fn epsilon(&self) -> f32 {
        let (lo, hi) = self.root.bounds();
        let (lo, hi) = transform_box(&Mat4::from_cols_array_2d(&self.world), lo, hi);
        self.epsilon_for(lo, hi)
    }

    fn epsilon_for(&self, lo: Vec3, hi: Vec3) -> f32 {
        (EPSILON_RELATIVE * (hi - lo).length()).max(1e-7)
    }
}

/// The smallest singular value of `m`'s linear part.
fn min_singular_value(m: &Mat4) -> f32 {
    let a = Mat3::from_mat4(*m);
    let ata = a.transpose() * a;
    // Eigenvalues of a symmetric 3×3 (Smith's closed form).
    let trace = ata.x_axis.x + ata.y_axis.y + ata.z_axis.z;
    let (p1, q) = (ata.x_axis.y.powi(2) + ata.x_axis.z.powi(2) + ata.y_axis.z.powi(2), trace / 3.0);
    let d = [ata.x_axis.x, ata.y_axis.y, ata.z_axis.z];
    if p1 <= 1e-12 * q * q {
        return d.iter().copied().fold(f32::INFINITY, f32::min).max(0.0).sqrt();
    }
    let p2 = d.iter().map(|x| (x - q).powi(2)).sum::<f32>() + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = (ata - Mat3::from_diagonal(Vec3::splat(q))) * (1.0 / p);
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f32::consts::PI / 3.0).cos();
    smallest.max(0.0).sqrt()
}

/// Reads a node's `UMBRA_implicit` object: the shape tree and the material index (`None`: the
/// glTF default material). Errors say what is wrong and where in the object (`at`).
pub fn parse(value: &Value, materials: usize) -> std::result::Result<(SdfNode, Option<usize>), String> {
    let object = value.as_object().ok_or("must be an object")?;
    let material = match object.get("material") {
        None => None,
        Some(m) => {
            let i = m.as_u64().ok_or("'material' must be a non-negative integer")? as usize;
            if i >= materials {
                return Err(format!("'material' is {i}, but the file has {materials} material(s)"));
            }
            Some(i)
        }
    };
    let root = parse_node(value, "UMBRA_implicit", true)?;
    let count = root.instructions();
    if count > MAX_INSTRUCTIONS {
        return Err(format!("the shape has {count} primitives and operations; at most {MAX_INSTRUCTIONS}"));
    }
    let depth = root.stack_depth();
    if depth > MAX_STACK {
        return Err(format!(
            "the shape nests {depth} levels deep; the marcher's stack holds {MAX_STACK} (flatten the tree)"
        ));
    }
    let (lo, hi) = root.bounds();
    if !lo.is_finite() || !hi.is_finite() {
        return Err("the shape is unbounded: a plane must be intersected with or subtracted from \
                    something bounded"
            .into());
    }
    if lo.cmpgt(hi).any() {
        return Err("the shape is empty (an intersection of disjoint parts)".into());
    }
    Ok((root, material))
}

const PRIMITIVES: [&str; 7] = ["sphere", "box", "roundedBox", "torus", "capsule", "cylinder", "plane"];
const OPERATIONS: [&str; 3] = ["union", "intersection", "subtraction"];

fn parse_node(value: &Value, at: &str, top: bool) -> std::result::Result<SdfNode, String> {
    let object = value.as_object().ok_or(format!("{at} must be an object"))?;
    let allowed: &[&str] =
        if top { &["material", "smoothness"] } else { &["translation", "rotation", "scale", "smoothness"] };
    let kinds: Vec<&String> = object
        .keys()
        .filter(|k| PRIMITIVES.contains(&k.as_str()) || OPERATIONS.contains(&k.as_str()))
        .collect();
    if let Some(unknown) = object.keys().find(|k| {
        !PRIMITIVES.contains(&k.as_str())
            && !OPERATIONS.contains(&k.as_str())
            && !allowed.contains(&k.as_str())
            && k.as_str() != "extras"
    }) {
        return Err(format!("{at}: unknown property '{unknown}'"));
    }
    let kind = match kinds.as_slice() {
        [one] => one.as_str(),
        [] => {
            return Err(format!(
                "{at} names no shape: give one of {} or {}",
                PRIMITIVES.join(", "),
                OPERATIONS.join(", ")
            ))
        }
        many => {
            return Err(format!(
                "{at} names {} shapes ({}); give exactly one",
                many.len(),
                many.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
            ))
        }
    };
    let here = format!("{at}.{kind}");
    if OPERATIONS.contains(&kind) {
        let op = match kind {
            "union" => CsgOp::Union,
            "intersection" => CsgOp::Intersection,
            _ => CsgOp::Subtraction,
        };
        let smoothness = optional_number(object.get("smoothness"), &format!("{at}.smoothness"), 0.0)?;
        if smoothness < 0.0 {
            return Err(format!("{at}.smoothness must be at least 0, not {smoothness}"));
        }
        if let Some(key) = ["translation", "rotation", "scale"].iter().find(|k| object.contains_key(**k)) {
            return Err(format!(
                "{at}.{key}: only primitives are placed (move the shapes inside the {kind})"
            ));
        }
        let list = object[kind].as_array().ok_or(format!("{here} must be an array of shapes"))?;
        if list.len() < 2 {
            return Err(format!("{here} needs at least two shapes, not {}", list.len()));
        }
        let children = list
            .iter()
            .enumerate()
            .map(|(i, c)| parse_node(c, &format!("{here}[{i}]"), false))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        return Ok(SdfNode::Csg { op, smoothness, children });
    }
    if top && object.contains_key("smoothness") {
        return Err(format!("{at}.smoothness belongs to a union, intersection or subtraction"));
    }
    let params = object[kind].as_object().ok_or(format!("{here} must be an object"))?;
    let positive = |name: &str| -> std::result::Result<f32, String> {
        let v = number(params.get(name), &format!("{here}.{name}"))?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(format!("{here}.{name} must be positive, not {v}"))
        }
    };
    let primitive = match kind {
        "sphere" => Primitive::Sphere { radius: positive("radius")? },
        "box" => Primitive::Box {
            half_extents: positive_vec3(params.get("halfExtents"), &format!("{here}.halfExtents"))?,
        },
        "roundedBox" => {
            let half_extents = positive_vec3(params.get("halfExtents"), &format!("{here}.halfExtents"))?;
            let radius = positive("radius")?;
            if half_extents.iter().any(|&e| radius > e) {
                return Err(format!("{here}.radius ({radius}) exceeds a half extent {half_extents:?}"));
            }
            Primitive::RoundedBox { half_extents, radius }
        }
        "torus" => Primitive::Torus {
            major_radius: positive("majorRadius")?,
            minor_radius: positive("minorRadius")?,
        },
        "capsule" => Primitive::Capsule { half_height: positive("halfHeight")?, radius: positive("radius")? },
        "cylinder" => {
            Primitive::Cylinder { half_height: positive("halfHeight")?, radius: positive("radius")? }
        }
        _ => {
            let n = vec3(params.get("normal"), &format!("{here}.normal"))?;
            let len = Vec3::from(n).length();
            if len <= 0.0 {
                return Err(format!("{here}.normal must not be zero"));
            }
            let offset = optional_number(params.get("offset"), &format!("{here}.offset"), 0.0)?;
            Primitive::Plane { normal: (Vec3::from(n) / len).to_array(), offset }
        }
    };
    let translation = match object.get("translation") {
        Some(v) => vec3(Some(v), &format!("{at}.translation"))?,
        None => [0.0; 3],
    };
    let rotation = match object.get("rotation") {
        Some(v) => {
            let q = numbers::<4>(Some(v), &format!("{at}.rotation"))?;
            let q = Quat::from_array(q);
            if q.length() <= 0.0 {
                return Err(format!("{at}.rotation must be a non-zero quaternion"));
            }
            q.normalize().to_array()
        }
        None => [0.0, 0.0, 0.0, 1.0],
    };
    let scale = optional_number(object.get("scale"), &format!("{at}.scale"), 1.0)?;
    if scale <= 0.0 {
        return Err(format!("{at}.scale must be a positive number (uniform scale), not {scale}"));
    }
    Ok(SdfNode::Primitive { primitive, translation, rotation, scale })
}

fn number(v: Option<&Value>, at: &str) -> std::result::Result<f32, String> {
    let v = v.ok_or(format!("{at} is missing"))?;
    let x = v.as_f64().ok_or(format!("{at} must be a number"))? as f32;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("{at} must be finite"))
    }
}

fn optional_number(v: Option<&Value>, at: &str, default: f32) -> std::result::Result<f32, String> {
    match v {
        None => Ok(default),
        some => number(some, at),
    }
}

fn numbers<const N: usize>(v: Option<&Value>, at: &str) -> std::result::Result<[f32; N], String> {
    let list = v
        .ok_or(format!("{at} is missing"))?
        .as_array()
        .ok_or(format!("{at} must be an array of {N} numbers"))?;
    if list.len() != N {
        return Err(format!("{at} must have {N} numbers, not {}", list.len()));
    }
    let mut out = [0.0; N];
    for (i, x) in list.iter().enumerate() {
        out[i] = number(Some(x), &format!("{at}[{i}]"))?;
    }
    Ok(out)
}

fn vec3(v: Option<&Value>, at: &str) -> std::result::Result<[f32; 3], String> {
    numbers::<3>(v, at)
}

fn positive_vec3(v: Option<&Value>, at: &str) -> std::result::Result<[f32; 3], String> {
    let e = vec3(v, at)?;
    if e.iter().all(|&x| x > 0.0) {
        Ok(e)
    } else {
        Err(format!("{at} must be positive, not {e:?}"))
    }
}

/// [`parse`] for a shape given in code (tests, tools): errors as [`Error::Invalid`].
pub fn from_json(label: &str, value: &Value, world: Mat4, materials: usize) -> Result<ImplicitShape> {
    let (root, material) =
        parse(value, materials).map_err(|e| Error::Invalid(format!("{label}: UMBRA_implicit: {e}")))?;
    Ok(ImplicitShape::new(label.into(), 0, material.unwrap_or(0) as u32, root, world))
}
