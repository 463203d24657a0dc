//! What a glTF file holds, before any GPU work (`umbra info SCENE`): its contents from the JSON,
//! what loading it gives (triangles, bounds, decoded textures) or why umbra refuses it, and the
//! extensions umbra reads, ignores or refuses.

use super::source::{self, Origin};
use super::{extension_supported, LoadOptions, Scene};
use crate::error::Result;
use gltf::json::Value;
use std::path::Path;

/// What umbra does with an extension a file uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtensionUse {
    /// Read and rendered.
    Read,
    /// Optional and not read: the file renders without what it adds.
    Ignored,
    /// Required and not read: the file is refused.
    Refused,
}

impl ExtensionUse {
    /// `read`, `ignored` or `refused`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Read => "read",
            Self::Ignored => "ignored",
            Self::Refused => "refused",
        }
    }
}

/// One extension of `extensionsUsed` (or `extensionsRequired`).
#[derive(Clone, Debug, PartialEq)]
pub struct ExtensionInfo {
    /// Its name.
    pub name: String,
    /// Whether the file requires it.
    pub required: bool,
    /// What umbra does with it.
    pub status: ExtensionUse,
}

/// One material: its name and the extensions it uses.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialInfo {
    /// Its name (empty when it has none).
    pub name: String,
    /// The extensions on it.
    pub extensions: Vec<String>,
}

/// One image as the file declares it, and its size once decoded.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageInfo {
    /// Its name, else its URI, else empty.
    pub name: String,
    /// Its MIME type (declared, or from the URI's extension), or empty.
    pub format: String,
    /// Width and height of the decoded texels (the largest among the textures using it); `None`
    /// when no texture umbra decoded uses it, or the scene was refused.
    pub size: Option<(u32, u32)>,
}

/// One animation: its name, channels and duration (the latest key time of its samplers' input
/// accessors' declared `max`).
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationInfo {
    /// Its name (empty when it has none).
    pub name: String,
    /// Its channels.
    pub channels: usize,
    /// Seconds from 0 to its last key.
    pub duration: f32,
}

/// What [`SceneInfo::read`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneInfo {
    /// The file.
    pub file: String,
    /// `glb` or `gltf`.
    pub container: &'static str,
    /// `asset.generator`, when given.
    pub generator: Option<String>,
    /// Every extension used or required, sorted by name.
    pub extensions: Vec<ExtensionInfo>,
    /// Meshes and their primitives.
    pub meshes: usize,
    /// Primitives over all meshes.
    pub primitives: usize,
    /// Nodes.
    pub nodes: usize,
    /// Materials in file order.
    pub materials: Vec<MaterialInfo>,
    /// Images in file order.
    pub images: Vec<ImageInfo>,
    /// Cameras (`perspective` or `orthographic`, in file order).
    pub cameras: Vec<String>,
    /// `KHR_lights_punctual` lights: kind and name.
    pub lights: Vec<(String, String)>,
    /// `KHR_materials_variants` names.
    pub variants: Vec<String>,
    /// Animations.
    pub animations: Vec<AnimationInfo>,
    /// Skins.
    pub skins: usize,
    /// Meshes with morph targets.
    pub morphed_meshes: usize,
    /// What loading the scene gave: its [`super::Stats`], bounds and warnings; or why it is
    /// refused.
    pub loaded: std::result::Result<LoadedInfo, String>,
}

/// What loading gave.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedInfo {
    /// Triangles, vertices, placed instances and the rest.
    pub stats: super::Stats,
    /// Axis-aligned bounds, world space.
    pub bounds: ([f32; 3], [f32; 3]),
    /// Implicit shapes (`UMBRA_implicit`).
    pub implicit_shapes: usize,
    /// The warnings loading gave (what umbra ignores or approximates).
    pub warnings: Vec<String>,
}

impl SceneInfo {
    /// Reads `path`: its JSON, then the whole scene (as [`Scene::load_with`] with `options`;
    /// CPU only). A file that is not glTF at all, or cannot be read, is an error; a glTF file
    /// umbra refuses gives its reason in [`SceneInfo::loaded`].
    pub fn read(path: &Path, options: &LoadOptions) -> Result<SceneInfo> {
        let name = path.display().to_string();
        let origin = Origin::new(&name, path.parent().map(Path::to_path_buf));
        let bytes =
            std::fs::read(path).map_err(|e| origin.error(format!("cannot read the scene file: {e}")))?;
        let container = if bytes.starts_with(b"glTF") { "glb" } else { "gltf" };
        let root = source::json_value(&origin, &bytes)?;
        let loaded = Scene::load_file_bytes(path, &bytes, options);
        Ok(Self::of(name, container, &root, loaded))
    }

    fn of(file: String, container: &'static str, root: &Value, loaded: Result<Scene>) -> SceneInfo {
        let list = |key: &str| array(root, key);
        let str_of = |v: &Value, key: &str| v.get(key).and_then(Value::as_str).unwrap_or_default().to_owned();
        let keys = |v: &Value| -> Vec<String> {
            v.get("extensions").and_then(Value::as_object).map_or(Vec::new(), |o| o.keys().cloned().collect())
        };
        let names = |key: &str| -> Vec<String> {
            list(key).iter().filter_map(Value::as_str).map(str::to_owned).collect()
        };
        let (used, required) = (names("extensionsUsed"), names("extensionsRequired"));
        let mut all: Vec<String> = used.iter().chain(&required).cloned().collect();
        all.sort();
        all.dedup();
        let extensions = all
            .into_iter()
            .map(|name| {
                let required = required.contains(&name);
                let status = match (extension_supported(&name), required) {
                    (true, _) => ExtensionUse::Read,
                    (false, false) => ExtensionUse::Ignored,
                    (false, true) => ExtensionUse::Refused,
                };
                ExtensionInfo { name, required, status }
            })
            .collect();
        let meshes = list("meshes");
        let primitives = |m| array(m, "primitives");
        let accessors = list("accessors");
        let animations = list("animations")
            .iter()
            .map(|a| {
                let samplers = array(a, "samplers");
                let duration = samplers
                    .iter()
                    .filter_map(|s| s.get("input").and_then(Value::as_u64))
                    .filter_map(|i| accessors.get(i as usize)?.get("max")?.get(0)?.as_f64())
                    .fold(0.0f64, f64::max) as f32;
                let channels = array(a, "channels").len();
                AnimationInfo { name: str_of(a, "name"), channels, duration }
            })
            .collect();
        let extension = |key: &str| root.get("extensions").and_then(|e| e.get(key));
        let lights = extension("KHR_lights_punctual")
            .and_then(|l| l.get("lights"))
            .and_then(Value::as_array)
            .map_or(Vec::new(), |ls| ls.iter().map(|l| (str_of(l, "type"), str_of(l, "name"))).collect());
        let variants = extension("KHR_materials_variants")
            .and_then(|v| v.get("variants"))
            .and_then(Value::as_array)
            .map_or(Vec::new(), |vs| vs.iter().map(|v| str_of(v, "name")).collect());
        let loaded = loaded.map(|scene| {
            (
                LoadedInfo {
                    stats: scene.stats(),
                    bounds: scene.bounds(),
                    implicit_shapes: scene.implicits.len(),
                    warnings: scene.warnings.clone(),
                },
                scene,
            )
        });
        // Each image's decoded size: that of the textures made from it, which carry the name the
        // decoder gives it (its name, else its URI, else "image i": texture.rs).
        let images = list("images")
            .iter()
            .enumerate()
            .map(|(i, image)| {
                let uri = str_of(image, "uri");
                let mut format = str_of(image, "mimeType");
                if format.is_empty() && !uri.starts_with("data:") {
                    let ext = Path::new(&uri).extension().map(|e| e.to_string_lossy().to_lowercase());
                    format = match ext.as_deref() {
                        Some("png") => "image/png".into(),
                        Some("jpg" | "jpeg") => "image/jpeg".into(),
                        Some("webp") => "image/webp".into(),
                        Some("ktx2") => "image/ktx2".into(),
                        _ => String::new(),
                    };
                }
                let label = match (image.get("name").and_then(Value::as_str), uri.as_str()) {
                    (Some(name), _) => name.to_owned(),
                    (None, uri) if !uri.is_empty() && !uri.starts_with("data:") => uri.to_owned(),
                    _ => format!("image {i}"),
                };
                let size = loaded.as_ref().ok().and_then(|(_, scene)| {
                    scene.textures.iter().filter(|t| t.name == label).map(|t| (t.width, t.height)).max()
                });
                ImageInfo { name: label, format, size }
            })
            .collect();
        SceneInfo {
            file,
            container,
            generator: root
                .get("asset")
                .and_then(|a| a.get("generator"))
                .and_then(Value::as_str)
                .map(str::to_owned),
            extensions,
            meshes: meshes.len(),
            primitives: meshes.iter().map(|m| primitives(m).len()).sum(),
            nodes: list("nodes").len(),
            materials: list("materials")
                .iter()
                .map(|m| MaterialInfo { name: str_of(m, "name"), extensions: keys(m) })
                .collect(),
            images,
            cameras: list("cameras").iter().map(|c| str_of(c, "type")).collect(),
            lights,
            variants,
            animations,
            skins: list("skins").len(),
            morphed_meshes: meshes
                .iter()
                .filter(|m| {
                    primitives(m)
                        .iter()
                        .any(|p| p.get("targets").and_then(Value::as_array).is_some_and(|t| !t.is_empty()))
                })
                .count(),
            loaded: loaded.map(|(info, _)| info).map_err(|e| e.to_string()),
        }
    }
}

/// `value[key]` as an array; empty when it is absent or not one.
fn array<'a>(value: &'a Value, key: &str) -> &'a [Value] {
    value.get(key).and_then(Value::as_array).map_or(&[], Vec::as_slice)
}
