//! The `RAYCAST_quadric` node extension (docs/RAYCAST_quadric.md): its JSON object as a
//! [`QuadricSpec`].

use crate::error::{Error, Result};
use crate::quadric::spec::check_finite;
use crate::quadric::QuadricSpec;
use glam::DVec3;
use serde_json::{Map, Value};

/// Parses the `RAYCAST_quadric` extension object: either `coefficients` (ten numbers) or
/// `Q` (nine), `P` (three) and `R`, plus optional `bounds: {min: [3], max: [3]}`.
/// Unknown keys are ignored. The error message does not name the node.
pub fn quadric_spec(v: &Value) -> Result<QuadricSpec> {
    let object = v
        .as_object()
        .ok_or_else(|| Error::msg("RAYCAST_quadric must be a JSON object"))?;
    let bounds = object.get("bounds").map(parse_bounds).transpose()?;
    let matrix_form = ["Q", "P", "R"].iter().any(|k| object.contains_key(*k));
    match (object.get("coefficients"), matrix_form) {
        (Some(_), true) => Err(Error::msg(
            "give either `coefficients` or `Q`/`P`/`R`, not both",
        )),
        (Some(c), false) => QuadricSpec::from_coefficients(numbers(c, "coefficients")?, bounds),
        (None, true) => parse_matrix_form(object, bounds),
        (None, false) => Err(Error::msg("missing `coefficients` (or `Q`, `P` and `R`)")),
    }
}

/// The matrix form `Q`, `P`, `R` of the extension; all three keys are required.
fn parse_matrix_form(
    object: &Map<String, Value>,
    bounds: Option<[DVec3; 2]>,
) -> Result<QuadricSpec> {
    let field = |key: &str| {
        object
            .get(key)
            .ok_or_else(|| Error::msg(format!("missing `{key}`")))
    };
    let q = numbers::<9>(field("Q")?, "Q")?;
    let p = numbers::<3>(field("P")?, "P")?;
    let r = number(field("R")?, "R")?;
    QuadricSpec::from_matrices(q, p, r, bounds)
}

/// Parses `{"min": [x, y, z], "max": [x, y, z]}`.
fn parse_bounds(v: &Value) -> Result<[DVec3; 2]> {
    let object = v
        .as_object()
        .ok_or_else(|| Error::msg("`bounds` must be an object with `min` and `max`"))?;
    let corner = |key: &str| -> Result<DVec3> {
        let value = object
            .get(key)
            .ok_or_else(|| Error::msg(format!("missing `bounds.{key}`")))?;
        Ok(DVec3::from_array(numbers(value, &format!("bounds.{key}"))?))
    };
    Ok([corner("min")?, corner("max")?])
}

/// A JSON array of exactly `N` finite numbers.
fn numbers<const N: usize>(v: &Value, what: &str) -> Result<[f64; N]> {
    let items = v
        .as_array()
        .ok_or_else(|| Error::msg(format!("`{what}` must be an array of {N} numbers")))?;
    if items.len() != N {
        return Err(Error::msg(format!(
            "`{what}` has {} numbers, expected {N}",
            items.len()
        )));
    }
    let mut out = [0.0; N];
    for (slot, item) in out.iter_mut().zip(items) {
        *slot = number(item, what)?;
    }
    Ok(out)
}

/// A finite JSON number.
fn number(v: &Value, what: &str) -> Result<f64> {
    let x = v
        .as_f64()
        .ok_or_else(|| Error::msg(format!("`{what}` must contain only numbers")))?;
    check_finite(what, &[x])?;
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The error message for an extension object, which must fail.
    fn extension_error(v: serde_json::Value) -> String {
        quadric_spec(&v).unwrap_err().message
    }

    #[test]
    fn extension_parses_both_forms() {
        let a = quadric_spec(&json!({
            "coefficients": [1, 1, 0, 0, 0, 0, 0, 0, 0, -1],
            "bounds": {"min": [-1, -1, -2], "max": [1, 1, 2]},
            "extras": {"ignored": true}
        }))
        .unwrap();
        let b = quadric_spec(&json!({
            "Q": [1, 0, 0, 0, 1, 0, 0, 0, 0], "P": [0, 0, 0], "R": -1,
            "bounds": {"min": [-1, -1, -2], "max": [1, 1, 2]}
        }))
        .unwrap();
        assert_eq!(a, b);
        assert_eq!(
            a.bounds,
            Some([DVec3::new(-1.0, -1.0, -2.0), DVec3::new(1.0, 1.0, 2.0)])
        );
        let sphere = quadric_spec(&json!({"coefficients": [1, 1, 1, 0, 0, 0, 0, 0, 0, -1]}));
        assert_eq!(sphere.unwrap().bounds, None);
    }

    #[test]
    fn extension_errors() {
        let sphere = json!([1, 1, 1, 0, 0, 0, 0, 0, 0, -1]);
        let both = json!({"coefficients": sphere, "Q": [1, 0, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0, 0], "R": -1});
        assert!(extension_error(both).contains("not both"));
        assert!(extension_error(json!({})).contains("missing"));
        assert!(extension_error(json!([1, 2])).contains("object"));
        assert!(extension_error(json!({"coefficients": [1, 1, 1]})).contains("expected 10"));
        assert!(
            extension_error(json!({"Q": [1, 0, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0], "R": -1}))
                .contains("expected 3")
        );
        assert!(
            extension_error(json!({"Q": [1, 0, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0, 0]}))
                .contains("missing `R`")
        );
        assert!(
            extension_error(json!({"coefficients": [1, 1, 1, 0, 0, 0, 0, 0, "x", -1]}))
                .contains("numbers")
        );
        assert!(extension_error(
            json!({"Q": [1, 0.5, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0, 0], "R": -1})
        )
        .contains("symmetric"));
        assert!(
            extension_error(json!({"coefficients": [0, 0, 0, 0, 0, 0, 0, 0, 0, 1]}))
                .contains("zero")
        );
        assert!(
            extension_error(json!({"coefficients": [1, 1, 0, 0, 0, 0, 0, 0, 0, -1]}))
                .contains("bounds")
        );
        let inverted =
            json!({"coefficients": sphere, "bounds": {"min": [0, 0, 1], "max": [1, 1, 0]}});
        assert!(extension_error(inverted).contains("exceeds"));
        let short = json!({"coefficients": sphere, "bounds": {"min": [0, 0], "max": [1, 1, 1]}});
        assert!(extension_error(short).contains("bounds.min"));
        assert!(
            extension_error(json!({"coefficients": sphere, "bounds": [0, 1]})).contains("`bounds`")
        );
        let nan = QuadricSpec::from_coefficients(
            [f64::NAN, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            None,
        );
        assert!(nan.unwrap_err().message.contains("non-finite"));
        let inf = QuadricSpec::from_matrices(
            [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            [0.0; 3],
            f64::INFINITY,
            None,
        );
        assert!(inf.unwrap_err().message.contains("non-finite"));
    }
}
