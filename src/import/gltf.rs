//! glTF 2.0 (`.gltf` and `.glb`) through the `gltf` crate.
//!
//! The crate refuses files whose `extensionsRequired` names an extension it does not know, so
//! the document is parsed without its validation; its validation is then run with those
//! complaints dropped and our own extension policy applied. Node transforms are read from the
//! raw JSON numbers in f64 (the crate stores them as f32). Accessors are bounds-checked before
//! any read, so a malformed file gives an error, never a panic. Images are never read.

use super::{place, LoadOptions};
use crate::camera::{Camera, Projection};
use crate::error::{Error, Result};
use crate::quadric::{Quadric, QuadricSpec};
use crate::scene::{Scene, SceneBuilder};
use glam::{DMat4, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::{Error as ValidationError, Validate};
use gltf::mesh::Mode;
use gltf::Document;
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;

/// Our node extension carrying an analytic quadric (docs/RAYCAST_quadric.md).
pub(crate) const QUADRIC_EXTENSION: &str = "RAYCAST_quadric";

/// Extensions whose absence from the crate does not change the geometry we read.
const HONOURED_REQUIRED: &[&str] = &["KHR_mesh_quantization", QUADRIC_EXTENSION];

/// Prefixes of extensions that only concern appearance (materials, textures, lights).
const APPEARANCE_PREFIXES: &[&str] = &[
    "KHR_materials_",
    "KHR_texture_",
    "KHR_lights_",
    "EXT_texture_",
    "EXT_lights_",
    "MSFT_texture_",
];

/// Largest count of an accessor without a buffer view (all zeros but its sparse values).
const MAX_UNBACKED_COUNT: usize = 1 << 24;

/// Most node instances one file may expand to (guards against exponential node sharing).
const MAX_NODE_VISITS: usize = 10_000_000;

/// Loads a glTF or GLB file.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let bytes =
        std::fs::read(path).map_err(|e| Error::in_file(path, format!("cannot read: {e}")))?;
    let fail = |message: String| Error::in_file(path, message);
    let kind = if bytes.starts_with(b"glTF") {
        "GLB"
    } else {
        "glTF"
    };
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| fail(format!("not a valid {kind} file: {e}")))?;
    let raw = raw_json(&bytes).map_err(fail)?;
    let document = &gltf.document;
    check_required_extensions(document).map_err(fail)?;
    validate(document).map_err(fail)?;
    let base = path.parent().unwrap_or(Path::new("."));
    check_buffer_files(document, base).map_err(fail)?;
    let buffers = gltf::import_buffers(document, Some(base), gltf.blob.clone())
        .map_err(|e| fail(format!("cannot load buffers: {e}")))?;
    let buffers: Vec<&[u8]> = buffers.iter().map(|b| &b.0[..]).collect();
    let mut loader = Loader {
        document,
        raw: &raw,
        buffers: &buffers,
        builder: SceneBuilder::new(),
        meshes: HashMap::new(),
    };
    loader
        .builder
        .set_extensions_used(document.extensions_used().map(String::from).collect());
    let roots =
        scene_roots(document, options.scene.as_deref(), &mut loader.builder).map_err(fail)?;
    loader.walk(&roots).map_err(fail)?;
    if loader.builder.object_count() == 0 {
        loader
            .builder
            .warn("the scene holds no triangles or quadrics");
    }
    Ok(loader.builder.finish(path.to_path_buf()))
}

/// The JSON part of a `.gltf` or `.glb`, parsed as plain JSON for full-precision numbers.
fn raw_json(bytes: &[u8]) -> std::result::Result<Value, String> {
    let json = if bytes.starts_with(b"glTF") {
        gltf::binary::Glb::from_slice(bytes)
            .map_err(|e| format!("not a valid GLB file: {e}"))?
            .json
            .into_owned()
    } else {
        bytes.to_vec()
    };
    serde_json::from_slice(&json).map_err(|e| format!("invalid JSON: {e}"))
}

/// Names the first external buffer file that does not exist, before anything is read.
fn check_buffer_files(document: &Document, base: &Path) -> std::result::Result<(), String> {
    for buffer in document.buffers() {
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            if uri.starts_with("data:") {
                continue;
            }
            let decoded =
                urlencoding::decode(uri).map_or_else(|_| uri.to_string(), |d| d.into_owned());
            if !base.join(&decoded).is_file() {
                return Err(format!(
                    "buffer {} refers to '{decoded}', which does not exist",
                    buffer.index()
                ));
            }
        }
    }
    Ok(())
}

/// Runs the crate's validation, ignoring its verdict on required extensions.
fn validate(document: &Document) -> std::result::Result<(), String> {
    let root = document.as_json();
    // gltf-json 1.4 indexes the POSITION accessor without a bounds check while validating.
    if let Some(first) = dangling_positions(root).first() {
        return Err(format!("invalid glTF: {first}: accessor does not exist"));
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        if error != ValidationError::Unsupported {
            errors.push(format!("{}: {error}", path()));
        }
    });
    match errors.first() {
        None => Ok(()),
        Some(first) if errors.len() == 1 => Err(format!("invalid glTF: {first}")),
        Some(first) => Err(format!(
            "invalid glTF: {first} (and {} more problems)",
            errors.len() - 1
        )),
    }
}

/// JSON pointers of POSITION attributes that name an accessor the file does not have. The
/// `gltf` crate's validation panics on them, so they are checked before it runs (here and
/// in `raycast check`).
pub(crate) fn dangling_positions(root: &gltf::json::Root) -> Vec<String> {
    let mut found = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(index) = primitive.attributes.get(&position) {
                if index.value() >= root.accessors.len() {
                    found.push(format!("/meshes/{m}/primitives/{p}/attributes/POSITION"));
                }
            }
        }
    }
    found
}

/// Refuses files that require an extension that changes geometry and that we cannot decode.
fn check_required_extensions(document: &Document) -> std::result::Result<(), String> {
    let unsupported: Vec<&str> = document
        .extensions_required()
        .filter(|e| !can_honour_required(e))
        .collect();
    if unsupported.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "requires extension {} which raycast cannot decode",
            unsupported.join(", ")
        ))
    }
}

/// True when a file that requires extension `name` can still be drawn correctly (it does not
/// change geometry, or we decode it). Shared with `raycast check`.
pub(crate) fn can_honour_required(name: &str) -> bool {
    HONOURED_REQUIRED.contains(&name) || APPEARANCE_PREFIXES.iter().any(|p| name.starts_with(p))
}

/// The root nodes of the chosen scene: by index or name, else the default scene, else the
/// first scene, else every node that is nobody's child (with a warning).
fn scene_roots(
    document: &Document,
    choice: Option<&str>,
    builder: &mut SceneBuilder,
) -> std::result::Result<Vec<usize>, String> {
    let scene = match choice {
        Some(choice) => Some(
            document
                .scenes()
                .find(|s| choice.parse::<usize>() == Ok(s.index()) || s.name() == Some(choice))
                .ok_or_else(|| {
                    format!(
                        "no scene '{choice}' (the file has {})",
                        document.scenes().count()
                    )
                })?,
        ),
        None => document
            .default_scene()
            .or_else(|| document.scenes().next()),
    };
    if let Some(scene) = scene {
        return Ok(scene.nodes().map(|n| n.index()).collect());
    }
    let mut is_child = vec![false; document.nodes().count()];
    for node in document.nodes() {
        for child in node.children() {
            is_child[child.index()] = true;
        }
    }
    let roots: Vec<usize> = (0..is_child.len()).filter(|&i| !is_child[i]).collect();
    if !roots.is_empty() {
        builder.warn("the file defines no scene: drawing every root node");
    }
    Ok(roots)
}

/// Walks the node hierarchy and fills the scene builder.
struct Loader<'a> {
    document: &'a Document,
    raw: &'a Value,
    buffers: &'a [&'a [u8]],
    builder: SceneBuilder,
    /// Object-space triangles of each mesh read so far.
    meshes: HashMap<usize, Vec<[DVec3; 3]>>,
}

impl Loader<'_> {
    fn walk(&mut self, roots: &[usize]) -> std::result::Result<(), String> {
        let node_count = self.document.nodes().count();
        let mut stack: Vec<(usize, DMat4, usize)> = roots
            .iter()
            .rev()
            .map(|&n| (n, DMat4::IDENTITY, 0))
            .collect();
        let mut visits = 0usize;
        let mut warned_skin = false;
        while let Some((index, parent, depth)) = stack.pop() {
            if depth > node_count {
                return Err(format!("node cycle through /nodes/{index}"));
            }
            visits += 1;
            if visits > MAX_NODE_VISITS {
                return Err(format!(
                    "the node hierarchy expands to more than {MAX_NODE_VISITS} instances"
                ));
            }
            let node = self
                .document
                .nodes()
                .nth(index)
                .ok_or_else(|| format!("node {index} does not exist"))?;
            let world = parent * self.local_transform(index)?;
            if !world.is_finite() {
                return Err(format!("/nodes/{index}: world transform is not finite"));
            }
            if node.skin().is_some() && !warned_skin {
                warned_skin = true;
                self.builder
                    .warn("skinned meshes are drawn in their bind pose");
            }
            let name = node
                .name()
                .map_or_else(|| format!("node{index}"), String::from);
            if let Some(mesh) = node.mesh() {
                self.read_mesh(&mesh)?;
                let local = &self.meshes[&mesh.index()];
                if !local.is_empty() {
                    let triangles = place(local, &world);
                    self.builder
                        .add_mesh(name.clone(), format!("/nodes/{index}"), triangles);
                }
            }
            if let Some(extension) = self.raw["nodes"][index]["extensions"].get(QUADRIC_EXTENSION) {
                let quadric = QuadricSpec::from_gltf_extension(extension)
                    .and_then(|spec| Quadric::new(&spec, world))
                    .map_err(|e| format!("/nodes/{index} ('{name}'): {QUADRIC_EXTENSION}: {e}"))?;
                let source = format!("/nodes/{index}/extensions/{QUADRIC_EXTENSION}");
                self.builder.add_quadric(name.clone(), source, quadric);
            }
            if let Some(camera) = node.camera() {
                self.add_camera(&camera, &name, &world);
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child.index(), world, depth + 1));
            }
        }
        Ok(())
    }

    /// A node's local matrix from the raw JSON, in f64.
    fn local_transform(&self, index: usize) -> std::result::Result<DMat4, String> {
        let node = &self.raw["nodes"][index];
        let numbers = |key: &str, len: usize| -> std::result::Result<Option<Vec<f64>>, String> {
            let Some(value) = node.get(key) else {
                return Ok(None);
            };
            let list: Option<Vec<f64>> = value
                .as_array()
                .filter(|a| a.len() == len)
                .and_then(|a| a.iter().map(Value::as_f64).collect());
            match list {
                Some(list) if list.iter().all(|x| x.is_finite()) => Ok(Some(list)),
                _ => Err(format!(
                    "/nodes/{index}/{key}: expected {len} finite numbers"
                )),
            }
        };
        if let Some(m) = numbers("matrix", 16)? {
            let matrix = DMat4::from_cols_slice(&m);
            return Ok(matrix);
        }
        let t = numbers("translation", 3)?.map_or(DVec3::ZERO, |v| DVec3::from_slice(&v));
        let s = numbers("scale", 3)?.map_or(DVec3::ONE, |v| DVec3::from_slice(&v));
        let r = match numbers("rotation", 4)? {
            None => DQuat::IDENTITY,
            Some(q) => {
                let q = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
                if q.length_squared() == 0.0 {
                    return Err(format!("/nodes/{index}/rotation: zero quaternion"));
                }
                q.normalize()
            }
        };
        Ok(DMat4::from_scale_rotation_translation(s, r, t))
    }

    fn add_camera(&mut self, camera: &gltf::Camera, node_name: &str, world: &DMat4) {
        let Some(to_world) = Camera::orthonormalised(*world) else {
            self.builder.warn(format!(
                "camera on node '{node_name}' has a degenerate transform: skipped"
            ));
            return;
        };
        let (projection, aspect_ratio, znear, zfar) = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => (
                Projection::Perspective {
                    yfov: p.yfov() as f64,
                },
                p.aspect_ratio().map(f64::from),
                p.znear() as f64,
                p.zfar().map(f64::from),
            ),
            gltf::camera::Projection::Orthographic(o) => (
                Projection::Orthographic {
                    ymag: o.ymag() as f64,
                },
                Some(o.xmag() as f64 / o.ymag() as f64).filter(|a| a.is_finite() && *a > 0.0),
                o.znear() as f64,
                Some(o.zfar() as f64),
            ),
        };
        self.builder.add_camera(Camera {
            name: camera
                .name()
                .map_or_else(|| node_name.to_string(), String::from),
            source: format!("gltf camera {} on node '{node_name}'", camera.index()),
            projection,
            aspect_ratio,
            znear,
            zfar,
            to_world,
        });
    }

    /// Reads the object-space triangles of a mesh (all its triangle primitives, in order) into
    /// the cache, once per mesh however many nodes use it.
    fn read_mesh(&mut self, mesh: &gltf::Mesh) -> std::result::Result<(), String> {
        if self.meshes.contains_key(&mesh.index()) {
            return Ok(());
        }
        let mut triangles = Vec::new();
        for primitive in mesh.primitives() {
            let at = format!("/meshes/{}/primitives/{}", mesh.index(), primitive.index());
            match primitive.mode() {
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {
                    let prim = self
                        .primitive_triangles(&primitive)
                        .map_err(|e| format!("{at}: {e}"))?;
                    triangles.extend(prim);
                }
                other => self.builder.warn(format!(
                    "{at}: {other:?} primitive skipped (only triangles are drawn)"
                )),
            }
        }
        self.meshes.insert(mesh.index(), triangles);
        Ok(())
    }

    fn primitive_triangles(
        &self,
        primitive: &gltf::Primitive,
    ) -> std::result::Result<Vec<[DVec3; 3]>, String> {
        let positions = primitive
            .get(&gltf::Semantic::Positions)
            .ok_or("has no POSITION attribute")?;
        let positions = read_positions(&positions, self.buffers)?;
        let indices = match primitive.indices() {
            Some(accessor) => read_indices(&accessor, self.buffers, positions.len())?,
            None => (0..positions.len() as u32).collect(),
        };
        let corners = assemble(primitive.mode(), &indices);
        Ok(corners
            .into_iter()
            .map(|[a, b, c]| {
                [
                    positions[a as usize],
                    positions[b as usize],
                    positions[c as usize],
                ]
            })
            .collect())
    }
}

/// Vertex index triples for a triangle list, strip or fan.
fn assemble(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|i| {
                if i % 2 == 0 {
                    [indices[i], indices[i + 1], indices[i + 2]]
                } else {
                    [indices[i + 1], indices[i], indices[i + 2]]
                }
            })
            .collect(),
        Mode::TriangleFan => (1..indices.len().saturating_sub(1))
            .map(|i| [indices[i], indices[i + 1], indices[0]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    }
}

/// Checks that every byte an accessor (and its sparse part) reads lies inside its buffer view
/// and buffer, so that reading it cannot go out of bounds.
fn check_accessor(accessor: &gltf::Accessor, buffers: &[&[u8]]) -> std::result::Result<(), String> {
    let element = accessor.size();
    let count = accessor.count();
    if count == 0 {
        return Err(format!("accessor {} has count 0", accessor.index()));
    }
    // Without a buffer view nothing bounds the count by the file's size: cap what it may
    // make us allocate.
    if accessor.view().is_none() && count > MAX_UNBACKED_COUNT {
        return Err(format!(
            "accessor {} has no buffer view and count {count} (more than {MAX_UNBACKED_COUNT})",
            accessor.index()
        ));
    }
    let fits =
        |view: &gltf::buffer::View, offset: usize, stride: usize, items: usize, size: usize| {
            let buffer_len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
            span_fits(
                buffer_len,
                view.offset(),
                view.length(),
                offset,
                stride,
                items,
                size,
            )
        };
    let bad = || {
        format!(
            "accessor {} reads past the end of its buffer",
            accessor.index()
        )
    };
    if let Some(view) = accessor.view() {
        if !fits(
            &view,
            accessor.offset(),
            view.stride().unwrap_or(element),
            count,
            element,
        ) {
            return Err(bad());
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(format!(
                "accessor {}: invalid sparse count {n}",
                accessor.index()
            ));
        }
        let indices = sparse.indices();
        let index_size = indices.index_type().size();
        let values = sparse.values();
        if !fits(&indices.view(), indices.offset(), index_size, n, index_size)
            || !fits(&values.view(), values.offset(), element, n, element)
        {
            return Err(bad());
        }
    }
    Ok(())
}

/// True when `items` elements of `size` bytes, `stride` apart from `offset` inside a buffer
/// view (`view_offset`, `view_length`) of a buffer of `buffer_len` bytes, all lie inside the
/// view and the view inside the buffer, without overflow. Shared with `raycast check`.
pub(crate) fn span_fits(
    buffer_len: usize,
    view_offset: usize,
    view_length: usize,
    offset: usize,
    stride: usize,
    items: usize,
    size: usize,
) -> bool {
    let view_end = view_offset.checked_add(view_length);
    let last = stride
        .checked_mul(items.saturating_sub(1))
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(size));
    matches!((view_end, last), (Some(end), Some(last)) if end <= buffer_len && last <= view_length)
        && stride >= size
        && items > 0
}

/// Reads an accessor as items of type `T` after [`check_accessor`].
fn read_items<T: gltf::accessor::Item>(
    accessor: &gltf::Accessor,
    buffers: &[&[u8]],
) -> std::result::Result<Vec<T>, String> {
    check_accessor(accessor, buffers)?;
    let items = gltf::accessor::Iter::<T>::new(accessor.clone(), |b: gltf::Buffer| {
        buffers.get(b.index()).copied()
    })
    .ok_or_else(|| format!("accessor {} cannot be read", accessor.index()))?;
    Ok(items.collect())
}

/// Reads POSITION data: float, or integer (normalized or not) as KHR_mesh_quantization allows.
fn read_positions(
    accessor: &gltf::Accessor,
    buffers: &[&[u8]],
) -> std::result::Result<Vec<DVec3>, String> {
    if accessor.dimensions() != Dimensions::Vec3 {
        return Err("POSITION is not VEC3".into());
    }
    let normalized = accessor.normalized();
    fn convert<T: Copy + Into<f64>>(items: Vec<[T; 3]>, scale: Option<f64>) -> Vec<DVec3> {
        items
            .into_iter()
            .map(|p| {
                let v = DVec3::new(p[0].into(), p[1].into(), p[2].into());
                match scale {
                    Some(max) => (v / max).max(DVec3::splat(-1.0)),
                    None => v,
                }
            })
            .collect()
    }
    let norm = |max: f64| normalized.then_some(max);
    let positions = match accessor.data_type() {
        DataType::F32 => convert(read_items::<[f32; 3]>(accessor, buffers)?, None),
        DataType::I8 => convert(read_items::<[i8; 3]>(accessor, buffers)?, norm(127.0)),
        DataType::U8 => convert(read_items::<[u8; 3]>(accessor, buffers)?, norm(255.0)),
        DataType::I16 => convert(read_items::<[i16; 3]>(accessor, buffers)?, norm(32767.0)),
        DataType::U16 => convert(read_items::<[u16; 3]>(accessor, buffers)?, norm(65535.0)),
        DataType::U32 => return Err("POSITION has component type UNSIGNED_INT".into()),
    };
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("POSITION {i} is not finite"));
    }
    Ok(positions)
}

/// Reads an index accessor and checks every index against the vertex count.
fn read_indices(
    accessor: &gltf::Accessor,
    buffers: &[&[u8]],
    vertices: usize,
) -> std::result::Result<Vec<u32>, String> {
    if accessor.dimensions() != Dimensions::Scalar {
        return Err("indices are not SCALAR".into());
    }
    let indices: Vec<u32> = match accessor.data_type() {
        DataType::U8 => read_items::<u8>(accessor, buffers)?
            .into_iter()
            .map(u32::from)
            .collect(),
        DataType::U16 => read_items::<u16>(accessor, buffers)?
            .into_iter()
            .map(u32::from)
            .collect(),
        DataType::U32 => read_items::<u32>(accessor, buffers)?,
        other => return Err(format!("indices have component type {other:?}")),
    };
    match indices.iter().find(|&&i| i as usize >= vertices) {
        Some(bad) => Err(format!("index {bad} out of range ({vertices} vertices)")),
        None => Ok(indices),
    }
}
