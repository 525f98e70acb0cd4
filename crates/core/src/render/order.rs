//! The order rays are traced in, which is not always the order they are given in: an image's
//! pixels go in tiles of 4 × 2 ([`tile_order`]), so that each packet of eight rays is a
//! tile, and a long list of rays through a large scene goes by the cells of its origins
//! ([`origin_order`]), so that rays traced one after another start near each other and find
//! the octree's nodes and the mesh in cache. Each ray's answer does not depend on the order
//! (the search of one ray is the same in a packet or alone); the buffers are put back in the
//! given order.

use crate::geometry::{Aabb, Ray, RaySource};
use glam::DVec3;
use rayon::prelude::*;

/// The width of a tile of [`tile_order`] (its height is two rows).
pub const TILE: usize = 4;

/// The rays of a block in the order they are traced: for an image `width` pixels wide
/// (blocks starting at an even row), tiles of 4 × 2 pixels, left to right along each pair of
/// rows, so that each packet of eight neighbouring rays is a tile; `None` to keep the order.
pub fn tile_order(len: usize, width: Option<usize>) -> Option<Vec<usize>> {
    let width = width.filter(|&w| w >= TILE)?;
    let mut order = Vec::with_capacity(len);
    for pair in (0..len).step_by(2 * width) {
        for x in (0..width).step_by(TILE) {
            for row in [pair, pair + width] {
                order.extend((row + x..row + (x + TILE).min(width)).filter(|&i| i < len));
            }
        }
    }
    Some(order)
}

/// `values`, given in the traced `order`, put back in the rays' own order (an empty list
/// stays empty).
#[inline(always)]
pub fn in_place<T: Copy>(order: &[usize], values: Vec<T>) -> Vec<T> {
    let mut in_place = values.clone();
    for (&j, &value) in order.iter().zip(&values) {
        in_place[j] = value;
    }
    in_place
}

/// Lists shorter than this are traced in their own order (four blocks of the trace).
pub const ORIGIN_ORDER_MIN: usize = 4096;

/// Scenes whose trace reads fewer bytes than this (octree, vertices, index triples) are traced
/// in the list's order: they stay in the last-level cache in any order (this machine's is 32
/// MiB, shared with the streamed rays and buffers), and ordering costs about 25 ns a ray to
/// make and undo, and 35–40 ns more to read the rays out of sequence. A
/// million incoherent rays, one thread: the bunny (3.9 MB) 6–8 % slower ordered, four
/// bunnies side by side (15 MB) 15–40 % faster, fifteen (58 MB) 26–30 %; see
/// reports/octree_profile.md.
pub const ORIGIN_ORDER_BYTES: usize = 8 << 20;

/// Bits per axis of the origin cells of [`origin_order`]: 32 cells along each side of the
/// origins' box. (Measured on a million incoherent rays, one thread, the rays sorted
/// beforehand: 16, 32 and 64 cells and a 1024-cell Morton curve were equally fast.)
const CELL_BITS: u32 = 5;

/// The order of a list of rays by the cell of their origin along a Morton curve over the box
/// of their finite origins (a counting sort, stable: rays of one cell keep their order).
/// Indices are `u32`: with the sort keys, 12 bytes a ray, as the command line's memory
/// estimate counts it (`raycast_io`'s `buffer_bytes`).
#[derive(Debug, Clone, PartialEq)]
pub struct OriginOrder {
    /// The rays' indices in the order they are traced.
    pub order: Vec<u32>,
    /// Each ray's place in `order`.
    place: Vec<u32>,
}

/// The [`OriginOrder`] of `source`, or `None` to keep its order: for an image's rays (they go
/// in tiles), for fewer than [`ORIGIN_ORDER_MIN`] rays or 2³² or more, when every origin lies
/// in one cell (a camera's rays), and for a scene whose trace reads fewer than
/// [`ORIGIN_ORDER_BYTES`] (`trace_bytes()`, asked only for a long list; `None` when unknown):
/// it stays in cache in any order.
pub fn origin_order<S: RaySource + ?Sized>(
    source: &S,
    trace_bytes: impl FnOnce() -> Option<usize>,
) -> Option<OriginOrder> {
    let n = source.len();
    if source.row_width().is_some() || n < ORIGIN_ORDER_MIN || u32::try_from(n).is_err() {
        return None;
    }
    if trace_bytes().is_none_or(|bytes| bytes < ORIGIN_ORDER_BYTES) {
        return None;
    }
    let origins = (0..n)
        .into_par_iter()
        .with_min_len(ORIGIN_ORDER_MIN)
        .map(|i| source.ray(i).origin)
        .filter(|o| o.is_finite())
        .fold(|| Aabb::EMPTY, Aabb::grow)
        .reduce(|| Aabb::EMPTY, Aabb::union);
    let (lo, extent) = (origins.min, origins.size());
    if !extent.is_finite() || extent.max_element() <= 0.0 {
        return None;
    }
    let cells = f64::from(1u32 << CELL_BITS);
    // Zero along an axis the origins do not spread over; then every cell index there is 0.
    let scale = DVec3::select(extent.cmpgt(DVec3::ZERO), cells / extent, DVec3::ZERO);
    let keys: Vec<u32> = (0..n)
        .into_par_iter()
        .with_min_len(ORIGIN_ORDER_MIN)
        .map(|i| cell_key(source.ray(i), lo, scale))
        .collect();
    let mut starts = vec![0usize; 1 << (3 * CELL_BITS)];
    for &key in &keys {
        starts[key as usize] += 1;
    }
    let mut next = 0;
    for slot in &mut starts {
        (*slot, next) = (next, next + *slot);
    }
    let (mut order, mut place) = (vec![0; n], vec![0; n]);
    for (i, &key) in (0u32..).zip(&keys) {
        let slot = &mut starts[key as usize];
        (order[*slot], place[i as usize]) = (i, *slot as u32);
        *slot += 1;
    }
    Some(OriginOrder { order, place })
}

impl OriginOrder {
    /// `values`, `stride` numbers per ray given in the traced order, in the rays' own order
    /// (the rays' chunks gathered in parallel).
    pub fn in_place<T: Copy + Default + Send + Sync>(&self, values: &[T], stride: usize) -> Vec<T> {
        let mut out = vec![T::default(); values.len()];
        out.par_chunks_mut(stride)
            .zip(self.place.par_iter())
            .with_min_len(ORIGIN_ORDER_MIN)
            .for_each(|(ray, &k)| {
                let k = k as usize;
                ray.copy_from_slice(&values[k * stride..(k + 1) * stride]);
            });
        out
    }
}

/// The Morton code of the cell of `ray`'s origin: its coordinates' cell indices (from `lo`,
/// `scale` cells per unit, clamped to the grid; a NaN gives 0) with their bits interleaved.
#[inline(always)]
fn cell_key(ray: Ray, lo: DVec3, scale: DVec3) -> u32 {
    let top = (1u32 << CELL_BITS) - 1;
    // `as` saturates: a negative or NaN cell is 0, a far one `u32::MAX`, then clamped.
    let cell = ((ray.origin - lo) * scale)
        .to_array()
        .map(|c| (c as u32).min(top));
    (0..CELL_BITS).fold(0, |key, bit| {
        let axis = |a: usize| ((cell[a] >> bit) & 1) << (3 * bit + a as u32);
        key | axis(0) | axis(1) | axis(2)
    })
}

/// The rays of `source` in the order `order` (ray `k` is the source's `order[k]`).
pub struct Reordered<'a, S: ?Sized> {
    /// The rays in their given order.
    pub source: &'a S,
    /// The order they are traced in.
    pub order: &'a [u32],
}

impl<S: RaySource + ?Sized> RaySource for Reordered<'_, S> {
    fn len(&self) -> usize {
        self.order.len()
    }

    #[inline(always)]
    fn ray(&self, index: usize) -> Ray {
        self.source.ray(self.order[index] as usize)
    }

    fn view_axis(&self) -> Option<(DVec3, DVec3)> {
        self.source.view_axis()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The order `origin_order` traces `rays` in, through a scene too large for the cache.
    fn traced_order(rays: &Vec<Ray>) -> Vec<usize> {
        let origins = origin_order(rays, || Some(usize::MAX)).expect("spread origins");
        origins.order.iter().map(|&i| i as usize).collect()
    }

    /// Every ray of a block is traced exactly once, and (for widths that are a multiple of
    /// the tile's) each run of eight rays is a 4 × 2 tile of neighbouring pixels.
    #[test]
    fn tile_order_is_a_permutation_of_whole_tiles() {
        for (len, width) in [
            (2048, 1024),
            (1200, 100),
            (1000, 7),
            (12, 4),
            (5, 4),
            (301, 301),
        ] {
            let order = tile_order(len, Some(width)).unwrap();
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(
                sorted,
                (0..len).collect::<Vec<_>>(),
                "{len} rays, width {width}"
            );
            if width % TILE == 0 && len % (2 * width) == 0 {
                for tile in order.chunks(8) {
                    let (x, y) = (tile[0] % width, tile[0] / width);
                    let expected: Vec<usize> = (0..8)
                        .map(|k| (y + k / TILE) * width + x + k % TILE)
                        .collect();
                    assert_eq!(tile, expected.as_slice(), "width {width}");
                }
            }
        }
        assert_eq!(tile_order(100, None), None);
        assert_eq!(tile_order(100, Some(3)), None);
    }

    /// Rays at the points of a 40 × 40 × 40 grid, given in a shuffled order: the order is a
    /// permutation, the cells it visits follow the Morton curve (each cell's index, from the
    /// grid point by an independent count, never decreases), and rays of one cell keep their
    /// given order.
    #[test]
    fn origin_order_follows_the_cells_of_the_morton_curve() {
        let side = 40;
        let mut points: Vec<[usize; 3]> = (0..side * side * side)
            .map(|i| [i % side, i / side % side, i / (side * side)])
            .collect();
        let mut state = 12345u64;
        for i in (1..points.len()).rev() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            points.swap(i, (state >> 33) as usize % (i + 1));
        }
        let rays: Vec<Ray> = points
            .iter()
            .map(|p| Ray::new(DVec3::from_array(p.map(|c| c as f64)), DVec3::X))
            .collect();
        let order = traced_order(&rays);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..rays.len()).collect::<Vec<_>>());
        // The box is [0, 39] on each axis, 32 cells: point c lies in cell ⌊32c/39⌋ (31 at 39).
        let morton = |p: [usize; 3]| {
            let cell = p.map(|c| (32 * c / 39).min(31));
            let bit = |a: usize, b: usize| ((cell[a] >> b) & 1) << (3 * b + a);
            (0..5)
                .map(|b| bit(0, b) | bit(1, b) | bit(2, b))
                .sum::<usize>()
        };
        for pair in order.windows(2) {
            let (a, b) = (morton(points[pair[0]]), morton(points[pair[1]]));
            assert!(a < b || (a == b && pair[0] < pair[1]), "{pair:?}");
        }
    }

    /// Short lists, a camera's rays (one origin), lists without a finite origin and scenes that
    /// stay in cache keep their order; a NaN or infinite origin among spread ones is placed
    /// without a panic.
    #[test]
    fn origin_order_leaves_what_it_cannot_improve() {
        let ray = |x: f64| Ray::new(DVec3::new(x, 0.0, 0.0), DVec3::Z);
        let short: Vec<Ray> = (0..100).map(|i| ray(i as f64)).collect();
        let all = || Some(usize::MAX);
        assert_eq!(origin_order(&short, all), None);
        let camera: Vec<Ray> = (0..5000).map(|_| ray(1.0)).collect();
        assert_eq!(origin_order(&camera, all), None);
        let lost: Vec<Ray> = (0..5000).map(|_| ray(f64::NAN)).collect();
        assert_eq!(origin_order(&lost, all), None);
        let spread: Vec<Ray> = (0..5000).map(|i| ray(i as f64)).collect();
        assert!(origin_order(&spread, all).is_some());
        let small = || Some(ORIGIN_ORDER_BYTES - 1);
        assert_eq!(
            origin_order(&spread, small),
            None,
            "a scene that stays in cache"
        );
        let unknown = || None;
        assert_eq!(
            origin_order(&spread, unknown),
            None,
            "an unknown scene size"
        );
        let mut mixed: Vec<Ray> = (0..5000).map(|i| ray((5000 - i) as f64)).collect();
        mixed[7] = ray(f64::NAN);
        mixed[8] = ray(f64::INFINITY);
        mixed[9] = ray(f64::NEG_INFINITY);
        let order = traced_order(&mixed);
        assert_eq!(order.len(), 5000);
        // NaN and −∞ fall in the first cell (before every finite x, in their given order), +∞
        // in the last, with the largest finite x.
        assert_eq!(order[..2], [7, 9]);
        let at = |i: usize| order.iter().position(|&k| k == i).unwrap();
        assert!(at(8) > at(1000) && at(0) > at(1000));
    }

    /// Values of one, two and three numbers per ray, given in the traced order, come back in
    /// the rays' own order.
    #[test]
    fn values_go_back_to_their_rays() {
        let rays: Vec<Ray> = (0..5000)
            .map(|i| Ray::new(DVec3::new(((i * 7919) % 5000) as f64, 0.0, 0.0), DVec3::Z))
            .collect();
        let origins = origin_order(&rays, || Some(usize::MAX)).expect("spread origins");
        for stride in [1, 2, 3] {
            let traced: Vec<f64> = origins
                .order
                .iter()
                .flat_map(|&i| (0..stride).map(move |c| (10 * i as usize + c) as f64))
                .collect();
            let own = origins.in_place(&traced, stride);
            let expected: Vec<f64> = (0..5000)
                .flat_map(|i| (0..stride).map(move |c| (10 * i + c) as f64))
                .collect();
            assert_eq!(own, expected, "stride {stride}");
        }
    }
}
