//! A quadric polynomial `f(x) = x·Q·x + P·x + R` in some frame, and the roots of
//! `f(x0 + t·v) = K t² + L t + M` along a ray in that frame.

use glam::{DMat3, DVec3};
use twofloat::TwoFloat;

/// Ray coefficients below this fraction of their rounding scale count as zero.
const NEGLIGIBLE_COEFFICIENT: f64 = 1e-13;

/// A bound on the rounding error of `K = v·Q·v` relative to its scale `|v|·|Q|·|v|` (the
/// products and the two sums of each of the three terms, and the sum of the three).
const K_ROUNDING: f64 = 8.0 * f64::EPSILON;

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

    /// A bound on the rounding error of [`Polynomial::value`] at `x`, itself exact: a few
    /// ulps of the sum of the terms' magnitudes, `|x|·|Q|·|x| + |P|·|x| + |R|`.
    pub fn value_rounding(&self, x: DVec3) -> f64 {
        let x_abs = x.abs();
        8.0 * f64::EPSILON
            * (x_abs.dot(self.q_abs * x_abs) + self.p.abs().dot(x_abs) + self.r.abs())
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
    /// Stable roots `q = −(L + sign(L)·√Δ)/2`, `t = q/K` and `M/q`; the linear case when the
    /// quadratic is linear to rounding ([`Polynomial::nearly_linear`]: the far root `q/K` is
    /// then noise), unless a non-zero `K` still gives a negative discriminant: a ray nearly
    /// along a cylinder's axis that passes outside it never reaches the surface. An accurate discriminant (see
    /// [`Polynomial::discriminant`]); one negative only by its rounding error counts as zero (a
    /// tangent ray, or any ray crossing coincident planes `x² = 0`).
    pub(super) fn ray_roots(&self, x0: DVec3, v: DVec3) -> Option<[f64; 2]> {
        let poly = self.ray_polynomial(x0, v);
        let disc = (poly.k != 0.0).then(|| self.discriminant(&poly, x0, v));
        if disc.is_some_and(|d| d.is_nan() || d < 0.0) {
            return None;
        }
        if self.nearly_linear(&poly) {
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

    /// Whether the ray's quadratic is linear to rounding: `K` vanishes against its scale, and
    /// either it is no more than its own rounding error or its term is negligible at the
    /// linear root (`|K·M| ≪ L²`, so `t = −M/L` is the near root). A `K` well above its
    /// rounding error whose term is not negligible (a ray 1e-7 rad off a cylinder's axis:
    /// `4KM ≈ L²`) keeps the quadratic: the stable near root `M/q` is right where `−M/L` is
    /// off by `K·M/L²` (40 % there), and the far root is a real exit.
    fn nearly_linear(&self, poly: &RayPolynomial) -> bool {
        let k = poly.k.abs();
        k <= NEGLIGIBLE_COEFFICIENT * poly.k_scale
            && (k <= K_ROUNDING * poly.k_scale
                || 4.0 * k * poly.m.abs() <= NEGLIGIBLE_COEFFICIENT * poly.l * poly.l)
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
        if value.abs() > uncertainty {
            return -4.0 * poly.k * value;
        }
        self.vertex_discriminant(x0, v)
    }

    /// `Δ` at the parabola's vertex in double-double arithmetic, for when f64 cannot tell its
    /// sign: the vertex is far along the ray (a ray nearly along a cylinder's axis, `t_c` ≈
    /// 1e7), so `f(m)` in f64 is uncertain by `|Q|·|m|·ε|m|`, more than its value.
    ///
    /// `K` and `L` are recomputed to about ε² (so `t_c` is right to a few ulps and `f(m)`
    /// exceeds the minimum of `f` along the ray by `K·(4ε·t_c)²` at most), the vertex `m =
    /// x0 + t_c·v` is formed exactly, and `f(m)` is summed to about ε²·(|m|·|Q|·|m| + |P|·|m|
    /// + |R|). A value within those bounds of zero gives `Δ = 0` (tangent).
    fn vertex_discriminant(&self, x0: DVec3, v: DVec3) -> f64 {
        let (x0, v) = (x0.to_array(), v.to_array());
        let k = self.form(&v, &v);
        let l = self.form(&x0, &v) * 2.0 + dot(&self.p.to_array(), &v);
        if k.hi() <= 0.0 || !k.hi().is_finite() || !l.hi().is_finite() {
            return 0.0;
        }
        let t_c = -l.hi() / (2.0 * k.hi());
        let m: [TwoFloat; 3] = std::array::from_fn(|i| TwoFloat::new_mul(t_c, v[i]) + x0[i]);
        let p = self.p.to_array();
        let value = self.form_dd(&m, &m)
            + (0..3).fold(TwoFloat::from(0.0), |s, i| s + m[i] * p[i])
            + self.r;
        let m_abs = m.map(|x| x.hi().abs());
        let size = DVec3::from_array(m_abs);
        let scale = size.dot(self.q_abs * size) + self.p.abs().dot(size) + self.r.abs();
        let excess = k.hi() * (4.0 * f64::EPSILON * t_c).powi(2);
        let uncertainty = 16.0 * f64::EPSILON * f64::EPSILON * scale + excess;
        if value.hi().abs() <= uncertainty {
            return 0.0;
        }
        -4.0 * k.hi() * value.hi()
    }

    /// `aᵀ Q b` in double-double, for f64 vectors.
    fn form(&self, a: &[f64; 3], b: &[f64; 3]) -> TwoFloat {
        self.form_dd(&a.map(TwoFloat::from), &b.map(TwoFloat::from))
    }

    /// `aᵀ Q b` in double-double.
    fn form_dd(&self, a: &[TwoFloat; 3], b: &[TwoFloat; 3]) -> TwoFloat {
        let q = self.q.to_cols_array_2d();
        let mut sum = TwoFloat::from(0.0);
        for (i, ai) in a.iter().enumerate() {
            for (j, bj) in b.iter().enumerate() {
                sum += *ai * *bj * q[j][i];
            }
        }
        sum
    }
}

/// `a · b` in double-double.
fn dot(a: &[f64; 3], b: &[f64; 3]) -> TwoFloat {
    (0..3).fold(TwoFloat::from(0.0), |s, i| {
        s + TwoFloat::new_mul(a[i], b[i])
    })
}

/// The power of two that brings the largest entry of `Q` (or of `P` when `Q = 0`) near 1, as
/// two factors to apply one after the other: for subnormal coefficients (below 2⁻¹⁰²²) the
/// power itself exceeds the f64 range, its halves do not. Scaling by a power of two is exact
/// unless a result is subnormal, so it changes no rounding.
pub(super) fn power_of_two_normaliser(q: DMat3, p: DVec3) -> [f64; 2] {
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
