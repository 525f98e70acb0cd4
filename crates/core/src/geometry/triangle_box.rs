//! Triangles against boxes, for the octree build: the exact overlap test, the octants of a cell
//! a triangle touches, and the bounds of the part of a triangle inside a cell.
//!
//! Every test works in f64 on the vertices as stored (f32 file data promoted exactly, or f64),
//! so the only rounding is that of the arithmetic itself.

use super::Aabb;
use glam::DVec3;

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
    if cell.holds(&bounds) {
        // No plane cuts it: clipping would keep the triangle as it is.
        return Some(bounds);
    }
    // Two polygons, clipped alternately one into the other: `from` holds the current one.
    let (mut a, mut b) = (Polygon::new(), Polygon::new());
    for v in tri {
        a.push(*v);
    }
    let mut clipping = Clipping {
        from: &mut a,
        to: &mut b,
    };
    clipping.slab::<0>(cell.min.x, cell.max.x);
    clipping.slab::<1>(cell.min.y, cell.max.y);
    clipping.slab::<2>(cell.min.z, cell.max.z);
    let polygon = clipping.from;
    let bounds = if polygon.overflowed {
        bounds.common(*cell)
    } else {
        Some(Aabb::from_points(polygon.vertices().iter().copied()))
    };
    bounds.filter(|b| !b.is_empty())
}

/// The two polygons of [`clipped_bounds`]: `from` the current one, `to` the one the next
/// plane clips it into.
struct Clipping<'p> {
    from: &'p mut Polygon,
    to: &'p mut Polygon,
}

impl Clipping<'_> {
    /// Clips the current polygon to the slab `[lo, hi]` on axis `AXIS`, the lower face first.
    fn slab<const AXIS: usize>(&mut self, lo: f64, hi: f64) {
        self.plane::<AXIS, false>(lo);
        self.plane::<AXIS, true>(hi);
    }

    /// Clips the current polygon to the inner side of the face `plane` (the upper face of the
    /// slab when `UPPER`).
    fn plane<const AXIS: usize, const UPPER: bool>(&mut self, plane: f64) {
        if self.from.clip_into::<AXIS, UPPER>(plane, self.to) {
            std::mem::swap(&mut self.from, &mut self.to);
        }
    }
}

/// A convex polygon of at most nine vertices: a triangle clipped by six planes. Rounding can
/// make a sliver's clipped polygon slightly non-convex, so that a plane adds more than one
/// vertex; a polygon that would outgrow the nine slots is marked `overflowed` instead, and
/// the caller falls back to the triangle's box within the cell.
struct Polygon {
    vertices: [DVec3; 9],
    len: usize,
    overflowed: bool,
}

impl Polygon {
    /// An empty polygon.
    fn new() -> Self {
        Polygon {
            vertices: [DVec3::ZERO; 9],
            len: 0,
            overflowed: false,
        }
    }

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

    /// Writes into `out` the part on the inner side of the face `plane` of axis `AXIS` (`p -
    /// plane >= 0` for a lower face, `<= 0` for an upper face: crossing points sit exactly
    /// on the plane) and returns true, or returns false when that part is the whole polygon (or
    /// it overflowed), leaving `out` as it is.
    fn clip_into<const AXIS: usize, const UPPER: bool>(
        &self,
        plane: f64,
        out: &mut Polygon,
    ) -> bool {
        let coord = |p: &DVec3| p.as_ref()[AXIS];
        let inside = |p: &DVec3| {
            let d = coord(p) - plane;
            if UPPER {
                d <= 0.0
            } else {
                d >= 0.0
            }
        };
        let vertices = self.vertices();
        if self.overflowed || vertices.iter().all(inside) {
            return false;
        }
        let (mut len, mut overflowed) = (0, false);
        let mut emit = |v: DVec3| {
            if len == out.vertices.len() {
                overflowed = true;
            } else {
                out.vertices[len] = v;
                len += 1;
            }
        };
        let mut p = vertices[vertices.len() - 1];
        let mut p_inside = inside(&p);
        for &q in vertices {
            // The edge from `p` to `q`, with `p` the previous vertex.
            let q_inside = inside(&q);
            if p_inside != q_inside {
                let s = (plane - coord(&p)) / (coord(&q) - coord(&p));
                let mut crossing = (p + (q - p) * s).to_array();
                crossing[AXIS] = plane;
                emit(DVec3::from_array(crossing));
            }
            if q_inside {
                emit(q);
            }
            (p, p_inside) = (q, q_inside);
        }
        (out.len, out.overflowed) = (len, overflowed);
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
    let mask = candidates & box_axes_mask(lo, hi, quarter, half);
    // Octants holding a point of the triangle well inside (`witness`) touch it: only the
    // others are still in question.
    let witness = Witness::new(&v, quarter, half, margin);
    let vertices = witness.map_or(0, |w| v.iter().fold(0, |m, &p| m | w.octants(p)));
    let mut test = OctantTest {
        v,
        quarter,
        half,
        mask,
        open: mask & !vertices,
    };
    if let Some(w) = witness.filter(|_| test.open != 0) {
        test.open &= !w.crossings(&v);
    }
    if test.open == 0 {
        return test.mask;
    }
    let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    test.axis(edges[0].cross(edges[1]));
    for e in edges {
        for axis in DVec3::AXES {
            if test.open == 0 {
                return test.mask;
            }
            test.axis(e.cross(axis));
        }
    }
    test.mask
}

/// The state of [`octant_mask`]'s separating-axis test: the triangle's vertices relative to
/// the cell centre, the octants' size, the octants not yet separated (`mask`) and those of
/// them whose overlap is still in question (`open`).
struct OctantTest {
    v: [DVec3; 3],
    quarter: DVec3,
    half: DVec3,
    mask: u8,
    open: u8,
}

impl OctantTest {
    /// Removes the octants that `axis` separates from the triangle.
    fn axis(&mut self, axis: DVec3) {
        if self.open == 0 || axis == DVec3::ZERO {
            return;
        }
        let v = &self.v;
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let (lo, hi) = extent(p);
        // Octant i's centre (±quarter on each axis) projected on the axis, term by term
        // (negating a product is exact).
        let q = self.quarter * axis;
        // Rounding is monotonic and odd, so every centre's computed projection lies in
        // [-reach, reach]; with that inside [lo, hi], `lo - c <= 0 <= radius` and
        // `hi - c >= 0 >= -radius` for every octant, and none is separated.
        let reach = q.x.abs() + q.y.abs() + q.z.abs();
        if lo <= -reach && hi >= reach {
            return;
        }
        // On an axis this small, rounding is not relative any more: test every octant.
        let candidates = if axis.abs().max_element() < TINY_AXIS {
            self.mask
        } else {
            self.open
        };
        let radius = self.half.dot(axis.abs());
        let (x, y, z) = ([-q.x, q.x], [-q.y, q.y], [-q.z, q.z]);
        let mut bits = candidates;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            let c = x[i & 1] + y[(i >> 1) & 1] + z[i >> 2];
            if lo - c > radius || hi - c < -radius {
                self.mask &= !(1 << i);
                self.open &= !(1 << i);
            }
            bits &= bits - 1;
        }
    }
}

/// The least and greatest of three projections, by plain comparisons (cheaper than
/// `f64::min`'s NaN rule). A NaN, which only an overflowing product can give, makes the
/// comparisons that use it false: the axis then separates less, never more.
fn extent([a, b, c]: [f64; 3]) -> (f64, f64) {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (if c < lo { c } else { lo }, if c > hi { c } else { hi })
}

/// Axes with no component above this in magnitude are tested in full by [`octant_mask`].
const TINY_AXIS: f64 = 1e-200;

/// The octants shrunk by `slack = margin / 2` on every side (spanning `±quarter ± inner`
/// about the cell centre, `inner = quarter + slack`), in which a point of the triangle
/// witnesses that the triangle touches the octant. A point inside an octant shrunk so cannot
/// be separated from it by [`octant_mask`]'s test: on an axis `a` the point lies `slack ·
/// |a|₁` inside the octant's projection, while the test's rounding is a few ulps of `|a|₁`
/// times the largest coordinate, kept below 2⁻⁴⁰ of it here (and axes below [`TINY_AXIS`],
/// where products may underflow, are tested in full). The look at a point has its own
/// rounding, a few ulps of the cell's size, which that slack also covers.
#[derive(Clone, Copy)]
struct Witness {
    /// The shrunk octants' outer faces: `2 quarter + slack` from the centre.
    outer: DVec3,
    slack: f64,
}

impl Witness {
    /// The witness octants for the triangle `v` (relative to the centre), or `None` when the
    /// margin is too little to stand for the rounding of the separating-axis test.
    fn new(v: &[DVec3; 3], quarter: DVec3, half: DVec3, margin: f64) -> Option<Witness> {
        let slack = 0.5 * margin;
        let scale = v
            .iter()
            .fold(half.max_element(), |m, p| m.max(p.abs().max_element()));
        let inner = half - DVec3::splat(slack);
        (slack > 0.0 && slack >= scale * TWO_TO_MINUS_40).then(|| Witness {
            outer: quarter + inner,
            slack,
        })
    }

    /// The shrunk octants holding the point `p` (relative to the centre): inside the shrunk
    /// cell, the octants on the side of each midplane that `p` is on, and on both sides
    /// where `p` lies within `slack` of the midplane.
    fn octants(&self, p: DVec3) -> u8 {
        // Without a branch on the first test (its outcome is not predictable).
        let inside = u8::from(p.abs().cmple(self.outer).all()).wrapping_neg();
        let axis = |a: usize, x: f64| {
            ALLOWED[a][usize::from(x <= self.slack) | usize::from(x >= -self.slack) << 1]
        };
        inside & axis(0, p.x) & axis(1, p.y) & axis(2, p.z)
    }

    /// The shrunk octants holding a point where an edge of the triangle `v` (relative to the
    /// centre) crosses one of the cell's midplanes. The point is placed exactly on the
    /// midplane, which lies inside both octants it separates, and its other coordinates carry
    /// a few ulps of rounding, as a vertex's projections do.
    fn crossings(&self, v: &[DVec3; 3]) -> u8 {
        let below = v.map(negative_axes);
        let mut mask = 0;
        for j in 0..3 {
            let k = (j + 1) % 3;
            let (p, q) = (v[j], v[k]);
            // The midplanes that the edge from p to q crosses.
            let mut crossed = below[j] ^ below[k];
            while crossed != 0 {
                let a = crossed.trailing_zeros() as usize;
                crossed &= crossed - 1;
                let mut x = p + (q - p) * (p[a] / (p[a] - q[a]));
                x[a] = 0.0;
                mask |= self.octants(x);
            }
        }
        mask
    }
}

/// 2⁻⁴⁰.
const TWO_TO_MINUS_40: f64 = 1.0 / (1u64 << 40) as f64;

/// By the bits (lower side touched, upper side touched) of axis a, the octants allowed: those
/// on the upper side of axis a have bit a set.
const ALLOWED: [[u8; 4]; 3] = [
    [0, 0b0101_0101, 0b1010_1010, 0xff],
    [0, 0b0011_0011, 0b1100_1100, 0xff],
    [0, 0b0000_1111, 0b1111_0000, 0xff],
];

/// The octants that the box `[lo, hi]` (relative to the cell centre) touches: octant `i`
/// spans `[c - half, c + half]` with `c = ±quarter` on each axis, so each
/// axis decides its lower and upper octants with one pair of comparisons.
fn box_axes_mask(lo: DVec3, hi: DVec3, quarter: DVec3, half: DVec3) -> u8 {
    // One axis: `x - (-q)` is `x + q` exactly.
    let axis = |a: usize, lo: f64, hi: f64, q: f64, r: f64| {
        let low = (lo + q <= r) & (hi + q >= -r);
        let high = (lo - q <= r) & (hi - q >= -r);
        ALLOWED[a][usize::from(low) | usize::from(high) << 1]
    };
    axis(0, lo.x, hi.x, quarter.x, half.x)
        & axis(1, lo.y, hi.y, quarter.y, half.y)
        & axis(2, lo.z, hi.z, quarter.z, half.z)
}

/// Bit a set when coordinate a of `p` is negative.
fn negative_axes(p: DVec3) -> u8 {
    u8::from(p.x < 0.0) | u8::from(p.y < 0.0) << 1 | u8::from(p.z < 0.0) << 2
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::geometry::TEST_TRIANGLE as TRI;

    #[test]
    fn clipping_a_polygon_past_nine_vertices_does_not_panic() {
        // Rounding can make a sliver's clipped polygon zigzag across a plane; nine vertices
        // alternating across x = 0.5 would need thirteen slots.
        let mut polygon = Polygon::new();
        for i in 0..9 {
            polygon.push(DVec3::new((i % 2) as f64, i as f64, 0.0));
        }
        let mut clipped = Polygon::new();
        assert!(polygon.clip_into::<0, false>(0.5, &mut clipped));
        assert!(clipped.overflowed);
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
            let expected = octants_by_box_test(tri, &cell, 1e-9);
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

    /// The octants of `cell` grown by `margin` that [`overlaps_box`] says the triangle touches.
    fn octants_by_box_test(tri: &[DVec3; 3], cell: &Aabb, margin: f64) -> u8 {
        (0..8)
            .filter(|&i| overlaps_box(tri, &cell.octant(i).expanded(margin)))
            .fold(0u8, |m, i| m | (1 << i))
    }

    #[test]
    fn octant_mask_agrees_with_the_box_test_on_cells_of_every_size() {
        // Triangles from a low-discrepancy sequence around the cell [-1, 1]³, from a tenth of
        // the cell to 10⁴ times its size (where every octant centre projects inside the
        // triangle on most edge axes), some with an edge parallel to a box axis.
        let unit = |k: usize| (k as f64 * 0.618_033_988_749_894_9).fract() * 2.0 - 1.0;
        let cell = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let mut seen = 0u8;
        for k in 0..3000 {
            let scale = [0.1, 1.0, 3.0, 1e2, 1e4][k % 5];
            let point = |j: usize| {
                let n = 9 * k + 3 * j;
                DVec3::new(unit(n), unit(n + 1), unit(n + 2)) * scale
            };
            let mut tri = [point(0), point(1), point(2)];
            if k % 7 == 0 {
                tri[1].y = tri[0].y;
            }
            let expected = octants_by_box_test(&tri, &cell, 1e-9);
            assert_eq!(octant_mask(&tri, &cell, 1e-9, 0xff), expected, "{tri:?}");
            seen |= expected;
            let partial = expected != 0 && expected != 0xff;
            if partial {
                assert_eq!(
                    octant_mask(&tri, &cell, 1e-9, 0b0101_1010),
                    expected & 0b0101_1010
                );
            }
        }
        assert_eq!(seen, 0xff);
    }
}
