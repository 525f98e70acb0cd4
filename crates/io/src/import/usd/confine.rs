//! An asset resolver that keeps a USD stage inside one folder tree: every layer, reference
//! and payload must resolve to a file under the root (after following symbolic links);
//! anything else is refused and recorded, never opened.

use openusd::ar::{self, Asset, ResolvedPath, Resolver};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

pub(crate) struct Confined {
    pub(crate) inner: ar::DefaultResolver,
    /// Canonical root folder.
    pub(crate) root: PathBuf,
    /// Asset paths refused so far.
    pub(crate) refused: Arc<Mutex<Vec<String>>>,
}

impl Confined {
    /// The file a resolved path reads: the package for `pkg.usdz[inner]`.
    fn file_of(resolved: &str) -> &str {
        match resolved.find('[') {
            Some(i) if resolved.ends_with(']') => &resolved[..i],
            _ => resolved,
        }
    }

    fn inside(&self, resolved: &str) -> bool {
        Path::new(Self::file_of(resolved))
            .canonicalize()
            .is_ok_and(|p| p.starts_with(&self.root))
    }

    fn refuse(&self, what: &str) {
        if let Ok(mut refused) = self.refused.lock() {
            if !refused.iter().any(|r| r == what) {
                refused.push(what.to_string());
            }
        }
    }
}

impl Resolver for Confined {
    fn create_identifier(&self, asset_path: &str, anchor: Option<&ResolvedPath>) -> String {
        self.inner.create_identifier(asset_path, anchor)
    }

    fn resolve(&self, asset_path: &str) -> Option<ResolvedPath> {
        let resolved = self.inner.resolve(asset_path)?;
        if self.inside(&resolved.to_string_lossy()) {
            Some(resolved)
        } else {
            self.refuse(asset_path);
            None
        }
    }

    fn resolve_for_new_asset(&self, _asset_path: &str) -> Option<ResolvedPath> {
        None
    }

    fn open_asset(&self, resolved_path: &ResolvedPath) -> io::Result<Box<dyn Asset>> {
        let text = resolved_path.to_string_lossy();
        if !self.inside(&text) {
            self.refuse(&text);
            return Err(io::Error::new(
                io::ErrorKind::PermissionDenied,
                format!("{text} lies outside the asset's folder"),
            ));
        }
        let mut asset = self.inner.open_asset(resolved_path)?;
        // Referenced text layers get the same nesting limit as the root layer.
        let bytes = asset.read_all()?;
        if super::text_nesting(&bytes).is_some_and(|d| d > super::MAX_TEXT_NESTING) {
            self.refuse(&text);
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "{text} nests deeper than {} levels",
                    super::MAX_TEXT_NESTING
                ),
            ));
        }
        Ok(Box::new(io::Cursor::new(bytes)))
    }

    fn identity(&self) -> String {
        format!("confined:{:?}:{}", self.root, self.inner.identity())
    }
}
