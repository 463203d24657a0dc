//! RIS at the path tracer's first hit (`PathSettings::direct`, `DirectSampling::Ris`: the
//! candidates and target function of the hybrid's ReSTIR DI): with 1 and 8 candidates it
//! converges to the image power-sampled light sampling converges to, on the many-light scene and
//! on the Cornell box (z-tests per region and channel); bad settings are refused with clear
//! errors; the command line renders with it.

mod common;

use common::{gamma_q, Gpu};
use std::path::Path;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{DirectSampling, Integrator, Strategy};
use umbra::render::{Passes, PathImage, PathSettings};
use umbra::scene::Scene;

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Blocks per side the image is split into for the z-tests.
const BLOCKS: u32 = 4;

/// The z-scores of the differences between `a`'s and `b`'s means over each of BLOCKS × BLOCKS
/// regions and the whole image, per channel, from the pixels' variances of their means (the
/// pixels' samples are independent, and so are the two renders: different seeds).
fn region_z(a: &PathImage, b: &PathImage) -> Vec<(String, f64)> {
    let (w, h) = a.size;
    let (va, vb) = (a.variance_of_mean(), b.variance_of_mean());
    let mut out = Vec::new();
    let mut region = |name: String, inside: &dyn Fn(u32, u32) -> bool| {
        for c in 0..3 {
            let (mut da, mut db, mut var, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    if inside(x, y) {
                        let i = (y * w + x) as usize;
                        da += a.mean[i][c] as f64;
                        db += b.mean[i][c] as f64;
                        var += va[i][c] as f64 + vb[i][c] as f64;
                        n += 1.0;
                    }
                }
            }
            let z = if var > 0.0 { (da - db) / var.sqrt() } else { 0.0 };
            out.push((format!("{name} channel {c}: {:.5} against {:.5}", da / n, db / n), z));
        }
    };
    for by in 0..BLOCKS {
        for bx in 0..BLOCKS {
            let inside = move |x: u32, y: u32| x * BLOCKS / w == bx && y * BLOCKS / h == by;
            region(format!("block ({bx}, {by})"), &inside);
        }
    }
    region("whole image".into(), &|_, _| true);
    out
}

/// Renders `scene` by power sampling and by RIS with 1 and 8 candidates (other seeds each) and
/// z-tests each RIS image against the power-sampled one per region and channel
/// ([`region_z`]: 51 tests per image): fails where any two-sided p is below the Šidák-corrected
/// level for a family-wise α = 0.001 over all the tests of the call.
fn ris_matches_power(name: &str, settings: PathSettings) {
    let gpu = Gpu::new();
    let scene = load(name);
    let gpu_scene = GpuScene::upload(&gpu, &scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let render = |direct, seed| {
        let image = passes
            .path_trace(&gpu_scene, &camera, &PathSettings { direct, seed, ..settings.clone() }, |_, _| {})
            .unwrap_or_else(|e| panic!("{name}, {direct:?}: {e}"));
        assert_eq!(image.nonfinite_samples, 0, "{name}, {direct:?}: non-finite samples");
        image
    };
    let power = render(DirectSampling::Power, 1);
    let cases = [(DirectSampling::Ris(1), 2), (DirectSampling::Ris(8), 3)];
    let results: Vec<(DirectSampling, Vec<(String, f64)>)> =
        cases.iter().map(|&(direct, seed)| (direct, region_z(&render(direct, seed), &power))).collect();
    let tests = results.iter().map(|(_, z)| z.len()).sum::<usize>() as f64;
    let alpha = 1.0 - (1.0 - 0.001f64).powf(1.0 / tests);
    let mut failures = Vec::new();
    for (direct, zs) in &results {
        let (worst, z) = zs.iter().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).expect("tests");
        let whole = &zs[zs.len() - 3..];
        println!(
            "{name}, {direct:?}: largest |z| {:.2} ({worst}); whole image z {:.2} {:.2} {:.2}",
            z.abs(),
            whole[0].1,
            whole[1].1,
            whole[2].1
        );
        for (what, z) in zs {
            let p = gamma_q(0.5, z * z / 2.0);
            if p < alpha {
                failures.push(format!("{direct:?}, {what}: z {z:.2}, p {p:.1e} < {alpha:.1e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{name}: RIS against power sampling:\n{}", failures.join("\n"));
}

/// scenes/many-lights.glb (480 emissive triangles, 136 punctual lights, pillars casting
/// shadows), three bounces: direct light at the first hit and the emitters BSDF-sampled rays hit
/// from there (which RIS must not count again), and indirect light beyond. Fails if W leaves
/// out the weights' sum, the candidates' source density is wrong, or emission hit from the first
/// hit counts again.
#[test]
fn ris_converges_to_power_sampling_on_many_lights() {
    let settings = PathSettings { size: (32, 32), spp: 256, max_bounces: 3, ..PathSettings::default() };
    ris_matches_power("many-lights.glb", settings);
}

/// The Cornell box (one emissive quad, no punctual lights: every candidate an emissive sample),
/// four bounces. Fails if W is left out; emission hit from the first hit counted again with its
/// MIS weight moves this image too little to show at this sample count (the many-light test
/// catches that).
#[test]
fn ris_converges_to_power_sampling_on_the_cornell_box() {
    let settings = PathSettings { size: (32, 32), spp: 256, max_bounces: 4, ..PathSettings::default() };
    ris_matches_power("cornell-box.glb", settings);
}

/// Bad RIS settings are refused with an error naming the problem: no candidates, too many, the
/// wavefront integrator, BSDF sampling alone.
#[test]
fn bad_ris_settings_are_refused() {
    let ok = PathSettings { direct: DirectSampling::Ris(8), ..PathSettings::default() };
    ok.validate().expect("RIS with 8 candidates is valid");
    for (settings, needle) in [
        (PathSettings { direct: DirectSampling::Ris(0), ..ok.clone() }, "0 RIS candidates"),
        (
            PathSettings { direct: DirectSampling::Ris(DirectSampling::MAX_CANDIDATES + 1), ..ok.clone() },
            "RIS candidates: must be 1 to",
        ),
        (PathSettings { integrator: Integrator::Wavefront, ..ok.clone() }, "megakernel only"),
        (PathSettings { strategy: Strategy::Bsdf, ..ok.clone() }, "--strategy bsdf"),
    ] {
        let error = settings.validate().expect_err(needle).to_string();
        assert!(error.contains(needle), "{error}");
    }
}

/// `umbra render --direct ris` renders the many-light scene with the validation layer on and
/// nothing logged; `--direct ris` outside the path tracer and `--direct restir` in it are
/// refused, naming the option.
#[test]
fn the_command_line_renders_with_ris() {
    let dir = std::env::temp_dir().join(format!("umbra-path-ris-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("many.png");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/many-lights.glb");
    common::run_validated(
        std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
            .args([
                "render",
                scene,
                "--direct",
                "ris",
                "--ris-candidates",
                "4",
                "--spp",
                "2",
                "--size",
                "24x24",
                "-o",
            ])
            .arg(&png),
    );
    assert!(png.exists(), "the PNG is written");
    for (mode, direct) in [("hybrid", "ris"), ("pathtrace", "restir")] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_umbra"))
            .args(["render", "--mode", mode, "--direct", direct, "--size", "8x8", "-o"])
            .arg(dir.join("no.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && stderr.contains(&format!("--direct {direct}")), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
