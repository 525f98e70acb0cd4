//! Nodes, scenes and cameras: local transforms read in f64 from the JSON numbers (the
//! `matrix`, or translation · rotation · scale), the root nodes of the chosen scene, and
//! camera projections.

use super::animation::Animated;
use super::diagnostics::{Code, Diagnostic, Sink};
use super::document::{array, as_index, index_of, Document};
use crate::bound::transform::BoundedMat4;
use crate::camera::Projection;
use crate::error::Error;
use glam::{DMat4, DQuat, DVec3};
use serde_json::Value;

/// A node's properties that the ray caster uses.
#[derive(Debug, Clone)]
pub struct Node<'a> {
    /// Index in `nodes`.
    pub index: usize,
    /// The node's JSON.
    pub json: &'a Value,
    /// `name`, if any.
    pub name: Option<&'a str>,
    /// `mesh`, if any.
    pub mesh: Option<usize>,
    /// `camera`, if any.
    pub camera: Option<usize>,
}

impl<'a> Node<'a> {
    /// Child node indices, as written (unchecked).
    pub fn children(&self) -> impl DoubleEndedIterator<Item = usize> + 'a {
        array(self.json, "children").iter().filter_map(as_index)
    }

    /// JSON pointer of the node.
    pub fn pointer(&self) -> String {
        format!("/nodes/{}", self.index)
    }
}

/// A camera's projection as the file states it.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraSpec {
    /// `name`, if any.
    pub name: Option<String>,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Width over height, when the file gives it.
    pub aspect_ratio: Option<f64>,
    /// Near plane.
    pub znear: f64,
    /// Far plane (infinite perspective when absent).
    pub zfar: Option<f64>,
}

impl Document {
    /// Node `index`, if it exists.
    pub fn node(&self, index: usize) -> Option<Node<'_>> {
        let json = self.item("nodes", index)?;
        Some(Node {
            index,
            json,
            name: json.get("name").and_then(Value::as_str),
            mesh: index_of(json, "mesh"),
            camera: index_of(json, "camera"),
        })
    }

    /// The root nodes of a scene: chosen by index or name, else the default scene, else the
    /// first; `Ok(None)` when the file defines no scene.
    pub fn scene_roots(&self, choice: Option<&str>) -> Result<Option<Vec<usize>>, Error> {
        let scenes = self.list("scenes");
        let scene = match choice {
            Some(choice) => Some(
                scenes
                    .iter()
                    .enumerate()
                    .find(|(i, s)| {
                        choice.parse::<usize>() == Ok(*i)
                            || s.get("name").and_then(Value::as_str) == Some(choice)
                    })
                    .map(|(_, s)| s)
                    .ok_or_else(|| {
                        Error::msg(format!(
                            "no scene '{choice}' (the file has {})",
                            scenes.len()
                        ))
                    })?,
            ),
            None => self
                .root()
                .get("scene")
                .and_then(as_index)
                .and_then(|s| scenes.get(s))
                .or(scenes.first()),
        };
        Ok(scene.map(|s| array(s, "nodes").iter().filter_map(as_index).collect()))
    }

    /// Every node that is nobody's child.
    pub fn parentless_nodes(&self) -> Vec<usize> {
        let nodes = self.list("nodes");
        let mut is_child = vec![false; nodes.len()];
        for node in nodes {
            for child in array(node, "children").iter().filter_map(as_index) {
                if let Some(flag) = is_child.get_mut(child) {
                    *flag = true;
                }
            }
        }
        (0..nodes.len()).filter(|&i| !is_child[i]).collect()
    }

    /// Camera `index`'s projection.
    pub fn camera(&self, index: usize) -> Result<CameraSpec, Diagnostic> {
        let at = format!("/cameras/{index}");
        let bad = |what: &str| Diagnostic::error(Code::CameraInvalid, &at, what.to_string());
        let camera = self
            .item("cameras", index)
            .ok_or_else(|| bad("camera does not exist"))?;
        let num = |part: &Value, key: &str| part.get(key).and_then(Value::as_f64);
        let name = camera.get("name").and_then(Value::as_str).map(String::from);
        match camera.get("type").and_then(Value::as_str) {
            Some("perspective") => {
                let p = camera
                    .get("perspective")
                    .ok_or_else(|| bad("no perspective"))?;
                let yfov = num(p, "yfov")
                    .filter(|y| *y > 0.0 && y.is_finite())
                    .ok_or_else(|| bad("invalid yfov"))?;
                let znear = num(p, "znear")
                    .filter(|z| *z > 0.0 && z.is_finite())
                    .ok_or_else(|| bad("invalid znear"))?;
                Ok(CameraSpec {
                    name,
                    projection: Projection::Perspective { yfov },
                    aspect_ratio: num(p, "aspectRatio").filter(|a| *a > 0.0 && a.is_finite()),
                    znear,
                    zfar: num(p, "zfar"),
                })
            }
            Some("orthographic") => {
                let o = camera
                    .get("orthographic")
                    .ok_or_else(|| bad("no orthographic"))?;
                let read = |k: &str| {
                    num(o, k)
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| bad(&format!("invalid {k}")))
                };
                let (xmag, ymag) = (read("xmag")?, read("ymag")?);
                Ok(CameraSpec {
                    name,
                    projection: Projection::Orthographic { ymag },
                    aspect_ratio: Some(xmag / ymag).filter(|a| a.is_finite() && *a > 0.0),
                    znear: read("znear")?,
                    zfar: Some(read("zfar")?),
                })
            }
            _ => Err(bad("type is neither perspective nor orthographic")),
        }
    }
}

/// A node's local matrix in f64: its `matrix`, else translation · rotation · scale. A
/// property that is not the right number of finite numbers is reported (`VALUE_NOT_IN_RANGE`)
/// and read as absent; a zero quaternion is an error, another non-unit one is normalized.
pub fn local_transform(node: &Value, at: &str, sink: &mut dyn Sink) -> DMat4 {
    animated_transform(node, None, at, sink)
}

/// [`local_transform`] with what an animation gives the node in place of its own
/// translation, rotation and scale (a node with a `matrix` is not animated).
pub fn animated_transform(
    node: &Value,
    animated: Option<&Animated>,
    at: &str,
    sink: &mut dyn Sink,
) -> DMat4 {
    bounded_transform(node, animated, at, sink).value
}

/// [`animated_transform`] with a bound on each entry's distance from the exact matrix of the
/// numbers it is made of ([`BoundedMat4::trs`], whose value is glam's product after
/// normalizing the quaternion; a `matrix` is taken as read, exact).
pub fn bounded_transform(
    node: &Value,
    animated: Option<&Animated>,
    at: &str,
    sink: &mut dyn Sink,
) -> BoundedMat4 {
    let mut read = |key: &str, len: usize| -> Option<Vec<f64>> {
        let list = node
            .get(key)?
            .as_array()
            .filter(|a| a.len() == len)
            .and_then(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>());
        match list {
            Some(list) if list.iter().all(|x| x.is_finite()) => Some(list),
            _ => {
                sink.error(
                    Code::ValueNotInRange,
                    format!("{at}/{key}"),
                    format!("expected {len} finite numbers"),
                );
                None
            }
        }
    };
    if node.get("matrix").is_some() {
        let matrix = read("matrix", 16).map_or(DMat4::IDENTITY, |m| DMat4::from_cols_slice(&m));
        return BoundedMat4::exact(matrix);
    }
    let animated = animated.cloned().unwrap_or_default();
    let t = match animated.translation {
        Some(t) => t,
        None => read("translation", 3).map_or(DVec3::ZERO, |v| DVec3::from_slice(&v)),
    };
    let s = match animated.scale {
        Some(s) => s,
        None => read("scale", 3).map_or(DVec3::ONE, |v| DVec3::from_slice(&v)),
    };
    let stored = match animated.rotation {
        Some(r) => Some(vec![r.x, r.y, r.z, r.w]),
        None => read("rotation", 4),
    };
    let r = match stored {
        None => DQuat::IDENTITY,
        Some(q) => {
            let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
            if q.length_squared() > 0.0 {
                q
            } else {
                sink.error(
                    Code::RotationNonUnit,
                    format!("{at}/rotation"),
                    "zero quaternion",
                );
                DQuat::IDENTITY
            }
        }
    };
    BoundedMat4::trs(t, r, s)
}
