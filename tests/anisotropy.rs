//! `KHR_materials_anisotropy`: the anisotropic BSDF against the extension's formula written here,
//! its white furnace against an independent quadrature, and, through the path tracer on generated
//! scenes, the direction's conventions (the rotation turns from the tangent towards the
//! bitangent; the texture's RG is the direction, its B scales the strength) and the surface
//! without a tangent frame, which renders isotropic. The chi-square test of its sampling is in
//! tests/sampling/ (the `Anisotropic` cases), the hybrid against the path tracer in
//! tests/ibl/, the loading in tests/scene/.

mod common;

use common::Gpu;
use glam::{DVec3, Vec3};
use umbra::gpu::kernels::sample_test;
use umbra::gpu::layout::SampleTestParams;
use umbra::gpu::scene::GpuScene;
use umbra::gpu::Pipeline;
use umbra::render::{path_trace, PathImage, PathSettings};
use umbra::scene::{LightKind, Material, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

/// `sample_test.comp` on its anisotropic surface (kind 9): `mode` 3 evaluates bsdf_eval (rgb) and
/// bsdf_pdf (w) at `dirs`, mode 5 draws `count` bsdf_sample weights.
#[allow(clippy::too_many_arguments)]
fn run(
    gpu: &Gpu,
    pipeline: &Pipeline<sample_test::Kernel>,
    mode: u32,
    wo: DVec3,
    alpha: f64,
    anisotropy: [f32; 4],
    dirs: &[[f32; 4]],
    count: u32,
) -> Vec<[f32; 4]> {
    let params = SampleTestParams {
        wo: wo.as_vec3().into(),
        alpha: alpha as f32,
        mode,
        count,
        seed: 777,
        kind: 9,
        anisotropy,
        anisotropy_base: 1.0,
        ..Default::default()
    };
    common::sample_test_run(gpu, pipeline, &params, dirs)
}

/// The extension's anisotropic GGX for a white metal (F = 1): D G1(o) G1(i) / (4 o.z i.z) with
/// α_t = α + (1 − α) strength² along the direction at angle `direction` from x towards y, α_b = α
/// across it; Smith's G1 = 1 / (1 + Λ), Λ(w) = (√(1 + (α_t² w_t² + α_b² w_b²) / w_z²) − 1) / 2.
fn white_metal(wo: DVec3, wi: DVec3, alpha: f64, strength: f64, direction: f64) -> f64 {
    let (s, c) = direction.sin_cos();
    let frame = |v: DVec3| DVec3::new(c * v.x + s * v.y, c * v.y - s * v.x, v.z);
    let (o, i) = (frame(wo), frame(wi));
    if o.z <= 0.0 || i.z <= 0.0 {
        return 0.0;
    }
    let (at, ab) = (alpha + (1.0 - alpha) * strength * strength, alpha);
    let h = (o + i).normalize();
    let q = (h.x / at).powi(2) + (h.y / ab).powi(2) + h.z * h.z;
    let d = 1.0 / (std::f64::consts::PI * at * ab * q * q);
    let lambda =
        |w: DVec3| (((at * w.x).powi(2) + (ab * w.y).powi(2)) / (w.z * w.z) + 1.0).sqrt() * 0.5 - 0.5;
    d / ((1.0 + lambda(o)) * (1.0 + lambda(i)) * 4.0 * o.z * i.z)
}

fn direction(theta_degrees: f64, phi_degrees: f64) -> DVec3 {
    let (t, p) = (theta_degrees.to_radians(), phi_degrees.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// bsdf_eval of an anisotropic white metal equals the extension's formula (relative 2e-4, f32
/// rounding of a lobe up to 1e3) over a grid of directions, for weak to total anisotropy with the
/// direction off the frame's axes: α_t from strength², the direction along x of the lobe's frame,
/// turned towards +y.
#[test]
fn the_anisotropic_bsdf_is_the_extensions() {
    let gpu = Gpu::new();
    let pipeline = Pipeline::<sample_test::Kernel>::new(&gpu, &sample_test::Spec::default(), None).unwrap();
    let mut dirs = Vec::new();
    for t in 0..9 {
        for p in 0..24 {
            dirs.push(direction(5.0 + 10.0 * t as f64, 15.0 * p as f64));
        }
    }
    let mut worst = 0.0f64;
    for (alpha, strength) in [(0.1, 0.3), (0.1, 1.0), (0.4, 0.7)] {
        for wo in [direction(30.0, 0.0), direction(60.0, 100.0)] {
            let direction = 30f64.to_radians();
            let anisotropy = [strength as f32, direction.cos() as f32, direction.sin() as f32, 1.0];
            let gpu_dirs: Vec<[f32; 4]> = dirs.iter().map(|d| d.as_vec3().extend(0.0).to_array()).collect();
            let out = run(&gpu, &pipeline, 3, wo, alpha, anisotropy, &gpu_dirs, dirs.len() as u32);
            for (wi, f) in dirs.iter().zip(&out) {
                let expected = white_metal(wo, *wi, alpha, strength, direction);
                let error = (f[0] as f64 - expected).abs() / expected.max(1e-3);
                worst = worst.max(error);
                assert!(
                    error < 2e-4,
                    "α {alpha} strength {strength} wo {wo:?} wi {wi:?}: bsdf_eval {} vs the extension's {expected}",
                    f[0]
                );
            }
        }
    }
    eprintln!("largest relative difference {worst:.2e}");
}

/// The white metal's directional albedo by an independent quadrature: half vectors from the
/// anisotropic GGX's D(h) cos θ_h by stretched slopes (a midpoint grid of n × n over the unit
/// square), each weighted by (o·h) G1(o) G1(i) / (o.z h.z) for i the reflection of o.
fn white_metal_albedo(wo: DVec3, alpha: f64, strength: f64, n: usize) -> f64 {
    let (at, ab) = (alpha + (1.0 - alpha) * strength * strength, alpha);
    let g1 = |w: DVec3| 2.0 * w.z / (w.z + ((at * w.x).powi(2) + (ab * w.y).powi(2) + w.z * w.z).sqrt());
    let mut sum = 0.0;
    for a in 0..n {
        let u = (a as f64 + 0.5) / n as f64;
        let r = (u / (1.0 - u)).sqrt();
        for b in 0..n {
            let phi = std::f64::consts::TAU * (b as f64 + 0.5) / n as f64;
            let h = DVec3::new(at * r * phi.cos(), ab * r * phi.sin(), 1.0).normalize();
            let oh = wo.dot(h);
            let i = 2.0 * oh * h - wo;
            if oh > 0.0 && i.z > 0.0 {
                sum += oh * g1(wo) * g1(i) / (wo.z * h.z);
            }
        }
    }
    sum / (n * n) as f64
}

/// The white furnace: bsdf_sample's mean weight f cos / pdf over 2^19 samples is the directional
/// albedo. For the white metal (F = 1) it equals the independent quadrature above (whose own
/// error, 800² against 1600² points, is below 2e-4) within z·se + 2e-4 and stays at most 1; for
/// a white dielectric (the glTF layering of its reflection over the diffuse lobe) it stays at most
/// 1 + z·se up to θo = 45°. (At grazing incidence the layering itself exceeds 1, anisotropic or
/// not: (1 − F) of the diffuse lobe takes F at each pair's half vector while the reflection takes
/// F near grazing; the isotropic surface's albedo is printed beside it.) z = 3.6: two-sided 0.01
/// with a Šidák correction over the 24 comparisons. Weak and total anisotropy, sharp and rough,
/// wo from the normal to grazing, in the lobe's frame at 30° from wo's plane.
#[test]
fn white_furnace_anisotropic() {
    let gpu = Gpu::new();
    let pipeline = Pipeline::<sample_test::Kernel>::new(&gpu, &sample_test::Spec::default(), None).unwrap();
    let z = 3.6;
    let count = 1u32 << 19;
    let direction = 30f64.to_radians();
    for (alpha, strength) in [(0.05, 0.5), (0.05, 1.0), (0.3, 0.5), (0.3, 1.0)] {
        for theta in [0.0, 45.0, 80.0] {
            // The quadrature works in the lobe's frame: wo turned by −30°.
            let wo = direction_of(theta);
            let local = DVec3::new(direction.cos() * wo.x, -direction.sin() * wo.x, wo.z);
            let (coarse, fine) = (
                white_metal_albedo(local, alpha, strength, 800),
                white_metal_albedo(local, alpha, strength, 1600),
            );
            assert!((coarse - fine).abs() < 2e-4, "quadrature {coarse} vs {fine}");
            for metallic in [1.0f32, 0.0] {
                let anisotropy = [strength as f32, direction.cos() as f32, direction.sin() as f32, metallic];
                let out = run(&gpu, &pipeline, 5, wo, alpha, anisotropy, &[], count);
                let (mut sum, mut sum2) = (0.0f64, 0.0f64);
                for w in &out {
                    let w = w[0] as f64;
                    assert!(w.is_finite() && w >= 0.0, "weight {w}");
                    sum += w;
                    sum2 += w * w;
                }
                let n = count as f64;
                let mean = sum / n;
                let se = ((sum2 / n - mean * mean).max(0.0) / n).sqrt();
                let isotropic = || {
                    let out = run(&gpu, &pipeline, 5, wo, alpha, [0.0, 1.0, 0.0, metallic], &[], count);
                    out.iter().map(|w| w[0] as f64).sum::<f64>() / n
                };
                eprintln!(
                    "α {alpha} strength {strength} θo {theta}° metallic {metallic}: albedo {mean:.5} ± {se:.5}{}",
                    if metallic == 1.0 {
                        format!(", quadrature {fine:.5}")
                    } else if theta > 45.0 {
                        format!(" (isotropic {:.5})", isotropic())
                    } else {
                        String::new()
                    }
                );
                if metallic == 1.0 || theta <= 45.0 {
                    assert!(mean <= 1.0 + z * se, "energy above 1: {mean} ± {se}");
                }
                if metallic == 1.0 {
                    assert!(fine <= 1.0, "quadrature {fine}");
                    assert!(
                        (mean - fine).abs() <= z * se + 2e-4,
                        "α {alpha} strength {strength} θo {theta}°: furnace {mean} ± {se} vs quadrature {fine}"
                    );
                }
            }
        }
    }
}

fn direction_of(theta_degrees: f64) -> DVec3 {
    direction(theta_degrees, 0.0)
}

// ---------------------------------------------------------------------------------------------
// The direction through the renderer: a generated metal plate under a point light.

/// A 2 × 2 plate in the xy plane facing the camera (+z) with per-vertex `tangent` (w: the
/// bitangent's sign; 0: no frame), UVs, one white metal of roughness 0.3 and anisotropy
/// (`strength`, `rotation`, `texture`: one RGBA8 texel), a point light beside the camera.
fn plate(tangent: [f32; 4], strength: f32, rotation: f32, texture: Option<[u8; 4]>) -> Scene {
    let mut scene = Scene { name: "anisotropic plate".into(), ..Default::default() };
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    for [x, y] in corners {
        scene.positions.push([x, y, 0.0]);
        scene.normals.push([0.0, 0.0, 1.0]);
        scene.tangents.push(tangent);
        scene.uv0.push([0.5 * (x + 1.0), 0.5 * (1.0 - y)]);
    }
    scene.triangles = vec![[0, 1, 2], [0, 2, 3]];
    scene.triangle_material = vec![0, 0];
    let anisotropy_texture = texture.map(|rgba| {
        scene.textures.push(Texture {
            name: "anisotropy".into(),
            width: 1,
            height: 1,
            rgba8: rgba.to_vec(),
            srgb: false,
            sampler: Default::default(),
        });
        TextureRef { texture: 0, tex_coord: 0, transform: IDENTITY_TRANSFORM, scale: 1.0 }
    });
    scene.materials.push(Material {
        base_color_factor: [1.0; 4],
        metallic: 1.0,
        roughness: 0.3,
        anisotropy_strength: strength,
        anisotropy_rotation: rotation,
        anisotropy_texture,
        ..Default::default()
    });
    scene.lights = vec![common::light(LightKind::Point, Vec3::new(0.4, 0.3, 1.5), Vec3::NEG_Z, 8.0)];
    scene.cameras = vec![common::camera(Vec3::new(0.0, 0.0, 2.2), Vec3::ZERO)];
    scene.update_emissive();
    scene
}

/// Direct light only (the light is a point: the image is a deterministic function of the pixel
/// jitter, the same for every scene).
fn render(gpu: &Gpu, scene: &Scene) -> PathImage {
    let settings = PathSettings { size: (32, 32), spp: 4, max_bounces: 1, ..Default::default() };
    let device = GpuScene::upload(gpu, scene).unwrap();
    path_trace(gpu, &device, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap()
}

/// Mean |a − b| over the pixels relative to a's mean (luminance-free: the green channel).
fn relative_difference(a: &PathImage, b: &PathImage) -> f64 {
    let mean: f64 = a.mean.iter().map(|p| p[1] as f64).sum::<f64>() / a.mean.len() as f64;
    let diff: f64 = a.mean.iter().zip(&b.mean).map(|(p, q)| (p[1] as f64 - q[1] as f64).abs()).sum::<f64>();
    diff / a.mean.len() as f64 / mean
}

const SQRT_HALF: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// anisotropyRotation turns the direction counter-clockwise, from the tangent towards the
/// bitangent (cross(n, t) × w): tangent +x turned by π/4 renders as tangent (x + y)/√2 unturned
/// (within 1e-4 of the mean: float rounding), and clearly unlike tangent (x − y)/√2, the
/// direction a clockwise turn would give (> 5 %). With the bitangent's sign w = −1 the bitangent
/// is −y, so the same turn gives (x − y)/√2.
#[test]
fn the_rotation_turns_from_the_tangent_towards_the_bitangent() {
    let gpu = Gpu::new();
    let quarter = std::f32::consts::FRAC_PI_4;
    let turned = render(&gpu, &plate([1.0, 0.0, 0.0, 1.0], 0.9, quarter, None));
    let along = render(&gpu, &plate([SQRT_HALF, SQRT_HALF, 0.0, 1.0], 0.9, 0.0, None));
    let across = render(&gpu, &plate([SQRT_HALF, -SQRT_HALF, 0.0, 1.0], 0.9, 0.0, None));
    let mirrored = render(&gpu, &plate([1.0, 0.0, 0.0, -1.0], 0.9, quarter, None));
    let (same, other, flipped) = (
        relative_difference(&turned, &along),
        relative_difference(&turned, &across),
        relative_difference(&mirrored, &across),
    );
    eprintln!("turned vs along {same:.2e}, vs across {other:.3}; mirrored frame vs across {flipped:.2e}");
    assert!(same < 1e-4, "tangent x turned by π/4 differs from tangent (x + y)/√2 by {same}");
    assert!(other > 0.05, "the two diagonal directions render alike ({other}): the test has no power");
    assert!(flipped < 1e-4, "with w = −1 the turn goes towards −y: differs by {flipped}");
}

/// anisotropyTexture: RG is the direction in tangent space (2 rg − 1), B scales the strength. A
/// texel (255, 255, 51) with strength 1 renders as no texture with strength 0.2 turned by π/4
/// (within 1e-4); the texel (255, 0, 51), direction (1, −1), renders unlike it (> 5 %), and so
/// does strength 1 turned by π/4 (the B channel ignored).
#[test]
fn the_texture_gives_direction_and_strength() {
    let gpu = Gpu::new();
    let quarter = std::f32::consts::FRAC_PI_4;
    let tangent = [1.0, 0.0, 0.0, 1.0];
    let textured = render(&gpu, &plate(tangent, 1.0, 0.0, Some([255, 255, 51, 255])));
    let factors = render(&gpu, &plate(tangent, 0.2, quarter, None));
    let other_direction = render(&gpu, &plate(tangent, 1.0, 0.0, Some([255, 0, 51, 255])));
    let full_strength = render(&gpu, &plate(tangent, 1.0, quarter, None));
    let (same, direction, strength) = (
        relative_difference(&factors, &textured),
        relative_difference(&factors, &other_direction),
        relative_difference(&factors, &full_strength),
    );
    eprintln!("texture vs factors {same:.2e}; other direction {direction:.3}; B ignored {strength:.3}");
    assert!(same < 1e-4, "the texel (255, 255, 51) differs from strength 0.2 at π/4 by {same}");
    assert!(direction > 0.05, "direction (1, −1) renders like (1, 1): {direction}");
    assert!(strength > 0.05, "strength 0.2 renders like 1: {strength}");
}

/// Without a tangent frame (w = 0, as the loader leaves a primitive without TANGENT and UVs) the
/// surface renders isotropic: the image does not depend on the rotation at all (bit for bit),
/// where with a frame it does (> 5 %).
#[test]
fn without_a_tangent_frame_the_surface_is_isotropic() {
    let gpu = Gpu::new();
    let half = std::f32::consts::FRAC_PI_2;
    let frameless = [1.0, 0.0, 0.0, 0.0];
    let a = render(&gpu, &plate(frameless, 0.9, 0.0, None));
    let b = render(&gpu, &plate(frameless, 0.9, half, None));
    assert!(a.mean == b.mean, "without a frame the rotation changed the image");
    let framed = [1.0, 0.0, 0.0, 1.0];
    let c = render(&gpu, &plate(framed, 0.9, 0.0, None));
    let d = render(&gpu, &plate(framed, 0.9, half, None));
    let difference = relative_difference(&c, &d);
    eprintln!("with a frame, rotation 0 vs π/2: {difference:.3}");
    assert!(difference > 0.05, "with a frame the rotation changes nothing: {difference}");
    // And the frameless image is the isotropic one (the anisotropic kernel's numbers).
    let isotropic = render(&gpu, &plate(framed, 0.0, 0.0, None));
    let from_isotropic = relative_difference(&isotropic, &a);
    assert!(from_isotropic < 1e-4, "frameless differs from isotropic by {from_isotropic}");
}
