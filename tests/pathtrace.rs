//! The path tracer against closed-form and numerically integrated answers, its determinism,
//! and its robustness (no NaN or Inf ever reaches the accumulation buffer).

mod common;

use common::{relative_mse, Gpu};
use glam::Vec3;
use umbra::gpu::layout::{GpuCamera, PathStats};
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{Microfacet, PathTarget, Sampler};
use umbra::procedural::{icosphere, Mesh};
use umbra::render::{path_trace, Passes, PathImage, PathSettings};
use umbra::scene::{Camera, Material, Scene};

/// A scene from meshes, one material per mesh, with flat (face) normals, or with `smooth` the
/// normals of a sphere centred at the origin.
fn scene_of(parts: &[(&Mesh, Material, bool)], camera: Camera) -> Scene {
    let mut scene = Scene { name: "test scene".into(), ..Default::default() };
    for (m, (mesh, material, smooth)) in parts.iter().enumerate() {
        scene.materials.push(material.clone());
        for t in &mesh.triangles {
            let p = t.map(|i| mesh.positions[i as usize]);
            let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let base = scene.positions.len() as u32;
            for v in &p {
                scene.positions.push((*v).into());
                let n = if *smooth { v.normalize() } else { face };
                scene.normals.push(n.into());
            }
            scene.triangles.push([base, base + 1, base + 2]);
            scene.triangle_material.push(m as u32);
        }
    }
    scene.cameras.push(camera);
    scene.update_emissive();
    scene
}

/// A camera at `height` above the origin looking straight down (-y), image up along -z.
fn looking_down(height: f32, yfov: f32) -> Camera {
    Camera {
        position: [0.0, height, 0.0],
        forward: [0.0, -1.0, 0.0],
        up: [0.0, 0.0, -1.0],
        yfov,
        aspect: None,
        znear: 0.01,
        orthographic: None,
    }
}

/// A square floor at y = 0, `half` metres each way, facing +y.
fn floor_quad(half: f32) -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-half, 0.0, -half),
            Vec3::new(half, 0.0, -half),
            Vec3::new(half, 0.0, half),
            Vec3::new(-half, 0.0, half),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
    }
}

/// The square [−1, 1]² at z = 0, facing +z.
fn facing_quad() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// A point light of intensity 2 one unit above the origin, pointing down.
fn bulb_above() -> umbra::scene::Light {
    umbra::scene::Light {
        name: "bulb".into(),
        kind: umbra::scene::LightKind::Point,
        position: [0.0, 1.0, 0.0],
        direction: [0.0, -1.0, 0.0],
        color: [1.0; 3],
        intensity: 2.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::FRAC_PI_4,
    }
}

fn camera(position: Vec3, target: Vec3, yfov_degrees: f32) -> Camera {
    Camera {
        position: position.into(),
        forward: (target - position).normalize().into(),
        up: [0.0, 1.0, 0.0],
        yfov: yfov_degrees.to_radians(),
        aspect: None,
        znear: 0.01,
        orthographic: None,
    }
}

fn render(gpu: &Gpu, scene: &Scene, settings: &PathSettings) -> PathImage {
    let device_scene = GpuScene::upload(gpu, scene).unwrap();
    let image = path_trace(gpu, &device_scene, &scene.camera(None).unwrap(), settings, |_, _| {}).unwrap();
    assert_eq!(
        image.nonfinite_samples,
        0,
        "NaN/Inf samples, arising in {:?}",
        umbra::gpu::layout::nonfinite_source_names(image.nonfinite_sources)
    );
    image
}

/// The direction through the centre of pixel (x, y), as `pathtrace.comp` computes it.
fn pixel_ray(cam: &Camera, (w, h): (u32, u32), x: u32, y: u32) -> Vec3 {
    let c = GpuCamera::new(cam, (w, h));
    let ndc = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / h as f32);
    (Vec3::from(c.forward) + ndc.0 * Vec3::from(c.right) + ndc.1 * Vec3::from(c.up)).normalize()
}

/// cos of the angle between the view ray and the normal of the unit sphere at the origin, at
/// the centre of each pixel; `None` off the sphere.
fn sphere_cosines(cam: &Camera, size: (u32, u32)) -> Vec<Option<f32>> {
    let o = Vec3::from(cam.position);
    (0..size.1)
        .flat_map(|y| (0..size.0).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = pixel_ray(cam, size, x, y);
            let b = o.dot(d);
            let disc = b * b - (o.length_squared() - 1.0);
            (disc > 0.0).then(|| {
                let p = o + d * (-b - disc.sqrt());
                p.normalize().dot(-d)
            })
        })
        .collect()
}

/// A Lambert sphere of albedo 1 (specular off) under a constant environment of 1 reflects
/// exactly 1 everywhere: the furnace test of throughput, sampling weights and the environment.
#[test]
fn white_furnace_lambert_sphere_is_one() {
    let gpu = Gpu::new();
    let sphere = icosphere(4, Vec3::ZERO, 1.0);
    let white =
        Material { metallic: 0.0, specular_factor: 0.0, base_color_factor: [1.0; 4], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 35.0);
    let scene = scene_of(&[(&sphere, white, false)], cam);
    let settings =
        PathSettings { size: (48, 48), spp: 16, env: [1.0; 3], max_bounces: 8, ..Default::default() };
    let image = render(&gpu, &scene, &settings);
    let cosines = sphere_cosines(&cam, settings.size);
    let mut checked = 0;
    for (i, p) in image.mean.iter().enumerate() {
        // Away from the silhouette (and from the polygonal outline of the icosphere).
        if cosines[i].is_some_and(|c| c > 0.3)
            || cosines[i].is_none() && image.normal_depth[i][3].is_infinite()
        {
            for (c, v) in p[..3].iter().enumerate() {
                assert!((v - 1.0).abs() <= 0.005, "pixel {i} channel {c}: {v}");
            }
            checked += 1;
        }
    }
    assert!(checked > 1500, "only {checked} pixels checked");
}

/// Directional albedo of a metal with F = 1 at cos θ_o = mu: ∫ D G1(o) G1(i) / (4 μ_o) dω_i over
/// the upper hemisphere, by midpoint quadrature in (θ_i, φ_i), for GGX or Beckmann (with the
/// same G1 approximations the kernel uses).
fn metal_albedo(mu: f64, alpha: f64, microfacet: Microfacet) -> f64 {
    use std::f64::consts::PI;
    let a2 = alpha * alpha;
    let d = |hz: f64| match microfacet {
        Microfacet::Ggx | Microfacet::GgxWalter => a2 / (PI * (hz * hz * (a2 - 1.0) + 1.0).powi(2)),
        Microfacet::Beckmann => {
            let c2 = hz * hz;
            (-(1.0 - c2) / c2 / a2).exp() / (PI * a2 * c2 * c2)
        }
    };
    let g1 = |c: f64| match microfacet {
        Microfacet::Ggx | Microfacet::GgxWalter => 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt()),
        Microfacet::Beckmann => {
            let b = c / (alpha * (1.0 - c * c).sqrt());
            if b >= 1.6 {
                1.0
            } else {
                (3.535 * b + 2.181 * b * b) / (1.0 + 2.276 * b + 2.577 * b * b)
            }
        }
    };
    let wo = [(1.0 - mu * mu).sqrt(), 0.0, mu];
    let (nt, np) = (400, 400);
    let mut sum = 0.0;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
        let (st, ct) = theta.sin_cos();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let wi = [st * phi.cos(), st * phi.sin(), ct];
            let h = [wo[0] + wi[0], wo[1] + wi[1], wo[2] + wi[2]];
            let hz = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            sum += d(hz) * g1(mu) * g1(ct) / (4.0 * mu * ct) * ct * st;
        }
    }
    sum * (std::f64::consts::FRAC_PI_2 / nt as f64) * (std::f64::consts::TAU / np as f64)
}

/// A metal sphere (base colour 1, so F = 1) under a constant environment of 1, GGX (VNDF
/// sampling and Walter's D(h) cos θh sampling) and Beckmann (half-vector sampling): each pixel
/// converges to the numerically integrated directional albedo at its view angle. A wrong pdf or
/// sampling weight shifts the mean. Pixels are pooled in bins of view angle (single pixels at
/// 64 spp are too skewed for a z-test: most samples are near 1 with a rare tail) and each bin
/// is z-tested at significance 0.01 with a Šidák correction over the bins.
#[test]
fn metal_spheres_match_integrated_albedo() {
    for microfacet in Microfacet::ALL {
        metal_sphere_matches_integrated_albedo(microfacet);
    }
}

fn metal_sphere_matches_integrated_albedo(microfacet: Microfacet) {
    let gpu = Gpu::new();
    let sphere = icosphere(6, Vec3::ZERO, 1.0);
    let roughness = 0.5f32;
    let metal = Material { metallic: 1.0, roughness, base_color_factor: [1.0; 4], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 32.0);
    let scene = scene_of(&[(&sphere, metal, true)], cam);
    let settings = PathSettings {
        size: (40, 40),
        spp: 64,
        env: [1.0; 3],
        max_bounces: 1,
        microfacet,
        ..Default::default()
    };
    let image = render(&gpu, &scene, &settings);
    let variance = image.variance_of_mean();
    let alpha = (roughness * roughness) as f64;
    const BINS: usize = 6;
    let (lo, hi) = (0.35f32, 1.0f32);
    let mut bins = [(0usize, 0.0f64, 0.0f64, 0.0f64); BINS]; // pixels, Σ got, Σ expected, Σ var
    for (i, mu) in sphere_cosines(&cam, settings.size).iter().enumerate() {
        let Some(mu) = mu.filter(|&c| c > lo) else { continue };
        let bin = (((mu - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1);
        let b = &mut bins[bin];
        b.0 += 1;
        b.1 += image.mean[i][1] as f64;
        b.2 += metal_albedo(mu as f64, alpha, microfacet);
        b.3 += variance[i][1] as f64;
    }
    // Two-sided critical z for α = 1 − 0.99^(1/6) ≈ 0.00167.
    let z_crit = 3.144;
    for (k, &(n, got, expected, var)) in bins.iter().enumerate() {
        assert!(n >= 20, "bin {k} has only {n} pixels");
        let z = (got - expected) / var.sqrt();
        eprintln!(
            "{microfacet:?} metal bin {k}: {n} px, mean {:.4} expected {:.4}, z {z:.2}",
            got / n as f64,
            expected / n as f64
        );
        assert!(z.abs() < z_crit, "bin {k}: mean {} vs {}, z = {z}", got / n as f64, expected / n as f64);
    }
}

#[test]
fn same_seed_same_bytes_different_seed_different() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let settings = PathSettings { size: (32, 32), spp: 4, ..Default::default() };
    let bytes =
        |s: &PathSettings| bytemuck::cast_slice::<[f32; 4], u8>(&render(&gpu, &scene, s).mean).to_vec();
    let a = bytes(&settings);
    let b = bytes(&settings);
    let c = bytes(&PathSettings { seed: 7, ..settings.clone() });
    assert!(a == b, "same seed, different output");
    assert!(a != c, "different seeds, identical output");
}

/// A scene built to provoke NaN and Inf: roughness 0 mirrors, zero-length vertex normals,
/// degenerate and tiny emissive triangles, rays grazing a floor and hitting edges.
#[test]
fn provoking_scene_never_accumulates_nan_or_inf() {
    let gpu = Gpu::new();
    let floor = floor_quad(5.0);
    let mirror_ball = icosphere(2, Vec3::new(0.0, 0.5, 0.0), 0.5);
    let tiny_light = Mesh {
        positions: vec![Vec3::new(0.0, 2.0, 0.0), Vec3::new(1e-4, 2.0, 0.0), Vec3::new(0.0, 2.0, 1e-4)],
        triangles: vec![[0, 2, 1]],
    };
    let degenerate_light = Mesh {
        positions: vec![Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(2.0, 2.0, 2.0)],
        triangles: vec![[0, 1, 2], [0, 0, 0]],
    };
    let big_light = icosphere(1, Vec3::new(-2.0, 2.0, -1.0), 0.3);
    let emissive =
        |e: f32| Material { emissive: [e; 3], metallic: 0.0, double_sided: true, ..Default::default() };
    let mirror = Material { metallic: 1.0, roughness: 0.0, ..Default::default() };
    let glossy = Material { metallic: 0.0, roughness: 0.0, ..Default::default() };
    let cam = camera(Vec3::new(0.0, 0.02, 6.0), Vec3::new(0.0, 0.0, 0.0), 60.0);
    let mut scene = scene_of(
        &[
            (&floor, glossy, false),
            (&mirror_ball, mirror, false),
            (&tiny_light, emissive(1e6), false),
            (&degenerate_light, emissive(100.0), false),
            (&big_light, emissive(20.0), false),
        ],
        cam,
    );
    // Zero-length shading normals on the mirror ball.
    let ball = scene.triangle_material.iter().position(|&m| m == 1).unwrap();
    for t in ball..ball + mirror_ball.triangles.len() {
        for v in scene.triangles[t] {
            scene.normals[v as usize] = [0.0; 3];
        }
    }
    for heuristic in
        [umbra::passes::pathtrace::Heuristic::Power, umbra::passes::pathtrace::Heuristic::Balance]
    {
        let settings = PathSettings {
            size: (48, 32),
            spp: 8,
            env: [0.5; 3],
            heuristic,
            max_bounces: 6,
            ..Default::default()
        };
        let image = render(&gpu, &scene, &settings);
        assert!(image.mean.iter().flatten().all(|v| v.is_finite()), "non-finite accumulated value");
        assert!(image.moment.iter().flatten().all(|v| v.is_finite()), "non-finite second moment");
    }
}

/// `target_error` stops accumulating once the estimated relative error is reached: a loose
/// target stops early, a tighter one needs more samples, and the image meets its target.
#[test]
fn target_error_stops_early_and_is_met() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    let run = |target: f32| {
        let settings =
            PathSettings { size: (24, 24), spp: 4096, target_error: Some(target), ..Default::default() };
        render(&gpu, &scene, &settings)
    };
    let (loose, tight) = (run(0.1), run(0.05));
    eprintln!(
        "target 0.1: {} spp, error {}; target 0.05: {} spp, error {}",
        loose.spp,
        loose.relative_error(),
        tight.spp,
        tight.relative_error()
    );
    assert!(loose.spp < tight.spp && tight.spp < 4096, "{} then {} spp", loose.spp, tight.spp);
    assert!(loose.relative_error() <= 0.1 && tight.relative_error() <= 0.05);
}

/// The error `target_error` stops at is the true one: the image's estimated relative error (from
/// its own per-pixel variance) against its relative RMS error to an independent reference (another
/// seed, 64× the samples), on the Cornell box (area light). With independent numbers (the
/// estimate's premise) the two agree within 50 %; the reference's own noise (1/64 of the image's
/// variance) adds under 1 %. With the default low-discrepancy numbers the estimate is high (the
/// stratification lowers the true error; 0.058 estimated, 0.045 true when written), never low.
/// What the estimate cannot do: see a heavy tail its samples missed. spheres.glb under a sky of
/// 0.3 (a directional light's glints on glossy spheres: rare bright paths) stopped at 64 spp with
/// 0.077 estimated and 0.161 true (independent numbers; 0.072 and 0.120 with low-discrepancy ones
/// at 128), where an earlier sequence of random numbers had drawn 0.064 and 0.073: it was left
/// out of this test, whose bound it meets by chance only.
#[test]
fn target_error_is_the_true_error() {
    let gpu = Gpu::new();
    let scene = Scene::cornell_box();
    for sampler in Sampler::ALL {
        let base = PathSettings { size: (24, 24), spp: 4096, max_bounces: 4, sampler, ..Default::default() };
        let image = render(&gpu, &scene, &PathSettings { target_error: Some(0.08), seed: 1, ..base.clone() });
        let reference = render(&gpu, &scene, &PathSettings { spp: 64 * image.spp, seed: 2, ..base });
        let (estimated, actual) =
            (image.relative_error() as f64, relative_mse(&image.mean, &reference.mean).sqrt());
        eprintln!("{sampler:?}: stopped at {} spp, estimated {estimated:.4}, true {actual:.4}", image.spp);
        assert!(image.spp < 4096 && estimated <= 0.08, "{sampler:?}: the target was not reached");
        match sampler {
            Sampler::Independent => assert!(
                (actual / estimated - 1.0).abs() < 0.5,
                "{sampler:?}: true error {actual} vs estimated {estimated}"
            ),
            Sampler::LowDiscrepancy => {
                assert!(actual < estimated, "{sampler:?}: true error {actual} over the estimate {estimated}")
            }
        }
    }
}

/// Direct light from KHR_lights_punctual lights on a Lambert floor against the closed form
/// L = albedo/π · I · cosθ / d² (point), with the spot's smooth cone falloff, and
/// albedo/π · E · cosθ (directional).
#[test]
fn punctual_lights_match_closed_form() {
    use umbra::scene::{Light, LightKind};
    let gpu = Gpu::new();
    let floor = floor_quad(20.0);
    let albedo = 0.5f32;
    let grey = Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [albedo, albedo, albedo, 1.0],
        ..Default::default()
    };
    let cam = looking_down(6.0, 60f32.to_radians());
    let base = Light {
        name: String::new(),
        kind: LightKind::Point,
        position: [0.5, 2.0, -0.3],
        direction: [0.0, -1.0, 0.0],
        color: [1.0, 0.8, 0.6],
        intensity: 30.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    };
    let spot = Light { kind: LightKind::Spot, inner_cone_angle: 0.2, outer_cone_angle: 0.9, ..base.clone() };
    let sun = Light {
        kind: LightKind::Directional,
        direction: Vec3::new(0.3, -1.0, 0.2).normalize().into(),
        intensity: 3.0,
        ..base.clone()
    };
    let settings = PathSettings { size: (40, 40), spp: 16, max_bounces: 1, ..Default::default() };
    for light in [base, spot, sun] {
        let mut scene = scene_of(&[(&floor, grey.clone(), false)], cam);
        scene.lights.push(light.clone());
        let image = render(&gpu, &scene, &settings);
        // Closed form for the floor point under pixel position (x, y) (in pixels, fractional).
        let expected_at = |x: f32, y: f32| {
            let (w, h) = (settings.size.0 as f32, settings.size.1 as f32);
            let c = GpuCamera::new(&cam, settings.size);
            let ndc = (2.0 * x / w - 1.0, 1.0 - 2.0 * y / h);
            let d =
                (Vec3::from(c.forward) + ndc.0 * Vec3::from(c.right) + ndc.1 * Vec3::from(c.up)).normalize();
            let p = Vec3::from(cam.position) + d * (cam.position[1] / -d.y);
            let (wi, irradiance) = match light.kind {
                LightKind::Directional => (-Vec3::from(light.direction), light.intensity),
                _ => {
                    let to = Vec3::from(light.position) - p;
                    let mut e = light.intensity / to.length_squared();
                    if light.kind == LightKind::Spot {
                        let (co, ci) = (light.outer_cone_angle.cos(), light.inner_cone_angle.cos());
                        let cos = (-to.normalize()).dot(Vec3::from(light.direction));
                        let s = ((cos - co) / (ci - co)).clamp(0.0, 1.0);
                        e *= s * s;
                    }
                    (to.normalize(), e)
                }
            };
            albedo / std::f32::consts::PI * irradiance * wi.y.max(0.0) * light.color[0]
        };
        let mut checked = 0;
        for y in 0..settings.size.1 {
            for x in 0..settings.size.0 {
                let (fx, fy) = (x as f32, y as f32);
                let centre = expected_at(fx + 0.5, fy + 0.5);
                // Across the pixel the closed form must be nearly constant for a fair comparison
                // (the spot's cone edge is not): compare the corners.
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                    .map(|(dx, dy)| expected_at(fx + dx, fy + dy));
                let spread = corners.iter().map(|c| (c - centre).abs()).fold(0.0f32, f32::max);
                if spread > 0.25 * centre.max(1e-3) {
                    continue;
                }
                let got = image.mean[(y * settings.size.0 + x) as usize][0];
                assert!(
                    (got - centre).abs() <= 0.01 * centre + spread + 1e-5,
                    "{:?} pixel ({x},{y}): {got} vs {centre}",
                    light.kind
                );
                checked += 1;
            }
        }
        assert!(checked > 800, "{:?}: only {checked} pixels checked", light.kind);
    }
}

fn lambert_sphere_scene(albedo: f32) -> (Scene, Camera) {
    let sphere = icosphere(4, Vec3::ZERO, 1.0);
    let material = Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [albedo, albedo, albedo, 1.0],
        ..Default::default()
    };
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 35.0);
    (scene_of(&[(&sphere, material, false)], cam), cam)
}

/// The furnace again, now through a constant environment MAP with importance sampling and MIS:
/// the two strategies' weights must still sum to one, so the sphere stays exactly 1 on average.
#[test]
fn white_furnace_through_an_importance_sampled_environment_map() {
    let gpu = Gpu::new();
    let (scene, cam) = lambert_sphere_scene(1.0);
    let map = umbra::environment::EnvironmentMap::from_texels("constant", 8, 4, vec![[1.0; 3]; 32]).unwrap();
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let settings =
        PathSettings { size: (40, 40), spp: 64, env: [1.0; 3], max_bounces: 4, ..Default::default() };
    let image = path_trace(&gpu, &device_scene, &cam, &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0);
    let cosines = sphere_cosines(&cam, settings.size);
    let on_sphere: Vec<f32> = image
        .mean
        .iter()
        .zip(&cosines)
        .filter(|(_, c)| c.is_some_and(|c| c > 0.3))
        .map(|(p, _)| p[1])
        .collect();
    let mean = on_sphere.iter().sum::<f32>() / on_sphere.len() as f32;
    eprintln!("furnace through the map: {} pixels, mean {mean}", on_sphere.len());
    assert!(on_sphere.len() > 500);
    assert!((mean - 1.0).abs() < 0.005, "mean {mean}");
}

/// A real HDR with a sun above 30,000: environment NEE with MIS and BSDF sampling alone are
/// both unbiased, so a grey Lambert sphere must come out the same either way (z-test on the
/// image mean, significance 0.001).
#[test]
fn environment_sampling_agrees_with_bsdf_sampling_on_a_real_hdr() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(std::path::Path::new(path)).unwrap();
    let peak = map.texels.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    assert!(peak > 1000.0, "the test map should have a sun; peak {peak}");
    let gpu = Gpu::new();
    let (scene, cam) = lambert_sphere_scene(0.5);
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let run = |env_nee: bool, spp: u32| {
        let settings = PathSettings {
            size: (24, 24),
            spp,
            env: [1.0; 3],
            env_nee,
            max_bounces: 3,
            seed: 3,
            ..Default::default()
        };
        path_trace(&gpu, &device_scene, &cam, &settings, |_, _| {}).unwrap()
    };
    let (nee, bsdf) = (run(true, 64), run(false, 1024));
    let summary = |image: &PathImage| {
        let var = image.variance_of_mean();
        let n = image.mean.len() as f64;
        let mean = image.mean.iter().map(|p| p[1] as f64).sum::<f64>() / n;
        let var_of_mean = var.iter().map(|v| v[1] as f64).sum::<f64>() / (n * n);
        (mean, var_of_mean)
    };
    let ((m1, v1), (m2, v2)) = (summary(&nee), summary(&bsdf));
    let z = (m1 - m2) / (v1 + v2).sqrt();
    eprintln!("image mean: NEE+MIS {m1:.4} (var {v1:.2e}), BSDF only {m2:.4} (var {v2:.2e}), z {z:.2}");
    assert!(z.abs() < 3.29, "the strategies disagree: z = {z}");
}

/// One light sample per scattering event serves the environment map and the emissive triangles
/// (picked with probability `env_pick`, by their power): a Lambert sphere under the sunny sky with
/// a glowing panel beside it, where the pick is strictly between the two. MIS, light sampling
/// alone and BSDF sampling alone agree (z-tests of the image means, Šidák over the two
/// comparisons at family α = 0.001). Seen to fail when the map's light samples leave the pick's
/// probability out of their pdf (z = −3.85); the same omission in the MIS weights (of rays that
/// escape to the map or hit an emitter) biases less than this test's noise (|z| ≤ 0.62).
#[test]
fn one_light_sample_serves_the_environment_and_the_emitters() {
    use umbra::passes::pathtrace::{PathTracePass, Strategy};
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/reference/sky-128x64.exr");
    let map = umbra::environment::EnvironmentMap::load(std::path::Path::new(path)).unwrap();
    let gpu = Gpu::new();
    let sphere = icosphere(3, Vec3::ZERO, 1.0);
    let lambert = Material {
        metallic: 0.0,
        specular_factor: 0.0,
        base_color_factor: [0.7, 0.7, 0.7, 1.0],
        ..Default::default()
    };
    let panel = Mesh {
        positions: vec![
            Vec3::new(1.8, -0.6, -0.6),
            Vec3::new(1.8, -0.6, 0.6),
            Vec3::new(1.8, 0.6, 0.6),
            Vec3::new(1.8, 0.6, -0.6),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let glow =
        Material { base_color_factor: [0.0, 0.0, 0.0, 1.0], emissive: [30.0; 3], ..Default::default() };
    let cam = camera(Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO, 45.0);
    let scene = scene_of(&[(&sphere, lambert, false), (&panel, glow, false)], cam);
    let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
    device_scene.set_environment(&gpu, &map).unwrap();
    let settings = |strategy: Strategy, spp: u32| PathSettings {
        size: (24, 24),
        spp,
        env: [1.0; 3],
        max_bounces: 3,
        seed: 5,
        strategy,
        ..Default::default()
    };
    let pick = PathTracePass::env_pick(&device_scene, &settings(Strategy::Mis, 1));
    eprintln!(
        "env_pick {pick} (map {}, emitters {})",
        device_scene.env_luminance, device_scene.emissive_power
    );
    assert!(pick > 0.1 && pick < 0.9, "the test wants both kinds of light sampled: env_pick {pick}");
    let without_map = PathSettings { env_nee: false, ..settings(Strategy::Mis, 1) };
    assert_eq!(PathTracePass::env_pick(&device_scene, &without_map), 0.0, "no map sampling, no pick of it");
    let summary = |strategy: Strategy, spp: u32| {
        let image = path_trace(&gpu, &device_scene, &cam, &settings(strategy, spp), |_, _| {}).unwrap();
        assert_eq!(image.nonfinite_samples, 0);
        let n = image.mean.len() as f64;
        let mean = image.mean.iter().map(|p| p[1] as f64).sum::<f64>() / n;
        let var = image.variance_of_mean().iter().map(|v| v[1] as f64).sum::<f64>() / (n * n);
        (mean, var)
    };
    let (mis, mis_var) = summary(Strategy::Mis, 256);
    for (strategy, spp) in [(Strategy::Light, 256), (Strategy::Bsdf, 2048)] {
        let (m, v) = summary(strategy, spp);
        let z = (m - mis) / (v + mis_var).sqrt();
        eprintln!("{strategy:?}: {m:.5} against MIS {mis:.5}: z = {z:.2}");
        assert!(z.abs() < 3.48, "{strategy:?} disagrees with MIS: z = {z:.2}");
    }
}

/// A base-colour texture on a Lambert quad facing the camera under a constant environment of 1:
/// each pixel is exactly the linearised texel its UV selects, through each glTF wrap mode
/// (UVs run from −0.5 to 1.5 across the quad) and a KHR_texture_transform offset.
#[test]
fn textures_wrap_decode_and_transform() {
    use umbra::scene::{Filter, Sampler, Texture, TextureRef, Wrap};
    let gpu = Gpu::new();
    // 2×2 texels: red, green / blue, white (sRGB 200 = linear 0.578).
    let texels: [[u8; 4]; 4] = [[200, 0, 0, 255], [0, 200, 0, 255], [0, 0, 200, 255], [200, 200, 200, 255]];
    let linear = |c: u8| umbra::color::srgb_decode(c as f32 / 255.0);
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0); // sees x, y in about ±0.83
    for (wrap, offset) in
        [(Wrap::Repeat, 0.0), (Wrap::ClampToEdge, 0.0), (Wrap::MirroredRepeat, 0.0), (Wrap::Repeat, 0.5)]
    {
        let material = Material {
            metallic: 0.0,
            specular_factor: 0.0,
            base_color_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: umbra::scene::texture_transform([offset, 0.0], 0.0, [1.0, 1.0]),
                scale: 1.0,
            }),
            ..Default::default()
        };
        let mut scene = scene_of(&[(&quad, material, false)], cam);
        // UV = (x + 1) - 0.5 across, v downwards: (−0.5, −0.5) at the top left.
        scene.uv0 = scene.positions.iter().map(|p| [p[0] + 0.5, 0.5 - p[1]]).collect();
        scene.textures.push(Texture {
            name: "checker".into(),
            width: 2,
            height: 2,
            rgba8: texels.concat(),
            srgb: true,
            sampler: Sampler {
                wrap_s: wrap,
                wrap_t: wrap,
                mag_filter: Filter::Nearest,
                min_filter: Filter::Nearest,
                mipmaps: false,
                mipmap_filter: Filter::Nearest,
            },
        });
        let settings =
            PathSettings { size: (32, 32), spp: 4, env: [1.0; 3], max_bounces: 1, ..Default::default() };
        let image = render(&gpu, &scene, &settings);
        let mut checked = 0;
        for y in 0..32u32 {
            for x in 0..32u32 {
                let d = pixel_ray(&cam, settings.size, x, y);
                let p = Vec3::from(cam.position) + d * (cam.position[2] / -d.z);
                let uv = [p.x + 0.5 + offset, 0.5 - p.y];
                // Skip pixels whose footprint (±1 pixel) straddles a texel edge.
                let pixel = 2.0 * 0.83 / 32.0;
                let near_edge = uv.iter().any(|c| ((c * 2.0).round() - c * 2.0).abs() < 2.0 * pixel);
                if near_edge {
                    continue;
                }
                let wrap_coord = |c: f32| -> usize {
                    let i = (c * 2.0).floor() as i32;
                    let i = match wrap {
                        Wrap::Repeat => i.rem_euclid(2),
                        Wrap::ClampToEdge => i.clamp(0, 1),
                        Wrap::MirroredRepeat => {
                            let m = i.rem_euclid(4);
                            if m < 2 {
                                m
                            } else {
                                3 - m
                            }
                        }
                    };
                    i as usize
                };
                let t = texels[wrap_coord(uv[1]) * 2 + wrap_coord(uv[0])];
                let got = image.mean[(y * 32 + x) as usize];
                for c in 0..3 {
                    let expected = linear(t[c]);
                    assert!(
                        (got[c] - expected).abs() < 1e-4,
                        "{wrap:?} offset {offset} pixel ({x},{y}) uv {uv:?}: {got:?} vs texel {t:?}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 300, "{wrap:?}: only {checked} pixels checked");
    }
}

/// A white directional light shining along `direction` with `intensity`.
fn sun(direction: [f32; 3], intensity: f32) -> umbra::scene::Light {
    umbra::scene::Light {
        name: String::new(),
        kind: umbra::scene::LightKind::Directional,
        position: [0.0; 3],
        direction,
        color: [1.0; 3],
        intensity,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    }
}

/// A normal map on a quad facing the camera, lit by a directional light from the +x side: the
/// shading normal is the map's tangent-space normal through (tangent, bitangent, normal), so the
/// Lambert radiance follows the closed form for the tilted normal, scaled as `normalTexture.scale`
/// says; tilting towards the tangent's +x brightens, towards −x darkens.
#[test]
fn normal_maps_tilt_the_shading_normal() {
    use umbra::scene::{TextureRef, IDENTITY_TRANSFORM};
    let gpu = Gpu::new();
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0);
    let light_dir = Vec3::new(1.0, 0.0, 1.0).normalize(); // towards the light
    let albedo = 0.8f32;
    for (tilt, scale) in [(0.5f32, 1.0f32), (-0.5, 1.0), (0.5, 0.5)] {
        let texel = [
            ((tilt.sin() * 0.5 + 0.5) * 255.0).round() as u8,
            128,
            ((tilt.cos() * 0.5 + 0.5) * 255.0).round() as u8,
            255,
        ];
        let material = Material {
            metallic: 0.0,
            specular_factor: 0.0,
            base_color_factor: [albedo, albedo, albedo, 1.0],
            normal_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
                transform: IDENTITY_TRANSFORM,
                scale,
            }),
            ..Default::default()
        };
        let mut scene = scene_of(&[(&quad, material, false)], cam);
        scene.uv0 = scene.positions.iter().map(|p| [p[0] * 0.5 + 0.5, 0.5 - p[1] * 0.5]).collect();
        scene.tangents = vec![[1.0, 0.0, 0.0, 1.0]; scene.positions.len()];
        scene.textures.push(common::row_texture("tilt", &[texel]));
        scene.lights.push(sun((-light_dir).into(), 2.0));
        let settings = PathSettings { size: (16, 16), spp: 2, max_bounces: 1, ..Default::default() };
        let image = render(&gpu, &scene, &settings);
        let decoded = Vec3::new(texel[0] as f32, texel[1] as f32, texel[2] as f32) / 255.0 * 2.0 - Vec3::ONE;
        let mapped = Vec3::new(decoded.x * scale, decoded.y * scale, decoded.z).normalize();
        let expected = albedo / std::f32::consts::PI * 2.0 * mapped.dot(light_dir).max(0.0);
        let got = image.mean[8 * 16 + 8][0];
        eprintln!(
            "tilt {tilt} scale {scale}: {got} (flat would be {})",
            albedo / std::f32::consts::PI * 2.0 * light_dir.z
        );
        assert!((got - expected).abs() < 1e-3 * expected, "tilt {tilt} scale {scale}: {got} vs {expected}");
    }
}

/// Each texture slot is read on its own: a quad whose material has a constant texture in one
/// slot only (base colour, metallic-roughness or emissive) renders as the same material with the
/// texel folded into the slot's factor. The kernels are specialised per slot (a slot no material
/// fills is compiled out), so a slot left out of the specialisation would render the factor alone.
#[test]
fn each_texture_slot_is_read_alone() {
    use umbra::scene::{TextureRef, IDENTITY_TRANSFORM};
    let gpu = Gpu::new();
    let quad = facing_quad();
    let cam = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 45.0);
    // Linear texels: n/255 is exact as the stored unorm16 (257 n / 65535).
    let texel = [128u8, 64, 200, 255];
    let t = texel.map(|c| c as f32 / 255.0);
    let slot = || Some(TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 });
    let base = Material {
        base_color_factor: [0.9, 0.8, 0.7, 1.0],
        metallic: 0.5,
        roughness: 0.6,
        emissive: [0.0; 3],
        ..Default::default()
    };
    let cases = [
        (
            "base colour",
            Material { base_color_texture: slot(), ..base.clone() },
            Material { base_color_factor: [0.9 * t[0], 0.8 * t[1], 0.7 * t[2], 1.0], ..base.clone() },
        ),
        (
            "metallic-roughness",
            Material { metallic: 1.0, roughness: 1.0, metallic_roughness_texture: slot(), ..base.clone() },
            Material { metallic: t[2], roughness: t[1], ..base.clone() },
        ),
        (
            "emissive",
            Material { emissive: [2.0, 1.0, 0.5], emissive_texture: slot(), ..base.clone() },
            Material { emissive: [2.0 * t[0], t[1], 0.5 * t[2]], ..base.clone() },
        ),
    ];
    for (name, textured, folded) in cases {
        let images: Vec<PathImage> = [textured, folded]
            .into_iter()
            .map(|material| {
                let mut scene = scene_of(&[(&quad, material, false)], cam);
                scene.uv0 = scene.positions.iter().map(|p| [p[0] * 0.5 + 0.5, 0.5 - p[1] * 0.5]).collect();
                scene.textures.push(common::row_texture("constant", &[texel]));
                scene.lights.push(sun([-0.5, -0.3, -1.0], 3.0));
                let settings = PathSettings { size: (16, 16), spp: 4, max_bounces: 1, ..Default::default() };
                render(&gpu, &scene, &settings)
            })
            .collect();
        let centre = images[1].mean[8 * 16 + 8];
        assert!(centre[0] > 0.01, "{name}: the quad is lit ({centre:?})");
        for (i, (a, b)) in images[0].mean.iter().zip(&images[1].mean).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-4 * b[c].abs().max(1e-3),
                    "{name}: pixel {i} channel {c}: textured {} vs factor {}",
                    a[c],
                    b[c]
                );
            }
        }
    }
}

/// Clear, smooth, white glass of ior 1.5: refracting (`volume`) or thin-walled.
fn clear_glass(volume: bool) -> Material {
    Material {
        base_color_factor: [1.0; 4],
        metallic: 0.0,
        roughness: 0.0,
        transmission_factor: 1.0,
        ior: 1.5,
        volume,
        double_sided: true,
        ..Default::default()
    }
}

/// KHR_materials_volume's attenuation, Beer–Lambert in the path tracer: a unit cube of smooth
/// glass (ior 1.5: F = 0.04 at normal incidence) seen straight down through its top and bottom
/// faces under a constant sky of 1. Light crossing the cube keeps a = exp(−σ) per crossing,
/// σ = −ln(colour)/distance, and bounces between the faces, so the cube shows
/// F + (1 − F)² a / (1 − a F) (every exit sees the sky); for colour (0.5, 0.25, 0.8) at distance
/// 2, a = √colour. The image's mean against it per channel, z-test at significance 1e-4 with the
/// path tracer's own variance. With ior 1 (no interface: F = 0) the cube shows a itself, with no
/// NaN (the refraction half vector is 0/0 there). Controls (each a test of the test): an
/// infinite distance gives 1 (a = 1); thin-walled glass (no volume) ignores the attenuation it
/// carries and gives 1.
#[test]
fn volume_attenuation_is_beer_lambert() {
    let gpu = Gpu::new();
    let cube = common::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5));
    let cam = looking_down(3.0, 2f32.to_radians());
    let colour = [0.5f64, 0.25, 0.8];
    let glass = |volume: bool, distance: f32| Material {
        attenuation_color: colour.map(|c| c as f32),
        attenuation_distance: distance,
        ..clear_glass(volume)
    };
    let settings = PathSettings { size: (8, 8), spp: 64, env: [1.0; 3], ..Default::default() };
    let check = |material: Material, expected: [f64; 3], what: &str| {
        let scene = common::build_with("glass cube", &[(cube.clone(), material)], vec![], cam);
        let image = render(&gpu, &scene, &settings);
        let var = image.variance_of_mean();
        let n = image.mean.len() as f64;
        for c in 0..3 {
            let mean = image.mean.iter().map(|p| p[c] as f64).sum::<f64>() / n;
            let sd = (var.iter().map(|v| v[c] as f64).sum::<f64>()).sqrt() / n;
            // The model takes every ray as straight down: the corners' obliquity (1/cos θ ≤
            // 1.0003 more glass) is below 1e-4 of the value, the floor of the deviation's scale.
            let z = (mean - expected[c]) / sd.max(1e-4 * expected[c]);
            eprintln!("{what}, channel {c}: mean {mean:.5}, expected {:.5}, z {z:.2}", expected[c]);
            assert!(z.abs() < 3.89, "{what}, channel {c}: mean {mean} vs {} (z = {z})", expected[c]);
        }
    };
    let f = 0.04f64;
    let seen = |a: f64| f + (1.0 - f) * (1.0 - f) * a / (1.0 - a * f);
    check(glass(true, 2.0), colour.map(|c| seen(c.sqrt())), "attenuating volume");
    check(glass(true, f32::INFINITY), [1.0; 3], "infinite attenuation distance");
    // ior 1: no interface (F = 0 at normal incidence), one crossing, no NaN (render checks).
    check(Material { ior: 1.0, ..glass(true, 2.0) }, colour.map(f64::sqrt), "ior 1 volume");
    check(glass(false, 2.0), [1.0; 3], "thin-walled glass");
}

/// A clear, smooth glass sphere (KHR_materials_transmission; refracting with
/// KHR_materials_volume, or thin-walled) under a constant environment of 1 is 1 on average: at
/// every interface reflection and transmission share the energy (F + (1 − F)), radiance scales
/// by η² inside and back on the way out, and total internal reflection keeps what cannot leave.
/// z-test of the mean over the sphere's interior pixels against 1 at significance 1e-4, plus a
/// 1 % bound. (A sphere whose `front` or η were inverted still conserves energy: the lens test
/// below catches that.)
#[test]
fn white_furnace_glass_spheres_are_one() {
    let gpu = Gpu::new();
    let sphere = icosphere(4, Vec3::ZERO, 1.0);
    let cam = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 35.0);
    for volume in [true, false] {
        let glass = clear_glass(volume);
        let scene = scene_of(&[(&sphere, glass, true)], cam);
        let settings =
            PathSettings { size: (40, 40), spp: 64, env: [1.0; 3], max_bounces: 64, ..Default::default() };
        let image = render(&gpu, &scene, &settings);
        let cosines = sphere_cosines(&cam, settings.size);
        let variance = image.variance_of_mean();
        let (mut sum, mut var, mut n) = (0.0f64, 0.0f64, 0usize);
        for (i, p) in image.mean.iter().enumerate() {
            if cosines[i].is_some_and(|c| c > 0.3) {
                sum += p[1] as f64;
                var += variance[i][1] as f64;
                n += 1;
            }
        }
        let mean = sum / n as f64;
        // The standard error, floored at 1e-5 for the f32 running mean's own rounding (the thin
        // sphere transmits almost every sample with weight exactly 1, so its variance is tiny).
        let z = (mean - 1.0) / (var / (n * n) as f64 + 1e-10).sqrt();
        eprintln!("glass furnace (volume {volume}): {n} pixels, mean {mean:.4}, z {z:.2}");
        assert!(n > 400, "only {n} pixels");
        assert!(z.abs() < 3.89 && (mean - 1.0).abs() < 0.01, "volume {volume}: mean {mean}, z {z}");
    }
}

/// Refraction bends light: a solid glass ball (η = 1.5) is a lens that images the environment
/// upside down (its focus lies 1.5 radii from the centre, so rays through its upper half leave
/// heading down), while a thin-walled ball lets rays through unbent. Under a sky that is red above
/// the horizon and blue below, pixels just above the ball's centre are blue through solid glass
/// and red through a thin wall.
#[test]
fn solid_glass_inverts_the_sky_and_thin_glass_does_not() {
    let gpu = Gpu::new();
    let sphere = icosphere(5, Vec3::ZERO, 1.0);
    let cam = camera(Vec3::new(0.0, 0.0, 6.0), Vec3::ZERO, 25.0);
    // Equirectangular, row 0 at the top: red above the horizon, blue below.
    let texels = [vec![[1.0, 0.0, 0.0]; 8], vec![[0.0, 0.0, 1.0]; 8]].concat();
    let map = umbra::environment::EnvironmentMap::from_texels("red over blue", 8, 2, texels).unwrap();
    let size = (48, 48);
    let mut colour_above_centre = Vec::new();
    for volume in [true, false] {
        let glass = clear_glass(volume);
        let scene = scene_of(&[(&sphere, glass, true)], cam);
        let mut device_scene = GpuScene::upload(&gpu, &scene).unwrap();
        device_scene.set_environment(&gpu, &map).unwrap();
        let settings = PathSettings { size, spp: 32, env: [1.0; 3], max_bounces: 16, ..Default::default() };
        let image = path_trace(&gpu, &device_scene, &cam, &settings, |_, _| {}).unwrap();
        assert_eq!(image.nonfinite_samples, 0);
        // The ball spans about ±13 pixels around the centre: rows 3–8 above it, columns ±3.
        let (mut red, mut blue) = (0.0, 0.0);
        for y in size.1 / 2 - 8..size.1 / 2 - 3 {
            for x in size.0 / 2 - 3..size.0 / 2 + 3 {
                let p = image.mean[(y * size.0 + x) as usize];
                red += p[0];
                blue += p[2];
            }
        }
        eprintln!("volume {volume}: red {red:.2}, blue {blue:.2} above the centre");

        colour_above_centre.push((red, blue));
    }
    let (solid, thin) = (colour_above_centre[0], colour_above_centre[1]);
    assert!(solid.1 > 4.0 * solid.0, "solid glass should show the blue ground above its centre: {solid:?}");
    assert!(thin.0 > 4.0 * thin.1, "thin glass should show the red sky above its centre: {thin:?}");
}

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

/// A point light behind rough thin glass shines through it: next-event estimation covers the
/// side below a transmitting surface (a delta light has no other strategy; before, the sheet
/// stayed black). A point light of intensity 1 one unit below a rough (α = 0.25) thin sheet,
/// the camera one unit above it looking down through a 2° field: each pixel equals
/// f_t(wo, wi) |cos θi| / d², f_t the thin-walled lobe of bsdf.glsl (the GGX reflection lobe
/// mirrored through the sheet, times 1 − F), averaged over the pixel (4×4 points), within 0.5 %.
#[test]
fn punctual_light_shines_through_rough_thin_glass() {
    let gpu = Gpu::new();
    let sheet = floor_quad(2.0);
    let glass = Material { roughness: 0.5, ..clear_glass(false) };
    let cam = looking_down(1.0, 2f32.to_radians());
    let mut scene = scene_of(&[(&sheet, glass, false)], cam);
    let light_pos = Vec3::new(0.0, -1.0, 0.0);
    scene.lights.push(umbra::scene::Light {
        name: "below".into(),
        kind: umbra::scene::LightKind::Point,
        position: light_pos.into(),
        direction: [0.0, 1.0, 0.0],
        color: [1.0; 3],
        intensity: 1.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    });
    let size = (8, 8);
    let settings = PathSettings { size, spp: 16, env: [0.0; 3], max_bounces: 1, ..Default::default() };
    let image = render(&gpu, &scene, &settings);

    let alpha = 0.25f64;
    let a2 = alpha * alpha;
    let g1 = |c: f64| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
    let c = GpuCamera::new(&cam, size);
    let v3 = |a: [f32; 3]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (origin, f, r, u) = (glam::DVec3::new(0.0, 1.0, 0.0), v3(c.forward), v3(c.right), v3(c.up));
    let radiance = |sx: f64, sy: f64| {
        let ndc = (2.0 * sx / size.0 as f64 - 1.0, 1.0 - 2.0 * sy / size.1 as f64);
        let d = (f + ndc.0 * r + ndc.1 * u).normalize();
        let p = origin + d * (origin.y / -d.y);
        let wo = -d;
        let to_light = light_pos.as_dvec3() - p;
        let wi = to_light.normalize();
        let wm = glam::DVec3::new(wi.x, -wi.y, wi.z); // mirrored to wo's side
        let h = (wo + wm).normalize();
        let fresnel = 0.04 + 0.96 * (1.0 - wo.dot(h)).powi(5);
        let d_ggx = a2 / (std::f64::consts::PI * (h.y * h.y * (a2 - 1.0) + 1.0).powi(2));
        let vis = g1(wo.y) * g1(wm.y) / (4.0 * wo.y * wm.y);
        (1.0 - fresnel) * d_ggx * vis * wi.y.abs() / to_light.length_squared()
    };
    let mut worst = 0.0f64;
    for y in 0..size.1 {
        for x in 0..size.0 {
            let expected = (0..16)
                .map(|k| {
                    radiance(
                        x as f64 + (k % 4) as f64 * 0.25 + 0.125,
                        y as f64 + (k / 4) as f64 * 0.25 + 0.125,
                    )
                })
                .sum::<f64>()
                / 16.0;
            let got = image.mean[(y * size.0 + x) as usize][1] as f64;
            worst = worst.max((got / expected - 1.0).abs());
        }
    }
    eprintln!("point light through rough thin glass: worst relative error {worst:.2e}");
    assert!(worst < 5e-3, "pixels differ from f_t |cos| / d² by up to {:.2} %", worst * 100.0);
}

/// A point light for the many-light tests.
fn point_light(position: [f32; 3], color: [f32; 3], intensity: f32) -> umbra::scene::Light {
    umbra::scene::Light {
        name: String::new(),
        kind: umbra::scene::LightKind::Point,
        position,
        direction: [0.0, -1.0, 0.0],
        color,
        intensity,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::PI,
    }
}

/// 20,000 copies of a light, each 1/20,000 as bright, light the floor as the one light does.
/// Beyond 16 lights shading samples 16 by power (here each draw is exact: the lights are alike),
/// so the work per sample is bounded: a shadow ray for every light ran into llvmpipe's limit on
/// loop iterations per invocation and stopped, leaving the floor 35 % too dark.
#[test]
fn many_punctual_lights_are_all_counted() {
    let gpu = Gpu::new();
    let floor = floor_quad(20.0);
    let grey =
        Material { metallic: 0.0, specular_factor: 0.0, base_color_factor: [0.5; 4], ..Default::default() };
    let settings = PathSettings { size: (8, 8), spp: 1, max_bounces: 1, ..Default::default() };
    let lit = |count: usize| {
        let mut scene = scene_of(&[(&floor, grey.clone(), false)], looking_down(6.0, 10f32.to_radians()));
        scene.lights = vec![point_light([0.0, 2.0, 0.0], [1.0; 3], 30.0 / count as f32); count];
        render(&gpu, &scene, &settings).mean
    };
    let (one, many) = (lit(1), lit(20_000));
    for (i, (a, b)) in one.iter().zip(&many).enumerate() {
        assert!(a[0] > 0.1 && (a[0] - b[0]).abs() <= 1e-4 * a[0], "pixel {i}: one light {a:?}, 20,000 {b:?}");
    }
}

/// Sampling punctual lights by power is unbiased: 16 lights (point, spot, directional; evaluated
/// one by one) and the same lights each split into four of a quarter the intensity (64: sampled,
/// 16 per shading point) give the same image in expectation. Same seed, so the camera jitter is
/// shared; the summed difference over all pixels, against its standard error from both images'
/// per-pixel variance (conservative: the jitter's share is common to both), must stay within
/// 4.5 sigma (two-sided p = 7e-6 for a correct sampler).
#[test]
fn sampled_punctual_lights_match_evaluating_each() {
    use umbra::scene::LightKind;
    let gpu = Gpu::new();
    let floor = floor_quad(6.0);
    let ball = icosphere(2, Vec3::new(0.3, 0.6, -0.2), 0.6);
    let grey =
        Material { metallic: 0.0, specular_factor: 0.0, base_color_factor: [0.5; 4], ..Default::default() };
    let mut rng = umbra::procedural::Rng::new(5);
    let mut lights: Vec<umbra::scene::Light> = (0..16)
        .map(|k| {
            let mut light = point_light(
                rng.in_box(Vec3::new(-3.0, 1.0, -3.0), Vec3::new(3.0, 3.0, 3.0)).into(),
                [rng.range(0.2, 1.0), rng.range(0.2, 1.0), rng.range(0.2, 1.0)],
                rng.range(1.0, 40.0),
            );
            if k % 4 == 1 {
                light.kind = LightKind::Spot;
                light.direction =
                    Vec3::new(rng.range(-0.3, 0.3), -1.0, rng.range(-0.3, 0.3)).normalize().into();
                (light.inner_cone_angle, light.outer_cone_angle) = (0.3, 0.8);
            }
            light
        })
        .collect();
    lights[15].kind = LightKind::Directional;
    lights[15].direction = Vec3::new(0.4, -1.0, 0.1).normalize().into();
    lights[15].intensity = 2.0;
    let settings = PathSettings { size: (32, 32), spp: 64, max_bounces: 1, ..Default::default() };
    let image = |lights: Vec<umbra::scene::Light>| {
        let mut scene = scene_of(
            &[(&floor, grey.clone(), false), (&ball, grey.clone(), false)],
            looking_down(5.0, 70f32.to_radians()),
        );
        scene.lights = lights;
        render(&gpu, &scene, &settings)
    };
    let split: Vec<_> = lights
        .iter()
        .flat_map(|l| {
            std::iter::repeat_n(umbra::scene::Light { intensity: l.intensity / 4.0, ..l.clone() }, 4)
        })
        .collect();
    let (each, sampled) = (image(lights), image(split));
    let spp = settings.spp as f64;
    let variance = |img: &PathImage, i: usize, c: usize| {
        let (m, q) = (img.mean[i][c] as f64, img.moment[i][c] as f64);
        (q - m * m).max(0.0) / (spp - 1.0)
    };
    for c in 0..3 {
        let (mut diff, mut var, mut total) = (0.0, 0.0, 0.0);
        for i in 0..each.mean.len() {
            diff += sampled.mean[i][c] as f64 - each.mean[i][c] as f64;
            var += variance(&sampled, i, c) + variance(&each, i, c);
            total += each.mean[i][c] as f64;
        }
        let z = diff / var.sqrt();
        eprintln!("channel {c}: difference {diff:.4} of {total:.1}, z = {z:.2}");
        assert!(
            var > 0.0 && z.abs() < 4.5,
            "channel {c}: sampled lights differ by {diff} (z = {z}) of {total}"
        );
    }
}

/// Renders `spp` samples of `scene` from its first camera into `target` (settings otherwise
/// `PathSettings::default()`'s at the target's size) and returns the target's counters.
fn render_into(gpu: &Gpu, scene: &Scene, target: &PathTarget, spp: u32) -> PathStats {
    let device_scene = GpuScene::upload(gpu, scene).unwrap();
    let passes = Passes::new(gpu, &device_scene);
    let camera = scene.camera(None).unwrap();
    let settings = PathSettings { size: target.size, spp, ..PathSettings::default() };
    gpu.submit(|cmd| passes.record_path_samples(cmd, &device_scene, &camera, target, &settings, 0, spp))
        .unwrap();
    target.stats.read::<PathStats>(gpu).unwrap()[0]
}

/// The megakernel's lane counts (`PathTarget::with_lane_counts`, the diagnostic behind
/// `umbra-bench paths --lanes`): they leave the render bit for bit as it was; where every lane's
/// walks take as many iterations (an unlit plane filling the view: every path one segment, its
/// walk one iteration) every lane of every group counts, and the lanes' count is the segments'; where
/// walks differ (the Cornell box) groups wait for their slowest lane, and shadow rays, which only
/// some lanes trace at a time, keep fewer lanes busy than the segments' rays.
#[test]
fn lane_counts_leave_the_render_alone_and_see_idle_lanes() {
    let gpu = Gpu::new();
    let subgroup = gpu.info().subgroup_size;
    let size = (16, 16);

    let unlit = Material { unlit: true, ..Material::default() };
    let plane = scene_of(&[(&floor_quad(100.0), unlit, false)], looking_down(1.0, 1.0));
    let stats = render_into(&gpu, &plane, &PathTarget::new(&gpu, size).unwrap().with_lane_counts(), 4);
    assert_eq!(stats.segments(), 16 * 16 * 4, "every path ends on the unlit plane");
    assert_eq!(stats.walk_counts()[0], stats.segments(), "one walk-loop iteration per segment");
    assert_eq!(stats.busy_lanes(false, subgroup), Some(1.0), "{stats:?}");
    assert_eq!(stats.busy_lanes(true, subgroup), None, "no light: no shadow rays");
    // 14 columns: a subgroup is a 4 × 2 block of a workgroup's 8 × 8 pixels (pixel.glsl), so the
    // blocks over columns 12..16 have 2 of their 4 columns in the image and the others idle:
    // 24 full blocks and 8 half ones, 224 of 256 lanes busy.
    if subgroup == 8 {
        let narrow = PathTarget::new(&gpu, (14, 16)).unwrap().with_lane_counts();
        let stats = render_into(&gpu, &plane, &narrow, 4);
        assert_eq!(stats.busy_lanes(false, subgroup), Some(224.0 / 256.0), "{stats:?}");
    }

    let cornell = Scene::cornell_box();
    let plain = PathTarget::new(&gpu, size).unwrap();
    let counting = PathTarget::new(&gpu, size).unwrap().with_lane_counts();
    let without = render_into(&gpu, &cornell, &plain, 4);
    let with = render_into(&gpu, &cornell, &counting, 4);
    assert_eq!(without.walk_counts(), [0; 4], "a plain target counts nothing");
    assert_eq!(with.segments(), without.segments());
    for (a, b) in [
        (&plain.accum, &counting.accum),
        (&plain.moment, &counting.moment),
        (&plain.albedo, &counting.albedo),
    ] {
        let (a, b) = (a.read::<[f32; 4]>(&gpu).unwrap(), b.read::<[f32; 4]>(&gpu).unwrap());
        assert!(
            a.iter().zip(&b).all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits)),
            "the counts changed the render"
        );
    }
    let closest = with.busy_lanes(false, subgroup).unwrap();
    let any = with.busy_lanes(true, subgroup).expect("the ceiling light's shadow rays");
    assert!(with.walk_counts()[0] >= with.segments(), "{with:?}");
    assert!(closest > 0.2 && closest < 0.95, "closest-hit walks: {closest}");
    assert!(any > 0.0 && any < closest, "any-hit walks: {any} against {closest}");
}
