//! Buffer views and accessors: layout (component types, matrix column padding, strides),
//! bounds checked before any byte is read, and decoding to `f64` — normalized and quantized
//! integers, sparse substitution, and accessors without a buffer view (zeros).
//!
//! Every byte goes through [`Document::view_bytes`], which also serves the views a decoder
//! produced (EXT_meshopt_compression), so compressed and plain data are read the same way.

use super::diagnostics::{Code, Diagnostic};
use super::document::{index_of, Document};
use serde_json::Value;
use std::sync::atomic::Ordering;

/// Most values (elements × components) one accessor may decode to; it bounds what an
/// accessor without a buffer view (not limited by the file's size) can make us allocate.
pub const MAX_VALUES: usize = 64 << 20;

/// Memory one value of an accessor without a buffer view is charged against the limit of
/// [`Document::limit_unbacked`]: its 8 bytes decoded, and its share of what the scene builds
/// from it (a triangle, 128 bytes in the scene as `raycast check` estimates it, is 9 position
/// values). A 593-byte file of three such 20-million-vertex accessors took 1.6 GB to render.
pub const UNBACKED_BYTES_PER_VALUE: u64 = 24;

/// Code of a read that needs a buffer whose data is not available (no `uri`, or a network
/// URI): the file is valid, the data is elsewhere.
pub const NO_DATA: Code = Code::BufferNoData;

/// Component byte size of a glTF `componentType`.
pub fn component_size(kind: u64) -> Option<usize> {
    match kind {
        5120 | 5121 => Some(1),
        5122 | 5123 => Some(2),
        5125 | 5126 => Some(4),
        _ => None,
    }
}

/// Components per element of an accessor `type`, and rows when it is a matrix.
pub fn type_shape(kind: &str) -> Option<(usize, Option<usize>)> {
    match kind {
        "SCALAR" => Some((1, None)),
        "VEC2" => Some((2, None)),
        "VEC3" => Some((3, None)),
        "VEC4" => Some((4, None)),
        "MAT2" => Some((4, Some(2))),
        "MAT3" => Some((9, Some(3))),
        "MAT4" => Some((16, Some(4))),
        _ => None,
    }
}

/// The layout of one accessor, when its JSON is well formed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    /// glTF `componentType` (5120..=5126).
    pub component: u64,
    /// Bytes per component.
    pub size: usize,
    /// Components per element.
    pub comps: usize,
    /// Rows of a matrix type.
    pub rows: Option<usize>,
    /// Elements.
    pub count: usize,
    /// Integers mapped to [0, 1] or [-1, 1].
    pub normalized: bool,
    /// Bytes of one element including matrix column padding.
    pub element: usize,
    /// Bytes the last element needs (without the last column's padding).
    pub last: usize,
}

impl Layout {
    /// The layout an accessor's JSON declares; `None` when a property is missing or invalid.
    pub fn of(acc: &Value) -> Option<Layout> {
        let component = index_of(acc, "componentType")? as u64;
        let size = component_size(component)?;
        let (comps, rows) = type_shape(acc.get("type")?.as_str()?)?;
        let count = index_of(acc, "count")?;
        let (element, last) = match rows {
            // Matrix columns start on 4-byte boundaries.
            Some(rows) => {
                let column = (rows * size).div_ceil(4) * 4;
                (column * rows, column * (rows - 1) + rows * size)
            }
            None => (comps * size, comps * size),
        };
        Some(Layout {
            component,
            size,
            comps,
            rows,
            count,
            normalized: acc.get("normalized").and_then(Value::as_bool) == Some(true),
            element,
            last,
        })
    }

    /// A scalar layout for `count` integers of `component` type (sparse indices).
    fn scalar(component: u64, count: usize) -> Option<Layout> {
        let size = component_size(component)?;
        Some(Layout {
            component,
            size,
            comps: 1,
            rows: None,
            count,
            normalized: false,
            element: size,
            last: size,
        })
    }

    /// Byte offset of component `c` inside an element.
    pub fn component_offset(&self, c: usize) -> usize {
        match self.rows {
            Some(rows) => (c / rows) * (rows * self.size).div_ceil(4) * 4 + (c % rows) * self.size,
            None => c * self.size,
        }
    }

    /// The component at byte `at` of `bytes`, as stored (no normalization). The caller has
    /// checked the span; a short slice reads zeros rather than panicking.
    pub fn read(&self, bytes: &[u8], at: usize) -> f64 {
        let b = |i: usize| bytes.get(at + i).copied().unwrap_or(0);
        match self.component {
            5120 => b(0) as i8 as f64,
            5121 => b(0) as f64,
            5122 => i16::from_le_bytes([b(0), b(1)]) as f64,
            5123 => u16::from_le_bytes([b(0), b(1)]) as f64,
            5125 => u32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64,
            _ => f32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64,
        }
    }

    /// A stored component as the value it stands for: normalized integers map to [0, 1]
    /// (unsigned) or [-1, 1] (signed, the most negative clamped to -1), per the specification.
    pub fn dequantize(&self, stored: f64) -> f64 {
        if !self.normalized {
            return stored;
        }
        match self.component {
            5120 => (stored / 127.0).max(-1.0),
            5121 => stored / 255.0,
            5122 => (stored / 32767.0).max(-1.0),
            5123 => stored / 65535.0,
            _ => stored,
        }
    }
}

/// True when `items` elements of `size` bytes, `stride` apart from `offset` inside a buffer
/// view (`view_offset`, `view_length`) of a buffer of `buffer_len` bytes, all lie inside the
/// view and the view inside the buffer, without overflow.
pub fn span_fits(
    buffer_len: usize,
    view_offset: usize,
    view_length: usize,
    offset: usize,
    stride: usize,
    items: usize,
    size: usize,
) -> bool {
    let view_end = view_offset.checked_add(view_length);
    let last = stride
        .checked_mul(items.saturating_sub(1))
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(size));
    matches!((view_end, last), (Some(end), Some(last)) if end <= buffer_len && last <= view_length)
        && stride >= size
        && items > 0
}

impl Document {
    /// The bytes of buffer view `view`: decoded bytes when a decoder produced them, else the
    /// view's range of its buffer. Fails when the view does not exist, its buffer was not
    /// read, or the range does not fit the buffer.
    pub fn view_bytes(&self, view: usize) -> Result<&[u8], Diagnostic> {
        if let Some(bytes) = self.decoded_views.get(&view) {
            return Ok(bytes);
        }
        let at = format!("/bufferViews/{view}");
        let json = self.item("bufferViews", view).ok_or_else(|| {
            Diagnostic::error(Code::UnresolvedReference, &at, "buffer view does not exist")
        })?;
        let buffer = index_of(json, "buffer").ok_or_else(|| {
            Diagnostic::error(Code::UndefinedProperty, format!("{at}/buffer"), "no buffer")
        })?;
        let bytes = self.buffer(buffer).ok_or_else(|| {
            Diagnostic::error(
                NO_DATA,
                format!("{at}/buffer"),
                format!("buffer {buffer} has no data that raycast can read"),
            )
        })?;
        let too_long = |what: String| {
            Diagnostic::error(
                Code::BufferViewTooLong,
                format!("{at}/byteLength"),
                format!("{what} do not fit buffer {buffer} ({} bytes)", bytes.len()),
            )
        };
        let length = match (json.get("byteLength"), index_of(json, "byteLength")) {
            (_, Some(length)) => length,
            (None, None) => {
                return Err(Diagnostic::error(
                    Code::UndefinedProperty,
                    format!("{at}/byteLength"),
                    "no byteLength",
                ))
            }
            // A whole number past 2^53, as tinygltf's bounds test has (1e300).
            (Some(v), None) if v.as_f64().is_some_and(|x| x > 0.0 && x.fract() == 0.0) => {
                return Err(too_long(format!("{v} bytes")));
            }
            (Some(v), None) => {
                return Err(Diagnostic::error(
                    Code::TypeMismatch,
                    format!("{at}/byteLength"),
                    format!("{v} is not a length in bytes"),
                ))
            }
        };
        let offset = index_of(json, "byteOffset").unwrap_or(0);
        offset
            .checked_add(length)
            .and_then(|end| bytes.get(offset..end))
            .ok_or_else(|| too_long(format!("bytes {offset}..+{length}")))
    }

    /// Limits what accessors without a buffer view (zeros of any length, which the file's
    /// size does not bound) may take to `bytes` in all, at [`UNBACKED_BYTES_PER_VALUE`]; one
    /// that would pass it is refused with `ASSET_TOO_LARGE`, naming `--max-memory`.
    pub fn limit_unbacked(&self, bytes: u64) {
        self.unbacked_budget.store(bytes, Ordering::Relaxed);
    }

    /// What accessors without a buffer view may still take: the limit of
    /// [`Document::limit_unbacked`] less what they took since.
    pub fn unbacked_left(&self) -> u64 {
        self.unbacked_budget.load(Ordering::Relaxed)
    }

    /// Charges `values` decoded by accessor `index`, which has no buffer view, against the
    /// limit of [`Document::limit_unbacked`].
    fn charge_unbacked(&self, index: usize, count: usize, values: usize) -> Result<(), Diagnostic> {
        let need = (values as u64).saturating_mul(UNBACKED_BYTES_PER_VALUE);
        let left = self.unbacked_left();
        if need > left {
            return Err(Diagnostic::error(
                Code::AssetTooLarge,
                format!("/accessors/{index}/count"),
                format!(
                    "accessor {index} has no buffer view: its {count} elements (zeros) would take about {}, more than the memory limit leaves (raise it with --max-memory)",
                    crate::sizes::human_bytes(need)
                ),
            ));
        }
        // One reader charges at a time (a scene build: see `Prepared::build`).
        self.unbacked_budget.store(left - need, Ordering::Relaxed);
        Ok(())
    }

    /// The layout of accessor `index`.
    pub fn layout(&self, index: usize) -> Result<Layout, Diagnostic> {
        let acc = self.item("accessors", index).ok_or_else(|| {
            Diagnostic::error(
                Code::UnresolvedReference,
                format!("/accessors/{index}"),
                "accessor does not exist",
            )
        })?;
        Layout::of(acc).ok_or_else(|| {
            Diagnostic::error(
                Code::AccessorInvalid,
                format!("/accessors/{index}"),
                "componentType, type or count is missing or invalid",
            )
        })
    }

    /// Decodes accessor `index` to its stored component values (`count × comps`, not
    /// normalized: see [`Layout::dequantize`]), sparse values applied. An accessor without a
    /// buffer view is zeros but for its sparse values.
    pub fn accessor_values(&self, index: usize) -> Result<(Layout, Vec<f64>), Diagnostic> {
        let layout = self.layout(index)?;
        let acc = &self.list("accessors")[index];
        let at = format!("/accessors/{index}");
        if layout.count == 0 {
            let at = format!("{at}/count");
            return Err(Diagnostic::error(
                Code::ValueNotInRange,
                at,
                "must be at least 1",
            ));
        }
        let Some(total) = layout
            .count
            .checked_mul(layout.comps)
            .filter(|&t| t <= MAX_VALUES)
        else {
            return Err(Diagnostic::error(
                Code::AssetTooLarge,
                format!("{at}/count"),
                format!(
                    "count {} is more than raycast decodes ({MAX_VALUES} values)",
                    layout.count
                ),
            ));
        };
        let view = index_of(acc, "bufferView");
        if view.is_none() {
            self.charge_unbacked(index, layout.count, total)?;
        }
        let mut values = vec![0.0; total];
        if let Some(view) = view {
            let bytes = self.view_bytes(view)?;
            let offset = index_of(acc, "byteOffset").unwrap_or(0);
            let stride = self
                .item("bufferViews", view)
                .and_then(|v| index_of(v, "byteStride"))
                .unwrap_or(layout.element);
            if !span_fits(
                bytes.len(),
                0,
                bytes.len(),
                offset,
                stride.max(layout.element),
                layout.count,
                layout.last,
            ) {
                return Err(Diagnostic::error(
                    Code::AccessorTooLong,
                    at,
                    format!(
                        "{} elements from offset {offset} run past the end of buffer view {view} ({} bytes)",
                        layout.count,
                        bytes.len()
                    ),
                ));
            }
            for (e, element) in values.chunks_exact_mut(layout.comps).enumerate() {
                let start = offset + e * stride;
                for (c, value) in element.iter_mut().enumerate() {
                    *value = layout.read(bytes, start + layout.component_offset(c));
                }
            }
        }
        if acc.get("sparse").is_some() {
            self.apply_sparse(index, &layout, &mut values)?;
        }
        Ok((layout, values))
    }

    /// The element indices of accessor `index`'s sparse part, as stored (they should
    /// increase and be below `count`; the caller checks).
    pub fn sparse_indices(&self, index: usize) -> Result<Vec<usize>, Diagnostic> {
        let acc = &self.list("accessors")[index];
        let at = format!("/accessors/{index}/sparse");
        let bad =
            |what: &str| Diagnostic::error(Code::AccessorSparseInvalid, &at, what.to_string());
        let sparse = acc.get("sparse").ok_or_else(|| bad("no sparse part"))?;
        let count = index_of(sparse, "count")
            .filter(|&n| n > 0)
            .ok_or_else(|| bad("invalid sparse count"))?;
        let indices = sparse
            .get("indices")
            .ok_or_else(|| bad("no sparse indices"))?;
        let kind = index_of(indices, "componentType").map(|c| c as u64);
        let layout = kind
            .filter(|c| matches!(c, 5121 | 5123 | 5125))
            .and_then(|c| Layout::scalar(c, count))
            .ok_or_else(|| bad("sparse indices must be unsigned integers"))?;
        let bytes = self.sparse_part(indices, &layout, &at)?;
        Ok((0..count)
            .map(|k| layout.read(bytes, k * layout.size) as usize)
            .collect())
    }

    /// The bytes of a sparse `indices` or `values` part, checked to hold `layout.count`
    /// tightly packed elements.
    fn sparse_part(&self, part: &Value, layout: &Layout, at: &str) -> Result<&[u8], Diagnostic> {
        let view = index_of(part, "bufferView").ok_or_else(|| {
            Diagnostic::error(
                Code::UndefinedProperty,
                at,
                "a sparse part without bufferView",
            )
        })?;
        let bytes = self.view_bytes(view)?;
        let offset = index_of(part, "byteOffset").unwrap_or(0);
        if !span_fits(
            bytes.len(),
            0,
            bytes.len(),
            offset,
            layout.element,
            layout.count,
            layout.element,
        ) {
            return Err(Diagnostic::error(
                Code::AccessorTooLong,
                at,
                "the sparse data does not fit its buffer view",
            ));
        }
        Ok(&bytes[offset..])
    }

    /// Writes the sparse values of accessor `index` over `values`.
    fn apply_sparse(
        &self,
        index: usize,
        layout: &Layout,
        values: &mut [f64],
    ) -> Result<(), Diagnostic> {
        let at = format!("/accessors/{index}/sparse");
        let targets = self.sparse_indices(index)?;
        if targets.len() > layout.count {
            return Err(Diagnostic::error(
                Code::AccessorSparseCountOutOfRange,
                format!("{at}/count"),
                format!(
                    "sparse count {} is more than count {}",
                    targets.len(),
                    layout.count
                ),
            ));
        }
        let part = self.list("accessors")[index]["sparse"]
            .get("values")
            .ok_or_else(|| {
                Diagnostic::error(
                    Code::UndefinedProperty,
                    format!("{at}/values"),
                    "no sparse values",
                )
            })?;
        let packed = Layout {
            count: targets.len(),
            ..*layout
        };
        let bytes = self.sparse_part(part, &packed, &format!("{at}/values"))?;
        for (k, &target) in targets.iter().enumerate() {
            if target >= layout.count {
                return Err(Diagnostic::error(
                    Code::AccessorSparseIndexOob,
                    &at,
                    format!("sparse index {target} >= count {}", layout.count),
                ));
            }
            for c in 0..layout.comps {
                values[target * layout.comps + c] =
                    layout.read(bytes, k * layout.element + layout.component_offset(c));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_padding() {
        let acc: Value = serde_json::json!({"componentType": 5121, "type": "MAT3", "count": 1});
        let l = Layout::of(&acc).unwrap();
        assert_eq!(l.element, 12);
        assert_eq!(l.component_offset(3), 4);
    }

    #[test]
    fn normalized_integers() {
        let acc: Value = serde_json::json!({"componentType": 5120, "type": "VEC3", "count": 1, "normalized": true});
        let l = Layout::of(&acc).unwrap();
        // The specification's rule: max(c / 127, -1).
        assert_eq!(l.dequantize(-128.0), -1.0);
        assert_eq!(l.dequantize(127.0), 1.0);
        let acc: Value =
            serde_json::json!({"componentType": 5123.0, "type": "SCALAR", "count": 2e0});
        let l = Layout::of(&acc).expect("integers written as floats are integers");
        assert_eq!((l.count, l.dequantize(65535.0)), (2, 65535.0));
    }

    #[test]
    fn unbacked_sparse_accessor_is_zeros_but_its_sparse_values() {
        // Buffer: one u8 sparse index (1), padding, then the f32 values (1, 2, 3).
        let json = serde_json::json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": 16, "uri": "data:application/octet-stream;base64,AQAAAAAAgD8AAABAAABAQA=="}],
            "bufferViews": [
                {"buffer": 0, "byteLength": 1},
                {"buffer": 0, "byteOffset": 4, "byteLength": 12}
            ],
            "accessors": [{
                "componentType": 5126, "count": 3, "type": "VEC3",
                "sparse": {"count": 1,
                    "indices": {"bufferView": 0, "componentType": 5121},
                    "values": {"bufferView": 1}}
            }]
        });
        let mut sink = crate::import::gltf::FailFast::default();
        let mut doc = Document::parse(json.to_string().into_bytes(), false, &mut sink).unwrap();
        let here = std::path::Path::new(".");
        let resources = crate::import::gltf::buffers::Resources {
            base: here,
            root: here,
            allow_outside: false,
            max_bytes: 1 << 20,
        };
        doc.load_buffers(&resources, None, &mut sink);
        assert_eq!(sink.error, None);
        let (_, values) = doc.accessor_values(0).unwrap();
        assert_eq!(values, [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0]);
    }
}
