//! Building the octree: the split rule, the exact distribution of primitives over children,
//! and parallel construction of large subtrees (smaller ones are built by [`super::arena`]).

use super::arena::Arena;
use super::cells::{add_child, child_budget, octant_counts, Builder, Node, Subtree, INTERIOR};
use super::OctreeStats;
use crate::accel::PrimitiveSet;
use crate::geometry::Aabb;
use glam::DVec3;
use rayon::prelude::*;

/// Cells with more references than this distribute them and build their children in
/// parallel; smaller ones are built sequentially into one [`Arena`].
const PARALLEL_REFS: usize = 8192;

/// The references of each of the eight children, by the octant masks of `refs`; `counts` are
/// the masks' bit counts per octant.
fn split(refs: &[u32], masks: &[u8], counts: &[usize; 8]) -> Vec<Vec<u32>> {
    let mut children: Vec<Vec<u32>> = counts.iter().map(|&n| Vec::with_capacity(n)).collect();
    for (&prim, &mask) in refs.iter().zip(masks) {
        let mut bits = mask;
        while bits != 0 {
            children[bits.trailing_zeros() as usize].push(prim);
            bits &= bits - 1;
        }
    }
    children
}

impl<P: PrimitiveSet> Builder<'_, P> {
    /// The subtree for `cell` holding `refs`, at `depth`. Each list is dropped as soon as it
    /// is distributed, as the children's lists are built.
    pub fn subtree(&self, cell: &Aabb, refs: Vec<u32>, depth: u32, budget: f64) -> Subtree {
        // Weighed only when the cell is large enough to be built here.
        let weight = (refs.len() > PARALLEL_REFS)
            .then(|| self.weight(&refs))
            .filter(|&weight| self.may_split(refs.len(), weight, depth));
        let Some(weight) = weight else {
            return Arena::new(self).subtree(cell, &refs, depth, budget);
        };
        let mid = cell.center();
        let masks: Vec<u8> = refs
            .par_iter()
            .map(|&prim| self.octants(cell, mid, prim))
            .collect();
        let counts = octant_counts(&masks);
        if !self.pays(depth, &refs, weight, &masks, &counts, budget) {
            return Arena::new(self).leaf_subtree(cell, &refs, depth);
        }
        let children = split(&refs, &masks, &counts);
        drop((refs, masks));
        let child_refs: usize = counts.iter().sum();
        let parts: Vec<Subtree> = children
            .into_par_iter()
            .enumerate()
            .map(|(i, child)| {
                let share = child_budget(budget, child.len(), child_refs);
                self.subtree(&cell.octant(i), child, depth + 1, share)
            })
            .collect();
        join(parts)
    }
}

/// Joins the eight child subtrees of a cell under a new root: root, then the roots of the
/// non-empty children, then the rest of each of their nodes in order. Empty children are not
/// stored; the root's child mask says which octants the stored children are.
fn join(parts: Vec<Subtree>) -> Subtree {
    let mut mask = 0u32;
    let mut stats = OctreeStats {
        nodes: 1,
        ..OctreeStats::default()
    };
    let mut kept = Vec::with_capacity(8);
    for (i, part) in parts.into_iter().enumerate() {
        add_child(&mut stats, &part.stats);
        if part.stats.references != 0 {
            mask |= 1 << i;
            kept.push(part);
        }
    }
    let occupied = kept
        .iter()
        .map(|p| p.occupied)
        .fold(Aabb::EMPTY, Aabb::union);
    let total: usize = kept.iter().map(|p| p.nodes.len()).sum();
    let mut nodes = Vec::with_capacity(total + 1);
    nodes.push(Node::interior(1, mask, &occupied));
    let mut refs = Vec::with_capacity(stats.references);
    let mut parts = Vec::with_capacity(stats.references);
    // Where each child's non-root nodes start, and where its references start.
    let mut node_base = 1 + kept.len();
    let mut bases = Vec::with_capacity(kept.len());
    for part in &kept {
        bases.push((node_base, refs.len()));
        node_base += part.nodes.len() - 1;
        refs.extend_from_slice(&part.refs);
        parts.extend_from_slice(&part.parts);
    }
    let relocate = |node: &Node, (node_base, ref_base): (usize, usize)| match node.count & INTERIOR
    {
        0 => Node {
            first: node.first + ref_base as u32,
            ..*node
        },
        _ => Node {
            first: node.first - 1 + node_base as u32,
            ..*node
        },
    };
    for (part, base) in kept.iter().zip(&bases) {
        nodes.push(relocate(&part.nodes[0], *base));
    }
    for (part, base) in kept.iter().zip(&bases) {
        nodes.extend(part.nodes[1..].iter().map(|n| relocate(n, *base)));
    }
    Subtree {
        nodes,
        refs,
        parts,
        stats,
        occupied,
    }
}

/// The smallest cube holding `bounds` with a little room, or a unit cube for an empty box.
pub(super) fn cube_around(bounds: &Aabb) -> Aabb {
    if bounds.is_empty() {
        return Aabb::new(DVec3::splat(-0.5), DVec3::splat(0.5));
    }
    let centre = bounds.center();
    let extent = bounds.size().max_element();
    let half = (extent * 0.5) * (1.0 + 1e-6) + 1e-9 * (centre.abs().max_element() + 1.0);
    Aabb::new(centre - DVec3::splat(half), centre + DVec3::splat(half))
}
