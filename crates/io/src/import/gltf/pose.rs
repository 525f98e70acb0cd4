//! The static pose a file describes when no animation plays: morph targets at their default
//! weights and skinned meshes placed by their joints (glTF 2.0 §3.7.2.2 and §3.7.3).
//!
//! - Morph targets: a vertex is `base + Σ_t w_t · delta_t` over the primitive's targets'
//!   POSITION deltas (float, or normalized or plain 8/16-bit integers, sparse or not), with
//!   the node's `weights`, else the mesh's; missing weights are 0.
//! - Skins: a vertex is `Σ_sets Σ_k w_k · (G_k · IBM_k) · v` over every `JOINTS_n` /
//!   `WEIGHTS_n` pair, with `G_k` the global transform of joint `k`'s node, `IBM_k` its inverse
//!   bind matrix (identity without `inverseBindMatrices`) and the weights as stored
//!   (normalized integers decoded, never renormalized). The skinned mesh node's own transform
//!   is ignored, as the specification says: the posed vertices are in world space.
//!
//! Everything is computed in f64 from the file's numbers. A primitive read from Draco data
//! reads its joints and weights from that data, and its morph targets from their accessors,
//! in the decoded vertex order (as three.js's GLTFLoader does).

use super::animation::NodeValues;
use super::decode;
use super::diagnostics::{Code, Diagnostic, FailFast};
use super::document::{array, as_index, index_of, numbers, Document};
use super::geometry::Geometry;
use super::node::animated_transform;
use crate::scene::{AnimationInfo, PoseInfo};
use glam::{DMat4, DVec3};
use serde_json::Value;

/// How one node's mesh is posed; `None` fields leave that step out.
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    /// Morph weights, when any is not zero.
    pub weights: Option<Vec<f64>>,
    /// Joint matrices `G_k · IBM_k` of the node's skin, when it has one.
    pub joints: Option<Vec<DMat4>>,
}

impl Pose {
    /// True when the pose moves no vertex (the rest shape under the node's transform).
    pub fn is_rest(&self) -> bool {
        self.weights.is_none() && self.joints.is_none()
    }
}

/// Each vertex's four joint indices and weights of one influence set.
type Influences = Vec<([f64; 4], [f64; 4])>;

/// Most skin influence sets (`JOINTS_n`) read per primitive.
const MAX_SETS: usize = 64;

impl Document {
    /// The morph weights of `node` drawing mesh `mesh`: `animated` (what an animation gives
    /// it), else the node's `weights`, else the mesh's; `None` when the mesh has no morph
    /// targets or every weight is 0.
    pub fn morph_weights(
        &self,
        node: &Value,
        mesh: usize,
        animated: Option<&[f64]>,
    ) -> Option<Vec<f64>> {
        let json = self.item("meshes", mesh)?;
        let has_targets = array(json, "primitives")
            .iter()
            .any(|p| !array(p, "targets").is_empty());
        if !has_targets {
            return None;
        }
        let weights = match animated {
            Some(weights) => weights.to_vec(),
            None => numbers(node, "weights").or_else(|| numbers(json, "weights"))?,
        };
        weights.iter().any(|&w| w != 0.0).then_some(weights)
    }

    /// The global transform of every node, by index, through its parents (`None` for a node
    /// in a cycle), with what the applied animations give the nodes. Fails on a node transform
    /// that is not valid or not finite.
    pub fn global_transforms(
        &self,
        animated: &NodeValues,
    ) -> Result<Vec<Option<DMat4>>, Diagnostic> {
        let nodes = self.list("nodes");
        let mut parent = vec![None; nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            for child in array(node, "children").iter().filter_map(as_index) {
                if let Some(p) = parent.get_mut(child) {
                    p.get_or_insert(i);
                }
            }
        }
        let mut local = Vec::with_capacity(nodes.len());
        for (i, node) in nodes.iter().enumerate() {
            let mut sink = FailFast::default();
            let at = format!("/nodes/{i}");
            local.push(animated_transform(node, animated.get(&i), &at, &mut sink));
            if let Some(error) = sink.error {
                return Err(error);
            }
        }
        let mut global: Vec<Option<DMat4>> = vec![None; nodes.len()];
        for start in 0..nodes.len() {
            if global[start].is_some() {
                continue;
            }
            // The chain of ancestors not yet known, nearest first.
            let mut chain = vec![start];
            let mut above = DMat4::IDENTITY;
            while let Some(p) = parent[*chain.last().unwrap_or(&start)] {
                if let Some(g) = global[p] {
                    above = g;
                    break;
                }
                if chain.len() > nodes.len() {
                    break;
                }
                chain.push(p);
            }
            if chain.len() > nodes.len() {
                continue;
            }
            for &n in chain.iter().rev() {
                above *= local[n];
                global[n] = Some(above);
            }
        }
        if let Some(i) = global
            .iter()
            .position(|g| g.is_some_and(|g| !g.is_finite()))
        {
            return Err(Diagnostic::error(
                Code::NodeTransformNotFinite,
                format!("/nodes/{i}"),
                "world transform is not finite",
            ));
        }
        Ok(global)
    }

    /// The joint matrices `G_k · IBM_k` of skin `skin`, given every node's global transform.
    pub fn joint_matrices(
        &self,
        skin: usize,
        globals: &[Option<DMat4>],
    ) -> Result<Vec<DMat4>, Diagnostic> {
        let at = format!("/skins/{skin}");
        let json = self.item("skins", skin).ok_or_else(|| {
            Diagnostic::error(Code::UnresolvedReference, &at, "skin does not exist")
        })?;
        let joints = array(json, "joints");
        let inverse_binds = match index_of(json, "inverseBindMatrices") {
            None => vec![DMat4::IDENTITY; joints.len()],
            Some(accessor) => {
                let (layout, values) = self.accessor_values(accessor).map_err(|e| e.within(&at))?;
                if layout.rows != Some(4) || layout.count < joints.len() {
                    return Err(Diagnostic::error(
                        Code::SkinIbmInvalidFormat,
                        format!("{at}/inverseBindMatrices"),
                        format!(
                            "must be a MAT4 accessor with one matrix per joint ({})",
                            joints.len()
                        ),
                    ));
                }
                values
                    .chunks_exact(16)
                    .map(|m| {
                        DMat4::from_cols_slice(
                            &m.iter().map(|&c| layout.dequantize(c)).collect::<Vec<_>>(),
                        )
                    })
                    .collect()
            }
        };
        joints
            .iter()
            .enumerate()
            .map(|(k, joint)| {
                let global = as_index(joint)
                    .and_then(|n| globals.get(n).copied().flatten())
                    .ok_or_else(|| {
                        Diagnostic::error(
                            Code::UnresolvedReference,
                            format!("{at}/joints/{k}"),
                            "joint is not a node with a transform",
                        )
                    })?;
                Ok(global * inverse_binds[k])
            })
            .collect()
    }

    /// Moves `geometry` (primitive `prim` of mesh `mesh`, as read) into `pose`: morph targets
    /// first, then the skin.
    pub fn pose_primitive(
        &self,
        mesh: usize,
        prim: usize,
        geometry: &mut Geometry,
        pose: &Pose,
    ) -> Result<(), Diagnostic> {
        let (json, at) = self.primitive_json(mesh, prim)?;
        let n = geometry.positions.len();
        if let Some(weights) = &pose.weights {
            for (t, target) in array(json, "targets").iter().enumerate() {
                let w = weights.get(t).copied().unwrap_or(0.0);
                self.morph_normals(target, w, geometry);
                let Some(accessor) = index_of(target, "POSITION").filter(|_| w != 0.0) else {
                    continue;
                };
                let tat = format!("{at}/targets/{t}/POSITION");
                let deltas = self.positions(accessor).map_err(|e| e.within(&tat))?;
                if deltas.len() != n {
                    return Err(Diagnostic::error(
                        Code::MeshPrimitiveMorphTargetInvalidAttributeCount,
                        tat,
                        format!("{} deltas for {n} vertices", deltas.len()),
                    ));
                }
                for (p, d) in geometry.positions.iter_mut().zip(&deltas) {
                    *p += w * *d;
                }
            }
        }
        if let Some(joints) = &pose.joints {
            let mut skinned = vec![DMat4::ZERO; n];
            for set in 0..MAX_SETS {
                let Some(influences) = self.influences(mesh, prim, json, set, n)? else {
                    break;
                };
                for (v, (ids, weights)) in influences.iter().enumerate() {
                    for (&id, &w) in ids.iter().zip(weights) {
                        if w == 0.0 {
                            continue;
                        }
                        let joint = joints.get(id as usize).ok_or_else(|| {
                            Diagnostic::error(
                                Code::AccessorJointsIndexOob,
                                format!("{at}/attributes/JOINTS_{set}"),
                                format!(
                                    "vertex {v} uses joint {id}, the skin has {}",
                                    joints.len()
                                ),
                            )
                        })?;
                        skinned[v] += *joint * w;
                    }
                }
            }
            for (p, m) in geometry.positions.iter_mut().zip(&skinned) {
                *p = m.transform_point3(*p);
            }
            // Normals follow the blended matrix by its inverse transpose (a skin that
            // collapses a vertex leaves a zero normal there: a miss).
            for (normal, m) in geometry.normals.iter_mut().flatten().zip(&skinned) {
                let linear = glam::DMat3::from_mat4(*m);
                *normal = match linear.determinant() {
                    0.0 => DVec3::ZERO,
                    _ => linear.inverse().transpose() * *normal,
                };
            }
        }
        if let Some(i) = geometry.positions.iter().position(|p| !p.is_finite()) {
            return Err(Diagnostic::error(
                Code::AccessorInvalidFloat,
                at,
                format!("posed vertex {i} is not finite"),
            ));
        }
        Ok(())
    }

    /// Adds `w` times morph target `target`'s NORMAL deltas to the geometry's normals; a
    /// target whose deltas cannot be read leaves the normals out (their hits are misses),
    /// as an unreadable NORMAL does, rather than stopping the render.
    fn morph_normals(&self, target: &Value, w: f64, geometry: &mut Geometry) {
        let Some(accessor) = index_of(target, "NORMAL").filter(|_| w != 0.0) else {
            return;
        };
        let Some(normals) = geometry.normals.as_mut() else {
            return;
        };
        match self.positions(accessor) {
            Ok(deltas) if deltas.len() == normals.len() => {
                for (n, d) in normals.iter_mut().zip(&deltas) {
                    *n += w * *d;
                }
            }
            _ => geometry.normals = None,
        }
    }

    /// The joint indices and weights (as values: normalized integers decoded) of influence
    /// set `set` of a primitive with `n` vertices; `None` when it has no `JOINTS_set`.
    fn influences(
        &self,
        mesh: usize,
        prim: usize,
        json: &Value,
        set: usize,
        n: usize,
    ) -> Result<Option<Influences>, Diagnostic> {
        let attributes = json.get("attributes");
        let (jname, wname) = (format!("JOINTS_{set}"), format!("WEIGHTS_{set}"));
        let at = format!("/meshes/{mesh}/primitives/{prim}/attributes");
        let Some(joints) = attributes.and_then(|a| index_of(a, &jname)) else {
            return Ok(None);
        };
        let weights = attributes
            .and_then(|a| index_of(a, &wname))
            .ok_or_else(|| {
                Diagnostic::error(
                    Code::MeshPrimitiveJointsWeightsMismatch,
                    format!("{at}/{jname}"),
                    format!("{jname} without {wname}"),
                )
            })?;
        let read = |accessor: usize, name: &str| -> Result<Vec<[f64; 4]>, Diagnostic> {
            let pointer = format!("{at}/{name}");
            let layout = self.layout(accessor).map_err(|e| e.within(&pointer))?;
            let stored = match decode::draco_attribute(self, mesh, prim, name, 4) {
                Some(values) => values.map_err(|e| e.within(&pointer))?,
                None => {
                    self.accessor_values(accessor)
                        .map_err(|e| e.within(&pointer))?
                        .1
                }
            };
            if layout.comps != 4 || layout.rows.is_some() || stored.len() != 4 * n {
                return Err(Diagnostic::error(
                    Code::MeshPrimitiveUnequalAccessorCount,
                    pointer,
                    format!("must be VEC4 with one element per vertex ({n})"),
                ));
            }
            Ok(stored
                .chunks_exact(4)
                .map(|c| [0, 1, 2, 3].map(|k| layout.dequantize(c[k])))
                .collect())
        };
        let (ids, ws) = (read(joints, &jname)?, read(weights, &wname)?);
        if let Some(v) = ids
            .iter()
            .position(|j| j.iter().any(|&i| i < 0.0 || i.fract() != 0.0))
        {
            return Err(Diagnostic::error(
                Code::MeshPrimitiveJointsInvalid,
                format!("{at}/{jname}"),
                format!("vertex {v}: joint indices must be unsigned integers"),
            ));
        }
        Ok(Some(ids.into_iter().zip(ws).collect()))
    }
}

/// What `info` and the sidecar say about a document's posing: its animations (those in
/// `applied` evaluated at `time`), skins and meshes with morph targets; `None` for a file
/// without any.
pub fn pose_info(doc: &Document, time: Option<f64>, applied: &[usize]) -> Option<PoseInfo> {
    let animations: Vec<AnimationInfo> = doc
        .animation_summaries()
        .into_iter()
        .enumerate()
        .map(|(index, a)| AnimationInfo {
            index,
            name: a.name,
            range: a.range.map(|(lo, hi)| [lo, hi]),
            channels: a.channels,
            applied: applied.contains(&index),
        })
        .collect();
    let skins = doc.list("skins").len();
    let morphed_meshes = doc
        .list("meshes")
        .iter()
        .filter(|m| {
            array(m, "primitives")
                .iter()
                .any(|p| !array(p, "targets").is_empty())
        })
        .count();
    (!animations.is_empty() || skins > 0 || morphed_meshes > 0).then_some(PoseInfo {
        time,
        animations,
        skins,
        morphed_meshes,
    })
}
