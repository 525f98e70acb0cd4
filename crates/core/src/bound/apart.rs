//! The edge-function filter of [`super::triangle::certainly_apart`] (its filter 3), four
//! triangles at a time: the `certain` AOV's candidates are mostly a hit's neighbours, which
//! the exact ray passes beside, and this passes over them for a few dozen AVX2 operations
//! per four, where the one-triangle filter takes some 275 instructions each.
//!
//! [`apart_four`] computes exactly the values of the one-triangle filter, operation for
//! operation (separate multiplies and adds: Rust fuses neither, and the AVX2 kernel uses no
//! fused instruction either), so a lane it reports apart is one that
//! [`super::triangle::certainly_apart`] reports apart too, by the same argument (written
//! there). The other lanes say nothing: the caller weighs them one by one.
//!
//! Its AVX2 pieces ([`margins`], [`sheared`], [`apart_lanes`]) also serve the search's packet
//! pre-filter, which has the sheared vertices of every tested pair already
//! ([`crate::geometry::triangle_packet::WatertightPacket::candidates_apart`]).

use super::triangle::edges_apart;
use crate::geometry::triangle::WatertightRay;
#[cfg(target_arch = "x86_64")]
use crate::simd::per_axes;
use crate::simd::Kernel;
use glam::DVec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Triangles weighed together by [`apart_four`].
pub const LANES: usize = 4;

/// Of the triangles `tris[i]` with bit `i` of `active` set (each with its vertices within
/// `placement[i]` of the stored ones, per coordinate), those whose edge functions certainly
/// have opposite signs for the exact ray `ray`: the exact ray misses them (bit `i` set). By
/// `kernel`; every kernel gives the same bits.
pub fn apart_four(
    ray: &WatertightRay,
    kernel: Kernel,
    tris: &[[DVec3; 3]; LANES],
    placement: &[f64; LANES],
    active: u32,
) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if kernel == Kernel::Avx2 {
        // SAFETY: `Kernel::Avx2` is only chosen where the CPU has AVX2.
        return unsafe { apart_avx2(ray, tris, placement) } & active;
    }
    let _ = kernel;
    apart_portable(ray, tris, placement, active)
}

/// [`apart_four`] one triangle after the other, by the one-triangle filter itself.
fn apart_portable(
    ray: &WatertightRay,
    tris: &[[DVec3; 3]; LANES],
    placement: &[f64; LANES],
    active: u32,
) -> u32 {
    (0..LANES)
        .filter(|&i| active & (1 << i) != 0 && edges_apart(ray, &tris[i], placement[i]))
        .fold(0, |mask, i| mask | 1 << i)
}

/// [`apart_four`] in AVX2 registers, one instance per axis permutation.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn apart_avx2(
    ray: &WatertightRay,
    tris: &[[DVec3; 3]; LANES],
    placement: &[f64; LANES],
) -> u32 {
    per_axes!(ray.axes(), |KX, KY, KZ| apart_avx2_in::<KX, KY, KZ>(
        ray, tris, placement
    ))
}

/// A sheared vertex per lane: `x`, its magnitude bound `X`, `y`, `Y` (see
/// [`super::triangle::certainly_apart`], filter 2).
#[cfg(target_arch = "x86_64")]
pub type Sheared4 = [__m256d; 4];

/// [`apart_avx2`] for the axis permutation `[KX, KY, KZ]`.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn apart_avx2_in<const KX: usize, const KY: usize, const KZ: usize>(
    ray: &WatertightRay,
    tris: &[[DVec3; 3]; LANES],
    placement: &[f64; LANES],
) -> u32 {
    let (shear, origin) = ray.shear_and_origin();
    let (splat, shear) = (|x: f64| _mm256_set1_pd(x), shear_lanes(shear));
    // SAFETY: four f64 in `placement`.
    let moved = margins(unsafe { _mm256_loadu_pd(placement.as_ptr()) }, shear);
    let vertex = |j: usize| {
        let coordinate = |k: usize| {
            let lane = |i: usize| tris[i][j][k];
            let v = _mm256_set_pd(lane(3), lane(2), lane(1), lane(0));
            _mm256_sub_pd(v, splat(origin[k]))
        };
        let p = [coordinate(KX), coordinate(KY), coordinate(KZ)];
        sheared(p, shear, moved)
    };
    let apart = apart_lanes(&[vertex(0), vertex(1), vertex(2)], moved);
    _mm256_movemask_pd(apart) as u32
}

/// The shear `(s_x, s_y)` of one ray in every lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn shear_lanes(shear: DVec3) -> [__m256d; 2] {
    [_mm256_set1_pd(shear.x), _mm256_set1_pd(shear.y)]
}

/// `(ε_x, ε_y)` per lane: what the vertices' own bound `placement` moves a sheared coordinate
/// (`pad(placement·(1 + |s|))`, as `Sheared::new` has it).
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub unsafe fn margins(placement: __m256d, [sx, sy]: [__m256d; 2]) -> [__m256d; 2] {
    let one = _mm256_set1_pd(1.0);
    let scaled = |s| _mm256_mul_pd(placement, _mm256_add_pd(one, abs(s)));
    [pad(scaled(sx)), pad(scaled(sy))]
}

/// A vertex `p` (relative to the ray's origin, permuted) sheared by `(s_x, s_y)` with its
/// magnitude bounds, as `Sheared::new` computes them.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub unsafe fn sheared(
    [px, py, pz]: [__m256d; 3],
    [sx, sy]: [__m256d; 2],
    [ex, ey]: [__m256d; 2],
) -> Sheared4 {
    let (m, n) = (_mm256_mul_pd(sx, pz), _mm256_mul_pd(sy, pz));
    [
        _mm256_sub_pd(px, m),
        _mm256_add_pd(_mm256_add_pd(abs(px), abs(m)), ex),
        _mm256_sub_pd(py, n),
        _mm256_add_pd(_mm256_add_pd(abs(py), abs(n)), ey),
    ]
}

/// The lanes (all bits set) whose triangle `[a, b, c]` (sheared vertices) has two edge
/// functions beyond their bounds with opposite signs, as `Sheared::edges` and
/// `certainly_apart`'s filter 3 decide it; `(ε_x, ε_y)` from [`margins`].
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub unsafe fn apart_lanes(vertices: &[Sheared4; 3], moved: [__m256d; 2]) -> __m256d {
    edge_lanes(vertices, moved)[0]
}

/// [`apart_lanes`], then the lanes whose three edge functions are all beyond their bounds
/// with one sign: the exact ray crosses the exact triangle's interior, as
/// `certainly_inside` decides it from the same values.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
pub unsafe fn edge_lanes([a, b, c]: &[Sheared4; 3], [ex, ey]: [__m256d; 2]) -> [__m256d; 2] {
    let splat = |x: f64| _mm256_set1_pd(x);
    // The edge function `x_p y_q − y_p x_q` and its bound, as `Sheared::edges` has them.
    let edge = |p: &Sheared4, q: &Sheared4| {
        let value = _mm256_sub_pd(_mm256_mul_pd(p[0], q[2]), _mm256_mul_pd(p[2], q[0]));
        let magnitude = _mm256_add_pd(_mm256_mul_pd(p[1], q[3]), _mm256_mul_pd(p[3], q[1]));
        let first = _mm256_mul_pd(splat(super::triangle::EDGE_ROUNDING), magnitude);
        let mut moved = _mm256_add_pd(_mm256_mul_pd(p[1], ey), _mm256_mul_pd(q[3], ex));
        moved = _mm256_add_pd(moved, _mm256_mul_pd(p[3], ex));
        moved = _mm256_add_pd(moved, _mm256_mul_pd(q[1], ey));
        moved = _mm256_add_pd(moved, _mm256_mul_pd(_mm256_mul_pd(splat(2.0), ex), ey));
        let error = pad(pad(_mm256_add_pd(first, moved)));
        let finite = |x| _mm256_cmp_pd::<_CMP_LT_OQ>(abs(x), splat(f64::INFINITY));
        let negated = _mm256_xor_pd(value, splat(-0.0));
        (
            _mm256_and_pd(finite(value), finite(error)),
            _mm256_cmp_pd::<_CMP_GT_OQ>(value, error),
            _mm256_cmp_pd::<_CMP_GT_OQ>(negated, error),
        )
    };
    let [(f0, p0, n0), (f1, p1, n1), (f2, p2, n2)] = [edge(c, b), edge(a, c), edge(b, a)];
    let finite = _mm256_and_pd(_mm256_and_pd(f0, f1), f2);
    let positive = _mm256_or_pd(_mm256_or_pd(p0, p1), p2);
    let negative = _mm256_or_pd(_mm256_or_pd(n0, n1), n2);
    let all_positive = _mm256_and_pd(_mm256_and_pd(p0, p1), p2);
    let all_negative = _mm256_and_pd(_mm256_and_pd(n0, n1), n2);
    [
        _mm256_and_pd(finite, _mm256_and_pd(positive, negative)),
        _mm256_and_pd(finite, _mm256_or_pd(all_positive, all_negative)),
    ]
}

/// `|x|` per lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn abs(x: __m256d) -> __m256d {
    _mm256_andnot_pd(_mm256_set1_pd(-0.0), x)
}

/// `pad` of `bound::triangle` per lane: `x·(1 + 2⁻³⁰) + 2⁻¹⁰²²`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn pad(x: __m256d) -> __m256d {
    let grown = _mm256_mul_pd(x, _mm256_set1_pd(super::triangle::PAD));
    _mm256_add_pd(grown, _mm256_set1_pd(f64::MIN_POSITIVE))
}

#[cfg(test)]
mod tests;
