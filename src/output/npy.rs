//! NumPy `.npy` files (format version 1.0): writing buffers and reading ray lists.

use crate::error::{Error, Result};
use crate::geometry::Ray;
use glam::DVec3;
use std::io::Write;
use std::path::Path;

/// The element data of an array to write.
#[derive(Debug, Clone, Copy)]
pub enum NpyData<'a> {
    /// Little-endian float64 (`<f8`).
    F64(&'a [f64]),
    /// Little-endian uint32 (`<u4`).
    U32(&'a [u32]),
}

/// Writes a C-order array of the given shape.
pub fn write(path: &Path, shape: &[usize], data: NpyData) -> Result<()> {
    let (descr, bytes): (&str, Vec<u8>) = match data {
        NpyData::F64(v) => ("<f8", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
        NpyData::U32(v) => ("<u4", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
    };
    let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
    let shape_text = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_text}, }}");
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + bytes.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(&bytes);
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(&out))
        .map_err(|e| Error::in_file(path, format!("cannot write: {e}")))
}

/// Reads an (N, 6) float32 or float64 array of ray origins and directions. Every ray must
/// have finite numbers and a non-zero direction.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    parse_rays(&bytes).map_err(|m| Error::in_file(path, m))
}

/// Reads a float64 (`<f8`) or uint32 (`<u4`) array as written by [`write`]: its shape and its
/// values as f64.
pub fn read(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    parse_array(&bytes).map_err(|m| Error::in_file(path, m))
}

fn parse_array(bytes: &[u8]) -> std::result::Result<(Vec<usize>, Vec<f64>), String> {
    let header = parse_header(bytes)?;
    let data = &bytes[header.data_offset..];
    let count: usize = header.shape.iter().product();
    let values: Vec<f64> = match header.descr.as_str() {
        "<f8" => data
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect(),
        "<u4" => data
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
            .collect(),
        other => return Err(format!("expected float64 or uint32 data, found '{other}'")),
    };
    if values.len() != count {
        return Err(format!(
            "data holds {} values, shape needs {count}",
            values.len()
        ));
    }
    Ok((header.shape, values))
}

fn parse_rays(bytes: &[u8]) -> std::result::Result<Vec<Ray>, String> {
    let header = parse_header(bytes)?;
    let rows = match header.shape[..] {
        [rows, 6] => rows,
        _ => return Err(format!("expected shape (N, 6), found {:?}", header.shape)),
    };
    let width = match header.descr.as_str() {
        "<f4" => 4,
        "<f8" => 8,
        other => {
            return Err(format!(
                "expected float32 or float64 little-endian data, found '{other}'"
            ))
        }
    };
    let data = &bytes[header.data_offset..];
    let needed = rows.checked_mul(6 * width).ok_or("array too large")?;
    if data.len() != needed {
        return Err(format!(
            "data holds {} bytes, shape needs {needed}",
            data.len()
        ));
    }
    let value = |i: usize| -> f64 {
        let b = &data[i * width..(i + 1) * width];
        match width {
            4 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    };
    (0..rows)
        .map(|r| {
            let v = |c: usize| value(r * 6 + c);
            let ray = Ray::new(DVec3::new(v(0), v(1), v(2)), DVec3::new(v(3), v(4), v(5)));
            if ray.is_valid() {
                Ok(ray)
            } else {
                Err(format!(
                    "ray {r} has a non-finite value or a zero direction"
                ))
            }
        })
        .collect()
}

/// What the header of an `.npy` file says.
struct Header {
    descr: String,
    shape: Vec<usize>,
    data_offset: usize,
}

fn parse_header(bytes: &[u8]) -> std::result::Result<Header, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy file".into());
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("unsupported .npy version {v}")),
    };
    let end = start
        .checked_add(len)
        .filter(|&e| e <= bytes.len())
        .ok_or("truncated .npy header")?;
    let text =
        std::str::from_utf8(&bytes[start..end]).map_err(|_| "the .npy header is not text")?;
    if dict_value(text, "fortran_order").is_some_and(|v| v.starts_with("True")) {
        return Err("Fortran-ordered arrays are not supported".into());
    }
    let descr = dict_value(text, "descr")
        .and_then(|v| v.split('\'').nth(1))
        .ok_or("the .npy header has no 'descr'")?
        .to_string();
    let shape_text = dict_value(text, "shape")
        .and_then(|v| v.strip_prefix('('))
        .and_then(|v| v.split(')').next())
        .ok_or("the .npy header has no 'shape'")?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad shape entry '{s}'"))
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok(Header {
        descr,
        shape,
        data_offset: end,
    })
}

/// The text after `'key':` in the header dictionary.
fn dict_value<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    let at = text.find(&format!("'{key}'"))?;
    let rest = &text[at + key.len() + 2..];
    Some(rest.trim_start().strip_prefix(':')?.trim_start())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}\n");
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn reads_float32_and_float64_rays() {
        let values = [0.0f64, 0.0, 5.0, 0.0, 0.0, -1.0];
        let f8: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let f4: Vec<u8> = values
            .iter()
            .flat_map(|v| (*v as f32).to_le_bytes())
            .collect();
        for bytes in [npy("<f8", "(1, 6)", &f8), npy("<f4", "(1, 6)", &f4)] {
            let rays = parse_rays(&bytes).unwrap();
            assert_eq!(rays, vec![Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z)]);
        }
    }

    #[test]
    fn rejects_bad_arrays() {
        let f8: Vec<u8> = [0.0f64; 6].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert!(parse_rays(&npy("<f8", "(1, 6)", &f8))
            .unwrap_err()
            .contains("zero direction"));
        assert!(parse_rays(&npy("<f8", "(2, 3)", &f8))
            .unwrap_err()
            .contains("shape"));
        assert!(parse_rays(&npy("<i4", "(1, 6)", &f8))
            .unwrap_err()
            .contains("float"));
        assert!(parse_rays(&npy("<f8", "(2, 6)", &f8))
            .unwrap_err()
            .contains("bytes"));
        assert!(parse_rays(b"garbage").is_err());
    }
}
