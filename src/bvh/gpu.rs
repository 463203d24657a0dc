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
    /// Uploads `bvh` through staging buffers. An empty BVH still gets valid (dummy) buffers.
    pub fn upload(ctx: &Context, bvh: &Bvh) -> Result<Self> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        let dummy = [super::BvhTri::default()];
        let tris = if bvh.tris.is_empty() { &dummy[..] } else { &bvh.tris[..] };
        Ok(Self {
            nodes: Buffer::upload(ctx, "bvh nodes", &bvh.nodes, usage)?,
            tris: Buffer::upload(ctx, "bvh triangles", tris, usage)?,
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

    /// Records a trace of `count` rays from `rays` into `hits`. Never submits.
    pub fn record(
        &self,
        cmd: raw::CommandBuffer,
        query: Query,
        bvh: &GpuBvh,
        rays: &Buffer,
        hits: &Buffer,
        count: u32,
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
                Descriptor::Buffer(rays),
                Descriptor::Buffer(hits),
            ],
        )?;
        pipeline.push_constants(cmd, &TraceParams { count, ..Default::default() })?;
        pipeline.dispatch(cmd, [count, 1, 1], [LOCAL, 1, 1])
    }

    /// Uploads `rays`, traces them and reads the hits back (one submission; for tests).
    pub fn trace(
        &self,
        ctx: &Context,
        query: Query,
        bvh: &GpuBvh,
        rays: &[TraceRay],
    ) -> Result<Vec<TraceHit>> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
        let ray_buffer = Buffer::upload(ctx, "rays", rays, usage)?;
        let hits = Buffer::new(
            ctx,
            "hits",
            (rays.len() * std::mem::size_of::<TraceHit>()) as u64,
            usage,
            MemoryLocation::GpuOnly,
        )?;
        ctx.submit(|cmd| self.record(cmd, query, bvh, &ray_buffer, &hits, rays.len() as u32))?;
        let mut out: Vec<TraceHit> = hits.read(ctx)?;
        out.truncate(rays.len());
        Ok(out)
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
