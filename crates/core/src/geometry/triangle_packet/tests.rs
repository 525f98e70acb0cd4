use super::*;
use crate::test_rng::Rng;

/// The packet's kernels on this CPU: the detected one and the portable one.
fn kernels(packet: WatertightPacket) -> [WatertightPacket; 2] {
    [packet, packet.portable()]
}

/// The point of `tri` with barycentric weights `w` (summing to 1).
fn at(tri: &[DVec3; 3], w: [f64; 3]) -> DVec3 {
    tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2]
}

/// Rays aimed from near one origin at points of a triangle's plane well inside it must be
/// kept, and rays aimed at points well outside it refused (their lines miss the triangle by
/// far more than rounding); the analysis, not the single-ray test, says which is which.
/// Scales from 1e-6 to 1e6 and origins up to a thousand sizes away.
#[test]
fn the_filter_keeps_rays_through_the_triangle_and_refuses_rays_beside_it() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut packets, mut refused) = (0, 0);
    for round in 0..4000 {
        let size = 10f64.powi(round % 13 - 6);
        let tri = [0; 3].map(|_| rng.point(-size, size));
        let normal = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        if normal.length() < 1e-3 * size * size {
            continue;
        }
        let origin = at(&tri, [1.0 / 3.0; 3])
            + normal.normalize() * size * rng.uniform(0.5, 1000.0)
            + rng.point(-size, size);
        let mut inside = 0u32;
        let targets: [DVec3; PACKET] = std::array::from_fn(|i| {
            let (a, b) = (rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
            let w = [a, b, 1.0 - a - b];
            let min = w.iter().copied().fold(f64::INFINITY, f64::min);
            if min >= 0.05 {
                inside |= 1 << i;
            }
            // Kept only when clearly inside or clearly outside.
            if min > -0.05 && min < 0.05 {
                at(&tri, [1.0 / 3.0; 3])
            } else {
                at(&tri, w)
            }
        });
        let centre = at(&tri, [1.0 / 3.0; 3]);
        inside |= targets
            .iter()
            .enumerate()
            .filter(|(_, t)| **t == centre)
            .fold(0, |m, (i, _)| m | 1 << i);
        let origins: [DVec3; PACKET] =
            std::array::from_fn(|_| origin + rng.point(-(1e-3 * size), 1e-3 * size));
        let rays: [WatertightRay; PACKET] =
            std::array::from_fn(|i| WatertightRay::new(origins[i], targets[i] - origins[i]));
        let Some(packet) = WatertightPacket::new(Kernel::detect(), |i| &rays[i]) else {
            continue;
        };
        packets += 1;
        for packet in kernels(packet) {
            let kept = packet.candidates(&tri, 0xff);
            assert_eq!(
                kept & inside,
                inside,
                "round {round}: a ray through the triangle refused"
            );
            assert_eq!(
                kept & !inside,
                0,
                "round {round}: a ray beside the triangle kept"
            );
            assert_eq!(packet.candidates(&tri, 0b1010_0101), kept & 0b1010_0101);
        }
        refused += (!inside & 0xff).count_ones();
    }
    assert!(
        packets > 3000 && refused > 10000,
        "{packets} packets, {refused} refusals"
    );
}

/// A triangle from a small set of corners (so that triangles share edges and vertices
/// exactly) at a scale from 1e-300 to 1e300, and rays through a vertex, along an edge and in
/// the triangle's plane.
fn edge_case(rng: &mut Rng, round: usize) -> ([DVec3; 3], [WatertightRay; PACKET]) {
    let scale = [1.0, 1e-300, 1e300, 1e-160, 3.0][round % 5];
    let corner = [
        rng.point(-1.0, 1.0),
        rng.point(-1.0, 1.0),
        rng.point(-1.0, 1.0),
    ];
    let pick = |r: &mut Rng| corner[(r.uniform(0.0, 1.0) * 3.0) as usize % 3] * scale;
    let tri = [pick(rng), rng.point(-1.0, 1.0) * scale, pick(rng)];
    let origin = rng.point(-4.0, 4.0) * scale;
    let base = tri[0] + (tri[1] - tri[0]) * rng.uniform(0.0, 1.0) - origin;
    let rays = std::array::from_fn(|i| {
        let target = match i {
            // Through a vertex, along an edge, and in the plane of the triangle.
            0 => tri[0] - origin,
            1 => tri[1] - tri[0],
            _ => base + (tri[2] - tri[1]) * rng.uniform(-0.1, 0.1),
        };
        WatertightRay::new(origin, target)
    });
    (tri, rays)
}

/// Whatever the geometry (shared edges and vertices, rays along a triangle's plane, far
/// origins, subnormal and huge coordinates), every ray the single-ray test hits is kept, and
/// the kernels agree bit for bit.
#[test]
fn no_ray_the_single_ray_test_hits_is_refused() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let (mut hits, mut tests) = (0, 0);
    for round in 0..50000 {
        let (tri, rays) = edge_case(&mut rng, round);
        let Some(packet) = WatertightPacket::new(Kernel::detect(), |i| &rays[i]) else {
            continue;
        };
        let expected = (0..PACKET)
            .filter(|&i| rays[i].intersect(&tri, f64::INFINITY).is_some())
            .fold(0u32, |m, i| m | 1 << i);
        let [fast, portable] = kernels(packet).map(|p| p.candidates(&tri, 0xff));
        assert_eq!(fast, portable, "round {round}: the kernels disagree");
        assert_eq!(fast & expected, expected, "round {round}: a hit refused");
        hits += expected.count_ones();
        tests += 1;
    }
    assert!(tests > 4000 && hits > 6000, "{tests} packets, {hits} hits");
}

/// The rays [`WatertightPacket::candidates_apart`] reports are exactly those `certainly_apart`'s
/// edge filter passes over, with either kernel, on the same edge cases and on rays aimed a
/// little beside a triangle, for a triangle taken as exact and for one whose vertices may be
/// off by a placement bound (half the rounds, from 1e-17 to 1e-8 of its size), for a packet
/// and for a lone ray; they are refused, none is hit, and `kept` is
/// [`WatertightPacket::candidates`]'s. The rays it reports `inside` are exactly those
/// `certainly_inside` finds, all kept.
#[test]
fn apart_rays_are_the_edge_filter_s() {
    let mut rng = Rng(0x6a09_e667_f3bc_c908);
    let (mut apart_rays, mut refused_rays, mut inside_rays) = (0, 0, 0);
    for round in 0..20000 {
        let (tri, mut rays) = edge_case(&mut rng, round);
        if round % 2 == 1 {
            // Beside an edge by a random power of ten of the triangle's size.
            let size = (tri[1] - tri[0]).length().max(f64::MIN_POSITIVE);
            for ray in rays.iter_mut().skip(2) {
                let (_, origin) = ray.shear_and_origin();
                let edge = tri[2] + (tri[1] - tri[2]) * rng.uniform(0.0, 1.0);
                let off = rng.point(-1.0, 1.0) * size * 10f64.powf(rng.uniform(-15.0, 0.0));
                *ray = WatertightRay::new(origin, edge + off - origin);
            }
        }
        let Some(packet) = WatertightPacket::new(Kernel::detect(), |i| &rays[i]) else {
            continue;
        };
        let hit = (0..PACKET)
            .filter(|&i| rays[i].intersect(&tri, f64::INFINITY).is_some())
            .fold(0u32, |m, i| m | 1 << i);
        let size = (tri[1] - tri[0]).length();
        let placement = match round % 4 {
            0 | 1 => 0.0,
            _ => size * 10f64.powf(rng.uniform(-17.0, -8.0)),
        };
        let lanes = |test: &dyn Fn(usize) -> bool| {
            (0..PACKET)
                .filter(|&i| test(i))
                .fold(0u32, |m, i| m | 1 << i)
        };
        use crate::bound::triangle::{certainly_inside, edges_apart};
        let filter = lanes(&|i| edges_apart(&rays[i], &tri, placement));
        let inside = lanes(&|i| certainly_inside(&rays[i], &tri, placement));
        let active = [0b1101_1111, 1 << (round % PACKET)][round / 4 % 2];
        for packet in kernels(packet) {
            let verdict = packet.candidates_apart(&tri, placement, active, |i| &rays[i]);
            let kept = verdict.kept;
            assert_eq!(kept, packet.candidates(&tri, active), "round {round}");
            assert_eq!(verdict.apart, filter & active, "round {round}: {tri:?}");
            assert_eq!(verdict.apart & (kept | hit), 0, "round {round}");
            assert_eq!(verdict.inside, inside & active, "round {round}: {tri:?}");
            assert_eq!(verdict.inside & !kept, 0, "round {round}");
            refused_rays += (active & !kept).count_ones();
        }
        apart_rays += (filter & active).count_ones();
        inside_rays += (inside & active).count_ones();
    }
    assert!(
        apart_rays > 1000 && refused_rays > apart_rays && inside_rays > 500,
        "{apart_rays} {refused_rays} {inside_rays}"
    );
}

#[test]
fn rays_with_different_dominant_axes_do_not_form_a_packet() {
    let rays: [WatertightRay; PACKET] = std::array::from_fn(|i| {
        let dir = if i == 5 {
            DVec3::new(1.0, 0.2, 0.1)
        } else {
            DVec3::new(0.1, 0.2, 1.0)
        };
        WatertightRay::new(DVec3::ZERO, dir)
    });
    assert!(WatertightPacket::new(Kernel::detect(), |i| &rays[i]).is_none());
    let same: [WatertightRay; PACKET] = std::array::from_fn(|i| {
        WatertightRay::new(DVec3::ZERO, DVec3::new(0.1, 0.2, 1.0 + i as f64))
    });
    assert!(WatertightPacket::new(Kernel::detect(), |i| &same[i]).is_some());
}

/// One ray against four triangles built around it: a triangle with a point of the ray well
/// inside it (all barycentric weights 0.05 or more, by construction) must be kept, one whose
/// plane the ray meets well outside it (a weight of -0.05 or less) refused; only the `active`
/// triangles are considered. Scales from 1e-6 to 1e6.
#[test]
fn the_group_filter_keeps_triangles_the_ray_crosses_and_refuses_the_others() {
    let mut rng = Rng(0x51_7cc1_b727_220a);
    let (mut groups, mut refused) = (0, 0);
    for round in 0..4000 {
        let size = 10f64.powi(round % 13 - 6);
        let origin = rng.point(-(10.0 * size), 10.0 * size);
        let dir = rng.point(-1.0, 1.0);
        let ray = WatertightRay::new(origin, dir);
        let mut crossed = 0u32;
        let tris: [[DVec3; 3]; 4] = std::array::from_fn(|k| {
            let point = origin + dir * rng.uniform(0.5, 20.0) * size;
            let inside = rng.uniform(0.0, 1.0) < 0.5;
            let (a, b) = if inside {
                (rng.uniform(0.05, 0.45), rng.uniform(0.05, 0.45))
            } else {
                (rng.uniform(-1.0, -0.05), rng.uniform(0.05, 0.9))
            };
            let w = [a, b, 1.0 - a - b];
            crossed |= u32::from(inside) << k;
            let (v0, v1) = (
                point + rng.point(-size, size),
                point + rng.point(-size, size),
            );
            let v2 = (point - v0 * w[0] - v1 * w[1]) / w[2];
            [v0, v1, v2]
        });
        // Keep the rounds whose triangles the ray meets at a clear angle.
        let steep = tris.iter().all(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            n.normalize().dot(dir.normalize()).abs() > 0.05
        });
        if !steep {
            continue;
        }
        groups += 1;
        let active = 1 + (round as u32 % 15);
        for kept in [
            ray.candidates(Kernel::detect(), &tris, active),
            ray.candidates_portable(&tris, active),
        ] {
            assert_eq!(kept, crossed & active, "round {round}");
        }
        refused += (!crossed & active).count_ones();
    }
    assert!(
        groups > 2000 && refused > 2000,
        "{groups} groups, {refused} refusals"
    );
}

/// Whatever the geometry (triangles sharing edges and vertices, rays through a vertex or along
/// a plane, subnormal and huge coordinates), every triangle of a group the single-ray test
/// hits is kept, and the kernels agree bit for bit.
#[test]
fn no_triangle_the_single_ray_test_hits_is_refused() {
    let mut rng = Rng(0x3c6e_f372_fe94_f82b);
    let mut hits = 0;
    for round in 0..40000 {
        let scale = [1.0, 1e-300, 1e300, 1e-160, 3.0][round % 5];
        let corner = [
            rng.point(-1.0, 1.0),
            rng.point(-1.0, 1.0),
            rng.point(-1.0, 1.0),
            rng.point(-1.0, 1.0),
        ];
        let pick = |r: &mut Rng| corner[(r.uniform(0.0, 1.0) * 4.0) as usize % 4] * scale;
        let tris: [[DVec3; 3]; 4] =
            std::array::from_fn(|_| [pick(&mut rng), pick(&mut rng), rng.point(-1.0, 1.0) * scale]);
        let origin = rng.point(-4.0, 4.0) * scale;
        let dir = match round % 3 {
            0 => corner[round % 4] * scale - origin,
            1 => tris[0][1] - tris[0][0],
            _ => (corner[0] + corner[1]) * 0.5 * scale - origin,
        };
        let ray = WatertightRay::new(origin, dir);
        let active = 1 + (round as u32 % 15);
        let expected = (0..4)
            .filter(|&k| active & (1 << k) != 0)
            .filter(|&k| ray.intersect(&tris[k], f64::INFINITY).is_some())
            .fold(0u32, |m, k| m | 1 << k);
        let fast = ray.candidates(Kernel::detect(), &tris, active);
        assert_eq!(
            fast,
            ray.candidates_portable(&tris, active),
            "round {round}"
        );
        assert_eq!(fast & expected, expected, "round {round}: a hit refused");
        assert_eq!(
            fast & !active,
            0,
            "round {round}: an inactive triangle kept"
        );
        hits += expected.count_ones();
    }
    assert!(hits > 6000, "{hits} hits");
}

/// [`WatertightRay::candidates_apart`] says of each of four triangles what the one-triangle
/// filters say (`edges_apart`, `certainly_inside`, lane for lane, with a placement bound of
/// its own per lane, zero in a quarter of the lanes), `kept` is
/// [`WatertightRay::candidates`]'s, and both kernels agree: on triangles crossed well inside or
/// passed well beside (scales 1e-6 to 1e6), and on triangles sharing vertices and edges with
/// rays through them (scales 1e-300 to 1e300).
#[test]
fn the_group_verdict_is_the_one_triangle_filters() {
    use crate::bound::triangle::{certainly_inside, edges_apart};
    let mut rng = Rng(0x1f83_d9ab_fb41_bd6b);
    let (mut apart_lanes, mut inside_lanes) = (0, 0);
    for round in 0..8000 {
        let scale = [1e-6, 1.0, 1e6, 1e-300, 1e300][round % 5];
        let origin = rng.point(-4.0, 4.0) * scale;
        let dir = rng.point(-1.0, 1.0);
        let tris: [[DVec3; 3]; 4] = std::array::from_fn(|k| {
            let point = origin + dir * rng.uniform(0.5, 20.0) * scale;
            let spread = |r: &mut Rng| point + r.point(-1.0, 1.0) * scale;
            if round % 2 == 0 || k == 0 {
                [spread(&mut rng), spread(&mut rng), spread(&mut rng)]
            } else {
                // Sharing an edge with the group's first triangle.
                let first = [spread(&mut rng), spread(&mut rng), spread(&mut rng)];
                [first[0], first[1], spread(&mut rng)]
            }
        });
        let ray = WatertightRay::new(origin, dir);
        let placement: [f64; 4] = std::array::from_fn(|k| {
            let size = (tris[k][1] - tris[k][0]).length();
            if k == round % 4 {
                0.0
            } else {
                size * 10f64.powf(rng.uniform(-17.0, -6.0))
            }
        });
        let active = 1 + (round as u32 % 15);
        let lanes = |test: &dyn Fn(usize) -> bool| {
            (0..4)
                .filter(|&k| active & (1 << k) != 0 && test(k))
                .fold(0u32, |m, k| m | 1 << k)
        };
        let apart = lanes(&|k| edges_apart(&ray, &tris[k], placement[k]));
        let inside = lanes(&|k| certainly_inside(&ray, &tris[k], placement[k]));
        for kernel in [Kernel::detect(), Kernel::Portable] {
            let verdict = ray.candidates_apart(kernel, &tris, active, &placement);
            assert_eq!(
                verdict.kept,
                ray.candidates(kernel, &tris, active),
                "{round}"
            );
            assert_eq!(verdict.apart, apart, "round {round}: {tris:?}");
            assert_eq!(verdict.inside, inside, "round {round}: {tris:?}");
            assert_eq!(verdict.apart & verdict.kept, 0, "round {round}");
        }
        apart_lanes += apart.count_ones();
        inside_lanes += inside.count_ones();
    }
    assert!(
        apart_lanes > 2000 && inside_lanes > 500,
        "{apart_lanes} {inside_lanes}"
    );
}
