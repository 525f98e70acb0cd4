//! NumPy `.npz` archives: a zip of `.npy` files, stored uncompressed as `numpy.savez` writes
//! them (the zip container is the `zip` crate's). `--hits` writes its CSR lists as one.

use super::npy::{self, NpyData};
use crate::error::{Error, Result};
use crate::trace::HitLists;
use std::io::{Seek, Write};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

/// The file `--hits` writes.
pub const HITS_FILE: &str = "hits.npz";

/// Writes the named 1-D arrays as `<name>.npy` members of an `.npz` archive.
pub fn write(out: &mut (impl Write + Seek), arrays: &[(&str, NpyData)]) -> Result<()> {
    let failed = |e: zip::result::ZipError| Error::msg(format!("cannot write: {e}"));
    let mut zip = ZipWriter::new(out);
    for (name, data) in arrays {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Stored)
            // Zip64 sizes for a member near 4 GiB (the header adds at most a few hundred bytes).
            .large_file(data.bytes() as u64 >= u64::from(u32::MAX) - 4096);
        zip.start_file(format!("{name}.npy"), options)
            .map_err(failed)?;
        npy::write(&mut zip, &[len(data)], *data)?;
    }
    zip.finish().map_err(failed)?;
    Ok(())
}

/// The number of elements of `data`.
fn len(data: &NpyData) -> usize {
    match data {
        NpyData::F64(v) => v.len(),
        NpyData::U32(v) => v.len(),
        NpyData::U64(v) => v.len(),
        NpyData::U8(v) => v.len(),
    }
}

/// Writes hit lists as `ray_splits` (uint64, N + 1), `t` (float64), `id` and `prim` (uint32),
/// the arrays of the Python package's `list_intersections`.
pub fn write_hits(out: &mut (impl Write + Seek), hits: &HitLists) -> Result<()> {
    write(
        out,
        &[
            ("ray_splits", NpyData::U64(&hits.splits)),
            ("t", NpyData::F64(&hits.t)),
            ("id", NpyData::U32(&hits.id)),
            ("prim", NpyData::U32(&hits.prim)),
        ],
    )
}
