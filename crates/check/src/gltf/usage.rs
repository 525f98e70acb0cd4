//! What each buffer view is used for, as the Khronos glTF-Validator tracks it
//! (`BufferView.setUsage` in `lib/src/base/buffer_view.dart`): a view's `target` (34962, a
//! vertex buffer; 34963, an index buffer) or else its first use sets its usage, and a later
//! use of another kind is BUFFER_VIEW_TARGET_OVERRIDE, reported where that use is.
//!
//! Uses are visited in the validator's link order (`lib/src/base/gltf.dart`): accessors
//! (sparse indices and values: other data), images, meshes (each primitive's attributes as
//! vertex data, then its indices, then its morph targets' attributes), skins (inverse bind
//! matrices), animations (sampler inputs and outputs: other data).

use super::Walker;
use crate::import::gltf::document::{array, as_index, escape, index_of};
use crate::Code;
use serde_json::Value;
use std::fmt;

/// A buffer view's usage.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Usage {
    Vertex,
    Index,
    Image,
    InverseBindMatrices,
    Other,
}

impl fmt::Display for Usage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Usage::Vertex => "vertex data",
            Usage::Index => "indices",
            Usage::Image => "an image",
            Usage::InverseBindMatrices => "inverse bind matrices",
            Usage::Other => "other data (sparse or animation)",
        })
    }
}

/// The usage of each buffer view so far.
struct Usages(Vec<Option<Usage>>);

impl Walker<'_, '_> {
    /// Buffer views used for two kinds of data.
    pub(super) fn buffer_view_usage(&mut self) {
        let mut usages = Usages(
            self.list("bufferViews")
                .iter()
                .map(|v| match v.get("target").and_then(Value::as_u64) {
                    Some(34962) => Some(Usage::Vertex),
                    Some(34963) => Some(Usage::Index),
                    _ => None,
                })
                .collect(),
        );
        for (i, accessor) in self.list("accessors").iter().enumerate() {
            for part in ["indices", "values"] {
                if let Some(sparse) = accessor.get("sparse").and_then(|s| s.get(part)) {
                    let at = format!("/accessors/{i}/sparse/{part}/bufferView");
                    self.use_view(
                        &mut usages,
                        index_of(sparse, "bufferView"),
                        Usage::Other,
                        at,
                    );
                }
            }
        }
        for (i, image) in self.list("images").iter().enumerate() {
            let at = format!("/images/{i}/bufferView");
            self.use_view(&mut usages, index_of(image, "bufferView"), Usage::Image, at);
        }
        self.mesh_usage(&mut usages);
        for (i, skin) in self.list("skins").iter().enumerate() {
            let at = format!("/skins/{i}/inverseBindMatrices");
            let view = self.accessor_view(skin, "inverseBindMatrices");
            self.use_view(&mut usages, view, Usage::InverseBindMatrices, at);
        }
        for (i, animation) in self.list("animations").iter().enumerate() {
            for (j, sampler) in array(animation, "samplers").iter().enumerate() {
                for key in ["input", "output"] {
                    let at = format!("/animations/{i}/samplers/{j}/{key}");
                    let view = self.accessor_view(sampler, key);
                    self.use_view(&mut usages, view, Usage::Other, at);
                }
            }
        }
    }

    /// The uses of the meshes' primitives, in the validator's order.
    fn mesh_usage(&mut self, usages: &mut Usages) {
        for (m, mesh) in self.list("meshes").iter().enumerate() {
            for (p, prim) in array(mesh, "primitives").iter().enumerate() {
                let at = format!("/meshes/{m}/primitives/{p}");
                self.attribute_usage(usages, prim.get("attributes"), &format!("{at}/attributes"));
                let view = self.accessor_view(prim, "indices");
                self.use_view(usages, view, Usage::Index, format!("{at}/indices"));
                for (t, target) in array(prim, "targets").iter().enumerate() {
                    self.attribute_usage(usages, Some(target), &format!("{at}/targets/{t}"));
                }
            }
        }
    }

    /// The vertex data uses of an attributes object at `at`.
    fn attribute_usage(&mut self, usages: &mut Usages, attributes: Option<&Value>, at: &str) {
        let Some(attributes) = attributes.and_then(Value::as_object) else {
            return;
        };
        for (name, accessor) in attributes {
            let view = self.view_of_accessor(as_index(accessor));
            let at = format!("{at}/{}", escape(name));
            self.use_view(usages, view, Usage::Vertex, at);
        }
    }

    /// The buffer view of the accessor `owner[key]` names.
    fn accessor_view(&self, owner: &Value, key: &str) -> Option<usize> {
        self.view_of_accessor(index_of(owner, key))
    }

    /// The buffer view of accessor `accessor`.
    fn view_of_accessor(&self, accessor: Option<usize>) -> Option<usize> {
        index_of(self.list("accessors").get(accessor?)?, "bufferView")
    }

    /// One use of buffer view `view` (an index, perhaps of no view) as `usage`, at `at`.
    fn use_view(&mut self, usages: &mut Usages, view: Option<usize>, usage: Usage, at: String) {
        let Some(slot) = view.and_then(|v| usages.0.get_mut(v)) else {
            return;
        };
        match *slot {
            None => *slot = Some(usage),
            Some(first) if first != usage => self.f.error(
                Code::BufferViewTargetOverride,
                at,
                format!(
                    "buffer view {} is used for {usage}, after being used for {first}",
                    view.unwrap_or_default()
                ),
            ),
            Some(_) => {}
        }
    }
}
