//! Shared by the fuzz targets: write the input to a file in a private empty folder (the
//! asset's folder tree, so nothing outside it can be read) and run `raycast check` on it,
//! or the importer as a render runs it.

use raycast::check::{check_asset, Asset, CheckOptions};
use std::path::PathBuf;

/// Lets panics that the importer catches (openusd's, turned into "the USD reader failed"
/// errors) pass instead of aborting, unless RAYCAST_FUZZ_STRICT is set: they are upstream
/// bugs already recorded in fixtures/fuzz/ and would stop every run at the first one. A
/// panic that reaches `check_asset` (INTERNAL_PANIC) still aborts the run.
pub fn tolerate_caught_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    if std::env::var_os("RAYCAST_FUZZ_STRICT").is_none() {
        ONCE.call_once(|| std::panic::set_hook(Box::new(|_| {})));
    }
}

/// Writes the input where [`run`] does and loads it as `raycast` and `raycast info` do
/// (fail-fast); errors are fine, a panic is a bug.
pub fn load(data: &[u8], name: &str) {
    let dir = std::env::temp_dir().join(format!("raycast-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path: PathBuf = dir.join(name);
    if std::fs::write(&path, data).is_ok() {
        let _ = raycast::import::load(&path, &raycast::import::LoadOptions::default());
    }
}

pub fn run(data: &[u8], name: &str) {
    run_with(data, name, false)
}

pub fn run_with(data: &[u8], name: &str, upstream_ok: bool) {
    let dir = std::env::temp_dir().join(format!("raycast-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path: PathBuf = dir.join(name);
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let options = CheckOptions {
        // Small limits keep each run fast; the limits themselves are under test too.
        max_bytes: 64 << 20,
        ..CheckOptions::default()
    };
    let report = check_asset(&Asset::found_in(path, &dir), &options);
    for finding in &report.findings {
        // Panics are caught per asset (and the USD importer turns openusd panics into
        // errors): both are still bugs for the fuzzer. Only a USD asset's message is read for
        // them: other readers quote the input, which the fuzzer soon makes say the words.
        let usd = name.contains(".usd");
        let upstream = usd && finding.message.contains("the USD reader failed");
        if finding.code == "INTERNAL_PANIC" || (upstream && !upstream_ok) {
            panic!("{}: {}", finding.code, finding.message);
        }
    }
}
