//! The material extensions the loader reads: each one's factors and textures reach the material,
//! and out-of-range values are refused naming them.

use crate::{read_glb, scenes_dir, to_glb};
use serde_json::{json, Value};
use umbra::scene::Scene;

/// KHR_materials_clearcoat's factors and three textures reach the material (0 and none without
/// the extension; the normal texture with its scale, UV set and transform), with no warning; a
/// factor outside [0, 1] or a texture index beyond the file's textures is refused naming it.
#[test]
fn clearcoat_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |coat: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_clearcoat": coat });
        Scene::from_glb_bytes("coat.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].clearcoat, plain.materials[0].clearcoat_roughness), (0.0, 0.0));
    let scene = load(json!({"clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.25})).unwrap();
    assert_eq!((scene.materials[0].clearcoat, scene.materials[0].clearcoat_roughness), (0.75, 0.25));
    assert!(scene.warnings.iter().all(|w| !w.contains("clearcoat")), "{:?}", scene.warnings);
    assert!(plain.materials[0].clearcoat_normal_texture.is_none());
    let scene = load(json!({
        "clearcoatFactor": 1.0,
        "clearcoatTexture": {"index": 0},
        "clearcoatRoughnessTexture": {"index": 0, "texCoord": 1},
        "clearcoatNormalTexture": {
            "index": 0,
            "scale": 0.5,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0]}}
        }
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.clearcoat, 1.0);
    assert!(scene.warnings.iter().all(|w| !w.contains("clearcoat")), "{:?}", scene.warnings);
    let (coat, rough, normal) = (
        m.clearcoat_texture.expect("clearcoatTexture"),
        m.clearcoat_roughness_texture.expect("clearcoatRoughnessTexture"),
        m.clearcoat_normal_texture.expect("clearcoatNormalTexture"),
    );
    assert_eq!((coat.tex_coord, rough.tex_coord, normal.tex_coord), (0, 1, 0));
    assert_eq!((coat.scale, normal.scale), (1.0, 0.5));
    assert_eq!(normal.transform[0][2], 0.25, "the normal texture's KHR_texture_transform");
    assert!(!scene.textures[coat.texture as usize].srgb, "the coat's textures are linear");
    let error = load(json!({"clearcoatRoughnessFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("coat.glb") && error.contains("clearcoatRoughnessFactor is 1.5"), "{error}");
    let error =
        load(json!({"clearcoatFactor": 1.0, "clearcoatTexture": {"index": 7}})).unwrap_err().to_string();
    assert!(
        error.contains("coat.glb") && error.contains("KHR_materials_clearcoat.clearcoatTexture.index is 7"),
        "{error}"
    );
}

/// KHR_materials_sheen's factors and two textures reach the material (0 and none without the
/// extension), the colour texture decoded as sRGB and the roughness texture as linear, with no
/// warning; a factor outside [0, 1] or a texture index beyond the file's textures is refused
/// naming it.
#[test]
fn sheen_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |sheen: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_sheen": sheen });
        Scene::from_glb_bytes("sheen.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].sheen_color, plain.materials[0].sheen_roughness), ([0.0; 3], 0.0));
    let scene = load(json!({"sheenColorFactor": [0.75, 0.5, 0.25], "sheenRoughnessFactor": 0.125})).unwrap();
    assert_eq!(
        (scene.materials[0].sheen_color, scene.materials[0].sheen_roughness),
        ([0.75, 0.5, 0.25], 0.125)
    );
    assert!(scene.warnings.iter().all(|w| !w.contains("sheen")), "{:?}", scene.warnings);
    let scene = load(json!({
        "sheenColorFactor": [1.0, 1.0, 1.0],
        "sheenColorTexture": {"index": 0},
        "sheenRoughnessTexture": {"index": 0}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(m.sheen_color, [1.0; 3]);
    let (color, roughness) =
        (m.sheen_color_texture.as_ref().unwrap(), m.sheen_roughness_texture.as_ref().unwrap());
    assert!(scene.textures[color.texture as usize].srgb, "the colour texture is sRGB");
    assert!(!scene.textures[roughness.texture as usize].srgb, "the roughness texture is linear");
    assert!(scene.warnings.iter().all(|w| !w.contains("sheen")), "{:?}", scene.warnings);
    assert!(
        plain.materials[0].sheen_color_texture.is_none()
            && plain.materials[0].sheen_roughness_texture.is_none()
    );
    let error = load(json!({"sheenColorFactor": [1.0, 1.0, 1.0], "sheenRoughnessTexture": {"index": 7}}))
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("sheen.glb") && error.contains("KHR_materials_sheen.sheenRoughnessTexture.index is 7"),
        "{error}"
    );
    let error = load(json!({"sheenRoughnessFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("sheen.glb") && error.contains("sheenRoughnessFactor is 1.5"), "{error}");
    let error = load(json!({"sheenColorFactor": [0.5, -0.25, 0.5]})).unwrap_err().to_string();
    assert!(error.contains("sheen.glb") && error.contains("sheenColorFactor[1] is -0.25"), "{error}");
}

/// KHR_materials_volume's `thicknessFactor` and `thicknessTexture` reach the material (0 and none
/// without the extension; the texture linear, its UV set kept), with no warning.
#[test]
fn volume_thickness_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!((plain.materials[0].thickness, plain.materials[0].thickness_texture), (0.0, None));
    let mut json = base.clone();
    json["extensionsUsed"] = json!(["KHR_materials_volume"]);
    json["materials"][0]["extensions"] = json!({ "KHR_materials_volume": {
        "thicknessFactor": 0.25,
        "thicknessTexture": {"index": 0, "texCoord": 1}
    }});
    let scene = Scene::from_glb_bytes("volume.glb", &to_glb(&json, &bin)).unwrap();
    let m = &scene.materials[0];
    assert!(m.volume);
    assert_eq!(m.thickness, 0.25);
    let texture = m.thickness_texture.expect("thicknessTexture");
    assert_eq!(texture.tex_coord, 1);
    assert!(!scene.textures[texture.texture as usize].srgb, "the thickness texture is linear");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

/// KHR_materials_diffuse_transmission's factor, colour and two textures reach the material (0,
/// white and none without the extension), the colour texture decoded as sRGB and the factor's as
/// linear, with no warning and no longer among the ignored extensions; a factor or colour outside
/// [0, 1] or a texture index beyond the file's textures is refused naming it.
#[test]
fn diffuse_transmission_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |through: Value| {
        let mut json = base.clone();
        json["extensionsUsed"] = json!(["KHR_materials_diffuse_transmission"]);
        json["materials"][0]["extensions"] = json!({ "KHR_materials_diffuse_transmission": through });
        Scene::from_glb_bytes("through.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    let m = &plain.materials[0];
    assert_eq!((m.diffuse_transmission, m.diffuse_transmission_color), (0.0, [1.0; 3]));
    assert!(m.diffuse_transmission_texture.is_none() && m.diffuse_transmission_color_texture.is_none());
    let scene = load(json!({
        "diffuseTransmissionFactor": 0.75,
        "diffuseTransmissionColorFactor": [0.5, 0.25, 0.125],
        "diffuseTransmissionTexture": {"index": 0},
        "diffuseTransmissionColorTexture": {"index": 0, "texCoord": 1}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.diffuse_transmission, m.diffuse_transmission_color), (0.75, [0.5, 0.25, 0.125]));
    let (factor, colour) =
        (m.diffuse_transmission_texture.unwrap(), m.diffuse_transmission_color_texture.unwrap());
    assert_eq!(colour.tex_coord, 1);
    assert!(!scene.textures[factor.texture as usize].srgb, "the factor's texture is linear");
    assert!(scene.textures[colour.texture as usize].srgb, "the colour texture is sRGB");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let error = load(json!({"diffuseTransmissionFactor": 1.5})).unwrap_err().to_string();
    assert!(error.contains("through.glb") && error.contains("diffuseTransmissionFactor is 1.5"), "{error}");
    let error = load(json!({"diffuseTransmissionColorFactor": [0.5, 2.0, 0.5]})).unwrap_err().to_string();
    assert!(
        error.contains("through.glb") && error.contains("diffuseTransmissionColorFactor[1] is 2"),
        "{error}"
    );
    let error =
        load(json!({"diffuseTransmissionFactor": 1.0, "diffuseTransmissionColorTexture": {"index": 7}}))
            .unwrap_err()
            .to_string();
    assert!(
        error.contains("through.glb")
            && error
                .contains("KHR_materials_diffuse_transmission.diffuseTransmissionColorTexture.index is 7"),
        "{error}"
    );
}

/// KHR_materials_iridescence's factor, ior, thickness range and two textures reach the material
/// (factor 0, ior 1.3, thickness 100–400 nm and no textures without the extension; the defaults
/// for the values the extension leaves out), with no warning; a value outside its range or a
/// texture index beyond the file's textures is refused naming it.
#[test]
fn iridescence_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |film: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({ "KHR_materials_iridescence": film });
        Scene::from_glb_bytes("film.glb", &to_glb(&json, &bin))
    };
    let film = |m: &umbra::scene::Material| (m.iridescence, m.iridescence_ior, m.iridescence_thickness);
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!(film(&plain.materials[0]), (0.0, 1.3, [100.0, 400.0]));
    assert!(plain.materials[0].iridescence_texture.is_none());
    let scene = load(json!({"iridescenceFactor": 0.75})).unwrap();
    assert_eq!(film(&scene.materials[0]), (0.75, 1.3, [100.0, 400.0]), "the defaults");
    let scene = load(json!({
        "iridescenceFactor": 0.5,
        "iridescenceIor": 1.8,
        "iridescenceThicknessMinimum": 250.0,
        "iridescenceThicknessMaximum": 125.0,
        "iridescenceTexture": {"index": 0},
        "iridescenceThicknessTexture": {"index": 0, "texCoord": 1,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0]}}}
    }))
    .unwrap();
    let m = &scene.materials[0];
    assert_eq!(film(m), (0.5, 1.8, [250.0, 125.0]), "the minimum may exceed the maximum");
    assert!(scene.warnings.iter().all(|w| !w.contains("iridescence")), "{:?}", scene.warnings);
    let (weight, thickness) = (
        m.iridescence_texture.expect("iridescenceTexture"),
        m.iridescence_thickness_texture.expect("thickness"),
    );
    assert_eq!((weight.tex_coord, thickness.tex_coord), (0, 1));
    assert_eq!(thickness.transform[0][2], 0.25, "the thickness texture's KHR_texture_transform");
    assert!(!scene.textures[weight.texture as usize].srgb, "the film's textures are linear");
    for (bad, named) in [
        (json!({"iridescenceFactor": 1.5}), "iridescenceFactor is 1.5"),
        (json!({"iridescenceIor": 0.5}), "iridescenceIor is 0.5"),
        (json!({"iridescenceThicknessMinimum": -1.0}), "iridescenceThicknessMinimum is -1"),
        (json!({"iridescenceThicknessMaximum": -2.0}), "iridescenceThicknessMaximum is -2"),
        (
            json!({"iridescenceFactor": 1.0, "iridescenceTexture": {"index": 7}}),
            "iridescenceTexture.index is 7",
        ),
    ] {
        let error = load(bad).unwrap_err().to_string();
        assert!(error.contains("film.glb") && error.contains(named), "{named}: {error}");
    }
}

/// KHR_materials_anisotropy's factors and texture reach the material (0 and none without the
/// extension), with no warning and no longer among the ignored extensions; a strength outside
/// [0, 1] or a texture index beyond the file's is refused naming it. A primitive of an
/// anisotropic material needs a tangent frame: from TANGENT, else generated from its UVs (w ±1);
/// with neither, its tangents' w is 0 (the kernels then shade it isotropic) and one warning names
/// the primitive.
#[test]
fn anisotropy_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let with = |json: &mut Value, anisotropy: Value| {
        json["extensionsUsed"] = json!(["KHR_materials_anisotropy"]);
        json["materials"][0]["extensions"] = json!({ "KHR_materials_anisotropy": anisotropy });
    };
    let load = |anisotropy: Value| {
        let mut json = base.clone();
        with(&mut json, anisotropy);
        Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    let m = &plain.materials[0];
    assert_eq!((m.anisotropy_strength, m.anisotropy_rotation, m.anisotropy_texture), (0.0, 0.0, None));
    let scene = load(json!({"anisotropyStrength": 0.75, "anisotropyRotation": -1.25})).unwrap();
    let m = &scene.materials[0];
    assert_eq!((m.anisotropy_strength, m.anisotropy_rotation), (0.75, -1.25));
    assert!(scene.warnings.iter().all(|w| !w.contains("anisotropy")), "{:?}", scene.warnings);
    let scene =
        load(json!({"anisotropyStrength": 1.0, "anisotropyTexture": {"index": 0, "texCoord": 1}})).unwrap();
    let texture = scene.materials[0].anisotropy_texture.expect("anisotropyTexture");
    assert_eq!(texture.tex_coord, 1);
    assert!(!scene.textures[texture.texture as usize].srgb, "the anisotropy texture is linear");
    let error = load(json!({"anisotropyStrength": 1.5})).unwrap_err().to_string();
    assert!(error.contains("aniso.glb") && error.contains("anisotropyStrength is 1.5"), "{error}");
    let error =
        load(json!({"anisotropyStrength": 1.0, "anisotropyTexture": {"index": 9}})).unwrap_err().to_string();
    assert!(
        error.contains("aniso.glb")
            && error.contains("KHR_materials_anisotropy.anisotropyTexture.index is 9"),
        "{error}"
    );
    // The floor (material 0, mesh 0) has TANGENT: no warning, every w ±1.
    let scene = load(json!({"anisotropyStrength": 0.5})).unwrap();
    assert!(!scene.tangents.is_empty() && scene.tangents.iter().all(|t| t[3].abs() == 1.0));
    // Without TANGENT, the tangents come from the UVs.
    let mut json = base.clone();
    with(&mut json, json!({"anisotropyStrength": 0.5}));
    json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("TANGENT");
    let scene = Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin)).unwrap();
    assert!(scene.tangents.iter().all(|t| t[3].abs() == 1.0), "tangents from the UVs");
    assert!(scene.warnings.iter().all(|w| !w.contains("tangent frame")), "{:?}", scene.warnings);
    // Without TANGENT and UVs: w 0 on that primitive's vertices, and the warning.
    let attributes = json["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap();
    attributes.remove("TEXCOORD_0");
    let scene = Scene::from_glb_bytes("aniso.glb", &to_glb(&json, &bin)).unwrap();
    let floor: Vec<usize> = (0..scene.triangles.len())
        .filter(|&t| scene.triangle_material[t] == 0)
        .flat_map(|t| scene.triangles[t].map(|v| v as usize))
        .collect();
    assert!(!floor.is_empty() && floor.iter().all(|&v| scene.tangents[v][3] == 0.0), "{:?}", scene.tangents);
    let warned: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("tangent frame")).collect();
    assert_eq!(warned.len(), 1, "{:?}", scene.warnings);
    assert!(
        warned[0].contains("aniso.glb")
            && warned[0].contains("mesh 0 ('plane') primitive 0")
            && warned[0].contains("isotropic"),
        "{}",
        warned[0]
    );
}

/// KHR_materials_volume's attenuation reaches the material: colour and distance as written, the
/// coefficient −ln(colour)/distance, and none without a thickness (thin-walled) or a distance.
#[test]
fn volume_attenuation_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |volume: Value| {
        let mut json = base.clone();
        json["materials"][0]["extensions"] = json!({
            "KHR_materials_transmission": {"transmissionFactor": 1.0},
            "KHR_materials_volume": volume,
        });
        Scene::from_glb_bytes("volume.glb", &to_glb(&json, &bin)).unwrap().materials[0].clone()
    };
    let m = load(
        json!({"thicknessFactor": 1.0, "attenuationColor": [0.5, 0.25, 1.0], "attenuationDistance": 2.0}),
    );
    assert!(m.volume);
    assert_eq!((m.attenuation_color, m.attenuation_distance), ([0.5, 0.25, 1.0], 2.0));
    let sigma = m.attenuation();
    for (got, expected) in sigma.iter().zip([0.5f32.ln() / -2.0, 0.25f32.ln() / -2.0, 0.0]) {
        assert!((got - expected).abs() < 1e-6, "{sigma:?}");
    }
    let thin = load(json!({"attenuationColor": [0.5, 0.25, 1.0], "attenuationDistance": 2.0}));
    assert!(!thin.volume && thin.attenuation() == [0.0; 3], "no thickness: thin-walled, no attenuation");
    let clear = load(json!({"thicknessFactor": 1.0, "attenuationColor": [0.5, 0.25, 1.0]}));
    assert!(clear.attenuation_distance.is_infinite() && clear.attenuation() == [0.0; 3]);
}

/// KHR_materials_dispersion's `dispersion` reaches the material (0 without the extension), with
/// no warning and no longer among the ignored extensions; a negative one is refused naming it.
#[test]
fn dispersion_is_read() {
    let (base, bin) = read_glb(&scenes_dir().join("textured.glb"));
    let load = |dispersion: Value| {
        let mut json = base.clone();
        json["extensionsUsed"] = json!(["KHR_materials_dispersion", "KHR_materials_volume"]);
        json["materials"][0]["extensions"] = json!({
            "KHR_materials_dispersion": dispersion,
            "KHR_materials_volume": {"thicknessFactor": 0.5},
        });
        Scene::from_glb_bytes("prism.glb", &to_glb(&json, &bin))
    };
    let plain = Scene::from_glb_bytes("plain.glb", &to_glb(&base, &bin)).unwrap();
    assert_eq!(plain.materials[0].dispersion, 0.0);
    let scene = load(json!({"dispersion": 0.33})).unwrap();
    assert_eq!(scene.materials[0].dispersion, 0.33);
    assert!(scene.materials[0].volume);
    assert!(scene.warnings.iter().all(|w| !w.contains("dispersion")), "{:?}", scene.warnings);
    let error = load(json!({"dispersion": -0.5})).unwrap_err().to_string();
    assert!(error.contains("prism.glb") && error.contains("dispersion is -0.5"), "{error}");
}

/// KHR_materials_variants: the file's variant names are read, every primitive keeps its own
/// material until a variant is selected, then takes the one its mappings give that variant (its
/// own where none does); an unknown name is an error listing the variants, and a mapping to a
/// variant the file lacks is refused naming the primitive. No warning: the extension is read.
#[test]
fn variants_select_materials() {
    let (base, bin) = read_glb(&crate::khronos("Box"));
    let own = base["materials"].as_array().map_or(0, Vec::len);
    let load = |mappings: Value| {
        let mut json = base.clone();
        json["extensionsUsed"] = json!(["KHR_materials_variants"]);
        json["extensions"] = json!({"KHR_materials_variants": {"variants": [
            {"name": "red"}, {"name": "green"}, {"name": "plain"}
        ]}});
        let materials = json["materials"].as_array_mut().unwrap();
        materials.push(json!({"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}}));
        materials.push(json!({"name": "green", "pbrMetallicRoughness": {"baseColorFactor": [0, 1, 0, 1]}}));
        json["meshes"][0]["primitives"][0]["extensions"] =
            json!({"KHR_materials_variants": {"mappings": mappings}});
        Scene::from_glb_bytes("configurator.glb", &to_glb(&json, &bin))
    };
    let mappings = json!([{"material": own, "variants": [0]}, {"material": own + 1, "variants": [1]}]);
    let mut scene = load(mappings).unwrap();
    assert_eq!(scene.variants.names, ["red", "green", "plain"]);
    assert!(scene.warnings.iter().all(|w| !w.contains("variants")), "{:?}", scene.warnings);
    let plain = scene.triangle_material.clone();
    assert!(!plain.is_empty() && plain.iter().all(|&m| (m as usize) < own), "{plain:?}");
    for (name, material) in [("red", Some(own)), ("green", Some(own + 1)), ("plain", None)] {
        let index = scene.variant_index(name).unwrap();
        scene.select_variant(Some(index)).unwrap();
        match material {
            Some(m) => assert!(scene.triangle_material.iter().all(|&t| t as usize == m), "{name}"),
            None => assert_eq!(scene.triangle_material, plain, "{name}"),
        }
        assert_eq!(scene.variants.selected, Some(index));
    }
    scene.select_variant(None).unwrap();
    assert_eq!(scene.triangle_material, plain);
    let error = scene.variant_index("blue").unwrap_err().to_string();
    assert!(error.contains("configurator.glb") && error.contains("'red', 'green', 'plain'"), "{error}");
    assert!(scene.select_variant(Some(3)).is_err());
    let error = load(json!([{"material": own, "variants": [7]}])).unwrap_err().to_string();
    assert!(error.contains("mesh 0") && error.contains("variant 7"), "{error}");
}
