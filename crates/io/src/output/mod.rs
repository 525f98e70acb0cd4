//! Writing results: AOV buffers as EXR, PNG and NPY, and the JSON sidecar. Every file is
//! written under a temporary name and renamed into place only when all files are written, so
//! a failed run leaves no half-written output. A render owns the files an earlier render of
//! the same scene file listed in the folder's `raycast.json` ([`ownership`]): those it does not
//! write again are removed; other files in the folder are never touched.

pub mod colormap;
pub mod cryptomatte;
pub mod exr;
pub mod npy;
pub mod npz;
pub mod ownership;
pub mod palette;
pub mod png;
pub mod points;
pub mod request;
pub mod sidecar;

use crate::error::{Error, Result};
use crate::render::{Aov, Buffers};
use npy::NpyData;
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Temporary files of every uncommitted [`Staging`] in this process, for
/// [`remove_partial_files_and_exit`].
static PARTIAL_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Output folders a running render created (the folder, and the outermost folder created for
/// it), removed again by [`remove_partial_files_and_exit`] when they are still empty.
static CREATED_FOLDERS: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

/// Removes the temporary files of every uncommitted staging, and the folders a running render
/// created if nothing else is in them, then exits with `code`; for a signal handler (SIGINT,
/// SIGTERM, SIGHUP). The list stays locked until the process ends, and temporary files are
/// only created under that lock and then written through their open handle (see
/// [`Staging::write`]), so none can reappear in between: a writer still running writes into an
/// unlinked file. A commit renames under the same lock, so it is either done or not begun.
pub fn remove_partial_files_and_exit(code: i32) -> ! {
    let files = PARTIAL_FILES.lock().unwrap_or_else(|p| p.into_inner());
    for file in files.iter() {
        let _ = std::fs::remove_file(file);
    }
    let folders = CREATED_FOLDERS.lock().unwrap_or_else(|p| p.into_inner());
    for (dir, created) in folders.iter() {
        request::remove_created_folder(dir, Some(created));
    }
    std::process::exit(code)
}

/// Creates a render's output folder `dir` if needed and proves it writable
/// ([`request::prepare_folder`]), and records what it created for the interrupt handler, all
/// under the lock of [`CREATED_FOLDERS`]: a signal in between waits for the record, so the
/// folder cannot be left behind (it was, when SIGTERM came right after the folder appeared).
/// Returns the outermost folder created.
pub fn prepare_tracked_folder(dir: &Path) -> Result<Option<PathBuf>> {
    let mut folders = CREATED_FOLDERS.lock().unwrap_or_else(|p| p.into_inner());
    let created = request::prepare_folder(dir)?;
    if let Some(created) = &created {
        folders.push((dir.to_path_buf(), created.clone()));
    }
    Ok(created)
}

/// Forgets the folders recorded for `dir` (the render is over: they hold its outputs, or were
/// removed).
pub fn untrack_created_folder(dir: &Path) {
    let mut folders = CREATED_FOLDERS.lock().unwrap_or_else(|p| p.into_inner());
    folders.retain(|(d, _)| d != dir);
}

/// Creates a temporary file under the lock of [`PARTIAL_FILES`] and adds it there.
fn create_partial(path: &Path) -> std::io::Result<File> {
    let mut files = PARTIAL_FILES.lock().unwrap_or_else(|p| p.into_inner());
    let file = File::create(path)?;
    files.push(path.to_path_buf());
    Ok(file)
}

/// Removes a temporary file from [`PARTIAL_FILES`] (not from the disk).
fn untrack_partial(path: &Path) {
    let mut files = PARTIAL_FILES.lock().unwrap_or_else(|p| p.into_inner());
    files.retain(|f| f != path);
}

/// The files of a `raycast distance` run, its sidecar last.
pub const DISTANCE_FILES: [&str; 7] = [
    "distance.npy",
    "signed_distance.npy",
    "point.npy",
    "id.npy",
    "prim.npy",
    "normal.npy",
    ownership::SIDECAR,
];

/// Whether `name` is a file name raycast writes into an output folder.
fn is_output_name(name: &str) -> bool {
    name == "raycast.json"
        || name == npz::HITS_FILE
        || name == cryptomatte::FILE
        || DISTANCE_FILES.contains(&name)
        || name
            .split_once('.')
            .is_some_and(|(aov, ext)| aov.parse::<Aov>().is_ok() && ext.parse::<Format>().is_ok())
}

/// A file format for buffers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// OpenEXR, full float or uint channels.
    Exr,
    /// PNG preview.
    Png,
    /// NumPy array at full precision.
    Npy,
    /// A PLY point cloud of the hits ([`points`]).
    Ply,
}

impl FromStr for Format {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "exr" => Ok(Format::Exr),
            "png" => Ok(Format::Png),
            "npy" => Ok(Format::Npy),
            "ply" => Ok(Format::Ply),
            _ => Err(Error::msg(format!(
                "unknown format '{s}' (choose from exr, png, npy, ply)"
            ))),
        }
    }
}

/// The layout of the buffers: an image or a list of rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// Row-major pixels, row 0 at the top.
    Image {
        /// Pixels per row.
        width: usize,
        /// Rows.
        height: usize,
    },
    /// One value per input ray.
    Rays(usize),
}

impl Layout {
    /// The number of rays: pixels of an image, or input rays.
    pub fn rays(self) -> usize {
        match self {
            Layout::Image { width, height } => width * height,
            Layout::Rays(n) => n,
        }
    }
}

/// Encodes one file into its open temporary file; the error is a one-line message.
type Encoder<'a> = Box<dyn FnOnce(&mut BufWriter<File>) -> Result<()> + Send + 'a>;

/// One file for [`Staging::write_all`]: its final name and how to encode it.
pub struct FileJob<'a> {
    name: String,
    body: Encoder<'a>,
}

impl<'a> FileJob<'a> {
    /// A file named `name` whose content `body` writes.
    pub fn new(
        name: impl Into<String>,
        body: impl FnOnce(&mut BufWriter<File>) -> Result<()> + Send + 'a,
    ) -> FileJob<'a> {
        FileJob {
            name: name.into(),
            body: Box::new(body),
        }
    }
}

/// Files being written into one folder; nothing appears under its final name before
/// [`Staging::commit`], and dropping an uncommitted staging removes its temporary files.
#[derive(Debug)]
pub struct Staging {
    dir: PathBuf,
    files: Vec<(PathBuf, String)>,
    protected: Vec<PathBuf>,
    /// For a render's output folder: the scene file whose earlier outputs there this run
    /// replaces (see [`ownership`]).
    scene: Option<PathBuf>,
}

impl Staging {
    /// Prepares `dir` (created if missing) for files written among others: committing
    /// replaces only the staged names and never removes anything (reports of `raycast
    /// check`, golden buffers).
    pub fn new(dir: &Path) -> Result<Staging> {
        std::fs::create_dir_all(dir)
            .map_err(|e| Error::in_file(dir, format!("cannot create output folder: {e}")))?;
        Ok(Staging {
            dir: dir.to_path_buf(),
            files: Vec::new(),
            protected: Vec::new(),
            scene: None,
        })
    }

    /// Prepares `dir` (created if missing) as the output folder of a render of `scene`:
    /// committing claims the folder again ([`ownership::claim`]) and removes the files an
    /// earlier render of the same scene listed that this one did not write.
    pub fn for_render(dir: &Path, scene: &Path) -> Result<Staging> {
        let mut staging = Staging::new(dir)?;
        staging.scene = Some(scene.to_path_buf());
        Ok(staging)
    }

    /// Marks an input file that must never be replaced by an output.
    pub fn protect(&mut self, input: &Path) {
        if let Ok(path) = input.canonicalize() {
            self.protected.push(path);
        }
    }

    /// Writes the file `name` under a temporary name: `body` gets the open file, and its
    /// error message is reported with the file's final path.
    pub fn write(
        &mut self,
        name: &str,
        body: impl FnOnce(&mut BufWriter<File>) -> Result<()> + Send,
    ) -> Result<()> {
        self.write_all(vec![FileJob::new(name, body)], |_| {})
    }

    /// Writes the files of `jobs` in parallel, each under a temporary name; `written(n)` is
    /// called each time a file is complete, with the number complete so far. The temporary
    /// files are all created (in order) before any is written.
    pub fn write_all(
        &mut self,
        jobs: Vec<FileJob<'_>>,
        written: impl Fn(usize) + Sync,
    ) -> Result<()> {
        let mut files = Vec::with_capacity(jobs.len());
        for job in &jobs {
            files.push(self.create(&job.name)?);
        }
        let complete = AtomicUsize::new(0);
        jobs.into_par_iter()
            .zip(files)
            .try_for_each(|(job, (file, target))| {
                let mut out = BufWriter::new(file);
                (job.body)(&mut out)
                    .and_then(|()| {
                        out.flush()
                            .map_err(|e| Error::msg(format!("cannot write: {e}")))
                    })
                    .map_err(|e| e.with_path(&target))?;
                written(complete.fetch_add(1, Ordering::Relaxed) + 1);
                Ok(())
            })
    }

    /// Creates the temporary file for `name`; returns it and the file's final path.
    fn create(&mut self, name: &str) -> Result<(File, PathBuf)> {
        let target = self.dir.join(name);
        let temp = self
            .dir
            .join(format!(".{name}.partial-{}", std::process::id()));
        let file = create_partial(&temp)
            .map_err(|e| Error::in_file(&target, format!("cannot write: {e}")))?;
        self.files.push((temp, name.to_string()));
        Ok((file, target))
    }

    /// Final names of the files staged so far.
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(_, name)| name.clone()).collect()
    }

    /// Renames every staged file to its final name (`raycast.json`, staged last, last of all),
    /// then, for a render, removes the files an earlier render of the same scene listed in the
    /// folder's `raycast.json` that this one did not write. Refuses, before renaming anything,
    /// when a final name is one of the protected inputs, or when the folder is no longer this
    /// scene's to write (another run wrote there meanwhile).
    pub fn commit(mut self) -> Result<()> {
        let written = self.names();
        let earlier = match &self.scene {
            Some(scene) => ownership::claim(&self.dir, scene, &written)?.listed,
            None => Vec::new(),
        };
        for (_, name) in &self.files {
            let target = self.dir.join(name);
            if target
                .canonicalize()
                .is_ok_and(|t| self.protected.contains(&t))
            {
                return Err(Error::in_file(
                    &target,
                    "is an input of this run; choose another --out folder",
                ));
            }
        }
        // Renamed under the lock of the interrupt handler: an interrupt waits until every
        // file is in place, so it never leaves a temporary file or half the set renamed.
        let mut partial = PARTIAL_FILES.lock().unwrap_or_else(|p| p.into_inner());
        while !self.files.is_empty() {
            let (temp, name) = self.files.remove(0);
            let target = self.dir.join(&name);
            partial.retain(|f| f != &temp);
            if let Err(e) = std::fs::rename(&temp, &target) {
                let _ = std::fs::remove_file(&temp);
                drop(partial);
                // the rest are removed by `drop(self)`
                return Err(Error::in_file(
                    &target,
                    format!("cannot move into place: {e}"),
                ));
            }
        }
        drop(partial);
        for stale in earlier.iter().filter(|name| !written.contains(name)) {
            let _ = std::fs::remove_file(self.dir.join(stale));
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        for (temp, _) in &self.files {
            untrack_partial(temp);
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// Writes every buffer of `buffers` in every format of `formats` (EXR and PNG only for
/// images), encoding the files in parallel; `written(done, total)` is called as files complete.
/// The distance previews map `pngs.depth_range` (default: the 1st to 99th percentile of the
/// finite values, see [`png::percentile_range`]); depth and z are 16-bit integers instead
/// with [`png::DistancePng::U16`]. Returns the depth range mapped into `depth.png`, if one
/// was written as a preview.
pub fn write_buffers(
    staging: &mut Staging,
    buffers: &Buffers,
    layout: Layout,
    formats: &[Format],
    pngs: PngOptions,
    written: impl Fn(usize, usize) + Sync,
) -> Result<Option<[f64; 2]>> {
    let mut written_range = None;
    let mut jobs = Vec::new();
    for format in request::merge_formats(formats) {
        for aov in Aov::ALL {
            let Some(values) = values(buffers, aov) else {
                continue;
            };
            if !format.holds(aov, matches!(layout, Layout::Rays(_))) {
                continue;
            }
            let job = match (format, layout) {
                (Format::Npy, _) => Some(npy_job(values, aov, layout)),
                (Format::Exr, Layout::Image { width, height }) => {
                    Some(exr_job(values, aov, width, height))
                }
                (Format::Png, Layout::Image { width, .. }) => {
                    let (job, range) = png_job(values, aov, width, pngs);
                    written_range = written_range.or(range);
                    job
                }
                (Format::Exr | Format::Png, Layout::Rays(_)) => None,
                (Format::Ply, _) if aov == Aov::Position => {
                    Some(FileJob::new(points::FILE.to_string(), move |out| {
                        points::write(out, buffers)
                    }))
                }
                (Format::Ply, _) => None,
            };
            jobs.extend(job);
        }
    }
    let total = jobs.len();
    written(0, total);
    staging.write_all(jobs, |done| written(done, total))?;
    Ok(written_range)
}

fn shape(layout: Layout, components: usize) -> Vec<usize> {
    let mut shape = match layout {
        Layout::Image { width, height } => vec![height, width],
        Layout::Rays(n) => vec![n],
    };
    if components > 1 {
        shape.push(components);
    }
    shape
}

/// The values of one computed AOV.
#[derive(Debug, Clone, Copy)]
enum Values<'a> {
    /// Distances (depth, z, t).
    Distances(&'a [f64]),
    /// Pairs (uv).
    Pairs(&'a [[f64; 2]]),
    /// Vectors (normal, position, bary, shading normal).
    Vectors(&'a [[f64; 3]]),
    /// Labels (id, prim, material).
    Labels(&'a [u32]),
    /// Flags (certain).
    Flags(&'a [u8]),
}

/// The values of `aov`, if it was computed.
fn values(b: &Buffers, aov: Aov) -> Option<Values<'_>> {
    b.floats(aov)
        .map(Values::Distances)
        .or_else(|| b.pairs(aov).map(Values::Pairs))
        .or_else(|| b.vectors(aov).map(Values::Vectors))
        .or_else(|| b.labels(aov).map(Values::Labels))
        .or_else(|| b.flags(aov).map(Values::Flags))
}

/// The `.npy` file of `aov`: float64, uint32 or uint8, one row per pixel or ray.
fn npy_job(values: Values<'_>, aov: Aov, layout: Layout) -> FileJob<'_> {
    let components = match values {
        Values::Pairs(_) => 2,
        Values::Vectors(_) => 3,
        _ => 1,
    };
    let shape = shape(layout, components);
    FileJob::new(format!("{aov}.npy"), move |out| match values {
        Values::Distances(v) => npy::write(out, &shape, NpyData::F64(v)),
        Values::Pairs(v) => npy::write(out, &shape, NpyData::F64(v.as_flattened())),
        Values::Vectors(v) => npy::write(out, &shape, NpyData::F64(v.as_flattened())),
        Values::Labels(v) => npy::write(out, &shape, NpyData::U32(v)),
        Values::Flags(v) => npy::write(out, &shape, NpyData::U8(v)),
    })
}

/// The convention written into each EXR header.
fn exr_note(aov: Aov) -> &'static str {
    match aov {
        Aov::Depth => "Z = distance from the ray origin to the hit along the ray (|hit - origin|), scene units; miss = +inf",
        Aov::T => "Z = ray parameter t of the hit, hit = origin + t * direction (units of |direction|); miss = +inf",
        Aov::Bary => "B = barycentric weights (w0, w1, w2) of the hit triangle's vertices in the mesh's order; miss or quadric = (0,0,0)",
        Aov::Z => "Z = camera-space depth along the view axis, scene units; miss = +inf",
        Aov::Normal => "N = world-space unit geometric normal (counter-clockwise winding is front; quadrics: toward f > 0); miss = (0,0,0)",
        Aov::Position => "P = world-space hit point; miss = (+inf,+inf,+inf)",
        Aov::Id => "id = 1-based object id from raycast.json objects; 0 = miss",
        Aov::Prim => "prim = triangle index inside the object (0 for quadrics); 4294967295 = miss",
        Aov::Error => "Z = bound on |depth - exact depth| of the same primitive's crossing, scene units, rounded up to f32 (depth.exr's own f32 rounding is not included); +inf = no bound; miss = 0",
        Aov::Certain => "certain = 1 when no value within the bounds could change the decision (nearest primitive, hit or miss), else 0",
        Aov::Uv => "UV = the file's texture coordinates (TEXCOORD_0, vt, primvars:st) interpolated at the hit, as stored (glTF: origin top left; no flip); miss, quadric or none in the file = (+inf,+inf)",
        Aov::ShadingNormal => "Ns = world-space unit shading normal: the file's normals interpolated, by the inverse transpose of the placement; quadrics: analytic normal; miss or none in the file = (0,0,0)",
        Aov::Material => "material = 1-based index into raycast.json materials; 0 = miss or no material",
    }
}

/// The `.exr` file of `aov`: f32 channels for distances and vectors (narrowed while
/// encoding), UINT channels for labels.
fn exr_job(values: Values<'_>, aov: Aov, width: usize, height: usize) -> FileJob<'_> {
    use exr::ExrChannel::{Float, Uint};
    FileJob::new(format!("{aov}.exr"), move |out| {
        let channels = match values {
            Values::Distances(v) if aov == Aov::Error => {
                vec![Float("Z".into(), v.iter().map(|&x| f32_up(x)).collect())]
            }
            Values::Distances(v) => vec![Float("Z".into(), v.iter().map(|&x| x as f32).collect())],
            Values::Pairs(v) => (0..2)
                .map(|c| {
                    let name = ["UV.U", "UV.V"][c];
                    Float(name.into(), v.iter().map(|p| p[c] as f32).collect())
                })
                .collect(),
            Values::Vectors(v) => {
                let names = match aov {
                    Aov::Normal => ["N.X", "N.Y", "N.Z"],
                    Aov::ShadingNormal => ["Ns.X", "Ns.Y", "Ns.Z"],
                    Aov::Bary => ["B.X", "B.Y", "B.Z"],
                    _ => ["P.X", "P.Y", "P.Z"],
                };
                (0..3)
                    .map(|c| Float(names[c].into(), v.iter().map(|p| p[c] as f32).collect()))
                    .collect()
            }
            Values::Labels(v) => vec![Uint(aov.name().into(), v.to_vec())],
            Values::Flags(v) => vec![Uint(
                "certain".into(),
                v.iter().map(|&x| x.into()).collect(),
            )],
        };
        let note = [("raycast/convention".to_string(), exr_note(aov).to_string())];
        exr::write(out, width, height, channels, &note)
    })
}

/// `x` narrowed to the nearest f32 at or above it (a bound stays a bound).
fn f32_up(x: f64) -> f32 {
    let narrow = x as f32;
    if f64::from(narrow) < x {
        narrow.next_up()
    } else {
        narrow
    }
}

/// How the PNG files of distances are written.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PngOptions {
    /// The distances the depth and z previews map, near to far; `None` for the 1st to 99th
    /// percentile of the hits.
    pub depth_range: Option<[f64; 2]>,
    /// Previews, or 16-bit integers, for depth and z.
    pub distances: png::DistancePng,
    /// The colour map of the distance previews (depth, z, t).
    pub colormap: colormap::Colormap,
}

/// The `.png` preview of `aov` (position and bary have none), and for depth the range it maps.
/// `pngs.depth_range` (scene units) applies to depth and z; `t`, in units of each ray's
/// direction, maps its own percentile range. Depth and z are 16-bit integers with
/// [`png::DistancePng::U16`].
fn png_job(
    values: Values<'_>,
    aov: Aov,
    width: usize,
    pngs: PngOptions,
) -> (Option<FileJob<'_>>, Option<[f64; 2]>) {
    let name = format!("{aov}.png");
    match (values, pngs.distances) {
        (Values::Distances(v), png::DistancePng::U16 { scale }) if aov != Aov::T => {
            let job = FileJob::new(name, move |out| {
                png::write(out, png::distance_u16(v, width, scale))
            });
            (Some(job), None)
        }
        (values, _) => preview_job(values, aov, width, pngs),
    }
}

/// The `.png` preview of `aov`, and for depth the range it maps (see [`png_job`]).
fn preview_job(
    values: Values<'_>,
    aov: Aov,
    width: usize,
    pngs: PngOptions,
) -> (Option<FileJob<'_>>, Option<[f64; 2]>) {
    let name = format!("{aov}.png");
    match values {
        Values::Distances(v) => {
            let range = (pngs.depth_range)
                .filter(|_| aov != Aov::T)
                .or_else(|| png::percentile_range(v))
                .unwrap_or([0.0, 1.0]);
            let job = FileJob::new(name, move |out| match pngs.colormap {
                colormap::Colormap::Grey => png::write(out, png::distance_image(v, width, range)),
                map => png::write(out, colormap::distance_image(v, width, range, map)),
            });
            (Some(job), (aov == Aov::Depth).then_some(range))
        }
        Values::Pairs(_) => (None, None),
        Values::Vectors(_) if !matches!(aov, Aov::Normal | Aov::ShadingNormal) => (None, None),
        Values::Vectors(v) => {
            let job = FileJob::new(name, move |out| {
                png::write(out, png::normal_image(v, width))
            });
            (Some(job), None)
        }
        Values::Labels(v) => {
            let miss = if aov == Aov::Prim { u32::MAX } else { 0 };
            let job = FileJob::new(name, move |out| {
                png::write(out, png::label_image(v, width, miss))
            });
            (Some(job), None)
        }
        Values::Flags(_) => (None, None),
    }
}
