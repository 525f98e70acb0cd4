//! Nodes, scenes and cameras: hierarchy (loops, parents), transforms (via the document
//! layer, plus the validator's TRS rules), dependencies, the quadric extension, the memory
//! estimate, and camera projections.

use super::{Walker, MAX_NODE_DEPTH};
use crate::import::gltf::document::{array, as_index, index_of, numbers};
use crate::import::gltf::node::local_transform;
use crate::import::gltf::QUADRIC_EXTENSION;
use crate::Code;
use glam::DMat4;
use serde_json::Value;
use std::collections::HashSet;

impl Walker<'_, '_> {
    /// Hierarchy, transforms, dependencies and the quadric extension; returns the number of
    /// triangles the default scene expands to (for the memory estimate).
    pub(super) fn nodes_and_scenes(&mut self) -> u64 {
        let nodes = self.list("nodes");
        let n = nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for (i, node) in nodes.iter().enumerate() {
            for (k, c) in array(node, "children").iter().enumerate() {
                let Some(c) = c
                    .as_u64()
                    .and_then(|c| usize::try_from(c).ok())
                    .filter(|&c| c < n)
                else {
                    continue;
                };
                children[i].push(c);
                if let Some(p) = parent[c] {
                    if p != i {
                        self.f.error(
                            Code::NodeParentOverride,
                            format!("/nodes/{i}/children/{k}"),
                            format!("node {c} is already a child of node {p}"),
                        );
                    }
                } else {
                    parent[c] = Some(i);
                }
            }
        }
        // Cycles: a colouring depth-first search, iterative.
        let mut state = vec![0u8; n];
        for start in 0..n {
            if state[start] != 0 {
                continue;
            }
            let mut stack = vec![(start, 0usize)];
            state[start] = 1;
            while let Some(&mut (node, ref mut next)) = stack.last_mut() {
                if let Some(&c) = children[node].get(*next) {
                    *next += 1;
                    match state[c] {
                        0 => {
                            state[c] = 1;
                            stack.push((c, 0));
                        }
                        1 => self.f.error(
                            Code::NodeLoop,
                            format!("/nodes/{node}/children"),
                            format!("node {c} is its own ancestor"),
                        ),
                        _ => {}
                    }
                } else {
                    state[node] = 2;
                    stack.pop();
                }
            }
        }
        let meshes = self.list("meshes");
        let mesh_targets = |m: usize| -> usize {
            meshes
                .get(m)
                .map(|mesh| {
                    array(mesh, "primitives")
                        .first()
                        .map_or(0, |p| array(p, "targets").len())
                })
                .unwrap_or(0)
        };
        let mesh_skinned = |m: usize| -> bool {
            meshes.get(m).is_some_and(|mesh| {
                array(mesh, "primitives").iter().any(|p| {
                    p.get("attributes")
                        .and_then(Value::as_object)
                        .is_some_and(|a| a.contains_key("JOINTS_0"))
                })
            })
        };
        let mut locals = vec![DMat4::IDENTITY; n];
        for (i, node) in nodes.iter().enumerate() {
            let at = format!("/nodes/{i}");
            locals[i] = self.node_transform(node, &at);
            let mesh = index_of(node, "mesh");
            if node.get("skin").is_some() {
                match mesh {
                    None => self.f.error(
                        Code::UnsatisfiedDependency,
                        format!("{at}/skin"),
                        "skin without mesh",
                    ),
                    Some(m) if m < meshes.len() && !mesh_skinned(m) => self.f.error(
                        Code::NodeSkinWithNonSkinnedMesh,
                        at.clone(),
                        "the node has a skin but its mesh has no JOINTS_0/WEIGHTS_0",
                    ),
                    _ => {}
                }
            } else if mesh.is_some_and(|m| m < meshes.len() && mesh_skinned(m)) {
                self.f.warn(
                    Code::NodeSkinnedMeshWithoutSkin,
                    at.clone(),
                    "a skinned mesh on a node without a skin",
                );
            }
            if let Some(weights) = node.get("weights").and_then(Value::as_array) {
                match mesh {
                    None => self.f.error(
                        Code::UnsatisfiedDependency,
                        format!("{at}/weights"),
                        "weights without mesh",
                    ),
                    Some(m) if m < meshes.len() && weights.len() != mesh_targets(m) => {
                        self.f.error(
                            Code::NodeWeightsInvalid,
                            format!("{at}/weights"),
                            format!(
                                "{} weights for {} morph targets",
                                weights.len(),
                                mesh_targets(m)
                            ),
                        )
                    }
                    _ => {}
                }
            }
            if let Some(ext) = node
                .get("extensions")
                .and_then(|e| e.get(QUADRIC_EXTENSION))
            {
                let spec = crate::import::gltf::quadric_extension::quadric_spec(ext)
                    .and_then(|s| s.validate().map(|()| s));
                if let Err(e) = spec {
                    self.f.error(
                        Code::QuadricInvalid,
                        format!("{at}/extensions/{QUADRIC_EXTENSION}"),
                        format!("{QUADRIC_EXTENSION}: {e}"),
                    );
                }
            }
        }
        // Scenes: roots must be roots; estimate the triangles drawn.
        let scenes = self.list("scenes");
        for (s, scene) in scenes.iter().enumerate() {
            for (k, node) in array(scene, "nodes").iter().enumerate() {
                if let Some(node) = node
                    .as_u64()
                    .and_then(|v| usize::try_from(v).ok())
                    .filter(|&v| v < n)
                {
                    if parent[node].is_some() {
                        self.f.error(
                            Code::SceneNonRootNode,
                            format!("/scenes/{s}/nodes/{k}"),
                            format!("node {node} has a parent"),
                        );
                    }
                }
            }
        }
        let roots: Vec<usize> = match self
            .root
            .get("scene")
            .and_then(as_index)
            .or(if scenes.is_empty() { None } else { Some(0) })
            .and_then(|s| scenes.get(s))
        {
            Some(scene) => array(scene, "nodes")
                .iter()
                .filter_map(|v| v.as_u64().and_then(|v| usize::try_from(v).ok()))
                .filter(|&v| v < n)
                .collect(),
            None => (0..n).filter(|&i| parent[i].is_none()).collect(),
        };
        let mesh_triangles: Vec<u64> = meshes
            .iter()
            .map(|mesh| {
                array(mesh, "primitives")
                    .iter()
                    .map(|p| {
                        let count = index_of(p, "indices")
                            .or_else(|| p.get("attributes").and_then(|a| index_of(a, "POSITION")))
                            .and_then(|a| self.layout(a))
                            .map_or(0, |l| l.count as u64);
                        count / 3 + 2
                    })
                    .sum()
            })
            .collect();
        let mut triangles = 0u64;
        let mut stack: Vec<(usize, usize, DMat4)> =
            roots.iter().map(|&r| (r, 0, DMat4::IDENTITY)).collect();
        let mut visits = 0u64;
        let mut reported_depth = false;
        let mut reported_world = HashSet::new();
        while let Some((node, depth, parent_world)) = stack.pop() {
            visits += 1;
            if visits > 10_000_000 {
                self.f.error(
                    Code::AssetTooLarge,
                    "/nodes",
                    "the node hierarchy expands to more than 10 million instances",
                );
                self.importable = false;
                break;
            }
            if depth > MAX_NODE_DEPTH {
                if !reported_depth {
                    reported_depth = true;
                    self.f.error(
                        Code::NodeHierarchyTooDeep,
                        format!("/nodes/{node}"),
                        format!("the hierarchy is deeper than {MAX_NODE_DEPTH} levels (or loops)"),
                    );
                    self.importable = false;
                }
                continue;
            }
            let world = parent_world * locals[node];
            if !world.is_finite() && reported_world.insert(node) {
                self.f.error(
                    Code::NodeTransformNotFinite,
                    format!("/nodes/{node}"),
                    "the world transform overflows to infinity or NaN",
                );
            }
            if let Some(m) = index_of(&nodes[node], "mesh") {
                triangles = triangles.saturating_add(mesh_triangles.get(m).copied().unwrap_or(0));
            }
            for &c in &children[node] {
                stack.push((c, depth + 1, world));
            }
        }
        triangles
    }

    /// The local matrix of a node as the importer computes it (the document layer reports
    /// malformed properties), with the validator's rules on it.
    fn node_transform(&mut self, node: &Value, at: &str) -> DMat4 {
        let mut sink = super::Collect {
            f: self.f,
            too_large: false,
        };
        let local = local_transform(node, at, &mut sink);
        let has_trs = ["translation", "rotation", "scale"]
            .iter()
            .any(|k| node.get(*k).is_some());
        if node.get("matrix").is_some() {
            if has_trs {
                self.f.error(
                    Code::NodeMatrixTrs,
                    at.to_string(),
                    "a node has both matrix and translation/rotation/scale",
                );
            }
            let upper = glam::DMat3::from_mat4(local);
            let gram = upper.transpose() * upper;
            let off = [gram.x_axis.y, gram.x_axis.z, gram.y_axis.z];
            let scale2 = gram
                .x_axis
                .x
                .max(gram.y_axis.y)
                .max(gram.z_axis.z)
                .max(f64::MIN_POSITIVE);
            if local.row(3) != glam::DVec4::W || off.iter().any(|o| o.abs() > 1e-5 * scale2) {
                self.f.error(
                    Code::NodeMatrixNonTrs,
                    format!("{at}/matrix"),
                    "the matrix is not a translation-rotation-scale",
                );
            }
        } else if let Some(q) = numbers(node, "rotation").filter(|q| q.len() == 4) {
            let length = q.iter().map(|c| c * c).sum::<f64>().sqrt();
            if (length - 1.0).abs() > super::UNIT_QUATERNION_TOLERANCE {
                self.f.error(
                    Code::RotationNonUnit,
                    format!("{at}/rotation"),
                    format!("the rotation quaternion has length {length}"),
                );
            }
        }
        let det = local.determinant();
        if local.is_finite() && (det == 0.0 || !det.is_finite()) {
            self.f.warn(
                Code::NodeTransformNotInvertible,
                at.to_string(),
                "the node's transform is singular (a zero scale?): its subtree collapses",
            );
        }
        local
    }

    pub(super) fn cameras(&mut self) {
        for (i, camera) in self.list("cameras").iter().enumerate() {
            let at = format!("/cameras/{i}");
            let kind = camera.get("type").and_then(Value::as_str);
            let p = camera.get("perspective");
            let o = camera.get("orthographic");
            if p.is_some() && o.is_some() {
                self.f.error(
                    Code::OneOfMismatch,
                    at.clone(),
                    "both perspective and orthographic",
                );
            }
            let num = |v: Option<&Value>, k: &str| v.and_then(|v| v.get(k)).and_then(Value::as_f64);
            match kind {
                Some("perspective") => {
                    if p.is_none() {
                        self.f.error(
                            Code::UndefinedProperty,
                            format!("{at}/perspective"),
                            "missing",
                        );
                    }
                    let znear = num(p, "znear");
                    let zfar = num(p, "zfar");
                    let yfov = num(p, "yfov");
                    if znear.is_some_and(|z| !(z > 0.0 && z.is_finite())) {
                        self.f.error(
                            Code::ValueNotInRange,
                            format!("{at}/perspective/znear"),
                            "znear must be positive and finite",
                        );
                    }
                    if yfov.is_some_and(|y| !(y > 0.0 && y.is_finite())) {
                        self.f.error(
                            Code::ValueNotInRange,
                            format!("{at}/perspective/yfov"),
                            "yfov must be positive",
                        );
                    } else if yfov.is_some_and(|y| y >= std::f64::consts::PI) {
                        self.f.warn(
                            Code::CameraYfovGequalPi,
                            format!("{at}/perspective/yfov"),
                            "yfov is at least pi",
                        );
                    }
                    if let (Some(n), Some(f)) = (znear, zfar) {
                        if f <= n {
                            self.f.error(
                                Code::CameraZfarLequalZnear,
                                format!("{at}/perspective/zfar"),
                                "zfar is not beyond znear",
                            );
                        }
                    }
                }
                Some("orthographic") => {
                    if o.is_none() {
                        self.f.error(
                            Code::UndefinedProperty,
                            format!("{at}/orthographic"),
                            "missing",
                        );
                    }
                    let (x, y) = (num(o, "xmag"), num(o, "ymag"));
                    if x == Some(0.0) || y == Some(0.0) {
                        self.f.error(
                            Code::CameraXmagYmagZero,
                            format!("{at}/orthographic"),
                            "xmag or ymag is zero",
                        );
                    }
                    if x.is_some_and(|v| v < 0.0) || y.is_some_and(|v| v < 0.0) {
                        self.f.warn(
                            Code::CameraXmagYmagNegative,
                            format!("{at}/orthographic"),
                            "xmag or ymag is negative",
                        );
                    }
                    if let (Some(n), Some(f)) = (num(o, "znear"), num(o, "zfar")) {
                        if f <= n {
                            self.f.error(
                                Code::CameraZfarLequalZnear,
                                format!("{at}/orthographic/zfar"),
                                "zfar is not beyond znear",
                            );
                        }
                    }
                }
                _ => {}
            }
        }
    }
}
