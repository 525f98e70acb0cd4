//! Mesh primitives: POSITION (float, or integers as KHR_mesh_quantization allows) and
//! indices, assembled into triangles for the three triangle modes. A primitive compressed
//! with KHR_draco_mesh_compression is offered to [`super::decode::draco_primitive`] first.

use super::decode;
use super::diagnostics::Diagnostic;
use super::document::{extension, index_of, Document};
use glam::DVec3;

/// Name of the Draco mesh compression extension.
pub const DRACO: &str = "KHR_draco_mesh_compression";

/// glTF primitive modes that make triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriangleMode {
    /// Mode 4: every three indices.
    List,
    /// Mode 5.
    Strip,
    /// Mode 6.
    Fan,
}

impl TriangleMode {
    /// The triangle mode for a glTF `mode`, `None` for points and lines.
    pub fn of(mode: usize) -> Option<TriangleMode> {
        match mode {
            4 => Some(TriangleMode::List),
            5 => Some(TriangleMode::Strip),
            6 => Some(TriangleMode::Fan),
            _ => None,
        }
    }
}

/// The geometry of one primitive in its mesh's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Vertex indices (all below `positions.len()`), in `mode`'s order.
    pub indices: Vec<u32>,
    /// How the indices make triangles.
    pub mode: TriangleMode,
    /// `TEXCOORD_0` per vertex, when read ([`Document::read_shading`]).
    pub uv: Option<Vec<[f64; 2]>>,
    /// `NORMAL` per vertex, when read (posed with the positions).
    pub normals: Option<Vec<DVec3>>,
    /// The primitive's material index, when it has one.
    pub material: Option<usize>,
}

impl Geometry {
    /// Checks the indices against the vertex count and the positions for finiteness.
    pub fn new(
        positions: Vec<DVec3>,
        indices: Option<Vec<u32>>,
        mode: TriangleMode,
        at: &str,
    ) -> Result<Geometry, Diagnostic> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(Diagnostic::error(
                "ACCESSOR_INVALID_FLOAT",
                at,
                format!("POSITION {i} is not finite"),
            ));
        }
        let n = positions.len();
        let indices = indices.unwrap_or_else(|| (0..n as u32).collect());
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(Diagnostic::error(
                "ACCESSOR_INDEX_OOB",
                format!("{at}/indices"),
                format!("index {bad} out of range ({n} vertices)"),
            ));
        }
        Ok(Geometry {
            positions,
            indices,
            mode,
            uv: None,
            normals: None,
            material: None,
        })
    }

    /// The triangles, as corner positions.
    pub fn triangles(&self) -> Vec<[DVec3; 3]> {
        self.corners()
            .into_iter()
            .map(|c| c.map(|v| self.positions[v as usize]))
            .collect()
    }

    /// The triangles, as the vertex indices of their corners.
    pub fn corners(&self) -> Vec<[u32; 3]> {
        let i = &self.indices;
        match self.mode {
            TriangleMode::Strip => (0..i.len().saturating_sub(2))
                .map(|k| {
                    if k % 2 == 0 {
                        [i[k], i[k + 1], i[k + 2]]
                    } else {
                        [i[k + 1], i[k], i[k + 2]]
                    }
                })
                .collect(),
            TriangleMode::Fan => (1..i.len().saturating_sub(1))
                .map(|k| [i[k], i[k + 1], i[0]])
                .collect(),
            TriangleMode::List => i.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        }
    }
}

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
                Diagnostic::error("UNRESOLVED_REFERENCE", &at, "primitive does not exist")
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
                "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT",
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
                "MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT",
                format!("/accessors/{accessor}"),
                "indices must be SCALAR unsigned integers",
            ));
        }
        let (_, values) = self.accessor_values(accessor)?;
        Ok(values.into_iter().map(|v| v as u32).collect())
    }
}
