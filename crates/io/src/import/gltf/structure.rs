//! The document's structure: properties the reader takes to be arrays or objects, and that a
//! file gives as another JSON type (`"primitives": {…}` where an array belongs). Read as
//! absent, such a property would silently drop geometry (a mesh without primitives, a node
//! without its matrix), so it is a TYPE_MISMATCH error, as the Khronos glTF-Validator's, and
//! the importer refuses the file (integrity rules, [`super::integrity`]).

use super::diagnostics::{Code, Sink};
use super::document::{escape, Document};
use serde_json::Value;

/// The JSON type a property must have.
#[derive(Clone, Copy)]
enum Kind {
    Array,
    Object,
}

impl Kind {
    fn holds(self, value: &Value) -> bool {
        match self {
            Kind::Array => value.is_array(),
            Kind::Object => value.is_object(),
        }
    }

    fn expected(self) -> &'static str {
        match self {
            Kind::Array => "expected an array",
            Kind::Object => "expected an object",
        }
    }
}

/// The top-level collections: arrays of objects.
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

/// Properties inside the collections' objects: the collection, the path below it (`*` for
/// every element of an array) and the type each must have. Per collection, because a name can
/// mean two things (`scale` is an array on a node but a number on a normal texture).
const PROPERTIES: &[(&str, &[&str], Kind)] = &[
    ("scenes", &["*", "nodes"], Kind::Array),
    ("nodes", &["*", "children"], Kind::Array),
    ("nodes", &["*", "matrix"], Kind::Array),
    ("nodes", &["*", "translation"], Kind::Array),
    ("nodes", &["*", "rotation"], Kind::Array),
    ("nodes", &["*", "weights"], Kind::Array),
    ("meshes", &["*", "weights"], Kind::Array),
    ("meshes", &["*", "primitives"], Kind::Array),
    ("meshes", &["*", "primitives", "*"], Kind::Object),
    (
        "meshes",
        &["*", "primitives", "*", "attributes"],
        Kind::Object,
    ),
    ("meshes", &["*", "primitives", "*", "targets"], Kind::Array),
    (
        "meshes",
        &["*", "primitives", "*", "targets", "*"],
        Kind::Object,
    ),
    ("skins", &["*", "joints"], Kind::Array),
    ("animations", &["*", "channels"], Kind::Array),
    ("animations", &["*", "channels", "*"], Kind::Object),
    (
        "animations",
        &["*", "channels", "*", "target"],
        Kind::Object,
    ),
    ("animations", &["*", "samplers"], Kind::Array),
    ("animations", &["*", "samplers", "*"], Kind::Object),
    ("accessors", &["*", "sparse"], Kind::Object),
    ("accessors", &["*", "min"], Kind::Array),
    ("accessors", &["*", "max"], Kind::Array),
];

/// Reports every property of the table above that has another JSON type.
pub fn check(doc: &Document, sink: &mut dyn Sink) {
    for &collection in COLLECTIONS {
        let Some(value) = doc.root().get(collection) else {
            continue;
        };
        let at = format!("/{collection}");
        if !value.is_array() {
            sink.error(Code::TypeMismatch, at, Kind::Array.expected());
            continue;
        }
        walk(value, &["*"], &at, Kind::Object, sink);
        for &(_, pattern, kind) in PROPERTIES.iter().filter(|p| p.0 == collection) {
            walk(value, pattern, &at, kind, sink);
        }
    }
}

/// Follows `pattern` from `value` (at pointer `at`) and reports where the end is not `kind`.
fn walk(value: &Value, pattern: &[&str], at: &str, kind: Kind, sink: &mut dyn Sink) {
    let Some((&step, rest)) = pattern.split_first() else {
        if !kind.holds(value) {
            sink.error(Code::TypeMismatch, at, kind.expected());
        }
        return;
    };
    if step == "*" {
        for (i, item) in value
            .as_array()
            .map_or(&[][..], Vec::as_slice)
            .iter()
            .enumerate()
        {
            walk(item, rest, &format!("{at}/{i}"), kind, sink);
        }
    } else if let Some(item) = value.as_object().and_then(|o| o.get(step)) {
        walk(item, rest, &format!("{at}/{}", escape(step)), kind, sink);
    }
}
