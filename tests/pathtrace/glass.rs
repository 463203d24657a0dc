//! Transmission: Beer–Lambert volumes, glass furnaces, refraction, and punctual light through
//! rough thin glass.

use crate::common::Gpu;
use crate::{camera, common, floor_quad, looking_down, render, scene_of, sphere_cosines};
use glam::Vec3;
use umbra::gpu::layout::GpuCamera;
use umbra::gpu::scene::GpuScene;
use umbra::procedural::icosphere;
use umbra::render::{path_trace, PathSettings};
use umbra::scene::Material;

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
