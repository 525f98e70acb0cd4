//! The nearest surface point of the scene to a query point, found through the octree.
//!
//! The octree's boxes are searched best first ([`Octree::nearest`]) with a lower bound
//! on the distance to each box; a leaf's world triangles are measured exactly
//! ([`closest_on_triangle`]), an instance's mesh is searched through its own octree, its
//! boxes and triangles placed in the world by the instance's transform, and a quadric is
//! measured whole by [`Quadric::closest`] (its box in the octree bounds its clipped surface
//! as a triangle's bounds the triangle, so the same lower bounds hold). Distances are world
//! distances for every kind of placement, so an instance scaled unevenly is measured as drawn.

use super::{Crossing, Instance, Scene, StoredMesh, Top};
use crate::accel::Octree;
use crate::geometry::closest::{closest_on_triangle, Closest};
use crate::quadric::Quadric;
use glam::DVec3;

/// The unit roundoff of f64.
const EPS: f64 = f64::EPSILON / 2.0;

/// The nearest surface point to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nearest {
    /// The nearest point and its distance, as measured on the primitive (offset from the
    /// query, distance, barycentric weights of the triangle's vertices in the mesh's order;
    /// for a quadric, the nearest point in the quadric's own coordinates instead).
    pub closest: Closest,
    /// The top-level primitive, and for an instance the triangle's index in its mesh, as
    /// the crossing of the ray from the query along `closest.offset` at `t = 1`.
    pub crossing: Crossing,
}

impl Nearest {
    /// The nearer of `self` and `other`; a tie goes to the smaller primitive, then the smaller
    /// instance triangle, so the answer does not depend on the search order.
    fn nearer(self, other: Nearest) -> Nearest {
        let key = |n: &Nearest| (n.closest.distance, n.crossing.top, n.crossing.inner);
        if key(&other).partial_cmp(&key(&self)) == Some(std::cmp::Ordering::Less) {
            other
        } else {
            self
        }
    }
}

impl Scene {
    /// The surface point nearest to `point` among the scene's triangles (world and
    /// instanced) and quadrics, searched through `octree` (built over this scene); `None` for
    /// an empty scene or a point that is not finite.
    pub fn nearest_point(&self, octree: &Octree, point: DVec3) -> Option<Nearest> {
        if !point.is_finite() {
            return None;
        }
        let local = point - self.anchor;
        // `local` is rounded by at most EPS · |local| per component.
        let slack = 2.0 * EPS * local.abs().max_element();
        let mut best: Option<Nearest> = None;
        octree.nearest(
            |b| lower_bound(box_distance(local, b), slack),
            |top| {
                let limit = best.map_or(f64::INFINITY, |b| b.closest.distance);
                if let Some(found) = self.nearest_in(top, point, limit) {
                    best = Some(best.map_or(found, |b| b.nearer(found)));
                }
                best.map_or(f64::INFINITY, |b| b.closest.distance)
            },
        );
        best
    }

    /// The nearest point of top-level primitive `top` to `point`, if it may be within `limit`.
    fn nearest_in(&self, top: u32, point: DVec3, limit: f64) -> Option<Nearest> {
        match self.top(top as usize) {
            Top::Triangle(i) => Some(Nearest {
                closest: closest_on_triangle(point, &self.world.mesh.triangle(i)),
                crossing: Crossing {
                    t: 1.0,
                    top,
                    inner: None,
                },
            }),
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let stored = &self.meshes[instance.mesh as usize];
                nearest_in_instance(instance, stored, point, limit).map(|(closest, inner)| {
                    Nearest {
                        closest,
                        crossing: Crossing {
                            t: 1.0,
                            top,
                            inner: Some(inner),
                        },
                    }
                })
            }
            Top::Quadric(q) => {
                nearest_on_quadric(&self.quadrics[q], point, limit).map(|closest| Nearest {
                    closest,
                    crossing: Crossing {
                        t: 1.0,
                        top,
                        inner: None,
                    },
                })
            }
        }
    }
}

/// The nearest point of an instance's placed triangles to the world point `point`, and the
/// triangle's index in the mesh, searched through the mesh's octree with its boxes placed in
/// the world. Only triangles that may be within `limit` are measured.
fn nearest_in_instance(
    instance: &Instance,
    stored: &StoredMesh,
    point: DVec3,
    limit: f64,
) -> Option<(Closest, u32)> {
    let to_world = &instance.to_world;
    let a = to_world.matrix3;
    let abs = glam::DMat3::from_cols(a.x_axis.abs(), a.y_axis.abs(), a.z_axis.abs());
    let mut best: Option<(Closest, u32)> = None;
    let mut limit = limit;
    stored.octree().nearest(
        |b| {
            // The box placed: centre A·c + t, half extents |A|·h, each rounded by less than
            // a few EPS of |A|·|c| + |t| + |A|·h (bounded generously by `slack`).
            let lo = DVec3::new(b[0].into(), b[1].into(), b[2].into());
            let hi = DVec3::new(b[3].into(), b[4].into(), b[5].into());
            let centre = (lo + hi) * 0.5 + stored.set.anchor;
            let half = (hi - lo) * 0.5;
            let placed = to_world.transform_point3(centre);
            let reach = abs * half;
            let size =
                (abs * centre.abs()).max_element() + to_world.translation.abs().max_element();
            let slack = 16.0 * EPS * (size + reach.max_element() + point.abs().max_element());
            let gap = (point - placed).abs() - reach;
            lower_bound(gap.max(DVec3::ZERO).length(), slack)
        },
        |prim| {
            let tri = stored
                .set
                .mesh
                .triangle(prim as usize)
                .map(|v| to_world.transform_point3(v));
            let found = closest_on_triangle(point, &tri);
            let better = match best {
                None => found.distance <= limit,
                Some((b, i)) => (found.distance, prim) < (b.distance, i),
            };
            if better {
                best = Some((found, prim));
                limit = found.distance;
            }
            limit
        },
    );
    best
}

/// The nearest point of a quadric to `point`, with the point in the quadric's own
/// coordinates where a triangle's has its barycentric weights.
fn nearest_on_quadric(quadric: &Quadric, point: DVec3, limit: f64) -> Option<Closest> {
    let found = quadric.closest(point, limit)?;
    Some(Closest {
        offset: found.offset,
        distance: found.distance,
        bary: found.local.to_array(),
    })
}

/// The distance from `p` to the box `b` (rows `min x, y, z, max x, y, z`), as computed.
fn box_distance(p: DVec3, b: &[f32; 6]) -> f64 {
    let lo = DVec3::new(b[0].into(), b[1].into(), b[2].into());
    let hi = DVec3::new(b[3].into(), b[4].into(), b[5].into());
    (lo - p).max(p - hi).max(DVec3::ZERO).length()
}

/// A lower bound on the exact distance whose computed value is `computed`, when the query
/// was off by at most `slack`: the subtractions, squares, sum and root round by less than
/// 4 EPS relative.
fn lower_bound(computed: f64, slack: f64) -> f64 {
    (computed * (1.0 - 4.0 * EPS) - slack).max(0.0)
}
