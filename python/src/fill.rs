//! The outputs ("AOVs") of `cast` and `render`: their Python names, and the library's buffers
//! as numpy arrays. The buffers are made by `raycast_core::render::trace`, the loop that makes the
//! command line's buffers, so the values are bit-identical to the command line's files.

use crate::threads;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raycast_core::geometry::RaySource;
use raycast_core::render::{self, Aov, Column, Rays};
use raycast_core::trace::Tracer;
use raycast_core::Error;

/// The output called `name` (`distance` is the command line's `depth`, and `depth` is
/// accepted too).
pub fn parse(name: &str, camera: bool) -> Result<Aov, Error> {
    Ok(match name {
        "t" => Aov::T,
        "distance" | "depth" => Aov::Depth,
        "z" if camera => Aov::Z,
        "normal" => Aov::Normal,
        "position" => Aov::Position,
        "id" => Aov::Id,
        "prim" => Aov::Prim,
        "bary" => Aov::Bary,
        "error" => Aov::Error,
        "certain" => Aov::Certain,
        "uv" => Aov::Uv,
        "shading_normal" => Aov::ShadingNormal,
        "material" => Aov::Material,
        "z" => {
            return Err(Error::msg(
                "the z output needs a camera: use render(), not cast()",
            ))
        }
        _ => {
            return Err(Error::msg(format!(
            "unknown output '{name}' (choose from t, distance, {}normal, position, id, prim, bary, error, certain, uv, shading_normal, material)",
            if camera { "z, " } else { "" }
        )))
        }
    })
}

/// Traces `rays` and returns a dict of `outputs` (with their names), arrays of shape `shape`
/// (+ `(2,)` for uv, `(3,)` for vectors), or the first refused ray. The tracing runs with the GIL
/// released, on `nthreads` threads (0: all cores).
pub fn trace_dict<'py, S, R>(
    py: Python<'py>,
    tracer: &Tracer,
    rays: &Rays<S, R>,
    outputs: &[(String, Aov)],
    shape: &[usize],
    nthreads: usize,
) -> PyResult<Result<Bound<'py, PyDict>, usize>>
where
    S: RaySource + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
{
    let aovs: Vec<Aov> = outputs.iter().map(|(_, a)| *a).collect();
    let traced =
        py.detach(|| threads::run(nthreads, || render::trace(tracer, rays, &aovs, |_| {})));
    let buffers = match traced? {
        Ok(buffers) => buffers,
        Err(i) => return Ok(Err(i)),
    };
    let dict = PyDict::new(py);
    for ((name, _), (_, column)) in outputs.iter().zip(buffers.into_columns()) {
        let array = match column {
            Column::Float(v) => array(py, shape, v)?,
            Column::Index(v) => array(py, shape, v)?,
            Column::Flag(v) => array(py, shape, v)?,
            Column::Pair(v) => array(py, &[shape, &[2]].concat(), v)?,
            Column::Vector(v) => array(py, &[shape, &[3]].concat(), v)?,
        };
        dict.set_item(name, array)?;
    }
    Ok(Ok(dict))
}

/// A numpy array of `shape` holding `values` (moved, not copied).
pub fn array<'py, T: numpy::Element>(
    py: Python<'py>,
    shape: &[usize],
    values: Vec<T>,
) -> PyResult<Bound<'py, PyAny>> {
    let array = ArrayD::from_shape_vec(IxDyn(shape), values)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py).into_any())
}
