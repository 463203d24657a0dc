//! Writes umbra's generated test scenes into `scenes/`: `cargo run --example gen_scenes`.
//!
//! The generator itself lives in `tests/support/generate.rs`, shared with `tests/scene/`, which
//! regenerates the scenes in memory and fails if a committed file differs.

#[path = "../tests/support/generate.rs"]
mod generate;

fn main() -> anyhow::Result<()> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    umbra::atomic::create_dir(&dir)?;
    for (name, bytes) in generate::all() {
        umbra::atomic::write(&dir.join(name), &bytes)?;
        println!("scenes/{name}: {} bytes", bytes.len());
    }
    Ok(())
}
