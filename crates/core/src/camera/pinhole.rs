//! Pinhole cameras in the computer-vision convention: an intrinsic matrix K for an image of a
//! fixed size, and camera-to-world matrices written in OpenGL's or OpenCV's axes.

use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DVec3};
use serde::Serialize;

/// The intrinsics of a pinhole camera in the computer-vision convention (OpenCV, Open3D,
/// nerfstudio): in the camera's frame +X is right, +Y down and +Z forward, and pixel (u, v)
/// (column u, row v from the top left) is centred at (u + ½, v + ½), so its ray runs along
/// K⁻¹ (u + ½, v + ½, 1). A centred principal point is (width / 2, height / 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pinhole {
    /// The intrinsic matrix K, row-major: `[[fx, s, cx], [0, fy, cy], [0, 0, 1]]`.
    pub k: [[f64; 3]; 3],
    /// The image width K is for, pixels.
    pub width: usize,
    /// The image height K is for, pixels.
    pub height: usize,
    /// K⁻¹, computed once.
    #[serde(skip)]
    k_inverse: DMat3,
}

impl Pinhole {
    /// The intrinsics `k` (row-major) of a `width`×`height` image; what is wrong with `k`, in
    /// a few words, when it is not finite and invertible with a last row of 0, 0, 1.
    pub fn new(k: [[f64; 3]; 3], width: usize, height: usize) -> Result<Pinhole> {
        if k.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::msg("K has a value that is not a finite number"));
        }
        if k[2] != [0.0, 0.0, 1.0] {
            return Err(Error::msg(format!(
                "K's last row must be 0, 0, 1, not {:?}",
                k[2]
            )));
        }
        let k_inverse = DMat3::from_cols_array_2d(&k).transpose().inverse();
        if !k_inverse.is_finite() {
            return Err(Error::msg("K is not invertible (a focal length is zero)"));
        }
        Ok(Pinhole {
            k,
            width,
            height,
            k_inverse,
        })
    }

    /// The pinhole of focal lengths `fx`, `fy` and principal point (`cx`, `cy`), no skew.
    pub fn from_focal([fx, fy, cx, cy]: [f64; 4], width: usize, height: usize) -> Result<Pinhole> {
        Pinhole::new(
            [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]],
            width,
            height,
        )
    }

    /// The direction of the ray through image point (`x`, `y`) (pixel (u, v) spans
    /// [u, u + 1] × [v, v + 1]) in the camera's frame, in raycast's axes (+Y up, looking down
    /// -Z): K⁻¹ (x, y, 1) with Y and Z negated.
    pub(super) fn direction(&self, x: f64, y: f64) -> DVec3 {
        let local = self.k_inverse * DVec3::new(x, y, 1.0);
        DVec3::new(local.x, -local.y, -local.z)
    }
}

/// The axes a camera-to-world matrix is written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CameraAxes {
    /// +X right, +Y up, looking down -Z: glTF, USD, OpenGL, Blender, nerfstudio.
    OpenGl,
    /// +X right, +Y down, looking down +Z: OpenCV, COLMAP, Open3D.
    OpenCv,
}

impl CameraAxes {
    /// The camera-to-world matrix in raycast's axes (OpenGL's) of `to_world`, written in these
    /// axes: OpenCV's Y and Z columns negated (exactly).
    pub fn to_opengl(self, to_world: DMat4) -> DMat4 {
        match self {
            CameraAxes::OpenGl => to_world,
            CameraAxes::OpenCv => DMat4::from_cols(
                to_world.x_axis,
                -to_world.y_axis,
                -to_world.z_axis,
                to_world.w_axis,
            ),
        }
    }
}

impl std::str::FromStr for CameraAxes {
    type Err = Error;
    fn from_str(text: &str) -> Result<CameraAxes> {
        match text.trim().to_ascii_lowercase().as_str() {
            "opengl" => Ok(CameraAxes::OpenGl),
            "opencv" => Ok(CameraAxes::OpenCv),
            _ => Err(Error::msg(format!(
                "'{text}' is not a camera axis convention: give opengl or opencv"
            ))),
        }
    }
}

/// A camera-to-world matrix (row-major, as written in files and on the command line) as
/// glam's matrix; what is wrong with it, in a few words, when it is not a finite invertible
/// affine matrix (last row 0, 0, 0, 1).
pub fn camera_to_world(rows: [[f64; 4]; 4]) -> Result<DMat4> {
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::msg(
            "the camera-to-world matrix has a value that is not a finite number",
        ));
    }
    if rows[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(Error::msg(format!(
            "the camera-to-world matrix's last row must be 0, 0, 0, 1, not {:?}",
            rows[3]
        )));
    }
    let matrix = DMat4::from_cols_array_2d(&rows).transpose();
    if matrix.determinant() == 0.0 {
        return Err(Error::msg("the camera-to-world matrix is not invertible"));
    }
    Ok(matrix)
}
