//! Scenes made from arrays, without a file: `Scene.from_arrays` (one mesh) and
//! `Scene.from_objects` (meshes and quadrics by coefficients), and the arrays they keep for
//! pickling.

use glam::{DMat4, DVec3};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use raycast_core::quadric::{Quadric, QuadricSpec};
use raycast_core::scene::{Mesh, Positions};
use raycast_core::Error;
use raycast_io::import;
use std::path::Path;

/// A named mesh as numpy arrays: its name, (N, 3) float64 vertices and (M, 3) int64 faces.
pub(crate) type MeshArrays<'py> = (String, Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

/// A quadric as `Scene.from_objects` takes it: its name, its ten coefficients `A..J`, its clip
/// box (min, max) in its own coordinates, and its object→world matrix (16 numbers, column
/// by column).
pub(crate) type QuadricArgs = (String, [f64; 10], Option<[[f64; 3]; 2]>, [f64; 16]);

/// A mesh given as arrays, checked (every index in range, every vertex finite). The mesh
/// keeps the vertices exactly ([`Positions::exact`]) and the faces as given, so the arrays
/// are read back from it for pickling.
#[derive(Debug, Clone)]
struct MeshPart {
    name: String,
    mesh: Mesh,
}

/// A quadric given by its coefficients, checked and placed.
#[derive(Debug, Clone)]
struct QuadricPart {
    args: QuadricArgs,
    quadric: Quadric,
}

/// The objects of a scene made from arrays: its meshes (ids 1..) then its quadrics.
#[derive(Debug, Clone)]
pub(crate) struct Objects {
    meshes: Vec<MeshPart>,
    quadrics: Vec<QuadricPart>,
}

impl Objects {
    /// The scene of these objects, each placed as given, with source `arrays:<name>`.
    pub(crate) fn source(&self) -> import::Source {
        let meshes = self.meshes.iter().map(|m| (m.name.clone(), m.mesh.clone()));
        let quadrics = self
            .quadrics
            .iter()
            .map(|q| (q.args.0.clone(), q.quadric.clone()));
        let scene = import::mesh_file_scene(
            Path::new("arrays"),
            "arrays",
            Vec::new(),
            meshes.collect(),
            quadrics.collect(),
        );
        import::Source::Fixed(Box::new(scene))
    }

    /// The arrays given: the list of (name, vertices, faces) and the list of quadrics as
    /// `load_objects` takes them.
    pub(crate) fn arrays<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Vec<MeshArrays<'py>>, Vec<QuadricArgs>)> {
        let meshes = self.meshes.iter().map(|m| {
            let (positions, faces) = (m.mesh.positions(), m.mesh.triangles());
            let v: Vec<f64> = (0..positions.len() as u32)
                .flat_map(|i| positions.get(i).to_array())
                .collect();
            let f: Vec<i64> = faces.iter().flatten().map(|&i| i64::from(i)).collect();
            let shaped = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
            let v = Array2::from_shape_vec((positions.len(), 3), v).map_err(shaped)?;
            let f = Array2::from_shape_vec((faces.len(), 3), f).map_err(shaped)?;
            Ok((m.name.clone(), v.into_pyarray(py), f.into_pyarray(py)))
        });
        let quadrics = self.quadrics.iter().map(|q| q.args.clone()).collect();
        Ok((meshes.collect::<PyResult<_>>()?, quadrics))
    }
}

/// `vertices` (N, 3) and triangle `faces` (M, 3) checked: every index in 0..N and every vertex
/// finite, else the message naming the first that is not.
fn mesh_part(
    name: String,
    vertices: &PyReadonlyArray2<'_, f64>,
    faces: &PyReadonlyArray2<'_, i64>,
) -> Result<MeshPart, Error> {
    let (v, f) = (vertices.as_array(), faces.as_array());
    if v.ncols() != 3 || f.ncols() != 3 {
        return Err(Error::msg(format!(
            "vertices must be (N, 3) and faces (M, 3), got {:?} and {:?}",
            v.shape(),
            f.shape()
        )));
    }
    let vertices: Vec<[f64; 3]> = v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    if let Some(i) = vertices
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::msg(format!(
            "vertex {i} is not finite: {:?}",
            vertices[i]
        )));
    }
    let n = vertices.len() as i64;
    let index = |i: i64| u32::try_from(i).ok().filter(|_| i < n);
    let mut triangles = Vec::with_capacity(f.nrows());
    for (k, r) in f.rows().into_iter().enumerate() {
        let (Some(a), Some(b), Some(c)) = (index(r[0]), index(r[1]), index(r[2])) else {
            return Err(Error::msg(format!(
                "face {k} is {:?}: its vertex indices must lie in 0..{n}",
                [r[0], r[1], r[2]]
            )));
        };
        triangles.push([a, b, c]);
    }
    let positions = vertices.into_iter().map(DVec3::from_array).collect();
    let mesh = Mesh::from_parts(Positions::exact(positions), triangles);
    Ok(MeshPart { name, mesh })
}

/// The quadric `args` describe, placed: its coefficients and clip box checked as a file's
/// `RAYCAST_quadric` (see [`QuadricSpec::from_coefficients`]) and its matrix as a node's.
fn quadric_part(args: QuadricArgs) -> Result<QuadricPart, Error> {
    let (_, coefficients, bounds, matrix) = &args;
    let bounds = bounds.map(|[min, max]| [DVec3::from_array(min), DVec3::from_array(max)]);
    let spec = QuadricSpec::from_coefficients(*coefficients, bounds)?;
    let quadric = Quadric::new(&spec, DMat4::from_cols_array(matrix))?;
    Ok(QuadricPart { args, quadric })
}

/// The objects of a scene of one mesh, `mesh`, from `vertices` (N, 3) and triangle `faces`
/// (M, 3) of vertex indices: every index in 0..N and every vertex finite, else a ValueError
/// naming the first that is not.
pub(crate) fn one_mesh(
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
) -> PyResult<Objects> {
    let mesh = mesh_part("mesh".to_string(), &vertices, &faces)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Objects {
        meshes: vec![mesh],
        quadrics: Vec::new(),
    })
}

/// The objects of a scene of several: `meshes` as (name, vertices, faces), checked as
/// [`one_mesh`] checks one, then `quadrics` (see [`QuadricArgs`]); object ids in that order
/// from 1. A ValueError names the first object that is wrong and what is wrong.
pub(crate) fn many(
    meshes: Vec<(String, PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, i64>)>,
    quadrics: Vec<QuadricArgs>,
) -> PyResult<Objects> {
    let meshes = meshes
        .into_iter()
        .map(|(name, v, f)| {
            let wrong = |e: Error| e.context(format!("mesh '{name}'"));
            mesh_part(name.clone(), &v, &f).map_err(wrong)
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let quadrics = quadrics
        .into_iter()
        .map(|args| {
            let wrong = format!("quadric '{}'", args.0);
            quadric_part(args).map_err(|e| e.context(wrong))
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(Objects { meshes, quadrics })
}
