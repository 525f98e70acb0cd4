//! Importers: turn a scene file into a [`Scene`](crate::scene::Scene).

pub mod gltf;
pub mod npy;
pub mod obj;
pub mod obj_text;
pub mod paths;
pub mod ply;
pub mod sniff;
pub mod stl;
pub mod usd;

use crate::error::{Error, ErrorKind, Result};
use crate::quadric::Quadric;
use crate::scene::{Mesh, Scene, SceneBuilder};
use glam::{DMat4, DVec3, DVec4};
use raycast_core::diagnostic::{Code, Diagnostic};
use std::path::Path;
use std::sync::Arc;

/// Choices that affect what is loaded.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// glTF scene to load, by index or name; `None` for the file's default scene.
    pub scene: Option<String>,
    /// The folder tree external files must stay in (`--root`); `None`: the asset's folder.
    pub root: Option<std::path::PathBuf>,
    /// Read external files wherever they are (`--allow-outside`).
    pub allow_outside: bool,
    /// `--time`: evaluate the glTF file's animations at this time, in seconds; read a USD
    /// stage's attributes at this time code. `None`: the glTF nodes' own transforms and
    /// default morph weights; USD's default time code.
    pub time: Option<f64>,
    /// The glTF animation to apply at `time`, by index or name (`--animation`); `None`: all.
    pub animation: Option<String>,
    /// The memory limit (`--max-memory`, bytes) that data a file does not hold (glTF
    /// accessors without a buffer view, which are zeros of any length) may take; `None`:
    /// the default limit ([`crate::sizes::default_memory_limit`]).
    pub max_memory: Option<u64>,
    /// USD variant selections (`--variant SET=NAME`), applied to every prim with that set.
    pub variants: Vec<usd::Choice>,
}

/// The file types the importers read, as messages list them.
pub const FILE_TYPES: &str = ".gltf, .glb, .obj, .ply, .stl, .usda, .usdc, .usd or .usdz";

/// The warning of every reader for a scene with nothing to draw.
pub const EMPTY_SCENE: &str = "the scene holds no triangles or quadrics";

/// The [`EMPTY_SCENE`] warning (code `EMPTY_SCENE`).
pub fn empty_scene() -> Diagnostic {
    Diagnostic::note(Code::EmptyScene, EMPTY_SCENE)
}

/// Loads a `.gltf`, `.glb`, `.obj`, `.ply`, `.stl`, `.usda`, `.usdc`, `.usd` or `.usdz` file,
/// choosing the importer by extension after checking that the content is that format.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    open(path, options)?.at(options.time)
}

/// A scene file opened once and posed at any number of times ([`Source::at`]): a glTF file is
/// read, parsed and decoded once; an OBJ, PLY or STL file, which has one pose, is read once; a USD stage is
/// read again at each time (the USD reader composes a stage at one time code).
pub enum Source {
    /// A glTF document with its buffers decoded.
    Gltf(Box<gltf::Prepared>),
    /// A scene with one pose whatever the time (OBJ, PLY, STL).
    Fixed(Box<Scene>),
    /// A USD stage, read again at each time.
    Usd {
        /// The stage's file.
        path: std::path::PathBuf,
        /// Its options (the time is replaced at each [`Source::at`]).
        options: LoadOptions,
    },
}

/// Opens `path` for [`Source::at`], checking that its content is the format its extension
/// says. A glTF file opened with `options.time` set has its animations' data loaded, so that
/// any time can be built from it.
pub fn open(path: &Path, options: &LoadOptions) -> Result<Source> {
    if path == Path::new("-") {
        return Err(Error::in_file(
            path,
            format!("standard input is not read: give the path of a scene file ({FILE_TYPES})"),
        ));
    }
    let extension = extension_of(path);
    sniff::check_content(path, &extension)?;
    match extension.as_str() {
        "gltf" | "glb" => Ok(Source::Gltf(Box::new(gltf::prepare_file(path, options)?))),
        "obj" => Ok(Source::Fixed(Box::new(obj::load(path)?))),
        "ply" => Ok(Source::Fixed(Box::new(ply::load(path)?))),
        "stl" => Ok(Source::Fixed(Box::new(stl::load(path)?))),
        "usda" | "usdc" | "usd" | "usdz" => Ok(Source::Usd {
            path: path.to_path_buf(),
            options: options.clone(),
        }),
        _ => Err(unsupported(path)),
    }
}

/// [`open`] of `bytes` in memory, as if they had been read from the file `name`: its
/// extension chooses the importer, it names the scene in messages, and its folder is where a
/// glTF's external files resolve (under the same rule as [`load`]'s). glTF, GLB, OBJ, PLY and
/// STL only: the USD reader reads files.
pub fn open_bytes(bytes: Vec<u8>, name: &Path, options: &LoadOptions) -> Result<Source> {
    let extension = extension_of(name);
    sniff::check_head(name, &bytes, &extension)?;
    match extension.as_str() {
        "gltf" | "glb" => Ok(Source::Gltf(Box::new(gltf::prepare(bytes, name, options)?))),
        "obj" => Ok(Source::Fixed(Box::new(obj::load_bytes(&bytes, name)?))),
        "ply" => Ok(Source::Fixed(Box::new(ply::load_bytes(&bytes, name)?))),
        "stl" => Ok(Source::Fixed(Box::new(stl::load_bytes(&bytes, name)?))),
        "usda" | "usdc" | "usd" | "usdz" => Err(Error::in_file(
            name,
            "USD scenes load from a file, not from bytes (the USD reader resolves layers by path)",
        )
        .as_usage()),
        _ => Err(unsupported(name)),
    }
}

/// Reads `path` whole and loads its bytes with `load_bytes` (the mesh formats read in
/// memory: PLY, STL).
fn load_whole(path: &Path, load_bytes: fn(&[u8], &Path) -> Result<Scene>) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| read_error(path, e))?;
    load_bytes(&bytes, path)
}

/// The scene of a mesh file (PLY, STL) or of arrays (the Python package's
/// `Scene.from_arrays` and `Scene.from_objects`): its reader's `warnings`, then one object
/// per `(name, mesh)`, placed as stored, then one per `(name, quadric)` (placed already), each
/// with source `<kind>:<name>`; an empty scene with the readers' [`EMPTY_SCENE`] warning when
/// there is none.
pub fn mesh_file_scene(
    path: &Path,
    kind: &str,
    warnings: Vec<String>,
    meshes: Vec<(String, Mesh)>,
    quadrics: Vec<(String, Quadric)>,
) -> Scene {
    let mut builder = SceneBuilder::new();
    for warning in warnings {
        builder.note(warning);
    }
    if meshes.is_empty() && quadrics.is_empty() {
        builder.warn(empty_scene());
    }
    for (name, mesh) in meshes {
        let id = builder.new_object(name.clone(), format!("{kind}:{name}"));
        builder.place_mesh(id, Arc::new(mesh), DMat4::IDENTITY);
    }
    for (name, quadric) in quadrics {
        builder.add_quadric(name.clone(), format!("{kind}:{name}"), quadric);
    }
    builder.finish(path.to_path_buf())
}

impl Source {
    /// The scene posed at `time` (glTF seconds, USD time code; `None`: the file's own pose),
    /// exactly as [`load`] with that time would give it.
    pub fn at(&self, time: Option<f64>) -> Result<Scene> {
        let mut scene = match self {
            Source::Gltf(prepared) => prepared.build(time)?,
            Source::Fixed(scene) => Scene::clone(scene),
            Source::Usd { path, options } => {
                let options = LoadOptions {
                    time,
                    ..options.clone()
                };
                usd::load(path, &options)?
            }
        };
        sort_warnings(&mut scene.warnings);
        Ok(scene)
    }

    /// Whether [`Source::at`] can pose any time: false for a glTF document opened without a
    /// time, whose animations' data were not read.
    pub fn animating(&self) -> bool {
        match self {
            Source::Gltf(prepared) => prepared.animating(),
            Source::Fixed(_) | Source::Usd { .. } => true,
        }
    }
}

/// Loads a scene from `bytes` in memory, as if they had been read from the file `name` (see
/// [`open_bytes`]).
pub fn load_bytes(bytes: Vec<u8>, name: &Path, options: &LoadOptions) -> Result<Scene> {
    open_bytes(bytes, name, options)?.at(options.time)
}

/// A path's extension in lower case (empty when it has none).
pub fn extension_of(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// A path's file name without its extension, naming the one object of a PLY or binary STL
/// file (`mesh` when the path has none).
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".to_string())
}

fn unsupported(path: &Path) -> Error {
    Error::in_file(
        path,
        format!("unsupported file type (expected {FILE_TYPES})"),
    )
}

/// The error for a scene file that cannot be read: [`ErrorKind::NotFound`] when it does not
/// exist.
pub(crate) fn read_error(path: &Path, e: std::io::Error) -> Error {
    let error = Error::in_file(path, format!("cannot read: {e}"));
    match e.kind() {
        std::io::ErrorKind::NotFound => error.with_kind(ErrorKind::NotFound),
        _ => error,
    }
}

/// Sorts warnings and drops repeats, so that every run lists them the same way whatever
/// order a reader produced them in.
pub fn sort_warnings(warnings: &mut Vec<Diagnostic>) {
    let mut lines: Vec<(String, Diagnostic)> =
        warnings.drain(..).map(|d| (d.to_string(), d)).collect();
    lines.sort_by(|a, b| a.0.cmp(&b.0));
    lines.dedup_by(|a, b| a.0 == b.0);
    warnings.extend(lines.into_iter().map(|(_, d)| d));
}

/// Local triangles placed in the world by `world`. A mirroring transform flips the winding back
/// so that counter-clockwise stays the front face (glTF's rule for negative determinants, and
/// USD's); a projective matrix (USD `matrix4d` ops may have one; usd-core applies it with the
/// homogeneous divide) maps triangles to triangles, so points are divided by `w`.
pub(crate) fn place(local: &[[DVec3; 3]], world: &DMat4) -> Vec<[DVec3; 3]> {
    let flip = world.determinant() < 0.0;
    let projective = world.row(3) != DVec4::W;
    local
        .iter()
        .map(|tri| {
            let [a, b, c] = tri.map(|p| {
                if projective {
                    world.project_point3(p)
                } else {
                    world.transform_point3(p)
                }
            });
            if flip {
                [a, c, b]
            } else {
                [a, b, c]
            }
        })
        .collect()
}
