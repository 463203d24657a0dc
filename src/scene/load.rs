//! Flattening a glTF document into a [`Scene`]: walk the node tree of the chosen scene, place every
//! mesh primitive with its world transform, and collect cameras, lights and emitters.

use super::accessor::Reader;
use super::geometry::{read_primitive, LocalPrimitive, Wanted};
use super::skin;
use super::source::{self, Asset, Origin};
use super::texture::TextureSet;
use super::LoadOptions;
use super::{Camera, Instance, Light, Material, Scene};
use crate::error::Result;
use glam::{Mat3, Mat4, Quat, Vec3};
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

/// Loads the scene in `bytes`; `base` is the folder external files are relative to.
pub(super) fn load(name: &str, bytes: &[u8], base: Option<&Path>, options: &LoadOptions) -> Result<Scene> {
    let origin = Origin::new(name, base.map(Path::to_path_buf));
    let asset = source::open(&origin, bytes)?;
    let mut textures = TextureSet::default();
    let mut materials = Vec::new();
    for m in asset.document.materials() {
        let mut material = Material::from_gltf(&m, &mut textures);
        material.read_extension_textures(&m, &asset.document, &mut textures).map_err(|e| {
            let index = m.index().map_or("default".to_owned(), |i| i.to_string());
            origin.error(format!("material {index} ('{}'): {e}", m.name().unwrap_or_default()))
        })?;
        if let Some(value) = m.extension_value("UMBRA_implicit") {
            material.parallax = super::material::parse_parallax(value, &asset.document, &mut textures)
                .map_err(|e| {
                    let index = m.index().map_or("default".to_owned(), |i| i.to_string());
                    origin.error(format!(
                        "material {index} ('{}'): UMBRA_implicit: {e}",
                        m.name().unwrap_or_default()
                    ))
                })?;
        }
        materials.push(material);
    }
    // A file with animations keeps what posing it again needs (Scene::pose): the document, its
    // buffers and the materials as read (before their unreadable textures are dropped).
    let rig = (asset.document.animations().len() > 0).then(|| Rig {
        origin: Origin::new(name, base.map(Path::to_path_buf)),
        asset: Asset {
            document: asset.document.clone(),
            buffers: asset.buffers.iter().map(|b| std::borrow::Cow::Owned(b.to_vec())).collect(),
            ignored_extensions: None,
        },
        materials: materials.clone(),
    });
    let mut builder = Builder::new(&origin, &asset, materials);
    if let Some(at) = &options.pose {
        builder.pose = Some(super::animation::pose(&origin, &builder.reader, &asset.document, at)?);
    }
    builder.walk()?;
    let posed = builder.static_pose_warning();
    let frameless = builder.frameless_warning();
    let mut scene = builder.finish()?;
    let (decoded, failed, warnings) = textures.decode(&origin, &asset, options.missing_textures)?;
    scene.textures = decoded;
    // The slots of unreadable images take the neutral value: no texture, the factors alone.
    for m in &mut scene.materials {
        for slot in m.texture_slots_mut() {
            if slot.is_some_and(|t| failed.contains(&t.texture)) {
                *slot = None;
            }
        }
        // Without its height map, no parallax: the flat surface.
        if m.parallax.is_some_and(|p| failed.contains(&p.height.texture)) {
            m.parallax = None;
        }
    }
    scene.warnings.extend(warnings);
    scene.warnings.extend(asset.ignored_extensions.clone());
    scene.warnings.extend(posed);
    scene.warnings.extend(frameless);
    // glTF requires every extension used to be listed; another viewer would drop the shapes.
    let implicit = !scene.implicits.is_empty() || scene.materials.iter().any(|m| m.parallax.is_some());
    if implicit && !asset.document.extensions_used().any(|e| e == "UMBRA_implicit") {
        scene.warnings.push(
            "UMBRA_implicit is used but not listed in extensionsUsed (glTF requires it): umbra renders \
             it, other viewers may ignore it silently"
                .into(),
        );
    }
    scene.update_emissive();
    scene.animation = rig.map(|r| super::AnimationSource(std::sync::Arc::new(r)));
    if log::log_enabled!(log::Level::Debug) {
        log::debug!("{name}: {:?}", scene.stats());
    }
    Ok(scene)
}

/// What [`Scene::pose`] poses a loaded scene from: the file's validated document, its buffers
/// (decompressed) and its materials as read.
pub(super) struct Rig {
    origin: Origin,
    /// Its buffers owned, so each pose borrows the document and buffers as they are.
    asset: Asset<'static>,
    materials: Vec<Material>,
}

/// Poses `scene` (loaded from a file with animations) at `at`: walks its node tree again under
/// the animations' pose and takes the new geometry, instances, cameras and lights, keeping the
/// materials and textures (and the selected variant). Nothing is read from disk.
pub(super) fn pose(scene: &mut Scene, at: &super::PoseAt) -> Result<()> {
    let Some(source) = scene.animation.clone() else {
        return Err(crate::Error::Scene {
            path: scene.name.clone().into(),
            message:
                "has no animations to pose (only a scene loaded from a file with animations can be posed)"
                    .into(),
        });
    };
    let Rig { origin, asset, materials } = &*source.0;
    let mut builder = Builder::new(origin, asset, materials.clone());
    builder.pose = Some(super::animation::pose(origin, &builder.reader, &asset.document, at)?);
    builder.walk()?;
    let posed = builder.finish()?;
    if posed.materials.len() != scene.materials.len() {
        return Err(origin.error("posing it placed a different set of materials than loading it did"));
    }
    let Scene {
        positions,
        normals,
        tangents,
        uv0,
        uv1,
        colors,
        triangles,
        triangle_material,
        cameras,
        lights,
        instances,
        implicits,
        variants,
        ..
    } = posed;
    scene.positions = positions;
    scene.normals = normals;
    scene.tangents = tangents;
    scene.uv0 = uv0;
    scene.uv1 = uv1;
    scene.colors = colors;
    scene.triangles = triangles;
    scene.triangle_material = triangle_material;
    scene.cameras = cameras;
    scene.lights = lights;
    scene.instances = instances;
    scene.implicits = implicits;
    scene.variants.primitives = variants.primitives;
    let selected = scene.variants.selected;
    // Re-applies the variant, and rebuilds the emissive table over the moved triangles.
    scene.select_variant(selected)
}

/// Accumulates the flat scene while the node tree is walked.
struct Builder<'a> {
    origin: &'a Origin,
    asset: &'a Asset<'a>,
    reader: Reader<'a>,
    /// Whether any material has a normal map or is anisotropic, so every vertex needs a tangent.
    tangents: bool,
    /// Primitives with an anisotropic material and no tangent frame (no `TANGENT`, no UVs), for
    /// the warning that they are rendered isotropic.
    frameless: Vec<String>,
    /// Each primitive read once per (mesh, primitive, morph weights' bits, skinned); `None` for
    /// primitives that are not triangles.
    primitives: HashMap<PrimitiveKey, Option<Rc<LocalPrimitive>>>,
    /// Every node's world transform, once a skin needs its joints'.
    node_worlds: Option<Vec<Option<Mat4>>>,
    /// Nodes placed with a skin, and meshes placed with morph targets, for the warning that a
    /// static pose is rendered.
    skinned_nodes: usize,
    morphed_meshes: Vec<usize>,
    /// Index of the glTF default material once a primitive needed it.
    default_material: Option<u32>,
    /// The animations' pose the nodes take (`LoadOptions::pose`); `None`: their defaults.
    pose: Option<super::animation::Pose>,
    /// Triangles dropped for non-finite positions, over all placements.
    dropped: usize,
    scene: Scene,
}

impl<'a> Builder<'a> {
    fn new(origin: &'a Origin, asset: &'a Asset<'a>, materials: Vec<Material>) -> Self {
        Self {
            origin,
            asset,
            reader: Reader { origin, buffers: &asset.buffers },
            tangents: materials.iter().any(|m| m.normal_texture.is_some() || m.anisotropic()),
            frameless: Vec::new(),
            primitives: HashMap::new(),
            node_worlds: None,
            skinned_nodes: 0,
            morphed_meshes: Vec::new(),
            default_material: None,
            pose: None,
            dropped: 0,
            scene: Scene {
                name: origin.name().to_owned(),
                materials,
                variants: super::Variants {
                    names: asset
                        .document
                        .variants()
                        .map_or(Vec::new(), |v| v.map(|v| v.name().to_owned()).collect()),
                    ..Default::default()
                },
                ..Scene::default()
            },
        }
    }

    /// Walks the default scene (or the first; or, in a file without scenes, every root node)
    /// depth first, parents before children, in file order.
    fn walk(&mut self) -> Result<()> {
        let document = &self.asset.document;
        let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; document.nodes().len()];
                for child in document.nodes().flat_map(|n| n.children()) {
                    is_child[child.index()] = true;
                }
                document.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let mut visited = vec![false; document.nodes().len()];
        let mut stack: Vec<(gltf::Node, Mat4)> =
            roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut visited[node.index()], true) {
                return Err(self.origin.error(format!(
                    "node {} is reached twice: the node hierarchy must be a set of disjoint trees \
                     (a cycle, or a node with two parents)",
                    node.index()
                )));
            }
            let world = parent * local_with(&self.pose, &node);
            if !world.is_finite() {
                return Err(self.origin.error(format!(
                    "{}: its world transform is not finite (check its matrix, rotation and scale)",
                    node_label(&node)
                )));
            }
            self.place(&node, world)?;
            stack.extend(node.children().collect::<Vec<_>>().into_iter().rev().map(|c| (c, world)));
        }
        Ok(())
    }

    /// Adds what one node carries: a camera, a light, a mesh (possibly GPU-instanced).
    fn place(&mut self, node: &gltf::Node, world: Mat4) -> Result<()> {
        // A camera or light looks down its node's -Z: a zero scale on the way leaves it no
        // direction (it would silently fall back to a default one).
        if (node.camera().is_some() || node.light().is_some())
            && Mat3::from_mat4(world).determinant().abs() <= 1e-18
        {
            return Err(self.origin.error(format!(
                "{}: its world transform is degenerate (a zero scale here or in a parent), so the camera \
                 or light it carries has no direction",
                node_label(node)
            )));
        }
        if let Some(camera) = node.camera() {
            let camera = Camera::from_gltf(self.origin, &self.asset.document, camera.index(), world)?;
            self.scene.cameras.push(camera);
        }
        if let Some(light) = node.light() {
            self.scene.lights.push(Light::from_gltf(&light, world));
        }
        if let Some(value) = node.extension_value("UMBRA_implicit") {
            self.place_implicit(node, value, world)?;
        }
        if let Some(mesh) = node.mesh() {
            // A skinned mesh is placed by its joints alone: glTF ignores its node's transform.
            let joints = match node.skin() {
                Some(skin) => Some(self.joint_matrices(node, &skin)?),
                None => None,
            };
            let placement = if joints.is_some() { Mat4::IDENTITY } else { world };
            for instance in self.gpu_instances(node)? {
                self.place_mesh(node, &mesh, placement * instance, joints.as_deref())?;
            }
        }
        Ok(())
    }

    /// `UMBRA_implicit` on `node`: its shape, validated, placed with the node's world transform.
    fn place_implicit(&mut self, node: &gltf::Node, value: &gltf::json::Value, world: Mat4) -> Result<()> {
        let label = node_label(node);
        let materials = self.asset.document.materials().len();
        let (root, material) = super::implicit::parse(value, materials)
            .map_err(|e| self.origin.error(format!("{label}: UMBRA_implicit: {e}")))?;
        if Mat3::from_mat4(world).determinant().abs() <= 1e-18 {
            return Err(self.origin.error(format!(
                "{label}: UMBRA_implicit: the node's world transform is degenerate (a zero scale here or in a \
                 parent)"
            )));
        }
        let material = self.material_index(material);
        if root.is_empty() {
            self.scene.warnings.push(format!(
                "{label}: UMBRA_implicit: the shape is empty everywhere (its CSG removes all of it): \
                 nothing renders there"
            ));
        }
        let shape = super::ImplicitShape::new(label.clone(), node.index() as u32, material, root, world);
        match shape.world_bounds() {
            Some((lo, hi)) if lo.abs().max(hi.abs()).max_element() <= super::MAX_COORDINATE => {}
            _ => {
                return Err(self.origin.error(format!(
                    "{label}: UMBRA_implicit: the shape's world box is not within ±{:e}",
                    super::MAX_COORDINATE
                )))
            }
        }
        self.scene.implicits.push(shape);
        Ok(())
    }

    /// Joint matrices of `skin` as `node` uses it (`skin.rs`).
    fn joint_matrices(&mut self, node: &gltf::Node, skin: &gltf::Skin) -> Result<Vec<Mat4>> {
        let pose = &self.pose;
        let worlds = self
            .node_worlds
            .get_or_insert_with(|| skin::node_worlds(&self.asset.document, |n| local_with(pose, n)));
        self.skinned_nodes += 1;
        skin::joint_matrices(&self.reader, skin, worlds, &node_label(node))
    }

    /// The one warning that the file moves (animations, skins, morph targets) and umbra renders
    /// it still: nodes at their default transforms, skins at the pose those give their joints,
    /// morph targets at their default weights. Logged here; `None` when nothing moves.
    /// The one warning naming the anisotropic primitives without a tangent frame, if any.
    fn frameless_warning(&self) -> Option<String> {
        if self.frameless.is_empty() {
            return None;
        }
        let warning = format!(
            "{}: KHR_materials_anisotropy needs a tangent frame, and {} no TANGENT and no TEXCOORD to derive one from: rendered isotropic there",
            self.origin.name(),
            if self.frameless.len() == 1 {
                format!("{} has", self.frameless[0])
            } else {
                format!("{} have", self.frameless.join(", "))
            }
        );
        log::warn!("{warning}");
        Some(warning)
    }

    fn static_pose_warning(&self) -> Option<String> {
        // Posed at a time, the file renders as it moves there.
        if self.pose.is_some() {
            return None;
        }
        let plural = |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        let mut what = Vec::new();
        let animations = self.asset.document.animations().len();
        if animations > 0 {
            what.push(format!("is animated ({})", plural(animations, "animation", "animations")));
        }
        if self.skinned_nodes > 0 {
            what.push(format!(
                "is skinned ({})",
                plural(self.skinned_nodes, "skinned node", "skinned nodes")
            ));
        }
        if !self.morphed_meshes.is_empty() {
            let n = self.morphed_meshes.len();
            what.push(format!("has morph targets ({})", plural(n, "mesh", "meshes")));
        }
        let (last, rest) = what.split_last()?;
        let what = if rest.is_empty() { last.clone() } else { format!("{} and {last}", rest.join(", ")) };
        let warning = format!(
            "{}: the scene {}; umbra renders one static pose: nodes at their default transforms, skins at \
             the pose those give their joints, morph targets at their default weights",
            self.origin.name(),
            what
        );
        log::warn!("{warning}");
        Some(warning)
    }

    /// `EXT_mesh_gpu_instancing`: the per-instance transforms of a node (one identity without it).
    fn gpu_instances(&self, node: &gltf::Node) -> Result<Vec<Mat4>> {
        let Some(extension) = node.extension_value("EXT_mesh_gpu_instancing") else {
            return Ok(vec![Mat4::IDENTITY]);
        };
        let label = format!("EXT_mesh_gpu_instancing of {}", node_label(node));
        let attribute = |name: &str| -> Result<Option<gltf::Accessor>> {
            let Some(index) = extension.get("attributes").and_then(|a| a.get(name)) else { return Ok(None) };
            let accessor = index.as_u64().and_then(|i| self.asset.document.accessors().nth(i as usize));
            accessor.map(Some).ok_or_else(|| {
                self.origin.error(format!("{label}: {name} refers to accessor {index}, which does not exist"))
            })
        };
        let read3 = |name: &str| -> Result<Option<Vec<Vec3>>> {
            let Some(accessor) = attribute(name)? else { return Ok(None) };
            let values = self.reader.vectors::<3>(&accessor, &format!("{name} of {label}"))?;
            Ok(Some(values.into_iter().map(Vec3::from).collect()))
        };
        let translation = read3("TRANSLATION")?;
        let scale = read3("SCALE")?;
        let rotation: Option<Vec<Quat>> = match attribute("ROTATION")? {
            Some(accessor) => {
                let values = self.reader.vectors::<4>(&accessor, &format!("ROTATION of {label}"))?;
                Some(values.into_iter().map(|q| Quat::from_array(q).normalize()).collect())
            }
            None => None,
        };
        let lengths: Vec<usize> = [
            translation.as_ref().map(Vec::len),
            rotation.as_ref().map(Vec::len),
            scale.as_ref().map(Vec::len),
        ]
        .into_iter()
        .flatten()
        .collect();
        let Some(&count) = lengths.first() else {
            return Err(self
                .origin
                .error(format!("{label} has no TRANSLATION, ROTATION or SCALE attribute")));
        };
        if lengths.iter().any(|&l| l != count) {
            return Err(self
                .origin
                .error(format!("{label}: its attributes have different counts {lengths:?}")));
        }
        Ok((0..count)
            .map(|i| {
                Mat4::from_scale_rotation_translation(
                    scale.as_ref().map_or(Vec3::ONE, |s| s[i]),
                    rotation.as_ref().map_or(Quat::IDENTITY, |r| r[i]),
                    translation.as_ref().map_or(Vec3::ZERO, |t| t[i]),
                )
            })
            .collect())
    }

    /// Places every primitive of `mesh` with transform `world` and records the instance; a skinned
    /// one (`joints`: its skin's joint matrices) is posed first, into world space.
    fn place_mesh(
        &mut self,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: Mat4,
        joints: Option<&[Mat4]>,
    ) -> Result<()> {
        if !world.is_finite() {
            return Err(self
                .origin
                .error(format!("{}: an instance transform is not finite", node_label(node))));
        }
        let first_triangle = self.scene.triangles.len();
        let first_vertex = self.scene.positions.len();
        // The node's morph weights override the mesh's (glTF); absent, every weight is 0.
        // Animated weights (a pose) override both.
        let animated = self.pose.as_ref().and_then(|p| p.weights[node.index()].clone());
        let weights = animated.as_deref().or(node.weights()).or(mesh.weights()).unwrap_or_default();
        if mesh.primitives().any(|p| p.morph_targets().len() > 0)
            && !self.morphed_meshes.contains(&mesh.index())
        {
            self.morphed_meshes.push(mesh.index());
        }
        for primitive in mesh.primitives() {
            if let Some(local) = self.local_primitive(mesh, &primitive, weights, joints.is_some())? {
                let material = self.material_index(local.material);
                // A height map on a UV set the primitive lacks would render it flat, silently.
                if let Some(p) = self.scene.materials[material as usize].parallax {
                    let set = p.height.tex_coord;
                    if [local.uv0.is_some(), local.uv1.is_some()].get(set as usize) != Some(&true) {
                        return Err(self.origin.error(format!(
                            "{}: its material's parallax height map (UMBRA_implicit) reads TEXCOORD_{set}, \
                             which the primitive does not have",
                            super::geometry::label(mesh, &primitive)
                        )));
                    }
                }
                let first = self.scene.triangles.len();
                match joints {
                    Some(joints) => {
                        let posed = skin::pose(&local, joints).map_err(|e| {
                            self.origin.error(format!(
                                "{} (skinned by {}): {e}",
                                super::geometry::label(mesh, &primitive),
                                node_label(node)
                            ))
                        })?;
                        self.append(&posed, world, material)?;
                    }
                    None => self.append(&local, world, material)?,
                }
                self.map_variants(mesh, &primitive, material, first)?;
                self.dropped += local.dropped;
            }
        }
        // Beyond what the GPU BVH's quantized boxes reach: refused here, where the node that put
        // the mesh there can be named.
        let reach = self.scene.positions[first_vertex..].iter().flatten().fold(0.0f32, |m, x| m.max(x.abs()));
        if reach > super::MAX_COORDINATE {
            return Err(self.origin.error(format!(
                "{} places mesh {} at coordinates up to {reach:e}; umbra's BVH takes world coordinates within \
                 ±{:e} (check the node's and its parents' translation and scale)",
                node_label(node),
                mesh.index(),
                super::MAX_COORDINATE
            )));
        }
        self.scene.instances.push(Instance {
            name: node.name().unwrap_or_default().to_owned(),
            node: node.index() as u32,
            mesh: mesh.index() as u32,
            transform: world.to_cols_array_2d(),
            first_triangle: first_triangle as u32,
            triangle_count: (self.scene.triangles.len() - first_triangle) as u32,
        });
        Ok(())
    }

    /// A primitive in object space, read on first use, morphed at `morph_weights`, with its
    /// joints and weights when `skinned`.
    fn local_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        morph_weights: &[f32],
        skinned: bool,
    ) -> Result<Option<Rc<LocalPrimitive>>> {
        let morphed = primitive.morph_targets().len() > 0;
        let weight_bits =
            if morphed { morph_weights.iter().map(|w| w.to_bits()).collect() } else { Vec::new() };
        let key = (mesh.index(), primitive.index(), weight_bits, skinned);
        if let Some(cached) = self.primitives.get(&key) {
            return Ok(cached.clone());
        }
        // Tangents from the normal map's UV set, else the anisotropy texture's, else set 0.
        let uv_set = |m: usize| {
            let m = self.scene.materials.get(m)?;
            m.normal_texture.or(m.anisotropy_texture).map(|t| t.tex_coord)
        };
        let wanted = Wanted {
            tangents_from_uv: self
                .tangents
                .then(|| primitive.material().index().and_then(uv_set).unwrap_or(0)),
            morph_weights,
            skinned,
        };
        let local = read_primitive(&self.reader, mesh, primitive, wanted)?.map(Rc::new);
        // KHR_materials_anisotropy's direction lies in the tangent frame: without one (no
        // TANGENT and no UVs to derive it from, tangent w = 0) the surface is rendered isotropic.
        let anisotropic = primitive
            .material()
            .index()
            .and_then(|m| self.scene.materials.get(m))
            .is_some_and(Material::anisotropic);
        if anisotropic && local.as_ref().is_some_and(|l| l.tangents.iter().any(|t| t.w == 0.0)) {
            self.frameless.push(super::geometry::label(mesh, primitive));
        }
        self.primitives.insert(key, local.clone());
        Ok(local)
    }

    /// The scene material index for a glTF material index (`None`: the default material).
    /// `KHR_materials_variants`: records the materials the variants give the primitive just
    /// placed (its triangles from `first` on; `material` its own).
    fn map_variants(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        material: u32,
        first: usize,
    ) -> Result<()> {
        let count = self.scene.variants.names.len();
        let mut variants = vec![None; count];
        for mapping in primitive.mappings() {
            let mapped = self.material_index(mapping.material().index());
            for &v in mapping.variants() {
                let slot = variants.get_mut(v as usize).ok_or_else(|| {
                    self.origin.error(format!(
                        "{}: KHR_materials_variants maps variant {v}, but the file has {count}",
                        super::geometry::label(mesh, primitive)
                    ))
                })?;
                *slot = Some(mapped);
            }
        }
        if variants.iter().any(Option::is_some) {
            self.scene.variants.primitives.push(super::VariantPrimitive {
                first_triangle: first as u32,
                triangle_count: (self.scene.triangles.len() - first) as u32,
                material,
                variants,
            });
        }
        Ok(())
    }

    fn material_index(&mut self, material: Option<usize>) -> u32 {
        match material {
            Some(m) => m as u32,
            None => *self.default_material.get_or_insert_with(|| {
                self.scene.materials.push(Material { name: "glTF default".into(), ..Material::default() });
                self.scene.materials.len() as u32 - 1
            }),
        }
    }

    /// Appends a primitive transformed to world space. Normals go through the inverse transpose;
    /// a mirroring transform reverses the winding (and the tangent handedness) so front faces
    /// stay counter-clockwise.
    fn append(&mut self, local: &LocalPrimitive, world: Mat4, material: u32) -> Result<()> {
        let base = self.scene.positions.len();
        if base + local.positions.len() > u32::MAX as usize {
            return Err(self.origin.error("the scene has more than 2^32 vertices"));
        }
        let linear = Mat3::from_mat4(world);
        let normal_matrix = linear.inverse().transpose();
        let mirrored = linear.determinant() < 0.0;
        let scene = &mut self.scene;
        scene.positions.extend(local.positions.iter().map(|&p| world.transform_point3(p).to_array()));
        let normals: Vec<Vec3> =
            local.normals.iter().map(|&n| (normal_matrix * n).normalize_or(Vec3::Z)).collect();
        if self.tangents {
            scene.tangents.extend(local.tangents.iter().zip(&normals).map(|(t, &n)| {
                let xyz = linear * t.truncate();
                let xyz = (xyz - n * n.dot(xyz)).normalize_or(n.any_orthonormal_vector());
                [xyz.x, xyz.y, xyz.z, if mirrored { -t.w } else { t.w }]
            }));
        }
        scene.normals.extend(normals.iter().map(|n| n.to_array()));
        extend_optional(&mut scene.uv0, base, local.uv0.as_deref(), [0.0; 2]);
        extend_optional(&mut scene.uv1, base, local.uv1.as_deref(), [0.0; 2]);
        extend_optional(&mut scene.colors, base, local.colors.as_deref(), [1.0; 4]);
        let base = base as u32;
        scene.triangles.extend(local.triangles.iter().map(|&[a, b, c]| {
            let [a, b, c] = [a + base, b + base, c + base];
            if mirrored {
                [a, c, b]
            } else {
                [a, b, c]
            }
        }));
        scene.triangle_material.extend(std::iter::repeat_n(material, local.triangles.len()));
        Ok(())
    }

    /// The finished scene: optional attributes padded to every vertex, emptiness rejected.
    fn finish(mut self) -> Result<Scene> {
        let scene = &mut self.scene;
        let vertices = scene.positions.len();
        for uv in [&mut scene.uv0, &mut scene.uv1] {
            if !uv.is_empty() {
                uv.resize(vertices, [0.0; 2]);
            }
        }
        if !scene.colors.is_empty() {
            scene.colors.resize(vertices, [1.0; 4]);
        }
        if scene.triangles.is_empty() && scene.implicits.is_empty() {
            return Err(self.origin.error(match self.dropped {
                0 => "the scene has no triangles to render".to_owned(),
                n => format!("all {n} triangles were dropped for NaN or infinite vertex positions"),
            }));
        }
        Ok(self.scene)
    }
}

/// Which reading of a primitive: mesh, primitive, its morph weights' bits (empty without morph
/// targets), skinned.
type PrimitiveKey = (usize, usize, Vec<u32>, bool);

/// A node's local transform under `pose` (its animated properties), or its own.
fn local_with(pose: &Option<super::animation::Pose>, node: &gltf::Node) -> Mat4 {
    pose.as_ref().map_or_else(|| local_transform(node), |p| p.local(node))
}

/// A node's local transform: its matrix, or translation · rotation · scale.
pub(super) fn local_transform(node: &gltf::Node) -> Mat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            Mat4::from_scale_rotation_translation(
                Vec3::from(scale),
                Quat::from_array(rotation).normalize(),
                Vec3::from(translation),
            )
        }
    }
}

/// "node 4 ('Wheel')", for messages.
fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(name) => format!("node {} ('{name}')", node.index()),
        None => format!("node {}", node.index()),
    }
}

/// Appends `values` to an optional vertex attribute, first padding it with `fill` for the
/// vertices of earlier primitives that lacked it.
fn extend_optional<T: Copy>(out: &mut Vec<T>, base: usize, values: Option<&[T]>, fill: T) {
    if let Some(values) = values {
        out.resize(base, fill);
        out.extend_from_slice(values);
    }
}
