//! `xformOpOrder` composed into a local matrix, in f64, with glam's column-vector convention.
//!
//! openusd 0.6 has `Xformable::local_to_parent_transform`, but it silently turns an unknown op,
//! a missing op attribute or a wrongly typed value into the identity. This module composes the
//! same stack itself so that those cases are reported: every op kind of UsdGeomXformOp
//! (`translate[XYZ]`, `scale[XYZ]`, `rotate[XYZ]`, the six `rotateXYZ`-style Euler orders,
//! `orient`, `transform`), op suffixes (`xformOp:translate:pivot`), `!invert!` and a leading
//! `!resetXformStack!`.
//!
//! `xformOpOrder` lists ops outermost first: for `[A, B, C]` a point `p` maps to `A·B·C·p`.
//!
//! Each op's matrix and the product come with a bound on their distance from the exact
//! matrices of the op values as read ([`BoundedMat4`], for the `error` and `certain` AOVs):
//! translations, scales and `transform` matrices are exact; a rotation in degrees carries its
//! angle's conversion and libm's `sin`/`cos` ([`rotation::about_axis`]); `orient` the f64
//! evaluation of usd-core's axis-and-angle reading ([`orient_rotation`]); the products their
//! roundings ([`BoundedMat4::then_bounded`]). An inverted op other than a translation (whose
//! inverse is exact) is not bounded (`+∞`).

use super::value::{self, value_matrix4, value_quat, value_scalar, value_vec3, At};
use super::warning_at;
use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DQuat, DVec3};
use openusd::sdf::Value;
use openusd::usd::Prim;
use raycast_core::bound::bounded::Bounded;
use raycast_core::bound::rotation;
use raycast_core::bound::transform::BoundedMat4;
use raycast_core::diagnostic::{Code, Diagnostic};
use std::ops::{Div, Mul, Sub};

const INVERT: &str = "!invert!";
const RESET: &str = "!resetXformStack!";

/// A prim's local transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// Local-to-parent matrix (column vectors), with its bound.
    pub matrix: BoundedMat4,
    /// `!resetXformStack!`: the matrix is local-to-world, the parent's transform is dropped.
    pub resets: bool,
}

/// Composes the prim's `xformOpOrder`. Problems that usd-core reports as warnings (an op
/// attribute that is not authored, an unknown op name) are pushed to `warnings` and the op
/// is skipped; a value of the wrong type or a singular inverted op is an error.
pub fn local_transform(prim: &Prim, at: At, warnings: &mut Vec<Diagnostic>) -> Result<Local> {
    let order = match value::raw(prim, "xformOpOrder", at)? {
        None => {
            return Ok(Local {
                matrix: BoundedMat4::exact(DMat4::IDENTITY),
                resets: false,
            })
        }
        Some(Value::TokenVec(tokens)) => tokens.iter().map(|t| t.as_str().to_string()).collect(),
        Some(Value::StringVec(strings)) => strings,
        Some(Value::TokenListOp(op)) => op
            .flatten()
            .into_iter()
            .map(|t| t.as_str().to_string())
            .collect::<Vec<String>>(),
        Some(other) => {
            return Err(Error::at(
                format!("{}.xformOpOrder", prim.path()),
                format!("expected token[], found {}", value::value_kind(&other)),
            ))
        }
    };
    let mut matrix = BoundedMat4::exact(DMat4::IDENTITY);
    let mut resets = false;
    for (i, entry) in order.iter().enumerate() {
        if entry == RESET {
            if i == 0 {
                resets = true;
                continue;
            }
            return Err(Error::at(
                format!("{}.xformOpOrder", prim.path()),
                format!("{RESET} is only valid as the first entry (found at {i})"),
            ));
        }
        let (inverted, name) = match entry.strip_prefix(INVERT) {
            Some(rest) => (true, rest),
            None => (false, entry.as_str()),
        };
        let Some(op) = op_matrix(prim, name, at, warnings)? else {
            continue;
        };
        let op = if inverted {
            invert(op).ok_or_else(|| {
                Error::at(
                    prim.path().to_string(),
                    format!("{entry} cannot be inverted (its matrix is singular)"),
                )
            })?
        } else {
            op
        };
        matrix = matrix.then_bounded(&op);
    }
    if !matrix.value.is_finite() {
        return Err(Error::at(
            prim.path().to_string(),
            "the local transform is not finite",
        ));
    }
    Ok(Local { matrix, resets })
}

/// Inverse of an op matrix, `None` when it is singular. A translation's is exact (its negation,
/// as glam's inverse computes it); any other's bound is not made (`+∞`).
fn invert(m: BoundedMat4) -> Option<BoundedMat4> {
    let value = m.value;
    let det = value.determinant();
    let scale = value.x_axis.truncate().length()
        * value.y_axis.truncate().length()
        * value.z_axis.truncate().length();
    if !(det.is_finite() && det.abs() > 1e-300 && det.abs() > 1e-14 * scale) {
        return None;
    }
    if m.is_exact() && DMat3::from_mat4(value) == DMat3::IDENTITY {
        return Some(BoundedMat4::exact(DMat4::from_translation(
            -value.w_axis.truncate(),
        )));
    }
    Some(BoundedMat4::unbounded(value.inverse()))
}

/// Whether `name` can name an attribute: identifiers (a letter or `_`, then letters, digits
/// or `_`) joined by single colons, as Sdf's property names are. An `xformOpOrder` entry
/// that is not one names no attribute of any layer (usd-core refuses the op stack); a
/// malformed one (`xformOp:}ota`) is refused before it becomes a property path.
fn is_property_name(name: &str) -> bool {
    name.split(':').all(|part| {
        let mut chars = part.chars();
        chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
            && chars.all(|c| c.is_alphanumeric() || c == '_')
    })
}

/// The matrix of one op, `None` (with a warning) when it cannot be evaluated.
fn op_matrix(
    prim: &Prim,
    name: &str,
    at: At,
    warnings: &mut Vec<Diagnostic>,
) -> Result<Option<BoundedMat4>> {
    let Some(rest) = name.strip_prefix("xformOp:") else {
        warnings.push(warning_at(
            prim.path().to_string(),
            format!("xformOpOrder entry '{name}' is not an xformOp: ignored"),
        ));
        return Ok(None);
    };
    if !is_property_name(name) {
        return Err(Error::at(
            format!("{}.xformOpOrder", prim.path()),
            format!("entry '{}' is not an attribute name", name.escape_debug()),
        )
        .with_code(Code::UsdInvalidPath));
    }
    let kind = rest.split(':').next().unwrap_or(rest);
    let Some(raw) = value::raw(prim, name, at)? else {
        let why = if at.time().is_none() && value::has_time_samples(prim, name) {
            "has only time samples (read at the default time, as usd-core does; --time CODE reads them)"
        } else {
            "is not authored"
        };
        warnings.push(warning_at(
            prim.path().to_string(),
            format!("xformOp {name} {why}: ignored"),
        ));
        return Ok(None);
    };
    let bad = |expected: &str| {
        Error::at(
            format!("{}.{name}", prim.path()),
            format!("expected {expected}, found {}", value::value_kind(&raw)),
        )
    };
    let scalar = || value_scalar(&raw).ok_or_else(|| bad("a number"));
    let vector = || value_vec3(&raw).ok_or_else(|| bad("a 3-vector"));
    let exact = BoundedMat4::exact;
    let matrix = match kind {
        "translate" => exact(DMat4::from_translation(vector()?)),
        "translateX" => exact(DMat4::from_translation(DVec3::X * scalar()?)),
        "translateY" => exact(DMat4::from_translation(DVec3::Y * scalar()?)),
        "translateZ" => exact(DMat4::from_translation(DVec3::Z * scalar()?)),
        "scale" => exact(DMat4::from_scale(vector()?)),
        "scaleX" => exact(DMat4::from_scale(DVec3::new(scalar()?, 1.0, 1.0))),
        "scaleY" => exact(DMat4::from_scale(DVec3::new(1.0, scalar()?, 1.0))),
        "scaleZ" => exact(DMat4::from_scale(DVec3::new(1.0, 1.0, scalar()?))),
        "rotateX" => rotation::about_axis(0, scalar()?),
        "rotateY" => rotation::about_axis(1, scalar()?),
        "rotateZ" => rotation::about_axis(2, scalar()?),
        // `rotateXYZ` rotates about X first, then Y, then Z: R = Rz·Ry·Rx for column vectors.
        "rotateXYZ" | "rotateXZY" | "rotateYXZ" | "rotateYZX" | "rotateZXY" | "rotateZYX" => {
            let angles = vector()?;
            let mut m = exact(DMat4::IDENTITY);
            for axis in kind["rotate".len()..].chars() {
                let axis = match axis {
                    'X' => 0,
                    'Y' => 1,
                    _ => 2,
                };
                m = rotation::about_axis(axis, angles[axis]).then_bounded(&m);
            }
            m
        }
        "orient" => {
            let q = value_quat(&raw).ok_or_else(|| bad("a quaternion"))?;
            if q.length_squared() == 0.0 || !q.is_finite() {
                return Err(Error::at(
                    format!("{}.{name}", prim.path()),
                    "zero or non-finite quaternion",
                ));
            }
            orient_rotation(q)
        }
        "transform" => exact(value_matrix4(&raw).ok_or_else(|| bad("a matrix4d"))?),
        _ => {
            warnings.push(warning_at(
                prim.path().to_string(),
                format!("unknown xformOp kind '{kind}' ({name}): ignored"),
            ));
            return Ok(None);
        }
    };
    Ok(Some(matrix))
}

/// The rotation usd-core makes of an `orient` quaternion (`GfRotation`): the real part, clamped
/// to [-1, 1], is the cosine of half the angle and the imaginary part gives only the axis. A
/// quaternion that is not exactly unit (any `quatf` such as `(0.8, 0.2, 0.4, 0.4)` rounded to
/// f32) is therefore not normalised as a whole: doing so turned that one by 3.4e-8.
///
/// The exact rotation is that of the unit quaternion `(v·√(1 − w²)/|v|, w)`; the same steps in
/// [`Bounded`] arithmetic (the axis length's square root, `1 − w²`, the quotient) and glam's
/// normalisation and multiplying out ([`BoundedMat4::trs_bounded`]) give the value glam
/// computes, bit for bit, and its bound.
fn orient_rotation(q: DQuat) -> BoundedMat4 {
    let axis = glam::DVec3::new(q.x, q.y, q.z);
    let length = axis.length();
    // GfRotation's GF_MIN_VECTOR_LENGTH: a shorter axis is no rotation.
    if length <= 1e-10 {
        return BoundedMat4::exact(DMat4::IDENTITY);
    }
    let cos = Bounded::exact(q.w.clamp(-1.0, 1.0));
    let [x, y, z] = [q.x, q.y, q.z].map(Bounded::exact);
    // `DVec3::length`: the square root of the dot product, summed left to right.
    let norm = (x.mul(x) + y.mul(y) + z.mul(z)).sqrt();
    let sin = Bounded::exact(1.0).sub(cos.mul(cos)).sqrt();
    let factor = sin.div(norm);
    let v = [x, y, z].map(|c| c.mul(factor));
    BoundedMat4::trs_bounded(DVec3::ZERO, [v[0], v[1], v[2], cos], DVec3::ONE)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// usd-core 25.x: `Gf.Matrix4d(Gf.Rotation(Gf.Quatd(Gf.Quatf(0.8, 0.2, 0.4, 0.4))),
    /// Gf.Vec3d(0))`, rows (USD's row vectors: row r is where axis r goes).
    const USD_ROWS: [[f64; 3]; 3] = [
        [0.3600000339084203, 0.7999999841054275, -0.4800000010596377],
        [-0.4800000010596377, 0.6000000211927627, 0.6399999793370561],
        [
            0.7999999841054275,
            -1.3245476437884207e-08,
            0.6000000211927627,
        ],
    ];

    #[test]
    fn orient_of_a_not_quite_unit_quatf_is_usd_cores_rotation() {
        let [w, x, y, z] = [0.8f32, 0.2, 0.4, 0.4].map(f64::from);
        let m = orient_rotation(DQuat::from_xyzw(x, y, z, w)).value;
        for (r, row) in USD_ROWS.iter().enumerate() {
            for (c, &expected) in row.iter().enumerate() {
                let got = m.col(r)[c];
                assert!(
                    (got - expected).abs() <= 4e-16,
                    "[{r}][{c}] {got} vs {expected}"
                );
            }
        }
    }

    /// An inverted translation (a pivot's `!invert!`) is glam's inverse, bit for bit, and
    /// exact; any other inverted op is left unbounded.
    #[test]
    fn an_inverted_translation_is_exact_and_glams_inverse() {
        for t in [
            DVec3::new(0.1, -2.5e7, 3.0e-9),
            DVec3::new(1.0 / 3.0, 7.0, -0.7),
        ] {
            let m = DMat4::from_translation(t);
            let inverse = invert(BoundedMat4::exact(m)).unwrap();
            assert_eq!(inverse.value, m.inverse());
            assert!(inverse.is_exact());
        }
        let turned = invert(rotation_about_z(30.0)).unwrap();
        assert!(turned.error.x_axis.x.is_infinite());
    }

    fn rotation_about_z(degrees: f64) -> BoundedMat4 {
        raycast_core::bound::rotation::about_axis(2, degrees)
    }
}
