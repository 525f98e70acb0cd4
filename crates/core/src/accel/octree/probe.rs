//! The octree queries of the `certain` AOV ([`crate::render`]): whether any primitive the
//! leaf filter lets through along a ray (or each ray of a packet) passes the caller's test, up
//! to a limit. The nearest-hit search's own notes ([`super::notes`]) decide most rays without
//! them.

use super::lanes::Lanes;
use super::traverse::{self, Unobserved};
use super::{leaf, packet, Mailbox, Octree, PacketMailbox, PACKET};
use crate::accel::{f32_above, set_bits};
use glam::DVec3;

impl Octree {
    /// Whether `visit` returns true for some primitive the ray `origin + t · dir` may meet with
    /// `0 <= t <= t_max`: the leaves it may reach front to back ([`Octree::traverse`]), each
    /// leaf's references first passed through the leaf filter (module `leaf`: a reference is
    /// dropped only when the ray meets its box, which holds its primitive's part in the leaf
    /// grown by the build margin, nowhere in that range). Stops at the first true; a
    /// primitive kept in several leaves is visited once (the search's `Mailbox`).
    pub fn any_reference(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_max: f64,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        let lanes = Lanes::new(origin, dir + DVec3::ZERO, self.scale);
        let bound = f32_above(t_max);
        let mut found = false;
        let mut visited = Mailbox::default();
        let leaf = |child, _, _| {
            let prims = self.layout.leaf(child);
            for first in (0..prims.len()).step_by(8) {
                let kept = leaf::chunk_mask(&self.layout, self.kernel, child, first, &lanes, bound);
                let prims = set_bits(kept).map(|j| prims[first + j]);
                if prims.filter(|&p| visited.check_in(p)).any(&mut visit) {
                    found = true;
                    return f64::NEG_INFINITY;
                }
            }
            t_max
        };
        traverse::run(
            &self.layout,
            self.kernel,
            &lanes,
            t_max,
            leaf,
            &mut Unobserved,
        );
        found
    }

    /// [`Octree::any_reference`] for [`PACKET`] rays at once, traversing the octree together
    /// (module `packet`, the same leaves and leaf filter as each ray alone): bit `i` of the
    /// result is set when `visit(i, prim)` returns true for some primitive ray `i` may meet
    /// with `0 <= t <= t_max[i]`; a ray stops at its first true, and a ray with a `t_max` of
    /// `-∞` takes no part. Each primitive is offered to a ray once (the packet's mailbox).
    /// `None` when the rays cannot go as one packet (see [`Octree::intersect_packet`]).
    pub fn any_reference_packet(
        &self,
        origins: &[DVec3; PACKET],
        dirs: &[DVec3; PACKET],
        t_max: &[f64; PACKET],
        mut visit: impl FnMut(usize, u32) -> bool,
    ) -> Option<u32> {
        let mut found = 0u32;
        let mut offered = PacketMailbox::default();
        let packed = packet::run(
            &self.layout,
            self.kernel,
            origins,
            dirs,
            self.scale,
            *t_max,
            |_, refs, reach, limits| {
                for (&prim, &rays) in refs.iter().zip(reach) {
                    for i in set_bits(offered.check_in(prim, rays & !found)) {
                        if visit(i, prim) {
                            found |= 1 << i;
                            limits[i] = f64::NEG_INFINITY;
                        }
                    }
                }
            },
        );
        packed.then_some(found)
    }
}
