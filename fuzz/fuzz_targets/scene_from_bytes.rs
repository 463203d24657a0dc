//! Loading a scene from arbitrary bytes (GLB or glTF JSON) returns a scene or an error, never
//! panics, hangs or exhausts memory; a loaded scene's indices are in range and its triangle
//! arrays agree.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    if let Ok(scene) = umbra::scene::Scene::from_glb_bytes("fuzz.glb", bytes) {
        assert_eq!(scene.triangles.len(), scene.triangle_material.len());
        let vertices = scene.positions.len() as u32;
        assert!(scene.triangles.iter().flatten().all(|&i| i < vertices));
        let materials = scene.materials.len().max(1) as u32;
        assert!(scene.triangle_material.iter().all(|&m| m < materials));
    }
});
