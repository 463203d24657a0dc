//! One render split across processes (`render --sample-range`, `--tile`) and joined again
//! (`umbra merge`): the parts merge into the render one process makes, and parts that do not
//! belong together are refused with the files named.

// Sample ranges are lists of ranges here, one long or several.
#![allow(clippy::single_range_in_vec_init)]

mod common;

use common::run_validated;
use std::path::{Path, PathBuf};
use std::process::Command;
use umbra::merge::PathExr;

fn umbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_umbra"))
}

/// A fresh folder for one test's files.
fn folder(name: &str) -> PathBuf {
    common::fresh_folder(&format!("merge-{name}"))
}

/// `umbra render` of the Cornell box at 40×30 with `extra` arguments, into `out`.
fn render(out: &Path, extra: &[&str]) -> PathExr {
    run_validated(
        umbra().args(["render", "--size", "40x30", "--max-bounces", "4"]).args(extra).arg("-o").arg(out),
    );
    PathExr::read(out).unwrap()
}

fn merge(out: &Path, parts: &[&Path]) -> std::process::Output {
    umbra().arg("merge").args(parts).arg("-o").arg(out).output().unwrap()
}

fn merged(out: &Path, parts: &[&Path]) -> PathExr {
    let result = merge(out, parts);
    assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
    PathExr::read(out).unwrap()
}

/// Every channel of `a` within `ulps` units in the last place of the largest value of `b`'s.
fn assert_close(what: &str, a: &[[f32; 3]], b: &[[f32; 3]], ulps: f32) {
    assert_eq!(a.len(), b.len(), "{what}: pixel counts");
    let largest = b.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
    let bound = ulps * largest * f32::EPSILON;
    let worst = a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    eprintln!(
        "{what}: largest difference {worst:e} ({:.2} ulps of the largest value {largest})",
        worst / (largest * f32::EPSILON)
    );
    assert!(worst <= bound, "{what}: differs by {worst:e}, more than {ulps} ulps of {largest}");
}

/// Samples 0..3 and 3..8, merged, are the 8-sample render (to float rounding: the parts' sums
/// round in another order; measured ≤ 1.1 ulps of the largest value; the albedo and emission,
/// means over the samples, likewise), with its first sample's normal exactly; the merged file says
/// it holds 0..8.
#[test]
fn sample_ranges_merge_into_the_whole_render() {
    let dir = folder("samples");
    let full = render(&dir.join("full.exr"), &["--spp", "8"]);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    let part = render(&a, &["--spp", "8", "--sample-range", "0..3"]);
    render(&b, &["--spp", "8", "--sample-range", "3..8"]);
    assert_eq!((part.samples.clone(), part.planned_spp), (vec![0..3], Some(8)));
    // Parts in either order.
    for order in [[&b, &a], [&a, &b]] {
        let m = merged(&dir.join("m.exr"), &order.map(|p| p.as_path()));
        assert_eq!(m.samples, [0..8]);
        assert_close("mean", &m.mean, &full.mean, 8.0);
        assert_close("second moment", &m.moment, &full.moment, 8.0);
        assert_close("albedo", &m.albedo, &full.albedo, 8.0);
        assert_close("emission", &m.emission, &full.emission, 8.0);
        assert_eq!(m.normal, full.normal);
        assert_eq!(m.region, full.region);
    }
    // The same part writes the same bytes (the header too).
    let (x, y) = (dir.join("x.exr"), dir.join("y.exr"));
    full.write(&x).unwrap();
    full.write(&y).unwrap();
    assert!(std::fs::read(&x).unwrap() == std::fs::read(&y).unwrap(), "one image, two different files");
    // A part is not the whole: samples 3..8 alone differ from 0..8 by far more than rounding.
    let late = PathExr::read(&b).unwrap();
    let diff = late
        .mean
        .iter()
        .flatten()
        .zip(full.mean.iter().flatten())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(diff > 1e-3, "samples 3..8 alone equal the whole render ({diff})");
    std::fs::remove_dir_all(&dir).ok();
}

/// The main RGB layer of an EXR (a denoised render's denoised image).
fn main_layer(path: &Path) -> Vec<[f32; 3]> {
    let (_, _, channels) = umbra::output::read_exr_channels(path).unwrap();
    let [r, g, b] = ["R", "G", "B"].map(|c| channels.iter().find(|(n, _)| n == c).unwrap().1.clone());
    (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect()
}

/// `--denoise` parts carry the denoiser's lobe split (layers `specular` and `split`, RGBA) and
/// the albedo's coverage (`albedo.A`); merged they are the whole `--denoise` render's to float
/// rounding (8 ulps of the largest value, as the mean), and `umbra merge --denoise` filters the
/// merge as the whole render was filtered: the denoised images agree to 1e-5 of the largest
/// value (the filter's edge-stopping weights are continuous in its inputs, which differ by
/// rounding only; measured on lavapipe: 1.6e-8). One part traced by the wavefront integrator,
/// which splits the same samples the same way.
#[test]
fn denoised_parts_merge_into_the_whole_denoised_render() {
    let dir = folder("denoise");
    let full_path = dir.join("full.exr");
    let full = render(&full_path, &["--spp", "8", "--denoise"]);
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    render(&a, &["--spp", "8", "--sample-range", "0..3", "--denoise"]);
    render(&b, &["--spp", "8", "--sample-range", "3..8", "--denoise", "--integrator", "wavefront"]);
    let m_path = dir.join("m.exr");
    let stdout = run_validated(umbra().arg("merge").arg(&a).arg(&b).arg("--denoise").arg("-o").arg(&m_path));
    let m = PathExr::read(&m_path).unwrap();
    eprintln!("{stdout}");
    assert_eq!(m.samples, [0..8]);
    assert_close("mean", &m.mean, &full.mean, 8.0);
    let coverage =
        |e: &PathExr| e.coverage.as_ref().expect("the coverage").iter().map(|&a| [a; 3]).collect::<Vec<_>>();
    assert_close("coverage", &coverage(&m), &coverage(&full), 8.0);
    let (ms, fs) =
        (m.lobe_split.as_ref().expect("the merge's split"), full.lobe_split.as_ref().expect("the split"));
    for (name, x, y) in [("specular", &ms.specular, &fs.specular), ("split", &ms.split, &fs.split)] {
        let rgb = |v: &Vec<[f32; 4]>| v.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
        let alpha = |v: &Vec<[f32; 4]>| v.iter().map(|p| [p[3]; 3]).collect::<Vec<_>>();
        assert_close(name, &rgb(x), &rgb(y), 8.0);
        assert_close(&format!("{name} alpha"), &alpha(x), &alpha(y), 8.0);
    }
    let (denoised, whole) = (main_layer(&m_path), main_layer(&full_path));
    assert_ne!(whole, full.mean, "the whole render's main layer is not denoised");
    let largest = whole.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
    let worst =
        denoised.iter().flatten().zip(whole.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max);
    eprintln!(
        "denoised: largest difference {worst:e} ({:e} of the largest value {largest})",
        worst / largest
    );
    assert!(worst <= 1e-5 * largest, "the denoised merge differs from the denoised render by {worst:e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Tiles render each pixel as the whole image does (same ray, same random numbers: bit for bit),
/// and tiles whose samples were split too merge into the whole render.
#[test]
fn tiles_merge_into_the_whole_render() {
    let dir = folder("tiles");
    let full = render(&dir.join("full.exr"), &["--spp", "6"]);
    let left = dir.join("left.exr");
    let tile = render(&left, &["--spp", "6", "--tile", "0,0,25,30"]);
    let width = 25;
    for y in 0..30 {
        for x in 0..width {
            assert_eq!(tile.mean[y * width + x], full.mean[y * 40 + x], "pixel ({x}, {y}) of the left tile");
        }
    }
    let (right_a, right_b) = (dir.join("right-a.exr"), dir.join("right-b.exr"));
    render(&right_a, &["--spp", "6", "--sample-range", "0..2", "--tile", "25,0,15,30"]);
    render(&right_b, &["--spp", "6", "--sample-range", "2..6", "--tile", "25,0,15,30"]);
    let m = merged(&dir.join("m.exr"), &[&right_a, &left, &right_b]);
    assert_eq!((m.region, m.samples.clone()), (full.region, vec![0..6]));
    assert_close("mean", &m.mean, &full.mean, 8.0);
    assert_close("albedo", &m.albedo, &full.albedo, 8.0);
    assert_eq!(m.normal, full.normal);
    // A tile outside the image is refused before rendering.
    let out = umbra()
        .args(["render", "--size", "40x30", "--tile", "30,0,15,30", "-o"])
        .arg(dir.join("x.exr"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && stderr.contains("does not fit in the 40x30 image"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Parts that do not make one render are refused, naming the files: overlapping samples, another
/// seed, overlapping tiles, tiles with a hole between them, a file umbra did not write.
#[test]
fn merge_refuses_parts_of_different_renders() {
    let dir = folder("refused");
    let p = |name: &str| dir.join(name);
    render(&p("a.exr"), &["--spp", "4", "--sample-range", "0..2"]);
    render(&p("overlap.exr"), &["--spp", "4", "--sample-range", "1..3"]);
    render(&p("seed.exr"), &["--spp", "4", "--sample-range", "2..4", "--seed", "7"]);
    render(&p("plan.exr"), &["--spp", "8", "--sample-range", "2..4"]);
    render(&p("t1.exr"), &["--spp", "2", "--tile", "0,0,20,30"]);
    render(&p("t2.exr"), &["--spp", "2", "--tile", "10,0,20,30"]);
    render(&p("t3.exr"), &["--spp", "2", "--tile", "30,0,10,30"]);
    umbra::output::write_exr(
        &p("plain.exr"),
        1,
        1,
        &[umbra::output::Layer { name: "", channels: &["R", "G", "B"], data: &[0.0; 3] }],
    )
    .unwrap();
    let cases: [(&str, &[&str], &str); 6] = [
        ("overlapping samples", &["a.exr", "overlap.exr"], "overlapping sample ranges"),
        ("another seed", &["a.exr", "seed.exr"], "are not parts of one render"),
        ("another plan", &["a.exr", "plan.exr"], "4 spp"),
        ("overlapping tiles", &["t1.exr", "t2.exr"], "overlap"),
        ("a hole", &["t1.exr", "t3.exr"], "leave holes"),
        ("not umbra's", &["a.exr", "plain.exr"], "no 'umbra.part' attribute"),
    ];
    for (what, files, message) in cases {
        let paths: Vec<PathBuf> = files.iter().map(|f| p(f)).collect();
        let out = merge(&p("m.exr"), &paths.iter().map(|p| p.as_path()).collect::<Vec<_>>());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{what}: merged");
        assert!(stderr.contains(message), "{what}: {stderr}");
        assert!(files.iter().any(|f| stderr.contains(f)), "{what}: no file named: {stderr}");
    }
    // --sample-range is a part of the path tracer's --spp, which it needs and may not pass.
    for args in [
        &["--sample-range", "0..2"][..],
        &["--spp", "4", "--sample-range", "2..6"],
        &["--mode", "hybrid", "--spp", "4", "--sample-range", "0..2"],
    ] {
        let out =
            umbra().args(["render", "--size", "8x8"]).args(args).arg("-o").arg(p("x.exr")).output().unwrap();
        assert!(!out.status.success(), "{args:?} accepted");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A lost part is not a whole render: with a sample range or a tile missing, merge refuses,
/// naming the files and what is missing (samples 2..4 in the middle or at the end, the top or
/// the left tile), and exits non-zero; `--allow-partial` writes what there is, saying what it
/// lacks. The merged file keeps the plan, so a partial merge completed later is whole.
#[test]
fn merge_refuses_a_lost_part_unless_asked() {
    let dir = folder("lost");
    let p = |name: &str| dir.join(name);
    for (name, range) in [("s0.exr", "0..2"), ("s1.exr", "2..4"), ("s2.exr", "4..6")] {
        render(&p(name), &["--spp", "6", "--sample-range", range]);
    }
    for (name, tile) in [("top.exr", "0,0,40,10"), ("bottom.exr", "0,10,40,20"), ("left.exr", "0,0,10,30")] {
        render(&p(name), &["--spp", "2", "--tile", tile]);
    }
    render(&p("right.exr"), &["--spp", "2", "--tile", "10,0,30,30"]);
    let cases: [(&[&str], &str); 5] = [
        (&["s0.exr", "s2.exr"], "samples 2..4 of the render's 0..6"),
        (&["s0.exr", "s1.exr"], "samples 4..6 of the render's 0..6"),
        (&["s1.exr", "s2.exr"], "samples 0..2 of the render's 0..6"),
        (&["bottom.exr"], "rows 0..10 (above)"),
        (&["right.exr"], "columns 0..10 (left)"),
    ];
    for (files, missing) in cases {
        let paths: Vec<PathBuf> = files.iter().map(|f| p(f)).collect();
        let parts: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
        let out = merge(&p("m.exr"), &parts);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{files:?}: merged");
        assert!(stderr.contains(missing) && stderr.contains("missing (a lost part?)"), "{files:?}: {stderr}");
        assert!(files.iter().all(|f| stderr.contains(f)), "{files:?}: the files not named: {stderr}");
        assert!(!p("m.exr").exists(), "{files:?}: written");
        let partial = p("partial.exr");
        let stderr =
            run_validated(umbra().arg("merge").args(&parts).arg("--allow-partial").arg("-o").arg(&partial));
        assert!(stderr.contains("--allow-partial: the merge lacks") && stderr.contains(missing), "{stderr}");
        std::fs::remove_file(&partial).unwrap();
    }
    // A partial merge of two parts, completed by the third: whole, 0..6.
    run_validated(
        umbra()
            .arg("merge")
            .arg(p("s0.exr"))
            .arg(p("s2.exr"))
            .arg("--allow-partial")
            .arg("-o")
            .arg(p("ends.exr")),
    );
    let whole = merged(&p("m.exr"), &[&p("ends.exr"), &p("s1.exr")]);
    assert_eq!((whole.samples, whole.planned_spp), (vec![0..6], Some(6)));
    std::fs::remove_dir_all(&dir).ok();
}
