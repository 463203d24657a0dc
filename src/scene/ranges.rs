//! Every numeric field umbra reads from a glTF file, checked against the range its specification
//! gives (the Khronos glTF Validator's `VALUE_NOT_IN_RANGE` and friends are the model), on the JSON
//! as written, before anything is loaded: an out-of-range value is an error naming the file, the
//! element, its index and name, the field, the value and the range. Never a silent drop or clamp.
//! Every material, light, camera and texture transform is checked, used or not, as the validator
//! does.

use super::source::Origin;
use crate::error::Result;
use gltf::json::Value;

/// The brightest punctual light umbra shades: its radiance times a BSDF and over a squared
/// distance must stay a finite 32-bit float (about 3.4e38), with room for a few orders of
/// magnitude of geometry. The sun is about 1e5 lux.
pub const MAX_LIGHT_INTENSITY: f64 = 1e20;

/// Problems found so far, each a sentence naming the element and the field.
struct Checker {
    problems: Vec<String>,
}

/// The allowed values of a number.
#[derive(Clone, Copy)]
enum Range {
    /// lo ≤ x ≤ hi.
    Closed(f64, f64),
    /// x ≥ lo.
    AtLeast(f64),
    /// x > lo.
    Above(f64),
    /// Any finite 32-bit float.
    Finite,
}

impl Range {
    fn contains(self, x: f64) -> bool {
        x.is_finite()
            && x.abs() <= f64::from(f32::MAX)
            && match self {
                Range::Closed(lo, hi) => (lo..=hi).contains(&x),
                Range::AtLeast(lo) => x >= lo,
                Range::Above(lo) => x > lo,
                Range::Finite => true,
            }
    }

    fn describe(self) -> String {
        match self {
            Range::Closed(lo, hi) => format!("within [{lo}, {hi}]"),
            Range::AtLeast(lo) => format!("at least {lo}"),
            Range::Above(lo) => format!("greater than {lo}"),
            Range::Finite => "a finite 32-bit float".into(),
        }
    }
}

/// `kind index ('name')`, the way the loader names elements.
fn label(kind: &str, index: usize, element: &Value) -> String {
    match element.get("name").and_then(Value::as_str) {
        Some(name) if !name.is_empty() => format!("{kind} {index} ('{name}')"),
        _ => format!("{kind} {index}"),
    }
}

impl Checker {
    /// Checks `object[field]` (a number, or an array of numbers), if present.
    fn field(&mut self, element: &str, object: &Value, field: &str, range: Range) {
        let Some(value) = object.get(field) else { return };
        let values: Vec<&Value> = match value {
            Value::Array(items) => items.iter().collect(),
            other => vec![other],
        };
        for (i, v) in values.iter().enumerate() {
            let at = if value.is_array() { format!("{field}[{i}]") } else { field.to_string() };
            match v.as_f64() {
                Some(x) if range.contains(x) => {}
                Some(_) => {
                    self.problems.push(format!("{element}: {at} is {v}, must be {}", range.describe()))
                }
                None => self.problems.push(format!("{element}: {at} is {v}, not a number")),
            }
        }
    }

    /// The texture transform (`KHR_texture_transform`) of a texture reference, if any.
    fn texture_info(&mut self, element: &str, slot: &str, info: Option<&Value>) {
        let Some(info) = info else { return };
        let element = format!("{element} {slot}");
        if let Some(t) = info.pointer("/extensions/KHR_texture_transform") {
            let element = format!("{element} KHR_texture_transform");
            for field in ["offset", "rotation", "scale"] {
                self.field(&element, t, field, Range::Finite);
            }
        }
        if slot == "occlusionTexture" {
            self.field(&element, info, "strength", Range::Closed(0.0, 1.0));
        }
        if slot == "normalTexture" || slot == "clearcoatNormalTexture" {
            self.field(&element, info, "scale", Range::Finite);
        }
    }

    fn material(&mut self, index: usize, m: &Value) {
        let element = label("material", index, m);
        let unit = Range::Closed(0.0, 1.0);
        if let Some(pbr) = m.get("pbrMetallicRoughness") {
            self.field(&element, pbr, "baseColorFactor", unit);
            self.field(&element, pbr, "metallicFactor", unit);
            self.field(&element, pbr, "roughnessFactor", unit);
            self.texture_info(&element, "baseColorTexture", pbr.get("baseColorTexture"));
            self.texture_info(&element, "metallicRoughnessTexture", pbr.get("metallicRoughnessTexture"));
        }
        self.field(&element, m, "emissiveFactor", unit);
        self.field(&element, m, "alphaCutoff", Range::AtLeast(0.0));
        for slot in ["normalTexture", "occlusionTexture", "emissiveTexture"] {
            self.texture_info(&element, slot, m.get(slot));
        }
        let Some(extensions) = m.get("extensions") else { return };
        let mut extension = |name: &str, fields: &[(&str, Range)], textures: &[&str]| {
            let Some(e) = extensions.get(name) else { return };
            let element = format!("{element} {name}");
            for &(field, range) in fields {
                self.field(&element, e, field, range);
            }
            for &slot in textures {
                self.texture_info(&element, slot, e.get(slot));
            }
        };
        extension("KHR_materials_emissive_strength", &[("emissiveStrength", Range::AtLeast(0.0))], &[]);
        extension("KHR_materials_transmission", &[("transmissionFactor", unit)], &["transmissionTexture"]);
        extension(
            "KHR_materials_clearcoat",
            &[("clearcoatFactor", unit), ("clearcoatRoughnessFactor", unit)],
            &["clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"],
        );
        extension(
            "KHR_materials_sheen",
            &[("sheenColorFactor", unit), ("sheenRoughnessFactor", unit)],
            &["sheenColorTexture", "sheenRoughnessTexture"],
        );
        extension(
            "KHR_materials_diffuse_transmission",
            &[("diffuseTransmissionFactor", unit), ("diffuseTransmissionColorFactor", unit)],
            &["diffuseTransmissionTexture", "diffuseTransmissionColorTexture"],
        );
        extension(
            "KHR_materials_iridescence",
            &[
                ("iridescenceFactor", unit),
                ("iridescenceIor", Range::AtLeast(1.0)),
                ("iridescenceThicknessMinimum", Range::AtLeast(0.0)),
                ("iridescenceThicknessMaximum", Range::AtLeast(0.0)),
            ],
            &["iridescenceTexture", "iridescenceThicknessTexture"],
        );
        extension(
            "KHR_materials_anisotropy",
            &[("anisotropyStrength", unit), ("anisotropyRotation", Range::Finite)],
            &["anisotropyTexture"],
        );
        extension("KHR_materials_dispersion", &[("dispersion", Range::AtLeast(0.0))], &[]);
        extension(
            "KHR_materials_volume",
            &[
                ("thicknessFactor", Range::AtLeast(0.0)),
                ("attenuationDistance", Range::Above(0.0)),
                ("attenuationColor", unit),
            ],
            &["thicknessTexture"],
        );
        extension(
            "KHR_materials_specular",
            &[("specularFactor", unit), ("specularColorFactor", Range::AtLeast(0.0))],
            &["specularTexture", "specularColorTexture"],
        );
        // The index of refraction: at least 1, or exactly 0 (the spec's "no refraction").
        if let Some(ior) = extensions.pointer("/KHR_materials_ior/ior") {
            match ior.as_f64() {
                Some(x) if x == 0.0 || Range::AtLeast(1.0).contains(x) => {}
                _ => self
                    .problems
                    .push(format!("{element} KHR_materials_ior: ior is {ior}, must be at least 1 (or 0)")),
            }
        }
    }

    fn light(&mut self, index: usize, light: &Value) {
        let element = format!("KHR_lights_punctual {}", label("light", index, light));
        self.field(&element, light, "color", Range::Closed(0.0, 1.0));
        self.field(&element, light, "intensity", Range::Closed(0.0, MAX_LIGHT_INTENSITY));
        self.field(&element, light, "range", Range::Above(0.0));
        let Some(spot) = light.get("spot") else { return };
        let half_pi = std::f64::consts::FRAC_PI_2;
        self.field(&element, spot, "innerConeAngle", Range::Closed(0.0, half_pi));
        self.field(&element, spot, "outerConeAngle", Range::Closed(0.0, half_pi));
        let angle = |field: &str, default: f64| spot.get(field).and_then(Value::as_f64).unwrap_or(default);
        let (inner, outer) =
            (angle("innerConeAngle", 0.0), angle("outerConeAngle", std::f64::consts::FRAC_PI_4));
        if inner >= outer {
            self.problems.push(format!(
                "{element}: spot innerConeAngle {inner} must be less than outerConeAngle {outer}"
            ));
        }
    }

    fn camera(&mut self, index: usize, camera: &Value) {
        let element = label("camera", index, camera);
        if let Some(p) = camera.get("perspective") {
            self.field(&element, p, "yfov", Range::Above(0.0));
            self.field(&element, p, "znear", Range::Above(0.0));
            self.field(&element, p, "aspectRatio", Range::Above(0.0));
            self.field(&element, p, "zfar", Range::Above(0.0));
            let near = p.get("znear").and_then(Value::as_f64);
            if let (Some(near), Some(far)) = (near, p.get("zfar").and_then(Value::as_f64)) {
                if far <= near {
                    self.problems.push(format!("{element}: zfar {far} must be greater than znear {near}"));
                }
            }
        }
        if let Some(o) = camera.get("orthographic") {
            self.field(&element, o, "xmag", Range::Finite);
            self.field(&element, o, "ymag", Range::Finite);
            self.field(&element, o, "znear", Range::AtLeast(0.0));
            self.field(&element, o, "zfar", Range::Above(0.0));
            for field in ["xmag", "ymag"] {
                if o.get(field).and_then(Value::as_f64) == Some(0.0) {
                    self.problems.push(format!("{element}: orthographic {field} must not be 0"));
                }
            }
        }
    }

    fn node(&mut self, index: usize, node: &Value) {
        let element = label("node", index, node);
        for field in ["translation", "rotation", "scale", "matrix", "weights"] {
            self.field(&element, node, field, Range::Finite);
        }
    }
}

/// Checks every numeric field of the glTF JSON `bytes` against its specified range.
pub(super) fn check(origin: &Origin, bytes: &[u8]) -> Result<()> {
    let json: Value = gltf::json::deserialize::from_slice(bytes)
        .map_err(|e| origin.error(format!("invalid glTF JSON: {e}")))?;
    let mut checker = Checker { problems: Vec::new() };
    let array = |key: &str| json.get(key).and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, m) in array("materials").iter().enumerate() {
        checker.material(i, m);
    }
    for (i, c) in array("cameras").iter().enumerate() {
        checker.camera(i, c);
    }
    for (i, n) in array("nodes").iter().enumerate() {
        checker.node(i, n);
    }
    let lights = json.pointer("/extensions/KHR_lights_punctual/lights").and_then(Value::as_array);
    for (i, l) in lights.into_iter().flatten().enumerate() {
        checker.light(i, l);
    }
    let problems = checker.problems;
    if problems.is_empty() {
        return Ok(());
    }
    let shown = problems.len().min(5);
    let more = if problems.len() > shown {
        format!(" (and {} more)", problems.len() - shown)
    } else {
        String::new()
    };
    Err(origin.error(format!("value out of range: {}{more}", problems[..shown].join("; "))))
}
