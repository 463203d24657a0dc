//! CPU traversal: the watertight ray/triangle test of `spirv/include/bvh.glsl` operation for
//! operation (Woop, Benthin and Wald 2013), so rays along shared edges and through shared
//! vertices never slip between triangles, and a robust slab test (Ize 2013) on the binary BVH's
//! exact boxes (the GPU's boxes are quantized, its slab test widened to match).

use super::{Bvh, BvhNode, BvhTri, MAX_DEPTH};
use glam::Vec3;

/// A ray segment: points `origin + t * dir` with `tmin < t < tmax`. `dir` need not be unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (not necessarily normalised; t is in its units).
    pub dir: Vec3,
    /// Smallest accepted t (exclusive).
    pub tmin: f32,
    /// Largest accepted t (exclusive).
    pub tmax: f32,
}

/// The nearest intersection found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray in units of `dir`.
    pub t: f32,
    /// Triangle index in the BVH's (leaf) order.
    pub tri: u32,
    /// Barycentric weights of the second and third vertices.
    pub bary: [f32; 2],
}

/// Direction components smaller than this are replaced by it (with their sign) in the slab test,
/// so `0 * inf` never makes a NaN. Matches `BVH_DIR_EPS` in `bvh.glsl`.
pub const DIR_EPS: f32 = 1e-20;

/// The slab test's far distance is scaled by this (1 + 2γ₃ rounded up, Ize 2013) so rounding
/// never culls a box the ray touches. Matches `BVH_SLAB_ROBUST` in `bvh.glsl`.
pub const SLAB_ROBUST: f32 = 1.0 + 1.0 / 1048576.0;

/// Per-ray constants of the watertight test and the slab test.
#[derive(Clone, Copy, Debug)]
pub struct RayPre {
    origin: Vec3,
    inv_dir: Vec3,
    /// The axes the direction is parallel to (components below `DIR_EPS`).
    parallel: glam::BVec3,
    k: [usize; 3],
    shear: Vec3,
}

impl RayPre {
    /// Precomputes the shear transform that maps `dir` onto +z (the axis of its largest
    /// component, with x and y swapped where that keeps the winding).
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = Vec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        let nudged = Vec3::select(a.cmplt(Vec3::splat(DIR_EPS)), Vec3::splat(DIR_EPS).copysign(dir), dir);
        Self {
            origin,
            inv_dir: nudged.recip(),
            parallel: a.cmplt(Vec3::splat(DIR_EPS)),
            k: [kx, ky, kz],
            shear,
        }
    }

    /// The watertight test: `Some((t, [b1, b2]))` when the ray meets the triangle with
    /// `tmin < t < tmax`. Triangles seen edge-on (zero determinant) are missed.
    pub fn intersect(&self, tri: &[Vec3; 3], tmin: f32, tmax: f32) -> Option<(f32, [f32; 2])> {
        let [kx, ky, kz] = self.k;
        let s = self.shear;
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
        let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
        let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let big_t = u * (s.z * a[kz]) + v * (s.z * b[kz]) + w * (s.z * c[kz]);
        let t = big_t / det;
        if !(t > tmin && t < tmax) {
            return None;
        }
        Some((t, [v / det, w / det]))
    }

    /// The robust slab test: the entry distance when the ray meets the box within
    /// `[tmin, tmax]`, `f32::INFINITY` otherwise.
    pub fn slab(&self, node: &BvhNode, tmin: f32, tmax: f32) -> f32 {
        let t0 = (Vec3::from(node.aabb_min) - self.origin) * self.inv_dir;
        let t1 = (Vec3::from(node.aabb_max) - self.origin) * self.inv_dir;
        // A ray parallel to an axis and on one of the box's planes there stays on it: its 0 on
        // that axis is neither an entry nor an exit (the triangle test hits the box's edges).
        let zero = |t: Vec3| self.parallel & t.cmpeq(Vec3::ZERO);
        let (near3, far3) = (t0.min(t1), t0.max(t1));
        let near3 = Vec3::select(zero(near3), Vec3::NEG_INFINITY, near3);
        let far3 = Vec3::select(zero(far3), Vec3::INFINITY, far3);
        let near = near3.max_element().max(tmin);
        // tmax is scaled too: a box whose entry rounds just past the nearest hit so far (a hit on
        // the box's face, as on every axis-aligned wall) is still visited, for its equally near
        // hits and the tie rule of `closest`.
        let far = far3.min_element().min(tmax) * SLAB_ROBUST;
        if near <= far {
            near
        } else {
            f32::INFINITY
        }
    }
}

/// The next float above a finite `x` (`f32::next_up`, stable only from Rust 1.86; `bvh_next_up` in
/// `bvh.glsl`).
pub(crate) fn next_up(x: f32) -> f32 {
    let bits = x.to_bits();
    if x > 0.0 {
        f32::from_bits(bits + 1)
    } else if x == 0.0 {
        f32::from_bits(1)
    } else {
        f32::from_bits(bits - 1)
    }
}

impl Bvh {
    /// The nearest hit of `ray`, and of equally near ones the first in the input, as
    /// `bvh_closest` in `bvh.glsl` finds it (the GPU walks another layout in another order; the
    /// tie rule makes the answer independent of the order).
    pub fn closest(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut best_order = u32::MAX;
        let mut tmax = ray.tmax;
        self.walk(ray, |pre, tri, index, tmin| {
            let order = tri.v0[3].to_bits();
            // After a hit, one equally near with a lower input index replaces it.
            let limit = if best.is_some() { next_up(tmax) } else { tmax };
            if let Some((t, bary)) = pre.intersect(&tri.vertices(), tmin, limit) {
                if t < tmax || order < best_order {
                    tmax = t;
                    best_order = order;
                    best = Some(Hit { t, tri: index, bary });
                }
            }
            (false, tmax)
        });
        best
    }

    /// Whether anything lies on `ray` between `tmin` and `tmax` (`bvh_any` in `bvh.glsl`).
    pub fn any(&self, ray: &Ray) -> bool {
        let mut found = false;
        self.walk(ray, |pre, tri, _, tmin| {
            found = pre.intersect(&tri.vertices(), tmin, ray.tmax).is_some();
            (found, ray.tmax)
        });
        found
    }

    /// Front-to-back traversal; `visit` tests one triangle and returns (stop, current tmax).
    fn walk(&self, ray: &Ray, mut visit: impl FnMut(&RayPre, &BvhTri, u32, f32) -> (bool, f32)) {
        let root = &self.nodes[0];
        if root.tri_count == 0 && root.aabb_min[0] > root.aabb_max[0] {
            return;
        }
        let pre = RayPre::new(ray.origin, ray.dir);
        let mut tmax = ray.tmax;
        let mut stack = [0u32; MAX_DEPTH];
        let mut sp = 0;
        let mut node = root;
        loop {
            if node.is_leaf() {
                for i in node.left_first..node.left_first + node.tri_count {
                    let (stop, t) = visit(&pre, &self.tris[i as usize], i, ray.tmin);
                    if stop {
                        return;
                    }
                    tmax = t;
                }
                if sp == 0 {
                    return;
                }
                sp -= 1;
                node = &self.nodes[stack[sp] as usize];
                continue;
            }
            let mut near = node.left_first;
            let mut far = near + 1;
            let mut d_near = pre.slab(&self.nodes[near as usize], ray.tmin, tmax);
            let mut d_far = pre.slab(&self.nodes[far as usize], ray.tmin, tmax);
            if d_near > d_far {
                std::mem::swap(&mut near, &mut far);
                std::mem::swap(&mut d_near, &mut d_far);
            }
            if d_near == f32::INFINITY {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                node = &self.nodes[stack[sp] as usize];
            } else {
                node = &self.nodes[near as usize];
                if d_far != f32::INFINITY {
                    stack[sp] = far;
                    sp += 1;
                }
            }
        }
    }
}
