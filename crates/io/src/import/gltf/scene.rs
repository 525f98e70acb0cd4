//! Nodes → scene: walks the chosen scene's node tree in f64, places each mesh (read once,
//! however many nodes use it) and quadric, and collects the cameras. The one place a node
//! becomes scene objects is [`add_mesh_object`].

use super::accessor::NO_DATA;
use super::animation::NodeValues;
use super::buffers::Need;
use super::decode::{self, GPU_INSTANCING, MESHOPT};
use super::diagnostics::{Code, Diagnostic, FailFast};
use super::document::{array, as_index, extension, index_of, Document};
use super::geometry::DRACO;
use super::node::{bounded_transform, Node};
use super::pose::Pose;
use super::shading::MeshShading;
use super::QUADRIC_EXTENSION;
use crate::bound::transform::BoundedMat4;
use crate::camera::Camera;
use crate::quadric::Quadric;
use crate::scene::{Attributes, Mesh, Scene, SceneBuilder};
use glam::{DMat4, DVec3};
use serde_json::Value;
use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::sync::Arc;

/// Most node instances one file may expand to (guards against exponential node sharing).
pub const MAX_NODE_VISITS: usize = 10_000_000;

/// Builds the scene `choice` (by index or name; `None`: the default) of a document whose
/// buffers are loaded. Fails at the first problem in what the scene draws.
pub fn build(doc: &Document, choice: Option<&str>, path: &Path) -> Result<Scene, Diagnostic> {
    build_at(doc, choice, &Timing::default(), path)
}

/// When the scene is posed: `--time` and `--animation`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Timing {
    /// Seconds; `None`: no animation applied.
    pub time: Option<f64>,
    /// The animation by index or name; `None`: all of them.
    pub animation: Option<String>,
}

/// [`build`] with the animations `timing` chooses evaluated at its time.
pub fn build_at(
    doc: &Document,
    choice: Option<&str>,
    timing: &Timing,
    path: &Path,
) -> Result<Scene, Diagnostic> {
    let chosen = match timing.time {
        None => Vec::new(),
        Some(_) => doc
            .chosen_animations(timing.animation.as_deref())
            .map_err(|e| {
                Diagnostic::error(Code::UnresolvedReference, "/animations", e.to_string())
            })?,
    };
    let animated = match timing.time {
        Some(time) => doc.animate(&chosen, time)?,
        None => NodeValues::new(),
    };
    let mut walk = Walk {
        doc,
        builder: SceneBuilder::new(),
        meshes: HashMap::new(),
        globals: None,
        animated,
    };
    if let Some(pose) = super::pose::pose_info(doc, timing.time, &chosen) {
        if timing.time.is_none() && !pose.animations.is_empty() {
            walk.builder.note(format!(
                "the file has {} animations; drawn without --time: the nodes' own transforms and default morph weights",
                pose.animations.len()
            ));
        }
        walk.builder.set_pose(pose);
    }
    for index in 0..doc.list("materials").len() {
        walk.builder
            .add_material(super::shading::material_name(doc, index));
    }
    walk.builder.set_extensions_used(
        doc.extension_names("extensionsUsed")
            .map(String::from)
            .collect(),
    );
    let roots = match doc
        .scene_roots(choice)
        .map_err(|e| Diagnostic::error(Code::UnresolvedReference, "/scenes", e.to_string()))?
    {
        Some(roots) => roots,
        None => {
            let roots = doc.parentless_nodes();
            if !roots.is_empty() {
                walk.builder
                    .note("the file defines no scene: drawing every root node");
            }
            roots
        }
    };
    walk.walk(&roots)?;
    for line in decode::summary(doc) {
        walk.builder.note_decoded(line);
    }
    if walk.builder.object_count() == 0 {
        walk.builder.warn(crate::import::empty_scene());
    }
    Ok(walk.builder.finish(path.to_path_buf()))
}

/// Adds one placed mesh to the scene as a new object: the mesh in its own frame (stored once
/// however many nodes place it), the f64 world matrix of the node (or instance), and the
/// object's name and source pointer; returns the object's id, `None` for an empty mesh. Every
/// mesh object of a glTF scene goes through here. Refuses placements whose bounds reach beyond
/// ±f32::MAX/2, which large but finite transforms, such as a corrupt GPU instance scale, can
/// reach and no real scene needs.
fn add_mesh_object(
    builder: &mut SceneBuilder,
    name: String,
    pointer: String,
    mesh: &Arc<Mesh>,
    placed: &BoundedMat4,
) -> Result<Option<u32>, Diagnostic> {
    let world = &placed.value;
    if mesh.is_empty() {
        return Ok(None);
    }
    let limit = f32::MAX as f64 / 2.0;
    let corners = mesh.bounds().corners().map(|c| world.transform_point3(c));
    if corners
        .iter()
        .any(|p| !p.is_finite() || p.abs().max_element() > limit)
    {
        return Err(Diagnostic::error(
            Code::NodeTransformNotFinite,
            pointer,
            format!(
                "('{name}'): placed coordinates exceed the range raycast accepts (±{limit:.1e})"
            ),
        ));
    }
    let id = builder.new_object(name, pointer);
    builder.place_composed_mesh(id, Arc::clone(mesh), *placed);
    Ok(Some(id))
}

/// Which buffers the geometry reads: those behind the accessors of mesh primitives (POSITION,
/// indices, sparse parts), Draco data and GPU instancing attributes, and the sources of
/// meshopt-compressed views; what posing reads (morph targets drawn with weights, skin joints,
/// weights and inverse bind matrices); with `animating`, every morph target and animation
/// sampler. Buffers that only shading attributes read (NORMAL, TEXCOORD_0, morph NORMAL
/// deltas) are [`Need::Shading`]. Others (textures, animations without `--time`) are never
/// read for a render.
pub fn needed_buffers(doc: &Document, animating: bool) -> Vec<Need> {
    let mut needed = vec![Need::No; doc.list("buffers").len()];
    let mut mark_view = |view: Option<usize>, need: Need| {
        let Some(v) = view.and_then(|v| doc.item("bufferViews", v)) else {
            return;
        };
        // A meshopt view is decoded from its extension's buffer: its own (fallback) buffer
        // is never read.
        let compressed = MESHOPT
            .iter()
            .find_map(|name| extension(v, name).map(|e| index_of(e, "buffer")));
        if let Some(b) = compressed.unwrap_or_else(|| index_of(v, "buffer")) {
            if let Some(flag) = needed.get_mut(b) {
                *flag = (*flag).max(need);
            }
        }
    };
    let mut accessors = Vec::new();
    let mut shading = Vec::new();
    // What posing reads: morph targets of meshes some node draws with weights that are not
    // all zero, the joints and weights of skinned meshes, inverse bind matrices.
    let (mut morphed, mut skinned) = (HashSet::new(), HashSet::new());
    for node in doc.list("nodes") {
        if let Some(mesh) = index_of(node, "mesh") {
            if animating || doc.morph_weights(node, mesh, None).is_some() {
                morphed.insert(mesh);
            }
            if let Some(skin) = index_of(node, "skin") {
                skinned.insert(mesh);
                accessors.extend(
                    doc.item("skins", skin)
                        .and_then(|s| index_of(s, "inverseBindMatrices")),
                );
            }
        }
    }
    for (m, mesh) in doc.list("meshes").iter().enumerate() {
        for prim in array(mesh, "primitives") {
            let attributes = prim.get("attributes");
            accessors.extend(attributes.and_then(|a| index_of(a, "POSITION")));
            for name in ["NORMAL", "TEXCOORD_0"] {
                shading.extend(attributes.and_then(|a| index_of(a, name)));
            }
            accessors.extend(index_of(prim, "indices"));
            let draco = extension(prim, DRACO).and_then(|d| index_of(d, "bufferView"));
            mark_view(draco, Need::Geometry);
            if morphed.contains(&m) {
                for target in array(prim, "targets") {
                    accessors.extend(index_of(target, "POSITION"));
                    shading.extend(index_of(target, "NORMAL"));
                }
            }
            if let Some(attributes) = attributes
                .and_then(Value::as_object)
                .filter(|_| skinned.contains(&m))
            {
                let influences = attributes
                    .iter()
                    .filter(|(k, _)| k.starts_with("JOINTS_") || k.starts_with("WEIGHTS_"));
                accessors.extend(influences.filter_map(|(_, v)| as_index(v)));
            }
        }
    }
    if animating {
        for animation in doc.list("animations") {
            for sampler in array(animation, "samplers") {
                accessors.extend(index_of(sampler, "input"));
                accessors.extend(index_of(sampler, "output"));
            }
        }
    }
    for node in doc.list("nodes") {
        if let Some(attributes) = extension(node, GPU_INSTANCING).and_then(|e| e.get("attributes"))
        {
            accessors.extend(
                attributes
                    .as_object()
                    .into_iter()
                    .flat_map(|a| a.values())
                    .filter_map(as_index),
            );
        }
    }
    let shading = shading.into_iter().map(|a| (a, Need::Shading));
    let all = accessors
        .into_iter()
        .map(|a| (a, Need::Geometry))
        .chain(shading);
    for (acc, need) in all.filter_map(|(a, need)| Some((doc.item("accessors", a)?, need))) {
        mark_view(index_of(acc, "bufferView"), need);
        if let Some(sparse) = acc.get("sparse") {
            let indices = sparse.get("indices");
            mark_view(indices.and_then(|i| index_of(i, "bufferView")), need);
            let values = sparse.get("values");
            mark_view(values.and_then(|v| index_of(v, "bufferView")), need);
        }
    }
    needed
}

/// The node walk's state.
struct Walk<'a> {
    doc: &'a Document,
    builder: SceneBuilder,
    /// Each mesh read so far, in its own frame (f32 as the file stores it), by index.
    meshes: HashMap<usize, Arc<Mesh>>,
    /// Every node's global transform, once a skin needs them.
    globals: Option<Vec<Option<DMat4>>>,
    /// What the applied animations give their nodes.
    animated: NodeValues,
}

impl Walk<'_> {
    fn walk(&mut self, roots: &[usize]) -> Result<(), Diagnostic> {
        let node_count = self.doc.list("nodes").len();
        // Each node's world matrix with the bound of its composition in f64.
        let mut stack: Vec<(usize, BoundedMat4, usize)> = roots
            .iter()
            .rev()
            .map(|&n| (n, BoundedMat4::exact(DMat4::IDENTITY), 0))
            .collect();
        let mut visits = 0usize;
        while let Some((index, parent, depth)) = stack.pop() {
            let at = format!("/nodes/{index}");
            if depth > node_count {
                return Err(Diagnostic::error(Code::NodeLoop, at, "node cycle"));
            }
            visits += 1;
            if visits > MAX_NODE_VISITS {
                return Err(Diagnostic::error(
                    Code::AssetTooLarge,
                    "/nodes",
                    format!("the node hierarchy expands to more than {MAX_NODE_VISITS} instances"),
                ));
            }
            let node = self.doc.node(index).ok_or_else(|| {
                Diagnostic::error(Code::UnresolvedReference, &at, "node does not exist")
            })?;
            let mut sink = FailFast::default();
            let animated = self.animated.get(&index);
            let local = bounded_transform(node.json, animated, &at, &mut sink);
            let world = parent.then_bounded(&local);
            if let Some(error) = sink.error {
                return Err(error);
            }
            if !world.value.is_finite() {
                return Err(Diagnostic::error(
                    Code::NodeTransformNotFinite,
                    at,
                    "world transform is not finite",
                ));
            }
            self.add_node(&node, &world)?;
            for child in node.children().rev() {
                stack.push((child, world, depth + 1));
            }
        }
        Ok(())
    }

    /// The node's mesh (once, or per GPU instance), quadric and camera. A node is one object
    /// (its mesh and its quadric together); each GPU instance is one object.
    fn add_node(&mut self, node: &Node, placed: &BoundedMat4) -> Result<(), Diagnostic> {
        let world = &placed.value;
        let at = node.pointer();
        let name = node
            .name
            .map_or_else(|| format!("node{}", node.index), String::from);
        let mut object = None;
        if let Some(mesh) = node.mesh {
            let pose = self.pose_of(node, mesh).map_err(|e| e.within(&at))?;
            // A skinned mesh is placed by its joints: its vertices are posed in the world.
            let placement = &match pose.joints {
                Some(_) => BoundedMat4::exact(DMat4::IDENTITY),
                None => *placed,
            };
            let posed;
            let local = if pose.is_rest() {
                self.read_mesh(mesh).map_err(|e| e.within(&at))?;
                &self.meshes[&mesh]
            } else {
                let (triangles, attributes) = self
                    .mesh_triangles(mesh, Some(&pose))
                    .map_err(|e| e.within(&at))?;
                posed = Arc::new(Mesh::from_soup(&triangles).with_attributes(attributes));
                &posed
            };
            let instances = match extension(node.json, GPU_INSTANCING) {
                Some(ext) => decode::gpu_instances(self.doc, node.index, ext)?,
                None => None,
            };
            match instances {
                None => {
                    object = add_mesh_object(
                        &mut self.builder,
                        name.clone(),
                        at.clone(),
                        local,
                        placement,
                    )?
                }
                Some(instances) => {
                    for (k, instance) in instances.iter().enumerate() {
                        let pointer = format!("{at}/extensions/{GPU_INSTANCING}/{k}");
                        add_mesh_object(
                            &mut self.builder,
                            format!("{name}[{k}]"),
                            pointer,
                            local,
                            &placement.then_bounded(instance),
                        )?;
                    }
                }
            }
        }
        if let Some(ext) = extension(node.json, QUADRIC_EXTENSION) {
            let quadric = crate::import::gltf::quadric_extension::quadric_spec(ext)
                .and_then(|spec| Quadric::new(&spec, *world))
                .map(|quadric| quadric.with_composition(placed))
                .map_err(|e| {
                    Diagnostic::error(
                        Code::QuadricInvalid,
                        format!("{at}/extensions/{QUADRIC_EXTENSION}"),
                        format!("('{name}'): {e}"),
                    )
                })?;
            match object {
                Some(id) => self.builder.place_quadric(id, quadric),
                None => {
                    let pointer = format!("{at}/extensions/{QUADRIC_EXTENSION}");
                    self.builder.add_quadric(name.clone(), pointer, quadric);
                }
            }
        }
        if let Some(camera) = node.camera {
            self.add_camera(camera, &name, world);
        }
        Ok(())
    }

    /// Reads the triangles of mesh `mesh` (all its triangle primitives, in order) into the
    /// cache, once per mesh however many nodes use it.
    fn read_mesh(&mut self, mesh: usize) -> Result<(), Diagnostic> {
        if self.meshes.contains_key(&mesh) {
            return Ok(());
        }
        if self.doc.item("meshes", mesh).is_none() {
            return Err(Diagnostic::error(
                Code::UnresolvedReference,
                format!("/meshes/{mesh}"),
                "mesh does not exist",
            ));
        }
        let (triangles, attributes) = self.mesh_triangles(mesh, None)?;
        let read = Mesh::from_soup(&triangles).with_attributes(attributes);
        self.meshes.insert(mesh, Arc::new(read));
        Ok(())
    }

    /// How node `node` poses its mesh `mesh`: its default morph weights and its skin's joint
    /// matrices (the global transforms of every node computed once, at the first skin).
    fn pose_of(&mut self, node: &Node, mesh: usize) -> Result<Pose, Diagnostic> {
        let animated = self.animated.get(&node.index);
        let weights = animated.and_then(|a| a.weights.as_deref());
        let weights = self.doc.morph_weights(node.json, mesh, weights);
        let joints = match index_of(node.json, "skin") {
            None => None,
            Some(skin) => {
                if self.globals.is_none() {
                    self.globals = Some(self.doc.global_transforms(&self.animated)?);
                }
                let globals = self.globals.as_deref().unwrap_or_default();
                Some(self.doc.joint_matrices(skin, globals)?)
            }
        };
        Ok(Pose { weights, joints })
    }

    /// The triangles of mesh `mesh` (all its triangle primitives, in order), posed by `pose`
    /// when given, in the mesh's frame (the world's for a skin), with their shading
    /// attributes (normals posed too).
    fn mesh_triangles(
        &mut self,
        mesh: usize,
        pose: Option<&Pose>,
    ) -> Result<(Vec<[DVec3; 3]>, Attributes), Diagnostic> {
        let mut triangles = Vec::new();
        let mut shading = MeshShading::default();
        for prim in 0..self.doc.primitive_count(mesh) {
            match self.doc.primitive_geometry(mesh, prim) {
                Ok(Some(mut geometry)) => {
                    for warning in self.doc.read_shading(mesh, prim, &mut geometry) {
                        self.builder.warn(warning);
                    }
                    if let Some(pose) = pose {
                        self.doc.pose_primitive(mesh, prim, &mut geometry, pose)?;
                    }
                    let corners = geometry.corners();
                    shading.add(&geometry, &corners);
                    triangles.extend(
                        corners
                            .iter()
                            .map(|c| c.map(|v| geometry.positions[v as usize])),
                    );
                }
                Ok(None) => {
                    let why = self.doc.primitive_skip_reason(mesh, prim);
                    let at = format!("/meshes/{mesh}/primitives/{prim}");
                    self.builder.warn(note_at(at, why));
                }
                // A buffer without a uri, or on the network, is valid: its data is simply
                // not here. The primitive is left out rather than the file refused.
                Err(e) if e.code == NO_DATA => {
                    let at = format!("/meshes/{mesh}/primitives/{prim}");
                    self.builder.warn(note_at(at, format!("skipped: {e}")));
                }
                Err(e) => return Err(e),
            }
        }
        Ok((triangles, shading.finish()))
    }

    fn add_camera(&mut self, camera: usize, node_name: &str, world: &DMat4) {
        let spec = match self.doc.camera(camera) {
            Ok(spec) => spec,
            Err(e) => {
                let message = format!("{}: camera skipped", e.text());
                self.builder.warn(note_at(e.location, message));
                return;
            }
        };
        let Some(to_world) = Camera::orthonormalised(*world) else {
            self.builder.note(format!(
                "camera on node '{node_name}' has a degenerate transform: skipped"
            ));
            return;
        };
        self.builder.add_camera(Camera {
            name: spec.name.unwrap_or_else(|| node_name.to_string()),
            source: format!("gltf camera {camera} on node '{node_name}'"),
            projection: spec.projection,
            aspect_ratio: spec.aspect_ratio,
            znear: spec.znear,
            zfar: spec.zfar,
            to_world,
        });
    }
}

/// An importer's warning about the part of the file at JSON pointer `at`.
fn note_at(at: impl Into<String>, message: impl Into<String>) -> Diagnostic {
    Diagnostic::warning(Code::ImporterNote, at, message)
}
