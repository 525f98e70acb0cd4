//! The per-ray outputs ("AOVs") of `cast` and `render`, filled in parallel from the nearest
//! crossings, with the same expressions as the library's `render::render`, so that the values
//! are bit-identical to the command line's buffers.

use glam::DVec3;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raycast::query::Query;
use raycast::render::RaySource;
use raycast::scene::Crossing;
use rayon::prelude::*;

/// One output per ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// Ray parameter of the hit, in units of |direction|; +inf on a miss.
    T,
    /// |hit - origin|; +inf on a miss.
    Distance,
    /// Depth along the camera's view axis (cameras only); +inf on a miss.
    Z,
    /// Unit world normal; zeros on a miss.
    Normal,
    /// World hit point; +inf on a miss.
    Position,
    /// 1-based object id; 0 on a miss.
    Id,
    /// Primitive index inside the object; 2^32 - 1 on a miss.
    Prim,
    /// Barycentric weights of the triangle's vertices; zeros on a miss or a quadric.
    Bary,
}

impl Output {
    /// The output called `name` (`depth` is `distance`, as on the command line).
    pub fn parse(name: &str, camera: bool) -> Result<Output, String> {
        Ok(match name {
            "t" => Output::T,
            "distance" | "depth" => Output::Distance,
            "z" if camera => Output::Z,
            "normal" => Output::Normal,
            "position" => Output::Position,
            "id" => Output::Id,
            "prim" => Output::Prim,
            "bary" => Output::Bary,
            "z" => return Err("the z output needs a camera: use render(), not cast()".into()),
            _ => {
                return Err(format!(
                    "unknown output '{name}' (choose from t, distance, {}normal, position, id, prim, bary)",
                    if camera { "z, " } else { "" }
                ))
            }
        })
    }
}

/// Values of one output for every ray.
enum Column {
    Float(Vec<f64>),
    Vector(Vec<DVec3>),
    Index(Vec<u32>),
}

/// Computes `output` for every ray of `source` from its nearest crossing `hits[i]`.
fn column(
    query: &Query,
    source: &(dyn RaySource + Sync),
    hits: &[Option<Crossing>],
    output: Output,
) -> Column {
    let scene = query.scene;
    let each =
        |f: &(dyn Fn(usize, &Crossing) -> f64 + Sync), miss| Column::Float(per_ray(hits, f, miss));
    let each3 = |f: &(dyn Fn(usize, &Crossing) -> DVec3 + Sync), miss| {
        Column::Vector(per_ray(hits, f, miss))
    };
    let each_u32 =
        |f: &(dyn Fn(usize, &Crossing) -> u32 + Sync), miss| Column::Index(per_ray(hits, f, miss));
    let locate = |i: usize, h: &Crossing| {
        let ray = source.ray(i);
        scene.locate_crossing(h, ray.origin, ray.dir)
    };
    match output {
        Output::T => each(&|_, h| h.t, f64::INFINITY),
        Output::Distance => each(&|i, h| h.t * source.ray(i).dir.length(), f64::INFINITY),
        Output::Z => {
            let (eye, forward) = source.view_axis().unwrap_or((DVec3::ZERO, DVec3::ZERO));
            each(
                &|i, h| (source.ray(i).at(h.t) - eye).dot(forward),
                f64::INFINITY,
            )
        }
        Output::Normal => each3(&|i, h| locate(i, h).normal, DVec3::ZERO),
        Output::Position => each3(&|i, h| source.ray(i).at(h.t), DVec3::INFINITY),
        Output::Id => each_u32(&|i, h| locate(i, h).object.id, 0),
        Output::Prim => each_u32(&|i, h| locate(i, h).prim, u32::MAX),
        Output::Bary => each3(
            &|i, h| {
                let ray = source.ray(i);
                let weights = scene.barycentric(h, ray.origin, ray.dir);
                weights.map_or(DVec3::ZERO, DVec3::from_array)
            },
            DVec3::ZERO,
        ),
    }
}

/// `f(i, hit)` for every ray `i` that hit, `miss` for the others, in parallel.
fn per_ray<T: Copy + Send + Sync>(
    hits: &[Option<Crossing>],
    f: &(dyn Fn(usize, &Crossing) -> T + Sync),
    miss: T,
) -> Vec<T> {
    (0..hits.len())
        .into_par_iter()
        .map(|i| hits[i].as_ref().map_or(miss, |h| f(i, h)))
        .collect()
}

/// Fills `outputs` (with their names) into a new dict of arrays of shape `shape` (+ `(3,)`
/// for vectors). The columns are computed with the GIL released.
pub fn fill_dict<'py>(
    py: Python<'py>,
    query: &Query,
    source: &(dyn RaySource + Sync),
    hits: &[Option<Crossing>],
    outputs: &[(String, Output)],
    shape: &[usize],
) -> PyResult<Bound<'py, PyDict>> {
    let columns: Vec<Column> = py.detach(|| {
        outputs
            .iter()
            .map(|(_, output)| column(query, source, hits, *output))
            .collect()
    });
    let dict = PyDict::new(py);
    for ((name, _), column) in outputs.iter().zip(columns) {
        let shape3 = [shape, &[3]].concat();
        let array = match column {
            Column::Float(v) => array(py, shape, v)?,
            Column::Index(v) => array(py, shape, v)?,
            Column::Vector(v) => array(py, &shape3, v.iter().flat_map(|p| p.to_array()).collect())?,
        };
        dict.set_item(name, array)?;
    }
    Ok(dict)
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
