//! The leaf filter against the exact test, on rays aimed at vertices and edges, grazing, and
//! from far away.

use super::super::layout::SLACK_WORDS;
use super::super::traverse::{self, Unobserved};
use super::super::{Octree, OctreeParams};
use super::*;
use crate::accel::{brute_force, prepare_ray, set_bits, PrimitiveSet};
use crate::scene::{Scene, SceneBuilder};
use crate::test_rng::Rng;
use glam::DVec3;
use std::collections::HashSet;

/// The kernels this CPU runs.
fn kernels() -> Vec<Kernel> {
    [Kernel::Avx2, Kernel::Portable]
        .into_iter()
        .filter(|k| k.available())
        .collect()
}

/// A bumpy grid of triangles sharing edges and vertices (some cells lying in a root
/// midplane), and the triangles.
fn grid(rng: &mut Rng) -> (Scene, Vec<[DVec3; 3]>) {
    let n = 24;
    let mut h = |i: usize, j: usize| {
        if (i + j).is_multiple_of(7) {
            0.0
        } else {
            rng.uniform(-0.3, 0.3)
        }
    };
    let mut heights = vec![vec![0.0; n + 1]; n + 1];
    for (i, row) in heights.iter_mut().enumerate() {
        for (j, z) in row.iter_mut().enumerate() {
            *z = h(i, j);
        }
    }
    let at = |i: usize, j: usize| {
        let step = 16.0 / n as f64;
        DVec3::new(
            -8.0 + i as f64 * step,
            -8.0 + j as f64 * step,
            heights[i][j],
        )
    };
    let mut tris = Vec::new();
    for i in 0..n {
        for j in 0..n {
            tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let mut builder = SceneBuilder::new();
    builder.add_mesh("grid".into(), "test".into(), tris.clone());
    let scene = builder.finish("grid".into());
    // The octree's coordinates are the scene's: the rays below need no anchor.
    assert_eq!(scene.anchor, DVec3::ZERO);
    (scene, tris)
}

/// A ray aimed at a vertex, a point of an edge or of the inside of a random triangle, from up
/// to 1e9 away, sometimes grazing (along an edge) or parallel to one or two axes.
fn aimed(rng: &mut Rng, tris: &[[DVec3; 3]]) -> (DVec3, DVec3) {
    let tri = tris[(rng.next() % tris.len() as u64) as usize];
    let (a, b) = (rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0));
    let target = match rng.next() % 3 {
        0 => tri[(rng.next() % 3) as usize],
        1 => tri[0] + (tri[1] - tri[0]) * a,
        _ => tri[0] + (tri[1] - tri[0]) * a.min(b) + (tri[2] - tri[0]) * (1.0 - a.max(b)),
    };
    let mut dir = match rng.next() % 4 {
        // Grazing: along an edge, a little off its plane.
        0 => (tri[1] - tri[0]) + DVec3::Z * rng.uniform(-1e-3, 1e-3),
        _ => rng.point(-1.0, 1.0),
    };
    for axis in 0..3 {
        if rng.next().is_multiple_of(5) {
            dir[axis] = 0.0;
        }
    }
    if dir == DVec3::ZERO {
        dir = DVec3::Z;
    }
    let distance = 10f64.powf(rng.uniform(-1.0, 9.0));
    (target - dir.normalize() * distance, dir)
}

/// For each ray, traversed without a limit (every leaf it crosses), every primitive the exact
/// test hits must be kept by the filter in some leaf: a hit primitive dropped everywhere is a
/// violation. Returns the references dropped and the violations.
fn audit(
    octree: &Octree,
    scene: &Scene,
    kernel: Kernel,
    rays: &[(DVec3, DVec3)],
) -> (usize, usize) {
    let layout = &octree.layout;
    let (mut dropped, mut violations) = (0, 0);
    for &(origin, dir) in rays {
        let lanes = Lanes::new(origin, dir + DVec3::ZERO, octree.scale);
        let mut kept = HashSet::new();
        let visit = |child: u32, _, _| {
            let prims = layout.leaf(child);
            let mut survived = 0;
            for first in (0..prims.len()).step_by(8) {
                let mask = chunk_mask(layout, kernel, child, first, &lanes, f32::INFINITY);
                for j in set_bits(mask) {
                    kept.insert(prims[first + j]);
                    survived += 1;
                }
            }
            dropped += prims.len() - survived;
            f64::INFINITY
        };
        traverse::run(
            layout,
            kernel,
            &lanes,
            f64::INFINITY,
            visit,
            &mut Unobserved,
        );
        let ray = prepare_ray(scene, origin, dir);
        let hit = |prim: u32| {
            scene
                .intersect(prim as usize, &ray, f64::INFINITY)
                .is_some()
        };
        violations += (0..scene.len() as u32)
            .filter(|prim| !kept.contains(prim) && hit(*prim))
            .count();
    }
    (dropped, violations)
}

/// The adversarial rays of these tests.
fn rays(rng: &mut Rng, tris: &[[DVec3; 3]]) -> Vec<(DVec3, DVec3)> {
    (0..6000).map(|_| aimed(rng, tris)).collect()
}

#[test]
fn every_primitive_the_exact_test_hits_is_kept_in_some_leaf() {
    let mut rng = Rng(0x1eaf_0001);
    let (scene, tris) = grid(&mut rng);
    let octree = Octree::build(&scene, OctreeParams::default());
    let rays = rays(&mut rng, &tris);
    for kernel in kernels() {
        let (dropped, violations) = audit(&octree, &scene, kernel, &rays);
        assert_eq!(
            violations, 0,
            "{kernel:?}: {violations} hit primitives dropped everywhere ({dropped} drops)"
        );
        assert!(dropped > 20_000, "{kernel:?}: only {dropped} drops");
    }
}

/// The audit can fail: boxes shrunk by one step of the grid on every side (a rounding inward
/// instead of outward) drop hits it sees.
#[test]
fn the_audit_catches_boxes_rounded_inward() {
    let mut rng = Rng(0x1eaf_0001);
    let (scene, tris) = grid(&mut rng);
    let mut octree = Octree::build(&scene, OctreeParams::default());
    let layout = &mut octree.layout;
    let mut at = 0;
    let mut shrunk = 0;
    while at + SLACK_WORDS < layout.refs.len() {
        let count = layout.refs[at] as usize;
        let boxes = at + HEADER + count;
        let words = &mut layout.refs[boxes..boxes + box_words(count)];
        let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).collect();
        for row in 0..ROWS {
            for b in &mut bytes[row * count..(row + 1) * count] {
                *b = if row < 3 {
                    b.saturating_add(1)
                } else {
                    b.saturating_sub(1)
                };
            }
        }
        for (word, b) in words.iter_mut().zip(bytes.chunks_exact(4)) {
            *word = u32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
        }
        shrunk += count;
        at = boxes + box_words(count);
    }
    assert_eq!(shrunk, octree.stats().references);
    let rays = rays(&mut rng, &tris);
    for kernel in kernels() {
        let (_, violations) = audit(&octree, &scene, kernel, &rays);
        assert!(violations > 10, "{kernel:?}: only {violations} violations");
    }
}

#[test]
fn the_filtered_octree_finds_brute_forces_hits() {
    let mut rng = Rng(0x1eaf_0002);
    let (scene, tris) = grid(&mut rng);
    let octree = Octree::build(&scene, OctreeParams::default());
    let mut hits = 0;
    for kernel in kernels() {
        let octree = octree.clone().with_kernel(kernel).expect("available");
        for (origin, dir) in rays(&mut rng, &tris) {
            let found = octree.intersect_ray(&scene, origin, dir, f64::INFINITY);
            assert_eq!(
                found,
                brute_force(&scene, &prepare_ray(&scene, origin, dir)),
                "{kernel:?}: {origin:?} + t {dir:?}"
            );
            hits += usize::from(found.is_some());
        }
    }
    assert!(hits > 5000, "{hits} hits");
}
