//! Reference answers that share nothing with the BVH but the triangle test: every triangle is
//! tested, in input order. To keep large scenes affordable, triangles are grouped in runs of
//! [`CHUNK`] consecutive input triangles whose box (computed in `f64` and padded) is tested
//! first; the padding makes that cull conservative, so the answer is the brute-force one.

use super::traverse::{Hit, Ray, RayPre};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Input triangles per culling box.
pub const CHUNK: usize = 64;

/// Brute force over a triangle soup with conservative per-chunk culling.
pub struct Reference<'a> {
    triangles: &'a [[Vec3; 3]],
    boxes: Vec<(DVec3, DVec3)>,
}

impl<'a> Reference<'a> {
    /// Prepares the culling boxes.
    pub fn new(triangles: &'a [[Vec3; 3]]) -> Self {
        let boxes = triangles
            .chunks(CHUNK)
            .map(|chunk| {
                let mut lo = DVec3::splat(f64::MAX);
                let mut hi = DVec3::splat(-f64::MAX);
                for v in chunk.iter().flatten() {
                    lo = lo.min(v.as_dvec3());
                    hi = hi.max(v.as_dvec3());
                }
                let pad = (hi - lo).max_element() * 1e-6 + (lo.abs().max(hi.abs())).max_element() * 1e-6;
                (lo - DVec3::splat(pad), hi + DVec3::splat(pad))
            })
            .collect();
        Self { triangles, boxes }
    }

    /// The nearest hit; `tri` is the INPUT index. Ties keep the lower index.
    pub fn closest(&self, ray: &Ray) -> Option<Hit> {
        let pre = RayPre::new(ray.origin, ray.dir);
        let mut best: Option<Hit> = None;
        for (c, b) in self.boxes.iter().enumerate() {
            let tmax = best.map_or(ray.tmax, |h| h.t);
            if !slab_f64(ray, b, tmax) {
                continue;
            }
            for (k, tri) in self.triangles[c * CHUNK..].iter().take(CHUNK).enumerate() {
                let tmax = best.map_or(ray.tmax, |h| h.t);
                if let Some((t, bary)) = pre.intersect(tri, ray.tmin, tmax) {
                    best = Some(Hit { t, tri: (c * CHUNK + k) as u32, bary });
                }
            }
        }
        best
    }

    /// Whether any triangle lies on the ray segment.
    pub fn any(&self, ray: &Ray) -> bool {
        let pre = RayPre::new(ray.origin, ray.dir);
        self.boxes.iter().enumerate().any(|(c, b)| {
            slab_f64(ray, b, ray.tmax)
                && self.triangles[c * CHUNK..]
                    .iter()
                    .take(CHUNK)
                    .any(|tri| pre.intersect(tri, ray.tmin, ray.tmax).is_some())
        })
    }

    /// [`Self::closest`] for many rays, in parallel.
    pub fn closest_all(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        rays.par_iter().map(|r| self.closest(r)).collect()
    }
}

/// Whether `got` answers a ray as `expected` does: both miss, or both hit the same triangle, or
/// (triangles tie) both hit at the same t within 1e-5 relative. `input_index` maps `got`'s
/// triangle index to `expected`'s numbering (e.g. BVH order to input order via
/// [`super::Bvh::prim_order`]).
pub fn same_hit(got: Option<Hit>, expected: Option<Hit>, input_index: impl Fn(u32) -> u32) -> bool {
    match (got, expected) {
        (None, None) => true,
        (Some(g), Some(e)) => input_index(g.tri) == e.tri || (g.t - e.t).abs() <= 1e-5 * e.t.abs(),
        _ => false,
    }
}

/// Slab test in `f64` against an already padded box, with a little extra slack in t.
fn slab_f64(ray: &Ray, (lo, hi): &(DVec3, DVec3), tmax: f32) -> bool {
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3();
    let (mut near, mut far) = (ray.tmin as f64, tmax as f64 * (1.0 + 1e-6) + 1e-30);
    for axis in 0..3 {
        if d[axis] == 0.0 {
            if o[axis] < lo[axis] || o[axis] > hi[axis] {
                return false;
            }
            continue;
        }
        let t0 = (lo[axis] - o[axis]) / d[axis];
        let t1 = (hi[axis] - o[axis]) / d[axis];
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    near <= far
}
