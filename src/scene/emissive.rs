//! The emissive-triangle table: which triangles emit, with how much power, and a CDF to pick one
//! in proportion to its power (next-event estimation on the GPU walks the same arrays).

use super::{Texture, Wrap};
use crate::color::luminance;
use glam::Vec3;

/// Every emitting triangle with its power and a normalised CDF over the powers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmissiveTable {
    /// Indices into [`super::Scene::triangles`].
    pub triangles: Vec<u32>,
    /// Each entry's power: `luminance(emissive) · area · π` (a Lambertian emitter's flux), times
    /// the mean linear luminance of the emissive texture's texels that the triangle can read
    /// (its footprint) when the material has one.
    pub power: Vec<f32>,
    /// Running sum of `power / total_power`; increasing, the last entry exactly 1.
    pub cdf: Vec<f32>,
    /// Sum of `power`.
    pub total_power: f32,
}

impl EmissiveTable {
    /// Builds the table. Triangles whose power is zero (zero area, no emission, or an emissive
    /// texture that is black wherever the triangle can read it) are left out: they emit nothing
    /// and could never be sampled.
    pub(super) fn build(scene: &super::Scene) -> Self {
        let super::Scene { positions, triangles, triangle_material, materials, textures, .. } = scene;
        // Summed-area tables of the textures that emitting materials read, built once each.
        let mut tables: Vec<Option<LuminanceTable>> = vec![None; textures.len()];
        for m in materials.iter().filter(|m| luminance(m.emission()) > 0.0) {
            if let Some(t) = m.emissive_texture.and_then(|t| textures.get(t.texture as usize).map(|x| (t, x)))
            {
                tables[t.0.texture as usize].get_or_insert_with(|| LuminanceTable::new(t.1));
            }
        }
        let mut table = Self::default();
        for (t, (tri, &m)) in triangles.iter().zip(triangle_material).enumerate() {
            let Some(material) = materials.get(m as usize) else { continue };
            let mut l = luminance(material.emission());
            if l <= 0.0 {
                continue;
            }
            if let Some(slot) = material.emissive_texture {
                if let (Some(texture), Some(Some(sums))) =
                    (textures.get(slot.texture as usize), tables.get(slot.texture as usize))
                {
                    // As the GPU reads it: any set but 0 is TEXCOORD_1 (the only other one loaded).
                    let uvs = if slot.tex_coord != 0 { &scene.uv1 } else { &scene.uv0 };
                    let uv = tri.map(|v| uvs.get(v as usize).map(|&uv| slot.transform_uv(uv)));
                    l *= match uv {
                        [Some(a), Some(b), Some(c)] => texture_footprint_mean(texture, sums, [a, b, c]),
                        _ => sums.mean(),
                    };
                }
                if l <= 0.0 {
                    continue;
                }
            }
            let [a, b, c] = tri.map(|v| Vec3::from(positions[v as usize]));
            let power = l * 0.5 * (b - a).cross(c - a).length() * std::f32::consts::PI;
            if power > 0.0 && power.is_finite() {
                table.triangles.push(t as u32);
                table.power.push(power);
            }
        }
        let total: f64 = table.power.iter().map(|&p| f64::from(p)).sum();
        let mut running = 0.0f64;
        table.cdf = table
            .power
            .iter()
            .map(|&p| {
                running += f64::from(p);
                (running / total) as f32
            })
            .collect();
        if let Some(last) = table.cdf.last_mut() {
            *last = 1.0;
        }
        table.total_power = total as f32;
        table
    }

    /// Whether nothing in the scene emits.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The probability of picking entry `entry`: its share of the total power.
    pub fn pmf(&self, entry: usize) -> f32 {
        self.power.get(entry).map_or(0.0, |p| p / self.total_power)
    }

    /// Picks an entry (an index into `triangles` and `power`) for a uniform `u` in [0, 1), in
    /// proportion to power; returns it with its probability. An empty table returns `(0, 0.0)`.
    pub fn sample(&self, u: f32) -> (usize, f32) {
        if self.is_empty() {
            return (0, 0.0);
        }
        let u = u.clamp(0.0, 1.0 - f32::EPSILON / 2.0);
        let entry = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        (entry, self.pmf(entry))
    }
}

/// A texture's linear luminance as a summed-area table: the sum over any rectangle of texels
/// in four reads.
#[derive(Clone, Debug)]
struct LuminanceTable {
    width: usize,
    height: usize,
    /// `(width + 1) × (height + 1)` running sums, row-major; row and column 0 are zero.
    sums: Vec<f64>,
}

impl LuminanceTable {
    fn new(texture: &Texture) -> Self {
        let (width, height) = (texture.width as usize, texture.height as usize);
        let texels = texture.luminances();
        let mut sums = vec![0.0f64; (width + 1) * (height + 1)];
        for (y, row) in texels.chunks_exact(width.max(1)).take(height).enumerate() {
            let mut running = 0.0f64;
            for (x, &l) in row.iter().enumerate() {
                running += f64::from(l);
                sums[(y + 1) * (width + 1) + x + 1] = sums[y * (width + 1) + x + 1] + running;
            }
        }
        Self { width, height, sums }
    }

    /// The sum over texels `xs` × `ys` (inclusive ranges inside the texture).
    fn sum(&self, (x0, x1): (usize, usize), (y0, y1): (usize, usize)) -> f64 {
        let at = |x: usize, y: usize| self.sums[y * (self.width + 1) + x];
        at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0)
    }

    /// The mean over the whole texture.
    fn mean(&self) -> f32 {
        if self.width == 0 || self.height == 0 {
            return 0.0;
        }
        (self.sum((0, self.width - 1), (0, self.height - 1)) / (self.width * self.height) as f64) as f32
    }
}

/// The mean luminance of the texels a triangle with texture coordinates `uv` can read from
/// `texture` at level 0, bilinear or nearest, through its wrap modes (what `texture_sample` in
/// texture.glsl fetches at any point of the triangle), from the rectangle that bounds them: zero
/// only when every such texel is black. The bounds are widened by a thousandth of a texel (and
/// more for coordinates far from the origin) against the rounding of the barycentric
/// interpolation on the GPU, so the triangle is kept wherever it could emit. Non-finite
/// coordinates read the whole texture.
fn texture_footprint_mean(texture: &Texture, table: &LuminanceTable, uv: [[f32; 2]; 3]) -> f32 {
    let (w, h) = (table.width as i64, table.height as i64);
    if w == 0 || h == 0 {
        return 0.0;
    }
    let span = |axis: usize, n: i64, wrap: Wrap| {
        let lo = uv.iter().map(|c| c[axis]).fold(f32::INFINITY, f32::min);
        let hi = uv.iter().map(|c| c[axis]).fold(f32::NEG_INFINITY, f32::max);
        // Texel centres at (i + ½) / n: a bilinear read at c touches floor(c·n − ½) and the next
        // (a nearest read floor(c·n), one of the two).
        let (lo, hi) = (f64::from(lo) * n as f64 - 0.5, f64::from(hi) * n as f64 - 0.5);
        let slack = |c: f64| 1e-3 + 1e-5 * c.abs();
        let first = (lo - slack(lo)).floor();
        let last = (hi + slack(hi)).floor() + 1.0;
        if !(first.is_finite() && last.is_finite()) || last - first >= 4.0 * n as f64 {
            return vec![(0, n as usize - 1)];
        }
        wrapped_ranges(first as i64, last as i64, n, wrap)
    };
    let xs = span(0, w, texture.sampler.wrap_s);
    let ys = span(1, h, texture.sampler.wrap_t);
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for &x in &xs {
        for &y in &ys {
            sum += table.sum(x, y);
            count += (x.1 - x.0 + 1) * (y.1 - y.0 + 1);
        }
    }
    (sum / count.max(1) as f64) as f32
}

/// The texel indices in `0..n` that the unwrapped indices `first..=last` read through `wrap`
/// (texture_wrap in texture.glsl), as at most two inclusive ranges that may cover more than
/// they must, never less.
fn wrapped_ranges(first: i64, last: i64, n: i64, wrap: Wrap) -> Vec<(usize, usize)> {
    let full = vec![(0, n as usize - 1)];
    let len = last - first + 1;
    match wrap {
        Wrap::ClampToEdge => vec![(first.clamp(0, n - 1) as usize, last.clamp(0, n - 1) as usize)],
        Wrap::Repeat => {
            if len >= n {
                return full;
            }
            let a = first.rem_euclid(n);
            let b = a + len - 1;
            if b < n {
                vec![(a as usize, b as usize)]
            } else {
                vec![(a as usize, n as usize - 1), (0, (b - n) as usize)]
            }
        }
        Wrap::MirroredRepeat => {
            if len >= n {
                return full;
            }
            let mirror = |i: i64| {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            };
            let (a, b) = (mirror(first), mirror(last));
            let (lo, hi) = (a.min(b), a.max(b));
            // A range shorter than n crosses at most one fold: at the texture's first texel
            // (an even multiple of n) or at its last (an odd one).
            let fold = last.div_euclid(n);
            if fold == first.div_euclid(n) {
                vec![(lo as usize, hi as usize)]
            } else if fold.rem_euclid(2) == 0 {
                vec![(0, hi as usize)]
            } else {
                vec![(lo as usize, n as usize - 1)]
            }
        }
    }
}
