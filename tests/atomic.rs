//! Files written whole or not at all (`umbra::atomic`), by fault injection: a write that fails
//! after N bytes (a full disk), an encoder that fails part-way, a failed sync or rename, a
//! read-only target, a device that is full, a folder that is missing or a file. Each leaves the
//! previous file byte for byte and no temporary beside it.

mod common;

use std::path::Path;
use umbra::atomic::{self, InjectedFault};

const OLD: &[u8] = b"the user's previous file, which must survive every failed write";

fn new_bytes() -> Vec<u8> {
    (0..100_000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8).collect()
}

#[test]
fn a_write_replaces_the_file_and_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = common::fresh_folder("atomic-replace");
    let path = dir.join("out.png");
    std::fs::write(&path, OLD).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o640)).unwrap();
    atomic::write(&path, &new_bytes()).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), new_bytes());
    assert_eq!(std::fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o640);
    assert_eq!(common::file_names(&dir), ["out.png"]);
    // A new file, and a path through a symbolic link: the link's target is replaced, the link kept.
    let fresh = dir.join("fresh.exr");
    atomic::write(&fresh, b"x").unwrap();
    std::os::unix::fs::symlink(&fresh, dir.join("link.exr")).unwrap();
    atomic::write(&dir.join("link.exr"), b"through the link").unwrap();
    assert_eq!(std::fs::read(&fresh).unwrap(), b"through the link");
    assert!(std::fs::symlink_metadata(dir.join("link.exr")).unwrap().file_type().is_symlink());
    std::fs::remove_dir_all(&dir).ok();
}

/// A full disk at every point of the write (after 0, 1, 4,095, 65,536 and all but one of the
/// bytes), a failed sync, a failed rename: an error naming the file, the previous bytes, no
/// temporary. The same faults on a file that did not exist leave no file.
#[test]
fn every_injected_fault_leaves_the_previous_file() {
    let dir = common::fresh_folder("atomic-faults");
    let path = dir.join("render.exr");
    let bytes = new_bytes();
    let faults = [0, 1, 4_095, 65_536, bytes.len() as u64 - 1]
        .map(InjectedFault::WriteAfter)
        .into_iter()
        .chain([InjectedFault::Sync, InjectedFault::Rename]);
    for fault in faults {
        for existing in [true, false] {
            if existing {
                std::fs::write(&path, OLD).unwrap();
            } else {
                let _ = std::fs::remove_file(&path);
            }
            atomic::inject_fault(Some(fault));
            let message = atomic::write(&path, &bytes).unwrap_err().to_string();
            assert!(message.starts_with(&format!("{}: ", path.display())), "{fault:?}: {message}");
            if let InjectedFault::WriteAfter(_) = fault {
                assert!(message.ends_with("no space left on device"), "{fault:?}: {message}");
            }
            if existing {
                assert_eq!(std::fs::read(&path).unwrap(), OLD, "{fault:?}");
                assert_eq!(common::file_names(&dir), ["render.exr"], "{fault:?}");
            } else {
                assert!(common::file_names(&dir).is_empty(), "{fault:?}: {:?}", common::file_names(&dir));
            }
        }
    }
    // Without a fault the same write goes through (the faults are one-shot).
    atomic::write(&path, &bytes).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
    std::fs::remove_dir_all(&dir).ok();
}

/// An encoder that fails after writing part of its output: its error, the previous file.
#[test]
fn a_failing_encoder_leaves_the_previous_file() {
    let dir = common::fresh_folder("atomic-encoder");
    let path = dir.join("chart.svg");
    std::fs::write(&path, OLD).unwrap();
    let err = atomic::write_with(&path, |w| {
        w.write_all(&new_bytes()[..5000])?;
        Err(std::io::Error::other("the encoder gave up"))
    })
    .unwrap_err();
    assert_eq!(err.to_string(), format!("{}: the encoder gave up", path.display()));
    assert_eq!(std::fs::read(&path).unwrap(), OLD);
    assert_eq!(common::file_names(&dir), ["chart.svg"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// A read-only file is refused (even for root, who could write it), before and at the write; a
/// directory, a missing folder and a file where the folder should be are named in words.
#[test]
fn targets_that_cannot_be_replaced_are_named() {
    let dir = common::fresh_folder("atomic-targets");
    let ro = dir.join("ro.exr");
    common::read_only_file(&ro, OLD);
    for err in [atomic::check_output(&ro).unwrap_err(), atomic::write(&ro, b"new").unwrap_err()] {
        assert!(err.to_string().contains("ro.exr: a read-only file: umbra does not replace it"), "{err}");
    }
    assert_eq!(std::fs::read(&ro).unwrap(), OLD);
    let err = atomic::check_output(&dir).unwrap_err().to_string();
    assert!(err.ends_with(": is a directory"), "{err}");
    let err = atomic::check_output(&dir.join("absent/out.png")).unwrap_err().to_string();
    assert!(
        err.contains("absent/out.png: its folder") && err.ends_with("no such file or directory"),
        "{err}"
    );
    let file = dir.join("file");
    std::fs::write(&file, b"").unwrap();
    let err = atomic::check_output(&file.join("out.png")).unwrap_err().to_string();
    assert!(err.ends_with("file is not a directory"), "{err}");
    let err = atomic::create_dir(&file).unwrap_err().to_string();
    assert_eq!(err, format!("{}: not a directory", file.display()));
    // The checks leave nothing behind.
    assert_eq!(common::file_names(&dir), ["file", "ro.exr"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// A file that is not a regular one is written in place, and a full device is an error.
#[test]
fn a_full_device_is_an_error() {
    let err = atomic::write(Path::new("/dev/full"), &new_bytes()).unwrap_err().to_string();
    assert_eq!(err, "/dev/full: no space left on device");
    atomic::write(Path::new("/dev/null"), b"written in place").unwrap();
}

/// A temporary whose process no longer runs is removed by the next write to its target; one
/// of a running process (pid 1), and the temporaries of other targets, are kept.
#[test]
fn leftovers_of_killed_writers_are_removed() {
    let dir = common::fresh_folder("atomic-leftovers");
    let path = dir.join("frame.png");
    let dead = dir.join(".frame.png.4000000000.umbra-tmp");
    let running = dir.join(".frame.png.1.umbra-tmp");
    let other = dir.join(".other.png.4000000000.umbra-tmp");
    for p in [&dead, &running, &other] {
        std::fs::write(p, b"partial").unwrap();
    }
    atomic::write(&path, b"frame").unwrap();
    assert_eq!(
        common::file_names(&dir),
        [".frame.png.1.umbra-tmp", ".other.png.4000000000.umbra-tmp", "frame.png"]
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// An output naming an input, by the same path, another spelling, a symbolic or a hard link, is
/// refused naming both; distinct files pass.
#[test]
fn outputs_that_name_an_input_are_refused() {
    let dir = common::fresh_folder("atomic-distinct");
    let scene = dir.join("scene.glb");
    std::fs::write(&scene, b"glTF").unwrap();
    std::os::unix::fs::symlink(&scene, dir.join("soft.glb")).unwrap();
    std::fs::hard_link(&scene, dir.join("hard.glb")).unwrap();
    let dotted = dir.join(".").join("scene.glb");
    for out in [scene.clone(), dotted, dir.join("soft.glb"), dir.join("hard.glb")] {
        let err = atomic::check_distinct(&[("-o", &out)], &[("the scene", &scene)]).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!(
                "-o {} names the same file as the scene {}",
                out.display(),
                scene.display()
            )),
            "{err}"
        );
    }
    let (a, b) = (dir.join("a.png"), dir.join("b.png"));
    atomic::check_distinct(&[("-o", &a), ("--exr", &b)], &[("the scene", &scene)]).unwrap();
    let err = atomic::check_distinct(&[("-o", &a), ("--png", &dir.join("./a.png"))], &[]).unwrap_err();
    assert!(err.to_string().contains("(another output)"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A target whose name is near the 255-byte limit is written (its temporary carries a shortened
/// name), and a killed writer's temporary of it is still found and removed.
#[test]
fn long_names_are_written() {
    let dir = common::fresh_folder("atomic-long");
    let name = format!("{}.png", "é".repeat(124));
    assert_eq!(name.len(), 252);
    let path = dir.join(&name);
    let stem: String = name.chars().take(100).collect();
    let dead = dir.join(format!(".{stem}.4000000000.umbra-tmp"));
    std::fs::write(&dead, b"partial").unwrap();
    atomic::check_output(&path).unwrap();
    atomic::write(&path, b"long").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"long");
    assert_eq!(common::file_names(&dir), [name]);
    std::fs::remove_dir_all(&dir).ok();
}
