//! Geometric building blocks: boxes, rays, the triangle tests and the triangle/box tests.

mod aabb;
mod ray;
pub mod triangle;
pub mod triangle_box;

pub use aabb::Aabb;
pub use ray::Ray;
