//! Shape rules that need no meaning: empty arrays, required properties, integer and string
//! properties, extension objects and lists (the asset version and the JSON types of
//! collections and structural properties are the document layer's rules:
//! [`crate::import::gltf::integrity`], [`crate::import::gltf::structure`]).

use super::{readable, Walker};
use crate::import::gltf::can_honour_required;
use crate::import::gltf::document::{array, as_index, escape};
use crate::Code;
use serde_json::{Map, Value};
use std::collections::HashSet;

/// Properties that hold an index (a reference to an object) wherever they appear: the
/// validator's `getIndex`, where a negative integer is INVALID_INDEX.
const INDEX_KEYS: &[&str] = &[
    "buffer",
    "bufferView",
    "mesh",
    "skin",
    "camera",
    "node",
    "input",
    "output",
    "source",
    "sampler",
    "index",
    "scene",
    "material",
    "indices",
    "inverseBindMatrices",
    "skeleton",
];

/// Properties that hold other non-negative integers wherever they appear: the validator's
/// `getUint`, where a negative integer is VALUE_NOT_IN_RANGE.
const UINT_KEYS: &[&str] = &[
    "byteLength",
    "byteOffset",
    "byteStride",
    "count",
    "componentType",
    "texCoord",
    "mode",
];

/// Properties that hold a string wherever they appear outside extensions.
const STRING_KEYS: &[&str] = &["name", "uri", "mimeType", "generator", "copyright"];

impl Walker<'_, '_> {
    /// Shape checks that need no meaning: empty arrays, required properties, integer and
    /// string properties, extension objects.
    pub(super) fn schema(&mut self) {
        // Collections and properties of the wrong JSON type: the document layer's rule
        // (crate::import::gltf::structure).
        let declared: HashSet<&str> = self.doc.extension_names("extensionsUsed").collect();
        self.tree_object(self.root, "", &declared);
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
                    self.f.error(
                        Code::EmptyEntity,
                        format!("{at}/attributes"),
                        "no attributes",
                    );
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
                    Code::OneOfMismatch,
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
                    Code::UndefinedProperty,
                    format!("{at}/{prop}"),
                    format!("property '{prop}' must be defined"),
                );
            }
        }
    }

    /// A value of integer property `key` that is no valid index, as the validator's
    /// `getIndex` and `getUint` read it: a negative integer (INVALID_INDEX for a reference,
    /// VALUE_NOT_IN_RANGE otherwise), a number with a fraction, or (outside extensions, whose
    /// schemas are their own) a string, boolean or array. An integer past 2⁵³ is an integer
    /// too (the rules of what it counts say what is wrong with it); an object is left alone:
    /// a sparse accessor's `indices` is one.
    fn integer(&mut self, key: &str, item: &Value, at: &str) {
        let index = INDEX_KEYS.contains(&key);
        if let Some(x) = item.as_f64() {
            if x.fract() != 0.0 || !x.is_finite() {
                self.f.error(
                    Code::TypeMismatch,
                    at,
                    format!("{} is not an integer", readable(x)),
                );
            } else if x < 0.0 && index {
                self.f.error(
                    Code::InvalidIndex,
                    at,
                    format!(
                        "{} is not a valid index: it must be a non-negative integer",
                        readable(x)
                    ),
                );
            } else if x < 0.0 {
                self.f.error(
                    Code::ValueNotInRange,
                    at,
                    format!("{} is not a valid non-negative integer", readable(x)),
                );
            } else if index {
                self.f.error(
                    Code::UnresolvedReference,
                    at,
                    format!("refers to {}, which does not exist", readable(x)),
                );
            }
        } else if matches!(item, Value::String(_) | Value::Bool(_) | Value::Array(_))
            && !at.contains("/extensions/")
        {
            self.f
                .error(Code::TypeMismatch, at, format!("{item} is not an integer"));
        }
    }

    /// A value of string property `key` (outside extensions) that is not a string.
    fn string(&mut self, item: &Value, at: &str) {
        if !item.is_string() && !at.contains("/extensions/") {
            self.f
                .error(Code::TypeMismatch, at, format!("{item} is not a string"));
        }
    }

    /// Empty arrays, integers out of range, and `extensions` objects with undeclared names,
    /// anywhere but in extras.
    fn tree(&mut self, v: &Value, at: &str, declared: &HashSet<&str>) {
        match v {
            Value::Array(items) => {
                if items.is_empty() {
                    self.f.error(Code::EmptyEntity, at, "an empty array");
                }
                for (i, item) in items.iter().enumerate() {
                    self.tree(item, &format!("{at}/{i}"), declared);
                }
            }
            Value::Object(map) => self.tree_object(map, at, declared),
            _ => {}
        }
    }

    /// [`Walker::tree`] for the members of one object.
    fn tree_object(&mut self, map: &Map<String, Value>, at: &str, declared: &HashSet<&str>) {
        for (key, item) in map {
            let here = format!("{at}/{}", escape(key));
            if key == "extras" {
                continue;
            }
            let integer = INDEX_KEYS.contains(&key.as_str()) || UINT_KEYS.contains(&key.as_str());
            if integer && as_index(item).is_none() {
                self.integer(key, item, &here);
            }
            if STRING_KEYS.contains(&key.as_str()) {
                self.string(item, &here);
            }
            if key != "extensions" {
                self.tree(item, &here, declared);
                continue;
            }
            let Some(extensions) = item.as_object() else {
                self.f.error(Code::TypeMismatch, here, "expected an object");
                continue;
            };
            for (name, ext) in extensions {
                let ext_at = format!("{here}/{}", escape(name));
                if !declared.contains(name.as_str()) {
                    self.f.error(
                        Code::UndeclaredExtension,
                        ext_at.clone(),
                        format!("extension '{name}' is not in extensionsUsed"),
                    );
                }
                if !ext.is_object() {
                    self.f.error(
                        Code::TypeMismatch,
                        ext_at.clone(),
                        "an extension must be an object",
                    );
                }
                self.tree(ext, &ext_at, declared);
            }
        }
    }

    pub(super) fn extension_lists(&mut self) {
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
                        Code::DuplicateElements,
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
                        Code::InvalidExtensionNameFormat,
                        format!("/{key}/{i}"),
                        format!("'{name}' is not PREFIX_name"),
                    );
                }
            }
        }
        if !required.is_empty() && self.root.get("extensionsUsed").is_none() {
            self.f.error(
                Code::UnsatisfiedDependency,
                "/extensionsRequired",
                "extensionsRequired without extensionsUsed",
            );
        }
        for (i, name) in required.iter().enumerate() {
            let at = format!("/extensionsRequired/{i}");
            if !used.contains(name) {
                self.f.error(
                    Code::UnusedExtensionRequired,
                    at.clone(),
                    format!("'{name}' is required but not in extensionsUsed"),
                );
            }
            if !can_honour_required(name) {
                self.f.error(
                    Code::UnsupportedExtension,
                    at,
                    format!("the file requires '{name}', which raycast cannot decode"),
                );
            }
        }
    }
}
