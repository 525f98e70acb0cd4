//! Messages a new user meets: wrong kinds of input named for what they are, help text, `info`.

mod common;
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
        "fuzz/usd/openusd_usdc_huge_array.usdc",
        "fuzz/usd/openusd_usdc_token_index.usdc",
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
        }
    }
    assert!(!out.exists());
}
