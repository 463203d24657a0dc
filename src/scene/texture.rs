//! Textures: decoded RGBA8 images with their sampler and colour space.
//!
//! A glTF texture is an image plus a sampler; its colour space comes from how a material uses it
//! (base colour, emissive and specular colour are sRGB, all other maps linear). umbra makes one
//! [`Texture`] per distinct (image, sampler, colour space) a material uses, and decodes each image
//! once, however many textures share it.

use super::source::{self, Asset, Origin};
use super::MissingTextures;
use crate::color::{luminance, srgb_decode, srgb_encode};
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
    /// Between mip levels when `mipmaps`: `Linear` blends the two nearest levels (trilinear with
    /// a linear `min_filter`), `Nearest` takes the nearest level (glTF `*_MIPMAP_NEAREST`).
    pub mipmap_filter: Filter,
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
            mipmap_filter: Filter::Linear,
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
            mipmap_filter: match min {
                Some(MinFilter::NearestMipmapNearest | MinFilter::LinearMipmapNearest) => Filter::Nearest,
                _ => Filter::Linear,
            },
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
    /// Adds the size, colour space, sampler and texels (not the name) to a content hash
    /// ([`super::Scene::content_hash`]).
    pub(super) fn hash_into(&self, h: &mut super::ContentHasher) {
        let Texture { name: _, width, height, rgba8, srgb, sampler } = self;
        let Sampler { wrap_s, wrap_t, mag_filter, min_filter, mipmaps, mipmap_filter } = sampler;
        h.u32s(&[*width, *height]);
        h.bool(*srgb);
        for wrap in [wrap_s, wrap_t] {
            h.u32(match wrap {
                Wrap::Repeat => 0,
                Wrap::ClampToEdge => 1,
                Wrap::MirroredRepeat => 2,
            });
        }
        for filter in [mag_filter, min_filter, mipmap_filter] {
            h.u32(match filter {
                Filter::Nearest => 0,
                Filter::Linear => 1,
            });
        }
        h.bool(*mipmaps);
        h.bytes(rgba8);
    }

    /// Linear luminance (Rec. 709) of each texel's RGB, row by row, decoding sRGB first when
    /// `srgb`.
    pub fn luminances(&self) -> Vec<f32> {
        let decode: [f32; 256] = std::array::from_fn(|v| {
            let c = v as f32 / 255.0;
            if self.srgb {
                srgb_decode(c)
            } else {
                c
            }
        });
        self.rgba8
            .chunks_exact(4)
            .map(|p| luminance([decode[p[0] as usize], decode[p[1] as usize], decode[p[2] as usize]]))
            .collect()
    }
}

/// One level of a texture's mip chain, RGBA8 like the texture.
#[derive(Clone, Debug, PartialEq)]
pub struct MipLevel {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texels, RGBA8, rows top to bottom.
    pub rgba8: Vec<u8>,
}

/// The number of levels of a full mip chain of a `width` × `height` texture, level 0 included:
/// each level halves both sizes (rounding down, at least 1) down to 1 × 1.
pub fn mip_level_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

impl Texture {
    /// The mip chain below level 0: levels 1 to [`mip_level_count`] − 1, each of size
    /// `max(1, size >> k)`. Each level is the area-weighted box filter of the level above (a 2 × 2
    /// box for even sizes; for an odd size each new texel covers 2.5 texels, the middle one shared
    /// by halves), so every level keeps the texture's mean. Filtering happens in linear space: sRGB
    /// colour is decoded, averaged and re-encoded (alpha is always linear); levels are computed
    /// from the unquantised level above and rounded to 8 bits once. Empty when `rgba8` does not
    /// hold `width × height` texels.
    pub fn mip_chain(&self) -> Vec<MipLevel> {
        if self.rgba8.len() as u64 != u64::from(self.width) * u64::from(self.height) * 4 {
            return Vec::new();
        }
        let decode: [f32; 256] = std::array::from_fn(|v| {
            let c = v as f32 / 255.0;
            if self.srgb {
                srgb_decode(c)
            } else {
                c
            }
        });
        // Level 0 is read through the decoding table where it is needed, not decoded into a
        // float copy first: that copy is 16 bytes a texel (64 MB for a 2048² texture), and fresh
        // memory costs a page fault per 4 KiB. `level` holds the unquantised level above from
        // level 1 on.
        let texel0 = |i: usize| {
            let p = &self.rgba8[4 * i..4 * i + 4];
            [decode[p[0] as usize], decode[p[1] as usize], decode[p[2] as usize], p[3] as f32 / 255.0]
        };
        let mut level: Vec<[f32; 4]> = Vec::new();
        let (mut w, mut h) = (self.width.max(1), self.height.max(1));
        let mut chain = Vec::new();
        for _ in 1..mip_level_count(w, h) {
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let (wx, wy) = (box_weights(w, nw), box_weights(h, nh));
            let mut next = vec![[0.0f32; 4]; (nw * nh) as usize];
            for (y, row_weights) in wy.iter().enumerate() {
                for (x, col_weights) in wx.iter().enumerate() {
                    let mut sum = [0.0f32; 4];
                    for &(sy, ky) in row_weights {
                        for &(sx, kx) in col_weights {
                            let i = (sy * w + sx) as usize;
                            let t = if chain.is_empty() { texel0(i) } else { level[i] };
                            for c in 0..4 {
                                sum[c] += ky * kx * t[c];
                            }
                        }
                    }
                    next[y * nw as usize + x] = sum;
                }
            }
            let rgba8 = next
                .iter()
                .flat_map(|t| {
                    let colour = |c: f32| if self.srgb { srgb_encode(c) } else { c };
                    [colour(t[0]), colour(t[1]), colour(t[2]), t[3]]
                        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
                })
                .collect();
            chain.push(MipLevel { width: nw, height: nh, rgba8 });
            (level, w, h) = (next, nw, nh);
        }
        chain
    }
}

/// For each of the `dst` texels along an axis, the `src` texels it covers and their weights
/// (overlap of [i·src/dst, (i+1)·src/dst) with each source texel, normalised).
fn box_weights(src: u32, dst: u32) -> Vec<Vec<(u32, f32)>> {
    (0..dst)
        .map(|i| {
            let (lo, hi) = (
                f64::from(i) * f64::from(src) / f64::from(dst),
                f64::from(i + 1) * f64::from(src) / f64::from(dst),
            );
            (lo.floor() as u32..(hi.ceil() as u32).min(src))
                .map(|j| {
                    let overlap = hi.min(f64::from(j + 1)) - lo.max(f64::from(j));
                    (j, (overlap / (hi - lo)) as f32)
                })
                .filter(|&(_, k)| k > 0.0)
                .collect()
        })
        .collect()
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

    /// Decodes every image in use (each once, in parallel) into the scene's textures. An image
    /// that cannot be read or decoded is an error, or with [`MissingTextures::Warn`] a warning
    /// (logged, and returned once per image) and a 1×1 white stand-in whose uses are returned so
    /// the materials can drop them.
    pub fn decode(
        self,
        origin: &Origin,
        asset: &Asset,
        missing: MissingTextures,
    ) -> Result<(Vec<super::Texture>, Vec<u32>, Vec<String>)> {
        let mut images: Vec<usize> = self.uses.iter().map(|u| u.image).collect();
        images.sort_unstable();
        images.dedup();
        let results: Vec<(usize, Result<Decoded>)> =
            images.par_iter().map(|&image| (image, decode_image(origin, asset, image))).collect();
        let mut decoded = HashMap::new();
        let mut warnings = Vec::new();
        for (image, result) in results {
            match (result, missing) {
                (Ok(d), _) => {
                    decoded.insert(image, d);
                }
                (Err(e), MissingTextures::Error) => return Err(e),
                (Err(e), MissingTextures::Warn) => {
                    let warning = format!("{e}; its texture slots use the material's factors alone");
                    log::warn!("{warning}");
                    warnings.push(warning);
                }
            }
        }
        let failed = (0..self.uses.len() as u32)
            .filter(|&i| !decoded.contains_key(&self.uses[i as usize].image))
            .collect();
        let white = Decoded { name: "missing".into(), width: 1, height: 1, rgba8: vec![255; 4] };
        // An image's last use takes its texels; earlier uses (other samplers or colour spaces)
        // copy them.
        let mut uses_left: HashMap<usize, usize> = HashMap::new();
        for u in &self.uses {
            *uses_left.entry(u.image).or_default() += 1;
        }
        let textures = self
            .uses
            .iter()
            .map(|u| {
                let left = uses_left.get_mut(&u.image).expect("counted above");
                *left -= 1;
                let (name, width, height, rgba8) = match (*left, decoded.get(&u.image)) {
                    (_, None) => (white.name.clone(), white.width, white.height, white.rgba8.clone()),
                    (0, Some(_)) => {
                        let image = decoded.remove(&u.image).expect("present");
                        (image.name, image.width, image.height, image.rgba8)
                    }
                    (_, Some(image)) => (image.name.clone(), image.width, image.height, image.rgba8.clone()),
                };
                Texture { name, width, height, rgba8, srgb: u.srgb, sampler: u.sampler }
            })
            .collect();
        Ok((textures, failed, warnings))
    }
}

/// A decoded image.
struct Decoded {
    name: String,
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// Reads and decodes image `index` (PNG, JPEG, for `EXT_texture_webp` WebP, for
/// `KHR_texture_basisu` KTX2: told apart by content) to RGBA8.
fn decode_image(origin: &Origin, asset: &Asset, index: usize) -> Result<Decoded> {
    let (bytes, description) = source::image_bytes(origin, asset, index)?;
    let (width, height, rgba8) = if bytes.starts_with(super::ktx2::MAGIC) {
        super::ktx2::decode(&bytes).map_err(|e| origin.error(format!("{description}: KTX2: {e}")))?
    } else {
        let image = image::load_from_memory(&bytes)
            .map_err(|e| origin.error(format!("{description}: cannot decode the image: {e}")))?
            .to_rgba8();
        (image.width(), image.height(), image.into_raw())
    };
    let json = &asset.document.as_json().images[index];
    let name = match (&json.name, &json.uri) {
        (Some(name), _) => name.clone(),
        (None, Some(uri)) if !uri.starts_with("data:") => uri.clone(),
        _ => format!("image {index}"),
    };
    Ok(Decoded { name, width, height, rgba8 })
}
