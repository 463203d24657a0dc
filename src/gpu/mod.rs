//! Host-side twins of GPU data and the typed interface of every kernel.
//!
//! [`layout`] is generated from `interface.rs` (the one definition of the structs, constants,
//! bindings, push constants and specialization constants Rust and GLSL share; `build.rs`
//! generates the GLSL side from the same file); [`kernel`] builds and records pipelines from it.

pub mod bvh;
pub mod cache;
pub mod implicit;
pub mod kernel;
pub mod layout;
pub mod scene;

pub use kernel::{Pipeline, SceneFeatures};
pub use layout::kernels;
