//! `raycast check` as a new user runs it: paths without assets, empty files, machine output,
//! and USD layers a ray caster does not need.

use crate::common;
use common::*;

/// The text of an output stream.
fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn a_folder_without_assets_or_a_mistyped_path_exits_2() {
    let empty = temp_dir("no-assets");
    std::fs::create_dir_all(&empty).unwrap();
    std::fs::write(empty.join("notes.txt"), "no assets here").unwrap();
    let result = raycast(&["check", arg(&empty)]);
    assert_eq!(result.status.code(), Some(2), "{}", text(&result.stderr));
    assert!(
        text(&result.stderr).contains("no assets in this folder"),
        "{}",
        text(&result.stderr)
    );
    let typo = empty.join("scene.gltf");
    let result = raycast(&["check", arg(&typo)]);
    assert_eq!(result.status.code(), Some(2), "{}", text(&result.stderr));
}

#[test]
fn an_empty_obj_is_an_empty_scene_and_counts_read_well() {
    let dir = temp_dir("empty-obj");
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("empty.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\n").unwrap();
    let result = raycast(&["check", arg(&obj)]);
    let (stdout, stderr) = (text(&result.stdout), text(&result.stderr));
    assert!(stdout.contains("EMPTY_SCENE"), "{stdout}");
    assert!(stdout.contains("(0 errors, 1 warning)"), "{stdout}");
    assert!(stderr.contains("checked 1 asset in"), "{stderr}");
}

#[test]
fn json_with_github_keeps_stdout_pure_json_lines() {
    let dir = temp_dir("json-github");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("empty.obj"), "").unwrap();
    std::fs::copy(fixture("gltf/cube.gltf"), dir.join("cube.gltf")).unwrap();
    std::fs::copy(fixture("gltf/cube.bin"), dir.join("cube.bin")).unwrap();
    let result = raycast(&["check", "--json", "--github", arg(&dir)]);
    let stdout = text(&result.stdout);
    for line in stdout.lines() {
        assert!(
            serde_json::from_str::<serde_json::Value>(line).is_ok(),
            "not JSON: {line}"
        );
    }
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    assert!(
        text(&result.stderr).contains("::warning file="),
        "{}",
        text(&result.stderr)
    );
}

/// A stage whose prims reference MaterialX material layers, which the USD reader cannot read.
fn stage_with_materialx(dir: &std::path::Path) -> std::path::PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let mtlx = "<?xml version=\"1.0\"?>\n<materialx version=\"1.38\"></materialx>\n";
    std::fs::write(dir.join("a.mtlx"), mtlx).unwrap();
    std::fs::write(dir.join("b.mtlx"), mtlx).unwrap();
    let mut stage = String::from("#usda 1.0\n\ndef Xform \"World\" {\n");
    for (name, layer) in [("A", "a"), ("B", "b"), ("C", "a")] {
        stage.push_str(&format!(
            "    def Mesh \"{name}\" {{\n        \
             point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n        \
             int[] faceVertexCounts = [3]\n        int[] faceVertexIndices = [0, 1, 2]\n    }}\n    \
             def Scope \"{name}Materials\" (\n        references = @./{layer}.mtlx@\n    ) {{\n    }}\n"
        ));
    }
    stage.push_str("}\n");
    let path = dir.join("stage.usda");
    std::fs::write(&path, stage).unwrap();
    path
}

#[test]
fn materialx_layers_make_at_most_one_note() {
    let dir = temp_dir("materialx");
    let stage = stage_with_materialx(&dir);
    let result = raycast(&["check", "--json", "--verbose", arg(&stage)]);
    let report: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    let findings = report["findings"].as_array().unwrap();
    let layers: Vec<_> = findings
        .iter()
        .filter(|f| f["message"].as_str().unwrap_or("").contains(".mtlx"))
        .collect();
    assert_eq!(layers.len(), 1, "{findings:?}");
    assert_eq!(layers[0]["severity"], "info");
    let out = dir.join("out");
    raycast_ok(&[arg(&stage), "--width", "8", "--out", arg(&out), "--quiet"]);
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    let warnings: Vec<String> = sidecar["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect();
    let mtlx: Vec<&String> = warnings.iter().filter(|w| w.contains(".mtlx")).collect();
    assert_eq!(mtlx.len(), 1, "{warnings:?}");
    // Material layers are not malformed: say what they are, in our words, not the reader's.
    assert!(
        mtlx[0].contains(
            "3 references to layers of a format raycast does not read (MaterialX .mtlx) skipped"
        ) && mtlx[0].contains("a.mtlx@ at /"),
        "{mtlx:?}"
    );
    assert!(!mtlx[0].contains("malformed"), "{mtlx:?}");
    assert_eq!(layers[0]["code"], "USD_UNSUPPORTED_LAYER");
    let mut sorted = warnings.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(warnings, sorted, "warnings are sorted, without repeats");
}

/// A report path that cannot be written is refused before any asset is checked (it failed
/// after the whole check, 8.8 s on a large folder), for `--junit`, `--summary` and
/// `--validator-json` alike; nothing is created.
#[test]
fn unwritable_report_paths_are_refused_before_checking() {
    let dir = temp_dir("unwritable-report");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let assets = fixture("gltf");
    let report = file.join("reports/x.xml");
    for flag in ["--junit", "--summary", "--validator-json"] {
        let result = raycast(&["check", arg(&assets), flag, arg(&report)]);
        let (stdout, stderr) = (text(&result.stdout), text(&result.stderr));
        assert_eq!(result.status.code(), Some(2), "{flag}: {stderr}");
        assert!(stdout.is_empty(), "{flag}: checked first: {stdout}");
        assert!(!stderr.contains("checked"), "{flag}: {stderr}");
        assert!(
            stderr.contains("x.xml: cannot be written"),
            "{flag}: {stderr}"
        );
        assert!(
            stderr.contains("a-file is not a folder"),
            "{flag}: {stderr}"
        );
    }
    assert_eq!(file_names(&dir), ["a-file"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--golden --time T` renders the views at that pose: goldens stored at one time match a
/// check at the same time and not one at another time, for an animated glTF (every animation
/// played) and a UsdSkel stage (through the isolated USD child process).
#[test]
fn golden_views_are_rendered_at_the_time_given() {
    let dir = temp_dir("cli_check_golden_time");
    let assets = dir.join("assets");
    std::fs::create_dir_all(&assets).unwrap();
    std::fs::copy(fixture("posed/BoxAnimated.glb"), assets.join("box.glb")).unwrap();
    std::fs::copy(fixture("usd/posed/skel.usda"), assets.join("skel.usda")).unwrap();
    let golden = dir.join("golden");
    let run = |extra: &[&str]| {
        let mut args = vec!["check", "--no-geometry", "--golden", arg(&golden)];
        args.extend(extra);
        args.push(arg(&assets));
        raycast(&args)
    };
    let stored = run(&["--update-golden", "--time", "0.5"]);
    assert_eq!(
        stored.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&stored.stdout)
    );
    let same = run(&["--time", "0.5"]);
    assert_eq!(
        same.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&same.stdout)
    );
    let other = run(&["--time", "3", "--json"]);
    assert_eq!(other.status.code(), Some(1));
    let text = String::from_utf8_lossy(&other.stdout);
    for asset in ["box.glb", "skel.usda"] {
        let mismatch = text
            .lines()
            .any(|l| l.contains(asset) && l.contains("GOLDEN_MISMATCH"));
        assert!(mismatch, "{asset}: {text}");
    }
    let needs_golden = raycast(&["check", "--time", "1", arg(&assets)]);
    assert_eq!(
        needs_golden.status.code(),
        Some(2),
        "--time without --golden is a usage error"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
