//! Reliability (issue 8): bad input that the other suites do not cover (environment maps with
//! NaN/Inf/negative texels, scenes over the device's buffer limits, absurd output sizes), faults
//! that name the pass, determinism of the hybrid mode, and a long run that loses nothing.

mod common;

use common::Gpu;
use std::sync::Mutex;
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::{GpuScene, SceneArrays};

use umbra::render::{path_trace, PathSettings};
use umbra::scene::{Material, Sampler, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

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

fn warnings_naming(name: &str) -> Vec<String> {
    static LOGGER: Capture = Capture;
    let _ = log::set_logger(&LOGGER).map(|()| log::set_max_level(log::LevelFilter::Warn));
    WARNINGS.lock().unwrap().iter().filter(|w| w.contains(name)).cloned().collect()
}

/// NaN, ±Inf and negative texels become 0 with one warning that counts them; the other texels
/// and the sampling tables are untouched by them (finite, a valid CDF).
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
    assert!(table
        .pdf_uv
        .iter()
        .chain(&table.marginal_cdf)
        .chain(&table.conditional_cdf)
        .all(|v| v.is_finite()));
    assert_eq!(table.marginal_cdf.last(), Some(&1.0));
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

fn assert_too_large(result: umbra::Result<impl Sized>, name: &str, buffer: &str, limit: u64) {
    match result {
        Err(e @ Error::Scene { .. }) => {
            let message = e.to_string();
            eprintln!("{message}");
            assert!(message.starts_with(name), "{message}");
            assert!(message.contains(buffer), "{message}");
            assert!(message.contains(&format!("at most {limit} bytes")), "{message}");
            assert!(message.contains("maxStorageBufferRange"), "{message}");
        }
        Err(e) => panic!("expected a scene error naming {name}, got: {e}"),
        Ok(_) => panic!("{name} fits under {limit} bytes"),
    }
}

/// The size check against a lowered `maxStorageBufferRange` (the hook: a [`DeviceInfo`] of our
/// own): the largest buffer fits at its exact size and is refused one byte below.
#[test]
fn scene_buffer_sizes_are_checked_against_the_device_limit() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let arrays = SceneArrays::new(&scene).unwrap();
    let sizes = arrays.buffer_sizes();
    let (largest, bytes) = sizes.iter().copied().max_by_key(|s| s.1).unwrap();
    let triangles = sizes.iter().find(|s| s.0 == "scene triangles").unwrap().1;
    assert_eq!(triangles, std::mem::size_of_val(arrays.triangles.as_slice()) as u64);
    let vertices = sizes.iter().find(|s| s.0 == "scene vertices").unwrap().1;
    assert_eq!(vertices, std::mem::size_of_val(arrays.vertices.as_slice()) as u64);
    let mut info = gpu.info().clone();
    info.max_storage_buffer_range = bytes;
    arrays.check_limits(&scene.name, &info).unwrap();
    info.max_storage_buffer_range = bytes - 1;
    assert_too_large(arrays.check_limits(&scene.name, &info), &scene.name, largest, bytes - 1);
    // Each buffer is checked, not just the largest.
    for (buffer, size) in sizes.into_iter().filter(|s| s.1 > 0) {
        info.max_storage_buffer_range = size - 1;
        let message = arrays.check_limits(&scene.name, &info).unwrap_err().to_string();
        assert!(sizes.iter().any(|(b, s)| message.contains(b) && *s >= size), "{buffer}: {message}");
    }
}

/// Just over the real device's limit, through the real upload: a scene whose one texture needs a
/// row more than `maxStorageBufferRange` holds, and an environment map likewise. One clear error
/// each, before anything is allocated, and no validation message.
#[test]
fn scenes_over_the_device_buffer_limit_are_one_clear_error() {
    let gpu = Gpu::new();
    let limit = gpu.info().max_storage_buffer_range;
    if limit > 512 << 20 {
        eprintln!("skipped: the device binds {limit} bytes per buffer; too much to allocate in a test");
        return;
    }
    let width = 4096u32;
    let height = (limit / (width as u64 * 4) + 1) as u32;
    let mut scene = Scene::cornell_box();
    scene.name = "huge-texture.glb".into();
    scene.textures.push(Texture {
        name: "huge".into(),
        width,
        height,
        rgba8: vec![128; width as usize * height as usize * 4],
        srgb: true,
        sampler: Sampler::default(),
    });
    scene.materials[0].base_color_texture =
        Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 });
    assert_too_large(GpuScene::upload(&gpu, &scene), "huge-texture.glb", "scene texels", limit);
    drop(scene);

    let mut device_scene = GpuScene::upload(&gpu, &Scene::cornell_box()).unwrap();
    let (w, h) = (4096, (limit / (4096 * 16) + 1) as usize);
    let map = EnvironmentMap::from_texels("huge-sky.exr", w, h, vec![[0.5; 3]; w * h]).unwrap();
    assert_too_large(device_scene.set_environment(&gpu, &map), "huge-sky.exr", "environment texels", limit);
    let _ = Material::default();
}
