//! USD: size and package checks before anything is parsed, then the importer with a
//! resolver confined to the asset's folder; composition problems become findings with the
//! prim path as location.

use super::{CheckOptions, Finding, Findings, SceneStats};
use crate::error::{Error, Result};
use crate::import::usd::child::{last_words, run_child, stopped_how};
use crate::import::{self, LoadOptions};
use crate::scene::Scene;
use crate::{Code, Diagnostic, Severity};
use std::path::Path;

/// Checks that can refuse a file before the USD reader sees it: `.usdz` packages must store
/// their files uncompressed (as the USDZ rules say), so a package cannot expand beyond its
/// size (no zip bombs). Returns whether the importer may run.
pub fn precheck(path: &Path, _options: &CheckOptions, f: &mut Findings) -> bool {
    let is_usdz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("usdz"));
    if !is_usdz {
        return true;
    }
    let bytes = match std::fs::read(path) {
        Ok(bytes) => bytes,
        Err(e) => {
            f.error(Code::IoError, "", format!("cannot read: {e}"));
            return false;
        }
    };
    match usdz_problem(&bytes) {
        None => true,
        Some(problem) => {
            f.error(Code::UsdzInvalidPackage, "", problem);
            false
        }
    }
}

/// Why a `.usdz` package is refused, if it is: not a zip, a compressed entry, an entry
/// that runs past the end, or sizes deferred to a data descriptor.
pub fn usdz_problem(bytes: &[u8]) -> Option<String> {
    let u16_at = |at: usize| {
        bytes
            .get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]) as usize)
    };
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let mut at = 0usize;
    let mut entries = 0;
    while u32_at(at) == Some(0x0403_4b50) {
        let (Some(flags), Some(method), Some(size), Some(name), Some(extra)) = (
            u16_at(at + 6),
            u16_at(at + 8),
            u32_at(at + 18),
            u16_at(at + 26),
            u16_at(at + 28),
        ) else {
            return Some("a zip entry header is cut short".into());
        };
        if method != 0 {
            return Some(format!(
                "entry {entries} is compressed (method {method}); USDZ packages store files uncompressed"
            ));
        }
        if flags & 0x8 != 0 {
            return Some(format!(
                "entry {entries} defers its size to a data descriptor"
            ));
        }
        let next = at
            .checked_add(30 + name + extra)
            .and_then(|x| x.checked_add(size));
        match next {
            Some(next) if next <= bytes.len() => at = next,
            _ => return Some(format!("entry {entries} runs past the end of the package")),
        }
        entries += 1;
    }
    if entries == 0 {
        return Some("not a zip package".into());
    }
    None
}

/// Loads the stage with references confined to the asset's folder (unless
/// `--allow-outside`); refused paths become `PATH_OUTSIDE_ASSET` errors.
pub fn load(path: &Path, root: &Path, options: &CheckOptions, f: &mut Findings) -> Result<Scene> {
    let load = LoadOptions {
        allow_outside: true,
        time: options.time(),
        ..LoadOptions::default()
    };
    if options.allow_outside {
        return import::usd::load(path, &load);
    }
    // A refused layer is reported once, as PATH_OUTSIDE_ASSET: the importer leaves it out of
    // the unresolved ones.
    let (result, refused) = import::usd::load_confined(path, &load, root);
    for asset in refused {
        f.error(
            Code::PathOutsideAsset,
            "",
            format!("'{asset}' resolves outside the asset's folder: not read (--allow-outside reads it)"),
        );
    }
    result
}

/// The code of a USD file the importer refuses: `USD_INVALID_PATH` for a path that cannot be
/// an `SdfPath` (an ill-formed `<...>` literal, an `xformOpOrder` entry that is no attribute
/// name; such paths once sent the reader's ancestor walks round without end: the importer's
/// error carries the code), else `LOAD_FAILED`.
pub fn load_failure_code(error: &Error) -> Code {
    match error.code {
        Some(Code::UsdInvalidPath) => Code::UsdInvalidPath,
        _ => Code::LoadFailed,
    }
}

/// Maps one composition problem reported by the USD reader (the importer gave it its code and
/// its location, the prim the arc is authored on) to a finding: a layer that cannot be found
/// (`MISSING_REFERENCE`) and a composition cycle (`USD_COMPOSITION_CYCLE`) are errors, layers
/// of a format the reader does not know (`USD_UNSUPPORTED_LAYER`: MaterialX, for instance) an
/// info, anything else (`USD_COMPOSITION_ERROR`) a warning.
pub fn composition_finding(problem: &Diagnostic, f: &mut Findings) {
    let (message, location) = (&problem.message, problem.location.clone());
    let severity = match problem.code {
        Code::UsdUnsupportedLayer => Severity::Info,
        Code::UsdCompositionError => Severity::Warning,
        _ => Severity::Error,
    };
    f.push(severity, problem.code, location, message.clone());
}

/// Checks a USD asset in a child `raycast check` (see [`CheckOptions::isolate_usd`]) and
/// adopts its findings; a child that dies (an abort in the reader, a signal) or runs too long
/// becomes a `USD_READER_CRASHED` error.
pub fn check_isolated(
    exe: &Path,
    path: &Path,
    root: &Path,
    options: &CheckOptions,
    f: &mut Findings,
) -> Option<SceneStats> {
    let mut command = std::process::Command::new(exe);
    command
        .arg("check")
        .arg("--json")
        .arg("--quiet")
        .arg("--jobs")
        .arg("1")
        .arg("--max-memory")
        .arg(options.max_bytes.to_string())
        .arg("--isolated-root")
        .arg(root);
    if options.allow_outside {
        command.arg("--allow-outside");
    }
    if !options.geometry {
        command.arg("--no-geometry");
    }
    if let Some((min, max)) = options.expect_size {
        command.arg("--expect-size").arg(format!("{min}..{max}"));
    }
    if let Some(golden) = &options.golden {
        command.arg("--golden").arg(&golden.dir);
        if golden.update {
            command.arg("--update-golden");
        }
        if let Some(time) = golden.time {
            command.arg("--time").arg(time.to_string());
        }
    }
    command.arg(path);
    let (status, stdout, stderr) = match run_child(command, options.usd_timeout) {
        Ok(run) => run,
        Err(e) => {
            f.error(
                Code::IoError,
                "",
                format!("cannot start the USD check process: {e}"),
            );
            return None;
        }
    };
    let report = stdout
        .lines()
        .next()
        .and_then(|line| serde_json::from_str::<serde_json::Value>(line).ok());
    match (status, report) {
        (Some(status), Some(report)) if matches!(status.code(), Some(0) | Some(1)) => {
            let findings: Vec<Finding> = report
                .get("findings")
                .and_then(|v| serde_json::from_value(v.clone()).ok())
                .unwrap_or_default();
            for finding in findings {
                f.push(
                    finding.severity,
                    finding.code,
                    finding.location,
                    finding.message,
                );
            }
            report
                .get("scene")
                .and_then(|v| serde_json::from_value(v.clone()).ok())
        }
        (status, _) => {
            let last = last_words(&stderr);
            let how = stopped_how(status, options.usd_timeout);
            f.error(
                Code::UsdReaderCrashed,
                "",
                if last.is_empty() {
                    format!("the USD reader {how} on this file")
                } else {
                    format!("the USD reader {how} on this file: {last}")
                },
            );
            None
        }
    }
}
