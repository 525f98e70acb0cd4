//! Buffers and the URIs that name them: the GLB BIN chunk, `data:` URIs (decoded, with their
//! size checked against the limit before decoding), and external files under the path rule
//! ([`crate::import::paths`]). Network URIs are never fetched.

use super::diagnostics::{Code, Diagnostic, Severity, Sink};
use super::document::{index_of, BufferData, Document};
use crate::import::paths::resolve_inside;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Where external files come from and how much may be read.
#[derive(Debug, Clone)]
pub struct Resources<'a> {
    /// The asset's folder: relative URIs start here.
    pub base: &'a Path,
    /// The folder tree external files must stay in.
    pub root: &'a Path,
    /// Read files outside `root` too.
    pub allow_outside: bool,
    /// Largest buffer (and total of buffers) read, in bytes.
    pub max_bytes: u64,
}

/// What a URI points to.
#[derive(Debug)]
pub enum Resource {
    /// An embedded `data:` URI: its media type and decoded bytes.
    Data {
        /// Media type before any parameters, e.g. `application/octet-stream`.
        mime: String,
        /// The decoded payload.
        bytes: Vec<u8>,
    },
    /// A file inside the root, not yet read: its path and the percent-decoded URI.
    File(PathBuf, String),
}

/// Resolves `uri` (at JSON pointer `at`) without reading files. Problems are reported to
/// `sink`; `None` when there is nothing to read (invalid, refused, or on the network).
pub fn resolve(
    uri: &str,
    at: &str,
    resources: &Resources,
    sink: &mut dyn Sink,
) -> Option<Resource> {
    if let Some(rest) = uri.strip_prefix("data:") {
        return data_uri(rest, at, resources.max_bytes, sink);
    }
    let scheme = uri
        .split_once(':')
        .map(|(s, _)| s)
        .filter(|s| s.len() > 1 && !s.contains('/'));
    if let Some(scheme) = scheme {
        if scheme
            .bytes()
            .all(|c| c.is_ascii_alphanumeric() || c == b'+' || c == b'-' || c == b'.')
            && scheme.as_bytes()[0].is_ascii_alphabetic()
        {
            sink.warn(
                Code::NonRelativeUri,
                at,
                format!("'{uri}' is not a relative path: never fetched (raycast reads no network)"),
            );
            return None;
        }
    }
    if uri.is_empty() || uri.starts_with(':') || uri.contains(['\\', '\0']) {
        sink.error(Code::InvalidUri, at, format!("'{uri}' is not a valid URI"));
        return None;
    }
    let Ok(decoded) = urlencoding::decode(uri) else {
        sink.error(
            Code::InvalidUri,
            at,
            format!("'{uri}' has bad percent-encoding"),
        );
        return None;
    };
    match resolve_inside(
        resources.base,
        resources.root,
        &decoded,
        resources.allow_outside,
    ) {
        Ok(path) => Some(Resource::File(path, decoded.into_owned())),
        Err(why) => {
            sink.error(Code::PathOutsideAsset, at, why.to_string());
            None
        }
    }
}

/// Decodes the part of a `data:` URI after `data:`.
fn data_uri(rest: &str, at: &str, max_bytes: u64, sink: &mut dyn Sink) -> Option<Resource> {
    let Some((header, payload)) = rest.split_once(',') else {
        sink.error(Code::InvalidUri, at, "a data: URI without a comma");
        return None;
    };
    let (mime, is_base64) = match header.strip_suffix(";base64") {
        Some(mime) => (mime, true),
        None => (header, false),
    };
    if mime.contains(';') && !mime.contains('=') {
        sink.error(
            Code::InvalidUri,
            at,
            format!("malformed data: URI header '{header}'"),
        );
        return None;
    }
    let mime = mime.split(';').next().unwrap_or("").to_string();
    let decoded_len = if is_base64 {
        payload.len() / 4 * 3
    } else {
        payload.len()
    };
    if decoded_len as u64 > max_bytes {
        sink.error(
            Code::AssetTooLarge,
            at,
            "the data: URI decodes to more than the --max-memory limit: not decoded",
        );
        return None;
    }
    let bytes = if is_base64 {
        // Percent-encoded base64 is still base64 once decoded.
        let text = urlencoding::decode(payload).unwrap_or_else(|_| payload.into());
        match base64_decode(&text) {
            Some(bytes) => bytes,
            None => {
                sink.error(Code::InvalidUri, at, "the data: URI is not valid base64");
                return None;
            }
        }
    } else {
        urlencoding::decode_binary(payload.as_bytes()).into_owned()
    };
    Some(Resource::Data { mime, bytes })
}

/// Standard or URL-safe base64 (padding optional); `None` when malformed.
pub fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let text = text.trim_end_matches('=');
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in text.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return None;
    }
    Some(out)
}

impl Document {
    /// Reads the buffers: all of them, or only those `needed` marks (the importer reads the
    /// buffers its geometry uses, so a missing texture file cannot stop a render). A buffer
    /// that cannot be read is left empty and reported (as a warning for one that only shading
    /// attributes need, which are then left out); reading its bytes later fails.
    pub fn load_buffers(
        &mut self,
        resources: &Resources,
        needed: Option<&[Need]>,
        sink: &mut dyn Sink,
    ) {
        let count = self.list("buffers").len();
        let mut loaded = Vec::with_capacity(count);
        let mut total = 0u64;
        for i in 0..count {
            let need = needed.map_or(Need::Geometry, |n| n.get(i).copied().unwrap_or_default());
            if sink.stopped() || need == Need::No {
                loaded.push(None);
                continue;
            }
            let mut lenient = AsWarnings(&mut *sink);
            let sink: &mut dyn Sink = match need {
                Need::Shading => &mut lenient,
                _ => &mut *sink,
            };
            let buffer = &self.list("buffers")[i];
            let at = format!("/buffers/{i}");
            let declared = index_of(buffer, "byteLength").unwrap_or(0) as u64;
            total = total.saturating_add(declared);
            if total > resources.max_bytes {
                sink.error(
                    Code::AssetTooLarge,
                    format!("{at}/byteLength"),
                    format!(
                        "buffers add up to more than the limit of {} bytes (--max-memory): not read",
                        resources.max_bytes
                    ),
                );
                loaded.push(None);
                continue;
            }
            let data = self.buffer_data(i, buffer, resources, sink);
            if let Some(data) = &data {
                let actual = match data {
                    BufferData::Bin(range) => range.len(),
                    BufferData::Owned(bytes) => bytes.len(),
                } as u64;
                if actual < declared {
                    sink.error(
                        Code::BufferByteLengthMismatch,
                        format!("{at}/byteLength"),
                        format!("byteLength {declared} but the data has {actual} bytes"),
                    );
                }
            }
            loaded.push(data);
        }
        self.buffers = loaded;
    }

    /// One buffer's data, from the BIN chunk, a `data:` URI or a file.
    fn buffer_data(
        &self,
        i: usize,
        buffer: &Value,
        resources: &Resources,
        sink: &mut dyn Sink,
    ) -> Option<BufferData> {
        let at = format!("/buffers/{i}");
        let Some(uri) = buffer.get("uri") else {
            if self.is_glb && i == 0 {
                if self.bin.is_none() {
                    sink.error(
                        Code::BufferMissingGlbData,
                        at,
                        "the buffer has no uri and the GLB has no BIN chunk",
                    );
                }
                return self.bin.clone().map(BufferData::Bin);
            }
            sink.info(
                Code::BufferNoData,
                at,
                "the buffer has no uri: its data is not available",
            );
            return None;
        };
        let Some(uri) = uri.as_str() else {
            sink.error(Code::TypeMismatch, format!("{at}/uri"), "expected a string");
            return None;
        };
        if self.is_glb && uri.starts_with("data:") {
            sink.warn(
                Code::DataUriGlb,
                format!("{at}/uri"),
                "a data: URI inside a GLB",
            );
        }
        let declared = index_of(buffer, "byteLength").unwrap_or(0) as u64;
        match resolve(uri, &format!("{at}/uri"), resources, sink)? {
            Resource::Data { mime, bytes } => {
                if !matches!(
                    mime.as_str(),
                    "application/octet-stream" | "application/gltf-buffer"
                ) {
                    sink.error(
                        Code::BufferDataUriMimeTypeInvalid,
                        format!("{at}/uri"),
                        format!("buffer data: URI has media type '{mime}'"),
                    );
                }
                if bytes.len() as u64 > declared {
                    sink.error(
                        Code::BufferByteLengthMismatch,
                        format!("{at}/byteLength"),
                        format!(
                            "byteLength {declared} but the data has {} bytes",
                            bytes.len()
                        ),
                    );
                }
                Some(BufferData::Owned(bytes))
            }
            Resource::File(path, decoded) => read_file(
                &path,
                &decoded,
                declared,
                &format!("{at}/uri"),
                resources,
                sink,
            ),
        }
    }

    /// The bytes of buffer `index`, when they were read.
    pub fn buffer(&self, index: usize) -> Option<&[u8]> {
        match self.buffers.get(index)?.as_ref()? {
            BufferData::Bin(range) => self.file.get(range.clone()),
            BufferData::Owned(bytes) => Some(bytes),
        }
    }
}

/// Reads a buffer file after checking its size against the limit.
fn read_file(
    path: &Path,
    decoded: &str,
    declared: u64,
    at: &str,
    resources: &Resources,
    sink: &mut dyn Sink,
) -> Option<BufferData> {
    let len = match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => meta.len(),
        _ => {
            sink.error(
                Code::IoError,
                at,
                format!("the buffer refers to '{decoded}', which does not exist"),
            );
            return None;
        }
    };
    let max = resources.max_bytes;
    if len > max || len > declared.saturating_add(1 << 20) && len > max / 2 {
        sink.error(
            Code::AssetTooLarge,
            at,
            format!("buffer file '{decoded}' has {len} bytes: not read"),
        );
        return None;
    }
    match std::fs::read(path) {
        Ok(bytes) => Some(BufferData::Owned(bytes)),
        Err(e) => {
            sink.error(
                Code::IoError,
                at,
                format!("cannot read buffer file '{decoded}': {e}"),
            );
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64() {
        assert_eq!(base64_decode("aGVsbG8="), Some(b"hello".to_vec()));
        assert_eq!(base64_decode("aGVsbG8"), Some(b"hello".to_vec()));
        assert_eq!(base64_decode("a"), None);
        assert_eq!(base64_decode("a*bc"), None);
    }
}

/// Why the importer reads a buffer ([`super::scene::needed_buffers`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum Need {
    /// Not at all.
    #[default]
    No,
    /// Only for shading attributes: a buffer that cannot be read leaves them out, with a
    /// warning, and never stops a render.
    Shading,
    /// For the geometry drawn.
    Geometry,
}

/// A sink that records errors as warnings (for buffers only shading attributes need).
struct AsWarnings<'a>(&'a mut dyn Sink);

impl Sink for AsWarnings<'_> {
    fn push(&mut self, mut diagnostic: Diagnostic) {
        if diagnostic.severity == Severity::Error {
            diagnostic.severity = Severity::Warning;
            diagnostic
                .message
                .push_str(": the shading attributes it holds are left out");
        }
        self.0.push(diagnostic);
    }
}
