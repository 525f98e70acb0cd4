//! PNG files: previews a person can read (distances as one channel of grey, near light and far
//! dark; normals as colours; ids as distinct colours; misses black), and distances as 16-bit
//! integers in a chosen unit, as the RGB-D datasets store depth.

use super::palette::label_colour;
use crate::error::{Error, Result};
use glam::DVec3;
use image::{DynamicImage, GrayImage, ImageBuffer, ImageFormat, Luma, RgbImage};
use std::io::{Seek, Write};

/// How the distance PNGs (depth and z) are written.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum DistancePng {
    /// An 8-bit grey preview over a range of distances.
    #[default]
    Preview,
    /// 16-bit integers: each distance divided by `scale` (scene units per step) and rounded;
    /// 0 for a miss and for a distance that rounds to 0 or above 65535 (no data), as TUM, ScanNet
    /// and BOP store depth.
    U16 {
        /// Scene units per integer step (0.001: millimetres of a scene in metres).
        scale: f64,
    },
}

/// The 16-bit value of `distance` at `scale` scene units per step: 0 (no data) for a miss, a
/// value that rounds to 0, or one past 65535.
pub fn u16_step(distance: f64, scale: f64) -> u16 {
    let steps = (distance / scale).round();
    if steps.is_finite() && (1.0..=f64::from(u16::MAX)).contains(&steps) {
        steps as u16
    } else {
        0
    }
}

/// A distance buffer as 16-bit integers of `scale` scene units (see [`u16_step`]).
pub fn distance_u16(values: &[f64], width: usize, scale: f64) -> ImageBuffer<Luma<u16>, Vec<u16>> {
    let height = values.len() / width.max(1);
    ImageBuffer::from_fn(width as u32, height as u32, |x, y| {
        Luma([u16_step(values[y as usize * width + x as usize], scale)])
    })
}

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

/// Grey preview of a distance buffer mapped linearly from `range` (near white, far at 15%),
/// one channel.
pub fn distance_image(values: &[f64], width: usize, range: [f64; 2]) -> GrayImage {
    let span = (range[1] - range[0]).max(f64::MIN_POSITIVE);
    let height = values.len() / width.max(1);
    GrayImage::from_fn(width as u32, height as u32, |x, y| {
        let v = values[y as usize * width + x as usize];
        if !v.is_finite() {
            return Luma([0]);
        }
        Luma([(255.0 - 215.0 * ((v - range[0]) / span).clamp(0.0, 1.0)).round() as u8])
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

/// Writes an image as PNG to `out`.
pub fn write(out: &mut (impl Write + Seek), image: impl Into<DynamicImage>) -> Result<()> {
    image
        .into()
        .write_to(out, ImageFormat::Png)
        .map_err(|e| Error::msg(format!("cannot write PNG: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn u16_steps_round_and_leave_no_data_at_zero() {
        assert_eq!(u16_step(1.2344, 0.001), 1234);
        assert_eq!(u16_step(1.2346, 0.001), 1235);
        assert_eq!(u16_step(f64::INFINITY, 0.001), 0);
        assert_eq!(u16_step(0.0004, 0.001), 0);
        assert_eq!(u16_step(65.535, 0.001), 65535);
        assert_eq!(u16_step(65.5356, 0.001), 0);
        assert_eq!(u16_step(-1.0, 0.001), 0);
    }
}
