//! The BVH oracle (feature `bvh-oracle`): the nearest hits of an obvhs hierarchy
//! ([`crate::accel::bvh`]) through the renderer's buffers, for the tests that check the octree
//! against it and the benchmarks that measure it.

use super::{NearestHits, Tracer};
use crate::accel::{prepare_ray, Bvh};
use crate::geometry::Ray;
use crate::scene::{Crossing, Scene};

/// A scene with an obvhs BVH built over it. It finds nearest hits from `t = 0` only: a ray
/// whose range starts later, an untraceable ray or a NaN limit has none. It has no octree, so
/// the `certain` buffer it fills is 0 everywhere.
#[derive(Debug, Clone, Copy)]
pub struct BvhTracer<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The hierarchy built over it.
    pub bvh: &'a Bvh,
}

impl BvhTracer<'_> {
    /// The nearest crossing of `ray` with `0 < t <= t_max`, as [`Tracer::nearest`] finds it
    /// with `t_min = 0`; `None` for any other `t_min`.
    pub fn nearest(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<Crossing> {
        if t_min != 0.0 || !super::traceable(ray, t_min, t_max) {
            return None;
        }
        let local = ray.origin - self.scene.anchor;
        let prepared = prepare_ray(self.scene, local, ray.dir);
        self.bvh
            .intersect(self.scene, &prepared, t_max)
            .map(Crossing::from)
    }
}

impl NearestHits for BvhTracer<'_> {
    fn scene(&self) -> &Scene {
        self.scene
    }

    fn nearest_all(&self, rays: &[Ray], ranges: &[(f64, f64)]) -> Vec<Option<Crossing>> {
        let each = rays.iter().zip(ranges);
        each.map(|(ray, &(t_min, t_max))| self.nearest(ray, t_min, t_max))
            .collect()
    }

    fn tracer(&self) -> Option<Tracer<'_>> {
        None
    }
}
