use super::*;
use crate::bound::bounded::exact3;
use crate::bound::triangle::{bound, certainly_apart};
use crate::bound::Side;
use crate::test_rng::Rng;

/// A random triangle and ray, the ray often aimed near a vertex or an edge of it, the scene
/// often far from the origin, the vertices' bound zero or near the ray's distance.
fn case(rng: &mut Rng) -> ([DVec3; 3], WatertightRay, f64) {
    let far = rng.pick(&[0.0, 1.0, 1e3, 1e7]);
    let centre = rng.point(-1.0, 1.0) * far;
    let size = rng.pick(&[1e-6, 1e-2, 1.0, 1e4]);
    let tri = [0, 1, 2].map(|_| centre + rng.point(-1.0, 1.0) * size);
    let target = match rng.below(3) {
        0 => tri[rng.below(3)],
        1 => {
            let w = rng.uniform(0.0, 1.0);
            let (i, j) = (rng.below(3), rng.below(3));
            tri[i] * w + tri[j] * (1.0 - w)
        }
        _ => centre + rng.point(-2.0, 2.0) * size,
    };
    // Off the aim by a random power of ten of the size (the vertices' bound likewise), so
    // that the bounds decide many lanes.
    let scale = |rng: &mut Rng| size * 10f64.powf(rng.uniform(-16.0, -1.0));
    let offset = rng.point(-1.0, 1.0) * scale(rng);
    let target = DVec3::from_array((target + offset).to_array().map(|x| rng.nudge(x, 4)));
    let dir = rng.point(-1.0, 1.0);
    let origin = target - dir * rng.uniform(0.5, 3.0) * size.max(1.0);
    let placement = match rng.below(3) {
        0 => 0.0,
        _ => scale(rng),
    };
    (tri, WatertightRay::new(origin, dir), placement)
}

/// Each kernel gives, for every lane, the one-triangle filter's answer (and so
/// [`certainly_apart`]'s): on 20,000 random lanes, edge- and vertex-aimed rays among them,
/// with lanes left inactive and overflowing and NaN coordinates.
#[test]
fn every_lane_is_the_one_triangle_filter() {
    let mut rng = Rng(0x5eed_a9a7);
    let (mut apart, mut kept) = (0, 0);
    for round in 0..5_000 {
        let (tri, ray, placement) = case(&mut rng);
        let mut tris = [tri; LANES];
        let mut placements = [placement; LANES];
        for lane in 1..LANES {
            let (other, _, p) = case(&mut rng);
            tris[lane] = other;
            placements[lane] = p;
        }
        if round % 500 == 0 {
            tris[1][0].x = f64::NAN;
            tris[2][1].y = 1e300;
        }
        let active = (rng.next() & 0xf) as u32;
        let expected = apart_portable(&ray, &tris, &placements, active);
        for kernel in [Kernel::Portable, Kernel::detect()] {
            assert_eq!(
                apart_four(&ray, kernel, &tris, &placements, active),
                expected,
                "{kernel:?} {tris:?} {placements:?}"
            );
        }
        for lane in 0..LANES {
            let bit = expected & (1 << lane) != 0;
            if bit {
                assert!(certainly_apart(
                    &ray,
                    &tris[lane],
                    placements[lane],
                    f64::INFINITY
                ));
            }
            if active & (1 << lane) != 0 {
                (apart, kept) = (apart + usize::from(bit), kept + usize::from(!bit));
            }
        }
    }
    assert!(apart > 2_000 && kept > 1_000, "{apart} apart, {kept} kept");
}

/// A ray through a triangle's interior, edge or vertex is never passed over; one beside it is,
/// unless the vertices' bound reaches the ray. Checked against the bounded recomputation.
#[test]
fn only_what_the_exact_ray_misses_is_apart() {
    let tri = [[-1.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].map(DVec3::from_array);
    let dir = DVec3::new(0.01, -0.02, -1.0);
    // Through `(x, y, 0)` at `t = 5`.
    let origin_at = |(x, y): (f64, f64)| DVec3::new(x, y, 0.0) - dir * 5.0;
    let aims = [
        (0.0, 0.1),
        (1.0, 0.0),
        (0.5, 0.5),
        (0.5 + 1e-3, 0.5),
        (3.0, 0.0),
    ];
    let rays = aims.map(|aim| WatertightRay::new(origin_at(aim), dir));
    for kernel in [Kernel::Portable, Kernel::detect()] {
        let got: Vec<u32> = rays
            .iter()
            .map(|ray| apart_four(ray, kernel, &[tri; LANES], &[0.0, 0.0, 1e-2, 1e-2], 0xf))
            .collect();
        assert_eq!(got, [0, 0, 0, 0b0011, 0b1111], "{kernel:?}");
    }
    for (ray, aim) in rays.iter().zip(aims) {
        let side = bound(&exact3(origin_at(aim)), &exact3(dir), &tri.map(exact3)).side;
        let passed = apart_four(ray, Kernel::Portable, &[tri; LANES], &[0.0; LANES], 1) != 0;
        assert_eq!(passed, side == Side::Outside, "aimed at {aim:?}");
    }
}
