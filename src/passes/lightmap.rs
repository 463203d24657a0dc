//! Lightmaps: irradiance baked into textures over a second UV set (`TEXCOORD_1`, glTF's usual
//! lightmap set).
//!
//! Every material whose triangles carry a `TEXCOORD_1` chart (a triangle whose three UV1
//! coordinates span an area) gets one square map over UV1 ∈ [0, 1]² ([`LightmapLayout`]): each
//! texel whose centre a triangle covers records the world position and the interpolated normal
//! there (a CPU rasterizer in UV space; where charts overlap the last triangle wins). The bake
//! (`lightmap_bake.comp`) then averages samples of each texel's irradiance in two layers:
//!
//! - `emitters`: direct irradiance from the emissive triangles (light sampling with shadow rays);
//! - `ambient`: irradiance from the environment and from the light that surfaces reflect (a
//!   cosine-distributed gather ray per sample, its hit shaded with the path tracer's BSDF and
//!   lights as the probes' rays are, `gather.glsl`; the bounces beyond come from a probe volume
//!   when one is given, else there are none).
//!
//! The punctual lights' direct light is in neither: the lighting pass computes it with its own
//! shadows. A texel whose centre no triangle covers stays empty, and bilinear filtering next to a
//! chart's border reads it: the seam, a dark line along every chart's edge. [`Lightmaps::dilate`]
//! fills empty texels from their covered neighbours, a ring per pass.

use crate::error::{Error, Result};
use crate::gpu::kernels::lightmap_bake;
use crate::gpu::layout::LightmapParams;
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::output::{write_exr, Layer};
use crate::passes::probes::ProbeVolume;
use crate::scene::Scene;
use crate::vk::{raw, Buffer, Context, TexelBuffer};
use glam::{Vec2, Vec3};
use gpu_allocator::MemoryLocation;
use std::path::{Path, PathBuf};

/// How lightmaps are laid out and baked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightmapSettings {
    /// Texels a side of each material's map.
    pub size: u32,
    /// Samples per texel.
    pub samples: u32,
    /// Seed of the samples.
    pub seed: u32,
    /// Rings of empty texels [`Lightmaps::dilate`] fills after the bake.
    pub dilation: u32,
}

impl Default for LightmapSettings {
    fn default() -> Self {
        Self { size: 128, samples: 256, seed: 0, dilation: 2 }
    }
}

impl LightmapSettings {
    /// Most texels of all maps together.
    pub const MAX_TEXELS: u64 = 1 << 24;

    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        if !(1..=4096).contains(&self.size) {
            return Err(Error::Invalid(format!(
                "lightmap size {}: must be 1 to 4096 texels a side",
                self.size
            )));
        }
        if self.samples == 0 {
            return Err(Error::Invalid("lightmaps need at least one sample per texel".into()));
        }
        Ok(())
    }
}

/// One texel's record for the bake: world position with coverage (w: 1 covered, 0 empty), then
/// the unit normal (w unused).
pub type LightmapTexel = [[f32; 4]; 2];

/// Where each material's lightmap texels lie in the world.
#[derive(Debug, Clone)]
pub struct LightmapLayout {
    /// Texels a side of each map.
    pub size: u32,
    /// The material of each map, in map order.
    pub materials: Vec<u32>,
    /// Every map's texels, map after map, rows from the top (UV1 v = 0).
    pub texels: Vec<LightmapTexel>,
}

impl LightmapLayout {
    /// Rasterizes the UV1 charts of `scene` into maps of `size`² texels, one per material with a
    /// chart. A scene without `TEXCOORD_1` (or without any chart of area) has no maps.
    pub fn new(scene: &Scene, size: u32) -> Result<Self> {
        let mut by_material: Vec<Vec<usize>> = vec![Vec::new(); scene.materials.len()];
        if !scene.uv1.is_empty() {
            for (t, tri) in scene.triangles.iter().enumerate() {
                let [a, b, c] = tri.map(|i| Vec2::from(scene.uv1[i as usize]));
                if (b - a).perp_dot(c - a).abs() > 1e-12 {
                    by_material[scene.triangle_material[t] as usize].push(t);
                }
            }
        }
        let materials: Vec<u32> =
            (0..by_material.len()).filter(|&m| !by_material[m].is_empty()).map(|m| m as u32).collect();
        let per_map = size as u64 * size as u64;
        if materials.len() as u64 * per_map > LightmapSettings::MAX_TEXELS {
            return Err(Error::Invalid(format!(
                "{} lightmaps of {size}² texels are more than {} texels: lower the lightmap size",
                materials.len(),
                LightmapSettings::MAX_TEXELS
            )));
        }
        let mut texels = vec![[[0.0f32; 4]; 2]; materials.len() * per_map as usize];
        for (k, &m) in materials.iter().enumerate() {
            let map = &mut texels[k * per_map as usize..(k + 1) * per_map as usize];
            for &t in &by_material[m as usize] {
                rasterize(scene, t, size, map);
            }
        }
        Ok(Self { size, materials, texels })
    }

    /// Texels of one map.
    pub fn texels_per_map(&self) -> usize {
        (self.size * self.size) as usize
    }

    /// Whether each texel is covered by a triangle.
    pub fn covered(&self) -> Vec<bool> {
        self.texels.iter().map(|t| t[0][3] != 0.0).collect()
    }
}

/// Gives every triangle of `scene` its own chart in a new `TEXCOORD_1` set, for scenes that
/// carry none: per material, the triangles in a grid of square cells of a map of `size` texels,
/// each laid flat (its first edge along u) at one scale for all of the material's triangles (the
/// largest fills its cell), inside a gutter of two texels (a quarter of the cell in maps too small
/// for that). Vertices are unshared first (each
/// triangle gets its own three), so charts never meet; seams run along every edge, and the
/// dilation's gutter keeps bilinear lookups inside each chart.
pub fn unwrap_triangles(scene: &mut Scene, size: u32) {
    let count = scene.triangles.len();
    let old = std::mem::take(&mut scene.triangles);
    // Each vertex attribute (absent ones stay empty) re-laid out three vertices per triangle.
    fn unshare<T: Copy>(attribute: &mut Vec<T>, triangles: &[[u32; 3]]) {
        if !attribute.is_empty() {
            *attribute = triangles.iter().flat_map(|t| t.map(|i| attribute[i as usize])).collect();
        }
    }
    unshare(&mut scene.positions, &old);
    unshare(&mut scene.normals, &old);
    unshare(&mut scene.uv0, &old);
    unshare(&mut scene.colors, &old);
    unshare(&mut scene.tangents, &old);
    scene.triangles = (0..count as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    // Each triangle flat in its own frame: A at the origin, B along u.
    let flat: Vec<[Vec2; 3]> = (0..count)
        .map(|t| {
            let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(scene.positions[3 * t + k]));
            let u = (b - a).normalize_or_zero();
            let n = (b - a).cross(c - a);
            let v = n.cross(u).normalize_or_zero();
            let p = |q: Vec3| Vec2::new((q - a).dot(u), (q - a).dot(v));
            let (pa, pb, pc) = (p(a), p(b), p(c));
            let lo = pa.min(pb).min(pc);
            [pa - lo, pb - lo, pc - lo]
        })
        .collect();
    let mut uv1 = vec![[0.0f32; 2]; 3 * count];
    for m in 0..scene.materials.len() as u32 {
        let tris: Vec<usize> = (0..count).filter(|&t| scene.triangle_material[t] == m).collect();
        if tris.is_empty() {
            continue;
        }
        let grid = (tris.len() as f32).sqrt().ceil() as usize;
        let cell = 1.0 / grid as f32;
        // Two texels, or a quarter of the cell in maps too small for that.
        let gutter = (2.0 / size as f32).min(0.25 * cell);
        let extent =
            tris.iter().map(|&t| flat[t].iter().fold(0.0f32, |e, p| e.max(p.x).max(p.y))).fold(0.0, f32::max);
        let scale = (cell - 2.0 * gutter).max(0.0) / extent.max(1e-12);
        for (k, &t) in tris.iter().enumerate() {
            let origin = Vec2::new((k % grid) as f32, (k / grid) as f32) * cell + gutter;
            for (j, p) in flat[t].iter().enumerate() {
                uv1[3 * t + j] = (origin + *p * scale).to_array();
            }
        }
    }
    scene.uv1 = uv1;
}

/// Writes triangle `t`'s texels (those whose centre it covers) into `map`.
fn rasterize(scene: &Scene, t: usize, size: u32, map: &mut [LightmapTexel]) {
    let tri = scene.triangles[t];
    let uv = tri.map(|i| Vec2::from(scene.uv1[i as usize]) * size as f32);
    let pos = tri.map(|i| Vec3::from(scene.positions[i as usize]));
    let nrm = tri.map(|i| Vec3::from(scene.normals[i as usize]));
    let face = (pos[1] - pos[0]).cross(pos[2] - pos[0]).normalize_or_zero();
    let area = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
    let lo = uv[0].min(uv[1]).min(uv[2]).floor().max(Vec2::ZERO);
    let hi = uv[0].max(uv[1]).max(uv[2]).ceil().min(Vec2::splat(size as f32));
    // Texel centres on an edge belong to the triangle: a small tolerance in UV texels².
    let eps = -1e-5 * area.abs();
    for y in lo.y as u32..hi.y as u32 {
        for x in lo.x as u32..hi.x as u32 {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let w0 = (uv[2] - uv[1]).perp_dot(p - uv[1]) / area;
            let w1 = (uv[0] - uv[2]).perp_dot(p - uv[2]) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 * area.abs() < eps || w1 * area.abs() < eps || w2 * area.abs() < eps {
                continue;
            }
            let world = w0 * pos[0] + w1 * pos[1] + w2 * pos[2];
            let mut n = (w0 * nrm[0] + w1 * nrm[1] + w2 * nrm[2]).normalize_or(face);
            if n.dot(face) < 0.0 {
                n = -n;
            }
            map[(y * size + x) as usize] = [world.extend(1.0).to_array(), n.extend(0.0).to_array()];
        }
    }
}

/// Baked lightmaps, read back: per map and texel the two layers' irradiance.
#[derive(Debug, Clone)]
pub struct Lightmaps {
    /// Texels a side of each map.
    pub size: u32,
    /// The material of each map.
    pub materials: Vec<u32>,
    /// Direct irradiance from the emissive triangles, every map's texels in turn.
    pub emitters: Vec<[f32; 3]>,
    /// Irradiance from the environment and reflected light.
    pub ambient: Vec<[f32; 3]>,
    /// The standard error of each texel's `emitters` red channel (0 for empty texels).
    pub emitters_error: Vec<f32>,
    /// Whether a triangle covers the texel (or, after [`Lightmaps::dilate`], a filled one).
    pub covered: Vec<bool>,
    /// Samples per texel.
    pub samples: u32,
}

impl Lightmaps {
    /// Fills `rings` rings of empty texels around each chart: an empty texel with covered
    /// neighbours (of its 8) takes their mean, ring by ring, so bilinear lookups across a chart's
    /// border read its own values instead of empty ones.
    pub fn dilate(&mut self, rings: u32) {
        dilate(self.size, &mut self.covered, &mut [&mut self.emitters, &mut self.ambient], rings);
    }

    /// Bilinear lookup of `layer` (one map's texels) at UV1 `uv` (texel centres at (i + ½)/size,
    /// clamped at the map's edges).
    pub fn sample(layer: &[[f32; 3]], size: u32, uv: [f32; 2]) -> [f32; 3] {
        let s = size as f32;
        let p = Vec2::from(uv) * s - 0.5;
        let base = p.floor();
        let f = p - base;
        let at = |x: f32, y: f32| {
            let (x, y) = (x.clamp(0.0, s - 1.0) as usize, y.clamp(0.0, s - 1.0) as usize);
            layer[y * size as usize + x]
        };
        let (a, b, c, d) = (
            at(base.x, base.y),
            at(base.x + 1.0, base.y),
            at(base.x, base.y + 1.0),
            at(base.x + 1.0, base.y + 1.0),
        );
        [0, 1, 2].map(|k| {
            (a[k] * (1.0 - f.x) + b[k] * f.x) * (1.0 - f.y) + (c[k] * (1.0 - f.x) + d[k] * f.x) * f.y
        })
    }

    /// Map `k`'s texels of `layer`.
    pub fn map<'a>(&self, layer: &'a [[f32; 3]], k: usize) -> &'a [[f32; 3]] {
        let n = (self.size * self.size) as usize;
        &layer[k * n..(k + 1) * n]
    }

    /// Writes one EXR per map into `dir` (`lightmap-<material>.exr`, layers `emitters` and
    /// `ambient`, channels R, G, B); returns the paths.
    pub fn write_exr(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        crate::atomic::create_dir(dir)?;
        let mut paths = Vec::new();
        for (k, m) in self.materials.iter().enumerate() {
            let flat =
                |layer: &[[f32; 3]]| self.map(layer, k).iter().flatten().copied().collect::<Vec<f32>>();
            let (emitters, ambient) = (flat(&self.emitters), flat(&self.ambient));
            let path = dir.join(format!("lightmap-{m}.exr"));
            let rgb = ["R", "G", "B"];
            let s = self.size as usize;
            write_exr(
                &path,
                s,
                s,
                &[
                    Layer { name: "emitters", channels: &rgb, data: &emitters },
                    Layer { name: "ambient", channels: &rgb, data: &ambient },
                ],
            )?;
            paths.push(path);
        }
        Ok(paths)
    }
}

/// Lightmaps on the GPU for the lighting pass: their `ambient` layers, which light the diffuse
/// lobe of the materials that have a map (instead of the probes or the environment's
/// irradiance), looked up bilinearly at the G-buffer's UV1.
pub struct GpuLightmaps {
    /// The header (texels a side, the number of materials), per material the index + 1 of its
    /// map (0: none), then every map's texels (RGBA32_SFLOAT, rgb).
    pub texels: TexelBuffer,
}

impl GpuLightmaps {
    /// Uploads `maps` for a scene of `material_count` materials.
    pub fn upload(ctx: &Context, maps: &Lightmaps, material_count: usize) -> Result<Self> {
        if let Some(&m) = maps.materials.iter().find(|&&m| m as usize >= material_count) {
            return Err(Error::Invalid(format!(
                "a lightmap for material {m}, but the scene has {material_count} materials: baked for another scene"
            )));
        }
        let mut texels = vec![[maps.size as f32, material_count as f32, 0.0, 0.0]];
        let mut table = vec![[0.0f32; 4]; material_count];
        for (k, &m) in maps.materials.iter().enumerate() {
            table[m as usize][0] = (k + 1) as f32;
        }
        texels.extend(table);
        texels.extend(maps.ambient.iter().map(|a| [a[0], a[1], a[2], 0.0]));
        Ok(Self {
            texels: TexelBuffer::upload(ctx, "lightmaps", &texels, raw::Format::R32G32B32A32_SFLOAT, 16)?,
        })
    }
}

/// Fills `rings` rings of empty texels of every map (`size`² texels each, in turn) in `layers`:
/// an empty texel with covered neighbours (of its 8) takes their mean, ring by ring.
fn dilate(size: u32, covered: &mut [bool], layers: &mut [&mut Vec<[f32; 3]>], rings: u32) {
    let s = size as i64;
    let per_map = (s * s) as usize;
    for _ in 0..rings {
        let before = covered.to_vec();
        let old: Vec<Vec<[f32; 3]>> = layers.iter().map(|l| l.to_vec()).collect();
        for i in 0..before.len() {
            if before[i] {
                continue;
            }
            let (base, local) = ((i / per_map) * per_map, (i % per_map) as i64);
            let (x, y) = (local % s, local / s);
            let mut sums = vec![[0.0f32; 3]; layers.len()];
            let mut n = 0.0f32;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (nx, ny) = (x + dx, y + dy);
                    if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= s || ny >= s {
                        continue;
                    }
                    let j = base + (ny * s + nx) as usize;
                    if before[j] {
                        for (sum, layer) in sums.iter_mut().zip(&old) {
                            (0..3).for_each(|c| sum[c] += layer[j][c]);
                        }
                        n += 1.0;
                    }
                }
            }
            if n > 0.0 {
                for (layer, sum) in layers.iter_mut().zip(&sums) {
                    layer[i] = sum.map(|v| v / n);
                }
                covered[i] = true;
            }
        }
    }
}

/// Baked ambient-occlusion maps over UV1 (for glTF's `occlusionTexture`, `texCoord` 1), one per
/// material with a chart: per texel the unoccluded fraction of cosine-distributed rays of a given
/// length (RTAO's estimator).
#[derive(Debug, Clone)]
pub struct OcclusionMaps {
    /// Texels a side of each map.
    pub size: u32,
    /// The material of each map.
    pub materials: Vec<u32>,
    /// Every map's texels in turn (1 = open), dilated; 1 where no chart reaches.
    pub values: Vec<f32>,
}

impl OcclusionMaps {
    /// Writes one grey PNG per map into `dir` (`occlusion-<material>.png`, linear values in
    /// 8 bits, as glTF reads an occlusion texture's red channel); returns the paths.
    pub fn write_png(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        crate::atomic::create_dir(dir)?;
        let n = (self.size * self.size) as usize;
        let mut paths = Vec::new();
        for (k, m) in self.materials.iter().enumerate() {
            let bytes: Vec<u8> = self.values[k * n..(k + 1) * n]
                .iter()
                .flat_map(|v| {
                    let g = (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
                    [g, g, g, 255]
                })
                .collect();
            let path = dir.join(format!("occlusion-{m}.png"));
            crate::output::write_png(&path, self.size, self.size, &bytes)?;
            paths.push(path);
        }
        Ok(paths)
    }
}

/// The bake kernel.
pub struct LightmapPass {
    pipeline: Pipeline<lightmap_bake::Kernel>,
    occlusion: Pipeline<lightmap_bake::Kernel>,
    /// Stand-ins for the probe volume's bindings when there is none (every probe inactive).
    no_probes: [TexelBuffer; 2],
}

impl LightmapPass {
    /// Builds the pipeline for `scene`'s features.
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        let no_probes = crate::passes::probes::no_probe_bindings(ctx)?;
        Ok(Self {
            pipeline: Pipeline::for_scene(ctx, scene, &lightmap_bake::Spec { occlusion: false })?,
            occlusion: Pipeline::for_scene(ctx, scene, &lightmap_bake::Spec { occlusion: true })?,
            no_probes,
        })
    }

    /// Bakes `layout`'s maps by `settings` under environment `env`, the bounces beyond the
    /// first from `probes` when given; submits a batch of samples at a time, calling
    /// `progress(done, total)`; reads the maps back, dilated by `settings.dilation` rings.
    #[allow(clippy::too_many_arguments)]
    pub fn bake(
        &self,
        ctx: &Context,
        scene: &GpuScene,
        layout: &LightmapLayout,
        settings: &LightmapSettings,
        env: [f32; 3],
        probes: Option<&ProbeVolume>,
        progress: impl FnMut(u32, u32),
    ) -> Result<Lightmaps> {
        let sums = self.run(ctx, scene, layout, settings, env, 0.0, probes, progress)?;
        let covered = layout.covered();
        let n = settings.samples as f32;
        let count = layout.texels.len();
        let mut maps = Lightmaps {
            size: layout.size,
            materials: layout.materials.clone(),
            emitters: Vec::with_capacity(count),
            ambient: Vec::with_capacity(count),
            emitters_error: Vec::with_capacity(count),
            covered: covered.clone(),
            samples: settings.samples,
        };
        for (i, &on) in covered.iter().enumerate() {
            let (e, a) = if on { (sums[2 * i], sums[2 * i + 1]) } else { ([0.0; 4], [0.0; 4]) };
            maps.emitters.push([e[0], e[1], e[2]]);
            maps.ambient.push([a[0], a[1], a[2]]);
            let variance = (e[3] - e[0] * e[0]).max(0.0) * n / (n - 1.0).max(1.0);
            maps.emitters_error.push((variance / n).sqrt());
        }
        maps.dilate(settings.dilation);
        Ok(maps)
    }

    /// Bakes ambient-occlusion maps of `layout` by `settings` (samples, seed, dilation) with
    /// occlusion rays of length `radius`, dilated; texels no chart reaches are 1.
    pub fn bake_occlusion(
        &self,
        ctx: &Context,
        scene: &GpuScene,
        layout: &LightmapLayout,
        settings: &LightmapSettings,
        radius: f32,
        progress: impl FnMut(u32, u32),
    ) -> Result<OcclusionMaps> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::Invalid(format!("occlusion radius {radius} must be a positive distance")));
        }
        let sums = self.run(ctx, scene, layout, settings, [0.0; 3], radius, None, progress)?;
        let mut covered = layout.covered();
        let mut values: Vec<[f32; 3]> =
            covered.iter().enumerate().map(|(i, &on)| [if on { sums[2 * i][0] } else { 1.0 }; 3]).collect();
        dilate(layout.size, &mut covered, &mut [&mut values], settings.dilation);
        Ok(OcclusionMaps {
            size: layout.size,
            materials: layout.materials.clone(),
            values: values.iter().map(|v| v[0]).collect(),
        })
    }

    /// Runs `settings.samples` samples of every texel (occlusion rays of `radius` when it is
    /// positive, irradiance otherwise) and reads the running means back.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        ctx: &Context,
        scene: &GpuScene,
        layout: &LightmapLayout,
        settings: &LightmapSettings,
        env: [f32; 3],
        radius: f32,
        probes: Option<&ProbeVolume>,
        mut progress: impl FnMut(u32, u32),
    ) -> Result<Vec<[f32; 4]>> {
        settings.validate()?;
        let count = layout.texels.len();
        if count == 0 {
            return Err(Error::Invalid(
                "the scene has no lightmap charts: no triangle carries a TEXCOORD_1 of any area (unwrap_triangles, `umbra bake --unwrap`, gives each triangle one)".into(),
            ));
        }
        let texels = TexelBuffer::upload(
            ctx,
            "lightmap texels",
            &layout.texels,
            raw::Format::R32G32B32A32_SFLOAT,
            16,
        )?;
        let accum = Buffer::new(
            ctx,
            "lightmap accumulation",
            count as u64 * 32,
            raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let [no_states, no_maps] = &self.no_probes;
        let resources = lightmap_bake::Resources {
            scene,
            lightmap_texels: &texels,
            probe_texels: probes.map_or(no_states, |p| &p.texels),
            probe_irradiance: probes.map_or(no_maps, |p| &p.irradiance),
            probe_distance: probes.map_or(no_maps, |p| &p.distance),
            lightmap_accum: &accum,
        };
        let pipeline = if radius > 0.0 { &self.occlusion } else { &self.pipeline };
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        // About 2^22 texel-samples per submission.
        let batch = ((1u64 << 22) / count as u64).clamp(1, 64) as u32;
        let mut done = 0;
        while done < settings.samples {
            let n = batch.min(settings.samples - done);
            ctx.record(|rec| {
                for sample_index in done..done + n {
                    let params = LightmapParams {
                        env,
                        texel_count: count as u32,
                        env_size: [env_w, env_h],
                        sample_index,
                        seed: settings.seed,
                        light_count: scene.light_count,
                        punctual_count: scene.punctual_count,
                        radius,
                        ..Default::default()
                    };
                    pipeline.record(rec, &resources, &params, [count as u32, 1, 1])?;
                }
                Ok(())
            })?;
            done += n;
            progress(done, settings.samples);
        }
        accum.read(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unwrapped Cornell box: every triangle keeps its shape (edge lengths at one scale per
    /// material) and its chart's box, grown by the gutter less one texel, meets no other chart of
    /// its material; the layout then covers texels of every chart.
    #[test]
    fn unwrapped_charts_keep_their_shape_and_never_meet() {
        let mut scene = Scene::cornell_box();
        let before: Vec<[Vec3; 3]> = scene.triangle_soup();
        let size = 128;
        unwrap_triangles(&mut scene, size);
        assert_eq!(scene.triangle_soup(), before, "unsharing vertices moved a triangle");
        let boxes: Vec<(u32, Vec2, Vec2)> = scene
            .triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let uv = tri.map(|i| Vec2::from(scene.uv1[i as usize]) * size as f32);
                (scene.triangle_material[t], uv[0].min(uv[1]).min(uv[2]), uv[0].max(uv[1]).max(uv[2]))
            })
            .collect();
        for (i, a) in boxes.iter().enumerate() {
            assert!(a.1.min_element() >= 0.0 && a.2.max_element() <= size as f32, "chart {i} leaves the map");
            for b in &boxes[i + 1..] {
                let apart = a.2.x + 1.0 <= b.1.x
                    || b.2.x + 1.0 <= a.1.x
                    || a.2.y + 1.0 <= b.1.y
                    || b.2.y + 1.0 <= a.1.y;
                assert!(a.0 != b.0 || apart, "charts meet: {a:?} {b:?}");
            }
        }
        // One scale per material: UV edge length / world edge length is the same for all of its
        // triangles.
        for m in 0..scene.materials.len() as u32 {
            let ratios: Vec<f32> = (0..scene.triangles.len())
                .filter(|&t| scene.triangle_material[t] == m)
                .map(|t| {
                    let [a, b, _] = scene.triangles[t].map(|i| i as usize);
                    let uv = Vec2::from(scene.uv1[b]) - Vec2::from(scene.uv1[a]);
                    uv.length() / (Vec3::from(scene.positions[b]) - Vec3::from(scene.positions[a])).length()
                })
                .collect();
            if let Some(&first) = ratios.first() {
                assert!(
                    ratios.iter().all(|r| (r / first - 1.0).abs() < 1e-3),
                    "material {m}: scales {ratios:?}"
                );
            }
        }
        let layout = LightmapLayout::new(&scene, size).unwrap();
        assert!(!layout.materials.is_empty());
        assert!(layout.covered().iter().filter(|c| **c).count() > 1000, "the charts cover texels");
    }
}
