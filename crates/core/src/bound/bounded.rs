//! [`Bounded`]: an f64 value computed in floating point, with a bound on its distance from the
//! exact real value it stands for (running forward error analysis).
//!
//! With `|a − x| ≤ eₐ` and `|b − y| ≤ e_b`:
//!
//! - `a ± b`: `|fl(a ± b) − (x ± y)| ≤ eₐ + e_b + ρ`;
//! - `a · b`: `|ab − xy| ≤ |a|e_b + |b|eₐ + eₐe_b`, plus `ρ`;
//! - `a / b` (`e_b < |b|`): `|a/b − x/y| = |ay − xb| / |by| ≤ (|a|e_b + |b|eₐ) / (|b|(|b| − e_b))`,
//!   plus `ρ`;
//! - `√a` (`a − eₐ > 0`): `|√a − √x| = |a − x| / (√a + √x) ≤ eₐ / (√a + √(a − eₐ))`, plus
//!   `γ₁ fl(√a)`.
//!
//! `ρ` is the operation's own rounding error, computed exactly rather than bounded by the
//! standard model's `γ₁|fl(z)|` (Higham's `γₙ = nu / (1 − nu)`, `u = 2⁻⁵³`): Knuth's two-sum for
//! a sum, a fused multiply-add `a·b − fl(a·b)` for a product, and for a quotient `q` the remainder
//! `a − q·b` (exact to one rounding) over `|b|`. An operation that happens to be exact (adding
//! zero, a product of short mantissas) then adds nothing, which keeps the bound within a
//! small factor of the actual error. A product's rounding error below the subnormal range is
//! itself rounded (by at most `2⁻¹⁰⁷⁵`); each product's bound gets `2⁻¹⁰⁷²` more, and a
//! product that overflows falls back to `γ₁|fl(ab)|`.
//!
//! The bounds themselves are sums and products of non-negative numbers evaluated in f64: a few
//! roundings, each at most a relative `u` (or `2⁻¹⁰⁷⁵` in the subnormal range). [`up`]
//! multiplies each by `1 + 2⁻⁴⁹` and adds `2⁻¹⁰⁷⁴`: the product, rounded to nearest, is at
//! least `x(1 + 2⁻⁴⁹)(1 − u) > x(1 + 2⁻⁵⁰)`, more than `x(1 + u)⁷`, and where it is subnormal
//! the added step covers its rounding, so a computed bound is never below its exact value;
//! [`down`] does the opposite for the divisors. A bound that cannot be made (a divisor that
//! may be zero) is `+∞`, never NaN.

use glam::DVec3;

/// The unit roundoff of f64, `2⁻⁵³`.
pub const UNIT: f64 = f64::EPSILON / 2.0;

/// Higham's `γₙ = nu / (1 − nu)`, rounded up.
pub fn gamma(n: u32) -> f64 {
    let nu = f64::from(n) * UNIT;
    up(nu / (1.0 - nu))
}

/// Relative slack that covers the roundings of a bound's own evaluation (up to seven, less
/// than `2⁻⁵⁰`) and the rounding of the product that applies it (`u` more).
const SLACK: f64 = 1.0 / (1u64 << 49) as f64;

/// The smallest positive f64, `2⁻¹⁰⁷⁴`: one step of the subnormal range.
const TINY: f64 = f64::from_bits(1);

/// `x ≥ 0` rounded up past the roundings of its own evaluation (see the module docs): a
/// multiply and an add, no branch.
#[inline(always)]
pub fn up(x: f64) -> f64 {
    x * (1.0 + SLACK) + TINY
}

/// `x ≥ 0` rounded down past the roundings of its own evaluation; `0` for a negative or NaN
/// `x`, `f64::MAX` for `+∞` (a finite value that overflowed is at least that).
#[inline(always)]
#[allow(clippy::manual_clamp)] // `clamp` keeps a NaN, which must become 0 here.
pub fn down(x: f64) -> f64 {
    (x * (1.0 - SLACK) - TINY).max(0.0).min(f64::MAX)
}

/// Extra absolute bound per product, for the underflow of its rounding error.
const UNDERFLOW: f64 = 4.0 * f64::MIN_POSITIVE * f64::EPSILON;

/// The exact rounding error `a·b − fl(a·b)`, or `None` when it cannot be had: the product
/// overflowed (`p` infinite), or an operand is not finite. A fused multiply-add gives it in
/// one correctly rounded operation (IEEE 754's `fusedMultiplyAdd`: the same bits on every CPU,
/// whether the instruction or libm computes it); it is exact unless the error is below the
/// subnormal range, which the callers' `2⁻¹⁰⁷²` per product covers.
#[inline(always)]
fn product_error(a: f64, b: f64, p: f64) -> Option<f64> {
    let error = a.mul_add(b, -p);
    error.is_finite().then_some(error)
}

/// The exact rounding error `a + b − fl(a + b)` (Knuth's two-sum).
#[inline(always)]
pub fn sum_error(a: f64, b: f64, s: f64) -> f64 {
    let bb = s - a;
    (a - (s - bb)) + (b - bb)
}

/// A computed value and a bound on its distance from the exact value: `|value − exact| ≤
/// error`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounded {
    /// The value as computed in f64.
    pub value: f64,
    /// A bound on `|value − exact|` (`+∞` when none could be made).
    pub error: f64,
}

impl Bounded {
    /// A number taken as exact.
    #[inline]
    pub const fn exact(value: f64) -> Bounded {
        Bounded { value, error: 0.0 }
    }

    /// A value with a known bound.
    #[inline]
    pub const fn new(value: f64, error: f64) -> Bounded {
        Bounded { value, error }
    }

    /// The largest magnitude the exact value may have.
    #[inline]
    pub fn magnitude(self) -> f64 {
        up(self.value.abs() + self.error)
    }

    /// Whether the exact value's sign is that of `value` and not zero.
    #[inline]
    pub fn sign_certain(self) -> bool {
        self.value.abs() > self.error
    }

    /// `√self` for a value that is not negative.
    #[inline]
    pub fn sqrt(self) -> Bounded {
        let value = self.value.max(0.0).sqrt();
        let low = down(self.value - self.error);
        let error = if low > 0.0 {
            up(self.error / down(value + down(low.sqrt())))
        } else {
            up((self.value.max(0.0) + self.error).sqrt())
        };
        Bounded::new(value, up(error + gamma(1) * value))
    }
}

impl std::ops::Add for Bounded {
    type Output = Bounded;

    /// `self + other`.
    #[inline(always)]
    fn add(self, other: Bounded) -> Bounded {
        let value = self.value + other.value;
        let rounding = sum_error(self.value, other.value, value).abs();
        let rounding = if rounding.is_finite() {
            rounding
        } else {
            gamma(1) * value.abs()
        };
        Bounded::new(value, up(self.error + other.error + rounding))
    }
}

impl std::ops::Sub for Bounded {
    type Output = Bounded;

    /// `self − other`.
    #[inline(always)]
    fn sub(self, other: Bounded) -> Bounded {
        self + -other
    }
}

impl std::ops::Mul for Bounded {
    type Output = Bounded;

    /// `self · other`.
    #[inline(always)]
    fn mul(self, other: Bounded) -> Bounded {
        let value = self.value * other.value;
        let spread = self.value.abs() * other.error
            + other.value.abs() * self.error
            + self.error * other.error;
        let rounding = product_error(self.value, other.value, value)
            .map_or(gamma(1) * value.abs(), |e| e.abs() + UNDERFLOW);
        Bounded::new(value, up(spread + rounding))
    }
}

impl std::ops::Div for Bounded {
    type Output = Bounded;

    /// `self / other`; an infinite bound when `other` may be zero.
    #[inline(always)]
    fn div(self, other: Bounded) -> Bounded {
        let value = self.value / other.value;
        let b = other.value.abs();
        let margin = down(down(b) - up(other.error));
        if margin.is_nan() || margin <= 0.0 || !value.is_finite() {
            return Bounded::new(value, f64::INFINITY);
        }
        let spread = up(self.value.abs() * other.error + b * self.error) / down(b * margin);
        // a − q·b: the high part cancels exactly (Sterbenz), the low part rounds once.
        let remainder = product_error(value, other.value, value * other.value)
            .map(|low| up(((self.value - value * other.value) - low).abs()) / down(b));
        let rounding = remainder.map_or(gamma(1) * value.abs(), |r| r + UNDERFLOW);
        Bounded::new(value, up(spread + rounding))
    }
}

impl std::ops::Neg for Bounded {
    type Output = Bounded;

    /// `−self` (exact).
    #[inline]
    fn neg(self) -> Bounded {
        Bounded::new(-self.value, self.error)
    }
}

/// A vector of [`Bounded`] components.
pub type BVec3 = [Bounded; 3];

/// The vector `v` taken as exact.
#[inline(always)]
pub fn exact3(v: DVec3) -> BVec3 {
    within3(v, 0.0)
}

/// The vector `v` with the same bound `error` on every component. (Arrays written out here
/// and below: the compiler leaves an array's `map` of [`Bounded`]s as calls.)
#[inline(always)]
pub fn within3(v: DVec3, error: f64) -> BVec3 {
    [
        Bounded::new(v.x, error),
        Bounded::new(v.y, error),
        Bounded::new(v.z, error),
    ]
}

/// The components of `v`, each within its own bound in `errors` (the inverse of [`values3`]
/// and [`errors3`]).
#[inline(always)]
pub fn bounded3(v: DVec3, errors: DVec3) -> BVec3 {
    [
        Bounded::new(v.x, errors.x),
        Bounded::new(v.y, errors.y),
        Bounded::new(v.z, errors.z),
    ]
}

/// The bounds of a bounded vector's components.
pub fn errors3(v: &BVec3) -> DVec3 {
    DVec3::new(v[0].error, v[1].error, v[2].error)
}

/// The values of a bounded vector.
pub fn values3(v: &BVec3) -> DVec3 {
    DVec3::new(v[0].value, v[1].value, v[2].value)
}

/// `a · b` summed left to right, `(a₀b₀ + a₁b₁) + a₂b₂` (glam's order).
#[inline(always)]
pub fn dot3(a: &BVec3, b: &BVec3) -> Bounded {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A 3×3 matrix of bounded entries, `rows[i][j]`.
pub type BMat3 = [[Bounded; 3]; 3];

/// The rows of `m`, each entry within `error`.
#[inline(always)]
pub fn rows3(m: glam::DMat3, error: f64) -> BMat3 {
    let r = m.transpose();
    [
        within3(r.x_axis, error),
        within3(r.y_axis, error),
        within3(r.z_axis, error),
    ]
}

/// `m · v` in glam's order: per row `(m₀v₀ + m₁v₁) + m₂v₂`.
#[inline(always)]
pub fn mat_vec(m: &BMat3, v: &BVec3) -> BVec3 {
    [dot3(&m[0], v), dot3(&m[1], v), dot3(&m[2], v)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ops::{Add, Div};

    /// Each operation's bound covers its exact result (computed with exact rationals: the
    /// values are small dyadic fractions plus or minus their bounds).
    #[test]
    fn operations_cover_the_exact_results() {
        // 0.1 is stored as 0.1000000000000000055511151231257827; exact 1/10 is within 6e-18.
        let tenth = Bounded::new(0.1, 6e-18);
        let third = Bounded::exact(1.0).div(Bounded::exact(3.0));
        // fl(1/3) = 0.333...3148 is within 1.9e-17 of 1/3.
        assert!(third.error >= 1.85e-17 && third.error < 1e-16, "{third:?}");
        let sum = tenth.add(tenth).add(tenth);
        // 0.3000000000000000444089209850062616… is 4.44089209850062616e-17 above 3/10.
        assert_eq!(sum.value, 0.30000000000000004);
        assert!(4.440892098500627e-17 <= sum.error, "{sum:?}");
        assert!(sum.error < 2e-16);
        let root = Bounded::exact(2.0).sqrt();
        // √2 = 1.41421356237309504880..., fl(√2) = 1.4142135623730951454...
        assert!(root.error >= 9.7e-17 && root.error < 1e-15, "{root:?}");
    }

    #[test]
    fn a_divisor_that_may_vanish_gives_an_infinite_bound() {
        let tiny = Bounded::new(1e-20, 1e-20);
        let q = Bounded::exact(1.0).div(tiny);
        assert_eq!(q.error, f64::INFINITY);
        assert!(!tiny.sign_certain());
        assert!(q.error.is_infinite() && !q.error.is_nan());
    }

    /// `up` clears `x(1 + 2⁻⁵⁰)` and `down` stays below `x(1 − 2⁻⁵⁰)` (differences of nearby
    /// floats are exact, so the comparisons are), across the normal and subnormal ranges; the
    /// ends map as documented.
    #[test]
    fn up_and_down_clear_their_slack() {
        let mut rng = crate::test_rng::Rng(0x0b0_0e5);
        let eighth_u = 1.0 / (1u64 << 50) as f64;
        for _ in 0..100_000 {
            let x = f64::from_bits(rng.next() % f64::MAX.to_bits());
            let (hi, lo) = (up(x), down(x));
            assert!(hi - x >= x * eighth_u && hi > x, "up({x:e}) = {hi:e}");
            assert!(
                x - lo >= x * eighth_u && lo < x && lo >= 0.0,
                "down({x:e}) = {lo:e}"
            );
        }
        assert_eq!((up(0.0), down(0.0)), (f64::from_bits(1), 0.0));
        assert_eq!(
            (up(f64::INFINITY), down(f64::INFINITY)),
            (f64::INFINITY, f64::MAX)
        );
        assert!(up(f64::NAN).is_nan() && down(f64::NAN) == 0.0);
        assert_eq!(down(-1.0), 0.0);
    }

    #[test]
    fn gamma_is_higham_s() {
        assert!(gamma(1) > UNIT && gamma(1) < 1.0000001 * UNIT);
        assert!(gamma(3) > 3.0 * UNIT);
        assert!(up(1.0) > 1.0 && down(1.0) < 1.0);
    }
}
