//! The host-engine example (`examples/embed.rs`) as a test: a pure-`ash` host with its own
//! device, images, G-buffer kernel, command buffer and fence asks umbra to record lighting and
//! tone mapping; validation on (the host's own messenger counts every message).

#[path = "../examples/embed.rs"]
mod embed;

/// Mean over pixels of the per-pixel largest 8-bit channel difference, and the share of pixels
/// that differ by more than `tolerance` steps.
fn compare(a: &[u8], b: &[u8], tolerance: u8) -> (f64, f64) {
    let mut sum = 0.0;
    let mut over = 0;
    let n = a.len() / 4;
    for (p, q) in a.chunks(4).zip(b.chunks(4)) {
        let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
        sum += d as f64;
        over += (d > tolerance) as usize;
    }
    (sum / n as f64, over as f64 / n as f64)
}

/// The host's G-buffer (its own kernel, its own images) lit by umbra gives the same frame as
/// umbra's own ray-cast G-buffer: the two differ only where the two ray casts pick different
/// triangles at shared edges and in the light samples' noise, which uses the same seeds.
#[test]
fn host_gbuffer_lit_by_umbra_matches_umbra_gbuffer() {
    let frames = embed::run((96, 96), true).expect("the example host runs");
    assert_eq!(frames.validation_messages, 0, "validation messages (printed above)");
    // One frame graph: the host's pass and umbra's, SSAO's four transient images (two per
    // frame) held by two physical images, the second frame's reusing the first's.
    let passes = ["ssao", "ao_blur", "lighting", "tonemap"];
    let expected: Vec<&str> =
        ["host gbuffer"].iter().chain(&passes).chain(&["gbuffer"]).chain(&passes).copied().collect();
    assert_eq!(frames.graph.recorded, expected);
    assert_eq!((frames.graph.transients, frames.graph.physical), (4, 2));
    let (mean, share) = compare(&frames.host_gbuffer, &frames.umbra_gbuffer, 8);
    eprintln!(
        "host vs umbra G-buffer: mean max-channel difference {mean:.3} steps, {:.2} % of pixels over 8 steps",
        share * 100.0
    );
    assert!(share < 0.01, "{:.2} % of pixels differ by more than 8 steps", share * 100.0);
    assert!(mean < 0.5, "mean difference {mean:.3} steps");

    // The frame is the lit Cornell box, not black or flat: the light (top centre) is the
    // brightest region, and the red and green walls show their colours on the left and right.
    let px = |x: u32, y: u32| {
        let i = ((y * frames.size.0 + x) * 4) as usize;
        [frames.host_gbuffer[i], frames.host_gbuffer[i + 1], frames.host_gbuffer[i + 2]]
    };
    let (w, h) = frames.size;
    let dominant = |c: [u8; 3], k: usize| (0..3).all(|j| j == k || c[k] as f32 > 1.5 * c[j] as f32);
    let left = px(w / 16 + 2, h / 2);
    let right = px(w - w / 16 - 3, h / 2);
    assert!(dominant(left, 0), "left wall should be red: {left:?}");
    assert!(dominant(right, 1), "right wall should be green: {right:?}");
    let floor = px(w / 2, h - 4);
    let light = px(w / 2, h * 15 / 100);
    let sum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
    assert!(sum(floor) > 90, "the floor is lit: {floor:?}");
    assert!(sum(light) > 600, "the light is the brightest thing in view: {light:?}");
}

mod common;

/// umbra's G-buffer of `camera`, lit by umbra's deferred lighting (default settings), read back.
fn lit_gbuffer(
    gpu: &common::Gpu,
    renderer: &umbra::embed::Renderer,
    camera: &umbra::scene::Camera,
    size: (u32, u32),
) -> Vec<[f32; 4]> {
    use umbra::vk::{raw, Image};
    let gbuffer = umbra::passes::gbuffer::GBuffer::new(gpu, size).unwrap();
    let hdr = Image::storage_2d(gpu, "hdr", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    gpu.submit(|cmd| {
        hdr.init_general(gpu, cmd);
        renderer.record_gbuffer(cmd, camera, &gbuffer.views())?;
        renderer.record_lighting(
            cmd,
            camera,
            &gbuffer.views(),
            hdr.view,
            &umbra::passes::deferred::LightingInputs::default(),
            &umbra::passes::deferred::LightingSettings::default(),
        )
    })
    .unwrap();
    hdr.read(gpu).unwrap()
}

/// A scene update (materials and lights changed, same geometry) through `Renderer::update_scene`
/// renders exactly what a renderer built from scratch on the changed scene renders, from a moved
/// camera too, and differs from the frame before the update.
#[test]
fn update_scene_equals_a_fresh_renderer() {
    use umbra::embed::Renderer;
    use umbra::scene::Scene;

    let gpu = common::Gpu::new();
    let size = (48, 48);
    let render =
        |renderer: &Renderer, camera: &umbra::scene::Camera| lit_gbuffer(&gpu, renderer, camera, size);
    let mut scene = Scene::cornell_box();
    let mut camera = scene.camera(None).unwrap();
    let mut renderer = Renderer::new(&gpu, &scene).unwrap();
    let before = render(&renderer, &camera);

    // Recolour every material, double the light, and move the camera.
    for m in &mut scene.materials {
        m.base_color_factor = [m.base_color_factor[2], m.base_color_factor[0], m.base_color_factor[1], 1.0];
        m.emissive = m.emissive.map(|e| 2.0 * e);
    }
    scene.update_emissive();
    camera.position[0] += 0.05;
    renderer.update_scene(&scene).unwrap();
    let updated = render(&renderer, &camera);
    let fresh = render(&Renderer::new(&gpu, &scene).unwrap(), &camera);
    assert!(updated == fresh, "an updated renderer differs from a fresh one");
    assert!(updated != before, "the update changed nothing");

    // A different triangle count is refused with a clear error, not a stale BVH.
    let mut other = scene.clone();
    other.triangles.pop();
    other.triangle_material.pop();
    let err = renderer.update_scene(&other).unwrap_err().to_string();
    assert!(err.contains("geometry changes need a new upload"), "{err}");
}

/// An animated scene posed again through `Scene::pose` and taken by
/// `Renderer::update_geometry` renders, refitted and rebuilt alike, exactly what a renderer built
/// from scratch on the file loaded at that time renders (the BVH's tie rule makes every hit
/// independent of the tree), and differs from the rest pose.
#[test]
fn posed_and_refitted_equals_a_fresh_renderer_at_that_time() {
    use umbra::embed::Renderer;
    use umbra::gpu::scene::BvhUpdate;
    use umbra::scene::{AnimationSelect, LoadOptions, PoseAt, Scene};

    let gpu = common::Gpu::new();
    let size = (64, 48);
    let render =
        |renderer: &Renderer, camera: &umbra::scene::Camera| lit_gbuffer(&gpu, renderer, camera, size);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animated.glb");
    let mut scene = Scene::load(&path).unwrap();
    let camera = scene.camera(None).unwrap();
    let mut renderer = Renderer::new(&gpu, &scene).unwrap();
    let rest = render(&renderer, &camera);
    for (time, how) in [(0.8, BvhUpdate::Refit), (1.3, BvhUpdate::Refit), (0.6, BvhUpdate::Rebuild)] {
        let at = PoseAt { time, animations: AnimationSelect::All };
        scene.pose(&at).unwrap();
        renderer.update_geometry(&scene, how).unwrap();
        let updated = render(&renderer, &camera);
        let loaded = Scene::load_with(&path, &LoadOptions { pose: Some(at), ..Default::default() }).unwrap();
        let fresh = render(&Renderer::new(&gpu, &loaded).unwrap(), &camera);
        assert!(updated == fresh, "posed at {time} s and {how:?}: differs from a fresh renderer");
        assert!(updated != rest, "posing at {time} s changed nothing");
    }
}

/// Progressive path tracing through the embedding API — samples recorded in two batches into
/// the caller's command buffers and resolved into the caller's image — gives the running mean
/// `render::path_trace` computes with the same settings: the same samples, merged into the mean
/// in two dispatches (2, then 4 samples) instead of one, so equal up to float rounding (a few ulps of the
/// largest value; a wrong sample or a sample counted twice moves a pixel by far more).
#[test]
fn embedded_path_tracing_equals_render_path_trace() {
    use umbra::embed::Renderer;
    use umbra::render::{path_trace, PathSettings};
    use umbra::scene::Scene;
    use umbra::vk::{raw, Image};

    let gpu = common::Gpu::new();
    let scene = Scene::cornell_box();
    let camera = scene.camera(None).unwrap();
    let renderer = Renderer::new(&gpu, &scene).unwrap();
    let settings = PathSettings { size: (32, 24), spp: 6, seed: 7, ..PathSettings::default() };
    let target = renderer.path_target(settings.size).unwrap();
    let output = Image::storage_2d(&gpu, "resolved", 32, 24, raw::Format::R32G32B32A32_SFLOAT).unwrap();
    gpu.submit(|cmd| {
        output.init_general(&gpu, cmd);
        renderer.record_path_samples(cmd, &camera, &target, &settings, 0, 2)
    })
    .unwrap();
    gpu.submit(|cmd| {
        renderer.record_path_samples(cmd, &camera, &target, &settings, 2, 4)?;
        renderer.record_path_resolve(cmd, &target, output.view)
    })
    .unwrap();
    let embedded: Vec<[f32; 4]> = output.read(&gpu).unwrap();
    let reference = path_trace(&gpu, renderer.scene(), &camera, &settings, |_, _| {}).unwrap();
    assert!(embedded.iter().any(|p| p[0] > 0.0), "the resolved image is black");
    let scale = embedded.iter().flat_map(|p| p[..3].iter()).fold(0.0f32, |m, v| m.max(v.abs()));
    let worst = embedded
        .iter()
        .zip(&reference.mean)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(
        worst <= 8.0 * f32::EPSILON * scale,
        "embedded samples differ from render::path_trace by {worst}"
    );
    assert!(embedded.iter().zip(&reference.mean).all(|(a, b)| a[3] == b[3]), "sample counts differ");

    let wrong = PathSettings { size: (16, 16), ..settings };
    let err =
        gpu.submit(|cmd| renderer.record_path_samples(cmd, &camera, &target, &wrong, 0, 1)).unwrap_err();
    assert!(err.to_string().contains("target is"), "{err}");
}

/// The whole hybrid frame recorded through the embedding API into the caller's images (one
/// `record_hybrid` call: the visibility buffer and the G-buffer resolved from it, SSAO and its
/// blur, lighting, tonemap) is exactly the one-shot `render::hybrid` of the same settings (whose
/// G-buffer is rasterized by default): both go through the one orchestrator. Passes built for
/// one scene's features refuse a scene with others instead of silently ignoring its textures.
#[test]
fn embedded_hybrid_frame_equals_render_hybrid() {
    use umbra::embed::Renderer;
    use umbra::passes::ao::AoSettings;
    use umbra::passes::gbuffer::GBuffer;
    use umbra::render::{hybrid, HybridSettings, HybridTargets, Passes};
    use umbra::scene::Scene;
    use umbra::vk::{raw, GpuTimer, Image};

    let gpu = common::Gpu::new();
    let scene = Scene::cornell_box();
    let camera = scene.camera(None).unwrap();
    let renderer = Renderer::new(&gpu, &scene).unwrap();
    let size = (40, 32);
    let settings = HybridSettings { size, ao: Some(AoSettings::default()), ..HybridSettings::default() };
    let gbuffer = GBuffer::new(&gpu, size).unwrap();
    let image = |name, format| Image::storage_2d(&gpu, name, size.0, size.1, format).unwrap();
    let hdr = image("hdr", raw::Format::R32G32B32A32_SFLOAT);
    let ldr = image("ldr", raw::Format::R8G8B8A8_UNORM);
    let ao = [image("ao", raw::Format::R32_SFLOAT), image("ao blurred", raw::Format::R32_SFLOAT)];
    let views = gbuffer.views();
    let visibility = renderer.visibility_buffer(size, settings.gbuffer).unwrap();
    assert!(visibility.is_some(), "lavapipe rasterizes the default G-buffer");
    let targets = HybridTargets {
        gbuffer: &views,
        visibility: visibility.as_ref(),
        ao: Some((ao[0].view, ao[1].view)),
        hdr: hdr.view,
        ldr: Some(ldr.view),
        shadows: None,
        probes: None,
        lightmaps: None,
        reservoirs: None,
        taa: None,
    };
    let mut timer = GpuTimer::new(&gpu, 8).unwrap();
    gpu.submit(|cmd| {
        for i in [&hdr, &ldr, &ao[0], &ao[1]] {
            i.init_general(&gpu, cmd);
        }
        timer.reset(cmd);
        renderer.record_hybrid(cmd, &camera, &targets, &settings, Some(&mut timer))
    })
    .unwrap();
    let names: Vec<String> = timer.read().unwrap().into_iter().map(|t| t.name).collect();
    assert_eq!(names, ["visibility", "gbuffer", "ssao", "ao_blur", "lighting", "tonemap"]);
    let reference = hybrid(&gpu, renderer.scene(), &camera, &settings).unwrap();
    let color: Vec<[f32; 4]> = hdr.read(&gpu).unwrap();
    let display: Vec<[u8; 4]> = ldr.read(&gpu).unwrap();
    assert!(color.iter().any(|p| p[0] > 0.0), "the frame is black");
    assert!(color == reference.color, "the embedded frame differs from render::hybrid");
    assert!(display == reference.display, "the embedded display image differs from render::hybrid");

    // Passes for the Cornell box (no textures) given a textured scene.
    let textured = umbra::gpu::scene::GpuScene::upload(
        &gpu,
        &Scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/textured.glb")))
            .unwrap(),
    )
    .unwrap();
    let passes = Passes::new(&gpu, renderer.scene());
    let err = passes.hybrid(&textured, &camera, &settings).unwrap_err().to_string();
    assert!(err.contains("build new passes"), "{err}");
}

/// A host may make umbra's renderer on a thread of its own, whose stack is smaller than the main
/// thread's 8 MiB (Rust's spawned threads get 2 MiB). `Renderer::new` on the Cornell box, on a
/// 1 MiB stack: the pipeline slot tables used to be inline in `Passes` (about 250 KB), and
/// `Renderer::new` and the calls it moved them through took about 1.2 MB of stack between them,
/// which overflowed a 2 MiB test thread once other frames were added.
#[test]
fn a_renderer_is_made_on_a_thread_with_a_small_stack() {
    use umbra::embed::Renderer;
    use umbra::scene::Scene;
    let gpu = common::Gpu::new();
    let scene = Scene::cornell_box();
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(1 << 20)
            .spawn_scoped(s, || Renderer::new(&gpu, &scene).map(|_| ()))
            .unwrap()
            .join()
            .expect("the renderer's thread panicked")
            .unwrap();
    });
}
