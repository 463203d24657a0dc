//! Ambient occlusion: RTAO against analytic values, SSAO against RTAO where SSAO's assumptions
//! hold, SSAO's three known failures measured against RTAO, and the blur's depth awareness.
//!
//! AO(p) = (1/π) ∫ V_r(p, ω) cos θ dω (src/passes/ao.rs). Two analytic cases, both from the fact
//! that cosine-weighted directions project uniformly onto the unit disk of the tangent plane:
//! - a floor point at distance d from a perpendicular wall (taller than r): the rays that reach
//!   the wall within r are those whose disk projection has a component towards the wall above
//!   a = d/r, a circular segment: AO = 1 − (acos a − a√(1 − a²))/π;
//! - a floor point under a parallel ceiling at height h: rays reach it within r when cos θ > h/r:
//!   AO = (h/r)².

mod common;

use common::Gpu;
use glam::Vec3;
use umbra::gpu::scene::{GpuScene, SceneArrays};
use umbra::passes::ao::AoSettings;
use umbra::render::{ambient_occlusion, camera_params, AoImage, AoMethod};
use umbra::scene::{Camera, Material, Scene};

/// A scene of quads (one grey diffuse material), built in memory.
#[derive(Default)]
struct Quads {
    scene: Scene,
}

impl Quads {
    fn new() -> Self {
        let mut q = Self::default();
        q.scene.name = "ao-test".into();
        q.scene.materials.push(Material {
            metallic: 0.0,
            base_color_factor: [0.8, 0.8, 0.8, 1.0],
            ..Default::default()
        });
        q
    }

    /// The parallelogram `corner`, `corner + u`, `corner + u + v`, `corner + v`, facing u × v.
    fn quad(mut self, corner: Vec3, u: Vec3, v: Vec3) -> Self {
        let s = &mut self.scene;
        let n = u.cross(v).normalize().to_array();
        let base = s.positions.len() as u32;
        for p in [corner, corner + u, corner + u + v, corner + v] {
            s.positions.push(p.to_array());
            s.normals.push(n);
        }
        s.triangles.push([base, base + 1, base + 2]);
        s.triangles.push([base, base + 2, base + 3]);
        s.triangle_material.extend([0, 0]);
        self
    }

    /// An axis-aligned box from `lo` to `hi`, faces outwards.
    fn cuboid(self, lo: Vec3, hi: Vec3) -> Self {
        let d = hi - lo;
        let (x, y, z) = (Vec3::new(d.x, 0.0, 0.0), Vec3::new(0.0, d.y, 0.0), Vec3::new(0.0, 0.0, d.z));
        self.quad(lo, z, x) // bottom, -y
            .quad(lo + y, x, z) // top, +y
            .quad(lo, x, y) // back, -z
            .quad(lo + z, y, x) // front, +z
            .quad(lo, y, z) // left, -x
            .quad(lo + x, z, y) // right, +x
    }

    /// The floor y = 0 over [-20, 20]², facing +y.
    fn floor(self) -> Self {
        self.quad(Vec3::new(-20.0, 0.0, -20.0), Vec3::new(0.0, 0.0, 40.0), Vec3::new(40.0, 0.0, 0.0))
    }

    fn upload(&self, gpu: &Gpu) -> GpuScene {
        GpuScene::from_arrays(gpu, &SceneArrays::new(&self.scene).unwrap()).unwrap()
    }
}

fn camera(position: Vec3, target: Vec3, up: Vec3, yfov_degrees: f32) -> Camera {
    let forward = (target - position).normalize();
    let up = (up - forward * forward.dot(up)).normalize();
    Camera {
        position: position.to_array(),
        forward: forward.to_array(),
        up: up.to_array(),
        yfov: yfov_degrees.to_radians(),
        aspect: None,
        znear: 0.01,
    }
}

/// World position and shading normal of each pixel's surface (`None` where there is none),
/// reconstructed on the CPU from the G-buffer's depth as the kernels do.
fn surfaces(image: &AoImage, cam: &Camera) -> Vec<Option<(Vec3, Vec3)>> {
    let (w, h) = image.size;
    let (o, f, r, u) = camera_params(cam, image.size);
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    (0..w * h)
        .map(|i| {
            let depth = image.gbuffer.depth[i as usize];
            if depth <= 0.0 {
                return None;
            }
            let (x, y) = (i % w, i / w);
            let ndc = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / h as f32);
            let dir = (v(f) + ndc.0 * v(r) + ndc.1 * v(u)).normalize();
            let n = image.gbuffer.normal[i as usize];
            Some((v(o) + dir * (depth / dir.dot(v(f))), Vec3::new(n[0], n[1], n[2]).normalize()))
        })
        .collect()
}

fn render(
    gpu: &Gpu,
    scene: &GpuScene,
    cam: &Camera,
    size: u32,
    method: AoMethod,
    settings: &AoSettings,
) -> AoImage {
    let image = ambient_occlusion(gpu, scene, cam, (size, size), method, settings).unwrap();
    let times: Vec<String> = image.pass_ms.iter().map(|(n, ms)| format!("{n} {ms:.2} ms")).collect();
    eprintln!("  {method:?} {size}x{size}: {}", times.join(", "));
    image
}

/// Cosine-weighted AO of a floor point at distance d from a perpendicular wall, radius r.
fn wall_ao(d: f64, r: f64) -> f64 {
    let a = (d / r).min(1.0);
    1.0 - (a.acos() - a * (1.0 - a * a).sqrt()) / std::f64::consts::PI
}

/// Mean of `f` over the pixels `select` accepts, and how many there were.
fn mean_over(n: usize, select: impl Fn(usize) -> bool, f: impl Fn(usize) -> f64) -> (f64, usize) {
    let (sum, count) = (0..n).filter(|&i| select(i)).fold((0.0, 0), |(s, c), i| (s + f(i), c + 1));
    (sum / count.max(1) as f64, count)
}

/// RTAO against the analytic values. A floor beside a wall, seen from above: pixels farther than
/// r from the wall must be exactly 1 (every ray escapes: a ray re-hitting its own floor would
/// show), and pixels nearer are pooled in 8 bins of d/r, each z-tested against the analytic
/// circular-segment value (binomial variance q(1 − q)/rays per pixel). Then a floor under a
/// ceiling at h = 0.6 r: AO = 0.36, one more z-test. Significance 0.01 with a Šidák correction
/// over the 9 tests: two-sided critical |z| = 3.26.
#[test]
fn rtao_matches_analytic_occlusion() {
    let gpu = Gpu::new();
    let r = 0.5f32;
    let rays = 64u32;
    let settings = AoSettings { samples: rays, radius: r, blur: false, ..Default::default() };
    let z_crit = 3.26;
    // A wall x = 0 facing +x, 2 high; the camera 2 above the floor looks straight down at x in
    // [0, 1.2] (the wall seen edge-on at the image's left border).
    let scene = Quads::new()
        .floor()
        .quad(Vec3::new(0.0, 0.0, -20.0), Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, 0.0, 40.0))
        .upload(&gpu);
    let half = 0.6f32;
    let yfov = 2.0 * (half / 2.0f32).atan().to_degrees();
    let cam = camera(Vec3::new(half, 2.0, 0.0), Vec3::new(half, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0), yfov);
    let image = render(&gpu, &scene, &cam, 64, AoMethod::Rtao, &settings);
    let points = surfaces(&image, &cam);
    const BINS: usize = 8;
    let mut bins = [(0usize, 0.0f64, 0.0f64, 0.0f64); BINS]; // pixels, Σ got, Σ expected, Σ variance
    let (mut open_pixels, mut not_open) = (0, Vec::new());
    for (i, s) in points.iter().enumerate() {
        let (p, n) = s.expect("the floor fills the image");
        assert!(n.y > 0.99 && p.y.abs() < 1e-4, "pixel {i} is not on the floor: {p} {n}");
        let got = image.values[i] as f64;
        let d = p.x as f64;
        if d > r as f64 * 1.001 {
            open_pixels += 1;
            if got != 1.0 {
                not_open.push((i, d, got));
            }
            continue;
        }
        let q = wall_ao(d, r as f64);
        let bin = ((d / r as f64 * BINS as f64) as usize).min(BINS - 1);
        let b = &mut bins[bin];
        b.0 += 1;
        b.1 += got;
        b.2 += q;
        b.3 += q * (1.0 - q) / rays as f64;
    }
    assert!(open_pixels > 1000, "only {open_pixels} pixels beyond r");
    assert!(
        not_open.is_empty(),
        "{} floor pixels beyond r of the wall are occluded: {:?}",
        not_open.len(),
        &not_open[..not_open.len().min(5)]
    );
    for (k, &(n, got, expected, var)) in bins.iter().enumerate() {
        assert!(n >= 64, "bin {k} has only {n} pixels");
        let z = (got - expected) / var.sqrt();
        eprintln!(
            "wall bin {k}: {n} px, RTAO {:.4}, analytic {:.4}, z {z:.2}",
            got / n as f64,
            expected / n as f64
        );
        assert!(
            z.abs() < z_crit,
            "wall bin {k}: RTAO {} vs {}, z = {z}",
            got / n as f64,
            expected / n as f64
        );
    }

    // Under a ceiling (facing down) at h = 0.3: the camera between the two looks straight down.
    let h = 0.3f32;
    let scene = Quads::new()
        .floor()
        .quad(Vec3::new(-20.0, h, -20.0), Vec3::new(40.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 40.0))
        .upload(&gpu);
    let cam = camera(Vec3::new(0.0, 0.25, 0.0), Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 60.0);
    let image = render(&gpu, &scene, &cam, 64, AoMethod::Rtao, &settings);
    let q = ((h / r) as f64).powi(2);
    let n = image.values.len() as f64;
    let got: f64 = image.values.iter().map(|&v| v as f64).sum();
    let z = (got - n * q) / (n * q * (1.0 - q) / rays as f64).sqrt();
    eprintln!("ceiling: RTAO {:.4}, analytic {q:.4}, z {z:.2}", got / n);
    assert!(z.abs() < z_crit, "ceiling: RTAO {} vs {q}, z = {z}", got / n);
}
