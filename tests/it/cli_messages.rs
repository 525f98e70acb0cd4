//! Messages a new user meets: wrong kinds of input named for what they are, help text, `info`.

use crate::common;
use common::*;

/// A stderr as text.
fn stderr(output: &std::process::Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn a_folder_given_as_the_scene_says_it_is_a_folder() {
    let folder = fixture("gltf");
    for args in [vec![arg(&folder)], vec!["info", arg(&folder)]] {
        let result = raycast(&args);
        assert_eq!(result.status.code(), Some(1), "{args:?}");
        assert!(
            stderr(&result).contains("gltf: is a folder"),
            "{}",
            stderr(&result)
        );
    }
}

#[test]
fn a_glb_named_obj_is_named_for_what_it_is() {
    let dir = temp_dir("glb-as-obj");
    std::fs::create_dir_all(&dir).unwrap();
    let disguised = dir.join("model.obj");
    std::fs::copy(fixture("gltf/cube.glb"), &disguised).unwrap();
    let result = raycast(&["info", arg(&disguised)]);
    assert_eq!(result.status.code(), Some(1));
    let said = "the content is a binary glTF (GLB), not what the .obj name says";
    assert!(
        stderr(&result).contains(&format!("model.obj: {said}")),
        "{}",
        stderr(&result)
    );
    // `check` says the same words (it said "OBJ_NOT_TEXT ... not UTF-8")
    let checked = raycast(&["check", arg(&disguised)]);
    let stdout = String::from_utf8_lossy(&checked.stdout);
    assert_eq!(checked.status.code(), Some(1));
    assert!(
        stdout.contains(&format!("FILE_TYPE_MISMATCH: {said}")),
        "{stdout}"
    );
}

/// Runs `raycast ARGS` under a 1.5 GB address-space limit (`ulimit -v`), so that a run that
/// reads a 2 GiB file whole fails instead of answering.
#[cfg(target_os = "linux")]
fn raycast_in_1_5_gb(args: &[&str]) -> std::process::Output {
    let mut script = format!("ulimit -v 1500000; exec '{}'", raycast_bin().display());
    for a in args {
        script.push_str(&format!(" '{a}'"));
    }
    std::process::Command::new("sh")
        .args(["-c", &script])
        .output()
        .unwrap()
}

/// A 2 GiB file whose first bytes already say it is no glTF is refused from those bytes,
/// by render, `info` and `check` alike, without reading it (it used to be read whole first:
/// 4.5-15 s and 2.1 GB for a 2 GB file).
#[cfg(target_os = "linux")]
#[test]
fn a_huge_file_is_refused_from_its_first_bytes() {
    let dir = temp_dir("huge");
    std::fs::create_dir_all(&dir).unwrap();
    let sparse = |name: &str, head: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, head).unwrap();
        let file = std::fs::OpenOptions::new().write(true).open(&path).unwrap();
        file.set_len(2 << 30).unwrap();
        path
    };
    let cases = [
        (
            sparse("zeros.glb", b""),
            "the file does not start with 'glTF'",
        ),
        (
            sparse("short.glb", b"glTF\x02\0\0\0\0\0\0\0"),
            "the GLB header declares 0 bytes: no room for a chunk",
        ),
        (
            sparse("zeros.gltf", b""),
            "not valid glTF JSON: expected value at line 1 column 1",
        ),
    ];
    for (path, message) in &cases {
        for args in [vec![arg(path)], vec!["info", arg(path)]] {
            let result = raycast_in_1_5_gb(&args);
            assert_eq!(
                result.status.code(),
                Some(1),
                "{args:?}: {}",
                stderr(&result)
            );
            assert!(stderr(&result).contains(message), "{}", stderr(&result));
        }
    }
    let checked = raycast_in_1_5_gb(&["check", arg(&dir)]);
    let stdout = String::from_utf8_lossy(&checked.stdout);
    assert_eq!(
        checked.status.code(),
        Some(1),
        "{stdout}{}",
        stderr(&checked)
    );
    for (_, message) in &cases {
        assert!(stdout.contains(message), "{stdout}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn help_mentions_usd() {
    for args in [vec!["--help"], vec!["info", "--help"]] {
        let result = raycast(&args);
        let text = String::from_utf8_lossy(&result.stdout);
        assert!(
            text.contains("USD") || text.contains(".usda"),
            "{args:?}: {text}"
        );
    }
}

#[test]
fn info_takes_several_files() {
    let cube = fixture("gltf/cube.gltf");
    let plane = fixture("obj/groups.obj");
    let result = raycast_ok(&["info", arg(&cube), arg(&plane)]);
    let text = String::from_utf8_lossy(&result.stdout);
    assert!(
        text.contains("cube.gltf") && text.contains("groups.obj"),
        "{text}"
    );
    let result = raycast_ok(&["info", "--json", arg(&cube), arg(&plane)]);
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(json.as_array().map(Vec::len), Some(2));
    let missing = fixture("gltf/no-such-file.gltf");
    let result = raycast(&["info", arg(&cube), arg(&missing)]);
    assert_eq!(result.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&result.stdout).contains("cube.gltf"));
    assert!(
        stderr(&result).contains("no-such-file.gltf"),
        "{}",
        stderr(&result)
    );
}

#[test]
fn info_columns_stay_aligned_for_long_names() {
    let dir = temp_dir("long-names");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("long.usda");
    let mesh = |name: &str| {
        format!(
            "    def Mesh \"{name}\" {{\n        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n        \
             int[] faceVertexCounts = [3]\n        int[] faceVertexIndices = [0, 1, 2]\n    }}\n"
        )
    };
    let text = format!(
        "#usda 1.0\n\ndef Xform \"World\" {{\n{}{}}}\n",
        mesh("a_prim_name_much_longer_than_thirty_two_characters"),
        mesh("b")
    );
    std::fs::write(&scene, text).unwrap();
    let result = raycast_ok(&["info", arg(&scene)]);
    let out = String::from_utf8_lossy(&result.stdout);
    let columns: Vec<usize> = out
        .lines()
        .filter(|l| l.trim_start().starts_with("object"))
        .map(|l| l.find(" 1 triangle").unwrap())
        .collect();
    assert_eq!(columns.len(), 2, "{out}");
    assert_eq!(columns[0], columns[1], "{out}");
    assert!(out.contains("2 objects, 2 triangles, 0 quadrics"), "{out}");
}

#[test]
fn usd_reader_crashes_and_hangs_end_with_one_line() {
    let out = temp_dir("fuzz-usd");
    let files = [
        "fuzz-hang/usd/openusd_instancing_recursion_1.usda",
        "fuzz-hang/usd/openusd_instancing_recursion_2.usda",
        "fuzz/usd/deep_nesting.usda",
        "fuzz/usd/openusd_usdc_token_index.usdc",
        "fuzz/usd/openusd_usdc_lz4_count_1.usdc",
        "fuzz/usd/openusd_usdc_lz4_count_2.usdc",
        "fuzz/usd/openusd_usdc_lz4_count_3.usdc",
        "fuzz/usd/openusd_usdc_lz4_count_4.usdc",
        "fuzz/usd/openusd_usdc_lz4_count_5.usdc",
        "fuzz/usd/openusd_usdc_section_size.usdc",
        // tobj's unchecked texture coordinate index (an overflow panic with debug assertions;
        // in a release build, the out-of-bounds error).
        "fuzz/obj/tobj_texcoord_index_overflow.obj",
    ];
    for file in files {
        let scene = fixture(file);
        for args in [
            vec![arg(&scene), "--usd-timeout", "3", "--out", arg(&out)],
            vec!["info", arg(&scene), "--usd-timeout", "3"],
        ] {
            let result = raycast(&args);
            let stderr = stderr(&result);
            assert_eq!(result.status.code(), Some(1), "{args:?}: {stderr}");
            assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
            assert!(stderr.contains(file), "{args:?}: {stderr}");
            assert!(!stderr.contains("panicked at"), "{args:?}: {stderr}");
            if file.contains("lz4_count") || file.contains("section_size") {
                // Aborted the reader (an allocation the file's count asked for); now refused.
                assert!(!stderr.contains("crashed"), "{args:?}: {stderr}");
            }
        }
    }
    assert!(!out.exists());
}

/// Common slips get words for what was meant (clap called each "the subcommand '…' cannot be
/// used with '<SCENE>'"), one line, exit 2.
#[test]
fn common_slips_say_what_was_meant() {
    let cube = fixture("gltf/cube.gltf");
    let cases: [(Vec<&str>, &str); 5] = [
        (
            vec!["a.glb", "b.obj"],
            "one scene per render: got 'a.glb' and 'b.obj'",
        ),
        (
            vec!["--width", "8", arg(&cube), "extra"],
            "one scene per render: got",
        ),
        (vec!["chek", "dir"], "did you mean 'raycast check dir'?"),
        (vec!["ifno", "x.glb"], "did you mean 'raycast info x.glb'?"),
        (vec![arg(&cube), "info"], "'info' goes first: raycast info"),
    ];
    for (args, said) in cases {
        let result = raycast(&args);
        assert_eq!(result.status.code(), Some(2), "{args:?}");
        let text = stderr(&result);
        assert!(text.contains(said), "{args:?}: {text}");
        assert_eq!(text.lines().count(), 1, "{text}");
    }
}

/// Invalid camera values exit 2 as the README says of invalid values, each named for what is
/// wrong (`--up 0,0,0` was called "parallel"); `--out -` and a scene from standard input are
/// refused in plain words.
#[test]
fn invalid_cameras_and_standard_streams_are_usage_errors() {
    let cube = fixture("gltf/cube.gltf");
    let out = temp_dir("camera-slips");
    let look = |extra: &[&str]| {
        let mut args = vec![arg(&cube), "--width", "8", "--out", arg(&out)];
        args.extend(extra);
        raycast(&args)
    };
    for (extra, said) in [
        (
            vec!["--eye", "1,1,1", "--target", "1,1,1"],
            "eye and target are the same point",
        ),
        (
            vec!["--eye", "1,1,1", "--target", "0,0,0", "--up", "0,0,0"],
            "up vector is zero",
        ),
        (
            vec!["--eye", "0,1,0", "--target", "0,0,0"],
            "up vector is parallel to the view direction",
        ),
    ] {
        let result = look(&extra);
        assert_eq!(result.status.code(), Some(2), "{extra:?}");
        assert!(stderr(&result).contains(said), "{}", stderr(&result));
        assert!(!out.exists());
    }
    let dash = raycast(&[arg(&cube), "--out", "-"]);
    assert_eq!(dash.status.code(), Some(2));
    assert!(stderr(&dash).contains("not standard output; name a folder"));
    assert!(!std::path::Path::new("-").exists());
    let stdin = raycast(&["-"]);
    assert!(
        stderr(&stdin).contains("standard input is not read"),
        "{}",
        stderr(&stdin)
    );
    let piped = std::process::Command::new(raycast_bin())
        .arg("/dev/stdin")
        .stdin(std::process::Stdio::piped())
        .output()
        .unwrap();
    assert!(
        stderr(&piped).contains("is not a regular file"),
        "{}",
        stderr(&piped)
    );
}

/// `--threads` and `check --jobs` follow one rule: 0 is refused, more than the cores is
/// brought down to the cores with a warning.
#[test]
fn threads_and_jobs_follow_one_rule() {
    let cube = fixture("gltf/cube.gltf");
    let out = temp_dir("threads");
    let cores = std::thread::available_parallelism().unwrap().get();
    let many = (cores + 1).to_string();
    for (args, flag) in [
        (
            vec![arg(&cube), "--width", "8", "--out", arg(&out), "--threads"],
            "--threads",
        ),
        (vec!["check", arg(&cube), "--jobs"], "--jobs"),
    ] {
        let mut zero = args.clone();
        zero.push("0");
        assert_eq!(raycast(&zero).status.code(), Some(2), "{flag} 0");
        let mut more = args.clone();
        more.push(&many);
        let result = raycast(&more);
        assert!(result.status.success(), "{}", stderr(&result));
        let said = format!("{flag} {many} is more than the {cores} cores; using {cores}");
        assert!(stderr(&result).contains(&said), "{}", stderr(&result));
    }
}

/// `info --json` on several files gives one record per file, a failed file's with its error,
/// so that results match inputs (it gave only the files that were read).
#[test]
fn info_json_has_a_record_for_each_file() {
    let good = fixture("gltf/cube.gltf");
    let bad = fixture("bad/bad_index.gltf");
    let result = raycast(&["info", "--json", arg(&good), arg(&bad), arg(&good)]);
    assert_eq!(result.status.code(), Some(1));
    let records: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    let records = records.as_array().unwrap();
    assert_eq!(records.len(), 3);
    assert_eq!(records[0]["triangles"], 12);
    assert_eq!(records[1]["scene"], arg(&bad));
    assert!(records[1]["error"]
        .as_str()
        .unwrap()
        .contains("index 99 out of range"));
    assert!(records[1].get("triangles").is_none());
    assert_eq!(records[2]["triangles"], 12);
}

/// A scene of many objects lists the first ones and counts the rest (501 lines for a scene
/// of 500 cubes); `--all` and `--json` list every one.
#[test]
fn info_summarises_many_objects_unless_asked_for_all() {
    let mut text = String::new();
    for i in 0..100 {
        text += &format!("o part{i}\nv {i} 0 0\nv {i}.5 0 0\nv {i} 1 0\nf -3 -2 -1\n");
    }
    let obj = temp_file("many-objects", "parts.obj", text);
    let listed = |args: &[&str]| {
        let out = raycast_ok(args).stdout;
        let text = String::from_utf8_lossy(&out).into_owned();
        text.lines().filter(|l| l.contains("  object ")).count()
    };
    assert_eq!(listed(&["info", arg(&obj)]), 20);
    let summary = raycast_ok(&["info", arg(&obj)]).stdout;
    assert!(String::from_utf8_lossy(&summary).contains("... 80 more objects (--all"));
    assert_eq!(listed(&["info", "--all", arg(&obj)]), 100);
    let json: serde_json::Value =
        serde_json::from_slice(&raycast_ok(&["info", "--json", arg(&obj)]).stdout).unwrap();
    assert_eq!(json["objects"].as_array().unwrap().len(), 100);
}

/// The fuzzer's two "hang" layers (issue 27, item 13) are refused at once, by what is wrong
/// with them, in render, `info` and `check`: one line naming the file, exit 1, and for
/// `check` a `USD_INVALID_PATH` finding. They ran until the child process's timeout (openusd
/// walked the ancestors of a path whose last component ended in an unmatched `}`, and that
/// path was its own parent). The generous `--usd-timeout 20` lets a regression fail on the
/// timeout's different message instead of stalling for the default two minutes.
#[test]
fn hostile_usd_is_refused_by_what_is_wrong() {
    let out = temp_dir("hostile-usd");
    let cases = [
        (
            "fuzz-hang/usd/openusd_instancing_recursion_1.usda",
            "ill-formed path <",
        ),
        (
            "fuzz-hang/usd/openusd_instancing_recursion_2.usda",
            "is not an attribute name",
        ),
    ];
    for (file, said) in cases {
        let scene = fixture(file);
        for args in [
            vec![arg(&scene), "--usd-timeout", "20", "--out", arg(&out)],
            vec!["info", arg(&scene), "--usd-timeout", "20"],
        ] {
            let result = raycast(&args);
            let text = stderr(&result);
            assert_eq!(result.status.code(), Some(1), "{args:?}: {text}");
            assert_eq!(text.lines().count(), 1, "{args:?}: {text}");
            assert!(text.contains(file), "{args:?}: {text}");
            assert!(text.contains(said), "{args:?}: {text}");
        }
        let result = raycast(&["check", "--json", "--quiet", "--timeout", "20", arg(&scene)]);
        assert_eq!(result.status.code(), Some(1), "{}", stderr(&result));
        let report: serde_json::Value =
            serde_json::from_slice(&result.stdout).expect("one JSON report");
        let findings = report["findings"].as_array().expect("findings");
        assert!(
            findings.iter().any(|f| f["code"] == "USD_INVALID_PATH"
                && f["message"].as_str().is_some_and(|m| m.contains(said))),
            "{findings:?}"
        );
    }
    assert!(!out.exists());
}

/// USD sublayers, references and payloads follow the path rule of glTF buffers in render and
/// `info`: one leading out of the scene's folder is refused in one line naming its asset path
/// (exit 1); `--allow-outside` lifts the rule and `--root` widens the tree.
#[test]
fn usd_layers_stay_inside_the_root() {
    let out = temp_dir("usd-confine");
    for file in ["outside_reference.usda", "outside_sublayer.usda"] {
        let scene = fixture(&format!("usd/confine/{file}"));
        let render = |extra: &[&str]| {
            let mut args = vec![arg(&scene), "--out", arg(&out), "--quiet"];
            args.extend_from_slice(extra);
            raycast(&args)
        };
        let info = |extra: &[&str]| {
            let mut args = vec!["info", arg(&scene)];
            args.extend_from_slice(extra);
            raycast(&args)
        };
        for result in [render(&[]), info(&[])] {
            let text = stderr(&result);
            assert_eq!(result.status.code(), Some(1), "{file}: {text}");
            assert_eq!(text.lines().count(), 1, "{file}: {text}");
            assert!(text.contains(file), "{file}: {text}");
            assert!(text.contains("gltf_cube.usda"), "{file}: {text}");
            assert!(text.contains("leads out of the folder"), "{file}: {text}");
        }
        assert!(!out.exists());
        let root = fixture("usd");
        for extra in [vec!["--allow-outside"], vec!["--root", arg(&root)]] {
            let result = info(&extra);
            assert_eq!(
                result.status.code(),
                Some(0),
                "{file} {extra:?}: {}",
                stderr(&result)
            );
            let text = String::from_utf8_lossy(&result.stdout);
            assert!(text.contains("12 triangles"), "{file} {extra:?}: {text}");
            let result = render(&extra);
            assert_eq!(
                result.status.code(),
                Some(0),
                "{file} {extra:?}: {}",
                stderr(&result)
            );
            std::fs::remove_dir_all(&out).expect("the render wrote its folder");
        }
    }
}

/// `info` gives the scene's own bounds, not the octree's conservative box: the "scaled"
/// cylinder of fixtures/quadrics/cylinder.gltf (x² + y² = 1 clipped to [-1, 1]³, scaled by
/// (0.5, 1.5, 2), moved by -16 in x) spans exactly [-16.5, -1.5, -2] .. [-15.5, 1.5, 2], and
/// the unit sphere at x = 6.4e6 exactly [6399999, -1, -1] .. [6400001, 1, 1]. (They used to
/// read -16.5000000000165 and -2.000000004002: the clip box's rounding tolerance and padding.)
#[test]
fn info_prints_the_scenes_own_bounds() {
    let cylinder = fixture("quadrics/cylinder.gltf");
    let result = raycast_ok(&["info", "--json", arg(&cylinder)]);
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    let scaled = json["objects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|o| o["name"] == "scaled")
        .unwrap();
    assert_eq!(
        scaled["bounds"],
        serde_json::json!([[-16.5, -1.5, -2.0], [-15.5, 1.5, 2.0]])
    );
    let sphere = fixture("quadrics/far_sphere.gltf");
    let result = raycast_ok(&["info", "--json", arg(&sphere)]);
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(
        json["bounds"],
        serde_json::json!([[6399999.0, -1.0, -1.0], [6400001.0, 1.0, 1.0]])
    );
    let text = raycast_ok(&["info", arg(&cylinder)]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("bounds [-16.5, -1.7, -2] .. [17.3, 1.5, 2]"),
        "{text}"
    );
}

/// A crate file whose array claims 2^52 elements: the reader used to allocate what it claimed
/// and abort (the child process died of SIGABRT); it now reads in chunks, runs into the end
/// of the data, and the mesh is skipped with a warning.
#[test]
fn a_usdc_array_longer_than_its_file_is_a_warning_not_a_crash() {
    let scene = fixture("fuzz/usd/openusd_usdc_huge_array.usdc");
    let result = raycast(&["info", arg(&scene), "--usd-timeout", "20"]);
    let out = String::from_utf8_lossy(&result.stdout);
    assert_eq!(result.status.code(), Some(0), "{}", stderr(&result));
    assert!(
        out.contains("/cube.faceVertexCounts: cannot be read") && out.contains("mesh skipped"),
        "{out}"
    );
}
