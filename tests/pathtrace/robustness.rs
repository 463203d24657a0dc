//! Determinism, robustness (no NaN or Inf reaches the accumulation buffer), the error target
//! and the lane counts.

use crate::common::{relative_mse, Gpu};
use crate::{camera, floor_quad, looking_down, render, scene_of};
use glam::Vec3;
use umbra::gpu::layout::PathStats;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{PathTarget, Sampler};
use umbra::procedural::{icosphere, Mesh};
use umbra::render::{Passes, PathSettings};
use umbra::scene::{Material, Scene};

#[test]
fn same_seed_same_bytes_different_seed_different() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let settings = PathSettings { size: (32, 32), spp: 4, ..Default::default() };
    let bytes =
        |s: &PathSettings| bytemuck::cast_slice::<[f32; 4], u8>(&render(&gpu, &scene, s).mean).to_vec();
    let a = bytes(&settings);
    let b = bytes(&settings);
    let c = bytes(&PathSettings { seed: 7, ..settings.clone() });
    assert!(a == b, "same seed, different output");
    assert!(a != c, "different seeds, identical output");
}

/// A scene built to provoke NaN and Inf: roughness 0 mirrors, zero-length vertex normals,
/// degenerate and tiny emissive triangles, rays grazing a floor and hitting edges.
#[test]
fn provoking_scene_never_accumulates_nan_or_inf() {
    let gpu = Gpu::new();
    let floor = floor_quad(5.0);
    let mirror_ball = icosphere(2, Vec3::new(0.0, 0.5, 0.0), 0.5);
    let tiny_light = Mesh {
        positions: vec![Vec3::new(0.0, 2.0, 0.0), Vec3::new(1e-4, 2.0, 0.0), Vec3::new(0.0, 2.0, 1e-4)],
        triangles: vec![[0, 2, 1]],
    };
    let degenerate_light = Mesh {
        positions: vec![Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(2.0, 2.0, 2.0)],
        triangles: vec![[0, 1, 2], [0, 0, 0]],
    };
    let big_light = icosphere(1, Vec3::new(-2.0, 2.0, -1.0), 0.3);
    let emissive =
        |e: f32| Material { emissive: [e; 3], metallic: 0.0, double_sided: true, ..Default::default() };
    let mirror = Material { metallic: 1.0, roughness: 0.0, ..Default::default() };
    let glossy = Material { metallic: 0.0, roughness: 0.0, ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.02, 6.0), Vec3::new(0.0, 0.0, 0.0), 60.0);
    let mut scene = scene_of(
        &[
            (&floor, glossy, false),
            (&mirror_ball, mirror, false),
            (&tiny_light, emissive(1e6), false),
            (&degenerate_light, emissive(100.0), false),
            (&big_light, emissive(20.0), false),
        ],
        cam,
    );
    // Zero-length shading normals on the mirror ball.
    let ball = scene.triangle_material.iter().position(|&m| m == 1).unwrap();
    for t in ball..ball + mirror_ball.triangles.len() {
        for v in scene.triangles[t] {
            scene.normals[v as usize] = [0.0; 3];
        }
    }
    for heuristic in
        [umbra::passes::pathtrace::Heuristic::Power, umbra::passes::pathtrace::Heuristic::Balance]
    {
        let settings = PathSettings {
            size: (48, 32),
            spp: 8,
            env: [0.5; 3],
            heuristic,
            max_bounces: 6,
            ..Default::default()
        };
        let image = render(&gpu, &scene, &settings);
        assert!(image.mean.iter().flatten().all(|v| v.is_finite()), "non-finite accumulated value");
        assert!(image.moment.iter().flatten().all(|v| v.is_finite()), "non-finite second moment");
    }
}

/// `target_error` stops accumulating once the estimated relative error is reached: a loose
/// target stops early, a tighter one needs more samples, and the image meets its target.
#[test]
fn target_error_stops_early_and_is_met() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let run = |target: f32| {
        let settings =
            PathSettings { size: (24, 24), spp: 4096, target_error: Some(target), ..Default::default() };
        render(&gpu, &scene, &settings)
    };
    let (loose, tight) = (run(0.1), run(0.05));
    eprintln!(
        "target 0.1: {} spp, error {}; target 0.05: {} spp, error {}",
        loose.spp,
        loose.relative_error(),
        tight.spp,
        tight.relative_error()
    );
    assert!(loose.spp < tight.spp && tight.spp < 4096, "{} then {} spp", loose.spp, tight.spp);
    assert!(loose.relative_error() <= 0.1 && tight.relative_error() <= 0.05);
}

/// The error `target_error` stops at is the true one: the image's estimated relative error (from
/// its own per-pixel variance) against its relative RMS error to an independent reference (another
/// seed, 64× the samples), on the Cornell box (area light). With independent numbers (the
/// estimate's premise) the two agree within 50 %; the reference's own noise (1/64 of the image's
/// variance) adds under 1 %. With the default low-discrepancy numbers the estimate is high (the
/// stratification lowers the true error; 0.058 estimated, 0.045 true when written), never low.
/// What the estimate cannot do: see a heavy tail its samples missed. spheres.glb under a sky of
/// 0.3 (a directional light's glints on glossy spheres: rare bright paths) stopped at 64 spp with
/// 0.077 estimated and 0.161 true (independent numbers; 0.072 and 0.120 with low-discrepancy ones
/// at 128), where an earlier sequence of random numbers had drawn 0.064 and 0.073: it was left
/// out of this test, whose bound it meets by chance only.
#[test]
fn target_error_is_the_true_error() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    for sampler in Sampler::ALL {
        let base = PathSettings { size: (24, 24), spp: 4096, max_bounces: 4, sampler, ..Default::default() };
        let image = render(&gpu, &scene, &PathSettings { target_error: Some(0.08), seed: 1, ..base.clone() });
        let reference = render(&gpu, &scene, &PathSettings { spp: 64 * image.spp, seed: 2, ..base });
        let (estimated, actual) =
            (image.relative_error() as f64, relative_mse(&image.mean, &reference.mean).sqrt());
        eprintln!("{sampler:?}: stopped at {} spp, estimated {estimated:.4}, true {actual:.4}", image.spp);
        assert!(image.spp < 4096 && estimated <= 0.08, "{sampler:?}: the target was not reached");
        match sampler {
            Sampler::Independent => assert!(
                (actual / estimated - 1.0).abs() < 0.5,
                "{sampler:?}: true error {actual} vs estimated {estimated}"
            ),
            Sampler::LowDiscrepancy => {
                assert!(actual < estimated, "{sampler:?}: true error {actual} over the estimate {estimated}")
            }
        }
    }
}

/// Renders `spp` samples of `scene` from its first camera into `target` (settings otherwise
/// `PathSettings::default()`'s at the target's size) and returns the target's counters.
fn render_into(gpu: &Gpu, scene: &Scene, target: &PathTarget, spp: u32) -> PathStats {
    let device_scene = GpuScene::upload(gpu, scene).unwrap();
    let passes = Passes::new(gpu, &device_scene);
    let camera = scene.camera(None).unwrap();
    let settings = PathSettings { size: target.size, spp, ..PathSettings::default() };
    gpu.record(|rec| passes.record_path_samples(rec, &device_scene, &camera, target, &settings, 0..spp))
        .unwrap();
    target.stats.read::<PathStats>(gpu).unwrap()[0]
}

/// The megakernel's lane counts (`PathTarget::with_lane_counts`, the diagnostic behind
/// `umbra-bench paths --lanes`): they leave the render bit for bit as it was; where every lane's
/// walks take as many iterations (an unlit plane filling the view: every path one segment, its
/// walk one iteration) every lane of every group counts, and the lanes' count is the segments'; where
/// walks differ (the Cornell box) groups wait for their slowest lane, and shadow rays, which only
/// some lanes trace at a time, keep fewer lanes busy than the segments' rays.
#[test]
fn lane_counts_leave_the_render_alone_and_see_idle_lanes() {
    let gpu = Gpu::new();
    let subgroup = gpu.info().subgroup_size;
    let size = (16, 16);

    let unlit = Material { unlit: true, ..Material::default() };
    let plane = scene_of(&[(&floor_quad(100.0), unlit, false)], looking_down(1.0, 1.0));
    let stats = render_into(&gpu, &plane, &PathTarget::new(&gpu, size).unwrap().with_lane_counts(), 4);
    assert_eq!(stats.segments(), 16 * 16 * 4, "every path ends on the unlit plane");
    assert_eq!(stats.walk_counts()[0], stats.segments(), "one walk-loop iteration per segment");
    assert_eq!(stats.busy_lanes(false, subgroup), Some(1.0), "{stats:?}");
    assert_eq!(stats.busy_lanes(true, subgroup), None, "no light: no shadow rays");
    // 14 columns: a subgroup is a 4 × 2 block of a workgroup's 8 × 8 pixels (pixel.glsl), so the
    // blocks over columns 12..16 have 2 of their 4 columns in the image and the others idle:
    // 24 full blocks and 8 half ones, 224 of 256 lanes busy.
    if subgroup == 8 {
        let narrow = PathTarget::new(&gpu, (14, 16)).unwrap().with_lane_counts();
        let stats = render_into(&gpu, &plane, &narrow, 4);
        assert_eq!(stats.busy_lanes(false, subgroup), Some(224.0 / 256.0), "{stats:?}");
    }

    let cornell = Scene::cornell_box();
    let plain = PathTarget::new(&gpu, size).unwrap();
    let counting = PathTarget::new(&gpu, size).unwrap().with_lane_counts();
    let without = render_into(&gpu, &cornell, &plain, 4);
    let with = render_into(&gpu, &cornell, &counting, 4);
    assert_eq!(without.walk_counts(), [0; 4], "a plain target counts nothing");
    assert_eq!(with.segments(), without.segments());
    for (a, b) in [
        (&plain.accum, &counting.accum),
        (&plain.moment, &counting.moment),
        (&plain.albedo, &counting.albedo),
    ] {
        let (a, b) = (a.read::<[f32; 4]>(&gpu).unwrap(), b.read::<[f32; 4]>(&gpu).unwrap());
        assert!(
            a.iter().zip(&b).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits)),
            "the counts changed the render"
        );
    }
    let closest = with.busy_lanes(false, subgroup).unwrap();
    let any = with.busy_lanes(true, subgroup).expect("the ceiling light's shadow rays");
    assert!(with.walk_counts()[0] >= with.segments(), "{with:?}");
    assert!(closest > 0.2 && closest < 0.95, "closest-hit walks: {closest}");
    assert!(any > 0.0 && any < closest, "any-hit walks: {any} against {closest}");
}
