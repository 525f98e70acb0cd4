//! A UsdSkelSkeleton and its SkelAnimation: the skinning transform of every joint at a time
//! code, as usd-core's `UsdSkelSkeletonQuery::ComputeSkinningTransforms` computes it.
//!
//! Matrices are glam's column-vector form of USD's row-vector ones: USD's `A * B` is `B * A`
//! here. A joint's skeleton-space transform is its parent's times its local one; its skinning
//! transform is that times the inverse of its bind transform.

use super::super::value::{self, At};
use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use openusd::usd::Prim;

/// A skeleton's joints, read once per load.
pub struct Skeleton {
    /// Joint paths (`Shoulder/Elbow`), in the skeleton's order.
    pub joints: Vec<String>,
    /// Each joint's parent: the nearest ancestor path in `joints` (usd-core's `UsdSkelTopology`).
    parents: Vec<Option<usize>>,
    /// Inverses of `bindTransforms` (skeleton space).
    inverse_bind: Vec<DMat4>,
    /// `restTransforms` (joint-local), when authored with one matrix per joint.
    rest: Option<Vec<DMat4>>,
}

/// A SkelAnimation's joint order and where its values are read.
pub struct Animation {
    prim: Prim,
    joints: Vec<String>,
}

impl Skeleton {
    /// Reads `joints`, `bindTransforms` and `restTransforms`; `Err` is why the skeleton cannot
    /// pose anything (a warning: usd-core skins nothing with it either).
    pub fn read(prim: &Prim, at: At) -> Result<Result<Skeleton>> {
        let joints = value::tokens(prim, "joints", at)?.unwrap_or_default();
        let parents = match parents(&joints) {
            Ok(parents) => parents,
            Err(why) => return Ok(Err(why)),
        };
        let bind = value::matrices(prim, "bindTransforms", at)?.unwrap_or_default();
        if bind.len() != joints.len() {
            return Ok(Err(Error::msg(format!(
                "has {} bindTransforms for {} joints",
                bind.len(),
                joints.len()
            ))));
        }
        let mut inverse_bind = Vec::with_capacity(bind.len());
        for (m, joint) in bind.iter().zip(&joints) {
            let det = m.determinant();
            if !det.is_finite() || det == 0.0 {
                return Ok(Err(Error::msg(format!(
                    "the bind transform of joint {joint} is singular"
                ))));
            }
            inverse_bind.push(m.inverse());
        }
        let rest = value::matrices(prim, "restTransforms", at)?.filter(|r| r.len() == joints.len());
        Ok(Ok(Skeleton {
            joints,
            parents,
            inverse_bind,
            rest,
        }))
    }

    /// The skinning transform of every joint at `at`, posed by `animation` where it gives a
    /// value (its joints mapped onto the skeleton's by name) and by `restTransforms`
    /// elsewhere, as usd-core does; `Err` when neither can pose a joint.
    pub fn skinning_transforms(
        &self,
        animation: Option<&Animation>,
        at: At,
    ) -> Result<Result<Vec<DMat4>>> {
        let local = match self.local_transforms(animation, at)? {
            Ok(local) => local,
            Err(why) => return Ok(Err(why)),
        };
        let mut skel: Vec<DMat4> = Vec::with_capacity(local.len());
        for (i, m) in local.iter().enumerate() {
            let world = match self.parents[i] {
                Some(p) => skel[p] * *m,
                None => *m,
            };
            skel.push(world);
        }
        Ok(Ok(skel
            .iter()
            .zip(&self.inverse_bind)
            .map(|(s, inv)| *s * *inv)
            .collect()))
    }

    /// Joint-local transforms: usd-core's `_ComputeJointLocalTransforms`.
    fn local_transforms(
        &self,
        animation: Option<&Animation>,
        at: At,
    ) -> Result<Result<Vec<DMat4>>> {
        let no_rest = "has no restTransforms with one matrix per joint";
        let mapping: Vec<Option<usize>> = match animation {
            Some(anim) => self
                .joints
                .iter()
                .map(|j| anim.joints.iter().position(|a| a == j))
                .collect(),
            None => Vec::new(),
        };
        let animated = animation.filter(|_| mapping.iter().any(Option::is_some));
        let Some(anim) = animated else {
            return Ok(self.rest.clone().ok_or_else(|| Error::msg(no_rest)));
        };
        let sparse = mapping.iter().any(Option::is_none);
        let Some(values) = anim.local_transforms(at)? else {
            return Ok(self.rest.clone().ok_or_else(|| Error::msg(no_rest)));
        };
        let mut local = match (&self.rest, sparse) {
            (Some(rest), _) => rest.clone(),
            (None, false) => vec![DMat4::IDENTITY; self.joints.len()],
            (None, true) => {
                return Ok(Err(Error::msg(format!(
                    "{no_rest}, and its animation poses only some joints"
                ))))
            }
        };
        for (target, source) in mapping.iter().enumerate() {
            if let Some(source) = source {
                local[target] = values[*source];
            }
        }
        Ok(Ok(local))
    }
}

/// An animation's blend shape weights at a time: names and weights, in its order.
#[derive(Debug, Clone)]
pub struct BlendWeights {
    pub names: Vec<String>,
    pub weights: Vec<f32>,
}

impl Animation {
    /// The SkelAnimation at `prim`, `None` when the prim is not one.
    pub fn read(prim: &Prim, at: At) -> Result<Option<Animation>> {
        let type_name = prim.type_name().map_err(|e| super::super::err(prim, e))?;
        if type_name.as_deref() != Some("SkelAnimation") {
            return Ok(None);
        }
        let joints = value::tokens(prim, "joints", at)?.unwrap_or_default();
        Ok(Some(Animation {
            prim: prim.clone(),
            joints,
        }))
    }

    /// The animation's blend shape names and weights at `at` (`None` when it weighs none, or
    /// when the two lengths differ: usd-core's mapper then fails).
    pub fn blend_shape_weights(&self, at: At) -> Result<Option<BlendWeights>> {
        let names = value::tokens(&self.prim, "blendShapes", at)?;
        let weights = value::numbers(&self.prim, "blendShapeWeights", at)?;
        let (Some(names), Some(weights)) = (names, weights) else {
            return Ok(None);
        };
        if names.len() != weights.len() {
            return Ok(None);
        }
        // float[] values: exact in f32.
        let weights = weights.into_iter().map(|w| w as f32).collect();
        Ok(Some(BlendWeights { names, weights }))
    }

    /// The animation's joint-local transforms at `at` in its own joint order; `None` when
    /// `translations`, `rotations` and `scales` are not all there with one value per joint
    /// (usd-core then poses the rest transforms).
    fn local_transforms(&self, at: At) -> Result<Option<Vec<DMat4>>> {
        let translations = value::vec3s(&self.prim, "translations", at)?;
        let rotations = value::quats(&self.prim, "rotations", at)?;
        let scales = value::vec3s(&self.prim, "scales", at)?;
        let (Some(t), Some(r), Some(s)) = (translations, rotations, scales) else {
            return Ok(None);
        };
        let n = self.joints.len();
        if t.len() != n || r.len() != n || s.len() != n {
            return Ok(None);
        }
        Ok(Some(
            (0..n).map(|i| joint_transform(t[i], r[i], s[i])).collect(),
        ))
    }
}

/// Each joint's parent: the nearest of its ancestor paths that is a joint; an error when a
/// parent comes after its child or a path repeats (usd-core's `UsdSkelTopology::Validate`).
fn parents(joints: &[String]) -> Result<Vec<Option<usize>>> {
    let mut parents = Vec::with_capacity(joints.len());
    for (i, joint) in joints.iter().enumerate() {
        if joints[..i].contains(joint) {
            return Err(Error::msg(format!("joint {joint} is listed twice")));
        }
        let mut parent = None;
        let mut path = joint.as_str();
        while let Some(cut) = path.rfind('/') {
            path = &path[..cut];
            if let Some(p) = joints.iter().position(|j| j == path) {
                parent = Some(p);
                break;
            }
        }
        if let Some(p) = parent.filter(|&p| p > i) {
            return Err(Error::msg(format!(
                "joint {joint} comes before its parent {} (joints must list parents first)",
                joints[p]
            )));
        }
        parents.push(parent);
    }
    Ok(parents)
}

/// usd-core's `UsdSkelMakeTransform(translate, GfMatrix3f(rotate), scale)`: the rotation
/// matrix is built from the `quatf` in float (`GfMatrix3f::SetRotate`), each row scaled in
/// float by the `half` scale, then widened to double with the translation as the last row.
/// Building the rotation in double instead moves a joint by up to ~1e-8 of its length.
pub fn joint_transform(translation: DVec3, rotation: DQuat, scale: DVec3) -> DMat4 {
    let r = rotation_f32(rotation);
    let s = scale.to_array().map(|x| x as f32);
    let mut rows = [0.0f64; 16];
    for row in 0..3 {
        for col in 0..3 {
            rows[row * 4 + col] = f64::from(r[row][col] * s[row]);
        }
    }
    rows[12..15].copy_from_slice(&translation.to_array());
    rows[15] = 1.0;
    // USD's row-major, row-vector matrix is glam's column-major storage of the column form.
    DMat4::from_cols_array(&rows)
}

/// `GfMatrix3f::_SetRotateFromQuat` for a `quatf` (exact in the f64 it was widened to): sums
/// of products in float, `1.0 - 2.0 * x` in double, each entry stored as float.
fn rotation_f32(q: DQuat) -> [[f32; 3]; 3] {
    let (r, i) = (q.w as f32, [q.x as f32, q.y as f32, q.z as f32]);
    let one_minus = |s: f32| (1.0 - 2.0 * f64::from(s)) as f32;
    let twice = |s: f32| (2.0 * f64::from(s)) as f32;
    [
        [
            one_minus(i[1] * i[1] + i[2] * i[2]),
            twice(i[0] * i[1] + i[2] * r),
            twice(i[2] * i[0] - i[1] * r),
        ],
        [
            twice(i[0] * i[1] - i[2] * r),
            one_minus(i[2] * i[2] + i[0] * i[0]),
            twice(i[1] * i[2] + i[0] * r),
        ],
        [
            twice(i[2] * i[0] + i[1] * r),
            twice(i[1] * i[2] - i[0] * r),
            one_minus(i[1] * i[1] + i[0] * i[0]),
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_parents_are_the_nearest_listed_ancestors() {
        let joints = ["a", "a/b/c", "a/b/c/d", "e"].map(String::from);
        assert_eq!(
            parents(&joints).unwrap(),
            vec![None, Some(0), Some(1), None]
        );
        let misordered = ["a/b", "a"].map(String::from);
        assert!(parents(&misordered)
            .unwrap_err()
            .message
            .contains("before its parent"));
    }

    #[test]
    fn a_joint_transform_scales_rotates_then_translates() {
        let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let m = joint_transform(DVec3::new(1.0, 2.0, 3.0), q, DVec3::new(2.0, 1.0, 1.0));
        let p = m.transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-6, "{p}");
    }
}
