//! Shared test harness: a validated context that fails the test on any validation message,
//! including those raised while the context is destroyed; the regularised incomplete gamma
//! function behind the statistical tests' chi-square and normal p-values; scenes built in code
//! from triangle soups.
#![allow(dead_code)]

use glam::Vec3;
use std::ops::Deref;
use std::sync::Arc;
use umbra::scene::{Camera, Light, LightKind, Material, Scene};
use umbra::vk::{Context, ContextDesc, ValidationLog};

/// A context with `VK_LAYER_KHRONOS_validation` on. Dropping it destroys the device and then
/// panics if the layer reported anything during the test.
pub struct Gpu {
    ctx: Option<Context>,
    log: Arc<ValidationLog>,
}

impl Gpu {
    /// A validated context on the default device (lavapipe in CI).
    pub fn new() -> Self {
        let ctx = Context::new(&ContextDesc { validation: Some(true), device: None })
            .unwrap_or_else(|e| panic!("creating a validated Vulkan context: {e}"));
        let log = ctx.validation().expect("validation is on");
        Self { ctx: Some(ctx), log }
    }

    /// The validation log, for tests that provoke a message on purpose.
    pub fn log(&self) -> &ValidationLog {
        &self.log
    }
}

impl Deref for Gpu {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.ctx.as_ref().expect("context alive until drop")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        drop(self.ctx.take());
        let messages = self.log.take();
        if !messages.is_empty() && !std::thread::panicking() {
            panic!("{} validation message(s):\n{}", messages.len(), messages.join("\n"));
        }
    }
}

/// A fresh, empty folder for one test's files: `umbra-<name>-<pid>` in the temporary directory.
pub fn fresh_folder(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("umbra-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The names of the entries of `dir`, sorted.
pub fn file_names(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Writes `bytes` to `path` and makes it read-only (mode 0444).
pub fn read_only_file(path: &std::path::Path, bytes: &[u8]) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(path, bytes).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o444)).unwrap();
}

/// The external asset collection (larger Khronos models, Sponza, HDR maps) that `UMBRA_ASSETS`
/// names, with its `gltf/` folder; `None` when unset, and the tests over it then skip with a note
/// (a clone alone passes `cargo test`). Set to a folder without `gltf/`, it panics: a wrong path
/// must not pass as "no assets". `.ci/run` names `../shared/assets` when it exists.
pub fn external_assets() -> Option<std::path::PathBuf> {
    let dir = std::path::PathBuf::from(std::env::var_os("UMBRA_ASSETS")?);
    assert!(
        dir.join("gltf").is_dir(),
        "UMBRA_ASSETS={} has no gltf/ folder: name the assets folder (e.g. ../shared/assets), or unset \
         UMBRA_ASSETS to skip the tests over it",
        dir.display()
    );
    Some(dir)
}

/// [`external_assets`]' `gltf/` folder, or `None` after printing that `test` is skipped.
pub fn external_gltf(test: &str) -> Option<std::path::PathBuf> {
    let dir = external_assets().map(|d| d.join("gltf"));
    if dir.is_none() {
        eprintln!("note: {test}: UMBRA_ASSETS is unset; the external models are left out");
    }
    dir
}

/// Runs one of umbra's binaries with `UMBRA_VALIDATION=1` and asserts that it succeeded and
/// logged no error (validation messages are logged as errors); returns its stderr.
pub fn run_validated(command: &mut std::process::Command) -> String {
    let out = command.env("UMBRA_VALIDATION", "1").output().expect("run the binary");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("ERROR"), "validation or other errors: {stderr}");
    stderr
}

/// ln Γ(z) for z > 0 (Lanczos approximation, g = 7, n = 9).
pub fn ln_gamma(z: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let z = z - 1.0;
    let mut s = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        s += c / (z + i as f64);
    }
    let t = z + 7.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (z + 0.5) * t.ln() - t + s.ln()
}

/// The two-sided p-value of Student's t statistic `t` with `df` degrees of freedom:
/// I_x(df/2, 1/2) at x = df / (df + t²) (the regularised incomplete beta function, Numerical
/// Recipes' betai with Lentz's continued fraction).
pub fn student_t_p(t: f64, df: f64) -> f64 {
    let (a, b, x) = (0.5 * df, 0.5, df / (df + t * t));
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    let fraction = |a: f64, b: f64, x: f64| {
        let tiny = 1e-300;
        let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
        let mut c = 1.0;
        let mut d = 1.0 - qab * x / qap;
        d = if d.abs() < tiny { tiny } else { d };
        d = 1.0 / d;
        let mut h = d;
        for m in 1..10_000 {
            let m = m as f64;
            let m2 = 2.0 * m;
            for aa in [
                m * (b - m) * x / ((qam + m2) * (a + m2)),
                -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
            ] {
                d = 1.0 + aa * d;
                d = if d.abs() < tiny { tiny } else { d };
                c = 1.0 + aa / c;
                c = if c.abs() < tiny { tiny } else { c };
                d = 1.0 / d;
                h *= d * c;
            }
            if (d * c - 1.0).abs() < 1e-15 {
                break;
            }
        }
        h
    };
    if x < (a + 1.0) / (a + b + 2.0) {
        front * fraction(a, b, x) / a
    } else {
        1.0 - front * fraction(b, a, 1.0 - x) / b
    }
}

/// Regularised upper incomplete gamma Q(a, x) (Numerical Recipes' gammq).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        let (mut sum, mut term, mut n) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - ln_gamma(a)).exp()
    } else {
        // Lentz's continued fraction.
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + a * x.ln() - ln_gamma(a)).exp() * h
    }
}

// ---------------------------------------------------------------------------------------------
// Scenes built in code

/// A scene from triangle soups, one material per soup (the glTF default material made
/// dielectric, so shading is Lambert-dominated), face normals.
pub fn build(name: &str, soups: &[Vec<[Vec3; 3]>], lights: Vec<Light>, camera: Camera) -> Scene {
    let lambert = Material { metallic: 0.0, roughness: 1.0, ..Default::default() };
    let soups: Vec<_> = soups.iter().map(|s| (s.clone(), lambert.clone())).collect();
    build_with(name, &soups, lights, camera)
}

/// A scene from triangle soups, each with its material, face normals; the emissive-triangle
/// table built.
pub fn build_with(
    name: &str,
    soups: &[(Vec<[Vec3; 3]>, Material)],
    lights: Vec<Light>,
    camera: Camera,
) -> Scene {
    let mut scene = Scene { name: name.into(), ..Default::default() };
    for (m, (soup, material)) in soups.iter().enumerate() {
        scene.materials.push(material.clone());
        for tri in soup {
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
            let first = scene.positions.len() as u32;
            for v in tri {
                scene.positions.push(v.to_array());
                scene.normals.push(n.to_array());
            }
            scene.triangles.push([first, first + 1, first + 2]);
            scene.triangle_material.push(m as u32);
        }
    }
    scene.lights = lights;
    scene.cameras = vec![camera];
    scene.update_emissive();
    scene
}

/// Two triangles of the quad centre ± u ± v, facing u × v.
pub fn quad(centre: Vec3, u: Vec3, v: Vec3) -> Vec<[Vec3; 3]> {
    let (a, b, c, d) = (centre - u - v, centre + u - v, centre + u + v, centre - u + v);
    vec![[a, b, c], [a, c, d]]
}

/// An axis-aligned box's twelve triangles, facing out.
pub fn cuboid(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let c = 0.5 * (lo + hi);
    let h = 0.5 * (hi - lo);
    let mut out = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let u = Vec3::AXES[(axis + 1) % 3] * h[(axis + 1) % 3];
            let v = Vec3::AXES[(axis + 2) % 3] * h[(axis + 2) % 3];
            let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
            out.extend(quad(c + n * h[axis], u, v));
        }
    }
    out
}

pub fn light(kind: LightKind, position: Vec3, direction: Vec3, intensity: f32) -> Light {
    Light {
        name: String::new(),
        kind,
        position: position.to_array(),
        direction: direction.normalize().to_array(),
        color: [1.0; 3],
        intensity,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: if kind == LightKind::Spot { 0.5 } else { std::f32::consts::PI },
    }
}

pub fn camera(position: Vec3, target: Vec3) -> Camera {
    let forward = (target - position).normalize();
    let up = (Vec3::Y - forward * forward.dot(Vec3::Y)).normalize();
    Camera {
        position: position.to_array(),
        forward: forward.to_array(),
        up: up.to_array(),
        yfov: 0.8,
        aspect: None,
        znear: 0.05,
        orthographic: None,
        jitter: [0.0; 2],
    }
}

/// Standard base64 with padding (data URIs of generated glTF files).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for i in 0..4 {
            out.push(if i <= chunk.len() {
                ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// A unit icosphere around the origin with `subdivisions`, its triangles wound to face inwards:
/// a closed room seen from inside.
pub fn inside_out_sphere(subdivisions: u32) -> Vec<[Vec3; 3]> {
    umbra::procedural::icosphere(subdivisions, Vec3::ZERO, 1.0)
        .soup()
        .into_iter()
        .map(|[a, b, c]| [a, c, b])
        .collect()
}

/// `scene` uploaded and a probe volume over `grid` baked in it (default lighting settings).
pub fn baked_probes(
    gpu: &Gpu,
    scene: &Scene,
    grid: umbra::passes::probes::ProbeGrid,
    settings: &umbra::passes::probes::ProbeSettings,
) -> umbra::passes::probes::ProbeVolume {
    let gpu_scene = umbra::gpu::scene::GpuScene::upload(gpu, scene).unwrap();
    let passes = umbra::render::Passes::new(gpu, &gpu_scene);
    let mut volume = umbra::passes::probes::ProbeVolume::with_grid(gpu, grid, settings).unwrap();
    passes.bake_probes(&gpu_scene, &mut volume, &Default::default(), |_, _| {}).unwrap();
    volume
}

pub mod quad;

/// A linear texture of one row of `texels` (nearest filtering, repeat).
pub fn row_texture(name: &str, texels: &[[u8; 4]]) -> umbra::scene::Texture {
    use umbra::scene::{Filter, Sampler, Texture, Wrap};
    Texture {
        name: name.into(),
        width: texels.len() as u32,
        height: 1,
        rgba8: texels.concat(),
        srgb: false,
        sampler: Sampler {
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            mag_filter: Filter::Nearest,
            min_filter: Filter::Nearest,
            mipmaps: false,
            mipmap_filter: Filter::Nearest,
        },
    }
}

/// Runs `sample_test.comp` in `mode` over `count` cases whose inputs are `input` (the mode's
/// texels per case, in order): the first three channels of each case's result.
pub fn sample_test_rgb(gpu: &Gpu, name: &str, mode: u32, input: &[[f32; 4]], count: u32) -> Vec<[f64; 3]> {
    use umbra::gpu::kernels::sample_test;
    use umbra::gpu::layout::SampleTestParams;
    use umbra::gpu::Pipeline;
    use umbra::vk::{raw, Buffer, MemoryLocation};
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let directions = Buffer::upload(gpu, &format!("{name} cases"), input, usage).unwrap();
    let results =
        Buffer::new(gpu, &format!("{name} values"), count as u64 * 16, usage, MemoryLocation::GpuOnly)
            .unwrap();
    let pipeline = Pipeline::<sample_test::Kernel>::plain(gpu).unwrap();
    let params = SampleTestParams { mode, count, ..Default::default() };
    gpu.record(|rec| {
        let resources = sample_test::Resources { directions: &directions, results: &results };
        pipeline.record(rec, &resources, &params, [count, 1, 1])
    })
    .unwrap();
    let out: Vec<[f32; 4]> = results.read(gpu).unwrap();
    out.iter().map(|r| [r[0] as f64, r[1] as f64, r[2] as f64]).collect()
}

/// Runs `sample_test.comp` through `pipeline` with `params` (its mode, count, surface kind and
/// parameters) over `input` (the mode's texels), the sheen's albedo table appended as the kernel
/// reads it: every invocation's result.
pub fn sample_test_run(
    gpu: &Gpu,
    pipeline: &umbra::gpu::Pipeline<umbra::gpu::kernels::sample_test::Kernel>,
    params: &umbra::gpu::layout::SampleTestParams,
    input: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    use umbra::gpu::kernels::sample_test;
    use umbra::vk::{raw, Buffer, MemoryLocation};
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let mut texels: Vec<[f32; 4]> = input.to_vec();
    texels.push([0.0; 4]);
    texels.extend(umbra::sheen::table().chunks(4).map(|c| [c[0], c[1], c[2], c[3]]));
    let directions = Buffer::upload(gpu, "sample test inputs", &texels, usage).unwrap();
    let results =
        Buffer::new(gpu, "sample test results", params.count as u64 * 16, usage, MemoryLocation::GpuOnly)
            .unwrap();
    gpu.record(|rec| {
        let resources = sample_test::Resources { directions: &directions, results: &results };
        pipeline.record(rec, &resources, params, [params.count, 1, 1])
    })
    .unwrap();
    results.read(gpu).unwrap()
}

/// Pixels whose 3×3 neighbourhood lies on one surface (the same material, every normal's cosine
/// to the centre's above `min_cos`) with smooth lighting (each neighbour's `color` within 25 % of
/// the centre's: no shadow edge crosses the pixel): there the path tracer's box-filtered pixel and
/// the G-buffer's centre sample see the same shading (tests/hybrid.rs, tests/orthographic.rs).
pub fn interior_pixels(
    g: &umbra::passes::gbuffer::GBufferData,
    color: &[[f32; 4]],
    min_cos: f32,
) -> Vec<bool> {
    use umbra::passes::gbuffer::GBUFFER_NO_SURFACE;
    let (w, h) = (g.size.0 as i64, g.size.1 as i64);
    let mut keep = vec![false; (w * h) as usize];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let c = (y * w + x) as usize;
            if g.material[c][0] == GBUFFER_NO_SURFACE {
                continue;
            }
            let nc = Vec3::from_slice(&g.normal[c][..3]);
            keep[c] = (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let i = ((y + dy) * w + x + dx) as usize;
                    g.material[i][0] == g.material[c][0]
                        && Vec3::from_slice(&g.normal[i][..3]).dot(nc) > min_cos
                        && (0..3).all(|k| (color[i][k] - color[c][k]).abs() <= 0.25 * color[c][k])
                })
            });
        }
    }
    keep
}

/// Over the pixels `keep` marks: how many, how many of them have a channel of `color` more than
/// 4 standard errors of the path-traced `reference`'s mean from it (with 2e-3 relative allowed
/// for the G-buffer's half floats), and the largest |z|.
pub fn z_outliers(
    reference: &umbra::render::PathImage,
    color: &[[f32; 4]],
    keep: &[bool],
) -> (usize, usize, f32) {
    let variance = reference.variance_of_mean();
    let (mut compared, mut outliers, mut worst) = (0, 0, 0.0f32);
    for i in (0..keep.len()).filter(|&i| keep[i]) {
        compared += 1;
        let bad = (0..3).any(|c| {
            let (d, r) = (color[i][c], reference.mean[i][c]);
            let z = (d - r).abs() / (variance[i][c].sqrt() + 2e-3 * r.abs() + 1e-6);
            worst = worst.max(z);
            z > 4.0
        });
        outliers += bad as usize;
    }
    (compared, outliers, worst)
}

/// Relative MSE of an RGBA image against an RGB or RGBA reference: the mean over pixels and the
/// three colour channels of (x − ref)² / (ref² + 0.01).
pub fn relative_mse<const N: usize>(image: &[[f32; 4]], reference: &[[f32; N]]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(p, r)| {
            (0..3).map(|c| ((p[c] - r[c]) as f64).powi(2) / ((r[c] as f64).powi(2) + 0.01)).sum::<f64>()
        })
        .sum();
    sum / (image.len() * 3) as f64
}

/// A small counter-based generator (SplitMix64), so synthetic images are the same on every run.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A standard normal number (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u = self.next_f64().max(1e-300);
        let v = self.next_f64();
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

/// A path tracer's image of `size` at `spp` samples per pixel with no pixels yet, for the
/// denoiser's tests to fill with [`push_noisy_pixel`].
pub fn synthetic_image(size: (u32, u32), spp: u32) -> umbra::render::PathImage {
    umbra::render::PathImage {
        size,
        spp,
        mean: Vec::new(),
        moment: Vec::new(),
        albedo: Vec::new(),
        normal_depth: Vec::new(),
        emission: Vec::new(),
        lobe_split: None,
        nonfinite_samples: 0,
        nonfinite_sources: 0,
        gpu_ms: 0.0,
        segments: 0,
        marches_exhausted: 0,
    }
}

/// Appends a pixel of `image.spp` samples, each the true `radiance` × (1 + `noise` g) with g a
/// standard normal number shared by the channels (a path's channels move together): its mean
/// (sample count in alpha), mean square, albedo, normal and distance, and no emission.
pub fn push_noisy_pixel(
    image: &mut umbra::render::PathImage,
    rng: &mut Rng,
    noise: f64,
    radiance: [f32; 3],
    albedo: [f32; 3],
    normal_depth: [f32; 4],
) {
    let spp = image.spp;
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..spp {
        let g = 1.0 + noise * rng.normal();
        for c in 0..3 {
            let s = radiance[c] as f64 * g;
            sum[c] += s;
            sum2[c] += s * s;
        }
    }
    let n = spp as f64;
    image.mean.push([(sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32, spp as f32]);
    image.moment.push([(sum2[0] / n) as f32, (sum2[1] / n) as f32, (sum2[2] / n) as f32, 0.0]);
    image.albedo.push([albedo[0], albedo[1], albedo[2], 1.0]);
    image.normal_depth.push(normal_depth);
    image.emission.push([0.0; 4]);
}
