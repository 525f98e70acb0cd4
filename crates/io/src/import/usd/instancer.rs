//! UsdGeomPointInstancer: one object per instance, each walking its prototype under the
//! instance transform, read as usd-core's `ComputeInstanceTransformsAtTime` reads it.
//!
//! At a time code, `positions`, `orientations` (or `orientationsf`) and `scales` are read at
//! that time (interpolated), unless `velocities` or `angularVelocities` apply: then the lower
//! bracketing samples are moved on by them, as usd-core moves them (the `motion` module).

use super::motion::Motion;
use super::value::{self, At};
use super::warning_at;
use super::{err, Instance, Loader, MAX_INSTANCER_DEPTH};
use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use openusd::usd::Prim;
use raycast_core::bound::bounded::Bounded;
use raycast_core::bound::transform::BoundedMat4;
use raycast_core::diagnostic::Diagnostic;
use std::collections::HashSet;

/// The per-instance arrays of a point instancer, checked against `protoIndices`.
struct Arrays {
    indices: Vec<i64>,
    positions: Vec<DVec3>,
    orientations: Option<Vec<DQuat>>,
    scales: Option<Vec<DVec3>>,
    ids: Option<Vec<i64>>,
    /// Ids neither drawn nor counted (usd-core's `ComputeMaskAtTime`: invisible or inactive).
    hidden: HashSet<i64>,
    /// The velocities that move the instances on from their held samples, where they apply.
    motion: Option<Motion>,
}

impl Arrays {
    /// Reads the arrays at `at` (a stage of `per_second` time codes per second), and warnings
    /// into `notes`; `Ok(Err(why))` when the instancer draws nothing (a warning).
    fn read(
        prim: &Prim,
        at: At,
        per_second: f64,
        notes: &mut Vec<Diagnostic>,
    ) -> Result<Result<Arrays>> {
        let Some(indices) = value::ints(prim, "protoIndices", at)? else {
            return Ok(Err(Error::msg("has no protoIndices")));
        };
        let n = indices.len();
        let motion = match at.time() {
            Some(time) => Some(Motion::read(prim, time, n, per_second)?),
            None => None,
        };
        notes.extend(motion.iter().flat_map(|m| m.notes.iter().cloned()));
        let motion = motion.filter(Motion::applies);
        // With motion, usd-core holds every array at its lower sample.
        let at_of = |name: &str| match motion {
            Some(_) => at.held_sample(prim, name),
            None => Ok(at),
        };
        let Some(positions) = value::vec3s(prim, "positions", at_of("positions")?)? else {
            return Ok(Err(Error::msg("has no positions")));
        };
        if positions.len() != n {
            return Ok(Err(Error::msg(format!(
                "has {} positions for {n} protoIndices",
                positions.len()
            ))));
        }
        let orientations = match value::quats(prim, "orientations", at_of("orientations")?)? {
            Some(q) => Some(q),
            None => value::quats(prim, "orientationsf", at_of("orientationsf")?)?,
        };
        let scales = value::vec3s(prim, "scales", at_of("scales")?)?;
        for (what, len) in [
            ("orientations", orientations.as_ref().map(Vec::len)),
            ("scales", scales.as_ref().map(Vec::len)),
        ] {
            if let Some(len) = len.filter(|&len| len != n) {
                return Ok(Err(Error::msg(format!(
                    "has {len} {what} for {n} protoIndices"
                ))));
            }
        }
        let ids = value::ints(prim, "ids", at)?;
        if let Some(ids) = ids.as_ref().filter(|ids| ids.len() != n) {
            return Ok(Err(Error::msg(format!(
                "has {} ids for {n} protoIndices",
                ids.len()
            ))));
        }
        // usd-core's ComputeMaskAtTime: neither invisible nor deactivated ids are drawn
        let hidden: HashSet<i64> = value::ints(prim, "invisibleIds", at)?
            .unwrap_or_default()
            .into_iter()
            .chain(value::int64_list_metadata(prim, "inactiveIds")?.unwrap_or_default())
            .collect();
        Ok(Ok(Arrays {
            indices,
            positions,
            orientations,
            scales,
            ids,
            hidden,
            motion,
        }))
    }
}

impl Loader {
    /// A UsdGeomPointInstancer: each instance walks its prototype with the instance
    /// transform `world · T(position) · R(orientation) · S(scale)`, collecting its
    /// triangles into one object named `name[i]`.
    pub(super) fn point_instancer(
        &mut self,
        prim: &Prim,
        world: BoundedMat4,
        outer: &mut Option<Instance>,
        depth: usize,
    ) -> Result<()> {
        let path = prim.path().to_string();
        if depth >= MAX_INSTANCER_DEPTH {
            return Err(Error::at(path.to_string(), format!("point instancers nest deeper than {MAX_INSTANCER_DEPTH} (a prototype instancing itself?)")));
        }
        let targets = prim
            .relationship("prototypes")
            .targets()
            .map_err(|e| err(prim, e))?;
        let targets: Vec<Prim> = targets.into_iter().map(|t| self.stage.prim(t)).collect();
        // Prototypes under their instancer are drawn only through it.
        for target in &targets {
            let target_path = target.path().to_string();
            if target_path.starts_with(&format!("{path}/")) {
                self.excluded.insert(target_path);
            }
        }
        let per_second = self.stage.time_codes_per_second();
        let arrays = match Arrays::read(prim, self.at, per_second, &mut self.warnings)? {
            Ok(arrays) => arrays,
            Err(why) => {
                self.warnings.push(super::warning_because(
                    path.to_string(),
                    &why,
                    format!("point instancer {why}: nothing drawn"),
                ));
                return Ok(());
            }
        };
        let Arrays {
            indices,
            positions,
            orientations,
            scales,
            ids,
            hidden,
            motion,
        } = arrays;
        let n = indices.len();
        let base_name = Self::object_name(prim, outer);
        let mut bad_index = 0usize;
        for i in 0..n {
            let id = ids.as_ref().map_or(i as i64, |ids| ids[i]);
            if hidden.contains(&id) {
                continue;
            }
            let Some(target) = usize::try_from(indices[i])
                .ok()
                .and_then(|k| targets.get(k))
            else {
                bad_index += 1;
                continue;
            };
            // As usd-core's ComputeInstanceTransformsAtTime: the quaternion goes into the
            // rotation formula as stored, not normalised (half-precision orientations are a
            // little off unit length, and usd-core places them so).
            let rotation = orientations
                .as_ref()
                .map(|q| q[i])
                .filter(|q| q.is_finite())
                .unwrap_or(glam::DQuat::IDENTITY);
            let scale = scales.as_ref().map_or(DVec3::ONE, |s| s[i]);
            // Velocities' f32 steps are not analysed: a moved instance is not bounded.
            let local = match &motion {
                Some(motion) => {
                    BoundedMat4::unbounded(motion.instance(i, positions[i], rotation, scale))
                }
                None => stored_trs(positions[i], rotation, scale),
            };
            let instance_world = world.then_bounded(&local);
            // Nested in an outer instance, this instance draws into the outer one's object.
            let mut inner = Some(match outer {
                Some(outer) => Instance {
                    name: outer.name.clone(),
                    root: target.path().to_string(),
                    source: outer.source.clone(),
                    object: outer.object,
                },
                None => Instance {
                    name: format!("{base_name}[{i}]"),
                    root: target.path().to_string(),
                    source: path.clone(),
                    object: None,
                },
            });
            self.walk(target, instance_world, None, None, &mut inner, depth + 1)?;
            if let (Some(outer), Some(inner)) = (outer.as_mut(), inner) {
                outer.object = inner.object;
            }
        }
        if bad_index > 0 {
            self.warnings.push(warning_at(
                path.to_string(),
                format!("{bad_index} instances have a protoIndex with no prototype: skipped"),
            ));
        }
        Ok(())
    }
}

/// An instance's `T(position)·R(orientation)·S(scale)` as glam's
/// `from_scale_rotation_translation` computes it, the rotation formula on the quaternion as
/// stored, with its bound ([`BoundedMat4::trs_as_given`]; for the `error` and `certain` AOVs).
fn stored_trs(position: DVec3, rotation: DQuat, scale: DVec3) -> BoundedMat4 {
    if rotation == DQuat::IDENTITY {
        // Products with 0 and 1: exact.
        return BoundedMat4::exact(DMat4::from_scale_rotation_translation(
            scale, rotation, position,
        ));
    }
    BoundedMat4::trs_as_given(position, rotation.to_array().map(Bounded::exact), scale)
}
