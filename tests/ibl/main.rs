//! Split-sum image-based lighting: the kernels' tables against f64 references, and the hybrid
//! renderer's IBL against the path tracer.

#[path = "../common/mod.rs"]
mod common;

mod anisotropy;
mod furnace;
mod sheen;
mod split_sum;
mod tables;

use common::Gpu;
use umbra::environment::EnvironmentMap;
use umbra::gpu::scene::GpuScene;
use umbra::passes::deferred::{IblLookup, LightingSettings};
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::{Camera, Scene};
use umbra::split_sum::{texel_direction, LUT_SIZE};

fn scene_file(name: &str) -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .expect("scene loads")
}

/// A synthetic map of `w` × `h` from a radiance function of direction.
fn synthetic_map(w: usize, h: usize, f: impl Fn([f64; 3]) -> [f64; 3]) -> EnvironmentMap {
    let texels = (0..w * h).map(|i| f(texel_direction(i % w, i / w, w, h).0).map(|v| v as f32)).collect();
    EnvironmentMap::from_texels("synthetic", w, h, texels).unwrap()
}

/// Unit vector.
fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

/// A sky: nothing below the horizon, 0.5 sin(elevation) above it, and a disc of radiance 30
/// within 10° of elevation 50° towards +z (the sphere grid's camera side).
fn sky(d: [f64; 3]) -> [f64; 3] {
    if d[1] < 0.0 {
        return [0.0; 3];
    }
    let sun = unit([0.0, 50f64.to_radians().sin(), 50f64.to_radians().cos()]);
    let cos = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2];
    let disc = if cos > 10f64.to_radians().cos() { 30.0 } else { 0.0 };
    [0.5 * d[1] + disc, 0.45 * d[1] + disc, 0.4 * d[1] + disc]
}

/// Hybrid (IBL only, no AO; with `supersample` the colour is box-filtered from 4×4 samples per
/// pixel) and path-traced (one scattering event: direct environment light) renders of `scene`
/// under `env`, with the per-pixel view directions.
fn render_pair(
    gpu: &Gpu,
    scene: &Scene,
    map: Option<&EnvironmentMap>,
    env: [f32; 3],
    size: (u32, u32),
    spp: u32,
    supersample: bool,
) -> (umbra::render::HybridImage, umbra::render::PathImage, Vec<glam::Vec3>) {
    let (mut hybrids, pt, view) =
        render_lookups(gpu, scene, map, env, size, spp, supersample, &[IblLookup::Mirror]);
    (hybrids.remove(0), pt, view)
}

/// [`render_pair`] with one hybrid image per IBL lookup (the path-traced image is shared).
#[allow(clippy::too_many_arguments)]
fn render_lookups(
    gpu: &Gpu,
    scene: &Scene,
    map: Option<&EnvironmentMap>,
    env: [f32; 3],
    size: (u32, u32),
    spp: u32,
    supersample: bool,
    lookups: &[IblLookup],
) -> (Vec<umbra::render::HybridImage>, umbra::render::PathImage, Vec<glam::Vec3>) {
    let camera = scene.camera(None).unwrap();
    let mut gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    if let Some(map) = map {
        gpu_scene.set_environment(gpu, map).unwrap();
    }
    let mut hybrids = Vec::new();
    for &ibl_lookup in lookups {
        let lighting = LightingSettings { env, shadow_rays: 1, ibl: true, ibl_lookup, ..Default::default() };
        let mut hyb =
            hybrid(gpu, &gpu_scene, &camera, &HybridSettings { size, lighting, ..Default::default() })
                .unwrap();
        // The colour box-filtered like the path tracer's pixels: 4×4 centre samples per pixel (a
        // mirror's sharp reflections would otherwise differ by the pixel filter alone).
        let big = (4 * size.0, 4 * size.1);
        let fine = match supersample {
            true => {
                hybrid(
                    gpu,
                    &gpu_scene,
                    &camera,
                    &HybridSettings { size: big, lighting, ..Default::default() },
                )
                .unwrap()
                .color
            }
            false => Vec::new(),
        };
        for (i, c) in hyb.color.iter_mut().enumerate().filter(|_| supersample) {
            let (x, y) = (4 * (i as u32 % size.0), 4 * (i as u32 / size.0));
            let mut sum = [0.0f32; 4];
            for k in 0..16 {
                let f = fine[((y + k / 4) * big.0 + x + k % 4) as usize];
                for ch in 0..4 {
                    sum[ch] += f[ch] / 16.0;
                }
            }
            *c = sum;
        }
        hybrids.push(hyb);
    }
    let settings = PathSettings { size, spp, max_bounces: 1, env, ..Default::default() };
    let pt = path_trace(gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let c = umbra::gpu::layout::GpuCamera::new(&camera, size);
    let cam = (c.origin, c.forward, c.right, c.up);
    let v = glam::Vec3::from;
    let view = (0..size.0 * size.1)
        .map(|i| {
            let (x, y) = (i % size.0, i / size.0);
            let ndc =
                (2.0 * (x as f32 + 0.5) / size.0 as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / size.1 as f32);
            (v(cam.1) + ndc.0 * v(cam.2) + ndc.1 * v(cam.3)).normalize()
        })
        .collect();
    (hybrids, pt, view)
}

/// One sphere of radius 1 at the origin (a 160 × 80 UV sphere, so facets stay below 1.2°) of one
/// material, nothing else, no lights, seen from distance 3 along +z, filling most of the image.
fn sphere_scene(base: [f32; 3], metallic: f32, roughness: f32) -> Scene {
    let mut scene = scene_file("spheres.glb");
    scene.lights.clear();
    let mut m = scene.materials[0].clone();
    m.name = format!("metallic {metallic} roughness {roughness}");
    m.base_color_factor = [base[0], base[1], base[2], 1.0];
    (m.metallic, m.roughness) = (metallic, roughness);
    scene.materials = vec![m];
    let (segments, rings) = (160u32, 80u32);
    scene.positions.clear();
    scene.normals.clear();
    for r in 0..=rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..=segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            let n = [theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin()].map(|c| c as f32);
            scene.positions.push(n);
            scene.normals.push(n);
        }
    }
    let row = segments + 1;
    scene.triangles.clear();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * row + s, (r + 1) * row + s);
            if r != 0 {
                scene.triangles.push([a, b, a + 1]);
            }
            if r != rings - 1 {
                scene.triangles.push([a + 1, b, b + 1]);
            }
        }
    }
    scene.triangle_material = vec![0; scene.triangles.len()];
    scene.tangents.clear();
    scene.uv0.clear();
    scene.uv1.clear();
    scene.colors.clear();
    scene.instances.clear();
    scene.update_emissive();
    let yfov = 2.0 * (1.0f32 / 3.0).asin() * 1.05;
    scene.cameras = vec![Camera {
        position: [0.0, 0.0, 3.0],
        forward: [0.0, 0.0, -1.0],
        up: [0.0, 1.0, 0.0],
        yfov,
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    }];
    scene
}

/// Interior surface pixels (the 3×3 neighbourhood is the same material) with their n·v.
fn interior_pixels(g: &umbra::passes::gbuffer::GBufferData, view: &[glam::Vec3]) -> Vec<(usize, f64)> {
    let (w, h) = (g.size.0 as usize, g.size.1 as usize);
    let mut out = Vec::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let m = g.material[i][0];
            let interior = (0..9).all(|k| g.material[(y + k / 3 - 1) * w + x + k % 3 - 1][0] == m);
            if m != umbra::passes::gbuffer::GBUFFER_NO_SURFACE && interior {
                let n = glam::Vec3::from_slice(&g.normal[i][..3]).normalize();
                out.push((i, -n.dot(view[i]) as f64));
            }
        }
    }
    out
}

/// The table's bilinear interpolation at (n·v, roughness), as `ibl_table` in deferred.comp reads
/// it (entries at [`lut_coordinates`]).
fn table_bilinear(table: &[[f64; 4]], nv: f64, roughness: f64) -> [f64; 4] {
    let n = LUT_SIZE as usize;
    let p = [nv * n as f64 - 0.5, roughness * (n - 1) as f64].map(|c| c.clamp(0.0, (n - 1) as f64));
    let i0 = p.map(|c| c as usize);
    let i1 = i0.map(|i| (i + 1).min(n - 1));
    let f = [p[0] - i0[0] as f64, p[1] - i0[1] as f64];
    std::array::from_fn(|c| {
        let at = |i: usize, j: usize| table[j * n + i][c];
        let a = at(i0[0], i0[1]) * (1.0 - f[0]) + at(i1[0], i0[1]) * f[0];
        let b = at(i0[0], i1[1]) * (1.0 - f[0]) + at(i1[0], i1[1]) * f[0];
        a * (1.0 - f[1]) + b * f[1]
    })
}

/// `f(n·v)` tabulated at 257 n·v in [10⁻⁴, 1] (each value a quadrature) and interpolated
/// linearly.
fn tabulated(f: impl Fn(f64) -> f64) -> impl Fn(f64) -> f64 {
    let grid: Vec<f64> = (0..=256).map(|k| f((k as f64 / 256.0).max(1e-4))).collect();
    move |nv| {
        let p = nv.clamp(0.0, 1.0) * 256.0;
        let k = (p as usize).min(255);
        grid[k] + (grid[k + 1] - grid[k]) * (p - k as f64)
    }
}

/// `f(n·v)` box-filtered over pixel `i` of the unit sphere at the origin as the path tracer's
/// pixels are (8×8 rays against the exact sphere): Fresnel's curvature in n·v makes the centre
/// value alone ~5e-4 low.
fn box_filtered(scene: &Scene, size: (u32, u32), i: usize, f: &dyn Fn(f64) -> f64) -> f64 {
    let c = umbra::gpu::layout::GpuCamera::new(&scene.camera(None).unwrap(), size);
    let c64 = |a: [f32; 3]| glam::DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64);
    let (origin, forward, right, up) = (c64(c.origin), c64(c.forward), c64(c.right), c64(c.up));
    let (x, y) = ((i % size.0 as usize) as f64, (i / size.0 as usize) as f64);
    let mut sum = 0.0;
    for k in 0..64 {
        let (sx, sy) = (x + ((k % 8) as f64 + 0.5) / 8.0, y + ((k / 8) as f64 + 0.5) / 8.0);
        let ndc = (2.0 * sx / size.0 as f64 - 1.0, 1.0 - 2.0 * sy / size.1 as f64);
        let d = (forward + ndc.0 * right + ndc.1 * up).normalize();
        let b = origin.dot(d);
        let t = -b - (b * b - origin.length_squared() + 1.0).max(0.0).sqrt();
        sum += f(-(origin + t * d).dot(d));
    }
    sum / 64.0
}
