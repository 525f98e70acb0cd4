//! The command line's pinhole cameras: `--K` for the intrinsics, `--cam-to-world` with
//! `--camera-axes` for the placement, and `--views` for many cameras from one file.

use clap::Args;
use glam::DMat4;
use raycast::camera::{camera_to_world, CameraAxes};
use raycast::{Error, Result};
use std::path::PathBuf;

/// Pinhole camera options of a render.
#[derive(Args)]
pub struct PinholeArgs {
    /// Pinhole intrinsics in pixels, FX,FY,CX,CY (or K's nine numbers, row-major) for a
    /// --width x --height image; pixel (u, v) is centred at (u + 0.5, v + 0.5), as in
    /// nerfstudio (a centred principal point is width/2, height/2).
    #[arg(long = "K", value_name = "FX,FY,CX,CY", value_parser = parse_k, requires_all = ["width", "height"], conflicts_with_all = ["fov", "ortho"], allow_hyphen_values = true)]
    pub k: Option<[[f64; 3]; 3]>,
    /// Camera-to-world matrix of the --K camera, 16 numbers row-major (with --camera-axes).
    #[arg(long, value_name = "M00,..,M33", value_parser = parse_matrix, requires_all = ["k", "camera_axes"], conflicts_with_all = ["camera", "eye"], allow_hyphen_values = true)]
    pub cam_to_world: Option<[[f64; 4]; 4]>,
    /// The axes --cam-to-world is written in: opencv (+Y down, looking down +Z; OpenCV,
    /// COLMAP, Open3D) or opengl (+Y up, looking down -Z; glTF, Blender, nerfstudio).
    #[arg(long, value_name = "opencv|opengl", requires = "cam_to_world")]
    pub camera_axes: Option<CameraAxes>,
    /// Render many views, one folder each (<out>/NNNN-NAME), reading the scene and building
    /// its octree once: a nerfstudio / instant-ngp transforms.json, or a JSON list of K and
    /// cam_to_world matrices (docs/buffers-and-cli.md).
    #[arg(long, value_name = "FILE.json", conflicts_with_all = ["camera", "eye", "k", "fov", "ortho", "rays"])]
    pub views: Option<PathBuf>,
}

impl PinholeArgs {
    /// The camera-to-world matrix in raycast's axes, if one was given.
    pub fn to_world(&self) -> Option<DMat4> {
        let axes = self.camera_axes.unwrap_or(CameraAxes::OpenGl);
        self.cam_to_world
            .map(|rows| axes.to_opengl(DMat4::from_cols_array_2d(&rows).transpose()))
    }
}

/// Comma-separated finite numbers.
fn numbers(text: &str) -> Result<Vec<f64>> {
    text.split(',')
        .map(|p| match p.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(Error::usage(format!(
                "'{}' is not a finite number",
                p.trim()
            ))),
        })
        .collect()
}

/// `--K`: FX,FY,CX,CY, or the nine numbers of K row-major.
fn parse_k(text: &str) -> Result<[[f64; 3]; 3]> {
    match numbers(text)?[..] {
        [fx, fy, cx, cy] => Ok([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]),
        [a, b, c, d, e, f, g, h, i] => Ok([[a, b, c], [d, e, f], [g, h, i]]),
        _ => Err(Error::usage(
            "expected FX,FY,CX,CY or the nine numbers of K, row-major",
        )),
    }
}

/// `--cam-to-world`: 16 numbers row-major, a finite invertible affine matrix.
fn parse_matrix(text: &str) -> Result<[[f64; 4]; 4]> {
    let values = numbers(text)?;
    let Ok(values) = <[f64; 16]>::try_from(values) else {
        return Err(Error::usage(
            "expected the 16 numbers of a 4x4 matrix, row-major",
        ));
    };
    let mut rows = [[0.0; 4]; 4];
    for (i, v) in values.into_iter().enumerate() {
        rows[i / 4][i % 4] = v;
    }
    camera_to_world(rows).map_err(Error::as_usage)?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_takes_four_or_nine_numbers() {
        let k = parse_k("500,510,320,240").unwrap();
        assert_eq!(
            k,
            [[500.0, 0.0, 320.0], [0.0, 510.0, 240.0], [0.0, 0.0, 1.0]]
        );
        assert_eq!(parse_k("1,2,3,4,5,6,7,8,9").unwrap()[2], [7.0, 8.0, 9.0]);
        assert!(parse_k("1,2,3").is_err());
        assert!(parse_k("1,2,nan,4").is_err());
    }

    #[test]
    fn cam_to_world_must_be_affine_and_invertible() {
        let identity = "1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1";
        assert!(parse_matrix(identity).is_ok());
        assert!(parse_matrix("1,0,0,0,0,1,0,0,0,0,1,0,0,0,1,1").is_err());
        assert!(parse_matrix("0,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1").is_err());
        assert!(parse_matrix("1,0,0").is_err());
    }
}
