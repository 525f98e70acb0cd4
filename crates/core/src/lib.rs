//! # raycast-core
//!
//! The layer of raycast that knows no file format: exact ray-triangle and ray-quadric
//! [`geometry`] and [`quadric`]s, rounding [`bound`]s, the [`accel::Octree`] over both kinds of
//! primitive, the world-space [`scene::Scene`] it is built over, [`camera`]s, the one
//! [`trace::Tracer`] with every ray and point query, and the buffers [`render`] fills. It depends on glam, rayon, serde and a few
//! numeric crates only; the readers and writers are raycast-io's.

#![warn(missing_docs)]

pub mod accel;
pub mod bound;
pub mod camera;
pub mod diagnostic;
pub mod error;
pub mod geometry;
pub mod quadric;
pub mod render;
pub mod scene;
pub mod simd;
pub mod trace;

pub use error::{Error, Result};
#[cfg(test)]
mod test_rng;
