//! The octree: cubic cells split into eight equal children, built over any [`PrimitiveSet`].
//!
//! # Build rule
//! A cell holding `n` primitive references becomes a leaf when `n <= leaf_size`, when its
//! depth reaches `max_depth`, or when splitting does not pay by the surface-area cost model:
//! a leaf costs `n · intersection_cost`; a split costs
//! `traversal_cost + Σ_children (area_child / area_cell) · n_child · intersection_cost`, where
//! every child cube has a quarter of its parent's surface area. Primitives that straddle cells
//! count in every child they touch, so splitting stops by itself where duplication outweighs
//! separation. A cell is also kept whole when one of its children would hold every one of its
//! references (the triangles around a shared vertex, say): no split can separate them there, and
//! without this rule the cost model alone keeps splitting such cells to the depth cap. A primitive goes into every child it really overlaps (exact triangle/box test;
//! see [`PrimitiveSet::overlaps`]), tested against the child cell grown by a tiny margin so that
//! rounding in the traversal can never lose a primitive lying on a cell face.
//!
//! # Traversal
//! Front to back after Revelles et al. (2000): the ray is mirrored so all direction components
//! are non-negative; the children of a cell are then met in increasing index order, and the
//! mirror mask maps that order back to the stored children. Slab parameters of child cells come
//! from the cell's midplanes, with the `0 · ∞` cases of axis-parallel rays resolved explicitly.
//!
//! The lecture's boundary trap: a primitive stored in an early cell can be hit beyond that cell's
//! exit while a nearer primitive waits in a later cell. The traversal therefore never stops at
//! the first hit: it keeps the best `t` and skips only cells whose entry lies beyond it.

use super::{Hit, PreparedRay, PrimitiveSet};
use crate::geometry::Aabb;
use glam::DVec3;
use serde::Serialize;

/// Parameters of the build rule (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OctreeParams {
    /// Cells at this depth are never split (the root has depth 0).
    pub max_depth: u32,
    /// Cells with at most this many references are never split.
    pub leaf_size: usize,
    /// Cost of visiting one interior cell, in units of one primitive test.
    pub traversal_cost: f64,
    /// Cost of one ray/primitive test.
    pub intersection_cost: f64,
}

impl Default for OctreeParams {
    fn default() -> Self {
        OctreeParams {
            max_depth: 16,
            leaf_size: 4,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
        }
    }
}

/// Size figures of a built octree.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct OctreeStats {
    /// All cells, interior and leaf.
    pub nodes: usize,
    /// Leaf cells.
    pub leaves: usize,
    /// Leaf cells without any primitive.
    pub empty_leaves: usize,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Primitive references stored in leaves (a primitive counts once per leaf).
    pub references: usize,
}

/// Marks an interior cell in [`Node::count`].
const INTERIOR: u32 = u32::MAX;

/// A cell: interior cells point at eight contiguous children, leaves at a run of references.
#[derive(Debug, Clone, Copy)]
struct Node {
    first: u32,
    count: u32,
}

/// An octree over the primitives of a [`PrimitiveSet`].
#[derive(Debug, Clone)]
pub struct Octree {
    root: Aabb,
    nodes: Vec<Node>,
    refs: Vec<u32>,
    params: OctreeParams,
    stats: OctreeStats,
}

/// One pending cell of a traversal, in the mirrored frame.
#[derive(Clone, Copy)]
struct Pending {
    node: u32,
    t0: DVec3,
    t1: DVec3,
    lo: DVec3,
    size: f64,
}

/// Deepest allowed cell; bounds the traversal stack.
const DEPTH_CAP: u32 = 24;

/// Longest possible traversal stack: a popped cell pushes at most eight children (eight only
/// when the ray passes exactly through its centre), so each level adds at most seven.
const STACK: usize = 7 * DEPTH_CAP as usize + 2;

impl Octree {
    /// Builds the octree over every primitive of `set`.
    pub fn build<P: PrimitiveSet>(set: &P, params: OctreeParams) -> Octree {
        let params = OctreeParams {
            max_depth: params.max_depth.min(DEPTH_CAP),
            ..params
        };
        let bounds = (0..set.len())
            .map(|i| set.bounds(i))
            .filter(|b| b.min.is_finite() && b.max.is_finite())
            .fold(Aabb::EMPTY, Aabb::union);
        let root = cube_around(&bounds);
        let mut tree = Octree {
            root,
            nodes: vec![Node { first: 0, count: 0 }],
            refs: Vec::new(),
            params,
            stats: OctreeStats::default(),
        };
        let all: Vec<u32> = (0..set.len() as u32).collect();
        let margin = root.size().x * 1e-9;
        tree.build_cell(set, 0, root, all, 0, margin);
        tree.stats.nodes = tree.nodes.len();
        tree.stats.references = tree.refs.len();
        tree
    }

    /// The root cell.
    pub fn root(&self) -> Aabb {
        self.root
    }

    /// Size figures.
    pub fn stats(&self) -> OctreeStats {
        self.stats
    }

    /// The parameters it was built with.
    pub fn params(&self) -> OctreeParams {
        self.params
    }

    fn build_cell<P: PrimitiveSet>(
        &mut self,
        set: &P,
        node: usize,
        cell: Aabb,
        refs: Vec<u32>,
        depth: u32,
        margin: f64,
    ) {
        match self.split(set, &cell, &refs, depth, margin) {
            Some(children) => {
                drop(refs);
                let first = self.nodes.len();
                self.nodes
                    .extend(std::iter::repeat_n(Node { first: 0, count: 0 }, 8));
                self.nodes[node] = Node {
                    first: first as u32,
                    count: INTERIOR,
                };
                for (i, child) in children.into_iter().enumerate() {
                    let child_cell = child_cell(&cell, i);
                    self.build_cell(set, first + i, child_cell, child, depth + 1, margin);
                }
            }
            None => {
                self.nodes[node] = Node {
                    first: self.refs.len() as u32,
                    count: refs.len() as u32,
                };
                self.stats.leaves += 1;
                self.stats.empty_leaves += usize::from(refs.is_empty());
                self.stats.depth = self.stats.depth.max(depth);
                self.refs.extend(refs);
            }
        }
    }

    /// The children's references if splitting `cell` pays, by the rule in the module docs.
    fn split<P: PrimitiveSet>(
        &self,
        set: &P,
        cell: &Aabb,
        refs: &[u32],
        depth: u32,
        margin: f64,
    ) -> Option<[Vec<u32>; 8]> {
        if refs.len() <= self.params.leaf_size || depth >= self.params.max_depth {
            return None;
        }
        let children = distribute(set, cell, refs, margin);
        if children.iter().any(|c| c.len() == refs.len()) {
            return None;
        }
        let child_refs: usize = children.iter().map(Vec::len).sum();
        let p = &self.params;
        let leaf_cost = refs.len() as f64 * p.intersection_cost;
        let split_cost = p.traversal_cost + 0.25 * child_refs as f64 * p.intersection_cost;
        (split_cost < leaf_cost).then_some(children)
    }

    /// The nearest hit with `0 < t <= t_max`, exactly the hit [`super::brute_force`] finds.
    pub fn intersect<P: PrimitiveSet>(
        &self,
        set: &P,
        ray: &PreparedRay<P::RayData>,
        t_max: f64,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.traverse(ray.local_origin, ray.dir, t_max, |refs, _, _| {
            for &prim in refs {
                let bound = best.map_or(t_max, |b| b.t);
                if let Some(t) = set.intersect(prim as usize, ray, bound) {
                    let hit = Hit { t, prim };
                    if hit.beats(&best) {
                        best = Some(hit);
                    }
                }
            }
            best.map_or(t_max, |b| b.t)
        });
        best
    }

    /// Visits the non-empty leaves the ray `origin + t · dir` passes through, front to back.
    ///
    /// `visit` gets the leaf's primitive indices and the ray's entry and exit parameters of the
    /// leaf, and returns the parameter beyond which nothing interests it any more (the best hit
    /// so far); leaves entered beyond that are skipped. `dir` must have no -0.0 component.
    pub fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        mut visit: impl FnMut(&[u32], f64, f64) -> f64,
    ) {
        let mut mask = 0usize;
        let mut o = origin;
        let mut d = dir;
        for axis in 0..3 {
            if d[axis] < 0.0 {
                mask |= 1 << axis;
                o[axis] = self.root.min[axis] + self.root.max[axis] - o[axis];
                d[axis] = -d[axis];
            }
        }
        let inv = d.recip();
        let t0 = nan_to((self.root.min - o) * inv, f64::NEG_INFINITY);
        let t1 = nan_to((self.root.max - o) * inv, f64::INFINITY);
        let mut limit = t_max;
        let mut stack = [Pending {
            node: 0,
            t0,
            t1,
            lo: self.root.min,
            size: self.root.size().x,
        }; STACK];
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let cell = stack[len];
            let enter = cell.t0.max_element().max(0.0);
            let exit = cell.t1.min_element().min(limit);
            if enter > exit {
                continue;
            }
            let node = self.nodes[cell.node as usize];
            if node.count != INTERIOR {
                if node.count > 0 {
                    let refs = &self.refs[node.first as usize..(node.first + node.count) as usize];
                    limit = limit.min(visit(refs, enter, exit));
                }
                continue;
            }
            let half = cell.size * 0.5;
            let tm = nan_to((cell.lo + DVec3::splat(half) - o) * inv, f64::INFINITY);
            for i in (0..8).rev() {
                let upper = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
                let pick = |a: DVec3, b: DVec3| {
                    DVec3::new(
                        if upper[0] { b.x } else { a.x },
                        if upper[1] { b.y } else { a.y },
                        if upper[2] { b.z } else { a.z },
                    )
                };
                let child = Pending {
                    node: node.first + (i ^ mask) as u32,
                    t0: pick(cell.t0, tm),
                    t1: pick(tm, cell.t1),
                    lo: cell.lo + pick(DVec3::ZERO, DVec3::splat(half)),
                    size: half,
                };
                if child.t0.max_element().max(0.0) <= child.t1.min_element().min(limit) {
                    stack[len] = child;
                    len += 1;
                }
            }
        }
    }
}

/// Replaces NaN components (from `0 · ∞` when a ray lies in a cell plane) by `value`.
fn nan_to(v: DVec3, value: f64) -> DVec3 {
    DVec3::new(
        if v.x.is_nan() { value } else { v.x },
        if v.y.is_nan() { value } else { v.y },
        if v.z.is_nan() { value } else { v.z },
    )
}

/// The smallest cube holding `bounds` with a little room, or a unit cube for an empty box.
fn cube_around(bounds: &Aabb) -> Aabb {
    if bounds.is_empty() {
        return Aabb::new(DVec3::splat(-0.5), DVec3::splat(0.5));
    }
    let centre = bounds.center();
    let extent = bounds.size().max_element();
    let half = (extent * 0.5) * (1.0 + 1e-6) + 1e-6 * (centre.abs().max_element() + 1.0) * 1e-3;
    Aabb::new(centre - DVec3::splat(half), centre + DVec3::splat(half))
}

/// Child `i` of a cubic cell: bit 0 selects the upper x half, bit 1 y, bit 2 z.
fn child_cell(cell: &Aabb, i: usize) -> Aabb {
    let half = cell.size() * 0.5;
    let offset = DVec3::new(
        if i & 1 != 0 { half.x } else { 0.0 },
        if i & 2 != 0 { half.y } else { 0.0 },
        if i & 4 != 0 { half.z } else { 0.0 },
    );
    let min = cell.min + offset;
    Aabb::new(min, min + half)
}

/// Sorts the references of `cell` into its eight children. A primitive whose bounds fall in
/// one child goes there directly; one whose bounds span several is tested exactly against each.
fn distribute<P: PrimitiveSet>(set: &P, cell: &Aabb, refs: &[u32], margin: f64) -> [Vec<u32>; 8] {
    let mid = cell.center();
    let mut children: [Vec<u32>; 8] = Default::default();
    for &prim in refs {
        let b = set.bounds(prim as usize);
        for (i, child) in children.iter_mut().enumerate() {
            let grown = child_cell(cell, i).expanded(margin);
            if !grown.overlaps(&b) {
                continue;
            }
            let inside_one =
                (0..3).all(|a| b.max[a] < mid[a] - margin || b.min[a] > mid[a] + margin);
            if inside_one || set.overlaps(prim as usize, &grown) {
                child.push(prim);
            }
        }
    }
    children
}
