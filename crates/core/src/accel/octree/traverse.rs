//! The stack traversal over eight-wide nodes.

use super::lanes::{self, Kernel, Lanes};
use super::layout::Layout;
use super::wide::{Wide, LEAF};
use super::DEPTH_CAP;
use crate::accel::f32_above;
use std::mem::MaybeUninit;

/// `ORDER[octant][hit]`: `hit` (bit `i` for lane `i`) with bit `j` moved to where lane
/// `j ^ octant` is, so that bit `j` of the result is the `j`-th child along the ray.
static ORDER: [[u8; 256]; 8] = {
    let mut order = [[0; 256]; 8];
    let mut octant = 0;
    while octant < 8 {
        let mut hit = 0;
        while hit < 256 {
            let mut j = 0;
            while j < 8 {
                if hit & (1 << (j ^ octant)) != 0 {
                    order[octant][hit] |= 1 << j;
                }
                j += 1;
            }
            hit += 1;
        }
        octant += 1;
    }
    order
};

/// At most eight entries wait per level, with a level to spare (a power of two, so
/// that masking the index keeps it in bounds without a check).
pub(super) const STACK: usize = (8 * (DEPTH_CAP as usize + 2)).next_power_of_two();

/// What a traversal reports besides leaves: used by the culling audit in tests.
pub(super) trait Observer {
    /// Node `node` was tested with the limit `t_best` (f32, rounded up) and `hit` lanes.
    fn tested(&mut self, node: usize, hit: u32, t_best: f32);
}

/// The observer of a normal traversal.
pub(super) struct Unobserved;

impl Observer for Unobserved {
    #[inline(always)]
    fn tested(&mut self, _: usize, _: u32, _: f32) {}
}

/// Visits the leaves the ray may reach before `limit`, front to back; see
/// [`super::Octree::traverse`].
pub(super) fn run<F, O>(
    layout: &Layout,
    kernel: Kernel,
    ray: &Lanes,
    limit: f64,
    visit: F,
    observer: &mut O,
) where
    F: FnMut(u32, f64, f64) -> f64,
    O: Observer,
{
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `Kernel::Avx2` is only chosen where `Kernel::available` said so.
        Kernel::Avx2 => unsafe { run_avx2(layout, ray, limit, visit, observer) },
        _ => run_with::<false, F, O>(layout, ray, limit, visit, observer),
    }
}

/// [`run_with`] compiled for AVX2 and FMA, so that the node test inlines.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_avx2<F, O>(layout: &Layout, ray: &Lanes, limit: f64, visit: F, observer: &mut O)
where
    F: FnMut(u32, f64, f64) -> f64,
    O: Observer,
{
    run_with::<true, F, O>(layout, ray, limit, visit, observer)
}

/// The traversal: test a node's eight lanes, push the hit children far to near with their
/// entry parameters, pop the nearest. A popped entry is skipped only when it is entered beyond
/// the best hit so far (the boundary trap rule); a leaf goes to `visit` (as its child
/// reference), which returns the new limit.
#[inline(always)]
fn run_with<const AVX2: bool, F, O>(
    layout: &Layout,
    ray: &Lanes,
    limit: f64,
    visit: F,
    observer: &mut O,
) where
    F: FnMut(u32, f64, f64) -> f64,
    O: Observer,
{
    if !layout.nodes.is_empty() {
        from_node::<AVX2, F, O>(layout, 0, ray, limit, visit, observer);
    }
}

/// [`run_with`] from node `start` on (and below it only).
#[inline(always)]
pub(super) fn from_node<const AVX2: bool, F, O>(
    layout: &Layout,
    start: usize,
    ray: &Lanes,
    mut limit: f64,
    mut visit: F,
    observer: &mut O,
) where
    F: FnMut(u32, f64, f64) -> f64,
    O: Observer,
{
    let mut node = start;
    let mut t_best = f32_above(limit);
    // Uninitialised: only entries below `top`, each written before, are read.
    let mut stack = [MaybeUninit::<(u32, f32, f32)>::uninit(); STACK];
    let mut top = 0;
    loop {
        let wide: &Wide = &layout.nodes[node];
        let tested = if AVX2 {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: only reached through `run_avx2`.
            unsafe {
                lanes::test_avx2(wide, ray, t_best)
            }
            #[cfg(not(target_arch = "x86_64"))]
            unreachable!()
        } else {
            lanes::test_portable(wide, ray, t_best)
        };
        let hit = if ray.open {
            wide.occupancy()
        } else {
            tested.hit
        };
        observer.tested(node, hit, t_best);
        // Far to near, so the nearest child is popped first; or rather taken at once (a cell
        // entered, a leaf visited): it was just found entered before `t_best`, all its pop
        // would check.
        let mut order = u32::from(ORDER[ray.octant & 7][hit as usize & 0xFF]);
        let lane = |order: u32| ((31 - order.leading_zeros() as usize) ^ ray.octant) & 7;
        while order.count_ones() > 1 {
            let far = lane(order);
            order &= !(1 << (31 - order.leading_zeros()));
            stack[top & (STACK - 1)].write((
                wide.children[far],
                tested.enter[far],
                tested.exit[far],
            ));
            top += 1;
        }
        if order != 0 {
            let near = lane(order);
            let child = wide.children[near];
            if child & LEAF == 0 {
                node = child as usize;
                continue;
            }
            let (enter, exit) = (tested.enter[near], tested.exit[near]);
            limit = limit.min(visit(child, f64::from(enter), f64::from(exit)));
            t_best = f32_above(limit);
        }
        loop {
            if top == 0 {
                return;
            }
            top -= 1;
            // SAFETY: entry `top` was written by the push that raised `top` above it.
            let (child, enter, exit) = unsafe { stack[top & (STACK - 1)].assume_init() };
            if enter > t_best {
                continue;
            }
            if child & LEAF == 0 {
                node = child as usize;
                break;
            }
            limit = limit.min(visit(child, f64::from(enter), f64::from(exit)));
            t_best = f32_above(limit);
        }
    }
}
