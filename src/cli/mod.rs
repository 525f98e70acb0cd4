//! Command-line front ends of the library's commands: argument parsing (clap) and progress
//! bars (indicatif) live here, on the binary side, so the library does not depend on them.

pub mod camera;
pub mod check;
pub mod distance;
pub mod signals;
pub mod slips;
pub mod threads;
