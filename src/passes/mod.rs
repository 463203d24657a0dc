//! Render passes: each owns its pipelines and records into a caller's command buffer.

pub mod ao;
pub mod deferred;
pub mod denoise;
pub mod gbuffer;
pub mod ibl;
pub mod lightmap;
pub mod pathtrace;
pub mod probes;
pub mod restir;
pub mod shadow;
pub mod taa;
pub mod temporal;
pub mod tonemap;
pub mod visibility;
pub mod wavefront;
