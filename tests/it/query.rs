//! The queries behind the Python package: crossings counted once at shared edges and
//! vertices, the parameter range, containment, loading from bytes, typed errors.
//! Expected values from the geometry (analysis), not from the code under test.

use crate::common;

use glam::DVec3;
use raycast::accel::{Octree, OctreeParams};
use raycast::error::ErrorKind;
use raycast::geometry::triangle::WatertightRay;
use raycast::geometry::Ray;
use raycast::import::{self, LoadOptions};
use raycast::trace::Tracer;
use std::path::Path;

fn cube() -> raycast::scene::Scene {
    import::load(
        Path::new("fixtures/gltf/cube.gltf"),
        &LoadOptions::default(),
    )
    .unwrap()
}

/// A fan of `n` triangles around the origin in the plane z = 0, counter-clockwise seen from +z.
fn fan(n: usize) -> Vec<[DVec3; 3]> {
    let rim = |i: usize| {
        let a = std::f64::consts::TAU * i as f64 / n as f64 + 0.1;
        DVec3::new(a.cos(), a.sin(), 0.0)
    };
    (0..n).map(|i| [DVec3::ZERO, rim(i), rim(i + 1)]).collect()
}

#[test]
fn a_ray_through_a_shared_edge_crosses_one_triangle() {
    // The quad (-1,-1) (1,-1) (1,1) (-1,1) split along y = x.
    let [a, b, c, d] =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| DVec3::new(x, y, 0.0));
    let quad = [[a, b, c], [a, c, d]];
    for s in [-0.75, -0.5, 0.0, 0.25, 0.5] {
        for dir in [DVec3::NEG_Z, DVec3::Z, DVec3::new(0.3, -0.2, -1.0)] {
            let origin = DVec3::new(s, s, 0.0) - dir * 3.0;
            let ray = WatertightRay::new(origin, dir);
            let inclusive = quad
                .iter()
                .filter(|t| ray.intersect(t, f64::INFINITY).is_some());
            let once = quad
                .iter()
                .filter(|t| ray.crossing(t, f64::INFINITY).is_some());
            assert_eq!(inclusive.count(), 2, "both triangles touch the edge");
            assert_eq!(once.count(), 1, "point ({s}, {s}) along {dir}");
        }
    }
}

#[test]
fn a_ray_through_a_shared_vertex_crosses_one_triangle() {
    for n in [3, 5, 6, 8] {
        let triangles = fan(n);
        for dir in [
            DVec3::NEG_Z,
            DVec3::Z,
            DVec3::new(0.2, 0.4, -1.0),
            DVec3::new(-0.5, 0.1, 1.0),
        ] {
            let ray = WatertightRay::new(-dir * 2.0, dir);
            let once = triangles
                .iter()
                .filter(|t| ray.crossing(t, f64::INFINITY).is_some());
            assert_eq!(once.count(), 1, "fan of {n} along {dir}");
        }
    }
}

#[test]
fn barycentric_weights_rebuild_the_point() {
    let tri = [DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 4.0];
    let ray = WatertightRay::new(DVec3::new(0.5, 1.0, 3.0), DVec3::NEG_Z);
    // (0.5, 1) = 0.5 a + 0.25 b + 0.25 c.
    assert_eq!(ray.barycentric(&tri), Some([0.5, 0.25, 0.25]));
}

#[test]
fn crossings_of_the_cube_through_edges_corners_and_faces() {
    let scene = cube();
    let octree = Octree::build(&scene, OctreeParams::default());
    let query = Tracer {
        scene: &scene,
        octree: &octree,
    };
    let rays = [
        (DVec3::new(0.0, 0.0, 5.0), DVec3::NEG_Z), // face diagonals of +-Z
        (DVec3::new(0.5, 0.5, 5.0), DVec3::NEG_Z), // the same diagonals elsewhere
        (DVec3::new(-2.0, -2.0, -2.0), DVec3::ONE), // opposite corners
        (DVec3::new(0.0, -3.0, -3.0), DVec3::new(0.0, 1.0, 1.0)), // midpoints of two edges
        (DVec3::new(0.3, 0.2, 0.1), DVec3::X),     // from inside: one crossing
    ];
    let expected = [2, 2, 2, 2, 1];
    for ((origin, dir), want) in rays.into_iter().zip(expected) {
        let found = query.crossings(&Ray::new(origin, dir), 0.0, f64::INFINITY);
        assert_eq!(found.len(), want, "ray from {origin} along {dir}");
        assert!(found.windows(2).all(|w| w[0].t <= w[1].t));
    }
    let ray = Ray::new(DVec3::new(0.2, 0.3, 5.0), DVec3::NEG_Z);
    let t: Vec<f64> = query
        .crossings(&ray, 0.0, f64::INFINITY)
        .iter()
        .map(|c| c.t)
        .collect();
    assert_eq!(t, [4.0, 6.0]);
    assert_eq!(query.crossings(&ray, 4.0, 10.0).len(), 1);
    assert_eq!(
        query.nearest(&ray, 4.0, f64::INFINITY).map(|c| c.t),
        Some(6.0)
    );
    assert_eq!(query.nearest(&ray, 0.0, 3.9), None);
    assert!(query.contains(DVec3::new(0.9, -0.9, 0.0)));
    assert!(!query.contains(DVec3::new(1.1, 0.0, 0.0)));
}

#[test]
fn loading_from_bytes_and_typed_errors() {
    let glb = std::fs::read("fixtures/gltf/cube.glb").unwrap();
    let scene = import::load_bytes(glb, Path::new("cube.glb"), &LoadOptions::default()).unwrap();
    assert_eq!(scene.triangle_count(), 12);
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
    let tri = import::load_bytes(obj, Path::new("t.obj"), &LoadOptions::default()).unwrap();
    assert_eq!(tri.triangle_count(), 1);
    let missing = import::load(Path::new("fixtures/no/such.glb"), &LoadOptions::default());
    assert_eq!(missing.unwrap_err().kind, ErrorKind::NotFound);
    let usd = import::load_bytes(
        b"#usda 1.0\n".to_vec(),
        Path::new("x.usda"),
        &LoadOptions::default(),
    );
    assert_eq!(usd.unwrap_err().kind, ErrorKind::Usage);
    let wrong = import::load_bytes(
        b"glTF\x02\0\0\0".to_vec(),
        Path::new("x.obj"),
        &LoadOptions::default(),
    );
    assert!(wrong.unwrap_err().message.contains("binary glTF"));
}

#[test]
fn occluded_stops_at_any_crossing_in_range() {
    // Down through the cube [-1, 1]^3 from z = 5: crossings at t = 4 and t = 6.
    let scene = cube();
    let octree = Octree::build(&scene, OctreeParams::default());
    let query = Tracer {
        scene: &scene,
        octree: &octree,
    };
    let ray = Ray::new(DVec3::new(0.2, 0.3, 5.0), DVec3::NEG_Z);
    let inf = f64::INFINITY;
    let ranges = [
        ((0.0, inf), true),
        ((0.0, 3.9), false),
        ((0.0, 4.0), true),
        ((4.0, 5.9), false),
        ((4.0, 6.0), true),
        ((6.0, inf), false),
        ((-1.0, inf), false), // refused, as by nearest
    ];
    for ((t_min, t_max), want) in ranges {
        assert_eq!(
            query.occluded(&ray, t_min, t_max),
            want,
            "({t_min}, {t_max}]"
        );
    }
    let zero = Ray::new(DVec3::ZERO, DVec3::ZERO);
    assert!(!query.occluded(&zero, 0.0, inf));
}

#[test]
fn occluded_agrees_with_the_nearest_hit_on_random_scenes() {
    // A different method: the nearest-hit search, which does not stop early.
    let mut rng = common::Rng(0x0cc1_0ded);
    for offset in [DVec3::ZERO, DVec3::splat(1e5)] {
        let scene = common::random_scene(&mut rng, 300, 12, offset);
        let octree = Octree::build(&scene, OctreeParams::default());
        let query = Tracer {
            scene: &scene,
            octree: &octree,
        };
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..4000 {
            // Toward a point among the primitives, so that many rays hit something.
            let origin = rng.point(-14.0, 14.0) + offset;
            let target = rng.point(-8.0, 8.0) + offset;
            let ray = Ray::new(origin, (target - origin).normalize());
            let t_min = if rng.uniform(0.0, 1.0) < 0.5 {
                0.0
            } else {
                rng.uniform(0.0, 10.0)
            };
            let t_max = t_min + rng.uniform(0.0, 20.0);
            let nearest = query.nearest(&ray, t_min, t_max).is_some();
            assert_eq!(
                query.occluded(&ray, t_min, t_max),
                nearest,
                "{ray:?} ({t_min}, {t_max}]"
            );
            *(if nearest { &mut hits } else { &mut misses }) += 1;
        }
        assert!(hits > 400 && misses > 400, "{hits} hits, {misses} misses");
    }
}
