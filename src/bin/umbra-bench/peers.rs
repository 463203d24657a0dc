//! The Markdown tables of `peers.py`'s JSON (`umbra-bench peers --table`): umbra's rays against
//! Embree's (`peers.json`) and its path tracer against Mitsuba 3 at equal error (`path.json`).
//! The measurements need Python, Embree and Mitsuba and stay in `peers.py`; their tables are
//! printed here, so that CI (no Python) checks the ones BENCHMARKS.md carries. The output is
//! what `peers.py`'s own printers wrote before they delegated here, character for character.

use super::num;
use serde_json::Value;

/// The table of either kind of file: a path comparison names its renderers, a rays one does not.
pub fn table(doc: &Value) -> String {
    if doc.get("renderers").is_some() {
        path_table(doc)
    } else {
        rays_table(doc)
    }
}

/// A JSON value as Python's f-string writes it: a string without quotes, anything else as JSON.
fn text(v: &Value) -> String {
    v.as_str().map_or_else(|| v.to_string(), str::to_string)
}

/// The last component of a path, as Python's `Path(p).name`.
fn file_name(v: &Value) -> String {
    let path = text(v);
    path.rsplit('/').next().unwrap_or(&path).to_string()
}

/// `x` as Python's `f"{x:.{digits}e}"`: a signed exponent of at least two digits (1.24e-02).
fn python_exp(x: f64, digits: usize) -> String {
    let s = format!("{x:.digits$e}");
    match s.split_once('e').map(|(m, e)| (m, e.parse::<i32>())) {
        Some((mantissa, Ok(e))) => format!("{mantissa}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs()),
        _ => s,
    }
}

/// `peers.py rays`'s table: per scene and ray kind, both renderers' throughput, their ratio and
/// the share of rays where both found the same answer.
fn rays_table(doc: &Value) -> String {
    let mut out = format!(
        "| scene ({}×{}, umbra LP_NUM_THREADS={}, Embree 1 thread) | kind | umbra Mrays/s | Embree Mrays/s \
         | umbra / Embree | same answer |\n|---|---|---:|---:|---:|---:|\n",
        text(&doc["size"][0]),
        text(&doc["size"][1]),
        text(&doc["umbra_threads"]),
    );
    for s in doc["scenes"].as_array().into_iter().flatten() {
        for k in s["kinds"].as_array().into_iter().flatten() {
            out += &format!(
                "| {} | {} | {:.2} | {:.2} | {:.2}× | {:.2} % |\n",
                text(&s["scene"]),
                text(&k["kind"]),
                num(&k["umbra_mrays_per_s"]),
                num(&k["embree_mrays_per_s"]),
                num(&k["ratio"]),
                100.0 * num(&k["same_answer"]),
            );
        }
    }
    out
}

/// `peers.py path`'s table: per sample count, each renderer's time and relative MSE against its
/// own reference, and umbra's time over Mitsuba's at equal error.
fn path_table(doc: &Value) -> String {
    let lit = match &doc["env"] {
        Value::Null | Value::Bool(false) => String::new(),
        Value::String(s) if s.is_empty() => String::new(),
        env => format!(" under {}", file_name(env)),
    };
    // Mitsuba's sampler, where the run names one (runs before it used `independent`).
    let sampler = match &doc["mitsuba_sampler"] {
        Value::String(s) => format!(", Mitsuba's sampler: {s}"),
        _ => String::new(),
    };
    let mut out = format!(
        "| {}{lit} {}×{}, {} bounces{sampler} | umbra ms | umbra rel. MSE | Mitsuba ms | Mitsuba rel. MSE \
         | umbra / Mitsuba time at equal error |\n|---:|---:|---:|---:|---:|---:|\n",
        file_name(&doc["scene"]),
        text(&doc["size"][0]),
        text(&doc["size"][1]),
        text(&doc["max_bounces"]),
    );
    for r in doc["rows"].as_array().into_iter().flatten() {
        out += &format!(
            "| {} spp | {:.1} | {} | {:.1} | {} | {:.2}× |\n",
            text(&r["spp"]),
            num(&r["umbra"]["ms"]),
            python_exp(num(&r["umbra"]["rel_mse"]), 2),
            num(&r["mitsuba"]["ms"]),
            python_exp(num(&r["mitsuba"]["rel_mse"]), 2),
            num(&r["ratio"]),
        );
    }
    out
}
