//! `KHR_materials_anisotropy` in the hybrid against the path tracer.

use crate::common::Gpu;
use crate::{common, interior_pixels, render_pair, sky, sphere_scene, synthetic_map};
use umbra::scene::Scene;

/// `sphere_scene` made anisotropic (`KHR_materials_anisotropy`, `strength`, no rotation), its
/// tangents along the parallels (around +y; any at the poles).
fn anisotropic_sphere(metallic: f32, roughness: f32, strength: f32) -> Scene {
    let mut scene = sphere_scene([0.9; 3], metallic, roughness);
    scene.tangents = scene
        .normals
        .iter()
        .map(|n| {
            let t = glam::Vec3::Y.cross(glam::Vec3::from(*n)).try_normalize().unwrap_or(glam::Vec3::X);
            [t.x, t.y, t.z, 1.0]
        })
        .collect();
    scene.materials[0].anisotropy_strength = strength;
    scene
}

/// Mean |hybrid − path| over the interior pixels relative to the path tracer's mean (green).
fn interior_difference(
    hyb: &umbra::render::HybridImage,
    pt: &umbra::render::PathImage,
    view: &[glam::Vec3],
) -> f64 {
    let pixels = interior_pixels(&hyb.gbuffer, view);
    let mean: f64 = pixels.iter().map(|&(i, _)| pt.mean[i][1] as f64).sum::<f64>() / pixels.len() as f64;
    let diff: f64 = pixels.iter().map(|&(i, _)| (hyb.color[i][1] as f64 - pt.mean[i][1] as f64).abs()).sum();
    diff / pixels.len() as f64 / mean
}

/// `KHR_materials_anisotropy` in the hybrid against the path tracer, on one anisotropic metal
/// sphere (roughness 0.4, strength 0.8, the direction along the parallels), 64², hybrid 4×4
/// supersampled, path tracer 64 spp of direct light.
/// (a) Under a directional light alone, the hybrid shades through the same BSDF from its
///     G-buffer (the anisotropy's direction and strength in gb_layers): mean |hybrid − path| per
///     interior pixel within 2 % of the mean (the pixel filters' difference; the isotropic
///     sphere's, printed, is of the same size), while the isotropic sphere's path-traced image
///     differs from the anisotropic one by more than 10 % (the bound has power: the hybrid
///     without the anisotropy fails it).
/// (b) Under a sky (0.5 sin(elevation)), with and without the bright disc, the environment
///     through the bent normal (the Sample Viewer's approximation, the prefiltered map at the
///     base's roughness): the sphere's mean luminance against the path tracer's, relative error
///     within the bounds docs/methods.md's known approximations state (a regression bound: the
///     approximation's error is large, +16 to +38 % on the smooth sky, +150 to +200 % with the
///     disc, where the isotropic sphere's split sum is within 6 %).
#[test]
fn anisotropic_sphere_hybrid_matches_path_tracer() {
    let gpu = Gpu::new();
    let (size, spp) = ((64, 64), 64);
    let sun = common::light(
        umbra::scene::LightKind::Directional,
        glam::Vec3::ZERO,
        glam::Vec3::new(-0.4, -0.5, -1.0),
        3.0,
    );
    let mut images = Vec::new();
    for strength in [0.8, 0.0] {
        let mut scene = anisotropic_sphere(1.0, 0.4, strength);
        scene.lights = vec![sun.clone()];
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [0.0; 3], size, spp, true);
        let difference = interior_difference(&hyb, &pt, &view);
        eprintln!("directional light, strength {strength}: mean |hybrid − path| / mean {difference:.4}");
        assert!(
            difference < 0.02,
            "strength {strength}: hybrid differs from the path tracer by {difference}"
        );
        images.push((hyb, pt, view));
    }
    let ((_, aniso, view), (_, iso, _)) = (&images[0], &images[1]);
    let pixels = interior_pixels(&images[0].0.gbuffer, view);
    let mean: f64 = pixels.iter().map(|&(i, _)| aniso.mean[i][1] as f64).sum::<f64>() / pixels.len() as f64;
    let power: f64 =
        pixels.iter().map(|&(i, _)| (aniso.mean[i][1] - iso.mean[i][1]).abs() as f64).sum::<f64>()
            / pixels.len() as f64
            / mean;
    eprintln!("anisotropic vs isotropic path-traced: {power:.3}");
    assert!(power > 0.1, "the anisotropy changes the image by only {power}");

    let lum = |c: &[f32]| (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f64;
    let smooth = |d: [f64; 3]| if d[1] < 0.0 { [0.0; 3] } else { [0.5 * d[1], 0.45 * d[1], 0.4 * d[1]] };
    type Sky<'a> = &'a dyn Fn([f64; 3]) -> [f64; 3];
    let skies: [(&str, Sky); 2] = [("disc", &sky), ("smooth", &smooth)];
    for ((name, f), strength) in skies.iter().flat_map(|s| [(s, 0.8f32), (s, 0.5), (s, 0.0)]) {
        let map = synthetic_map(256, 128, f);
        let scene = anisotropic_sphere(1.0, 0.4, strength);
        let (hyb, pt, view) = render_pair(&gpu, &scene, Some(&map), [1.0; 3], size, spp, true);
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        let var = pt.variance_of_mean();
        let (mut h, mut p, mut v) = (0.0, 0.0, 0.0);
        for &(i, _) in &pixels {
            h += lum(&hyb.color[i]);
            p += lum(&pt.mean[i]);
            v += var[i][1] as f64;
        }
        let n = pixels.len() as f64;
        let (h, p, se) = (h / n, p / n, v.sqrt() / n);
        let error = (h - p) / p;
        eprintln!("sky {name}, strength {strength}: hybrid {h:.4}, path {p:.4} ± {se:.4}: relative error {error:+.4}");
        // The bounds docs/methods.md states (measured +0.38 / +0.16 smooth, +1.47 / +2.00 with the disc
        // at strength 0.8 / 0.5; the isotropic split sum's own +0.003 and −0.05).
        let bound = match (*name, strength > 0.0) {
            ("smooth", true) => 0.45,
            (_, true) => 2.2,
            _ => 0.06,
        };
        assert!(
            error.abs() < bound,
            "sky {name}, strength {strength}: the hybrid's error {error} exceeds {bound}"
        );
    }
}
