//! Packets: eight rays whose directions share an octant traverse the octree together.
//!
//! Each node is fetched once for the packet, and each of its children is tested against all
//! eight rays at once (SIMD across the rays, where a single ray's test is SIMD across the
//! children). A child is pushed with the rays that enter it and their entry parameters; a
//! popped child goes on with those of its rays whose entry does not lie beyond their own best
//! hit, and a leaf is handed to each such ray in turn.
//!
//! Every ray gets exactly its single-ray answer: its slab parameters are computed from the
//! same exactly decoded planes with the same conservative set-up ([`super::lanes`], whose rounding
//! bound covers a multiply and an add as well as an FMA), so a child that holds a ray's hit is
//! never culled for it; the shared front-to-back order is exact for every direction in the
//! octant; and the boundary-trap rule is applied per ray.

use super::lanes::{Kernel, Lanes, TINY, UNIT};
use super::layout::Layout;
use super::leaf;
use super::traverse::{self, Unobserved, STACK};
use super::wide::LIMIT;
use super::wide::{Wide, LEAF};
use crate::accel::{f32_above, set_bits as bits};
use glam::DVec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;
use std::mem::MaybeUninit;

/// Rays in a packet ([`crate::simd::PACKET`]).
pub const WIDTH: usize = crate::simd::PACKET;

/// Eight rays set up for the packet test: per axis, one value per ray.
#[derive(Debug, Clone, Copy)]
pub(super) struct Bundle {
    r: [[f32; WIDTH]; 3],
    c_near: [[f32; WIDTH]; 3],
    c_far: [[f32; WIDTH]; 3],
    /// Per axis: the near plane is the box's upper one (the directions are negative).
    flip: [bool; 3],
    /// The shared octant: bit `a` set when the directions are negative on axis `a`.
    octant: usize,
}

impl Bundle {
    /// The rays `origins[i] + t · dirs[i]` as one packet in a tree whose planes are at most
    /// `scale` in magnitude, or `None` when their directions lie in different octants or some
    /// ray needs the single-ray test's special cases (an axis that cannot cull, such as a
    /// direction component of zero). Each ray's values are `Lanes::new`'s, by the same
    /// operations, computed axis by axis over the eight rays so that they vectorise. (One
    /// per-axis function shared by both was measured: the single-ray set-up then no longer
    /// vectorised, +6 % instructions per incoherent ray; so the two keep their own loops.)
    #[cfg(test)]
    pub fn new(origins: &[DVec3; WIDTH], dirs: &[DVec3; WIDTH], scale: f64) -> Option<Bundle> {
        let mut bundle = Bundle::EMPTY;
        bundle.set(origins, dirs, scale).then_some(bundle)
    }

    /// No rays: [`Bundle::set`] fills it.
    const EMPTY: Bundle = Bundle {
        r: [[0.0; WIDTH]; 3],
        c_near: [[0.0; WIDTH]; 3],
        c_far: [[0.0; WIDTH]; 3],
        flip: [false; 3],
        octant: 0,
    };

    /// [`Bundle::new`] in place (a returned bundle was copied twice, some 130 instructions a
    /// packet): false when the rays cannot go as one packet.
    #[inline(always)]
    fn set(&mut self, origins: &[DVec3; WIDTH], dirs: &[DVec3; WIDTH], scale: f64) -> bool {
        let bundle = self;
        for axis in 0..3 {
            let (mut culls, mut negative) = (true, 0u32);
            for i in 0..WIDTH {
                let (o, d) = (origins[i][axis], dirs[i][axis] + 0.0);
                let r = 1.0 / d;
                let s = (scale + o.abs()) * r.abs();
                let eps = s * (10.0 * UNIT) + TINY;
                let c = -o * r;
                // False for d = 0 (s is then infinite or NaN) and for NaN.
                culls &= s <= LIMIT && r.abs() >= 1.0 / LIMIT;
                negative |= u32::from(d < 0.0) << i;
                bundle.r[axis][i] = r as f32;
                bundle.c_near[axis][i] = (c - eps) as f32;
                bundle.c_far[axis][i] = (c + eps) as f32;
            }
            if !culls || (negative != 0 && negative != (1 << WIDTH) - 1) {
                return false;
            }
            bundle.flip[axis] = negative != 0;
            bundle.octant |= usize::from(negative != 0) << axis;
        }
        true
    }

    /// [`Bundle::set`] four rays per AVX2 register. Its operations are the scalar loop's, one
    /// by one (IEEE division, products, sums and the rounding to f32 give the same bits in
    /// either unit; nothing is fused), so the values are the same bit for bit.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn set_avx2(
        &mut self,
        origins: &[DVec3; WIDTH],
        dirs: &[DVec3; WIDTH],
        scale: f64,
    ) -> bool {
        let zero = _mm256_setzero_pd();
        let sign = _mm256_set1_pd(-0.0);
        let abs = |x| _mm256_andnot_pd(sign, x);
        let all = (1u32 << WIDTH) - 1;
        for axis in 0..3 {
            let (mut culls, mut negative) = (0u32, 0u32);
            for half in 0..WIDTH / 4 {
                let at = 4 * half;
                let gather = |v: &[DVec3; WIDTH]| {
                    _mm256_set_pd(
                        v[at + 3][axis],
                        v[at + 2][axis],
                        v[at + 1][axis],
                        v[at][axis],
                    )
                };
                let (o, d) = (gather(origins), _mm256_add_pd(gather(dirs), zero));
                let r = _mm256_div_pd(_mm256_set1_pd(1.0), d);
                let s = _mm256_mul_pd(_mm256_add_pd(_mm256_set1_pd(scale), abs(o)), abs(r));
                let eps = _mm256_add_pd(
                    _mm256_mul_pd(s, _mm256_set1_pd(10.0 * UNIT)),
                    _mm256_set1_pd(TINY),
                );
                let c = _mm256_mul_pd(_mm256_xor_pd(o, sign), r);
                let cull = _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_LE_OQ>(s, _mm256_set1_pd(LIMIT)),
                    _mm256_cmp_pd::<_CMP_GE_OQ>(abs(r), _mm256_set1_pd(1.0 / LIMIT)),
                );
                culls |= (_mm256_movemask_pd(cull) as u32) << at;
                negative |= (_mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(d, zero)) as u32) << at;
                let store = |row: &mut [f32; WIDTH], x| {
                    // SAFETY: `at + 4 <= WIDTH`: four f32 within the row.
                    unsafe { _mm_storeu_ps(row.as_mut_ptr().add(at), _mm256_cvtpd_ps(x)) }
                };
                store(&mut self.r[axis], r);
                store(&mut self.c_near[axis], _mm256_sub_pd(c, eps));
                store(&mut self.c_far[axis], _mm256_add_pd(c, eps));
            }
            if culls != all || (negative != 0 && negative != all) {
                return false;
            }
            self.flip[axis] = negative != 0;
            self.octant |= usize::from(negative != 0) << axis;
        }
        true
    }

    /// The portable packet test: for every lane of `node`, the rays (bit `i` for ray `i`)
    /// that enter its box before their `t_best`, and their entry parameters.
    #[inline(always)]
    pub(super) fn test_portable(&self, node: &Wide, t_best: &[f32; WIDTH], out: &mut Tested) {
        out.hit = [0; 8];
        for lane in bits(node.occupancy()) {
            let mut enter = [0.0f32; WIDTH];
            let mut exit = *t_best;
            for axis in 0..3 {
                let (lo, hi) = (node.planes[axis][lane], node.planes[axis + 3][lane]);
                let (near, far) = if self.flip[axis] { (hi, lo) } else { (lo, hi) };
                let (near, far) = (node.plane(axis, near), node.plane(axis, far));
                let (r, c_near, c_far) = (&self.r[axis], &self.c_near[axis], &self.c_far[axis]);
                for i in 0..WIDTH {
                    let n = near * r[i] + c_near[i];
                    let f = far * r[i] + c_far[i];
                    enter[i] = if n > enter[i] { n } else { enter[i] };
                    exit[i] = if f < exit[i] { f } else { exit[i] };
                }
            }
            out.hit[lane] = (0..WIDTH).fold(0, |m, i| m | u32::from(enter[i] <= exit[i]) << i);
            out.enter[lane] = enter;
        }
    }

    /// The AVX2 packet test: the node's planes decoded once, near and far per axis, then per
    /// lane one FMA per plane row across the eight rays.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(super) unsafe fn test_avx2(&self, node: &Wide, t_best: &[f32; WIDTH], out: &mut Tested) {
        let (mut near, mut far) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
        for axis in 0..3 {
            // SAFETY: the CPU requirement is this function's own.
            let (lo, hi) = unsafe { (node.row_avx2(axis), node.row_avx2(axis + 3)) };
            let (n, f) = if self.flip[axis] { (hi, lo) } else { (lo, hi) };
            // SAFETY: each row is eight f32.
            unsafe {
                _mm256_storeu_ps(near[axis].as_mut_ptr(), n);
                _mm256_storeu_ps(far[axis].as_mut_ptr(), f);
            }
        }
        // SAFETY: each row is eight f32.
        let load = |row: &[f32; WIDTH]| unsafe { _mm256_loadu_ps(row.as_ptr()) };
        let r = self.r.each_ref().map(load);
        let c_near = self.c_near.each_ref().map(load);
        let c_far = self.c_far.each_ref().map(load);
        let t_best = load(t_best);
        out.hit = [0; 8];
        for lane in bits(node.occupancy()) {
            let mut enter = _mm256_setzero_ps();
            let mut exit = t_best;
            for axis in 0..3 {
                let n = _mm256_broadcast_ss(&near[axis][lane]);
                let f = _mm256_broadcast_ss(&far[axis][lane]);
                let n = _mm256_fmadd_ps(n, r[axis], c_near[axis]);
                let f = _mm256_fmadd_ps(f, r[axis], c_far[axis]);
                enter = _mm256_max_ps(enter, n);
                exit = _mm256_min_ps(exit, f);
            }
            out.hit[lane] = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(enter, exit)) as u32;
            // SAFETY: `out.enter[lane]` is eight f32.
            unsafe { _mm256_storeu_ps(out.enter[lane].as_mut_ptr(), enter) };
        }
    }
}

/// The result of a packet test, per lane of the node: the rays that enter its box, and
/// their entry parameters.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Tested {
    pub hit: [u32; 8],
    pub enter: [[f32; WIDTH]; 8],
}

/// A child waiting on the stack: its reference, the rays that enter it, their entries.
#[derive(Debug, Clone, Copy)]
struct Entry {
    child: u32,
    rays: u32,
    enter: [f32; WIDTH],
}

/// Visits, for each ray `origins[i] + t · dirs[i]` of a packet, the leaves it may reach before
/// `limits[i]`, front to back, in a tree whose planes are at most `scale` in magnitude;
/// `visit(rays, refs, reach, limits)` gets the rays that reach the leaf (bit `i` for ray `i`),
/// up to eight of the leaf's primitive indices at a time, for each of them the rays that may
/// hit it there (the leaf filter, module `leaf`), and the rays' limits, and lowers the limits
/// of those rays to their best hits so far. Returns false, having visited nothing, when the rays cannot go as one
/// packet ([`Bundle::set`]).
pub(super) fn run<F>(
    layout: &Layout,
    kernel: Kernel,
    origins: &[DVec3; WIDTH],
    dirs: &[DVec3; WIDTH],
    scale: f64,
    limits: [f64; WIDTH],
    visit: F,
) -> bool
where
    F: FnMut(u32, &[u32], &[u32], &mut [f64; WIDTH]),
{
    let rays = (origins, dirs, scale);
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Kernel::Avx2` is only chosen where `Kernel::available` said so.
        Kernel::Avx2 => unsafe { run_avx2(layout, rays, limits, visit) },
        _ => run_with::<false, F>(layout, rays, limits, visit),
    }
}

/// A packet's origins, directions and the tree's plane magnitude, as [`run`] takes them.
type Rays<'r> = (&'r [DVec3; WIDTH], &'r [DVec3; WIDTH], f64);

/// [`run_with`] compiled for AVX2 and FMA, so that the eight rays' loops use eight-wide
/// registers.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_avx2<F>(layout: &Layout, rays: Rays, limits: [f64; WIDTH], visit: F) -> bool
where
    F: FnMut(u32, &[u32], &[u32], &mut [f64; WIDTH]),
{
    run_with::<true, F>(layout, rays, limits, visit)
}

/// The packet traversal (see the module docs).
#[inline(always)]
fn run_with<const AVX2: bool, F>(
    layout: &Layout,
    (origins, dirs, scale): Rays,
    mut limits: [f64; WIDTH],
    mut visit: F,
) -> bool
where
    F: FnMut(u32, &[u32], &[u32], &mut [f64; WIDTH]),
{
    let mut bundle = Bundle::EMPTY;
    let set = if AVX2 {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: only reached through `run_avx2`.
        unsafe {
            bundle.set_avx2(origins, dirs, scale)
        }
        #[cfg(not(target_arch = "x86_64"))]
        unreachable!()
    } else {
        bundle.set(origins, dirs, scale)
    };
    if !set {
        return false;
    }
    if layout.nodes.is_empty() {
        return true;
    }
    let mut t_best = limits.map(f32_above);
    // Uninitialised: only entries below `top`, each written before, are read.
    let mut stack = [MaybeUninit::<Entry>::uninit(); STACK];
    let mut top = 0;
    let (mut node, mut live) = (0usize, (1u32 << WIDTH) - 1);
    let mut tested = Tested::default();
    loop {
        let wide: &Wide = &layout.nodes[node];
        if AVX2 {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: only reached through `run_avx2`.
            unsafe {
                bundle.test_avx2(wide, &t_best, &mut tested)
            }
        } else {
            bundle.test_portable(wide, &t_best, &mut tested)
        }
        // Far to near, so the nearest child is popped first.
        for j in (0..8).rev() {
            let lane = j ^ bundle.octant;
            let hit = tested.hit[lane] & live;
            if hit != 0 {
                stack[top & (STACK - 1)].write(Entry {
                    child: wide.children[lane],
                    rays: hit,
                    enter: tested.enter[lane],
                });
                top += 1;
            }
        }
        loop {
            if top == 0 {
                return true;
            }
            top -= 1;
            // SAFETY: entry `top` was written by the push that raised `top` above it.
            let entry = unsafe { stack[top & (STACK - 1)].assume_init() };
            let within = (0..WIDTH).fold(0, |m, i| m | u32::from(entry.enter[i] <= t_best[i]) << i);
            let rays = entry.rays & within;
            if rays == 0 {
                continue;
            }
            if entry.child & LEAF == 0 && rays.count_ones() > 1 {
                (node, live) = (entry.child as usize, rays);
                break;
            }
            if entry.child & LEAF == 0 {
                // A ray left alone goes on by itself: one node test per node, not per child.
                let i = rays.trailing_zeros() as usize;
                let ray = Lanes::new(origins[i], dirs[i] + DVec3::ZERO, scale);
                let limit = limits[i];
                let kernel = if AVX2 { Kernel::Avx2 } else { Kernel::Portable };
                let alone = |leaf: u32, _, _| {
                    let prims = layout.leaf(leaf);
                    for first in (0..prims.len()).step_by(8) {
                        let t_best = f32_above(limits[i]);
                        let kept = leaf::chunk_mask(layout, kernel, leaf, first, &ray, t_best);
                        let masks: [u32; 8] = std::array::from_fn(|j| rays * (kept >> j & 1));
                        let chunk = &prims[first..prims.len().min(first + 8)];
                        visit(rays, chunk, &masks[..chunk.len()], &mut limits);
                    }
                    limits[i]
                };
                let (start, observer) = (entry.child as usize, &mut Unobserved);
                traverse::from_node::<AVX2, _, _>(layout, start, &ray, limit, alone, observer);
                t_best[i] = f32_above(limits[i]);
                continue;
            }
            let prims = layout.leaf(entry.child);
            for first in (0..prims.len()).step_by(8) {
                let boxes = leaf::chunk_node(layout, entry.child, first);
                if AVX2 {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: only reached through `run_avx2`.
                    unsafe {
                        bundle.test_avx2(&boxes, &t_best, &mut tested)
                    }
                } else {
                    bundle.test_portable(&boxes, &t_best, &mut tested)
                }
                let masks = tested.hit.map(|hit| hit & rays);
                let chunk = &prims[first..prims.len().min(first + 8)];
                visit(rays, chunk, &masks[..chunk.len()], &mut limits);
                for i in bits(rays) {
                    t_best[i] = f32_above(limits[i]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// A direction component that is zero, signed zero, subnormal, tiny or ordinary.
    fn component(rng: &mut Rng) -> f64 {
        let special = [0.0, -0.0, 5e-324, -1e-310, 1e-41, 1e-20, -1e-300, 1e300];
        if rng.next().is_multiple_of(5) {
            rng.pick(&special)
        } else {
            rng.uniform(-1.0, 1.0)
        }
    }

    #[test]
    fn the_avx2_set_up_gives_the_scalar_set_up_bit_for_bit() {
        if !Kernel::Avx2.available() {
            return;
        }
        let bits = |b: &Bundle| {
            let rows = [b.r, b.c_near, b.c_far].map(|axes| axes.map(|row| row.map(f32::to_bits)));
            (rows, b.flip, b.octant)
        };
        let mut rng = Rng(0xb0d1e);
        let (mut packets, mut refused) = (0, 0);
        for n in 0..20_000 {
            let scale = rng.pick(&[1.0, 16.0, 3e5, 1e30, f64::INFINITY]);
            let far = 10f64.powf(rng.uniform(-3.0, 12.0));
            let dir = DVec3::new(
                component(&mut rng),
                component(&mut rng),
                component(&mut rng),
            );
            let origins: [DVec3; WIDTH] = std::array::from_fn(|_| rng.point(-far, far));
            let mut dirs: [DVec3; WIDTH] =
                std::array::from_fn(|_| dir * (DVec3::ONE + rng.point(0.0, 0.02)));
            if n % 7 == 0 {
                // One ray in another octant.
                dirs[n % WIDTH].y = -dirs[n % WIDTH].y;
            }
            let (mut scalar, mut avx2) = (Bundle::EMPTY, Bundle::EMPTY);
            let formed = scalar.set(&origins, &dirs, scale);
            // SAFETY: the CPU has AVX2 (checked above).
            assert_eq!(formed, unsafe { avx2.set_avx2(&origins, &dirs, scale) });
            if formed {
                assert_eq!(bits(&scalar), bits(&avx2), "{origins:?} {dirs:?} {scale}");
                packets += 1;
            } else {
                refused += 1;
            }
        }
        assert!(packets > 5_000 && refused > 2_000, "{packets} {refused}");
    }
}
