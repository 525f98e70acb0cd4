//! The point of a triangle nearest to a query point, in f64.
//!
//! The triangle's Voronoi regions are told apart by the signs of six dot products of the
//! edges with the query's offsets from the vertices (the classic region test: a vertex, an
//! edge's interior or the face), and the nearest point is the vertex, the projection onto the
//! edge or the projection onto the plane. Everything is computed from differences with the
//! vertices, so a triangle far from the origin loses nothing to its position: the distance is
//! measured as `|(p − a) − (v · ab + w · ac)|`, never as the difference of two world points.
//!
//! # Accuracy
//! Each dot product has an error below γ₃ of the product of its operands' lengths, so a region
//! is mistaken only for a query within a few ulps (relative to `L`, the largest of `|p − a|`,
//! `|ab|` and `|ac|`) of the boundary between two regions, where the nearest points of both
//! regions lie within that distance of each other: the distance function is continuous across
//! region boundaries. The parameters along an edge or across the face then carry a relative
//! error of a few ε, and the reported distance an absolute error of a small multiple of `ε · L`
//! (inside the face, a few ε of the distance itself: it is the height over the plane)
//! (tests/python/test_py_distance.py measures it against exact rational arithmetic).
//! Degenerate triangles (collinear or coincident vertices) are measured as their longest
//! edge, a segment.

use glam::DVec3;

/// The nearest point of a triangle to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// The offset from the query to the nearest point: the nearest point is `query + offset`.
    pub offset: DVec3,
    /// `|offset|`.
    pub distance: f64,
    /// The nearest point's barycentric weights of the three vertices (summing to 1).
    pub bary: [f64; 3],
}

/// The point of triangle `tri` nearest to `p`.
pub fn closest_on_triangle(p: DVec3, tri: &[DVec3; 3]) -> Closest {
    let [a, b, c] = *tri;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(ap, ab, ac, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return at(ap, ab, ac, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return at(ap, ab, ac, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return at(ap, ab, ac, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return at(ap, ab, ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return at(ap, ab, ac, [0.0, 1.0 - w, w]);
    }
    let sum = va + vb + vc;
    if !(sum > 0.0 && sum.is_finite()) {
        return on_longest_edge(p, tri);
    }
    let (v, w) = (vb / sum, vc / sum);
    on_face(ap, ab, ac, [1.0 - v - w, v, w])
}

/// The result inside the face: the query projected onto the plane along the normal `n`, so
/// that the distance `|n · ap| / |n|` is exact to a few ε of itself (a query on the plane is
/// at distance 0), where `at`'s difference would be off by ε times the triangle's size.
fn on_face(ap: DVec3, ab: DVec3, ac: DVec3, bary: [f64; 3]) -> Closest {
    let n = ab.cross(ac);
    let height = n.dot(ap);
    let offset = n * (-height / n.length_squared());
    Closest {
        offset,
        distance: height.abs() / n.length(),
        bary,
    }
}

/// The result for barycentric weights `bary`: the offset `(v · ab + w · ac) − (p − a)`.
fn at(ap: DVec3, ab: DVec3, ac: DVec3, bary: [f64; 3]) -> Closest {
    let offset = ab * bary[1] + ac * bary[2] - ap;
    Closest {
        offset,
        distance: offset.length(),
        bary,
    }
}

/// A degenerate triangle measured as its longest edge (which covers the other two).
fn on_longest_edge(p: DVec3, tri: &[DVec3; 3]) -> Closest {
    let edges = [(0, 1), (1, 2), (2, 0)];
    let (i, j) = edges
        .into_iter()
        .max_by(|&(a, b), &(c, d)| {
            let (x, y) = ((tri[b] - tri[a]).length(), (tri[d] - tri[c]).length());
            x.total_cmp(&y)
        })
        .expect("three edges");
    let (ab, ap) = (tri[j] - tri[i], p - tri[i]);
    let length2 = ab.length_squared();
    let s = if length2 > 0.0 {
        (ab.dot(ap) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let offset = ab * s - ap;
    let mut bary = [0.0; 3];
    bary[i] = 1.0 - s;
    bary[j] += s;
    Closest {
        offset,
        distance: offset.length(),
        bary,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, 0.0),
    ];

    #[test]
    fn each_region_gives_its_feature() {
        // Above the face, beside each vertex and beyond each edge: worked out by hand.
        let cases = [
            (DVec3::new(0.8, 0.2, 1.0), [0.2, 0.6, 0.2], 1.0),
            (DVec3::new(-1.0, -1.0, 0.0), [1.0, 0.0, 0.0], 2f64.sqrt()),
            (DVec3::new(2.0, -1.0, 0.0), [0.0, 1.0, 0.0], 2f64.sqrt()),
            (DVec3::new(2.0, 2.0, 0.0), [0.0, 0.0, 1.0], 2f64.sqrt()),
            (DVec3::new(0.5, -2.0, 0.0), [0.5, 0.5, 0.0], 2.0),
            (DVec3::new(3.0, 0.5, 0.0), [0.0, 0.5, 0.5], 2.0),
            (DVec3::new(0.0, 1.0, 0.0), [0.5, 0.0, 0.5], 0.5f64.sqrt()),
        ];
        for (p, bary, distance) in cases {
            let got = closest_on_triangle(p, &TRI);
            let off = (0..3)
                .map(|i| (got.bary[i] - bary[i]).abs())
                .fold(0.0, f64::max);
            assert!(off < 1e-15, "{p}: {got:?}");
            assert!((got.distance - distance).abs() < 1e-15, "{p}: {got:?}");
        }
    }

    #[test]
    fn degenerate_triangles_are_their_longest_edge() {
        let line = [DVec3::X, DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0)];
        for got in [
            closest_on_triangle(DVec3::new(1.5, 1.0, 0.0), &line),
            on_longest_edge(DVec3::new(1.5, 1.0, 0.0), &line),
        ] {
            let point: DVec3 = (0..3).map(|i| line[i] * got.bary[i]).sum();
            assert_eq!((got.distance, point), (1.0, DVec3::new(1.5, 0.0, 0.0)));
        }
        let far = on_longest_edge(DVec3::new(-3.0, 0.0, 0.0), &line);
        assert_eq!((far.distance, far.bary), (3.0, [0.0, 1.0, 0.0]));
        let point = [DVec3::ONE; 3];
        let got = closest_on_triangle(DVec3::ZERO, &point);
        assert_eq!(got.distance, 3f64.sqrt());
        assert!(got.bary.iter().sum::<f64>() == 1.0);
    }
}
