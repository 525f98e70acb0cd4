//! The `error` and `certain` AOVs on scenes whose exact answers are known by analysis.

use glam::DVec3;
use raycast::accel::{Octree, OctreeParams};
use raycast::geometry::Ray;
use raycast::render::{render, trace, Aov, Rays};
use raycast::scene::SceneBuilder;
use raycast::trace::Tracer;

/// The exact `a − b` as an unevaluated sum `hi + lo` (Knuth's two-sum).
fn two_diff(a: f64, b: f64) -> (f64, f64) {
    let hi = a - b;
    let bb = a - hi;
    (hi, (a - (hi + bb)) + (bb - b))
}

/// Traces `rays` at a unit square of two triangles (sharing the diagonal) in the plane
/// z = `height`, and returns the depth, error and certain buffers.
fn square_at(height: f64, rays: Vec<Ray>) -> (Vec<f64>, Vec<f64>, Vec<u8>) {
    let [a, b, c, d] =
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| DVec3::new(x, y, height));
    let mut builder = SceneBuilder::new();
    builder.add_mesh("square".into(), "test".into(), vec![[a, b, c], [a, c, d]]);
    let scene = builder.finish("square".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer::new(&scene, &octree);
    let buffers = render(
        &tracer,
        &rays,
        &[Aov::Depth, Aov::Error, Aov::Certain],
        |_| {},
    );
    (
        buffers.floats(Aov::Depth).unwrap().to_vec(),
        buffers.floats(Aov::Error).unwrap().to_vec(),
        buffers.flags(Aov::Certain).unwrap().to_vec(),
    )
}

/// Straight down from z = 1 at the plane z = 0.1 (the f64 nearest 1/10): the exact depth is
/// `1 − 0.1` as reals, which two-sum gives exactly; the bound covers it and is a few ulps.
/// An interior ray is certain; one through the shared diagonal, or a corner, is not.
#[test]
fn depth_bound_covers_the_exact_depth_and_edges_are_uncertain() {
    let down = |x: f64, y: f64| Ray::new(DVec3::new(x, y, 1.0), DVec3::NEG_Z);
    let rays = vec![
        down(0.7, 0.2),
        down(0.5, 0.5),
        down(0.0, 0.0),
        down(0.3, 0.9),
    ];
    let (depth, error, certain) = square_at(0.1, rays);
    let (hi, lo) = two_diff(1.0, 0.1);
    for i in [0, 3] {
        let off = (depth[i] - hi) - lo;
        assert!(off.abs() <= error[i], "ray {i}: {off:e} > {:e}", error[i]);
        assert!(error[i] < 1e-14, "ray {i}: {:e}", error[i]);
        assert_eq!(certain[i], 1, "ray {i}");
    }
    assert_eq!(certain[1], 0, "through the shared edge");
    assert_eq!(certain[2], 0, "through a corner");
}

/// A miss far from the square is certain, and so is one 1e-15 beside its edge from 1 unit
/// away (the coordinates are small there, their rounding far below 1e-15). From 1000 units
/// away, aimed 1e-14 beside the edge, the sheared coordinates carry rounding of about
/// 1e-13 (an ulp of 1000): the miss is within the edge's bound, not certain. A miss's error
/// is 0.
#[test]
fn misses_beside_an_edge_are_uncertain_only_within_the_bound() {
    let far = DVec3::new(1000.0, 0.5, 1000.0);
    let rays = vec![
        Ray::new(DVec3::new(5.0, 5.0, 1.0), DVec3::NEG_Z),
        Ray::new(DVec3::new(1.0 + 1e-15, 0.5, 1.0), DVec3::NEG_Z),
        Ray::new(far, DVec3::new(1.0 + 1e-14, 0.5, 0.1) - far),
    ];
    let (depth, error, certain) = square_at(0.1, rays);
    assert_eq!(depth[..2], [f64::INFINITY; 2]);
    assert_eq!(error[..2], [0.0; 2]);
    assert_eq!(certain, [1, 1, 0]);
}

/// Two parallel squares 1e-16 apart (closer than any bound of their crossings): the nearest
/// is not certain. 1 apart: it is.
#[test]
fn surfaces_within_each_others_bounds_are_uncertain() {
    for (gap, expected) in [(1e-16, 0), (1.0, 1)] {
        let mut builder = SceneBuilder::new();
        for (name, z) in [("near", 0.5 + gap), ("far", 0.5)] {
            let [a, b, c] =
                [[-1.0, -1.0], [2.0, -1.0], [0.0, 2.0]].map(|[x, y]| DVec3::new(x, y, z));
            builder.add_mesh(name.into(), "test".into(), vec![[a, b, c]]);
        }
        let scene = builder.finish("pair".into());
        let octree = Octree::build(&scene, OctreeParams::default());
        let tracer = Tracer::new(&scene, &octree);
        let rays = vec![Ray::new(DVec3::new(0.2, 0.3, 3.0), DVec3::NEG_Z)];
        let buffers = render(&tracer, &rays, &[Aov::Certain], |_| {});
        assert_eq!(
            buffers.flags(Aov::Certain).unwrap(),
            [expected],
            "gap {gap}"
        );
    }
}

/// `error` is one definition: the same bits whether `certain` is asked beside it or not
/// (the hit's own decision takes the bounded recomputation, the error never does), on a
/// mesh placed by a rotation (vertex bounds) and on a sphere (a quadric root).
#[test]
fn error_does_not_depend_on_certain_being_asked() {
    use raycast::quadric::{Quadric, QuadricSpec};
    let mut builder = SceneBuilder::new();
    let id = builder.new_object("turned".into(), "test".into());
    let square = raycast::scene::Mesh::from_soup(&[[
        DVec3::new(-1.0, -1.0, 0.0),
        DVec3::new(1.0, -1.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ]]);
    let turn = glam::DMat4::from_rotation_x(0.3) * glam::DMat4::from_translation(DVec3::X * 3.0);
    builder.place_mesh(id, std::sync::Arc::new(square), turn);
    let sphere =
        QuadricSpec::from_coefficients([1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0], None)
            .unwrap();
    let placed = Quadric::new(
        &sphere,
        glam::DMat4::from_translation(DVec3::new(-3.0, 0.1, 0.0)),
    );
    builder.add_quadric("sphere".into(), "test".into(), placed.unwrap());
    let scene = builder.finish("mixed".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer::new(&scene, &octree);
    let rays: Vec<Ray> = (0..400)
        .map(|i| {
            let x = -4.5 + 9.0 * f64::from(i % 20) / 19.0;
            let y = -1.5 + 3.0 * f64::from(i / 20) / 19.0;
            Ray::new(DVec3::new(x, y, 10.0), DVec3::new(0.01, -0.02, -1.0))
        })
        .collect();
    let alone = render(&tracer, &rays, &[Aov::Error], |_| {});
    let both = render(&tracer, &rays, &[Aov::Error, Aov::Certain], |_| {});
    let (alone, both) = (
        alone.floats(Aov::Error).unwrap(),
        both.floats(Aov::Error).unwrap(),
    );
    let hits = alone.iter().filter(|e| **e > 0.0 && e.is_finite()).count();
    assert!(hits > 50, "{hits} bounded hits");
    for (i, (a, b)) in alone.iter().zip(both).enumerate() {
        assert_eq!(a.to_bits(), b.to_bits(), "ray {i}");
    }
}

/// `certain` is decided the same way for a ray in a packet of eight, alone, and alone with a
/// range that does not start at 0 (decided from what the packet's or the ray's search
/// offered it, or by a traversal of its own where that cannot tell): rays straight down at two overlapping squares 1e-16 apart on the left (uncertain
/// where both are crossed), a plain square in the middle, with rays on and 1e-15 beside its
/// diagonal and edges, misses beside it, a stack of fourteen squares on the right (more
/// primitives offered than are noted), and packets that mix all of these.
#[test]
fn certain_is_the_same_for_a_ray_alone_and_in_a_packet() {
    let mut builder = SceneBuilder::new();
    let square = |x0: f64, z: f64| {
        let [a, b, c, d] =
            [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(|[x, y]| DVec3::new(x0 + x, y, z));
        vec![[a, b, c], [a, c, d]]
    };
    builder.add_mesh("near".into(), "test".into(), square(-1.5, 0.5 + 1e-16));
    builder.add_mesh("far".into(), "test".into(), square(-1.2, 0.5));
    builder.add_mesh("right".into(), "test".into(), square(0.5, 0.1));
    for k in 0..14 {
        let name = format!("stack {k}");
        builder.add_mesh(name, "test".into(), square(1.6, 0.2 + f64::from(k) * 1e-3));
    }
    let scene = builder.finish("squares".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer::new(&scene, &octree);
    let offsets = [0.0, 1e-15, -1e-15, 0.25, 1.0];
    let rays: Vec<Ray> = (0..800u32)
        .map(|i| {
            let x = -1.6 + 4.4 * f64::from(i % 40) / 39.0;
            let y = f64::from(i / 40) / 19.0 + offsets[i as usize % offsets.len()];
            // No zero component: the rays can go as packets.
            Ray::new(DVec3::new(x, y, 2.0), DVec3::new(1e-3, 1e-3, -1.0))
        })
        .collect();
    let together = render(&tracer, &rays, &[Aov::Certain], |_| {});
    let together = together.flags(Aov::Certain).unwrap();
    let alone: Vec<u8> = rays
        .iter()
        .map(|ray| render(&tracer, &vec![*ray], &[Aov::Certain], |_| {}))
        .map(|b| b.flags(Aov::Certain).unwrap()[0])
        .collect();
    assert_eq!(together, alone.as_slice());
    // From the smallest positive `tmin` (the same hits here): no search notes its offers,
    // so every ray's competitors are looked for by a traversal of their own.
    let probed: Vec<u8> = rays
        .iter()
        .map(|ray| {
            let rays = Rays {
                source: &vec![*ray],
                range: |_| (f64::MIN_POSITIVE, f64::INFINITY),
                refuse_untraceable: false,
            };
            let buffers = trace(&tracer, &rays, &[Aov::Certain], |_| {}).unwrap();
            buffers.flags(Aov::Certain).unwrap()[0]
        })
        .collect();
    assert_eq!(together, probed.as_slice());
    let uncertain = alone.iter().filter(|&&c| c == 0).count();
    assert!(
        (40..760).contains(&uncertain),
        "{uncertain} of 800 uncertain: the scene should give both"
    );
}

/// A ray that cannot be traced (a zero direction, a NaN origin) is a miss, never a certain
/// one; a plain miss beside it is certain.
#[test]
fn rays_that_were_not_traced_are_not_certain() {
    let rays = vec![
        Ray::new(DVec3::new(5.0, 5.0, 1.0), DVec3::NEG_Z),
        Ray::new(DVec3::new(0.5, 0.5, 1.0), DVec3::ZERO),
        Ray::new(DVec3::new(f64::NAN, 0.5, 1.0), DVec3::NEG_Z),
    ];
    let (depth, _, certain) = square_at(0.1, rays);
    assert_eq!(depth, [f64::INFINITY; 3]);
    assert_eq!(certain, [1, 0, 0]);
}
