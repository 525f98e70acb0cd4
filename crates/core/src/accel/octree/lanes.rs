//! The per-ray set-up and the eight-wide node test, in f32 and conservative.
//!
//! # Why an f32 test cannot lose a hit
//! A lane's slab parameter on an axis with direction component `d ≠ 0` is `t = (P - o) · r`
//! with `r = 1/d`, computed as `P · r₃₂ + c` (one FMA, or a multiply and an add), where `P` is
//! the f32 plane (decoded exactly from its byte, see `super::wide`), `r₃₂` is `r` rounded to
//! f32 and `c` is `-o · r` moved by `ε` (down for the near plane, up for the far plane), then
//! rounded to f32. With `u = 2⁻²⁴`, `B` the largest coordinate magnitude of any stored plane
//! and `s = (B + |o|) · |r|`, the roundings of `r₃₂`, of the product and of the sum together
//! move the result by less than `4u · s`, and rounding `c` (at most `s + ε` in magnitude) by
//! less than `1.01u · s`, plus `2⁻¹⁴⁹` per rounding in the
//! subnormal range; so with `ε = 10u · s + 2⁻¹²⁰` the computed near parameter is below the
//! exact one and the computed far parameter above it. `ε` grows with `|o|`: a far origin gets
//! the slack its own rounding needs.
//!
//! NaN cannot arise: planes are finite, `r₃₂` and `c` are finite when the axis culls, and an
//! axis that cannot cull safely gets `r₃₂ = 0` and `c = ∓∞`, whose products are never `0 · ∞`.
//! That happens when `d = 0` (the axis is then tested by comparing the planes with the origin
//! rounded outward) and when `s > 2¹⁰⁰` or `|r| < 2⁻¹⁰⁰` (the axis then does not cull at all).
//! A lane is hit when `max(near₀, near₁, near₂, 0) <= min(far₀, far₁, far₂, t_best)` with
//! `t_best` the best hit rounded up to f32: equal parameters still reach the primitive tests.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use super::wide::{Wide, LIMIT};
use crate::accel::{f32_above, f32_below};
pub use crate::simd::Kernel;
use glam::DVec3;

/// The unit roundoff of f32, `2⁻²⁴`.
pub(super) const UNIT: f64 = 1.0 / 16777216.0;

/// The absolute part of the rounding bound, `2⁻¹²⁰`: far above the subnormal spacing.
pub(super) const TINY: f64 = 1.0 / (1u128 << 120) as f64;

/// A ray prepared for the node test.
#[derive(Debug, Clone, Copy)]
pub(super) struct Lanes {
    /// Per axis: true when the direction is negative there, so the near plane is the box's
    /// upper one.
    pub flip: [bool; 3],
    pub r: [f32; 3],
    pub c_near: [f32; 3],
    pub c_far: [f32; 3],
    /// On axes with `d = 0`, the origin rounded down and up; elsewhere -∞ and +∞.
    pub o_lo: [f32; 3],
    pub o_hi: [f32; 3],
    /// Some axis has `d = 0`: compare the planes with `o_lo`/`o_hi`.
    pub parallel: bool,
    /// No axis culls (a degenerate ray or tree): every occupied lane is entered.
    pub open: bool,
    /// Bit `a` set when the direction is negative on axis `a`: children in the order
    /// `j ^ octant` (`j = 0..8`) are front to back.
    pub octant: usize,
}

impl Lanes {
    /// Set-up for `origin + t · dir` in a tree whose planes are at most `scale` in magnitude
    /// (`scale` infinite: no axis culls). `dir` must have no -0.0 component. The packet
    /// set-up (`packet::Bundle::set`, and its AVX2 form four rays at a time) repeats these
    /// operations per axis and must stay the same.
    pub fn new(origin: DVec3, dir: DVec3, scale: f64) -> Lanes {
        let r = dir.recip();
        let s = (DVec3::splat(scale) + origin.abs()) * r.abs();
        let eps = s * (10.0 * UNIT) + DVec3::splat(TINY);
        let c = -origin * r;
        // False for d = 0 (s is then infinite or NaN) and for NaN.
        let culls = s.cmple(DVec3::splat(LIMIT)) & r.abs().cmpge(DVec3::splat(1.0 / LIMIT));
        let octant = dir.cmplt(DVec3::ZERO).bitmask() as usize;
        let mut lanes = Lanes {
            flip: [0, 1, 2].map(|axis| octant >> axis & 1 != 0),
            r: r.as_vec3().to_array(),
            c_near: (c - eps).as_vec3().to_array(),
            c_far: (c + eps).as_vec3().to_array(),
            o_lo: [f32::NEG_INFINITY; 3],
            o_hi: [f32::INFINITY; 3],
            parallel: false,
            open: false,
            octant,
        };
        if !culls.all() {
            lanes.without_culling(culls.bitmask(), origin, dir, scale);
        }
        lanes
    }

    /// Axes not in `culls` get `r = 0` and `c = ∓∞`; those with `d = 0` compare the planes
    /// with the origin instead (when the origin and the planes are finite).
    #[cold]
    fn without_culling(&mut self, culls: u32, origin: DVec3, dir: DVec3, scale: f64) {
        for axis in (0..3).filter(|a| culls & (1 << a) == 0) {
            self.r[axis] = 0.0;
            self.c_near[axis] = f32::NEG_INFINITY;
            self.c_far[axis] = f32::INFINITY;
            let o = origin[axis];
            if dir[axis] == 0.0 && o.is_finite() && scale.is_finite() {
                self.o_lo[axis] = f32_below(o);
                self.o_hi[axis] = f32_above(o);
                self.parallel = true;
            }
        }
        self.open = culls == 0 && !self.parallel;
    }
}

/// The result of one node test: bit `i` of `hit` for lane `i`, and per lane the entry and
/// exit parameters (meaningful for hit lanes only).
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(super) struct Tested {
    pub enter: [f32; 8],
    pub exit: [f32; 8],
    pub hit: u32,
}

/// The plane rows `(near, far)` of `axis` for `ray`.
#[inline(always)]
fn rows(ray: &Lanes, axis: usize) -> (usize, usize) {
    if ray.flip[axis] {
        (axis + 3, axis)
    } else {
        (axis, axis + 3)
    }
}

/// The portable kernel.
#[inline(always)]
pub(super) fn test_portable(node: &Wide, ray: &Lanes, t_best: f32) -> Tested {
    let plane = |row: usize, lane: usize| node.plane(row % 3, node.planes[row][lane]);
    let (enter, exit, hit) = slabs_portable(plane, ray, t_best);
    Tested {
        enter,
        exit,
        hit: hit & node.occupancy(),
    }
}

/// The conservative slab test of eight boxes, `plane(row, lane)` giving plane row `row` (rows
/// as in [`Wide::planes`]) of lane `lane`, exactly decoded: per lane the entry and exit
/// parameters and bit `lane` of the mask when the lane is entered before `t_best`. Lanes that
/// hold no box must be masked by the caller.
#[inline(always)]
pub(super) fn slabs_portable(
    plane: impl Fn(usize, usize) -> f32,
    ray: &Lanes,
    t_best: f32,
) -> ([f32; 8], [f32; 8], u32) {
    let mut enter = [0.0f32; 8];
    let mut exit = [t_best; 8];
    for axis in 0..3 {
        let (near, far) = rows(ray, axis);
        let (r, c_near, c_far) = (ray.r[axis], ray.c_near[axis], ray.c_far[axis]);
        for lane in 0..8 {
            let n = plane(near, lane) * r + c_near;
            let f = plane(far, lane) * r + c_far;
            enter[lane] = if n > enter[lane] { n } else { enter[lane] };
            exit[lane] = if f < exit[lane] { f } else { exit[lane] };
        }
    }
    let mut hit = 0;
    for lane in 0..8 {
        hit |= u32::from(enter[lane] <= exit[lane]) << lane;
    }
    if ray.parallel {
        for axis in 0..3 {
            for lane in 0..8 {
                let inside =
                    plane(axis, lane) <= ray.o_hi[axis] && plane(axis + 3, lane) >= ray.o_lo[axis];
                hit &= !(u32::from(!inside) << lane);
            }
        }
    }
    (enter, exit, hit)
}

/// The AVX2 kernel: per plane row, one FMA decodes the quantised planes and one computes
/// their slab parameters.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(super) unsafe fn test_avx2(node: &Wide, ray: &Lanes, t_best: f32) -> Tested {
    // SAFETY: this function's own requirement.
    let planes = |row: usize| unsafe { node.row_avx2(row) };
    // SAFETY: as above.
    let (enter, exit, mut hit) = unsafe { slabs_avx2(planes, ray, t_best) };
    // SAFETY: `children` is eight u32, the size of the unaligned load.
    let children = unsafe { _mm256_loadu_si256(node.children.as_ptr().cast()) };
    let empty = _mm256_cmpeq_epi32(children, _mm256_set1_epi32(-1));
    hit = _mm256_andnot_ps(_mm256_castsi256_ps(empty), hit);
    let mut out = Tested {
        enter: [0.0; 8],
        exit: [0.0; 8],
        hit: _mm256_movemask_ps(hit) as u32,
    };
    _mm256_store_ps(out.enter.as_mut_ptr(), enter);
    _mm256_store_ps(out.exit.as_mut_ptr(), exit);
    out
}

/// [`slabs_portable`] in AVX2 registers, `planes(row)` giving a decoded plane row: the entry
/// and exit parameters and the mask of lanes entered before `t_best` (all ones or zeros per
/// lane).
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
pub(super) unsafe fn slabs_avx2(
    planes: impl Fn(usize) -> __m256,
    ray: &Lanes,
    t_best: f32,
) -> (__m256, __m256, __m256) {
    let mut enter = _mm256_setzero_ps();
    let mut exit = _mm256_set1_ps(t_best);
    for axis in 0..3 {
        let (near, far) = rows(ray, axis);
        let r = _mm256_set1_ps(ray.r[axis]);
        let n = _mm256_fmadd_ps(planes(near), r, _mm256_set1_ps(ray.c_near[axis]));
        let f = _mm256_fmadd_ps(planes(far), r, _mm256_set1_ps(ray.c_far[axis]));
        enter = _mm256_max_ps(enter, n);
        exit = _mm256_min_ps(exit, f);
    }
    let mut hit = _mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit);
    if ray.parallel {
        for axis in 0..3 {
            let lo = _mm256_cmp_ps::<_CMP_LE_OQ>(planes(axis), _mm256_set1_ps(ray.o_hi[axis]));
            let hi = _mm256_cmp_ps::<_CMP_GE_OQ>(planes(axis + 3), _mm256_set1_ps(ray.o_lo[axis]));
            hit = _mm256_and_ps(hit, _mm256_and_ps(lo, hi));
        }
    }
    (enter, exit, hit)
}
