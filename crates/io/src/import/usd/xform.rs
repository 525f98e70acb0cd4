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

use super::value::{self, value_matrix4, value_quat, value_scalar, value_vec3, At};
use super::warning_at;
use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use openusd::sdf::Value;
use openusd::usd::Prim;
use raycast_core::diagnostic::{Code, Diagnostic};

const INVERT: &str = "!invert!";
const RESET: &str = "!resetXformStack!";

/// A prim's local transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Local {
    /// Local-to-parent matrix (column vectors).
    pub matrix: DMat4,
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
                matrix: DMat4::IDENTITY,
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
    let mut matrix = DMat4::IDENTITY;
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
        matrix *= op;
    }
    if !matrix.is_finite() {
        return Err(Error::at(
            prim.path().to_string(),
            "the local transform is not finite",
        ));
    }
    Ok(Local { matrix, resets })
}

/// Inverse of an op matrix, `None` when it is singular.
fn invert(m: DMat4) -> Option<DMat4> {
    let det = m.determinant();
    let scale =
        m.x_axis.truncate().length() * m.y_axis.truncate().length() * m.z_axis.truncate().length();
    (det.is_finite() && det.abs() > 1e-300 && det.abs() > 1e-14 * scale).then(|| m.inverse())
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
) -> Result<Option<DMat4>> {
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
    let rx = |deg: f64| DMat4::from_rotation_x(deg.to_radians());
    let ry = |deg: f64| DMat4::from_rotation_y(deg.to_radians());
    let rz = |deg: f64| DMat4::from_rotation_z(deg.to_radians());
    let matrix = match kind {
        "translate" => DMat4::from_translation(vector()?),
        "translateX" => DMat4::from_translation(DVec3::X * scalar()?),
        "translateY" => DMat4::from_translation(DVec3::Y * scalar()?),
        "translateZ" => DMat4::from_translation(DVec3::Z * scalar()?),
        "scale" => DMat4::from_scale(vector()?),
        "scaleX" => DMat4::from_scale(DVec3::new(scalar()?, 1.0, 1.0)),
        "scaleY" => DMat4::from_scale(DVec3::new(1.0, scalar()?, 1.0)),
        "scaleZ" => DMat4::from_scale(DVec3::new(1.0, 1.0, scalar()?)),
        "rotateX" => rx(scalar()?),
        "rotateY" => ry(scalar()?),
        "rotateZ" => rz(scalar()?),
        // `rotateXYZ` rotates about X first, then Y, then Z: R = Rz·Ry·Rx for column vectors.
        "rotateXYZ" | "rotateXZY" | "rotateYXZ" | "rotateYZX" | "rotateZXY" | "rotateZYX" => {
            let angles = vector()?;
            let mut m = DMat4::IDENTITY;
            for axis in kind["rotate".len()..].chars() {
                let r = match axis {
                    'X' => rx(angles.x),
                    'Y' => ry(angles.y),
                    _ => rz(angles.z),
                };
                m = r * m;
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
            DMat4::from_quat(orient_rotation(q))
        }
        "transform" => value_matrix4(&raw).ok_or_else(|| bad("a matrix4d"))?,
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
fn orient_rotation(q: DQuat) -> DQuat {
    let axis = glam::DVec3::new(q.x, q.y, q.z);
    let length = axis.length();
    // GfRotation's GF_MIN_VECTOR_LENGTH: a shorter axis is no rotation.
    if length <= 1e-10 {
        return DQuat::IDENTITY;
    }
    let cos = q.w.clamp(-1.0, 1.0);
    let v = axis * ((1.0 - cos * cos).sqrt() / length);
    DQuat::from_xyzw(v.x, v.y, v.z, cos).normalize()
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
        let m = DMat4::from_quat(orient_rotation(DQuat::from_xyzw(x, y, z, w)));
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
}
