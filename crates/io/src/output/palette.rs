//! The colours of the id and prim previews: the first [`SPREAD_IDS`] ids each get a colour
//! chosen to be far from every other's (so that any two objects of a scene of that many are
//! told apart wherever they meet in the image), later ids colours stepped around the OKLCh
//! hue circle.

use std::sync::OnceLock;

/// Ids with a colour from the spread palette ([`spread_palette`]); a scene of up to this many
/// objects has every two colours at least 90 apart in 8-bit sRGB (the sum of the channels'
/// differences) and 0.08 in OKLab (four times a just-noticeable difference, about 0.02).
pub const SPREAD_IDS: usize = 64;

/// The sRGB levels the spread palette is chosen from, per channel: 0, 15, ..., 255.
const LEVEL_STEP: usize = 15;

/// Darkest OKLab lightness a label colour may have: misses are black.
const MIN_LIGHTNESS: f64 = 0.4;

/// Weight of the OKLab distance against the sRGB one in the spread palette's choice (OKLab
/// distances are about a thousandth of sRGB sums for colours of equal difference).
const OKLAB_WEIGHT: f64 = 1000.0;

/// Hue step between consecutive labels beyond the spread palette: the golden angle, so that
/// hues never repeat and neighbours are far apart on the colour wheel.
const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// The colour of label `v`: for `1..=SPREAD_IDS` its entry of [`spread_palette`]; otherwise
/// OKLCh hue stepping by the golden angle, chroma 0.12 and lightness cycling through three
/// levels, so that labels close in number differ in both hue and lightness (at least 0.1
/// apart in OKLab).
pub fn label_colour(v: u32) -> [u8; 3] {
    if let Some(&colour) = (v as usize)
        .checked_sub(1)
        .and_then(|i| spread_palette().get(i))
    {
        return colour;
    }
    let hue = f64::from(v) * GOLDEN_ANGLE;
    let lightness = [0.62, 0.78, 0.9][v as usize % 3];
    let chroma = 0.12;
    oklab_to_srgb(lightness, chroma * hue.cos(), chroma * hue.sin())
}

/// [`SPREAD_IDS`] colours, each in turn the sRGB grid colour (lighter than
/// [`MIN_LIGHTNESS`]) farthest from black and from the colours before it, by the smaller of
/// the sRGB sum of differences and the weighted OKLab distance: a greedy farthest-point
/// order, so that the first `n` colours are spread for every `n`.
pub fn spread_palette() -> &'static [[u8; 3]] {
    static PALETTE: OnceLock<Vec<[u8; 3]>> = OnceLock::new();
    PALETTE.get_or_init(|| {
        let levels: Vec<u8> = (0..=255).step_by(LEVEL_STEP).collect();
        let mut candidates = Vec::new();
        for &r in &levels {
            for &g in &levels {
                for &b in &levels {
                    let lab = srgb_to_oklab([r, g, b]);
                    if lab[0] > MIN_LIGHTNESS {
                        candidates.push(([r, g, b], lab));
                    }
                }
            }
        }
        let black = ([0, 0, 0], srgb_to_oklab([0, 0, 0]));
        let mut nearest: Vec<f64> = candidates.iter().map(|c| distance(c, &black)).collect();
        let mut palette = Vec::with_capacity(SPREAD_IDS);
        for _ in 0..SPREAD_IDS {
            let far =
                (0..candidates.len()).fold(
                    0,
                    |best, i| {
                        if nearest[i] > nearest[best] {
                            i
                        } else {
                            best
                        }
                    },
                );
            palette.push(candidates[far].0);
            for (d, c) in nearest.iter_mut().zip(&candidates) {
                *d = d.min(distance(c, &candidates[far]));
            }
        }
        palette
    })
}

/// The spread palette's distance between two colours (sRGB and OKLab forms).
fn distance(a: &([u8; 3], [f64; 3]), b: &([u8; 3], [f64; 3])) -> f64 {
    let srgb: f64 = (0..3).map(|i| f64::from(a.0[i].abs_diff(b.0[i]))).sum();
    srgb.min(OKLAB_WEIGHT * oklab_distance(a.1, b.1))
}

/// Euclidean distance in OKLab.
pub fn oklab_distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// 8-bit sRGB to OKLab (Björn Ottosson's published forward transform).
pub fn srgb_to_oklab(rgb: [u8; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(|c| {
        let c = f64::from(c) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    });
    let l = (0.412_221_470_8 * r + 0.536_332_536_3 * g + 0.051_445_992_9 * b).cbrt();
    let m = (0.211_903_498_2 * r + 0.680_699_545_1 * g + 0.107_396_956_6 * b).cbrt();
    let s = (0.088_302_461_9 * r + 0.281_718_837_6 * g + 0.629_978_700_5 * b).cbrt();
    [
        0.210_454_255_3 * l + 0.793_617_785_0 * m - 0.004_072_046_8 * s,
        1.977_998_495_1 * l - 2.428_592_205_0 * m + 0.450_593_709_9 * s,
        0.025_904_037_1 * l + 0.782_771_766_2 * m - 0.808_675_766_0 * s,
    ]
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum of the channels' differences of two 8-bit colours.
    fn srgb_difference(a: [u8; 3], b: [u8; 3]) -> u32 {
        (0..3).map(|i| u32::from(a[i].abs_diff(b[i]))).sum()
    }

    /// Any two of the first 64 ids, wherever they meet in a preview: at least 90 apart in
    /// sRGB (the review's measure; the chess set's 33 objects met at 25) and 0.08 in OKLab.
    #[test]
    fn any_two_of_the_first_ids_get_clearly_different_colours() {
        let colours: Vec<[u8; 3]> = (1..=SPREAD_IDS as u32).map(label_colour).collect();
        for (i, &a) in colours.iter().enumerate() {
            assert!(srgb_to_oklab(a)[0] > MIN_LIGHTNESS, "id {}: {a:?}", i + 1);
            for (j, &b) in colours.iter().enumerate().skip(i + 1) {
                let lab = oklab_distance(srgb_to_oklab(a), srgb_to_oklab(b));
                assert!(
                    srgb_difference(a, b) >= 90 && lab >= 0.08,
                    "ids {} and {}: {a:?} {b:?} ({lab})",
                    i + 1,
                    j + 1
                );
            }
        }
    }

    #[test]
    fn later_neighbouring_ids_get_clearly_different_colours() {
        // The closest pair among ids at most `gap` apart, for each gap.
        let mut closest = [f64::INFINITY; 9];
        for a in SPREAD_IDS as u32 + 1..=SPREAD_IDS as u32 + 256 {
            for gap in 1..=8 {
                let (x, y) = (
                    srgb_to_oklab(label_colour(a)),
                    srgb_to_oklab(label_colour(a + gap)),
                );
                closest[gap as usize] = closest[gap as usize].min(oklab_distance(x, y));
            }
            // Never black (a miss) nor close to it.
            assert!(srgb_to_oklab(label_colour(a))[0] > 0.5);
        }
        // Adjacent ids: five times a just-noticeable difference (about 0.02); ids up to 8 apart:
        // twice.
        assert!(closest[1..=2].iter().all(|&d| d >= 0.1), "{closest:?}");
        assert!(closest[1..].iter().all(|&d| d >= 0.04), "{closest:?}");
    }
}
