//! The seams where compressed data enters the document layer. Each is one function with a
//! small contract, called from exactly one place:
//!
//! - [`meshopt_view`]: every buffer view with EXT_meshopt_compression (or its KHR_ name) is
//!   decoded once, by [`Document::decode_views`], before any accessor is read; from then on
//!   [`Document::view_bytes`] serves the decoded bytes, so accessors never know.
//! - [`draco_primitive`]: [`Document::primitive_geometry`] offers every primitive with
//!   KHR_draco_mesh_compression here first; `None` means "read the fallback accessors".
//! - [`gpu_instances`]: the scene walk asks for the instance matrices of every node with
//!   EXT_mesh_gpu_instancing; each instance becomes an object `<node name>[i]`.
//!
//! No decoder is built in yet: a file that *requires* one of these extensions is refused by
//! the extension policy ([`super::can_honour_required`]); one that only *uses* it is read
//! through its fallback data.

use super::diagnostics::{Diagnostic, Sink};
use super::document::Document;
use super::mesh::Geometry;
use glam::DMat4;
use serde_json::Value;

/// Names of the meshopt buffer view extension.
pub const MESHOPT: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// Name of the GPU instancing node extension.
pub const GPU_INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// The decoded bytes of buffer view `view`, whose meshopt extension object is `ext`.
/// `Ok(None)`: not decoded (the view's own, fallback bytes are read instead).
pub fn meshopt_view(
    _doc: &Document,
    _view: usize,
    _ext: &Value,
) -> Result<Option<Vec<u8>>, Diagnostic> {
    Ok(None)
}

/// The geometry of a Draco-compressed primitive, whose extension object is `ext`. `None`:
/// not decoded here; the primitive's fallback accessors are read instead.
pub fn draco_primitive(
    _doc: &Document,
    _mesh: usize,
    _prim: usize,
    _ext: &Value,
) -> Option<Result<Geometry, Diagnostic>> {
    None
}

/// The local instance matrices (relative to the node) of a node with GPU instancing, whose
/// extension object is `ext`. `Ok(None)`: instancing not applied (the node is drawn once).
pub fn gpu_instances(
    _doc: &Document,
    _node: usize,
    _ext: &Value,
) -> Result<Option<Vec<DMat4>>, Diagnostic> {
    Ok(None)
}

impl Document {
    /// Runs [`meshopt_view`] on every buffer view that carries the extension; failures are
    /// reported to `sink`.
    pub fn decode_views(&mut self, sink: &mut dyn Sink) {
        let mut decoded = Vec::new();
        for (i, view) in self.list("bufferViews").iter().enumerate() {
            let Some(ext) = MESHOPT
                .iter()
                .find_map(|name| super::document::extension(view, name))
            else {
                continue;
            };
            match meshopt_view(self, i, ext) {
                Ok(Some(bytes)) => decoded.push((i, bytes)),
                Ok(None) => {}
                Err(e) => sink.push(e),
            }
            if sink.stopped() {
                break;
            }
        }
        self.decoded_views.extend(decoded);
    }
}
