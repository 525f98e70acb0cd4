//! A quadric polynomial `f(x) = x·Q·x + P·x + R` in some frame, and the roots of
//! `f(x0 + t·v) = K t² + L t + M` along a ray in that frame.

use glam::{DMat3, DVec3};

/// Ray coefficients below this fraction of their rounding scale count as zero.
const NEGLIGIBLE_COEFFICIENT: f64 = 1e-13;

/// Relative rounding error assumed for a point computed along a ray (a few ulps).
const VERTEX_ROUNDING: f64 = 4.0 * f64::EPSILON;

/// Coefficients of a quadric polynomial, scaled by a power of two so that the largest entry
/// of `Q` (or of `P` when `Q = 0`) is about 1.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Polynomial {
    pub q: DMat3,
    q_abs: DMat3,
    pub p: DVec3,
    pub r: f64,
}

/// The quadratic `K t² + L t + M` along a ray, with rounding scales for `K` and `L`.
struct RayPolynomial {
    k: f64,
    l: f64,
    m: f64,
    k_scale: f64,
    l_scale: f64,
}

impl Polynomial {
    /// The polynomial with coefficients `q`, `p`, `r`, normalised by an exact power of two.
    pub fn new(q: DMat3, p: DVec3, r: f64) -> Polynomial {
        let (q, p, r) = power_of_two_normaliser(q, p)
            .into_iter()
            .fold((q, p, r), |(q, p, r), s| (q * s, p * s, r * s));
        Polynomial {
            q,
            q_abs: q.abs(),
            p,
            r,
        }
    }

    /// `f(x)`.
    pub fn value(&self, x: DVec3) -> f64 {
        x.dot(self.q * x) + self.p.dot(x) + self.r
    }

    /// `∇f(x) = 2Qx + P`.
    pub fn gradient(&self, x: DVec3) -> DVec3 {
        2.0 * (self.q * x) + self.p
    }

    /// A bound on the error of [`Polynomial::gradient`] at a point whose coordinates carry a
    /// rounding error of a few ulps of `size` (per component): `2|Q|·δ`, with `δ` a few ulps.
    pub fn gradient_rounding(&self, size: DVec3) -> f64 {
        (2.0 * (self.q_abs * (VERTEX_ROUNDING * size))).max_element()
    }

    /// The ray's quadratic for the start point `x0` and direction `v`.
    fn ray_polynomial(&self, x0: DVec3, v: DVec3) -> RayPolynomial {
        let qv = self.q * v;
        let v_abs = v.abs();
        let q_abs_v = self.q_abs * v_abs;
        RayPolynomial {
            k: v.dot(qv),
            l: 2.0 * x0.dot(qv) + self.p.dot(v),
            m: self.value(x0),
            k_scale: v_abs.dot(q_abs_v),
            l_scale: 2.0 * x0.abs().dot(q_abs_v) + self.p.abs().dot(v_abs),
        }
    }

    /// The real roots of `f(x0 + t·v) = 0` in ascending order (equal for a double or a single
    /// linear root), or `None` when there is none or the ray lies along the surface.
    ///
    /// Stable roots `q = −(L + sign(L)·√Δ)/2`, `t = q/K` and `M/q`; the linear case when `K`
    /// vanishes to rounding (the far root `q/K` is then noise), unless a non-zero `K` still
    /// gives a negative discriminant: a ray nearly along a cylinder's axis that passes outside
    /// it never reaches the surface. An accurate discriminant (see
    /// [`Polynomial::discriminant`]); one negative only by its rounding error counts as zero (a
    /// tangent ray, or any ray crossing coincident planes `x² = 0`).
    pub fn ray_roots(&self, x0: DVec3, v: DVec3) -> Option<[f64; 2]> {
        let poly = self.ray_polynomial(x0, v);
        let disc = (poly.k != 0.0).then(|| self.discriminant(&poly, x0, v));
        if disc.is_some_and(|d| d.is_nan() || d < 0.0) {
            return None;
        }
        if poly.k.abs() <= NEGLIGIBLE_COEFFICIENT * poly.k_scale {
            if poly.l.abs() <= NEGLIGIBLE_COEFFICIENT * poly.l_scale {
                return None;
            }
            let t = -poly.m / poly.l;
            return t.is_finite().then_some([t, t]);
        }
        let disc = disc.unwrap_or(0.0);
        let q = -0.5 * (poly.l + disc.sqrt().copysign(poly.l));
        if q == 0.0 {
            let t = -poly.l / (2.0 * poly.k);
            return Some([t, t]);
        }
        let (a, b) = (q / poly.k, poly.m / q);
        Some([a.min(b), a.max(b)])
    }

    /// `Δ = L² − 4KM`. When `4KM` is close to `L²` the difference cancels, so it is computed as
    /// `−4K·f(m)` at the point `m = x0 + t_c·v`, `t_c = −L/(2K)`, the vertex of the parabola in
    /// `t`; elsewhere the plain form is accurate.
    ///
    /// The vertex `m` carries a rounding error of about `ε·(|x0| + |t_c·v|)` per component, so
    /// `f(m)` is uncertain by `|∇f(m)|·δ + |Q|·δ²`; a value within that of zero gives `Δ = 0`.
    fn discriminant(&self, poly: &RayPolynomial, x0: DVec3, v: DVec3) -> f64 {
        let four_km = 4.0 * poly.k * poly.m;
        let square = poly.l * poly.l;
        if four_km <= 0.5 * square {
            return square - four_km;
        }
        let t_c = -poly.l / (2.0 * poly.k);
        let m = x0 + t_c * v;
        let value = self.value(m);
        let delta = VERTEX_ROUNDING * (x0.abs() + (t_c * v).abs());
        let gradient = (2.0 * (self.q_abs * m.abs()) + self.p.abs()).dot(delta);
        let uncertainty = gradient + delta.dot(self.q_abs * delta);
        if value.abs() <= uncertainty {
            return 0.0;
        }
        -4.0 * poly.k * value
    }
}

/// The power of two that brings the largest entry of `Q` (or of `P` when `Q = 0`) near 1, as
/// two factors to apply one after the other: for subnormal coefficients (below 2⁻¹⁰²²) the
/// power itself exceeds the f64 range, its halves do not. Scaling by a power of two is exact
/// unless a result is subnormal, so it changes no rounding.
fn power_of_two_normaliser(q: DMat3, p: DVec3) -> [f64; 2] {
    let largest = q.abs().to_cols_array().into_iter().fold(0.0, f64::max);
    let largest = if largest > 0.0 {
        largest
    } else {
        p.abs().max_element()
    };
    let exponent = -(largest.log2().round() as i32);
    let half = exponent / 2;
    [2f64.powi(half), 2f64.powi(exponent - half)]
}
