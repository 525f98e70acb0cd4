//! Which side of a closed quadric a point is on, for signed distances.
//!
//! Only an ellipsoid that its clip box does not cut (or without one) bounds a volume: every
//! other kind is unbounded and is drawn only inside its box, where it is an open surface (a
//! cylinder without caps, a bowl, a saddle) with no inside, and an ellipsoid cut by its box
//! has a hole. For a closed ellipsoid the inside is where `f` has the opposite sign to `Q`'s
//! eigenvalues (the sign `f` has at the centre); the sign of `f` at a point is certain when
//! `|f|` exceeds its rounding bound, which is exactly the point being off the surface to
//! rounding.

use super::{Quadric, QuadricKind};
use glam::{DMat3, DVec3};

/// The side of a point, `|f|` at most this many times its rounding bound counting as on.
const ON_SURFACE: f64 = 16.0;

impl Quadric {
    /// Whether the clipped surface bounds a volume: an ellipsoid inside its clip box (the
    /// box as the intersection test widens it), or without one.
    pub fn encloses(&self) -> bool {
        self.kind == QuadricKind::Ellipsoid
            && self.clip.is_none_or(|[min, max]| {
                let [lo, hi] = self.ellipsoid_box(DMat3::IDENTITY);
                let shift = self.local_anchor - self.anchor;
                (lo + shift).cmpge(min).all() && (hi + shift).cmple(max).all()
            })
    }

    /// For a quadric that [`Quadric::encloses`] a volume, whether the world point `point` is
    /// inside it: `Some(true)` inside, `Some(false)` outside, `None` on the surface to
    /// rounding (or not finite). Meaningless for other quadrics.
    pub fn inside(&self, point: DVec3) -> Option<bool> {
        let u = point - self.anchor;
        let value = self.world.value(u);
        let rounding = ON_SURFACE * self.world.value_rounding(u);
        if value.is_nan() || rounding.is_nan() || value.abs() <= rounding {
            return None;
        }
        let q = self.world.q;
        let trace = q.x_axis.x + q.y_axis.y + q.z_axis.z;
        Some((value < 0.0) == (trace > 0.0))
    }
}
