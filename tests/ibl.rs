//! Split-sum image-based lighting: the kernels' tables against f64 references, and the hybrid
//! renderer's IBL against the path tracer.

mod common;

use common::Gpu;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ibl::{IblResources, IblSettings};
use umbra::scene::Scene;
use umbra::split_sum::{lut_coordinates, lut_entry, lut_reference, LUT_SIZE};

fn scene_file(name: &str) -> Scene {
    Scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name))
        .expect("scene loads")
}

/// The kernel's BRDF table (128² midpoint samples of visible normals and of the cosine
/// hemisphere per entry) equals the f64 Gauss–Legendre reference within 1e-3 in every entry and
/// channel; the reference's own error, estimated by doubling its nodes on a sample of entries,
/// is below 1e-5.
#[test]
fn brdf_lut_matches_cpu_quadrature() {
    let s = LUT_SIZE as usize;
    // The reference's own error: 64 against 128 nodes per axis, at the table's corners and on a
    // sparse grid.
    let mut self_error: f64 = 0.0;
    for j in (0..s).step_by(5).chain([s - 1]) {
        for i in (0..s).step_by(5).chain([s - 1]) {
            let (nv, r) = lut_coordinates(i, j);
            let (a, b) = (lut_entry(nv, r, 64), lut_entry(nv, r, 128));
            self_error = self_error.max((0..4).map(|c| (a[c] - b[c]).abs()).fold(0.0, f64::max));
        }
    }
    eprintln!("reference: 64 vs 128 nodes differ by at most {self_error:.2e}");
    assert!(self_error < 1e-5, "the reference quadrature has not converged: {self_error:e}");
    let reference = lut_reference(64);

    let gpu = Gpu::new();
    let scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    let ibl = IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap();
    let lut: Vec<[f32; 4]> = ibl.lut.read(&gpu).unwrap();
    let mut worst = (0.0f64, 0, 0);
    for (k, (g, r)) in lut.iter().zip(&reference).enumerate() {
        for c in 0..4 {
            let e = (g[c] as f64 - r[c]).abs();
            if e > worst.0 {
                worst = (e, k, c);
            }
        }
    }
    let (e, k, c) = worst;
    eprintln!(
        "GPU LUT vs reference: max |error| {e:.2e} at (n·v, roughness) {:.3?}, channel {c} (GPU {:?}, CPU {:?})",
        lut_coordinates(k % s, k / s),
        lut[k],
        reference[k]
    );
    for j in [0, s / 2, s - 1] {
        for i in [0, s / 2, s - 1] {
            eprintln!("  nv {i:2} r {j:2}: {:?}", lut[j * s + i]);
        }
    }
    assert!(e < 1e-3, "GPU BRDF table differs from the reference by {e:e}");
}

use umbra::environment::EnvironmentMap;
use umbra::split_sum::{
    irradiance_brute_force, sh9_irradiance, sh9_irradiance_coefficients, texel_direction,
};

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

const NORMALS: [[f64; 3]; 6] = [
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 0.6, 0.8],
    [-0.48, 0.6, -0.64],
    [0.0, 0.0, -1.0],
];

/// The f64 SH9 projection of `map`, how far the kernel's coefficients are from it (relative to
/// the largest), and the IBL resources built.
fn sh9_gpu_error(
    gpu: &Gpu,
    scene: &mut GpuScene,
    map: &EnvironmentMap,
) -> ([[f64; 3]; 9], f64, IblResources) {
    let cpu = sh9_irradiance_coefficients(map);
    scene.set_environment(gpu, map).unwrap();
    let ibl = IblResources::build(gpu, scene, &IblSettings::default()).unwrap();
    let sh: Vec<[f32; 4]> = ibl.sh.read(gpu).unwrap();
    let largest = cpu.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = (0..9)
        .flat_map(|k| (0..3).map(move |c| (k, c)))
        .map(|(k, c)| (sh[k][c] as f64 - cpu[k][c]).abs())
        .fold(0.0, f64::max)
        / largest;
    (cpu, error, ibl)
}

/// SH9 irradiance: the kernel's coefficients equal the f64 projection (1e-4 relative to the
/// largest); for a constant map the SH irradiance is exactly π L (the texel-integrated basis
/// has no band 1–2 content; the brute-force sum over texel centres is within 1e-3); for a map of bands 0–2 only, SH9
/// is exact, so it equals the brute-force integral up to the map's quadrature error (measured at
/// 128×64: below 1e-3 relative); for the sky with a bright disc, the truncation error stays
/// within the Cauchy–Schwarz bound |E − E₉| ≤ ‖K‖₂ ‖L‖₂, ‖K‖₂² = 2π/3 − (π/4 + π/3 + 5π/64) =
/// π/192 being the energy of the clamped cosine beyond band 2.
#[test]
fn sh9_irradiance_matches_brute_force() {
    let (w, h) = (128, 64);
    let constant = synthetic_map(w, h, |_| [0.7, 1.0, 1.3]);
    let banded = synthetic_map(w, h, |d| {
        let v = 1.0 + 0.5 * d[1] - 0.3 * d[0] + 0.4 * d[0] * d[2] + 0.2 * (3.0 * d[1] * d[1] - 1.0);
        [v, 0.5 * v, 0.25 * v]
    });
    let bright = synthetic_map(w, h, sky);

    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    for (name, map) in [("constant", &constant), ("banded", &banded), ("sky", &bright)] {
        let (cpu, gpu_error, ibl) = sh9_gpu_error(&gpu, &mut scene, map);
        let l2 = map.texels.iter().enumerate().map(|(i, t)| {
            let d_omega = texel_direction(i % w, i / w, w, h).1;
            t.map(|v| (v as f64).powi(2) * d_omega)
        });
        let norm: [f64; 3] = l2.fold([0.0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]).map(f64::sqrt);
        let k_norm = (std::f64::consts::PI / 192.0).sqrt();
        let (mut worst_rel, mut worst_ratio): (f64, f64) = (0.0, 0.0);
        for n in NORMALS.map(unit) {
            let (e9, exact) = (sh9_irradiance(&cpu, n), irradiance_brute_force(map, n));
            for c in 0..3 {
                let err = (e9[c] - exact[c]).abs();
                worst_rel = worst_rel.max(err / exact[c].max(1e-3 * norm[c]));
                worst_ratio = worst_ratio.max(err / (k_norm * norm[c]));
                match name {
                    "constant" => {
                        let expected = std::f64::consts::PI * [0.7f32, 1.0, 1.3][c] as f64;
                        assert!(
                            (e9[c] - expected).abs() < 1e-9 * expected,
                            "{name}: E {} vs π L {expected}",
                            e9[c]
                        );
                        assert!(
                            (exact[c] - expected).abs() < 1e-3 * expected,
                            "{name}: brute force {}",
                            exact[c]
                        );
                    }
                    "banded" => {
                        assert!(err < 1e-3 * exact[c], "{name} n {n:?}: SH9 {} vs {}", e9[c], exact[c])
                    }
                    _ => assert!(
                        err <= k_norm * norm[c],
                        "{name} n {n:?}: |{} − {}| > bound {}",
                        e9[c],
                        exact[c],
                        k_norm * norm[c]
                    ),
                }
            }
        }
        eprintln!(
            "{name}: GPU vs f64 coefficients {gpu_error:.2e} (of the largest); SH9 vs brute force: worst relative {worst_rel:.2e}, worst |error| / (‖K‖‖L‖) {worst_ratio:.3}"
        );
        assert!(gpu_error < 1e-4, "{name}: GPU SH coefficients differ from f64 by {gpu_error:e}");
        if name == "constant" {
            // The prefiltered levels of a constant are the constant.
            let levels: Vec<[f32; 4]> = ibl.prefiltered.read(&gpu).unwrap();
            let worst = levels.iter().map(|t| (t[1] - 1.0).abs()).fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "prefiltered constant map off by {worst}");
        }
    }
}

use umbra::passes::deferred::{IblLookup, LightingSettings};
use umbra::render::{hybrid, path_trace, HybridSettings, PathSettings};

/// spheres.glb for IBL: no sun, no floor, and each sphere shrunk about its centre to radius 0.3
/// (neighbours then hide at most ~25° of elevation from a sphere's lower side, where the sky is
/// dim), so the path tracer's direct environment light differs from IBL by the split sum alone.
fn ibl_spheres() -> Scene {
    let mut scene = scene_file("spheres.glb");
    scene.lights.clear();
    let floor = scene.materials.iter().position(|m| m.name == "floor").expect("floor material") as u32;
    let keep: Vec<usize> =
        (0..scene.triangles.len()).filter(|&t| scene.triangle_material[t] != floor).collect();
    scene.triangles = keep.iter().map(|&t| scene.triangles[t]).collect();
    scene.triangle_material = keep.iter().map(|&t| scene.triangle_material[t]).collect();
    for p in &mut scene.positions {
        if p[1] > 0.0 || p[0].abs() < 3.5 {
            let c = [(p[0] + 3.0).round() - 3.0, 0.4, (p[2] + 3.0).round() - 3.0];
            for k in 0..3 {
                p[k] = c[k] + 0.75 * (p[k] - c[k]);
            }
        }
    }
    scene
}

/// Per material: (sum of hybrid, sum of path traced, sum of path-traced variance of the mean,
/// pixel count) over interior pixels, in luminance; `bin` picks which pixels count (by n·v).
fn per_material(
    g: &umbra::passes::gbuffer::GBufferData,
    hyb: &[[f32; 4]],
    pt: &umbra::render::PathImage,
    view: &[glam::Vec3],
    bin: impl Fn(f32) -> bool,
) -> std::collections::BTreeMap<u32, [f64; 4]> {
    let lum = |c: &[f32]| (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f64;
    let var = pt.variance_of_mean();
    let (w, h) = (g.size.0 as usize, g.size.1 as usize);
    let mut out = std::collections::BTreeMap::new();
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let m = g.material[i][0];
            let interior = (0..9).all(|k| g.material[(y + k / 3 - 1) * w + x + k % 3 - 1][0] == m);
            if m == umbra::passes::gbuffer::GBUFFER_NO_SURFACE || !interior {
                continue;
            }
            let nv = -glam::Vec3::from_slice(&g.normal[i][..3]).dot(view[i]);
            if !bin(nv) {
                continue;
            }
            let e = out.entry(m).or_insert([0.0; 4]);
            e[0] += lum(&hyb[i]);
            e[1] += lum(&pt.mean[i]);
            e[2] += 0.2126f64.powi(2) * var[i][0] as f64
                + 0.7152f64.powi(2) * var[i][1] as f64
                + 0.0722f64.powi(2) * var[i][2] as f64;
            e[3] += 1.0;
        }
    }
    out
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

/// Split-sum IBL against the path tracer's direct environment light on the sphere grid under a
/// sky with a bright disc: per sphere (interior pixels, luminance), relative error
/// |hybrid − path| / path of the sphere's mean, for the textbook split sum (lookup along the
/// mirror direction). (a) the error grows with roughness: the mean
/// error of the roughest column exceeds the smoothest column's by more than 3 standard errors of
/// the path tracer's noise (one-sided z-test, significance ≈ 0.0013); (b) it grows towards
/// grazing angles: over the spheres of roughness ≥ 0.5, the pooled relative error of the pixels
/// with n·v < 0.6 (the small spheres keep few interior pixels nearer grazing) exceeds that of n·v > 0.85 by more than 3 standard errors.
#[test]
fn split_sum_error_grows_with_roughness_and_grazing_angle() {
    let gpu = Gpu::new();
    let scene = ibl_spheres();
    let map = synthetic_map(128, 64, sky);
    let start = std::time::Instant::now();
    let (size, spp) = ((160, 112), 128);
    let lookups = [IblLookup::Mirror, IblLookup::Dominant];
    let (hybrids, pt, view) = render_lookups(&gpu, &scene, Some(&map), [1.0; 3], size, spp, true, &lookups);
    let hyb = &hybrids[0];
    eprintln!("renders: {:.1} s", start.elapsed().as_secs_f64());
    let spheres = per_material(&hyb.gbuffer, &hyb.color, &pt, &view, |_| true);
    // Error and its standard error (from the path tracer's noise) of one material's sums.
    let rel = |e: &[f64; 4]| ((e[0] - e[1]).abs() / e[1], e[2].sqrt() * e[0] / (e[1] * e[1]));
    let mut columns = [(0.0, 0.0, 0); 7];
    eprintln!("roughness metallic  pixels  hybrid    path      rel. error");
    for (&m, e) in &spheres {
        let mat = &scene.materials[m as usize];
        let (err, se) = rel(e);
        let col = (mat.roughness * 6.0).round() as usize;
        eprintln!(
            "{:9.2} {:8.2} {:7} {:9.4} {:9.4} {:7.4} ± {:.4}",
            mat.roughness,
            mat.metallic,
            e[3],
            e[0] / e[3],
            e[1] / e[3],
            err,
            se
        );
        columns[col].0 += err;
        columns[col].1 += se * se;
        columns[col].2 += 1;
    }
    let column = |c: usize| (columns[c].0 / columns[c].2 as f64, columns[c].1.sqrt() / columns[c].2 as f64);
    for c in 0..7 {
        eprintln!(
            "column roughness {:.2}: mean rel. error {:.4} ± {:.4}",
            c as f64 / 6.0,
            column(c).0,
            column(c).1
        );
    }
    assert!(spheres.len() >= 45, "the camera should see most of the 49 spheres ({})", spheres.len());
    let ((smooth, s_se), (rough, r_se)) = (column(0), column(6));
    assert!(
        rough - smooth > 3.0 * (s_se * s_se + r_se * r_se).sqrt(),
        "roughest column error {rough:.4} ± {r_se:.4} vs smoothest {smooth:.4} ± {s_se:.4}"
    );

    // Reading the prefiltered map along the lobe's dominant direction (umbra's default) removes
    // much of the roughness-dependent error: the roughest column's error falls by more than 3
    // standard errors.
    let dominant = per_material(&hybrids[1].gbuffer, &hybrids[1].color, &pt, &view, |_| true);
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0);
    for (&m, e) in &dominant {
        if (scene.materials[m as usize].roughness * 6.0).round() as usize == 6 {
            let (err, se) = rel(e);
            sum += err;
            var += se * se;
            n += 1;
        }
    }
    let (rough_dominant, rd_se) = (sum / n as f64, var.sqrt() / n as f64);
    eprintln!(
        "roughest column along the dominant direction: {rough_dominant:.4} ± {rd_se:.4} (mirror {rough:.4})"
    );
    assert!(
        rough - rough_dominant > 3.0 * r_se.max(rd_se),
        "the dominant direction should help the roughest column: {rough_dominant:.4} vs {rough:.4}"
    );

    let pooled = |bin: &dyn Fn(f32) -> bool| {
        let sums = per_material(&hyb.gbuffer, &hyb.color, &pt, &view, bin);
        let mut t = [0.0; 4];
        for (&m, e) in &sums {
            if scene.materials[m as usize].roughness >= 0.5 {
                for k in 0..4 {
                    t[k] += e[k];
                }
            }
        }
        (rel(&t), t[3])
    };
    let ((frontal, f_se), nf) = pooled(&|nv| nv > 0.85);
    let ((grazing, g_se), ng) = pooled(&|nv| nv < 0.6);
    eprintln!("roughness >= 0.5: n·v > 0.85: {frontal:.4} ± {f_se:.4} ({nf} px); n·v < 0.6: {grazing:.4} ± {g_se:.4} ({ng} px)");
    assert!(
        grazing - frontal > 3.0 * (f_se * f_se + g_se * g_se).sqrt(),
        "grazing error {grazing:.4} should exceed frontal {frontal:.4}"
    );
}

use umbra::scene::Camera;

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

/// The white furnace's reflected radiance (environment 1, white base colour) from the table's
/// entries (A, B, C, D): a metal's directional albedo A + B; a dielectric's F0 A + F90 B plus the
/// diffuse lobe's 1 − F0 C − F90 D (the path tracer's BSDF weights its diffuse lobe by
/// 1 − max3(F(v·h)) and its specular lobe is Schlick-Fresnel GGX with separable Smith G, which is
/// exactly what the table integrates).
fn furnace_albedo(e: [f64; 4], metallic: f64, f0: f64, f90: f64) -> f64 {
    let dielectric = f0 * e[0] + f90 * e[1] + 1.0 - f0 * e[2] - f90 * e[3];
    let metal = e[0] + e[1];
    dielectric + (metal - dielectric) * metallic
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

/// `KHR_materials_clearcoat` in the furnace: a grey dielectric sphere (base colour ½, roughness 1)
/// under a coat (weight 1 and ½, roughness 0.3), environment 1, one scattering event. The
/// extension's layering mixes the base and the coat's lobe with w = clearcoat · F_schlick(0.04, 1,
/// n·v), so the single-scattering albedo is E = (1 − w) E_base + w E_coat, with
/// E_base = F0 A + F90 B + ½ (1 − F0 C − F90 D) and E_coat the table's A + B at the coat's
/// roughness (its lobe has no Fresnel inside); the hybrid's prediction is the same with the table
/// T. Without the base's weight 1 − w the path tracer is 0.126 too bright at grazing n·v (z 47). Per n·v bin (< 0.3, 0.3–0.7, > 0.7): the path tracer's mean equals E's within
/// z·se + 1e-4 (z 3.26: two-sided 0.01, Šidák over the 6 bins), every interior hybrid pixel its
/// T-prediction within 1e-3, the layered albedo stays at most 1 (the furnace's energy bound) and
/// the coat shows (E differs from the uncoated base's by more than 5 se at grazing n·v).
#[test]
fn white_furnace_clearcoat_is_the_extensions_layering() {
    let gpu = Gpu::new();
    let nodes = 48;
    let table = lut_reference(nodes);
    let (size, spp) = ((96, 96), 32);
    let z = 3.26;
    let bins: [(f64, f64); 3] = [(0.0, 0.3), (0.3, 0.7), (0.7, 1.01)];
    let (roughness, coat_roughness) = (1.0f64, 0.3f64);
    for coat in [1.0f32, 0.5] {
        let grey = 0.5;
        let mut scene = sphere_scene([grey as f32; 3], 0.0, roughness as f32);
        scene.materials[0].clearcoat = coat;
        scene.materials[0].clearcoat_roughness = coat_roughness as f32;
        let mat = &scene.materials[0];
        let f0 = (((mat.ior - 1.0) / (mat.ior + 1.0)).powi(2) * mat.specular_factor) as f64;
        let f90 = mat.specular_factor as f64;
        let weight = |nv: f64| coat as f64 * (0.04 + 0.96 * (1.0 - nv.clamp(0.0, 1.0)).powi(5));
        let base_albedo = |e: [f64; 4]| f0 * e[0] + f90 * e[1] + grey * (1.0 - f0 * e[2] - f90 * e[3]);
        let layered = |nv: f64, base: [f64; 4], layer: [f64; 4]| {
            let w = weight(nv);
            (1.0 - w) * base_albedo(base) + w * (layer[0] + layer[1])
        };
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [1.0; 3], size, spp, false);
        let var = pt.variance_of_mean();
        let exact = tabulated(|nv| {
            layered(nv, lut_entry(nv, roughness, nodes), lut_entry(nv, coat_roughness, nodes))
        });
        let base_only = tabulated(|nv| base_albedo(lut_entry(nv, roughness, nodes)));
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        for &(lo, hi) in &bins {
            let (mut n, mut sp, mut se2, mut s_e, mut s_b, mut worst) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0f64);
            for &(i, nv) in pixels.iter().filter(|p| p.1 >= lo && p.1 < hi) {
                let t = layered(
                    nv,
                    table_bilinear(&table, nv, roughness),
                    table_bilinear(&table, nv, coat_roughness),
                );
                worst = (0..3).map(|c| (hyb.color[i][c] as f64 - t).abs()).fold(worst, f64::max);
                sp += pt.mean[i][1] as f64;
                se2 += var[i][1] as f64;
                s_e += box_filtered(&scene, size, i, &exact);
                s_b += box_filtered(&scene, size, i, &base_only);
                n += 1.0;
            }
            let se = se2.sqrt() / n;
            let (p, e, b) = (sp / n, s_e / n, s_b / n);
            eprintln!(
                "coat {coat} n·v {lo:.1}–{:.1}: {} pixels, path {p:.5}, E {e:.5} (uncoated {b:.5}), path − E {:+.5}, se {se:.5}, max |hybrid − T| {worst:.2e}",
                hi.min(1.0),
                n as usize,
                p - e
            );
            assert!(n >= 50.0, "too few pixels in n·v bin {lo}–{hi}: {n}");
            assert!(
                e <= 1.0 && p <= 1.0 + z * se + 1e-4,
                "coat {coat}: albedo above 1: E {e}, path {p} ± {se}"
            );
            assert!(
                (p - e).abs() <= z * se + 1e-4,
                "coat {coat}: path tracer {p} vs the layering's albedo {e} ± {se} (n·v {lo}–{hi})"
            );
            assert!(worst < 1e-3, "coat {coat}: hybrid differs from the table's layering by {worst:e}");
            if lo == 0.0 {
                assert!(
                    (e - b).abs() > 5.0 * se,
                    "coat {coat}: the coat does not show at grazing n·v ({e} vs {b})"
                );
            }
        }
    }
}

/// White furnace: a constant environment of 1 and one white sphere per render (metal at
/// roughness 0, ½, 1; dielectric at 0, 1), hybrid (IBL only, no AO) against the path tracer with
/// one scattering event. For a constant environment the split sum is exact but for its table: the
/// hybrid gives T(n·v), the bilinearly interpolated 32² table, the path tracer's expectation is
/// E(n·v), the exact single-scattering albedo (f64 quadrature, box-filtered over each pixel).
/// Expected and tested, per sphere and per n·v bin (< 0.3, 0.3–0.7, > 0.7; ≥ 50 pixels each):
/// (a) every interior hybrid pixel equals T at its n·v within 1e-3 (the GPU table's tolerance in
///     `brdf_lut_matches_cpu_quadrature`);
/// (b) the path tracer's mean equals the mean of E within z·se + 1e-4 (se from its per-pixel
///     variance of the mean; z = 3.40: two-sided 0.01 with a Šidák correction over the 15 bins;
///     1e-4 for f32 accumulation);
/// (c) the table's interpolation error |T − E| is below 2e-3 in every bin (the table spans
///     roughness 0..1 edge to edge; one sampled at roughness texel centres clamps roughness 1 to
///     0.984 and is 1.6e-2 too bright on a rough metal), so hybrid and path tracer agree within
///     z·se + 1e-4 + 1e-3 + 2e-3;
/// (d) the metal's albedo A + B falls below 1 as roughness grows (single-scattering energy loss):
///     frontal means strictly decreasing with roughness in both renderers, and at roughness 1
///     below 1 by more than 10 standard errors in the path tracer.
#[test]
fn white_furnace_split_sum_matches_path_tracer() {
    let start = std::time::Instant::now();
    let gpu = Gpu::new();
    let nodes = 48;
    let table = lut_reference(nodes);
    let (size, spp) = ((96, 96), 32);
    let cases: [(f32, f32); 5] = [(1.0, 0.0), (1.0, 0.5), (1.0, 1.0), (0.0, 0.0), (0.0, 1.0)];
    let z = 3.40;
    let bins: [(f64, f64); 3] = [(0.0, 0.3), (0.3, 0.7), (0.7, 1.01)];
    let mut frontal_metal = Vec::new();
    eprintln!("metallic roughness  n·v bin    pixels  hybrid    path      E (exact)  T (table)  path−E     se      max|hyb−T|");
    for (metallic, roughness) in cases {
        let scene = sphere_scene([1.0; 3], metallic, roughness);
        let mat = &scene.materials[0];
        let f0 = (((mat.ior - 1.0) / (mat.ior + 1.0)).powi(2) * mat.specular_factor) as f64;
        let f90 = mat.specular_factor as f64;
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [1.0; 3], size, spp, false);
        let var = pt.variance_of_mean();
        // E on a fine n·v grid (linear interpolation error below 1e-6 here).
        let exact =
            tabulated(|nv| furnace_albedo(lut_entry(nv, roughness as f64, nodes), metallic as f64, f0, f90));
        let exact_box = |i: usize| box_filtered(&scene, size, i, &exact);
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        assert!(pixels.len() > 2000, "the sphere should fill the image ({} interior pixels)", pixels.len());
        for &(lo, hi) in &bins {
            let (mut n, mut sh, mut sp, mut se2, mut s_e, mut s_t, mut worst) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0f64);
            for &(i, nv) in pixels.iter().filter(|p| p.1 >= lo && p.1 < hi) {
                let t =
                    furnace_albedo(table_bilinear(&table, nv, roughness as f64), metallic as f64, f0, f90);
                // The channels are equal (white), so one channel's noise is the pixel's.
                worst = (0..3).map(|c| (hyb.color[i][c] as f64 - t).abs()).fold(worst, f64::max);
                sh += hyb.color[i][1] as f64;
                sp += pt.mean[i][1] as f64;
                se2 += var[i][1] as f64;
                s_e += exact_box(i);
                s_t += t;
                n += 1.0;
            }
            let se = se2.sqrt() / n;
            let (h, p, e, t) = (sh / n, sp / n, s_e / n, s_t / n);
            eprintln!(
                "{metallic:8.2} {roughness:9.2}  {lo:.1}–{:.1}  {:7} {h:9.5} {p:9.5} {e:9.5}  {t:9.5}  {:+9.5} {se:8.5} {worst:9.2e}",
                hi.min(1.0),
                n as usize,
                p - e
            );
            assert!(n >= 50.0, "too few pixels in n·v bin {lo}–{hi}: {n}");
            assert!(
                worst < 1e-3,
                "hybrid differs from the table's prediction by {worst:e} (m {metallic} r {roughness})"
            );
            assert!(
                (p - e).abs() <= z * se + 1e-4,
                "path tracer {p} vs exact single-scattering albedo {e} ± {se} (m {metallic} r {roughness}, n·v {lo}–{hi})"
            );
            assert!(
                (t - e).abs() < 2e-3,
                "the table's interpolation T {t} differs from the exact albedo E {e} (m {metallic} r {roughness}, n·v {lo}–{hi})"
            );
            assert!(
                (h - p).abs() <= z * se + 1e-4 + 1e-3 + 2e-3,
                "hybrid {h} vs path tracer {p} ± {se} (m {metallic} r {roughness}, n·v {lo}–{hi})"
            );
            if metallic == 1.0 && lo == 0.7 {
                frontal_metal.push((roughness, h, p, se, e));
            }
        }
    }
    for w in frontal_metal.windows(2) {
        let ((r0, h0, p0, s0, _), (r1, h1, p1, s1, _)) = (w[0], w[1]);
        assert!(h1 < h0, "hybrid metal albedo should fall with roughness: {h0} at {r0}, {h1} at {r1}");
        assert!(
            p0 - p1 > z * (s0 * s0 + s1 * s1).sqrt(),
            "path-traced metal albedo should fall with roughness: {p0} at {r0}, {p1} at {r1}"
        );
    }
    let &(_, h, p, se, e) = frontal_metal.last().unwrap();
    eprintln!(
        "rough metal (n·v > 0.7): 1 − E = {:.4}, 1 − path = {:.4} ± {se:.4}, 1 − hybrid = {:.4}",
        1.0 - e,
        1.0 - p,
        1.0 - h
    );
    assert!(1.0 - p > 10.0 * se, "the roughest metal should lose energy: path {p} ± {se}");
    eprintln!("white furnace: {:.1} s", start.elapsed().as_secs_f64());
}

/// Grazing angles, for the textbook split sum (lookup along the mirror direction, as the
/// prefiltering assumed n = v = r): one rough metal sphere (roughness 0.75, the grid's orange)
/// filling a 96² image under the sky with a bright disc, hybrid (4×4 supersampled) against the
/// path tracer's direct environment light. Per n·v bin (grazing < 0.3, frontal > 0.8; at least
/// 150 interior pixels each), the split sum's relative mean squared error in luminance, with the
/// path tracer's noise removed: R = Σ[(h − p)² − var(p)] / Σ p², var(p) its per-pixel variance of
/// the mean; se(R) from var[(h − p)²] ≈ 4 (h − p)² var(p) + 2 var(p)² (Gaussian pixel means).
/// The grazing bin's R exceeds the frontal bin's by more than 3.09 standard errors (one-sided,
/// significance 0.001). (A dielectric of the same roughness is not tested: its error, ~6.5 % RMS
/// in every bin, is dominated by SH9's truncation of the disc in the diffuse term, flat in n·v.)
#[test]
fn split_sum_error_is_largest_at_grazing_angles() {
    let gpu = Gpu::new();
    let map = synthetic_map(128, 64, sky);
    let lum = |c: &[f32]| (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f64;
    {
        let metallic = 1.0;
        let scene = sphere_scene([0.9, 0.5, 0.2], metallic, 0.75);
        let lookups = [IblLookup::Mirror, IblLookup::Dominant];
        let (hybrids, pt, view) =
            render_lookups(&gpu, &scene, Some(&map), [1.0; 3], (96, 96), 64, true, &lookups);
        let hyb = &hybrids[0];
        let var = pt.variance_of_mean();
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        let bin_of = |hyb: &umbra::render::HybridImage, lo: f64, hi: f64| {
            let (mut num, mut den, mut var_num, mut n) = (0.0, 0.0, 0.0, 0);
            for &(i, _) in pixels.iter().filter(|p| p.1 >= lo && p.1 < hi) {
                let (h, p) = (lum(&hyb.color[i]), lum(&pt.mean[i]));
                let v = 0.2126f64.powi(2) * var[i][0] as f64
                    + 0.7152f64.powi(2) * var[i][1] as f64
                    + 0.0722f64.powi(2) * var[i][2] as f64;
                let d2 = (h - p).powi(2);
                num += d2 - v;
                den += p * p;
                var_num += 4.0 * (d2 - v).max(0.0) * v + 2.0 * v * v;
                n += 1;
            }
            (num / den, var_num.sqrt() / den, n)
        };
        let bin = |lo: f64, hi: f64| bin_of(hyb, lo, hi);
        let (grazing, g_se, ng) = bin(0.0, 0.3);
        let (frontal, f_se, nf) = bin(0.8, 1.01);
        let (middle, m_se, nm) = bin(0.3, 0.8);
        eprintln!(
            "metallic {metallic}, roughness 0.75: RMS relative error (noise removed) n·v < 0.3: {:.4} ({ng} px), 0.3–0.8: {:.4} ({nm} px), > 0.8: {:.4} ({nf} px); R = {grazing:.2e} ± {g_se:.1e}, {middle:.2e} ± {m_se:.1e}, {frontal:.2e} ± {f_se:.1e}",
            grazing.max(0.0).sqrt(),
            middle.max(0.0).sqrt(),
            frontal.max(0.0).sqrt()
        );
        assert!(ng >= 150 && nf >= 150, "too few pixels: {ng} grazing, {nf} frontal");
        assert!(
            grazing - frontal > 3.09 * (g_se * g_se + f_se * f_se).sqrt(),
            "metallic {metallic}: grazing R {grazing:e} ± {g_se:e} should exceed frontal {frontal:e} ± {f_se:e}"
        );
        // Along the dominant direction (umbra's default) the grazing error falls by more than
        // 3.09 standard errors.
        let (dominant, d_se, _) = bin_of(&hybrids[1], 0.0, 0.3);
        eprintln!(
            "grazing R along the dominant direction: {dominant:.2e} ± {d_se:.1e} (mirror {grazing:.2e})"
        );
        assert!(
            grazing - dominant > 3.09 * g_se.max(d_se),
            "the dominant direction should help at grazing angles: {dominant:e} vs {grazing:e}"
        );
    }
}

/// Prefiltered levels against brute force: a 64 × 32 grey map (a dim gradient and a disc of
/// radiance 20 and radius 12°), every texel of the levels for roughness 0.4 (16 × 8) and 1.0
/// (8 × 4) against the f64 integral the kernel estimates, ∫ L(l) D(h)/4 (r·l) dl / ∫ D(h)/4 (r·l) dl
/// with n = v = r (the source taken piecewise constant, 4 × 4 exact-solid-angle cells per texel).
/// Expected error: the kernel's 64 Hammersley samples with filtered importance sampling should do
/// no worse than 64 independent samples of the same pdf D/4, whose ratio estimator has standard
/// error σ = √(∫ q (r·l)² (L − μ)² dl / 64) / ∫ q (r·l) dl (q = D/4; computed per texel by the
/// same quadrature). Tested: every texel within 3 σ (plus 1e-3 of its value for the texel
/// reconstruction: the kernel reads the source bilinearly).
///
/// The kernel's level of detail is 0.5 log2(Ωs / Ωtexel) − 1.5 (see ibl_prefilter.comp). Measured
/// (mean |error| / σ; worst texel's |error| / (3σ + 1e-3 μ)), roughness 0.4 and 1.0: with
/// Křivánek and Colbert's +1 bias 50 / 15 and 37 / 48 (the box chain blurs the disc, up to
/// +63 %); with 0: 12.5 / 3.0 and 15 / 12.5; −1: 0.86 / 0.57 and 0.58 / 1.47; −1.5 (kept):
/// 0.52 / 0.33 and 0.37 / 0.52; −2: 0.42 / 0.32, but the worst texels turn noisy (the sun
/// aliasing filtering exists to prevent; worst 2.03 against 1.02).
#[test]
fn prefiltered_levels_match_brute_force() {
    use std::f64::consts::PI;
    let (w, h) = (64usize, 32usize);
    let disc = unit([0.8, 0.5, -0.3]);
    let radiance = |d: [f64; 3]| {
        let cos = d[0] * disc[0] + d[1] * disc[1] + d[2] * disc[2];
        let l = if cos > 12f64.to_radians().cos() { 20.0 } else { 0.2 + 0.3 * d[1].max(0.0) };
        [l; 3]
    };
    let map = synthetic_map(w, h, radiance);
    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    scene.set_environment(&gpu, &map).unwrap();
    let settings = IblSettings::default();
    let ibl = IblResources::build(&gpu, &scene, &settings).unwrap();
    let levels: Vec<[f32; 4]> = ibl.prefiltered.read(&gpu).unwrap();
    let sizes = umbra::split_sum::prefiltered_level_sizes((w as u32, h as u32));
    // Source cells: direction, solid angle, radiance.
    let sub = 4usize;
    let mut cells = Vec::with_capacity(w * h * sub * sub);
    for y in 0..h * sub {
        let (t0, t1) = (PI * y as f64 / (h * sub) as f64, PI * (y + 1) as f64 / (h * sub) as f64);
        let d_omega = 2.0 * PI / (w * sub) as f64 * (t0.cos() - t1.cos());
        for x in 0..w * sub {
            let d = texel_direction(x, y, w * sub, h * sub).0;
            cells.push((d, d_omega, map.texels[(y / sub) * w + x / sub][0] as f64));
        }
    }
    let mut worst_ratio: f64 = 0.0;
    for (k, roughness) in [(2usize, 0.4f64), (5, 1.0)] {
        let a = roughness * roughness;
        let offset: u32 = sizes[1..k].iter().map(|&(w, h)| w * h).sum();
        let (lw, lh) = (sizes[k].0 as usize, sizes[k].1 as usize);
        let (mut worst, mut sum_ratio) = ((0.0f64, 0.0, 0.0, 0.0), 0.0);
        for t in 0..lw * lh {
            let r = texel_direction(t % lw, t / lw, lw, lh).0;
            let (mut wsum, mut lsum) = (0.0, 0.0);
            let weights: Vec<(f64, f64)> = cells
                .iter()
                .filter_map(|&(l, d_omega, radiance)| {
                    let c = r[0] * l[0] + r[1] * l[1] + r[2] * l[2];
                    if c <= 0.0 {
                        return None;
                    }
                    // n·h for h = (r + l)/|r + l| with r·l = c.
                    let nh2 = (1.0 + c) / 2.0;
                    let d = a * a / (PI * (nh2 * (a * a - 1.0) + 1.0).powi(2));
                    let q = d / 4.0 * d_omega;
                    wsum += q * c;
                    lsum += q * c * radiance;
                    Some((q * c * c, radiance))
                })
                .collect();
            let mu = lsum / wsum;
            let var: f64 = weights.iter().map(|&(qc2, l)| qc2 * (l - mu).powi(2)).sum::<f64>()
                / settings.prefilter_samples as f64;
            let sigma = var.sqrt() / wsum;
            let g = levels[offset as usize + t][1] as f64;
            let ratio = (g - mu).abs() / (3.0 * sigma + 1e-3 * mu);
            sum_ratio += (g - mu).abs() / sigma;
            if ratio > worst.0 {
                worst = (ratio, g, mu, sigma);
            }
        }
        let (ratio, g, mu, sigma) = worst;
        eprintln!(
            "roughness {roughness}: mean |GPU − brute| / σ {:.2}; worst texel GPU {g:.4} vs {mu:.4} (σ {sigma:.4}, |error| / (3σ + 1e-3 μ) = {ratio:.2})",
            sum_ratio / (lw * lh) as f64
        );
        worst_ratio = worst_ratio.max(ratio);
    }
    assert!(worst_ratio <= 1.0, "a prefiltered texel is further than 3σ from the brute-force integral");
}

/// Transmission in the hybrid: a thin glass sheet (transmission 1, roughness 0, white) seen from
/// above against a sky that is 1 below the horizon and 0 above. Through one thin interface the
/// path tracer sees (1 − F)·1 + F·0; the hybrid's split sum gives its diffuse weight
/// 1 − F0·C − F90·D times the environment straight through (the table at roughness 0 is the
/// Fresnel term's, so both are 1 − F(n·v) up to the table's interpolation). Tested: every
/// interior hybrid pixel equals the table's prediction within 1e-3 (as in the furnace), and the
/// means of hybrid and path tracer agree within z·se + 3e-3 (z = 3.29, two-sided 0.001; 3e-3 for
/// the table). A hybrid that shaded glass as opaque saw the dark upper sky diffusely: ~0.
#[test]
fn thin_glass_transmits_the_environment_behind_it() {
    let gpu = Gpu::new();
    let mut scene = scene_file("spheres.glb");
    scene.lights.clear();
    let mut glass = scene.materials[0].clone();
    glass.name = "thin glass".into();
    (glass.base_color_factor, glass.metallic, glass.roughness) = ([1.0; 4], 0.0, 0.0);
    glass.transmission_factor = 1.0;
    glass.volume = false;
    scene.materials = vec![glass];
    scene.positions = vec![[-2.0, 0.0, -2.0], [-2.0, 0.0, 2.0], [2.0, 0.0, 2.0], [2.0, 0.0, -2.0]];
    scene.normals = vec![[0.0, 1.0, 0.0]; 4];
    scene.tangents.clear();
    scene.uv0.clear();
    scene.uv1.clear();
    scene.colors.clear();
    scene.triangles = vec![[0, 1, 2], [0, 2, 3]];
    scene.triangle_material = vec![0, 0];
    scene.instances.clear();
    let mut camera = scene.camera(None).unwrap();
    (camera.position, camera.forward, camera.up, camera.yfov) =
        ([0.0, 2.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0], 30f32.to_radians());
    scene.cameras = vec![camera];
    let (w, h) = (64usize, 32usize);
    let sky: Vec<[f32; 3]> = (0..w * h).map(|i| if i / w >= h / 2 { [1.0; 3] } else { [0.0; 3] }).collect();
    let map = EnvironmentMap::from_texels("two-tone sky", w, h, sky).unwrap();
    let size = (48, 48);
    let (hyb, pt, view) = render_pair(&gpu, &scene, Some(&map), [1.0; 3], size, 32, false);
    let table = lut_reference(48);
    let mat = &scene.materials[0];
    let f0 = (((mat.ior - 1.0) / (mat.ior + 1.0)).powi(2) * mat.specular_factor) as f64;
    let f90 = mat.specular_factor as f64;
    let pixels = interior_pixels(&hyb.gbuffer, &view);
    assert!(pixels.len() > 1500, "the sheet should fill the image ({} pixels)", pixels.len());
    let var = pt.variance_of_mean();
    let (mut sh, mut sp, mut se2, mut worst) = (0.0, 0.0, 0.0, 0.0f64);
    for &(i, nv) in &pixels {
        let e = table_bilinear(&table, nv, 0.0);
        let expected = 1.0 - f0 * e[2] - f90 * e[3];
        worst = (0..3).map(|c| (hyb.color[i][c] as f64 - expected).abs()).fold(worst, f64::max);
        sh += hyb.color[i][1] as f64;
        sp += pt.mean[i][1] as f64;
        se2 += var[i][1] as f64;
    }
    let n = pixels.len() as f64;
    let (h_mean, p_mean, se) = (sh / n, sp / n, se2.sqrt() / n);
    eprintln!("thin glass: hybrid {h_mean:.5}, path {p_mean:.5} ± {se:.5}, max |hybrid − table| {worst:.2e}");
    assert!(worst < 1e-3, "hybrid differs from 1 − F0·C − F90·D by {worst:e}");
    assert!((h_mean - p_mean).abs() <= 3.29 * se + 3e-3, "hybrid {h_mean} vs path tracer {p_mean} ± {se}");
    assert!(h_mean > 0.9, "the glass should show the bright sky behind it: {h_mean}");
}

/// The SH9 projection of a large map is not cut short: llvmpipe breaks every loop of an
/// invocation after 65,535 loop iterations in all, and one invocation of `ibl_sh.comp` used to
/// sum every 128th row in full (a 4096×2048 map, the largest lavapipe's storage buffers hold,
/// came out 98 % off). Its coefficients must equal the f64 projection (1e-4 relative to the
/// largest), as the small maps' do.
#[test]
fn sh9_of_a_large_map_is_not_cut_short() {
    let map = synthetic_map(4096, 2048, sky);
    let gpu = Gpu::new();
    let mut scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    let (_, error, _) = sh9_gpu_error(&gpu, &mut scene, &map);
    eprintln!("SH9 of a 4096×2048 map: GPU vs f64 projection {error:.2e} of the largest coefficient");
    assert!(error < 1e-4, "SH9 coefficients off by {error:e} of the largest");
}

/// Sample counts that one invocation could not finish on a CPU device are refused with a clear
/// error, and the largest allowed ones build.
#[test]
fn ibl_sample_counts_are_checked() {
    let gpu = Gpu::new();
    let scene = GpuScene::upload(&gpu, &scene_file("spheres.glb")).unwrap();
    for settings in [
        IblSettings { lut_samples: 0, ..Default::default() },
        IblSettings { lut_samples: IblSettings::MAX_LUT_SAMPLES + 1, ..Default::default() },
        IblSettings { prefilter_samples: IblSettings::MAX_PREFILTER_SAMPLES + 1, ..Default::default() },
    ] {
        let message = IblResources::build(&gpu, &scene, &settings).err().expect("refused").to_string();
        assert!(message.contains("must be 1 to"), "{message}");
    }
    // The largest table is the default one's integral (not cut short): within the default's
    // quadrature error, 1e-3.
    let largest = IblSettings { lut_samples: IblSettings::MAX_LUT_SAMPLES, ..Default::default() };
    let big: Vec<[f32; 4]> = IblResources::build(&gpu, &scene, &largest).unwrap().lut.read(&gpu).unwrap();
    let default: Vec<[f32; 4]> =
        IblResources::build(&gpu, &scene, &IblSettings::default()).unwrap().lut.read(&gpu).unwrap();
    let worst =
        big.iter().flatten().zip(default.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0f32, f32::max);
    assert!(
        worst < 1e-3,
        "the {}-sample table differs from the default by {worst}",
        IblSettings::MAX_LUT_SAMPLES
    );
}

/// `KHR_materials_sheen`'s lobe times n·l for sheenColor 1, written here from the extension's
/// text (not the library's): the Charlie distribution at α = roughness² (roughness at least
/// [`umbra::sheen::ROUGHNESS_MIN`], the kernels' clamp) and Conty Estevez and Kulla's visibility
/// with their fitted Λ.
fn sheen_f_cos(v: glam::DVec3, l: glam::DVec3, roughness: f64) -> f64 {
    let a = roughness.max(umbra::sheen::ROUGHNESS_MIN).powi(2);
    let fit = |x: f64| {
        let t = (1.0 - a) * (1.0 - a);
        let m = |p: f64, q: f64| p * (1.0 - t) + q * t;
        m(21.5473, 25.3245) / (1.0 + m(3.82987, 3.32435) * x.powf(m(0.19823, 0.16801)))
            + m(-1.97760, -1.27393) * x
            + m(-4.32054, -4.85967)
    };
    let lambda = |c: f64| if c < 0.5 { fit(c).exp() } else { (2.0 * fit(0.5) - fit(1.0 - c)).exp() };
    let h = (v + l).normalize();
    let sin2 = 1.0 - h.z * h.z;
    let d = (2.0 + 1.0 / a) * sin2.max(0.0).powf(0.5 / a) / std::f64::consts::TAU;
    d / ((1.0 + lambda(v.z) + lambda(l.z)) * 4.0 * v.z)
}

/// The sheen's directional albedo E(μ, roughness) by a 200 × 200 midpoint rule over the
/// hemisphere (cos θl = t², t uniform, so cells crowd at the horizon; φ over [0, π], doubled),
/// independent of src/sheen.rs's Gauss–Legendre panels. Its own error, against 800 × 800:
/// below 5e-5 (checked in `sheen_albedo_table_matches_an_independent_quadrature`).
fn sheen_albedo_midpoint(mu: f64, roughness: f64, n: usize) -> f64 {
    let mu = mu.clamp(umbra::sheen::COSINE_MIN, 1.0);
    let v = glam::DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let mut sum = 0.0;
    for i in 0..n {
        let t = (i as f64 + 0.5) / n as f64;
        let z = t * t;
        let s = (1.0 - z * z).sqrt();
        for k in 0..n {
            let phi = std::f64::consts::PI * (k as f64 + 0.5) / n as f64;
            sum += 2.0 * t * sheen_f_cos(v, glam::DVec3::new(s * phi.cos(), s * phi.sin(), z), roughness);
        }
    }
    sum * std::f64::consts::TAU / (n * n) as f64
}

/// `f(μ)` tabulated at 129 μ with √μ uniform in [0, 1] and interpolated linearly in √μ (E rises
/// and falls within μ < 0.02).
fn tabulated_sqrt(f: impl Fn(f64) -> f64) -> impl Fn(f64) -> f64 {
    let grid: Vec<f64> = (0..=128).map(|k| f((k as f64 / 128.0).powi(2))).collect();
    move |mu| {
        let p = mu.clamp(0.0, 1.0).sqrt() * 128.0;
        let k = (p as usize).min(127);
        grid[k] + (grid[k + 1] - grid[k]) * (p - k as f64)
    }
}

/// The sheen's albedo table (src/sheen.rs: 32 × 32 over (√μ, roughness), each entry a
/// Gauss–Legendre quadrature, interpolated bilinearly by the kernels) against the independent
/// midpoint quadrature: (a) the midpoint rule's own error (200² against 800², at 12 points) is
/// below 5e-5; (b) at the entries, the table equals it within 1e-4; (c) at the cell centres, the
/// bilinear interpolation's error is below 5e-3 for roughness ≥ 0.25 and n·v ≥ 0.01 (measured
/// 2.9e-3). Where the fitted Λ lets E exceed 1 (roughness < 0.25, n·v < 0.01: E peaks at 3.9
/// within n·v 0.002–0.005 for roughness 0.05) 32 entries do not resolve it: there the error is
/// printed, not bounded (0.46 at n·v 0.0023, roughness 0.05).
#[test]
fn sheen_albedo_table_matches_an_independent_quadrature() {
    use umbra::sheen::{table, table_coordinates, table_lookup, TABLE_SIZE};
    let t = table();
    let mut worst_self = 0.0f64;
    for mu in [0.001, 0.01, 0.1, 0.5] {
        for r in [0.1, 0.5, 1.0] {
            let (coarse, fine) = (sheen_albedo_midpoint(mu, r, 200), sheen_albedo_midpoint(mu, r, 800));
            worst_self = worst_self.max((coarse - fine).abs());
        }
    }
    eprintln!("midpoint 200² vs 800²: max |difference| {worst_self:.2e}");
    assert!(worst_self < 5e-5, "the test's own quadrature is off by {worst_self}");
    let mut worst_entry = (0.0f64, 0.0, 0.0);
    for j in 0..TABLE_SIZE {
        for i in 0..TABLE_SIZE {
            let (mu, r) = table_coordinates(i, j);
            let d = (t[j * TABLE_SIZE + i] as f64 - sheen_albedo_midpoint(mu, r, 200)).abs();
            if d > worst_entry.0 {
                worst_entry = (d, mu, r);
            }
        }
    }
    eprintln!(
        "table entries: max |E_table − E| {:.2e} at n·v {:.4}, roughness {:.3}",
        worst_entry.0, worst_entry.1, worst_entry.2
    );
    assert!(worst_entry.0 < 1e-4, "table entry off by {:?}", worst_entry);
    let (mut worst_all, mut worst_smooth) = ((0.0f64, 0.0, 0.0), (0.0f64, 0.0, 0.0));
    let step = 1.0 / (TABLE_SIZE - 1) as f64;
    for j in 0..TABLE_SIZE - 1 {
        for i in 0..TABLE_SIZE - 1 {
            let x = (i as f64 + 0.5) * step;
            let (mu, r) = (x * x, (j as f64 + 0.5) * step);
            let d = (table_lookup(&t, mu, r) - sheen_albedo_midpoint(mu, r, 200)).abs();
            if d > worst_all.0 {
                worst_all = (d, mu, r);
            }
            if r >= 0.25 && mu >= 0.01 && d > worst_smooth.0 {
                worst_smooth = (d, mu, r);
            }
        }
    }
    eprintln!(
        "bilinear at cell centres: max error {:.2e} (n·v {:.4}, roughness {:.3}); for roughness ≥ 0.25, n·v ≥ 0.01: {:.2e} (n·v {:.4}, roughness {:.3})",
        worst_all.0, worst_all.1, worst_all.2, worst_smooth.0, worst_smooth.1, worst_smooth.2
    );
    assert!(worst_smooth.0 < 5e-3, "interpolation error {worst_smooth:?}");
}

/// `KHR_materials_sheen` in the furnace (environment 1, one scattering event), three spheres:
/// (a) the sheen alone (black base, specular 0; sheen white, roughness ½): the path tracer's
///     albedo is the lobe's E(n·v), here by the independent midpoint quadrature;
/// (b) a grey diffuse base (½, specular 0) under a sheen of colour 0.8, roughness 1: the
///     extension's layering, 0.8 E(n·v) + ½ ∫ max(0, min(1 − 0.8 E(n·v), 1 − 0.8 E(n·l))) cos/π;
/// (c) (b) under a clear coat (weight 1, roughness 0.3): (1 − w) (b) + w (A + B) at the coat's
///     roughness, the coat over the sheen.
/// Per n·v bin (< 0.3, 0.3–0.7, > 0.7): the path tracer's mean equals that albedo within
/// z·se + 1e-4 (z 3.26: two-sided 0.01, Šidák over the 9 bins) and stays at most 1; every interior
/// hybrid pixel equals its own prediction within 1e-3 (the table's E at n·v, the extension's
/// simplified scaling 1 − 0.8 E(n·v) of the base, the sheen lit by the irradiance), and the
/// hybrid's difference from the path tracer is that prediction's difference from the exact
/// layering (the approximation, printed per bin) within z·se + 1e-3 + 1e-4.
#[test]
fn white_furnace_sheen_is_the_extensions_layering() {
    let gpu = Gpu::new();
    let nodes = 48;
    let table = lut_reference(nodes);
    let sheen_table = umbra::sheen::table();
    let (size, spp) = ((96, 96), 32);
    let z = 3.26;
    let bins: [(f64, f64); 3] = [(0.0, 0.3), (0.3, 0.7), (0.7, 1.01)];
    let coat_roughness = 0.3f64;
    // (base grey, sheen colour, sheen roughness, coat)
    let cases: [(f64, f64, f64, f64); 3] = [(0.0, 1.0, 0.5, 0.0), (0.5, 0.8, 1.0, 0.0), (0.5, 0.8, 1.0, 1.0)];
    for (grey, colour, roughness, coat) in cases {
        let mut scene = sphere_scene([grey as f32; 3], 0.0, 1.0);
        let m = &mut scene.materials[0];
        m.specular_factor = 0.0;
        m.sheen_color = [colour as f32; 3];
        m.sheen_roughness = roughness as f32;
        m.clearcoat = coat as f32;
        m.clearcoat_roughness = coat_roughness as f32;
        let e = tabulated_sqrt(|mu| sheen_albedo_midpoint(mu, roughness, 200));
        // ∫ max(0, min(1 − c E(v), 1 − c E(l))) cos/π dl = 2 ∫ … z dz, midpoint in z.
        let scaled_base = |nv: f64| {
            let sv = 1.0 - colour * e(nv);
            let n = 2000;
            let integral: f64 = (0..n)
                .map(|k| {
                    let zl = (k as f64 + 0.5) / n as f64;
                    2.0 * zl * sv.min(1.0 - colour * e(zl)).max(0.0)
                })
                .sum::<f64>()
                / n as f64;
            grey * integral
        };
        let weight = |nv: f64| coat * (0.04 + 0.96 * (1.0 - nv.clamp(0.0, 1.0)).powi(5));
        let layered = |nv: f64, sheened: f64, coat_table: [f64; 4]| {
            let w = weight(nv);
            (1.0 - w) * sheened + w * (coat_table[0] + coat_table[1])
        };
        let exact = tabulated_sqrt(|nv| {
            layered(nv, colour * e(nv) + scaled_base(nv), lut_entry(nv, coat_roughness, nodes))
        });
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [1.0; 3], size, spp, false);
        let var = pt.variance_of_mean();
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        for &(lo, hi) in &bins {
            let (mut n, mut sp, mut sh, mut se2, mut s_e, mut s_t, mut worst) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0f64);
            for &(i, nv) in pixels.iter().filter(|p| p.1 >= lo && p.1 < hi) {
                let et = umbra::sheen::table_lookup(&sheen_table, nv, roughness);
                let t = layered(
                    nv,
                    (1.0 - colour * et).max(0.0) * grey + colour * et,
                    table_bilinear(&table, nv, coat_roughness),
                );
                worst = (0..3).map(|c| (hyb.color[i][c] as f64 - t).abs()).fold(worst, f64::max);
                sp += pt.mean[i][1] as f64;
                sh += hyb.color[i][1] as f64;
                se2 += var[i][1] as f64;
                s_e += box_filtered(&scene, size, i, &exact);
                s_t += t;
                n += 1.0;
            }
            let se = se2.sqrt() / n;
            let (p, h, e, t) = (sp / n, sh / n, s_e / n, s_t / n);
            eprintln!(
                "base {grey} sheen {colour} r {roughness} coat {coat}, n·v {lo:.1}–{:.1}: {} pixels, path {p:.5}, exact {e:.5}, path − exact {:+.5}, se {se:.5}; hybrid {h:.5}, hybrid − path {:+.5} (its approximation: prediction − exact {:+.5}), max |hybrid − prediction| {worst:.2e}",
                hi.min(1.0),
                n as usize,
                p - e,
                h - p,
                t - e
            );
            assert!(n >= 50.0, "too few pixels in n·v bin {lo}–{hi}: {n}");
            assert!(e <= 1.0 && p <= 1.0 + z * se + 1e-4, "albedo above 1: exact {e}, path {p} ± {se}");
            assert!(
                (p - e).abs() <= z * se + 1e-4,
                "base {grey} sheen {colour} coat {coat}: path tracer {p} vs the layering's albedo {e} ± {se} (n·v {lo}–{hi})"
            );
            assert!(worst < 1e-3, "hybrid differs from its prediction by {worst:e}");
            assert!(
                ((h - p) - (t - e)).abs() <= z * se + 1e-3 + 1e-4,
                "hybrid − path {} is not the approximation's {} ± {se}",
                h - p,
                t - e
            );
        }
    }
}

/// `KHR_materials_iridescence` in the furnace (environment 1, one scattering event), three
/// spheres under a film of weight 1: a white dielectric (roughness 0.5) under a film of ior 2.0,
/// 300 nm (its Fresnel up to 0.3 where the bare one is 0.04: the diffuse lobe must give way); a
/// white metal (roughness 0.3) under a film of ior 1.5, 450 nm; a copper-coloured metal (0.955,
/// 0.638, 0.538; roughness 0.6) under the default film (ior 1.3) of 250 nm; each also rendered
/// without the film.
///
/// Energy: glTF's own layering is not energy-conserving for a white dielectric at grazing angles
/// (its diffuse lobe gives way by 1 − F at the light's half vector, the specular lobe takes F at
/// its own: a smooth white dielectric's albedo is 1.20 at n·v < 0.3, the split-sum furnace test
/// above), so the bound is: per n·v bin (< 0.3, 0.3–0.7, > 0.7) and channel, the path tracer's mean
/// with the film stays at most max(1, without the film) + z·se + 1e-4 (z 3.39: one-sided 0.01,
/// Šidák over the 27 bins and channels; se of the difference). Weighting the dielectric's diffuse
/// lobe by the bare Fresnel instead of the film's gives up to 1.13 at n·v > 0.7 (1.17 below 0.3).
///
/// The hybrid takes the film's Fresnel at n·v for its whole split-sum lobe, where the path tracer
/// takes it at each microfacet's v·h: their means per bin and channel differ by at most 0.15 at
/// n·v < 0.3, 0.06 at 0.3–0.7 and 0.015 above (measured: 0.133, 0.052, 0.008; docs/methods.md "Hybrid:
/// what it approximates"), + z·se. A hybrid that left the film out would be 0.10 off on the
/// copper sphere at n·v > 0.7.
#[test]
fn white_furnace_iridescence_keeps_energy() {
    let gpu = Gpu::new();
    let (size, spp) = ((96, 96), 32);
    let z = 3.39;
    let bins: [(f64, f64, f64); 3] = [(0.0, 0.3, 0.15), (0.3, 0.7, 0.06), (0.7, 1.01, 0.015)];
    // (base, metallic, roughness, film ior, thickness nm)
    let cases: [([f32; 3], f32, f32, f32, f32); 3] = [
        ([1.0; 3], 0.0, 0.5, 2.0, 300.0),
        ([1.0; 3], 1.0, 0.3, 1.5, 450.0),
        ([0.955, 0.638, 0.538], 1.0, 0.6, 1.3, 250.0),
    ];
    let mut failures = Vec::new();
    let mut worst = [0.0f64; 3];
    for (base, metallic, roughness, ior, thickness) in cases {
        let plain_scene = sphere_scene(base, metallic, roughness);
        let mut scene = plain_scene.clone();
        let m = &mut scene.materials[0];
        m.iridescence = 1.0;
        m.iridescence_ior = ior;
        m.iridescence_thickness = [thickness; 2];
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [1.0; 3], size, spp, false);
        let (_, plain, _) = render_pair(&gpu, &plain_scene, None, [1.0; 3], size, spp, false);
        let (var, plain_var) = (pt.variance_of_mean(), plain.variance_of_mean());
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        for (b, &(lo, hi, bound)) in bins.iter().enumerate() {
            let inside: Vec<usize> = pixels.iter().filter(|p| p.1 >= lo && p.1 < hi).map(|p| p.0).collect();
            let n = inside.len() as f64;
            assert!(n >= 50.0, "too few pixels in n·v bin {lo}–{hi}: {n}");
            for c in 0..3 {
                let mean = |image: &[[f32; 4]]| inside.iter().map(|&i| image[i][c] as f64).sum::<f64>() / n;
                let se = |v: &[[f32; 3]]| inside.iter().map(|&i| v[i][c] as f64).sum::<f64>().sqrt() / n;
                let (p, h, q) = (mean(&pt.mean), mean(&hyb.color), mean(&plain.mean));
                let (se, se_plain) = (se(&var), se(&plain_var));
                eprintln!(
                    "base {base:?} metallic {metallic} roughness {roughness} film {ior} {thickness} nm, n·v {lo:.1}–{:.1}, channel {c}: path {p:.4} ± {se:.4} (without the film {q:.4}), hybrid {h:.4}, hybrid − path {:+.4}",
                    hi.min(1.0),
                    h - p
                );
                worst[b] = worst[b].max((h - p).abs());
                if p > q.max(1.0) + z * (se * se + se_plain * se_plain).sqrt() + 1e-4 {
                    failures.push(format!(
                        "film {ior} {thickness} nm, n·v {lo}–{hi}, channel {c}: albedo {p} ± {se} above max(1, {q})"
                    ));
                }
                if (h - p).abs() > bound + z * se {
                    failures.push(format!(
                        "film {ior} {thickness} nm, n·v {lo}–{hi}, channel {c}: hybrid {h} vs path {p} ± {se}"
                    ));
                }
            }
        }
    }
    eprintln!("largest |hybrid − path| per n·v bin: {worst:.4?}");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `sphere_scene` made anisotropic (`KHR_materials_anisotropy`, `strength`, no rotation), its
/// tangents along the parallels (around +y; any at the poles).
fn anisotropic_sphere(metallic: f32, roughness: f32, strength: f32) -> Scene {
    let mut scene = sphere_scene([0.9; 3], metallic, roughness);
    scene.tangents = scene
        .normals
        .iter()
        .map(|n| {
            let t = glam::Vec3::Y.cross(glam::Vec3::from(*n)).try_normalize().unwrap_or(glam::Vec3::X);
            [t.x, t.y, t.z, 1.0]
        })
        .collect();
    scene.materials[0].anisotropy_strength = strength;
    scene
}

/// Mean |hybrid − path| over the interior pixels relative to the path tracer's mean (green).
fn interior_difference(
    hyb: &umbra::render::HybridImage,
    pt: &umbra::render::PathImage,
    view: &[glam::Vec3],
) -> f64 {
    let pixels = interior_pixels(&hyb.gbuffer, view);
    let mean: f64 = pixels.iter().map(|&(i, _)| pt.mean[i][1] as f64).sum::<f64>() / pixels.len() as f64;
    let diff: f64 = pixels.iter().map(|&(i, _)| (hyb.color[i][1] as f64 - pt.mean[i][1] as f64).abs()).sum();
    diff / pixels.len() as f64 / mean
}

/// `KHR_materials_anisotropy` in the hybrid against the path tracer, on one anisotropic metal
/// sphere (roughness 0.4, strength 0.8, the direction along the parallels), 64², hybrid 4×4
/// supersampled, path tracer 64 spp of direct light.
/// (a) Under a directional light alone, the hybrid shades through the same BSDF from its
///     G-buffer (the anisotropy's direction and strength in gb_layers): mean |hybrid − path| per
///     interior pixel within 2 % of the mean (the pixel filters' difference; the isotropic
///     sphere's, printed, is of the same size), while the isotropic sphere's path-traced image
///     differs from the anisotropic one by more than 10 % (the bound has power: the hybrid
///     without the anisotropy fails it).
/// (b) Under a sky (0.5 sin(elevation)), with and without the bright disc, the environment
///     through the bent normal (the Sample Viewer's approximation, the prefiltered map at the
///     base's roughness): the sphere's mean luminance against the path tracer's, relative error
///     within the bounds docs/methods.md's known approximations state (a regression bound: the
///     approximation's error is large, +16 to +38 % on the smooth sky, +150 to +200 % with the
///     disc, where the isotropic sphere's split sum is within 6 %).
#[test]
fn anisotropic_sphere_hybrid_matches_path_tracer() {
    let gpu = Gpu::new();
    let (size, spp) = ((64, 64), 64);
    let sun = common::light(
        umbra::scene::LightKind::Directional,
        glam::Vec3::ZERO,
        glam::Vec3::new(-0.4, -0.5, -1.0),
        3.0,
    );
    let mut images = Vec::new();
    for strength in [0.8, 0.0] {
        let mut scene = anisotropic_sphere(1.0, 0.4, strength);
        scene.lights = vec![sun.clone()];
        let (hyb, pt, view) = render_pair(&gpu, &scene, None, [0.0; 3], size, spp, true);
        let difference = interior_difference(&hyb, &pt, &view);
        eprintln!("directional light, strength {strength}: mean |hybrid − path| / mean {difference:.4}");
        assert!(
            difference < 0.02,
            "strength {strength}: hybrid differs from the path tracer by {difference}"
        );
        images.push((hyb, pt, view));
    }
    let ((_, aniso, view), (_, iso, _)) = (&images[0], &images[1]);
    let pixels = interior_pixels(&images[0].0.gbuffer, view);
    let mean: f64 = pixels.iter().map(|&(i, _)| aniso.mean[i][1] as f64).sum::<f64>() / pixels.len() as f64;
    let power: f64 =
        pixels.iter().map(|&(i, _)| (aniso.mean[i][1] - iso.mean[i][1]).abs() as f64).sum::<f64>()
            / pixels.len() as f64
            / mean;
    eprintln!("anisotropic vs isotropic path-traced: {power:.3}");
    assert!(power > 0.1, "the anisotropy changes the image by only {power}");

    let lum = |c: &[f32]| (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f64;
    let smooth = |d: [f64; 3]| if d[1] < 0.0 { [0.0; 3] } else { [0.5 * d[1], 0.45 * d[1], 0.4 * d[1]] };
    type Sky<'a> = &'a dyn Fn([f64; 3]) -> [f64; 3];
    let skies: [(&str, Sky); 2] = [("disc", &sky), ("smooth", &smooth)];
    for ((name, f), strength) in skies.iter().flat_map(|s| [(s, 0.8f32), (s, 0.5), (s, 0.0)]) {
        let map = synthetic_map(256, 128, f);
        let scene = anisotropic_sphere(1.0, 0.4, strength);
        let (hyb, pt, view) = render_pair(&gpu, &scene, Some(&map), [1.0; 3], size, spp, true);
        let pixels = interior_pixels(&hyb.gbuffer, &view);
        let var = pt.variance_of_mean();
        let (mut h, mut p, mut v) = (0.0, 0.0, 0.0);
        for &(i, _) in &pixels {
            h += lum(&hyb.color[i]);
            p += lum(&pt.mean[i]);
            v += var[i][1] as f64;
        }
        let n = pixels.len() as f64;
        let (h, p, se) = (h / n, p / n, v.sqrt() / n);
        let error = (h - p) / p;
        eprintln!("sky {name}, strength {strength}: hybrid {h:.4}, path {p:.4} ± {se:.4}: relative error {error:+.4}");
        // The bounds docs/methods.md states (measured +0.38 / +0.16 smooth, +1.47 / +2.00 with the disc
        // at strength 0.8 / 0.5; the isotropic split sum's own +0.003 and −0.05).
        let bound = match (*name, strength > 0.0) {
            ("smooth", true) => 0.45,
            (_, true) => 2.2,
            _ => 0.06,
        };
        assert!(
            error.abs() < bound,
            "sky {name}, strength {strength}: the hybrid's error {error} exceeds {bound}"
        );
    }
}
