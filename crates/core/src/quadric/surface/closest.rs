//! The point of a clipped quadric nearest to a query point, in f64, in world distances.
//!
//! # Method
//! The nearest point of the clipped surface `S ∩ B` (`B` the clip box, a parallelepiped in
//! the world) is a critical point of the distance on one of three pieces:
//!
//! 1. the surface itself, inside the box: the critical points of [`critical`] (the Lagrange
//!    condition in the eigenbasis of the world matrix `Q'`, the secular polynomial's roots,
//!    the hard cases and the singular points), every one, not only the nearest, since the
//!    box may cut the nearest away (one sheet of a hyperboloid);
//! 2. the curve where the surface meets a face of the box: a conic in the face's plane, the
//!    same problem one dimension lower, solved by the same code with the query's foot on the
//!    plane as the query and a third direction without curvature;
//! 3. the points where it meets an edge of the box: the roots of a quadratic along the edge,
//!    and the edge's point nearest the query when the edge lies on the surface.
//!
//! Each candidate is settled on the surface (Newton steps along the gradient, restricted to
//! the face's plane for a face's; then Newton steps for the distance along the surface, kept
//! while they bring it nearer), kept only if it then lies on the surface to rounding and
//! in the box as stated (not the intersection test's widened box), and the nearest kept one
//! wins. When the nearest of the unclipped surface's candidates is in the box, it is the
//! answer and the box's faces and edges are not searched; faces and edges farther from the
//! query than the best so far are skipped.
//!
//! # Accuracy
//! Every answer is a point of the surface (its `f` within a few ulps of rounding) in the box,
//! so the distance can only be too large, and by no more than the candidate's distance from
//! the true nearest point along the surface: settled candidates are critical to rounding,
//! where the distance is stationary. The distance is then right to a few ε of
//! `|u| + size + |anchor|`, `u` the query relative to the quadric's anchor (whose own world
//! position carries ε|anchor|): tests/python/test_quadric_distance.py measures it against a
//! 50-digit mpmath minimisation on every kind, at most 1.05 ε of that scale.

mod critical;
mod roots;
#[cfg(test)]
mod tests;

use super::Quadric;
use crate::quadric::eigen::symmetric_eigen;
use crate::quadric::eigen::ZERO_EIGENVALUE;
use crate::quadric::kind::QuadricKind;
use critical::Diagonal;
use glam::{DMat3, DVec3};

/// The unit roundoff of f64.
const EPS: f64 = f64::EPSILON / 2.0;

/// Newton steps onto the surface, at most.
const NEWTON_STEPS: usize = 8;

/// Steps along the surface towards a critical point, at most.
const TANGENT_STEPS: usize = 4;

/// A point counts as on the surface when `|f|` is at most this many times its rounding bound.
const ON_SURFACE: f64 = 16.0;

/// The nearest point of a quadric to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadricClosest {
    /// From the query to the nearest point, in world coordinates.
    pub offset: DVec3,
    /// `|offset|`.
    pub distance: f64,
    /// The nearest point in the quadric's own coordinates (where its coefficients are written).
    pub local: DVec3,
}

/// Which directions a candidate may be settled along.
#[derive(Clone, Copy)]
enum Along {
    /// Any: a point of the surface.
    Surface,
    /// In the plane `n·w = h` (`n` a unit normal): a point of a face's plane.
    Plane(DVec3, f64),
}

impl Along {
    /// The part of the direction `v` allowed.
    fn project(self, v: DVec3) -> DVec3 {
        match self {
            Along::Surface => v,
            Along::Plane(n, _) => v - n * n.dot(v),
        }
    }

    /// The point `w` moved into the plane (a candidate made about a far query's foot carries
    /// the foot's rounding, `ε` of the query's distance, across the plane).
    fn snap(self, w: DVec3) -> DVec3 {
        match self {
            Along::Surface => w,
            Along::Plane(n, h) => w - n * (n.dot(w) - h),
        }
    }
}

/// The nearest kept candidate so far, relative to the anchor.
struct Best {
    query: DVec3,
    point: Option<DVec3>,
    distance: f64,
}

impl Best {
    fn offer(&mut self, w: DVec3) {
        let distance = (w - self.query).length();
        if distance < self.distance || self.point.is_none() {
            self.point = Some(w);
            self.distance = distance;
        }
    }
}

impl Quadric {
    /// The point of the clipped surface nearest to the world point `point` (see the module
    /// docs for the method and its accuracy). Faces and edges of the clip box farther than
    /// `limit` are not searched, so a nearest point farther than `limit` may be missed (and
    /// another one, or none, returned). `None` for a point that is not finite, an empty
    /// quadric, or one whose surface misses its clip box.
    pub fn closest(&self, point: DVec3, limit: f64) -> Option<QuadricClosest> {
        if !point.is_finite() || self.kind == QuadricKind::Empty {
            return None;
        }
        let u = point - self.anchor;
        let mut best = Best {
            query: u,
            point: None,
            distance: f64::INFINITY,
        };
        let nearest_unclipped = self.on_surface(u, &mut best);
        if self.stated_clip.is_some() && nearest_unclipped.is_none_or(|w| !self.in_box(w)) {
            self.on_faces(u, limit, &mut best);
            self.on_edges(u, limit, &mut best);
        }
        let w = best.point?;
        Some(QuadricClosest {
            offset: w - u,
            distance: best.distance,
            local: self.to_local * w + self.local_anchor,
        })
    }

    /// Offers the surface's critical points in the box to `best`; returns the nearest of them
    /// all, in the box or not (the unclipped surface's nearest point).
    fn on_surface(&self, u: DVec3, best: &mut Best) -> Option<DVec3> {
        let (lambda, frame) = symmetric_eigen(self.world.q);
        let diagonal = Diagonal {
            lambda: lambda.to_array(),
            b: (frame.transpose() * self.world.p).to_array(),
            r: self.world.r,
            zero: self.zero_eigenvalue(),
        };
        let mut candidates = Vec::new();
        diagonal.candidates((frame.transpose() * u).to_array(), &mut candidates);
        let mut unclipped = Best {
            query: u,
            point: None,
            distance: f64::INFINITY,
        };
        for y in candidates {
            let start = frame * DVec3::from_array(y);
            let Some(w) = self.settle(start, u, Along::Surface, |_| true) else {
                continue;
            };
            unclipped.offer(w);
            if self.in_box(w) {
                best.offer(w);
            } else if let Some(w) = self.settle(start, u, Along::Surface, |w| self.in_box(w)) {
                best.offer(w);
            }
        }
        unclipped.point
    }

    /// Offers the critical points of the conics where the surface meets the box's faces.
    fn on_faces(&self, u: DVec3, limit: f64, best: &mut Best) {
        let Some([min, max]) = self.stated_clip else {
            return;
        };
        let mut candidates = Vec::new();
        for axis in 0..3 {
            for level in [min[axis], max[axis]] {
                let row = self.to_local.row(axis);
                let normal = row / row.length();
                let offset = (level - self.local_anchor[axis]) / row.length();
                let height = normal.dot(u) - offset;
                if height.abs() >= best.distance.min(limit) {
                    continue;
                }
                let foot = u - normal * height;
                let (frame, diagonal) = self.face_conic(axis, foot);
                candidates.clear();
                diagonal.candidates([0.0; 3], &mut candidates);
                for y in &candidates {
                    let s = frame * DVec3::from_array(*y);
                    let w = foot + s;
                    let along = Along::Plane(normal, offset);
                    if let Some(w) = self.settle(w, u, along, |w| self.in_box(w)) {
                        best.offer(w);
                    }
                }
            }
        }
    }

    /// The surface restricted to the face plane through `foot` across local axis `axis`, in
    /// a frame of the plane (its third direction along the normal, without curvature): the
    /// world map of the frame (columns) and the conic, diagonal, about `foot`.
    fn face_conic(&self, axis: usize, foot: DVec3) -> (DMat3, Diagonal) {
        let e1 = self.to_world.col((axis + 1) % 3).normalize();
        let e2 = self.to_world.col((axis + 2) % 3);
        let e2 = (e2 - e1 * e1.dot(e2)).normalize();
        let q = self.world.q;
        let (a, b, c) = (e1.dot(q * e1), e1.dot(q * e2), e2.dot(q * e2));
        let conic = DMat3::from_cols(DVec3::new(a, b, 0.0), DVec3::new(b, c, 0.0), DVec3::ZERO);
        let (lambda, rotation) = symmetric_eigen(conic);
        let gradient = self.world.gradient(foot);
        let linear = DVec3::new(e1.dot(gradient), e2.dot(gradient), 0.0);
        let frame = DMat3::from_cols(e1, e2, e1.cross(e2)) * rotation;
        let diagonal = Diagonal {
            lambda: lambda.to_array(),
            b: (rotation.transpose() * linear).to_array(),
            r: self.world.value(foot),
            zero: self.zero_eigenvalue(),
        };
        (frame, diagonal)
    }

    /// Offers the points where the surface meets the box's edges.
    fn on_edges(&self, u: DVec3, limit: f64, best: &mut Best) {
        let Some([min, max]) = self.stated_clip else {
            return;
        };
        for axis in 0..3 {
            let (j, k) = ((axis + 1) % 3, (axis + 2) % 3);
            for (a, b) in [
                (min[j], min[k]),
                (min[j], max[k]),
                (max[j], min[k]),
                (max[j], max[k]),
            ] {
                let mut start = min;
                start[j] = a;
                start[k] = b;
                let x0 = start - self.local_anchor;
                let mut v = DVec3::ZERO;
                v[axis] = max[axis] - min[axis];
                let (w0, dw) = (self.to_world * x0, self.to_world * v);
                let along = if dw.length_squared() > 0.0 {
                    ((u - w0).dot(dw) / dw.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                if (w0 + dw * along - u).length() >= best.distance.min(limit) {
                    continue;
                }
                // The edge's point nearest the query counts when the edge lies on the surface.
                let nearest = w0 + dw * along;
                if self.is_on_surface(nearest) {
                    best.offer(nearest);
                }
                for t in self.local.ray_roots(x0, v).into_iter().flatten() {
                    if (-4.0 * EPS..=1.0 + 4.0 * EPS).contains(&t) {
                        best.offer(self.to_world * (x0 + v * t.clamp(0.0, 1.0)));
                    }
                }
            }
        }
    }

    /// `w` (relative to the anchor) moved onto the surface and then towards being critical
    /// for the distance from `query`, along `along`, by steps that stay where `keep` holds;
    /// `None` if it does not reach the surface there.
    fn settle(
        &self,
        w: DVec3,
        query: DVec3,
        along: Along,
        keep: impl Fn(DVec3) -> bool,
    ) -> Option<DVec3> {
        let mut w = self.onto_surface(w, along).filter(|&w| keep(w))?;
        for _ in 0..TANGENT_STEPS {
            let Some(step) = self.tangent_step(w, query, along) else {
                break;
            };
            if step.length() <= 4.0 * EPS * (w.length() + (query - w).length()) {
                break;
            }
            match self.onto_surface(w + step, along) {
                Some(next) if (next - query).length() < (w - query).length() && keep(next) => {
                    w = next
                }
                _ => break,
            }
        }
        Some(w)
    }

    /// A step along the surface at `w` (on it) towards being critical for the distance from
    /// `query`, in the tangent directions `along` allows: Newton's, `s` solving
    /// `T(I − 2νQ)T s = T(query − w)` with `ν = g·(w − query)/|g|²` the Lagrange multiplier
    /// (`g` the gradient, projected by `along`), where that Hessian is positive definite (a
    /// minimum nearby); else the foot of `query` on the tangent plane. `None` where the
    /// gradient vanishes.
    fn tangent_step(&self, w: DVec3, query: DVec3, along: Along) -> Option<DVec3> {
        let g = along.project(self.world.gradient(w));
        let n = g.try_normalize()?;
        let towards = query - w;
        let nu = g.dot(-towards) / g.length_squared();
        let hessian = |a: DVec3, b: DVec3| a.dot(b) - 2.0 * nu * a.dot(self.world.q * b);
        let newton = match along {
            Along::Plane(m, _) => m.cross(n).try_normalize().and_then(|t| {
                let h = hessian(t, t);
                (h > 0.0).then(|| t * (t.dot(towards) / h))
            }),
            Along::Surface => {
                let t1 = n.any_orthonormal_vector();
                let t2 = n.cross(t1);
                let (a, b, c) = (hessian(t1, t1), hessian(t1, t2), hessian(t2, t2));
                let det = a * c - b * b;
                let (r1, r2) = (t1.dot(towards), t2.dot(towards));
                (a > 0.0 && det > 0.0)
                    .then(|| t1 * ((c * r1 - b * r2) / det) + t2 * ((a * r2 - b * r1) / det))
            }
        };
        Some(newton.unwrap_or(towards - n * n.dot(towards)))
    }

    /// Newton steps on `f` along its gradient (restricted by `along`) from `w`; the point if
    /// it then lies on the surface to rounding.
    fn onto_surface(&self, w: DVec3, along: Along) -> Option<DVec3> {
        let mut w = along.snap(w);
        for _ in 0..NEWTON_STEPS {
            let value = self.world.value(w);
            let gradient = along.project(self.world.gradient(w));
            let squared = gradient.length_squared();
            if value == 0.0 || squared.is_nan() || squared == 0.0 {
                break;
            }
            let step = gradient * (value / squared);
            w -= step;
            if step.length() <= 2.0 * EPS * w.length() {
                break;
            }
        }
        (w.is_finite() && self.is_on_surface(w)).then_some(w)
    }

    /// Whether `f(w)` is zero to a few times its rounding.
    fn is_on_surface(&self, w: DVec3) -> bool {
        self.world.value(w).abs() <= ON_SURFACE * self.world.value_rounding(w)
    }

    /// Whether `w` (relative to the anchor) lies in the clip box as stated, to the rounding
    /// of its local coordinates; true without a clip box.
    fn in_box(&self, w: DVec3) -> bool {
        self.stated_clip.is_none_or(|[min, max]| {
            let local = self.to_local * w + self.local_anchor;
            let size = min.abs().max(max.abs()).max(max - min).max_element();
            let slack = 16.0 * EPS * (size + (self.to_local.abs() * w.abs()).max_element());
            local.cmpge(min - slack).all() && local.cmple(max + slack).all()
        })
    }

    /// Eigenvalues of the world matrix at most this in magnitude count as zero.
    fn zero_eigenvalue(&self) -> f64 {
        let q = self.world.q;
        let largest = [q.x_axis, q.y_axis, q.z_axis]
            .map(|c| c.abs().max_element())
            .into_iter()
            .fold(0.0, f64::max);
        ZERO_EIGENVALUE * largest
    }
}
