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
//! The decoders are self-contained modules with a narrow API (bytes and extension JSON in,
//! decoded data out): [`super::draco`] (draco-core), [`super::meshopt`] (meshoptimizer) and
//! [`super::instancing`]. [`summary`] tells `info` and the sidecar what was decoded.

use super::accessor::NO_DATA;
use super::diagnostics::{Code, Diagnostic, Sink};
use super::document::{extension, index_of, Document};
use super::geometry::{Geometry, TriangleMode, DRACO};
use super::{draco, instancing, meshopt};
use crate::bound::transform::BoundedMat4;
use glam::DVec3;
use serde_json::Value;

/// The codes of the diagnostics the decoders give (Draco, meshopt, GPU instancing data that
/// cannot be decoded).
pub const DECODE_ERRORS: [Code; 3] = [
    Code::DracoInvalid,
    Code::MeshoptInvalid,
    Code::InstancingInvalid,
];

/// Names of the meshopt buffer view extension.
pub const MESHOPT: [&str; 2] = meshopt::EXTENSIONS;

/// Name of the GPU instancing node extension.
pub const GPU_INSTANCING: &str = instancing::EXTENSION;

/// The decoded bytes of buffer view `view`, whose meshopt extension object is `ext`. The
/// view's own buffer (often a fallback buffer without data) is never read.
pub fn meshopt_view(
    doc: &Document,
    view: usize,
    ext: &Value,
) -> Result<Option<Vec<u8>>, Diagnostic> {
    let name = meshopt_name(doc, view);
    let at = format!("/bufferViews/{view}/extensions/{name}");
    let invalid = |e: String| Diagnostic::error(Code::MeshoptInvalid, &at, e);
    let spec = meshopt::MeshoptView::parse(ext).map_err(|e| invalid(e.to_string()))?;
    let buffer = doc.buffer(spec.buffer).ok_or_else(|| {
        Diagnostic::error(
            NO_DATA,
            format!("{at}/buffer"),
            format!("buffer {} has no data that raycast can read", spec.buffer),
        )
    })?;
    let encoded = spec
        .byte_offset
        .checked_add(spec.byte_length)
        .and_then(|end| buffer.get(spec.byte_offset..end))
        .ok_or_else(|| {
            invalid(format!(
                "the compressed bytes lie outside buffer {}",
                spec.buffer
            ))
        })?;
    let bytes = meshopt::decode(encoded, &spec).map_err(|e| invalid(e.to_string()))?;
    let length = doc
        .item("bufferViews", view)
        .and_then(|v| index_of(v, "byteLength"))
        .unwrap_or(0);
    if bytes.len() > length {
        return Err(invalid(format!(
            "decodes to {} bytes, more than the view's byteLength {length}",
            bytes.len()
        )));
    }
    Ok(Some(bytes))
}

/// Which meshopt extension name buffer view `view` carries.
fn meshopt_name(doc: &Document, view: usize) -> &'static str {
    let json = doc.item("bufferViews", view);
    MESHOPT
        .into_iter()
        .find(|name| json.and_then(|v| extension(v, name)).is_some())
        .unwrap_or(MESHOPT[0])
}

/// True when the Draco data of a primitive (`json`) is what we read: Draco is required, or
/// the fallback POSITION accessor has no data. Otherwise the fallback accessors are read.
fn reads_draco(doc: &Document, json: &Value) -> bool {
    let required = doc
        .extension_names("extensionsRequired")
        .any(|e| e == DRACO);
    let position = json.get("attributes").and_then(|a| index_of(a, "POSITION"));
    let empty_fallback = position
        .and_then(|p| doc.item("accessors", p))
        .is_none_or(|a| a.get("bufferView").is_none());
    required || empty_fallback
}

/// The geometry of a Draco-compressed primitive, whose extension object is `ext`. `None`:
/// not decoded here; the primitive's fallback accessors are read instead. The POSITION
/// accessor gives the decoded values' normalization and must agree with their count.
pub fn draco_primitive(
    doc: &Document,
    mesh: usize,
    prim: usize,
    ext: &Value,
) -> Option<Result<Geometry, Diagnostic>> {
    let json = doc.item("meshes", mesh)?.get("primitives")?.get(prim)?;
    reads_draco(doc, json)
        .then(|| decode_draco(doc, json, ext, &format!("/meshes/{mesh}/primitives/{prim}")))
}

fn decode_draco(
    doc: &Document,
    json: &Value,
    ext: &Value,
    at: &str,
) -> Result<Geometry, Diagnostic> {
    let at_ext = format!("{at}/extensions/{DRACO}");
    let invalid = |e: String| Diagnostic::error(Code::DracoInvalid, &at_ext, e);
    let view = draco::buffer_view(ext).map_err(|e| invalid(e.to_string()))?;
    let bytes = doc.view_bytes(view)?;
    let decoded = draco::decode(bytes, ext).map_err(|e| invalid(e.to_string()))?;
    let position = json
        .get("attributes")
        .and_then(|a| index_of(a, "POSITION"))
        .ok_or_else(|| Diagnostic::error(Code::UndefinedProperty, at, "no POSITION attribute"))?;
    let layout = doc.layout(position)?;
    if layout.count != decoded.positions.len() {
        return Err(invalid(format!(
            "POSITION accessor count {} differs from the {} points Draco decoded",
            layout.count,
            decoded.positions.len()
        )));
    }
    let positions = decoded
        .positions
        .iter()
        .map(|p| DVec3::from_array(p.map(|c| layout.dequantize(c))))
        .collect();
    Geometry::new(positions, Some(decoded.indices), TriangleMode::List, at)
}

/// The stored values of glTF attribute `name` (`comps` per vertex) of a primitive read from
/// Draco data whose extension compresses that attribute, in the decoded vertex order; `None`
/// when the primitive's accessors are read instead.
pub fn draco_attribute(
    doc: &Document,
    mesh: usize,
    prim: usize,
    name: &str,
    comps: usize,
) -> Option<Result<Vec<f64>, Diagnostic>> {
    let json = doc.item("meshes", mesh)?.get("primitives")?.get(prim)?;
    let ext = extension(json, DRACO).filter(|_| reads_draco(doc, json))?;
    let at_ext = format!("/meshes/{mesh}/primitives/{prim}/extensions/{DRACO}");
    let invalid = |e: String| Diagnostic::error(Code::DracoInvalid, &at_ext, e);
    let read = || -> Result<Option<Vec<f64>>, Diagnostic> {
        let view = draco::buffer_view(ext).map_err(|e| invalid(e.to_string()))?;
        let bytes = doc.view_bytes(view)?;
        draco::decode_attribute(bytes, ext, name, comps).map_err(|e| invalid(e.to_string()))
    };
    read().transpose()
}

/// The local instance matrices (relative to the node) of a node with GPU instancing, whose
/// extension object is `ext`.
pub fn gpu_instances(
    doc: &Document,
    node: usize,
    ext: &Value,
) -> Result<Option<Vec<BoundedMat4>>, Diagnostic> {
    let at = format!("/nodes/{node}/extensions/{GPU_INSTANCING}");
    let invalid = |e: String| Diagnostic::error(Code::InstancingInvalid, &at, e);
    let accessors = instancing::accessors(ext).map_err(|e| invalid(e.to_string()))?;
    let read = |accessor: Option<usize>,
                comps: usize,
                what: &str|
     -> Result<Option<Vec<Vec<f64>>>, Diagnostic> {
        let Some(accessor) = accessor else {
            return Ok(None);
        };
        let (layout, values) = doc.accessor_values(accessor)?;
        if layout.comps != comps || layout.rows.is_some() {
            return Err(invalid(format!(
                "{what} accessor {accessor} must have {comps} components"
            )));
        }
        let rows = values
            .chunks_exact(comps)
            .map(|row| row.iter().map(|&c| layout.dequantize(c)).collect())
            .collect();
        Ok(Some(rows))
    };
    let vec3 = |rows: Vec<Vec<f64>>| rows.into_iter().map(|r| DVec3::from_slice(&r)).collect();
    let values = instancing::InstanceValues {
        translation: read(accessors.translation, 3, "TRANSLATION")?.map(vec3),
        rotation: read(accessors.rotation, 4, "ROTATION")?
            .map(|rows| rows.into_iter().map(|r| [r[0], r[1], r[2], r[3]]).collect()),
        scale: read(accessors.scale, 3, "SCALE")?.map(vec3),
    };
    instancing::matrices(&values)
        .map(Some)
        .map_err(|e| invalid(e.to_string()))
}

/// One line per decoding extension the document uses, for `info` and the sidecar: meshopt
/// buffer views decoded, Draco primitives read from Draco data (by connectivity method), and
/// GPU-instanced nodes with their instance counts.
pub fn summary(doc: &Document) -> Vec<String> {
    let mut lines = Vec::new();
    if !doc.decoded_views.is_empty() {
        let name = (0..doc.list("bufferViews").len())
            .find(|&v| doc.decoded_views.contains_key(&v))
            .map_or(MESHOPT[0], |v| meshopt_name(doc, v));
        lines.push(format!("{name}: {} buffer views", doc.decoded_views.len()));
    }
    let (mut sequential, mut edgebreaker) = (0, 0);
    for mesh in doc.list("meshes") {
        for json in super::document::array(mesh, "primitives") {
            let Some(ext) = extension(json, DRACO).filter(|_| reads_draco(doc, json)) else {
                continue;
            };
            let bytes = draco::buffer_view(ext)
                .ok()
                .and_then(|v| doc.view_bytes(v).ok());
            match bytes.and_then(|b| draco::method(b).ok()) {
                Some(draco::Method::Sequential) => sequential += 1,
                Some(draco::Method::Edgebreaker) => edgebreaker += 1,
                None => {}
            }
        }
    }
    if sequential + edgebreaker > 0 {
        lines.push(format!(
            "{DRACO}: {} primitives ({sequential} sequential, {edgebreaker} edgebreaker)",
            sequential + edgebreaker
        ));
    }
    let (mut nodes, mut instances) = (0, 0);
    for node in doc.list("nodes") {
        let Some(ext) = extension(node, GPU_INSTANCING) else {
            continue;
        };
        let first = instancing::accessors(ext)
            .ok()
            .and_then(|a| a.translation.or(a.rotation).or(a.scale));
        if let Some(layout) = first.and_then(|a| doc.layout(a).ok()) {
            nodes += 1;
            instances += layout.count;
        }
    }
    if nodes > 0 {
        lines.push(format!(
            "{GPU_INSTANCING}: {instances} instances on {nodes} nodes"
        ));
    }
    lines
}

impl Document {
    /// True when buffer view `view` holds bytes a meshopt decoder produced (its filters are
    /// lossy: writers declare accessor bounds from the data before filtering).
    pub fn is_decoded_view(&self, view: usize) -> bool {
        self.decoded_views.contains_key(&view)
    }

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
