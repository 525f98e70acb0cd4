//! The scene model: world-space triangles and quadrics, the object table and the cameras.
//!
//! Triangles are stored as f32 relative to a scene anchor kept in f64: the centre of the scene's
//! bounds when the scene lies far from the world origin (more than 64 times its size away), so
//! it keeps its digits, and the origin otherwise, so that vertices read from f32 file data are
//! stored exactly. Every test promotes them back to f64.

use crate::accel::{octants_by_overlap, PreparedRay, PrimitiveSet};
use crate::camera::Camera;
use crate::geometry::triangle::{self, WatertightRay};
use crate::geometry::Aabb;
use crate::quadric::Quadric;
use glam::{DVec3, Vec3};
use serde::Serialize;
use std::path::PathBuf;

/// What an object is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectKind {
    /// A triangle mesh.
    Mesh,
    /// One analytic quadric surface.
    Quadric,
}

/// One entry of the object table: a glTF node instance, an OBJ object or group, a quadric.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Object {
    /// Stable 1-based id, written to the `id` buffer (0 means no hit).
    pub id: u32,
    /// Node, object or prim name.
    pub name: String,
    /// Mesh or quadric.
    pub kind: ObjectKind,
    /// Where it came from: a JSON pointer such as `/nodes/3`, or `obj:<name>`.
    pub source: String,
    /// Number of triangles (0 for a quadric).
    pub triangles: u32,
    /// Index of its first primitive in the scene's triangle or quadric list.
    #[serde(skip)]
    pub first: u32,
}

/// USD stage metadata, after USD's fallbacks (`upAxis` Y, `metersPerUnit` 0.01).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct StageInfo {
    /// The stage's up axis, `Y` or `Z`.
    pub up_axis: String,
    /// Metres per scene unit.
    pub meters_per_unit: f64,
}

/// A loaded scene, ready for an acceleration structure.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it was loaded from.
    pub path: PathBuf,
    /// World position that stored triangle coordinates are relative to.
    pub anchor: DVec3,
    triangles: Vec<[Vec3; 3]>,
    triangle_objects: Vec<u32>,
    quadrics: Vec<Quadric>,
    quadric_objects: Vec<u32>,
    /// The object table, in id order.
    pub objects: Vec<Object>,
    /// Cameras defined by the file.
    pub cameras: Vec<Camera>,
    /// Things the importer skipped or repaired, one line each.
    pub warnings: Vec<String>,
    /// Extensions the file declares (glTF `extensionsUsed`).
    pub extensions_used: Vec<String>,
    /// What the importer decoded, one line per extension (Draco, meshopt, GPU instancing).
    pub decoded: Vec<String>,
    /// USD stage metadata (USD files only).
    pub stage: Option<StageInfo>,
}

/// Per-ray data of the scene's primitives.
#[derive(Debug, Clone, Copy)]
pub struct SceneRay {
    triangle: WatertightRay,
    world_origin: DVec3,
}

impl Scene {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The quadrics, in primitive order.
    pub fn quadrics(&self) -> &[Quadric] {
        &self.quadrics
    }

    /// World-space bounds of everything in the scene (empty box for an empty scene).
    pub fn world_bounds(&self) -> Aabb {
        let local = (0..self.len())
            .map(|i| PrimitiveSet::bounds(self, i))
            .fold(Aabb::EMPTY, Aabb::union);
        if local.is_empty() {
            local
        } else {
            local.translated(-self.anchor)
        }
    }

    /// A mesh object's triangles, stored relative to [`Scene::anchor`] in f32 (empty for a
    /// quadric). Used by `raycast check` for topology and hole tests.
    pub fn mesh_triangles(&self, object: &Object) -> &[[Vec3; 3]] {
        match object.kind {
            ObjectKind::Mesh => {
                let start = (object.first as usize).min(self.triangles.len());
                let end = (start + object.triangles as usize).min(self.triangles.len());
                &self.triangles[start..end]
            }
            ObjectKind::Quadric => &[],
        }
    }

    /// World-space bounds of one object.
    pub fn object_bounds(&self, object: &Object) -> Aabb {
        let offset = match object.kind {
            ObjectKind::Mesh => 0,
            ObjectKind::Quadric => self.triangles.len(),
        };
        let count = match object.kind {
            ObjectKind::Mesh => object.triangles as usize,
            ObjectKind::Quadric => 1,
        };
        let start = offset + object.first as usize;
        (start..start + count)
            .map(|i| PrimitiveSet::bounds(self, i))
            .fold(Aabb::EMPTY, Aabb::union)
            .translated(-self.anchor)
    }

    /// The object a primitive belongs to, and the primitive's index inside that object
    /// (triangle order for meshes, 0 for quadrics).
    pub fn object_of(&self, prim: u32) -> (&Object, u32) {
        let prim = prim as usize;
        let (object, first) = match prim.checked_sub(self.triangles.len()) {
            None => (self.triangle_objects[prim], prim),
            Some(q) => (self.quadric_objects[q], q),
        };
        let object = &self.objects[object as usize];
        (object, (first - object.first as usize) as u32)
    }

    /// Unit world normal of primitive `prim` at the hit `ray.at(t)`: the triangle's winding
    /// normal, or the quadric's gradient direction. Finite for every hit.
    pub fn normal(&self, prim: u32, origin: DVec3, dir: DVec3, t: f64) -> DVec3 {
        let prim = prim as usize;
        match prim.checked_sub(self.triangles.len()) {
            None => triangle::geometric_normal(&self.triangles[prim])
                .unwrap_or_else(|| -dir.normalize_or_zero()),
            Some(q) => self.quadrics[q].normal(origin, dir, t),
        }
    }
}

impl PrimitiveSet for Scene {
    type RayData = SceneRay;

    fn len(&self) -> usize {
        self.triangles.len() + self.quadrics.len()
    }

    fn bounds(&self, index: usize) -> Aabb {
        match index.checked_sub(self.triangles.len()) {
            None => Aabb::from_points(self.triangles[index].map(|v| v.as_dvec3())),
            Some(q) => {
                let [min, max] = self.quadrics[q].bounds();
                Aabb::new(min, max).translated(self.anchor)
            }
        }
    }

    fn overlaps(&self, index: usize, cell: &Aabb) -> bool {
        match index.checked_sub(self.triangles.len()) {
            None => triangle::overlaps_box(&self.triangles[index], cell),
            Some(q) => {
                let world = cell.translated(-self.anchor);
                self.quadrics[q].may_overlap_box(world.min, world.max)
            }
        }
    }

    fn child_mask(&self, index: usize, cell: &Aabb, margin: f64) -> u8 {
        match index.checked_sub(self.triangles.len()) {
            None => triangle::octant_mask(&self.triangles[index], cell, margin),
            Some(_) => octants_by_overlap(self, index, cell, margin),
        }
    }

    fn clipped_bounds(&self, index: usize, cell: &Aabb) -> Option<Aabb> {
        let clipped = self
            .triangles
            .get(index)
            .and_then(|tri| triangle::clipped_bounds(tri, cell));
        // Clipping a triangle that only touches the cell can round away to nothing.
        clipped.or_else(|| self.bounds(index).common(*cell))
    }

    fn prepare(&self, local_origin: DVec3, dir: DVec3) -> SceneRay {
        SceneRay {
            triangle: WatertightRay::new(local_origin, dir),
            world_origin: local_origin + self.anchor,
        }
    }

    fn intersect(&self, index: usize, ray: &PreparedRay<SceneRay>, t_max: f64) -> Option<f64> {
        match index.checked_sub(self.triangles.len()) {
            None => ray.extra.triangle.intersect(&self.triangles[index], t_max),
            Some(q) => self.quadrics[q].intersect(ray.extra.world_origin, ray.dir, t_max),
        }
    }
}

/// True when a scene lies close enough to the origin, relative to its size, that its
/// coordinates keep their digits in f32 without an anchor.
fn near_origin(bounds: &Aabb) -> bool {
    bounds.center().abs().max_element() <= 64.0 * bounds.size().max_element()
}

/// Collects objects in world space (f64) and turns them into a [`Scene`].
#[derive(Debug, Default)]
pub struct SceneBuilder {
    triangles: Vec<[DVec3; 3]>,
    triangle_objects: Vec<u32>,
    quadrics: Vec<Quadric>,
    quadric_objects: Vec<u32>,
    objects: Vec<Object>,
    cameras: Vec<Camera>,
    warnings: Vec<String>,
    extensions_used: Vec<String>,
    decoded: Vec<String>,
    stage: Option<StageInfo>,
}

impl SceneBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        SceneBuilder::default()
    }

    /// Adds a mesh object made of world-space triangles; returns its id.
    pub fn add_mesh(&mut self, name: String, source: String, triangles: Vec<[DVec3; 3]>) -> u32 {
        let id = self.push_object(name, ObjectKind::Mesh, source, &triangles);
        self.triangle_objects
            .extend(std::iter::repeat_n(id - 1, triangles.len()));
        self.triangles.extend(triangles);
        id
    }

    /// Adds a quadric object; returns its id.
    pub fn add_quadric(&mut self, name: String, source: String, quadric: Quadric) -> u32 {
        let id = self.push_object(name, ObjectKind::Quadric, source, &[]);
        self.quadric_objects.push(id - 1);
        self.quadrics.push(quadric);
        id
    }

    fn push_object(
        &mut self,
        name: String,
        kind: ObjectKind,
        source: String,
        triangles: &[[DVec3; 3]],
    ) -> u32 {
        let id = self.objects.len() as u32 + 1;
        let first = match kind {
            ObjectKind::Mesh => self.triangles.len(),
            ObjectKind::Quadric => self.quadrics.len(),
        };
        self.objects.push(Object {
            id,
            name,
            kind,
            source,
            triangles: triangles.len() as u32,
            first: first as u32,
        });
        id
    }

    /// Adds a camera.
    pub fn add_camera(&mut self, camera: Camera) {
        self.cameras.push(camera);
    }

    /// Records a warning.
    pub fn warn(&mut self, warning: impl Into<String>) {
        self.warnings.push(warning.into());
    }

    /// Records the extensions the file declares.
    pub fn set_extensions_used(&mut self, extensions: Vec<String>) {
        self.extensions_used = extensions;
    }

    /// Records what was decoded (one line, e.g. an extension and its counts).
    pub fn note_decoded(&mut self, line: String) {
        self.decoded.push(line);
    }

    /// Records USD stage metadata.
    pub fn set_stage(&mut self, stage: StageInfo) {
        self.stage = Some(stage);
    }

    /// Number of objects added so far.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Fixes the anchor and stores the triangles relative to it in f32: the world origin for a
    /// scene near it (so vertices that were f32 in the file are stored exactly), else the
    /// centre of the scene's bounds.
    pub fn finish(self, path: PathBuf) -> Scene {
        let bounds = self
            .triangles
            .iter()
            .flat_map(|t| t.iter().copied())
            .fold(Aabb::EMPTY, Aabb::grow);
        let bounds = self.quadrics.iter().fold(bounds, |b, q| {
            let [min, max] = q.bounds();
            b.union(Aabb::new(min, max))
        });
        let anchor = if bounds.is_empty() || near_origin(&bounds) {
            DVec3::ZERO
        } else {
            bounds.center()
        };
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|v| (v - anchor).as_vec3()))
            .collect();
        Scene {
            path,
            anchor,
            triangles,
            triangle_objects: self.triangle_objects,
            quadrics: self.quadrics,
            quadric_objects: self.quadric_objects,
            objects: self.objects,
            cameras: self.cameras,
            warnings: self.warnings,
            extensions_used: self.extensions_used,
            decoded: self.decoded,
            stage: self.stage,
        }
    }
}
