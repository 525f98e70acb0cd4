//! Golden comparison: an asset is rendered from three fixed views (depth and id with their
//! certified bounds, `error` and `certain`; 64×64) and the buffers are compared with the ones
//! stored under the golden folder; `--update-golden` stores them instead. A failed comparison
//! writes a difference image beside the golden buffers.
//!
//! With stored bounds a pixel differs only when rounding cannot explain it ([`differs`]):
//! both renders are `certain` (the exact nearest primitive, or the exact miss) and the hit,
//! the id, or the depth beyond the sum of both depths' bounds differ. Golden buffers stored
//! without bounds (before they were written) are compared with [`DEPTH_TOLERANCE`].

use super::Findings;
use crate::accel::{Octree, OctreeParams};
use crate::bound::bounded::up;
use crate::camera::Camera;
use crate::import::npy;
use crate::output::npy::{self as npy_out, NpyData};
use crate::output::{png, Staging};
use crate::render::{self, Aov, Buffers, CameraView};
use crate::scene::Scene;
use crate::trace::Tracer;
use crate::Code;
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

/// For golden buffers without bounds: depths may differ by this fraction of the scene's size
/// (float rounding across builds and platforms stays far below it; a moved or rescaled object
/// does not).
const DEPTH_TOLERANCE: f64 = 1e-6;

/// What each view renders.
const AOVS: [Aov; 4] = [Aov::Depth, Aov::Id, Aov::Error, Aov::Certain];

/// Renders the views of `scene` and compares them with (or stores them under) the golden folder
/// for the asset `key` (its path relative to the checked folder).
pub fn check(scene: &Scene, key: &Path, options: &GoldenOptions, findings: &mut Findings) {
    let dir = options.dir.join(key);
    let octree = Octree::build(scene, OctreeParams::default());
    let tracer = Tracer::new(scene, &octree);
    let bounds = scene.world_bounds();
    let size = if bounds.is_empty() {
        1.0
    } else {
        bounds.size().length()
    };
    for (index, direction) in VIEWS.into_iter().enumerate() {
        let view = CameraView::new(Camera::framing_from(&bounds, direction), SIZE, SIZE);
        let buffers = render::render(&tracer, &view, &AOVS, |_| {});
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
            Code::GoldenUpdated,
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

fn errors(b: &Buffers) -> &[f64] {
    b.floats(Aov::Error).unwrap_or_default()
}

fn certain(b: &Buffers) -> &[u8] {
    b.flags(Aov::Certain).unwrap_or_default()
}

/// One pixel of a view: its depth (`+∞` for a miss), its object id, and, when known, its
/// depth's bound and whether its decision is certain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pixel {
    /// Distance to the hit; `+∞` for a miss.
    pub depth: f64,
    /// The hit object's id (0 for a miss), as the id buffer stores it.
    pub id: f64,
    /// The depth's error bound and whether the decision is certain, when the view has them.
    pub bound: Option<(f64, bool)>,
}

/// Whether the pixel `current` differs from `golden` for real. With both bounds known: only
/// when both decisions are certain and the hit, the id or the depth beyond `δ + δ_golden`
/// differ (the exact depths of one scene are within those of both). Otherwise: a different
/// hit or id, or depths apart by more than `tolerance`.
pub fn differs(current: Pixel, golden: Pixel, tolerance: f64) -> bool {
    let hits = (current.depth.is_finite(), golden.depth.is_finite());
    let depth_apart = |allowed: f64| (current.depth - golden.depth).abs() > allowed;
    match (current.bound, golden.bound) {
        (Some((error, sure)), Some((golden_error, golden_sure))) => {
            sure && golden_sure
                && (hits.0 != hits.1
                    || current.id != golden.id
                    || (hits.0 && hits.1 && depth_apart(up(error + golden_error))))
        }
        _ => hits.0 != hits.1 || current.id != golden.id || (hits.0 && depth_apart(tolerance)),
    }
}

type Failure = (Code, String);

fn store(dir: &Path, index: usize, buffers: &Buffers) -> Result<(), Failure> {
    let fail = |e: crate::Error| (Code::IoError, format!("cannot write golden buffers: {e}"));
    let mut staging = Staging::new(dir).map_err(fail)?;
    let shape = [SIZE, SIZE];
    let files = [
        ("depth", NpyData::F64(depth(buffers))),
        ("id", NpyData::U32(ids(buffers))),
        ("error", NpyData::F64(errors(buffers))),
        ("certain", NpyData::U8(certain(buffers))),
    ];
    for (aov, data) in files {
        let name = format!("view{index}.{aov}.npy");
        staging
            .write(&name, |out| npy_out::write(out, &shape, data))
            .map_err(fail)?;
    }
    staging.commit().map_err(fail)
}

fn compare(dir: &Path, index: usize, buffers: &Buffers, size: f64) -> Result<(), Failure> {
    let read = |name: String| {
        npy::read(&dir.join(&name)).map_err(|e| {
            (
                Code::GoldenMissing,
                format!("no usable golden buffer ({e}); run with --update-golden"),
            )
        })
    };
    let (_, golden_depth) = read(format!("view{index}.depth.npy"))?;
    let (_, golden_id) = read(format!("view{index}.id.npy"))?;
    if golden_depth.len() != SIZE * SIZE || golden_id.len() != SIZE * SIZE {
        return Err((
            Code::GoldenMissing,
            "golden buffers have the wrong size; run with --update-golden".into(),
        ));
    }
    // Bounds stored beside them (goldens written before they were have none; a bound buffer
    // that is there but unusable is an error, not a silent fall-back to the tolerance).
    let mut bounds = Vec::new();
    for aov in ["error", "certain"] {
        let path = dir.join(format!("view{index}.{aov}.npy"));
        if path.exists() {
            let (_, values) = read(format!("view{index}.{aov}.npy"))?;
            if values.len() != SIZE * SIZE {
                return Err((
                    Code::GoldenMissing,
                    format!("golden {aov} buffer has the wrong size; run with --update-golden"),
                ));
            }
            bounds.push(values);
        }
    }
    let golden_bounds = match &bounds[..] {
        [error, certain] => Some((error, certain)),
        _ => None,
    };
    let tolerance = DEPTH_TOLERANCE * size;
    let differs: Vec<bool> = (0..SIZE * SIZE)
        .map(|i| {
            let now = Pixel {
                depth: depth(buffers)[i],
                id: f64::from(ids(buffers)[i]),
                bound: Some((errors(buffers)[i], certain(buffers)[i] == 1)),
            };
            let then = Pixel {
                depth: golden_depth[i],
                id: golden_id[i],
                bound: golden_bounds.map(|(e, c)| (e[i], c[i] == 1.0)),
            };
            differs(now, then, tolerance)
        })
        .collect();
    let count = differs.iter().filter(|&&d| d).count();
    if count == 0 {
        return Ok(());
    }
    let diff_path = dir.join(format!("view{index}.diff.png"));
    let written = write_difference(&diff_path, depth(buffers), &differs);
    Err((
        Code::GoldenMismatch,
        format!(
            "{count} of {} pixels differ from the golden depth/id buffers ({}){}",
            SIZE * SIZE,
            match golden_bounds {
                Some(_) => "certain pixels, depths apart by more than both bounds".to_string(),
                None => format!("depth tolerance {DEPTH_TOLERANCE:.0e} of the scene size"),
            },
            match written {
                Ok(()) => format!("; difference image {}", diff_path.display()),
                Err(e) => format!("; the difference image could not be written: {e}"),
            }
        ),
    ))
}

/// The current depth preview with every differing pixel drawn red.
fn write_difference(path: &Path, depth: &[f64], differs: &[bool]) -> crate::error::Result<()> {
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

#[cfg(test)]
mod tests {
    use super::{differs, Pixel};

    fn hit(depth: f64, error: f64, certain: bool) -> Pixel {
        Pixel {
            depth,
            id: 1.0,
            bound: Some((error, certain)),
        }
    }

    /// With bounds, depths within the sum of both bounds are the same exact depth; beyond it
    /// they differ, even far below the tolerance of goldens without bounds.
    #[test]
    fn depths_differ_only_beyond_both_bounds() {
        let golden = hit(10.0, 1e-14, true);
        assert!(!differs(hit(10.0 + 1.5e-14, 1e-14, true), golden, 1e-5));
        assert!(differs(hit(10.0 + 3e-14, 1e-14, true), golden, 1e-5));
        // Without stored bounds: the tolerance.
        let old = Pixel {
            bound: None,
            ..golden
        };
        assert!(!differs(hit(10.0 + 3e-14, 1e-14, true), old, 1e-5));
        assert!(differs(hit(10.0 + 2e-5, 1e-14, true), old, 1e-5));
    }

    /// A hit against a miss, or another id, is real only where both decisions are certain.
    #[test]
    fn changed_decisions_count_only_where_both_are_certain() {
        let miss = |certain| Pixel {
            depth: f64::INFINITY,
            id: 0.0,
            bound: Some((0.0, certain)),
        };
        assert!(differs(hit(10.0, 1e-14, true), miss(true), 1e-5));
        assert!(!differs(hit(10.0, 1e-14, false), miss(true), 1e-5));
        assert!(!differs(hit(10.0, 1e-14, true), miss(false), 1e-5));
        let other = Pixel {
            id: 2.0,
            ..hit(10.0, 1e-14, true)
        };
        assert!(differs(hit(10.0, 1e-14, true), other, 1e-5));
    }
}
