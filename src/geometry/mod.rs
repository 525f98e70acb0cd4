//! Geometric building blocks: boxes, rays and the triangle tests.

mod aabb;
mod ray;
pub mod triangle;

pub use aabb::Aabb;
pub use ray::Ray;
