//! Orthographic cameras (glTF `camera.orthographic`) in the kernels that cast or project camera
//! rays: the G-buffer's view of squares facing the camera (exactly the pixels the magnification
//! puts them on, at one depth each), the hybrid's deferred lighting against the path tracer on one
//! orthographic view. (SSAO: tests/ao.rs; the wavefront integrator: tests/wavefront.rs; the
//! loader: tests/scene/.)

mod common;

use common::Gpu;
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::passes::gbuffer::{GBuffer, GBufferPass, GBUFFER_NO_SURFACE};
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{Camera, LightKind, Orthographic};

/// An orthographic camera at `position` looking at `target` with half extents `xmag`, `ymag`.
fn orthographic(position: Vec3, target: Vec3, xmag: f32, ymag: f32) -> Camera {
    Camera {
        yfov: 0.0,
        aspect: Some(xmag / ymag),
        orthographic: Some(Orthographic { xmag, ymag, zfar: 100.0 }),
        ..common::camera(position, target)
    }
}

/// Two unit squares facing an orthographic camera 5 in front of the nearer (xmag 2, ymag 1), the
/// second 3 farther and to the right. Every pixel's centre ray runs straight down -z from the
/// image plane, so a pixel sees a square exactly when its centre, placed on the 4 × 2 view
/// (±ymag × the image's aspect wide, ±ymag high), lies inside it, at view depth 5 or 8 whatever
/// the pixel. At 128 × 64 (the file's aspect) each square covers 32 × 32 pixels (a pinhole would
/// make the farther one smaller); at 64 × 64 the view is 2 × 2 (ymag kept, the width from the
/// image), and half of each square is in it. Square edges fall between pixel centres.
#[test]
fn gbuffer_of_squares_facing_an_orthographic_camera_is_exact() {
    let gpu = Gpu::new();
    let near = common::quad(Vec3::new(-1.0, 0.0, 0.0), Vec3::X * 0.5, Vec3::Y * 0.5);
    let far = common::quad(Vec3::new(1.0, 0.0, -3.0), Vec3::X * 0.5, Vec3::Y * 0.5);
    let camera = orthographic(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 2.0, 1.0);
    let scene = common::build("orthographic squares", &[near, far], vec![], camera);
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let pass = GBufferPass::new(&gpu, &gpu_scene).unwrap();
    for (size, covered) in [((128u32, 64u32), 32 * 32), ((64, 64), 16 * 32)] {
        let target = GBuffer::new(&gpu, size).unwrap();
        let params = GBufferPass::params(&camera, size);
        gpu.record(|rec| pass.record(rec, &gpu_scene, &target.views(), &params, None)).unwrap();
        let data = target.read(&gpu).unwrap();
        let half_width = size.0 as f32 / size.1 as f32;
        let (mut counts, mut wrong) = ([0usize; 2], Vec::new());
        for y in 0..size.1 {
            for x in 0..size.0 {
                let i = (y * size.0 + x) as usize;
                let px = (2.0 * (x as f32 + 0.5) / size.0 as f32 - 1.0) * half_width;
                let py = 1.0 - 2.0 * (y as f32 + 0.5) / size.1 as f32;
                let on = |cx: f32| (px - cx).abs() < 0.5 && py.abs() < 0.5;
                let expected = if on(-1.0) {
                    Some((0, 5.0))
                } else if on(1.0) {
                    Some((1, 8.0))
                } else {
                    None
                };
                let (material, depth) = (data.material[i][0], data.depth[i]);
                match expected {
                    Some((m, d)) if material == m && (depth - d).abs() <= 1e-5 * d => counts[m as usize] += 1,
                    None if material == GBUFFER_NO_SURFACE && depth == 0.0 => {}
                    _ => wrong
                        .push(format!("{x},{y}: material {material} depth {depth}, expected {expected:?}")),
                }
            }
        }
        eprintln!("{size:?}: squares cover {counts:?} pixels, {} wrong", wrong.len());
        assert!(
            wrong.is_empty(),
            "{size:?}: {} wrong pixels:\n{}",
            wrong.len(),
            wrong[..wrong.len().min(20)].join("\n")
        );
        assert_eq!(counts, [covered; 2], "{size:?}");
    }
}

/// A box on a floor under a point light, seen from above by an orthographic camera: the hybrid's
/// deferred lighting (the G-buffer's orthographic rays, its points reconstructed from depth for
/// the light and shadow rays) equals the path tracer's direct light (one scattering event; its
/// orthographic camera rays) within the path tracer's noise on interior pixels (see
/// [`common::interior_pixels`], one flat face: normals within 2.6°). z = difference / standard error of the path-traced mean, with 2e-3
/// relative for the G-buffer's half floats; |z| > 4 has probability 6e-5 per channel for a
/// Gaussian: at most 0.5 % of the pixels may exceed it. The light falls off with distance and
/// angle everywhere, so a point reconstructed off its surface shows.
#[test]
fn hybrid_equals_the_path_tracer_under_an_orthographic_camera() {
    let gpu = Gpu::new();
    let floor = common::quad(Vec3::ZERO, Vec3::Z * 3.0, Vec3::X * 3.0);
    let cube = common::cuboid(Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 1.0, 0.5));
    let light = common::light(LightKind::Point, Vec3::new(1.2, 2.5, 0.8), Vec3::NEG_Y, 6.0);
    let camera = orthographic(Vec3::new(3.0, 4.0, 5.0), Vec3::new(0.0, 0.3, 0.0), 1.6, 1.6);
    let scene = common::build("orthographic box", &[floor, cube], vec![light], camera);
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let size = (64, 64);
    let settings = PathSettings { size, spp: 64, max_bounces: 1, ..Default::default() };
    let reference = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let hybrid = hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size, ..Default::default() }).unwrap();
    let keep = common::interior_pixels(&hybrid.gbuffer, &hybrid.color, 0.999);
    let (compared, outliers, worst) = common::z_outliers(&reference, &hybrid.color, &keep);
    let lit = (0..keep.len()).filter(|&i| keep[i] && reference.mean[i][0] > 0.01).count();
    let box_faces = (0..keep.len()).filter(|&i| keep[i] && hybrid.gbuffer.material[i][0] == 1).count();
    eprintln!("{compared} interior pixels ({box_faces} on the box, {lit} lit), {outliers} with |z| > 4, worst |z| {worst:.2}");
    assert!(
        compared > 2000 && box_faces > 300 && lit > 1500,
        "too few pixels to compare: {compared}, {box_faces}, {lit}"
    );
    assert!(outliers * 200 <= compared, "{outliers} of {compared} pixels differ (worst |z| {worst:.2})");
}
