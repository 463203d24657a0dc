//! `KHR_materials_unlit`: the surface shows its base colour (factor × texture × `COLOR_0`)
//! whatever the light, in the hybrid and the path tracer; in the path tracer it is an emitter of
//! that colour that scatters nothing and is not light-sampled, so an unlit enclosure lights a
//! scene exactly as a constant sky of the same radiance does; the probes' gathers see it too; and
//! only scenes with an unlit material get kernels specialised for it.

mod common;
#[path = "support/generate.rs"]
mod generate;

use common::{baked_probes, build, build_with, camera, cuboid, inside_out_sphere, light, quad, Gpu};
use glam::Vec3;
use serde_json::json;
use umbra::color::{srgb_decode, srgb_encode};
use umbra::gpu::scene::GpuScene;
use umbra::gpu::SceneFeatures;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::probes::{ProbeGrid, ProbeSettings};
use umbra::render::{hybrid, path_trace, HybridSettings, Passes, PathSettings};
use umbra::scene::{LightKind, Material, Sampler, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

const SIZE: (u32, u32) = (24, 24);

/// An unlit material of base colour factor `base`, with the properties an unlit surface must
/// ignore set to values that would show: glossy, metallic, emissive.
fn unlit(base: [f32; 3]) -> Material {
    Material {
        base_color_factor: [base[0], base[1], base[2], 1.0],
        metallic: 0.5,
        roughness: 0.2,
        emissive: [4.0; 3],
        unlit: true,
        ..Default::default()
    }
}

/// A linear colour as a vertex keeps it: sRGB-encoded to 8 bits and decoded.
fn as_vertex_color(c: f32) -> f32 {
    srgb_decode((srgb_encode(c) * 255.0).round() / 255.0)
}

/// An unlit 4 m square filling the view of a camera 1.5 m away, base colour factor × a 1×1 sRGB
/// texture × a uniform vertex colour, under a sun, a constant sky and an emitter behind the
/// camera: every pixel, in both modes, is exactly that product (the path tracer to float
/// rounding; the hybrid to its half-float G-buffer), and the emissive factor is ignored. Fails
/// if the surface is shaded, its emission or the light around adds in, or the texture or vertex
/// colour is left out.
#[test]
fn unlit_surfaces_show_their_base_colour_in_both_modes() {
    let gpu = Gpu::new();
    let factor = [0.8f32, 0.5, 0.9];
    let texel = [200u8, 120, 60];
    let vertex = [0.5f32, 1.0, 0.25];
    let mut material = unlit(factor);
    material.base_color_texture =
        Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 });
    let emitter = Material { emissive: [3.0; 3], ..Default::default() };
    let mut scene = build_with(
        "unlit square",
        &[
            (quad(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)), material),
            (quad(Vec3::new(0.0, 0.0, 3.0), Vec3::X, -Vec3::Y), emitter),
        ],
        vec![light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.3, -0.2, -1.0), 5.0)],
        camera(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO),
    );
    scene.textures.push(Texture {
        name: "texel".into(),
        width: 1,
        height: 1,
        rgba8: vec![texel[0], texel[1], texel[2], 255],
        srgb: true,
        sampler: Sampler::default(),
    });
    scene.uv0 = vec![[0.5; 2]; scene.positions.len()];
    scene.colors = vec![[vertex[0], vertex[1], vertex[2], 1.0]; scene.positions.len()];
    scene.update_emissive();
    assert_eq!(scene.emissive.triangles, vec![2, 3], "only the emitter, not the unlit square, is a light");
    // The texel as the GPU stores it: sRGB-decoded to 16-bit linear (within 2^-17 of
    // srgb_decode, which a dark texel's relative error of up to 10^-4 would show at 10^-5).
    let stored = |code: u8| umbra::gpu::scene::texel_unorm16(code, true) as f32 / 65535.0;
    let expected: [f32; 3] =
        std::array::from_fn(|c| factor[c] * stored(texel[c]) * as_vertex_color(vertex[c]));

    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let lighting = LightingSettings { env: [0.5; 3], shadow_rays: 4, ..Default::default() };
    let h = hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size: SIZE, lighting, ..Default::default() })
        .unwrap();
    let settings = PathSettings { size: SIZE, spp: 4, env: [0.5; 3], ..Default::default() };
    let p = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let (mut worst_hybrid, mut worst_path) = (0.0f32, 0.0f32);
    for (h, p) in h.color.iter().zip(&p.mean) {
        for c in 0..3 {
            worst_hybrid = worst_hybrid.max((h[c] / expected[c] - 1.0).abs());
            worst_path = worst_path.max((p[c] / expected[c] - 1.0).abs());
        }
    }
    eprintln!(
        "expected {expected:?}; relative error: hybrid {worst_hybrid:.2e}, path traced {worst_path:.2e}"
    );
    assert!(worst_hybrid < 1e-3, "hybrid off by {worst_hybrid} (relative)");
    assert!(worst_path < 1e-5, "path tracer off by {worst_path} (relative)");
}

/// Lit only by an unlit box around it (no light, a black sky), a rough floor looks exactly as it
/// does under a constant sky of the box's colour with no box: the path tracer treats the unlit
/// surface as an emitter of its base colour that ends the path, and with the same seed each path
/// takes the same steps in both scenes, so the two images agree pixel by pixel to float
/// rounding. Fails if the unlit surface is dark to indirect rays, or scatters (the path would go
/// on and add more).
#[test]
fn an_unlit_box_lights_like_a_constant_sky() {
    let gpu = Gpu::new();
    let sky = [0.6f32, 0.4, 0.2];
    let floor = quad(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0));
    let view = camera(Vec3::new(0.0, 1.2, 1.2), Vec3::ZERO);
    let lambert = Material { metallic: 0.0, roughness: 1.0, ..Default::default() };
    let boxed = build_with(
        "floor in an unlit box",
        &[(floor.clone(), lambert), (cuboid(Vec3::splat(-5.0), Vec3::splat(5.0)), unlit(sky))],
        vec![],
        view,
    );
    let open = build("floor under the sky", &[floor], vec![], view);
    let render = |scene: &Scene, env: [f32; 3]| {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        let settings = PathSettings { size: SIZE, spp: 8, seed: 3, env, ..Default::default() };
        let image = path_trace(&gpu, &gpu_scene, &view, &settings, |_, _| {}).unwrap();
        assert_eq!(image.nonfinite_samples, 0);
        image.mean
    };
    let in_box = render(&boxed, [0.0; 3]);
    let under_sky = render(&open, sky);
    let floor_pixels = under_sky.iter().filter(|p| p[0] < 0.99 * sky[0]).count();
    let mut worst = 0.0f32;
    for (a, b) in in_box.iter().zip(&under_sky) {
        for c in 0..3 {
            worst = worst.max((a[c] - b[c]).abs() / b[c].max(1e-3));
        }
    }
    eprintln!(
        "{floor_pixels} floor pixels; the boxed floor off the open one by at most {worst:.2e} (relative)"
    );
    assert!(floor_pixels > 100, "the floor fills the view");
    assert!(worst < 1e-4, "the unlit box and the sky disagree by {worst} (relative)");
}

/// Irradiance probes inside a room whose walls are unlit with colour L hold irradiance π L in
/// every direction (each gather ray brings L back; nothing else lights the room, and the walls
/// reflect nothing). Fails if the gathers shade the walls as lit surfaces (0 here).
#[test]
fn probes_see_unlit_walls_as_their_colour() {
    let gpu = Gpu::new();
    let wall = [0.5f32, 0.3, 0.1];
    let sphere = inside_out_sphere(2);
    let scene = build_with("unlit room", &[(sphere, unlit(wall))], vec![], camera(Vec3::ZERO, Vec3::NEG_Z));
    let grid = ProbeGrid { origin: [-0.3; 3], spacing: [0.6; 3], counts: [2, 2, 2] };
    let settings = ProbeSettings { rays: 64, bounces: 2, sweeps: 4, ..Default::default() };
    let volume = baked_probes(&gpu, &scene, grid, &settings);
    assert!(volume.read_active(&gpu).unwrap().iter().all(|a| *a), "every probe is inside the room");
    let mut worst = 0.0f32;
    for texel in volume.read_irradiance(&gpu).unwrap() {
        for c in 0..3 {
            worst = worst.max((texel[c] / (std::f32::consts::PI * wall[c]) - 1.0).abs());
        }
    }
    eprintln!("probe irradiance within {worst:.2e} (relative) of pi L");
    assert!(worst < 1e-3, "a probe texel is {:.2} % off pi L", 100.0 * worst);
}

/// A glTF material with `KHR_materials_unlit` loads as unlit, its emissive factor ignored (no
/// light in the emissive table) and the extension not among the ignored ones; kernels are
/// specialised for unlit materials only when the scene has one.
#[test]
fn unlit_materials_load_and_specialise_only_their_scenes() {
    let box_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/khronos/Box/Box.glb");
    let (mut json, bin) = generate::split_glb(&std::fs::read(box_path).unwrap());
    let lit =
        Scene::from_glb_bytes("box.glb", &generate::glb(&serde_json::to_vec(&json).unwrap(), &bin)).unwrap();
    json["materials"][0]["extensions"] = json!({ "KHR_materials_unlit": {} });
    json["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
    json["extensionsUsed"] = json!(["KHR_materials_unlit"]);
    json["extensionsRequired"] = json!(["KHR_materials_unlit"]);
    let flat = Scene::from_glb_bytes("unlit.glb", &generate::glb(&serde_json::to_vec(&json).unwrap(), &bin))
        .unwrap();
    assert!(flat.materials[0].unlit && !lit.materials[0].unlit);
    assert_eq!(flat.materials[0].emission(), [0.0; 3]);
    assert!(flat.emissive.is_empty(), "an unlit material does not emit");
    assert!(flat.warnings.is_empty(), "{:?}", flat.warnings);

    let gpu = Gpu::new();
    let features = |scene: &Scene| SceneFeatures::of(&GpuScene::upload(&gpu, scene).unwrap());
    assert!(features(&flat).unlit);
    assert!(!features(&lit).unlit);
    assert!(!features(&Scene::cornell_box()).unlit);
    let passes = Passes::new(&gpu, &GpuScene::upload(&gpu, &lit).unwrap());
    assert!(!passes.features().unlit, "the pipelines of a scene without unlit materials leave it out");
}
