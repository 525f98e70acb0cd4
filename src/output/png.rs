//! PNG previews a person can read: depth as grey (near light, far dark), normals as colours,
//! ids as distinct colours; misses are black.

use crate::error::{Error, Result};
use glam::DVec3;
use image::{ImageFormat, RgbImage};
use std::path::Path;

/// Finite range of the values, or `None` when every value is infinite.
pub fn finite_range(values: &[f64]) -> Option<[f64; 2]> {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold(None, |r: Option<[f64; 2]>, &v| match r {
            None => Some([v, v]),
            Some([lo, hi]) => Some([lo.min(v), hi.max(v)]),
        })
}

/// Grey preview of a distance buffer mapped linearly from `range` (near white, far at 15%).
pub fn distance_image(values: &[f64], width: usize, range: [f64; 2]) -> RgbImage {
    let span = (range[1] - range[0]).max(f64::MIN_POSITIVE);
    image_from(values, width, |&v| {
        if !v.is_finite() {
            return [0, 0, 0];
        }
        let g = (255.0 - 215.0 * ((v - range[0]) / span).clamp(0.0, 1.0)).round() as u8;
        [g, g, g]
    })
}

/// Colour preview of unit vectors: each component mapped from [-1, 1] to [0, 255].
pub fn normal_image(values: &[DVec3], width: usize) -> RgbImage {
    image_from(values, width, |n| {
        if *n == DVec3::ZERO {
            return [0, 0, 0];
        }
        let c = (*n * 0.5 + DVec3::splat(0.5)).clamp(DVec3::ZERO, DVec3::ONE) * 255.0;
        [c.x.round() as u8, c.y.round() as u8, c.z.round() as u8]
    })
}

/// Colour preview of integer labels: each label gets a bright hashed colour; `miss` is black.
pub fn label_image(values: &[u32], width: usize, miss: u32) -> RgbImage {
    image_from(values, width, |&v| {
        if v == miss {
            return [0, 0, 0];
        }
        let h = v
            .wrapping_mul(0x9E37_79B1)
            .rotate_left(13)
            .wrapping_mul(0x85EB_CA6B);
        let [r, g, b, _] = h.to_le_bytes();
        [r | 0x40, g | 0x40, b | 0x40]
    })
}

fn image_from<T>(values: &[T], width: usize, colour: impl Fn(&T) -> [u8; 3]) -> RgbImage {
    let height = values.len() / width.max(1);
    RgbImage::from_fn(width as u32, height as u32, |x, y| {
        image::Rgb(colour(&values[y as usize * width + x as usize]))
    })
}

/// Writes a preview as PNG.
pub fn write(path: &Path, image: &RgbImage) -> Result<()> {
    image
        .save_with_format(path, ImageFormat::Png)
        .map_err(|e| Error::in_file(path, format!("cannot write PNG: {e}")))
}
