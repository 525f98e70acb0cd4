//! Joint influences (`primvars:skel:jointIndices` / `jointWeights`) and linear blend skinning
//! with them, as usd-core's `UsdSkelSkinningQuery` and `UsdSkelSkinPointsLBS` /
//! `UsdSkelSkinTransformLBS` apply them, in f64.

use super::super::value::{self, At};
use crate::error::{Error, Result};
use glam::{DMat4, DVec3, DVec4};
use openusd::usd::Prim;

const INDICES: &str = "primvars:skel:jointIndices";
const WEIGHTS: &str = "primvars:skel:jointWeights";

/// The joint influences of one skinnable prim.
pub struct Influences {
    /// Joint index per influence, into the prim's joint order (`skel:joints`, else the
    /// skeleton's).
    indices: Vec<i64>,
    /// Weight per influence, as authored (usd-core does not normalise them).
    weights: Vec<f64>,
    /// Influences per point (the primvars' `elementSize`).
    per_point: usize,
    /// `constant` interpolation: one set of influences for the whole prim (a rigid binding).
    pub rigid: bool,
}

impl Influences {
    /// Reads the influences from the prims that author them (they are inherited down
    /// namespace); `Ok(Err(why))` when usd-core would refuse them (a warning).
    pub fn read(indices_prim: &Prim, weights_prim: &Prim, at: At) -> Result<Result<Influences>> {
        let (indices, index_size, index_interp) = primvar(indices_prim, INDICES, at)?;
        let (weights, weight_size, weight_interp) = primvar(weights_prim, WEIGHTS, at)?;
        let indices: Vec<i64> = indices.iter().map(|&x| x as i64).collect();
        if index_size != weight_size {
            return Ok(Err(Error::msg(format!(
                "jointIndices elementSize {index_size} differs from jointWeights elementSize {weight_size}"
            ))));
        }
        if index_size < 1 {
            return Ok(Err(Error::msg(format!(
                "joint influences have elementSize {index_size}"
            ))));
        }
        if index_interp != weight_interp {
            return Ok(Err(Error::msg(format!(
                "jointIndices interpolation {index_interp} differs from jointWeights interpolation {weight_interp}"
            ))));
        }
        if index_interp != "constant" && index_interp != "vertex" {
            return Ok(Err(Error::msg(format!(
                "joint influences have interpolation {index_interp} (constant or vertex)"
            ))));
        }
        let per_point = index_size as usize;
        let rigid = index_interp == "constant";
        if indices.len() != weights.len()
            || !indices.len().is_multiple_of(per_point)
            || (rigid && indices.len() != per_point)
        {
            return Ok(Err(Error::msg(format!(
                "{} jointIndices and {} jointWeights do not fit elementSize {per_point} ({index_interp})",
                indices.len(),
                weights.len()
            ))));
        }
        Ok(Ok(Influences {
            indices,
            weights,
            per_point,
            rigid,
        }))
    }

    /// Skins `points` (the prim's own, vertex influences) by `joints` (skinning transforms in the prim's joint
    /// order), after `geom_bind`: `p' = Σ w · X_j · G · p`, in the skeleton's space. `Err` names
    /// a point count that does not match or a joint index out of range (usd-core then leaves
    /// the prim unskinned).
    pub fn skin_points(
        &self,
        points: &[DVec3],
        joints: &[DMat4],
        geom_bind: DMat4,
    ) -> Result<Vec<DVec3>> {
        if self.indices.len() != points.len() * self.per_point {
            return Err(Error::msg(format!(
                "{} influences for {} points of {} each",
                self.indices.len(),
                points.len(),
                self.per_point
            )));
        }
        let mut skinned = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let bound = geom_bind.transform_point3(*p);
            let start = i * self.per_point;
            let mut sum = DVec3::ZERO;
            for k in start..start + self.per_point {
                let joint = self.joint(k, joints)?;
                let w = self.weights[k];
                if w != 0.0 {
                    sum += joint.transform_point3(bound) * w;
                }
            }
            skinned.push(sum);
        }
        Ok(skinned)
    }

    /// The transform of a rigidly bound prim in the skeleton's space (usd-core's
    /// `UsdSkelSkinTransformLBS`): `X_j · G` for one influence of weight 1, else the weighted
    /// sum of `X_j · G` with its last row reset to (0, 0, 0, 1), which is the transform usd-core
    /// rebuilds from the skinned origin and axes.
    pub fn skin_transform(&self, joints: &[DMat4], geom_bind: DMat4) -> Result<DMat4> {
        if self.per_point == 1 && (self.weights[0] - 1.0).abs() <= 1e-6 {
            return Ok(*self.joint(0, joints)? * geom_bind);
        }
        let mut sum = DMat4::ZERO;
        for k in 0..self.per_point {
            sum += (*self.joint(k, joints)? * geom_bind) * self.weights[k];
        }
        let affine = |c: DVec4| DVec4::new(c.x, c.y, c.z, 0.0);
        Ok(DMat4::from_cols(
            affine(sum.x_axis),
            affine(sum.y_axis),
            affine(sum.z_axis),
            sum.w_axis.truncate().extend(1.0),
        ))
    }

    fn joint<'a>(&self, k: usize, joints: &'a [DMat4]) -> Result<&'a DMat4> {
        let index = self.indices[k];
        usize::try_from(index)
            .ok()
            .and_then(|i| joints.get(i))
            .ok_or_else(|| {
                Error::msg(format!(
                    "joint index {index} is out of range for {} joints",
                    joints.len()
                ))
            })
    }
}

/// A primvar's flattened values (through `:indices` when it is indexed), `elementSize`
/// (fallback 1) and `interpolation` (fallback `constant`).
fn primvar(prim: &Prim, name: &str, at: At) -> Result<(Vec<f64>, i64, String)> {
    let values = value::numbers(prim, name, at)?.unwrap_or_default();
    let values = match value::ints(prim, &format!("{name}:indices"), at)? {
        None => values,
        Some(indices) => {
            let mut flat = Vec::with_capacity(indices.len());
            for i in indices {
                let v = usize::try_from(i).ok().and_then(|i| values.get(i));
                flat.push(*v.ok_or_else(|| {
                    Error::msg(format!(
                        "{}.{name}:indices: {i} is out of range",
                        prim.path()
                    ))
                })?);
            }
            flat
        }
    };
    let attribute = prim.attribute(name);
    let element_size = attribute
        .get_metadata::<openusd::sdf::Value>("elementSize")
        .map_err(|e| {
            Error::at(
                format!("{}.{name}", prim.path()),
                format!("elementSize: {e:#}"),
            )
        })?
        .and_then(|v| value::value_scalar(&v))
        .map_or(1, |x| x as i64);
    let interpolation = attribute
        .get_metadata::<openusd::sdf::Value>("interpolation")
        .map_err(|e| {
            Error::at(
                format!("{}.{name}", prim.path()),
                format!("interpolation: {e:#}"),
            )
        })?
        .and_then(|v| match v {
            openusd::sdf::Value::Token(t) => Some(t.as_str().to_string()),
            openusd::sdf::Value::String(s) => Some(s),
            _ => None,
        })
        .unwrap_or_else(|| "constant".into());
    Ok((values, element_size, interpolation))
}
