//! USD (`.usda`, `.usdc`, `.usd`, `.usdz`) through the `openusd` crate.
//!
//! openusd composes the stage (sublayers, references, payloads, variants, inherits,
//! specializes, scene-graph instancing); this module walks the composed prims from the
//! pseudo-root (or from the prim chosen with `--scene PATH`) and turns them into world-space
//! triangles and quadrics:
//!
//! - transforms composed in f64 from the root ([`xform`]), `!resetXformStack!` honoured;
//! - `Mesh` polygons as triangle fans ([`mesh`]); intrinsic gprims as quadrics ([`shapes`]);
//!   prims with `raycast:quadric:*` attributes as general quadrics ([`quadric`]);
//! - `Camera` prims as cameras named by their prim path;
//! - instanceable prims through their instance proxies (each instance's gprims are objects
//!   named by their proxy paths) and `PointInstancer` (one object per instance, `path[i]`);
//! - `def` prims only (not `over` or `class`), active, not `invisible`, purpose neither
//!   `guide` nor `proxy`.
//!
//! Attribute values are read at `--time CODE` as usd-core's `UsdAttribute::Get(time)` reads
//! them, or at the default time code, as usd-core does for `UsdTimeCode::Default()`
//! ([`value`]); `--variant SET=NAME` selections are authored in memory as the walk meets
//! their prims ([`variants`]); point instancers are in [`instancer`]. Composition problems (a missing referenced file, an unresolved
//! payload) and attributes of unknown value types ([`read_warnings`]) are warnings. The file format is read by openusd; docs/usd.md has the details.

mod camera;
pub mod child;
mod composition;
pub use composition::{UNREAD_LAYER, UNREAD_NOTE};
mod confine;
mod instancer;
mod mesh;
mod motion;
mod primvars;
mod quadric;
mod read_warnings;
pub use read_warnings::UNKNOWN_VALUE_TYPE;
mod shapes;
mod skel;
mod value;
mod variants;
mod xform;

pub use variants::{parse_choice, Choice};

use super::LoadOptions;
use crate::bound::transform::BoundedMat4;
use crate::error::{Error, Result};
use crate::quadric::Quadric;
use crate::scene::attributes::runs;
use crate::scene::{Mesh, Scene, SceneBuilder, StageInfo};
use glam::{DMat4, DVec3};
use openusd::sdf;
use openusd::usd::{Prim, Stage};
use raycast_core::diagnostic::{Code, Diagnostic};
use shapes::Part;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

/// Deepest nesting of braces, parentheses and brackets accepted in a text layer: the USD
/// reader parses recursively, so a hostile file could otherwise exhaust the stack.
pub const MAX_TEXT_NESTING: usize = 256;

/// The deepest nesting of `{`, `(` and `[` in a text (`#usda`) layer, outside strings and
/// comments; None for a binary layer.
pub fn text_nesting(bytes: &[u8]) -> Option<usize> {
    if !bytes.starts_with(b"#usda") {
        return None;
    }
    let (mut depth, mut deepest) = (0usize, 0usize);
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'#' => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            q @ (b'"' | b'\'') => {
                let triple = bytes[i..].starts_with(&[q, q, q]);
                i += if triple { 3 } else { 1 };
                while i < bytes.len() {
                    if bytes[i] == b'\\' {
                        i += 2;
                        continue;
                    }
                    if bytes[i] == q && (!triple || bytes[i..].starts_with(&[q, q, q])) {
                        i += if triple { 2 } else { 0 };
                        break;
                    }
                    i += 1;
                }
            }
            b'{' | b'(' | b'[' => {
                depth += 1;
                deepest = deepest.max(depth);
            }
            b'}' | b')' | b']' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
    Some(deepest)
}

/// Deepest nesting of point instancers (a prototype that instances itself is refused).
pub(super) const MAX_INSTANCER_DEPTH: usize = 16;

/// Most prims one file may expand to, counting every instance.
const MAX_PRIM_VISITS: usize = 20_000_000;

/// Loads a USD file (render and `info`). Its sublayers, references and payloads follow the
/// one path rule for external files (README): they must resolve inside `options.root`, the
/// file's own folder by default, unless `options.allow_outside`; the first one that does not
/// fails the load with one line naming its asset path.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    if options.allow_outside {
        return load_with(path, options, None);
    }
    let root = options
        .root
        .clone()
        .unwrap_or_else(|| super::paths::folder_of(path));
    let (result, refused) = load_confined(path, options, &root);
    match refused.first() {
        Some(asset) => Err(Error::in_file(
            path,
            format!(
                "'{asset}' leads out of the folder {}: not read (--root DIR widens it, \
                 --allow-outside lifts it)",
                root.display()
            ),
        )),
        None => result,
    }
}

/// Loads a USD file whose layers, references and payloads may only come from inside the
/// folder `root` (after following symbolic links): any other asset path is refused, left
/// unresolved (a composition warning), and listed in the returned vector. Used by
/// `raycast check`.
pub fn load_confined(
    path: &Path,
    options: &LoadOptions,
    root: &Path,
) -> (Result<Scene>, Vec<String>) {
    let refused = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let confine = root.canonicalize().ok().map(|root| confine::Confined {
        inner: openusd::ar::DefaultResolver::new(),
        root,
        refused: refused.clone(),
    });
    let result = match confine {
        Some(confine) => load_with(path, options, Some(confine)),
        None => Err(Error::in_file(root, "cannot resolve the asset's folder")),
    };
    let refused = refused.lock().map(|r| r.clone()).unwrap_or_default();
    (result, refused)
}

fn load_with(
    path: &Path,
    options: &LoadOptions,
    confine: Option<confine::Confined>,
) -> Result<Scene> {
    std::fs::metadata(path).map_err(|e| super::read_error(path, e))?;
    let is_text = {
        use std::io::Read;
        let mut head = [0u8; 5];
        std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut head))
            .is_ok()
            && &head == b"#usda"
    };
    if let Some(depth) = is_text
        .then(|| std::fs::read(path).ok())
        .flatten()
        .and_then(|bytes| text_nesting(&bytes))
        .filter(|&d| d > MAX_TEXT_NESTING)
    {
        return Err(Error::in_file(
            path,
            format!("the layer nests {depth} levels deep (more than {MAX_TEXT_NESTING}): not read"),
        ));
    }
    let text = path
        .to_str()
        .ok_or_else(|| Error::in_file(path, "the file name is not valid UTF-8"))?;
    // openusd is young: a panic inside it on malformed input becomes an error here.
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        load_stage(path, text, options, confine)
    }));
    match outcome {
        Ok(result) => result,
        Err(panic) => {
            let what = crate::error::panic_message(&*panic);
            Err(Error::in_file(
                path,
                format!("the USD reader failed on this file: {what}"),
            ))
        }
    }
}

fn load_stage(
    path: &Path,
    text: &str,
    options: &LoadOptions,
    confine: Option<confine::Confined>,
) -> Result<Scene> {
    let fail = |e: Error| e.with_path(path);
    let refused = confine.as_ref().map(|c| c.refused.clone());
    let stage = match confine {
        None => Stage::open(text),
        Some(confine) => Stage::builder().resolver(confine).open(text),
    }
    .map_err(|e| {
        let ill_formed = e.chain().any(|c| c.is::<sdf::IllFormedPath>());
        open_error(path, &e, ill_formed)
    })?;
    let mut loader = Loader {
        at: value::At::new(options.time),
        variants: variants::Variants::new(options.variants.clone()),
        stage: stage.clone(),
        builder: SceneBuilder::new(),
        warnings: Vec::new(),
        notes: BTreeMap::new(),
        meshes: HashMap::new(),
        excluded: HashSet::new(),
        visits: 0,
        skels: skel::Skels::default(),
    };
    let roots = loader.roots(options.scene.as_deref()).map_err(fail)?;
    for (root, world) in roots {
        loader
            .walk(&root, world, None, None, &mut None, 0)
            .map_err(fail)?;
    }
    let mut builder = std::mem::take(&mut loader.builder);
    let variant_sets = std::mem::replace(&mut loader.variants, variants::Variants::new(Vec::new()))
        .finish()
        .map_err(fail)?;
    // A layer the confinement refused is reported as refused (`raycast check`'s
    // PATH_OUTSIDE_ASSET, or the render's error), not as unresolved too.
    let refused = refused
        .and_then(|r| r.lock().ok().map(|r| r.clone()))
        .unwrap_or_default();
    for warning in composition::warnings(&stage, &refused)
        .into_iter()
        .chain(read_warnings::warnings(&stage))
    {
        builder.warn(warning);
    }
    for warning in loader.warnings.drain(..) {
        builder.warn(warning);
    }
    for (what, prims) in &loader.notes {
        let shown: Vec<&str> = prims.iter().take(3).map(String::as_str).collect();
        let more = if prims.len() > 3 {
            format!(" and {} more", prims.len() - 3)
        } else {
            String::new()
        };
        builder.note(format!(
            "{} {what}: {}{more}",
            prims.len(),
            shown.join(", ")
        ));
    }
    if builder.object_count() == 0 {
        builder.warn(Diagnostic::note(
            Code::EmptyScene,
            "the stage holds no triangles or quadrics",
        ));
    }
    let (sampled, first) = time_sampled_attributes(&stage);
    if let Some(first) = first.filter(|_| options.time.is_none()) {
        builder.note(format!(
            "the stage has time samples ({sampled} attribute specs, such as {first}): drawn at \
             the default time code, as usd-core's Usd.TimeCode.Default() reads it; --time CODE \
             draws it at a time code"
        ));
    }
    let mut info = stage_info(&stage);
    if sampled > 0 || info.time_code_range.is_some() || options.time.is_some() {
        info.time_codes_per_second = Some(stage.time_codes_per_second());
    }
    info.time = options.time;
    info.time_sampled_attributes = sampled;
    info.variant_sets = variant_sets;
    info.skeletons = std::mem::take(&mut loader.skels).finish();
    builder.set_stage(info);
    Ok(builder.finish(path.to_path_buf()))
}

/// How many attribute specs of the stage's loaded layers author time samples, and the first
/// of them by path (one pass over the specs once the walk has loaded every layer it needs).
fn time_sampled_attributes(stage: &Stage) -> (usize, Option<String>) {
    let mut count = 0;
    let mut first: Option<sdf::Path> = None;
    for identifier in stage.layer_identifiers() {
        let Some(layer) = stage.layer(&identifier) else {
            continue;
        };
        let data = layer.data();
        for path in data.spec_paths() {
            if path.is_property_path() && data.has_field(&path, "timeSamples") {
                count += 1;
                if first.as_ref().is_none_or(|f| path.as_str() < f.as_str()) {
                    first = Some(path);
                }
            }
        }
    }
    (count, first.map(|p| p.to_string()))
}

/// The stage's `upAxis` and `metersPerUnit`, with USD's fallbacks (Y, 0.01) where they are
/// not authored or not readable.
fn stage_info(stage: &Stage) -> StageInfo {
    let up_axis = match stage.stage_metadata("upAxis") {
        Ok(Some(sdf::Value::Token(t))) => t.as_str().to_string(),
        Ok(Some(sdf::Value::String(s))) => s,
        _ => "Y".to_string(),
    };
    let meters_per_unit = match stage.stage_metadata("metersPerUnit") {
        Ok(Some(sdf::Value::Double(m))) => m,
        Ok(Some(sdf::Value::Float(m))) => f64::from(m),
        _ => 0.01,
    };
    let time_code_range = stage
        .has_authored_time_code_range()
        .then(|| [stage.start_time_code(), stage.end_time_code()]);
    StageInfo {
        up_axis,
        meters_per_unit,
        time_codes_per_second: None,
        time_code_range,
        time: None,
        time_sampled_attributes: 0,
        variant_sets: Vec::new(),
        skeletons: Vec::new(),
    }
}

/// What an instance of a point instancer collects while its prototype is walked.
pub(super) struct Instance {
    /// Object name of the instance: `instancer[i]`.
    name: String,
    /// Path of the prototype root being walked.
    root: String,
    /// Prim path of the instancer (the object's source).
    source: String,
    /// The instance's object, once something in it is drawn.
    object: Option<u32>,
}

/// A mesh prim's mesh in its own frame, shared by every instance that draws it.
#[derive(Clone)]
struct CachedMesh {
    mesh: Arc<Mesh>,
    /// Each triangle's face, for per-face material bindings.
    faces: Arc<Vec<u32>>,
    subdivided: bool,
}

/// Where a prim's parts go: one object for the prim, created when its first part is drawn, or
/// the object of the point instance being walked.
struct Target<'a> {
    name: &'a str,
    source: &'a str,
    instance: &'a mut Option<Instance>,
    object: Option<u32>,
}

impl Target<'_> {
    fn id(&mut self, builder: &mut SceneBuilder) -> u32 {
        match self.instance {
            Some(inst) => *inst
                .object
                .get_or_insert_with(|| builder.new_object(inst.name.clone(), inst.source.clone())),
            None => *self.object.get_or_insert_with(|| {
                builder.new_object(self.name.to_string(), self.source.to_string())
            }),
        }
    }
}

struct Loader {
    stage: Stage,
    builder: SceneBuilder,
    /// Warnings, in the order met.
    warnings: Vec<Diagnostic>,
    /// Aggregated notes: what happened -> prims it happened to.
    notes: BTreeMap<&'static str, Vec<String>>,
    /// Mesh data by the path it was read from (prototype paths for instance proxies).
    meshes: HashMap<String, Option<CachedMesh>>,
    /// Point-instancer prototypes that live under their instancer: never drawn in place.
    excluded: HashSet<String>,
    visits: usize,
    /// When values are read (`--time`).
    at: value::At,
    /// Variant sets met, and the `--variant` choices.
    variants: variants::Variants,
    /// Skeletons met under SkelRoots, posed at `at`.
    skels: skel::Skels,
}

/// `true` when the type carries a transform (UsdGeomXformable); the ops of untyped prims
/// and scopes are ignored, as usd-core does.
fn is_xformable(type_name: &str) -> bool {
    !matches!(
        type_name,
        "" | "Scope" | "GeomSubset" | "Material" | "Shader" | "NodeGraph"
    )
}

pub(super) fn err(prim: &Prim, e: impl std::fmt::Display) -> Error {
    Error::at(prim.path().to_string(), format!("{e:#}"))
}

impl Loader {
    fn note(&mut self, what: &'static str, prim: &Prim) {
        self.notes
            .entry(what)
            .or_default()
            .push(prim.path().to_string());
    }

    /// The prims to walk, with their parents' world transforms: every root prim, or the
    /// prim named by `--scene`.
    fn roots(&mut self, choice: Option<&str>) -> Result<Vec<(Prim, BoundedMat4)>> {
        if let Some(name) = self.stage.default_prim() {
            let path = format!("/{}", name.as_str());
            let exists = sdf::Path::new(&path)
                .ok()
                .map(|p| self.stage.prim(p))
                .is_some_and(|p| p.is_valid().unwrap_or(false));
            if !exists {
                self.warnings.push(Diagnostic::note(
                    Code::ImporterNote,
                    format!(
                        "defaultPrim '{}' does not exist: drawing the whole stage",
                        name.as_str()
                    ),
                ));
            }
        }
        match choice {
            None => {
                let names = self
                    .stage
                    .root_prims()
                    .map_err(|e| Error::msg(format!("cannot list the root prims: {e:#}")))?;
                let mut roots = Vec::new();
                for name in names {
                    let path = sdf::Path::new(&format!("/{}", name.as_str())).map_err(|e| {
                        Error::msg(format!("bad root prim name '{}': {e}", name.as_str()))
                    })?;
                    roots.push((self.stage.prim(path), BoundedMat4::exact(DMat4::IDENTITY)));
                }
                Ok(roots)
            }
            Some(choice) => {
                let path = if choice == "default" {
                    let name = self.stage.default_prim().ok_or_else(|| {
                        Error::msg("--scene default: the stage has no defaultPrim")
                    })?;
                    format!("/{}", name.as_str())
                } else {
                    choice.to_string()
                };
                let sdf_path = sdf::Path::new(&path)
                    .map_err(|e| Error::msg(format!("--scene '{path}' is not a prim path: {e}")))?;
                let prim = self.stage.prim(sdf_path);
                if !prim.is_valid().map_err(|e| err(&prim, e))? || !path.starts_with('/') {
                    return Err(Error::msg(format!("no prim '{path}' in the stage")));
                }
                // The chosen prim keeps its ancestors' transforms.
                let world = self.parent_world_of(&prim)?;
                Ok(vec![(prim, world)])
            }
        }
    }

    /// World transform of the parent of any prim: its ancestors' transforms composed from
    /// the root.
    fn parent_world_of(&mut self, prim: &Prim) -> Result<BoundedMat4> {
        let mut world = BoundedMat4::exact(DMat4::IDENTITY);
        let mut ancestors: Vec<Prim> = Vec::new();
        let mut p = prim.path().parent();
        while let Some(parent) = p {
            if parent.is_abs_root() {
                break;
            }
            p = parent.parent();
            ancestors.push(self.stage.prim(parent));
        }
        for ancestor in ancestors.iter().rev() {
            world = self.world_of(ancestor, world)?;
        }
        Ok(world)
    }

    /// World transform of any prim (a skeleton, wherever it is in namespace).
    fn world_of_prim(&mut self, prim: &Prim) -> Result<DMat4> {
        let parent = self.parent_world_of(prim)?;
        Ok(self.world_of(prim, parent)?.value)
    }

    /// World transform of `prim` given its parent's, with the bound of its composition.
    fn world_of(&mut self, prim: &Prim, parent: BoundedMat4) -> Result<BoundedMat4> {
        let type_name = prim.type_name().map_err(|e| err(prim, e))?;
        let type_name = type_name.as_deref().unwrap_or("");
        if !is_xformable(type_name) {
            return Ok(parent);
        }
        let local = xform::local_transform(prim, self.at, &mut self.warnings)?;
        let world = if local.resets {
            local.matrix
        } else {
            parent.then_bounded(&local.matrix)
        };
        if world.value.is_finite() {
            Ok(world)
        } else {
            Err(Error::at(
                prim.path().to_string(),
                "world transform is not finite",
            ))
        }
    }

    /// Name of the object drawn for `prim`: its path, or inside a point instance the
    /// instance name followed by the prim's path below the prototype root.
    fn object_name(prim: &Prim, instance: &Option<Instance>) -> String {
        let path = prim.path().to_string();
        match instance {
            None => path,
            Some(inst) => {
                let rest = path.strip_prefix(&inst.root).unwrap_or(&path);
                format!("{}{rest}", inst.name)
            }
        }
    }

    /// Walks `prim` and its descendants. `purpose` is the closest authored purpose above;
    /// `skel` the skinning binding inherited under a SkelRoot.
    fn walk(
        &mut self,
        prim: &Prim,
        parent_world: BoundedMat4,
        purpose: Option<Rc<str>>,
        skel: Option<Rc<skel::Binding>>,
        instance: &mut Option<Instance>,
        depth: usize,
    ) -> Result<()> {
        self.visits += 1;
        if self.visits > MAX_PRIM_VISITS {
            return Err(Error::msg(format!(
                "the stage expands to more than {MAX_PRIM_VISITS} prims (counting instances)"
            )));
        }
        let path = prim.path().to_string();
        let is_instance_root = instance.as_ref().is_some_and(|i| i.root == path);
        if !is_instance_root && self.excluded.contains(&path) {
            return Ok(());
        }
        match prim.specifier().map_err(|e| err(prim, e))? {
            Some(sdf::Specifier::Def) => {}
            // `over` without a `def` anywhere, and `class`, are not drawn (nor their subtree).
            _ => return Ok(()),
        }
        // A chosen variant changes what the prim composes: before anything else is read.
        self.variants.visit(&self.stage, prim)?;
        if !prim.is_active().map_err(|e| err(prim, e))? {
            self.note("inactive prims skipped", prim);
            return Ok(());
        }
        if value::token(prim, "visibility", self.at)?.as_deref() == Some("invisible") {
            self.note("invisible prims skipped", prim);
            return Ok(());
        }
        let purpose = match value::token(prim, "purpose", self.at)? {
            Some(p) => Some(Rc::from(p.as_str())),
            None => purpose,
        };
        let type_name = prim.type_name().map_err(|e| err(prim, e))?;
        let type_name = type_name.as_deref().unwrap_or("").to_string();
        let world = if is_instance_root {
            // A point-instance prototype keeps its own transform under the instance's.
            let local = xform::local_transform(prim, self.at, &mut self.warnings)?;
            parent_world.then_bounded(&local.matrix)
        } else {
            self.world_of(prim, parent_world)?
        };
        let skel = skel::Binding::below(skel.as_ref(), prim, &type_name)?;
        let skinnable = skel.is_some() && skel::is_skinnable(&type_name);
        let pose = match &skel {
            Some(binding) if skinnable => self.skin(prim, &type_name, binding)?,
            _ => None,
        };
        // A rigidly skinned prim moves with its children; skinned points move the mesh only.
        let (world, drawn_world, skinned) = match pose {
            None => (world, world, None),
            Some(skel::Pose::Rigid(moved)) => {
                let moved = BoundedMat4::exact(moved);
                (moved, moved, None)
            }
            Some(skel::Pose::Points { points, skel_world }) => {
                (world, BoundedMat4::exact(skel_world), Some(points))
            }
        };
        let hidden_purpose = matches!(purpose.as_deref(), Some("guide") | Some("proxy"));
        let draws =
            type_name == "Mesh" || shapes::is_shape(&type_name) || quadric::has_quadric(prim)?;
        if hidden_purpose && draws {
            self.note("guide or proxy prims skipped", prim);
        } else {
            self.draw(prim, &type_name, drawn_world, skinned, instance)?;
        }
        if type_name == "PointInstancer" {
            if hidden_purpose {
                self.note("guide or proxy prims skipped", prim);
            } else {
                self.point_instancer(prim, world, instance, depth)?;
            }
        }
        // Skinnable prims do not nest: nothing below one is skinned (as usd-core).
        let skel = skel.filter(|_| !skinnable);
        let children = prim.children().map_err(|e| err(prim, e))?;
        for child in children {
            self.walk(
                &child,
                world,
                purpose.clone(),
                skel.clone(),
                instance,
                depth,
            )?;
        }
        Ok(())
    }

    /// Draws what the prim itself defines: a mesh (with `skinned` points in place of its own
    /// when a skeleton poses it), a gprim, a quadric, a camera. Everything it draws is one
    /// object (inside a point instance, the instance's object).
    fn draw(
        &mut self,
        prim: &Prim,
        type_name: &str,
        world: BoundedMat4,
        skinned: Option<Vec<DVec3>>,
        instance: &mut Option<Instance>,
    ) -> Result<()> {
        let name = Self::object_name(prim, instance);
        let source = prim.path().to_string();
        let mut target = Target {
            name: &name,
            source: &source,
            instance,
            object: None,
        };
        if type_name == "Mesh" {
            if let Some(mut mesh) = self.mesh(prim)? {
                if mesh.subdivided {
                    self.note("subdivision meshes drawn as their control cage", prim);
                }
                if let Some(points) = skinned {
                    let Some(posed) = mesh.mesh.with_positions(points) else {
                        self.warnings.push(warning_at(
                            source.to_string(),
                            "a skinned point is not finite: skipped",
                        ));
                        return Ok(());
                    };
                    if posed.attributes().is_some_and(|a| !a.normals.is_empty()) {
                        self.warnings.push(warning_at(
                            source.to_string(),
                            "normals of a UsdSkel-skinned mesh are not posed: left out",
                        ));
                    }
                    mesh.mesh = Arc::new(posed.without_normals());
                }
                let runs = primvars::material_runs(prim, self.at, &mesh.faces, &mut self.builder);
                if !runs.is_empty() {
                    mesh.mesh = Arc::new(Mesh::clone(&mesh.mesh).with_materials(runs));
                }
                if mesh.mesh.places_finitely(&world.value) {
                    let id = target.id(&mut self.builder);
                    self.builder.place_composed_mesh(id, mesh.mesh, world);
                } else {
                    self.warnings.push(warning_at(
                        source.to_string(),
                        "its projective transform sends points to infinity: skipped",
                    ));
                }
            }
        } else if shapes::is_shape(type_name) {
            match shapes::parts(prim, type_name, self.at)? {
                Err(reason) => self.warnings.push(reason.to_warning(Code::ImporterNote)),
                Ok(parts) => {
                    for part in parts {
                        match part {
                            Part::Quadric { spec, frame, .. } => {
                                let quadric = Quadric::new(&spec, world.value * frame)
                                    .map(|q| q.with_composition(&world.then(&frame)))
                                    .map_err(|e| e.context(format!("{source} ({type_name})")))?;
                                let id = target.id(&mut self.builder);
                                let material = self.bound_material(prim);
                                self.builder.place_bound_quadric(id, quadric, material);
                            }
                            Part::Mesh { triangles, .. } => {
                                let id = target.id(&mut self.builder);
                                let material = self.bound_material(prim);
                                let runs = runs(&vec![material; triangles.len()]);
                                let mesh = Mesh::from_soup(&triangles).with_materials(runs);
                                self.builder.place_composed_mesh(id, Arc::new(mesh), world);
                            }
                        }
                    }
                }
            }
        } else if type_name == "Camera" {
            self.camera(prim, &name, world.value)?;
        }
        if quadric::has_quadric(prim)? {
            let quadric = quadric::read(prim, self.at)
                .and_then(|spec| Quadric::new(&spec, world.value))
                .map(|quadric| quadric.with_composition(&world))
                .map_err(|e| e.context(format!("{source}: raycast:quadric")))?;
            let id = target.id(&mut self.builder);
            self.builder.place_quadric(id, quadric);
        }
        Ok(())
    }

    /// The id of the material bound to `prim` (0: none).
    fn bound_material(&mut self, prim: &Prim) -> u32 {
        primvars::bound_material(prim).map_or(0, |m| self.builder.material(&m))
    }

    /// A mesh's local triangles, read once per prototype.
    fn mesh(&mut self, prim: &Prim) -> Result<Option<CachedMesh>> {
        let key = match prim.prim_in_prototype() {
            Ok(Some(proto)) => proto.path().to_string(),
            _ => prim.path().to_string(),
        };
        if let Some(cached) = self.meshes.get(&key) {
            return Ok(cached.clone());
        }
        let read = match mesh::read(prim, self.at)? {
            mesh::MeshRead::Skip(reason) => {
                self.warnings.push(reason);
                None
            }
            mesh::MeshRead::Triangles {
                mesh,
                faces,
                subdivided,
                degenerate_faces,
                warnings,
            } => {
                self.warnings.extend(warnings);
                if degenerate_faces > 0 {
                    self.warnings.push(warning_at(
                        prim.path().to_string(),
                        format!("{degenerate_faces} faces with fewer than 3 vertices skipped"),
                    ));
                }
                Some(CachedMesh {
                    mesh: Arc::new(mesh),
                    faces: Arc::new(faces),
                    subdivided,
                })
            }
        };
        self.meshes.insert(key, read.clone());
        Ok(read)
    }
}

/// The error of a stage that cannot be opened: `USD_INVALID_PATH` when the reader refused
/// a `<...>` literal that cannot be an `SdfPath` (`ill_formed`: openusd's
/// `sdf::IllFormedPath` in the error's chain), else no code of its own.
fn open_error(path: &Path, e: &impl std::fmt::Display, ill_formed: bool) -> Error {
    let error = Error::in_file(path, format!("cannot open the USD stage: {e:#}"));
    if ill_formed {
        error.with_code(Code::UsdInvalidPath)
    } else {
        error
    }
}

/// An importer's warning about the prim or attribute at `location`, of code `IMPORTER_NOTE`.
pub(super) fn warning_at(location: impl Into<String>, message: impl Into<String>) -> Diagnostic {
    Diagnostic::warning(Code::ImporterNote, location, message)
}

/// A warning at `location` because of `why`, a read that failed: of `why`'s code (a value
/// that cannot be decoded is `USD_UNREADABLE_VALUE`), else `IMPORTER_NOTE`.
pub(super) fn warning_because(
    location: impl Into<String>,
    why: &Error,
    message: impl Into<String>,
) -> Diagnostic {
    Diagnostic::warning(why.code.unwrap_or(Code::ImporterNote), location, message)
}
