//! The shading attributes of mesh primitives: `TEXCOORD_0` (floats, or normalized 8/16-bit
//! integers) and `NORMAL` (floats), Draco-compressed ones included, and the primitive's
//! `material`. They never stop a render: an attribute that cannot be read is left out with a
//! warning, and its hits hold the miss value.

use super::decode;
use super::diagnostics::{Code, Diagnostic};
use super::document::{index_of, Document};
use super::geometry::Geometry;
use crate::error::{Error, Result};
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
    pub fn read_shading(
        &self,
        mesh: usize,
        prim: usize,
        geometry: &mut Geometry,
    ) -> Vec<Diagnostic> {
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
                    warnings.push(Diagnostic::warning(
                        Code::ImporterNote,
                        format!("{at}/attributes/{name}"),
                        format!("{why}: left out"),
                    ));
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
    ) -> Result<Vec<f64>> {
        let layout = self
            .layout(accessor)
            .map_err(|e| Error::msg(e.to_string()))?;
        if layout.comps != comps || layout.rows.is_some() {
            return Err(Error::msg(format!(
                "must have {comps} components per vertex"
            )));
        }
        let stored = match decode::draco_attribute(self, mesh, prim, name, comps) {
            Some(values) => values.map_err(|e| Error::msg(e.to_string()))?,
            None => {
                self.accessor_values(accessor)
                    .map_err(|e| Error::msg(e.to_string()))?
                    .1
            }
        };
        if stored.len() != comps * n {
            return Err(Error::msg(format!(
                "{} values for {n} vertices",
                stored.len() / comps
            )));
        }
        let values: Vec<f64> = stored.into_iter().map(|v| layout.dequantize(v)).collect();
        match values.iter().all(|v| v.is_finite()) {
            true => Ok(values),
            false => Err(Error::msg("holds a value that is not finite")),
        }
    }
}

/// The attributes of a mesh's triangles gathered primitive by primitive: where some primitives
/// have texture coordinates or normals and others not, the others' corners hold the miss
/// values (infinite texture coordinates, zero normals, which the lookups give as misses). A
/// list is only made once a primitive has that attribute.
#[derive(Debug, Default)]
pub struct MeshShading {
    uv: Option<Vec<[[f32; 2]; 3]>>,
    normals: Option<Vec<[[f32; 3]; 3]>>,
    materials: Vec<u32>,
}

/// Appends one corner value per triangle of `corners` to `list`: `value(vertex)` where the
/// primitive has the attribute (`list` started, filled with `miss` for the triangles before,
/// if it was not), `miss` where only other primitives have it.
fn extend<T: Copy>(
    list: &mut Option<Vec<[T; 3]>>,
    before: usize,
    corners: &[[u32; 3]],
    value: Option<impl Fn(u32) -> T>,
    miss: T,
) {
    match (list.as_mut(), value) {
        (None, None) => {}
        (Some(list), None) => list.extend(std::iter::repeat_n([miss; 3], corners.len())),
        (list_now, Some(value)) => {
            let list = match list_now {
                Some(list) => list,
                None => list.insert(vec![[miss; 3]; before]),
            };
            list.extend(corners.iter().map(|c| c.map(&value)));
        }
    }
}

impl MeshShading {
    /// Adds the triangles `corners` (vertex index triples) of `geometry`.
    pub fn add(&mut self, geometry: &Geometry, corners: &[[u32; 3]]) {
        let before = self.materials.len();
        let uv = (geometry.uv.as_deref()).map(|uv| |v: u32| uv[v as usize].map(|x| x as f32));
        extend(&mut self.uv, before, corners, uv, [f32::INFINITY; 2]);
        let normals =
            (geometry.normals.as_deref()).map(|n| |v: u32| n[v as usize].as_vec3().to_array());
        extend(&mut self.normals, before, corners, normals, [0.0; 3]);
        let material = geometry.material.map_or(0, |m| m as u32 + 1);
        self.materials
            .extend(std::iter::repeat_n(material, corners.len()));
    }

    /// The gathered attributes (material `m` of the file is the scene's material `m + 1`).
    pub fn finish(self) -> Attributes {
        Attributes {
            uv: self.uv.unwrap_or_default(),
            normals: self.normals.unwrap_or_default(),
            materials: runs(&self.materials),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A primitive without texture coordinates before or after one with them: its triangles
    /// hold the miss value, the others their own.
    #[test]
    fn primitives_without_an_attribute_hold_the_miss_value() {
        let corners = [[0, 1, 2]];
        for with_first in [true, false] {
            let mut list = None;
            let value = |v: u32| v as f32;
            for (k, has) in [with_first, !with_first].into_iter().enumerate() {
                extend(&mut list, k, &corners, has.then_some(value), f32::INFINITY);
            }
            let (own, miss) = ([0.0, 1.0, 2.0], [f32::INFINITY; 3]);
            let expected = if with_first { [own, miss] } else { [miss, own] };
            assert_eq!(list, Some(expected.to_vec()));
        }
        let mut none: Option<Vec<[f32; 3]>> = None;
        extend(&mut none, 0, &corners, None::<fn(u32) -> f32>, 0.0);
        assert_eq!(none, None);
    }
}
