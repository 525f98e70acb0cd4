//! Importers: turn a scene file into a [`Scene`](crate::scene::Scene).

pub mod gltf;
pub mod obj;
pub mod usd;

use crate::error::{Error, Result};
use crate::scene::Scene;
use std::path::Path;

/// Choices that affect what is loaded.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// glTF scene to load, by index or name; `None` for the file's default scene.
    pub scene: Option<String>,
}

/// Loads a `.gltf`, `.glb` or `.obj` file, choosing the importer by extension.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("gltf") | Some("glb") => gltf::load(path, options),
        Some("obj") => obj::load(path),
        Some("usda") | Some("usdc") | Some("usd") | Some("usdz") => usd::load(path, options),
        _ => Err(Error::in_file(
            path,
            "unsupported file type (expected .gltf, .glb, .obj, .usda, .usdc, .usd or .usdz)",
        )),
    }
}
