//! Files written whole or not at all: every file umbra writes (images, probe bakes, lightmaps,
//! merged renders, benchmark reports) goes through [`write()`] or [`write_with`].
//!
//! The bytes go to a temporary file beside the target (`.NAME.PID.umbra-tmp`: the same directory,
//! so that the rename stays on one file system), which is flushed, `fsync`ed and renamed over the
//! target; the directory is synced after the rename. Whatever fails (the encoder, a full disk, a
//! file-size limit, the sync, the rename), the temporary is removed and the target is left as it
//! was, byte for byte, and the error names the target. A process killed while it writes leaves
//! the target as it was and its temporary behind: the next write to the same target removes the
//! temporaries of processes that no longer run.
//!
//! A target that exists and is not a regular file (`/dev/stdout`, a pipe, `/dev/full`) cannot be
//! replaced: it is written in place, and its write errors are errors too. A read-only target is
//! refused, as a shell's `>` refuses it, even for root. [`check_output`] runs these checks, and
//! probes the directory with a temporary, before any work, so that a long render does not end in
//! a path it cannot write; [`check_distinct`] refuses outputs that name an input.

use crate::error::{Error, Result};
use std::fs::{File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The end of every temporary's name.
const SUFFIX: &str = ".umbra-tmp";

/// Writes `bytes` to `path` atomically (the module's docs).
pub fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes what `fill` writes to `path` atomically (the module's docs): an error from `fill`
/// leaves the target as it was, like any other.
pub fn write_with(path: &Path, fill: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> Result<()> {
    let io = |e: io::Error| Error::io(path, e);
    match Target::of(path)? {
        Target::InPlace(real) => {
            let mut file = OpenOptions::new().write(true).truncate(true).open(&real).map_err(io)?;
            let mut sink = faults::Sink::new(&mut file);
            fill(&mut sink).and_then(|()| sink.flush()).map_err(io)
        }
        Target::Replace { real, dir, name } => {
            remove_leftovers(&dir, &name);
            let temp = dir.join(temp_name(&name, std::process::id()));
            let result = write_temp(&temp, &real, fill).and_then(|()| {
                faults::check(faults::Fault::Rename)?;
                std::fs::rename(&temp, &real)
            });
            if let Err(e) = result {
                let _ = std::fs::remove_file(&temp);
                return Err(io(e));
            }
            // The rename is durable once the directory is; a file system that cannot sync a
            // directory has still replaced the file whole.
            if let Ok(d) = File::open(&dir) {
                let _ = d.sync_all();
            }
            Ok(())
        }
    }
}

/// Checks, before any work, that `path` can be written: its directory exists and takes a new
/// file (probed with a temporary, removed at once), and it is not a directory or a read-only
/// file. [`write()`] checks the same again when it writes.
pub fn check_output(path: &Path) -> Result<()> {
    match Target::of(path)? {
        Target::Replace { dir, name, .. } => probe(path, &dir, &name),
        Target::InPlace(_) => Ok(()),
    }
}

/// Creates a temporary for `name` in `dir` and removes it: whether `dir` takes new files. An
/// error names `path`.
fn probe(path: &Path, dir: &Path, name: &std::ffi::OsStr) -> Result<()> {
    let probe = dir.join(temp_name(name, std::process::id()));
    OpenOptions::new().write(true).create_new(true).open(&probe).map_err(|e| {
        let why = match e.kind() {
            io::ErrorKind::PermissionDenied | io::ErrorKind::ReadOnlyFilesystem => {
                format!("cannot create a file in {}: {}", dir.display(), io_message(&e))
            }
            _ => io_message(&e),
        };
        Error::Io { path: path.to_path_buf(), error: io::Error::new(e.kind(), why) }
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Refuses an output that names an input or another output (the same file by any path: a
/// symbolic or hard link, `./x` for `x`), naming both: umbra never overwrites what it reads.
/// `outputs` and `inputs` are `(what, path)`, e.g. `("-o", out)`, `("the scene", scene)`.
pub fn check_distinct(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<()> {
    for (i, (what, out)) in outputs.iter().enumerate() {
        let others = outputs[..i].iter().chain(inputs);
        if let Some((other, path)) = others.into_iter().find(|(_, p)| same_file(out, p)) {
            let role = if inputs.iter().any(|(_, p)| p == path) { "an input" } else { "another output" };
            return Err(Error::Invalid(format!(
                "{what} {} names the same file as {other} {} ({role}): umbra will not overwrite \
                 it; choose another output path",
                out.display(),
                path.display()
            )));
        }
    }
    Ok(())
}

/// Creates the output folder `dir` (and its parents) if it is absent, and checks that it takes
/// new files (before any work that would end in writing there); an existing file there is "not a
/// directory".
pub fn create_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::io(dir, io::Error::new(io::ErrorKind::NotADirectory, "not a directory")));
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    probe(dir, dir, std::ffi::OsStr::new("umbra-probe"))
}

/// The OS's message without its error number ("Permission denied", not "Permission denied (os
/// error 13)"), in the words umbra's messages use for the common cases; an error umbra made
/// itself, its own words.
pub(crate) fn io_message(e: &io::Error) -> String {
    if e.raw_os_error().is_none() {
        return e.to_string();
    }
    match e.kind() {
        io::ErrorKind::NotADirectory => "not a directory".into(),
        io::ErrorKind::IsADirectory => "is a directory".into(),
        io::ErrorKind::NotFound => "no such file or directory".into(),
        io::ErrorKind::StorageFull => "no space left on device".into(),
        io::ErrorKind::FileTooLarge => "file too large (over the process's file-size limit)".into(),
        _ => {
            let s = e.to_string();
            match s.find(" (os error ") {
                Some(i) => s[..i].to_string(),
                None => s,
            }
        }
    }
}

/// Where and how a path is written.
enum Target {
    /// An existing file that is not a regular one: written in place.
    InPlace(PathBuf),
    /// A regular file, existing or not (symbolic links followed): replaced by a rename in `dir`
    /// (its folder, `.` for a bare name).
    Replace { real: PathBuf, dir: PathBuf, name: std::ffi::OsString },
}

impl Target {
    fn of(path: &Path) -> Result<Self> {
        let err = |kind, message: &str| Err(Error::io(path, io::Error::new(kind, message.to_string())));
        let real = match std::fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
                Ok(real) => real,
                Err(_) => return err(io::ErrorKind::NotFound, "a symbolic link to nothing"),
            },
            _ => path.to_path_buf(),
        };
        match std::fs::metadata(&real) {
            Ok(m) if m.is_dir() => return err(io::ErrorKind::IsADirectory, "is a directory"),
            Ok(m) if !m.is_file() => return Ok(Target::InPlace(real)),
            Ok(m) if m.permissions().readonly() => {
                return err(
                    io::ErrorKind::PermissionDenied,
                    "a read-only file: umbra does not replace it (make it writable, or choose another path)",
                )
            }
            _ => {}
        }
        let Some(name) = real.file_name().map(|n| n.to_os_string()) else {
            return err(io::ErrorKind::InvalidInput, "names no file");
        };
        let dir = folder_of(&real).to_path_buf();
        match std::fs::metadata(&dir) {
            Ok(m) if m.is_dir() => Ok(Target::Replace { real, dir, name }),
            Ok(_) => Err(Error::io(
                path,
                io::Error::new(io::ErrorKind::NotADirectory, format!("{} is not a directory", dir.display())),
            )),
            Err(e) => Err(Error::io(
                path,
                io::Error::new(e.kind(), format!("its folder {}: {}", dir.display(), io_message(&e))),
            )),
        }
    }
}

/// The folder of `path`: its parent, `.` for a bare name.
fn folder_of(path: &Path) -> &Path {
    path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// `.NAME.PID.umbra-tmp`.
fn temp_name(name: &std::ffi::OsStr, pid: u32) -> std::ffi::OsString {
    let mut temp = std::ffi::OsString::from(".");
    temp.push(temp_stem(name));
    temp.push(format!(".{pid}{SUFFIX}"));
    temp
}

/// The part of a target's name its temporaries carry: the name, cut to 200 bytes so that a
/// temporary of a long name stays within the 255 bytes a file name may have.
fn temp_stem(name: &std::ffi::OsStr) -> String {
    let mut stem = name.to_string_lossy().into_owned();
    let mut end = stem.len().min(200);
    while !stem.is_char_boundary(end) {
        end -= 1;
    }
    stem.truncate(end);
    stem
}

/// Writes the temporary `temp` for `real`: created new, with `real`'s permissions if it exists,
/// filled, flushed and synced. The caller removes it on error.
fn write_temp(
    temp: &Path,
    real: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> io::Result<()> {
    // A temporary of this process's number is a leftover of an earlier process of that number.
    let _ = std::fs::remove_file(temp);
    let mut file = OpenOptions::new().write(true).create_new(true).open(temp)?;
    if let Ok(m) = std::fs::metadata(real) {
        file.set_permissions(m.permissions())?;
    }
    let mut sink = faults::Sink::new(&mut file);
    fill(&mut sink)?;
    sink.flush()?;
    faults::check(faults::Fault::Sync)?;
    file.sync_all()
}

/// Removes the temporaries `.NAME.PID.umbra-tmp` of `name` in `dir` whose process no longer
/// runs (on Linux, read from /proc; elsewhere those a day old).
fn remove_leftovers(dir: &Path, name: &std::ffi::OsStr) {
    let name = temp_stem(name);
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let prefix = format!(".{name}.");
    let proc = Path::new("/proc/self").exists();
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(pid) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix)?.strip_suffix(SUFFIX))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let gone = if proc {
            pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists()
        } else {
            entry
                .metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|age| age.as_secs() > 86_400)
        };
        if gone {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// Whether `a` and `b` name the same file: for existing files the same device and inode (on
/// Unix; elsewhere the same canonical path), otherwise the same canonical folder and name.
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        use std::os::unix::fs::MetadataExt;
        return (x.dev(), x.ino()) == (y.dev(), y.ino());
    }
    let identity = |p: &Path| -> Option<PathBuf> {
        std::fs::canonicalize(p).ok().or_else(|| {
            let dir = folder_of(p);
            Some(std::fs::canonicalize(dir).ok()?.join(p.file_name()?))
        })
    };
    matches!((identity(a), identity(b)), (Some(x), Some(y)) if x == y)
}

/// Fault injection for umbra's own tests (the `testing` feature): a write that fails after a
/// number of bytes, a failed sync or rename; absent from other builds.
mod faults {
    use std::io::{self, Write};

    /// Where the next write on this thread fails.
    #[cfg_attr(not(feature = "testing"), allow(dead_code))]
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum Fault {
        /// The file takes this many bytes, then every write fails (a full disk).
        WriteAfter(u64),
        /// The temporary's sync fails.
        Sync,
        /// The rename over the target fails.
        Rename,
    }

    #[cfg(feature = "testing")]
    thread_local! {
        pub static INJECTED: std::cell::Cell<Option<Fault>> = const { std::cell::Cell::new(None) };
    }

    /// Fails with the injected fault if it is `at` (and clears it).
    pub fn check(at: Fault) -> io::Result<()> {
        #[cfg(feature = "testing")]
        if INJECTED.with(|f| f.get()) == Some(at) {
            INJECTED.with(|f| f.set(None));
            return Err(io::Error::other(format!("injected fault: {at:?}")));
        }
        let _ = at;
        Ok(())
    }

    /// A file's writer that fails as a full disk after the injected byte count.
    pub struct Sink<'a> {
        file: &'a mut std::fs::File,
        room: Option<u64>,
    }

    impl<'a> Sink<'a> {
        pub fn new(file: &'a mut std::fs::File) -> Self {
            #[cfg(feature = "testing")]
            let room = match INJECTED.with(|f| f.get()) {
                Some(Fault::WriteAfter(n)) => {
                    INJECTED.with(|f| f.set(None));
                    Some(n)
                }
                _ => None,
            };
            #[cfg(not(feature = "testing"))]
            let room = None;
            Self { file, room }
        }
    }

    impl Write for Sink<'_> {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            let take = match self.room {
                Some(0) => return Err(io::Error::new(io::ErrorKind::StorageFull, "no space left on device")),
                Some(room) => buf.len().min(room as usize),
                None => buf.len(),
            };
            let n = self.file.write(&buf[..take])?;
            if let Some(room) = &mut self.room {
                *room -= n as u64;
            }
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            self.file.flush()
        }
    }
}

/// Fault injection for umbra's own tests: the next [`write_with`] on this thread fails as
/// `fault` says.
#[cfg(feature = "testing")]
#[doc(hidden)]
pub fn inject_fault(fault: Option<InjectedFault>) {
    faults::INJECTED.with(|f| f.set(fault));
}

/// The faults [`inject_fault`] injects.
#[cfg(feature = "testing")]
#[doc(hidden)]
pub use faults::Fault as InjectedFault;
