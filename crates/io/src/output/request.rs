//! Checks made on a render request before any work is done: which files the requested formats
//! can hold, whether the output folder can be written, and how much memory the buffers need.
//! Each failure is a usage error ([`Error::usage`]).

use super::{Format, Layout};
use crate::error::{Error, Result};
use crate::render::Aov;
use crate::sizes::{default_memory_limit, human_bytes};
use std::path::{Path, PathBuf};

/// Bytes per ray of `--hits`'s splits, and per listed crossing (t, id, prim, twice: while
/// they are gathered per ray and in the flat lists).
const SPLIT_BYTES: u64 = 8;
const CROSSING_BYTES: u64 = 32;

/// Crossings per ray assumed by the memory estimate of `--hits all` (a ray through one closed
/// surface).
const ASSUMED_CROSSINGS: u64 = 2;

/// The formats in the order first given, without repeats (`png,png` is `png`).
pub fn merge_formats(formats: &[Format]) -> Vec<Format> {
    let mut merged = Vec::new();
    for &format in formats {
        if !merged.contains(&format) {
            merged.push(format);
        }
    }
    merged
}

impl Format {
    /// The format's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Format::Exr => "exr",
            Format::Png => "png",
            Format::Npy => "npy",
            Format::Ply => "ply",
        }
    }

    /// Whether this format writes `aov` into a file: NPY always; EXR for images; PNG previews
    /// for images, except positions, barycentric weights and texture coordinates (which have
    /// no meaningful preview); the PLY point cloud holds positions and, beside them, normals, ids and prims.
    pub fn holds(self, aov: Aov, rays_mode: bool) -> bool {
        match self {
            Format::Npy => true,
            Format::Exr => !rays_mode,
            Format::Png => {
                !rays_mode
                    && !matches!(
                        aov,
                        Aov::Position | Aov::Bary | Aov::Error | Aov::Certain | Aov::Uv
                    )
            }
            Format::Ply => matches!(aov, Aov::Position | Aov::Normal | Aov::Id | Aov::Prim),
        }
    }

    /// Whether this format writes a file of its own for `aov` (the point cloud is one file,
    /// named for `position`).
    fn names_file(self, aov: Aov, rays_mode: bool) -> bool {
        self.holds(aov, rays_mode) && (self != Format::Ply || aov == Aov::Position)
    }
}

/// Refuses a request in which a format writes no file, or an AOV gets no file: nothing must
/// be skipped silently.
pub fn check_files(aovs: &[Aov], formats: &[Format], rays_mode: bool) -> Result<()> {
    if formats.contains(&Format::Ply) && !aovs.contains(&Aov::Position) {
        return Err(Error::usage(
            "--format ply writes the hits as a point cloud: add position to --aov",
        ));
    }
    for &format in formats {
        if aovs.iter().all(|&aov| !format.holds(aov, rays_mode)) {
            let reason = if rays_mode {
                "holds images only; rays mode writes one value per ray, use --format npy"
                    .to_string()
            } else {
                format!("has no preview of --aov {}", names(aovs))
            };
            return Err(Error::usage(format!(
                "--format {} would write no file: {} {reason}",
                format.name(),
                format.name()
            )));
        }
    }
    for &aov in aovs {
        if formats.iter().all(|f| !f.holds(aov, rays_mode)) {
            return Err(Error::usage(format!(
                "--aov {aov} would be written to no file: --format {} cannot hold it \
                 (add exr or npy)",
                formats
                    .iter()
                    .map(|f| f.name())
                    .collect::<Vec<_>>()
                    .join(",")
            )));
        }
    }
    Ok(())
}

/// The names of the files a request writes, `raycast.json` last (what
/// [`super::write_buffers`] and the `--hits` list write).
pub fn file_names(aovs: &[Aov], formats: &[Format], rays_mode: bool, hits: bool) -> Vec<String> {
    let mut names: Vec<String> = merge_formats(formats)
        .into_iter()
        .flat_map(|format| {
            Aov::ALL
                .into_iter()
                .filter(move |aov| aovs.contains(aov) && format.names_file(*aov, rays_mode))
                .map(move |aov| format!("{aov}.{}", format.name()))
        })
        .collect();
    if hits {
        names.push(super::npz::HITS_FILE.to_string());
    }
    names.push(super::ownership::SIDECAR.to_string());
    names
}

/// The AOV names joined with commas.
pub fn names(aovs: &[Aov]) -> String {
    aovs.iter()
        .map(Aov::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

/// Creates the output folder if needed and proves it writable with a probe file, so that a
/// read-only or mistyped `--out` is reported before the scene is loaded. Never touches files
/// already there. Returns the outermost folder it created, for [`remove_created_folder`].
pub fn prepare_folder(dir: &Path) -> Result<Option<PathBuf>> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::in_file(
            dir,
            "is a file, not a folder; --out names the output folder",
        )
        .as_usage());
    }
    let created = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .last()
        .map(Path::to_path_buf);
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::in_file(dir, format!("cannot create the output folder: {e}")).as_usage()
    })?;
    let probe = dir.join(format!(".raycast-probe-{}", std::process::id()));
    if let Err(e) = std::fs::write(&probe, b"") {
        remove_created_folder(dir, created.as_deref());
        return Err(
            Error::in_file(dir, format!("cannot write to the output folder: {e}")).as_usage(),
        );
    }
    let _ = std::fs::remove_file(&probe);
    Ok(created)
}

/// Removes the empty folders from `dir` up to `created` (what [`prepare_folder`] created), so
/// that a failed run leaves nothing behind.
pub fn remove_created_folder(dir: &Path, created: Option<&Path>) {
    let Some(created) = created else {
        return;
    };
    for folder in dir.ancestors() {
        if std::fs::remove_dir(folder).is_err() || folder == created {
            break;
        }
    }
}

/// Bytes per element (pixel or ray) of each AOV's buffer.
fn aov_bytes(aov: Aov) -> u64 {
    match aov {
        Aov::Depth | Aov::Z | Aov::T | Aov::Error => 8,
        Aov::Normal | Aov::Position | Aov::Bary | Aov::ShadingNormal => 24,
        Aov::Uv => 16,
        Aov::Id | Aov::Prim | Aov::Material => 4,
        Aov::Certain => 1,
    }
}

/// Bytes per element of the largest file being encoded at one time (the encoder's copy).
fn encoding_bytes(aov: Aov, format: Format) -> u64 {
    match format {
        Format::Npy => aov_bytes(aov),
        Format::Exr => match aov {
            Aov::Id | Aov::Prim | Aov::Material | Aov::Certain => 4,
            _ => aov_bytes(aov) / 2,
        },
        Format::Png => 4,
        // The point cloud is streamed; it keeps the index of each hit.
        Format::Ply => 8,
    }
}

/// An estimate of the memory the buffers of a run take at their peak: every AOV buffer, twice
/// the `encoders` largest files being encoded (the files are encoded in parallel), and with
/// `--hits` (at most `hits` crossings per ray) the
/// crossing lists, counting two crossings per ray at most.
pub fn buffer_bytes(
    aovs: &[Aov],
    formats: &[Format],
    layout: Layout,
    hits: Option<usize>,
    encoders: usize,
) -> u64 {
    let rays_mode = matches!(layout, Layout::Rays(_));
    let count = layout.rays() as u64;
    let buffers: u64 = aovs.iter().map(|&a| aov_bytes(a)).sum();
    // The files are encoded in parallel, `encoders` (the worker threads) at a time: the
    // largest ones may be in flight together.
    let mut encodings: Vec<u64> = aovs
        .iter()
        .flat_map(|&a| formats.iter().map(move |&f| (a, f)))
        .filter(|&(a, f)| f.holds(a, rays_mode))
        .map(|(a, f)| encoding_bytes(a, f))
        .collect();
    encodings.sort_unstable_by(|a, b| b.cmp(a));
    let encoding: u64 = encodings.iter().take(encoders.max(1)).sum();
    let lists = hits.map_or(0, |limit| {
        SPLIT_BYTES + CROSSING_BYTES * ASSUMED_CROSSINGS.min(limit as u64)
    });
    // A ray list may be traced in the order of its origins: that order, its sort keys, and
    // one buffer's copy while the buffers are put back in the file's order.
    let reorder = if rays_mode {
        ORDER_BYTES + aovs.iter().map(|&a| aov_bytes(a)).max().unwrap_or(0)
    } else {
        0
    };
    count.saturating_mul(buffers + 2 * encoding + lists + reorder)
}

/// Bytes per ray of the order a ray list is traced in (`raycast_core::render::trace`): the
/// order and each ray's place in it, and the sort keys, four bytes each.
const ORDER_BYTES: u64 = 12;

/// Refuses a run whose buffers need more than `limit` bytes (`--max-memory`, or by default
/// [`default_memory_limit`]).
pub fn check_memory(need: u64, limit: Option<u64>, what: &str) -> Result<()> {
    let (limit, source) = match limit {
        Some(limit) => (limit, "--max-memory"),
        None => match default_memory_limit() {
            Some(default) => (
                default,
                "the default: half the physical memory, or what is available if less; raise it \
                 with --max-memory",
            ),
            None => return Ok(()),
        },
    };
    if need <= limit {
        return Ok(());
    }
    Err(Error::usage(format!(
        "{what} need about {} of memory, more than {} ({source}); render fewer pixels or AOVs",
        human_bytes(need),
        human_bytes(limit)
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_formats_merge_in_order() {
        let merged = merge_formats(&[Format::Png, Format::Exr, Format::Png]);
        assert_eq!(merged, [Format::Png, Format::Exr]);
    }

    #[test]
    fn memory_estimate_counts_hits_buffers_and_encoding() {
        // 10 pixels, depth (8) + normal (24), exr encodes normal as 12: 10 * (32 + 24).
        let layout = Layout::Image {
            width: 5,
            height: 2,
        };
        let aovs = [Aov::Depth, Aov::Normal];
        let bytes = buffer_bytes(&aovs, &[Format::Exr], layout, None, 1);
        assert_eq!(bytes, 560);
        // two encoders: depth's EXR (4) is encoded beside normal's: 10 * (32 + 2 * 16)
        assert_eq!(buffer_bytes(&aovs, &[Format::Exr], layout, None, 2), 640);
        // --hits 1: + 10 * (8 + 32).
        let with_hits = buffer_bytes(&aovs, &[Format::Exr], layout, Some(1), 1);
        assert_eq!(with_hits, 960);
        // 10 rays of a ray file: + 10 * (12 + 24), the order and one buffer's copy.
        let rays = buffer_bytes(&aovs, &[Format::Npy], Layout::Rays(10), None, 1);
        assert_eq!(rays, 10 * (32 + 2 * 24 + 36));
        assert!(check_memory(800, Some(800), "buffers").is_ok());
        let e = check_memory(801, Some(800), "buffers").unwrap_err();
        assert!(e.message.contains("--max-memory"), "{e}");
    }
}
