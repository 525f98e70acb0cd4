#![no_main]
//! glTF and GLB: the check walker, the importer and the geometric checks.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"glTF") {
        "asset.glb"
    } else {
        "asset.gltf"
    };
    common::run(data, name);
});
