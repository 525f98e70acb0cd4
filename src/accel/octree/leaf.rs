//! The leaves' filter: per reference, the box its primitive can occupy in the leaf, stored as
//! four bits per plane inside the leaf's box on the parent node's grid, so that the node test
//! (module `lanes`), run over a leaf's references eight at a time, drops the primitives a ray
//! cannot hit inside the leaf before its best hit. The exact primitive test then runs on the
//! references it keeps only; a reference it drops is not checked into the mailbox, so a later
//! leaf holding the primitive tests it again.
//!
//! # Layout
//! A leaf in [`Layout::refs`] is a header of three words (reference count `n`; parent node
//! times eight plus the leaf's lane in it; per axis a step `s`, one byte each), its `n`
//! references, then its boxes: three rows (`x, y, z`) of `n` bytes, byte `j` of a row for
//! reference `j`, padded to a whole word. With `L` and `H` the bytes of the leaf's own box on
//! that axis in the parent node (its lane's planes), a byte's low four bits `a` stand for the
//! lower plane `L + a · s` and its high four bits `b` for the upper plane `H − b · s`, in units
//! of the parent's grid (`s = ⌈(H − L) / 15⌉`, at least 1). `SLACK_WORDS` after the last leaf
//! let a kernel load eight bytes from any row.
//!
//! # Why no hit is lost
//! A reference's box is its primitive's bounds ([`PrimitiveSet::bounds`], in the octree's
//! coordinates) grown by the build margin, clamped to the leaf's stored box, rounded outward
//! onto the parent's grid ([`Frame::below`] and [`Frame::above`], checked in exact arithmetic)
//! and then outward again onto the leaf's coarser grid (integer arithmetic: `a` rounds down,
//! `b` rounds down from the top); so it contains every point of the primitive that lies in
//! the leaf's stored box (within the margin, which covers the octree's coordinates, as it does
//! for the occupied boxes). Its planes are planes `L ≤ q ≤ H` of the parent's frame, decoded
//! exactly (the integers `L + a · s` and `H − b · s` are exact in f32, and then `q · step +
//! origin` is, as for the node's own planes), so they are f32 values no larger than the
//! largest stored plane: the node test's rounding argument (module `lanes`) holds for them
//! unchanged, and the computed slab interval of each box contains the exact one. A reference
//! is therefore dropped only when the ray meets the primitive nowhere in the leaf's box with
//! `0 <= t <= best` (the best hit rounded up to f32, compared non-strictly, so an equal `t`
//! still reaches the tie rule). A hit outside the leaf's box lies in the box of another leaf
//! holding the primitive (see the module docs of `super`), which the traversal reaches unless
//! its entry lies beyond the best hit; there the primitive is still new to the mailbox. The
//! answer is the least `(t, primitive)` over every primitive brute force would find, bit for
//! bit, for either kernel.

use super::lanes::{self, Kernel, Lanes};
use super::wide::{Layout, Wide, LEAF};
use crate::accel::{f32_above, f32_below};
use crate::geometry::Aabb;
use rayon::prelude::*;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Words of a leaf's header in [`Layout::refs`]: count, parent and lane, steps.
pub(super) const HEADER: usize = 3;

/// Words after the last leaf: an eight-byte load from any row of its boxes stays in the array.
pub(super) const SLACK_WORDS: usize = 2;

/// The header of a leaf of `count` references in lane `lane` of node `parent`, its steps not
/// yet known.
pub(super) fn header(count: usize, parent: usize, lane: usize) -> [u32; HEADER] {
    assert!(
        parent < 1 << 28,
        "{parent} nodes: too many for a leaf's header"
    );
    [count as u32, (parent << 3 | lane) as u32, 0]
}

/// Words of the boxes of a leaf of `count` references.
pub(super) fn box_words(count: usize) -> usize {
    (3 * count).div_ceil(4)
}

/// Fills the steps and boxes of every leaf of `layout` from the primitives' `bounds`, grown by
/// `margin`. A layout whose planes could not all be quantised keeps them zero: its octree
/// never culls, so no kernel reads them.
pub(super) fn fill(layout: &mut Layout, bounds: &[Aabb], margin: f64) {
    if layout.largest.is_none() {
        return;
    }
    let view: &Layout = layout;
    let leaves: Vec<[(usize, Vec<u32>); 2]> = view
        .nodes
        .par_iter()
        .with_min_len(64)
        .flat_map_iter(|node| {
            let leaf = |lane: &usize| node.children[*lane] & LEAF != 0;
            (0..8)
                .filter(move |lane| node.children[*lane] != Wide::EMPTY && leaf(lane))
                .map(|lane| leaf_words(view, node, lane, bounds, margin))
        })
        .collect();
    for (at, words) in leaves.into_iter().flatten() {
        layout.refs[at..at + words.len()].copy_from_slice(&words);
    }
}

/// The steps word and the boxes of the leaf in lane `lane` of `node`, each with its place in
/// [`Layout::refs`].
fn leaf_words(
    layout: &Layout,
    node: &Wide,
    lane: usize,
    bounds: &[Aabb],
    margin: f64,
) -> [(usize, Vec<u32>); 2] {
    let child = node.children[lane];
    let prims = layout.leaf(child);
    let count = prims.len();
    let steps: [u8; 3] = std::array::from_fn(|axis| {
        let (lo_q, hi_q) = (node.planes[axis][lane], node.planes[axis + 3][lane]);
        hi_q.saturating_sub(lo_q).div_ceil(15).max(1)
    });
    let mut bytes = vec![0u8; 4 * box_words(count)];
    for (j, &prim) in prims.iter().enumerate() {
        for (axis, &s) in steps.iter().enumerate() {
            bytes[axis * count + j] =
                reference_byte(node, lane, axis, s, &bounds[prim as usize], margin);
        }
    }
    let words = bytes
        .chunks_exact(4)
        .map(|w| u32::from_ne_bytes([w[0], w[1], w[2], w[3]]));
    let at = (child & !LEAF) as usize;
    let steps = u32::from_le_bytes([steps[0], steps[1], steps[2], 0]);
    [
        (at + 2, vec![steps]),
        (at + HEADER + count, words.collect()),
    ]
}

/// The byte of a reference whose primitive has bounds `b` on `axis`, in the leaf in lane
/// `lane` of `node` whose step on that axis is `s` (see the module docs).
fn reference_byte(node: &Wide, lane: usize, axis: usize, s: u8, b: &Aabb, margin: f64) -> u8 {
    let frame = node.frame(axis);
    let (lo_q, hi_q) = (node.planes[axis][lane], node.planes[axis + 3][lane]);
    let (lane_lo, lane_hi) = (node.plane(axis, lo_q), node.plane(axis, hi_q));
    let (lane_lo, lane_hi) = (f64::from(lane_lo), f64::from(lane_hi));
    // Clamped into the lane's box (f64::max and min also drop a NaN).
    let lo = (b.min[axis] - margin).max(lane_lo).min(lane_hi);
    let hi = (b.max[axis] + margin).min(lane_hi).max(lane_lo);
    let below = (frame.below(f32_below(lo)) - lo_q) / s;
    let above = (hi_q - frame.above(f32_above(hi))) / s;
    below | above << 4
}

/// The references of the leaf `child` names whose boxes the ray `ray` may enter with `0 <= t
/// <= t_best`, in their order in the leaf (all of them when the ray does not cull).
#[inline(always)]
pub(super) fn survivors<'a>(
    layout: &'a Layout,
    kernel: Kernel,
    child: u32,
    ray: &'a Lanes,
    t_best: f32,
) -> impl Iterator<Item = u32> + 'a {
    let [count, place, steps] = layout.header(child);
    let count = count as usize;
    let prims = layout.leaf(child);
    let boxes = Boxes {
        node: &layout.nodes[(place >> 3) as usize],
        lane: (place & 7) as usize,
        steps: steps.to_le_bytes(),
        refs: &layout.refs,
        at: 4 * ((child & !LEAF) as usize + HEADER + count),
        count,
    };
    let (mut next, mut mask) = (0usize, 0u32);
    std::iter::from_fn(move || loop {
        if mask != 0 {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            return Some(prims[next - 8 + lane]);
        }
        if next >= count {
            return None;
        }
        let left = u32::MAX >> 32usize.saturating_sub(count - next);
        mask = boxes.test(next, kernel, ray, t_best) & left;
        next += 8;
    })
}

/// A leaf's boxes as the filter reads them: its parent `node` and lane there, its steps, and
/// its rows from byte `at` of `refs`, a row every `count` bytes.
struct Boxes<'a> {
    node: &'a Wide,
    lane: usize,
    steps: [u8; 4],
    refs: &'a [u32],
    at: usize,
    count: usize,
}

impl Boxes<'_> {
    /// Bit `i` set when the ray may enter the box of reference `first + i` with `0 <= t <=
    /// t_best` (all bits when the ray does not cull).
    #[inline(always)]
    fn test(&self, first: usize, kernel: Kernel, ray: &Lanes, t_best: f32) -> u32 {
        if ray.open {
            return 0xff;
        }
        let bytes = self.load(first);
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Kernel::Avx2` is only chosen where `Kernel::available` said so.
            Kernel::Avx2 => unsafe { self.test_avx2(&bytes, ray, t_best) },
            _ => self.test_portable(&bytes, ray, t_best),
        }
    }

    /// The eight bytes of each row from reference `first` on, checked against the array's end
    /// once.
    #[inline(always)]
    fn load(&self, first: usize) -> [[u8; 8]; 3] {
        let start = self.at + first;
        assert!(
            start + 2 * self.count + 8 <= 4 * self.refs.len(),
            "a leaf's boxes end inside the array"
        );
        let bytes = self.refs.as_ptr().cast::<u8>();
        // SAFETY: row `r` starts at byte `start + r · count`, and eight bytes from there lie in
        // `refs` (checked above); `[u8; 8]` may be read from any address.
        std::array::from_fn(|r| unsafe {
            bytes
                .add(start + r * self.count)
                .cast::<[u8; 8]>()
                .read_unaligned()
        })
    }

    /// The parent's bytes of the leaf's own box on `axis`, `L` and `H`.
    #[inline(always)]
    fn bounds(&self, axis: usize) -> (u8, u8) {
        (
            self.node.planes[axis][self.lane],
            self.node.planes[axis + 3][self.lane],
        )
    }

    /// [`Boxes::test`] by the portable kernel.
    fn test_portable(&self, bytes: &[[u8; 8]; 3], ray: &Lanes, t_best: f32) -> u32 {
        let plane = |row: usize, lane: usize| {
            let axis = row % 3;
            let ((lo, hi), s) = (self.bounds(axis), self.steps[axis]);
            let byte = bytes[axis][lane];
            // Within `lo..=hi` for a stored byte (see the module docs); the lanes past the
            // leaf's end, which wrap, are masked.
            let q = if row < 3 {
                lo.wrapping_add((byte & 15).wrapping_mul(s))
            } else {
                hi.wrapping_sub((byte >> 4).wrapping_mul(s))
            };
            self.node.plane(axis, q)
        };
        lanes::slabs_portable(plane, ray, t_best).2
    }

    /// [`Boxes::test`] by the AVX2 kernel.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn test_avx2(&self, bytes: &[[u8; 8]; 3], ray: &Lanes, t_best: f32) -> u32 {
        let mut rows = [_mm256_setzero_ps(); 6];
        for axis in 0..3 {
            let v = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(i64::from_le_bytes(bytes[axis])));
            let below = _mm256_cvtepi32_ps(_mm256_and_si256(v, _mm256_set1_epi32(15)));
            let above = _mm256_cvtepi32_ps(_mm256_srli_epi32::<4>(v));
            let ((lo, hi), s) = (
                self.bounds(axis),
                _mm256_set1_ps(f32::from(self.steps[axis])),
            );
            // Exact: small integers.
            let lo = _mm256_fmadd_ps(below, s, _mm256_set1_ps(f32::from(lo)));
            let hi = _mm256_fnmadd_ps(above, s, _mm256_set1_ps(f32::from(hi)));
            // SAFETY: this function's own requirement.
            rows[axis] = unsafe { self.node.decode_q_avx2(axis, lo) };
            // SAFETY: as above.
            rows[axis + 3] = unsafe { self.node.decode_q_avx2(axis, hi) };
        }
        // SAFETY: as above.
        let (_, _, hit) = unsafe { lanes::slabs_avx2(|row| rows[row], ray, t_best) };
        _mm256_movemask_ps(hit) as u32
    }
}

#[cfg(test)]
mod tests;
