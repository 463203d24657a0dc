//! KHR_materials_iridescence: the thin-film Fresnel of bsdf.glsl (`iridescent_fresnel`, which
//! the path tracer and the hybrid share) against an independent float64 reference written here
//! from the physics (the Airy reflectance of a film, exact Fresnel amplitudes for both
//! polarisations, integrated over wavelength against the tabulated CIE 1931 colour matching
//! functions), and the extension's rules through whole renders: no film at weight or thickness 0,
//! the weight from the R channel of `iridescenceTexture` and the thickness from the G channel of
//! `iridescenceThicknessTexture`.

mod common;

use common::quad::{same, slot, MODES};
use common::Gpu;
use std::f64::consts::PI;
use umbra::scene::{Material, Scene, Texture};

/// The CIE 1931 2° standard observer (x̄, ȳ, z̄) from 380 to 780 nm every 5 nm (CIE 015:2018's
/// table).
#[rustfmt::skip]
const CIE_1931: [[f64; 3]; 81] = [
    [0.001368, 0.000039, 0.006450], [0.002236, 0.000064, 0.010550], [0.004243, 0.000120, 0.020050],
    [0.007650, 0.000217, 0.036210], [0.014310, 0.000396, 0.067850], [0.023190, 0.000640, 0.110200],
    [0.043510, 0.001210, 0.207400], [0.077630, 0.002180, 0.371300], [0.134380, 0.004000, 0.645600],
    [0.214770, 0.007300, 1.039050], [0.283900, 0.011600, 1.385600], [0.328500, 0.016840, 1.622960],
    [0.348280, 0.023000, 1.747060], [0.348060, 0.029800, 1.782600], [0.336200, 0.038000, 1.772110],
    [0.318700, 0.048000, 1.744100], [0.290800, 0.060000, 1.669200], [0.251100, 0.073900, 1.528100],
    [0.195360, 0.090980, 1.287640], [0.142100, 0.112600, 1.041900], [0.095640, 0.139020, 0.812950],
    [0.058010, 0.169300, 0.616200], [0.032010, 0.208020, 0.465180], [0.014700, 0.258600, 0.353300],
    [0.004900, 0.323000, 0.272000], [0.002400, 0.407300, 0.212300], [0.009300, 0.503000, 0.158200],
    [0.029100, 0.608200, 0.111700], [0.063270, 0.710000, 0.078250], [0.109600, 0.793200, 0.057250],
    [0.165500, 0.862000, 0.042160], [0.225750, 0.914850, 0.029840], [0.290400, 0.954000, 0.020300],
    [0.359700, 0.980300, 0.013400], [0.433450, 0.994950, 0.008750], [0.512050, 1.000000, 0.005750],
    [0.594500, 0.995000, 0.003900], [0.678400, 0.978600, 0.002750], [0.762100, 0.952000, 0.002100],
    [0.842500, 0.915400, 0.001800], [0.916300, 0.870000, 0.001650], [0.978600, 0.816300, 0.001400],
    [1.026300, 0.757000, 0.001100], [1.056700, 0.694900, 0.001000], [1.062200, 0.631000, 0.000800],
    [1.045600, 0.566800, 0.000600], [1.002600, 0.503000, 0.000340], [0.938400, 0.441200, 0.000240],
    [0.854450, 0.381000, 0.000190], [0.751400, 0.321000, 0.000100], [0.642400, 0.265000, 0.000050],
    [0.541900, 0.217000, 0.000030], [0.447900, 0.175000, 0.000020], [0.360800, 0.138200, 0.000010],
    [0.283500, 0.107000, 0.000000], [0.218700, 0.081600, 0.000000], [0.164900, 0.061000, 0.000000],
    [0.121200, 0.044580, 0.000000], [0.087400, 0.032000, 0.000000], [0.063600, 0.023200, 0.000000],
    [0.046770, 0.017000, 0.000000], [0.032900, 0.011920, 0.000000], [0.022700, 0.008210, 0.000000],
    [0.015840, 0.005723, 0.000000], [0.011359, 0.004102, 0.000000], [0.008111, 0.002929, 0.000000],
    [0.005790, 0.002091, 0.000000], [0.004109, 0.001484, 0.000000], [0.002899, 0.001047, 0.000000],
    [0.002049, 0.000740, 0.000000], [0.001440, 0.000520, 0.000000], [0.001000, 0.000361, 0.000000],
    [0.000690, 0.000249, 0.000000], [0.000476, 0.000172, 0.000000], [0.000332, 0.000120, 0.000000],
    [0.000235, 0.000085, 0.000000], [0.000166, 0.000060, 0.000000], [0.000117, 0.000042, 0.000000],
    [0.000083, 0.000030, 0.000000], [0.000059, 0.000021, 0.000000], [0.000042, 0.000015, 0.000000],
];

/// CIE XYZ to linear Rec. 709 (sRGB primaries, D65 white), rows.
const XYZ_TO_REC709: [[f64; 3]; 3] = [
    [3.2404542, -1.5371385, -0.4985314],
    [-0.9692660, 1.8760108, 0.0415560],
    [0.0556434, -0.2040259, 1.0572252],
];

#[derive(Clone, Copy)]
struct Complex(f64, f64);

impl Complex {
    fn add(self, o: Complex) -> Complex {
        Complex(self.0 + o.0, self.1 + o.1)
    }
    fn mul(self, o: Complex) -> Complex {
        Complex(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn norm2(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
}

/// Fresnel's amplitude reflection coefficients (s, p) from index n1 into n2 at cosine c1 in n1,
/// and the cosine in n2 (real indices, no total internal reflection in the cases used).
fn fresnel_amplitudes(n1: f64, n2: f64, c1: f64) -> (f64, f64, f64) {
    let s2 = n1 / n2 * (1.0 - c1 * c1).sqrt();
    let c2 = (1.0 - s2 * s2).sqrt();
    let rs = (n1 * c1 - n2 * c2) / (n1 * c1 + n2 * c2);
    let rp = (n2 * c1 - n1 * c2) / (n2 * c1 + n1 * c2);
    (rs, rp, c2)
}

/// The reflectance of a film (index `film`, `thickness` nm) between air and a base of index
/// `base`, lit at cosine `cos1` in air by unpolarised light of wavelength `lambda` nm: the Airy
/// sum of all round trips, r = (r12 + r23 e^{iδ}) / (1 + r12 r23 e^{iδ}) with δ = 4π n d cos θ2 / λ,
/// |r|² averaged over s and p.
fn airy_reflectance(film: f64, base: f64, thickness: f64, cos1: f64, lambda: f64) -> f64 {
    let (rs12, rp12, c2) = fresnel_amplitudes(1.0, film, cos1);
    let (rs23, rp23, _) = fresnel_amplitudes(film, base, c2);
    let delta = 4.0 * PI * film * thickness * c2 / lambda;
    let e = Complex(delta.cos(), delta.sin());
    let r = |r12: f64, r23: f64| {
        let num = Complex(r12, 0.0).add(Complex(r23, 0.0).mul(e));
        let den = Complex(1.0, 0.0).add(Complex(r12 * r23, 0.0).mul(e));
        num.norm2() / den.norm2()
    };
    0.5 * (r(rs12, rs23) + r(rp12, rp23))
}

/// The film's reflectance as linear Rec. 709 colour: per channel the base's index from that
/// channel's F0 (n = (1 + √F0) / (1 − √F0), as the extension derives it), the spectral
/// reflectance integrated against the colour matching functions (equal-energy light, normalised
/// by ∫ȳ), converted to Rec. 709 and white-balanced so a constant reflectance keeps its value
/// (the extension takes the Airy sum's mean as that constant).
fn reference_film(film: f64, thickness: f64, base_f0: [f64; 3], cos1: f64) -> [f64; 3] {
    let y_sum: f64 = CIE_1931.iter().map(|c| c[1]).sum();
    let to_rgb = |xyz: [f64; 3]| XYZ_TO_REC709.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2]);
    let white = to_rgb(std::array::from_fn(|k| CIE_1931.iter().map(|c| c[k]).sum::<f64>() / y_sum));
    std::array::from_fn(|channel| {
        let root = base_f0[channel].clamp(0.0, 0.9999).sqrt();
        let base = (1.0 + root) / (1.0 - root);
        let mut xyz = [0.0; 3];
        for (i, cmf) in CIE_1931.iter().enumerate() {
            let r = airy_reflectance(film, base, thickness, cos1, 380.0 + 5.0 * i as f64);
            for k in 0..3 {
                xyz[k] += r * cmf[k] / y_sum;
            }
        }
        to_rgb(xyz)[channel] / white[channel]
    })
}

/// `iridescent_fresnel` on the GPU (sample_test.comp mode 4) for (cos, thickness, film ior, F0).
fn gpu_film(gpu: &Gpu, cases: &[(f64, f64, f64, [f64; 3])]) -> Vec<[f64; 3]> {
    let input: Vec<[f32; 4]> = cases
        .iter()
        .flat_map(|&(c, d, n, f0)| {
            [[c as f32, d as f32, n as f32, 0.0], [f0[0] as f32, f0[1] as f32, f0[2] as f32, 0.0]]
        })
        .collect();
    common::sample_test_rgb(gpu, "film", 4, &input, cases.len() as u32)
}

/// The reference's own checks: the colour matching functions' three integrals are equal (the
/// table is the CIE's: 106.86 nm each, within 0.01 %), and a film of thickness 0 reflects what
/// the bare base does (Fresnel's unpolarised reflectance between air and the base).
#[test]
fn the_reference_is_sound() {
    let sums: Vec<f64> = (0..3).map(|k| 5.0 * CIE_1931.iter().map(|c| c[k]).sum::<f64>()).collect();
    assert!(sums.iter().all(|s| (s - 106.857).abs() < 0.011), "{sums:?}");
    for (film, base, c) in [(1.3, 1.5, 1.0), (2.0, 1.2, 0.6), (1.6, 3.0, 0.3)] {
        let (rs, rp, _) = fresnel_amplitudes(1.0, base, c);
        let bare = 0.5 * (rs * rs + rp * rp);
        let f0 = ((base - 1.0) / (base + 1.0)).powi(2);
        let zero = reference_film(film, 0.0, [f0; 3], c);
        assert!(zero.iter().all(|z| (z - bare).abs() < 1e-9), "{zero:?} vs {bare}");
    }
}

/// The GPU's thin-film Fresnel against the reference: films of index 1.3, 1.6 and 2.0 over
/// dielectric bases of index 1.2, 1.5 and 2.0 and over two metals' F0 (gold-like (1, 0.78, 0.34),
/// copper-like (0.96, 0.64, 0.54)), at normal incidence and at cos 0.75, each over thicknesses
/// 100 to 800 nm in steps of 25 (the extension's default range and beyond).
///
/// Tolerance: per case, the RMS over the thicknesses of the largest channel error at most 0.032
/// and every error at most 0.06. The extension's formula is an approximation of the reference,
/// and its own error, measured in float64 over these cases (scratch computation), is at most 0.054
/// (RMS 0.029, for a film of index 2 over a base of 1.2, whose interference is the strongest:
/// the reference's values span ±0.1 there): the oscillating terms pass through XYZ → Rec. 709
/// without the white balance that its mean (taken as grey) implies, up to 20 % too red (most of
/// the error: 0.046 → 0.015 with it); Gaussian fits for the colour matching functions; Schlick's
/// form for both interfaces (exact at normal incidence); the Airy sum cut after two round trips;
/// float32 adds below 1e-4. Caught, measured the same way: the optical path without its factor 2
/// (max error 0.46), the phase shift π at the film's upper interface dropped (0.48) or at the base
/// (0.44), the path length at the outer angle instead of the refracted one (0.45), a thickness
/// 10 % off (0.33), the interference terms without their factor 2 (0.15), the colour matrix
/// transposed (0.13). Not caught (below the formula's own error): the second round trip dropped.
#[test]
fn thin_film_fresnel_matches_an_airy_reference() {
    let gpu = Gpu::new();
    let thicknesses: Vec<f64> = (0..=28).map(|k| 100.0 + 25.0 * k as f64).collect();
    let mut bases: Vec<(String, [f64; 3])> = [1.2, 1.5, 2.0]
        .iter()
        .map(|&n: &f64| (format!("ior {n}"), [((n - 1.0) / (n + 1.0)).powi(2); 3]))
        .collect();
    bases.push(("gold".into(), [1.0, 0.782, 0.344]));
    bases.push(("copper".into(), [0.955, 0.638, 0.538]));
    let mut failures = Vec::new();
    let (mut worst_rms, mut worst_max) = (0.0f64, 0.0f64);
    for cos in [1.0, 0.75] {
        for film in [1.3, 1.6, 2.0] {
            for (name, f0) in &bases {
                let cases: Vec<_> = thicknesses.iter().map(|&d| (cos, d, film, *f0)).collect();
                let gpu_values = gpu_film(&gpu, &cases);
                let errors: Vec<f64> = thicknesses
                    .iter()
                    .zip(&gpu_values)
                    .map(|(&d, g)| {
                        let r = reference_film(film, d, *f0, cos);
                        (0..3).map(|k| (g[k] - r[k]).abs()).fold(0.0, f64::max)
                    })
                    .collect();
                let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
                let max = errors.iter().copied().fold(0.0, f64::max);
                eprintln!("cos {cos} film {film} base {name}: RMS error {rms:.4}, max {max:.4}");
                (worst_rms, worst_max) = (worst_rms.max(rms), worst_max.max(max));
                if rms > 0.032 || max > 0.06 {
                    failures.push(format!("cos {cos} film {film} base {name}: RMS {rms:.4}, max {max:.4}"));
                }
            }
        }
    }
    eprintln!("worst: RMS {worst_rms:.4}, max {worst_max:.4}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The quad of `common::quad::scene` under a sun of 2 lux.
fn scene(material: Material, texture: Option<Texture>) -> Scene {
    common::quad::scene("film", material, texture, 2.0)
}

/// `common::quad::renders` under a sky of 0.5.
fn renders(gpu: &Gpu, scene: &Scene) -> [Vec<[f32; 4]>; 2] {
    common::quad::renders(gpu, scene, 0.5)
}

/// A linear 1×1 texture of `texel`.
fn texel_texture(texel: [u8; 4]) -> Texture {
    common::row_texture("film", &[texel])
}

/// Half metal, half dielectric, so both Fresnels show the film.
fn filmed(iridescence: f32, thickness: [f32; 2]) -> Material {
    Material {
        base_color_factor: [0.6, 0.5, 0.4, 1.0],
        metallic: 0.5,
        roughness: 0.35,
        double_sided: true,
        iridescence,
        iridescence_ior: 1.8,
        iridescence_thickness: thickness,
        ..Default::default()
    }
}

/// A film of weight 0 or of thickness 0 is no film: the same quad renders as without the
/// extension (within 1e-4 per pixel, both modes), in kernels specialised for the film (the
/// weight is 1 and the texture, or the thickness, takes it to 0): weight 0 from
/// `iridescenceTexture`'s R; thickness 0 from minimum = maximum = 0, and from a thickness texture
/// whose G is 0 with minimum 0. A film of 300 nm changes most pixels (so the comparison can fail:
/// the extension's formula at thickness 0 is not the bare Fresnel, 0.030 against 0.040 at normal
/// incidence for this film).
#[test]
fn no_film_at_weight_or_thickness_zero() {
    let gpu = Gpu::new();
    let plain = renders(&gpu, &scene(filmed(0.0, [100.0, 400.0]), None));
    let cases = [
        (
            "weight texture R = 0",
            Material { iridescence_texture: slot(), ..filmed(1.0, [300.0, 300.0]) },
            true,
        ),
        ("thickness 0", filmed(1.0, [0.0, 0.0]), false),
        (
            "thickness texture G = 0",
            Material { iridescence_thickness_texture: slot(), ..filmed(1.0, [0.0, 400.0]) },
            true,
        ),
    ];
    let mut failures = Vec::new();
    for (name, material, textured) in cases {
        let images = renders(&gpu, &scene(material, textured.then(|| texel_texture([0, 0, 255, 255]))));
        for (mode, (image, plain)) in MODES.iter().zip(images.iter().zip(&plain)) {
            if let Some((i, (p, q))) = image.iter().zip(plain).enumerate().find(|(_, (p, q))| !same(p, q)) {
                failures.push(format!("{name}, {mode}: pixel {i}: {p:?}, without a film {q:?}"));
            }
        }
    }
    let film = renders(&gpu, &scene(filmed(1.0, [300.0, 300.0]), None));
    for (mode, (image, plain)) in MODES.iter().zip(film.iter().zip(&plain)) {
        let differ = image.iter().zip(plain).filter(|(p, q)| !same(p, q)).count();
        if differ <= image.len() / 2 {
            failures.push(format!("{mode}: a 300 nm film changes only {differ} pixels"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The film's textures: a texel whose channels all differ (R 153, G 51, B 200, A 100) in
/// `iridescenceTexture` renders as its R folded into the factor, and in
/// `iridescenceThicknessTexture` as its G placing the thickness between the minimum (100 nm) and
/// the maximum (500 nm), in both modes (the hybrid carries the texels in its G-buffer); a slot
/// that read another channel would not match. Each texel also changes the image against the
/// factors alone (weight 0.9, thickness the maximum).
#[test]
fn film_textures_read_r_and_g() {
    let gpu = Gpu::new();
    // Linear texels: n/255 is exact as the stored unorm16, and as the G-buffer's unorm16.
    let texel = [153u8, 51, 200, 100];
    let t = texel.map(|c| c as f32 / 255.0);
    let (lo, hi) = (100.0f32, 500.0f32);
    let thickness = lo + (hi - lo) * t[1];
    let cases = [
        (
            "iridescenceTexture",
            Material { iridescence_texture: slot(), ..filmed(0.9, [lo, hi]) },
            filmed(0.9 * t[0], [lo, hi]),
        ),
        (
            "iridescenceThicknessTexture",
            Material { iridescence_thickness_texture: slot(), ..filmed(0.9, [lo, hi]) },
            filmed(0.9, [thickness, thickness]),
        ),
    ];
    let factor = renders(&gpu, &scene(filmed(0.9, [lo, hi]), None));
    let mut failures = Vec::new();
    for (name, textured, folded) in cases {
        let a = renders(&gpu, &scene(textured, Some(texel_texture(texel))));
        let b = renders(&gpu, &scene(folded, None));
        for (mode, ((a, b), f)) in MODES.iter().zip(a.iter().zip(&b).zip(&factor)) {
            if let Some((i, (p, q))) = a.iter().zip(b).enumerate().find(|(_, (p, q))| !same(p, q)) {
                failures
                    .push(format!("{name}, {mode}: pixel {i}: textured {p:?} vs the texel folded in {q:?}"));
            }
            let differ = b.iter().zip(f).filter(|(p, q)| !same(p, q)).count();
            if differ <= a.len() / 2 {
                failures.push(format!("{name}, {mode}: the texel changes only {differ} pixels"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
