//! NumPy `.npy` files (format version 1.0): writing buffers. Reading is
//! [`crate::import::npy`]'s.

use crate::error::{Error, Result};
use std::io::Write;

/// The element data of an array to write.
#[derive(Debug, Clone, Copy)]
pub enum NpyData<'a> {
    /// Little-endian float64 (`<f8`).
    F64(&'a [f64]),
    /// Little-endian uint32 (`<u4`).
    U32(&'a [u32]),
    /// Bytes (`|u1`).
    U8(&'a [u8]),
    /// Little-endian uint64 (`<u8`).
    U64(&'a [u64]),
}

impl NpyData<'_> {
    /// The number of data bytes.
    pub fn bytes(&self) -> usize {
        match self {
            NpyData::F64(v) => 8 * v.len(),
            NpyData::U32(v) => 4 * v.len(),
            NpyData::U64(v) => 8 * v.len(),
            NpyData::U8(v) => v.len(),
        }
    }
}

/// Writes a C-order array of the given shape to `out`.
pub fn write(out: &mut impl Write, shape: &[usize], data: NpyData) -> Result<()> {
    let descr = match data {
        NpyData::F64(_) => "<f8",
        NpyData::U32(_) => "<u4",
        NpyData::U64(_) => "<u8",
        NpyData::U8(_) => "|u1",
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
    let mut write_all = |bytes: &[u8]| {
        out.write_all(bytes)
            .map_err(|e| Error::msg(format!("cannot write: {e}")))
    };
    write_all(b"\x93NUMPY\x01\x00")?;
    write_all(&(header.len() as u16).to_le_bytes())?;
    write_all(header.as_bytes())?;
    match data {
        NpyData::F64(v) => v.iter().try_for_each(|x| write_all(&x.to_le_bytes())),
        NpyData::U32(v) => v.iter().try_for_each(|x| write_all(&x.to_le_bytes())),
        NpyData::U64(v) => v.iter().try_for_each(|x| write_all(&x.to_le_bytes())),
        NpyData::U8(v) => write_all(v),
    }
}
