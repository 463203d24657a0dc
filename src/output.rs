//! Writing frames: linear HDR EXR with named layers (AOVs) and display-referred sRGB PNG.

use crate::error::{Error, Result};
use std::path::Path;

/// One layer of an EXR: interleaved `f32` samples, `channels.len()` per pixel.
#[derive(Debug, Clone, Copy)]
pub struct Layer<'a> {
    /// Layer name; `""` is the main colour layer (`R`, `G`, `B`, `A` channels, as every EXR
    /// reader expects), others are written as `name.channel` (e.g. `albedo.R`).
    pub name: &'a str,
    /// Channel names, e.g. `["R", "G", "B"]` or `["Z"]`.
    pub channels: &'a [&'a str],
    /// `width * height * channels.len()` samples, row-major, top row first.
    pub data: &'a [f32],
}

/// Writes a single-part EXR with every layer's channels (zip-compressed, f32).
pub fn write_exr(path: &Path, width: usize, height: usize, layers: &[Layer<'_>]) -> Result<()> {
    write_exr_with(path, width, height, layers, &[])
}

/// [`write_exr`] with text attributes in the header (`(name, value)`, Latin-1 text).
pub fn write_exr_with(
    path: &Path,
    width: usize,
    height: usize,
    layers: &[Layer<'_>],
    attributes: &[(&str, String)],
) -> Result<()> {
    use exr::prelude::*;
    let image_error = |message: String| crate::Error::Image { path: path.to_path_buf(), message };
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes {
        let text = |s: &str| {
            Text::new_or_none(s)
                .ok_or_else(|| image_error(format!("attribute {name}: '{s}' is not Latin-1 text")))
        };
        layer_attributes.other.insert(text(name)?, exr::meta::attribute::AttributeValue::Text(text(value)?));
    }
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for layer in layers {
        let n = layer.channels.len();
        if n == 0 || layer.data.len() != width * height * n {
            return Err(image_error(format!(
                "layer '{}' has {} samples, expected {}x{}x{}",
                layer.name,
                layer.data.len(),
                width,
                height,
                n
            )));
        }
        for (c, channel) in layer.channels.iter().enumerate() {
            let name =
                if layer.name.is_empty() { channel.to_string() } else { format!("{}.{channel}", layer.name) };
            let samples: Vec<f32> = layer.data.iter().skip(c).step_by(n).copied().collect();
            channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(samples)));
        }
    }
    let layer = exr::image::Layer::new(
        (width, height),
        layer_attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    // Encoded in memory, then written atomically: the exr crate's own file writer deletes the
    // target when a write fails.
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut bytes).map_err(|e| image_error(e.to_string()))?;
    crate::atomic::write(path, bytes.get_ref())
}

/// One EXR channel: its full name (e.g. `albedo.R`) and its samples, row-major.
pub type Channel = (String, Vec<f32>);

/// Reads every channel of a single-part EXR as `(width, height, channels)`, for tests and tools.
pub fn read_exr_channels(path: &Path) -> Result<(usize, usize, Vec<Channel>)> {
    let image = read_exr(path)?;
    Ok((image.width, image.height, image.channels))
}

/// A single-part EXR as read: its size, every channel, its text attributes.
#[derive(Debug, Clone)]
pub struct ExrImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Every channel, by full name.
    pub channels: Vec<Channel>,
    /// The header's text attributes other than the standard ones, `(name, value)`.
    pub attributes: Vec<(String, String)>,
}

/// Reads a single-part EXR: every channel as `f32`, and its text attributes.
pub fn read_exr(path: &Path) -> Result<ExrImage> {
    read_exr_bytes(path, &std::fs::read(path).map_err(|e| Error::io(path, e))?)
}

/// [`read_exr`] of a file's bytes, already read; `path` names it in errors.
pub fn read_exr_bytes(path: &Path, bytes: &[u8]) -> Result<ExrImage> {
    use exr::meta::attribute::AttributeValue;
    use exr::prelude::*;
    let image_error = |message: String| crate::Error::Image { path: path.to_path_buf(), message };
    if !bytes.starts_with(&EXR_MAGIC) {
        return Err(image_error(format!("not an OpenEXR file{}", file_kind(bytes))));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| {
            image_error(match e {
                // The exr crate's word for an unexpected end of the file.
                exr::error::Error::Invalid(why) if why == "reference to missing bytes" => {
                    "truncated: the file ends before its image data".into()
                }
                e => format!("damaged OpenEXR file: {e}"),
            })
        })?;
    let size = image.layer_data.size;
    let channels = image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    let attributes = image
        .layer_data
        .attributes
        .other
        .iter()
        .chain(&image.attributes.other)
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok(ExrImage { width: size.0, height: size.1, channels, attributes })
}

/// The first four bytes of every OpenEXR file.
pub const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// " (a PNG image)" and the like for a file that is not what was expected, from its first bytes.
fn file_kind(bytes: &[u8]) -> &'static str {
    match bytes {
        [] => " (the file is empty)",
        [0x89, b'P', b'N', b'G', ..] => " (it is a PNG image)",
        [0xff, 0xd8, 0xff, ..] => " (it is a JPEG image)",
        [b'#', b'?', ..] => " (it is a Radiance HDR image)",
        [b'g', b'l', b'T', b'F', ..] => " (it is a glTF binary)",
        [b'U', b'M', b'B', b'R', b'A', b'P', b'R', b'B', ..] => " (it is an umbra probe bake)",
        _ => "",
    }
}

/// Writes 8-bit sRGB RGBA as PNG, atomically ([`crate::atomic`]).
pub fn write_png(path: &Path, width: u32, height: u32, srgb8: &[u8]) -> Result<()> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(srgb8, width, height, image::ExtendedColorType::Rgba8)
        .map_err(|e| Error::Image { path: path.to_path_buf(), message: e.to_string() })?;
    crate::atomic::write(path, &bytes)
}
