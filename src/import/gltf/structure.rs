//! The document's structure: properties the reader takes to be arrays or objects, and that a
//! file gives as another JSON type (`"primitives": {…}` where an array belongs). Read as
//! absent, such a property would silently drop geometry (a mesh without primitives, a node
//! without its matrix), so it is a TYPE_MISMATCH error, as the Khronos glTF-Validator's, and
//! the importer refuses the file (integrity rules, [`super::integrity`]).

use super::diagnostics::Sink;
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

/// Properties inside the collections' objects, by their path below the collection (`*` for
/// every element of an array), and the type each must have.
const PROPERTIES: &[(&[&str], Kind)] = &[
    (&["*", "nodes"], Kind::Array),
    (&["*", "children"], Kind::Array),
    (&["*", "matrix"], Kind::Array),
    (&["*", "translation"], Kind::Array),
    (&["*", "rotation"], Kind::Array),
    (&["*", "weights"], Kind::Array),
    (&["*", "primitives"], Kind::Array),
    (&["*", "primitives", "*"], Kind::Object),
    (&["*", "primitives", "*", "attributes"], Kind::Object),
    (&["*", "primitives", "*", "targets"], Kind::Array),
    (&["*", "primitives", "*", "targets", "*"], Kind::Object),
    (&["*", "joints"], Kind::Array),
    (&["*", "channels"], Kind::Array),
    (&["*", "channels", "*"], Kind::Object),
    (&["*", "channels", "*", "target"], Kind::Object),
    (&["*", "samplers"], Kind::Array),
    (&["*", "samplers", "*"], Kind::Object),
    (&["*", "sparse"], Kind::Object),
    (&["*", "min"], Kind::Array),
    (&["*", "max"], Kind::Array),
];

/// Which collections each property pattern applies in (a `scale` is an array on a node but a
/// number on a normal texture, so patterns are per collection).
fn applies(collection: &str, pattern: &[&str]) -> bool {
    match pattern.get(1).copied() {
        Some("nodes") => collection == "scenes",
        Some("children" | "matrix" | "translation" | "rotation") => collection == "nodes",
        Some("weights") => matches!(collection, "nodes" | "meshes"),
        Some("primitives") => collection == "meshes",
        Some("joints") => collection == "skins",
        Some("channels" | "samplers") => collection == "animations",
        Some("sparse" | "min" | "max") => collection == "accessors",
        _ => false,
    }
}

/// Reports every property of the table above that has another JSON type.
pub fn check(doc: &Document, sink: &mut dyn Sink) {
    for &collection in COLLECTIONS {
        let Some(value) = doc.root().get(collection) else {
            continue;
        };
        let at = format!("/{collection}");
        if !value.is_array() {
            sink.error("TYPE_MISMATCH", at, Kind::Array.expected());
            continue;
        }
        walk(value, &["*"], &at, Kind::Object, sink);
        for &(pattern, kind) in PROPERTIES {
            if applies(collection, pattern) {
                walk(value, pattern, &at, kind, sink);
            }
        }
    }
}

/// Follows `pattern` from `value` (at pointer `at`) and reports where the end is not `kind`.
fn walk(value: &Value, pattern: &[&str], at: &str, kind: Kind, sink: &mut dyn Sink) {
    let Some((&step, rest)) = pattern.split_first() else {
        if !kind.holds(value) {
            sink.error("TYPE_MISMATCH", at, kind.expected());
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
