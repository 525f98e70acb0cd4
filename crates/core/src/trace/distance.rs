//! Distance queries: the nearest surface point, and which side of the surface a point is on.
//!
//! # The nearest point
//! [`Tracer::closest`] searches the octree best first ([`Scene::nearest_point`]) and measures
//! each candidate triangle exactly in f64 (see [`crate::geometry::closest`] for the error: a
//! small multiple of ε times the triangle's size and the query's distance from it) and each
//! candidate quadric with [`Quadric::closest`] (the Lagrange condition in the quadric's
//! eigenbasis and the clip box's faces and edges; a few ε of the query's distance from the
//! quadric's anchor plus its size).
//!
//! # The side, by crossings
//! [`Tracer::side_by_crossings`] counts the crossings of rays from the point with the
//! watertight ownership rule of [`crate::geometry::triangle::WatertightRay::crossing`]: the
//! edge functions of a shared edge are exact negatives in both triangles, so a ray through an
//! edge or a vertex of a closed, consistently wound mesh crosses it exactly once, and a ray
//! that grazes a silhouette crosses both sides or neither. The parity of the count is
//! therefore exact whatever the ray passes through, except for the decision `t > 0` on a
//! crossing right at the point: the computed `t` of a crossing is off by less than
//! `32 ε R` (`R` bounding the distance from the point to any vertex, plus the point's own
//! magnitude for the instance frames' rounding; a generous multiple of the test's forward
//! error, which is a few ε times the vertices' distances from the origin along the ray). So a
//! point farther than [`Tracer::surface_margin`] from every surface gets a certain side, and
//! a nearer one is reported as on the surface (sign 0). Certain only for closed meshes (every
//! edge shared by two triangles in opposite directions, as `raycast info` reports per
//! object); for open ones the parity is a guess.
//!
//! Quadrics take part only when every one bounds a volume ([`Quadric::encloses`]: an
//! ellipsoid its clip box does not cut); any other quadric is an open surface with no
//! inside, and [`Signer::new`] refuses the scene, naming the object. A closed ellipsoid's
//! side is not counted along the rays but read from the sign of its polynomial at the point
//! ([`Quadric::inside`], certain off the surface to rounding, sign 0 on it), and its parity
//! joins the triangles' crossing parity: the rays' roots on a quadric are not exact, a
//! tangent ray touches it once, and a sign cannot be fooled that way.
//!
//! # The side, by winding number
//! [`winding_number`] sums the signed solid angles of all triangles seen from the point
//! (Van Oosterom and Strackee's formula), over 4π: 1 inside a closed, outward-wound surface,
//! 0 outside, and a smooth value in between where the surface has holes, so that a point is
//! inside when the number exceeds 1/2. Every triangle is visited for every point: O(N) per
//! point. Triangles only: a scene with quadrics is refused (a quadric's solid angle is not
//! summed).

use super::Tracer;
use crate::error::{Error, Result};
use crate::geometry::Aabb;
#[cfg(doc)]
use crate::quadric::Quadric;
use crate::scene::Nearest;
use glam::DVec3;

/// The unit roundoff of f64.
const EPS: f64 = f64::EPSILON / 2.0;

/// The nearest surface point to a query point, resolved to the scene's objects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NearestPoint {
    /// The nearest point (world coordinates).
    pub point: DVec3,
    /// Its distance from the query, measured from the triangle's vertices or about the
    /// quadric's anchor (not from `point`, which is rounded to world coordinates).
    pub distance: f64,
    /// The 1-based object id.
    pub id: u32,
    /// The triangle's number in its object, or the quadric's (as the `prim` buffer counts).
    pub prim: u32,
    /// The barycentric weights of the triangle's vertices, in the mesh's order; for a
    /// quadric, the nearest point in the quadric's own coordinates (where its coefficients
    /// are written).
    pub bary: [f64; 3],
    /// The triangle's unit geometric normal (world), or the quadric's unit gradient at the
    /// point (towards `f > 0`; towards the query where the gradient vanishes, as at a cone's
    /// apex), as the `normal` buffer gives it.
    pub normal: DVec3,
}

/// Which side of the scene's surfaces a point is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Inside: an odd number of surfaces around it (by crossings) or a winding number above
    /// 1/2.
    Inside,
    /// Outside.
    Outside,
    /// Within [`Tracer::surface_margin`] of a surface: no side is certain.
    OnSurface,
}

impl Side {
    /// The sign of the signed distance: −1 inside, +1 outside, 0 on the surface.
    pub fn sign(self) -> f64 {
        match self {
            Side::Inside => -1.0,
            Side::Outside => 1.0,
            Side::OnSurface => 0.0,
        }
    }
}

impl Tracer<'_> {
    /// The surface point nearest to `point`, on a triangle or a quadric; `None` for a point
    /// that is not finite or an empty scene.
    pub fn closest(&self, point: DVec3) -> Option<NearestPoint> {
        let Nearest { closest, crossing } = self.scene.nearest_point(self.octree, point)?;
        let at = point + closest.offset;
        // The normal's fallback for a degenerate triangle: towards the query.
        let located = self.scene.locate_crossing(&crossing, point, at - point);
        Some(NearestPoint {
            point: at,
            distance: closest.distance,
            id: located.object.id,
            prim: located.prim,
            bary: closest.bary,
            normal: located.normal,
        })
    }

    /// The distance below which [`Tracer::side_by_crossings`] cannot be sure of the side of
    /// `point`, for a scene whose world bounds are `bounds` (see the module docs).
    pub fn surface_margin(point: DVec3, bounds: &Aabb) -> f64 {
        let far = bounds
            .corners()
            .into_iter()
            .map(|c| (c - point).abs().max_element())
            .fold(0.0, f64::max);
        32.0 * EPS * (far + point.abs().max_element()) * 3f64.sqrt()
    }

    /// The side of `point`, at `distance` from the nearest surface, by the parity of the
    /// crossings of rays from it (certain for closed meshes; see the module docs) and the
    /// sides of the closed quadrics; `bounds` are the scene's world bounds. Meaningful when
    /// every quadric [`Quadric::encloses`] a volume ([`Signer::new`] checks).
    pub fn side_by_crossings(&self, point: DVec3, distance: f64, bounds: &Aabb) -> Side {
        if distance <= Tracer::surface_margin(point, bounds) || distance.is_nan() {
            return Side::OnSurface;
        }
        let (ellipsoids, on_ellipsoid) = self.ellipsoid_parity(point);
        if on_ellipsoid {
            return Side::OnSurface;
        }
        if self.crossing_parity(point) ^ ellipsoids {
            Side::Inside
        } else {
            Side::Outside
        }
    }
}

/// How the side of a point is decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignRule {
    /// The parity of exact watertight crossing counts (certain for closed meshes).
    Crossings,
    /// The generalised winding number above 1/2 (for meshes that are not closed).
    Winding,
}

impl SignRule {
    /// The rule's name, as `--sign` and Python's `sign=` take it.
    pub fn name(self) -> &'static str {
        match self {
            SignRule::Crossings => "crossings",
            SignRule::Winding => "winding",
        }
    }
}

/// Signed distances of many points in one scene: what [`Signer::measure`] needs, made once.
pub struct Signer<'a> {
    query: Tracer<'a>,
    rule: SignRule,
    bounds: Aabb,
    /// Every triangle of the scene in world coordinates, for [`SignRule::Winding`].
    triangles: Vec<[DVec3; 3]>,
}

impl<'a> Signer<'a> {
    /// Prepares signed distances in `query`'s scene by `rule`. Errors: a quadric that does
    /// not bound a volume (see the module docs), or any quadric for [`SignRule::Winding`],
    /// one line naming the object.
    pub fn new(query: Tracer<'a>, rule: SignRule) -> Result<Signer<'a>> {
        let scene = query.scene;
        let refused = scene
            .quadrics()
            .iter()
            .enumerate()
            .find(|(_, q)| match rule {
                SignRule::Crossings => !q.encloses(),
                SignRule::Winding => true,
            });
        if let Some((index, quadric)) = refused {
            let object = scene.quadric_object(index);
            let what = format!(
                "object '{}' (id {}) is a quadric ({})",
                object.name,
                object.id,
                quadric.kind().name()
            );
            return Err(Error::msg(match rule {
                SignRule::Crossings => format!(
                    "{what} clipped open by its box: it has no inside, so no signed distance \
                     (only an ellipsoid that its clip box does not cut is closed); its \
                     distance alone is defined (Python's Scene.distance and closest_points, \
                     raycast distance --sign none)"
                ),
                SignRule::Winding => format!(
                    "sign=winding sums the solid angles of triangles and has no rule for \
                     quadrics, and {what}; use sign=crossings (closed ellipsoids)"
                ),
            }));
        }
        let triangles = match rule {
            SignRule::Winding => scene
                .objects
                .iter()
                .flat_map(|o| scene.mesh_triangles(o))
                .collect(),
            SignRule::Crossings => Vec::new(),
        };
        Ok(Signer {
            query,
            rule,
            bounds: scene.world_bounds(),
            triangles,
        })
    }

    /// The nearest point of `point` (`None` for an empty scene) and its side.
    pub fn measure(&self, point: DVec3) -> (Option<NearestPoint>, Side) {
        let Some(nearest) = self.query.closest(point) else {
            return (None, Side::Outside);
        };
        let side = match self.rule {
            SignRule::Crossings => {
                self.query
                    .side_by_crossings(point, nearest.distance, &self.bounds)
            }
            SignRule::Winding if nearest.distance == 0.0 => Side::OnSurface,
            SignRule::Winding if winding_number(&self.triangles, point) > 0.5 => Side::Inside,
            SignRule::Winding => Side::Outside,
        };
        (Some(nearest), side)
    }

    /// The signed distance of `point`: +inf for an empty scene, 0 on the surface.
    pub fn signed_distance(&self, point: DVec3) -> f64 {
        signed(self.measure(point))
    }
}

/// The signed distance a [`Signer::measure`] result gives: +inf without a nearest point, 0 on
/// the surface.
pub fn signed((nearest, side): (Option<NearestPoint>, Side)) -> f64 {
    match (nearest, side) {
        (None, _) => f64::INFINITY,
        (Some(_), Side::OnSurface) => 0.0,
        (Some(n), side) => side.sign() * n.distance,
    }
}

/// The generalised winding number of `triangles` (world coordinates) at `point`: the sum of
/// their signed solid angles over 4π (see the module docs).
pub fn winding_number(triangles: &[[DVec3; 3]], point: DVec3) -> f64 {
    let total: f64 = triangles
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|v| v - point);
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let numerator = a.dot(b.cross(c));
            let denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
            2.0 * numerator.atan2(denominator)
        })
        .sum();
    total / (4.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::{Octree, OctreeParams};
    use crate::scene::{Scene, SceneBuilder};

    /// The unit cube [0, 1]³, wound outward (12 triangles).
    fn cube() -> Vec<[DVec3; 3]> {
        let v = |i: u32| DVec3::new(f64::from(i & 1), f64::from(i >> 1 & 1), f64::from(i >> 2));
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        quads
            .iter()
            .flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]])
            .collect()
    }

    fn scene_of(triangles: Vec<[DVec3; 3]>) -> (Scene, Octree) {
        let mut builder = SceneBuilder::new();
        builder.add_mesh("cube".into(), "test".into(), triangles);
        let scene = builder.finish("cube".into());
        let octree = Octree::build(&scene, OctreeParams::default());
        (scene, octree)
    }

    #[test]
    fn the_cube_is_wound_outward() {
        for tri in cube() {
            let [a, b, c] = tri;
            let n = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0 - DVec3::splat(0.5);
            assert!(n.dot(centre) > 0.0, "{tri:?}");
        }
    }

    #[test]
    fn distances_to_a_cube_by_hand() {
        let (scene, octree) = scene_of(cube());
        let query = Tracer::new(&scene, &octree);
        let bounds = scene.world_bounds();
        // Centre, a point beyond a corner, one on a face, one above an edge.
        let cases = [
            (DVec3::splat(0.5), 0.5, Side::Inside),
            (DVec3::splat(-0.5), 0.75f64.sqrt(), Side::Outside),
            (DVec3::new(0.3, 0.0, 0.6), 0.0, Side::OnSurface),
            (DVec3::new(0.5, 2.0, 2.0), 2f64.sqrt(), Side::Outside),
            (DVec3::new(1e-12, 0.5, 0.5), 1e-12, Side::Inside),
            (DVec3::new(-1e-12, 0.5, 0.5), 1e-12, Side::Outside),
        ];
        for (p, distance, side) in cases {
            let got = query.closest(p).expect("a cube has a nearest point");
            // A few ε of the cube's size (see `geometry::closest`).
            assert!((got.distance - distance).abs() <= 4.0 * EPS, "{p}: {got:?}");
            assert!((got.point - p).length() - distance <= 1e-15, "{p}: {got:?}");
            assert_eq!(
                query.side_by_crossings(p, got.distance, &bounds),
                side,
                "{p}"
            );
        }
    }

    #[test]
    fn winding_numbers_of_a_closed_and_an_open_cube() {
        let closed = cube();
        assert!((winding_number(&closed, DVec3::splat(0.5)) - 1.0).abs() < 1e-14);
        assert!(winding_number(&closed, DVec3::splat(3.0)).abs() < 1e-14);
        // The top face missing: the centre sees 5/6 of the sphere covered.
        let open: Vec<_> = closed
            .iter()
            .copied()
            .filter(|t| t.iter().any(|v| v.z < 1.0))
            .collect();
        assert_eq!(open.len(), 10);
        assert!((winding_number(&open, DVec3::splat(0.5)) - 5.0 / 6.0).abs() < 1e-14);
    }
}
