//! Conservative range of a quadratic function over a box (interval arithmetic).

use glam::{DMat3, DVec3};

/// Relative widening of the computed range that covers every rounding error in it.
const ROUNDING_MARGIN: f64 = 1e-9;

/// A closed interval `[lo, hi]`.
#[derive(Clone, Copy)]
struct Interval {
    lo: f64,
    hi: f64,
}

impl Interval {
    /// The product of two intervals.
    fn mul(self, other: Interval) -> Interval {
        let products = [
            self.lo * other.lo,
            self.lo * other.hi,
            self.hi * other.lo,
            self.hi * other.hi,
        ];
        Interval {
            lo: products.into_iter().fold(f64::INFINITY, f64::min),
            hi: products.into_iter().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// The square of an interval (never negative, unlike `self.mul(self)`).
    fn square(self) -> Interval {
        let (a, b) = (self.lo * self.lo, self.hi * self.hi);
        if self.lo <= 0.0 && self.hi >= 0.0 {
            Interval {
                lo: 0.0,
                hi: a.max(b),
            }
        } else {
            Interval {
                lo: a.min(b),
                hi: a.max(b),
            }
        }
    }

    /// The interval scaled by the number `c`.
    fn scale(self, c: f64) -> Interval {
        let (a, b) = (self.lo * c, self.hi * c);
        Interval {
            lo: a.min(b),
            hi: a.max(b),
        }
    }

    /// The largest magnitude in the interval.
    fn magnitude(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }
}

/// Whether `u·Q·u + P·u + R` may be zero for some `u` in the box `[lo, hi]`; false only when
/// the padded interval enclosure of its values excludes zero.
pub(super) fn value_range_may_contain_zero(
    q: DMat3,
    p: DVec3,
    r: f64,
    lo: DVec3,
    hi: DVec3,
) -> bool {
    let x = [0, 1, 2].map(|i| Interval {
        lo: lo[i],
        hi: hi[i],
    });
    let entry = |i: usize, j: usize| q.col(j)[i];
    let terms = [
        Interval { lo: r, hi: r },
        x[0].square().scale(entry(0, 0)),
        x[1].square().scale(entry(1, 1)),
        x[2].square().scale(entry(2, 2)),
        x[0].mul(x[1]).scale(2.0 * entry(0, 1)),
        x[0].mul(x[2]).scale(2.0 * entry(0, 2)),
        x[1].mul(x[2]).scale(2.0 * entry(1, 2)),
        x[0].scale(p.x),
        x[1].scale(p.y),
        x[2].scale(p.z),
    ];
    let margin = ROUNDING_MARGIN * terms.iter().map(|t| t.magnitude()).sum::<f64>();
    let low: f64 = terms.iter().map(|t| t.lo).sum();
    let high: f64 = terms.iter().map(|t| t.hi).sum();
    low - margin <= 0.0 && high + margin >= 0.0
}
