#![no_main]
//! glTF and GLB: the document layer read collect-all by `check` (with the validator's rules,
//! the scene build and the geometric checks), and fail-fast as a render reads it.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"glTF") {
        "asset.glb"
    } else {
        "asset.gltf"
    };
    common::run(data, name);
    common::load(data, name);
});
