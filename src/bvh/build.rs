//! Top-down SAH build: binned (the default) or full sweep (the quality reference), parallel over
//! subtrees with `rayon`, then flattened depth-first into sibling pairs.

use super::{Bvh, BvhNode, BvhStats, BvhTri, MAX_DEPTH};
use glam::{Vec3, Vec3A};
use std::time::Instant;

/// How a BVH is built.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildOptions {
    /// Bins per axis for the binned SAH.
    pub bins: usize,
    /// Largest leaf the SAH may choose; larger sets are always split (unless they cannot be).
    pub max_leaf_size: usize,
    /// SAH cost of one node visit.
    pub traversal_cost: f32,
    /// SAH cost of one triangle test.
    pub intersection_cost: f32,
    /// Evaluate every split position (sorting per node) instead of binning: slow, the quality
    /// reference for the binned build.
    pub full_sweep: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self { bins: 16, max_leaf_size: 4, traversal_cost: 1.0, intersection_cost: 1.0, full_sweep: false }
    }
}

/// Nodes with fewer primitives than this are built on the current thread.
const PARALLEL_THRESHOLD: usize = 4096;

#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: Vec3A,
    max: Vec3A,
}

impl Aabb {
    const EMPTY: Self = Self { min: Vec3A::splat(f32::MAX), max: Vec3A::splat(-f32::MAX) };

    fn grow(&mut self, other: &Aabb) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
    }

    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// Half the surface area (the SAH only needs ratios); 0 for an empty box.
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// A primitive as the builder sees it.
struct Prim {
    bounds: Aabb,
    centroid: Vec3A,
}

/// The tree before flattening.
enum Node {
    Leaf { bounds: Aabb, first: usize, count: usize },
    Interior { bounds: Aabb, children: Box<[Node; 2]> },
}

impl Node {
    fn bounds(&self) -> &Aabb {
        match self {
            Node::Leaf { bounds, .. } | Node::Interior { bounds, .. } => bounds,
        }
    }
}

/// A chosen split: primitives whose key is below `position` on `axis` go left.
struct Split {
    axis: usize,
    cost: f32,
    kind: SplitKind,
}

enum SplitKind {
    /// Binned: left takes bins `0..bin`.
    Bin { bin: usize, scale: f32, origin: f32 },
    /// Sweep: left takes the first `count` primitives in centroid order.
    Sorted { count: usize },
}

struct Builder<'a> {
    prims: &'a [Prim],
    options: &'a BuildOptions,
}

pub(super) fn build(triangles: &[[Vec3; 3]], options: &BuildOptions) -> Bvh {
    let start = Instant::now();
    if triangles.is_empty() {
        return Bvh::empty();
    }
    let prims: Vec<Prim> = triangles
        .iter()
        .map(|t| {
            let mut bounds = Aabb::EMPTY;
            for v in t {
                bounds.grow_point((*v).into());
            }
            Prim { bounds, centroid: (bounds.min + bounds.max) * 0.5 }
        })
        .collect();
    let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
    let builder = Builder { prims: &prims, options };
    let root_bounds = prims.iter().fold(Aabb::EMPTY, |mut b, p| {
        b.grow(&p.bounds);
        b
    });
    let root = builder.node(&mut order, 0, root_bounds, 0);

    let mut nodes = vec![BvhNode::default(); 2];
    flatten(&root, 0, &mut nodes);
    let tris = order.iter().map(|&i| BvhTri::new(&triangles[i as usize], i)).collect();
    let mut bvh = Bvh { nodes, tris, prim_order: order, stats: BvhStats::default() };
    bvh.stats = stats(&bvh, options);
    bvh.stats.build_ms = start.elapsed().as_secs_f64() * 1e3;
    bvh
}

impl Builder<'_> {
    /// Builds the subtree over `order` (whose first element is primitive `first` of the final
    /// order) with the given bounds.
    fn node(&self, order: &mut [u32], first: usize, bounds: Aabb, depth: usize) -> Node {
        let count = order.len();
        let leaf = Node::Leaf { bounds, first, count };
        if count == 1 || depth + 1 >= MAX_DEPTH {
            return leaf;
        }
        let leaf_cost = self.options.intersection_cost * count as f32;
        let split = match self.options.full_sweep {
            false => self.best_binned(order),
            true => self.best_sweep(order),
        };
        let split_cost = split.as_ref().map_or(f32::INFINITY, |s| {
            self.options.traversal_cost + s.cost / bounds.half_area().max(f32::MIN_POSITIVE)
        });
        if count <= self.options.max_leaf_size && leaf_cost <= split_cost {
            return leaf;
        }
        let left_count = match &split {
            Some(split) => self.partition(order, split),
            // All centroids coincide: any split is as good as any other.
            None => count / 2,
        };
        let left_count = if left_count == 0 || left_count == count { count / 2 } else { left_count };
        let (left, right) = order.split_at_mut(left_count);
        let lb = self.bounds_of(left);
        let rb = self.bounds_of(right);
        let (l, r) = if count >= PARALLEL_THRESHOLD {
            rayon::join(
                || self.node(left, first, lb, depth + 1),
                || self.node(right, first + left_count, rb, depth + 1),
            )
        } else {
            (self.node(left, first, lb, depth + 1), self.node(right, first + left_count, rb, depth + 1))
        };
        Node::Interior { bounds, children: Box::new([l, r]) }
    }

    fn bounds_of(&self, order: &[u32]) -> Aabb {
        order.iter().fold(Aabb::EMPTY, |mut b, &i| {
            b.grow(&self.prims[i as usize].bounds);
            b
        })
    }

    /// The cheapest binned split over all three axes (its cost as the unnormalised
    /// `area(L)·n(L) + area(R)·n(R)` times the intersection cost), or `None` when the centroids
    /// do not spread on any axis.
    fn best_binned(&self, order: &[u32]) -> Option<Split> {
        let bins = self.options.bins;
        let mut centroid_bounds = Aabb::EMPTY;
        for &i in order {
            centroid_bounds.grow_point(self.prims[i as usize].centroid);
        }
        let extent = centroid_bounds.max - centroid_bounds.min;
        let origin = centroid_bounds.min;
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins as f32 * (1.0 - f32::EPSILON)) / extent,
            Vec3A::ZERO,
        );
        let mut bin_bounds = vec![[Aabb::EMPTY; 3]; bins];
        let mut bin_count = vec![[0u32; 3]; bins];
        for &i in order {
            let prim = &self.prims[i as usize];
            let b = ((prim.centroid - origin) * scale).to_array();
            for axis in 0..3 {
                let bin = (b[axis] as usize).min(bins - 1);
                bin_bounds[bin][axis].grow(&prim.bounds);
                bin_count[bin][axis] += 1;
            }
        }
        let mut best: Option<Split> = None;
        let mut right_area = vec![0.0f32; bins];
        let mut right_count = vec![0u32; bins];
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let (mut acc, mut n) = (Aabb::EMPTY, 0);
            for bin in (1..bins).rev() {
                acc.grow(&bin_bounds[bin][axis]);
                n += bin_count[bin][axis];
                right_area[bin] = acc.half_area();
                right_count[bin] = n;
            }
            let (mut acc, mut n) = (Aabb::EMPTY, 0);
            for bin in 1..bins {
                acc.grow(&bin_bounds[bin - 1][axis]);
                n += bin_count[bin - 1][axis];
                if n == 0 || right_count[bin] == 0 {
                    continue;
                }
                let cost = self.options.intersection_cost
                    * (acc.half_area() * n as f32 + right_area[bin] * right_count[bin] as f32);
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split {
                        axis,
                        cost,
                        kind: SplitKind::Bin { bin, scale: scale[axis], origin: origin[axis] },
                    });
                }
            }
        }
        best
    }

    /// The cheapest split between consecutive primitives in centroid order on any axis.
    fn best_sweep(&self, order: &[u32]) -> Option<Split> {
        let n = order.len();
        let mut sorted = order.to_vec();
        let mut right_area = vec![0.0f32; n];
        let mut best: Option<Split> = None;
        for axis in 0..3 {
            sorted.sort_unstable_by(|&a, &b| self.key(a, axis).total_cmp(&self.key(b, axis)));
            if self.key(sorted[0], axis) == self.key(sorted[n - 1], axis) {
                continue;
            }
            let mut acc = Aabb::EMPTY;
            for k in (1..n).rev() {
                acc.grow(&self.prims[sorted[k] as usize].bounds);
                right_area[k] = acc.half_area();
            }
            let mut acc = Aabb::EMPTY;
            for k in 1..n {
                acc.grow(&self.prims[sorted[k - 1] as usize].bounds);
                let cost = self.options.intersection_cost
                    * (acc.half_area() * k as f32 + right_area[k] * (n - k) as f32);
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split { axis, cost, kind: SplitKind::Sorted { count: k } });
                }
            }
        }
        best
    }

    fn key(&self, prim: u32, axis: usize) -> f32 {
        self.prims[prim as usize].centroid[axis]
    }

    /// Reorders `order` so the left side of `split` comes first; returns its size.
    fn partition(&self, order: &mut [u32], split: &Split) -> usize {
        match split.kind {
            SplitKind::Bin { bin, scale, origin } => {
                let bins = self.options.bins;
                let goes_left = |i: &u32| {
                    let c = self.key(*i, split.axis);
                    (((c - origin) * scale) as usize).min(bins - 1) < bin
                };
                partition_in_place(order, goes_left)
            }
            SplitKind::Sorted { count } => {
                order.sort_unstable_by(|&a, &b| {
                    self.key(a, split.axis).total_cmp(&self.key(b, split.axis)).then(a.cmp(&b))
                });
                count
            }
        }
    }
}

fn partition_in_place(order: &mut [u32], goes_left: impl Fn(&u32) -> bool) -> usize {
    let mut left = 0;
    for i in 0..order.len() {
        if goes_left(&order[i]) {
            order.swap(i, left);
            left += 1;
        }
    }
    left
}

/// Writes `node` at `index`, allocating each pair of children at the end (at even indices).
fn flatten(node: &Node, index: usize, nodes: &mut Vec<BvhNode>) {
    let b = node.bounds();
    let (min, max) = (Vec3::from(b.min).into(), Vec3::from(b.max).into());
    match node {
        Node::Leaf { first, count, .. } => {
            nodes[index] =
                BvhNode { aabb_min: min, left_first: *first as u32, aabb_max: max, tri_count: *count as u32 };
        }
        Node::Interior { children, .. } => {
            let left = nodes.len();
            nodes.resize(left + 2, BvhNode::default());
            nodes[index] = BvhNode { aabb_min: min, left_first: left as u32, aabb_max: max, tri_count: 0 };
            flatten(&children[0], left, nodes);
            flatten(&children[1], left + 1, nodes);
        }
    }
}

fn stats(bvh: &Bvh, options: &BuildOptions) -> BvhStats {
    let root_area = bvh.nodes[0].surface_area().max(f32::MIN_POSITIVE);
    let mut s = BvhStats { triangles: bvh.tris.len(), ..Default::default() };
    let mut cost = 0.0f64;
    let mut stack = vec![(0usize, 0usize)];
    while let Some((index, depth)) = stack.pop() {
        let node = &bvh.nodes[index];
        let area = (node.surface_area() / root_area) as f64;
        s.nodes += 1;
        s.depth = s.depth.max(depth);
        if node.is_leaf() {
            s.leaves += 1;
            s.max_leaf_size = s.max_leaf_size.max(node.tri_count as usize);
            cost += area * options.intersection_cost as f64 * node.tri_count as f64;
        } else {
            cost += area * options.traversal_cost as f64;
            let l = node.left_first as usize;
            stack.extend([(l, depth + 1), (l + 1, depth + 1)]);
        }
    }
    s.mean_leaf_size = s.triangles as f32 / s.leaves.max(1) as f32;
    s.sah_cost = cost as f32;
    s
}
