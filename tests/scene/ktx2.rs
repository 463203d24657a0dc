//! `KHR_texture_basisu` against Binomial's own encoder and transcoder: the KTX2 files in
//! `tests/scene/ktx2/` were encoded by basisu (ETC1S with its BasisLZ codebooks, UASTC with and
//! without Zstandard, with and without mip levels, with alpha, at a size no multiple of the 4×4
//! blocks), and each file's `.reference.png` is its level 0 as Binomial's C++ transcoder gives it
//! (both through ktx2-encoder's WebAssembly build; `make.mjs`, `prepare.py`). umbra's texels must
//! equal those exactly.

use crate::{assert_scene_error, read_glb, scenes_dir, to_glb};
use serde_json::{json, Value};
use umbra::scene::{Scene, Texture};

fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scene/ktx2").join(name)
}

fn reference(name: &str) -> image::RgbaImage {
    image::open(fixture(&format!("{name}.reference.png"))).unwrap().to_rgba8()
}

/// `scenes/textured.glb` with image `i` of each `(i, name)` replaced by KTX2 file `name` through
/// `KHR_texture_basisu`: required (the textures lose their PNG `source`) or, with `fallback`,
/// optional (the PNG stays as the textures' `source`).
fn textured_with(replaced: &[(usize, &str)], fallback: bool) -> Vec<u8> {
    let (mut root, mut bin) = read_glb(&scenes_dir().join("textured.glb"));
    for &(image, name) in replaced {
        let bytes = std::fs::read(fixture(&format!("{name}.ktx2"))).unwrap();
        bin.resize(bin.len().next_multiple_of(4), 0);
        let views = root["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        let view = views.len() - 1;
        bin.extend_from_slice(&bytes);
        let images = root["images"].as_array_mut().unwrap();
        images.push(json!({"bufferView": view, "mimeType": "image/ktx2", "name": name}));
        let ktx2 = images.len() - 1;
        for texture in root["textures"].as_array_mut().unwrap() {
            if texture["source"] == json!(image) {
                texture["extensions"] = json!({"KHR_texture_basisu": {"source": ktx2}});
                if !fallback {
                    texture.as_object_mut().unwrap().remove("source");
                }
            }
        }
    }
    root["buffers"][0]["byteLength"] = json!(bin.len());
    root["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_texture_basisu"));
    if !fallback {
        root["extensionsRequired"] = json!(["KHR_texture_basisu"]);
    }
    to_glb(&root, &bin)
}

fn texture<'s>(scene: &'s Scene, name: &str) -> &'s Texture {
    scene.textures.iter().find(|t| t.name == name).unwrap_or_else(|| panic!("no texture '{name}'"))
}

/// Every fixture (ETC1S with mips, UASTC + Zstandard with mips, UASTC plain, both with alpha at
/// 37×23) transcodes to exactly Binomial's texels, and keeps the colour space its use gives it
/// (base colour sRGB, normal and metallic-roughness maps linear, as the PNGs they replace) and
/// the PNG's samplers.
#[test]
fn ktx2_textures_transcode_to_binomials_texels() {
    let plain = crate::load(&scenes_dir().join("textured.glb"));
    let cases: [&[(usize, &str)]; 2] = [
        &[(0, "checker-etc1s-srgb-mips"), (1, "bumps-uastc-zstd-mips"), (2, "metal-rough-uastc")],
        &[(0, "gradient-etc1s-alpha"), (1, "gradient-uastc-zstd-alpha")],
    ];
    for case in cases {
        let scene = Scene::from_glb_bytes("ktx2.glb", &textured_with(case, false)).unwrap();
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        assert_eq!(scene.textures.len(), plain.textures.len());
        for (a, b) in scene.textures.iter().zip(&plain.textures) {
            assert_eq!((a.srgb, &a.sampler), (b.srgb, &b.sampler), "{} against {}", a.name, b.name);
        }
        for &(_, name) in case {
            let t = texture(&scene, name);
            let r = reference(name);
            assert_eq!((t.width, t.height), r.dimensions(), "{name}");
            let differing = t.rgba8.iter().zip(r.as_raw()).filter(|(a, b)| a != b).count();
            assert_eq!(differing, 0, "{name}: {differing} bytes differ from Binomial's transcoder");
        }
    }
}

/// An optional `KHR_texture_basisu` with a PNG fallback: the KTX2 is used, with no warning.
#[test]
fn an_optional_ktx2_is_used_over_its_png_fallback() {
    let scene =
        Scene::from_glb_bytes("optional.glb", &textured_with(&[(0, "checker-etc1s-srgb-mips")], true))
            .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let t = texture(&scene, "checker-etc1s-srgb-mips");
    assert_eq!(t.rgba8, reference("checker-etc1s-srgb-mips").into_raw());
    assert!(scene.textures.iter().all(|t| t.name != "checker"), "the PNG fallback was decoded too");
}

/// A bad KTX2 is refused naming the image: not Basis texels at all, cut short, a source index
/// out of range; bytes flipped anywhere give an error or a (wrong) texture, never a panic.
#[test]
fn broken_ktx2_images_are_refused_naming_them() {
    let glb = textured_with(&[(2, "metal-rough-uastc")], false);
    let (root, bin) = crate::generate::split_glb(&glb);
    let image = root["images"].as_array().unwrap().len() - 1;
    let view = root["images"][image]["bufferView"].as_u64().unwrap() as usize;
    let start = root["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
    let length = root["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    let load = |edit: &dyn Fn(&mut Value, &mut Vec<u8>)| {
        let (mut j, mut b) = (root.clone(), bin.clone());
        edit(&mut j, &mut b);
        Scene::from_glb_bytes("broken.glb", &to_glb(&j, &b))
    };
    // Not a Basis payload: the KTX2 identifier followed by nothing it can read.
    assert_scene_error(
        load(&|_, b| b[start + 12..start + length].fill(0)),
        "broken.glb",
        &format!("image {image} (embedded): KTX2: not a Basis Universal KTX2 file"),
    );
    assert_scene_error(
        load(&|j, _| j["bufferViews"][view]["byteLength"] = json!(100)),
        "broken.glb",
        &format!("image {image} (embedded): KTX2"),
    );
    assert_scene_error(
        load(&|j, _| j["textures"][2]["extensions"]["KHR_texture_basisu"]["source"] = json!(40)),
        "broken.glb",
        "texture 2: the source of its KHR_texture_basisu (40) is not an image index",
    );
    crate::flip_bits(start, length, 0x9e37_79b9, 400, |at, bit| {
        let _ = load(&|_, b| b[at] ^= bit);
    });
}
