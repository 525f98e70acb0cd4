//! Checks on the loaded scene: an empty scene, degenerate triangles, open or non-manifold
//! meshes, holes (rays through a mesh that should be closed that cross its surface an odd
//! number of times), inverted normals (a closed mesh with negative signed volume) and the
//! scene's size against `--expect-size`.
//!
//! Closedness is topological ([`crate::scene::topology`]); an open mesh that is meant closed
//! (small holes: [`crate::scene::topology::Topology::meant_closed`]) is checked for holes like
//! a closed one.

use super::{CheckOptions, Findings, SceneStats};
use crate::scene::topology::topology;
use crate::scene::{ObjectKind, Scene};
use crate::Code;
use glam::DVec3;
use raycast_core::geometry::triangle::WatertightRay;

/// Rays cast through each closed or nearly closed mesh.
pub const HOLE_RAYS: usize = 64;

/// Most ray-triangle tests spent on one mesh's hole check.
const HOLE_BUDGET: usize = 20_000_000;

/// Signed volume enclosed by the triangles and the bound below which its sign says nothing:
/// `(volume, zero_below)`. A mesh whose `|volume| <= zero_below` encloses no volume up to
/// rounding (a flat mesh, or one flattened by a singular or projective transform), and its
/// sign is no finding.
///
/// The bound adds two parts:
/// - the rounding of this sum: each term `a · (b × c)` (vertices relative to the first one,
///   `v - o` rounded once) is a 3 × 3 determinant, computed with an error of at most
///   `γ₆ · P` where `P = Σ |a_i b_j c_k|` over its six products (one rounding of each
///   difference, two of each cross-product term, three of the dot product's sum), and the
///   `n` terms are summed with a further error of at most `γₙ · Σ |term|`, which `P` bounds
///   too; `(γ₆ + γₙ) Σ P` with `γₖ = k·u / (1 - k·u)`, `u = 2⁻⁵³`;
/// - the rounding already in the coordinates: world vertices come out of f64 transforms (a
///   projective one divides by `w`), each coordinate off by some units in the last place of
///   the mesh's extent `E` (its largest absolute coordinate). Moving every point of a
///   surface of area `A` by at most `δ` changes the volume it encloses by at most `δ · A`;
///   with `δ = 64 u E` (a generous count of roundings per coordinate) this is `64 u E A`.
///
/// On `weird_matrix_transform.usda` (usd-wg: a cube under a rank-2 projective matrix) the
/// volume is -3.8e-15 and the bound 3.3e-12. A real closed mesh that is inside out encloses
/// a volume of the order of `A` times its thickness, far above both.
pub fn signed_volume_bound(triangles: &[[DVec3; 3]]) -> (f64, f64) {
    const U: f64 = f64::EPSILON / 2.0;
    let gamma = |k: f64| k * U / (1.0 - k * U);
    let Some(first) = triangles.first() else {
        return (0.0, 0.0);
    };
    let o = first[0];
    let (mut sum, mut products, mut area, mut extent) = (0.0, 0.0, 0.0, 0.0f64);
    for t in triangles {
        let [a, b, c] = t.map(|v| v - o);
        sum += a.dot(b.cross(c));
        let (a, b, c) = (a.abs(), b.abs(), c.abs());
        products += a.dot(DVec3::new(
            b.y * c.z + b.z * c.y,
            b.z * c.x + b.x * c.z,
            b.x * c.y + b.y * c.x,
        ));
        area += 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        for v in t {
            extent = extent.max(v.abs().max_element());
        }
    }
    let n = triangles.len() as f64;
    let rounding = (gamma(6.0) + gamma(n)) * products / 6.0;
    let coordinates = 64.0 * U * extent * area;
    // The bound's own arithmetic rounds too; a relative 1e-9 covers it.
    (sum / 6.0, (rounding + coordinates) * (1.0 + 1e-9))
}

/// Signed volume enclosed by the triangles (positive when normals point outward).
pub fn signed_volume(triangles: &[[DVec3; 3]]) -> f64 {
    signed_volume_bound(triangles).0
}

/// Points spread over the unit sphere (a Fibonacci lattice), deterministic.
fn directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64 + 0.3;
            DVec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

/// Casts `rays` lines through the mesh's bounds; returns how many cross its surface an odd
/// number of times (through a closed surface the count is always even).
pub fn odd_crossings(triangles: &[[DVec3; 3]], rays: usize) -> (usize, usize) {
    let (min, max) = triangles.iter().flatten().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let centre = (min + max) * 0.5;
    let half = (max - min) * 0.5;
    let reach = (max - min).length().max(1e-30) * 2.0;
    let rays = rays.min(HOLE_BUDGET / triangles.len().max(1)).max(4);
    let mut odd = 0;
    for (i, dir) in directions(rays).into_iter().enumerate() {
        // Aim at points spread through the middle of the box (a Halton-like sequence).
        let h = |base: usize| {
            let (mut f, mut r, mut k) = (1.0, 0.0, i + 1);
            while k > 0 {
                f /= base as f64;
                r += f * (k % base) as f64;
                k /= base;
            }
            r * 1.2 - 0.6
        };
        let target = centre + half * DVec3::new(h(2), h(3), h(5));
        let origin = target - dir * reach;
        let ray = WatertightRay::new(origin, dir);
        let hits = triangles
            .iter()
            .filter(|t| ray.intersect(t, f64::INFINITY).is_some())
            .count();
        odd += hits % 2;
    }
    (odd, rays)
}

/// Runs the scene checks; returns the scene's figures.
pub fn check(scene: &Scene, options: &CheckOptions, f: &mut Findings) -> SceneStats {
    let bounds = scene.world_bounds();
    let size = if bounds.is_empty() {
        0.0
    } else {
        bounds.size().length()
    };
    let stats = SceneStats {
        objects: scene.objects.len(),
        triangles: scene.triangle_count(),
        quadrics: scene.quadrics().len(),
        size,
    };
    // An OBJ without faces still has its file's object: count primitives, not objects.
    if stats.triangles == 0 && stats.quadrics == 0 {
        f.warn(
            Code::EmptyScene,
            "",
            "the scene holds no triangles or quadrics",
        );
        return stats;
    }
    if !size.is_finite() {
        f.error(
            Code::NonFinitePosition,
            "",
            "the scene's bounds are not finite",
        );
    }
    if let Some((min, max)) = options.expect_size {
        // Out of range only beyond the rounding of the placed coordinates and the diagonal.
        let slack = scene.size_bound(&bounds);
        if !(size + slack >= min && size - slack <= max) {
            let hint = if size > max && size / 100.0 <= max && size / 100.0 >= min {
                " (centimetres instead of metres?)"
            } else if size < min && size * 100.0 >= min && size * 100.0 <= max {
                " (metres expected, but this looks 100 times too small)"
            } else {
                ""
            };
            f.error(
                Code::SceneSizeOutOfRange,
                "",
                format!("the scene's bounding-box diagonal is {size:.6} units, expected {min}..{max}{hint}"),
            );
        }
    }
    if !options.geometry {
        return stats;
    }
    for object in &scene.objects {
        if object.kind != ObjectKind::Mesh {
            continue;
        }
        let triangles = scene.mesh_triangles(object);
        if triangles.is_empty() {
            continue;
        }
        let at = object.source.clone();
        let topo = topology(&triangles);
        if topo.degenerate > 0 {
            f.warn(
                Code::DegenerateTriangles,
                at.clone(),
                format!(
                    "{} of {} triangles of '{}' have zero area",
                    topo.degenerate,
                    triangles.len(),
                    object.name
                ),
            );
        }
        if topo.non_manifold > 0 {
            f.info(
                Code::MeshNonManifold,
                at.clone(),
                format!(
                    "{} edges of '{}' are shared by more than two triangles",
                    topo.non_manifold, object.name
                ),
            );
        }
        let nearly = topo.meant_closed();
        if topo.closed() {
            let (odd, rays) = odd_crossings(&triangles, HOLE_RAYS);
            if odd > 0 {
                f.warn(
                    Code::MeshHoles,
                    at.clone(),
                    format!(
                        "'{}' is closed, yet {odd} of {rays} rays cross it an odd number of times",
                        object.name
                    ),
                );
            }
            let (volume, zero_below) = signed_volume_bound(&triangles);
            if volume < -zero_below {
                f.warn(
                    Code::InvertedNormals,
                    at.clone(),
                    format!(
                        "'{}' is closed but its normals point inward (signed volume {volume:.6e})",
                        object.name
                    ),
                );
            }
        } else if nearly {
            let (odd, rays) = odd_crossings(&triangles, HOLE_RAYS);
            let escaped = if odd > 0 {
                format!("; {odd} of {rays} rays through it escape through a hole")
            } else {
                String::new()
            };
            f.warn(
                Code::MeshHoles,
                at.clone(),
                format!(
                    "'{}' looks meant to be closed but has {} boundary edges of {}{escaped}",
                    object.name, topo.boundary, topo.edges
                ),
            );
        } else if topo.misoriented > 0 && topo.boundary == 0 {
            f.warn(
                Code::MeshInconsistentWinding,
                at.clone(),
                format!(
                    "{} edges of '{}' join triangles wound the opposite way",
                    topo.misoriented, object.name
                ),
            );
        }
    }
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<[DVec3; 3]> {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let quads = [
            [v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)],
            [v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)],
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)],
            [v(0., 1., 0.), v(0., 1., 1.), v(1., 1., 1.), v(1., 1., 0.)],
            [v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)],
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
        ];
        quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    #[test]
    fn closed_cube() {
        let c = cube();
        let t = topology(&c);
        assert!(t.closed(), "{t:?}");
        assert!((signed_volume(&c) - 1.0).abs() < 1e-12);
        assert_eq!(odd_crossings(&c, 64).0, 0);
    }

    #[test]
    fn a_volume_zero_up_to_rounding_has_no_sign() {
        // usd-wg's weird_matrix_transform.usda: the unit cube (centred) under the rank-2
        // projective matrix ((1,2,3,4),(5,6,7,8),(9,10,11,12),(13,14,15,1)) (USD's rows,
        // points as rows) is flat; its computed volume is a rounding residue.
        let m = glam::DMat4::from_cols_array(&[
            1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15., 1.,
        ]);
        let flat: Vec<_> = cube()
            .into_iter()
            .map(|t| t.map(|p| m.project_point3(p - DVec3::splat(0.5))))
            .collect();
        let (volume, zero_below) = signed_volume_bound(&flat);
        assert!(
            volume != 0.0 && volume.abs() <= zero_below,
            "{volume} {zero_below}"
        );
        assert!(zero_below < 1e-10, "{zero_below}");
        // A cube inside out keeps its sign, with a bound near 1e-14.
        let inverted: Vec<_> = cube().into_iter().map(|[a, b, c]| [a, c, b]).collect();
        let (volume, zero_below) = signed_volume_bound(&inverted);
        assert_eq!(volume, -1.0);
        assert!(zero_below < 1e-13, "{zero_below}");
        // So does a thin closed slab (1 × 1 × 1e-9) inside out.
        let slab: Vec<_> = inverted
            .iter()
            .map(|t| t.map(|p| DVec3::new(p.x, p.y, p.z * 1e-9)))
            .collect();
        let (volume, zero_below) = signed_volume_bound(&slab);
        assert!(volume < -zero_below, "{volume} {zero_below}");
    }

    #[test]
    fn inverted_and_holed_cube() {
        let inverted: Vec<_> = cube().into_iter().map(|[a, b, c]| [a, c, b]).collect();
        assert!(topology(&inverted).closed());
        assert!(signed_volume(&inverted) < 0.0);
        let mut holed = cube();
        holed.pop();
        let t = topology(&holed);
        assert_eq!(t.boundary, 3);
        assert!(odd_crossings(&holed, 64).0 > 0);
        // The missing triangle's area, 0.5 (its boundary is one planar loop).
        assert!((t.hole_area - 0.5).abs() < 1e-12, "{t:?}");
    }

    #[test]
    fn open_boxes_and_pipes_are_open_on_purpose() {
        // A box without its lid (McUsd's blocks): the hole is a fifth of the capped surface.
        let open_box: Vec<_> = cube().into_iter().skip(2).collect();
        let t = topology(&open_box);
        assert_eq!((t.boundary, t.edges), (4, 17));
        assert!((t.hole_area - 1.0).abs() < 1e-12, "{t:?}");
        assert!(!t.meant_closed(), "{t:?}");
        // A pipe open at both ends: two loops whose vector areas would cancel if summed.
        let pipe: Vec<_> = cube().into_iter().skip(4).collect();
        let t = topology(&pipe);
        assert!((t.hole_area - 2.0).abs() < 1e-12, "{t:?}");
        assert!(!t.meant_closed());
    }

    /// The cube's faces split into 16 x 16 quads each (dyadic, so shared corners weld
    /// exactly), two triangles per quad.
    fn fine_cube() -> Vec<[DVec3; 3]> {
        let mut fine = Vec::new();
        for [a, b, c] in cube().into_iter().step_by(2) {
            let (u, v) = ((b - a) / 16.0, (c - b) / 16.0);
            for i in 0..16 {
                for j in 0..16 {
                    let p = a + u * i as f64 + v * j as f64;
                    fine.push([p, p + u, p + u + v]);
                    fine.push([p, p + u + v, p + v]);
                }
            }
        }
        fine
    }

    #[test]
    fn a_fine_mesh_missing_one_triangle_is_meant_closed() {
        let mut fine = fine_cube();
        fine.pop();
        let t = topology(&fine);
        assert!(t.boundary > 0 && t.meant_closed(), "{t:?}");
    }

    #[test]
    fn holes_touching_at_a_corner_are_measured() {
        // Remove the first triangle of quads (3, 3) and (4, 4) of the first face: they share
        // only the corner p + u + v, which then starts two boundary edges.
        let mut fine = fine_cube();
        let first = |i: usize, j: usize| 2 * (16 * i + j);
        fine.remove(first(4, 4));
        fine.remove(first(3, 3));
        let t = topology(&fine);
        assert_eq!(t.boundary, 6);
        // Two triangles of area (1/16)^2 / 2 each.
        assert!((t.hole_area - 2.0 / 512.0).abs() < 1e-15, "{t:?}");
        assert!(t.meant_closed(), "{t:?}");
    }
}
