//! `raycast check` for glTF: the document layer ([`crate::import::gltf`]) read collect-all,
//! then the rules only a validator needs, one file per part of the document.
//!
//! The file is parsed once: the layer's [`Document`] reports container, JSON, URI and
//! buffer problems into the findings, the walker below adds the validator's rules working on
//! the raw JSON (so one bad property does not hide the others), and the scene is built from
//! the same document by the importer's own code ([`scene::build`]). So `check` and the
//! renderer agree on what loads, by construction. The layer's whole-document rules (asset
//! version, unresolved references: [`layer::integrity`]) are the importer's too.
//!
//! Codes are the Khronos glTF-Validator's where the meaning is the same.

mod accessors;
mod animations;
mod buffers;
mod materials;
mod meshes;
mod nodes;
mod schema;
mod skins;
mod usage;

use super::{CheckOptions, Findings, Severity};
use crate::import::gltf::accessor::Layout;
use crate::import::gltf::buffers::Resources;
use crate::import::gltf::decode::DECODE_ERRORS;
use crate::import::gltf::document::index_of;
use crate::import::gltf::{self as layer, scene, Diagnostic, Document, Sink};
use crate::scene::Scene;
use crate::Code;
use serde_json::{Map, Value};
use std::collections::HashMap;
use std::path::Path;

/// How far from 1 the length of a unit vector (normal, tangent) may be: the Khronos
/// glTF-Validator's tolerance, so that check flags what the validator flags and no more
/// (quantized normals are routinely a few parts in a thousand off).
const UNIT_VECTOR_TOLERANCE: f64 = 0.00674;

/// How far from 1 the length of a rotation quaternion (node or animation key) may be: the
/// Khronos glTF-Validator's tolerance.
const UNIT_QUATERNION_TOLERANCE: f64 = 0.00769;
use std::rc::Rc;

/// Deepest node hierarchy walked.
pub const MAX_NODE_DEPTH: usize = 1024;

/// Bytes of memory one triangle costs the importer and the scene (f64 while building, f32
/// stored, object table), used to estimate what an asset will allocate.
const BYTES_PER_TRIANGLE: u64 = 128;

/// The findings as the document layer's sink. Remembers whether the layer refused to read
/// something for its size, which stops the scene from being built.
struct Collect<'f> {
    f: &'f mut Findings,
    too_large: bool,
}

impl Sink for Collect<'_> {
    fn push(&mut self, d: Diagnostic) {
        self.too_large |= d.code == Code::AssetTooLarge;
        let message = d.text();
        self.f.push(d.severity, d.code, d.location, message);
    }
}

/// Checks a `.gltf` or `.glb` file, external files confined to the folder tree `tree_root`.
/// Returns the scene the importer builds from it, or `None` when it is not built (the file
/// cannot be read, no JSON to read, or more than the memory limit).
pub fn check(
    path: &Path,
    tree_root: &Path,
    options: &CheckOptions,
    f: &mut Findings,
) -> Option<crate::error::Result<Scene>> {
    let mut sink = Collect {
        f,
        too_large: false,
    };
    let is_glb = layer::is_glb_path(path);
    let bytes = match layer::document::read_file(path, is_glb, &mut sink) {
        Ok(bytes) => bytes?,
        Err(e) => {
            sink.f.error(Code::IoError, "", format!("cannot read: {e}"));
            return None;
        }
    };
    let mut doc = Document::parse(bytes, is_glb, &mut sink)?;
    doc.limit_unbacked(options.max_bytes);
    let base = crate::import::paths::folder_of(path);
    let resources = Resources {
        base: &base,
        root: tree_root,
        allow_outside: options.allow_outside,
        max_bytes: options.max_bytes,
    };
    doc.load_buffers(&resources, None, &mut sink);
    doc.decode_views(&mut sink);
    layer::integrity::check(&doc, &mut sink);
    let too_large = sink.too_large;
    let mut walker = Walker {
        doc: &doc,
        root: doc.root(),
        f,
        options,
        resources,
        values: HashMap::new(),
        importable: !too_large,
    };
    walker.run();
    if !walker.importable {
        return None;
    }
    let timing = scene::Timing {
        time: options.time(),
        animation: None,
    };
    let built = scene::build_at(&doc, None, &timing, path);
    // The walker does not decode: a decoder's error is reported with its own code.
    if let Err(e) = &built {
        if DECODE_ERRORS.contains(&e.code) {
            f.push(Severity::Error, e.code, e.location.clone(), e.text());
        }
    }
    // The importer's verdict keeps the layer's code, so a reader of the report need not
    // match message strings.
    Some(built.map_err(|e| crate::Error::in_file(path, format!("{} {e}", e.code))))
}

/// A number for a message: plain when short, in scientific notation when plain would be
/// long (`1e300`, not three hundred digits).
fn readable(x: f64) -> String {
    let plain = x.to_string();
    if plain.len() <= 24 {
        plain
    } else {
        format!("{x:e}")
    }
}

/// The validator's walk over one document.
struct Walker<'a, 'f> {
    doc: &'a Document,
    root: &'a Map<String, Value>,
    f: &'f mut Findings,
    options: &'a CheckOptions,
    /// Where external files (images) may come from.
    resources: Resources<'a>,
    /// Decoded accessor values (sparse applied), by accessor index.
    values: HashMap<usize, Option<Rc<Vec<f64>>>>,
    /// False once the scene must not be built (too large).
    importable: bool,
}

impl<'a> Walker<'a, '_> {
    /// A top-level array of the document.
    fn list(&self, key: &str) -> &'a [Value] {
        self.doc.list(key)
    }

    fn run(&mut self) {
        self.schema();
        self.extension_lists();
        self.buffers();
        self.buffer_views();
        self.accessors();
        self.materials();
        self.meshes();
        let triangles = self.nodes_and_scenes();
        self.cameras();
        self.images();
        self.animations();
        self.skins();
        self.buffer_view_usage();
        let estimate = triangles.saturating_mul(BYTES_PER_TRIANGLE);
        if estimate > self.options.max_bytes {
            self.f.error(
                Code::AssetTooLarge,
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

    /// The layout of accessor `accessor`, when it exists and is well formed.
    fn layout(&self, accessor: usize) -> Option<Layout> {
        Layout::of(self.list("accessors").get(accessor)?)
    }

    /// The buffer view JSON of accessor `accessor`.
    fn view_of(&self, accessor: usize) -> Option<&'a Value> {
        let view = index_of(self.list("accessors").get(accessor)?, "bufferView")?;
        self.list("bufferViews").get(view)
    }

    /// Decodes an accessor with a buffer view (sparse applied), once. `None` when its data
    /// cannot be read (the layout rules say why) or it has no buffer view (zeros are not
    /// checked: the validator leaves them alone too).
    fn values(&mut self, index: usize) -> Option<Rc<Vec<f64>>> {
        if let Some(v) = self.values.get(&index) {
            return v.clone();
        }
        let backed = self
            .list("accessors")
            .get(index)
            .is_some_and(|a| a.get("bufferView").is_some());
        let decoded = backed
            .then(|| self.doc.accessor_values(index).ok())
            .flatten()
            .map(|(_, values)| Rc::new(values));
        self.values.insert(index, decoded.clone());
        decoded
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_readable() {
        assert_eq!(readable(1e300), "1e300");
        assert_eq!(readable(-2.5), "-2.5");
        assert_eq!(readable(4294967296.0), "4294967296");
    }
}
