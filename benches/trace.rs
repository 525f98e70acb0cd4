//! Benchmark driver for the acceleration backends (not a timed test; run by `raycast_tools bench`).
//!
//! ```text
//! cargo bench --bench trace -- SCENE --rays NAME=FILE.npy [--rays ...] [--backends octree,bvh,cwbvh]
//!     [--threads 1,2] [--runs 3] [--build-runs 3 (0: one build, no warm-up)] [--aov-compare NAME]
//! ```
//!
//! For each backend: one warm-up build and `--build-runs` timed builds (median; each the whole
//! build a render does, the instanced meshes' own octrees included), then for each
//! ray set and thread count one warm-up trace and `--runs` timed traces (median) through the
//! same `render` path the CLI uses with `--aov depth`. Prints one JSON object on stdout.
//! Peak memory is the process's VmHWM from /proc/self/status, reset (when the kernel allows it)
//! before each backend, so it covers the scene, the rays, that backend and its buffers.

use raycast::accel::{Bvh, BvhKind, Octree, OctreeParams, PrimitiveSet};
use raycast::geometry::Ray;
use raycast::import::npy;
use raycast::import::{self, LoadOptions};
use raycast::render::{self, Aov};
use raycast::scene::Scene;
use raycast::trace::{self, BvhTracer, NearestHits, Tracer};
use serde_json::{json, Value};
use std::path::PathBuf;
use std::str::FromStr;
use std::time::Instant;

/// A backend to measure: the octree or one of the obvhs hierarchies (the BVH oracle).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Backend {
    Octree,
    Bvh(BvhKind),
}

impl Backend {
    const ALL: [Backend; 3] = [
        Backend::Octree,
        Backend::Bvh(BvhKind::Bvh2),
        Backend::Bvh(BvhKind::Cwbvh),
    ];

    fn name(self) -> &'static str {
        match self {
            Backend::Octree => "octree",
            Backend::Bvh(kind) => kind.name(),
        }
    }
}

impl FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let known = Backend::ALL.into_iter().find(|b| b.name() == s);
        known.ok_or_else(|| format!("unknown backend '{s}' (choose octree, bvh, cwbvh)"))
    }
}

/// A built backend.
enum Built {
    Octree(Octree),
    Bvh(Bvh),
}

impl Built {
    /// What the renderer traces through.
    fn tracer<'a>(&'a self, scene: &'a Scene) -> Box<dyn NearestHits + 'a> {
        match self {
            Built::Octree(octree) => Box::new(Tracer::new(scene, octree)),
            Built::Bvh(bvh) => Box::new(BvhTracer { scene, bvh }),
        }
    }
}

struct Args {
    scene: PathBuf,
    rays: Vec<(String, PathBuf)>,
    backends: Vec<Backend>,
    threads: Vec<usize>,
    runs: usize,
    build_runs: usize,
    aov_compare: Option<String>,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        scene: PathBuf::new(),
        rays: Vec::new(),
        backends: Backend::ALL.to_vec(),
        threads: vec![1],
        runs: 3,
        build_runs: 3,
        aov_compare: None,
    };
    let mut it = std::env::args().skip(1);
    let list = |v: String| -> Vec<String> { v.split(',').map(str::to_string).collect() };
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--bench" => {}
            "--rays" => {
                let v = value()?;
                let (name, path) = v.split_once('=').ok_or("--rays NAME=FILE.npy")?;
                args.rays.push((name.to_string(), PathBuf::from(path)));
            }
            "--backends" => {
                args.backends = list(value()?)
                    .iter()
                    .map(|b| b.parse())
                    .collect::<Result<_, _>>()?
            }
            "--threads" => {
                args.threads = list(value()?)
                    .iter()
                    .map(|t| t.parse().map_err(|_| format!("bad thread count {t}")))
                    .collect::<Result<_, _>>()?
            }
            "--runs" => args.runs = value()?.parse().map_err(|_| "bad --runs")?,
            "--build-runs" => args.build_runs = value()?.parse().map_err(|_| "bad --build-runs")?,
            "--aov-compare" => args.aov_compare = Some(value()?),
            s if s.starts_with("--") => return Err(format!("unknown option {s}")),
            s => args.scene = PathBuf::from(s),
        }
    }
    if args.scene.as_os_str().is_empty() {
        return Err("usage: trace SCENE --rays NAME=FILE.npy [options]".into());
    }
    Ok(args)
}

/// A field of /proc/self/status in MiB (VmHWM, VmRSS).
fn status_mib(field: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(field))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

/// Resets VmHWM to the current RSS; false when the kernel refuses.
fn reset_peak() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let value = f();
    (value, start.elapsed().as_secs_f64())
}

/// The whole build, as a render does it: the instanced meshes' own octrees (dropped first, so
/// that every timed build builds them again) and the top-level structure.
fn build(scene: &mut Scene, kind: Backend) -> Built {
    scene.forget_instance_octrees();
    match kind {
        Backend::Octree => Built::Octree(trace::build_octree(scene, OctreeParams::default())),
        Backend::Bvh(kind) => {
            scene.build_instances();
            Built::Bvh(Bvh::build(scene, kind))
        }
    }
}

fn accel_stats(accel: &Built, prims: usize) -> Value {
    match accel {
        Built::Octree(o) => {
            let s = o.stats();
            let bytes = o.bytes();
            json!({
                "octree": s,
                "params": o.params(),
                "bytes": bytes,
                "bytes_per_prim": bytes as f64 / prims.max(1) as f64,
                "refs_per_prim": s.references as f64 / prims.max(1) as f64,
            })
        }
        Built::Bvh(b) => {
            let s = b.stats();
            json!({
                "bvh": s,
                "bytes": s.bytes,
                "bytes_per_prim": s.bytes as f64 / prims.max(1) as f64,
            })
        }
    }
}

fn trace_once(tracer: &dyn NearestHits, rays: &Vec<Ray>, aovs: &[Aov]) -> render::Buffers {
    render::render(tracer, rays, aovs, |_| {})
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("trace: {e}");
            std::process::exit(2);
        }
    };
    let (scene, load_s) = timed(|| import::load(&args.scene, &LoadOptions::default()));
    let mut scene = scene.unwrap_or_else(|e| {
        eprintln!("trace: {e}");
        std::process::exit(1)
    });
    let prims = scene.len();
    let ray_sets: Vec<(String, Vec<Ray>)> = args
        .rays
        .iter()
        .map(|(name, path)| {
            let rays = npy::read_rays(path)
                .map(|file| file.rays)
                .unwrap_or_else(|e| {
                    eprintln!("trace: {e}");
                    std::process::exit(1)
                });
            (name.clone(), rays)
        })
        .collect();
    let pools: Vec<(usize, rayon::ThreadPool)> = args
        .threads
        .iter()
        .map(|&n| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .expect("thread pool");
            (n, pool)
        })
        .collect();
    let rss_scene = status_mib("VmRSS:");
    let mut results = Vec::new();
    for &kind in &args.backends {
        let peak_reset = reset_peak();
        let rss_before = status_mib("VmRSS:");
        // Warm-up build, then timed builds; the last one is kept. `--build-runs 0`: one timed
        // build without warm-up (large scenes).
        let (mut accel, first) = timed(|| build(&mut scene, kind));
        let mut build_times = Vec::new();
        if args.build_runs == 0 {
            build_times.push(first);
        }
        for _ in 0..args.build_runs {
            drop(accel);
            let (a, s) = timed(|| build(&mut scene, kind));
            accel = a;
            build_times.push(s);
        }
        let mut stats = accel_stats(&accel, prims);
        // What a trace reads besides the structure: the triangles and the instanced meshes.
        stats["geometry_bytes"] = json!(scene.trace_bytes());
        let boxed = accel.tracer(&scene);
        let tracer = boxed.as_ref();
        let mut traces = Vec::new();
        for (name, rays) in &ray_sets {
            for (threads, pool) in &pools {
                let mut hits = 0usize;
                let mut times = Vec::new();
                pool.install(|| {
                    let warm = trace_once(tracer, rays, &[Aov::Depth]);
                    hits = warm
                        .floats(Aov::Depth)
                        .map_or(0, |d| d.iter().filter(|t| t.is_finite()).count());
                    for _ in 0..args.runs.max(1) {
                        let (_, s) = timed(|| trace_once(tracer, rays, &[Aov::Depth]));
                        times.push(s);
                    }
                });
                let m = median(times.clone());
                traces.push(json!({
                    "rays": name,
                    "count": rays.len(),
                    "threads": threads,
                    "median_s": m,
                    "runs_s": times,
                    "mrays_per_s": rays.len() as f64 / m / 1e6,
                    "hit_ratio": hits as f64 / rays.len().max(1) as f64,
                }));
            }
        }
        let peak_trace = status_mib("VmHWM:");
        // Depth only against every AOV a ray file supports, all threads of the last pool.
        let mut aov = Value::Null;
        if let Some(name) = &args.aov_compare {
            if let (Some((_, rays)), Some((threads, pool))) =
                (ray_sets.iter().find(|(n, _)| n == name), pools.last())
            {
                let all = [Aov::Depth, Aov::Normal, Aov::Position, Aov::Id, Aov::Prim];
                let mut figures = serde_json::Map::new();
                for (label, aovs) in [("depth", &[Aov::Depth][..]), ("all", &all[..])] {
                    pool.install(|| drop(trace_once(tracer, rays, aovs)));
                    let reset = reset_peak();
                    let base = status_mib("VmRSS:");
                    let mut times = Vec::new();
                    for _ in 0..args.runs.max(1) {
                        let (b, s) = timed(|| pool.install(|| trace_once(tracer, rays, aovs)));
                        times.push(s);
                        drop(b);
                    }
                    figures.insert(
                        label.into(),
                        json!({
                            "aovs": aovs.iter().map(|a| a.name()).collect::<Vec<_>>(),
                            "median_s": median(times),
                            "peak_extra_mib": if reset { status_mib("VmHWM:") - base } else { f64::NAN },
                        }),
                    );
                }
                figures.insert("rays".into(), json!(name));
                figures.insert("threads".into(), json!(threads));
                aov = Value::Object(figures);
            }
        }
        results.push(json!({
            "backend": kind.name(),
            "build_s": median(build_times.clone()),
            "build_runs_s": build_times,
            "stats": stats,
            "peak_rss_mib": peak_trace,
            "peak_is_per_backend": peak_reset,
            "rss_before_build_mib": rss_before,
            "traces": traces,
            "aov": aov,
        }));
        drop(boxed);
        drop(accel);
    }
    let quadrics = scene.quadrics().len();
    let out = json!({
        "scene": args.scene.display().to_string(),
        "triangles": scene.triangle_count(),
        "quadrics": quadrics,
        "load_s": load_s,
        "rss_scene_and_rays_mib": rss_scene,
        "backends": results,
        "bvh_kinds": [BvhKind::Bvh2.name(), BvhKind::Cwbvh.name()],
    });
    println!("{out}");
}
