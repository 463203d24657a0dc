//! The extensions' layer textures: `KHR_materials_specular`'s `specularTexture` (A) and
//! `specularColorTexture` (RGB), `KHR_materials_transmission`'s `transmissionTexture` (R),
//! `KHR_materials_clearcoat`'s `clearcoatTexture` (R), `clearcoatRoughnessTexture` (G) and
//! `clearcoatNormalTexture` (and the coat's own, unmapped normal), `KHR_materials_sheen`'s
//! `sheenColorTexture` (RGB) and `sheenRoughnessTexture` (A),
//! `KHR_materials_diffuse_transmission`'s `diffuseTransmissionTexture` (A) and
//! `diffuseTransmissionColorTexture` (RGB), in the path tracer and the hybrid renderer (which
//! carries their texels in the G-buffer's `layers` and `layers2` images). A quad facing the
//! camera fills the view; each render is compared with the same scene whose texture is folded
//! into the material's factor, pixel by pixel.

mod common;

use common::quad::{renders, same, slot, MODES, SIZE};
use common::Gpu;
use glam::Vec3;
use umbra::scene::{LightKind, Material, Scene, Texture, TextureRef, IDENTITY_TRANSFORM};

/// The quad of `common::quad::scene`, named for these tests.
fn quad_scene(material: Material, texture: Option<Texture>, sun: f32) -> Scene {
    common::quad::scene("layer textures", material, texture, sun)
}

/// A constant texture in each layer slot renders as the same material with its texel folded into
/// the slot's factor, in both modes. The texel's channels all differ (R 128, G 64, B 200, A 160),
/// so a slot that read another channel than the specification's (A for `specularTexture`, RGB
/// for `specularColorTexture`, R for `transmissionTexture` and `clearcoatTexture`, G for
/// `clearcoatRoughnessTexture`, A for `diffuseTransmissionTexture`, RGB for
/// `diffuseTransmissionColorTexture`, whose lobe the sky behind the quad lights) would not match;
/// the kernels are specialised per texture group (`specular_map`, `transmission_map`,
/// `clearcoat_map`, `diffuse_transmission_map`), so a slot left out of its group would
/// render the factor alone. Every case is also checked to differ from the factor
/// alone, so the texture has something to change.
#[test]
fn each_layer_texture_is_read_alone() {
    let gpu = Gpu::new();
    // Linear texels: n/255 is exact as the stored unorm16 (257 n / 65535), and as the G-buffer's.
    let texel = [128u8, 64, 200, 160];
    let t = texel.map(|c| c as f32 / 255.0);
    let base = Material {
        base_color_factor: [0.6, 0.5, 0.4, 1.0],
        metallic: 0.0,
        roughness: 0.4,
        double_sided: true,
        ..Default::default()
    };
    let cases = [
        (
            "specular",
            Material { specular_factor: 0.9, specular_texture: slot(), ..base.clone() },
            Material { specular_factor: 0.9 * t[3], ..base.clone() },
            Material { specular_factor: 0.9, ..base.clone() },
        ),
        (
            "specular colour",
            Material {
                specular_color_factor: [2.0, 1.5, 1.0],
                specular_color_texture: slot(),
                ..base.clone()
            },
            Material { specular_color_factor: [2.0 * t[0], 1.5 * t[1], t[2]], ..base.clone() },
            Material { specular_color_factor: [2.0, 1.5, 1.0], ..base.clone() },
        ),
        (
            "transmission",
            Material { transmission_factor: 0.9, transmission_texture: slot(), ..base.clone() },
            Material { transmission_factor: 0.9 * t[0], ..base.clone() },
            Material { transmission_factor: 0.9, ..base.clone() },
        ),
        (
            "clear coat",
            Material { clearcoat: 0.9, clearcoat_roughness: 0.2, clearcoat_texture: slot(), ..base.clone() },
            Material { clearcoat: 0.9 * t[0], clearcoat_roughness: 0.2, ..base.clone() },
            Material { clearcoat: 0.9, clearcoat_roughness: 0.2, ..base.clone() },
        ),
        (
            "clear coat roughness",
            Material {
                clearcoat: 1.0,
                clearcoat_roughness: 0.8,
                clearcoat_roughness_texture: slot(),
                ..base.clone()
            },
            Material { clearcoat: 1.0, clearcoat_roughness: 0.8 * t[1], ..base.clone() },
            Material { clearcoat: 1.0, clearcoat_roughness: 0.8, ..base.clone() },
        ),
        (
            "diffuse transmission",
            Material { diffuse_transmission: 0.9, diffuse_transmission_texture: slot(), ..base.clone() },
            Material { diffuse_transmission: 0.9 * t[3], ..base.clone() },
            Material { diffuse_transmission: 0.9, ..base.clone() },
        ),
        (
            "diffuse transmission colour",
            Material {
                diffuse_transmission: 0.9,
                diffuse_transmission_color: [0.9, 0.8, 0.7],
                diffuse_transmission_color_texture: slot(),
                ..base.clone()
            },
            Material {
                diffuse_transmission: 0.9,
                diffuse_transmission_color: [0.9 * t[0], 0.8 * t[1], 0.7 * t[2]],
                ..base.clone()
            },
            Material {
                diffuse_transmission: 0.9,
                diffuse_transmission_color: [0.9, 0.8, 0.7],
                ..base.clone()
            },
        ),
    ];
    // Every case and mode is checked before the test fails, naming each that does.
    let mut failures = Vec::new();
    for (name, textured, folded, factor) in cases {
        let [a, b, f] = [(textured, true), (folded, false), (factor, false)].map(|(m, tex)| {
            renders(&gpu, &quad_scene(m, tex.then(|| common::row_texture("layer", &[texel])), 2.0), 0.5)
        });
        for (mode, ((a, b), f)) in MODES.iter().zip(a.iter().zip(&b).zip(&f)) {
            let centre = b[(SIZE.1 / 2 * SIZE.0 + SIZE.0 / 2) as usize];
            assert!(centre[0] > 0.01, "{name}, {mode}: the quad is lit ({centre:?})");
            if let Some((i, (p, q))) = a.iter().zip(b).enumerate().find(|(_, (p, q))| !same(p, q)) {
                failures.push(format!("{name}, {mode}: pixel {i}: textured {p:?} vs factor × texel {q:?}"));
            }
            let differ = b.iter().zip(f).filter(|(p, q)| !same(p, q)).count();
            if differ <= a.len() / 2 {
                failures.push(format!("{name}, {mode}: the texel changes only {differ} pixels"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A texture that is not constant is read where the UVs say: `specularTexture` of A = 0 over the
/// left half of the UV square and A = 1 over the right, on a black dielectric under a constant
/// sky (the sun off). Where A = 0 the surface reflects nothing (F0 = F90 = 0, no diffuse): black;
/// where A = 1 it equals the untextured material. The R, G, B channels hold the opposite (a
/// channel mix-up swaps the halves). The same through `TEXCOORD_1` (mirrored in u: the halves
/// swap) and through a `KHR_texture_transform` that mirrors u (swapped too).
#[test]
fn a_half_specular_texture_darkens_its_half() {
    let gpu = Gpu::new();
    let black = Material {
        base_color_factor: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        roughness: 0.3,
        double_sided: true,
        ..Default::default()
    };
    let texture = || Some(common::row_texture("layer", &[[255, 255, 255, 0], [0, 0, 0, 255]]));
    let plain = renders(&gpu, &quad_scene(black.clone(), None, 0.0), 1.0);
    let mirror = [[-1.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
    let cases = [
        ("TEXCOORD_0", 0, IDENTITY_TRANSFORM, false),
        ("TEXCOORD_1", 1, IDENTITY_TRANSFORM, true),
        ("a mirroring transform", 0, mirror, true),
    ];
    let (w, h) = SIZE;
    for (name, tex_coord, transform, swapped) in cases {
        let specular_texture = Some(TextureRef { texture: 0, tex_coord, transform, scale: 1.0 });
        let material = Material { specular_texture, ..black.clone() };
        let images = renders(&gpu, &quad_scene(material, texture(), 0.0), 1.0);
        for (mode, (image, plain)) in MODES.iter().zip(images.iter().zip(&plain)) {
            // Two columns clear of the seam (a path traced pixel's jitter crosses it).
            for y in 0..h {
                for x in (0..w).filter(|x| x + 2 < w / 2 || *x >= w / 2 + 2) {
                    let i = (y * w + x) as usize;
                    let dark = (x < w / 2) != swapped;
                    let (p, q) = (image[i], plain[i]);
                    assert!(q[0] > 0.01, "{mode}: pixel ({x}, {y}) reflects the sky without the texture");
                    if dark {
                        assert!(
                            p[..3].iter().all(|&c| c == 0.0),
                            "{name}, {mode}: ({x}, {y}) is {p:?}, not black"
                        );
                    } else {
                        assert!(same(&p, &q), "{name}, {mode}: ({x}, {y}) is {p:?}, untextured {q:?}");
                    }
                }
            }
        }
    }
}

/// A tangent-space normal map of one texel tilting the normal by 45° towards the tangent (+x).
fn tilt_map() -> Texture {
    // (sin 45°, 0, cos 45°) encoded as (n + 1) / 2: 218 = round(255 × 0.8536).
    common::row_texture("layer", &[[218, 128, 218, 255]])
}

/// KHR_materials_clearcoat's normal: the coat lies on the unmapped (interpolated) normal, and
/// only its own `clearcoatNormalTexture` tilts it. A black dielectric with no specular of its own
/// (`specularFactor` 0: the base reflects nothing) under a smooth coat, lit by a sun from the
/// camera's side: the image is the coat's highlight alone. A strong base normal map (45°) must
/// leave it as it is without the map (within 1e-3 per pixel, both modes); the same map as the
/// coat's normal must move it (the image's sum changes by more than half).
#[test]
fn the_coat_keeps_the_unmapped_normal() {
    let gpu = Gpu::new();
    let coated = Material {
        base_color_factor: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        specular_factor: 0.0,
        clearcoat: 1.0,
        clearcoat_roughness: 0.3,
        double_sided: true,
        ..Default::default()
    };
    let tangents = |mut s: Scene| {
        s.tangents = vec![[1.0, 0.0, 0.0, 1.0]; s.positions.len()];
        s
    };
    let render = |m: Material, map: bool| {
        let mut s = tangents(quad_scene(m, map.then(tilt_map), 0.0));
        s.lights = vec![common::light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 3.0)];
        renders(&gpu, &s, 0.0)
    };
    let plain = render(coated.clone(), false);
    let base_mapped = render(Material { normal_texture: slot(), ..coated.clone() }, true);
    let coat_mapped = render(Material { clearcoat_normal_texture: slot(), ..coated.clone() }, true);
    for (mode, ((plain, base), coat)) in MODES.iter().zip(plain.iter().zip(&base_mapped).zip(&coat_mapped)) {
        let sum = |image: &[[f32; 4]]| image.iter().map(|p| p[0] as f64).sum::<f64>();
        assert!(sum(plain) > 1.0, "{mode}: the coat's highlight is seen ({})", sum(plain));
        for (i, (p, q)) in base.iter().zip(plain).enumerate() {
            assert!(
                (0..3).all(|c| (p[c] - q[c]).abs() <= 1e-3 * q[c].abs().max(1e-2)),
                "{mode}: pixel {i}: with the base's normal map {p:?}, without {q:?}"
            );
        }
        let (moved, kept) = (sum(coat), sum(plain));
        eprintln!("{mode}: coat highlight {kept:.3}, with the coat's own normal map {moved:.3}");
        assert!((moved - kept).abs() > 0.5 * kept, "{mode}: the coat's normal map moves its highlight");
    }
}

/// KHR_materials_sheen's two textures reach the lobe: a quad whose `sheenColorTexture` and
/// `sheenRoughnessTexture` are one texture of two texels (the left and right halves of the UV
/// square), lit by a grazing sun (75.5° from the normal, where the Charlie sheen is strongest)
/// and a dim sky, renders on each half as the untextured material whose factors are × that half's
/// texel (RGB for the colour, A for the roughness), pixel by pixel in both modes (the hybrid
/// carries them in the G-buffer's `layers2`). The texels' channels all differ, so a slot that read
/// another channel, or a half that read the other texel, would not match; each half must also
/// differ from the factors alone.
#[test]
fn the_sheen_textures_reach_the_lobe() {
    let gpu = Gpu::new();
    let texels = [[200u8, 120, 40, 60], [60, 160, 230, 240]];
    let t = texels.map(|texel| texel.map(|c| c as f32 / 255.0));
    let base = Material {
        base_color_factor: [0.2, 0.2, 0.2, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        sheen_color: [1.0, 0.9, 0.8],
        sheen_roughness: 0.9,
        double_sided: true,
        ..Default::default()
    };
    let render = |m: Material, textured: bool| {
        let mut s = quad_scene(m, textured.then(|| common::row_texture("sheen", &texels)), 0.0);
        let grazing = Vec3::new(-0.968, 0.0, -0.25);
        s.lights = vec![common::light(LightKind::Directional, Vec3::ZERO, grazing, 4.0)];
        renders(&gpu, &s, 0.05)
    };
    let folded = |t: [f32; 4]| Material {
        sheen_color: [0, 1, 2].map(|c| base.sheen_color[c] * t[c]),
        sheen_roughness: base.sheen_roughness * t[3],
        ..base.clone()
    };
    let textured = render(
        Material { sheen_color_texture: slot(), sheen_roughness_texture: slot(), ..base.clone() },
        true,
    );
    let halves = [render(folded(t[0]), false), render(folded(t[1]), false)];
    let factor = render(base.clone(), false);
    let (w, h) = SIZE;
    let mut failures = Vec::new();
    for (m, mode) in MODES.iter().enumerate() {
        for (half, reference) in halves.iter().enumerate() {
            // Two columns clear of the seam (a path traced pixel's jitter crosses it).
            let columns: Vec<u32> =
                if half == 0 { (0..w / 2 - 2).collect() } else { (w / 2 + 2..w).collect() };
            let (mut differ, mut count) = (0, 0);
            for y in 0..h {
                for &x in &columns {
                    let i = (y * w + x) as usize;
                    let (p, q) = (textured[m][i], reference[m][i]);
                    assert!(q[0] > 0.01, "{mode}: pixel ({x}, {y}) is lit ({q:?})");
                    if !same(&p, &q) {
                        failures
                            .push(format!("{mode}, half {half}: ({x}, {y}) textured {p:?} vs folded {q:?}"));
                    }
                    differ += usize::from(!same(&q, &factor[m][i]));
                    count += 1;
                }
            }
            if differ <= count / 2 {
                failures
                    .push(format!("{mode}, half {half}: the texel changes only {differ} of {count} pixels"));
            }
        }
    }
    failures.truncate(8);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// KHR_materials_volume's attenuation in the hybrid: Beer–Lambert over the material's thickness
/// (`thicknessFactor` × `thicknessTexture` G), as the Sample Viewer approximates it, against the
/// path tracer on a slab of that thickness. A glass slab 0.5 deep (ior 1: nothing bends or
/// reflects, `specularFactor` 0: no Fresnel) filling the view under a sky of 1: the path tracer
/// sees the sky through the slab attenuated by exp(−σ d / cos θ), the hybrid by exp(−σ t). At
/// the image's centre (θ below 1.2°) both equal the closed form exp(−σ · 0.5) within 1e-3 per
/// channel (σ = −ln(colour) / distance: colour (0.5, 0.25, 0.8) at distance 1). A thickness
/// texture of G = 128 (R and B 255, A 0: another channel would read 1 or 0) gives the hybrid
/// exp(−σ · 0.5 · 128/255) in every pixel, and leaves the path tracer, which traces the slab, as
/// it was.
#[test]
fn the_hybrid_attenuates_by_the_thickness() {
    use umbra::gpu::scene::GpuScene;
    use umbra::passes::deferred::LightingSettings;
    use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
    let gpu = Gpu::new();
    let slab = Material {
        base_color_factor: [1.0; 4],
        metallic: 0.0,
        roughness: 0.0,
        specular_factor: 0.0,
        ior: 1.0,
        transmission_factor: 1.0,
        volume: true,
        thickness: 0.5,
        attenuation_color: [0.5, 0.25, 0.8],
        attenuation_distance: 1.0,
        ..Default::default()
    };
    let sigma = slab.attenuation();
    let render = |m: Material, texture: Option<Texture>| {
        let camera = common::camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
        let soup = common::cuboid(Vec3::new(-4.0, -4.0, -0.5), Vec3::new(4.0, 4.0, 0.0));
        let mut scene = common::build_with("thickness", &[(soup, m)], vec![], camera);
        scene.uv0 = vec![[0.5, 0.5]; scene.positions.len()];
        scene.textures.extend(texture);
        let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
        let camera = scene.camera(None).unwrap();
        let path = PathSettings { size: SIZE, spp: 4, max_bounces: 4, env: [1.0; 3], ..Default::default() };
        let traced = path_trace(&gpu, &gpu_scene, &camera, &path, |_, _| {}).unwrap();
        let settings = HybridSettings {
            size: SIZE,
            lighting: LightingSettings { env: [1.0; 3], ..Default::default() },
            ao: None,
            ..Default::default()
        };
        let lit = hybrid(&gpu, &gpu_scene, &camera, &settings).unwrap();
        [traced.mean, lit.color]
    };
    let centre = (SIZE.1 / 2 * SIZE.0 + SIZE.0 / 2) as usize;
    let plain = render(slab.clone(), None);
    let expected = sigma.map(|s| (-s * 0.5).exp());
    for (mode, image) in MODES.iter().zip(&plain) {
        let p = image[centre];
        for c in 0..3 {
            assert!(
                (p[c] - expected[c]).abs() <= 1e-3,
                "{mode}: centre channel {c}: {} vs exp(−σ d) {}",
                p[c],
                expected[c]
            );
        }
    }
    let half = common::row_texture("thickness", &[[255, 128, 255, 0]]);
    let textured = render(Material { thickness_texture: slot(), ..slab.clone() }, Some(half));
    let expected = sigma.map(|s| (-s * 0.5 * 128.0 / 255.0).exp());
    for (i, p) in textured[1].iter().enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - expected[c]).abs() <= 1e-3,
                "hybrid: pixel {i} channel {c}: {} vs {}",
                p[c],
                expected[c]
            );
        }
    }
    let q = textured[0][centre];
    let p = plain[0][centre];
    assert!(same(&q, &p), "path tracer: the thickness texture changed the traced slab: {q:?} vs {p:?}");
}
