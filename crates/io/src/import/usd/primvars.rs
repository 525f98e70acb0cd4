//! A UsdGeomMesh's texture coordinates (`primvars:st`) and normals (`primvars:normals`, else
//! `normals`), expanded to the corners of its triangles by their interpolation (`vertex` and
//! `varying`: per point; `faceVarying`: per face-vertex; `uniform`: per face; `constant`: one
//! value), indexed primvars (`:indices`) resolved; and material bindings (`material:binding`
//! of the prim or its nearest ancestor, `materialBind` GeomSubsets per face). A primvar that
//! cannot be read, or whose length does not fit its interpolation, is left out with a warning.

use super::value::{self, At, ValueResult};
use crate::error::{Error, Result};
use crate::scene::attributes::{corners, runs, MaterialRun};
use crate::scene::{Attributes, SceneBuilder};
use openusd::sdf::Value;
use openusd::usd::Prim;
use raycast_core::diagnostic::Diagnostic;

/// A triangulated mesh's topology, as [`super::mesh`] made it.
pub struct Topology<'a> {
    /// Point indices of each triangle's corners.
    pub triangles: &'a [[u32; 3]],
    /// Each corner's place in `faceVertexIndices`.
    pub corners: &'a [[u32; 3]],
    /// Each triangle's face.
    pub faces: &'a [u32],
    /// Number of points, face-vertices and faces.
    pub points: usize,
    pub face_vertices: usize,
    pub face_count: usize,
}

/// The texture coordinates and normals of a mesh's triangle corners, and warnings for the
/// primvars left out.
pub fn read(prim: &Prim, at: At, topology: &Topology) -> (Attributes, Vec<Diagnostic>) {
    let mut warnings = Vec::new();
    let uv =
        vec2s(prim, "primvars:st", at).and_then(|v| expand(prim, "primvars:st", at, topology, v));
    let normals_name = match value::raw(prim, "primvars:normals", at) {
        Ok(Some(_)) => "primvars:normals",
        _ => "normals",
    };
    let normals = value::vec3s(prim, normals_name, at)
        .map(|v| v.map(|v| v.iter().map(|n| n.as_vec3().to_array()).collect()))
        .and_then(|v| expand(prim, normals_name, at, topology, v));
    let attributes = Attributes {
        uv: left_out(prim, "primvars:st", uv, &mut warnings),
        normals: left_out(prim, normals_name, normals, &mut warnings),
        materials: Vec::new(),
    };
    (attributes, warnings)
}

/// The values of a primvar read, or none with a warning saying why.
fn left_out<T>(
    prim: &Prim,
    name: &str,
    read: Result<Vec<T>>,
    warnings: &mut Vec<Diagnostic>,
) -> Vec<T> {
    read.unwrap_or_else(|why| {
        let at = format!("{}.{name}", prim.path());
        warnings.push(super::warning_because(at, &why, format!("{why}: left out")));
        Vec::new()
    })
}

/// The corner values of primvar `name`, whose `values` were read (`Ok(empty)` when
/// unauthored), expanded by its `interpolation` (default `vertex`, as `normals` and the `st`
/// that exporters write are).
fn expand<T: Copy>(
    prim: &Prim,
    name: &str,
    at: At,
    topology: &Topology,
    values: Option<Vec<T>>,
) -> Result<Vec<[T; 3]>> {
    let Some(mut values) = values else {
        return Ok(Vec::new());
    };
    if let Some(indices) = value::ints(prim, &format!("{name}:indices"), at)? {
        if indices.iter().any(|&i| i < 0 || i as usize >= values.len()) {
            return Err(Error::msg("an index of its :indices is out of range"));
        }
        values = indices.iter().map(|&i| values[i as usize]).collect();
    }
    let interpolation = interpolation(prim, name).unwrap_or_else(|| "vertex".to_string());
    let (per_triangle, needed): (Vec<[u32; 3]>, usize) = match interpolation.as_str() {
        "vertex" | "varying" => (topology.triangles.to_vec(), topology.points),
        "faceVarying" => (topology.corners.to_vec(), topology.face_vertices),
        "uniform" => (
            topology.faces.iter().map(|&f| [f; 3]).collect(),
            topology.face_count,
        ),
        "constant" => (vec![[0; 3]; topology.triangles.len()], 1),
        other => return Err(Error::msg(format!("interpolation '{other}' is not read"))),
    };
    if values.len() < needed {
        return Err(Error::msg(format!(
            "{} values for {interpolation} interpolation, which needs {needed}",
            values.len()
        )));
    }
    Ok(corners(&values, &per_triangle))
}

/// The `interpolation` metadata of attribute `name`.
fn interpolation(prim: &Prim, name: &str) -> Option<String> {
    match prim.attribute(name).get_metadata::<Value>("interpolation") {
        Ok(Some(Value::Token(t))) => Some(t.as_str().to_string()),
        Ok(Some(Value::String(s))) => Some(s),
        _ => None,
    }
}

/// An array of 2-vectors of any precision (`texCoord2f[]`, `float2[]`, …).
fn vec2s(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<[f32; 2]>> {
    let Some(value) = value::raw(prim, name, at)? else {
        return Ok(None);
    };
    Ok(Some(match &value {
        Value::Vec2fVec(v) => v.iter().map(|p| [p.x, p.y]).collect(),
        Value::Vec2dVec(v) => v.iter().map(|p| [p.x as f32, p.y as f32]).collect(),
        Value::Vec2hVec(v) => v.iter().map(|p| [p.x.to_f32(), p.y.to_f32()]).collect(),
        _ => {
            return Err(Error::at(
                format!("{}.{name}", prim.path()),
                format!(
                    "expected an array of 2-vectors, found {}",
                    value::value_kind(&value)
                ),
            ))
        }
    }))
}

/// The material bound to `prim`: the first target of `material:binding` on it or its nearest
/// ancestor that has one.
pub fn bound_material(prim: &Prim) -> Option<String> {
    let stage = prim.stage();
    let mut path = Some(prim.path().clone());
    while let Some(p) = path {
        let here = stage.prim(p.clone());
        if let Ok(targets) = here.relationship("material:binding").targets() {
            if let Some(first) = targets.first() {
                return Some(first.to_string());
            }
        }
        path = p.parent().filter(|parent| !parent.as_str().is_empty());
    }
    None
}

/// The material runs of a mesh prim's triangles (`faces`: each triangle's face): each face's
/// `materialBind` GeomSubset's binding, else the prim's own ([`bound_material`]); empty when
/// nothing is bound.
pub fn material_runs(
    prim: &Prim,
    at: At,
    faces: &[u32],
    builder: &mut SceneBuilder,
) -> Vec<MaterialRun> {
    let own = bound_material(prim).map_or(0, |m| builder.material(&m));
    let mut per_face: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    for child in prim.children().unwrap_or_default() {
        let subset = child
            .type_name()
            .ok()
            .flatten()
            .is_some_and(|t| t.as_str() == "GeomSubset");
        let family = value::token(&child, "familyName", at).ok().flatten();
        if !subset || family.as_deref() != Some("materialBind") {
            continue;
        }
        let Some(material) = bound_material(&child) else {
            continue;
        };
        let id = builder.material(&material);
        for face in value::ints(&child, "indices", at)
            .ok()
            .flatten()
            .unwrap_or_default()
        {
            per_face.entry(face as u32).or_insert(id);
        }
    }
    let per_triangle: Vec<u32> = faces
        .iter()
        .map(|f| per_face.get(f).copied().unwrap_or(own))
        .collect();
    runs(&per_triangle)
}
