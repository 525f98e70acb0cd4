//! `raycast._raycast`: the compiled half of the Python package `raycast`.
//!
//! Thin by design: it converts numpy arrays to the library's rays and the library's answers to
//! numpy arrays, releases the GIL while the library traces (on rayon's threads), and maps the
//! library's [`raycast_core::error::ErrorKind`] to the exception classes of `raycast.errors`. Shapes,
//! dtypes and argument names are checked by the Python layer (`raycast/__init__.py`), which
//! hands over float64 arrays; what only a pass over the data can find (a NaN, a zero
//! direction) is found here, in parallel.

mod arrays;
mod camera;
mod distance;
mod fill;
mod objects;
mod scene;
mod threads;

use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception for a library error: `raycast.errors.<class>` chosen by its kind.
pub(crate) fn to_pyerr(py: Python<'_>, error: raycast_core::Error) -> PyErr {
    use raycast_core::error::ErrorKind;
    let class = match error.kind {
        ErrorKind::Usage => "UsageError",
        ErrorKind::NotFound => "SceneNotFoundError",
        _ => "SceneError",
    };
    let message = error.to_string();
    let raised = py
        .import("raycast.errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| Ok(c.cast_into::<PyType>()?))
        .and_then(|c| c.call1((message.clone(),)))
        .and_then(|instance| {
            instance.setattr("code", error.code().name())?;
            Ok(instance)
        });
    match raised {
        Ok(instance) => PyErr::from_value(instance),
        Err(e) => e,
    }
}

#[pymodule]
fn _raycast(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<scene::PyScene>()?;
    m.add_class::<camera::PyCamera>()?;
    m.add_function(wrap_pyfunction!(scene::load_path, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load_objects, m)?)?;
    m.add_function(wrap_pyfunction!(distance::closest_points, m)?)?;
    m.add_function(wrap_pyfunction!(distance::signed_distance, m)?)?;
    m.add_function(wrap_pyfunction!(camera::look_at, m)?)?;
    m.add_function(wrap_pyfunction!(camera::pinhole, m)?)?;
    m.add_function(wrap_pyfunction!(camera::read_views, m)?)?;
    Ok(())
}
