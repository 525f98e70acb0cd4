//! Rays in world space.

use glam::DVec3;

/// A ray `origin + t * dir`, both in world coordinates (f64). `dir` need not be unit length;
/// distances along the ray are `t * |dir|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: DVec3,
    /// Direction; need not be normalised.
    pub dir: DVec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Ray { origin, dir }
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + self.dir * t
    }

    /// True when the ray can be traced: finite origin and a finite, non-zero direction.
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite() && self.dir.is_finite() && self.dir != DVec3::ZERO
    }
}

/// Something that yields rays by index: a camera image or a list of rays.
pub trait RaySource: Sync {
    /// Number of rays.
    fn len(&self) -> usize;
    /// True when there are no rays.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Ray number `index`.
    fn ray(&self, index: usize) -> Ray;
    /// Eye and unit view direction, for the `z` AOV (cameras only).
    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        None
    }
    /// Rays per image row, for a source whose rays are an image's pixels in row-major order:
    /// the trace then groups them in small tiles, which neighbouring rays share more of the
    /// octree than rows do. `None` (the default) keeps the source's order.
    fn row_width(&self) -> Option<usize> {
        None
    }
}

impl RaySource for Vec<Ray> {
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn ray(&self, index: usize) -> Ray {
        self[index]
    }
}
