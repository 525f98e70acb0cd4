//! The per-ray outputs ("AOVs") of `cast` and `render`, computed in the same parallel pass as
//! the nearest-hit search (each ray's outputs are written while its hit is at hand), with the
//! same expressions as the library's `render::render`, so that the values are bit-identical to
//! the command line's buffers.

use glam::DVec3;
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use raycast::geometry::Ray;
use raycast::query::Query;
use raycast::render::RaySource;
use raycast::scene::{Crossing, Located};
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

    /// Whether the output needs the hit resolved to its object and primitive.
    fn needs_locate(self) -> bool {
        matches!(self, Output::Normal | Output::Id | Output::Prim)
    }

    /// The value on a miss.
    fn miss(self) -> Value {
        match self {
            Output::T | Output::Distance | Output::Z => Value::Float(f64::INFINITY),
            Output::Position => Value::Vector(DVec3::INFINITY),
            Output::Normal | Output::Bary => Value::Vector(DVec3::ZERO),
            Output::Id => Value::Index(0),
            Output::Prim => Value::Index(u32::MAX),
        }
    }

    /// The value at the hit `at`.
    fn value(self, at: &At) -> Value {
        let (ray, hit) = (at.ray, at.hit);
        let located = || at.located.as_ref();
        match self {
            Output::T => Value::Float(hit.t),
            Output::Distance => Value::Float(hit.t * ray.dir.length()),
            Output::Z => Value::Float((ray.at(hit.t) - at.eye).dot(at.forward)),
            Output::Position => Value::Vector(ray.at(hit.t)),
            Output::Normal => located().map_or(self.miss(), |l| Value::Vector(l.normal)),
            Output::Id => located().map_or(self.miss(), |l| Value::Index(l.object.id)),
            Output::Prim => located().map_or(self.miss(), |l| Value::Index(l.prim)),
            Output::Bary => {
                let weights = at.query.scene.barycentric(hit, ray.origin, ray.dir);
                Value::Vector(weights.map_or(DVec3::ZERO, DVec3::from_array))
            }
        }
    }
}

/// What the outputs of one ray's hit are computed from.
struct At<'a> {
    query: &'a Query<'a>,
    ray: &'a Ray,
    hit: &'a Crossing,
    /// The hit's object and primitive, when an output needs them.
    located: Option<Located<'a>>,
    /// The camera's eye and view axis (zeros without a camera).
    eye: DVec3,
    forward: DVec3,
}

/// One output's value for one ray.
enum Value {
    Float(f64),
    Vector(DVec3),
    Index(u32),
}

/// One output's values for every ray (vectors flattened, three per ray).
enum Column {
    Float(Vec<f64>),
    Vector(Vec<f64>),
    Index(Vec<u32>),
}

impl Column {
    fn new(output: Output, n: usize) -> Column {
        match output.miss() {
            Value::Float(_) => Column::Float(vec![0.0; n]),
            Value::Vector(_) => Column::Vector(vec![0.0; 3 * n]),
            Value::Index(_) => Column::Index(vec![0; n]),
        }
    }

    /// The column cut into blocks of `BLOCK` rays.
    fn blocks(&mut self) -> Box<dyn Iterator<Item = Slot<'_>> + '_> {
        match self {
            Column::Float(v) => Box::new(v.chunks_mut(BLOCK).map(Slot::Float)),
            Column::Vector(v) => Box::new(v.chunks_mut(3 * BLOCK).map(Slot::Vector)),
            Column::Index(v) => Box::new(v.chunks_mut(BLOCK).map(Slot::Index)),
        }
    }
}

/// One block of a column.
enum Slot<'a> {
    Float(&'a mut [f64]),
    Vector(&'a mut [f64]),
    Index(&'a mut [u32]),
}

impl Slot<'_> {
    /// Stores the `j`-th value of the block (a column holds its output's type of value).
    fn set(&mut self, j: usize, value: Value) {
        match (self, value) {
            (Slot::Float(s), Value::Float(v)) => s[j] = v,
            (Slot::Vector(s), Value::Vector(v)) => {
                s[3 * j..3 * j + 3].copy_from_slice(&v.to_array())
            }
            (Slot::Index(s), Value::Index(v)) => s[j] = v,
            _ => unreachable!("a column is made for its output's type"),
        }
    }
}

/// Rays per parallel task.
const BLOCK: usize = 1024;

/// The rays of a query: their source, each ray's `(tmin, tmax]`, and which missing rays are
/// refused (`refused(i)` for a ray without a hit). Generic, so that reading a ray and its range
/// is inlined into the search loop.
pub struct Rays<'a, S: ?Sized, R, F> {
    /// The rays.
    pub source: &'a S,
    /// Ray `i`'s parameter range.
    pub range: R,
    /// Whether ray `i`, which has no hit, is one that cannot be traced.
    pub refused: F,
}

/// Finds the nearest hit of every ray and computes `outputs` from it, in one parallel pass.
/// Returns the columns, or the first refused ray.
fn trace<S, R, F>(
    query: &Query,
    rays: &Rays<S, R, F>,
    outputs: &[Output],
) -> Result<Vec<Column>, usize>
where
    S: RaySource + Sync + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
    F: Fn(usize) -> bool + Sync,
{
    let n = rays.source.len();
    let mut columns: Vec<Column> = outputs.iter().map(|&o| Column::new(o, n)).collect();
    let mut blocks: Vec<Vec<Slot>> = (0..n.div_ceil(BLOCK)).map(|_| Vec::new()).collect();
    for column in &mut columns {
        for (block, slot) in blocks.iter_mut().zip(column.blocks()) {
            block.push(slot);
        }
    }
    let locate = outputs.iter().any(|o| o.needs_locate());
    let (eye, forward) = rays
        .source
        .view_axis()
        .unwrap_or((DVec3::ZERO, DVec3::ZERO));
    let refused = blocks
        .into_par_iter()
        .enumerate()
        .filter_map(|(b, mut slots)| {
            let mut refused = None;
            for i in b * BLOCK..n.min((b + 1) * BLOCK) {
                let ray = rays.source.ray(i);
                let (t0, t1) = (rays.range)(i);
                let hit = query.nearest(&ray, t0, t1);
                let at = hit.as_ref().map(|hit| At {
                    query,
                    ray: &ray,
                    hit,
                    located: locate.then(|| query.scene.locate_crossing(hit, ray.origin, ray.dir)),
                    eye,
                    forward,
                });
                if at.is_none() && refused.is_none() && (rays.refused)(i) {
                    refused = Some(i);
                }
                for (slot, output) in slots.iter_mut().zip(outputs) {
                    let value = at.as_ref().map_or(output.miss(), |at| output.value(at));
                    slot.set(i - b * BLOCK, value);
                }
            }
            refused
        })
        .min();
    match refused {
        Some(i) => Err(i),
        None => Ok(columns),
    }
}

/// Traces `rays` and returns a dict of `outputs` (with their names), arrays of shape `shape`
/// (+ `(3,)` for vectors), or the first refused ray. The tracing runs with the GIL released.
pub fn trace_dict<'py, S, R, F>(
    py: Python<'py>,
    query: &Query,
    rays: &Rays<S, R, F>,
    outputs: &[(String, Output)],
    shape: &[usize],
) -> PyResult<Result<Bound<'py, PyDict>, usize>>
where
    S: RaySource + Sync + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
    F: Fn(usize) -> bool + Sync,
{
    let kinds: Vec<Output> = outputs.iter().map(|(_, o)| *o).collect();
    let columns = match py.detach(|| trace(query, rays, &kinds)) {
        Ok(columns) => columns,
        Err(i) => return Ok(Err(i)),
    };
    let dict = PyDict::new(py);
    for ((name, _), column) in outputs.iter().zip(columns) {
        let array = match column {
            Column::Float(v) => array(py, shape, v)?,
            Column::Index(v) => array(py, shape, v)?,
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
