//! A whole `raycast check` run: find the assets, check them in parallel, write the outputs
//! and decide the verdict. The command line (`src/cli/check.rs` in the binary) only parses
//! arguments into [`RunOptions`] and draws the progress bar.

use super::{check_all, discover, report, CheckOptions};
use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// What a `raycast check` run is asked to do.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Asset files, or folders searched recursively.
    pub paths: Vec<PathBuf>,
    /// Print JSON Lines instead of the text report.
    pub json: bool,
    /// Also write a JUnit XML report to this file.
    pub junit: Option<PathBuf>,
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

/// Runs `raycast check`, calling `progress(done, total)` after each asset. Returns whether
/// the run passed (no asset has an error); an `Err` is a usage or I/O problem (a path that does
/// not exist, a report that cannot be written).
pub fn run(options: &RunOptions, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<bool> {
    let started = Instant::now();
    let mut assets = discover(&options.paths).map_err(Error::usage)?;
    if let Some(root) = &options.root {
        for asset in &mut assets {
            asset.root = root.clone();
        }
    }
    if let Some(junit) = &options.junit {
        refuse_overwriting_input(junit, &assets)?;
    }
    let total = assets.len();
    let done = AtomicUsize::new(0);
    // Panics are caught per asset and reported as findings; keep the default hook quiet.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let reports = check_all(&assets, &options.check, options.jobs, &|| {
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, total)
    });
    std::panic::set_hook(hook);
    let reports = reports.map_err(Error::usage)?;
    let seconds = started.elapsed().as_secs_f64();
    let mut text = String::new();
    if options.json {
        text.push_str(&report::json_lines(&reports));
    } else if !options.quiet {
        text.push_str(&report::human(&reports, options.verbose));
    }
    if options.github && options.json {
        // stdout stays pure JSON Lines; the annotations go to stderr (GitHub reads both).
        eprint!("{}", report::github(&reports));
    } else if options.github {
        text.push_str(&report::github(&reports));
    }
    let mut stdout = std::io::stdout().lock();
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| Error::usage(format!("cannot write the report: {e}")))?;
    if let Some(junit) = &options.junit {
        write_atomically(junit, report::junit(&reports, seconds).as_bytes())?;
    }
    if !options.quiet {
        eprintln!("raycast check: {}", report::summary(&reports, seconds));
    }
    Ok(!reports.iter().any(|r| r.has_errors()))
}

/// Refuses a report path that is one of the assets being checked.
fn refuse_overwriting_input(out: &Path, assets: &[super::Asset]) -> Result<()> {
    if out.is_dir() {
        return Err(Error::usage(format!("{} is a folder", out.display())));
    }
    let Ok(target) = out.canonicalize() else {
        return Ok(());
    };
    if assets
        .iter()
        .any(|a| a.path.canonicalize().is_ok_and(|a| a == target))
    {
        return Err(Error::usage(format!(
            "{} is one of the assets being checked: refusing to overwrite it",
            out.display()
        )));
    }
    Ok(())
}

/// Writes `bytes` to `.NAME.partial-PID` beside `path`, then renames it into place; the
/// temporary file is removed if anything fails.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    let name = path
        .file_name()
        .ok_or_else(|| Error::usage(format!("{}: not a file name", path.display())))?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let temp = dir.join(format!(".{name}.partial-{}", std::process::id()));
    let result = std::fs::write(&temp, bytes).and_then(|()| std::fs::rename(&temp, path));
    if let Err(e) = result {
        let _ = std::fs::remove_file(&temp);
        return Err(Error::usage(format!(
            "cannot write {}: {e}",
            path.display()
        )));
    }
    Ok(())
}
