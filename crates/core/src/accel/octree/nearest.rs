//! The nearest-primitive search: leaves in order of a lower bound on their distance from a
//! query, best first.
//!
//! The search pops, from a heap, the node or leaf whose stored box may come nearest to the
//! query; in a leaf, each reference the search has not met before (a mailbox, as the ray
//! traversal's) goes to the caller, who measures it exactly and returns the best distance so
//! far; every entry whose bound exceeds that is skipped. A primitive's part in a leaf lies
//! inside the leaf's stored box and every stored box on the way down (the boxes are rounded
//! outward, see module `wide`), so the nearest primitive is measured whenever the bounds are
//! lower bounds: the answer is a brute-force search's.

use super::wide::{Wide, LEAF};
use super::{Mailbox, Octree};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

impl Octree {
    /// Offers the primitives to `measure`, nearest boxes first, by `gap`, until none can
    /// beat the best.
    ///
    /// `gap(box)` must be a lower bound on the distance from the query to any point of the
    /// box (rows `min x, min y, min z, max x, max y, max z`, in the octree's coordinates);
    /// `measure` gets a primitive's index and returns the best distance found so far. The
    /// primitives of leaves whose bound exceeds it are not offered, nor is one offered before
    /// (unless the mailbox forgot it). When the tree's boxes could not be quantised (planes
    /// beyond the culling range), every primitive is offered.
    pub fn nearest(&self, gap: impl Fn(&[f32; 6]) -> f64, mut measure: impl FnMut(u32) -> f64) {
        let Some(root) = self.layout.nodes.first() else {
            return;
        };
        let boxes_hold = self.layout.largest.is_some();
        let bound = |node: &Wide, lane: usize| {
            if boxes_hold {
                gap(&node.bounds(lane)).max(0.0)
            } else {
                0.0
            }
        };
        let mut best = f64::INFINITY;
        let mut mailbox = Mailbox::default();
        // Non-negative bounds order as their bit patterns do.
        let mut heap = BinaryHeap::new();
        push_children(root, &bound, best, &mut heap);
        while let Some(Reverse((key, child))) = heap.pop() {
            if f64::from_bits(key) > best {
                break;
            }
            if child & LEAF != 0 {
                // The references' own boxes (module `leaf`) are not tested here: decoding and
                // measuring them cost more than the triangles they would skip (callgrind, the
                // bunny, points around it: 96,000 instructions per point with them, 84,000
                // without).
                for &prim in self.layout.leaf(child) {
                    if mailbox.check_in(prim) {
                        best = best.min(measure(prim));
                    }
                }
            } else {
                let node = &self.layout.nodes[child as usize];
                push_children(node, &bound, best, &mut heap);
            }
        }
    }
}

/// Pushes the occupied lanes of `node` whose bound does not exceed `best`.
fn push_children(
    node: &Wide,
    bound: &impl Fn(&Wide, usize) -> f64,
    best: f64,
    heap: &mut BinaryHeap<Reverse<(u64, u32)>>,
) {
    for lane in 0..8 {
        let child = node.children[lane];
        if child == Wide::EMPTY {
            continue;
        }
        let gap = bound(node, lane);
        if gap <= best {
            heap.push(Reverse((gap.to_bits(), child)));
        }
    }
}
