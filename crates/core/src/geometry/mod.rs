//! Geometric building blocks: boxes, rays, the bounds pre-test, the triangle tests (one ray, and a packet's
//! pre-filter) and the triangle/box tests.

mod aabb;
pub mod closest;
mod ray;
mod reach;
pub mod triangle;
pub mod triangle_box;
pub mod triangle_packet;

pub use aabb::Aabb;
pub use ray::{Ray, RaySource};
pub use reach::ReachBox;

/// A triangle in the plane z = 0 around the origin, for the unit tests of [`triangle`] and
/// [`triangle_box`].
#[cfg(test)]
const TEST_TRIANGLE: [glam::DVec3; 3] = [
    glam::DVec3::new(-1.0, -1.0, 0.0),
    glam::DVec3::new(1.0, -1.0, 0.0),
    glam::DVec3::new(0.0, 1.0, 0.0),
];
