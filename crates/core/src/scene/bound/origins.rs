//! Mapped ray origins kept across the hits of a block ([`Origins`]).

use crate::bound::bounded::BVec3;
use glam::DVec3;

/// Slots of an [`Origins`] cache (a power of two).
const SLOTS: usize = 16;

/// The mapped origins of a block's recent quadric hits, by top-level primitive: the rays of a
/// camera share their origin, and mapping it into a quadric's frame with its bound
/// ([`crate::scene::Scene::hit_bound`], [`crate::quadric::Quadric::bounded_origin`]) is a
/// large part of such a hit's bound. (An instance's mapping costs less than keeping it: not
/// kept.) Direct-mapped by primitive; an origin is matched by its bits, so a hit gets exactly
/// the bound it gets without the cache.
#[derive(Debug, Default)]
pub struct Origins {
    slots: [Option<(u32, [u64; 3], BVec3)>; SLOTS],
}

impl Origins {
    /// The mapped `origin` of top-level primitive `top`, made by `map` unless kept.
    pub fn get(&mut self, top: u32, origin: DVec3, map: impl FnOnce() -> BVec3) -> BVec3 {
        let bits = origin.to_array().map(f64::to_bits);
        let slot = &mut self.slots[top as usize % SLOTS];
        match slot {
            Some((kept, at, mapped)) if *kept == top && *at == bits => *mapped,
            _ => {
                let mapped = map();
                *slot = Some((top, bits, mapped));
                mapped
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bound::bounded::exact3;

    /// A kept origin is returned only for the same primitive and the same bits (not for
    /// `-0.0` where `0.0` was kept, nor for another primitive in the same slot).
    #[test]
    fn kept_only_for_the_same_primitive_and_bits() {
        let mut origins = Origins::default();
        let (one, two) = (exact3(DVec3::ONE), exact3(DVec3::splat(2.0)));
        assert_eq!(origins.get(3, DVec3::ZERO, || one), one);
        assert_eq!(origins.get(3, DVec3::ZERO, || two), one);
        assert_eq!(origins.get(3, DVec3::new(-0.0, 0.0, 0.0), || two), two);
        assert_eq!(origins.get(3 + SLOTS as u32, DVec3::ZERO, || one), one);
        assert_eq!(origins.get(3, DVec3::ZERO, || two), two);
    }
}
