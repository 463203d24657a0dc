//! The hybrid pipeline's passes against independent answers: the G-buffer against CPU traversal
//! of the same rays.

mod common;

use common::Gpu;
use glam::Vec3;
use umbra::bvh::traverse::Ray;
use umbra::gpu::layout::GpuCamera;
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::passes::gbuffer::{GBuffer, GBufferPass, GBUFFER_NO_SURFACE};
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};
use umbra::scene::Scene;

fn scene_file(name: &str) -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .expect("scene loads")
}

/// The centre ray of `pixel`, computed on the CPU from the same camera parameters.
fn centre_ray(c: &GpuCamera, (w, h): (u32, u32), (x, y): (u32, u32)) -> Ray {
    let v = Vec3::from;
    let ndc = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / h as f32);
    let dir = (v(c.forward) + ndc.0 * v(c.right) + ndc.1 * v(c.up)).normalize();
    Ray { origin: v(c.origin), dir, tmin: 0.0, tmax: f32::INFINITY }
}

/// Every pixel of the G-buffer of the sphere grid (and of the textured scene) agrees with a CPU
/// traversal of the pixel's centre ray: surface or not, material, view depth, the interpolated
/// normal (untextured scene) and the material's base colour, metallic and roughness.
#[test]
fn gbuffer_matches_cpu_traversal() {
    let gpu = Gpu::new();
    for (file, check_shading) in [("spheres.glb", true), ("textured.glb", false)] {
        let scene = scene_file(file);
        let camera = scene.camera(None).unwrap();
        let size = (96, 64);
        let arrays = SceneArrays::new(&scene).unwrap();
        let gpu_scene = GpuScene::from_arrays(&gpu, &arrays).unwrap();
        let pass = GBufferPass::new(&gpu, &gpu_scene).unwrap();
        let target = GBuffer::new(&gpu, size).unwrap();
        let params = GBufferPass::params(&camera, size);
        gpu.record(|rec| pass.record(rec, &gpu_scene, &target.views(), &params, None)).unwrap();
        let data = target.read(&gpu).unwrap();

        let cam = GpuCamera::new(&camera, size);
        let forward = Vec3::from(camera.forward).normalize();
        let (mut surfaces, mut mismatched) = (0, Vec::new());
        for y in 0..size.1 {
            for x in 0..size.0 {
                let i = (y * size.0 + x) as usize;
                let ray = centre_ray(&cam, size, (x, y));
                let material = data.material[i][0];
                let Some(hit) = arrays.bvh.closest(&ray) else {
                    if material != GBUFFER_NO_SURFACE || data.depth[i] != 0.0 {
                        mismatched.push(format!("{x},{y}: CPU miss, GPU material {material}"));
                    }
                    continue;
                };
                surfaces += 1;
                let tri = &arrays.triangles[hit.tri as usize];
                let depth = hit.t * ray.dir.dot(forward);
                if material != tri.material || (data.depth[i] - depth).abs() > 1e-5 * depth {
                    mismatched.push(format!(
                        "{x},{y}: material {material} vs {}, depth {} vs {depth}",
                        tri.material, data.depth[i]
                    ));
                    continue;
                }
                if !check_shading {
                    continue;
                }
                let [b1, b2] = hit.bary;
                let n = |v: u32| Vec3::from_slice(&arrays.vertices[v as usize].normal_u[..3]);
                let mut normal = ((1.0 - b1 - b2) * n(tri.v0) + b1 * n(tri.v1) + b2 * n(tri.v2)).normalize();
                // On the viewer's side of the geometric normal (grazing hits at a silhouette can
                // see a triangle from behind while its vertex normals face the camera).
                let [p0, p1, p2] = arrays.bvh.tris[hit.tri as usize].vertices();
                let mut ng = (p1 - p0).cross(p2 - p0);
                if ng.dot(ray.dir) > 0.0 {
                    ng = -ng;
                }
                if normal.dot(ng) < 0.0 {
                    normal = -normal;
                }
                let m = &arrays.materials[tri.material as usize];
                let got = data.normal[i];
                // Half floats: 11-bit significands, so 1e-3 relative.
                let normal_error = (Vec3::new(got[0], got[1], got[2]) - normal).length();
                let roughness = m.emissive_rough[3].clamp(0.01, 1.0);
                let base = data.base[i];
                let expected = [m.base_color[0], m.base_color[1], m.base_color[2], m.params[0]];
                if normal_error > 2e-3
                    || (got[3] - roughness).abs() > 1e-3
                    || base.iter().zip(expected).any(|(g, e)| (g - e).abs() > 1e-3 * e.max(1.0))
                {
                    mismatched.push(format!(
                        "{x},{y}: normal {got:?} vs {normal}, base {base:?} vs {expected:?}, roughness {roughness}"
                    ));
                }
            }
        }
        let pixels = (size.0 * size.1) as usize;
        eprintln!("{file}: {surfaces} of {pixels} pixels on a surface, {} mismatched", mismatched.len());
        assert!(surfaces > pixels / 4, "{file}: the camera should see the scene");
        assert!(
            mismatched.is_empty(),
            "{file}: {} mismatched pixels:\n{}",
            mismatched.len(),
            mismatched.join("\n")
        );
    }
}

/// With one directional light and nothing else, deferred shading equals the path tracer's
/// direct-lighting image (one scattering event) within the path tracer's noise: the same BSDF,
/// light and shadow rays, differing only in the pixel filter (centre sample vs box), so pixels on
/// silhouettes are left out. z = difference / standard error of the path-traced mean, with an
/// allowance of 2e-3 relative for the G-buffer's half floats.
#[test]
fn deferred_direct_light_equals_path_traced_direct_light() {
    let gpu = Gpu::new();
    let scene = scene_file("spheres.glb");
    assert_eq!(scene.lights.len(), 1, "spheres.glb has one directional light");
    assert!(scene.emissive.triangles.is_empty(), "and no emissive triangles");
    let camera = scene.camera(None).unwrap();
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let size = (192, 128);
    let settings = PathSettings { size, spp: 64, max_bounces: 1, ..Default::default() };
    let reference = path_trace(&gpu, &gpu_scene, &camera, &settings, |_, _| {}).unwrap();
    let hybrid = hybrid(&gpu, &gpu_scene, &camera, &HybridSettings { size, ..Default::default() }).unwrap();
    let keep = common::interior_pixels(&hybrid.gbuffer, &hybrid.color, 0.9);
    let (compared, outliers, worst) = common::z_outliers(&reference, &hybrid.color, &keep);
    let on_spheres = (0..keep.len()).filter(|&i| keep[i] && hybrid.gbuffer.normal[i][1] < 0.999).count();
    eprintln!("{compared} interior pixels ({on_spheres} on spheres), {outliers} with |z| > 4, worst |z| {worst:.2}; passes {:?}", hybrid.pass_ms);
    let surface = hybrid.gbuffer.material.iter().filter(|m| m[0] != GBUFFER_NO_SURFACE).count();
    assert!(compared * 3 > surface && on_spheres > 1000, "too few interior pixels: {compared} of {surface}");
    // |z| > 4 has probability 6e-5 per channel for a Gaussian: allow 0.5 % of pixels for the
    // curvature of the shading inside a pixel (box filter vs centre sample).
    assert!(outliers * 200 <= compared, "{outliers} of {compared} pixels differ (worst |z| {worst:.2})");
}

/// Deferred shading with 20,000 copies of spheres.glb's light, each 1/20,000 as bright, equals
/// shading with the one light: beyond 16 punctual lights the lighting pass samples 16 by power
/// (exact here, the copies being alike) rather than sending 20,000 shadow rays per pixel, which
/// llvmpipe's limit on loop iterations per invocation would cut short.
#[test]
fn deferred_shading_counts_every_one_of_many_punctual_lights() {
    let gpu = Gpu::new();
    let one = scene_file("spheres.glb");
    let mut many = one.clone();
    let light =
        umbra::scene::Light { intensity: one.lights[0].intensity / 20_000.0, ..one.lights[0].clone() };
    many.lights = vec![light; 20_000];
    let settings = HybridSettings { size: (64, 48), ..Default::default() };
    let shade = |scene: &Scene| {
        let gpu_scene = GpuScene::upload(&gpu, scene).unwrap();
        hybrid(&gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings).unwrap().color
    };
    let (a, b) = (shade(&one), shade(&many));
    let lit = a.iter().filter(|p| p[0] > 0.05).count();
    assert!(lit > 500, "only {lit} lit pixels");
    for (i, (a, b)) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 1e-3 * a[c].abs() + 1e-5,
                "pixel {i}: one light {a:?}, 20,000 {b:?}"
            );
        }
    }
}

/// The tonemap kernel equals its CPU twin (src/tonemap.rs) to one 8-bit step on every curve, over
/// values from 0 to far above white, negative, NaN and Inf; and the twin has the curves' known
/// values (worked by hand from their definitions).
#[test]
fn tonemap_kernel_matches_its_cpu_twin() {
    use umbra::color::tone_curve;
    use umbra::passes::tonemap::{ToneCurve, TonemapPass};
    // Known values. PBR Neutral: grey 0.5 loses the 0.04 offset and is otherwise untouched; grey
    // 1.0 -> 0.96 -> compressed to 1 - 0.24² / 0.44. ACES fit: black stays black; both matrices'
    // rows sum to 1, so grey 1 maps to the fit at 1: (1.0245786 - 0.000090537) / (0.983729 +
    // 0.432951 + 0.238081).
    let close = |a: [f32; 3], b: f32| a.iter().all(|v| (v - b).abs() < 1e-5);
    assert!(close(tone_curve([0.5; 3], ToneCurve::KhronosPbrNeutral), 0.46));
    assert!(close(tone_curve([1.0; 3], ToneCurve::KhronosPbrNeutral), 1.0 - 0.0576 / 0.44));
    assert!(close(tone_curve([0.0; 3], ToneCurve::Aces), 0.0));
    let white = tone_curve([1.0; 3], ToneCurve::Aces);
    let fit = (1.0245786 - 0.000090537) / (0.983729 + 0.432951 + 0.238081);
    assert!(white.iter().all(|v| (v - fit).abs() < 1e-4), "{white:?}");
    assert_eq!(tone_curve([0.25, 2.0, -1.0], ToneCurve::Clamp), [0.25, 1.0, 0.0]);

    let gpu = Gpu::new();
    let (w, h) = (64u32, 8u32);
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let v = 0.02 * (x as f32).powf(1.5) * (1.0 + y as f32 * 0.37);
            texels.push([v, v * 0.5 + 0.01 * y as f32, (x as f32 * 0.31).sin() * 3.0, 1.0]);
        }
    }
    texels[5] = [f32::NAN, f32::INFINITY, -1.0, f32::NAN];
    let src =
        umbra::vk::Image::storage_2d(&gpu, "tonemap src", w, h, umbra::vk::raw::Format::R32G32B32A32_SFLOAT)
            .unwrap();
    let dst = umbra::vk::Image::storage_2d(&gpu, "tonemap dst", w, h, umbra::vk::raw::Format::R8G8B8A8_UNORM)
        .unwrap();
    src.write(&gpu, &texels).unwrap();
    let pass = TonemapPass::new(&gpu).unwrap();
    for curve in [ToneCurve::Clamp, ToneCurve::Aces, ToneCurve::KhronosPbrNeutral] {
        gpu.record(|rec| {
            let cmd = rec.cmd();
            dst.init_general(&gpu, cmd);
            pass.record(rec, src.view, dst.view, (w, h), 0.5, curve)
        })
        .unwrap();
        let got: Vec<[u8; 4]> = dst.read(&gpu).unwrap();
        let flat: Vec<f32> = texels.iter().flatten().copied().collect();
        let expected = umbra::color::to_display8(&flat, 0.5f32.exp2(), curve);
        let worst =
            got.iter().flatten().zip(&expected).map(|(&g, &e)| (g as i32 - e as i32).abs()).max().unwrap();
        assert!(worst <= 1, "{curve:?}: GPU and CPU differ by {worst} steps");
    }
}
