//! A glTF walker that reports every problem it sees, not just the first.
//!
//! It works on the raw JSON (`serde_json::Value`), so that one bad property does not hide
//! the others, and reads buffers only after their sizes are checked against the limit. The
//! `gltf` crate's own deserialization and reference validation run beside it and add what
//! they find (unresolved references above all). The importer's span arithmetic
//! (`import::gltf::span_fits`), extension policy (`can_honour_required`) and quadric parser
//! (`QuadricSpec`) are reused, so `check` and the renderer agree on what loads.
//!
//! Codes are the Khronos glTF-Validator's where the meaning is the same.

use super::{resolve_inside, CheckOptions, Findings};
use crate::import::gltf::accessor::span_fits;
use crate::import::gltf::{can_honour_required, QUADRIC_EXTENSION};
use crate::quadric::QuadricSpec;
use glam::{DMat4, DQuat, DVec3};
use serde_json::{Map, Value};
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::rc::Rc;

/// Deepest node hierarchy walked.
pub const MAX_NODE_DEPTH: usize = 1024;

/// Most accessor values decoded for data checks (an accessor beyond is checked for layout only).
const MAX_VALUES: usize = 64 << 20;

/// Bytes of memory one triangle costs the importer and the scene (f64 while building, f32
/// stored, object table), used to estimate what an asset will allocate.
const BYTES_PER_TRIANGLE: u64 = 128;

/// Properties that hold non-negative integers wherever they appear.
const INTEGER_KEYS: &[&str] = &[
    "buffer",
    "bufferView",
    "byteLength",
    "byteOffset",
    "byteStride",
    "count",
    "componentType",
    "mesh",
    "skin",
    "camera",
    "node",
    "input",
    "output",
    "source",
    "texCoord",
    "scene",
    "material",
    "indices",
    "mode",
    "inverseBindMatrices",
    "skeleton",
];

const JSON_CHUNK: u32 = 0x4E4F_534A;
const BIN_CHUNK: u32 = 0x004E_4942;

/// Checks a `.gltf` or `.glb` file held in `bytes`. Returns whether the importer may run on
/// it (false when it cannot parse it, when it would read outside the asset, or when it would
/// need more memory than allowed).
pub fn check(
    path: &Path,
    tree_root: &Path,
    bytes: &[u8],
    options: &CheckOptions,
    f: &mut Findings,
) -> bool {
    let is_glb = bytes.starts_with(b"glTF")
        || path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let (json, bin) = if is_glb {
        match glb_chunks(bytes, f) {
            Some(chunks) => chunks,
            None => return false,
        }
    } else {
        (bytes, None)
    };
    let value: Value = match serde_json::from_slice(json) {
        Ok(v) => v,
        Err(e) => {
            let code = if e.to_string().contains("number out of range") {
                "VALUE_NOT_IN_RANGE"
            } else {
                "INVALID_JSON"
            };
            f.error(code, "", format!("not valid JSON: {e}"));
            return false;
        }
    };
    let Some(root) = value.as_object() else {
        f.error("TYPE_MISMATCH", "", "the JSON root is not an object");
        return false;
    };
    let crate_error = crate_validation(json, f);
    let base = path.parent().unwrap_or(Path::new("."));
    let mut walker = Walker {
        root,
        f,
        options,
        base,
        tree_root,
        is_glb,
        bin,
        buffers: Vec::new(),
        values: HashMap::new(),
        importable: true,
    };
    walker.run();
    let importable = walker.importable;
    if let Some(message) = crate_error {
        // The reader's limits, not necessarily the file's faults (it wants integers written
        // without a fraction, and some properties the specification leaves optional).
        let code = "LOAD_FAILED";
        let severity = if f.has_errors() {
            super::Severity::Info
        } else {
            super::Severity::Error
        };
        f.push(
            severity,
            code,
            "",
            format!("the glTF reader refuses the file: {message}"),
        );
        return false;
    }
    importable
}

/// Splits a GLB into its JSON and BIN chunks, reporting every structural problem.
fn glb_chunks<'a>(bytes: &'a [u8], f: &mut Findings) -> Option<(&'a [u8], Option<&'a [u8]>)> {
    let u32_at = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    if bytes.len() < 12 {
        if bytes.len() >= 4 && !bytes.starts_with(b"glTF") {
            f.error(
                "GLB_INVALID_MAGIC",
                "",
                "the file does not start with 'glTF'",
            );
        } else {
            f.error(
                "GLB_UNEXPECTED_END_OF_HEADER",
                "",
                format!("{} bytes: too short for a GLB header", bytes.len()),
            );
        }
        return None;
    }
    if !bytes.starts_with(b"glTF") {
        f.error(
            "GLB_INVALID_MAGIC",
            "",
            "the file does not start with 'glTF'",
        );
        return None;
    }
    let version = u32_at(4)?;
    if version != 2 {
        f.error(
            "GLB_INVALID_VERSION",
            "",
            format!("GLB version {version}, expected 2"),
        );
        return None;
    }
    let declared = u32_at(8)? as usize;
    if declared < 20 {
        f.error(
            "GLB_LENGTH_TOO_SMALL",
            "",
            format!("declared length {declared} leaves no room for a chunk"),
        );
    }
    if declared > bytes.len() || declared < 20 && declared != bytes.len() {
        f.error(
            "GLB_LENGTH_MISMATCH",
            "",
            format!(
                "declared length {declared} differs from the file's {} bytes",
                bytes.len()
            ),
        );
    }
    let end = declared.min(bytes.len());
    let mut at = 12;
    let mut json: Option<&[u8]> = None;
    let mut bin: Option<&[u8]> = None;
    let mut index = 0;
    let mut broken = false;
    while at < end {
        let Some((length, kind)) = u32_at(at).zip(u32_at(at + 4)).filter(|_| at + 8 <= end) else {
            f.error(
                "GLB_UNEXPECTED_END_OF_CHUNK_HEADER",
                "",
                format!("chunk header at byte {at} is cut short"),
            );
            broken = true;
            break;
        };
        let length = length as usize;
        let data_start = at + 8;
        if !length.is_multiple_of(4) {
            f.error(
                "GLB_CHUNK_LENGTH_UNALIGNED",
                "",
                format!("chunk {index} length {length} is not a multiple of 4"),
            );
        }
        let data_end = data_start.saturating_add(length);
        if data_end > declared {
            f.error(
                "GLB_CHUNK_TOO_BIG",
                "",
                format!("chunk {index} ({length} bytes) runs past the declared length"),
            );
        }
        if data_end > bytes.len() {
            f.error(
                "GLB_UNEXPECTED_END_OF_CHUNK_DATA",
                "",
                format!("chunk {index} ({length} bytes) runs past the end of the file"),
            );
            broken = true;
            break;
        }
        let data = &bytes[data_start..data_end];
        match kind {
            JSON_CHUNK => {
                if index != 0 {
                    f.error(
                        "GLB_DUPLICATE_CHUNK",
                        "",
                        format!("chunk {index} is a second JSON chunk"),
                    );
                } else {
                    if length == 0 {
                        f.error("GLB_EMPTY_CHUNK", "", "the JSON chunk is empty");
                    }
                    json = Some(data);
                }
            }
            BIN_CHUNK => {
                if index == 0 {
                    f.error(
                        "GLB_UNEXPECTED_FIRST_CHUNK",
                        "",
                        "the first chunk is BIN, not JSON",
                    );
                } else if bin.is_some() {
                    f.error("GLB_DUPLICATE_CHUNK", "", "a second BIN chunk");
                } else if index != 1 {
                    f.error(
                        "GLB_UNEXPECTED_BIN_CHUNK",
                        "",
                        format!("the BIN chunk is chunk {index}, not the second"),
                    );
                } else {
                    if length == 0 {
                        f.error("GLB_EMPTY_CHUNK", "", "the BIN chunk is empty");
                    }
                    bin = Some(data);
                }
            }
            other => {
                if index == 0 {
                    f.error(
                        "GLB_UNEXPECTED_FIRST_CHUNK",
                        "",
                        format!("the first chunk has type 0x{other:08x}, not JSON"),
                    );
                }
                f.warn(
                    "GLB_UNKNOWN_CHUNK_TYPE",
                    "",
                    format!("chunk {index} has unknown type 0x{other:08x}: ignored"),
                );
            }
        }
        index += 1;
        at = data_end;
    }
    if !broken && bytes.len() > declared && declared >= 20 {
        // A file longer than declared: the rest is ignored.
        f.warn(
            "GLB_EXTRA_DATA",
            "",
            format!("{} bytes after the declared end", bytes.len() - declared),
        );
    }
    match json {
        Some(json) if !json.is_empty() => Some((json, bin)),
        Some(_) => None,
        None => {
            if !f.has_errors() {
                f.error("GLB_UNEXPECTED_FIRST_CHUNK", "", "no JSON chunk");
            }
            None
        }
    }
}

/// Runs the `gltf` crate's deserialization and validation; reference problems become
/// findings; a refusal to deserialize is returned (reported last, since the walker usually
/// explains it better).
fn crate_validation(json: &[u8], f: &mut Findings) -> Option<String> {
    use gltf::json::validation::{Error as VError, Validate};
    let root: gltf::json::Root = match serde_json::from_slice(json) {
        Ok(root) => root,
        Err(e) => return Some(e.to_string()),
    };
    let dangling = dangling_positions(&root);
    if !dangling.is_empty() {
        for pointer in dangling {
            f.error(
                "UNRESOLVED_REFERENCE",
                pointer,
                "refers to an accessor that does not exist",
            );
        }
        return None;
    }
    let mut found = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, error| {
        found.push((path().to_string(), error));
    });
    for (path, error) in found {
        let pointer = json_pointer(&path);
        match error {
            VError::IndexOutOfBounds => f.error(
                "UNRESOLVED_REFERENCE",
                pointer,
                "refers to an object that does not exist",
            ),
            // The crate asks for properties the specification leaves optional; the walker
            // checks the required ones itself.
            VError::Missing => {}
            VError::Invalid => f.warn("VALUE_NOT_IN_LIST", pointer, "invalid value"),
            VError::Oversize => f.error("VALUE_NOT_IN_RANGE", pointer, "value too large"),
            VError::Unsupported => {}
        }
    }
    None
}

/// JSON pointers of POSITION attributes that name an accessor the file does not have. The
/// `gltf` crate's validation panics on them, so they are checked before it runs.
fn dangling_positions(root: &gltf::json::Root) -> Vec<String> {
    let mut found = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position) {
                if index.value() >= root.accessors.len() {
                    found.push(format!("/meshes/{m}/primitives/{p}/attributes/POSITION"));
                }
            }
        }
    }
    found
}

/// `meshes[0].primitives[1].indices` -> `/meshes/0/primitives/1/indices`.
fn json_pointer(path: &str) -> String {
    let mut out = String::new();
    for part in path.split(['.', '[']) {
        let part = part.trim_end_matches(']');
        if part.is_empty() {
            continue;
        }
        out.push('/');
        out.push_str(&part.replace('~', "~0").replace('/', "~1"));
    }
    out
}

fn escape(key: &str) -> String {
    key.replace('~', "~0").replace('/', "~1")
}

fn index_of(v: &Value, key: &str) -> Option<usize> {
    v.get(key)?.as_u64().and_then(|n| usize::try_from(n).ok())
}

fn array<'a>(v: &'a Value, key: &str) -> &'a [Value] {
    v.get(key)
        .and_then(Value::as_array)
        .map_or(&[], Vec::as_slice)
}

fn numbers(v: &Value, key: &str) -> Option<Vec<f64>> {
    v.get(key)?.as_array()?.iter().map(Value::as_f64).collect()
}

/// Component byte size of a glTF componentType.
fn component_size(kind: u64) -> Option<usize> {
    match kind {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

/// Components per element, and rows when the type is a matrix.
fn type_shape(kind: &str) -> Option<(usize, Option<usize>)> {
    match kind {
        "SCALAR" => Some((1, None)),
        "VEC2" => Some((2, None)),
        "VEC3" => Some((3, None)),
        "VEC4" => Some((4, None)),
        "MAT2" => Some((4, Some(2))),
        "MAT3" => Some((9, Some(3))),
        "MAT4" => Some((16, Some(4))),
        _ => None,
    }
}

/// The layout of one accessor, when its JSON is well formed.
#[derive(Debug, Clone, Copy)]
struct Layout {
    component: u64,
    size: usize,
    comps: usize,
    rows: Option<usize>,
    count: usize,
    normalized: bool,
    /// Bytes of one element including matrix column padding.
    element: usize,
    /// Bytes the last element needs (without the last column's padding).
    last: usize,
}

impl Layout {
    fn of(acc: &Value) -> Option<Layout> {
        let component = acc.get("componentType")?.as_u64()?;
        let size = component_size(component)?;
        let (comps, rows) = type_shape(acc.get("type")?.as_str()?)?;
        let count = index_of(acc, "count")?;
        let (element, last) = match rows {
            // Matrix columns start on 4-byte boundaries.
            Some(rows) => {
                let column = (rows * size).div_ceil(4) * 4;
                (column * rows, column * (rows - 1) + rows * size)
            }
            None => (comps * size, comps * size),
        };
        Some(Layout {
            component,
            size,
            comps,
            rows,
            count,
            normalized: acc.get("normalized").and_then(Value::as_bool) == Some(true),
            element,
            last,
        })
    }

    /// Byte offset of component `c` inside an element.
    fn component_offset(&self, c: usize) -> usize {
        match self.rows {
            Some(rows) => (c / rows) * (rows * self.size).div_ceil(4) * 4 + (c % rows) * self.size,
            None => c * self.size,
        }
    }

    fn read(&self, bytes: &[u8], at: usize) -> f64 {
        let b = |i: usize| bytes.get(at + i).copied().unwrap_or(0);
        match self.component {
            5120 => b(0) as i8 as f64,
            5121 => b(0) as f64,
            5122 => i16::from_le_bytes([b(0), b(1)]) as f64,
            5123 => u16::from_le_bytes([b(0), b(1)]) as f64,
            5125 => u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64,
            _ => f32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64,
        }
    }
}

struct Walker<'a, 'f> {
    root: &'a Map<String, Value>,
    f: &'f mut Findings,
    options: &'a CheckOptions,
    base: &'a Path,
    /// The folder tree external files must stay in.
    tree_root: &'a Path,
    is_glb: bool,
    bin: Option<&'a [u8]>,
    /// Each buffer's bytes, when they could be read.
    buffers: Vec<Option<Vec<u8>>>,
    /// Decoded accessor values (sparse applied), by accessor index.
    values: HashMap<usize, Option<Rc<Vec<f64>>>>,
    importable: bool,
}

impl<'a> Walker<'a, '_> {
    fn list(&self, key: &str) -> &'a [Value] {
        let root: &'a Map<String, Value> = self.root;
        root.get(key)
            .and_then(Value::as_array)
            .map_or(&[], Vec::as_slice)
    }

    fn run(&mut self) {
        self.schema();
        self.asset();
        self.extension_lists();
        self.buffers();
        self.buffer_views();
        self.accessors();
        self.meshes();
        let triangles = self.nodes_and_scenes();
        self.cameras();
        self.images();
        self.animations();
        self.skins();
        let estimate = triangles.saturating_mul(BYTES_PER_TRIANGLE);
        if estimate > self.options.max_bytes {
            self.f.error(
                "ASSET_TOO_LARGE",
                "",
                format!(
                    "the scene expands to about {triangles} triangles (~{} MiB), more than the limit of {} MiB (--max-memory): not loaded",
                    estimate >> 20,
                    self.options.max_bytes >> 20
                ),
            );
            self.importable = false;
        }
    }

    /// Shape checks that need no meaning: collection types, empty arrays, required
    /// properties, extension objects.
    fn schema(&mut self) {
        const COLLECTIONS: &[&str] = &[
            "accessors",
            "animations",
            "buffers",
            "bufferViews",
            "cameras",
            "images",
            "materials",
            "meshes",
            "nodes",
            "samplers",
            "scenes",
            "skins",
            "textures",
        ];
        for &key in COLLECTIONS {
            match self.root.get(key) {
                None => {}
                Some(Value::Array(items)) => {
                    for (i, item) in items.iter().enumerate() {
                        if !item.is_object() {
                            self.f.error(
                                "TYPE_MISMATCH",
                                format!("/{key}/{i}"),
                                "expected an object",
                            );
                        }
                    }
                }
                Some(_) => self
                    .f
                    .error("TYPE_MISMATCH", format!("/{key}"), "expected an array"),
            }
        }
        let root = Value::Object(self.root.clone());
        let declared: HashSet<String> = array(&root, "extensionsUsed")
            .iter()
            .filter_map(Value::as_str)
            .map(String::from)
            .collect();
        self.tree(&root, String::new(), &declared);
        match self.root.get("asset") {
            None => self.f.error(
                "UNDEFINED_PROPERTY",
                "/asset",
                "the asset property is missing",
            ),
            Some(asset) if !asset.is_object() => {
                self.f
                    .error("TYPE_MISMATCH", "/asset", "expected an object")
            }
            Some(asset) => self.required(asset, "/asset", &["version"]),
        }
        let required: &[(&str, &[&str])] = &[
            ("accessors", &["componentType", "count", "type"]),
            ("animations", &["channels", "samplers"]),
            ("buffers", &["byteLength"]),
            ("bufferViews", &["buffer", "byteLength"]),
            ("cameras", &["type"]),
            ("meshes", &["primitives"]),
            ("skins", &["joints"]),
        ];
        for &(key, props) in required {
            for (i, item) in self.list(key).iter().enumerate() {
                self.required(item, &format!("/{key}/{i}"), props);
            }
        }
        for (i, mesh) in self.list("meshes").iter().enumerate() {
            for (j, prim) in array(mesh, "primitives").iter().enumerate() {
                let at = format!("/meshes/{i}/primitives/{j}");
                self.required(prim, &at, &["attributes"]);
                if prim
                    .get("attributes")
                    .and_then(Value::as_object)
                    .is_some_and(Map::is_empty)
                {
                    self.f
                        .error("EMPTY_ENTITY", format!("{at}/attributes"), "no attributes");
                }
            }
        }
        for (i, anim) in self.list("animations").iter().enumerate() {
            for (j, channel) in array(anim, "channels").iter().enumerate() {
                let at = format!("/animations/{i}/channels/{j}");
                self.required(channel, &at, &["sampler", "target"]);
                if let Some(target) = channel.get("target") {
                    self.required(target, &format!("{at}/target"), &["path"]);
                }
            }
            for (j, sampler) in array(anim, "samplers").iter().enumerate() {
                let at = format!("/animations/{i}/samplers/{j}");
                self.required(sampler, &at, &["input", "output"]);
            }
        }
        for (i, acc) in self.list("accessors").iter().enumerate() {
            if let Some(sparse) = acc.get("sparse") {
                let at = format!("/accessors/{i}/sparse");
                self.required(sparse, &at, &["count", "indices", "values"]);
                if let Some(ind) = sparse.get("indices") {
                    self.required(
                        ind,
                        &format!("{at}/indices"),
                        &["bufferView", "componentType"],
                    );
                }
                if let Some(val) = sparse.get("values") {
                    self.required(val, &format!("{at}/values"), &["bufferView"]);
                }
            }
        }
        for (i, image) in self.list("images").iter().enumerate() {
            let has_uri = image.get("uri").is_some();
            let has_view = image.get("bufferView").is_some();
            if has_uri == has_view {
                self.f.error(
                    "ONE_OF_MISMATCH",
                    format!("/images/{i}"),
                    "an image needs exactly one of uri and bufferView",
                );
            }
        }
    }

    fn required(&mut self, item: &Value, at: &str, props: &[&str]) {
        let Some(obj) = item.as_object() else {
            return;
        };
        for prop in props {
            if !obj.contains_key(*prop) {
                self.f.error(
                    "UNDEFINED_PROPERTY",
                    format!("{at}/{prop}"),
                    format!("property '{prop}' must be defined"),
                );
            }
        }
    }

    /// Empty arrays, and `extensions` objects with undeclared names, anywhere but in extras.
    fn tree(&mut self, v: &Value, at: String, declared: &HashSet<String>) {
        match v {
            Value::Array(items) => {
                if items.is_empty() {
                    self.f.error("EMPTY_ENTITY", at.clone(), "an empty array");
                }
                for (i, item) in items.iter().enumerate() {
                    self.tree(item, format!("{at}/{i}"), declared);
                }
            }
            Value::Object(map) => {
                for (key, item) in map {
                    let here = format!("{at}/{}", escape(key));
                    if key == "extras" {
                        continue;
                    }
                    if INTEGER_KEYS.contains(&key.as_str()) {
                        if let Some(x) = item.as_f64().filter(|_| item.as_u64().is_none()) {
                            if !(x >= 0.0 && x.fract() == 0.0 && x <= 9007199254740991.0) {
                                self.f.error(
                                    "VALUE_NOT_IN_RANGE",
                                    here.clone(),
                                    format!("{x} is not a valid non-negative integer"),
                                );
                            }
                        }
                    }
                    if key == "extensions" {
                        match item.as_object() {
                            None => {
                                self.f
                                    .error("TYPE_MISMATCH", here.clone(), "expected an object")
                            }
                            Some(exts) => {
                                for (name, ext) in exts {
                                    let ext_at = format!("{here}/{}", escape(name));
                                    if !declared.contains(name) {
                                        self.f.error(
                                            "UNDECLARED_EXTENSION",
                                            ext_at.clone(),
                                            format!("extension '{name}' is not in extensionsUsed"),
                                        );
                                    }
                                    if !ext.is_object() {
                                        self.f.error(
                                            "TYPE_MISMATCH",
                                            ext_at.clone(),
                                            "an extension must be an object",
                                        );
                                    }
                                    self.tree(ext, ext_at, declared);
                                }
                            }
                        }
                        continue;
                    }
                    self.tree(item, here, declared);
                }
            }
            _ => {}
        }
    }

    fn asset(&mut self) {
        let Some(asset) = self.root.get("asset") else {
            return;
        };
        let parse = |v: Option<&Value>| -> Option<Option<(u64, u64)>> {
            let v = v?;
            Some(v.as_str().and_then(|t| {
                let (a, b) = t.split_once('.')?;
                let ok = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
                if !(ok(a) && ok(b)) {
                    return None;
                }
                Some((a.parse().ok()?, b.parse().ok()?))
            }))
        };
        let version = match parse(asset.get("version")) {
            None => None,
            Some(None) => {
                self.f.error(
                    "PATTERN_MISMATCH",
                    "/asset/version",
                    "the version must look like MAJOR.MINOR",
                );
                None
            }
            Some(Some(v)) => Some(v),
        };
        if let Some((major, minor)) = version {
            if major != 2 {
                self.f.error(
                    "UNKNOWN_ASSET_MAJOR_VERSION",
                    "/asset/version",
                    format!("glTF {major}.{minor} is not glTF 2"),
                );
            } else if minor > 0 {
                self.f.warn(
                    "UNKNOWN_ASSET_MINOR_VERSION",
                    "/asset/version",
                    format!("glTF 2.{minor} is newer than 2.0"),
                );
            }
        }
        match (parse(asset.get("minVersion")), version) {
            (Some(None), _) => self.f.error(
                "PATTERN_MISMATCH",
                "/asset/minVersion",
                "minVersion must look like MAJOR.MINOR",
            ),
            (Some(Some(min)), Some(version)) if min > version => self.f.error(
                "ASSET_MIN_VERSION_GREATER_THAN_VERSION",
                "/asset/minVersion",
                "minVersion is greater than version",
            ),
            _ => {}
        }
    }

    fn extension_lists(&mut self) {
        let names = |key: &str| -> Vec<String> {
            self.list(key)
                .iter()
                .filter_map(Value::as_str)
                .map(String::from)
                .collect()
        };
        let used = names("extensionsUsed");
        let required = names("extensionsRequired");
        for (key, list) in [("extensionsUsed", &used), ("extensionsRequired", &required)] {
            let mut seen = HashSet::new();
            for (i, name) in list.iter().enumerate() {
                if !seen.insert(name) {
                    self.f.error(
                        "DUPLICATE_ELEMENTS",
                        format!("/{key}/{i}"),
                        format!("'{name}' is listed twice"),
                    );
                }
                let valid = name.split_once('_').is_some_and(|(prefix, rest)| {
                    !prefix.is_empty()
                        && prefix
                            .bytes()
                            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit())
                        && !rest.is_empty()
                });
                if key == "extensionsUsed" && !valid {
                    self.f.warn(
                        "INVALID_EXTENSION_NAME_FORMAT",
                        format!("/{key}/{i}"),
                        format!("'{name}' is not PREFIX_name"),
                    );
                }
            }
        }
        if !required.is_empty() && self.root.get("extensionsUsed").is_none() {
            self.f.error(
                "UNSATISFIED_DEPENDENCY",
                "/extensionsRequired",
                "extensionsRequired without extensionsUsed",
            );
        }
        for (i, name) in required.iter().enumerate() {
            let at = format!("/extensionsRequired/{i}");
            if !used.contains(name) {
                self.f.error(
                    "UNUSED_EXTENSION_REQUIRED",
                    at.clone(),
                    format!("'{name}' is required but not in extensionsUsed"),
                );
            }
            if !can_honour_required(name) {
                self.f.error(
                    "UNSUPPORTED_EXTENSION",
                    at,
                    format!("the file requires '{name}', which raycast cannot decode"),
                );
            }
        }
    }

    /// Checks and reads the buffers, within the size limit and the asset's folder.
    fn buffers(&mut self) {
        let buffers = self.list("buffers").to_vec();
        let mut total = 0u64;
        for (i, buffer) in buffers.iter().enumerate() {
            let at = format!("/buffers/{i}");
            let declared = buffer.get("byteLength").and_then(Value::as_u64);
            if declared == Some(0) {
                self.f.error(
                    "VALUE_NOT_IN_RANGE",
                    format!("{at}/byteLength"),
                    "must be at least 1",
                );
            }
            let declared = declared.unwrap_or(0);
            total = total.saturating_add(declared);
            if total > self.options.max_bytes {
                self.f.error(
                    "ASSET_TOO_LARGE",
                    format!("{at}/byteLength"),
                    format!(
                        "buffers add up to more than the limit of {} bytes (--max-memory): not read",
                        self.options.max_bytes
                    ),
                );
                self.importable = false;
                self.buffers.push(None);
                continue;
            }
            let data = match buffer.get("uri") {
                None => {
                    if self.is_glb && i == 0 {
                        match self.bin {
                            Some(bin) => Some(bin.to_vec()),
                            None => {
                                self.f.error(
                                    "BUFFER_MISSING_GLB_DATA",
                                    at.clone(),
                                    "the buffer has no uri and the GLB has no BIN chunk",
                                );
                                None
                            }
                        }
                    } else {
                        self.f.info(
                            "BUFFER_NO_DATA",
                            at.clone(),
                            "the buffer has no uri: its data is not available",
                        );
                        None
                    }
                }
                Some(uri) => match uri.as_str() {
                    None => {
                        self.f
                            .error("TYPE_MISMATCH", format!("{at}/uri"), "expected a string");
                        None
                    }
                    Some(uri) => {
                        if self.is_glb && uri.starts_with("data:") {
                            self.f.warn(
                                "DATA_URI_GLB",
                                format!("{at}/uri"),
                                "a data: URI inside a GLB",
                            );
                        }
                        self.external(&format!("{at}/uri"), uri, true, declared)
                    }
                },
            };
            if let Some(data) = &data {
                let actual = data.len() as u64;
                if actual < declared {
                    self.f.error(
                        "BUFFER_BYTE_LENGTH_MISMATCH",
                        format!("{at}/byteLength"),
                        format!("byteLength {declared} but the data has {actual} bytes"),
                    );
                } else if self.is_glb
                    && i == 0
                    && buffer.get("uri").is_none()
                    && actual > declared + 3
                {
                    self.f.warn(
                        "BUFFER_GLB_CHUNK_TOO_BIG",
                        at.clone(),
                        format!("the BIN chunk has {actual} bytes for a {declared}-byte buffer"),
                    );
                } else if buffer
                    .get("uri")
                    .is_some_and(|u| u.as_str().is_some_and(|u| u.starts_with("data:")))
                    && actual != declared
                {
                    self.f.error(
                        "BUFFER_BYTE_LENGTH_MISMATCH",
                        format!("{at}/byteLength"),
                        format!("byteLength {declared} but the data has {actual} bytes"),
                    );
                }
            }
            self.buffers.push(data);
        }
    }

    /// Reads what a uri points to (a buffer when `is_buffer`, else an image), with the
    /// confinement and size rules. Images are only looked for, never read, unless embedded.
    fn external(&mut self, at: &str, uri: &str, is_buffer: bool, declared: u64) -> Option<Vec<u8>> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let Some((header, payload)) = rest.split_once(',') else {
                self.f
                    .error("INVALID_URI", at, "a data: URI without a comma");
                return None;
            };
            let (mime, is_base64) = match header.strip_suffix(";base64") {
                Some(mime) => (mime, true),
                None => (header, false),
            };
            if mime.contains(';') && !mime.contains('=') {
                self.f.error(
                    "INVALID_URI",
                    at,
                    format!("malformed data: URI header '{header}'"),
                );
                return None;
            }
            let mime = mime.split(';').next().unwrap_or("");
            if is_buffer && !matches!(mime, "application/octet-stream" | "application/gltf-buffer")
            {
                self.f.error(
                    "BUFFER_DATA_URI_MIME_TYPE_INVALID",
                    at,
                    format!("buffer data: URI has media type '{mime}'"),
                );
            }
            if !is_buffer
                && !matches!(
                    mime,
                    "image/png" | "image/jpeg" | "image/webp" | "image/ktx2"
                )
            {
                self.f.error(
                    "IMAGE_MIME_TYPE_INVALID",
                    at,
                    format!("image data: URI has media type '{mime}'"),
                );
            }
            let decoded_len = payload.len() / 4 * 3;
            if decoded_len as u64 > self.options.max_bytes {
                self.f.error(
                    "ASSET_TOO_LARGE",
                    at,
                    "the data: URI decodes to more than the --max-memory limit: not decoded",
                );
                self.importable = false;
                return None;
            }
            if !is_base64 {
                return Some(urlencoding::decode_binary(payload.as_bytes()).into_owned());
            }
            return match base64_decode(payload) {
                Some(data) => Some(data),
                None => {
                    self.f
                        .error("INVALID_URI", at, "the data: URI is not valid base64");
                    None
                }
            };
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
                self.f.push(
                    super::Severity::Warning,
                    "NON_RELATIVE_URI",
                    at,
                    format!(
                        "'{uri}' is not a relative path: never fetched (raycast reads no network)"
                    ),
                );
                if is_buffer {
                    self.importable = false;
                }
                return None;
            }
        }
        if uri.is_empty() || uri.starts_with(':') || uri.contains(['\\', '\0']) {
            self.f
                .error("INVALID_URI", at, format!("'{uri}' is not a valid URI"));
            if is_buffer {
                self.importable = false;
            }
            return None;
        }
        let decoded = match urlencoding::decode(uri) {
            Ok(d) => d.into_owned(),
            Err(_) => {
                self.f.error(
                    "INVALID_URI",
                    at,
                    format!("'{uri}' has bad percent-encoding"),
                );
                return None;
            }
        };
        let path = match resolve_inside(
            self.base,
            self.tree_root,
            &decoded,
            self.options.allow_outside,
        ) {
            Ok(path) => path,
            Err(why) => {
                self.f.error("PATH_OUTSIDE_ASSET", at, why);
                if is_buffer {
                    self.importable = false;
                }
                return None;
            }
        };
        let meta = match std::fs::metadata(&path) {
            Ok(meta) if meta.is_file() => meta,
            _ => {
                let what = if is_buffer { "buffer" } else { "image" };
                let severity = if is_buffer {
                    super::Severity::Error
                } else {
                    // Images are never read by raycast.
                    super::Severity::Warning
                };
                self.f.push(
                    severity,
                    "IO_ERROR",
                    at,
                    format!("{what} file '{decoded}' cannot be found"),
                );
                if is_buffer {
                    self.importable = false;
                }
                return None;
            }
        };
        if !is_buffer {
            // Images are never decoded; their first bytes are sniffed.
            use std::io::Read;
            let mut head = Vec::new();
            let read =
                std::fs::File::open(&path).and_then(|file| file.take(64).read_to_end(&mut head));
            return read.ok().map(|_| head);
        }
        if meta.len() > self.options.max_bytes
            || meta.len() > declared.saturating_add(1 << 20)
                && meta.len() > self.options.max_bytes / 2
        {
            self.f.error(
                "ASSET_TOO_LARGE",
                at,
                format!("buffer file '{decoded}' has {} bytes: not read", meta.len()),
            );
            self.importable = false;
            return None;
        }
        match std::fs::read(&path) {
            Ok(data) => Some(data),
            Err(e) => {
                self.f.error(
                    "IO_ERROR",
                    at,
                    format!("cannot read buffer file '{decoded}': {e}"),
                );
                self.importable = false;
                None
            }
        }
    }

    fn buffer_len(&self, index: usize) -> Option<usize> {
        self.buffers.get(index)?.as_ref().map(Vec::len)
    }

    fn buffer_views(&mut self) {
        let views = self.list("bufferViews").to_vec();
        let buffers = self.list("buffers").to_vec();
        for (i, view) in views.iter().enumerate() {
            let at = format!("/bufferViews/{i}");
            let length = view.get("byteLength").and_then(Value::as_u64);
            if length == Some(0) {
                self.f.error(
                    "VALUE_NOT_IN_RANGE",
                    format!("{at}/byteLength"),
                    "must be at least 1",
                );
            }
            let offset = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
            if let (Some(length), Some(buffer)) = (length, index_of(view, "buffer")) {
                if let Some(declared) = buffers
                    .get(buffer)
                    .and_then(|b| b.get("byteLength"))
                    .and_then(Value::as_u64)
                {
                    if offset.checked_add(length).is_none_or(|end| end > declared) {
                        self.f.error(
                            "BUFFER_VIEW_TOO_LONG",
                            format!("{at}/byteLength"),
                            format!(
                                "bytes {offset}..{} do not fit buffer {buffer} of {declared} bytes",
                                offset.saturating_add(length)
                            ),
                        );
                    }
                }
            }
            if let Some(stride) = view.get("byteStride").and_then(Value::as_u64) {
                let sat = format!("{at}/byteStride");
                if !(4..=252).contains(&stride) {
                    self.f.error(
                        "VALUE_NOT_IN_RANGE",
                        sat.clone(),
                        format!("byteStride {stride} is not in 4..252"),
                    );
                } else if stride % 4 != 0 {
                    self.f.error(
                        "VALUE_MULTIPLE_OF",
                        sat.clone(),
                        format!("byteStride {stride} is not a multiple of 4"),
                    );
                }
                if length.is_some_and(|l| stride > l) {
                    self.f.error(
                        "BUFFER_VIEW_TOO_BIG_BYTE_STRIDE",
                        sat.clone(),
                        "byteStride is larger than the view",
                    );
                }
                if view.get("target").and_then(Value::as_u64) == Some(34963) {
                    self.f.error(
                        "BUFFER_VIEW_INVALID_BYTE_STRIDE",
                        sat,
                        "an index buffer view cannot have a byteStride",
                    );
                }
            }
        }
    }

    /// The view's (buffer length, offset, length, stride) when all are known.
    fn view_span(&self, view: usize) -> Option<(usize, usize, usize, Option<usize>)> {
        let v = self.list("bufferViews").get(view)?;
        let buffer = index_of(v, "buffer")?;
        let len = self.buffer_len(buffer)?;
        Some((
            len,
            index_of(v, "byteOffset").unwrap_or(0),
            index_of(v, "byteLength")?,
            index_of(v, "byteStride"),
        ))
    }

    fn accessors(&mut self) {
        let accessors = self.list("accessors").to_vec();
        for (i, acc) in accessors.iter().enumerate() {
            let at = format!("/accessors/{i}");
            if acc.get("count").and_then(Value::as_u64) == Some(0) {
                self.f.error(
                    "VALUE_NOT_IN_RANGE",
                    format!("{at}/count"),
                    "must be at least 1",
                );
            }
            let view = index_of(acc, "bufferView");
            let offset = index_of(acc, "byteOffset").unwrap_or(0);
            if view.is_none() && acc.get("byteOffset").is_some() {
                self.f.error(
                    "UNSATISFIED_DEPENDENCY",
                    format!("{at}/byteOffset"),
                    "byteOffset without bufferView",
                );
            }
            let Some(layout) = Layout::of(acc) else {
                continue;
            };
            if layout.normalized && matches!(layout.component, 5125 | 5126) {
                self.f.error(
                    "ACCESSOR_NORMALIZED_INVALID",
                    format!("{at}/normalized"),
                    "only 8- and 16-bit integer accessors can be normalized",
                );
            }
            if let Some(view_index) = view {
                if !offset.is_multiple_of(layout.size) {
                    self.f.error(
                        "ACCESSOR_OFFSET_ALIGNMENT",
                        format!("{at}/byteOffset"),
                        format!("offset {offset} is not a multiple of {}", layout.size),
                    );
                }
                let view_json = self.list("bufferViews").get(view_index).cloned();
                if let Some(v) = &view_json {
                    let view_offset = index_of(v, "byteOffset").unwrap_or(0);
                    if !(view_offset + offset).is_multiple_of(layout.size) {
                        self.f.error(
                            "ACCESSOR_TOTAL_OFFSET_ALIGNMENT",
                            at.clone(),
                            format!(
                                "total offset {} is not a multiple of {}",
                                view_offset + offset,
                                layout.size
                            ),
                        );
                    }
                    if layout.rows.is_some() && !offset.is_multiple_of(4) {
                        self.f.error(
                            "ACCESSOR_MATRIX_ALIGNMENT",
                            format!("{at}/byteOffset"),
                            "matrix accessors must start on a 4-byte boundary",
                        );
                    }
                    let stride = index_of(v, "byteStride");
                    if let Some(stride) = stride.filter(|&s| s < layout.element) {
                        self.f.error(
                            "ACCESSOR_SMALL_BYTESTRIDE",
                            at.clone(),
                            format!(
                                "byteStride {stride} is smaller than an element ({} bytes)",
                                layout.element
                            ),
                        );
                    }
                    if let Some(view_length) = index_of(v, "byteLength") {
                        let stride = stride.unwrap_or(layout.element).max(layout.element);
                        if !span_fits(
                            usize::MAX,
                            0,
                            view_length,
                            offset,
                            stride,
                            layout.count.max(1),
                            layout.last,
                        ) {
                            self.f.error(
                                "ACCESSOR_TOO_LONG",
                                at.clone(),
                                format!("{} elements from offset {offset} do not fit buffer view {view_index} ({view_length} bytes)", layout.count),
                            );
                        }
                    }
                }
            }
            if let Some(sparse) = acc.get("sparse") {
                let n = index_of(sparse, "count").unwrap_or(0);
                if n == 0 || n > layout.count {
                    self.f.error(
                        "ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE",
                        format!("{at}/sparse/count"),
                        format!("sparse count {n} is not in 1..={}", layout.count),
                    );
                }
                let ic = sparse
                    .get("indices")
                    .and_then(|x| x.get("componentType"))
                    .and_then(Value::as_u64);
                if ic.is_some_and(|c| !matches!(c, 5121 | 5123 | 5125)) {
                    self.f.error(
                        "VALUE_NOT_IN_LIST",
                        format!("{at}/sparse/indices/componentType"),
                        "sparse indices must be unsigned integers",
                    );
                }
            }
            self.accessor_data(i, &layout, &at);
        }
    }

    /// Decodes an accessor (sparse applied). None when its data cannot be read safely.
    fn values(&mut self, index: usize) -> Option<Rc<Vec<f64>>> {
        if let Some(v) = self.values.get(&index) {
            return v.clone();
        }
        let decoded = self.decode(index).map(Rc::new);
        self.values.insert(index, decoded.clone());
        decoded
    }

    fn decode(&mut self, index: usize) -> Option<Vec<f64>> {
        let acc = self.list("accessors").get(index)?.clone();
        let layout = Layout::of(&acc)?;
        let total = layout.count.checked_mul(layout.comps)?;
        if total == 0 || total > MAX_VALUES {
            return None;
        }
        // Accessors without a buffer view (zeros, maybe with sparse values) are not checked:
        // the validator leaves them alone too.
        index_of(&acc, "bufferView")?;
        let mut values = vec![0.0; total];
        if let Some(view) = index_of(&acc, "bufferView") {
            let (buffer_len, view_offset, view_length, stride) = self.view_span(view)?;
            let offset = index_of(&acc, "byteOffset").unwrap_or(0);
            let stride = stride.unwrap_or(layout.element);
            if !span_fits(
                buffer_len,
                view_offset,
                view_length,
                offset,
                stride.max(layout.element),
                layout.count,
                layout.last,
            ) {
                return None;
            }
            let buffer = index_of(&self.list("bufferViews")[view], "buffer")?;
            let bytes = self.buffers.get(buffer)?.as_ref()?;
            for e in 0..layout.count {
                let start = view_offset + offset + e * stride;
                for c in 0..layout.comps {
                    values[e * layout.comps + c] =
                        layout.read(bytes, start + layout.component_offset(c));
                }
            }
        }
        if let Some(sparse) = acc.get("sparse") {
            let n = index_of(sparse, "count")?;
            if n == 0 || n > layout.count {
                return None;
            }
            let ind = sparse.get("indices")?;
            let ind_layout = Layout {
                component: ind.get("componentType")?.as_u64()?,
                size: component_size(ind.get("componentType")?.as_u64()?)?,
                comps: 1,
                rows: None,
                count: n,
                normalized: false,
                element: component_size(ind.get("componentType")?.as_u64()?)?,
                last: component_size(ind.get("componentType")?.as_u64()?)?,
            };
            let val = sparse.get("values")?;
            let read_span = |w: &Walker, part: &Value, element: usize| -> Option<(usize, usize)> {
                let view = index_of(part, "bufferView")?;
                let (len, vo, vl, _) = w.view_span(view)?;
                let off = index_of(part, "byteOffset").unwrap_or(0);
                span_fits(len, vo, vl, off, element, n, element).then_some((view, vo + off))
            };
            let (iv, istart) = read_span(self, ind, ind_layout.element)?;
            let (vv, vstart) = read_span(self, val, layout.element)?;
            let views = self.list("bufferViews");
            let ib = index_of(&views[iv], "buffer")?;
            let vb = index_of(&views[vv], "buffer")?;
            let ibytes = self.buffers.get(ib)?.as_ref()?;
            let vbytes = self.buffers.get(vb)?.as_ref()?;
            let mut last: Option<usize> = None;
            let at = format!("/accessors/{index}/sparse");
            let mut problems = Vec::new();
            for k in 0..n {
                let target = ind_layout.read(ibytes, istart + k * ind_layout.element) as usize;
                if last.is_some_and(|l| target <= l) {
                    problems.push((
                        "ACCESSOR_SPARSE_INDICES_NON_INCREASING",
                        format!("sparse index {k} ({target}) does not increase"),
                    ));
                }
                last = Some(target);
                if target >= layout.count {
                    problems.push((
                        "ACCESSOR_SPARSE_INDEX_OOB",
                        format!("sparse index {target} >= count {}", layout.count),
                    ));
                    continue;
                }
                for c in 0..layout.comps {
                    values[target * layout.comps + c] = layout.read(
                        vbytes,
                        vstart + k * layout.element + layout.component_offset(c),
                    );
                }
            }
            for (code, message) in problems {
                self.f.error(code, at.clone(), message);
            }
        }
        Some(values)
    }

    /// Non-finite floats and min/max against the data.
    fn accessor_data(&mut self, index: usize, layout: &Layout, at: &str) {
        let acc = self.list("accessors")[index].clone();
        let min = numbers(&acc, "min");
        let max = numbers(&acc, "max");
        for (key, bound) in [("min", &min), ("max", &max)] {
            if bound.as_ref().is_some_and(|b| b.len() != layout.comps) {
                self.f.error(
                    "ACCESSOR_MIN_MAX_COUNT",
                    format!("{at}/{key}"),
                    format!("{key} must have {} entries", layout.comps),
                );
            }
        }
        let Some(values) = self.values(index) else {
            return;
        };
        if layout.component == 5126 {
            if let Some(bad) = values.iter().position(|v| !v.is_finite()) {
                self.f.error(
                    "ACCESSOR_INVALID_FLOAT",
                    at.to_string(),
                    format!("element {} holds NaN or infinity", bad / layout.comps),
                );
                return;
            }
        }
        let comps = layout.comps;
        let mut actual_min = vec![f64::INFINITY; comps];
        let mut actual_max = vec![f64::NEG_INFINITY; comps];
        for element in values.chunks_exact(comps) {
            for c in 0..comps {
                actual_min[c] = actual_min[c].min(element[c]);
                actual_max[c] = actual_max[c].max(element[c]);
            }
        }
        let as_stored = |v: f64| {
            if layout.component == 5126 {
                v as f32 as f64
            } else {
                v
            }
        };
        if let Some(min) = min.filter(|m| m.len() == comps) {
            for c in 0..comps {
                let declared = as_stored(min[c]);
                if actual_min[c] < declared {
                    self.f.error(
                        "ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND",
                        format!("{at}/min/{c}"),
                        format!(
                            "a value {} is below the declared min {}",
                            actual_min[c], min[c]
                        ),
                    );
                }
                if actual_min[c] != declared {
                    self.f.error(
                        "ACCESSOR_MIN_MISMATCH",
                        format!("{at}/min/{c}"),
                        format!(
                            "declared min {} but the data's is {}",
                            min[c], actual_min[c]
                        ),
                    );
                }
            }
        }
        if let Some(max) = max.filter(|m| m.len() == comps) {
            for c in 0..comps {
                let declared = as_stored(max[c]);
                if actual_max[c] > declared {
                    self.f.error(
                        "ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND",
                        format!("{at}/max/{c}"),
                        format!(
                            "a value {} is above the declared max {}",
                            actual_max[c], max[c]
                        ),
                    );
                }
                if actual_max[c] != declared {
                    self.f.error(
                        "ACCESSOR_MAX_MISMATCH",
                        format!("{at}/max/{c}"),
                        format!(
                            "declared max {} but the data's is {}",
                            max[c], actual_max[c]
                        ),
                    );
                }
            }
        }
    }

    fn layout(&self, accessor: usize) -> Option<Layout> {
        Layout::of(self.list("accessors").get(accessor)?)
    }

    fn view_of(&self, accessor: usize) -> Option<Value> {
        let view = index_of(self.list("accessors").get(accessor)?, "bufferView")?;
        self.list("bufferViews").get(view).cloned()
    }

    fn meshes(&mut self) {
        let meshes = self.list("meshes").to_vec();
        let quantized = self
            .list("extensionsUsed")
            .iter()
            .any(|e| e.as_str() == Some("KHR_mesh_quantization"));
        let mut vertex_views: HashMap<usize, usize> = HashMap::new();
        let mut index_views: HashSet<usize> = HashSet::new();
        for (m, mesh) in meshes.iter().enumerate() {
            let prims = array(mesh, "primitives");
            let mut targets_count = None;
            for (p, prim) in prims.iter().enumerate() {
                let at = format!("/meshes/{m}/primitives/{p}");
                let attributes = prim
                    .get("attributes")
                    .and_then(Value::as_object)
                    .cloned()
                    .unwrap_or_default();
                let mut count = None;
                let mut sets: HashMap<&str, Vec<usize>> = HashMap::new();
                for (name, acc) in &attributes {
                    let aat = format!("{at}/attributes/{}", escape(name));
                    let semantic = name.split_once('_').filter(|(base, n)| {
                        matches!(*base, "TEXCOORD" | "COLOR" | "JOINTS" | "WEIGHTS")
                            && !n.is_empty()
                            && n.bytes().all(|c| c.is_ascii_digit())
                            && (n.len() == 1 || !n.starts_with('0'))
                    });
                    if let Some((base, n)) = semantic {
                        if let Ok(n) = n.parse::<usize>() {
                            let base = match base {
                                "TEXCOORD" => "TEXCOORD",
                                "COLOR" => "COLOR",
                                "JOINTS" => "JOINTS",
                                _ => "WEIGHTS",
                            };
                            sets.entry(base).or_default().push(n);
                        }
                    } else if !matches!(name.as_str(), "POSITION" | "NORMAL" | "TANGENT")
                        && !name.starts_with('_')
                    {
                        self.f.error(
                            "MESH_PRIMITIVE_INVALID_ATTRIBUTE",
                            aat.clone(),
                            format!("'{name}' is not a valid attribute semantic"),
                        );
                    }
                    let Some(acc) = acc.as_u64().and_then(|a| usize::try_from(a).ok()) else {
                        continue;
                    };
                    let Some(layout) = self.layout(acc) else {
                        continue;
                    };
                    if count.is_some_and(|c| c != layout.count) {
                        self.f.error(
                            "MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT",
                            aat.clone(),
                            "attribute accessors have different counts",
                        );
                    }
                    count.get_or_insert(layout.count);
                    if layout.component == 5125 {
                        self.f.error(
                            "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT",
                            aat.clone(),
                            "vertex attributes cannot be UNSIGNED_INT",
                        );
                    }
                    let float_vec = |n: usize| layout.comps == n && layout.rows.is_none();
                    let format_ok = match name.as_str() {
                        "POSITION" => float_vec(3) && (layout.component == 5126 || quantized),
                        "NORMAL" => float_vec(3) && (layout.component == 5126 || quantized),
                        "TANGENT" => float_vec(4) && (layout.component == 5126 || quantized),
                        _ => true,
                    };
                    if !format_ok {
                        self.f.error(
                            "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT",
                            aat.clone(),
                            format!("invalid accessor format for {name}"),
                        );
                    }
                    let acc_json = self.list("accessors")[acc].clone();
                    if name == "POSITION"
                        && (acc_json.get("min").is_none() || acc_json.get("max").is_none())
                    {
                        self.f.error(
                            "MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS",
                            aat.clone(),
                            "POSITION accessors must have min and max",
                        );
                    }
                    if let Some(view_index) = index_of(&acc_json, "bufferView") {
                        *vertex_views.entry(view_index).or_insert(0) += 1;
                        if let Some(view) = self.view_of(acc) {
                            let total = index_of(&view, "byteOffset").unwrap_or(0)
                                + index_of(&acc_json, "byteOffset").unwrap_or(0);
                            if !total.is_multiple_of(4) {
                                self.f.error(
                                    "MESH_PRIMITIVE_ACCESSOR_UNALIGNED",
                                    aat.clone(),
                                    "vertex attribute data must start on a 4-byte boundary",
                                );
                            }
                            if view.get("target").and_then(Value::as_u64) == Some(34963) {
                                self.f.error(
                                    "BUFFER_VIEW_TARGET_OVERRIDE",
                                    aat.clone(),
                                    "an index buffer view is used for vertex data",
                                );
                            }
                        }
                    }
                    self.attribute_data(name, acc, &layout, &aat);
                }
                for (base, mut ns) in sets {
                    ns.sort_unstable();
                    if ns.iter().enumerate().any(|(i, &n)| i != n) {
                        self.f.error(
                            "MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY",
                            format!("{at}/attributes"),
                            format!("{base}_n sets are not numbered 0, 1, 2, ..."),
                        );
                    }
                }
                let has = |k: &str| attributes.contains_key(k);
                let joints = attributes
                    .keys()
                    .filter(|k| k.starts_with("JOINTS_"))
                    .count();
                let weights = attributes
                    .keys()
                    .filter(|k| k.starts_with("WEIGHTS_"))
                    .count();
                if joints != weights {
                    self.f.error(
                        "MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH",
                        format!("{at}/attributes"),
                        "JOINTS_n and WEIGHTS_n come in pairs",
                    );
                }
                if !has("POSITION") {
                    self.f.warn(
                        "MESH_PRIMITIVE_NO_POSITION",
                        format!("{at}/attributes"),
                        "no POSITION: nothing is drawn",
                    );
                }
                if has("TANGENT") && !has("NORMAL") {
                    self.f.warn(
                        "MESH_PRIMITIVE_TANGENT_WITHOUT_NORMAL",
                        format!("{at}/attributes"),
                        "TANGENT without NORMAL",
                    );
                }
                let texcoords = attributes
                    .keys()
                    .filter(|k| k.starts_with("TEXCOORD_"))
                    .count();
                if let Some(material) =
                    index_of(prim, "material").and_then(|i| self.list("materials").get(i))
                {
                    let needed = max_tex_coord(material);
                    if needed.is_some_and(|n| n >= texcoords) {
                        self.f.error(
                            "MESH_PRIMITIVE_TOO_FEW_TEXCOORDS",
                            at.clone(),
                            "the material reads a TEXCOORD set the primitive does not have",
                        );
                    }
                }
                let mode = prim.get("mode").and_then(Value::as_u64).unwrap_or(4);
                if let Some(indices) = index_of(prim, "indices") {
                    if let Some(view) = index_of(
                        &self
                            .list("accessors")
                            .get(indices)
                            .cloned()
                            .unwrap_or_default(),
                        "bufferView",
                    ) {
                        index_views.insert(view);
                    }
                    self.indices(indices, count, mode, &format!("{at}/indices"));
                } else if let Some(count) = count {
                    self.mode_count(mode, count, &at);
                }
                let targets = array(prim, "targets");
                if targets_count.is_some_and(|t| t != targets.len()) {
                    self.f.error(
                        "MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT",
                        format!("{at}/targets"),
                        "primitives of a mesh have different numbers of morph targets",
                    );
                }
                targets_count.get_or_insert(targets.len());
                for (t, target) in targets.iter().enumerate() {
                    let Some(target) = target.as_object() else {
                        continue;
                    };
                    for (name, acc) in target {
                        let tat = format!("{at}/targets/{t}/{}", escape(name));
                        if !attributes.contains_key(name) {
                            self.f.error(
                                "MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR",
                                tat.clone(),
                                format!("morph target {name} has no base attribute"),
                            );
                        }
                        let Some(acc) = acc.as_u64().and_then(|a| usize::try_from(a).ok()) else {
                            continue;
                        };
                        if let Some(layout) = self.layout(acc) {
                            if count.is_some_and(|c| c != layout.count) {
                                self.f.error(
                                    "MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT",
                                    tat.clone(),
                                    "morph target accessor count differs from the base",
                                );
                            }
                        }
                        let acc_json = self.list("accessors").get(acc).cloned().unwrap_or_default();
                        if name == "POSITION"
                            && (acc_json.get("min").is_none() || acc_json.get("max").is_none())
                        {
                            self.f.error(
                                "MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS",
                                tat.clone(),
                                "morph POSITION accessors must have min and max",
                            );
                        }
                        if let Some(view) = self.view_of(acc) {
                            if view.get("target").and_then(Value::as_u64) == Some(34963) {
                                self.f.error(
                                    "BUFFER_VIEW_TARGET_OVERRIDE",
                                    tat.clone(),
                                    "an index buffer view is used for vertex data",
                                );
                            }
                        }
                    }
                }
            }
            if let (Some(weights), Some(targets)) =
                (mesh.get("weights").and_then(Value::as_array), targets_count)
            {
                if weights.len() != targets {
                    self.f.error(
                        "MESH_INVALID_WEIGHTS_COUNT",
                        format!("/meshes/{m}/weights"),
                        format!("{} weights for {targets} morph targets", weights.len()),
                    );
                }
            }
        }
        for (view, users) in vertex_views {
            let Some(v) = self.list("bufferViews").get(view).cloned() else {
                continue;
            };
            if users > 1 && v.get("byteStride").is_none() {
                self.f.error(
                    "MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE",
                    format!("/bufferViews/{view}"),
                    "a buffer view shared by vertex attributes needs a byteStride",
                );
            }
            if index_views.contains(&view)
                || v.get("target").and_then(Value::as_u64) == Some(34963) && users > 0
            {
                self.f.error(
                    "BUFFER_VIEW_TARGET_OVERRIDE",
                    format!("/bufferViews/{view}"),
                    "the view is used both for vertices and for indices",
                );
            }
        }
        for view in index_views {
            if let Some(v) = self.list("bufferViews").get(view) {
                if v.get("target").and_then(Value::as_u64) == Some(34962) {
                    self.f.error(
                        "BUFFER_VIEW_TARGET_OVERRIDE",
                        format!("/bufferViews/{view}"),
                        "a vertex buffer view is used for indices",
                    );
                }
            }
        }
    }

    /// Value checks on normals, tangents, colours and skin weights.
    fn attribute_data(&mut self, name: &str, acc: usize, layout: &Layout, at: &str) {
        if layout.component != 5126 {
            return;
        }
        let check = |n: &str| name == n || name.starts_with(&format!("{n}_"));
        if !(check("NORMAL") || check("TANGENT") || check("COLOR") || check("WEIGHTS")) {
            return;
        }
        let Some(values) = self.values(acc) else {
            return;
        };
        let comps = layout.comps;
        for (e, v) in values.chunks_exact(comps).enumerate() {
            let problem = if name == "NORMAL" || name == "TANGENT" {
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if (len - 1.0).abs() > 5e-4 {
                    Some((
                        "ACCESSOR_VECTOR3_NON_UNIT",
                        format!("element {e} has length {len}"),
                    ))
                } else if name == "TANGENT" && comps == 4 && v[3] != 1.0 && v[3] != -1.0 {
                    Some((
                        "ACCESSOR_INVALID_SIGN",
                        format!("element {e} has w = {}", v[3]),
                    ))
                } else {
                    None
                }
            } else if check("COLOR") {
                v.iter().any(|c| !(0.0..=1.0).contains(c)).then(|| {
                    (
                        "ACCESSOR_NON_CLAMPED",
                        format!("element {e} is outside [0, 1]"),
                    )
                })
            } else if v.iter().any(|w| *w < 0.0) {
                Some((
                    "ACCESSOR_WEIGHTS_NEGATIVE",
                    format!("element {e} has a negative weight"),
                ))
            } else {
                None
            };
            if let Some((code, message)) = problem {
                self.f.error(code, at.to_string(), message);
                return;
            }
        }
        if check("WEIGHTS") && name == "WEIGHTS_0" {
            let sum_ok = values
                .chunks_exact(comps)
                .all(|v| (v.iter().sum::<f64>() - 1.0).abs() <= 2e-3 || comps != 4);
            if !sum_ok {
                self.f.error(
                    "ACCESSOR_WEIGHTS_NON_NORMALIZED",
                    at.to_string(),
                    "skin weights do not add up to 1",
                );
            }
        }
    }

    fn mode_count(&mut self, mode: u64, count: usize, at: &str) {
        let bad = match mode {
            4 => !count.is_multiple_of(3),
            5 | 6 => count < 3,
            1 => !count.is_multiple_of(2),
            3 => count < 2,
            2 => count < 2,
            _ => false,
        };
        if bad {
            self.f.warn(
                "MESH_PRIMITIVE_INCOMPATIBLE_MODE",
                at.to_string(),
                format!("{count} vertices do not make whole primitives of mode {mode}"),
            );
        }
    }

    fn indices(&mut self, indices: usize, vertices: Option<usize>, mode: u64, at: &str) {
        let Some(layout) = self.layout(indices) else {
            return;
        };
        if layout.comps != 1 || !matches!(layout.component, 5121 | 5123 | 5125) {
            self.f.error(
                "MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT",
                at.to_string(),
                "indices must be SCALAR unsigned integers",
            );
            return;
        }
        if let Some(view) = self.view_of(indices) {
            if view.get("byteStride").is_some() {
                self.f.error(
                    "MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE",
                    at.to_string(),
                    "the indices' buffer view has a byteStride",
                );
            }
        }
        self.mode_count(mode, layout.count, at);
        let Some(values) = self.values(indices) else {
            return;
        };
        let restart = match layout.component {
            5121 => 255.0,
            5123 => 65535.0,
            _ => 4294967295.0,
        };
        let mut oob = 0usize;
        let mut first_oob = None;
        let mut restarts = 0usize;
        for &v in values.iter() {
            if v == restart {
                restarts += 1;
            } else if vertices.is_some_and(|n| v as usize >= n) {
                oob += 1;
                first_oob.get_or_insert(v);
            }
        }
        if restarts > 0 {
            self.f.error(
                "ACCESSOR_INDEX_PRIMITIVE_RESTART",
                format!("/accessors/{indices}"),
                format!("{restarts} indices hold the primitive restart value {restart}"),
            );
        }
        if let (Some(first), Some(n)) = (first_oob, vertices) {
            self.f.error(
                "ACCESSOR_INDEX_OOB",
                format!("/accessors/{indices}"),
                format!("{oob} indices out of range (first: {first}; {n} vertices)"),
            );
        }
    }

    /// Hierarchy, transforms, dependencies and the quadric extension; returns the number of
    /// triangles the default scene expands to (for the memory estimate).
    fn nodes_and_scenes(&mut self) -> u64 {
        let nodes = self.list("nodes").to_vec();
        let n = nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (i, node) in nodes.iter().enumerate() {
            for (k, c) in array(node, "children").iter().enumerate() {
                let Some(c) = c
                    .as_u64()
                    .and_then(|c| usize::try_from(c).ok())
                    .filter(|&c| c < n)
                else {
                    continue;
                };
                children[i].push(c);
                if let Some(p) = parent[c] {
                    if p != i {
                        self.f.error(
                            "NODE_PARENT_OVERRIDE",
                            format!("/nodes/{i}/children/{k}"),
                            format!("node {c} is already a child of node {p}"),
                        );
                    }
                } else {
                    parent[c] = Some(i);
                }
            }
        }
        // Cycles: a colouring depth-first search, iterative.
        let mut state = vec![0u8; n];
        for start in 0..n {
            if state[start] != 0 {
                continue;
            }
            let mut stack = vec![(start, 0usize)];
            state[start] = 1;
            while let Some(&mut (node, ref mut next)) = stack.last_mut() {
                if let Some(&c) = children[node].get(*next) {
                    *next += 1;
                    match state[c] {
                        0 => {
                            state[c] = 1;
                            stack.push((c, 0));
                        }
                        1 => self.f.error(
                            "NODE_LOOP",
                            format!("/nodes/{node}/children"),
                            format!("node {c} is its own ancestor"),
                        ),
                        _ => {}
                    }
                } else {
                    state[node] = 2;
                    stack.pop();
                }
            }
        }
        let meshes = self.list("meshes").to_vec();
        let mesh_targets = |m: usize| -> usize {
            meshes
                .get(m)
                .map(|mesh| {
                    array(mesh, "primitives")
                        .first()
                        .map_or(0, |p| array(p, "targets").len())
                })
                .unwrap_or(0)
        };
        let mesh_skinned = |m: usize| -> bool {
            meshes.get(m).is_some_and(|mesh| {
                array(mesh, "primitives").iter().any(|p| {
                    p.get("attributes")
                        .and_then(Value::as_object)
                        .is_some_and(|a| a.contains_key("JOINTS_0"))
                })
            })
        };
        let mut locals = vec![DMat4::IDENTITY; n];
        for (i, node) in nodes.iter().enumerate() {
            let at = format!("/nodes/{i}");
            locals[i] = self.node_transform(node, &at);
            let mesh = index_of(node, "mesh");
            if node.get("skin").is_some() {
                match mesh {
                    None => self.f.error(
                        "UNSATISFIED_DEPENDENCY",
                        format!("{at}/skin"),
                        "skin without mesh",
                    ),
                    Some(m) if m < meshes.len() && !mesh_skinned(m) => self.f.error(
                        "NODE_SKIN_WITH_NON_SKINNED_MESH",
                        at.clone(),
                        "the node has a skin but its mesh has no JOINTS_0/WEIGHTS_0",
                    ),
                    _ => {}
                }
            } else if mesh.is_some_and(|m| m < meshes.len() && mesh_skinned(m)) {
                self.f.warn(
                    "NODE_SKINNED_MESH_WITHOUT_SKIN",
                    at.clone(),
                    "a skinned mesh on a node without a skin",
                );
            }
            if let Some(weights) = node.get("weights").and_then(Value::as_array) {
                match mesh {
                    None => self.f.error(
                        "UNSATISFIED_DEPENDENCY",
                        format!("{at}/weights"),
                        "weights without mesh",
                    ),
                    Some(m) if m < meshes.len() && weights.len() != mesh_targets(m) => {
                        self.f.error(
                            "NODE_WEIGHTS_INVALID",
                            format!("{at}/weights"),
                            format!(
                                "{} weights for {} morph targets",
                                weights.len(),
                                mesh_targets(m)
                            ),
                        )
                    }
                    _ => {}
                }
            }
            if let Some(ext) = node
                .get("extensions")
                .and_then(|e| e.get(QUADRIC_EXTENSION))
            {
                let spec =
                    QuadricSpec::from_gltf_extension(ext).and_then(|s| s.validate().map(|()| s));
                if let Err(e) = spec {
                    self.f.error(
                        "QUADRIC_INVALID",
                        format!("{at}/extensions/{QUADRIC_EXTENSION}"),
                        format!("{QUADRIC_EXTENSION}: {e}"),
                    );
                }
            }
        }
        // Scenes: roots must be roots; estimate the triangles drawn.
        let scenes = self.list("scenes").to_vec();
        for (s, scene) in scenes.iter().enumerate() {
            for (k, node) in array(scene, "nodes").iter().enumerate() {
                if let Some(node) = node
                    .as_u64()
                    .and_then(|v| usize::try_from(v).ok())
                    .filter(|&v| v < n)
                {
                    if parent[node].is_some() {
                        self.f.error(
                            "SCENE_NON_ROOT_NODE",
                            format!("/scenes/{s}/nodes/{k}"),
                            format!("node {node} has a parent"),
                        );
                    }
                }
            }
        }
        let roots: Vec<usize> = match index_of(&Value::Object(self.root.clone()), "scene")
            .or(if scenes.is_empty() { None } else { Some(0) })
            .and_then(|s| scenes.get(s))
        {
            Some(scene) => array(scene, "nodes")
                .iter()
                .filter_map(|v| v.as_u64().and_then(|v| usize::try_from(v).ok()))
                .filter(|&v| v < n)
                .collect(),
            None => (0..n).filter(|&i| parent[i].is_none()).collect(),
        };
        let mesh_triangles: Vec<u64> = meshes
            .iter()
            .map(|mesh| {
                array(mesh, "primitives")
                    .iter()
                    .map(|p| {
                        let count = index_of(p, "indices")
                            .or_else(|| p.get("attributes").and_then(|a| index_of(a, "POSITION")))
                            .and_then(|a| self.layout(a))
                            .map_or(0, |l| l.count as u64);
                        count / 3 + 2
                    })
                    .sum()
            })
            .collect();
        let mut triangles = 0u64;
        let mut stack: Vec<(usize, usize, DMat4)> =
            roots.iter().map(|&r| (r, 0, DMat4::IDENTITY)).collect();
        let mut visits = 0u64;
        let mut reported_depth = false;
        let mut reported_world = HashSet::new();
        while let Some((node, depth, parent_world)) = stack.pop() {
            visits += 1;
            if visits > 10_000_000 {
                self.f.error(
                    "ASSET_TOO_LARGE",
                    "/nodes",
                    "the node hierarchy expands to more than 10 million instances",
                );
                self.importable = false;
                break;
            }
            if depth > MAX_NODE_DEPTH {
                if !reported_depth {
                    reported_depth = true;
                    self.f.error(
                        "NODE_HIERARCHY_TOO_DEEP",
                        format!("/nodes/{node}"),
                        format!("the hierarchy is deeper than {MAX_NODE_DEPTH} levels (or loops)"),
                    );
                    self.importable = false;
                }
                continue;
            }
            let world = parent_world * locals[node];
            if !world.is_finite() && reported_world.insert(node) {
                self.f.error(
                    "NODE_TRANSFORM_NOT_FINITE",
                    format!("/nodes/{node}"),
                    "the world transform overflows to infinity or NaN",
                );
            }
            if let Some(m) = index_of(&nodes[node], "mesh") {
                triangles = triangles.saturating_add(mesh_triangles.get(m).copied().unwrap_or(0));
            }
            for &c in &children[node] {
                stack.push((c, depth + 1, world));
            }
        }
        triangles
    }

    /// The local matrix of a node, reporting what is wrong with it (identity when unusable).
    fn node_transform(&mut self, node: &Value, at: &str) -> DMat4 {
        let read = |f: &mut Findings, key: &str, len: usize| -> Option<Vec<f64>> {
            let v = node.get(key)?;
            let list = v
                .as_array()
                .filter(|a| a.len() == len)
                .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>());
            match list {
                Some(list) if list.iter().all(|x| x.is_finite()) => Some(list),
                _ => {
                    f.error(
                        "VALUE_NOT_IN_RANGE",
                        format!("{at}/{key}"),
                        format!("expected {len} finite numbers"),
                    );
                    None
                }
            }
        };
        let has_trs = ["translation", "rotation", "scale"]
            .iter()
            .any(|k| node.get(*k).is_some());
        let matrix = read(self.f, "matrix", 16);
        let translation = read(self.f, "translation", 3);
        let rotation = read(self.f, "rotation", 4);
        let scale = read(self.f, "scale", 3);
        let local = if node.get("matrix").is_some() {
            if has_trs {
                self.f.error(
                    "NODE_MATRIX_TRS",
                    at.to_string(),
                    "a node has both matrix and translation/rotation/scale",
                );
            }
            let Some(m) = matrix else {
                return DMat4::IDENTITY;
            };
            let m = DMat4::from_cols_slice(&m);
            let row3 = m.row(3);
            let upper = glam::DMat3::from_mat4(m);
            let gram = upper.transpose() * upper;
            let off = [gram.x_axis.y, gram.x_axis.z, gram.y_axis.z];
            let scale2 = gram
                .x_axis
                .x
                .max(gram.y_axis.y)
                .max(gram.z_axis.z)
                .max(f64::MIN_POSITIVE);
            if row3 != glam::DVec4::W || off.iter().any(|o| o.abs() > 1e-5 * scale2) {
                self.f.error(
                    "NODE_MATRIX_NON_TRS",
                    format!("{at}/matrix"),
                    "the matrix is not a translation-rotation-scale",
                );
            }
            m
        } else {
            let t = translation.map_or(DVec3::ZERO, |v| DVec3::from_slice(&v));
            let s = scale.map_or(DVec3::ONE, |v| DVec3::from_slice(&v));
            let r = match rotation {
                None => DQuat::IDENTITY,
                Some(q) => {
                    let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
                    if (q.length() - 1.0).abs() > 5e-6 {
                        self.f.error(
                            "ROTATION_NON_UNIT",
                            format!("{at}/rotation"),
                            format!("the rotation quaternion has length {}", q.length()),
                        );
                    }
                    if q.length_squared() > 0.0 {
                        q.normalize()
                    } else {
                        DQuat::IDENTITY
                    }
                }
            };
            DMat4::from_scale_rotation_translation(s, r, t)
        };
        let det = local.determinant();
        if local.is_finite() && (det == 0.0 || !det.is_finite()) {
            self.f.warn(
                "NODE_TRANSFORM_NOT_INVERTIBLE",
                at.to_string(),
                "the node's transform is singular (a zero scale?): its subtree collapses",
            );
        }
        local
    }

    fn cameras(&mut self) {
        for (i, camera) in self.list("cameras").to_vec().iter().enumerate() {
            let at = format!("/cameras/{i}");
            let kind = camera.get("type").and_then(Value::as_str);
            let p = camera.get("perspective");
            let o = camera.get("orthographic");
            if p.is_some() && o.is_some() {
                self.f.error(
                    "ONE_OF_MISMATCH",
                    at.clone(),
                    "both perspective and orthographic",
                );
            }
            let num = |v: Option<&Value>, k: &str| v.and_then(|v| v.get(k)).and_then(Value::as_f64);
            match kind {
                Some("perspective") => {
                    if p.is_none() {
                        self.f
                            .error("UNDEFINED_PROPERTY", format!("{at}/perspective"), "missing");
                    }
                    let znear = num(p, "znear");
                    let zfar = num(p, "zfar");
                    let yfov = num(p, "yfov");
                    if znear.is_some_and(|z| !(z > 0.0 && z.is_finite())) {
                        self.f.error(
                            "VALUE_NOT_IN_RANGE",
                            format!("{at}/perspective/znear"),
                            "znear must be positive and finite",
                        );
                    }
                    if yfov.is_some_and(|y| !(y > 0.0 && y.is_finite())) {
                        self.f.error(
                            "VALUE_NOT_IN_RANGE",
                            format!("{at}/perspective/yfov"),
                            "yfov must be positive",
                        );
                    } else if yfov.is_some_and(|y| y >= std::f64::consts::PI) {
                        self.f.warn(
                            "CAMERA_YFOV_GEQUAL_PI",
                            format!("{at}/perspective/yfov"),
                            "yfov is at least pi",
                        );
                    }
                    if let (Some(n), Some(f)) = (znear, zfar) {
                        if f <= n {
                            self.f.error(
                                "CAMERA_ZFAR_LEQUAL_ZNEAR",
                                format!("{at}/perspective/zfar"),
                                "zfar is not beyond znear",
                            );
                        }
                    }
                }
                Some("orthographic") => {
                    if o.is_none() {
                        self.f.error(
                            "UNDEFINED_PROPERTY",
                            format!("{at}/orthographic"),
                            "missing",
                        );
                    }
                    let (x, y) = (num(o, "xmag"), num(o, "ymag"));
                    if x == Some(0.0) || y == Some(0.0) {
                        self.f.error(
                            "CAMERA_XMAG_YMAG_ZERO",
                            format!("{at}/orthographic"),
                            "xmag or ymag is zero",
                        );
                    }
                    if x.is_some_and(|v| v < 0.0) || y.is_some_and(|v| v < 0.0) {
                        self.f.warn(
                            "CAMERA_XMAG_YMAG_NEGATIVE",
                            format!("{at}/orthographic"),
                            "xmag or ymag is negative",
                        );
                    }
                    if let (Some(n), Some(f)) = (num(o, "znear"), num(o, "zfar")) {
                        if f <= n {
                            self.f.error(
                                "CAMERA_ZFAR_LEQUAL_ZNEAR",
                                format!("{at}/orthographic/zfar"),
                                "zfar is not beyond znear",
                            );
                        }
                    }
                }
                _ => {}
            }
        }
    }

    fn images(&mut self) {
        for (i, image) in self.list("images").to_vec().iter().enumerate() {
            let at = format!("/images/{i}");
            if let Some(uri) = image.get("uri").and_then(Value::as_str) {
                if let Some(data) = self.external(&format!("{at}/uri"), uri, false, 0) {
                    self.image_bytes(&data, &at);
                }
            }
            if let Some(view) = index_of(image, "bufferView") {
                if image.get("mimeType").is_none() {
                    self.f.error(
                        "UNSATISFIED_DEPENDENCY",
                        format!("{at}/mimeType"),
                        "an image in a buffer view needs a mimeType",
                    );
                }
                if let Some(v) = self.list("bufferViews").get(view).cloned() {
                    if v.get("byteStride").is_some() {
                        self.f.error(
                            "IMAGE_BUFFER_VIEW_WITH_BYTESTRIDE",
                            format!("{at}/bufferView"),
                            "an image's buffer view has a byteStride",
                        );
                    }
                    if let Some((len, off, vlen, _)) = self.view_span(view) {
                        if let Some(buffer) = index_of(&v, "buffer") {
                            if off.checked_add(vlen).is_some_and(|end| end <= len) {
                                let data = self.buffers[buffer]
                                    .as_ref()
                                    .map(|b| b[off..off + vlen].to_vec());
                                if let Some(data) = data {
                                    self.image_bytes(&data, &at);
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// Sniffs embedded image data (it is never decoded).
    fn image_bytes(&mut self, data: &[u8], at: &str) {
        const PNG: &[u8] = b"\x89PNG\r\n\x1a\n";
        if data.starts_with(PNG) {
            if data.len() < 33 && data.len() < 64 {
                self.f.error(
                    "IMAGE_UNEXPECTED_EOS",
                    at.to_string(),
                    "the PNG data ends early",
                );
            } else if &data[12..16] != b"IHDR" {
                self.f.error(
                    "IMAGE_DATA_INVALID",
                    at.to_string(),
                    "the PNG data has no IHDR chunk",
                );
            }
        } else if data.starts_with(&[0xFF, 0xD8]) {
            if data.len() < 4 {
                self.f.error(
                    "IMAGE_UNEXPECTED_EOS",
                    at.to_string(),
                    "the JPEG data ends early",
                );
            }
        } else if data.len() >= 4 && &data[..4] == b"RIFF" || data.starts_with(b"\xABKTX") {
        } else if data.len() >= 8 && data[..8].starts_with(&PNG[..4]) {
            self.f
                .error("IMAGE_DATA_INVALID", at.to_string(), "broken PNG signature");
        } else {
            self.f.warn(
                "IMAGE_UNRECOGNIZED_FORMAT",
                at.to_string(),
                "not PNG, JPEG, WebP or KTX2 data",
            );
        }
    }

    fn animations(&mut self) {
        let nodes = self.list("nodes").to_vec();
        for (a, anim) in self.list("animations").to_vec().iter().enumerate() {
            let samplers = array(anim, "samplers").to_vec();
            let mut targets = HashSet::new();
            for (c, channel) in array(anim, "channels").iter().enumerate() {
                let at = format!("/animations/{a}/channels/{c}");
                let target = channel.get("target");
                let node = target.and_then(|t| index_of(t, "node"));
                if let Some(bad) = node.filter(|&k| k >= nodes.len()) {
                    self.f.error(
                        "UNRESOLVED_REFERENCE",
                        format!("{at}/target/node"),
                        format!("node {bad} does not exist"),
                    );
                }
                if let Some(bad) = index_of(channel, "sampler").filter(|&k| k >= samplers.len()) {
                    self.f.error(
                        "UNRESOLVED_REFERENCE",
                        format!("{at}/sampler"),
                        format!("sampler {bad} does not exist"),
                    );
                }
                let path = target.and_then(|t| t.get("path")).and_then(Value::as_str);
                if let (Some(node), Some(path)) = (node, path) {
                    if !targets.insert((node, path.to_string())) {
                        self.f.error(
                            "ANIMATION_DUPLICATE_TARGETS",
                            format!("{at}/target"),
                            "two channels animate the same property",
                        );
                    }
                    if let Some(n) = nodes.get(node) {
                        if n.get("matrix").is_some() && path != "weights" {
                            self.f.error(
                                "ANIMATION_CHANNEL_TARGET_NODE_MATRIX",
                                format!("{at}/target/node"),
                                "an animated node cannot have a matrix",
                            );
                        }
                        if path == "weights" {
                            let morphs = index_of(n, "mesh")
                                .and_then(|m| self.list("meshes").get(m))
                                .is_some_and(|m| {
                                    array(m, "primitives")
                                        .iter()
                                        .any(|p| !array(p, "targets").is_empty())
                                });
                            if !morphs {
                                self.f.error(
                                    "ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS",
                                    format!("{at}/target/node"),
                                    "weights animated on a node without morph targets",
                                );
                            }
                        }
                    }
                }
                let Some(sampler) = index_of(channel, "sampler").and_then(|s| samplers.get(s))
                else {
                    continue;
                };
                let sat = format!(
                    "/animations/{a}/samplers/{}",
                    index_of(channel, "sampler").unwrap_or(0)
                );
                let cubic =
                    sampler.get("interpolation").and_then(Value::as_str) == Some("CUBICSPLINE");
                let input = index_of(sampler, "input");
                let output = index_of(sampler, "output");
                for acc in [input, output].into_iter().flatten() {
                    if self
                        .view_of(acc)
                        .is_some_and(|v| v.get("byteStride").is_some())
                    {
                        self.f.error(
                            "ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE",
                            sat.clone(),
                            "animation accessors cannot use a byteStride",
                        );
                    }
                }
                let in_layout = input.and_then(|i| self.layout(i));
                if let (Some(i), Some(l)) = (input, in_layout) {
                    if l.comps != 1 || l.component != 5126 {
                        self.f.error(
                            "ANIMATION_SAMPLER_INPUT_ACCESSOR_INVALID_FORMAT",
                            format!("{sat}/input"),
                            "input must be SCALAR float",
                        );
                    } else {
                        let acc = self.list("accessors")[i].clone();
                        if acc.get("min").is_none() || acc.get("max").is_none() {
                            self.f.error(
                                "ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS",
                                format!("{sat}/input"),
                                "input needs min and max",
                            );
                        }
                        if cubic && l.count < 2 {
                            self.f.error(
                                "ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS",
                                format!("{sat}/input"),
                                "CUBICSPLINE needs two keyframes",
                            );
                        }
                        if let Some(times) = self.values(i) {
                            if times.iter().any(|t| *t < 0.0) {
                                self.f.error(
                                    "ACCESSOR_ANIMATION_INPUT_NEGATIVE",
                                    format!("/accessors/{i}"),
                                    "negative key time",
                                );
                            }
                            if times.windows(2).any(|w| w[1] <= w[0]) {
                                self.f.error(
                                    "ACCESSOR_ANIMATION_INPUT_NON_INCREASING",
                                    format!("/accessors/{i}"),
                                    "key times do not increase",
                                );
                            }
                        }
                    }
                }
                if let (Some(o), Some(path)) = (output, path) {
                    let Some(l) = self.layout(o) else {
                        continue;
                    };
                    let ok = match path {
                        "translation" | "scale" => {
                            l.comps == 3 && l.rows.is_none() && l.component == 5126
                        }
                        "rotation" => {
                            l.comps == 4
                                && l.rows.is_none()
                                && (l.component == 5126 || l.normalized)
                        }
                        "weights" => l.comps == 1 && (l.component == 5126 || l.normalized),
                        _ => true,
                    };
                    if !ok {
                        self.f.error(
                            "ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_FORMAT",
                            format!("{sat}/output"),
                            format!("invalid output format for {path}"),
                        );
                    }
                    if let Some(inl) = in_layout {
                        let per = if cubic { 3 } else { 1 };
                        let morphs = if path == "weights" {
                            node.and_then(|n| nodes.get(n))
                                .and_then(|n| index_of(n, "mesh"))
                                .and_then(|m| self.list("meshes").get(m))
                                .and_then(|m| array(m, "primitives").first())
                                .map_or(1, |p| array(p, "targets").len().max(1))
                        } else {
                            1
                        };
                        if l.count != inl.count * per * morphs {
                            self.f.error(
                                "ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT",
                                format!("{sat}/output"),
                                format!("{} outputs for {} inputs", l.count, inl.count),
                            );
                        }
                    }
                    if path == "rotation" && l.component == 5126 && l.comps == 4 {
                        if let Some(q) = self.values(o) {
                            let bad = q.chunks_exact(4).enumerate().any(|(k, q)| {
                                let tangent = cubic && k % 3 != 1;
                                !tangent
                                    && ((q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
                                        .sqrt()
                                        - 1.0)
                                        .abs()
                                        > 5e-4
                            });
                            if bad {
                                self.f.error(
                                    "ACCESSOR_ANIMATION_SAMPLER_OUTPUT_NON_NORMALIZED_QUATERNION",
                                    format!("/accessors/{o}"),
                                    "rotation keys are not unit quaternions",
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    fn skins(&mut self) {
        let nodes = self.list("nodes").to_vec();
        let n = nodes.len();
        let mut parent = vec![None; n];
        for (i, node) in nodes.iter().enumerate() {
            for c in array(node, "children") {
                if let Some(c) = c
                    .as_u64()
                    .and_then(|c| usize::try_from(c).ok())
                    .filter(|&c| c < n)
                {
                    parent[c].get_or_insert(i);
                }
            }
        }
        let ancestors = |mut x: usize| {
            let mut list = vec![x];
            while let Some(p) = parent[x] {
                if list.contains(&p) || list.len() > MAX_NODE_DEPTH {
                    break;
                }
                list.push(p);
                x = p;
            }
            list
        };
        let in_scene: HashSet<usize> = {
            let mut set = HashSet::new();
            for scene in self.list("scenes") {
                for r in array(scene, "nodes").iter().filter_map(|v| v.as_u64()) {
                    let mut stack = vec![r as usize];
                    while let Some(x) = stack.pop() {
                        if x < n && set.insert(x) {
                            stack.extend(
                                array(&nodes[x], "children")
                                    .iter()
                                    .filter_map(|c| c.as_u64().map(|c| c as usize)),
                            );
                        }
                    }
                }
            }
            set
        };
        for (s, skin) in self.list("skins").to_vec().iter().enumerate() {
            let at = format!("/skins/{s}");
            let joints: Vec<usize> = array(skin, "joints")
                .iter()
                .filter_map(|j| j.as_u64().map(|j| j as usize))
                .filter(|&j| j < n)
                .collect();
            if let Some(ibm) = index_of(skin, "inverseBindMatrices") {
                if let Some(l) = self.layout(ibm) {
                    if l.comps != 16 || l.component != 5126 {
                        self.f.error(
                            "SKIN_IBM_INVALID_FORMAT",
                            format!("{at}/inverseBindMatrices"),
                            "inverse bind matrices must be MAT4 float",
                        );
                    } else {
                        if l.count < joints.len() {
                            self.f.error(
                                "INVALID_IBM_ACCESSOR_COUNT",
                                format!("{at}/inverseBindMatrices"),
                                "fewer inverse bind matrices than joints",
                            );
                        }
                        if let Some(m) = self.values(ibm) {
                            if m.chunks_exact(16)
                                .any(|m| m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0)
                            {
                                self.f.error(
                                    "ACCESSOR_INVALID_IBM",
                                    format!("/accessors/{ibm}"),
                                    "an inverse bind matrix is not affine",
                                );
                            }
                        }
                    }
                }
                if self
                    .view_of(ibm)
                    .is_some_and(|v| v.get("byteStride").is_some())
                {
                    self.f.error(
                        "SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE",
                        format!("{at}/inverseBindMatrices"),
                        "inverse bind matrices cannot use a byteStride",
                    );
                }
            }
            if joints.len() > 1 {
                let chains: Vec<Vec<usize>> = joints.iter().map(|&j| ancestors(j)).collect();
                let common = chains[0]
                    .iter()
                    .any(|a| chains.iter().all(|c| c.contains(a)));
                if !common {
                    self.f.error(
                        "SKIN_NO_COMMON_ROOT",
                        format!("{at}/joints"),
                        "the joints have no common root",
                    );
                }
            }
            if array(skin, "joints")
                .iter()
                .any(|j| j.as_u64().is_none_or(|j| j as usize >= n))
                && joints.len() > 1
            {
                self.f.error(
                    "SKIN_NO_COMMON_ROOT",
                    format!("{at}/joints"),
                    "a joint does not exist",
                );
            }
            if let Some(skeleton) = index_of(skin, "skeleton").filter(|&k| k < n) {
                if !joints.iter().all(|&j| ancestors(j).contains(&skeleton)) {
                    self.f.error(
                        "SKIN_SKELETON_INVALID",
                        format!("{at}/skeleton"),
                        "the skeleton is not a common root of the joints",
                    );
                }
            }
            if !joints.is_empty()
                && !self.list("scenes").is_empty()
                && joints.iter().all(|j| !in_scene.contains(j))
            {
                self.f.error(
                    "NODE_SKIN_NO_SCENE",
                    format!("{at}/joints"),
                    "no joint is in a scene",
                );
            }
        }
    }
}

/// The largest `texCoord` a material's textures read, if any.
fn max_tex_coord(v: &Value) -> Option<usize> {
    match v {
        Value::Object(map) => {
            let here = map
                .get("index")
                .filter(|_| map.len() <= 4)
                .map(|_| index_of(v, "texCoord").unwrap_or(0));
            map.iter()
                .filter(|(k, _)| *k != "extras")
                .filter_map(|(_, x)| max_tex_coord(x))
                .chain(here)
                .max()
        }
        _ => None,
    }
}

/// Standard base64 (padding optional); None when malformed.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers() {
        assert_eq!(
            json_pointer("meshes[0].primitives[1].indices"),
            "/meshes/0/primitives/1/indices"
        );
        assert_eq!(json_pointer("scene"), "/scene");
    }

    #[test]
    fn base64() {
        assert_eq!(base64_decode("aGVsbG8="), Some(b"hello".to_vec()));
        assert_eq!(base64_decode("aGVsbG8"), Some(b"hello".to_vec()));
        assert_eq!(base64_decode("a"), None);
        assert_eq!(base64_decode("a*bc"), None);
    }

    #[test]
    fn matrix_padding() {
        let acc: Value = serde_json::json!({"componentType": 5121, "type": "MAT3", "count": 1});
        let l = Layout::of(&acc).unwrap();
        assert_eq!(l.element, 12);
        assert_eq!(l.component_offset(3), 4);
    }
}
