//! Anti-aliasing of the hybrid frame: the camera's sub-pixel jitter (every pass samples where the
//! pixel's ray goes), one-shot supersampling (`HybridSettings::samples`) and temporal
//! anti-aliasing through the embedding API (`HybridTargets::taa`).
//!
//! The scene is a box on a floor under a point light with one shadow ray, no AO and a black
//! environment: every pixel's value is a deterministic function of its ray, so a jittered frame
//! can be compared with a finer unjittered one exactly.

mod common;

use common::Gpu;
use glam::Vec3;
use umbra::embed::Renderer;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::gbuffer::{GBuffer, GBufferData, GBUFFER_NO_SURFACE};
use umbra::passes::taa::{HistoryFilter, TaaHistory, TaaSettings};
use umbra::render::{GBufferMethod, HybridSettings, HybridTargets, Passes};
use umbra::scene::{Camera, LightKind, Scene};
use umbra::vk::{raw, Image};

fn box_scene(camera: Camera) -> Scene {
    let floor = common::quad(Vec3::ZERO, Vec3::Z * 3.0, Vec3::X * 3.0);
    // Turned 30° about the vertical, so that its edges cross the pixels at slants.
    let turn = glam::Quat::from_rotation_y(0.52);
    let cube: Vec<[Vec3; 3]> = common::cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5))
        .into_iter()
        .map(|t| t.map(|p| turn * p))
        .collect();
    let light = common::light(LightKind::Point, Vec3::new(1.2, 2.5, 0.8), Vec3::NEG_Y, 6.0);
    common::build("box on a floor", &[floor, cube], vec![light], camera)
}

fn view() -> Camera {
    common::camera(Vec3::new(2.2, 2.0, 3.4), Vec3::new(0.0, 0.4, 0.0))
}

/// The deterministic hybrid: ray-cast G-buffer, one shadow ray to the point light, no AO.
fn settings(size: (u32, u32), samples: u32) -> HybridSettings {
    HybridSettings {
        size,
        gbuffer: GBufferMethod::Raycast,
        samples,
        ao: None,
        lighting: LightingSettings { shadow_rays: 1, ..Default::default() },
        ..Default::default()
    }
}

fn gbuffer_of(
    gpu: &Gpu,
    passes: &Passes,
    scene: &umbra::gpu::scene::GpuScene,
    camera: &Camera,
    size: (u32, u32),
) -> GBufferData {
    let target = GBuffer::new(gpu, size).unwrap();
    gpu.record(|rec| passes.record_gbuffer(rec, scene, camera, &target.views())).unwrap();
    target.read(gpu).unwrap()
}

/// A pixel jittered by ±¼ samples the image position of one pixel of an image of twice the size
/// (pixel p + ½ ± ¼ is (2p + 1 ± ½) / 2): the ray-cast G-buffers agree there bit for bit (depth,
/// normal, material) on every pixel.
#[test]
fn jittered_gbuffer_samples_where_an_image_of_twice_the_size_does() {
    let gpu = Gpu::new();
    let camera = view();
    let scene = box_scene(camera);
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let (w, h) = (40, 30);
    let fine = gbuffer_of(&gpu, &passes, &gpu_scene, &camera, (2 * w, 2 * h));
    for (jitter, (ox, oy)) in [([0.25, 0.25], (1, 1)), ([-0.25, -0.25], (0, 0)), ([0.25, -0.25], (1, 0))] {
        let coarse = gbuffer_of(&gpu, &passes, &gpu_scene, &camera.jittered(jitter), (w, h));
        let unjittered = gbuffer_of(&gpu, &passes, &gpu_scene, &camera, (w, h));
        let (mut surfaces, mut moved, mut differ) = (0, 0, Vec::new());
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let j = ((2 * y + oy) * 2 * w + 2 * x + ox) as usize;
                surfaces += (coarse.material[i][0] != GBUFFER_NO_SURFACE) as usize;
                moved += (coarse.depth[i] != unjittered.depth[i]) as usize;
                let same = coarse.depth[i].to_bits() == fine.depth[j].to_bits()
                    && coarse.normal[i].map(f32::to_bits) == fine.normal[j].map(f32::to_bits)
                    && coarse.material[i] == fine.material[j];
                if !same {
                    differ.push(format!("{x},{y}: depth {} vs {}", coarse.depth[i], fine.depth[j]));
                }
            }
        }
        eprintln!("jitter {jitter:?}: {surfaces} surface pixels, {moved} moved by the jitter");
        assert!(
            surfaces * 3 > (w * h) as usize && moved * 2 > surfaces,
            "{surfaces} surfaces, {moved} moved"
        );
        assert!(
            differ.is_empty(),
            "jitter {jitter:?}: {} pixels differ:\n{}",
            differ.len(),
            differ.join("\n")
        );
    }
}

/// Four sub-frames (the 2 × 2 grid of offsets ±¼) average the four samples an image of twice
/// the size takes in each pixel: the supersampled frame is that image's 2 × 2 box downsample, to
/// the rounding of a running mean; its AOVs are the pixels' centres' (the one-sample frame's).
#[test]
fn supersampled_frame_is_the_box_downsample_of_an_image_of_twice_the_size() {
    let gpu = Gpu::new();
    let camera = view();
    let scene = box_scene(camera);
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let (w, h) = (48, 36);
    let four = passes.hybrid(&gpu_scene, &camera, &settings((w, h), 4)).unwrap();
    let one = passes.hybrid(&gpu_scene, &camera, &settings((w, h), 1)).unwrap();
    let fine = passes.hybrid(&gpu_scene, &camera, &settings((2 * w, 2 * h), 1)).unwrap();
    let (mut worst, mut edges) = (0.0f32, 0);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let at = |dx: u32, dy: u32| fine.color[((2 * y + dy) * 2 * w + 2 * x + dx) as usize];
            for c in 0..3 {
                let mean = (at(0, 0)[c] + at(1, 0)[c] + at(0, 1)[c] + at(1, 1)[c]) / 4.0;
                worst = worst.max((four.color[i][c] - mean).abs() / mean.max(1.0));
                if (four.color[i][c] - one.color[i][c]).abs() > 0.05 * one.color[i][c].max(0.05) {
                    edges += 1;
                }
            }
        }
    }
    eprintln!("worst relative difference {worst:.2e}; {edges} channels moved by anti-aliasing");
    assert!(worst <= 4e-7, "the supersampled frame is not the downsample: {worst:.2e}");
    assert!(edges > 30, "anti-aliasing changed only {edges} channels");
    assert!(four.gbuffer.depth == one.gbuffer.depth && four.gbuffer.material == one.gbuffer.material);
    assert!(four.display != one.display, "the display image is the one-sample frame's");
}

/// A host's frames through the embedding API with TAA.
struct Host {
    gpu: Gpu,
    renderer: Renderer,
    size: (u32, u32),
    gbuffer: GBuffer,
    hdr: Image,
    history: TaaHistory,
}

impl Host {
    fn new(scene: &Scene, size: (u32, u32)) -> Self {
        let gpu = Gpu::new();
        let renderer = Renderer::new(&gpu, scene).unwrap();
        let gbuffer = GBuffer::new(&gpu, size).unwrap();
        let hdr = Image::storage_2d(&gpu, "hdr", size.0, size.1, raw::Format::R32G32B32A32_SFLOAT).unwrap();
        let history = renderer.taa_history(size, TaaSettings::default()).unwrap();
        gpu.submit(|cmd| {
            hdr.init_general(&gpu, cmd);
            history.init_general(&gpu, cmd);
            Ok(())
        })
        .unwrap();
        Self { gpu, renderer, size, gbuffer, hdr, history }
    }

    /// One frame seen by `camera`: its own samples (`hdr`) and the resolve.
    fn frame(&self, camera: &Camera) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
        let views = self.gbuffer.views();
        let targets = HybridTargets {
            gbuffer: &views,
            visibility: None,
            ao: None,
            hdr: self.hdr.view,
            ldr: None,
            shadows: None,
            probes: None,
            lightmaps: None,
            reservoirs: None,
            taa: Some(&self.history),
        };
        let settings = settings(self.size, 1);
        self.gpu.submit(|cmd| self.renderer.record_hybrid(cmd, camera, &targets, &settings, None)).unwrap();
        (self.hdr.read(&self.gpu).unwrap(), self.history.read(&self.gpu).unwrap())
    }

    /// The frame supersampled by 64 sub-frames (an 8 × 8 grid): the anti-aliased truth.
    fn reference(&self, camera: &Camera) -> Vec<[f32; 4]> {
        self.renderer.passes().hybrid(self.renderer.scene(), camera, &settings(self.size, 64)).unwrap().color
    }
}

/// Root-mean-square difference of the rgb channels.
fn rms(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let sum: f64 =
        a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).powi(2))).sum();
    (sum / (3 * a.len()) as f64).sqrt()
}

/// The camera turned by `angle` radians about the vertical (a rotation moves every point of the
/// image alike, whatever its depth).
fn turned(camera: &Camera, angle: f32) -> Camera {
    let turn = glam::Quat::from_rotation_y(angle);
    Camera {
        forward: (turn * Vec3::from(camera.forward)).to_array(),
        up: (turn * Vec3::from(camera.up)).to_array(),
        ..*camera
    }
}

/// TAA on a still view converges toward the supersampled frame: after two cycles of the
/// jitter, its error against 64 sub-frames is at most half the one-sample frame's (the aliasing
/// TAA exists to remove); the first frame is the frame itself, and a reset starts afresh.
#[test]
fn taa_converges_on_a_still_view() {
    let camera = view();
    let host = Host::new(&box_scene(camera), (64, 48));
    let reference = host.reference(&camera);
    let (first, resolved) = host.frame(&camera);
    let one_sample = rms(&first, &reference);
    // The first frame has no history: the resolve is its samples (at the first jitter).
    assert!(first.iter().zip(&resolved).all(|(a, b)| a[..3] == b[..3]), "the first resolve is not the frame");
    let mut errors = Vec::new();
    for _ in 1..16 {
        let (_, resolved) = host.frame(&camera);
        errors.push(rms(&resolved, &reference));
    }
    eprintln!("one sample: rms {one_sample:.4}; TAA over frames 2..16: {errors:.4?}");
    let last = *errors.last().unwrap();
    assert!(one_sample > 1e-3, "no aliasing to remove ({one_sample})");
    assert!(
        last <= 0.5 * one_sample,
        "TAA's error {last:.4} is over half the one-sample frame's {one_sample:.4}"
    );
    host.history.reset();
    let (frame, resolved) = host.frame(&camera);
    assert!(frame.iter().zip(&resolved).all(|(a, b)| a[..3] == b[..3]), "the reset did not start afresh");
}

/// TAA follows a turning view: each frame's resolve is nearer the supersampled frame of its
/// camera than its own samples are (the history reprojected, not smeared), with either history
/// filter, and the Catmull-Rom history (the default) nearer than the bilinear one, which blurs a
/// little at every reprojection; where the turn brings in what the last frame did not see, the
/// resolve is the frame's samples alone.
#[test]
fn taa_follows_a_turning_view() {
    let camera = view();
    let mut host = Host::new(&box_scene(camera), (64, 48));
    // A pixel's angle at the image's centre.
    let pixel = 2.0 * (camera.yfov / 2.0).tan() / 48.0;
    let mut cam = camera;
    let mut errors = Vec::new();
    for filter in [HistoryFilter::Bilinear, HistoryFilter::CatmullRom] {
        host.history.settings.history = filter;
        host.history.reset();
        cam = camera;
        for _ in 0..12 {
            cam = turned(&cam, 0.3 * pixel);
            host.frame(&cam);
        }
        let (samples, resolved) = host.frame(&cam);
        let reference = host.reference(&cam);
        let (own, taa) = (rms(&samples, &reference), rms(&resolved, &reference));
        eprintln!("turning 0.3 px a frame, {filter:?} history: one sample rms {own:.4}, TAA {taa:.4}");
        assert!(
            taa <= 0.75 * own,
            "{filter:?}: TAA's error {taa:.4} while turning is not below the frame's own {own:.4} by a quarter"
        );
        errors.push(taa);
    }
    assert!(
        errors[1] < errors[0],
        "the Catmull-Rom history's error {:.4} is not below the bilinear one's {:.4}",
        errors[1],
        errors[0]
    );

    // A turn of 8 pixels to the left: the 6 columns at the left edge were out of view.
    let left = turned(&cam, 8.0 * pixel);
    let (samples, resolved) = host.frame(&left);
    let (w, h) = host.size;
    for y in 0..h {
        for x in 0..6 {
            let i = (y * w + x) as usize;
            assert_eq!(
                samples[i][..3],
                resolved[i][..3],
                "pixel {x},{y} came into view but is not the frame's"
            );
        }
    }
    let kept = (0..(w * h) as usize).filter(|&i| resolved[i][3] > 1.0).count();
    assert!(kept * 2 > (w * h) as usize, "only {kept} pixels kept their history through the turn");
}

/// `scenes/animated.glb` posed at `time` (every animation).
fn animated_at(scene: &mut Scene, time: f32) {
    let at = umbra::scene::PoseAt { time, animations: umbra::scene::AnimationSelect::All };
    scene.pose(&at).unwrap();
}

fn animated() -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/animated.glb")).unwrap()
}

/// After a geometry update the G-buffer's `motion` is each surface point's displacement: at the
/// pixels of the posed animated scene (a skin, a turning node, a morph target), the point the
/// pixel's ray meets on the CPU (brute force over the posed triangles) less the point of the same
/// barycentrics on that triangle in the earlier pose, within half precision; exactly 0 on what
/// did not move. A scene that has not moved writes none.
#[test]
fn gbuffer_motion_is_each_points_displacement() {
    use umbra::bvh::{reference::Reference, Ray};
    use umbra::gpu::scene::BvhUpdate;
    let mut scene = animated();
    animated_at(&mut scene, 0.5);
    let gpu = Gpu::new();
    let mut renderer = Renderer::new(&gpu, &scene).unwrap();
    assert!(!renderer.scene().geometry_moved());
    let before = scene.triangle_soup();
    animated_at(&mut scene, 0.6);
    renderer.update_geometry(&scene, BvhUpdate::Refit).unwrap();
    assert!(renderer.scene().geometry_moved() && renderer.scene().geometry_generation() == 1);
    let after = scene.triangle_soup();
    let camera = scene.camera(None).unwrap();
    let (w, h) = (64u32, 48u32);
    let gbuffer = GBuffer::new(&gpu, (w, h)).unwrap();
    gpu.submit(|cmd| renderer.record_gbuffer(cmd, &camera, &gbuffer.views())).unwrap();
    let motion: Vec<[u16; 4]> = gbuffer.motion.read(&gpu).unwrap();
    let depth: Vec<f32> = gbuffer.depth.read(&gpu).unwrap();
    let reference = Reference::new(&after);
    let c = umbra::gpu::layout::GpuCamera::new(&camera, (w, h));
    let (o, f, r, u) = (Vec3::from(c.origin), Vec3::from(c.forward), Vec3::from(c.right), Vec3::from(c.up));
    let (mut moving, mut still, mut edges, mut worst) = (0, 0, 0, 0.0f32);
    for i in 0..(w * h) as usize {
        if depth[i] <= 0.0 {
            continue;
        }
        let (x, y) = ((i as u32 % w) as f32, (i as u32 / w) as f32);
        let ndc = (2.0 * (x + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y + 0.5) / h as f32);
        let dir = (f + ndc.0 * r + ndc.1 * u).normalize();
        let Some(hit) = reference.closest(&Ray { origin: o, dir, tmin: 0.0, tmax: f32::MAX }) else {
            edges += 1;
            continue;
        };
        // Where the CPU's surface is not the GPU's (a silhouette's rounding), nothing to compare.
        let cpu_depth = hit.t * dir.dot(f.normalize());
        if (cpu_depth - depth[i]).abs() > 1e-3 * depth[i] {
            edges += 1;
            continue;
        }
        let [b1, b2] = hit.bary;
        let at = |t: &[Vec3; 3]| t[0] * (1.0 - b1 - b2) + t[1] * b1 + t[2] * b2;
        let expected = at(&after[hit.tri as usize]) - at(&before[hit.tri as usize]);
        let m = motion[i].map(|v| half::f16::from_bits(v).to_f32());
        let got = Vec3::new(m[0], m[1], m[2]);
        if expected == Vec3::ZERO {
            assert_eq!(got, Vec3::ZERO, "pixel {x},{y} did not move but has motion {got}");
            still += 1;
        } else {
            moving += 1;
            worst = worst.max((got - expected).length() / (1e-3 * expected.length() + 1e-4));
        }
    }
    eprintln!("{moving} moving pixels, {still} still, {edges} left out; worst error {worst:.2} of the bound");
    assert!(moving > 100 && still > 200, "the view shows too little: {moving} moving, {still} still");
    assert!(edges * 20 < moving + still, "{edges} pixels left out");
    assert!(worst <= 1.0, "a motion is off by {worst:.2} times half precision's bound");
}

/// TAA follows moving geometry by the G-buffer's motion: over frames of the animated scene seen
/// by a still camera, posed and refitted each frame, the resolve's error against the
/// supersampled frame of the last pose is below the frame's own samples' by a quarter; a history
/// that skips an update starts afresh (its resolve is the frame's samples).
#[test]
fn taa_follows_moving_geometry() {
    use umbra::gpu::scene::BvhUpdate;
    let mut scene = animated();
    animated_at(&mut scene, 0.4);
    let camera = scene.camera(None).unwrap();
    let mut host = Host::new(&scene, (64, 48));
    let mut time = 0.4;
    for _ in 0..12 {
        time += 1.0 / 30.0;
        animated_at(&mut scene, time);
        host.renderer.update_geometry(&scene, BvhUpdate::Refit).unwrap();
        host.frame(&camera);
    }
    let (samples, resolved) = host.frame(&camera);
    let reference = host.reference(&camera);
    // The pixels whose surface moved (by the G-buffer's motion, which the test above checks).
    let motion: Vec<[u16; 4]> = host.gbuffer.motion.read(&host.gpu).unwrap();
    let moved: Vec<usize> =
        (0..motion.len()).filter(|&i| motion[i][..3].iter().any(|&m| m & 0x7fff != 0)).collect();
    let pick = |image: &[[f32; 4]]| moved.iter().map(|&i| image[i]).collect::<Vec<_>>();
    let (own, taa) = (rms(&pick(&samples), &pick(&reference)), rms(&pick(&resolved), &pick(&reference)));
    eprintln!(
        "moving geometry ({} pixels), still camera: one sample rms {own:.4}, TAA {taa:.4}",
        moved.len()
    );
    assert!(moved.len() > 100, "only {} pixels moved", moved.len());
    assert!(taa <= 0.75 * own, "TAA's error {taa:.4} is not below the frame's own {own:.4} by a quarter");

    // Two updates between frames: the history cannot follow, and starts afresh.
    for _ in 0..2 {
        time += 1.0 / 30.0;
        animated_at(&mut scene, time);
        host.renderer.update_geometry(&scene, BvhUpdate::Refit).unwrap();
    }
    let (samples, resolved) = host.frame(&camera);
    assert!(samples.iter().zip(&resolved).all(|(a, b)| a[..3] == b[..3]), "the history did not start afresh");
}
