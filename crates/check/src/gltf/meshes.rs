//! Meshes and primitives: attribute semantics and formats, morph targets, indices, modes,
//! and how buffer views are shared between vertices and indices.

use super::Walker;
use crate::import::gltf::accessor::Layout;
use crate::import::gltf::document::{array, as_index, escape, index_of};
use crate::Code;
use serde_json::Value;
use std::collections::{HashMap, HashSet};

impl Walker<'_, '_> {
    pub(super) fn meshes(&mut self) {
        let meshes = self.list("meshes");
        let quantized = self
            .list("extensionsUsed")
            .iter()
            .any(|e| e.as_str() == Some("KHR_mesh_quantization"));
        // Vertex buffer views and the accessors that read them: the validator asks for a
        // byteStride only where two or more accessors share a view, not where one accessor
        // is used by several primitives.
        let mut vertex_views: HashMap<usize, HashSet<usize>> = HashMap::new();
        for (m, mesh) in meshes.iter().enumerate() {
            let prims = array(mesh, "primitives");
            let mut targets_count = None;
            for (p, prim) in prims.iter().enumerate() {
                let at = format!("/meshes/{m}/primitives/{p}");
                let empty = serde_json::Map::new();
                let attributes = prim
                    .get("attributes")
                    .and_then(Value::as_object)
                    .unwrap_or(&empty);
                let mut count = None;
                let mut sets: HashMap<&str, Vec<usize>> = HashMap::new();
                for (name, acc) in attributes {
                    let aat = format!("{at}/attributes/{}", escape(name));
                    let semantic = name.split_once('_').filter(|(base, n)| {
                        matches!(*base, "TEXCOORD" | "COLOR" | "JOINTS" | "WEIGHTS")
                            && !n.is_empty()
                            && n.bytes().all(|c| c.is_ascii_digit())
                            && (n.len() == 1 || !n.starts_with('0'))
                    });
                    if let Some((base, n)) = semantic {
                        if let Ok(n) = n.parse::<usize>() {
                            let base = match base {
                                "TEXCOORD" => "TEXCOORD",
                                "COLOR" => "COLOR",
                                "JOINTS" => "JOINTS",
                                _ => "WEIGHTS",
                            };
                            sets.entry(base).or_default().push(n);
                        }
                    } else if !matches!(name.as_str(), "POSITION" | "NORMAL" | "TANGENT")
                        && !name.starts_with('_')
                    {
                        self.f.error(
                            Code::MeshPrimitiveInvalidAttribute,
                            aat.clone(),
                            format!("'{name}' is not a valid attribute semantic"),
                        );
                    }
                    let Some(acc) = acc.as_u64().and_then(|a| usize::try_from(a).ok()) else {
                        continue;
                    };
                    let Some(layout) = self.layout(acc) else {
                        continue;
                    };
                    if count.is_some_and(|c| c != layout.count) {
                        self.f.error(
                            Code::MeshPrimitiveUnequalAccessorCount,
                            aat.clone(),
                            "attribute accessors have different counts",
                        );
                    }
                    count.get_or_insert(layout.count);
                    if layout.component == 5125 {
                        self.f.error(
                            Code::MeshPrimitiveAttributesAccessorUnsignedInt,
                            aat.clone(),
                            "vertex attributes cannot be UNSIGNED_INT",
                        );
                    }
                    let float_vec = |n: usize| layout.comps == n && layout.rows.is_none();
                    let format_ok = match name.as_str() {
                        "POSITION" => float_vec(3) && (layout.component == 5126 || quantized),
                        "NORMAL" => float_vec(3) && (layout.component == 5126 || quantized),
                        "TANGENT" => float_vec(4) && (layout.component == 5126 || quantized),
                        _ => true,
                    };
                    if !format_ok {
                        self.f.error(
                            Code::MeshPrimitiveAttributesAccessorInvalidFormat,
                            aat.clone(),
                            format!("invalid accessor format for {name}"),
                        );
                    }
                    let acc_json = &self.list("accessors")[acc];
                    if name == "POSITION"
                        && (acc_json.get("min").is_none() || acc_json.get("max").is_none())
                    {
                        self.f.error(
                            Code::MeshPrimitivePositionAccessorWithoutBounds,
                            aat.clone(),
                            "POSITION accessors must have min and max",
                        );
                    }
                    if let Some(view_index) = index_of(acc_json, "bufferView") {
                        vertex_views.entry(view_index).or_default().insert(acc);
                        if let Some(view) = self.view_of(acc) {
                            let total = index_of(view, "byteOffset").unwrap_or(0)
                                + index_of(acc_json, "byteOffset").unwrap_or(0);
                            if !total.is_multiple_of(4) {
                                self.f.error(
                                    Code::MeshPrimitiveAccessorUnaligned,
                                    aat.clone(),
                                    "vertex attribute data must start on a 4-byte boundary",
                                );
                            }
                        }
                    }
                    self.attribute_data(name, acc, &layout, &aat);
                }
                self.weight_sums(attributes, &at);
                // As the validator counts them: the TEXCOORD_n sets if numbered 0, 1, 2, ...,
                // none otherwise.
                let texcoords = sets.get("TEXCOORD").map_or(0, |ns| {
                    let continuous = ns.iter().max().is_some_and(|&m| m + 1 == ns.len());
                    if continuous {
                        ns.len()
                    } else {
                        0
                    }
                });
                for (base, mut ns) in sets {
                    ns.sort_unstable();
                    if ns.iter().enumerate().any(|(i, &n)| i != n) {
                        self.f.error(
                            Code::MeshPrimitiveIndexedSemanticContinuity,
                            format!("{at}/attributes"),
                            format!("{base}_n sets are not numbered 0, 1, 2, ..."),
                        );
                    }
                }
                let has = |k: &str| attributes.contains_key(k);
                let joints = attributes
                    .keys()
                    .filter(|k| k.starts_with("JOINTS_"))
                    .count();
                let weights = attributes
                    .keys()
                    .filter(|k| k.starts_with("WEIGHTS_"))
                    .count();
                if joints != weights {
                    self.f.error(
                        Code::MeshPrimitiveJointsWeightsMismatch,
                        format!("{at}/attributes"),
                        "JOINTS_n and WEIGHTS_n come in pairs",
                    );
                }
                if !has("POSITION") {
                    self.f.warn(
                        Code::MeshPrimitiveNoPosition,
                        format!("{at}/attributes"),
                        "no POSITION: nothing is drawn",
                    );
                }
                if has("TANGENT") && !has("NORMAL") {
                    self.f.warn(
                        Code::MeshPrimitiveTangentWithoutNormal,
                        format!("{at}/attributes"),
                        "TANGENT without NORMAL",
                    );
                }
                if let Some(material) =
                    index_of(prim, "material").and_then(|i| self.list("materials").get(i))
                {
                    self.tangent_space(&at, has("NORMAL") && has("TANGENT"), material);
                    let needed = max_tex_coord(material);
                    if needed.is_some_and(|n| n >= texcoords) {
                        self.f.error(
                            Code::MeshPrimitiveTooFewTexcoords,
                            at.clone(),
                            "the material reads a TEXCOORD set the primitive does not have",
                        );
                    }
                }
                let mode = index_of(prim, "mode").unwrap_or(4) as u64;
                if let Some(indices) = index_of(prim, "indices") {
                    // Without an attribute accessor there are no vertices to index (the
                    // validator's vertex count of -1: every index is out of range).
                    let accessors = self.list("accessors").len();
                    let resolvable = attributes
                        .values()
                        .any(|a| as_index(a).is_some_and(|a| a < accessors));
                    let vertices = if resolvable { count } else { Some(0) };
                    self.indices(indices, vertices, mode, &format!("{at}/indices"));
                } else if let Some(count) = count {
                    self.mode_count(mode, count, &at);
                }
                let targets = array(prim, "targets");
                if targets_count.is_some_and(|t| t != targets.len()) {
                    self.f.error(
                        Code::MeshPrimitivesUnequalTargetsCount,
                        format!("{at}/targets"),
                        "primitives of a mesh have different numbers of morph targets",
                    );
                }
                targets_count.get_or_insert(targets.len());
                for (t, target) in targets.iter().enumerate() {
                    let Some(target) = target.as_object() else {
                        continue;
                    };
                    for (name, acc) in target {
                        let tat = format!("{at}/targets/{t}/{}", escape(name));
                        if !attributes.contains_key(name) {
                            self.f.error(
                                Code::MeshPrimitiveMorphTargetNoBaseAccessor,
                                tat.clone(),
                                format!("morph target {name} has no base attribute"),
                            );
                        }
                        let Some(acc) = acc.as_u64().and_then(|a| usize::try_from(a).ok()) else {
                            continue;
                        };
                        if let Some(layout) = self.layout(acc) {
                            if count.is_some_and(|c| c != layout.count) {
                                self.f.error(
                                    Code::MeshPrimitiveMorphTargetInvalidAttributeCount,
                                    tat.clone(),
                                    "morph target accessor count differs from the base",
                                );
                            }
                        }
                        let acc_json = self.list("accessors").get(acc).unwrap_or(&Value::Null);
                        if name == "POSITION"
                            && (acc_json.get("min").is_none() || acc_json.get("max").is_none())
                        {
                            self.f.error(
                                Code::MeshPrimitivePositionAccessorWithoutBounds,
                                tat.clone(),
                                "morph POSITION accessors must have min and max",
                            );
                        }
                    }
                }
            }
            if let (Some(weights), Some(targets)) =
                (mesh.get("weights").and_then(Value::as_array), targets_count)
            {
                if weights.len() != targets {
                    self.f.error(
                        Code::MeshInvalidWeightsCount,
                        format!("/meshes/{m}/weights"),
                        format!("{} weights for {targets} morph targets", weights.len()),
                    );
                }
            }
        }
        for (view, accessors) in vertex_views {
            let users = accessors.len();
            let Some(v) = self.list("bufferViews").get(view) else {
                continue;
            };
            if users > 1 && v.get("byteStride").is_none() {
                self.f.error(
                    Code::MeshPrimitiveAccessorWithoutBytestride,
                    format!("/bufferViews/{view}"),
                    format!("a buffer view shared by {users} vertex accessors needs a byteStride"),
                );
            }
        }
    }

    /// Value checks on normals, tangents, colours and skin weights.
    fn attribute_data(&mut self, name: &str, acc: usize, layout: &Layout, at: &str) {
        if layout.component != 5126 {
            return;
        }
        let check = |n: &str| name == n || name.starts_with(&format!("{n}_"));
        if !(check("NORMAL") || check("TANGENT") || check("COLOR") || check("WEIGHTS")) {
            return;
        }
        let Some(values) = self.values(acc) else {
            return;
        };
        let comps = layout.comps;
        let vector = name == "NORMAL" || name == "TANGENT";
        if vector && comps < 3 {
            // A wrong type: the format rule reports it
            // (MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT).
            return;
        }
        for (e, v) in values.chunks_exact(comps).enumerate() {
            let problem = if vector {
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                if (len - 1.0).abs() > super::UNIT_VECTOR_TOLERANCE {
                    Some((
                        Code::AccessorVector3NonUnit,
                        format!("element {e} has length {len}"),
                    ))
                } else if name == "TANGENT" && comps == 4 && v[3] != 1.0 && v[3] != -1.0 {
                    Some((
                        Code::AccessorInvalidSign,
                        format!("element {e} has w = {}", v[3]),
                    ))
                } else {
                    None
                }
            } else if check("COLOR") {
                v.iter().any(|c| !(0.0..=1.0).contains(c)).then(|| {
                    (
                        Code::AccessorNonClamped,
                        format!("element {e} is outside [0, 1]"),
                    )
                })
            } else if v.iter().any(|w| *w < 0.0) {
                Some((
                    Code::AccessorWeightsNegative,
                    format!("element {e} has a negative weight"),
                ))
            } else {
                None
            };
            if let Some((code, message)) = problem {
                self.f.error(code, at.to_string(), message);
                return;
            }
        }
    }

    /// ACCESSOR_WEIGHTS_NON_NORMALIZED: each vertex's weights, summed over every `WEIGHTS_n`
    /// set of the primitive (a vertex with more than four joints spreads its weights over
    /// several sets), must add up to 1 within 2e-3, negative weights left out. Float VEC4
    /// sets of one count are compared; the finding points at `WEIGHTS_0`.
    fn weight_sums(&mut self, attributes: &serde_json::Map<String, Value>, at: &str) {
        let mut sets = Vec::new();
        for n in 0.. {
            let Some(acc) = attributes.get(&format!("WEIGHTS_{n}")) else {
                break;
            };
            let Some(acc) = acc.as_u64().and_then(|a| usize::try_from(a).ok()) else {
                return;
            };
            match self.layout(acc) {
                Some(layout) if layout.component == 5126 && layout.comps == 4 => {}
                _ => return,
            }
            let Some(values) = self.values(acc) else {
                return;
            };
            sets.push(values);
        }
        let Some(first) = sets.first() else {
            return;
        };
        if sets.iter().any(|s| s.len() != first.len()) {
            return;
        }
        let vertices = first.len() / 4;
        let bad = (0..vertices).find(|&e| {
            // A negative weight (ACCESSOR_WEIGHTS_NEGATIVE) is left out of the sum, as the
            // validator leaves it out: 1 and -0.25 add up to 1, 1.5 and -0.5 do not.
            let sum: f64 = sets
                .iter()
                .flat_map(|s| &s[4 * e..4 * e + 4])
                .map(|w| w.max(0.0))
                .sum();
            (sum - 1.0).abs() > 2e-3
        });
        if let Some(e) = bad {
            self.f.error(
                Code::AccessorWeightsNonNormalized,
                format!("{at}/attributes/WEIGHTS_0"),
                format!(
                    "skin weights of vertex {e} do not add up to 1 over {} WEIGHTS_n sets",
                    sets.len()
                ),
            );
        }
    }

    fn mode_count(&mut self, mode: u64, count: usize, at: &str) {
        let bad = match mode {
            4 => !count.is_multiple_of(3),
            5 | 6 => count < 3,
            1 => !count.is_multiple_of(2),
            3 => count < 2,
            2 => count < 2,
            _ => false,
        };
        if bad {
            self.f.warn(
                Code::MeshPrimitiveIncompatibleMode,
                at.to_string(),
                format!("{count} vertices do not make whole primitives of mode {mode}"),
            );
        }
    }

    fn indices(&mut self, indices: usize, vertices: Option<usize>, mode: u64, at: &str) {
        let Some(layout) = self.layout(indices) else {
            return;
        };
        if layout.comps != 1 || !matches!(layout.component, 5121 | 5123 | 5125) {
            self.f.error(
                Code::MeshPrimitiveIndicesAccessorInvalidFormat,
                at.to_string(),
                "indices must be SCALAR unsigned integers",
            );
            return;
        }
        if let Some(view) = self.view_of(indices) {
            if view.get("byteStride").is_some() {
                self.f.error(
                    Code::MeshPrimitiveIndicesAccessorWithBytestride,
                    at.to_string(),
                    "the indices' buffer view has a byteStride",
                );
            }
        }
        self.mode_count(mode, layout.count, at);
        let Some(values) = self.values(indices) else {
            return;
        };
        let restart = match layout.component {
            5121 => 255.0,
            5123 => 65535.0,
            _ => 4294967295.0,
        };
        let mut oob = 0usize;
        let mut first_oob = None;
        let mut restarts = 0usize;
        for &v in values.iter() {
            // The validator's two rules are independent: a restart value past the last
            // vertex is also out of range.
            if v == restart {
                restarts += 1;
            }
            if vertices.is_some_and(|n| v as usize >= n) {
                oob += 1;
                first_oob.get_or_insert(v);
            }
        }
        if restarts > 0 {
            self.f.error(
                Code::AccessorIndexPrimitiveRestart,
                format!("/accessors/{indices}"),
                format!("{restarts} indices hold the primitive restart value {restart}"),
            );
        }
        if let (Some(first), Some(n)) = (first_oob, vertices) {
            self.f.error(
                Code::AccessorIndexOob,
                format!("/accessors/{indices}"),
                format!("{oob} indices out of range (first: {first}; {n} vertices)"),
            );
        }
    }
}

/// The largest `texCoord` a material's textures read, if any.
fn max_tex_coord(v: &Value) -> Option<usize> {
    match v {
        Value::Object(map) => {
            let here = map
                .get("index")
                .filter(|_| map.len() <= 4)
                .map(|_| index_of(v, "texCoord").unwrap_or(0));
            map.iter()
                .filter(|(k, _)| *k != "extras")
                .filter_map(|(_, x)| max_tex_coord(x))
                .chain(here)
                .max()
        }
        _ => None,
    }
}
