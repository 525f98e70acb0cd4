//! One render run from start to finish: load, build, trace, write, with timings. The binary
//! is a thin layer over [`run`].

use crate::accel::OctreeParams;
use crate::camera::{Camera, Projection};
use crate::error::{Error, Result};
use crate::import::{self, LoadOptions};
use crate::output::npy::RayFile;
use crate::output::request::{self, buffer_bytes, check_memory};
use crate::output::sidecar::{self, CameraInfo, HitsInfo, Sidecar, Stats, Timings};
use crate::output::{self, npz, ownership, Format, Layout, Staging};
use crate::query::HitLists;
use crate::render::{self, AccelKind, AccelStructure, Aov, Buffers, CameraView, RaySource};
use crate::render::{Rays, Tracer};
use crate::scene::Scene;
use glam::DVec3;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

pub mod sequence;

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
    /// The acceleration structure to build.
    pub accel: AccelKind,
    /// A ray that cannot be traced (non-finite origin or direction, zero direction) is an
    /// error, not a miss with a warning.
    pub strict_rays: bool,
    /// The distance range mapped into the depth and z previews, near to far; `None` for the
    /// 1st to 99th percentile of the hits.
    pub depth_range: Option<[f64; 2]>,
    /// Refuse a run whose buffers need more bytes than this; `None`: the memory the system
    /// reports available.
    pub max_memory: Option<u64>,
    /// List every surface crossing of each ray (or the nearest few) into `hits.npz`.
    pub hits: Option<HitLimit>,
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
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim() {
            "all" => Ok(HitLimit::All),
            n => match n.parse::<usize>() {
                Ok(n) if n > 0 => Ok(HitLimit::Nearest(n)),
                _ => Err(format!(
                    "'{s}' is not a number of hits per ray: give all or a count of at least 1"
                )),
            },
        }
    }
}

/// Default image width and height.
const DEFAULT_SIZE: usize = 512;

/// Largest image side accepted.
pub const MAX_SIDE: usize = 1 << 15;

impl RenderJob {
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
    let out = job.out_dir();
    let created = output::prepare_tracked_folder(&out)?;
    let names = request::file_names(&job.aovs, &formats, job.rays.is_some(), job.hits.is_some());
    let inputs: Vec<&Path> = std::iter::once(job.scene.as_path())
        .chain(job.rays.as_deref())
        .collect();
    let result = ownership::refuse_inputs(&out, &names, &inputs)
        .and_then(|()| ownership::claim(&out, &job.scene, &names))
        .and_then(|_| run_checked(job, source, &formats, progress));
    if result.is_err() {
        request::remove_created_folder(&out, created.as_deref());
    }
    output::untrack_created_folder(&out);
    result
}

/// [`run`] after the request checks.
fn run_checked(
    job: &RenderJob,
    source: Option<&import::Source>,
    formats: &[Format],
    progress: impl FnMut(Progress) + Send,
) -> Result<Sidecar> {
    let mut ray_warnings = Vec::new();
    let rays = job
        .rays
        .as_deref()
        .map(|path| read_rays(path, job, &mut ray_warnings))
        .transpose()?;
    let started = Instant::now();
    let scene = match source {
        Some(source) => source.at(job.load.time)?,
        None => import::load(&job.scene, &job.load)?,
    };
    let load = started.elapsed().as_secs_f64();
    let mut warnings = scene.warnings.clone();
    warnings.append(&mut ray_warnings);
    let view = match rays {
        Some(_) => None,
        None => Some(camera_view(&scene, job, &mut warnings)?),
    };
    let layout = match (&view, &rays) {
        (Some(v), _) => Layout::Image {
            width: v.width,
            height: v.height,
        },
        (None, rays) => Layout::Rays(rays.as_ref().map_or(0, |r| r.rays.len())),
    };
    let buffers = buffer_bytes(
        &job.aovs,
        formats,
        layout,
        job.hits.map(HitLimit::count),
        rayon::current_num_threads(),
    );
    let what = match layout {
        Layout::Image { width, height } => format!("{width}x{height} pixels"),
        Layout::Rays(n) => format!("{n} rays"),
    };
    check_memory(
        buffers.saturating_add(AccelStructure::estimated_bytes(&scene)),
        job.max_memory,
        &format!(
            "{what} of --aov {} and the {} over {} primitives",
            request::names(&job.aovs),
            job.accel.name(),
            scene.accel_primitive_count()
        ),
    )?;
    let started = Instant::now();
    let accel = AccelStructure::build(&scene, job.accel, job.octree);
    let build = started.elapsed().as_secs_f64();
    let tracer = Tracer {
        scene: &scene,
        accel: accel.view(),
    };
    let total = layout.rays();
    let started = Instant::now();
    // Files are written in parallel; their reports take turns.
    let progress = Mutex::new(progress);
    let report = |event| (progress.lock().unwrap_or_else(|p| p.into_inner()))(event);
    let tracing = |done| report(Progress::Tracing { done, total });
    let (buffers, hits) = match (&rays, &view) {
        (Some(file), _) => trace_all(&tracer, job, file, &file.rays, tracing)?,
        (None, Some(view)) => trace_all(&tracer, job, &RayFile::default(), view, tracing)?,
        (None, None) => unreachable!("camera mode always has a view"),
    };
    let trace = started.elapsed().as_secs_f64();

    let started = Instant::now();
    let mut staging = Staging::for_render(&job.out_dir(), &job.scene)?;
    staging.protect(&job.scene);
    if let Some(rays) = &job.rays {
        staging.protect(rays);
    }
    let depth_png_range = output::write_buffers(
        &mut staging,
        &buffers,
        layout,
        formats,
        job.depth_range,
        |done, files| report(Progress::Writing { done, total: files }),
    )?;
    if let Some(hits) = &hits {
        staging.write(npz::HITS_FILE, |out| npz::write_hits(out, hits))?;
    }
    let write = started.elapsed().as_secs_f64();
    let mut files = staging.names();
    files.push("raycast.json".into());
    let sidecar = Sidecar {
        raycast_version: env!("CARGO_PKG_VERSION"),
        scene: job.scene.display().to_string(),
        scene_file: ownership::scene_key(&job.scene),
        mode: if view.is_some() { "camera" } else { "rays" },
        width: view.as_ref().map(|v| v.width),
        height: view.as_ref().map(|v| v.height),
        rays: view.is_none().then_some(total),
        camera: view
            .as_ref()
            .map(|v| CameraInfo::new(&v.camera, v.width, v.height)),
        aovs: job.aovs.iter().map(|a| a.to_string()).collect(),
        conventions: sidecar::conventions(),
        files,
        hits: job.hits.zip(hits.as_ref()).map(|(limit, lists)| HitsInfo {
            limit: match limit {
                HitLimit::All => None,
                HitLimit::Nearest(n) => Some(n),
            },
            crossings: lists.t.len(),
        }),
        depth_png_range,
        objects: scene.objects.clone(),
        stats: Stats {
            triangles: scene.triangle_count(),
            quadrics: scene.quadrics().len(),
            objects: scene.objects.len(),
            accel: job.accel.name(),
            octree: match &accel {
                AccelStructure::Octree(o) => Some(o.stats()),
                AccelStructure::Bvh(_) => None,
            },
            octree_params: match &accel {
                AccelStructure::Octree(o) => Some(o.params()),
                AccelStructure::Bvh(_) => None,
            },
            bvh: match &accel {
                AccelStructure::Octree(_) => None,
                AccelStructure::Bvh(b) => Some(b.stats()),
            },
        },
        timings: Timings {
            load,
            build,
            trace,
            write,
        },
        stage: scene.stage.clone(),
        decoded: scene.decoded.clone(),
        pose: scene.pose.clone(),
        warnings,
    };
    let json = serde_json::to_string_pretty(&sidecar).map_err(|e| Error::msg(e.to_string()))?;
    staging.write("raycast.json", |out| {
        out.write_all(json.as_bytes())
            .map_err(|e| format!("cannot write: {e}"))
    })?;
    staging.commit()?;
    Ok(sidecar)
}

/// Traces the rays of `source` (with the ranges of `file`, if it has them) into the buffers of
/// the job's AOVs, and lists their crossings when the job asks for hits.
fn trace_all(
    tracer: &Tracer,
    job: &RenderJob,
    file: &RayFile,
    source: &(impl RaySource + ?Sized),
    progress: impl FnMut(usize) + Send,
) -> Result<(Buffers, Option<HitLists>)> {
    let range = |i: usize| {
        file.ranges
            .as_ref()
            .map_or((0.0, f64::INFINITY), |ranges| ranges[i])
    };
    let rays = Rays {
        source,
        range,
        refuse_untraceable: false,
    };
    let buffers = render::trace(tracer, &rays, &job.aovs, progress)
        .map_err(|i| Error::msg(format!("ray {i} cannot be traced")))?;
    let hits = match job.hits {
        Some(limit) => {
            let query = tracer.query().ok_or_else(hits_need_octree)?;
            Some(query.hit_lists(source, range, limit.count()))
        }
        None => None,
    };
    Ok((buffers, hits))
}

/// The error for `--hits` with a BVH.
fn hits_need_octree() -> Error {
    Error::usage("--hits needs --accel octree (the crossing lists are searched in the octree)")
}

/// Reads a ray file. Untraceable rays are misses with one warning, or with `--strict-rays` an
/// error naming the first. Per-ray ranges (an (N, 8) file) need the octree.
fn read_rays(path: &Path, job: &RenderJob, warnings: &mut Vec<String>) -> Result<RayFile> {
    let file = output::npy::read_rays(path)?;
    if file.ranges.is_some() && job.accel != AccelKind::Octree {
        return Err(Error::in_file(
            path,
            format!(
                "per-ray tmin and tmax (an (N, 8) ray file) need --accel octree, not --accel {}",
                job.accel
            ),
        )
        .as_usage());
    }
    if let Some(first) = file.untraceable.first() {
        if job.strict_rays {
            return Err(Error::in_file(path, format!("{first} (--strict-rays)")));
        }
        let n = file.untraceable.len();
        let (rays, counted) = match n {
            1 => ("ray has", "counts as a miss"),
            _ => ("rays have", "count as misses"),
        };
        warnings.push(format!(
            "{}: {n} {rays} a non-finite origin or direction or a zero direction and {counted} \
             (first: {first}); --strict-rays makes this an error",
            path.display(),
        ));
    }
    Ok(file)
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
        None => vec![Format::Exr, Format::Png],
    };
    request::check_files(&job.aovs, &formats, rays_mode)?;
    if job.hits.is_some() && job.accel != AccelKind::Octree {
        return Err(hits_need_octree());
    }
    Ok(formats)
}

/// The camera and image size for camera mode.
/// A file camera whose aspect ratio the image's does not match is said in `warnings`.
fn camera_view(scene: &Scene, job: &RenderJob, warnings: &mut Vec<String>) -> Result<CameraView> {
    let chosen = choose_camera(scene, &job.camera)?;
    let auto = chosen.is_none();
    let mut camera = chosen.unwrap_or_else(|| framing(scene, 1.0));
    if let Some(fov) = job.camera.fov_degrees {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(Error::usage(format!(
                "--fov must lie between 0 and 180 degrees, got {fov}"
            )));
        }
        camera.projection = Projection::Perspective {
            yfov: fov.to_radians(),
        };
    }
    if let Some(height) = job.camera.ortho_height {
        if !(height > 0.0 && height.is_finite()) {
            return Err(Error::usage(format!(
                "--ortho must be a positive height, got {height}"
            )));
        }
        camera.projection = Projection::Orthographic { ymag: height / 2.0 };
    }
    let aspect = camera.aspect_ratio.filter(|a| a.is_finite() && *a > 0.0);
    let from_aspect = |side: usize, a: f64| ((side as f64 * a).round() as usize).max(1);
    let (width, height) = match (job.width, job.height, aspect) {
        (Some(w), Some(h), _) => (w, h),
        (Some(w), None, Some(a)) => (w, from_aspect(w, 1.0 / a)),
        (None, Some(h), Some(a)) => (from_aspect(h, a), h),
        (Some(w), None, None) => (w, w),
        (None, Some(h), None) => (h, h),
        (None, None, Some(a)) => (DEFAULT_SIZE, from_aspect(DEFAULT_SIZE, 1.0 / a)),
        (None, None, None) => (DEFAULT_SIZE, DEFAULT_SIZE),
    };
    if let (Some(a), Some(w), Some(h)) = (aspect, job.width, job.height) {
        let image = w as f64 / h as f64;
        if (image / a - 1.0).abs() > 1e-3 {
            warnings.push(format!(
                "camera '{}' has aspect ratio {a:.4}; the {w}x{h} image ({image:.4}) keeps its \
                 vertical field of view and widens or narrows the horizontal one (give only \
                 --width or --height to keep the camera's aspect)",
                camera.name
            ));
        }
    }
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::usage(format!(
            "image size {width}x{height} is out of range (1 to {MAX_SIDE} per side)"
        )));
    }
    if auto {
        let projection = camera.projection;
        camera = Camera {
            projection,
            ..framing(scene, width as f64 / height as f64)
        };
    }
    Ok(CameraView::new(camera, width, height))
}

/// The automatic camera for an image of width / height `aspect`, upright in the stage's up
/// axis (+Z for a Z-up USD stage, +Y otherwise).
fn framing(scene: &Scene, aspect: f64) -> Camera {
    let up = match &scene.stage {
        Some(stage) if stage.up_axis == "Z" => DVec3::Z,
        _ => DVec3::Y,
    };
    Camera::framing_image(&scene.framing_points(), &scene.world_bounds(), aspect, up)
}

/// The camera asked for, or the file's first; `None` for the automatic framing camera.
fn choose_camera(scene: &Scene, choice: &CameraChoice) -> Result<Option<Camera>> {
    if let Some((eye, target, up)) = choice.look_at {
        let projection = Projection::Perspective { yfov: 0.8 };
        return Camera::look_at(eye, target, up, projection).map(Some);
    }
    let Some(name) = &choice.name else {
        return Ok(scene.cameras.first().cloned());
    };
    scene
        .cameras
        .iter()
        .enumerate()
        .find(|(i, c)| name.parse::<usize>() == Ok(*i) || &c.name == name)
        .map(|(_, c)| Some(c.clone()))
        .ok_or_else(|| Error::in_file(&scene.path, no_camera(name, scene)))
}

/// The message for a camera name that the file does not have: the names it has.
fn no_camera(name: &str, scene: &Scene) -> String {
    if scene.cameras.is_empty() {
        return format!("no camera '{name}': the file has no cameras");
    }
    let names: Vec<String> = scene
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| format!("{i} '{}'", c.name))
        .collect();
    format!(
        "no camera '{name}'; the file's cameras are {}",
        names.join(", ")
    )
}
