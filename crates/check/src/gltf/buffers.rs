//! Buffers, buffer views and images: the rules beyond what the document layer reports while
//! reading them (it reports URIs, data: URIs, missing files and byte lengths shorter than
//! declared). Images are never decoded; their first bytes are sniffed.

use super::{readable, Walker};
use crate::import::gltf::buffers::{resolve, Resource};
use crate::import::gltf::document::index_of;
use crate::Code;
use serde_json::Value;
use std::io::Read;

impl Walker<'_, '_> {
    /// Rules on buffers that the layer does not need: a zero byteLength, a BIN chunk much
    /// longer than its buffer.
    pub(super) fn buffers(&mut self) {
        for (i, buffer) in self.list("buffers").iter().enumerate() {
            let at = format!("/buffers/{i}");
            let declared = buffer.get("byteLength").and_then(Value::as_u64);
            if declared == Some(0) {
                self.f.error(
                    Code::ValueNotInRange,
                    format!("{at}/byteLength"),
                    "must be at least 1",
                );
            }
            let uses_bin = self.doc.is_glb && i == 0 && buffer.get("uri").is_none();
            if let (true, Some(bin), Some(declared)) = (uses_bin, self.doc.bin_chunk(), declared) {
                if bin.len() as u64 > declared + 3 {
                    self.f.warn(
                        Code::BufferGlbChunkTooBig,
                        at,
                        format!(
                            "the BIN chunk has {} bytes for a {declared}-byte buffer",
                            bin.len()
                        ),
                    );
                }
            }
        }
    }

    /// Lengths, offsets and strides of buffer views against their buffers.
    pub(super) fn buffer_views(&mut self) {
        let views = self.list("bufferViews");
        for (i, view) in views.iter().enumerate() {
            let at = format!("/bufferViews/{i}");
            // As numbers: an integer past 2^53 (1e300) is an integer to the validator too,
            // and too long for any buffer.
            let length = view.get("byteLength").and_then(whole);
            if length == Some(0.0) {
                self.f.error(
                    Code::ValueNotInRange,
                    format!("{at}/byteLength"),
                    "must be at least 1",
                );
            }
            let offset = view.get("byteOffset").and_then(whole).unwrap_or(0.0);
            if let (Some(length), Some(buffer)) = (length, index_of(view, "buffer")) {
                if let Some(declared) = self
                    .list("buffers")
                    .get(buffer)
                    .and_then(|b| b.get("byteLength"))
                    .and_then(whole)
                {
                    if offset + length > declared {
                        self.f.error(
                            Code::BufferViewTooLong,
                            format!("{at}/byteLength"),
                            format!(
                                "bytes {}..{} do not fit buffer {buffer} of {} bytes",
                                readable(offset),
                                readable(offset + length),
                                readable(declared)
                            ),
                        );
                    }
                }
            }
            if let Some(stride) = view.get("byteStride").and_then(Value::as_u64) {
                let sat = format!("{at}/byteStride");
                if !(4..=252).contains(&stride) {
                    self.f.error(
                        Code::ValueNotInRange,
                        sat.clone(),
                        format!("byteStride {stride} is not in 4..252"),
                    );
                } else if stride % 4 != 0 {
                    self.f.error(
                        Code::ValueMultipleOf,
                        sat.clone(),
                        format!("byteStride {stride} is not a multiple of 4"),
                    );
                }
                if length.is_some_and(|l| stride as f64 > l) {
                    self.f.error(
                        Code::BufferViewTooBigByteStride,
                        sat.clone(),
                        "byteStride is larger than the view",
                    );
                }
                if view.get("target").and_then(Value::as_u64) == Some(34963) {
                    self.f.error(
                        Code::BufferViewInvalidByteStride,
                        sat,
                        "an index buffer view cannot have a byteStride",
                    );
                }
            }
        }
    }

    /// Images: where their URIs lead (the layer's path rule) and what their bytes look like.
    pub(super) fn images(&mut self) {
        for (i, image) in self.list("images").iter().enumerate() {
            let at = format!("/images/{i}");
            if let Some(uri) = image.get("uri").and_then(Value::as_str) {
                if let Some(head) = self.image_head(uri, &format!("{at}/uri")) {
                    self.image_bytes(&head, &at);
                }
            }
            let Some(view) = index_of(image, "bufferView") else {
                continue;
            };
            if image.get("mimeType").is_none() {
                self.f.error(
                    Code::UnsatisfiedDependency,
                    format!("{at}/mimeType"),
                    "an image in a buffer view needs a mimeType",
                );
            }
            if self
                .list("bufferViews")
                .get(view)
                .is_some_and(|v| v.get("byteStride").is_some())
            {
                self.f.error(
                    Code::ImageBufferViewWithBytestride,
                    format!("{at}/bufferView"),
                    "an image's buffer view has a byteStride",
                );
            }
            if let Ok(data) = self.doc.view_bytes(view) {
                self.image_bytes(data, &at);
            }
        }
    }

    /// The first bytes of an image named by `uri` (embedded or a file under the path rule).
    fn image_head(&mut self, uri: &str, at: &str) -> Option<Vec<u8>> {
        let resources = self.resources.clone();
        let mut sink = super::Collect {
            f: self.f,
            too_large: false,
        };
        match resolve(uri, at, &resources, &mut sink)? {
            Resource::Data { mime, bytes } => {
                if !matches!(
                    mime.as_str(),
                    "image/png" | "image/jpeg" | "image/webp" | "image/ktx2"
                ) {
                    self.f.error(
                        Code::ImageMimeTypeInvalid,
                        at,
                        format!("image data: URI has media type '{mime}'"),
                    );
                }
                Some(bytes)
            }
            Resource::File(path, decoded) => {
                let mut head = Vec::new();
                let read = std::fs::File::open(&path)
                    .and_then(|file| file.take(64).read_to_end(&mut head));
                if read.is_err() || !path.is_file() {
                    // Images are never read by raycast: a missing one is a warning.
                    self.f.warn(
                        Code::IoError,
                        at,
                        format!("image file '{decoded}' cannot be found"),
                    );
                    return None;
                }
                Some(head)
            }
        }
    }

    /// Sniffs embedded image data (it is never decoded).
    fn image_bytes(&mut self, data: &[u8], at: &str) {
        const PNG: &[u8] = b"\x89PNG\r\n\x1a\n";
        if data.starts_with(PNG) {
            if data.len() < 33 && data.len() < 64 {
                self.f.error(
                    Code::ImageUnexpectedEos,
                    at.to_string(),
                    "the PNG data ends early",
                );
            } else if &data[12..16] != b"IHDR" {
                self.f.error(
                    Code::ImageDataInvalid,
                    at.to_string(),
                    "the PNG data has no IHDR chunk",
                );
            }
        } else if data.starts_with(&[0xFF, 0xD8]) {
            if data.len() < 4 {
                self.f.error(
                    Code::ImageUnexpectedEos,
                    at.to_string(),
                    "the JPEG data ends early",
                );
            }
        } else if data.len() >= 4 && &data[..4] == b"RIFF" || data.starts_with(b"\xABKTX") {
        } else if data.len() >= 8 && data[..8].starts_with(&PNG[..4]) {
            self.f.error(
                Code::ImageDataInvalid,
                at.to_string(),
                "broken PNG signature",
            );
        } else {
            self.f.warn(
                Code::ImageUnrecognizedFormat,
                at.to_string(),
                "not PNG, JPEG, WebP or KTX2 data",
            );
        }
    }
}

/// A non-negative whole number, of any size.
fn whole(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| *x >= 0.0 && x.fract() == 0.0)
}
