//! PNG previews a person can read: depth as grey (near light, far dark), normals as colours,
//! ids as distinct colours; misses are black.

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

/// Hue step between consecutive labels: the golden angle, so that hues never repeat and
/// neighbours are far apart on the colour wheel.
const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// The colour of label `v`: OKLCh hue stepping by the golden angle, chroma 0.12 and lightness
/// cycling through three levels, so that labels close in number (neighbouring ids) differ in
/// both hue and lightness — at least 0.1 apart in OKLab, well above a just-noticeable
/// difference (about 0.02).
pub fn label_colour(v: u32) -> [u8; 3] {
    let hue = f64::from(v) * GOLDEN_ANGLE;
    let lightness = [0.62, 0.78, 0.9][v as usize % 3];
    let chroma = 0.12;
    oklab_to_srgb(lightness, chroma * hue.cos(), chroma * hue.sin())
}

/// OKLab to 8-bit sRGB (Björn Ottosson's matrices), clamped to the gamut.
fn oklab_to_srgb(l: f64, a: f64, b: f64) -> [u8; 3] {
    let l_ = l + 0.396_337_777_4 * a + 0.215_803_757_3 * b;
    let m_ = l - 0.105_561_345_8 * a - 0.063_854_172_8 * b;
    let s_ = l - 0.089_484_177_5 * a - 1.291_485_548_0 * b;
    let (l3, m3, s3) = (l_.powi(3), m_.powi(3), s_.powi(3));
    let linear = [
        4.076_741_662_1 * l3 - 3.307_711_591_3 * m3 + 0.230_969_929_2 * s3,
        -1.268_438_004_6 * l3 + 2.609_757_401_1 * m3 - 0.341_319_396_5 * s3,
        -0.004_196_086_3 * l3 - 0.703_418_614_7 * m3 + 1.707_614_701_0 * s3,
    ];
    linear.map(|c| {
        let c = c.clamp(0.0, 1.0);
        let encoded = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (encoded * 255.0).round() as u8
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

#[cfg(test)]
mod tests {
    use super::*;

    /// 8-bit sRGB to OKLab, written from the published forward transform (the inverse of what
    /// the palette uses), to measure the colours the preview actually holds.
    fn oklab(rgb: [u8; 3]) -> [f64; 3] {
        let [r, g, b] = rgb.map(|c| {
            let c = f64::from(c) / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        });
        let l = (0.4122214708 * r + 0.5363325363 * g + 0.0514459929 * b).cbrt();
        let m = (0.2119034982 * r + 0.6806995451 * g + 0.1073969566 * b).cbrt();
        let s = (0.0883024619 * r + 0.2817188376 * g + 0.6299787005 * b).cbrt();
        [
            0.2104542553 * l + 0.7936177850 * m - 0.0040720468 * s,
            1.9779984951 * l - 2.4285922050 * m + 0.4505937099 * s,
            0.0259040371 * l + 0.7827717662 * m - 0.8086757660 * s,
        ]
    }

    #[test]
    fn neighbouring_ids_get_clearly_different_colours() {
        // The closest pair among ids at most `gap` apart, for each gap.
        let mut closest = [f64::INFINITY; 9];
        for a in 1..=256u32 {
            for gap in 1..=8 {
                let (x, y) = (oklab(label_colour(a)), oklab(label_colour(a + gap)));
                let distance = (0..3).map(|i| (x[i] - y[i]).powi(2)).sum::<f64>().sqrt();
                closest[gap as usize] = closest[gap as usize].min(distance);
            }
            // Never black (a miss) nor close to it.
            assert!(oklab(label_colour(a))[0] > 0.5);
        }
        // Adjacent ids: five times a just-noticeable difference (about 0.02); ids up to 8 apart:
        // twice.
        assert!(closest[1..=2].iter().all(|&d| d >= 0.1), "{closest:?}");
        assert!(closest[1..].iter().all(|&d| d >= 0.04), "{closest:?}");
    }
}
