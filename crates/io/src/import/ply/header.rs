//! The PLY header: the body's encoding and the elements it holds, each with its count and
//! properties, as Greg Turk's PLY description (and rply, the reader most tools use) defines
//! them. The header is ASCII text of `\n` or `\r\n` lines from `ply` to `end_header`; the
//! body starts on the byte after that line.

use super::PlyError;
use crate::error::Error;

/// How the body is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Whitespace-separated decimal numbers.
    Ascii,
    /// Packed binary values, least significant byte first.
    BinaryLittleEndian,
    /// Packed binary values, most significant byte first.
    BinaryBigEndian,
}

/// A scalar type: the PLY names (`char` … `double`) and their sized aliases (`int8` …
/// `float64`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// `char`, `int8`.
    I8,
    /// `uchar`, `uint8`.
    U8,
    /// `short`, `int16`.
    I16,
    /// `ushort`, `uint16`.
    U16,
    /// `int`, `int32`.
    I32,
    /// `uint`, `uint32`.
    U32,
    /// `float`, `float32`.
    F32,
    /// `double`, `float64`.
    F64,
}

impl Scalar {
    /// The type named `name`, if PLY has it.
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Bytes of one value in a binary body.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Whether the type holds integers (list counts and vertex indices must).
    pub fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

/// What one property holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// One value.
    Scalar(Scalar),
    /// A count, then that many items.
    List {
        /// The type of the count.
        count: Scalar,
        /// The type of each item.
        item: Scalar,
    },
}

/// A property of an element.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Property {
    /// Its name (`x`, `vertex_indices`, ...).
    pub name: String,
    /// Its type.
    pub kind: Kind,
}

/// An element: `count` records of the same properties.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Element {
    /// Its name (`vertex`, `face`, ...).
    pub name: String,
    /// How many records the body holds.
    pub count: u64,
    /// The properties of each record, in body order.
    pub properties: Vec<Property>,
    /// The header line (from 1) that declared it.
    pub line: usize,
}

impl Element {
    /// The fewest body bytes one record can take: its scalars and list counts in binary (a
    /// list may be empty), one character and one separator per value in ASCII.
    pub fn min_record_bytes(&self, format: Format) -> u64 {
        let each = |p: &Property| match (format, p.kind) {
            (Format::Ascii, _) => 2,
            (_, Kind::Scalar(s)) | (_, Kind::List { count: s, .. }) => s.size() as u64,
        };
        self.properties.iter().map(each).sum()
    }

    /// The index of the property named `name`.
    pub fn property(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name)
    }
}

/// A parsed header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// The body's encoding.
    pub format: Format,
    /// The elements, in body order.
    pub elements: Vec<Element>,
    /// The offset of the body's first byte.
    pub body_start: usize,
    /// Lines that are no PLY header line (free text, as some exporters write), skipped as
    /// trimesh skips them: each line's number and text.
    pub unknown_lines: Vec<(usize, String)>,
}

impl Header {
    /// The element named `name`, if declared.
    pub fn element(&self, name: &str) -> Option<&Element> {
        self.elements.iter().find(|e| e.name == name)
    }
}

/// Whether `bytes` start as a PLY file does (`ply` alone on the first line).
pub fn is_ply(bytes: &[u8]) -> bool {
    bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")
}

/// Reads the header at the start of `bytes`.
pub fn parse(bytes: &[u8]) -> Result<Header, PlyError> {
    let error = |line: usize, why: String| PlyError::Header { line, why };
    if !is_ply(bytes) {
        return Err(error(1, "the file does not start with a 'ply' line".into()));
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut unknown_lines = Vec::new();
    let mut offset = 0;
    for number in 1.. {
        let Some(length) = bytes[offset..].iter().position(|&b| b == b'\n') else {
            return Err(error(number, "the header has no 'end_header' line".into()));
        };
        let raw = &bytes[offset..offset + length];
        offset += length + 1;
        let text = std::str::from_utf8(raw)
            .map_err(|_| error(number, "the header line is not text".into()))?;
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] if number == 1 => {}
            ["end_header"] => break,
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["format", encoding, version] if format.is_none() => {
                format = Some(
                    parse_format(encoding, version).map_err(|w| error(number, w.to_string()))?,
                );
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| {
                    error(
                        number,
                        format!("element '{name}' has a bad count '{count}'"),
                    )
                })?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: number,
                });
            }
            ["property", ..] => {
                let property =
                    parse_property(&words[1..]).map_err(|w| error(number, w.to_string()))?;
                let element = elements
                    .last_mut()
                    .ok_or_else(|| error(number, "a property before any element".to_string()))?;
                element.properties.push(property);
            }
            ["ply" | "format" | "end_header", ..] => {
                return Err(error(number, format!("a bad '{}' line", words[0])));
            }
            _ => unknown_lines.push((number, super::super::obj_text::quoted(text.trim()))),
        }
    }
    let format = format.ok_or_else(|| error(2, "the header has no 'format' line".into()))?;
    Ok(Header {
        format,
        elements,
        body_start: offset,
        unknown_lines,
    })
}

/// The one warning for the header's unknown lines, naming the first.
pub fn warnings(header: &Header) -> Vec<String> {
    let Some((line, text)) = header.unknown_lines.first() else {
        return Vec::new();
    };
    let more = match header.unknown_lines.len() - 1 {
        0 => String::new(),
        1 => " (and 1 more line)".to_string(),
        n => format!(" (and {n} more lines)"),
    };
    vec![format!(
        "PLY header line {line}: '{text}' is not a PLY header line: skipped, as trimesh skips \
         it{more}"
    )]
}

fn parse_format(encoding: &str, version: &str) -> Result<Format, Error> {
    if version != "1.0" {
        return Err(Error::msg(format!("format version '{version}' is not 1.0")));
    }
    match encoding {
        "ascii" => Ok(Format::Ascii),
        "binary_little_endian" => Ok(Format::BinaryLittleEndian),
        "binary_big_endian" => Ok(Format::BinaryBigEndian),
        _ => Err(Error::msg(format!("unknown format '{encoding}'"))),
    }
}

/// A `property` line's words after `property`: `TYPE NAME` or `list COUNT ITEM NAME`.
fn parse_property(words: &[&str]) -> Result<Property, Error> {
    let scalar = |name: &str| {
        Scalar::parse(name).ok_or_else(|| Error::msg(format!("unknown property type '{name}'")))
    };
    let (kind, name) = match words {
        ["list", count, item, name] => {
            let count = scalar(count)?;
            if !count.is_integer() {
                return Err(Error::msg(format!(
                    "the count of list '{name}' is not an integer type"
                )));
            }
            let item = scalar(item)?;
            (Kind::List { count, item }, name)
        }
        [ty, name] => (Kind::Scalar(scalar(ty)?), name),
        _ => return Err(Error::msg("a property line needs a type and a name")),
    };
    Ok(Property {
        name: name.to_string(),
        kind,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_header_with_crlf_lines_comments_and_lists() {
        let text = b"ply\r\nformat binary_big_endian 1.0\r\ncomment made by hand\r\n\
                     element vertex 3\r\nproperty double x\r\nproperty float32 y\r\n\
                     property float z\r\nelement face 1\r\nproperty list uint8 int vertex_index\r\n\
                     end_header\r\nBODY";
        let h = parse(text).unwrap();
        assert_eq!(h.format, Format::BinaryBigEndian);
        assert_eq!(&text[h.body_start..], b"BODY");
        let face = h.element("face").unwrap();
        assert_eq!(face.line, 8);
        assert_eq!(
            face.properties[0].kind,
            Kind::List {
                count: Scalar::U8,
                item: Scalar::I32
            }
        );
        assert_eq!(h.element("vertex").unwrap().min_record_bytes(h.format), 16);
    }

    #[test]
    fn unknown_header_lines_are_skipped_with_one_warning() {
        let text = b"ply\nformat ascii 1.0\nCreated by hand\nelement vertex 0\nmade 2024\n\
                     end_header\n";
        let h = parse(text).unwrap();
        assert_eq!(h.elements.len(), 1);
        assert_eq!(
            warnings(&h),
            [
                "PLY header line 3: 'Created by hand' is not a PLY header line: skipped, as \
              trimesh skips it (and 1 more line)"
            ]
        );
    }

    #[test]
    fn bad_headers_name_their_line() {
        let cases: [(&[u8], &str); 7] = [
            (
                b"ply\nformat ascii 1.0\nformat ascii 1.0\nend_header\n",
                "line 3: a bad 'format' line",
            ),
            (
                b"plyx\n",
                "line 1: the file does not start with a 'ply' line",
            ),
            (
                b"ply\nformat ascii 1.0\n",
                "line 3: the header has no 'end_header' line",
            ),
            (
                b"ply\nformat ascii 2.0\nend_header\n",
                "line 2: format version '2.0' is not 1.0",
            ),
            (
                b"ply\nformat ascii 1.0\nelement v 1\nproperty half x\nend_header\n",
                "line 4: unknown property type 'half'",
            ),
            (
                b"ply\nformat ascii 1.0\nelement v -1\nend_header\n",
                "line 3: element 'v' has a bad count '-1'",
            ),
            (
                b"ply\nend_header\n",
                "line 2: the header has no 'format' line",
            ),
        ];
        for (text, want) in cases {
            assert_eq!(
                parse(text).unwrap_err().to_string(),
                format!("PLY header {want}")
            );
        }
    }
}
