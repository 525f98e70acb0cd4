//! A PointInstancer's motion attributes at a time code, applied as usd-core's
//! `ComputeInstanceTransformsAtTime(time, time)` applies them (`samplingUtils.cpp`'s
//! `UsdGeom_GetPositionsVelocitiesAndAccelerations` and
//! `UsdGeom_GetOrientationsAndAngularVelocities`, `pointInstancer.cpp`'s
//! `_DoComputeInstanceTransformsAtTime`).
//!
//! Each attribute is read at the lower of its time samples bracketing the time (the default
//! time code when it has none). `velocities` apply when `positions` and `velocities` both have
//! samples, bracket the time by the same pair of samples (at a sample, the pair after it),
//! were read at the same sample and have one value per position; `accelerations` apply
//! likewise over `velocities`, and `angularVelocities` over `orientations`. When any applies,
//! usd-core draws the lower samples moved on by `dt = (time − sample) / timeCodesPerSecond`
//! instead of interpolating them: `positions` and `scales` and `orientations` are all held at
//! their lower samples, an instance is translated to `p + dt·(v + dt·a/2)` (computed, as
//! usd-core computes it, in f32: `GfVec3f` arithmetic) and turned, after its orientation, by
//! `dt·|ω|` degrees about `ω`. Outside the samples `dt` is negative or past the last sample,
//! and the motion extrapolates, as usd-core's does.

use super::value::{self, At};
use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use openusd::usd::{Prim, TimeCode};
use raycast_core::diagnostic::Diagnostic;

/// usd-core's `UsdTimeCode::SafeStep()`: the step past a sample at which its bracketing pair
/// is looked up again (`1e6 · ε · 10`).
const SAFE_STEP: f64 = 1e6 * f64::EPSILON * 10.0;

/// Where usd-core reads an attribute for motion: the sample read and the bracketing pair its
/// alignment is checked on.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bracket {
    sample: f64,
    lower: f64,
    upper: f64,
}

/// The bracket of `prim.name` at `time` (usd-core's `_GetAttrForTransforms`); `None` when the
/// attribute has no time samples.
fn bracket(prim: &Prim, name: &str, time: f64) -> Result<Option<Bracket>> {
    let read = |t: f64| {
        prim.attribute(name)
            .bracketing_time_samples(TimeCode::new(t))
            .map_err(|e| {
                Error::at(
                    format!("{}.{name}", prim.path()),
                    format!("cannot read its time samples: {e:#}"),
                )
            })
    };
    let Some((lower, upper)) = read(time)? else {
        return Ok(None);
    };
    let sample = lower;
    let (lower, upper) = if close(lower, upper) {
        read(time + SAFE_STEP)?.unwrap_or((lower, upper))
    } else {
        (lower, upper)
    };
    Ok(Some(Bracket {
        sample,
        lower,
        upper,
    }))
}

/// usd-core's `GfIsClose(a, b, ε)` on time values.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < f64::EPSILON
}

/// Whether `b` is read where `a` is (usd-core's `_CheckSampleAlignment`).
fn aligned(a: &Bracket, b: &Bracket) -> bool {
    close(a.lower, b.lower) && close(a.upper, b.upper) && close(a.sample, b.sample)
}

/// One rate attribute (`velocities`, `angularVelocities`) that applies, with the seconds since
/// its sample.
#[derive(Debug)]
struct Rate {
    values: Vec<DVec3>,
    seconds: f64,
}

/// The motion a point instancer's attributes apply at a time code.
#[derive(Debug)]
pub(super) struct Motion {
    velocities: Option<Rate>,
    accelerations: Option<Vec<DVec3>>,
    angular: Option<Rate>,
    /// usd-core's warnings about rates it left out (misaligned samples, wrong lengths).
    pub notes: Vec<Diagnostic>,
}

impl Motion {
    /// The motion at time code `time` for `n` instances (`None` when nothing applies: usd-core
    /// then interpolates the samples). `per_second` is the stage's `timeCodesPerSecond`.
    pub fn read(prim: &Prim, time: f64, n: usize, per_second: f64) -> Result<Motion> {
        let mut notes = Vec::new();
        let orientations = if value::raw(prim, "orientations", At::new(Some(time)))?.is_some() {
            "orientations"
        } else {
            "orientationsf"
        };
        let mut read = |names| rate(prim, names, (time, per_second), n, &mut notes);
        let velocities = read(("velocities", "positions"))?;
        let angular = read(("angularVelocities", orientations))?;
        let accelerations = match &velocities {
            Some(_) => read(("accelerations", "velocities"))?.map(|r| r.values),
            None => None,
        };
        Ok(Motion {
            velocities,
            accelerations,
            angular,
            notes,
        })
    }

    /// Whether any rate applies (usd-core then holds the samples instead of interpolating).
    pub fn applies(&self) -> bool {
        self.velocities.is_some() || self.angular.is_some()
    }

    /// Instance `i`'s transform (before the instancer's world transform) from its held
    /// position, orientation and scale, moved on by the rates.
    pub fn instance(&self, i: usize, position: DVec3, rotation: DQuat, scale: DVec3) -> DMat4 {
        let local = DMat4::from_scale_rotation_translation(scale, rotation, DVec3::ZERO);
        let turned = match &self.angular {
            Some(rate) => DMat4::from_quat(spin(rate.values[i], rate.seconds)) * local,
            None => local,
        };
        let translation = match &self.velocities {
            Some(rate) => {
                let a = self.accelerations.as_ref().map(|a| a[i]);
                moved_f32(position, rate.values[i], a, rate.seconds)
            }
            None => position,
        };
        DMat4::from_translation(translation) * turned
    }
}

/// The rotation by `seconds · |ω|` degrees about `ω` (`GfRotation(ω, dt·|ω|)`, the length
/// taken in f32 as `GfVec3f::GetLength`).
fn spin(omega: DVec3, seconds: f64) -> DQuat {
    let w = omega.as_vec3();
    let length = (w.x * w.x + w.y * w.y + w.z * w.z).sqrt();
    if length == 0.0 {
        return DQuat::IDENTITY;
    }
    let degrees = seconds * f64::from(length);
    DQuat::from_axis_angle(omega.normalize(), degrees.to_radians())
}

/// `p + dt·(v + dt·a·½)` as usd-core computes it with `GfVec3f`: every product of a double
/// and a float rounded to f32, every sum of floats in f32.
fn moved_f32(p: DVec3, v: DVec3, a: Option<DVec3>, dt: f64) -> DVec3 {
    let scaled = |x: f32| (dt * f64::from(x)) as f32;
    let component = |p: f64, v: f64, a: Option<f64>| {
        let mut velocity = v as f32;
        if let Some(a) = a {
            velocity += scaled(a as f32) * 0.5;
        }
        f64::from(p as f32 + scaled(velocity))
    };
    DVec3::new(
        component(p.x, v.x, a.map(|a| a.x)),
        component(p.y, v.y, a.map(|a| a.y)),
        component(p.z, v.z, a.map(|a| a.z)),
    )
}

/// The rate `names.0` over `names.1` (its base attribute) at `time` (with the stage's time
/// codes per second), if it applies; where usd-core leaves an authored one out with a warning,
/// a note says why.
fn rate(
    prim: &Prim,
    (name, over): (&str, &str),
    (time, per_second): (f64, f64),
    n: usize,
    notes: &mut Vec<Diagnostic>,
) -> Result<Option<Rate>> {
    let Some(base) = bracket(prim, over, time)? else {
        return Ok(None);
    };
    let own = bracket(prim, name, time)?;
    let read_at = own.map(|own| own.sample);
    let Some(values) = value::vec3s(prim, name, At::new(read_at))?.filter(|v| !v.is_empty()) else {
        return Ok(None);
    };
    let path = prim.path();
    let Some(own) = own.filter(|own| aligned(&base, own)) else {
        notes.push(super::warning_at(
            path.to_string(),
            format!(
                "{name} samples are not aligned with {over} samples: not applied (as usd-core)"
            ),
        ));
        return Ok(None);
    };
    if values.len() != n {
        notes.push(super::warning_at(
            path.to_string(),
            format!(
                "found {} {name}, but expected {n}: not applied (as usd-core)",
                values.len()
            ),
        ));
        return Ok(None);
    }
    let seconds = (time - own.sample) / per_second;
    Ok(Some(Rate { values, seconds }))
}
