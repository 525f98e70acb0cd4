//! The leaves' filter: per reference, the box its primitive can occupy in the leaf, stored as
//! one byte per plane on the parent node's grid, so that the node test (module `lanes`), run
//! over a leaf's references eight at a time, drops the primitives a ray cannot hit inside the
//! leaf before its best hit. The exact primitive test then runs on the
//! references it keeps only; a reference it drops is not checked into the mailbox, so a later
//! leaf holding the primitive tests it again.
//!
//! # Layout
//! A leaf in [`Layout::refs`] is a header of two words (reference count `n`; parent node
//! times eight plus the leaf's lane in it), its `n` references, then its boxes: six rows (`lo
//! x, lo y, lo z, hi x, hi y, hi z`, as a node's planes) of `n` bytes, byte `j` of a row for
//! reference `j`, each standing for the plane `(k + q) · step` of the parent node's frame on
//! that axis, padded to a whole word. `SLACK_WORDS` after the last leaf let a kernel load
//! eight bytes from any row.
//!
//! # Why no hit is lost
//! A reference's box is the bounds of its primitive's part in the leaf's cell grown by the
//! build margin (the part the build clipped for the leaf's occupied box, or the primitive's
//! bounds within that cell where it did not clip), grown by the margin again, rounded outward
//! to f32, clamped to the leaf's stored box and rounded outward onto the parent's grid
//! ([`Frame::below`] and [`Frame::above`], checked in exact arithmetic). So it holds whatever
//! this primitive adds to the leaf's occupied box, with the same margin (which covers the
//! octree's coordinates and the clipping's rounding). Its planes are planes of the parent's
//! frame within the leaf's lane, so they decode exactly to f32 values no larger than the
//! largest stored plane: the node test's rounding argument (module `lanes`) holds for them
//! unchanged, and the computed slab interval of each box contains the exact one.
//!
//! Take a hit point of a primitive with `t` not beyond the best hit. It lies in the cell of
//! some leaf holding the primitive, inside that leaf's occupied box (the module docs of
//! `super`), so the traversal reaches that leaf unless its entry lies beyond the best hit; and
//! there the point lies in the reference's box, so the filter keeps the reference (it drops a
//! reference only when the ray meets its box nowhere with `0 <= t <= best`, the best hit
//! rounded up to f32 and compared non-strictly, so that an equal `t` still reaches the tie
//! rule). A leaf that drops the reference earlier does not check it into the mailbox, so it is
//! still new there. The answer is therefore the least `(t, primitive)` over every primitive
//! brute force would find, bit for bit, for either kernel.

use super::lanes::{self, Kernel, Lanes};
use super::layout::{box_words, Layout, HEADER, ROWS};
use super::wide::{within, Wide, LEAF};
use rayon::prelude::*;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Fills the boxes of every leaf of `layout`, each at `sources` (where it starts in the
/// layout, and where its references' `parts`, the boxes of their primitives' parts in it,
/// start). A layout whose planes could not all be quantised keeps them zero: its octree never
/// culls, so no kernel reads them.
pub(super) fn fill(layout: &mut Layout, sources: &[(usize, usize)], parts: &[[f32; 6]]) {
    if layout.largest.is_none() {
        return;
    }
    let view: &Layout = layout;
    let leaves: Vec<(usize, Vec<u32>)> = sources
        .par_iter()
        .with_min_len(256)
        .map(|&(at, first)| leaf_words(view, at, &parts[first..]))
        .collect();
    for (at, words) in leaves {
        layout.refs[at..at + words.len()].copy_from_slice(&words);
    }
}

/// The boxes of the leaf at `at` in [`Layout::refs`] from its references' `parts`, and where
/// they go.
fn leaf_words(layout: &Layout, at: usize, parts: &[[f32; 6]]) -> (usize, Vec<u32>) {
    let child = LEAF | at as u32;
    let [count, place] = layout.header(child);
    let (count, lane) = (count as usize, (place & 7) as usize);
    let node = &layout.nodes[(place >> 3) as usize];
    let mut bytes = vec![0u8; 4 * box_words(count)];
    for axis in 0..3 {
        let frame = node.frame(axis);
        let (lo_q, hi_q) = (node.planes[axis][lane], node.planes[axis + 3][lane]);
        let (lane_lo, lane_hi) = (node.plane(axis, lo_q), node.plane(axis, hi_q));
        for (j, part) in parts[..count].iter().enumerate() {
            // Clamped into the lane's box; a NaN becomes the lane's plane on its side (the
            // upper one through the negations, which are exact).
            let lo = within(part[axis], lane_lo, lane_hi);
            let hi = -within(-part[axis + 3], -lane_hi, -lane_lo);
            bytes[axis * count + j] = frame.below(lo);
            bytes[(axis + 3) * count + j] = frame.above(hi);
        }
    }
    let words = bytes
        .chunks_exact(4)
        .map(|w| u32::from_ne_bytes([w[0], w[1], w[2], w[3]]));
    (at + HEADER + count, words.collect())
}

/// Bit `j` set when the ray `ray` may enter the box of reference `first + j` of the leaf
/// `child` with `0 <= t <= t_best` (`first` a multiple of eight; bits past the leaf's end
/// clear).
#[inline(always)]
pub(super) fn chunk_mask(
    layout: &Layout,
    kernel: Kernel,
    child: u32,
    first: usize,
    ray: &Lanes,
    t_best: f32,
) -> u32 {
    let boxes = Boxes::of(layout, child);
    boxes.test(first, kernel, ray, t_best) & boxes.lanes(first)
}

/// The boxes of references `first..first + 8` of the leaf `child` as the lanes of a node on
/// its parent's frames (lanes past the leaf's end empty), for the packet test.
#[inline(always)]
pub(super) fn chunk_node(layout: &Layout, child: u32, first: usize) -> Wide {
    let boxes = Boxes::of(layout, child);
    let prims = layout.leaf(child);
    let lanes = boxes.lanes(first);
    Wide {
        origin: boxes.node.origin,
        step: boxes.node.step,
        planes: boxes.load(first),
        children: std::array::from_fn(|j| {
            if lanes & (1 << j) != 0 {
                prims[first + j]
            } else {
                Wide::EMPTY
            }
        }),
    }
}

/// A leaf's boxes as the filter reads them: its parent `node`, and its rows from byte `at` of
/// `refs`, a row every `count` bytes.
struct Boxes<'a> {
    node: &'a Wide,
    refs: &'a [u32],
    at: usize,
    count: usize,
}

impl Boxes<'_> {
    /// The boxes of the leaf `child`.
    #[inline(always)]
    fn of(layout: &Layout, child: u32) -> Boxes<'_> {
        let [count, place] = layout.header(child);
        let count = count as usize;
        Boxes {
            node: &layout.nodes[(place >> 3) as usize],
            refs: &layout.refs,
            at: 4 * ((child & !LEAF) as usize + HEADER + count),
            count,
        }
    }

    /// Bit `j` set when reference `first + j` is in the leaf.
    #[inline(always)]
    fn lanes(&self, first: usize) -> u32 {
        0xff >> (first + 8).saturating_sub(self.count).min(8)
    }

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
    fn load(&self, first: usize) -> [[u8; 8]; ROWS] {
        let start = self.at + first;
        assert!(
            start + (ROWS - 1) * self.count + 8 <= 4 * self.refs.len(),
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

    /// [`Boxes::test`] by the portable kernel.
    fn test_portable(&self, bytes: &[[u8; 8]; ROWS], ray: &Lanes, t_best: f32) -> u32 {
        let plane = |row: usize, lane: usize| self.node.plane(row % 3, bytes[row][lane]);
        lanes::slabs_portable(plane, ray, t_best).2
    }

    /// [`Boxes::test`] by the AVX2 kernel.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn test_avx2(&self, bytes: &[[u8; 8]; ROWS], ray: &Lanes, t_best: f32) -> u32 {
        // SAFETY: this function's own requirement.
        let rows: [__m256; ROWS] =
            std::array::from_fn(|r| unsafe { self.node.decode_avx2(r % 3, bytes[r]) });
        // SAFETY: as above.
        let (_, _, hit) = unsafe { lanes::slabs_avx2(|row| rows[row], ray, t_best) };
        _mm256_movemask_ps(hit) as u32
    }
}

#[cfg(test)]
mod tests;
