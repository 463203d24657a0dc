//! Punctual lights: closed forms, many lights, and sampling them by power.

use crate::common::Gpu;
use crate::{floor_quad, looking_down, render, scene_of};
use glam::Vec3;
use umbra::gpu::layout::GpuCamera;
use umbra::procedural::icosphere;
use umbra::render::{PathImage, PathSettings};
use umbra::scene::Material;

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
