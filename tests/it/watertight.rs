//! Rays through shared edges and vertices of a closed mesh never leak through it.

use glam::DVec3;
use raycast::accel::{brute_force, prepare_ray, Octree, OctreeParams};
use raycast::scene::SceneBuilder;

/// A closed sphere-like mesh: an octahedron subdivided `levels` times, vertices pushed onto
/// the unit sphere and rounded to f32 (the storage precision), outward winding.
fn closed_mesh(levels: u32) -> Vec<[DVec3; 3]> {
    let round = |v: DVec3| v.normalize().as_vec3().as_dvec3();
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let mut tris = Vec::new();
    for sx in [1.0, -1.0] {
        for sy in [1.0, -1.0] {
            for sz in [1.0, -1.0] {
                let (a, b, c) = (x * sx, y * sy, z * sz);
                tris.push(if sx * sy * sz > 0.0 {
                    [a, b, c]
                } else {
                    [a, c, b]
                });
            }
        }
    }
    for _ in 0..levels {
        tris = tris
            .into_iter()
            .flat_map(|[a, b, c]| {
                let (ab, bc, ca) = (round(a + b), round(b + c), round(c + a));
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

#[test]
fn rays_through_vertices_and_edges_never_leak() {
    let tris = closed_mesh(4);
    let mut targets: Vec<DVec3> = Vec::new();
    for t in &tris {
        for i in 0..3 {
            targets.push(t[i]);
            targets.push((t[i] + t[(i + 1) % 3]) * 0.5);
        }
    }
    let mut builder = SceneBuilder::new();
    builder.add_mesh("sphere".into(), "test".into(), tris);
    let scene = builder.finish("closed".into());
    assert_eq!(
        scene.anchor,
        DVec3::ZERO,
        "symmetric bounds keep the stored vertices exact"
    );
    let octree = Octree::build(&scene, OctreeParams::default());
    let mut rays = 0;
    for target in targets {
        // From the centre outward, exactly through the vertex or edge point.
        for (origin, dir) in [
            (DVec3::ZERO, target),
            (DVec3::ZERO, target * 3.0),
            (target * 4.0, -target),
            (
                DVec3::new(0.1, 0.0, 0.0),
                target - DVec3::new(0.1, 0.0, 0.0),
            ),
        ] {
            let ray = prepare_ray(&scene, origin, dir);
            let hit = octree.intersect(&scene, &ray, f64::INFINITY);
            assert!(hit.is_some(), "leak: ray {origin:?} + t {dir:?}");
            assert_eq!(hit, brute_force(&scene, &ray));
            rays += 1;
        }
    }
    assert!(rays > 5000);
}
