//! The error bound of the watertight triangle test ([`crate::geometry::triangle`]).
//!
//! # What is bounded
//! The exact ray `o + t·d` (its f64 numbers, or in an instance frame the exact image of the
//! world ray) against the exact triangle (its vertices, each within a per-component bound of the
//! stored ones). Translating by `o`, permuting so that `z` is the dominant direction axis and
//! shearing (`S = (d_x/d_z, d_y/d_z)`) are exact changes of coordinates in real arithmetic, so
//! the exact hit has barycentric weights `λᵢ = eᵢ*/D*` from the exact edge functions and
//! `t* = sz*·W*` with `W* = Σ eᵢ* zᵢ* / D*`, `D* = Σ eᵢ*`, `sz* = 1/d_z` and `zᵢ` the vertices'
//! unscaled `z` relative to `o`.
//!
//! # Derivation
//! The sheared coordinates and edge functions are recomputed here in [`Bounded`] arithmetic,
//! with the same operations in the same order as the test, so each comes with `|eᵢ − eᵢ*| ≤ Eᵢ`
//! and `|zᵢ − zᵢ*| ≤ Zᵢ`. Let `W̃ = Σ eᵢzᵢ / D` with `D = Σ eᵢ` in real arithmetic on the computed
//! values. Because `Σ eᵢ(zᵢ − W̃) = 0` exactly,
//!
//! `Σ eᵢ*(zᵢ* − W̃) = Σ (eᵢ* − eᵢ)(zᵢ* − W̃) + Σ eᵢ(zᵢ* − zᵢ)`, so
//! `|W* − W̃| ≤ [Σ Eᵢ(|zᵢ − W̃| + Zᵢ) + Σ |eᵢ| Zᵢ] / (|D| − Σ Eᵢ)`.
//!
//! This is first-order tight: an error in an edge function moves `t` only by its weight times the
//! vertex's offset `zᵢ − W̃` from the hit, not by `zᵢ` itself (a plain interval quotient of
//! `Σ eᵢzᵢ` by `Σ eᵢ` would lose the ratio of the distance to the triangle's size). `|zᵢ − W̃|` is
//! taken from the computed `W` plus its rounding `ω`; `|D| ≥ |det| − γ₂Σ|eᵢ|`. The last step,
//! from `W̃·sz` to the f64 `t = (Σ (eᵢ·sz)·zᵢ) / det`, is the rounding of two products and two sums
//! in the numerator (`γ₄ |sz| Σ|eᵢzᵢ|`), two sums in `det` (`γ₂ Σ|eᵢ|`) and the quotient (`γ₁|t|`).
//!
//! The bound is on `t` as recomputed here; a caller whose `t` came from elsewhere (the packet
//! test, or the plane fallback for slivers) adds the difference, which is exact to compute.

use super::bounded::{down, gamma, up, values3, BVec3, Bounded};
use super::Side;
use crate::geometry::triangle::WatertightRay;
use crate::simd::with_avx2;
use std::ops::{Div, Mul, Sub};

/// The bound of one ray/triangle pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangleBound {
    /// Where the exact ray passes the triangle: [`Side::Inside`] when every edge function has
    /// a certain sign, the same for all; [`Side::Outside`] when two have certain, opposite
    /// signs; [`Side::Edge`] when one may be zero.
    pub side: Side,
    /// `t` where the ray meets the triangle's plane, as the watertight test computes it, with a
    /// bound on its distance from the exact plane's `t` (`+∞` for a ray that may be parallel to
    /// the plane, or whose direction's dominant component may be zero).
    pub t: Bounded,
}

/// The bound for the ray `origin + t·dir` and the triangle `tri`, all with per-component
/// bounds on their distance from the exact values (compiled for AVX2 and FMA where the CPU has them,
/// [`with_avx2`]).
#[inline(always)]
pub fn bound(origin: &BVec3, dir: &BVec3, tri: &[BVec3; 3]) -> TriangleBound {
    with_avx2(
        #[inline(always)]
        || bound_here(origin, dir, tri),
    )
}

/// [`bound`], inlined into its caller.
#[inline(always)]
fn bound_here(origin: &BVec3, dir: &BVec3, tri: &[BVec3; 3]) -> TriangleBound {
    let axes = WatertightRay::new(values3(origin), values3(dir)).axes();
    let [kx, ky, kz] = axes;
    let one = Bounded::exact(1.0);
    let shear = [dir[kx].div(dir[kz]), dir[ky].div(dir[kz]), one.div(dir[kz])];
    let [a, b, c] = [
        sheared(&tri[0], origin, axes, &shear),
        sheared(&tri[1], origin, axes, &shear),
        sheared(&tri[2], origin, axes, &shear),
    ];
    let e = [edge(&c, &b), edge(&a, &c), edge(&b, &a)];
    let z = [a[2], b[2], c[2]];
    TriangleBound {
        side: side(&e),
        t: plane_t(&e, &z, shear[2]),
    }
}

/// Vertex `v` relative to `origin`, permuted to `axes` and sheared by `(s_x, s_y)`: the
/// watertight test's `(x − s_x z, y − s_y z, z)`. Functions, not closures, so that they inline
/// into [`with_avx2`]'s FMA code.
#[inline(always)]
fn sheared(v: &BVec3, origin: &BVec3, [kx, ky, kz]: [usize; 3], shear: &BVec3) -> BVec3 {
    let (x, y, z) = (
        v[kx].sub(origin[kx]),
        v[ky].sub(origin[ky]),
        v[kz].sub(origin[kz]),
    );
    [x.sub(shear[0].mul(z)), y.sub(shear[1].mul(z)), z]
}

/// The edge function `p_x q_y − p_y q_x` of two sheared vertices.
#[inline(always)]
fn edge(p: &BVec3, q: &BVec3) -> Bounded {
    p[0].mul(q[1]).sub(p[1].mul(q[0]))
}

/// Whether the exact ray certainly has no crossing with the triangle in `(0, limit]`, for an
/// exact ray and vertices within `placement` of the stored ones (per coordinate): a cheaper,
/// coarser test than [`bound`], to pass over most candidates. Three filters, cheapest first:
///
/// 1. **Depth.** A crossing's `t` is a convex combination of the vertices' `p_z / d_z` (the
///    barycentric weights of an interior hit are not negative), so all vertices behind the
///    origin or all beyond `limit`, each by more than `placement` and the rounding of `p_z`,
///    rule it out.
/// 2. **Sheared box.** With `X = |p_x| + |s_x·p_z| + ε_x` (`p` a vertex relative to the origin,
///    `s` the shear, `ε_x = placement·(1 + |s_x|)` what the vertex's own bound moves a sheared
///    coordinate), a sheared coordinate is within `γ₇X + ε_x` of its exact value (the rounding
///    of `p`, of `s`, of the product and of the difference; `8u` for `γ₇`). The exact ray is
///    the point `(0, 0)` of the sheared plane and a crossing a convex combination of the
///    vertices' sheared points, so all three certainly on one side of `x = 0` (or `y = 0`)
///    rule it out.
/// 3. **Edge functions.** An edge function `x_c y_b − y_c x_b` is within
///    `γ₁₇(X_c Y_b + Y_c X_b) + X_c ε_y + Y_b ε_x + Y_c ε_x + X_b ε_y + 2 ε_x ε_y` (expanding
///    the products of the bounds; `32u` for `γ₁₇`, and `2⁻³⁰` of slack for the second-order
///    terms). Two edge functions beyond it with opposite signs: a certain miss.
pub fn certainly_apart(
    ray: &WatertightRay,
    tri: &[glam::DVec3; 3],
    placement: f64,
    limit: f64,
) -> bool {
    let [_, _, kz] = ray.axes();
    let (shear, origin) = ray.shear_and_origin();
    let unit = super::bounded::UNIT;
    let depth = [
        tri[0][kz] - origin[kz],
        tri[1][kz] - origin[kz],
        tri[2][kz] - origin[kz],
    ];
    let margin = |p: f64| pad(placement + 2.0 * unit * p.abs());
    let behind = depth
        .iter()
        .all(|&p| p * shear.z < 0.0 && p.abs() > margin(p));
    let far = |p: f64| (p.abs() - margin(p)) * shear.z.abs() * (1.0 - 8.0 * unit);
    // Above the smallest normal number, each rounding of `far` is within a relative `u`.
    let floor = limit.max(f64::MIN_POSITIVE);
    let beyond = depth.iter().all(|&p| p * shear.z > 0.0 && far(p) > floor);
    if behind || beyond {
        return true;
    }
    let sheared = Sheared::new(ray, tri, placement);
    if one_side(&sheared.vertices, 0, sheared.ex, unit)
        || one_side(&sheared.vertices, 2, sheared.ey, unit)
    {
        return true;
    }
    sheared.edges().is_some_and(|e| opposite(&e))
}

/// Filter 3 of [`certainly_apart`] alone (what [`super::apart::apart_four`] computes four at
/// a time): whether two edge functions certainly have opposite signs.
pub(crate) fn edges_apart(ray: &WatertightRay, tri: &[glam::DVec3; 3], placement: f64) -> bool {
    let e = Sheared::new(ray, tri, placement).edges();
    e.is_some_and(|e| opposite(&e))
}

/// Whether two of the edge functions `e` (each with its bound) are beyond their bounds with
/// opposite signs.
#[inline(always)]
fn opposite(e: &[(f64, f64); 3]) -> bool {
    let positive = e.iter().any(|&(v, err)| v > err);
    let negative = e.iter().any(|&(v, err)| -v > err);
    positive && negative
}

/// Whether the exact ray certainly crosses the triangle's interior (not an edge or a vertex),
/// for an exact ray and vertices within `placement` of the stored ones (per coordinate): the
/// three edge functions of [`certainly_apart`]'s filter 3 each beyond their bound, all with
/// the same sign. Sound and a little coarser than [`bound`]'s [`Side::Inside`], for a few
/// dozen operations where that recomputes the test in bounded arithmetic; `false` means
/// "not known", not "outside".
pub fn certainly_inside(ray: &WatertightRay, tri: &[glam::DVec3; 3], placement: f64) -> bool {
    let Some(e) = Sheared::new(ray, tri, placement).edges() else {
        return false;
    };
    e.iter().all(|&(v, err)| v > err) || e.iter().all(|&(v, err)| -v > err)
}

/// A triangle sheared into the frame of a [`WatertightRay`] in f64, per vertex its sheared
/// `x`, a bound `X` on its magnitude, its sheared `y` and `Y` (see [`certainly_apart`], filter
/// 2), with `ε_x`, `ε_y`, what the vertices' own bound moves a sheared coordinate.
struct Sheared {
    vertices: [[f64; 4]; 3],
    ex: f64,
    ey: f64,
}

impl Sheared {
    /// `tri`, with vertices within `placement` of the stored ones, in `ray`'s frame.
    #[inline(always)]
    fn new(ray: &WatertightRay, tri: &[glam::DVec3; 3], placement: f64) -> Sheared {
        let [kx, ky, kz] = ray.axes();
        let (shear, origin) = ray.shear_and_origin();
        let (ex, ey) = (
            pad(placement * (1.0 + shear.x.abs())),
            pad(placement * (1.0 + shear.y.abs())),
        );
        // Written out: no array `map`, which the compiler leaves as calls here.
        let shear_one = |v: glam::DVec3| {
            let p = (v - origin).to_array();
            let (m, n) = (shear.x * p[kz], shear.y * p[kz]);
            [
                p[kx] - m,
                p[kx].abs() + m.abs() + ex,
                p[ky] - n,
                p[ky].abs() + n.abs() + ey,
            ]
        };
        Sheared {
            vertices: [shear_one(tri[0]), shear_one(tri[1]), shear_one(tri[2])],
            ex,
            ey,
        }
    }

    /// The three edge functions, each with its bound ([`certainly_apart`], filter 3); `None`
    /// when one is not finite.
    #[inline(always)]
    fn edges(&self) -> Option<[(f64, f64); 3]> {
        let (ex, ey) = (self.ex, self.ey);
        let [a, b, c] = &self.vertices;
        let edge = |p: &[f64; 4], q: &[f64; 4]| {
            let value = p[0] * q[2] - p[2] * q[0];
            let first = EDGE_ROUNDING * (p[1] * q[3] + p[3] * q[1]);
            let moved = p[1] * ey + q[3] * ex + p[3] * ex + q[1] * ey + 2.0 * ex * ey;
            // Twice: the slack for the second-order terms, then the evaluation's roundings.
            (value, pad(pad(first + moved)))
        };
        let e = [edge(c, b), edge(a, c), edge(b, a)];
        let finite = e.iter().all(|(v, err)| v.is_finite() && err.is_finite());
        finite.then_some(e)
    }
}

/// `x ≥ 0`, a bound of [`certainly_apart`] evaluated in a few f64 operations, raised past
/// their roundings: each is at most a relative `u` (with an absolute `2⁻¹⁰⁷⁴` when the result
/// is subnormal), far less than the factor `1 + 2⁻³⁰` and the smallest normal number added.
/// One multiply and one add where [`up`] would take a step per operation.
#[inline]
fn pad(x: f64) -> f64 {
    x * PAD + f64::MIN_POSITIVE
}

/// The factor of [`pad`], `1 + 2⁻³⁰`.
pub(super) const PAD: f64 = 1.0 + 1.0 / (1u64 << 30) as f64;

/// `γ₁₇` of filter 3 of [`certainly_apart`], as `32u`.
pub(super) const EDGE_ROUNDING: f64 = 32.0 * super::bounded::UNIT;

/// Whether the sheared coordinate `at` (`0` for `x`, `2` for `y`; its magnitude bound next to
/// it) of all three vertices is certainly positive, or certainly negative (filter 2 of
/// [`certainly_apart`]; `moved` is the vertices' own bound in that coordinate).
fn one_side(sheared: &[[f64; 4]; 3], at: usize, moved: f64, unit: f64) -> bool {
    let error = |s: &[f64; 4]| pad(8.0 * unit * s[at + 1] + moved);
    let positive = sheared.iter().all(|s| s[at] > error(s));
    let negative = sheared.iter().all(|s| -s[at] > error(s));
    // NaN coordinates fail both comparisons: no conclusion.
    positive || negative
}

/// The side from the edge functions' signs.
fn side(e: &[Bounded; 3]) -> Side {
    let positive = e.iter().any(|f| f.sign_certain() && f.value > 0.0);
    let negative = e.iter().any(|f| f.sign_certain() && f.value < 0.0);
    if positive && negative {
        Side::Outside
    } else if e.iter().all(|f| f.sign_certain()) {
        Side::Inside
    } else {
        Side::Edge
    }
}

/// `t` from the edge functions `e`, the vertices' unscaled `z` and the scale `sz = 1/d_z`, as
/// the test computes it, with the bound of the module docs.
#[inline(always)]
fn plane_t(e: &[Bounded; 3], z: &[Bounded; 3], sz: Bounded) -> Bounded {
    let det = e[0].value + e[1].value + e[2].value;
    let scaled = |i: usize| e[i].value * sz.value * z[i].value;
    let t = (scaled(0) + scaled(1) + scaled(2)) / det;
    let unbounded = Bounded::new(t, f64::INFINITY);
    let sum_e = up(e.iter().map(|f| f.value.abs()).sum());
    let sum_ez = up((0..3).map(|i| (e[i].value * z[i].value).abs()).sum());
    let d_low = down(det.abs() - up(gamma(2) * sum_e));
    let sum_err = up(e.iter().map(|f| f.error).sum());
    let d_star_low = down(d_low - sum_err);
    if d_star_low.is_nan() || d_star_low <= 0.0 || !t.is_finite() || !sz.error.is_finite() {
        return unbounded;
    }
    // |W̃| ≤ Σ|eᵢzᵢ| / |D|; the computed W and its distance ω from W̃.
    let w_abs = up(sum_ez / d_low);
    let w = (e[0].value * z[0].value + e[1].value * z[1].value + e[2].value * z[2].value) / det;
    let omega = up((gamma(3) * sum_ez + gamma(2) * sum_e * w_abs) / d_low + gamma(1) * w.abs());
    let spread: f64 = (0..3)
        .map(|i| {
            let offset = up((z[i].value - w).abs() + omega + z[i].error);
            up(e[i].error * offset + e[i].value.abs() * z[i].error)
        })
        .sum();
    let dw = up(up(spread) / d_star_low);
    let s_abs = sz.value.abs();
    let exact_part = up(dw * up(s_abs + sz.error) + up(w_abs + dw) * sz.error);
    let rounding = up(up(gamma(4) * s_abs * sum_ez + s_abs * w_abs * gamma(2) * sum_e) / d_low);
    Bounded::new(t, up(exact_part + rounding + gamma(1) * t.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bound::bounded::exact3;
    use glam::DVec3;

    fn tri(points: [[f64; 3]; 3]) -> [BVec3; 3] {
        points.map(|p| exact3(DVec3::from_array(p)))
    }

    /// A head-on hit at an exactly representable t: zero error there, and a tiny bound.
    #[test]
    fn head_on_hits_are_tight_and_inside() {
        let t = tri([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]);
        let o = exact3(DVec3::new(0.1, 0.2, 5.0));
        let d = exact3(DVec3::new(0.0, 0.0, -2.0));
        let b = bound(&o, &d, &t);
        assert_eq!(b.side, Side::Inside);
        assert_eq!(b.t.value, 2.5);
        assert!(b.t.error > 0.0 && b.t.error < 1e-14, "{b:?}");
    }

    /// A ray through a vertex is an edge case; one beside the triangle is certainly outside.
    #[test]
    fn vertices_are_edges_and_misses_are_outside() {
        let t = tri([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]);
        let d = exact3(DVec3::NEG_Z);
        let through = bound(&exact3(DVec3::new(0.0, 1.0, 5.0)), &d, &t);
        assert_eq!(through.side, Side::Edge);
        let beside = bound(&exact3(DVec3::new(3.0, 0.0, 5.0)), &d, &t);
        assert_eq!(beside.side, Side::Outside);
    }

    /// The coarse pre-test rules out triangles behind the origin, beyond the limit or well
    /// beside the ray, and never one the ray crosses or passes within its bounds.
    #[test]
    fn the_coarse_test_passes_over_only_what_is_apart() {
        let at = |z: f64| [[-1.0, -1.0, z], [1.0, -1.0, z], [0.0, 1.0, z]].map(DVec3::from_array);
        let ray = WatertightRay::new(DVec3::new(0.1, 0.2, 5.0), DVec3::NEG_Z);
        assert!(
            certainly_apart(&ray, &at(6.0), 0.0, f64::INFINITY),
            "behind"
        );
        assert!(certainly_apart(&ray, &at(0.0), 0.0, 4.0), "beyond t = 4");
        assert!(
            !certainly_apart(&ray, &at(0.0), 0.0, 5.0),
            "crossed at t = 5"
        );
        assert!(
            !certainly_apart(&ray, &at(0.0), 0.0, f64::INFINITY),
            "crossed"
        );
        let beside = WatertightRay::new(DVec3::new(3.0, 0.0, 5.0), DVec3::NEG_Z);
        assert!(
            certainly_apart(&beside, &at(0.0), 0.0, f64::INFINITY),
            "beside"
        );
        // 1e-3 beside the edge x + y = 1 (7e-4 away): apart for exact vertices, not for
        // vertices that may be off by 1e-2.
        let near = WatertightRay::new(DVec3::new(0.5 + 1e-3, 0.5, 5.0), DVec3::NEG_Z);
        let edge = [[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from_array);
        assert!(!certainly_apart(&near, &edge, 1e-2, f64::INFINITY));
        assert!(certainly_apart(&near, &edge, 0.0, f64::INFINITY));
        // 1e-3 past the vertex (1, 0), the largest x: the sheared box is beside the ray
        // for exact vertices; vertices that may be 1e-2 off may reach it.
        let past = WatertightRay::new(DVec3::new(1.0 + 1e-3, 0.0, 5.0), DVec3::NEG_Z);
        assert!(certainly_apart(&past, &edge, 0.0, f64::INFINITY));
        assert!(!certainly_apart(&past, &edge, 1e-2, f64::INFINITY));
    }

    /// The cheap interior test is sound where the bounded recomputation can tell, and says
    /// "not known" on edges, at vertices and within the vertices' bound of an edge; on
    /// interior rays of an ordinary triangle it agrees with the recomputation.
    #[test]
    fn the_cheap_interior_test_finds_interiors_and_not_edges() {
        let corners = [[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let stored = corners.map(DVec3::from_array);
        let down = |x: f64, y: f64| (DVec3::new(x, y, 5.0), DVec3::new(0.01, -0.02, -1.0));
        let inside = |(o, d): (DVec3, DVec3), placement: f64| {
            certainly_inside(&WatertightRay::new(o, d), &stored, placement)
        };
        assert!(inside(down(0.0, 0.1), 0.0));
        assert!(
            !inside(down(0.0, 0.1), 0.5),
            "vertices may move past the ray"
        );
        let (o, d) = down(0.0, 0.0);
        let on_vertex = stored[1] - d * (stored[1].z - o.z) / d.z;
        assert!(!inside((on_vertex, d), 0.0), "through a vertex");
        assert!(!inside(down(3.0, 0.0), 0.0), "outside");
        let mut agree = 0;
        for i in 0..2000 {
            let (x, y) = (
                -1.2 + 2.4 * f64::from(i % 50) / 49.0,
                f64::from(i / 50) / 39.0,
            );
            let ray = down(x - 0.5 * y, y - 0.5);
            let full = bound(&exact3(ray.0), &exact3(ray.1), &tri(corners)).side;
            if inside(ray, 0.0) {
                assert_eq!(full, Side::Inside, "ray {ray:?}");
                agree += 1;
            } else {
                assert_ne!(full, Side::Inside, "ray {ray:?}: a plain interior hit");
            }
        }
        assert!(agree > 400, "{agree} interior rays");
    }

    /// A ray in the triangle's plane has no bounded t.
    #[test]
    fn parallel_rays_are_unbounded() {
        let t = tri([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]);
        let b = bound(&exact3(DVec3::new(-5.0, 0.0, 0.0)), &exact3(DVec3::X), &t);
        assert_eq!(b.t.error, f64::INFINITY);
    }
}
