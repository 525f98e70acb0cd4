//! `raycast check`: validation of assets for CI.
//!
//! Every asset gets a list of [`Finding`]s, each with a stable code (the glTF-Validator's code
//! where the meaning is the same), a [`Severity`] and a location (a JSON pointer for glTF, a
//! prim path for USD, `line N` for OBJ). Checking never stops at the first problem and never
//! panics on bad input: a separate glTF walker ([`gltf`]) reports every problem it sees, then
//! the importer loads the scene and the geometric checks ([`geometry`]) look for holes,
//! inverted normals, degenerate triangles and the scene's size.
//!
//! Limits instead of trust: files and buffers bigger than [`CheckOptions::max_bytes`] are
//! refused before they are read, the triangles a glTF expands to are estimated before the
//! importer allocates them, external files resolve only inside the asset's folder unless
//! [`CheckOptions::allow_outside`], and nothing is fetched from the network.

#![warn(missing_docs)]

pub mod geometry;
pub mod gltf;
pub mod golden;
pub mod layers;
pub mod merge;
pub mod meshes;
pub mod obj;
pub mod report;
pub mod run;
pub mod select;
pub mod summary;
pub mod usd;
pub mod validator;

// The lower layers' modules, for paths such as `crate::scene::Scene` in this crate.
use raycast_core::{accel, bound, camera, error, render, scene, trace, Error};
use raycast_io::{import, info, output};

pub use crate::import::paths::resolve_inside;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use raycast_core::diagnostic::{Code, Diagnostic, Severity};

/// One problem found in an asset: core's one [`Diagnostic`] type, with the code, severity,
/// location and message every report shows.
pub type Finding = Diagnostic;

/// Most findings of one code kept per asset; the rest are counted in one `TRUNCATED` info.
pub const MAX_PER_CODE: usize = 50;

/// Collects findings, keeping at most [`MAX_PER_CODE`] of each code and no exact repeats.
#[derive(Debug, Default)]
pub struct Findings {
    list: Vec<Finding>,
    per_code: HashMap<Code, usize>,
}

impl Findings {
    /// Records a finding.
    pub fn push(
        &mut self,
        severity: Severity,
        code: Code,
        location: impl Into<String>,
        message: impl Into<String>,
    ) {
        let location = location.into();
        let seen = self.per_code.entry(code).or_insert(0);
        *seen += 1;
        if *seen > MAX_PER_CODE {
            return;
        }
        if self
            .list
            .iter()
            .any(|f| f.code == code && f.location == location && f.severity == severity)
        {
            *seen -= 1;
            return;
        }
        self.list
            .push(Finding::new(code, severity, location, message.into()));
    }

    /// Records an error.
    pub fn error(&mut self, code: Code, location: impl Into<String>, message: impl Into<String>) {
        self.push(Severity::Error, code, location, message);
    }

    /// Records a warning.
    pub fn warn(&mut self, code: Code, location: impl Into<String>, message: impl Into<String>) {
        self.push(Severity::Warning, code, location, message);
    }

    /// Records an info.
    pub fn info(&mut self, code: Code, location: impl Into<String>, message: impl Into<String>) {
        self.push(Severity::Info, code, location, message);
    }

    /// True when an error has been recorded.
    pub fn has_errors(&self) -> bool {
        self.list.iter().any(|f| f.severity == Severity::Error)
    }

    /// The findings, with a `TRUNCATED` info per code that had too many.
    pub fn finish(mut self) -> Vec<Finding> {
        let mut over: Vec<(&'static str, usize)> = self
            .per_code
            .iter()
            .filter(|(_, &n)| n > MAX_PER_CODE)
            .map(|(c, &n)| (c.name(), n - MAX_PER_CODE))
            .collect();
        over.sort();
        for (code, more) in over {
            let message = format!("{more} more {code} findings not listed");
            let truncated = Finding::new(Code::Truncated, Severity::Info, "", message);
            self.list.push(truncated);
        }
        self.list
    }
}

/// What to check and the limits to apply.
#[derive(Debug, Clone)]
pub struct CheckOptions {
    /// Let external buffers, images and USD references resolve outside the asset's folder.
    pub allow_outside: bool,
    /// Largest file, buffer or estimated scene (bytes) one asset may make us read or allocate.
    pub max_bytes: u64,
    /// Expected range of the scene's bounding-box diagonal, in scene units.
    pub expect_size: Option<(f64, f64)>,
    /// Run the geometric checks (holes, inverted normals, degenerate triangles).
    pub geometry: bool,
    /// Check USD assets in a child process of this `raycast` executable, so that a reader
    /// that aborts (openusd can, on hostile `.usdc` files: an allocation failure is not a
    /// panic) only fails its asset. None: in this process.
    pub isolate_usd: Option<PathBuf>,
    /// Longest the child process may take over one USD asset before it is stopped.
    pub usd_timeout: std::time::Duration,
    /// Compare rendered views with golden buffers (or store them).
    pub golden: Option<golden::GoldenOptions>,
}

impl CheckOptions {
    /// The time the assets are posed at: `--golden`'s `--time`.
    pub fn time(&self) -> Option<f64> {
        self.golden.as_ref().and_then(|g| g.time)
    }
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            allow_outside: false,
            max_bytes: 2 << 30,
            expect_size: None,
            geometry: true,
            isolate_usd: None,
            usd_timeout: std::time::Duration::from_secs(120),
            golden: None,
        }
    }
}

/// Scene figures of an asset that loaded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneStats {
    /// Objects in the scene.
    pub objects: usize,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Quadrics in the scene.
    pub quadrics: usize,
    /// Diagonal of the scene's bounding box (0 for an empty scene).
    pub size: f64,
}

/// An asset's verdict: the worst severity among its findings (infos do not count).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// No errors or warnings.
    Ok,
    /// Warnings but no errors.
    Warning,
    /// At least one error.
    Error,
}

impl Status {
    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Warning => "warning",
            Status::Error => "error",
        }
    }
}

/// The verdict on one asset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AssetReport {
    /// The asset's path as found.
    pub path: String,
    /// The asset's path relative to the folder named on the command line (the file name for
    /// a file named directly), with `/` separators: the key assets are sorted and sharded by.
    pub relpath: String,
    /// `gltf`, `glb`, `obj`, `ply`, `stl` or `usd`.
    pub format: String,
    /// `ok`, `warning` or `error`: the worst severity among the findings (infos are `ok`).
    pub status: Status,
    /// Number of errors.
    pub errors: usize,
    /// Number of warnings.
    pub warnings: usize,
    /// Number of infos.
    pub infos: usize,
    /// Seconds spent on the asset.
    pub seconds: f64,
    /// Figures of the loaded scene, when it loaded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneStats>,
    /// Everything found (the most severe `--max-findings` of it, when that is given).
    pub findings: Vec<Finding>,
    /// Findings left out of `findings` by `--max-findings` (still counted above).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub omitted: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl AssetReport {
    fn new(asset: &Asset, findings: Vec<Finding>, scene: Option<SceneStats>, seconds: f64) -> Self {
        let count = |s: Severity| findings.iter().filter(|f| f.severity == s).count();
        let (errors, warnings, infos) = (
            count(Severity::Error),
            count(Severity::Warning),
            count(Severity::Info),
        );
        AssetReport {
            path: asset.path.display().to_string(),
            relpath: asset.relpath.clone(),
            format: format_of(&asset.path).unwrap_or("unknown").to_string(),
            status: if errors > 0 {
                Status::Error
            } else if warnings > 0 {
                Status::Warning
            } else {
                Status::Ok
            },
            errors,
            warnings,
            infos,
            seconds,
            scene,
            findings,
            omitted: 0,
        }
    }

    /// True when the asset has an error.
    pub fn has_errors(&self) -> bool {
        self.errors > 0
    }

    /// True when the asset fails the run: it has an error, or (`strict`) a warning.
    pub fn fails(&self, strict: bool) -> bool {
        self.errors > 0 || (strict && self.warnings > 0)
    }

    /// Keeps the `max` most severe findings (errors first; the order among those kept is
    /// unchanged) and counts the rest in [`AssetReport::omitted`]; the counts and the status
    /// still describe every finding.
    pub fn limit_findings(&mut self, max: usize) {
        if self.findings.len() <= max {
            return;
        }
        let mut order: Vec<usize> = (0..self.findings.len()).collect();
        order.sort_by_key(|&i| (self.findings[i].severity, i));
        let mut keep = vec![false; self.findings.len()];
        for &i in &order[..max] {
            keep[i] = true;
        }
        let mut index = 0;
        self.findings.retain(|_| {
            index += 1;
            keep[index - 1]
        });
        self.omitted += order.len() - max;
    }
}

/// The order assets are reported and sharded in: by [`AssetReport::relpath`], compared folder
/// by folder (so `a/b` comes before `a-c`), then by the path as found.
pub fn report_order(a: (&str, &str), b: (&str, &str)) -> std::cmp::Ordering {
    let parts = |s: &str| s.split('/').map(str::to_string).collect::<Vec<_>>();
    parts(a.0)
        .cmp(&parts(b.0))
        .then_with(|| Path::new(a.1).cmp(Path::new(b.1)))
}

/// The format of a file by its extension, if `check` handles it.
pub fn format_of(path: &Path) -> Option<&'static str> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "gltf" => Some("gltf"),
        "glb" => Some("glb"),
        "obj" => Some("obj"),
        "ply" => Some("ply"),
        "stl" => Some("stl"),
        "usd" | "usda" | "usdc" | "usdz" => Some("usd"),
        _ => None,
    }
}

/// An asset to check and the folder tree its external files must stay in.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Asset {
    /// The asset file.
    pub path: PathBuf,
    /// The folder named on the command line that it was found in, or the file's own folder
    /// when the file was named directly.
    pub root: PathBuf,
    /// The path relative to the folder it was found in (the file name for a file named
    /// directly), `/`-separated; see [`AssetReport::relpath`].
    pub relpath: String,
}

impl Asset {
    /// An asset confined to its own folder.
    pub fn file(path: impl Into<PathBuf>) -> Asset {
        let path = path.into();
        let root = parent_of(&path);
        let relpath = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        Asset {
            path,
            root,
            relpath,
        }
    }

    /// An asset found below the folder `root` named on the command line.
    pub fn found_in(path: PathBuf, root: &Path) -> Asset {
        let relpath = path
            .strip_prefix(root)
            .unwrap_or(&path)
            .components()
            .map(|c| c.as_os_str().to_string_lossy())
            .collect::<Vec<_>>()
            .join("/");
        Asset {
            path,
            root: root.to_path_buf(),
            relpath,
        }
    }
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The assets named by `paths`: files as given (whatever their extension), folders searched
/// recursively (symbolic links not followed) for the extensions `check` handles, in
/// [`report_order`].
/// A path that does not exist is a usage error (exit code 2).
pub fn discover(paths: &[PathBuf]) -> error::Result<Vec<Asset>> {
    let mut found = Vec::new();
    let unreadable =
        |path: &Path, e: std::io::Error| Error::in_file(path, e.to_string()).as_usage();
    for path in paths {
        let meta = std::fs::metadata(path).map_err(|e| unreadable(path, e))?;
        if meta.is_dir() {
            let mut stack = vec![path.clone()];
            let mut in_dir = Vec::new();
            while let Some(dir) = stack.pop() {
                let entries = std::fs::read_dir(&dir).map_err(|e| unreadable(&dir, e))?;
                for entry in entries.flatten() {
                    let Ok(kind) = entry.file_type() else {
                        continue;
                    };
                    let p = entry.path();
                    if kind.is_dir() {
                        stack.push(p);
                    } else if kind.is_file() && format_of(&p).is_some() {
                        in_dir.push(p);
                    }
                }
            }
            if in_dir.is_empty() {
                return Err(Error::in_file(
                    path,
                    "no assets in this folder (searched for .gltf, .glb, .obj, .ply, .stl, \
                     .usd, .usda, .usdc and .usdz files)",
                )
                .as_usage());
            }
            found.extend(in_dir.into_iter().map(|p| Asset::found_in(p, path)));
        } else {
            found.push(Asset::file(path.clone()));
        }
    }
    let mut seen = std::collections::HashSet::new();
    found.retain(|a| seen.insert(a.path.clone()));
    found.sort_by(|a, b| {
        report_order(
            (&a.relpath, &a.path.to_string_lossy()),
            (&b.relpath, &b.path.to_string_lossy()),
        )
    });
    Ok(found)
}

/// Stack of each checking thread.
pub const CHECK_STACK_BYTES: usize = 256 << 20;

/// Checks every asset in parallel on a pool of `jobs` threads (0: all cores), calling
/// `progress` after each; reports come back in the order of `assets`.
pub fn check_all(
    assets: &[Asset],
    options: &CheckOptions,
    jobs: usize,
    progress: &(dyn Fn() + Sync),
) -> error::Result<Vec<AssetReport>> {
    // Readers of hostile files may recurse deeply: give each worker a large stack (only the
    // pages used are committed).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .stack_size(CHECK_STACK_BYTES)
        .build()
        .map_err(|e| Error::usage(format!("cannot start {jobs} threads: {e}")))?;
    Ok(pool.install(|| {
        assets
            .par_iter()
            .map(|asset| {
                let report = check_asset(asset, options);
                progress();
                report
            })
            .collect()
    }))
}

/// Checks one asset. Never panics: a panic inside a reader becomes an `INTERNAL_PANIC` error.
pub fn check_asset(asset: &Asset, options: &CheckOptions) -> AssetReport {
    let started = Instant::now();
    let path = asset.path.as_path();
    let root = asset.root.as_path();
    let mut findings = Findings::default();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        check_into(path, root, options, &mut findings)
    }));
    // Findings made before a panic are kept.
    let scene = match outcome {
        Ok(scene) => scene,
        Err(panic) => {
            let what = crate::error::panic_message(&*panic);
            findings.error(
                Code::InternalPanic,
                "",
                format!("raycast failed on this asset (a bug; please report it): {what}"),
            );
            None
        }
    };
    let findings = findings.finish();
    AssetReport::new(asset, findings, scene, started.elapsed().as_secs_f64())
}

fn check_into(
    path: &Path,
    root: &Path,
    options: &CheckOptions,
    findings: &mut Findings,
) -> Option<SceneStats> {
    let meta = match std::fs::metadata(path) {
        Ok(meta) => meta,
        Err(e) => {
            findings.error(Code::IoError, "", format!("cannot read: {e}"));
            return None;
        }
    };
    if !meta.is_file() {
        findings.error(Code::IoError, "", "not a regular file");
        return None;
    }
    if meta.len() > options.max_bytes {
        findings.error(
            Code::FileTooLarge,
            "",
            format!(
                "{} bytes is more than the limit of {} (--max-memory): not read",
                meta.len(),
                options.max_bytes
            ),
        );
        return None;
    }
    let Some(format) = format_of(path) else {
        findings.error(
            Code::UnsupportedFileType,
            "",
            format!("not a {} file", import::FILE_TYPES),
        );
        return None;
    };
    // The same words as a render's for content that is another format than the name says.
    let extension = crate::import::extension_of(path);
    if let Err(e) = crate::import::sniff::check_content(path, &extension) {
        findings.error(Code::FileTypeMismatch, "", e.detail());
        return None;
    }
    let scene = match format {
        "gltf" | "glb" => gltf::check(path, root, options, findings)?,
        "obj" => {
            let bytes = match std::fs::read(path) {
                Ok(bytes) => bytes,
                Err(e) => {
                    findings.error(Code::IoError, "", format!("cannot read: {e}"));
                    return None;
                }
            };
            if !obj::check(path, root, &bytes, options, findings) {
                return None;
            }
            import::obj::load(path)
        }
        "ply" | "stl" => Ok(meshes::check(path, format, findings)?),
        _ => {
            if !usd::precheck(path, options, findings) {
                return None;
            }
            if let Some(exe) = &options.isolate_usd {
                return usd::check_isolated(exe, path, root, options, findings);
            }
            usd::load(path, root, options, findings)
        }
    };
    let scene = match scene {
        Ok(scene) => scene,
        Err(e) => {
            // The walker already explains most failures; the importer's verdict is then a
            // note, else it is the error.
            let severity = if findings.has_errors() {
                Severity::Info
            } else {
                Severity::Error
            };
            let code = match format {
                "gltf" | "glb" | "obj" => Code::LoadFailed,
                _ => usd::load_failure_code(&e),
            };
            findings.push(
                severity,
                code,
                "",
                format!("the importer refuses the asset: {}", e.detail()),
            );
            return None;
        }
    };
    let mut warnings = scene.warnings.clone();
    crate::import::sort_warnings(&mut warnings);
    for warning in &warnings {
        importer_warning(warning, findings);
    }
    if let Some(golden) = &options.golden {
        let key = path.strip_prefix(root).unwrap_or(path);
        golden::check(&scene, key, golden, findings);
    }
    Some(geometry::check(&scene, options, findings))
}

/// Maps an importer warning to a finding, by its code: an empty scene is left to the
/// geometric checks (`EMPTY_SCENE`), USD composition problems are findings of their own
/// ([`usd::composition_finding`]), attributes of value types USD does not know a warning
/// (usd-core opens such a layer too, and leaves the values unread), a value the file holds but
/// the reader cannot decode (a corrupt crate field) an error at that value (the render skips
/// the prim and goes on), anything else an `IMPORTER_NOTE` info at the warning's location.
fn importer_warning(warning: &Diagnostic, findings: &mut Findings) {
    let line = warning.to_string();
    match warning.code {
        Code::EmptyScene => {}
        Code::UsdCompositionCycle
        | Code::MissingReference
        | Code::UsdUnsupportedLayer
        | Code::UsdCompositionError => usd::composition_finding(warning, findings),
        Code::UsdUnknownValueType => findings.warn(warning.code, "", line),
        Code::UsdUnreadableValue => findings.error(warning.code, warning.location.clone(), line),
        _ => findings.info(Code::ImporterNote, warning.location.clone(), line),
    }
}

/// Parses `MIN..MAX` (either side may be empty for no bound).
pub fn parse_range(text: &str) -> error::Result<(f64, f64)> {
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| Error::usage(format!("'{text}': expected MIN..MAX")))?;
    let side = |s: &str, default: f64| -> error::Result<f64> {
        let s = s.trim();
        if s.is_empty() {
            Ok(default)
        } else {
            s.parse::<f64>()
                .ok()
                .filter(|v| !v.is_nan())
                .ok_or_else(|| Error::usage(format!("'{s}' is not a number")))
        }
    };
    let (min, max) = (side(a, 0.0)?, side(b, f64::INFINITY)?);
    if min > max {
        return Err(Error::usage(format!("'{text}': MIN is larger than MAX")));
    }
    Ok((min, max))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges() {
        assert_eq!(parse_range("0.5..2"), Ok((0.5, 2.0)));
        assert_eq!(parse_range("1..").map(|r| r.0), Ok(1.0));
        assert_eq!(
            parse_range("2..1").map_err(|e| e.to_string()),
            Err("'2..1': MIN is larger than MAX".to_string())
        );
        assert!(parse_range("2..1").is_err());
    }

    #[test]
    fn findings_are_capped() {
        let mut f = Findings::default();
        for i in 0..(MAX_PER_CODE + 10) {
            f.error(Code::IndexOob, format!("/{i}"), "bad");
        }
        f.error(Code::IndexOob, "/0", "bad");
        let list = f.finish();
        assert_eq!(list.len(), MAX_PER_CODE + 1);
        assert_eq!(list.last().map(|f| f.code), Some(Code::Truncated));
    }
}
