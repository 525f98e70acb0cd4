//! UsdGeomMesh: polygons triangulated as fans in the prim's local space.

use super::value::{self, At};
use crate::error::{Error, Result};
use crate::scene::Mesh;
use openusd::usd::Prim;
use raycast_core::diagnostic::{Code, Diagnostic};

/// What reading a mesh gave.
pub enum MeshRead {
    /// The mesh in its own frame: the points as stored, triangles in face order (fans),
    /// winding made counter-clockwise-is-front.
    Triangles {
        /// The mesh, with its texture coordinates and normals ([`super::primvars`]).
        mesh: Mesh,
        /// Each triangle's face (its index in `faceVertexCounts`), for per-face materials.
        faces: Vec<u32>,
        /// The mesh is a subdivision surface (drawn as its control cage).
        subdivided: bool,
        /// Faces with fewer than three vertices that were dropped.
        degenerate_faces: usize,
        /// Primvars that could not be read (left out).
        warnings: Vec<Diagnostic>,
    },
    /// Nothing to draw, with the reason (a warning).
    Skip(Diagnostic),
}

/// Reads `points`, `faceVertexCounts`, `faceVertexIndices`, `orientation` and
/// `subdivisionScheme`. Malformed data (a value of the wrong type, an index out of range,
/// counts that do not add up to the index count) skips the mesh with a warning, as
/// usd-core's imaging does; the error only reports a failure to read the stage.
pub fn read(prim: &Prim, at: At) -> Result<MeshRead> {
    match read_checked(prim, at) {
        Ok(read) => Ok(read),
        Err(e) => {
            let mut skipped = e.to_warning(Code::ImporterNote);
            skipped.message.push_str(": mesh skipped");
            Ok(MeshRead::Skip(skipped))
        }
    }
}

fn read_checked(prim: &Prim, at: At) -> Result<MeshRead> {
    let path = prim.path();
    let points = value::vec3s(prim, "points", at)?;
    let counts = value::ints(prim, "faceVertexCounts", at)?;
    let indices = value::ints(prim, "faceVertexIndices", at)?;
    let (Some(points), Some(counts), Some(indices)) = (points, counts, indices) else {
        let animated = at.time().is_none()
            && ["points", "faceVertexCounts", "faceVertexIndices"]
                .iter()
                .any(|name| value::has_time_samples(prim, name));
        let why = if animated {
            "has time-sampled points or topology but no default value (--time CODE reads them)"
        } else {
            "has no points or faces"
        };
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            format!("empty mesh ({why}): skipped"),
        )));
    };
    if points.is_empty() || counts.is_empty() || indices.is_empty() {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            "empty mesh (no points or faces): skipped",
        )));
    }
    if let Some(i) = points.iter().position(|p| !p.is_finite()) {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            format!("point {i} is not finite: mesh skipped"),
        )));
    }
    if let Some(&bad) = counts.iter().find(|&&c| c < 0) {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            format!("faceVertexCounts holds {bad}: mesh skipped"),
        )));
    }
    let total: i64 = counts.iter().sum();
    if total != indices.len() as i64 {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            format!(
                "faceVertexCounts add up to {total} but faceVertexIndices has {}: mesh skipped",
                indices.len()
            ),
        )));
    }
    if let Some(&bad) = indices
        .iter()
        .find(|&&i| i < 0 || i as usize >= points.len())
    {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            format!(
                "faceVertexIndices holds {bad}, out of range for {} points: mesh skipped",
                points.len()
            ),
        )));
    }
    let left_handed = match value::token(prim, "orientation", at)?.as_deref() {
        None | Some("rightHanded") => false,
        Some("leftHanded") => true,
        Some(other) => {
            return Err(Error::at(
                format!("{path}.orientation"),
                format!("'{other}' is neither rightHanded nor leftHanded"),
            ));
        }
    };
    // USD's fallback subdivisionScheme is catmullClark: a mesh is a subdivision surface
    // unless it says `none`.
    let subdivided = value::token(prim, "subdivisionScheme", at)?.as_deref() != Some("none");
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(indices.len());
    // Each corner's place in faceVertexIndices, and each triangle's face.
    let mut corners: Vec<[u32; 3]> = Vec::with_capacity(indices.len());
    let mut faces: Vec<u32> = Vec::with_capacity(indices.len());
    let mut degenerate_faces = 0;
    let mut start = 0usize;
    for (f, &count) in counts.iter().enumerate() {
        let face = &indices[start..start + count as usize];
        let first = start as u32;
        start += count as usize;
        if face.len() < 3 {
            degenerate_faces += 1;
            continue;
        }
        for k in 1..face.len() - 1 {
            let fan = if left_handed {
                [0, k + 1, k]
            } else {
                [0, k, k + 1]
            };
            triangles.push(fan.map(|c| face[c] as u32));
            corners.push(fan.map(|c| first + c as u32));
            faces.push(f as u32);
        }
    }
    if triangles.is_empty() {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            "empty mesh (no face has three vertices): skipped",
        )));
    }
    // Indices and points were checked above, so this always succeeds.
    let topology = super::primvars::Topology {
        triangles: &triangles,
        corners: &corners,
        faces: &faces,
        points: points.len(),
        face_vertices: indices.len(),
        face_count: counts.len(),
    };
    let (attributes, warnings) = super::primvars::read(prim, at, &topology);
    let Some(mesh) = Mesh::new(points, triangles) else {
        return Ok(MeshRead::Skip(super::warning_at(
            path.to_string(),
            "invalid mesh: skipped",
        )));
    };
    Ok(MeshRead::Triangles {
        mesh: mesh.with_attributes(attributes),
        faces,
        warnings,
        subdivided,
        degenerate_faces,
    })
}
