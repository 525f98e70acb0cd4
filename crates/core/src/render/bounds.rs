//! The `error` and `certain` buffers of a trace, from the bounds of [`crate::bound`] (what
//! they bound and mean is said there): a hit's bound, its depth error, and the search for a
//! competitor that decides `certain`.

use crate::accel::octree::OFFERED;
use crate::accel::{Offered, PACKET};
use crate::bound::bounded::{self, gamma, sum_error, up, Bounded};
use crate::bound::residual;
use crate::bound::HitBound;
use crate::geometry::triangle::WatertightRay;
use crate::geometry::Ray;
use crate::scene::{Crossing, Origins, Probe, Scene};
use crate::trace::{traceable, Tracer};
use glam::DVec3;
use std::ops::Mul;

/// The bound of `hit`, the nearest hit of `ray`: computed once per hit and shared by the
/// `error` and `certain` AOVs; whether the primitive's own decision is certain only when
/// `decide` is `Some` (the `certain` AOV asks for it), `Some(true)` when the search found the
/// exact ray certainly inside the hit triangle ([`Offered::crosses_inside`]). `origins`
/// carries mapped origins from hit to hit.
#[inline(always)]
pub fn hit_bound(
    scene: &Scene,
    ray: &Ray,
    hit: &Crossing,
    decide: Option<bool>,
    origins: &mut Origins,
) -> HitBound {
    scene.hit_bound(hit, (ray.origin, ray.dir), decide, origins)
}

/// The `error` AOV of a hit of `ray` from its bound: a bound on `|t·|d| − t*·|d||` (see the
/// module docs).
#[inline(always)]
pub fn depth_error(bound: &HitBound, ray: &Ray) -> f64 {
    let (t, dir) = (bound.t.value, ray.dir);
    if !residual::all_in_range([t, dir.x, dir.y, dir.z]) {
        return depth_bound(bound.t, dir).error;
    }
    // The exact roundings, by fused multiply-adds (exact in the range checked): `fl(d·d)` is
    // `S` less the products' errors `eᵢ` and the sums' `σ`; `r = Ŝ − L̂²` is the square root's
    // residual, so `|√Ŝ − L̂| ≤ |r| / (L̂(2 − u))`; `|√S − √Ŝ| ≤ |S − Ŝ| / (√Ŝ + √(Ŝ − E_S))`;
    // the depth `fl(t·L̂)` is off by its own product's error. Then
    // `|depth − t*|d|| ≤ e_depth + |t|·E_L + δₜ(L̂ + E_L)`.
    let p = dir * dir;
    let e = [
        dir.x.mul_add(dir.x, -p.x).abs(),
        dir.y.mul_add(dir.y, -p.y).abs(),
        dir.z.mul_add(dir.z, -p.z).abs(),
    ];
    let partial = p.x + p.y;
    let square = partial + p.z;
    let sums = sum_error(p.x, p.y, partial).abs() + sum_error(partial, p.z, square).abs();
    let square_error = up(e[0] + e[1] + e[2] + sums);
    let length = square.sqrt();
    let residual = (-length).mul_add(length, square).abs();
    let below = bounded::down(square - square_error).max(0.0).sqrt();
    let root_error = up(residual / bounded::down(length * (2.0 - gamma(1))))
        + up(square_error / bounded::down(length + below));
    let depth = t * length;
    let product = t.mul_add(length, -depth).abs();
    let length_error = up(root_error);
    up(up(product + t.abs() * length_error) + up(bound.t.error * up(length + length_error)))
}

/// `t·|d|` as the trace computes it (`dot` then `sqrt`), with its bound.
#[inline(always)]
fn depth_bound(t: Bounded, dir: DVec3) -> Bounded {
    let d = bounded::exact3(dir);
    t.mul(bounded::dot3(&d, &d).sqrt())
}

/// The `certain` AOV of `ray` with its nearest hit `hit` (and the hit's [`hit_bound`]) in the
/// range `(t_min, t_max]` (see the module docs). A hit must lie in the range by more than its
/// bound; crossings before `t_min` count as competitors too (conservative).
///
/// Cost: the hit's own test comes first (most uncertain hits are decided there, at no extra
/// cost); then one scalar traversal of the octree up to `t + δ` (or `t_max` for a miss),
/// each candidate passed over by [`crate::bound::triangle::certainly_apart`]'s f64 filters (a
/// depth range, the sheared triangle's box, the edge functions' signs) before any bounded
/// recomputation. [`certain_packet`] does the same for eight rays in one packet traversal;
/// [`certain_offered`] needs no traversal at all for a ray whose search noted what it offered
/// the ray (every ray of a render whose range starts at 0).
pub fn certain(
    tracer: &Tracer,
    ray: &Ray,
    hit: Option<(&Crossing, &HitBound)>,
    range: (f64, f64),
) -> bool {
    let Some(limit) = probe_limit(ray, hit, range) else {
        return false;
    };
    let (scene, local) = (tracer.scene, ray.origin - tracer.scene.anchor);
    let watertight = WatertightRay::new(ray.origin, ray.dir);
    no_competitor(tracer, ray, hit, (watertight, limit), |probe| {
        let competes = |prim: u32| scene.may_cross(prim as usize, probe);
        tracer.octree.any_reference(local, ray.dir, limit, competes)
    })
}

/// [`certain`] for [`PACKET`] rays (with their hits and ranges), their competitors searched
/// in one packet traversal of the octree ([`crate::accel::Octree::any_reference_packet`]),
/// or ray by ray when they cannot go as one packet: the same answers either way.
pub fn certain_packet(
    tracer: &Tracer,
    rays: &[Ray; PACKET],
    hits: &[Option<(&Crossing, &HitBound)>; PACKET],
    ranges: &[(f64, f64); PACKET],
) -> [bool; PACKET] {
    let limits: [Option<f64>; PACKET] =
        std::array::from_fn(|i| probe_limit(&rays[i], hits[i], ranges[i]));
    if limits.iter().all(Option::is_none) {
        return [false; PACKET];
    }
    let scene = tracer.scene;
    let inner: [Option<Crossing>; PACKET] = std::array::from_fn(|i| {
        let hit = hits[i].filter(|_| limits[i].is_some());
        hit.map(|(h, _)| scene.with_inner(h, rays[i].origin, rays[i].dir))
    });
    let probes: [Probe; PACKET] = std::array::from_fn(|i| {
        let limit = limits[i].unwrap_or(f64::NEG_INFINITY);
        let watertight = WatertightRay::new(rays[i].origin, rays[i].dir);
        probe(tracer, &rays[i], (watertight, limit), inner[i].as_ref())
    });
    let origins = rays.each_ref().map(|ray| ray.origin - scene.anchor);
    let dirs = rays.each_ref().map(|ray| ray.dir);
    let t_max = probes.each_ref().map(|p| p.limit);
    let competes = |i: usize, prim: u32| scene.may_cross(prim as usize, &probes[i]);
    let Some(found) = tracer
        .octree
        .any_reference_packet(&origins, &dirs, &t_max, competes)
    else {
        return std::array::from_fn(|i| certain(tracer, &rays[i], hits[i], ranges[i]));
    };
    std::array::from_fn(|i| limits[i].is_some() && found & (1 << i) == 0)
}

/// [`certain`] from what the ray's packet search offered it ([`Offered`], module
/// `accel::octree::notes`): the same answer without a second traversal, the offered
/// primitives weighed as [`certain`] weighs those its traversal meets. `None` when the offers
/// cannot decide it: more were offered than noted, or `t + δ` lies beyond the search's reach.
#[inline(always)]
pub fn certain_offered(
    tracer: &Tracer,
    ray: &Ray,
    hit: Option<(&Crossing, &HitBound)>,
    range: (f64, f64),
    offered: &Offered,
) -> Option<bool> {
    let Some(limit) = probe_limit(ray, hit, range) else {
        return Some(false);
    };
    let prims = offered.prims()?;
    let within = limit <= offered.reach;
    if !within {
        return None;
    }
    // Most rays are offered nothing but their own hit (the search leaves out what they
    // certainly miss), and the rest mostly neighbours the exact ray passes beside (four at a
    // time by `Scene::apart`): no probe to make for them.
    let (scene, own) = (tracer.scene, hit.map(|(h, _)| h));
    // The common case first, before the rivals' array is made.
    if prims.iter().all(|&p| scene.is_hit_itself(p as usize, own)) {
        return Some(true);
    }
    let mut rivals = [0; OFFERED];
    let mut count = 0;
    for &prim in prims
        .iter()
        .filter(|&&p| !scene.is_hit_itself(p as usize, own))
    {
        rivals[count] = prim;
        count += 1;
    }
    let watertight = WatertightRay::new(ray.origin, ray.dir);
    let root = root_size(tracer);
    let apart = scene.apart(&watertight, tracer.octree.kernel(), &rivals[..count], root);
    let mut left = (0..count)
        .filter(|k| apart & (1 << k) == 0)
        .map(|k| rivals[k])
        .peekable();
    if left.peek().is_none() {
        return Some(true);
    }
    Some(no_competitor(
        tracer,
        ray,
        hit,
        (watertight, limit),
        |probe| left.any(|prim| scene.may_cross(prim as usize, probe)),
    ))
}

/// Whether `search` finds no competitor of `ray`'s `hit` up to `reach`'s limit (with the ray's
/// watertight set-up): it is handed the ray's probe (the hit's instance triangle found) and
/// says whether some candidate primitive may cross the ray there ([`Scene::may_cross`]).
fn no_competitor(
    tracer: &Tracer,
    ray: &Ray,
    hit: Option<(&Crossing, &HitBound)>,
    reach: (WatertightRay, f64),
    search: impl FnOnce(&Probe) -> bool,
) -> bool {
    let hit = hit.map(|(h, _)| tracer.scene.with_inner(h, ray.origin, ray.dir));
    !search(&probe(tracer, ray, reach, hit.as_ref()))
}

/// How far `certain`'s search for a competitor goes: `t + δ` for a hit whose own decision is
/// certain and which lies inside `(t_min, t_max]` by more than its bound, `t_max` for a miss;
/// `None` when the ray is uncertain already, or was not traced (a ray or range
/// [`traceable`] refuses is a miss with a warning, or an error, never a certain one).
fn probe_limit(
    ray: &Ray,
    hit: Option<(&Crossing, &HitBound)>,
    (t_min, t_max): (f64, f64),
) -> Option<f64> {
    if !traceable(ray, t_min, t_max) {
        return None;
    }
    let Some((_, bound)) = hit else {
        return Some(t_max);
    };
    let (low, high) = (
        bound.t.value - bound.t.error,
        up(bound.t.value + bound.t.error),
    );
    let decided = !bound.certain || low.is_nan() || low <= t_min || high > t_max;
    (!decided).then_some(high)
}

/// The probe of `ray` (with its watertight set-up) up to `limit` against its hit (its
/// instance triangle found).
fn probe<'a>(
    tracer: &Tracer,
    ray: &Ray,
    (watertight, limit): (WatertightRay, f64),
    hit: Option<&'a Crossing>,
) -> Probe<'a> {
    Probe::new(ray, watertight, limit, hit, root_size(tracer))
}

/// The largest side of the scene octree's root ([`Probe::root`]).
fn root_size(tracer: &Tracer) -> f64 {
    tracer.octree.root().size().max_element()
}
