//! The one path rule for external files (glTF buffers and images, OBJ material libraries),
//! shared by render, `info` and `check`: a relative URI resolves from the asset's folder and
//! must stay inside a root folder tree — by default the asset's own folder, widened with
//! `--root DIR`, lifted with `--allow-outside`.

use crate::error::{Error, Result};
use std::path::{Component, Path, PathBuf};

/// Where external files may come from.
#[derive(Debug, Clone)]
pub struct Confinement {
    /// The folder tree files must stay in; `None` for the asset's own folder.
    pub root: Option<PathBuf>,
    /// Lift the rule: any path is read.
    pub allow_outside: bool,
}

/// Where an external file named by an asset resolves, or why it is refused: `uri` is a
/// relative path (already percent-decoded) from the asset's folder `base`, and must stay
/// inside the folder tree `root`. Absolute paths, `..` escapes and symbolic links leading out
/// of the tree are refused unless `allow_outside`; nothing is read here. The refusal names
/// the URI.
pub fn resolve_inside(base: &Path, root: &Path, uri: &str, allow_outside: bool) -> Result<PathBuf> {
    let relative = Path::new(uri);
    let windows_drive = uri.len() >= 2 && uri.as_bytes()[1] == b':';
    if relative.is_absolute() || uri.starts_with('\\') || windows_drive {
        if allow_outside {
            return Ok(relative.to_path_buf());
        }
        return Err(Error::msg(format!(
            "'{uri}' is an absolute path: not read (--allow-outside reads it)"
        )));
    }
    let full = base.join(relative);
    if allow_outside {
        return Ok(full);
    }
    let lexical = |p: &Path| -> Option<PathBuf> {
        let absolute = std::path::absolute(p).ok()?;
        let mut out = PathBuf::new();
        for component in absolute.components() {
            match component {
                Component::ParentDir => {
                    if !out.pop() {
                        return None;
                    }
                }
                Component::CurDir => {}
                other => out.push(other),
            }
        }
        Some(out)
    };
    match (lexical(&full), lexical(root)) {
        (Some(f), Some(r)) if f.starts_with(&r) => {}
        _ => {
            return Err(Error::msg(format!(
                "'{uri}' leads out of the folder {}: not read (--root DIR widens it, --allow-outside lifts it)",
                root.display()
            )))
        }
    }
    if let (Ok(real), Ok(root_real)) = (full.canonicalize(), root.canonicalize()) {
        if !real.starts_with(&root_real) {
            return Err(Error::msg(format!(
                "'{uri}' leads out of the folder {} through a symbolic link: not read",
                root.display()
            )));
        }
    }
    Ok(full)
}

/// The folder an asset's files are read from: its parent, or `.` for a bare file name.
pub fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_stay_inside() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
        let base = &fixtures.join("gltf");
        assert!(resolve_inside(base, base, "cube.bin", false).is_ok());
        assert!(resolve_inside(base, base, "../gltf/cube.bin", false).is_ok());
        assert!(resolve_inside(base, base, "../../Cargo.toml", false).is_err());
        assert!(resolve_inside(base, base, "/etc/passwd", false).is_err());
        assert!(resolve_inside(base, base, "a/../../x", false).is_err());
        assert!(resolve_inside(base, base, "/etc/passwd", true).is_ok());
        // A wider tree lets a file reach its siblings.
        let root = &fixtures;
        assert!(resolve_inside(base, root, "../obj/x.obj", false).is_ok());
        assert!(resolve_inside(base, root, "../../Cargo.toml", false).is_err());
        let refused = resolve_inside(base, base, "../../elsewhere/x.bin", false);
        assert!(refused.is_err_and(|e| e.message.contains("../../elsewhere/x.bin")));
    }
}
