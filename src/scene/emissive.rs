//! The emissive-triangle table: which triangles emit, with how much power, and a CDF to pick one
//! in proportion to its power (next-event estimation on the GPU walks the same arrays).

use super::{Material, Texture};
use crate::color::luminance;
use glam::Vec3;

/// Every emitting triangle with its power and a normalised CDF over the powers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmissiveTable {
    /// Indices into [`super::Scene::triangles`].
    pub triangles: Vec<u32>,
    /// Each entry's power: `luminance(emissive) · area · π` (a Lambertian emitter's flux), times
    /// the emissive texture's mean linear luminance when the material has one.
    pub power: Vec<f32>,
    /// Running sum of `power / total_power`; increasing, the last entry exactly 1.
    pub cdf: Vec<f32>,
    /// Sum of `power`.
    pub total_power: f32,
}

impl EmissiveTable {
    /// Builds the table. Triangles whose power is zero (zero area, black emissive texture) are
    /// left out: they emit nothing and could never be sampled.
    pub(super) fn build(
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        triangle_material: &[u32],
        materials: &[Material],
        textures: &[Texture],
    ) -> Self {
        let radiance: Vec<f32> = materials.iter().map(|m| material_luminance(m, textures)).collect();
        let mut table = Self::default();
        for (t, (tri, &m)) in triangles.iter().zip(triangle_material).enumerate() {
            let l = radiance.get(m as usize).copied().unwrap_or(0.0);
            if l <= 0.0 {
                continue;
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

/// A material's emitted luminance, averaged over its emissive texture.
fn material_luminance(material: &Material, textures: &[Texture]) -> f32 {
    let l = luminance(material.emission());
    match material.emissive_texture.and_then(|t| textures.get(t.texture as usize)) {
        Some(texture) if l > 0.0 => l * texture.mean_luminance(),
        _ => l,
    }
}
