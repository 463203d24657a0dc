//! Equirectangular environment maps (OpenEXR or Radiance HDR) and the piecewise-constant 2D
//! distribution that importance-samples them by luminance × sin θ.
//!
//! Convention (as `spirv/include/environment.glsl`): +Y is up; a direction d maps to
//! u = atan2(d.x, −d.z) / 2π + ½ and v = acos(d.y) / π, row 0 at the top (v = 0, straight up).

use crate::error::{Error, Result};
use std::path::Path;

/// A linear RGB equirectangular map.
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    /// Where it came from.
    pub name: String,
    /// Width (u, longitude).
    pub width: usize,
    /// Height (v, latitude).
    pub height: usize,
    /// Row-major texels, top row first.
    pub texels: Vec<[f32; 3]>,
}

/// The sampling tables of a map.
#[derive(Clone, Debug)]
pub struct EnvironmentDistribution {
    /// Per texel: the density over the unit (u, v) square of picking a point in it.
    pub pdf_uv: Vec<f32>,
    /// Inclusive CDF over rows (length `height`, last = 1).
    pub marginal_cdf: Vec<f32>,
    /// Inclusive CDF over each row's texels (row-major, each row ending at 1).
    pub conditional_cdf: Vec<f32>,
    /// The map's mean luminance over the sphere of directions (each texel weighted by its solid
    /// angle, ∝ sin θ).
    pub mean_luminance: f32,
}

/// The largest map umbra loads (texels); larger ones are refused with a clear error.
pub const MAX_TEXELS: usize = 8192 * 4096;

impl EnvironmentMap {
    /// Loads an EXR (any compression the `exr` crate reads, DWAB included) or a Radiance `.hdr`.
    /// NaN, infinite and negative texels are replaced by 0 with one warning that counts them.
    pub fn load(path: &Path) -> Result<Self> {
        let bad = |message: String| Error::Scene { path: path.to_path_buf(), message };
        let is_exr = std::fs::read(path)
            .map_err(|source| Error::Io { path: path.to_path_buf(), source })?
            .starts_with(&[0x76, 0x2f, 0x31, 0x01]);
        let (width, height, texels) = if is_exr {
            let (w, h, channels) = crate::output::read_exr_channels(path)?;
            let find = |n: &str| channels.iter().find(|c| c.0 == n).map(|c| &c.1);
            let (Some(r), Some(g), Some(b)) = (find("R"), find("G"), find("B")) else {
                let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
                return Err(bad(format!("an environment EXR needs R, G and B channels; it has {names:?}")));
            };
            (w, h, (0..w * h).map(|i| [r[i], g[i], b[i]]).collect::<Vec<_>>())
        } else {
            let decoded = image::ImageReader::open(path)
                .map_err(|source| Error::Io { path: path.to_path_buf(), source })?
                .with_guessed_format()
                .map_err(|source| Error::Io { path: path.to_path_buf(), source })?
                .decode()
                .map_err(|e| bad(format!("not a readable EXR or Radiance HDR image: {e}")))?
                .into_rgb32f();
            let (w, h) = (decoded.width() as usize, decoded.height() as usize);
            (w, h, decoded.pixels().map(|p| p.0).collect())
        };
        Self::from_texels(&path.display().to_string(), width, height, texels)
    }

    /// A map from texels, sanitised as [`Self::load`] does.
    pub fn from_texels(name: &str, width: usize, height: usize, mut texels: Vec<[f32; 3]>) -> Result<Self> {
        if width == 0 || height == 0 || width * height > MAX_TEXELS || texels.len() != width * height {
            return Err(Error::Scene {
                path: name.into(),
                message: format!(
                    "environment map of {width}×{height} with {} texels: needs 1 to {MAX_TEXELS} texels",
                    texels.len()
                ),
            });
        }
        let mut fixed = 0;
        for t in texels.iter_mut().flatten() {
            if !(t.is_finite() && *t >= 0.0) {
                *t = 0.0;
                fixed += 1;
            }
        }
        if fixed > 0 {
            log::warn!("{name}: {fixed} NaN, infinite or negative texel values set to 0");
        }
        Ok(Self { name: name.into(), width, height, texels })
    }

    /// A stable 64-bit hash of the map's size and texels (not its name), as
    /// [`crate::scene::Scene::content_hash`] is of a scene.
    pub fn content_hash(&self) -> u64 {
        let mut h = crate::scene::ContentHasher::new();
        h.str("umbra environment 1");
        h.len(self.width);
        h.len(self.height);
        h.f32s(self.texels.as_flattened());
        h.finish()
    }

    /// A constant map (one texel).
    pub fn constant(rgb: [f32; 3]) -> Self {
        Self { name: "constant".into(), width: 1, height: 1, texels: vec![rgb] }
    }

    /// The importance-sampling tables: density ∝ luminance × sin θ (uniform where all is black).
    pub fn distribution(&self) -> EnvironmentDistribution {
        let (w, h) = (self.width, self.height);
        let weight: Vec<f64> = (0..w * h)
            .map(|i| {
                let [r, g, b] = self.texels[i];
                let theta = std::f64::consts::PI * ((i / w) as f64 + 0.5) / h as f64;
                (0.2126 * r as f64 + 0.7152 * g as f64 + 0.0722 * b as f64) * theta.sin()
            })
            .collect();
        let total: f64 = weight.iter().sum();
        let solid_angle: f64 =
            (0..h).map(|y| (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin()).sum::<f64>()
                * w as f64;
        let mean_luminance = if solid_angle > 0.0 { (total / solid_angle) as f32 } else { 0.0 };
        let weight = if total > 0.0 { weight } else { vec![1.0; w * h] };
        let total: f64 = if total > 0.0 { total } else { (w * h) as f64 };
        let mut conditional_cdf = vec![0.0f32; w * h];
        let mut marginal_cdf = vec![0.0f32; h];
        let mut running_rows = 0.0;
        for y in 0..h {
            let row = &weight[y * w..(y + 1) * w];
            let row_sum: f64 = row.iter().sum();
            let mut running = 0.0;
            for (x, &v) in row.iter().enumerate() {
                running += if row_sum > 0.0 { v } else { 1.0 };
                conditional_cdf[y * w + x] =
                    (running / if row_sum > 0.0 { row_sum } else { w as f64 }) as f32;
            }
            conditional_cdf[y * w + w - 1] = 1.0;
            running_rows += row_sum;
            marginal_cdf[y] = (running_rows / total) as f32;
        }
        marginal_cdf[h - 1] = 1.0;
        let pdf_uv = weight.iter().map(|&v| (v / total * (w * h) as f64) as f32).collect();
        EnvironmentDistribution { pdf_uv, marginal_cdf, conditional_cdf, mean_luminance }
    }
}
