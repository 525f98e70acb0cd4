//! The traversed layout's nodes: eight-wide nodes holding their children's occupied boxes as
//! quantised planes, one lane per octant (module `layout` lays them out depth first).
//!
//! # Quantised planes
//! A node stores, per axis, a frame: a step `m · 2^e` (`m` an integer from 8 to 15) and an
//! origin `k · step`, and each child's box as one byte per plane, `q`, standing for the plane
//! `(k + q) · step`. The build rounds every f32 plane outward onto that grid, checking each
//! rounding in exact arithmetic, so a child's stored box contains its occupied box. The frame
//! keeps `(|k| + 255) · m < 2²⁴`: then `q · step` and `(k + q) · step` are exact in f32, and a
//! kernel decodes a plane exactly (one multiply-add) before the conservative slab test of
//! [`super::lanes`], whose rounding bound therefore holds as for any f32 plane. The price is
//! a slightly looser box: a plane moves outward by less than one step, about 1/230 of the
//! node's box (or 2⁻¹⁹ of its coordinates' magnitude, which keeps `k` small).

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// A child reference with this bit set names a leaf (the index in
/// [`super::layout::Layout::refs`] of its reference count, followed by its references);
/// otherwise it names a node.
pub(super) const LEAF: u32 = 1 << 31;

/// Below this magnitude a ray's `|r|` loses relative precision in f32, and above it for `s`
/// the node test's products come near the f32 range: either way that axis does not cull
/// ([`super::lanes`]). Planes beyond it are not quantised: the octree then does not cull.
pub(super) const LIMIT: f64 = (1u128 << 100) as f64;

/// The largest plane magnitude quantised.
const RANGE: f64 = LIMIT;

/// An interior cell: per axis the quantisation frame, its children's occupied boxes as
/// quantised planes (rows `lo x, lo y, lo z, hi x, hi y, hi z`, one lane per octant, rounded
/// outward) and their references. A lane without a child has the inverted box `lo = 255, hi =
/// 0` and reference [`Wide::EMPTY`].
#[derive(Debug, Clone, Copy)]
#[repr(C, align(8))]
pub(super) struct Wide {
    /// Per axis, the plane of `q = 0`: `k · step`.
    pub origin: [f32; 3],
    /// Per axis, the distance between neighbouring planes.
    pub step: [f32; 3],
    pub planes: [[u8; 8]; 6],
    pub children: [u32; 8],
}

/// The quantisation frame of one axis: planes `(k + q) · step` for `q = 0..=255`. `k`,
/// `step` and every plane are exact in f32 (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Frame {
    k: f32,
    step: f32,
    /// `1 / step`, rounded: only for the first guess of [`Frame::floor_q`].
    inv: f32,
}

impl Frame {
    /// The frame for planes within `[lo, hi]`, or `None` when they are not finite or beyond
    /// [`RANGE`].
    fn new(lo: f64, hi: f64) -> Option<Frame> {
        let magnitude = lo.abs().max(hi.abs());
        if !(magnitude.is_finite() && magnitude <= RANGE && lo <= hi) {
            return None;
        }
        // 254 steps across (one more absorbs flooring the origin), at least 2⁻¹⁹ of the
        // magnitude (so |k| <= 2¹⁹ + 1) and far from f32's subnormals.
        let need = ((hi - lo) / 254.0)
            .max(magnitude / (1u64 << 19) as f64)
            .max(RANGE.recip());
        let mut step = step_at_least(need);
        loop {
            let k = floor_multiple(lo, step);
            if (k + 255.0) * step >= hi {
                return Some(Frame::on(k, step));
            }
            step = step_at_least(step * (1.0 + 1.0 / 16.0));
        }
    }

    /// The frame of planes `(k + q) · step` (`k` an integer and `step` a frame's step, both
    /// exact in f32).
    fn on(k: f64, step: f64) -> Frame {
        let step = step as f32;
        Frame {
            k: k as f32,
            step,
            inv: step.recip(),
        }
    }

    /// The plane of `q = 0`, `k · step`.
    pub fn origin(&self) -> f32 {
        self.plane(0.0)
    }

    /// The distance between neighbouring planes.
    pub fn step(&self) -> f32 {
        self.step
    }

    /// The byte of a lower plane `lo`: the largest `q` with `(k + q) · step <= lo` (0 when
    /// `lo` lies below every plane, 255 when above).
    pub fn below(&self, lo: f32) -> u8 {
        self.floor_q(self.clamped(lo)) as u8
    }

    /// The byte of an upper plane `hi`: the smallest `q` with `(k + q) · step >= hi` (0 when
    /// `hi` lies below every plane, 255 when above).
    pub fn above(&self, hi: f32) -> u8 {
        let x = self.clamped(hi);
        let q = self.floor_q(x);
        // `x` is at most plane 255, so a plane below it is below 255 too.
        (q + f32::from(u8::from(self.plane(q) < x))) as u8
    }

    /// Plane `q` (an integer from 0 to 255): `(k + q) · step`, exact in f32.
    fn plane(&self, q: f32) -> f32 {
        (self.k + q) * self.step
    }

    /// `x` moved into `[plane 0, plane 255]` (a NaN to plane 0).
    fn clamped(&self, x: f32) -> f32 {
        within(x, self.plane(0.0), self.plane(255.0))
    }

    /// The largest `q` in `0..=255` with plane `q <= x`, for `x` in `[plane 0, plane 255]`,
    /// without a branch. The quotient `(x − plane 0) / step` is at most 255; computed as
    /// `(x − plane 0) · (1 / step)` it takes three f32 roundings (the difference, the
    /// reciprocal, the product) of relative size 2⁻²⁴ each, so it lies within 5·10⁻⁵ of the
    /// exact one. Its nearest integer (adding and taking away 2²³ rounds a number from 0 to
    /// 2²³ to an integer, exactly) is then the answer or the one above it, and one exact
    /// comparison with the plane it stands for settles which (the planes are exact in f32).
    fn floor_q(&self, x: f32) -> f32 {
        const ROUND: f32 = 8_388_608.0; // 2²³
        let guess = ((x - self.plane(0.0)) * self.inv + ROUND) - ROUND;
        guess - f32::from(u8::from(self.plane(guess) > x))
    }
}

/// `x` moved into `[lo, hi]` (`lo <= hi`) by plain comparisons, which a NaN fails: it
/// becomes `lo`. (`f32::max` and `min` do the same with more instructions.)
#[inline(always)]
pub(super) fn within(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x >= lo { x } else { lo };
    if x <= hi {
        x
    } else {
        hi
    }
}

/// The smallest `m · 2^e >= x` with `m` an integer from 8 to 15 (`x` positive and normal).
fn step_at_least(x: f64) -> f64 {
    let unit = 2f64.powi(x.log2().floor() as i32 - 3);
    let mut m = (x / unit).ceil();
    // `log2` may be off by one near powers of two: bring `m` into 8..=15.
    let mut unit = unit;
    while m > 15.0 {
        unit *= 2.0;
        m = (x / unit).ceil();
    }
    while m < 8.0 {
        unit /= 2.0;
        m = (x / unit).ceil();
    }
    m * unit
}

/// The largest integer `k` with `k · step <= x`, checked exactly (`k · step` is exact in f64
/// for the frames above).
fn floor_multiple(x: f64, step: f64) -> f64 {
    // The quotient is below 2²¹ in magnitude here: truncating through an integer is a floor
    // up to one, and the checks below settle that one (`floor` is a library call without
    // SSE4.1).
    let mut k = (x / step) as i64 as f64;
    while k * step > x {
        k -= 1.0;
    }
    while (k + 1.0) * step <= x {
        k += 1.0;
    }
    k
}

/// The lanes that hold a child: `(lane, f32 box, reference)`.
fn occupied(
    lanes: &[Option<([f32; 6], u32)>; 8],
) -> impl Iterator<Item = (usize, [f32; 6], u32)> + '_ {
    (0..8).filter_map(|lane| lanes[lane].map(|(bounds, child)| (lane, bounds, child)))
}

impl Wide {
    /// The reference of a lane without a child.
    pub const EMPTY: u32 = u32::MAX;

    /// A node without children.
    const VACANT: Wide = Wide {
        origin: [0.0; 3],
        step: [1.0; 3],
        planes: [[255; 8], [255; 8], [255; 8], [0; 8], [0; 8], [0; 8]],
        children: [Wide::EMPTY; 8],
    };

    /// A node holding, per lane, a child's f32 occupied box (rows as in `planes`) and
    /// reference. Also returns the largest magnitude of a plane it stores, or `None` when the
    /// boxes cannot be quantised (planes not finite or beyond [`RANGE`]); the node then holds
    /// the right references, but boxes no kernel may cull with.
    pub fn new(lanes: &[Option<([f32; 6], u32)>; 8]) -> (Wide, Option<f64>) {
        let mut node = Wide::VACANT;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (lane, bounds, child) in occupied(lanes) {
            node.children[lane] = child;
            for axis in 0..3 {
                lo[axis] = lo[axis].min(f64::from(bounds[axis]));
                hi[axis] = hi[axis].max(f64::from(bounds[axis + 3]));
            }
        }
        let mut quantised = true;
        for axis in 0..3 {
            let Some(frame) = Frame::new(lo[axis], hi[axis]) else {
                quantised = false;
                continue;
            };
            node.origin[axis] = frame.origin();
            node.step[axis] = frame.step();
            for (lane, bounds, _) in occupied(lanes) {
                node.planes[axis][lane] = frame.below(bounds[axis]);
                node.planes[axis + 3][lane] = frame.above(bounds[axis + 3]);
            }
        }
        let largest = occupied(lanes)
            .flat_map(|(lane, _, _)| node.bounds(lane))
            .fold(0.0f64, |l, plane| l.max(f64::from(plane.abs())));
        (node, quantised.then_some(largest))
    }

    /// Bit `i` set when lane `i` holds a child.
    #[inline(always)]
    pub fn occupancy(&self) -> u32 {
        (0..8).fold(0, |m, i| {
            m | u32::from(self.children[i] != Wide::EMPTY) << i
        })
    }

    /// The plane that byte `q` stands for on `axis`: the product and the sum are both exact
    /// in f32 (see the module docs), so no fused multiply-add is needed.
    #[inline(always)]
    pub fn plane(&self, axis: usize, q: u8) -> f32 {
        f32::from(q) * self.step[axis] + self.origin[axis]
    }

    /// Plane row `row` (as in `planes`), decoded for the eight lanes at once: one FMA, exact.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub unsafe fn row_avx2(&self, row: usize) -> __m256 {
        // SAFETY: this function's own requirement.
        unsafe { self.decode_avx2(row % 3, self.planes[row]) }
    }

    /// Eight bytes `q` on the frame of `axis`, decoded to their planes at once: one FMA,
    /// exact.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub unsafe fn decode_avx2(&self, axis: usize, q: [u8; 8]) -> __m256 {
        let bytes = _mm_cvtsi64_si128(i64::from_le_bytes(q));
        let q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(bytes));
        _mm256_fmadd_ps(
            q,
            _mm256_set1_ps(self.step[axis]),
            _mm256_set1_ps(self.origin[axis]),
        )
    }

    /// The frame of `axis` (exact: the stored origin is `k · step` with both factors exact).
    pub fn frame(&self, axis: usize) -> Frame {
        let step = f64::from(self.step[axis]);
        Frame::on(f64::from(self.origin[axis]) / step, step)
    }

    /// Lane `lane`'s stored box, decoded: rows as in `planes`.
    pub fn bounds(&self, lane: usize) -> [f32; 6] {
        std::array::from_fn(|row| self.plane(row % 3, self.planes[row][lane]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift) of f32 values of varied magnitude.
    fn values(seed: u64, n: usize) -> Vec<f32> {
        let mut x = seed;
        (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                let mantissa = (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5;
                mantissa * 2f32.powi((x % 60) as i32 - 30)
            })
            .collect()
    }

    #[test]
    fn stored_boxes_contain_the_given_ones_and_are_at_most_a_step_wider() {
        let v = values(0x5eed_1234, 6000);
        for chunk in v.chunks_exact(48) {
            let mut lanes = [None; 8];
            for (lane, slot) in lanes.iter_mut().enumerate().filter(|(i, _)| i % 3 != 1) {
                let c = &chunk[lane * 6..lane * 6 + 6];
                let bounds = std::array::from_fn(|row| {
                    let (a, b) = (c[row % 3], c[row % 3 + 3]);
                    if row < 3 {
                        a.min(b)
                    } else {
                        a.max(b)
                    }
                });
                *slot = Some((bounds, lane as u32));
            }
            let (node, largest) = Wide::new(&lanes);
            let largest = largest.expect("finite planes are quantised");
            assert_eq!(node.occupancy(), 0b0110_1101);
            for (lane, bounds, child) in occupied(&lanes) {
                assert_eq!(node.children[lane], child);
                let stored = node.bounds(lane);
                for axis in 0..3 {
                    let step = f64::from(node.step[axis]);
                    let (lo, hi) = (f64::from(stored[axis]), f64::from(stored[axis + 3]));
                    let (want_lo, want_hi) = (f64::from(bounds[axis]), f64::from(bounds[axis + 3]));
                    assert!(
                        lo <= want_lo && want_lo - lo < step,
                        "axis {axis}: {lo} {bounds:?}"
                    );
                    assert!(
                        hi >= want_hi && hi - want_hi < step,
                        "axis {axis}: {hi} {bounds:?}"
                    );
                    assert!(lo.abs().max(hi.abs()) <= largest);
                    // Exact decoding: each plane is an integer number of steps.
                    assert_eq!((lo / step).fract(), 0.0, "{lo} / {step}");
                    assert_eq!((hi / step).fract(), 0.0, "{hi} / {step}");
                }
            }
        }
    }

    /// The bytes [`Frame::below`] and [`Frame::above`] give for `x`, by their definition in
    /// f64: the nearest grid plane at or below (above) `x`, as a step count from the frame's
    /// origin, clamped to a byte.
    fn bytes_by_definition(frame: &Frame, x: f32) -> (u8, u8) {
        let (x, k, step) = (f64::from(x), f64::from(frame.k), f64::from(frame.step));
        let below = floor_multiple(x, step) - k;
        let above = -floor_multiple(-x, step) - k;
        (below.clamp(0.0, 255.0) as u8, above.clamp(0.0, 255.0) as u8)
    }

    #[test]
    fn bytes_are_the_grid_planes_next_to_a_value() {
        let v = values(0xf4a3_0001, 9000);
        for chunk in v.chunks_exact(9) {
            let (lo, hi) = (chunk[0].min(chunk[1]), chunk[0].max(chunk[1]));
            let frame = Frame::new(f64::from(lo), f64::from(hi)).expect("finite frame");
            // Values across the frame and within three widths of it (the reference's quotient
            // must stay small), on every plane and one f32 step beside it.
            let width = hi - lo;
            let mut xs: Vec<f32> = chunk[2..]
                .iter()
                .map(|t| lo + t.fract() * 3.0 * width)
                .collect();
            xs.extend([lo, hi, lo - width, hi + width]);
            for q in 0..=255 {
                let p = frame.plane(f32::from(q as u8));
                xs.extend([p, p.next_down(), p.next_up()]);
            }
            for x in xs {
                assert_eq!(
                    (frame.below(x), frame.above(x)),
                    bytes_by_definition(&frame, x),
                    "{x} in {frame:?}"
                );
            }
        }
    }

    #[test]
    fn boxes_on_the_grid_are_stored_exactly_and_huge_ones_not_at_all() {
        let mut lanes = [None; 8];
        // Extents of 254 steps of a power of two (2⁻⁹, 2⁻⁸), ends on that grid; a flat axis.
        let on_grid = [0.25, -0.5, 0.5, 0.74609375, 0.4921875, 0.5];
        lanes[3] = Some((on_grid, 7));
        let (node, largest) = Wide::new(&lanes);
        assert_eq!(node.bounds(3), on_grid);
        assert_eq!(node.occupancy(), 1 << 3);
        assert!(largest.is_some());
        lanes[5] = Some(([0.0, 0.0, 0.0, 1e31, 1.0, 1.0], 8));
        let (node, largest) = Wide::new(&lanes);
        assert_eq!(largest, None);
        assert_eq!(node.occupancy(), 1 << 3 | 1 << 5);
    }
}
