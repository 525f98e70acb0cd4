//! KHR_draco_mesh_compression: one primitive's Draco stream decoded with `draco-core`.
//!
//! The caller hands over the bytes of the extension's buffer view and the extension's JSON;
//! it gets back the positions (as the stream stores them, widened to f64) and the triangle
//! list. The stream's own ceilings ([`draco_core::DecodeLimits`]) are tightened to what one
//! glTF primitive may hold, so a hostile header cannot make us allocate gigabytes.

use crate::error::{Error, Result};
use draco_core::{DecodeLimits, DecoderBuffer, Mesh, MeshDecoder};
use serde_json::Value;

/// Extension name.
pub const EXTENSION: &str = "KHR_draco_mesh_compression";

/// Most points or faces one decoded primitive may have.
const MAX_ELEMENTS: u64 = 1 << 26;

/// Most bytes of attribute values one decoded primitive may have.
const MAX_DECODED_BYTES: u64 = 1 << 31;

/// The connectivity coding a Draco mesh stream uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Faces stored one by one.
    Sequential,
    /// Faces stored as an EdgeBreaker traversal.
    Edgebreaker,
}

/// A decoded Draco primitive.
#[derive(Debug, Clone, PartialEq)]
pub struct DracoPrimitive {
    /// Position components per point, as stored (integers are not normalized here).
    pub positions: Vec<[f64; 3]>,
    /// Three point indices per triangle.
    pub indices: Vec<u32>,
    /// How the connectivity was coded.
    pub method: Method,
}

/// The buffer view index that `extension` (the primitive's `KHR_draco_mesh_compression`
/// object) names.
pub fn buffer_view(extension: &Value) -> Result<usize> {
    extension
        .get("bufferView")
        .and_then(Value::as_u64)
        .map(|v| v as usize)
        .ok_or_else(|| {
            Error::msg(format!(
                "{EXTENSION}: bufferView is missing or not an index"
            ))
        })
}

/// Decodes the Draco stream `bytes` of a primitive whose extension object is `extension`.
pub fn decode(bytes: &[u8], extension: &Value) -> Result<DracoPrimitive> {
    let position_id = extension
        .get("attributes")
        .and_then(|a| a.get("POSITION"))
        .and_then(Value::as_u64)
        .and_then(|id| u32::try_from(id).ok())
        .ok_or_else(|| {
            Error::msg(format!(
                "{EXTENSION}: attributes.POSITION is missing or not an id"
            ))
        })?;
    let method = method(bytes)?;
    let mesh = decode_mesh(bytes)?;
    let attribute = mesh.attribute_by_unique_id(position_id).ok_or_else(|| {
        Error::msg(format!(
            "{EXTENSION}: the Draco stream has no attribute {position_id} for POSITION"
        ))
    })?;
    if attribute.num_components() != 3 {
        return Err(Error::msg(format!(
            "{EXTENSION}: POSITION attribute has {} components, not 3",
            attribute.num_components()
        )));
    }
    let points = mesh.num_points();
    let positions = attribute
        .read_f32s(points, 3)
        .chunks_exact(3)
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect();
    let indices: Vec<u32> = mesh.faces().as_flattened().iter().map(|p| p.0).collect();
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= points) {
        return Err(Error::msg(format!(
            "{EXTENSION}: face index {bad} out of range ({points} points)"
        )));
    }
    Ok(DracoPrimitive {
        positions,
        indices,
        method,
    })
}

/// Decodes a Draco mesh stream under the limits of one glTF primitive.
fn decode_mesh(bytes: &[u8]) -> Result<Mesh> {
    let limits = DecodeLimits::default()
        .with_max_points(MAX_ELEMENTS)
        .with_max_faces(MAX_ELEMENTS)
        .with_max_decoded_bytes(MAX_DECODED_BYTES);
    let mut buffer = DecoderBuffer::new(bytes).with_limits(limits);
    let mut mesh = Mesh::new();
    MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| Error::msg(format!("{EXTENSION}: cannot decode the Draco stream: {e}")))?;
    Ok(mesh)
}

/// The values of the attribute the extension maps glTF attribute `name` to (JOINTS_0, say),
/// `comps` per point as stored (integers are not normalized here), in the decoded point
/// order; `Ok(None)` when the extension does not compress that attribute.
pub fn decode_attribute(
    bytes: &[u8],
    extension: &Value,
    name: &str,
    comps: usize,
) -> Result<Option<Vec<f64>>> {
    let Some(id) = extension.get("attributes").and_then(|a| a.get(name)) else {
        return Ok(None);
    };
    let id = id
        .as_u64()
        .and_then(|id| u32::try_from(id).ok())
        .ok_or_else(|| Error::msg(format!("{EXTENSION}: attributes.{name} is not an id")))?;
    method(bytes)?;
    let mesh = decode_mesh(bytes)?;
    let attribute = mesh.attribute_by_unique_id(id).ok_or_else(|| {
        Error::msg(format!(
            "{EXTENSION}: the Draco stream has no attribute {id} for {name}"
        ))
    })?;
    if attribute.num_components() as usize != comps {
        return Err(Error::msg(format!(
            "{EXTENSION}: {name} attribute has {} components, not {comps}",
            attribute.num_components()
        )));
    }
    let values = attribute.read_f32s(mesh.num_points(), comps);
    Ok(Some(values.into_iter().map(f64::from).collect()))
}

/// Reads the connectivity method from the stream header ("DRACO", major, minor, geometry
/// type, method), refusing streams that are not triangle meshes.
pub fn method(bytes: &[u8]) -> Result<Method> {
    match bytes {
        [b'D', b'R', b'A', b'C', b'O', _, _, 1, method, ..] => match method {
            0 => Ok(Method::Sequential),
            1 => Ok(Method::Edgebreaker),
            other => Err(Error::msg(format!(
                "{EXTENSION}: unknown Draco mesh method {other}"
            ))),
        },
        [b'D', b'R', b'A', b'C', b'O', _, _, kind, ..] => Err(Error::msg(format!(
            "{EXTENSION}: the Draco stream is not a triangle mesh (geometry type {kind})"
        ))),
        _ => Err(Error::msg(format!(
            "{EXTENSION}: the buffer view is not a Draco stream"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn refuses_what_is_not_a_draco_mesh() {
        let extension = json!({"bufferView": 0, "attributes": {"POSITION": 0}});
        let err = decode(b"not draco at all", &extension).unwrap_err().message;
        assert!(err.contains("not a Draco stream"), "{err}");
        let point_cloud = b"DRACO\x02\x02\x00\x00\x00";
        let err = decode(point_cloud, &extension).unwrap_err().message;
        assert!(err.contains("not a triangle mesh"), "{err}");
        let truncated = b"DRACO\x02\x02\x01\x01\x00";
        let err = decode(truncated, &extension).unwrap_err().message;
        assert!(err.contains("cannot decode"), "{err}");
    }

    #[test]
    fn needs_a_position_id_and_a_buffer_view() {
        let err = decode(b"DRACO\x02\x02\x01\x00", &json!({"attributes": {}}))
            .unwrap_err()
            .message;
        assert!(err.contains("attributes.POSITION"), "{err}");
        assert!(buffer_view(&json!({"attributes": {}})).is_err());
        assert_eq!(buffer_view(&json!({"bufferView": 3})), Ok(3));
    }
}
