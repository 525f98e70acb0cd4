//! The camera of a camera-mode run and its image size: a file camera, a look-at, the
//! automatic framing camera, or a pinhole camera given by its intrinsics (`--K`) and
//! placement (`--cam-to-world`), with the command line's projection overrides.

use super::{CameraChoice, RenderJob, DEFAULT_SIZE};
use crate::camera::{Camera, Pinhole, Projection, AUTO_YFOV, MAX_SIDE};
use crate::error::{Error, Result};
use crate::render::CameraView;
use crate::scene::Scene;
use glam::DVec3;

/// The camera and image size for camera mode.
/// A file camera whose aspect ratio the image's does not match is said in `warnings`.
pub(super) fn camera_view(
    scene: &Scene,
    job: &RenderJob,
    warnings: &mut Vec<String>,
) -> Result<CameraView> {
    if let Some(view) = pinhole_view(job)? {
        return Ok(view);
    }
    // The automatic camera is framed once the image's size is known.
    let chosen = choose_camera(scene, &job.camera)?;
    let auto = Projection::Perspective { yfov: AUTO_YFOV };
    let mut projection = chosen.as_ref().map_or(auto, |c| c.projection);
    if let Some(fov) = job.camera.fov_degrees {
        if !(fov > 0.0 && fov < 180.0) {
            return Err(Error::usage(format!(
                "--fov must lie between 0 and 180 degrees, got {fov}"
            )));
        }
        projection = Projection::Perspective {
            yfov: fov.to_radians(),
        };
    }
    if let Some(height) = job.camera.ortho_height {
        if !(height > 0.0 && height.is_finite()) {
            return Err(Error::usage(format!(
                "--ortho must be a positive height, got {height}"
            )));
        }
        projection = Projection::Orthographic { ymag: height / 2.0 };
    }
    let aspect = chosen
        .as_ref()
        .and_then(|c| c.aspect_ratio)
        .filter(|a| a.is_finite() && *a > 0.0);
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
    if let (Some(camera), Some(a), Some(w), Some(h)) = (&chosen, aspect, job.width, job.height) {
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
    if let Some(k) = job.camera.intrinsics {
        projection = Projection::Pinhole(pinhole(k, width, height)?);
    }
    if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::usage(format!(
            "image size {width}x{height} is out of range (1 to {MAX_SIDE} per side)"
        )));
    }
    let camera = chosen.unwrap_or_else(|| framing(scene, width as f64 / height as f64));
    Ok(CameraView::new(
        Camera {
            projection,
            ..camera
        },
        width,
        height,
    ))
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

/// The view of a pinhole camera placed by `--cam-to-world` (or a views file), which needs
/// neither the scene nor a framing; `None` when the job does not place the camera so.
fn pinhole_view(job: &RenderJob) -> Result<Option<CameraView>> {
    let (Some(k), Some(to_world)) = (job.camera.intrinsics, job.camera.to_world) else {
        return Ok(None);
    };
    let (Some(width), Some(height)) = (job.width, job.height) else {
        return Err(Error::usage(
            "--K needs the image size: give --width and --height",
        ));
    };
    let camera = Camera::pinhole(
        pinhole(k, width, height)?,
        to_world,
        job.camera.name.clone().unwrap_or_else(|| "pinhole".into()),
        "command line (--K, --cam-to-world)".into(),
    );
    Ok(Some(CameraView::new(camera, width, height)))
}

/// The pinhole of intrinsics `k` for a `width`×`height` image, or a usage error.
fn pinhole(k: [[f64; 3]; 3], width: usize, height: usize) -> Result<Pinhole> {
    Pinhole::new(k, width, height).map_err(|e| Error::usage(format!("--K: {e}")))
}
