//! glTF alpha (MASK and BLEND) in the path tracer's traversal, its shadow rays and the G-buffer.

use crate::common::Gpu;
use crate::{bulb_above, camera, facing_quad, floor_quad, render, scene_of};
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::procedural::Mesh;
use umbra::render::{PathImage, PathSettings};
use umbra::scene::Material;

/// glTF alpha, in the path tracer's traversal (camera rays and shadow rays alike) and in the
/// G-buffer: a dark grey Lambert quad (albedo 0.2) facing the camera under a white sky.
/// MASK below its cutoff vanishes (every pixel is the sky's 1), at or above it is opaque (0.2); a
/// base-colour texture's alpha masks per texel (its transparent left half shows the sky); BLEND
/// with alpha 0.25 shows 0.25 · 0.2 + 0.75 · 1 = 0.8 on average (stochastic transparency: z-test
/// of the quad's mean at significance 1e-4); a masked-away occluder casts no shadow; the hybrid's
/// G-buffer sees through a masked-away quad.
#[test]
fn alpha_mask_and_blend() {
    use umbra::scene::{AlphaMode, Filter, Sampler, Texture, TextureRef, Wrap};
    let gpu = Gpu::new();
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0); // sees x, y in about ±0.83
    let grey = |alpha: f32, mode: AlphaMode| Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [0.2, 0.2, 0.2, alpha],
        alpha_mode: mode,
        alpha_cutoff: 0.5,
        ..Default::default()
    };
    let settings =
        PathSettings { size: (24, 24), spp: 64, env: [1.0; 3], max_bounces: 1, ..Default::default() };
    let centre = |image: &PathImage| {
        // The 12×12 pixels around the centre: all on the quad.
        (6..18)
            .flat_map(|y| (6..18).map(move |x| (x, y)))
            .map(|(x, y)| image.mean[y * 24 + x][1])
            .collect::<Vec<_>>()
    };

    let masked_away = render(&gpu, &scene_of(&[(&quad, grey(0.4, AlphaMode::Mask), false)], cam), &settings);
    assert!(
        centre(&masked_away).iter().all(|&v| (v - 1.0).abs() < 1e-5),
        "alpha 0.4 < cutoff 0.5 must vanish"
    );
    // The hybrid's G-buffer sees through it too (and sees the kept quad).
    for (alpha, visible) in [(0.4, false), (0.5, true)] {
        let scene = scene_of(&[(&quad, grey(alpha, AlphaMode::Mask), false)], cam);
        let device_scene = GpuScene::upload(&gpu, &scene).unwrap();
        let hybrid_settings = umbra::render::HybridSettings { size: (24, 24), ..Default::default() };
        let image = umbra::render::hybrid(&gpu, &device_scene, &cam, &hybrid_settings).unwrap();
        assert_eq!(image.gbuffer.depth[12 * 24 + 12] > 0.0, visible, "G-buffer with alpha {alpha}");
    }
    let kept = render(&gpu, &scene_of(&[(&quad, grey(0.5, AlphaMode::Mask), false)], cam), &settings);
    assert!(centre(&kept).iter().all(|&v| (v - 0.2).abs() < 1e-3), "alpha 0.5 = cutoff is opaque");
    let opaque = render(&gpu, &scene_of(&[(&quad, grey(0.0, AlphaMode::Opaque), false)], cam), &settings);
    assert!(centre(&opaque).iter().all(|&v| (v - 0.2).abs() < 1e-3), "OPAQUE ignores alpha");

    // BLEND: the quad's mean against 0.8 with the path tracer's own variance.
    let blend = render(&gpu, &scene_of(&[(&quad, grey(0.25, AlphaMode::Blend), false)], cam), &settings);
    let var = blend.variance_of_mean();
    let (mut sum, mut v, mut n) = (0.0f64, 0.0f64, 0.0f64);
    for y in 6..18 {
        for x in 6..18 {
            sum += blend.mean[y * 24 + x][1] as f64;
            v += var[y * 24 + x][1] as f64;
            n += 1.0;
        }
    }
    let z = (sum / n - 0.8) / (v.sqrt() / n);
    eprintln!("blend 0.25: quad mean {:.4} (expected 0.8), z {z:.2}", sum / n);
    assert!(z.abs() < 3.89, "blend mean {} vs 0.8 (z = {z})", sum / n);

    // A texture whose left column is transparent, right column opaque (nearest filtering).
    let mut material = grey(1.0, AlphaMode::Mask);
    material.base_color_texture = Some(TextureRef {
        texture: 0,
        tex_coord: 0,
        transform: umbra::scene::IDENTITY_TRANSFORM,
        scale: 1.0,
    });
    let mut scene = scene_of(&[(&quad, material, false)], cam);
    scene.uv0 = scene.positions.iter().map(|p| [(p[0] + 1.0) / 2.0, (1.0 - p[1]) / 2.0]).collect();
    let nearest = Sampler {
        wrap_s: Wrap::ClampToEdge,
        wrap_t: Wrap::ClampToEdge,
        mag_filter: Filter::Nearest,
        min_filter: Filter::Nearest,
        mipmaps: false,
        mipmap_filter: Filter::Nearest,
    };
    scene.textures.push(Texture {
        name: "half transparent".into(),
        width: 2,
        height: 1,
        rgba8: [[255, 255, 255, 0], [255, 255, 255, 255]].concat(),
        srgb: true,
        sampler: nearest,
    });
    let textured = render(&gpu, &scene, &settings);
    for y in 6..18 {
        for (x, expected) in [(7, 1.0), (8, 1.0), (15, 0.2), (16, 0.2)] {
            let v = textured.mean[y * 24 + x][1];
            assert!((v - expected).abs() < 1e-3, "textured mask at ({x}, {y}): {v}, expected {expected}");
        }
    }

    // Shadows: a floor under a point light, with a masked-away occluder between them, is lit
    // exactly as the floor alone.
    let floor = floor_quad(2.0);
    let occluder = Mesh {
        positions: floor.positions.iter().map(|p| *p * 0.5 + Vec3::new(0.0, 0.5, 0.0)).collect(),
        triangles: floor.triangles.clone(),
    };
    // Low, from the side: it sees the floor under the occluder.
    let top = camera(Vec3::new(1.9, 0.25, 1.9), Vec3::ZERO, 50.0);
    let white =
        Material { metallic: 0.0, specular_factor: 0.0, base_color_factor: [1.0; 4], ..Default::default() };
    let light = bulb_above();
    let lit = |parts: &[(&Mesh, Material, bool)]| {
        let mut scene = scene_of(parts, top);
        scene.lights.push(light.clone());
        let settings =
            PathSettings { size: (24, 24), spp: 4, env: [0.0; 3], max_bounces: 1, ..Default::default() };
        render(&gpu, &scene, &settings).mean
    };
    let alone = lit(&[(&floor, white.clone(), false)]);
    let behind_mask = lit(&[(&floor, white.clone(), false), (&occluder, grey(0.1, AlphaMode::Mask), false)]);
    let behind_opaque =
        lit(&[(&floor, white.clone(), false), (&occluder, grey(0.1, AlphaMode::Opaque), false)]);
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter().zip(b).map(|(p, q)| (p[1] - q[1]).abs()).fold(0.0f32, f32::max)
    };
    assert!(
        diff(&alone, &behind_mask) < 1e-4,
        "a masked-away occluder shadows: {}",
        diff(&alone, &behind_mask)
    );
    assert!(diff(&alone, &behind_opaque) > 0.01, "the opaque occluder should shadow (a test of the test)");
}

/// Alpha tests run after the traversal's walk, which restarts behind a cut-out hit
/// (bvh.glsl's bvh_trace): layers of masked-away quads in front of an opaque one leave the
/// opaque one seen, in the path tracer and in the G-buffer (its depth); a masked-away quad
/// nearer a shaded floor than an opaque occluder, so that a shadow ray's walk ends on the masked
/// candidate and has culled the occluder behind it, still leaves the floor in the occluder's
/// shadow: the images with and without the masked quad are equal, in the path tracer and in the
/// hybrid's ray-traced shadows. (Before each check, a test of the test: the masked quads at an
/// alpha above the cutoff do change the image.)
#[test]
fn alpha_tests_restart_the_walk_behind_cut_out_hits() {
    use umbra::scene::AlphaMode;
    let gpu = Gpu::new();
    let material = |grey: f32, alpha: f32, mode: AlphaMode| Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [grey, grey, grey, alpha],
        alpha_mode: mode,
        alpha_cutoff: 0.5,
        ..Default::default()
    };
    let at_z = |z: f32| {
        let q = facing_quad();
        Mesh {
            positions: q.positions.iter().map(|p| *p + Vec3::new(0.0, 0.0, z)).collect(),
            triangles: q.triangles,
        }
    };
    let (front, middle, back) = (at_z(0.5), at_z(0.25), at_z(0.0));
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 30.0);
    let settings =
        PathSettings { size: (16, 16), spp: 16, env: [1.0; 3], max_bounces: 1, ..Default::default() };
    let layers = |alpha: f32| {
        scene_of(
            &[
                (&front, material(0.9, alpha, AlphaMode::Mask), false),
                (&middle, material(0.6, alpha, AlphaMode::Blend), false),
                (&back, material(0.2, 1.0, AlphaMode::Opaque), false),
            ],
            cam,
        )
    };
    let seen = render(&gpu, &layers(0.0), &settings);
    assert!(
        seen.mean.iter().take(16 * 16).all(|p| (p[1] - 0.2).abs() < 1e-3 || (p[1] - 1.0).abs() < 1e-5),
        "every pixel shows the opaque quad (0.2) or the sky (1)"
    );
    assert!((seen.mean[8 * 16 + 8][1] - 0.2).abs() < 1e-3, "the centre shows the opaque quad");
    let covered = render(&gpu, &layers(1.0), &settings);
    assert!(
        (covered.mean[8 * 16 + 8][1] - 0.9).abs() < 1e-3,
        "a test of the test: the kept front quad is seen"
    );
    for (alpha, depth) in [(0.0, 2.0), (1.0, 1.5)] {
        let device_scene = GpuScene::upload(&gpu, &layers(alpha)).unwrap();
        let hybrid_settings = umbra::render::HybridSettings { size: (16, 16), ..Default::default() };
        let image = umbra::render::hybrid(&gpu, &device_scene, &cam, &hybrid_settings).unwrap();
        let d = image.gbuffer.depth[8 * 16 + 8];
        assert!(
            (d - depth).abs() < 1e-4,
            "G-buffer depth with the masks at alpha {alpha}: {d}, expected {depth}"
        );
    }

    // Shadows: a point light above a floor, an opaque occluder at y = 0.5 and a masked quad
    // below it at y = 0.25 (nearer the floor: a shadow ray meets it first).
    let floor = floor_quad(2.0);
    let plate = |y: f32, scale: f32| Mesh {
        positions: floor.positions.iter().map(|p| *p * scale + Vec3::new(0.0, y, 0.0)).collect(),
        triangles: floor.triangles.clone(),
    };
    let (occluder, low) = (plate(0.5, 0.25), plate(0.25, 0.5));
    let top = camera(Vec3::new(1.9, 0.2, 1.9), Vec3::ZERO, 50.0);
    let white = material(1.0, 1.0, AlphaMode::Opaque);
    let light = bulb_above();
    let lit = |low_alpha: Option<f32>| {
        let mut parts =
            vec![(&floor, white.clone(), false), (&occluder, material(0.5, 1.0, AlphaMode::Opaque), false)];
        if let Some(alpha) = low_alpha {
            parts.push((&low, material(0.5, alpha, AlphaMode::Mask), false));
        }
        let mut scene = scene_of(&parts, top);
        scene.lights.push(light.clone());
        let settings =
            PathSettings { size: (24, 24), spp: 4, env: [0.0; 3], max_bounces: 1, ..Default::default() };
        let path = render(&gpu, &scene, &settings).mean;
        let device_scene = GpuScene::upload(&gpu, &scene).unwrap();
        let hybrid_settings = umbra::render::HybridSettings { size: (24, 24), ..Default::default() };
        let hybrid = umbra::render::hybrid(&gpu, &device_scene, &top, &hybrid_settings).unwrap().color;
        (path, hybrid)
    };
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter().zip(b).map(|(p, q)| (p[1] - q[1]).abs()).fold(0.0f32, f32::max)
    };
    let (path_alone, hybrid_alone) = lit(None);
    let (path_masked, hybrid_masked) = lit(Some(0.0));
    let (path_kept, hybrid_kept) = lit(Some(1.0));
    assert!(
        diff(&path_alone, &path_kept) > 0.01,
        "a test of the test: the kept low quad changes the path-traced image"
    );
    assert!(
        diff(&hybrid_alone, &hybrid_kept) > 0.01,
        "a test of the test: the kept low quad changes the hybrid image"
    );
    assert!(
        diff(&path_alone, &path_masked) < 1e-4,
        "path tracer: the masked-away quad changes the shadow: {}",
        diff(&path_alone, &path_masked)
    );
    assert!(
        diff(&hybrid_alone, &hybrid_masked) < 1e-4,
        "hybrid: the masked-away quad changes the shadow: {}",
        diff(&hybrid_alone, &hybrid_masked)
    );
}
