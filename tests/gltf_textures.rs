//! glTF textures as files ship them: `EXT_texture_webp` (a WebP image replacing the texture's
//! fallback source, decoded by `image`) and emissive textures with
//! `KHR_materials_emissive_strength`, in the hybrid and the path tracer. The scenes are generated
//! in memory (`tests/support/generate.rs`: `webp_square`, `emissive_square`), a square filling
//! the view of a camera 2 m away.

mod common;
#[path = "support/generate.rs"]
mod generate;

use common::Gpu;
use serde_json::json;
use umbra::color::srgb_decode;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::LightingSettings;
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::Scene;
use umbra::Error;

/// 2 × 2 RGB texels, rows from the top: four distinct colours.
const WEBP_TEXELS: [u8; 12] = [250, 10, 20, 30, 240, 40, 50, 60, 230, 200, 180, 70];
/// The fallback image: a different, uniform grey.
const PNG_TEXELS: [u8; 12] = [128; 12];

const SIZE: (u32, u32) = (16, 16);

/// The texel of the 2 × 2 texture a pixel of the square shows, or `None` within a pixel of the
/// seams (where the path tracer's jittered rays see two texels).
fn quadrant(i: usize) -> Option<usize> {
    let (x, y) = ((i as u32 % SIZE.0) as i32, (i as u32 / SIZE.0) as i32);
    let half = SIZE.0 as i32 / 2;
    if (x - half).abs() <= 1
        || (x - half + 1).abs() <= 1
        || (y - half).abs() <= 1
        || (y - half + 1).abs() <= 1
    {
        return None;
    }
    Some(usize::from(y >= half) * 2 + usize::from(x >= half))
}

/// The texture of an `EXT_texture_webp` texture is the WebP image (lossless: texel for texel),
/// not its PNG fallback, and reaches the G-buffer's base colour; a texture with no fallback
/// source (the extension required) loads the same; the extension is not reported as ignored.
/// Fails if the fallback is used, WebP cannot be decoded, or a texture without `source` is
/// refused.
#[test]
fn webp_textures_replace_their_fallback() {
    let rgba: Vec<u8> = WEBP_TEXELS.chunks(3).flat_map(|t| [t[0], t[1], t[2], 255]).collect();
    for (name, fallback) in [("webp+png.glb", Some(&PNG_TEXELS[..])), ("webp.glb", None)] {
        let scene = Scene::from_glb_bytes(name, &generate::webp_square(&WEBP_TEXELS, fallback))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.textures.len(), 1);
        assert_eq!((scene.textures[0].width, scene.textures[0].height), (2, 2));
        assert_eq!(scene.textures[0].rgba8, rgba, "{name}: the texels are the WebP image's");
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
    }
    let gpu = Gpu::new();
    let scene =
        Scene::from_glb_bytes("webp.glb", &generate::webp_square(&WEBP_TEXELS, Some(&PNG_TEXELS))).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let h = hybrid(
        &gpu,
        &gpu_scene,
        &scene.camera(None).unwrap(),
        &HybridSettings { size: SIZE, ..Default::default() },
    )
    .unwrap();
    let mut checked = 0;
    for (i, base) in h.gbuffer.base.iter().enumerate() {
        let Some(q) = quadrant(i) else { continue };
        for c in 0..3 {
            let expected = srgb_decode(f32::from(WEBP_TEXELS[3 * q + c]) / 255.0);
            assert!(
                (base[c] - expected).abs() < 2e-3,
                "pixel {i} channel {c}: base {}, expected {expected}",
                base[c]
            );
        }
        checked += 1;
    }
    assert!(checked > 50, "{checked} pixels checked");
}

/// An `EXT_texture_webp` source that names no image, and WebP bytes that are not an image, are
/// errors naming the file, the texture or image and the problem.
#[test]
fn bad_webp_sources_are_clear_errors() {
    let glb = generate::webp_square(&WEBP_TEXELS, Some(&PNG_TEXELS));
    let (json, mut bin) = generate::split_glb(&glb);
    let mut bad_index = json.clone();
    bad_index["textures"][0]["extensions"]["EXT_texture_webp"]["source"] = json!(7);
    let error =
        Scene::from_glb_bytes("bad.glb", &generate::glb(&serde_json::to_vec(&bad_index).unwrap(), &bin))
            .expect_err("an image index out of range");
    assert!(matches!(error, Error::Scene { .. }));
    assert_eq!(
        error.to_string().split_once(": ").map(|(_, m)| m.to_owned()),
        Some(
            "texture 0: the source of its EXT_texture_webp (7) is not an image index (the file has 2 images)"
                .into()
        ),
        "{error}"
    );
    // Corrupt the WebP image's bytes past its RIFF header.
    let webp = json["textures"][0]["extensions"]["EXT_texture_webp"]["source"].as_u64().unwrap() as usize;
    let view = &json["bufferViews"][json["images"][webp]["bufferView"].as_u64().unwrap() as usize];
    let (at, len) =
        (view["byteOffset"].as_u64().unwrap() as usize, view["byteLength"].as_u64().unwrap() as usize);
    bin[at + 16..at + len].fill(0xAB);
    let error =
        Scene::from_glb_bytes("corrupt.glb", &generate::glb(&serde_json::to_vec(&json).unwrap(), &bin))
            .expect_err("undecodable WebP");
    let text = error.to_string();
    assert!(
        text.contains("corrupt.glb") && text.contains("image 0 (embedded): cannot decode the image"),
        "{text}"
    );
}

/// An emissive texture (2 × 2, four colours) times the emissive factor times
/// `KHR_materials_emissive_strength` 4 on a black square seen by the camera, no light: every
/// pixel is its texel (decoded from sRGB) × factor × strength, in the hybrid (half-float
/// G-buffer) and the path tracer. Fails if the texture, the factor or the strength is left out,
/// the texture is read as linear, or the texels land in the wrong quadrant.
#[test]
fn emissive_textures_times_factor_and_strength() {
    let gpu = Gpu::new();
    let texels = [255u8, 128, 0, 0, 64, 255, 200, 200, 200, 10, 250, 90];
    let (factor, strength) = ([0.5f64, 1.0, 0.25], 4.0f64);
    let scene =
        Scene::from_glb_bytes("glow.glb", &generate::emissive_square(&texels, factor, strength)).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let camera = scene.camera(None).unwrap();
    let lighting = LightingSettings { env: [0.0; 3], ..Default::default() };
    let h = hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size: SIZE, lighting, ..Default::default() })
        .unwrap();
    let settings = PathSettings { size: SIZE, spp: 4, env: [0.0; 3], ..Default::default() };
    let p = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let (mut checked, mut worst_hybrid, mut worst_path) = (0, 0.0f32, 0.0f32);
    for i in 0..h.color.len() {
        let Some(q) = quadrant(i) else { continue };
        for c in 0..3 {
            let expected = srgb_decode(f32::from(texels[3 * q + c]) / 255.0) * (factor[c] * strength) as f32;
            let off = |x: f32| (x - expected).abs() / expected.max(0.05);
            worst_hybrid = worst_hybrid.max(off(h.color[i][c]));
            worst_path = worst_path.max(off(p.mean[i][c]));
        }
        checked += 1;
    }
    eprintln!(
        "{checked} pixels: hybrid within {worst_hybrid:.2e}, path traced within {worst_path:.2e} (relative)"
    );
    assert!(checked > 50);
    assert!(worst_hybrid < 2e-3, "hybrid off by {worst_hybrid}");
    assert!(worst_path < 1e-4, "path tracer off by {worst_path}");
}
