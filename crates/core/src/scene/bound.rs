//! The per-primitive side of [`crate::bound`]: a hit's bound, and whether a primitive may be
//! crossed by the exact ray within a range.

use super::instance::StoredMesh;
use super::{Crossing, Scene, Top};
use crate::bound::apart::{apart_four, LANES};
use crate::bound::bounded;
use crate::bound::bounded::{
    bounded3, errors3, exact3, gamma, up, values3, within3, BVec3, Bounded,
};
use crate::bound::residual::{self, NearRay};
use crate::bound::transform::moved;
use crate::bound::triangle::{self, TriangleBound};
use crate::bound::{mapped, HitBound, Side, CELL_SLACK};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Aabb;
use crate::geometry::Ray;
use crate::quadric::{Others, Quadric, QuadricBound, RootBound};
use crate::simd::{with_avx2, Kernel};
use glam::{DMat3, DVec3};
use std::ops::Sub;

/// One `certain` query: the exact ray, the range `(0, limit]` searched for competitors, the
/// hit they compete with, and the size of the scene octree's root (see [`crate::bound::CELL_SLACK`]); the
/// ray's watertight set-up made once for all candidates.
#[derive(Debug, Clone, Copy)]
pub struct Probe<'a> {
    /// The ray's f64 origin, taken as exact.
    pub origin: DVec3,
    /// The ray's f64 direction, taken as exact.
    pub dir: DVec3,
    /// The same ray prepared for the watertight test's frame.
    pub watertight: WatertightRay,
    /// Competitors are crossings in `(0, limit]`.
    pub limit: f64,
    /// The reported hit (its instance triangle found), or `None` for a miss.
    pub hit: Option<&'a Crossing>,
    /// The largest side of the scene octree's root.
    pub root: f64,
}

impl<'a> Probe<'a> {
    /// The probe of `ray` up to `limit` against `hit`; `watertight` is the ray's watertight
    /// set-up (`WatertightRay::new` of its origin and direction), made by the caller, who may
    /// need it before.
    pub fn new(
        ray: &Ray,
        watertight: WatertightRay,
        limit: f64,
        hit: Option<&'a Crossing>,
        root: f64,
    ) -> Probe<'a> {
        Probe {
            origin: ray.origin,
            dir: ray.dir,
            watertight,
            limit,
            hit,
            root,
        }
    }
}

/// Whether a bounded crossing `t` may lie in `(0, limit]`.
fn may_lie_in(t: Bounded, limit: f64) -> bool {
    t.value + t.error > 0.0 && t.value - t.error <= limit
}

/// Whether a bounded triangle crossing may lie in `(0, limit]`.
fn triangle_competes(b: &TriangleBound, limit: f64) -> bool {
    b.side != Side::Outside && may_lie_in(b.t, limit)
}

/// Whether one of a quadric's exact crossings, other than `skip`, may lie in `(0, limit]`
/// inside its clip box.
fn quadric_competes(b: &QuadricBound, limit: f64, skip: Option<usize>) -> bool {
    let roots = b.roots.iter().enumerate().filter(|&(i, _)| Some(i) != skip);
    let root = roots
        .map(|(_, r)| r)
        .any(|r: &RootBound| !r.isolated || (r.clip != Side::Outside && may_lie_in(r.t, limit)));
    root || match b.others {
        Others::None => false,
        Others::Within(t) => may_lie_in(t, limit),
        Others::Beyond(reach) => reach.is_nan() || reach <= limit,
        Others::Unknown => true,
    }
}

/// Whether the exact plane of the triangle `tri` (vertices within `placement` of the stored
/// ones) certainly meets the probe's ray beyond its limit, so that the triangle cannot compete:
/// the f64 watertight test's `t` with the bound of [`residual::plane_error`] (every crossing
/// of the exact triangle lies on its exact plane). It passes over what the f64 filters of
/// [`triangle::certainly_apart`] cannot, a closed object's exit face (the ray crosses it, only
/// farther), for less than half the bounded recomputation's instructions.
fn plane_beyond(probe: &Probe, tri: &[DVec3; 3], placement: f64) -> bool {
    let Some(t) = probe.watertight.intersect(tri, f64::INFINITY) else {
        return false;
    };
    let ray = NearRay::exact(probe.origin, probe.dir);
    // `t − δ` rounded down: the exact crossing is at least that.
    residual::plane_error(&ray, tri, placement, t)
        .is_some_and(|error| bounded::down(t - error) > probe.limit)
}

/// The ray parameter where `origin + t·dir` leaves `aabb` (at most; `+∞` if it never does).
fn exit_t(aabb: &Aabb, origin: DVec3, dir: DVec3) -> f64 {
    (0..3)
        .map(|i| {
            let (a, b) = (
                (aabb.min[i] - origin[i]) / dir[i],
                (aabb.max[i] - origin[i]) / dir[i],
            );
            if a.is_nan() || b.is_nan() {
                f64::INFINITY
            } else {
                a.max(b)
            }
        })
        .fold(f64::INFINITY, f64::min)
}

impl Scene {
    /// The bound of `hit`, a crossing of the ray `origin + t·dir` (see [`crate::bound`]). A
    /// triangle's `t` is bounded by the residual of its exact plane
    /// ([`crate::bound::residual`]), or where that declines by the bounded recomputation of the
    /// watertight test; whether its own decision is certain (which takes that recomputation)
    /// only when `decide` is `Some` (`certain` is `false` otherwise); `Some(true)` says the
    /// search already found the exact ray certainly inside a hit world triangle (the test of
    /// [`triangle::certainly_inside`], which is then not made again).
    ///
    /// `origins` keeps quadrics' mapped origins for the next hits.
    #[inline(always)]
    pub fn hit_bound(
        &self,
        hit: &Crossing,
        (origin, dir): (DVec3, DVec3),
        decide: Option<bool>,
        origins: &mut Origins,
    ) -> HitBound {
        let unbounded = HitBound {
            t: Bounded::new(hit.t, f64::INFINITY),
            certain: false,
        };
        match self.top(hit.top as usize) {
            Top::Triangle(i) => {
                let tri = self.world.mesh.triangle(i);
                let ray = NearRay::exact(origin, dir);
                let placement = self.placement_of(i);
                let inside = || {
                    let watertight = WatertightRay::new(origin, dir);
                    triangle::certainly_inside(&watertight, &tri, placement)
                };
                let full =
                    || triangle::bound(&exact3(origin), &exact3(dir), &self.world_triangle(i));
                let decide = decide.map(|known_inside| known_inside || inside());
                triangle_hit(&ray, &tri, placement, hit.t, decide, full)
            }
            Top::Instance(k) => {
                let stored = &self.meshes[self.instances[k].mesh as usize];
                let Some(inner) = self.with_inner(hit, origin, dir).inner else {
                    return unbounded;
                };
                let (o, d) = self.instance_ray(k, origin, dir);
                let tri = self.bounded_instance_triangle(k, stored, inner as usize);
                let ray = NearRay {
                    origin: values3(&o),
                    origin_error: errors3(&o),
                    dir: values3(&d),
                    dir_error: errors3(&d),
                };
                let vertex_error = tri
                    .iter()
                    .map(|v| errors3(v).max_element())
                    .fold(0.0, f64::max);
                let stored_tri = tri.map(|v| values3(&v));
                let full = || triangle::bound(&o, &d, &tri);
                // The mapped ray is not exact: its side is the bounded recomputation's.
                let decide = decide.map(|_| false);
                triangle_hit(&ray, &stored_tri, vertex_error, hit.t, decide, full)
            }
            Top::Quadric(q) => {
                let quadric = &self.quadrics[q];
                let x0 = origins.get(hit.top, origin, || quadric.bounded_origin(origin));
                quadric_hit(quadric, (&x0, origin, dir), hit.t, decide.is_some())
            }
        }
    }

    /// `hit` with the triangle of the instance it hits, found again if it does not carry it
    /// (as [`Scene::locate`] does); unchanged for other primitives.
    pub fn with_inner(&self, hit: &Crossing, origin: DVec3, dir: DVec3) -> Crossing {
        let Top::Instance(k) = self.top(hit.top as usize) else {
            return *hit;
        };
        if hit.inner.is_some() {
            return *hit;
        }
        let instance = &self.instances[k];
        let stored = &self.meshes[instance.mesh as usize];
        let inner = instance
            .intersect(stored, origin, dir, hit.t)
            .map(|h| h.prim);
        Crossing { inner, ..*hit }
    }

    /// Whether top-level primitive `index` is `hit`'s own triangle or quadric: then it is no
    /// competitor of the hit ([`Scene::may_cross`] says no at once; a quadric's other roots are
    /// weighed by its hit bound). A hit instance's other triangles may compete.
    pub fn is_hit_itself(&self, index: usize, hit: Option<&Crossing>) -> bool {
        hit.is_some_and(|h| h.top as usize == index) && !matches!(self.top(index), Top::Instance(_))
    }

    /// Whether top-level primitive `index` may have an exact crossing with the probe's ray in
    /// `(0, limit]`, other than the probe's hit itself (see [`CELL_SLACK`] for the root).
    pub fn may_cross(&self, index: usize, probe: &Probe) -> bool {
        if self.is_hit_itself(index, probe.hit) {
            return false;
        }
        let own = probe.hit.filter(|h| h.top as usize == index);
        let (origin, dir, limit) = (probe.origin, probe.dir, probe.limit);
        match self.top(index) {
            Top::Triangle(i) => {
                let placement = self.placement_of(i);
                if placement > CELL_SLACK * probe.root {
                    return true;
                }
                let tri = self.world.mesh.triangle(i);
                if triangle::certainly_apart(&probe.watertight, &tri, placement, limit)
                    || plane_beyond(probe, &tri, placement)
                {
                    return false;
                }
                let b = triangle::bound(&exact3(origin), &exact3(dir), &self.world_triangle(i));
                triangle_competes(&b, limit)
            }
            Top::Instance(k) => self.instance_may_cross(k, origin, dir, limit, own),
            // The hit quadric's other roots are weighed by its hit bound ([`quadric_hit`]).
            Top::Quadric(q) => {
                if !self.quadrics[q].may_reach(origin, dir, limit) {
                    return false;
                }
                quadric_competes(&self.quadrics[q].bound_roots(origin, dir), limit, None)
            }
        }
    }

    /// Of the primitives `prims` (at most 32), those [`Scene::may_cross`] certainly says no
    /// to by the edge functions alone, world triangles four at a time ([`apart_four`] by
    /// `kernel`): bit `k` for `prims[k]`. Instances, quadrics and a triangle whose placement
    /// bound `may_cross` would not weigh (see [`CELL_SLACK`]; `root` as in [`Probe`]) are left
    /// to `may_cross`.
    pub fn apart(&self, ray: &WatertightRay, kernel: Kernel, prims: &[u32], root: f64) -> u32 {
        let mut apart = 0;
        for (g, group) in prims.chunks(LANES).enumerate() {
            let mut tris = [[DVec3::ZERO; 3]; LANES];
            let mut placement = [0.0; LANES];
            let mut active = 0;
            for (lane, &prim) in group.iter().enumerate() {
                let Top::Triangle(i) = self.top(prim as usize) else {
                    continue;
                };
                placement[lane] = self.placement_of(i);
                if placement[lane] > CELL_SLACK * root {
                    continue;
                }
                tris[lane] = self.world.mesh.triangle(i);
                active |= 1 << lane;
            }
            if active != 0 {
                apart |= apart_four(ray, kernel, &tris, &placement, active) << (LANES * g);
            }
        }
        apart
    }

    /// [`Scene::may_cross`] for instance `k`: its own octree along the mapped ray, every
    /// triangle but the hit's.
    fn instance_may_cross(
        &self,
        k: usize,
        origin: DVec3,
        dir: DVec3,
        limit: f64,
        own: Option<&Crossing>,
    ) -> bool {
        let instance = &self.instances[k];
        let stored = &self.meshes[instance.mesh as usize];
        let (o, d) = self.instance_ray(k, origin, dir);
        let (ov, dv) = (
            crate::bound::bounded::values3(&o),
            crate::bound::bounded::values3(&d),
        );
        let octree = stored.octree();
        let reach = limit.min(exit_t(
            &octree.root().translated(-stored.set.anchor),
            ov - stored.set.anchor,
            dv,
        ));
        let worst = |v: &BVec3| v.iter().map(|c| c.error).fold(0.0, f64::max);
        let vertices = self.instance_vertex_error(k);
        let drift = up(up(worst(&o) + up(reach.max(0.0) * worst(&d))) + vertices);
        if drift.is_nan() || drift > CELL_SLACK * octree.root().size().max_element() {
            return true;
        }
        let skip = own.map(|h| h.inner);
        octree.any_reference(ov - stored.set.anchor, dv, limit, |prim| {
            if skip == Some(Some(prim)) {
                return false;
            }
            let tri = self.bounded_instance_triangle(k, stored, prim as usize);
            triangle_competes(&triangle::bound(&o, &d, &tri), limit)
        })
    }

    /// A bound on how far the diagonal of `bounds` ([`Scene::world_bounds`], the box `raycast
    /// info` prints) may be from the diagonal of the same box made from exactly placed
    /// coordinates: each face moves by at most the largest placement bound of a world mesh
    /// (nested instances: what their composed matrix may move the farthest corner by), so each
    /// side by twice that and the diagonal by `2√3` times it, plus the rounding of the box's
    /// move from the anchor (`u` of the largest coordinate per face) and of the diagonal itself
    /// (`γ₆` of it). The box's own padding only makes it larger. Projective placements, whose
    /// rounding is not bounded, are left out.
    pub fn size_bound(&self, bounds: &Aabb) -> f64 {
        let world = self.placement.iter().copied().filter(|p| p.is_finite());
        let instances = self
            .instances
            .iter()
            .zip(&self.instance_errors)
            .map(|(i, e)| {
                let local = self.meshes[i.mesh as usize].set.mesh.bounds();
                moved(e, local.min.abs().max(local.max.abs()))
            });
        let moved = world.chain(instances).fold(0.0, f64::max);
        let far = bounds.min.abs().max(bounds.max.abs()).max_element();
        let faces = up(moved + gamma(1) * far);
        let size = bounds.size().length();
        up(2.0 * 3f64.sqrt() * up(faces * (1.0 + gamma(1))) + gamma(6) * size)
    }

    /// World triangle `i` with its placement bound.
    fn world_triangle(&self, i: usize) -> [BVec3; 3] {
        let error = self.placement_of(i);
        self.world.mesh.triangle(i).map(|v| within3(v, error))
    }

    /// The placement bound of world triangle `i`'s vertices.
    fn placement_of(&self, i: usize) -> f64 {
        self.placement[self.world_parts[i] as usize]
    }

    /// World triangle `i`'s placement bound where the search may pass over the triangle for
    /// a ray [`Scene::apart`] would find apart from it: the scene's rays are searched unmoved
    /// (anchor 0), so that the search's watertight set-up is the exact ray's, and the bound is
    /// one `apart` weighs for any octree of the scene (at most [`CELL_SLACK`] times the world
    /// triangles' extent, which the root's size is not below).
    pub(super) fn searched_apart(&self, i: usize) -> Option<f64> {
        let placement = self.placement_of(i);
        (self.anchor == DVec3::ZERO && placement <= self.apart_placement).then_some(placement)
    }

    /// The world ray in instance `k`'s mesh frame as the trace maps it, `L(o − T)` and `L d`,
    /// bounded against the exact image `M̂⁻¹o`, `M̂⁻¹d` through the f64 placement `M̂`
    /// ([`crate::bound::mapped`]; with FMA where the CPU has it, [`with_avx2`]).
    fn instance_ray(&self, k: usize, origin: DVec3, dir: DVec3) -> (BVec3, BVec3) {
        let instance = &self.instances[k];
        let (a, norm) = (instance.to_world.matrix3, instance.inverse_norm());
        let t = instance.to_world.translation;
        let l = instance.to_local.matrix3;
        with_avx2(
            #[inline(always)]
            || {
                let (o, t3) = (exact3(origin), exact3(t));
                let offset = [o[0].sub(t3[0]), o[1].sub(t3[1]), o[2].sub(t3[2])];
                (
                    mapped(a, &DMat3::ZERO, norm, &offset, l * (origin - t)),
                    mapped(a, &DMat3::ZERO, norm, &exact3(dir), l * dir),
                )
            },
        )
    }

    /// Triangle `i` of instance `k`'s stored mesh, each vertex `v` within `|Â⁻¹|(E_A|v| + E_T)`
    /// of the exact triangle in the `M̂` frame, componentwise (see
    /// [`Scene::instance_vertex_error`]; `|Â⁻¹| ≤ |L| + (‖Â⁻¹‖∞ − ‖L‖∞)` entrywise, `L` the f64
    /// inverse, from `Â⁻¹ = (I − E)⁻¹L` as in [`crate::bound::inverse_norm`]).
    fn bounded_instance_triangle(&self, k: usize, stored: &StoredMesh, i: usize) -> [BVec3; 3] {
        let tri = stored.set.mesh.triangle(i);
        let composed = &self.instance_errors[k];
        if *composed == glam::DMat4::ZERO {
            return tri.map(exact3);
        }
        let instance = &self.instances[k];
        let l = instance.to_local.matrix3.abs();
        let rows = l.transpose();
        let l_norm = [rows.x_axis, rows.y_axis, rows.z_axis]
            .map(|r| bounded::down(r.element_sum()))
            .into_iter()
            .fold(0.0, f64::max);
        let slack = up(instance.inverse_norm() - l_norm).max(0.0);
        let (a_error, t_error) = (DMat3::from_mat4(*composed), composed.w_axis.truncate());
        tri.map(|v| {
            let w = (a_error * v.abs() + t_error).to_array().map(up);
            let w = DVec3::from_array(w);
            let spread = (l * w + DVec3::splat(slack * w.max_element())).to_array();
            bounded3(v, DVec3::from_array(spread.map(up)))
        })
    }

    /// How far, per coordinate, instance `k`'s exact vertices may lie from its stored ones in
    /// the frame of its f64 placement `M̂`: the exact placement `M*` of a nested node
    /// ([`crate::bound::transform`]) draws vertex `v` at `M*v`, which `M̂` maps from
    /// `M̂⁻¹M*v = v + Â⁻¹((A* − Â)v + (T* − T̂))`, within `‖Â⁻¹‖∞ · max(E_A|v| + E_T)`; here `|v|` is
    /// taken at the corner of the mesh's bounds farthest from its origin (all vertices). Putting the
    /// composition's error on the vertices, not on the mapped ray, keeps it proportional to
    /// the mesh's size rather than to the ray origin's distance. Zero for a matrix as read.
    fn instance_vertex_error(&self, k: usize) -> f64 {
        let composed = &self.instance_errors[k];
        if *composed == glam::DMat4::ZERO {
            return 0.0;
        }
        let instance = &self.instances[k];
        let bounds = self.meshes[instance.mesh as usize].set.mesh.bounds();
        let far = bounds.min.abs().max(bounds.max.abs());
        up(instance.inverse_norm() * moved(composed, far))
    }
}

/// A triangle hit's bound: the reported `t` within the residual bound of its exact plane
/// ([`residual::plane_error`]), or, where that declines, within the distance to the recomputed
/// `t` plus its bound (`full`, [`triangle::bound`]). `decide` is `None` when `certain` is not
/// asked; otherwise it says whether a cheaper test already found the exact ray inside the
/// triangle ([`triangle::certainly_inside`]), and where it did not, the recomputation decides.
/// Certain when the exact ray crosses the interior in front of the origin.
#[inline(always)]
fn triangle_hit(
    ray: &NearRay,
    tri: &[DVec3; 3],
    vertex_error: f64,
    t: f64,
    decide: Option<bool>,
    full: impl Fn() -> TriangleBound,
) -> HitBound {
    let fast = residual::plane_error(ray, tri, vertex_error, t);
    let full = (decide == Some(false) || fast.is_none()).then(full);
    let recomputed = |b: &TriangleBound| up((t - b.t.value).abs() + b.t.error);
    let error = fast.or_else(|| full.as_ref().map(recomputed));
    let error = error.unwrap_or(f64::INFINITY);
    let inside = decide == Some(true) || full.is_some_and(|b| b.side == Side::Inside);
    HitBound {
        t: Bounded::new(t, error),
        certain: decide.is_some() && inside && t - error > 0.0,
    }
}

/// The index of the root nearest `t`.
fn nearest_root(b: &QuadricBound, t: f64) -> Option<usize> {
    (0..b.roots.len()).min_by(|&i, &j| {
        let d = |k: usize| (b.roots[k].t.value - t).abs();
        d(i).total_cmp(&d(j))
    })
}

/// A quadric hit's bound: the distance from the reported `t` to the nearest exact root
/// ([`Quadric::bound_root_at`]); with `decide`, all roots are bounded ([`Quadric::bound_roots`])
/// and the one the trace reports (the same check at the same `t`, so the same bound) decides:
/// certain when it is isolated, inside the clip box and in front of the origin, and no other
/// exact root may be a nearer valid crossing.
fn quadric_hit(
    quadric: &Quadric,
    (x0, origin, dir): (&BVec3, DVec3, DVec3),
    t: f64,
    decide: bool,
) -> HitBound {
    let alone = || HitBound {
        t: Bounded::new(t, quadric.bound_root_at(x0, dir, t).0),
        certain: false,
    };
    if !decide {
        return alone();
    }
    let b = quadric.bound_roots_from(x0, origin, dir);
    let Some(i) = nearest_root(&b, t).filter(|&i| b.roots[i].t.value == t) else {
        return alone();
    };
    let root = b.roots[i];
    let error = root.t.error;
    let own = root.isolated && root.clip == Side::Inside && t - error > 0.0;
    HitBound {
        t: root.t,
        certain: own && !quadric_competes(&b, up(t + error), Some(i)),
    }
}

mod origins;
pub use origins::Origins;

#[cfg(test)]
mod tests;
