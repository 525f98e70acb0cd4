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
//! references while others hold copies of some (the triangles around a shared vertex, say): no
//! split can separate them there, and without this rule the cost model alone keeps splitting such
//! cells to the depth cap. (When all references fall into one child and no other, the split goes
//! ahead: it only shrinks the cell around them.) A primitive goes into every child it really overlaps (exact triangle/box test;
//! see [`PrimitiveSet::overlaps`]), tested against the child cell grown by a tiny margin so that
//! rounding in the traversal can never lose a primitive lying on a cell face.
//!
//! Large cells build their eight subtrees in parallel; the result does not depend on the thread
//! count. Each interior cell records which children hold any primitive, so traversal never
//! descends into empty ones.
//!
//! # Traversal
//! Front to back after Revelles et al. (2000): the ray is mirrored so all direction components
//! are non-negative; in a cell, the first child crossed follows from the entry plane and the
//! midplane parameters, and each next child from the current child's exit plane, so only the
//! (at most four) children the ray really crosses are visited, in order. The mirror mask maps
//! them back to the stored children. Slab parameters of child cells come from the cell's
//! midplanes, with the `0 · ∞` cases of axis-parallel rays resolved explicitly.
//!
//! The lecture's boundary trap: a primitive stored in an early cell can be hit beyond that cell's
//! exit while a nearer primitive waits in a later cell. The traversal therefore never stops at
//! the first hit: it keeps the best `t` and skips only cells whose entry lies beyond it.

mod build;

use super::{test_primitive, Hit, PreparedRay, PrimitiveSet};
use crate::geometry::Aabb;
use build::{cube_around, Builder};
use glam::DVec3;
use serde::Serialize;

/// Parameters of the build rule (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OctreeParams {
    /// Cells at this depth are never split (the root has depth 0); at most 24.
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
            leaf_size: 8,
            traversal_cost: 2.0,
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

/// Set in [`Node::count`] for interior cells; the low eight bits then flag non-empty children.
const INTERIOR: u32 = 1 << 31;

/// Deepest allowed cell; bounds the recursion of a traversal.
const DEPTH_CAP: u32 = 24;

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

/// A ray mirrored into the frame where every direction component is non-negative.
struct Mirrored {
    origin: DVec3,
    inv_dir: DVec3,
    mask: usize,
}

/// One cell on the way down, in the mirrored frame: the ray's slab parameters and the cell's
/// lower corner and edge length.
#[derive(Clone, Copy)]
struct Cell {
    node: u32,
    t0: DVec3,
    t1: DVec3,
    lo: DVec3,
    size: f64,
}

impl Octree {
    /// Builds the octree over every primitive of `set`.
    pub fn build<P: PrimitiveSet>(set: &P, params: OctreeParams) -> Octree {
        let params = OctreeParams {
            max_depth: params.max_depth.min(DEPTH_CAP),
            ..params
        };
        let bounds: Vec<Aabb> = (0..set.len()).map(|i| set.bounds(i)).collect();
        let finite = bounds
            .iter()
            .filter(|b| b.min.is_finite() && b.max.is_finite())
            .fold(Aabb::EMPTY, |a, b| a.union(*b));
        let root = cube_around(&finite);
        let builder = Builder {
            set,
            bounds,
            params,
            margin: root.size().x * 1e-9,
        };
        let all: Vec<u32> = (0..set.len() as u32).collect();
        let tree = builder.subtree(root, all, 0);
        Octree {
            root,
            nodes: tree.nodes,
            refs: tree.refs,
            params,
            stats: tree.stats,
        }
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

    /// Bytes of the octree's own arrays (cells and references, not the primitives).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.refs.len() * 4
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
                test_primitive(set, prim, ray, t_max, &mut best);
            }
            best.map_or(t_max, |b| b.t)
        });
        best
    }

    /// Visits the non-empty leaves the ray `origin + t · dir` passes through, front to back.
    ///
    /// `visit` gets the leaf's primitive indices and the ray's entry and exit parameters of the
    /// leaf, and returns the parameter beyond which nothing interests it any more (the best hit
    /// so far); cells entered beyond that are skipped. `dir` must have no -0.0 component.
    pub fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        mut visit: impl FnMut(&[u32], f64, f64) -> f64,
    ) {
        let mut ray = Mirrored {
            origin,
            inv_dir: DVec3::ZERO,
            mask: 0,
        };
        let mut d = dir;
        for axis in 0..3 {
            if d[axis] < 0.0 {
                ray.mask |= 1 << axis;
                ray.origin[axis] = self.root.min[axis] + self.root.max[axis] - origin[axis];
                d[axis] = -d[axis];
            }
        }
        ray.inv_dir = d.recip();
        let root = Cell {
            node: 0,
            t0: nan_to(
                (self.root.min - ray.origin) * ray.inv_dir,
                f64::NEG_INFINITY,
            ),
            t1: nan_to((self.root.max - ray.origin) * ray.inv_dir, f64::INFINITY),
            lo: self.root.min,
            size: self.root.size().x,
        };
        let mut limit = t_max;
        self.visit_cell(&root, &ray, &mut limit, &mut visit);
    }

    fn visit_cell<F: FnMut(&[u32], f64, f64) -> f64>(
        &self,
        cell: &Cell,
        ray: &Mirrored,
        limit: &mut f64,
        visit: &mut F,
    ) {
        let enter = cell.t0.max_element().max(0.0);
        let exit = cell.t1.min_element().min(*limit);
        if enter > exit {
            return;
        }
        let node = self.nodes[cell.node as usize];
        if node.count & INTERIOR == 0 {
            if node.count > 0 {
                let refs = &self.refs[node.first as usize..(node.first + node.count) as usize];
                *limit = limit.min(visit(refs, enter, exit));
            }
            return;
        }
        let half = cell.size * 0.5;
        let tm = nan_to(
            (cell.lo + DVec3::splat(half) - ray.origin) * ray.inv_dir,
            f64::INFINITY,
        );
        let mut child = first_child(cell.t0, tm);
        loop {
            let upper = [child & 1 != 0, child & 2 != 0, child & 4 != 0];
            let pick = |a: DVec3, b: DVec3| {
                DVec3::new(
                    if upper[0] { b.x } else { a.x },
                    if upper[1] { b.y } else { a.y },
                    if upper[2] { b.z } else { a.z },
                )
            };
            let next = Cell {
                node: 0,
                t0: pick(cell.t0, tm),
                t1: pick(tm, cell.t1),
                lo: cell.lo + pick(DVec3::ZERO, DVec3::splat(half)),
                size: half,
            };
            let stored = child ^ ray.mask;
            if node.count & (1 << stored) != 0 {
                let next = Cell {
                    node: node.first + stored as u32,
                    ..next
                };
                self.visit_cell(&next, ray, limit, visit);
            }
            let exit_axis = if next.t1.x <= next.t1.y && next.t1.x <= next.t1.z {
                0
            } else if next.t1.y <= next.t1.z {
                1
            } else {
                2
            };
            if child & (1 << exit_axis) != 0 || next.t1[exit_axis] > *limit {
                return;
            }
            child |= 1 << exit_axis;
        }
    }
}

/// The first child (mirrored index) a ray crosses, from the cell's entry parameters `t0` and
/// midplane parameters `tm`: the entry plane is the last slab entered; on the other axes the
/// ray starts in the upper half if it crossed that midplane before entering the cell.
fn first_child(t0: DVec3, tm: DVec3) -> usize {
    let enter = t0.max_element();
    let mut child = 0;
    for axis in 0..3 {
        if tm[axis] < enter {
            child |= 1 << axis;
        }
    }
    child
}

/// Replaces NaN components (from `0 · ∞` when a ray lies in a cell plane) by `value`.
fn nan_to(v: DVec3, value: f64) -> DVec3 {
    DVec3::new(
        if v.x.is_nan() { value } else { v.x },
        if v.y.is_nan() { value } else { v.y },
        if v.z.is_nan() { value } else { v.z },
    )
}
