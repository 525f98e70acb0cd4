//! `Camera` prims (UsdGeomCamera) as cameras named by their prim path: perspective from the
//! focal length and vertical aperture, orthographic from the aperture (tenths of a scene
//! unit), the clipping range, and a warning for what is skipped or ignored.

use super::value;
use super::warning_at;
use super::Loader;
use crate::camera::{Camera, Projection};
use crate::error::Result;
use glam::DMat4;
use openusd::usd::Prim;

impl Loader {
    /// A UsdGeomCamera as a camera named by its prim path.
    pub(super) fn camera(&mut self, prim: &Prim, name: &str, world: DMat4) -> Result<()> {
        let Some(to_world) = Camera::orthonormalised(world) else {
            self.warnings.push(warning_at(
                prim.path().to_string(),
                "camera has a degenerate transform: skipped",
            ));
            return Ok(());
        };
        let focal = value::scalar(prim, "focalLength", self.at)?.unwrap_or(50.0);
        let horizontal = value::scalar(prim, "horizontalAperture", self.at)?.unwrap_or(20.955);
        let vertical = value::scalar(prim, "verticalAperture", self.at)?.unwrap_or(15.2908);
        let [near, far] = value::vec2(prim, "clippingRange", self.at)?.unwrap_or([1.0, 1e6]);
        let projection =
            value::token(prim, "projection", self.at)?.unwrap_or_else(|| "perspective".into());
        let positive = |x: f64| x.is_finite() && x > 0.0;
        if !positive(horizontal) || !positive(vertical) {
            self.warnings.push(warning_at(
                prim.path().to_string(),
                "camera apertures must be positive: skipped",
            ));
            return Ok(());
        }
        let projection = match projection.as_str() {
            "orthographic" => Projection::Orthographic {
                // Apertures are in tenths of a scene unit.
                ymag: vertical * 0.1 / 2.0,
            },
            _ => {
                if !positive(focal) {
                    self.warnings.push(warning_at(
                        prim.path().to_string(),
                        "camera focalLength must be positive: skipped",
                    ));
                    return Ok(());
                }
                Projection::Perspective {
                    yfov: 2.0 * (vertical / (2.0 * focal)).atan(),
                }
            }
        };
        for offset in ["horizontalApertureOffset", "verticalApertureOffset"] {
            if value::scalar(prim, offset, self.at)?.is_some_and(|x| x != 0.0) {
                self.warnings.push(warning_at(
                    prim.path().to_string(),
                    format!("camera {offset} is not supported (ignored)"),
                ));
            }
        }
        self.builder.add_camera(Camera {
            name: name.to_string(),
            source: format!("usd camera {}", prim.path()),
            projection,
            aspect_ratio: Some(horizontal / vertical),
            znear: near,
            zfar: Some(far).filter(|f| f.is_finite()),
            to_world,
        });
        Ok(())
    }
}
