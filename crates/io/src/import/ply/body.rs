//! Reading the values of a PLY body one at a time, in any of its three encodings. ASCII
//! values are whitespace-separated tokens, read as one stream (records need not keep to one
//! line, as rply reads them) or, for files whose lines do not hold the records the header
//! declares, one record per line ([`Layout::Lines`], as trimesh reads them); binary values are
//! packed in the header's types and byte order.

use super::header::{Format, Scalar};

/// How ASCII records are laid out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// One stream of values: a record may span lines, or share one.
    Stream,
    /// One record per line (blank lines skipped): values past the declared properties are
    /// ignored, a line that ends early leaves the rest of its record missing.
    Lines,
}

/// How a record ended on its line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordEnd {
    /// At the end of its line (or of the body), as the header declares it.
    Clean,
    /// Before the end of its line: in [`Layout::Lines`], the rest of the line was skipped.
    Early,
    /// In [`Layout::Lines`], the line ended before the record's last value.
    Short,
}

/// Why a value could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fault {
    /// The body ended.
    End,
    /// In [`Layout::Lines`], the record's line ended.
    LineEnd,
    /// An ASCII token that is not a number of the property's type (the token, shortened).
    NotA(Scalar, String),
}

/// A cursor over the body.
#[derive(Debug)]
pub struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    format: Format,
    layout: Layout,
    /// In [`Layout::Lines`], whether the current record's line has ended.
    line_ended: bool,
}

impl<'a> Body<'a> {
    /// A cursor at the start of the body `bytes`, encoded as `format` says.
    /// Its ASCII records are laid out as `layout` says (binary bodies ignore it).
    pub fn new(bytes: &'a [u8], format: Format, layout: Layout) -> Self {
        Body {
            bytes,
            at: 0,
            format,
            layout,
            line_ended: false,
        }
    }

    /// Whether ASCII records are read one per line.
    fn by_lines(&self) -> bool {
        self.format == Format::Ascii && self.layout == Layout::Lines
    }

    /// Starts a record: in [`Layout::Lines`], at the next line that holds a value.
    pub fn start_record(&mut self) {
        if self.by_lines() {
            self.skip_while(u8::is_ascii_whitespace);
            self.line_ended = false;
        }
    }

    /// Ends a record (ASCII only; binary records are always [`RecordEnd::Clean`]): says
    /// whether it ended with its line and, in [`Layout::Lines`], moves past the line.
    pub fn end_record(&mut self) -> RecordEnd {
        if self.format != Format::Ascii {
            return RecordEnd::Clean;
        }
        if self.line_ended {
            return RecordEnd::Short;
        }
        let rest = &self.bytes[self.at..];
        let blank = rest
            .iter()
            .take_while(|&&b| b != b'\n')
            .all(u8::is_ascii_whitespace);
        if self.by_lines() {
            self.skip_while(|&b| b != b'\n');
        }
        if blank {
            RecordEnd::Clean
        } else {
            RecordEnd::Early
        }
    }

    fn skip_while(&mut self, mut skip: impl FnMut(&u8) -> bool) {
        let rest = &self.bytes[self.at..];
        self.at += rest.iter().position(|b| !skip(b)).unwrap_or(rest.len());
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> u64 {
        (self.bytes.len() - self.at) as u64
    }

    /// The body's encoding.
    pub fn format(&self) -> Format {
        self.format
    }

    /// Whether every byte not read yet is ASCII whitespace.
    pub fn rest_is_blank(&self) -> bool {
        self.bytes[self.at..].iter().all(u8::is_ascii_whitespace)
    }

    /// The next value, of type `scalar`, as an f64 (exact for every PLY type). An ASCII
    /// `float` is rounded to f32 as a binary one is stored.
    pub fn read(&mut self, scalar: Scalar) -> Result<f64, Fault> {
        match self.format {
            Format::Ascii => self.read_text(scalar),
            Format::BinaryLittleEndian => self.read_binary(scalar, false),
            Format::BinaryBigEndian => self.read_binary(scalar, true),
        }
    }

    fn read_text(&mut self, scalar: Scalar) -> Result<f64, Fault> {
        if self.by_lines() {
            self.skip_while(|&b| b != b'\n' && b.is_ascii_whitespace());
            if self.line_ended || self.bytes.get(self.at).is_none_or(|&b| b == b'\n') {
                self.line_ended = true;
                return Err(Fault::LineEnd);
            }
        }
        let rest = &self.bytes[self.at..];
        let start = rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or(Fault::End)?;
        let length = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        let token = &rest[start..start + length];
        self.at += start + length;
        let text = std::str::from_utf8(token).unwrap_or("");
        let value = if scalar.is_integer() {
            text.parse::<i64>().ok().map(|v| v as f64)
        } else {
            text.parse::<f64>().ok()
        };
        match value {
            Some(v) if scalar == Scalar::F32 => Ok(v as f32 as f64),
            Some(v) if !scalar.is_integer() || in_range(scalar, v) => Ok(v),
            _ => Err(Fault::NotA(
                scalar,
                super::super::obj_text::quoted(&String::from_utf8_lossy(token)),
            )),
        }
    }

    fn read_binary(&mut self, scalar: Scalar, big: bool) -> Result<f64, Fault> {
        let size = scalar.size();
        let raw = self.bytes.get(self.at..self.at + size).ok_or(Fault::End)?;
        self.at += size;
        let mut b = [0u8; 8];
        b[..size].copy_from_slice(raw);
        if big {
            b[..size].reverse();
        }
        Ok(match scalar {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

/// Whether the integer `v` fits the integer type `scalar`.
fn in_range(scalar: Scalar, v: f64) -> bool {
    let (lo, hi) = match scalar {
        Scalar::I8 => (i8::MIN as f64, i8::MAX as f64),
        Scalar::U8 => (0.0, u8::MAX as f64),
        Scalar::I16 => (i16::MIN as f64, i16::MAX as f64),
        Scalar::U16 => (0.0, u16::MAX as f64),
        Scalar::I32 => (i32::MIN as f64, i32::MAX as f64),
        _ => (0.0, u32::MAX as f64),
    };
    (lo..=hi).contains(&v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_tokens_span_lines_and_keep_their_types() {
        let mut b = Body::new(b" 3\n0.1  -2\r\n1e40 x", Format::Ascii, Layout::Stream);
        assert_eq!(b.read(Scalar::U8), Ok(3.0));
        assert_eq!(b.read(Scalar::F32), Ok(0.1f32 as f64));
        assert_eq!(b.read(Scalar::I16), Ok(-2.0));
        assert_eq!(b.read(Scalar::F64), Ok(1e40));
        assert_eq!(
            b.read(Scalar::F64),
            Err(Fault::NotA(Scalar::F64, "x".into()))
        );
        assert_eq!(b.read(Scalar::F64), Err(Fault::End));
        let mut b = Body::new(b"256 -1", Format::Ascii, Layout::Stream);
        assert_eq!(
            b.read(Scalar::U8),
            Err(Fault::NotA(Scalar::U8, "256".into()))
        );
        assert!(b.read(Scalar::U32).is_err());
    }

    #[test]
    fn records_by_lines_skip_extra_values_and_stop_at_short_lines() {
        let text = b"1 2 3 4\n\n5 6\n7 8";
        let mut b = Body::new(text, Format::Ascii, Layout::Lines);
        let record = |b: &mut Body| {
            b.start_record();
            let values = [b.read(Scalar::U8), b.read(Scalar::U8), b.read(Scalar::U8)];
            (values, b.end_record())
        };
        assert_eq!(
            record(&mut b),
            ([Ok(1.0), Ok(2.0), Ok(3.0)], RecordEnd::Early)
        );
        let short = [Ok(5.0), Ok(6.0), Err(Fault::LineEnd)];
        assert_eq!(record(&mut b), (short, RecordEnd::Short));
        let short = [Ok(7.0), Ok(8.0), Err(Fault::LineEnd)];
        assert_eq!(record(&mut b), (short, RecordEnd::Short));
        assert_eq!(b.remaining(), 0);
        // A stream reads across lines and says where a record ended.
        let mut b = Body::new(text, Format::Ascii, Layout::Stream);
        assert_eq!(record(&mut b).1, RecordEnd::Early);
        assert_eq!(
            record(&mut b),
            ([Ok(4.0), Ok(5.0), Ok(6.0)], RecordEnd::Clean)
        );
    }

    #[test]
    fn binary_values_in_both_byte_orders() {
        let le = [0xfe, 0x01, 0x00, 0x00, 0x80, 0x3f, 0x07];
        let mut b = Body::new(&le, Format::BinaryLittleEndian, Layout::Stream);
        assert_eq!(b.read(Scalar::I8), Ok(-2.0));
        assert_eq!(b.read(Scalar::U8), Ok(1.0));
        assert_eq!(b.read(Scalar::F32), Ok(1.0));
        assert_eq!(b.remaining(), 1);
        assert_eq!(b.read(Scalar::U16), Err(Fault::End));
        let be = [0x3f, 0xf0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xfe];
        let mut b = Body::new(&be, Format::BinaryBigEndian, Layout::Stream);
        assert_eq!(b.read(Scalar::F64), Ok(1.0));
        assert_eq!(b.read(Scalar::I32), Ok(-2.0));
    }
}
