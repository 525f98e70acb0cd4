//! OpenEXR files through the `exr` crate: float channels for distances and vectors, UINT
//! channels for ids, and the buffer conventions written into the header.

use crate::error::{Error, Result};
use exr::prelude::*;
use std::io::{Seek, Write};

/// One channel of an image to write.
pub enum ExrChannel {
    /// A FLOAT channel.
    Float(String, Vec<f32>),
    /// A UINT channel.
    Uint(String, Vec<u32>),
}

/// Writes one layer holding `channels` and the text attributes `notes` (name, value) to `out`.
pub fn write(
    out: &mut (impl Write + Seek),
    width: usize,
    height: usize,
    channels: Vec<ExrChannel>,
    notes: &[(String, String)],
) -> Result<()> {
    let list: Vec<AnyChannel<FlatSamples>> = channels
        .into_iter()
        .map(|c| match c {
            ExrChannel::Float(name, v) => AnyChannel::new(name.as_str(), FlatSamples::F32(v)),
            ExrChannel::Uint(name, v) => AnyChannel::new(name.as_str(), FlatSamples::U32(v)),
        })
        .collect();
    let mut attributes = LayerAttributes::default();
    for (name, value) in notes {
        attributes.other.insert(
            Text::from(name.as_str()),
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
        .to_buffered(out)
        .map_err(|e| Error::msg(format!("cannot write EXR: {e}")))
}
