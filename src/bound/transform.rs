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
//! node's own matrix is taken as the numbers the file gives (a `matrix`: as read; translation,
//! rotation and scale: as multiplied out in f64, not bounded).
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
use glam::{DMat3, DMat4, DVec3, DVec4};
use std::ops::{Add, Mul};

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

    /// `self · local` as glam computes it (the importer's product, bit for bit), with the bound
    /// of the module docs: each entry's sum of four products evaluated in [`Bounded`]
    /// arithmetic in glam's order (`((p₀l₀ + p₁l₁) + p₂l₂) + p₃l₃`), the parent's entries
    /// within their bounds and the local matrix exact, so the bound holds the actual roundings
    /// rather than `γ₄`'s worst case. A root's exact identity parent adds no error.
    pub fn then(&self, local: &DMat4) -> BoundedMat4 {
        let value = self.value * *local;
        if self.value == DMat4::IDENTITY && self.is_exact() {
            return BoundedMat4 {
                value,
                error: DMat4::ZERO,
            };
        }
        let (p, e, l) = (
            self.value.transpose().to_cols_array_2d(),
            self.error.transpose().to_cols_array_2d(),
            local.to_cols_array_2d(),
        );
        let mut error = [[0.0; 4]; 4];
        for (j, column) in l.iter().enumerate() {
            for i in 0..4 {
                let term = |k: usize| Bounded::new(p[i][k], e[i][k]).mul(Bounded::exact(column[k]));
                let entry = term(0).add(term(1)).add(term(2)).add(term(3));
                error[j][i] = entry.error;
            }
        }
        // Two affine matrices: the last row (0, 0, 0, 1) is computed exactly (the products'
        // underflow allowance is not needed there).
        if self.value.row(3) == DVec4::W
            && local.row(3) == DVec4::W
            && self.error.row(3) == DVec4::ZERO
        {
            for column in &mut error {
                column[3] = 0.0;
            }
        }
        BoundedMat4 {
            value,
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
