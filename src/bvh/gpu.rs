//! The BVH on the GPU: its 4-wide layout in two texel buffers, and `trace.comp`, which traces a
//! buffer of rays (closest or any hit) for the traversal tests and the ray-throughput benchmark.

use super::{Bvh, BvhNode};
use crate::error::{Error, Result};
use crate::gpu::layout::{TraceHit, TraceParams, TraceRay};
use crate::vk::{
    raw, Buffer, ComputePipeline, Context, Descriptor, MemoryLocation, PipelineDesc, TexelBuffer,
};

/// The node and triangle lists of a [`Bvh`], uploaded once: every kernel binds the BVH as two
/// read-only storage texel buffers of RGBA32UI (bindings 0 and 1, see `bvh.glsl`).
pub struct GpuBvh {
    /// `bvh_node_texels`: each [`GpuBvhNode`] as eight texels.
    pub nodes: TexelBuffer,
    /// `bvh_tri_texels`: each triangle as three texels.
    pub tris: TexelBuffer,
}

impl GpuBvh {
    /// Uploads `bvh` through staging buffers. Fails for more than [`GpuBvhNode::MAX_NODES`] nodes.
    pub fn upload(ctx: &Context, bvh: &Bvh) -> Result<Self> {
        const RGBA32UI: raw::Format = raw::Format::R32G32B32A32_UINT;
        let nodes = GpuBvhNode::from_bvh(bvh);
        if nodes.len() > GpuBvhNode::MAX_NODES {
            return Err(Error::Invalid(format!(
                "the BVH of {} triangles has {} 4-wide nodes; the traversal addresses at most {}",
                bvh.stats.triangles,
                nodes.len(),
                GpuBvhNode::MAX_NODES
            )));
        }
        Ok(Self {
            nodes: TexelBuffer::upload(ctx, "bvh nodes", &nodes, RGBA32UI, 16)?,
            tris: TexelBuffer::upload(ctx, "bvh triangles", &bvh.tris, RGBA32UI, 16)?,
        })
    }

    /// The descriptor types of the BVH's two bindings (0 and 1 of every kernel that traces).
    pub const BINDINGS: [raw::DescriptorType; 2] = [raw::DescriptorType::STORAGE_TEXEL_BUFFER; 2];

    /// The BVH's two descriptors, in the order of [`GpuBvh::BINDINGS`].
    pub fn descriptors(&self) -> [Descriptor<'_>; 2] {
        [Descriptor::Texels(&self.nodes), Descriptor::Texels(&self.tris)]
    }
}

/// One child of a [`GpuBvhNode`]: its box, and what it is.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBvhChild {
    /// Box minimum.
    pub aabb_min: [f32; 3],
    /// An inner child: its [`GpuBvhNode`]. A leaf: its first triangle.
    pub index: u32,
    /// Box maximum.
    pub aabb_max: [f32; 3],
    /// 0 for an inner child, the triangle count of a leaf, or [`GpuBvhChild::NONE`].
    pub count: u32,
}

impl GpuBvhChild {
    /// The `count` of a child that is not there (never hit): the root's second child when the
    /// whole BVH is one leaf, both when it is empty.
    pub const NONE: u32 = u32::MAX;

    fn none() -> Self {
        Self { count: Self::NONE, ..Default::default() }
    }
}

/// The BVH as the GPU traverses it: a 4-wide tree collapsed from [`Bvh::nodes`] (each node
/// takes its binary node's two children and opens the largest-area inner child until it has four
/// or only leaves), holding all children's boxes (Aila and Laine 2009), so one step fetches 128
/// bytes (eight texels), tests four boxes, and the triangles of the leaf children hit are tested
/// in the same step. Node 0 is the root.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBvhNode {
    /// Up to four children; absent ones have `count == GpuBvhChild::NONE`.
    pub children: [GpuBvhChild; 4],
}
const _: () = assert!(std::mem::size_of::<GpuBvhNode>() == 128);

impl GpuBvhNode {
    /// Children per node.
    pub const WIDTH: usize = 4;

    /// The most nodes the traversal addresses: its stack entries keep a node index in 24 bits
    /// (`bvh.glsl`), about 50 million triangles.
    pub const MAX_NODES: usize = 1 << 24;

    /// The GPU layout of `bvh`, nodes in depth-first order of creation (a node's inner children
    /// get consecutive slots, which the traversal stack relies on); a BVH that is a single leaf
    /// or empty gets one root whose children are that leaf or absent.
    pub fn from_bvh(bvh: &Bvh) -> Vec<Self> {
        let nodes = &bvh.nodes;
        let root = &nodes[0];
        let none = GpuBvhChild::none();
        if root.is_leaf() || root.aabb_min[0] > root.aabb_max[0] {
            let only = if root.is_leaf() { Self::child(root, 0) } else { none };
            return vec![Self { children: [only, none, none, none] }];
        }
        let mut out = vec![Self::default()];
        // (binary inner node, its slot in `out`)
        let mut work = vec![(0usize, 0usize)];
        while let Some((n, slot)) = work.pop() {
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
            let mut node = Self { children: [none; 4] };
            for (c, &k) in kids.iter().enumerate() {
                let index = if nodes[k].is_leaf() {
                    0
                } else {
                    out.push(Self::default());
                    work.push((k, out.len() - 1));
                    (out.len() - 1) as u32
                };
                node.children[c] = Self::child(&nodes[k], index);
            }
            out[slot] = node;
        }
        out
    }

    fn child(node: &BvhNode, gpu_index: u32) -> GpuBvhChild {
        let (index, count) = if node.is_leaf() { (node.left_first, node.tri_count) } else { (gpu_index, 0) };
        GpuBvhChild { aabb_min: node.aabb_min, index, aabb_max: node.aabb_max, count }
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

/// `trace.comp` specialised for both queries.
pub struct RayTracer {
    closest: ComputePipeline,
    any: ComputePipeline,
}

/// Workgroup size of `trace.comp`.
const LOCAL: u32 = 64;

impl RayTracer {
    /// Builds both pipelines.
    pub fn new(ctx: &Context) -> Result<Self> {
        let make = |any: u32| {
            ComputePipeline::new(
                ctx,
                "trace",
                &PipelineDesc {
                    bindings: &[
                        GpuBvh::BINDINGS[0],
                        GpuBvh::BINDINGS[1],
                        raw::DescriptorType::STORAGE_BUFFER,
                        raw::DescriptorType::STORAGE_BUFFER,
                    ],
                    push_constant_size: std::mem::size_of::<TraceParams>() as u32,
                    specialization: &[(0, any)],
                },
            )
        };
        Ok(Self { closest: make(0)?, any: make(1)? })
    }

    /// Records a trace of `batch`'s rays into its hits. Never submits.
    pub fn record(
        &self,
        cmd: raw::CommandBuffer,
        query: Query,
        bvh: &GpuBvh,
        batch: &RayBatch,
    ) -> Result<()> {
        let pipeline = match query {
            Query::Closest => &self.closest,
            Query::Any => &self.any,
        };
        pipeline.bind(cmd);
        pipeline.push_descriptors(
            cmd,
            &[
                bvh.descriptors()[0],
                bvh.descriptors()[1],
                Descriptor::Buffer(&batch.rays),
                Descriptor::Buffer(&batch.hits),
            ],
        )?;
        pipeline.push_constants(cmd, &TraceParams { count: batch.count, ..Default::default() })?;
        pipeline.dispatch(cmd, [batch.count, 1, 1], [LOCAL, 1, 1])
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
        ctx.submit(|cmd| self.record(cmd, query, bvh, &batch))?;
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

impl From<&super::Ray> for TraceRay {
    fn from(ray: &super::Ray) -> Self {
        Self { origin_tmin: ray.origin.extend(ray.tmin).into(), dir_tmax: ray.dir.extend(ray.tmax).into() }
    }
}

impl TraceHit {
    /// The hit as a [`super::Hit`], `None` for a miss (closest-hit mode only).
    pub fn hit(&self) -> Option<super::Hit> {
        (self.tri != TraceHit::MISS).then_some(super::Hit {
            t: self.t,
            tri: self.tri,
            bary: [self.u, self.v],
        })
    }
}
