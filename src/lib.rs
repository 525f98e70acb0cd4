//! # raycast
//!
//! An exact ray caster for glTF, USD (`.usda`, `.usdc`, `.usd`, `.usdz`) and OBJ scenes that
//! mix triangle meshes with analytic quadric surfaces. The pipeline: [`import`] a file into a [`scene::Scene`] (world-space triangles,
//! quadrics, an object table and cameras), build an [`accel::Octree`] over all primitives,
//! trace rays from a [`camera::Camera`] or a ray file with [`render`], and write depth,
//! normal, position and id buffers with [`output`].

pub mod accel;
pub mod bound;
pub mod camera;
pub mod check;
pub mod error;
pub mod geometry;
pub mod import;
pub mod quadric;
pub mod scene;

pub use error::{Error, Result};
pub mod info;
pub mod job;
pub mod output;
pub mod query;
pub mod render;
#[cfg(test)]
mod test_rng;
