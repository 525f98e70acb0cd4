//! `raycast distance`: its arguments and its summary line; the run itself is
//! [`raycast::job::distance::run`].

use crate::{probe_usd, PathArgs, PoseArgs};
use clap::{Args, ValueEnum};
use raycast::job::distance::{self, DistanceJob};
use raycast::trace::SignRule;
use std::path::PathBuf;

/// Arguments of `raycast distance`.
#[derive(Args)]
pub struct DistanceArgs {
    /// Scene file (.gltf, .glb, .obj, .ply, .stl, .usda, .usdc, .usd, .usdz). Quadrics count;
    /// one that bounds no volume (anything but an ellipsoid its clip box leaves whole) has no
    /// sign, and the run is refused unless --sign none.
    scene: PathBuf,
    /// Tracer points: an (N, 3) float32 or float64 .npy file.
    points: PathBuf,
    /// Output folder (default: <scene stem>.distance), holding distance.npy,
    /// signed_distance.npy (not with --sign none), point.npy, id.npy, prim.npy, normal.npy and
    /// raycast.json.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// How the sign is decided: crossings (exact parity; certain for closed meshes, 0 within
    /// the rounding margin of a surface) or winding (the generalised winding number, for
    /// meshes that are not closed; visits every triangle for every point), or none (distances
    /// only, in any scene: no signed_distance.npy).
    #[arg(long, value_enum, default_value_t = Sign::Crossings)]
    sign: Sign,
    /// Worker threads (default: all cores). The output does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    threads: Option<u32>,
    /// glTF scene by index or name.
    #[arg(long = "scene", value_name = "N|NAME")]
    scene_choice: Option<String>,
    /// Seconds the USD reader may take (it reads the file in a child process first).
    #[arg(long, value_name = "SECS", default_value_t = 120.0, value_parser = crate::parse_positive)]
    usd_timeout: f64,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    #[command(flatten)]
    paths: PathArgs,
    #[command(flatten)]
    pose: PoseArgs,
}

/// `--sign`.
#[derive(Clone, Copy, ValueEnum)]
enum Sign {
    Crossings,
    Winding,
    None,
}

/// Runs `raycast distance`.
pub fn run(args: DistanceArgs) -> raycast::Result<()> {
    if let Some(threads) = args.threads {
        let threads = super::threads::clamp(threads as usize, "--threads", args.quiet);
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .map_err(|e| raycast::Error::msg(format!("cannot start {threads} threads: {e}")))?;
    }
    if args.pose.sequence()?.is_some() {
        return Err(raycast::Error::usage(
            "--time START:STOP:STEP renders a sequence; distance measures one time",
        ));
    }
    let mut child_args = args.paths.child_args();
    child_args.extend(args.pose.child_args());
    probe_usd(&args.scene, args.usd_timeout, &child_args)?;
    let job = DistanceJob {
        load: args.paths.load_options(args.scene_choice, args.pose, None),
        scene: args.scene,
        points: args.points,
        out: args.out,
        sign: match args.sign {
            Sign::Crossings => Some(SignRule::Crossings),
            Sign::Winding => Some(SignRule::Winding),
            Sign::None => None,
        },
    };
    let outcome = distance::run(&job)?;
    if !args.quiet {
        let [load, build, measure] = outcome.seconds;
        let signs = match outcome.uncertain {
            Some(n) => format!(" ({n} signs within the rounding margin: 0)"),
            None => " (no signs)".to_string(),
        };
        eprintln!(
            "raycast: {} points -> {}{signs}; load {load:.3}s, build {build:.3}s, measure {measure:.3}s",
            outcome.points,
            outcome.folder.display(),
        );
    }
    Ok(())
}
