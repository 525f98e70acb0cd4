//! Every crossing of a ray with one top-level primitive, not only the nearest: what the
//! multiple-hit queries of [`crate::query`] are made of.
//!
//! Triangles are tested with [`WatertightRay::crossing`], so that a ray through a shared edge
//! or vertex of a consistently wound mesh crosses it once; a quadric gives each of its roots
//! inside the clip box. An instance is searched with its own octree, and its crossings carry the
//! triangle's number in the mesh, so that no later search has to find it again.

use super::{PartKind, Scene, SceneRay, Top};
use crate::accel::{Hit, PreparedRay};
use crate::geometry::triangle::WatertightRay;
use glam::DVec3;

/// One crossing of a ray with the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Ray parameter: the point is `origin + t · dir`.
    pub t: f64,
    /// The top-level primitive (as in [`crate::accel::Hit::prim`]).
    pub top: u32,
    /// For an instance, the triangle's index in its mesh; `None` otherwise, or when not known.
    pub inner: Option<u32>,
}

impl From<Hit> for Crossing {
    /// The crossing of a nearest hit (no instance triangle recorded).
    fn from(hit: Hit) -> Crossing {
        Crossing {
            t: hit.t,
            top: hit.prim,
            inner: None,
        }
    }
}

/// How a triangle counts a ray through one of its edges or vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EdgeRule {
    /// Every triangle sharing the edge is hit ([`WatertightRay::intersect`], the nearest-hit
    /// rule).
    Inclusive,
    /// Exactly one of them is ([`WatertightRay::crossing`], for counting crossings).
    Once,
}

impl EdgeRule {
    fn test(self, ray: &WatertightRay, tri: &[DVec3; 3], t_max: f64) -> Option<f64> {
        match self {
            EdgeRule::Inclusive => ray.intersect(tri, t_max),
            EdgeRule::Once => ray.crossing(tri, t_max),
        }
    }
}

impl Scene {
    /// Appends to `out` every crossing of top-level primitive `index` with
    /// `t_min < t <= t_max` (and `t > 0`).
    pub fn crossings_of(
        &self,
        index: usize,
        ray: &PreparedRay<SceneRay>,
        (t_min, t_max): (f64, f64),
        rule: EdgeRule,
        out: &mut Vec<Crossing>,
    ) {
        let top = index as u32;
        let origin = ray.extra.world_origin;
        match self.top(index) {
            Top::Triangle(i) => {
                let hit = rule.test(&ray.extra.triangle, &self.world.mesh.triangle(i), t_max);
                if let Some(t) = hit.filter(|&t| t > t_min) {
                    out.push(Crossing {
                        t,
                        top,
                        inner: None,
                    });
                }
            }
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let stored = &self.meshes[instance.mesh as usize];
                let o = instance.to_local.transform_point3(origin);
                let d = instance.to_local.transform_vector3(ray.dir) + DVec3::ZERO;
                let local = WatertightRay::new(o, d);
                stored
                    .octree()
                    .traverse(o - stored.set.anchor, d, t_max, |refs, _, _| {
                        for &prim in refs {
                            let tri = stored.set.mesh.triangle(prim as usize);
                            if let Some(t) = rule.test(&local, &tri, t_max).filter(|&t| t > t_min) {
                                out.push(Crossing {
                                    t,
                                    top,
                                    inner: Some(prim),
                                });
                            }
                        }
                        t_max
                    });
            }
            Top::Quadric(q) => {
                let roots = self.quadrics[q].crossings(origin, ray.dir, t_min, t_max);
                out.extend(roots.into_iter().map(|t| Crossing {
                    t,
                    top,
                    inner: None,
                }));
            }
        }
    }

    /// The barycentric weights of the crossed triangle's vertices (in the mesh's order) at a
    /// crossing of the ray `origin + t · dir`; `None` for a quadric.
    pub fn barycentric(&self, crossing: &Crossing, origin: DVec3, dir: DVec3) -> Option<[f64; 3]> {
        match self.top(crossing.top as usize) {
            Top::Triangle(i) => {
                WatertightRay::new(origin, dir).barycentric(&self.world.mesh.triangle(i))
            }
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let stored = &self.meshes[instance.mesh as usize];
                let inner = self.instance_triangle(k, crossing, origin, dir)?;
                let o = instance.to_local.transform_point3(origin);
                let d = instance.to_local.transform_vector3(dir) + DVec3::ZERO;
                WatertightRay::new(o, d).barycentric(&stored.set.mesh.triangle(inner as usize))
            }
            Top::Quadric(_) => None,
        }
    }

    /// The triangle of instance `k`'s mesh that a crossing of the ray `origin + t · dir` is
    /// on: the one it carries, else found by tracing the instance up to the crossing's `t`.
    pub(super) fn instance_triangle(
        &self,
        k: usize,
        crossing: &Crossing,
        origin: DVec3,
        dir: DVec3,
    ) -> Option<u32> {
        let instance = &self.instances[k];
        let stored = &self.meshes[instance.mesh as usize];
        match crossing.inner {
            Some(inner) => Some(inner),
            None => Some(instance.intersect(stored, origin, dir, crossing.t)?.prim),
        }
    }

    /// Resolves a crossing of the ray `origin + t · dir` like [`Scene::locate`], using the
    /// instance triangle the crossing carries instead of searching the instance again.
    pub fn locate_crossing(
        &self,
        crossing: &Crossing,
        origin: DVec3,
        dir: DVec3,
    ) -> super::Located<'_> {
        let hit = crate::accel::Hit {
            t: crossing.t,
            prim: crossing.top,
        };
        let (Top::Instance(k), Some(inner)) = (self.top(crossing.top as usize), crossing.inner)
        else {
            return self.locate(&hit, origin, dir);
        };
        let part = self.part_of(crossing.top);
        debug_assert!(matches!(part.kind, PartKind::Instance(_)));
        let instance = &self.instances[k];
        let stored = &self.meshes[instance.mesh as usize];
        let normal = stored
            .set
            .normal(inner as usize, Some(&instance.to_world))
            .unwrap_or_else(|| -dir.normalize_or_zero());
        super::Located {
            object: &self.objects[part.object as usize],
            prim: part.first_prim + inner,
            normal,
        }
    }
}
