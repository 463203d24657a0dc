//! Reliability (issue 8): bad input that the other suites do not cover (environment maps with
//! NaN/Inf/negative texels, scenes over the device's buffer limits, absurd output sizes), faults
//! that name the pass, determinism of the hybrid mode, and a long run that loses nothing.

mod common;

use common::Gpu;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::{check_environment_limits, GpuScene, SceneArrays};

use umbra::passes::ao::AoSettings;
use umbra::passes::pathtrace::{PathTarget, PathTracePass};
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{Sampler, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

use umbra::gpu::kernels::{spin_test, test_buffer};
use umbra::gpu::layout::BufferTestParams;
use umbra::gpu::Pipeline;
use umbra::vk::{raw, Buffer, MemoryLocation};
use umbra::Error;

/// Every warning logged in this test binary (tests run in parallel: filter by a unique name).
static WARNINGS: Mutex<Vec<String>> = Mutex::new(Vec::new());

struct Capture;

impl log::Log for Capture {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::Level::Warn
    }
    fn log(&self, record: &log::Record) {
        if self.enabled(record.metadata()) {
            WARNINGS.lock().unwrap().push(record.args().to_string());
        }
    }
    fn flush(&self) {}
}

/// The embedded Cornell box uploaded to `gpu`, and its camera.
fn cornell_box(gpu: &Gpu) -> (GpuScene, umbra::scene::Camera) {
    let scene = Scene::cornell_box();
    (GpuScene::upload(gpu, &scene).unwrap(), scene.camera(None).unwrap())
}

fn warnings_naming(name: &str) -> Vec<String> {
    static LOGGER: Capture = Capture;
    let _ = log::set_logger(&LOGGER).map(|()| log::set_max_level(log::LevelFilter::Warn));
    WARNINGS.lock().unwrap().iter().filter(|w| w.contains(name)).cloned().collect()
}

/// NaN, ±Inf and negative texels become 0 with one warning that counts them; the other texels
/// and the sampling tables are untouched by them (finite, valid alias tables).
#[test]
fn environment_nan_inf_and_negative_texels_are_zeroed_with_one_warning() {
    warnings_naming("");
    let (w, h) = (8, 4);
    let mut texels: Vec<[f32; 3]> = (0..w * h).map(|i| [0.1 * i as f32, 1.0, 2.0]).collect();
    texels[3] = [f32::NAN, 1.0, 1.0];
    texels[7] = [1.0, f32::INFINITY, 1.0];
    texels[12] = [1.0, 1.0, f32::NEG_INFINITY];
    texels[20] = [-0.5, -1e30, 1.0];
    let map = EnvironmentMap::from_texels("bad-sky-texels", w, h, texels.clone()).unwrap();
    let warnings = warnings_naming("bad-sky-texels");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("5 NaN, infinite or negative"), "{warnings:?}");
    for (i, (got, was)) in map.texels.iter().zip(&texels).enumerate() {
        for c in 0..3 {
            let expected = if was[c].is_finite() && was[c] >= 0.0 { was[c] } else { 0.0 };
            assert_eq!(got[c], expected, "texel {i} channel {c}");
        }
    }
    let table = map.distribution();
    assert!(table.pdf_uv.iter().all(|v| v.is_finite()));
    assert!(table.rows.iter().chain(&table.columns).all(|e| (0.0..=1.0).contains(&e.keep)));
    assert!(table.rows.iter().all(|e| (e.alias as usize) < h));
    assert!(table.columns.iter().all(|e| (e.alias as usize) < w));
    // A map with nothing valid left is black, and samples uniformly rather than dividing by 0.
    let all_nan = EnvironmentMap::from_texels("all-nan-sky", 4, 2, vec![[f32::NAN; 3]; 8]).unwrap();
    assert!(all_nan.texels.iter().flatten().all(|&v| v == 0.0));
    assert!(all_nan.distribution().pdf_uv.iter().all(|&p| p == 1.0));
    assert_eq!(warnings_naming("all-nan-sky").len(), 1);
    // A clean map warns about nothing.
    EnvironmentMap::from_texels("clean-sky", 2, 1, vec![[1.0; 3]; 2]).unwrap();
    assert!(warnings_naming("clean-sky").is_empty());
}

/// The same from a file: the warning names the file, and a path-traced render lit by the
/// sanitised map stays finite.
#[test]
fn environment_file_with_bad_texels_is_named_and_renders_finite() {
    warnings_naming("");
    let dir = std::env::temp_dir().join(format!("umbra-rel-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("poisoned-sky.exr");
    let (w, h) = (16, 8);
    let mut rgb: Vec<f32> = (0..w * h * 3).map(|i| 0.5 + (i % 7) as f32 * 0.1).collect();
    for (k, bad) in [f32::NAN, f32::INFINITY, -3.0, f32::NEG_INFINITY].into_iter().enumerate() {
        rgb[k * 37] = bad;
    }
    let layer = umbra::output::Layer { name: "", channels: &["R", "G", "B"], data: &rgb };
    umbra::output::write_exr(&path, w, h, &[layer]).unwrap();
    let map = EnvironmentMap::load(&path).unwrap();
    let warnings = warnings_naming("poisoned-sky.exr");
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("4 NaN, infinite or negative"), "{warnings:?}");

    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let settings = PathSettings { size: (8, 8), spp: 4, env: [1.0; 3], ..Default::default() };
    let image = path_trace(&gpu, &device_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0);
    assert!(image.mean.iter().flatten().all(|v| v.is_finite()));
    std::fs::remove_dir_all(&dir).ok();
}

/// The texel size of the scene buffers bound as storage texel buffers (the BVH's RGBA32UI, the
/// scene texels' R32UI); `None` for storage buffers.
fn texel_bytes(buffer: &str) -> Option<u64> {
    match buffer {
        b if b.starts_with("bvh ") => Some(16),
        "scene triangles"
        | "scene vertices"
        | "scene materials"
        | "scene lights"
        | "scene punctual lights" => Some(16),
        "scene texels" | "environment alias" => Some(8),
        "environment texels" => Some(16),
        _ => None,
    }
}

fn assert_too_large(result: umbra::Result<impl Sized>, name: &str, buffer: &str, limit: u64) {
    match result {
        Err(e @ Error::Scene { .. }) => {
            let message = e.to_string();
            eprintln!("{message}");
            assert!(message.starts_with(name), "{message}");
            assert!(message.contains(buffer), "{message}");
            assert!(message.contains(&format!("at most {limit} bytes")), "{message}");
            let what = if texel_bytes(buffer).is_some() {
                "maxTexelBufferElements"
            } else {
                "maxStorageBufferRange"
            };
            assert!(message.contains(what), "{message}");
        }
        Err(e) => panic!("expected a scene error naming {name}, got: {e}"),
        Ok(_) => panic!("{name} fits under {limit} bytes"),
    }
}

/// The size check against a lowered `maxStorageBufferRange` and `maxTexelBufferElements` (the
/// hook: a [`DeviceInfo`] of our own), on the Cornell box with a small texture so that both kinds
/// of texel buffer (the BVH's RGBA32UI, the scene texels' R32UI) and the storage buffers are
/// non-empty: each fits at its exact size and is refused one unit (a byte, or a texel) below.
#[test]
fn scene_buffer_sizes_are_checked_against_the_device_limit() {
    let gpu = Gpu::new();
    let mut scene = Scene::cornell_box();
    scene.textures.push(Texture {
        name: "small".into(),
        width: 5,
        height: 3,
        rgba8: vec![200; 5 * 3 * 4],
        srgb: true,
        sampler: Sampler::default(),
    });
    scene.materials[0].base_color_texture =
        Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 });
    let arrays = SceneArrays::new(&scene).unwrap();
    let sizes = arrays.buffer_sizes();
    let triangles = sizes.iter().find(|s| s.0 == "scene triangles").unwrap().1;
    assert_eq!(triangles, std::mem::size_of_val(arrays.triangles.as_slice()) as u64);
    let vertices = sizes.iter().find(|s| s.0 == "scene vertices").unwrap().1;
    assert_eq!(vertices, std::mem::size_of_val(arrays.vertices.as_slice()) as u64);
    let texels = sizes.iter().find(|s| s.0 == "scene texels").unwrap().1;
    assert_eq!(texels, std::mem::size_of_val(arrays.texels.as_slice()) as u64);
    assert!(texels >= 8 * (256 + 5 * 3), "the sRGB table, then two words per texel (and mips)");
    // A device that binds `bytes` in `buffer`'s kind of buffer: a storage buffer range in bytes,
    // or as many texels of `buffer`'s size (the other texel format then binds 2× more or less:
    // one limit counts texels of either).
    let device = |buffer: &str, bytes: u64| {
        let mut info = gpu.info().clone();
        info.max_storage_buffer_range = bytes;
        info.max_texel_buffer_elements = (bytes / texel_bytes(buffer).unwrap_or(4)) as u32;
        info
    };
    // (The Cornell box has no punctual light: that buffer is empty, nothing to check.)
    for (buffer, size) in sizes.into_iter().filter(|s| s.1 > 0) {
        let unit = texel_bytes(buffer).unwrap_or(1);
        assert_eq!(size % unit, 0, "{buffer} is not whole texels");
        // Fits at its exact size (whatever fails then is another, larger buffer)...
        if let Err(e) = arrays.check_limits(&scene.name, &device(buffer, size)) {
            let message = e.to_string();
            assert!(!message.contains(&format!("its {buffer} need")), "{buffer} at its own size: {message}");
        }
        // ...and one unit below, some buffer at least as large is refused: this one, if no other.
        let below = size - unit;
        let message = arrays.check_limits(&scene.name, &device(buffer, below)).unwrap_err().to_string();
        assert!(sizes.iter().any(|(b, s)| message.contains(b) && *s >= size), "{buffer}: {message}");
    }
    // The largest storage buffer and both kinds of texel buffer, exactly: alone over the limit.
    for kind in ["scene texels", "bvh nodes"] {
        let size = sizes.iter().find(|s| s.0 == kind).unwrap().1;
        let mut info = gpu.info().clone();
        info.max_texel_buffer_elements = (size / texel_bytes(kind).unwrap()) as u32 - 1;
        let limit = info.max_texel_buffer_elements as u64 * texel_bytes(kind).unwrap();
        assert_too_large(arrays.check_limits(&scene.name, &info), &scene.name, kind, limit);
        info.max_texel_buffer_elements += 1;
        let message =
            arrays.check_limits(&scene.name, &info).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(!message.contains(&format!("its {kind} need")), "{kind} fits exactly: {message}");
    }
    // Every scene buffer is a texel buffer now; the storage-buffer limit (the environment map's)
    // is checked through a real upload in the next test. A storage buffer here would be checked.
    assert!(sizes.iter().all(|s| texel_bytes(s.0).is_some()), "a scene storage buffer: check its limit");
    let mut info = gpu.info().clone();
    info.max_storage_buffer_range = 1;
    arrays.check_limits(&scene.name, &info).expect("no scene buffer is a storage buffer");
}

/// An environment map's two texel buffers against a lowered `maxTexelBufferElements`: each fits
/// at its exact size and is one clear error naming the map and the buffer a texel below, before
/// anything is allocated. (The real limit, 2^27 texels on lavapipe, is beyond the largest map
/// umbra loads, `environment::MAX_TEXELS`.)
#[test]
fn environment_maps_over_the_device_buffer_limit_are_one_clear_error() {
    let gpu = Gpu::new();
    let (w, h) = (64, 32);
    let map = EnvironmentMap::from_texels("huge-sky.exr", w, h, vec![[0.5; 3]; w * h]).unwrap();
    // Texels: w·h of them; the alias tables: a row's entry and a texel's each.
    for (kind, texels) in [("environment texels", w * h), ("environment alias", w * h + h)] {
        let mut info = gpu.info().clone();
        info.max_texel_buffer_elements = texels as u32 - 1;
        let limit = info.max_texel_buffer_elements as u64 * texel_bytes(kind).unwrap();
        assert_too_large(check_environment_limits(&map, &info), "huge-sky.exr", kind, limit);
        info.max_texel_buffer_elements += 1;
        let message = check_environment_limits(&map, &info).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(!message.contains(&format!("its {kind} need")), "{kind} fits exactly: {message}");
    }
    let mut device_scene = GpuScene::upload(&gpu, &Scene::cornell_box()).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
}

/// The pass marker: a submission that fails (here by fault injection, as a lost device or an
/// exhausted heap would) names the last pass recorded into it; nothing reached the queue, so the
/// context goes on working and is destroyed without a validation message. A real allocation
/// larger than any heap is one clear error naming the buffer.
#[test]
fn failed_submissions_name_the_last_pass() {
    let gpu = Gpu::new();
    let (device_scene, camera) = cornell_box(&gpu);
    let settings = PathSettings { size: (8, 8), spp: 1, ..Default::default() };
    let pass = PathTracePass::for_scene(&gpu, &device_scene, Default::default()).unwrap();
    let resolve = umbra::passes::pathtrace::ResolvePass::new(&gpu).unwrap();
    let target = PathTarget::new(&gpu, settings.size).unwrap();
    let output =
        umbra::vk::Image::storage_2d(&gpu, "resolved", 8, 8, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    let params = PathTracePass::params(&device_scene, &camera, &settings);
    let cases = [
        (raw::Result::ERROR_DEVICE_LOST, false, "pathtrace"),
        (raw::Result::ERROR_OUT_OF_DEVICE_MEMORY, true, "resolve"),
    ];
    for (fault, then_resolve, expected) in cases {
        gpu.inject_submit_fault(fault);
        let mut recorded = raw::CommandBuffer::null();
        let err = gpu
            .record(|rec| {
                let cmd = rec.cmd();
                recorded = cmd;
                output.init_general(&gpu, cmd);
                pass.record(rec, &device_scene, &target, &params)?;
                if then_resolve {
                    resolve.record(rec, &target, output.view)?;
                }
                Ok(())
            })
            .unwrap_err();
        let message = err.to_string();
        eprintln!("{message}");
        match &err {
            Error::Vulkan { call: "vkQueueSubmit2", result, pass: Some(pass) } => {
                // Nothing reached the GPU, so its breadcrumb is empty: the last pass recorded.
                assert_eq!((*result, pass.split(',').next()), (fault, Some(expected)), "{message}");
                assert!(pass.ends_with("the last pass recorded; the submission never reached the GPU"));
            }
            other => panic!("expected a Vulkan error naming {expected}: {other}"),
        }
        assert!(message.contains(&format!("{fault}")) && message.contains(expected), "{message}");
        assert_eq!(gpu.last_pass(recorded), None, "the marker outlives its submission");
    }
    // A submission that never dispatched names no pass.
    gpu.inject_submit_fault(raw::Result::ERROR_DEVICE_LOST);
    match gpu.submit(|_| Ok(())) {
        Err(Error::Vulkan { pass: None, .. }) => {}
        other => panic!("expected a Vulkan error without a pass, got {:?}", other.err()),
    }
    // The context still renders.
    let image = path_trace(&gpu, &device_scene, &camera, &settings, |_, _| {}).unwrap();
    assert!(image.mean.iter().any(|p| p[0] > 0.0));
    // Out of memory for real: more than any heap holds.
    let heap_total = 1u64 << 50;
    let usage = raw::BufferUsageFlags::TRANSFER_DST;
    match Buffer::new(&gpu, "absurd readback", heap_total, usage, MemoryLocation::GpuToCpu) {
        Err(e @ Error::Allocation { .. }) => {
            eprintln!("{e}");
            assert!(e.to_string().contains("absurd readback"), "{e}");
        }
        Err(e) => panic!("expected an allocation error, got {e}"),
        Ok(_) => panic!("allocated 2^50 bytes"),
    }
}

/// What [`hung_submission`] saw: the submission's error and what waiting for the still-held
/// submission said.
struct Hung {
    err: Error,
    still: umbra::Result<()>,
}

/// A kernel that hangs until the host releases it, recorded between two quick ones into one
/// submission with a 1.5 s timeout (and `wait_fault` injected into the wait, if given). Whatever
/// happens, the host releases the GPU afterwards and checks that it finished the work: the
/// dispatch after the spin ran, a later submission finishes normally, and the submission's
/// fence, pool and breadcrumb, kept while it ran, are freed without a validation message.
fn hung_submission(wait_fault: Option<raw::Result>) -> Hung {
    let gpu = Gpu::new();
    let quick = Pipeline::<test_buffer::Kernel>::plain(&gpu).unwrap();
    let spin = Pipeline::<spin_test::Kernel>::plain(&gpu).unwrap();
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let input: Vec<u32> = (0..64).collect();
    let input = Buffer::upload(&gpu, "quick input", &input, usage).unwrap();
    let outputs =
        [0, 1].map(|i| Buffer::upload(&gpu, &format!("quick output {i}"), &[0u32; 64], usage).unwrap());
    let mut flag = Buffer::new(&gpu, "spin flag", 12, usage, MemoryLocation::CpuToGpu).unwrap();
    flag.mapped_mut().unwrap().fill(0);
    // SAFETY: a host-visible, coherent mapping of at least 4 bytes, alive as long as `flag`;
    // the kernel reads it only atomically.
    let release = unsafe { &*(flag.mapped_mut().unwrap().as_mut_ptr() as *const AtomicU32) };

    let timeout = Duration::from_millis(1500);
    gpu.set_submit_timeout(timeout);
    assert_eq!(gpu.submit_timeout(), timeout);
    if let Some(fault) = wait_fault {
        gpu.inject_wait_fault(fault);
    }
    let started = Instant::now();
    let (sender, receiver) = std::sync::mpsc::channel();
    let (result, waited, still) = std::thread::scope(|s| {
        s.spawn(|| {
            let result = gpu.record(|rec| {
                for (k, output) in outputs.iter().enumerate() {
                    let resources = test_buffer::Resources { values_in: &input, values_out: output };
                    let params = BufferTestParams { count: 64, add: k as u32 };
                    quick.record(rec, &resources, &params, [64, 1, 1])?;
                    if k == 0 {
                        // 1024 workgroups of 64: on lavapipe (where an invocation's loops end
                        // after 65535 iterations) ~80 ms each on one core, 40 s on two, if
                        // never released; released, they all end within milliseconds.
                        let resources = spin_test::Resources { spin: &flag };
                        spin.record(rec, &resources, &(), [1024 * 64, 1, 1])?;
                    }
                }
                Ok(())
            });
            let _ = sender.send(result);
        });
        // Whatever happens, the host releases the GPU: a missing timeout fails, never hangs.
        let result = receiver.recv_timeout(Duration::from_secs(60));
        let waited = started.elapsed();
        // Still held: waiting for the abandoned submission times out too, naming the same pass.
        gpu.set_submit_timeout(Duration::from_millis(200));
        let still = gpu.wait_idle();
        release.store(1, Ordering::SeqCst);
        (result, waited, still)
    });
    let err = match result {
        Ok(Err(e)) => e,
        Ok(Ok(())) => panic!("the submission finished although the kernel was never released"),
        Err(_) => panic!("submit did not return within 60 s despite its {timeout:?} timeout"),
    };
    eprintln!("{err} (after {waited:?})");
    assert!(waited >= timeout && waited < Duration::from_secs(30), "{waited:?}");

    // Released, the GPU finishes; the abandoned submission is reclaimed.
    gpu.set_submit_timeout(Duration::from_secs(600));
    let released_at = Instant::now();
    gpu.wait_idle().unwrap();
    eprintln!("the GPU finished {:?} after its release", released_at.elapsed());
    let [_, spun, released] = flag.read::<u32>(&gpu).unwrap()[..] else { panic!("3 words") };
    assert_eq!(released, 1, "the kernel ran until the host released it ({spun} iterations)");
    let expected: Vec<u32> = (0..64).map(|v| 3 * v + 1).collect();
    assert_eq!(outputs[1].read::<u32>(&gpu).unwrap(), expected, "the dispatch after the spin ran");
    // A later submission finishes normally.
    let out: Vec<u32> = outputs[0].read(&gpu).unwrap();
    assert_eq!(out, (0..64).map(|v| 3 * v).collect::<Vec<_>>());
    Hung { err, still }
}

/// The GPU-written breadcrumb: the hung submission makes `submit` time out naming the hanging
/// kernel as the one running on the GPU (dispatch 2 of 3, the first finished), not the last one
/// recorded; waiting for the held submission times out too, naming the same pass.
#[test]
fn a_hung_submission_names_the_pass_the_gpu_was_running() {
    let Hung { err, still, .. } = hung_submission(None);
    let message = err.to_string();
    match &err {
        Error::Timeout { seconds, pass: Some(pass) } => {
            assert_eq!(*seconds, 1.5);
            assert_eq!(pass, "spin_test, dispatch 2 of 3: running or next to run on the GPU; 1 finished");
        }
        other => panic!("expected a timeout naming spin_test: {other}"),
    }
    assert!(message.starts_with("GPU work did not finish within 1.5 s (pass spin_test"), "{message}");
    match still {
        Err(Error::Timeout { pass: Some(pass), .. }) => {
            assert!(pass.starts_with("spin_test, dispatch 2 of 3"))
        }
        other => panic!("expected waiting for the held submission to time out: {other:?}"),
    }
}

/// A device lost while the GPU runs a submission (injected into the wait, after the work was
/// really submitted and the GPU got as far as the hanging kernel): the error names the call, the
/// result and the pass the GPU had reached, from the breadcrumb it writes per dispatch
/// (spin_test, dispatch 2 of 3), not the last pass recorded (test_buffer, dispatch 3).
#[test]
fn a_lost_device_names_the_pass_the_gpu_reached() {
    let Hung { err, .. } = hung_submission(Some(raw::Result::ERROR_DEVICE_LOST));
    match &err {
        Error::Vulkan {
            call: "vkWaitForFences",
            result: raw::Result::ERROR_DEVICE_LOST,
            pass: Some(pass),
        } => {
            assert_eq!(pass, "spin_test, dispatch 2 of 3: running or next to run on the GPU; 1 finished");
        }
        other => panic!("expected a lost device naming spin_test: {other}"),
    }
    let message = err.to_string();
    assert!(message.contains("vkWaitForFences") && message.contains("device has been lost"), "{message}");
}

/// Hybrid renders are deterministic: the same seeds give the same bytes (colour and display),
/// another shadow-ray or SSAO seed gives other bytes.
#[test]
fn hybrid_same_seed_same_bytes_different_seed_different() {
    let gpu = Gpu::new();
    let (device_scene, camera) = cornell_box(&gpu);
    let mut settings =
        HybridSettings { size: (32, 32), ao: Some(AoSettings::default()), ..Default::default() };
    settings.lighting.env = [0.5; 3];
    let render = |s: &HybridSettings| {
        let image = hybrid(&gpu, &device_scene, &camera, s).unwrap();
        let mut bytes = bytemuck::cast_slice::<[f32; 4], u8>(&image.color).to_vec();
        bytes.extend(image.display.iter().flatten());
        bytes
    };
    let a = render(&settings);
    assert!(a == render(&settings), "same seeds, different output");
    let mut shadow_seed = settings.clone();
    shadow_seed.lighting.seed = 7;
    assert!(a != render(&shadow_seed), "another shadow-ray seed, identical output");
    let mut ao_seed = settings.clone();
    ao_seed.ao.as_mut().unwrap().seed = 7;
    assert!(a != render(&ao_seed), "another SSAO seed, identical output");
}

/// A long run loses nothing: 10,000 samples per pixel of a 4×4 Cornell box through
/// [`path_trace`] (its batching, its float32 running mean) equal the float64 mean of the same
/// 10,000 per-sample radiances to float rounding. The per-sample radiance of sample s is read
/// by running the kernel for sample s alone on a zeroed accumulator (a render of that one
/// sample), which then holds the radiance exactly, with count 1. A dispatch sums its run of k
/// samples (S, each addition rounding once) and merges it into the running mean,
/// m_n = m + (S − k·m)/n; the bound is the worst case of those roundings,
/// u·Σ ((Σ|partial sums| + |k·m| + |S − k·m|)/n + |S − k·m|/n + |m_n|) with u = 2⁻²⁴; it is
/// deterministic (no significance level). Also checked: the same runs merged in float32 on the CPU agree much more tightly (a
/// dropped or repeated sample is caught).
#[test]
fn ten_thousand_samples_equal_a_float64_accumulation() {
    const N: u32 = 10_000;
    const PIXELS: usize = 16;
    let gpu = Gpu::new();
    let (device_scene, camera) = cornell_box(&gpu);
    let settings = PathSettings { size: (4, 4), spp: N, ..Default::default() };
    let start = std::time::Instant::now();
    let image = path_trace(&gpu, &device_scene, &camera, &settings, |_, _| {}).unwrap();
    let long_run = start.elapsed();
    assert_eq!(image.spp, N);
    assert_eq!(image.nonfinite_samples, 0);

    // Every sample alone: zero the accumulator, trace sample s, copy the result out.
    let start = std::time::Instant::now();
    let pass = PathTracePass::for_scene(&gpu, &device_scene, settings.options()).unwrap();
    let target = PathTarget::new(&gpu, settings.size).unwrap();
    let mut params = PathTracePass::params(&device_scene, &camera, &settings);
    let row = (PIXELS * 16) as u64;
    let samples = Buffer::new(
        &gpu,
        "per-sample radiance",
        row * N as u64,
        raw::BufferUsageFlags::STORAGE_BUFFER
            | raw::BufferUsageFlags::TRANSFER_DST
            | raw::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::GpuOnly,
    )
    .unwrap();
    for first in (0..N).step_by(1000) {
        gpu.record(|rec| {
            for s in first..first + 1000 {
                rec.fill(&target.accum, 0);
                params.sample_index = s;
                pass.record(rec, &device_scene, &target, &params)?;
                let region = [raw::BufferCopy::default().dst_offset(s as u64 * row).size(row)];
                rec.copy(&target.accum, &samples, &region);
            }
            Ok(())
        })
        .unwrap();
    }
    let per_sample: Vec<[f32; 4]> = samples.read(&gpu).unwrap();
    eprintln!("10,000 spp: {long_run:.2?}; the samples one by one: {:.2?}", start.elapsed());

    let u = f64::powi(2.0, -24);
    // path_trace submits 64 samples a time at this size, each submission split into dispatches
    // of SAMPLES_PER_DISPATCH: runs of that many samples from sample 0.
    let run = PathTracePass::SAMPLES_PER_DISPATCH as usize;
    assert_eq!(64 % run, 0, "dispatch runs no longer align with path_trace's submissions");
    let (mut worst_ratio, mut worst_tight) = (0.0f64, 0.0f64);
    for p in 0..PIXELS {
        for c in 0..3 {
            let r: Vec<f64> = (0..N as usize)
                .map(|s| {
                    let v = per_sample[s * PIXELS + p];
                    assert_eq!(v[3], 1.0, "sample {s} pixel {p}: count");
                    v[c] as f64
                })
                .collect();
            let exact = r.iter().sum::<f64>() / N as f64;
            // The worst-case bound of the float32 running mean's roundings, run by run.
            let (mut m, mut bound) = (0.0f64, 0.0f64);
            let mut m32 = 0.0f32;
            for (d, samples) in r.chunks(run).enumerate() {
                let k = samples.len() as f64;
                let n = (d * run) as f64 + k;
                let (mut sum, mut sum_bound, mut sum32) = (0.0f64, 0.0f64, 0.0f32);
                for &rk in samples {
                    sum += rk;
                    sum_bound += u * sum.abs();
                    sum32 += rk as f32;
                }
                let step = (sum - k * m) / n;
                bound += (sum_bound + u * (k * m).abs() + u * (sum - k * m).abs()) / n
                    + u * step.abs()
                    + u * (m + step).abs();
                m += step;
                m32 += (sum32 - k as f32 * m32) / n as f32;
            }
            bound += f64::MIN_POSITIVE;
            let got = image.mean[p][c] as f64;
            let error = (got - exact).abs();
            assert!(
                error <= bound,
                "pixel {p} channel {c}: {got} vs float64 {exact}: error {error:e} > bound {bound:e}"
            );
            worst_ratio = worst_ratio.max(error / bound);
            // The same runs merged on the CPU: only a fused multiply-add the GPU may use and the
            // rounding drift it starts differ; a sample dropped or repeated is ~|r − m|/N.
            let tight = 64.0 * u * exact.abs().max(1e-30);
            let drift = (got - m32 as f64).abs();
            worst_tight = worst_tight.max(drift / tight);
            assert!(
                drift <= tight,
                "pixel {p} channel {c}: {got} vs CPU float32 running mean {m32}: {drift:e} > {tight:e}"
            );
        }
    }
    eprintln!("worst error / rounding bound: {worst_ratio:.4}; worst CPU-float32 drift / its tolerance: {worst_tight:.4}");
}

/// Absurd output sizes are one clear CLI error each, never a panic: refused by the parser, or
/// (16384×16384, which parses) by the device's buffer limit naming the buffer.
#[test]
fn absurd_output_sizes_are_clear_cli_errors() {
    let umbra = || std::process::Command::new(env!("CARGO_BIN_EXE_umbra"));
    let cases = [
        ("100000x100000", "at most 16384"),
        ("0x10", "positive"),
        ("10x0", "positive"),
        ("-4x4", "-4x4"),
        ("4294967296x1", "4294967296x1"),
        ("x", "'x'"),
        ("64", "WIDTHxHEIGHT"),
    ];
    for (size, phrase) in cases {
        let out = umbra().args(["render", "--spp", "1", &format!("--size={size}")]).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(phrase), "--size {size}: {stderr}");
        assert!(!stderr.contains("panicked"), "--size {size}: {stderr}");
    }
    let out = umbra().args(["render", "--spp", "1", "--size", "16384x16384"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    eprintln!("{stderr}");
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("path accum") && stderr.contains("binds at most"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// Hybrid lighting settings that one kernel invocation could not finish on a CPU device (more
/// shadow rays than `LightingSettings::MAX_SHADOW_RAYS`), none at all, or a negative environment
/// are one clear error, not a silently darker frame.
#[test]
fn hybrid_lighting_settings_are_checked() {
    use umbra::passes::deferred::LightingSettings;
    let gpu = Gpu::new();
    let (device_scene, camera) = cornell_box(&gpu);
    let bad = [
        LightingSettings { shadow_rays: 0, ..Default::default() },
        LightingSettings { shadow_rays: LightingSettings::MAX_SHADOW_RAYS + 1, ..Default::default() },
        LightingSettings { env: [0.5, -1.0, 0.5], ..Default::default() },
    ];
    for lighting in bad {
        let settings = HybridSettings { size: (8, 8), lighting, ..Default::default() };
        match hybrid(&gpu, &device_scene, &camera, &settings) {
            Err(Error::Invalid(message)) => assert!(message.contains("must be"), "{message}"),
            other => panic!("{lighting:?}: expected a clear error, got {:?}", other.map(|_| ())),
        }
    }
    let most = LightingSettings { shadow_rays: LightingSettings::MAX_SHADOW_RAYS, ..Default::default() };
    hybrid(
        &gpu,
        &device_scene,
        &camera,
        &HybridSettings { size: (8, 8), lighting: most, ..Default::default() },
    )
    .unwrap();
}
