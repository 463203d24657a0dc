//! The BVH on the GPU: its two storage buffers, and `trace.comp`, which traces a buffer of rays
//! (closest or any hit) for the traversal tests and the ray-throughput benchmark.

use super::Bvh;
use crate::error::Result;
use crate::gpu::layout::{TraceHit, TraceParams, TraceRay};
use crate::vk::{raw, Buffer, ComputePipeline, Context, Descriptor, MemoryLocation, PipelineDesc};

/// The node and triangle buffers of a [`Bvh`], uploaded once.
pub struct GpuBvh {
    /// `bvh_nodes[]`.
    pub nodes: Buffer,
    /// `bvh_tris[]`.
    pub tris: Buffer,
}

impl GpuBvh {
    /// Uploads `bvh` through staging buffers (an empty BVH's triangle list still gets a minimal
    /// buffer: see [`Buffer::new`]).
    pub fn upload(ctx: &Context, bvh: &Bvh) -> Result<Self> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            nodes: Buffer::upload(ctx, "bvh nodes", &bvh.nodes, usage)?,
            tris: Buffer::upload(ctx, "bvh triangles", &bvh.tris, usage)?,
        })
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
                    bindings: &[raw::DescriptorType::STORAGE_BUFFER; 4],
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
                Descriptor::Buffer(&bvh.nodes),
                Descriptor::Buffer(&bvh.tris),
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
