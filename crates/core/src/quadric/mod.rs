//! Analytic quadric surfaces `p·Q·p + P·p + R = 0`: parsing from scene files, placement in
//! world space about a local anchor, classification, bounds, ray intersection and nearest
//! points ([`Quadric::closest`]) in f64, and the side of a closed one ([`Quadric::inside`]).
//!
//! The module depends only on `glam`, `twofloat` and, for the error bound of a
//! crossing ([`Quadric::bound_roots`]), on [`crate::bound`]'s bounded arithmetic.

mod eigen;
mod interval;
mod kind;
mod polynomial;
#[cfg(test)]
mod regression_tests;
pub mod spec;
mod surface;
#[cfg(test)]
mod tests;

pub use kind::QuadricKind;
pub use spec::QuadricSpec;
pub use surface::{Others, Quadric, QuadricBound, QuadricClosest, RootBound};
