//! Irradiance probes on the speed/accuracy chart: the hybrid (4 shadow rays, IBL) without probes
//! (with and without SSAO) and with baked probes at a sweep of spacings (the scene's longest
//! side / n; no SSAO: the probes' visibility is the occlusion, and SSAO's radius is the suite's
//! scene-wide one, which on top of the probes darkens twice),
//! each point's frame time (median GPU time of its per-frame passes after a warm-up; the bake is
//! reported apart, as the one-off cost it is), its relative MSE and LDR-FLIP against a converged
//! path-traced reference (the suite's, cached), and the probes' count and bake time. `suite`
//! runs the same series on its scenes; `probes` runs it alone, with Sponza and a sun, and on the
//! Cornell box also lightmaps (its triangles unwrapped into charts of their own, baked at a sweep
//! of map sizes, the bounces beyond the first from the 1/8 probe volume, which lights the
//! unmapped rest). Each baked point is rendered again with the command line's default SSAO on
//! top, its error and bias recorded: the AO must leave the baked light alone.

use super::num;
use super::suite::{self, Point, SuiteSettings};
use crate::scenes::bench_camera;
use crate::scenes::load_gltf;
use crate::scenes::sponza_under_a_sun;
use crate::write_json;
use anyhow::Context as _;
use anyhow::Result;
use serde_json::{json, Value};
use std::path::PathBuf;
use umbra::embed::Renderer;
use umbra::passes::ao::AoSettings;
use umbra::passes::deferred::LightingSettings;
use umbra::passes::probes::{ProbeSettings, ProbeVolume};
use umbra::render::HybridSettings;
use umbra::scene::Camera;
use umbra::vk::Context;
use umbra::vk::ContextDesc;

/// The series' name on the charts and in the JSON.
pub const SERIES: &str = "hybrid + probes";

/// One baked volume's point.
pub struct ProbePoint {
    /// The chart's point (unit `probes_per_side`).
    pub point: Point,
    /// Probes in the volume.
    pub probes: u32,
    /// Of them active (outside geometry).
    pub active: u32,
    /// GPU milliseconds of the bake.
    pub bake_ms: f64,
    /// What the bake's light does with and without the command line's default SSAO on top.
    pub ao: BakedWithAo,
}

/// A baked point's bias without ambient occlusion, and its relative MSE and bias with the
/// default SSAO on top (which must leave the baked light alone: it holds its occlusion).
#[derive(Clone, Copy)]
pub struct BakedWithAo {
    /// The image's mean over the reference's, less 1, without AO.
    pub bias: f64,
    /// Relative MSE with SSAO.
    pub ssao_rel_mse: f64,
    /// Bias with SSAO.
    pub ssao_bias: f64,
}

/// The mean of `image` over the mean of `reference` (all channels), less 1.
fn bias(image: &[[f32; 4]], reference: &[[f32; 4]]) -> f64 {
    let sum = |c: &[[f32; 4]]| c.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
    sum(image) / sum(reference) - 1.0
}

/// [`BakedWithAo`] of a baked point whose image without AO is `bare`, rendering it again with
/// the default SSAO by `render`.
fn with_ao(
    bare: &[[f32; 4]],
    reference: &[[f32; 4]],
    render: impl FnOnce() -> umbra::error::Result<umbra::render::HybridImage>,
) -> Result<BakedWithAo> {
    let image = render()?;
    Ok(BakedWithAo {
        bias: bias(bare, reference),
        ssao_rel_mse: suite::errors(&image.color, reference).1,
        ssao_bias: bias(&image.color, reference),
    })
}

/// The hybrid's settings of the probe series (without SSAO) and of the points without probes it
/// is compared with (with and without it): 4 shadow rays, split-sum IBL, under `s.env`.
pub fn hybrid_settings(s: &SuiteSettings, ssao: bool) -> HybridSettings {
    HybridSettings {
        size: s.size,
        lighting: LightingSettings { shadow_rays: 4, seed: 1, env: s.env, ..LightingSettings::default() },
        ao: ssao.then(|| AoSettings { samples: 16, radius: s.ao_radius, seed: 1, ..AoSettings::default() }),
        ..HybridSettings::default()
    }
}

/// Bakes a volume at each spacing of `per_side` (the scene's longest side / n) and times the
/// hybrid with it against `reference`.
pub fn series(
    ctx: &umbra::vk::Context,
    renderer: &Renderer,
    camera: &Camera,
    reference: &[[f32; 4]],
    s: &SuiteSettings,
    per_side: &[u32],
) -> Result<Vec<ProbePoint>> {
    let settings = hybrid_settings(s, false);
    let with_ssao = hybrid_settings(s, true);
    let [lo, hi] = renderer.scene().bounds;
    let longest = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
    let mut out = Vec::new();
    for &n in per_side {
        let probe_settings = ProbeSettings { spacing: Some(longest / n as f32), ..ProbeSettings::default() };
        let mut volume = ProbeVolume::new(ctx, renderer.scene(), &probe_settings)?;
        let bar = super::progress_bar(volume.bake_sweeps() as u64, &format!("probes 1/{n}: bake"));
        let bake_ms =
            renderer.passes().bake_probes(renderer.scene(), &mut volume, &settings.lighting, |done, _| {
                bar.set_position(done as u64)
            })?;
        bar.finish_and_clear();
        let (ms, image) = suite::timed(
            s.repeats,
            || renderer.passes().hybrid_with_probes(renderer.scene(), camera, &settings, Some(&volume)),
            suite::frame_ms,
        )?;
        let (rmse, rel_mse) = suite::errors(&image.color, reference);
        let flip = Some(suite::flip_mean(&image.color, reference, s.size));
        let ao = with_ao(&image.color, reference, || {
            renderer.passes().hybrid_with_probes(renderer.scene(), camera, &with_ssao, Some(&volume))
        })?;
        let active = volume.read_active(ctx)?.iter().filter(|a| **a).count() as u32;
        out.push(ProbePoint {
            point: Point {
                method: SERIES.into(),
                unit: "probes_per_side",
                value: n,
                ms,
                rmse,
                rel_mse,
                flip,
                shadow_rel_mse: None,
            },
            probes: volume.grid.count(),
            active,
            bake_ms,
            ao,
        });
    }
    Ok(out)
}

/// One scene's run of the `probes` command: the hybrid without probes, then the series.
pub struct SceneProbes {
    /// The scene's name.
    pub scene: String,
    /// Triangles.
    pub triangles: usize,
    /// The reference's own relative MSE.
    pub floor: f64,
    /// The hybrid without probes, with SSAO and without.
    pub plain: [Point; 2],
    /// With probes, by spacing.
    pub probes: Vec<ProbePoint>,
    /// With lightmaps (and probes), by map size.
    pub lightmaps: Vec<LightmapPoint>,
}

/// One lightmap bake's point.
pub struct LightmapPoint {
    /// Texels a side of each map.
    pub size: u32,
    /// Maps (materials with charts).
    pub maps: usize,
    /// GPU-and-readback milliseconds of the bake (wall clock: it submits in batches).
    pub bake_ms: f64,
    /// The frame.
    pub point: Point,
    /// With the default SSAO on top.
    pub ao: BakedWithAo,
}

/// Lightmaps on `scene` unwrapped (a chart per triangle), at each map size of `sizes`, with a
/// probe volume at 1/8 of the longest side for the bounces beyond the first.
pub fn lightmap_series(
    ctx: &umbra::vk::Context,
    scene: &umbra::scene::Scene,
    camera: &Camera,
    reference: &[[f32; 4]],
    s: &SuiteSettings,
    sizes: &[u32],
) -> Result<Vec<LightmapPoint>> {
    use umbra::passes::lightmap::{unwrap_triangles, GpuLightmaps, LightmapLayout, LightmapSettings};
    let settings = hybrid_settings(s, false);
    let with_ssao = hybrid_settings(s, true);
    let mut out = Vec::new();
    for &size in sizes {
        let mut unwrapped = scene.clone();
        unwrap_triangles(&mut unwrapped, size);
        let renderer = Renderer::new(ctx, &unwrapped)?;
        let [lo, hi] = renderer.scene().bounds;
        let longest = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f32, f32::max);
        let probe_settings = ProbeSettings { spacing: Some(longest / 8.0), ..ProbeSettings::default() };
        let mut volume = ProbeVolume::new(ctx, renderer.scene(), &probe_settings)?;
        renderer.passes().bake_probes(renderer.scene(), &mut volume, &settings.lighting, |_, _| {})?;
        let layout = LightmapLayout::new(&unwrapped, size)?;
        let lightmap_settings = LightmapSettings { size, samples: 256, ..LightmapSettings::default() };
        let bar = super::progress_bar(lightmap_settings.samples as u64, &format!("lightmaps {size}²: bake"));
        let start = std::time::Instant::now();
        let maps = renderer.passes().bake_lightmaps(
            renderer.scene(),
            &layout,
            &lightmap_settings,
            &settings.lighting,
            Some(&volume),
            |done, _| bar.set_position(done as u64),
        )?;
        let bake_ms = start.elapsed().as_secs_f64() * 1e3;
        bar.finish_and_clear();
        let lightmaps = GpuLightmaps::upload(ctx, &maps, unwrapped.materials.len())?;
        let (ms, image) = suite::timed(
            s.repeats,
            || {
                renderer.passes().hybrid_with(
                    renderer.scene(),
                    camera,
                    &settings,
                    Some(&volume),
                    Some(&lightmaps),
                )
            },
            suite::frame_ms,
        )?;
        let (rmse, rel_mse) = suite::errors(&image.color, reference);
        let flip = Some(suite::flip_mean(&image.color, reference, s.size));
        let ao = with_ao(&image.color, reference, || {
            let passes = renderer.passes();
            passes.hybrid_with(renderer.scene(), camera, &with_ssao, Some(&volume), Some(&lightmaps))
        })?;
        let method = "hybrid + lightmaps".to_string();
        out.push(LightmapPoint {
            size,
            maps: maps.materials.len(),
            bake_ms,
            point: Point {
                method,
                unit: "lightmap_size",
                value: size,
                ms,
                rmse,
                rel_mse,
                flip,
                shadow_rel_mse: None,
            },
            ao,
        });
    }
    Ok(out)
}

/// Runs the comparison on one scene.
pub fn run_scene(
    ctx: &umbra::vk::Context,
    key: &str,
    scene: &umbra::scene::Scene,
    camera: &Camera,
    s: &SuiteSettings,
    per_side: &[u32],
    lightmap_sizes: &[u32],
) -> Result<SceneProbes> {
    let renderer = Renderer::new(ctx, scene)?;
    let (reference, floor) = suite::reference_for(&renderer, camera, key, s)?;
    let mut plain = Vec::new();
    for (ssao, method) in [(true, "hybrid"), (false, "hybrid, no SSAO")] {
        let settings = hybrid_settings(s, ssao);
        let (ms, image) = suite::timed(
            s.repeats,
            || renderer.passes().hybrid(renderer.scene(), camera, &settings),
            suite::frame_ms,
        )?;
        let (rmse, rel_mse) = suite::errors(&image.color, &reference);
        let flip = Some(suite::flip_mean(&image.color, &reference, s.size));
        plain.push(Point {
            method: method.into(),
            unit: "shadow_rays",
            value: 4,
            ms,
            rmse,
            rel_mse,
            flip,
            shadow_rel_mse: None,
        });
    }
    let plain: [Point; 2] = plain.try_into().map_err(|_| anyhow::anyhow!("two hybrid points"))?;
    let probes = series(ctx, &renderer, camera, &reference, s, per_side)?;
    let lightmaps = lightmap_series(ctx, scene, camera, &reference, s, lightmap_sizes)?;
    // The chart: error against frame time, the points labelled by their setting.
    let mut points: Vec<&Point> = plain.iter().collect();
    points.extend(probes.iter().map(|p| &p.point));
    points.extend(lightmaps.iter().map(|p| &p.point));
    let chart_points: Vec<super::chart::ChartPoint> = points
        .iter()
        .map(|p| super::chart::ChartPoint {
            method: &p.method,
            unit: p.unit,
            value: p.value,
            ms: p.ms,
            error: p.rel_mse,
        })
        .collect();
    let title =
        format!("{}: probes and lightmaps — {}×{} on {}", scene.name, s.size.0, s.size.1, ctx.info().name);
    let chart =
        super::chart::Chart { title: &title, y_desc: "relative MSE vs converged path tracing (log)", floor };
    super::chart::write(&s.out.join(format!("probes-{key}")), &chart, &chart_points)?;
    Ok(SceneProbes {
        scene: scene.name.clone(),
        triangles: renderer.scene().bvh_stats.triangles,
        floor,
        plain,
        probes,
        lightmaps,
    })
}

/// A baked point's JSON gains its bias and its error and bias with SSAO.
fn baked_ao(v: &mut Value, ao: &BakedWithAo) {
    v["bias"] = json!(ao.bias);
    v["with_ssao"] = json!({"rel_mse": ao.ssao_rel_mse, "bias": ao.ssao_bias});
}

/// The JSON document of a run.
pub fn to_json(device: &str, s: &SuiteSettings, scenes: &[SceneProbes]) -> Value {
    let point = |p: &Point| json!({ "gpu_ms": p.ms, "rel_mse": p.rel_mse, "flip": p.flip, "rmse": p.rmse });
    json!({
        "device": device,
        "size": [s.size.0, s.size.1],
        "reference_spp": s.reference_spp,
        "repeats": s.repeats,
        "scenes": scenes.iter().map(|r| json!({
            "scene": r.scene,
            "triangles": r.triangles,
            "reference_rel_mse_floor": r.floor,
            "hybrid": point(&r.plain[0]),
            "hybrid_no_ssao": point(&r.plain[1]),
            "probes": r.probes.iter().map(|p| {
                let mut v = point(&p.point);
                v["per_side"] = json!(p.point.value);
                v["probes"] = json!(p.probes);
                v["active"] = json!(p.active);
                v["bake_ms"] = json!(p.bake_ms);
                baked_ao(&mut v, &p.ao);
                v
            }).collect::<Vec<_>>(),
            "lightmaps": r.lightmaps.iter().map(|p| {
                let mut v = point(&p.point);
                v["size"] = json!(p.size);
                v["maps"] = json!(p.maps);
                v["bake_ms"] = json!(p.bake_ms);
                baked_ao(&mut v, &p.ao);
                v
            }).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    })
}

/// The Markdown table of a run's JSON (what BENCHMARKS.md shows).
pub fn table(doc: &Value) -> String {
    let mut out = format!(
        "{}×{}, {}-spp references, {}; hybrid = 4 shadow rays, IBL (SSAO 16 where said; the probes' \
         irradiance replaces the IBL's diffuse part); ratios against the hybrid with SSAO; bias: the \
         image's mean over the reference's, less 1; the baked rows without AO, and (last two \
         columns) with the command line's default SSAO on top:\n\n\
         | scene | probes (longest side / n) | active | bake | frame | ÷ hybrid frame | rel. MSE | ÷ hybrid rel. MSE | FLIP | bias | with SSAO: rel. MSE | with SSAO: bias |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        doc["size"][0],
        doc["size"][1],
        doc["reference_spp"],
        doc["device"].as_str().unwrap_or("?"),
    );
    for scene in doc["scenes"].as_array().cloned().unwrap_or_default() {
        let name = scene["scene"].as_str().unwrap_or("?");
        let plain = &scene["hybrid"];
        let (plain_ms, plain_rel) = (num(&plain["gpu_ms"]), num(&plain["rel_mse"]));
        out += &format!(
            "| {name} | none (SSAO) | — | — | {plain_ms:.1} ms | 1 | {plain_rel:.4} | 1 | {:.3} | — | — | — |\n",
            num(&plain["flip"])
        );
        let bare = &scene["hybrid_no_ssao"];
        out += &format!(
            "| {name} | none (no SSAO) | — | — | {:.1} ms | {:.2} | {:.4} | {:.2} | {:.3} | — | — | — |\n",
            num(&bare["gpu_ms"]),
            num(&bare["gpu_ms"]) / plain_ms,
            num(&bare["rel_mse"]),
            num(&bare["rel_mse"]) / plain_rel,
            num(&bare["flip"])
        );
        // A baked row: its label, active probes, bake and frame against the hybrid with SSAO.
        let row = |label: String, active: String, p: &Value| {
            // Bias and the SSAO columns, where the run recorded them.
            let percent =
                |v: &Value| if v.is_f64() { format!("{:+.1} %", 100.0 * num(v)) } else { "—".into() };
            let ssao_rel = &p["with_ssao"]["rel_mse"];
            format!(
                "| {name} | {label} | {active} | {:.0} ms | {:.1} ms | {:.2} | {:.4} | {:.2} | {:.3} | {} | {} | {} |\n",
                num(&p["bake_ms"]),
                num(&p["gpu_ms"]),
                num(&p["gpu_ms"]) / plain_ms,
                num(&p["rel_mse"]),
                num(&p["rel_mse"]) / plain_rel,
                num(&p["flip"]),
                percent(&p["bias"]),
                if ssao_rel.is_f64() { format!("{:.4}", num(ssao_rel)) } else { "—".into() },
                percent(&p["with_ssao"]["bias"]),
            )
        };
        for p in scene["probes"].as_array().cloned().unwrap_or_default() {
            out += &row(format!("{} (1/{})", p["probes"], p["per_side"]), p["active"].to_string(), &p);
        }
        for p in scene["lightmaps"].as_array().cloned().unwrap_or_default() {
            out +=
                &row(format!("lightmaps {}² ({} maps) + probes 1/8", p["size"], p["maps"]), "—".into(), &p);
        }
    }
    let floors: Vec<String> = doc["scenes"]
        .as_array()
        .cloned()
        .unwrap_or_default()
        .iter()
        .map(|s| format!("{} {:.1e}", s["scene"].as_str().unwrap_or("?"), num(&s["reference_rel_mse_floor"])))
        .collect();
    out += &format!("\nThe references' own noise (relative MSE): {}.\n", floors.join(", "));
    out
}

/// The probes comparison on the Cornell box, Sponza under a sun (when present) and `gltf`.
pub(crate) fn run_probes(
    settings: &suite::SuiteSettings,
    sponza: Option<&std::path::Path>,
    gltf: &[PathBuf],
    lightmap_sizes: &[u32],
) -> Result<()> {
    let ctx = Context::new(&ContextDesc::default())?;
    umbra::atomic::create_dir(&settings.out)?;
    let mut scenes = vec![("cornell".to_string(), umbra::scene::Scene::cornell_box())];
    scenes.extend(sponza_under_a_sun(sponza));
    scenes.extend(load_gltf(gltf)?);
    let mut results = Vec::new();
    for (key, scene) in &scenes {
        let camera = bench_camera(scene);
        results.push(
            run_scene(
                &ctx,
                key,
                scene,
                &camera,
                settings,
                &settings.probes_per_side,
                if key == "cornell" { lightmap_sizes } else { &[] },
            )
            .with_context(|| scene.name.clone())?,
        );
    }
    let doc = to_json(&ctx.info().name, settings, &results);
    print!("{}", table(&doc));
    write_json(&settings.out, "probes.json", &doc)
}
