//! Distance queries on a scene: nearest points, signed distances and occupancy, one point per
//! row of an (N, 3) float64 array, in parallel with the GIL released.

use crate::fill::array;
use crate::scene::PyScene;
use crate::threads;
use glam::DVec3;
use numpy::ndarray::ArrayView2;
use numpy::PyReadonlyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raycast_core::trace::{NearestPoint, SignRule, Signer};

/// The rows of `points`, after checking the shape and that every point is finite.
fn rows<'a>(points: &'a PyReadonlyArray2<'_, f64>) -> PyResult<ArrayView2<'a, f64>> {
    let points = points.as_array();
    if points.ncols() != 3 {
        return Err(PyValueError::new_err("points must be (N, 3)"));
    }
    if let Some(i) = (0..points.nrows()).find(|&i| !points.row(i).iter().all(|v| v.is_finite())) {
        return Err(PyValueError::new_err(format!(
            "point {i} is not finite: {}",
            points.row(i)
        )));
    }
    Ok(points)
}

fn point(points: &ArrayView2<'_, f64>, i: usize) -> DVec3 {
    DVec3::new(points[[i, 0]], points[[i, 1]], points[[i, 2]])
}

/// The nearest surface point of each (N, 3) point: a dict of `point` (N, 3), `distance` (N,),
/// `id` (N,), `prim` (N,), `bary` (N, 3) (a quadric's: the point in its own coordinates) and
/// `normal` (N, 3), on `nthreads` threads (0: all cores). An empty scene gives infinite
/// points and distances, id 0 and prim `u32::MAX`.
#[pyfunction]
pub fn closest_points<'py>(
    py: Python<'py>,
    scene: &PyScene,
    points: PyReadonlyArray2<'py, f64>,
    nthreads: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let points = rows(&points)?;
    let query = scene.tracer();
    let found: Vec<Option<NearestPoint>> = threads::map(py, nthreads, points.nrows(), |i| {
        query.closest(point(&points, i))
    })?;
    let n = found.len();
    let column = |f: &dyn Fn(&NearestPoint) -> [f64; 3], miss: f64| {
        found
            .iter()
            .flat_map(|c| c.as_ref().map_or([miss; 3], f))
            .collect::<Vec<f64>>()
    };
    let dict = PyDict::new(py);
    dict.set_item(
        "point",
        array(py, &[n, 3], column(&|c| c.point.to_array(), f64::INFINITY))?,
    )?;
    let distance = found
        .iter()
        .map(|c| c.map_or(f64::INFINITY, |c| c.distance));
    dict.set_item("distance", array(py, &[n], distance.collect())?)?;
    let id = found.iter().map(|c| c.map_or(0, |c| c.id));
    dict.set_item("id", array(py, &[n], id.collect())?)?;
    let prim = found.iter().map(|c| c.map_or(u32::MAX, |c| c.prim));
    dict.set_item("prim", array(py, &[n], prim.collect())?)?;
    dict.set_item("bary", array(py, &[n, 3], column(&|c| c.bary, 0.0))?)?;
    dict.set_item(
        "normal",
        array(py, &[n, 3], column(&|c| c.normal.to_array(), 0.0))?,
    )?;
    Ok(dict)
}

/// The signed distance of each (N, 3) point: negative inside, 0 where no side is certain
/// (within the crossing test's margin of a surface), by `sign` = "crossings" (exact parity,
/// for closed meshes and closed ellipsoids) or "winding" (the generalised winding number
/// above 1/2, triangles only). A scene whose sign is not defined raises ValueError naming
/// the object (see `Signer::new`).
#[pyfunction]
pub fn signed_distance<'py>(
    py: Python<'py>,
    scene: &PyScene,
    points: PyReadonlyArray2<'py, f64>,
    sign: &str,
    nthreads: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let points = rows(&points)?;
    let query = scene.tracer();
    let rule = match sign {
        "crossings" => SignRule::Crossings,
        "winding" => SignRule::Winding,
        _ => {
            return Err(PyValueError::new_err(format!(
                "unknown sign rule '{sign}' (choose crossings or winding)"
            )))
        }
    };
    let path = scene.scene().path.display().to_string();
    let signer = py
        .detach(|| Signer::new(query, rule))
        .map_err(|e| PyValueError::new_err(format!("{path}: {e}")))?;
    let signed = threads::map(py, nthreads, points.nrows(), |i| {
        signer.signed_distance(point(&points, i))
    })?;
    array(py, &[signed.len()], signed)
}
