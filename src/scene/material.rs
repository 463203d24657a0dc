//! Materials: glTF 2.0 metallic-roughness with the emissive strength, specular, transmission, IOR,
//! volume, unlit, clear coat, sheen and anisotropy extensions, and `KHR_texture_transform` on
//! every texture slot.

use super::texture::TextureSet;
use gltf::json::Value;

/// How a material's alpha (base colour alpha × texture alpha) is used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AlphaMode {
    /// Alpha is ignored (the glTF default).
    #[default]
    Opaque,
    /// Alpha below `alpha_cutoff` is fully transparent, above fully opaque.
    Mask,
    /// Alpha blends with what is behind.
    Blend,
}

/// The identity UV transform.
pub const IDENTITY_TRANSFORM: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A material's use of a texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    /// Index into [`super::Scene::textures`].
    pub texture: u32,
    /// Which UV set (`0`: `uv0`, `1`: `uv1`), after any `KHR_texture_transform` override.
    pub tex_coord: u32,
    /// `KHR_texture_transform` as a 2×3 affine matrix, rows first:
    /// `u' = t[0][0]·u + t[0][1]·v + t[0][2]`, `v' = t[1][0]·u + t[1][1]·v + t[1][2]`.
    /// See [`texture_transform`].
    pub transform: [[f32; 3]; 2],
    /// The normal map's `scale` or the occlusion map's `strength`; 1 for other slots.
    pub scale: f32,
}

/// Parallax occlusion mapping of a material (`UMBRA_implicit`'s `parallax` on a glTF material;
/// docs/gltf.md "Parallax occlusion mapping"): a height field under the triangles, ray-marched in their
/// plane at every hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parallax {
    /// The height map: R = 1 on the triangle's surface, R = 0 at [`Parallax::scale`] below it
    /// along the geometric normal (the side the viewer is on), linearly between.
    pub height: TextureRef,
    /// Depth of height 0 below the surface, in world units (metres; the node's scale does not
    /// apply: the triangles are marched in world space).
    pub scale: f32,
    /// Layers of the linear search (the depth range cut into that many equal steps).
    pub layers: u32,
    /// Steps of binary-search refinement after the linear search.
    pub refinement: u32,
}

impl Parallax {
    /// The most layers accepted: each is a texture lookup per hit (and per light for the
    /// self-shadow march).
    pub const MAX_LAYERS: u32 = 256;
    /// The most refinement steps accepted (2⁻¹⁶ of a layer is below `f32`'s resolution of depth).
    pub const MAX_REFINEMENT: u32 = 16;
    /// Layers when the file gives none.
    pub const DEFAULT_LAYERS: u32 = 32;
    /// Refinement steps when the file gives none.
    pub const DEFAULT_REFINEMENT: u32 = 8;
}

impl Material {
    /// Every texture slot, for changing them all (a missing image's uses are dropped).
    pub(super) fn texture_slots_mut(&mut self) -> [&mut Option<TextureRef>; 19] {
        [
            &mut self.base_color_texture,
            &mut self.metallic_roughness_texture,
            &mut self.normal_texture,
            &mut self.occlusion_texture,
            &mut self.emissive_texture,
            &mut self.specular_texture,
            &mut self.specular_color_texture,
            &mut self.transmission_texture,
            &mut self.clearcoat_texture,
            &mut self.clearcoat_roughness_texture,
            &mut self.clearcoat_normal_texture,
            &mut self.iridescence_texture,
            &mut self.iridescence_thickness_texture,
            &mut self.anisotropy_texture,
            &mut self.sheen_color_texture,
            &mut self.sheen_roughness_texture,
            &mut self.diffuse_transmission_texture,
            &mut self.diffuse_transmission_color_texture,
            &mut self.thickness_texture,
        ]
    }
}

impl Material {
    /// Adds every parameter but the name to a content hash ([`super::Scene::content_hash`]).
    pub(super) fn hash_into(&self, h: &mut super::ContentHasher) {
        let Material {
            name: _,
            base_color_factor,
            metallic,
            roughness,
            emissive,
            ior,
            specular_factor,
            specular_color_factor,
            transmission_factor,
            volume,
            attenuation_color,
            attenuation_distance,
            alpha_mode,
            alpha_cutoff,
            double_sided,
            unlit,
            clearcoat,
            clearcoat_roughness,
            sheen_color,
            sheen_roughness,
            iridescence,
            iridescence_ior,
            iridescence_thickness,
            anisotropy_strength,
            anisotropy_rotation,
            diffuse_transmission,
            diffuse_transmission_color,
            thickness,
            dispersion,
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            occlusion_texture,
            emissive_texture,
            specular_texture,
            specular_color_texture,
            transmission_texture,
            clearcoat_texture,
            clearcoat_roughness_texture,
            clearcoat_normal_texture,
            iridescence_texture,
            iridescence_thickness_texture,
            anisotropy_texture,
            sheen_color_texture,
            sheen_roughness_texture,
            diffuse_transmission_texture,
            diffuse_transmission_color_texture,
            thickness_texture,
            parallax,
        } = self;
        h.f32s(base_color_factor);
        h.f32s(&[*metallic, *roughness]);
        h.f32s(emissive);
        h.f32s(&[*ior, *specular_factor]);
        h.f32s(specular_color_factor);
        h.f32s(&[*transmission_factor]);
        h.bool(*volume);
        h.f32s(attenuation_color);
        h.f32s(&[*attenuation_distance]);
        h.u32(match alpha_mode {
            AlphaMode::Opaque => 0,
            AlphaMode::Mask => 1,
            AlphaMode::Blend => 2,
        });
        h.f32s(&[*alpha_cutoff]);
        h.bool(*double_sided);
        h.bool(*unlit);
        h.f32s(&[*clearcoat, *clearcoat_roughness]);
        // Nothing without parallax: the hashes of scenes without it stay what they were.
        if let Some(Parallax { height, scale, layers, refinement }) = parallax {
            h.u32s(&[height.texture, height.tex_coord, *layers, *refinement]);
            h.f32s(height.transform.as_flattened());
            h.f32s(&[*scale]);
        }
        // Nothing without a sheen: the hashes of scenes without it stay what they were.
        if *sheen_color != [0.0; 3] || *sheen_roughness != 0.0 {
            h.f32s(sheen_color);
            h.f32s(&[*sheen_roughness]);
        }
        let slot = |h: &mut super::ContentHasher, slot: &Option<TextureRef>| match slot {
            None => h.u32(0),
            Some(TextureRef { texture, tex_coord, transform, scale }) => {
                h.u32(1);
                h.u32s(&[*texture, *tex_coord]);
                h.f32s(transform.as_flattened());
                h.f32s(&[*scale]);
            }
        };
        for s in [
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            occlusion_texture,
            emissive_texture,
            specular_texture,
            specular_color_texture,
            transmission_texture,
        ] {
            slot(h, s);
        }
        // Nothing without the clear coat's textures: the hashes of scenes without them stay
        // what they were.
        let coat = [clearcoat_texture, clearcoat_roughness_texture, clearcoat_normal_texture];
        if coat.iter().any(|t| t.is_some()) {
            for s in coat {
                slot(h, s);
            }
        }
        // Nothing without a film: the hashes of scenes without it stay what they were.
        let film = [iridescence_texture, iridescence_thickness_texture];
        let default = Material::default();
        if *iridescence != 0.0
            || *iridescence_ior != default.iridescence_ior
            || *iridescence_thickness != default.iridescence_thickness
            || film.iter().any(|t| t.is_some())
        {
            h.f32s(&[*iridescence, *iridescence_ior]);
            h.f32s(iridescence_thickness);
            for s in film {
                slot(h, s);
            }
        }
        // Nor without anisotropy.
        if *anisotropy_strength != 0.0 || *anisotropy_rotation != 0.0 || anisotropy_texture.is_some() {
            h.f32s(&[*anisotropy_strength, *anisotropy_rotation]);
            slot(h, anisotropy_texture);
        }
        // Nor without the sheen's textures.
        let sheen = [sheen_color_texture, sheen_roughness_texture];
        if sheen.iter().any(|t| t.is_some()) {
            for s in sheen {
                slot(h, s);
            }
        }
        // Nor without a volume's thickness.
        if *thickness != 0.0 || thickness_texture.is_some() {
            h.f32s(&[*thickness]);
            slot(h, thickness_texture);
        }
        // Nor without dispersion.
        if *dispersion != 0.0 {
            h.f32s(&[*dispersion]);
        }
        // Nor without diffuse transmission.
        let through = [diffuse_transmission_texture, diffuse_transmission_color_texture];
        if *diffuse_transmission != 0.0
            || *diffuse_transmission_color != [1.0; 3]
            || through.iter().any(|t| t.is_some())
        {
            h.f32s(&[*diffuse_transmission]);
            h.f32s(diffuse_transmission_color);
            for s in through {
                slot(h, s);
            }
        }
    }
}

impl Material {
    /// The radiance the material emits (before its emissive texture): `emissive`, or nothing for
    /// an unlit material, whose emission glTF says to ignore.
    pub fn emission(&self) -> [f32; 3] {
        if self.unlit {
            [0.0; 3]
        } else {
            self.emissive
        }
    }

    /// The volume's attenuation coefficient per unit length, −ln(colour) / distance per
    /// channel (Beer–Lambert: light keeps exp(−σ·d) after d); 0 without a volume, for a white
    /// colour or an infinite distance; a black channel counts as the smallest normal float
    /// (σ ≈ 87 / distance, so σ·d stays finite and exp(−σ·0) is 1).
    pub fn attenuation(&self) -> [f32; 3] {
        let d = self.attenuation_distance;
        if !self.volume || d.is_nan() || d <= 0.0 || d.is_infinite() {
            return [0.0; 3];
        }
        self.attenuation_color.map(|c| if c >= 1.0 { 0.0 } else { -c.max(f32::MIN_POSITIVE).ln() / d })
    }
}

/// The wavelengths (nm) at which a dispersive volume's index of refraction is taken for the red,
/// green and blue channels: the Fraunhofer C, d and F lines that define the Abbe number (so red
/// to blue spans the extension's n_F − n_C = (ior − 1) / V_d, green is the material's ior).
pub const DISPERSION_WAVELENGTHS: [f32; 3] = [656.3, 587.6, 486.1];

impl Material {
    /// Whether the material disperses: a transmitting volume with a dispersion above 0 (the
    /// extension builds on `KHR_materials_volume`; a thin wall does not disperse).
    pub fn disperses(&self) -> bool {
        self.volume && self.dispersion > 0.0 && self.transmission_factor > 0.0
    }

    /// The index of refraction of the red, green and blue channels ([`DISPERSION_WAVELENGTHS`])
    /// under `KHR_materials_dispersion` (every one the ior without a dispersive volume). The
    /// path tracer follows one channel through a dispersive volume (picked uniformly at the first
    /// dispersive surface a path meets, its throughput weighted 3× on that channel alone), the
    /// hybrid refracts the environment once per channel.
    pub fn dispersion_iors(&self) -> [f32; 3] {
        if !self.disperses() {
            return [self.ior; 3];
        }
        DISPERSION_WAVELENGTHS.map(|l| {
            (self.ior + (self.ior - 1.0) * self.dispersion / 20.0 * (523_655.0 / (l * l) - 1.5168)).max(1.0)
        })
    }
}

impl TextureRef {
    /// Applies [`TextureRef::transform`] to a UV coordinate.
    pub fn transform_uv(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        let [r0, r1] = self.transform;
        [r0[0] * u + r0[1] * v + r0[2], r1[0] * u + r1[1] * v + r1[2]]
    }
}

/// The `KHR_texture_transform` matrix `translation · rotation · scale` as 2×3, rows first.
///
/// `rotation` turns the UVs counter-clockwise as seen in the image (whose v axis points down):
/// `u' = sx·cos·u + sy·sin·v + ox`, `v' = −sx·sin·u + sy·cos·v + oy`. This is the convention of
/// the extension's worked example ("offset [0, 1], rotation π/2, scale ½ uses the lower-left
/// quadrant"), of the Khronos sample viewer and of three.js; the GLSL snippet in the extension
/// text, read as column-major, would rotate the other way.
pub fn texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> [[f32; 3]; 2] {
    let (sin, cos) = rotation.sin_cos();
    [[scale[0] * cos, scale[1] * sin, offset[0]], [-scale[0] * sin, scale[1] * cos, offset[1]]]
}

/// A glTF 2.0 metallic-roughness material, with every factor resolved.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The material's name (empty when it has none).
    pub name: String,
    /// Linear RGBA multiplier of the base colour texture.
    pub base_color_factor: [f32; 4],
    /// Metalness, 0 (dielectric) to 1 (metal).
    pub metallic: f32,
    /// Perceptual roughness (α = roughness²).
    pub roughness: f32,
    /// Emitted radiance, linear RGB: `emissiveFactor` × `KHR_materials_emissive_strength`.
    pub emissive: [f32; 3],
    /// Index of refraction (`KHR_materials_ior`, default 1.5).
    pub ior: f32,
    /// Specular strength (`KHR_materials_specular`, default 1).
    pub specular_factor: f32,
    /// Specular F0 colour (`KHR_materials_specular`, default white).
    pub specular_color_factor: [f32; 3],
    /// Transmission (`KHR_materials_transmission`, default 0).
    pub transmission_factor: f32,
    /// `KHR_materials_volume` with a thickness above 0: the surface bounds a volume and
    /// transmission refracts (Snell's law, total internal reflection); otherwise it is
    /// thin-walled, as glTF specifies. The thickness is not modelled (the path tracer traces the
    /// real distances; the hybrid does not model transmission).
    pub volume: bool,
    /// `KHR_materials_volume`'s attenuation colour: the colour white light takes after
    /// [`Material::attenuation_distance`] inside the volume (Beer–Lambert; default white).
    pub attenuation_color: [f32; 3],
    /// `KHR_materials_volume`'s attenuation distance (default +∞: no attenuation).
    pub attenuation_distance: f32,
    /// How alpha is used.
    pub alpha_mode: AlphaMode,
    /// The `Mask` threshold (default 0.5).
    pub alpha_cutoff: f32,
    /// Whether back faces are shaded too (with the normal flipped).
    pub double_sided: bool,
    /// `KHR_materials_unlit`: the surface shows its base colour (factor × texture × `COLOR_0`)
    /// whatever the light, and every other property but alpha and `double_sided` is ignored,
    /// emission included ([`Material::emission`]). The path tracer models it as an emitter of
    /// that radiance which scatters nothing (paths end there; it is not among the sampled
    /// lights), the hybrid renderer writes the colour as it is.
    pub unlit: bool,
    /// `KHR_materials_clearcoat`'s `clearcoatFactor` (default 0: no coat): the weight of a
    /// clear dielectric coat (ior 1.5, GGX) over the material, after the specification's
    /// layering (the base scaled by 1 − clearcoat · F(N·V)).
    pub clearcoat: f32,
    /// `clearcoatRoughnessFactor` (default 0).
    pub clearcoat_roughness: f32,
    /// `KHR_materials_sheen`'s `sheenColorFactor` (linear RGB, default 0: no sheen): the colour
    /// of a "Charlie" sheen lobe over the material (under a clear coat), after the
    /// specification's albedo scaling (the material scaled by 1 − max3(sheenColor) · E).
    pub sheen_color: [f32; 3],
    /// `sheenRoughnessFactor` (default 0; the kernels use at least 0.05).
    pub sheen_roughness: f32,
    /// `KHR_materials_iridescence`'s `iridescenceFactor` (default 0: no film): the weight of a thin
    /// dielectric film's interference Fresnel over the material's own (dielectric and metal),
    /// after the extension's layering.
    pub iridescence: f32,
    /// `iridescenceIor`: the film's index of refraction (default 1.3).
    pub iridescence_ior: f32,
    /// `iridescenceThicknessMinimum` and `iridescenceThicknessMaximum`: the film's thickness in nm
    /// where the thickness texture reads 0 and 1 (default 100 and 400; the maximum without a
    /// texture). A film of thickness 0 is none (the material's own Fresnel).
    pub iridescence_thickness: [f32; 2],
    /// `KHR_materials_anisotropy`'s `anisotropyStrength` (default 0: isotropic): the specular
    /// lobes' GGX roughness along the anisotropy direction is αt = mix(α, 1, strength²), across
    /// it αb = α.
    pub anisotropy_strength: f32,
    /// `KHR_materials_volume`'s `thicknessFactor` (default 0; above 0 the surface bounds a
    /// volume, [`Material::volume`]): the hybrid's attenuation approximates the distance light
    /// travels inside by it (the path tracer traces the distance).
    pub thickness: f32,
    /// `KHR_materials_dispersion`'s `dispersion` (20 / Abbe number; default 0: none): a volume's
    /// index of refraction by wavelength after the extension's Cauchy fit, n(λ) = max(ior +
    /// (ior − 1) · dispersion / 20 · (523655 nm² / λ² − 1.5168), 1), taken per colour channel at
    /// the Fraunhofer lines the Abbe number is defined by ([`Material::dispersion_iors`]). Only
    /// a volume ([`Material::volume`]) disperses.
    pub dispersion: f32,
    /// `KHR_materials_diffuse_transmission`'s `diffuseTransmissionFactor` (default 0: none): the
    /// share of the dielectric's diffuse lobe that leaves through the back as a Lambertian lobe.
    pub diffuse_transmission: f32,
    /// `diffuseTransmissionColorFactor` (linear RGB, default 1): that lobe's colour.
    pub diffuse_transmission_color: [f32; 3],
    /// `anisotropyRotation` (radians, default 0): the anisotropy direction's angle from the
    /// tangent towards the bitangent (the texture's direction, when there is one, rotated so).
    pub anisotropy_rotation: f32,
    /// Base colour (sRGB RGBA).
    pub base_color_texture: Option<TextureRef>,
    /// Roughness in G, metalness in B (linear).
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map (linear); `scale` scales its XY.
    pub normal_texture: Option<TextureRef>,
    /// Ambient occlusion in R (linear); `scale` is the strength. The hybrid renderer scales its
    /// image-based (ambient) light by 1 + strength (r − 1), never direct light; the path tracer
    /// ignores it (it traces occlusion itself).
    pub occlusion_texture: Option<TextureRef>,
    /// Emission (sRGB RGB), multiplied by `emissive`.
    pub emissive_texture: Option<TextureRef>,
    /// Specular strength in A (linear).
    pub specular_texture: Option<TextureRef>,
    /// Specular colour (sRGB RGB).
    pub specular_color_texture: Option<TextureRef>,
    /// Transmission in R (linear).
    pub transmission_texture: Option<TextureRef>,
    /// `KHR_materials_clearcoat`'s `clearcoatTexture`: the coat's weight in R (linear).
    pub clearcoat_texture: Option<TextureRef>,
    /// `clearcoatRoughnessTexture`: the coat's roughness in G (linear).
    pub clearcoat_roughness_texture: Option<TextureRef>,
    /// `clearcoatNormalTexture`: the coat's own tangent-space normal map (linear; `scale` scales
    /// its XY). Without it the coat lies on the interpolated normal, whatever the base's
    /// `normal_texture` does.
    pub clearcoat_normal_texture: Option<TextureRef>,
    /// `iridescenceTexture`: the film's weight in R (linear), × `iridescenceFactor`.
    pub iridescence_texture: Option<TextureRef>,
    /// `iridescenceThicknessTexture`: in G (linear), the film's thickness from the minimum (0) to
    /// the maximum (1).
    pub iridescence_thickness_texture: Option<TextureRef>,
    /// `anisotropyTexture` (linear): RG the direction in tangent space (2·rg − 1), B × the
    /// strength.
    pub anisotropy_texture: Option<TextureRef>,
    /// `KHR_materials_sheen`'s `sheenColorTexture`: the sheen's colour in RGB (sRGB), ×
    /// `sheenColorFactor`.
    pub sheen_color_texture: Option<TextureRef>,
    /// `sheenRoughnessTexture`: the sheen's roughness in A (linear), × `sheenRoughnessFactor`.
    pub sheen_roughness_texture: Option<TextureRef>,
    /// `diffuseTransmissionTexture`: the diffuse transmission's share in A (linear), ×
    /// `diffuseTransmissionFactor`.
    pub diffuse_transmission_texture: Option<TextureRef>,
    /// `diffuseTransmissionColorTexture`: its colour in RGB (sRGB), ×
    /// `diffuseTransmissionColorFactor`.
    pub diffuse_transmission_color_texture: Option<TextureRef>,
    /// `KHR_materials_volume`'s `thicknessTexture`: in G (linear), × `thicknessFactor`.
    pub thickness_texture: Option<TextureRef>,
    /// Parallax occlusion mapping (`UMBRA_implicit`'s `parallax`), with its height map.
    pub parallax: Option<Parallax>,
}

impl Default for Material {
    /// The glTF default material: white, fully metallic, fully rough, opaque, one-sided.
    fn default() -> Self {
        Self {
            name: String::new(),
            base_color_factor: [1.0; 4],
            metallic: 1.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            ior: 1.5,
            specular_factor: 1.0,
            specular_color_factor: [1.0; 3],
            transmission_factor: 0.0,
            volume: false,
            attenuation_color: [1.0; 3],
            attenuation_distance: f32::INFINITY,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: 0.5,
            double_sided: false,
            unlit: false,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            sheen_color: [0.0; 3],
            sheen_roughness: 0.0,
            iridescence: 0.0,
            iridescence_ior: 1.3,
            iridescence_thickness: [100.0, 400.0],
            anisotropy_strength: 0.0,
            anisotropy_rotation: 0.0,
            diffuse_transmission: 0.0,
            diffuse_transmission_color: [1.0; 3],
            thickness: 0.0,
            dispersion: 0.0,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            occlusion_texture: None,
            emissive_texture: None,
            specular_texture: None,
            specular_color_texture: None,
            transmission_texture: None,
            clearcoat_texture: None,
            clearcoat_roughness_texture: None,
            clearcoat_normal_texture: None,
            iridescence_texture: None,
            iridescence_thickness_texture: None,
            anisotropy_texture: None,
            sheen_color_texture: None,
            sheen_roughness_texture: None,
            diffuse_transmission_texture: None,
            diffuse_transmission_color_texture: None,
            thickness_texture: None,
            parallax: None,
        }
    }
}

impl Material {
    /// Converts a glTF material, registering the textures it uses in `textures`.
    pub(super) fn from_gltf(material: &gltf::Material, textures: &mut TextureSet) -> Self {
        let pbr = material.pbr_metallic_roughness();
        let mut info = |info: Option<gltf::texture::Info>, srgb: bool| {
            info.map(|info| {
                let transform = info.texture_transform();
                let tex_coord = transform.as_ref().and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
                TextureRef {
                    texture: textures.index_of(&info.texture(), srgb),
                    tex_coord,
                    transform: transform.map_or(IDENTITY_TRANSFORM, |t| {
                        texture_transform(t.offset(), t.rotation(), t.scale())
                    }),
                    scale: 1.0,
                }
            })
        };
        let base_color_texture = info(pbr.base_color_texture(), true);
        let metallic_roughness_texture = info(pbr.metallic_roughness_texture(), false);
        let emissive_texture = info(material.emissive_texture(), true);
        let specular = material.specular();
        let specular_texture = info(specular.as_ref().and_then(|s| s.specular_texture()), false);
        let specular_color_texture = info(specular.as_ref().and_then(|s| s.specular_color_texture()), true);
        let transmission = material.transmission();
        let transmission_texture = info(transmission.as_ref().and_then(|t| t.transmission_texture()), false);
        let thickness_texture = info(material.volume().and_then(|v| v.thickness_texture()), false);
        // Normal and occlusion textures are their own glTF types (with a scale or a strength), so
        // their KHR_texture_transform is read from the raw extension value.
        let mut raw_ref = |texture: gltf::Texture, tex_coord: u32, transform: Option<&Value>, scale: f32| {
            let (tex_coord, transform) = raw_transform(transform, tex_coord);
            TextureRef { texture: textures.index_of(&texture, false), tex_coord, transform, scale }
        };
        let normal_texture = material.normal_texture().map(|t| {
            raw_ref(t.texture(), t.tex_coord(), t.extension_value("KHR_texture_transform"), t.scale())
        });
        let occlusion_texture = material.occlusion_texture().map(|t| {
            raw_ref(t.texture(), t.tex_coord(), t.extension_value("KHR_texture_transform"), t.strength())
        });
        let strength = material.emissive_strength().unwrap_or(1.0);
        let clearcoat = material.extension_value("KHR_materials_clearcoat");
        // In [0, 1]: ranges.rs refuses a file with other values.
        let coat_number =
            |key: &str| clearcoat.and_then(|c| c.get(key)).and_then(Value::as_f64).map_or(0.0, |x| x as f32);
        let sheen = material.extension_value("KHR_materials_sheen");
        // In [0, 1]: ranges.rs refuses a file with other values.
        let sheen_roughness = sheen
            .and_then(|c| c.get("sheenRoughnessFactor"))
            .and_then(Value::as_f64)
            .map_or(0.0, |x| x as f32);
        let mut sheen_color = [0.0f32; 3];
        if let Some(Value::Array(c)) = sheen.and_then(|c| c.get("sheenColorFactor")) {
            for (out, v) in sheen_color.iter_mut().zip(c) {
                *out = v.as_f64().unwrap_or(0.0) as f32;
            }
        }
        let through = material.extension_value("KHR_materials_diffuse_transmission");
        // In [0, 1]: ranges.rs refuses a file with other values.
        let through_number =
            |key: &str| through.and_then(|t| t.get(key)).and_then(Value::as_f64).map_or(0.0, |x| x as f32);
        let mut diffuse_transmission_color = [1.0f32; 3];
        if let Some(Value::Array(c)) = through.and_then(|t| t.get("diffuseTransmissionColorFactor")) {
            for (out, v) in diffuse_transmission_color.iter_mut().zip(c) {
                *out = v.as_f64().unwrap_or(1.0) as f32;
            }
        }
        let film = material.extension_value("KHR_materials_iridescence");
        // In range: ranges.rs refuses a file with other values.
        let film_number = |key: &str, default: f32| {
            film.and_then(|c| c.get(key)).and_then(Value::as_f64).map_or(default, |x| x as f32)
        };
        let film_default = Self::default();
        let anisotropy = material.extension_value("KHR_materials_anisotropy");
        // Strength in [0, 1], rotation finite: ranges.rs refuses a file with other values.
        let anisotropy_number =
            |key: &str| anisotropy.and_then(|a| a.get(key)).and_then(Value::as_f64).map_or(0.0, |x| x as f32);
        Self {
            name: material.name().unwrap_or_default().to_owned(),
            base_color_factor: pbr.base_color_factor(),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            emissive: material.emissive_factor().map(|e| e * strength),
            ior: material.ior().unwrap_or(1.5),
            specular_factor: specular.as_ref().map_or(1.0, |s| s.specular_factor()),
            specular_color_factor: specular.as_ref().map_or([1.0; 3], |s| s.specular_color_factor()),
            transmission_factor: transmission.as_ref().map_or(0.0, |t| t.transmission_factor()),
            volume: material.volume().is_some_and(|v| v.thickness_factor() > 0.0),
            attenuation_color: material.volume().map_or([1.0; 3], |v| v.attenuation_color()),
            attenuation_distance: material.volume().map_or(f32::INFINITY, |v| v.attenuation_distance()),
            alpha_mode: match material.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha_cutoff: material.alpha_cutoff().unwrap_or(0.5),
            double_sided: material.double_sided(),
            unlit: material.unlit(),
            clearcoat: coat_number("clearcoatFactor"),
            clearcoat_roughness: coat_number("clearcoatRoughnessFactor"),
            sheen_color,
            sheen_roughness,
            iridescence: film_number("iridescenceFactor", film_default.iridescence),
            iridescence_ior: film_number("iridescenceIor", film_default.iridescence_ior),
            iridescence_thickness: [
                film_number("iridescenceThicknessMinimum", film_default.iridescence_thickness[0]),
                film_number("iridescenceThicknessMaximum", film_default.iridescence_thickness[1]),
            ],
            anisotropy_strength: anisotropy_number("anisotropyStrength"),
            anisotropy_rotation: anisotropy_number("anisotropyRotation"),
            diffuse_transmission: through_number("diffuseTransmissionFactor"),
            diffuse_transmission_color,
            thickness: material.volume().map_or(0.0, |v| v.thickness_factor()),
            // At least 0: ranges.rs refuses a file with other values.
            dispersion: material
                .extension_value("KHR_materials_dispersion")
                .and_then(|d| d.get("dispersion"))
                .and_then(Value::as_f64)
                .map_or(0.0, |x| x as f32),
            base_color_texture,
            metallic_roughness_texture,
            normal_texture,
            occlusion_texture,
            emissive_texture,
            specular_texture,
            specular_color_texture,
            transmission_texture,
            // Read with the file's texture list (read_extension_textures).
            clearcoat_texture: None,
            clearcoat_roughness_texture: None,
            clearcoat_normal_texture: None,
            iridescence_texture: None,
            iridescence_thickness_texture: None,
            anisotropy_texture: None,
            sheen_color_texture: None,
            sheen_roughness_texture: None,
            diffuse_transmission_texture: None,
            diffuse_transmission_color_texture: None,
            thickness_texture,
            parallax: None,
        }
    }

    /// Whether the material is anisotropic (`KHR_materials_anisotropy` with a strength above 0):
    /// its primitives need tangents, as a normal map's do.
    pub fn anisotropic(&self) -> bool {
        self.anisotropy_strength > 0.0
    }

    /// Reads the textures of the extensions the `gltf` crate leaves as raw JSON
    /// (`KHR_materials_clearcoat`'s three, `KHR_materials_iridescence`'s two,
    /// `KHR_materials_anisotropy`'s, `KHR_materials_sheen`'s two,
    /// `KHR_materials_diffuse_transmission`'s two), registering them in `textures`. Errors say which
    /// texture reference is wrong; the caller names the file and the material.
    pub(super) fn read_extension_textures(
        &mut self,
        material: &gltf::Material,
        document: &gltf::Document,
        textures: &mut TextureSet,
    ) -> std::result::Result<(), String> {
        if let Some(coat) = material.extension_value("KHR_materials_clearcoat") {
            let mut read = |key: &str| {
                let element = format!("KHR_materials_clearcoat.{key}");
                coat.get(key).map(|info| raw_texture_ref(info, &element, document, textures)).transpose()
            };
            self.clearcoat_texture = read("clearcoatTexture")?;
            self.clearcoat_roughness_texture = read("clearcoatRoughnessTexture")?;
            self.clearcoat_normal_texture = read("clearcoatNormalTexture")?;
        }
        if let Some(film) = material.extension_value("KHR_materials_iridescence") {
            let mut read = |key: &str| {
                let element = format!("KHR_materials_iridescence.{key}");
                film.get(key).map(|info| raw_texture_ref(info, &element, document, textures)).transpose()
            };
            self.iridescence_texture = read("iridescenceTexture")?;
            self.iridescence_thickness_texture = read("iridescenceThicknessTexture")?;
        }
        if let Some(info) =
            material.extension_value("KHR_materials_anisotropy").and_then(|a| a.get("anisotropyTexture"))
        {
            let element = "KHR_materials_anisotropy.anisotropyTexture";
            self.anisotropy_texture = Some(raw_texture_ref(info, element, document, textures)?);
        }
        if let Some(sheen) = material.extension_value("KHR_materials_sheen") {
            let mut read = |key: &str, srgb: bool| {
                let element = format!("KHR_materials_sheen.{key}");
                sheen
                    .get(key)
                    .map(|info| raw_texture_ref_as(info, &element, document, textures, srgb))
                    .transpose()
            };
            self.sheen_color_texture = read("sheenColorTexture", true)?;
            self.sheen_roughness_texture = read("sheenRoughnessTexture", false)?;
        }
        if let Some(through) = material.extension_value("KHR_materials_diffuse_transmission") {
            let mut read = |key: &str, srgb: bool| {
                let element = format!("KHR_materials_diffuse_transmission.{key}");
                through
                    .get(key)
                    .map(|info| raw_texture_ref_as(info, &element, document, textures, srgb))
                    .transpose()
            };
            self.diffuse_transmission_texture = read("diffuseTransmissionTexture", false)?;
            self.diffuse_transmission_color_texture = read("diffuseTransmissionColorTexture", true)?;
        }
        Ok(())
    }
}

/// A `textureInfo` (or `normalTextureInfo`) in raw JSON, named `element` in errors: its texture
/// (the index checked against the file's textures; linear texels), its UV set and
/// `KHR_texture_transform`, and its `scale` (a normal texture's; 1 without one).
fn raw_texture_ref(
    info: &Value,
    element: &str,
    document: &gltf::Document,
    textures: &mut TextureSet,
) -> std::result::Result<TextureRef, String> {
    raw_texture_ref_as(info, element, document, textures, false)
}

/// [`raw_texture_ref`] of a texture whose texels are sRGB-encoded where `srgb` (a colour).
fn raw_texture_ref_as(
    info: &Value,
    element: &str,
    document: &gltf::Document,
    textures: &mut TextureSet,
    srgb: bool,
) -> std::result::Result<TextureRef, String> {
    let count = document.textures().len();
    let index = info
        .get("index")
        .ok_or(format!("{element}.index is missing"))?
        .as_u64()
        .ok_or(format!("{element}.index must be a non-negative integer"))?;
    let texture = document
        .textures()
        .nth(index as usize)
        .ok_or(format!("{element}.index is {index}, but the file has {count} texture(s)"))?;
    let tex_coord = match info.get("texCoord") {
        None => 0,
        Some(t) => {
            t.as_u64().ok_or(format!("{element}.texCoord must be a non-negative integer, not {t}"))? as u32
        }
    };
    let transform = info.get("extensions").and_then(|e| e.get("KHR_texture_transform"));
    let (tex_coord, transform) = raw_transform(transform, tex_coord);
    let scale = info.get("scale").and_then(Value::as_f64).map_or(1.0, |s| s as f32);
    Ok(TextureRef { texture: textures.index_of(&texture, srgb), tex_coord, transform, scale })
}

/// `KHR_texture_transform` read from raw JSON (the `gltf` crate parses it only on plain texture
/// infos, not on normal and occlusion textures): the UV set and the matrix.
fn raw_transform(value: Option<&Value>, tex_coord: u32) -> (u32, [[f32; 3]; 2]) {
    let Some(value) = value else { return (tex_coord, IDENTITY_TRANSFORM) };
    let pair = |key: &str, default: [f32; 2]| {
        let array = value.get(key).and_then(Value::as_array);
        let at = |i: usize| array.and_then(|a| a.get(i)).and_then(Value::as_f64).map(|x| x as f32);
        [at(0).unwrap_or(default[0]), at(1).unwrap_or(default[1])]
    };
    let rotation = value.get("rotation").and_then(Value::as_f64).unwrap_or(0.0) as f32;
    let tex_coord = value.get("texCoord").and_then(Value::as_u64).map_or(tex_coord, |t| t as u32);
    (tex_coord, texture_transform(pair("offset", [0.0, 0.0]), rotation, pair("scale", [1.0, 1.0])))
}

/// Reads `UMBRA_implicit` on a glTF material (its `parallax` object; docs/gltf.md "Parallax occlusion
/// mapping", docs/UMBRA_implicit.schema.json), registering the height map in `textures`. Errors
/// say what is wrong and where in the object; the caller names the file and the material.
pub(super) fn parse_parallax(
    value: &Value,
    document: &gltf::Document,
    textures: &mut TextureSet,
) -> std::result::Result<Option<Parallax>, String> {
    let object = value.as_object().ok_or("must be an object")?;
    if let Some(key) = object.keys().find(|k| k.as_str() != "parallax") {
        return Err(format!("unknown property '{key}' (a material's UMBRA_implicit has only 'parallax')"));
    }
    let Some(parallax) = object.get("parallax") else { return Ok(None) };
    let parallax = parallax.as_object().ok_or("parallax must be an object")?;
    const KEYS: [&str; 4] = ["heightTexture", "scale", "layers", "refinement"];
    if let Some(key) = parallax.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(format!("unknown property 'parallax.{key}' (expected one of {})", KEYS.join(", ")));
    }
    let info = parallax.get("heightTexture").ok_or("parallax.heightTexture is missing")?;
    let info = info.as_object().ok_or("parallax.heightTexture must be an object")?;
    let count = document.textures().len();
    let index = info
        .get("index")
        .ok_or("parallax.heightTexture.index is missing")?
        .as_u64()
        .ok_or("parallax.heightTexture.index must be a non-negative integer")?;
    let texture = document
        .textures()
        .nth(index as usize)
        .ok_or(format!("parallax.heightTexture.index is {index}, but the file has {count} texture(s)"))?;
    let tex_coord = match info.get("texCoord") {
        None => 0,
        Some(t) => match t.as_u64() {
            Some(t @ (0 | 1)) => t as u32,
            _ => {
                return Err(format!(
                    "parallax.heightTexture.texCoord must be 0 or 1 (umbra reads two UV sets), not {t}"
                ))
            }
        },
    };
    let transform = info.get("extensions").and_then(|e| e.get("KHR_texture_transform"));
    let (tex_coord, transform) = raw_transform(transform, tex_coord);
    let scale = match parallax.get("scale").ok_or("parallax.scale is missing")?.as_f64() {
        Some(s) if s.is_finite() && s > 0.0 && (s as f32).is_finite() => s as f32,
        _ => return Err("parallax.scale must be a finite number above 0 (world units)".into()),
    };
    let count = |key: &str, default: u32, lo: u32, hi: u32| -> std::result::Result<u32, String> {
        let Some(v) = parallax.get(key) else { return Ok(default) };
        match v.as_u64() {
            Some(n) if n >= u64::from(lo) && n <= u64::from(hi) => Ok(n as u32),
            _ => Err(format!("parallax.{key} must be an integer from {lo} to {hi}, not {v}")),
        }
    };
    let layers = count("layers", Parallax::DEFAULT_LAYERS, 1, Parallax::MAX_LAYERS)?;
    let refinement = count("refinement", Parallax::DEFAULT_REFINEMENT, 0, Parallax::MAX_REFINEMENT)?;
    let height = TextureRef { texture: textures.index_of(&texture, false), tex_coord, transform, scale: 1.0 };
    Ok(Some(Parallax { height, scale, layers, refinement }))
}
