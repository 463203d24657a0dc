//! Environment maps: importance sampling with MIS, and one light sample shared by the map and
//! the emitters.

use crate::common::Gpu;
use crate::{camera, scene_of, sphere_cosines};
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::procedural::{icosphere, Mesh};
use umbra::render::{path_trace, PathImage, PathSettings};
use umbra::scene::{Camera, Material, Scene};

fn lambert_sphere_scene(albedo: f32) -> (Scene, Camera) {
    let sphere = icosphere(4, Vec3::ZERO, 1.0);
    let material = Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [albedo, albedo, albedo, 1.0],
        ..Default::default()
    };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 35.0);
    (scene_of(&[(&sphere, material, false)], cam), cam)
}

/// The furnace again, now through a constant environment MAP with importance sampling and MIS:
/// the two strategies' weights must still sum to one, so the sphere stays exactly 1 on average.
#[test]
fn white_furnace_through_an_importance_sampled_environment_map() {
    let gpu = Gpu::new();
    let (scene, cam) = lambert_sphere_scene(1.0);
    let map = umbra::environment::EnvironmentMap::from_texels("constant", 8, 4, vec![[1.0; 3]; 32]).unwrap();
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let settings =
        PathSettings { size: (40, 40), spp: 64, env: [1.0; 3], max_bounces: 4, ..Default::default() };
    let image = path_trace(&gpu, &device_scene, &cam, &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0);
    let cosines = sphere_cosines(&cam, settings.size);
    let on_sphere: Vec<f32> = image
        .mean
        .iter()
        .zip(&cosines)
        .filter(|(_, c)| c.is_some_and(|c| c > 0.3))
        .map(|(p, _)| p[1])
        .collect();
    let mean = on_sphere.iter().sum::<f32>() / on_sphere.len() as f32;
    eprintln!("furnace through the map: {} pixels, mean {mean}", on_sphere.len());
    assert!(on_sphere.len() > 500);
    assert!((mean - 1.0).abs() < 0.005, "mean {mean}");
}

/// A real HDR with a sun above 30,000: environment NEE with MIS and BSDF sampling alone are
/// both unbiased, so a grey Lambert sphere must come out the same either way (z-test on the
/// image mean, significance 0.001).
#[test]
fn environment_sampling_agrees_with_bsdf_sampling_on_a_real_hdr() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(std::path::Path::new(path)).unwrap();
    let peak = map.texels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    assert!(peak > 1000.0, "the test map should have a sun; peak {peak}");
    let gpu = Gpu::new();
    let (scene, cam) = lambert_sphere_scene(0.5);
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let run = |env_nee: bool, spp: u32| {
        let settings = PathSettings {
            size: (24, 24),
            spp,
            env: [1.0; 3],
            env_nee,
            max_bounces: 3,
            seed: 3,
            ..Default::default()
        };
        path_trace(&gpu, &device_scene, &cam, &settings, |_, _| {}).unwrap()
    };
    let (nee, bsdf) = (run(true, 64), run(false, 1024));
    let summary = |image: &PathImage| {
        let var = image.variance_of_mean();
        let n = image.mean.len() as f64;
        let mean = image.mean.iter().map(|p| p[1] as f64).sum::<f64>() / n;
        let var_of_mean = var.iter().map(|v| v[1] as f64).sum::<f64>() / (n * n);
        (mean, var_of_mean)
    };
    let ((m1, v1), (m2, v2)) = (summary(&nee), summary(&bsdf));
    let z = (m1 - m2) / (v1 + v2).sqrt();
    eprintln!("image mean: NEE+MIS {m1:.4} (var {v1:.2e}), BSDF only {m2:.4} (var {v2:.2e}), z {z:.2}");
    assert!(z.abs() < 3.29, "the strategies disagree: z = {z}");
}

/// One light sample per scattering event serves the environment map and the emissive triangles
/// (picked with probability `env_pick`, by their power): a Lambert sphere under the sunny sky with
/// a glowing panel beside it, where the pick is strictly between the two. MIS, light sampling
/// alone and BSDF sampling alone agree (z-tests of the image means, Šidák over the two
/// comparisons at family α = 0.001). Seen to fail when the map's light samples leave the pick's
/// probability out of their pdf (z = −3.85); the same omission in the MIS weights (of rays that
/// escape to the map or hit an emitter) biases less than this test's noise (|z| ≤ 0.62).
#[test]
fn one_light_sample_serves_the_environment_and_the_emitters() {
    use umbra::passes::pathtrace::{PathTracePass, Strategy};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(std::path::Path::new(path)).unwrap();
    let gpu = Gpu::new();
    let sphere = icosphere(3, Vec3::ZERO, 1.0);
    let lambert = Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [0.7, 0.7, 0.7, 1.0],
        ..Default::default()
    };
    let panel = Mesh {
        positions: vec![
            Vec3::new(1.8, -0.6, -0.6),
            Vec3::new(1.8, -0.6, 0.6),
            Vec3::new(1.8, 0.6, 0.6),
            Vec3::new(1.8, 0.6, -0.6),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let glow =
        Material { base_color_factor: [0.0, 0.0, 0.0, 1.0], emissive: [30.0; 3], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO, 45.0);
    let scene = scene_of(&[(&sphere, lambert, false), (&panel, glow, false)], cam);
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let settings = |strategy: Strategy, spp: u32| PathSettings {
        size: (24, 24),
        spp,
        env: [1.0; 3],
        max_bounces: 3,
        seed: 5,
        strategy,
        ..Default::default()
    };
    let pick = PathTracePass::env_pick(&device_scene, &settings(Strategy::Mis, 1));
    eprintln!(
        "env_pick {pick} (map {}, emitters {})",
        device_scene.env_luminance, device_scene.emissive_power
    );
    assert!(pick > 0.1 && pick < 0.9, "the test wants both kinds of light sampled: env_pick {pick}");
    let without_map = PathSettings { env_nee: false, ..settings(Strategy::Mis, 1) };
    assert_eq!(PathTracePass::env_pick(&device_scene, &without_map), 0.0, "no map sampling, no pick of it");
    let summary = |strategy: Strategy, spp: u32| {
        let image = path_trace(&gpu, &device_scene, &cam, &settings(strategy, spp), |_, _| {}).unwrap();
        assert_eq!(image.nonfinite_samples, 0);
        let n = image.mean.len() as f64;
        let mean = image.mean.iter().map(|p| p[1] as f64).sum::<f64>() / n;
        let var = image.variance_of_mean().iter().map(|v| v[1] as f64).sum::<f64>() / (n * n);
        (mean, var)
    };
    let (mis, mis_var) = summary(Strategy::Mis, 256);
    for (strategy, spp) in [(Strategy::Light, 256), (Strategy::Bsdf, 2048)] {
        let (m, v) = summary(strategy, spp);
        let z = (m - mis) / (v + mis_var).sqrt();
        eprintln!("{strategy:?}: {m:.5} against MIS {mis:.5}: z = {z:.2}");
        assert!(z.abs() < 3.48, "{strategy:?} disagrees with MIS: z = {z:.2}");
    }
}
