//! The glTF occlusion map (`occlusionTexture`): the hybrid renderer scales its image-based
//! (ambient) light by 1 + strength (r − 1) and leaves direct light alone; the path tracer ignores
//! the map. The scene (`generate::occlusion_square`) is a rough white square filling the view,
//! its occlusion map black (r = 0) on the left half and white (r = 1) on the right; each render is
//! compared with the same scene without the map, pixel by pixel, away from the seam.

mod common;
#[path = "support/generate.rs"]
mod generate;

use common::Gpu;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridImage, HybridSettings, PathSettings};
use umbra::scene::Scene;

const SIZE: (u32, u32) = (64, 64);

fn scene(occlusion: Option<f64>, sun: bool) -> Scene {
    Scene::from_glb_bytes("occlusion-square.glb", &generate::occlusion_square(occlusion, sun))
        .expect("scene loads")
}

/// The hybrid render of `scene` in a constant environment `env` (split-sum IBL on, no SSAO).
fn render(gpu: &Gpu, scene: &Scene, env: [f32; 3]) -> HybridImage {
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let settings = HybridSettings {
        size: SIZE,
        lighting: LightingSettings { env, ..Default::default() },
        ..Default::default()
    };
    hybrid(gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings).unwrap()
}

/// Pixel indices of the square's left (black occlusion) and right (white) halves, four pixels
/// clear of the seam and the border.
fn halves() -> [Vec<usize>; 2] {
    let (w, h) = SIZE;
    let pixels = |xs: std::ops::Range<u32>| {
        (4..h - 4).flat_map(move |y| xs.clone().map(move |x| (y * w + x) as usize)).collect::<Vec<_>>()
    };
    [pixels(4..w / 2 - 4), pixels(w / 2 + 4..w - 4)]
}

/// Checks, per pixel and channel, that `without` is lit (> 0.02) and `with / without` is within
/// `tol` of `factor`.
fn check_ratio(
    with: &HybridImage,
    without: &HybridImage,
    pixels: &[usize],
    factor: f32,
    tol: f32,
    what: &str,
) {
    let mut worst = 0.0f32;
    for &i in pixels {
        for c in 0..3 {
            let (a, b) = (with.color[i][c], without.color[i][c]);
            assert!(b > 0.02, "{what}: pixel {i} is not lit without the map ({b})");
            let off = (a / b - factor).abs();
            worst = worst.max(off);
            assert!(
                off <= tol,
                "{what}: pixel {i} channel {c}: {a} with the map, {b} without: ratio {}, expected {factor}",
                a / b
            );
        }
    }
    eprintln!("{what}: ratio within {worst:.2e} of {factor}");
}

/// The G-buffer's occlusion (emission alpha) over `pixels` is `expected`.
fn check_gbuffer(image: &HybridImage, pixels: &[usize], expected: f32, what: &str) {
    for &i in pixels {
        let a = image.gbuffer.emission[i][3];
        assert!(
            (a - expected).abs() < 1e-3,
            "{what}: G-buffer occlusion {a} at pixel {i}, expected {expected}"
        );
    }
}

/// Lit only by a constant environment (IBL), strength 1: the black half loses all its light
/// (1 + 1 (0 − 1) = 0), the white half keeps exactly what it has without the map. Fails if the
/// map never reaches the G-buffer or the lighting, or darkens where it is white.
#[test]
fn occlusion_map_scales_image_based_light() {
    let gpu = Gpu::new();
    let env = [1.0; 3];
    let without = render(&gpu, &scene(None, false), env);
    let with = render(&gpu, &scene(Some(1.0), false), env);
    let [left, right] = halves();
    check_gbuffer(&without, &left, 1.0, "no map");
    check_gbuffer(&with, &left, 0.0, "black half");
    check_gbuffer(&with, &right, 1.0, "white half");
    check_ratio(&with, &without, &left, 0.0, 1e-4, "IBL, strength 1, black half");
    check_ratio(&with, &without, &right, 1.0, 1e-4, "IBL, strength 1, white half");
}

/// Strength 0.5 halves the black half's image-based light (1 + 0.5 (0 − 1)) and leaves the
/// white half alone. Fails if the strength is ignored or applied other than as glTF specifies.
#[test]
fn occlusion_strength_interpolates_to_unoccluded() {
    let gpu = Gpu::new();
    let env = [1.0; 3];
    let without = render(&gpu, &scene(None, false), env);
    let with = render(&gpu, &scene(Some(0.5), false), env);
    let [left, right] = halves();
    check_gbuffer(&with, &left, 0.5, "black half, strength 0.5");
    check_ratio(&with, &without, &left, 0.5, 1e-3, "IBL, strength 0.5, black half");
    check_ratio(&with, &without, &right, 1.0, 1e-4, "IBL, strength 0.5, white half");
}

/// Lit only by a directional light (the environment black, so IBL adds nothing): the map
/// changes nothing, on either half. Fails if the occlusion scales direct light.
#[test]
fn occlusion_map_leaves_direct_light_alone() {
    let gpu = Gpu::new();
    let env = [0.0; 3];
    let without = render(&gpu, &scene(None, true), env);
    let with = render(&gpu, &scene(Some(1.0), true), env);
    let [left, right] = halves();
    check_gbuffer(&with, &left, 0.0, "black half");
    check_ratio(&with, &without, &left, 1.0, 1e-4, "sun, black half");
    check_ratio(&with, &without, &right, 1.0, 1e-4, "sun, white half");
}

/// The path tracer ignores the map (it traces occlusion itself): the same samples give the same
/// image, bit for bit, with and without it.
#[test]
fn path_tracer_ignores_the_occlusion_map() {
    let gpu = Gpu::new();
    let settings = PathSettings { size: SIZE, spp: 4, seed: 11, env: [1.0; 3], ..PathSettings::default() };
    let trace = |scene: &Scene| {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        path_trace(&gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap().mean
    };
    let without = trace(&scene(None, true));
    let with = trace(&scene(Some(1.0), true));
    let [left, _] = halves();
    assert!(left.iter().all(|&i| without[i][0] > 0.02), "the square's left half should be lit");
    assert!(with == without, "the occlusion map changed the path-traced image");
}
