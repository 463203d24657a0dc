//! The foundation on lavapipe: kernels, buffers, images, timestamps, validation, errors, output.

mod common;

use common::Gpu;
use umbra::gpu::kernels::{fold_test, test_buffer, test_pattern};
use umbra::gpu::layout::{BufferTestParams, PatternParams};
use umbra::gpu::Pipeline;
use umbra::vk::{raw, Buffer, ComputePipeline, Descriptor, GpuTimer, Image, PipelineDesc};

fn pattern_pipeline(gpu: &Gpu, multiplier: u32) -> Pipeline<test_pattern::Kernel> {
    Pipeline::new(gpu, &test_pattern::Spec { pattern_multiplier: multiplier }, None)
        .expect("test_pattern pipeline")
}

/// Records test_pattern.comp over `params.size` into `image` (8×8 workgroups).
fn record_pattern(
    pipeline: &Pipeline<test_pattern::Kernel>,
    rec: &mut umbra::vk::Recorder<'_>,
    image: &Image,
    params: &PatternParams,
) -> umbra::Result<()> {
    let [w, h] = params.size;
    pipeline.record(rec, &test_pattern::Resources { out_image: &image.view }, params, [w, h, 1])
}

/// The CPU twin of `pattern_hash` in test_pattern.comp.
fn pattern_hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

#[test]
fn pattern_1080p_reads_back_exactly() {
    let gpu = Gpu::new();
    let (w, h) = (1920u32, 1080u32);
    let params = PatternParams { size: [w, h], seed: 12345, frame: 7 };
    let multiplier = 3;
    let image = Image::storage_2d(&gpu, "pattern", w, h, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    let pipeline = pattern_pipeline(&gpu, multiplier);
    gpu.record(|rec| {
        image.init_general(&gpu, rec.cmd());
        record_pattern(&pipeline, rec, &image, &params)
    })
    .unwrap();
    let texels: Vec<f32> = image.read(&gpu).unwrap();
    assert_eq!(texels.len(), (4 * w * h) as usize);
    let mut mismatches = 0usize;
    for y in 0..h {
        for x in 0..w {
            let hash = pattern_hash(x.wrapping_add(y * w).wrapping_add(params.seed)) & 0xffff;
            let expected =
                [x as f32, y as f32, ((x * y + params.frame) % 65521) as f32, (hash * multiplier) as f32];
            let i = 4 * (y * w + x) as usize;
            if texels[i..i + 4] != expected {
                if mismatches < 5 {
                    eprintln!("({x},{y}): got {:?}, expected {expected:?}", &texels[i..i + 4]);
                }
                mismatches += 1;
            }
        }
    }
    assert_eq!(mismatches, 0, "{mismatches} texels differ");
}

#[test]
fn timestamps_give_positive_durations() {
    let gpu = Gpu::new();
    let (w, h) = (512u32, 512u32);
    let image = Image::storage_2d(&gpu, "timed", w, h, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    let pipeline = pattern_pipeline(&gpu, 1);
    let mut timer = GpuTimer::new(&gpu, 2).unwrap();
    gpu.record(|rec| {
        let cmd = rec.cmd();
        timer.reset(cmd);
        image.init_general(&gpu, cmd);
        for pass in ["first", "second"] {
            timer.begin(cmd, pass)?;
            record_pattern(&pipeline, rec, &image, &PatternParams { size: [w, h], seed: 1, frame: 0 })?;
            timer.end(cmd)?;
        }
        // A third pass exceeds the timer's capacity and is refused, not written out of range.
        assert!(timer.begin(cmd, "third").is_err());
        Ok(())
    })
    .unwrap();
    let times = timer.read().unwrap();
    assert_eq!(times.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), ["first", "second"]);
    for t in &times {
        assert!(t.ms > 0.0 && t.ms < 10_000.0, "{}: {} ms", t.name, t.ms);
    }
}

#[test]
fn buffers_round_trip_through_staging_and_a_kernel() {
    let gpu = Gpu::new();
    let count = 100_003u32; // not a multiple of the workgroup size
    let input: Vec<u32> = (0..count).map(|i| i.wrapping_mul(2654435761)).collect();
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let src = Buffer::upload(&gpu, "input", &input, usage).unwrap();
    assert_eq!(src.read::<u32>(&gpu).unwrap(), input, "staging upload then readback");

    let dst = Buffer::upload(&gpu, "output", &vec![0u32; count as usize], usage).unwrap();
    let pipeline = Pipeline::<test_buffer::Kernel>::plain(&gpu).unwrap();
    let params = BufferTestParams { count, add: 17 };
    gpu.record(|rec| {
        let resources = test_buffer::Resources { values_in: &src, values_out: &dst };
        pipeline.record(rec, &resources, &params, [count, 1, 1])
    })
    .unwrap();
    let out: Vec<u32> = dst.read(&gpu).unwrap();
    let expected: Vec<u32> = input.iter().map(|v| v.wrapping_mul(3).wrapping_add(17)).collect();
    assert_eq!(out, expected);
}

/// What `fold_test.comp` writes for `v` with its constants at `a` and `b`.
fn fold_expected(v: u32, a: bool, b: bool, add: u32) -> u32 {
    let mut r = if a { 1 } else { 2 };
    if a && v & 1 == 1 {
        r |= 4;
    }
    if v.is_multiple_of(3) || b {
        r |= 8;
    }
    if b || v.is_multiple_of(5) {
        r |= 16;
    }
    if !(a && v > 5) {
        r |= 32;
    }
    if a {
        r |= if b { 64 } else { 128 };
    } else if v > 100 {
        r |= 256;
    }
    if b {
        let h = (0..v & 3).fold(v, |h, _| h.wrapping_mul(2654435761).wrapping_add(1));
        r |= (h & 1) << 9;
    }
    r + add
}

/// The host folds a pipeline's boolean constants into its branches before the driver sees them
/// (src/vk/specialize.rs): each of the four settings of fold_test's two constants must give what
/// the unfolded kernel means, and the folding must have happened (branches folded, blocks cut).
#[test]
fn folded_specialization_constants_keep_the_kernels_meaning() {
    let gpu = Gpu::new();
    let count = 1000u32;
    let input: Vec<u32> = (0..count).map(|i| i.wrapping_mul(2654435761) % 997).collect();
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let src = Buffer::upload(&gpu, "input", &input, usage).unwrap();
    let words = umbra::kernels::kernel("fold_test").unwrap().words();
    for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
        let (_, folded) = umbra::vk::specialize::specialize(words, &[(32, a as u32), (33, b as u32)]);
        assert!(folded.branches >= 6 && folded.blocks_cut >= 6, "a {a}, b {b}: only {folded:?}");
        let dst = Buffer::upload(&gpu, "output", &vec![0u32; count as usize], usage).unwrap();
        let pipeline =
            Pipeline::<fold_test::Kernel>::new(&gpu, &fold_test::Spec { flag_a: a, flag_b: b }, None)
                .unwrap();
        let params = BufferTestParams { count, add: 1 << 12 };
        gpu.record(|rec| {
            let resources = fold_test::Resources { values_in: &src, values_out: &dst };
            pipeline.record(rec, &resources, &params, [count, 1, 1])
        })
        .unwrap();
        let out: Vec<u32> = dst.read(&gpu).unwrap();
        let expected: Vec<u32> = input.iter().map(|&v| fold_expected(v, a, b, params.add)).collect();
        let wrong = out.iter().zip(&expected).position(|(o, e)| o != e);
        assert!(
            wrong.is_none(),
            "constants a {a}, b {b}: input {} gave {:#b}, meant {:#b}",
            input[wrong.unwrap()],
            out[wrong.unwrap()],
            expected[wrong.unwrap()]
        );
    }
}

/// test_pattern.comp through the untyped pipeline of the Vulkan layer (as a host engine would
/// make its own kernel), its pattern multiplier 1.
fn untyped_pattern_pipeline(gpu: &Gpu) -> ComputePipeline {
    let desc = PipelineDesc {
        bindings: &[(0, raw::DescriptorType::STORAGE_IMAGE)],
        push_constant_size: std::mem::size_of::<PatternParams>() as u32,
        specialization: &[(umbra::gpu::kernel::FIRST_KERNEL_SPEC_ID, 1)],
    };
    ComputePipeline::new(gpu, "test_pattern", &desc).unwrap()
}

#[test]
fn binding_mistakes_are_errors_not_silent() {
    let gpu = Gpu::new();
    let image = Image::storage_2d(&gpu, "img", 8, 8, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    let buffer = Buffer::upload(&gpu, "buf", &[0u32; 16], raw::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    // The untyped pipeline of the Vulkan layer (what the typed one is built on) checks what it is
    // given against its layout.
    let pipeline = untyped_pattern_pipeline(&gpu);
    gpu.submit(|cmd| {
        pipeline.bind(cmd);
        let wrong_type = pipeline.push_descriptors(cmd, &[Descriptor::Buffer(&buffer)]);
        assert!(wrong_type.unwrap_err().to_string().contains("test_pattern"));
        let too_many =
            pipeline.push_descriptors(cmd, &[Descriptor::StorageImage(&image), Descriptor::Buffer(&buffer)]);
        assert!(too_many.is_err());
        let wrong_size = pipeline.push_constants(cmd, &[0u32; 3]);
        assert!(wrong_size.unwrap_err().to_string().contains("16 bytes"));
        Ok(())
    })
    .unwrap();
    assert!(ComputePipeline::new(&gpu, "no_such_kernel", &PipelineDesc::default()).is_err());
}

#[test]
fn device_limits_are_enforced_with_clear_errors() {
    let gpu = Gpu::new();
    let limit = gpu.info().max_storage_buffer_range;
    let too_big = Buffer::new(
        &gpu,
        "scene vertices",
        limit + 4,
        raw::BufferUsageFlags::STORAGE_BUFFER,
        umbra::vk::MemoryLocation::GpuOnly,
    );
    let message = too_big.err().expect("over-limit buffer refused").to_string();
    assert!(message.contains("scene vertices") && message.contains(&limit.to_string()), "{message}");

    let absurd = Image::storage_2d(&gpu, "frame", 1 << 20, 16, raw::Format::R32G32B32A32_SFLOAT);
    let message = absurd.err().expect("absurd image refused").to_string();
    assert!(message.contains("frame") && message.contains("1048576x16"), "{message}");
}

#[test]
fn validation_layer_reports_invalid_usage() {
    let gpu = Gpu::new();
    assert!(gpu.log().is_empty());
    // A buffer with no usage flags violates VUID-VkBufferCreateInfo-usage-requiredbitmask.
    let info = raw::BufferCreateInfo::default().size(64).usage(raw::BufferUsageFlags::empty());
    unsafe {
        let buffer = gpu.device().create_buffer(&info, None).expect("lavapipe creates it anyway");
        gpu.device().destroy_buffer(buffer, None);
    }
    let messages = gpu.log().take();
    assert!(
        messages.iter().any(|m| m.contains("VUID-VkBufferCreateInfo-usage")),
        "the messenger did not report the invalid usage: {messages:?}"
    );
}

#[test]
fn contexts_coexist_across_threads() {
    let handles: Vec<_> = (0..2)
        .map(|seed| {
            std::thread::spawn(move || {
                let gpu = Gpu::new();
                let image = Image::storage_2d(&gpu, "img", 16, 16, raw::Format::R32G32B32A32_SFLOAT).unwrap();
                let pipeline = pattern_pipeline(&gpu, 1);
                gpu.record(|rec| {
                    image.init_general(&gpu, rec.cmd());
                    record_pattern(&pipeline, rec, &image, &PatternParams { size: [16, 16], seed, frame: 0 })
                })
                .unwrap();
                let texels: Vec<f32> = image.read(&gpu).unwrap();
                texels[3]
            })
        })
        .collect();
    let w: Vec<f32> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    assert_eq!(w[0], (pattern_hash(0) & 0xffff) as f32);
    assert_eq!(w[1], (pattern_hash(1) & 0xffff) as f32);
}

#[test]
fn unknown_device_filter_names_the_devices() {
    let err = umbra::vk::Context::new(&umbra::vk::ContextDesc {
        validation: Some(false),
        device: Some("no-such-gpu-9000".into()),
    })
    .err()
    .expect("no device matches");
    let message = err.to_string();
    let devices = umbra::vk::Context::list_devices().expect("devices are listed");
    assert!(!devices.is_empty());
    assert!(message.contains("no-such-gpu-9000"), "{message}");
    for (name, _) in &devices {
        assert!(message.contains(name.as_str()), "'{name}' missing from: {message}");
    }
}

/// A host's own kernel recorded between umbra's passes, its write declared to the recorder, is
/// ordered by the barrier the recorder derives: the tone map reads the host's pattern (the same
/// bytes as with a submission between the two), with one barrier between them and one at the end,
/// and the validation layer's synchronization checks find no hazard. Left undeclared, the same
/// recording has no barrier between them and the validation layer reports the read after write:
/// the synchronization checks, on in every test, are what tests each derived barrier.
#[test]
fn a_declared_host_pass_is_ordered_by_derived_barriers() {
    use umbra::passes::tonemap::{ToneCurve, TonemapPass};
    use umbra::vk::{Recorder, Resource, Use};
    let gpu = Gpu::new();
    let (w, h) = (32u32, 32u32);
    let hdr = Image::storage_2d(&gpu, "hdr", w, h, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    let ldr = Image::storage_2d(&gpu, "ldr", w, h, raw::Format::R8G8B8A8_UNORM).unwrap();
    // The host's kernel: test_pattern through the untyped pipeline, which the recorder never sees.
    let host = untyped_pattern_pipeline(&gpu);
    let tonemap = TonemapPass::new(&gpu).unwrap();
    let params = PatternParams { size: [w, h], seed: 5, frame: 0 };
    let host_pass = |cmd| -> umbra::Result<()> {
        host.bind(cmd);
        host.push_descriptors(cmd, &[Descriptor::StorageImage(&hdr)])?;
        host.push_constants(cmd, &params)?;
        host.dispatch(cmd, [w, h, 1], test_pattern::LOCAL)
    };
    let tone = |rec: &mut Recorder<'_>| tonemap.record(rec, hdr.view, ldr.view, (w, h), 1.0, ToneCurve::Aces);
    gpu.submit(|cmd| {
        hdr.init_general(&gpu, cmd);
        ldr.init_general(&gpu, cmd);
        Ok(())
    })
    .unwrap();

    // The reference: a submission between the host's pass and umbra's.
    gpu.submit(host_pass).unwrap();
    gpu.record(tone).unwrap();
    let reference: Vec<u8> = ldr.read(&gpu).unwrap();
    assert!(reference.chunks(4).any(|p| p[..3] != reference[..3]), "the pattern is not flat");
    assert!(gpu.log().take().is_empty());

    let record = |declared: bool| {
        gpu.submit(|cmd| {
            let mut rec = Recorder::new(&gpu, cmd);
            if declared {
                rec.access(&[(Resource::Image(hdr.view), Use::ComputeWrite)]);
            }
            host_pass(cmd)?;
            tone(&mut rec)?;
            Ok(rec.finish())
        })
        .unwrap()
    };
    let stats = record(true);
    assert_eq!((stats.operations, stats.barriers), (2, 2), "one barrier between the passes, one at the end");
    assert_eq!(ldr.read::<u8>(&gpu).unwrap(), reference);
    let messages = gpu.log().take();
    assert!(messages.is_empty(), "{messages:?}");

    let stats = record(false);
    assert_eq!((stats.operations, stats.barriers), (1, 1), "nothing to order the tone map after");
    let messages = gpu.log().take();
    assert!(
        messages.iter().any(|m| m.contains("SYNC-HAZARD-READ-AFTER-WRITE")),
        "the undeclared write is a hazard the validation layer reports: {messages:?}"
    );
}

/// A frame graph culls, aliases and holds each pass to what it declared. Two patterns, each
/// tone-mapped into an image the caller reads, pass through transient HDR images whose lifetimes
/// do not overlap: one physical image holds both, the second pattern written after the first tone
/// map read it (a write after read the recorder orders). A pass whose output nothing reads is
/// culled and never runs. Run again, the graph takes its image from the pool. Each result equals
/// the same passes recorded without the graph, and the validation layer finds no hazard. A tone
/// map that reads the transient without declaring it is refused, the pass and image named.
#[test]
fn a_frame_graph_culls_aliases_and_holds_passes_to_their_declarations() {
    use std::cell::Cell;
    use umbra::passes::tonemap::{ToneCurve, TonemapPass};
    use umbra::vk::{Graph, ImageDesc, TransientPool};
    let gpu = Gpu::new();
    let (w, h) = (32u32, 32u32);
    let pattern = &pattern_pipeline(&gpu, 3);
    let tonemap = &TonemapPass::new(&gpu).unwrap();
    let ldr = [0, 1].map(|_| Image::storage_2d(&gpu, "ldr", w, h, raw::Format::R8G8B8A8_UNORM).unwrap());
    let hdr = Image::storage_2d(&gpu, "hdr", w, h, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    gpu.record(|rec| {
        for image in ldr.iter().chain([&hdr]) {
            image.init_general(&gpu, rec.cmd());
        }
        Ok(())
    })
    .unwrap();
    // Patterns differing in their blue channel (the frame number's).
    let params = |frame| PatternParams { size: [w, h], seed: 5, frame };
    let reference = [5, 900].map(|frame| {
        gpu.record(|rec| {
            record_pattern(pattern, rec, &hdr, &params(frame))?;
            tonemap.record(rec, hdr.view, ldr[0].view, (w, h), 1.0, ToneCurve::Aces)
        })
        .unwrap();
        ldr[0].read::<u8>(&gpu).unwrap()
    });
    assert!(reference[0] != reference[1], "the two patterns tone-map alike");

    let pool = TransientPool::new();
    let desc = ImageDesc { size: (w, h), format: raw::Format::R32G32B32A32_SFLOAT };
    let culled_ran = Cell::new(false);
    let build = |declare_read: bool| {
        let mut graph = Graph::new();
        for (k, frame) in [5, 900].into_iter().enumerate() {
            let hdr = graph.transient("pattern", desc);
            let out = graph.import("ldr", ldr[k].view);
            let p = params(frame);
            graph.add_pass("pattern").write(hdr).record(move |rec, views| {
                pattern.record(rec, &test_pattern::Resources { out_image: &views[hdr] }, &p, [w, h, 1])
            });
            let mut tone = graph.add_pass("tonemap").write(out);
            if declare_read {
                tone = tone.read(hdr);
            }
            tone.record(move |rec, views| {
                tonemap.record(rec, views[hdr], views[out], (w, h), 1.0, ToneCurve::Aces)
            });
        }
        let unused = graph.transient("unused", desc);
        graph.add_pass("unused").write(unused).record(|_, _| {
            culled_ran.set(true);
            Ok(())
        });
        graph
    };
    for round in 0..2 {
        let stats = gpu.record(|rec| build(true).execute(rec, &pool, None)).unwrap();
        assert_eq!(stats.recorded, ["pattern", "tonemap", "pattern", "tonemap"]);
        assert_eq!(stats.culled, ["unused"]);
        assert_eq!((stats.transients, stats.physical), (2, 1), "round {round}");
        assert_eq!(pool.len(), 1, "round {round}: the one image back in the pool");
        for (image, expected) in ldr.iter().zip(&reference) {
            assert!(&image.read::<u8>(&gpu).unwrap() == expected, "round {round}: not the reference");
        }
        let messages = gpu.log().take();
        assert!(messages.is_empty(), "{messages:?}");
    }
    assert!(!culled_ran.get(), "the culled pass recorded");
    let err = gpu.record(|rec| build(false).execute(rec, &pool, None)).unwrap_err().to_string();
    assert!(err.contains("pass 'tonemap' uses the image 'pattern' it did not declare"), "{err}");
}
