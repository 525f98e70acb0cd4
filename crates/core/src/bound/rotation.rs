//! A rotation about a coordinate axis by an angle in degrees (USD's `rotateX`, `rotateY`,
//! `rotateZ` and the three-angle ops), as a [`BoundedMat4`]: glam's matrix of
//! `degrees.to_radians()`, bit for bit, with a bound on each entry's distance from the exact
//! rotation by the exact angle `degrees · π / 180`.
//!
//! # Derivation
//! `to_radians` is `r̂ = fl(degrees · C)` with `C = fl(fl(π) / 180)`: `|fl(π) − π| ≤ uπ` and the
//! quotient's rounding give `|C − π/180| ≤ 2u(1 + u)·π/180`, and the product's rounding
//! `u|r̂|`, so `|r̂ − r*| ≤ u|r̂| + 2u(1 + u)|degrees|π/180 ≤ γ₄|r̂|` (`|degrees|·π/180 ≤
//! |r̂|/(1 − 3u)`). `sin` and `cos` are 1-Lipschitz, so the exact functions at `r̂` are within
//! `γ₄|r̂|` of those at `r*`; libm's values are within [`LIBM_ULPS`] units in the last place of
//! the exact functions at `r̂` (glibc documents at most one for `sin` and `cos` on x86-64; two
//! are allowed here), at most `2u` each relative to the value, plus the smallest subnormal for
//! a result that underflows. Each entry of the matrix is one of `±sin`, `cos`, `0` and `1` as
//! glam places them; `0` and `1` are exact.

use super::bounded::{gamma, up, UNIT};
use super::transform::BoundedMat4;
use glam::{DMat4, DVec4};

/// Units in the last place allowed between libm's `sin`/`cos` and the exact functions.
pub const LIBM_ULPS: f64 = 2.0;

/// A bound on `|fl(f(r̂)) − f(r*)|` for `f` one of `sin`, `cos` with the computed value
/// `value` (see the module docs).
fn trig_error(radians: f64, value: f64) -> f64 {
    let libm = LIBM_ULPS * 2.0 * UNIT * value.abs() + f64::from_bits(1);
    up(gamma(4) * radians.abs() + libm)
}

/// The rotation by `degrees` about coordinate axis `axis` (0: x, 1: y, 2: z), as glam computes
/// `DMat4::from_rotation_{x,y,z}(degrees.to_radians())`, with its bound.
pub fn about_axis(axis: usize, degrees: f64) -> BoundedMat4 {
    let radians = degrees.to_radians();
    let value = match axis {
        0 => DMat4::from_rotation_x(radians),
        1 => DMat4::from_rotation_y(radians),
        _ => DMat4::from_rotation_z(radians),
    };
    if degrees == 0.0 {
        // sin 0 = 0 and cos 0 = 1, exactly, in libm as in the reals.
        return BoundedMat4::exact(value);
    }
    let (sin, cos) = radians.sin_cos();
    let (sin_error, cos_error) = (trig_error(radians, sin), trig_error(radians, cos));
    // The two other axes, in the plane of the rotation.
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut error = [[0.0; 4]; 4];
    error[i][i] = cos_error;
    error[j][j] = cos_error;
    error[i][j] = sin_error;
    error[j][i] = sin_error;
    let error = DMat4::from_cols_array_2d(&error);
    debug_assert_eq!(error.w_axis, DVec4::ZERO);
    BoundedMat4 { value, error }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values are glam's; cos 90° is not 0 in f64 (6.1e-17), and the bound covers that
    /// distance from the exact 0.
    #[test]
    fn a_quarter_turn_is_glams_and_its_bound_covers_cos_90() {
        let m = about_axis(2, 90.0);
        assert_eq!(m.value, DMat4::from_rotation_z(90f64.to_radians()));
        let cos = m.value.x_axis.x;
        assert!(cos != 0.0 && cos.abs() < 1e-16, "{cos}");
        assert!(m.error.x_axis.x >= cos.abs(), "{:?}", m.error);
        assert!(m.error.x_axis.x < 1e-15);
        // sin 90° = 1 exactly, and fl(sin(fl(π/2))) is 1 too: a bound of a few u.
        assert_eq!(m.value.x_axis.y, 1.0);
        assert!(m.error.x_axis.y > 0.0 && m.error.x_axis.y < 2e-15);
        assert_eq!(m.error.z_axis, DVec4::ZERO);
        assert_eq!(m.error.col(2).z, 0.0);
    }

    /// The bounded entries are those of the plane of rotation, for each axis.
    #[test]
    fn each_axis_bounds_its_own_plane() {
        for axis in 0..3 {
            let m = about_axis(axis, 33.0);
            let e = m.error.to_cols_array_2d();
            for (c, column) in e.iter().enumerate() {
                for (r, &bound) in column.iter().enumerate() {
                    let in_plane = c != axis && r != axis && c < 3 && r < 3;
                    assert_eq!(bound > 0.0, in_plane, "axis {axis} [{c}][{r}]");
                }
            }
        }
        assert!(about_axis(0, 0.0).is_exact());
    }
}
