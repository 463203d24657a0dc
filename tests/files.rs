//! What the `umbra` binary does to the user's files: every output written atomically (a full
//! device, a file-size limit, a kill in the middle of the write, a read-only target: the previous
//! file byte for byte, an error, a non-zero exit, no "wrote"), outputs that name an input refused
//! before any work, and messages in words.

mod common;

use std::path::Path;
use std::process::{Command, Output};

fn umbra() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_umbra"));
    command.env("UMBRA_VALIDATION", "1");
    command
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts that `out` failed with a message containing each of `words`, and wrote nothing it
/// claims.
fn refused(out: &Output, words: &[&str]) {
    let (stdout, stderr) = (String::from_utf8_lossy(&out.stdout), stderr(out));
    assert!(!out.status.success(), "succeeded: {stdout}{stderr}");
    assert!(!stdout.contains("wrote"), "claims a write: {stdout}");
    for w in words {
        assert!(stderr.contains(w), "no '{w}' in: {stderr}");
    }
}

const OLD: &[u8] = b"the user's previous image";

/// `umbra pattern` (a quick GPU render) writing a 512x512 PNG (its blue channel is noise: far over
/// 64 KiB) under a file-size
/// limit of 64 KiB: killed by SIGXFSZ in the middle of its write, the previous PNG is intact and
/// its temporary is left; with SIGXFSZ ignored, the write fails with "file too large" and a
/// non-zero exit, the previous PNG intact and no temporary. The next run removes the killed
/// run's temporary and writes the PNG.
#[test]
fn a_kill_or_a_file_size_limit_mid_write_leaves_the_previous_file() {
    let dir = common::fresh_folder("files-limit");
    let png = dir.join("pattern.png");
    std::fs::write(&png, OLD).unwrap();
    let limited = |trap: &str| {
        Command::new("bash")
            .arg("-c")
            .arg(format!("{trap} ulimit -c 0; ulimit -f 64; exec \"$0\" pattern --size 512x512 -o \"$1\""))
            .arg(env!("CARGO_BIN_EXE_umbra"))
            .arg(&png)
            // (ulimit -c 0: SIGXFSZ dumps core by default, and .ci/run allows cores.) The driver's
            // shader cache must not meet the limit first.
            .env("MESA_SHADER_CACHE_DISABLE", "true")
            .env("UMBRA_VALIDATION", "1")
            .output()
            .unwrap()
    };
    let ignored = limited("trap '' XFSZ;");
    refused(&ignored, &["pattern.png: file too large"]);
    assert_eq!(std::fs::read(&png).unwrap(), OLD);
    assert_eq!(common::file_names(&dir), ["pattern.png"]);

    let killed = limited("");
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(killed.status.signal(), Some(25), "not killed by SIGXFSZ: {}", stderr(&killed));
    assert_eq!(std::fs::read(&png).unwrap(), OLD);
    let left = common::file_names(&dir);
    assert!(
        left.len() == 2 && left[0].starts_with(".pattern.png.") && left[0].ends_with(".umbra-tmp"),
        "{left:?}"
    );

    common::run_validated(umbra().args(["pattern", "--size", "256x256", "-o"]).arg(&png));
    assert_eq!(common::file_names(&dir), ["pattern.png"], "the killed run's temporary is removed");
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A full device, a read-only output, a missing folder: one clear error, a non-zero exit, the
/// user's file as it was; the read-only and missing-folder cases before any rendering.
#[test]
fn unwritable_outputs_are_errors() {
    let dir = common::fresh_folder("files-unwritable");
    let tiny = ["--size", "16x16", "--spp", "1"];
    // A full disk: full.png links to /dev/full, which takes no byte.
    let full = dir.join("full.png");
    std::os::unix::fs::symlink("/dev/full", &full).unwrap();
    let out = umbra().args(["render", "-o"]).arg(&full).args(tiny).output().unwrap();
    refused(&out, &["full.png: no space left on device"]);
    std::fs::remove_file(&full).unwrap();
    let ro = dir.join("ro.exr");
    common::read_only_file(&ro, OLD);
    let out = umbra().args(["render", "-o"]).arg(&ro).args(tiny).output().unwrap();
    refused(&out, &["ro.exr: a read-only file: umbra does not replace it"]);
    assert!(!stderr(&out).contains("pathtrace:"), "rendered before refusing");
    assert_eq!(std::fs::read(&ro).unwrap(), OLD);
    let out = umbra().args(["render", "-o"]).arg(dir.join("parts/p.exr")).args(tiny).output().unwrap();
    refused(&out, &["parts/p.exr: its folder", "parts: no such file or directory"]);
    // A file where the lightmaps' folder should be: "not a directory", the OS's cause once.
    let out = umbra().args(["bake", "--lightmaps"]).arg(&ro).output().unwrap();
    refused(&out, &["ro.exr: not a directory"]);
    assert_eq!(stderr(&out).matches("not a directory").count(), 1, "{}", stderr(&out));
    assert_eq!(common::file_names(&dir), ["ro.exr"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// Outputs that name an input (the scene, the environment, a probe file, a merge part) are
/// refused naming both, and a bake's output must end in .probes: nothing is overwritten.
#[test]
fn outputs_that_name_an_input_are_refused() {
    let dir = common::fresh_folder("files-inputs");
    let scene = dir.join("scene.glb");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.glb"), &scene).unwrap();
    let sky = dir.join("sky.exr");
    std::fs::copy(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference/sky-128x64.exr"), &sky)
        .unwrap();
    let part = dir.join("part.exr");
    common::run_validated(
        umbra().args(["render", "--size", "8x8", "--spp", "2", "--sample-range", "0..1", "-o"]).arg(&part),
    );
    let link = dir.join("link.png");
    std::os::unix::fs::symlink(&scene, &link).unwrap();
    let before: Vec<Vec<u8>> = [&scene, &sky, &part].iter().map(|p| std::fs::read(p).unwrap()).collect();
    let cases: [(&str, Vec<&std::ffi::OsStr>, &[&str]); 4] = [
        (
            "render over its environment",
            vec![
                "render".as_ref(),
                scene.as_ref(),
                "--env".as_ref(),
                sky.as_ref(),
                "-o".as_ref(),
                sky.as_ref(),
            ],
            &["-o", "names the same file as --env", "sky.exr"],
        ),
        (
            "bake over the scene",
            vec!["bake".as_ref(), scene.as_ref(), "-o".as_ref(), scene.as_ref()],
            &["the file name must end in .probes"],
        ),
        (
            "merge over its part",
            vec!["merge".as_ref(), part.as_ref(), "-o".as_ref(), part.as_ref()],
            &["names the same file as the part", "part.exr"],
        ),
        (
            "render over its scene through a link",
            vec!["render".as_ref(), scene.as_ref(), "-o".as_ref(), link.as_ref()],
            &["-o", "link.png names the same file as the scene", "scene.glb"],
        ),
    ];
    for (what, args, words) in cases {
        let out = umbra().args(&args).output().unwrap();
        refused(&out, words);
        eprintln!("{what}: {}", stderr(&out).trim());
    }
    let after: Vec<Vec<u8>> = [&scene, &sky, &part].iter().map(|p| std::fs::read(p).unwrap()).collect();
    assert!(before == after, "an input changed");
    std::fs::remove_dir_all(&dir).ok();
}

/// Files that are not what merge reads are named in words: a PNG, an empty file, a truncated
/// part.
#[test]
fn merge_names_foreign_and_truncated_files() {
    let dir = common::fresh_folder("files-foreign");
    let part = dir.join("part.exr");
    common::run_validated(
        umbra().args(["render", "--size", "8x8", "--spp", "2", "--sample-range", "0..1", "-o"]).arg(&part),
    );
    let png = dir.join("image.png");
    common::run_validated(umbra().args(["pattern", "--size", "8x8", "-o"]).arg(&png));
    let empty = dir.join("empty.exr");
    std::fs::write(&empty, b"").unwrap();
    let truncated = dir.join("truncated.exr");
    let bytes = std::fs::read(&part).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();
    for (file, words) in [
        (&png, &["image.png: not an OpenEXR file (it is a PNG image)"][..]),
        (&empty, &["empty.exr: not an OpenEXR file (the file is empty)"]),
        (&truncated, &["truncated.exr: truncated"]),
    ] {
        let out = umbra().arg("merge").arg(file).arg("-o").arg(dir.join("m.exr")).output().unwrap();
        refused(&out, words);
    }
    std::fs::remove_dir_all(&dir).ok();
}
