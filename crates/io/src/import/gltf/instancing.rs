//! EXT_mesh_gpu_instancing: a node drawn once per row of its TRANSLATION, ROTATION and SCALE
//! accessors. Each instance's matrix applies in the node's space: world = node world x
//! instance T x R x S.

use crate::bound::transform::BoundedMat4;
use crate::error::{Error, Result};
use glam::{DQuat, DVec3};
use serde_json::Value;

/// Extension name.
pub const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// Most instances one node may have.
const MAX_INSTANCES: usize = 1 << 24;

/// The accessors the extension names (each optional, at least one present).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InstanceAccessors {
    /// Per-instance translation (VEC3 float).
    pub translation: Option<usize>,
    /// Per-instance rotation (VEC4 float, or normalized byte or short).
    pub rotation: Option<usize>,
    /// Per-instance scale (VEC3 float).
    pub scale: Option<usize>,
}

/// Per-instance values read from the accessors.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct InstanceValues {
    /// Translations, if the extension has them.
    pub translation: Option<Vec<DVec3>>,
    /// Rotations as (x, y, z, w), if the extension has them.
    pub rotation: Option<Vec<[f64; 4]>>,
    /// Scales, if the extension has them.
    pub scale: Option<Vec<DVec3>>,
}

/// Reads the accessor indices from the node's extension object.
pub fn accessors(extension: &Value) -> Result<InstanceAccessors> {
    let attributes = extension
        .get("attributes")
        .and_then(Value::as_object)
        .ok_or_else(|| Error::msg(format!("{EXTENSION}: attributes is missing")))?;
    let index = |key: &str| -> Result<Option<usize>> {
        match attributes.get(key) {
            None => Ok(None),
            Some(v) => v
                .as_u64()
                .and_then(|v| usize::try_from(v).ok())
                .map(Some)
                .ok_or_else(|| {
                    Error::msg(format!(
                        "{EXTENSION}: attributes.{key} is not an accessor index"
                    ))
                }),
        }
    };
    let found = InstanceAccessors {
        translation: index("TRANSLATION")?,
        rotation: index("ROTATION")?,
        scale: index("SCALE")?,
    };
    if found
        .translation
        .or(found.rotation)
        .or(found.scale)
        .is_none()
    {
        return Err(Error::msg(format!(
            "{EXTENSION}: none of TRANSLATION, ROTATION, SCALE is given"
        )));
    }
    Ok(found)
}

/// The instance matrices (in the node's space), one per row, each with the bound of its
/// multiplication ([`BoundedMat4::trs`]); all given attributes must have the same count.
pub fn matrices(values: &InstanceValues) -> Result<Vec<BoundedMat4>> {
    let counts = [
        values.translation.as_ref().map(Vec::len),
        values.rotation.as_ref().map(Vec::len),
        values.scale.as_ref().map(Vec::len),
    ];
    let mut given = counts.iter().flatten();
    let count = *given
        .next()
        .ok_or_else(|| Error::msg(format!("{EXTENSION}: no instance attribute")))?;
    if given.any(|&c| c != count) {
        return Err(Error::msg(format!(
            "{EXTENSION}: attribute counts differ (TRANSLATION, ROTATION, SCALE: {counts:?})"
        )));
    }
    if count > MAX_INSTANCES {
        return Err(Error::msg(format!(
            "{EXTENSION}: {count} instances (at most {MAX_INSTANCES})"
        )));
    }
    (0..count)
        .map(|i| {
            let t = values.translation.as_ref().map_or(DVec3::ZERO, |v| v[i]);
            let s = values.scale.as_ref().map_or(DVec3::ONE, |v| v[i]);
            let r = match &values.rotation {
                None => DQuat::IDENTITY,
                Some(r) => {
                    rotation(r[i]).map_err(|e| e.context(format!("{EXTENSION}: instance {i}")))?
                }
            };
            let m = BoundedMat4::trs(t, r, s);
            if m.value.is_finite() {
                Ok(m)
            } else {
                Err(Error::msg(format!(
                    "{EXTENSION}: instance {i} has a non-finite transform"
                )))
            }
        })
        .collect()
}

/// A quaternion from stored (x, y, z, w), to be normalized as node rotations are.
fn rotation([x, y, z, w]: [f64; 4]) -> Result<DQuat> {
    let q = DQuat::from_xyzw(x, y, z, w);
    if !q.is_finite() || q.length_squared() == 0.0 {
        return Err(Error::msg(format!(
            "rotation {:?} is not a rotation",
            [x, y, z, w]
        )));
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn accessors_are_read_and_one_is_needed() {
        let ext = json!({"attributes": {"TRANSLATION": 3, "SCALE": 5}});
        let found = accessors(&ext).unwrap();
        assert_eq!(found.translation, Some(3));
        assert_eq!(found.rotation, None);
        assert_eq!(found.scale, Some(5));
        assert!(accessors(&json!({"attributes": {}})).is_err());
        assert!(accessors(&json!({"attributes": {"ROTATION": -1}})).is_err());
        assert!(accessors(&json!({})).is_err());
    }

    #[test]
    fn instance_matrix_is_translate_rotate_scale() {
        // A quarter turn about z, scale 2 along x, then a shift: (1, 0, 0) goes to
        // 2 * (0, 1, 0) + (10, 0, 0). The rotation is stored unnormalized (times 3).
        let h = 0.5f64.sqrt() * 3.0;
        let values = InstanceValues {
            translation: Some(vec![DVec3::new(10.0, 0.0, 0.0), DVec3::ZERO]),
            rotation: Some(vec![[0.0, 0.0, h, h], [0.0, 0.0, 0.0, 1.0]]),
            scale: Some(vec![DVec3::new(2.0, 1.0, 1.0), DVec3::ONE]),
        };
        let m = matrices(&values).unwrap();
        assert_eq!(m.len(), 2);
        let p = m[0].value.transform_point3(DVec3::X);
        assert!((p - DVec3::new(10.0, 2.0, 0.0)).length() < 1e-15, "{p}");
        // The identity rotation is exact; the unnormalized quarter turn is not.
        assert_eq!(m[1], BoundedMat4::exact(glam::DMat4::IDENTITY));
        assert!(!m[0].is_exact());
    }

    #[test]
    fn bad_instances_are_refused() {
        let counts_differ = InstanceValues {
            translation: Some(vec![DVec3::ZERO; 2]),
            scale: Some(vec![DVec3::ONE; 3]),
            ..Default::default()
        };
        assert!(matrices(&counts_differ).is_err());
        let zero_rotation = InstanceValues {
            rotation: Some(vec![[0.0; 4]]),
            ..Default::default()
        };
        assert!(matrices(&zero_rotation).is_err());
        let infinite = InstanceValues {
            scale: Some(vec![DVec3::new(f64::INFINITY, 1.0, 1.0)]),
            ..Default::default()
        };
        assert!(matrices(&infinite).is_err());
        assert!(matrices(&InstanceValues::default()).is_err());
    }
}
