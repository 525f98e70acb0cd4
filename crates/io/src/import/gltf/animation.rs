//! glTF animations evaluated at one time (`--time SECONDS`): every channel of the chosen
//! animations (all of them by default) gives its target node a translation, rotation, scale or
//! morph weights in place of the node's own. Samplers: STEP, LINEAR (rotations by spherical
//! interpolation of unit quaternions) and CUBICSPLINE (Hermite, tangents times the keyframe
//! interval; rotations normalized), clamped to the first and last keyframe outside them.
//! Where two chosen animations animate the same property of a node, the first one sets it.
//! KHR_animation_pointer is not read.

use super::diagnostics::{Code, Diagnostic};
use super::document::{array, index_of, Document};
use crate::error::Error;
use glam::{DQuat, DVec3};
use serde_json::Value;
use std::collections::HashMap;

/// What the chosen animations give one node at the chosen time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Animated {
    /// Translation, when animated.
    pub translation: Option<DVec3>,
    /// Rotation (unit), when animated.
    pub rotation: Option<DQuat>,
    /// Scale, when animated.
    pub scale: Option<DVec3>,
    /// Morph weights, when animated.
    pub weights: Option<Vec<f64>>,
}

/// Every animated node's values, by node index.
pub type NodeValues = HashMap<usize, Animated>;

/// One animation as `info` lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct AnimationSummary {
    /// `name`, if any.
    pub name: Option<String>,
    /// First and last keyframe time over all its samplers (seconds).
    pub range: Option<(f64, f64)>,
    /// Number of channels.
    pub channels: usize,
}

/// How keyframes are interpolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Interpolation {
    Step,
    Linear,
    CubicSpline,
}

impl Document {
    /// The indices of the animations `choice` names (an index or a name; `None`: all).
    pub fn chosen_animations(&self, choice: Option<&str>) -> Result<Vec<usize>, Error> {
        let animations = self.list("animations");
        let Some(choice) = choice else {
            return Ok((0..animations.len()).collect());
        };
        let found = animations.iter().enumerate().find(|(i, a)| {
            choice.parse::<usize>() == Ok(*i)
                || a.get("name").and_then(Value::as_str) == Some(choice)
        });
        match found {
            Some((i, _)) => Ok(vec![i]),
            None => {
                let names: Vec<String> = animations
                    .iter()
                    .enumerate()
                    .map(|(i, a)| match a.get("name").and_then(Value::as_str) {
                        Some(name) => format!("{i} '{name}'"),
                        None => i.to_string(),
                    })
                    .collect();
                Err(Error::msg(format!(
                    "no animation '{choice}' (the file has {}: {})",
                    animations.len(),
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                )))
            }
        }
    }

    /// Name, keyframe range and channel count of every animation.
    pub fn animation_summaries(&self) -> Vec<AnimationSummary> {
        self.list("animations")
            .iter()
            .map(|a| {
                let mut range: Option<(f64, f64)> = None;
                for sampler in array(a, "samplers") {
                    let times = index_of(sampler, "input").and_then(|i| self.item("accessors", i));
                    let bound = |key: &str| {
                        times
                            .and_then(|t| t.get(key))
                            .and_then(|v| v.get(0))
                            .and_then(Value::as_f64)
                    };
                    if let (Some(lo), Some(hi)) = (bound("min"), bound("max")) {
                        range = Some(range.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))));
                    }
                }
                AnimationSummary {
                    name: a.get("name").and_then(Value::as_str).map(String::from),
                    range,
                    channels: array(a, "channels").len(),
                }
            })
            .collect()
    }

    /// The values the animations `chosen` give their target nodes at `time` seconds.
    pub fn animate(&self, chosen: &[usize], time: f64) -> Result<NodeValues, Diagnostic> {
        let mut values = NodeValues::new();
        for &a in chosen {
            let animation = &self.list("animations")[a];
            for (c, channel) in array(animation, "channels").iter().enumerate() {
                let at = format!("/animations/{a}/channels/{c}");
                let target = channel.get("target");
                let Some(node) = target.and_then(|t| index_of(t, "node")) else {
                    continue;
                };
                let path = target.and_then(|t| t.get("path")).and_then(Value::as_str);
                let entry = values.entry(node).or_default();
                let taken = match path {
                    Some("translation") => entry.translation.is_some(),
                    Some("rotation") => entry.rotation.is_some(),
                    Some("scale") => entry.scale.is_some(),
                    Some("weights") => entry.weights.is_some(),
                    _ => true,
                };
                if taken {
                    continue;
                }
                let sampler = index_of(channel, "sampler")
                    .and_then(|s| array(animation, "samplers").get(s))
                    .ok_or_else(|| {
                        Diagnostic::error(
                            Code::UnresolvedReference,
                            format!("{at}/sampler"),
                            "sampler does not exist",
                        )
                    })?;
                let width = match path {
                    Some("weights") => self.morph_target_count(node).max(1),
                    Some("rotation") => 4,
                    _ => 3,
                };
                let value = self.sample(
                    sampler,
                    width,
                    path == Some("rotation"),
                    time,
                    &format!(
                        "/animations/{a}/samplers/{}",
                        index_of(channel, "sampler").unwrap_or(0)
                    ),
                )?;
                match path {
                    Some("translation") => entry.translation = Some(DVec3::from_slice(&value)),
                    Some("scale") => entry.scale = Some(DVec3::from_slice(&value)),
                    Some("rotation") => {
                        let q = DQuat::from_slice(&value);
                        let q = if q.length_squared() > 0.0 {
                            q.normalize()
                        } else {
                            DQuat::IDENTITY
                        };
                        entry.rotation = Some(q)
                    }
                    _ => entry.weights = Some(value),
                }
            }
        }
        Ok(values)
    }

    /// Morph targets of the mesh of node `node` (0 without one).
    fn morph_target_count(&self, node: usize) -> usize {
        self.item("nodes", node)
            .and_then(|n| index_of(n, "mesh"))
            .and_then(|m| self.item("meshes", m))
            .and_then(|m| array(m, "primitives").first())
            .map_or(0, |p| array(p, "targets").len())
    }

    /// Sampler `sampler`'s value (`width` numbers) at `time`.
    fn sample(
        &self,
        sampler: &Value,
        width: usize,
        rotation: bool,
        time: f64,
        at: &str,
    ) -> Result<Vec<f64>, Diagnostic> {
        let bad = |what: String| Diagnostic::error(Code::AnimationSamplerInvalid, at, what);
        let interpolation = match sampler.get("interpolation").and_then(Value::as_str) {
            None | Some("LINEAR") => Interpolation::Linear,
            Some("STEP") => Interpolation::Step,
            Some("CUBICSPLINE") => Interpolation::CubicSpline,
            Some(other) => return Err(bad(format!("unknown interpolation {other}"))),
        };
        let input = index_of(sampler, "input").ok_or_else(|| bad("no input".into()))?;
        let output = index_of(sampler, "output").ok_or_else(|| bad("no output".into()))?;
        let (layout, times) = self.accessor_values(input).map_err(|e| e.within(at))?;
        let times: Vec<f64> = times.iter().map(|&t| layout.dequantize(t)).collect();
        let (layout, stored) = self.accessor_values(output).map_err(|e| e.within(at))?;
        let out: Vec<f64> = stored.iter().map(|&v| layout.dequantize(v)).collect();
        let per_key = if interpolation == Interpolation::CubicSpline {
            3 * width
        } else {
            width
        };
        if times.is_empty() || out.len() != times.len() * per_key {
            return Err(bad(format!(
                "{} output values for {} keyframes of {per_key}",
                out.len(),
                times.len()
            )));
        }
        if times.iter().any(|t| !t.is_finite()) || out.iter().any(|v| !v.is_finite()) {
            return Err(bad("keyframe times or values are not finite".into()));
        }
        if let Some(k) = (1..times.len()).find(|&k| times[k] <= times[k - 1]) {
            return Err(bad(format!("keyframe time {k} does not increase")));
        }
        // The value part of keyframe k.
        let value = |k: usize| -> &[f64] {
            match interpolation {
                Interpolation::CubicSpline => &out[k * per_key + width..k * per_key + 2 * width],
                _ => &out[k * width..(k + 1) * width],
            }
        };
        let last = times.len() - 1;
        if time <= times[0] {
            return Ok(value(0).to_vec());
        }
        if time >= times[last] {
            return Ok(value(last).to_vec());
        }
        // The interval [times[k], times[k + 1]) holding `time`.
        let k = times.partition_point(|&t| t <= time) - 1;
        let interval = times[k + 1] - times[k];
        let s = (time - times[k]) / interval;
        let (a, b) = (value(k), value(k + 1));
        Ok(match interpolation {
            Interpolation::Step => a.to_vec(),
            Interpolation::Linear if rotation => slerp(a, b, s),
            Interpolation::Linear => a
                .iter()
                .zip(b)
                .map(|(x, y)| x * (1.0 - s) + y * s)
                .collect(),
            Interpolation::CubicSpline => {
                let out_tangent = &out[k * per_key + 2 * width..(k + 1) * per_key];
                let in_tangent = &out[(k + 1) * per_key..(k + 1) * per_key + width];
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                (0..width)
                    .map(|c| {
                        h00 * a[c]
                            + h10 * interval * out_tangent[c]
                            + h01 * b[c]
                            + h11 * interval * in_tangent[c]
                    })
                    .collect()
            }
        })
    }
}

/// Spherical interpolation from unit quaternion `a` to `b` (x, y, z, w) by `s`, along the
/// shorter arc; nearly equal ones are interpolated linearly and normalized.
fn slerp(a: &[f64], b: &[f64], s: f64) -> Vec<f64> {
    let cos: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let dir = if cos >= 0.0 { 1.0 } else { -1.0 };
    let sqr_sin = 1.0 - cos * cos;
    let (mut wa, mut wb) = (1.0 - s, s);
    if sqr_sin > f64::EPSILON {
        let sin = sqr_sin.sqrt();
        let angle = sin.atan2(cos * dir);
        wa = (wa * angle).sin() / sin;
        wb = (wb * angle).sin() / sin;
    }
    let q: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| x * wa + y * wb * dir)
        .collect();
    if sqr_sin > f64::EPSILON {
        return q;
    }
    let length = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.iter().map(|x| x / length).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slerp_halfway_and_at_the_ends() {
        let h = 0.5f64.sqrt();
        let (a, b) = ([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, h, h]);
        let m = slerp(&a, &b, 0.5);
        let quarter = (std::f64::consts::PI / 8.0).sin();
        assert!((m[2] - quarter).abs() < 1e-15, "{m:?}");
        assert_eq!(slerp(&a, &b, 0.0), a.to_vec());
        // The shorter arc: -b is the same rotation as b.
        let nb = [0.0, 0.0, -h, -h];
        let m2 = slerp(&a, &nb, 0.5);
        assert!((m2[2] - quarter).abs() < 1e-15 && m2[3] > 0.0, "{m2:?}");
    }
}
