//! The octree must return exactly what a brute-force loop over all primitives returns,
//! including in the lecture's boundary trap and for rays lying on cell planes.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::accel::{
    brute_force, prepare_ray, Octree, OctreeParams, PreparedRay, PrimitiveSet, PACKET,
};
use raycast::geometry::Aabb;
use raycast::quadric::{Quadric, QuadricSpec};
use raycast::scene::{Scene, SceneBuilder, SceneRay};

fn assert_same_as_brute_force(scene: &Scene, octree: &Octree, origin: DVec3, dir: DVec3) {
    let local = origin - scene.anchor;
    let ray = prepare_ray(scene, local, dir);
    let expected = brute_force(scene, &ray);
    let found = octree.intersect(scene, &ray, f64::INFINITY);
    assert_eq!(found, expected, "ray {origin:?} + t {dir:?}");
}

#[test]
fn random_scenes_match_brute_force() {
    let mut rng = Rng(0x5eed_0001);
    for round in 0..4 {
        let scene = random_scene(&mut rng, 400 + 300 * round, 6, DVec3::ZERO);
        let octree = Octree::build(&scene, OctreeParams::default());
        assert!(octree.stats().depth >= 2, "{:?}", octree.stats());
        let mut hits = 0;
        for _ in 0..3000 {
            let origin = rng.point(-14.0, 14.0);
            let dir = rng.direction() * rng.uniform(0.1, 10.0);
            assert_same_as_brute_force(&scene, &octree, origin, dir);
            hits += usize::from(
                brute_force(&scene, &prepare_ray(&scene, origin - scene.anchor, dir)).is_some(),
            );
        }
        assert!(hits > 200, "the test should exercise hits, got {hits}");
    }
}

#[test]
fn rays_on_cell_planes_axis_parallel_and_negative_zero() {
    let mut rng = Rng(0x5eed_0002);
    let scene = random_scene(&mut rng, 1500, 4, DVec3::ZERO);
    let octree = Octree::build(&scene, OctreeParams::default());
    let root = octree.root();
    let c = root.center() + scene.anchor;
    let quarter = root.size().x / 4.0;
    let planes = [c.x - quarter, c.x, c.x + quarter];
    for _ in 0..1500 {
        let mut origin = rng.point(-12.0, 12.0);
        origin.x = planes[(rng.next_u64() % 3) as usize];
        origin.y = [c.y, origin.y][(rng.next_u64() % 2) as usize];
        let dir = rng.axis_direction(&[]);
        assert_same_as_brute_force(&scene, &octree, origin, dir);
    }
}

/// The lecture's trap, from fixtures/gltf/trap.gltf: the big triangle is found first, in a
/// cell whose exit lies before its hit, while the nearer quad waits in a later cell.
#[test]
fn boundary_trap_is_not_fallen_into() {
    let scene = load("gltf/trap.gltf");
    let octree = Octree::build(&scene, OctreeParams::default());
    let origin = DVec3::new(-12.0, 0.25, 0.25) - scene.anchor;
    let dir = DVec3::X;
    let ray = prepare_ray(&scene, origin, dir);
    let (prim, t, exit) = naive_first_hit(&scene, &octree, &ray);
    assert_eq!(
        scene.object(prim).name,
        "big",
        "the trap needs the big triangle first"
    );
    assert!(
        t > exit,
        "the big triangle's hit (t = {t}) lies beyond its cell (exit {exit})"
    );
    assert!((t - 20.0).abs() < 1e-9);
    // The octree's answer is the nearer quad, exactly as brute force finds it.
    let hit = octree.intersect(&scene, &ray, f64::INFINITY).unwrap();
    assert_eq!(Some(hit), brute_force(&scene, &ray));
    assert_eq!(scene.object(hit.prim).name, "near");
    assert!((hit.t - 14.0).abs() < 1e-12);
    let sample = cast_one(&scene, [-12.0, 0.25, 0.25], [1.0, 0.0, 0.0]);
    assert_hit(&sample, "near", 14.0, [-1.0, 0.0, 0.0], &[0]);
}

#[test]
fn empty_scene_misses_everything() {
    let scene = SceneBuilder::new().finish("empty".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let ray = prepare_ray(&scene, DVec3::ZERO, DVec3::X);
    assert_eq!(octree.intersect(&scene, &ray, f64::INFINITY), None);
}

/// Rays from far away (up to 1e15 scene sizes) aimed at triangle vertices, edge midpoints and
/// cell planes: the traversal's rounding grows with the origin's distance, and the octree must
/// still find exactly what brute force finds (issue 14: the margin ignored the origin).
#[test]
fn far_origins_match_brute_force() {
    let mut rng = Rng(0x5eed_0003);
    let scene = random_scene(&mut rng, 1200, 0, DVec3::ZERO);
    let octree = Octree::build(&scene, OctreeParams::default());
    let triangles: Vec<_> = scene
        .objects
        .iter()
        .flat_map(|o| scene.mesh_triangles(o))
        .collect();
    let mut hits = 0;
    for k in 0..4000 {
        let v = triangles[(rng.next_u64() % triangles.len() as u64) as usize];
        let target = match k % 3 {
            0 => v[0],
            1 => (v[0] + v[1]) * 0.5,
            _ => (v[0] + v[1] + v[2]) / 3.0,
        };
        let distance = 10f64.powf(rng.uniform(6.0, 15.0));
        let dir = rng.direction();
        let origin = target - dir * distance;
        let local = origin - scene.anchor;
        let ray = prepare_ray(&scene, local, dir);
        let expected = brute_force(&scene, &ray);
        hits += usize::from(expected.is_some());
        let found = octree.intersect(&scene, &ray, f64::INFINITY);
        assert_eq!(found, expected, "ray {origin:?} + t {dir:?}");
    }
    assert!(hits > 1000, "the test should exercise hits, got {hits}");
}

/// `traverse` is public: a direction with -0.0 components must visit the same leaves, with the
/// same parameters, as the same direction with +0.0 (issue 14).
#[test]
fn traverse_treats_negative_zero_as_zero() {
    let mut rng = Rng(0x5eed_0004);
    let scene = random_scene(&mut rng, 800, 2, DVec3::ZERO);
    let octree = Octree::build(&scene, OctreeParams::default());
    let visits = |origin: DVec3, dir: DVec3| {
        let mut seen = Vec::new();
        octree.traverse(origin, dir, f64::INFINITY, |refs, enter, exit| {
            seen.push((refs.to_vec(), enter, exit));
            f64::INFINITY
        });
        seen
    };
    let mut visited = 0;
    for _ in 0..300 {
        let origin = rng.point(-12.0, 12.0) - scene.anchor;
        let mut dir = rng.axis_direction(&[]) + DVec3::ZERO;
        let plus = visits(origin, dir);
        for axis in 0..3 {
            if dir[axis] == 0.0 {
                dir[axis] = -0.0;
            }
        }
        assert_eq!(visits(origin, dir), plus, "ray {origin:?} + t {dir:?}");
        visited += plus.len();
    }
    assert!(
        visited > 300,
        "the rays should pass through leaves ({visited})"
    );
}

/// A scene whose primitives all weigh `cost` in the split rule (everything else is the
/// scene's own).
struct Weighed<'a> {
    scene: &'a Scene,
    cost: f64,
}

impl PrimitiveSet for Weighed<'_> {
    type RayData = SceneRay;

    fn len(&self) -> usize {
        self.scene.len()
    }
    fn bounds(&self, index: usize) -> Aabb {
        self.scene.bounds(index)
    }
    fn cost(&self, _index: usize) -> f64 {
        self.cost
    }
    fn overlaps(&self, index: usize, cell: &Aabb) -> bool {
        self.scene.overlaps(index, cell)
    }
    fn child_mask(&self, index: usize, cell: &Aabb, margin: f64, candidates: u8) -> u8 {
        self.scene.child_mask(index, cell, margin, candidates)
    }
    fn clipped_bounds(&self, index: usize, cell: &Aabb) -> Option<Aabb> {
        self.scene.clipped_bounds(index, cell)
    }
    fn prepare(&self, local_origin: DVec3, dir: DVec3) -> SceneRay {
        self.scene.prepare(local_origin, dir)
    }
    fn intersect(&self, index: usize, ray: &PreparedRay<SceneRay>, t_max: f64) -> Option<f64> {
        self.scene.intersect(index, ray, t_max)
    }
    // Packets test one ray at a time (the trait's default).
    type PacketData = ();
    fn prepare_packet(&self, _rays: &[PreparedRay<SceneRay>; PACKET]) {}
}

/// Quadrics weigh [`Quadric::TEST_COST`] triangle tests: their cells split into more, smaller
/// leaves than the same primitives weighed as triangles, and the answers stay brute force's.
#[test]
fn costlier_primitives_split_into_smaller_leaves() {
    let mut rng = Rng(0x5eed_0005);
    let scene = random_scene(&mut rng, 0, 600, DVec3::ZERO);
    let params = OctreeParams::default();
    let weighed = Octree::build(&scene, params);
    let as_triangles = Octree::build(
        &Weighed {
            scene: &scene,
            cost: 1.0,
        },
        params,
    );
    let (w, t) = (weighed.stats(), as_triangles.stats());
    let per_leaf = |s: raycast::accel::OctreeStats| s.references as f64 / s.leaves as f64;
    assert!(
        w.leaves > 2 * t.leaves && per_leaf(w) < per_leaf(t),
        "weighed {w:?}, as triangles {t:?}"
    );
    for _ in 0..3000 {
        let origin = rng.point(-14.0, 14.0);
        let dir = rng.direction();
        assert_same_as_brute_force(&scene, &weighed, origin, dir);
    }
}

/// A set without a packet test of its own (the trait's default: one ray at a time) traced in
/// packets gets every ray's brute-force answer, as the scene's own packet test does, over
/// triangles and quadrics.
#[test]
fn packets_match_brute_force_with_and_without_a_set_packet_test() {
    let mut rng = Rng(0x5eed_0006);
    let scene = random_scene(&mut rng, 500, 40, DVec3::ZERO);
    let weighed = Weighed {
        scene: &scene,
        cost: 1.0,
    };
    let by_default = Octree::build(&weighed, OctreeParams::default());
    let own = Octree::build(&scene, OctreeParams::default());
    let (mut packets, mut hits) = (0, 0);
    for _ in 0..1500 {
        let (origin, dir) = (rng.point(-14.0, 14.0), rng.direction());
        let origins: [DVec3; PACKET] = std::array::from_fn(|_| origin + rng.point(-0.3, 0.3));
        let dirs: [DVec3; PACKET] = std::array::from_fn(|_| dir + rng.point(-0.02, 0.02));
        let locals = origins.map(|o| o - scene.anchor);
        let t_max = [f64::INFINITY; PACKET];
        let found = [
            by_default.intersect_packet(&weighed, &locals, &dirs, &t_max),
            own.intersect_packet(&scene, &locals, &dirs, &t_max),
        ];
        let [Some(default), Some(own)] = found else {
            continue;
        };
        packets += 1;
        for i in 0..PACKET {
            let expected = brute_force(&scene, &prepare_ray(&scene, locals[i], dirs[i]));
            assert_eq!(
                (default[i], own[i]),
                (expected, expected),
                "ray {i} of a packet"
            );
            hits += usize::from(expected.is_some());
        }
    }
    assert!(
        packets > 1000 && hits > 2000,
        "{packets} packets, {hits} hits"
    );
}

/// A cell holding one reference is never split, however much it weighs: splitting cannot
/// separate anything, and an expensive primitive inside one octant would otherwise be passed
/// down a chain of single-child cells to the depth cap.
#[test]
fn a_single_heavy_primitive_stays_in_one_leaf() {
    let mut builder = SceneBuilder::new();
    let sphere =
        QuadricSpec::from_coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None)
            .unwrap();
    // Two small spheres in opposite corners of the scene: each lies inside one octant of the
    // root and of several levels below it.
    for (i, centre) in [DVec3::splat(1.5), DVec3::splat(98.5)]
        .into_iter()
        .enumerate()
    {
        let world =
            glam::DMat4::from_scale_rotation_translation(DVec3::ONE, glam::DQuat::IDENTITY, centre);
        let quadric = Quadric::new(&sphere, world).unwrap();
        builder.add_quadric(format!("q{i}"), "test".into(), quadric);
    }
    let scene = builder.finish("corners".into());
    let heavy = Weighed {
        scene: &scene,
        cost: 100.0,
    };
    let stats = Octree::build(&heavy, OctreeParams::default()).stats();
    assert_eq!((stats.depth, stats.leaves), (1, 2), "{stats:?}");
}

/// Large triangles crossing the whole scene among small ones: the small ones make every
/// split pay, and each split copies the large ones into about four children. Unbounded, the
/// tree held over 500 references per primitive (2,000 of each kind, two seeds, measured with
/// the same scene as an OBJ); it holds at most 256 (README, `accel/`), and stays exact.
#[test]
fn crossing_triangles_stay_within_the_reference_bound() {
    let mut rng = Rng(0x5eed_0010);
    let mut tris = Vec::new();
    for _ in 0..2000 {
        tris.push([0; 3].map(|_| rng.point(0.0, 1.0)));
        let centre = rng.point(0.0, 1.0);
        tris.push([0; 3].map(|_| centre + rng.point(-0.002, 0.002)));
    }
    let mut builder = SceneBuilder::new();
    builder.add_mesh("soup".into(), "test".into(), tris);
    let scene = builder.finish("soup".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let stats = octree.stats();
    assert!(stats.depth >= 2, "{stats:?}");
    assert!(stats.references <= 256 * 4000, "{stats:?}");
    for _ in 0..1000 {
        let origin = rng.point(-0.5, 1.5);
        let dir = rng.direction();
        assert_same_as_brute_force(&scene, &octree, origin, dir);
    }
}
