//! Rays borrowed from numpy arrays without a copy, and the checks that need a pass over them.

use glam::DVec3;
use numpy::ndarray::{ArrayView1, ArrayView2};
use pyo3::exceptions::PyValueError;
use pyo3::{PyErr, PyResult};
use raycast_core::geometry::Ray;
use raycast_core::geometry::RaySource;
use rayon::prelude::*;

/// The rows of an (N, 3) array: a slice of rows when it is C-contiguous (read without index
/// arithmetic), else the strided view.
enum Rows<'a> {
    Flat(&'a [[f64; 3]]),
    Strided(ArrayView2<'a, f64>),
}

impl<'a> Rows<'a> {
    fn new(view: ArrayView2<'a, f64>) -> Rows<'a> {
        match view.to_slice() {
            Some(flat) => Rows::Flat(flat.as_chunks().0),
            None => Rows::Strided(view),
        }
    }

    #[inline]
    fn get(&self, i: usize) -> DVec3 {
        match self {
            Rows::Flat(v) => DVec3::from_array(v[i]),
            Rows::Strided(v) => DVec3::new(v[[i, 0]], v[[i, 1]], v[[i, 2]]),
        }
    }
}

/// A per-ray value given once for all rays or per ray.
enum PerRay<'a> {
    All(f64),
    Each(ArrayView1<'a, f64>),
}

impl<'a> PerRay<'a> {
    fn new(view: ArrayView1<'a, f64>) -> PerRay<'a> {
        match view.len() {
            1 => PerRay::All(view[0]),
            _ => PerRay::Each(view),
        }
    }

    #[inline]
    fn get(&self, i: usize) -> f64 {
        match self {
            PerRay::All(v) => *v,
            PerRay::Each(v) => v[i],
        }
    }
}

/// `N` rays: (N, 3) origins and directions, and per-ray `tmin`, `tmax` of length N or 1
/// (broadcast). Views of the caller's arrays: any strides, no copy.
pub struct RayArrays<'a> {
    len: usize,
    origins: Rows<'a>,
    directions: Rows<'a>,
    tmin: PerRay<'a>,
    tmax: PerRay<'a>,
}

impl<'a> RayArrays<'a> {
    /// The rays of the arrays, after checking their shapes.
    pub fn new(
        origins: ArrayView2<'a, f64>,
        directions: ArrayView2<'a, f64>,
        tmin: ArrayView1<'a, f64>,
        tmax: ArrayView1<'a, f64>,
    ) -> PyResult<RayArrays<'a>> {
        let len = origins.nrows();
        let per_ray = |a: &ArrayView1<f64>| a.len() == len || a.len() == 1;
        if origins.ncols() != 3
            || directions.shape() != origins.shape()
            || !per_ray(&tmin)
            || !per_ray(&tmax)
        {
            return Err(PyValueError::new_err(
                "origins and directions must be (N, 3), tmin and tmax (N,) or (1,)",
            ));
        }
        Ok(RayArrays {
            len,
            origins: Rows::new(origins),
            directions: Rows::new(directions),
            tmin: PerRay::new(tmin),
            tmax: PerRay::new(tmax),
        })
    }

    /// The common case, read without a choice per ray: C-contiguous origins and directions
    /// and one `(tmin, tmax]` for every ray.
    pub fn contiguous(&self) -> Option<(ContiguousRays<'a>, (f64, f64))> {
        match (&self.origins, &self.directions, &self.tmin, &self.tmax) {
            (Rows::Flat(o), Rows::Flat(d), PerRay::All(t0), PerRay::All(t1)) => Some((
                ContiguousRays {
                    origins: o,
                    directions: d,
                },
                (*t0, *t1),
            )),
            _ => None,
        }
    }

    /// The parameter range `(tmin, tmax]` of ray `i`.
    #[inline]
    pub fn range(&self, i: usize) -> (f64, f64) {
        (self.tmin.get(i), self.tmax.get(i))
    }

    /// Refuses the first ray that cannot be traced, among the rays `suspect` picks: a
    /// non-finite origin or direction, a zero direction, a NaN or negative `tmin`, a NaN
    /// `tmax`. (Such a ray has no hit, so callers pass the rays without one: the check costs
    /// nothing when every ray hits.)
    pub fn check(&self, suspect: impl Fn(usize) -> bool + Sync) -> PyResult<()> {
        let first = (0..self.len)
            .into_par_iter()
            .find_first(|&i| suspect(i) && self.problem(i).is_some());
        first.map_or(Ok(()), |i| Err(self.error(i)))
    }

    /// The error that refuses ray `i`.
    pub fn error(&self, i: usize) -> PyErr {
        let problem = self.problem(i).unwrap_or_else(|| "cannot be traced".into());
        PyValueError::new_err(format!("ray {i}: {problem}"))
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

/// Rays from C-contiguous (N, 3) arrays (see [`RayArrays::contiguous`]).
pub struct ContiguousRays<'a> {
    origins: &'a [[f64; 3]],
    directions: &'a [[f64; 3]],
}

impl RaySource for ContiguousRays<'_> {
    fn len(&self) -> usize {
        self.origins.len()
    }

    #[inline]
    fn ray(&self, i: usize) -> Ray {
        Ray::new(
            DVec3::from_array(self.origins[i]),
            DVec3::from_array(self.directions[i]),
        )
    }
}

fn show(v: DVec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}

impl RaySource for RayArrays<'_> {
    fn len(&self) -> usize {
        self.len
    }

    #[inline]
    fn ray(&self, i: usize) -> Ray {
        Ray::new(self.origins.get(i), self.directions.get(i))
    }
}
