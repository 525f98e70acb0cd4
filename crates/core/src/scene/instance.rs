//! Instances: one stored mesh, with its own octree, placed in the world by an f64 transform.
//!
//! A ray meets an instance the way it meets a quadric: it moves into the mesh's frame in f64
//! (`o' = T⁻¹ o`, `d' = T⁻¹ d`, not renormalised, so the parameter `t` is the same in both
//! frames), and the watertight test runs against the vertices as stored.

use super::mesh::MeshSet;
use crate::accel::{set_bits, Hit, Octree, OctreeParams, PreparedRay, PACKET};
use crate::geometry::triangle::WatertightRay;
use crate::geometry::{Aabb, ReachBox};
use crate::simd::Kernel;
use glam::{DAffine3, DMat4, DVec3};
use std::sync::OnceLock;

/// Rays of a packet reaching an instance from which they go through its octree as a packet:
/// with fewer, setting the packet up costs more than it saves (measured on instanced bunnies:
/// from two rays, +6 % instructions at 256²).
const PACKET_FROM: usize = 4;

/// A mesh stored once, with the octree over its triangles in its own frame. The octree is
/// built on first use ([`StoredMesh::octree`]), so that reading a scene (`raycast info`,
/// `check`) does not pay for it; a render builds all of them, in parallel, just before
/// the top-level structure (`Scene::build_instances`).
#[derive(Debug, Clone)]
pub struct StoredMesh {
    /// The mesh and the anchor of its octree's coordinates.
    pub set: MeshSet,
    params: OctreeParams,
    octree: OnceLock<Octree>,
}

impl StoredMesh {
    /// Stores `set`; its octree will be built with `params`.
    pub fn new(set: MeshSet, params: OctreeParams) -> StoredMesh {
        StoredMesh {
            set,
            params,
            octree: OnceLock::new(),
        }
    }

    /// The octree over `set`, built now if it was not yet.
    pub fn octree(&self) -> &Octree {
        self.octree
            .get_or_init(|| Octree::build(&self.set, self.params))
    }

    /// Drops the octree, so that the next use builds it again.
    pub(crate) fn forget_octree(&mut self) {
        self.octree.take();
    }

    /// Bytes of vertices, indices and (once built) octree.
    pub fn bytes(&self) -> usize {
        self.set.mesh.bytes() + self.octree.get().map_or(0, Octree::bytes)
    }

    /// [`StoredMesh::bytes`] without the shading attributes: what a trace reads.
    pub fn trace_bytes(&self) -> usize {
        self.set.mesh.trace_bytes() + self.octree.get().map_or(0, Octree::bytes)
    }
}

/// One placement of a stored mesh.
#[derive(Debug, Clone)]
pub struct Instance {
    /// Index of the stored mesh.
    pub mesh: u32,
    /// Mesh frame to world.
    pub to_world: DAffine3,
    /// World to mesh frame.
    pub to_local: DAffine3,
    /// The scene part it draws.
    pub part: u32,
    /// World bounds (the mesh bounds' corners placed, padded for their rounding), for the
    /// pre-test.
    reach: ReachBox,
    /// A bound on `‖A⁻¹‖∞` for `A = to_world.matrix3` ([`crate::bound::inverse_norm`]).
    inverse_norm: f64,
}

impl Instance {
    /// An instance of `mesh` placed by `world`; `None` unless `world` is an invertible affine
    /// map (projective or singular placements are stored as placed triangles instead).
    pub fn new(mesh: u32, stored: &StoredMesh, world: &DMat4, part: u32) -> Option<Instance> {
        if world.row(3) != glam::DVec4::W {
            return None;
        }
        let to_world = DAffine3::from_mat4(*world);
        let det = to_world.matrix3.determinant();
        if !det.is_finite() || det == 0.0 {
            return None;
        }
        let to_local = to_world.inverse();
        if !to_local.is_finite() {
            return None;
        }
        let local = stored.set.mesh.bounds();
        let bounds = Aabb::from_points(local.corners().map(|c| to_world.transform_point3(c)));
        let bounds = bounds.expanded(1e-12 * bounds.min.abs().max(bounds.max.abs()).max_element());
        Some(Instance {
            mesh,
            to_world,
            to_local,
            part,
            reach: ReachBox::new(bounds),
            inverse_norm: crate::bound::inverse_norm(to_world.matrix3, to_local.matrix3),
        })
    }

    /// A bound on `‖A⁻¹‖∞` for the placement's linear part `A`.
    pub fn inverse_norm(&self) -> f64 {
        self.inverse_norm
    }

    /// World bounds (the mesh bounds' corners placed, padded for their rounding).
    pub fn bounds(&self) -> Aabb {
        self.reach.bounds
    }

    /// The nearest hit with `0 < t <= t_max` of the world ray `origin + t · dir`: its `t`
    /// and the triangle's index in the mesh. Deterministic: the inner octree returns what
    /// a test of every triangle would, ties going to the smaller index.
    pub fn intersect(
        &self,
        stored: &StoredMesh,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
    ) -> Option<Hit> {
        self.intersect_by(stored.octree().kernel(), stored, origin, dir, t_max)
    }

    /// [`Instance::intersect`] by `kernel`: that of the traversal the ray comes from.
    pub fn intersect_by(
        &self,
        kernel: Kernel,
        stored: &StoredMesh,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
    ) -> Option<Hit> {
        if !self.may_reach(origin, dir, t_max) {
            return None;
        }
        self.trace(kernel, stored, origin, dir, t_max)
    }

    /// [`Instance::intersect_by`] for a ray [`Instance::may_reach`] has let through.
    fn trace(
        &self,
        kernel: Kernel,
        stored: &StoredMesh,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
    ) -> Option<Hit> {
        let frame = self.in_frame((origin, dir));
        let local = anchored(stored, frame);
        let prepare = || prepared(kernel, local, frame.0);
        stored
            .octree()
            .intersect_preparing(&stored.set, local, t_max, (kernel, prepare))
    }

    /// Whether the world ray `origin + t · dir` may meet the instance with `0 <= t <= t_max`:
    /// the bounds pre-test ([`ReachBox::may_reach`]). Every hit lies in the bounds (up to the
    /// rounding they are padded for), so no hit is passed over: the instance's octree and its
    /// set-up are skipped only for rays that cannot reach it before their best hit so far.
    pub fn may_reach(&self, origin: DVec3, dir: DVec3, t_max: f64) -> bool {
        self.reach.may_reach(origin, dir.recip(), t_max)
    }

    /// [`Instance::intersect`] for the rays `active` (bit `i` for ray `i`) of a packet, ray `i`
    /// given by `rays(i)` as its world origin and direction: the mask of the rays that hit,
    /// each with the `t` of its [`Instance::intersect`] answer in `ts`. The rays
    /// [`Instance::may_reach`] lets through go through the mesh's octree together when there
    /// are `PACKET_FROM` of them or more and their directions in the mesh frame can go as one
    /// packet, else one by one.
    pub fn intersect_packet(
        &self,
        kernel: Kernel,
        stored: &StoredMesh,
        rays: impl Fn(usize) -> (DVec3, DVec3),
        active: u32,
        (t_max, ts): (&[f64; PACKET], &mut [f64; PACKET]),
    ) -> u32 {
        let active = self.reach.reaching(kernel, &rays, active, t_max);
        if active == 0 {
            return 0;
        }
        let mut best = [None; PACKET];
        let as_packet = active.count_ones() as usize >= PACKET_FROM
            && self.trace_packet(kernel, stored, &rays, active, t_max, &mut best);
        if !as_packet {
            for i in set_bits(active) {
                let (origin, dir) = rays(i);
                best[i] = self.trace(kernel, stored, origin, dir, t_max[i]);
            }
        }
        let mut hits = 0;
        for i in set_bits(active) {
            if let Some(hit) = best[i] {
                ts[i] = hit.t;
                hits |= 1 << i;
            }
        }
        hits
    }

    /// The rays `active` (at least one) through the mesh's octree as one packet, their
    /// answers into `best`; false, with `best` untouched, when they cannot go as one
    /// ([`Octree::intersect_packet_preparing`]). Each ray's set-up for the triangle tests is
    /// made only if the packet reaches a leaf.
    fn trace_packet(
        &self,
        kernel: Kernel,
        stored: &StoredMesh,
        rays: &impl Fn(usize) -> (DVec3, DVec3),
        active: u32,
        t_max: &[f64; PACKET],
        best: &mut [Option<Hit>; PACKET],
    ) -> bool {
        // The rays not taking part stand in for the first one that does, with a limit of -inf.
        let first = active.trailing_zeros() as usize;
        let stand_in = self.in_frame(rays(first));
        let mut frame = [stand_in; PACKET];
        let mut limits = [f64::NEG_INFINITY; PACKET];
        for i in set_bits(active) {
            if i != first {
                frame[i] = self.in_frame(rays(i));
            }
            limits[i] = t_max[i];
        }
        let local = frame.map(|ray| anchored(stored, ray));
        let local_origins = local.map(|(origin, _)| origin);
        let dirs = local.map(|(_, dir)| dir);
        let prepare = |i: usize| prepared(kernel, local[i], frame[i].0);
        stored.octree().intersect_packet_preparing(
            &stored.set,
            &local_origins,
            &dirs,
            &limits,
            (kernel, prepare),
            best,
        )
    }

    /// The world ray `(origin, dir)` in the mesh frame (same `t`).
    #[inline]
    fn in_frame(&self, (origin, dir): (DVec3, DVec3)) -> (DVec3, DVec3) {
        // origin - translation first: near the instance that difference is exact or small, so
        // the mesh-frame origin keeps the digits of the ray's offset from the instance rather
        // than those of its distance from the world origin (same operation count as
        // transform_point3)
        let origin = self.to_local.matrix3 * (origin - self.to_world.translation);
        (origin, self.to_local.transform_vector3(dir) + DVec3::ZERO)
    }
}

/// The mesh-frame ray `(origin, dir)` in the coordinates of `stored`'s octree (the origin from
/// its anchor).
#[inline]
fn anchored(stored: &StoredMesh, (origin, dir): (DVec3, DVec3)) -> (DVec3, DVec3) {
    (origin - stored.set.anchor, dir)
}

/// A mesh-frame ray prepared for its octree: `local`, the ray in the octree's coordinates
/// ([`anchored`]), is traversed; the watertight set-up is made from `origin`, the ray's origin
/// in the mesh frame itself.
#[inline]
fn prepared(
    kernel: Kernel,
    (local_origin, dir): (DVec3, DVec3),
    origin: DVec3,
) -> PreparedRay<WatertightRay> {
    PreparedRay {
        local_origin,
        dir,
        extra: WatertightRay::new(origin, dir),
        kernel,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::Mesh;
    use crate::test_rng::Rng;
    use glam::DQuat;
    use std::sync::Arc;

    /// Every hit the instance's own octree finds for a world ray (the test without the
    /// pre-test) lies where [`Instance::may_reach`] lets the ray through with `t_max` the hit's
    /// `t`: placements rotated, scaled from 1e-3 to 1e3 and moved up to 1e6 away, rays aimed
    /// at the copy's triangles; and rays aimed away are refused, so the test can fail.
    #[test]
    fn the_bounds_pre_test_lets_every_hit_through() {
        let mut rng = Rng(0x0dd_ba11);
        let tris: Vec<[DVec3; 3]> = (0..60)
            .map(|_| {
                let c = rng.point(-1.0, 1.0);
                [
                    c + rng.point(-0.2, 0.2),
                    c + rng.point(-0.2, 0.2),
                    c + rng.point(-0.2, 0.2),
                ]
            })
            .collect();
        let set = MeshSet {
            mesh: Arc::new(Mesh::from_soup(&tris)),
            anchor: DVec3::ZERO,
        };
        let stored = StoredMesh::new(set, OctreeParams::default());
        let (mut hits, mut refused) = (0, 0);
        for round in 0..400 {
            let scale = 10f64.powi(round % 7 - 3);
            let rotation = DQuat::from_axis_angle(
                rng.point(-1.0, 1.0).normalize(),
                6.0 * rng.uniform(0.0, 1.0),
            );
            let place = {
                let reach = 10f64.powi(round % 7);
                rng.point(-reach, reach)
            } * scale;
            let world = DMat4::from_scale_rotation_translation(
                DVec3::new(
                    1.0 + rng.uniform(0.0, 1.0),
                    1.0 + rng.uniform(0.0, 1.0),
                    1.0 + rng.uniform(0.0, 1.0),
                ) * scale,
                rotation,
                place,
            );
            let instance = Instance::new(0, &stored, &world, 0).unwrap();
            for _ in 0..10 {
                let tri = tris[(rng.uniform(0.0, 1.0) * tris.len() as f64) as usize % tris.len()];
                let target = world.transform_point3((tri[0] + tri[1] + tri[2]) / 3.0);
                let origin = target + rng.point(-5.0 * scale, 5.0 * scale);
                let dir = target - origin;
                let kernel = Kernel::detect();
                if let Some(hit) = instance.trace(kernel, &stored, origin, dir, f64::INFINITY) {
                    assert!(instance.may_reach(origin, dir, hit.t), "round {round}");
                    hits += 1;
                }
                let away = instance.bounds().center() - origin;
                refused += usize::from(!instance.may_reach(origin, -away, f64::INFINITY));
            }
        }
        assert!(
            hits > 3000 && refused > 3000,
            "{hits} hits, {refused} refused"
        );
    }
}
