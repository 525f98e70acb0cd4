//! Building a subtree sequentially into one set of arrays: each cell's children are placed
//! next to each other as soon as the cell splits, and every buffer is reused from cell to
//! cell, so that no node or reference is copied after it is written.

use super::cells::{add_child, child_budget, octant_counts, Builder, Children, Node, Subtree};
use super::OctreeStats;
use crate::accel::PrimitiveSet;
use crate::geometry::Aabb;

/// The room a subtree's arrays are given, in references (and their parts) per reference of
/// its root cell: the bench scenes' octrees hold 2.5 to 5 references per primitive
/// (reports/octree_profile.md), and a subtree about as many per reference of its root.
const ROOM: usize = 3;

/// A node slot not yet written.
const VACANT: Node = Node {
    first: 0,
    count: 0,
    bounds: [0.0; 6],
};

/// The arrays of one subtree under construction, with the scratch buffers of its cells.
pub(super) struct Arena<'b, 'a, P> {
    builder: &'b Builder<'a, P>,
    nodes: Vec<Node>,
    refs: Vec<u32>,
    /// Per reference, its box in its leaf.
    parts: Vec<[f32; 6]>,
    /// The children's references of the cell being split at each depth below the subtree's
    /// root (reused by its siblings and cousins).
    levels: Vec<Children>,
    masks: Vec<u8>,
}

impl<'b, 'a, P: PrimitiveSet> Arena<'b, 'a, P> {
    /// An empty arena for cells of `builder`.
    pub fn new(builder: &'b Builder<'a, P>) -> Self {
        Arena {
            builder,
            nodes: vec![VACANT],
            refs: Vec::new(),
            parts: Vec::new(),
            levels: Vec::new(),
            masks: Vec::new(),
        }
    }

    /// The subtree for `cell` holding `refs`, at `depth`, with at most `budget` references.
    pub fn subtree(mut self, cell: &Aabb, refs: &[u32], depth: u32, budget: f64) -> Subtree {
        self.reserve(refs.len());
        let (stats, occupied) = self.cell(0, cell, refs, depth, budget);
        self.finish(stats, occupied)
    }

    /// `cell` as one leaf holding `refs`, at `depth`.
    pub fn leaf_subtree(mut self, cell: &Aabb, refs: &[u32], depth: u32) -> Subtree {
        self.parts.reserve_exact(refs.len());
        let (stats, occupied) = self.leaf(0, cell, refs, depth);
        self.finish(stats, occupied)
    }

    /// Room for the subtree of a cell holding `count` references, so that its arrays rarely
    /// grow (each growth copies them): [`ROOM`] references and parts per reference, half a
    /// node per reference (the bench scenes' octrees have a quarter), a mask per reference.
    fn reserve(&mut self, count: usize) {
        self.refs.reserve(ROOM * count);
        self.parts.reserve(ROOM * count);
        self.nodes.reserve(count / 2);
        self.masks.reserve(count);
    }

    /// The subtree built, its arrays trimmed to their length (they were given room, or grew by
    /// doubling, and wait for [`super::build`]'s join or the layout).
    fn finish(mut self, stats: OctreeStats, occupied: Aabb) -> Subtree {
        self.nodes.shrink_to_fit();
        self.refs.shrink_to_fit();
        self.parts.shrink_to_fit();
        Subtree {
            nodes: self.nodes,
            refs: self.refs,
            parts: self.parts,
            stats,
            occupied,
        }
    }

    /// Builds `cell` (holding `refs`, at `depth`, with at most `budget` references) into node
    /// `slot`; returns its figures and occupied box.
    fn cell(
        &mut self,
        slot: usize,
        cell: &Aabb,
        refs: &[u32],
        depth: u32,
        budget: f64,
    ) -> (OctreeStats, Aabb) {
        let builder = self.builder;
        let weight = builder.weight(refs);
        if builder.may_split(refs.len(), weight, depth) {
            builder.masks(cell, refs, &mut self.masks);
            let counts = octant_counts(&self.masks);
            if builder.pays(depth, refs, weight, &self.masks, &counts, budget) {
                let level = depth as usize;
                if self.levels.len() <= level {
                    self.levels.resize_with(level + 1, Children::default);
                }
                let mut children = std::mem::take(&mut self.levels[level]);
                children.fill(refs, &self.masks, &counts);
                let built = self.interior(slot, cell, &children, depth, budget);
                self.levels[level] = children;
                return built;
            }
        }
        self.leaf(slot, cell, refs, depth)
    }

    /// Places the non-empty children of a split cell next to each other, builds each (sharing
    /// the cell's `budget` of references), and writes the cell into node `slot`.
    fn interior(
        &mut self,
        slot: usize,
        cell: &Aabb,
        children: &Children,
        depth: u32,
        budget: f64,
    ) -> (OctreeStats, Aabb) {
        let first = self.nodes.len();
        let wanted = (0..8).filter(|&i| !children.of(i).is_empty()).count();
        self.nodes.resize(first + wanted, VACANT);
        let mut stats = OctreeStats {
            nodes: 1,
            ..OctreeStats::default()
        };
        let (mut mask, mut kept, mut occupied) = (0u32, 0usize, Aabb::EMPTY);
        let child_refs = children.total();
        for i in 0..8 {
            let refs = children.of(i);
            if refs.is_empty() {
                // An empty child is an empty leaf that is not stored.
                stats.empty_leaves += 1;
                continue;
            }
            let (nodes, refs_len) = (self.nodes.len(), self.refs.len());
            let share = child_budget(budget, refs.len(), child_refs);
            let (child, child_occupied) =
                self.cell(first + kept, &cell.octant(i), refs, depth + 1, share);
            add_child(&mut stats, &child);
            if child.references == 0 {
                // Left without references: dropped, and its slot goes to the next child.
                self.nodes.truncate(nodes);
                self.refs.truncate(refs_len);
                self.parts.truncate(refs_len);
                continue;
            }
            mask |= 1 << i;
            kept += 1;
            occupied = occupied.union(child_occupied);
        }
        self.nodes[slot] = Node::interior(first, mask, &occupied);
        (stats, occupied)
    }

    /// Writes `cell` as a leaf holding `refs` into node `slot`.
    fn leaf(&mut self, slot: usize, cell: &Aabb, refs: &[u32], depth: u32) -> (OctreeStats, Aabb) {
        let occupied = self.builder.occupied(cell, refs, &mut self.parts);
        self.nodes[slot] = Node::leaf(self.refs.len(), refs.len(), &occupied);
        self.refs.extend_from_slice(refs);
        let stats = OctreeStats {
            nodes: 1,
            leaves: 1,
            empty_leaves: usize::from(refs.is_empty()),
            depth,
            references: refs.len(),
        };
        (stats, occupied)
    }
}
