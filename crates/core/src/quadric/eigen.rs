//! Eigen-decomposition of symmetric 3×3 matrices (cyclic Jacobi rotations).

use glam::{DMat3, DVec3};

/// Eigenvalues whose magnitude is at most this fraction of the largest magnitude count as zero.
pub(super) const ZERO_EIGENVALUE: f64 = 1e-13;

/// Upper bound on Jacobi sweeps; a 3×3 matrix converges to machine precision in about six.
const MAX_SWEEPS: usize = 50;

/// The eigenvalues of a symmetric matrix and the orthonormal eigenvectors (as columns, in the
/// same order). Only the upper triangle of `m` is read.
pub(super) fn symmetric_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut a = m.transpose().to_cols_array_2d(); // a[row][col]
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    (a[1][0], a[2][0], a[2][1]) = (a[0][1], a[0][2], a[1][2]);
    for _ in 0..MAX_SWEEPS {
        if a[0][1] == 0.0 && a[0][2] == 0.0 && a[1][2] == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            jacobi_rotate(&mut a, &mut v, p, q);
        }
    }
    let values = DVec3::new(a[0][0], a[1][1], a[2][2]);
    let vectors = DMat3::from_cols_array_2d(&v).transpose();
    (values, vectors)
}

/// Applies the rotation in the (p, q) plane that zeroes `a[p][q]`, accumulating it into `v`.
/// An off-diagonal entry that no longer changes the diagonal in f64 is set to zero directly.
fn jacobi_rotate(a: &mut [[f64; 3]; 3], v: &mut [[f64; 3]; 3], p: usize, q: usize) {
    let apq = a[p][q];
    if apq == 0.0 {
        return;
    }
    let negligible = 1e-3 * f64::EPSILON;
    if apq.abs() <= negligible * a[p][p].abs() && apq.abs() <= negligible * a[q][q].abs() {
        a[p][q] = 0.0;
        a[q][p] = 0.0;
        return;
    }
    let theta = (a[q][q] - a[p][p]) / (2.0 * apq);
    let t = theta.signum() / (theta.abs() + theta.hypot(1.0));
    let c = 1.0 / t.hypot(1.0);
    let s = t * c;
    for row in a.iter_mut() {
        let (akp, akq) = (row[p], row[q]);
        row[p] = c * akp - s * akq;
        row[q] = s * akp + c * akq;
    }
    let (row_p, row_q) = (a[p], a[q]);
    a[p] = [0, 1, 2].map(|k| c * row_p[k] - s * row_q[k]);
    a[q] = [0, 1, 2].map(|k| s * row_p[k] + c * row_q[k]);
    a[p][q] = 0.0;
    a[q][p] = 0.0;
    for row in v.iter_mut() {
        let (vp, vq) = (row[p], row[q]);
        row[p] = c * vp - s * vq;
        row[q] = s * vp + c * vq;
    }
}

/// Whether the symmetric matrix is positive or negative definite (all eigenvalues non-zero,
/// relative to the largest, and of one sign).
pub(super) fn is_definite(m: DMat3) -> bool {
    let (values, _) = symmetric_eigen(m);
    let largest = values.abs().max_element();
    let nonzero = values.abs().min_element() > ZERO_EIGENVALUE * largest;
    nonzero && (values.cmpgt(DVec3::ZERO).all() || values.cmplt(DVec3::ZERO).all())
}
