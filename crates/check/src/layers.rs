//! `--root-layers-only`: a USD kit is a tree of files (assemblies reference components, which
//! reference geometry and material layers); checking each file as a scene of its own reports
//! material layers as empty scenes. This finds the layers that other checked layers bring in
//! (as a sublayer, reference or payload) so that only the roots are checked.
//!
//! Only text layers (`#usda`, whatever the extension) are read for their arcs, each on its
//! own, without composing a stage (cheap, and every shard of a run computes the same set).
//! Binary (crate) layers and `.usdz` packages are treated as referring to nothing: the
//! layers they bring in are then checked as roots too (more checking, never less).

use super::Asset;
use openusd::sdf::{self, AbstractData, Value};
use std::collections::{HashMap, HashSet, VecDeque};
use std::path::{Path, PathBuf};

/// The assets left when the USD layers that another checked layer reaches are dropped.
/// A layer reached only through a cycle of layers that nothing else reaches is kept.
pub fn root_layers(assets: Vec<Asset>, max_bytes: u64) -> Vec<Asset> {
    let index: HashMap<PathBuf, usize> = assets
        .iter()
        .enumerate()
        .filter_map(|(i, a)| Some((a.path.canonicalize().ok()?, i)))
        .collect();
    let arcs: Vec<Vec<usize>> = assets
        .iter()
        .map(|a| {
            layer_arcs(&a.path, max_bytes)
                .iter()
                .filter_map(|target| index.get(target).copied())
                .collect()
        })
        .collect();
    let mut referenced = vec![false; assets.len()];
    for targets in &arcs {
        for &t in targets {
            referenced[t] = true;
        }
    }
    // Everything reachable from a layer that nothing references is dropped.
    let mut reached = vec![false; assets.len()];
    let mut queue: VecDeque<usize> = (0..assets.len()).filter(|&i| !referenced[i]).collect();
    while let Some(i) = queue.pop_front() {
        for &t in &arcs[i] {
            if t != i && !reached[t] {
                reached[t] = true;
                queue.push_back(t);
            }
        }
    }
    assets
        .into_iter()
        .zip(reached)
        .filter(|(_, reached)| !reached)
        .map(|(a, _)| a)
        .collect()
}

/// The files a USD text layer names as sublayers, references or payloads, resolved against
/// the layer's folder and canonicalized (those that exist). Empty for anything else, or a
/// layer that cannot be read or parsed (checking it will say why).
fn layer_arcs(path: &Path, max_bytes: u64) -> Vec<PathBuf> {
    if super::format_of(path) != Some("usd") {
        return Vec::new();
    }
    let Ok(meta) = std::fs::metadata(path) else {
        return Vec::new();
    };
    if meta.len() > max_bytes {
        return Vec::new();
    }
    let Ok(bytes) = std::fs::read(path) else {
        return Vec::new();
    };
    // The parser recurses: refuse what the importer refuses (see `import::usd`).
    match crate::import::usd::text_nesting(&bytes) {
        Some(depth) if depth <= crate::import::usd::MAX_TEXT_NESTING => {}
        _ => return Vec::new(),
    }
    let Ok(text) = std::str::from_utf8(&bytes) else {
        return Vec::new();
    };
    let parsed = std::panic::catch_unwind(|| openusd::usda::parse(text).ok());
    let Ok(Some(data)) = parsed else {
        return Vec::new();
    };
    let folder = path.parent().unwrap_or(Path::new("."));
    asset_paths(&data)
        .into_iter()
        .filter(|p| !p.is_empty() && !p.contains("://"))
        .filter_map(|p| folder.join(p).canonicalize().ok())
        .collect::<HashSet<_>>()
        .into_iter()
        .collect()
}

/// Every asset path of the layer's sublayers, references and payloads (variants included).
fn asset_paths(data: &sdf::Data) -> Vec<String> {
    let mut out = Vec::new();
    for spec in data.spec_paths() {
        for field in ["references", "payload", "subLayers"] {
            let Ok(Some(value)) = data.try_field(&spec, field) else {
                continue;
            };
            match value.as_ref() {
                Value::ReferenceListOp(op) => {
                    out.extend(op.iter().map(|r| r.asset_path.clone()));
                }
                Value::PayloadListOp(op) => {
                    out.extend(op.iter().map(|p| p.asset_path.clone()));
                }
                Value::Payload(p) => out.push(p.asset_path.clone()),
                Value::StringVec(layers) => out.extend(layers.iter().cloned()),
                _ => {}
            }
        }
    }
    out
}
