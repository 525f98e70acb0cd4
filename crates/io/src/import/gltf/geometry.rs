//! The geometry of one mesh primitive, however it was stored (plain accessors, Draco,
//! meshopt): positions, indices and the triangle mode that assembles them into triangles.

use super::diagnostics::{Code, Diagnostic};
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
    /// `TEXCOORD_0` per vertex, when read ([`super::document::Document::read_shading`]).
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
                Code::AccessorInvalidFloat,
                at,
                format!("POSITION {i} is not finite"),
            ));
        }
        let n = positions.len();
        let indices = indices.unwrap_or_else(|| (0..n as u32).collect());
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(Diagnostic::error(
                Code::AccessorIndexOob,
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
