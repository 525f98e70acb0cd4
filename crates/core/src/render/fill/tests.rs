//! Tests of the trace loop: refused rays, progress, and the origin order's buffers.

use super::*;
use crate::accel::{Octree, OctreeParams};
use crate::scene::SceneBuilder;
use crate::trace::Tracer;

/// 200 000 rays at a unit square, some of them untraceable, in a pool of `threads`; in
/// the order of their origins (which spread along x) when `reorder`.
fn trace_with_bad_rays(
    threads: usize,
    bad: &[usize],
    reorder: bool,
) -> (Result<Buffers, usize>, Vec<usize>) {
    let mut builder = SceneBuilder::new();
    let square = [DVec3::ZERO, DVec3::X, DVec3::Y];
    builder.add_mesh("t".into(), "test".into(), vec![square]);
    let scene = builder.finish("square".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer::new(&scene, &octree);
    let mut source: Vec<Ray> = (0..200_000)
        .map(|i| {
            let x = (i % 1000) as f64 / 2000.0;
            Ray::new(DVec3::new(x, 0.1, 1.0), DVec3::NEG_Z)
        })
        .collect();
    for &i in bad {
        source[i].dir = DVec3::ZERO;
    }
    let rays = Rays {
        source: &source,
        range: |_| (0.0, f64::INFINITY),
        refuse_untraceable: true,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut reports = Vec::new();
    let report = |n| reports.push(n);
    let result = pool.install(|| match reorder {
        true => {
            let origins = origin_order(&source, || Some(usize::MAX)).expect("spread origins");
            trace_reordered(&tracer, &rays, &[Aov::Depth], report, &origins)
        }
        false => trace(&tracer, &rays, &[Aov::Depth], report),
    });
    (result, reports)
}

/// The first untraceable ray is the one reported, whatever the thread count and wherever
/// the others lie (blocks after a refused ray may be skipped, blocks before it may not).
#[test]
fn the_first_refused_ray_is_reported() {
    for (threads, reorder) in [(1, false), (2, false), (4, false), (1, true), (2, true)] {
        // Ray 999 is at the far end of x, ray 1000 at its start: ordered, 1000 goes first.
        for bad in [
            &[150_001, 70_000, 199_999][..],
            &[5, 190_000],
            &[199_999],
            &[999, 1000],
        ] {
            let (result, _) = trace_with_bad_rays(threads, bad, reorder);
            let first = bad.iter().copied().min();
            assert_eq!(result.err(), first, "{threads} threads, bad rays {bad:?}");
        }
    }
}

/// Progress counts only grow, come about every 64 Ki rays and end at the ray count.
#[test]
fn progress_grows_to_the_ray_count() {
    for (threads, reorder) in [(1, false), (2, false), (4, false), (2, true)] {
        let (result, reports) = trace_with_bad_rays(threads, &[], reorder);
        let buffers = result.expect("every ray is traceable");
        let depth = buffers.floats(Aov::Depth).expect("depth buffer");
        assert!(
            depth.iter().all(|&d| d == 1.0),
            "every ray hits at distance 1"
        );
        assert!(reports.windows(2).all(|w| w[0] < w[1]), "{reports:?}");
        assert_eq!(reports.last(), Some(&200_000), "{reports:?}");
        assert!(
            (3..=8).contains(&reports.len()),
            "{threads} threads: {reports:?}"
        );
    }
}

/// A list of rays with spread origins, traced in the order of their origins' cells, gives
/// each buffer (one, two and three numbers, labels and flags per ray) exactly as traced in
/// the given order.
#[test]
fn origin_order_gives_the_buffers_of_the_given_order() {
    let mut rng = crate::test_rng::Rng(0x5eed);
    let triangles: Vec<[DVec3; 3]> = (0..300)
        .map(|_| {
            let a = rng.point(-1.0, 1.0);
            [a, a + rng.point(-0.3, 0.3), a + rng.point(-0.3, 0.3)]
        })
        .collect();
    let mut builder = SceneBuilder::new();
    builder.add_mesh("t".into(), "test".into(), triangles);
    let scene = builder.finish("soup".into());
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer::new(&scene, &octree);
    let source: Vec<Ray> = (0..6000)
        .map(|_| {
            let dir = rng.point(-1.0, 1.0);
            Ray::new(rng.point(-1.5, 1.5), dir)
        })
        .collect();
    let origins = origin_order(&source, || Some(usize::MAX)).expect("spread origins");
    let rays = Rays {
        source: &source,
        range: |_| (0.0, f64::INFINITY),
        refuse_untraceable: false,
    };
    let aovs = [
        Aov::Depth,
        Aov::Normal,
        Aov::Uv,
        Aov::Id,
        Aov::Error,
        Aov::Certain,
    ];
    let reordered = trace_reordered(&tracer, &rays, &aovs, |_| {}, &origins).unwrap();
    let given = trace_in_order(&tracer, &rays, &aovs, |_| {}).unwrap();
    assert_eq!(reordered, given);
    let depth = given.floats(Aov::Depth).unwrap();
    let hits = depth.iter().filter(|d| d.is_finite()).count();
    assert!((600..5400).contains(&hits), "{hits} of 6000 rays hit");
}
