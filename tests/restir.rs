//! ReSTIR DI in the hybrid renderer (`umbra::passes::restir`): its resampling keeps each light
//! with the probability resampled importance sampling gives (chi-square against the exact
//! distribution); the unbiased combination, with temporal and spatial reuse, converges to the
//! image power-sampled light sampling converges to (z-test over independent seeds); the biased
//! combination's bias is measured; bad settings are refused with clear errors.

mod common;

use common::{build_with, camera, gamma_q, light, quad, Gpu};
use glam::Vec3;
use umbra::gpu::layout::{RESTIR_NONE, RESTIR_PUNCTUAL};
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::{DirectLight, LightingSettings};
use umbra::passes::gbuffer::GBuffer;
use umbra::passes::restir::{Reservoirs, RestirSettings};
use umbra::render::{HybridSettings, Passes};
use umbra::scene::{LightKind, Material, Scene};

const SIZE: (u32, u32) = (64, 64);

/// A Lambertian square (`KHR_materials_specular` factor 0: no specular lobe, so the BRDF is
/// base / π whatever the directions) filling the view, lit by four white directional lights of
/// intensities 1 to 4 at incidence cosines `cosines`: every pixel has the same target function.
fn four_suns(cosines: [f32; 4]) -> Scene {
    let material = Material {
        base_color_factor: [0.8, 0.8, 0.8, 1.0],
        metallic: 0.0,
        roughness: 1.0,
        specular_factor: 0.0,
        ..Default::default()
    };
    let lights = cosines
        .iter()
        .enumerate()
        .map(|(i, &c)| {
            // Travelling towards -Z (the square faces +Z) at incidence cosine c, from azimuth i.
            let phi = i as f32 * 1.7;
            let s = (1.0 - c * c).sqrt();
            light(
                LightKind::Directional,
                Vec3::ZERO,
                Vec3::new(s * phi.cos(), s * phi.sin(), -c),
                1.0 + i as f32,
            )
        })
        .collect();
    build_with(
        "four suns",
        &[(quad(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)), material)],
        lights,
        camera(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO),
    )
}

/// Records the G-buffer and one ReSTIR frame of `scene`, returns the reservoirs.
fn reservoirs_of(
    gpu: &Gpu,
    scene: &Scene,
    settings: &RestirSettings,
    seed: u32,
) -> Vec<umbra::gpu::layout::GpuReservoir> {
    let gpu_scene = GpuScene::upload(gpu, scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(gpu, &gpu_scene);
    let gbuffer = GBuffer::new(gpu, SIZE).expect("G-buffer");
    let reservoirs = Reservoirs::new(gpu, SIZE).expect("reservoirs");
    let lighting = LightingSettings { seed, ..Default::default() };
    gpu.record(|rec| {
        passes.record_gbuffer(rec, &gpu_scene, &camera, &gbuffer.views())?;
        passes.record_restir(rec, &gpu_scene, &camera, &gbuffer.views(), &reservoirs, settings, &lighting)
    })
    .expect("record and submit");
    reservoirs.read(gpu).expect("read back")
}

/// Resampled importance sampling with M candidates from the source pmf keeps light i with
/// probability E[Σ_{j: x_j = i} w_i / Σ_j w_{x_j}], w = p̂ / pmf: enumerated over all 4^M
/// candidate tuples. On the four-sun square p̂_i = 0.8/π · cos_i · I_i and pmf_i = I_i / ΣI, so
/// w_i ∝ cos_i. The GPU's kept lights over 4,096 pixels (one reservoir each, no reuse) against
/// that distribution: chi-square, 3 degrees of freedom, fails below p = 0.001. Fails if the
/// weights leave out the source pmf (the kept lights then follow p̂ × pmf) or the reservoir keeps
/// a candidate with another probability than w / w_sum.
#[test]
fn ris_keeps_each_light_with_its_exact_probability() {
    let gpu = Gpu::new();
    let cosines = [0.9f32, 0.3, 0.6, 0.15];
    let scene = four_suns(cosines);
    const M: u32 = 4;
    let settings = RestirSettings {
        candidates: M,
        temporal: false,
        neighbours: 0,
        unbiased: true,
        frames: 1,
        ..Default::default()
    };
    let reservoirs = reservoirs_of(&gpu, &scene, &settings, 7);

    let intensity = [1.0f64, 2.0, 3.0, 4.0];
    let total: f64 = intensity.iter().sum();
    let pmf: Vec<f64> = intensity.iter().map(|i| i / total).collect();
    let w: Vec<f64> = (0..4).map(|i| cosines[i] as f64 * intensity[i] / pmf[i]).collect();
    let mut expected = [0.0f64; 4];
    for tuple in 0..4usize.pow(M) {
        let picks: Vec<usize> = (0..M).map(|j| tuple / 4usize.pow(j) % 4).collect();
        let p: f64 = picks.iter().map(|&k| pmf[k]).product();
        let sum: f64 = picks.iter().map(|&k| w[k]).sum();
        for &k in &picks {
            expected[k] += p * w[k] / sum;
        }
    }
    let mut counts = [0u64; 4];
    for r in &reservoirs {
        assert!(
            r.light != RESTIR_NONE && r.light & RESTIR_PUNCTUAL != 0,
            "every pixel keeps a punctual light: {r:?}"
        );
        counts[(r.light & !RESTIR_PUNCTUAL) as usize] += 1;
        assert!(r.weight > 0.0 && r.weight.is_finite(), "a positive weight: {r:?}");
    }
    let n = reservoirs.len() as f64;
    let chi2: f64 = (0..4).map(|i| (counts[i] as f64 - n * expected[i]).powi(2) / (n * expected[i])).sum();
    let p = gamma_q(1.5, chi2 / 2.0);
    println!("kept {counts:?}, expected {:?}, chi2 {chi2:.2}, p {p:.3}", expected.map(|e| e * n));
    assert!(
        p > 0.001,
        "kept lights {counts:?} against expected {:?}: chi2 {chi2:.1}, p {p:.2e}",
        expected.map(|e| e * n)
    );
}

/// The mean radiance of a hybrid render of `scene` (direct light only: no image-based light, no
/// SSAO) with `direct` light sampling and `seed`.
fn image_mean(
    passes: &Passes,
    gpu_scene: &GpuScene,
    camera: &umbra::scene::Camera,
    direct: DirectLight,
    seed: u32,
) -> f64 {
    let settings = HybridSettings {
        size: (48, 48),
        lighting: LightingSettings { seed, ibl: false, shadow_rays: 16, direct, ..Default::default() },
        ao: None,
        ..Default::default()
    };
    let image = passes.hybrid(gpu_scene, camera, &settings).expect("hybrid render");
    image.color.iter().map(|c| (c[0] + c[1] + c[2]) as f64 / 3.0).sum::<f64>() / image.color.len() as f64
}

/// Mean and variance of the mean of `xs`.
fn mean_and_variance(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var / n)
}

/// The unbiased combination with temporal reuse (4 frames) and 5 spatial neighbours, on
/// scenes/many-lights.glb (480 emissive triangles, 136 punctual lights, pillars casting shadows):
/// its image mean over 32 seeds against power-sampled light sampling's (16 shadow rays) over 32
/// others: a two-sample z-test, fails above |z| = 3.29 (two-sided, α = 0.001). The biased
/// combination on the same seeds is reported beside it (its bias is BENCHMARKS.md's restir table's,
/// analysed in docs/history/2026-12-02.md). Fails if the candidates' source density, the
/// reservoirs' count weighting or the 1/Z normalisation is wrong.
#[test]
fn unbiased_restir_converges_to_power_sampling() {
    let gpu = Gpu::new();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/many-lights.glb");
    let scene = Scene::load(std::path::Path::new(path)).expect("many-lights.glb");
    let gpu_scene = GpuScene::upload(&gpu, &scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let restir = |unbiased| DirectLight::Restir(RestirSettings { unbiased, frames: 4, ..Default::default() });
    let seeds = 32u32;
    let power: Vec<f64> =
        (0..seeds).map(|s| image_mean(&passes, &gpu_scene, &camera, DirectLight::Power, s)).collect();
    let unbiased: Vec<f64> =
        (0..seeds).map(|s| image_mean(&passes, &gpu_scene, &camera, restir(true), 1000 + s)).collect();
    let biased: Vec<f64> =
        (0..seeds).map(|s| image_mean(&passes, &gpu_scene, &camera, restir(false), 1000 + s)).collect();
    let (p, vp) = mean_and_variance(&power);
    let (u, vu) = mean_and_variance(&unbiased);
    let (b, vb) = mean_and_variance(&biased);
    let z = (u - p) / (vu + vp).sqrt();
    println!(
        "power {p:.5} ± {:.5}, unbiased ReSTIR {u:.5} ± {:.5} (z {z:.2}), biased ReSTIR {b:.5} ± {:.5} ({:+.2} %)",
        vp.sqrt(),
        vu.sqrt(),
        vb.sqrt(),
        100.0 * (b / p - 1.0)
    );
    assert!(z.abs() < 3.29, "unbiased ReSTIR's mean {u:.5} against power sampling's {p:.5}: z = {z:.2}");
}

/// Bad ReSTIR settings are refused with an error naming the setting (directly and through the
/// lighting settings), and reservoirs of another size than the G-buffer are refused.
#[test]
fn bad_restir_settings_are_refused() {
    let ok = RestirSettings::default();
    for (settings, needle) in [
        (RestirSettings { candidates: 0, ..ok }, "candidates"),
        (RestirSettings { candidates: RestirSettings::MAX_CANDIDATES + 1, ..ok }, "candidates"),
        (RestirSettings { neighbours: RestirSettings::MAX_NEIGHBOURS + 1, ..ok }, "neighbours"),
        (RestirSettings { radius: 0.5, ..ok }, "radius"),
        (RestirSettings { radius: f32::NAN, ..ok }, "radius"),
        (RestirSettings { history_cap: 0.0, ..ok }, "history cap"),
        (RestirSettings { frames: 0, ..ok }, "frames"),
    ] {
        let error = settings.validate().expect_err(needle).to_string();
        assert!(error.contains("ReSTIR") && error.contains(needle), "{error}");
        let lighting = LightingSettings { direct: DirectLight::Restir(settings), ..Default::default() };
        assert_eq!(lighting.validate().expect_err(needle).to_string(), error);
    }
    ok.validate().expect("the defaults are valid");

    let gpu = Gpu::new();
    let scene = four_suns([0.5; 4]);
    let gpu_scene = GpuScene::upload(&gpu, &scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let gbuffer = GBuffer::new(&gpu, SIZE).expect("G-buffer");
    let reservoirs = Reservoirs::new(&gpu, (8, 8)).expect("reservoirs");
    let error = gpu
        .record(|rec| {
            passes.record_restir(
                rec,
                &gpu_scene,
                &camera,
                &gbuffer.views(),
                &reservoirs,
                &ok,
                &LightingSettings::default(),
            )
        })
        .expect_err("reservoirs of another size")
        .to_string();
    assert!(error.contains("8x8") && error.contains("64x64"), "{error}");
}

/// `umbra render --direct restir` renders the many-light scene with the validation layer on and
/// nothing logged; `--direct restir` outside the hybrid mode is refused, naming the option.
#[test]
fn the_command_line_renders_with_restir() {
    let dir = std::env::temp_dir().join(format!("umbra-restir-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("many.png");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/many-lights.glb");
    common::run_validated(
        std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
            .args([
                "render",
                scene,
                "--mode",
                "hybrid",
                "--direct",
                "restir",
                "--restir-frames",
                "2",
                "--size",
                "24x24",
                "-o",
            ])
            .arg(&png),
    );
    assert!(png.exists(), "the PNG is written");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
        .args(["render", "--direct", "restir", "--size", "8x8", "-o"])
        .arg(dir.join("no.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("--direct"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}
