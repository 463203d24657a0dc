//! Reading a glTF file's bytes: the GLB container, the validated JSON document, the buffers
//! (GLB `BIN` chunk, external files, `data:` URIs) and the encoded bytes of each image.
//!
//! The GLB container is parsed here rather than by the `gltf` crate so that a truncated or
//! malformed file gets a precise message (and cannot reach an arithmetic overflow there).

use super::extension_supported;
use crate::error::{Error, Result};
use gltf::json;
use gltf::json::validation::{Checked, Validate};
use std::borrow::Cow;
use std::path::PathBuf;

/// Where a scene came from: names it in errors and resolves the files it refers to.
pub(super) struct Origin {
    name: String,
    /// The folder external URIs are relative to; `None` for an in-memory scene.
    base: Option<PathBuf>,
}

impl Origin {
    pub fn new(name: &str, base: Option<PathBuf>) -> Self {
        Self { name: name.to_owned(), base }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// An [`Error::Scene`] naming this scene.
    pub fn error(&self, message: impl Into<String>) -> Error {
        Error::Scene { path: PathBuf::from(&self.name), message: message.into() }
    }

    /// Reads the file `uri` (relative, percent-encoded) refers to; `what` names the referrer.
    fn read_external(&self, uri: &str, what: &str) -> Result<Vec<u8>> {
        let Some(base) = &self.base else {
            return Err(self.error(format!(
                "{what} refers to the external file '{uri}', which an in-memory scene cannot read"
            )));
        };
        let path = base.join(percent_decode(uri));
        std::fs::read(&path).map_err(|e| self.error(format!("{what}: cannot read '{}': {e}", path.display())))
    }

    /// The bytes a buffer or image `uri` names: a `data:` URI or a file next to the scene.
    pub fn resolve_uri(&self, uri: &str, what: &str) -> Result<Vec<u8>> {
        match uri.strip_prefix("data:") {
            Some(data) => decode_data_uri(data)
                .ok_or_else(|| self.error(format!("{what} has a malformed base64 data: URI"))),
            None => self.read_external(uri, what),
        }
    }
}

/// A validated glTF document and the bytes of each of its buffers.
pub(super) struct Asset<'a> {
    pub document: gltf::Document,
    pub buffers: Vec<Cow<'a, [u8]>>,
    /// The one warning naming the optional extensions umbra ignores, if the file uses any.
    pub ignored_extensions: Option<String>,
}

/// Parses and validates `bytes` (GLB or glTF JSON) and resolves its buffers.
pub(super) fn open<'a>(origin: &Origin, bytes: &'a [u8]) -> Result<Asset<'a>> {
    let (json_bytes, bin) =
        if bytes.starts_with(b"glTF") { split_glb(origin, bytes)? } else { (bytes, None) };
    let mut root = parse_json(origin, json_bytes)?;
    let ignored_extensions = check_extensions(origin, &root)?;
    use_extension_sources(origin, &mut root)?;
    super::ranges::check(origin, json_bytes)?;
    // Compressed views and primitives are decoded into buffers of their own, and the JSON
    // pointed at them, before it is validated: Draco's accessors have no views until then. The
    // decoders check every index they follow.
    let mut buffers = load_buffers(origin, &root, bin)?;
    if super::meshopt::any(&root) {
        buffers.push(Cow::Owned(super::meshopt::decode(origin, &mut root, &buffers)?));
    }
    #[cfg(feature = "draco")]
    if super::draco::any(&root) {
        buffers.push(Cow::Owned(super::draco::decode(origin, &mut root, &buffers)?));
    }
    let document = validate(origin, root)?;
    check_views(origin, &document, &buffers)?;
    Ok(Asset { document, buffers, ignored_extensions })
}

/// The JSON of `bytes` (GLB or glTF JSON) as a plain value, unvalidated ([`super::info`]).
pub(super) fn json_value(origin: &Origin, bytes: &[u8]) -> Result<gltf::json::Value> {
    let json_bytes = if bytes.starts_with(b"glTF") { split_glb(origin, bytes)?.0 } else { bytes };
    if json_bytes.iter().find(|b| !b.is_ascii_whitespace()) != Some(&b'{') {
        return Err(origin.error("not a glTF file: it is neither GLB (no 'glTF' magic) nor JSON"));
    }
    gltf::json::deserialize::from_slice(json_bytes)
        .map_err(|e| origin.error(format!("invalid glTF JSON: {e}")))
}

/// Splits a GLB file into its JSON chunk and optional BIN chunk.
fn split_glb<'a>(origin: &Origin, bytes: &'a [u8]) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let word = |at: usize| bytes.get(at..at + 4).and_then(|b| b.try_into().ok()).map(u32::from_le_bytes);
    let truncated = |what: String| origin.error(format!("truncated GLB: {what}"));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(truncated(format!("the 12-byte header is cut off at {} bytes", bytes.len())));
    };
    if version != 2 {
        return Err(origin.error(format!("GLB container version {version} is not supported (only 2)")));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(truncated(format!("the header says {length} bytes but the file has {}", bytes.len())));
    }
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < length {
        let (Some(chunk_length), Some(kind)) = (word(at), bytes.get(at + 4..at + 8)) else {
            return Err(truncated(format!("the chunk header at byte {at} is cut off")));
        };
        let start = at + 8;
        let end = start + chunk_length as usize;
        if start > length || end > length {
            let kind = String::from_utf8_lossy(kind).trim_end_matches('\0').to_owned();
            return Err(truncated(format!(
                "the {kind} chunk at byte {at} claims {chunk_length} bytes but only {} remain",
                length.saturating_sub(start)
            )));
        }
        chunks.push((kind, &bytes[start..end]));
        at = end;
    }
    match chunks.as_slice() {
        [(b"JSON", json), rest @ ..] => {
            // Chunks of unknown type must be ignored; the BIN chunk, if any, comes second.
            let bin = rest.first().filter(|(kind, _)| *kind == b"BIN\0").map(|(_, data)| *data);
            Ok((json, bin))
        }
        [(kind, _), ..] => Err(origin.error(format!(
            "the first GLB chunk must be JSON, found '{}'",
            String::from_utf8_lossy(kind).trim_end_matches('\0')
        ))),
        [] => Err(truncated("the file has no JSON chunk".into())),
    }
}

/// Deserialises the JSON document, telling "not glTF at all" from "broken glTF JSON".
fn parse_json(origin: &Origin, bytes: &[u8]) -> Result<json::Root> {
    let looks_like_json = bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
    if !looks_like_json {
        return Err(origin.error("not a glTF file: it is neither GLB (no 'glTF' magic) nor JSON"));
    }
    let root: json::Root =
        json::deserialize::from_slice(bytes).map_err(|e| origin.error(format!("invalid glTF JSON: {e}")))?;
    if !root.asset.version.starts_with("2.") {
        return Err(origin.error(format!(
            "glTF version '{}' is not supported (umbra reads glTF 2.x)",
            root.asset.version
        )));
    }
    Ok(root)
}

/// Rejects files that require an extension umbra lacks; names the optional ones it ignores in
/// one warning (logged, and returned for the scene's warnings): what they add to the look is not
/// rendered.
fn check_extensions(origin: &Origin, root: &json::Root) -> Result<Option<String>> {
    let supported = |name: &&String| extension_supported(name);
    let unsupported: Vec<&str> =
        root.extensions_required.iter().filter(|e| !supported(e)).map(String::as_str).collect();
    if !unsupported.is_empty() {
        return Err(origin.error(format!(
            "requires glTF extension{} umbra does not support: {}{}",
            if unsupported.len() == 1 { "" } else { "s" },
            unsupported.join(", "),
            if unsupported.contains(&"KHR_draco_mesh_compression") {
                " (this umbra was built without its `draco` feature)"
            } else {
                ""
            }
        )));
    }
    let ignored: Vec<&str> =
        root.extensions_used.iter().filter(|e| !supported(e)).map(String::as_str).collect();
    if ignored.is_empty() {
        return Ok(None);
    }
    let warning = format!(
        "{}: ignoring optional glTF extension{} {}: rendered without {}",
        origin.name(),
        if ignored.len() == 1 { "" } else { "s" },
        ignored.join(", "),
        if ignored.len() == 1 { "it" } else { "them" }
    );
    log::warn!("{warning}");
    Ok(Some(warning))
}

/// `KHR_texture_basisu` and `EXT_texture_webp`: a texture's KTX2 or WebP image replaces its
/// `source` (which, if present, is the fallback for readers without the extension, and may be
/// absent when the extension is required); with both, the KTX2. The extension's `source` must
/// name an image.
fn use_extension_sources(origin: &Origin, root: &mut json::Root) -> Result<()> {
    let images = root.images.len();
    for (i, texture) in root.textures.iter_mut().enumerate() {
        let others = texture.extensions.as_ref().map(|e| &e.others);
        let Some((name, extension)) = ["KHR_texture_basisu", "EXT_texture_webp"]
            .into_iter()
            .find_map(|name| Some((name, others?.get(name)?)))
        else {
            continue;
        };
        let source = extension.get("source");
        match source.and_then(json::Value::as_u64).filter(|&s| (s as usize) < images) {
            Some(image) => texture.source = json::Index::new(image as u32),
            None => {
                return Err(origin.error(format!(
                    "texture {i}: the source of its {name} ({}) is not an image index (the file has \
                     {images} images)",
                    source.map_or("absent".to_owned(), |s| s.to_string())
                )))
            }
        }
    }
    Ok(())
}

/// Runs the `gltf` crate's validation (indices in range, required fields, enum values).
fn validate(origin: &Origin, root: json::Root) -> Result<gltf::Document> {
    check_position_indices(origin, &root)?;
    let mut errors = Vec::new();
    root.validate(&root, json::Path::new, &mut |path, error| errors.push(format!("{}: {error}", path())));
    // Required extensions were checked above against umbra's own list.
    errors.retain(|e| !e.starts_with("extensionsRequired"));
    if !errors.is_empty() {
        let shown = errors.len().min(5);
        let more =
            if errors.len() > shown { format!(" (and {} more)", errors.len() - shown) } else { "".into() };
        return Err(origin.error(format!("invalid glTF: {}{more}", errors[..shown].join("; "))));
    }
    Ok(gltf::Document::from_json_without_validation(root))
}

/// The `gltf` crate's validation indexes `accessors[POSITION]` before checking the index, so an
/// out-of-range POSITION would panic there: check it first.
fn check_position_indices(origin: &Origin, root: &json::Root) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&Checked::Valid(gltf::Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(origin.error(format!(
                    "mesh {m} primitive {p}: POSITION refers to accessor {}, but the file has {} accessors",
                    index.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// The bytes of every buffer, each at least as long as its declared `byteLength`.
fn load_buffers<'a>(
    origin: &Origin,
    root: &json::Root,
    mut bin: Option<&'a [u8]>,
) -> Result<Vec<Cow<'a, [u8]>>> {
    let mut buffers = Vec::new();
    for (index, buffer) in root.buffers.iter().enumerate() {
        let what = format!("buffer {index}");
        // EXT_meshopt_compression's fallback for readers without it: umbra decodes the views.
        if super::meshopt::is_fallback(buffer) {
            buffers.push(Cow::Borrowed(&[][..]));
            continue;
        }
        let data: Cow<'a, [u8]> = match &buffer.uri {
            Some(uri) => Cow::Owned(origin.resolve_uri(uri, &what)?),
            // The GLB BIN chunk belongs to the first buffer without a URI.
            None => Cow::Borrowed(bin.take().ok_or_else(|| {
                origin.error(format!("{what} has no uri and there is no (unclaimed) GLB BIN chunk"))
            })?),
        };
        if (data.len() as u64) < buffer.byte_length.0 {
            return Err(origin.error(format!(
                "{what} declares {} bytes but its data has only {}",
                buffer.byte_length.0,
                data.len()
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Every buffer view must lie inside its buffer.
fn check_views(origin: &Origin, document: &gltf::Document, buffers: &[Cow<[u8]>]) -> Result<()> {
    for view in document.views() {
        let buffer = view.buffer().index();
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|end| end > buffer_len(document, buffers, buffer)) {
            return Err(origin.error(format!(
                "buffer view {} (bytes {}..{}) runs past the end of buffer {buffer}, which has {} bytes",
                view.index(),
                view.offset(),
                view.offset() as u128 + view.length() as u128,
                buffer_len(document, buffers, buffer)
            )));
        }
    }
    Ok(())
}

/// A buffer's usable length: its declared `byteLength` (its data may carry padding beyond).
fn buffer_len(document: &gltf::Document, buffers: &[Cow<[u8]>], index: usize) -> usize {
    let declared = document.buffers().nth(index).map_or(0, |b| b.length());
    declared.min(buffers.get(index).map_or(0, |b| b.len()))
}

/// The bytes of a buffer view (already checked to lie inside its buffer).
pub(super) fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Cow<[u8]>]) -> &'b [u8] {
    let data = buffers.get(view.buffer().index()).map_or(&[][..], |b| &b[..]);
    data.get(view.offset()..view.offset() + view.length()).unwrap_or(&[])
}

/// The encoded bytes of image `index`, and a description of where they came from for messages.
pub(super) fn image_bytes<'b>(
    origin: &Origin,
    asset: &'b Asset,
    index: usize,
) -> Result<(Cow<'b, [u8]>, String)> {
    let json = &asset.document.as_json().images[index];
    if let Some(uri) = &json.uri {
        let name = if uri.starts_with("data:") {
            format!("image {index} (data URI)")
        } else {
            format!("image {index} ('{uri}')")
        };
        return Ok((Cow::Owned(origin.resolve_uri(uri, &name)?), name));
    }
    let name = format!("image {index} (embedded)");
    let view = json.buffer_view.and_then(|v| asset.document.views().nth(v.value()));
    match view {
        Some(view) => Ok((Cow::Borrowed(view_bytes(&view, &asset.buffers)), name)),
        None => Err(origin.error(format!("image {index} has neither a uri nor a bufferView"))),
    }
}

/// Decodes the payload of a `data:[<mediatype>][;base64],<data>` URI (after `data:`).
fn decode_data_uri(data: &str) -> Option<Vec<u8>> {
    let (header, payload) = data.split_once(',')?;
    if header.ends_with(";base64") {
        base64_decode(payload)
    } else {
        Some(percent_decode(payload).into_bytes())
    }
}

/// Standard base64 (RFC 4648, padding optional, whitespace ignored); `None` on a bad character.
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let symbols: Vec<u8> =
        text.bytes().filter(|c| !c.is_ascii_whitespace()).take_while(|&c| c != b'=').collect();
    if symbols.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(symbols.len() * 3 / 4);
    for group in symbols.chunks(4) {
        let mut bits = 0u32;
        for (i, &c) in group.iter().enumerate() {
            bits |= value(c)? << (18 - 6 * i);
        }
        let bytes = bits.to_be_bytes();
        out.extend_from_slice(&bytes[1..group.len()]);
    }
    Some(out)
}

/// Decodes `%XX` escapes (URIs in glTF are RFC 3986); malformed escapes are kept as they are.
fn percent_decode(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(byte)) => {
                out.push(byte);
                i += 3;
            }
            (byte, _) => {
                out.push(byte);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_vectors() {
        for (text, bytes) in
            [("", ""), ("Zg==", "f"), ("Zm8=", "fo"), ("Zm9v", "foo"), ("Zm9vYmFy", "foobar")]
        {
            assert_eq!(base64_decode(text).as_deref(), Some(bytes.as_bytes()), "{text}");
        }
        assert_eq!(base64_decode("Zm9vYg"), Some(b"foob".to_vec()), "padding is optional");
        assert_eq!(base64_decode("Zm9v!"), None);
        assert_eq!(base64_decode("Z"), None);
    }

    #[test]
    fn data_uris_and_percent_escapes_decode() {
        assert_eq!(decode_data_uri("application/octet-stream;base64,AAEC"), Some(vec![0, 1, 2]));
        assert_eq!(decode_data_uri("text/plain,a%20b"), Some(b"a b".to_vec()));
        assert_eq!(percent_decode("my%20file%2.bin"), "my file%2.bin");
    }
}
