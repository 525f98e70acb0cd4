#![no_main]
//! OBJ: the line scanner, tobj and the geometric checks.

#[path = "common.rs"]
mod common;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    common::run(data, "asset.obj");
});
