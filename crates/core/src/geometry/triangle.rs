//! Triangles: the watertight ray test and the geometric normal (the tests against boxes that
//! the octree build uses are in [`super::triangle_box`]).
//!
//! Every test works in f64 on the vertices as stored (f32 file data promoted exactly, or f64),
//! so the only rounding is that of the arithmetic itself.

use glam::DVec3;

/// Per-ray constants of the watertight test (Woop, Benthin and Wald, JCGT 2013): the axis
/// permutation that makes z the dominant direction component, and the shear that maps the ray
/// onto the +z axis.
#[derive(Debug, Clone, Copy)]
pub struct WatertightRay {
    pub(super) origin: DVec3,
    pub(super) axes: [usize; 3],
    pub(super) shear: DVec3,
}

impl WatertightRay {
    /// The set-up of the ray `t · (0, 0, 1)` (`new(DVec3::ZERO, DVec3::Z)`), as a constant: it
    /// stands in where no triangle will be tested, for free.
    pub const Z_AXIS: WatertightRay = WatertightRay {
        origin: DVec3::ZERO,
        axes: [0, 1, 2],
        shear: DVec3::new(0.0, 0.0, 1.0),
    };

    /// Prepares `origin + t * dir` (same coordinates as the triangles; `dir` non-zero).
    #[inline]
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        let abs = dir.abs();
        let kz = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let shear = DVec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]);
        WatertightRay {
            origin,
            axes: [kx, ky, kz],
            shear,
        }
    }

    /// The axis permutation `[kx, ky, kz]`: `kz` is the direction's dominant axis.
    pub fn axes(&self) -> [usize; 3] {
        self.axes
    }

    /// The shear `(d[kx]/d[kz], d[ky]/d[kz], 1/d[kz])` and the origin, as computed.
    pub fn shear_and_origin(&self) -> (DVec3, DVec3) {
        (self.shear, self.origin)
    }

    /// The ray parameter `t` of the hit with triangle `tri`, if `0 < t <= t_max`.
    ///
    /// Watertight: a ray through a shared edge or vertex hits at least one of the triangles
    /// sharing it, because the edge functions of a shared edge are exact negatives of each
    /// other and a zero counts as inside.
    pub fn intersect(&self, tri: &[DVec3; 3], t_max: f64) -> Option<f64> {
        self.dispatch::<false>(tri, t_max)
    }

    /// Like [`WatertightRay::intersect`], but a ray through a shared edge or vertex crosses
    /// exactly one of the triangles sharing it, so that counting hits counts surface crossings.
    ///
    /// A zero edge function counts as inside only when its edge *owns* the ray: the edge's
    /// vector in the sheared plane, turned by the sign of the determinant (so that both
    /// triangles of a consistently wound surface see it the same way round), points up, or
    /// right when level — a top-left rule. The neighbour computes the same edge vector negated,
    /// exactly, so exactly one of the two owns it; around a vertex the ray passes through, the
    /// edges' directions wrap once around the circle, so exactly one triangle of the fan owns
    /// both of its edges there. Where the surface folds back (a silhouette the ray grazes) the
    /// two sides see opposite determinants, and the ray crosses both or neither: the parity of
    /// the count is still right.
    pub fn crossing(&self, tri: &[DVec3; 3], t_max: f64) -> Option<f64> {
        self.dispatch::<true>(tri, t_max)
    }

    /// The barycentric weights of `tri`'s vertices at the point where the ray's line meets
    /// its plane, from the same edge functions as the hit test (so they are exactly those a
    /// hit was decided on); `None` when the line is parallel to the plane.
    pub fn barycentric(&self, tri: &[DVec3; 3]) -> Option<[f64; 3]> {
        let [kx, ky, kz] = self.axes;
        let sheared = |v: DVec3| {
            let p = v - self.origin;
            DVec3::new(
                p[kx] - self.shear.x * p[kz],
                p[ky] - self.shear.y * p[kz],
                0.0,
            )
        };
        let weights = edge_functions(sheared(tri[0]), sheared(tri[1]), sheared(tri[2]));
        let det: f64 = weights.iter().sum();
        (det != 0.0).then(|| weights.map(|f| f / det))
    }

    /// One instance per axis permutation, so the permuted components are fixed fields.
    #[inline(always)]
    fn dispatch<const ONCE: bool>(&self, tri: &[DVec3; 3], t_max: f64) -> Option<f64> {
        match self.axes {
            [1, 2, 0] => self.intersect_in::<1, 2, 0, ONCE>(tri, t_max),
            [2, 1, 0] => self.intersect_in::<2, 1, 0, ONCE>(tri, t_max),
            [2, 0, 1] => self.intersect_in::<2, 0, 1, ONCE>(tri, t_max),
            [0, 2, 1] => self.intersect_in::<0, 2, 1, ONCE>(tri, t_max),
            [0, 1, 2] => self.intersect_in::<0, 1, 2, ONCE>(tri, t_max),
            _ => self.intersect_in::<1, 0, 2, ONCE>(tri, t_max),
        }
    }

    /// [`WatertightRay::intersect`] for the axis permutation `[KX, KY, KZ]`; with `ONCE`, the
    /// edge ownership rule of [`WatertightRay::crossing`].
    #[inline(always)]
    fn intersect_in<const KX: usize, const KY: usize, const KZ: usize, const ONCE: bool>(
        &self,
        tri: &[DVec3; 3],
        t_max: f64,
    ) -> Option<f64> {
        // Moves a vertex into the ray's sheared frame (z not yet scaled).
        let sheared = |v: DVec3| {
            let p = (v - self.origin).to_array();
            DVec3::new(
                p[KX] - self.shear.x * p[KZ],
                p[KY] - self.shear.y * p[KZ],
                p[KZ],
            )
        };
        let a = sheared(tri[0]);
        let b = sheared(tri[1]);
        let c = sheared(tri[2]);
        let [u, v, w] = edge_functions(a, b, c);
        let negative = u < 0.0 || v < 0.0 || w < 0.0;
        let positive = u > 0.0 || v > 0.0 || w > 0.0;
        if negative && positive {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        if ONCE && !owns_zero_edges([(u, b, c), (v, c, a), (w, a, b)], det) {
            return None;
        }
        let t = if det.abs() > self.sliver_bound(a, b, c) {
            let sz = self.shear.z;
            let t_scaled = u * sz * a.z + v * sz * b.z + w * sz * c.z;
            t_scaled / det
        } else {
            self.plane_t::<KX, KY, KZ>(tri)
        };
        // A direction with subnormal components overflows the shear to ±inf: no finite hit.
        (t > 0.0 && t <= t_max && t.is_finite()).then_some(t)
    }

    /// Below this `|det|` a hit's edge functions are too close to their rounding for the `t`
    /// made from them. A sheared coordinate `x' = p_x - shear.x · p_z` (`p` the vertex relative
    /// to the origin) carries rounding of about `u · (|p_x| + |shear.x · p_z|)`, at most
    /// `u · (|x'| + 2 |shear.x · p_z|)`; with `X` and `Y` those sizes summed over the vertices,
    /// `det` carries about `10u · X · Y`, and at `2⁻⁴⁰ · X · Y` that is a thousandth of `det`.
    /// Only slivers (three nearly collinear points) and triangles some million times smaller
    /// than their distance from the ray's origin come below it. `a`, `b`, `c` are the sheared
    /// vertices (z unscaled).
    #[inline(always)]
    fn sliver_bound(&self, a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let size = |v: DVec3| {
            let z = 2.0 * v.z.abs();
            (
                v.x.abs() + z * self.shear.x.abs(),
                v.y.abs() + z * self.shear.y.abs(),
            )
        };
        let ((xa, ya), (xb, yb), (xc, yc)) = (size(a), size(b), size(c));
        (xa + xb + xc) * (ya + yb + yc) * SLIVER
    }

    /// `t` where the ray meets the plane of `tri`, from the triangle's own edges (unsheared, so
    /// that coordinates a sliver shares exactly, as on a flat CAD face, stay exact): for a hit
    /// that [`WatertightRay::sliver_bound`] says the edge functions cannot place. The ray's
    /// direction is `(shear.x, shear.y, 1) / shear.z` in the permuted axes.
    #[cold]
    #[inline(never)]
    fn plane_t<const KX: usize, const KY: usize, const KZ: usize>(&self, tri: &[DVec3; 3]) -> f64 {
        let permute = |v: DVec3| DVec3::new(v[KX], v[KY], v[KZ]);
        let [a, b, c] = tri.map(permute);
        let normal = (b - a).cross(c - a);
        let along = normal.dot(DVec3::new(self.shear.x, self.shear.y, 1.0));
        normal.dot(a - permute(self.origin)) / along * self.shear.z
    }
}

/// The relative size below which `det` is too close to its rounding: see
/// [`WatertightRay::sliver_bound`].
const SLIVER: f64 = 1.0 / (1u64 << 40) as f64;

/// The edge functions of the sheared triangle `a b c`: twice the signed areas that the ray's
/// point makes with the edges opposite `a`, `b` and `c`.
#[inline(always)]
fn edge_functions(a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    [
        c.x * b.y - c.y * b.x,
        a.x * c.y - a.y * c.x,
        b.x * a.y - b.y * a.x,
    ]
}

/// True when every edge whose edge function is zero owns the ray (see
/// [`WatertightRay::crossing`]); each entry is an edge function with the edge's start and end
/// in the sheared frame.
#[inline(always)]
fn owns_zero_edges(edges: [(f64, DVec3, DVec3); 3], det: f64) -> bool {
    edges.iter().all(|&(f, from, to)| {
        if f != 0.0 {
            return true;
        }
        let (x, y) = if det > 0.0 {
            (to.x - from.x, to.y - from.y)
        } else {
            (from.x - to.x, from.y - to.y)
        };
        y > 0.0 || (y == 0.0 && x > 0.0)
    })
}

/// Unit geometric normal of a triangle from its winding (counter-clockwise = front), or
/// `None` for a degenerate triangle.
pub fn geometric_normal(tri: &[DVec3; 3]) -> Option<DVec3> {
    let [a, b, c] = *tri;
    (b - a).cross(c - a).try_normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::TEST_TRIANGLE as TRI;

    #[test]
    fn hits_at_the_analytic_distance() {
        let ray = WatertightRay::new(DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(ray.intersect(&TRI, f64::INFINITY), Some(2.5));
        assert_eq!(ray.intersect(&TRI, 2.0), None);
    }

    /// The constant is the set-up `new` makes for the +z axis (kz = 2, no swap, unit shear),
    /// and it tests like it: the plane z = 0 of the test triangle, met from below at t = 1.
    #[test]
    fn the_z_axis_constant_is_the_z_axis_set_up() {
        let made = WatertightRay::new(DVec3::ZERO, DVec3::Z);
        let constant = WatertightRay::Z_AXIS;
        assert_eq!(constant.axes(), made.axes());
        assert_eq!(constant.shear_and_origin(), made.shear_and_origin());
        let below = WatertightRay {
            origin: DVec3::new(0.0, 0.0, -1.0),
            ..WatertightRay::Z_AXIS
        };
        assert_eq!(below.intersect(&TRI, f64::INFINITY), Some(1.0));
    }

    #[test]
    fn misses_behind_and_beside() {
        let behind = WatertightRay::new(DVec3::new(0.0, 0.0, 5.0), DVec3::Z);
        assert_eq!(behind.intersect(&TRI, f64::INFINITY), None);
        let beside = WatertightRay::new(DVec3::new(3.0, 0.0, 5.0), -DVec3::Z);
        assert_eq!(beside.intersect(&TRI, f64::INFINITY), None);
    }

    #[test]
    fn subnormal_directions_give_no_infinite_hit() {
        // Along +z at 1e-310 per unit t, the plane z = 0 lies at t = 5e310 (analysis): beyond
        // f64, so no hit, rather than t = +inf.
        let ray = WatertightRay::new(DVec3::new(0.0, 0.0, -5.0), DVec3::new(0.0, 0.0, 1e-310));
        assert_eq!(ray.intersect(&TRI, f64::INFINITY), None);
    }

    #[test]
    fn normal_follows_winding() {
        assert_eq!(geometric_normal(&TRI), Some(DVec3::Z));
        let flipped = [TRI[0], TRI[2], TRI[1]];
        assert_eq!(geometric_normal(&flipped), Some(-DVec3::Z));
        assert_eq!(geometric_normal(&[TRI[0]; 3]), None);
    }
}
