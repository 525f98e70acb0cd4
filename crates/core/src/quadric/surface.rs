//! A quadric placed in world space: intersection, normals, bounds and classification.

use crate::error::{Error, Result};
use crate::geometry::{Aabb, ReachBox};
use glam::{DMat3, DMat4, DVec3, DVec4};

use super::eigen::is_definite;
use super::interval::value_range_may_contain_zero;
use super::kind::{classify, QuadricKind};
use super::polynomial::{power_of_two_normaliser, Polynomial};
use super::spec::QuadricSpec;

mod bound;
mod closest;
mod side;

pub use bound::{Others, QuadricBound, RootBound};
pub use closest::QuadricClosest;

/// World matrices whose determinant is below this fraction of the cube of the longest column
/// count as singular (a condition number of about 1e14 or worse).
const SINGULAR_DETERMINANT: f64 = 1e-14;

/// Relative padding that keeps the world bounds conservative under rounding.
const BOUNDS_PADDING: f64 = 1e-12;

/// The clip box grows by this fraction of its largest side, so that a surface lying on a box
/// face (a cylinder of radius 1 clipped to `[-1, 1]³`) is not lost to rounding of the hit point.
const CLIP_TOLERANCE: f64 = 1e-9;

/// A quadric placed in world space, ready to intersect.
///
/// Both forms are kept about an anchor point `c` (the world image of the clip-box centre, or of
/// the ellipsoid centre when there is no clip box), which keeps the precision of the local
/// description however far from the world origin the surface is placed:
/// - the world form `f(w) = u·Q'·u + P'·u + R'` with `u = w − c` (`Q' = A⁻ᵀQA⁻¹`), used for the
///   classification, the bounds and the cell overlap test;
/// - the local form about the local anchor, used for intersection: the ray is moved into the
///   node's frame (`x0 = A⁻¹(o − c)`, `v = A⁻¹d`, same `t`). Computing `K = v·Q·v` there keeps
///   its relative accuracy when the ray runs nearly along a direction in which the surface is
///   flat (a cylinder's axis, a cone's generator): in the world form `K = d·Q'·d` carries an
///   absolute error of about `u·|Q'|·|d|²` and loses such rays.
#[derive(Clone, Debug, PartialEq)]
pub struct Quadric {
    /// World anchor `c` that `u = w − c` is measured from.
    anchor: DVec3,
    /// The world form about the anchor.
    world: Polynomial,
    /// The local form about the local anchor.
    local: Polynomial,
    /// The world→local linear map `A⁻¹`: `local = A⁻¹ u + local_anchor`.
    to_local: DMat3,
    /// The local→world linear map `A`.
    to_world: DMat3,
    /// The anchor in local coordinates.
    local_anchor: DVec3,
    /// Clip box in local coordinates, widened by [`CLIP_TOLERANCE`].
    clip: Option<[DVec3; 2]>,
    /// Clip box in local coordinates as stated (for [`Quadric::closest`]).
    stated_clip: Option<[DVec3; 2]>,
    /// Conservative world AABB of the clipped surface, for the bounds pre-test.
    reach: ReachBox,
    /// The same bounds from the clip box as given, not widened ([`Quadric::own_bounds`]).
    own: [DVec3; 2],
    /// Affine type, from the world-space coefficients.
    kind: QuadricKind,
    /// Error bounds of the numbers above, for [`Quadric::bound_roots`], made on first use.
    errors: bound::LazyErrors,
}

impl Quadric {
    /// What one ray/quadric test costs, in units of one triangle test, for a ray that reaches
    /// the quadric's bounds: the weight of a quadric reference in the octree's split rule
    /// ([`crate::accel::PrimitiveSet::cost`]). Measured with callgrind: a second unit sphere
    /// in a one-leaf scene adds 585 instructions per ray to rays through its bounds, a second
    /// triangle 194 (reports/octree_profile.md).
    pub const TEST_COST: f64 = 3.0;

    /// Places `spec` in world space with the object→world affine matrix `world`.
    /// Errors: an invalid spec (see [`QuadricSpec::validate`], which includes an unbounded
    /// surface without bounds), a non-finite, non-affine or singular `world`.
    pub fn new(spec: &QuadricSpec, world: DMat4) -> Result<Quadric> {
        spec.validate()?;
        let linear = affine_linear_part(world)?;
        let to_local = linear.inverse();
        let local_anchor = match spec.bounds {
            Some([min, max]) => (min + max) * 0.5,
            None => ellipsoid_centre(spec.q, spec.p),
        };
        let gradient = 2.0 * (spec.q * local_anchor) + spec.p;
        let q_world = to_local.transpose() * spec.q * to_local;
        let q_world = (q_world + q_world.transpose()) * 0.5;
        let p_world = to_local.transpose() * gradient;
        let r_world = local_anchor.dot(spec.q * local_anchor) + spec.p.dot(local_anchor) + spec.r;
        let anchor = world.transform_point3(local_anchor);
        let scale = power_of_two_normaliser(spec.q, gradient);
        let exact = crate::bound::transform::BoundedMat4::exact(world);
        let errors = bound::LazyErrors::new(spec, exact, scale);
        let mut quadric = Quadric {
            anchor,
            world: Polynomial::new(q_world, p_world, r_world),
            local: Polynomial::new(spec.q, gradient, r_world),
            to_local,
            to_world: linear,
            local_anchor,
            clip: spec.bounds.map(widen_clip_box),
            stated_clip: spec.bounds,
            reach: ReachBox::new(Aabb::new(anchor, anchor)),
            own: [anchor, anchor],
            kind: QuadricKind::Empty,
            errors,
        };
        let definite = is_definite(spec.q).then_some(linear);
        let clip_world = quadric
            .clip
            .map(|b| quadric.world_box_of_local_box(b, linear));
        let [min, max] = quadric.clipped_bounds(clip_world, definite, pad);
        quadric.reach = ReachBox::new(Aabb::new(min, max));
        let own_clip = spec
            .bounds
            .map(|b| quadric.world_box_of_local_box(b, linear));
        quadric.own = quadric.clipped_bounds(own_clip, definite, |b| b);
        let length = clip_world.map_or(0.0, |[min, max]| 0.5 * (max - min).length());
        quadric.kind = classify(quadric.world.q, quadric.world.p, quadric.world.r, length);
        Ok(quadric)
    }

    /// Conservative world-space AABB `[min, max]` of the clipped surface; tight (to rounding)
    /// for an unclipped ellipsoid. Always finite; a single point for an empty surface.
    pub fn bounds(&self) -> [DVec3; 2] {
        [self.reach.bounds.min, self.reach.bounds.max]
    }

    /// World AABB `[min, max]` of the clipped surface as the scene gives it: as
    /// [`Quadric::bounds`] but from the clip box not widened by the rounding tolerance of the
    /// hit test (what `raycast info` prints).
    pub fn own_bounds(&self) -> [DVec3; 2] {
        self.own
    }

    /// The world anchor point the coefficients are expressed about.
    pub fn anchor(&self) -> DVec3 {
        self.anchor
    }

    /// Smallest `t` with `0 < t <= t_max` where `origin + t·dir` lies on the surface inside the
    /// clip box. `origin` and `dir` are in world coordinates; `dir` need not be unit length.
    ///
    /// Rays that miss [`Quadric::bounds`] are rejected by a slab test before the exact test,
    /// with the same answer (see `Quadric::may_reach_bounds`).
    pub fn intersect(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<f64> {
        if !self.may_reach_bounds(origin, dir.recip(), t_max) {
            return None;
        }
        self.intersect_exact(origin, dir, t_max)
    }

    /// The bounds pre-test ([`ReachBox::may_reach`]); `inv_dir` is `dir.recip()`.
    #[inline]
    pub(super) fn may_reach_bounds(&self, origin: DVec3, inv_dir: DVec3, t_max: f64) -> bool {
        self.reach.may_reach(origin, inv_dir, t_max)
    }

    /// Every `t` with `t_min < t <= t_max` where `origin + t·dir` lies on the surface inside
    /// the clip box, nearest first: the roots [`Quadric::intersect`] chooses from, all of them.
    /// A tangent ray's double root counts once.
    pub fn crossings(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Vec<f64> {
        if !self.may_reach_bounds(origin, dir.recip(), t_max) {
            return Vec::new();
        }
        let x0 = self.to_local * (origin - self.anchor);
        let v = self.to_local * dir;
        let Some(roots) = self.local.ray_roots(x0, v) else {
            return Vec::new();
        };
        let mut hits: Vec<f64> = roots
            .into_iter()
            .filter(|&t| t > t_min.max(0.0) && t <= t_max && self.inside_clip(x0 + t * v))
            .collect();
        hits.dedup();
        hits
    }

    /// [`Quadric::intersect`] without the bounds pre-test.
    pub(super) fn intersect_exact(&self, origin: DVec3, dir: DVec3, t_max: f64) -> Option<f64> {
        let x0 = self.to_local * (origin - self.anchor);
        let v = self.to_local * dir;
        let roots = self.local.ray_roots(x0, v)?;
        roots
            .into_iter()
            .find(|&t| t > 0.0 && t <= t_max && self.inside_clip(x0 + t * v))
    }

    /// Unit world normal at `origin + t·dir`: the normalised world gradient
    /// `A⁻ᵀ(2Qx + P)` (equal to `2Q'u + P'`), pointing to `f > 0`. Where the gradient vanishes
    /// to within the rounding of the hit point (cone apex, the crossing line of a plane pair, a
    /// point quadric), so that its direction would be noise, it is `−dir` normalised, and `+Z`
    /// if even that fails.
    pub fn normal(&self, origin: DVec3, dir: DVec3, t: f64) -> DVec3 {
        let (x0, v) = (self.to_local * (origin - self.anchor), self.to_local * dir);
        let x = x0 + t * v;
        let local_gradient = self.local.gradient(x);
        let rounding = self.local.gradient_rounding(x0.abs() + (t * v).abs());
        let gradient = self.to_local.transpose() * local_gradient;
        (local_gradient.abs().max_element() > rounding)
            .then(|| unit_or_none(gradient))
            .flatten()
            .or_else(|| unit_or_none(-dir))
            .unwrap_or(DVec3::Z)
    }

    /// Affine classification from the world-space coefficients.
    pub fn kind(&self) -> QuadricKind {
        self.kind
    }

    /// Conservative test whether the clipped surface may touch the world AABB `[min, max]`:
    /// false only if the box misses [`Quadric::bounds`] or the quadric's value has one strict
    /// sign over the whole box (interval arithmetic, padded for rounding).
    pub fn may_overlap_box(&self, min: DVec3, max: DVec3) -> bool {
        let lo = min.max(self.reach.bounds.min);
        let hi = max.min(self.reach.bounds.max);
        if lo.cmpgt(hi).any() {
            return false;
        }
        let w = &self.world;
        value_range_may_contain_zero(w.q, w.p, w.r, lo - self.anchor, hi - self.anchor)
    }

    /// Whether the local point `local_anchor + x` lies in the clip box (inclusive); true
    /// without one.
    fn inside_clip(&self, x: DVec3) -> bool {
        self.clip.is_none_or(|[min, max]| {
            let local = x + self.local_anchor;
            local.cmpge(min).all() && local.cmple(max).all()
        })
    }

    /// World AABB of the local box `[min, max]` (its eight corners), to rounding.
    fn world_box_of_local_box(&self, [min, max]: [DVec3; 2], linear: DMat3) -> [DVec3; 2] {
        let centre = linear * ((min + max) * 0.5 - self.local_anchor);
        let half = linear.abs() * ((max - min) * 0.5);
        [self.anchor + centre - half, self.anchor + centre + half]
    }

    /// The world bounds: the clip box's world AABB, intersected with the ellipsoid's tight box
    /// when `Q` is definite (always so when there is no clip box); `definite_linear` is then
    /// the object→world linear map. `finish` is applied to both boxes first ([`pad`] for
    /// conservative bounds).
    fn clipped_bounds(
        &self,
        clip_world: Option<[DVec3; 2]>,
        definite_linear: Option<DMat3>,
        finish: fn([DVec3; 2]) -> [DVec3; 2],
    ) -> [DVec3; 2] {
        let ellipsoid = definite_linear.map(|linear| finish(self.ellipsoid_box(linear)));
        let [lo, hi] = match (clip_world.map(finish), ellipsoid) {
            (Some([a, b]), Some([c, d])) => [a.max(c), b.min(d)],
            (Some(b), None) | (None, Some(b)) => b,
            (None, None) => [self.anchor, self.anchor],
        };
        if lo.cmple(hi).all() {
            [lo, hi]
        } else {
            [self.anchor, self.anchor]
        }
    }

    /// Tight world AABB (to rounding) of the ellipsoid `f = 0` for a definite `Q`, from the local form and
    /// the object→world map `A`: local centre `e = −Q⁻¹P/2`, world half-extent
    /// `sqrt(−f(e)·(A·Q⁻¹·Aᵀ)ᵢᵢ)` along axis `i`. Inverting the local `Q` (diagonal for a
    /// needle or a disc placed by its node) keeps the digits that inverting the world `Q'`
    /// (condition number squared by the turn) loses. An empty surface gives the point box at
    /// its centre.
    fn ellipsoid_box(&self, linear: DMat3) -> [DVec3; 2] {
        let l = &self.local;
        let inverse = l.q.inverse();
        let centre = -0.5 * (inverse * l.p);
        let level = -(l.r + 0.5 * l.p.dot(centre));
        let spread = linear * inverse * linear.transpose();
        let diagonal = DVec3::new(spread.x_axis.x, spread.y_axis.y, spread.z_axis.z);
        let half = (diagonal * level).max(DVec3::ZERO);
        let half = DVec3::new(half.x.sqrt(), half.y.sqrt(), half.z.sqrt());
        let world_centre = self.anchor + linear * centre;
        [world_centre - half, world_centre + half]
    }
}

/// The upper-left 3×3 of an affine matrix, after checking it is finite, affine and invertible.
fn affine_linear_part(world: DMat4) -> Result<DMat3> {
    if !world.is_finite() {
        return Err(Error::msg("world matrix has a non-finite entry"));
    }
    if world.row(3) != DVec4::W {
        return Err(Error::msg(
            "world matrix is not affine (last row is not 0 0 0 1)",
        ));
    }
    let linear = DMat3::from_mat4(world);
    let longest = [linear.x_axis, linear.y_axis, linear.z_axis]
        .map(DVec3::length)
        .into_iter()
        .fold(0.0, f64::max);
    if linear.determinant().abs() <= SINGULAR_DETERMINANT * longest.powi(3) {
        return Err(Error::msg("world matrix is singular"));
    }
    Ok(linear)
}

/// The centre `−Q⁻¹P/2` of a definite quadric; `Q` and `P` are first divided by the largest
/// entry of `Q`, so that the determinant of tiny (even subnormal) coefficients cannot
/// underflow.
fn ellipsoid_centre(q: DMat3, p: DVec3) -> DVec3 {
    let largest = q.abs().to_cols_array().into_iter().fold(0.0, f64::max);
    -0.5 * ((q / largest).inverse() * (p / largest))
}

/// The local clip box widened by [`CLIP_TOLERANCE`] times its largest side.
fn widen_clip_box([min, max]: [DVec3; 2]) -> [DVec3; 2] {
    let margin = CLIP_TOLERANCE * (max - min).max_element();
    [min - margin, max + margin]
}

/// Grows a box by a relative margin so that rounding in its computation cannot shrink it.
fn pad([lo, hi]: [DVec3; 2]) -> [DVec3; 2] {
    let margin = (lo.abs().max(hi.abs())) * BOUNDS_PADDING;
    [lo - margin, hi + margin]
}

/// `v` normalised, or `None` if it is zero or not finite. Scaling by the largest component
/// first avoids overflow and underflow.
fn unit_or_none(v: DVec3) -> Option<DVec3> {
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    (v / largest).try_normalize()
}
