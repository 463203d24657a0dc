//! The denoiser (src/passes/denoise.rs) on images whose truth is known: a constant image and a
//! textured one on constant light pass unchanged; an albedo edge, a normal edge and a depth edge
//! survive; known noise loses most of its MSE (54× measured, 10× asserted); the filter is
//! deterministic; and the 4-spp Cornell box comes much closer to the converged reference
//! (tests/reference/cornell-48.exr). Each edge test also runs the filter without the weight it
//! relies on (or without demodulation) and requires that to fail its bound: the test can fail.
//!
//! Synthetic images are built as the path tracer builds its own: n samples per pixel, their
//! running mean and mean square, and first-hit AOVs (base colour, normal, distance).

mod common;

use common::{push_noisy_pixel, relative_mse, synthetic_image, Gpu, Rng};
use umbra::gpu::scene::GpuScene;
use umbra::render::{denoise, path_trace, DenoiseSettings, LobeSplitImage, PathImage, PathSettings};
use umbra::scene::Scene;

const SIZE: (u32, u32) = (64, 64);

/// What one pixel shows: true radiance, base colour, normal, distance.
#[derive(Clone, Copy)]
struct Truth {
    radiance: [f32; 3],
    albedo: [f32; 3],
    normal: [f32; 3],
    depth: f32,
}

/// An image of `spp` samples per pixel of `truth`, each sample the true radiance × (1 + `noise` g)
/// with g a standard normal number shared by the channels (a path's channels move together).
fn synthetic(
    truth: impl Fn(u32, u32) -> Truth,
    spp: u32,
    noise: f32,
    seed: u64,
) -> (PathImage, Vec<[f32; 3]>) {
    let mut rng = Rng(seed);
    let (w, h) = SIZE;
    let mut image = synthetic_image(SIZE, spp);
    let mut expected = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let t = truth(x, y);
            let normal_depth = [t.normal[0], t.normal[1], t.normal[2], t.depth];
            push_noisy_pixel(&mut image, &mut rng, noise as f64, t.radiance, t.albedo, normal_depth);
            expected.push(t.radiance);
        }
    }
    (image, expected)
}

/// A plane facing the camera at distance 2, lit by irradiance `e` (radiance = albedo × e).
fn plane(albedo: [f32; 3], e: f32) -> Truth {
    Truth { radiance: albedo.map(|a| a * e), albedo, normal: [0.0, 0.0, 1.0], depth: 2.0 }
}

fn mse(a: &[[f32; 4]], b: &[[f32; 3]]) -> f64 {
    let sum: f64 =
        a.iter().zip(b).map(|(p, q)| (0..3).map(|c| ((p[c] - q[c]) as f64).powi(2)).sum::<f64>()).sum();
    sum / (a.len() * 3) as f64
}

/// How far the edge between columns `edge − 1` and `edge` bled: per column within `band` of it,
/// the mean over the rows of the relative error (the noise averages out, a blur does not); the
/// largest of those, over the channels too.
fn edge_error(denoised: &[[f32; 4]], truth: &[[f32; 3]], edge: u32, band: u32) -> f32 {
    let mut worst = 0.0f32;
    for x in edge - band..edge + band {
        for c in 0..3 {
            let sum: f32 = (0..SIZE.1)
                .map(|y| {
                    let i = (y * SIZE.0 + x) as usize;
                    (denoised[i][c] - truth[i][c]) / truth[i][c]
                })
                .sum();
            worst = worst.max((sum / SIZE.1 as f32).abs());
        }
    }
    worst
}

#[test]
fn constant_images_pass_unchanged() {
    let gpu = Gpu::new();
    // A constant image, and a checkerboard texture under constant light: both noise-free.
    let constant = |_, _| plane([0.6, 0.5, 0.4], 0.8);
    let checker = |x: u32, y: u32| {
        plane(if (x / 4 + y / 4).is_multiple_of(2) { [0.9, 0.2, 0.1] } else { [0.1, 0.3, 0.8] }, 1.5)
    };
    for (name, truth) in [("constant", &constant as &dyn Fn(u32, u32) -> Truth), ("checker", &checker)] {
        let (image, expected) = synthetic(truth, 4, 0.0, 1);
        let out = denoise(&gpu, &image, &DenoiseSettings::default()).unwrap();
        let worst = out
            .color
            .iter()
            .zip(&expected)
            .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs() / q[c]))
            .fold(0.0f32, f32::max);
        eprintln!("{name}: largest relative change {worst:e}");
        assert!(worst < 1e-5, "{name}: a pixel changed by {worst} (relative)");
        assert!(out.color.iter().all(|p| p[3] == 1.0));
    }
}

/// A noisy plane whose left half has base colour 0.8, its right half 0.2, under the same light:
/// demodulated, the two halves are one signal, so the edge stays sharp (within 2 % in the four
/// columns beside it) while the noise goes. Without demodulation it blurs (the luminance weight
/// alone does not keep the halves apart at this noise): the test can fail.
#[test]
fn an_albedo_edge_survives() {
    let gpu = Gpu::new();
    let truth = |x: u32, _| plane(if x < 32 { [0.8; 3] } else { [0.2; 3] }, 1.0);
    let (image, expected) = synthetic(truth, 4, 0.3, 2);
    let raw: Vec<[f32; 4]> = image.mean.clone();
    let error = |settings: &DenoiseSettings| {
        let out = denoise(&gpu, &image, settings).unwrap();
        (edge_error(&out.color, &expected, 32, 2), mse(&out.color, &expected))
    };
    let (edge, denoised_mse) = error(&DenoiseSettings::default());
    let (blind_edge, _) = error(&DenoiseSettings { demodulate: false, ..Default::default() });
    let raw_mse = mse(&raw, &expected);
    eprintln!(
        "albedo edge: bled {edge:.4} (no demodulation {blind_edge:.4}); MSE {raw_mse:.3e} raw, \
         {denoised_mse:.3e} denoised"
    );
    assert!(edge < 0.02, "the albedo edge blurred: {edge}");
    assert!(blind_edge > 0.02, "the test cannot tell a blur: {blind_edge}");
    assert!(denoised_mse * 10.0 < raw_mse, "the noise stayed: {denoised_mse:e} vs {raw_mse:e}");
}

/// Two planes meeting at a crease (normals 60° apart, same distance, same base colour), lit
/// 0.5 and 0.35: too close in luminance for the luminance weight to keep apart at this noise,
/// the normal weight keeps the crease within 2 % in the four columns beside it; without it
/// (σ_n tiny, or no edge stopping) the two sides blur into each other.
#[test]
fn a_normal_edge_survives() {
    let gpu = Gpu::new();
    let s = 0.75f32.sqrt();
    let truth = |x: u32, _| {
        let mut t = plane([0.7; 3], if x < 32 { 0.5 / 0.7 } else { 0.35 / 0.7 });
        if x >= 32 {
            t.normal = [s, 0.0, 0.5];
        }
        t
    };
    let (image, expected) = synthetic(truth, 4, 0.3, 3);
    let error = |settings: &DenoiseSettings| {
        edge_error(&denoise(&gpu, &image, settings).unwrap().color, &expected, 32, 2)
    };
    let edge = error(&DenoiseSettings::default());
    let blind = error(&DenoiseSettings { sigma_normal: 1e-3, ..Default::default() });
    eprintln!("normal edge: worst relative error beside it {edge:.4} (normal weight off: {blind:.4})");
    assert!(edge < 0.02, "the crease blurred: {edge}");
    assert!(blind > 0.02, "the test cannot tell a blur: {blind}");
}

/// A near plane in front of a far one (distance 2 and 4, same normal and base colour), lit 0.5
/// and 0.4: the depth weight keeps the silhouette within 2 % in the four columns beside it;
/// without it (σ_z huge) the two blur into each other.
#[test]
fn a_depth_edge_survives() {
    let gpu = Gpu::new();
    let truth = |x: u32, _| {
        let mut t = plane([0.7; 3], if x < 32 { 0.5 / 0.7 } else { 0.45 / 0.7 });
        if x >= 32 {
            t.depth = 4.0;
        }
        t
    };
    let (image, expected) = synthetic(truth, 4, 0.3, 4);
    let error = |settings: &DenoiseSettings| {
        edge_error(&denoise(&gpu, &image, settings).unwrap().color, &expected, 32, 2)
    };
    let edge = error(&DenoiseSettings::default());
    let blind = error(&DenoiseSettings { sigma_depth: 1e9, ..Default::default() });
    eprintln!("depth edge: worst relative error beside it {edge:.4} (depth weight off: {blind:.4})");
    assert!(edge < 0.02, "the silhouette blurred: {edge}");
    assert!(blind > 0.02, "the test cannot tell a blur: {blind}");
}

/// The luminance weight is calibrated by the variance of the mean: on one plane, a step from 0.5
/// to 0.4 under noise of ±10 % per sample (16 samples: 4.5 standard deviations of the mean) is
/// kept (without the spatial variance floor, which would see the step itself as noise); a
/// variance taken 16× too large (the samples' rather than their mean's) or carried through the
/// iterations with linear rather than squared weights blurs it. Measured bleed: 0.58 % as
/// written, 3.8 % and 4.0 % with those two mistakes; the bound is 1 %.
#[test]
fn the_luminance_weight_follows_the_variance_of_the_mean() {
    let gpu = Gpu::new();
    let truth = |x: u32, _| plane([0.7; 3], if x < 32 { 0.5 / 0.7 } else { 0.4 / 0.7 });
    let (image, expected) = synthetic(truth, 16, 0.1, 8);
    let settings = DenoiseSettings { spatial_variance: false, ..Default::default() };
    let out = denoise(&gpu, &image, &settings).unwrap();
    let edge = edge_error(&out.color, &expected, 32, 2);
    let far = edge_error(&out.color, &expected, 16, 2);
    eprintln!("luminance step: bled {edge:.4} (away from it {far:.4})");
    assert!(edge < 0.01, "the luminance step blurred: {edge}");
}

/// The spatial variance floor (on by default) fades with samples: at 64 samples per pixel the
/// same step as above is kept, though the neighbours' spread, which holds the step itself, would
/// blur it at full weight (measured bleed: 0.36 % as written, 4.2 % with the floor unfaded; the
/// bound is 1 %).
#[test]
fn the_spatial_variance_floor_fades_with_samples() {
    let gpu = Gpu::new();
    let truth = |x: u32, _| plane([0.7; 3], if x < 32 { 0.5 / 0.7 } else { 0.4 / 0.7 });
    let (image, expected) = synthetic(truth, 64, 0.1, 9);
    let out = denoise(&gpu, &image, &DenoiseSettings::default()).unwrap();
    let edge = edge_error(&out.color, &expected, 32, 2);
    eprintln!("luminance step at 64 spp: bled {edge:.4}");
    assert!(edge < 0.01, "the luminance step blurred: {edge}");
}

/// Known noise (4 samples per pixel, each ±50 % relative, Gaussian) on a smoothly lit plane with
/// a few coloured regions: the MSE against the truth falls at least 10×.
#[test]
fn known_noise_loses_most_of_its_mse() {
    let gpu = Gpu::new();
    let truth = |x: u32, y: u32| {
        let albedo = match (x / 32, y / 32) {
            (0, 0) => [0.8, 0.3, 0.2],
            (1, 0) => [0.2, 0.7, 0.3],
            (0, 1) => [0.3, 0.3, 0.9],
            _ => [0.7, 0.7, 0.7],
        };
        let e = 0.5 + 1.5 * (x as f32 + 0.5 * y as f32) / 96.0;
        plane(albedo, e)
    };
    let (image, expected) = synthetic(truth, 4, 0.5, 5);
    let raw_mse = mse(&image.mean, &expected);
    let out = denoise(&gpu, &image, &DenoiseSettings::default()).unwrap();
    let denoised_mse = mse(&out.color, &expected);
    let factor = raw_mse / denoised_mse;
    eprintln!("known noise: MSE {raw_mse:.3e} raw, {denoised_mse:.3e} denoised: {factor:.1}x lower");
    assert!(factor >= 10.0, "MSE only {factor:.2}x lower");
}

/// [`synthetic`] with the path tracer's lobe split: each sample's diffuse part the pixel's base
/// colour × `e` × (1 + `noise` g), its specular part `highlight(x)` (not tinted by the base colour,
/// as a dielectric's) × (1 + `noise` g'), g and g' independent standard normal numbers.
fn synthetic_split(
    albedo: impl Fn(u32) -> [f32; 3],
    e: f32,
    highlight: impl Fn(u32) -> f32,
    spp: u32,
    noise: f32,
    seed: u64,
) -> (PathImage, Vec<[f32; 3]>) {
    let mut rng = Rng(seed);
    let (image, _) = synthetic(|x, _| plane(albedo(x), e), spp, 0.0, seed);
    let mut image =
        PathImage { lobe_split: Some(LobeSplitImage { specular: Vec::new(), split: Vec::new() }), ..image };
    let (mut mean, mut moment, mut expected) = (Vec::new(), Vec::new(), Vec::new());
    let luma = |c: [f64; 3]| 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
    for _y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let (a, h) = (albedo(x), highlight(x) as f64);
            let (mut sum, mut sum2, mut spec_sum) = ([0.0f64; 3], [0.0f64; 3], 0.0f64);
            let (mut d2, mut s2) = (0.0f64, 0.0f64);
            for _ in 0..spp {
                let g = 1.0 + noise as f64 * rng.normal();
                let spec = h * (1.0 + noise as f64 * rng.normal());
                let diffuse = a.map(|a| a as f64 * e as f64 * g);
                for c in 0..3 {
                    sum[c] += diffuse[c] + spec;
                    sum2[c] += (diffuse[c] + spec).powi(2);
                }
                spec_sum += spec;
                d2 += luma([0, 1, 2].map(|c| diffuse[c] / (a[c] as f64).max(0.01))).powi(2);
                s2 += spec * spec;
            }
            let n = spp as f64;
            mean.push([0, 1, 2, 3].map(|c| if c == 3 { spp as f32 } else { (sum[c] / n) as f32 }));
            moment.push([0, 1, 2, 3].map(|c| if c == 3 { 0.0 } else { (sum2[c] / n) as f32 }));
            let split = image.lobe_split.as_mut().unwrap();
            let spec_mean = (spec_sum / n) as f32;
            split.specular.push([spec_mean, spec_mean, spec_mean, (d2 / n) as f32]);
            split.split.push([1.0, 1.0, 1.0, (s2 / n) as f32]);
            expected.push(a.map(|a| a * e + h as f32));
        }
    }
    image.mean = mean;
    image.moment = moment;
    (image, expected)
}

/// A noisy plane whose left half has base colour 0.02, its right half 0.8, under the same light,
/// with a glossy highlight of 0.5 over both (a dielectric's: not tinted by the base colour).
/// Divided by the base colour, the highlight on the dark half becomes 25 (the lit surface 1): the
/// filter of the sum then smears the halves' highlights into each other (the textured scene's
/// failure, docs/history/2026-12-02.md, "the denoiser's lobe split"), while the lobe split divides
/// only the diffuse part by it and keeps the edge within 2 % in the four columns beside it. Both
/// halves lose most of their noise.
#[test]
fn the_lobe_split_keeps_a_highlight_off_a_dark_texel() {
    let gpu = Gpu::new();
    let albedo = |x: u32| if x < 32 { [0.02; 3] } else { [0.8; 3] };
    let (image, expected) = synthetic_split(albedo, 1.0, |_| 0.5, 4, 0.3, 8);
    let error = |settings: &DenoiseSettings| {
        let out = denoise(&gpu, &image, settings).unwrap();
        (edge_error(&out.color, &expected, 32, 2), mse(&out.color, &expected))
    };
    let (edge, denoised_mse) = error(&DenoiseSettings::default());
    let (summed_edge, summed_mse) = error(&DenoiseSettings { lobe_split: false, ..Default::default() });
    let raw_mse = mse(&image.mean, &expected);
    eprintln!(
        "highlight on a dark texel: edge bled {edge:.4} split, {summed_edge:.4} summed; MSE {raw_mse:.3e} raw, \
         {denoised_mse:.3e} split, {summed_mse:.3e} summed"
    );
    assert!(edge < 0.02, "the edge blurred with the split: {edge}");
    assert!(summed_edge > 0.02, "the test cannot tell the sum's failure: {summed_edge}");
    assert!(denoised_mse * 10.0 < raw_mse, "the noise stayed: {denoised_mse:e} vs {raw_mse:e}");
}

/// The path tracer's lobe split (`PathSettings::lobe_split`) leaves the estimate as it was (mean,
/// moment and AOVs bit for bit) and splits it by the lobes: on the Cornell box with every
/// material a metal the diffuse part is 0, with every material a dielectric without specular
/// reflection (`KHR_materials_specular` 0) the specular part is, and as glTF has it (dielectrics
/// with their 4 % reflection) both parts carry light.
#[test]
fn the_lobe_split_parts_are_the_lobes() {
    let gpu = Gpu::new();
    let settings = PathSettings { size: (32, 32), spp: 8, seed: 5, ..Default::default() };
    let split_settings = PathSettings { lobe_split: true, ..settings.clone() };
    // Per scene: the sums over the image of the diffuse and specular parts, and of the radiance
    // less the first hit's emission; the largest part below 0.
    let parts = |scene: &Scene| {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let plain = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
        let split = path_trace(&gpu, &gpu_scene, &camera, &split_settings, |_, _| {}).unwrap();
        assert!(plain.lobe_split.is_none());
        for (name, a, b) in [
            ("mean", &plain.mean, &split.mean),
            ("moment", &plain.moment, &split.moment),
            ("albedo", &plain.albedo, &split.albedo),
            ("emission", &plain.emission, &split.emission),
            ("normal_depth", &plain.normal_depth, &split.normal_depth),
        ] {
            assert!(a == b, "the split changed the {name}");
        }
        let specular = &split.lobe_split.as_ref().unwrap().specular;
        let (mut diffuse_sum, mut specular_sum, mut total, mut negative) = (0.0f64, 0.0f64, 0.0f64, 0.0f32);
        for ((m, e), s) in split.mean.iter().zip(&split.emission).zip(specular) {
            for c in 0..3 {
                let d = m[c] - e[c] - s[c];
                diffuse_sum += d as f64;
                specular_sum += s[c] as f64;
                total += (m[c] - e[c]) as f64;
                negative = negative.max(-d).max(-s[c]);
            }
        }
        (diffuse_sum / total, specular_sum / total, negative)
    };
    let mut metal = Scene::cornell_box();
    let mut matte = Scene::cornell_box();
    for m in &mut metal.materials {
        m.metallic = 1.0;
    }
    for m in &mut matte.materials {
        m.metallic = 0.0;
        m.specular_factor = 0.0;
    }
    let (d, s, negative) = parts(&Scene::cornell_box());
    eprintln!(
        "glTF materials: diffuse {d:.4}, specular {s:.4} of the light, worst negative part {negative:e}"
    );
    assert!(d > 0.5 && s > 0.005, "a part is missing: diffuse {d}, specular {s}");
    assert!(negative < 1e-6, "a part went below 0: {negative}");
    let (d, s, negative) = parts(&metal);
    eprintln!("metals: diffuse {d:e}, specular {s:.6} of the light, worst negative part {negative:e}");
    assert!(d.abs() < 1e-5 && (s - 1.0).abs() < 1e-5, "metals: diffuse {d}, specular {s}");
    let (d, s, negative) = parts(&matte);
    eprintln!(
        "matte dielectrics: diffuse {d:.6}, specular {s:e} of the light, worst negative part {negative:e}"
    );
    assert!(s.abs() < 1e-6 && (d - 1.0).abs() < 1e-5, "matte: diffuse {d}, specular {s}");
    assert!(negative < 1e-6, "a part went below 0: {negative}");
}

#[test]
fn the_filter_is_deterministic() {
    let gpu = Gpu::new();
    let (image, _) = synthetic(|x, y| plane([0.5, 0.6, 0.7], 1.0 + (x * y) as f32 / 4096.0), 4, 0.5, 6);
    let settings = DenoiseSettings::default();
    let a = denoise(&gpu, &image, &settings).unwrap();
    let b = denoise(&gpu, &image, &settings).unwrap();
    assert!(
        bytemuck::cast_slice::<[f32; 4], u8>(&a.color) == bytemuck::cast_slice::<[f32; 4], u8>(&b.color),
        "two runs differ"
    );
    assert!(a.color != image.mean, "the filter changed nothing");
}

#[test]
fn settings_are_validated() {
    let gpu = Gpu::new();
    let (image, _) = synthetic(|_, _| plane([0.5; 3], 1.0), 1, 0.0, 7);
    for (settings, words) in [
        (DenoiseSettings { iterations: 0, ..Default::default() }, "iterations"),
        (DenoiseSettings { iterations: 9, ..Default::default() }, "iterations"),
        (DenoiseSettings { sigma_luminance: f32::NAN, ..Default::default() }, "sigma_luminance"),
        (DenoiseSettings { sigma_normal: 0.0, ..Default::default() }, "sigma_normal"),
        (DenoiseSettings { sigma_depth: -1.0, ..Default::default() }, "sigma_depth"),
        (DenoiseSettings { albedo_offset: 2.0, ..Default::default() }, "albedo_offset"),
    ] {
        let e = denoise(&gpu, &image, &settings).unwrap_err().to_string();
        assert!(e.contains(words), "{e}");
    }
    let mut short = image.clone();
    short.albedo.pop();
    let e = denoise(&gpu, &short, &DenoiseSettings::default()).unwrap_err().to_string();
    assert!(e.contains("albedo"), "{e}");
}

/// The embedded Cornell box at 4 spp (48×48, the stored reference's size) against its 16,384-spp
/// reference, three seeds, with and without the lobe split. The goal is a relative MSE 8×
/// lower; at 128×128 (`umbra-bench denoise`, BENCHMARKS.md; analysis: docs/history/2026-12-05.md)
/// the Cornell box reaches it, but at 48×48 a pixel spans so much of the box that the filter's bias
/// is larger: 4.1–4.8× was measured here (lavapipe), and 3× is asserted.
#[test]
fn cornell_box_at_4_spp_comes_much_closer_to_the_reference() {
    let gpu = Gpu::new();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/cornell-48.exr");
    let (w, h, channels) = umbra::output::read_exr_channels(&path).unwrap();
    assert_eq!((w, h), (48, 48));
    let get = |name: &str| &channels.iter().find(|c| c.0 == name).unwrap().1;
    let (r, g, b) = (get("R"), get("G"), get("B"));
    let reference: Vec<[f32; 3]> = (0..w * h).map(|i| [r[i], g[i], b[i]]).collect();

    let scene = Scene::cornell_box();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let mut factors = Vec::new();
    for (seed, lobe_split) in [(1u32, false), (2, false), (3, false), (1, true), (2, true), (3, true)] {
        let settings = PathSettings { size: (48, 48), spp: 4, seed, lobe_split, ..Default::default() };
        let image = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
        let out = denoise(&gpu, &image, &DenoiseSettings::default()).unwrap();
        let (raw, denoised) = (relative_mse(&image.mean, &reference), relative_mse(&out.color, &reference));
        eprintln!(
            "Cornell 48x48, 4 spp, seed {seed}, lobe split {lobe_split}: relative MSE {raw:.4e} raw, {denoised:.4e} \
             denoised: {:.2}x lower (path tracing {:.2} ms, filter {:.2} ms on the GPU)",
            raw / denoised,
            image.gpu_ms,
            out.gpu_ms
        );
        factors.push(raw / denoised);
    }
    let worst = factors.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(worst >= 3.0, "relative MSE only {worst:.2}x lower");
}
