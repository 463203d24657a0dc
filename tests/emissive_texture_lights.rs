//! Emissive textures as lights: the emissive-triangle table weighs each triangle by the texels
//! its footprint can read (src/scene/emissive.rs), so triangles on black texels leave the table
//! and next-event estimation samples where light is. These tests check that nothing that emits
//! is left out (a triangle left out would be missed by light sampling: a bias), through every
//! wrap mode, a texture transform and the second UV set, and that light sampling and BSDF
//! sampling still agree on the GPU.

mod common;

use common::{build_with, camera, quad, Gpu};
use glam::{Vec2, Vec3};
use umbra::gpu::scene::GpuScene;
use umbra::passes::pathtrace::{PathSettings, Strategy};
use umbra::render::{path_trace, PathImage};
use umbra::scene::{texture_transform, Filter, Material, Sampler, Scene, Texture, TextureRef, Wrap};

/// A 16 × 2 emissive texture, black but for texel (0, 0) (white) and (9, 1) (dark grey).
fn sparse_texture(wrap: Wrap, filter: Filter) -> Texture {
    let mut rgba8 = vec![0u8; 16 * 2 * 4];
    rgba8[..4].copy_from_slice(&[255, 255, 255, 255]);
    rgba8[4 * (16 + 9)..][..4].copy_from_slice(&[40, 40, 40, 255]);
    Texture {
        name: "sparse".into(),
        width: 16,
        height: 2,
        rgba8,
        srgb: true,
        sampler: Sampler {
            wrap_s: wrap,
            wrap_t: wrap,
            mag_filter: filter,
            min_filter: filter,
            mipmaps: false,
            mipmap_filter: Filter::Nearest,
        },
    }
}

/// The texel index `i` of a level `n` texels wide through `wrap` (texture_wrap in texture.glsl).
fn wrap_index(i: i64, n: i64, wrap: Wrap) -> usize {
    (match wrap {
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }) as usize
}

/// The red channel of `texture` at `uv` as texture_sample in texture.glsl reads it (level 0,
/// bilinear or nearest, wrapped; the code value, not decoded: zero exactly where it is black).
fn texture_at(texture: &Texture, uv: Vec2) -> f32 {
    let (w, h) = (texture.width as i64, texture.height as i64);
    let texel = |x: i64, y: i64| {
        let (x, y) = (wrap_index(x, w, texture.sampler.wrap_s), wrap_index(y, h, texture.sampler.wrap_t));
        f32::from(texture.rgba8[4 * (y * w as usize + x)])
    };
    if texture.sampler.mag_filter == Filter::Nearest {
        return texel((uv.x * w as f32).floor() as i64, (uv.y * h as f32).floor() as i64);
    }
    let st = uv * Vec2::new(w as f32, h as f32) - 0.5;
    let (p, f) = (st.floor(), st - st.floor());
    let (x, y) = (p.x as i64, p.y as i64);
    let a = texel(x, y) * (1.0 - f.x) + texel(x + 1, y) * f.x;
    let b = texel(x, y + 1) * (1.0 - f.x) + texel(x + 1, y + 1) * f.x;
    a * (1.0 - f.y) + b * f.y
}

/// A strip of `columns` × 2 quads (two triangles each) over x ∈ [−1, 1], z ∈ [−¼, ¼] at height
/// `y`, facing down, whose UVs (both sets) run over `u` along x and `v` along z.
fn emitter_strip(columns: usize, y: f32, u: (f32, f32), v: (f32, f32), material: Material) -> Scene {
    let mut soup = Vec::new();
    for i in 0..columns {
        for j in 0..2 {
            let x0 = -1.0 + 2.0 * i as f32 / columns as f32;
            let z0 = -0.25 + 0.25 * j as f32;
            let centre = Vec3::new(x0 + 1.0 / columns as f32, y, z0 + 0.125);
            soup.extend(quad(centre, Vec3::X / columns as f32, Vec3::Z * 0.125));
        }
    }
    let mut scene =
        build_with("strip", &[(soup, material)], vec![], camera(Vec3::new(0.0, 3.0, 2.0), Vec3::ZERO));
    let uv = |p: &[f32; 3]| {
        let (s, t) = ((p[0] + 1.0) / 2.0, (p[2] + 0.25) / 0.5);
        [u.0 + s * (u.1 - u.0), v.0 + t * (v.1 - v.0)]
    };
    scene.uv0 = scene.positions.iter().map(uv).collect();
    scene.uv1 = scene.uv0.clone();
    scene
}

fn glowing(slot: TextureRef) -> Material {
    Material {
        base_color_factor: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        emissive: [1.0; 3],
        emissive_texture: Some(slot),
        ..Default::default()
    }
}

fn slot(tex_coord: u32, transform: [[f32; 3]; 2]) -> TextureRef {
    TextureRef { texture: 0, tex_coord, transform, scale: 1.0 }
}

/// Every triangle that emits anywhere the GPU can read (its corners, edges and interior on a
/// fine barycentric grid) is in the table; few beside them are; the powers follow
/// the texels. Through repeat, mirrored-repeat and clamp-to-edge wraps of UVs that cross the
/// texture's edges, bilinear and nearest filtering, a KHR_texture_transform and TEXCOORD_1.
#[test]
fn the_table_keeps_every_triangle_that_can_emit_and_only_those() {
    let rotated = texture_transform([0.3, -0.2], 0.7, [1.5, 0.8]);
    let cases = [
        (Wrap::Repeat, Filter::Linear, (0.3, 1.45), (-0.2, 0.9), slot(0, umbra::scene::IDENTITY_TRANSFORM)),
        (Wrap::Repeat, Filter::Nearest, (-1.2, 0.1), (0.0, 1.0), slot(0, umbra::scene::IDENTITY_TRANSFORM)),
        (
            Wrap::MirroredRepeat,
            Filter::Linear,
            (0.6, 1.7),
            (0.1, 1.9),
            slot(0, umbra::scene::IDENTITY_TRANSFORM),
        ),
        (
            Wrap::MirroredRepeat,
            Filter::Linear,
            (-0.9, 0.2),
            (-1.0, 0.3),
            slot(1, umbra::scene::IDENTITY_TRANSFORM),
        ),
        (
            Wrap::ClampToEdge,
            Filter::Linear,
            (-0.5, 0.8),
            (-0.3, 1.3),
            slot(0, umbra::scene::IDENTITY_TRANSFORM),
        ),
        (Wrap::Repeat, Filter::Linear, (0.0, 1.0), (0.0, 1.0), slot(1, rotated)),
    ];
    for (case, (wrap, filter, u, v, slot)) in cases.into_iter().enumerate() {
        let mut scene = emitter_strip(48, 1.0, u, v, glowing(slot));
        scene.textures = vec![sparse_texture(wrap, filter)];
        scene.update_emissive();
        let texture = &scene.textures[0];
        let uvs = if slot.tex_coord == 1 { &scene.uv1 } else { &scene.uv0 };
        let mut emitting = 0;
        for (t, tri) in scene.triangles.iter().enumerate() {
            let corner = tri.map(|v| Vec2::from(slot.transform_uv(uvs[v as usize])));
            const STEPS: usize = 24;
            let brightest = (0..=STEPS)
                .flat_map(|i| (0..=STEPS - i).map(move |j| (i, j)))
                .map(|(i, j)| {
                    let (a, b) = (i as f32 / STEPS as f32, j as f32 / STEPS as f32);
                    texture_at(texture, corner[0] * (1.0 - a - b) + corner[1] * a + corner[2] * b)
                })
                .fold(0.0f32, f32::max);
            let entry = scene.emissive.triangles.iter().position(|&e| e == t as u32);
            if brightest > 0.0 {
                emitting += 1;
                assert!(
                    entry.is_some(),
                    "case {case}: triangle {t} emits (up to {brightest}) but left the table"
                );
            }
        }
        let kept = scene.emissive.triangles.len();
        eprintln!("case {case} ({wrap:?}, {filter:?}): {emitting} triangles emit, {kept} of 192 kept");
        assert!(emitting > 0, "case {case}: a test of the test: something emits");
        // Black triangles leave; the bounding rectangle keeps at most a few beside the emitting
        // ones (nearest filtering reads half the texels the bound allows for).
        assert!(
            kept < scene.triangles.len() && kept <= 2 * emitting,
            "case {case}: black triangles stay in the table ({kept} kept, {emitting} emit)"
        );
    }

    // Powers follow the texels: on a strip over u ∈ [0, 1] whose only bright texel is (0, 0),
    // the leftmost columns (over it) carry the most power.
    let mut scene =
        emitter_strip(16, 1.0, (0.0, 1.0), (0.0, 1.0), glowing(slot(0, umbra::scene::IDENTITY_TRANSFORM)));
    scene.textures = vec![sparse_texture(Wrap::ClampToEdge, Filter::Linear)];
    scene.update_emissive();
    let table = &scene.emissive;
    let (first, _) =
        table.power.iter().enumerate().fold((0, 0.0f32), |m, (i, &p)| if p > m.1 { (i, p) } else { m });
    let centroid_x: f32 = scene.triangles[table.triangles[first] as usize]
        .iter()
        .map(|&v| scene.positions[v as usize][0] / 3.0)
        .sum();
    assert!(
        centroid_x < -0.75,
        "the most powerful triangle sits at x = {centroid_x}, not over the bright texel"
    );
}

fn render(gpu: &Gpu, scene: &Scene, strategy: Strategy, spp: u32) -> PathImage {
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let settings =
        PathSettings { size: (24, 24), spp, max_bounces: 1, strategy, env: [0.0; 3], ..Default::default() };
    path_trace(gpu, &gpu_scene, &scene.camera(None).unwrap(), &settings, |_, _| {}).unwrap()
}

/// A floor lit by a strip whose emissive texture is black but for two texels, bilinear, its UVs
/// wrapping around the texture's edge: direct light by light sampling alone (which sees only
/// the table's triangles, with their powers as the selection pmf) equals direct light by BSDF
/// sampling alone (which sees every triangle), by a z-test of the image means at α = 0.001.
/// End to end (the table's powers as the GPU's pmf); the exact check of the footprints is the
/// test above: a footprint without the bilinear filter's reach fails it, while here the light
/// it loses is below the noise (z = 0.10 measured with that mistake).
#[test]
fn light_sampling_of_a_sparse_emissive_texture_agrees_with_bsdf_sampling() {
    let gpu = Gpu::new();
    let strip =
        emitter_strip(48, 0.6, (0.3, 1.45), (-0.2, 0.9), glowing(slot(0, umbra::scene::IDENTITY_TRANSFORM)));
    let floor = Material { metallic: 0.0, roughness: 1.0, specular_factor: 0.0, ..Default::default() };
    let glow = strip.materials[0].clone();
    let mut scene = build_with(
        "lit floor",
        &[(quad(Vec3::ZERO, Vec3::X * 1.5, -Vec3::Z * 1.5), floor)],
        vec![],
        camera(Vec3::new(0.0, 2.5, 2.5), Vec3::ZERO),
    );
    // The strip's triangles after the floor's, with the glowing material.
    let base = scene.positions.len() as u32;
    scene.materials.push(glow);
    scene.positions.extend(&strip.positions);
    scene.normals.extend(&strip.normals);
    scene.triangles.extend(strip.triangles.iter().map(|t| t.map(|v| v + base)));
    scene.triangle_material.extend(strip.triangles.iter().map(|_| 1u32));
    scene.uv0 = vec![[0.0; 2]; base as usize];
    scene.uv0.extend(&strip.uv0);
    scene.uv1 = scene.uv0.clone();
    scene.textures = vec![sparse_texture(Wrap::Repeat, Filter::Linear)];
    scene.update_emissive();
    assert!(scene.emissive.triangles.len() < strip.triangles.len() / 2);

    let light = render(&gpu, &scene, Strategy::Light, 256);
    let bsdf = render(&gpu, &scene, Strategy::Bsdf, 2048);
    let stats = |image: &PathImage| {
        let n = image.mean.len() as f64;
        let mean = image.mean.iter().map(|p| f64::from(p[1])).sum::<f64>() / n;
        let var = image.variance_of_mean().iter().map(|v| f64::from(v[1])).sum::<f64>() / (n * n);
        (mean, var)
    };
    let ((l, vl), (b, vb)) = (stats(&light), stats(&bsdf));
    let z = (l - b) / (vl + vb).sqrt();
    eprintln!("floor's mean green: light sampling {l:.5e}, BSDF sampling {b:.5e}, z = {z:.2}");
    assert!(l > 0.0 && b > 0.0);
    assert!(z.abs() < 3.29, "light and BSDF sampling disagree: z = {z:.2}");

    // What the footprints buy: the table of before, every triangle of the strip by its area
    // (the material's mean emission is the same for all), spends most light samples on black
    // texels; at equal samples its variance is higher.
    let all: Vec<u32> =
        (0..scene.triangles.len() as u32).filter(|&t| scene.triangle_material[t as usize] == 1).collect();
    let power = vec![1.0f32; all.len()];
    let cdf = (1..=all.len()).map(|k| k as f32 / all.len() as f32).collect();
    scene.emissive = umbra::scene::EmissiveTable { triangles: all, power, cdf, total_power: 0.0 };
    scene.emissive.total_power = scene.emissive.power.len() as f32;
    let (by_area, v_area) = stats(&render(&gpu, &scene, Strategy::Light, 256));
    let z = (by_area - b) / (v_area + vb).sqrt();
    eprintln!(
        "by area: {by_area:.5e} (z = {z:.2} against BSDF sampling), variance {:.1}x the footprints'",
        v_area / vl
    );
    assert!(z.abs() < 3.29, "the test of the test: sampling by area is unbiased too (z = {z:.2})");
    assert!(v_area > 2.0 * vl, "footprint powers do not lower the variance: {v_area:.3e} vs {vl:.3e}");
}
