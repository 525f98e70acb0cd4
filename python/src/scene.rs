//! `Scene`: a loaded scene with its octree, and the queries on it.

use crate::arrays::RayArrays;
use crate::camera::PyCamera;
use crate::fill::{array, trace_dict};
use crate::objects::{self, MeshArrays, Objects, QuadricArgs};
use crate::threads;
use glam::DVec3;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use raycast_core::accel::{Octree, OctreeParams};
use raycast_core::geometry::RaySource;
use raycast_core::render::{Aov, CameraView, Rays};
use raycast_core::scene::Scene;
use raycast_core::trace::{self, Tracer};
use raycast_io::import::{self, LoadOptions};
use std::path::PathBuf;
use std::sync::Arc;

/// Where a scene came from, so that it can be loaded again (pickling).
#[derive(Debug, Clone)]
pub(crate) enum Source {
    Path(PathBuf),
    Bytes {
        data: Vec<u8>,
        name: PathBuf,
    },
    /// `Scene.from_arrays` or `Scene.from_objects`: the objects, kept for pickling.
    Arrays(Objects),
}

/// What poses a scene: the glTF animation time and animation (`--time`, `--animation`), or
/// the USD time code (`--time`) and variant selections (`--variant`).
#[derive(Debug, Clone, Default)]
pub struct Pose {
    /// glTF seconds or USD time code.
    pub time: Option<f64>,
    /// The glTF animation.
    pub animation: Option<String>,
    /// USD (set, variant) selections.
    pub variants: Vec<(String, String)>,
}

/// A loaded scene and its octree (the compiled half of `raycast.Scene`).
#[pyclass(name = "_Scene", module = "raycast._raycast", frozen)]
pub struct PyScene {
    scene: Scene,
    octree: Octree,
    source: Source,
    choice: Option<String>,
    /// What posed it.
    pose: Pose,
    /// The file as opened (a glTF document with its buffers decoded), which `at` poses again
    /// without reading the file.
    opened: Arc<import::Source>,
}

impl PyScene {
    /// The scene `source` gives, posed, with its octree.
    pub(crate) fn build(
        py: Python<'_>,
        source: Source,
        choice: Option<String>,
        pose: Pose,
    ) -> PyResult<PyScene> {
        if pose.time.is_some_and(|t| !t.is_finite()) {
            return Err(PyValueError::new_err(
                "time must be a finite number (glTF seconds, USD time code)",
            ));
        }
        if pose.animation.is_some() && pose.time.is_none() {
            return Err(PyValueError::new_err("animation needs a time"));
        }
        let variants = pose
            .variants
            .iter()
            .map(|(set, name)| {
                import::usd::parse_choice(&format!("{set}={name}"))
                    .map_err(|e| PyValueError::new_err(e.to_string()))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let options = LoadOptions {
            scene: choice.clone(),
            time: pose.time,
            animation: pose.animation.clone(),
            variants,
            ..LoadOptions::default()
        };
        let opened = py.detach(|| match &source {
            Source::Path(path) => import::open(path, &options),
            Source::Bytes { data, name } => import::open_bytes(data.clone(), name, &options),
            Source::Arrays(objects) => Ok(objects.source()),
        });
        let opened = Arc::new(opened.map_err(|e| crate::to_pyerr(py, e))?);
        PyScene::posed(py, source, choice, pose, opened)
    }

    /// The scene `opened` gives at `pose.time`, with its octree.
    fn posed(
        py: Python<'_>,
        source: Source,
        choice: Option<String>,
        pose: Pose,
        opened: Arc<import::Source>,
    ) -> PyResult<PyScene> {
        let built = py.detach(|| {
            let scene = opened.at(pose.time)?;
            let octree = trace::build_octree(&scene, OctreeParams::default());
            Ok((scene, octree))
        });
        let (scene, octree) = built.map_err(|e| crate::to_pyerr(py, e))?;
        Ok(PyScene {
            scene,
            octree,
            source,
            choice,
            pose,
            opened,
        })
    }

    /// The scene.
    pub(crate) fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene and its octree, for every query.
    pub(crate) fn tracer(&self) -> Tracer<'_> {
        Tracer::new(&self.scene, &self.octree)
    }

    /// `cast()` of the rays of `source` in their `range` (see [`trace_dict`]).
    fn cast_rays<'py, S, R>(
        &self,
        py: Python<'py>,
        source: &S,
        range: R,
        outputs: &[(String, Aov)],
        shape: &[usize],
        nthreads: usize,
    ) -> PyResult<Result<Bound<'py, PyDict>, usize>>
    where
        S: RaySource + ?Sized,
        R: Fn(usize) -> (f64, f64) + Sync,
    {
        let rays = Rays {
            source,
            range,
            refuse_untraceable: true,
        };
        trace_dict(py, &self.tracer(), &rays, outputs, shape, nthreads)
    }
}

/// A scene of one mesh from arrays (`Scene.from_arrays`; see [`objects::one_mesh`]).
#[pyfunction]
pub fn load_arrays(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
) -> PyResult<PyScene> {
    let objects = objects::one_mesh(vertices, faces)?;
    PyScene::build(py, Source::Arrays(objects), None, Pose::default())
}

/// A scene of meshes and quadrics from arrays (`Scene.from_objects`; see
/// [`objects::many`]).
#[pyfunction]
pub fn load_objects(
    py: Python<'_>,
    meshes: Vec<(String, PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, i64>)>,
    quadrics: Vec<QuadricArgs>,
) -> PyResult<PyScene> {
    let objects = objects::many(meshes, quadrics)?;
    PyScene::build(py, Source::Arrays(objects), None, Pose::default())
}

/// Loads the scene file `path` (`scene`: a glTF scene by index or name, a USD prim path;
/// `time`, `animation`: the glTF animations played to that time, or the USD time code;
/// `variants`: USD (set, variant) selections).
#[pyfunction]
#[pyo3(signature = (path, scene = None, time = None, animation = None, variants = None))]
pub fn load_path(
    py: Python<'_>,
    path: PathBuf,
    scene: Option<String>,
    time: Option<f64>,
    animation: Option<String>,
    variants: Option<Vec<(String, String)>>,
) -> PyResult<PyScene> {
    // Absolute, so that a pickled scene loads in a worker with another working folder.
    let path = std::path::absolute(&path).unwrap_or(path);
    let pose = Pose {
        time,
        animation,
        variants: variants.unwrap_or_default(),
    };
    PyScene::build(py, Source::Path(path), scene, pose)
}

/// Loads a scene from bytes, as if read from the file `name` (its extension is the format).
#[pyfunction]
#[pyo3(signature = (data, name, scene = None, time = None, animation = None))]
pub fn load_bytes(
    py: Python<'_>,
    data: Vec<u8>,
    name: PathBuf,
    scene: Option<String>,
    time: Option<f64>,
    animation: Option<String>,
) -> PyResult<PyScene> {
    let pose = Pose {
        time,
        animation,
        variants: Vec::new(),
    };
    PyScene::build(py, Source::Bytes { data, name }, scene, pose)
}

/// The rays as the Python layer hands them over: float64 (N, 3) origins and directions, and
/// `tmin`, `tmax` of length N or 1.
type RayArgs<'py> = (
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
);

/// Borrows the rays (no copy).
fn rays<'a>(args: &'a RayArgs<'_>) -> PyResult<RayArrays<'a>> {
    let (origins, directions, tmin, tmax) = args;
    RayArrays::new(
        origins.as_array(),
        directions.as_array(),
        tmin.as_array(),
        tmax.as_array(),
    )
}

#[pymethods]
impl PyScene {
    /// The nearest hit of each ray in `(tmin, tmax]`, as a dict of the requested outputs.
    fn cast<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        outputs: Vec<String>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let outputs = parse_outputs(&outputs, false)?;
        let rays = self::rays(&rays)?;
        let shape = [rays.len()];
        // Contiguous arrays with one range are read without a choice per ray.
        let traced = match rays.contiguous() {
            Some((contiguous, range)) => {
                self.cast_rays(py, &contiguous, |_| range, &outputs, &shape, nthreads)
            }
            None => self.cast_rays(py, &rays, |i| rays.range(i), &outputs, &shape, nthreads),
        }?;
        traced.map_err(|i| rays.error(i))
    }

    /// Whether each ray hits anything in `(tmin, tmax]`.
    fn occluded<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rays = self::rays(&rays)?;
        let query = self.tracer();
        let hit = threads::map(py, nthreads, rays.len(), |i| {
            let (t0, t1) = rays.range(i);
            query.occluded(&rays.ray(i), t0, t1)
        })?;
        py.detach(|| rays.check(|i| !hit[i]))?;
        array(py, &[hit.len()], hit)
    }

    /// Every surface crossing of each ray in `(tmin, tmax]`, in CSR form:
    /// (ray_splits uint64 (N+1,), t float64, id uint32, prim uint32).
    fn crossings<'py>(
        &self,
        py: Python<'py>,
        rays: RayArgs<'py>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let rays = self::rays(&rays)?;
        let query = self.tracer();
        let lists = py.detach(|| {
            let trace = || query.hit_lists(&rays, |i| rays.range(i), usize::MAX);
            let lists = threads::run(nthreads, trace)?;
            rays.check(|i| lists.splits[i] == lists.splits[i + 1])?;
            PyResult::Ok(lists)
        })?;
        let n = lists.t.len();
        PyTuple::new(
            py,
            [
                array(py, &[lists.splits.len()], lists.splits)?,
                array(py, &[n], lists.t)?,
                array(py, &[n], lists.id)?,
                array(py, &[n], lists.prim)?,
            ],
        )
    }

    /// Whether each (N, 3) point lies inside the scene's closed surfaces (crossing parity).
    fn contains<'py>(
        &self,
        py: Python<'py>,
        points: PyReadonlyArray2<'py, f64>,
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyAny>> {
        let points = points.as_array();
        if points.ncols() != 3 {
            return Err(PyValueError::new_err("points must be (N, 3)"));
        }
        let query = self.tracer();
        let inside = threads::map(py, nthreads, points.nrows(), |i| {
            query.contains(DVec3::new(points[[i, 0]], points[[i, 1]], points[[i, 2]]))
        })?;
        array(py, &[inside.len()], inside)
    }

    /// Rows `first..last` of an image of `width`×`height` pixels seen by `camera`: a dict of
    /// (last − first, W[, 3]) arrays (the rows of the whole image, bit for bit: each pixel's
    /// ray is its own).
    #[allow(clippy::too_many_arguments)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        camera: &PyCamera,
        width: usize,
        height: usize,
        outputs: Vec<String>,
        rows: (usize, usize),
        nthreads: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        let outputs = parse_outputs(&outputs, true)?;
        let view = crate::camera::view(camera, width, height)?;
        let (first, last) = rows;
        if first > last || last > height {
            return Err(PyValueError::new_err(format!(
                "rows {first}..{last} are not within the image's {height}"
            )));
        }
        let window = Rows {
            view: &view,
            start: first * width,
            len: (last - first) * width,
        };
        let rays = Rays {
            source: &window,
            range: |_| (0.0, f64::INFINITY),
            refuse_untraceable: false,
        };
        let shape = [last - first, width];
        trace_dict(py, &self.tracer(), &rays, &outputs, &shape, nthreads)?
            .map_err(|i| PyValueError::new_err(format!("camera ray {i} cannot be traced")))
    }

    /// The materials, named as the file names them (`material` m is `materials[m - 1]`).
    fn materials(&self) -> Vec<String> {
        self.scene.materials().to_vec()
    }

    /// The warnings for `outputs` that read attributes some objects lack (one line each).
    fn attribute_warnings(&self, outputs: Vec<String>) -> PyResult<Vec<String>> {
        let aovs: Vec<Aov> = parse_outputs(&outputs, true)?
            .into_iter()
            .map(|(_, a)| a)
            .collect();
        Ok(raycast_core::render::attribute_warnings(&self.scene, &aovs))
    }

    /// The object table: a list of dicts (id, name, kind, source, triangles, bounds).
    fn objects<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.scene
            .objects
            .iter()
            .map(|o| {
                let d = PyDict::new(py);
                d.set_item("id", o.id)?;
                d.set_item("name", &o.name)?;
                let kind = match o.kind {
                    raycast_core::scene::ObjectKind::Mesh => "mesh",
                    raycast_core::scene::ObjectKind::Quadric => "quadric",
                };
                d.set_item("kind", kind)?;
                d.set_item("source", &o.source)?;
                d.set_item("triangles", o.triangles)?;
                let b = self.scene.object_bounds(o);
                d.set_item("bounds", [b.min.to_array(), b.max.to_array()])?;
                Ok(d)
            })
            .collect()
    }

    /// Object `id`'s triangles in world coordinates, a (T, 3, 3) float64 array in the order of
    /// its `prim` numbers (empty for a quadric).
    fn triangles<'py>(&self, py: Python<'py>, id: u32) -> PyResult<Bound<'py, PyAny>> {
        let object = id
            .checked_sub(1)
            .and_then(|i| self.scene.objects.get(i as usize))
            .ok_or_else(|| PyValueError::new_err(format!("no object has id {id}")))?;
        let triangles = self.scene.mesh_triangles(object);
        let values = triangles.iter().flatten().flat_map(|p| p.to_array());
        array(py, &[triangles.len(), 3, 3], values.collect())
    }

    /// World bounds [[xmin, ymin, zmin], [xmax, ymax, zmax]].
    fn bounds(&self) -> [[f64; 3]; 2] {
        let b = self.scene.world_bounds();
        [b.min.to_array(), b.max.to_array()]
    }

    /// The file's cameras.
    fn cameras(&self) -> Vec<PyCamera> {
        let cameras = self.scene.cameras.iter().cloned();
        cameras.map(|camera| PyCamera { camera }).collect()
    }

    /// The same file posed at `time` (glTF seconds, USD time code), as `load(..., time=time)`
    /// with this scene's other choices: a glTF document is not read again, unless this
    /// scene was loaded without a time (its animations' data were not read then).
    fn at(&self, py: Python<'_>, time: f64) -> PyResult<PyScene> {
        let pose = Pose {
            time: Some(time),
            ..self.pose.clone()
        };
        let (source, choice) = (self.source.clone(), self.choice.clone());
        match self.opened.animating() && time.is_finite() {
            true => PyScene::posed(py, source, choice, pose, Arc::clone(&self.opened)),
            false => PyScene::build(py, source, choice, pose),
        }
    }

    /// What `raycast info --json` prints, as a JSON string.
    fn info_json(&self) -> PyResult<String> {
        let info = raycast_io::info::SceneInfo::new(&self.scene);
        serde_json::to_string(&info).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// What loads this scene again: (path, None, scene, time, animation, variants) or (bytes,
    /// name, scene, time, animation, variants).
    fn source<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let Pose {
            time,
            animation,
            variants,
        } = self.pose.clone();
        match &self.source {
            Source::Path(path) => (
                path.clone(),
                py.None(),
                self.choice.clone(),
                time,
                animation,
                variants,
            )
                .into_pyobject(py),
            Source::Bytes { data, name } => (
                PyBytes::new(py, data),
                name.clone(),
                self.choice.clone(),
                time,
                animation,
                variants,
            )
                .into_pyobject(py),
            Source::Arrays(_) => Err(PyValueError::new_err(
                "a scene made from arrays has no file; see arrays()",
            )),
        }
    }

    /// Whether `Scene.from_arrays` or `Scene.from_objects` made this scene (without copying
    /// its arrays out).
    fn is_arrays(&self) -> bool {
        matches!(self.source, Source::Arrays(_))
    }

    /// The (meshes, quadrics) a scene made from arrays was made from, as `load_objects`
    /// takes them; None for a scene loaded from a file.
    #[allow(clippy::type_complexity)]
    fn arrays<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Vec<MeshArrays<'py>>, Vec<QuadricArgs>)>> {
        match &self.source {
            Source::Arrays(objects) => objects.arrays(py).map(Some),
            _ => Ok(None),
        }
    }
}

fn parse_outputs(names: &[String], camera: bool) -> PyResult<Vec<(String, Aov)>> {
    names
        .iter()
        .map(|n| crate::fill::parse(n, camera).map(|o| (n.clone(), o)))
        .collect::<Result<_, _>>()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Consecutive pixels of a camera image (whole rows), as a ray source of their own.
struct Rows<'a> {
    view: &'a CameraView,
    start: usize,
    len: usize,
}

impl RaySource for Rows<'_> {
    fn len(&self) -> usize {
        self.len
    }

    fn ray(&self, index: usize) -> raycast_core::geometry::Ray {
        self.view.ray(self.start + index)
    }

    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        self.view.view_axis()
    }

    fn row_width(&self) -> Option<usize> {
        self.view.row_width()
    }
}
