//! UsdSkel blend shapes: a skinned mesh's rest points moved by its `skel:blendShapeTargets`
//! at the weights its skeleton's animation gives, before skinning, as usd-core's
//! `UsdSkelBlendShapeQuery` (`blendShapeQuery.cpp`) and `UsdSkel.BakeSkinning` apply them.
//!
//! - The animation's `blendShapes` and `blendShapeWeights` (at the load's time code) are
//!   mapped by name onto the mesh's `skel:blendShapes`, which names its targets in order; a
//!   shape the animation does not weigh has weight 0.
//! - Each target (a BlendShape prim) has sub-shapes sorted by weight: the null shape at 0, the
//!   primary `offsets` at 1, and every `inbetweens:NAME` attribute at its `weight` metadata
//!   (an inbetween within 1e-6 of 0 or 1 is skipped, as usd-core skips it). A weight `w`
//!   between two sub-shapes weighs the lower by `1 − α` and the upper by `α`, with `α` their
//!   linear parameter; outside, the first or last two extrapolate. Without inbetweens `w` goes
//!   to the primary shape as it is. These weights are computed in f32, as usd-core computes
//!   them (its sub-shape weights are `float`), so that they are usd-core's to the bit.
//! - An offset moves the point its `pointIndices` entry names (every point in order when
//!   there are none), by offset × weight, in f64.

use super::super::err;
use super::super::value::{self, At};
use crate::error::{Error, Result};
use glam::DVec3;
use openusd::sdf::Value;
use openusd::usd::Prim;

/// usd-core's tolerance on sub-shape weights (`EPS` in blendShapeQuery.cpp).
const EPS: f64 = 1e-6;

/// One sub-shape: its weight, and its offsets (`None`: the null shape).
struct SubShape {
    weight: f32,
    offsets: Option<Vec<DVec3>>,
}

/// One target of the mesh: its sub-shapes sorted by weight, and the points they move.
struct Shape {
    subs: Vec<SubShape>,
    indices: Option<Vec<usize>>,
}

/// A mesh's blend shapes, in its `skel:blendShapes` order.
pub(super) struct BlendShapes {
    names: Vec<String>,
    /// `None` for a target that is inactive or not a BlendShape (it moves nothing).
    shapes: Vec<Option<Shape>>,
}

impl BlendShapes {
    /// The blend shapes of mesh `prim`: `Ok(None)` when it has none, `Ok(Some(Err(why)))` when
    /// usd-core would not apply them (`why` says so).
    pub fn read(prim: &Prim, at: At) -> Result<Option<Result<BlendShapes>>> {
        let Some(names) = value::tokens(prim, "skel:blendShapes", at)? else {
            return Ok(None);
        };
        let targets = prim
            .relationship("skel:blendShapeTargets")
            .targets()
            .map_err(|e| err(prim, e))?;
        if names.len() != targets.len() {
            return Ok(Some(Err(Error::msg(format!(
                "{} skel:blendShapes for {} skel:blendShapeTargets",
                names.len(),
                targets.len()
            )))));
        }
        let mut shapes = Vec::with_capacity(targets.len());
        for target in targets {
            let target = prim.stage().prim(target);
            match Shape::read(&target, at)? {
                Ok(shape) => shapes.push(shape),
                Err(why) => return Ok(Some(Err(why))),
            }
        }
        Ok(Some(Ok(BlendShapes { names, shapes })))
    }

    /// Moves `points` by the shapes at the animation's weights (`names` and `weights` in the
    /// animation's order); `Err(why)` when an offset names no point.
    pub fn apply(&self, (names, weights): (&[String], &[f32]), points: &mut [DVec3]) -> Result<()> {
        for (name, shape) in self.names.iter().zip(&self.shapes) {
            let Some(shape) = shape else { continue };
            let w = names
                .iter()
                .position(|n| n == name)
                .and_then(|k| weights.get(k))
                .copied()
                .unwrap_or(0.0);
            for (sub, weight) in sub_shape_weights(&shape.subs, w) {
                // usd-core skips a sub-shape without offsets.
                let offsets = shape.subs[sub].offsets.as_deref().unwrap_or_default();
                if !offsets.is_empty() {
                    shape.displace(offsets, f64::from(weight), points)?;
                }
            }
        }
        Ok(())
    }
}

impl Shape {
    /// The BlendShape at `prim` (`Ok(Ok(None))`: inactive, moves nothing).
    fn read(prim: &Prim, at: At) -> Result<Result<Option<Shape>>> {
        let path = prim.path();
        let type_name = prim.type_name().map_err(|e| err(prim, e))?;
        if type_name.as_deref() != Some("BlendShape") {
            return Ok(Err(Error::msg(format!(
                "skel:blendShapeTargets names {path}, which is not a BlendShape"
            ))));
        }
        if !prim.is_active().map_err(|e| err(prim, e))? {
            return Ok(Ok(None));
        }
        let primary = value::vec3s(prim, "offsets", at)?.unwrap_or_default();
        let mut subs = vec![
            SubShape {
                weight: 1.0,
                offsets: Some(primary),
            },
            SubShape {
                weight: 0.0,
                offsets: None,
            },
        ];
        subs.extend(inbetweens(prim, at)?);
        subs.sort_by(|a, b| a.weight.total_cmp(&b.weight));
        let indices = match value::ints(prim, "pointIndices", at)? {
            None => None,
            Some(ints) => match ints.iter().map(|&i| usize::try_from(i)).collect() {
                Ok(indices) => Some(indices),
                Err(_) => {
                    return Ok(Err(Error::msg(format!(
                        "{path}.pointIndices has a negative index"
                    ))))
                }
            },
        };
        Ok(Ok(Some(Shape { subs, indices })))
    }

    /// Adds `offsets × weight` to the points the shape moves.
    fn displace(&self, offsets: &[DVec3], weight: f64, points: &mut [DVec3]) -> Result<()> {
        let n = points.len();
        match &self.indices {
            None if offsets.len() == n => {
                for (p, o) in points.iter_mut().zip(offsets) {
                    *p += *o * weight;
                }
            }
            None => {
                return Err(Error::msg(format!(
                    "a blend shape has {} offsets for {n} points",
                    offsets.len()
                )))
            }
            Some(indices) if indices.len() == offsets.len() => {
                for (&i, o) in indices.iter().zip(offsets) {
                    let point = points.get_mut(i).ok_or_else(|| {
                        Error::msg(format!(
                            "a blend shape's pointIndices names point {i} of {n}"
                        ))
                    })?;
                    *point += *o * weight;
                }
            }
            Some(indices) => {
                return Err(Error::msg(format!(
                    "a blend shape has {} offsets for {} pointIndices",
                    offsets.len(),
                    indices.len()
                )))
            }
        }
        Ok(())
    }
}

/// The `inbetweens:NAME` sub-shapes of `prim` with a usable `weight`.
fn inbetweens(prim: &Prim, at: At) -> Result<Vec<SubShape>> {
    let mut subs = Vec::new();
    for name in prim.property_names().map_err(|e| err(prim, e))? {
        let name = name.as_str();
        if !name.starts_with("inbetweens:") {
            continue;
        }
        let weight = prim
            .attribute(name)
            .get_metadata::<Value>("weight")
            .map_err(|e| {
                Error::at(
                    format!("{}.{name}", prim.path()),
                    format!("cannot read its weight: {e:#}"),
                )
            })?;
        // The weight is a float (usd-core's `GetWeight(float*)`).
        let Some(weight) = weight.as_ref().and_then(value::value_scalar) else {
            continue;
        };
        let weight = weight as f32;
        let w = f64::from(weight);
        if (w - 0.0).abs() < EPS || (w - 1.0).abs() < EPS {
            continue;
        }
        let offsets = value::vec3s(prim, name, at)?.unwrap_or_default();
        subs.push(SubShape {
            weight,
            offsets: Some(offsets),
        });
    }
    Ok(subs)
}

/// usd-core's `ComputeSubShapeWeights` for one shape at weight `w`: the sub-shapes (indices
/// into `subs`, sorted by weight) and their weights, in f32 as usd-core computes them.
fn sub_shape_weights(subs: &[SubShape], w: f32) -> Vec<(usize, f32)> {
    let n = subs.len();
    if n < 3 {
        // The null shape and the primary one: the primary (weight 1) sorts last.
        return vec![(n - 1, w)];
    }
    let upper_bound = subs.partition_point(|s| s.weight <= w);
    let (lower, upper) = match upper_bound {
        i if i == n => (n - 2, n - 1),
        0 => (0, 1),
        i => (i - 1, i),
    };
    let delta = subs[upper].weight - subs[lower].weight;
    let mut out = Vec::with_capacity(2);
    if f64::from(delta) > EPS {
        let alpha = (w - subs[lower].weight) / delta;
        let alpha_d = f64::from(alpha);
        if subs[lower].offsets.is_some() && (alpha_d - 1.0).abs() >= EPS {
            out.push((lower, (1.0 - alpha_d) as f32));
        }
        if subs[upper].offsets.is_some() && alpha_d.abs() >= EPS {
            out.push((upper, alpha));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn subs(weights: &[f32]) -> Vec<SubShape> {
        weights
            .iter()
            .map(|&weight| SubShape {
                weight,
                offsets: (weight != 0.0).then(Vec::new),
            })
            .collect()
    }

    #[test]
    fn without_inbetweens_the_primary_takes_the_weight_as_it_is() {
        assert_eq!(
            sub_shape_weights(&subs(&[0.0, 1.0]), -0.75),
            vec![(1, -0.75)]
        );
        assert_eq!(sub_shape_weights(&subs(&[0.0, 1.0]), 1.5), vec![(1, 1.5)]);
    }

    #[test]
    fn an_inbetween_splits_the_weight_linearly_and_the_ends_extrapolate() {
        // Sub-shapes: null 0, inbetween 0.5, primary 1.
        let s = subs(&[0.0, 0.5, 1.0]);
        assert_eq!(sub_shape_weights(&s, 0.25), vec![(1, 0.5)]);
        assert_eq!(sub_shape_weights(&s, 0.5), vec![(1, 1.0)]);
        assert_eq!(sub_shape_weights(&s, 0.75), vec![(1, 0.5), (2, 0.5)]);
        // Past 1: the inbetween and the primary extrapolate (1 - 2, 2).
        assert_eq!(sub_shape_weights(&s, 1.5), vec![(1, -1.0), (2, 2.0)]);
        // Below 0: the null shape and the inbetween, alpha = -0.5.
        assert_eq!(sub_shape_weights(&s, -0.25), vec![(1, -0.5)]);
    }
}
