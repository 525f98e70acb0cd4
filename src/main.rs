//! The `raycast` command line: a thin layer over the library.

mod cli;

use clap::{Args, Parser, Subcommand};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use raycast::accel::OctreeParams;
use raycast::import::{self, LoadOptions};
use raycast::info::{AllObjects, SceneInfo};
use raycast::job::sequence::{self, Times};
use raycast::job::{self, CameraChoice, HitLimit, RenderJob};
use raycast::output::png::DistancePng;
use raycast::output::{Format, PngOptions};
use raycast::render::Aov;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Exact ray casting of glTF, USD, OBJ, PLY and STL scenes with triangle meshes and analytic
/// quadrics.
#[derive(Parser)]
#[command(
    name = "raycast",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: RenderArgs,
}

#[derive(Subcommand)]
enum Command {
    /// Print what the importer finds in a scene.
    Info(InfoArgs),
    /// Validate assets for CI (exit 0: no errors, 1: errors, or warnings with --strict, 2: usage
    /// or I/O problem).
    Check(Box<cli::check::CheckArgs>),
    /// The nearest surface point and signed distance of each point of an (N, 3) .npy file.
    Distance(Box<cli::distance::DistanceArgs>),
}

#[derive(Args)]
struct InfoArgs {
    /// Scene files (.gltf, .glb, .obj, .ply, .stl, .usda, .usdc, .usd, .usdz).
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// glTF scene by index or name.
    #[arg(long = "scene", value_name = "N|NAME")]
    scene_choice: Option<String>,
    /// Print JSON instead of text (one record per file: a failed file's has its error).
    #[arg(long)]
    json: bool,
    /// List every object (the text lists the first ones of a large scene, then counts the
    /// rest).
    #[arg(long)]
    all: bool,
    /// Seconds the USD reader may take on one file (it reads it in a child process first).
    #[arg(long, value_name = "SECS", default_value_t = 120.0, value_parser = parse_positive)]
    usd_timeout: f64,
    #[command(flatten)]
    paths: PathArgs,
    #[command(flatten)]
    pose: PoseArgs,
}

/// When a scene is posed: glTF animations, USD time codes and variants.
#[derive(Args)]
struct PoseArgs {
    /// glTF: evaluate the animations at this time in seconds (default: no animation, the
    /// nodes' own transforms and default morph weights). USD: read the stage at this time
    /// code (default: the default time code, as usd-core's Usd.TimeCode.Default()). A render
    /// takes START:STOP:STEP too: one folder per time, <out>/NNNN-tTIME, the file read once.
    #[arg(long, value_name = "SECONDS|CODE|START:STOP:STEP", value_parser = parse_time, allow_hyphen_values = true)]
    time: Option<TimeArg>,
    /// The glTF animation to apply at --time, by index or name (default: all of them).
    #[arg(long, value_name = "N|NAME", requires = "time")]
    animation: Option<String>,
    /// USD: select variant NAME of the variant set SET on every prim that has that set
    /// (repeatable).
    #[arg(long = "variant", value_name = "SET=NAME", value_parser = raycast::import::usd::parse_choice)]
    variants: Vec<raycast::import::usd::Choice>,
}

/// `--time`: one time, or the text of a sequence START:STOP:STEP (read by [`Times`] where a
/// sequence is allowed, so that what is wrong with it is said in one line).
#[derive(Debug, Clone, PartialEq)]
enum TimeArg {
    /// One time.
    At(f64),
    /// A sequence, as written.
    Sequence(String),
}

/// A finite number, or text with a colon (a sequence).
fn parse_time(text: &str) -> raycast::Result<TimeArg> {
    match text.contains(':') {
        true => Ok(TimeArg::Sequence(text.to_string())),
        false => parse_finite(text).map(TimeArg::At),
    }
}

impl PoseArgs {
    /// The sequence `--time START:STOP:STEP` gives, if it gives one; a usage error when it is
    /// not a sequence raycast renders.
    fn sequence(&self) -> raycast::Result<Option<Times>> {
        match &self.time {
            Some(TimeArg::Sequence(text)) => text.parse().map(Some).map_err(|e| {
                raycast::Error::usage(format!("--time {text}: {e} (START:STOP:STEP)"))
            }),
            _ => Ok(None),
        }
    }

    /// The one time `--time` gives; the first of a sequence (bad sequences are refused by
    /// [`PoseArgs::sequence`] first).
    fn single_time(&self) -> Option<f64> {
        match &self.time {
            Some(TimeArg::At(time)) => Some(*time),
            Some(TimeArg::Sequence(text)) => text.parse::<Times>().ok().map(|t| t.time(0)),
            None => None,
        }
    }

    /// The same choices for a child `raycast info` (see [`probe_usd`]); the first time of a
    /// sequence.
    fn child_args(&self) -> Vec<std::ffi::OsString> {
        let mut args: Vec<std::ffi::OsString> = Vec::new();
        if let Some(time) = self.single_time() {
            args.extend(["--time".into(), format!("{time:?}").into()]);
        }
        if let Some(animation) = &self.animation {
            args.extend(["--animation".into(), animation.into()]);
        }
        for choice in &self.variants {
            args.extend([
                "--variant".into(),
                format!("{}={}", choice.set, choice.name).into(),
            ]);
        }
        args
    }
}

/// Where a scene's external files may come from (the same rule as `raycast check`).
#[derive(Args)]
struct PathArgs {
    /// Folder tree external files (glTF buffers, USD layers) must stay in (default: the
    /// scene's folder).
    #[arg(long, value_name = "DIR")]
    root: Option<PathBuf>,
    /// Read external files wherever they are.
    #[arg(long)]
    allow_outside: bool,
}

impl PathArgs {
    /// The same options for a child `raycast info` (see [`probe_usd`]).
    fn child_args(&self) -> Vec<std::ffi::OsString> {
        let mut args = Vec::new();
        if let Some(root) = &self.root {
            args.extend(["--root".into(), root.clone().into_os_string()]);
        }
        if self.allow_outside {
            args.push("--allow-outside".into());
        }
        args
    }

    fn load_options(
        self,
        scene: Option<String>,
        pose: PoseArgs,
        max_memory: Option<u64>,
    ) -> LoadOptions {
        LoadOptions {
            scene,
            root: self.root,
            allow_outside: self.allow_outside,
            time: pose.single_time(),
            animation: pose.animation,
            variants: pose.variants,
            max_memory,
        }
    }
}

#[derive(Args)]
struct RenderArgs {
    /// Scene file (.gltf, .glb, .obj, .ply, .stl, .usda, .usdc, .usd, .usdz).
    #[arg(required = true)]
    scene: Option<PathBuf>,
    /// Buffers to compute: depth, z, t, normal, position, bary, id, prim, error, certain.
    #[arg(long, value_delimiter = ',', default_value = "depth")]
    aov: Vec<Aov>,
    /// Image width in pixels (default 512, or from the camera's aspect ratio).
    #[arg(long, value_parser = parse_side)]
    width: Option<usize>,
    /// Image height in pixels.
    #[arg(long, value_parser = parse_side)]
    height: Option<usize>,
    /// Camera from the file, by index or name (default: the first, else a framing view).
    #[arg(long, value_name = "N|NAME", conflicts_with = "eye")]
    camera: Option<String>,
    /// Eye position x,y,z (with --target).
    #[arg(long, value_parser = parse_vec3, requires = "target", allow_hyphen_values = true)]
    eye: Option<DVec3>,
    /// Point to look at x,y,z (with --eye).
    #[arg(long, value_parser = parse_vec3, requires = "eye", allow_hyphen_values = true)]
    target: Option<DVec3>,
    /// Up direction x,y,z (default 0,1,0).
    #[arg(long, value_parser = parse_vec3, requires = "eye", allow_hyphen_values = true)]
    up: Option<DVec3>,
    /// Perspective projection with this vertical field of view in degrees.
    #[arg(long, conflicts_with = "ortho", value_parser = parse_fov)]
    fov: Option<f64>,
    /// Orthographic projection with this view height in scene units.
    #[arg(long, value_parser = parse_positive)]
    ortho: Option<f64>,
    /// Trace the rays of an (N, 6) .npy file (origin xyz, direction xyz) instead of a camera,
    /// or of an (N, 8) file that adds each ray's tmin and tmax (a hit needs tmin < t <= tmax).
    #[arg(long, value_name = "FILE.npy", conflicts_with_all = ["camera", "eye", "width", "height", "fov", "ortho"])]
    rays: Option<PathBuf>,
    /// With --rays: a ray with a non-finite origin or direction, or a zero direction, is an
    /// error (default: a miss, counted in the warnings).
    #[arg(long, requires = "rays")]
    strict_rays: bool,
    /// Also list every surface crossing of each ray (all), or the nearest N, into hits.npz
    /// (CSR: ray_splits, t, id, prim).
    #[arg(long, value_name = "all|N")]
    hits: Option<HitLimit>,
    /// Output folder (default: <scene stem>.raycast).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Output formats: exr, png, npy, ply (a point cloud of the hits, with --aov position;
    /// default exr,png, exr alone when no AOV asked for has a PNG preview; npy with --rays).
    #[arg(long, value_delimiter = ',')]
    format: Option<Vec<Format>>,
    /// glTF scene by index or name.
    #[arg(long = "scene", value_name = "N|NAME")]
    scene_choice: Option<String>,
    /// Worker threads (default: all cores). The output does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    threads: Option<u32>,
    /// Refuse a render whose buffers would need more memory than this (bytes; K, M, G, T
    /// suffixes; default: the memory the system reports available).
    #[arg(long, value_name = "SIZE", value_parser = raycast::sizes::parse_size)]
    max_memory: Option<u64>,
    /// Distances mapped to the depth and z previews, NEAR,FAR (default: the 1st to 99th
    /// percentile of the hits).
    #[arg(long, value_name = "NEAR,FAR", value_parser = parse_range, allow_hyphen_values = true, conflicts_with = "depth_scale")]
    depth_range: Option<[f64; 2]>,
    /// Write depth.png and z.png as 16-bit integers of this many scene units each (0.001:
    /// millimetres of a scene in metres; 0 = no data), as TUM, ScanNet and BOP store depth,
    /// instead of 8-bit previews.
    #[arg(long, value_name = "UNITS", value_parser = parse_positive)]
    depth_scale: Option<f64>,
    /// Colour map of the depth, z and t previews: grey (near white, far dark; one channel),
    /// viridis or turbo (near the map's top end: yellow, dark red).
    #[arg(
        long,
        value_name = "NAME",
        default_value = "grey",
        conflicts_with = "depth_scale"
    )]
    colormap: raycast::output::colormap::Colormap,
    /// Seconds the USD reader may take on the scene (it reads it in a child process first,
    /// so that a reader crash or hang ends with a one-line error).
    #[arg(long, value_name = "SECS", default_value_t = 120.0, value_parser = parse_positive)]
    usd_timeout: f64,
    /// Also write Cryptomatte object mattes (the objects' names hashed, ranked by coverage,
    /// six per pixel) into cryptomatte.exr, from --spp samples per pixel.
    #[arg(long, conflicts_with = "rays")]
    cryptomatte: bool,
    /// Samples per pixel for --cryptomatte, a square (1, 4, 9, 16, ...); every other buffer
    /// stays one exact ray through each pixel's centre.
    #[arg(long, value_name = "N", default_value_t = 16, requires = "cryptomatte")]
    spp: usize,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    #[command(flatten)]
    paths: PathArgs,
    #[command(flatten)]
    pose: PoseArgs,
    #[command(flatten)]
    pinhole: cli::camera::PinholeArgs,
}

/// A usage error: an option value the command line refuses.
fn usage(message: String) -> raycast::Error {
    raycast::Error::usage(message)
}

fn parse_vec3(text: &str) -> raycast::Result<DVec3> {
    let parts: Vec<f64> = text
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|_| usage(format!("'{p}' is not a number")))
        })
        .collect::<Result<_, _>>()?;
    match parts[..] {
        [x, y, z] if parts.iter().all(|v| v.is_finite()) => Ok(DVec3::new(x, y, z)),
        _ => Err(usage(format!(
            "expected three finite numbers x,y,z, got '{text}'"
        ))),
    }
}

/// An image side in pixels: 1 to 32768.
fn parse_side(text: &str) -> raycast::Result<usize> {
    match text.trim().parse::<usize>() {
        Ok(n) if (1..=raycast::camera::MAX_SIDE).contains(&n) => Ok(n),
        _ => Err(usage(format!(
            "'{text}' is not an image side (1 to {} pixels)",
            raycast::camera::MAX_SIDE
        ))),
    }
}

/// A vertical field of view strictly between 0 and 180 degrees.
fn parse_fov(text: &str) -> raycast::Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v < 180.0 => Ok(v),
        _ => Err(usage(format!(
            "'{text}' is not a field of view (between 0 and 180 degrees)"
        ))),
    }
}

/// Two finite numbers NEAR,FAR with NEAR < FAR.
fn parse_range(text: &str) -> raycast::Result<[f64; 2]> {
    let values: Vec<f64> = text
        .split(',')
        .filter_map(|v| v.trim().parse().ok())
        .collect();
    match values[..] {
        [near, far] if near.is_finite() && far.is_finite() && near < far => Ok([near, far]),
        _ => Err(usage(format!(
            "expected NEAR,FAR with NEAR < FAR, got '{text}'"
        ))),
    }
}

/// A finite number.
fn parse_finite(text: &str) -> raycast::Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(usage(format!("'{text}' is not a finite number"))),
    }
}

/// A positive finite number.
fn parse_positive(text: &str) -> raycast::Result<f64> {
    match text.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(v),
        _ => Err(usage(format!("'{text}' is not a positive number"))),
    }
}

fn main() -> ExitCode {
    // SIGINT, SIGTERM, SIGHUP: remove temporary output files, then exit as a shell expects.
    cli::signals::install();
    let args: Vec<String> = std::env::args().collect();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => match cli::slips::explain::<Cli>(&e, &args[1..]) {
            Some(meant) => {
                eprintln!("raycast: error: {meant}");
                return ExitCode::from(2);
            }
            None => e.exit(),
        },
    };
    let result = match cli.command {
        Some(Command::Info(args)) => info(args),
        Some(Command::Check(args)) => return cli::check::run(&args),
        Some(Command::Distance(args)) => cli::distance::run(*args),
        None => render(cli.render),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("raycast: error: {e}");
            ExitCode::from(match e.kind {
                raycast::error::ErrorKind::Usage => 2,
                _ => 1,
            })
        }
    }
}

/// One file's record for `raycast info --json`: what was found, or why it could not be read.
#[derive(serde::Serialize)]
#[serde(untagged)]
enum InfoRecord {
    /// The file was read.
    Read(Box<SceneInfo>),
    /// The file could not be read.
    Failed {
        /// The file, as given.
        scene: String,
        /// What is wrong, in one line.
        error: String,
    },
}

/// `raycast info`: each file in turn (text blocks, or one JSON object per file; a JSON array
/// for several files, a record for each, a failed one with its error). A file that fails is
/// reported and the others still printed; the run then fails.
fn info(args: InfoArgs) -> raycast::Result<()> {
    if args.pose.sequence()?.is_some() {
        return Err(raycast::Error::usage(
            "--time START:STOP:STEP renders a sequence; info reads one time (--time SECONDS)",
        ));
    }
    let mut child_args = args.paths.child_args();
    child_args.extend(args.pose.child_args());
    let options = args.paths.load_options(args.scene_choice, args.pose, None);
    let mut failed = None;
    let mut records = Vec::new();
    for path in &args.scenes {
        match probe_usd(path, args.usd_timeout, &child_args)
            .and_then(|()| import::load(path, &options))
        {
            Ok(scene) => records.push(InfoRecord::Read(Box::new(SceneInfo::new(&scene)))),
            Err(e) if args.scenes.len() == 1 => return Err(e),
            Err(e) => {
                eprintln!("raycast: error: {e}");
                records.push(InfoRecord::Failed {
                    scene: path.display().to_string(),
                    error: e.detail(),
                });
                failed = Some(e);
            }
        }
    }
    let text = if args.json {
        let json = match &records[..] {
            [one] if args.scenes.len() == 1 => serde_json::to_string_pretty(one),
            all => serde_json::to_string_pretty(all),
        };
        format!(
            "{}\n",
            json.map_err(|e| raycast::Error::msg(e.to_string()))?
        )
    } else {
        records
            .iter()
            .filter_map(|r| match r {
                InfoRecord::Read(info) if args.all => Some(AllObjects(info).to_string()),
                InfoRecord::Read(info) => Some(info.to_string()),
                InfoRecord::Failed { .. } => None,
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    print_stdout(&text)?;
    match failed {
        Some(_) => Err(raycast::Error::msg(
            "some files could not be read (see above)",
        )),
        None => Ok(()),
    }
}

/// Reads a USD scene in a child process first (see [`raycast::import::usd::child::probe`]), unless
/// this process is that child; other formats pass.
fn probe_usd(path: &Path, timeout: f64, child_args: &[std::ffi::OsString]) -> raycast::Result<()> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let usd = matches!(extension.as_deref(), Some("usda" | "usdc" | "usd" | "usdz"));
    if !usd || std::env::var_os(raycast::import::usd::child::PROBE_CHILD).is_some() {
        return Ok(());
    }
    let Ok(exe) = std::env::current_exe() else {
        return Ok(());
    };
    raycast::import::usd::child::probe(&exe, path, child_args, Duration::from_secs_f64(timeout))
}

/// Writes `text` to standard output; a closed pipe (`raycast info x | head`) is not an error.
fn print_stdout(text: &str) -> raycast::Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(raycast::Error::msg(format!(
            "cannot write to standard output: {e}"
        ))),
        _ => Ok(()),
    }
}

fn render(args: RenderArgs) -> raycast::Result<()> {
    if let Some(threads) = args.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(cli::threads::clamp(
                threads as usize,
                "--threads",
                args.quiet,
            ))
            .build_global()
            .map_err(|e| raycast::Error::msg(format!("cannot start {threads} threads: {e}")))?;
    }
    let times = args.pose.sequence()?;
    if let Some(scene) = &args.scene {
        let mut child_args = args.paths.child_args();
        child_args.extend(args.pose.child_args());
        probe_usd(scene, args.usd_timeout, &child_args)?;
    }
    let look_at = args
        .eye
        .zip(args.target)
        .map(|(eye, target)| (eye, target, args.up.unwrap_or(DVec3::Y)));
    let job = RenderJob {
        scene: args.scene.unwrap_or_default(),
        load: args
            .paths
            .load_options(args.scene_choice, args.pose, args.max_memory),
        aovs: dedup(args.aov),
        camera: CameraChoice {
            name: args.camera,
            look_at,
            fov_degrees: args.fov,
            ortho_height: args.ortho,
            intrinsics: args.pinhole.k,
            to_world: args.pinhole.to_world(),
        },
        width: args.width,
        height: args.height,
        rays: args.rays,
        out: args.out,
        formats: args.format,
        octree: OctreeParams::default(),
        max_memory: args.max_memory,
        strict_rays: args.strict_rays,
        pngs: PngOptions {
            depth_range: args.depth_range,
            distances: match args.depth_scale {
                Some(scale) => DistancePng::U16 { scale },
                None => DistancePng::Preview,
            },
            colormap: args.colormap,
        },
        hits: args.hits,
        cryptomatte: args.cryptomatte.then_some(args.spp),
    };
    let bar = Progress::new(args.quiet);
    if let Some(path) = &args.pinhole.views {
        if times.is_some() {
            return Err(raycast::Error::usage(
                "--views renders one time; give --time SECONDS, not START:STOP:STEP",
            ));
        }
        let size = job.width.zip(job.height);
        let views = raycast::camera::views::read(path, size)?;
        let outcome = job::views::run(&job, &views, |_, event| bar.update(event))?;
        bar.finish();
        if !args.quiet {
            say_views(&job, &outcome);
        }
        return Ok(());
    }
    if let Some(times) = times {
        let outcome = sequence::run(&job, &times, |_, event| bar.update(event))?;
        bar.finish();
        if !args.quiet {
            say_sequence(&job, &outcome);
        }
        return Ok(());
    }
    let sidecar = job::run(&job, |event| bar.update(event))?;
    bar.finish();
    if !args.quiet {
        for warning in &sidecar.warnings {
            eprintln!("raycast: warning: {warning}");
        }
        let t = sidecar.timings;
        eprintln!(
            "raycast: wrote {} to {} (load {:.3}s, build {:.3}s, trace {:.3}s, write {:.3}s)",
            sidecar.files.join(", "),
            job.out_dir().display(),
            t.load,
            t.build,
            t.trace,
            t.write
        );
    }
    Ok(())
}

/// The warnings of several renders' sidecars, each once.
fn say_warnings(sidecars: &[raycast::output::sidecar::Sidecar]) {
    let mut warnings: Vec<&String> = sidecars.iter().flat_map(|s| &s.warnings).collect();
    warnings.sort();
    warnings.dedup();
    for warning in warnings {
        eprintln!("raycast: warning: {warning}");
    }
}

/// The total of one timing over several renders' sidecars.
fn total(
    sidecars: &[raycast::output::sidecar::Sidecar],
    part: fn(&raycast::output::sidecar::Timings) -> f64,
) -> f64 {
    sidecars.iter().map(|s| part(&s.timings)).sum()
}

/// `FIRST … LAST`, the names of the first and last of several output folders, and the files
/// each holds (the first's list).
fn span(
    first: Option<&Path>,
    last: Option<&Path>,
    sidecars: &[raycast::output::sidecar::Sidecar],
) -> String {
    let name = |f: Option<&Path>| {
        f.and_then(|f| f.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let files = sidecars
        .first()
        .map(|s| s.files.join(", "))
        .unwrap_or_default();
    format!("({} … {}), each {files}", name(first), name(last))
}

/// What a run of many views wrote: its warnings (each once), then one line.
fn say_views(job: &RenderJob, outcome: &job::views::Outcome) {
    let sidecars = &outcome.sidecars;
    say_warnings(sidecars);
    let folders = &outcome.folders;
    eprintln!(
        "raycast: wrote {} views to {} {} (load {:.3}s, build {:.3}s, once; in all: trace {:.3}s, write {:.3}s)",
        folders.len(),
        job.out_dir().display(),
        span(folders.first().map(PathBuf::as_path), folders.last().map(PathBuf::as_path), sidecars),
        outcome.load,
        outcome.build,
        total(sidecars, |t| t.trace),
        total(sidecars, |t| t.write),
    );
}

/// What a sequence wrote: its warnings (each once), then one line.
fn say_sequence(job: &RenderJob, outcome: &sequence::Outcome) {
    let sidecars = &outcome.sidecars;
    say_warnings(sidecars);
    let first = outcome.frames.first().map(|f| f.folder.as_path());
    let last = outcome.frames.last().map(|f| f.folder.as_path());
    eprintln!(
        "raycast: wrote {} times to {} {} (open {:.3}s; in all: pose {:.3}s, build {:.3}s, trace {:.3}s, write {:.3}s)",
        outcome.frames.len(),
        job.out_dir().display(),
        span(first, last, sidecars),
        outcome.open,
        total(sidecars, |t| t.load),
        total(sidecars, |t| t.build),
        total(sidecars, |t| t.trace),
        total(sidecars, |t| t.write),
    );
}

/// AOVs in the order given, without repeats.
fn dedup(aovs: Vec<Aov>) -> Vec<Aov> {
    let mut seen = Vec::new();
    for aov in aovs {
        if !seen.contains(&aov) {
            seen.push(aov);
        }
    }
    seen
}

/// The progress bar's look, counting `what`, with the time left once `eta` (a guess from the
/// first moments is no guess: the first ETA read 36 s for a 1.4 s trace).
fn style(what: &str, eta: bool) -> ProgressStyle {
    let eta = if eta { " {eta}" } else { "" };
    ProgressStyle::with_template(&format!("{{bar:40}} {{pos}}/{{len}} {what}{eta}"))
        .unwrap_or_else(|_| ProgressStyle::default_bar())
}

/// The share of the work after which the bar shows the time left.
const ETA_AFTER: f64 = 0.1;

/// A progress bar on stderr that appears only on a terminal and only once a render has taken
/// more than a second.
struct Progress {
    bar: Option<ProgressBar>,
    started: Instant,
    /// Whether the bar shows the time left (the current stage is [`ETA_AFTER`] done).
    eta: std::sync::atomic::AtomicBool,
}

impl Progress {
    fn new(quiet: bool) -> Progress {
        let bar = (!quiet && std::io::stderr().is_terminal()).then(|| {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
            bar.set_style(style("rays", false));
            bar
        });
        Progress {
            bar,
            started: Instant::now(),
            eta: std::sync::atomic::AtomicBool::new(false),
        }
    }

    fn update(&self, event: job::Progress) {
        if let Some(bar) = &self.bar {
            let (done, total, what) = match event {
                job::Progress::Tracing { done, total } => (done, total, "rays"),
                job::Progress::Writing { done, total } => (done, total, "files written"),
            };
            let late = done as f64 >= ETA_AFTER * total as f64;
            if done == 0 || late != self.eta.swap(late, std::sync::atomic::Ordering::Relaxed) {
                // the count and the length first, so no frame shows rays of files
                bar.set_length(total as u64);
                bar.set_position(done as u64);
                bar.set_style(style(what, late));
            }
            bar.set_length(total as u64);
            bar.set_position(done as u64);
            if bar.is_hidden() && self.started.elapsed() > Duration::from_secs(1) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
            }
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
