//! The octree: cubic cells split into eight equal children, built over any [`PrimitiveSet`].
//!
//! # Build rule
//! Each reference weighs what testing its primitive costs ([`PrimitiveSet::cost`]: 1 for a
//! triangle, `Quadric::TEST_COST` for a quadric), and a cell's weight `w` is the sum over its
//! references. A cell becomes a leaf when `w <= leaf_size` (`triangle_leaf_size`, twice as
//! large, for a set of triangles alone), when it holds a single reference,
//! when its depth reaches `max_depth`, or when splitting does not pay by the surface-area cost
//! model: a leaf costs `w · intersection_cost`; a split costs
//! `traversal_cost + Σ_children (area_child / area_cell) · w_child · intersection_cost`, where
//! every child cube has a quarter of its parent's surface area. For triangles alone the weights
//! are the reference counts; cells of quadrics, which cost about three triangle tests each,
//! split into smaller leaves (reports/octree_profile.md has the measurements behind the
//! weight). Primitives that straddle cells count in every child they touch, so splitting stops
//! by itself where duplication outweighs separation. The model compares costs for a ray that
//! enters the cell, so it would keep splitting tiny cells around clusters of vertices (the
//! OpenChessSet's board, stacked layers 1e-4 apart, reached depth 15 and 15.6 references per
//! triangle) although few rays ever enter them. So a split must also save, per ray through
//! the root (a ray enters a cell at depth `d` with probability `4^-d`), at least
//! `DUPLICATION_COST` (1e-6) tests for each reference weight it adds:
//! `4^-d · (leaf − split) ≥ 1e-6 · (Σ_children w_child − w)`. A cell is also kept whole when
//! one of its children would hold every one of its references while others hold copies of some (the
//! triangles around a shared vertex, say): no split can separate them there, and without this
//! rule the cost model alone keeps splitting such cells to the depth cap. (When all references
//! fall into one child and no other, the split goes ahead: it only shrinks the cell around
//! them.) A primitive goes into every child it really overlaps (exact triangle/box test; see
//! [`PrimitiveSet::overlaps`]), tested against the child cell grown by a tiny margin, so that a
//! primitive lying on a cell face belongs to the cells on both sides. (Rounding in the
//! traversal is covered separately, by the rounding bound of the node test.)
//!
//! Large cells build their eight subtrees in parallel; the result does not depend on the thread
//! count. Each interior cell records which children hold any primitive; empty children are not
//! stored, and traversal never descends into them.
//!
//! Every cell also records the box its primitives occupy inside it (for a leaf, the bounds of
//! its triangles clipped to the cell; for an interior cell, the union of its children's),
//! grown by the margin and rounded outward to f32. A ray that misses a cell's occupied box
//! skips the cell: cubic cells hold much empty space around a surface, and this removes most
//! of it from traversal.
//!
//! # Traversal
//! Cells are traversed as eight-wide nodes (module `wide`): an interior cell holds its eight
//! children's occupied boxes, one SIMD lane per octant, as one byte per plane on a grid of the
//! node's own (rounded outward again, and decoded exactly to f32), and one test
//! (module `lanes`: AVX2 with FMA when the CPU has it, else portable code the compiler
//! vectorises) tells which children the ray enters and where. The test is conservative: the
//! f32 interval of every lane contains the exact one, with a rounding bound that grows with the
//! origin's distance. Children go front to back by lane index XOR the ray's octant (the sign
//! bits of its direction), which for an octree's equal halves is exact; the hit ones wait on a
//! fixed stack with their entry parameters, nearest on top.
//!
//! Rays in runs of eight whose directions share an octant (a camera's neighbouring pixels) can
//! also go as one packet (module `packet`, [`Octree::intersect_packet`]): a node is fetched
//! once for the eight, each child's box is tested against all eight rays in one SIMD test,
//! and the rays share the stack; in a leaf, each primitive is tested against the packet's rays
//! that reach it together ([`PrimitiveSet::intersect_packet`]). A ray alone tests a leaf's
//! primitives four at a time ([`PrimitiveSet::intersect_group`]). Every ray still gets exactly
//! its own answer.
//!
//! A leaf also stores, per reference, the box of its primitive's part in the leaf (module
//! `leaf`): the node test run over those boxes, eight references at a time and with the best
//! hit as the limit, drops the primitives a ray (or each ray of a packet) cannot hit there
//! before its best hit, so that the exact tests run on the others only.
//!
//! The lecture's boundary trap: a primitive stored in an early cell can be hit beyond that cell's
//! exit while a nearer primitive waits in a later cell. The traversal therefore never stops at
//! the first hit: it keeps the best `t` and skips only cells whose entry lies beyond it. A hit
//! point of a primitive lies in the occupied box of every cell on the way down to a leaf
//! holding it, so that leaf is reached whenever the hit is not beyond the best one: the answer
//! is exactly brute force's, for any kernel.

mod arena;
mod build;
mod cells;
mod lanes;
mod layout;
mod leaf;
mod nearest;
mod notes;
mod packet;
mod probe;
mod traverse;
mod wide;

use super::{
    f32_above, prepare_ray_with, set_bits, Hit, PacketCrossings, PreparedRay, PrimitiveSet, GROUP,
};
use crate::geometry::Aabb;
pub use crate::simd::Kernel;
use build::cube_around;
use cells::Builder;
use glam::DVec3;
use lanes::Lanes;
use layout::Layout;
pub use notes::{Notes, Offered, Unnoted, OFFERED};
pub use packet::WIDTH as PACKET;
use rayon::prelude::*;
use serde::Serialize;
use traverse::Unobserved;

/// Parameters of the build rule (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct OctreeParams {
    /// Cells at this depth are never split (the root has depth 0); at most 24.
    pub max_depth: u32,
    /// Cells whose references weigh at most this much (this many triangles) are never split.
    pub leaf_size: usize,
    /// [`OctreeParams::leaf_size`] for a set of triangles alone
    /// ([`PrimitiveSet::triangles_only`]).
    pub triangle_leaf_size: usize,
    /// Cost of visiting one interior cell, in units of one triangle test.
    pub traversal_cost: f64,
    /// Cost of one ray/triangle test; a reference costs this times its primitive's
    /// [`PrimitiveSet::cost`].
    pub intersection_cost: f64,
}

impl Default for OctreeParams {
    fn default() -> Self {
        OctreeParams {
            max_depth: 16,
            leaf_size: 12,
            triangle_leaf_size: 24,
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

/// Deepest allowed cell; bounds the traversal stack.
const DEPTH_CAP: u32 = 24;

/// An octree over the primitives of a [`PrimitiveSet`].
#[derive(Debug, Clone)]
pub struct Octree {
    root: Aabb,
    layout: Layout,
    /// The largest magnitude of any stored plane (infinite when the planes could not be
    /// quantised; no axis then culls).
    scale: f64,
    kernel: Kernel,
    params: OctreeParams,
    stats: OctreeStats,
}

impl Octree {
    /// Builds the octree over every primitive of `set`.
    pub fn build<P: PrimitiveSet>(set: &P, params: OctreeParams) -> Octree {
        let params = OctreeParams {
            max_depth: params.max_depth.min(DEPTH_CAP),
            ..params
        };
        let bounds: Vec<Aabb> = (0..set.len())
            .into_par_iter()
            .map(|i| set.bounds(i))
            .collect();
        let finite = bounds
            .iter()
            .filter(|b| b.min.is_finite() && b.max.is_finite())
            .fold(Aabb::EMPTY, |a, b| a.union(*b));
        let root = cube_around(&finite);
        let margin = root.size().x * 1e-9;
        // Only a set with a primitive that does not cost 1 keeps a cost per primitive.
        let costs = (0..set.len())
            .into_par_iter()
            .any(|i| set.cost(i) != 1.0)
            .then(|| (0..set.len()).map(|i| set.cost(i)).collect());
        let leaf_size = if set.triangles_only() {
            params.triangle_leaf_size
        } else {
            params.leaf_size
        };
        let builder = Builder {
            set,
            bounds,
            costs,
            params: OctreeParams {
                leaf_size,
                ..params
            },
            margin,
        };
        let all: Vec<u32> = (0..set.len() as u32).collect();
        let budget = cells::MAX_REFERENCES_PER_PRIMITIVE * all.len() as f64;
        let tree = builder.subtree(&root, all, 0, budget);
        let (mut layout, sources) = Layout::new(&tree.nodes, &tree.refs);
        leaf::fill(&mut layout, &sources, &tree.parts);
        // The largest stored plane bounds the node test's rounding; a tree whose planes could
        // not all be quantised does not cull.
        let scale = layout
            .largest
            .filter(|&largest| largest <= wide::LIMIT)
            .unwrap_or(f64::INFINITY);
        Octree {
            root,
            layout,
            scale,
            kernel: Kernel::detect(),
            params,
            stats: tree.stats,
        }
    }

    /// The same octree traversed with `kernel`, or `None` when this CPU cannot run it.
    pub fn with_kernel(self, kernel: Kernel) -> Option<Octree> {
        kernel.available().then_some(Octree { kernel, ..self })
    }

    /// The node test in use.
    pub fn kernel(&self) -> Kernel {
        self.kernel
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

    /// Bytes of the octree's own arrays (nodes, and the leaves' counts and references; not
    /// the primitives).
    pub fn bytes(&self) -> usize {
        self.layout.bytes()
    }

    /// The nearest hit with `0 < t <= t_max`, exactly the hit [`super::brute_force`] finds.
    pub fn intersect<P: PrimitiveSet>(
        &self,
        set: &P,
        ray: &PreparedRay<P::RayData>,
        t_max: f64,
    ) -> Option<Hit> {
        let local = (ray.local_origin, ray.dir);
        self.intersect_preparing(set, local, t_max, (ray.kernel, || *ray))
    }

    /// The nearest hit with `0 < t <= t_max` of the ray `local_origin + t · dir`, exactly the
    /// hit [`super::brute_force`] finds, for a ray whose primitive data the caller prepares:
    /// `prepare()` gives it prepared for `kernel` (with this `local_origin` and `dir`), asked
    /// for once the ray reaches a leaf. The mapped rays of an instance come this way (their
    /// set-up is made from the origin in the mesh frame, not from the anchored one).
    pub fn intersect_preparing<P: PrimitiveSet>(
        &self,
        set: &P,
        (local_origin, dir): (DVec3, DVec3),
        t_max: f64,
        (kernel, prepare): (Kernel, impl Fn() -> PreparedRay<P::RayData> + Copy),
    ) -> Option<Hit> {
        let ray = (local_origin, dir, (kernel, prepare));
        self.intersect_with(set, ray, t_max, &mut Unnoted)
    }

    /// [`Octree::intersect_preparing`] for a ray prepared by [`super::prepare_ray`] (only
    /// when it reaches a leaf: most camera rays reach none).
    pub fn intersect_ray<P: PrimitiveSet>(
        &self,
        set: &P,
        local_origin: DVec3,
        dir: DVec3,
        t_max: f64,
    ) -> Option<Hit> {
        self.intersect_ray_noting(set, local_origin, dir, t_max, &mut Unnoted)
    }

    /// [`Octree::intersect_ray`] that tells `notes` what it offers the ray and keeps its limit
    /// at `notes.reach` of its best hit (module `notes`): the same hit.
    pub fn intersect_ray_noting<P: PrimitiveSet>(
        &self,
        set: &P,
        local_origin: DVec3,
        dir: DVec3,
        t_max: f64,
        notes: &mut impl Notes,
    ) -> Option<Hit> {
        let kernel = self.kernel;
        let prepare = move || prepare_ray_with(set, kernel, local_origin, dir);
        self.intersect_with(set, (local_origin, dir, (kernel, prepare)), t_max, notes)
    }

    /// [`Octree::intersect_preparing`] for the ray `(local_origin, dir, (kernel, prepare))`,
    /// and `notes` told what the ray is offered (the ray is number 0 to them).
    #[allow(clippy::type_complexity)]
    fn intersect_with<P: PrimitiveSet, N: Notes>(
        &self,
        set: &P,
        (local_origin, dir, (kernel, prepare)): (
            DVec3,
            DVec3,
            (Kernel, impl Fn() -> PreparedRay<P::RayData> + Copy),
        ),
        t_max: f64,
        notes: &mut N,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let mut own = None;
        let mut tested = Mailbox::default();
        let lanes = Lanes::new(local_origin, dir + DVec3::ZERO, self.scale);
        let visit = |child, _, _| {
            let ray: &_ = own.get_or_insert_with(prepare);
            let bound = f32_above(best.map_or(t_max, |b| notes.reach(b.t)));
            let prims = self.layout.leaf(child);
            let mut batch = Batch::default();
            // Eight references' boxes to a filter test (a written-out loop: the iterator it
            // replaced cost about 26 instructions more per incoherent bunny ray).
            for first in (0..prims.len()).step_by(8) {
                let kept = leaf::chunk_mask(&self.layout, kernel, child, first, &lanes, bound);
                for j in set_bits(kept) {
                    let prim = prims[first + j];
                    if tested.check_in(prim) {
                        batch.push(set, prim, ray, (t_max, &mut best), (&mut *notes, 0));
                    }
                }
            }
            batch.finish(set, ray, (t_max, &mut best), (&mut *notes, 0));
            best.map_or(t_max, |b| notes.reach(b.t))
        };
        traverse::run(&self.layout, kernel, &lanes, t_max, visit, &mut Unobserved);
        best
    }

    /// [`Octree::intersect_ray`] for [`PACKET`] rays at once, traversing the octree together
    /// (module `packet`): each ray's answer is the one it gets alone. `None` when the rays
    /// cannot go as one packet: their directions' signs differ, or some direction has a zero
    /// component (the caller then traces them one by one).
    pub fn intersect_packet<P: PrimitiveSet>(
        &self,
        set: &P,
        local_origins: &[DVec3; PACKET],
        dirs: &[DVec3; PACKET],
        t_max: &[f64; PACKET],
    ) -> Option<[Option<Hit>; PACKET]> {
        let mut best = [None; PACKET];
        self.intersect_packet_noting(set, local_origins, dirs, t_max, &mut best, &mut Unnoted)
            .then_some(best)
    }

    /// [`Octree::intersect_packet`] into `best` (all `None` on entry), telling `notes` what it
    /// offers each ray and keeping each ray's limit at `notes.reach` of its best hit (module
    /// `notes`; [`Unnoted`] for a plain search): the same hits. False, with `best` untouched,
    /// when the rays cannot go as one packet. Spares the caller the copies of a returned array.
    #[inline]
    pub fn intersect_packet_noting<P: PrimitiveSet>(
        &self,
        set: &P,
        local_origins: &[DVec3; PACKET],
        dirs: &[DVec3; PACKET],
        t_max: &[f64; PACKET],
        best: &mut [Option<Hit>; PACKET],
        notes: &mut impl Notes,
    ) -> bool {
        let kernel = self.kernel;
        let prepare = |i: usize| prepare_ray_with(set, kernel, local_origins[i], dirs[i]);
        let rays = (local_origins, dirs, (kernel, prepare));
        self.intersect_packet_with(set, rays, t_max, best, notes)
    }

    /// [`Octree::intersect_packet_noting`] without notes, for rays whose primitive data the
    /// caller prepares: `prepare(i)` gives ray `i` prepared for `kernel` (its `local_origin`
    /// and `dir` those given here), asked for once the packet reaches a leaf. A ray with a
    /// `t_max` of -inf takes no part. The mapped rays of an instance come this way: their
    /// set-up is made from the origin in the mesh frame, not from the anchored one.
    pub fn intersect_packet_preparing<P: PrimitiveSet>(
        &self,
        set: &P,
        local_origins: &[DVec3; PACKET],
        dirs: &[DVec3; PACKET],
        t_max: &[f64; PACKET],
        (kernel, prepare): (Kernel, impl Fn(usize) -> PreparedRay<P::RayData> + Copy),
        best: &mut [Option<Hit>; PACKET],
    ) -> bool {
        let rays = (local_origins, dirs, (kernel, prepare));
        self.intersect_packet_with(set, rays, t_max, best, &mut Unnoted)
    }

    /// [`Octree::intersect_packet_noting`] for the rays `(local_origins, dirs, (kernel,
    /// prepare))`, prepared for the primitive tests by `prepare` (by `kernel`) when the first
    /// of them reaches a leaf, and `notes` told what each ray is offered.
    #[allow(clippy::type_complexity)]
    fn intersect_packet_with<P: PrimitiveSet, N: Notes>(
        &self,
        set: &P,
        (local_origins, dirs, (kernel, prepare)): (
            &[DVec3; PACKET],
            &[DVec3; PACKET],
            (Kernel, impl Fn(usize) -> PreparedRay<P::RayData> + Copy),
        ),
        t_max: &[f64; PACKET],
        best: &mut [Option<Hit>; PACKET],
        notes: &mut N,
    ) -> bool {
        let mut own = None;
        let mut packet_data = None;
        let mut tested = PacketMailbox::default();
        let mut ts = [0.0; PACKET];
        packet::run(
            &self.layout,
            kernel,
            local_origins,
            dirs,
            self.scale,
            *t_max,
            |rays, refs, reach, limits| {
                let prepared: &[_; PACKET] =
                    own.get_or_insert_with(|| std::array::from_fn(prepare));
                let kept = refs.iter().zip(reach).filter(|(_, &rays)| rays != 0);
                if rays.is_power_of_two() {
                    // A ray alone: its primitives in groups, as in `intersect_ray`.
                    let i = rays.trailing_zeros() as usize;
                    let new = kept
                        .map(|(&prim, _)| prim)
                        .filter(|&prim| tested.check_in(prim, rays) != 0);
                    test_leaf(set, new, &prepared[i], (t_max[i], &mut best[i]), (notes, i));
                    limits[i] = best[i].map_or(t_max[i], |b| notes.reach(b.t));
                    return;
                }
                let packet = packet_data.get_or_insert_with(|| set.prepare_packet(prepared));
                for (&prim, &rays) in kept {
                    let active = tested.check_in(prim, rays);
                    if active == 0 {
                        continue;
                    }
                    let (hits, inside) = if N::NOTING {
                        // Offered to the rays that may cross it (those that certainly miss it
                        // are no competitor of any hit: module `notes`).
                        let crossings = set.intersect_packet_apart(
                            prim as usize,
                            prepared,
                            packet,
                            active,
                            limits,
                            &mut ts,
                        );
                        for i in set_bits(active & !crossings.apart) {
                            notes.offer(i, prim);
                        }
                        (crossings.hits, crossings.inside)
                    } else {
                        let index = prim as usize;
                        let hits =
                            set.intersect_packet(index, prepared, packet, active, limits, &mut ts);
                        (hits, 0)
                    };
                    for i in set_bits(hits) {
                        let hit = Hit { t: ts[i], prim };
                        if hit.beats(&best[i]) {
                            best[i] = Some(hit);
                            limits[i] = notes.reach(hit.t);
                            if inside & (1 << i) != 0 {
                                notes.inside(i, prim);
                            }
                        }
                    }
                }
            },
        )
    }

    /// Visits the non-empty leaves the ray `origin + t · dir` may reach with `0 <= t <=
    /// t_max`, front to back.
    ///
    /// `visit` gets the leaf's primitive indices and the ray's entry and exit parameters of the
    /// leaf's occupied box (conservative: slightly wider than the exact ones, and the exit
    /// clipped to the current limit), and returns the parameter beyond which nothing interests
    /// it any more (the best hit so far); leaves entered beyond that are skipped. A -0.0
    /// direction component counts as +0.0.
    pub fn traverse(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        visit: impl FnMut(&[u32], f64, f64) -> f64,
    ) {
        let ray = Lanes::new(origin, dir + DVec3::ZERO, self.scale);
        let mut visit = visit;
        let leaf = |child, enter, exit| visit(self.layout.leaf(child), enter, exit);
        traverse::run(
            &self.layout,
            self.kernel,
            &ray,
            t_max,
            leaf,
            &mut Unobserved,
        );
    }
}

/// The primitives a ray tested last, so that one referenced by several leaves along the ray
/// is tested once. Skipping a repeat cannot change the answer: its test gives the same result,
/// already folded into the best hit (kept even beyond the leaf that found it). Direct-mapped:
/// a primitive has one slot, by its index, so a look-up is one comparison; two primitives
/// sharing a slot only cost a repeated test.
#[derive(Debug, Clone, Copy)]
struct Mailbox {
    slots: [u32; MAILBOX],
}

/// Slots of a [`Mailbox`] (a power of two).
const MAILBOX: usize = 32;

impl Default for Mailbox {
    fn default() -> Mailbox {
        Mailbox {
            slots: [u32::MAX; MAILBOX],
        }
    }
}

impl Mailbox {
    /// Whether `prim` is new to the ray (then it is remembered).
    #[inline(always)]
    fn check_in(&mut self, prim: u32) -> bool {
        let slot = &mut self.slots[prim as usize % MAILBOX];
        let new = *slot != prim;
        *slot = prim;
        new
    }
}

/// Tests the primitives `prims` of a leaf (those the ray has not met yet) against `ray`,
/// [`GROUP`] at a time ([`test_group`]), telling `notes` what it offers ray `noted.1`.
#[inline(always)]
fn test_leaf<P: PrimitiveSet, N: Notes>(
    set: &P,
    prims: impl Iterator<Item = u32>,
    ray: &PreparedRay<P::RayData>,
    (t_max, best): (f64, &mut Option<Hit>),
    noted: (&mut N, usize),
) {
    let mut batch = Batch::default();
    for prim in prims {
        batch.push(set, prim, ray, (t_max, best), (&mut *noted.0, noted.1));
    }
    batch.finish(set, ray, (t_max, best), noted);
}

/// A ray's primitives gathered [`GROUP`] at a time for [`test_group`].
#[derive(Default)]
struct Batch {
    prims: [u32; GROUP],
    len: usize,
}

impl Batch {
    /// Adds `prim`; a full group is tested at once.
    #[inline(always)]
    fn push<P: PrimitiveSet, N: Notes>(
        &mut self,
        set: &P,
        prim: u32,
        ray: &PreparedRay<P::RayData>,
        search: (f64, &mut Option<Hit>),
        noted: (&mut N, usize),
    ) {
        self.prims[self.len] = prim;
        self.len += 1;
        if self.len == GROUP {
            test_group(set, &self.prims, ray, search, noted);
            self.len = 0;
        }
    }

    /// Tests what is left.
    #[inline(always)]
    fn finish<P: PrimitiveSet, N: Notes>(
        &self,
        set: &P,
        ray: &PreparedRay<P::RayData>,
        search: (f64, &mut Option<Hit>),
        noted: (&mut N, usize),
    ) {
        test_group(set, &self.prims[..self.len], ray, search, noted);
    }
}

/// Tests the primitives `group` against `ray` ([`PrimitiveSet::intersect_group`]) and keeps in
/// `best` the hit that beats the others and the one there (see [`Hit::beats`]): the same
/// answer as testing them one after the other. Where `notes` note, the group is offered to
/// ray `ray_index` but for the primitives its exact ray certainly misses, and a best hit whose
/// interior it certainly crosses is noted so ([`PrimitiveSet::intersect_group_apart`]).
#[inline(always)]
fn test_group<P: PrimitiveSet, N: Notes>(
    set: &P,
    group: &[u32],
    ray: &PreparedRay<P::RayData>,
    (t_max, best): (f64, &mut Option<Hit>),
    (notes, ray_index): (&mut N, usize),
) {
    if group.is_empty() {
        return;
    }
    let mut ts = [0.0; GROUP];
    let bound = best.map_or(t_max, |b| b.t);
    let crossings = if N::NOTING {
        let crossings = set.intersect_group_apart(group, ray, bound, &mut ts);
        for (k, &prim) in group.iter().enumerate() {
            if crossings.apart & (1 << k) == 0 {
                notes.offer(ray_index, prim);
            }
        }
        crossings
    } else {
        PacketCrossings::hits_only(set.intersect_group(group, ray, bound, &mut ts))
    };
    for k in set_bits(crossings.hits) {
        let hit = Hit {
            t: ts[k],
            prim: group[k],
        };
        if hit.beats(best) {
            *best = Some(hit);
            if crossings.inside & (1 << k) != 0 {
                notes.inside(ray_index, group[k]);
            }
        }
    }
}

/// [`Mailbox`] for the rays of a packet: per slot, a primitive and the rays it has been
/// tested with.
#[derive(Debug, Clone, Copy)]
struct PacketMailbox {
    slots: [(u32, u32); MAILBOX],
}

impl Default for PacketMailbox {
    fn default() -> PacketMailbox {
        PacketMailbox {
            slots: [(u32::MAX, 0); MAILBOX],
        }
    }
}

impl PacketMailbox {
    /// Which of `rays` (bit `i` for ray `i`) `prim` is new to (then it is remembered with
    /// them).
    #[inline(always)]
    fn check_in(&mut self, prim: u32, rays: u32) -> u32 {
        let slot = &mut self.slots[prim as usize % MAILBOX];
        if slot.0 != prim {
            *slot = (prim, rays);
            return rays;
        }
        let new = rays & !slot.1;
        slot.1 |= rays;
        new
    }
}

#[cfg(test)]
mod tests;
