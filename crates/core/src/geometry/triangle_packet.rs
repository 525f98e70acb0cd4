//! The watertight triangle test's first step, four at a time: for a packet of rays, which rays
//! the edge functions of one triangle leave in question ([`WatertightPacket::candidates`]);
//! for one ray, which of four triangles ([`WatertightRay::candidates`]).
//!
//! Both compute the sheared vertices and the edge functions by exactly the operations of
//! [`WatertightRay::intersect`] (separate multiplies and subtracts: Rust never fuses them, and
//! neither does the AVX2 kernel here), so their values are the single-ray test's, bit for bit.
//! They drop a (ray, triangle) pair exactly when the single-ray test would stop on the same
//! values (edge functions of both signs, or a zero determinant); the pairs they keep go
//! through [`WatertightRay::intersect`], which decides. The answers are therefore the
//! single-ray test's, whichever kernel runs.
//!
//! Most pairs a leaf offers are refused on the signs alone: the filter spends about forty
//! instructions per four pairs where the single-ray test spends some sixty per pair.
//!
//! For the search that notes what it offers each ray (the `certain` AOV),
//! [`WatertightPacket::candidates_apart`] also says which refused rays certainly miss the
//! exact triangle, and which rays certainly cross its interior, by the edge filter of
//! [`crate::bound::apart`] on the same sheared vertices.

use super::triangle::WatertightRay;
#[cfg(target_arch = "x86_64")]
use crate::bound::apart;
use crate::bound::triangle::{certainly_inside, edges_apart};
#[cfg(target_arch = "x86_64")]
use crate::simd::per_axes;
use crate::simd::Kernel;
use crate::simd::PACKET;
use glam::DVec3;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// What [`WatertightPacket::candidates_apart`] says of one triangle, a bit per ray.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EdgeVerdict {
    /// The rays [`WatertightPacket::candidates`] keeps.
    pub kept: u32,
    /// The rays whose exact ray certainly misses the exact triangle (a subset of the refused).
    pub apart: u32,
    /// The rays whose exact ray certainly crosses the exact triangle's interior (as
    /// [`crate::bound::triangle::certainly_inside`] decides it).
    pub inside: u32,
}

impl EdgeVerdict {
    /// The kept lanes `kept`, saying nothing of the others.
    #[inline(always)]
    pub fn kept(kept: u32) -> EdgeVerdict {
        EdgeVerdict {
            kept,
            ..EdgeVerdict::default()
        }
    }

    /// The verdict one lane after the other, of the `lanes` lanes `active`: `kept` as the
    /// portable pre-filter gives it, the others by the one-triangle filters `apart(i)` and
    /// `inside(i)` (`edges_apart`, `certainly_inside`) of lane `i`.
    fn portable(
        (lanes, active, kept): (usize, u32, u32),
        apart: impl Fn(usize) -> bool,
        inside: impl Fn(usize) -> bool,
    ) -> EdgeVerdict {
        let mask = |test: &dyn Fn(usize) -> bool| {
            (0..lanes)
                .filter(|&i| active & (1 << i) != 0 && test(i))
                .fold(0, |mask, i| mask | 1 << i)
        };
        EdgeVerdict {
            kept,
            apart: mask(&apart),
            inside: mask(&inside),
        }
    }

    /// The three masks in one word, `PACKET` bits each.
    #[inline(always)]
    fn pack(self) -> u32 {
        self.kept | (self.apart << PACKET) | (self.inside << (2 * PACKET))
    }

    /// The masks [`EdgeVerdict::pack`] packed.
    #[inline(always)]
    fn unpack(word: u32) -> EdgeVerdict {
        let mask = (1 << PACKET) - 1;
        EdgeVerdict {
            kept: word & mask,
            apart: (word >> PACKET) & mask,
            inside: (word >> (2 * PACKET)) & mask,
        }
    }
}

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
    /// through the single-ray test. `kernel` runs [`WatertightPacket::candidates`].
    pub fn new<'r>(
        kernel: Kernel,
        ray: impl Fn(usize) -> &'r WatertightRay,
    ) -> Option<WatertightPacket> {
        let axes = ray(0).axes;
        let mut packet = WatertightPacket {
            axes,
            origin: [[0.0; PACKET]; 3],
            shear: [[0.0; PACKET]; 2],
            avx2: kernel == Kernel::Avx2,
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
            return unsafe { self.candidates_avx2::<false>(tri, 0.0, active) };
        }
        self.candidates_portable(tri, active)
    }

    /// [`WatertightPacket::candidates`], and of the rays `active` those whose exact ray
    /// certainly misses the exact triangle, whose vertices lie within `placement` of `tri`'s
    /// per coordinate ([`crate::bound::apart`]: two edge functions beyond their rounding
    /// bounds with opposite signs, as `certainly_apart` decides it; a subset of the refused
    /// rays), and those whose exact ray certainly crosses its interior (all three beyond
    /// their bounds with one sign). `ray(i)` is ray `i`, for the portable kernel.
    #[inline(always)]
    pub fn candidates_apart<'r>(
        &self,
        tri: &[DVec3; 3],
        placement: f64,
        active: u32,
        ray: impl Fn(usize) -> &'r WatertightRay,
    ) -> EdgeVerdict {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set where the CPU has AVX2.
            let packed = unsafe { self.candidates_avx2::<true>(tri, placement, active) };
            return EdgeVerdict::unpack(packed);
        }
        EdgeVerdict::portable(
            (PACKET, active, self.candidates_portable(tri, active)),
            |i| edges_apart(ray(i), tri, placement),
            |i| certainly_inside(ray(i), tri, placement),
        )
    }

    /// [`WatertightPacket::candidates`] one ray after the other.
    fn candidates_portable(&self, tri: &[DVec3; 3], active: u32) -> u32 {
        let [kx, ky, kz] = self.axes;
        let tri = tri.map(|v| [v[kx], v[ky], v[kz]]);
        let lanes = (0..PACKET).filter(|&i| active & (1 << i) != 0);
        lanes
            .filter(|&i| {
                let origin = [0, 1, 2].map(|k| self.origin[k][i]);
                kept(&tri, origin, [self.shear[0][i], self.shear[1][i]])
            })
            .fold(0, |mask, i| mask | 1 << i)
    }

    /// [`WatertightPacket::candidates`] four rays at a time in AVX2 registers, one instance
    /// per axis permutation (so that permuting a vertex is picking its fields).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    /// With `APART`, also the rays [`WatertightPacket::candidates_apart`] reports for
    /// `placement`, [`EdgeVerdict::pack`]ed (else the kept rays alone: one word, returned in a
    /// register).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn candidates_avx2<const APART: bool>(
        &self,
        tri: &[DVec3; 3],
        placement: f64,
        active: u32,
    ) -> u32 {
        let args = (tri, placement, active);
        per_axes!(self.axes, |KX, KY, KZ| self
            .avx2_in::<KX, KY, KZ, APART>(args))
    }

    /// [`WatertightPacket::candidates_avx2`] for the axis permutation `[KX, KY, KZ]`.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn avx2_in<const KX: usize, const KY: usize, const KZ: usize, const APART: bool>(
        &self,
        (tri, placement, active): (&[DVec3; 3], f64, u32),
    ) -> u32 {
        let vertex = |v: &DVec3| {
            let c = |k| _mm256_set1_pd(v[k]);
            [c(KX), c(KY), c(KZ)]
        };
        let vertices = [vertex(&tri[0]), vertex(&tri[1]), vertex(&tri[2])];
        let mut verdict = EdgeVerdict::default();
        for quad in 0..PACKET / 4 {
            let rays = (active >> (4 * quad)) & 0xf;
            if rays != 0 {
                // SAFETY: `4 * quad + 4 <= PACKET`: four f64 within each row.
                let load =
                    |row: &[f64; PACKET]| unsafe { _mm256_loadu_pd(row.as_ptr().add(4 * quad)) };
                let origin = [
                    load(&self.origin[0]),
                    load(&self.origin[1]),
                    load(&self.origin[2]),
                ];
                let shear = [load(&self.shear[0]), load(&self.shear[1])];
                let [kept, apart, inside] = if APART {
                    kept_apart_avx2(&vertices, (&origin, &shear), _mm256_set1_pd(placement))
                } else {
                    [kept_avx2(&vertices, &origin, &shear), 0, 0]
                };
                verdict.kept |= (kept & rays) << (4 * quad);
                verdict.apart |= (apart & rays) << (4 * quad);
                verdict.inside |= (inside & rays) << (4 * quad);
            }
        }
        verdict.pack()
    }
}

impl WatertightRay {
    /// Of the triangles `tris[i]` with bit `i` of `active` set, those
    /// [`WatertightRay::intersect`] may find a hit with: all but those its edge functions
    /// already refuse (four triangles per AVX2 register, exactly as
    /// [`WatertightPacket::candidates`] takes four rays), by `kernel`.
    pub fn candidates(&self, kernel: Kernel, tris: &[[DVec3; 3]; 4], active: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if kernel == Kernel::Avx2 {
            // SAFETY: the CPU has AVX2.
            return unsafe { self.candidates_avx2::<false>(tris, active, &[0.0; 4]) };
        }
        self.candidates_portable(tris, active)
    }

    /// [`WatertightRay::candidates`], and of the triangles `active` those the exact ray
    /// certainly misses, and those whose interior it certainly crosses, the exact triangle
    /// `i` within `placement[i]` of `tris[i]` (as [`WatertightPacket::candidates_apart`] says
    /// it for rays), by `kernel`.
    pub fn candidates_apart(
        &self,
        kernel: Kernel,
        tris: &[[DVec3; 3]; 4],
        active: u32,
        placement: &[f64; 4],
    ) -> EdgeVerdict {
        #[cfg(target_arch = "x86_64")]
        if kernel == Kernel::Avx2 {
            // SAFETY: the CPU has AVX2.
            let packed = unsafe { self.candidates_avx2::<true>(tris, active, placement) };
            return EdgeVerdict::unpack(packed);
        }
        EdgeVerdict::portable(
            (4, active, self.candidates_portable(tris, active)),
            |i| edges_apart(self, &tris[i], placement[i]),
            |i| certainly_inside(self, &tris[i], placement[i]),
        )
    }

    /// [`WatertightRay::candidates`] one triangle after the other.
    fn candidates_portable(&self, tris: &[[DVec3; 3]; 4], active: u32) -> u32 {
        let [kx, ky, kz] = self.axes;
        let origin = [self.origin[kx], self.origin[ky], self.origin[kz]];
        let shear = [self.shear.x, self.shear.y];
        (0..4)
            .filter(|&i| active & (1 << i) != 0)
            .filter(|&i| kept(&tris[i].map(|v| [v[kx], v[ky], v[kz]]), origin, shear))
            .fold(0, |mask, i| mask | 1 << i)
    }

    /// [`WatertightRay::candidates`] in one AVX2 register per coordinate, one instance per
    /// axis permutation; with `APART`, [`WatertightRay::candidates_apart`]'s verdict,
    /// [`EdgeVerdict::pack`]ed.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn candidates_avx2<const APART: bool>(
        &self,
        tris: &[[DVec3; 3]; 4],
        active: u32,
        placement: &[f64; 4],
    ) -> u32 {
        let args = (tris, active, placement);
        per_axes!(self.axes, |KX, KY, KZ| self
            .avx2_in::<KX, KY, KZ, APART>(args))
    }

    /// [`WatertightRay::candidates_avx2`] for the axis permutation `[KX, KY, KZ]`.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn avx2_in<const KX: usize, const KY: usize, const KZ: usize, const APART: bool>(
        &self,
        (tris, active, placement): (&[[DVec3; 3]; 4], u32, &[f64; 4]),
    ) -> u32 {
        // Coordinate `k` of vertex `j` of the four triangles, lane `i` for triangle `i`.
        let gather = |j: usize, k: usize| {
            _mm256_set_pd(tris[3][j][k], tris[2][j][k], tris[1][j][k], tris[0][j][k])
        };
        let vertex = |j| [gather(j, KX), gather(j, KY), gather(j, KZ)];
        let vertices = [vertex(0), vertex(1), vertex(2)];
        let o = |k| _mm256_set1_pd(self.origin[k]);
        let origin = [o(KX), o(KY), o(KZ)];
        let shear = [_mm256_set1_pd(self.shear.x), _mm256_set1_pd(self.shear.y)];
        if !APART {
            return kept_avx2(&vertices, &origin, &shear) & active;
        }
        // SAFETY: four f64 in `placement`.
        let placement = unsafe { _mm256_loadu_pd(placement.as_ptr()) };
        let [kept, apart, inside] = kept_apart_avx2(&vertices, (&origin, &shear), placement);
        EdgeVerdict {
            kept: kept & active,
            apart: apart & active,
            inside: inside & active,
        }
        .pack()
    }
}

/// Whether the single-ray test goes on with the triangle `tri` (permuted axes) for the ray with
/// origin `origin` (permuted axes) and shear `shear`: false when its edge functions have both
/// signs or sum to zero. The operations of [`WatertightRay::intersect`], one by one.
#[inline(always)]
fn kept(tri: &[[f64; 3]; 3], origin: [f64; 3], shear: [f64; 2]) -> bool {
    let sheared = |v: &[f64; 3]| {
        let p = [0, 1, 2].map(|k| v[k] - origin[k]);
        (p[0] - shear[0] * p[2], p[1] - shear[1] * p[2])
    };
    let [(ax, ay), (bx, by), (cx, cy)] = tri.each_ref().map(sheared);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let negative = u < 0.0 || v < 0.0 || w < 0.0;
    let positive = u > 0.0 || v > 0.0 || w > 0.0;
    !(negative && positive) && u + v + w != 0.0
}

/// [`kept`] for four lanes (bits 0 to 3 of the result): per lane a triangle's vertices
/// `vertices[j][k]` (vertex `j`, permuted coordinate `k`), a ray's `origin` and `shear`.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn kept_avx2(
    vertices: &[[__m256d; 3]; 3],
    origin: &[__m256d; 3],
    shear: &[__m256d; 2],
) -> u32 {
    let sheared = |v: &[__m256d; 3]| {
        let px = _mm256_sub_pd(v[0], origin[0]);
        let py = _mm256_sub_pd(v[1], origin[1]);
        let pz = _mm256_sub_pd(v[2], origin[2]);
        (
            _mm256_sub_pd(px, _mm256_mul_pd(shear[0], pz)),
            _mm256_sub_pd(py, _mm256_mul_pd(shear[1], pz)),
        )
    };
    kept_lanes([
        sheared(&vertices[0]),
        sheared(&vertices[1]),
        sheared(&vertices[2]),
    ])
}

/// [`kept_avx2`], the lanes whose exact ray certainly misses the exact triangle, within
/// `placement` (per lane) of the stored one, and those whose exact ray certainly crosses its
/// interior ([`crate::bound::apart::edge_lanes`]), from the same sheared coordinates.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn kept_apart_avx2(
    vertices: &[[__m256d; 3]; 3],
    (origin, shear): (&[__m256d; 3], &[__m256d; 2]),
    placement: __m256d,
) -> [u32; 3] {
    let moved = apart::margins(placement, *shear);
    // Written out: an array's `map` may stay a call here.
    let sheared = |v: &[__m256d; 3]| {
        let p = [
            _mm256_sub_pd(v[0], origin[0]),
            _mm256_sub_pd(v[1], origin[1]),
            _mm256_sub_pd(v[2], origin[2]),
        ];
        apart::sheared(p, *shear, moved)
    };
    let all = [
        sheared(&vertices[0]),
        sheared(&vertices[1]),
        sheared(&vertices[2]),
    ];
    let kept = kept_lanes([
        (all[0][0], all[0][2]),
        (all[1][0], all[1][2]),
        (all[2][0], all[2][2]),
    ]);
    let [apart, inside] = apart::edge_lanes(&all, moved);
    [
        kept,
        _mm256_movemask_pd(apart) as u32,
        _mm256_movemask_pd(inside) as u32,
    ]
}

/// [`kept`] for four lanes from the sheared `(x, y)` of the three vertices.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn kept_lanes([(ax, ay), (bx, by), (cx, cy)]: [(__m256d, __m256d); 3]) -> u32 {
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

#[cfg(test)]
mod tests;
