//! Irradiance probes: indirect diffuse light for the hybrid renderer, precomputed or updated a
//! budget of probes per frame (after DDGI: Majercik et al. 2019, "Dynamic Diffuse Global
//! Illumination with Ray-Traced Irradiance Fields").
//!
//! A [`ProbeGrid`] of probes spans the scene's bounds. One update of a range of probes runs two
//! kernels: `probe_trace` casts each probe's rays (a spherical Fibonacci set under a random
//! rotation per update) through the BVH and shades their hits with the path tracer's BSDF and
//! lights (`shading.glsl`: punctual lights and an emissive-triangle sample with shadow rays), plus
//! the volume's own irradiance at the hit through the diffuse lobe (each update adds a bounce);
//! misses bring the environment. `probe_blend` folds the rays into each probe's octahedral maps —
//! irradiance (6×6 texels) and the mean and mean square of the distance to the nearest surface
//! (14×14), each with a one-texel border so bilinear lookups wrap — and switches off probes that
//! see more than a quarter of back faces (inside geometry).
//!
//! The probes carry what the lighting pass does not compute itself: a hit's emission is left out
//! (the lighting pass samples emitters and punctual lights as direct light), the environment is
//! in (its light with the scene's occlusion, replacing the split sum's unoccluded irradiance). The
//! lighting pass (`deferred.comp`, `probes.glsl`) reads the eight probes around each shaded
//! point, moved along its normal and towards the viewer, with trilinear weights, a back-face term
//! and Chebyshev visibility from the distance moments, and lights the diffuse lobe with it (times
//! ambient occlusion); the specular lobe keeps the split sum.
//!
//! A probe's first [`ProbeSettings::bounces`] updates replace its maps (each adds a bounce of
//! light, the trace reading the volume); later ones average: a bake runs sweeps over all probes
//! as a running mean that converges to the probes' multi-bounce irradiance; an embedding host
//! updates a budget of probes per frame, blended with hysteresis ([`ProbeSettings::hysteresis`]).

use crate::error::{Error, Result};
use crate::gpu::kernels::{probe_blend, probe_trace};
use crate::gpu::layout::{
    GpuProbeGrid, ProbeUpdateParams, PROBE_ACTIVE, PROBE_DISTANCE_TEXELS, PROBE_HEADER_TEXELS,
    PROBE_IRRADIANCE_TEXELS, PROBE_MAX_RAYS, PROBE_RAY_GROUP, PROBE_VISIBILITY,
};
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::vk::{raw, Buffer, Context, Recorder, TexelBuffer};
use glam::{Mat3, Quat, Vec3};
use gpu_allocator::MemoryLocation;

/// Texels of one probe's irradiance map, border included.
pub const IRRADIANCE_MAP_TEXELS: u32 = (PROBE_IRRADIANCE_TEXELS + 2) * (PROBE_IRRADIANCE_TEXELS + 2);
/// Texels of one probe's distance map, border included.
pub const DISTANCE_MAP_TEXELS: u32 = (PROBE_DISTANCE_TEXELS + 2) * (PROBE_DISTANCE_TEXELS + 2);

/// How the probe volume is laid out and updated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeSettings {
    /// Distance between neighbouring probes (world units); `None`: the scene's longest side / 8.
    pub spacing: Option<f32>,
    /// Rays per probe and update: a multiple of 64, at most 256.
    pub rays: u32,
    /// Weigh probes by Chebyshev visibility from their distance maps (off only to show the
    /// light leaking it prevents).
    pub visibility: bool,
    /// How far a shaded point moves along its normal before it samples the probes, as a fraction
    /// of the smallest spacing.
    pub normal_bias: f32,
    /// How far it moves towards the viewer, as a fraction of the smallest spacing.
    pub view_bias: f32,
    /// Updates of a probe that replace its maps (one bounce of light each) before updates
    /// average.
    pub bounces: u32,
    /// Sweeps of the bake that average (a running mean over them).
    pub sweeps: u32,
    /// Weight an embedding host's updates keep of the old maps (1 − the least weight of the new
    /// estimate), after DDGI's hysteresis.
    pub hysteresis: f32,
}

impl Default for ProbeSettings {
    fn default() -> Self {
        Self {
            spacing: None,
            rays: 128,
            visibility: true,
            normal_bias: 0.1,
            view_bias: 0.3,
            bounces: 6,
            sweeps: 32,
            hysteresis: 0.97,
        }
    }
}

impl ProbeSettings {
    /// Most probes in one volume (5 KiB of maps each).
    pub const MAX_PROBES: u32 = 1 << 16;

    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        let invalid = |what: String| Err(Error::Invalid(format!("probes: {what}")));
        if let Some(s) = self.spacing {
            if !(s.is_finite() && s > 0.0) {
                return invalid(format!("spacing {s} must be a positive distance"));
            }
        }
        if self.rays == 0 || !self.rays.is_multiple_of(PROBE_RAY_GROUP) || self.rays > PROBE_MAX_RAYS {
            return invalid(format!(
                "{} rays per probe: must be a multiple of {PROBE_RAY_GROUP} up to {PROBE_MAX_RAYS}",
                self.rays
            ));
        }
        for (name, v) in [("normal bias", self.normal_bias), ("view bias", self.view_bias)] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return invalid(format!("{name} {v} must be a fraction of the spacing in [0, 1]"));
            }
        }
        if !(self.hysteresis.is_finite() && (0.0..1.0).contains(&self.hysteresis)) {
            return invalid(format!("hysteresis {} must be in [0, 1)", self.hysteresis));
        }
        if self.bounces == 0 && self.sweeps == 0 {
            return invalid("a bake needs at least one sweep".into());
        }
        Ok(())
    }
}

/// Where the probes are: probe (i, j, k) at `origin + spacing * (i, j, k)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeGrid {
    /// Position of probe (0, 0, 0).
    pub origin: [f32; 3],
    /// Distance between neighbours per axis.
    pub spacing: [f32; 3],
    /// Probes per axis.
    pub counts: [u32; 3],
}

impl ProbeGrid {
    /// A grid of cubic cells of side `spacing` (default: the longest side / 8) centred on the
    /// box `bounds`, a probe at each cell's centre (none on the box's faces, where a closed
    /// room's walls are), at least two per axis (a flat scene gets a layer either side). A spacing
    /// that puts fewer than two cells across the box's longest side is refused (it would place
    /// the probes outside the scene), as is one of more than [`ProbeSettings::MAX_PROBES`] probes.
    pub fn for_bounds(bounds: [[f32; 3]; 2], spacing: Option<f32>) -> Result<Self> {
        let lo = Vec3::from(bounds[0]);
        let hi = Vec3::from(bounds[1]);
        let extent = (hi - lo).max(Vec3::ZERO);
        let s = spacing.unwrap_or(extent.max_element() / 8.0);
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::Invalid(format!("probes: no spacing fits a scene of extent {extent}")));
        }
        if (extent.max_element() / s).ceil() < 2.0 {
            return Err(Error::Invalid(format!(
                "probes: spacing {s} puts fewer than 2 probes across the scene, whose extent is \
                 {extent} (longest side {}): give a spacing below {}",
                extent.max_element(),
                extent.max_element() / 2.0
            )));
        }
        let counts = (extent / s).ceil().max(Vec3::splat(2.0));
        let total = counts.x as f64 * counts.y as f64 * counts.z as f64;
        if total > ProbeSettings::MAX_PROBES as f64 {
            return Err(Error::Invalid(format!(
                "probes: spacing {s} over a scene of extent {extent} makes {total} probes, more than {}: \
                 raise the spacing",
                ProbeSettings::MAX_PROBES
            )));
        }
        let origin = (lo + hi) * 0.5 - (counts - 1.0) * s * 0.5;
        Ok(Self { origin: origin.into(), spacing: [s; 3], counts: counts.as_uvec3().into() })
    }

    /// Number of probes.
    pub fn count(&self) -> u32 {
        self.counts.iter().product()
    }

    /// Position of probe `i` (x fastest, then y, then z).
    pub fn position(&self, i: u32) -> [f32; 3] {
        let [nx, ny, _] = self.counts;
        let c = [i % nx, (i / nx) % ny, i / (nx * ny)];
        [0, 1, 2].map(|a| self.origin[a] + self.spacing[a] * c[a] as f32)
    }

    /// The header the kernels read, with the settings' biases in world units.
    pub fn gpu(&self, settings: &ProbeSettings) -> GpuProbeGrid {
        let s = self.spacing.iter().copied().fold(f32::INFINITY, f32::min);
        GpuProbeGrid {
            origin: self.origin,
            normal_bias: settings.normal_bias * s,
            spacing: self.spacing,
            view_bias: settings.view_bias * s,
            counts: self.counts,
            flags: if settings.visibility { PROBE_VISIBILITY } else { 0 },
        }
    }
}

/// A probe volume on the GPU: its grid, each probe's state and maps, and room for one update's
/// rays.
pub struct ProbeVolume {
    /// The settings it was made with.
    pub settings: ProbeSettings,
    /// Where the probes are.
    pub grid: ProbeGrid,
    /// The grid ([`GpuProbeGrid`], [`PROBE_HEADER_TEXELS`] texels), then per probe its state:
    /// [`PROBE_ACTIVE`] bit, updates since the maps were last replaced, back-face hits of the last
    /// update, updates in all (RGBA32_UINT).
    pub texels: TexelBuffer,
    /// Octahedral irradiance maps, [`IRRADIANCE_MAP_TEXELS`] per probe (RGBA32_SFLOAT, rgb).
    pub irradiance: TexelBuffer,
    /// Octahedral distance maps, [`DISTANCE_MAP_TEXELS`] per probe (RGBA32_SFLOAT: mean, mean
    /// square).
    pub distance: TexelBuffer,
    rays: Buffer,
    /// Probes one dispatch updates (the ray buffer holds their rays).
    chunk: u32,
    /// The next probe a budgeted update starts at.
    cursor: u32,
    /// Updates recorded (each turns the rays anew).
    updates: u32,
}

impl ProbeVolume {
    /// A volume over `scene`'s bounds by `settings`, every probe inactive until updated.
    pub fn new(ctx: &Context, scene: &GpuScene, settings: &ProbeSettings) -> Result<Self> {
        settings.validate()?;
        let grid = ProbeGrid::for_bounds(scene.bounds, settings.spacing)?;
        Self::with_grid(ctx, grid, settings)
    }

    /// A volume on `grid` (the probes placed by hand) by `settings` (its spacing unused).
    pub fn with_grid(ctx: &Context, grid: ProbeGrid, settings: &ProbeSettings) -> Result<Self> {
        settings.validate()?;
        let count = grid.count();
        if count == 0 || count > ProbeSettings::MAX_PROBES {
            return Err(Error::Invalid(format!(
                "probes: a grid of {:?} probes must hold 1 to {}",
                grid.counts,
                ProbeSettings::MAX_PROBES
            )));
        }
        let zeros = |texels: u32| vec![[0.0f32; 4]; texels as usize];
        Self::from_maps(
            ctx,
            grid,
            settings,
            &vec![[0u32; 4]; count as usize],
            &zeros(count * IRRADIANCE_MAP_TEXELS),
            &zeros(count * DISTANCE_MAP_TEXELS),
        )
    }

    /// A volume on `grid` with the given states and maps (a loaded bake).
    pub fn from_maps(
        ctx: &Context,
        grid: ProbeGrid,
        settings: &ProbeSettings,
        states: &[[u32; 4]],
        irradiance: &[[f32; 4]],
        distance: &[[f32; 4]],
    ) -> Result<Self> {
        let count = grid.count();
        if states.len() != count as usize
            || irradiance.len() != (count * IRRADIANCE_MAP_TEXELS) as usize
            || distance.len() != (count * DISTANCE_MAP_TEXELS) as usize
        {
            return Err(Error::Invalid(format!("probes: maps of the wrong size for {count} probes")));
        }
        let mut texels: Vec<[u32; 4]> = bytemuck::cast_slice(&[grid.gpu(settings)]).to_vec();
        debug_assert_eq!(texels.len(), PROBE_HEADER_TEXELS as usize);
        texels.extend_from_slice(states);
        let chunk = count.min(Self::MAX_CHUNK);
        let f32x4 = raw::Format::R32G32B32A32_SFLOAT;
        Ok(Self {
            settings: *settings,
            grid,
            texels: TexelBuffer::upload(ctx, "probe states", &texels, raw::Format::R32G32B32A32_UINT, 16)?,
            irradiance: TexelBuffer::upload(ctx, "probe irradiance", irradiance, f32x4, 16)?,
            distance: TexelBuffer::upload(ctx, "probe distance", distance, f32x4, 16)?,
            rays: Buffer::new(
                ctx,
                "probe rays",
                chunk as u64 * settings.rays as u64 * 16,
                raw::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?,
            chunk,
            cursor: 0,
            updates: 0,
        })
    }

    /// Most probes one dispatch updates.
    pub const MAX_CHUNK: u32 = 4096;

    /// Sweeps over all probes a bake runs: [`ProbeSettings::bounces`] that replace the maps, then
    /// [`ProbeSettings::sweeps`] that average.
    pub fn bake_sweeps(&self) -> u32 {
        self.settings.bounces + self.settings.sweeps
    }

    /// Updates recorded so far.
    pub fn updates(&self) -> u32 {
        self.updates
    }

    /// Reads every probe's state back: active, updates since replaced, back-face hits.
    pub fn read_states(&self, ctx: &Context) -> Result<Vec<[u32; 4]>> {
        let texels: Vec<[u32; 4]> = self.texels.buffer.read(ctx)?;
        Ok(texels[PROBE_HEADER_TEXELS as usize..][..self.grid.count() as usize].to_vec())
    }

    /// Whether each probe is active (outside geometry and updated at least once).
    pub fn read_active(&self, ctx: &Context) -> Result<Vec<bool>> {
        Ok(self.read_states(ctx)?.iter().map(|s| s[0] & PROBE_ACTIVE != 0 && s[1] > 0).collect())
    }

    /// Reads the irradiance maps back ([`IRRADIANCE_MAP_TEXELS`] per probe).
    pub fn read_irradiance(&self, ctx: &Context) -> Result<Vec<[f32; 4]>> {
        let n = (self.grid.count() * IRRADIANCE_MAP_TEXELS) as usize;
        Ok(self.irradiance.buffer.read::<[f32; 4]>(ctx)?[..n].to_vec())
    }

    /// Reads the distance maps back ([`DISTANCE_MAP_TEXELS`] per probe).
    pub fn read_distance(&self, ctx: &Context) -> Result<Vec<[f32; 4]>> {
        let n = (self.grid.count() * DISTANCE_MAP_TEXELS) as usize;
        Ok(self.distance.buffer.read::<[f32; 4]>(ctx)?[..n].to_vec())
    }
}

/// Stand-ins for a probe volume's bindings (`probe_texels`, and both maps) in kernels run without
/// one: a zeroed grid header and one inactive probe, so `probe_volume_irradiance` finds no probe
/// and gives 0; one map texel.
pub fn no_probe_bindings(ctx: &Context) -> Result<[TexelBuffer; 2]> {
    let states = [[0u32; 4]; PROBE_HEADER_TEXELS as usize + 1];
    Ok([
        TexelBuffer::upload(ctx, "no probe states", &states, raw::Format::R32G32B32A32_UINT, 16)?,
        TexelBuffer::upload(ctx, "no probe maps", &[[0.0f32; 4]], raw::Format::R32G32B32A32_SFLOAT, 16)?,
    ])
}

/// A uniformly random rotation (Shoemake 1992) from a hash of `seed`, as three rows.
fn random_rotation(seed: u32) -> [[f32; 4]; 3] {
    let mut state = seed as u64 ^ 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        // splitmix64
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let (u1, u2, u3) = (next(), next(), next());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let q = Quat::from_xyzw(
        (a * (tau * u2).sin()) as f32,
        (a * (tau * u2).cos()) as f32,
        (b * (tau * u3).sin()) as f32,
        (b * (tau * u3).cos()) as f32,
    )
    .normalize();
    let m = Mat3::from_quat(q).transpose();
    [m.x_axis, m.y_axis, m.z_axis].map(|r| [r.x, r.y, r.z, 0.0])
}

/// The probe kernels.
pub struct ProbePass {
    trace: Pipeline<probe_trace::Kernel>,
    blend: Pipeline<probe_blend::Kernel>,
}

impl ProbePass {
    /// Builds the pipelines for `scene`'s features.
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        Ok(Self {
            trace: Pipeline::for_scene(ctx, scene, &probe_trace::Spec {})?,
            blend: Pipeline::plain(ctx)?,
        })
    }

    /// Records one update of `count` probes of `volume` from its cursor on (wrapping), in
    /// dispatches of at most [`ProbeVolume::MAX_CHUNK`] probes, each new estimate weighed at
    /// least `blend_min` against the old once a probe's first [`ProbeSettings::bounces`] updates
    /// have replaced its maps, under environment `env` (the lighting's constant or map
    /// multiplier). Never submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        volume: &mut ProbeVolume,
        count: u32,
        blend_min: f32,
        env: [f32; 3],
    ) -> Result<()> {
        let total = volume.grid.count();
        let count = count.min(total);
        let rotation = random_rotation(volume.updates);
        let (env_w, env_h) = scene.env_size.unwrap_or((1, 1));
        let rays = volume.settings.rays;
        let diagonal = Vec3::from(volume.grid.spacing).length();
        let mut done = 0;
        while done < count {
            let n = (count - done).min(volume.chunk);
            let params = ProbeUpdateParams {
                rotation0: rotation[0],
                rotation1: rotation[1],
                rotation2: rotation[2],
                env,
                rays,
                env_size: [env_w, env_h],
                first_probe: (volume.cursor + done) % total,
                probe_count: n,
                light_count: scene.light_count,
                punctual_count: scene.punctual_count,
                seed: volume.updates,
                blend_min,
                max_distance: 4.0 * diagonal,
                warmup: volume.settings.bounces,
                ..Default::default()
            };
            let trace = probe_trace::Resources {
                scene,
                probe_texels: &volume.texels,
                probe_irradiance: &volume.irradiance,
                probe_distance: &volume.distance,
                probe_rays: &volume.rays,
            };
            self.trace.record(rec, &trace, &params, [rays, n, 1])?;
            let blend = probe_blend::Resources {
                probe_rays: &volume.rays,
                probe_texels: &volume.texels,
                probe_irradiance: &volume.irradiance,
                probe_distance: &volume.distance,
            };
            let side = PROBE_DISTANCE_TEXELS + 2;
            self.blend.record(rec, &blend, &params, [side * n, side, 1])?;
            done += n;
        }
        volume.cursor = (volume.cursor + count) % total;
        volume.updates = volume.updates.wrapping_add(1);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_centres_its_cells_in_the_bounds() {
        let grid = ProbeGrid::for_bounds([[0.0, 0.0, 0.0], [8.0, 4.0, 1.0]], Some(1.0)).unwrap();
        assert_eq!(grid.counts, [8, 4, 2]);
        assert_eq!(grid.position(0), [0.5, 0.5, 0.0]);
        assert_eq!(grid.position(grid.count() - 1), [7.5, 3.5, 1.0]);
        let auto = ProbeGrid::for_bounds([[0.0, 0.0, 0.0], [8.0, 4.0, 1.0]], None).unwrap();
        assert_eq!(auto.spacing, [1.0; 3]);
        assert!(ProbeGrid::for_bounds([[0.0; 3], [100.0; 3]], Some(0.1)).is_err());
        assert!(ProbeGrid::for_bounds([[0.0; 3], [0.0; 3]], None).is_err());
        // One cell across the longest side (the probes 1e9 apart, outside the scene): refused,
        // naming the extent; two cells are the fewest.
        let far = ProbeGrid::for_bounds([[0.0; 3], [8.0, 4.0, 1.0]], Some(1e9)).unwrap_err().to_string();
        assert!(far.contains("fewer than 2 probes") && far.contains("longest side 8"), "{far}");
        assert!(ProbeGrid::for_bounds([[0.0; 3], [8.0, 4.0, 1.0]], Some(8.0)).is_err());
        assert_eq!(ProbeGrid::for_bounds([[0.0; 3], [8.0, 4.0, 1.0]], Some(4.0)).unwrap().counts, [2, 2, 2]);
    }

    #[test]
    fn random_rotations_are_orthonormal_and_differ() {
        let a = random_rotation(0);
        let b = random_rotation(1);
        assert_ne!(a, b);
        let m = Mat3::from_cols_array(&[
            a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2],
        ]);
        let i = m * m.transpose();
        assert!(i.abs_diff_eq(Mat3::IDENTITY, 1e-5), "{i:?}");
    }
}
