//! The cells of a build: the node format a build writes ([`Node`]), a subtree in its own
//! arrays, the sorting of a cell's references into its children, and the rules every cell
//! follows (its weight, whether it may and should split, the box its primitives occupy),
//! shared by the parallel build of large cells ([`super::build`]) and the sequential one of
//! small cells ([`super::arena`]).

use super::{OctreeParams, OctreeStats};
use crate::accel::{f32_above, f32_below, PrimitiveSet};
use crate::geometry::Aabb;
use glam::DVec3;

/// What one more reference (of weight 1) must save for a split to pay, in primitive tests per
/// ray through the root (see the module docs). Measured on the OpenChessSet's board
/// (reports/octree_profile.md): 1e-6 halves its references for under 1 % more trace instructions
/// and leaves the bunny's and the helmet's octrees as they were.
const DUPLICATION_COST: f64 = 1e-6;

/// The most references a tree may hold per primitive. Each cell gets a budget of references
/// (the root this many per primitive) and shares it among its children in proportion to
/// their references, and a split that would exceed it is not made; so the tree never holds
/// more than this many references per primitive, whatever the scene. Real scenes use 1 to 13
/// per primitive; 256 leaves the trees of all 652 fixtures and shared assets as they were
/// but many-cubes's (0.07 % fewer references). Without it, a soup of large crossing
/// triangles is split until each sits in thousands of leaves: 80,000 random triangles made
/// 403 million references, 3.7 GB and 213 s of build (now 10.6 million, 160 MB, 12 s).
pub(super) const MAX_REFERENCES_PER_PRIMITIVE: f64 = 256.0;

/// Set in [`Node::count`] for interior cells; the low eight bits then flag non-empty children.
pub(super) const INTERIOR: u32 = 1 << 31;

/// A cell as built: interior cells point at their non-empty children (stored contiguously, in
/// octant order), leaves at a run of references. `bounds` is the box its primitives occupy
/// inside it, grown by the margin and rounded outward to f32: `[lo x, lo y, lo z, hi x, hi y,
/// hi z]`. [`super::wide`] turns these cells into the eight-wide nodes that are traversed.
#[derive(Debug, Clone, Copy)]
pub(super) struct Node {
    pub first: u32,
    pub count: u32,
    pub bounds: [f32; 6],
}

impl Node {
    /// A leaf holding `count` references from `first` on.
    pub fn leaf(first: usize, count: usize, occupied: &Aabb) -> Node {
        Node {
            first: first as u32,
            count: count as u32,
            bounds: outward(occupied),
        }
    }

    /// An interior cell whose non-empty children (bit `i` of `mask` for octant `i`) start at
    /// node `first`.
    pub fn interior(first: usize, mask: u32, occupied: &Aabb) -> Node {
        Node {
            first: first as u32,
            count: INTERIOR | mask,
            bounds: outward(occupied),
        }
    }
}

/// `occupied` rounded outward to f32 planes.
fn outward(occupied: &Aabb) -> [f32; 6] {
    let (lo, hi) = (occupied.min, occupied.max);
    [
        f32_below(lo.x),
        f32_below(lo.y),
        f32_below(lo.z),
        f32_above(hi.x),
        f32_above(hi.y),
        f32_above(hi.z),
    ]
}

/// A subtree in its own arrays: node 0 is its root; interior nodes point at their non-empty
/// children, stored contiguously, by index into `nodes`, leaves at a run of `refs`. Nodes
/// that no cell points at may remain (a child left without references is not unlinked from
/// the array); `stats` counts only the linked ones. `occupied` bounds the parts of its
/// primitives inside its cell (grown by the margin).
#[derive(Debug)]
pub(super) struct Subtree {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    /// Per reference, the box of its primitive's part in its leaf (see [`Builder::occupied`]).
    pub parts: Vec<[f32; 6]>,
    pub stats: OctreeStats,
    pub occupied: Aabb,
}

/// The references of a cell's eight children, one child after another in octant order.
#[derive(Debug, Default)]
pub(super) struct Children {
    refs: Vec<u32>,
    /// Child `i` holds `refs[ends[i - 1]..ends[i]]` (from 0 for child 0).
    ends: [usize; 8],
}

impl Children {
    /// Sorts `refs` into the children by their octant masks, keeping their order within each
    /// child; `counts` are the masks' bit counts per octant.
    pub fn fill(&mut self, refs: &[u32], masks: &[u8], counts: &[usize; 8]) {
        let mut starts = [0usize; 8];
        let mut end = 0;
        for i in 0..8 {
            starts[i] = end;
            end += counts[i];
            self.ends[i] = end;
        }
        self.refs.clear();
        self.refs.resize(end, 0);
        for (&prim, &mask) in refs.iter().zip(masks) {
            let mut bits = mask;
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                self.refs[starts[i]] = prim;
                starts[i] += 1;
                bits &= bits - 1;
            }
        }
    }

    /// The references of all eight children together.
    pub fn total(&self) -> usize {
        self.ends[7]
    }

    /// The references of child `i`.
    pub fn of(&self, i: usize) -> &[u32] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] };
        &self.refs[start..self.ends[i]]
    }
}

/// How many masks have bit `i` set, for each octant `i`. Up to 255 masks are summed at a
/// time in one word, byte `i` counting bit `i` (one table look-up and one add per mask).
pub(super) fn octant_counts(masks: &[u8]) -> [usize; 8] {
    let mut counts = [0usize; 8];
    for chunk in masks.chunks(255) {
        let bytes: u64 = chunk.iter().map(|&mask| SPREAD[usize::from(mask)]).sum();
        for (i, count) in counts.iter_mut().enumerate() {
            *count += (bytes >> (8 * i) & 0xff) as usize;
        }
    }
    counts
}

/// Each mask with its bit `i` moved to bit `8 i`.
const SPREAD: [u64; 256] = {
    let mut table = [0u64; 256];
    let mut mask = 0;
    while mask < 256 {
        let mut i = 0;
        while i < 8 {
            table[mask] |= ((mask as u64 >> i) & 1) << (8 * i);
            i += 1;
        }
        mask += 1;
    }
    table
};

/// What every cell of one build shares.
pub(super) struct Builder<'a, P> {
    pub set: &'a P,
    pub bounds: Vec<Aabb>,
    /// Each primitive's [`PrimitiveSet::cost`], or `None` when every one costs 1 (a
    /// reference then weighs 1 and a cell's weight is its count).
    pub costs: Option<Vec<f64>>,
    pub params: OctreeParams,
    /// Cells are grown by this much for the overlap tests.
    pub margin: f64,
}

impl<P: PrimitiveSet> Builder<'_, P> {
    /// The weight of the references `refs`: the sum of their primitives' costs.
    pub fn weight(&self, refs: &[u32]) -> f64 {
        match &self.costs {
            None => refs.len() as f64,
            Some(costs) => refs.iter().map(|&prim| costs[prim as usize]).sum(),
        }
    }

    /// Whether a cell of `n` references weighing `weight` at `depth` may be split at all.
    pub fn may_split(&self, n: usize, weight: f64, depth: u32) -> bool {
        n > 1 && weight > self.params.leaf_size as f64 && depth < self.params.max_depth
    }

    /// Whether splitting a cell at `depth` holding `refs` (weighing `weight`) into children by
    /// their octant `masks` (`counts` references per child) pays, by the rule in the module
    /// docs, and stays within the cell's `budget` of references
    /// ([`MAX_REFERENCES_PER_PRIMITIVE`]).
    pub fn pays(
        &self,
        depth: u32,
        refs: &[u32],
        weight: f64,
        masks: &[u8],
        counts: &[usize; 8],
        budget: f64,
    ) -> bool {
        let n = refs.len();
        let child_refs: usize = counts.iter().sum();
        if child_refs as f64 > budget || (child_refs > n && counts.contains(&n)) {
            return false;
        }
        let child_weight = match &self.costs {
            None => child_refs as f64,
            Some(costs) => refs
                .iter()
                .zip(masks)
                .map(|(&prim, &mask)| costs[prim as usize] * f64::from(mask.count_ones()))
                .sum(),
        };
        let p = &self.params;
        let leaf_cost = weight * p.intersection_cost;
        let split_cost = p.traversal_cost + 0.25 * child_weight * p.intersection_cost;
        // A ray through the root enters a cell at `depth` with probability 4^-depth.
        let saved = (leaf_cost - split_cost) * 0.25f64.powi(depth as i32);
        split_cost < leaf_cost && saved >= DUPLICATION_COST * (child_weight - weight)
    }

    /// The octant masks of `refs` in `cell` (see [`Builder::octants`]), into `masks`.
    pub fn masks(&self, cell: &Aabb, refs: &[u32], masks: &mut Vec<u8>) {
        let mid = cell.center();
        masks.clear();
        masks.extend(refs.iter().map(|&prim| self.octants(cell, mid, prim)));
    }

    /// The children of `cell` (centre `mid`) that primitive `prim` goes into. A primitive
    /// whose bounds fall in one child goes there directly; one whose bounds span several is
    /// tested exactly against each.
    pub fn octants(&self, cell: &Aabb, mid: DVec3, prim: u32) -> u8 {
        let margin = DVec3::splat(self.margin);
        let b = &self.bounds[prim as usize];
        let low = b.min.cmplt(mid + margin).bitmask();
        let high = b.max.cmpgt(mid - margin).bitmask();
        // Children whose (grown) cell the bounds reach: child i spans the upper half on
        // axis a when bit a of i is set.
        const UPPER: [u8; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];
        let reached = UPPER.iter().enumerate().fold(0xff, |m, (a, &upper)| {
            let lower = if low >> a & 1 != 0 { !upper } else { 0 };
            let higher = if high >> a & 1 != 0 { upper } else { 0 };
            m & (lower | higher)
        });
        if reached.count_ones() == 1 {
            reached
        } else {
            self.set
                .child_mask(prim as usize, cell, self.margin, reached)
        }
    }

    /// The box the primitives `refs` occupy inside `cell`: their parts inside the cell grown
    /// by the margin, bounded and grown by the margin again. A primitive whose bounds within
    /// the grown cell already lie inside the box so far is not clipped: its part there lies
    /// inside those bounds, so it cannot add to the box. Each reference's own box (its part,
    /// or those bounds where it was not clipped, grown by the margin and rounded outward; an
    /// empty box for a primitive with nothing there) goes to `parts`.
    pub fn occupied(&self, cell: &Aabb, refs: &[u32], parts: &mut Vec<[f32; 6]>) -> Aabb {
        let grown = cell.expanded(self.margin);
        let mut occupied = Aabb::EMPTY;
        for &prim in refs {
            let part = self.bounds[prim as usize].common(grown).and_then(|within| {
                if occupied.holds(&within) {
                    return Some(within);
                }
                let part = self.set.clipped_bounds(prim as usize, &grown)?;
                occupied = occupied.union(part);
                Some(part)
            });
            parts.push(outward(
                &part.map_or(Aabb::EMPTY, |p| p.expanded(self.margin)),
            ));
        }
        occupied.expanded(self.margin)
    }
}

/// The share of a split cell's reference `budget` that a child holding `count` of the
/// children's `child_refs` references gets: in proportion, so that it is at least `count`
/// whenever the split was within the budget.
pub(super) fn child_budget(budget: f64, count: usize, child_refs: usize) -> f64 {
    budget * count as f64 / child_refs.max(1) as f64
}

/// Adds a child's figures to its parent's `stats`: a child left without references counts
/// only its empty leaves (it is not stored).
pub(super) fn add_child(stats: &mut OctreeStats, child: &OctreeStats) {
    stats.empty_leaves += child.empty_leaves;
    if child.references == 0 {
        return;
    }
    stats.nodes += child.nodes;
    stats.leaves += child.leaves;
    stats.depth = stats.depth.max(child.depth);
    stats.references += child.references;
}
