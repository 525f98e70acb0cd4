//! Per-ray work of the octree (not a timed test; `tools/profile_trace.sh` runs it): for the
//! auto-framed camera image of a scene, how many leaves holding primitives a ray visits, how
//! many primitive tests it runs and how many distinct primitives those are, and the share of
//! rays that hit.
//!
//! ```text
//! cargo bench --bench octree_counts -- SCENE [SIDE (default 256)]
//! ```

use raycast::accel::{prepare_ray, test_primitive, Hit, Octree, OctreeParams};
use raycast::camera::Camera;
use raycast::geometry::RaySource;
use raycast::import::{self, LoadOptions};
use raycast::render::CameraView;
use std::collections::HashSet;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| a != "--bench")
        .collect();
    let Some(path) = args.first() else {
        eprintln!("usage: octree_counts SCENE [SIDE]");
        std::process::exit(2);
    };
    let side: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let scene = match import::load(Path::new(path), &LoadOptions::default()) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("{e:#}");
            std::process::exit(1);
        }
    };
    let octree = Octree::build(&scene, OctreeParams::default());
    let view = CameraView::new(Camera::framing(&scene.world_bounds()), side, side);
    let (mut leaves, mut tests, mut distinct, mut hits) = (0usize, 0usize, 0usize, 0usize);
    for i in 0..view.len() {
        let ray = view.ray(i);
        let ray = prepare_ray(&scene, ray.origin - scene.anchor, ray.dir);
        let mut best: Option<Hit> = None;
        let mut seen = HashSet::new();
        octree.traverse(ray.local_origin, ray.dir, f64::INFINITY, |refs, _, _| {
            leaves += 1;
            for &prim in refs {
                tests += 1;
                distinct += usize::from(seen.insert(prim));
                test_primitive(&scene, prim, &ray, f64::INFINITY, &mut best);
            }
            best.map_or(f64::INFINITY, |b| b.t)
        });
        hits += usize::from(best.is_some());
    }
    let per_ray = |n: usize| n as f64 / view.len() as f64;
    println!(
        "{path}: {} rays, hits {:.1}%, leaves/ray {:.2}, tests/ray {:.2}, distinct/ray {:.2}",
        view.len(),
        100.0 * per_ray(hits),
        per_ray(leaves),
        per_ray(tests),
        per_ray(distinct)
    );
}
