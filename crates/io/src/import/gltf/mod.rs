//! glTF 2.0 (`.gltf` and `.glb`): one document layer, used twice.
//!
//! - The importer ([`prepare`], then [`Prepared::build`] at each time) reads it fail-fast:
//!   the first error ends the load.
//! - `raycast check` reads the same [`Document`] collect-all, through a [`Sink`] that keeps
//!   every [`Diagnostic`] (code, severity, JSON pointer, message), then builds the scene from
//!   it with [`scene::build`]: the file is parsed once, and both agree on what loads.
//!
//! The JSON is kept as `serde_json::Value` and only the parts a ray caster uses are
//! interpreted — buffers, buffer views, accessors, meshes, nodes, scenes, cameras and the
//! `RAYCAST_quadric` extension — so textures, images, samplers, materials, animations, skins
//! and extensions used but not required cannot stop a render. (The `gltf` crate's JSON model
//! refuses valid files: integers written as `1.0`, textures without `source`, accessors
//! without `bufferView`.) What does stop it anywhere in the document is what makes it no
//! glTF 2.0 document at all ([`integrity`]): a missing or ill-formed `asset.version`, and
//! references to objects that do not exist (checked by the `gltf` crate's validation where
//! it can read the file). Only the buffers the geometry reads are loaded, under the path
//! rule of [`crate::import::paths`].
//!
//! Compressed data (Draco, meshopt) and GPU instancing enter through the seams of [`decode`].

pub mod accessor;
pub mod animation;
pub mod buffers;
pub mod decode;
pub mod diagnostics;
pub mod document;
pub mod draco;
pub mod geometry;
pub mod instancing;
pub mod integrity;
pub mod mesh;
pub mod meshopt;
pub mod node;
pub mod pose;
pub mod quadric_extension;
pub mod scene;
pub mod shading;
pub mod structure;

pub use diagnostics::{Code, Diagnostic, ErrorsOnly, FailFast, Severity, Sink};
pub use document::Document;

use super::paths::folder_of;
use super::LoadOptions;
use crate::error::{Error, Result};
use crate::scene::Scene;
use crate::sizes::default_memory_limit;
use std::path::Path;

/// Our node extension carrying an analytic quadric (docs/RAYCAST_quadric.md).
pub const QUADRIC_EXTENSION: &str = "RAYCAST_quadric";

/// Extensions whose absence from our reader does not change the geometry we read.
const HONOURED_REQUIRED: &[&str] = &[
    "KHR_mesh_quantization",
    QUADRIC_EXTENSION,
    geometry::DRACO,
    decode::MESHOPT[0],
    decode::MESHOPT[1],
    decode::GPU_INSTANCING,
];

/// Prefixes of extensions that only concern appearance (materials, textures, lights, shader
/// techniques: KHR_techniques_webgl, and KHR_technique_webgl as older exporters spell it).
const APPEARANCE_PREFIXES: &[&str] = &[
    "KHR_materials_",
    "KHR_technique_webgl",
    "KHR_techniques_webgl",
    "KHR_texture_",
    "KHR_lights_",
    "EXT_texture_",
    "EXT_lights_",
    "MSFT_texture_",
];

/// True when a file that requires extension `name` can still be drawn correctly (it does not
/// change geometry, or we decode it). Shared with `raycast check`.
pub fn can_honour_required(name: &str) -> bool {
    HONOURED_REQUIRED.contains(&name) || APPEARANCE_PREFIXES.iter().any(|p| name.starts_with(p))
}

/// True when the path names a GLB by its extension.
pub fn is_glb_path(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
}

/// Refuses a document that requires an extension that changes geometry and that we cannot
/// decode (`UNSUPPORTED_EXTENSION`, at `/extensionsRequired/i`).
pub fn check_required_extensions(doc: &Document, sink: &mut dyn Sink) {
    for (i, name) in doc.extension_names("extensionsRequired").enumerate() {
        if !can_honour_required(name) {
            sink.error(
                Code::UnsupportedExtension,
                format!("/extensionsRequired/{i}"),
                format!("requires extension {name} which raycast cannot decode"),
            );
        }
    }
}

/// [`prepare`] of the file at `path`, fail-fast. External files resolve under the path rule
/// of `options` (the asset's folder unless widened or lifted).
pub fn prepare_file(path: &Path, options: &LoadOptions) -> Result<Prepared> {
    let mut sink = FailFast::default();
    match document::read_file(path, is_glb_path(path), &mut sink) {
        Ok(Some(bytes)) => prepare(bytes, path, options),
        Ok(None) => Err(match sink.error {
            Some(d) => Error::from_diagnostic(path, &d),
            None => Error::in_file(path, String::new()),
        }),
        Err(e) => Err(super::read_error(path, e)),
    }
}

/// A glTF document read, checked, with its buffers loaded and decoded: what every pose of
/// the file is built from, so that a sequence of times (`--time START:STOP:STEP`,
/// `Scene.at`) reads and decodes the file once.
pub struct Prepared {
    /// The document, its buffers loaded and decoded.
    doc: Document,
    /// The file it was read from (or named by), for messages and the scene's source.
    path: std::path::PathBuf,
    /// The scene to build (`--scene`).
    choice: Option<String>,
    /// The animation to play (`--animation`).
    animation: Option<String>,
    /// What the document layer noticed while reading (warnings), put before the scene's own.
    notes: Vec<Diagnostic>,
    /// Whether the animations' data were loaded (the document was prepared with a time).
    animating: bool,
    /// What accessors without a buffer view may take in each build (the memory limit less
    /// what reading took), restored before each; held while building, so that builds from
    /// several threads charge that budget one at a time.
    unbacked: std::sync::Mutex<u64>,
}

/// Parses glTF or GLB `bytes` (read from `path`) and loads and decodes the buffers the
/// geometry (and, with `options.time`, the animations) read, fail-fast. `bytes` are named by
/// `path` in messages, which says by its extension whether they are a GLB and is where
/// external files resolve.
pub fn prepare(bytes: Vec<u8>, path: &Path, options: &LoadOptions) -> Result<Prepared> {
    let fail = |d: Diagnostic| Error::from_diagnostic(path, &d);
    let mut sink = FailFast::default();
    let parsed = Document::parse(bytes, is_glb_path(path), &mut sink);
    let mut doc = match (parsed, sink.error.take()) {
        (Some(doc), None) => doc,
        (_, Some(error)) => return Err(fail(error)),
        (None, None) => return Err(Error::in_file(path, "not a glTF file")),
    };
    let limit = options.max_memory.or_else(default_memory_limit);
    doc.limit_unbacked(limit.unwrap_or(u64::MAX));
    check_required_extensions(&doc, &mut sink);
    if sink.error.is_none() {
        integrity::check(&doc, &mut ErrorsOnly(&mut sink));
    }
    let base = folder_of(path);
    let root = options.root.clone().unwrap_or_else(|| base.clone());
    let resources = buffers::Resources {
        base: &base,
        root: &root,
        allow_outside: options.allow_outside,
        max_bytes: u64::MAX,
    };
    if sink.error.is_none() {
        let needed = scene::needed_buffers(&doc, options.time.is_some());
        doc.load_buffers(&resources, Some(&needed), &mut sink);
    }
    if sink.error.is_none() {
        doc.decode_views(&mut sink);
    }
    if let Some(error) = sink.error {
        return Err(fail(error));
    }
    let notes = sink
        .notes
        .iter()
        .filter(|d| d.severity == Severity::Warning);
    Ok(Prepared {
        path: path.to_path_buf(),
        choice: options.scene.clone(),
        animation: options.animation.clone(),
        notes: notes.cloned().collect(),
        animating: options.time.is_some(),
        unbacked: std::sync::Mutex::new(doc.unbacked_left()),
        doc,
    })
}

impl Prepared {
    /// Whether any time can be built ([`Prepared::build`]): the document was prepared with a
    /// time, so the animations' data were loaded (they are not read without one).
    pub fn animating(&self) -> bool {
        self.animating
    }

    /// The scene posed at `time` (seconds; `None`: no animation); a time needs a document
    /// prepared with one ([`Prepared::animating`]).
    pub fn build(&self, time: Option<f64>) -> Result<Scene> {
        if time.is_some() && !self.animating {
            return Err(Error::in_file(
                &self.path,
                "was read without a time: its animations' data were not loaded",
            ));
        }
        let timing = scene::Timing {
            time,
            animation: self.animation.clone(),
        };
        let built = {
            let budget = self.unbacked.lock().unwrap_or_else(|p| p.into_inner());
            self.doc.limit_unbacked(*budget);
            scene::build_at(&self.doc, self.choice.as_deref(), &timing, &self.path)
        };
        let mut scene = built.map_err(|d| Error::from_diagnostic(&self.path, &d))?;
        // What the layer noticed while reading (a network URI, extra bytes after a GLB) comes
        // before what the scene walk noticed.
        scene.warnings.splice(0..0, self.notes.iter().cloned());
        Ok(scene)
    }
}
