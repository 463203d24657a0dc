//! The bounding volume hierarchy: a binned-SAH build on the CPU (parallel with `rayon`) with
//! split triangle references (early split clipping and spatial splits, [`BuildOptions`]),
//! flattened depth-first into 32-byte nodes, with the triangles reordered to match the leaves.
//!
//! Layout (tinybvh's `BVHNode`): node 0 is the root, node 1 is unused so that every pair of
//! siblings starts at an even index and shares one 64-byte cache line. An interior node has
//! `tri_count == 0` and its children at `left_first` and `left_first + 1`; a leaf holds
//! `tri_count` triangles from `tris[left_first]`. An empty BVH is a root with `tri_count == 0`
//! and an inverted box (`aabb_min > aabb_max`), which traversal checks once per ray.
//!
//! The GLSL traversal in `spirv/include/bvh.glsl` and [`traverse`] here share the ray set-up and
//! the triangle test operation for operation and cull boxes conservatively, so the CPU can
//! validate the GPU hit for hit.

mod build;
pub mod reference;
pub mod traverse;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::mem::size_of;

pub use build::{BuildOptions, SPATIAL_NODE_OVERLAP, SPATIAL_OVERLAP};
pub use traverse::{Hit, Ray};

/// The deepest a BVH may be; the traversal stack holds this many entries.
pub const MAX_DEPTH: usize = 64;

/// One node of the flattened binary BVH (the CPU side; the GPU reads [`crate::gpu::bvh::GpuBvhNode`]s).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// Box minimum.
    pub aabb_min: [f32; 3],
    /// Interior: index of the left child (the right is the next). Leaf: first triangle.
    pub left_first: u32,
    /// Box maximum.
    pub aabb_max: [f32; 3],
    /// Triangles in a leaf; 0 for an interior node.
    pub tri_count: u32,
}
const _: () = assert!(size_of::<BvhNode>() == 32);

impl BvhNode {
    /// Whether this node is a leaf.
    pub fn is_leaf(&self) -> bool {
        self.tri_count > 0
    }

    pub(crate) fn surface_area(&self) -> f32 {
        let e = Vec3::from(self.aabb_max) - Vec3::from(self.aabb_min);
        if e.min_element() < 0.0 {
            return 0.0;
        }
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

pub use crate::gpu::layout::BvhTri;

impl BvhTri {
    fn new(v: &[Vec3; 3], input_index: u32) -> Self {
        let w = f32::from_bits(input_index);
        Self { v0: v[0].extend(w).into(), v1: v[1].extend(0.0).into(), v2: v[2].extend(0.0).into() }
    }

    /// A procedural primitive's slot: its box as the first two "vertices" (the third repeats the
    /// first, so the triangle test never hits it) and, in `v2[3]`, the bits of the first texel of
    /// its program in `bvh_tri_texels` (0 for a triangle; set by [`Bvh::attach_implicit`]).
    fn procedural(b: &[Vec3; 2], input_index: u32) -> Self {
        let w = f32::from_bits(input_index);
        Self { v0: b[0].extend(w).into(), v1: b[1].extend(0.0).into(), v2: b[0].extend(0.0).into() }
    }

    /// The first texel of this slot's implicit-shape program, `None` for a triangle.
    pub fn program(&self) -> Option<u32> {
        Some(self.v2[3].to_bits()).filter(|&p| p != 0)
    }

    /// The three vertices.
    pub fn vertices(&self) -> [Vec3; 3] {
        [Vec3::from_slice(&self.v0), Vec3::from_slice(&self.v1), Vec3::from_slice(&self.v2)]
    }

    /// This triangle's index in the builder's input.
    pub fn input_index(&self) -> u32 {
        self.v0[3].to_bits()
    }
}

/// Numbers that describe a built BVH.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Triangles of the input (after [`Bvh::renumber`], of the larger input, the left-out ones
    /// among them).
    pub triangles: usize,
    /// Input triangles the build was not given ([`Bvh::renumber`]): in no leaf, never hit.
    pub left_out: usize,
    /// Triangle references in the leaves: the triangles plus the extra pieces of the ones split
    /// by [`BuildOptions::presplit`] and [`BuildOptions::spatial`].
    pub references: usize,
    /// Nodes in use (the unused slot 1 not counted).
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Longest root-to-leaf path in edges.
    pub depth: usize,
    /// Largest leaf.
    pub max_leaf_size: usize,
    /// Mean references per leaf.
    pub mean_leaf_size: f32,
    /// Surface-area-heuristic cost with the build's traversal and intersection costs.
    pub sah_cost: f32,
    /// Wall-clock build time in milliseconds (bounds to reordered triangles; not these stats).
    pub build_ms: f64,
}

/// A flattened BVH over a triangle soup.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes, root first (see the module docs for the layout).
    pub nodes: Vec<BvhNode>,
    /// Triangles in leaf order: a triangle split by [`BuildOptions::presplit`] or
    /// [`BuildOptions::spatial`] appears once per piece, in the leaves of those pieces.
    pub tris: Vec<BvhTri>,
    /// `prim_order[i]` is the input index of `tris[i]`; every input index appears at least once,
    /// but for the `stats.left_out` triangles a [`Bvh::renumber`]ed build was not given.
    pub prim_order: Vec<u32>,
    /// Build statistics.
    pub stats: BvhStats,
    /// Procedural primitives (implicit shapes' boxes): input indices
    /// `stats.triangles .. stats.triangles + procedurals`.
    pub procedurals: usize,
    /// The implicit shapes' programs ([`crate::gpu::implicit::program`]), uploaded after
    /// `tris` in the same texel buffer.
    pub implicit_texels: Vec<[u32; 4]>,
}

impl Bvh {
    /// Builds with [`BuildOptions::default`]. Every vertex must be finite: a non-finite one is an
    /// [`crate::Error::Invalid`] naming the triangle (the scene loader removes them first).
    pub fn build(triangles: &[[Vec3; 3]]) -> crate::Result<Self> {
        Self::build_with(triangles, &BuildOptions::default())
    }

    /// Builds with the given options.
    pub fn build_with(triangles: &[[Vec3; 3]], options: &BuildOptions) -> crate::Result<Self> {
        Self::build_mixed(triangles, &[], options)
    }

    /// Builds over triangles and procedural primitives given by their boxes (`[min, max]`),
    /// which take the input indices after the triangles'.
    pub fn build_mixed(
        triangles: &[[Vec3; 3]],
        boxes: &[[Vec3; 2]],
        options: &BuildOptions,
    ) -> crate::Result<Self> {
        if let Some(i) =
            boxes.iter().position(|b| !(b[0].is_finite() && b[1].is_finite() && b[0].cmple(b[1]).all()))
        {
            return Err(crate::Error::Invalid(format!(
                "BVH input box {i} is not finite or inverted: {:?}",
                boxes[i]
            )));
        }
        if let Some(i) = triangles.iter().position(|t| !t.iter().all(|v| v.is_finite())) {
            return Err(crate::Error::Invalid(format!(
                "BVH input triangle {i} has a non-finite vertex: {:?}",
                triangles[i]
            )));
        }
        if triangles.len() + boxes.len() >= (1 << 31) {
            return Err(crate::Error::Invalid(format!(
                "{} triangles are more than a BVH can index",
                triangles.len()
            )));
        }
        Ok(build::build(triangles, boxes, options))
    }

    /// Attaches the implicit shapes' programs, one per procedural primitive in input order: each
    /// slot's `v2[3]` then points at its program's first texel (after the triangles' texels).
    pub fn attach_implicit(&mut self, programs: &[Vec<[u32; 4]>]) {
        assert_eq!(programs.len(), self.procedurals, "one program per procedural primitive");
        let mut first = Vec::with_capacity(programs.len());
        self.implicit_texels.clear();
        let base = 3 * self.tris.len() as u32;
        for p in programs {
            first.push(base + self.implicit_texels.len() as u32);
            self.implicit_texels.extend_from_slice(p);
        }
        let n = self.stats.triangles as u32;
        for t in &mut self.tris {
            let input = t.input_index();
            if input >= n {
                t.v2[3] = f32::from_bits(first[(input - n) as usize]);
            }
        }
    }

    /// Gives a BVH built over some of a larger input's triangles (`kept[i]`: the larger input's
    /// index of triangle i, ascending; the procedural primitives after them) the larger input's
    /// indices: in `prim_order`, in each triangle's input index (the tie rule's order, which
    /// `kept` being ascending keeps) and in `stats`, which then counts `total` triangles of which
    /// `total - kept.len()` left out. So a scene can leave out triangles no ray may hit (alpha
    /// classes, `crate::gpu::scene`) and still name every slot by its scene triangle.
    pub fn renumber(&mut self, kept: &[u32], total: usize) {
        debug_assert!(
            kept.windows(2).all(|w| w[0] < w[1]) && kept.last().is_none_or(|&k| (k as usize) < total)
        );
        let built = kept.len() as u32;
        let to_input = |i: u32| if i < built { kept[i as usize] } else { total as u32 + (i - built) };
        for p in &mut self.prim_order {
            *p = to_input(*p);
        }
        for t in &mut self.tris {
            t.v0[3] = f32::from_bits(to_input(t.input_index()));
        }
        self.stats.left_out += total - kept.len();
        self.stats.triangles = total;
    }

    /// Moves the triangles and procedural boxes to new positions (the build's input order and
    /// counts: `triangles`, then `boxes`) and refits every node's box bottom-up, keeping the
    /// tree: O(n), against a rebuild's O(n log n), at the price of the tree's quality once
    /// things have moved far from where it was built (boxes grow and overlap). A triangle split
    /// into pieces by the build now bounds its whole triangle in each piece's leaf. Triangles a
    /// [`Bvh::renumber`]ed build left out stay out. The tree, its leaves and every reference's
    /// input index are unchanged; so are [`Bvh::stats`] but for `sah_cost`, recomputed (with the
    /// default build options' costs).
    pub fn refit(&mut self, triangles: &[[Vec3; 3]], boxes: &[[Vec3; 2]]) -> crate::Result<()> {
        let n = self.stats.triangles;
        if triangles.len() != n || boxes.len() != self.procedurals {
            return Err(crate::Error::Invalid(format!(
                "a refit needs the build's {n} triangles and {} boxes, not {} and {}",
                self.procedurals,
                triangles.len(),
                boxes.len()
            )));
        }
        if let Some(i) = triangles.iter().position(|t| !t.iter().all(|v| v.is_finite())) {
            return Err(crate::Error::Invalid(format!(
                "refit triangle {i} has a non-finite vertex: {:?}",
                triangles[i]
            )));
        }
        let mut bounds = Vec::with_capacity(self.tris.len());
        for t in &mut self.tris {
            let input = t.input_index() as usize;
            let (lo, hi) = if input < n {
                let v = triangles[input];
                t.v0[..3].copy_from_slice(&v[0].to_array());
                t.v1[..3].copy_from_slice(&v[1].to_array());
                t.v2[..3].copy_from_slice(&v[2].to_array());
                (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]))
            } else {
                let b = boxes[input - n];
                t.v0[..3].copy_from_slice(&b[0].to_array());
                t.v1[..3].copy_from_slice(&b[1].to_array());
                t.v2[..3].copy_from_slice(&b[0].to_array());
                (b[0], b[1])
            };
            bounds.push((lo, hi));
        }
        if self.is_empty() {
            return Ok(());
        }
        // Post-order by an explicit stack (the depth is at most MAX_DEPTH): a node's box once
        // its children's are known.
        let mut stack = vec![(0usize, false)];
        while let Some((i, children_done)) = stack.pop() {
            let node = self.nodes[i];
            let (lo, hi) = if node.is_leaf() {
                let first = node.left_first as usize;
                bounds[first..first + node.tri_count as usize]
                    .iter()
                    .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), b| (lo.min(b.0), hi.max(b.1)))
            } else if !children_done {
                let left = node.left_first as usize;
                stack.extend([(i, true), (left, false), (left + 1, false)]);
                continue;
            } else {
                let [a, b] = [0, 1].map(|k| self.nodes[node.left_first as usize + k]);
                (
                    Vec3::from(a.aabb_min).min(Vec3::from(b.aabb_min)),
                    Vec3::from(a.aabb_max).max(Vec3::from(b.aabb_max)),
                )
            };
            self.nodes[i].aabb_min = lo.into();
            self.nodes[i].aabb_max = hi.into();
        }
        self.stats.sah_cost = build::stats(self, &BuildOptions::default(), n).sah_cost;
        Ok(())
    }

    /// The BVH of no triangles: every ray misses.
    pub fn empty() -> Self {
        let root = BvhNode { aabb_min: [f32::MAX; 3], left_first: 0, aabb_max: [-f32::MAX; 3], tri_count: 0 };
        Self {
            nodes: vec![root],
            tris: Vec::new(),
            prim_order: Vec::new(),
            stats: BvhStats::default(),
            procedurals: 0,
            implicit_texels: Vec::new(),
        }
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The root's bounds; `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        (!self.is_empty()).then(|| (self.nodes[0].aabb_min.into(), self.nodes[0].aabb_max.into()))
    }

    /// Checks every structural invariant: children in range and pairwise at even indices, each
    /// reference in exactly one leaf and every input triangle in at least one, child boxes inside
    /// their parent's, every triangle inside its leaf's box (a split one's box meeting it), depth
    /// within [`MAX_DEPTH`]. Returns the first violation.
    pub fn validate(&self) -> Result<(), String> {
        if self.is_empty() {
            return match self.nodes.as_slice() {
                [root] if root.tri_count == 0 && root.aabb_min[0] > root.aabb_max[0] => {
                    if self.stats.triangles + self.procedurals == self.stats.left_out {
                        Ok(())
                    } else {
                        Err(format!(
                            "an empty BVH of {} inputs left out {}",
                            self.stats.triangles, self.stats.left_out
                        ))
                    }
                }
                _ => Err("an empty BVH must be a single inverted root".into()),
            };
        }
        let mut seen = vec![false; self.tris.len()];
        // How many references each input triangle has: one must lie inside its leaf's box, the
        // pieces of a split one only meet theirs.
        let mut pieces = vec![0u32; self.stats.triangles + self.procedurals];
        for &p in &self.prim_order {
            *pieces.get_mut(p as usize).ok_or(format!("input index {p} out of range"))? += 1;
        }
        let absent = pieces.iter().filter(|&&k| k == 0).count();
        if absent != self.stats.left_out {
            let p = pieces.iter().position(|&k| k == 0).unwrap_or(0);
            return Err(format!(
                "{absent} input triangles are in no leaf (the first {p}), {} were left out",
                self.stats.left_out
            ));
        }
        let mut stack = vec![(0usize, 0usize)];
        while let Some((index, depth)) = stack.pop() {
            if depth >= MAX_DEPTH {
                return Err(format!("node {index} is at depth {depth}, beyond {MAX_DEPTH}"));
            }
            let node = self.nodes.get(index).ok_or(format!("node {index} out of range"))?;
            let (lo, hi) = (Vec3::from(node.aabb_min), Vec3::from(node.aabb_max));
            let inside = |v: Vec3| v.cmpge(lo).all() && v.cmple(hi).all();
            if node.is_leaf() {
                let range = node.left_first as usize..node.left_first as usize + node.tri_count as usize;
                if range.end > self.tris.len() {
                    return Err(format!("leaf {index} points past the triangles"));
                }
                for t in range {
                    if std::mem::replace(&mut seen[t], true) {
                        return Err(format!("triangle {t} is in two leaves"));
                    }
                    let v = self.tris[t].vertices();
                    let fits = if pieces[self.prim_order[t] as usize] == 1 {
                        v.iter().all(|&v| inside(v))
                    } else {
                        let (a, b) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
                        a.cmple(hi).all() && b.cmpge(lo).all()
                    };
                    if !fits {
                        return Err(format!("triangle {t} pokes out of leaf {index}"));
                    }
                }
            } else {
                let left = node.left_first as usize;
                if !left.is_multiple_of(2) || left < 2 || left + 1 >= self.nodes.len() {
                    return Err(format!("node {index} has children at {left}, which is invalid"));
                }
                for child in [left, left + 1] {
                    let c = &self.nodes[child];
                    if !inside(c.aabb_min.into()) || !inside(c.aabb_max.into()) {
                        return Err(format!("child {child} is not inside its parent {index}"));
                    }
                    stack.push((child, depth + 1));
                }
            }
        }
        match seen.iter().position(|s| !s) {
            Some(t) => Err(format!("triangle {t} is in no leaf")),
            None => Ok(()),
        }
    }
}
