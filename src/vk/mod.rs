//! The thin Vulkan layer: only what umbra uses.

pub mod barrier;
mod breadcrumb;
mod buffer;
mod commands;
mod context;
mod debug;
mod graph;
mod image;
mod pipeline;
mod recorder;
pub mod specialize;
mod timer;

pub use buffer::{Buffer, TexelBuffer};
pub use context::{Context, ContextDesc, DeviceInfo, HostDevice, MemoryReport, REQUIRED_PUSH_DESCRIPTORS};
pub use debug::ValidationLog;
pub use graph::{Graph, GraphImage, GraphStats, GraphViews, ImageDesc, PassBuilder, TransientPool};
pub use image::Image;
pub use pipeline::{ComputePipeline, Descriptor, PipelineDesc};
pub use recorder::{Recorder, RecorderStats, Resource, Use};
pub use timer::{GpuTimer, PassTime};

pub use ash::vk as raw;
pub use gpu_allocator::MemoryLocation;
