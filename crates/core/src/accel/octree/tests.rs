//! Unit tests of the node test: the culling audit for every kernel, and rays lying in planes.

use super::lanes::{Kernel, Lanes};
use super::layout::Layout;
use super::packet::{Bundle, Tested};
use super::traverse::{self, Observer};
use super::wide::Wide;
use super::*;
use crate::accel::{brute_force, f32_above, prepare_ray, test_primitive};
use crate::scene::{Scene, SceneBuilder};
use crate::test_rng::Rng;

/// The kernels this CPU runs.
fn kernels() -> Vec<Kernel> {
    [Kernel::Avx2, Kernel::Portable]
        .into_iter()
        .filter(|k| k.available())
        .collect()
}

/// Random small triangles in [-8, 8]³, with some lying in the root's midplanes.
fn scene(rng: &mut Rng) -> Scene {
    let mut tris = Vec::new();
    for i in 0..1500 {
        let c = rng.point(-8.0, 8.0);
        let mut tri = [0; 3].map(|_| c + rng.point(-0.6, 0.6));
        if i % 5 == 0 {
            let axis = i % 3;
            tri.iter_mut().for_each(|v| v[axis] = 0.0);
        }
        tris.push(tri);
    }
    let mut builder = SceneBuilder::new();
    builder.add_mesh("t".into(), "test".into(), tris);
    builder.finish("random".into())
}

/// Does the ray enter lane `lane`'s box with `0 <= t <= limit`, by the f64 slab test?
fn enters(node: &Wide, lane: usize, origin: DVec3, dir: DVec3, limit: f64) -> bool {
    let planes = node.bounds(lane);
    let plane = |row: usize| f64::from(planes[row]);
    let lane_box = Aabb::new(
        DVec3::new(plane(0), plane(1), plane(2)),
        DVec3::new(plane(3), plane(4), plane(5)),
    );
    lane_box.ray_enters(origin, dir, limit)
}

/// Re-checks every lane the kernel culled with [`enters`].
struct Audit<'a> {
    layout: &'a Layout,
    origin: DVec3,
    dir: DVec3,
    culled: usize,
}

impl Observer for Audit<'_> {
    fn tested(&mut self, node: usize, hit: u32, t_best: f32) {
        let wide = &self.layout.nodes[node];
        for lane in 0..8 {
            if wide.occupancy() & (1 << lane) == 0 || hit & (1 << lane) != 0 {
                continue;
            }
            self.culled += 1;
            assert!(
                !enters(wide, lane, self.origin, self.dir, f64::from(t_best)),
                "lane {lane} of node {node} culled: ray {:?} + t {:?}, limit {t_best}",
                self.origin,
                self.dir
            );
        }
    }
}

/// Adversarial rays: axis-parallel, through cell faces and corners, from far away, with tiny
/// direction components.
fn adversarial(rng: &mut Rng, root: &Aabb) -> (DVec3, DVec3) {
    let tiny = [0.0, -0.0, 1e-20, -1e-38, 1e-41, 5e-324, 1e-300];
    let size = root.size().x;
    let mut dir = rng.point(-1.0, 1.0);
    for axis in 0..3 {
        if rng.next().is_multiple_of(3) {
            dir[axis] = rng.pick(&tiny);
        }
    }
    if dir == DVec3::ZERO {
        dir.x = 1.0;
    }
    let mut origin = rng.point(-12.0, 12.0);
    for axis in 0..3 {
        if rng.next().is_multiple_of(2) {
            // A cell face of depth up to 6.
            let k = rng.next() % 65;
            origin[axis] = root.min[axis] + size * k as f64 / 64.0;
        }
    }
    if rng.next().is_multiple_of(4) {
        let distance = 10f64.powf(rng.uniform(3.0, 15.0));
        let target = origin;
        origin = target - dir.normalize_or(DVec3::X) * distance;
    }
    (origin, dir + DVec3::ZERO)
}

#[test]
fn no_kernel_culls_a_lane_the_exact_slab_test_enters() {
    let mut rng = Rng(0x0c7_1234_5678);
    let scene = scene(&mut rng);
    let octree = Octree::build(&scene, OctreeParams::default());
    for kernel in kernels() {
        let (mut culled, mut hits) = (0, 0);
        for _ in 0..4000 {
            let (origin, dir) = adversarial(&mut rng, &octree.root());
            let ray = prepare_ray(&scene, origin, dir);
            let mut audit = Audit {
                layout: &octree.layout,
                origin,
                dir,
                culled: 0,
            };
            let mut best = None;
            let lanes = Lanes::new(origin, dir, octree.scale);
            traverse::run(
                &octree.layout,
                kernel,
                &lanes,
                f64::INFINITY,
                |leaf, _, _| {
                    for &prim in octree.layout.leaf(leaf) {
                        test_primitive(&scene, prim, &ray, f64::INFINITY, &mut best);
                    }
                    best.map_or(f64::INFINITY, |b| b.t)
                },
                &mut audit,
            );
            assert_eq!(
                best,
                brute_force(&scene, &ray),
                "{kernel:?}: {origin:?} + t {dir:?}"
            );
            culled += audit.culled;
            hits += usize::from(best.is_some());
        }
        assert!(
            culled > 10_000 && hits > 500,
            "{kernel:?}: {culled} culled, {hits} hits"
        );
    }
}

/// A node whose lane 0 holds the box [0.2, 0.8]³, and the planes it stores (rounded outward).
fn one_box() -> (Wide, [f64; 6]) {
    let mut lanes = [None; 8];
    lanes[0] = Some(([0.2, 0.2, 0.2, 0.8, 0.8, 0.8], 0));
    let (node, _) = Wide::new(&lanes);
    let stored = node.bounds(0).map(f64::from);
    (node, stored)
}

#[test]
fn a_ray_in_a_box_plane_keeps_the_other_bounds() {
    let (node, stored) = one_box();
    let (lo, hi, y) = (stored[0], stored[3], stored[1]);
    for kernel in kernels() {
        // In the box's lower y plane, along +x from x = -5: enters at x = lo, leaves at hi.
        let ray = Lanes::new(DVec3::new(-5.0, y, 0.5), DVec3::X, 1.0);
        let t = test(kernel, &node, &ray, f32::INFINITY);
        assert_eq!(t.hit & 1, 1, "{kernel:?}");
        let (enter, exit) = (f64::from(t.enter[0]), f64::from(t.exit[0]));
        assert!(
            (enter - (lo + 5.0)).abs() < 1e-5,
            "{kernel:?}: enter {enter}"
        );
        assert!((exit - (hi + 5.0)).abs() < 1e-5, "{kernel:?}: exit {exit}");
        // Just outside the plane, or ending before the box: culled.
        let below = Lanes::new(DVec3::new(-5.0, y - 1e-6, 0.5), DVec3::X, 1.0);
        assert_eq!(test(kernel, &node, &below, f32::INFINITY).hit & 1, 0);
        assert_eq!(test(kernel, &node, &ray, 5.1).hit & 1, 0);
    }
}

/// The node test of `kernel`.
fn test(kernel: Kernel, node: &Wide, ray: &Lanes, t_best: f32) -> super::lanes::Tested {
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: only kernels the CPU runs are tested.
        Kernel::Avx2 => unsafe { super::lanes::test_avx2(node, ray, t_best) },
        _ => super::lanes::test_portable(node, ray, t_best),
    }
}

/// A packet around an adversarial ray: origins moved by up to 1% of the root, directions
/// scaled per component by up to 2% (signs and zeros kept, so most packets can go as one).
fn packet(rng: &mut Rng, root: &Aabb) -> ([DVec3; PACKET], [DVec3; PACKET]) {
    let (origin, dir) = adversarial(rng, root);
    let spread = root.size().x * 0.01;
    let origins = std::array::from_fn(|_| origin + rng.point(-spread, spread));
    let dirs = std::array::from_fn(|_| dir * (DVec3::ONE + rng.point(0.0, 0.02)));
    (origins, dirs)
}

#[test]
fn every_ray_of_a_packet_gets_its_brute_force_answer() {
    let mut rng = Rng(0x9ac_4e75);
    let scene = scene(&mut rng);
    let octree = Octree::build(&scene, OctreeParams::default());
    for kernel in kernels() {
        let octree = octree.clone().with_kernel(kernel).unwrap();
        let (mut packets, mut hits) = (0, 0);
        for _ in 0..3000 {
            let (origins, dirs) = packet(&mut rng, &octree.root());
            let t_max = [f64::INFINITY; PACKET];
            let Some(found) = octree.intersect_packet(&scene, &origins, &dirs, &t_max) else {
                continue;
            };
            packets += 1;
            for i in 0..PACKET {
                let ray = prepare_ray(&scene, origins[i], dirs[i]);
                assert_eq!(found[i], brute_force(&scene, &ray), "{kernel:?}: ray {i}");
                hits += usize::from(found[i].is_some());
            }
        }
        assert!(
            packets > 1000 && hits > 500,
            "{kernel:?}: {packets} packets, {hits} hits"
        );
    }
}

#[test]
fn rays_in_different_octants_or_along_an_axis_do_not_form_a_packet() {
    let scene = scene(&mut Rng(7));
    let octree = Octree::build(&scene, OctreeParams::default());
    let origins = [DVec3::splat(-20.0); PACKET];
    let t_max = [f64::INFINITY; PACKET];
    let mut dirs = [DVec3::ONE; PACKET];
    assert!(octree
        .intersect_packet(&scene, &origins, &dirs, &t_max)
        .is_some());
    dirs[5].y = -1.0;
    assert!(octree
        .intersect_packet(&scene, &origins, &dirs, &t_max)
        .is_none());
    dirs[5].y = 0.0;
    assert!(octree
        .intersect_packet(&scene, &origins, &dirs, &t_max)
        .is_none());
}

#[test]
fn no_packet_kernel_culls_a_ray_the_exact_slab_test_lets_in() {
    let mut rng = Rng(0xa0d17);
    let scene = scene(&mut rng);
    let octree = Octree::build(&scene, OctreeParams::default());
    let nodes = &octree.layout.nodes;
    for kernel in kernels() {
        let mut culled = 0;
        for _ in 0..400 {
            let (origins, dirs) = packet(&mut rng, &octree.root());
            let Some(bundle) = Bundle::new(&origins, &dirs, octree.scale) else {
                continue;
            };
            for _ in 0..20 {
                let node = &nodes[(rng.next() % nodes.len() as u64) as usize];
                let limit = rng.pick(&[f64::INFINITY, 30.0, 5.0]);
                let t_best = [f32_above(limit); PACKET];
                let mut tested = Tested::default();
                match kernel {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: only kernels the CPU runs are tested.
                    Kernel::Avx2 => unsafe { bundle.test_avx2(node, &t_best, &mut tested) },
                    _ => bundle.test_portable(node, &t_best, &mut tested),
                }
                for lane in (0..8).filter(|lane| node.occupancy() & (1 << lane) != 0) {
                    for i in (0..PACKET).filter(|i| tested.hit[lane] & (1 << i) == 0) {
                        culled += 1;
                        assert!(
                            !enters(node, lane, origins[i], dirs[i], f64::from(t_best[i])),
                            "{kernel:?}: lane {lane} culled for {:?} + t {:?}",
                            origins[i],
                            dirs[i]
                        );
                    }
                }
            }
        }
        assert!(culled > 20_000, "{kernel:?}: {culled} culled");
    }
}
