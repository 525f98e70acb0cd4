//! Acceleration structures over any set of primitives.
//!
//! The octree does not know what a primitive is: it asks a [`PrimitiveSet`] for bounds, for an
//! overlap test against a cell and for a ray hit, by primitive index. The scene implements it
//! over triangles and quadrics together.

#[cfg(feature = "bvh-oracle")]
pub mod bvh;
pub mod octree;

use crate::geometry::Aabb;
pub use crate::simd::Kernel;
use glam::DVec3;

#[cfg(feature = "bvh-oracle")]
pub use bvh::{Bvh, BvhKind, BvhStats};
pub use octree::{Notes, Octree, OctreeParams, OctreeStats, Offered, Unnoted, PACKET};

/// A ray prepared for tracing: world origin and direction plus whatever the primitive set
/// precomputes per ray (`R`, for instance the watertight triangle frame).
#[derive(Debug, Clone, Copy)]
pub struct PreparedRay<R> {
    /// Ray origin in the acceleration structure's (scene-local) coordinates.
    pub local_origin: DVec3,
    /// Ray direction; no component is -0.0.
    pub dir: DVec3,
    /// Per-ray data of the primitive set.
    pub extra: R,
    /// The kernel of every SIMD test this ray goes through.
    pub kernel: Kernel,
}

/// The closest hit of a ray: its parameter and the global primitive index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter: the hit point is `origin + t * dir`.
    pub t: f64,
    /// Index of the primitive in the [`PrimitiveSet`].
    pub prim: u32,
}

impl Hit {
    /// True when `self` beats `best`: nearer, or as near with a smaller primitive index (so
    /// every traversal order picks the same primitive on ties).
    pub fn beats(&self, best: &Option<Hit>) -> bool {
        match best {
            None => true,
            Some(b) => self.t < b.t || (self.t == b.t && self.prim < b.prim),
        }
    }
}

/// A collection of primitives an acceleration structure can be built over.
pub trait PrimitiveSet: Sync {
    /// Per-ray data computed once by [`PrimitiveSet::prepare`].
    type RayData: Copy;

    /// Number of primitives.
    fn len(&self) -> usize;

    /// True when there is no primitive.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bounding box of primitive `index`, in local coordinates.
    fn bounds(&self, index: usize) -> Aabb;

    /// What testing primitive `index` against a ray costs, in units of one triangle test:
    /// the octree's split rule weighs each reference by it. The default, 1, suits sets of
    /// triangles.
    fn cost(&self, _index: usize) -> f64 {
        1.0
    }

    /// True when every primitive is a triangle: the octree then uses
    /// [`OctreeParams::triangle_leaf_size`]. The default, false, suits mixed sets.
    fn triangles_only(&self) -> bool {
        false
    }

    /// Conservative test: may primitive `index` touch the closed box `cell`?
    fn overlaps(&self, index: usize, cell: &Aabb) -> bool;

    /// Which of the octants in `candidates` of `cell`, each grown by `margin`, primitive
    /// `index` may touch: bit `i` for [`Aabb::octant`] `i`, a subset of `candidates`. The
    /// default asks [`PrimitiveSet::overlaps`] once per candidate.
    fn child_mask(&self, index: usize, cell: &Aabb, margin: f64, candidates: u8) -> u8 {
        octants_by_overlap(self, index, cell, margin, candidates)
    }

    /// Bounds of the part of primitive `index` inside `cell`, or `None` when nothing of it is
    /// there. The default clips the primitive's bounds to the cell.
    fn clipped_bounds(&self, index: usize, cell: &Aabb) -> Option<Aabb> {
        self.bounds(index).common(*cell)
    }

    /// Per-ray precomputation for a ray with the given local origin and direction.
    fn prepare(&self, local_origin: DVec3, dir: DVec3) -> Self::RayData;

    /// Parameter `t` of the nearest hit of primitive `index` with `0 < t <= t_max`.
    fn intersect(&self, index: usize, ray: &PreparedRay<Self::RayData>, t_max: f64) -> Option<f64>;

    /// [`PrimitiveSet::intersect`] of the primitives `indices` (at most [`GROUP`]) with one
    /// ray, each with `0 < t <= t_max`: writes the `t` of a hit with `indices[k]` into `ts[k]`
    /// and returns the hit ones (bit `k`). The answers are exactly those of one `intersect`
    /// per primitive, which is what the default does.
    fn intersect_group(
        &self,
        indices: &[u32],
        ray: &PreparedRay<Self::RayData>,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> u32 {
        intersect_one_by_one(self, indices, ray, t_max, ts)
    }

    /// [`PrimitiveSet::intersect_group`], and which primitives of the group the exact ray
    /// certainly does not cross at all, or crosses in the interior, bit `k` for `indices[k]`
    /// (as [`PrimitiveSet::intersect_packet_apart`] says it for the rays of a packet). The
    /// default tells nothing (`apart` and `inside` 0).
    #[inline(always)]
    fn intersect_group_apart(
        &self,
        indices: &[u32],
        ray: &PreparedRay<Self::RayData>,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> PacketCrossings {
        PacketCrossings::hits_only(self.intersect_group(indices, ray, t_max, ts))
    }

    /// Per-packet data computed once by [`PrimitiveSet::prepare_packet`].
    type PacketData;

    /// Per-packet precomputation for [`PACKET`] rays prepared by [`prepare_ray`].
    fn prepare_packet(&self, rays: &[PreparedRay<Self::RayData>; PACKET]) -> Self::PacketData;

    /// [`PrimitiveSet::intersect`] of primitive `index` with the rays `active` of a packet (bit
    /// `i` for ray `i`), each with its own `t_max`: writes each hit's `t` into `ts` and returns
    /// the rays hit. The answers are exactly those of one `intersect` per ray, which is what
    /// the default does ([`intersect_each`]).
    fn intersect_packet(
        &self,
        index: usize,
        rays: &[PreparedRay<Self::RayData>; PACKET],
        _packet: &Self::PacketData,
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> u32 {
        intersect_each(self, index, rays, active, t_max, ts)
    }

    /// [`PrimitiveSet::intersect_packet`], and which of the rays `active` certainly do not
    /// cross primitive `index` at all, or certainly cross its interior (the `certain` AOV's
    /// filters, `bound::apart`, for the exact ray and primitive). Used by a search that notes
    /// what it offers (module `octree::notes`), which then offers a ray nothing it certainly
    /// misses. The default tells nothing (`apart` and `inside` 0).
    #[inline(always)]
    fn intersect_packet_apart(
        &self,
        index: usize,
        rays: &[PreparedRay<Self::RayData>; PACKET],
        packet: &Self::PacketData,
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> PacketCrossings {
        PacketCrossings::hits_only(self.intersect_packet(index, rays, packet, active, t_max, ts))
    }
}

/// What [`PrimitiveSet::intersect_packet_apart`] says of one primitive, a bit per ray.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PacketCrossings {
    /// The rays that hit it within their limits (their `t` written).
    pub hits: u32,
    /// The rays whose exact ray certainly misses the exact primitive.
    pub apart: u32,
    /// The rays whose exact ray certainly crosses the exact primitive's interior (for a
    /// triangle, as `bound::triangle::certainly_inside` decides it).
    pub inside: u32,
}

impl PacketCrossings {
    /// The rays `hits` hit it; nothing said of the others.
    #[inline(always)]
    pub fn hits_only(hits: u32) -> PacketCrossings {
        PacketCrossings {
            hits,
            ..PacketCrossings::default()
        }
    }
}

/// Primitives tested together by [`PrimitiveSet::intersect_group`].
pub const GROUP: usize = 4;

/// [`PrimitiveSet::intersect_group`] by one [`PrimitiveSet::intersect`] per primitive.
#[inline(always)]
pub fn intersect_one_by_one<P: PrimitiveSet + ?Sized>(
    set: &P,
    indices: &[u32],
    ray: &PreparedRay<P::RayData>,
    t_max: f64,
    ts: &mut [f64; GROUP],
) -> u32 {
    let mut hits = 0;
    for (k, &index) in indices.iter().enumerate() {
        if let Some(t) = set.intersect(index as usize, ray, t_max) {
            ts[k] = t;
            hits |= 1 << k;
        }
    }
    hits
}

/// [`PrimitiveSet::intersect_packet`] by one [`PrimitiveSet::intersect`] per active ray.
#[inline(always)]
pub fn intersect_each<P: PrimitiveSet + ?Sized>(
    set: &P,
    index: usize,
    rays: &[PreparedRay<P::RayData>; PACKET],
    active: u32,
    t_max: &[f64; PACKET],
    ts: &mut [f64; PACKET],
) -> u32 {
    let mut hits = 0;
    for i in set_bits(active) {
        if let Some(t) = set.intersect(index, &rays[i], t_max[i]) {
            ts[i] = t;
            hits |= 1 << i;
        }
    }
    hits
}

/// The indices of the set bits of `mask`, lowest first.
#[inline(always)]
pub(crate) fn set_bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        let i = (mask != 0).then(|| mask.trailing_zeros() as usize)?;
        mask &= mask - 1;
        Some(i)
    })
}

/// The largest f32 not above `x` (-inf below the f32 range; NaN stays NaN).
pub(crate) fn f32_below(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x {
        f.next_down()
    } else {
        f
    }
}

/// The smallest f32 not below `x` (+inf above the f32 range; NaN stays NaN).
pub(crate) fn f32_above(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// [`PrimitiveSet::child_mask`] computed with one [`PrimitiveSet::overlaps`] test per
/// candidate octant.
pub fn octants_by_overlap<P: PrimitiveSet + ?Sized>(
    set: &P,
    index: usize,
    cell: &Aabb,
    margin: f64,
    candidates: u8,
) -> u8 {
    (0..8)
        .filter(|&i| candidates & (1 << i) != 0)
        .filter(|&i| set.overlaps(index, &cell.octant(i).expanded(margin)))
        .fold(0, |mask, i| mask | (1 << i))
}

/// Prepares a ray for [`PrimitiveSet::intersect`]; turns -0.0 direction components into +0.0.
pub fn prepare_ray<P: PrimitiveSet>(
    set: &P,
    local_origin: DVec3,
    dir: DVec3,
) -> PreparedRay<P::RayData> {
    prepare_ray_with(set, Kernel::detect(), local_origin, dir)
}

/// [`prepare_ray`] for the kernel `kernel` (which the CPU must run). Always inlined, with
/// `Scene::prepare`: as calls they cost 0.3–1 % of a trace's instructions (callgrind, depth:
/// bunny 512² camera 264.6 M → 263.1 M, helmet incoherent 46.26 M → 45.94 M, quadric scene
/// 52.6 M → 52.1 M).
#[inline(always)]
pub fn prepare_ray_with<P: PrimitiveSet>(
    set: &P,
    kernel: Kernel,
    local_origin: DVec3,
    dir: DVec3,
) -> PreparedRay<P::RayData> {
    let dir = dir + DVec3::ZERO;
    PreparedRay {
        local_origin,
        dir,
        extra: set.prepare(local_origin, dir),
        kernel,
    }
}

/// The reference answer: tests every primitive. Used by tests and as the exactness oracle.
pub fn brute_force<P: PrimitiveSet>(set: &P, ray: &PreparedRay<P::RayData>) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    for index in 0..set.len() as u32 {
        test_primitive(set, index, ray, f64::INFINITY, &mut best);
    }
    best
}

/// Tests primitive `prim` for a hit with `0 < t <= t_max` and keeps it in `best` when it beats
/// the hit there (see [`Hit::beats`]); returns whether it did. Every backend goes through here,
/// so all of them pick the same primitive.
#[inline(always)]
pub fn test_primitive<P: PrimitiveSet>(
    set: &P,
    prim: u32,
    ray: &PreparedRay<P::RayData>,
    t_max: f64,
    best: &mut Option<Hit>,
) -> bool {
    let bound = best.map_or(t_max, |b| b.t);
    let Some(t) = set.intersect(prim as usize, ray, bound) else {
        return false;
    };
    let hit = Hit { t, prim };
    let better = hit.beats(best);
    if better {
        *best = Some(hit);
    }
    better
}
