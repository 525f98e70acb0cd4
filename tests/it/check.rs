//! `raycast check`: the glTF-Validator suite (agreement written to
//! `reports/validator_agreement.md`), the malformed and bad fixtures, fuzzing regressions,
//! the command line (exit codes, JSON, JUnit, GitHub annotations, path confinement) and a
//! run over `../shared/assets` when it is there.

use raycast::check::{check_asset, discover, Asset, AssetReport, CheckOptions, Severity};
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Files of the validator suite whose ERRORs get an error or warning from `check`: the
/// measured agreement may not fall below this.
const AGREEMENT_BASELINE: usize = 190;

/// The longest one asset of the fixtures may take.
const PER_FILE_LIMIT: Duration = Duration::from_secs(20);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn fixture(relative: &str) -> PathBuf {
    root().join("fixtures").join(relative)
}

fn timed(asset: &Asset) -> AssetReport {
    let report = check_asset(asset, &CheckOptions::default());
    assert!(
        Duration::from_secs_f64(report.seconds) < PER_FILE_LIMIT,
        "{} took {:.1}s",
        report.path,
        report.seconds
    );
    assert!(
        !report
            .findings
            .iter()
            .any(|f| f.code.name() == "INTERNAL_PANIC"),
        "{}: {:?}",
        report.path,
        report.findings
    );
    report
}

fn codes(report: &AssetReport, severities: &[Severity]) -> BTreeSet<String> {
    report
        .findings
        .iter()
        .filter(|f| severities.contains(&f.severity))
        .map(|f| f.code.name().to_string())
        .collect()
}

/// Codes that say nothing about the file's validity in the validator's sense.
fn incidental(code: &str) -> bool {
    matches!(code, "EMPTY_SCENE" | "LOAD_FAILED")
}

#[test]
fn validator_suite_agreement() {
    let suite = fixture("gltf-validator");
    let assets = discover(std::slice::from_ref(&suite)).expect("the suite is in fixtures/");
    assert!(
        assets.len() >= 250,
        "only {} files in the suite",
        assets.len()
    );
    let mut rows = Vec::new();
    let (mut with_errors, mut agree, mut exact, mut specific) = (0, 0, 0, 0);
    let mut false_errors = Vec::new();
    let mut clean = Vec::new();
    for asset in &assets {
        let report = timed(asset);
        let report_path = PathBuf::from(format!("{}.report.json", asset.path.display()));
        let text = std::fs::read_to_string(&report_path)
            .unwrap_or_else(|e| panic!("{}: {e}", report_path.display()));
        let verdict: Value = serde_json::from_str(&text).expect("report.json is JSON");
        let validator: BTreeSet<String> = verdict["issues"]["messages"]
            .as_array()
            .map(|m| m.as_slice())
            .unwrap_or_default()
            .iter()
            .filter(|m| m["severity"] == 0)
            .filter_map(|m| m["code"].as_str().map(String::from))
            .collect();
        let ours = codes(&report, &[Severity::Error, Severity::Warning]);
        let name = asset
            .path
            .strip_prefix(&suite)
            .unwrap_or(&asset.path)
            .display()
            .to_string();
        if validator.is_empty() {
            let errors = codes(&report, &[Severity::Error]);
            if !errors.is_empty() {
                false_errors.push((name.clone(), errors.clone()));
            }
            let warnings = codes(&report, &[Severity::Warning]);
            clean.push((name, errors, warnings, report.scene.clone()));
            continue;
        }
        with_errors += 1;
        let agrees = !ours.is_empty();
        let same_code = validator.iter().any(|c| ours.contains(c));
        let own = ours.iter().any(|c| !incidental(c));
        agree += agrees as usize;
        exact += same_code as usize;
        specific += own as usize;
        rows.push((name, validator, ours, agrees, same_code, own));
    }
    let mut md = String::new();
    md.push_str("# glTF-Validator suite: agreement of `raycast check`\n\n");
    md.push_str(
        "Written by `tests/it/check.rs` (`cargo test --test it check::validator_suite_agreement`) from\n",
    );
    md.push_str("`fixtures/gltf-validator/` (the Khronos glTF-Validator `test/base/data`, each file with the\n");
    md.push_str("validator's own `report.json`). Do not edit by hand.\n\n");
    md.push_str(&format!(
        "- Files in the suite: {}; the validator reports an ERROR for {with_errors}.\n",
        assets.len()
    ));
    md.push_str(&format!(
        "- **Agreement** (the file gets an error or warning from `check`): **{agree} of {with_errors}**.\n"
    ));
    md.push_str(&format!(
        "- Flagged by a finding of its own (not only `LOAD_FAILED` from the importer or `EMPTY_SCENE`): {specific} of {with_errors}.\n"
    ));
    md.push_str(&format!(
        "- Same code as the validator (at least one of its error codes among ours): {exact} of {with_errors}.\n"
    ));
    let loaded = clean.iter().filter(|c| c.3.is_some()).count();
    md.push_str(&format!(
        "- Validator-clean files: {}. **False errors** (`check` gives one an error): **{}**. The importer builds a scene for {loaded} of them (listed at the end).\n\n",
        clean.len(),
        false_errors.len()
    ));
    md.push_str(
        "| file | validator's error codes | our errors and warnings | agree? | same code? |\n",
    );
    md.push_str("| --- | --- | --- | --- | --- |\n");
    let join = |s: &BTreeSet<String>| {
        if s.is_empty() {
            "—".to_string()
        } else {
            s.iter().cloned().collect::<Vec<_>>().join(", ")
        }
    };
    for (name, validator, ours, agrees, same, own) in &rows {
        let verdict = match (agrees, own) {
            (false, _) => "**no**",
            (true, false) => "yes (incidental)",
            (true, true) => "yes",
        };
        md.push_str(&format!(
            "| `{name}` | {} | {} | {verdict} | {} |\n",
            join(validator),
            join(ours),
            if *same { "yes" } else { "no" }
        ));
    }
    md.push_str("\n## Misses\n\n");
    let misses: Vec<_> = rows.iter().filter(|r| !r.3).collect();
    if misses.is_empty() {
        md.push_str("None: every file with a validator ERROR gets an error or warning.\n");
    }
    for (name, validator, ..) in misses {
        md.push_str(&format!("- `{name}`: {}\n", join(validator)));
    }
    md.push_str("\n## Incidental agreement\n\nFiles flagged only because the importer refuses them (`LOAD_FAILED`) or\nbecause the scene is empty; the validator's complaint itself is not detected:\n\n");
    for (name, validator, ..) in rows.iter().filter(|r| r.3 && !r.5) {
        md.push_str(&format!("- `{name}`: {}\n", join(validator)));
    }
    md.push_str("\n## Validator-clean files\n\n");
    md.push_str(
        "What `check` says about each file the validator finds no error in, and the scene the\n",
    );
    md.push_str(
        "importer builds from it (the one `raycast` renders; the same code builds both).\n\n",
    );
    md.push_str("| file | our errors | our warnings | scene |\n| --- | --- | --- | --- |\n");
    for (name, errors, warnings, scene) in &clean {
        let scene = match scene {
            Some(s) => format!("{} objects, {} triangles", s.objects, s.triangles),
            None => "**not built**".to_string(),
        };
        md.push_str(&format!(
            "| `{name}` | {} | {} | {scene} |\n",
            join(errors),
            join(warnings)
        ));
    }
    let out = root().join("reports/validator_agreement.md");
    if std::fs::read_to_string(&out).ok().as_deref() != Some(md.as_str()) {
        std::fs::write(&out, &md).expect("reports/ is writable");
    }
    assert!(
        agree >= AGREEMENT_BASELINE,
        "agreement fell to {agree} of {with_errors} (baseline {AGREEMENT_BASELINE}); see reports/validator_agreement.md"
    );
    assert_eq!(
        loaded,
        clean.len(),
        "the importer refuses validator-clean files; see reports/validator_agreement.md"
    );
    // None since the glTF document layer (32 before it, all the old importer's limits).
    assert!(
        false_errors.is_empty(),
        "validator-clean files get errors: {false_errors:?}"
    );
}

#[test]
fn malformed_and_bad_fixtures_are_reported() {
    for folder in ["malformed", "bad"] {
        let assets = discover(&[fixture(folder)]).expect("fixtures exist");
        assert!(!assets.is_empty());
        for asset in &assets {
            let report = timed(asset);
            let name = asset
                .path
                .file_name()
                .and_then(|n| n.to_str())
                .unwrap_or("");
            // The tinygltf issue-440 file is valid once its chunk is read correctly.
            if name.starts_with("zero-sized-bin-chunk") {
                continue;
            }
            assert!(
                report.errors + report.warnings > 0,
                "{}: nothing found",
                report.path
            );
        }
    }
}

#[test]
fn specific_codes_on_bad_fixtures() {
    let expect = [
        ("bad/node_cycle.gltf", "NODE_LOOP"),
        ("bad/bad_index.gltf", "ACCESSOR_INDEX_OOB"),
        ("bad/nan_position.gltf", "ACCESSOR_INVALID_FLOAT"),
        ("bad/not_json.gltf", "INVALID_JSON"),
        ("bad/draco_required.gltf", "DRACO_INVALID"),
        ("bad/meshopt_required.gltf", "MESHOPT_INVALID"),
        ("bad/missing_buffer.gltf", "IO_ERROR"),
        ("bad/quadric_not_symmetric.gltf", "QUADRIC_INVALID"),
        ("bad/quadric_missing_r.gltf", "QUADRIC_INVALID"),
        ("bad/empty.gltf", "EMPTY_SCENE"),
        (
            "malformed/integer-out-of-bounds.gltf",
            "BUFFER_VIEW_TOO_LONG",
        ),
        (
            "gltf-validator/mesh/unresolved_positions.gltf",
            "UNRESOLVED_REFERENCE",
        ),
        ("fuzz/gltf/unbacked_sparse_bomb.gltf", "ASSET_TOO_LARGE"),
        ("fuzz/usd/deep_nesting.usda", "LOAD_FAILED"),
    ];
    for (file, code) in expect {
        let report = timed(&Asset::file(fixture(file)));
        assert!(
            report.findings.iter().any(|f| f.code.name() == code),
            "{file}: expected {code}, got {:?}",
            report.findings
        );
    }
    let clean = ["gltf/cube.gltf", "gltf/cube.glb", "gltf/instances.gltf"];
    for file in clean {
        let report = timed(&Asset::file(fixture(file)));
        assert_eq!(report.errors, 0, "{file}: {:?}", report.findings);
    }
}

/// Every input the fuzzers crashed on (fixtures/fuzz/<target>/) is reported without a panic
/// or a hang. They run through the command line, which checks USD assets in a child process:
/// some abort inside the USD reader (an allocation failure is not a panic).
#[test]
fn fuzzing_regressions() {
    let dir = fixture("fuzz");
    let expected = discover(std::slice::from_ref(&dir))
        .expect("fixtures/fuzz")
        .len();
    let out = raycast(&[
        "check",
        "--json",
        "--quiet",
        dir.to_str().unwrap_or_default(),
    ]);
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let reports = reports_without_panics(&String::from_utf8_lossy(&out.stdout), expected);
    for r in &reports {
        assert!(r["errors"].as_u64() >= Some(1), "{}: no error", r["path"]);
        assert!(r["seconds"].as_f64() < Some(PER_FILE_LIMIT.as_secs_f64()));
    }
    // The array that claimed 2^52 elements aborted the reader (USD_READER_CRASHED); it is now
    // read in chunks and the field reported as unreadable.
    let huge = reports
        .iter()
        .find(|r| {
            r["path"]
                .as_str()
                .is_some_and(|p| p.ends_with("openusd_usdc_huge_array.usdc"))
        })
        .expect("the abort regression is there");
    assert!(
        huge["findings"]
            .as_array()
            .is_some_and(|f| f.iter().any(|f| f["code"] == "USD_UNREADABLE_VALUE"
                && f["location"] == "/cube.faceVertexCounts")),
        "{huge}"
    );
}

/// Inputs on which the USD reader never finished (found by fuzzing; an ancestor walk on a
/// path that was its own parent) are refused well within `--timeout`, as `USD_INVALID_PATH`
/// (they were `USD_READER_CRASHED` after it); the child process and its timeout stay the last
/// line of defence (`fuzzing_regressions`: an abort is `USD_READER_CRASHED`).
#[test]
fn usd_reader_hangs_are_stopped() {
    let dir = fixture("fuzz-hang");
    let out = raycast(&[
        "check",
        "--json",
        "--quiet",
        "--timeout",
        "20",
        dir.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(text.lines().count(), 2, "{text}");
    for line in text.lines() {
        let r: Value = serde_json::from_str(line).expect("JSON");
        assert!(
            r["findings"]
                .as_array()
                .is_some_and(|f| f.iter().any(|f| f["code"] == "USD_INVALID_PATH")),
            "{line}"
        );
    }
}

struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("raycast-check-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        Scratch(dir)
    }

    fn write(&self, name: &str, text: &[u8]) -> PathBuf {
        let path = self.0.join(name);
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent).expect("folder");
        }
        std::fs::write(&path, text).expect("write");
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A unit cube as OBJ text; `flip` reverses every face, `drop` leaves faces out.
fn cube_obj(flip: bool, drop: usize) -> String {
    let mut text = String::new();
    for v in 0..8 {
        text += &format!("v {} {} {}\n", v & 1, (v >> 1) & 1, (v >> 2) & 1);
    }
    let faces = [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ];
    for face in faces.iter().skip(drop) {
        let mut f = face.to_vec();
        if flip {
            f.reverse();
        }
        text += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    text
}

/// An OBJ cube of side `n` whose faces are divided into unit quads on the integer grid (so
/// shared corners weld exactly), wound outward; `drop_one` leaves out one quad.
fn fine_cube_obj(n: usize, drop_one: bool) -> String {
    let mut ids: std::collections::HashMap<[usize; 3], usize> = Default::default();
    let (mut vertices, mut faces) = (String::new(), String::new());
    let mut id = |p: [usize; 3]| {
        let next = ids.len() + 1;
        *ids.entry(p).or_insert_with(|| {
            vertices += &format!("v {} {} {}\n", p[0], p[1], p[2]);
            next
        })
    };
    for axis in 0..3 {
        for side in [0, n] {
            for a in 0..n {
                for b in 0..n {
                    if drop_one && axis == 0 && side == n && a == 3 && b == 4 {
                        continue;
                    }
                    let at = |da: usize, db: usize| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = a + da;
                        p[(axis + 2) % 3] = b + db;
                        p
                    };
                    let mut quad = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)].map(&mut id);
                    if side == 0 {
                        quad.reverse();
                    }
                    faces += &format!("f {} {} {} {}\n", quad[0], quad[1], quad[2], quad[3]);
                }
            }
        }
    }
    vertices + &faces
}

#[test]
fn geometric_checks() {
    let dir = Scratch::new("geometry");
    let run = |name: &str, text: String| timed(&Asset::file(dir.write(name, text.as_bytes())));
    let good = run("good.obj", cube_obj(false, 0));
    assert!(good.findings.is_empty(), "{:?}", good.findings);
    assert!((good.scene.as_ref().map_or(0.0, |s| s.size) - 3f64.sqrt()).abs() < 1e-12);
    let inverted = run("inverted.obj", cube_obj(true, 0));
    assert!(codes(&inverted, &[Severity::Warning]).contains("INVERTED_NORMALS"));
    // A cube without one face is an open box, open on purpose: no MESH_HOLES (issue 14).
    let lidless = run("lidless.obj", cube_obj(false, 1));
    assert!(
        !codes(&lidless, &[Severity::Warning]).contains("MESH_HOLES"),
        "{:?}",
        lidless.findings
    );
    // A finely divided cube missing one small quad is meant closed: the hole is reported.
    let holed = run("holed.obj", fine_cube_obj(8, true));
    let hole = holed
        .findings
        .iter()
        .find(|f| f.code.name() == "MESH_HOLES");
    assert!(
        hole.is_some_and(|f| f.message.contains("4 boundary edges")),
        "{:?}",
        holed.findings
    );
    let whole = run("whole.obj", fine_cube_obj(8, false));
    assert!(whole.findings.is_empty(), "{:?}", whole.findings);
    // Scale: a 1.7-unit cube checked as metres against 1..10 passes, against 100..1000 fails.
    let path = dir.write("scale.obj", cube_obj(false, 0).as_bytes());
    let with = |min: f64, max: f64| {
        check_asset(
            &Asset::file(path.clone()),
            &CheckOptions {
                expect_size: Some((min, max)),
                ..CheckOptions::default()
            },
        )
    };
    assert_eq!(with(1.0, 10.0).errors, 0);
    let out_of_range = |report: AssetReport| {
        report
            .findings
            .iter()
            .any(|f| f.code.name() == "SCENE_SIZE_OUT_OF_RANGE")
    };
    assert!(out_of_range(with(100.0, 1000.0)));
    // The unit cube's diagonal is √3 (its f64: 1.7320508075688772). A range ending one ulp
    // below is within the diagonal's rounding bound: no finding; one ending 1e-9 below is.
    let root3 = 3f64.sqrt();
    assert!(!out_of_range(with(1.0, root3.next_down())));
    assert!(!out_of_range(with(root3.next_up(), 10.0)));
    assert!(out_of_range(with(1.0, root3 - 1e-9)));
    // OBJ lines are located.
    let bad = run("bad.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 9\n".into());
    let at: Vec<_> = bad
        .findings
        .iter()
        .map(|f| (f.code.name(), f.location.as_str()))
        .collect();
    assert!(at.contains(&("NON_FINITE_POSITION", "line 3")), "{at:?}");
    assert!(at.contains(&("INDEX_OOB", "line 4")), "{at:?}");
}

#[test]
fn external_files_stay_inside_the_asset() {
    let dir = Scratch::new("confine");
    dir.write("secret.bin", &[0u8; 36]);
    let gltf = |uri: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":36}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,0,0]}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}]}}"#
        )
    };
    let inside = dir.write("a/inside.gltf", gltf("../secret.bin").as_bytes());
    let absolute = dir.write(
        "a/absolute.gltf",
        gltf(&dir.0.join("secret.bin").display().to_string()).as_bytes(),
    );
    let remote = dir.write(
        "a/remote.gltf",
        gltf("https://example.com/x.bin").as_bytes(),
    );
    for path in [&inside, &absolute] {
        let report = check_asset(&Asset::file(path.clone()), &CheckOptions::default());
        assert!(
            report
                .findings
                .iter()
                .any(|f| f.code.name() == "PATH_OUTSIDE_ASSET"),
            "{:?}",
            report.findings
        );
        let allowed = check_asset(
            &Asset::file(path.clone()),
            &CheckOptions {
                allow_outside: true,
                ..CheckOptions::default()
            },
        );
        assert!(
            !allowed
                .findings
                .iter()
                .any(|f| f.code.name() == "PATH_OUTSIDE_ASSET"),
            "{:?}",
            allowed.findings
        );
    }
    // The folder named on the command line is the tree: from there `../secret.bin` is inside.
    let found = discover(std::slice::from_ref(&dir.0)).expect("scratch exists");
    let tree = found.iter().find(|a| a.path == inside).expect("found");
    let report = check_asset(tree, &CheckOptions::default());
    assert!(!report
        .findings
        .iter()
        .any(|f| f.code.name() == "PATH_OUTSIDE_ASSET"));
    let report = check_asset(&Asset::file(remote), &CheckOptions::default());
    assert!(report
        .findings
        .iter()
        .any(|f| f.code.name() == "NON_RELATIVE_URI"));
    // Limits: a buffer larger than --max-memory is refused before it is read.
    let small = check_asset(
        &Asset::file(inside.clone()),
        &CheckOptions {
            max_bytes: 16,
            allow_outside: true,
            ..CheckOptions::default()
        },
    );
    assert!(small
        .findings
        .iter()
        .any(|f| f.code.name() == "ASSET_TOO_LARGE" || f.code.name() == "FILE_TOO_LARGE"));
}

fn raycast(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_raycast"))
        .args(args)
        .output()
        .expect("raycast runs")
}

#[test]
fn command_line() {
    let cube = fixture("gltf/cube.gltf");
    let cycle = fixture("bad/node_cycle.gltf");
    let out = raycast(&["check", cube.to_str().unwrap_or_default()]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = raycast(&[
        "check",
        "--json",
        cube.to_str().unwrap_or_default(),
        cycle.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let lines: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[0]["status"], "ok");
    assert!(lines[1]["findings"]
        .as_array()
        .is_some_and(|f| f.iter().any(|f| f["code"] == "NODE_LOOP"
            && f["location"]
                .as_str()
                .is_some_and(|l| l.starts_with("/nodes/")))));
    let out = raycast(&[
        "check",
        "--github",
        "--quiet",
        cycle.to_str().unwrap_or_default(),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.lines()
            .any(|l| l.starts_with("::error file=") && l.contains("title=NODE_LOOP::")),
        "{text}"
    );
    let out = raycast(&["check", "no/such/file.gltf"]);
    assert_eq!(out.status.code(), Some(2));
    let out = raycast(&[
        "check",
        "--expect-size",
        "5..1",
        cube.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    // JUnit: written atomically, never over an input.
    let dir = Scratch::new("cli");
    let input = dir.write("cube.gltf", &std::fs::read(&cube).expect("fixture"));
    dir.write(
        "cube.bin",
        &std::fs::read(fixture("gltf/cube.bin")).expect("fixture"),
    );
    let before = std::fs::read(&input).expect("input");
    let out = raycast(&[
        "check",
        "--junit",
        input.to_str().unwrap_or_default(),
        input.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        std::fs::read(&input).expect("input"),
        before,
        "the input was overwritten"
    );
    let junit = dir.0.join("report.xml");
    let out = raycast(&[
        "check",
        "--quiet",
        "--junit",
        junit.to_str().unwrap_or_default(),
        dir.0.to_str().unwrap_or_default(),
        cycle.to_str().unwrap_or_default(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let xml = std::fs::read_to_string(&junit).expect("junit written");
    assert_eq!(xml.matches("<testcase ").count(), 2);
    assert_eq!(xml.matches("<failure ").count(), 1);
    let leftovers: Vec<_> = std::fs::read_dir(&dir.0)
        .expect("dir")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".partial-"))
        .collect();
    assert!(leftovers.is_empty());
}

/// `raycast check` over ../shared/assets whole, when it is there: no panic, no hang, exit 1
/// (the folder holds broken files on purpose), one JSON object and one testcase per asset.
#[test]
fn shared_assets() {
    let shared = root().join("../shared/assets");
    if !shared.is_dir() {
        eprintln!("skipped: {} is not here", shared.display());
        return;
    }
    let expected = discover(std::slice::from_ref(&shared))
        .expect("listable")
        .len();
    let dir = Scratch::new("shared");
    let junit = dir.0.join("junit.xml");
    let json = dir.0.join("out.jsonl");
    let started = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_raycast"))
        .args(["check", "--json", "--jobs", "2", "--junit"])
        .arg(&junit)
        .arg(&shared)
        .stdout(std::fs::File::create(&json).expect("json file"))
        .stderr(Stdio::null())
        .spawn()
        .expect("raycast runs");
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if started.elapsed() > Duration::from_secs(600) {
            let _ = child.kill();
            panic!("raycast check over ../shared/assets hung (over 10 minutes)");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(status.code(), Some(1));
    let text = std::fs::read_to_string(&json).expect("json");
    let reports = reports_without_panics(&text, expected);
    let ok = |path: &str| {
        reports
            .iter()
            .find(|r| r["path"].as_str().is_some_and(|p| p.ends_with(path)))
            .map(|r| r["errors"] == 0)
    };
    for good in [
        "gltf/DamagedHelmet.glb",
        "obj/stanford-bunny.obj",
        "gltf/Box.glb",
    ] {
        assert_eq!(ok(good), Some(true), "{good} should have no errors");
    }
    let xml = std::fs::read_to_string(&junit).expect("junit");
    assert_eq!(xml.matches("<testcase ").count(), expected);
    eprintln!(
        "checked {expected} assets of ../shared/assets in {:.1}s",
        started.elapsed().as_secs_f64()
    );
}

#[test]
fn json_output_is_stable() {
    let report = check_asset(
        &Asset::file(fixture("bad/node_cycle.gltf")),
        &CheckOptions::default(),
    );
    let value = serde_json::to_value(&report).expect("serialisable");
    for key in [
        "path", "format", "status", "errors", "warnings", "infos", "seconds", "findings",
    ] {
        assert!(value.get(key).is_some(), "missing {key}");
    }
    let finding = &value["findings"][0];
    for key in ["code", "severity", "location", "message"] {
        assert!(finding.get(key).is_some(), "missing {key}");
    }
    assert!(Path::new(report.path.as_str()).ends_with("node_cycle.gltf"));
}

/// The JSON Lines reports of `raycast check --json`: `expected` of them, none with an
/// INTERNAL_PANIC finding.
fn reports_without_panics(text: &str, expected: usize) -> Vec<Value> {
    let reports: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON per line"))
        .collect();
    assert_eq!(reports.len(), expected);
    for r in &reports {
        let findings = r["findings"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or_default();
        assert!(
            !findings.iter().any(|f| f["code"] == "INTERNAL_PANIC"),
            "{}",
            r["path"]
        );
    }
    reports
}

/// `--golden`: stored buffers match the same asset, and a changed asset under the same name is
/// an error with a difference image; missing golden buffers are an error too.
#[test]
fn golden_comparison() {
    let dir = std::env::temp_dir().join(format!("raycast-golden-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let assets = dir.join("assets");
    let golden = dir.join("golden");
    std::fs::create_dir_all(&assets).unwrap();
    for name in ["cube.gltf", "cube.bin"] {
        std::fs::copy(fixture(&format!("gltf/{name}")), assets.join(name)).unwrap();
    }
    let arg = |p: &Path| p.to_str().unwrap().to_string();
    let run = |extra: &[&str]| {
        let mut args = vec!["check".to_string(), "--golden".into(), arg(&golden)];
        args.extend(extra.iter().map(|s| s.to_string()));
        args.push(arg(&assets));
        raycast(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    assert_eq!(run(&["--update-golden"]).status.code(), Some(0));
    assert!(golden.join("cube.gltf/view0.depth.npy").is_file());
    assert_eq!(
        run(&[]).status.code(),
        Some(0),
        "the same asset matches its golden buffers"
    );
    // The golden depths moved within the bounds of both renders (half the stored bound):
    // rounding could explain that, so it is no finding; moved by four times the bound (twice
    // the sum of both, still far below 1e-6 of the scene's size), it is.
    let view = golden.join("cube.gltf");
    let (_, depth) = raycast::import::npy::read(&view.join("view0.depth.npy")).unwrap();
    let (_, error) = raycast::import::npy::read(&view.join("view0.error.npy")).unwrap();
    assert!(error.iter().any(|&e| e > 0.0) && error.iter().all(|&e| e < 1e-12));
    let moved = |by: f64| {
        let shifted: Vec<f64> = depth.iter().zip(&error).map(|(d, e)| d + by * e).collect();
        let mut out = std::fs::File::create(view.join("view0.depth.npy")).unwrap();
        let data = raycast::output::npy::NpyData::F64(&shifted);
        raycast::output::npy::write(&mut out, &[64, 64], data).unwrap();
    };
    moved(0.5);
    assert_eq!(run(&[]).status.code(), Some(0), "moved within the bounds");
    moved(4.0);
    let out = run(&[]);
    assert_eq!(out.status.code(), Some(1), "moved beyond the bounds");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("GOLDEN_MISMATCH") && text.contains("both bounds"),
        "{text}"
    );
    assert_eq!(run(&["--update-golden"]).status.code(), Some(0));
    // Another scene under the same name: the comparison fails and says where the image is.
    std::fs::copy(fixture("gltf/instances.gltf"), assets.join("cube.gltf")).unwrap();
    let out = run(&[]);
    assert_eq!(out.status.code(), Some(1));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("GOLDEN_MISMATCH"), "{text}");
    assert!(golden.join("cube.gltf/view0.diff.png").is_file());
    std::fs::remove_dir_all(&golden).unwrap();
    let out = run(&[]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("GOLDEN_MISSING"));
    let _ = std::fs::remove_dir_all(&dir);
}
