//! Argument parsers and `main` shared by the `umbra` and `umbra-bench` binaries: a module of each
//! binary (`umbra-bench` includes this file by path), not of the library, which needs neither
//! `anyhow` nor `env_logger`.

/// Parses `WIDTHxHEIGHT` (both positive, at most 16384).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT"))?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("'{s}': {e}"));
    let (w, h) = (parse(w)?, parse(h)?);
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be positive"));
    }
    if w > 16384 || h > 16384 {
        return Err(format!("'{s}': at most 16384 pixels on a side"));
    }
    Ok((w, h))
}

/// An output path whose extension is one of `extensions` (any case), so that a wrong one is
/// refused before a long render rather than after it.
fn parse_output(s: &str, extensions: &[&str], what: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::PathBuf::from(s);
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if extensions.iter().any(|x| e.eq_ignore_ascii_case(x)) => Ok(path),
        _ => Err(format!("'{s}': the file name must end in {what}")),
    }
}

/// A PNG output path (`.png`).
pub fn parse_png(s: &str) -> Result<std::path::PathBuf, String> {
    parse_output(s, &["png"], ".png")
}

/// A PNG or EXR output path (`.png`, or `.exr` for the EXR alone).
pub fn parse_png_or_exr(s: &str) -> Result<std::path::PathBuf, String> {
    parse_output(s, &["png", "exr"], ".png or .exr")
}

/// An EXR output path (`.exr`).
pub fn parse_exr(s: &str) -> Result<std::path::PathBuf, String> {
    parse_output(s, &["exr"], ".exr")
}

/// A probe bake output path (`.probes`): never a scene's or an image's name.
#[allow(dead_code)] // one binary uses it
pub fn parse_probes_file(s: &str) -> Result<std::path::PathBuf, String> {
    parse_output(s, &["probes"], ".probes")
}

/// Refuses, before any work, outputs that name an input or another output, or that cannot be
/// written (a missing folder, a directory, a read-only file): `umbra::atomic`'s checks over the
/// flags given (`(flag, path)`; `None` where a flag is absent).
#[allow(dead_code)] // one binary uses it
pub fn check_outputs(
    outputs: &[(&str, Option<&std::path::Path>)],
    inputs: &[(&str, Option<&std::path::Path>)],
) -> umbra::Result<()> {
    fn given<'a>(v: &[(&'a str, Option<&'a std::path::Path>)]) -> Vec<(&'a str, &'a std::path::Path)> {
        v.iter().filter_map(|&(what, path)| Some((what, path?))).collect()
    }
    let outputs = given(outputs);
    umbra::atomic::check_distinct(&outputs, &given(inputs))?;
    outputs.iter().try_for_each(|(_, path)| umbra::atomic::check_output(path))
}

/// The ids of the arguments given on the command line (not defaults) of a subcommand's matches.
#[allow(dead_code)] // one binary uses it
pub fn given_flags(matches: &clap::ArgMatches) -> Vec<String> {
    matches
        .ids()
        .filter(|id| matches.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
        .map(|id| id.to_string())
        .collect()
}

/// The ids of the arguments a group of flags (`#[derive(clap::Args)]`) declares.
#[allow(dead_code)] // one binary uses it
pub fn arg_ids<T: clap::Args>() -> Vec<String> {
    T::augment_args(clap::Command::new("group")).get_arguments().map(|a| a.get_id().to_string()).collect()
}

/// A group of flags: their argument ids, whether they apply to the command as given, and what
/// they need when they do not.
#[allow(dead_code)] // one binary uses it
pub type FlagGroup = (Vec<String>, bool, &'static str);

/// Refuses the flags in `given` (those on the command line: a default never blocks) whose group
/// does not apply, each with what it needs: a flag that cannot apply is refused, never ignored.
#[allow(dead_code)] // one binary uses it
pub fn refuse_inapplicable(given: &[String], groups: &[FlagGroup]) -> anyhow::Result<()> {
    let refused: Vec<String> = given
        .iter()
        .filter_map(|id| {
            let (_, applies, needs) = groups.iter().find(|(ids, ..)| ids.contains(id))?;
            (!applies).then(|| format!("{} applies to {needs}", flag(id)))
        })
        .collect();
    if !refused.is_empty() {
        anyhow::bail!("{}: such a flag would be ignored", refused.join("; "));
    }
    Ok(())
}

/// The flag of an argument id: `--shadow-map-size` for `shadow_map_size`.
#[allow(dead_code)] // one binary uses it
pub fn flag(id: &str) -> String {
    format!("--{}", id.replace('_', "-"))
}

/// What a render writes: the PNG `output` names, or none when it names an EXR; the EXR of
/// `exr`, or else of `output` when that names one.
pub fn outputs(
    output: &std::path::Path,
    exr: Option<&std::path::PathBuf>,
) -> (Option<std::path::PathBuf>, Option<std::path::PathBuf>) {
    let is_exr = output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let png = (!is_exr).then(|| output.to_path_buf());
    (png, exr.cloned().or_else(|| is_exr.then(|| output.to_path_buf())))
}

/// Three comma-separated numbers, if `s` holds three and `ok` accepts them.
fn parse_three(s: &str, ok: impl Fn(&[f32; 3]) -> bool) -> Option<Result<[f32; 3], String>> {
    let v: Result<Vec<f32>, _> = s.split(',').map(|c| c.trim().parse::<f32>()).collect();
    match v {
        Err(e) => Some(Err(format!("'{s}': {e}"))),
        Ok(v) => <[f32; 3]>::try_from(v.as_slice()).ok().filter(|v| ok(v)).map(Ok),
    }
}

/// Parses `R,G,B` (three finite, non-negative numbers).
pub fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    parse_three(s, |v| v.iter().all(|c| c.is_finite() && *c >= 0.0))
        .unwrap_or_else(|| Err(format!("'{s}' is not three non-negative numbers R,G,B")))
}

/// Parses `X,Y,Z`: a direction (three finite numbers, not all zero).
#[allow(dead_code)] // one binary uses it
pub fn parse_direction(s: &str) -> Result<[f32; 3], String> {
    parse_three(s, |v| v.iter().all(|c| c.is_finite()) && v.iter().any(|c| *c != 0.0)).unwrap_or_else(|| {
        Err(format!("'{s}' is not a direction X,Y,Z (three finite numbers, not all zero)"))
    })
}

/// Parses a finite number (NaN and the infinities refused).
pub fn parse_finite(s: &str) -> Result<f32, String> {
    let x: f32 = s.trim().parse().map_err(|e| format!("'{s}': {e}"))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("'{s}' is not a finite number"))
    }
}

/// Parses a finite number at least 0.
pub fn parse_non_negative(s: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        x if x >= 0.0 => Ok(x),
        _ => Err(format!("'{s}' is negative: must be at least 0")),
    }
}

/// Parses `A..B`: samples A (inclusive) to B (exclusive) of the sequence, A < B.
#[allow(dead_code)] // one binary uses it
pub fn parse_sample_range(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = s.split_once("..").ok_or_else(|| format!("'{s}' is not a sample range A..B"))?;
    let parse = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("'{s}': {e}"));
    let (a, b) = (parse(a)?, parse(b)?);
    if a >= b {
        return Err(format!("'{s}': the range is empty (A..B needs A < B)"));
    }
    Ok((a, b))
}

/// Parses `X,Y,W,H`: a tile's left column, top row, width and height in pixels (W, H > 0).
#[allow(dead_code)] // one binary uses it
pub fn parse_tile(s: &str) -> Result<[u32; 4], String> {
    let v: Vec<u32> = s
        .split(',')
        .map(|v| v.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("'{s}' is not a tile X,Y,W,H: {e}"))?;
    match v[..] {
        [x, y, w, h] if w > 0 && h > 0 => Ok([x, y, w, h]),
        [_, _, _, _] => Err(format!("'{s}': a tile's width and height must be positive")),
        _ => Err(format!("'{s}' is not a tile X,Y,W,H (four numbers)")),
    }
}

/// Parses a number in [0, 1].
#[allow(dead_code)] // one binary uses it
pub fn parse_unit(s: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        x if (0.0..=1.0).contains(&x) => Ok(x),
        _ => Err(format!("'{s}' must lie in [0, 1]")),
    }
}

/// Parses a finite number greater than 0.
pub fn parse_positive(s: &str) -> Result<f32, String> {
    match parse_finite(s)? {
        x if x > 0.0 => Ok(x),
        _ => Err(format!("'{s}' must be greater than 0")),
    }
}

/// A binary's `main`: logging at `info` (`RUST_LOG` overrides), then `run`; an error is printed
/// once with its causes and the process exits with status 1 (never a panic).
pub fn main(run: impl FnOnce() -> anyhow::Result<()>) {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("info"))
        .format_timestamp(None)
        .init();
    if let Err(e) = run() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
