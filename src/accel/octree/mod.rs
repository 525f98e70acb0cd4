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
//! count. Each interior cell records which children hold any primitive; empty children are not
//! stored, and traversal never descends into them.
//!
//! Every cell also records the box its primitives occupy inside it (for a leaf, the bounds of
//! its triangles clipped to the cell; for an interior cell, the union of its children's),
//! grown by the margin and rounded outward onto a grid of 255 steps across the cell, so it
//! costs six bytes. A ray that misses a cell's occupied box skips the cell: cubic cells hold
//! much empty space around a surface, and this removes most of it from traversal.
//!
//! # Traversal
//! Front to back after Revelles et al. (2000): the ray is mirrored so all direction components
//! are non-negative; in a cell, the first child crossed follows from the entry plane and the
//! midplane parameters, and each next child from the current child's exit plane, so only the
//! (at most four) children the ray really crosses are visited, in order. The mirror mask maps
//! them back to the stored children. A cell's own entry and exit parameters are those of its
//! cube clipped to its occupied box. Slab parameters of child cells come from the cell's
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
            leaf_size: 12,
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
    /// Empty leaves: octants of interior cells without any primitive (not stored), or the
    /// root of an empty tree.
    pub empty_leaves: usize,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Primitive references stored in leaves (a primitive counts once per leaf).
    pub references: usize,
}

/// Set in [`Node::count`] for interior cells; the low eight bits then flag non-empty children.
const INTERIOR: u32 = 1 << 31;

/// `RANK[mask][i]`: how many of the children flagged in `mask` come before child `i`, i.e.
/// where child `i` is stored among its parent's non-empty children.
static RANK: [[u8; 8]; 256] = {
    let mut rank = [[0; 8]; 256];
    let mut mask = 0;
    while mask < 256 {
        let mut i = 0;
        while i < 8 {
            rank[mask][i] = (mask & ((1 << i) - 1)).count_ones() as u8;
            i += 1;
        }
        mask += 1;
    }
    rank
};

/// Deepest allowed cell; bounds the recursion of a traversal.
const DEPTH_CAP: u32 = 24;

/// A cell: interior cells point at their non-empty children (stored contiguously, in octant
/// order), leaves at a run of references; every cell also bounds the part of it that its
/// primitives occupy.
#[derive(Debug, Clone, Copy)]
struct Node {
    first: u32,
    count: u32,
    occupied: Occupied,
}

/// The occupied part of a cell, as planes on a grid of 255 steps across the cell, rounded
/// outward: levels `[lo x, lo y, lo z, hi x, hi y, hi z]`; on each axis the box spans
/// `PLANE[lo]..PLANE[hi]` of the cell's edge, where level 0 and 255 stand for no bound at all
/// (the cell's own faces then limit the ray).
#[derive(Debug, Clone, Copy)]
struct Occupied([u8; 6]);

/// Plane positions of [`Occupied`] levels as fractions of the cell's edge.
static PLANE: [f64; 256] = {
    let mut planes = [0.0; 256];
    let mut level = 1;
    while level < 255 {
        planes[level] = level as f64 / 255.0;
        level += 1;
    }
    planes[0] = f64::NEG_INFINITY;
    planes[255] = f64::INFINITY;
    planes
};

/// [`PLANE`] seen from a mirrored axis: the plane of level `l` at `1 - PLANE[l]`, which is
/// `PLANE[255 - l]`.
static PLANE_MIRRORED: [f64; 256] = {
    let mut planes = [0.0; 256];
    let mut level = 0;
    while level < 256 {
        planes[level] = PLANE[255 - level];
        level += 1;
    }
    planes
};

impl Occupied {
    /// The levels of `cell`'s grid that enclose `occupied`. Each level's plane is
    /// `cell.min + level · edge / 255`; the levels are rounded outward, so the planes
    /// enclose `occupied` up to one rounding of that sum, far less than the build margin
    /// `occupied` already carries.
    fn around(occupied: &Aabb, cell: &Aabb) -> Occupied {
        let lo = ((occupied.min - cell.min) / cell.size() * 255.0).floor();
        let hi = ((occupied.max - cell.min) / cell.size() * 255.0).ceil();
        let level = |v: f64, min: f64, max: f64| v.clamp(min, max) as u8;
        let lo = lo.to_array().map(|v| level(v, 0.0, 254.0));
        let hi = hi.to_array().map(|v| level(v, 1.0, 255.0));
        Occupied([lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]])
    }

    /// The ray's entry and exit parameters of the box, per axis, in the mirrored frame of
    /// `ray`, for a cell whose lower corner (in that frame) is `lo` with edge `size`. A
    /// mirrored axis takes its lower plane from the stored upper level and the other way
    /// round, reflected (see [`Mirrored::planes`]). A ray lying in a box plane gets NaN there,
    /// which `f64::max`/`min` then ignore.
    fn span(&self, ray: &Mirrored, lo: DVec3, size: f64) -> (DVec3, DVec3) {
        let plane = |axis: usize, side: usize| {
            let (level, table) = ray.planes[axis];
            table[self.0[level[side]] as usize]
        };
        let low = DVec3::new(plane(0, 0), plane(1, 0), plane(2, 0));
        let high = DVec3::new(plane(0, 1), plane(1, 1), plane(2, 1));
        (
            (lo + low * size - ray.origin) * ray.inv_dir,
            (lo + high * size - ray.origin) * ray.inv_dir,
        )
    }
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
    /// Per axis: which stored [`Occupied`] levels give the ray's lower and upper plane, and
    /// the table placing them ([`PLANE_MIRRORED`] with the levels swapped on mirrored axes).
    planes: [([usize; 2], &'static [f64; 256]); 3],
}

/// One cell on the way down, in the mirrored frame: its node, the ray's slab parameters and
/// the cell's lower corner and edge length.
#[derive(Clone, Copy)]
struct Cell {
    node: Node,
    t0: DVec3,
    t1: DVec3,
    lo: DVec3,
    size: f64,
}

impl Cell {
    /// The ray's entry and exit parameters of the cell clipped to its occupied box, with
    /// `0 <= t <= limit`, or `None` when that is empty.
    fn span(&self, ray: &Mirrored, limit: f64) -> Option<(f64, f64)> {
        let (b0, b1) = self.node.occupied.span(ray, self.lo, self.size);
        let enter = self.t0.max(b0).max_element().max(0.0);
        let exit = self.t1.min(b1).min_element().min(limit);
        (enter <= exit).then_some((enter, exit))
    }
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
    /// leaf's occupied box (clipped to the cell), and returns the parameter beyond which
    /// nothing interests it any more (the best hit so far); cells entered beyond that are
    /// skipped. `dir` must have no -0.0 component.
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
            planes: [0, 1, 2].map(|axis| ([axis, axis + 3], &PLANE)),
        };
        let mut d = dir;
        for axis in 0..3 {
            if d[axis] < 0.0 {
                ray.mask |= 1 << axis;
                ray.planes[axis] = ([axis + 3, axis], &PLANE_MIRRORED);
                ray.origin[axis] = self.root.min[axis] + self.root.max[axis] - origin[axis];
                d[axis] = -d[axis];
            }
        }
        ray.inv_dir = d.recip();
        let root = Cell {
            node: self.nodes[0],
            t0: nan_to(
                (self.root.min - ray.origin) * ray.inv_dir,
                f64::NEG_INFINITY,
            ),
            t1: nan_to((self.root.max - ray.origin) * ray.inv_dir, f64::INFINITY),
            lo: self.root.min,
            size: self.root.size().x,
        };
        let mut limit = t_max;
        if let Some((enter, exit)) = root.span(&ray, limit) {
            self.visit_cell(&root, enter, exit, &ray, &mut limit, &mut visit);
        }
    }

    /// Visits `cell`, which the ray enters at `enter` and leaves at `exit` (its cube clipped
    /// to its occupied box and to the limit): a leaf goes to `visit`; an interior cell visits
    /// those of its children the ray crosses, front to back, computing each child's span
    /// before descending so that children whose occupied box the ray misses cost no call.
    fn visit_cell<F: FnMut(&[u32], f64, f64) -> f64>(
        &self,
        cell: &Cell,
        enter: f64,
        exit: f64,
        ray: &Mirrored,
        limit: &mut f64,
        visit: &mut F,
    ) {
        let node = cell.node;
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
            let t1 = pick(tm, cell.t1);
            let stored = child ^ ray.mask;
            if node.count & (1 << stored) != 0 {
                let index = node.first + u32::from(RANK[(node.count & 0xFF) as usize][stored]);
                let next = Cell {
                    node: self.nodes[index as usize],
                    t0: pick(cell.t0, tm),
                    t1,
                    lo: cell.lo + pick(DVec3::ZERO, DVec3::splat(half)),
                    size: half,
                };
                if let Some((enter, exit)) = next.span(ray, *limit) {
                    self.visit_cell(&next, enter, exit, ray, limit, visit);
                }
            }
            let exit_axis = if t1.x <= t1.y && t1.x <= t1.z {
                0
            } else if t1.y <= t1.z {
                1
            } else {
                2
            };
            if child & (1 << exit_axis) != 0 || t1[exit_axis] > *limit {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The plane of `level` for a cell from `lo` with edge `size`.
    fn plane(lo: f64, size: f64, level: u8) -> f64 {
        lo + PLANE[level as usize] * size
    }

    #[test]
    fn occupied_levels_enclose_the_box() {
        let cell = Aabb::new(DVec3::new(-3.0, 0.5, 10.0), DVec3::new(-1.0, 2.5, 12.0));
        let size = 2.0;
        for k in 0..200 {
            let f = |i: u32| ((k * 37 + i * 101) % 997) as f64 / 997.0;
            let a = cell.min + DVec3::new(f(1), f(2), f(3)) * size;
            let b = cell.min + DVec3::new(f(4), f(5), f(6)) * size;
            let occupied = Aabb::new(a.min(b), a.max(b));
            let q = Occupied::around(&occupied, &cell);
            for axis in 0..3 {
                assert!(plane(cell.min[axis], size, q.0[axis]) <= occupied.min[axis]);
                assert!(plane(cell.min[axis], size, q.0[axis + 3]) >= occupied.max[axis]);
                // Rounded outward by less than one step; level 0 (no bound) only within the
                // first step of the cell.
                let below = plane(cell.min[axis], size, q.0[axis]).max(cell.min[axis]);
                assert!(occupied.min[axis] - below < size / 255.0);
            }
        }
        // Beyond the cell on a side: no bound there.
        let wide = Aabb::new(DVec3::new(-3.5, 1.0, 10.5), DVec3::new(-2.0, 3.0, 11.0));
        let q = Occupied::around(&wide, &cell);
        assert_eq!((q.0[0], q.0[4]), (0, 255));
    }

    #[test]
    fn mirrored_span_is_the_same_interval() {
        // The cell [0, 1]^3 of a root [0, 2]^3, occupied box [0.25, 0.5]^3, and a ray going
        // towards -x: traversal sees the mirrored frame, where the cell spans [1, 2] on x.
        let cell = Aabb::new(DVec3::ZERO, DVec3::ONE);
        let q = Occupied::around(&Aabb::new(DVec3::splat(0.25), DVec3::splat(0.5)), &cell);
        let origin = DVec3::new(0.9, 0.3, 0.3);
        let dir = DVec3::new(-1.0, 0.05, 0.02);
        let ray = Mirrored {
            origin: DVec3::new(2.0 - origin.x, origin.y, origin.z),
            inv_dir: dir.abs().recip(),
            mask: 1,
            planes: [
                ([3, 0], &PLANE_MIRRORED),
                ([1, 4], &PLANE),
                ([2, 5], &PLANE),
            ],
        };
        let (t0, t1) = q.span(&ray, DVec3::new(1.0, 0.0, 0.0), 1.0);
        // Unmirrored, the ray enters the box at its upper x plane and leaves at the lower.
        let enter_x = origin.x - plane(0.0, 1.0, q.0[3]);
        let exit_x = origin.x - plane(0.0, 1.0, q.0[0]);
        assert!((t0.x - enter_x).abs() < 1e-15 && (t1.x - exit_x).abs() < 1e-15);
        assert!(enter_x < exit_x);
        let enter_y = (plane(0.0, 1.0, q.0[1]) - origin.y) / dir.y;
        let exit_y = (plane(0.0, 1.0, q.0[4]) - origin.y) / dir.y;
        assert!((t0.y - enter_y).abs() < 1e-13 && (t1.y - exit_y).abs() < 1e-13);
    }
}
