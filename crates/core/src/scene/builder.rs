//! Collecting a scene: objects, their placed meshes and quadrics, cameras and warnings.

use super::instance::{Instance, StoredMesh};
use super::mesh::{Mesh, MeshSet, Positions};
use super::shading::PartShading;
use super::{near_origin, Object, ObjectKind, Part, PartKind, PoseInfo, Scene, StageInfo};
use crate::accel::{OctreeParams, PrimitiveSet};
use crate::bound::transform::BoundedMat4;
use crate::bound::CELL_SLACK;
use crate::camera::Camera;
use crate::diagnostic::{Code, Diagnostic};
use crate::geometry::Aabb;
use crate::quadric::Quadric;
use glam::{DMat3, DMat4, DVec3};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// A mesh placed by fewer triangles than this is copied into the world mesh even when it is
/// drawn several times: its instance record and octree would cost more than its triangles.
const MIN_INSTANCED_TRIANGLES: usize = 16;

/// An object as collected: its names and how many primitives its parts hold so far.
#[derive(Debug)]
struct Draft {
    name: String,
    source: String,
    prims: u32,
}

/// One part as collected.
#[derive(Debug)]
enum Item {
    Mesh(Arc<Mesh>, Box<BoundedMat4>),
    /// A quadric and its material (1-based; 0: none).
    Quadric(Box<Quadric>, u32),
}

/// Collects objects (meshes in their own frames with f64 transforms, quadrics) and turns
/// them into a [`Scene`].
#[derive(Debug, Default)]
pub struct SceneBuilder {
    drafts: Vec<Draft>,
    /// `(object, first primitive inside it, part)`, in the order added.
    items: Vec<(u32, u32, Item)>,
    cameras: Vec<Camera>,
    warnings: Vec<Diagnostic>,
    extensions_used: Vec<String>,
    decoded: Vec<String>,
    stage: Option<StageInfo>,
    pose: Option<PoseInfo>,
    /// Material names, in the order first met (a material's id is its index + 1).
    materials: Vec<String>,
    material_ids: HashMap<String, u32>,
    /// Meshes seen so far by content hash, so that equal meshes read from different places
    /// (USD prims referencing one asset, say) are stored once.
    by_content: HashMap<u64, Vec<Arc<Mesh>>>,
    /// Each mesh already placed, by address, with the mesh stored for it (the placed one is
    /// kept alive so that its address cannot be reused by another mesh).
    by_address: HashMap<usize, (Arc<Mesh>, Arc<Mesh>)>,
}

impl SceneBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        SceneBuilder::default()
    }

    /// Starts an object; returns its id. Give it parts with [`SceneBuilder::place_mesh`] and
    /// [`SceneBuilder::place_quadric`].
    pub fn new_object(&mut self, name: String, source: String) -> u32 {
        self.drafts.push(Draft {
            name,
            source,
            prims: 0,
        });
        self.drafts.len() as u32
    }

    fn push(&mut self, id: u32, prims: u32, item: Item) {
        let draft = &mut self.drafts[id as usize - 1];
        self.items.push((id - 1, draft.prims, item));
        draft.prims += prims;
    }

    /// Adds `mesh`, placed in the world by `world`, to object `id`. Pass the same `Arc` for
    /// every use of one mesh: a mesh used several times is stored once.
    pub fn place_mesh(&mut self, id: u32, mesh: Arc<Mesh>, world: DMat4) {
        self.place_composed_mesh(id, mesh, BoundedMat4::exact(world));
    }

    /// [`SceneBuilder::place_mesh`] with a matrix composed from nested nodes, and the bound of
    /// that composition (for the `error` and `certain` AOVs; the mesh is placed by
    /// `world.value`).
    pub fn place_composed_mesh(&mut self, id: u32, mesh: Arc<Mesh>, world: BoundedMat4) {
        if !mesh.is_empty() {
            let mesh = self.canonical(mesh);
            self.push(id, mesh.len() as u32, Item::Mesh(mesh, Box::new(world)));
        }
    }

    /// The first mesh placed with the same content as `mesh` (compared bit for bit), or
    /// `mesh` itself.
    fn canonical(&mut self, mesh: Arc<Mesh>) -> Arc<Mesh> {
        let address = Arc::as_ptr(&mesh) as usize;
        if let Some((_, stored)) = self.by_address.get(&address) {
            return Arc::clone(stored);
        }
        let same = self.by_content.entry(mesh.content_hash()).or_default();
        let stored = match same.iter().find(|m| ***m == *mesh) {
            Some(m) => Arc::clone(m),
            None => {
                same.push(Arc::clone(&mesh));
                Arc::clone(&mesh)
            }
        };
        self.by_address.insert(address, (mesh, Arc::clone(&stored)));
        stored
    }

    /// Adds a quadric to object `id`.
    pub fn place_quadric(&mut self, id: u32, quadric: Quadric) {
        self.place_bound_quadric(id, quadric, 0);
    }

    /// Adds a quadric bound to `material` (from [`SceneBuilder::material`]; 0: none) to
    /// object `id`.
    pub fn place_bound_quadric(&mut self, id: u32, quadric: Quadric, material: u32) {
        self.push(id, 1, Item::Quadric(Box::new(quadric), material));
    }

    /// Adds a material named `name` to the scene's list, even when another has that name
    /// (glTF materials, which are told apart by index); returns its id (1-based).
    pub fn add_material(&mut self, name: String) -> u32 {
        self.material_ids
            .entry(name.clone())
            .or_insert(self.materials.len() as u32 + 1);
        self.materials.push(name);
        self.materials.len() as u32
    }

    /// The id of the material named `name` (1-based, in the order materials are first
    /// named), for [`crate::scene::attributes::MaterialRun`]s and bound quadrics.
    pub fn material(&mut self, name: &str) -> u32 {
        if let Some(&id) = self.material_ids.get(name) {
            return id;
        }
        self.materials.push(name.to_string());
        let id = self.materials.len() as u32;
        self.material_ids.insert(name.to_string(), id);
        id
    }

    /// Adds a mesh object made of world-space triangles; returns its id.
    pub fn add_mesh(&mut self, name: String, source: String, triangles: Vec<[DVec3; 3]>) -> u32 {
        let id = self.new_object(name, source);
        self.place_mesh(id, Arc::new(Mesh::from_soup(&triangles)), DMat4::IDENTITY);
        id
    }

    /// Adds a quadric object; returns its id.
    pub fn add_quadric(&mut self, name: String, source: String, quadric: Quadric) -> u32 {
        let id = self.new_object(name, source);
        self.place_quadric(id, quadric);
        id
    }

    /// Adds a camera.
    pub fn add_camera(&mut self, camera: Camera) {
        self.cameras.push(camera);
    }

    /// Records a warning.
    pub fn warn(&mut self, warning: Diagnostic) {
        self.warnings.push(warning);
    }

    /// Records a warning about the whole file (no location) of code `IMPORTER_NOTE`.
    pub fn note(&mut self, message: impl Into<String>) {
        self.warn(Diagnostic::note(Code::ImporterNote, message));
    }

    /// Records the extensions the file declares.
    pub fn set_extensions_used(&mut self, extensions: Vec<String>) {
        self.extensions_used = extensions;
    }

    /// Records what was decoded (one line, e.g. an extension and its counts).
    pub fn note_decoded(&mut self, line: String) {
        self.decoded.push(line);
    }

    /// Records what the file can pose and what was drawn.
    pub fn set_pose(&mut self, pose: PoseInfo) {
        self.pose = Some(pose);
    }

    /// Records USD stage metadata.
    pub fn set_stage(&mut self, stage: StageInfo) {
        self.stage = Some(stage);
    }

    /// Number of objects added so far.
    pub fn object_count(&self) -> usize {
        self.drafts.len()
    }

    /// Stores each mesh drawn several times once, with its octree, and places the others in
    /// the world in f64; fixes the anchor (the world origin for a scene near it, else the
    /// centre of the scene's bounds) and lays the parts out object by object.
    pub fn finish(self, path: PathBuf) -> Scene {
        let SceneBuilder {
            drafts,
            mut items,
            cameras,
            warnings,
            extensions_used,
            decoded,
            stage,
            pose,
            materials,
            ..
        } = self;
        items.sort_by_key(|&(object, first, _)| (object, first));
        let (meshes, mesh_of) = store_instanced(&items);
        let mut layout = Layout::default();
        for (part, (object, first_prim, item)) in items.into_iter().enumerate() {
            layout.add(part as u32, object, first_prim, item, &meshes, &mesh_of);
        }
        let Layout {
            points,
            triangles,
            world_parts,
            instances,
            quadrics,
            quadric_parts,
            parts,
            placement,
            shading,
            instance_errors,
        } = layout;
        let bounds = points.iter().copied().fold(Aabb::EMPTY, Aabb::grow);
        let bounds = instances.iter().fold(bounds, |b, i| b.union(i.bounds()));
        let bounds = quadrics.iter().fold(bounds, |b, q| {
            let [min, max] = q.bounds();
            b.union(Aabb::new(min, max))
        });
        let anchor = frame_anchor(&bounds);
        let world = MeshSet {
            mesh: Arc::new(Mesh::from_parts(Positions::exact(points), triangles)),
            anchor,
        };
        let objects = objects(drafts, &parts, &meshes, &instances);
        let apart_placement = CELL_SLACK * finite_extent(&world);
        Scene {
            path,
            anchor,
            world,
            world_parts,
            meshes,
            instances,
            quadrics,
            quadric_parts,
            parts,
            placement,
            apart_placement,
            shading,
            materials,
            instance_errors,
            objects,
            cameras,
            warnings,
            extensions_used,
            decoded,
            stage,
            pose,
        }
    }
}

/// The largest side of the union of `world`'s triangles' finite bounds (0 for none): no more
/// than that of any octree root holding them.
fn finite_extent(world: &MeshSet) -> f64 {
    let finite = |b: &Aabb| b.min.is_finite() && b.max.is_finite();
    let bounds = (0..world.len()).map(|i| world.bounds(i)).filter(finite);
    let union = bounds.fold(Aabb::EMPTY, Aabb::union);
    if union.is_empty() {
        return 0.0;
    }
    union.size().max_element()
}

/// The anchor for coordinates inside `bounds`: the origin when that keeps their digits, else
/// the centre.
fn frame_anchor(bounds: &Aabb) -> DVec3 {
    if bounds.is_empty() || near_origin(bounds) {
        DVec3::ZERO
    } else {
        bounds.center()
    }
}

/// True when `mesh` placed by `world` is drawn as an instance (given its number of uses).
fn instanced(mesh: &Mesh, world: &DMat4, uses: usize) -> bool {
    uses >= 2 && mesh.len() >= MIN_INSTANCED_TRIANGLES && world.row(3) == glam::DVec4::W
}

/// Stores each mesh drawn as an instance once (its octree is built later, see
/// [`StoredMesh::octree`]); returns them and the index of each by the mesh's address.
fn store_instanced(items: &[(u32, u32, Item)]) -> (Vec<StoredMesh>, HashMap<usize, u32>) {
    let mut uses: HashMap<usize, usize> = HashMap::new();
    for (_, _, item) in items {
        if let Item::Mesh(mesh, _) = item {
            *uses.entry(Arc::as_ptr(mesh) as usize).or_default() += 1;
        }
    }
    let mut unique: Vec<Arc<Mesh>> = Vec::new();
    let mut mesh_of = HashMap::new();
    for (_, _, item) in items {
        if let Item::Mesh(mesh, world) = item {
            let key = Arc::as_ptr(mesh) as usize;
            if instanced(mesh, &world.value, uses[&key]) && !mesh_of.contains_key(&key) {
                mesh_of.insert(key, unique.len() as u32);
                unique.push(Arc::clone(mesh));
            }
        }
    }
    let meshes = unique
        .iter()
        .map(|mesh| {
            let set = MeshSet {
                anchor: frame_anchor(&mesh.bounds()),
                mesh: Arc::clone(mesh),
            };
            StoredMesh::new(set, OctreeParams::default())
        })
        .collect();
    (meshes, mesh_of)
}

/// The scene's primitives and parts, laid out part by part.
#[derive(Default)]
struct Layout {
    points: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    world_parts: Vec<u32>,
    instances: Vec<Instance>,
    quadrics: Vec<Quadric>,
    quadric_parts: Vec<u32>,
    parts: Vec<Part>,
    placement: Vec<f64>,
    shading: Vec<PartShading>,
    instance_errors: Vec<DMat4>,
}

impl Layout {
    fn add(
        &mut self,
        part: u32,
        object: u32,
        first_prim: u32,
        item: Item,
        meshes: &[StoredMesh],
        mesh_of: &HashMap<usize, u32>,
    ) {
        let mut placement = 0.0;
        let shading;
        let kind = match item {
            Item::Quadric(quadric, material) => {
                shading = PartShading::quadric(material);
                self.quadrics.push(*quadric);
                self.quadric_parts.push(part);
                PartKind::Quadric(self.quadrics.len() as u32 - 1)
            }
            Item::Mesh(mesh, world) => {
                let stored = mesh_of.get(&(Arc::as_ptr(&mesh) as usize));
                let instance =
                    stored.and_then(|&m| Instance::new(m, &meshes[m as usize], &world.value, part));
                let attributes = mesh.attributes().cloned();
                match instance {
                    Some(instance) => {
                        shading = PartShading::mesh(attributes, instance.to_world.matrix3, false);
                        self.instances.push(instance);
                        self.instance_errors.push(world.error);
                        PartKind::Instance(self.instances.len() as u32 - 1)
                    }
                    None => {
                        let swapped = world.value.determinant() < 0.0;
                        shading =
                            PartShading::mesh(attributes, DMat3::from_mat4(world.value), swapped);
                        let positions = mesh.positions();
                        placement = crate::bound::placement_error(
                            &world,
                            (0..positions.len() as u32).map(|v| positions.get(v)),
                        );
                        let first = self.triangles.len() as u32;
                        mesh.place_into(&world.value, &mut self.points, &mut self.triangles);
                        let count = self.triangles.len() as u32 - first;
                        self.world_parts
                            .extend(std::iter::repeat_n(part, count as usize));
                        PartKind::World { first, count }
                    }
                }
            }
        };
        self.placement.push(placement);
        self.shading.push(shading);
        self.parts.push(Part {
            object,
            first_prim,
            kind,
        });
    }
}

/// The object table: each draft with its kind, triangle count and range of parts (parts are
/// sorted by object).
fn objects(
    drafts: Vec<Draft>,
    parts: &[Part],
    meshes: &[StoredMesh],
    instances: &[Instance],
) -> Vec<Object> {
    let mut objects: Vec<Object> = drafts
        .into_iter()
        .enumerate()
        .map(|(i, d)| Object {
            id: i as u32 + 1,
            name: d.name,
            kind: ObjectKind::Mesh,
            source: d.source,
            triangles: 0,
            quadric: None,
            parts: 0..0,
        })
        .collect();
    for (index, part) in parts.iter().enumerate() {
        let object = &mut objects[part.object as usize];
        if object.parts.is_empty() {
            object.parts = index as u32..index as u32;
        }
        object.parts.end = index as u32 + 1;
        match part.kind {
            PartKind::World { count, .. } => object.triangles += count,
            PartKind::Instance(k) => {
                object.triangles +=
                    meshes[instances[k as usize].mesh as usize].set.mesh.len() as u32
            }
            PartKind::Quadric(q) => {
                object.kind = ObjectKind::Quadric;
                object.quadric.get_or_insert(q);
            }
        }
    }
    objects
}
