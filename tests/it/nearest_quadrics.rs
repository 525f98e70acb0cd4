//! The octree's nearest search with quadrics among triangles finds what a brute-force search
//! over every primitive finds (the same distance, bit for bit), near the origin and 1e6 from
//! it: the quadrics' boxes in the octree bound their clipped surfaces, so no leaf that could
//! hold the nearest point is skipped.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::accel::{Octree, OctreeParams};
use raycast::geometry::closest::closest_on_triangle;
use raycast::trace::Tracer;

#[test]
fn the_octree_search_is_the_brute_force_search() {
    for offset in [DVec3::ZERO, DVec3::splat(1e6)] {
        let mut rng = Rng(0x9ea7_0017);
        let scene = random_scene(&mut rng, 300, 12, offset);
        let octree = Octree::build(&scene, OctreeParams::default());
        let query = Tracer {
            scene: &scene,
            octree: &octree,
        };
        let triangles: Vec<_> = scene
            .objects
            .iter()
            .flat_map(|o| scene.mesh_triangles(o))
            .collect();
        for _ in 0..300 {
            let p = rng.point(-14.0, 14.0) + offset;
            let on_triangles = triangles
                .iter()
                .map(|t| closest_on_triangle(p, t).distance)
                .fold(f64::INFINITY, f64::min);
            let on_quadrics = scene
                .quadrics()
                .iter()
                .filter_map(|q| q.closest(p, f64::INFINITY))
                .map(|c| c.distance)
                .fold(f64::INFINITY, f64::min);
            let found = query.closest(p).expect("a nearest point");
            assert_eq!(found.distance, on_triangles.min(on_quadrics), "{p}");
        }
    }
}
