//! # raycast
//!
//! An exact ray caster for glTF, USD (`.usda`, `.usdc`, `.usd`, `.usdz`), OBJ, PLY and STL
//! scenes that mix triangle meshes with analytic quadric surfaces. The pipeline: [`import`] a
//! file into a [`scene::Scene`] (world-space triangles, quadrics, an object table and
//! cameras), build an [`accel::Octree`] over all primitives, trace rays from a
//! [`camera::Camera`] or a ray file with [`render`], and write depth, normal, position and id
//! buffers with [`output`].
//!
//! This crate is the `raycast` command line and the jobs it runs ([`job`]); it re-exports the
//! layers below it, each a crate of its own (docs/architecture.md): [`raycast_core`] (geometry,
//! quadrics, the octree, scenes, cameras, tracing), [`raycast_io`] (readers and writers) and
//! [`raycast_check`] (`raycast check`).

#![warn(missing_docs)]

pub use raycast_check as check;
pub use raycast_core::{accel, bound, camera, error, geometry, quadric, render, scene, trace};
pub use raycast_core::{Error, Result};
pub use raycast_io::{import, info, output, sizes};

pub mod job;
