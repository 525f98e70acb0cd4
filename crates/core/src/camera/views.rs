//! Camera files: the many views of one run (`--views FILE`).
//!
//! Two kinds of JSON file are read, told apart by their keys:
//!
//! - **nerfstudio / instant-ngp `transforms.json`** (a `frames` array): each frame's
//!   `transform_matrix` is camera-to-world in OpenGL axes; the intrinsics (`fl_x`, `fl_y`, `cx`,
//!   `cy`, `w`, `h`, or `camera_angle_x` / `camera_angle_y` for the focal lengths) are read from
//!   the frame, else from the top level; `cx`, `cy` default to the image centre and `fl_y` to
//!   `fl_x`. Pixel centres are at (u + ½, v + ½), as nerfstudio's rays are. Lens distortion
//!   (`k1` … `k4`, `p1`, `p2` not zero) and camera models other than a pinhole are refused:
//!   an ideal pinhole would draw another image.
//! - **A plain view list** (a `views` array): `axes` (`"opencv"` or `"opengl"`, required),
//!   `K` (3×3, row-major), `width` and `height` at the top level or per view, and each view's
//!   `cam_to_world` (4×4, row-major) and optional `name`.
//!
//! A view whose values are wrong is an error that names the frame.

use super::{camera_to_world, CameraAxes, Pinhole};
use crate::error::{Error, Result};
use glam::DMat4;
use serde_json::{Map, Value};
use std::path::Path;

/// Most views one file may hold.
pub const MAX_VIEWS: usize = 100_000;

/// One view of a camera file.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// A name for its output folder: the frame's `file_path` stem or the view's `name`.
    pub name: Option<String>,
    /// Its intrinsics and image size.
    pub pinhole: Pinhole,
    /// Camera-to-world, in raycast's (OpenGL's) axes.
    pub to_world: DMat4,
}

/// The views of the camera file at `path`. `size` (the command line's `--width` and
/// `--height`) stands in for an image size the file does not give.
pub fn read(path: &Path, size: Option<(usize, usize)>) -> Result<Vec<View>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::in_file(path, format!("cannot read the views file: {e}")))?;
    let json: Value = serde_json::from_str(&text)
        .map_err(|e| Error::in_file(path, format!("not a JSON views file: {e}")))?;
    let top = json.as_object().ok_or_else(|| {
        Error::in_file(path, "a views file is a JSON object ('frames' or 'views')")
    })?;
    let views = match (top.get("frames"), top.get("views")) {
        (Some(frames), None) => each(frames, "frames", |f| frame(top, f, size)),
        (None, Some(views)) => {
            let axes = axes(top).map_err(|e| e.with_path(path))?;
            each(views, "views", |v| plain(top, v, axes, size))
        }
        _ => Err(Error::msg(
            "expected a 'frames' array (nerfstudio transforms.json) or a 'views' array \
                  (K and cam_to_world), not both",
        )),
    };
    let views = views.map_err(|e| e.with_path(path))?;
    if views.is_empty() {
        return Err(Error::in_file(path, "the views file lists no views"));
    }
    Ok(views)
}

/// `read` over the array `list` (the key `key`), each entry by `one`; the error of the
/// first entry that has one, naming it.
fn each(
    list: &Value,
    key: &str,
    one: impl Fn(&Map<String, Value>) -> Result<View>,
) -> Result<Vec<View>> {
    let list = list
        .as_array()
        .ok_or_else(|| Error::msg(format!("'{key}' is not an array")))?;
    if list.len() > MAX_VIEWS {
        return Err(Error::msg(format!("more than {MAX_VIEWS} views")));
    }
    list.iter()
        .enumerate()
        .map(|(i, entry)| {
            let entry = entry
                .as_object()
                .ok_or_else(|| Error::msg(format!("{key}[{i}] is not an object")))?;
            one(entry).map_err(|e| e.context(format!("{key}[{i}]{}", label(entry))))
        })
        .collect()
}

/// ` ('NAME')` for an entry with a `file_path` or `name`, to say which frame is meant.
fn label(entry: &Map<String, Value>) -> String {
    match entry.get("file_path").or_else(|| entry.get("name")) {
        Some(Value::String(s)) => format!(" ('{s}')"),
        _ => String::new(),
    }
}

/// A nerfstudio frame, its missing intrinsics taken from the file's top level `top`.
fn frame(
    top: &Map<String, Value>,
    frame: &Map<String, Value>,
    size: Option<(usize, usize)>,
) -> Result<View> {
    let get = |key: &str| frame.get(key).or_else(|| top.get(key));
    let number = |key: &str| get(key).map(|v| finite(v, key)).transpose();
    refuse_distortion(get)?;
    let (width, height) = image_size(get, size)?;
    let focal = |fl: &str, angle: &str, side: usize| -> Result<Option<f64>> {
        Ok(match (number(fl)?, number(angle)?) {
            (Some(f), _) => Some(f),
            (None, Some(a)) => Some(side as f64 / (2.0 * (a / 2.0).tan())),
            (None, None) => None,
        })
    };
    let fx = focal("fl_x", "camera_angle_x", width)?;
    let fy = focal("fl_y", "camera_angle_y", height)?;
    let fx = fx
        .or(fy)
        .ok_or_else(|| Error::msg("no focal length (fl_x or camera_angle_x)"))?;
    let fy = fy.unwrap_or(fx);
    let cx = number("cx")?.unwrap_or(width as f64 / 2.0);
    let cy = number("cy")?.unwrap_or(height as f64 / 2.0);
    let pinhole = Pinhole::from_focal([fx, fy, cx, cy], width, height)?;
    let matrix = frame
        .get("transform_matrix")
        .ok_or_else(|| Error::msg("no transform_matrix"))?;
    let to_world = camera_to_world(rows::<4>(matrix, "transform_matrix")?)?;
    let name = match frame.get("file_path") {
        Some(Value::String(p)) => Path::new(p)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned()),
        _ => None,
    };
    Ok(View {
        name,
        pinhole,
        to_world: CameraAxes::OpenGl.to_opengl(to_world),
    })
}

/// Refuses a frame with lens distortion or a camera model that is not a pinhole.
fn refuse_distortion<'a>(get: impl Fn(&str) -> Option<&'a Value>) -> Result<()> {
    if let Some(model) = get("camera_model") {
        let model = model.as_str().unwrap_or_default();
        if !matches!(model, "OPENCV" | "PINHOLE" | "SIMPLE_PINHOLE") {
            return Err(Error::msg(format!(
                "camera_model {model:?} is not a pinhole; raycast traces pinhole cameras only"
            )));
        }
    }
    for key in ["k1", "k2", "k3", "k4", "p1", "p2"] {
        if let Some(v) = get(key) {
            let v = finite(v, key)?;
            if v != 0.0 {
                return Err(Error::msg(format!(
                    "lens distortion {key} = {v} is not supported (raycast traces an ideal \
                     pinhole camera; undistort the images' intrinsics or set it to 0)"
                )));
            }
        }
    }
    Ok(())
}

/// The image size `w`, `h` of a frame, or the command line's.
fn image_size<'a>(
    get: impl Fn(&str) -> Option<&'a Value>,
    size: Option<(usize, usize)>,
) -> Result<(usize, usize)> {
    match (get("w"), get("h"), size) {
        (Some(w), Some(h), _) => Ok((side(w, "w")?, side(h, "h")?)),
        (None, None, Some(size)) => Ok(size),
        _ => Err(Error::msg(
            "no image size (w and h): give --width and --height",
        )),
    }
}

/// A view of a plain view list, its missing values taken from the top level `top`.
fn plain(
    top: &Map<String, Value>,
    view: &Map<String, Value>,
    axes: CameraAxes,
    size: Option<(usize, usize)>,
) -> Result<View> {
    let get = |key: &str| view.get(key).or_else(|| top.get(key));
    let (width, height) = match (get("width"), get("height"), size) {
        (Some(w), Some(h), _) => (side(w, "width")?, side(h, "height")?),
        (None, None, Some(size)) => size,
        _ => return Err(Error::msg("no image size (width and height)")),
    };
    let k = get("K").ok_or_else(|| Error::msg("no K"))?;
    let pinhole = Pinhole::new(rows::<3>(k, "K")?, width, height)?;
    let matrix = view
        .get("cam_to_world")
        .ok_or_else(|| Error::msg("no cam_to_world"))?;
    let to_world = camera_to_world(rows::<4>(matrix, "cam_to_world")?)?;
    let name = match view.get("name") {
        Some(Value::String(s)) => Some(s.clone()),
        _ => None,
    };
    Ok(View {
        name,
        pinhole,
        to_world: axes.to_opengl(to_world),
    })
}

/// The plain list's `axes`.
fn axes(top: &Map<String, Value>) -> Result<CameraAxes> {
    match top.get("axes") {
        Some(Value::String(s)) => s.parse(),
        Some(_) => Err(Error::msg(
            "'axes' must be the text \"opencv\" or \"opengl\"",
        )),
        None => Err(Error::msg(
            "no 'axes': say whether cam_to_world is in \"opencv\" axes (+Y down, \
                     looking down +Z) or \"opengl\" axes (+Y up, looking down -Z)",
        )),
    }
}

/// An N×N matrix written as N rows of N numbers.
fn rows<const N: usize>(value: &Value, key: &str) -> Result<[[f64; N]; N]> {
    let wrong = || Error::msg(format!("{key} must be {N} rows of {N} numbers"));
    let rows = value
        .as_array()
        .filter(|r| r.len() == N)
        .ok_or_else(wrong)?;
    let mut out = [[0.0; N]; N];
    for (r, row) in rows.iter().enumerate() {
        let row = row.as_array().filter(|r| r.len() == N).ok_or_else(wrong)?;
        for (c, v) in row.iter().enumerate() {
            out[r][c] = finite(v, key)?;
        }
    }
    Ok(out)
}

/// A finite number.
fn finite(value: &Value, key: &str) -> Result<f64> {
    match value.as_f64() {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(Error::msg(format!(
            "{key} must be a finite number, not {value}"
        ))),
    }
}

/// An image side: a whole number of pixels, 1 to [`super::MAX_SIDE`].
fn side(value: &Value, key: &str) -> Result<usize> {
    let max = super::MAX_SIDE;
    let whole = value.as_u64().or_else(|| {
        value
            .as_f64()
            .filter(|v| v.fract() == 0.0 && *v >= 0.0)
            .map(|v| v as u64)
    });
    match whole {
        Some(n) if (1..=max as u64).contains(&n) => Ok(n as usize),
        _ => Err(Error::msg(format!(
            "{key} must be an image side of 1 to {max} pixels, not {value}"
        ))),
    }
}
