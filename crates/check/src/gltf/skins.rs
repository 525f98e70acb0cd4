//! Skins: joints, skeleton and inverse bind matrices (never read for a render).

use super::{Walker, MAX_NODE_DEPTH};
use crate::import::gltf::document::{array, index_of};
use crate::Code;
use std::collections::HashSet;

impl Walker<'_, '_> {
    pub(super) fn skins(&mut self) {
        let nodes = self.list("nodes");
        let n = nodes.len();
        let mut parent = vec![None; n];
        for (i, node) in nodes.iter().enumerate() {
            for c in array(node, "children") {
                if let Some(c) = c
                    .as_u64()
                    .and_then(|c| usize::try_from(c).ok())
                    .filter(|&c| c < n)
                {
                    parent[c].get_or_insert(i);
                }
            }
        }
        let ancestors = |mut x: usize| {
            let mut list = vec![x];
            while let Some(p) = parent[x] {
                if list.contains(&p) || list.len() > MAX_NODE_DEPTH {
                    break;
                }
                list.push(p);
                x = p;
            }
            list
        };
        let in_scene: HashSet<usize> = {
            let mut set = HashSet::new();
            for scene in self.list("scenes") {
                for r in array(scene, "nodes").iter().filter_map(|v| v.as_u64()) {
                    let mut stack = vec![r as usize];
                    while let Some(x) = stack.pop() {
                        if x < n && set.insert(x) {
                            stack.extend(
                                array(&nodes[x], "children")
                                    .iter()
                                    .filter_map(|c| c.as_u64().map(|c| c as usize)),
                            );
                        }
                    }
                }
            }
            set
        };
        for (s, skin) in self.list("skins").iter().enumerate() {
            let at = format!("/skins/{s}");
            let joints: Vec<usize> = array(skin, "joints")
                .iter()
                .filter_map(|j| j.as_u64().map(|j| j as usize))
                .filter(|&j| j < n)
                .collect();
            if let Some(ibm) = index_of(skin, "inverseBindMatrices") {
                if let Some(l) = self.layout(ibm) {
                    if l.comps != 16 || l.component != 5126 {
                        self.f.error(
                            Code::SkinIbmInvalidFormat,
                            format!("{at}/inverseBindMatrices"),
                            "inverse bind matrices must be MAT4 float",
                        );
                    } else {
                        if l.count < joints.len() {
                            self.f.error(
                                Code::InvalidIbmAccessorCount,
                                format!("{at}/inverseBindMatrices"),
                                "fewer inverse bind matrices than joints",
                            );
                        }
                        if let Some(m) = self.values(ibm) {
                            if m.chunks_exact(16)
                                .any(|m| m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0)
                            {
                                self.f.error(
                                    Code::AccessorInvalidIbm,
                                    format!("/accessors/{ibm}"),
                                    "an inverse bind matrix is not affine",
                                );
                            }
                        }
                    }
                }
                if self
                    .view_of(ibm)
                    .is_some_and(|v| v.get("byteStride").is_some())
                {
                    self.f.error(
                        Code::SkinIbmAccessorWithBytestride,
                        format!("{at}/inverseBindMatrices"),
                        "inverse bind matrices cannot use a byteStride",
                    );
                }
            }
            if joints.len() > 1 {
                let chains: Vec<Vec<usize>> = joints.iter().map(|&j| ancestors(j)).collect();
                let common = chains[0]
                    .iter()
                    .any(|a| chains.iter().all(|c| c.contains(a)));
                if !common {
                    self.f.error(
                        Code::SkinNoCommonRoot,
                        format!("{at}/joints"),
                        "the joints have no common root",
                    );
                }
            }
            if array(skin, "joints")
                .iter()
                .any(|j| j.as_u64().is_none_or(|j| j as usize >= n))
                && joints.len() > 1
            {
                self.f.error(
                    Code::SkinNoCommonRoot,
                    format!("{at}/joints"),
                    "a joint does not exist",
                );
            }
            if let Some(skeleton) = index_of(skin, "skeleton").filter(|&k| k < n) {
                if !joints.iter().all(|&j| ancestors(j).contains(&skeleton)) {
                    self.f.error(
                        Code::SkinSkeletonInvalid,
                        format!("{at}/skeleton"),
                        "the skeleton is not a common root of the joints",
                    );
                }
            }
            if !joints.is_empty()
                && !self.list("scenes").is_empty()
                && joints.iter().all(|j| !in_scene.contains(j))
            {
                self.f.error(
                    Code::NodeSkinNoScene,
                    format!("{at}/joints"),
                    "no joint is in a scene",
                );
            }
        }
    }
}
