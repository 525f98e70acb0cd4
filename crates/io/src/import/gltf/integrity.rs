//! Rules about the document as a whole, broken anywhere in it, also in parts a ray caster
//! never reads: the asset's glTF version, the JSON types of its structure
//! ([`super::structure`]) and references to objects that do not exist.
//!
//! A document that breaks them is not a glTF 2.0 document (an unknown major version must
//! not be loaded; a dangling index means the file is corrupt or cut), so the importer
//! refuses it through [`FailFast`](super::FailFast), and `raycast check` reports the same
//! diagnostics. Rules about values (empty arrays, enums, accessor bounds) stay with `check`:
//! the geometry the importer reads is checked where it is read.

use super::diagnostics::{Code, Sink};
use super::document::{array, escape, index_of, Document};
use serde_json::Value;

/// Reports the asset rules, structural type mismatches and every unresolved reference of
/// `doc`.
pub fn check(doc: &Document, sink: &mut dyn Sink) {
    asset(doc, sink);
    super::structure::check(doc, sink);
    references(doc, sink);
    animation_targets(doc, sink);
}

/// Animation channels whose target node does not exist (the `gltf` crate's validation does
/// not look at them).
fn animation_targets(doc: &Document, sink: &mut dyn Sink) {
    let nodes = doc.list("nodes").len();
    for (a, anim) in doc.list("animations").iter().enumerate() {
        for (c, channel) in array(anim, "channels").iter().enumerate() {
            let node = channel.get("target").and_then(|t| index_of(t, "node"));
            if let Some(bad) = node.filter(|&k| k >= nodes) {
                sink.error(
                    Code::UnresolvedReference,
                    format!("/animations/{a}/channels/{c}/target/node"),
                    format!("refers to node {bad}, which does not exist"),
                );
            }
        }
    }
}

/// `asset` and its `version` (`MAJOR.MINOR`, major 2) and `minVersion`.
pub fn asset(doc: &Document, sink: &mut dyn Sink) {
    let asset = match doc.root().get("asset") {
        None => {
            return sink.error(
                Code::UndefinedProperty,
                "/asset",
                "the asset property is missing",
            )
        }
        Some(asset) if !asset.is_object() => {
            return sink.error(Code::TypeMismatch, "/asset", "expected an object")
        }
        Some(asset) => asset,
    };
    let version = match asset.get("version") {
        None => {
            sink.error(
                Code::UndefinedProperty,
                "/asset/version",
                "property 'version' must be defined",
            );
            None
        }
        Some(v) => parse_version(v).or_else(|| {
            sink.error(
                Code::PatternMismatch,
                "/asset/version",
                format!("{v} is not a version: it must look like \"MAJOR.MINOR\""),
            );
            None
        }),
    };
    if let Some((major, minor)) = version {
        if major != 2 {
            sink.error(
                Code::UnknownAssetMajorVersion,
                "/asset/version",
                format!("glTF {major}.{minor} is not glTF 2"),
            );
        } else if minor > 0 {
            sink.warn(
                Code::UnknownAssetMinorVersion,
                "/asset/version",
                format!("glTF 2.{minor} is newer than 2.0"),
            );
        }
    }
    match (asset.get("minVersion").map(parse_version), version) {
        (Some(None), _) => sink.error(
            Code::PatternMismatch,
            "/asset/minVersion",
            "minVersion must look like MAJOR.MINOR",
        ),
        (Some(Some(min)), Some(version)) if min > version => sink.error(
            Code::AssetMinVersionGreaterThanVersion,
            "/asset/minVersion",
            "minVersion is greater than version",
        ),
        _ => {}
    }
}

/// A version string `MAJOR.MINOR` (digits only on both sides).
fn parse_version(v: &Value) -> Option<(u64, u64)> {
    let (a, b) = v.as_str()?.split_once('.')?;
    let ok = |s: &str| !s.is_empty() && s.bytes().all(|c| c.is_ascii_digit());
    if !(ok(a) && ok(b)) {
        return None;
    }
    Some((a.parse().ok()?, b.parse().ok()?))
}

/// Runs the `gltf` crate's reference validation where the crate can read the file (it
/// refuses some valid files, which are then not checked here): every index that names no
/// object is an `UNRESOLVED_REFERENCE` error. The crate's other findings come along: values
/// not in their list (warnings) and sizes past the machine's (errors).
pub fn references(doc: &Document, sink: &mut dyn Sink) {
    use gltf::json::validation::{Error as VError, Validate};
    let Ok(root) = serde_json::from_slice::<gltf::json::Root>(doc.json_text()) else {
        return;
    };
    let unresolved = |sink: &mut dyn Sink, pointer: String| {
        let message = match pointed(doc, &pointer) {
            Some(index) => format!("refers to {index}, which does not exist"),
            None => "refers to an object that does not exist".to_string(),
        };
        sink.error(Code::UnresolvedReference, pointer, message);
    };
    let dangling = dangling_positions(&root);
    if !dangling.is_empty() {
        for pointer in dangling {
            unresolved(sink, pointer);
        }
        return;
    }
    let mut found = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, error| {
        found.push((path().to_string(), error));
    });
    for (path, error) in found {
        let pointer = json_pointer(&path);
        match error {
            VError::IndexOutOfBounds => unresolved(sink, pointer),
            VError::Invalid => sink.warn(Code::ValueNotInList, pointer, "invalid value"),
            VError::Oversize => sink.error(Code::ValueNotInRange, pointer, "value too large"),
            // The crate asks for properties the specification leaves optional; `check`
            // checks the required ones itself.
            VError::Missing | VError::Unsupported => {}
        }
    }
}

/// The JSON value at `pointer` in the document.
fn pointed<'a>(doc: &'a Document, pointer: &str) -> Option<&'a Value> {
    let rest = pointer.strip_prefix('/')?;
    let (key, rest) = rest.split_once('/').unwrap_or((rest, ""));
    let top = doc.root().get(key)?;
    if rest.is_empty() {
        Some(top)
    } else {
        top.pointer(&format!("/{rest}"))
    }
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
        // The crate names morph target attributes by its field names.
        let part = match part {
            "positions" => "POSITION",
            "normals" => "NORMAL",
            "tangents" => "TANGENT",
            other => other,
        };
        out.push('/');
        out.push_str(&escape(part));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::gltf::FailFast;

    fn first_error(json: &str) -> Option<String> {
        let mut sink = FailFast::default();
        let doc = Document::parse(json.as_bytes().to_vec(), false, &mut sink).unwrap();
        check(&doc, &mut sink);
        sink.error.map(|d| d.to_string())
    }

    #[test]
    fn pointers() {
        assert_eq!(
            json_pointer("meshes[0].primitives[1].indices"),
            "/meshes/0/primitives/1/indices"
        );
        assert_eq!(json_pointer("scene"), "/scene");
        assert_eq!(
            json_pointer("meshes[0].primitives[0].targets[1].positions"),
            "/meshes/0/primitives/0/targets/1/POSITION"
        );
    }

    #[test]
    fn versions() {
        let doc = |version: &str| format!(r#"{{"asset":{{"version":{version}}}}}"#);
        assert_eq!(first_error(&doc("\"2.0\"")), None);
        assert_eq!(first_error(&doc("\"2.1\"")), None, "a newer minor loads");
        for bad in ["\"\"", "\"2\"", "\"2.x\"", "2.0", "\" 2.0\""] {
            let e = first_error(&doc(bad)).unwrap();
            assert!(e.starts_with("/asset/version: "), "{bad}: {e}");
        }
        assert!(first_error(&doc("\"1.0\"")).unwrap().contains("not glTF 2"));
        assert!(first_error("{}").unwrap().contains("/asset"));
        assert!(first_error(r#"{"asset":{}}"#)
            .unwrap()
            .contains("/asset/version"));
    }

    #[test]
    fn dangling_references_anywhere() {
        let doc = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{}],
            "textures":[{"source":3}]}"#;
        assert_eq!(
            first_error(doc).unwrap(),
            "/textures/0/source: refers to 3, which does not exist"
        );
        let fine = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{}]}"#;
        assert_eq!(first_error(fine), None);
    }
}
