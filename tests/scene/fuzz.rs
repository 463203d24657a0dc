//! Random mutations of the committed scenes: errors, never panics.

use crate::{committed_scenes, generate, to_glb};
use serde_json::{json, Value};
use umbra::scene::Scene;

/// A small deterministic generator for the fuzz test.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// Random mutations of every committed scene (bytes truncated or overwritten; one JSON number
/// replaced by an awkward value) load or give an error naming the file: never a panic. The
/// outcome counts are printed (and kept in docs/reliability.md).
#[test]
fn mutated_files_give_errors_not_panics() {
    let mut rng = XorShift(0x5eed_cafe);
    let odd_numbers = [
        json!(-1),
        json!(0),
        json!(1),
        json!(3),
        json!(255),
        json!(65536),
        json!(4_294_967_295u64),
        json!(1e30),
        json!(-0.5),
    ];
    // [raw bytes, JSON edits] × [loaded, rejected].
    let mut outcomes = [[0usize; 2]; 2];
    let mut tally = |kind: usize, result: umbra::Result<Scene>| match result {
        Ok(_) => outcomes[kind][0] += 1,
        Err(e) => {
            assert!(e.to_string().contains("fuzz.glb"), "the error does not name the file: {e}");
            outcomes[kind][1] += 1;
        }
    };
    let files = committed_scenes();
    for path in &files {
        let bytes = std::fs::read(path).unwrap();
        let (json, bin) = generate::split_glb(&bytes);
        let mut numbers = Vec::new();
        collect_number_paths(&json, &mut Vec::new(), &mut numbers);
        for round in 0..120 {
            // Raw bytes: truncate, or overwrite a few bytes anywhere.
            let mut raw = bytes.clone();
            if round % 3 == 0 {
                raw.truncate(rng.next() as usize % raw.len());
            } else {
                for _ in 0..4 {
                    let at = rng.next() as usize % raw.len();
                    raw[at] = rng.next() as u8;
                }
            }
            tally(0, Scene::from_glb_bytes("fuzz.glb", &raw));
            // Structure: replace one number of the JSON with an awkward value.
            let mut edited = json.clone();
            let target = &numbers[rng.next() as usize % numbers.len()];
            *pointer_mut(&mut edited, target) = odd_numbers[rng.next() as usize % odd_numbers.len()].clone();
            tally(1, Scene::from_glb_bytes("fuzz.glb", &to_glb(&edited, &bin)));
        }
    }
    let [[raw_ok, raw_err], [json_ok, json_err]] = outcomes;
    eprintln!(
        "{} scenes: byte mutations {raw_ok} loaded, {raw_err} rejected; JSON edits {json_ok} loaded, \
         {json_err} rejected; no panic",
        files.len()
    );
    assert_eq!(raw_ok + raw_err + json_ok + json_err, files.len() * 240);
}

fn collect_number_paths(value: &Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match value {
        Value::Number(_) => out.push(path.clone()),
        Value::Array(items) => items.iter().enumerate().for_each(|(i, v)| {
            path.push(i.to_string());
            collect_number_paths(v, path, out);
            path.pop();
        }),
        Value::Object(map) => map.iter().for_each(|(k, v)| {
            path.push(k.clone());
            collect_number_paths(v, path, out);
            path.pop();
        }),
        _ => {}
    }
}

fn pointer_mut<'v>(value: &'v mut Value, path: &[String]) -> &'v mut Value {
    path.iter().fold(value, |v, key| match v {
        Value::Array(items) => &mut items[key.parse::<usize>().unwrap()],
        other => &mut other[key.as_str()],
    })
}
