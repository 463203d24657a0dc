//! glTF `COLOR_0`: the vertex colour multiplies the base colour and its alpha (as the glTF
//! specification says), in the G-buffer, the hybrid's image and the path tracer, interpolated
//! across the triangle, and cuts alpha-masked surfaces.

mod common;

use common::{build_with, camera, light, quad, Gpu};
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{AlphaMode, LightKind, Material, Scene};

/// A 2 m square facing the camera under a sun and a sky, its material `material`, its six
/// vertices (two triangles) coloured by `color(position)`.
fn square(material: Material, color: impl Fn(Vec3) -> [f32; 4]) -> Scene {
    let face = quad(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
    let mut scene = build_with(
        "coloured square",
        &[(face, material)],
        vec![light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.2, -0.3, -1.0), 3.0)],
        camera(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO),
    );
    scene.colors = scene.positions.iter().map(|p| color(Vec3::from(*p))).collect();
    scene
}

fn lambert(base: [f32; 4]) -> Material {
    Material { base_color_factor: base, metallic: 0.0, roughness: 1.0, ..Default::default() }
}

const SIZE: (u32, u32) = (32, 32);

/// A uniform vertex colour renders as the same colour in the base colour factor, in the hybrid
/// and the path tracer (same seed), within the 8-bit sRGB packing of vertex colours (under 1 %).
#[test]
fn a_uniform_vertex_colour_equals_the_same_base_colour() {
    let gpu = Gpu::new();
    let rgb = [0.5f32, 0.25, 0.9];
    let by_vertex = square(lambert([1.0; 4]), |_| [rgb[0], rgb[1], rgb[2], 1.0]);
    let by_factor = square(lambert([rgb[0], rgb[1], rgb[2], 1.0]), |_| [1.0; 4]);
    let lighting = LightingSettings { env: [0.3; 3], ..Default::default() };
    let mut means = Vec::new();
    for scene in [&by_vertex, &by_factor] {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let h =
            hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size: SIZE, lighting, ..Default::default() })
                .unwrap();
        let p = path_trace(
            &gpu,
            &gpu_scene,
            &camera,
            &PathSettings { size: SIZE, spp: 16, env: [0.3; 3], ..Default::default() },
            |_, _| {},
        )
        .unwrap();
        let mean =
            |img: &[[f32; 4]], c: usize| img.iter().map(|x| x[c] as f64).sum::<f64>() / img.len() as f64;
        means.push([0, 1, 2].map(|c| (mean(&h.color, c), mean(&p.mean, c))));
        // The G-buffer's base colour is the product.
        let centre = (SIZE.1 / 2 * SIZE.0 + SIZE.0 / 2) as usize;
        let base = h.gbuffer.base[centre];
        for c in 0..3 {
            assert!(
                (base[c] - rgb[c]).abs() < 0.01 * rgb[c] + 2e-3,
                "base colour {base:?}, expected {rgb:?}"
            );
        }
    }
    eprintln!("(hybrid, path traced) means per channel: by vertex {:?}, by factor {:?}", means[0], means[1]);
    for (c, (v, f)) in means[0].iter().zip(&means[1]).enumerate() {
        for (k, (a, b)) in [(v.0, f.0), (v.1, f.1)].into_iter().enumerate() {
            assert!(
                (a / b - 1.0).abs() < 0.01,
                "channel {c}, {}: by vertex {a:.5}, by factor {b:.5}",
                ["hybrid", "path"][k]
            );
        }
    }
}

/// Colours interpolate across the triangle: red on the left edge, green on the right, the
/// G-buffer's base colour across a row goes linearly from one to the other.
#[test]
fn vertex_colours_interpolate_across_the_surface() {
    let gpu = Gpu::new();
    let scene =
        square(lambert([1.0; 4]), |p| if p.x < 0.0 { [1.0, 0.0, 0.0, 1.0] } else { [0.0, 1.0, 0.0, 1.0] });
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let h = hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size: SIZE, ..Default::default() }).unwrap();
    let row = SIZE.1 / 2;
    let (mut checked, mut worst) = (0, 0.0f32);
    for x in 0..SIZE.0 {
        let i = (row * SIZE.0 + x) as usize;
        if h.gbuffer.material[i][0] != 0 {
            continue;
        }
        let base = h.gbuffer.base[i];
        // Red and green sum to 1 in linear light along the row; red falls as x grows.
        worst = worst.max((base[0] + base[1] - 1.0).abs());
        if x > 0 && h.gbuffer.material[i - 1][0] == 0 {
            assert!(base[0] <= h.gbuffer.base[i - 1][0] + 1e-3, "red grows to the right at x = {x}");
        }
        checked += 1;
    }
    eprintln!("{checked} pixels on the row, red + green off 1 by at most {worst:.4}");
    assert!(checked > 10 && worst < 0.01);
    let left = h.gbuffer.base[(row * SIZE.0 + SIZE.0 / 2 - 6) as usize];
    assert!(left[0] > 0.6 && left[1] < 0.4, "left of centre is mostly red: {left:?}");
}

/// The vertex alpha multiplies the material's: an alpha-masked material whose vertices carry
/// alpha 0.2 under a cutoff of 0.5 is cut out entirely (the G-buffer sees nothing), and with
/// alpha 0.8 it stays.
#[test]
fn vertex_alpha_cuts_masked_surfaces() {
    let gpu = Gpu::new();
    let masked = Material { alpha_mode: AlphaMode::Mask, alpha_cutoff: 0.5, ..lambert([1.0; 4]) };
    for (alpha, visible) in [(0.2f32, false), (0.8, true)] {
        let scene = square(masked.clone(), |_| [1.0, 1.0, 1.0, alpha]);
        let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let h =
            hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size: SIZE, ..Default::default() }).unwrap();
        let surface = h.gbuffer.material.iter().filter(|m| m[0] == 0).count();
        assert_eq!(surface > 100, visible, "vertex alpha {alpha}: {surface} surface pixels");
    }
}
