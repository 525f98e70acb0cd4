//! Reports in the Khronos glTF-Validator's JSON schema (`--validator-json DIR`), one per
//! asset, so that dashboards built for the validator read ours: `uri`, `mimeType`,
//! `validatorVersion` and `issues` with `numErrors`, `numWarnings`, `numInfos`, `numHints`,
//! `messages` (`code`, `message`, `severity` 0 error / 1 warning / 2 info, `pointer`) and
//! `truncated`.

use super::{AssetReport, Severity};
use crate::Code;
use serde::Serialize;

/// One validator-format report.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ValidatorReport<'a> {
    /// The asset's path relative to the checked folder.
    pub uri: &'a str,
    /// The asset's media type.
    pub mime_type: &'static str,
    /// `raycast <version>`.
    pub validator_version: String,
    /// The findings.
    pub issues: Issues<'a>,
}

/// The validator's `issues` object.
#[derive(Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Issues<'a> {
    /// Errors (all of them, also those left out of `messages`).
    pub num_errors: usize,
    /// Warnings.
    pub num_warnings: usize,
    /// Infos.
    pub num_infos: usize,
    /// Hints (raycast has none).
    pub num_hints: usize,
    /// The findings listed.
    pub messages: Vec<Message<'a>>,
    /// Whether findings were left out (`--max-findings`, or more than 50 of one code).
    pub truncated: bool,
}

/// One of the validator's messages.
#[derive(Debug, Serialize)]
pub struct Message<'a> {
    /// The code.
    pub code: &'a str,
    /// The text.
    pub message: &'a str,
    /// 0 error, 1 warning, 2 info (3, hint, is not used).
    pub severity: u8,
    /// JSON pointer (glTF), prim path (USD) or `line N` (OBJ); absent for the whole file.
    #[serde(skip_serializing_if = "str::is_empty")]
    pub pointer: &'a str,
}

/// The media type the validator would give (glTF), or the registered one (OBJ, STL, USD).
fn mime_type(report: &AssetReport) -> &'static str {
    match report.format.as_str() {
        "gltf" => "model/gltf+json",
        "glb" => "model/gltf-binary",
        "obj" => "model/obj",
        "stl" => "model/stl",
        // PLY has no registered media type; this is the unregistered one tools give it.
        "ply" => "model/x-ply",
        _ if report.relpath.to_ascii_lowercase().ends_with(".usdz") => "model/vnd.usdz+zip",
        _ => "model/vnd.usda",
    }
}

/// The validator-format report of `report`.
pub fn report(report: &AssetReport) -> ValidatorReport<'_> {
    ValidatorReport {
        uri: &report.relpath,
        mime_type: mime_type(report),
        validator_version: format!("raycast {}", env!("CARGO_PKG_VERSION")),
        issues: Issues {
            num_errors: report.errors,
            num_warnings: report.warnings,
            num_infos: report.infos,
            num_hints: 0,
            messages: report
                .findings
                .iter()
                .map(|f| Message {
                    code: f.code.name(),
                    message: &f.message,
                    severity: match f.severity {
                        Severity::Error => 0,
                        Severity::Warning => 1,
                        Severity::Info => 2,
                    },
                    pointer: &f.location,
                })
                .collect(),
            truncated: report.omitted > 0
                || report.findings.iter().any(|f| f.code == Code::Truncated),
        },
    }
}

/// Where the report of `report` goes inside the output folder: its relative path plus
/// `.report.json` (the validator suite's naming), `..` and absolute parts dropped.
pub fn file_name(report: &AssetReport) -> std::path::PathBuf {
    let mut path = std::path::PathBuf::new();
    for part in report.relpath.split('/') {
        if !part.is_empty() && part != "." && part != ".." {
            path.push(part);
        }
    }
    let name = path
        .file_name()
        .map_or_else(|| "asset".into(), |n| n.to_string_lossy().into_owned());
    path.set_file_name(format!("{name}.report.json"));
    path
}
