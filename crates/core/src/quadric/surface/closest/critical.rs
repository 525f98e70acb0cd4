//! Where the distance from a point to a quadric surface may be smallest: every critical point
//! of the distance on the surface, for a quadric written in an orthonormal frame where its
//! matrix is diagonal.
//!
//! # The Lagrange condition
//! With `f(y) = Σ λᵢ yᵢ² + b·y + r`, a point `y` of `f = 0` is critical for `|y − p|` when
//! `y − p = (ν/2) ∇f(y)` for some `ν`, that is `yᵢ (1 − ν λᵢ) = pᵢ + ν bᵢ / 2`. Written about
//! the centres `cᵢ = −bᵢ / (2λᵢ)` of the directions with `λᵢ ≠ 0` (`qᵢ = pᵢ − cᵢ`):
//!
//! - `yᵢ = cᵢ + qᵢ / (1 − ν λᵢ)` where `λᵢ ≠ 0`,
//! - `yⱼ = pⱼ + ν bⱼ / 2` where `λⱼ = 0` (a paraboloid's or a plane's linear direction; a
//!   cylinder's axis, where `bⱼ = 0`, keeps `yⱼ = pⱼ`),
//!
//! and `f(y(ν)) = Σ λᵢ qᵢ² / Dᵢ² + k + Σ bⱼ pⱼ + ν Σ bⱼ² / 2 = 0` with `Dᵢ = 1 − ν λᵢ` and
//! `k = r − Σ λᵢ cᵢ²`. Multiplied by `Π Dᵢ²` this is a polynomial of degree at most 6 in `ν`
//! (the secular polynomial), whose real roots give every critical point but two kinds:
//!
//! - **the hard case**: at a pole `ν = 1/λᵢ` with `qᵢ = 0` (the point on a plane of
//!   symmetry: the centre of a sphere, the axis of a cylinder) the component `yᵢ` is free
//!   and is chosen to put `y` on the surface, `±` along the group of directions that share
//!   the pole. Near the hard case the roots lie so near the pole that `1 − ν λᵢ` has lost its
//!   digits; the hard-case points are then the near ones, so both are offered;
//! - **singular points**, where `∇f = 0` on the surface (a cone's apex, the line where two
//!   planes cross, any point of a double plane): the centre, with `yⱼ = pⱼ` along the
//!   directions without curvature.
//!
//! The candidates are approximate (a root in f64, a pole's lost digits): the caller settles
//! each on the surface and keeps the nearest that lies on it. A candidate that is not a
//! critical point costs only time, since every settled candidate is a point of the surface.

use super::roots::real_roots;

/// Eigenvalues within this fraction of a pole's eigenvalue share its hard case (a sphere's
/// three equal eigenvalues, computed unequal by rounding).
const SAME_POLE: f64 = 1e-6;

/// A quadric `f(y) = Σ λᵢ yᵢ² + b·y + r` in an orthonormal frame where its matrix is
/// diagonal; eigenvalues of magnitude at most `zero` count as 0.
pub(super) struct Diagonal {
    /// The eigenvalues `λ`.
    pub lambda: [f64; 3],
    /// The linear coefficients `b` in the frame.
    pub b: [f64; 3],
    /// The constant `r`.
    pub r: f64,
    /// Eigenvalues at most this in magnitude count as 0.
    pub zero: f64,
}

/// The secular equation of a query point: `y(ν)` and what the polynomial is made of.
struct Secular {
    /// Whether `λᵢ` counts as non-zero.
    curved: [bool; 3],
    /// `cᵢ` (0 where `λᵢ = 0`).
    centre: [f64; 3],
    /// `qᵢ = pᵢ − cᵢ` (0 where `λᵢ = 0`).
    q: [f64; 3],
    /// The query point.
    p: [f64; 3],
    /// `k + Σ bⱼ pⱼ` over the directions without curvature.
    constant: f64,
    /// `Σ bⱼ² / 2` over the directions without curvature.
    slope: f64,
}

impl Diagonal {
    /// Every candidate nearest point to `p` (see the module docs), approximate, in the frame.
    pub fn candidates(&self, p: [f64; 3], out: &mut Vec<[f64; 3]>) {
        let s = self.secular(p);
        let scale = (0..3)
            .filter(|&i| s.curved[i])
            .map(|i| self.lambda[i].abs())
            .fold(0.0, f64::max);
        // In `μ = ν · scale` the polynomial's coefficients are of one size.
        let scale = if scale > 0.0 { scale } else { 1.0 };
        let (roots, turns) = real_roots(&self.polynomial(&s, scale));
        for mu in roots.into_iter().chain(turns) {
            push_finite(out, self.at(&s, mu / scale));
        }
        for pole in 0..3 {
            self.hard_case(&s, pole, out);
        }
        push_finite(
            out,
            std::array::from_fn(|i| if s.curved[i] { s.centre[i] } else { p[i] }),
        );
    }

    /// The secular equation's pieces for the query `p`.
    fn secular(&self, p: [f64; 3]) -> Secular {
        let curved = self.lambda.map(|l| l.abs() > self.zero);
        let centre: [f64; 3] = std::array::from_fn(|i| {
            if curved[i] {
                -self.b[i] / (2.0 * self.lambda[i])
            } else {
                0.0
            }
        });
        let q = std::array::from_fn(|i| if curved[i] { p[i] - centre[i] } else { 0.0 });
        let mut constant = self.r;
        let mut slope = 0.0;
        for i in 0..3 {
            if curved[i] {
                constant -= self.lambda[i] * centre[i] * centre[i];
            } else {
                constant += self.b[i] * p[i];
                slope += 0.5 * self.b[i] * self.b[i];
            }
        }
        Secular {
            curved,
            centre,
            q,
            p,
            constant,
            slope,
        }
    }

    /// The point `y(ν)`.
    fn at(&self, s: &Secular, nu: f64) -> [f64; 3] {
        std::array::from_fn(|i| {
            if s.curved[i] {
                s.centre[i] + s.q[i] / (1.0 - nu * self.lambda[i])
            } else {
                s.p[i] + 0.5 * nu * self.b[i]
            }
        })
    }

    /// The secular polynomial in `μ = ν · scale`, lowest degree first:
    /// `Σ λᵢ qᵢ² Π_{h≠i} D_h² + (constant + slope · ν) Π D_h²`, `D_h = 1 − μ λ_h / scale`.
    fn polynomial(&self, s: &Secular, scale: f64) -> Vec<f64> {
        let squares: Vec<(usize, Vec<f64>)> = (0..3)
            .filter(|&i| s.curved[i])
            .map(|i| {
                let d = [1.0, -self.lambda[i] / scale];
                (i, multiply(&d, &d))
            })
            .collect();
        let product_without = |skip: Option<usize>| {
            squares
                .iter()
                .filter(|(i, _)| Some(*i) != skip)
                .fold(vec![1.0], |acc, (_, sq)| multiply(&acc, sq))
        };
        let mut total = multiply(&[s.constant, s.slope / scale], &product_without(None));
        for &(i, _) in &squares {
            let weight = self.lambda[i] * s.q[i] * s.q[i];
            for (t, c) in total.iter_mut().zip(product_without(Some(i))) {
                *t += weight * c;
            }
        }
        total
    }

    /// The hard-case points at the pole of direction `pole` (if it is the first of the
    /// directions sharing the pole): the others at `ν = 1/λ`, the pole's group on the surface
    /// along its `q` (or along `pole` when that is 0), both ways.
    fn hard_case(&self, s: &Secular, pole: usize, out: &mut Vec<[f64; 3]>) {
        if !s.curved[pole] {
            return;
        }
        let lambda = self.lambda[pole];
        let shares =
            |i: usize| s.curved[i] && (self.lambda[i] - lambda).abs() <= SAME_POLE * lambda.abs();
        if (0..pole).any(shares) {
            return;
        }
        let nu = 1.0 / lambda;
        let mut y = self.at(s, nu);
        let mut rest = s.constant + s.slope * nu;
        for i in (0..3).filter(|&i| s.curved[i] && !shares(i)) {
            let z = y[i] - s.centre[i];
            rest += self.lambda[i] * z * z;
        }
        let radius_squared = -rest / lambda;
        if radius_squared.is_nan() || radius_squared < 0.0 {
            return;
        }
        let length = (0..3)
            .filter(|&i| shares(i))
            .map(|i| s.q[i] * s.q[i])
            .sum::<f64>()
            .sqrt();
        let radius = radius_squared.sqrt();
        for sign in [1.0, -1.0] {
            for i in (0..3).filter(|&i| shares(i)) {
                let along = if length > 0.0 {
                    s.q[i] / length
                } else {
                    f64::from(u8::from(i == pole))
                };
                y[i] = s.centre[i] + sign * radius * along;
            }
            push_finite(out, y);
        }
    }
}

/// The product of two polynomials (lowest degree first).
fn multiply(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

fn push_finite(out: &mut Vec<[f64; 3]>, y: [f64; 3]) {
    if y.iter().all(|v| v.is_finite()) {
        out.push(y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The nearest candidate on the surface: approximate (the caller settles candidates), so
    /// the tests below allow 1e-9.
    fn nearest(d: &Diagonal, p: [f64; 3]) -> f64 {
        let mut out = Vec::new();
        d.candidates(p, &mut out);
        let f = |y: &[f64; 3]| {
            (0..3)
                .map(|i| d.lambda[i] * y[i] * y[i] + d.b[i] * y[i])
                .sum::<f64>()
                + d.r
        };
        out.iter()
            .filter(|y| f(y).abs() < 1e-9)
            .map(|y| (0..3).map(|i| (y[i] - p[i]).powi(2)).sum::<f64>().sqrt())
            .fold(f64::INFINITY, f64::min)
    }

    const SPHERE: Diagonal = Diagonal {
        lambda: [1.0, 1.0, 1.0],
        b: [0.0; 3],
        r: -1.0,
        zero: 1e-13,
    };

    #[test]
    fn a_sphere_from_outside_inside_and_its_centre() {
        assert!((nearest(&SPHERE, [3.0, 0.0, 0.0]) - 2.0).abs() < 1e-9);
        assert!((nearest(&SPHERE, [0.0, 0.25, 0.0]) - 0.75).abs() < 1e-9);
        assert!((nearest(&SPHERE, [0.0; 3]) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn an_ellipsoid_s_centre_is_nearest_its_shortest_axis() {
        let d = Diagonal {
            lambda: [1.0, 4.0, 0.25],
            b: [0.0; 3],
            r: -1.0,
            zero: 1e-13,
        };
        assert!((nearest(&d, [0.0; 3]) - 0.5).abs() < 1e-9);
    }

    #[test]
    fn a_cylinder_s_axis_and_a_paraboloid_s_vertex() {
        let cylinder = Diagonal {
            lambda: [1.0, 1.0, 0.0],
            b: [0.0; 3],
            r: -4.0,
            zero: 1e-13,
        };
        assert!((nearest(&cylinder, [0.0, 0.0, 7.0]) - 2.0).abs() < 1e-9);
        // z = x² + y²: from (0, 0, −1) the vertex is nearest, at 1.
        let bowl = Diagonal {
            lambda: [1.0, 1.0, 0.0],
            b: [0.0, 0.0, -1.0],
            r: 0.0,
            zero: 1e-13,
        };
        assert!((nearest(&bowl, [0.0, 0.0, -1.0]) - 1.0).abs() < 1e-9);
        // From (0, 0, 1) the circle z = 1/2 at radius 1/√2 is nearest: √3/2.
        assert!((nearest(&bowl, [0.0, 0.0, 1.0]) - 0.75f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn a_cone_s_apex_is_a_candidate() {
        let cone = Diagonal {
            lambda: [1.0, 1.0, -1.0],
            b: [0.0; 3],
            r: 0.0,
            zero: 1e-13,
        };
        let mut out = Vec::new();
        cone.candidates([0.0, 0.0, -2.0], &mut out);
        assert!(out.contains(&[0.0, 0.0, 0.0]));
        assert!((nearest(&cone, [0.0, 0.0, -2.0]) - 2f64.sqrt()).abs() < 1e-9);
    }
}
