//! STL (stereolithography) meshes, ASCII and binary, through the `stl_io` crate. Vertices
//! are f32, as the format stores them (ASCII numbers are rounded to f32, as `stl_io` parses
//! them); triangles keep the file's order and winding, and corners with the same bits are
//! one vertex.
//!
//! Which encoding a file is, is decided here, not by `stl_io` (which takes every file that
//! starts with `solid ` for ASCII, though binary exporters often begin their 80-byte header
//! with that word): a file whose length is exactly `84 + 50 · n` for the triangle count `n`
//! at bytes 80..84 is binary, as trimesh decides; else text that starts with `solid` is
//! ASCII; else the file is read as binary, and is truncated if shorter than its count says.
//!
//! An ASCII file may hold several `solid … endsolid` blocks: each is a scene object, named
//! by its `solid` line (the file's name when that is empty). `stl_io` reads one solid at a
//! time, with its keywords in lower case (trimesh and most readers ignore their case). A
//! binary file is one object named after the file.

use crate::error::{Error, Result};
use crate::scene::{Mesh, Positions, Scene};
use glam::Vec3;
use raycast_core::diagnostic::Code;
use std::borrow::Cow;
use std::fmt;
use std::io::Cursor;
use std::path::Path;

/// Bytes before the first triangle of a binary STL: the 80-byte header and the count.
const HEADER: usize = 84;
/// Bytes of one binary triangle: normal, three corners, attribute count.
const RECORD: u64 = 50;

/// Why an STL file cannot be read. Each kind has a `raycast check` code ([`StlError::code`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum StlError {
    /// Neither text that starts with `solid` nor long enough for a binary header.
    NotStl {
        /// The file's length.
        bytes: usize,
    },
    /// A binary file shorter than its triangle count needs.
    Truncated {
        /// The count in the header.
        triangles: u32,
        /// The bytes that count needs.
        needs: u64,
        /// The file's length.
        has: u64,
    },
    /// An ASCII solid without its `endsolid` line.
    Unterminated {
        /// The `solid` line, from 1.
        line: usize,
    },
    /// An ASCII line outside a solid that is not a `solid` line.
    Stray {
        /// The line, from 1.
        line: usize,
    },
    /// An ASCII solid that does not parse (`stl_io`'s words).
    Parse {
        /// The `solid` line, from 1.
        line: usize,
        /// What `stl_io` says.
        why: String,
    },
    /// A NaN or infinite corner.
    NonFinite {
        /// The triangle, from 0 in the file.
        triangle: usize,
    },
}

impl StlError {
    /// The `raycast check` code of this error (docs/check.md).
    pub fn code(&self) -> Code {
        match self {
            StlError::NotStl { .. } => Code::StlNotStl,
            StlError::Truncated { .. } | StlError::Unterminated { .. } => Code::StlTruncated,
            StlError::Stray { .. } | StlError::Parse { .. } => Code::StlParseError,
            StlError::NonFinite { .. } => Code::NonFinitePosition,
        }
    }
}

impl fmt::Display for StlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StlError::NotStl { bytes } => write!(
                f,
                "not an STL file: no 'solid' text, and {bytes} bytes are too few for a binary \
                 header"
            ),
            StlError::Truncated {
                triangles,
                needs,
                has,
            } => write!(
                f,
                "truncated: the binary header counts {triangles} triangles, {needs} bytes, but \
                 the file has {has}"
            ),
            StlError::Unterminated { line } => write!(
                f,
                "truncated: the solid of line {line} has no 'endsolid' line"
            ),
            StlError::Stray { line } => {
                write!(
                    f,
                    "line {line}: text outside a 'solid' ... 'endsolid' block"
                )
            }
            StlError::Parse { line, why } => write!(f, "the solid of line {line}: {why}"),
            StlError::NonFinite { triangle } => {
                write!(f, "triangle {triangle} has a corner that is not finite")
            }
        }
    }
}

impl std::error::Error for StlError {}

/// One solid: its name (empty when unnamed) and its mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Solid {
    /// The name on its `solid` line; empty for a binary file or an unnamed solid.
    pub name: String,
    /// Its triangles, in file order.
    pub mesh: Mesh,
}

/// What an STL file draws.
#[derive(Debug, Clone, PartialEq)]
pub struct StlMesh {
    /// The solids, in file order (those without triangles left out).
    pub solids: Vec<Solid>,
    /// What was read past (bytes after a binary file's last triangle).
    pub warnings: Vec<String>,
}

/// Loads an STL file.
pub fn load(path: &Path) -> Result<Scene> {
    super::load_whole(path, load_bytes)
}

/// Loads STL `bytes`; `path` names them in messages and names unnamed solids.
pub fn load_bytes(bytes: &[u8], path: &Path) -> Result<Scene> {
    let mesh = read(bytes).map_err(|e| Error::in_file(path, e.to_string()).with_code(e.code()))?;
    Ok(scene(mesh, path))
}

/// The scene of an STL file read by [`read`]: one object per solid, or an empty scene with
/// the other readers' warning when there is no triangle.
pub fn scene(mesh: StlMesh, path: &Path) -> Scene {
    let objects = mesh.solids.into_iter().map(|solid| {
        let name = if solid.name.is_empty() {
            super::file_stem(path)
        } else {
            solid.name
        };
        (name, solid.mesh)
    });
    super::mesh_file_scene(path, "stl", mesh.warnings, objects.collect(), Vec::new())
}

/// Reads an STL file held in `bytes`.
pub fn read(bytes: &[u8]) -> std::result::Result<StlMesh, StlError> {
    match binary_count(bytes) {
        Some(n) if exact_binary(bytes, n) || !is_ascii(bytes) => read_binary(bytes, n),
        _ if is_ascii(bytes) => read_ascii(&String::from_utf8_lossy(bytes)),
        _ => Err(StlError::NotStl { bytes: bytes.len() }),
    }
}

/// The triangle count of a binary header, when the file is long enough to have one.
fn binary_count(bytes: &[u8]) -> Option<u32> {
    let count = bytes.get(80..HEADER)?;
    Some(u32::from_le_bytes([count[0], count[1], count[2], count[3]]))
}

/// Whether the file is exactly as long as a binary STL of `n` triangles.
fn exact_binary(bytes: &[u8], n: u32) -> bool {
    bytes.len() as u64 == HEADER as u64 + RECORD * u64::from(n)
}

/// Whether the file is text that starts with the word `solid` (in any case, after blanks):
/// no NUL byte, which binary counts and coordinates all but always hold.
fn is_ascii(bytes: &[u8]) -> bool {
    let start = bytes.trim_ascii_start();
    let word = start
        .get(..5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    let ends = start.get(5).is_none_or(u8::is_ascii_whitespace);
    word && ends && !bytes.contains(&0)
}

fn read_binary(bytes: &[u8], n: u32) -> std::result::Result<StlMesh, StlError> {
    let needs = HEADER as u64 + RECORD * u64::from(n);
    let has = bytes.len() as u64;
    if has < needs {
        return Err(StlError::Truncated {
            triangles: n,
            needs,
            has,
        });
    }
    let body = &bytes[..needs as usize];
    // stl_io reads a file that starts with `solid ` as ASCII: blank the header (it holds
    // nothing the reader uses) of a binary file that starts so.
    let body: Cow<[u8]> = if body.starts_with(b"solid") {
        let mut owned = body.to_vec();
        owned[..5].fill(0);
        Cow::Owned(owned)
    } else {
        Cow::Borrowed(body)
    };
    let mesh = stl_mesh(body.as_ref(), 0)?;
    let mut warnings = Vec::new();
    if has > needs {
        warnings.push(format!(
            "{} bytes after the last of the header's {n} triangles ignored",
            has - needs
        ));
    }
    let solids = (!mesh.is_empty()).then(|| Solid {
        name: String::new(),
        mesh,
    });
    Ok(StlMesh {
        solids: solids.into_iter().collect(),
        warnings,
    })
}

fn read_ascii(text: &str) -> std::result::Result<StlMesh, StlError> {
    let mut solids = Vec::new();
    let mut first_triangle = 0;
    // The solid being read: its line, name and the lines of its body in lower case.
    let mut open: Option<(usize, String, String)> = None;
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let keyword = words.next().map(str::to_ascii_lowercase);
        match (&mut open, keyword.as_deref()) {
            (_, None) => {}
            (None, Some("solid")) => {
                let name = line.trim_start()[5..].trim().to_string();
                open = Some((n + 1, name, "solid s\n".to_string()));
            }
            (None, Some(_)) => return Err(StlError::Stray { line: n + 1 }),
            (Some(_), Some("endsolid")) => {
                let (line, name, mut body) = open.take().unwrap_or_default();
                body.push_str("endsolid s\n");
                let mesh = stl_mesh(body.as_bytes(), first_triangle).map_err(|e| match e {
                    StlError::Parse { why, .. } => StlError::Parse { line, why },
                    e => e,
                })?;
                first_triangle += mesh.len();
                if !mesh.is_empty() {
                    solids.push(Solid { name, mesh });
                }
            }
            (Some((_, _, body)), Some(_)) => {
                body.push_str(&line.to_ascii_lowercase());
                body.push('\n');
            }
        }
    }
    if let Some((line, _, _)) = open {
        return Err(StlError::Unterminated { line });
    }
    Ok(StlMesh {
        solids,
        warnings: Vec::new(),
    })
}

/// One solid (or a binary file) read by `stl_io`, its corners checked to be finite;
/// `first` numbers its first triangle in the file, for messages.
fn stl_mesh(bytes: &[u8], first: usize) -> std::result::Result<Mesh, StlError> {
    let parse = |e: std::io::Error| StlError::Parse {
        line: 0,
        why: e.to_string(),
    };
    let mut cursor = Cursor::new(bytes);
    let indexed = stl_io::create_stl_reader(&mut cursor)
        .and_then(|mut r| r.as_indexed_triangles())
        .map_err(parse)?;
    let finite = |v: &stl_io::Vertex| v.0.iter().all(|c| c.is_finite());
    if let Some(t) = indexed
        .faces
        .iter()
        .position(|f| !f.vertices.iter().all(|&i| finite(&indexed.vertices[i])))
    {
        return Err(StlError::NonFinite {
            triangle: first + t,
        });
    }
    // A binary file holds at most 2³² − 1 triangles, so up to three times as many distinct
    // corners; past 2³² − 1 the indices could not be stored.
    if indexed.vertices.len() > u32::MAX as usize {
        return Err(StlError::Parse {
            line: 0,
            why: "more than 2³² − 1 distinct vertices".into(),
        });
    }
    let positions = indexed.vertices.iter().map(|v| Vec3::from_array(v.0));
    let triangles = indexed.faces.iter().map(|f| f.vertices.map(|i| i as u32));
    Ok(Mesh::from_parts(
        Positions::F32(positions.collect()),
        triangles.collect(),
    ))
}

#[cfg(test)]
mod tests;
