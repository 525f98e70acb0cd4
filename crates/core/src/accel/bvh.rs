//! A second acceleration backend: bounding volume hierarchies built by the `obvhs` crate (a
//! binary BVH2 or an eight-wide compressed CWBVH), over any [`PrimitiveSet`].
//!
//! It exists to measure the octree against a well-tuned BVH on the same primitives, the same
//! rays and the same exact f64 primitive tests, and to cross-check the octree's answers: a
//! test and benchmark oracle behind the `bvh-oracle` feature, not part of the command line or
//! the Python package (see [`crate::trace::BvhTracer`]).
//!
//! # Exactness with an f32 hierarchy
//! obvhs stores and traverses boxes in f32; the primitive tests stay in f64 through
//! [`PrimitiveSet::intersect`], and the closest hit is chosen with [`Hit::beats`], so the answer
//! is exactly the one [`super::brute_force`] gives provided the f32 box tests never cull a box
//! the exact ray enters before the best hit. That is made conservative as follows:
//!
//! - Every primitive box (the f64 [`PrimitiveSet::bounds`], in the scene-local coordinates the
//!   set uses) is grown by a pad `p = 1e-5 · scale + 1e-6`, where `scale` is the largest
//!   coordinate magnitude of the scene box, and then rounded outward to f32.
//! - The f32 ray starts where the exact ray enters the scene box grown by `4p` (or at its own
//!   origin when that lies inside), so its f32 origin has the rounding error of scene
//!   coordinates, not of a far camera. Its direction is the unit direction times
//!   `L ≈ 1000 · p` (a power of two), so an f32 parameter is a distance over `L`: the CWBVH node
//!   test clamps every child's entry to at least `1e-4` (obvhs's fixed `tmin`), and a box that
//!   holds a hit reaches at least `p` beyond it, that is `1e-3` in these units. Unit-direction
//!   components below `1e-15` in magnitude are replaced by `±1e-15` (obvhs would otherwise
//!   replace `1/d` by `±1/ε`, which narrows the slab of an axis-parallel ray).
//! - The rounding errors of the f32 slab tests (origin, direction, reciprocal, subtraction,
//!   product: a few ulps of `scale`) stay far below `p`, so a box holding a hit at distance `s`
//!   is entered, in f32, before `s` and left after it; the traversal limit handed back to obvhs
//!   is the best hit's distance plus `p`, rounded up. Ties in `t` are therefore never culled.
//! - Primitives with non-finite bounds are tested for every ray, outside the hierarchy.
//!
//! The pad makes the boxes a little looser than tight f32 boxes: `1e-5` of the scene size,
//! small against the primitives of any scene with fewer than about 10¹⁰ of them.

use super::{f32_above as round_up, f32_below as round_down};
use super::{test_primitive, Hit, PreparedRay, PrimitiveSet};
use glam::{DVec3, Vec3A};
use obvhs::aabb::Aabb as Aabb32;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray as Ray32, RayHit};
use obvhs::BvhBuildParams;
use serde::Serialize;
use std::fmt;
use std::str::FromStr;
use std::time::Duration;

/// Which obvhs hierarchy to build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BvhKind {
    /// Binary BVH (PLOC build, reinsertion, leaf collapsing).
    Bvh2,
    /// Compressed eight-wide BVH (Ylitie et al. 2017) converted from a BVH2.
    Cwbvh,
}

impl BvhKind {
    /// The name the benchmarks use.
    pub fn name(self) -> &'static str {
        match self {
            BvhKind::Bvh2 => "bvh",
            BvhKind::Cwbvh => "cwbvh",
        }
    }
}

impl fmt::Display for BvhKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for BvhKind {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "bvh" | "bvh2" => Ok(BvhKind::Bvh2),
            "cwbvh" => Ok(BvhKind::Cwbvh),
            _ => Err(crate::Error::msg(format!(
                "unknown BVH kind '{s}' (choose bvh or cwbvh)"
            ))),
        }
    }
}

/// Size figures of a built hierarchy.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BvhStats {
    /// The hierarchy's kind.
    pub kind: BvhKind,
    /// Nodes (for the CWBVH, each node holds up to eight children).
    pub nodes: usize,
    /// Primitives inside the hierarchy.
    pub primitives: usize,
    /// Primitives with non-finite bounds, tested by every ray outside the hierarchy.
    pub unbounded: usize,
    /// Bytes of nodes and primitive indices kept for tracing.
    pub bytes: usize,
    /// The obvhs build preset.
    pub build: &'static str,
}

/// The obvhs structure itself.
#[derive(Clone)]
enum Tree {
    Empty,
    Bvh2(Bvh2),
    Cwbvh(CwBvh),
}

/// A BVH over the primitives of a [`PrimitiveSet`], traversed in f32 and exact in f64.
#[derive(Clone)]
pub struct Bvh {
    tree: Tree,
    /// Primitives with non-finite bounds.
    unbounded: Vec<u32>,
    /// The box that the f32 ray starts on (the scene box grown by `4 · pad`).
    outer: [DVec3; 2],
    /// The pad of every primitive box (see the module docs).
    pad: f64,
    /// Length of the f32 ray's direction, `L` in the module docs.
    unit: f64,
    stats: BvhStats,
}

/// Direction components are at least this large in magnitude in the f32 ray.
const MIN_DIR: f32 = 1e-15;

impl Bvh {
    /// Builds a hierarchy of `kind` over every primitive of `set` with obvhs's `medium_build`.
    pub fn build<P: PrimitiveSet>(set: &P, kind: BvhKind) -> Bvh {
        let all: Vec<_> = (0..set.len()).map(|i| set.bounds(i)).collect();
        let finite = |b: &crate::geometry::Aabb| b.min.is_finite() && b.max.is_finite();
        let scene = all
            .iter()
            .filter(|b| finite(b))
            .fold(crate::geometry::Aabb::EMPTY, |a, b| a.union(*b));
        let scale = if scene.is_empty() {
            1.0
        } else {
            scene.min.abs().max(scene.max.abs()).max_element()
        };
        let pad = 1e-5 * scale + 1e-6;
        let mut boxes = Vec::with_capacity(all.len());
        let mut inside = Vec::with_capacity(all.len());
        let mut unbounded = Vec::new();
        for (i, b) in all.iter().enumerate() {
            if !finite(b) {
                unbounded.push(i as u32);
            } else if !b.is_empty() {
                let lo = b.min - DVec3::splat(pad);
                let hi = b.max + DVec3::splat(pad);
                boxes.push(Aabb32::new(
                    Vec3A::new(round_down(lo.x), round_down(lo.y), round_down(lo.z)),
                    Vec3A::new(round_up(hi.x), round_up(hi.y), round_up(hi.z)),
                ));
                inside.push(i as u32);
            }
        }
        drop(all);
        let params = BvhBuildParams::medium_build();
        let mut time = Duration::ZERO;
        let (tree, nodes, bytes) = if boxes.is_empty() {
            (Tree::Empty, 0, 0)
        } else {
            match kind {
                BvhKind::Bvh2 => {
                    let mut bvh = build_bvh2(&boxes, params, &mut time);
                    drop(boxes);
                    remap(&mut bvh.primitive_indices, &inside);
                    bvh.parents = Vec::new();
                    bvh.primitives_to_nodes = Vec::new();
                    bvh.primitive_indices_freelist = Vec::new();
                    bvh.nodes.shrink_to_fit();
                    bvh.primitive_indices.shrink_to_fit();
                    let bytes = bvh.nodes.len() * size_of::<Bvh2Node>()
                        + bvh.primitive_indices.len() * size_of::<u32>();
                    let nodes = bvh.nodes.len();
                    (Tree::Bvh2(bvh), nodes, bytes)
                }
                BvhKind::Cwbvh => {
                    let mut bvh = build_cwbvh(&boxes, params, &mut time);
                    drop(boxes);
                    remap(&mut bvh.primitive_indices, &inside);
                    bvh.exact_node_aabbs = None;
                    bvh.nodes.shrink_to_fit();
                    bvh.primitive_indices.shrink_to_fit();
                    let bytes = bvh.nodes.len() * size_of::<CwBvhNode>()
                        + bvh.primitive_indices.len() * size_of::<u32>();
                    let nodes = bvh.nodes.len();
                    (Tree::Cwbvh(bvh), nodes, bytes)
                }
            }
        };
        let grow = DVec3::splat(4.0 * pad);
        Bvh {
            tree,
            outer: [scene.min - grow, scene.max + grow],
            pad,
            unit: (1000.0 * pad).log2().round().exp2(),
            stats: BvhStats {
                kind,
                nodes,
                primitives: inside.len(),
                unbounded: unbounded.len(),
                bytes: bytes + unbounded.len() * size_of::<u32>(),
                build: "medium_build",
            },
            unbounded,
        }
    }

    /// Size figures.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// The nearest hit with `0 < t <= t_max`, exactly the hit [`super::brute_force`] finds.
    pub fn intersect<P: PrimitiveSet>(
        &self,
        set: &P,
        ray: &PreparedRay<P::RayData>,
        t_max: f64,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let test = |prim: u32, best: &mut Option<Hit>| test_primitive(set, prim, ray, t_max, best);
        for &prim in &self.unbounded {
            test(prim, &mut best);
        }
        let limit = best.map_or(t_max, |b| b.t);
        let Some(frame) = self.frame(ray.local_origin, ray.dir, limit) else {
            return best;
        };
        // The f32 traversal limit for a hit at ray parameter `t`.
        let bound = |t: f64| round_up(((t * frame.len - frame.start) + self.pad) / self.unit);
        let ray32 = frame.ray(bound(limit));
        let record = |id: usize, best: &mut Option<Hit>, indices: &[u32]| {
            if test(indices[id], best) {
                best.map_or(f32::INFINITY, |b| bound(b.t))
            } else {
                f32::INFINITY
            }
        };
        match &self.tree {
            Tree::Empty => {}
            Tree::Bvh2(bvh) => {
                bvh.ray_traverse(ray32, &mut RayHit::none(), |_, id| {
                    record(id, &mut best, &bvh.primitive_indices)
                });
            }
            Tree::Cwbvh(bvh) => {
                bvh.ray_traverse(ray32, &mut RayHit::none(), |_, id| {
                    record(id, &mut best, &bvh.primitive_indices)
                });
            }
        }
        best
    }

    /// The f32 ray of the exact ray `origin + t · dir`, `t <= limit`, or `None` when the ray
    /// cannot reach any bounded primitive before `limit`.
    fn frame(&self, origin: DVec3, dir: DVec3, limit: f64) -> Option<Frame> {
        if matches!(self.tree, Tree::Empty) {
            return None;
        }
        let len = dir.length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let unit = dir / len;
        let [lo, hi] = self.outer;
        let (mut enter, mut exit) = (0.0f64, limit * len);
        for a in 0..3 {
            if unit[a] == 0.0 {
                if origin[a] < lo[a] || origin[a] > hi[a] {
                    return None;
                }
            } else {
                let t1 = (lo[a] - origin[a]) / unit[a];
                let t2 = (hi[a] - origin[a]) / unit[a];
                enter = enter.max(t1.min(t2));
                exit = exit.min(t1.max(t2));
            }
        }
        // NaN (from an infinite limit times nothing) never happens: len > 0.
        if enter > exit {
            return None;
        }
        let start = origin + unit * enter;
        let scale = self.unit as f32;
        let component = |v: f64| {
            let f = v as f32;
            let f = if f.abs() < MIN_DIR {
                MIN_DIR.copysign(if v == 0.0 { 1.0 } else { f })
            } else {
                f
            };
            f * scale
        };
        Some(Frame {
            origin: Vec3A::new(start.x as f32, start.y as f32, start.z as f32),
            dir: Vec3A::new(component(unit.x), component(unit.y), component(unit.z)),
            start: enter,
            len,
        })
    }
}

impl fmt::Debug for Bvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Bvh")
            .field("stats", &self.stats)
            .field("pad", &self.pad)
            .finish_non_exhaustive()
    }
}

/// Replaces obvhs's indices into the bounded primitives by indices into the set.
fn remap(indices: &mut [u32], inside: &[u32]) {
    for i in indices {
        *i = inside[*i as usize];
    }
}

/// The f32 ray handed to obvhs.
struct Frame {
    origin: Vec3A,
    dir: Vec3A,
    /// Distance along the exact ray where the f32 ray starts.
    start: f64,
    /// Length of the exact ray's direction.
    len: f64,
}

impl Frame {
    fn ray(&self, tmax: f32) -> Ray32 {
        Ray32 {
            origin: self.origin,
            direction: self.dir,
            inv_direction: self.dir.recip(),
            tmin: 0.0,
            tmax,
        }
    }
}
