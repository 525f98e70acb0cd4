//! OpenEXR files through the `exr` crate: float channels for distances and vectors, UINT
//! channels for ids, and the buffer conventions written into the header.

use crate::error::{Error, Result};
use exr::prelude::*;
use std::path::Path;

/// One channel of an image to write.
pub enum ExrChannel {
    /// A FLOAT channel.
    Float(&'static str, Vec<f32>),
    /// A UINT channel.
    Uint(&'static str, Vec<u32>),
}

/// Writes one layer holding `channels` and the text attributes `notes` (name, value).
pub fn write(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<ExrChannel>,
    notes: &[(&str, String)],
) -> Result<()> {
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|c| match c {
            ExrChannel::Float(name, v) => AnyChannel::new(name, FlatSamples::F32(v)),
            ExrChannel::Uint(name, v) => AnyChannel::new(name, FlatSamples::U32(v)),
        })
        .collect();
    let mut attributes = LayerAttributes::default();
    for (name, value) in notes {
        attributes.other.insert(
            Text::from(*name),
            AttributeValue::Text(Text::from(value.as_str())),
        );
    }
    let layer = Layer::new(
        (width, height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(SmallVec::from_vec(list)),
    );
    Image::from_layer(layer)
        .write()
        .to_file(path)
        .map_err(|e| Error::in_file(path, format!("cannot write EXR: {e}")))
}
