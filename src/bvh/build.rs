//! Top-down SAH build: binned (the default) or full sweep (the quality reference), over triangle
//! references that early split clipping and spatial splits may add, parallel over subtrees with
//! `rayon`, then flattened depth-first into sibling pairs.

use super::{Bvh, BvhNode, BvhStats, BvhTri, MAX_DEPTH};
use glam::{Vec3, Vec3A};
use rayon::prelude::*;
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
    /// Early split clipping (Ernst and Greiner 2007): a triangle whose box has more than this
    /// many times the mean box surface area is clipped into pieces (halving the longest axis of
    /// the piece's box) until each piece's box is below that, and the build sees the pieces'
    /// tighter boxes; each piece becomes a reference to the same triangle. At most a
    /// `1/presplit` share of the triangles is large enough (Markov's inequality), so the extra
    /// references stay bounded. 0 disables it.
    pub presplit: f32,
    /// Spatial splits (Stich, Friedrich and Dietrich 2009, "SBVH"): where the best object
    /// split's two boxes overlap by more than [`SPATIAL_OVERLAP`] of the root's area (and
    /// [`SPATIAL_NODE_OVERLAP`] of the node's), the build
    /// also bins the node's triangles clipped into slabs along each axis and may split them at a
    /// plane, a triangle that crosses it becoming a reference on each side (unless keeping it
    /// whole on one side is cheaper). The extra references are bounded by this share of the
    /// input's references (0.5: at most half as many again); 0 disables it.
    pub spatial: f32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            bins: 16,
            max_leaf_size: 4,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            full_sweep: false,
            presplit: 8.0,
            spatial: 0.5,
        }
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

/// A primitive's box, moved with its input index as the builder partitions.
#[derive(Clone, Copy)]
struct PrimRef {
    min: Vec3A,
    max: Vec3A,
}

impl PrimRef {
    /// Twice the centroid (the builder only compares and bins it).
    fn centroid2(&self) -> Vec3A {
        self.min + self.max
    }

    fn aabb(&self) -> Aabb {
        Aabb { min: self.min, max: self.max }
    }
}

impl From<Aabb> for PrimRef {
    fn from(b: Aabb) -> Self {
        Self { min: b.min, max: b.max }
    }
}

/// A chosen split, with its unnormalised cost `area(L)·n(L) + area(R)·n(R)` (times the
/// intersection cost).
struct Split {
    axis: usize,
    cost: f32,
    kind: SplitKind,
}

enum SplitKind {
    /// Binned: left takes bins `0..bin` of `bin_of`; `boxes` are the two sides' bounds.
    Bin { bin: usize, binning: Binning, boxes: [Aabb; 2] },
    /// Spatial: references below `plane` on the axis go left, above it right, and those that
    /// cross it are clipped into a piece on each side (or kept whole on one side).
    Spatial { plane: f32 },
    /// Sweep: left takes the first `count` primitives in the centroid order that the sweep
    /// left in its `sorted` output.
    Sorted { count: usize },
}

/// Nodes this small are split by an exact sweep (cheaper than binning them, and better).
const SMALL: usize = 12;

/// The most bins per axis.
pub const MAX_BINS: usize = 32;

/// Maps a (doubled) centroid to a bin on each axis.
#[derive(Clone, Copy)]
struct Binning {
    origin: Vec3A,
    scale: Vec3A,
    bins: usize,
}

impl Binning {
    /// `bins` equal bins per axis over the box `min`..`max` (one bin on an axis without extent).
    fn new(min: Vec3A, max: Vec3A, bins: usize) -> Self {
        let extent = max - min;
        let scale = Vec3A::select(
            extent.cmpgt(Vec3A::ZERO),
            Vec3A::splat(bins as f32 * (1.0 - f32::EPSILON)) / extent,
            Vec3A::ZERO,
        );
        Self { origin: min, scale, bins }
    }

    /// The bin of `c2` on each axis. Clamped to the last bin as a float and converted to `i32`
    /// with all three lanes at once: a saturating `f32 as usize` per axis costs several
    /// instructions each (`c2 - origin` is never negative, so the result is never below 0).
    fn bins_of(&self, c2: Vec3A) -> [usize; 3] {
        let last = Vec3A::splat((self.bins - 1) as f32);
        let b = ((c2 - self.origin) * self.scale).min(last).as_ivec3();
        [b.x as usize, b.y as usize, b.z as usize]
    }

    /// Whether `c2` falls in a bin below `bin` on `axis` (`bins_of(c2)[axis] < bin`, compared
    /// as floats: for a whole number `bin`, `floor(b) < bin` exactly when `b < bin`).
    fn below(&self, c2: Vec3A, axis: usize, bin: usize) -> bool {
        (c2[axis] - self.origin[axis]) * self.scale[axis] < bin as f32
    }

    /// Where bin `bin` begins on `axis` (for bins over points rather than doubled centroids).
    fn plane(&self, axis: usize, bin: usize) -> f32 {
        self.origin[axis] + bin as f32 / self.scale[axis]
    }
}

/// Per-axis bin boxes and counts.
#[derive(Clone)]
struct Bins {
    min: [[Vec3A; MAX_BINS]; 3],
    max: [[Vec3A; MAX_BINS]; 3],
    count: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Self {
        Self {
            min: [[Vec3A::splat(f32::MAX); MAX_BINS]; 3],
            max: [[Vec3A::splat(-f32::MAX); MAX_BINS]; 3],
            count: [[0; MAX_BINS]; 3],
        }
    }

    fn add(mut self, binning: &Binning, refs: &[PrimRef]) -> Self {
        for r in refs {
            for (axis, bin) in binning.bins_of(r.centroid2()).into_iter().enumerate() {
                self.min[axis][bin] = self.min[axis][bin].min(r.min);
                self.max[axis][bin] = self.max[axis][bin].max(r.max);
                self.count[axis][bin] += 1;
            }
        }
        self
    }

    fn merge(mut self, other: Self) -> Self {
        for axis in 0..3 {
            for bin in 0..MAX_BINS {
                self.min[axis][bin] = self.min[axis][bin].min(other.min[axis][bin]);
                self.max[axis][bin] = self.max[axis][bin].max(other.max[axis][bin]);
                self.count[axis][bin] += other.count[axis][bin];
            }
        }
        self
    }
}

/// Per-axis slab boxes of clipped references, and how many references enter and leave each.
struct SpatialBins {
    boxes: [[Aabb; MAX_BINS]; 3],
    entry: [[u32; MAX_BINS]; 3],
    exit: [[u32; MAX_BINS]; 3],
}

impl SpatialBins {
    fn new() -> Self {
        Self { boxes: [[Aabb::EMPTY; MAX_BINS]; 3], entry: [[0; MAX_BINS]; 3], exit: [[0; MAX_BINS]; 3] }
    }

    /// Bins `refs` (of input primitives `order`) over the node's box (`binning`'s bins are
    /// slabs of it): a reference inside one slab as it is, one that crosses slabs clipped at
    /// each plane between them.
    fn add(mut self, builder: &Builder, binning: &Binning, refs: &[PrimRef], order: &[u32]) -> Self {
        for (r, &prim) in refs.iter().zip(order) {
            let (first, last) = (binning.bins_of(r.min), binning.bins_of(r.max));
            let mut source = None;
            for axis in 0..3 {
                let (b0, b1) = (first[axis], last[axis]);
                self.entry[axis][b0] += 1;
                self.exit[axis][b1] += 1;
                if b0 == b1 {
                    self.boxes[axis][b0].grow(&r.aabb());
                    continue;
                }
                let source = source.get_or_insert_with(|| builder.clip_source(prim));
                let mut rest = Some(*r);
                for bin in b0..b1 {
                    let Some(piece) = rest else { break };
                    let [below, above] =
                        Builder::split_reference(source, &piece, axis, binning.plane(axis, bin + 1));
                    if let Some(b) = below {
                        self.boxes[axis][bin].grow(&b);
                    }
                    rest = above.map(PrimRef::from);
                }
                if let Some(piece) = rest {
                    self.boxes[axis][b1].grow(&piece.aabb());
                }
            }
        }
        self
    }

    fn merge(mut self, other: Self) -> Self {
        for axis in 0..3 {
            for bin in 0..MAX_BINS {
                self.boxes[axis][bin].grow(&other.boxes[axis][bin]);
                self.entry[axis][bin] += other.entry[axis][bin];
                self.exit[axis][bin] += other.exit[axis][bin];
            }
        }
        self
    }
}

/// Nodes with at least this many primitives bin in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;

struct Builder<'a> {
    options: &'a BuildOptions,
    /// The input, for clipping triangles at spatial split planes (references past its end are
    /// procedural boxes).
    triangles: &'a [[Vec3; 3]],
    /// Half the root's surface area.
    root_area: f32,
}

/// A node tries spatial splits when its best object split's children overlap by more than this
/// share of the root's surface area (the paper's α, 1e-5 there: on Dabrovic Sponza 1e-3 gave the
/// same rays and path-tracing times for half the build time, docs/history/2026-12-05.md, ninth session).
pub const SPATIAL_OVERLAP: f32 = 1e-3;

/// … and by more than this share of the node's own surface area. Not in the paper: without it
/// a terrain's top nodes, whose sides overlap in thin slabs that span the terrain's height, bin
/// every reference spatially for nothing (its SAH cost did not move) and its build took about
/// 1.6× the time of one without spatial splits; with it 1.15–1.3×, and Dabrovic Sponza keeps its
/// SAH cost within 0.3 % (docs/history/2026-12-05.md, ninth session).
pub const SPATIAL_NODE_OVERLAP: f32 = 0.2;

pub(super) fn build(triangles: &[[Vec3; 3]], boxes: &[[Vec3; 2]], options: &BuildOptions) -> Bvh {
    let start = Instant::now();
    if triangles.is_empty() && boxes.is_empty() {
        return Bvh::empty();
    }
    let (mut refs, mut order) =
        if triangles.is_empty() { (Vec::new(), Vec::new()) } else { references(triangles, options.presplit) };
    // Procedural primitives (boxes) follow the triangles' input indices; never split.
    let first_box = triangles.len() as u32;
    refs.extend(boxes.iter().map(|b| PrimRef { min: b[0].into(), max: b[1].into() }));
    order.extend((0..boxes.len() as u32).map(|k| first_box + k));
    let (bounds, centroids) = bounds_of(&refs);
    let builder = Builder {
        options: &BuildOptions { bins: options.bins.clamp(2, MAX_BINS), ..options.clone() },
        triangles,
        root_area: bounds.half_area(),
    };
    // Room for the references that spatial splits add: a subtree has a capacity of c
    // references (c ≥ the m it holds), c places in `refs` and `order` and 2(c - 1) child slots,
    // and shares its spare room among its children in proportion to their references.
    let count = refs.len();
    let capacity = count + (count as f64 * options.spatial.max(0.0) as f64) as usize;
    refs.resize(capacity, PrimRef { min: Vec3A::ZERO, max: Vec3A::ZERO });
    order.resize(capacity, 0);
    let prepared = start.elapsed();
    // The root's child slots start at 2.
    let mut slots: Vec<BvhNode> = bytemuck::zeroed_vec(2 * capacity);
    let (head, child_slots) = slots.split_at_mut(2);
    head[0] = builder.node(&mut refs, &mut order, count, 0, bounds, centroids, 0, child_slots, 2);
    let built = start.elapsed();
    let (nodes, order) = compact(&slots, &order);
    drop(slots);
    let flattened = start.elapsed();
    let tris = order
        .par_iter()
        .map(|&i| match boxes.get((i as usize).wrapping_sub(triangles.len())) {
            Some(b) if i >= first_box => BvhTri::procedural(b, i),
            _ => BvhTri::new(&triangles[i as usize], i),
        })
        .collect();
    let mut bvh = Bvh {
        nodes,
        tris,
        prim_order: order,
        stats: BvhStats::default(),
        procedurals: boxes.len(),
        implicit_texels: Vec::new(),
    };
    let reordered = start.elapsed();
    bvh.stats = stats(&bvh, options, triangles.len());
    bvh.stats.build_ms = reordered.as_secs_f64() * 1e3;
    log::debug!(
        "BVH build phases (cumulative): prepare {prepared:?}, tree {built:?}, flatten {flattened:?}, \
         triangles {reordered:?}, stats {:?}",
        start.elapsed()
    );
    bvh
}

/// What the build partitions: a box per triangle, or with `presplit` > 0 per piece of the large
/// ones (see [`BuildOptions::presplit`]), each with the input index of its triangle.
fn references(triangles: &[[Vec3; 3]], presplit: f32) -> (Vec<PrimRef>, Vec<u32>) {
    let boxes: Vec<PrimRef> = triangles
        .par_iter()
        .map(|t| {
            let (a, b, c) = (Vec3A::from(t[0]), Vec3A::from(t[1]), Vec3A::from(t[2]));
            PrimRef { min: a.min(b).min(c), max: a.max(b).max(c) }
        })
        .collect();
    let unsplit = |boxes| (boxes, (0..triangles.len() as u32).collect());
    if presplit <= 0.0 {
        return unsplit(boxes);
    }
    let area = |r: &PrimRef| r.aabb().half_area();
    let mean = boxes.par_iter().map(|b| area(b) as f64).sum::<f64>() / boxes.len() as f64;
    let threshold = presplit * mean as f32;
    if !threshold.is_finite() || !boxes.par_iter().any(|b| area(b) > threshold) {
        return unsplit(boxes);
    }
    // A split triangle's first piece takes its place, the others go at the end.
    let large: Vec<usize> =
        (0..triangles.len()).into_par_iter().filter(|&i| area(&boxes[i]) > threshold).collect();
    let pieces: Vec<Vec<PrimRef>> = large
        .par_iter()
        .map(|&i| {
            let polygon = triangles[i].map(Vec3A::from);
            let mut out = Vec::new();
            clip_pieces(&polygon, boxes[i], boxes[i], threshold, 0, &mut |r| out.push(r));
            out
        })
        .collect();
    let mut refs = boxes;
    let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
    for (&i, p) in large.iter().zip(&pieces) {
        let Some((first, rest)) = p.split_first() else { continue };
        refs[i] = *first;
        refs.extend_from_slice(rest);
        order.extend(std::iter::repeat_n(i as u32, rest.len()));
    }
    (refs, order)
}

/// Pieces deeper than this are kept whatever their size (at most 2^8 per triangle).
const MAX_CLIP_DEPTH: u32 = 8;

/// Splits `polygon` (a piece of a triangle whose own box is `whole`; `piece` is the polygon's
/// box) at the middle of the box's longest axis until the pieces' boxes are below `threshold`,
/// and hands each box to `out`. A box is padded by some ulps of the triangle's coordinates, then
/// clipped to `whole` (exact: the triangle's own vertices), so the rounding of the clip points
/// cannot leave any point of the triangle outside the union of its pieces' boxes.
fn clip_pieces(
    polygon: &[Vec3A],
    piece: PrimRef,
    whole: PrimRef,
    threshold: f32,
    depth: u32,
    out: &mut impl FnMut(PrimRef),
) {
    if piece.aabb().half_area() <= threshold || depth >= MAX_CLIP_DEPTH {
        out(piece);
        return;
    }
    let extent = piece.max - piece.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let plane = 0.5 * (piece.min[axis] + piece.max[axis]);
    for below in [true, false] {
        let inside = |v: Vec3A| if below { v[axis] <= plane } else { v[axis] >= plane };
        // Sutherland-Hodgman against one plane; both sides compute each crossing from the same
        // edge in the same direction, so they share it bit for bit.
        // A convex polygon gains at most one vertex per clip: 3 + MAX_CLIP_DEPTH in all.
        let mut buffer = [Vec3A::ZERO; 3 + MAX_CLIP_DEPTH as usize];
        let mut len = 0;
        for (k, &p) in polygon.iter().enumerate() {
            let q = polygon[(k + 1) % polygon.len()];
            if inside(p) {
                buffer[len] = p;
                len += 1;
            }
            if inside(p) != inside(q) {
                buffer[len] = crossing(p, q, axis, plane);
                len += 1;
            }
        }
        if len < 3 {
            continue;
        }
        let part = &buffer[..len];
        let mut bounds = Aabb::EMPTY;
        part.iter().for_each(|&v| bounds.grow_point(v));
        let pad = clip_pad(whole.min.abs().max(whole.max.abs()));
        let next = PrimRef { min: (bounds.min - pad).max(whole.min), max: (bounds.max + pad).min(whole.max) };
        clip_pieces(part, next, whole, threshold, depth + 1, out);
    }
}

/// Where the edge `p`→`q`, which crosses `plane` on `axis`, meets it: exactly on the plane. Two
/// clips that compute a crossing from the same edge in the same direction share it bit for bit.
fn crossing(p: Vec3A, q: Vec3A, axis: usize, plane: f32) -> Vec3A {
    let mut x = p + (q - p) * ((plane - p[axis]) / (q[axis] - p[axis]));
    x[axis] = plane;
    x
}

/// The padding of a box of clip points of a triangle whose coordinates reach `magnitude`: each
/// level's clip points are within a few ulps of that magnitude of true points of the triangle
/// (errors add up over the levels), and 64 ulps cover all of `clip_pieces`' eight levels.
fn clip_pad(magnitude: Vec3A) -> Vec3A {
    magnitude * (64.0 * f32::EPSILON)
}

/// The box of the primitives and the box of their (doubled) centroids.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let fold = |(mut b, mut c): (Aabb, Aabb), r: &PrimRef| {
        b.grow(&r.aabb());
        c.grow_point(r.centroid2());
        (b, c)
    };
    if refs.len() >= PARALLEL_BINNING {
        refs.par_chunks(PARALLEL_BINNING / 4)
            .map(|chunk| chunk.iter().fold((Aabb::EMPTY, Aabb::EMPTY), fold))
            .reduce(
                || (Aabb::EMPTY, Aabb::EMPTY),
                |(mut a, mut b), (c, d)| {
                    a.grow(&c);
                    b.grow(&d);
                    (a, b)
                },
            )
    } else {
        refs.iter().fold((Aabb::EMPTY, Aabb::EMPTY), fold)
    }
}

impl Builder<'_> {
    /// Builds the subtree over the first `count` of `refs`/`order` and returns its root. The
    /// slices are the subtree's capacity (see `build`); position `i` of them is position
    /// `first + i` of the build's (gapped) order. Descendants go into `slots` (at absolute index
    /// `base`, 2(capacity - 1) of them): this node's children first, then the left subtree's
    /// slots, then the right's.
    #[allow(clippy::too_many_arguments)]
    fn node(
        &self,
        refs: &mut [PrimRef],
        order: &mut [u32],
        count: usize,
        first: usize,
        bounds: Aabb,
        centroids: Aabb,
        depth: usize,
        slots: &mut [BvhNode],
        base: usize,
    ) -> BvhNode {
        let capacity = refs.len();
        let leaf = node_of(&bounds, first as u32, count as u32);
        if count == 1 || depth + 1 >= MAX_DEPTH {
            return leaf;
        }
        let leaf_cost = self.options.intersection_cost * count as f32;
        // A sweep's best axis in centroid order (sort keys, see `sort_key`), for the partition.
        let mut sorted_small = [0u64; SMALL];
        let mut sorted_large = Vec::new();
        let sorted = if count <= SMALL {
            &mut sorted_small[..count]
        } else {
            sorted_large.resize(if self.options.full_sweep { count } else { 0 }, 0);
            &mut sorted_large[..]
        };
        let live = &refs[..count];
        let object = if self.options.full_sweep || count <= SMALL {
            best_sweep(live, sorted, self.options.intersection_cost)
        } else {
            self.best_binned(live, &centroids)
        };
        // A spatial split where the object split's sides overlap enough and there is room for
        // more references (not in nodes small enough for the exact sweep).
        let sides = match &object {
            _ if count <= SMALL || capacity == count => None,
            Some(Split { kind: SplitKind::Bin { boxes, .. }, .. }) => Some(*boxes),
            Some(Split { kind: SplitKind::Sorted { count: left }, .. }) => {
                let side = |keys: &[u64]| {
                    keys.iter().fold(Aabb::EMPTY, |mut b, &k| {
                        b.grow(&live[position_of(k)].aabb());
                        b
                    })
                };
                Some([side(&sorted[..*left]), side(&sorted[*left..])])
            }
            _ => None,
        };
        let spatial = sides.and_then(|[l, r]| {
            let overlap = Aabb { min: l.min.max(r.min), max: l.max.min(r.max) };
            let overlap = overlap.half_area();
            (overlap > SPATIAL_OVERLAP * self.root_area
                && overlap > SPATIAL_NODE_OVERLAP * bounds.half_area())
            .then(|| self.best_spatial(live, &order[..count], &bounds))
            .flatten()
            .filter(|s| object.as_ref().is_some_and(|o| s.cost < o.cost))
        });
        let split_cost = spatial.as_ref().or(object.as_ref()).map_or(f32::INFINITY, |s| {
            self.options.traversal_cost + s.cost / bounds.half_area().max(f32::MIN_POSITIVE)
        });
        if count <= self.options.max_leaf_size && leaf_cost <= split_cost {
            return leaf;
        }
        // The two sides' sizes where the spatial split partitioned the references.
        let spatially = match &spatial {
            Some(Split { axis, kind: SplitKind::Spatial { plane }, .. }) => {
                self.partition_spatial(refs, order, count, *axis, *plane)
            }
            _ => None,
        };
        let (left_count, right_count, child_bounds) = match spatially {
            Some((left_count, right_count)) => (left_count, right_count, None),
            // The object split (also where the spatial one would leave a side empty).
            None => {
                let (left_count, child_bounds) = match &object {
                    Some(split) => partition(&mut refs[..count], &mut order[..count], split, sorted),
                    // All centroids coincide: any split is as good as any other.
                    None => (count / 2, None),
                };
                let (left_count, child_bounds) = if left_count == 0 || left_count == count {
                    (count / 2, None)
                } else {
                    (left_count, child_bounds)
                };
                (left_count, count - left_count, child_bounds)
            }
        };
        // The spare room, shared in proportion; the right side's references move to the start
        // of its share (a spatial partition has put them there already).
        let left_capacity = left_share(capacity, left_count, right_count);
        if spatially.is_none() && left_capacity > left_count {
            refs.copy_within(left_count..count, left_capacity);
            order.copy_within(left_count..count, left_capacity);
        }
        let (left_refs, right_refs) = refs.split_at_mut(left_capacity);
        let (left_order, right_order) = order.split_at_mut(left_capacity);
        let [(lb, lc), (rb, rc)] = child_bounds
            .unwrap_or_else(|| [bounds_of(&left_refs[..left_count]), bounds_of(&right_refs[..right_count])]);
        let (pair, rest) = slots.split_at_mut(2);
        let (left_slots, right_slots) = rest.split_at_mut(2 * (left_capacity - 1));
        let (left_base, right_base) = (base + 2, base + 2 + 2 * (left_capacity - 1));
        let right_first = first + left_capacity;
        let mut left = move |slots| {
            self.node(left_refs, left_order, left_count, first, lb, lc, depth + 1, slots, left_base)
        };
        let mut right = move |slots| {
            self.node(right_refs, right_order, right_count, right_first, rb, rc, depth + 1, slots, right_base)
        };
        let (l, r) = if count >= PARALLEL_THRESHOLD {
            rayon::join(move || left(left_slots), move || right(right_slots))
        } else {
            (left(left_slots), right(right_slots))
        };
        pair[0] = l;
        pair[1] = r;
        node_of(&bounds, base as u32, 0)
    }

    /// The cheapest binned split over all three axes, or `None` when the centroids do not
    /// spread on any axis.
    // Out of line, so that its locals stay off the stack frame `node` keeps through its recursion.
    #[inline(never)]
    fn best_binned(&self, refs: &[PrimRef], centroids: &Aabb) -> Option<Split> {
        let n_bins = self.options.bins;
        let binning = Binning::new(centroids.min, centroids.max, n_bins);
        let bins = if refs.len() >= PARALLEL_BINNING {
            refs.par_chunks(PARALLEL_BINNING / 4)
                .map(|chunk| Bins::new().add(&binning, chunk))
                .reduce(Bins::new, Bins::merge)
        } else {
            Bins::new().add(&binning, refs)
        };
        let mut best: Option<Split> = None;
        for axis in (0..3).filter(|&a| centroids.max[a] > centroids.min[a]) {
            sweep_bins(
                n_bins,
                self.options.intersection_cost,
                |b| Aabb { min: bins.min[axis][b], max: bins.max[axis][b] },
                |b| bins.count[axis][b],
                |b| bins.count[axis][b],
                |bin, cost, boxes| {
                    if best.as_ref().is_none_or(|b| cost < b.cost) {
                        best = Some(Split { axis, cost, kind: SplitKind::Bin { bin, binning, boxes } });
                    }
                },
            );
        }
        best
    }

    /// The triangle of input primitive `prim` and the padding its clip points need (`None`
    /// for a procedural box).
    fn clip_source(&self, prim: u32) -> Option<([Vec3A; 3], Vec3A)> {
        self.triangles.get(prim as usize).map(|t| {
            let v = t.map(Vec3A::from);
            (v, clip_pad(v[0].abs().max(v[1].abs()).max(v[2].abs())))
        })
    }

    /// Splits reference `r` at `plane` on `axis`: the boxes of the parts of its triangle
    /// (`source`, from [`Self::clip_source`]) below and above the plane, each within `r`'s box;
    /// `None` for a side the triangle does not reach inside that box. A procedural box is cut
    /// in two.
    fn split_reference(
        source: &Option<([Vec3A; 3], Vec3A)>,
        r: &PrimRef,
        axis: usize,
        plane: f32,
    ) -> [Option<Aabb>; 2] {
        let (mut below, mut above) = (Aabb::EMPTY, Aabb::EMPTY);
        let pad = match source {
            Some((v, pad)) => {
                for k in 0..3 {
                    let (p, q) = (v[k], v[(k + 1) % 3]);
                    if p[axis] <= plane {
                        below.grow_point(p);
                    }
                    if p[axis] >= plane {
                        above.grow_point(p);
                    }
                    if (p[axis] < plane && q[axis] > plane) || (p[axis] > plane && q[axis] < plane) {
                        let x = crossing(p, q, axis, plane);
                        below.grow_point(x);
                        above.grow_point(x);
                    }
                }
                *pad
            }
            None => {
                below = r.aabb();
                above = r.aabb();
                below.max[axis] = plane;
                above.min[axis] = plane;
                Vec3A::ZERO
            }
        };
        [below, above].map(|b| {
            let clipped = Aabb { min: (b.min - pad).max(r.min), max: (b.max + pad).min(r.max) };
            clipped.min.cmple(clipped.max).all().then_some(clipped)
        })
    }

    /// The cheapest spatial split over all three axes: the node's box cut into equal slabs,
    /// each reference's triangle clipped into the slabs it crosses, a reference counted as
    /// entering its first slab and leaving its last (the paper's chopped binning).
    // Out of line, so that its locals stay off the stack frame `node` keeps through its recursion.
    #[inline(never)]
    fn best_spatial(&self, refs: &[PrimRef], order: &[u32], bounds: &Aabb) -> Option<Split> {
        let n_bins = self.options.bins;
        let binning = Binning::new(bounds.min, bounds.max, n_bins);
        let bins = if refs.len() >= PARALLEL_BINNING {
            refs.par_chunks(PARALLEL_BINNING / 4)
                .zip(order.par_chunks(PARALLEL_BINNING / 4))
                .map(|(r, o)| SpatialBins::new().add(self, &binning, r, o))
                .reduce(SpatialBins::new, SpatialBins::merge)
        } else {
            SpatialBins::new().add(self, &binning, refs, order)
        };
        let mut best: Option<Split> = None;
        for axis in (0..3).filter(|&a| bounds.max[a] > bounds.min[a]) {
            sweep_bins(
                n_bins,
                self.options.intersection_cost,
                |b| bins.boxes[axis][b],
                |b| bins.entry[axis][b],
                |b| bins.exit[axis][b],
                |bin, cost, _| {
                    if best.as_ref().is_none_or(|b| cost < b.cost) {
                        let plane = binning.plane(axis, bin);
                        best = Some(Split { axis, cost, kind: SplitKind::Spatial { plane } });
                    }
                },
            );
        }
        best
    }

    /// Partitions the first `count` references by a spatial split at `plane` on `axis`, the
    /// left side to the front of `refs`/`order` and the right side to the start of its share
    /// of the spare room (as `node` shares it). A reference that crosses the plane is split in
    /// two, or kept whole on one side where that costs less (the paper's reference unsplitting).
    /// Returns the two sides' sizes, or `None` (nothing moved) when a side would be empty or
    /// the references outgrow the room.
    // Out of line, so that its locals stay off the stack frame `node` keeps through its recursion.
    #[inline(never)]
    fn partition_spatial(
        &self,
        refs: &mut [PrimRef],
        order: &mut [u32],
        count: usize,
        axis: usize,
        plane: f32,
    ) -> Option<(usize, usize)> {
        let (mut left, mut right, mut crossing) = (Vec::new(), Vec::new(), Vec::new());
        let (mut left_box, mut right_box) = (Aabb::EMPTY, Aabb::EMPTY);
        for (r, &prim) in refs[..count].iter().zip(&order[..count]) {
            if r.max[axis] <= plane {
                left_box.grow(&r.aabb());
                left.push((*r, prim));
            } else if r.min[axis] >= plane {
                right_box.grow(&r.aabb());
                right.push((*r, prim));
            } else {
                crossing.push((*r, prim));
            }
        }
        // Counts as if every crossing reference were split.
        let (mut n_left, mut n_right) =
            ((left.len() + crossing.len()) as f32, (right.len() + crossing.len()) as f32);
        for (r, prim) in crossing {
            let whole = r.aabb();
            let source = self.clip_source(prim);
            match Self::split_reference(&source, &r, axis, plane) {
                [Some(below), Some(above)] => {
                    let grown = |side: &Aabb, b: &Aabb| {
                        let mut g = *side;
                        g.grow(b);
                        g.half_area()
                    };
                    let split = grown(&left_box, &below) * n_left + grown(&right_box, &above) * n_right;
                    let all_left =
                        grown(&left_box, &whole) * n_left + right_box.half_area() * (n_right - 1.0);
                    let all_right =
                        left_box.half_area() * (n_left - 1.0) + grown(&right_box, &whole) * n_right;
                    // A procedural box is kept whole (its pieces would share one shape's hits);
                    // keeping a reference whole never takes the last one from the other side.
                    let procedural = source.is_none();
                    let keep_left = all_left < split && all_left <= all_right && n_right > 1.0;
                    let keep_right = all_right < split && n_left > 1.0;
                    if keep_left || (procedural && all_left <= all_right) {
                        left_box.grow(&whole);
                        left.push((r, prim));
                        n_right -= 1.0;
                    } else if keep_right || procedural {
                        right_box.grow(&whole);
                        right.push((r, prim));
                        n_left -= 1.0;
                    } else {
                        left_box.grow(&below);
                        right_box.grow(&above);
                        left.push((below.into(), prim));
                        right.push((above.into(), prim));
                    }
                }
                [Some(_), None] => {
                    left_box.grow(&whole);
                    left.push((r, prim));
                    n_right -= 1.0;
                }
                _ => {
                    right_box.grow(&whole);
                    right.push((r, prim));
                    n_left -= 1.0;
                }
            }
        }
        let (left_count, right_count) = (left.len(), right.len());
        if left_count == 0 || right_count == 0 || left_count + right_count > refs.len() {
            return None;
        }
        let left_capacity = left_share(refs.len(), left_count, right_count);
        for (k, (r, prim)) in left.into_iter().enumerate() {
            (refs[k], order[k]) = (r, prim);
        }
        for (k, (r, prim)) in right.into_iter().enumerate() {
            (refs[left_capacity + k], order[left_capacity + k]) = (r, prim);
        }
        Some((left_count, right_count))
    }
}

/// The SAH cost (unnormalised, as [`Split`]'s) of each boundary `bin` between one axis's bins
/// `0..bin` and `bin..n_bins` with references on both sides, handed to `each` with the two sides'
/// boxes. Bin `b`'s box is `boxes(b)`; it holds `left(b)` references counted on a left side and
/// `right(b)` on a right side (the same for object bins; those that enter it and those that
/// leave it for spatial slabs).
fn sweep_bins(
    n_bins: usize,
    intersection_cost: f32,
    boxes: impl Fn(usize) -> Aabb,
    left: impl Fn(usize) -> u32,
    right: impl Fn(usize) -> u32,
    mut each: impl FnMut(usize, f32, [Aabb; 2]),
) {
    let mut right_box = [Aabb::EMPTY; MAX_BINS];
    let mut right_count = [0u32; MAX_BINS];
    let (mut acc, mut n) = (Aabb::EMPTY, 0);
    for bin in (1..n_bins).rev() {
        acc.grow(&boxes(bin));
        n += right(bin);
        right_box[bin] = acc;
        right_count[bin] = n;
    }
    let (mut acc, mut n) = (Aabb::EMPTY, 0);
    for bin in 1..n_bins {
        acc.grow(&boxes(bin - 1));
        n += left(bin - 1);
        if n == 0 || right_count[bin] == 0 {
            continue;
        }
        let cost = intersection_cost
            * (acc.half_area() * n as f32 + right_box[bin].half_area() * right_count[bin] as f32);
        each(bin, cost, [acc, right_box[bin]]);
    }
}

/// The cheapest split between consecutive primitives in centroid order on any axis; the best
/// axis's order is left in `sorted` (one key per primitive).
fn best_sweep(refs: &[PrimRef], sorted: &mut [u64], intersection_cost: f32) -> Option<Split> {
    let n = refs.len();
    if n <= SMALL {
        sweep(refs, &mut [0; SMALL][..n], sorted, &mut [0.0; SMALL][..n], intersection_cost)
    } else {
        sweep(refs, &mut vec![0; n], sorted, &mut vec![0.0; n], intersection_cost)
    }
}

/// Orders primitives by centroid, then by position in the node: the centroid's bits mapped so
/// that unsigned order is float order (finite values), above the position. Sorting these plain
/// integers is several times faster than sorting (f32, u32) pairs with `total_cmp`.
fn sort_key(centroid: f32, position: usize) -> u64 {
    let bits = centroid.to_bits();
    let ordered = if bits >> 31 == 1 { !bits } else { bits | 1 << 31 };
    (u64::from(ordered) << 32) | position as u64
}

/// The position in the node that a [`sort_key`] holds.
fn position_of(key: u64) -> usize {
    key as u32 as usize
}

/// [`best_sweep`] with caller-provided scratch space: sort keys and areas.
fn sweep(
    refs: &[PrimRef],
    keys: &mut [u64],
    sorted: &mut [u64],
    right_area: &mut [f32],
    cost: f32,
) -> Option<Split> {
    let n = refs.len();
    let mut best: Option<Split> = None;
    for axis in 0..3 {
        for (i, (k, r)) in keys.iter_mut().zip(refs).enumerate() {
            *k = sort_key(r.centroid2()[axis], i);
        }
        keys.sort_unstable();
        if keys[0] >> 32 == keys[n - 1] >> 32 {
            continue;
        }
        let prim = |k: usize| {
            let r = &refs[position_of(keys[k])];
            r.aabb()
        };
        let mut acc = Aabb::EMPTY;
        for k in (1..n).rev() {
            acc.grow(&prim(k));
            right_area[k] = acc.half_area();
        }
        let mut acc = Aabb::EMPTY;
        let mut improved = false;
        for (k, &right) in right_area.iter().enumerate().skip(1) {
            acc.grow(&prim(k - 1));
            let c = cost * (acc.half_area() * k as f32 + right * (n - k) as f32);
            if best.as_ref().is_none_or(|b| c < b.cost) {
                best = Some(Split { axis, cost: c, kind: SplitKind::Sorted { count: k } });
                improved = true;
            }
        }
        if improved {
            sorted.copy_from_slice(keys);
        }
    }
    best
}

/// Reorders `refs` and `order` together so the left side of `split` comes first; returns its
/// size and, when it comes for free, the (bounds, centroid bounds) of both sides.
fn partition(
    refs: &mut [PrimRef],
    order: &mut [u32],
    split: &Split,
    sorted: &[u64],
) -> (usize, Option<[(Aabb, Aabb); 2]>) {
    match &split.kind {
        SplitKind::Bin { bin, binning, .. } => {
            // The four boxes live in locals (registers): indexing an array of sides by the
            // side chained every primitive's update through memory.
            let (mut left_box, mut left_centroids) = (Aabb::EMPTY, Aabb::EMPTY);
            let (mut right_box, mut right_centroids) = (Aabb::EMPTY, Aabb::EMPTY);
            let mut left = 0;
            for i in 0..refs.len() {
                let r = refs[i];
                let c2 = r.centroid2();
                if binning.below(c2, split.axis, *bin) {
                    left_box.grow(&r.aabb());
                    left_centroids.grow_point(c2);
                    refs.swap(i, left);
                    order.swap(i, left);
                    left += 1;
                } else {
                    right_box.grow(&r.aabb());
                    right_centroids.grow_point(c2);
                }
            }
            (left, Some([(left_box, left_centroids), (right_box, right_centroids)]))
        }
        SplitKind::Spatial { .. } => unreachable!("spatial splits partition in `partition_spatial`"),
        SplitKind::Sorted { count } => {
            // Apply the sweep's order (no second sort: the partition is the order the sweep
            // evaluated, ties included).
            let n = refs.len();
            let mut small = [(PrimRef { min: Vec3A::ZERO, max: Vec3A::ZERO }, 0u32); SMALL];
            let mut large = Vec::new();
            let before = if n <= SMALL {
                &mut small[..n]
            } else {
                large.resize(n, small[0]);
                &mut large[..]
            };
            for (k, p) in before.iter_mut().enumerate() {
                *p = (refs[k], order[k]);
            }
            for (k, &key) in sorted.iter().enumerate() {
                (refs[k], order[k]) = before[position_of(key)];
            }
            (*count, None)
        }
    }
}

/// The capacity (see `build`) of a node's left child: its references and its share of the
/// node's spare room, in proportion to its references.
fn left_share(capacity: usize, left_count: usize, right_count: usize) -> usize {
    let spare = capacity - left_count - right_count;
    left_count + (spare as u64 * left_count as u64 / (left_count + right_count) as u64) as usize
}

fn node_of(bounds: &Aabb, left_first: u32, tri_count: u32) -> BvhNode {
    BvhNode {
        aabb_min: Vec3::from(bounds.min).into(),
        left_first,
        aabb_max: Vec3::from(bounds.max).into(),
        tri_count,
    }
}

/// Copies the tree out of its slots (which have gaps where leaves held several primitives)
/// depth-first, each pair of children allocated at the end, at even indices, and the leaves'
/// references out of `order` (which has gaps where spatial splits had room to spare) in the
/// same order.
fn compact(slots: &[BvhNode], order: &[u32]) -> (Vec<BvhNode>, Vec<u32>) {
    let mut nodes = Vec::with_capacity(slots.len());
    let mut leaf_order = Vec::with_capacity(order.len());
    nodes.extend_from_slice(&slots[..2]);
    let mut stack = vec![0usize];
    while let Some(index) = stack.pop() {
        let node = nodes[index];
        if node.is_leaf() {
            let from = node.left_first as usize;
            nodes[index].left_first = leaf_order.len() as u32;
            leaf_order.extend_from_slice(&order[from..from + node.tri_count as usize]);
            continue;
        }
        let from = node.left_first as usize;
        let to = nodes.len();
        nodes.extend_from_slice(&slots[from..from + 2]);
        nodes[index].left_first = to as u32;
        stack.extend([to + 1, to]);
    }
    (nodes, leaf_order)
}

pub(super) fn stats(bvh: &Bvh, options: &BuildOptions, triangles: usize) -> BvhStats {
    let root_area = bvh.nodes[0].surface_area().max(f32::MIN_POSITIVE);
    let mut s = BvhStats { triangles, references: bvh.tris.len(), ..Default::default() };
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
    s.mean_leaf_size = s.references as f32 / s.leaves.max(1) as f32;
    s.sah_cost = cost as f32;
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedural::Rng;

    /// Sort keys order like `total_cmp` on the centroid, then by position: negative values,
    /// both zeros, ties, tiny and huge magnitudes.
    #[test]
    fn sort_keys_order_by_centroid_then_position() {
        let mut rng = Rng::new(7);
        let values = [-3.5e30, -2.0, -1.0, -1e-30, -0.0, 0.0, 1e-30, 0.5, 1.0, 7.25, 3e30];
        for _ in 0..200 {
            let n = 1 + rng.below(40);
            let centroids: Vec<f32> = (0..n).map(|_| values[rng.below(values.len())]).collect();
            let mut keys: Vec<u64> = centroids.iter().enumerate().map(|(i, &c)| sort_key(c, i)).collect();
            keys.sort_unstable();
            let mut expected: Vec<usize> = (0..n).collect();
            expected.sort_by(|&a, &b| centroids[a].total_cmp(&centroids[b]).then(a.cmp(&b)));
            assert_eq!(keys.iter().map(|&k| position_of(k)).collect::<Vec<_>>(), expected);
        }
    }

    fn half_area_of(refs: &[PrimRef]) -> f32 {
        let mut b = Aabb::EMPTY;
        for r in refs {
            b.grow(&r.aabb());
        }
        b.half_area()
    }

    /// A sweep's partition is the split it evaluated: the two sides it leaves have exactly the
    /// chosen cost, which is the least over every split of every axis's centroid order, and the
    /// input indices still follow their boxes. Centroids snap to a coarse grid so that ties
    /// (where sorting twice could order differently) are common.
    #[test]
    fn sweep_partitions_as_evaluated() {
        let mut rng = Rng::new(11);
        for round in 0..500 {
            let n = 2 + rng.below(if round % 2 == 0 { SMALL - 1 } else { 40 });
            let refs: Vec<PrimRef> = (0..n)
                .map(|_| {
                    let c = Vec3A::new(rng.below(4) as f32, rng.below(3) as f32 - 1.0, rng.below(2) as f32);
                    let h = Vec3A::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.0, 1.0));
                    PrimRef { min: c - h, max: c + h }
                })
                .collect();
            let mut sorted = vec![0u64; n];
            let Some(split) = best_sweep(&refs, &mut sorted, 1.0) else {
                continue;
            };
            // The least cost over all axes and split positions, by brute force.
            let mut least = f32::INFINITY;
            for axis in 0..3 {
                let mut by_axis = refs.clone();
                by_axis.sort_by(|a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
                for k in 1..n {
                    if by_axis[k - 1].centroid2()[axis] == by_axis[n - 1].centroid2()[axis] {
                        break;
                    }
                    let cost =
                        half_area_of(&by_axis[..k]) * k as f32 + half_area_of(&by_axis[k..]) * (n - k) as f32;
                    least = least.min(cost);
                }
            }
            assert!(split.cost <= least * (1.0 + 1e-6), "round {round}: chose {} over {least}", split.cost);
            let mut parted = refs.clone();
            let mut order: Vec<u32> = (0..n as u32).collect();
            let (count, _) = partition(&mut parted, &mut order, &split, &sorted);
            let cost = half_area_of(&parted[..count]) * count as f32
                + half_area_of(&parted[count..]) * (n - count) as f32;
            assert_eq!(cost, split.cost, "round {round}: the partition's cost is not the evaluated one");
            for (r, &i) in parted.iter().zip(&order) {
                let original = &refs[i as usize];
                assert!(r.min == original.min && r.max == original.max, "round {round}: index lost its box");
            }
        }
    }
}
