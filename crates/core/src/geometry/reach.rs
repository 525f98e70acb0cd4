//! The bounds pre-test shared by quadrics and instances: a cheap slab test that passes over a
//! primitive's exact test (or an instance's set-up and octree) for rays that cannot reach its
//! bounds, and never for a ray that can.

use super::Aabb;
use crate::simd::Kernel;
use crate::simd::PACKET;
use glam::DVec3;

/// A primitive's world bounds, with what the pre-test's margin needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachBox {
    /// The bounds.
    pub bounds: Aabb,
    centre: DVec3,
    extent: f64,
}

impl ReachBox {
    /// The pre-test for `bounds` (finite, `min <= max`).
    pub fn new(bounds: Aabb) -> ReachBox {
        ReachBox {
            bounds,
            centre: bounds.center(),
            extent: bounds.size().max_element(),
        }
    }

    /// False only when `origin + t·dir` for `0 <= t <= t_max` stays outside the box grown by
    /// `1e-9 · (box size + the origin's distance from the box centre)`; `inv_dir` is
    /// `dir.recip()`. Every hit of the primitive lies inside the box (up to the rounding the
    /// box is padded for), and the margin is some six orders of magnitude above the rounding
    /// of the slab parameters, so no hit is ever passed over. On an axis with `dir = 0` the
    /// parameters are infinite, of opposite signs when the origin lies inside the slab and of
    /// the same sign when outside. `0 · ∞`, NaN, arises only for an origin exactly on a grown
    /// face with `dir = 0` on that axis: the ray then stays outside the box, so either answer
    /// is right.
    #[inline]
    pub fn may_reach(&self, origin: DVec3, inv_dir: DVec3, t_max: f64) -> bool {
        // Plain comparisons (`f64::max` spends instructions on NaN rules): a NaN candidate
        // compares false and is passed over, as in `f64::max`; no other operand is NaN.
        let larger = |a: f64, b: f64| if b > a { b } else { a };
        let smaller = |a: f64, b: f64| if b < a { b } else { a };
        let offset = (origin - self.centre).abs();
        let margin = 1e-9 * (self.extent + larger(larger(offset.x, offset.y), offset.z));
        let a = (self.bounds.min - DVec3::splat(margin) - origin) * inv_dir;
        let b = (self.bounds.max + DVec3::splat(margin) - origin) * inv_dir;
        let (near, far) = (a.min(b), a.max(b));
        let enter = larger(larger(larger(0.0, near.x), near.y), near.z);
        let exit = smaller(smaller(smaller(t_max, far.x), far.y), far.z);
        enter <= exit
    }

    /// [`ReachBox::may_reach`] for the rays `active` (bit `i` for ray `i`) of a packet, ray `i`
    /// given by `rays(i)` as (origin, direction): the mask of those it lets through, by
    /// `kernel`. Every ray is tested, without branches, so that the loop compiles to
    /// straight-line code.
    #[inline]
    pub fn reaching(
        &self,
        kernel: Kernel,
        rays: impl Fn(usize) -> (DVec3, DVec3),
        active: u32,
        t_max: &[f64; PACKET],
    ) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if kernel == Kernel::Avx2 {
            // SAFETY: the Avx2 kernel is only chosen where the CPU has AVX2 (and FMA).
            return unsafe { self.reaching_avx2(rays, active, t_max) };
        }
        self.reaching_with(rays, active, t_max)
    }

    /// [`ReachBox::reaching`] compiled for AVX2 (the same operations, in wider registers).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn reaching_avx2(
        &self,
        rays: impl Fn(usize) -> (DVec3, DVec3),
        active: u32,
        t_max: &[f64; PACKET],
    ) -> u32 {
        self.reaching_with(rays, active, t_max)
    }

    /// [`ReachBox::reaching`]'s loop.
    #[inline(always)]
    fn reaching_with(
        &self,
        rays: impl Fn(usize) -> (DVec3, DVec3),
        active: u32,
        t_max: &[f64; PACKET],
    ) -> u32 {
        let mut mask = 0;
        for (i, &t_max) in t_max.iter().enumerate() {
            let (origin, dir) = rays(i);
            mask |= u32::from(self.may_reach(origin, dir.recip(), t_max)) << i;
        }
        mask & active
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    /// The pre-test against answers from the geometry: a ray aimed at a random point of the
    /// box passes with `t_max` at that point; a ray beside the box parallel to its x faces, one
    /// pointing away from it, and one stopping short of it are refused (the margins are far
    /// below the distances involved); and the packet form agrees with the single-ray form lane
    /// by lane. Boxes from 1e-4 to 1e4 in size, up to 1e7 away from the origin.
    #[test]
    fn lets_rays_at_the_box_through_and_refuses_the_others() {
        let mut rng = Rng(0x5eed_b0c5);
        for round in 0..2000 {
            let scale = 10f64.powi(round % 9 - 4);
            let centre = rng.point(-1e3, 1e3) * scale;
            let half = (rng.point(0.0, 1.0) + DVec3::splat(1e-3)) * scale;
            let reach = ReachBox::new(Aabb::new(centre - half, centre + half));
            let target = centre + half * rng.point(-1.0, 1.0);
            let origin = target + rng.point(-10.0, 10.0) * scale;
            let dir = target - origin;
            assert!(reach.may_reach(origin, dir.recip(), 1.0), "round {round}");
            let beside = DVec3::new(centre.x + 1.5 * half.x, origin.y, origin.z);
            let along = DVec3::new(0.0, dir.y, dir.z);
            assert!(
                !reach.may_reach(beside, along.recip(), 1.0),
                "round {round}"
            );
            assert!(!reach.may_reach(beside, DVec3::X.recip(), f64::INFINITY));
            let before = centre - DVec3::X * 5.0 * half.x;
            let step = DVec3::X * half.x;
            assert!(!reach.may_reach(before, step.recip(), 3.0), "round {round}");
            assert!(reach.may_reach(before, step.recip(), 5.0), "round {round}");
            let rays: [(DVec3, DVec3); PACKET] = std::array::from_fn(|i| match i % 3 {
                0 => (origin, dir),
                1 => (beside, along),
                _ => (before, step),
            });
            let limits = std::array::from_fn(|i| [1.0, 3.0, 5.0][i % 3]);
            let expected = (0..PACKET).fold(0, |m, i| {
                m | u32::from(reach.may_reach(rays[i].0, rays[i].1.recip(), limits[i])) << i
            });
            assert_eq!(expected, 0b0110_1101, "round {round}");
            for kernel in [Kernel::Avx2, Kernel::Portable]
                .into_iter()
                .filter(|k| k.available())
            {
                assert_eq!(reach.reaching(kernel, |i| rays[i], 0xff, &limits), expected);
                assert_eq!(
                    reach.reaching(kernel, |i| rays[i], 0b1010_0101, &limits),
                    expected & 0b1010_0101
                );
            }
        }
    }
}
