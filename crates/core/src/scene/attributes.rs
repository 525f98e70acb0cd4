//! Shading attributes of a mesh's triangles, as the file gives them: texture coordinates,
//! shading normals and materials, looked up only after a trace, from the hit's triangle and
//! barycentric weights (the tracer never reads them).
//!
//! Texture coordinates and normals are stored per triangle corner (the three values of each
//! triangle, in the mesh's corner order), so per-vertex (glTF, PLY), per-corner (OBJ's `vt`/`vn`
//! indices, USD `faceVarying`) and per-face (USD `uniform`) data are kept alike; they are f32,
//! as glTF, USD and PLY store them (OBJ text is rounded to the nearest f32). That costs 24 bytes
//! per triangle for texture coordinates and 36 for normals, only for meshes whose file has them.
//! Materials are runs of triangles sharing one material of the scene's list.

use glam::DVec3;

/// One run of triangles bound to one material: triangles from `first` up to the next run's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MaterialRun {
    /// The run's first triangle.
    pub first: u32,
    /// 1-based index into [`crate::scene::Scene::materials`]; 0: no material.
    pub material: u32,
}

/// Texture coordinates, shading normals and materials of a mesh's triangles (see the module
/// docs). Each list is empty when the file has none; a non-empty corner list has one entry per
/// triangle.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Attributes {
    /// Texture coordinates of each triangle's corners, as stored (no flip of any axis).
    pub uv: Vec<[[f32; 2]; 3]>,
    /// Shading normals of each triangle's corners, in the mesh's frame, as stored (not
    /// normalised).
    pub normals: Vec<[[f32; 3]; 3]>,
    /// Material runs, by increasing `first`; empty: no material.
    pub materials: Vec<MaterialRun>,
}

impl Attributes {
    /// True when there is nothing to look up.
    pub fn is_empty(&self) -> bool {
        self.uv.is_empty() && self.normals.is_empty() && self.materials.is_empty()
    }

    /// Bytes of attribute data.
    pub fn bytes(&self) -> usize {
        self.uv.len() * 24 + self.normals.len() * 36 + self.materials.len() * 8
    }

    /// Triangle `i`'s material (1-based; 0: none).
    pub fn material(&self, i: usize) -> u32 {
        let after = self
            .materials
            .partition_point(|run| run.first as usize <= i);
        after
            .checked_sub(1)
            .map_or(0, |run| self.materials[run].material)
    }

    /// Triangle `i`'s texture coordinates at barycentric `weights` of its corners.
    pub fn uv_at(&self, i: usize, weights: [f64; 3]) -> Option<[f64; 2]> {
        let corners = self.uv.get(i)?;
        let mut uv = [0.0; 2];
        for (corner, w) in corners.iter().zip(weights) {
            uv[0] += w * f64::from(corner[0]);
            uv[1] += w * f64::from(corner[1]);
        }
        Some(uv)
    }

    /// Triangle `i`'s shading normal at barycentric `weights` of its corners, in the mesh's
    /// frame (not normalised).
    pub fn normal_at(&self, i: usize, weights: [f64; 3]) -> Option<DVec3> {
        let corners = self.normals.get(i)?;
        Some(
            corners
                .iter()
                .zip(weights)
                .map(|(n, w)| w * DVec3::from_array(n.map(f64::from)))
                .sum(),
        )
    }
}

/// The material runs of a per-triangle list of materials (1-based, 0: none); empty when no
/// triangle has one.
pub fn runs(per_triangle: &[u32]) -> Vec<MaterialRun> {
    if per_triangle.iter().all(|&m| m == 0) {
        return Vec::new();
    }
    let mut runs: Vec<MaterialRun> = Vec::new();
    for (i, &material) in per_triangle.iter().enumerate() {
        if runs.last().is_none_or(|run| run.material != material) {
            runs.push(MaterialRun {
                first: i as u32,
                material,
            });
        }
    }
    runs
}

/// Per-corner values of `triangles` (index triples into `values`); empty when `values` does
/// not cover every index (an attribute that does not fit its mesh is left out).
pub fn corners<T: Copy>(values: &[T], triangles: &[[u32; 3]]) -> Vec<[T; 3]> {
    if triangles
        .iter()
        .flatten()
        .any(|&i| i as usize >= values.len())
    {
        return Vec::new();
    }
    triangles
        .iter()
        .map(|t| t.map(|i| values[i as usize]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_and_lookup_agree_with_the_per_triangle_list() {
        let list = [0, 2, 2, 1, 1, 1, 0, 3];
        let attributes = Attributes {
            materials: runs(&list),
            ..Attributes::default()
        };
        assert_eq!(attributes.materials.len(), 5);
        for (i, &m) in list.iter().enumerate() {
            assert_eq!(attributes.material(i), m, "triangle {i}");
        }
        assert!(runs(&[0, 0]).is_empty());
    }

    #[test]
    fn interpolation_weights_the_corners() {
        let attributes = Attributes {
            uv: vec![[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]],
            normals: vec![[[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]],
            materials: Vec::new(),
        };
        assert_eq!(attributes.uv_at(0, [0.5, 0.25, 0.25]), Some([0.25, 0.25]));
        assert_eq!(
            attributes.normal_at(0, [0.5, 0.25, 0.25]),
            Some(DVec3::new(0.25, 0.0, 0.75))
        );
        assert_eq!(attributes.uv_at(1, [1.0, 0.0, 0.0]), None);
        assert_eq!(corners(&[1, 2], &[[0, 1, 2]]), Vec::<[i32; 3]>::new());
    }
}
