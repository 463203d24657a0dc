//! `umbra-bench` never rots: its quick runs finish, validate, and write output that parses, and
//! BENCHMARKS.md's current tables are what `--table` prints from the committed JSON. (Timings are
//! recorded in BENCHMARKS.md, never asserted.)

mod common;

use common::run_validated;
use std::process::Command;

#[test]
fn rays_quick_validates_and_writes_json() {
    let dir = std::env::temp_dir().join(format!("umbra-bench-{}", std::process::id()));
    run_validated(
        Command::new(env!("CARGO_BIN_EXE_umbra-bench")).args(["rays", "--quick", "--out"]).arg(&dir),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("rays.json")).expect("rays.json written"))
            .expect("rays.json parses");
    let scene = &json["scenes"][0];
    assert!(scene["triangles"].as_u64().unwrap() > 50_000);
    let kinds: Vec<&str> =
        scene["rays"].as_array().unwrap().iter().map(|r| r["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds, ["primary", "shadow", "diffuse"]);
    for r in scene["rays"].as_array().unwrap() {
        assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0, "{r}");
    }
    // The full-sweep comparison ran and the binned build is within 2 % of its SAH cost.
    let (binned, sweep) =
        (scene["binned"]["sah_cost"].as_f64().unwrap(), scene["sweep"]["sah_cost"].as_f64().unwrap());
    assert!(binned <= sweep * 1.02, "binned SAH {binned} vs sweep {sweep}");
    let table = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["rays", "--table"])
        .arg(dir.join("rays.json"))
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&table.stdout);
    assert!(table.contains("| terrain | 78018 |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench suite --quick` runs every method, writes JSON, CSV and charts that parse, and
/// its errors behave: path tracing's relative MSE falls with samples (32 spp has 1/32 of the
/// variance of 1 spp; the test asks for a quarter), RTAO's with rays, and every error is finite.
#[test]
fn suite_quick_writes_json_csv_and_charts() {
    let dir = std::env::temp_dir().join(format!("umbra-suite-{}", std::process::id()));
    run_validated(
        Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["suite", "--quick", "--out"])
            .arg(&dir),
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("suite.json")).expect("suite.json written"))
            .expect("suite.json parses");
    let scenes = json["scenes"].as_array().unwrap();
    assert!(scenes.len() >= 2, "the Cornell box and the sphere grid");
    let mut rows = 0;
    for scene in scenes {
        let points = scene["points"].as_array().unwrap();
        let ao_points = scene["ao_points"].as_array().unwrap();
        rows += points.len() + ao_points.len();
        for method in [
            "pathtrace",
            "hybrid",
            "hybrid, no SSAO",
            "hybrid, no IBL",
            "hybrid, SSAO sweep",
            "hybrid, supersampled",
        ] {
            assert!(points.iter().any(|p| p["method"] == method), "{method} missing in {}", scene["scene"]);
        }
        for method in ["ssao", "gtao", "gtao half", "rtao"] {
            assert!(
                ao_points.iter().any(|p| p["method"] == method),
                "{method} missing in {}",
                scene["scene"]
            );
        }
        for (p, keys) in points
            .iter()
            .map(|p| (p, &["gpu_ms", "rmse", "rel_mse", "flip"][..]))
            .chain(ao_points.iter().map(|p| (p, &["gpu_ms", "mse"][..])))
        {
            for key in keys {
                let v = p[key].as_f64().unwrap_or(f64::NAN);
                assert!(v.is_finite() && v >= 0.0, "{key} of {p}");
            }
        }
        // RTAO converges to its reference: 16 rays have less error than 1 (expected 1/16).
        let rtao: Vec<f64> =
            ao_points.iter().filter(|p| p["method"] == "rtao").map(|p| p["mse"].as_f64().unwrap()).collect();
        assert!(rtao[rtao.len() - 1] < rtao[0] / 4.0, "RTAO error does not fall with rays: {rtao:?}");
    }
    // The sphere grid's sun: the shadow term against its sized rays (256 per light) is recorded
    // for the maps and the sized rays' own series, whose error falls with rays (16 rays against
    // 1: expected 1/16 of the variance; asked for a quarter).
    let spheres = scenes.iter().find(|s| s["scene"] == "scenes/spheres.glb").expect("the sphere grid");
    assert_eq!(spheres["shadow_reference"]["rays"], 256, "{}", spheres["shadow_reference"]);
    let points = spheres["points"].as_array().unwrap();
    let shadow = |method: &str| -> Vec<f64> {
        let values: Vec<f64> = points
            .iter()
            .filter(|p| p["method"] == method)
            .map(|p| p["shadow_rel_mse"].as_f64().unwrap())
            .collect();
        assert!(
            !values.is_empty() && values.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{method}: {values:?}"
        );
        values
    };
    shadow("hybrid, pcss shadow maps");
    let sized = shadow("hybrid, rt sized shadows");
    assert!(sized[sized.len() - 1] < sized[0] / 4.0, "the sized rays' error does not fall: {sized:?}");
    let cornell = scenes[0]["points"].as_array().unwrap();
    let path: Vec<f64> = cornell
        .iter()
        .filter(|p| p["method"] == "pathtrace")
        .map(|p| p["rel_mse"].as_f64().unwrap())
        .collect();
    assert!(path[path.len() - 1] < path[0] / 4.0, "path tracing error does not fall with spp: {path:?}");

    let csv = std::fs::read_to_string(dir.join("suite.csv")).expect("suite.csv written");
    assert_eq!(csv.lines().count(), rows + 1, "one CSV row per point plus the header");
    for (key, series) in [
        ("cornell", "pathtrace"),
        ("spheres", "pathtrace"),
        ("cornell-ao", "rtao"),
        ("spheres-ao", "ssao"),
        ("spheres-ao", "gtao half"),
        ("cornell-flip", "hybrid"),
    ] {
        let svg = std::fs::read_to_string(dir.join(format!("suite-{key}.svg"))).expect("SVG chart");
        assert!(svg.contains("<svg") && svg.contains(series), "SVG chart of {key}");
        let png = image::open(dir.join(format!("suite-{key}.png"))).expect("PNG chart decodes");
        assert_eq!((png.width(), png.height()), (900, 600));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench suite --redraw` redraws every scene's three charts (image error, FLIP, AO) of the
/// committed suite.json, and nothing else, with no Vulkan driver to be found (it measures
/// nothing): each SVG and PNG of the usual size, each SVG titled with its scene and holding every
/// charted series of the JSON. A truncated file, a missing field and a missing file are errors
/// naming the file (and the field), and write nothing.
#[test]
fn suite_redraw_writes_every_scenes_charts_from_json() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = common::fresh_folder("suite-redraw");
    let out = dir.join("charts");
    // What the committed file's scenes are keyed by (it predates the JSON's `key`).
    let keys = [
        ("cornell-box.glb (embedded)", "cornell"),
        ("Cornell box, point light", "cornell-point"),
        ("scenes/spheres.glb", "spheres"),
        ("scenes/textured.glb", "textured"),
        ("sponza_dabrovic under a sun", "sponza-sun"),
    ];
    let redraw = |file: &std::path::Path| {
        Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .current_dir(root)
            .env("VK_DRIVER_FILES", "/nonexistent/no-driver.json")
            .env("VK_ICD_FILENAMES", "/nonexistent/no-driver.json")
            .args(["suite", "--redraw"])
            .arg(file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap()
    };
    let file = std::path::Path::new(root).join("docs/bench/suite.json");
    let run = redraw(&file);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));

    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    let scenes = json["scenes"].as_array().unwrap();
    assert!(scenes.len() >= 5, "every scene of the suite, Sponza's included");
    let mut expected = Vec::new();
    for scene in scenes {
        let name = scene["scene"].as_str().unwrap();
        let key = scene["key"].as_str().or_else(|| keys.iter().find(|(n, _)| *n == name).map(|(_, k)| *k));
        let key = key.unwrap_or_else(|| panic!("no key for the scene {name:?}: add it to this test"));
        // The series each chart draws: those with a point of positive time and error.
        let series = |points: &str, error: &str| -> Vec<String> {
            let mut names: Vec<String> = Vec::new();
            for p in scene[points].as_array().unwrap() {
                let method = p["method"].as_str().unwrap().to_string();
                let charted = p["gpu_ms"].as_f64().is_some_and(|v| v > 0.0)
                    && p[error].as_f64().is_some_and(|v| v > 0.0);
                if charted && !names.contains(&method) {
                    names.push(method);
                }
            }
            assert!(!names.is_empty(), "{name}: nothing to chart in {points}");
            names
        };
        // The titles the measuring run gives them (the committed file predates `ao_radius`: the
        // default 0.5).
        let (w, h) = (&json["size"][0], &json["size"][1]);
        let title = format!("{name} — {w}×{h} on {}", json["device"].as_str().unwrap());
        let r = json["ao_radius"].as_f64().unwrap_or(0.5);
        let ao_title = format!("ambient occlusion, r = {r} — {name} — {w}×{h}");
        for (stem, title, series) in [
            (format!("suite-{key}"), &title, series("points", "rel_mse")),
            (format!("suite-{key}-flip"), &title, series("points", "flip")),
            (format!("suite-{key}-ao"), &ao_title, series("ao_points", "mse")),
        ] {
            let svg = std::fs::read_to_string(out.join(format!("{stem}.svg")))
                .unwrap_or_else(|e| panic!("{stem}.svg: {e}"));
            assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"), "{stem}.svg");
            assert!(svg.contains(r#"width="900" height="600""#), "{stem}.svg is not 900×600");
            let escape = |t: &str| t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;");
            // plotters writes each text on a line of its own.
            let has_text = |text: &str| svg.lines().any(|line| line == escape(text));
            assert!(has_text(title), "{stem}.svg is not titled {title:?}");
            for method in &series {
                assert!(has_text(method), "{stem}.svg: no series {method:?} in the legend");
            }
            let png = image::open(out.join(format!("{stem}.png")))
                .unwrap_or_else(|e| panic!("{stem}.png does not decode: {e}"));
            assert_eq!((png.width(), png.height()), (900, 600), "{stem}.png");
            expected.extend([format!("{stem}.png"), format!("{stem}.svg")]);
        }
    }
    expected.sort();
    let mut written: Vec<String> =
        std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    written.sort();
    assert_eq!(written, expected, "the charts, and nothing else");

    // Bad input: an error naming the file (and the field), no panic, nothing written.
    let text = std::fs::read_to_string(&file).unwrap();
    let truncated = dir.join("truncated.json");
    std::fs::write(&truncated, &text[..text.len() / 2]).unwrap();
    let mut doc = json.clone();
    doc["scenes"][1]["points"][3].as_object_mut().unwrap().remove("gpu_ms");
    let missing_field = dir.join("missing-field.json");
    std::fs::write(&missing_field, serde_json::to_string(&doc).unwrap()).unwrap();
    for (bad, says) in [
        (truncated, "parsing"),
        (missing_field, "scenes[1].points[3].gpu_ms"),
        (dir.join("absent.json"), "No such file"),
    ] {
        std::fs::remove_dir_all(&out).ok();
        let run = redraw(&bad);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{}: {stderr}", bad.display());
        assert!(
            stderr.contains(&bad.display().to_string())
                && stderr.contains(says)
                && !stderr.contains("panicked"),
            "{}: the error should name it and say {says:?}: {stderr}",
            bad.display()
        );
        assert!(!out.exists(), "{}: charts written from bad input", bad.display());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench denoise --quick` writes JSON with both series at every reading and a chart, and
/// its table prints it; the denoiser lowers the Cornell box's relative MSE at 4 spp (4.3× measured at
/// 64×64 against its 256-spp reference; 3× is asked for).
#[test]
fn denoise_quick_writes_json_and_a_chart() {
    let dir = std::env::temp_dir().join(format!("umbra-denoise-bench-{}", std::process::id()));
    run_validated(
        Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["denoise", "--quick", "--repeats", "1", "--out"])
            .arg(&dir),
    );
    let path = dir.join("denoise.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("denoise.json written")).expect("parses");
    let scene = &json["scenes"][0];
    let readings = scene["readings"].as_array().unwrap();
    assert_eq!(readings.iter().map(|r| r["spp"].as_u64().unwrap()).collect::<Vec<_>>(), [1, 2, 4, 8, 16, 32]);
    for r in readings {
        for key in ["raw_ms", "raw_rel_mse", "denoised_ms", "denoised_rel_mse"] {
            let v = r[key].as_f64().unwrap_or(f64::NAN);
            assert!(v.is_finite() && v > 0.0, "{key} of {r}");
        }
    }
    let at4 = &readings[2];
    let factor = at4["raw_rel_mse"].as_f64().unwrap() / at4["denoised_rel_mse"].as_f64().unwrap();
    assert!(factor > 3.0, "denoising at 4 spp lowers the relative MSE only {factor:.2}x");
    let svg = std::fs::read_to_string(dir.join("denoise-cornell.svg")).expect("SVG chart");
    assert!(svg.contains("path tracing + denoiser"), "the denoised series is charted");
    let table =
        Command::new(env!("CARGO_BIN_EXE_umbra-bench")).arg("denoise").arg("--table").arg(&path).output();
    let table = String::from_utf8(table.unwrap().stdout).unwrap();
    assert!(table.contains("| cornell-box.glb (embedded) |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench antialias` measures its series (supersampled at each sub-frame count, TAA after
/// each frame, TAA turning for 1, 2, … frames with each history filter, and for an animated scene
/// TAA while its geometry moves), writes JSON and a chart, and prints its table from the JSON.
#[test]
fn antialias_writes_json_a_chart_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-antialias-bench-{}", std::process::id()));
    // A run on a tiny image (the scene's flags, the sub-frame counts) and its JSON.
    let run = |scene: &[&str], samples: &str, json: &str| -> serde_json::Value {
        let out = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .arg("antialias")
            .args(scene)
            .args(["--size", "24x16", "--reference-spp", "8", "--samples", samples])
            .args(["--taa-frames", "3", "--repeats", "1", "--out"])
            .arg(&dir)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        serde_json::from_str(&std::fs::read_to_string(dir.join(json)).expect("JSON written")).expect("parses")
    };
    let json = run(&[], "1,4", "antialias-spheres.json");
    let path = dir.join("antialias-spheres.json");
    let points = json["points"].as_array().expect("points");
    let series = |m: &str| points.iter().filter(|p| p["method"] == m).count();
    assert_eq!((series("supersampled"), series("TAA, still camera")), (2, 3), "{points:?}");
    // Runs of 1 and 2 frames (the powers of two up to --taa-frames 3), with either history read.
    let turning = ["TAA, turning camera", "TAA, turning camera, bilinear history"];
    assert_eq!(turning.map(series), [2, 2], "{points:?}");
    assert!(points.iter().all(|p| p["ms"].as_f64().unwrap() > 0.0 && p["flip"].as_f64().unwrap() > 0.0));
    let svg = std::fs::read_to_string(dir.join("antialias-spheres.svg")).expect("SVG chart");
    assert!(svg.contains("TAA, still camera"), "the TAA series is charted");
    let table = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .arg("antialias")
        .arg("--table")
        .arg(&path)
        .output()
        .unwrap();
    let table = String::from_utf8(table.stdout).unwrap();
    assert!(table.contains("| supersampled | 4 sub-frames |"), "{table}");
    assert!(table.contains("| TAA, turning camera, bilinear history | 2 frames |"), "{table}");
    assert_eq!(series("TAA, moving geometry"), 0, "the sphere grid does not move");
    // An animated scene adds the moving-geometry series: runs of 1 and 2 frames.
    let json = run(&["--scene", "scenes/animated.glb"], "1", "antialias-animated.json");
    let moving = json["points"].as_array().unwrap().iter().filter(|p| p["method"] == "TAA, moving geometry");
    assert_eq!(moving.count(), 2, "{json}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `umbra-bench restir` on a tiny image writes JSON with every method's points and a chart, and
/// its table prints them.
#[test]
fn restir_writes_json_a_chart_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-restir-bench-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args([
            "restir",
            "--size",
            "16x16",
            "--reference-frames",
            "2",
            "--repeats",
            "1",
            "--frames",
            "2",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let path = dir.join("restir.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("restir.json written")).expect("parses");
    let points = json["points"].as_array().expect("points");
    for method in ["power", "RIS alone", "ReSTIR unbiased", "ReSTIR biased"] {
        assert!(points.iter().any(|p| p["method"] == method), "{method} measured");
    }
    assert!(points.iter().all(|p| p["ms"].as_f64().unwrap() > 0.0 && p["rel_mse"].as_f64().unwrap() >= 0.0));
    let svg = std::fs::read_to_string(dir.join("restir.svg")).expect("SVG chart");
    assert!(svg.contains("ReSTIR biased"), "the biased series is charted");
    let table =
        Command::new(env!("CARGO_BIN_EXE_umbra-bench")).arg("restir").arg("--table").arg(&path).output();
    let table = String::from_utf8(table.unwrap().stdout).unwrap();
    assert!(table.contains("| ReSTIR unbiased | 16 candidates |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench animation` on tiny frames writes JSON with both BVH updates for each motion,
/// and its table prints them with the ratio to the rebuild's frame.
#[test]
fn animation_writes_json_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-animation-bench-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["animation", "--size", "16x16", "--spp", "1", "--frames", "2", "--repeats", "1", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let path = dir.join("animation.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("animation.json written"))
            .expect("parses");
    let points = json["points"].as_array().expect("points");
    for motion in ["skin", "rigid node", "morph target", "all three"] {
        for bvh in ["refit", "rebuild"] {
            let p = points.iter().find(|p| p["motion"] == motion && p["bvh"] == bvh);
            let p = p.unwrap_or_else(|| panic!("{motion} with a {bvh} measured"));
            for key in ["bvh_ms", "update_ms", "sah", "trace_ms"] {
                assert!(p[key].as_f64().unwrap() > 0.0, "{motion} {bvh}: {key} {}", p[key]);
            }
        }
    }
    let table = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["animation", "--table"])
        .arg(&path)
        .output()
        .unwrap();
    let table = String::from_utf8(table.stdout).unwrap();
    assert_eq!(table.lines().filter(|l| l.starts_with("| skin |")).count(), 2, "{table}");
    assert!(table.contains("| 1.000 |"), "the rebuild's own ratio: {table}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `umbra-bench restir-pt` on a tiny image writes JSON with the power, RIS and RIS-with-reuse
/// series and a chart, and its table prints them.
#[test]
fn restir_pt_writes_json_a_chart_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-restir-pt-bench-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args([
            "restir-pt",
            "--size",
            "8x8",
            "--reference-spp",
            "16",
            "--max-bounces",
            "2",
            "--repeats",
            "1",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let path = dir.join("restir-pt.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("restir-pt.json written"))
            .expect("parses");
    let points = json["points"].as_array().expect("points");
    for method in ["power", "RIS 16", "RIS 32", "RIS 16 + samples", "RIS 16 + spatial", "RIS 4 + both"] {
        assert!(points.iter().any(|p| p["method"] == method), "{method} measured");
    }
    assert!(points.iter().all(|p| p["ms"].as_f64().unwrap() > 0.0 && p["rel_mse"].as_f64().unwrap() >= 0.0));
    // Power sampling's series runs past the others' (so their errors fall within it).
    assert!(points.iter().any(|p| p["method"] == "power" && p["spp"] == 256), "power at 256 spp");
    assert!(!points.iter().any(|p| p["method"] == "RIS 16" && p["spp"] == 256), "RIS up to 64 spp");
    let svg = std::fs::read_to_string(dir.join("restir-pt.svg")).expect("SVG chart");
    assert!(svg.contains("RIS 16"), "the RIS series are charted");
    let table =
        Command::new(env!("CARGO_BIN_EXE_umbra-bench")).arg("restir-pt").arg("--table").arg(&path).output();
    let table = String::from_utf8(table.unwrap().stdout).unwrap();
    assert!(table.contains("| RIS 16 | 4 |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The commands that print BENCHMARKS.md's current tables from the JSON committed in docs/bench.
const GENERATED_TABLES: &[&[&str]] = &[
    &["rays", "--table", "docs/bench/rays.json"],
    &["build", "--table", "docs/bench/build.json"],
    &["passes", "--table", "docs/bench/passes-cornell.json", "--table", "docs/bench/passes-spheres.json"],
    &["passes", "--table", "docs/bench/passes-sponza-1080.json"],
    &["animation", "--table", "docs/bench/animation.json"],
    &["antialias", "--table", "docs/bench/antialias-helmet.json"],
    &["antialias", "--table", "docs/bench/antialias-spheres.json"],
    &["antialias", "--table", "docs/bench/antialias-animated.json"],
    &["paths", "--table", "docs/bench/paths.json"],
    &["pipelines", "--table", "docs/bench/pipelines.json"],
    &["suite", "--table", "docs/bench/suite.json"],
    &["shadows", "--table", "docs/bench/shadows-sponza.json"],
    &["shadows", "--table", "docs/bench/shadows-sponza-one.json"],
    &["shadows", "--table", "docs/bench/shadows-spheres.json"],
    &["mis", "--table", "docs/bench/mis.json"],
    &["probes", "--table", "docs/bench/probes.json"],
    &["denoise", "--table", "docs/bench/denoise.json"],
    &["peers", "--table", "docs/bench/peers.json"],
    &["peers", "--table", "docs/bench/path.json"],
    &["peers", "--table", "docs/bench/path-helmet.json"],
    &["peers", "--table", "docs/bench/path-ldsampler.json"],
    &["peers", "--table", "docs/bench/path-helmet-ldsampler.json"],
    &["implicit", "--table", "docs/bench/implicit.json"],
    &["restir", "--table", "docs/bench/restir.json"],
    &["restir-pt", "--table", "docs/bench/restir-pt.json"],
    &["temporal", "--table", "docs/bench/temporal.json"],
    &["temporal", "--table", "docs/bench/temporal-still.json"],
];

/// BENCHMARKS.md's figures cannot drift from their JSON: everything each `--table` command prints
/// from the committed JSON (caption, rows, the lines under a table) stands verbatim in the part
/// above "# History", and every table row of that part is one of those printed. A changed JSON, a
/// hand-edited figure, a hand-typed table or a changed formatter fails here; the message names the
/// command that prints the right block.
#[test]
fn generated_tables_match_their_json() {
    let root = env!("CARGO_MANIFEST_DIR");
    let benchmarks = std::fs::read_to_string(format!("{root}/BENCHMARKS.md")).expect("BENCHMARKS.md");
    let (current, _history) =
        benchmarks.split_once("\n# History\n").expect("BENCHMARKS.md has a \"# History\" part");
    let current = format!("\n{current}\n");
    let mut printed_rows = std::collections::HashSet::new();
    for args in GENERATED_TABLES {
        let out =
            Command::new(env!("CARGO_BIN_EXE_umbra-bench")).current_dir(root).args(*args).output().unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let printed = String::from_utf8(out.stdout).unwrap();
        assert!(
            printed.lines().filter(|l| l.starts_with('|')).count() > 2,
            "umbra-bench {}: no table printed",
            args.join(" ")
        );
        assert!(
            current.contains(&format!("\n{printed}")),
            "BENCHMARKS.md's current figures do not hold what `umbra-bench {}` prints:\n{printed}",
            args.join(" ")
        );
        printed_rows.extend(printed.lines().filter(|l| l.starts_with('|')).map(str::to_string));
    }
    let typed: Vec<&str> =
        current.lines().filter(|l| l.starts_with('|') && !printed_rows.contains(*l)).collect();
    assert!(
        typed.is_empty(),
        "table rows above BENCHMARKS.md's \"# History\" that no --table command prints (generate \
         them, or move them to the history):\n{}",
        typed.join("\n")
    );
}

/// `umbra-bench build` on a small terrain writes build.json, and its table prints it.
#[test]
fn build_writes_json_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-build-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["build", "--terrain", "40", "--builds", "2", "--sweep", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let path = dir.join("build.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("build.json written")).expect("parses");
    let scene = &json["scenes"][0];
    assert_eq!(scene["triangles"].as_u64(), Some(2 * 40 * 40 + 15_360));
    assert!(scene["median_ms"].as_f64().unwrap() > 0.0 && scene["sweep_sah_cost"].as_f64().unwrap() > 0.0);
    let table =
        Command::new(env!("CARGO_BIN_EXE_umbra-bench")).arg("build").arg("--table").arg(&path).output();
    let table = String::from_utf8(table.unwrap().stdout).unwrap();
    assert!(table.contains("| terrain | 18560 |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench passes` writes passes.json with every pass and stage of each G-buffer's and AO
/// variant's hybrid frame (each stage the sum of its passes), and two runs print as one table.
#[test]
fn passes_writes_json_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-passes-{}", std::process::id()));
    run_validated(
        Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .args(["passes", "--size", "16x16", "--repeats", "1", "--out"])
            .arg(&dir),
    );
    let path = dir.join("passes.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("passes.json written")).expect("parses");
    let frames = json["frames"].as_array().unwrap();
    let labels: Vec<(&str, &str)> =
        frames.iter().map(|f| (f["gbuffer"].as_str().unwrap(), f["ao"].as_str().unwrap())).collect();
    // (G-buffer, AO label, AO pass) per frame, in the order the runs take turns.
    let variants = [("ssao", "ssao"), ("gtao", "gtao"), ("gtao half", "gtao")];
    let expected: Vec<(&str, &str, &str)> = ["raycast", "raster"]
        .iter()
        .flat_map(|&g| variants.iter().map(move |&(label, pass)| (g, label, pass)))
        .collect();
    assert_eq!(labels, expected.iter().map(|&(g, label, _)| (g, label)).collect::<Vec<_>>());
    for (frame, &(gbuffer, _, ao)) in frames.iter().zip(&expected) {
        let passes: Vec<&str> =
            frame["passes"].as_array().unwrap().iter().map(|p| p["pass"].as_str().unwrap()).collect();
        // The raster G-buffer's visibility buffer is a pass of its own, of the gbuffer stage.
        let first: &[&str] = if gbuffer == "raster" { &["visibility", "gbuffer"] } else { &["gbuffer"] };
        assert_eq!(passes, [first, &[ao, "ao_blur", "lighting"]].concat());
        // One repeat: each stage is the sum of its passes' times, the frame the sum of all.
        let ms = |pass: &str| {
            frame["passes"].as_array().unwrap().iter().find(|p| p["pass"] == pass).unwrap()["median_ms"]
                .as_f64()
                .unwrap()
        };
        let stage = |name: &str| frame["stages"][name]["median_ms"].as_f64().unwrap();
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
        let gbuffer_ms: f64 = first.iter().map(|p| ms(p)).sum();
        assert!(close(stage("gbuffer"), gbuffer_ms), "{frame}");
        assert!(close(stage("ao"), ms(ao) + ms("ao_blur")), "{frame}");
        assert!(close(stage("lighting"), ms("lighting")), "{frame}");
        assert!(close(stage("frame"), stage("gbuffer") + stage("ao") + stage("lighting")), "{frame}");
    }
    assert!(json["pathtrace"]["median_ms"].as_f64().unwrap() > 0.0);
    let output = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["passes", "--table"])
        .arg(&path)
        .arg("--table")
        .arg(&path)
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success()
            && table.contains("| pathtrace 1 spp |")
            && table.contains("| **frame** |")
            && table.contains(": raycast, gtao half |")
            && table.contains(": raster, ssao |")
            && table.contains("| gbuffer ÷ ray-cast + ssao's |"),
        "{table}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `umbra-bench paths` on two small scenes writes JSON that parses: positive rates, at least one
/// path segment per sample (the camera ray), at most max_bounces + 1, and the table prints it.
#[test]
fn paths_writes_json_and_a_table() {
    let dir = std::env::temp_dir().join(format!("umbra-paths-{}", std::process::id()));
    run_validated(
        Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .args(["paths", "scenes/textured.glb", "scenes/cornell-box.glb"])
            .args(["--size", "16x16", "--spp", "2", "--repeats", "1", "--max-bounces", "4", "--out"])
            .arg(&dir),
    );
    let path = dir.join("paths.json");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("paths.json written")).expect("parses");
    let scenes = json["scenes"].as_array().unwrap();
    assert_eq!(scenes.len(), 2);
    for s in scenes {
        assert!(s["msamples_per_s"].as_f64().unwrap() > 0.0, "{s}");
        let segments = s["segments_per_sample"].as_f64().unwrap();
        assert!(
            (1.0..=5.0).contains(&segments),
            "segments per sample {segments} outside [1, max_bounces + 1]"
        );
    }
    // The closed box keeps paths longer than the open textured plane's.
    assert!(scenes[1]["segments_per_sample"].as_f64() > scenes[0]["segments_per_sample"].as_f64());
    let output = Command::new(env!("CARGO_BIN_EXE_umbra-bench"))
        .args(["paths", "--table"])
        .arg(&path)
        .output()
        .unwrap();
    let table = String::from_utf8_lossy(&output.stdout);
    assert!(table.contains("| textured |") && table.contains("| cornell-box |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}
