//! The glTF document: the container (plain JSON or GLB chunks), the JSON parsed once as
//! `serde_json::Value` (full-precision numbers, and no part of the file refused for a shape
//! the ray caster never reads), and the buffers once [`Document::load_buffers`] has run.
//!
//! Typed reads of the parts a ray caster uses live beside this file: [`super::accessor`]
//! (bufferViews and accessors), [`super::mesh`] (primitives), [`super::node`] (transforms,
//! cameras, scenes). Textures, images, samplers, materials, animations and skins are never
//! interpreted here: only `raycast check` looks at them.

use super::diagnostics::{Code, Severity, Sink};
use serde_json::{Map, Value};
use std::collections::HashMap;
use std::io::Read;
use std::ops::Range;
use std::path::Path;
use std::sync::atomic::AtomicU64;

const JSON_CHUNK: u32 = 0x4E4F_534A;
const BIN_CHUNK: u32 = 0x004E_4942;

/// Where one buffer's bytes are.
#[derive(Debug)]
pub(super) enum BufferData {
    /// The GLB's BIN chunk, as a range of the file.
    Bin(Range<usize>),
    /// Read from a file or decoded from a `data:` URI.
    Owned(Vec<u8>),
}

/// A parsed glTF document and, once loaded, its buffers.
#[derive(Debug)]
pub struct Document {
    /// The whole file (a GLB's BIN chunk is read from here, not copied).
    pub(super) file: Vec<u8>,
    /// The JSON text's place in `file`.
    json_text: Range<usize>,
    /// The JSON root object.
    pub(super) json: Map<String, Value>,
    /// True for a GLB container.
    pub is_glb: bool,
    /// The BIN chunk's place in `file`, for a GLB that has one.
    pub(super) bin: Option<Range<usize>>,
    /// Each buffer's data, `None` where it could not (or need not) be read.
    pub(super) buffers: Vec<Option<BufferData>>,
    /// Buffer views whose bytes a decoder produced (EXT_meshopt_compression), by index.
    pub(super) decoded_views: HashMap<usize, Vec<u8>>,
    /// Bytes that accessors without a buffer view may still take ([`Document::limit_unbacked`]).
    pub(super) unbacked_budget: AtomicU64,
}

impl Document {
    /// Parses a `.gltf` or `.glb` file's bytes (`is_glb` from its extension, or its magic).
    /// GLB structure problems and invalid JSON are reported to `sink`; `None` when there is
    /// no JSON object to read.
    pub fn parse(file: Vec<u8>, is_glb: bool, sink: &mut dyn Sink) -> Option<Document> {
        let is_glb = is_glb || file.starts_with(b"glTF");
        let (json_text, bin) = if is_glb {
            glb_chunks(&file, sink)?
        } else {
            (0..file.len(), None)
        };
        let value: Value = match serde_json::from_slice(&file[json_text.clone()]) {
            Ok(value) => value,
            Err(e) => {
                let code = if e.to_string().contains("number out of range") {
                    Code::ValueNotInRange
                } else {
                    Code::InvalidJson
                };
                sink.error(code, "", format!("not valid glTF JSON: {e}"));
                return None;
            }
        };
        let Value::Object(json) = value else {
            sink.error(Code::TypeMismatch, "", "the JSON root is not an object");
            return None;
        };
        Some(Document {
            file,
            json_text,
            json,
            is_glb,
            bin,
            buffers: Vec::new(),
            decoded_views: HashMap::new(),
            unbacked_budget: AtomicU64::new(u64::MAX),
        })
    }

    /// The JSON root object.
    pub fn root(&self) -> &Map<String, Value> {
        &self.json
    }

    /// The JSON text, as in the file.
    pub fn json_text(&self) -> &[u8] {
        &self.file[self.json_text.clone()]
    }

    /// A top-level array (`"meshes"`, `"nodes"`, ...), empty when absent or not an array.
    pub fn list(&self, key: &str) -> &[Value] {
        array_of(self.json.get(key))
    }

    /// Item `index` of a top-level array.
    pub fn item(&self, key: &str, index: usize) -> Option<&Value> {
        self.list(key).get(index)
    }

    /// The GLB's BIN chunk, if the file is a GLB with one.
    pub fn bin_chunk(&self) -> Option<&[u8]> {
        self.bin.clone().map(|r| &self.file[r])
    }

    /// Names in `extensionsRequired` (or `extensionsUsed`), as strings.
    pub fn extension_names(&self, key: &str) -> impl Iterator<Item = &str> {
        self.list(key).iter().filter_map(Value::as_str)
    }
}

/// The items of an optional JSON array (empty when absent or not an array).
pub fn array_of(value: Option<&Value>) -> &[Value] {
    value.and_then(Value::as_array).map_or(&[], Vec::as_slice)
}

/// `v[key]` as an array (empty when absent or not an array).
pub fn array<'a>(v: &'a Value, key: &str) -> &'a [Value] {
    array_of(v.get(key))
}

/// A non-negative integer, also when written with a fraction of zero (`1.0`, `1e0`): JSON
/// does not tell them apart, and neither does the specification.
pub fn as_index(v: &Value) -> Option<usize> {
    if let Some(n) = v.as_u64() {
        return usize::try_from(n).ok();
    }
    let x = v.as_f64()?;
    (x >= 0.0 && x.fract() == 0.0 && x <= 9_007_199_254_740_991.0).then_some(x as usize)
}

/// `v[key]` as a non-negative integer (see [`as_index`]).
pub fn index_of(v: &Value, key: &str) -> Option<usize> {
    as_index(v.get(key)?)
}

/// `v[key]` as a list of numbers.
pub fn numbers(v: &Value, key: &str) -> Option<Vec<f64>> {
    v.get(key)?.as_array()?.iter().map(Value::as_f64).collect()
}

/// The extension object `name` of a JSON object, if present.
pub fn extension<'a>(v: &'a Value, name: &str) -> Option<&'a Value> {
    v.get("extensions")?.get(name)
}

/// Escapes a JSON object key for a JSON pointer.
pub fn escape(key: &str) -> String {
    key.replace('~', "~0").replace('/', "~1")
}

/// Reads a `.gltf` or `.glb` file (`is_glb` from its extension), checking its first bytes
/// before the rest: a GLB header that cannot be right (magic, version, a declared length the
/// file does not have) or JSON text that goes wrong at its start is reported to `sink` as
/// [`Document::parse`] would report it, without reading a large file whole. `Ok(None)` when
/// such a problem was reported.
pub fn read_file(
    path: &Path,
    is_glb: bool,
    sink: &mut dyn Sink,
) -> std::io::Result<Option<Vec<u8>>> {
    let mut file = std::fs::File::open(path)?;
    let length = file.metadata()?.len();
    let mut head = Vec::with_capacity(HEAD_BYTES);
    (&mut file).take(HEAD_BYTES as u64).read_to_end(&mut head)?;
    if (head.len() as u64) < length {
        // Problems are gathered here first: when there are none, the whole file's parse
        // reports what it finds (the warnings included) once.
        let mut found = Vec::new();
        if is_glb || head.starts_with(b"glTF") {
            glb_header(
                &head,
                usize::try_from(length).unwrap_or(usize::MAX),
                &mut found,
            );
        } else {
            json_start(&head, &mut found);
        }
        if found.iter().any(|d| d.severity == Severity::Error) {
            for diagnostic in found {
                sink.push(diagnostic);
            }
            return Ok(None);
        }
    }
    let mut bytes = head;
    file.read_to_end(&mut bytes)?;
    Ok(Some(bytes))
}

/// Bytes [`read_file`] looks at before reading the rest of a file.
const HEAD_BYTES: usize = 64 * 1024;

/// Reports to `sink` a syntax error within the first bytes `head` of a longer JSON file: the
/// error the whole file's parse would report first.
fn json_start(head: &[u8], sink: &mut dyn Sink) {
    if let Err(e) = serde_json::from_slice::<serde::de::IgnoredAny>(head) {
        if e.classify() == serde_json::error::Category::Syntax {
            sink.error(Code::InvalidJson, "", format!("not valid glTF JSON: {e}"));
        }
    }
}

/// Checks a GLB's 12-byte header at the start of `bytes`, the file being `file_length` bytes
/// long, reporting every problem; returns the declared length, `None` when the header cannot
/// be read (wrong magic, too short, another version).
fn glb_header(bytes: &[u8], file_length: usize, sink: &mut dyn Sink) -> Option<usize> {
    let u32_at = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if !bytes.starts_with(b"glTF") && bytes.len() >= 4 {
        sink.error(
            Code::GlbInvalidMagic,
            "",
            "the file does not start with 'glTF'",
        );
        return None;
    }
    if bytes.len() < 12 {
        sink.error(
            Code::GlbUnexpectedEndOfHeader,
            "",
            format!("{} bytes: too short for a GLB header", bytes.len()),
        );
        return None;
    }
    let version = u32_at(4)?;
    if version != 2 {
        sink.error(
            Code::GlbInvalidVersion,
            "",
            format!("GLB version {version}, expected 2"),
        );
        return None;
    }
    let declared = u32_at(8)? as usize;
    if declared < 20 {
        sink.error(
            Code::GlbLengthTooSmall,
            "",
            format!("the GLB header declares {declared} bytes: no room for a chunk"),
        );
    }
    if declared > file_length || declared < 20 && declared != file_length {
        sink.error(
            Code::GlbLengthMismatch,
            "",
            format!("the GLB header declares {declared} bytes but the file has {file_length}"),
        );
    }
    Some(declared)
}

/// Splits a GLB into the ranges of its JSON and BIN chunks, reporting every structural
/// problem. `None` when there is no JSON chunk to read.
fn glb_chunks(bytes: &[u8], sink: &mut dyn Sink) -> Option<(Range<usize>, Option<Range<usize>>)> {
    let u32_at = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let declared = glb_header(bytes, bytes.len(), sink)?;
    let end = declared.min(bytes.len());
    let mut chunks = Chunks::default();
    let mut at = 12;
    let mut broken = false;
    while at < end {
        let Some((length, kind)) = u32_at(at).zip(u32_at(at + 4)).filter(|_| at + 8 <= end) else {
            sink.error(
                Code::GlbUnexpectedEndOfChunkHeader,
                "",
                format!("chunk header at byte {at} is cut short"),
            );
            broken = true;
            break;
        };
        let length = length as usize;
        let data_start = at + 8;
        if !length.is_multiple_of(4) {
            sink.error(
                Code::GlbChunkLengthUnaligned,
                "",
                format!(
                    "chunk {} length {length} is not a multiple of 4",
                    chunks.index
                ),
            );
        }
        let data_end = data_start.saturating_add(length);
        if data_end > declared {
            sink.error(
                Code::GlbChunkTooBig,
                "",
                format!(
                    "chunk {} ({length} bytes) runs past the declared length",
                    chunks.index
                ),
            );
        }
        if data_end > bytes.len() {
            sink.error(
                Code::GlbUnexpectedEndOfChunkData,
                "",
                format!(
                    "chunk {} ({length} bytes) runs past the end of the file",
                    chunks.index
                ),
            );
            broken = true;
            break;
        }
        chunks.add(kind, data_start..data_end, sink);
        at = data_end;
    }
    if !broken && bytes.len() > declared && declared >= 20 {
        sink.warn(
            Code::GlbExtraData,
            "",
            format!(
                "{} bytes after the declared end: ignored",
                bytes.len() - declared
            ),
        );
    }
    match chunks.json {
        Some(json) if !json.is_empty() => Some((json, chunks.bin)),
        Some(_) => None,
        None => {
            sink.error(Code::GlbUnexpectedFirstChunk, "", "no JSON chunk");
            None
        }
    }
}

/// The chunks of a GLB seen so far.
#[derive(Default)]
struct Chunks {
    index: usize,
    json: Option<Range<usize>>,
    bin: Option<Range<usize>>,
}

impl Chunks {
    /// Takes chunk number `self.index` of type `kind`, reporting misplaced chunks.
    fn add(&mut self, kind: u32, data: Range<usize>, sink: &mut dyn Sink) {
        let index = self.index;
        self.index += 1;
        let empty = data.is_empty();
        match kind {
            JSON_CHUNK if index != 0 => sink.error(
                Code::GlbDuplicateChunk,
                "",
                format!("chunk {index} is a second JSON chunk"),
            ),
            JSON_CHUNK => {
                if empty {
                    sink.error(Code::GlbEmptyChunk, "", "the JSON chunk is empty");
                }
                self.json = Some(data);
            }
            BIN_CHUNK if index == 0 => sink.error(
                Code::GlbUnexpectedFirstChunk,
                "",
                "the first chunk is BIN, not JSON",
            ),
            BIN_CHUNK if self.bin.is_some() => {
                sink.error(Code::GlbDuplicateChunk, "", "a second BIN chunk")
            }
            BIN_CHUNK if index != 1 => sink.error(
                Code::GlbUnexpectedBinChunk,
                "",
                format!("the BIN chunk is chunk {index}, not the second"),
            ),
            BIN_CHUNK => {
                if empty {
                    sink.error(Code::GlbEmptyChunk, "", "the BIN chunk is empty");
                }
                self.bin = Some(data);
            }
            other => {
                if index == 0 {
                    sink.error(
                        Code::GlbUnexpectedFirstChunk,
                        "",
                        format!("the first chunk has type 0x{other:08x}, not JSON"),
                    );
                }
                sink.warn(
                    Code::GlbUnknownChunkType,
                    "",
                    format!("chunk {index} has unknown type 0x{other:08x}: ignored"),
                );
            }
        }
    }
}
