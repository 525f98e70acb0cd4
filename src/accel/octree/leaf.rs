//! The leaves' filter: per reference, the box its primitive can occupy in the leaf, stored as
//! bytes on the parent node's grid, so that the node test (module `lanes`), run over a leaf's
//! references eight at a time, drops the primitives a ray cannot hit inside the leaf before its
//! best hit. The exact primitive test then runs on the references it keeps only; a reference
//! it drops is not checked into the mailbox, so a later leaf holding the primitive tests it
//! again.
//!
//! # Layout
//! A leaf in [`Layout::refs`] is its header (reference count `n`, parent node, offset of its
//! boxes in [`Layout::boxes`]) and its `n` references. Its boxes are six rows of `n` bytes
//! (`lo x, lo y, lo z, hi x, hi y, hi z`, like a node's planes), byte `j` of a row for
//! reference `j`, standing for the plane `(k + q) · step` of the parent node's frame on that
//! axis. `SLACK` bytes after the last leaf let a kernel load eight bytes from any row.
//!
//! # Why no hit is lost
//! A reference's box is its primitive's bounds ([`PrimitiveSet::bounds`], in the octree's
//! coordinates) grown by the build margin, clamped to the leaf's stored box (the parent's lane)
//! and rounded outward onto the parent's grid; the rounding is exact ([`Frame::below`] and
//! [`Frame::above`] check it in exact arithmetic), so the stored box contains every point of
//! the primitive (within the margin that covers the octree's coordinates, as for the occupied
//! boxes) that lies in the leaf's stored box. Its planes are planes of the parent's frame
//! within the parent's lane, so they decode exactly to f32 values no larger than the largest
//! stored plane: the node test's rounding argument (module `lanes`) holds for them unchanged,
//! and the computed slab interval of each box contains the exact one. So a reference is
//! dropped only when the ray meets the primitive nowhere in the leaf's box with `0 <= t <=
//! best` (the best hit rounded up to f32, compared non-strictly, so an equal `t` still reaches
//! the tie rule). A hit outside the leaf's box lies in the box of another leaf holding the
//! primitive (see the module docs of `super`), which the traversal reaches unless its entry
//! lies beyond the best hit; there the primitive is still unseen by the mailbox. The answer is
//! therefore the least `(t, primitive)` over every primitive brute force would find, bit for
//! bit, for either kernel.

use super::lanes::{self, Kernel, Lanes};
use super::wide::{Layout, Wide, LEAF};
use crate::accel::f32_above;
use crate::accel::f32_below;
use crate::geometry::Aabb;
use rayon::prelude::*;
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// Words of a leaf's header in [`Layout::refs`]: count, parent node, offset of its boxes.
pub(super) const HEADER: usize = 3;

/// Bytes per reference: six planes.
pub(super) const ROWS: usize = 6;

/// Bytes after the last leaf's boxes: an eight-byte load from any row stays in the array.
pub(super) const SLACK: usize = 8;

/// Fills the leaves' boxes of `layout` from the primitives' `bounds`, grown by `margin`. A
/// layout whose planes could not all be quantised keeps them zero: its octree never culls, so
/// no kernel reads them.
pub(super) fn fill(layout: &mut Layout, bounds: &[Aabb], margin: f64) {
    if layout.largest.is_none() {
        return;
    }
    let view: &Layout = layout;
    let leaves: Vec<(usize, Vec<u8>)> = view
        .nodes
        .par_iter()
        .with_min_len(64)
        .flat_map_iter(|node| {
            (0..8)
                .filter(|&lane| {
                    node.children[lane] & LEAF != 0 && node.children[lane] != Wide::EMPTY
                })
                .map(|lane| leaf_boxes(view, node, lane, bounds, margin))
        })
        .collect();
    for (offset, bytes) in leaves {
        layout.boxes[offset..offset + bytes.len()].copy_from_slice(&bytes);
    }
}

/// The boxes of the leaf in lane `lane` of `node`: its offset and its six rows.
fn leaf_boxes(
    layout: &Layout,
    node: &Wide,
    lane: usize,
    bounds: &[Aabb],
    margin: f64,
) -> (usize, Vec<u8>) {
    let child = node.children[lane];
    let [count, _, offset] = layout.header(child);
    let mut bytes = vec![0; ROWS * count];
    for (j, &prim) in layout.leaf(child).iter().enumerate() {
        let b = bounds[prim as usize];
        for axis in 0..3 {
            let frame = node.frame(axis);
            let (lo_q, hi_q) = (node.planes[axis][lane], node.planes[axis + 3][lane]);
            let (lane_lo, lane_hi) = (node.plane(axis, lo_q), node.plane(axis, hi_q));
            let (lane_lo, lane_hi) = (f64::from(lane_lo), f64::from(lane_hi));
            // Clamped into the lane's box (f64::max and min also drop a NaN).
            let lo = (b.min[axis] - margin).max(lane_lo).min(lane_hi);
            let hi = (b.max[axis] + margin).min(lane_hi).max(lane_lo);
            bytes[axis * count + j] = frame.below(f32_below(lo));
            bytes[(axis + 3) * count + j] = frame.above(f32_above(hi));
        }
    }
    (offset, bytes)
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
    let [count, parent, offset] = layout.header(child);
    let prims = layout.leaf(child);
    let node = &layout.nodes[parent];
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
        let rows = Rows {
            node,
            boxes: &layout.boxes,
            at: offset + next,
            count,
        };
        mask = rows.test(kernel, ray, t_best) & (u32::MAX >> 32usize.saturating_sub(count - next));
        next += 8;
    })
}

/// Eight references of a leaf: their rows start at byte `at` of `boxes`, a row every `count`
/// bytes, on the frames of the parent `node`.
struct Rows<'a> {
    node: &'a Wide,
    boxes: &'a [u8],
    at: usize,
    count: usize,
}

impl Rows<'_> {
    /// Bit `i` set when the ray may enter box `i` with `0 <= t <= t_best` (all bits when the
    /// ray does not cull).
    #[inline(always)]
    fn test(&self, kernel: Kernel, ray: &Lanes, t_best: f32) -> u32 {
        if ray.open {
            return 0xff;
        }
        match kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Kernel::Avx2` is only chosen where `Kernel::available` said so.
            Kernel::Avx2 => unsafe { self.test_avx2(ray, t_best) },
            _ => self.test_portable(ray, t_best),
        }
    }

    /// The eight bytes of each plane row, checked against the array's end once.
    #[inline(always)]
    fn load(&self) -> [[u8; 8]; ROWS] {
        let last = self.at + (ROWS - 1) * self.count;
        assert!(
            last + 8 <= self.boxes.len(),
            "a leaf's boxes end inside the array"
        );
        let start = self.boxes[self.at..].as_ptr();
        // SAFETY: row `r` starts at `at + r · count <= last`, and eight bytes from `last` lie
        // in `boxes` (checked above); `[u8; 8]` may be read from any address.
        std::array::from_fn(|r| unsafe {
            start.add(r * self.count).cast::<[u8; 8]>().read_unaligned()
        })
    }

    /// [`Rows::test`] by the portable kernel.
    fn test_portable(&self, ray: &Lanes, t_best: f32) -> u32 {
        let rows = self.load();
        let plane = |row: usize, lane: usize| self.node.plane(row % 3, rows[row][lane]);
        lanes::slabs_portable(plane, ray, t_best).2
    }

    /// [`Rows::test`] by the AVX2 kernel.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn test_avx2(&self, ray: &Lanes, t_best: f32) -> u32 {
        let bytes = self.load();
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
