//! Which files of an output folder a render may replace or remove. A folder's `raycast.json`
//! says which scene file its outputs were made from (`scene_file`, the canonical path) and
//! which files they are (`files`). A render of the same scene file owns those files: it may
//! replace them, and removes those it does not write again. A render of another scene owns
//! nothing there and is refused before any work, and so is a render that would replace a file
//! no run of its scene listed: nothing another run (or a person) wrote is ever lost.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// The sidecar's name.
pub const SIDECAR: &str = "raycast.json";

/// The files of an output folder that a render of one scene owns.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Claim {
    /// Files an earlier run of the same scene listed (output names only).
    pub listed: Vec<String>,
}

/// How a sidecar names the scene file it was made from: its canonical path (absolute, links
/// resolved), or the path as given when it cannot be resolved.
pub fn scene_key(scene: &Path) -> String {
    scene
        .canonicalize()
        .unwrap_or_else(|_| scene.to_path_buf())
        .display()
        .to_string()
}

/// What the folder's sidecar says, if it has one: the scene key of its run, the scene as that
/// run named it, and the files it listed.
struct Earlier {
    key: String,
    named: String,
    files: Vec<String>,
}

/// Reads `dir/raycast.json`; `Ok(None)` when there is none. A sidecar of an older raycast has
/// no `scene_file`: its `scene` is resolved as that run would have (from the current folder).
fn earlier(dir: &Path) -> Result<Option<Earlier>> {
    let path = dir.join(SIDECAR);
    let text = match std::fs::read(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::in_file(&path, format!("cannot read: {e}"))),
    };
    let json: serde_json::Value = serde_json::from_slice(&text).map_err(|_| {
        refusal(
            dir,
            "has a raycast.json that is not a raycast sidecar".to_string(),
        )
    })?;
    let named = json["scene"].as_str().unwrap_or_default().to_string();
    let key = match json["scene_file"].as_str() {
        Some(key) => key.to_string(),
        None => scene_key(&PathBuf::from(&named)),
    };
    let files = json["files"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|f| f.as_str())
        .filter(|f| super::is_output_name(f))
        .map(str::to_string)
        .collect();
    Ok(Some(Earlier { key, named, files }))
}

/// The usage error that refuses an output folder.
fn refusal(dir: &Path, why: String) -> Error {
    Error::in_file(
        dir,
        format!("{why}; choose another --out folder (nothing was written)"),
    )
    .as_usage()
}

/// Claims `dir` for a render of `scene` that will write the files `names` (`raycast.json`
/// among them or not). Refuses when the folder holds another scene's outputs, or when one of
/// `names` exists there and no earlier run of this scene listed it.
pub fn claim(dir: &Path, scene: &Path, names: &[String]) -> Result<Claim> {
    // The sidecar itself exists only when `earlier` found one, and then it is this scene's.
    let listed = match earlier(dir)? {
        Some(e) if e.key != scene_key(scene) => {
            return Err(refusal(
                dir,
                format!("holds the outputs of another scene ({})", e.named),
            ))
        }
        Some(e) => e.files,
        None => Vec::new(),
    };
    let owned = |name: &str| name == SIDECAR || listed.iter().any(|l| l == name);
    if let Some(name) = names
        .iter()
        .find(|name| !owned(name) && dir.join(name).exists())
    {
        return Err(refusal(
            dir,
            format!("already has {name}, which no earlier run of this scene wrote"),
        ));
    }
    Ok(Claim { listed })
}

/// Refuses a render that would write one of `names` over one of its `inputs` (the scene, the
/// ray file): an output never replaces an input.
pub fn refuse_inputs(dir: &Path, names: &[String], inputs: &[&Path]) -> Result<()> {
    let inputs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|p| p.canonicalize().ok())
        .collect();
    for name in names {
        let target = dir.join(name);
        if target.canonicalize().is_ok_and(|t| inputs.contains(&t)) {
            return Err(Error::in_file(
                &target,
                "is an input of this run; choose another --out folder",
            )
            .as_usage());
        }
    }
    Ok(())
}
