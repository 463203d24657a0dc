//! Shadow maps: the real-time alternative to the lighting pass's shadow rays for punctual lights.
//!
//! A compute rasterizer (no graphics pipeline) renders the scene's BVH triangles into one depth
//! map per layer: one for a spot light (a perspective map over its cone), six for a point light
//! (a cube: one perspective map per axis direction), and cascades for a directional light
//! (orthographic maps over slices of the camera's view depth, after Zhang et al. 2006's practical
//! split scheme up to the scene's farthest corner rounded up to a power of two, each sized by the
//! slice's bounding sphere and its centre snapped to whole texels so the maps do not shimmer as
//! the camera turns or moves). Per layer five kernels run: `shadow_tiles` lists the tiles
//! (16×16 texels) to render, `shadow_bin` counts each triangle into the listed tiles its
//! light-space box overlaps (a small triangle rasterizes itself there; a large one that entered a
//! tile is listed for the fill), `shadow_scan` turns the counts into list offsets, `shadow_bin`
//! again, over the listed large triangles alone (an indirect dispatch), fills the lists, and
//! `shadow_raster` runs one workgroup per listed tile, one invocation per 2 × 2 texels, over the
//! tile's list: watertight homogeneous edge functions with a tie rule, alpha cut-outs as in the
//! traversal, the nearest linear depth stored. [`ShadowMethod::Moments`] adds their four moments,
//! box-filtered.
//!
//! The lighting pass (`deferred.comp`, `shadow.glsl`) then reads them with the chosen filter
//! instead of casting a shadow ray per punctual light; emissive triangles and the environment
//! keep their own methods. Cube faces and spot maps are rendered with a guard band a little
//! wider than the face, so a filter centred inside the face never reads past the map (seams).
//!
//! A directional cascade renders only its window ([`ShadowPlan::windows`]): the tiles around the
//! box its slice of the view makes in the layer, widened by the filters' reach, since no pixel of
//! that view reads the rest ([`ShadowSettings::cascade_windows`]). Maps rendered for a view
//! ([`ShadowView`], after its G-buffer) go further, as virtual shadow maps do: `shadow_mark`
//! marks the tiles the pixels' lookups reach (a superset: per block of 4 × 4 pixels, the box its
//! depth range can reach; [`ShadowSettings::mark_box`]), `shadow_tiles` lists a layer's marked
//! tiles, and binning, rasterizing and the moments' filter visit only those (indirect dispatches
//! over the list; [`ShadowSettings::view_marks`]). Both measured in docs/history/2026-12-04.md,
//! "cascade windows and view marks".
//!
//! The maps depend on the lights and the geometry, and for directional lights on the camera:
//! [`ShadowPlan::new`] places the layers (a moved light or camera needs a new plan, so new
//! [`ShadowMaps`]), and a host re-records them only when one of those changes.

use crate::error::{Error, Result};
use crate::gpu::kernels::{
    shadow_bin, shadow_mark, shadow_moments, shadow_raster, shadow_scan, shadow_tiles,
};
use crate::gpu::layout::{
    GpuCamera, GpuLight, GpuShadowLayer, ShadowMarkParams, ShadowMomentParams, ShadowRasterParams,
    ShadowStats, SHADOW_DISPATCH_WORDS, SHADOW_HEADER_TEXELS, SHADOW_LAYER_TEXELS, SHADOW_LIGHT_CASCADES,
    SHADOW_LIGHT_CUBE, SHADOW_LIGHT_SINGLE, SHADOW_MARK_BLOCK, SHADOW_MAX_CASCADES, SHADOW_ORTHOGRAPHIC,
    SHADOW_PERSPECTIVE, SHADOW_TILE,
};
use crate::gpu::scene::GpuScene;
use crate::gpu::Pipeline;
use crate::passes::gbuffer::GBufferViews;
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, GpuTimer, Recorder, TexelBuffer};
use glam::{Vec3, Vec4};
use gpu_allocator::MemoryLocation;

/// How the lighting pass shadows punctual lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ShadowMethod {
    /// One shadow ray per light and pixel through the BVH: exact (for a point source).
    #[default]
    #[cfg_attr(feature = "cli", value(name = "rt"))]
    RayTraced,
    /// A shadow map, the nearest texel compared.
    Hard,
    /// Percentage-closer filtering: 16 rotated Poisson taps, each a bilinear compare.
    ///
    /// The taps reach [`ShadowSettings::pcf_radius`] texels.
    Pcf,
    /// Percentage-closer soft shadows (Fernando 2005): a penumbra from the light's size.
    ///
    /// A blocker search, the penumbra from [`ShadowSettings::light_radius`] or
    /// [`ShadowSettings::sun_angle`], PCF of it.
    Pcss,
    /// Moment shadow maps (Peters and Klein 2015, Hamburger 4MSM), filtered before lookup.
    Moments,
}

impl ShadowMethod {
    /// Every method, in the order of their names.
    pub const ALL: [ShadowMethod; 5] = [
        ShadowMethod::RayTraced,
        ShadowMethod::Hard,
        ShadowMethod::Pcf,
        ShadowMethod::Pcss,
        ShadowMethod::Moments,
    ];

    /// The method's name in the CLI and scripts: `rt`, `hard`, `pcf`, `pcss`, `moments`.
    pub fn name(self) -> &'static str {
        match self {
            ShadowMethod::RayTraced => "rt",
            ShadowMethod::Hard => "hard",
            ShadowMethod::Pcf => "pcf",
            ShadowMethod::Pcss => "pcss",
            ShadowMethod::Moments => "moments",
        }
    }

    /// The method named `name` ([`ShadowMethod::name`]).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether the method reads shadow maps.
    pub fn uses_maps(self) -> bool {
        self != ShadowMethod::RayTraced
    }
}

/// Shadow-map settings. Biases and radii are in texels of the layer at the receiver, so one
/// value suits every resolution and distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowSettings {
    /// The method; the others apply to the map methods only.
    pub method: ShadowMethod,
    /// Width = height of every layer, texels.
    pub map_size: u32,
    /// Cascades of a directional light.
    pub cascades: u32,
    /// The split scheme: 0 uniform in view depth, 1 logarithmic, between: the blend (Zhang et
    /// al. 2006's practical scheme).
    pub cascade_split: f32,
    /// Constant depth bias, texels.
    pub depth_bias: f32,
    /// Slope-scaled depth bias, texels per unit of tan θ (θ between normal and light).
    pub slope_bias: f32,
    /// Normal offset: the receiver moves this many texels along its geometric normal.
    pub normal_bias: f32,
    /// PCF's filter radius, texels.
    pub pcf_radius: f32,
    /// Radius of point and spot lights for PCSS, metres.
    pub light_radius: f32,
    /// Angular radius of directional lights for PCSS, radians (the sun: 0.00465).
    pub sun_angle: f32,
    /// The largest filter radius (PCSS's search and penumbra), texels; also sets the guard band
    /// of cube faces and spot maps.
    pub max_radius: f32,
    /// Box-filter radius of the moment maps, texels.
    pub moment_blur: u32,
    /// Moment bias α of 4MSM (towards two equal spikes at 0 and 1).
    pub moment_bias: f32,
    /// With [`ShadowMethod::RayTraced`]: shadow the punctual lights as sized lights, a sphere of
    /// [`ShadowSettings::light_radius`] or a cone of [`ShadowSettings::sun_angle`], by the
    /// unoccluded fraction of `shadow_rays` rays per light
    /// ([`crate::passes::deferred::LightingSettings::sized_lights`]): the soft shadows PCSS
    /// approximates. Off by default: `rt` shadows points, as the path tracer's lights are.
    pub sized_rays: bool,
    /// Directional cascades render only the tiles their slice of the view can read: the
    /// slice's box in the layer, widened by the filters' reach and the normal offset
    /// ([`ShadowPlan::windows`]); texels outside it are left undefined. Off: the whole layer.
    pub cascade_windows: bool,
    /// Maps rendered for a view ([`ShadowView`]: by [`crate::render::Passes::hybrid`], and
    /// by hosts that pass one) render of each cascade only the tiles its G-buffer's pixels read,
    /// within the filters' reach; the rest is left undefined. Off: the window
    /// ([`ShadowSettings::cascade_windows`]).
    pub view_marks: bool,
    /// With view marks: the marking kernel's lanes each take a block of pixels and mark the
    /// box of tiles their points can reach (from the block's depth range); a subgroup whose
    /// boxes in a cascade fit a box of at most this many tiles a lane marks that box together
    /// (a store per lane a round, a superset of the tiles its pixels read), otherwise, and
    /// everywhere at 0, each lane its own box. All render what the view reads; this trades tiles
    /// rendered against the marking's time (docs/history/2026-12-04.md, third and fourth
    /// sessions).
    pub mark_rounds: u32,
    /// With view marks: the most tiles a block's box may hold; a block whose box is larger (its
    /// pixels across a depth edge), and every block at 0, marks each pixel's own tiles instead.
    pub mark_box: u32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        Self {
            method: ShadowMethod::RayTraced,
            map_size: 1024,
            cascades: 4,
            cascade_split: 0.75,
            depth_bias: 1.0,
            slope_bias: 1.0,
            normal_bias: 1.0,
            pcf_radius: 1.5,
            light_radius: 0.05,
            sun_angle: 0.00465,
            max_radius: 16.0,
            moment_blur: 2,
            moment_bias: 3e-5,
            sized_rays: false,
            cascade_windows: true,
            view_marks: true,
            mark_rounds: 4,
            mark_box: 16,
        }
    }
}

/// Spot lights with a wider cone than this get a cube map (one perspective map would stretch).
const SPOT_SINGLE_MAP_MAX_ANGLE: f32 = 60.0 * std::f32::consts::PI / 180.0;

impl ShadowSettings {
    /// The largest map side: a triangle covering the map loops over every tile when binning,
    /// and CPU devices cut an invocation's loops short past 65,535 iterations.
    pub const MAX_MAP_SIZE: u32 = 2048;
    /// The smallest map side.
    pub const MIN_MAP_SIZE: u32 = 16;
    /// The most cascades.
    pub const MAX_CASCADES: u32 = SHADOW_MAX_CASCADES;

    /// The default largest filter radius ([`ShadowSettings::max_radius`]) for maps of `map_size`
    /// texels: the default's 16, at most an eighth of the map (the most its guard band allows), so
    /// that on a small map the default of PCSS's search never blocks another method.
    pub fn default_max_radius(map_size: u32) -> f32 {
        (map_size as f32 / 8.0).min(Self::default().max_radius)
    }

    /// Checks every setting, naming the one out of range.
    pub fn validate(&self) -> Result<()> {
        let fail = |what: String| Err(Error::Invalid(format!("shadow maps: {what}")));
        if !(Self::MIN_MAP_SIZE..=Self::MAX_MAP_SIZE).contains(&self.map_size) {
            return fail(format!(
                "map size {} must be {} to {} texels",
                self.map_size,
                Self::MIN_MAP_SIZE,
                Self::MAX_MAP_SIZE
            ));
        }
        if !(1..=Self::MAX_CASCADES).contains(&self.cascades) {
            return fail(format!("{} cascades: must be 1 to {}", self.cascades, Self::MAX_CASCADES));
        }
        if !(0.0..=1.0).contains(&self.cascade_split) {
            return fail(format!("cascade split {} must be in [0, 1]", self.cascade_split));
        }
        for (name, value, max) in [
            ("depth bias", self.depth_bias, 64.0),
            ("slope bias", self.slope_bias, 64.0),
            ("normal bias", self.normal_bias, 64.0),
            ("light radius", self.light_radius, f32::MAX),
            ("sun angle", self.sun_angle, 0.5),
        ] {
            if !(value.is_finite() && (0.0..=max).contains(&value)) {
                return fail(format!("{name} {value} must be finite, at least 0 and at most {max}"));
            }
        }
        let guard_max = self.map_size as f32 / 8.0;
        if !(self.max_radius.is_finite() && self.max_radius >= 0.5 && self.max_radius <= guard_max) {
            return fail(format!(
                "largest filter radius {} texels must be 0.5 to {guard_max} (an eighth of the map size {})",
                self.max_radius, self.map_size
            ));
        }
        if !(self.pcf_radius.is_finite() && self.pcf_radius > 0.0 && self.pcf_radius <= self.max_radius) {
            return fail(format!(
                "PCF radius {} texels must be above 0 and at most the largest filter radius {}",
                self.pcf_radius, self.max_radius
            ));
        }
        if self.moment_blur as f32 > self.max_radius {
            return fail(format!(
                "moment blur radius {} texels must be at most the largest filter radius {}",
                self.moment_blur, self.max_radius
            ));
        }
        if !(self.moment_bias.is_finite() && self.moment_bias > 0.0 && self.moment_bias < 0.1) {
            return fail(format!("moment bias {} must be in (0, 0.1)", self.moment_bias));
        }
        Ok(())
    }

    /// Texels around a cube face or spot cone the map renders beyond it, so filters centred in
    /// the face stay inside the map.
    fn guard(&self) -> u32 {
        self.max_radius.max(self.pcf_radius).max(self.moment_blur as f32).ceil() as u32 + 2
    }

    /// Texels around where a shaded point lands in a directional cascade that its lookup may
    /// read: the method's filter (`shadow.glsl`: PCF's taps within its radius, PCSS's search and
    /// taps within the largest radius, the moments' blur, each with a bilinear texel more), the
    /// normal offset (at most that many texels in an orthographic layer), and a texel to spare.
    fn reach(&self) -> f32 {
        let filter = match self.method {
            ShadowMethod::RayTraced | ShadowMethod::Hard => 0.0,
            ShadowMethod::Pcf => self.pcf_radius.ceil() + 1.0,
            ShadowMethod::Pcss => self.max_radius.ceil() + 1.0,
            ShadowMethod::Moments => self.moment_blur as f32 + 1.0,
        };
        filter + self.normal_bias.ceil() + 1.0
    }
}

/// Where the layers of every punctual light are and how each is placed, computed on the host
/// ([`ShadowPlan::new`]).
#[derive(Debug, Clone)]
pub struct ShadowPlan {
    /// Every layer in order, lights in scene order.
    pub layers: Vec<GpuShadowLayer>,
    /// Per punctual light: (its first layer, layer count, `SHADOW_LIGHT_*`).
    pub lights: Vec<(u32, u32, u32)>,
    /// Per layer, the tiles ([`SHADOW_TILE`]² texels) the rasterizer renders: first and last
    /// tile column, first and last tile row. The whole layer but for directional cascades with
    /// [`ShadowSettings::cascade_windows`]; the layer's texels outside are undefined.
    pub windows: Vec<[u32; 4]>,
}

impl ShadowPlan {
    /// Places the layers of `lights` for a scene within `bounds`, seen by `camera` over an image
    /// of `size` (directional cascades follow the view).
    pub fn new(
        lights: &[GpuLight],
        bounds: [[f32; 3]; 2],
        camera: &Camera,
        size: (u32, u32),
        settings: &ShadowSettings,
    ) -> Result<Self> {
        settings.validate()?;
        let (lo, hi) = (Vec3::from(bounds[0]), Vec3::from(bounds[1]));
        let corners: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]))
            .collect();
        let s = settings.map_size;
        let mut plan = ShadowPlan { layers: Vec::new(), lights: Vec::new(), windows: Vec::new() };
        let whole = [0, 0, s.div_ceil(SHADOW_TILE) - 1, s.div_ceil(SHADOW_TILE) - 1];
        for light in lights {
            let first = plan.layers.len() as u32;
            let position = Vec3::from_slice(&light.position_range[..3]);
            let direction = Vec3::from_slice(&light.direction_kind[..3]).normalize_or(Vec3::NEG_Z);
            let kind = light.direction_kind[3];
            let far = corners.iter().map(|c| c.distance(position)).fold(1e-6, f32::max);
            let record = if kind == GpuLight::DIRECTIONAL {
                for (layer, window) in cascades(direction, &corners, camera, size, settings) {
                    plan.layers.push(layer);
                    plan.windows.push(if settings.cascade_windows { window } else { whole });
                }
                SHADOW_LIGHT_CASCADES
            } else if kind == GpuLight::SPOT && light.cone[0] >= SPOT_SINGLE_MAP_MAX_ANGLE.cos() {
                let tan = (1.0 - light.cone[0] * light.cone[0]).max(0.0).sqrt() / light.cone[0];
                plan.layers.push(perspective(position, direction, tan, far, s, settings.guard()));
                plan.windows.push(whole);
                SHADOW_LIGHT_SINGLE
            } else {
                for axis in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
                    plan.layers.push(perspective(position, axis, 1.0, far, s, settings.guard()));
                    plan.windows.push(whole);
                }
                SHADOW_LIGHT_CUBE
            };
            plan.lights.push((first, plan.layers.len() as u32 - first, record));
        }
        for (i, layer) in plan.layers.iter_mut().enumerate() {
            layer.offset = i as u32 * s * s;
            layer.size = s;
        }
        Ok(plan)
    }

    /// The `shadow_texels` the lighting pass reads: the filter settings, each light's record
    /// (the texel of its first layer, the layer count, the kind), then each layer's texels.
    pub fn texels(&self, settings: &ShadowSettings) -> Vec<[u32; 4]> {
        let f = |v: [f32; 4]| v.map(f32::to_bits);
        let mut out = vec![
            f([settings.depth_bias, settings.slope_bias, settings.normal_bias, settings.pcf_radius]),
            f([settings.light_radius, settings.sun_angle.tan(), settings.max_radius, settings.moment_bias]),
        ];
        debug_assert_eq!(out.len() as u32, SHADOW_HEADER_TEXELS);
        let layers_at = SHADOW_HEADER_TEXELS + self.lights.len() as u32;
        out.extend(
            self.lights
                .iter()
                .map(|&(first, count, kind)| [layers_at + SHADOW_LAYER_TEXELS * first, count, kind, 0]),
        );
        // The layers as they lie in memory, `SHADOW_LAYER_TEXELS` texels each (`shadow.glsl`
        // reads them field by field).
        out.extend_from_slice(bytemuck::cast_slice::<GpuShadowLayer, [u32; 4]>(&self.layers));
        out
    }
}

/// A perspective layer from `origin` looking along `axis` over a square of half-angle tangent
/// `tan` (widened by `guard` texels each side), depths up to `far`.
fn perspective(origin: Vec3, axis: Vec3, tan: f32, far: f32, size: u32, guard: u32) -> GpuShadowLayer {
    let s = size as f32;
    let tan = tan * s / (s - 2.0 * guard as f32);
    let right = axis.any_orthonormal_vector();
    let up = axis.cross(right);
    let half = 0.5 * s;
    let row = |v: Vec3| v.extend(-v.dot(origin)).to_array();
    GpuShadowLayer {
        row0: row(half * (right / tan + axis)),
        row1: row(half * (-up / tan + axis)),
        row2: row(axis),
        row3: row(axis),
        kind: SHADOW_PERSPECTIVE,
        texel_world: 2.0 * tan / s,
        depth_far: far,
        ..Default::default()
    }
}

/// A directional light's cascades over the view depth of `camera` (image `size`), each an
/// orthographic layer around the bounding sphere of its slice of the view frustum, centred on a
/// whole texel; depth measured along the light from the scene's nearest corner. With each, the
/// tiles that can be read ([`ShadowPlan::windows`]): the box of the slice's eight corners in the
/// layer, widened by the method's reach ([`ShadowSettings::reach`]: filter, normal offset, a texel).
fn cascades(
    direction: Vec3,
    corners: &[Vec3],
    camera: &Camera,
    size: (u32, u32),
    settings: &ShadowSettings,
) -> Vec<(GpuShadowLayer, [u32; 4])> {
    let s = settings.map_size as f32;
    let eye = Vec3::from(camera.position);
    let forward = Vec3::from(camera.forward).normalize();
    let image_aspect = size.0 as f32 / size.1.max(1) as f32;
    let aspect =
        if camera.orthographic.is_some() { image_aspect } else { camera.aspect.unwrap_or(image_aspect) };
    // A slice's corners at view depth z lie sqrt(k2) z off the axis (pinhole), or sqrt(k2)
    // (orthographic: the view's half diagonal at every depth).
    let (half_x, half_y) = camera.half_extent(1.0, aspect);
    let k2 = half_x * half_x + half_y * half_y;
    // The cascades reach the scene's farthest corner from the eye, rounded up to a power of two:
    // independent of where the camera looks, and of small moves, so the slices (and with them
    // each cascade's texel size) stay put while the view changes.
    let near = camera.znear.max(1e-4);
    let reach = corners.iter().map(|c| c.distance(eye)).fold(near * 1.01, f32::max);
    let far = reach.log2().ceil().exp2();
    let n = settings.cascades;
    let split = |i: u32| {
        let t = i as f32 / n as f32;
        let log = near * (far / near).powf(t);
        let uniform = near + (far - near) * t;
        settings.cascade_split * log + (1.0 - settings.cascade_split) * uniform
    };
    let right = direction.any_orthonormal_vector();
    let up = direction.cross(right);
    let depth0 = corners.iter().map(|c| c.dot(direction)).fold(f32::INFINITY, f32::min);
    let depth1 = corners.iter().map(|c| c.dot(direction)).fold(f32::NEG_INFINITY, f32::max);
    let widen = s / (s - 2.0 * settings.guard() as f32);
    let view_right = forward.cross(Vec3::from(camera.up)).normalize();
    let view_up = view_right.cross(forward);
    let reach = settings.reach();
    let last_tile = (settings.map_size.div_ceil(SHADOW_TILE) - 1) as f32;
    (0..n)
        .map(|i| {
            let (za, zb) = (if i == 0 { 0.0 } else { split(i) }, split(i + 1));
            // The smallest sphere around the slice's eight corners has its centre on the axis.
            let (zc, radius) = if camera.orthographic.is_some() {
                (0.5 * (za + zb), (0.25 * (zb - za).powi(2) + k2).sqrt())
            } else {
                let zc = ((1.0 + k2) * 0.5 * (za + zb)).min(zb);
                (zc, ((zc - za).powi(2) + za * za * k2).max((zb - zc).powi(2) + zb * zb * k2).sqrt())
            };
            let texel = 2.0 * radius * widen / s;
            let centre = eye + forward * zc;
            let snap = |v: f32| (v / texel).floor() * texel;
            let (cx, cy) = (snap(centre.dot(right)), snap(centre.dot(up)));
            let layer = GpuShadowLayer {
                row0: (right / texel).extend(-cx / texel + 0.5 * s).to_array(),
                row1: (-up / texel).extend(cy / texel + 0.5 * s).to_array(),
                row2: direction.extend(-depth0).to_array(),
                row3: Vec4::W.to_array(),
                kind: SHADOW_ORTHOGRAPHIC,
                texel_world: texel,
                depth_far: (depth1 - depth0).max(1e-6),
                split: if i + 1 == n { f32::MAX } else { zb },
                ..Default::default()
            };
            // The slice's corners in texels, their box widened, as tiles.
            let (mut lo, mut hi) = (glam::Vec2::splat(f32::INFINITY), glam::Vec2::splat(f32::NEG_INFINITY));
            for corner in 0..8 {
                let z = if corner & 1 == 0 { za } else { zb };
                let scale = if camera.orthographic.is_some() { 1.0 } else { z };
                let sx = if corner & 2 == 0 { -half_x } else { half_x };
                let sy = if corner & 4 == 0 { -half_y } else { half_y };
                let p = eye + forward * z + (view_right * sx + view_up * sy) * scale;
                let t = glam::Vec2::new(
                    Vec3::from_slice(&layer.row0[..3]).dot(p) + layer.row0[3],
                    Vec3::from_slice(&layer.row1[..3]).dot(p) + layer.row1[3],
                );
                (lo, hi) = (lo.min(t), hi.max(t));
            }
            let tile = |v: f32| ((v / SHADOW_TILE as f32).floor().clamp(0.0, last_tile)) as u32;
            let window = [tile(lo.x - reach), tile(lo.y - reach), tile(hi.x + reach), tile(hi.y + reach)];
            (layer, window)
        })
        .collect()
}

/// Every layer's depth (and moments) for one scene's punctual lights, with the rasterizer's
/// working buffers, placed by a [`ShadowPlan`].
pub struct ShadowMaps {
    /// The settings they were made with.
    pub settings: ShadowSettings,
    /// The placement.
    pub plan: ShadowPlan,
    /// The lighting pass's records ([`ShadowPlan::texels`]).
    pub texels: TexelBuffer,
    /// Linear depth per texel, every layer (R32_SFLOAT texels).
    pub depth: TexelBuffer,
    /// Moments filtered along x (RGBA32_SFLOAT; one texel unless the method is moments).
    moments_x: TexelBuffer,
    /// Filtered moments (RGBA32_SFLOAT; one texel unless the method is moments).
    pub moments: TexelBuffer,
    tile_count: Buffer,
    tile_start: Buffer,
    /// One layer of depth bits for the small triangles' `atomicMin`.
    scratch: Buffer,
    lists: RasterLists,
    stats: Buffer,
    /// Per layer and tile: nonzero where rendered.
    marks: Buffer,
    /// Per layer, the rendered tiles.
    tile_list: Buffer,
    /// Per layer, the indirect dispatches over its rendered tiles and its large triangles
    /// ([`SHADOW_DISPATCH_WORDS`] words).
    dispatch: Buffer,
}

/// Two 16-bit coordinates as one push-constant word, x | y << 16 (`shadow_pack.glsl`'s
/// `shadow_unpack`).
fn pack_pair(x: u32, y: u32) -> u32 {
    x | y << 16
}

/// Byte offset of layer `layer`'s indirect dispatches in [`ShadowMaps`]' dispatch buffer
/// ([`SHADOW_DISPATCH_WORDS`] words a layer: the tiles' first, the fill's 16 bytes on).
fn dispatch_offset(layer: usize) -> u64 {
    4 * SHADOW_DISPATCH_WORDS as u64 * layer as u64
}

/// The view shadow maps are rendered for: with [`ShadowSettings::view_marks`] each directional
/// cascade renders only the tiles the G-buffer's pixels read. The G-buffer must hold this
/// camera's view when the maps' recording runs.
#[derive(Clone, Copy)]
pub struct ShadowView<'a> {
    /// The camera the G-buffer was rendered with.
    pub camera: &'a Camera,
    /// The G-buffer (its depth is read).
    pub gbuffer: &'a GBufferViews,
}

impl ShadowMaps {
    /// Allocates the maps `plan` places for `scene`, refusing more than
    /// [`ShadowMaps::MAX_BYTES`].
    pub fn new(ctx: &Context, plan: ShadowPlan, settings: &ShadowSettings, scene: &GpuScene) -> Result<Self> {
        let s = settings.map_size as u64;
        let layers = plan.layers.len() as u64;
        let moments = settings.method == ShadowMethod::Moments;
        let bytes = layers * s * s * if moments { 4 + 32 } else { 4 };
        if bytes > Self::MAX_BYTES {
            return Err(Error::Invalid(format!(
                "shadow maps: {layers} layers of {s}x{s} need {} MiB, more than {} MiB: lower --shadow-map-size",
                bytes >> 20,
                Self::MAX_BYTES >> 20
            )));
        }
        let tiles = (settings.map_size.div_ceil(SHADOW_TILE) as u64).pow(2);
        let storage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        let per_tile =
            |name| Buffer::new(ctx, name, 4 * layers.max(1) * tiles, storage, MemoryLocation::GpuOnly);
        let texels = TexelBuffer::upload(
            ctx,
            "shadow records",
            &plan.texels(settings),
            raw::Format::R32G32B32A32_UINT,
            16,
        )?;
        let f32x4 = raw::Format::R32G32B32A32_SFLOAT;
        let no_usage = raw::BufferUsageFlags::empty();
        let moment_texels = if moments { layers * s * s } else { 1 };
        let stats = Buffer::new(
            ctx,
            "shadow stats",
            std::mem::size_of::<ShadowStats>() as u64,
            storage | raw::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            settings: *settings,
            texels,
            depth: TexelBuffer::new(
                ctx,
                "shadow depth",
                layers * s * s,
                raw::Format::R32_SFLOAT,
                4,
                no_usage,
            )?,
            moments_x: TexelBuffer::new(ctx, "shadow moments x", moment_texels, f32x4, 16, no_usage)?,
            moments: TexelBuffer::new(ctx, "shadow moments", moment_texels, f32x4, 16, no_usage)?,
            tile_count: Buffer::new(ctx, "shadow tile counts", 4 * tiles, storage, MemoryLocation::GpuOnly)?,
            tile_start: Buffer::new(ctx, "shadow tile starts", 4 * tiles, storage, MemoryLocation::GpuOnly)?,
            scratch: Buffer::new(ctx, "shadow scratch layer", 4 * s * s, storage, MemoryLocation::GpuOnly)?,
            lists: RasterLists::new(ctx, scene, "shadow", tiles)?,
            stats,
            marks: per_tile("shadow tile marks")?,
            tile_list: per_tile("shadow tile lists of layers")?,
            dispatch: Buffer::new(
                ctx,
                "shadow tile dispatches",
                4 * SHADOW_DISPATCH_WORDS as u64 * layers.max(1),
                storage | raw::BufferUsageFlags::INDIRECT_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?,
            plan,
        })
    }

    /// The most memory the maps of one scene may take.
    pub const MAX_BYTES: u64 = 1 << 30;

    /// Tile-list entries the maps hold.
    pub fn capacity(&self) -> u32 {
        self.lists.capacity
    }

    /// Triangles one tile may hold: each texel's invocation loops over them, and CPU devices
    /// (llvmpipe) cut an invocation's loops short past 65,535 iterations.
    pub const MAX_TILE_TRIANGLES: u32 = 60_000;

    /// What the last submitted rendering needed (read back; submits a copy): the tile-list
    /// entries and the fullest tile's triangles of the neediest layer.
    pub fn stats(&self, ctx: &Context) -> Result<ShadowStats> {
        Ok(self.stats.read::<ShadowStats>(ctx)?[0])
    }

    /// After a submitted rendering: `None` when every layer's tile lists fit, else the entries
    /// needed (the maps are incomplete: [`ShadowMaps::reserve`] them and render again). An error
    /// when a tile held more than [`ShadowMaps::MAX_TILE_TRIANGLES`].
    pub fn check(&self, ctx: &Context) -> Result<Option<u32>> {
        let stats = self.stats(ctx)?;
        log::debug!(
            "shadow maps: {} layers, at most {} tile-list entries and {} triangles in a tile per layer",
            self.plan.layers.len(),
            stats.entries,
            stats.tile_max
        );
        self.lists.check(stats, "shadow maps", ": raise the map size")
    }

    /// Grows the tile lists to hold `entries` (and a quarter more).
    pub fn reserve(&mut self, ctx: &Context, entries: u32) -> Result<()> {
        self.lists.reserve(ctx, entries)
    }

    /// Per layer, the tiles ([`SHADOW_TILE`]² texels) the last submitted rendering rendered (read
    /// back; submits a copy); texels of the others are undefined.
    pub fn rendered_tiles(&self, ctx: &Context) -> Result<Vec<u32>> {
        let words: Vec<u32> = self.dispatch.read(ctx)?;
        Ok(words.chunks(SHADOW_DISPATCH_WORDS as usize).map(|d| d[0]).collect())
    }

    /// Reads every layer's depth back (tests and dumps), row-major per layer.
    pub fn read_depth(&self, ctx: &Context) -> Result<Vec<f32>> {
        let n = self.plan.layers.len() * (self.settings.map_size as usize).pow(2);
        Ok(self.depth.buffer.read::<f32>(ctx)?[..n].to_vec())
    }
}

/// The compute rasterizer's triangles and tile lists, shared by the shadow maps and the
/// visibility buffer ([`crate::passes::visibility`]): the BVH positions to rasterize, the large
/// triangles one layer lists and their set-ups, and the tiles' lists with their capacity.
pub(crate) struct RasterLists {
    /// The BVH positions to rasterize ([`GpuScene::unique_triangles`]).
    pub raster_tris: Buffer,
    pub raster_count: u32,
    /// One layer's large triangles that enter a rendered tile (the fill's work list).
    pub large_tris: Buffer,
    /// The large triangles' edge functions and depths (three `vec4` each).
    pub setup: TexelBuffer,
    /// The lists: `capacity` triangle indices.
    pub tile_tris: Buffer,
    pub capacity: u32,
    /// The buffers' names begin with it.
    prefix: &'static str,
}

impl RasterLists {
    /// The lists for `scene` over layers of `tiles` tiles (the first capacity a guess that
    /// [`RasterLists::reserve`] corrects).
    pub fn new(ctx: &Context, scene: &GpuScene, prefix: &'static str, tiles: u64) -> Result<Self> {
        let unique = scene.unique_triangles();
        let storage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        let capacity = (4 * unique.len() as u64).max(4 * tiles).max(1 << 16).min(u32::MAX as u64 / 8) as u32;
        Ok(Self {
            raster_tris: Buffer::upload(
                ctx,
                &format!("{prefix} triangles"),
                &unique,
                raw::BufferUsageFlags::STORAGE_BUFFER,
            )?,
            raster_count: unique.len() as u32,
            large_tris: Buffer::new(
                ctx,
                &format!("{prefix} large triangles"),
                4 * unique.len().max(1) as u64,
                storage,
                MemoryLocation::GpuOnly,
            )?,
            setup: TexelBuffer::new(
                ctx,
                &format!("{prefix} triangle set-ups"),
                3 * scene.bvh_stats.references as u64,
                raw::Format::R32G32B32A32_SFLOAT,
                16,
                raw::BufferUsageFlags::STORAGE_BUFFER,
            )?,
            tile_tris: Self::lists(ctx, prefix, capacity)?,
            capacity,
            prefix,
        })
    }

    fn lists(ctx: &Context, prefix: &str, capacity: u32) -> Result<Buffer> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        Buffer::new(ctx, &format!("{prefix} tile lists"), 4 * capacity as u64, usage, MemoryLocation::GpuOnly)
    }

    /// After a submitted rendering that counted `stats`: `None` when the lists held every entry,
    /// else the entries needed; an error (naming `what`, with `advice`) when a tile held more
    /// than [`ShadowMaps::MAX_TILE_TRIANGLES`].
    pub fn check(&self, stats: ShadowStats, what: &str, advice: &str) -> Result<Option<u32>> {
        if stats.tile_max > ShadowMaps::MAX_TILE_TRIANGLES {
            return Err(Error::Invalid(format!(
                "{what}: one {SHADOW_TILE}x{SHADOW_TILE} tile holds {} triangles, more than {}{advice}",
                stats.tile_max,
                ShadowMaps::MAX_TILE_TRIANGLES
            )));
        }
        Ok((stats.entries > self.capacity).then_some(stats.entries))
    }

    /// Grows the lists to hold `entries` (and a quarter more).
    pub fn reserve(&mut self, ctx: &Context, entries: u32) -> Result<()> {
        let capacity = entries.saturating_add(entries / 4).min(u32::MAX / 8);
        self.tile_tris = Self::lists(ctx, self.prefix, capacity)?;
        self.capacity = capacity;
        Ok(())
    }
}

/// The shadow-map kernels.
pub struct ShadowPass {
    count: Pipeline<shadow_bin::Kernel>,
    fill: Pipeline<shadow_bin::Kernel>,
    scan: Pipeline<shadow_scan::Kernel>,
    raster: Pipeline<shadow_raster::Kernel>,
    moments: Pipeline<shadow_moments::Kernel>,
    mark: Pipeline<shadow_mark::Kernel>,
    tiles: Pipeline<shadow_tiles::Kernel>,
}

impl ShadowPass {
    /// Builds the pipelines (the rasterizer's alpha test as the scene needs it).
    pub fn new(ctx: &Context, scene: &GpuScene) -> Result<Self> {
        Ok(Self {
            count: Pipeline::for_scene(ctx, scene, &shadow_bin::Spec { fill: false })?,
            fill: Pipeline::for_scene(ctx, scene, &shadow_bin::Spec { fill: true })?,
            scan: Pipeline::plain(ctx)?,
            raster: Pipeline::for_scene(ctx, scene, &shadow_raster::Spec {})?,
            moments: Pipeline::plain(ctx)?,
            mark: Pipeline::plain(ctx)?,
            tiles: Pipeline::plain(ctx)?,
        })
    }

    /// Timer entries [`ShadowPass::record`] uses for `maps`: one per step and layer, and the
    /// marks.
    pub fn timer_entries(maps: &ShadowMaps) -> u32 {
        maps.plan.layers.len() as u32 * 7 + 1
    }

    /// Records every layer of `maps` (and their moments when the method needs them), each step
    /// timed under its kernel's name into `timer` when
    /// given (room for [`ShadowPass::timer_entries`]). With a `view` and
    /// [`ShadowSettings::view_marks`], cascades render only the tiles its pixels read. Never
    /// submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        maps: &ShadowMaps,
        view: Option<ShadowView<'_>>,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let cmd = rec.cmd();
        let mut step = |name: &str, record: &mut dyn FnMut() -> Result<()>| {
            GpuTimer::time(&mut timer, cmd, name, record)
        };
        let s = maps.settings.map_size;
        let tiles = s.div_ceil(SHADOW_TILE);
        let layer_bytes = 4 * (tiles * tiles) as u64;
        let view = view.filter(|_| maps.settings.view_marks);
        rec.fill(&maps.tile_count, 0);
        rec.fill(&maps.stats, 0);
        rec.fill(&maps.scratch, f32::INFINITY.to_bits());
        rec.fill(&maps.dispatch, 0);
        // Test builds poison every texel first (depth and moments 0: an occluder at the light):
        // a lit point whose lookup reads one left unrendered shows as shadowed (tests/shadow.rs
        // compares against whole layers).
        #[cfg(feature = "testing")]
        for texels in [&maps.depth, &maps.moments_x, &maps.moments] {
            rec.fill(&texels.buffer, 0);
        }
        // Every tile of a window is marked but the cascades' for a view, which the view marks.
        for (first, count, kind) in &maps.plan.lights {
            let marked = view.is_none() || *kind != SHADOW_LIGHT_CASCADES;
            let at = *first as u64 * layer_bytes;
            rec.fill_range(&maps.marks, at, *count as u64 * layer_bytes, u32::from(marked));
        }
        if let Some(view) = view {
            let size = view.gbuffer.size;
            let params = ShadowMarkParams {
                camera: GpuCamera::new(view.camera, size),
                size: [size.0, size.1],
                lights: maps.plan.lights.len() as u32,
                layers_at: SHADOW_HEADER_TEXELS + maps.plan.lights.len() as u32,
                tiles,
                reach: maps.settings.reach(),
                rounds: maps.settings.mark_rounds,
                box_limit: maps.settings.mark_box,
            };
            let resources = shadow_mark::Resources {
                gb: view.gbuffer,
                shadow_texels: &maps.texels,
                tile_marks: &maps.marks,
            };
            step("shadow_mark", &mut || {
                // An invocation per block of pixels.
                self.mark.record(
                    rec,
                    &resources,
                    &params,
                    [size.0.div_ceil(SHADOW_MARK_BLOCK), size.1.div_ceil(SHADOW_MARK_BLOCK), 1],
                )
            })?;
        }
        let tri_count = maps.lists.raster_count;
        let bins = shadow_bin::Resources {
            scene,
            raster_tris: &maps.lists.raster_tris,
            tile_count: &maps.tile_count,
            tile_start: &maps.tile_start,
            tile_tris: &maps.lists.tile_tris,
            shadow_scratch: &maps.scratch,
            tile_setup: &maps.lists.setup.buffer,
            tile_marks: &maps.marks,
            large_tris: &maps.lists.large_tris,
            tile_dispatch: &maps.dispatch,
        };
        let listing = shadow_tiles::Resources {
            tile_marks: &maps.marks,
            tile_list: &maps.tile_list,
            tile_dispatch: &maps.dispatch,
        };
        for (i, (layer, window)) in maps.plan.layers.iter().zip(&maps.plan.windows).enumerate() {
            let params = ShadowRasterParams {
                row0: layer.row0,
                row1: layer.row1,
                row2: layer.row2,
                row3: layer.row3,
                size: s,
                tiles,
                tri_count,
                offset: layer.offset,
                capacity: maps.lists.capacity,
                window_lo: pack_pair(window[0], window[1]),
                window_hi: pack_pair(window[2], window[3]),
                list_at: i as u32 * tiles * tiles,
            };
            // The window's tiles.
            let span = [window[2] - window[0] + 1, window[3] - window[1] + 1];
            step("shadow_tiles", &mut || self.tiles.record(rec, &listing, &params, [span[0], span[1], 1]))?;
            let dispatch_at = dispatch_offset(i);
            step("shadow_bin", &mut || self.count.record(rec, &bins, &params, [tri_count, 1, 1]))?;
            let scan = shadow_scan::Resources {
                tile_count: &maps.tile_count,
                tile_start: &maps.tile_start,
                stats: &maps.stats,
            };
            step("shadow_scan", &mut || self.scan.record(rec, &scan, &params, [256, 1, 1]))?;
            step("shadow_fill", &mut || {
                self.fill.bind(rec, &bins)?;
                self.fill.push_constants(rec, &params)?;
                self.fill.dispatch_indirect(rec, &maps.dispatch, dispatch_at + 16);
                Ok(())
            })?;
            let raster = shadow_raster::Resources {
                scene,
                tile_count: &maps.tile_count,
                tile_start: &maps.tile_start,
                tile_tris: &maps.lists.tile_tris,
                setup_texels: &maps.lists.setup,
                tile_list: &maps.tile_list,
                shadow_scratch: &maps.scratch,
                shadow_depth: &maps.depth,
            };
            step("shadow_raster", &mut || {
                self.raster.bind(rec, &raster)?;
                self.raster.push_constants(rec, &params)?;
                self.raster.dispatch_indirect(rec, &maps.dispatch, dispatch_at);
                Ok(())
            })?;
        }
        if maps.settings.method == ShadowMethod::Moments {
            let resources = shadow_moments::Resources {
                shadow_depth: &maps.depth,
                moments_x: &maps.moments_x,
                shadow_moments: &maps.moments,
                tile_list: &maps.tile_list,
            };
            for (i, (layer, window)) in maps.plan.layers.iter().zip(&maps.plan.windows).enumerate() {
                // The window's texels (a last tile may reach past the layer's edge).
                let first = [window[0] * SHADOW_TILE, window[1] * SHADOW_TILE];
                let span = [
                    ((window[2] + 1) * SHADOW_TILE).min(s) - first[0],
                    ((window[3] + 1) * SHADOW_TILE).min(s) - first[1],
                ];
                for direction in 0..2 {
                    let params = ShadowMomentParams {
                        offset: layer.offset,
                        size: s,
                        radius: maps.settings.moment_blur,
                        direction,
                        depth_far: layer.depth_far,
                        first: pack_pair(first[0], first[1]),
                        last: pack_pair(first[0] + span[0] - 1, first[1] + span[1] - 1),
                        list_at: i as u32 * tiles * tiles,
                    };
                    step("shadow_moments", &mut || {
                        self.moments.bind(rec, &resources)?;
                        self.moments.push_constants(rec, &params)?;
                        self.moments.dispatch_indirect(rec, &maps.dispatch, dispatch_offset(i));
                        Ok(())
                    })?;
                }
            }
        }
        Ok(())
    }
}
