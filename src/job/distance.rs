//! `raycast distance`: the nearest surface point and the signed distance of every point of a
//! points file, written as `.npy` files with a `raycast.json` sidecar, by the same rules as a
//! render's folder (nothing half-written, nothing of another scene's run removed).
//!
//! The queries are [`Tracer::closest`] and [`Tracer::side_by_crossings`] or the winding number
//! (see [`crate::query`]'s distance module), the ones the Python package's `closest_points`
//! and `signed_distance` call. Quadrics count (see [`crate::quadric::Quadric::closest`]);
//! a run that writes signed distances in a scene whose sign is not defined (a quadric that
//! is not a closed ellipsoid, or any quadric with `--sign winding`: see [`Signer::new`]) is
//! refused, naming the object; a run without signs (`--sign none`) measures distances in any
//! scene and writes no `signed_distance.npy`.

use super::into_folder;
use crate::accel::{Octree, OctreeParams};
use crate::error::{Error, Result};
use crate::import::npy::read_points;
use crate::import::{self, LoadOptions};
use crate::output::npy::{self, NpyData};
use crate::output::{ownership, FileJob, Staging, DISTANCE_FILES as FILES};
use crate::trace::{self, NearestPoint, Side, SignRule, Signer, Tracer};
use glam::DVec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Everything a distance run needs.
#[derive(Debug, Clone)]
pub struct DistanceJob {
    /// The scene file.
    pub scene: PathBuf,
    /// Importer options.
    pub load: LoadOptions,
    /// The (N, 3) float32 or float64 `.npy` file of query points.
    pub points: PathBuf,
    /// Output folder; `None` for `<scene stem>.distance`.
    pub out: Option<PathBuf>,
    /// How signs are decided; `None` for no signs (no `signed_distance.npy`).
    pub sign: Option<SignRule>,
}

/// What a finished run did.
#[derive(Debug, Clone, PartialEq)]
pub struct DistanceOutcome {
    /// The folder written.
    pub folder: PathBuf,
    /// Points measured.
    pub points: usize,
    /// Points within the rounding margin of a surface, whose sign is 0 (`None` without signs).
    pub uncertain: Option<usize>,
    /// Seconds to load the scene, build the octree and measure.
    pub seconds: [f64; 3],
}

impl DistanceJob {
    /// The output folder.
    pub fn out_dir(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            let stem = self.scene.file_stem().unwrap_or_default().to_string_lossy();
            PathBuf::from(format!("{stem}.distance"))
        })
    }

    /// The files the run writes: every one of [`FILES`], but `signed_distance.npy` only with
    /// signs.
    fn files(&self) -> Vec<&'static str> {
        FILES
            .into_iter()
            .filter(|&name| self.sign.is_some() || name != SIGNED_FILE)
            .collect()
    }
}

/// The one file of [`FILES`] a run without signs does not write.
const SIGNED_FILE: &str = FILES[1];

/// A point's nearest surface point (`None` in an empty scene) and, with signs, its side.
type Measured = (Option<NearestPoint>, Option<Side>);

/// Runs a distance job.
pub fn run(job: &DistanceJob) -> Result<DistanceOutcome> {
    if job.out.as_deref() == Some(Path::new("-")) {
        return Err(Error::usage(
            "--out -: a distance run writes a folder of files, not standard output; name a folder",
        ));
    }
    let names: Vec<String> = job.files().iter().map(|s| s.to_string()).collect();
    let out = job.out_dir();
    let inputs = [job.scene.as_path(), job.points.as_path()];
    into_folder(&out, &inputs, &names, || measure_and_write(job, &out))
}

/// Loads, builds, measures and writes (in `out`, claimed already).
fn measure_and_write(job: &DistanceJob, out: &Path) -> Result<DistanceOutcome> {
    let points = read_points(&job.points)?;
    let clock = Instant::now();
    let scene = import::load(&job.scene, &job.load)?;
    let load = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    scene.build_instances();
    let octree = Octree::build(&scene, OctreeParams::default());
    let build = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let query = Tracer {
        scene: &scene,
        octree: &octree,
    };
    let measured: Vec<Measured> = match job.sign {
        Some(rule) => {
            let signer =
                Signer::new(query, rule).map_err(|e| e.with_path(&job.scene).as_usage())?;
            let measure = |&p: &DVec3| {
                let (nearest, side) = signer.measure(p);
                (nearest, Some(side))
            };
            points.par_iter().map(measure).collect()
        }
        None => points
            .par_iter()
            .map(|&p| (query.closest(p), None))
            .collect(),
    };
    let seconds = [load, build, clock.elapsed().as_secs_f64()];
    let uncertain = job.sign.map(|_| {
        let on_surface = |m: &&Measured| m.1 == Some(Side::OnSurface);
        measured.iter().filter(on_surface).count()
    });
    let mut staging = Staging::for_render(out, &job.scene)?;
    staging.protect(&job.scene);
    staging.protect(&job.points);
    write(&mut staging, &measured)?;
    let sidecar = sidecar(job, &scene, points.len(), uncertain, seconds);
    staging.write(ownership::SIDECAR, |w| {
        serde_json::to_writer_pretty(&mut *w, &sidecar)
            .map_err(|e| Error::msg(format!("cannot write: {e}")))
    })?;
    staging.commit()?;
    Ok(DistanceOutcome {
        folder: out.to_path_buf(),
        points: points.len(),
        uncertain,
        seconds,
    })
}

/// Writes the buffers: misses (an empty scene) are +inf distances and points, id
/// 0, prim `u32::MAX` and a zero normal, as the render's buffers have them; signed distances
/// when the points have sides.
fn write(staging: &mut Staging, measured: &[Measured]) -> Result<()> {
    let n = measured.len();
    let distance: Vec<f64> = measured
        .iter()
        .map(|(m, _)| m.map_or(f64::INFINITY, |m| m.distance))
        .collect();
    let signed: Option<Vec<f64>> = measured
        .iter()
        .map(|&(m, side)| side.map(|side| trace::signed((m, side))))
        .collect();
    let vector = |f: fn(&NearestPoint) -> DVec3, miss: f64| -> Vec<f64> {
        measured
            .iter()
            .flat_map(|(m, _)| m.as_ref().map_or([miss; 3], |m| f(m).to_array()))
            .collect()
    };
    let point = vector(|m| m.point, f64::INFINITY);
    let normal = vector(|m| m.normal, 0.0);
    let id: Vec<u32> = measured
        .iter()
        .map(|(m, _)| m.map_or(0, |m| m.id))
        .collect();
    let prim: Vec<u32> = measured
        .iter()
        .map(|(m, _)| m.map_or(u32::MAX, |m| m.prim))
        .collect();
    fn file<'a>(name: &'static str, shape: Vec<usize>, data: NpyData<'a>) -> FileJob<'a> {
        FileJob::new(name, move |w| npy::write(w, &shape, data))
    }
    let mut jobs = vec![file(FILES[0], vec![n], NpyData::F64(&distance))];
    if let Some(signed) = &signed {
        jobs.push(file(SIGNED_FILE, vec![n], NpyData::F64(signed)));
    }
    jobs.extend([
        file(FILES[2], vec![n, 3], NpyData::F64(&point)),
        file(FILES[3], vec![n], NpyData::U32(&id)),
        file(FILES[4], vec![n], NpyData::U32(&prim)),
        file(FILES[5], vec![n, 3], NpyData::F64(&normal)),
    ]);
    staging.write_all(jobs, |_| {})
}

/// The run's `raycast.json`: what was measured, from what, how, and the files (the fields
/// [`ownership`] reads: `scene`, `scene_file`, `files`).
fn sidecar(
    job: &DistanceJob,
    scene: &crate::scene::Scene,
    points: usize,
    uncertain: Option<usize>,
    [load, build, measure]: [f64; 3],
) -> serde_json::Value {
    let closed: Vec<serde_json::Value> = crate::info::SceneInfo::new(scene)
        .objects
        .into_iter()
        .filter_map(|o| {
            o.closed
                .map(|c| serde_json::json!({"id": o.id, "name": o.name, "closed": c}))
        })
        .collect();
    serde_json::json!({
        "raycast": env!("CARGO_PKG_VERSION"),
        "command": "distance",
        "scene": job.scene.display().to_string(),
        "scene_file": ownership::scene_key(&job.scene),
        "points_file": job.points.display().to_string(),
        "points": points,
        "sign": job.sign.map_or("none", SignRule::name),
        "uncertain_signs": uncertain,
        "meshes": closed,
        "timings": {"load": load, "build": build, "measure": measure},
        "files": job.files(),
    })
}
