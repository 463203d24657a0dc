//! The path tracer against ground truth from outside: references of umbra's test scenes rendered
//! by Mitsuba 3 from the same glTF files (tests/reference/mitsuba_refs.py; what it maps and how is
//! in tests/reference/README.md). A bias in umbra's BSDF (rough glass too), lights, environment,
//! textures or camera shows up here; drift against umbra's own reference (tests/convergence.rs)
//! cannot.
//!
//! Each reference holds, per pixel, the mean of 32 independent Mitsuba renders of 2,048 samples
//! and the variance of that mean. umbra renders the same scene, camera and size at `spp`; per
//! pixel and channel z = (umbra − reference) / √(var_umbra + var_reference + rounding²):
//! - var_umbra is the larger of umbra's own variance of its pixel mean (sample variance / spp)
//!   and the reference's per-sample variance (its variance of the mean × 65,536) / spp. Rare,
//!   bright paths (caustics of the sky's sun through mirror spheres, a directional light's glint
//!   on a roughness-0 sphere) are a heavy tail: umbra's few samples mostly miss them, and its own
//!   estimate is then far too low, where Mitsuba's 65,536 samples see them. Without this floor,
//!   Mitsuba fails against itself at umbra's sample count (tests/reference/README.md);
//! - rounding = 10⁻⁵ · max(|umbra|, |reference|), float32 rounding: pixels that see one constant
//!   radiance (background, a light seen directly) have no variance in either renderer and must
//!   agree to 10⁻⁵.
//!
//! Each scene is rendered with its default estimator (GGX or Beckmann as the reference, the power
//! heuristic, MIS), and the Cornell box and the spheres under the sky with every other estimator
//! that can be tested at this sample count ([`estimators`]: Walter's GGX sampling, the balance
//! heuristic, BSDF or light sampling alone). Three statistics per comparison (two for BSDF
//! sampling alone in the Cornell box), each at α = 1 − (1 − 0.001)^(1/46) (Šidák over the
//! 3 × 5 statistics of the scenes and the 31 of the other estimators: 0.001 in all; [`alpha`]
//! counts them):
//! - pixels: the count of pixel channels with |z| > 3.29 (two-sided 0.001 each) is at most the
//!   binomial(n, 0.001) quantile at 1 − α: localised errors (orientation, a texture, a light);
//! - blocks: the pixels are averaged over 4×4 blocks (z of the block means, which are much closer
//!   to normal than single pixels with fireflies) and Σ z² is tested against χ²(blocks × 3);
//! - image: the image mean of each channel, z against N(0, 1), two-sided, Šidák over the channels.
//!
//! The deliberately biased variants (a base colour 2 % darker, also under BSDF sampling alone
//! without the per-pixel statistic; emission found by BSDF sampling counted without its MIS
//! weight; glass of index 1.45 instead of 1.5, or tinted 2 % darker) must be rejected by the same
//! test.
//! `UMBRA_MITSUBA_DEBUG=DIR` writes umbra's image, the reference and z for every comparison.

mod common;

use common::{gamma_q, Gpu};
use std::path::{Path, PathBuf};
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{
    EmitterSampling, Heuristic, Microfacet, PathOptions, RisReuse, Sampler, Strategy,
};
use umbra::render::{path_trace, PathImage, PathSettings};
use umbra::scene::Scene;

/// The family's significance: 0.001 over every statistic of every comparison (Šidák): the 3 of
/// each of the 5 scenes with its default estimator, and the 3 (or 2) of every other estimator of
/// [`estimators`].
fn alpha() -> f64 {
    let statistics = 3 * SCENES.len() + estimators().iter().map(|e| 2 + e.pixel_test as usize).sum::<usize>();
    1.0 - (1.0 - 1e-3f64).powf(1.0 / statistics as f64)
}

/// z beyond which a single pixel channel counts as an outlier (two-sided 0.001).
const PIXEL_Z: f64 = 3.29;
/// Pixels on a side of a block of the block statistic.
const BLOCK: usize = 4;

struct Case {
    /// The reference's name in tests/reference/mitsuba.
    name: &'static str,
    gltf: &'static str,
    environment: bool,
    /// The reference's microfacet distribution (GGX or Beckmann), which umbra's default estimator
    /// for it samples.
    microfacet: Microfacet,
    size: (u32, u32),
    /// umbra's samples per pixel.
    spp: u32,
}

const CORNELL: Case = Case {
    name: "cornell",
    gltf: "cornell-box.glb",
    environment: false,
    microfacet: Microfacet::Ggx,
    size: (48, 48),
    spp: 1024,
};
const SPHERES: Case = Case {
    name: "spheres-sky",
    gltf: "spheres.glb",
    environment: true,
    microfacet: Microfacet::Ggx,
    size: (72, 48),
    spp: 1024,
};
const SPHERES_BECKMANN: Case = Case {
    name: "spheres-sky-beckmann",
    gltf: "spheres.glb",
    environment: true,
    microfacet: Microfacet::Beckmann,
    size: (72, 48),
    spp: 1024,
};
const TEXTURED: Case = Case {
    name: "textured",
    gltf: "textured.glb",
    environment: false,
    microfacet: Microfacet::Ggx,
    size: (64, 48),
    spp: 1024,
};
/// Rough glass, solid and thin-walled, under the sky (scenes/glass.glb).
const GLASS: Case = Case {
    name: "glass",
    gltf: "glass.glb",
    environment: true,
    microfacet: Microfacet::Ggx,
    size: (64, 48),
    spp: 1024,
};
const SCENES: [&Case; 5] = [&CORNELL, &SPHERES, &SPHERES_BECKMANN, &TEXTURED, &GLASS];

/// One more estimator of a reference's scene than its default (the case's microfacet, the power
/// heuristic, MIS), with its samples per pixel.
struct Estimator {
    case: &'static Case,
    options: PathOptions,
    spp: u32,
    /// Whether the per-pixel statistic applies (blocks and the image mean always do).
    pixel_test: bool,
}

/// Every estimator compared with the references besides the defaults: per scene with an area
/// light or an environment map, each microfacet sampling of its distribution (GGX: visible
/// normals and Walter's D(h) cos θh) × {MIS with the power and the balance heuristic, BSDF
/// sampling alone, light sampling alone} (the heuristic only matters to MIS), and in the Cornell
/// box emissive points sampled by solid angle (`EmitterSampling::SolidAngle`), but for two
/// exclusions, measured (tests/reference/README.md, "Estimators"):
/// - under the sky (spheres-sky, spheres-sky-beckmann), either strategy alone: BSDF sampling
///   finds the sun (one texel: 56 % of the sky's power on 0.02 % of the sphere) in a few of a
///   pixel's 1,024 samples or none, and light sampling finds the sky's reflection in the roughness-0 spheres (α 10⁻⁴)
///   essentially never. umbra's pixel then comes out low with an estimated variance near 0:
///   hundreds of pixel channels beyond |z| 3.29, blocks χ²/dof 5 to 20, all of them too dark.
///   That is a variance umbra cannot estimate at a test's sample count, not a bias it could show;
/// - BSDF sampling alone in the Cornell box: the per-pixel statistic (not the blocks, not the
///   image mean), because a dark pixel's samples may all miss the light, so that its estimated
///   variance is 0 (495 channels beyond |z| 3.29 at 1,024 spp, 95 at 4,096, 21 at 16,384, bound
///   20; blocks χ²/dof 0.97, 0.95, 0.98).
fn estimators() -> Vec<Estimator> {
    let mut out = Vec::new();
    for case in [&CORNELL, &SPHERES, &SPHERES_BECKMANN] {
        let samplings: &[Microfacet] = match case.microfacet {
            Microfacet::Beckmann => &[Microfacet::Beckmann],
            _ => &[Microfacet::Ggx, Microfacet::GgxWalter],
        };
        for &microfacet in samplings {
            for (strategy, heuristic) in [
                (Strategy::Mis, Heuristic::Power),
                (Strategy::Mis, Heuristic::Balance),
                (Strategy::Bsdf, Heuristic::Power),
                (Strategy::Light, Heuristic::Power),
            ] {
                let options = PathOptions {
                    microfacet,
                    heuristic,
                    strategy,
                    ris: false,
                    ris_reuse: RisReuse::Off,
                    sampler: Sampler::default(),
                    emitter_sampling: EmitterSampling::Area,
                };
                if options == default_options(case) {
                    continue; // the scene's own test
                }
                if case.environment && strategy != Strategy::Mis {
                    continue; // not testable at a test's sample count (above)
                }
                let pixel_test = strategy != Strategy::Bsdf;
                out.push(Estimator { case, options, spp: case.spp, pixel_test });
            }
        }
    }
    // Emissive points by solid angle where a triangle subtends at least 0.2 sr (the walls and
    // ceiling next to the Cornell box's light), with MIS as the default.
    let options = PathOptions { emitter_sampling: EmitterSampling::SolidAngle, ..default_options(&CORNELL) };
    out.push(Estimator { case: &CORNELL, options, spp: CORNELL.spp, pixel_test: true });
    out
}

/// The estimator each scene's own test uses.
fn default_options(case: &Case) -> PathOptions {
    PathOptions { microfacet: case.microfacet, ..Default::default() }
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Per pixel rgb: the reference's mean and the variance of that mean.
struct Reference {
    mean: Vec<[f64; 3]>,
    variance: Vec<[f64; 3]>,
}

fn reference(case: &Case) -> Reference {
    let path = root().join(format!("tests/reference/mitsuba/{}.exr", case.name));
    let (w, h, channels) = umbra::output::read_exr_channels(&path).unwrap();
    assert_eq!((w, h), (case.size.0 as usize, case.size.1 as usize), "{}", path.display());
    let get = |name: &str| &channels.iter().find(|c| c.0 == name).unwrap_or_else(|| panic!("{name}")).1;
    let rgb = |r: &[f32], g: &[f32], b: &[f32]| {
        (0..w * h).map(|i| [r[i] as f64, g[i] as f64, b[i] as f64]).collect::<Vec<_>>()
    };
    Reference {
        mean: rgb(get("R"), get("G"), get("B")),
        variance: rgb(get("variance.R"), get("variance.G"), get("variance.B")),
    }
}

/// Samples per pixel of the reference in all, from the JSON beside it.
fn reference_samples(case: &Case) -> u64 {
    let path = root().join(format!("tests/reference/mitsuba/{}.json", case.name));
    let meta: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    meta["spp_per_render"].as_u64().unwrap() * meta["renders"].as_u64().unwrap()
}

/// umbra's render of `case` with `options` at `spp` (Russian roulette off, as in the reference),
/// after `edit` changed the loaded scene.
fn render(
    gpu: &Gpu,
    case: &Case,
    options: PathOptions,
    spp: u32,
    seed: u32,
    edit: impl FnOnce(&mut Scene),
) -> PathImage {
    let mut scene = Scene::load(&root().join("scenes").join(case.gltf)).unwrap();
    edit(&mut scene);
    let camera = scene.camera(None).unwrap();
    let mut device_scene = GpuScene::upload(gpu, &scene).unwrap();
    if case.environment {
        let map =
            umbra::environment::EnvironmentMap::load(&root().join("tests/reference/sky-128x64.exr")).unwrap();
        device_scene.set_environment(gpu, &map).unwrap();
    }
    let settings = PathSettings {
        size: case.size,
        spp,
        seed,
        max_bounces: 8,
        rr_depth: 1 << 20,
        microfacet: options.microfacet,
        heuristic: options.heuristic,
        strategy: options.strategy,
        env: if case.environment { [1.0; 3] } else { [0.0; 3] },
        // Independent numbers: the z-tests take a pixel's own sample variance, which the default
        // low-discrepancy numbers over-estimate (their samples are stratified), costing the tests
        // their power. Both draw each sample from the same distribution, so both have the same
        // expectation; tests/convergence.rs follows the default's error down against this
        // reference.
        sampler: Sampler::Independent,
        ..Default::default()
    };
    let image = path_trace(gpu, &device_scene, &camera, &settings, |_, _| {}).unwrap();
    assert_eq!(image.nonfinite_samples, 0);
    image
}

/// Two-sided tail of the standard normal: P(|Z| > z).
fn normal_two_sided(z: f64) -> f64 {
    gamma_q(0.5, 0.5 * z * z)
}

/// The smallest k with P(X > k) ≤ alpha for X ~ binomial(n, p).
fn binomial_quantile(n: usize, p: f64, alpha: f64) -> usize {
    let ln_choose = |k: usize| -> f64 { (1..=k).map(|i| ((n - k + i) as f64 / i as f64).ln()).sum() };
    let mut cdf = 0.0;
    for k in 0..=n {
        cdf += (ln_choose(k) + k as f64 * p.ln() + (n - k) as f64 * (1.0 - p).ln()).exp();
        if 1.0 - cdf <= alpha {
            return k;
        }
    }
    n
}

/// The comparison's statistics.
#[derive(Debug)]
struct Agreement {
    mean_z2: f64,
    beyond: usize,
    beyond_bound: usize,
    block_chi2: f64,
    block_dof: usize,
    block_p: f64,
    image_z: [f64; 3],
    image_p: f64,
    /// (umbra − reference) / reference of the image mean, per channel.
    relative: [f64; 3],
}

impl Agreement {
    /// Why the images disagree beyond noise, or None; `pixels`: with the per-pixel statistic.
    fn rejection(&self, pixels: bool) -> Option<String> {
        let alpha = alpha();
        let mut why = Vec::new();
        if pixels && self.beyond > self.beyond_bound {
            why.push(format!(
                "{} pixel channels beyond |z| {PIXEL_Z} (at most {})",
                self.beyond, self.beyond_bound
            ));
        }
        if self.block_p < alpha {
            why.push(format!(
                "blocks: chi2 {:.1} on {} dof, p {:.2e}",
                self.block_chi2, self.block_dof, self.block_p
            ));
        }
        if self.image_p < alpha {
            why.push(format!(
                "image mean z {:?}, p {:.2e}",
                self.image_z.map(|z| (z * 100.0).round() / 100.0),
                self.image_p
            ));
        }
        (!why.is_empty()).then(|| why.join("; "))
    }
}

fn z_of(d: f64, var: f64) -> f64 {
    if var > 0.0 {
        d / var.sqrt()
    } else if d == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

fn compare(case: &Case, image: &PathImage, reference: &Reference, label: &str) -> Agreement {
    let (w, h) = (case.size.0 as usize, case.size.1 as usize);
    let variance = image.variance_of_mean();
    let ref_samples = reference_samples(case) as f64;
    let umbra: Vec<[f64; 3]> = image.mean.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
    // Per pixel channel: the difference and its variance.
    let pixel = |i: usize, c: usize| {
        let (u, r) = (umbra[i][c], reference.mean[i][c]);
        let rounding = 1e-5 * u.abs().max(r.abs());
        let per_sample = reference.variance[i][c] * ref_samples;
        let umbra_var = (variance[i][c] as f64).max(per_sample / image.spp as f64);
        (u - r, umbra_var + reference.variance[i][c] + rounding * rounding)
    };
    let z: Vec<[f64; 3]> =
        (0..w * h).map(|i| [0, 1, 2].map(|c| z_of(pixel(i, c).0, pixel(i, c).1))).collect();
    let beyond = z.iter().flatten().filter(|z| z.abs() > PIXEL_Z).count();
    let sum_z2: f64 = z.iter().flatten().map(|z| z * z).sum();
    let n = w * h * 3;
    let (mut block_chi2, mut block_dof) = (0.0, 0);
    for by in 0..h / BLOCK {
        for bx in 0..w / BLOCK {
            for c in 0..3 {
                let (mut d, mut var) = (0.0, 0.0);
                for y in by * BLOCK..(by + 1) * BLOCK {
                    for x in bx * BLOCK..(bx + 1) * BLOCK {
                        let (dp, vp) = pixel(y * w + x, c);
                        d += dp;
                        var += vp;
                    }
                }
                block_chi2 += z_of(d, var).powi(2);
                block_dof += 1;
            }
        }
    }
    let block_p =
        if block_chi2.is_finite() { gamma_q(block_dof as f64 / 2.0, block_chi2 / 2.0) } else { 0.0 };
    let mut image_z = [0.0; 3];
    let mut relative = [0.0; 3];
    for c in 0..3 {
        let (mut d, mut var, mut r) = (0.0, 0.0, 0.0);
        for i in 0..w * h {
            let (dp, vp) = pixel(i, c);
            d += dp;
            var += vp;
            r += reference.mean[i][c];
        }
        image_z[c] = z_of(d, var);
        relative[c] = d / r;
    }
    let worst = image_z.iter().fold(0.0f64, |m, z| m.max(z.abs()));
    let image_p = 1.0 - (1.0 - normal_two_sided(worst)).powi(3);
    let agreement = Agreement {
        mean_z2: sum_z2 / n as f64,
        beyond,
        beyond_bound: binomial_quantile(n, 2.0 * 0.0005, alpha()),
        block_chi2,
        block_dof,
        block_p,
        image_z,
        image_p,
        relative,
    };
    eprintln!(
        "{label}: {} spp; pixels: mean z² {:.3}, |z| > {PIXEL_Z}: {} of {} ({:.4}, bound {}); blocks {BLOCK}×{BLOCK}: χ² {:.1} on {} dof (p {:.3e}); image mean z {:.2?}, relative difference {:+.4?}",
        image.spp,
        agreement.mean_z2,
        agreement.beyond,
        n,
        agreement.beyond as f64 / n as f64,
        agreement.beyond_bound,
        agreement.block_chi2,
        agreement.block_dof,
        agreement.block_p,
        agreement.image_z,
        agreement.relative,
    );
    if let Some(dir) = std::env::var_os("UMBRA_MITSUBA_DEBUG") {
        write_debug(Path::new(&dir), label, (w, h), &umbra, reference, &z);
    }
    agreement
}

/// umbra's image, the reference and z, as one EXR per comparison.
fn write_debug(
    dir: &Path,
    label: &str,
    (w, h): (usize, usize),
    umbra: &[[f64; 3]],
    reference: &Reference,
    z: &[[f64; 3]],
) {
    use umbra::output::{write_exr, Layer};
    std::fs::create_dir_all(dir).unwrap();
    let flat = |v: &[[f64; 3]]| v.iter().flat_map(|p| p.map(|x| x as f32)).collect::<Vec<f32>>();
    let (u, r, zf) = (flat(umbra), flat(&reference.mean), flat(z));
    let rgb = ["R", "G", "B"];
    let layers = [
        Layer { name: "", channels: &rgb, data: &u },
        Layer { name: "reference", channels: &rgb, data: &r },
        Layer { name: "z", channels: &rgb, data: &zf },
    ];
    let path = dir.join(format!("{}.exr", label.replace([' ', '%', '/'], "-")));
    write_exr(&path, w, h, &layers).unwrap();
    eprintln!("wrote {}", path.display());
}

fn agrees(case: &Case) {
    let gpu = Gpu::new();
    let image = render(&gpu, case, default_options(case), case.spp, 1, |_| {});
    let agreement = compare(case, &image, &reference(case), case.name);
    if let Some(why) = agreement.rejection(true) {
        panic!("{}: umbra and Mitsuba disagree beyond noise: {why}", case.name);
    }
}

/// Every estimator of [`estimators`] for `case` sampling `microfacet` agrees with the reference.
fn estimators_agree(case: &Case, microfacet: Microfacet) {
    let gpu = Gpu::new();
    let reference = reference(case);
    let mut failures = Vec::new();
    for e in estimators().iter().filter(|e| std::ptr::eq(e.case, case) && e.options.microfacet == microfacet)
    {
        let o = e.options;
        let label =
            format!("{} {} {} {}", case.name, microfacet.name(), o.strategy.name(), o.heuristic.name());
        let image = render(&gpu, case, o, e.spp, 1, |_| {});
        if let Some(why) = compare(case, &image, &reference, &label).rejection(e.pixel_test) {
            failures.push(format!("{label}: {why}"));
        }
    }
    assert!(failures.is_empty(), "umbra and Mitsuba disagree beyond noise:\n{}", failures.join("\n"));
}

/// Scales every material's base colour factor by `factor`.
fn scale_base_colour(scene: &mut Scene, factor: f32) {
    for m in &mut scene.materials {
        for c in &mut m.base_color_factor[..3] {
            *c *= factor;
        }
    }
}

#[test]
fn cornell_box_agrees_with_mitsuba() {
    agrees(&CORNELL);
}

#[test]
fn spheres_under_the_sky_agree_with_mitsuba() {
    agrees(&SPHERES);
}

#[test]
fn beckmann_spheres_under_the_sky_agree_with_mitsuba() {
    agrees(&SPHERES_BECKMANN);
}

#[test]
fn textured_scene_with_point_and_spot_lights_agrees_with_mitsuba() {
    agrees(&TEXTURED);
}

#[test]
fn rough_glass_under_the_sky_agrees_with_mitsuba() {
    agrees(&GLASS);
}

/// A base colour 2 % darker on every material must be told apart from the reference: with the
/// default estimator, and with BSDF sampling alone in the Cornell box, which is tested without
/// the per-pixel statistic ([`estimators`]).
#[test]
fn a_two_percent_darker_base_colour_is_rejected() {
    let gpu = Gpu::new();
    let bsdf_only = PathOptions { strategy: Strategy::Bsdf, ..default_options(&CORNELL) };
    for (case, options, pixels) in [
        (&CORNELL, default_options(&CORNELL), true),
        (&TEXTURED, default_options(&TEXTURED), true),
        (&CORNELL, bsdf_only, false),
    ] {
        let image = render(&gpu, case, options, case.spp, 1, |scene| scale_base_colour(scene, 0.98));
        let label = format!("{} {} base colour -2%", case.name, options.strategy.name());
        let agreement = compare(case, &image, &reference(case), &label);
        assert!(
            agreement.rejection(pixels).is_some(),
            "{label}: a 2 % darker base colour passed: {agreement:?}"
        );
    }
}

/// Every transmissive material of `scene`.
fn glass(scene: &mut Scene) -> impl Iterator<Item = &mut umbra::scene::Material> {
    scene.materials.iter_mut().filter(|m| m.transmission_factor > 0.0)
}

/// Glass whose index of refraction is 1.45 instead of 1.5 (its Fresnel reflectance and its
/// refraction both change), and glass whose base colour, which tints what it transmits, is 2 %
/// darker, must each be told apart from the reference.
#[test]
fn wrong_glass_is_rejected() {
    let gpu = Gpu::new();
    let reference = reference(&GLASS);
    let ior: fn(&mut Scene) = |scene| glass(scene).for_each(|m| m.ior = 1.45);
    let tint: fn(&mut Scene) =
        |scene| glass(scene).for_each(|m| m.base_color_factor[..3].iter_mut().for_each(|c| *c *= 0.98));
    for (what, edit) in [("ior 1.45", ior), ("transmission tint -2%", tint)] {
        let image = render(&gpu, &GLASS, default_options(&GLASS), GLASS.spp, 1, edit);
        let agreement = compare(&GLASS, &image, &reference, &format!("glass {what}"));
        assert!(agreement.rejection(true).is_some(), "glass, {what}: passed: {agreement:?}");
    }
}

/// Emission found by BSDF sampling counted without its MIS weight must be told apart.
#[test]
fn a_missing_mis_weight_is_rejected() {
    let gpu = Gpu::new();
    for case in [&CORNELL, &SPHERES] {
        let options = PathOptions { heuristic: Heuristic::UnweightedBsdfHits, ..default_options(case) };
        let image = render(&gpu, case, options, case.spp, 1, |_| {});
        let agreement = compare(case, &image, &reference(case), &format!("{} without MIS weight", case.name));
        assert!(
            agreement.rejection(true).is_some(),
            "{}: a missing MIS weight passed: {agreement:?}",
            case.name
        );
    }
}

#[test]
fn cornell_box_estimators_agree_with_mitsuba() {
    estimators_agree(&CORNELL, Microfacet::Ggx);
}

#[test]
fn cornell_box_estimators_with_walter_sampling_agree_with_mitsuba() {
    estimators_agree(&CORNELL, Microfacet::GgxWalter);
}

#[test]
fn spheres_under_the_sky_estimators_agree_with_mitsuba() {
    estimators_agree(&SPHERES, Microfacet::Ggx);
}

#[test]
fn spheres_under_the_sky_estimators_with_walter_sampling_agree_with_mitsuba() {
    estimators_agree(&SPHERES, Microfacet::GgxWalter);
}

#[test]
fn beckmann_spheres_under_the_sky_estimators_agree_with_mitsuba() {
    estimators_agree(&SPHERES_BECKMANN, Microfacet::Beckmann);
}
