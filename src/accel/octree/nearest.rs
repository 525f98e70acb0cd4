//! The nearest-primitive search: leaves in order of a lower bound on their distance from a
//! query, best first.
//!
//! The search pops, from a heap, the node or leaf whose stored box may come nearest to the
//! query; a leaf's references go to the caller, who measures them exactly and returns the best
//! distance so far, and every entry whose bound exceeds that is skipped. A primitive's part in
//! a leaf lies inside the leaf's stored box and every stored box on the way down to it (the
//! boxes are rounded outward, see module `wide`), so the nearest primitive's leaf is reached
//! whenever the bounds are lower bounds: the answer is a brute-force search's.

use super::wide::{Wide, LEAF};
use super::Octree;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

impl Octree {
    /// Visits the non-empty leaves nearest first, by `gap`, until none can beat the best.
    ///
    /// `gap(box)` must be a lower bound on the distance from the query to any point of the
    /// box (rows `min x, min y, min z, max x, max y, max z`, in the octree's coordinates);
    /// `visit` gets a leaf's primitive indices and returns the best distance found so far.
    /// Leaves whose bound exceeds it are not visited. When the tree's boxes could not be
    /// quantised (planes beyond the culling range), every leaf is visited.
    pub fn nearest_leaves(
        &self,
        gap: impl Fn(&[f32; 6]) -> f64,
        mut visit: impl FnMut(&[u32]) -> f64,
    ) {
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
        // Non-negative bounds order as their bit patterns do.
        let mut heap = BinaryHeap::new();
        push_children(root, &bound, best, &mut heap);
        while let Some(Reverse((key, child))) = heap.pop() {
            if f64::from_bits(key) > best {
                break;
            }
            if child & LEAF != 0 {
                best = best.min(visit(self.layout.leaf(child)));
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
