//! Irradiance probes: the hybrid's indirect diffuse light against the path tracer, a closed box
//! against its closed form, and the failure modes (light leaking through a thin wall, a probe
//! inside a wall).

mod common;

use common::Gpu;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::probes::{ProbeSettings, ProbeVolume};
use umbra::render::{HybridSettings, Passes, PathSettings};
use umbra::scene::Scene;

/// Relative MSE of `image` against `reference`: mean over pixels and channels of
/// (x − r)² / (r² + 0.01).
fn relative_mse(image: &[[f32; 4]], reference: &[[f32; 4]]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .flat_map(|(a, r)| {
            (0..3).map(move |c| (a[c] as f64 - r[c] as f64).powi(2) / ((r[c] as f64).powi(2) + 0.01))
        })
        .sum();
    sum / (3 * image.len()) as f64
}

#[test]
fn cornell_probes_cut_the_hybrid_error() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let camera = scene.camera(None).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let size = (64, 64);
    let lighting = LightingSettings { shadow_rays: 16, ..Default::default() };
    let settings = HybridSettings { size, lighting, ..Default::default() };
    let t = std::time::Instant::now();
    let reference = passes
        .path_trace(&gpu_scene, &camera, &PathSettings { size, spp: 512, ..Default::default() }, |_, _| {})
        .unwrap();
    eprintln!("reference {:?}", t.elapsed());
    let plain = passes.hybrid(&gpu_scene, &camera, &settings).unwrap();
    let mut volume = ProbeVolume::new(&gpu, &gpu_scene, &ProbeSettings::default()).unwrap();
    let t = std::time::Instant::now();
    let bake_ms = passes.bake_probes(&gpu_scene, &mut volume, &settings.lighting, |_, _| {}).unwrap();
    eprintln!("bake {:?} gpu {bake_ms:.0} ms, grid {:?}", t.elapsed(), volume.grid);
    let probed = passes.hybrid_with_probes(&gpu_scene, &camera, &settings, Some(&volume)).unwrap();
    let e_plain = relative_mse(&plain.color, &reference.mean);
    let e_probes = relative_mse(&probed.color, &reference.mean);
    let noise = reference.relative_error().powi(2);
    eprintln!("relMSE plain {e_plain:.4} probes {e_probes:.4} reference noise {noise:.5}");
    let active = volume.read_active(&gpu).unwrap();
    eprintln!("active {} of {}", active.iter().filter(|a| **a).count(), active.len());
    let mean =
        |img: &[[f32; 4]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / img.len() as f64;
    eprintln!(
        "means: ref {:.4} plain {:.4} probes {:.4}",
        mean(&reference.mean),
        mean(&plain.color),
        mean(&probed.color)
    );
    assert!(e_probes * 5.0 < e_plain);
}
