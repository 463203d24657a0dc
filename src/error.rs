//! umbra's error type. Every message names what failed and, for input, the file.

use ash::vk;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything the library can fail with.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// No Vulkan loader, no driver, or no usable device.
    #[error("{0}")]
    NoDevice(String),
    /// The device lacks a feature or extension umbra needs.
    #[error("device '{device}' cannot run umbra: {missing}")]
    Unsupported {
        /// Device name.
        device: String,
        /// What is missing.
        missing: String,
    },
    /// A Vulkan call failed.
    #[error("Vulkan call {call} failed: {result}{}", pass_hint(.pass))]
    Vulkan {
        /// The entry point that failed.
        call: &'static str,
        /// Its result code.
        result: vk::Result,
        /// The pass of the failed submission, when known: the kernel name first, then where it
        /// stood. From the GPU-written breadcrumb of [`crate::vk::Context::submit`], the first
        /// dispatch the GPU had not finished (`"ssao, dispatch 2 of 4: running or next to run on
        /// the GPU; 1 finished"`); when the work never reached the GPU, the last pass recorded
        /// (`"pathtrace, the last pass recorded; the submission never reached the GPU"`).
        pass: Option<String>,
    },
    /// Device memory could not be allocated.
    #[error("GPU memory allocation for '{name}' failed: {source}")]
    Allocation {
        /// The resource being allocated.
        name: String,
        /// The allocator's reason.
        source: gpu_allocator::AllocationError,
    },
    /// A kernel was not found among the embedded ones.
    #[error("no kernel named '{0}' was compiled into this binary")]
    MissingKernel(String),
    /// A request outside what umbra or the device allows.
    #[error("{0}")]
    Invalid(String),
    /// A file could not be read or written. The message holds the OS's reason once ("not a
    /// directory", "Permission denied"), so the error has no separate source.
    #[error("{path}: {}", crate::atomic::io_message(.error))]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// A scene or environment file is malformed, breaks the glTF rules, or needs what umbra lacks.
    #[error("{path}: {message}")]
    Scene {
        /// The file (or the name of an embedded scene).
        path: std::path::PathBuf,
        /// What is wrong, precisely enough to fix it.
        message: String,
    },
    /// An image file could not be written or read.
    #[error("{path}: {message}")]
    Image {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A probe bake file is not one, is damaged, or does not fit the scene it is loaded for
    /// ([`crate::bake`]).
    #[error("{path}: {message}")]
    Bake {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with it, and what to do.
        message: String,
    },
    /// Submitted GPU work did not finish within the context's submit timeout
    /// ([`crate::vk::Context::set_submit_timeout`]).
    #[error("GPU work did not finish within {seconds} s{}", pass_hint(.pass))]
    Timeout {
        /// The timeout, in seconds.
        seconds: f64,
        /// The pass the GPU was running, from the breadcrumb (as in [`Error::Vulkan`]).
        pass: Option<String>,
    },
}

impl Error {
    /// [`Error::Io`] for `path`.
    pub fn io(path: &std::path::Path, error: std::io::Error) -> Self {
        Error::Io { path: path.to_path_buf(), error }
    }
}

fn pass_hint(pass: &Option<String>) -> String {
    pass.as_ref().map(|p| format!(" (pass {p})")).unwrap_or_default()
}

/// Turns an `ash` result into [`Error::Vulkan`] naming the call.
pub(crate) trait VkContext<T> {
    fn call(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn call(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { call, result, pass: None })
    }
}
