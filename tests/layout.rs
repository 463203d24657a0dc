//! Host/GPU struct layouts: every struct of `spirv/include/layout.glsl` against its Rust twin,
//! read from the compiled SPIR-V with naga.

use naga::{ArraySize, Module, TypeInner};
use std::collections::{BTreeSet, HashMap};
use umbra::gpu::layout::{gpu_layouts, StructLayout};
use umbra::kernels::KERNELS;

fn parse(words: &[u32]) -> Result<Module, String> {
    let words = texel_buffers_as_1d(words);
    let bytes: &[u8] = bytemuck::cast_slice(&words);
    naga::front::spv::parse_u8_slice(bytes, &naga::front::spv::Options::default())
        .map_err(|e| format!("{e:?}"))
}

/// naga has no texel buffers (its `ImageDimension` lacks SPIR-V's `Buffer`), which every kernel
/// that traces binds for the BVH: present them to it as 1D storage images, which it reads the
/// same way (`OpImageRead` by one integer coordinate), and drop the `SampledBuffer` and
/// `ImageBuffer` capabilities. Nothing else of the module changes, so the struct layouts it
/// checks are the kernel's own.
fn texel_buffers_as_1d(words: &[u32]) -> Vec<u32> {
    const OP_CAPABILITY: u32 = 17;
    const OP_TYPE_IMAGE: u32 = 25;
    const CAPABILITY_SAMPLED_BUFFER: u32 = 46;
    const CAPABILITY_IMAGE_BUFFER: u32 = 47;
    const DIM_1D: u32 = 0;
    const DIM_BUFFER: u32 = 5;
    let mut out = words[..5].to_vec();
    let mut i = 5;
    while i < words.len() {
        let (count, opcode) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let mut instruction = words[i..i + count.max(1)].to_vec();
        i += count.max(1);
        match opcode {
            OP_CAPABILITY
                if [CAPABILITY_SAMPLED_BUFFER, CAPABILITY_IMAGE_BUFFER].contains(&instruction[1]) =>
            {
                continue
            }
            OP_TYPE_IMAGE if instruction[3] == DIM_BUFFER => instruction[3] = DIM_1D,
            _ => {}
        }
        out.extend(instruction);
    }
    out
}

/// Differences between the host layouts and every named struct of `module`, plus the names of
/// host structs whose array stride the module proves.
fn compare(module: &Module, host: &[StructLayout]) -> (Vec<String>, BTreeSet<String>) {
    let by_name: HashMap<&str, &StructLayout> = host.iter().map(|s| (s.name, s)).collect();
    let mut layouter = naga::proc::Layouter::default();
    if let Err(e) = layouter.update(module.to_ctx()) {
        return (vec![format!("naga layouter: {e:?}")], BTreeSet::new());
    }
    let mut errors = Vec::new();
    let mut strided = BTreeSet::new();
    for (handle, ty) in module.types.iter() {
        match &ty.inner {
            TypeInner::Struct { members, .. } => {
                let Some(h) = ty.name.as_deref().and_then(|n| by_name.get(n)) else { continue };
                let gpu: Vec<(String, u32, u32)> = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset, layouter[m.ty].size))
                    .collect();
                let cpu: Vec<(String, u32, u32)> =
                    h.members.iter().map(|m| (m.name.to_string(), m.offset as u32, m.size as u32)).collect();
                if gpu != cpu {
                    errors.push(format!("{}: GPU (name, offset, size) {gpu:?} != host {cpu:?}", h.name));
                }
                let _ = handle;
            }
            TypeInner::Array { base, stride, size } => {
                let base_ty = &module.types[*base];
                let Some(h) = base_ty.name.as_deref().and_then(|n| by_name.get(n)) else { continue };
                if *stride as usize != h.size {
                    errors.push(format!(
                        "array of {} ({size:?}): GPU stride {stride} != host size_of {}",
                        h.name, h.size
                    ));
                } else if matches!(size, ArraySize::Dynamic) {
                    strided.insert(h.name.to_string());
                }
            }
            _ => {}
        }
    }
    (errors, strided)
}

/// Struct names declared in `spirv/include/layout.glsl`.
fn glsl_struct_names() -> BTreeSet<String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/spirv/include/layout.glsl");
    let text = std::fs::read_to_string(path).expect("layout.glsl is readable");
    text.lines()
        .filter_map(|l| l.trim().strip_prefix("struct "))
        .filter_map(|rest| rest.split(|c: char| !c.is_alphanumeric() && c != '_').next())
        .map(str::to_string)
        .collect()
}

#[test]
fn every_kernel_parses_with_naga() {
    let failures: Vec<String> =
        KERNELS.iter().filter_map(|k| parse(k.words()).err().map(|e| format!("{}: {e}", k.name))).collect();
    assert!(failures.is_empty(), "naga could not parse: {failures:#?}");
}

#[test]
fn gpu_structs_match_host_layouts() {
    let host = gpu_layouts();
    let host_names: BTreeSet<String> = host.iter().map(|s| s.name.to_string()).collect();
    assert_eq!(glsl_struct_names(), host_names, "layout.glsl structs and src/gpu/layout.rs twins differ");

    let mut strided = BTreeSet::new();
    for k in KERNELS {
        let module = parse(k.words()).unwrap_or_else(|e| panic!("{}: {e}", k.name));
        let (errors, proven) = compare(&module, &host);
        assert!(errors.is_empty(), "kernel {}: {errors:#?}", k.name);
        strided.extend(proven);
    }
    assert_eq!(strided, host_names, "layout_check.comp must declare a runtime array of every shared struct");
}

/// The check must fail when only one side changes.
#[test]
fn layout_check_detects_one_sided_changes() {
    let module = parse(umbra::kernels::kernel("layout_check").expect("layout_check kernel").words()).unwrap();
    let host = gpu_layouts();
    assert!(compare(&module, &host).0.is_empty());

    let mut moved = host.clone();
    moved[0].members[1].offset += 4;
    assert!(!compare(&module, &moved).0.is_empty(), "a moved member went unnoticed");

    let mut renamed = host.clone();
    renamed[0].members.swap(0, 1);
    assert!(!compare(&module, &renamed).0.is_empty(), "reordered members went unnoticed");

    let mut resized = host.clone();
    resized[0].size += 4;
    assert!(!compare(&module, &resized).0.is_empty(), "a padded host struct went unnoticed");
}
