//! Reading NumPy `.npy` arrays: ray files (`--rays`, (N, 6) or (N, 8)), query points
//! (`raycast distance`, (N, 3)) and stored buffers (`raycast check --golden`), float32 or
//! float64 (and uint8 for flags), C or Fortran order. The writer is `output::npy`.

use crate::error::{Error, Result};
use crate::geometry::Ray;
use glam::DVec3;
use std::path::Path;

/// The rays of a ray file in file order, and those that cannot be traced.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RayFile {
    /// Every ray, in file order (untraceable ones included: they count as misses).
    pub rays: Vec<Ray>,
    /// Each ray's parameter range `(tmin, tmax]`, from an (N, 8) file; `None` for an (N, 6)
    /// file (every ray from `t > 0`).
    pub ranges: Option<Vec<(f64, f64)>>,
    /// The rays with a non-finite origin or direction, or a zero direction.
    pub untraceable: Vec<Untraceable>,
}

/// A ray that cannot be traced, and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Untraceable {
    /// Its row in the file.
    pub index: usize,
    /// `origin` or `direction`.
    pub field: &'static str,
    /// `is not finite` or `is zero`.
    pub problem: &'static str,
}

impl std::fmt::Display for Untraceable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ray {}: the {} {}", self.index, self.field, self.problem)
    }
}

/// Reads an (N, 6) or (N, 8) float32 or float64 array (C or Fortran order) of ray origins and
/// directions, and with 8 columns each ray's `tmin` and `tmax` (a hit needs `tmin < t <= tmax`;
/// a NaN or negative `tmin`, a NaN `tmax` or `tmin > tmax` is an error). Rays with a non-finite origin or direction or a zero direction are kept and
/// listed in [`RayFile::untraceable`]; the tracer counts them as misses.
pub fn read_rays(path: &Path) -> Result<RayFile> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    parse_rays(&bytes).map_err(|e| e.with_path(path))
}

/// Why `ray` cannot be traced, if it cannot.
fn untraceable(index: usize, ray: &Ray) -> Option<Untraceable> {
    let (field, problem) = if !ray.origin.is_finite() {
        ("origin", "is not finite")
    } else if !ray.dir.is_finite() {
        ("direction", "is not finite")
    } else if ray.dir == DVec3::ZERO {
        ("direction", "is zero")
    } else {
        return None;
    };
    Some(Untraceable {
        index,
        field,
        problem,
    })
}

/// Reads a float64 (`<f8`), uint32 (`<u4`) or byte (`|u1`) array as written by [`write`]: its
/// shape and its values as f64.
pub fn read(path: &Path) -> Result<(Vec<usize>, Vec<f64>)> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    parse_array(&bytes).map_err(|e| e.with_path(path))
}

fn parse_array(bytes: &[u8]) -> Result<(Vec<usize>, Vec<f64>)> {
    let header = parse_header(bytes)?;
    if header.fortran && header.shape.len() > 1 {
        return Err(Error::msg("Fortran-ordered arrays are not supported here"));
    }
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
        "|u1" => data.iter().map(|&b| f64::from(b)).collect(),
        other => {
            return Err(Error::msg(format!(
                "expected float64, uint32 or uint8 data, found '{other}'"
            )))
        }
    };
    if values.len() != count {
        return Err(Error::msg(format!(
            "data holds {} values, shape needs {count}",
            values.len()
        )));
    }
    Ok((header.shape, values))
}

/// A two-dimensional float32 or float64 array of an `.npy` file, read in place.
struct Table<'a> {
    data: &'a [u8],
    width: usize,
    fortran: bool,
    rows: usize,
    columns: usize,
}

impl<'a> Table<'a> {
    /// The (N, C) float table of `bytes`, `C` one of `columns`; `shapes` says which shapes
    /// are expected, for the error.
    fn parse(bytes: &'a [u8], columns: &[usize], shapes: &str) -> Result<Table<'a>> {
        let header = parse_header(bytes)?;
        let (rows, width_columns) = match header.shape[..] {
            [rows, c] if columns.contains(&c) => (rows, c),
            _ => {
                return Err(Error::msg(format!(
                    "expected shape {shapes}, found {:?}",
                    header.shape
                )))
            }
        };
        let width = match header.descr.as_str() {
            "<f4" => 4,
            "<f8" => 8,
            other => {
                return Err(Error::msg(format!(
                    "expected float32 or float64 little-endian data, found '{other}'"
                )))
            }
        };
        let data = &bytes[header.data_offset..];
        let needed = rows
            .checked_mul(width_columns * width)
            .ok_or_else(|| Error::msg("array too large"))?;
        if data.len() != needed {
            return Err(Error::msg(format!(
                "data holds {} bytes, shape needs {needed}",
                data.len()
            )));
        }
        Ok(Table {
            data,
            width,
            fortran: header.fortran,
            rows,
            columns: width_columns,
        })
    }

    /// Element (r, c): C order stores rows one after another, Fortran order columns.
    fn at(&self, r: usize, c: usize) -> f64 {
        let i = match self.fortran {
            false => r * self.columns + c,
            true => c * self.rows + r,
        };
        let b = &self.data[i * self.width..(i + 1) * self.width];
        match self.width {
            4 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

/// Reads an (N, 3) float32 or float64 array (C or Fortran order) of points; every point must
/// be finite (the error names the first that is not).
pub fn read_points(path: &Path) -> Result<Vec<DVec3>> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    parse_points(&bytes).map_err(|e| e.with_path(path))
}

fn parse_points(bytes: &[u8]) -> Result<Vec<DVec3>> {
    let table = Table::parse(bytes, &[3], "(N, 3) (x, y, z)")?;
    let points: Vec<DVec3> = (0..table.rows)
        .map(|r| DVec3::new(table.at(r, 0), table.at(r, 1), table.at(r, 2)))
        .collect();
    match points.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(Error::msg(format!(
            "point {i} is not finite: {}",
            points[i]
        ))),
        None => Ok(points),
    }
}

fn parse_rays(bytes: &[u8]) -> Result<RayFile> {
    let table = Table::parse(
        bytes,
        &[6, 8],
        "(N, 6) (origin, direction) or (N, 8) (origin, direction, tmin, tmax)",
    )?;
    let (rows, columns) = (table.rows, table.columns);
    let at = |r: usize, c: usize| table.at(r, c);
    let rays: Vec<Ray> = (0..rows)
        .map(|r| {
            let v = |c: usize| at(r, c);
            Ray::new(DVec3::new(v(0), v(1), v(2)), DVec3::new(v(3), v(4), v(5)))
        })
        .collect();
    let untraceable = rays
        .iter()
        .enumerate()
        .filter_map(|(i, ray)| untraceable(i, ray))
        .collect();
    let ranges = (columns == 8)
        .then(|| {
            (0..rows)
                .map(|r| check_range(r, at(r, 6), at(r, 7)))
                .collect::<std::result::Result<Vec<_>, _>>()
        })
        .transpose()?;
    Ok(RayFile {
        rays,
        ranges,
        untraceable,
    })
}

/// Ray `index`'s range `(tmin, tmax]`, or why it is not one.
fn check_range(index: usize, tmin: f64, tmax: f64) -> Result<(f64, f64)> {
    if tmin.is_nan() || tmin < 0.0 {
        Err(Error::msg(format!(
            "ray {index}: tmin {tmin} is not a number >= 0"
        )))
    } else if tmax.is_nan() {
        Err(Error::msg(format!("ray {index}: tmax is NaN")))
    } else if tmin > tmax {
        Err(Error::msg(format!(
            "ray {index}: tmin {tmin} is greater than tmax {tmax}"
        )))
    } else {
        Ok((tmin, tmax))
    }
}

/// What the header of an `.npy` file says.
struct Header {
    descr: String,
    fortran: bool,
    shape: Vec<usize>,
    data_offset: usize,
}

fn parse_header(bytes: &[u8]) -> Result<Header> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(Error::msg("not a .npy file"));
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(Error::msg(format!("unsupported .npy version {v}"))),
    };
    let end = start
        .checked_add(len)
        .filter(|&e| e <= bytes.len())
        .ok_or_else(|| Error::msg("truncated .npy header"))?;
    let text = std::str::from_utf8(&bytes[start..end])
        .map_err(|_| Error::msg("the .npy header is not text"))?;
    let fortran = dict_value(text, "fortran_order").is_some_and(|v| v.starts_with("True"));
    let descr = dict_value(text, "descr")
        .and_then(|v| v.split('\'').nth(1))
        .ok_or_else(|| Error::msg("the .npy header has no 'descr'"))?
        .to_string();
    let shape_text = dict_value(text, "shape")
        .and_then(|v| v.strip_prefix('('))
        .and_then(|v| v.split(')').next())
        .ok_or_else(|| Error::msg("the .npy header has no 'shape'"))?;
    let shape = shape_text
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| Error::msg(format!("bad shape entry '{s}'")))
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    Ok(Header {
        descr,
        fortran,
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
        npy_ordered(descr, false, shape, data)
    }

    fn npy_ordered(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let order = if fortran { "True" } else { "False" };
        let header =
            format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}\n");
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
            let rays = parse_rays(&bytes).unwrap().rays;
            assert_eq!(rays, vec![Ray::new(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z)]);
        }
    }

    /// A `certain` buffer (uint8) reads back as its 0s and 1s.
    #[test]
    fn reads_bytes() {
        let (shape, values) = parse_array(&npy("|u1", "(3,)", &[1, 0, 1])).unwrap();
        assert_eq!((shape, values), (vec![3], vec![1.0, 0.0, 1.0]));
    }

    #[test]
    fn reads_fortran_ordered_rays() {
        // numpy's `.T` of a C-order (6, 2) array: the (2, 6) array stored column by column
        // (the .npy format stores a Fortran-ordered array's columns one after another).
        let rows = [
            [1.0f64, 2.0, 3.0, 0.0, 0.0, -1.0],
            [4.0, 5.0, 6.0, 1.0, 0.0, 0.0],
        ];
        let columns: Vec<u8> = (0..6)
            .flat_map(|c| rows.map(|r| r[c]))
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let file = parse_rays(&npy_ordered("<f8", true, "(2, 6)", &columns)).unwrap();
        let expected =
            rows.map(|r| Ray::new(DVec3::new(r[0], r[1], r[2]), DVec3::new(r[3], r[4], r[5])));
        assert_eq!(file.rays, expected);
    }

    #[test]
    fn untraceable_rays_are_listed_with_their_field() {
        let values = [
            [0.0, 0.0, 5.0, 0.0, 0.0, -1.0],
            [f64::NAN, 0.0, 5.0, 0.0, 0.0, -1.0],
            [0.0, 0.0, 5.0, 0.0, f64::INFINITY, -1.0],
            [0.0, 0.0, 5.0, 0.0, 0.0, 0.0],
        ];
        let f8: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let file = parse_rays(&npy("<f8", "(4, 6)", &f8)).unwrap();
        assert_eq!(file.rays.len(), 4);
        let listed: Vec<String> = file.untraceable.iter().map(|u| u.to_string()).collect();
        assert_eq!(
            listed,
            [
                "ray 1: the origin is not finite",
                "ray 2: the direction is not finite",
                "ray 3: the direction is zero"
            ]
        );
    }

    #[test]
    fn reads_ranges_from_eight_columns() {
        let values = [
            [0.0f64, 0.0, 5.0, 0.0, 0.0, -1.0, 0.5, f64::INFINITY],
            [1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0, 2.0],
        ];
        let f8: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let file = parse_rays(&npy("<f8", "(2, 8)", &f8)).unwrap();
        assert_eq!(file.rays[1], Ray::new(DVec3::new(1.0, 2.0, 3.0), DVec3::X));
        assert_eq!(file.ranges, Some(vec![(0.5, f64::INFINITY), (0.0, 2.0)]));
        let six: Vec<u8> = values[0][..6]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert_eq!(
            parse_rays(&npy("<f8", "(1, 6)", &six)).unwrap().ranges,
            None
        );
    }

    #[test]
    fn rejects_bad_ranges() {
        let cases = [
            (f64::NAN, 1.0, "ray 0: tmin NaN is not a number >= 0"),
            (-1.0, 1.0, "ray 0: tmin -1 is not a number >= 0"),
            (0.0, f64::NAN, "ray 0: tmax is NaN"),
            (2.0, 1.0, "ray 0: tmin 2 is greater than tmax 1"),
        ];
        for (tmin, tmax, message) in cases {
            let row = [0.0f64, 0.0, 5.0, 0.0, 0.0, -1.0, tmin, tmax];
            let f8: Vec<u8> = row.iter().flat_map(|v| v.to_le_bytes()).collect();
            assert_eq!(
                parse_rays(&npy("<f8", "(1, 8)", &f8)).unwrap_err().message,
                message
            );
        }
    }

    #[test]
    fn rejects_bad_arrays() {
        let f8: Vec<u8> = [0.0f64; 6].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert!(parse_rays(&npy("<f8", "(2, 3)", &f8))
            .unwrap_err()
            .message
            .contains("shape"));
        let seven: Vec<u8> = [0.0f64; 7].iter().flat_map(|v| v.to_le_bytes()).collect();
        assert!(parse_rays(&npy("<f8", "(1, 7)", &seven))
            .unwrap_err()
            .message
            .contains("expected shape (N, 6) (origin, direction) or (N, 8)"));
        assert!(parse_rays(&npy("<i4", "(1, 6)", &f8))
            .unwrap_err()
            .message
            .contains("float"));
        assert!(parse_rays(&npy("<f8", "(2, 6)", &f8))
            .unwrap_err()
            .message
            .contains("bytes"));
        assert!(parse_rays(b"garbage").is_err());
    }
}
