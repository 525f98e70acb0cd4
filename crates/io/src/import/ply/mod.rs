//! PLY (Stanford polygon files): ASCII, binary little-endian and binary big-endian bodies.
//! The `vertex` element's `x`, `y`, `z` (any scalar type; kept in f64 where the file has
//! doubles, see [`crate::scene::Positions`]) and the `face` element's `vertex_indices` (or
//! `vertex_index`) lists of any integer type are read; polygons are fanned into triangles
//! from their first corner, as the OBJ reader triangulates them. Other properties and
//! elements are read past and dropped. The file is one scene object named after the file.
//! Header lines that are no PLY statement are skipped with one warning ([`header::warnings`]);
//! an ASCII body whose records do not fit the header as one stream of values is read one
//! record per line, as trimesh reads it, with one warning ([`read`]).
//!
//! The reader is written here rather than taken from `ply-rs` 0.1.3, the one PLY crate: its
//! last release is from 2020, it needs `peg` and a `skeptic` build script, and it keeps every
//! record as a map of named properties (hundreds of bytes per vertex of a scan).
//!
//! Memory is bounded by the file: before an element is read, its declared count times the
//! fewest bytes a record takes must fit in what is left of the body, so that a header that
//! claims 10⁹ vertices in a 1 KiB file is refused before anything is allocated.

mod body;
pub mod header;

use crate::error::{Error, Result};
use crate::scene::attributes::corners;
use crate::scene::{Attributes, Mesh, Positions, Scene};
use body::{Body, Fault, Layout, RecordEnd};
use glam::DVec3;
use header::{Element, Format, Header, Kind, Scalar};
use raycast_core::diagnostic::Code;
use std::fmt;
use std::path::Path;

/// Why a PLY file cannot be read. Each kind has a `raycast check` code ([`PlyError::code`]).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum PlyError {
    /// The header is not a PLY header, or declares what the reader cannot use.
    Header {
        /// The header line, from 1.
        line: usize,
        /// What is wrong with it.
        why: String,
    },
    /// The header declares more records than the rest of the file can hold.
    Oversized {
        /// The element.
        element: String,
        /// Its declared count.
        count: u64,
        /// The fewest bytes that many records take.
        needs: u64,
        /// The bytes left in the body.
        left: u64,
    },
    /// The body ends inside a record.
    Truncated {
        /// The element.
        element: String,
        /// The record (from 0) that is cut short.
        record: u64,
        /// The declared count.
        count: u64,
    },
    /// An ASCII value that is not a number of its property's type.
    Value {
        /// The element.
        element: String,
        /// The record, from 0.
        record: u64,
        /// The token as written (shortened).
        token: String,
        /// The property's type.
        scalar: Scalar,
    },
    /// A face corner that is not one of the vertices (PLY indices count from 0).
    IndexOutOfRange {
        /// The face, from 0.
        face: u64,
        /// The index.
        index: i64,
        /// The number of vertices.
        vertices: u64,
    },
    /// A vertex used by a face that is NaN or infinite.
    NonFinite {
        /// The vertex, from 0.
        vertex: usize,
    },
}

impl PlyError {
    /// The `raycast check` code of this error (docs/check.md).
    pub fn code(&self) -> Code {
        match self {
            PlyError::Header { .. } => Code::PlyHeaderError,
            PlyError::Oversized { .. } | PlyError::Truncated { .. } => Code::PlyTruncated,
            PlyError::Value { .. } => Code::PlyParseError,
            PlyError::IndexOutOfRange { .. } => Code::IndexOob,
            PlyError::NonFinite { .. } => Code::NonFinitePosition,
        }
    }
}

impl fmt::Display for PlyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PlyError::Header { line, why } => write!(f, "PLY header line {line}: {why}"),
            PlyError::Oversized {
                element,
                count,
                needs,
                left,
            } => write!(
                f,
                "truncated: the header declares {count} '{element}' records, at least {needs} \
                 bytes, but {left} bytes are left in the file"
            ),
            PlyError::Truncated {
                element,
                record,
                count,
            } => write!(
                f,
                "truncated: the file ends in '{element}' record {record} of {count}"
            ),
            PlyError::Value {
                element,
                record,
                token,
                scalar,
            } => write!(
                f,
                "'{element}' record {record}: '{token}' is not a {}",
                scalar_name(*scalar)
            ),
            PlyError::IndexOutOfRange {
                face,
                index,
                vertices,
            } => write!(
                f,
                "face {face} refers to vertex {index}, but the file has {vertices} vertices \
                 (numbered from 0)"
            ),
            PlyError::NonFinite { vertex } => write!(f, "vertex {vertex} is not finite"),
        }
    }
}

impl std::error::Error for PlyError {}

fn scalar_name(scalar: Scalar) -> &'static str {
    match scalar {
        Scalar::I8 => "char",
        Scalar::U8 => "uchar",
        Scalar::I16 => "short",
        Scalar::U16 => "ushort",
        Scalar::I32 => "int",
        Scalar::U32 => "uint",
        Scalar::F32 => "float",
        Scalar::F64 => "double",
    }
}

/// What a PLY file draws: its vertices and its faces as triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyMesh {
    /// The `vertex` records' positions (empty when the file has no faces to draw).
    pub positions: Vec<DVec3>,
    /// The faces fanned into triangles, in file order.
    pub triangles: Vec<[u32; 3]>,
    /// The vertices' texture coordinates (`u v`, `s t` or `texture_u texture_v`), if any.
    pub uv: Vec<[f32; 2]>,
    /// The vertices' normals (`nx ny nz`), if any.
    pub normals: Vec<[f32; 3]>,
    /// What was read past (faces of fewer than three corners, data after the last element).
    pub warnings: Vec<String>,
}

/// Loads a PLY file.
pub fn load(path: &Path) -> Result<Scene> {
    super::load_whole(path, load_bytes)
}

/// Loads PLY `bytes`; `path` names them in messages and names the scene object.
pub fn load_bytes(bytes: &[u8], path: &Path) -> Result<Scene> {
    let mesh = read(bytes).map_err(|e| Error::in_file(path, e.to_string()).with_code(e.code()))?;
    Ok(scene(mesh, path))
}

/// The scene of a PLY file read by [`read`]: one object named after the file, or an empty
/// scene with the glTF, OBJ and USD readers' warning when there is no face.
pub fn scene(mesh: PlyMesh, path: &Path) -> Scene {
    let objects = if mesh.triangles.is_empty() {
        Vec::new()
    } else {
        // `read` checked every index and every vertex a face uses.
        let attributes = Attributes {
            uv: corners(&mesh.uv, &mesh.triangles),
            normals: corners(&mesh.normals, &mesh.triangles),
            materials: Vec::new(),
        };
        let drawn = Mesh::from_parts(Positions::exact(mesh.positions), mesh.triangles);
        vec![(super::file_stem(path), drawn.with_attributes(attributes))]
    };
    super::mesh_file_scene(path, "ply", mesh.warnings, objects, Vec::new())
}

/// Reads a PLY file held in `bytes`. An ASCII body is read as one stream of values (as rply
/// reads it); when that fails, or its records do not end with their lines, it is read again
/// one record per line, as trimesh reads ASCII PLY, and that reading is kept (with a warning)
/// if it succeeds.
pub fn read(bytes: &[u8]) -> std::result::Result<PlyMesh, PlyError> {
    let header = header::parse(bytes)?;
    let roles = Roles::of(&header)?;
    let body = &bytes[header.body_start..];
    let stream = read_body(body, &header, &roles, Layout::Stream);
    let stream_problem = match &stream {
        _ if header.format != Format::Ascii => None,
        Ok(out) if out.off_line.records == 0 => None,
        Ok(out) => Some(out.off_line.describe("end before their line does")),
        Err(e) => Some(e.to_string()),
    };
    let Some(problem) = stream_problem else {
        return finish(stream?, &header);
    };
    match read_body(body, &header, &roles, Layout::Lines) {
        Ok(out) => {
            let warning = lines_warning(&problem, &out.off_line);
            let mut mesh = finish(out, &header)?;
            mesh.warnings.insert(0, warning);
            Ok(mesh)
        }
        Err(_) => stream.and_then(|out| finish(out, &header)),
    }
}

/// The one warning for an ASCII body read one record per line.
fn lines_warning(problem: &str, off_line: &OffLine) -> String {
    format!(
        "ASCII records do not follow the header as one stream of values ({problem}): read one \
         record per line, as trimesh reads them; {}: values past their properties ignored, \
         missing values left out",
        off_line.describe("do not fill their line exactly")
    )
}

/// The body read in one layout: the geometry and the bytes left after the last element.
struct Read {
    out: Collected,
    left: u64,
    blank_rest: bool,
    off_line: OffLine,
}

/// ASCII records that did not end with their lines: how many, and the first.
#[derive(Default)]
struct OffLine {
    records: u64,
    first: Option<(String, u64)>,
}

impl OffLine {
    fn note(&mut self, element: &str, record: u64) {
        self.records += 1;
        if self.first.is_none() {
            self.first = Some((element.to_string(), record));
        }
    }

    /// "N records {what} (first: 'face' record 3)".
    fn describe(&self, what: &str) -> String {
        let (element, record) = self.first.clone().unwrap_or_default();
        format!(
            "{} records {what} (first: '{element}' record {record})",
            self.records
        )
    }
}

fn read_body(
    bytes: &[u8],
    header: &Header,
    roles: &Roles,
    layout: Layout,
) -> std::result::Result<Read, PlyError> {
    let mut body = Body::new(bytes, header.format, layout);
    let mut out = Collected::default();
    let mut off_line = OffLine::default();
    for (k, element) in header.elements.iter().enumerate() {
        let role = roles.of_element(k);
        read_element(element, role, &mut body, &mut out, &mut off_line)?;
    }
    Ok(Read {
        out,
        left: body.remaining(),
        blank_rest: body.rest_is_blank(),
        off_line,
    })
}

/// The mesh of a body read by [`read_body`], with the warnings of what was read past.
fn finish(read: Read, header: &Header) -> std::result::Result<PlyMesh, PlyError> {
    let Read {
        mut out,
        left,
        blank_rest,
        ..
    } = read;
    let mut warnings = header::warnings(header);
    if out.short_faces > 0 {
        warnings.push(format!(
            "{} faces with fewer than 3 corners skipped",
            out.short_faces
        ));
    }
    warnings.extend(unread_strips(header));
    if left > 0 && !(header.format == Format::Ascii && blank_rest) {
        warnings.push(format!("{left} bytes after the last element ignored"));
    }
    if out.triangles.is_empty() {
        out.positions.clear();
    } else if let Some(vertex) = out.positions.iter().position(|p| !p.is_finite()) {
        return Err(PlyError::NonFinite { vertex });
    }
    Ok(PlyMesh {
        positions: out.positions,
        triangles: out.triangles,
        uv: out.uv,
        normals: out.normals,
        warnings,
    })
}

/// The warning for a `tristrips` element (triangle strips, strips ended by -1), which is
/// not read: its records would be triangles the scene lacks.
fn unread_strips(header: &Header) -> Option<String> {
    let strips = header
        .elements
        .iter()
        .find(|e| e.name == "tristrips" && e.count > 0)?;
    Some(format!(
        "{} 'tristrips' records not read: raycast reads the 'face' element only",
        strips.count
    ))
}

/// What an element is read for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    /// Positions (and texture coordinates, normals) from the properties at these indices.
    Vertex(VertexProperties),
    /// Faces from the list property at this index, into `vertices` vertices.
    Face { list: usize, vertices: u64 },
    /// Read past.
    Skip,
}

/// The properties of the `vertex` element read: its position's, and its texture
/// coordinates' and normal's where it has all of their scalars.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct VertexProperties {
    position: [usize; 3],
    uv: Option<[usize; 2]>,
    normal: Option<[usize; 3]>,
}

/// The names texture coordinates go by in PLY files (trimesh's, Blender's, MeshLab's).
const UV_NAMES: [[&str; 2]; 3] = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"]];

/// Which elements are the vertices and the faces.
struct Roles {
    vertex: Option<(usize, VertexProperties)>,
    face: Option<(usize, usize, u64)>,
}

impl Roles {
    fn of(header: &Header) -> std::result::Result<Roles, PlyError> {
        let error = |element: &Element, why: String| PlyError::Header {
            line: element.line,
            why,
        };
        let find = |name: &str| header.elements.iter().position(|e| e.name == name);
        let face = match find("face") {
            Some(k) if header.elements[k].count > 0 => {
                let e = &header.elements[k];
                let list = ["vertex_indices", "vertex_index"]
                    .iter()
                    .find_map(|n| e.property(n))
                    .ok_or_else(|| {
                        error(e, "element 'face' has no 'vertex_indices' list".into())
                    })?;
                match e.properties[list].kind {
                    Kind::List { item, .. } if item.is_integer() => {}
                    _ => {
                        let name = &e.properties[list].name;
                        return Err(error(e, format!("'{name}' is not a list of integers")));
                    }
                }
                let vertices = find("vertex").map_or(0, |v| header.elements[v].count);
                if vertices > u64::from(u32::MAX) {
                    return Err(error(
                        e,
                        format!("{vertices} vertices are more than 2³² − 1"),
                    ));
                }
                Some((k, list, vertices))
            }
            _ => None,
        };
        let vertex = match find("vertex") {
            Some(k) if face.is_some() => {
                let e = &header.elements[k];
                let axis = |name: &str| match e.property(name) {
                    Some(i) if matches!(e.properties[i].kind, Kind::Scalar(_)) => Ok(i),
                    _ => Err(error(e, format!("element 'vertex' has no scalar '{name}'"))),
                };
                let scalar = |name: &str| axis(name).ok();
                let uv = UV_NAMES
                    .iter()
                    .find_map(|[u, v]| Some([scalar(u)?, scalar(v)?]));
                let normal = (|| Some([scalar("nx")?, scalar("ny")?, scalar("nz")?]))();
                let position = [axis("x")?, axis("y")?, axis("z")?];
                Some((
                    k,
                    VertexProperties {
                        position,
                        uv,
                        normal,
                    },
                ))
            }
            _ => None,
        };
        Ok(Roles { vertex, face })
    }

    fn of_element(&self, k: usize) -> Role {
        match (self.vertex, self.face) {
            (Some((v, properties)), _) if v == k => Role::Vertex(properties),
            (_, Some((f, list, vertices))) if f == k => Role::Face { list, vertices },
            _ => Role::Skip,
        }
    }
}

/// The geometry read so far.
#[derive(Default)]
struct Collected {
    positions: Vec<DVec3>,
    uv: Vec<[f32; 2]>,
    normals: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    short_faces: u64,
}

/// Reads the `element.count` records of `element`, keeping what `role` asks for, and notes
/// the ASCII records that do not end with their lines.
fn read_element(
    element: &Element,
    role: Role,
    body: &mut Body<'_>,
    out: &mut Collected,
    off_line: &mut OffLine,
) -> std::result::Result<(), PlyError> {
    let format = body.format();
    if element.properties.is_empty() {
        return Ok(());
    }
    let needs = element
        .count
        .saturating_mul(element.min_record_bytes(format));
    // An ASCII body's last value may end the file without a separator.
    let left = body.remaining() + u64::from(format == Format::Ascii);
    if needs > left {
        return Err(PlyError::Oversized {
            element: element.name.clone(),
            count: element.count,
            needs,
            left: body.remaining(),
        });
    }
    if let Role::Vertex(_) = role {
        out.positions.reserve(element.count as usize);
    }
    let mut values = Vec::new();
    let mut corners = Vec::new();
    for record in 0..element.count {
        let fault = |fault: Fault| match fault {
            Fault::End | Fault::LineEnd => PlyError::Truncated {
                element: element.name.clone(),
                record,
                count: element.count,
            },
            Fault::NotA(scalar, token) => PlyError::Value {
                element: element.name.clone(),
                record,
                token,
                scalar,
            },
        };
        values.clear();
        body.start_record();
        for (k, property) in element.properties.iter().enumerate() {
            // A value missing at the end of its line (Layout::Lines) is left out: NaN, or
            // an empty list.
            let value = match property.kind {
                Kind::Scalar(s) => body.read(s),
                Kind::List { count, item } => {
                    let keep = matches!(role, Role::Face { list, .. } if list == k);
                    let list = read_list(body, count, item, keep, &mut corners);
                    if keep && list.is_err() {
                        corners.clear();
                    }
                    list.map(|()| f64::NAN)
                }
            };
            match value {
                Ok(v) => values.push(v),
                Err(Fault::LineEnd) => values.push(f64::NAN),
                Err(other) => return Err(fault(other)),
            }
        }
        if body.end_record() != RecordEnd::Clean {
            off_line.note(&element.name, record);
        }
        match role {
            Role::Vertex(properties) => {
                let [x, y, z] = properties.position;
                out.positions
                    .push(DVec3::new(values[x], values[y], values[z]));
                if let Some(uv) = properties.uv {
                    out.uv.push(uv.map(|k| values[k] as f32));
                }
                if let Some(normal) = properties.normal {
                    out.normals.push(normal.map(|k| values[k] as f32));
                }
            }
            Role::Face { vertices, .. } => fan(&corners, record, vertices, out)?,
            Role::Skip => {}
        }
    }
    Ok(())
}

/// Reads one list: its count, then its items, kept in `corners` when `keep`. A count larger
/// than the rest of the body can hold is a truncation, found before the items are read.
fn read_list(
    body: &mut Body<'_>,
    count: Scalar,
    item: Scalar,
    keep: bool,
    corners: &mut Vec<f64>,
) -> std::result::Result<(), Fault> {
    let n = body.read(count)?;
    if n < 0.0 {
        return Err(Fault::NotA(count, format!("{n}")));
    }
    let n = n as u64;
    let least = match body.format() {
        Format::Ascii => 1,
        _ => item.size() as u64,
    };
    if n.saturating_mul(least) > body.remaining() {
        return Err(Fault::End);
    }
    if keep {
        corners.clear();
    }
    for _ in 0..n {
        let v = body.read(item)?;
        if keep {
            corners.push(v);
        }
    }
    Ok(())
}

/// Fans face `face`'s corners into triangles from the first corner (a face of fewer than
/// three corners draws nothing and is counted), each corner checked against `vertices`.
fn fan(
    corners: &[f64],
    face: u64,
    vertices: u64,
    out: &mut Collected,
) -> std::result::Result<(), PlyError> {
    if let Some(&index) = corners.iter().find(|&&i| i < 0.0 || i >= vertices as f64) {
        return Err(PlyError::IndexOutOfRange {
            face,
            // An integer of a PLY integer type: exact.
            index: index as i64,
            vertices,
        });
    }
    if corners.len() < 3 {
        out.short_faces += 1;
        return Ok(());
    }
    // Every index is below `vertices`, which fits memory (checked against the body's size).
    let index = |i: usize| corners[i] as u32;
    for i in 1..corners.len() - 1 {
        out.triangles.push([index(0), index(i), index(i + 1)]);
    }
    Ok(())
}

#[cfg(test)]
mod tests;
