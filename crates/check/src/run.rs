//! A whole `raycast check` run: find and select the assets, check them in parallel (or merge
//! the shards of an earlier run), write the outputs and decide the verdict. The command line
//! (`src/cli/check.rs` in the binary) only parses arguments into [`RunOptions`] and draws the
//! progress bar.

use super::merge::{self, ShardHeader};
use super::select::{self, Excludes, Shard};
use super::{check_all, discover, layers, report, summary, validator, AssetReport, CheckOptions};
use crate::error::{Error, Result};
use crate::output::Staging;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// What a `raycast check` run is asked to do.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Asset files, or folders searched recursively (with `merge`: the shard files).
    pub paths: Vec<PathBuf>,
    /// Merge the JSON Lines of the shards named by `paths` instead of checking assets.
    pub merge: bool,
    /// Check only this shard of the assets found.
    pub shard: Option<Shard>,
    /// Leave out assets whose relative path matches one of these globs.
    pub exclude: Vec<String>,
    /// Leave out USD layers that another checked layer brings in.
    pub root_layers_only: bool,
    /// Warnings fail the run too.
    pub strict: bool,
    /// Most findings listed per asset.
    pub max_findings: Option<usize>,
    /// Print JSON Lines instead of the text report.
    pub json: bool,
    /// Also write a JUnit XML report to this file.
    pub junit: Option<PathBuf>,
    /// Also write a Markdown summary to this file.
    pub summary: Option<PathBuf>,
    /// Also write one glTF-Validator-format report per asset into this folder.
    pub validator_json: Option<PathBuf>,
    /// Print GitHub workflow annotations.
    pub github: bool,
    /// Assets checked at once (0: all cores).
    pub jobs: usize,
    /// Folder tree external files must stay in, instead of the folder each asset was found in.
    pub root: Option<PathBuf>,
    /// List infos and assets without findings too.
    pub verbose: bool,
    /// Print only the outputs asked for and errors of the tool itself.
    pub quiet: bool,
    /// The checks and limits applied to each asset.
    pub check: CheckOptions,
}

impl RunOptions {
    /// The options that shape the findings and the verdict, recorded in a shard's header so
    /// that only shards of the same run merge.
    fn settings(&self) -> serde_json::Value {
        let c = &self.check;
        serde_json::json!({
            "raycast": env!("CARGO_PKG_VERSION"),
            "paths": self.paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "exclude": self.exclude,
            "root_layers_only": self.root_layers_only,
            "strict": self.strict,
            "max_findings": self.max_findings,
            "root": self.root.as_ref().map(|p| p.display().to_string()),
            "allow_outside": c.allow_outside,
            "max_memory": c.max_bytes,
            "expect_size": c.expect_size.map(|(a, b)| [a, b]),
            "geometry": c.geometry,
            "golden": c.golden.as_ref().map(|g| g.dir.display().to_string()),
        })
    }
}

/// What a run found: the reports and how to judge and time them.
struct Outcome {
    reports: Vec<AssetReport>,
    /// The shard's header, for a `--shard` run.
    header: Option<ShardHeader>,
    /// Warnings fail (`--strict`, or shards run with it).
    strict: bool,
    /// The run's seconds (a merge: its shards' added up).
    seconds: f64,
}

/// Runs `raycast check`, calling `progress(done, total)` after each asset. Returns whether
/// the run passed (no asset has an error, nor a warning when strict); an `Err` is a usage or
/// I/O problem (a path that does not exist, shards that do not fit, a report that cannot be
/// written).
pub fn run(options: &RunOptions, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<bool> {
    let outcome = if options.merge {
        merged(options)?
    } else {
        checked(options, progress)?
    };
    print(options, &outcome)?;
    write_files(options, &outcome)?;
    if !options.quiet {
        eprintln!(
            "raycast check: {}",
            report::summary(&outcome.reports, outcome.seconds)
        );
    }
    Ok(!outcome.reports.iter().any(|r| r.fails(outcome.strict)))
}

/// The shards named by `options.paths`, merged.
fn merged(options: &RunOptions) -> Result<Outcome> {
    refuse_overwriting_inputs(options, &options.paths)?;
    let merged = merge::merge(&options.paths)?;
    Ok(Outcome {
        strict: options.strict || merged.settings["strict"] == true,
        reports: merged.reports,
        header: None,
        seconds: merged.seconds,
    })
}

/// Finds, selects and checks the assets; with `--shard`, also the shard's header.
fn checked(options: &RunOptions, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<Outcome> {
    let started = Instant::now();
    let mut assets = discover(&options.paths)?;
    if let Some(root) = &options.root {
        for asset in &mut assets {
            asset.root = root.clone();
        }
    }
    let inputs: Vec<PathBuf> = assets.iter().map(|a| a.path.clone()).collect();
    refuse_overwriting_inputs(options, &inputs)?;
    let mut assets = select::exclude(assets, &Excludes::new(&options.exclude)?)?;
    if options.root_layers_only {
        assets = layers::root_layers(assets, options.check.max_bytes);
    }
    let total = assets.len();
    let assets = select::shard(assets, options.shard);
    let done = AtomicUsize::new(0);
    // Panics are caught per asset and reported as findings; keep the default hook quiet.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let reports = check_all(&assets, &options.check, options.jobs, &|| {
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, assets.len())
    });
    std::panic::set_hook(hook);
    let mut reports = reports?;
    if let Some(max) = options.max_findings {
        for report in &mut reports {
            report.limit_findings(max);
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    let header = options.shard.map(|shard| ShardHeader {
        index: shard.index,
        count: shard.count,
        assets: reports.len(),
        total,
        seconds,
        settings: options.settings(),
    });
    Ok(Outcome {
        reports,
        header,
        strict: options.strict,
        seconds,
    })
}

/// Prints the report on stdout (and the annotations, on stderr beside JSON).
fn print(options: &RunOptions, outcome: &Outcome) -> Result<()> {
    let reports = &outcome.reports;
    let mut text = String::new();
    if options.json {
        if let Some(header) = &outcome.header {
            text.push_str(&header.line());
        }
        text.push_str(&report::json_lines(reports));
    } else if !options.quiet {
        text.push_str(&report::human(reports, options.verbose));
        if outcome.strict && reports.iter().any(|r| r.warnings > 0) {
            text.push_str("(--strict: warnings fail this run)\n");
        }
    }
    if options.github {
        let see = match (&options.summary, &options.junit) {
            (Some(summary), _) => format!("the job summary ({})", summary.display()),
            (None, Some(junit)) => format!("the JUnit report ({})", junit.display()),
            (None, None) => "the full report (raycast check --summary FILE)".to_string(),
        };
        let annotations = report::github(reports, &see);
        if options.json {
            // stdout stays pure JSON Lines; the annotations go to stderr (GitHub reads both).
            eprint!("{annotations}");
        } else {
            text.push_str(&annotations);
        }
    }
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| Error::usage(format!("cannot write the report: {e}")))
}

/// Writes the report files: each under a temporary name first (removed on Ctrl-C or
/// failure), all renamed into place at the end.
fn write_files(options: &RunOptions, outcome: &Outcome) -> Result<()> {
    let (reports, strict, seconds) = (&outcome.reports, outcome.strict, outcome.seconds);
    let mut files = Files::default();
    if let Some(junit) = &options.junit {
        files.add(junit, report::junit(reports, seconds, strict).as_bytes())?;
    }
    if let Some(path) = &options.summary {
        files.add(path, summary::markdown(reports, strict, seconds).as_bytes())?;
    }
    if let Some(dir) = &options.validator_json {
        if dir.is_file() {
            return Err(validator_json_is_a_file(dir));
        }
        let mut names = std::collections::HashSet::new();
        for r in reports {
            let name = validator::file_name(r);
            if !names.insert(name.clone()) {
                return Err(Error::usage(format!(
                    "two assets have the relative path {}: check one folder at a time with --validator-json",
                    r.relpath
                )));
            }
            let json = serde_json::to_vec_pretty(&validator::report(r))
                .map_err(|e| Error::msg(e.to_string()))?;
            files.add(&dir.join(name), &json)?;
        }
    }
    files.commit()
}

/// Report files being written, staged per folder.
#[derive(Default)]
struct Files(BTreeMap<PathBuf, Staging>);

impl Files {
    fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        let name = path
            .file_name()
            .ok_or_else(|| Error::usage(format!("{}: not a file name", path.display())))?
            .to_string_lossy()
            .into_owned();
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if path.is_dir() {
            return Err(Error::in_file(path, "is a folder").as_usage());
        }
        let staging = match self.0.entry(dir.clone()) {
            std::collections::btree_map::Entry::Occupied(e) => e.into_mut(),
            std::collections::btree_map::Entry::Vacant(e) => {
                e.insert(Staging::new(&dir).map_err(Error::as_usage)?)
            }
        };
        staging
            .write(&name, |out| {
                out.write_all(bytes)
                    .map_err(|e| Error::msg(format!("cannot write: {e}")))
            })
            .map_err(Error::as_usage)
    }

    fn commit(self) -> Result<()> {
        for staging in self.0.into_values() {
            staging.commit().map_err(Error::as_usage)?;
        }
        Ok(())
    }
}

/// Refuses, before any asset is checked, a `--junit` or `--summary` path that is a folder or
/// one of the run's inputs (an asset, or a shard file of a merge), and any report path
/// (`--validator-json` too) whose folder cannot be written.
fn refuse_overwriting_inputs(options: &RunOptions, inputs: &[PathBuf]) -> Result<()> {
    for out in [&options.junit, &options.summary].into_iter().flatten() {
        if out.is_dir() {
            return Err(Error::usage(format!("{} is a folder", out.display())));
        }
        let folder = out.parent().filter(|p| !p.as_os_str().is_empty());
        probe_writable(out, folder.unwrap_or(Path::new(".")))?;
    }
    if let Some(dir) = &options.validator_json {
        if dir.is_file() {
            return Err(validator_json_is_a_file(dir));
        }
        probe_writable(dir, dir)?;
    }
    for out in [&options.junit, &options.summary].into_iter().flatten() {
        let Ok(target) = out.canonicalize() else {
            continue;
        };
        if inputs
            .iter()
            .any(|a| a.canonicalize().is_ok_and(|a| a == target))
        {
            return Err(Error::usage(format!(
                "{} is one of the inputs of this run: refusing to overwrite it",
                out.display()
            )));
        }
    }
    Ok(())
}

/// Refuses the report path `report` when the folder `dir` it goes into (or, when `dir` does
/// not exist yet, the nearest folder above it that does) cannot be written: a probe file is
/// created there and removed, and nothing else is created.
fn probe_writable(report: &Path, dir: &Path) -> Result<()> {
    let refuse =
        |why: String| Error::in_file(report, format!("cannot be written: {why}")).as_usage();
    let absolute = std::path::absolute(dir).map_err(|e| refuse(e.to_string()))?;
    let Some(existing) = absolute.ancestors().find(|a| a.exists()) else {
        return Err(refuse("no folder above it exists".into()));
    };
    if !existing.is_dir() {
        return Err(refuse(format!("{} is not a folder", existing.display())));
    }
    let probe = existing.join(format!(".raycast-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|e| refuse(format!("{}: {e}", existing.display())))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// The error for a `--validator-json` path that is a file.
fn validator_json_is_a_file(dir: &Path) -> Error {
    Error::in_file(dir, "--validator-json needs a folder, this is a file").as_usage()
}
