#![no_main]
//! PLY: the header and the three body encodings, read by `raycast check` (typed errors and
//! the geometric checks) and as a render reads it.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::run(data, "asset.ply");
    common::load(data, "asset.ply");
});
