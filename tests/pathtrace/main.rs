//! The path tracer against closed-form and numerically integrated answers, its determinism,
//! and its robustness (no NaN or Inf ever reaches the accumulation buffer).

#[path = "../common/mod.rs"]
mod common;

mod alpha;
mod environment;
mod furnace;
mod glass;
mod lights;
mod robustness;
mod textures;

use common::Gpu;
use glam::Vec3;
use umbra::gpu::layout::GpuCamera;
use umbra::gpu::scene::GpuScene;
use umbra::procedural::Mesh;
use umbra::render::{path_trace, PathImage, PathSettings};
use umbra::scene::{Camera, Material, Scene};

/// A scene from meshes, one material per mesh, with flat (face) normals, or with `smooth` the
/// normals of a sphere centred at the origin.
fn scene_of(parts: &[(&Mesh, Material, bool)], camera: Camera) -> Scene {
    let mut scene = Scene { name: "test scene".into(), ..Default::default() };
    for (m, (mesh, material, smooth)) in parts.iter().enumerate() {
        scene.materials.push(material.clone());
        for t in &mesh.triangles {
            let p = t.map(|i| mesh.positions[i as usize]);
            let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            let base = scene.positions.len() as u32;
            for v in &p {
                scene.positions.push((*v).into());
                let n = if *smooth { v.normalize() } else { face };
                scene.normals.push(n.into());
            }
            scene.triangles.push([base, base + 1, base + 2]);
            scene.triangle_material.push(m as u32);
        }
    }
    scene.cameras.push(camera);
    scene.update_emissive();
    scene
}

/// A camera at `height` above the origin looking straight down (-y), image up along -z.
fn looking_down(height: f32, yfov: f32) -> Camera {
    Camera {
        position: [0.0, height, 0.0],
        forward: [0.0, -1.0, 0.0],
        up: [0.0, 0.0, -1.0],
        yfov,
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    }
}

/// A square floor at y = 0, `half` metres each way, facing +y.
fn floor_quad(half: f32) -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-half, 0.0, -half),
            Vec3::new(half, 0.0, -half),
            Vec3::new(half, 0.0, half),
            Vec3::new(-half, 0.0, half),
        ],
        triangles: vec![[0, 2, 1], [0, 3, 2]],
    }
}

/// The square [−1, 1]² at z = 0, facing +z.
fn facing_quad() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// A point light of intensity 2 one unit above the origin, pointing down.
fn bulb_above() -> umbra::scene::Light {
    umbra::scene::Light {
        name: "bulb".into(),
        kind: umbra::scene::LightKind::Point,
        position: [0.0, 1.0, 0.0],
        direction: [0.0, -1.0, 0.0],
        color: [1.0; 3],
        intensity: 2.0,
        range: None,
        inner_cone_angle: 0.0,
        outer_cone_angle: std::f32::consts::FRAC_PI_4,
    }
}

fn camera(position: Vec3, target: Vec3, yfov_degrees: f32) -> Camera {
    Camera {
        position: position.into(),
        forward: (target - position).normalize().into(),
        up: [0.0, 1.0, 0.0],
        yfov: yfov_degrees.to_radians(),
        aspect: None,
        znear: 0.01,
        orthographic: None,
        jitter: [0.0; 2],
    }
}

fn render(gpu: &Gpu, scene: &Scene, settings: &PathSettings) -> PathImage {
    let device_scene = GpuScene::upload(gpu, scene).unwrap();
    let image = path_trace(gpu, &device_scene, &scene.camera(None).unwrap(), settings, |_, _| {}).unwrap();
    assert_eq!(
        image.nonfinite_samples,
        0,
        "NaN/Inf samples, arising in {:?}",
        umbra::gpu::layout::nonfinite_source_names(image.nonfinite_sources)
    );
    image
}

/// The direction through the centre of pixel (x, y), as `pathtrace.comp` computes it.
fn pixel_ray(cam: &Camera, (w, h): (u32, u32), x: u32, y: u32) -> Vec3 {
    let c = GpuCamera::new(cam, (w, h));
    let ndc = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0, 1.0 - 2.0 * (y as f32 + 0.5) / h as f32);
    (Vec3::from(c.forward) + ndc.0 * Vec3::from(c.right) + ndc.1 * Vec3::from(c.up)).normalize()
}

/// cos of the angle between the view ray and the normal of the unit sphere at the origin, at
/// the centre of each pixel; `None` off the sphere.
fn sphere_cosines(cam: &Camera, size: (u32, u32)) -> Vec<Option<f32>> {
    let o = Vec3::from(cam.position);
    (0..size.1)
        .flat_map(|y| (0..size.0).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = pixel_ray(cam, size, x, y);
            let b = o.dot(d);
            let disc = b * b - (o.length_squared() - 1.0);
            (disc > 0.0).then(|| {
                let p = o + d * (-b - disc.sqrt());
                p.normalize().dot(-d)
            })
        })
        .collect()
}
