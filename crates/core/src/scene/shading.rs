//! Looking up a hit's shading attributes after the trace: texture coordinates, the shading
//! normal and the material, from the hit's part, triangle and barycentric weights (see
//! [`super::attributes`]). Nothing here runs while the nearest hit is searched.

use super::attributes::Attributes;
use super::{Crossing, Object, PartKind, Scene, Top};
use crate::geometry::triangle::WatertightRay;
use glam::{DMat3, DVec3};
use std::sync::Arc;

/// What the lookups of one part need.
#[derive(Debug, Clone)]
pub(super) struct PartShading {
    /// The attributes of the part's mesh (`None`: a quadric, or a mesh without any).
    pub attributes: Option<Arc<Attributes>>,
    /// The inverse transpose of the placement's linear part: mesh-frame normals to the world
    /// (so a mirroring placement keeps them on the side the `normal` AOV's rule gives).
    pub normal_matrix: DMat3,
    /// A world part whose triangles were stored with corners 1 and 2 swapped (a mirroring
    /// placement), so that its barycentric weights are swapped back for the lookup.
    pub swapped: bool,
    /// A quadric part's material (1-based; 0: none).
    pub material: u32,
}

impl PartShading {
    /// The lookups of a mesh part with `attributes`, placed by a map whose linear part is
    /// `linear`.
    pub fn mesh(attributes: Option<Arc<Attributes>>, linear: DMat3, swapped: bool) -> Self {
        PartShading {
            attributes,
            normal_matrix: linear.inverse().transpose(),
            swapped,
            material: 0,
        }
    }

    /// The lookups of a quadric part bound to `material`.
    pub fn quadric(material: u32) -> Self {
        PartShading {
            attributes: None,
            normal_matrix: DMat3::IDENTITY,
            swapped: false,
            material,
        }
    }
}

/// The shading attributes a scene can lack, for [`Scene::missing_attribute`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attribute {
    /// Texture coordinates (`uv`).
    Uv,
    /// Shading normals (`shading_normal`; quadrics have their analytic normal).
    Normal,
    /// A material (`material`).
    Material,
}

/// A hit's part and, on a mesh, its triangle in the mesh and the barycentric weights of that
/// triangle's corners in the mesh's order.
struct Surface<'a> {
    shading: &'a PartShading,
    triangle: Option<(usize, [f64; 3])>,
}

impl Scene {
    /// The materials the scene's parts are bound to, named as the file names them; the
    /// `material` AOV's value `m` is `materials[m - 1]` (0: no material).
    pub fn materials(&self) -> &[String] {
        &self.materials
    }

    fn surface(&self, crossing: &Crossing, origin: DVec3, dir: DVec3) -> Option<Surface<'_>> {
        let (part, triangle) = match self.top(crossing.top as usize) {
            Top::Triangle(i) => {
                let part = self.world_parts[i];
                let PartKind::World { first, .. } = self.parts[part as usize].kind else {
                    unreachable!("world triangles belong to world parts")
                };
                let ray = WatertightRay::new(origin, dir);
                let weights = ray.barycentric(&self.world.mesh.triangle(i))?;
                let [w0, w1, w2] = weights;
                let weights = match self.shading[part as usize].swapped {
                    true => [w0, w2, w1],
                    false => weights,
                };
                (part, Some((i - first as usize, weights)))
            }
            Top::Instance(k) => {
                let inner = self.instance_triangle(k, crossing, origin, dir)?;
                let found = Crossing {
                    inner: Some(inner),
                    ..*crossing
                };
                let weights = self.barycentric(&found, origin, dir)?;
                (self.instances[k].part, Some((inner as usize, weights)))
            }
            Top::Quadric(q) => (self.quadric_parts[q], None),
        };
        Some(Surface {
            shading: &self.shading[part as usize],
            triangle,
        })
    }

    /// The texture coordinates at a crossing of the ray `origin + t · dir`, interpolated
    /// from the file's values at the triangle's corners; `None` on a quadric or a mesh
    /// without them.
    pub fn uv(&self, crossing: &Crossing, origin: DVec3, dir: DVec3) -> Option<[f64; 2]> {
        let surface = self.surface(crossing, origin, dir)?;
        let (triangle, weights) = surface.triangle?;
        surface
            .shading
            .attributes
            .as_ref()?
            .uv_at(triangle, weights)
    }

    /// The unit world shading normal at a crossing: the file's normals interpolated and
    /// mapped by the inverse transpose of the placement; a quadric's analytic normal. `None`
    /// on a mesh without normals, or where they interpolate to zero.
    pub fn shading_normal(&self, crossing: &Crossing, origin: DVec3, dir: DVec3) -> Option<DVec3> {
        let surface = self.surface(crossing, origin, dir)?;
        let Some((triangle, weights)) = surface.triangle else {
            return Some(self.locate_crossing(crossing, origin, dir).normal);
        };
        let local = surface
            .shading
            .attributes
            .as_ref()?
            .normal_at(triangle, weights)?;
        (surface.shading.normal_matrix * local).try_normalize()
    }

    /// The material at a crossing (1-based index into [`Scene::materials`]; 0: none).
    pub fn material(&self, crossing: &Crossing, origin: DVec3, dir: DVec3) -> u32 {
        let Some(surface) = self.surface(crossing, origin, dir) else {
            return 0;
        };
        match (surface.triangle, &surface.shading.attributes) {
            (Some((triangle, _)), Some(attributes)) => attributes.material(triangle),
            (Some(_), None) => 0,
            (None, _) => surface.shading.material,
        }
    }

    /// One line saying which objects lack `attribute` (so that their hits hold the miss
    /// value), or `None` when every object has it.
    pub fn missing_attribute(&self, attribute: Attribute) -> Option<String> {
        let lacking: Vec<&Object> = self
            .objects
            .iter()
            .filter(|object| !self.has_attribute(object, attribute))
            .collect();
        let first = lacking.first()?;
        let what = match attribute {
            Attribute::Uv => "texture coordinates: their uv is (inf, inf)",
            Attribute::Normal => "shading normals: their shading_normal is (0, 0, 0)",
            Attribute::Material => "material: their material is 0",
        };
        let more = match lacking.len() {
            1 => String::new(),
            n => format!(" and {} more", n - 1),
        };
        Some(format!(
            "{} of {} objects ('{}'{more}) have no {what}",
            lacking.len(),
            self.objects.len(),
            first.name
        ))
    }

    /// Whether every part of `object` has `attribute`.
    fn has_attribute(&self, object: &Object, attribute: Attribute) -> bool {
        let parts = object.parts.start as usize..object.parts.end as usize;
        parts.into_iter().all(|p| {
            let shading = &self.shading[p];
            let quadric = matches!(self.parts[p].kind, PartKind::Quadric(_));
            let attributes = shading.attributes.as_deref();
            match attribute {
                Attribute::Uv => attributes.is_some_and(|a| !a.uv.is_empty()),
                Attribute::Normal => quadric || attributes.is_some_and(|a| !a.normals.is_empty()),
                Attribute::Material if quadric => shading.material != 0,
                Attribute::Material => attributes.is_some_and(|a| {
                    !a.materials.is_empty() && a.materials.iter().all(|r| r.material != 0)
                }),
            }
        })
    }
}
