//! The traversed layout's arrays: the eight-wide nodes ([`Wide`]) depth first, and the
//! leaves, each a header, its references and its filter boxes ([`super::leaf`]), laid out from
//! the cells of a build.
//!
//! A leaf in [`Layout::refs`] is a header of [`HEADER`] words (reference count `n`; parent
//! node times eight plus the leaf's lane in it), its `n` references, then its boxes: [`ROWS`]
//! rows of `n` bytes, padded to a whole word ([`box_words`]); [`SLACK_WORDS`] follow the last
//! leaf.

use super::cells::{Node, INTERIOR};
use super::wide::{Wide, LEAF};
use rayon::prelude::*;

/// Words of a leaf's header in [`Layout::refs`]: count, parent and lane.
pub(super) const HEADER: usize = 2;

/// Bytes per reference: six planes.
pub(super) const ROWS: usize = 6;

/// Words after the last leaf: an eight-byte load from any row of its boxes stays in the array.
pub(super) const SLACK_WORDS: usize = 2;

/// The header of a leaf of `count` references in lane `lane` of node `parent`.
pub(super) fn header(count: usize, parent: usize, lane: usize) -> [u32; HEADER] {
    assert!(
        parent < 1 << 28,
        "{parent} nodes: too many for a leaf's header"
    );
    [count as u32, (parent << 3 | lane) as u32]
}

/// Words of the boxes of a leaf of `count` references.
pub(super) fn box_words(count: usize) -> usize {
    (ROWS * count).div_ceil(4)
}

/// The traversed arrays: the nodes, node 0 the root (none for an empty tree), and each leaf as
/// its header, references and reference boxes (module `leaf`), in `refs`.
#[derive(Debug, Clone, Default)]
pub(super) struct Layout {
    pub nodes: Vec<Wide>,
    pub refs: Vec<u32>,
    /// The largest magnitude of any stored plane, or `None` when some node's boxes could not
    /// be quantised.
    pub largest: Option<f64>,
}

impl Layout {
    /// Converts built cells (node 0 the root) and their references into eight-wide nodes,
    /// depth first: a node's first interior child follows it directly. An interior root's own
    /// occupied box is not stored (its children's lie within it). The order is fixed in one
    /// pass; the nodes themselves (quantising their children's boxes) are then made in
    /// parallel.
    /// Also returns, per leaf, where it starts in [`Layout::refs`] and where its references
    /// start in `refs`.
    pub fn new(cells: &[Node], refs: &[u32]) -> (Layout, Vec<(usize, usize)>) {
        let interior = cells.iter().filter(|c| c.count & INTERIOR != 0).count();
        let mut order = Order {
            cells,
            refs,
            nodes: Vec::with_capacity(interior),
            // Each leaf's references and its header.
            leaves: Vec::with_capacity(refs.len() + HEADER * (cells.len() - interior)),
            sources: Vec::with_capacity(cells.len() - interior),
        };
        if cells[0].count & INTERIOR != 0 {
            order.place(0, 0, 0);
        } else if cells[0].count != 0 {
            // A root leaf waits in lane 0 of a node of its own.
            let mut lanes = [None; 8];
            lanes[0] = Some((cells[0].bounds, order.place(0, 0, 0)));
            let (refs, sources) = order.finish();
            let mut layout = Layout {
                nodes: Vec::new(),
                refs,
                largest: Some(0.0),
            };
            let node = layout.wide(&lanes);
            layout.nodes.push(node);
            return (layout, sources);
        }
        let (nodes, largest): (Vec<Wide>, Vec<Option<f64>>) = order
            .nodes
            .par_iter()
            .with_min_len(64)
            .map(|&(cell, children)| Wide::new(&lanes(cells, cell, &children)))
            .unzip();
        let (refs, sources) = order.finish();
        let mut layout = Layout {
            nodes,
            refs,
            largest: Some(0.0),
        };
        for node in largest {
            layout.fold_largest(node);
        }
        (layout, sources)
    }

    /// The node for `lanes`, its largest plane folded into [`Layout::largest`].
    fn wide(&mut self, lanes: &[Option<([f32; 6], u32)>; 8]) -> Wide {
        let (node, largest) = Wide::new(lanes);
        self.fold_largest(largest);
        node
    }

    /// Folds a node's largest plane (`None`: not quantised) into [`Layout::largest`].
    fn fold_largest(&mut self, largest: Option<f64>) {
        self.largest = self.largest.zip(largest).map(|(a, b)| a.max(b));
    }

    /// The leaf that child reference `child` (with [`LEAF`] set) names: its references.
    #[inline(always)]
    pub fn leaf(&self, child: u32) -> &[u32] {
        let at = (child & !LEAF) as usize;
        let count = self.refs[at] as usize;
        &self.refs[at + HEADER..at + HEADER + count]
    }

    /// The header of the leaf `child` names (see module `leaf`).
    #[inline(always)]
    pub fn header(&self, child: u32) -> [u32; HEADER] {
        let at = (child & !LEAF) as usize;
        std::array::from_fn(|i| self.refs[at + i])
    }

    /// Bytes of the nodes and the leaves.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Wide>() + self.refs.len() * size_of::<u32>()
    }
}

/// The depth-first order of [`Layout::new`]: per node, the interior cell it is made from and
/// its children's references; the leaves' counts and references as laid out.
struct Order<'c> {
    cells: &'c [Node],
    refs: &'c [u32],
    nodes: Vec<(usize, [u32; 8])>,
    leaves: Vec<u32>,
    /// Per leaf, where it starts in `leaves` and where its references start in `refs`.
    sources: Vec<(usize, usize)>,
}

impl Order<'_> {
    /// Places cell `index`, in lane `lane` of node `parent`, and everything below it;
    /// returns its reference.
    fn place(&mut self, index: usize, parent: usize, lane: usize) -> u32 {
        let cell = self.cells[index];
        if cell.count & INTERIOR == 0 {
            let at = self.leaves.len();
            let first = cell.first as usize;
            let count = cell.count as usize;
            self.sources.push((at, first));
            self.leaves.extend_from_slice(&header(count, parent, lane));
            self.leaves
                .extend_from_slice(&self.refs[first..first + count]);
            // The boxes, filled by [`super::leaf::fill`].
            self.leaves.resize(self.leaves.len() + box_words(count), 0);
            return LEAF | at as u32;
        }
        let at = self.nodes.len();
        self.nodes.push((index, [Wide::EMPTY; 8]));
        let mut next = cell.first as usize;
        for lane in 0..8 {
            if cell.count & (1 << lane) != 0 {
                self.nodes[at].1[lane] = self.place(next, at, lane);
                next += 1;
            }
        }
        at as u32
    }
}

impl Order<'_> {
    /// The leaves' array, with the slack the leaf filter's loads need, and the leaves'
    /// sources.
    fn finish(mut self) -> (Vec<u32>, Vec<(usize, usize)>) {
        self.leaves.resize(self.leaves.len() + SLACK_WORDS, 0);
        (self.leaves, self.sources)
    }
}

/// The lanes of the node made from interior cell `index`: its non-empty children's boxes
/// (stored after each other from `first`, in octant order) with their references `children`.
fn lanes(cells: &[Node], index: usize, children: &[u32; 8]) -> [Option<([f32; 6], u32)>; 8] {
    let cell = cells[index];
    let mut lanes = [None; 8];
    let mut next = cell.first as usize;
    for (lane, slot) in lanes.iter_mut().enumerate() {
        if cell.count & (1 << lane) != 0 {
            *slot = Some((cells[next].bounds, children[lane]));
            next += 1;
        }
    }
    lanes
}
