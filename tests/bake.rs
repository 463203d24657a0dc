//! Probe bakes on disk (`umbra::bake`): a saved bake loads back bit for bit and lights the same
//! hybrid image; a bake of another scene or environment, a truncated file and a file that is not
//! a bake are refused with errors naming the file; the scene hash a bake records.

mod common;

use common::Gpu;
use std::path::{Path, PathBuf};
use umbra::bake::{self, load_probes, save_probes, HEADER_BYTES, PROBE_BYTES};
use umbra::embed::Renderer;
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::GpuScene;
use umbra::passes::probes::{ProbeSettings, ProbeVolume};
use umbra::render::{HybridSettings, Passes};
use umbra::scene::Scene;
use umbra::Error;

/// A bake small enough for lavapipe: 3×3×3 probes over the 0.55 m Cornell box, three sweeps.
fn tiny() -> ProbeSettings {
    ProbeSettings { spacing: Some(0.2), rays: 64, bounces: 1, sweeps: 2, ..Default::default() }
}

fn temp_dir(name: &str) -> PathBuf {
    common::fresh_folder(&format!("bake-{name}"))
}

/// The error of a load that must fail (`ProbeVolume` is not `Debug`).
fn load_error(gpu: &Gpu, path: &Path, hash: u64, env: [f32; 3]) -> Error {
    match load_probes(gpu, path, hash, env) {
        Ok(_) => panic!("{} loaded", path.display()),
        Err(e) => e,
    }
}

fn bits(v: &[[f32; 4]]) -> Vec<[u32; 4]> {
    v.iter().map(|t| t.map(f32::to_bits)).collect()
}

#[test]
fn a_saved_bake_loads_bit_for_bit_and_lights_the_same_image() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let camera = scene.camera(None).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let settings = HybridSettings { size: (32, 32), ..Default::default() };
    let env = settings.lighting.env;
    let mut volume = ProbeVolume::new(&gpu, &gpu_scene, &tiny()).unwrap();
    passes.bake_probes(&gpu_scene, &mut volume, &settings.lighting, |_, _| {}).unwrap();
    assert_eq!(volume.grid.counts, [3, 3, 3]);

    let dir = temp_dir("round-trip");
    let path = dir.join("cornell.probes");
    let hash = bake::scene_hash(&scene, None);
    save_probes(&gpu, &path, &volume, hash, env).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().len() as usize,
        HEADER_BYTES + 27 * PROBE_BYTES + bake::CHECKSUM_BYTES
    );
    let loaded = load_probes(&gpu, &path, hash, env).unwrap();
    assert_eq!((loaded.grid, loaded.settings), (volume.grid, volume.settings));

    // The states and maps, read back from the GPU, bit for bit; and not vacuously (the bake lit
    // something).
    let states = volume.read_states(&gpu).unwrap();
    assert!(volume.read_active(&gpu).unwrap().iter().any(|a| *a), "no active probe: {states:?}");
    assert_eq!(loaded.read_states(&gpu).unwrap(), states);
    let irradiance = bits(&volume.read_irradiance(&gpu).unwrap());
    assert!(irradiance.iter().flatten().any(|&b| f32::from_bits(b) > 0.0), "black irradiance");
    assert_eq!(bits(&loaded.read_irradiance(&gpu).unwrap()), irradiance);
    assert_eq!(bits(&loaded.read_distance(&gpu).unwrap()), bits(&volume.read_distance(&gpu).unwrap()));

    // The same hybrid image from the baked and the loaded volume, and another one without.
    let baked = passes.hybrid_with_probes(&gpu_scene, &camera, &settings, Some(&volume)).unwrap();
    let reloaded = passes.hybrid_with_probes(&gpu_scene, &camera, &settings, Some(&loaded)).unwrap();
    let plain = passes.hybrid(&gpu_scene, &camera, &settings).unwrap();
    assert_eq!(bits(&reloaded.color), bits(&baked.color));
    assert_eq!(reloaded.display, baked.display);
    assert_ne!(bits(&plain.color), bits(&baked.color), "the probes changed nothing");

    // The embedding API loads the same file (and saves it back byte for byte).
    let renderer = Renderer::new(&gpu, &scene).unwrap();
    let hosted = renderer.load_probes(&path, hash, &settings.lighting).unwrap();
    assert_eq!(bits(&hosted.read_irradiance(&gpu).unwrap()), irradiance);
    let resaved = dir.join("resaved.probes");
    renderer.save_probes(&resaved, &hosted, hash, &settings.lighting).unwrap();
    assert_eq!(std::fs::read(&resaved).unwrap(), std::fs::read(&path).unwrap());

    // Another scene (one vertex moved) and another environment are refused, naming the file.
    let mut moved = scene.clone();
    moved.positions[0][1] += 0.01;
    let other = bake::scene_hash(&moved, None);
    let message = load_error(&gpu, &path, other, env).to_string();
    assert!(message.contains("cornell.probes"), "{message}");
    assert!(
        message.contains(&format!("baked for another scene (hash {hash:016x}), this scene is {other:016x}")),
        "{message}"
    );
    let message = load_error(&gpu, &path, hash, [1.0; 3]).to_string();
    assert!(message.contains("cornell.probes") && message.contains("environment radiance"), "{message}");

    // A truncated file, a file that is not a bake, a missing file: each named, none a panic.
    let bytes = std::fs::read(&path).unwrap();
    let truncated = dir.join("truncated.probes");
    std::fs::write(&truncated, &bytes[..bytes.len() - 1]).unwrap();
    let message = load_error(&gpu, &truncated, hash, env).to_string();
    assert!(message.contains("truncated.probes") && message.contains("truncated or corrupt:"), "{message}");
    // One flipped byte in the first probe's irradiance, and one in the scene hash: corrupt, not
    // a bake that renders, nor one "baked for another scene".
    let probes: usize = (0..3)
        .map(|i| u32::from_le_bytes(bytes[44 + 4 * i..48 + 4 * i].try_into().unwrap()) as usize)
        .product();
    let irradiance = umbra::bake::HEADER_BYTES + 16 * probes;
    for (offset, what) in [(irradiance + 5, "irradiance"), (13, "scene hash")] {
        let mut damaged = bytes.clone();
        damaged[offset] ^= 0x40;
        let path = dir.join("damaged.probes");
        std::fs::write(&path, &damaged).unwrap();
        let message = load_error(&gpu, &path, hash, env).to_string();
        assert!(
            message.starts_with(&format!("{}: corrupt: the checksum does not match", path.display())),
            "{what}: {message}"
        );
    }
    let foreign = dir.join("cornell-box.glb");
    std::fs::write(
        &foreign,
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.glb")).unwrap(),
    )
    .unwrap();
    let message = load_error(&gpu, &foreign, hash, env).to_string();
    assert!(message.contains("cornell-box.glb") && message.contains("not a probe bake"), "{message}");
    let missing = dir.join("missing.probes");
    match load_error(&gpu, &missing, hash, env) {
        Error::Io { path, .. } => assert_eq!(path, missing),
        e => panic!("not an I/O error: {e}"),
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The hash a bake records: the scene's content hash, and the environment map's with one.
#[test]
fn the_bake_hash_covers_the_environment_map() {
    let scene = Scene::cornell_box();
    assert_eq!(bake::scene_hash(&scene, None), scene.content_hash());
    let grey = EnvironmentMap::constant([0.5; 3]);
    let with_map = bake::scene_hash(&scene, Some(&grey));
    assert_ne!(with_map, scene.content_hash());
    assert_eq!(bake::scene_hash(&scene, Some(&EnvironmentMap::constant([0.5; 3]))), with_map);
    assert_ne!(bake::scene_hash(&scene, Some(&EnvironmentMap::constant([0.5, 0.5, 0.6]))), with_map);
    let renamed = EnvironmentMap { name: "elsewhere.exr".into(), ..grey.clone() };
    assert_eq!(bake::scene_hash(&scene, Some(&renamed)), with_map);
}
