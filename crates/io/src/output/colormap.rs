//! Colour maps for the distance previews (`--colormap`): `grey` (the default: near white, far
//! dark, one channel), `viridis` and `turbo` (three channels). Near is each map's top end
//! (white, yellow, dark red), far its bottom end (dark grey, purple, dark blue); misses are
//! black in every map.
//!
//! Viridis and Turbo are evaluated from published polynomial fits, not looked up in tables:
//! Matt Zucker's degree-6 fit of matplotlib's viridis (CC0, shadertoy `WlfXRN`) and Ruofei
//! Du's degree-5 fit of Google's Turbo (Apache-2.0, the "polynomial approximation" published
//! with Turbo). Both are previews: the exact distances are in the EXR and NPY files.

use crate::error::Error;
use image::RgbImage;
use std::fmt;
use std::str::FromStr;

/// A colour map of the distance previews.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Colormap {
    /// One channel of grey: near white, far at 15 % (the default).
    #[default]
    Grey,
    /// matplotlib's perceptually uniform viridis.
    Viridis,
    /// Google's Turbo rainbow.
    Turbo,
}

impl Colormap {
    /// All maps, as `--colormap` lists them.
    pub const ALL: [Colormap; 3] = [Colormap::Grey, Colormap::Viridis, Colormap::Turbo];

    /// The name on the command line and in the sidecar.
    pub fn name(self) -> &'static str {
        match self {
            Colormap::Grey => "grey",
            Colormap::Viridis => "viridis",
            Colormap::Turbo => "turbo",
        }
    }

    /// The 8-bit sRGB colour at `x` in [0, 1] (1: near). Grey as the one-channel preview.
    pub fn colour(self, x: f64) -> [u8; 3] {
        let x = x.clamp(0.0, 1.0);
        let rgb = match self {
            Colormap::Grey => [(40.0 + 215.0 * x) / 255.0; 3],
            Colormap::Viridis => viridis(x),
            Colormap::Turbo => turbo(x),
        };
        rgb.map(|c| (255.0 * c.clamp(0.0, 1.0)).round() as u8)
    }
}

impl fmt::Display for Colormap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Colormap {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        let s = if s == "gray" { "grey" } else { s };
        Colormap::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Colormap::ALL.iter().map(|m| m.name()).collect();
                Error::msg(format!(
                    "unknown colour map '{s}' (choose from {})",
                    names.join(", ")
                ))
            })
    }
}

/// Matt Zucker's polynomial fit of viridis.
fn viridis(t: f64) -> [f64; 3] {
    const C: [[f64; 3]; 7] = [
        [
            0.277_727_327_223_417_7,
            0.005_407_344_544_966_578,
            0.334_099_805_335_306_1,
        ],
        [
            0.105_093_043_108_577_4,
            1.404_613_529_898_575,
            1.384_590_162_594_685,
        ],
        [
            -0.330_861_828_725_556_3,
            0.214_847_559_468_213,
            0.095_095_163_028_236_59,
        ],
        [
            -4.634_230_498_983_486,
            -5.799_100_973_351_585,
            -19.332_440_956_279_87,
        ],
        [
            6.228_269_936_347_081,
            14.179_933_366_805_09,
            56.690_552_600_681_05,
        ],
        [
            4.776_384_997_670_288,
            -13.745_145_377_746_01,
            -65.353_032_633_372_34,
        ],
        [
            -5.435_455_855_934_631,
            4.645_852_612_178_535,
            26.312_435_249_583_2,
        ],
    ];
    [0, 1, 2].map(|k| C.iter().rev().fold(0.0, |acc, c| acc * t + c[k]))
}

/// Ruofei Du's polynomial fit of Turbo.
fn turbo(x: f64) -> [f64; 3] {
    const C: [[f64; 6]; 3] = [
        [
            0.135_721_38,
            4.615_392_60,
            -42.660_322_58,
            132.131_082_34,
            -152.942_393_96,
            59.286_379_43,
        ],
        [
            0.091_402_61,
            2.194_188_39,
            4.842_966_58,
            -14.185_033_33,
            4.277_298_57,
            2.829_566_04,
        ],
        [
            0.106_673_30,
            12.641_946_08,
            -60.582_048_36,
            110.362_767_71,
            -89.903_109_12,
            27.348_249_73,
        ],
    ];
    C.map(|c| c.iter().rev().fold(0.0, |acc, &k| acc * x + k))
}

/// A colour preview of a distance buffer mapped linearly from `range` (near: the map's top
/// end), misses black.
pub fn distance_image(values: &[f64], width: usize, range: [f64; 2], map: Colormap) -> RgbImage {
    let span = (range[1] - range[0]).max(f64::MIN_POSITIVE);
    let height = values.len() / width.max(1);
    RgbImage::from_fn(width as u32, height as u32, |x, y| {
        let v = values[y as usize * width + x as usize];
        match v.is_finite() {
            true => image::Rgb(map.colour(1.0 - ((v - range[0]) / span).clamp(0.0, 1.0))),
            false => image::Rgb([0; 3]),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fits' ends against matplotlib's and Google's published tables: viridis runs from
    /// (68, 1, 84) to (253, 231, 37), Turbo from (48, 18, 59) to (122, 4, 3); the fits are
    /// within these distances of them.
    #[test]
    fn the_fits_end_near_the_published_colours() {
        let near = |a: [u8; 3], b: [u8; 3], tolerance: i32| {
            (0..3).all(|k| (a[k] as i32 - b[k] as i32).abs() <= tolerance)
        };
        assert!(
            near(Colormap::Viridis.colour(0.0), [68, 1, 84], 3),
            "{:?}",
            Colormap::Viridis.colour(0.0)
        );
        assert!(
            near(Colormap::Viridis.colour(1.0), [253, 231, 37], 4),
            "{:?}",
            Colormap::Viridis.colour(1.0)
        );
        assert!(
            near(Colormap::Turbo.colour(0.5), [164, 252, 60], 30),
            "{:?}",
            Colormap::Turbo.colour(0.5)
        );
        assert_eq!(Colormap::Grey.colour(1.0), [255; 3]);
        assert_eq!(Colormap::Grey.colour(0.0), [40; 3]);
        assert_eq!("gray".parse::<Colormap>(), Ok(Colormap::Grey));
        assert!("jet".parse::<Colormap>().is_err());
    }
}
