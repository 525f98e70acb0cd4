//! Axis-aligned bounding boxes in f64.

use glam::DVec3;

/// An axis-aligned box; `min > max` on some axis means empty.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: DVec3,
    /// Largest corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// A box from its two corners.
    pub fn new(min: DVec3, max: DVec3) -> Self {
        Aabb { min, max }
    }

    /// The smallest box holding all `points`.
    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Self {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grow(p))
    }

    /// This box grown to hold `p`.
    pub fn grow(self, p: DVec3) -> Self {
        Aabb::new(self.min.min(p), self.max.max(p))
    }

    /// The smallest box holding both.
    pub fn union(self, other: Aabb) -> Self {
        Aabb::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// The common part of both boxes, or `None` when they share no point.
    pub fn common(self, other: Aabb) -> Option<Aabb> {
        let both = Aabb::new(self.min.max(other.min), self.max.min(other.max));
        (!both.is_empty()).then_some(both)
    }

    /// True when `other` lies inside this box (faces may touch).
    pub fn holds(&self, other: &Aabb) -> bool {
        other.min.cmpge(self.min).all() && other.max.cmple(self.max).all()
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// True when both boxes share at least one point (closed boxes).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// Centre point.
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths.
    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    /// The box grown by `margin` on every side.
    pub fn expanded(&self, margin: f64) -> Self {
        Aabb::new(
            self.min - DVec3::splat(margin),
            self.max + DVec3::splat(margin),
        )
    }

    /// Does `origin + t·dir` meet the closed box for some `0 <= t <= t_max`? The f64 slab
    /// test; an axis with `dir = 0` (either sign) only asks whether the origin lies in the slab.
    pub fn ray_enters(&self, origin: DVec3, dir: DVec3, t_max: f64) -> bool {
        let (mut near, mut far) = (0.0f64, t_max);
        for axis in 0..3 {
            let (lo, hi) = (self.min[axis], self.max[axis]);
            let (o, d) = (origin[axis], dir[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let (a, b) = ((lo - o) / d, (hi - o) / d);
            near = near.max(a.min(b));
            far = far.min(a.max(b));
        }
        near <= far
    }

    /// The same box moved by `-offset`.
    pub fn translated(&self, offset: DVec3) -> Self {
        Aabb::new(self.min - offset, self.max - offset)
    }

    /// Octant `i` of the box: bit 0 of `i` selects the upper x half, bit 1 y, bit 2 z.
    pub fn octant(&self, i: usize) -> Aabb {
        let half = self.size() * 0.5;
        let offset = DVec3::new(
            if i & 1 != 0 { half.x } else { 0.0 },
            if i & 2 != 0 { half.y } else { 0.0 },
            if i & 4 != 0 { half.z } else { 0.0 },
        );
        let min = self.min + offset;
        Aabb::new(min, min + half)
    }

    /// The eight corners.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }
}
