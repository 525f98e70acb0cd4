//! The traversed layout: eight-wide nodes holding their children's occupied boxes as f32
//! planes, one lane per octant, laid out depth first.

use super::build::{Node, INTERIOR};

/// A child reference with this bit set names a leaf (an index into [`Layout::leaves`]);
/// otherwise it names a node.
pub(super) const LEAF: u32 = 1 << 31;

/// An interior cell: the occupied boxes of its eight children as planes (rows `lo x, lo y,
/// lo z, hi x, hi y, hi z`, one lane per octant, rounded outward) and their references. A lane
/// without a child holds the inverted box `[f32::MAX, -f32::MAX]` and reference
/// [`Wide::EMPTY`].
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
pub(super) struct Wide {
    pub planes: [[f32; 8]; 6],
    pub children: [u32; 8],
}

impl Wide {
    /// The reference of a lane without a child.
    pub const EMPTY: u32 = u32::MAX;

    /// A node without children.
    pub const VACANT: Wide = {
        let lo = [f32::MAX; 8];
        let hi = [-f32::MAX; 8];
        Wide {
            planes: [lo, lo, lo, hi, hi, hi],
            children: [Wide::EMPTY; 8],
        }
    };

    /// Bit `i` set when lane `i` holds a child.
    pub fn occupancy(&self) -> u32 {
        (0..8).fold(0, |m, i| {
            m | u32::from(self.children[i] != Wide::EMPTY) << i
        })
    }

    /// Puts a child with occupied box `bounds` in `lane`; planes beyond the f32 range are
    /// clamped to it (the octree then never culls; see [`super::lanes`]).
    fn set(&mut self, lane: usize, bounds: &[f32; 6], child: u32) {
        for (row, &plane) in bounds.iter().enumerate() {
            self.planes[row][lane] = plane.clamp(-f32::MAX, f32::MAX);
        }
        self.children[lane] = child;
    }
}

/// The traversed arrays: node 0 is a top node whose lane 0 holds the root cell (the root's own
/// occupied box is tested like any child's); leaves are `(first reference, count)`.
#[derive(Debug, Clone, Default)]
pub(super) struct Layout {
    pub nodes: Vec<Wide>,
    pub leaves: Vec<[u32; 2]>,
}

impl Layout {
    /// Converts built cells (node 0 the root) into eight-wide nodes, depth first: a node's
    /// first interior child follows it directly.
    pub fn new(cells: &[Node]) -> Layout {
        let mut layout = Layout {
            nodes: vec![Wide::VACANT],
            leaves: Vec::new(),
        };
        if cells[0].count != 0 {
            let root = layout.place(cells, 0);
            layout.nodes[0].set(0, &cells[0].bounds, root);
        }
        layout
    }

    /// Places cell `index` and everything below it; returns its reference.
    fn place(&mut self, cells: &[Node], index: usize) -> u32 {
        let cell = cells[index];
        if cell.count & INTERIOR == 0 {
            self.leaves.push([cell.first, cell.count]);
            return LEAF | (self.leaves.len() - 1) as u32;
        }
        let at = self.nodes.len();
        self.nodes.push(Wide::VACANT);
        let mut next = cell.first as usize;
        for lane in 0..8 {
            if cell.count & (1 << lane) != 0 {
                let child = self.place(cells, next);
                self.nodes[at].set(lane, &cells[next].bounds, child);
                next += 1;
            }
        }
        at as u32
    }

    /// Bytes of the nodes and leaf records.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Wide>() + self.leaves.len() * size_of::<[u32; 2]>()
    }
}
