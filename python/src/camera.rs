//! Cameras for `Scene.render`: the library's cameras (file cameras, look-at) and a pinhole
//! camera given by an intrinsic matrix, in the computer-vision convention.

use glam::{DMat3, DMat4, DVec3, DVec4};
use numpy::PyReadonlyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use raycast::camera::{Camera, Projection};
use raycast::geometry::Ray;
use raycast::render::{CameraView, RaySource};

/// How a [`PyCamera`] makes its rays.
#[derive(Debug, Clone)]
pub enum Kind {
    /// A library camera (glTF/USD conventions: looks down -Z, +Y up, vertical field of view).
    Scene(Camera),
    /// A pinhole camera: pixel (u, v) looks along `rotation · K⁻¹ (u + ½, v + ½, 1)` (looks
    /// down +Z, +Y down, as OpenCV and Open3D).
    Pinhole {
        k_inverse: DMat3,
        to_world: DMat4,
        width: usize,
        height: usize,
    },
}

/// A camera: from a scene file, `raycast.camera.look_at` or `raycast.camera.pinhole`.
#[pyclass(name = "Camera", module = "raycast", frozen)]
#[derive(Debug, Clone)]
pub struct PyCamera {
    pub kind: Kind,
}

#[pymethods]
impl PyCamera {
    /// Camera name (file cameras) or how it was made.
    #[getter]
    fn name(&self) -> String {
        match &self.kind {
            Kind::Scene(c) => c.name.clone(),
            Kind::Pinhole { .. } => "pinhole".into(),
        }
    }

    /// Camera-to-world matrix, (4, 4).
    #[getter]
    fn cam_to_world(&self) -> [[f64; 4]; 4] {
        let m = match &self.kind {
            Kind::Scene(c) => c.to_world,
            Kind::Pinhole { to_world, .. } => *to_world,
        };
        m.transpose().to_cols_array_2d()
    }

    /// Image size (width, height) a pinhole camera was made for; None otherwise.
    #[getter]
    fn size(&self) -> Option<(usize, usize)> {
        match &self.kind {
            Kind::Pinhole { width, height, .. } => Some((*width, *height)),
            Kind::Scene(_) => None,
        }
    }

    fn __repr__(&self) -> String {
        match &self.kind {
            Kind::Scene(c) => format!(
                "Camera(name={:?}, source={:?}, projection={:?})",
                c.name, c.source, c.projection
            ),
            Kind::Pinhole { width, height, .. } => format!("Camera(pinhole, {width}x{height})"),
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
    Ok(PyCamera {
        kind: Kind::Scene(camera),
    })
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
    let k = DMat3::from_cols_array_2d(&[0, 1, 2].map(|c| [0, 1, 2].map(|r| k[[r, c]])));
    let to_world =
        DMat4::from_cols_array_2d(&[0, 1, 2, 3].map(|c| [0, 1, 2, 3].map(|r| m[[r, c]])));
    let k_inverse = k.inverse();
    let affine = to_world.row(3) == DVec4::W;
    if !k_inverse.is_finite() || !to_world.is_finite() || !affine || to_world.determinant() == 0.0 {
        return Err(PyValueError::new_err(
            "K must be invertible and cam_to_world a finite invertible affine matrix (last row 0 0 0 1)",
        ));
    }
    check_size(width, height)?;
    Ok(PyCamera {
        kind: Kind::Pinhole {
            k_inverse,
            to_world,
            width,
            height,
        },
    })
}

/// Refuses an image side of 0 or more than the command line's largest.
fn check_size(width: usize, height: usize) -> PyResult<()> {
    let max = raycast::job::MAX_SIDE;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(PyValueError::new_err(format!(
            "image size {width}x{height} is out of range (1 to {max} per side)"
        )));
    }
    Ok(())
}

/// The pixels of a pinhole camera as rays, row-major from the top row.
pub struct PinholeView {
    k_inverse: DMat3,
    to_world: DMat4,
    width: usize,
    height: usize,
}

impl RaySource for PinholeView {
    fn len(&self) -> usize {
        self.width * self.height
    }

    fn ray(&self, index: usize) -> Ray {
        let (u, v) = (
            (index % self.width) as f64 + 0.5,
            (index / self.width) as f64 + 0.5,
        );
        let local = self.k_inverse * DVec3::new(u, v, 1.0);
        Ray::new(
            self.to_world.w_axis.truncate(),
            self.to_world.transform_vector3(local),
        )
    }

    fn row_width(&self) -> Option<usize> {
        Some(self.width)
    }

    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        let forward = self
            .to_world
            .transform_vector3(DVec3::Z)
            .normalize_or_zero();
        Some((self.to_world.w_axis.truncate(), forward))
    }
}

/// The rays of `camera` for a `width`×`height` image.
pub enum View {
    Scene(CameraView),
    Pinhole(PinholeView),
}

impl View {
    pub fn new(camera: &PyCamera, width: usize, height: usize) -> PyResult<View> {
        check_size(width, height)?;
        Ok(match &camera.kind {
            Kind::Scene(c) => View::Scene(CameraView::new(c.clone(), width, height)),
            Kind::Pinhole {
                k_inverse,
                to_world,
                width: w,
                height: h,
            } => {
                if (*w, *h) != (width, height) {
                    return Err(PyValueError::new_err(format!(
                        "this pinhole camera was made for {w}x{h} pixels, not {width}x{height}"
                    )));
                }
                View::Pinhole(PinholeView {
                    k_inverse: *k_inverse,
                    to_world: *to_world,
                    width,
                    height,
                })
            }
        })
    }

    pub fn source(&self) -> &(dyn RaySource + Sync) {
        match self {
            View::Scene(v) => v,
            View::Pinhole(v) => v,
        }
    }
}
