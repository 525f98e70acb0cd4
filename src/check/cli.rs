//! The `raycast check` subcommand: arguments, parallel run, outputs and exit code.

use super::{check_all, discover, parse_range, parse_size, report, CheckOptions};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Arguments of `raycast check`.
#[derive(Args, Debug, Clone)]
pub struct CheckArgs {
    /// Asset files, or folders searched recursively for .gltf, .glb, .obj, .usd, .usda,
    /// .usdc and .usdz files.
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Print one JSON object per asset (JSON Lines) instead of the text report.
    #[arg(long)]
    pub json: bool,
    /// Also write a JUnit XML report (one testcase per asset) to this file.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Print GitHub workflow annotations (::error file=...::message).
    #[arg(long)]
    pub github: bool,
    /// Assets checked at once (default: all cores).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Expected bounding-box diagonal of each scene, MIN..MAX in scene units.
    #[arg(long, value_name = "MIN..MAX", value_parser = parse_range)]
    pub expect_size: Option<(f64, f64)>,
    /// Largest file, buffer or expanded scene one asset may make raycast read or allocate
    /// (bytes; K, M, G suffixes).
    #[arg(long, value_name = "SIZE", default_value = "2G", value_parser = parse_size)]
    pub max_memory: u64,
    /// Folder tree external files must stay in (default: the folder named on the command
    /// line, or the file's own folder).
    #[arg(long, value_name = "DIR")]
    pub root: Option<PathBuf>,
    /// Let external buffers, images and USD references resolve outside the asset's folder.
    #[arg(long)]
    pub allow_outside: bool,
    /// Seconds one USD asset may take (it is read in a child process, stopped after this).
    #[arg(long, value_name = "SECS", default_value_t = 120.0)]
    pub timeout: f64,
    /// Skip the geometric checks (holes, inverted normals, degenerate triangles).
    #[arg(long)]
    pub no_geometry: bool,
    /// Render three fixed views of each asset (depth and id) and compare them with the golden
    /// buffers stored in this folder; a mismatch is an error with a difference image
    #[arg(long, value_name = "DIR")]
    pub golden: Option<PathBuf>,
    /// With --golden: store the current buffers as the golden ones instead of comparing
    #[arg(long, requires = "golden")]
    pub update_golden: bool,
    /// List infos and assets without findings too.
    #[arg(long, short)]
    pub verbose: bool,
    /// Print only the outputs asked for and errors of the tool itself.
    #[arg(long, short)]
    pub quiet: bool,
    /// Internal: check one USD asset in this process, confined to this folder tree (how the
    /// parent `raycast check` isolates the USD reader).
    #[arg(long, hide = true, value_name = "DIR")]
    pub isolated_root: Option<PathBuf>,
}

/// Runs `raycast check`: exit 0 when no asset has an error, 1 when one does, 2 for usage
/// or I/O problems (a path that does not exist, a report that cannot be written).
pub fn run(args: &CheckArgs) -> ExitCode {
    match run_inner(args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(message) => {
            eprintln!("raycast check: error: {message}");
            ExitCode::from(2)
        }
    }
}

fn run_inner(args: &CheckArgs) -> Result<bool, String> {
    let started = Instant::now();
    let mut assets = discover(&args.paths)?;
    if let Some(root) = args.isolated_root.as_ref().or(args.root.as_ref()) {
        for asset in &mut assets {
            asset.root = root.clone();
        }
    }
    if let Some(junit) = &args.junit {
        refuse_overwriting_input(junit, &assets)?;
    }
    let options = CheckOptions {
        allow_outside: args.allow_outside,
        max_bytes: args.max_memory,
        expect_size: args.expect_size,
        geometry: !args.no_geometry,
        golden: args.golden.clone().map(|dir| super::golden::GoldenOptions {
            dir,
            update: args.update_golden,
        }),
        usd_timeout: std::time::Duration::try_from_secs_f64(args.timeout).map_err(|_| {
            format!(
                "--timeout {}: expected a positive number of seconds",
                args.timeout
            )
        })?,
        // The USD reader runs in a child process unless this already is one.
        isolate_usd: if args.isolated_root.is_some() {
            None
        } else {
            std::env::current_exe().ok()
        },
    };
    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
        let bar =
            ProgressBar::with_draw_target(Some(assets.len() as u64), ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} assets {eta}") {
            bar.set_style(style);
        }
        bar
    });
    // Panics are caught per asset and reported as findings; keep the default hook quiet.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let reports = check_all(&assets, &options, args.jobs.unwrap_or(0), &|| {
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    });
    std::panic::set_hook(hook);
    let reports = reports?;
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let seconds = started.elapsed().as_secs_f64();
    let mut stdout = std::io::stdout().lock();
    let mut text = String::new();
    if args.json {
        text.push_str(&report::json_lines(&reports));
    } else if !args.quiet {
        text.push_str(&report::human(&reports, args.verbose));
    }
    if args.github && args.json {
        // stdout stays pure JSON Lines; the annotations go to stderr (GitHub reads both).
        eprint!("{}", report::github(&reports));
    } else if args.github {
        text.push_str(&report::github(&reports));
    }
    stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .map_err(|e| format!("cannot write the report: {e}"))?;
    if let Some(junit) = &args.junit {
        write_atomically(junit, report::junit(&reports, seconds).as_bytes())?;
    }
    if !args.quiet {
        eprintln!("raycast check: {}", report::summary(&reports, seconds));
    }
    Ok(!reports.iter().any(|r| r.has_errors()))
}

/// Refuses a report path that is one of the assets being checked.
fn refuse_overwriting_input(out: &Path, assets: &[super::Asset]) -> Result<(), String> {
    if out.is_dir() {
        return Err(format!("{} is a folder", out.display()));
    }
    let Ok(target) = out.canonicalize() else {
        return Ok(());
    };
    if assets
        .iter()
        .any(|a| a.path.canonicalize().is_ok_and(|a| a == target))
    {
        return Err(format!(
            "{} is one of the assets being checked: refusing to overwrite it",
            out.display()
        ));
    }
    Ok(())
}

/// Writes `bytes` to `.NAME.partial-PID` beside `path`, then renames it into place; the
/// temporary file is removed if anything fails.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let name = path
        .file_name()
        .ok_or_else(|| format!("{}: not a file name", path.display()))?
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
        return Err(format!("cannot write {}: {e}", path.display()));
    }
    Ok(())
}
