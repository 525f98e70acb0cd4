//! Cryptomatte mattes (`--cryptomatte`), as the Cryptomatte specification (v1.2.0, Psyop)
//! defines them, in `cryptomatte.exr`: two layers, objects (`CryptoObject`, by the `id`
//! AOV) and materials (`CryptoMaterial`, by the `material` AOV), each written by the same
//! rules:
//!
//! - each object's (material's) name is hashed with MurmurHash3_32 (seed 0) and the hash stored as the
//!   float32 of the same bits, its exponent clamped to 1..=254 so that no id is a NaN, an
//!   infinity, zero or a denormal;
//! - each pixel's objects are ranked by coverage (the share of its `spp` stratified samples
//!   that hit them; misses are background and not ranked), and rank pairs are written as the
//!   channels `CryptoObject00.R` (rank 0 id), `.G` (its coverage), `.B`, `.A` (rank 1), then
//!   `CryptoObject01` for ranks 2 and 3, and so on, empty ranks 0 (a hit without material
//!   is not ranked in the material layer, as a miss);
//! - the header says `cryptomatte/KEY/name` (the layer's name), `/hash` (`MurmurHash3_32`),
//!   `/conversion` (`uint32_to_float32`) and `/manifest` (JSON: each name and its hash in
//!   eight hex digits), KEY being the first seven hex digits of the layer name's hash.

use super::exr::{self, ExrChannel};
use crate::error::Result;
use std::io::{Seek, Write};

/// The layer of object mattes.
pub const OBJECT_LAYER: &str = "CryptoObject";

/// The layer of material mattes.
pub const MATERIAL_LAYER: &str = "CryptoMaterial";

/// One layer of mattes: its name, each pixel's ranked labels (from [`rank`]) and the names
/// the labels stand for (`names[label - 1]`, made unique by [`unique_names`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// `CryptoObject` or `CryptoMaterial`.
    pub name: &'static str,
    /// Per pixel, the labels by coverage.
    pub ranked: Vec<Vec<(u32, f32)>>,
    /// The names of the labels.
    pub names: Vec<String>,
}

/// The file written.
pub const FILE: &str = "cryptomatte.exr";

/// Rank pairs written per layer: `CryptoObject00` … `CryptoObject02`, six per pixel.
pub const LEVELS: usize = 3;

/// MurmurHash3's 32-bit hash of `bytes` with seed 0 (Austin Appleby's x86_32 variant).
pub fn murmur3_32(bytes: &[u8]) -> u32 {
    const C1: u32 = 0xcc9e_2d51;
    const C2: u32 = 0x1b87_3593;
    let mut h: u32 = 0;
    let blocks = bytes.chunks_exact(4);
    let tail = blocks.remainder();
    for block in blocks {
        let k = u32::from_le_bytes([block[0], block[1], block[2], block[3]]);
        h ^= k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
        h = h.rotate_left(13).wrapping_mul(5).wrapping_add(0xe654_6b64);
    }
    if !tail.is_empty() {
        let k = tail
            .iter()
            .rev()
            .fold(0u32, |k, &b| (k << 8) | u32::from(b));
        h ^= k.wrapping_mul(C1).rotate_left(15).wrapping_mul(C2);
    }
    h ^= bytes.len() as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^ (h >> 16)
}

/// The float32 id of `hash`: the same bits, the exponent clamped to 1..=254.
pub fn hash_to_float(hash: u32) -> f32 {
    let exponent = ((hash >> 23) & 0xff).clamp(1, 254);
    f32::from_bits((hash & 0x807f_ffff) | (exponent << 23))
}

/// The manifest key of a layer: the first seven hex digits of its name's hash.
fn layer_key(layer: &str) -> String {
    format!("{:08x}", murmur3_32(layer.as_bytes()))[..7].to_string()
}

/// The JSON manifest of `names` and their `hashes`: `{"name": "hash in eight hex digits", …}`.
fn manifest(names: &[String], hashes: &[u32]) -> String {
    let entries: serde_json::Map<String, serde_json::Value> = names
        .iter()
        .zip(hashes)
        .map(|(n, h)| (n.clone(), format!("{h:08x}").into()))
        .collect();
    serde_json::Value::Object(entries).to_string()
}

/// Each pixel's labels (1-based, as the `id` and `material` AOVs) by coverage, most first
/// (ties: the lower label first), at most `2 · LEVELS`: `samples` holds `spp` labels per
/// pixel, 0 for a miss (or no material).
pub fn rank(samples: &[u32], spp: usize) -> Vec<Vec<(u32, f32)>> {
    samples
        .chunks_exact(spp)
        .map(|pixel| {
            let mut counts: Vec<(u32, usize)> = Vec::new();
            for &id in pixel.iter().filter(|&&id| id != 0) {
                match counts.iter_mut().find(|(i, _)| *i == id) {
                    Some((_, n)) => *n += 1,
                    None => counts.push((id, 1)),
                }
            }
            counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
            counts.truncate(2 * LEVELS);
            counts
                .into_iter()
                .map(|(id, n)| (id, (n as f64 / spp as f64) as f32))
                .collect()
        })
        .collect()
}

/// Writes the mattes of `layers` as a `width`×`height` EXR to `out`.
pub fn write(
    out: &mut (impl Write + Seek),
    width: usize,
    height: usize,
    layers: &[Layer],
) -> Result<()> {
    let mut channels = Vec::with_capacity(4 * LEVELS * layers.len());
    let mut notes = Vec::new();
    for layer in layers {
        let hashes: Vec<u32> = layer
            .names
            .iter()
            .map(|n| murmur3_32(n.as_bytes()))
            .collect();
        channels.extend(layer_channels(layer, &hashes));
        let key = layer_key(layer.name);
        notes.extend([
            (format!("cryptomatte/{key}/name"), layer.name.to_string()),
            (
                format!("cryptomatte/{key}/hash"),
                "MurmurHash3_32".to_string(),
            ),
            (
                format!("cryptomatte/{key}/conversion"),
                "uint32_to_float32".to_string(),
            ),
            (
                format!("cryptomatte/{key}/manifest"),
                manifest(&layer.names, &hashes),
            ),
        ]);
    }
    exr::write(out, width, height, channels, &notes)
}

/// The rank-pair channels of one layer whose names hash to `hashes`.
fn layer_channels(layer: &Layer, hashes: &[u32]) -> Vec<ExrChannel> {
    let ids: Vec<f32> = hashes.iter().map(|&h| hash_to_float(h)).collect();
    let mut channels = Vec::with_capacity(4 * LEVELS);
    for level in 0..LEVELS {
        for (c, channel) in ["R", "G", "B", "A"].iter().enumerate() {
            let rank = 2 * level + c / 2;
            let values = (layer.ranked.iter())
                .map(|pixel| match pixel.get(rank) {
                    Some(&(id, _)) if c % 2 == 0 => ids[id as usize - 1],
                    Some(&(_, coverage)) => coverage,
                    None => 0.0,
                })
                .collect();
            let name = format!("{}{level:02}.{channel}", layer.name);
            channels.push(ExrChannel::Float(name, values));
        }
    }
    channels
}

/// The names objects (or materials) are matted by: each name, made unique by ` #ID` (its
/// 1-based label) where two share one (or it is empty), so that each has a matte of its own.
pub fn unique_names(names: impl Iterator<Item = String>) -> Vec<String> {
    let names: Vec<String> = names.collect();
    let mut uses: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for n in &names {
        *uses.entry(n.as_str()).or_default() += 1;
    }
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let shared = n.is_empty() || uses[n.as_str()] > 1;
            if shared {
                format!("{n} #{}", i + 1)
            } else {
                n.clone()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn murmur3_matches_published_values() {
        // Reference values of MurmurHash3_x86_32 with seed 0 (SMHasher's verification set).
        assert_eq!(murmur3_32(b""), 0);
        assert_eq!(murmur3_32(b"hello"), 0x248b_fa47);
        assert_eq!(murmur3_32(b"Hello, world!"), 0xc036_3e43);
        assert_eq!(
            murmur3_32(b"The quick brown fox jumps over the lazy dog"),
            0x2e4f_f723
        );
    }

    #[test]
    fn ids_are_never_special_floats() {
        for hash in [0u32, 0x7f80_0000, 0xff80_0001, 0x0000_0001, 0x7fff_ffff] {
            let f = hash_to_float(hash);
            assert!(f.is_normal(), "{hash:#x} -> {f}");
        }
        assert_eq!(hash_to_float(0x4000_0000).to_bits(), 0x4000_0000);
    }

    #[test]
    fn ranks_by_coverage_then_id() {
        let ranked = rank(&[2, 2, 1, 0, 3, 3, 3, 3], 4);
        assert_eq!(ranked[0], vec![(2, 0.5), (1, 0.25)]);
        assert_eq!(ranked[1], vec![(3, 1.0)]);
    }

    #[test]
    fn shared_names_get_their_id() {
        let names = unique_names(["a", "b", "a", ""].map(String::from).into_iter());
        assert_eq!(names, ["a #1", "b", "a #3", " #4"]);
    }
}
