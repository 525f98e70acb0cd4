//! Writing results: AOV buffers as EXR, PNG and NPY, and the JSON sidecar. Every file is
//! written under a temporary name and renamed into place only when all files are written, so
//! a failed run leaves no half-written output.

pub mod exr;
pub mod npy;
pub mod png;
pub mod sidecar;

use crate::error::{Error, Result};
use crate::render::{Aov, Buffers};
use glam::DVec3;
use npy::NpyData;
use std::path::{Path, PathBuf};
use std::str::FromStr;

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

    /// Temporary path to write the file `name` to.
    pub fn file(&mut self, name: &str) -> PathBuf {
        let temp = self
            .dir
            .join(format!(".{name}.partial-{}", std::process::id()));
        self.files.push((temp.clone(), name.to_string()));
        temp
    }

    /// Final names of the files staged so far.
    pub fn names(&self) -> Vec<String> {
        self.files.iter().map(|(_, name)| name.clone()).collect()
    }

    /// Renames every staged file to its final name; refuses, before renaming anything, when a
    /// final name is one of the protected inputs.
    pub fn commit(mut self) -> Result<()> {
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
        for (temp, name) in std::mem::take(&mut self.files) {
            let target = self.dir.join(&name);
            std::fs::rename(&temp, &target)
                .map_err(|e| Error::in_file(&target, format!("cannot move into place: {e}")))?;
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        for (temp, _) in &self.files {
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// Writes every buffer of `buffers` in every format of `formats` (EXR and PNG only for
/// images). Returns the depth range mapped into `depth.png`, if one was written.
pub fn write_buffers(
    staging: &mut Staging,
    buffers: &Buffers,
    layout: Layout,
    formats: &[Format],
) -> Result<Option<[f64; 2]>> {
    let mut depth_range = None;
    for format in formats {
        for aov in Aov::ALL {
            match (format, layout) {
                (Format::Npy, _) => write_npy(staging, buffers, aov, layout)?,
                (Format::Exr, Layout::Image { width, height }) => {
                    write_exr(staging, buffers, aov, width, height)?
                }
                (Format::Png, Layout::Image { width, .. }) => {
                    if let Some(range) = write_png(staging, buffers, aov, width)? {
                        depth_range = depth_range.or(Some(range));
                    }
                }
                _ => {}
            }
        }
    }
    Ok(depth_range)
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
    if let Some((data, components)) = floats {
        npy::write(
            &staging.file(&name),
            &shape(layout, components),
            NpyData::F64(&data),
        )?;
    }
    if let Some(data) = ints {
        npy::write(&staging.file(&name), &shape(layout, 1), NpyData::U32(data))?;
    }
    Ok(())
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
    let path = staging.file(&format!("{aov}.exr"));
    exr::write(
        &path,
        width,
        height,
        channels,
        &[("raycast/convention", exr_note(aov).to_string())],
    )
}

fn write_png(
    staging: &mut Staging,
    b: &Buffers,
    aov: Aov,
    width: usize,
) -> Result<Option<[f64; 2]>> {
    let distance = |v: &Vec<f64>| {
        let range = png::finite_range(v).unwrap_or([0.0, 1.0]);
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
    png::write(&staging.file(&format!("{aov}.png")), &image)?;
    Ok(range)
}
