//! `raycast check` for large libraries: `--shard`, `--merge` and every way shards can fail to
//! fit, `--strict`, `--exclude`, `--root-layers-only`, `--max-findings`, `--validator-json`.
//! (docs/ci.md's workflows and the summary's Markdown are run in tests/python/test_check_ci.py.)

use crate::common;
use common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Copies `from` (a file) to `dir/name`, creating folders.
fn put(dir: &Path, name: &str, from: &str) {
    let to = dir.join(name);
    std::fs::create_dir_all(to.parent().unwrap()).unwrap();
    std::fs::copy(fixture(from), to).unwrap();
}

/// A library of eight assets: clean, warned about and broken glTF and OBJ.
fn library(name: &str) -> PathBuf {
    let dir = temp_dir(name);
    put(&dir, "a/cube.gltf", "gltf/cube.gltf");
    put(&dir, "a/cube.bin", "gltf/cube.bin");
    put(&dir, "a-b/two.obj", "obj/two_objects.obj");
    put(&dir, "b/groups.obj", "obj/groups.obj");
    put(&dir, "b/garbage.obj", "bad/garbage.obj");
    put(&dir, "c/index.gltf", "bad/bad_index.gltf");
    put(&dir, "c/nan.gltf", "bad/nan_position.gltf");
    put(&dir, "d/far.obj", "obj/far_triangle.obj");
    std::fs::write(dir.join("empty.obj"), "v 0 0 0\n").unwrap();
    dir
}

/// JSON lines of a run's stdout.
fn lines(stdout: &[u8]) -> Vec<Value> {
    text(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

/// Records without their timing.
fn untimed(mut records: Vec<Value>) -> Vec<Value> {
    for r in &mut records {
        r.as_object_mut().unwrap().remove("seconds");
    }
    records
}

/// Runs shard K/N of `dir` with `extra` options into `out/shard-K-of-N.jsonl`.
fn shard(dir: &Path, out: &Path, k: usize, n: usize, extra: &[&str]) -> PathBuf {
    std::fs::create_dir_all(out).unwrap();
    let spec = format!("{k}/{n}");
    let mut args = vec!["check", arg(dir), "--shard", &spec, "--json", "-q"];
    args.extend(extra);
    let result = raycast(&args);
    assert!(
        matches!(result.status.code(), Some(0 | 1)),
        "{}",
        text(&result.stderr)
    );
    let file = out.join(format!("shard-{k}-of-{n}.jsonl"));
    std::fs::write(&file, &result.stdout).unwrap();
    file
}

/// Asserts a one-line usage error (exit 2) that contains every one of `needles`.
fn usage_error(result: &std::process::Output, needles: &[&str]) {
    let stderr = text(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "{needle:?} not in {stderr}");
    }
}

#[test]
fn shards_cover_everything_once_and_merge_to_the_unsharded_run() {
    let dir = library("shard-merge");
    let plain = raycast(&["check", arg(&dir), "--json", "-q"]);
    assert_eq!(plain.status.code(), Some(1));
    let full = lines(&plain.stdout);
    assert_eq!(full.len(), 8);
    // Folder by folder: a/ before a-b/ (a plain string sort would put a-b/ first).
    assert_eq!(full[0]["relpath"], "a/cube.gltf");
    assert_eq!(full[1]["relpath"], "a-b/two.obj");
    for n in [1, 2, 4, 12] {
        let out = dir.with_extension(format!("out{n}"));
        let files: Vec<PathBuf> = (1..=n).map(|k| shard(&dir, &out, k, n, &[])).collect();
        let mut seen: Vec<String> = Vec::new();
        for (k, file) in files.iter().enumerate() {
            let records = lines(&std::fs::read(file).unwrap());
            let header = &records[0]["raycast_check_shard"];
            assert_eq!(header["index"], k + 1);
            assert_eq!(header["total"], 8);
            assert_eq!(header["assets"], records.len() - 1);
            seen.extend(records[1..].iter().map(|r| r["path"].to_string()));
        }
        seen.sort();
        let mut all: Vec<String> = full.iter().map(|r| r["path"].to_string()).collect();
        all.sort();
        assert_eq!(seen, all, "{n} shards");
        let mut args = vec!["check", "--merge", "--json", "-q"];
        // In reverse: the merge does not depend on the order the files are named in.
        args.extend(files.iter().rev().map(|f| arg(f)));
        let merged = raycast(&args);
        assert_eq!(merged.status.code(), Some(1), "{}", text(&merged.stderr));
        assert_eq!(untimed(lines(&merged.stdout)), untimed(full.clone()));
    }
    // Validator-format reports from a merge are those of the unsharded run, file for file.
    let (a, b) = (dir.with_extension("va"), dir.with_extension("vb"));
    raycast(&["check", arg(&dir), "-q", "--validator-json", arg(&a)]);
    let out = dir.with_extension("outv");
    let files: Vec<PathBuf> = (1..=3).map(|k| shard(&dir, &out, k, 3, &[])).collect();
    let mut args = vec!["check", "--merge", "-q", "--validator-json", arg(&b)];
    args.extend(files.iter().map(|f| arg(f)));
    raycast(&args);
    let listing = |root: &Path| {
        let found = std::process::Command::new("find")
            .args([arg(root), "-type", "f"])
            .output()
            .unwrap();
        let mut names: Vec<String> = text(&found.stdout)
            .lines()
            .map(|l| l.strip_prefix(arg(root)).unwrap().to_string())
            .collect();
        names.sort();
        names
    };
    assert_eq!(listing(&a).len(), 8);
    assert_eq!(listing(&a), listing(&b));
    for name in listing(&a) {
        let read = |root: &Path| std::fs::read(format!("{}{name}", arg(root))).unwrap();
        assert_eq!(read(&a), read(&b), "{name}");
    }
}

#[test]
fn bad_shard_values_are_one_line_usage_errors() {
    let dir = library("shard-values");
    for bad in ["0/3", "4/3", "3", "a/b", "1/0", "1/2/3", "-1/2"] {
        let result = raycast(&["check", arg(&dir), "--shard", bad]);
        usage_error(&result, &["--shard", bad]);
    }
    let result = raycast(&["check", arg(&dir), "--max-findings", "many"]);
    usage_error(&result, &["--max-findings", "many"]);
}

#[test]
fn shards_that_do_not_fit_are_refused_naming_the_file() {
    let dir = library("merge-errors");
    let out = dir.with_extension("out");
    let s: Vec<PathBuf> = (1..=3).map(|k| shard(&dir, &out, k, 3, &[])).collect();
    let merge = |files: &[&Path]| {
        let mut args = vec!["check", "--merge"];
        args.extend(files.iter().map(|f| arg(f)));
        raycast(&args)
    };
    let (s1, s2, s3) = (s[0].as_path(), s[1].as_path(), s[2].as_path());
    let name = |p: &Path| p.file_name().unwrap().to_str().unwrap().to_string();

    let plain = out.join("plain.jsonl");
    std::fs::write(&plain, raycast(&["check", arg(&dir), "--json"]).stdout).unwrap();
    usage_error(&merge(&[&plain]), &["plain.jsonl", "no shard header"]);

    let cut = out.join("cut.jsonl");
    let body = std::fs::read_to_string(s2).unwrap();
    let kept: Vec<&str> = body.lines().collect();
    std::fs::write(&cut, kept[..kept.len() - 1].join("\n")).unwrap();
    usage_error(&merge(&[s1, &cut, s3]), &["cut.jsonl", "cut short"]);

    let corrupt = out.join("corrupt.jsonl");
    std::fs::write(&corrupt, body.replacen("{\"path\"", "{\"pa", 1)).unwrap();
    usage_error(
        &merge(&[s1, &corrupt, s3]),
        &["corrupt.jsonl", "line 2", "not an asset record"],
    );

    usage_error(&merge(&[s1, s2, s2, s3]), &[&name(s2), "given twice"]);
    usage_error(&merge(&[s1, s3]), &["shard 2/3 missing"]);

    let other_n = shard(&dir, &out, 2, 2, &[]);
    usage_error(
        &merge(&[s1, &other_n, s3]),
        &[&name(&other_n), "does not belong"],
    );

    let strict = out.join("strict.jsonl");
    std::fs::rename(shard(&dir, &out, 2, 3, &["--strict"]), &strict).unwrap();
    usage_error(
        &merge(&[s1, &strict, s3]),
        &["strict.jsonl", "other settings", "strict"],
    );

    // A shard of the same settings but another library (one asset more).
    let grown = library("merge-errors-grown");
    std::fs::write(grown.join("zz.obj"), "v 0 0 0\n").unwrap();
    let foreign = shard(&grown, &grown.with_extension("out"), 2, 3, &[]);
    let result = merge(&[s1, &foreign, s3]);
    assert_eq!(result.status.code(), Some(2), "{}", text(&result.stderr));

    // The merged report may not replace one of the shards it reads.
    let result = raycast(&[
        "check",
        "--merge",
        arg(s1),
        arg(s2),
        arg(s3),
        "--junit",
        arg(s1),
    ]);
    usage_error(&result, &[&name(s1), "refusing to overwrite"]);

    let missing = out.join("nope.jsonl");
    usage_error(&merge(&[&missing]), &["nope.jsonl", "cannot read"]);
}

#[test]
fn strict_makes_warnings_fail_also_after_a_merge() {
    let dir = temp_dir("strict");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("empty.obj"), "v 0 0 0\n").unwrap();
    put(&dir, "two.obj", "obj/two_objects.obj");
    assert_eq!(raycast(&["check", arg(&dir), "-q"]).status.code(), Some(0));
    let junit = dir.with_extension("xml");
    let result = raycast(&["check", arg(&dir), "--strict", "--junit", arg(&junit)]);
    assert_eq!(result.status.code(), Some(1));
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("failures=\"1\""), "{xml}");
    assert!(xml.contains("<failure message=\"EMPTY_SCENE"), "{xml}");
    let out = dir.with_extension("out");
    let files: Vec<PathBuf> = (1..=2)
        .map(|k| shard(&dir, &out, k, 2, &["--strict"]))
        .collect();
    let merged = raycast(&["check", "--merge", arg(&files[0]), arg(&files[1])]);
    assert_eq!(merged.status.code(), Some(1), "{}", text(&merged.stderr));
    let plain: Vec<PathBuf> = (1..=2)
        .map(|k| shard(&dir, &dir.with_extension("p"), k, 2, &[]))
        .collect();
    let merged = raycast(&["check", "--merge", arg(&plain[0]), arg(&plain[1])]);
    assert_eq!(merged.status.code(), Some(0));
    let merged = raycast(&[
        "check",
        "--merge",
        "--strict",
        arg(&plain[0]),
        arg(&plain[1]),
    ]);
    assert_eq!(merged.status.code(), Some(1));
}

/// The relative paths a run reports.
fn relpaths(args: &[&str]) -> Vec<String> {
    let result = raycast(args);
    assert!(
        matches!(result.status.code(), Some(0 | 1)),
        "{}",
        text(&result.stderr)
    );
    lines(&result.stdout)
        .iter()
        .map(|r| r["relpath"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn exclude_matches_names_folders_and_relative_paths() {
    let dir = library("exclude");
    let all = relpaths(&["check", arg(&dir), "--json"]);
    assert_eq!(all.len(), 8);
    let without = |globs: &[&str]| {
        let mut args = vec!["check", arg(&dir), "--json"];
        for g in globs {
            args.extend(["--exclude", g]);
        }
        relpaths(&args)
    };
    let keep = |f: &dyn Fn(&str) -> bool| -> Vec<String> {
        all.iter().filter(|p| f(p)).cloned().collect()
    };
    assert_eq!(without(&["*.obj"]), keep(&|p| !p.ends_with(".obj")));
    assert_eq!(without(&["c"]), keep(&|p| !p.starts_with("c/")));
    assert_eq!(
        without(&["b/*.obj", "a"]),
        keep(&|p| !p.starts_with("b/") && !p.starts_with("a/"))
    );
    // `*` does not cross folders in a pattern with '/'.
    assert_eq!(without(&["*/x/*.obj"]), all);
    usage_error(
        &raycast(&[
            "check",
            arg(&dir),
            "--exclude",
            "*.obj",
            "--exclude",
            "*.gltf",
        ]),
        &["--exclude leaves none of the 8 assets"],
    );
    usage_error(
        &raycast(&["check", arg(&dir), "--exclude", "[a"]),
        &["--exclude '[a'"],
    );
}

/// A kit: a root layer that brings in a component by reference and a layer by sublayer; the
/// component references a material layer (no geometry).
fn usd_kit(dir: &Path) {
    let mesh = "def Mesh \"tri\" {\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n    \
                int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n";
    std::fs::create_dir_all(dir.join("parts/materials")).unwrap();
    std::fs::write(
        dir.join("parts/materials/red.usda"),
        "#usda 1.0\n\ndef Scope \"materials\" {\n    def Material \"red\" {\n    }\n}\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("parts/wheel.usda"),
        format!(
            "#usda 1.0\n\ndef Xform \"wheel\" (\n    prepend references = @./materials/red.usda@</materials>\n) {{\n{mesh}}}\n"
        ),
    )
    .unwrap();
    std::fs::write(dir.join("ground.usda"), format!("#usda 1.0\n\n{mesh}")).unwrap();
    std::fs::write(
        dir.join("car.usda"),
        "#usda 1.0\n(\n    subLayers = [@./ground.usda@]\n)\n\ndef Xform \"car\" (\n    \
         prepend references = @parts/wheel.usda@</wheel>\n) {\n}\n",
    )
    .unwrap();
}

#[test]
fn root_layers_only_checks_the_kit_once() {
    let dir = temp_dir("root-layers");
    usd_kit(&dir);
    let all = raycast(&["check", arg(&dir), "--json"]);
    let records = lines(&all.stdout);
    assert_eq!(records.len(), 4);
    let material = records
        .iter()
        .find(|r| r["relpath"] == "parts/materials/red.usda")
        .unwrap();
    assert_eq!(material["findings"][0]["code"], "EMPTY_SCENE");
    let roots = raycast(&["check", arg(&dir), "--json", "--root-layers-only"]);
    assert_eq!(roots.status.code(), Some(0), "{}", text(&roots.stderr));
    let records = lines(&roots.stdout);
    assert_eq!(records.len(), 1);
    assert_eq!(records[0]["relpath"], "car.usda");
    // The root's scene holds the wheel and the ground: nothing was lost, only not repeated.
    assert_eq!(records[0]["scene"]["triangles"], 2);
    // Shards deal the roots only.
    let out = dir.with_extension("out");
    let s = shard(&dir, &out, 1, 2, &["--root-layers-only"]);
    let header = &lines(&std::fs::read(s).unwrap())[0]["raycast_check_shard"];
    assert_eq!(header["total"], 1);
}

#[test]
fn max_findings_keeps_the_most_severe_and_counts_the_rest() {
    let dir = temp_dir("max-findings");
    std::fs::create_dir_all(&dir).unwrap();
    put(&dir, "bad.gltf", "malformed/invalid-primitive-indices.gltf");
    let all = lines(&raycast(&["check", arg(&dir), "--json"]).stdout).remove(0);
    let total = all["findings"].as_array().unwrap().len();
    assert!(total > 3 && all["errors"].as_u64().unwrap() > 2, "{all}");
    let cut =
        lines(&raycast(&["check", arg(&dir), "--json", "--max-findings", "2"]).stdout).remove(0);
    let kept = cut["findings"].as_array().unwrap();
    assert_eq!(kept.len(), 2);
    assert!(kept.iter().all(|f| f["severity"] == "error"), "{cut}");
    assert_eq!(cut["omitted"], total - 2);
    for count in ["errors", "warnings", "infos", "status"] {
        assert_eq!(cut[count], all[count], "{count}");
    }
    let human = text(&raycast(&["check", arg(&dir), "--max-findings", "2"]).stdout);
    assert!(
        human.contains(&format!("({} more findings not listed", total - 2)),
        "{human}"
    );
}

#[test]
fn validator_json_follows_the_khronos_report_schema() {
    let dir = temp_dir("validator-json");
    // Two with a validator error, one with only warnings.
    let files = [
        "accessor/empty_array.gltf",
        "mesh/accessor_unequal_count.gltf",
        "accessor/custom_property.gltf",
    ];
    for f in files {
        put(&dir, f, &format!("gltf-validator/{f}"));
    }
    put(&dir, "cube.gltf", "gltf/cube.gltf");
    put(&dir, "cube.bin", "gltf/cube.bin");
    let out = dir.with_extension("reports");
    let result = raycast(&["check", arg(&dir), "--validator-json", arg(&out), "-q"]);
    assert!(matches!(result.status.code(), Some(0 | 1)));
    let mut compared = 0;
    for f in files.iter().chain(&["cube.gltf"]) {
        let ours: Value =
            serde_json::from_slice(&std::fs::read(out.join(format!("{f}.report.json"))).unwrap())
                .unwrap();
        assert_eq!(ours["uri"], *f);
        assert_eq!(ours["mimeType"], "model/gltf+json");
        let issues = &ours["issues"];
        for key in [
            "numErrors",
            "numWarnings",
            "numInfos",
            "numHints",
            "truncated",
        ] {
            assert!(!issues[key].is_null(), "{key} missing in {ours}");
        }
        for m in issues["messages"].as_array().unwrap() {
            assert!(m["code"].is_string() && m["message"].is_string(), "{m}");
            assert!(matches!(m["severity"].as_u64(), Some(0..=3)), "{m}");
        }
        // The validator's own report of the same file: the same keys, the same verdict.
        let theirs_path = fixture(&format!("gltf-validator/{f}.report.json"));
        if let Ok(bytes) = std::fs::read(theirs_path) {
            let theirs: Value = serde_json::from_slice(&bytes).unwrap();
            for key in ["uri", "mimeType", "validatorVersion", "issues"] {
                assert!(!theirs[key].is_null() && !ours[key].is_null(), "{key}");
            }
            let keys = |v: &Value| {
                let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
                k.sort();
                k
            };
            assert_eq!(keys(&ours["issues"]), keys(&theirs["issues"]));
            let errs = |v: &Value| v["issues"]["numErrors"].as_u64().unwrap() > 0;
            assert_eq!(errs(&ours), errs(&theirs), "{f}");
            compared += 1;
        }
    }
    assert_eq!(compared, 3);
    // Written atomically: no temporary files are left.
    let leftovers = std::process::Command::new("find")
        .args([arg(&out), "-name", ".*partial*"])
        .output()
        .unwrap();
    assert!(leftovers.stdout.is_empty(), "{}", text(&leftovers.stdout));
    let file = dir.join("cube.bin");
    usage_error(
        &raycast(&["check", arg(&dir), "--validator-json", arg(&file)]),
        &["cube.bin", "needs a folder"],
    );
}
