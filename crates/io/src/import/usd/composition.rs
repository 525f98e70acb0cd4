//! What the USD reader could not compose, as warnings: problems with arcs (cycles, layers
//! that could not be read), and one note for all the layers of formats it has no reader for
//! (MaterialX `.mtlx` materials, for instance), which a ray caster does not need.

use openusd::pcp;
use openusd::usd::Stage;
use raycast_core::diagnostic::{Code, Diagnostic};
use std::collections::BTreeSet;

/// What the USD reader says of a referenced layer whose format it cannot read.
pub const UNREAD_LAYER: &str = "no file format registered";

/// The words of the one note for all such layers (`raycast check` maps it to
/// `USD_UNSUPPORTED_LAYER`).
pub const UNREAD_NOTE: &str = "of a format raycast does not read";

/// A referenced layer of a format the reader has no reader for.
struct Unread {
    asset: String,
    site: String,
}

/// The composition warnings of `stage`, each one line (`composition: ...`): every problem in
/// its own line, and the layers of unknown formats counted in one. Each has its code: a
/// composition cycle `USD_COMPOSITION_CYCLE`, a layer or prim that cannot be found
/// `MISSING_REFERENCE`, the layers of unknown formats `USD_UNSUPPORTED_LAYER`, anything else
/// `USD_COMPOSITION_ERROR`.
pub fn warnings(stage: &Stage, refused: &[String]) -> Vec<Diagnostic> {
    let mut unread = Vec::new();
    let mut lines = Vec::new();
    for error in stage.composition_errors() {
        if asset_of(&error).is_some_and(|asset| refused.iter().any(|r| asset.contains(r.as_str())))
        {
            continue;
        }
        match &error {
            pcp::Error::MalformedLayer {
                asset_path,
                site_path,
                reason,
                ..
            } if reason.contains(UNREAD_LAYER) => unread.push(Unread {
                asset: asset_path.clone(),
                site: site_path.to_string(),
            }),
            _ => lines.push(composition(
                code_of(&error),
                site_of(&error),
                format!("{error}"),
            )),
        }
    }
    let note = unread_note(unread);
    lines.extend(note.map(|(site, line)| composition(Code::UsdUnsupportedLayer, site, line)));
    lines
}

/// The asset path of a layer the problem is about, if it is about one.
fn asset_of(error: &pcp::Error) -> Option<&str> {
    use pcp::Error::*;
    match error {
        UnresolvedLayer { asset_path, .. }
        | MalformedLayer { asset_path, .. }
        | MutedAssetPath { asset_path, .. }
        | UnresolvedSublayer { asset_path, .. }
        | MalformedSublayer { asset_path, .. } => Some(asset_path),
        _ => None,
    }
}

/// The prim the problem's arc is authored on, where the error names one; empty otherwise.
fn site_of(error: &pcp::Error) -> String {
    use pcp::Error::*;
    match error {
        ArcCycle(chain) => chain.composing.to_string(),
        UnresolvedLayer { site_path, .. }
        | MalformedLayer { site_path, .. }
        | MutedAssetPath { site_path, .. }
        | InvalidPrimPath { site_path, .. }
        | UnresolvedPrimPath { site_path, .. }
        | MissingDefaultPrim { site_path, .. }
        | InvalidDefaultPrim { site_path, .. }
        | InvalidExpression { site_path, .. } => site_path.to_string(),
        ProhibitedRelocationSource { site, .. } => site.to_string(),
        _ => String::new(),
    }
}

/// The code of a composition problem.
fn code_of(error: &pcp::Error) -> Code {
    match error {
        pcp::Error::ArcCycle(_) | pcp::Error::SublayerCycle { .. } => Code::UsdCompositionCycle,
        pcp::Error::UnresolvedLayer { .. }
        | pcp::Error::UnresolvedPrimPath { .. }
        | pcp::Error::UnresolvedSublayer { .. } => Code::MissingReference,
        // A sublayer of a format the reader has no reader for (the reader says so in its
        // reason, as for the referenced layers above).
        pcp::Error::MalformedSublayer { reason, .. } if reason.contains(UNREAD_LAYER) => {
            Code::UsdUnsupportedLayer
        }
        _ => Code::UsdCompositionError,
    }
}

/// A composition warning at the prim `site`: the line reads `composition: {message}`.
fn composition(code: Code, site: String, message: String) -> Diagnostic {
    Diagnostic {
        heading: Some("composition"),
        ..Diagnostic::warning(code, site, message)
    }
}

/// One line for the layers of unknown formats, naming their kinds and the first of them, with
/// the prim that first one is referenced on.
fn unread_note(mut unread: Vec<Unread>) -> Option<(String, String)> {
    unread.sort_by(|a, b| (&a.asset, &a.site).cmp(&(&b.asset, &b.site)));
    let first = unread.first()?;
    let kinds: BTreeSet<String> = unread.iter().map(|u| kind_of(&u.asset)).collect();
    let kinds: Vec<String> = kinds.into_iter().collect();
    let count = unread.len();
    let references = if count == 1 {
        "reference"
    } else {
        "references"
    };
    let line = format!(
        "{count} {references} to layers {UNREAD_NOTE} ({}) skipped: materials \
         and the like, not needed for ray casting; first: @{}@ at {}",
        kinds.join(", "),
        first.asset,
        first.site
    );
    Some((first.site.clone(), line))
}

/// The kind of layer an asset path names: `MaterialX .mtlx` for MaterialX, else its
/// extension.
fn kind_of(asset: &str) -> String {
    let extension = std::path::Path::new(asset)
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match extension.as_str() {
        "mtlx" => "MaterialX .mtlx".into(),
        "" => "no extension".into(),
        other => format!(".{other}"),
    }
}
