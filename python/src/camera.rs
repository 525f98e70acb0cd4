//! Cameras for `Scene.render`: the library's cameras (file cameras, look-at) and a pinhole
//! camera given by an intrinsic matrix, in the computer-vision convention.

use glam::DVec3;
use numpy::PyReadonlyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use raycast_core::camera::{camera_to_world, Camera, CameraAxes, Pinhole, Projection};
use raycast_core::render::CameraView;

/// A camera: from a scene file, `raycast.camera.look_at` or `raycast.camera.pinhole` (a
/// library camera with a pinhole projection: the command line's `--K` and `--cam-to-world`).
#[pyclass(name = "Camera", module = "raycast", frozen)]
#[derive(Debug, Clone)]
pub struct PyCamera {
    pub camera: Camera,
}

impl PyCamera {
    /// The pinhole projection, for a pinhole camera.
    fn pinhole(&self) -> Option<&Pinhole> {
        match &self.camera.projection {
            Projection::Pinhole(p) => Some(p),
            _ => None,
        }
    }
}

#[pymethods]
impl PyCamera {
    /// Camera name (file cameras) or how it was made.
    #[getter]
    fn name(&self) -> String {
        self.camera.name.clone()
    }

    /// Camera-to-world matrix, (4, 4): in the axes the camera was given in (OpenCV's for a
    /// pinhole camera, glTF's otherwise).
    #[getter]
    fn cam_to_world(&self) -> [[f64; 4]; 4] {
        let m = self.camera.to_world;
        let m = match self.pinhole() {
            // OpenCV's axes from OpenGL's: the Y and Z columns negated back (exactly).
            Some(_) => CameraAxes::OpenCv.to_opengl(m),
            None => m,
        };
        m.transpose().to_cols_array_2d()
    }

    /// Image size (width, height) a pinhole camera was made for; None otherwise.
    #[getter]
    fn size(&self) -> Option<(usize, usize)> {
        self.pinhole().map(|p| (p.width, p.height))
    }

    fn __repr__(&self) -> String {
        match self.pinhole() {
            Some(p) => format!("Camera(pinhole, {}x{})", p.width, p.height),
            None => format!(
                "Camera(name={:?}, source={:?}, projection={:?})",
                self.camera.name, self.camera.source, self.camera.projection
            ),
        }
    }
}

fn vec3(v: [f64; 3], what: &str) -> PyResult<DVec3> {
    let v = DVec3::from_array(v);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PyValueError::new_err(format!(
            "{what} must be three finite numbers, got {v}"
        )))
    }
}

/// A perspective camera at `eye` looking at `target`; `yfov_deg` is the vertical field of view.
#[pyfunction]
#[pyo3(signature = (eye, target, up = [0.0, 1.0, 0.0], yfov_deg = 45.0))]
pub fn look_at(
    py: Python<'_>,
    eye: [f64; 3],
    target: [f64; 3],
    up: [f64; 3],
    yfov_deg: f64,
) -> PyResult<PyCamera> {
    if !(yfov_deg > 0.0 && yfov_deg < 180.0) {
        return Err(PyValueError::new_err(format!(
            "yfov_deg must lie strictly between 0 and 180, got {yfov_deg}"
        )));
    }
    let projection = Projection::Perspective {
        yfov: yfov_deg.to_radians(),
    };
    let camera = Camera::look_at(
        vec3(eye, "eye")?,
        vec3(target, "target")?,
        vec3(up, "up")?,
        projection,
    )
    .map_err(|e| crate::to_pyerr(py, e.as_usage()))?;
    Ok(PyCamera { camera })
}

/// A pinhole camera from the 3×3 intrinsic matrix `K` and the 4×4 camera-to-world matrix.
#[pyfunction]
pub fn pinhole(
    k: PyReadonlyArray2<'_, f64>,
    cam_to_world: PyReadonlyArray2<'_, f64>,
    width: usize,
    height: usize,
) -> PyResult<PyCamera> {
    let (k, m) = (k.as_array(), cam_to_world.as_array());
    if k.shape() != [3, 3] || m.shape() != [4, 4] {
        return Err(PyValueError::new_err(format!(
            "K must be (3, 3) and cam_to_world (4, 4), got {:?} and {:?}",
            k.shape(),
            m.shape()
        )));
    }
    check_size(width, height)?;
    let k_rows = [0, 1, 2].map(|r| [0, 1, 2].map(|c| k[[r, c]]));
    let m_rows = [0, 1, 2, 3].map(|r| [0, 1, 2, 3].map(|c| m[[r, c]]));
    let pinhole =
        Pinhole::new(k_rows, width, height).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let to_world = camera_to_world(m_rows).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let to_world = CameraAxes::OpenCv.to_opengl(to_world);
    let camera = Camera::pinhole(
        pinhole,
        to_world,
        "pinhole".into(),
        "raycast.camera.pinhole".into(),
    );
    Ok(PyCamera { camera })
}

/// The views of a camera file (`--views`: a nerfstudio / instant-ngp `transforms.json` or a
/// plain list of K and cam_to_world), each as (name, pinhole camera); `width` and `height`
/// stand in for an image size the file does not give.
#[pyfunction]
#[pyo3(signature = (path, width = None, height = None))]
pub fn read_views(
    py: Python<'_>,
    path: std::path::PathBuf,
    width: Option<usize>,
    height: Option<usize>,
) -> PyResult<Vec<(Option<String>, PyCamera)>> {
    let views = raycast_core::camera::views::read(&path, width.zip(height))
        .map_err(|e| crate::to_pyerr(py, e))?;
    let camera = |view: &raycast_core::camera::views::View| PyCamera {
        camera: Camera::pinhole(
            view.pinhole,
            view.to_world,
            view.name.clone().unwrap_or_else(|| "pinhole".into()),
            format!("views file {}", path.display()),
        ),
    };
    Ok(views.iter().map(|v| (v.name.clone(), camera(v))).collect())
}

/// Refuses an image side of 0 or more than the command line's largest.
fn check_size(width: usize, height: usize) -> PyResult<()> {
    let max = raycast_core::camera::MAX_SIDE;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(PyValueError::new_err(format!(
            "image size {width}x{height} is out of range (1 to {max} per side)"
        )));
    }
    Ok(())
}

/// The rays of `camera` for a `width`×`height` image (a pinhole camera's own size only).
pub fn view(camera: &PyCamera, width: usize, height: usize) -> PyResult<CameraView> {
    check_size(width, height)?;
    if let Some(p) = camera.pinhole() {
        if (p.width, p.height) != (width, height) {
            return Err(PyValueError::new_err(format!(
                "this pinhole camera was made for {}x{} pixels, not {width}x{height}",
                p.width, p.height
            )));
        }
    }
    Ok(CameraView::new(camera.camera.clone(), width, height))
}
