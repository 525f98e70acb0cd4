//! PNG previews a person can read: depth as grey (near light, far dark), normals as colours,
//! ids as distinct colours; misses are black.

use super::palette::label_colour;
use glam::DVec3;
use image::{ImageFormat, RgbImage};
use std::io::{Seek, Write};

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

/// The 1st to the 99th percentile of the finite values (the full range when that is a single
/// value), so that a few far hits do not wash the preview out; `None` when every value is
/// infinite.
pub fn percentile_range(values: &[f64]) -> Option<[f64; 2]> {
    let mut finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    finite.sort_unstable_by(f64::total_cmp);
    let last = finite.len() - 1;
    let (lo, hi) = (finite[last / 100], finite[last - last / 100]);
    if lo < hi {
        Some([lo, hi])
    } else {
        Some([finite[0], finite[last]])
    }
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
pub fn normal_image(values: &[[f64; 3]], width: usize) -> RgbImage {
    image_from(values, width, |n| {
        let n = DVec3::from_array(*n);
        if n == DVec3::ZERO {
            return [0, 0, 0];
        }
        let c = (n * 0.5 + DVec3::splat(0.5)).clamp(DVec3::ZERO, DVec3::ONE) * 255.0;
        [c.x.round() as u8, c.y.round() as u8, c.z.round() as u8]
    })
}

/// Colour preview of integer labels: each label gets a colour from [`label_colour`]; `miss`
/// is black.
pub fn label_image(values: &[u32], width: usize, miss: u32) -> RgbImage {
    image_from(values, width, |&v| {
        if v == miss {
            return [0, 0, 0];
        }
        label_colour(v)
    })
}

fn image_from<T>(values: &[T], width: usize, colour: impl Fn(&T) -> [u8; 3]) -> RgbImage {
    let height = values.len() / width.max(1);
    RgbImage::from_fn(width as u32, height as u32, |x, y| {
        image::Rgb(colour(&values[y as usize * width + x as usize]))
    })
}

/// Writes a preview as PNG to `out`.
pub fn write(out: &mut (impl Write + Seek), image: &RgbImage) -> Result<(), String> {
    image
        .write_to(out, ImageFormat::Png)
        .map_err(|e| format!("cannot write PNG: {e}"))
}
