//! Textures: decoded RGBA8 images with their sampler and colour space.
//!
//! A glTF texture is an image plus a sampler; its colour space comes from how a material uses it
//! (base colour, emissive and specular colour are sRGB, all other maps linear). umbra makes one
//! [`Texture`] per distinct (image, sampler, colour space) a material uses, and decodes each image
//! once, however many textures share it.

use super::source::{self, Asset, Origin};
use crate::error::Result;
use gltf::texture::{MagFilter, MinFilter, WrappingMode};
use rayon::prelude::*;
use std::collections::HashMap;

/// How texture coordinates outside [0, 1] wrap.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    /// Tile (the glTF default).
    Repeat,
    /// Clamp to the edge texel.
    ClampToEdge,
    /// Tile, mirroring every other copy.
    MirroredRepeat,
}

/// Texel filtering.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Filter {
    /// The nearest texel.
    Nearest,
    /// Bilinear.
    Linear,
}

/// How a texture is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Wrapping of u.
    pub wrap_s: Wrap,
    /// Wrapping of v.
    pub wrap_t: Wrap,
    /// Filter when magnified.
    pub mag_filter: Filter,
    /// Filter within a mip level when minified.
    pub min_filter: Filter,
    /// Whether minification uses mipmaps (the glTF minification filter is a mipmap mode, or is
    /// left to the renderer).
    pub mipmaps: bool,
}

impl Default for Sampler {
    /// glTF's default sampler: repeat, linear, mipmapped.
    fn default() -> Self {
        Self {
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            mag_filter: Filter::Linear,
            min_filter: Filter::Linear,
            mipmaps: true,
        }
    }
}

impl Sampler {
    fn from_gltf(sampler: &gltf::texture::Sampler) -> Self {
        let wrap = |mode| match mode {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let min = sampler.min_filter();
        Self {
            wrap_s: wrap(sampler.wrap_s()),
            wrap_t: wrap(sampler.wrap_t()),
            mag_filter: match sampler.mag_filter() {
                Some(MagFilter::Nearest) => Filter::Nearest,
                _ => Filter::Linear,
            },
            min_filter: match min {
                Some(
                    MinFilter::Nearest | MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear,
                ) => Filter::Nearest,
                _ => Filter::Linear,
            },
            mipmaps: !matches!(min, Some(MinFilter::Nearest | MinFilter::Linear)),
        }
    }
}

/// A decoded texture, ready for upload.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The image's name, file name, or "image N".
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, RGBA8, rows top to bottom (`width * height * 4` bytes).
    pub rgba8: Vec<u8>,
    /// Whether the texels are sRGB-encoded colour (to be linearised when sampled).
    pub srgb: bool,
    /// How to sample it.
    pub sampler: Sampler,
}

impl Texture {
    /// Mean linear luminance (Rec. 709) of the RGB texels, decoding sRGB first when `srgb`.
    pub fn mean_luminance(&self) -> f32 {
        let decode: [f32; 256] = std::array::from_fn(|v| {
            let c = v as f32 / 255.0;
            if self.srgb {
                srgb_to_linear(c)
            } else {
                c
            }
        });
        let texels = self.rgba8.chunks_exact(4);
        let count = texels.len().max(1);
        let sum: f64 = texels
            .map(|p| {
                f64::from(luminance([decode[p[0] as usize], decode[p[1] as usize], decode[p[2] as usize]]))
            })
            .sum();
        (sum / count as f64) as f32
    }
}

/// Rec. 709 luminance of linear RGB.
pub(super) fn luminance([r, g, b]: [f32; 3]) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// The sRGB transfer function, inverted.
fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// One texture a material uses: which image, sampled how, in which colour space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Use {
    image: usize,
    sampler: Sampler,
    srgb: bool,
}

/// Collects the textures materials use (giving each its index in [`super::Scene::textures`]),
/// then decodes them.
#[derive(Default)]
pub(super) struct TextureSet {
    uses: Vec<Use>,
    index: HashMap<Use, u32>,
}

impl TextureSet {
    /// The scene texture index for `texture` used in the given colour space.
    pub fn index_of(&mut self, texture: &gltf::Texture, srgb: bool) -> u32 {
        let key =
            Use { image: texture.source().index(), sampler: Sampler::from_gltf(&texture.sampler()), srgb };
        *self.index.entry(key).or_insert_with(|| {
            self.uses.push(key);
            self.uses.len() as u32 - 1
        })
    }

    /// Decodes every image in use (each once, in parallel) into the scene's textures.
    pub fn decode(self, origin: &Origin, asset: &Asset) -> Result<Vec<super::Texture>> {
        let mut images: Vec<usize> = self.uses.iter().map(|u| u.image).collect();
        images.sort_unstable();
        images.dedup();
        let decoded: HashMap<usize, Decoded> = images
            .par_iter()
            .map(|&image| decode_image(origin, asset, image).map(|d| (image, d)))
            .collect::<Result<_>>()?;
        Ok(self
            .uses
            .iter()
            .map(|u| {
                let image = &decoded[&u.image];
                Texture {
                    name: image.name.clone(),
                    width: image.width,
                    height: image.height,
                    rgba8: image.rgba8.clone(),
                    srgb: u.srgb,
                    sampler: u.sampler,
                }
            })
            .collect())
    }
}

/// A decoded image.
struct Decoded {
    name: String,
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// Reads and decodes image `index` (PNG or JPEG) to RGBA8.
fn decode_image(origin: &Origin, asset: &Asset, index: usize) -> Result<Decoded> {
    let (bytes, description) = source::image_bytes(origin, asset, index)?;
    let image = image::load_from_memory(&bytes)
        .map_err(|e| origin.error(format!("{description}: cannot decode the image: {e}")))?
        .to_rgba8();
    let json = &asset.document.as_json().images[index];
    let name = match (&json.name, &json.uri) {
        (Some(name), _) => name.clone(),
        (None, Some(uri)) if !uri.starts_with("data:") => uri.clone(),
        _ => format!("image {index}"),
    };
    Ok(Decoded { name, width: image.width(), height: image.height(), rgba8: image.into_raw() })
}
