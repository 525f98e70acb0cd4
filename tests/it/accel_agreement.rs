//! Both acceleration backends agree: the obvhs BVH2 and CWBVH return the hit the octree and
//! brute force return (same primitive, same `t`), on random scenes of triangles and quadrics,
//! near the origin and far from it, with random, axis-parallel and far-away rays. Only rays
//! where two primitives hit within 1e-9 relative of each other may differ in the primitive.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::accel::{
    brute_force, prepare_ray, Bvh, BvhKind, Hit, Octree, OctreeParams, PrimitiveSet,
};
use raycast::scene::{Scene, SceneBuilder};
use raycast::trace::{BvhTracer, Tracer};

/// Tallies of one scene's comparisons.
#[derive(Default, Debug)]
struct Tally {
    rays: usize,
    hits: usize,
    quadric_hits: usize,
    ties: usize,
}

/// Checks one ray on every backend; returns the brute-force answer.
fn check(
    scene: &Scene,
    octree: &Octree,
    bvhs: &[Bvh],
    origin: DVec3,
    dir: DVec3,
    tally: &mut Tally,
) -> Option<Hit> {
    let ray = prepare_ray(scene, origin - scene.anchor, dir);
    let expected = brute_force(scene, &ray);
    let mut found = vec![
        ("octree", octree.intersect(scene, &ray, f64::INFINITY)),
        // The tracer's path: lazy set-up, mailbox, primitives tested in groups.
        (
            "octree ray",
            octree.intersect_ray(scene, ray.local_origin, ray.dir, f64::INFINITY),
        ),
    ];
    for bvh in bvhs {
        let name = match bvh.stats().kind {
            BvhKind::Bvh2 => "bvh2",
            BvhKind::Cwbvh => "cwbvh",
        };
        found.push((name, bvh.intersect(scene, &ray, f64::INFINITY)));
    }
    let mut tied = false;
    for (name, hit) in found {
        if hit == expected {
            continue;
        }
        // Only a tie within 1e-9 relative may pick another primitive.
        let (Some(h), Some(e)) = (hit, expected) else {
            panic!("{name}: {hit:?} != brute force {expected:?} for ray {origin:?} + t {dir:?}");
        };
        let close = (h.t - e.t).abs() <= 1e-9 * e.t.abs();
        let real = scene
            .intersect(h.prim as usize, &ray, f64::INFINITY)
            .is_some_and(|t| (t - e.t).abs() <= 1e-9 * e.t.abs());
        assert!(
            close && real,
            "{name}: {h:?} != brute force {e:?} for ray {origin:?} + t {dir:?}"
        );
        tied = true;
    }
    tally.rays += 1;
    tally.ties += usize::from(tied);
    if let Some(e) = expected {
        tally.hits += 1;
        tally.quadric_hits += usize::from(e.prim as usize >= scene.triangle_count());
    }
    expected
}

fn backends(scene: &Scene) -> (Octree, Vec<Bvh>) {
    let octree = Octree::build(scene, OctreeParams::default());
    let bvhs = vec![
        Bvh::build(scene, BvhKind::Bvh2),
        Bvh::build(scene, BvhKind::Cwbvh),
    ];
    for bvh in &bvhs {
        let s = bvh.stats();
        assert_eq!(s.primitives + s.unbounded, scene.len(), "{s:?}");
        assert_eq!(s.nodes > 0 && s.bytes > 0, scene.len() > 0, "{s:?}");
    }
    (octree, bvhs)
}

#[test]
fn random_scenes_agree_with_octree_and_brute_force() {
    let mut rng = Rng(0xacce_1001);
    for (round, offset) in [DVec3::ZERO, DVec3::new(3.0e6, -2.0e6, 1.0e6)]
        .into_iter()
        .cycle()
        .take(4)
        .enumerate()
    {
        let scene = random_scene(&mut rng, 300 + 250 * round, 8, offset);
        let (octree, bvhs) = backends(&scene);
        let mut tally = Tally::default();
        for i in 0..2500 {
            let origin = match i % 3 {
                // Inside the scene.
                0 => rng.point(-12.0, 12.0),
                // Far away, aimed at the scene.
                1 => rng.direction() * rng.uniform(50.0, 5000.0),
                _ => rng.point(-14.0, 14.0),
            } + offset;
            let dir = if i % 3 == 1 {
                (offset + rng.point(-8.0, 8.0) - origin) * rng.uniform(0.01, 3.0)
            } else {
                rng.direction() * rng.uniform(0.1, 10.0)
            };
            check(&scene, &octree, &bvhs, origin, dir, &mut tally);
        }
        assert!(tally.hits > 250, "the test should exercise hits: {tally:?}");
        assert!(tally.quadric_hits > 30, "and quadric hits: {tally:?}");
        assert!(tally.rays - tally.hits > 100, "and misses: {tally:?}");
        assert!(
            tally.ties * 100 <= tally.rays,
            "ties should be rare: {tally:?}"
        );
    }
}

#[test]
fn axis_parallel_and_grazing_rays_agree() {
    let mut rng = Rng(0xacce_1002);
    let scene = random_scene(&mut rng, 1200, 6, DVec3::ZERO);
    let (octree, bvhs) = backends(&scene);
    let mut tally = Tally::default();
    for _ in 0..3000 {
        let mut origin = rng.point(-12.0, 12.0);
        let dir = rng.axis_direction(&[1e-12]);
        let axis = (0..3).find(|&a| dir[a].abs() == 1.0).unwrap();
        // Half the rays start on a primitive's bounding-box face (grazing its box).
        if rng.next_u64().is_multiple_of(2) {
            let b = scene.bounds((rng.next_u64() % scene.len() as u64) as usize);
            let other = (axis + 1) % 3;
            origin[other] = b.min[other] + scene.anchor[other];
        }
        check(&scene, &octree, &bvhs, origin, dir, &mut tally);
    }
    assert!(tally.hits > 300, "{tally:?}");
    assert!(tally.rays - tally.hits > 300, "{tally:?}");
}

#[test]
fn quadrics_only_and_empty_scenes_agree() {
    let mut rng = Rng(0xacce_1003);
    let scene = random_scene(&mut rng, 0, 60, DVec3::ZERO);
    let (octree, bvhs) = backends(&scene);
    let mut tally = Tally::default();
    for _ in 0..3000 {
        let origin = rng.point(-14.0, 14.0);
        let dir = rng.direction();
        check(&scene, &octree, &bvhs, origin, dir, &mut tally);
    }
    assert!(tally.quadric_hits > 500, "{tally:?}");
    assert_eq!(tally.quadric_hits, tally.hits);

    let empty = SceneBuilder::new().finish("empty".into());
    let (octree, bvhs) = backends(&empty);
    assert!(check(&empty, &octree, &bvhs, DVec3::ZERO, DVec3::X, &mut tally).is_none());
}

/// The bvh backends through the oracle [`BvhTracer`], as benches/trace.rs renders with them.
#[test]
fn tracer_over_a_fixture_agrees() {
    let scene = load("assets/suzanne.obj");
    let octree = Octree::build(&scene, OctreeParams::default());
    let bvh2 = Bvh::build(&scene, BvhKind::Bvh2);
    let cwbvh = Bvh::build(&scene, BvhKind::Cwbvh);
    let reference = Tracer::new(&scene, &octree);
    let others = [
        BvhTracer {
            scene: &scene,
            bvh: &bvh2,
        },
        BvhTracer {
            scene: &scene,
            bvh: &cwbvh,
        },
    ];
    let bounds = scene.world_bounds();
    let mut rng = Rng(0xacce_1004);
    let mut hits = 0;
    for _ in 0..4000 {
        let eye = bounds.center() + rng.direction() * bounds.size().length() * 2.0;
        let target = bounds.center() + (rng.point(-0.5, 0.5) * bounds.size());
        let r = raycast::geometry::Ray::new(eye, target - eye);
        let expected = reference.nearest(&r, 0.0, f64::INFINITY);
        hits += usize::from(expected.is_some());
        for tracer in &others {
            assert_eq!(tracer.nearest(&r, 0.0, f64::INFINITY), expected, "{r:?}");
        }
    }
    assert!(hits > 1000, "{hits}");
}
