//! `KHR_texture_basisu`: KTX2 images holding Basis Universal texels (ETC1S with its BasisLZ
//! codebooks, or UASTC, optionally Zstandard-supercompressed), as gltfpack, glTF-Transform and
//! toktx write them. Transcoded at load by the `basisu` crate (a pure-Rust port of Binomial's
//! transcoder) to RGBA8, the texels a PNG decodes to; from there they are the same texture as a
//! PNG's: linearised or not by their use in the material (base colour, emission and the other
//! colour slots are sRGB whatever the file's transfer function says), mipmapped by umbra.
//!
//! Only level 0 is read: umbra makes its own mip chain (the same box filter for every source
//! format), so a file's levels, which its encoder filtered its own way, are not needed. Array
//! layers, cubemap faces and ETC1S video are refused: glTF's textures are single 2D images.

/// The 12-byte KTX 2.0 file identifier.
pub(super) const MAGIC: &[u8; 12] = b"\xABKTX 20\xBB\r\n\x1A\n";

/// The largest width or height accepted (the texel count then allocated is at most 1 GiB).
const MAX_DIMENSION: u32 = 16384;

/// Transcodes a KTX2 file's level 0 to RGBA8: (width, height, texels row by row from the top).
pub(super) fn decode(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), String> {
    // basisu is young: a corrupt file that trips an assertion in it is this file's error, not a
    // host's crash.
    match std::panic::catch_unwind(|| transcode(bytes)) {
        Ok(result) => result,
        Err(_) => Err("the KTX2 data is corrupt (the transcoder stopped on it)".into()),
    }
}

fn transcode(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), String> {
    use basisu::{DecodeFlags, TargetFormat, Transcoder};
    let file = Transcoder::new(bytes).map_err(|e| match e {
        basisu::Error::InvalidData => {
            "not a Basis Universal KTX2 file (KHR_texture_basisu needs ETC1S or UASTC texels)".to_owned()
        }
        e => format!("the KTX2 container is unreadable: {e:?}"),
    })?;
    let (width, height) = file.base_dimensions();
    if width == 0 || height == 0 || width > MAX_DIMENSION || height > MAX_DIMENSION {
        return Err(format!("its size {width}×{height} is outside 1..={MAX_DIMENSION} texels a side"));
    }
    if file.layer_count() > 1 || file.face_count() > 1 || file.is_video() {
        return Err(format!(
            "it holds {} layers, {} faces{}: a glTF texture is one 2D image",
            file.layer_count(),
            file.face_count(),
            if file.is_video() { " and video frames" } else { "" }
        ));
    }
    let texels = file
        .transcode(0, TargetFormat::Rgba32, DecodeFlags::NONE)
        .map_err(|e| format!("its {:?} texels do not transcode: {e:?}", file.source_format()))?;
    if texels.len() != width as usize * height as usize * 4 {
        return Err(format!("the transcoder returned {} bytes for {width}×{height} texels", texels.len()));
    }
    Ok((width, height, texels))
}
