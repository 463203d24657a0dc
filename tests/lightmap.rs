//! Lightmaps: the baked irradiance of a plane under a square area light against the analytic
//! irradiance (Lambert's polygon formula), texel by texel within the Monte-Carlo error; the seam
//! along a chart's border that bilinear filtering makes without dilation.

mod common;

use common::{build_with, camera, gamma_q, quad, Gpu};
use glam::Vec3;
use umbra::gpu::scene::GpuScene;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::lightmap::{LightmapLayout, LightmapSettings, Lightmaps};
use umbra::render::Passes;
use umbra::scene::{Material, Scene};

/// The floor's UV1 chart in the atlas: [0.25, 0.75]² (so its border lies inside the map).
fn chart_uv(p: Vec3) -> [f32; 2] {
    [0.25 + 0.25 * (p.x + 1.0), 0.25 + 0.25 * (p.z + 1.0)]
}

/// The emitter's corners: a 0.5 m square at height 0.5 facing down, off the floor's centre.
fn emitter_corners() -> [Vec3; 4] {
    let c = Vec3::new(0.3, 0.5, -0.2);
    [
        c + Vec3::new(-0.25, 0.0, -0.25),
        c + Vec3::new(0.25, 0.0, -0.25),
        c + Vec3::new(0.25, 0.0, 0.25),
        c + Vec3::new(-0.25, 0.0, 0.25),
    ]
}

const RADIANCE: f32 = 2.0;

/// A 2 m floor with a lightmap chart (UV1) under a square emitter of `radiance` without one.
fn floor_under_a_square_light(radiance: f32) -> Scene {
    let floor = quad(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -1.0));
    let [a, b, c, d] = emitter_corners();
    // Facing down: wound clockwise seen from above.
    let lamp = vec![[a, b, c], [a, c, d]];
    // Pure Lambert (no specular layer): all of the floor's light is irradiance.
    let lambert = Material { metallic: 0.0, roughness: 1.0, specular_factor: 0.0, ..Default::default() };
    let lamp_material =
        Material { emissive: [radiance; 3], base_color_factor: [0.0, 0.0, 0.0, 1.0], ..lambert.clone() };
    let mut scene = build_with(
        "floor under a square light",
        &[(floor, lambert), (lamp, lamp_material)],
        vec![],
        camera(Vec3::new(0.0, 2.0, 1.0), Vec3::ZERO),
    );
    scene.uv1 = scene
        .positions
        .iter()
        .enumerate()
        .map(|(i, p)| if i < 6 { chart_uv(Vec3::from(*p)) } else { [0.0, 0.0] })
        .collect();
    scene
}

/// Irradiance at p (normal n) from a Lambertian polygon of radiance L (Lambert's formula:
/// E = L/2 |Σ θ_i γ_i · n|, θ_i the angle each edge subtends at p, γ_i the unit normal of the plane
/// through p and the edge).
fn polygon_irradiance(p: Vec3, n: Vec3, corners: &[Vec3], radiance: f32) -> f64 {
    let mut sum = 0.0f64;
    for i in 0..corners.len() {
        let a = (corners[i] - p).normalize().as_dvec3();
        let b = (corners[(i + 1) % corners.len()] - p).normalize().as_dvec3();
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        sum += theta * a.cross(b).normalize().dot(n.as_dvec3());
    }
    0.5 * radiance as f64 * sum.abs()
}

fn bake(gpu: &Gpu, scene: &Scene, settings: &LightmapSettings) -> (LightmapLayout, Lightmaps) {
    let gpu_scene = GpuScene::upload(gpu, scene).unwrap();
    let passes = Passes::new(gpu, &gpu_scene);
    let layout = LightmapLayout::new(scene, settings.size).unwrap();
    let maps = passes
        .bake_lightmaps(&gpu_scene, &layout, settings, &LightingSettings::default(), None, |_, _| {})
        .unwrap();
    (layout, maps)
}

/// Every covered texel of the floor's map holds the analytic direct irradiance from the square
/// light within its Monte-Carlo error: z = (baked − analytic) / standard error, each texel's
/// two-sided p-value above the Šidák level for a family significance level of 0.001; and the
/// ambient layer is 0 (no environment, nothing lit to reflect: the floor's own light reaches the
/// black lamp only).
#[test]
fn a_floor_under_a_square_light_bakes_the_analytic_irradiance() {
    let gpu = Gpu::new();
    let scene = floor_under_a_square_light(RADIANCE);
    let settings = LightmapSettings { size: 32, samples: 512, dilation: 0, ..Default::default() };
    let (layout, maps) = bake(&gpu, &scene, &settings);
    assert_eq!(maps.materials, vec![0], "one map: the floor's");
    let corners = emitter_corners();
    let covered: Vec<usize> = (0..layout.texels.len()).filter(|&i| layout.texels[i][0][3] != 0.0).collect();
    assert_eq!(covered.len(), 16 * 16, "the chart covers 16×16 texels");
    // Šidák: the per-texel two-sided level for a family level of 0.001.
    let per_texel = 1.0 - (1.0 - 0.001f64).powf(1.0 / covered.len() as f64);
    let (mut worst, mut worst_rel) = (0.0f64, 0.0f64);
    for &i in &covered {
        let p = Vec3::from_slice(&layout.texels[i][0][..3]);
        let expected = polygon_irradiance(p, Vec3::Y, &corners, RADIANCE);
        let baked = maps.emitters[i][0] as f64;
        let z = (baked - expected) / (maps.emitters_error[i] as f64).max(1e-9);
        worst = worst.max(z.abs());
        worst_rel = worst_rel.max((baked / expected - 1.0).abs());
        // P(|Z| > |z|) = Q(1/2, z²/2).
        let p_value = gamma_q(0.5, 0.5 * z * z);
        assert!(
            p_value > per_texel,
            "texel {i} at {p}: baked {baked:.5}, analytic {expected:.5}, z = {z:.2}"
        );
        assert_eq!(maps.ambient[i], [0.0; 3], "texel {i}: ambient light from nowhere");
    }
    eprintln!("{} texels, worst |z| {worst:.2} (level {per_texel:.1e} per texel), worst relative error {worst_rel:.4}", covered.len());
}

/// The seam: bilinear lookups on a chart's border read half from the empty texels outside it
/// (measured: 50 % of the light half a texel inside); dilating the charts by a ring of
/// texels fills those with their neighbours' values, and the border reads what the texel inside
/// holds (measured within 2.3 %, bound 5 %: the light's own gradient across half a texel).
#[test]
fn dilation_closes_the_seam_along_a_charts_border() {
    let gpu = Gpu::new();
    let scene = floor_under_a_square_light(RADIANCE);
    let settings = LightmapSettings { size: 32, samples: 256, dilation: 0, ..Default::default() };
    let (_, raw) = bake(&gpu, &scene, &settings);
    let mut dilated = raw.clone();
    dilated.dilate(1);
    let (mut worst_raw, mut worst_dilated) = (0.0f64, 0.0f64);
    // Points along the chart's four edges (the floor's border), away from its corners, and the
    // point half a texel (1/16 m) inside each.
    let inward = 2.0 / 16.0 * 0.5;
    for k in 1..8 {
        let t = -1.0 + 2.0 * k as f32 / 8.0;
        for (p, n) in [
            (Vec3::new(-1.0, 0.0, t), Vec3::X),
            (Vec3::new(1.0, 0.0, t), -Vec3::X),
            (Vec3::new(t, 0.0, -1.0), Vec3::Z),
            (Vec3::new(t, 0.0, 1.0), -Vec3::Z),
        ] {
            let read = |maps: &Lightmaps, p: Vec3| {
                Lightmaps::sample(maps.map(&maps.emitters, 0), maps.size, chart_uv(p))[0] as f64
            };
            let seam = |maps: &Lightmaps| read(maps, p) / read(maps, p + inward * n);
            worst_raw = worst_raw.max(seam(&raw));
            worst_dilated = worst_dilated.max((seam(&dilated) - 1.0).abs());
        }
    }
    eprintln!(
        "on the chart's border, against half a texel inside: undilated at most {worst_raw:.3}, dilated within {worst_dilated:.3}"
    );
    assert!(worst_raw < 0.6, "the seam does not show: the border reads {worst_raw:.3} of the light inside");
    assert!(
        worst_dilated < 0.05,
        "dilated, the border is {:.1} % off the light inside",
        100.0 * worst_dilated
    );
}

/// The lightmap in the hybrid: under a sky, with the lamp switched off (a black square: all the
/// light is ambient), the floor's light is the sky less what the square hides: the split sum's
/// unoccluded sky irradiance overestimates it under the square, the baked `ambient` layer holds
/// it. Against the path tracer, lightmaps cut the hybrid's relative MSE over the floor (away from
/// silhouettes) at least 10× (measured: 0.0059 → 0.00002), with the command line's default SSAO
/// too (0.00002: it leaves the lightmap's light alone; multiplying it too, as before, 0.0100),
/// and a material without a map keeps the split sum.
#[test]
fn lightmaps_light_the_hybrids_diffuse_lobe() {
    use umbra::passes::lightmap::GpuLightmaps;
    use umbra::render::{HybridSettings, PathSettings};
    let gpu = Gpu::new();
    let scene = floor_under_a_square_light(0.0);
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let env = [0.5f32; 3];
    let lighting = LightingSettings { env, shadow_rays: 16, ..Default::default() };
    let layout = LightmapLayout::new(&scene, 32).unwrap();
    let settings = LightmapSettings { size: 32, samples: 1024, ..Default::default() };
    let maps = passes.bake_lightmaps(&gpu_scene, &layout, &settings, &lighting, None, |_, _| {}).unwrap();
    let lightmaps = GpuLightmaps::upload(&gpu, &maps, scene.materials.len()).unwrap();
    let size = (48, 48);
    let camera = scene.camera(None).unwrap();
    let hybrid = HybridSettings { size, lighting, ..Default::default() };
    let plain = passes.hybrid(&gpu_scene, &camera, &hybrid).unwrap();
    let mapped = passes.hybrid_with(&gpu_scene, &camera, &hybrid, None, Some(&lightmaps)).unwrap();
    let reference = passes
        .path_trace(
            &gpu_scene,
            &camera,
            &PathSettings { size, spp: 1024, env, ..Default::default() },
            |_, _| {},
        )
        .unwrap();
    // Floor pixels (material 0 in the G-buffer) away from silhouettes: the path tracer averages
    // a pixel's area, the G-buffer sees its centre.
    let material = |x: i32, y: i32| {
        let (x, y) = (x.clamp(0, size.0 as i32 - 1), y.clamp(0, size.1 as i32 - 1));
        plain.gbuffer.material[(y * size.0 as i32 + x) as usize][0]
    };
    let floor: Vec<usize> = (0..plain.gbuffer.material.len())
        .filter(|&i| {
            let (x, y) = ((i % size.0 as usize) as i32, (i / size.0 as usize) as i32);
            (-1..=1).all(|dy| (-1..=1).all(|dx| material(x + dx, y + dy) == 0))
        })
        .collect();
    assert!(floor.len() > 500, "the camera sees the floor");
    let rel = |img: &[[f32; 4]]| {
        floor
            .iter()
            .map(|&i| {
                (0..3)
                    .map(|c| {
                        (img[i][c] - reference.mean[i][c]).powi(2) as f64
                            / ((reference.mean[i][c] as f64).powi(2) + 0.01)
                    })
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (3 * floor.len()) as f64
    };
    let (e_plain, e_mapped) = (rel(&plain.color), rel(&mapped.color));
    // The command line's default SSAO on top: it leaves the lightmap's light alone.
    let with_ao = HybridSettings { ao: Some(AoSettings::default()), ..hybrid.clone() };
    let mapped_ao = passes.hybrid_with(&gpu_scene, &camera, &with_ao, None, Some(&lightmaps)).unwrap();
    let e_mapped_ao = rel(&mapped_ao.color);
    eprintln!("floor relative MSE against the path tracer: split sum {e_plain:.5}, lightmap {e_mapped:.5}, lightmap and SSAO {e_mapped_ao:.5}");
    assert!(e_mapped * 10.0 < e_plain, "the lightmap cuts the error only from {e_plain:.5} to {e_mapped:.5}");
    assert!(e_mapped_ao * 10.0 < e_plain, "with SSAO the lightmap cuts the error only to {e_mapped_ao:.5}");
    // The lamp (no map) is shaded as without lightmaps.
    let lamp: Vec<usize> =
        (0..plain.gbuffer.material.len()).filter(|&i| plain.gbuffer.material[i][0] == 1).collect();
    assert!(lamp.iter().all(|&i| plain.color[i] == mapped.color[i]), "a material without a map changed");
}

/// The baked occlusion map (`umbra bake --ao`): under the square (rays long enough to reach all
/// of it), each texel's unoccluded fraction is 1 − the square's form factor, Lambert's formula
/// over π; a z-test per texel with the Bernoulli variance a(1 − a)/N, at a family level of 0.001
/// (Šidák). Rays shorter than the square's height see nothing: all 1.
#[test]
fn the_occlusion_map_is_one_less_the_occluders_form_factor() {
    let gpu = Gpu::new();
    let scene = floor_under_a_square_light(0.0);
    let gpu_scene = GpuScene::upload(&gpu, &scene).unwrap();
    let passes = Passes::new(&gpu, &gpu_scene);
    let settings = LightmapSettings { size: 32, samples: 1024, dilation: 0, ..Default::default() };
    let layout = LightmapLayout::new(&scene, settings.size).unwrap();
    let maps = passes.bake_occlusion(&gpu_scene, &layout, &settings, 10.0, |_, _| {}).unwrap();
    let corners = emitter_corners();
    let covered: Vec<usize> = (0..layout.texels.len()).filter(|&i| layout.texels[i][0][3] != 0.0).collect();
    let per_texel = 1.0 - (1.0 - 0.001f64).powf(1.0 / covered.len() as f64);
    let n = settings.samples as f64;
    let mut worst = 0.0f64;
    for &i in &covered {
        let p = Vec3::from_slice(&layout.texels[i][0][..3]);
        let expected = 1.0 - polygon_irradiance(p, Vec3::Y, &corners, 1.0) / std::f64::consts::PI;
        let baked = maps.values[i] as f64;
        let z = (baked - expected) / (expected * (1.0 - expected) / n).sqrt().max(1e-9);
        worst = worst.max(z.abs());
        assert!(
            gamma_q(0.5, 0.5 * z * z) > per_texel,
            "texel {i} at {p}: baked {baked:.4}, expected {expected:.4}, z = {z:.2}"
        );
    }
    eprintln!("{} texels, worst |z| {worst:.2}", covered.len());
    let short = passes.bake_occlusion(&gpu_scene, &layout, &settings, 0.4, |_, _| {}).unwrap();
    assert!(covered.iter().all(|&i| short.values[i] == 1.0), "rays of 0.4 m reach a square 0.5 m up");
}
