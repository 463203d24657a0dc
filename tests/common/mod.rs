//! Shared test harness: a validated context that fails the test on any validation message,
//! including those raised while the context is destroyed.
#![allow(dead_code)]

use std::ops::Deref;
use std::sync::Arc;
use umbra::vk::{Context, ContextDesc, ValidationLog};

/// A context with `VK_LAYER_KHRONOS_validation` on. Dropping it destroys the device and then
/// panics if the layer reported anything during the test.
pub struct Gpu {
    ctx: Option<Context>,
    log: Arc<ValidationLog>,
}

impl Gpu {
    /// A validated context on the default device (lavapipe in CI).
    pub fn new() -> Self {
        let ctx = Context::new(&ContextDesc { validation: Some(true), device: None })
            .unwrap_or_else(|e| panic!("creating a validated Vulkan context: {e}"));
        let log = ctx.validation().expect("validation is on");
        Self { ctx: Some(ctx), log }
    }

    /// The validation log, for tests that provoke a message on purpose.
    pub fn log(&self) -> &ValidationLog {
        &self.log
    }
}

impl Deref for Gpu {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.ctx.as_ref().expect("context alive until drop")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        drop(self.ctx.take());
        let messages = self.log.take();
        if !messages.is_empty() && !std::thread::panicking() {
            panic!("{} validation message(s):\n{}", messages.len(), messages.join("\n"));
        }
    }
}

/// Runs one of umbra's binaries with `UMBRA_VALIDATION=1` and asserts that it succeeded and
/// logged no error (validation messages are logged as errors); returns its stderr.
pub fn run_validated(command: &mut std::process::Command) -> String {
    let out = command.env("UMBRA_VALIDATION", "1").output().expect("run the binary");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("ERROR"), "validation or other errors: {stderr}");
    stderr
}
