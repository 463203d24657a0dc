//! The rasterized G-buffer's first half: a visibility buffer (Burns and Hunt 2013) from the
//! compute rasterizer the shadow maps use, with the camera as its one layer.
//!
//! Each pixel keeps the nearest triangle through its centre as one 64-bit word, the view depth's
//! bits above the triangle's BVH index, by `atomicMin` on a storage buffer: positive floats order
//! as their bits, so the nearest wins, and equally near triangles go to the lower index. The
//! kernels are the shadow rasterizer's (`raster_bin.glsl`, `raster_tile.glsl`: binned 16 × 16
//! tiles, watertight homogeneous edge functions with a tie rule, small triangles drawing
//! themselves, a tile's depth cull) with the camera's rows: pixels for texels, view depth for the
//! light's. The G-buffer kernel (`gbuffer.comp` with `raster`) then resolves each pixel: the
//! pixel's ray meets its triangle in the traversal's own watertight terms (without their inside
//! test: a centre within rounding of an edge is a tie either way), and every attribute is
//! evaluated as the ray-cast G-buffer evaluates it.
//!
//! The one 64-bit atomic needs `shaderInt64` and `shaderBufferInt64Atomics`: lavapipe (Mesa 22.3)
//! offers both, as desktop GPUs do. Without them, and for scenes the rasterizer cannot draw
//! ([`VisibilityBuffer::unsupported`]: implicit shapes, blended materials), the G-buffer is
//! ray-cast.

use crate::error::{Error, Result};
use crate::gpu::kernels::{shadow_scan, shadow_tiles, vis_bin, vis_raster};
use crate::gpu::layout::{GpuCamera, ShadowRasterParams, ShadowStats, SHADOW_DISPATCH_WORDS, SHADOW_TILE};
use crate::gpu::scene::GpuScene;
use crate::gpu::{Pipeline, SceneFeatures};
use crate::passes::shadow::RasterLists;
use crate::scene::Camera;
use crate::vk::{raw, Buffer, Context, GpuTimer, Recorder};
use gpu_allocator::MemoryLocation;

/// How the hybrid frame finds each pixel's first surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum GBufferMethod {
    /// Rasterized into a visibility buffer, then resolved; ray-cast where the device or the
    /// scene does not allow it ([`VisibilityBuffer::unsupported`]). The same G-buffer as
    /// [`GBufferMethod::Raycast`]'s but for ties at triangle edges (tests/visibility.rs), and
    /// cheaper where primary rays cost most (large scenes at high resolutions: BENCHMARKS.md).
    #[default]
    Raster,
    /// One ray per pixel through the BVH.
    Raycast,
}

/// The visibility buffer of one image size and scene, with the rasterizer's working buffers.
pub struct VisibilityBuffer {
    size: (u32, u32),
    /// The layer's side: the image's longer side (the rasterizer's layers are square; the
    /// window covers the image's tiles).
    side: u32,
    /// Per pixel (row-major, `side` a row) depth bits << 32 | triangle.
    pub(crate) visibility: Buffer,
    tile_count: Buffer,
    tile_start: Buffer,
    lists: RasterLists,
    marks: Buffer,
    tile_list: Buffer,
    dispatch: Buffer,
    stats: Buffer,
}

impl VisibilityBuffer {
    /// Why `scene`'s G-buffer cannot be rasterized on `ctx`'s device, or `None` when it can.
    pub fn unsupported(ctx: &Context, scene: &GpuScene) -> Option<&'static str> {
        if !ctx.info().int64_enabled {
            Some("the device has no 64-bit buffer atomics enabled (shaderInt64, shaderBufferInt64Atomics)")
        } else if scene.has_implicit {
            Some("the scene has implicit shapes, which the rasterizer cannot draw")
        } else if scene.has_blend {
            Some("the scene has blended materials, whose coverage is hashed per ray")
        } else {
            None
        }
    }

    /// Allocates the buffer for images of `size` of `scene`; an error where
    /// [`VisibilityBuffer::unsupported`] gives a reason.
    pub fn new(ctx: &Context, scene: &GpuScene, size: (u32, u32)) -> Result<Self> {
        if let Some(why) = Self::unsupported(ctx, scene) {
            return Err(Error::Invalid(format!("the G-buffer cannot be rasterized: {why}")));
        }
        let side = size.0.max(size.1).max(1);
        let tiles = side.div_ceil(SHADOW_TILE) as u64;
        let tiles = tiles * tiles;
        let storage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        let per_tile = |name| Buffer::new(ctx, name, 4 * tiles, storage, MemoryLocation::GpuOnly);
        Ok(Self {
            size,
            side,
            visibility: Buffer::new(
                ctx,
                "visibility buffer",
                8 * side as u64 * side as u64,
                storage | raw::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?,
            tile_count: per_tile("visibility tile counts")?,
            tile_start: per_tile("visibility tile starts")?,
            lists: RasterLists::new(ctx, scene, "visibility", tiles)?,
            marks: per_tile("visibility tile marks")?,
            tile_list: per_tile("visibility tile list")?,
            dispatch: Buffer::new(
                ctx,
                "visibility dispatches",
                4 * SHADOW_DISPATCH_WORDS as u64,
                storage | raw::BufferUsageFlags::INDIRECT_BUFFER,
                MemoryLocation::GpuOnly,
            )?,
            stats: Buffer::new(
                ctx,
                "visibility stats",
                std::mem::size_of::<ShadowStats>() as u64,
                storage | raw::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
            )?,
        })
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The visibility buffer's row length in pixels.
    pub fn stride(&self) -> u32 {
        self.side
    }

    /// After a submitted frame: `None` when the tile lists held every entry, else the entries
    /// needed (that frame's visibility is incomplete: [`VisibilityBuffer::reserve`] and render
    /// again). An error when one tile held more triangles than a CPU device's loops allow.
    pub fn check(&self, ctx: &Context) -> Result<Option<u32>> {
        let stats = self.stats.read::<ShadowStats>(ctx)?[0];
        log::debug!(
            "visibility buffer: {} tile-list entries, {} triangles in the fullest tile",
            stats.entries,
            stats.tile_max
        );
        self.lists.check(stats, "visibility buffer", "")
    }

    /// Grows the tile lists to hold `entries` (and a quarter more).
    pub fn reserve(&mut self, ctx: &Context, entries: u32) -> Result<()> {
        self.lists.reserve(ctx, entries)
    }

    /// Reads the visibility buffer back (tests): per pixel of the image, row-major, the triangle's
    /// BVH index ([`crate::gpu::layout::RASTER_NO_TRIANGLE`] where none) and its view depth.
    pub fn read(&self, ctx: &Context) -> Result<Vec<(u32, f32)>> {
        let words: Vec<u64> = self.visibility.read(ctx)?;
        let (w, h) = self.size;
        Ok((0..h as usize)
            .flat_map(|y| (0..w as usize).map(move |x| y * self.side as usize + x))
            .map(|i| (words[i] as u32, f32::from_bits((words[i] >> 32) as u32)))
            .collect())
    }
}

/// The camera's rows for the rasterizer: world point p to (x w, y w, depth, w) with x, y in
/// pixels (row 0 at the top) less the camera's jitter (so that the rasterizer's pixel centres are
/// the pixels' sample positions), depth the view depth along the forward axis and w that depth (a
/// pinhole) or 1 (orthographic): `camera.glsl`'s projection, computed in f64 from the same f32
/// camera the G-buffer's rays start from.
fn camera_rows(camera: &GpuCamera) -> [[f32; 4]; 4] {
    let v = |a: [f32; 3]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (o, f, r, u) = (v(camera.origin), v(camera.forward), v(camera.right), v(camera.up));
    let (hw, hh) = (camera.image_width as f64 / 2.0, camera.image_height as f64 / 2.0);
    let [jx, jy] = camera.jitter().map(f64::from);
    let a = r / r.length_squared();
    let b = u / u.length_squared();
    // A row (n, -n · o) + c: the affine function n · (p - o) + c.
    let row = |n: glam::DVec3, c: f64| {
        let w = c - n.dot(o);
        [n.x as f32, n.y as f32, n.z as f32, w as f32]
    };
    let depth = row(f, 0.0);
    if camera.orthographic() {
        [row(a * hw, hw - jx), row(-b * hh, hh - jy), depth, [0.0, 0.0, 0.0, 1.0]]
    } else {
        [row((a + f) * hw - f * jx, 0.0), row((f - b) * hh - f * jy, 0.0), depth, depth]
    }
}

/// The visibility buffer's kernels.
pub struct VisibilityPass {
    count: Pipeline<vis_bin::Kernel>,
    fill: Pipeline<vis_bin::Kernel>,
    scan: Pipeline<shadow_scan::Kernel>,
    raster: Pipeline<vis_raster::Kernel>,
    tiles: Pipeline<shadow_tiles::Kernel>,
}

impl VisibilityPass {
    /// Builds the pipelines for scenes with `features` (the alpha test as they need it).
    pub fn for_features(ctx: &Context, features: &SceneFeatures) -> Result<Self> {
        Ok(Self {
            count: Pipeline::new(ctx, &vis_bin::Spec { fill: false }, Some(features))?,
            fill: Pipeline::new(ctx, &vis_bin::Spec { fill: true }, Some(features))?,
            scan: Pipeline::plain(ctx)?,
            raster: Pipeline::new(ctx, &vis_raster::Spec {}, Some(features))?,
            tiles: Pipeline::plain(ctx)?,
        })
    }

    /// Timer entries [`VisibilityPass::record`] uses: one per step.
    pub const TIMER_ENTRIES: u32 = 6;

    /// Records the visibility of `scene` from `camera` into `vis`, each step timed under its
    /// kernel's name into `timer` when given (room for [`VisibilityPass::TIMER_ENTRIES`]). Never
    /// submits.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        scene: &GpuScene,
        camera: &Camera,
        vis: &VisibilityBuffer,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<()> {
        let cmd = rec.cmd();
        let mut step =
            |name: &str, rec: &mut Recorder<'_>, record: &mut dyn FnMut(&mut Recorder<'_>) -> Result<()>| {
                GpuTimer::time(&mut timer, cmd, name, || record(rec))
            };
        let (w, h) = vis.size;
        let tiles = vis.side.div_ceil(SHADOW_TILE);
        let [row0, row1, row2, row3] = camera_rows(&GpuCamera::new(camera, vis.size));
        let last = [w.div_ceil(SHADOW_TILE) - 1, h.div_ceil(SHADOW_TILE) - 1];
        let params = ShadowRasterParams {
            row0,
            row1,
            row2,
            row3,
            size: vis.side,
            tiles,
            tri_count: vis.lists.raster_count,
            offset: 0,
            capacity: vis.lists.capacity,
            window_lo: 0,
            window_hi: last[0] | last[1] << 16,
            list_at: 0,
        };
        step("vis_clear", rec, &mut |rec| {
            rec.fill(&vis.visibility, u32::MAX);
            rec.fill(&vis.tile_count, 0);
            rec.fill(&vis.stats, 0);
            rec.fill(&vis.dispatch, 0);
            rec.fill(&vis.marks, 1);
            Ok(())
        })?;
        let listing = shadow_tiles::Resources {
            tile_marks: &vis.marks,
            tile_list: &vis.tile_list,
            tile_dispatch: &vis.dispatch,
        };
        step("vis_tiles", rec, &mut |rec| {
            self.tiles.record(rec, &listing, &params, [last[0] + 1, last[1] + 1, 1])
        })?;
        let bins = vis_bin::Resources {
            scene,
            raster_tris: &vis.lists.raster_tris,
            tile_count: &vis.tile_count,
            tile_start: &vis.tile_start,
            tile_tris: &vis.lists.tile_tris,
            visibility: &vis.visibility,
            tile_setup: &vis.lists.setup.buffer,
            tile_marks: &vis.marks,
            large_tris: &vis.lists.large_tris,
            tile_dispatch: &vis.dispatch,
        };
        step("vis_bin", rec, &mut |rec| {
            self.count.record(rec, &bins, &params, [vis.lists.raster_count, 1, 1])
        })?;
        let scan = shadow_scan::Resources {
            tile_count: &vis.tile_count,
            tile_start: &vis.tile_start,
            stats: &vis.stats,
        };
        step("vis_scan", rec, &mut |rec| self.scan.record(rec, &scan, &params, [256, 1, 1]))?;
        step("vis_fill", rec, &mut |rec| {
            self.fill.bind(rec, &bins)?;
            self.fill.push_constants(rec, &params)?;
            self.fill.dispatch_indirect(rec, &vis.dispatch, 16);
            Ok(())
        })?;
        let raster = vis_raster::Resources {
            scene,
            tile_count: &vis.tile_count,
            tile_start: &vis.tile_start,
            tile_tris: &vis.lists.tile_tris,
            setup_texels: &vis.lists.setup,
            tile_list: &vis.tile_list,
            visibility: &vis.visibility,
        };
        step("vis_raster", rec, &mut |rec| {
            self.raster.bind(rec, &raster)?;
            self.raster.push_constants(rec, &params)?;
            self.raster.dispatch_indirect(rec, &vis.dispatch, 0);
            Ok(())
        })
    }
}
