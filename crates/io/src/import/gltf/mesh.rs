//! Mesh primitives read from their accessors: POSITION (float, or integers as
//! KHR_mesh_quantization allows) and indices, into a [`Geometry`]. A primitive compressed with
//! KHR_draco_mesh_compression is offered to [`super::decode::draco_primitive`] first.

use super::decode;
use super::diagnostics::{Code, Diagnostic};
use super::document::{extension, index_of, Document};
use super::geometry::{Geometry, TriangleMode, DRACO};
use glam::DVec3;

impl Document {
    /// Number of primitives of mesh `mesh`.
    pub fn primitive_count(&self, mesh: usize) -> usize {
        self.item("meshes", mesh)
            .map_or(0, |m| super::document::array(m, "primitives").len())
    }

    /// The JSON of primitive `prim` of mesh `mesh`, and its JSON pointer.
    pub(super) fn primitive_json(
        &self,
        mesh: usize,
        prim: usize,
    ) -> Result<(&serde_json::Value, String), Diagnostic> {
        let at = format!("/meshes/{mesh}/primitives/{prim}");
        let json = self
            .item("meshes", mesh)
            .and_then(|m| m.get("primitives"))
            .and_then(|p| p.get(prim))
            .ok_or_else(|| {
                Diagnostic::error(Code::UnresolvedReference, &at, "primitive does not exist")
            })?;
        Ok((json, at))
    }

    /// The geometry of primitive `prim` of mesh `mesh`: `Ok(None)` for points and lines, and
    /// for a primitive without POSITION (nothing to draw).
    pub fn primitive_geometry(
        &self,
        mesh: usize,
        prim: usize,
    ) -> Result<Option<Geometry>, Diagnostic> {
        let (json, at) = self.primitive_json(mesh, prim)?;
        let Some(mode) = TriangleMode::of(index_of(json, "mode").unwrap_or(4)) else {
            return Ok(None);
        };
        if let Some(ext) = extension(json, DRACO) {
            if let Some(decoded) = decode::draco_primitive(self, mesh, prim, ext) {
                return decoded.map(Some);
            }
        }
        let Some(position) = json.get("attributes").and_then(|a| index_of(a, "POSITION")) else {
            return Ok(None);
        };
        let positions = self.positions(position).map_err(|e| e.within(&at))?;
        let indices = match index_of(json, "indices") {
            Some(accessor) => Some(self.indices(accessor).map_err(|e| e.within(&at))?),
            None => None,
        };
        Geometry::new(positions, indices, mode, &at).map(Some)
    }

    /// Why [`Document::primitive_geometry`] gives no geometry for a primitive.
    pub fn primitive_skip_reason(&self, mesh: usize, prim: usize) -> String {
        let json = self
            .item("meshes", mesh)
            .and_then(|m| m.get("primitives"))
            .and_then(|p| p.get(prim));
        let mode = json.and_then(|p| index_of(p, "mode")).unwrap_or(4);
        let name = match mode {
            0 => "Points",
            1 => "Lines",
            2 => "LineLoop",
            3 => "LineStrip",
            _ => return "no POSITION: nothing to draw".into(),
        };
        format!("{name} primitive skipped (only triangles are drawn)")
    }

    /// Reads a POSITION accessor: VEC3 of floats or (KHR_mesh_quantization) 8/16-bit integers.
    pub fn positions(&self, accessor: usize) -> Result<Vec<DVec3>, Diagnostic> {
        let at = format!("/accessors/{accessor}");
        let layout = self.layout(accessor)?;
        if layout.comps != 3 || layout.rows.is_some() || layout.component == 5125 {
            return Err(Diagnostic::error(
                Code::MeshPrimitiveAttributesAccessorInvalidFormat,
                at,
                "POSITION must be VEC3 of floats or 8/16-bit integers",
            ));
        }
        let (layout, values) = self.accessor_values(accessor)?;
        Ok(values
            .chunks_exact(3)
            .map(|p| {
                DVec3::new(
                    layout.dequantize(p[0]),
                    layout.dequantize(p[1]),
                    layout.dequantize(p[2]),
                )
            })
            .collect())
    }

    /// Reads an index accessor: SCALAR unsigned integers.
    pub fn indices(&self, accessor: usize) -> Result<Vec<u32>, Diagnostic> {
        let layout = self.layout(accessor)?;
        if layout.comps != 1 || !matches!(layout.component, 5121 | 5123 | 5125) {
            return Err(Diagnostic::error(
                Code::MeshPrimitiveIndicesAccessorInvalidFormat,
                format!("/accessors/{accessor}"),
                "indices must be SCALAR unsigned integers",
            ));
        }
        let (_, values) = self.accessor_values(accessor)?;
        Ok(values.into_iter().map(|v| v as u32).collect())
    }
}
