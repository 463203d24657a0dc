//! A textured square filling the view, rendered by both the path tracer and the hybrid renderer:
//! the harness of the material-texture tests (tests/layer_textures.rs, tests/iridescence.rs).

use super::Gpu;
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{LightKind, Material, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

/// Image size of every render.
pub const SIZE: (u32, u32) = (24, 24);

/// The two renders of [`renders`], in order.
pub const MODES: [&str; 2] = ["path tracer", "hybrid"];

/// Texture 0 through UV set 0, untransformed.
pub fn slot() -> Option<TextureRef> {
    Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 })
}

/// The square [−1, 1]² at z = 0 facing a camera 2 m away (it fills the view), its UV set 0
/// running left to right over u and top to bottom over v, its set 1 mirrored in u; a sun of
/// `sun` lux from the camera's side; `texture` as texture 0.
pub fn scene(name: &str, material: Material, texture: Option<Texture>, sun: f32) -> Scene {
    let quad = super::quad(Vec3::ZERO, Vec3::X, Vec3::Y);
    let sun = super::light(LightKind::Directional, Vec3::ZERO, Vec3::new(-0.3, -0.2, -1.0), sun);
    let camera = super::camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
    let mut scene = super::build_with(name, &[(quad, material)], vec![sun], camera);
    scene.uv0 = scene.positions.iter().map(|p| [p[0] * 0.5 + 0.5, 0.5 - p[1] * 0.5]).collect();
    scene.uv1 = scene.uv0.iter().map(|&[u, v]| [1.0 - u, v]).collect();
    scene.textures.extend(texture);
    scene
}

/// Linear radiance per pixel from the path tracer (4 spp, one bounce) and from the hybrid
/// renderer (split-sum IBL, no AO), under a constant sky `env`.
pub fn renders(gpu: &Gpu, scene: &Scene, env: f32) -> [Vec<[f32; 4]>; 2] {
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let path = PathSettings { size: SIZE, spp: 4, max_bounces: 1, env: [env; 3], ..Default::default() };
    let traced = path_trace(gpu, &gpu_scene, &camera, &path, |_, _| {}).unwrap();
    assert_eq!(traced.nonfinite_samples, 0, "NaN/Inf samples");
    let settings = HybridSettings {
        size: SIZE,
        lighting: LightingSettings { env: [env; 3], ..Default::default() },
        ao: None,
        ..Default::default()
    };
    let lit = hybrid(gpu, &gpu_scene, &camera, &settings).unwrap();
    [traced.mean, lit.color]
}

/// Pixels agree in every channel within 1e-4 of `b` (1e-7 absolute).
pub fn same(a: &[f32; 4], b: &[f32; 4]) -> bool {
    (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-4 * b[c].abs().max(1e-3))
}
