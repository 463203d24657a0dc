//! The BVH on the GPU: its 4-wide layout in two texel buffers, and `trace.comp`, which traces a
//! buffer of rays (closest or any hit) for the traversal tests and the ray-throughput benchmark.

use crate::bvh::traverse::next_up;
use crate::bvh::{Bvh, BvhNode, BvhTri};
use crate::error::{Error, Result};
use crate::gpu::kernel::SceneFeatures;
use crate::gpu::kernels::trace;
pub use crate::gpu::layout::GpuBvhNode;
use crate::gpu::layout::{TraceHit, TraceParams, TraceRay, BVH_REGISTERS};
use crate::gpu::Pipeline;
use crate::vk::{raw, Buffer, Context, Descriptor, MemoryLocation, Recorder, TexelBuffer};
use rayon::prelude::*;
use std::sync::OnceLock;

/// The node and triangle lists of a [`Bvh`], uploaded once: every kernel binds the BVH as two
/// read-only storage texel buffers of RGBA32UI (bindings 0 and 1, see `bvh.glsl`).
pub struct GpuBvh {
    /// `bvh_node_texels`: each [`GpuBvhNode`] as four texels.
    pub nodes: TexelBuffer,
    /// `bvh_tri_texels`: each triangle as three texels, then the implicit shapes' programs.
    pub tris: TexelBuffer,
    /// Whether the BVH holds implicit shapes (procedural primitives): the trace kernel must then
    /// be specialised for them ([`RayTracer::with_implicit`]).
    pub implicit: bool,
    /// The most entries a walk's stack holds ([`GpuBvhNode::stack_depth`]; `umbra render` logs
    /// it): what a stack in registers would need to hold (docs/history/2026-12-04.md,
    /// fourth session).
    pub stack_depth: u32,
}

impl GpuBvh {
    /// The entries of the kernels' register stack for this BVH ([`SceneFeatures::bvh_stack`]):
    /// its stack depth, at least 1, or 0 when that is more than [`BVH_REGISTERS`] (the stack in
    /// memory). A push or pop moves every register (`bvh.glsl`), so the walk carries no more than
    /// it fills: 0.94-0.96 of a small scene's time against 16 (docs/history/2026-12-05.md, seventh session).
    pub fn register_stack(&self) -> u32 {
        register_stack(self.stack_depth)
    }

    /// Uploads `bvh` through staging buffers. Fails for more than [`GpuBvhNode::MAX_NODES`] nodes
    /// or as [`GpuBvhNode::from_bvh`] does.
    pub fn upload(ctx: &Context, bvh: &Bvh) -> Result<Self> {
        Self::upload_nodes(ctx, bvh, GpuBvhNode::from_bvh(bvh)?)
    }

    /// [`GpuBvh::upload`] with `bvh`'s GPU layout already made ([`GpuBvhNode::from_bvh`]).
    pub fn upload_nodes(ctx: &Context, bvh: &Bvh, nodes: Vec<GpuBvhNode>) -> Result<Self> {
        const RGBA32UI: raw::Format = raw::Format::R32G32B32A32_UINT;
        if nodes.len() > GpuBvhNode::MAX_NODES {
            return Err(Error::Invalid(format!(
                "the BVH of {} triangles has {} 4-wide nodes; the traversal addresses at most {}",
                bvh.stats.triangles,
                nodes.len(),
                GpuBvhNode::MAX_NODES
            )));
        }
        // Implicit shapes' programs follow the triangles in the same texel buffer (the walk finds
        // a procedural primitive's program through its v2.w, `bvh.glsl`).
        let tris: Vec<[u32; 4]> = bytemuck::cast_slice::<BvhTri, [u32; 4]>(&bvh.tris)
            .iter()
            .chain(&bvh.implicit_texels)
            .copied()
            .collect();
        Ok(Self {
            nodes: TexelBuffer::upload(ctx, "bvh nodes", &nodes, RGBA32UI, 16)?,
            tris: TexelBuffer::upload(ctx, "bvh triangles", &tris, RGBA32UI, 16)?,
            implicit: bvh.procedurals > 0,
            stack_depth: GpuBvhNode::stack_depth(&nodes),
        })
    }

    /// The BVH's two descriptors (bindings 0 and 1 of every kernel that traces).
    pub fn descriptors(&self) -> [Descriptor<'_>; 2] {
        [Descriptor::Texels(&self.nodes), Descriptor::Texels(&self.tris)]
    }
}

/// A box, `(min, max)`.
type Box3 = ([f32; 3], [f32; 3]);

/// A GPU node while the layout is built: its children (box, child word), how many, its depth.
#[derive(Clone, Copy, Default)]
struct Slot {
    children: [(Box3, u32); 4],
    len: usize,
    depth: u32,
}

/// One child while the layout is built.
#[derive(Clone, Copy)]
enum Kid {
    /// A binary inner node.
    Inner(usize),
    /// Triangles `first..first + count` of binary leaf `leaf` (all of it or a part).
    Leaf { leaf: usize, first: u32, count: u32 },
}

impl GpuBvhNode {
    /// Children per node.
    pub const WIDTH: usize = 4;

    /// The child word's count of a child that is not there (never hit): all of them in the root
    /// of an empty BVH, and those a node has fewer than four of.
    pub const NONE: u32 = 15;

    /// The most triangles a GPU leaf holds (the child word's 4 bits); a larger leaf of the binary
    /// BVH becomes a small subtree of GPU nodes whose leaves share its box.
    pub const MAX_LEAF: u32 = 14;

    /// The most nodes the traversal addresses: its stack entries keep a node index in 24 bits
    /// (`bvh.glsl`), about 50 million triangles.
    pub const MAX_NODES: usize = 1 << 24;

    /// Nodes this close to the root (at most 1,365 of them) get the grid that grows their
    /// children's boxes least among a few (`Grid::fit_least_growth`), the others the one through
    /// their bounds: +2–3 % shadow rays on Sponza for no measurable layout time; for all nodes it
    /// gained no more and took 3× the time (docs/history/2026-12-01.md, third round).
    const SEARCH_DEPTH: u32 = 6;

    /// The most triangle references a child word addresses (28 bits).
    pub const MAX_TRIANGLES: usize = 1 << 28;

    /// The GPU layout of `bvh`, nodes in depth-first order of creation (a node's inner children
    /// get consecutive slots, which the traversal stack relies on); a BVH that is a single leaf
    /// or empty gets a root whose children are that leaf or absent. Fails for more than
    /// [`GpuBvhNode::MAX_TRIANGLES`] references or a box beyond the grid's reach (a step above
    /// 2^52: a scene more than about 1e18 across).
    pub fn from_bvh(bvh: &Bvh) -> Result<Vec<Self>> {
        if bvh.tris.len() > Self::MAX_TRIANGLES {
            return Err(Error::Invalid(format!(
                "the BVH holds {} triangle references; the GPU layout addresses at most {}",
                bvh.tris.len(),
                Self::MAX_TRIANGLES
            )));
        }
        let nodes = &bvh.nodes;
        let root = &nodes[0];
        let empty = !root.is_leaf() && root.aabb_min[0] > root.aabb_max[0];
        let box_of = |kid: &Kid| {
            let n = &nodes[match *kid {
                Kid::Inner(n) => n,
                Kid::Leaf { leaf, .. } => leaf,
            }];
            (n.aabb_min, n.aabb_max)
        };
        // The tree first, about one GPU node per three binary ones; then the grids, in parallel.
        let mut slots: Vec<Slot> = Vec::with_capacity(nodes.len() / 3 + 1);
        slots.push(Slot::default());
        let root_kid = if root.is_leaf() {
            Kid::Leaf { leaf: 0, first: root.left_first, count: root.tri_count }
        } else {
            Kid::Inner(0)
        };
        let mut work = if empty { Vec::new() } else { vec![(root_kid, 0usize)] };
        while let Some((kid, slot)) = work.pop() {
            let kids = match kid {
                Kid::Inner(n) => Self::collapse(nodes, n),
                Kid::Leaf { leaf, first, count } => {
                    let parts = count.div_ceil(Self::MAX_LEAF).min(Self::WIDTH as u32);
                    let size = count.div_ceil(parts);
                    (0..parts)
                        .map(|p| Kid::Leaf {
                            leaf,
                            first: first + p * size,
                            count: size.min(count - p * size),
                        })
                        .collect()
                }
            };
            for (c, kid) in kids.into_iter().enumerate() {
                let word = match kid {
                    Kid::Leaf { first, count, .. } if count <= Self::MAX_LEAF => first << 4 | count,
                    _ => {
                        let depth = slots[slot].depth + 1;
                        slots.push(Slot { depth, ..Slot::default() });
                        work.push((kid, slots.len() - 1));
                        ((slots.len() - 1) as u32) << 4
                    }
                };
                slots[slot].children[c] = (box_of(&kid), word);
                slots[slot].len = c + 1;
            }
        }
        slots.par_iter().map(|s| Self::new(&s.children[..s.len], s.depth < Self::SEARCH_DEPTH)).collect()
    }

    /// The children of binary inner node `n` in a 4-wide node: its two, then the largest-area
    /// inner child opened until there are four or only leaves.
    fn collapse(nodes: &[BvhNode], n: usize) -> Vec<Kid> {
        let first = nodes[n].left_first as usize;
        let mut kids = vec![first, first + 1];
        while kids.len() < Self::WIDTH {
            let widest = (0..kids.len())
                .filter(|&k| !nodes[kids[k]].is_leaf())
                .max_by(|&a, &b| nodes[kids[a]].surface_area().total_cmp(&nodes[kids[b]].surface_area()));
            let Some(k) = widest else { break };
            let opened = kids.remove(k);
            let first = nodes[opened].left_first as usize;
            kids.extend([first, first + 1]);
        }
        kids.into_iter()
            .map(|k| match &nodes[k] {
                leaf if leaf.is_leaf() => {
                    Kid::Leaf { leaf: k, first: leaf.left_first, count: leaf.tri_count }
                }
                _ => Kid::Inner(k),
            })
            .collect()
    }

    /// A node of up to four children (box, child word), on each axis the grid through their
    /// bounds or, with `search`, the one of a few that grows their boxes least.
    fn new(children: &[(Box3, u32)], search: bool) -> Result<Self> {
        let mut node = Self { child: [Self::NONE; 4], ..Default::default() };
        for axis in 0..3 {
            let mut planes = [[0.0f32; 2]; 4];
            for (p, (b, _)) in planes.iter_mut().zip(children) {
                *p = [b.0[axis], b.1[axis]];
            }
            let planes = &planes[..children.len()];
            let grid = if search {
                // A box's area grows by its other two extents per unit of this one.
                let mut weights = [0.0f64; 4];
                for (w, (b, _)) in weights.iter_mut().zip(children) {
                    let extent = |k: usize| f64::from(b.1[k] - b.0[k]);
                    *w = extent((axis + 1) % 3) + extent((axis + 2) % 3);
                }
                Grid::fit_least_growth(planes, &weights[..children.len()])
            } else {
                Grid::fit(planes)
            };
            let grid = grid.ok_or_else(|| {
                Error::Invalid(format!(
                    "a BVH node's boxes span {planes:?} on axis {axis}; the GPU layout takes boxes within about 1e18"
                ))
            })?;
            node.origin[axis] = grid.origin;
            node.step[axis] = grid.step;
            for (c, &[lo, hi]) in planes.iter().enumerate() {
                node.lo[axis][c] = grid.below(lo);
                node.hi[axis][c] = grid.above(hi);
            }
        }
        for (c, &(_, word)) in children.iter().enumerate() {
            node.child[c] = word;
        }
        Ok(node)
    }

    /// Child `c`'s count: 0 inner, [`GpuBvhNode::NONE`] absent, else a leaf's triangles.
    pub fn count(&self, c: usize) -> u32 {
        self.child[c] & 15
    }

    /// Child `c`'s index: an inner child's node, a leaf's first triangle.
    pub fn index(&self, c: usize) -> u32 {
        self.child[c] >> 4
    }

    /// The most entries the traversal's stack (`bvh.glsl`) holds in a walk of `nodes` from node
    /// 0: a visit with two or more inner children hit pushes one entry, which stays while the walk
    /// is below its node, so this is the most nodes with two or more inner children on a path
    /// from the root (0 for an empty BVH).
    pub fn stack_depth(nodes: &[GpuBvhNode]) -> u32 {
        fn depth(nodes: &[GpuBvhNode], i: usize) -> u32 {
            let node = &nodes[i];
            let inner: Vec<usize> =
                (0..4).filter(|&c| node.count(c) == 0).map(|c| node.index(c) as usize).collect();
            let below = inner.iter().map(|&c| depth(nodes, c)).max().unwrap_or(0);
            below + u32::from(inner.len() >= 2)
        }
        if nodes.is_empty() {
            0
        } else {
            depth(nodes, 0)
        }
    }

    /// Child `c`'s box as the traversal sees it (to the nearest float64 of its exact planes), or
    /// `None` for an absent child.
    pub fn child_box(&self, c: usize) -> Option<([f64; 3], [f64; 3])> {
        (self.count(c) != Self::NONE).then(|| {
            let grid = |axis: usize| Grid { origin: self.origin[axis], step: self.step[axis] };
            (
                std::array::from_fn(|axis| grid(axis).plane(self.lo[axis][c]).0),
                std::array::from_fn(|axis| grid(axis).plane(self.hi[axis][c]).0),
            )
        })
    }
}

/// One axis of a node's grid: planes at `origin + q * step` for q in 0..=255, each exactly the
/// unevaluated sum of two float64s (`plane`), so the rounding of boxes to the grid is exact.
#[derive(Clone, Copy, Debug)]
struct Grid {
    origin: f32,
    step: f32,
}

impl Grid {
    /// The finest step (2^-64): `step / d` stays a normal float for any direction the traversal
    /// meets (components are at least 1e-20), and a flat axis takes it.
    const MIN_STEP: f32 = 5.421_011e-20;
    /// The coarsest step (2^52, boxes up to about 1e18): `step / d` stays finite for a direction
    /// component of 1e-20, and so does `(origin - o) / d` for ray origins within about 3e18 of the
    /// scene, which the slab test's slack needs (`bvh.glsl`).
    const MAX_STEP: f32 = 4_503_599_627_370_496.0;

    /// Of the grid through the children's bounds (`fit`) and those through one bound and one of
    /// the children's planes inside (to a float's precision), the one whose rounding grows the
    /// children's boxes least, each axis's growth weighted by `weights` (the other two extents).
    /// A child's plane inside the node, such as where the two halves of a symmetric scene meet,
    /// then often stays exact: where a camera on the symmetry plane would otherwise be inside
    /// both halves' grown boxes.
    fn fit_least_growth(planes: &[[f32; 2]], weights: &[f64]) -> Option<Self> {
        let natural = Self::fit(planes)?;
        let (lo, hi) = Self::span(planes);
        let (lo64, hi64) = (f64::from(lo), f64::from(hi));
        let growth = |g: &Self| -> f64 {
            let moved = |[a, b]: [f32; 2]| {
                f64::from(a) - g.plane(g.below(a)).0 + g.plane(g.above(b)).0 - f64::from(b)
            };
            planes.iter().zip(weights).map(|(&p, w)| w * moved(p)).sum()
        };
        let at = |p: f64| 255.0 * (p - lo64) / (hi64 - lo64);
        let inside = planes.iter().flatten().map(|&p| f64::from(p)).filter(|&p| p > lo64 && p < hi64);
        inside
            .flat_map(|p| {
                let (below, above) = ((at(p).floor() as u8).max(1), (at(p).ceil() as u8).min(254));
                [Self::through(lo64, 0, p, below, lo, hi), Self::through(p, above, hi64, 255, lo, hi)]
            })
            .flatten()
            .fold((growth(&natural), natural), |best, g| {
                let c = growth(&g);
                if c < best.0 {
                    (c, g)
                } else {
                    best
                }
            })
            .1
            .into()
    }

    /// The grid with plane `i` at (about) `p` and plane `j` at `r`, moved down and widened by
    /// ulps until it spans `[lo, hi]`, if its step is within reach.
    fn through(p: f64, i: u8, r: f64, j: u8, lo: f32, hi: f32) -> Option<Self> {
        let step = ((r - p) / f64::from(j - i)).max(f64::from(Self::MIN_STEP));
        let mut grid = Self { origin: round_down(p - f64::from(i) * step), step: round_up(step) };
        for _ in 0..16 {
            if grid.at_or_below(0, lo) {
                break;
            }
            grid.origin = next_down(grid.origin);
        }
        for _ in 0..16 {
            if grid.at_or_above(255, hi) {
                break;
            }
            grid.step = next_up(grid.step);
        }
        let fits = grid.at_or_below(0, lo) && grid.at_or_above(255, hi);
        (fits && grid.origin.is_finite() && grid.step <= Self::MAX_STEP).then_some(grid)
    }

    /// The grid whose first and last planes are (to a float's precision, and outward) the
    /// children's lowest and highest planes on this axis (`planes`, lower and upper), or `None`
    /// for boxes beyond the coarsest step or not finite. A flat axis takes the finest step.
    fn fit(planes: &[[f32; 2]]) -> Option<Self> {
        let (lo, hi) = Self::span(planes);
        if planes.is_empty() || (lo == hi && lo.is_finite()) {
            let origin = if planes.is_empty() { 0.0 } else { lo };
            return Some(Self { origin, step: Self::MIN_STEP });
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return None;
        }
        Self::through(f64::from(lo), 0, f64::from(hi), 255, lo, hi)
    }

    /// The lowest and highest of `planes` (lower, upper): infinite and inverted for none.
    fn span(planes: &[[f32; 2]]) -> (f32, f32) {
        let lo = planes.iter().map(|p| p[0]).fold(f32::INFINITY, f32::min);
        let hi = planes.iter().map(|p| p[1]).fold(f32::NEG_INFINITY, f32::max);
        (lo, hi)
    }

    /// Plane `q` exactly, as `(s, e)` with `s` the nearest float64 and `s + e` the plane: `q *
    /// step` is exact in float64 (8 by 24 bits), and TwoSum gives the sum's rounding error.
    fn plane(&self, q: u8) -> (f64, f64) {
        let (a, b) = (f64::from(self.origin), f64::from(q) * f64::from(self.step));
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    /// How plane `q` compares with `v`, exactly: the nearest float64 of the plane decides unless
    /// it is `v` itself (any other float64 lies beyond the plane's rounding error).
    fn compare(&self, q: u8, v: f32) -> std::cmp::Ordering {
        let ((s, e), v) = (self.plane(q), f64::from(v));
        if s != v {
            return s.total_cmp(&v);
        }
        e.partial_cmp(&0.0).unwrap_or(std::cmp::Ordering::Equal)
    }

    fn at_or_below(&self, q: u8, v: f32) -> bool {
        self.compare(q, v).is_le()
    }

    fn at_or_above(&self, q: u8, v: f32) -> bool {
        self.compare(q, v).is_ge()
    }

    /// About the plane at `v` (truncated: `v` is at or above the origin).
    fn guess(&self, v: f32) -> u8 {
        ((f64::from(v) - f64::from(self.origin)) / f64::from(self.step)).clamp(0.0, 255.0) as u8
    }

    /// The highest plane at or below `v` (plane 0 is).
    fn below(&self, v: f32) -> u8 {
        let mut q = self.guess(v);
        while q > 0 && !self.at_or_below(q, v) {
            q -= 1;
        }
        while q < 255 && self.at_or_below(q + 1, v) {
            q += 1;
        }
        q
    }

    /// The lowest plane at or above `v` (plane 255 is).
    fn above(&self, v: f32) -> u8 {
        let mut q = self.guess(v);
        while q < 255 && !self.at_or_above(q, v) {
            q += 1;
        }
        while q > 0 && self.at_or_above(q - 1, v) {
            q -= 1;
        }
        q
    }
}

/// The next float below finite `x`.
fn next_down(x: f32) -> f32 {
    -next_up(-x)
}

/// The smallest float at or above `x`.
fn round_up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        next_up(y)
    } else {
        y
    }
}

/// The largest float at or below `x`.
fn round_down(x: f64) -> f32 {
    -round_up(-x)
}

/// The entries of the kernels' register stack for a BVH whose walk holds at most `stack_depth`
/// ([`GpuBvh::register_stack`]): that, at least 1, or 0 (the stack in memory) beyond
/// [`BVH_REGISTERS`].
pub fn register_stack(stack_depth: u32) -> u32 {
    if stack_depth <= BVH_REGISTERS {
        stack_depth.max(1)
    } else {
        0
    }
}

/// Which query `trace.comp` answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Query {
    /// Nearest hit: t, triangle, barycentrics.
    Closest,
    /// Any hit in (tmin, tmax): occlusion only.
    Any,
}

/// `trace.comp` specialised for both queries and every walk: a BVH whose walk holds at most
/// [`BVH_REGISTERS`] stack entries is traced with a stack of as many registers
/// ([`GpuBvh::register_stack`]), any other with the stack in memory. Each pipeline is made on
/// its first use.
pub struct RayTracer {
    /// Index: (BVH_REGISTERS + 1) × any-hit + the register stack's entries (0: in memory).
    pipelines: [OnceLock<Pipeline<trace::Kernel>>; 2 * STACKS],
    implicit: bool,
    ctx: Context,
}

/// The register stacks a kernel may walk with, and the stack in memory.
const STACKS: usize = BVH_REGISTERS as usize + 1;

impl RayTracer {
    /// Builds the pipelines, for BVHs of triangles only (implicit shapes compiled out: they are
    /// never hit).
    pub fn new(ctx: &Context) -> Result<Self> {
        Self::with_implicit(ctx, false)
    }

    /// Builds the pipelines of both queries for the deepest register stack (the others when a
    /// BVH needs them); `implicit`: ray-march the BVH's implicit shapes.
    pub fn with_implicit(ctx: &Context, implicit: bool) -> Result<Self> {
        let tracer = Self { pipelines: std::array::from_fn(|_| OnceLock::new()), implicit, ctx: ctx.clone() };
        for query in [Query::Closest, Query::Any] {
            tracer.pipeline(query, BVH_REGISTERS)?;
        }
        Ok(tracer)
    }

    /// The pipeline for `query` with a register stack of `entries` (0: the stack in memory).
    fn pipeline(&self, query: Query, entries: u32) -> Result<&Pipeline<trace::Kernel>> {
        let any = query == Query::Any;
        let cell = &self.pipelines[STACKS * any as usize + entries as usize];
        if let Some(pipeline) = cell.get() {
            return Ok(pipeline);
        }
        let features = SceneFeatures { implicit: self.implicit, bvh_stack: entries, ..Default::default() };
        let pipeline = Pipeline::new(&self.ctx, &trace::Spec { trace_any: any }, Some(&features))?;
        Ok(cell.get_or_init(|| pipeline))
    }

    /// Records a trace of `batch`'s rays into its hits. Never submits.
    pub fn record(&self, rec: &mut Recorder<'_>, query: Query, bvh: &GpuBvh, batch: &RayBatch) -> Result<()> {
        self.pipeline(query, bvh.register_stack())?.record(
            rec,
            &trace::Resources { bvh, rays: &batch.rays, hits: &batch.hits },
            &TraceParams { count: batch.count, ..Default::default() },
            [batch.count, 1, 1],
        )
    }

    /// Uploads `rays`, traces them and reads the hits back (one submission; for tests).
    pub fn trace(
        &self,
        ctx: &Context,
        query: Query,
        bvh: &GpuBvh,
        rays: &[TraceRay],
    ) -> Result<Vec<TraceHit>> {
        let batch = RayBatch::new(ctx, rays)?;
        ctx.record(|rec| self.record(rec, query, bvh, &batch))?;
        batch.read_hits(ctx)
    }
}

/// Rays on the GPU and room for their hits: traced once or many times (the benchmark).
pub struct RayBatch {
    /// `TraceRay`s.
    pub rays: Buffer,
    /// `TraceHit`s, one per ray.
    pub hits: Buffer,
    /// Number of rays.
    pub count: u32,
}

impl RayBatch {
    /// Uploads `rays` and allocates their hits.
    pub fn new(ctx: &Context, rays: &[TraceRay]) -> Result<Self> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
        let size = (rays.len() * std::mem::size_of::<TraceHit>()) as u64;
        Ok(Self {
            rays: Buffer::upload(ctx, "rays", rays, usage)?,
            hits: Buffer::new(ctx, "hits", size, usage, MemoryLocation::GpuOnly)?,
            count: rays.len() as u32,
        })
    }

    /// The hits of the last trace.
    pub fn read_hits(&self, ctx: &Context) -> Result<Vec<TraceHit>> {
        let mut hits: Vec<TraceHit> = self.hits.read(ctx)?;
        hits.truncate(self.count as usize);
        Ok(hits)
    }
}

impl From<&crate::bvh::Ray> for TraceRay {
    fn from(ray: &crate::bvh::Ray) -> Self {
        Self { origin_tmin: ray.origin.extend(ray.tmin).into(), dir_tmax: ray.dir.extend(ray.tmax).into() }
    }
}

impl TraceHit {
    /// The hit as a [`crate::bvh::Hit`], `None` for a miss (closest-hit mode only).
    pub fn hit(&self) -> Option<crate::bvh::Hit> {
        (self.tri != TraceHit::MISS).then_some(crate::bvh::Hit {
            t: self.t,
            tri: self.tri,
            bary: [self.u, self.v],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node whose children are `words` (`index << 4 | count`; absent ones NONE).
    fn node(words: [u32; 4]) -> GpuBvhNode {
        GpuBvhNode { child: words, ..bytemuck::Zeroable::zeroed() }
    }

    /// Only nodes with two or more inner children push, and the deepest path's pushes count.
    #[test]
    fn stack_depth_counts_the_pushes_on_the_deepest_path() {
        let none = GpuBvhNode::NONE;
        let inner = |i: u32| i << 4;
        let leaf = 1;
        // 0: inner 1, inner 2; 1: inner 3, inner 4, leaf; 2: leaf; 3: inner 5 alone; 4, 5: leaves.
        let nodes = [
            node([inner(1), inner(2), none, none]),
            node([inner(3), inner(4), leaf, none]),
            node([leaf, none, none, none]),
            node([inner(5), leaf, none, none]),
            node([leaf, leaf, none, none]),
            node([leaf, none, none, none]),
        ];
        assert_eq!(GpuBvhNode::stack_depth(&nodes), 2);
        assert_eq!(GpuBvhNode::stack_depth(&nodes[2..3]), 0);
        assert_eq!(GpuBvhNode::stack_depth(&[]), 0);
    }
}
