//! The Cryptomatte pass of a camera run (`--cryptomatte --spp N`): N stratified samples per
//! pixel, traced for the object id and the material only, band of rows by band of rows (so
//! that no more than about a million samples are held at a time), ranked per pixel by
//! coverage ([`crate::output::cryptomatte`]).

use crate::error::{Error, Result};
use crate::output::cryptomatte::{self, Layer};
use crate::render::samples::PixelSamples;
use crate::render::{self, Aov, CameraView, Rays};
use crate::trace::Tracer;

/// Most samples traced at once.
const BAND_SAMPLES: usize = 1 << 20;

/// Most samples per pixel.
pub const MAX_SPP: usize = 1024;

/// The side of the grid of `spp` samples per pixel, or a usage error when `spp` is not a
/// square from 1 to [`MAX_SPP`].
pub(super) fn side(spp: usize) -> Result<usize> {
    let side = (1..=32).find(|s| s * s >= spp).unwrap_or(usize::MAX);
    if side.checked_mul(side) == Some(spp) && spp <= MAX_SPP {
        Ok(side)
    } else {
        Err(Error::usage(format!(
            "--spp {spp}: give a square number of samples per pixel (1, 4, 9, 16, … up to \
             {MAX_SPP}): they lie on a regular grid over each pixel"
        )))
    }
}

/// The object and material layers of `view`, from `spp` samples per pixel.
pub(super) fn mattes(tracer: &Tracer, view: &CameraView, spp: usize) -> Result<[Layer; 2]> {
    let side = side(spp)?;
    let band = (BAND_SAMPLES / (view.width * spp)).max(1);
    let pixels = view.width * view.height;
    let (mut objects, mut materials) = (Vec::with_capacity(pixels), Vec::with_capacity(pixels));
    for start in (0..view.height).step_by(band) {
        let samples = PixelSamples {
            view,
            side,
            rows: start..(start + band).min(view.height),
        };
        let rays = Rays {
            source: &samples,
            range: |_| (0.0, f64::INFINITY),
            refuse_untraceable: false,
        };
        let buffers = render::trace(tracer, &rays, &[Aov::Id, Aov::Material], |_| {})
            .map_err(|i| Error::msg(format!("cryptomatte sample {i} cannot be traced")))?;
        let labels = |aov| buffers.labels(aov).unwrap_or_default();
        objects.extend(cryptomatte::rank(labels(Aov::Id), spp));
        materials.extend(cryptomatte::rank(labels(Aov::Material), spp));
    }
    let scene = tracer.scene;
    let names = |names: Vec<String>| cryptomatte::unique_names(names.into_iter());
    Ok([
        Layer {
            name: cryptomatte::OBJECT_LAYER,
            ranked: objects,
            names: names(scene.objects.iter().map(|o| o.name.clone()).collect()),
        },
        Layer {
            name: cryptomatte::MATERIAL_LAYER,
            ranked: materials,
            names: names(scene.materials().to_vec()),
        },
    ])
}
