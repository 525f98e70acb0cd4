//! The scene model: meshes stored as the file gives them, instances, quadrics, the object
//! table and the cameras.
//!
//! # Storage
//! A mesh keeps its vertices in its own frame and in the file's precision (see [`mesh`]);
//! every transform is f64. A mesh drawn once is placed in the world in f64 (its triangles join
//! the scene's world mesh, stored in f64 unless every placed coordinate is an f32 value); a mesh
//! drawn several times is stored once with its own octree, and each use is an [`Instance`]. The
//! scene's top-level primitives are the world mesh's triangles, the instances and the quadrics,
//! in that order, and one octree is built over them all.
//!
//! The acceleration structure works in coordinates relative to [`Scene::anchor`]: the centre of
//! the scene's bounds when the scene lies far from the world origin (more than 64 times its size
//! away), so that deep cells keep their digits, and the origin otherwise. The ray tests use the
//! world ray against the stored vertices, so nothing is rounded before a ray is cast.
//!
//! # Objects
//! One [`Object`] per scene object (a glTF node, an OBJ object, a USD prim or point instance).
//! An object is made of parts (placed meshes and quadrics); its primitives are numbered in the
//! order its parts were added, a mesh counting one per triangle and a quadric one, which is what
//! the `prim` buffer reports.

pub mod attributes;
mod bound;
mod builder;
mod framing;
mod hits;
pub mod instance;
pub mod mesh;
mod proximity;
mod shading;
pub mod topology;

pub use attributes::Attributes;
pub use bound::Origins;
pub use bound::Probe;
pub use builder::SceneBuilder;
pub use hits::{Crossing, EdgeRule};
pub use instance::{Instance, StoredMesh};
pub use mesh::{Mesh, MeshSet, Positions};
pub use proximity::Nearest;
pub use shading::Attribute;

use crate::accel::{
    intersect_each, intersect_one_by_one, octants_by_overlap, Hit, PacketCrossings, PreparedRay,
    PrimitiveSet, GROUP, PACKET,
};
use crate::camera::Camera;
use crate::geometry::triangle::WatertightRay;
use crate::geometry::triangle_packet::WatertightPacket;
use crate::geometry::Aabb;
use crate::quadric::Quadric;
use glam::DVec3;
use serde::Serialize;
use std::ops::Range;
use std::path::PathBuf;

/// Vertices [`Scene::framing_points`] gathers at most (48 MiB of points).
pub const FRAMING_POINTS: usize = 2 << 20;

/// What an object is made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectKind {
    /// Triangle meshes only.
    Mesh,
    /// An analytic quadric surface, possibly with mesh parts (a USD cylinder's caps).
    Quadric,
}

/// One entry of the object table: a glTF node, an OBJ object or group, a USD prim or point
/// instance, a quadric.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Object {
    /// Stable 1-based id, written to the `id` buffer (0 means no hit).
    pub id: u32,
    /// Node, object or prim name.
    pub name: String,
    /// Mesh or quadric.
    pub kind: ObjectKind,
    /// Where it came from: a JSON pointer such as `/nodes/3`, `obj:<name>` or a prim path.
    pub source: String,
    /// Number of triangles drawn (0 for a plain quadric).
    pub triangles: u32,
    /// Index of its first quadric in [`Scene::quadrics`], if it has one.
    #[serde(skip)]
    pub quadric: Option<u32>,
    /// Its parts, as a range of the scene's part list.
    #[serde(skip)]
    parts: Range<u32>,
}

/// One part of an object: a run of world-mesh triangles, an instance or a quadric.
#[derive(Debug, Clone, Copy)]
struct Part {
    /// Index into the object table.
    object: u32,
    /// Number of the part's first primitive among its object's primitives.
    first_prim: u32,
    kind: PartKind,
}

#[derive(Debug, Clone, Copy)]
enum PartKind {
    /// World-mesh triangles `first..first + count`.
    World { first: u32, count: u32 },
    /// Instance index.
    Instance(u32),
    /// Quadric index.
    Quadric(u32),
}

/// USD stage metadata, after USD's fallbacks (`upAxis` Y, `metersPerUnit` 0.01), and the
/// time code and variant selections drawn. The fields after `metersPerUnit` are left out of
/// JSON when the stage has nothing to say there (a static stage's records are unchanged).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct StageInfo {
    /// The stage's up axis, `Y` or `Z`.
    pub up_axis: String,
    /// Metres per scene unit.
    pub meters_per_unit: f64,
    /// `timeCodesPerSecond` (fallbacks `framesPerSecond`, 24), when the stage authors a time
    /// range or its drawn prims have time samples.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_codes_per_second: Option<f64>,
    /// `startTimeCode` and `endTimeCode`, when both are authored.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_code_range: Option<[f64; 2]>,
    /// The time code drawn (`--time`); `None`: the default time code.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time: Option<f64>,
    /// Attribute specs of the stage's layers that author time samples.
    #[serde(skip_serializing_if = "is_zero")]
    pub time_sampled_attributes: usize,
    /// Variant sets of the drawn prims, with their choices and selections.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub variant_sets: Vec<VariantSetInfo>,
    /// UsdSkel skeletons that pose drawn prims, with what they skin.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub skeletons: Vec<SkeletonInfo>,
}

/// One UsdSkel skeleton met under a SkelRoot (see [`StageInfo`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct SkeletonInfo {
    /// The Skeleton prim's path.
    pub path: String,
    /// How many joints it has.
    pub joints: usize,
    /// The SkelAnimation that poses it, `None`: its rest transforms.
    pub animation: Option<String>,
    /// The prims it skins, in walk order.
    pub skinned: Vec<String>,
    /// The skinned meshes its animation's blend shapes moved, in walk order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub blend_shaped: Vec<String>,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// One variant set of one prim (see [`StageInfo`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct VariantSetInfo {
    /// The prim's path.
    pub prim: String,
    /// The set's name.
    pub set: String,
    /// Its variants, sorted by name (as usd-core's `GetVariantNames`).
    pub choices: Vec<String>,
    /// The selection the layers author (or compose by fallback), before `--variant`.
    pub authored: Option<String>,
    /// The selection drawn: `--variant`'s where it names this set, else the authored one.
    pub selected: Option<String>,
}

/// What a glTF file can pose and what was drawn: its animations, skins and morph targets, and
/// the time and animations applied (`--time`, `--animation`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseInfo {
    /// The time the animations were evaluated at (seconds); `None`: no animation applied, the
    /// nodes' own transforms and default morph weights drawn.
    pub time: Option<f64>,
    /// Every animation of the file.
    pub animations: Vec<AnimationInfo>,
    /// Number of skins.
    pub skins: usize,
    /// Number of meshes with morph targets.
    pub morphed_meshes: usize,
}

/// One animation of [`PoseInfo`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AnimationInfo {
    /// Index in the file.
    pub index: usize,
    /// `name`, if any.
    pub name: Option<String>,
    /// First and last keyframe time (seconds), from the samplers' input bounds.
    pub range: Option<[f64; 2]>,
    /// Number of channels.
    pub channels: usize,
    /// True when it was applied (with `time`).
    pub applied: bool,
}

/// A loaded scene, ready for an acceleration structure.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it was loaded from.
    pub path: PathBuf,
    /// World position that the acceleration structure's coordinates are relative to.
    pub anchor: DVec3,
    world: MeshSet,
    world_parts: Vec<u32>,
    meshes: Vec<StoredMesh>,
    instances: Vec<Instance>,
    quadrics: Vec<Quadric>,
    quadric_parts: Vec<u32>,
    parts: Vec<Part>,
    /// Per part, a bound on each stored coordinate's distance from the exact placement of the
    /// file's vertex (0 but for world meshes placed by a transform; see
    /// [`crate::bound::placement_error`]).
    placement: Vec<f64>,
    /// The largest placement bound the search's edge filter weighs (`Scene::searched_apart`):
    /// [`crate::bound::CELL_SLACK`] times the largest side of the world triangles' finite
    /// bounds.
    apart_placement: f64,
    /// Per part, what the shading lookups need ([`shading`]).
    shading: Vec<shading::PartShading>,
    /// The materials parts are bound to, named as the file names them.
    materials: Vec<String>,
    /// Per instance, the entrywise bound of its placement matrix's composition from nested
    /// nodes ([`crate::bound::transform`]; zero for a matrix as read).
    instance_errors: Vec<glam::DMat4>,
    /// The object table, in id order.
    pub objects: Vec<Object>,
    /// Cameras defined by the file.
    pub cameras: Vec<Camera>,
    /// Things the importer skipped or repaired, one diagnostic each (one line as shown by
    /// their `Display`; the codes say what `raycast check` makes of them).
    pub warnings: Vec<crate::diagnostic::Diagnostic>,
    /// Extensions the file declares (glTF `extensionsUsed`).
    pub extensions_used: Vec<String>,
    /// What the importer decoded, one line per extension (Draco, meshopt, GPU instancing).
    pub decoded: Vec<String>,
    /// USD stage metadata (USD files only).
    pub stage: Option<StageInfo>,
    /// Animations, skins and morph targets and the pose drawn (glTF files that have any).
    pub pose: Option<PoseInfo>,
}

/// Per-ray data of the scene's primitives.
#[derive(Debug, Clone, Copy)]
pub struct SceneRay {
    triangle: WatertightRay,
    world_origin: DVec3,
}

/// What a hit is, resolved for the `id`, `prim` and `normal` buffers.
#[derive(Debug, Clone, Copy)]
pub struct Located<'a> {
    /// The object hit.
    pub object: &'a Object,
    /// The primitive's number inside the object (see the module docs).
    pub prim: u32,
    /// Unit world normal: the triangle's winding normal or the quadric's gradient direction.
    pub normal: DVec3,
}

/// Which kind of top-level primitive an index is.
enum Top {
    Triangle(usize),
    Instance(usize),
    Quadric(usize),
}

impl Scene {
    fn top(&self, index: usize) -> Top {
        let t = self.world.mesh.len();
        let i = self.instances.len();
        if index < t {
            Top::Triangle(index)
        } else if index < t + i {
            Top::Instance(index - t)
        } else {
            Top::Quadric(index - t - i)
        }
    }

    /// Number of triangles drawn (an instanced mesh counts once per instance).
    pub fn triangle_count(&self) -> usize {
        self.world.mesh.len()
            + self
                .instances
                .iter()
                .map(|i| self.meshes[i.mesh as usize].set.mesh.len())
                .sum::<usize>()
    }

    /// Number of triangles stored (an instanced mesh counts once).
    pub fn stored_triangle_count(&self) -> usize {
        self.world.mesh.len() + self.meshes.iter().map(|m| m.set.mesh.len()).sum::<usize>()
    }

    /// Primitives the acceleration structures are built over: the top level's (world
    /// triangles, instances, quadrics) and every stored instanced mesh's triangles.
    pub fn accel_primitive_count(&self) -> usize {
        PrimitiveSet::len(self) + self.meshes.iter().map(|m| m.set.mesh.len()).sum::<usize>()
    }

    /// Builds the octree of every instanced mesh that has none yet, in parallel. Tracing
    /// builds a missing one on first use anyway; a render calls this with its build step so
    /// that the work is parallel and timed as building.
    pub fn build_instances(&self) {
        use rayon::prelude::*;
        self.meshes.par_iter().for_each(|mesh| {
            mesh.octree();
        });
    }

    /// Drops the instanced meshes' octrees, so that the next build builds them again
    /// (benchmarks time whole builds this way).
    pub fn forget_instance_octrees(&mut self) {
        self.meshes.iter_mut().for_each(StoredMesh::forget_octree);
    }

    /// The instances.
    pub fn instances(&self) -> &[Instance] {
        &self.instances
    }

    /// Bytes of stored geometry: vertices, indices, per-triangle part indices, instanced
    /// meshes with their octrees, instance records and quadrics, and the shading attributes
    /// of the meshes placed in the world.
    pub fn geometry_bytes(&self) -> usize {
        let world_attributes: usize = (self.parts.iter().zip(&self.shading))
            .filter(|(part, _)| matches!(part.kind, PartKind::World { .. }))
            .filter_map(|(_, s)| s.attributes.as_ref())
            .map(|a| a.bytes())
            .sum();
        world_attributes
            + self.world.mesh.bytes()
            + self.world_parts.len() * 4
            + self.meshes.iter().map(StoredMesh::bytes).sum::<usize>()
            + self.instances.len() * std::mem::size_of::<Instance>()
            + self.quadrics.len() * std::mem::size_of::<Quadric>()
    }

    /// Bytes of what tracing reads besides the top-level octree: the world's vertices and
    /// index triples, the instanced meshes' with their octrees, the instance records and the
    /// quadrics (not the shading attributes, nor the part indices the id buffers read).
    pub fn trace_bytes(&self) -> usize {
        self.world.mesh.trace_bytes()
            + self
                .meshes
                .iter()
                .map(StoredMesh::trace_bytes)
                .sum::<usize>()
            + self.instances.len() * std::mem::size_of::<Instance>()
            + self.quadrics.len() * std::mem::size_of::<Quadric>()
    }

    /// The quadrics, in primitive order.
    pub fn quadrics(&self) -> &[Quadric] {
        &self.quadrics
    }

    /// The object quadric `q` (an index into [`Scene::quadrics`]) belongs to.
    pub fn quadric_object(&self, q: usize) -> &Object {
        &self.objects[self.parts[self.quadric_parts[q] as usize].object as usize]
    }

    /// The quadric top-level primitive `top` is (as [`Crossing::top`] names it), if it is one.
    pub fn quadric_at(&self, top: u32) -> Option<&Quadric> {
        match self.top(top as usize) {
            Top::Quadric(q) => Some(&self.quadrics[q]),
            _ => None,
        }
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

    /// World-space bounds of what the scene holds, as it gives it: instances by their placed
    /// vertices and quadrics by their clip boxes as given ([`Quadric::own_bounds`]), where
    /// [`Scene::world_bounds`] is the octree's conservative box (what `raycast info` prints).
    pub fn own_bounds(&self) -> Aabb {
        (0..self.len())
            .map(|i| self.world_prim_bounds(i))
            .fold(Aabb::EMPTY, Aabb::union)
    }

    /// The top-level primitives of a part.
    fn part_prims(&self, part: &Part) -> Range<usize> {
        let t = self.world.mesh.len();
        let i = self.instances.len();
        match part.kind {
            PartKind::World { first, count } => first as usize..(first + count) as usize,
            PartKind::Instance(k) => t + k as usize..t + k as usize + 1,
            PartKind::Quadric(q) => t + i + q as usize..t + i + q as usize + 1,
        }
    }

    fn object_parts(&self, object: &Object) -> &[Part] {
        &self.parts[object.parts.start as usize..object.parts.end as usize]
    }

    /// An object's triangles in world coordinates (f64), instances placed; empty for a plain
    /// quadric. Used by `raycast check` for topology and hole tests.
    pub fn mesh_triangles(&self, object: &Object) -> Vec<[DVec3; 3]> {
        let mut triangles = Vec::new();
        for part in self.object_parts(object) {
            match part.kind {
                PartKind::World { first, count } => triangles
                    .extend((first..first + count).map(|i| self.world.mesh.triangle(i as usize))),
                PartKind::Instance(k) => {
                    let instance = &self.instances[k as usize];
                    let mesh = &self.meshes[instance.mesh as usize].set.mesh;
                    let flip = instance.to_world.matrix3.determinant() < 0.0;
                    triangles.extend((0..mesh.len()).map(|i| {
                        let [a, b, c] = mesh
                            .triangle(i)
                            .map(|p| instance.to_world.transform_point3(p));
                        if flip {
                            [a, c, b]
                        } else {
                            [a, b, c]
                        }
                    }));
                }
                PartKind::Quadric(_) => {}
            }
        }
        triangles
    }

    /// World-space bounds of one object.
    pub fn object_bounds(&self, object: &Object) -> Aabb {
        self.object_parts(object)
            .iter()
            .flat_map(|part| self.part_prims(part))
            .map(|i| self.world_prim_bounds(i))
            .fold(Aabb::EMPTY, Aabb::union)
    }

    /// World bounds of top-level primitive `index`. An instance's are its mesh's vertices
    /// placed one by one, exact where the octree's (the placed corners of the mesh's box) are
    /// only conservative.
    fn world_prim_bounds(&self, index: usize) -> Aabb {
        match self.top(index) {
            Top::Quadric(q) => {
                let [min, max] = self.quadrics[q].own_bounds();
                Aabb::new(min, max)
            }
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let positions = self.meshes[instance.mesh as usize].set.mesh.positions();
                Aabb::from_points(
                    (0..positions.len() as u32)
                        .map(|v| instance.to_world.transform_point3(positions.get(v))),
                )
            }
            _ => PrimitiveSet::bounds(self, index).translated(-self.anchor),
        }
    }

    fn part_of(&self, prim: u32) -> &Part {
        let part = match self.top(prim as usize) {
            Top::Triangle(i) => self.world_parts[i],
            Top::Instance(k) => self.instances[k].part,
            Top::Quadric(q) => self.quadric_parts[q],
        };
        &self.parts[part as usize]
    }

    /// The object a top-level primitive belongs to.
    pub fn object(&self, prim: u32) -> &Object {
        &self.objects[self.part_of(prim).object as usize]
    }

    /// Resolves a hit of the ray `origin + t · dir`: the object, the primitive's number inside
    /// it and the unit world normal (finite for every hit). A hit on an instance traces the
    /// instance's own octree again, up to the hit's `t`, to find the triangle.
    pub fn locate(&self, hit: &Hit, origin: DVec3, dir: DVec3) -> Located<'_> {
        let part = self.part_of(hit.prim);
        let fallback = || -dir.normalize_or_zero();
        let (prim, normal) = match self.top(hit.prim as usize) {
            Top::Triangle(i) => {
                let PartKind::World { first, .. } = part.kind else {
                    unreachable!("world triangles belong to world parts")
                };
                let normal = self.world.normal(i, None).unwrap_or_else(fallback);
                (i as u32 - first, normal)
            }
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let stored = &self.meshes[instance.mesh as usize];
                match instance.intersect(stored, origin, dir, hit.t) {
                    Some(inner) => {
                        let normal = stored
                            .set
                            .normal(inner.prim as usize, Some(&instance.to_world));
                        (inner.prim, normal.unwrap_or_else(fallback))
                    }
                    None => (0, fallback()),
                }
            }
            Top::Quadric(q) => (0, self.quadrics[q].normal(origin, dir, hit.t)),
        };
        Located {
            object: &self.objects[part.object as usize],
            prim: part.first_prim + prim,
            normal,
        }
    }
}

impl PrimitiveSet for Scene {
    type RayData = SceneRay;

    fn len(&self) -> usize {
        self.world.mesh.len() + self.instances.len() + self.quadrics.len()
    }

    fn bounds(&self, index: usize) -> Aabb {
        match self.top(index) {
            Top::Triangle(i) => self.world.bounds(i),
            Top::Instance(k) => self.instances[k].bounds().translated(self.anchor),
            Top::Quadric(q) => {
                let [min, max] = self.quadrics[q].bounds();
                Aabb::new(min, max).translated(self.anchor)
            }
        }
    }

    fn triangles_only(&self) -> bool {
        self.instances.is_empty() && self.quadrics.is_empty()
    }

    /// Quadrics weigh [`Quadric::TEST_COST`]; triangles and instance boxes 1 (weighing the
    /// instances more changed nothing on the bench's mixed scene, whose top level holds four).
    fn cost(&self, index: usize) -> f64 {
        match self.top(index) {
            Top::Quadric(_) => Quadric::TEST_COST,
            Top::Triangle(_) | Top::Instance(_) => 1.0,
        }
    }

    fn overlaps(&self, index: usize, cell: &Aabb) -> bool {
        match self.top(index) {
            Top::Triangle(i) => self.world.overlaps(i, cell),
            Top::Instance(_) => self.bounds(index).overlaps(cell),
            Top::Quadric(q) => {
                let world = cell.translated(-self.anchor);
                self.quadrics[q].may_overlap_box(world.min, world.max)
            }
        }
    }

    fn child_mask(&self, index: usize, cell: &Aabb, margin: f64, candidates: u8) -> u8 {
        match self.top(index) {
            Top::Triangle(i) => self.world.child_mask(i, cell, margin, candidates),
            _ => octants_by_overlap(self, index, cell, margin, candidates),
        }
    }

    fn clipped_bounds(&self, index: usize, cell: &Aabb) -> Option<Aabb> {
        match self.top(index) {
            Top::Triangle(i) => self.world.clipped_bounds(i, cell),
            _ => self.bounds(index).common(*cell),
        }
    }

    /// Only the world's triangles read the watertight set-up: a scene of instances and
    /// quadrics alone skips it (with the top level's packet set-up, 4 % of the trace of 15
    /// instanced bunnies' camera rays). Always inlined (see [`crate::accel::prepare_ray_with`]).
    #[inline(always)]
    fn prepare(&self, local_origin: DVec3, dir: DVec3) -> SceneRay {
        let world_origin = local_origin + self.anchor;
        let triangle = if self.world.mesh.is_empty() {
            WatertightRay::Z_AXIS
        } else {
            WatertightRay::new(world_origin, dir)
        };
        SceneRay {
            triangle,
            world_origin,
        }
    }

    /// Always inlined (with [`crate::accel::test_primitive`]): left to the compiler, whether
    /// these two calls per primitive test were inlined changed with unrelated edits, and the
    /// calls cost 8 % of a trace's instructions (callgrind, 512² bunny 1266 -> 1162, helmet
    /// 1190 -> 1094 per ray).
    #[inline(always)]
    fn intersect(&self, index: usize, ray: &PreparedRay<SceneRay>, t_max: f64) -> Option<f64> {
        if index < self.world.mesh.len() {
            self.world
                .intersect_triangle(index, &ray.extra.triangle, t_max)
        } else {
            self.intersect_other(index, ray, t_max)
        }
    }

    /// The world's triangles through the four-triangle pre-filter; a group holding anything
    /// else one primitive at a time.
    #[inline(always)]
    fn intersect_group(
        &self,
        indices: &[u32],
        ray: &PreparedRay<SceneRay>,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> u32 {
        let triangles = self.world.mesh.len();
        if indices.iter().all(|&i| (i as usize) < triangles) {
            let (world, kernel) = (&self.world, ray.kernel);
            return world.intersect_triangles(indices, &ray.extra.triangle, kernel, t_max, ts);
        }
        intersect_one_by_one(self, indices, ray, t_max, ts)
    }

    /// For a group of world triangles, the group pre-filter's `apart` and `inside` lanes of
    /// those `Scene::searched_apart` admits (as [`PrimitiveSet::intersect_packet_apart`]
    /// says them for packets); anything else tells nothing.
    #[inline(always)]
    fn intersect_group_apart(
        &self,
        indices: &[u32],
        ray: &PreparedRay<SceneRay>,
        t_max: f64,
        ts: &mut [f64; GROUP],
    ) -> PacketCrossings {
        let triangles = self.world.mesh.len();
        if !indices.iter().all(|&i| (i as usize) < triangles) {
            return PacketCrossings::hits_only(intersect_one_by_one(self, indices, ray, t_max, ts));
        }
        let (mut placement, mut searched) = ([0.0; GROUP], 0);
        for (k, &i) in indices.iter().enumerate() {
            if let Some(p) = self.searched_apart(i as usize) {
                placement[k] = p;
                searched |= 1 << k;
            }
        }
        let ray = (&ray.extra.triangle, ray.kernel);
        let crossings = self
            .world
            .triangle_group::<true>(indices, ray, (t_max, ts), &placement);
        PacketCrossings {
            apart: crossings.apart & searched,
            inside: crossings.inside & searched,
            ..crossings
        }
    }

    type PacketData = Option<WatertightPacket>;

    /// `None` (no packet pre-filter) for a scene without triangles of its own.
    fn prepare_packet(&self, rays: &[PreparedRay<SceneRay>; PACKET]) -> Self::PacketData {
        if self.world.mesh.is_empty() {
            return None;
        }
        WatertightPacket::new(rays[0].kernel, |i| &rays[i].extra.triangle)
    }

    /// The world's triangles through the packet pre-filter, instances as packets through
    /// their own octrees, quadrics one ray at a time.
    #[inline(always)]
    fn intersect_packet(
        &self,
        index: usize,
        rays: &[PreparedRay<SceneRay>; PACKET],
        packet: &Self::PacketData,
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> u32 {
        self.packet_test::<false>(index, rays, packet, active, (t_max, ts))
            .hits
    }

    /// For a world triangle whose placement bound [`Scene::apart`] weighs (see
    /// `Scene::searched_apart`) in a scene whose rays the search prepares unmoved (anchor 0:
    /// `(o − 0) + 0` is `o`), the packet pre-filter's `apart` lanes
    /// (`MeshSet::triangle_packet`): the very filter [`Scene::apart`] would apply to the exact
    /// ray afterwards; and its `inside` lanes, the test of [`crate::bound::triangle::certainly_inside`] the
    /// hit's bound would make. Anything else tells nothing.
    #[inline(always)]
    fn intersect_packet_apart(
        &self,
        index: usize,
        rays: &[PreparedRay<SceneRay>; PACKET],
        packet: &Self::PacketData,
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> PacketCrossings {
        self.packet_test::<true>(index, rays, packet, active, (t_max, ts))
    }
}

impl Scene {
    /// [`PrimitiveSet::intersect_packet`], with `APART` its `_apart` form.
    #[inline(always)]
    fn packet_test<const APART: bool>(
        &self,
        index: usize,
        rays: &[PreparedRay<SceneRay>; PACKET],
        packet: &Option<WatertightPacket>,
        active: u32,
        (t_max, ts): (&[f64; PACKET], &mut [f64; PACKET]),
    ) -> PacketCrossings {
        let Some(packet) = packet.as_ref().filter(|_| index < self.world.mesh.len()) else {
            return PacketCrossings::hits_only(
                self.intersect_other_packet(index, rays, active, t_max, ts),
            );
        };
        let ray = |i: usize| &rays[i].extra.triangle;
        let world = &self.world;
        // Asked only with `APART`: the plain search does not read the placement.
        let apart = if APART {
            self.searched_apart(index)
        } else {
            None
        };
        match apart {
            Some(placement) => {
                world.triangle_packet::<true>(index, packet, ray, (active, placement), (t_max, ts))
            }
            None => world.triangle_packet::<false>(index, packet, ray, (active, 0.0), (t_max, ts)),
        }
    }
}

impl Scene {
    /// The instance and quadric tests, kept out of line so that the triangle test alone
    /// inlines into traversal (measured with callgrind: inlining all of them costs
    /// instructions on scenes without instances).
    #[inline(never)]
    fn intersect_other(
        &self,
        index: usize,
        ray: &PreparedRay<SceneRay>,
        t_max: f64,
    ) -> Option<f64> {
        let origin = ray.extra.world_origin;
        match self.top(index) {
            Top::Triangle(i) => self.world.intersect_triangle(i, &ray.extra.triangle, t_max),
            Top::Instance(k) => {
                let instance = &self.instances[k];
                let stored = &self.meshes[instance.mesh as usize];
                instance
                    .intersect_by(ray.kernel, stored, origin, ray.dir, t_max)
                    .map(|hit| hit.t)
            }
            Top::Quadric(q) => self.quadrics[q].intersect(origin, ray.dir, t_max),
        }
    }

    /// [`PrimitiveSet::intersect_packet`] for what the packet pre-filter does not take:
    /// instances through [`Instance::intersect_packet`], the rest one ray at a time.
    #[inline(never)]
    fn intersect_other_packet(
        &self,
        index: usize,
        rays: &[PreparedRay<SceneRay>; PACKET],
        active: u32,
        t_max: &[f64; PACKET],
        ts: &mut [f64; PACKET],
    ) -> u32 {
        let Top::Instance(k) = self.top(index) else {
            return intersect_each(self, index, rays, active, t_max, ts);
        };
        let instance = &self.instances[k];
        let stored = &self.meshes[instance.mesh as usize];
        let world = |i: usize| (rays[i].extra.world_origin, rays[i].dir);
        instance.intersect_packet(rays[0].kernel, stored, world, active, (t_max, ts))
    }
}

/// True when a scene lies close enough to the origin, relative to its size, that coordinates
/// relative to the origin keep their digits in deep octree cells.
fn near_origin(bounds: &Aabb) -> bool {
    bounds.center().abs().max_element() <= 64.0 * bounds.size().max_element()
}
