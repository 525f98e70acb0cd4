//! PLY and STL: the importers' typed errors become findings with their codes (PLY_…, STL_…,
//! `INDEX_OOB`, `NON_FINITE_POSITION`), and the scene they read goes on to the geometric
//! checks. Both readers stop at the first problem: a PLY or STL body has no lines to report
//! one by one, and what follows a bad value cannot be found again.

use super::Findings;
use crate::import::{ply, stl};
use crate::scene::Scene;
use crate::Code;
use std::path::Path;

/// Reads the PLY (`format` "ply") or STL ("stl") file `path`; the scene, or `None` with the
/// reason among `findings`.
pub fn check(path: &Path, format: &str, findings: &mut Findings) -> Option<Scene> {
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) => {
            findings.error(Code::IoError, "", format!("cannot read: {e}"));
            return None;
        }
    };
    let read = match format {
        "ply" => ply::read(&bytes)
            .map(|mesh| ply::scene(mesh, path))
            .map_err(|e| (e.code(), e.to_string())),
        _ => stl::read(&bytes)
            .map(|mesh| stl::scene(mesh, path))
            .map_err(|e| (e.code(), e.to_string())),
    };
    match read {
        Ok(scene) => Some(scene),
        Err((code, message)) => {
            findings.error(code, "", message);
            None
        }
    }
}
