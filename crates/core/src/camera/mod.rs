//! Cameras: the glTF conventions (look down local -Z, +Y up, vertical field of view), framing
//! of a whole scene, and the per-pixel ray generation.

use crate::error::{Error, Result};
use crate::geometry::{Aabb, Ray};
use framing::fit_eye;
use glam::{DMat4, DVec3, DVec4};
use serde::Serialize;

mod framing;
mod pinhole;
pub mod views;
pub use pinhole::{camera_to_world, CameraAxes, Pinhole};

/// Largest image side accepted, in pixels, by the command line, views files and Python.
pub const MAX_SIDE: usize = 1 << 15;

/// How a camera projects.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Projection {
    /// Pinhole camera with a vertical field of view in radians.
    Perspective {
        /// Vertical field of view, radians.
        yfov: f64,
    },
    /// Parallel projection; `ymag` is half the view height.
    Orthographic {
        /// Half the view height in scene units.
        ymag: f64,
    },
    /// A pinhole camera given by its intrinsic matrix, for an image of a fixed size.
    Pinhole(Pinhole),
}

/// A camera placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Name (glTF camera or node name), or a description for generated cameras.
    pub name: String,
    /// Where it came from, e.g. `gltf camera 0`, `auto`, `command line`.
    pub source: String,
    /// Projection.
    pub projection: Projection,
    /// Width / height the file asks for, if any.
    pub aspect_ratio: Option<f64>,
    /// Near clipping distance (reported only; rays start at the eye).
    pub znear: f64,
    /// Far clipping distance, `None` for infinite (reported only).
    pub zfar: Option<f64>,
    /// Camera-to-world matrix in raycast's axes (+Y up, looking down -Z), with an
    /// orthonormal rotation part, except for a pinhole camera (whose matrix is used as given).
    pub to_world: DMat4,
}

/// The vertical field of view of the automatic cameras ([`Camera::framing_image`],
/// [`Camera::framing_from`]), in radians.
pub const AUTO_YFOV: f64 = 0.8;

impl Camera {
    /// A pinhole camera of intrinsics `pinhole` placed by `to_world` (raycast's axes, used as
    /// given), named `name`, from `source`.
    pub fn pinhole(pinhole: Pinhole, to_world: DMat4, name: String, source: String) -> Camera {
        Camera {
            name,
            source,
            projection: Projection::Pinhole(pinhole),
            aspect_ratio: None,
            znear: 0.0,
            zfar: None,
            to_world,
        }
    }

    /// A camera at `eye` looking at `target`, with `up` giving the vertical.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3, projection: Projection) -> Result<Camera> {
        let back = (eye - target).try_normalize().ok_or_else(|| {
            Error::usage("the camera's eye and target are the same point (--eye, --target)")
        })?;
        if up.try_normalize().is_none() {
            return Err(Error::usage("the camera's up vector is zero (--up)"));
        }
        let right = up.cross(back).try_normalize().ok_or_else(|| {
            Error::usage("the camera's up vector is parallel to the view direction (--up)")
        })?;
        let up = back.cross(right);
        Ok(Camera {
            name: "camera".into(),
            source: "command line".into(),
            projection,
            aspect_ratio: None,
            znear: 0.0,
            zfar: None,
            to_world: DMat4::from_cols(
                right.extend(0.0),
                up.extend(0.0),
                back.extend(0.0),
                eye.extend(1.0),
            ),
        })
    }

    /// A perspective camera framing all of `bounds` from the front (+Z side, slightly from
    /// the right and above), 0.8 rad vertical field of view.
    pub fn framing(bounds: &Aabb) -> Camera {
        Camera::framing_from(bounds, DVec3::new(0.4, 0.3, 1.0))
    }

    /// The automatic camera: a perspective view (0.8 rad vertical field of view) from the
    /// front, slightly from the right and above, with `up` (+Y, or +Z for a Z-up USD stage) as
    /// the vertical, placed so that the projections of `points` (the scene's vertices) fill an
    /// image of width / height `aspect` to 95 % in the axis that binds, centred in both axes:
    /// a wide image of a wide scene is filled across, and the empty corners of a bounding box
    /// (a chess board's air above the low pieces) take no room. `bounds` stands in when there
    /// are no points.
    pub fn framing_image(points: &[DVec3], bounds: &Aabb, aspect: f64, up: DVec3) -> Camera {
        let yfov = AUTO_YFOV;
        let bounds = if bounds.is_empty() {
            Aabb::new(DVec3::splat(-1.0), DVec3::ONE)
        } else {
            *bounds
        };
        let corners = bounds.corners();
        let points = if points.is_empty() {
            &corners[..]
        } else {
            points
        };
        let centre = bounds.center();
        // The front of a Z-up scene is its -Y side (+Z of a Y-up one turned up to +Z).
        let direction = if up == DVec3::Z {
            DVec3::new(0.4, -1.0, 0.3)
        } else {
            DVec3::new(0.4, 0.3, 1.0)
        };
        let mut camera = Camera::look_at(
            centre + direction,
            centre,
            up,
            Projection::Perspective { yfov },
        )
        .expect("framing directions are never parallel to the up axis");
        let axes = [
            camera.to_world.x_axis,
            camera.to_world.y_axis,
            camera.to_world.z_axis,
        ]
        .map(|a| a.truncate());
        let fill = 1.0 / 1.05;
        let ty = (yfov * 0.5).tan() * fill;
        let (eye, nearest) = fit_eye(points, centre, axes, [ty * aspect, ty]);
        let size = bounds.size().max_element().max(1e-9);
        let [right, up, back] = axes;
        // in front of every point by at least 1e-3 of the scene's size
        let depth = eye[2].max(nearest + 1e-3 * size);
        camera.to_world.w_axis = (centre + right * eye[0] + up * eye[1] + back * depth).extend(1.0);
        camera.name = "auto".into();
        camera.source = "auto (frames the whole scene)".into();
        camera.znear = depth - nearest;
        camera
    }

    /// A perspective camera framing all of `bounds`, looking at its centre from `direction`
    /// (not parallel to +Y), 0.8 rad vertical field of view.
    pub fn framing_from(bounds: &Aabb, direction: DVec3) -> Camera {
        let (centre, radius) = if bounds.is_empty() {
            (DVec3::ZERO, 1.0)
        } else {
            (bounds.center(), (bounds.size().length() * 0.5).max(1e-9))
        };
        let yfov = AUTO_YFOV;
        let distance = radius / (yfov * 0.5).sin() * 1.05;
        let eye = centre + direction.normalize() * distance;
        let mut camera = Camera::look_at(eye, centre, DVec3::Y, Projection::Perspective { yfov })
            .expect("framing directions are never parallel to +Y");
        camera.name = "auto".into();
        camera.source = "auto (frames the whole scene)".into();
        camera.znear = distance - radius;
        camera
    }

    /// Camera-to-world matrix with the rotation part orthonormalised (scale and shear of a
    /// node transform removed), keeping the position and the viewing direction.
    pub fn orthonormalised(to_world: DMat4) -> Option<DMat4> {
        let back = to_world.z_axis.truncate().try_normalize()?;
        let right = to_world.y_axis.truncate().cross(back).try_normalize()?;
        let up = back.cross(right);
        Some(DMat4::from_cols(
            right.extend(0.0),
            up.extend(0.0),
            back.extend(0.0),
            to_world.w_axis,
        ))
    }

    /// Eye position in the world.
    pub fn eye(&self) -> DVec3 {
        self.to_world.w_axis.truncate()
    }

    /// Unit viewing direction (the camera's -Z axis in the world; normalised for a pinhole
    /// camera, whose matrix may scale).
    pub fn forward(&self) -> DVec3 {
        match self.projection {
            Projection::Pinhole(_) => -self.to_world.z_axis.truncate().normalize_or_zero(),
            _ => -self.to_world.z_axis.truncate(),
        }
    }

    /// The ray through the centre of pixel (`column`, `row`) of a `width`×`height` image;
    /// row 0 is the top.
    pub fn pixel_ray(&self, column: usize, row: usize, width: usize, height: usize) -> Ray {
        self.screen_ray(column, row, width, height, self.half_height())
    }

    /// Half the view height at unit distance (`tan(yfov / 2)`) for a perspective camera, or in
    /// scene units (`ymag`) for an orthographic one: the constant of [`Camera::screen_ray`]
    /// (1, unused, for a pinhole camera).
    pub fn half_height(&self) -> f64 {
        match self.projection {
            Projection::Perspective { yfov } => (yfov * 0.5).tan(),
            Projection::Orthographic { ymag } => ymag,
            Projection::Pinhole(_) => 1.0,
        }
    }

    /// [`Camera::pixel_ray`] with [`Camera::half_height`] computed once by the caller.
    pub fn screen_ray(
        &self,
        column: usize,
        row: usize,
        width: usize,
        height: usize,
        half_height: f64,
    ) -> Ray {
        let (x, y) = (column as f64 + 0.5, row as f64 + 0.5);
        self.image_ray(x, y, width, height, half_height)
    }

    /// The ray through image point (`x`, `y`) of a `width`×`height` image, in pixels from the
    /// top left corner (pixel (u, v) spans [u, u + 1] × [v, v + 1]; its centre is
    /// [`Camera::screen_ray`]'s).
    pub fn image_ray(&self, x: f64, y: f64, width: usize, height: usize, half_height: f64) -> Ray {
        let aspect = width as f64 / height as f64;
        let sx = 2.0 * x / width as f64 - 1.0;
        let sy = 1.0 - 2.0 * y / height as f64;
        match self.projection {
            Projection::Perspective { .. } => {
                let dir = DVec4::new(sx * half_height * aspect, sy * half_height, -1.0, 0.0);
                Ray::new(self.eye(), (self.to_world * dir).truncate())
            }
            Projection::Orthographic { .. } => {
                let local = DVec4::new(sx * half_height * aspect, sy * half_height, 0.0, 1.0);
                Ray::new((self.to_world * local).truncate(), self.forward())
            }
            Projection::Pinhole(pinhole) => Ray::new(
                self.eye(),
                self.to_world.transform_vector3(pinhole.direction(x, y)),
            ),
        }
    }
}
