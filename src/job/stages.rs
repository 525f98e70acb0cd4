//! The stages of a render run: read the scene (and the ray file), choose what to trace, check
//! the memory, build the acceleration structure, trace and write. A single run goes through
//! them once ([`run_checked`]); a run of many views ([`super::views`]) reads and builds once
//! and traces each view.

use super::view::camera_view;
use super::{HitLimit, Progress, RenderJob};
use crate::error::{Error, Result};
use crate::geometry::RaySource;
use crate::import;
use crate::import::npy::RayFile;
use crate::output::colormap::Colormap;
use crate::output::cryptomatte;
use crate::output::png::DistancePng;
use crate::output::request::{self, buffer_bytes, check_memory};
use crate::output::sidecar::{self, CameraInfo, HitsInfo, Sidecar, Stats, Timings};
use crate::output::{self, npz, ownership, Format, Layout, Staging};

use crate::accel::Octree;
use crate::render::Rays;
use crate::render::{self, Buffers, CameraView};
use crate::scene::Scene;
use crate::trace::{self, HitLists, Tracer};
use std::io::Write;
use std::path::Path;
use std::sync::Mutex;
use std::time::Instant;

/// [`super::run`] after the request checks.
pub(super) fn run_checked(
    job: &RenderJob,
    source: Option<&import::Source>,
    formats: &[Format],
    progress: impl FnMut(Progress) + Send,
) -> Result<Sidecar> {
    let loaded = load(job, source)?;
    let target = target(job, &loaded)?;
    check_memory_for(job, formats, target.layout, &loaded.scene)?;
    let built = build(job, &loaded.scene);
    trace_and_write(job, formats, &loaded, &built, &target, progress)
}

/// A scene read for a run, with its ray file in rays mode.
pub(super) struct Loaded {
    /// The scene.
    pub scene: Scene,
    /// The ray file (rays mode).
    pub rays: Option<RayFile>,
    /// What reading the scene and the rays said.
    pub warnings: Vec<String>,
    /// Seconds taken to read the scene.
    pub seconds: f64,
}

/// Reads the job's ray file and scene (posed from `source` at the job's time, when given).
pub(super) fn load(job: &RenderJob, source: Option<&import::Source>) -> Result<Loaded> {
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
    let seconds = started.elapsed().as_secs_f64();
    let mut warnings: Vec<String> = scene.warnings.iter().map(ToString::to_string).collect();
    warnings.append(&mut ray_warnings);
    warnings.extend(render::attribute_warnings(&scene, &job.aovs));
    Ok(Loaded {
        scene,
        rays,
        warnings,
        seconds,
    })
}

/// What a run traces: a camera's view, or (rays mode) the ray file's rays.
pub(super) struct Target {
    /// The camera's view (camera mode).
    pub view: Option<CameraView>,
    /// The buffers' shape.
    pub layout: Layout,
    /// The scene's and the rays' warnings, then the camera's.
    pub warnings: Vec<String>,
}

/// The job's camera view over `loaded`'s scene, or its rays.
pub(super) fn target(job: &RenderJob, loaded: &Loaded) -> Result<Target> {
    let mut warnings = loaded.warnings.clone();
    let view = match loaded.rays {
        Some(_) => None,
        None => Some(camera_view(&loaded.scene, job, &mut warnings)?),
    };
    let layout = match (&view, &loaded.rays) {
        (Some(v), _) => Layout::Image {
            width: v.width,
            height: v.height,
        },
        (None, rays) => Layout::Rays(rays.as_ref().map_or(0, |r| r.rays.len())),
    };
    Ok(Target {
        view,
        layout,
        warnings,
    })
}

/// Refuses a run whose buffers of `layout` and acceleration structure over `scene` need
/// more memory than the job allows.
pub(super) fn check_memory_for(
    job: &RenderJob,
    formats: &[Format],
    layout: Layout,
    scene: &Scene,
) -> Result<()> {
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
        buffers.saturating_add(trace::estimated_build_bytes(scene)),
        job.max_memory,
        &format!(
            "{what} of --aov {} and the octree over {} primitives",
            request::names(&job.aovs),
            scene.accel_primitive_count()
        ),
    )
}

/// The octree built for a run.
pub(super) struct Built {
    /// The octree.
    pub octree: Octree,
    /// Seconds taken to build it.
    pub seconds: f64,
}

/// Builds the job's octree over `scene`.
pub(super) fn build(job: &RenderJob, scene: &Scene) -> Built {
    let started = Instant::now();
    let octree = trace::build_octree(scene, job.octree);
    Built {
        octree,
        seconds: started.elapsed().as_secs_f64(),
    }
}

/// Traces `target` through `built` and writes the job's files and sidecar.
pub(super) fn trace_and_write(
    job: &RenderJob,
    formats: &[Format],
    loaded: &Loaded,
    built: &Built,
    target: &Target,
    progress: impl FnMut(Progress) + Send,
) -> Result<Sidecar> {
    let scene = &loaded.scene;
    let tracer = Tracer::new(scene, &built.octree);
    let (view, layout) = (&target.view, target.layout);
    let total = layout.rays();
    let started = Instant::now();
    // Files are written in parallel; their reports take turns.
    let progress = Mutex::new(progress);
    let report = |event| (progress.lock().unwrap_or_else(|p| p.into_inner()))(event);
    let tracing = |done| report(Progress::Tracing { done, total });
    let (buffers, hits) = match (&loaded.rays, view) {
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
        job.pngs,
        |done, files| report(Progress::Writing { done, total: files }),
    )?;
    if let Some(hits) = &hits {
        staging.write(npz::HITS_FILE, |out| npz::write_hits(out, hits))?;
    }
    if let (Some(spp), Some(view)) = (job.cryptomatte, view) {
        let layers = super::cryptomatte::mattes(&tracer, view, spp)?;
        staging.write(cryptomatte::FILE, |out| {
            cryptomatte::write(out, view.width, view.height, &layers)
        })?;
    }
    let mut files = staging.names();
    files.push("raycast.json".into());
    let timings = Timings {
        load: loaded.seconds,
        build: built.seconds,
        trace,
        write: started.elapsed().as_secs_f64(),
    };
    let written = Written {
        files,
        bounds: sidecar::BoundsInfo::of(&buffers),
        hits: hits.as_ref(),
        depth_png_range,
        timings,
    };
    let sidecar = sidecar(job, scene, &built.octree, target, written);
    let json = serde_json::to_string_pretty(&sidecar).map_err(|e| Error::msg(e.to_string()))?;
    staging.write("raycast.json", |out| {
        out.write_all(json.as_bytes())
            .map_err(|e| Error::msg(format!("cannot write: {e}")))
    })?;
    staging.commit()?;
    Ok(sidecar)
}

/// What tracing and writing gave, for the sidecar.
struct Written<'a> {
    files: Vec<String>,
    bounds: Option<sidecar::BoundsInfo>,
    hits: Option<&'a HitLists>,
    depth_png_range: Option<[f64; 2]>,
    timings: Timings,
}

/// The sidecar of a run of `job` over `scene`.
fn sidecar(
    job: &RenderJob,
    scene: &Scene,
    octree: &Octree,
    target: &Target,
    written: Written,
) -> Sidecar {
    let view = &target.view;
    let total = target.layout.rays();
    let Written {
        files,
        bounds,
        hits,
        depth_png_range,
        timings,
    } = written;
    Sidecar {
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
        hits: job.hits.zip(hits).map(|(limit, lists)| HitsInfo {
            limit: match limit {
                HitLimit::All => None,
                HitLimit::Nearest(n) => Some(n),
            },
            crossings: lists.t.len(),
        }),
        depth_png_range,
        depth_png_colormap: Some(job.pngs.colormap.name())
            .filter(|_| job.pngs.colormap != Colormap::Grey),
        depth_png_scale: match job.pngs.distances {
            DistancePng::U16 { scale } => Some(scale),
            DistancePng::Preview => None,
        },
        cryptomatte_spp: job.cryptomatte.filter(|_| view.is_some()),
        bounds,
        objects: scene.objects.clone(),
        materials: (job.aovs.contains(&render::Aov::Material) || job.cryptomatte.is_some())
            .then(|| scene.materials().to_vec()),
        stats: Stats {
            triangles: scene.triangle_count(),
            quadrics: scene.quadrics().len(),
            objects: scene.objects.len(),
            accel: "octree",
            octree: octree.stats(),
            octree_params: octree.params(),
        },
        timings,
        stage: scene.stage.clone(),
        decoded: scene.decoded.clone(),
        pose: scene.pose.clone(),
        warnings: target.warnings.clone(),
    }
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
    let hits = job
        .hits
        .map(|limit| tracer.hit_lists(source, range, limit.count()));
    Ok((buffers, hits))
}

/// Reads a ray file. Untraceable rays are misses with one warning, or with `--strict-rays` an
/// error naming the first.
fn read_rays(path: &Path, job: &RenderJob, warnings: &mut Vec<String>) -> Result<RayFile> {
    let file = crate::import::npy::read_rays(path)?;
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
