//! The library's modules depend on each other one way: the Vulkan layer and the CPU-side
//! modules at the bottom, then the BVH and the GPU interface, then the passes, then the
//! orchestrator (`render`), then the embedding API (`embed`). A module may use its own layer and
//! the ones below, never one above (the passes once imported the one-shot renders, which imported
//! every pass). Read from the sources, comments (and so doc links) left out.

use std::collections::BTreeMap;
use std::path::Path;

/// Each top-level module of `src/` (a file or a folder) and its layer.
const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("atomic", 0),
    ("kernels", 0),
    ("vk", 0),
    ("procedural", 0),
    ("output", 0),
    ("color", 0),
    ("environment", 0),
    ("split_sum", 0),
    ("sheen", 0),
    ("scene", 0),
    ("bvh", 1),
    ("gpu", 1),
    ("passes", 2),
    ("render", 3),
    ("bake", 3),
    ("embed", 4),
    ("merge", 4),
];

/// The `crate::<module>` paths in the code of `text` (comments removed).
fn crate_references(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for line in text.lines() {
        let code = match line.find("//") {
            Some(i) => &line[..i],
            None => line,
        };
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            found.push(name);
        }
    }
    found
}

/// `(module, referenced module, file)` for every reference of a module to a higher layer.
fn upward_references(src: &Path) -> Vec<(String, String, String)> {
    let layers: BTreeMap<&str, u32> = LAYERS.iter().copied().collect();
    let mut violations = Vec::new();
    let mut files = Vec::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    for file in files {
        let relative = file.strip_prefix(src).unwrap();
        let top = relative.components().next().unwrap().as_os_str().to_string_lossy();
        let module = top.trim_end_matches(".rs").to_string();
        // The binaries (main.rs and its args.rs, bin/, and cli.rs, which both binaries include)
        // and the crate root are not library modules.
        if ["main", "args", "lib", "bin", "cli"].contains(&module.as_str()) {
            continue;
        }
        let own =
            *layers.get(module.as_str()).unwrap_or_else(|| panic!("src/{module}: give it a layer in LAYERS"));
        let text = std::fs::read_to_string(&file).unwrap();
        for target in crate_references(&text) {
            if let Some(&layer) = layers.get(target.as_str()) {
                if layer > own {
                    violations.push((module.clone(), target, relative.display().to_string()));
                }
            }
        }
    }
    violations.sort();
    violations.dedup();
    violations
}

#[test]
fn modules_depend_downwards_only() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let violations = upward_references(&src);
    assert!(violations.is_empty(), "upward references (module, uses, file): {violations:#?}");
}

/// The check must see an upward reference when there is one.
#[test]
fn an_upward_reference_is_found() {
    let dir = std::env::temp_dir().join(format!("umbra-modules-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("passes")).unwrap();
    std::fs::write(
        dir.join("passes/x.rs"),
        "// crate::embed in a comment is fine\nuse crate::render::hybrid;\n",
    )
    .unwrap();
    std::fs::write(dir.join("render.rs"), "use crate::passes::x;\n").unwrap();
    let violations = upward_references(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(violations, vec![("passes".to_string(), "render".to_string(), "passes/x.rs".to_string())]);
}
