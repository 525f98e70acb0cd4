#![no_main]
//! USD: text (.usda) and binary crate (.usdc) layers through openusd and the importer.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let name = if data.starts_with(b"PXR-USDC") {
        "asset.usdc"
    } else {
        "asset.usda"
    };
    common::tolerate_caught_panics();
    let strict = std::env::var_os("RAYCAST_FUZZ_STRICT").is_some();
    common::run_with(data, name, !strict);
});
