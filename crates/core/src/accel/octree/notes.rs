//! What a packet search may note beside its nearest hits, for the `certain` AOV
//! ([`crate::render::bounds`]): the primitives it offered each ray, and how far beyond its
//! best hit each ray's search went.
//!
//! A decision is certain when no primitive other than the hit may have an exact crossing up
//! to `t + δ` (the hit's bound). Every such primitive is offered to the ray by a search that
//! goes that far: the node culling and the leaf filter only drop what the ray cannot reach
//! within the search's limit (see module `leaf`: boxes grown by the build margin), and the
//! mailbox only drops repeats. So the search keeps each ray's limit a little beyond its best
//! hit so far ([`Notes::reach`]), records what it offers, and the decision then weighs those
//! primitives alone, without a second traversal, whenever `t + δ` lies within the reach.
//! Widening the limit cannot change the nearest hit: a crossing between the best hit and
//! the widened limit is tested and loses to the best.
//!
//! What the packet path tests against several rays at once goes through the set's
//! [`super::PrimitiveSet::intersect_packet_apart`]: a ray whose exact ray certainly misses the
//! primitive (for the scene: a world triangle, exact or within a placement bound the decision
//! weighs, by the edge filter the decision itself applies, `bound::apart`; lone rays too) is
//! not told of it, since it competes with nothing. The same filter also says when the exact
//! ray certainly crosses a hit triangle's interior ([`Notes::inside`]): the hit's bound then
//! need not test it again.

use super::PACKET;

/// What [`super::Octree::intersect_packet_noting`] tells its notes.
pub trait Notes {
    /// Whether there is anything to note (a constant, so that the plain search's loops over
    /// the offered rays compile away).
    const NOTING: bool;

    /// The limit the search keeps for a ray whose best hit so far is at `t`: `t` for a plain
    /// search, a little more (`widen`) where it notes, to see competitors beyond it.
    #[inline(always)]
    fn reach(&self, t: f64) -> f64 {
        if Self::NOTING {
            widen(t)
        } else {
            t
        }
    }

    /// Primitive `prim` was offered to ray `ray` of the packet (it passed the leaf filter,
    /// for the first time along the ray).
    fn offer(&mut self, ray: usize, prim: u32);

    /// Ray `ray`'s exact ray certainly crosses the interior of `prim`, its best hit so far.
    #[inline(always)]
    fn inside(&mut self, _ray: usize, _prim: u32) {}
}

/// The plain search: nothing noted, nothing widened.
pub struct Unnoted;

impl Notes for Unnoted {
    const NOTING: bool = false;

    #[inline(always)]
    fn offer(&mut self, _: usize, _: u32) {}
}

/// Primitives noted per ray: more and the ray's list is marked incomplete (its `certain` then
/// takes a traversal of its own). 24 measured best of 12, 16, 24 and 32 (trace instructions
/// with `error,certain` on the bunny, the helmet and 501 placed cubes; at most
/// [`crate::scene::Scene::apart`]'s 32).
pub const OFFERED: usize = 24;

/// The primitives a search offered one ray, and how far it searched.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Offered {
    prims: [u32; OFFERED],
    /// How many of `prims` hold primitives; `OFFERED + 1` once more were offered than fit.
    len: u8,
    /// The search found every crossing with `0 < t ≤ reach` among the offered primitives.
    pub reach: f64,
    /// A primitive whose interior the exact ray certainly crosses (the last best hit noted so,
    /// [`Notes::inside`]), or [`NO_PRIMITIVE`]: a plain index, so that the notes stay 112
    /// bytes (an `Option` made them 120, and copying them a call to `memcpy`: 3 % of the
    /// bunny's trace with `certain`).
    inside: u32,
}

/// No primitive's index (indices are below the primitive count, itself a `u32`).
const NO_PRIMITIVE: u32 = u32::MAX;

impl Offered {
    /// Nothing offered yet.
    pub const EMPTY: Offered = Offered {
        prims: [0; OFFERED],
        len: 0,
        reach: 0.0,
        inside: NO_PRIMITIVE,
    };

    /// The offered primitives, or `None` when more were offered than fit.
    pub fn prims(&self) -> Option<&[u32]> {
        self.prims.get(..usize::from(self.len))
    }

    /// Whether the search found the exact ray certainly crossing the interior of primitive
    /// `prim` (see [`Notes::inside`]; `false` says nothing).
    pub fn crosses_inside(&self, prim: u32) -> bool {
        prim != NO_PRIMITIVE && self.inside == prim
    }

    /// Notes `prim` (or that the list overflowed).
    #[inline(always)]
    fn note(&mut self, prim: u32) {
        let len = usize::from(self.len);
        if len < OFFERED {
            self.prims[len] = prim;
            self.len += 1;
        } else {
            self.len = OFFERED as u8 + 1;
        }
    }

    /// Sets the reach once the search is done: the widened limit of the best hit `best` (a
    /// ray parameter), or `t_max` for a miss.
    pub fn finish(&mut self, best: Option<f64>, t_max: f64) {
        self.reach = best.map_or(t_max, widen);
    }
}

/// The widened limit of a ray whose best hit is at `t`: a relative `2⁻³⁰` beyond it (far more
/// than the bound of any hit that can be certain: those are a few ulps of `t`, and the
/// decision falls back to its own search beyond the reach); `t` itself when not finite.
#[inline(always)]
fn widen(t: f64) -> f64 {
    (t * (1.0 + 1.0 / f64::from(1u32 << 30))).next_up()
}

/// The notes of one ray's search ([`super::Octree::intersect_ray_noting`]).
impl Notes for Offered {
    const NOTING: bool = true;

    #[inline(always)]
    fn offer(&mut self, _: usize, prim: u32) {
        self.note(prim);
    }

    #[inline(always)]
    fn inside(&mut self, _: usize, prim: u32) {
        self.inside = prim;
    }
}

/// The notes of a packet's search ([`super::Octree::intersect_packet_noting`]): one
/// [`Offered`] per ray.
impl Notes for [Offered; PACKET] {
    const NOTING: bool = true;

    #[inline(always)]
    fn offer(&mut self, ray: usize, prim: u32) {
        self[ray].note(prim);
    }

    #[inline(always)]
    fn inside(&mut self, ray: usize, prim: u32) {
        self[ray].inside = prim;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The list holds what was offered, and says so when it overflows.
    #[test]
    fn offers_fill_then_overflow() {
        let mut notes = [Offered::EMPTY; PACKET];
        for prim in 0..OFFERED as u32 {
            notes.offer(3, prim);
        }
        let all: Vec<u32> = (0..OFFERED as u32).collect();
        assert_eq!(notes[3].prims(), Some(all.as_slice()));
        assert_eq!(notes[2].prims(), Some(&[][..]));
        notes.offer(3, 99);
        assert_eq!(notes[3].prims(), None);
        notes.offer(3, 100);
        assert_eq!(notes[3].prims(), None);
    }

    /// The widened limit is above `t` by about `2⁻³⁰` of it, and stays infinite.
    #[test]
    fn the_reach_is_a_little_beyond() {
        for t in [1e-300, 0.1, 1.0, 3e7, 1e300] {
            let w = widen(t);
            assert!(
                w > t && (w - t) / t < 1e-9 && (w - t) / t > 9e-10,
                "{t} {w}"
            );
        }
        assert_eq!(widen(f64::INFINITY), f64::INFINITY);
    }
}
