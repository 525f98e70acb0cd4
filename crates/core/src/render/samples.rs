//! Stratified samples of a camera's pixels, for passes that need more than the one exact ray
//! through each pixel's centre (Cryptomatte's coverage): `side`×`side` rays per pixel through
//! the centres of a regular grid over it, pixel by pixel, for a band of rows.

use super::CameraView;
use crate::geometry::Ray;
use crate::geometry::RaySource;
use std::ops::Range;

/// The samples of the pixels of rows `rows` of `view`, `side`² per pixel, ordered by pixel
/// (row-major), then by sample (row-major within the pixel).
pub struct PixelSamples<'a> {
    /// The camera's image.
    pub view: &'a CameraView,
    /// Samples per pixel side.
    pub side: usize,
    /// The rows sampled.
    pub rows: Range<usize>,
}

impl RaySource for PixelSamples<'_> {
    fn len(&self) -> usize {
        self.rows.len() * self.view.width * self.side * self.side
    }

    fn ray(&self, index: usize) -> Ray {
        let spp = self.side * self.side;
        let (pixel, sample) = (index / spp, index % spp);
        let (row, column) = (
            self.rows.start + pixel / self.view.width,
            pixel % self.view.width,
        );
        let step = 1.0 / self.side as f64;
        let x = column as f64 + (0.5 + (sample % self.side) as f64) * step;
        let y = row as f64 + (0.5 + (sample / self.side) as f64) * step;
        let view = self.view;
        view.camera
            .image_ray(x, y, view.width, view.height, view.half_height)
    }
}
