//! Point clouds (`--format ply`): the hits of a render as `position.ply`, one vertex per ray
//! that hit something, in binary little-endian PLY 1.0 as Open3D, trimesh and MeshLab read it:
//! `double x, y, z` (the hit, exactly the `position` buffer), then with the AOVs asked for
//! `double nx, ny, nz` (`normal`), `uint id`, `uint prim`, and always `uint ray` (the pixel's
//! row-major index, or the ray's index in the ray file). Misses are left out.

use crate::error::{Error, Result};
use crate::render::{Aov, Buffers};
use std::io::Write;

/// The name of the point cloud file.
pub const FILE: &str = "position.ply";

/// Writes the hits of `buffers` (which hold `position`) as a PLY point cloud to `out`.
pub fn write(out: &mut impl Write, buffers: &Buffers) -> Result<()> {
    let positions = buffers
        .vectors(Aov::Position)
        .ok_or_else(|| Error::msg("a point cloud needs the position AOV"))?;
    let normals = buffers.vectors(Aov::Normal);
    let ids = buffers.labels(Aov::Id);
    let prims = buffers.labels(Aov::Prim);
    let hits: Vec<usize> = (0..positions.len())
        .filter(|&i| positions[i].iter().all(|v| v.is_finite()))
        .collect();
    let io = |e: std::io::Error| Error::msg(format!("cannot write: {e}"));
    out.write_all(
        header(
            hits.len(),
            normals.is_some(),
            ids.is_some(),
            prims.is_some(),
        )
        .as_bytes(),
    )
    .map_err(io)?;
    let mut record = Vec::with_capacity(64);
    for &i in &hits {
        record.clear();
        let vectors = std::iter::once(&positions[i]).chain(normals.map(|n| &n[i]));
        for v in vectors.flatten() {
            record.extend_from_slice(&v.to_le_bytes());
        }
        for labels in [ids, prims].into_iter().flatten() {
            record.extend_from_slice(&labels[i].to_le_bytes());
        }
        record.extend_from_slice(&(i as u32).to_le_bytes());
        out.write_all(&record).map_err(io)?;
    }
    Ok(())
}

/// The PLY header of `count` points with the properties asked for.
fn header(count: usize, normals: bool, ids: bool, prims: bool) -> String {
    let mut h = String::from("ply\nformat binary_little_endian 1.0\n");
    h += "comment raycast hits: position (scene units), normal, id, prim as asked; ray = pixel or ray index\n";
    h += &format!("element vertex {count}\n");
    h += "property double x\nproperty double y\nproperty double z\n";
    if normals {
        h += "property double nx\nproperty double ny\nproperty double nz\n";
    }
    if ids {
        h += "property uint id\n";
    }
    if prims {
        h += "property uint prim\n";
    }
    h + "property uint ray\nend_header\n"
}
