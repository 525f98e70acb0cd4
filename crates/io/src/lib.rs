//! # raycast-io
//!
//! raycast's readers and writers: [`import`] turns glTF, USD, OBJ, PLY and STL files into
//! raycast-core's [`Scene`](raycast_core::scene::Scene); [`output`] writes the traced buffers
//! (EXR, PNG, NPY, NPZ) and their JSON sidecar, atomically (the default feature `output`);
//! [`info`] describes a scene; [`sizes`] reads and prints byte counts.

#![warn(missing_docs)]

pub mod import;
pub mod info;
#[cfg(feature = "output")]
pub mod output;
pub mod sizes;

// The core's modules, for paths such as `crate::scene::Scene` in this crate.
#[cfg(feature = "output")]
use raycast_core::{accel, render, trace};
use raycast_core::{bound, camera, error, geometry, quadric, scene};
