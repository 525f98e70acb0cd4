#![no_main]
//! STL: the binary/ASCII decision, the solids of an ASCII file and stl_io, read by
//! `raycast check` and as a render reads it.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::run(data, "asset.stl");
    common::load(data, "asset.stl");
});
