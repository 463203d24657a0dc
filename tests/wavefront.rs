//! The wavefront path tracer traces the megakernel's samples: the same paths from the same
//! random numbers, so the same image up to float rounding, the same path segments, on every kind
//! of scene (emitters, punctual lights picked by power, an environment map, glass, textures), in
//! waves of whole images or of rows, and progressively; and with the denoiser's lobe split, the
//! same split.

mod common;
#[path = "support/generate.rs"]
mod generate;

use common::Gpu;
use glam::{Mat4, Vec3};
use std::path::Path;
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{Integrator, PathTarget};
use umbra::render::{Passes, PathImage, PathSettings};
use umbra::scene::{implicit, LightKind, Scene};

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Renders `scene` with both integrators.
fn both(
    ctx: &Gpu,
    scene: &GpuScene,
    camera: &umbra::scene::Camera,
    settings: &PathSettings,
) -> [PathImage; 2] {
    let passes = Passes::new(ctx, scene);
    Integrator::ALL.map(|integrator| {
        passes
            .path_trace(scene, camera, &PathSettings { integrator, ..settings.clone() }, |_, _| {})
            .unwrap_or_else(|e| panic!("{}: {e}", integrator.name()))
    })
}

/// How two renders of the same samples differ: the largest difference of a pixel's mean, of
/// its second moment and of its AOVs, relative to the pixel's value (or 1 where it is below 1).
/// With the lobe split in both, its buffers too (else neither may have it).
fn largest_difference(a: &PathImage, b: &PathImage) -> f32 {
    let mut worst = 0.0f32;
    let mut buffers =
        vec![(&a.mean, &b.mean), (&a.moment, &b.moment), (&a.albedo, &b.albedo), (&a.emission, &b.emission)];
    match (&a.lobe_split, &b.lobe_split) {
        (Some(p), Some(q)) => buffers.extend([(&p.specular, &q.specular), (&p.split, &q.split)]),
        (None, None) => {}
        _ => panic!("one render has the lobe split, the other not"),
    }
    for (x, y) in buffers {
        assert_eq!(x.len(), y.len());
        for (p, q) in x.iter().zip(y) {
            for c in 0..4 {
                worst = worst.max((p[c] - q[c]).abs() / p[c].abs().max(1.0));
            }
        }
    }
    for (p, q) in a.normal_depth.iter().zip(&b.normal_depth) {
        for c in 0..4 {
            if p[c].is_finite() || q[c].is_finite() {
                worst = worst.max((p[c] - q[c]).abs() / p[c].abs().max(1.0));
            }
        }
    }
    worst
}

/// The tolerance of "the same samples": both integrators run path.glsl's one path_shade on the
/// same numbers, so only the compiler's rounding in two kernels may differ (a difference that
/// flipped one Russian-roulette or lobe choice would move a pixel's mean by far more). On
/// lavapipe the images are bit-identical (measured: a largest difference of 0 in every test
/// here); a GPU's compiler may contract differently in the two kernels.
const SAME_SAMPLES: f32 = 1e-5;

fn check_same(name: &str, images: &[PathImage; 2]) {
    let [mega, wave] = images;
    assert_eq!(mega.nonfinite_samples, 0, "{name}");
    assert_eq!(wave.nonfinite_samples, 0, "{name}");
    assert_eq!(mega.segments, wave.segments, "{name}: path segments differ");
    assert!(mega.segments > 0, "{name}");
    let worst = largest_difference(mega, wave);
    assert!(worst <= SAME_SAMPLES, "{name}: the integrators' images differ by up to {worst} (relative)");
}

/// The Cornell box seen by an orthographic camera in place of its own (the same place and
/// direction; 0.3 × 0.3 half extents).
fn orthographic_cornell() -> Scene {
    let mut scene = Scene::cornell_box();
    let magnification = umbra::scene::Orthographic { xmag: 0.3, ymag: 0.3, zfar: 10.0 };
    let camera = umbra::scene::Camera { orthographic: Some(magnification), ..scene.cameras[0] };
    scene.cameras = vec![camera];
    scene
}

#[test]
fn the_wavefront_traces_the_megakernels_samples_on_every_kind_of_scene() {
    let ctx = Gpu::new();
    let settings =
        PathSettings { size: (40, 32), spp: 5, max_bounces: 6, seed: 3, ..PathSettings::default() };
    // The Cornell box (emissive triangles), textures, the floor made anisotropic
    // (KHR_materials_anisotropy), glass (transmission, volumes), a sphere grid, and 480 emitters
    // with 136 punctual lights (sixteen picked by power per point).
    let mut anisotropic = load("textured.glb");
    let floor = &mut anisotropic.materials[0];
    (floor.roughness, floor.anisotropy_strength, floor.anisotropy_rotation) = (0.3, 0.8, 0.5);
    anisotropic.tangents = anisotropic
        .normals
        .iter()
        .map(|n| Vec3::from(*n).any_orthonormal_vector().extend(1.0).to_array())
        .collect();
    // glass.glb's volumes made dispersive (KHR_materials_dispersion): each path's colour channel
    // travels in the wavefront's path state.
    let mut dispersive = load("glass.glb");
    for m in dispersive.materials.iter_mut().filter(|m| m.volume) {
        m.dispersion = 1.0;
    }
    assert!(dispersive.materials.iter().any(|m| m.disperses()), "glass.glb has a transmitting volume");
    for (name, scene, env) in [
        ("cornell box", Scene::cornell_box(), [0.0; 3]),
        ("glass.glb, dispersive", dispersive, [0.5; 3]),
        ("textured.glb", load("textured.glb"), [0.4, 0.5, 0.6]),
        ("textured.glb, anisotropic floor", anisotropic, [0.4, 0.5, 0.6]),
        ("glass.glb", load("glass.glb"), [0.5; 3]),
        ("spheres.glb", load("spheres.glb"), [0.5; 3]),
        ("many-lights.glb", load("many-lights.glb"), [0.0; 3]),
        ("cornell box, orthographic camera", orthographic_cornell(), [0.0; 3]),
    ] {
        let gpu_scene = GpuScene::upload(&ctx, &scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let images = both(&ctx, &gpu_scene, &camera, &PathSettings { env, ..settings.clone() });
        check_same(name, &images);
    }
}

#[test]
fn the_wavefront_samples_an_environment_map_and_emitters_as_the_megakernel() {
    let ctx = Gpu::new();
    let scene = Scene::cornell_box();
    let mut gpu_scene = GpuScene::upload(&ctx, &scene).unwrap();
    // A map with a bright spot, so importance sampling and the map/triangle pick both matter.
    let (w, h) = (16usize, 8usize);
    let texels = (0..w * h).map(|i| if i % 37 == 5 { [40.0, 30.0, 20.0] } else { [0.3, 0.4, 0.5] }).collect();
    gpu_scene.set_environment(&ctx, &EnvironmentMap::from_texels("spot", w, h, texels).unwrap()).unwrap();
    let camera = scene.camera(None).unwrap();
    let settings = PathSettings { size: (32, 32), spp: 4, seed: 9, env: [1.0; 3], ..PathSettings::default() };
    check_same("cornell box under a map", &both(&ctx, &gpu_scene, &camera, &settings));
}

/// Waves of a few rows and one sample (a host bounding the state's memory) trace the same
/// samples as whole-image waves of many; and renders that continue a target (first > 0) add to
/// its running mean as the megakernel's do.
#[test]
fn waves_of_rows_and_progressive_batches_trace_the_same_samples() {
    let ctx = Gpu::new();
    let scene = load("spheres.glb");
    let gpu_scene = GpuScene::upload(&ctx, &scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let settings = PathSettings {
        size: (24, 20),
        spp: 6,
        seed: 5,
        env: [0.5; 3],
        integrator: Integrator::Wavefront,
        ..PathSettings::default()
    };
    let passes = Passes::new(&ctx, &gpu_scene);
    let whole = passes.path_trace(&gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let mega = passes
        .path_trace(
            &gpu_scene,
            &camera,
            &PathSettings { integrator: Integrator::Megakernel, ..settings.clone() },
            |_, _| {},
        )
        .unwrap();
    check_same("spheres.glb", &[mega, whole.clone()]);

    // 7 rows of 24 pixels a wave (168 paths: 3 waves of rows per sample, the last of 6 rows),
    // recorded in batches of 1, 2 and 3 samples.
    let target = PathTarget::new(&ctx, settings.size).unwrap();
    target.init_wave(&ctx, &gpu_scene, settings.max_bounces, 7 * 24).unwrap();
    assert!(target.init_wave(&ctx, &gpu_scene, settings.max_bounces, 7 * 24).is_err(), "a second state");
    let too_deep = PathSettings { max_bounces: 1001, ..settings.clone() };
    let error = too_deep.validate().expect_err("1001 bounces through the wavefront").to_string();
    assert!(error.contains("at most 1000 bounces"), "{error}");
    assert!(PathSettings { integrator: Integrator::Megakernel, ..too_deep }.validate().is_ok());
    // The same with the lobe split: a split target's state holds the split's fields and shadow
    // texels too (fewer paths a wave in the same memory).
    let split = PathSettings { lobe_split: true, ..settings.clone() };
    let whole_split = passes.path_trace(&gpu_scene, &camera, &split, |_, _| {}).unwrap();
    let split_target = PathTarget::with_lobe_split(&ctx, settings.size).unwrap();
    split_target.init_wave(&ctx, &gpu_scene, settings.max_bounces, 7 * 24).unwrap();
    let mut first = 0;
    for count in [1, 2, 3] {
        ctx.record(|rec| {
            passes.record_path_samples(rec, &gpu_scene, &camera, &target, &settings, first..first + count)?;
            passes.record_path_samples(rec, &gpu_scene, &camera, &split_target, &split, first..first + count)
        })
        .unwrap();
        first += count;
    }
    let lobes = split_target.lobe_split.as_ref().unwrap();
    let whole_lobes = whole_split.lobe_split.as_ref().unwrap();
    for (name, whole, rows) in [
        ("mean", &whole.mean, target.accum.read(&ctx).unwrap()),
        ("split mean", &whole_split.mean, split_target.accum.read(&ctx).unwrap()),
        ("specular", &whole_lobes.specular, lobes.specular.read(&ctx).unwrap()),
        ("split", &whole_lobes.split, lobes.split.read(&ctx).unwrap()),
    ] {
        let rows: Vec<[f32; 4]> = rows;
        let mut worst = 0.0f32;
        for (p, q) in whole.iter().zip(&rows) {
            if name.ends_with("mean") {
                assert_eq!(p[3], q[3], "{name}: sample counts");
            }
            for c in 0..3 {
                worst = worst.max((p[c] - q[c]).abs() / p[c].abs().max(1.0));
            }
        }
        // The running mean's arithmetic differs by batch (6 samples at once against 1 + 2 + 3).
        assert!(worst <= 1e-5, "{name}: waves of rows differ from whole-image waves by up to {worst}");
    }
}

/// With the denoiser's lobe split (`PathSettings::lobe_split`) the wavefront splits each sample
/// as the megakernel does: the same mean, moment and AOVs, and the same split buffers (the
/// specular part and its divisor, the two parts' variances), on the Cornell box (emitters;
/// with every material a metal too, where the split's divisor is the base colour), glass
/// (transmission: specular paths past the first hit) and a textured scene under an environment.
#[test]
fn the_wavefront_splits_the_lobes_as_the_megakernel() {
    let ctx = Gpu::new();
    let settings = PathSettings {
        size: (40, 32),
        spp: 5,
        max_bounces: 6,
        seed: 7,
        lobe_split: true,
        ..PathSettings::default()
    };
    let mut metal = Scene::cornell_box();
    for (i, m) in metal.materials.iter_mut().enumerate() {
        (m.metallic, m.roughness) = (1.0, 0.2 + 0.1 * i as f32);
    }
    for (name, scene, env) in [
        ("cornell box", Scene::cornell_box(), [0.0; 3]),
        ("cornell box, metals", metal, [0.0; 3]),
        ("glass.glb", load("glass.glb"), [0.5; 3]),
        ("textured.glb", load("textured.glb"), [0.4, 0.5, 0.6]),
    ] {
        let gpu_scene = GpuScene::upload(&ctx, &scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let images = both(&ctx, &gpu_scene, &camera, &PathSettings { env, ..settings.clone() });
        check_same(name, &images);
        // The split is there to compare: the specular part carries light.
        let split = images[1].lobe_split.as_ref().expect("the wavefront's split");
        let specular: f64 = split.specular.iter().map(|s| (s[0] + s[1] + s[2]) as f64).sum();
        let total: f64 = images[1].mean.iter().map(|m| (m[0] + m[1] + m[2]) as f64).sum();
        eprintln!("{name}: specular part {:.4} of the light", specular / total);
        assert!(specular > 0.001 * total, "{name}: no specular part ({specular} of {total})");
    }
}

/// `umbra render --integrator wavefront` renders the embedded Cornell box as the default
/// megakernel does (under the validation layer, as `common::run_validated`): the same PNG, to
/// within one 8-bit step.
#[test]
fn the_command_line_renders_with_either_integrator() {
    let dir = std::env::temp_dir().join(format!("umbra-wavefront-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let render = |integrator: &str| {
        let png = dir.join(format!("{integrator}.png"));
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
            .args(["render", "--size", "24x20", "--spp", "3", "--integrator", integrator, "-o"])
            .arg(&png)
            .env("UMBRA_VALIDATION", "1")
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && !stderr.contains("ERROR"), "{stderr}");
        // The summary names the integrator that traced the samples.
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains(&format!("segments per sample, {integrator})")), "{stdout}");
        image::open(&png).unwrap().to_rgb8()
    };
    let (mega, wave) = (render("megakernel"), render("wavefront"));
    assert_eq!(mega.dimensions(), (24, 20));
    let worst = mega.as_raw().iter().zip(wave.as_raw()).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
    assert!(worst <= 1, "the integrators' PNGs differ by up to {worst} steps");
    std::fs::remove_dir_all(&dir).ok();
}

/// Kernels specialised for implicit shapes (marched in the traversal, the marches cut short
/// counted) and for parallax occlusion mapping (whose module-level state path_shade sets at a
/// hit and reads for every light sample and the next ray: within one shade invocation in the
/// wavefront) trace the same samples through both integrators.
#[test]
fn implicit_shapes_and_parallax_materials_trace_the_same_samples() {
    let ctx = Gpu::new();
    let settings =
        PathSettings { size: (32, 24), spp: 3, seed: 11, env: [0.6; 3], ..PathSettings::default() };

    // A square with ridges of a height map 0.15 m deep, seen at a slant under a low sun.
    let heights: Vec<u8> = (0..16 * 16).map(|i| if (i % 16) / 4 % 2 == 0 { 255 } else { 0 }).collect();
    let parallax =
        serde_json::json!({ "heightTexture": { "index": 0 }, "scale": 0.15, "layers": 16, "refinement": 4 });
    let glb = generate::parallax_square(1.0, 16, 16, &heights, true, Some(parallax));
    let mut square = Scene::from_glb_bytes("parallax.glb", &glb).unwrap();
    square.cameras = vec![common::camera(Vec3::new(0.0, -1.6, 1.4), Vec3::ZERO)];
    square.lights.push(common::light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.3, 0.6, -0.5), 3.0));

    // An implicit sphere minus a box over a floor, lit by a point light.
    let floor = common::quad(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), Vec3::new(2.0, 0.0, 0.0));
    let bulb = common::light(LightKind::Point, Vec3::new(1.0, 2.0, 1.0), Vec3::NEG_Y, 8.0);
    let mut shape =
        common::build("cut ball", &[floor], vec![bulb], common::camera(Vec3::new(0.0, 1.2, 2.2), Vec3::ZERO));
    let text = r#"{"subtraction": [{"sphere": {"radius": 0.5}}, {"box": {"halfExtents": [0.6, 0.2, 0.6]}}], "material": 0}"#;
    let value: serde_json::Value = serde_json::from_str(text).unwrap();
    let centre = Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0));
    shape.implicits.push(implicit::from_json("cut ball", &value, centre, shape.materials.len()).unwrap());

    for (name, scene) in [("parallax square", square), ("implicit shape over a floor", shape)] {
        let gpu_scene = GpuScene::upload(&ctx, &scene).unwrap();
        assert!(gpu_scene.has_parallax || gpu_scene.has_implicit, "{name}: the feature under test");
        let camera = scene.camera(None).unwrap();
        let images = both(&ctx, &gpu_scene, &camera, &settings);
        check_same(name, &images);
        assert_eq!(images[0].marches_exhausted, images[1].marches_exhausted, "{name}");
    }
}
