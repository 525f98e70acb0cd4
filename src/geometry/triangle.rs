//! Triangles: the watertight ray test and the exact triangle/box overlap test.
//!
//! Every test works in f64 on the vertices as stored (f32 file data promoted exactly, or f64),
//! so the only rounding is that of the arithmetic itself.

use super::Aabb;
use glam::DVec3;

/// Per-ray constants of the watertight test (Woop, Benthin and Wald, JCGT 2013): the axis
/// permutation that makes z the dominant direction component, and the shear that maps the ray
/// onto the +z axis.
#[derive(Debug, Clone, Copy)]
pub struct WatertightRay {
    origin: DVec3,
    axes: [usize; 3],
    shear: DVec3,
}

impl WatertightRay {
    /// Prepares `origin + t * dir` (same coordinates as the triangles; `dir` non-zero).
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

/// Exact separating-axis test: does the closed triangle touch the closed box?
///
/// Axes: the three box normals, the triangle normal and the nine edge/box-axis cross products
/// (Akenine-Möller 2001). Computed in f64 on the exact f32 vertex values.
pub fn overlaps_box(tri: &[DVec3; 3], aabb: &Aabb) -> bool {
    let centre = aabb.center();
    let half = aabb.size() * 0.5;
    let v = tri.map(|p| p - centre);
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: DVec3| {
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let radius = half.dot(axis.abs());
        p[0].min(p[1]).min(p[2]) > radius || p[0].max(p[1]).max(p[2]) < -radius
    };
    if DVec3::AXES.into_iter().any(separated) || separated(edges[0].cross(edges[1])) {
        return false;
    }
    !edges
        .iter()
        .flat_map(|e| DVec3::AXES.map(|axis| e.cross(axis)))
        .any(separated)
}

/// Bounds of the part of the triangle inside `cell` (Sutherland–Hodgman clipping against the
/// six faces), or `None` when clipping leaves nothing. The clipped vertices carry rounding of
/// a few ulps of the coordinates; callers grow the box by their margin.
pub fn clipped_bounds(tri: &[DVec3; 3], cell: &Aabb) -> Option<Aabb> {
    let bounds = Aabb::from_points(tri.iter().copied());
    if bounds.min.cmpge(cell.min).all() && bounds.max.cmple(cell.max).all() {
        // No plane cuts it: clipping would keep the triangle as it is.
        return Some(bounds);
    }
    // Two polygons, clipped alternately one into the other.
    let mut pair = [Polygon::default(), Polygon::default()];
    let mut current = 0;
    for v in tri {
        pair[0].push(*v);
    }
    for axis in 0..3 {
        for (plane, side) in [(cell.min[axis], 1.0), (cell.max[axis], -1.0)] {
            let [a, b] = &mut pair;
            let (from, to) = if current == 0 { (a, b) } else { (b, a) };
            if from.clip_into(axis, plane, side, to) {
                current ^= 1;
            }
        }
    }
    let polygon = &pair[current];
    let bounds = if polygon.overflowed {
        bounds.common(*cell)
    } else {
        Some(Aabb::from_points(polygon.vertices().iter().copied()))
    };
    bounds.filter(|b| !b.is_empty())
}

/// A convex polygon of at most nine vertices: a triangle clipped by six planes. Rounding can
/// make a sliver's clipped polygon slightly non-convex, so that a plane adds more than one
/// vertex; a polygon that would outgrow the nine slots is marked `overflowed` instead, and
/// the caller falls back to the triangle's box within the cell.
#[derive(Default)]
struct Polygon {
    vertices: [DVec3; 9],
    len: usize,
    overflowed: bool,
}

impl Polygon {
    fn push(&mut self, v: DVec3) {
        if self.len == self.vertices.len() {
            self.overflowed = true;
            return;
        }
        self.vertices[self.len] = v;
        self.len += 1;
    }

    fn vertices(&self) -> &[DVec3] {
        &self.vertices[..self.len]
    }

    /// Writes into `out` the part with `side · (p[axis] - plane) >= 0` (crossing points sit
    /// exactly on the plane) and returns true, or returns false when that part is the whole
    /// polygon (or it overflowed), leaving `out` as it is.
    fn clip_into(&self, axis: usize, plane: f64, side: f64, out: &mut Polygon) -> bool {
        // Coordinates by array index (indexing a `DVec3` branches on the axis).
        let coord = |p: &DVec3| p.as_ref()[axis];
        let inside = |p: &DVec3| side * (coord(p) - plane) >= 0.0;
        if self.overflowed || self.vertices().iter().all(inside) {
            return false;
        }
        out.len = 0;
        out.overflowed = false;
        let mut p = self.vertices[self.len - 1];
        let mut p_inside = inside(&p);
        for &q in self.vertices() {
            // The edge from `p` to `q`, with `p` the previous vertex.
            let q_inside = inside(&q);
            if p_inside != q_inside {
                let s = (plane - coord(&p)) / (coord(&q) - coord(&p));
                let mut crossing = (p + (q - p) * s).to_array();
                crossing[axis] = plane;
                out.push(DVec3::from_array(crossing));
            }
            if q_inside {
                out.push(q);
            }
            (p, p_inside) = (q, q_inside);
        }
        true
    }
}

/// Which of the octants in `candidates` (bit `i` for [`Aabb::octant`] `i`) of `cell`, each
/// grown by `margin`, the closed triangle touches. The same separating-axis test as
/// [`overlaps_box`]: the three box axes reduce to comparing the triangle's bounds with the
/// cell's midplanes, and for the other ten axes each projection of the triangle is computed
/// once and compared with every octant still in question. A zero axis (an edge parallel to a
/// box axis, or the normal of a degenerate triangle) separates nothing and is skipped.
pub fn octant_mask(tri: &[DVec3; 3], cell: &Aabb, margin: f64, candidates: u8) -> u8 {
    let centre = cell.center();
    let quarter = cell.size() * 0.25;
    let half = quarter + DVec3::splat(margin);
    let v = tri.map(|p| p - centre);
    let (lo, hi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
    let mut mask = candidates & box_axes_mask(lo, hi, quarter, half);
    // Octants still in question: those holding a vertex well inside touch the triangle.
    let mut open = mask & !holding_a_vertex(&v, quarter, half, margin);
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let mut axes = [edges[0].cross(edges[1]); 10];
    for (k, e) in edges.iter().enumerate() {
        for (j, axis) in DVec3::AXES.into_iter().enumerate() {
            axes[1 + 3 * k + j] = e.cross(axis);
        }
    }
    for axis in axes {
        if open == 0 {
            break;
        }
        if axis == DVec3::ZERO {
            continue;
        }
        // On an axis this small, rounding is not relative any more: test every octant.
        let open_here = if axis.abs().max_element() < TINY_AXIS {
            mask
        } else {
            open
        };
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let radius = half.dot(axis.abs());
        // Octant i's centre (±quarter on each axis) projected on the axis, term by term
        // (negating a product is exact).
        let q = quarter * axis;
        let (x, y, z) = ([-q.x, q.x], [-q.y, q.y], [-q.z, q.z]);
        let mut bits = open_here;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            let c = x[i & 1] + y[(i >> 1) & 1] + z[i >> 2];
            if lo - c > radius || hi - c < -radius {
                mask &= !(1 << i);
                open &= !(1 << i);
            }
            bits &= bits - 1;
        }
    }
    mask
}

/// Axes with no component above this in magnitude are tested in full by [`octant_mask`].
const TINY_AXIS: f64 = 1e-200;

/// The octants (spanning `±quarter ± half` about the cell centre on each axis) holding one
/// of the vertices `v` (relative to the centre) at least `margin / 2` inside. The
/// separating-axis test of [`octant_mask`] cannot separate such an octant: on an axis `a`
/// the vertex lies `margin / 2 · |a|₁` inside the octant's projection, while the test's
/// rounding is a few ulps of `|a|₁` times the largest coordinate, kept below 2⁻⁴⁰ of it here
/// (and axes below [`TINY_AXIS`], where products may underflow, are tested in full).
fn holding_a_vertex(v: &[DVec3; 3], quarter: DVec3, half: DVec3, margin: f64) -> u8 {
    let slack = 0.5 * margin;
    let scale = v
        .iter()
        .fold(half.max_element(), |m, p| m.max(p.abs().max_element()));
    if slack <= 0.0 || slack < scale * TWO_TO_MINUS_40 {
        return 0;
    }
    let inner = half - DVec3::splat(slack);
    v.iter()
        .fold(0, |m, &p| m | box_axes_mask(p, p, quarter, inner))
}

/// 2⁻⁴⁰.
const TWO_TO_MINUS_40: f64 = 1.0 / (1u64 << 40) as f64;

/// The octants that the box `[lo, hi]` (relative to the cell centre) touches: octant `i`
/// spans `[c - half, c + half]` with `c = ±quarter` on each axis, so each
/// axis decides its lower and upper octants with one pair of comparisons.
fn box_axes_mask(lo: DVec3, hi: DVec3, quarter: DVec3, half: DVec3) -> u8 {
    // Octants on the upper side of axis a (bit a of i set), for a = x, y, z.
    const UPPER: [u8; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];
    let mut mask = 0xff;
    for (a, upper) in UPPER.into_iter().enumerate() {
        let touches = |c: f64| lo[a] - c <= half[a] && hi[a] - c >= -half[a];
        let (low_side, high_side) = (touches(-quarter[a]), touches(quarter[a]));
        mask &= match (low_side, high_side) {
            (true, true) => 0xff,
            (true, false) => !upper,
            (false, true) => upper,
            (false, false) => 0,
        };
    }
    mask
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [DVec3; 3] = [
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];

    #[test]
    fn hits_at_the_analytic_distance() {
        let ray = WatertightRay::new(DVec3::new(0.0, 0.0, 5.0), DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(ray.intersect(&TRI, f64::INFINITY), Some(2.5));
        assert_eq!(ray.intersect(&TRI, 2.0), None);
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
    fn clipping_a_polygon_past_nine_vertices_does_not_panic() {
        // Rounding can make a sliver's clipped polygon zigzag across a plane; nine vertices
        // alternating across x = 0.5 would need thirteen slots.
        let mut polygon = Polygon::default();
        for i in 0..9 {
            polygon.push(DVec3::new((i % 2) as f64, i as f64, 0.0));
        }
        let mut clipped = Polygon::default();
        assert!(polygon.clip_into(0, 0.5, 1.0, &mut clipped));
        assert!(clipped.overflowed);
    }

    #[test]
    fn normal_follows_winding() {
        assert_eq!(geometric_normal(&TRI), Some(DVec3::Z));
        let flipped = [TRI[0], TRI[2], TRI[1]];
        assert_eq!(geometric_normal(&flipped), Some(-DVec3::Z));
        assert_eq!(geometric_normal(&[TRI[0]; 3]), None);
    }

    #[test]
    fn octant_mask_agrees_with_the_box_test() {
        let cell = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let tris = [
            TRI,
            [
                DVec3::new(0.1, 0.1, 0.1),
                DVec3::new(0.9, 0.2, 0.3),
                DVec3::new(0.2, 0.8, 0.9),
            ],
            [
                DVec3::new(-0.9, 0.8, -0.1),
                DVec3::new(0.95, -0.9, 0.2),
                DVec3::new(0.7, 0.9, 0.05),
            ],
            [
                DVec3::new(0.5, -2.0, 0.5),
                DVec3::new(0.5, 2.0, 0.5),
                DVec3::new(-3.0, 0.0, -0.2),
            ],
        ];
        for tri in &tris {
            let expected = (0..8)
                .filter(|&i| overlaps_box(tri, &cell.octant(i).expanded(1e-9)))
                .fold(0u8, |m, i| m | (1 << i));
            assert_eq!(octant_mask(tri, &cell, 1e-9, 0xff), expected, "{tri:?}");
            for candidates in [0b0000_0001, 0b1010_0101, 0b0111_1110] {
                let restricted = octant_mask(tri, &cell, 1e-9, candidates);
                assert_eq!(restricted, expected & candidates, "{tri:?}");
            }
        }
    }

    #[test]
    fn clipping_bounds_the_part_inside_the_cell() {
        let v = |x, y, z| DVec3::new(x, y, z);
        // The hypotenuse x + y = 2 leaves the whole unit square inside.
        let big = [v(-1.0, -1.0, 0.0), v(3.0, -1.0, 0.0), v(-1.0, 3.0, 0.0)];
        let unit = Aabb::new(DVec3::ZERO, DVec3::ONE);
        let b = clipped_bounds(&big, &unit).unwrap();
        assert_eq!((b.min, b.max), (DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)));
        // Inside x >= 1 the triangle x, y >= 0, x + y <= 2 spans x in [1, 2], y in [0, 1].
        let corner = [v(0.0, 0.0, 0.5), v(2.0, 0.0, 0.5), v(0.0, 2.0, 0.5)];
        let cell = Aabb::new(DVec3::new(1.0, 0.0, 0.0), DVec3::splat(3.0));
        let b = clipped_bounds(&corner, &cell).unwrap();
        assert_eq!(b.min, DVec3::new(1.0, 0.0, 0.5));
        assert_eq!(b.max, DVec3::new(2.0, 1.0, 0.5));
        let away = Aabb::new(DVec3::splat(5.0), DVec3::splat(6.0));
        assert!(clipped_bounds(&corner, &away).is_none());
    }

    #[test]
    fn box_overlap_is_exact() {
        let unit = Aabb::new(DVec3::splat(-0.5), DVec3::splat(0.5));
        assert!(overlaps_box(&TRI, &unit));
        // Box whose bounding boxes overlap the triangle's but which lies beyond its slanted edge.
        let corner = Aabb::new(DVec3::new(0.8, 0.8, -0.1), DVec3::new(1.0, 1.0, 0.1));
        assert!(!overlaps_box(&TRI, &corner));
        // Touching the plane z = 0 from above counts (closed box).
        let touching = Aabb::new(DVec3::new(-0.1, -0.1, 0.0), DVec3::new(0.1, 0.1, 1.0));
        assert!(overlaps_box(&TRI, &touching));
        let above = Aabb::new(DVec3::new(-0.1, -0.1, 0.001), DVec3::new(0.1, 0.1, 1.0));
        assert!(!overlaps_box(&TRI, &above));
    }
}
