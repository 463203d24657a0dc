//! Host-side twins of GPU data.

pub mod layout;
pub mod scene;
