//! The Rust/GLSL interface, read back from the compiled SPIR-V with naga: every struct of
//! `src/gpu/interface.rs` against its Rust twin (offsets, sizes, array strides), and every
//! shipping kernel's bindings (set, number, name, kind, element type or format, access), push
//! constants and specialization constants against the kernel's interface. The GLSL side is
//! generated from the same definition; this checks the generator and the kernels (a kernel cannot
//! add a binding of its own by hand) and shows that swapping two same-typed buffers is caught.

use naga::{AddressSpace, ArraySize, ImageClass, ImageDimension, Module, StorageAccess, TypeInner};
use std::collections::{BTreeSet, HashMap};
use umbra::gpu::kernel::{
    Access, BindingDesc, BindingKind, KernelInterface, FIRST_KERNEL_SPEC_ID, SCENE_FEATURES,
};
use umbra::gpu::kernels;
use umbra::gpu::layout::{gpu_layouts, StructLayout};
use umbra::kernels::KERNELS;

fn parse(words: &[u32]) -> Result<Module, String> {
    let words = texel_buffers_as_1d(words);
    let bytes: &[u8] = bytemuck::cast_slice(&words);
    naga::front::spv::parse_u8_slice(bytes, &naga::front::spv::Options::default())
        .map_err(|e| format!("{e:?}"))
}

fn module(name: &str) -> Module {
    let kernel = umbra::kernels::kernel(name).unwrap_or_else(|| panic!("kernel {name} is embedded"));
    parse(kernel.words()).unwrap_or_else(|e| panic!("{name}: {e}"))
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
    for (_, ty) in module.types.iter() {
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

/// A type as GLSL names it in `interface.rs`: a struct's name, `float`, `uvec4`, ...
fn glsl_type(module: &Module, ty: naga::Handle<naga::Type>) -> String {
    let t = &module.types[ty];
    let scalar = |s: &naga::Scalar| match s.kind {
        naga::ScalarKind::Float => ("float", ""),
        naga::ScalarKind::Uint if s.width == 8 => ("uint64_t", "u64"),
        naga::ScalarKind::Uint => ("uint", "u"),
        naga::ScalarKind::Sint => ("int", "i"),
        _ => ("?", "?"),
    };
    match &t.inner {
        TypeInner::Struct { .. } => t.name.clone().unwrap_or_default(),
        // naga types an array that atomics touch as atomic: in GLSL it is the plain scalar.
        TypeInner::Scalar(s) | TypeInner::Atomic(s) => scalar(s).0.to_string(),
        TypeInner::Vector { size, scalar: s } => format!("{}vec{}", scalar(s).1, *size as u8),
        other => format!("{other:?}"),
    }
}

/// The GLSL format qualifier of a naga storage format.
fn glsl_format(format: naga::StorageFormat) -> &'static str {
    use naga::StorageFormat as F;
    match format {
        F::R32Float => "r32f",
        F::R32Uint => "r32ui",
        F::Rg32Uint => "rg32ui",
        F::Rgba8Unorm => "rgba8",
        F::Rgba16Float => "rgba16f",
        F::Rgba32Float => "rgba32f",
        F::Rgba32Uint => "rgba32ui",
        _ => "(other)",
    }
}

/// What a kernel's access qualifier allows.
fn allowed(access: Access) -> StorageAccess {
    match access {
        Access::ReadOnly => StorageAccess::LOAD,
        Access::WriteOnly => StorageAccess::STORE,
        Access::ReadWrite | Access::Coherent => StorageAccess::LOAD | StorageAccess::STORE,
    }
}

/// Differences between a kernel's compiled bindings, push constants and specialization constants
/// and `bindings` (its interface's numbered bindings, or a deliberately altered copy).
fn check_interface(
    module: &Module,
    interface: &KernelInterface,
    bindings: &[(u32, BindingDesc)],
) -> Vec<String> {
    let name = interface.name;
    let mut errors = Vec::new();
    let expected: HashMap<u32, &BindingDesc> = bindings.iter().map(|(n, b)| (*n, b)).collect();
    let mut seen = BTreeSet::new();
    let mut push_blocks = 0;
    for (_, var) in module.global_variables.iter() {
        if var.space == AddressSpace::Immediate {
            push_blocks += 1;
            let found = match &module.types[var.ty].inner {
                TypeInner::Struct { members, .. } if members.len() == 1 => {
                    (members[0].name.clone().unwrap_or_default(), glsl_type(module, members[0].ty))
                }
                other => (String::new(), format!("{other:?}")),
            };
            if found != ("params".to_string(), interface.push_type.to_string()) {
                errors.push(format!(
                    "{name}: push constants {found:?}, interface says params: {}",
                    interface.push_type
                ));
            }
            continue;
        }
        let Some(rb) = &var.binding else { continue };
        if rb.group != 0 {
            errors.push(format!("{name}: a binding in set {} (umbra uses set 0 only)", rb.group));
            continue;
        }
        seen.insert(rb.binding);
        let Some(b) = expected.get(&rb.binding) else {
            errors.push(format!("{name}: binding {} ({:?}) is not in the interface", rb.binding, var.name));
            continue;
        };
        let ty = &module.types[var.ty];
        let (found_name, kind, arg, access) = match (&var.space, &ty.inner) {
            (AddressSpace::Storage { access }, TypeInner::Struct { members, .. }) if members.len() == 1 => {
                let m = &members[0];
                let (kind, arg) = match module.types[m.ty].inner {
                    TypeInner::Array { base, size: ArraySize::Dynamic, .. } => {
                        (BindingKind::Buffer, glsl_type(module, base))
                    }
                    _ => (BindingKind::BufferStruct, glsl_type(module, m.ty)),
                };
                (m.name.clone().unwrap_or_default(), kind, arg, *access)
            }
            (
                AddressSpace::Handle,
                TypeInner::Image { dim, class: ImageClass::Storage { format, access }, .. },
            ) => {
                let kind = if *dim == ImageDimension::D1 { BindingKind::Texels } else { BindingKind::Image };
                (var.name.clone().unwrap_or_default(), kind, glsl_format(*format).to_string(), *access)
            }
            (space, inner) => {
                errors.push(format!("{name}: binding {}: unexpected {space:?} {inner:?}", rb.binding));
                continue;
            }
        };
        let got = (found_name.as_str(), kind, arg.as_str());
        if got != (b.name, b.kind, b.arg) {
            errors.push(format!(
                "{name}: binding {} is {got:?} in the kernel, {:?} in the interface",
                rb.binding,
                (b.name, b.kind, b.arg)
            ));
        }
        if !allowed(b.access).contains(access) {
            errors.push(format!(
                "{name}: binding {} ({}) is {access:?}, interface says {:?}",
                rb.binding, b.name, b.access
            ));
        }
    }
    // A binding the kernel never reads may be left out of the SPIR-V; the kernel's own ones are
    // all used.
    let first_own = interface.first_own_binding();
    for (n, b) in bindings {
        if *n >= first_own && !seen.contains(n) {
            errors.push(format!("{name}: binding {n} ({}) is missing from the kernel", b.name));
        }
    }
    if push_blocks != (interface.push_size > 0) as usize {
        errors.push(format!("{name}: {push_blocks} push-constant blocks for {} bytes", interface.push_size));
    }
    // Specialization constants by name and id.
    let mut spec: Vec<(u16, String)> = SCENE_FEATURES
        .iter()
        .enumerate()
        .filter(|(_, f)| interface.features().contains(f))
        .map(|(i, f)| (i as u16, format!("HAS_{}", f.to_uppercase())))
        .collect();
    // The register stack's entries, in kernels that walk with them.
    if interface.features().contains(&"shallow_bvh") {
        spec.push((umbra::gpu::kernel::BVH_STACK_SPEC_ID as u16, "BVH_STACK".to_string()));
    }
    for (i, s) in interface.spec.iter().enumerate() {
        spec.push(((FIRST_KERNEL_SPEC_ID as usize + i) as u16, s.name.to_uppercase()));
    }
    let found: BTreeSet<(u16, String)> = module
        .overrides
        .iter()
        .filter_map(|(_, o)| Some((o.id?, o.name.clone().unwrap_or_default())))
        .collect();
    // An unused constant may be left out; every one present must be the interface's.
    for f in &found {
        if !spec.contains(f) {
            errors.push(format!("{name}: specialization constant {f:?} is not in the interface {spec:?}"));
        }
    }
    // The workgroup size: declared once, in the interface (the kernel places build.rs's
    // `KERNEL_LOCAL_SIZE`, without which it would be 1 × 1 × 1).
    for entry in &module.entry_points {
        if entry.workgroup_size != interface.local {
            errors.push(format!(
                "{name}: workgroup size {:?}, the interface declares {:?}",
                entry.workgroup_size, interface.local
            ));
        }
    }
    errors
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
    let mut strided = BTreeSet::new();
    for k in KERNELS {
        let module = parse(k.words()).unwrap_or_else(|e| panic!("{}: {e}", k.name));
        let (errors, proven) = compare(&module, &host);
        assert!(errors.is_empty(), "kernel {}: {errors:#?}", k.name);
        strided.extend(proven);
    }
    assert_eq!(
        strided, host_names,
        "the generated layout_check kernel declares a runtime array of every struct"
    );
}

/// Every kernel of `spirv/` has an interface, and every interface's kernel matches it.
#[test]
fn every_kernel_matches_its_interface() {
    let interfaces: BTreeSet<&str> = kernels::all().iter().map(|k| k.name).collect();
    let shipped: BTreeSet<&str> = KERNELS.iter().map(|k| k.name).filter(|n| *n != "layout_check").collect();
    assert_eq!(interfaces, shipped, "kernels and interfaces differ");
    let mut errors = Vec::new();
    for interface in kernels::all() {
        let module = module(interface.name);
        errors.extend(check_interface(&module, interface, &interface.numbered_bindings()));
    }
    assert!(errors.is_empty(), "{errors:#?}");
}

/// The check must fail when only one side changes.
#[test]
fn layout_check_detects_one_sided_changes() {
    let module = module("layout_check");
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

/// Two buffers of one type swapped on one side (the path tracer's `accum` and `moment`, the
/// scene's `light_texels` and `punctual_texels`), a texel buffer's format changed, a kernel's own
/// binding moved: each is reported.
#[test]
fn interface_check_detects_swapped_bindings() {
    let swapped = |interface: &KernelInterface, a: &str, b: &str| {
        let mut bindings = interface.numbered_bindings();
        let i = bindings.iter().position(|(_, d)| d.name == a).unwrap();
        let j = bindings.iter().position(|(_, d)| d.name == b).unwrap();
        let (ni, nj) = (bindings[i].0, bindings[j].0);
        bindings[i].0 = nj;
        bindings[j].0 = ni;
        bindings
    };
    let pathtrace = module("pathtrace");
    let interface = &kernels::pathtrace::INTERFACE;
    assert!(check_interface(&pathtrace, interface, &interface.numbered_bindings()).is_empty());
    for (a, b) in
        [("accum", "moment"), ("light_texels", "punctual_texels"), ("aov_albedo", "aov_normal_depth")]
    {
        let errors = check_interface(&pathtrace, interface, &swapped(interface, a, b));
        assert!(
            errors.iter().any(|e| e.contains(a)) && errors.iter().any(|e| e.contains(b)),
            "{a}/{b}: {errors:?}"
        );
    }

    let deferred = module("deferred");
    let interface = &kernels::deferred::INTERFACE;
    let errors = check_interface(&deferred, interface, &swapped(interface, "gb_normal", "gb_base"));
    assert!(!errors.is_empty(), "two rgba16f images swapped went unnoticed");

    let mut bindings = interface.numbered_bindings();
    bindings.iter_mut().find(|(_, b)| b.name == "scene_texels").unwrap().1.arg = "rgba32ui";
    assert!(
        !check_interface(&deferred, interface, &bindings).is_empty(),
        "a texel format change went unnoticed"
    );

    let mut bindings = interface.numbered_bindings();
    bindings.last_mut().unwrap().0 += 1;
    assert!(!check_interface(&deferred, interface, &bindings).is_empty(), "a moved binding went unnoticed");

    // The path tracer's two specialization constants in the other order (ids swapped).
    let pt = &kernels::pathtrace::INTERFACE;
    let reordered = KernelInterface { spec: vec![pt.spec[1], pt.spec[0]].leak(), ..*pt };
    let errors = check_interface(&pathtrace, &reordered, &pt.numbered_bindings());
    assert!(errors.iter().any(|e| e.contains("BECKMANN")), "{errors:?}");
    // A push-constant struct of another name.
    let other_push = KernelInterface { push_type: "DeferredParams", ..*pt };
    assert!(!check_interface(&pathtrace, &other_push, &pt.numbered_bindings()).is_empty());
    // Another workgroup size than the compiled kernel's.
    let other_local = KernelInterface { local: [16, 4, 1], ..*pt };
    let errors = check_interface(&pathtrace, &other_local, &pt.numbered_bindings());
    assert!(errors.iter().any(|e| e.contains("workgroup size")), "{errors:?}");
}

/// The walls real GPUs enforce (build.rs and compile-time assertions refuse a kernel past them;
/// this prints each wall's closest kernel, so a review sees the room left): bindings against
/// `maxPushDescriptors`, push constants against 128 bytes, own specialization constants against
/// their id range.
#[test]
fn kernels_stay_inside_the_walls_gpus_enforce() {
    use umbra::gpu::layout::{KERNEL_SPEC_IDS, MAX_KERNEL_BINDINGS, MAX_PUSH_CONSTANT_BYTES};
    let all = kernels::all();
    let most =
        |f: &dyn Fn(&KernelInterface) -> u32| all.iter().map(|k| (f(k), k.name)).max().expect("kernels");
    let bindings = most(&|k| k.numbered_bindings().len() as u32);
    let push = most(&|k| k.push_size);
    let spec = most(&|k| k.spec.len() as u32);
    eprintln!("bindings: {bindings:?} of {MAX_KERNEL_BINDINGS}; push constants: {push:?} of {MAX_PUSH_CONSTANT_BYTES} bytes; own specialization constants: {spec:?} of {KERNEL_SPEC_IDS}");
    assert!(
        bindings.0 <= MAX_KERNEL_BINDINGS && push.0 <= MAX_PUSH_CONSTANT_BYTES && spec.0 <= KERNEL_SPEC_IDS
    );
}

/// A feature set's name in a kernel's list stands for its features, each feature once and none
/// other: the deferred kernel, listed with `all_lights`, is specialised on the environment map;
/// ReSTIR's, listed with `lights, punctual`, is not.
#[test]
fn feature_sets_expand_to_their_features_once() {
    use umbra::gpu::kernel::{expand_features, FEATURE_SETS};
    use umbra::gpu::kernels::{deferred, restir_initial};
    let surface = FEATURE_SETS.iter().find(|(name, _)| *name == "surface").expect("the surface set").1;
    let expanded = expand_features(&["alpha", "surface", "implicit"]);
    assert_eq!(expanded.len(), surface.len() + 1, "{expanded:?}");
    assert_eq!((expanded[0], expanded[expanded.len() - 1]), ("alpha", "implicit"));
    for feature in surface {
        assert_eq!(expanded.iter().filter(|e| *e == feature).count(), 1, "{feature}");
    }
    assert!(deferred::INTERFACE.features().contains(&"env_map"));
    assert!(!restir_initial::INTERFACE.features().contains(&"env_map"));
    assert!(restir_initial::INTERFACE.features().contains(&"punctual"));
}
