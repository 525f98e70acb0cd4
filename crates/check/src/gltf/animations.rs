//! Animations: channels, targets and sampler accessors (never read for a render).

use super::Walker;
use crate::import::gltf::document::{array, index_of};
use crate::Code;
use serde_json::Value;
use std::collections::HashSet;

impl Walker<'_, '_> {
    pub(super) fn animations(&mut self) {
        let nodes = self.list("nodes");
        for (a, anim) in self.list("animations").iter().enumerate() {
            let samplers = array(anim, "samplers");
            let mut targets = HashSet::new();
            for (c, channel) in array(anim, "channels").iter().enumerate() {
                let at = format!("/animations/{a}/channels/{c}");
                let target = channel.get("target");
                // A node that does not exist is the document layer's rule.
                let node = target.and_then(|t| index_of(t, "node"));
                if let Some(bad) = index_of(channel, "sampler").filter(|&k| k >= samplers.len()) {
                    self.f.error(
                        Code::UnresolvedReference,
                        format!("{at}/sampler"),
                        format!("sampler {bad} does not exist"),
                    );
                }
                let path = target.and_then(|t| t.get("path")).and_then(Value::as_str);
                if let (Some(node), Some(path)) = (node, path) {
                    if !targets.insert((node, path.to_string())) {
                        self.f.error(
                            Code::AnimationDuplicateTargets,
                            format!("{at}/target"),
                            "two channels animate the same property",
                        );
                    }
                    if let Some(n) = nodes.get(node) {
                        if n.get("matrix").is_some() && path != "weights" {
                            self.f.error(
                                Code::AnimationChannelTargetNodeMatrix,
                                format!("{at}/target/node"),
                                "an animated node cannot have a matrix",
                            );
                        }
                        if path == "weights" {
                            let morphs = index_of(n, "mesh")
                                .and_then(|m| self.list("meshes").get(m))
                                .is_some_and(|m| {
                                    array(m, "primitives")
                                        .iter()
                                        .any(|p| !array(p, "targets").is_empty())
                                });
                            if !morphs {
                                self.f.error(
                                    Code::AnimationChannelTargetNodeWeightsNoMorphs,
                                    format!("{at}/target/node"),
                                    "weights animated on a node without morph targets",
                                );
                            }
                        }
                    }
                }
                let Some(sampler) = index_of(channel, "sampler").and_then(|s| samplers.get(s))
                else {
                    continue;
                };
                let sat = format!(
                    "/animations/{a}/samplers/{}",
                    index_of(channel, "sampler").unwrap_or(0)
                );
                let cubic =
                    sampler.get("interpolation").and_then(Value::as_str) == Some("CUBICSPLINE");
                let input = index_of(sampler, "input");
                let output = index_of(sampler, "output");
                for acc in [input, output].into_iter().flatten() {
                    if self
                        .view_of(acc)
                        .is_some_and(|v| v.get("byteStride").is_some())
                    {
                        self.f.error(
                            Code::AnimationSamplerAccessorWithBytestride,
                            sat.clone(),
                            "animation accessors cannot use a byteStride",
                        );
                    }
                }
                let in_layout = input.and_then(|i| self.layout(i));
                if let (Some(i), Some(l)) = (input, in_layout) {
                    if l.comps != 1 || l.component != 5126 {
                        self.f.error(
                            Code::AnimationSamplerInputAccessorInvalidFormat,
                            format!("{sat}/input"),
                            "input must be SCALAR float",
                        );
                    } else {
                        let acc = &self.list("accessors")[i];
                        if acc.get("min").is_none() || acc.get("max").is_none() {
                            self.f.error(
                                Code::AnimationSamplerInputAccessorWithoutBounds,
                                format!("{sat}/input"),
                                "input needs min and max",
                            );
                        }
                        if cubic && l.count < 2 {
                            self.f.error(
                                Code::AnimationSamplerInputAccessorTooFewElements,
                                format!("{sat}/input"),
                                "CUBICSPLINE needs two keyframes",
                            );
                        }
                        if let Some(times) = self.values(i) {
                            if times.iter().any(|t| *t < 0.0) {
                                self.f.error(
                                    Code::AccessorAnimationInputNegative,
                                    format!("/accessors/{i}"),
                                    "negative key time",
                                );
                            }
                            if times.windows(2).any(|w| w[1] <= w[0]) {
                                self.f.error(
                                    Code::AccessorAnimationInputNonIncreasing,
                                    format!("/accessors/{i}"),
                                    "key times do not increase",
                                );
                            }
                        }
                    }
                }
                if let (Some(o), Some(path)) = (output, path) {
                    let Some(l) = self.layout(o) else {
                        continue;
                    };
                    let ok = match path {
                        "translation" | "scale" => {
                            l.comps == 3 && l.rows.is_none() && l.component == 5126
                        }
                        "rotation" => {
                            l.comps == 4
                                && l.rows.is_none()
                                && (l.component == 5126 || l.normalized)
                        }
                        "weights" => l.comps == 1 && (l.component == 5126 || l.normalized),
                        _ => true,
                    };
                    if !ok {
                        self.f.error(
                            Code::AnimationSamplerOutputAccessorInvalidFormat,
                            format!("{sat}/output"),
                            format!("invalid output format for {path}"),
                        );
                    }
                    if let Some(inl) = in_layout {
                        let per = if cubic { 3 } else { 1 };
                        let morphs = if path == "weights" {
                            node.and_then(|n| nodes.get(n))
                                .and_then(|n| index_of(n, "mesh"))
                                .and_then(|m| self.list("meshes").get(m))
                                .and_then(|m| array(m, "primitives").first())
                                .map_or(1, |p| array(p, "targets").len().max(1))
                        } else {
                            1
                        };
                        if l.count != inl.count * per * morphs {
                            self.f.error(
                                Code::AnimationSamplerOutputAccessorInvalidCount,
                                format!("{sat}/output"),
                                format!("{} outputs for {} inputs", l.count, inl.count),
                            );
                        }
                    }
                    if path == "rotation" && l.component == 5126 && l.comps == 4 {
                        if let Some(q) = self.values(o) {
                            let bad = q.chunks_exact(4).enumerate().any(|(k, q)| {
                                let tangent = cubic && k % 3 != 1;
                                !tangent
                                    && ((q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
                                        .sqrt()
                                        - 1.0)
                                        .abs()
                                        > super::UNIT_QUATERNION_TOLERANCE
                            });
                            if bad {
                                self.f.error(
                                    Code::AccessorAnimationSamplerOutputNonNormalizedQuaternion,
                                    format!("/accessors/{o}"),
                                    "rotation keys are not unit quaternions",
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}
