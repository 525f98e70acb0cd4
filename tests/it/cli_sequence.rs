//! `--time START:STOP:STEP`: one folder per time, each what a single run at that time writes
//! (compared file by file with single runs: two code paths, the file opened once or at each
//! run); bad ranges are usage errors in one line; the output folders follow the ownership and
//! interrupt rules of single runs.

use crate::common;
use common::{arg, file_names, fixture, raycast, raycast_ok, temp_dir};
use std::path::Path;

/// A sidecar without its timings (the only part that differs from run to run).
fn sidecar_without_timings(dir: &Path) -> serde_json::Value {
    let text = std::fs::read(dir.join("raycast.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&text).unwrap();
    json.as_object_mut().unwrap().remove("timings");
    json
}

/// The render options the comparisons use.
const RENDER: [&str; 6] = [
    "--aov",
    "depth,normal,id,prim,bary",
    "--width",
    "48",
    "--format",
    "exr,png,npy",
];

/// A skinned, animated sample (CesiumMan) and an animated node hierarchy (BoxAnimated) over
/// 0:1:0.1 (0.3 is 0.30000000000000004 when accumulated or multiplied): eleven folders, named
/// in time order, each equal to `raycast --time T` in every file but the timings.
#[test]
fn a_sequence_equals_single_runs_at_each_time() {
    for sample in ["posed/CesiumMan.glb", "posed/BoxAnimated.glb"] {
        let scene = fixture(sample);
        let dir = temp_dir(&format!("sequence-{}", sample.replace('/', "-")));
        let seq = dir.join("seq");
        let mut args = vec![arg(&scene), "--time", "0:1:0.1", "--out", arg(&seq), "-q"];
        args.extend(RENDER);
        raycast_ok(&args);
        let expected: Vec<String> = (0..=10)
            .map(|i| format!("{i:04}-t{}.{}", i / 10, i % 10))
            .collect();
        assert_eq!(file_names(&seq), expected, "{sample}");
        for (i, folder) in expected.iter().enumerate() {
            let time = format!("{}.{}", i / 10, i % 10);
            let single = dir.join(format!("single-{time}"));
            let mut args = vec![arg(&scene), "--time", &time, "--out", arg(&single), "-q"];
            args.extend(RENDER);
            raycast_ok(&args);
            let got = seq.join(folder);
            assert_eq!(file_names(&got), file_names(&single), "{sample} {folder}");
            for name in file_names(&single) {
                if name == "raycast.json" {
                    continue;
                }
                let same = std::fs::read(got.join(&name)).unwrap()
                    == std::fs::read(single.join(&name)).unwrap();
                assert!(same, "{sample} {folder}/{name} differs from --time {time}");
            }
            let json = sidecar_without_timings(&got);
            assert_eq!(json, sidecar_without_timings(&single), "{sample} {folder}");
            assert_eq!(json["pose"]["time"], time.parse::<f64>().unwrap());
        }
        // The poses differ: a sequence of one pose would pass the comparisons above.
        let first = std::fs::read(seq.join(&expected[0]).join("depth.npy")).unwrap();
        let last = std::fs::read(seq.join(&expected[10]).join("depth.npy")).unwrap();
        assert_ne!(first, last, "{sample}");
    }
}

/// Ranges raycast does not render are usage errors, in one line that says what is wrong.
#[test]
fn bad_ranges_are_usage_errors_in_one_line() {
    let scene = fixture("posed/BoxAnimated.glb");
    let out = temp_dir("sequence-bad");
    for (range, said) in [
        ("0:1:0", "STEP must be positive"),
        ("0:1:-0.5", "STEP must be positive"),
        ("1:0:0.1", "STOP is before START"),
        ("0:100:0.001", "more than 10000 times"),
        ("0:one:0.1", "'one' is not a finite number"),
        ("0:1", "expected START:STOP:STEP"),
        ("0:nan:1", "'nan' is not a finite number"),
    ] {
        let result = raycast(&[arg(&scene), "--time", range, "--out", arg(&out)]);
        let text = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{range}: {text}");
        assert!(text.contains(said), "{range}: {text}");
        assert_eq!(text.lines().count(), 1, "{range}: {text}");
        assert!(!out.exists(), "{range}");
    }
    let result = raycast(&["info", arg(&scene), "--time", "0:1:0.5"]);
    assert_eq!(result.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&result.stderr).lines().count(), 1);
}

/// Each folder of a sequence is owned as a single run's folder is: a file no run of the scene
/// wrote refuses the whole sequence before anything is written, and a second sequence removes
/// the files its scene's first one listed and it does not write again.
#[test]
fn sequence_folders_follow_the_ownership_rules() {
    let scene = fixture("posed/BoxAnimated.glb");
    let out = temp_dir("sequence-ownership");
    let theirs = out.join("0002-t1.0");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("depth.exr"), b"someone's").unwrap();
    let result = raycast(&[
        arg(&scene),
        "--time",
        "0:2:0.5",
        "--width",
        "8",
        "--out",
        arg(&out),
    ]);
    let text = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{text}");
    assert!(
        text.contains("which no earlier run of this scene wrote"),
        "{text}"
    );
    assert_eq!(file_names(&out), ["0002-t1.0"]);
    assert_eq!(
        std::fs::read(theirs.join("depth.exr")).unwrap(),
        b"someone's"
    );

    std::fs::remove_dir_all(&out).unwrap();
    let run = |aov: &str| {
        raycast_ok(&[
            arg(&scene),
            "--time",
            "0:1:0.5",
            "--width",
            "8",
            "--aov",
            aov,
            "--out",
            arg(&out),
            "-q",
        ])
    };
    run("depth,normal");
    assert!(file_names(&out.join("0001-t0.5")).contains(&"normal.exr".to_string()));
    run("depth");
    for folder in ["0000-t0.0", "0001-t0.5", "0002-t1.0"] {
        let names = file_names(&out.join(folder));
        assert_eq!(
            names,
            ["depth.exr", "depth.png", "raycast.json"],
            "{folder}"
        );
    }
}

/// An interrupted sequence keeps the folders it finished and removes the unfinished one's
/// temporary files and the folder itself.
#[test]
fn an_interrupted_sequence_keeps_finished_times_only() {
    let scene = fixture("posed/CesiumMan.glb");
    let out = temp_dir("sequence-interrupt");
    let mut child = std::process::Command::new(common::raycast_bin())
        .args([
            arg(&scene),
            "--time",
            "0:2:1",
            "--width",
            "1500",
            "--height",
            "1500",
        ])
        .args(["--aov", "depth,normal,position", "--format", "exr,png,npy"])
        .args(["--out", arg(&out), "--quiet"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let second = out.join("0001-t1");
    let started = std::time::Instant::now();
    let mut sent = false;
    while child.try_wait().unwrap().is_none() && started.elapsed().as_secs() < 120 {
        if second.exists() {
            let status = std::process::Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
            sent = status.unwrap().success();
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let output = child.wait_with_output().unwrap();
    assert!(sent, "the sequence ended first: {:?}", output.status);
    assert_eq!(output.status.code(), Some(143));
    assert_eq!(file_names(&out), ["0000-t0"]);
    let finished = file_names(&out.join("0000-t0"));
    assert!(
        finished.contains(&"raycast.json".to_string()),
        "{finished:?}"
    );
    assert!(
        !finished.iter().any(|n| n.contains(".partial-")),
        "{finished:?}"
    );
}
