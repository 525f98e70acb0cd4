//! EXT_meshopt_compression and KHR_meshopt_compression: one buffer view decoded with the
//! `meshopt` crate (meshoptimizer's own decoders and filters).
//!
//! The caller hands over the compressed bytes the extension names and the extension's JSON;
//! it gets back the buffer view's plain bytes (`count * byteStride`), to be read through the
//! usual accessors.

use crate::error::{Error, Result};
use serde_json::Value;

/// The two names of the extension (same layout; the KHR one allows newer codec versions,
/// which the decoder reads too).
pub const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// Most bytes one decoded buffer view may have.
const MAX_DECODED_BYTES: usize = 1 << 30;

/// How a buffer view was encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Vertex attributes.
    Attributes,
    /// A triangle list's indices.
    Triangles,
    /// Any other index sequence.
    Indices,
}

/// The filter applied after decoding attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// None.
    None,
    /// Octahedral unit vectors (8 or 16 bits per component).
    Octahedral,
    /// Quaternions with the largest component dropped (16 bits per component).
    Quaternion,
    /// Floats as a shared exponent and 24-bit mantissa.
    Exponential,
    /// YCoCg colours (KHR_meshopt_compression only).
    Color,
}

/// The extension object of one buffer view.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshoptView {
    /// Buffer holding the compressed bytes.
    pub buffer: usize,
    /// Offset of the compressed bytes in it.
    pub byte_offset: usize,
    /// Length of the compressed bytes.
    pub byte_length: usize,
    /// Bytes per decoded element.
    pub byte_stride: usize,
    /// Decoded elements.
    pub count: usize,
    /// Codec.
    pub mode: Mode,
    /// Filter (attributes only).
    pub filter: Filter,
}

impl MeshoptView {
    /// Reads the extension object of a buffer view.
    pub fn parse(extension: &Value) -> Result<MeshoptView> {
        let index = |key: &str| -> Result<usize> {
            extension
                .get(key)
                .and_then(Value::as_u64)
                .and_then(|v| usize::try_from(v).ok())
                .ok_or_else(|| {
                    Error::msg(format!("{key} is missing or not a non-negative integer"))
                })
        };
        let byte_offset = match extension.get("byteOffset") {
            None => 0,
            Some(_) => index("byteOffset")?,
        };
        let mode = match extension.get("mode").and_then(Value::as_str) {
            Some("ATTRIBUTES") => Mode::Attributes,
            Some("TRIANGLES") => Mode::Triangles,
            Some("INDICES") => Mode::Indices,
            other => return Err(Error::msg(format!("unknown mode {other:?}"))),
        };
        let filter = match extension.get("filter").and_then(Value::as_str) {
            None | Some("NONE") => Filter::None,
            Some("OCTAHEDRAL") => Filter::Octahedral,
            Some("QUATERNION") => Filter::Quaternion,
            Some("EXPONENTIAL") => Filter::Exponential,
            Some("COLOR") => Filter::Color,
            Some(other) => return Err(Error::msg(format!("unknown filter '{other}'"))),
        };
        let view = MeshoptView {
            buffer: index("buffer")?,
            byte_offset,
            byte_length: index("byteLength")?,
            byte_stride: index("byteStride")?,
            count: index("count")?,
            mode,
            filter,
        };
        view.check()?;
        Ok(view)
    }

    /// Refuses combinations the codec does not define, and oversized views.
    fn check(&self) -> Result<()> {
        let stride = self.byte_stride;
        let stride_ok = match self.mode {
            Mode::Attributes => stride.is_multiple_of(4) && (4..=256).contains(&stride),
            Mode::Triangles | Mode::Indices => stride == 2 || stride == 4,
        };
        if !stride_ok {
            return Err(Error::msg(format!(
                "byteStride {stride} is not allowed in mode {:?}",
                self.mode
            )));
        }
        let filter_ok = match (self.mode, self.filter) {
            (_, Filter::None) | (Mode::Attributes, Filter::Exponential) => true,
            (Mode::Attributes, Filter::Octahedral | Filter::Color) => stride == 4 || stride == 8,
            (Mode::Attributes, Filter::Quaternion) => stride == 8,
            _ => false,
        };
        if !filter_ok {
            return Err(Error::msg(format!(
                "filter {:?} does not apply to mode {:?} with byteStride {stride}",
                self.filter, self.mode
            )));
        }
        if self.mode == Mode::Triangles && !self.count.is_multiple_of(3) {
            return Err(Error::msg(format!(
                "TRIANGLES count {} is not a multiple of 3",
                self.count
            )));
        }
        match self.count.checked_mul(stride) {
            Some(n) if n <= MAX_DECODED_BYTES => Ok(()),
            _ => Err(Error::msg(format!(
                "decodes to more than {MAX_DECODED_BYTES} bytes ({} x {stride})",
                self.count
            ))),
        }
    }
}

/// Decodes the compressed bytes `encoded` of a view described by `view` into its plain bytes.
pub fn decode(encoded: &[u8], view: &MeshoptView) -> Result<Vec<u8>> {
    let fail = |e: meshopt::Error| {
        Error::msg(format!(
            "cannot decode {:?} data: the compressed bytes are malformed ({e})",
            view.mode
        ))
    };
    let mut bytes = match (view.mode, view.byte_stride) {
        (Mode::Attributes, stride) => decode_attributes(encoded, view.count, stride)?,
        (Mode::Triangles, 2) => {
            u16_bytes(&meshopt::decode_index_buffer::<u16>(encoded, view.count).map_err(fail)?)
        }
        (Mode::Triangles, _) => {
            u32_bytes(&meshopt::decode_index_buffer::<u32>(encoded, view.count).map_err(fail)?)
        }
        (Mode::Indices, 2) => {
            u16_bytes(&meshopt::decode_index_sequence::<u16>(encoded, view.count).map_err(fail)?)
        }
        (Mode::Indices, _) => {
            u32_bytes(&meshopt::decode_index_sequence::<u32>(encoded, view.count).map_err(fail)?)
        }
    };
    apply_filter(&mut bytes, view.filter, view.byte_stride);
    Ok(bytes)
}

/// Decodes a vertex stream of `count` elements of `stride` bytes (a multiple of 4 up to 256).
fn decode_attributes(encoded: &[u8], count: usize, stride: usize) -> Result<Vec<u8>> {
    /// One element: `S` bytes (arrays over 32 have no `Default`).
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    struct Element<const S: usize>([u8; S]);
    impl<const S: usize> Default for Element<S> {
        fn default() -> Self {
            Element([0; S])
        }
    }
    fn run<const S: usize>(encoded: &[u8], count: usize) -> Result<Vec<u8>> {
        meshopt::decode_vertex_buffer::<Element<S>>(encoded, count)
            .map(|v| v.iter().flat_map(|e| e.0).collect())
            .map_err(|e| {
                Error::msg(format!(
                    "cannot decode Attributes data: the compressed bytes are malformed ({e})"
                ))
            })
    }
    macro_rules! by_stride {
        ($($s:literal)*) => {
            match stride {
                $($s => run::<$s>(encoded, count),)*
                other => Err(Error::msg(format!(
                    "byteStride {other} is not allowed in mode Attributes"
                ))),
            }
        };
    }
    by_stride!(4 8 12 16 20 24 28 32 36 40 44 48 52 56 60 64 68 72 76 80 84 88 92 96 100 104 108
        112 116 120 124 128 132 136 140 144 148 152 156 160 164 168 172 176 180 184 188 192 196
        200 204 208 212 216 220 224 228 232 236 240 244 248 252 256)
}

/// Runs a decode filter in place over decoded attribute bytes. The component types only
/// choose the element size the filter expects (4 or 8 bytes); signedness is the filter's.
fn apply_filter(bytes: &mut [u8], filter: Filter, stride: usize) {
    match (filter, stride) {
        (Filter::None, _) => {}
        (Filter::Octahedral, 4) => in_groups(bytes, meshopt::decode_filter_oct::<i8>),
        (Filter::Octahedral, _) => in_groups(bytes, meshopt::decode_filter_oct::<i16>),
        (Filter::Color, 4) => in_groups(bytes, meshopt::decode_filter_color::<i8>),
        (Filter::Color, _) => in_groups(bytes, meshopt::decode_filter_color::<i16>),
        (Filter::Quaternion, _) => in_groups(bytes, meshopt::decode_filter_quat),
        // Each 32-bit component is decoded on its own, so any stride is a run of u32s.
        (Filter::Exponential, _) => in_groups(bytes, meshopt::decode_filter_exp::<1>),
    }
}

/// A little-endian component of a filter's element.
trait Component: Copy {
    const SIZE: usize;
    fn read(bytes: &[u8]) -> Self;
    fn write(self, out: &mut [u8]);
}

macro_rules! component {
    ($($t:ty)*) => {$(
        impl Component for $t {
            const SIZE: usize = std::mem::size_of::<$t>();
            fn read(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(std::array::from_fn(|i| bytes[i]))
            }
            fn write(self, out: &mut [u8]) {
                out[..Self::SIZE].copy_from_slice(&self.to_le_bytes());
            }
        }
    )*};
}
component!(i8 i16 u32);

/// Runs `filter` over `bytes` seen as elements of `N` components of type `C`.
fn in_groups<C: Component, const N: usize>(bytes: &mut [u8], filter: impl FnOnce(&mut [[C; N]])) {
    let size = C::SIZE * N;
    let mut items: Vec<[C; N]> = bytes
        .chunks_exact(size)
        .map(|g| std::array::from_fn(|i| C::read(&g[i * C::SIZE..])))
        .collect();
    filter(&mut items);
    for (out, item) in bytes.chunks_exact_mut(size).zip(items) {
        for (i, c) in item.into_iter().enumerate() {
            c.write(&mut out[i * C::SIZE..]);
        }
    }
}

/// Little-endian bytes of 16-bit indices.
fn u16_bytes(indices: &[u16]) -> Vec<u8> {
    indices.iter().flat_map(|i| i.to_le_bytes()).collect()
}

/// Little-endian bytes of 32-bit indices.
fn u32_bytes(indices: &[u32]) -> Vec<u8> {
    indices.iter().flat_map(|i| i.to_le_bytes()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn view(mode: &str, stride: usize, count: usize, filter: &str) -> Value {
        json!({"buffer": 0, "byteLength": 1, "byteStride": stride, "count": count,
               "mode": mode, "filter": filter})
    }

    #[test]
    fn parses_and_refuses_layouts() {
        let ok = MeshoptView::parse(&view("ATTRIBUTES", 8, 10, "QUATERNION")).unwrap();
        assert_eq!(
            (ok.mode, ok.filter, ok.byte_offset),
            (Mode::Attributes, Filter::Quaternion, 0)
        );
        for (mode, stride, count, filter) in [
            ("ATTRIBUTES", 6, 1, "NONE"),
            ("ATTRIBUTES", 260, 1, "NONE"),
            ("ATTRIBUTES", 12, 1, "QUATERNION"),
            ("ATTRIBUTES", 12, 1, "OCTAHEDRAL"),
            ("TRIANGLES", 2, 4, "NONE"),
            ("TRIANGLES", 8, 3, "NONE"),
            ("INDICES", 2, 3, "EXPONENTIAL"),
            ("STRIPS", 2, 3, "NONE"),
            ("ATTRIBUTES", 4, 1, "SPLINE"),
            ("ATTRIBUTES", 256, 1 << 30, "NONE"),
        ] {
            let err = MeshoptView::parse(&view(mode, stride, count, filter));
            assert!(err.is_err(), "{mode} {stride} {count} {filter} accepted");
        }
    }

    #[test]
    fn index_modes_round_trip_through_the_library_encoders() {
        // The triangle codec may rotate a triangle's corners (keeping its winding): compare
        // each triangle starting from its smallest index.
        let canonical = |t: &[u32]| -> Vec<[u32; 3]> {
            t.chunks_exact(3)
                .map(|c| {
                    let k = (0..3).min_by_key(|&k| c[k]).unwrap();
                    [c[k], c[(k + 1) % 3], c[(k + 2) % 3]]
                })
                .collect()
        };
        let triangles: Vec<u32> = vec![0, 1, 2, 2, 1, 3, 3, 4, 2, 70000, 4, 3];
        let encoded = meshopt::encode_index_buffer(&triangles, 70001).unwrap();
        let mut v = MeshoptView::parse(&view("TRIANGLES", 4, 12, "NONE")).unwrap();
        let bytes = decode(&encoded, &v).unwrap();
        let decoded: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(canonical(&decoded), canonical(&triangles));
        let lines: Vec<u32> = vec![5, 6, 6, 7, 7, 5, 0, 9];
        let encoded = meshopt::encode_index_sequence(&lines, 10).unwrap();
        v = MeshoptView::parse(&view("INDICES", 2, 8, "NONE")).unwrap();
        let expected: Vec<u16> = lines.iter().map(|&i| i as u16).collect();
        assert_eq!(decode(&encoded, &v).unwrap(), u16_bytes(&expected));
    }

    #[test]
    fn attributes_at_an_odd_stride_round_trip() {
        let vertices: Vec<[u8; 36]> = (0..40u8)
            .map(|i| std::array::from_fn(|j| i ^ j as u8))
            .collect();
        let encoded = meshopt::encode_vertex_buffer(&vertices).unwrap();
        let v = MeshoptView::parse(&view("ATTRIBUTES", 36, 40, "NONE")).unwrap();
        assert_eq!(decode(&encoded, &v).unwrap(), vertices.as_flattened());
    }

    #[test]
    fn exponential_filter_gives_the_floats_back() {
        // 2^E * M with E in the top byte and a 24-bit signed mantissa: (-3, 3) is 3/8 = 0.375,
        // (2, -5) is -20.
        let words = [(0xFDu32 << 24) | 3, (2u32 << 24) | (0x00FF_FFFB)];
        let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        apply_filter(&mut bytes, Filter::Exponential, 8);
        let floats: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(floats, [0.375, -20.0]);
    }

    #[test]
    fn garbage_is_an_error_not_a_crash() {
        let v = MeshoptView::parse(&view("ATTRIBUTES", 12, 100, "NONE")).unwrap();
        assert!(decode(&[0xA0, 1, 2, 3], &v).is_err());
        let v = MeshoptView::parse(&view("TRIANGLES", 2, 300, "NONE")).unwrap();
        assert!(decode(&[0xE1, 0, 0], &v).is_err());
        assert!(decode(&[], &v).is_err());
    }
}
