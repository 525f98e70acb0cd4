//! Reading typed values out of composed `openusd` attributes.
//!
//! Every reader returns `Ok(None)` when the attribute has no authored default value (openusd
//! has no schema registry, so the caller applies USD's fallback), and an error naming the
//! attribute when the authored value has a type that cannot mean what the schema says.
//! Values are read at the time an [`At`] carries: `--time CODE` resolves time samples as
//! usd-core's `UsdAttribute::Get(time)` does (openusd interpolates them with usd-core's
//! arithmetic, vendor/openusd/PATCHES.md); without it, at the default time code, as usd-core
//! does for `UsdTimeCode::Default()`: an attribute with time samples but no default value
//! reads as unauthored.

use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use openusd::sdf::Value;
use openusd::usd::{Prim, TimeCode};
use raycast_core::diagnostic::Code;

/// When attribute values are read: a time code, or the default time code (`None`).
#[derive(Debug, Clone, Copy)]
pub struct At {
    time: Option<f64>,
}

impl At {
    /// Reads at `time` (`None`: the default time code).
    pub fn new(time: Option<f64>) -> Self {
        At { time }
    }

    /// The time code, `None` for the default time code.
    pub fn time(&self) -> Option<f64> {
        self.time
    }

    /// The lower of `prim.name`'s time samples bracketing the time (usd-core's
    /// `_GetAttrForTransforms`, where velocities move a PointInstancer's positions on from);
    /// the default time code when the attribute has no samples or no time is chosen.
    pub fn held_sample(self, prim: &Prim, name: &str) -> Result<At> {
        let Some(time) = self.time else {
            return Ok(self);
        };
        let lower = prim
            .attribute(name)
            .bracketing_time_samples(TimeCode::new(time))
            .map_err(|e| {
                Error::at(
                    format!("{}.{name}", prim.path()),
                    format!("cannot read its time samples: {e:#}"),
                )
            })?
            .map(|(lower, _)| lower);
        Ok(At { time: lower })
    }
}

/// Result of a value read: the message names the attribute.
pub type ValueResult<T> = Result<Option<T>>;

/// The raw composed value of `prim.name` at `at`, `None` when unauthored or blocked.
pub fn raw(prim: &Prim, name: &str, at: At) -> ValueResult<Value> {
    let attribute = prim.attribute(name);
    let value = match at.time {
        None => attribute.get::<Value>(),
        Some(time) => attribute.get_at::<Value>(TimeCode::new(time)),
    }
    .map_err(|e| {
        Error::at(
            format!("{}.{name}", prim.path()),
            format!("cannot be read: {e}"),
        )
        .with_code(Code::UsdUnreadableValue)
    })?;
    Ok(value.filter(|v| !matches!(v, Value::ValueBlock | Value::None)))
}

/// True when `prim.name` has time samples (used to explain an unauthored default).
pub fn has_time_samples(prim: &Prim, name: &str) -> bool {
    prim.attribute(name).num_time_samples().is_ok_and(|n| n > 0)
}

fn wrong_type(prim: &Prim, name: &str, expected: &str, value: &Value) -> Error {
    Error::at(
        format!("{}.{name}", prim.path()),
        format!("expected {expected}, found {}", value_kind(value)),
    )
}

/// A short description of a value's type for error messages.
pub fn value_kind(value: &Value) -> String {
    let debug = format!("{value:?}");
    let name: String = debug
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    if name.is_empty() {
        "a value of another type".into()
    } else {
        name
    }
}

/// A scalar number (double, float, half or integer).
pub fn scalar(prim: &Prim, name: &str, at: At) -> ValueResult<f64> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    let x = match &value {
        Value::Double(x) => *x,
        Value::Float(x) => *x as f64,
        Value::Half(x) => x.to_f64(),
        Value::Int(x) => *x as f64,
        Value::Int64(x) => *x as f64,
        Value::Uint(x) => *x as f64,
        _ => return Err(wrong_type(prim, name, "a number", &value)),
    };
    Ok(Some(x))
}

/// A token (or string) value.
pub fn token(prim: &Prim, name: &str, at: At) -> ValueResult<String> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value {
        Value::Token(t) => Ok(Some(t.as_str().to_string())),
        Value::String(s) => Ok(Some(s)),
        other => Err(wrong_type(prim, name, "a token", &other)),
    }
}

/// A three-component vector of any precision.
pub fn vec3(prim: &Prim, name: &str, at: At) -> ValueResult<DVec3> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value_vec3(&value) {
        Some(v) => Ok(Some(v)),
        None => Err(wrong_type(prim, name, "a 3-vector", &value)),
    }
}

/// Converts a 3-vector value of any precision.
pub fn value_vec3(value: &Value) -> Option<DVec3> {
    Some(match value {
        Value::Vec3d(v) => DVec3::new(v.x, v.y, v.z),
        Value::Vec3f(v) => DVec3::new(v.x as f64, v.y as f64, v.z as f64),
        Value::Vec3h(v) => DVec3::new(v.x.to_f64(), v.y.to_f64(), v.z.to_f64()),
        Value::Vec3i(v) => DVec3::new(v.x as f64, v.y as f64, v.z as f64),
        _ => return None,
    })
}

/// A scalar value of any numeric type, for op values.
pub fn value_scalar(value: &Value) -> Option<f64> {
    Some(match value {
        Value::Double(x) => *x,
        Value::Float(x) => *x as f64,
        Value::Half(x) => x.to_f64(),
        Value::Int(x) => *x as f64,
        Value::Int64(x) => *x as f64,
        _ => return None,
    })
}

/// A quaternion value of any precision, `(w, x, y, z)` in USD, as a glam quaternion.
pub fn value_quat(value: &Value) -> Option<DQuat> {
    Some(match value {
        Value::Quatd(q) => DQuat::from_xyzw(q.x, q.y, q.z, q.w),
        Value::Quatf(q) => DQuat::from_xyzw(q.x as f64, q.y as f64, q.z as f64, q.w as f64),
        Value::Quath(q) => DQuat::from_xyzw(q.x.to_f64(), q.y.to_f64(), q.z.to_f64(), q.w.to_f64()),
        _ => return None,
    })
}

/// A `matrix4d` value as a column-vector glam matrix. USD stores matrices row-major for row
/// vectors (`p' = p M`, translation in the last row), which is exactly glam's column-major
/// storage of the column-vector matrix `Mᵀ`.
pub fn value_matrix4(value: &Value) -> Option<DMat4> {
    match value {
        Value::Matrix4d(m) => Some(DMat4::from_cols_array(&m.0)),
        _ => None,
    }
}

/// An array of `matrix4d` values as column-vector glam matrices (see [`value_matrix4`]).
pub fn matrices(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<DMat4>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value {
        Value::Matrix4dVec(v) => Ok(Some(
            v.iter().map(|m| DMat4::from_cols_array(&m.0)).collect(),
        )),
        other => Err(wrong_type(prim, name, "a matrix4d[]", &other)),
    }
}

/// A `matrix4d` value as a column-vector glam matrix.
pub fn matrix(prim: &Prim, name: &str, at: At) -> ValueResult<DMat4> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value_matrix4(&value) {
        Some(m) => Ok(Some(m)),
        None => Err(wrong_type(prim, name, "a matrix4d", &value)),
    }
}

/// An array of tokens (or strings).
pub fn tokens(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<String>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value {
        Value::TokenVec(v) => Ok(Some(v.iter().map(|t| t.as_str().to_string()).collect())),
        Value::StringVec(v) => Ok(Some(v)),
        other => Err(wrong_type(prim, name, "a token[]", &other)),
    }
}

/// True when `prim.name` has an authored value: a default or time samples (usd-core's
/// `HasAuthoredValue`).
pub fn is_authored(prim: &Prim, name: &str) -> Result<bool> {
    Ok(raw(prim, name, At::new(None))?.is_some() || has_time_samples(prim, name))
}

/// A `matrix3d` value as its nine entries, row-major (as written in the file).
pub fn matrix3_rows(prim: &Prim, name: &str, at: At) -> ValueResult<[f64; 9]> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    match value {
        Value::Matrix3d(m) => Ok(Some(m.0)),
        other => Err(wrong_type(prim, name, "a matrix3d", &other)),
    }
}

/// An array of numbers of any numeric type.
pub fn numbers(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<f64>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    let list: Vec<f64> = match &value {
        Value::DoubleVec(v) => v.clone(),
        Value::FloatVec(v) => v.iter().map(|&x| x as f64).collect(),
        Value::HalfVec(v) => v.iter().map(|x| x.to_f64()).collect(),
        Value::IntVec(v) => v.iter().map(|&x| x as f64).collect(),
        Value::Int64Vec(v) => v.iter().map(|&x| x as f64).collect(),
        _ => return Err(wrong_type(prim, name, "an array of numbers", &value)),
    };
    Ok(Some(list))
}

/// An array of integers (`int[]`, `int64[]`, `uint[]`).
pub fn ints(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<i64>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    let list: Vec<i64> = match &value {
        Value::IntVec(v) => v.iter().map(|&x| x as i64).collect(),
        Value::Int64Vec(v) => v.clone(),
        Value::UintVec(v) => v.iter().map(|&x| x as i64).collect(),
        Value::Uint64Vec(v) => v.iter().map(|&x| x as i64).collect(),
        _ => return Err(wrong_type(prim, name, "an array of integers", &value)),
    };
    Ok(Some(list))
}

/// An array of 3-vectors of any precision (`point3f[]`, `double3[]`, `half3[]`, ...).
pub fn vec3s(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<DVec3>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    let list: Vec<DVec3> = match &value {
        Value::Vec3fVec(v) => v
            .iter()
            .map(|p| DVec3::new(p.x as f64, p.y as f64, p.z as f64))
            .collect(),
        Value::Vec3dVec(v) => v.iter().map(|p| DVec3::new(p.x, p.y, p.z)).collect(),
        Value::Vec3hVec(v) => v
            .iter()
            .map(|p| DVec3::new(p.x.to_f64(), p.y.to_f64(), p.z.to_f64()))
            .collect(),
        Value::Vec3iVec(v) => v
            .iter()
            .map(|p| DVec3::new(p.x as f64, p.y as f64, p.z as f64))
            .collect(),
        _ => return Err(wrong_type(prim, name, "an array of 3-vectors", &value)),
    };
    Ok(Some(list))
}

/// An array of quaternions of any precision.
pub fn quats(prim: &Prim, name: &str, at: At) -> ValueResult<Vec<DQuat>> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    let list: Vec<DQuat> = match &value {
        Value::QuathVec(v) => v
            .iter()
            .map(|q| DQuat::from_xyzw(q.x.to_f64(), q.y.to_f64(), q.z.to_f64(), q.w.to_f64()))
            .collect(),
        Value::QuatfVec(v) => v
            .iter()
            .map(|q| DQuat::from_xyzw(q.x as f64, q.y as f64, q.z as f64, q.w as f64))
            .collect(),
        Value::QuatdVec(v) => v
            .iter()
            .map(|q| DQuat::from_xyzw(q.x, q.y, q.z, q.w))
            .collect(),
        _ => return Err(wrong_type(prim, name, "an array of quaternions", &value)),
    };
    Ok(Some(list))
}

/// A 2-vector of any precision (camera `clippingRange`).
pub fn vec2(prim: &Prim, name: &str, at: At) -> ValueResult<[f64; 2]> {
    let Some(value) = raw(prim, name, at)? else {
        return Ok(None);
    };
    Ok(Some(match &value {
        Value::Vec2f(v) => [v.x as f64, v.y as f64],
        Value::Vec2d(v) => [v.x, v.y],
        Value::Vec2h(v) => [v.x.to_f64(), v.y.to_f64()],
        _ => return Err(wrong_type(prim, name, "a 2-vector", &value)),
    }))
}

/// The composed `int64listop` metadata `name` of `prim` (a PointInstancer's `inactiveIds`):
/// each layer's opinion on the prim stack applied over the weaker ones, as usd-core composes
/// list ops. A text layer's explicit form (`inactiveIds = [3, 7]`) may come back from openusd
/// as a plain integer array: that replaces the weaker opinions, as an explicit list op does.
/// `Ok(None)` when no layer authors it.
pub fn int64_list_metadata(prim: &Prim, name: &str) -> ValueResult<Vec<i64>> {
    let stack = prim.prim_stack().map_err(|e| {
        Error::at(
            prim.path().to_string(),
            format!("cannot read its prim stack: {e:#}"),
        )
    })?;
    let mut composed: Option<Vec<i64>> = None;
    for (layer, path) in stack.iter().rev() {
        let Some(layer) = prim.stage().layer(layer) else {
            continue;
        };
        let value = layer.data().try_field(path, name).map_err(|e| {
            Error::at(
                prim.path().to_string(),
                format!("metadata {name} cannot be read: {e}"),
            )
        })?;
        let Some(value) = value else {
            continue;
        };
        let weaker = composed.take().unwrap_or_default();
        composed = Some(match &*value {
            Value::Int64ListOp(op) => op.compose_over(&weaker),
            Value::IntVec(v) => v.iter().map(|&x| x as i64).collect(),
            Value::Int64Vec(v) => v.clone(),
            other => {
                return Err(Error::at(
                    prim.path().to_string(),
                    format!(
                        "metadata {name}: expected an int64 list op, found {}",
                        value_kind(other)
                    ),
                ))
            }
        });
    }
    Ok(composed)
}
