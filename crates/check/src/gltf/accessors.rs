//! Accessors: layout, alignment, sparse parts, and the data against `min`/`max`.

use super::Walker;
use crate::import::gltf::accessor::span_fits;
use crate::import::gltf::accessor::Layout;
use crate::import::gltf::document::{index_of, numbers};
use crate::Code;
use serde_json::Value;

impl Walker<'_, '_> {
    pub(super) fn accessors(&mut self) {
        let accessors = self.list("accessors");
        for (i, acc) in accessors.iter().enumerate() {
            let at = format!("/accessors/{i}");
            if acc.get("count").and_then(Value::as_u64) == Some(0) {
                self.f.error(
                    Code::ValueNotInRange,
                    format!("{at}/count"),
                    "must be at least 1",
                );
            }
            let view = index_of(acc, "bufferView");
            let offset = index_of(acc, "byteOffset").unwrap_or(0);
            if view.is_none() && acc.get("byteOffset").is_some() {
                self.f.error(
                    Code::UnsatisfiedDependency,
                    format!("{at}/byteOffset"),
                    "byteOffset without bufferView",
                );
            }
            let Some(layout) = Layout::of(acc) else {
                continue;
            };
            if layout.normalized && matches!(layout.component, 5125 | 5126) {
                self.f.error(
                    Code::AccessorNormalizedInvalid,
                    format!("{at}/normalized"),
                    "only 8- and 16-bit integer accessors can be normalized",
                );
            }
            if let Some(view_index) = view {
                if !offset.is_multiple_of(layout.size) {
                    self.f.error(
                        Code::AccessorOffsetAlignment,
                        format!("{at}/byteOffset"),
                        format!("offset {offset} is not a multiple of {}", layout.size),
                    );
                }
                let view_json = self.list("bufferViews").get(view_index);
                if let Some(v) = &view_json {
                    let view_offset = index_of(v, "byteOffset").unwrap_or(0);
                    if !(view_offset + offset).is_multiple_of(layout.size) {
                        self.f.error(
                            Code::AccessorTotalOffsetAlignment,
                            at.clone(),
                            format!(
                                "total offset {} is not a multiple of {}",
                                view_offset + offset,
                                layout.size
                            ),
                        );
                    }
                    if layout.rows.is_some() && !offset.is_multiple_of(4) {
                        self.f.error(
                            Code::AccessorMatrixAlignment,
                            format!("{at}/byteOffset"),
                            "matrix accessors must start on a 4-byte boundary",
                        );
                    }
                    let stride = index_of(v, "byteStride");
                    if let Some(stride) = stride.filter(|&s| s < layout.element) {
                        self.f.error(
                            Code::AccessorSmallBytestride,
                            at.clone(),
                            format!(
                                "byteStride {stride} is smaller than an element ({} bytes)",
                                layout.element
                            ),
                        );
                    }
                    if let Some(view_length) = index_of(v, "byteLength") {
                        let stride = stride.unwrap_or(layout.element).max(layout.element);
                        if !span_fits(
                            usize::MAX,
                            0,
                            view_length,
                            offset,
                            stride,
                            layout.count.max(1),
                            layout.last,
                        ) {
                            self.f.error(
                                Code::AccessorTooLong,
                                at.clone(),
                                format!("{} elements from offset {offset} do not fit buffer view {view_index} ({view_length} bytes)", layout.count),
                            );
                        }
                    }
                }
            }
            if let Some(sparse) = acc.get("sparse") {
                let n = index_of(sparse, "count").unwrap_or(0);
                if n == 0 || n > layout.count {
                    self.f.error(
                        Code::AccessorSparseCountOutOfRange,
                        format!("{at}/sparse/count"),
                        format!("sparse count {n} is not in 1..={}", layout.count),
                    );
                }
                let ic = sparse
                    .get("indices")
                    .and_then(|x| x.get("componentType"))
                    .and_then(Value::as_u64);
                if ic.is_some_and(|c| !matches!(c, 5121 | 5123 | 5125)) {
                    self.f.error(
                        Code::ValueNotInList,
                        format!("{at}/sparse/indices/componentType"),
                        "sparse indices must be unsigned integers",
                    );
                }
                self.sparse_indices(i, layout.count);
            }
            self.accessor_data(i, &layout, &at);
        }
    }

    /// Sparse indices must increase and stay below the accessor's count.
    fn sparse_indices(&mut self, index: usize, count: usize) {
        let Ok(targets) = self.doc.sparse_indices(index) else {
            return;
        };
        let at = format!("/accessors/{index}/sparse");
        if let Some(k) = (1..targets.len()).find(|&k| targets[k] <= targets[k - 1]) {
            self.f.error(
                Code::AccessorSparseIndicesNonIncreasing,
                at.clone(),
                format!("sparse index {k} ({}) does not increase", targets[k]),
            );
        }
        if let Some(bad) = targets.iter().find(|&&t| t >= count) {
            self.f.error(
                Code::AccessorSparseIndexOob,
                at,
                format!("sparse index {bad} >= count {count}"),
            );
        }
    }

    /// Non-finite floats and min/max against the data.
    fn accessor_data(&mut self, index: usize, layout: &Layout, at: &str) {
        let acc = &self.list("accessors")[index];
        let min = numbers(acc, "min");
        let max = numbers(acc, "max");
        for (key, bound) in [("min", &min), ("max", &max)] {
            if bound.as_ref().is_some_and(|b| b.len() != layout.comps) {
                self.f.error(
                    Code::AccessorMinMaxCount,
                    format!("{at}/{key}"),
                    format!("{key} must have {} entries", layout.comps),
                );
            }
        }
        // Bounds of meshopt-decoded data are not compared: the writer declares them from the
        // data before its lossy filter (glTF-Validator, which does not decode, cannot compare
        // them either).
        let decoded = index_of(acc, "bufferView").is_some_and(|v| self.doc.is_decoded_view(v));
        let Some(values) = self.values(index).filter(|_| !decoded) else {
            return;
        };
        if layout.component == 5126 {
            if let Some(bad) = values.iter().position(|v| !v.is_finite()) {
                self.f.error(
                    Code::AccessorInvalidFloat,
                    at.to_string(),
                    format!("element {} holds NaN or infinity", bad / layout.comps),
                );
                return;
            }
        }
        let comps = layout.comps;
        let mut actual_min = vec![f64::INFINITY; comps];
        let mut actual_max = vec![f64::NEG_INFINITY; comps];
        for element in values.chunks_exact(comps) {
            for c in 0..comps {
                actual_min[c] = actual_min[c].min(element[c]);
                actual_max[c] = actual_max[c].max(element[c]);
            }
        }
        let as_stored = |v: f64| {
            if layout.component == 5126 {
                v as f32 as f64
            } else {
                v
            }
        };
        if let Some(min) = min.filter(|m| m.len() == comps) {
            for c in 0..comps {
                let declared = as_stored(min[c]);
                if actual_min[c] < declared {
                    self.f.error(
                        Code::AccessorElementOutOfMinBound,
                        format!("{at}/min/{c}"),
                        format!(
                            "a value {} is below the declared min {}",
                            actual_min[c], min[c]
                        ),
                    );
                }
                if actual_min[c] != declared {
                    self.f.error(
                        Code::AccessorMinMismatch,
                        format!("{at}/min/{c}"),
                        format!(
                            "declared min {} but the data's is {}",
                            min[c], actual_min[c]
                        ),
                    );
                }
            }
        }
        if let Some(max) = max.filter(|m| m.len() == comps) {
            for c in 0..comps {
                let declared = as_stored(max[c]);
                if actual_max[c] > declared {
                    self.f.error(
                        Code::AccessorElementOutOfMaxBound,
                        format!("{at}/max/{c}"),
                        format!(
                            "a value {} is above the declared max {}",
                            actual_max[c], max[c]
                        ),
                    );
                }
                if actual_max[c] != declared {
                    self.f.error(
                        Code::AccessorMaxMismatch,
                        format!("{at}/max/{c}"),
                        format!(
                            "declared max {} but the data's is {}",
                            max[c], actual_max[c]
                        ),
                    );
                }
            }
        }
    }
}
