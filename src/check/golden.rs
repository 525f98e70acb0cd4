//! Golden comparison: an asset is rendered from three fixed views (depth and id, 64×64) and the
//! buffers are compared with the ones stored under the golden folder; `--update-golden` stores
//! them instead. A failed comparison writes a difference image beside the golden buffers.

use super::Findings;
use crate::accel::{Octree, OctreeParams};
use crate::camera::Camera;
use crate::output::npy::{self, NpyData};
use crate::output::{png, Staging};
use crate::render::{self, Aov, Buffers, CameraView, Tracer};
use crate::scene::Scene;
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Where golden buffers live and whether to rewrite them.
#[derive(Debug, Clone, PartialEq)]
pub struct GoldenOptions {
    /// The golden folder.
    pub dir: PathBuf,
    /// Store the current buffers instead of comparing.
    pub update: bool,
    /// The pose rendered (`--time`): glTF seconds (every animation) or a USD time code;
    /// `None`: the file's static pose, as a render without `--time` draws it.
    pub time: Option<f64>,
}

/// Image side of each golden view.
const SIZE: usize = 64;

/// Directions the views look from (toward the scene's centre).
const VIEWS: [DVec3; 3] = [
    DVec3::new(0.4, 0.3, 1.0),
    DVec3::new(1.0, 0.5, -0.4),
    DVec3::new(-0.6, 0.8, -0.7),
];

/// Depths may differ by this fraction of the scene's size (float rounding across builds and
/// platforms stays far below it; a moved or rescaled object does not).
const DEPTH_TOLERANCE: f64 = 1e-6;

/// Renders the views of `scene` and compares them with (or stores them under) the golden folder
/// for the asset `key` (its path relative to the checked folder).
pub fn check(scene: &Scene, key: &Path, options: &GoldenOptions, findings: &mut Findings) {
    let dir = options.dir.join(key);
    let octree = Octree::build(scene, OctreeParams::default());
    let tracer = Tracer {
        scene,
        accel: (&octree).into(),
    };
    let bounds = scene.world_bounds();
    let size = if bounds.is_empty() {
        1.0
    } else {
        bounds.size().length()
    };
    for (index, direction) in VIEWS.into_iter().enumerate() {
        let view = CameraView::new(Camera::framing_from(&bounds, direction), SIZE, SIZE);
        let buffers = render::render(&tracer, &view, &[Aov::Depth, Aov::Id], |_| {});
        let outcome = if options.update {
            store(&dir, index, &buffers)
        } else {
            compare(&dir, index, &buffers, size)
        };
        if let Err((code, message)) = outcome {
            findings.error(code, format!("view {index}"), message);
        }
    }
    if options.update {
        findings.info(
            "GOLDEN_UPDATED",
            "",
            format!("golden buffers written to {}", dir.display()),
        );
    }
}

fn depth(b: &Buffers) -> &[f64] {
    b.floats(Aov::Depth).unwrap_or_default()
}

fn ids(b: &Buffers) -> &[u32] {
    b.labels(Aov::Id).unwrap_or_default()
}

type Failure = (&'static str, String);

fn store(dir: &Path, index: usize, buffers: &Buffers) -> Result<(), Failure> {
    let fail = |e: crate::Error| ("IO_ERROR", format!("cannot write golden buffers: {e}"));
    let mut staging = Staging::new(dir).map_err(fail)?;
    let shape = [SIZE, SIZE];
    staging
        .write(&format!("view{index}.depth.npy"), |out| {
            npy::write(out, &shape, NpyData::F64(depth(buffers)))
        })
        .map_err(fail)?;
    staging
        .write(&format!("view{index}.id.npy"), |out| {
            npy::write(out, &shape, NpyData::U32(ids(buffers)))
        })
        .map_err(fail)?;
    staging.commit().map_err(fail)
}

fn compare(dir: &Path, index: usize, buffers: &Buffers, size: f64) -> Result<(), Failure> {
    let read = |name: String| {
        npy::read(&dir.join(&name)).map_err(|e| {
            (
                "GOLDEN_MISSING",
                format!("no usable golden buffer ({e}); run with --update-golden"),
            )
        })
    };
    let (_, golden_depth) = read(format!("view{index}.depth.npy"))?;
    let (_, golden_id) = read(format!("view{index}.id.npy"))?;
    if golden_depth.len() != SIZE * SIZE || golden_id.len() != SIZE * SIZE {
        return Err((
            "GOLDEN_MISSING",
            "golden buffers have the wrong size; run with --update-golden".into(),
        ));
    }
    let differs: Vec<bool> = (0..SIZE * SIZE)
        .map(|i| {
            let (a, b) = (depth(buffers)[i], golden_depth[i]);
            let depth_differs = match (a.is_finite(), b.is_finite()) {
                (true, true) => (a - b).abs() > DEPTH_TOLERANCE * size,
                (hit_a, hit_b) => hit_a != hit_b,
            };
            depth_differs || f64::from(ids(buffers)[i]) != golden_id[i]
        })
        .collect();
    let count = differs.iter().filter(|&&d| d).count();
    if count == 0 {
        return Ok(());
    }
    let diff_path = dir.join(format!("view{index}.diff.png"));
    let written = write_difference(&diff_path, depth(buffers), &differs);
    Err((
        "GOLDEN_MISMATCH",
        format!(
            "{count} of {} pixels differ from the golden depth/id buffers (depth tolerance {:.0e} of the scene size){}",
            SIZE * SIZE,
            DEPTH_TOLERANCE,
            match written {
                Ok(()) => format!("; difference image {}", diff_path.display()),
                Err(e) => format!("; the difference image could not be written: {e}"),
            }
        ),
    ))
}

/// The current depth preview with every differing pixel drawn red.
fn write_difference(path: &Path, depth: &[f64], differs: &[bool]) -> crate::Result<()> {
    let range = png::finite_range(depth).unwrap_or([0.0, 1.0]);
    let mut image = image::DynamicImage::from(png::distance_image(depth, SIZE, range)).to_rgb8();
    for (i, _) in differs.iter().enumerate().filter(|(_, &d)| d) {
        image.put_pixel(
            (i % SIZE) as u32,
            (i / SIZE) as u32,
            image::Rgb([255, 0, 0]),
        );
    }
    let mut staging = Staging::new(path.parent().unwrap_or(Path::new(".")))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    staging.write(&name, |out| png::write(out, image))?;
    staging.commit()
}
