//! `raycast check`: its arguments, progress bar and exit code; the run itself is
//! [`raycast::check::run`].

use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raycast::check::golden::GoldenOptions;
use raycast::check::run::RunOptions;
use raycast::check::{parse_range, CheckOptions};
use raycast::sizes::parse_size;
use raycast::Error;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raycast check`.
#[derive(Args, Debug, Clone)]
pub struct CheckArgs {
    /// Asset files, or folders searched recursively for .gltf, .glb, .obj, .ply, .stl, .usd,
    /// .usda, .usdc and .usdz files (with --merge: the shard files).
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// Print one JSON object per asset (JSON Lines) instead of the text report; with --shard,
    /// a shard header line comes first (the input of --merge).
    #[arg(long)]
    pub json: bool,
    /// Also write a JUnit XML report (one testcase per asset) to this file.
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Also write a Markdown summary (counts by status and code, worst and slowest assets) to
    /// this file, e.g. for $GITHUB_STEP_SUMMARY.
    #[arg(long, value_name = "FILE")]
    pub summary: Option<PathBuf>,
    /// Also write one report per asset in the Khronos glTF-Validator's JSON schema into this
    /// folder (<relative path>.report.json).
    #[arg(long, value_name = "DIR")]
    pub validator_json: Option<PathBuf>,
    /// Print GitHub workflow annotations (::error file=...::message), at most 10 of each type
    /// (GitHub's cap per step), then a notice pointing to the summary.
    #[arg(long)]
    pub github: bool,
    /// Warnings fail the run too (exit 1), like usdchecker -t.
    #[arg(long)]
    pub strict: bool,
    /// Check only the K-th of N parts of the assets found (1-based; sorted relative paths
    /// dealt round-robin), for N parallel CI jobs. Use with --json to merge them later.
    #[arg(
        long,
        value_name = "K/N",
        conflicts_with = "merge",
        allow_hyphen_values = true
    )]
    pub shard: Option<String>,
    /// Merge the --shard K/N --json outputs named as PATHs into the report of the whole run
    /// (findings, order and exit code as if unsharded).
    #[arg(long, conflicts_with_all = ["exclude", "root_layers_only", "max_findings", "golden", "expect_size", "no_geometry", "root", "allow_outside"])]
    pub merge: bool,
    /// Leave out assets whose path relative to the folder named matches GLOB (a GLOB without
    /// '/' matches any file or folder name on the way); repeatable.
    #[arg(long, value_name = "GLOB")]
    pub exclude: Vec<String>,
    /// USD: leave out layers that another checked layer brings in as a sublayer, reference or
    /// payload (a kit's components and materials), checking only the root layers.
    #[arg(long)]
    pub root_layers_only: bool,
    /// List at most N findings per asset, the most severe first (the counts still include
    /// every finding).
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub max_findings: Option<String>,
    /// Assets checked at once (default: all cores; at most the cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub jobs: Option<u32>,
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
    /// With --golden: render the views at this pose (glTF: seconds, every animation played;
    /// USD: a time code), for goldens and comparison alike
    #[arg(
        long,
        requires = "golden",
        value_name = "T",
        allow_negative_numbers = true
    )]
    pub time: Option<f64>,
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

impl CheckArgs {
    /// The run these arguments ask for.
    fn options(&self) -> raycast::Result<RunOptions> {
        let usd_timeout = std::time::Duration::try_from_secs_f64(self.timeout).map_err(|_| {
            Error::usage(format!(
                "--timeout {}: expected a positive number of seconds",
                self.timeout
            ))
        })?;
        let check = CheckOptions {
            allow_outside: self.allow_outside,
            max_bytes: self.max_memory,
            expect_size: self.expect_size,
            geometry: !self.no_geometry,
            golden: self.golden.clone().map(|dir| GoldenOptions {
                dir,
                update: self.update_golden,
                time: self.time,
            }),
            usd_timeout,
            // The USD reader runs in a child process unless this already is one.
            isolate_usd: if self.isolated_root.is_some() {
                None
            } else {
                std::env::current_exe().ok()
            },
        };
        let shard = self
            .shard
            .as_deref()
            .map(|text| {
                text.parse::<raycast::check::select::Shard>()
                    .map_err(|e| Error::usage(format!("--shard {e}")))
            })
            .transpose()?;
        let max_findings = self
            .max_findings
            .as_deref()
            .map(|text| {
                text.trim().parse::<usize>().map_err(|_| {
                    Error::usage(format!("--max-findings '{text}': expected a whole number"))
                })
            })
            .transpose()?;
        Ok(RunOptions {
            paths: self.paths.clone(),
            merge: self.merge,
            shard,
            exclude: self.exclude.clone(),
            root_layers_only: self.root_layers_only,
            strict: self.strict,
            max_findings,
            json: self.json,
            junit: self.junit.clone(),
            summary: self.summary.clone(),
            validator_json: self.validator_json.clone(),
            github: self.github,
            jobs: self.jobs.map_or(0, |n| {
                super::threads::clamp(n as usize, "--jobs", self.quiet)
            }),
            root: self.isolated_root.clone().or_else(|| self.root.clone()),
            verbose: self.verbose,
            quiet: self.quiet,
            check,
        })
    }
}

/// Runs `raycast check`: exit 0 when no asset has an error, 1 when one does, 2 for usage
/// or I/O problems (a path that does not exist, a report that cannot be written).
pub fn run(args: &CheckArgs) -> ExitCode {
    let result = args.options().and_then(|options| {
        let bar = Bar::new(args.quiet);
        let passed = raycast::check::run::run(&options, &|done, total| bar.update(done, total));
        bar.finish();
        passed
    });
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(message) => {
            eprintln!("raycast check: error: {message}");
            ExitCode::from(2)
        }
    }
}

/// The assets-checked bar on stderr, only on a terminal.
struct Bar(Option<ProgressBar>);

impl Bar {
    fn new(quiet: bool) -> Bar {
        Bar((!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} assets {eta}") {
                bar.set_style(style);
            }
            bar
        }))
    }

    fn update(&self, done: usize, total: usize) {
        if let Some(bar) = &self.0 {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.0 {
            bar.finish_and_clear();
        }
    }
}
