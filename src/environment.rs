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
    /// Walker's alias table over the rows (length `height`), each row picked by its share of
    /// the map's weight.
    pub rows: Vec<AliasEntry>,
    /// An alias table within each row (row-major, `width` entries a row), each texel picked by
    /// its share of the row's weight (uniformly in a row of no weight, which `rows` never picks
    /// unless the whole map has none).
    pub columns: Vec<AliasEntry>,
    /// The map's mean luminance over the sphere of directions (each texel weighted by its solid
    /// angle, ∝ sin θ).
    pub mean_luminance: f32,
}

/// One entry of an alias table (Walker 1977; Vose 1991's construction): a uniform pick of entry
/// i keeps i with probability `keep` and takes `alias` otherwise, so entry i is drawn with
/// probability (keep_i + Σ over the entries j whose alias is i of (1 − keep_j)) / n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AliasEntry {
    /// The probability of keeping this entry, in [0, 1].
    pub keep: f32,
    /// The entry taken otherwise.
    pub alias: u32,
}

impl AliasEntry {
    /// The entry as an RG32UI texel: `keep`'s bits, then `alias` (`environment.glsl` reads it).
    pub fn texel(self) -> [u32; 2] {
        [self.keep.to_bits(), self.alias]
    }
}

/// The alias table drawing index i with probability `weights[i] / Σ weights`: O(1) per sample (a
/// uniform entry and one comparison), where a CDF's binary search takes log2(n) dependent reads.
/// Weights must be finite and non-negative; all zero (or none) draws uniformly.
pub fn alias_table(weights: &[f64]) -> Vec<AliasEntry> {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    if n == 0 {
        return Vec::new();
    }
    let uniform = total.is_nan() || total <= 0.0;
    // Each entry's probability times n: the table's columns hold 1 each.
    let mut scaled: Vec<f64> =
        weights.iter().map(|&w| if uniform { 1.0 } else { w / total * n as f64 }).collect();
    let mut table: Vec<AliasEntry> = (0..n as u32).map(|i| AliasEntry { keep: 1.0, alias: i }).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        table[s] = AliasEntry { keep: scaled[s] as f32, alias: l as u32 };
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left holds 1 up to rounding; an entry of no weight left over (rounding ran the
    // other list out first) must still never be drawn: it takes the heaviest entry always.
    let heaviest = || (0..n).max_by(|&a, &b| weights[a].total_cmp(&weights[b])).unwrap_or(0) as u32;
    for i in small.into_iter().chain(large) {
        table[i] = if !uniform && weights[i] <= 0.0 {
            AliasEntry { keep: 0.0, alias: heaviest() }
        } else {
            AliasEntry { keep: 1.0, alias: i as u32 }
        };
    }
    table
}

/// The probability with which `table` draws each index (for tests and checks).
pub fn alias_probabilities(table: &[AliasEntry]) -> Vec<f64> {
    let n = table.len() as f64;
    let mut p = vec![0.0; table.len()];
    for (i, e) in table.iter().enumerate() {
        p[i] += e.keep as f64 / n;
        p[e.alias as usize] += (1.0 - e.keep as f64) / n;
    }
    p
}

/// The largest map umbra loads (texels); larger ones are refused with a clear error.
pub const MAX_TEXELS: usize = 8192 * 4096;

impl EnvironmentMap {
    /// Loads an EXR (any compression the `exr` crate reads, DWAB included) or a Radiance `.hdr`.
    /// NaN, infinite and negative texels are replaced by 0 with one warning that counts them.
    pub fn load(path: &Path) -> Result<Self> {
        let bad = |message: String| Error::Scene { path: path.to_path_buf(), message };
        // Read once: the first bytes tell EXR from the rest, and either decoder takes the bytes.
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let (width, height, texels) = if bytes.starts_with(&crate::output::EXR_MAGIC) {
            let exr = crate::output::read_exr_bytes(path, &bytes)?;
            let (w, h, channels) = (exr.width, exr.height, exr.channels);
            let find = |n: &str| channels.iter().find(|c| c.0 == n).map(|c| &c.1);
            let (Some(r), Some(g), Some(b)) = (find("R"), find("G"), find("B")) else {
                let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
                return Err(bad(format!("an environment EXR needs R, G and B channels; it has {names:?}")));
            };
            (w, h, (0..w * h).map(|i| [r[i], g[i], b[i]]).collect::<Vec<_>>())
        } else {
            let decoded = image::ImageReader::new(std::io::Cursor::new(&bytes))
                .with_guessed_format()
                .map_err(|e| Error::io(path, e))?
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
        let row_sums: Vec<f64> = weight.chunks(w).map(|row| row.iter().sum()).collect();
        let rows = alias_table(&row_sums);
        let columns = weight.chunks(w).flat_map(alias_table).collect();
        let pdf_uv = weight.iter().map(|&v| (v / total * (w * h) as f64) as f32).collect();
        EnvironmentDistribution { pdf_uv, rows, columns, mean_luminance }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table draws each index with its weight's share (to f32 rounding of the keep
    /// probabilities), never one of no weight, and uniformly when every weight is 0.
    #[test]
    fn alias_table_draws_each_index_by_its_weight() {
        let cases: [&[f64]; 5] = [
            &[1.0, 2.0, 3.0, 4.0],
            &[0.0, 5.0, 0.0, 0.0, 1e-9, 3.0],
            &[7.0],
            &[0.0, 0.0, 0.0],
            &[1e30, 1.0, 1e-30, 0.0, 2.5e29, 1.0, 1.0, 1.0, 1.0],
        ];
        for weights in cases {
            let table = alias_table(weights);
            let total: f64 = weights.iter().sum();
            let p = alias_probabilities(&table);
            for (i, (&w, &pi)) in weights.iter().zip(&p).enumerate() {
                let expected = if total > 0.0 { w / total } else { 1.0 / weights.len() as f64 };
                assert!(
                    (pi - expected).abs() <= 1e-7,
                    "{weights:?}: index {i} drawn with {pi}, not {expected}"
                );
                if total > 0.0 && w == 0.0 {
                    assert_eq!(pi, 0.0, "{weights:?}: index {i} has no weight but is drawn");
                }
            }
        }
        // A map's tables: row by row and texel by texel within the row, the product is pdf_uv.
        let texels: Vec<[f32; 3]> = (0..24).map(|i| [(i % 5) as f32, (i % 3) as f32 * 0.5, 0.0]).collect();
        let map = EnvironmentMap::from_texels("test", 6, 4, texels).unwrap();
        let d = map.distribution();
        let rows = alias_probabilities(&d.rows);
        for (y, p_row) in rows.iter().enumerate() {
            let row = alias_probabilities(&d.columns[y * 6..(y + 1) * 6]);
            for (x, p_column) in row.iter().enumerate() {
                let p_uv = p_row * p_column * 24.0;
                assert!((p_uv - d.pdf_uv[y * 6 + x] as f64).abs() < 1e-5, "texel ({x}, {y}): {p_uv}");
            }
        }
    }
}
