//! Box-filters an environment map down by an integer factor (energy preserving) and writes an
//! EXR: how tests/reference/sky-128x64.exr was made from a CC0 Poly Haven map.
//!
//! cargo run --release --example downsample_env -- IN.exr FACTOR OUT.exr

use umbra::environment::EnvironmentMap;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, factor, output] = args.as_slice() else {
        anyhow::bail!("usage: downsample_env IN.exr FACTOR OUT.exr");
    };
    let map = EnvironmentMap::load(input.as_ref())?;
    let f: usize = factor.parse()?;
    anyhow::ensure!(f > 0 && map.width % f == 0 && map.height % f == 0, "factor must divide the size");
    let (w, h) = (map.width / f, map.height / f);
    let mut rgb = vec![0.0f32; w * h * 3];
    for y in 0..map.height {
        for x in 0..map.width {
            let t = map.texels[y * map.width + x];
            let o = ((y / f) * w + x / f) * 3;
            for c in 0..3 {
                rgb[o + c] += t[c] / (f * f) as f32;
            }
        }
    }
    let layer = umbra::output::Layer { name: "", channels: &["R", "G", "B"], data: &rgb };
    umbra::output::write_exr(output.as_ref(), w, h, &[layer])?;
    println!("{w}x{h}, peak {}", rgb.iter().fold(0.0f32, |a, &b| a.max(b)));
    Ok(())
}
