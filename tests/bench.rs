//! `umbra-bench` never rots: its quick runs finish, validate, and write output that parses.
//! (Timings are recorded in BENCHMARKS.md, never asserted.)

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
    std::fs::remove_dir_all(&dir).ok();
}
