//! [`BoundedMat4`]: a node transform composed in f64, with a bound on each entry's distance
//! from the exact product of the file's matrices.
//!
//! # Derivation
//! A nested node's world matrix is `M = P · L`, `P` its parent's world matrix and `L` its own
//! matrix as read. Each entry of the f64 product is a sum of four products, which glam
//! evaluates as `((p₀l₀ + p₁l₁) + p₂l₂) + p₃l₃`; evaluating the same sum in [`Bounded`]
//! arithmetic, with the parent's entries within their bounds `E_P` (`|P̂ − P*| ≤ E_P`, zero for a
//! root) and `L` exact, gives the same value and a bound on its distance from the exact
//! `(P*L)ᵢⱼ`: each product's and sum's actual rounding (two-product, two-sum) plus the
//! parent's bound carried through `|L|`. Never more than Higham's `γ₄|P̂||L| + E_P|L|`, and
//! usually far less (a product of short mantissas, an affine matrix's last row, are exact). A
//! node's own `matrix` is taken as the numbers the file gives; a translation, rotation and
//! scale stand for `T · R(q/|q|) · S` with the quaternion normalized exactly, and the f64
//! normalization and multiplying out ([`BoundedMat4::trs`]) are bounded the same way, the
//! local bound then carried through the parent's product ([`BoundedMat4::then_bounded`]:
//! `|P̂||E_L| + E_P|L̂| + E_P E_L` beside the roundings).
//!
//! # Where it enters the bounds
//! - A mesh drawn once is placed by `M̂`: each placed coordinate moves by at most
//!   `(E_A|v| + E_T)ᵢ` more (`E_A` the linear part's bound, `E_T` the translation's), added to
//!   its placement bound ([`crate::bound::placement_error`]).
//! - An instance or a quadric is intersected in its frame through `M̂⁻¹`: the exact frame's ray
//!   differs by the residual's extra term `E_A|x|` and through `‖A*⁻¹‖∞ ≤ ‖Â⁻¹‖∞ / (1 −
//!   ‖Â⁻¹‖∞‖E_A‖∞)` ([`crate::bound::mapped`], [`perturbed_inverse_norm`]); the anchor or
//!   translation moves by `E_A|a| + E_T`.

use super::bounded::{down, up, Bounded};
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use std::ops::{Add, Div, Mul, Sub};

/// An f64 affine matrix and a bound on each entry's distance from the exact one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedMat4 {
    /// The matrix as computed (what the importer places with).
    pub value: DMat4,
    /// Entrywise bounds `|value − exact|` (zero: exact).
    pub error: DMat4,
}

impl BoundedMat4 {
    /// A matrix taken as exact.
    pub const fn exact(value: DMat4) -> BoundedMat4 {
        BoundedMat4 {
            value,
            error: DMat4::ZERO,
        }
    }

    /// A matrix whose distance from the exact one is not bounded (`+∞` everywhere).
    pub fn unbounded(value: DMat4) -> BoundedMat4 {
        BoundedMat4 {
            value,
            error: DMat4::from_cols_array(&[f64::INFINITY; 16]),
        }
    }

    /// `self · local` as glam computes it (the importer's product, bit for bit), with the bound
    /// of the module docs: each entry's sum of four products evaluated in [`Bounded`]
    /// arithmetic in glam's order (`((p₀l₀ + p₁l₁) + p₂l₂) + p₃l₃`), the parent's entries
    /// within their bounds and the local matrix exact, so the bound holds the actual roundings
    /// rather than `γ₄`'s worst case. A root's exact identity parent adds no error.
    pub fn then(&self, local: &DMat4) -> BoundedMat4 {
        self.then_bounded(&BoundedMat4::exact(*local))
    }

    /// [`BoundedMat4::then`] for a local matrix that is itself within a bound of the exact one
    /// (a node's translation, rotation and scale multiplied out: [`BoundedMat4::trs`]).
    pub fn then_bounded(&self, local: &BoundedMat4) -> BoundedMat4 {
        let value = self.value * local.value;
        if self.value == DMat4::IDENTITY && self.is_exact() {
            return BoundedMat4 {
                value,
                error: local.error,
            };
        }
        let (p, e) = (
            self.value.transpose().to_cols_array_2d(),
            self.error.transpose().to_cols_array_2d(),
        );
        let (l, f) = (
            local.value.to_cols_array_2d(),
            local.error.to_cols_array_2d(),
        );
        let mut error = [[0.0; 4]; 4];
        for (j, (column, column_error)) in l.iter().zip(&f).enumerate() {
            for i in 0..4 {
                let term = |k: usize| {
                    Bounded::new(p[i][k], e[i][k]).mul(Bounded::new(column[k], column_error[k]))
                };
                let entry = term(0).add(term(1)).add(term(2)).add(term(3));
                error[j][i] = entry.error;
            }
        }
        // Two affine matrices: the last row (0, 0, 0, 1) is computed exactly (the products'
        // underflow allowance is not needed there).
        let exact_row =
            |m: &BoundedMat4| m.value.row(3) == DVec4::W && m.error.row(3) == DVec4::ZERO;
        if exact_row(self) && exact_row(local) {
            for column in &mut error {
                column[3] = 0.0;
            }
        }
        BoundedMat4 {
            value,
            error: DMat4::from_cols_array_2d(&error),
        }
    }

    /// The matrix `T · R · S` of a translation, a rotation given by the quaternion `rotation`
    /// as read (normalized here, as the importer does) and a scale, as glam computes it
    /// (`DQuat::normalize`, then `DMat4::from_scale_rotation_translation`: the same value, bit
    /// for bit), with a bound on each entry's distance from the exact matrix of the exact unit
    /// quaternion `rotation / |rotation|`: the same operations in [`Bounded`] arithmetic. The
    /// translation and the last row are exact.
    pub fn trs(translation: DVec3, rotation: DQuat, scale: DVec3) -> BoundedMat4 {
        if rotation == DQuat::IDENTITY {
            // Every operation is exact: products with 0 and 1, and 1 − 0 (the bounded products
            // would add their underflow allowance).
            let value = DMat4::from_scale_rotation_translation(scale, rotation, translation);
            return BoundedMat4::exact(value);
        }
        BoundedMat4::trs_bounded(translation, rotation.to_array().map(Bounded::exact), scale)
    }

    /// [`BoundedMat4::trs`] for a quaternion `(x, y, z, w)` whose components are themselves
    /// within bounds of the exact ones (a rotation computed from an axis and an angle): the
    /// exact matrix is that of the exact quaternion, normalized exactly.
    pub fn trs_bounded(translation: DVec3, q: [Bounded; 4], scale: DVec3) -> BoundedMat4 {
        // `DVec4::normalize`: the product with the reciprocal of the length.
        let length = q[0]
            .mul(q[0])
            .add(q[1].mul(q[1]))
            .add(q[2].mul(q[2]))
            .add(q[3].mul(q[3]));
        let recip = Bounded::exact(1.0).div(length.sqrt());
        BoundedMat4::trs_as_given(translation, q.map(|c| c.mul(recip)), scale)
    }

    /// `T · R · S` with the rotation formula applied to the quaternion `(x, y, z, w)` as given,
    /// not normalized (glam's `from_scale_rotation_translation`, and USD's point instancers,
    /// apply it so), each component within its bound of the exact one.
    pub fn trs_as_given(translation: DVec3, q: [Bounded; 4], scale: DVec3) -> BoundedMat4 {
        let [x, y, z, w] = q;
        // `DMat4::quat_to_axes`.
        let (x2, y2, z2) = (x.add(x), y.add(y), z.add(z));
        let (xx, xy, xz) = (x.mul(x2), x.mul(y2), x.mul(z2));
        let (yy, yz, zz) = (y.mul(y2), y.mul(z2), z.mul(z2));
        let (wx, wy, wz) = (w.mul(x2), w.mul(y2), w.mul(z2));
        let one = Bounded::exact(1.0);
        let axes = [
            [one.sub(yy.add(zz)), xy.add(wz), xz.sub(wy)],
            [xy.sub(wz), one.sub(xx.add(zz)), yz.add(wx)],
            [xz.add(wy), yz.sub(wx), one.sub(xx.add(yy))],
        ];
        let mut value = [[0.0; 4]; 4];
        let mut error = [[0.0; 4]; 4];
        for (j, axis) in axes.iter().enumerate() {
            for (i, entry) in axis.iter().enumerate() {
                let scaled = entry.mul(Bounded::exact(scale[j]));
                (value[j][i], error[j][i]) = (scaled.value, scaled.error);
            }
        }
        value[3] = translation.extend(1.0).to_array();
        BoundedMat4 {
            value: DMat4::from_cols_array_2d(&value),
            error: DMat4::from_cols_array_2d(&error),
        }
    }

    /// Whether the bound is zero.
    pub fn is_exact(&self) -> bool {
        self.error == DMat4::ZERO
    }
}

/// A bound on `‖A*⁻¹‖∞` for every `A*` within `error` (entrywise) of a matrix whose inverse
/// norm is at most `norm`: `norm / (1 − norm·‖error‖∞)`, `+∞` when that is not positive.
pub fn perturbed_inverse_norm(norm: f64, error: &DMat3) -> f64 {
    if *error == DMat3::ZERO {
        return norm;
    }
    let size = row_norm(error);
    let margin = down(1.0 - up(norm * size));
    if margin.is_nan() || margin <= 0.0 {
        return f64::INFINITY;
    }
    up(norm / margin)
}

/// `‖m‖∞` (the largest row sum of magnitudes), rounded up.
pub fn row_norm(m: &DMat3) -> f64 {
    let rows = m.abs().transpose();
    [rows.x_axis, rows.y_axis, rows.z_axis]
        .map(|r| up(r.element_sum()))
        .into_iter()
        .fold(0.0, f64::max)
}

/// The largest component of `E_A|x| + E_T` for the entrywise bound `error` of an affine
/// matrix: what the exactly composed matrix may move the image of `x` by, rounded up.
pub fn moved(error: &DMat4, x: DVec3) -> f64 {
    let (linear, translation) = (DMat3::from_mat4(*error), error.w_axis.truncate());
    up((linear * x.abs() + translation).max_element())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound covers the rounding of the product: the actual error of one entry, computed
    /// with Python's `fractions` from the two f64 factors, is 4.6259e-19 (`γ₄` of the product
    /// would be 1.48e-17); the bound is that rounding, rounded up.
    #[test]
    fn the_bound_covers_the_rounding_of_the_product() {
        let third = 1.0 / 3.0;
        let parent = BoundedMat4::exact(DMat4::from_scale(DVec3::splat(third)));
        let local = DMat4::from_translation(DVec3::new(0.1, 0.2, 0.3));
        let child = parent.then(&local);
        assert_eq!(child.value.w_axis.x, third * 0.1);
        // |fl(third · 0.1) − third · 0.1| = 300239975158033 / 2^109 (Fraction).
        assert!(
            child.error.w_axis.x >= 4.6259292692714e-19,
            "{:?}",
            child.error
        );
        assert!(child.error.w_axis.x < 4.7e-19, "{:?}", child.error);
        // The last row (0, 0, 0, 1) of two affine matrices is exact.
        assert_eq!(child.error.row(3), glam::DVec4::ZERO);
        // A deeper level carries the parent's bound through |L|.
        let grand = child.then(&DMat4::from_scale(DVec3::splat(2.0)));
        assert!(grand.error.x_axis.x >= 2.0 * child.error.x_axis.x);
        assert!(BoundedMat4::exact(DMat4::IDENTITY).then(&local).is_exact());
    }

    /// The bounded TRS matrix is glam's (after the importer's normalization), bit for bit,
    /// for random translations, rotations (not unit, as files give them) and scales.
    #[test]
    fn trs_is_glams_matrix() {
        let mut rng = crate::test_rng::Rng(7);
        for _ in 0..2000 {
            let t = rng.point(-1e4, 1e4);
            let s = rng.point(-3.0, 3.0);
            let (xyz, w) = (rng.point(-1.0, 1.0), rng.uniform(-1.0, 1.0));
            let q = DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, w);
            let bounded = BoundedMat4::trs(t, q, s);
            let glam = DMat4::from_scale_rotation_translation(s, q.normalize(), t);
            assert_eq!(bounded.value.to_cols_array(), glam.to_cols_array());
            assert!(bounded.error.is_finite() && bounded.error.row(3) == DVec4::ZERO);
            assert!(
                bounded.error.w_axis == DVec4::ZERO,
                "the translation is exact"
            );
        }
    }

    /// The rotation formula on a quaternion as given (USD's point instancers) is glam's, bit
    /// for bit, without normalizing; its bound covers the distance to the same formula in
    /// exact arithmetic (the entries recomputed with Dekker's exact products: a different
    /// method from the fused multiply-adds of the bounded type).
    #[test]
    fn trs_as_given_is_glams_matrix_and_bounds_the_formula() {
        let exact_product = |a: f64, b: f64| {
            let split = |x: f64| {
                let c = 134_217_729.0 * x;
                let hi = c - (c - x);
                (hi, x - hi)
            };
            let ((ah, al), (bh, bl)) = (split(a), split(b));
            let p = a * b;
            (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
        };
        let mut rng = crate::test_rng::Rng(11);
        for _ in 0..500 {
            let (xyz, w) = (rng.point(-1.0, 1.0), rng.uniform(-1.0, 1.0));
            let q = DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, w);
            let bounded = BoundedMat4::trs_as_given(
                DVec3::ZERO,
                q.to_array().map(Bounded::exact),
                DVec3::ONE,
            );
            let glam = DMat4::from_scale_rotation_translation(DVec3::ONE, q, DVec3::ZERO);
            assert_eq!(bounded.value.to_cols_array(), glam.to_cols_array());
            // Entry (0, 0), 1 − 2(y² + z²), as a double-double: the products' exact parts
            // summed by two-sums, within about 50u² of the exact value.
            let ((yy, yy_low), (zz, zz_low)) = (exact_product(q.y, q.y), exact_product(q.z, q.z));
            let (mut hi, mut lo) = (1.0f64, 0.0f64);
            for term in [-2.0 * yy, -2.0 * zz, -2.0 * yy_low, -2.0 * zz_low] {
                let sum = hi + term;
                let back = sum - hi;
                lo += (hi - (sum - back)) + (term - back);
                hi = sum;
            }
            let distance = ((bounded.value.x_axis.x - hi) - lo).abs();
            let slack = 64.0 * f64::EPSILON * f64::EPSILON;
            assert!(distance <= bounded.error.x_axis.x * (1.0 + 1e-15) + slack);
        }
    }

    /// The quarter turn about z, `(0, 0, sin 45°, cos 45°)` in f64, is not exactly unit: its
    /// matrix's zero entries keep only the products' underflow allowance, while the entries
    /// near 0.0 and 1 carry the normalization's and the products' roundings, a few units of
    /// 2⁻⁵³. The identity rotation gives an exact matrix; and a parent over a bounded child
    /// carries the child's bound.
    #[test]
    fn trs_bounds_the_rotation_s_roundings() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let m = BoundedMat4::trs(DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, h, h), DVec3::ONE);
        assert!(
            m.error.x_axis.x > 0.0 && m.error.x_axis.x < 1e-15,
            "{:?}",
            m.error
        );
        assert!(
            m.error.x_axis.y > 0.0 && m.error.x_axis.y < 1e-15,
            "{:?}",
            m.error
        );
        assert!(m.error.x_axis.z < 1e-300, "{:?}", m.error);
        assert!(BoundedMat4::trs(DVec3::X, DQuat::IDENTITY, DVec3::splat(2.0)).is_exact());
        let parent = BoundedMat4::exact(DMat4::from_translation(DVec3::splat(3.0)));
        let child = parent.then_bounded(&m);
        assert!(
            child.error.x_axis.y >= m.error.x_axis.y,
            "{:?}",
            child.error
        );
    }

    #[test]
    fn perturbation_widens_the_inverse_norm() {
        let e = DMat3::from_diagonal(DVec3::splat(0.25));
        assert_eq!(perturbed_inverse_norm(2.0, &DMat3::ZERO), 2.0);
        // 2 / (1 − 2·0.25) = 4.
        let n = perturbed_inverse_norm(2.0, &e);
        assert!((4.0..4.0 + 1e-12).contains(&n), "{n}");
        assert_eq!(perturbed_inverse_norm(4.0, &e), f64::INFINITY);
    }
}
