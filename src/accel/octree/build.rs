//! Building the octree: the split rule, the exact distribution of primitives over children,
//! and parallel construction of large subtrees.

use super::{OctreeParams, OctreeStats};
use crate::accel::{f32_above, f32_below, PrimitiveSet};
use crate::geometry::Aabb;
use glam::DVec3;

/// Cells with more references than this build their children in parallel.
const PARALLEL_REFS: usize = 8192;

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
/// children, stored contiguously, by index into `nodes`, leaves at a run of `refs`.
/// `occupied` bounds the parts of its primitives inside its cell (grown by the margin).
#[derive(Debug)]
pub(super) struct Subtree {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub stats: OctreeStats,
    pub occupied: Aabb,
}

/// What every cell of one build shares.
pub(super) struct Builder<'a, P> {
    pub set: &'a P,
    pub bounds: Vec<Aabb>,
    pub params: OctreeParams,
    /// Cells are grown by this much for the overlap tests.
    pub margin: f64,
}

impl<P: PrimitiveSet> Builder<'_, P> {
    /// The subtree for `cell` holding `refs`, at `depth`.
    pub fn subtree(&self, cell: Aabb, refs: Vec<u32>, depth: u32) -> Subtree {
        let Some(children) = self.split(&cell, &refs, depth) else {
            return self.leaf(&cell, refs, depth);
        };
        drop(refs);
        let build = |(i, child): (usize, Vec<u32>)| self.subtree(cell.octant(i), child, depth + 1);
        let parts: Vec<Subtree> = if children.iter().map(Vec::len).sum::<usize>() > PARALLEL_REFS {
            use rayon::prelude::*;
            children.into_par_iter().enumerate().map(build).collect()
        } else {
            children.into_iter().enumerate().map(build).collect()
        };
        join(parts)
    }

    /// A leaf subtree; its occupied box bounds the parts of its primitives inside the (grown)
    /// cell.
    fn leaf(&self, cell: &Aabb, refs: Vec<u32>, depth: u32) -> Subtree {
        let grown = cell.expanded(self.margin);
        let occupied = refs
            .iter()
            .filter_map(|&prim| self.set.clipped_bounds(prim as usize, &grown))
            .fold(Aabb::EMPTY, Aabb::union)
            .expanded(self.margin);
        Subtree {
            nodes: vec![Node {
                first: 0,
                count: refs.len() as u32,
                bounds: outward(&occupied),
            }],
            stats: OctreeStats {
                nodes: 1,
                leaves: 1,
                empty_leaves: usize::from(refs.is_empty()),
                depth,
                references: refs.len(),
            },
            refs,
            occupied,
        }
    }

    /// The children's references if splitting `cell` pays, by the rule in the module docs.
    fn split(&self, cell: &Aabb, refs: &[u32], depth: u32) -> Option<Vec<Vec<u32>>> {
        if refs.len() <= self.params.leaf_size || depth >= self.params.max_depth {
            return None;
        }
        let children = self.distribute(cell, refs);
        let child_refs: usize = children.iter().map(Vec::len).sum();
        if child_refs > refs.len() && children.iter().any(|c| c.len() == refs.len()) {
            return None;
        }
        let p = &self.params;
        let leaf_cost = refs.len() as f64 * p.intersection_cost;
        let split_cost = p.traversal_cost + 0.25 * child_refs as f64 * p.intersection_cost;
        (split_cost < leaf_cost).then_some(children)
    }

    /// Sorts the references of `cell` into its eight children. A primitive whose bounds fall
    /// in one child goes there directly; one whose bounds span several is tested exactly
    /// against each.
    fn distribute(&self, cell: &Aabb, refs: &[u32]) -> Vec<Vec<u32>> {
        let mid = cell.center();
        let margin = DVec3::splat(self.margin);
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); 8];
        for &prim in refs {
            let b = &self.bounds[prim as usize];
            let low = b.min.cmplt(mid + margin).bitmask();
            let high = b.max.cmpgt(mid - margin).bitmask();
            // Children whose (grown) cell the bounds reach: child i spans the upper half on
            // axis a when bit a of i is set.
            let reached = (0..8u32)
                .filter(|&i| (high & i) == i && (low & !i & 0b111) == (!i & 0b111))
                .fold(0u8, |m, i| m | (1 << i));
            let mask = if reached.count_ones() == 1 {
                reached
            } else {
                reached & self.set.child_mask(prim as usize, cell, self.margin)
            };
            for (i, child) in children.iter_mut().enumerate() {
                if mask & (1 << i) != 0 {
                    child.push(prim);
                }
            }
        }
        children
    }
}

/// Joins the eight child subtrees of a cell under a new root: root, then the roots of the
/// non-empty children, then the rest of each of their nodes in order. Empty children are not
/// stored; the root's child mask says which octants the stored children are.
fn join(parts: Vec<Subtree>) -> Subtree {
    let mut mask = 0u32;
    let mut stats = OctreeStats::default();
    let mut kept = Vec::with_capacity(8);
    for (i, part) in parts.into_iter().enumerate() {
        if part.refs.is_empty() {
            stats.empty_leaves += part.stats.empty_leaves;
        } else {
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
    nodes.push(Node {
        first: 1,
        count: INTERIOR | mask,
        bounds: outward(&occupied),
    });
    let mut refs = Vec::with_capacity(kept.iter().map(|p| p.refs.len()).sum());
    stats.nodes = total + 1;
    // Where each child's non-root nodes start, and where its references start.
    let mut node_base = 1 + kept.len();
    let mut bases = Vec::with_capacity(kept.len());
    for part in &kept {
        bases.push((node_base, refs.len()));
        node_base += part.nodes.len() - 1;
        refs.extend_from_slice(&part.refs);
        stats.leaves += part.stats.leaves;
        stats.empty_leaves += part.stats.empty_leaves;
        stats.depth = stats.depth.max(part.stats.depth);
        stats.references += part.stats.references;
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
