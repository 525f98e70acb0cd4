//! One render run from start to finish: load, build, trace, write, with timings. The binary
//! is a thin layer over [`run`].

use crate::accel::OctreeParams;
use crate::error::{Error, Result};
use crate::import::{self, LoadOptions};
use crate::output::request::{self};
use crate::output::sidecar::Sidecar;
use crate::output::{self, ownership, Format, PngOptions};
use crate::render::Aov;
use glam::{DMat4, DVec3};
use stages::run_checked;
use std::path::{Path, PathBuf};

mod cryptomatte;
pub mod distance;
pub mod sequence;
mod stages;
mod view;
pub mod views;

/// How to choose the camera.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraChoice {
    /// A file camera by index or name; `None` takes the first one, or frames the scene.
    pub name: Option<String>,
    /// Look from `eye` to `target` with `up` instead of a file camera.
    pub look_at: Option<(DVec3, DVec3, DVec3)>,
    /// Override the projection: perspective with this vertical field of view (degrees).
    pub fov_degrees: Option<f64>,
    /// Override the projection: orthographic with this full view height.
    pub ortho_height: Option<f64>,
    /// Override the projection: a pinhole camera of this intrinsic matrix (row-major), for
    /// the job's width and height (both needed).
    pub intrinsics: Option<[[f64; 3]; 3]>,
    /// Place a pinhole camera (with `intrinsics`) by this camera-to-world matrix, in raycast's
    /// axes (+Y up, looking down -Z), instead of a file camera, a look-at or the framing.
    pub to_world: Option<DMat4>,
}

/// Everything a render run needs.
#[derive(Debug, Clone)]
pub struct RenderJob {
    /// The scene file.
    pub scene: PathBuf,
    /// Importer options.
    pub load: LoadOptions,
    /// Buffers to compute.
    pub aovs: Vec<Aov>,
    /// Camera choice (camera mode).
    pub camera: CameraChoice,
    /// Image width; `None` for the default.
    pub width: Option<usize>,
    /// Image height; `None` for the default.
    pub height: Option<usize>,
    /// A ray file: rays mode instead of camera mode.
    pub rays: Option<PathBuf>,
    /// Output folder; `None` for `<scene stem>.raycast`.
    pub out: Option<PathBuf>,
    /// Output formats; `None` for the mode's default.
    pub formats: Option<Vec<Format>>,
    /// Octree parameters.
    pub octree: OctreeParams,
    /// A ray that cannot be traced (non-finite origin or direction, zero direction) is an
    /// error, not a miss with a warning.
    pub strict_rays: bool,
    /// How depth and z PNGs are written: previews over a range of distances, or 16-bit
    /// integers.
    pub pngs: PngOptions,
    /// Refuse a run whose buffers need more bytes than this; `None`: the memory the system
    /// reports available.
    pub max_memory: Option<u64>,
    /// List every surface crossing of each ray (or the nearest few) into `hits.npz`.
    pub hits: Option<HitLimit>,
    /// Write Cryptomatte object mattes into `cryptomatte.exr`, from this many stratified
    /// samples per pixel (a square: 1, 4, 9, 16, …); camera mode only.
    pub cryptomatte: Option<usize>,
}

/// How many crossings `--hits` lists per ray.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HitLimit {
    /// Every crossing.
    All,
    /// The nearest `n` (at least 1).
    Nearest(usize),
}

impl HitLimit {
    /// The most crossings listed per ray.
    pub fn count(self) -> usize {
        match self {
            HitLimit::All => usize::MAX,
            HitLimit::Nearest(n) => n,
        }
    }
}

impl std::str::FromStr for HitLimit {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim() {
            "all" => Ok(HitLimit::All),
            n => match n.parse::<usize>() {
                Ok(n) if n > 0 => Ok(HitLimit::Nearest(n)),
                _ => Err(Error::usage(format!(
                    "'{s}' is not a number of hits per ray: give all or a count of at least 1"
                ))),
            },
        }
    }
}

/// Default image width and height.
const DEFAULT_SIZE: usize = 512;

impl RenderJob {
    /// The names of the files this job writes in `formats`, `raycast.json` last.
    pub fn file_names(&self, formats: &[Format]) -> Vec<String> {
        let rays_mode = self.rays.is_some();
        let mut names = request::file_names(&self.aovs, formats, rays_mode, self.hits.is_some());
        if self.cryptomatte.is_some() {
            names.insert(names.len() - 1, output::cryptomatte::FILE.to_string());
        }
        names
    }

    /// The output folder this job writes to.
    pub fn out_dir(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            let stem = self.scene.file_stem().unwrap_or_default().to_string_lossy();
            PathBuf::from(format!("{stem}.raycast"))
        })
    }
}

/// How far a render has come, for a progress display.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// `done` of `total` rays traced.
    Tracing {
        /// Rays traced so far.
        done: usize,
        /// Rays in all.
        total: usize,
    },
    /// `done` of `total` files written.
    Writing {
        /// Files complete so far.
        done: usize,
        /// Files in all.
        total: usize,
    },
}

/// Runs a render job; `progress` is told as rays are traced and as files are written.
///
/// The request is checked before the scene is loaded: every format and AOV must give a file,
/// and the output folder must be writable. The buffers' memory is estimated before tracing.
pub fn run(job: &RenderJob, progress: impl FnMut(Progress) + Send) -> Result<Sidecar> {
    run_from(job, None, progress)
}

/// [`run`] with the scene posed from `source` (a file opened once for many runs, see
/// [`sequence`]) at the job's time, instead of reading `job.scene`.
pub fn run_from(
    job: &RenderJob,
    source: Option<&import::Source>,
    progress: impl FnMut(Progress) + Send,
) -> Result<Sidecar> {
    let formats = check_request(job)?;
    into_job_folder(job, &formats, || {
        run_checked(job, source, &formats, progress)
    })
}

/// [`into_folder`] for a render job: its output folder, its inputs (the scene, the ray file)
/// and the files it writes in `formats`.
fn into_job_folder<T>(
    job: &RenderJob,
    formats: &[Format],
    work: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let inputs: Vec<&Path> = std::iter::once(job.scene.as_path())
        .chain(job.rays.as_deref())
        .collect();
    into_folder(&job.out_dir(), &inputs, &job.file_names(formats), work)
}

/// Runs `work` for a run of the scene `inputs[0]` (reading `inputs`) that writes `names` into
/// the folder `out`: the folder is created if need be (and removed again when the run fails)
/// and claimed for the scene first.
fn into_folder<T>(
    out: &Path,
    inputs: &[&Path],
    names: &[String],
    work: impl FnOnce() -> Result<T>,
) -> Result<T> {
    let created = output::prepare_tracked_folder(out)?;
    let result = ownership::refuse_inputs(out, names, inputs)
        .and_then(|()| ownership::claim(out, inputs[0], names))
        .and_then(|_| work());
    if result.is_err() {
        request::remove_created_folder(out, created.as_deref());
    }
    output::untrack_created_folder(out);
    result
}

/// Checks what can be checked before loading (see [`run`]); returns the formats to write,
/// merged.
fn check_request(job: &RenderJob) -> Result<Vec<Format>> {
    if job.out.as_deref() == Some(Path::new("-")) {
        return Err(Error::usage(
            "--out -: a render writes a folder of files, not standard output; name a folder",
        ));
    }
    let rays_mode = job.rays.is_some();
    if rays_mode && job.aovs.contains(&Aov::Z) {
        return Err(Error::usage(
            "the z AOV needs a camera; it is not available with --rays",
        ));
    }
    let formats = match &job.formats {
        Some(formats) => request::merge_formats(formats),
        None if rays_mode => vec![Format::Npy],
        // PNG previews where an AOV has one (`--aov error,certain` alone has none).
        None if job.aovs.iter().any(|&aov| Format::Png.holds(aov, false)) => {
            vec![Format::Exr, Format::Png]
        }
        None => vec![Format::Exr],
    };
    request::check_files(&job.aovs, &formats, rays_mode)?;
    if let Some(spp) = job.cryptomatte {
        if rays_mode {
            return Err(Error::usage(
                "--cryptomatte makes image mattes; it is not available with --rays",
            ));
        }
        cryptomatte::side(spp)?;
    }
    Ok(formats)
}
