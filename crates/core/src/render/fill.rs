//! The per-ray outputs (AOVs) of a trace, computed in the same parallel pass as the nearest-hit
//! search: each task finds the hits of a block of rays (1,024, or whole pairs of an image's
//! rows, traced in tiles of 4 × 2 pixels) and at once fills the block's part of every output
//! column, while the block is in cache; no array of hits for all rays is kept. A long list of
//! rays goes in the order of its origins' cells, its buffers put back in the given order
//! (module `order`).
//! The command line's buffers and the Python package's `cast` and `render` are all made by
//! [`trace`], so they share this loop.

use super::order::{in_place, origin_order, tile_order, OriginOrder, Reordered};
use super::Aov;
use crate::accel::{Offered, PACKET};
use crate::bound::HitBound;
use crate::geometry::Ray;
use crate::geometry::RaySource;
use crate::scene::{Crossing, Located, Origins, Scene};
use crate::simd::Kernel;
use crate::trace::{traceable, NearestHits};
use glam::DVec3;
use rayon::prelude::*;
use std::cell::OnceCell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// One AOV's values for every ray.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    /// One number per ray (depth, z, t).
    Float(Vec<f64>),
    /// Two numbers per ray, flattened (uv).
    Pair(Vec<f64>),
    /// Three numbers per ray, flattened (normal, position, bary, shading normal).
    Vector(Vec<f64>),
    /// One label per ray (id, prim).
    Index(Vec<u32>),
    /// One flag per ray, 0 or 1 (certain).
    Flag(Vec<u8>),
}

impl Column {
    fn new(aov: Aov, n: usize) -> Column {
        match aov {
            Aov::T | Aov::Depth | Aov::Z | Aov::Error => Column::Float(vec![0.0; n]),
            Aov::Uv => Column::Pair(vec![0.0; 2 * n]),
            Aov::Normal | Aov::Position | Aov::Bary | Aov::ShadingNormal => {
                Column::Vector(vec![0.0; 3 * n])
            }
            Aov::Id | Aov::Prim | Aov::Material => Column::Index(vec![0; n]),
            Aov::Certain => Column::Flag(vec![0; n]),
        }
    }

    /// The column cut into blocks of `len` rays.
    fn blocks(&mut self, len: usize) -> Box<dyn Iterator<Item = Slot<'_>> + '_> {
        match self {
            Column::Float(v) => Box::new(v.chunks_mut(len).map(Slot::Float)),
            Column::Pair(v) => Box::new(v.as_chunks_mut().0.chunks_mut(len).map(Slot::Pair)),
            Column::Vector(v) => Box::new(v.as_chunks_mut().0.chunks_mut(len).map(Slot::Vector)),
            Column::Index(v) => Box::new(v.chunks_mut(len).map(Slot::Index)),
            Column::Flag(v) => Box::new(v.chunks_mut(len).map(Slot::Flag)),
        }
    }
}

/// The buffers of a trace: one column per requested AOV, in the order requested.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Buffers {
    columns: Vec<(Aov, Column)>,
}

impl Buffers {
    /// The buffers of rays traced in `order`, in the rays' own order.
    fn in_place(self, order: &OriginOrder) -> Buffers {
        let columns = self.columns.into_iter().map(|(aov, column)| {
            let column = match column {
                Column::Float(v) => Column::Float(order.in_place(&v, 1)),
                Column::Pair(v) => Column::Pair(order.in_place(&v, 2)),
                Column::Vector(v) => Column::Vector(order.in_place(&v, 3)),
                Column::Index(v) => Column::Index(order.in_place(&v, 1)),
                Column::Flag(v) => Column::Flag(order.in_place(&v, 1)),
            };
            (aov, column)
        });
        Buffers {
            columns: columns.collect(),
        }
    }

    /// The values of `aov`, if it was computed.
    pub fn column(&self, aov: Aov) -> Option<&Column> {
        self.columns.iter().find(|(a, _)| *a == aov).map(|(_, c)| c)
    }

    /// The values of a one-number AOV (depth, z, t).
    pub fn floats(&self, aov: Aov) -> Option<&[f64]> {
        match self.column(aov)? {
            Column::Float(v) => Some(v),
            _ => None,
        }
    }

    /// The values of a two-number AOV (uv).
    pub fn pairs(&self, aov: Aov) -> Option<&[[f64; 2]]> {
        match self.column(aov)? {
            Column::Pair(v) => Some(v.as_chunks().0),
            _ => None,
        }
    }

    /// The values of a vector AOV (normal, position, bary, shading normal).
    pub fn vectors(&self, aov: Aov) -> Option<&[[f64; 3]]> {
        match self.column(aov)? {
            Column::Vector(v) => Some(v.as_chunks().0),
            _ => None,
        }
    }

    /// The values of a label AOV (id, prim, material).
    pub fn labels(&self, aov: Aov) -> Option<&[u32]> {
        match self.column(aov)? {
            Column::Index(v) => Some(v),
            _ => None,
        }
    }

    /// The values of a flag AOV (certain).
    pub fn flags(&self, aov: Aov) -> Option<&[u8]> {
        match self.column(aov)? {
            Column::Flag(v) => Some(v),
            _ => None,
        }
    }

    /// The columns, in the order the AOVs were requested.
    pub fn into_columns(self) -> Vec<(Aov, Column)> {
        self.columns
    }
}

/// One block of a column.
enum Slot<'a> {
    Float(&'a mut [f64]),
    Pair(&'a mut [[f64; 2]]),
    Vector(&'a mut [[f64; 3]]),
    Index(&'a mut [u32]),
    Flag(&'a mut [u8]),
}

/// Sets `out[j]` to `value(j, hit)` for each ray `j` of a block with a hit, `miss` for the
/// others.
#[inline(always)]
fn fill<T: Copy>(
    out: &mut [T],
    hits: &[Option<Crossing>],
    miss: T,
    value: impl Fn(usize, &Crossing) -> T,
) {
    for (j, (slot, hit)) in out.iter_mut().zip(hits).enumerate() {
        *slot = hit.as_ref().map_or(miss, |hit| value(j, hit));
    }
}

/// Where the hits of one block of rays are turned into AOV values.
struct Block<'a> {
    tracer: &'a dyn NearestHits,
    /// The tracer's scene.
    scene: &'a Scene,
    /// The index of the block's first ray.
    start: usize,
    /// The camera's eye and view axis (zeros without a camera).
    eye: DVec3,
    forward: DVec3,
    /// Each ray's `(t_min, t_max]`, for the `certain` AOV.
    range: &'a (dyn Fn(usize) -> (f64, f64) + Sync),
    /// The hits' bounds, once `error` or `certain` asks for them.
    bounds: OnceCell<Vec<Option<(HitBound, f64)>>>,
    /// Whether the `certain` AOV is asked for (the hits' bounds then decide it too).
    decide: bool,
    /// The order the block's rays were traced in ([`tile_order`]; `None`: as they come).
    order: Option<Vec<usize>>,
    /// What each ray's search offered it, for `certain` (empty when it is not asked).
    offered: Vec<Option<Offered>>,
    /// The block's rays, in their own order: made once for the search, then read by every
    /// column (a camera ray takes about a hundred instructions to make).
    rays: Vec<Ray>,
}

impl Block<'_> {
    /// The `j`-th ray of the block (made once, by the search's set-up).
    #[inline(always)]
    fn ray(&self, j: usize) -> Ray {
        self.rays[j]
    }

    /// The hit's object and primitive.
    #[inline(always)]
    fn locate(&self, j: usize, hit: &Crossing) -> Located<'_> {
        let ray = self.ray(j);
        self.scene.locate_crossing(hit, ray.origin, ray.dir)
    }

    /// The kernel of the tracer's octree (the portable one for a tracer without one).
    fn kernel(&self) -> Kernel {
        self.tracer
            .tracer()
            .map_or(Kernel::Portable, |t| t.octree.kernel())
    }

    /// The bound of each hit of the block ([`super::bounds::hit_bound`]) and of its depth
    /// ([`super::bounds::depth_error`]), made on first use and shared by the `error` and
    /// `certain` columns.
    fn hit_bounds(&self, hits: &[Option<Crossing>]) -> &[Option<(HitBound, f64)>] {
        self.bounds
            .get_or_init(|| match (self.kernel(), self.decide) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `Kernel::Avx2` is only chosen where `Kernel::available` said so.
                (Kernel::Avx2, true) => unsafe { block_bounds_avx2::<true>(self, hits) },
                #[cfg(target_arch = "x86_64")]
                // SAFETY: as above.
                (Kernel::Avx2, false) => unsafe { block_bounds_avx2::<false>(self, hits) },
                (_, true) => block_bounds::<true>(self, hits),
                (_, false) => block_bounds::<false>(self, hits),
            })
    }

    /// Fills `slot`, the block's part of the column of `aov`, from the block's `hits`.
    fn fill(&self, aov: Aov, slot: &mut Slot, hits: &[Option<Crossing>]) {
        let inf = f64::INFINITY;
        match (aov, slot) {
            (Aov::T, Slot::Float(out)) => fill(out, hits, inf, |_, h| h.t),
            (Aov::Depth, Slot::Float(out)) => {
                fill(out, hits, inf, |j, h| h.t * self.ray(j).dir.length())
            }
            (Aov::Z, Slot::Float(out)) => fill(out, hits, inf, |j, h| {
                (self.ray(j).at(h.t) - self.eye).dot(self.forward)
            }),
            (Aov::Position, Slot::Vector(out)) => {
                fill(out, hits, [inf; 3], |j, h| self.ray(j).at(h.t).to_array())
            }
            (Aov::Normal, Slot::Vector(out)) => fill(out, hits, [0.0; 3], |j, h| {
                self.locate(j, h).normal.to_array()
            }),
            (Aov::Bary, Slot::Vector(out)) => fill(out, hits, [0.0; 3], |j, h| {
                let ray = self.ray(j);
                let weights = self.scene.barycentric(h, ray.origin, ray.dir);
                weights.unwrap_or([0.0; 3])
            }),
            (Aov::Uv, Slot::Pair(out)) => fill(out, hits, [inf; 2], |j, h| {
                let ray = self.ray(j);
                let uv = self.scene.uv(h, ray.origin, ray.dir);
                uv.unwrap_or([inf; 2])
            }),
            (Aov::ShadingNormal, Slot::Vector(out)) => fill(out, hits, [0.0; 3], |j, h| {
                let ray = self.ray(j);
                let normal = self.scene.shading_normal(h, ray.origin, ray.dir);
                normal.map_or([0.0; 3], |n| n.to_array())
            }),
            (Aov::Material, Slot::Index(out)) => fill(out, hits, 0, |j, h| {
                let ray = self.ray(j);
                self.scene.material(h, ray.origin, ray.dir)
            }),
            (Aov::Id, Slot::Index(out)) => fill(out, hits, 0, |_, h| self.scene.object(h.top).id),
            (Aov::Prim, Slot::Index(out)) => {
                fill(out, hits, u32::MAX, |j, h| self.locate(j, h).prim)
            }
            (Aov::Error, Slot::Float(out)) => {
                let bounds = self.hit_bounds(hits);
                fill(out, hits, 0.0, |j, _| {
                    bounds[j].map_or(f64::INFINITY, |b| b.1)
                })
            }
            (Aov::Certain, Slot::Flag(out)) => self.certain(out, hits),
            _ => unreachable!("a column is made for its AOV's type"),
        }
    }

    /// Fills `out`, the block's part of the `certain` column, from the block's `hits`: each
    /// ray decided from what its search offered it ([`super::bounds::certain_offered`]),
    /// eight at a time in the order they were traced (an image's 4 × 2 tiles); where that
    /// cannot tell for some ray of the eight, by one packet traversal for all of them
    /// ([`super::bounds::certain_packet`]), and for one of the last rays, by its own
    /// traversal. All 0 for a tracer without an octree.
    fn certain(&self, out: &mut [u8], hits: &[Option<Crossing>]) {
        let Some(query) = self.tracer.tracer() else {
            out.fill(0);
            return;
        };
        let bounds = self.hit_bounds(hits);
        let hit = |j: usize| hits[j].as_ref().zip(bounds[j].as_ref().map(|b| &b.0));
        let range = |j: usize| (self.range)(self.start + j);
        let as_given: Vec<usize>;
        let order = match &self.order {
            Some(order) => order,
            None => {
                as_given = (0..hits.len()).collect();
                &as_given
            }
        };
        let (packets, rest) = order.as_chunks::<PACKET>();
        let offered = |j: usize| {
            let offered = self.offered.get(j)?.as_ref()?;
            super::bounds::certain_offered(&query, &self.rays[j], hit(j), range(j), offered)
        };
        for packet in packets {
            // Written out, stopping at the first ray the offers cannot decide (the others are
            // then decided with it by the packet probe).
            let mut decided = true;
            for &j in packet {
                let Some(flag) = offered(j) else {
                    decided = false;
                    break;
                };
                out[j] = u8::from(flag);
            }
            if !decided {
                let rays = packet.map(|j| self.ray(j));
                let (hits, ranges) = (packet.map(hit), packet.map(range));
                let flags = super::bounds::certain_packet(&query, &rays, &hits, &ranges);
                for (&j, flag) in packet.iter().zip(flags) {
                    out[j] = u8::from(flag);
                }
            }
        }
        for &j in rest {
            let certain = offered(j)
                .unwrap_or_else(|| super::bounds::certain(&query, &self.rays[j], hit(j), range(j)));
            out[j] = u8::from(certain);
        }
    }
}

/// [`block_bounds`] compiled for AVX2 and FMA, so that what it inlines uses the instructions:
/// the bounded arithmetic's exact product errors ([`crate::bound::bounded`]) and the depth's
/// are fused multiply-adds, one instruction here and a call into the runtime otherwise. The
/// same bits either way: a fused multiply-add is correctly rounded on every CPU.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn block_bounds_avx2<const DECIDE: bool>(
    block: &Block<'_>,
    hits: &[Option<Crossing>],
) -> Vec<Option<(HitBound, f64)>> {
    block_bounds::<DECIDE>(block, hits)
}

/// The bounds of [`Block::hit_bounds`], a loop rather than `map` and `collect` (closures and
/// the collecting function are compiled apart, outside [`block_bounds_avx2`]'s instructions);
/// `DECIDE` is the block's `decide`, a constant so that the `error` column alone compiles
/// without the decision's lookups.
#[inline(always)]
fn block_bounds<const DECIDE: bool>(
    block: &Block<'_>,
    hits: &[Option<Crossing>],
) -> Vec<Option<(HitBound, f64)>> {
    let mut bounds = Vec::with_capacity(hits.len());
    let mut origins = Origins::default();
    for (j, hit) in hits.iter().enumerate() {
        let Some(hit) = hit else {
            bounds.push(None);
            continue;
        };
        let ray = block.ray(j);
        let decide = DECIDE.then(|| {
            let offered = block.offered.get(j).and_then(Option::as_ref);
            offered.is_some_and(|o| o.crosses_inside(hit.top))
        });
        let bound = super::bounds::hit_bound(block.scene, &ray, hit, decide, &mut origins);
        bounds.push(Some((bound, super::bounds::depth_error(&bound, &ray))));
    }
    bounds
}

/// Rays per parallel task (at least; an image's blocks are whole pairs of rows).
const BLOCK: usize = 1024;

/// Rays between two progress reports.
const REPORT: usize = 1 << 16;

/// The rays of a trace: their source, each ray's `(t_min, t_max]`, and whether a ray that
/// cannot be traced is an error. Generic, so that reading a ray and its range is inlined into
/// the search loop.
pub struct Rays<'a, S: ?Sized, R> {
    /// The rays.
    pub source: &'a S,
    /// Ray `i`'s parameter range `(t_min, t_max]`.
    pub range: R,
    /// Whether a ray [`crate::trace::traceable`] refuses (non-finite or zero, or a bad range)
    /// makes [`trace`] fail; otherwise it is a miss.
    pub refuse_untraceable: bool,
}

/// Finds the nearest hit of every ray in its range ([`NearestHits::nearest_all`]) and computes `aovs`
/// from it, in one parallel pass over blocks of rays (no pause between blocks: the workers
/// report progress themselves). `progress` is told how many rays are done, about every 64 Ki
/// rays, with counts that only grow. Returns the buffers, or the first refused ray (with
/// [`Rays::refuse_untraceable`]; blocks after a refused ray found so far are skipped);
/// whether a ray without a hit is refused is checked with the ray at hand, not read again.
///
/// A long list of rays is traced in the order of its origins' cells (module `render::order`)
/// and its buffers put back in the given order: the same values as in the given order.
pub fn trace<S, R>(
    tracer: &dyn NearestHits,
    rays: &Rays<S, R>,
    aovs: &[Aov],
    progress: impl FnMut(usize) + Send,
) -> Result<Buffers, usize>
where
    S: RaySource + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
{
    let trace_bytes = || {
        let tracer = tracer.tracer()?;
        Some(tracer.octree.bytes() + tracer.scene.trace_bytes())
    };
    match origin_order(rays.source, trace_bytes) {
        Some(origins) => trace_reordered(tracer, rays, aovs, progress, &origins),
        None => trace_in_order(tracer, rays, aovs, progress),
    }
}

/// [`trace`] in the order `origins`, the buffers put back in the rays' own order; a refused
/// ray is the first in their own order that cannot be traced, as [`trace_in_order`] says.
fn trace_reordered<S, R>(
    tracer: &dyn NearestHits,
    rays: &Rays<S, R>,
    aovs: &[Aov],
    progress: impl FnMut(usize) + Send,
    origins: &OriginOrder,
) -> Result<Buffers, usize>
where
    S: RaySource + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
{
    let order = &origins.order;
    let reordered = Rays {
        source: &Reordered {
            source: rays.source,
            order,
        },
        range: |k: usize| (rays.range)(order[k] as usize),
        refuse_untraceable: rays.refuse_untraceable,
    };
    match trace_in_order(tracer, &reordered, aovs, progress) {
        Ok(buffers) => Ok(buffers.in_place(origins)),
        Err(k) => Err((0..order.len())
            .find(|&i| {
                let (t_min, t_max) = (rays.range)(i);
                !traceable(&rays.source.ray(i), t_min, t_max)
            })
            .unwrap_or(order[k] as usize)),
    }
}

/// [`trace`] in the rays' own order (an image's in tiles).
fn trace_in_order<S, R>(
    tracer: &dyn NearestHits,
    rays: &Rays<S, R>,
    aovs: &[Aov],
    progress: impl FnMut(usize) + Send,
) -> Result<Buffers, usize>
where
    S: RaySource + ?Sized,
    R: Fn(usize) -> (f64, f64) + Sync,
{
    let n = rays.source.len();
    let width = rays.source.row_width();
    let block_len = width.map_or(BLOCK, |w| BLOCK.div_ceil(2 * w) * 2 * w);
    let mut columns: Vec<(Aov, Column)> = aovs.iter().map(|&a| (a, Column::new(a, n))).collect();
    let mut blocks: Vec<Vec<Slot>> = (0..n.div_ceil(block_len)).map(|_| Vec::new()).collect();
    for (_, column) in &mut columns {
        for (block, slot) in blocks.iter_mut().zip(column.blocks(block_len)) {
            block.push(slot);
        }
    }
    let (eye, forward) = rays
        .source
        .view_axis()
        .unwrap_or((DVec3::ZERO, DVec3::ZERO));
    // Finds the block's hits, then fills each column's part, the columns one after another.
    let fill = |start: usize, len: usize, slots: &mut [Slot]| -> Option<usize> {
        let mut block = Block {
            tracer,
            scene: tracer.scene(),
            start,
            eye,
            forward,
            range: &rays.range,
            bounds: OnceCell::new(),
            decide: aovs.contains(&Aov::Certain),
            order: tile_order(len, width),
            offered: Vec::new(),
            rays: Vec::new(),
        };
        let indices: Vec<usize> = match &block.order {
            Some(order) => order.iter().map(|&j| block.start + j).collect(),
            None => (block.start..block.start + len).collect(),
        };
        let ray_list: Vec<Ray> = indices.iter().map(|&i| rays.source.ray(i)).collect();
        let ranges: Vec<(f64, f64)> = indices.iter().map(|&i| (rays.range)(i)).collect();
        let (mut hits, mut offered) = if block.decide {
            tracer.nearest_all_offered(&ray_list, &ranges)
        } else {
            (tracer.nearest_all(&ray_list, &ranges), Vec::new())
        };
        let refused = rays.refuse_untraceable.then(|| {
            let each = indices.iter().zip(&ray_list).zip(&ranges).zip(&hits);
            each.filter(|(_, hit)| hit.is_none())
                .filter(|(((_, ray), &(t_min, t_max)), _)| !traceable(ray, t_min, t_max))
                .map(|(((&i, _), _), _)| i)
                .min()
        });
        if let Some(order) = &block.order {
            hits = in_place(order, hits);
            offered = in_place(order, offered);
        }
        block.offered = offered;
        block.rays = match &block.order {
            Some(order) => in_place(order, ray_list),
            None => ray_list,
        };
        for (slot, &aov) in slots.iter_mut().zip(aovs) {
            block.fill(aov, slot, &hits);
        }
        refused.flatten()
    };
    let first_refused = AtomicUsize::new(usize::MAX);
    let progress = Progress::new(n, progress);
    let refused = blocks
        .into_par_iter()
        .enumerate()
        .filter_map(|(b, mut slots)| {
            let start = b * block_len;
            // A block after a refused ray cannot hold the first one.
            if start > first_refused.load(Ordering::Relaxed) {
                return None;
            }
            let len = block_len.min(n - start);
            let refused = fill(start, len, &mut slots);
            if let Some(i) = refused {
                first_refused.fetch_min(i, Ordering::Relaxed);
            }
            progress.add(len);
            refused
        })
        .min();
    match refused {
        Some(i) => Err(i),
        None => Ok(Buffers { columns }),
    }
}

/// Progress told from the workers of a trace: the rays done, about every [`REPORT`] rays and
/// at the end, with counts that only grow (the reports take turns).
struct Progress<F> {
    total: usize,
    done: AtomicUsize,
    /// The count last reported, and the callback.
    reported: Mutex<(usize, F)>,
}

impl<F: FnMut(usize)> Progress<F> {
    fn new(total: usize, report: F) -> Progress<F> {
        Progress {
            total,
            done: AtomicUsize::new(0),
            reported: Mutex::new((0, report)),
        }
    }

    /// Counts `len` more rays done; reports when that crosses a multiple of [`REPORT`] or
    /// completes the trace.
    fn add(&self, len: usize) {
        let before = self.done.fetch_add(len, Ordering::Relaxed);
        let after = before + len;
        if after / REPORT == before / REPORT && after != self.total {
            return;
        }
        let mut reported = self.reported.lock().unwrap_or_else(|p| p.into_inner());
        let now = self.done.load(Ordering::Relaxed);
        if now > reported.0 {
            reported.0 = now;
            (reported.1)(now);
        }
    }
}

#[cfg(test)]
mod tests;
