//! Quadric coefficients as written in a scene file (the glTF extension `RAYCAST_quadric` is
//! read by raycast-io, `import::gltf::quadric_extension`).

use crate::error::{Error, Result};
use glam::{DMat3, DVec3};

use super::eigen::is_definite;

/// Largest asymmetry `|Qᵢⱼ − Qⱼᵢ|` accepted, relative to the largest `|Qᵢⱼ|`.
const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// Local-space quadric as written in a file: `p·Q·p + P·p + R = 0`, with an optional clip box
/// `[min, max]` in the same local space.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadricSpec {
    /// Symmetric matrix of the quadratic terms.
    pub q: DMat3,
    /// Coefficients of the linear terms.
    pub p: DVec3,
    /// Constant term.
    pub r: f64,
    /// Clip box `[min, max]` in local space; the surface exists only inside it (inclusive).
    pub bounds: Option<[DVec3; 2]>,
}

impl QuadricSpec {
    /// From ten coefficients `A..J` of `Ax² + By² + Cz² + Dxy + Exz + Fyz + Gx + Hy + Iz + J`.
    /// The cross terms enter `Q` halved: `Q = [[A, D/2, E/2], [D/2, B, F/2], [E/2, F/2, C]]`,
    /// `P = [G, H, I]`, `R = J`. Errors as [`QuadricSpec::validate`].
    pub fn from_coefficients(c: [f64; 10], bounds: Option<[DVec3; 2]>) -> Result<Self> {
        check_finite("coefficients", &c)?;
        let [a, b, cc, d, e, f, g, h, i, j] = c;
        let q = DMat3::from_cols_array(&[
            a,
            d / 2.0,
            e / 2.0,
            d / 2.0,
            b,
            f / 2.0,
            e / 2.0,
            f / 2.0,
            cc,
        ]);
        let spec = Self {
            q,
            p: DVec3::new(g, h, i),
            r: j,
            bounds,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// From `Q` (nine numbers, row-major, symmetric to 1e-12 of its largest entry; stored
    /// symmetrised), `P` and `R`. Errors as [`QuadricSpec::validate`], plus an asymmetric `Q`.
    pub fn from_matrices(
        q: [f64; 9],
        p: [f64; 3],
        r: f64,
        bounds: Option<[DVec3; 2]>,
    ) -> Result<Self> {
        check_finite("Q", &q)?;
        check_finite("P", &p)?;
        check_finite("R", &[r])?;
        let rows = DMat3::from_cols_array(&q).transpose();
        let asymmetry = (rows - rows.transpose()).abs().to_cols_array();
        let largest = rows.abs().to_cols_array().into_iter().fold(0.0, f64::max);
        if asymmetry.into_iter().fold(0.0, f64::max) > SYMMETRY_TOLERANCE * largest {
            return Err(Error::msg("Q is not symmetric"));
        }
        let q = (rows + rows.transpose()) * 0.5;
        let spec = Self {
            q,
            p: DVec3::from_array(p),
            r,
            bounds,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// Checks the invariants every constructor guarantees: finite numbers, symmetric `Q`,
    /// `Q` and `P` not both zero, `min <= max` in the clip box, and a clip box for every
    /// surface that is not bounded by itself (bounded iff `Q` is definite).
    pub fn validate(&self) -> Result<()> {
        check_finite("Q", &self.q.to_cols_array())?;
        check_finite("P", &self.p.to_array())?;
        check_finite("R", &[self.r])?;
        if self.q != self.q.transpose() {
            return Err(Error::msg("Q is not symmetric"));
        }
        if self.q == DMat3::ZERO && self.p == DVec3::ZERO {
            return Err(Error::msg("Q and P are all zero: not a surface"));
        }
        match self.bounds {
            Some([min, max]) => {
                check_finite("bounds", &[min.to_array(), max.to_array()].concat())?;
                if min.cmpgt(max).any() {
                    return Err(Error::msg("bounds.min exceeds bounds.max"));
                }
            }
            None if !is_definite(self.q) => {
                return Err(Error::msg(
                    "unbounded surface (Q not definite) needs `bounds`",
                ));
            }
            None => {}
        }
        Ok(())
    }
}

/// Rejects NaN and infinities: `Err` names `what`.
pub fn check_finite(what: &str, values: &[f64]) -> Result<()> {
    if values.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::msg(format!("`{what}` contains a non-finite number")))
    }
}
