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
