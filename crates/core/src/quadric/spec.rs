//! Quadric coefficients as written in a scene file, and the `RAYCAST_quadric` glTF extension.

use glam::{DMat3, DVec3};
use serde_json::{Map, Value};

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
    pub fn from_coefficients(c: [f64; 10], bounds: Option<[DVec3; 2]>) -> Result<Self, String> {
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
    ) -> Result<Self, String> {
        check_finite("Q", &q)?;
        check_finite("P", &p)?;
        check_finite("R", &[r])?;
        let rows = DMat3::from_cols_array(&q).transpose();
        let asymmetry = (rows - rows.transpose()).abs().to_cols_array();
        let largest = rows.abs().to_cols_array().into_iter().fold(0.0, f64::max);
        if asymmetry.into_iter().fold(0.0, f64::max) > SYMMETRY_TOLERANCE * largest {
            return Err("Q is not symmetric".to_string());
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

    /// Parses the `RAYCAST_quadric` extension object: either `coefficients` (ten numbers) or
    /// `Q` (nine), `P` (three) and `R`, plus optional `bounds: {min: [3], max: [3]}`.
    /// Unknown keys are ignored. The error message does not name the node.
    pub fn from_gltf_extension(v: &Value) -> Result<Self, String> {
        let object = v
            .as_object()
            .ok_or("RAYCAST_quadric must be a JSON object")?;
        let bounds = object.get("bounds").map(parse_bounds).transpose()?;
        let matrix_form = ["Q", "P", "R"].iter().any(|k| object.contains_key(*k));
        match (object.get("coefficients"), matrix_form) {
            (Some(_), true) => Err("give either `coefficients` or `Q`/`P`/`R`, not both".into()),
            (Some(c), false) => Self::from_coefficients(numbers(c, "coefficients")?, bounds),
            (None, true) => parse_matrix_form(object, bounds),
            (None, false) => Err("missing `coefficients` (or `Q`, `P` and `R`)".into()),
        }
    }

    /// Checks the invariants every constructor guarantees: finite numbers, symmetric `Q`,
    /// `Q` and `P` not both zero, `min <= max` in the clip box, and a clip box for every
    /// surface that is not bounded by itself (bounded iff `Q` is definite).
    pub fn validate(&self) -> Result<(), String> {
        check_finite("Q", &self.q.to_cols_array())?;
        check_finite("P", &self.p.to_array())?;
        check_finite("R", &[self.r])?;
        if self.q != self.q.transpose() {
            return Err("Q is not symmetric".into());
        }
        if self.q == DMat3::ZERO && self.p == DVec3::ZERO {
            return Err("Q and P are all zero: not a surface".into());
        }
        match self.bounds {
            Some([min, max]) => {
                check_finite("bounds", &[min.to_array(), max.to_array()].concat())?;
                if min.cmpgt(max).any() {
                    return Err("bounds.min exceeds bounds.max".into());
                }
            }
            None if !is_definite(self.q) => {
                return Err("unbounded surface (Q not definite) needs `bounds`".into());
            }
            None => {}
        }
        Ok(())
    }
}

/// The matrix form `Q`, `P`, `R` of the extension; all three keys are required.
fn parse_matrix_form(
    object: &Map<String, Value>,
    bounds: Option<[DVec3; 2]>,
) -> Result<QuadricSpec, String> {
    let field = |key: &str| object.get(key).ok_or(format!("missing `{key}`"));
    let q = numbers::<9>(field("Q")?, "Q")?;
    let p = numbers::<3>(field("P")?, "P")?;
    let r = number(field("R")?, "R")?;
    QuadricSpec::from_matrices(q, p, r, bounds)
}

/// Parses `{"min": [x, y, z], "max": [x, y, z]}`.
fn parse_bounds(v: &Value) -> Result<[DVec3; 2], String> {
    let object = v
        .as_object()
        .ok_or("`bounds` must be an object with `min` and `max`")?;
    let corner = |key: &str| -> Result<DVec3, String> {
        let value = object.get(key).ok_or(format!("missing `bounds.{key}`"))?;
        Ok(DVec3::from_array(numbers(value, &format!("bounds.{key}"))?))
    };
    Ok([corner("min")?, corner("max")?])
}

/// A JSON array of exactly `N` finite numbers.
fn numbers<const N: usize>(v: &Value, what: &str) -> Result<[f64; N], String> {
    let items = v
        .as_array()
        .ok_or(format!("`{what}` must be an array of {N} numbers"))?;
    if items.len() != N {
        return Err(format!(
            "`{what}` has {} numbers, expected {N}",
            items.len()
        ));
    }
    let mut out = [0.0; N];
    for (slot, item) in out.iter_mut().zip(items) {
        *slot = number(item, what)?;
    }
    Ok(out)
}

/// A finite JSON number.
fn number(v: &Value, what: &str) -> Result<f64, String> {
    let x = v
        .as_f64()
        .ok_or(format!("`{what}` must contain only numbers"))?;
    check_finite(what, &[x])?;
    Ok(x)
}

/// Rejects NaN and infinities.
fn check_finite(what: &str, values: &[f64]) -> Result<(), String> {
    if values.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("`{what}` contains a non-finite number"))
    }
}
