//! The watertight triangle test's first step for a packet of rays at once: which rays of the
//! packet the edge functions of a triangle leave in question.
//!
//! [`WatertightPacket::candidates`] computes, for every ray, the sheared vertices and the edge
//! functions of a triangle by exactly the operations of [`WatertightRay::intersect`] (separate
//! multiplies and subtracts: Rust never fuses them, and neither does the AVX2 kernel here), so
//! its values are the single-ray test's, bit for bit. It drops a ray exactly when the
//! single-ray test would stop on the same values (edge functions of both signs, or a zero
//! determinant); the rays it keeps go through [`WatertightRay::intersect`], which decides. A
//! packet's answers are therefore the single-ray test's, whichever kernel runs.
//!
//! Most (ray, triangle) pairs a leaf offers are refused on the signs alone, so the packet test
//! spends one vertex fetch per triangle and about forty instructions per four rays where the
//! single-ray test spends a fetch and some sixty instructions per ray.

use super::triangle::WatertightRay;
use crate::accel::PACKET;
use glam::DVec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Up to [`PACKET`] rays prepared for [`WatertightPacket::candidates`]: the rays' shared axis
/// permutation, and per ray its origin in the permuted axes and its shear.
#[derive(Debug, Clone, Copy)]
pub struct WatertightPacket {
    /// The permutation `[kx, ky, kz]` every ray of the packet uses.
    axes: [usize; 3],
    /// Per permuted axis, each ray's origin component.
    origin: [[f64; PACKET]; 3],
    /// Per ray, its shear's x and y components.
    shear: [[f64; PACKET]; 2],
    /// Whether the AVX2 kernel runs (else the portable loop).
    avx2: bool,
}

impl WatertightPacket {
    /// The rays `ray(0)`, ..., `ray(PACKET - 1)` as one packet, or `None` when they do not
    /// share an axis permutation (their dominant direction axes differ); then each goes
    /// through the single-ray test.
    pub fn new<'r>(ray: impl Fn(usize) -> &'r WatertightRay) -> Option<WatertightPacket> {
        let axes = ray(0).axes;
        let mut packet = WatertightPacket {
            axes,
            origin: [[0.0; PACKET]; 3],
            shear: [[0.0; PACKET]; 2],
            avx2: avx2_available(),
        };
        for i in 0..PACKET {
            let ray = ray(i);
            if ray.axes != axes {
                return None;
            }
            for (k, &axis) in axes.iter().enumerate() {
                packet.origin[k][i] = ray.origin[axis];
            }
            packet.shear[0][i] = ray.shear.x;
            packet.shear[1][i] = ray.shear.y;
        }
        Some(packet)
    }

    /// The same packet with the portable kernel (for tests: every kernel gives the same
    /// candidates).
    pub fn portable(self) -> WatertightPacket {
        WatertightPacket {
            avx2: false,
            ..self
        }
    }

    /// The rays among `active` (bit `i` for ray `i`) that [`WatertightRay::intersect`] may
    /// find a hit with triangle `tri` for: all but those its edge functions already refuse.
    #[inline(always)]
    pub fn candidates(&self, tri: &[DVec3; 3], active: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set where the CPU has AVX2.
            return unsafe { self.candidates_avx2(tri, active) };
        }
        self.candidates_portable(tri, active)
    }

    /// [`WatertightPacket::candidates`] one ray after the other.
    fn candidates_portable(&self, tri: &[DVec3; 3], active: u32) -> u32 {
        let [kx, ky, kz] = self.axes;
        let tri = tri.map(|v| [v[kx], v[ky], v[kz]]);
        let mut kept = 0;
        for i in (0..PACKET).filter(|&i| active & (1 << i) != 0) {
            let sheared = |v: &[f64; 3]| {
                let p = [0, 1, 2].map(|k| v[k] - self.origin[k][i]);
                (
                    p[0] - self.shear[0][i] * p[2],
                    p[1] - self.shear[1][i] * p[2],
                )
            };
            let [(ax, ay), (bx, by), (cx, cy)] = tri.each_ref().map(sheared);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let negative = u < 0.0 || v < 0.0 || w < 0.0;
            let positive = u > 0.0 || v > 0.0 || w > 0.0;
            if !(negative && positive) && u + v + w != 0.0 {
                kept |= 1 << i;
            }
        }
        kept
    }

    /// [`WatertightPacket::candidates`] four rays at a time in AVX2 registers, one instance
    /// per axis permutation (so that permuting a vertex is picking its fields).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn candidates_avx2(&self, tri: &[DVec3; 3], active: u32) -> u32 {
        match self.axes {
            [1, 2, 0] => self.avx2_in::<1, 2, 0>(tri, active),
            [2, 1, 0] => self.avx2_in::<2, 1, 0>(tri, active),
            [2, 0, 1] => self.avx2_in::<2, 0, 1>(tri, active),
            [0, 2, 1] => self.avx2_in::<0, 2, 1>(tri, active),
            [0, 1, 2] => self.avx2_in::<0, 1, 2>(tri, active),
            _ => self.avx2_in::<1, 0, 2>(tri, active),
        }
    }

    /// [`WatertightPacket::candidates_avx2`] for the axis permutation `[KX, KY, KZ]`.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn avx2_in<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        tri: &[DVec3; 3],
        active: u32,
    ) -> u32 {
        let permute = |v: &DVec3| [v[KX], v[KY], v[KZ]];
        let tri = [permute(&tri[0]), permute(&tri[1]), permute(&tri[2])];
        let mut kept = 0;
        for quad in 0..PACKET / 4 {
            let rays = (active >> (4 * quad)) & 0xf;
            if rays != 0 {
                kept |= (self.quad_avx2(&tri, quad) & rays) << (4 * quad);
            }
        }
        kept
    }

    /// The rays `4 · quad ..` `4 · quad + 3` (bits 0 to 3) that the edge functions of `tri`
    /// (permuted axes) leave in question.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn quad_avx2(&self, tri: &[[f64; 3]; 3], quad: usize) -> u32 {
        let lane = 4 * quad;
        // SAFETY: `lane + 4 <= PACKET`: four f64 within each row.
        let load = |row: &[f64; PACKET]| unsafe { _mm256_loadu_pd(row.as_ptr().add(lane)) };
        let (ox, oy, oz) = (
            load(&self.origin[0]),
            load(&self.origin[1]),
            load(&self.origin[2]),
        );
        let (sx, sy) = (load(&self.shear[0]), load(&self.shear[1]));
        let sheared = |v: &[f64; 3]| {
            let px = _mm256_sub_pd(_mm256_set1_pd(v[0]), ox);
            let py = _mm256_sub_pd(_mm256_set1_pd(v[1]), oy);
            let pz = _mm256_sub_pd(_mm256_set1_pd(v[2]), oz);
            (
                _mm256_sub_pd(px, _mm256_mul_pd(sx, pz)),
                _mm256_sub_pd(py, _mm256_mul_pd(sy, pz)),
            )
        };
        let (ax, ay) = sheared(&tri[0]);
        let (bx, by) = sheared(&tri[1]);
        let (cx, cy) = sheared(&tri[2]);
        let edge = |p, q, r, s| _mm256_sub_pd(_mm256_mul_pd(p, q), _mm256_mul_pd(r, s));
        let (u, v, w) = (
            edge(cx, by, cy, bx),
            edge(ax, cy, ay, cx),
            edge(bx, ay, by, ax),
        );
        let zero = _mm256_setzero_pd();
        let below = |f| _mm256_cmp_pd::<_CMP_LT_OQ>(f, zero);
        let above = |f| _mm256_cmp_pd::<_CMP_GT_OQ>(f, zero);
        let negative = _mm256_or_pd(_mm256_or_pd(below(u), below(v)), below(w));
        let positive = _mm256_or_pd(_mm256_or_pd(above(u), above(v)), above(w));
        let det = _mm256_add_pd(_mm256_add_pd(u, v), w);
        let refused = _mm256_or_pd(
            _mm256_and_pd(negative, positive),
            _mm256_cmp_pd::<_CMP_EQ_OQ>(det, zero),
        );
        !(_mm256_movemask_pd(refused) as u32) & 0xf
    }
}

/// True when this CPU runs the AVX2 kernel.
fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    return is_x86_feature_detected!("avx2");
    #[cfg(not(target_arch = "x86_64"))]
    return false;
}

#[cfg(test)]
mod tests;
