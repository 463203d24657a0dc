//! The compute kernels of `spirv/`, compiled to SPIR-V by build.rs and embedded in the binary.

/// Embedded bytes aligned to 4, so they can be read as SPIR-V words without a copy.
#[repr(C)]
pub struct Aligned<B: ?Sized> {
    _align: [u32; 0],
    bytes: B,
}

/// One compiled kernel: its file stem in `spirv/` and its SPIR-V.
pub struct Kernel {
    /// File stem, e.g. `"test_pattern"` for `spirv/test_pattern.comp`.
    pub name: &'static str,
    spirv: &'static Aligned<[u8]>,
}

impl Kernel {
    /// SPIR-V 1.6 words.
    pub fn words(&self) -> &'static [u32] {
        bytemuck::cast_slice(&self.spirv.bytes)
    }
}

impl std::fmt::Debug for Kernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Kernel({}, {} words)", self.name, self.spirv.bytes.len() / 4)
    }
}

macro_rules! words {
    ($path:expr) => {
        &Aligned { _align: [], bytes: *include_bytes!($path) }
    };
}

include!(concat!(env!("OUT_DIR"), "/kernels.rs"));

/// The kernel compiled from `spirv/<name>.comp`.
pub fn kernel(name: &str) -> Option<&'static Kernel> {
    KERNELS.iter().find(|k| k.name == name)
}
