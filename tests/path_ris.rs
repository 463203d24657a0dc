//! RIS at the path tracer's first hit (`PathSettings::direct`, `DirectSampling::Ris`: the
//! candidates and target function of the hybrid's ReSTIR DI): with 1 and 8 candidates it
//! converges to the image power-sampled light sampling converges to, on the many-light scene and
//! on the Cornell box (z-tests per region and channel); bad settings are refused with clear
//! errors; the command line renders with it. With reuse (`PathSettings::ris_reuse`: the previous
//! sample index's reservoirs of the pixel and its neighbours, combined by pairwise MIS) it
//! converges to the same image (t-tests over independent renders, whose samples are correlated
//! within a render) and caps the reservoirs' counts. The other way to draw light samples,
//! emissive points by solid angle (`EmitterSampling::SolidAngle`), converges to area sampling's
//! image too.

mod common;

use common::{gamma_q, student_t_p, Gpu};
use std::path::Path;
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{DirectSampling, Integrator, RisReuse, Sampler, Strategy};
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
/// pixels' samples are independent, [`Sampler::Independent`], and so are the two renders:
/// different seeds).
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
            .path_trace(
                &gpu_scene,
                &camera,
                // Independent numbers: region_z takes each pixel's own sample variance, which the
                // default low-discrepancy numbers over-estimate.
                &PathSettings { direct, seed, sampler: Sampler::Independent, ..settings.clone() },
                |_, _| {},
            )
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

/// The mean over each of BLOCKS × BLOCKS regions and the whole image (region_z's order), per
/// channel.
fn region_means(image: &PathImage) -> Vec<[f64; 3]> {
    let (w, h) = image.size;
    let mut out = Vec::new();
    let mut region = |inside: &dyn Fn(u32, u32) -> bool| {
        let (mut sum, mut n) = ([0.0f64; 3], 0.0f64);
        for y in 0..h {
            for x in 0..w {
                if inside(x, y) {
                    let m = image.mean[(y * w + x) as usize];
                    for c in 0..3 {
                        sum[c] += m[c] as f64;
                    }
                    n += 1.0;
                }
            }
        }
        out.push(sum.map(|s| s / n));
    };
    for by in 0..BLOCKS {
        for bx in 0..BLOCKS {
            region(&move |x: u32, y: u32| x * BLOCKS / w == bx && y * BLOCKS / h == by);
        }
    }
    region(&|_, _| true);
    out
}

/// Renders `scene` by power sampling (one render, its pixels' samples independent) and by RIS
/// with each reuse of `cases` (`renders` renders of `spp` samples each, other seeds: a render's
/// samples are correlated across sample indices by the reuse, independent renders are not), and
/// t-tests each case's mean over its renders against power sampling's per region and channel
/// (the variance: the renders' sample variance of their region means over `renders`, plus power
/// sampling's variance of its mean; `renders` − 1 degrees of freedom): fails where any
/// two-sided p is below the Šidák-corrected level for a family-wise α = 0.001 over all the tests.
fn reuse_matches_power(
    name: &str,
    scene: &Scene,
    settings: PathSettings,
    cases: &[(RisReuse, u32)],
    renders: u32,
    spp: u32,
) {
    let gpu = Gpu::new();
    let gpu_scene = GpuScene::upload(&gpu, scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let render = |settings: PathSettings| {
        let what = format!("{name}, {:?} {:?} seed {}", settings.direct, settings.ris_reuse, settings.seed);
        let image = passes
            .path_trace(&gpu_scene, &camera, &settings, |_, _| {})
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(image.nonfinite_samples, 0, "{what}: non-finite samples");
        image
    };
    let power = render(PathSettings { seed: 1, ..settings.clone() });
    let power_means = region_means(&power);
    // Power sampling's variance of each region's mean: its pixels are independent.
    let power_var: Vec<[f64; 3]> = {
        let (w, h) = power.size;
        let var = power.variance_of_mean();
        let mut out = Vec::new();
        let mut region = |inside: &dyn Fn(u32, u32) -> bool| {
            let (mut sum, mut n) = ([0.0f64; 3], 0.0f64);
            for y in 0..h {
                for x in 0..w {
                    if inside(x, y) {
                        let v = var[(y * w + x) as usize];
                        for c in 0..3 {
                            sum[c] += v[c] as f64;
                        }
                        n += 1.0;
                    }
                }
            }
            out.push(sum.map(|s| s / (n * n)));
        };
        for by in 0..BLOCKS {
            for bx in 0..BLOCKS {
                region(&move |x: u32, y: u32| x * BLOCKS / w == bx && y * BLOCKS / h == by);
            }
        }
        region(&|_, _| true);
        out
    };
    let mut results = Vec::new();
    for (case, &(reuse, candidates)) in cases.iter().enumerate() {
        let means: Vec<Vec<[f64; 3]>> = (0..renders)
            .map(|r| {
                region_means(&render(PathSettings {
                    direct: DirectSampling::Ris(candidates),
                    ris_reuse: reuse,
                    spp,
                    seed: 100 + 1000 * case as u32 + r,
                    ..settings.clone()
                }))
            })
            .collect();
        let n = renders as f64;
        let mut ts = Vec::new();
        for (region, reference) in power_means.iter().enumerate() {
            for c in 0..3 {
                let mean = means.iter().map(|m| m[region][c]).sum::<f64>() / n;
                let var = means.iter().map(|m| (m[region][c] - mean).powi(2)).sum::<f64>() / (n - 1.0);
                let se = (var / n + power_var[region][c]).sqrt();
                let t = if se > 0.0 { (mean - reference[c]) / se } else { 0.0 };
                ts.push((format!("region {region} channel {c}: {mean:.5} against {:.5}", reference[c]), t));
            }
        }
        results.push((reuse, candidates, ts));
    }
    let tests = results.iter().map(|(_, _, t)| t.len()).sum::<usize>() as f64;
    let alpha = 1.0 - (1.0 - 0.001f64).powf(1.0 / tests);
    let mut failures = Vec::new();
    for (reuse, candidates, ts) in &results {
        let (worst, t) = ts.iter().max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).expect("tests");
        let whole = &ts[ts.len() - 3..];
        println!(
            "{name}, reuse {reuse:?}, {candidates} candidates: largest |t| {:.2} ({worst}); whole image t {:.2} {:.2} {:.2}",
            t.abs(),
            whole[0].1,
            whole[1].1,
            whole[2].1
        );
        for (what, t) in ts {
            let p = student_t_p(*t, renders as f64 - 1.0);
            if p < alpha {
                failures.push(format!("{reuse:?} {candidates}, {what}: t {t:.2}, p {p:.1e} < {alpha:.1e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{name}: RIS with reuse against power sampling:\n{}", failures.join("\n"));
}

/// scenes/many-lights.glb, direct light (one bounce: the first hit's light sample and the
/// emitters its BSDF-sampled ray reaches): RIS with the previous sample index's reservoirs of
/// the pixel and its neighbours (8 candidates), and of the pixel alone (1 candidate: the reused
/// reservoirs carry most of the weight), each as 160 renders of 8 samples, against 256 samples
/// of power sampling. Fails if the MIS weights leave out the targets at the reservoirs' own hits
/// (1/M), if a reused sample keeps its own pixel's target instead of this one's, if W leaves
/// out the reused weights, or if the canonical reservoir's pairwise weight is 1/n (t 52 and 116
/// at 32 renders). One candidate's rare, large samples (a light of little power close to a
/// surface) skew a render's mean: over 32 renders one region's blue channel stood at t −5.1
/// (three bounces: −5.35) while the whole image's |t| stayed below 2.4; over 160 renders the
/// largest |t| was 1.9, as a skew and not a bias gives. One bounce: the vertices beyond the
/// first reuse nothing (`ris_converges_to_power_sampling_on_many_lights` tests them).
#[test]
fn ris_reuse_converges_to_power_sampling_on_many_lights() {
    let settings = PathSettings { size: (32, 32), spp: 256, max_bounces: 1, ..PathSettings::default() };
    let scene = load("many-lights.glb");
    reuse_matches_power(
        "many-lights.glb",
        &scene,
        settings,
        &[(RisReuse::Both, 8), (RisReuse::Samples, 1)],
        160,
        8,
    );
}

/// A one-sided emissive quad (0.3 high, 1.2 wide) standing on a 2 × 2 floor, facing +x, seen from
/// above.
fn one_sided_emitter() -> Scene {
    use common::{build_with, camera, quad};
    use glam::Vec3;
    use umbra::scene::Material;
    let floor = Material { metallic: 0.0, roughness: 1.0, ..Default::default() };
    let emitter = Material { emissive: [4.0; 3], base_color_factor: [0.0, 0.0, 0.0, 1.0], ..floor.clone() };
    build_with(
        "one-sided emitter",
        &[
            (quad(Vec3::ZERO, Vec3::X * 2.0, -Vec3::Z * 2.0), floor),
            (quad(Vec3::new(0.0, 0.3, 0.0), Vec3::Y * 0.3, Vec3::Z * 1.2), emitter),
        ],
        Vec::new(),
        camera(Vec3::new(0.4, 2.2, 1.8), Vec3::ZERO),
    )
}

/// A one-sided emissive quad standing on a floor, facing +x, seen from above: the floor on its
/// back side is unlit, so a neighbour there (as similar as a surface can be: the same plane)
/// cannot produce the quad's samples that the lit side keeps. Direct light only, spatial reuse
/// (2 candidates) and both (8), 64 renders of 16 samples each, against 256 samples of power
/// sampling. Fails if the MIS weights give the unlit neighbours a share of the quad's samples
/// (1/M: the lit floor darkens by up to half along the quad's foot), or if a reused sample keeps
/// its own pixel's target.
#[test]
fn ris_reuse_converges_to_power_sampling_across_a_one_sided_emitter() {
    let scene = one_sided_emitter();
    let settings = PathSettings { size: (32, 32), spp: 256, max_bounces: 1, ..PathSettings::default() };
    reuse_matches_power(
        "one-sided emitter",
        &scene,
        settings,
        &[(RisReuse::Spatial, 2), (RisReuse::Both, 8)],
        64,
        16,
    );
}

/// `EmitterSampling::SolidAngle` (next-event estimation draws points uniform in the solid angle
/// of emissive triangles that subtend at least 0.2 sr, by area elsewhere) converges to the image
/// area sampling converges to, and is quieter next to the emitter: the one-sided quad standing on
/// a floor, three bounces (so BSDF-sampled rays from near the quad that hit it are weighed with
/// the solid-angle density too), 256 independent samples each, z-tests per region and channel
/// ([`region_z`], family-wise α = 0.001). Fails if the MIS density of a BSDF hit on the quad keeps
/// the area density, and if solid-angle sampling leaves the image's summed variance of the pixel
/// means above 0.8 of area sampling's (measured: 0.71-0.72 over four pairs of seeds).
#[test]
fn solid_angle_emitter_sampling_converges_to_area_sampling() {
    use umbra::passes::pathtrace::EmitterSampling;
    let scene = one_sided_emitter();
    let gpu = Gpu::new();
    let gpu_scene = GpuScene::upload(&gpu, &scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let render = |emitter_sampling, seed| {
        let settings = PathSettings {
            size: (32, 32),
            spp: 256,
            max_bounces: 3,
            seed,
            sampler: Sampler::Independent,
            emitter_sampling,
            ..PathSettings::default()
        };
        let image = passes.path_trace(&gpu_scene, &camera, &settings, |_, _| {}).expect("render");
        assert_eq!(image.nonfinite_samples, 0, "{emitter_sampling:?}: non-finite samples");
        image
    };
    let area = render(EmitterSampling::Area, 1);
    let solid = render(EmitterSampling::SolidAngle, 2);
    let zs = region_z(&solid, &area);
    let alpha = 1.0 - (1.0 - 0.001f64).powf(1.0 / zs.len() as f64);
    let failures: Vec<String> = zs
        .iter()
        .filter_map(|(what, z)| {
            let p = gamma_q(0.5, z * z / 2.0);
            (p < alpha).then(|| format!("{what}: z {z:.2}, p {p:.1e} < {alpha:.1e}"))
        })
        .collect();
    let summed =
        |image: &PathImage| image.variance_of_mean().iter().map(|v| (v[0] + v[1] + v[2]) as f64).sum::<f64>();
    let ratio = summed(&solid) / summed(&area);
    println!(
        "solid angle against area: largest |z| {:.2}; summed variance ratio {ratio:.3}",
        zs.iter().map(|(_, z)| z.abs()).fold(0.0, f64::max)
    );
    assert!(failures.is_empty(), "solid-angle against area emitter sampling:\n{}", failures.join("\n"));
    assert!(ratio < 0.8, "solid-angle sampling is not quieter next to the quad: variance ratio {ratio}");
}

/// Student's t p-values against known quantiles (two-sided): t = 2.131 at 15 degrees of
/// freedom is the 5 % point, 4.073 the 0.1 % point; t = 0 has p = 1.
#[test]
fn student_t_p_values_match_tables() {
    for (t, df, p) in [(2.131, 15.0, 0.05), (4.073, 15.0, 0.001), (1.96, 1e6, 0.05), (0.0, 7.0, 1.0)] {
        let got = student_t_p(t, df);
        assert!((got - p).abs() < 0.02 * p, "t {t}, df {df}: p {got} against {p}");
    }
}

/// RIS with reuse recorded in batches of 1, 2 and 3 samples into one target (the host's
/// progressive frames) gives the one-shot render's image (the reservoirs carry over between
/// records), and the reservoirs' counts M stop at the cap, RIS_REUSE_CAP × the candidates, which
/// they reach after 6 samples of spatial and sample reuse. Fails if the cap is skipped, or a
/// record starts from cleared or stale reservoirs.
#[test]
fn ris_reuse_carries_over_between_records_and_caps_its_counts() {
    use umbra::gpu::layout::{GpuPathReservoir, RIS_REUSE_CAP};
    use umbra::passes::pathtrace::PathTarget;
    let gpu = Gpu::new();
    let scene = load("many-lights.glb");
    let gpu_scene = GpuScene::upload(&gpu, &scene).expect("upload");
    let camera = scene.camera(None).expect("camera");
    let passes = Passes::new(&gpu, &gpu_scene);
    let candidates = 4;
    let settings = PathSettings {
        size: (16, 16),
        spp: 6,
        max_bounces: 2,
        direct: DirectSampling::Ris(candidates),
        ris_reuse: RisReuse::Both,
        ..PathSettings::default()
    };
    let whole = passes.path_trace(&gpu_scene, &camera, &settings, |_, _| {}).expect("one-shot render");
    let target = PathTarget::new(&gpu, settings.size).expect("target");
    let mut first = 0;
    for count in [1, 2, 3] {
        gpu.record(|rec| {
            passes.record_path_samples(rec, &gpu_scene, &camera, &target, &settings, first..first + count)
        })
        .expect("record");
        first += count;
    }
    let batched: Vec<[f32; 4]> = target.accum.read(&gpu).expect("read");
    assert!(whole.mean.iter().any(|p| p[0] > 0.0), "the image is black");
    for (i, (a, b)) in batched.iter().zip(&whole.mean).enumerate() {
        assert_eq!(a, b, "pixel {i}: batched records against the one-shot render");
    }
    let cap = RIS_REUSE_CAP * candidates as f32;
    let reservoirs = target.ris_reservoirs.get().expect("the target's reservoirs");
    // Sample 5 (the last) wrote reservoirs[1].
    let last: Vec<GpuPathReservoir> = reservoirs[1].read(&gpu).expect("read");
    let most = last.iter().map(|r| r.count).fold(0.0f32, f32::max);
    assert!(most <= cap, "a reservoir counts {most} candidates, over the cap {cap}");
    assert!(most == cap, "no reservoir reached the cap {cap} (the most: {most})");
}

/// Bad RIS settings are refused with an error naming the problem: no candidates, too many (at a
/// vertex, over a path's bounces), the wavefront integrator, BSDF sampling alone; reuse without
/// RIS, in the wavefront integrator, of a tile, of a sample range not from 0.
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
        (
            PathSettings { direct: DirectSampling::Ris(128), max_bounces: 5, ..ok.clone() },
            "640 a path: at most 512",
        ),
        (PathSettings { integrator: Integrator::Wavefront, ..ok.clone() }, "megakernel only"),
        (PathSettings { strategy: Strategy::Bsdf, ..ok.clone() }, "--strategy bsdf"),
        (PathSettings { ris_reuse: RisReuse::Both, ..PathSettings::default() }, "it needs --direct ris"),
        (
            PathSettings { ris_reuse: RisReuse::Samples, integrator: Integrator::Wavefront, ..ok.clone() },
            "megakernel only",
        ),
        (
            PathSettings {
                ris_reuse: RisReuse::Spatial,
                size: (8, 8),
                tile: Some(umbra::passes::pathtrace::Tile { image: (16, 16), origin: (0, 0) }),
                ..ok.clone()
            },
            "not with --tile",
        ),
        (PathSettings { ris_reuse: RisReuse::Both, first_sample: 4, ..ok.clone() }, "must start at 0"),
    ] {
        let error = settings.validate().expect_err(needle).to_string();
        assert!(error.contains(needle), "{error}");
    }
}

/// `umbra render --direct ris --ris-reuse both` renders the many-light scene with the validation layer on and
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
                "--ris-reuse",
                "both",
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
