//! Rays borrowed from numpy arrays without a copy, and the checks that need a pass over them.

use glam::DVec3;
use numpy::ndarray::{ArrayView1, ArrayView2};
use raycast::geometry::Ray;
use raycast::render::RaySource;
use rayon::prelude::*;

/// `N` rays: (N, 3) origins and directions, and per-ray `tmin`, `tmax` of length N or 1
/// (broadcast). Views of the caller's arrays: any strides, no copy.
pub struct RayArrays<'a> {
    pub origins: ArrayView2<'a, f64>,
    pub directions: ArrayView2<'a, f64>,
    pub tmin: ArrayView1<'a, f64>,
    pub tmax: ArrayView1<'a, f64>,
}

impl RayArrays<'_> {
    /// The parameter range `(tmin, tmax]` of ray `i`.
    pub fn range(&self, i: usize) -> (f64, f64) {
        let at = |a: &ArrayView1<f64>| a[if a.len() == 1 { 0 } else { i }];
        (at(&self.tmin), at(&self.tmax))
    }

    /// The first ray that cannot be traced, described: a non-finite origin or direction, a
    /// zero direction, a NaN or negative `tmin`, a NaN `tmax`.
    pub fn first_invalid(&self) -> Option<String> {
        (0..self.len())
            .into_par_iter()
            .find_first(|&i| self.problem(i).is_some())
            .and_then(|i| self.problem(i).map(|p| format!("ray {i}: {p}")))
    }

    fn problem(&self, i: usize) -> Option<String> {
        let ray = self.ray(i);
        let (tmin, tmax) = self.range(i);
        if !ray.origin.is_finite() {
            Some(format!("origin {} is not finite", show(ray.origin)))
        } else if !ray.dir.is_finite() {
            Some(format!("direction {} is not finite", show(ray.dir)))
        } else if ray.dir == DVec3::ZERO {
            Some("direction is zero".into())
        } else if tmin.is_nan() || tmin < 0.0 {
            Some(format!("tmin {tmin} is not a number >= 0"))
        } else if tmax.is_nan() {
            Some("tmax is NaN".into())
        } else {
            None
        }
    }
}

fn show(v: DVec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

impl RaySource for RayArrays<'_> {
    fn len(&self) -> usize {
        self.origins.nrows()
    }

    fn ray(&self, i: usize) -> Ray {
        let o = &self.origins;
        let d = &self.directions;
        Ray::new(
            DVec3::new(o[[i, 0]], o[[i, 1]], o[[i, 2]]),
            DVec3::new(d[[i, 0]], d[[i, 1]], d[[i, 2]]),
        )
    }
}
