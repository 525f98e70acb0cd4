//! Certified error bounds per ray: the `error` and `certain` AOVs.
//!
//! # What `error` bounds
//! For a hit, `δ ≥ 0` with `|depth − depth*| ≤ δ`, where `depth` is the f64 depth written
//! (`t·|d|`) and `depth* = t*·|d|` is the exact depth of the ray (its f64 origin and direction
//! as exact numbers) with the same primitive's exact surface: the triangle's plane (vertices as
//! stored, instance meshes placed by their f64 matrix, world meshes with the rounding of their
//! f64 placement bounded, see [`placement_error`]), or the quadric's nearest root (its file
//! coefficients and clip box placed by its node matrix); a glTF node matrix is the exact
//! product of the transforms above it (a translation/rotation/scale node's matrix that of its
//! exactly normalized quaternion), the f64 normalization's, multiplying out's and
//! composition's rounding carried in [`transform::BoundedMat4`]. When `certain` is 1, that crossing
//! is the exact nearest hit. It is a forward error analysis: a triangle hit's `t` by the
//! residual of the exact plane at the reported point ([`residual`]: `|t − t*| = |R*|/|D*|`,
//! both evaluated with Higham's `γₙ` and moved by the vertices' and the ray's bounds), or where
//! its standard model does not apply, and for the hit's own decision, the watertight test
//! recomputed in [`bounded::Bounded`] (value plus bound, each operation's exact rounding:
//! [`triangle`]); a quadric's roots by [`crate::quadric::Quadric::bound_roots`]. `+∞` where no
//! bound can be made (a ray in a triangle's plane); `0` for a miss.
//!
//! # What `certain` means
//! 1 when no exact values within the bounds can change the ray's decision: the hit primitive's
//! exact crossing lies strictly inside it (every edge function, or the clip box test, has a
//! certain sign), is certainly in front of the origin and isolated (no tangent), and no other
//! primitive's bounded crossing may lie in `(0, t + δ_t]`; for a miss, no primitive's bounded
//! crossing may lie anywhere along the ray. The candidates are those of the octree's leaves
//! along the ray up to `t + δ_t`: what the nearest-hit search offered the ray (it looks a
//! little beyond its best hit when this AOV is asked, module `accel::octree::notes`), or else
//! a separate traversal; the cells are grown by 1e-9 of the root, so a primitive whose stored
//! geometry or mapped ray may be off by more than 1e-10 of its octree's root counts as a
//! possible crossing. A ray that was not traced is not certain.
//!
//! USD transform ops are bounded against the exact composition of the op values as read
//! (rotations in degrees: [`rotation`]). Not covered (the bound takes them as exact): the
//! rounding of an animation's interpolated translation, rotation and scale, of decimal numbers
//! read into f64, of a rigidly skinned USD prim's joint transform, of posed (skinned, morphed)
//! vertices, and of the camera's ray generation (the ray traced is the one bounded); an
//! inverted USD op other than a translation and point instances moved by velocities get `+∞`.

pub mod apart;
pub mod bounded;
pub mod residual;
pub mod rotation;
pub mod transform;
pub mod triangle;

use bounded::{gamma, up, Bounded};
use glam::{DMat3, DVec3};
use std::ops::{Add, Mul, Sub};

/// Where an exact crossing lies against a primitive's boundary (a triangle's edges or a
/// quadric's clip box).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Certainly inside.
    Inside,
    /// Certainly outside.
    Outside,
    /// Within the bounds of the boundary.
    Edge,
}

/// Stored geometry or mapped rays off by more than this fraction of their octree's root may
/// lie in cells the traversal does not visit (cells are grown by 1e-9 of the root).
pub const CELL_SLACK: f64 = 1e-10;

/// A bound on `‖A⁻¹‖∞` from the computed inverse `inverse` of `a`: with `E = I − inverse·A`
/// evaluated in bounded arithmetic and `η = ‖E‖∞ < 1`, `A⁻¹ = (I − E)⁻¹·inverse`, so
/// `‖A⁻¹‖∞ ≤ ‖inverse‖∞ / (1 − η)`. `+∞` when `η ≥ 1`.
pub fn inverse_norm(a: DMat3, inverse: DMat3) -> f64 {
    let l = inverse.transpose().to_cols_array_2d();
    let a_cols = a.to_cols_array_2d();
    let mut eta: f64 = 0.0;
    let mut norm: f64 = 0.0;
    for (i, row) in l.iter().enumerate() {
        let mut residual_row = 0.0;
        for (j, col) in a_cols.iter().enumerate() {
            let exact = |k: usize| Bounded::exact(row[k]).mul(Bounded::exact(col[k]));
            let product = exact(0).add(exact(1)).add(exact(2));
            let identity = Bounded::exact(if i == j { 1.0 } else { 0.0 });
            residual_row += identity.sub(product).magnitude();
        }
        eta = eta.max(up(residual_row));
        norm = norm.max(up(row.iter().map(|x| x.abs()).sum()));
    }
    if eta >= 1.0 {
        return f64::INFINITY;
    }
    up(norm / bounded::down(1.0 - eta))
}

/// The computed `x = inverse · y` (the f64 values the tracer uses) as a bounded image of the
/// exact `A*⁻¹y*`, `y*` within `y`'s bounds and `A*` within `a_error` (entrywise) of `a`: with
/// the residual `r = y − A·x` evaluated in bounded arithmetic, `A*(A*⁻¹y* − x) = (y* − y) + r
/// − (A* − A)x`, so every component is within `‖A*⁻¹‖∞ · (max eᵧ + max |r| + max (a_error·|x|))`
/// (`inverse_norm` bounds `‖A*⁻¹‖∞`: [`inverse_norm`], widened by
/// [`transform::perturbed_inverse_norm`] when `a_error` is not zero).
#[inline(always)]
pub fn mapped(
    a: DMat3,
    a_error: &DMat3,
    inverse_norm: f64,
    y: &bounded::BVec3,
    x: DVec3,
) -> bounded::BVec3 {
    let ax = bounded::mat_vec(&bounded::rows3(a, 0.0), &bounded::exact3(x));
    let off = |i: usize| Bounded::exact(y[i].value).sub(ax[i]).magnitude();
    let residual = 0.0f64.max(off(0)).max(off(1)).max(off(2));
    let y_error = y.iter().map(|c| c.error).fold(0.0, f64::max);
    let mut spread = up(residual + y_error);
    if *a_error != DMat3::ZERO {
        spread = up(spread + up((*a_error * x.abs()).max_element()));
    }
    let error = up(inverse_norm * spread);
    bounded::within3(x, error)
}

/// A bound on each coordinate's error when `points` are placed by the f64 affine matrix
/// `world.value` (`transform_point3`: three products and three sums per coordinate, `γ₄` of
/// the sum of magnitudes), plus what the exactly composed matrix may place them elsewhere
/// ([`transform::moved`]); zero for an exact identity, `+∞` for a projective matrix.
pub fn placement_error(world: &transform::BoundedMat4, points: impl Iterator<Item = DVec3>) -> f64 {
    let exact = world.is_exact();
    if world.value == glam::DMat4::IDENTITY && exact {
        return 0.0;
    }
    if world.value.row(3) != glam::DVec4::W || world.error.row(3) != glam::DVec4::ZERO {
        return f64::INFINITY;
    }
    let linear = DMat3::from_mat4(world.value).abs();
    let translation = world.value.w_axis.truncate().abs();
    let (rounding, composed) = points.fold((0.0, 0.0), |(r, c): (f64, f64), p| {
        let rounding = (linear * p.abs() + translation).max_element();
        let composed = if exact {
            0.0
        } else {
            transform::moved(&world.error, p)
        };
        (r.max(rounding), c.max(composed))
    });
    let rounded = up(gamma(4) * up(rounding));
    if exact {
        rounded
    } else {
        up(rounded + composed)
    }
}

/// The bound of a hit: its `t` with a bound on the distance to the same primitive's exact
/// crossing, and whether the primitive's own decision is certain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HitBound {
    /// The hit's `t`, reported, and its bound.
    pub t: Bounded,
    /// The exact crossing is inside the primitive, in front of the origin and isolated, and
    /// the primitive has no other exact crossing nearer than `t + δ`.
    pub certain: bool,
}
