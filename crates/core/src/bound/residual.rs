//! The `error` bound of a triangle hit from the residual of the exact plane at the reported
//! point: a few dozen f64 operations, where [`super::triangle::bound`] recomputes the
//! watertight test in [`super::bounded::Bounded`] arithmetic (about ten times the work).
//!
//! # Derivation
//! Inputs, all f64 numbers taken as exact reals: the stored vertices `a, b, c`, each coordinate
//! of the exact vertices within `ε` of them; the ray `o + t·d`, the exact ray's origin and
//! direction within `eₒ`, `e_d` (per coordinate); the reported `t`. The exact plane of the exact
//! triangle is `n*·(x − a*) = 0` with `n* = (b* − a*) × (c* − a*)`, and the exact crossing `t*`
//! satisfies `n*·(o* + t*d* − a*) = 0`, so with the residual `R* = n*·(o* + t·d* − a*)` at the
//! reported `t`, `R* = (t − t*)·(n*·d*)`: **`|t − t*| = |R*| / |D*|**, `D* = n*·d*`.
//!
//! `R*` and `D*` are evaluated from f64 numbers with a bound on their distance from the exact
//! values (standard model: each operation `fl(x ∘ y) = (x ∘ y)(1 + δ)`, `|δ| ≤ u`, so its error
//! is at most `γ₁|fl(x ∘ y)|`):
//! - `q = fl(fl(o − a) + fl(t·d))` is within `Q = γ₁(|o − a|̂ + |t·d|̂ + |q|)` of
//!   `X = o + t·d − a` per coordinate;
//! - `ñ = fl(e₁ × e₂)` with `e₁ = fl(b − a)`, `e₂ = fl(c − a)` is within
//!   `Nᵢ = γ₄(|fl(e₁ⱼe₂ₖ)| + |fl(e₁ₖe₂ⱼ)|)` of the stored triangle's exact normal `n`: each
//!   product is within `(2γ₁ + γ₁²)` of the product of the exact differences, `γ₃` of the
//!   rounded one with its own rounding, and the difference adds `γ₁|ñᵢ| ≤ γ₁(1 + u)Σ|products|`;
//! - `r̃ = fl(ñ·q)` is within `γ₁(Σ|fl(ñᵢqᵢ)| + |partial sum| + |r̃|) + Σ(|ñᵢ|Qᵢ + Nᵢ(|qᵢ| + Qᵢ))`
//!   of `R = n·X`, and `D̃ = fl(ñ·d)` within the same expression with `d` (exact, `Q = 0`) of
//!   `n·d`;
//! - the exact scene moves `X` by at most `P = eₒ + |t|e_d + ε` and `n` by at most
//!   `Mᵢ = 2ε(|E₁ⱼ| + |E₁ₖ| + |E₂ⱼ| + |E₂ₖ|) + 8ε²` (`|E| ≤ |e|(1 + γ₁)`), so
//!   `|R* − R| ≤ Σ Mᵢ(|Xᵢ| + Pᵢ) + Σ |nᵢ|Pᵢ` and `|D* − n·d| ≤ Σ Mᵢ(|dᵢ| + e_dᵢ) + Σ |nᵢ|e_dᵢ`.
//!
//! Then `|t − t*| ≤ (|r̃| + E_R) / (|D̃| − E_D)`, `+∞` when the divisor may vanish.
//!
//! **Where the standard model holds.** Every operation above stays in the normal range when the
//! inputs and the intermediates that are multiplied again (`o − a`, `q`, `e₁`, `e₂`, `ñ`) are
//! zero or between `2⁻²⁵⁰` and `2²⁵⁰` in magnitude, which [`plane_error`] checks (`None`
//! otherwise: the caller then takes the bounded recomputation). The bound's own evaluation is
//! sums and products of non-negative normal numbers, each within a relative `u`: a few hundred
//! of them are covered by the final factor `1 + 2⁻⁴⁰`, and the divisor is rounded down.

use super::bounded::{down, gamma, up};
use glam::DVec3;

/// Smallest and largest magnitudes (besides zero) for which the standard model is applied.
const LOW: f64 = 1.0 / (1u128 << 125) as f64 / (1u128 << 125) as f64;
const HIGH: f64 = (1u128 << 125) as f64 * (1u128 << 125) as f64;

/// Whether every coordinate of `v` is in range ([`all_in_range`]).
#[inline(always)]
fn fits3(v: DVec3) -> bool {
    all_in_range(v.to_array())
}

/// Whether every one of `values` is zero or within `[2⁻²⁵⁰, 2²⁵⁰]` in magnitude (not NaN, not
/// infinite): where the bounds of this module apply the standard model. Comparisons without a
/// branch (a NaN fails them all), which the compiler runs four lanes at a time; a range's
/// `contains` cost some twenty instructions a number. The failures are gathered in an
/// integer, not a `bool`: where the `bool` form was inlined into the `certain` column's
/// bounds the compiler reduced it with a register-to-register `vmovq` that valgrind 3.19
/// cannot decode (callgrind, this project's measure, stopped there), and this form is also a
/// few instructions shorter. Give it whole groups of four: for a remainder the compiler once
/// emitted the same `vmovq`.
#[inline(always)]
#[allow(clippy::manual_range_contains)]
pub fn all_in_range<const N: usize>(values: [f64; N]) -> bool {
    let mut outside = 0u64;
    for x in values {
        let a = x.abs();
        outside |= u64::from(!((a == 0.0) | ((a >= LOW) & (a <= HIGH))));
    }
    outside == 0
}

/// A ray within bounds of the exact one, per coordinate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearRay {
    /// The origin as traced.
    pub origin: DVec3,
    /// Per-coordinate bound on its distance from the exact origin.
    pub origin_error: DVec3,
    /// The direction as traced.
    pub dir: DVec3,
    /// Per-coordinate bound on its distance from the exact direction.
    pub dir_error: DVec3,
}

impl NearRay {
    /// A ray taken as exact.
    pub fn exact(origin: DVec3, dir: DVec3) -> NearRay {
        NearRay {
            origin,
            origin_error: DVec3::ZERO,
            dir,
            dir_error: DVec3::ZERO,
        }
    }
}

/// A bound on `|t − t*|` for the reported `t` of `ray` on the triangle `tri` whose exact
/// vertices are within `vertex_error` of the stored ones (see the module docs); `+∞` when the
/// exact ray may be parallel to the exact plane; `None` outside the range where the standard
/// model is applied.
#[inline(always)]
pub fn plane_error(ray: &NearRay, tri: &[DVec3; 3], vertex_error: f64, t: f64) -> Option<f64> {
    let g = gamma(1);
    let [a, b, c] = *tri;
    let (o, d) = (ray.origin, ray.dir);
    let (u, w) = (o - a, d * t);
    let q = u + w;
    let q_err = g * (u.abs() + w.abs() + q.abs());
    let (e1, e2) = (b - a, c - a);
    let (p1, p2) = (
        DVec3::new(e1.y * e2.z, e1.z * e2.x, e1.x * e2.y),
        DVec3::new(e1.z * e2.y, e1.x * e2.z, e1.y * e2.x),
    );
    let n = p1 - p2;
    let vectors = [
        a,
        b,
        c,
        o,
        d,
        ray.origin_error,
        ray.dir_error,
        u,
        q,
        e1,
        e2,
        n,
    ];
    // 38 numbers and two zeros: whole groups of four lanes.
    let mut values = [0.0; 40];
    (values[0], values[1]) = (t, vertex_error);
    for (k, v) in vectors.iter().enumerate() {
        values[2 + 3 * k..5 + 3 * k].copy_from_slice(&v.to_array());
    }
    if !all_in_range(values) {
        return None;
    }
    // Each product `fl(e₁ⱼe₂ₖ)` is within `γ₃` of the exact `E₁ⱼE₂ₖ` (the two differences'
    // roundings and its own), the difference within `γ₁` more.
    let n_err = (p1.abs() + p2.abs()) * gamma(4);
    let (r, r_err) = dot_error(n, q, n_err, q_err);
    let (den, den_err) = dot_error(n, d, n_err, DVec3::ZERO);
    let exact_scene =
        vertex_error == 0.0 && ray.origin_error == DVec3::ZERO && ray.dir_error == DVec3::ZERO;
    let (r_move, d_move) = if exact_scene {
        (0.0, 0.0)
    } else {
        let normal = (n.abs() + n_err, normal_move(vertex_error, e1, e2));
        let r_move = residual_move(ray, (vertex_error, t), (e1, e2), (n, n_err), (q, q_err))?;
        (r_move, direction_move(ray, normal))
    };
    let inflate = |x: f64| x * (1.0 + 1.0 / (1u64 << 40) as f64);
    let numerator = up(inflate(r.abs() + r_err + r_move));
    let divisor = down(den.abs() - up(inflate(den_err + d_move)));
    if divisor.is_nan() || divisor <= 0.0 || !numerator.is_finite() {
        return Some(f64::INFINITY);
    }
    Some(up(numerator / divisor))
}

/// The axes after each one (`j`) and after that (`k`): `(y, z, x)` and `(z, x, y)`.
#[inline(always)]
fn after(v: DVec3) -> (DVec3, DVec3) {
    (DVec3::new(v.y, v.z, v.x), DVec3::new(v.z, v.x, v.y))
}

/// A bound on `|n* − n|` per coordinate when each vertex moves by at most `eps`:
/// `2ε(|E₁ⱼ| + |E₁ₖ| + |E₂ⱼ| + |E₂ₖ|) + 8ε²`, `|E| ≤ |e|(1 + γ₁)` for the exact differences.
#[inline(always)]
fn normal_move(eps: f64, e1: DVec3, e2: DVec3) -> DVec3 {
    if eps == 0.0 {
        return DVec3::ZERO;
    }
    let (big1, big2) = (e1.abs() * (1.0 + gamma(1)), e2.abs() * (1.0 + gamma(1)));
    let ((j1, k1), (j2, k2)) = (after(big1), after(big2));
    (j1 + k1 + j2 + k2) * (2.0 * eps) + DVec3::splat(8.0 * eps * eps)
}

/// A bound on `|D* − n·d|`: `Σ Mᵢ(|dᵢ| + e_dᵢ) + Σ |nᵢ|e_dᵢ` for `(|n|, M)` = `normal`.
#[inline(always)]
fn direction_move(ray: &NearRay, (n_abs, moved): (DVec3, DVec3)) -> f64 {
    (moved * (ray.dir.abs() + ray.dir_error) + n_abs * ray.dir_error).element_sum()
}

/// A bound on `|R* − R|` when each vertex moves by at most `eps` and the ray by its bounds,
/// `None` outside the standard model's range. With `A = a − p`, `B = b − p`, `C = c − p`
/// (`p = o + t·d`), `R = −det(A, B, C)`, and the exact scene's `R*` is the same determinant
/// with each column moved by `α′`, `|α′ᵢ| ≤ Pᵢ = ε + eₒᵢ + |t|e_dᵢ`. Multilinearity gives the
/// first-order terms `α′·(B × C)`, `β′·(C × A)`, `γ′·(A × B)` (for a point inside the triangle
/// each cross product is its barycentric weight times `n`, so they sum to about `P·|n|`), the
/// second-order `C·(α′ × β′)` and its like, at most `Σᵢ|Cᵢ|·2PⱼPₖ`, and the third
/// `6PₓP_yP_z`. The cross products come from what [`plane_error`] computed: `A = −X`,
/// `B = E₁ − X`, `C = E₂ − X`, so `A × B = E₁ × X`, `C × A = X × E₂` and
/// `B × C = n − E₁ × X − X × E₂`.
#[inline(always)]
fn residual_move(
    ray: &NearRay,
    (eps, t): (f64, f64),
    (e1, e2): (DVec3, DVec3),
    (n, n_err): (DVec3, DVec3),
    (q, q_err): (DVec3, DVec3),
) -> Option<f64> {
    let moved = ray.origin_error + ray.dir_error * t.abs() + DVec3::splat(eps);
    if !fits3(moved) {
        return None;
    }
    let (s1, s2) = (e1.abs() * gamma(1), e2.abs() * gamma(1));
    let (c1, c1_err) = cross(e1, s1, q, q_err);
    let (c2, c2_err) = cross(q, q_err, e2, s2);
    let rest = n - c1 - c2;
    let rest_err = (n.abs() + c1.abs() + c2.abs()) * gamma(2) + n_err + c1_err + c2_err;
    let crosses = (c1.abs() + c1_err) + (c2.abs() + c2_err) + (rest.abs() + rest_err);
    let first = moved.dot(crosses);
    let (mj, mk) = after(moved);
    let x = q.abs() + q_err;
    let columns = x * 3.0 + e1.abs() + s1 + e2.abs() + s2;
    let second = columns.dot(mj * mk * 2.0);
    let third = 6.0 * moved.x * moved.y * moved.z;
    Some(first + second + third)
}

/// `fl(x × y)` and a bound on its distance from the exact `x* × y*` for `x*`, `y*` within
/// `dx`, `dy` of `x`, `y`: each component's products and difference (`γ₃` of the products'
/// magnitudes) and the carried bounds.
#[inline(always)]
fn cross(x: DVec3, dx: DVec3, y: DVec3, dy: DVec3) -> (DVec3, DVec3) {
    let ((xj, xk), (yj, yk)) = (after(x), after(y));
    let ((dxj, dxk), (dyj, dyk)) = (after(dx), after(dy));
    let (first, second) = (xj * yk, xk * yj);
    let rounding = (first.abs() + second.abs()) * gamma(3);
    let carried = xj.abs() * dyk + dxj * (yk.abs() + dyk) + xk.abs() * dyj + dxk * (yj.abs() + dyj);
    (first - second, rounding + carried)
}

/// `fl(x·y)` summed as `(x₀y₀ + x₁y₁) + x₂y₂`, and a bound on its distance from the exact `x*·y*`
/// for `x*`, `y*` within `x_err`, `y_err` of `x`, `y` (see the module docs).
#[inline(always)]
fn dot_error(x: DVec3, y: DVec3, x_err: DVec3, y_err: DVec3) -> (f64, f64) {
    let p = x * y;
    let partial = p.x + p.y;
    let sum = partial + p.z;
    let rounding = gamma(1) * (p.abs().element_sum() + partial.abs() + sum.abs());
    let carried = (x.abs() * y_err + x_err * (y.abs() + y_err)).element_sum();
    (sum, rounding + carried)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A head-on hit at an exactly representable `t` has error 0 and a bound of a few ulps of
    /// the depth; a reported `t` off by 1e-9 is bounded by at least that.
    #[test]
    fn the_bound_covers_a_moved_t_and_is_small_at_the_exact_one() {
        let tri = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from_array);
        let ray = NearRay::exact(DVec3::new(0.1, 0.2, 5.0), DVec3::new(0.0, 0.0, -2.0));
        let at = plane_error(&ray, &tri, 0.0, 2.5).unwrap();
        assert!(at < 1e-14, "{at}");
        let off = plane_error(&ray, &tri, 0.0, 2.5 + 1e-9).unwrap();
        assert!((1e-9..1.1e-9).contains(&off), "{off}");
    }

    /// The vertices' and the ray's bounds widen it by their first-order effect: vertices 1e-6
    /// off move the plane by up to about 1e-6 along the ray (a head-on ray of length 2: 5e-7
    /// in t), an origin 1e-6 off the same.
    #[test]
    fn vertex_and_ray_bounds_widen_it() {
        let tri = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from_array);
        let exact = NearRay::exact(DVec3::new(0.1, 0.2, 5.0), DVec3::new(0.0, 0.0, -2.0));
        let moved = plane_error(&exact, &tri, 1e-6, 2.5).unwrap();
        assert!((5e-7..1e-5).contains(&moved), "{moved}");
        let near = NearRay {
            origin_error: DVec3::splat(1e-6),
            ..exact
        };
        let shifted = plane_error(&near, &tri, 0.0, 2.5).unwrap();
        assert!((5e-7..1e-5).contains(&shifted), "{shifted}");
    }

    /// The bitwise check agrees with the comparisons on both sides of each end of the range,
    /// at zero, on subnormals, infinities and NaN, with either sign.
    #[test]
    fn the_bitwise_range_check_is_the_comparisons() {
        let ends = [
            0.0,
            f64::from_bits(1),
            LOW,
            HIGH,
            1.0,
            f64::MAX,
            f64::INFINITY,
        ];
        let mut values = vec![f64::NAN];
        for x in ends {
            values.extend([
                x,
                x.next_up(),
                x.next_down(),
                -x,
                -x.next_up(),
                -x.next_down(),
            ]);
        }
        let in_range = |x: f64| x == 0.0 || (LOW..=HIGH).contains(&x.abs());
        for x in values {
            assert_eq!(all_in_range([x]), in_range(x), "{x:e}");
            assert_eq!(all_in_range([1.0, x, 0.0]), in_range(x), "{x:e}");
        }
        assert!(all_in_range([0.0, -0.0, LOW, -HIGH, 1e-70, 3e70]));
    }

    /// A ray in the plane has no bound; numbers outside the standard model's range are left
    /// to the bounded recomputation.
    #[test]
    fn parallel_rays_are_unbounded_and_extremes_are_declined() {
        let tri = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from_array);
        let along = NearRay::exact(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(plane_error(&along, &tri, 0.0, 5.0), Some(f64::INFINITY));
        let tiny = tri.map(|v| v * 1e-80);
        let ray = NearRay::exact(DVec3::new(0.0, 0.0, 1e-79), DVec3::NEG_Z);
        assert_eq!(plane_error(&ray, &tiny, 0.0, 1e-79), None);
    }
}
