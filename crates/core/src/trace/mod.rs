//! The one tracer: a scene with its octree and every ray query over them, the nearest hit
//! from `t > 0` (what the renderer fills its buffers from), a parameter range
//! `(t_min, t_max]`, packets of coherent rays, every surface crossing along a ray, point
//! containment by crossing parity and the distance queries ([`Tracer::closest`]). The command
//! line, `raycast check`'s golden buffers and the Python package all trace through it.
//!
//! With `t_min = 0` the nearest hit of [`Tracer::nearest`] is exactly [`Tracer::trace`]'s (the
//! same search), so buffers filled from either are bit-identical.
//!
//! With the `bvh-oracle` feature, `BvhTracer` finds the same nearest hits through an obvhs
//! BVH, for the tests and benchmarks that check and measure the octree against it.

mod distance;
#[cfg(feature = "bvh-oracle")]
mod oracle;

pub use distance::{signed, winding_number, NearestPoint, Side, SignRule, Signer};
#[cfg(feature = "bvh-oracle")]
pub use oracle::BvhTracer;

use crate::accel::{test_primitive, Hit, Notes, Octree, OctreeParams, Offered};
use crate::accel::{PreparedRay, PrimitiveSet, Unnoted, PACKET};
use crate::geometry::{Ray, RaySource};
use crate::quadric::Quadric;
use crate::scene::{Crossing, EdgeRule, Scene, SceneRay};
use glam::DVec3;
use rayon::prelude::*;

/// Memory per primitive that building the octree takes, for the estimate a render checks
/// against its memory limit: each primitive's box (48 bytes) and, measured as the growth of
/// peak memory from loading to building on the shared assets, 25 to 74 bytes for the tree (4
/// to 6 references per primitive). A scene of large crossing triangles may take up to 256
/// references per primitive (about 1 KiB), the octree's bound.
pub const ACCEL_BYTES_PER_PRIMITIVE: u64 = 128;

/// Builds the octree over `scene` (with `params`), the octrees of its instanced meshes first
/// ([`Scene::build_instances`]). Building them alongside with `rayon::join` runs the whole
/// build on a pool thread, whose allocator keeps what it frees: six builds in a row
/// (benches/trace.rs) then peaked at 34 instead of 24 MiB on the bunny.
pub fn build_octree(scene: &Scene, params: OctreeParams) -> Octree {
    scene.build_instances();
    Octree::build(scene, params)
}

/// An estimate of the memory [`build_octree`] takes over `scene`: the top-level octree over
/// its primitives and one per stored instanced mesh, at [`ACCEL_BYTES_PER_PRIMITIVE`] each.
pub fn estimated_build_bytes(scene: &Scene) -> u64 {
    (scene.accel_primitive_count() as u64).saturating_mul(ACCEL_BYTES_PER_PRIMITIVE)
}

/// What the renderer fills its buffers from ([`crate::render::trace`]): the nearest hits of
/// many rays in their ranges. [`Tracer`] is the one implementation of the command line and
/// the Python package; `BvhTracer` (feature `bvh-oracle`) the oracle of tests and benches.
pub trait NearestHits: Sync {
    /// The scene the hits are in.
    fn scene(&self) -> &Scene;

    /// The nearest crossing of each of `rays` in its range of `ranges` (see
    /// [`Tracer::nearest`]).
    fn nearest_all(&self, rays: &[Ray], ranges: &[(f64, f64)]) -> Vec<Option<Crossing>>;

    /// [`NearestHits::nearest_all`], with what each ray's search offered it where it was
    /// noted ([`Tracer::nearest_all_offered`]); none by default.
    fn nearest_all_offered(
        &self,
        rays: &[Ray],
        ranges: &[(f64, f64)],
    ) -> (Vec<Option<Crossing>>, Vec<Option<Offered>>) {
        (self.nearest_all(rays, ranges), vec![None; rays.len()])
    }

    /// The octree's tracer, for the queries beyond the nearest hit (the `certain` buffer);
    /// `None` for an oracle without one.
    fn tracer(&self) -> Option<Tracer<'_>>;
}

/// The crossings of many rays in CSR form: ray `i`'s are entries `splits[i]..splits[i + 1]`
/// of `t`, `id` and `prim`, nearest first (as [`Tracer::crossings`] lists them).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HitLists {
    /// N + 1 offsets, from 0 to the number of crossings.
    pub splits: Vec<u64>,
    /// Ray parameter of each crossing (units of |direction|).
    pub t: Vec<f64>,
    /// 1-based object id of each crossing.
    pub id: Vec<u32>,
    /// Primitive index inside the object of each crossing.
    pub prim: Vec<u32>,
}

/// A scene with its octree, ready for every ray and point query.
#[derive(Debug, Clone, Copy)]
pub struct Tracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The octree built over it.
    pub octree: &'a Octree,
}

impl<'a> Tracer<'a> {
    /// A tracer of `scene` through `octree`, which must have been built over it.
    pub fn new(scene: &'a Scene, octree: &'a Octree) -> Self {
        Tracer { scene, octree }
    }

    /// The nearest hit of `ray` with `t > 0`, as a top-level [`Hit`]; `None` for a miss or
    /// an untraceable ray (see [`Ray::is_valid`]).
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let local = ray.origin - self.scene.anchor;
        self.octree
            .intersect_ray(self.scene, local, ray.dir, f64::INFINITY)
    }

    /// The nearest crossing with `t_min < t <= t_max` (and `t > 0`); `None` for a miss, an
    /// untraceable ray (see [`Ray::is_valid`]), a NaN or negative `t_min` or a NaN `t_max`.
    /// Ties go to the smaller primitive index, as in [`Hit::beats`].
    pub fn nearest(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Crossing> {
        self.nearest_noting(ray, t_min, t_max, &mut Unnoted)
    }

    /// [`Tracer::nearest`] that tells `notes` what the search from 0 offers the ray
    /// ([`Octree::intersect_ray_noting`]; a range from beyond 0 notes nothing): the same hit.
    #[inline(always)]
    fn nearest_noting(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
        notes: &mut impl Notes,
    ) -> Option<Crossing> {
        if !traceable(ray, t_min, t_max) {
            return None;
        }
        let local = ray.origin - self.scene.anchor;
        if t_min == 0.0 {
            let hit =
                (self.octree).intersect_ray_noting(self.scene, local, ray.dir, t_max, notes)?;
            return Some(hit.into());
        }
        self.nearest_beyond(local, ray.dir, t_min, t_max)
    }

    /// [`Tracer::nearest`], with what its search offered the ray ([`Offered`], for the
    /// `certain` AOV) when the range starts at 0 (`None` otherwise, and for a ray that is not
    /// traced).
    fn nearest_offered(
        &self,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> (Option<Crossing>, Option<Offered>) {
        if t_min != 0.0 || !traceable(ray, t_min, t_max) {
            return (self.nearest(ray, t_min, t_max), None);
        }
        let mut notes = Offered::EMPTY;
        let hit = self.nearest_noting(ray, t_min, t_max, &mut notes);
        notes.finish(hit.map(|h| h.t), t_max);
        (hit, Some(notes))
    }

    /// The ray `local + t · dir` (origin relative to the scene's anchor) prepared for the
    /// primitive tests with the octree's kernel.
    fn prepare(&self, local: DVec3, dir: DVec3) -> PreparedRay<SceneRay> {
        crate::accel::prepare_ray_with(self.scene, self.octree.kernel(), local, dir)
    }

    /// [`Tracer::nearest`] for a range that does not start at 0, the ray's origin relative to
    /// the scene's anchor: every crossing in the range, the nearest kept. Kept out of line so
    /// that the common range from 0 does not pay for its set-up.
    #[inline(never)]
    fn nearest_beyond(&self, local: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<Crossing> {
        let prepared = self.prepare(local, dir);
        let mut best: Option<Crossing> = None;
        let mut found = Vec::new();
        self.octree.traverse(local, dir, t_max, |refs, _, _| {
            let limit = best.map_or(t_max, |b| b.t);
            for &prim in refs {
                found.clear();
                let range = (t_min, limit);
                let rule = EdgeRule::Inclusive;
                self.scene
                    .crossings_of(prim as usize, &prepared, range, rule, &mut found);
                for c in &found {
                    let hit = Hit {
                        t: c.t,
                        prim: c.top,
                    };
                    let current = best.map(|b| Hit {
                        t: b.t,
                        prim: b.top,
                    });
                    if hit.beats(&current) {
                        best = Some(*c);
                    }
                }
            }
            best.map_or(t_max, |b| b.t)
        });
        best
    }

    /// [`Tracer::nearest`] for [`PACKET`] rays traced together (see [`Octree::intersect_packet`]),
    /// the answers written into `found`: the same answers, or false, with `found` untouched,
    /// when they cannot go as one packet (a range not starting at 0, an untraceable ray,
    /// directions in different octants or with a zero component).
    pub fn nearest_packet(
        &self,
        rays: &[Ray; PACKET],
        ranges: &[(f64, f64); PACKET],
        found: &mut [Option<Crossing>; PACKET],
    ) -> bool {
        self.nearest_packet_noting(rays, ranges, found, &mut Unnoted)
    }

    /// [`Tracer::nearest_packet`] that tells `notes` what the search offers each ray
    /// ([`Octree::intersect_packet_noting`]): the same answers.
    pub fn nearest_packet_noting(
        &self,
        rays: &[Ray; PACKET],
        ranges: &[(f64, f64); PACKET],
        found: &mut [Option<Crossing>; PACKET],
        notes: &mut impl Notes,
    ) -> bool {
        if !plain_packet(ranges) {
            return false;
        }
        let origins = rays.each_ref().map(|ray| ray.origin - self.scene.anchor);
        let dirs = rays.each_ref().map(|ray| ray.dir);
        let t_max = ranges.map(|(_, t_max)| t_max);
        let mut hits = [None; PACKET];
        let packed = self
            .octree
            .intersect_packet_noting(self.scene, &origins, &dirs, &t_max, &mut hits, notes);
        if packed {
            for (found, hit) in found.iter_mut().zip(hits) {
                *found = hit.map(Crossing::from);
            }
        }
        packed
    }

    /// [`Tracer::nearest`] for every ray of `rays` with its range in `ranges`: runs of
    /// [`PACKET`] rays that can go together are traced as packets (the same answers, fewer
    /// node visits for coherent rays such as a camera's), the others one by one.
    pub fn nearest_all(&self, rays: &[Ray], ranges: &[(f64, f64)]) -> Vec<Option<Crossing>> {
        self.nearest_all_with::<false>(rays, ranges, &mut Vec::new())
    }

    /// [`Tracer::nearest_all`], with, for each ray, the primitives its search offered it and
    /// how far it searched ([`Offered`]: for the `certain` AOV); `None` for
    /// a ray whose range does not start at 0.
    pub fn nearest_all_offered(
        &self,
        rays: &[Ray],
        ranges: &[(f64, f64)],
    ) -> (Vec<Option<Crossing>>, Vec<Option<Offered>>) {
        let mut offered = Vec::with_capacity(rays.len());
        let hits = self.nearest_all_with::<true>(rays, ranges, &mut offered);
        (hits, offered)
    }

    /// [`Tracer::nearest_all`], noting the offers into `offered` when `NOTE` (a constant, so
    /// that the plain search compiles as if there were nothing to note).
    fn nearest_all_with<const NOTE: bool>(
        &self,
        rays: &[Ray],
        ranges: &[(f64, f64)],
        offered: &mut Vec<Option<Offered>>,
    ) -> Vec<Option<Crossing>> {
        let mut hits = Vec::with_capacity(rays.len());
        let (packets, rest) = rays.as_chunks::<PACKET>();
        let (packet_ranges, rest_ranges) = ranges.as_chunks::<PACKET>();
        // Directions' signs first: incoherent rays stop here, before any set-up.
        let octant = |ray: &Ray| ray.dir.cmplt(DVec3::ZERO).bitmask();
        for (packet, range) in packets.iter().zip(packet_ranges) {
            let first = octant(&packet[0]);
            let coherent = packet.iter().all(|ray| octant(ray) == first);
            if coherent {
                let start = hits.len();
                hits.resize(start + PACKET, None);
                let found = hits[start..].as_mut_array().expect("PACKET slots");
                let packed = match NOTE {
                    false => self.nearest_packet(packet, range, found),
                    true => self.noted_packet(packet, range, found, offered),
                };
                if packed {
                    continue;
                }
                hits.truncate(start);
            }
            self.extend_one::<NOTE>(packet, range, &mut hits, offered);
        }
        self.extend_one::<NOTE>(rest, rest_ranges, &mut hits, offered);
        hits
    }

    /// The nearest hits of `rays` traced one by one, appended to `hits`; with `NOTE`, what
    /// each search offered its ray appended to `offered`.
    #[inline(always)]
    fn extend_one<const NOTE: bool>(
        &self,
        rays: &[Ray],
        ranges: &[(f64, f64)],
        hits: &mut Vec<Option<Crossing>>,
        offered: &mut Vec<Option<Offered>>,
    ) {
        for (ray, &(t_min, t_max)) in rays.iter().zip(ranges) {
            if NOTE {
                let (hit, noted) = self.nearest_offered(ray, t_min, t_max);
                hits.push(hit);
                offered.push(noted);
            } else {
                hits.push(self.nearest(ray, t_min, t_max));
            }
        }
    }

    /// [`Tracer::nearest_packet_noting`] with one [`Offered`] per ray, the offers appended to
    /// `offered` when the rays went as a packet.
    fn noted_packet(
        &self,
        rays: &[Ray; PACKET],
        ranges: &[(f64, f64); PACKET],
        found: &mut [Option<Crossing>; PACKET],
        offered: &mut Vec<Option<Offered>>,
    ) -> bool {
        let mut notes = [Offered::EMPTY; PACKET];
        if !self.nearest_packet_noting(rays, ranges, found, &mut notes) {
            return false;
        }
        for ((noted, hit), &(_, t_max)) in notes.iter_mut().zip(found.iter()).zip(ranges) {
            noted.finish(hit.map(|h| h.t), t_max);
        }
        offered.extend(notes.map(Some));
        true
    }

    /// Whether the ray has any crossing with `t_min < t <= t_max` (and `t > 0`): exactly
    /// `self.nearest(ray, t_min, t_max).is_some()`, with the same primitive tests, but the
    /// search stops at the first crossing in range instead of looking for the nearest.
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        if !traceable(ray, t_min, t_max) {
            return false;
        }
        let local = ray.origin - self.scene.anchor;
        let prepared = self.prepare(local, ray.dir);
        // Returned to the traversal once a crossing is found: no leaf is entered below it.
        let stop = f64::NEG_INFINITY;
        let mut hit = false;
        if t_min == 0.0 {
            let mut best = None;
            self.octree.traverse(local, ray.dir, t_max, |refs, _, _| {
                for &prim in refs {
                    if test_primitive(self.scene, prim, &prepared, t_max, &mut best) {
                        hit = true;
                        return stop;
                    }
                }
                t_max
            });
            return hit;
        }
        let mut found = Vec::new();
        self.octree.traverse(local, ray.dir, t_max, |refs, _, _| {
            for &prim in refs {
                let range = (t_min, t_max);
                let rule = EdgeRule::Inclusive;
                self.scene
                    .crossings_of(prim as usize, &prepared, range, rule, &mut found);
                if !found.is_empty() {
                    hit = true;
                    return stop;
                }
            }
            t_max
        });
        hit
    }

    /// Every surface crossing with `t_min < t <= t_max` (and `t > 0`), nearest first (ties by
    /// primitive); none for the rays [`Tracer::nearest`] refuses. A ray through an edge or
    /// vertex shared by triangles of a consistently wound mesh crosses it once (see
    /// [`crate::geometry::triangle::WatertightRay::crossing`]); a ray tangent to a quadric
    /// touches it once.
    pub fn crossings(&self, ray: &Ray, t_min: f64, t_max: f64) -> Vec<Crossing> {
        let mut found = Vec::new();
        if !traceable(ray, t_min, t_max) {
            return found;
        }
        let local = ray.origin - self.scene.anchor;
        let prepared = self.prepare(local, ray.dir);
        self.octree.traverse(local, ray.dir, t_max, |refs, _, _| {
            for &prim in refs {
                let range = (t_min, t_max);
                self.scene.crossings_of(
                    prim as usize,
                    &prepared,
                    range,
                    EdgeRule::Once,
                    &mut found,
                );
            }
            t_max
        });
        // A primitive in several leaves is found once per leaf.
        found.sort_by(|a, b| {
            a.t.total_cmp(&b.t)
                .then(a.top.cmp(&b.top))
                .then(a.inner.cmp(&b.inner))
        });
        found.dedup();
        found
    }

    /// The [`Tracer::crossings`] of every ray of `source` in its `range`, the nearest `limit`
    /// of each, resolved to object ids and primitives; in parallel.
    pub fn hit_lists<S, R>(&self, source: &S, range: R, limit: usize) -> HitLists
    where
        S: RaySource + ?Sized,
        R: Fn(usize) -> (f64, f64) + Sync,
    {
        let per_ray: Vec<Vec<(f64, u32, u32)>> = (0..source.len())
            .into_par_iter()
            .map(|i| {
                let ray = source.ray(i);
                let (t_min, t_max) = range(i);
                let found = self.crossings(&ray, t_min, t_max);
                let nearest = found.iter().take(limit);
                nearest
                    .map(|c| {
                        let located = self.scene.locate_crossing(c, ray.origin, ray.dir);
                        (c.t, located.object.id, located.prim)
                    })
                    .collect()
            })
            .collect();
        let mut lists = HitLists {
            splits: Vec::with_capacity(per_ray.len() + 1),
            ..HitLists::default()
        };
        lists.splits.push(0);
        for hits in per_ray {
            for (t, id, prim) in hits {
                lists.t.push(t);
                lists.id.push(id);
                lists.prim.push(prim);
            }
            lists.splits.push(lists.t.len() as u64);
        }
        lists
    }

    /// Whether `point` lies inside the scene's closed surfaces. Triangles and open quadrics
    /// count by [`Tracer::crossing_parity`]; a closed ellipsoid ([`Quadric::encloses`]) counts
    /// by the sign of its polynomial at the point ([`Tracer::ellipsoid_parity`]), so that a ray
    /// tangent to it cannot flip the count. A point on a surface may count either way.
    pub fn contains(&self, point: DVec3) -> bool {
        self.crossing_parity(point) ^ self.ellipsoid_parity(point).0
    }

    /// The parity of the crossings of triangles and open quadrics (every quadric but those
    /// that [`Quadric::encloses`]) along three rays from `point` in fixed, unrelated
    /// directions, by majority. A single ray can only be wrong where it passes exactly through
    /// a silhouette edge or a vertex where the surface is not crossed but touched, or touches
    /// an open quadric; three rays are wrong only when two of them are.
    pub fn crossing_parity(&self, point: DVec3) -> bool {
        let by_side = |c: &Crossing| self.scene.quadric_at(c.top).is_some_and(Quadric::encloses);
        self.parity_vote(point, |c| !by_side(c))
    }

    /// The parity of the closed ellipsoids ([`Quadric::encloses`]) around `point`, each by
    /// [`Quadric::inside`], and whether `point` lies on one of them to rounding (that one
    /// then left out of the parity).
    pub fn ellipsoid_parity(&self, point: DVec3) -> (bool, bool) {
        let closed = self.scene.quadrics().iter().filter(|q| q.encloses());
        closed.fold((false, false), |(odd, on), quadric| {
            match quadric.inside(point) {
                Some(within) => (odd ^ within, on),
                None => (odd, true),
            }
        })
    }

    /// The parity of the crossings that `counts` keeps along three rays from `point`, by
    /// majority (see [`Tracer::crossing_parity`]).
    fn parity_vote(&self, point: DVec3, counts: impl Fn(&Crossing) -> bool) -> bool {
        if !point.is_finite() || self.scene.is_empty() {
            return false;
        }
        let odd = PARITY_DIRECTIONS
            .iter()
            .filter(|d| {
                let ray = Ray::new(point, DVec3::from_array(**d));
                let crossings = self.crossings(&ray, 0.0, f64::INFINITY);
                crossings.iter().filter(|c| counts(c)).count() % 2 == 1
            })
            .count();
        odd >= 2
    }
}

impl NearestHits for Tracer<'_> {
    fn scene(&self) -> &Scene {
        self.scene
    }

    fn nearest_all(&self, rays: &[Ray], ranges: &[(f64, f64)]) -> Vec<Option<Crossing>> {
        Tracer::nearest_all(self, rays, ranges)
    }

    fn nearest_all_offered(
        &self,
        rays: &[Ray],
        ranges: &[(f64, f64)],
    ) -> (Vec<Option<Crossing>>, Vec<Option<Offered>>) {
        Tracer::nearest_all_offered(self, rays, ranges)
    }

    fn tracer(&self) -> Option<Tracer<'_>> {
        Some(*self)
    }
}

/// Whether [`Tracer::nearest`] can trace `ray` in `(t_min, t_max]`: a traceable ray (see
/// [`Ray::is_valid`]) with `t_min >= 0` and `t_max` not NaN.
#[inline]
pub fn traceable(ray: &Ray, t_min: f64, t_max: f64) -> bool {
    ray.is_valid() && t_min >= 0.0 && !t_max.is_nan()
}

/// True when every range of a packet starts at 0 and has a limit that is not NaN. The rays
/// themselves need no check here: the packet set-up refuses a packet in which some ray has an
/// origin or a direction that is not finite, or a zero direction component (see
/// `Bundle::set`), and such a ray then goes through [`Tracer::nearest`], which refuses it.
fn plain_packet(ranges: &[(f64, f64); PACKET]) -> bool {
    ranges.iter().fold(true, |plain, &(t_min, t_max)| {
        plain & (t_min == 0.0) & !t_max.is_nan()
    })
}

/// Directions of the parity rays of [`Tracer::contains`]: no axis, diagonal or simple ratio,
/// so that rays from points on a grid do not run along the faces or edges of axis-aligned or
/// regularly tessellated models.
const PARITY_DIRECTIONS: [[f64; 3]; 3] = [
    [0.419, 0.753, 0.511],
    [-0.83, 0.269, -0.487],
    [0.233, -0.911, 0.341],
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A packet forms only when every ray is traceable over its range and the range starts at
    /// 0 (one odd ray among seven plain ones: infinite or NaN coordinates, zero or subnormal
    /// direction components, odd ranges), and then gives each ray its own answer.
    #[test]
    fn a_packet_forms_only_of_traceable_rays_with_ranges_from_zero() {
        let mut builder = crate::scene::SceneBuilder::new();
        let triangle = [
            DVec3::ZERO,
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(0.0, 4.0, 0.0),
        ];
        builder.add_mesh("t".into(), "test".into(), vec![triangle]);
        let scene = builder.finish("one triangle".into());
        let octree = Octree::build(&scene, crate::accel::OctreeParams::default());
        let tracer = Tracer::new(&scene, &octree);
        let odd = [
            0.0,
            -0.0,
            1e-310,
            f64::MAX,
            f64::INFINITY,
            -f64::INFINITY,
            f64::NAN,
        ];
        let base = Ray::new(DVec3::new(1.0, 1.0, 3.0), DVec3::new(0.05, 0.025, -1.0));
        let (mut packed, mut refused) = (0, 0);
        for (slot, &x) in (0..6).flat_map(|slot| odd.iter().map(move |x| (slot, x))) {
            for (t_min, t_max) in [
                (0.0, f64::INFINITY),
                (-0.0, 5.0),
                (0.5, 5.0),
                (0.0, f64::NAN),
            ] {
                let mut ray = base;
                if slot < 3 {
                    ray.origin[slot] = x;
                } else {
                    ray.dir[slot - 3] = x;
                }
                let mut rays = [base; PACKET];
                rays[5] = ray;
                let mut ranges = [(0.0, 5.0); PACKET];
                ranges[5] = (t_min, t_max);
                let plain = t_min == 0.0 && traceable(&ray, t_min, t_max);
                let mut found = [None; PACKET];
                if tracer.nearest_packet(&rays, &ranges, &mut found) {
                    assert!(plain, "{ray:?} {t_min} {t_max} went as a packet");
                    for ((ray, &(t_min, t_max)), found) in rays.iter().zip(&ranges).zip(found) {
                        assert_eq!(found, tracer.nearest(ray, t_min, t_max), "{ray:?}");
                    }
                    packed += 1;
                } else {
                    refused += 1;
                }
            }
        }
        assert!(
            packed > 10 && refused > 100,
            "{packed} packed, {refused} refused"
        );
    }
}
