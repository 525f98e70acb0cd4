//! Writing results: AOV buffers as EXR, PNG and NPY, and the JSON sidecar. Every file is
//! written under a temporary name and renamed into place only when all files are written, so
//! a failed run leaves no half-written output. A run owns the files an earlier run listed in
//! the folder's `raycast.json`: those it does not write again are removed; other files in the
//! folder are never touched.

pub mod exr;
pub mod npy;
pub mod png;
pub mod request;
pub mod sidecar;

use crate::error::{Error, Result};
use crate::render::{Aov, Buffers};
use glam::DVec3;
use npy::NpyData;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;

/// Temporary files of every uncommitted [`Staging`] in this process, for
/// [`remove_partial_files`].
static PARTIAL_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Removes the temporary files of every uncommitted staging and exits with `code`; for an
/// interrupt handler (Ctrl-C). The list stays locked until the process ends, and temporary
/// files are only created under that lock and then written through their open handle (see
/// [`Staging::write`]), so none can reappear in between: a writer still running writes into an
/// unlinked file.
pub fn remove_partial_files_and_exit(code: i32) -> ! {
    let files = PARTIAL_FILES.lock().unwrap_or_else(|p| p.into_inner());
    for file in files.iter() {
        let _ = std::fs::remove_file(file);
    }
    std::process::exit(code)
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

/// Whether `name` is a file name raycast writes into an output folder.
fn is_output_name(name: &str) -> bool {
    name == "raycast.json"
        || name
            .split_once('.')
            .is_some_and(|(aov, ext)| aov.parse::<Aov>().is_ok() && ext.parse::<Format>().is_ok())
}

/// The output files an earlier run listed in `dir/raycast.json` (only names raycast writes).
fn earlier_outputs(dir: &Path) -> Vec<String> {
    let Ok(text) = std::fs::read(dir.join("raycast.json")) else {
        return Vec::new();
    };
    let Ok(json) = serde_json::from_slice::<serde_json::Value>(&text) else {
        return Vec::new();
    };
    json["files"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|f| f.as_str())
        .filter(|f| is_output_name(f))
        .map(str::to_string)
        .collect()
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
}

impl FromStr for Format {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "exr" => Ok(Format::Exr),
            "png" => Ok(Format::Png),
            "npy" => Ok(Format::Npy),
            _ => Err(format!("unknown format '{s}' (choose from exr, png, npy)")),
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

/// Files being written into one folder; nothing appears under its final name before
/// [`Staging::commit`], and dropping an uncommitted staging removes its temporary files.
#[derive(Debug)]
pub struct Staging {
    dir: PathBuf,
    files: Vec<(PathBuf, String)>,
    protected: Vec<PathBuf>,
}

impl Staging {
    /// Prepares `dir` (created if missing).
    pub fn new(dir: &Path) -> Result<Staging> {
        std::fs::create_dir_all(dir)
            .map_err(|e| Error::in_file(dir, format!("cannot create output folder: {e}")))?;
        Ok(Staging {
            dir: dir.to_path_buf(),
            files: Vec::new(),
            protected: Vec::new(),
        })
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
        body: impl FnOnce(&mut BufWriter<File>) -> std::result::Result<(), String>,
    ) -> Result<()> {
        let target = self.dir.join(name);
        let temp = self
            .dir
            .join(format!(".{name}.partial-{}", std::process::id()));
        let file = create_partial(&temp)
            .map_err(|e| Error::in_file(&target, format!("cannot write: {e}")))?;
        self.files.push((temp, name.to_string()));
        let mut out = BufWriter::new(file);
        body(&mut out)
            .and_then(|()| out.flush().map_err(|e| format!("cannot write: {e}")))
            .map_err(|message| Error::in_file(&target, message))
    }

    /// Final names of the files staged so far.
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(_, name)| name.clone()).collect()
    }

    /// Renames every staged file to its final name (`raycast.json`, staged last, last of all),
    /// then removes the files an earlier run listed in the folder's `raycast.json` that this
    /// run did not write. Refuses, before renaming anything, when a final name is one of the
    /// protected inputs.
    pub fn commit(mut self) -> Result<()> {
        let earlier = earlier_outputs(&self.dir);
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
        let written = self.names();
        for (temp, name) in std::mem::take(&mut self.files) {
            let target = self.dir.join(&name);
            untrack_partial(&temp);
            if let Err(e) = std::fs::rename(&temp, &target) {
                let _ = std::fs::remove_file(&temp);
                return Err(Error::in_file(
                    &target,
                    format!("cannot move into place: {e}"),
                ));
            }
        }
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
/// images). The distance previews map `depth_range` (default: the 1st to 99th percentile of the
/// finite values, see [`png::percentile_range`]). Returns the depth range mapped into
/// `depth.png`, if one was written.
pub fn write_buffers(
    staging: &mut Staging,
    buffers: &Buffers,
    layout: Layout,
    formats: &[Format],
    depth_range: Option<[f64; 2]>,
) -> Result<Option<[f64; 2]>> {
    let mut written_range = None;
    for format in request::merge_formats(formats) {
        for aov in Aov::ALL {
            match (format, layout) {
                (Format::Npy, _) => write_npy(staging, buffers, aov, layout)?,
                (Format::Exr, Layout::Image { width, height }) => {
                    write_exr(staging, buffers, aov, width, height)?
                }
                (Format::Png, Layout::Image { width, .. }) => {
                    if let Some(range) = write_png(staging, buffers, aov, width, depth_range)? {
                        written_range = written_range.or(Some(range));
                    }
                }
                (Format::Exr | Format::Png, Layout::Rays(_)) => {}
            }
        }
    }
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

fn flatten(v: &[DVec3]) -> Vec<f64> {
    v.iter().flat_map(|p| p.to_array()).collect()
}

fn write_npy(staging: &mut Staging, b: &Buffers, aov: Aov, layout: Layout) -> Result<()> {
    let name = format!("{aov}.npy");
    let scalar = |v: &Option<Vec<f64>>| v.as_ref().map(|v| (v.clone(), 1));
    let vector = |v: &Option<Vec<DVec3>>| v.as_ref().map(|v| (flatten(v), 3));
    let (floats, ints) = match aov {
        Aov::Depth => (scalar(&b.depth), None),
        Aov::Z => (scalar(&b.z), None),
        Aov::Normal => (vector(&b.normal), None),
        Aov::Position => (vector(&b.position), None),
        Aov::Id => (None, b.id.as_ref()),
        Aov::Prim => (None, b.prim.as_ref()),
    };
    let (shape, data) = match (&floats, ints) {
        (Some((data, components)), _) => (shape(layout, *components), NpyData::F64(data)),
        (None, Some(data)) => (shape(layout, 1), NpyData::U32(data)),
        (None, None) => return Ok(()),
    };
    staging.write(&name, |out| npy::write(out, &shape, data))
}

/// The convention written into each EXR header.
fn exr_note(aov: Aov) -> &'static str {
    match aov {
        Aov::Depth => "Z = distance from the ray origin to the hit along the ray (|hit - origin|), scene units; miss = +inf",
        Aov::Z => "Z = camera-space depth along the view axis, scene units; miss = +inf",
        Aov::Normal => "N = world-space unit geometric normal (counter-clockwise winding is front; quadrics: toward f > 0); miss = (0,0,0)",
        Aov::Position => "P = world-space hit point; miss = (+inf,+inf,+inf)",
        Aov::Id => "id = 1-based object id from raycast.json objects; 0 = miss",
        Aov::Prim => "prim = triangle index inside the object (0 for quadrics); 4294967295 = miss",
    }
}

fn write_exr(
    staging: &mut Staging,
    b: &Buffers,
    aov: Aov,
    width: usize,
    height: usize,
) -> Result<()> {
    use exr::ExrChannel::{Float, Uint};
    let narrow = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    let split = |v: &[DVec3], names: [&'static str; 3]| {
        (0..3)
            .map(|c| Float(names[c], v.iter().map(|p| p[c] as f32).collect()))
            .collect::<Vec<_>>()
    };
    let channels = match aov {
        Aov::Depth => b.depth.as_ref().map(|v| vec![Float("Z", narrow(v))]),
        Aov::Z => b.z.as_ref().map(|v| vec![Float("Z", narrow(v))]),
        Aov::Normal => b.normal.as_ref().map(|v| split(v, ["N.X", "N.Y", "N.Z"])),
        Aov::Position => b.position.as_ref().map(|v| split(v, ["P.X", "P.Y", "P.Z"])),
        Aov::Id => b.id.as_ref().map(|v| vec![Uint("id", v.clone())]),
        Aov::Prim => b.prim.as_ref().map(|v| vec![Uint("prim", v.clone())]),
    };
    let Some(channels) = channels else {
        return Ok(());
    };
    let note = [("raycast/convention", exr_note(aov).to_string())];
    staging.write(&format!("{aov}.exr"), |out| {
        exr::write(out, width, height, channels, &note)
    })
}

fn write_png(
    staging: &mut Staging,
    b: &Buffers,
    aov: Aov,
    width: usize,
    depth_range: Option<[f64; 2]>,
) -> Result<Option<[f64; 2]>> {
    let distance = |v: &Vec<f64>| {
        let range = depth_range
            .or_else(|| png::percentile_range(v))
            .unwrap_or([0.0, 1.0]);
        (png::distance_image(v, width, range), Some(range))
    };
    let image = match aov {
        Aov::Depth => b.depth.as_ref().map(distance),
        Aov::Z => b.z.as_ref().map(|v| (distance(v).0, None)),
        Aov::Normal => b
            .normal
            .as_ref()
            .map(|v| (png::normal_image(v, width), None)),
        Aov::Position => None,
        Aov::Id => b.id.as_ref().map(|v| (png::label_image(v, width, 0), None)),
        Aov::Prim => b
            .prim
            .as_ref()
            .map(|v| (png::label_image(v, width, u32::MAX), None)),
    };
    let Some((image, range)) = image else {
        return Ok(None);
    };
    staging.write(&format!("{aov}.png"), |out| png::write(out, &image))?;
    Ok(range)
}
