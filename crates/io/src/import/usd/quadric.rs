//! The general quadric prim: custom `raycast:quadric:*` attributes on a prim of any type,
//! with the same forms, rules and errors as the glTF extension `RAYCAST_quadric`
//! (docs/RAYCAST_quadric.md, docs/usd.md).

use super::value::{self, At};
use crate::error::{Error, Result};
use crate::quadric::QuadricSpec;
use openusd::usd::Prim;

/// Attribute namespace of the quadric prim.
pub const PREFIX: &str = "raycast:quadric:";

const COEFFICIENTS: &str = "raycast:quadric:coefficients";
const Q: &str = "raycast:quadric:Q";
const P: &str = "raycast:quadric:P";
const R: &str = "raycast:quadric:R";
const BOUNDS_MIN: &str = "raycast:quadric:boundsMin";
const BOUNDS_MAX: &str = "raycast:quadric:boundsMax";

/// True when the prim has any `raycast:quadric:` property.
pub fn has_quadric(prim: &Prim) -> Result<bool> {
    let names = prim.property_names().map_err(|e| {
        Error::at(
            prim.path().to_string(),
            format!("cannot list properties: {e}"),
        )
    })?;
    Ok(names.iter().any(|n| n.as_str().starts_with(PREFIX)))
}

/// Reads the quadric of a prim that has `raycast:quadric:` properties. The error does not
/// name the prim (the caller prefixes it).
pub fn read(prim: &Prim, at: At) -> Result<QuadricSpec> {
    let strip = |mut e: Error| {
        // value readers locate `<prim>.<attr>`: keep only the attribute part.
        let prefix = format!("{}.", prim.path());
        if let Some(attribute) = e.location.strip_prefix(&prefix) {
            e.location = attribute.to_string();
        }
        e
    };
    let min = value::vec3(prim, BOUNDS_MIN, at).map_err(strip)?;
    let max = value::vec3(prim, BOUNDS_MAX, at).map_err(strip)?;
    let bounds = match (min, max) {
        (Some(min), Some(max)) => Some([min, max]),
        (None, None) => None,
        (Some(_), None) => {
            return Err(Error::msg(format!(
                "{BOUNDS_MIN} is given without {BOUNDS_MAX}"
            )))
        }
        (None, Some(_)) => {
            return Err(Error::msg(format!(
                "{BOUNDS_MAX} is given without {BOUNDS_MIN}"
            )))
        }
    };
    let coefficients = value::numbers(prim, COEFFICIENTS, at).map_err(strip)?;
    let q = value::matrix3_rows(prim, Q, at).map_err(strip)?;
    let p = value::vec3(prim, P, at).map_err(strip)?;
    let r = value::scalar(prim, R, at).map_err(strip)?;
    let matrix_form = q.is_some() || p.is_some() || r.is_some();
    match (coefficients, matrix_form) {
        (Some(_), true) => Err(Error::msg(format!(
            "give either {COEFFICIENTS} or {Q}/{P}/{R}, not both"
        ))),
        (Some(c), false) => {
            let c: [f64; 10] = c.as_slice().try_into().map_err(|_| {
                Error::msg(format!(
                    "{COEFFICIENTS} has {} numbers, expected 10",
                    c.len()
                ))
            })?;
            QuadricSpec::from_coefficients(c, bounds)
        }
        (None, true) => {
            let q = q.ok_or_else(|| Error::msg(format!("missing {Q}")))?;
            let p = p.ok_or_else(|| Error::msg(format!("missing {P}")))?;
            let r = r.ok_or_else(|| Error::msg(format!("missing {R}")))?;
            QuadricSpec::from_matrices(q, p.to_array(), r, bounds)
        }
        (None, false) => Err(Error::msg(format!(
            "missing {COEFFICIENTS} (or {Q}, {P} and {R})"
        ))),
    }
}
