//! The shading attributes of mesh primitives: `TEXCOORD_0` (floats, or normalized 8/16-bit
//! integers) and `NORMAL` (floats), Draco-compressed ones included, and the primitive's
//! `material`. They never stop a render: an attribute that cannot be read is left out with a
//! warning, and its hits hold the miss value.

use super::decode;
use super::document::{index_of, Document};
use super::mesh::Geometry;
use crate::scene::attributes::{runs, Attributes};
use glam::DVec3;

/// The name of material `index` of a document: its `name`, else `material<index>`.
pub fn material_name(doc: &Document, index: usize) -> String {
    doc.item("materials", index)
        .and_then(|m| m.get("name"))
        .and_then(|n| n.as_str())
        .map_or_else(|| format!("material{index}"), String::from)
}

impl Document {
    /// Reads primitive `prim`'s texture coordinates, normals and material into `geometry`;
    /// returns a warning for each attribute that the file has but that cannot be read.
    pub fn read_shading(&self, mesh: usize, prim: usize, geometry: &mut Geometry) -> Vec<String> {
        let mut warnings = Vec::new();
        let Ok((json, at)) = self.primitive_json(mesh, prim) else {
            return warnings;
        };
        let n = geometry.positions.len();
        geometry.material =
            index_of(json, "material").filter(|&m| m < self.list("materials").len());
        let attributes = json.get("attributes");
        let mut read = |name: &str, comps: usize| -> Option<Vec<f64>> {
            let accessor = attributes.and_then(|a| index_of(a, name))?;
            match self.attribute(mesh, prim, accessor, name, comps, n) {
                Ok(values) => Some(values),
                Err(why) => {
                    warnings.push(format!("{at}/attributes/{name}: {why}: left out"));
                    None
                }
            }
        };
        geometry.uv =
            read("TEXCOORD_0", 2).map(|v| v.chunks_exact(2).map(|c| [c[0], c[1]]).collect());
        geometry.normals = read("NORMAL", 3).map(|v| {
            v.chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2]))
                .collect()
        });
        warnings
    }

    /// The values of attribute `name` (accessor `accessor`, `comps` per vertex) of a
    /// primitive with `n` vertices, decoded from Draco data where the primitive is compressed,
    /// normalized integers dequantized.
    fn attribute(
        &self,
        mesh: usize,
        prim: usize,
        accessor: usize,
        name: &str,
        comps: usize,
        n: usize,
    ) -> Result<Vec<f64>, String> {
        let layout = self.layout(accessor).map_err(|e| e.to_string())?;
        if layout.comps != comps || layout.rows.is_some() {
            return Err(format!("must have {comps} components per vertex"));
        }
        let stored = match decode::draco_attribute(self, mesh, prim, name, comps) {
            Some(values) => values.map_err(|e| e.to_string())?,
            None => self.accessor_values(accessor).map_err(|e| e.to_string())?.1,
        };
        if stored.len() != comps * n {
            return Err(format!("{} values for {n} vertices", stored.len() / comps));
        }
        let values: Vec<f64> = stored.into_iter().map(|v| layout.dequantize(v)).collect();
        match values.iter().all(|v| v.is_finite()) {
            true => Ok(values),
            false => Err("holds a value that is not finite".into()),
        }
    }
}

/// The attributes of a mesh's triangles gathered primitive by primitive: where some primitives
/// have texture coordinates or normals and others not, the others' corners hold the miss
/// values (infinite texture coordinates, zero normals, which the lookups give as misses).
#[derive(Debug, Default)]
pub struct MeshShading {
    uv: Vec<[[f32; 2]; 3]>,
    normals: Vec<[[f32; 3]; 3]>,
    has_uv: bool,
    has_normals: bool,
    materials: Vec<u32>,
}

impl MeshShading {
    /// Adds the triangles `corners` (vertex index triples) of `geometry`.
    pub fn add(&mut self, geometry: &Geometry, corners: &[[u32; 3]]) {
        let uv = geometry.uv.as_deref();
        let normals = geometry.normals.as_deref();
        self.has_uv |= uv.is_some();
        self.has_normals |= normals.is_some();
        for corner in corners {
            self.uv.push(corner.map(|v| match uv {
                Some(uv) => uv[v as usize].map(|x| x as f32),
                None => [f32::INFINITY; 2],
            }));
            self.normals.push(corner.map(|v| match normals {
                Some(n) => n[v as usize].as_vec3().to_array(),
                None => [0.0; 3],
            }));
        }
        let material = geometry.material.map_or(0, |m| m as u32 + 1);
        self.materials
            .extend(std::iter::repeat_n(material, corners.len()));
    }

    /// The gathered attributes (material `m` of the file is the scene's material `m + 1`).
    pub fn finish(self) -> Attributes {
        Attributes {
            uv: if self.has_uv { self.uv } else { Vec::new() },
            normals: if self.has_normals {
                self.normals
            } else {
                Vec::new()
            },
            materials: runs(&self.materials),
        }
    }
}
