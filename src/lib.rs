//! umbra: physically based rendering with raw Vulkan compute kernels.
//!
//! The library builds on [`vk::Context`], either umbra's own headless device or a host engine's
//! ([`vk::Context::from_host`]). Passes record into a caller's command buffer and never submit.
#![warn(missing_docs)]

pub mod atomic;
pub mod bake;
pub mod bvh;
pub mod color;
pub mod embed;
pub mod environment;
pub mod error;
pub mod gpu;
pub mod kernels;
pub mod merge;
pub mod output;
pub mod passes;
pub mod procedural;
pub mod render;
pub mod scene;
pub mod sheen;
pub mod split_sum;
pub mod vk;

pub use error::{Error, Result};
