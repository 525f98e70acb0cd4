//! The command line as a user runs it: outputs, conventions, exit codes and error messages.

use crate::common;
use common::*;
use std::path::PathBuf;

#[test]
fn default_render_writes_exr_png_and_sidecar() {
    let out = temp_dir("default");
    let scene = fixture("gltf/cube.gltf");
    let result = raycast_ok(&[arg(&scene), "--out", arg(&out), "--quiet"]);
    assert!(result.stderr.is_empty(), "--quiet prints nothing");
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    files.sort();
    assert_eq!(files, ["depth.exr", "depth.png", "raycast.json"]);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(json["width"], 512);
    assert_eq!(json["camera"]["name"], "cam");
    assert_eq!(json["objects"][0]["name"], "cube");
    assert_eq!(json["objects"][0]["id"], 1);
    assert_eq!(json["stats"]["triangles"], 12);
    for stage in ["load", "build", "trace", "write"] {
        assert!(json["timings"][stage].as_f64().unwrap() >= 0.0);
    }
    let png = image::open(out.join("depth.png")).unwrap().to_rgb8();
    assert_eq!(png.get_pixel(0, 0).0, [0, 0, 0], "corner misses: black");
    assert_ne!(png.get_pixel(256, 256).0, [0, 0, 0]);
}

#[test]
fn camera_buffers_follow_the_pixel_conventions() {
    let out = temp_dir("conventions");
    let scene = fixture("gltf/cube.gltf");
    raycast_ok(&[
        arg(&scene),
        "--aov",
        "depth,z,normal,position,id,prim",
        "--format",
        "npy",
        "--width",
        "65",
        "--height",
        "65",
        "--out",
        arg(&out),
        "--quiet",
    ]);
    let (shape, depth) = read_f64(&out.join("depth.npy"));
    assert_eq!(shape, [65, 65]);
    assert_eq!(
        depth[32 * 65 + 32],
        4.0,
        "centre pixel looks straight at the face"
    );
    let (_, z) = read_f64(&out.join("z.npy"));
    let (shape, position) = read_f64(&out.join("position.npy"));
    assert_eq!(shape, [65, 65, 3]);
    // Row 1 is near the top of the image (+Y), column 1 near the left (-X).
    let p = &position[(65 + 1) * 3..(65 + 1) * 3 + 3];
    assert!(
        p[0] < -0.9 && p[1] > 0.9 && (p[2] - 1.0).abs() < 1e-12,
        "{p:?}"
    );
    let k = 0.25f64.tan();
    let (sx, sy) = (2.0 * 1.5 / 65.0 - 1.0, 1.0 - 2.0 * 1.5 / 65.0);
    let expected = 4.0 * (1.0 + (sx * k).powi(2) + (sy * k).powi(2)).sqrt();
    assert!(
        (depth[66] - expected).abs() < 1e-12 * expected,
        "{} vs {expected}",
        depth[66]
    );
    assert!((z[66] - 4.0).abs() < 1e-12);
    let (_, id) = read_u32(&out.join("id.npy"));
    let (_, prim) = read_u32(&out.join("prim.npy"));
    let (_, normal) = read_f64(&out.join("normal.npy"));
    assert_eq!(
        (id[0], prim[0], depth[0], z[0]),
        (0, u32::MAX, f64::INFINITY, f64::INFINITY),
        "corner misses"
    );
    assert_eq!(&normal[..3], &[0.0, 0.0, 0.0]);
    assert_eq!(id[66], 1);
    assert_eq!(&normal[66 * 3..66 * 3 + 3], &[0.0, 0.0, 1.0]);
    let hits = id.iter().filter(|&&i| i == 1).count();
    assert_eq!(hits, 63 * 63, "|sx|, |sy| <= 1/(4k) hit the front face");
}

#[test]
fn rays_mode_keeps_input_order_and_is_thread_count_independent() {
    let out1 = temp_dir("rays1");
    let out2 = temp_dir("rays2");
    std::fs::create_dir_all(&out1).unwrap();
    let rays_file = out1.join("rays.npy");
    let mut rays = vec![
        [0.5, -0.25, 5.0, 0.0, 0.0, -1.0],
        [2.0, 0.0, 5.0, 0.0, 0.0, -1.0],
        [0.25, 0.5, 0.0, 0.0, 0.0, 2.0],
    ];
    let mut rng = Rng(7);
    for _ in 0..5000 {
        let o = rng.point(-3.0, 3.0);
        let d = rng.direction();
        rays.push([o.x, o.y, o.z, d.x, d.y, d.z]);
    }
    write_rays(&rays_file, &rays);
    let scene = fixture("gltf/instances.gltf");
    for (out, threads) in [(&out1, "1"), (&out2, "2")] {
        raycast_ok(&[
            arg(&scene),
            "--rays",
            arg(&rays_file),
            "--aov",
            "depth,normal,id,prim",
            "--out",
            arg(out),
            "--threads",
            threads,
            "--quiet",
        ]);
    }
    for name in ["depth.npy", "normal.npy", "id.npy", "prim.npy"] {
        assert_eq!(
            std::fs::read(out1.join(name)).unwrap(),
            std::fs::read(out2.join(name)).unwrap(),
            "{name}"
        );
    }
    let (shape, depth) = read_f64(&out1.join("depth.npy"));
    assert_eq!(shape, [rays.len()]);
    assert_eq!(depth[1], f64::INFINITY);
    let cube = temp_dir("rays-cube");
    let result = raycast(&[
        arg(&fixture("gltf/cube.gltf")),
        "--rays",
        arg(&rays_file),
        "--out",
        arg(&cube),
        "--quiet",
    ]);
    assert!(result.status.success());
    let (_, depth) = read_f64(&cube.join("depth.npy"));
    assert_eq!(&depth[..3], &[4.0, f64::INFINITY, 1.0]);
}

#[test]
fn bad_inputs_fail_cleanly_naming_the_file() {
    let out = temp_dir("bad");
    let cube = fixture("gltf/cube.gltf");
    let cases: Vec<(PathBuf, Vec<&str>, &str)> = vec![
        (fixture("bad/truncated.glb"), vec![], "GLB"),
        (
            fixture("bad/bad_index.gltf"),
            vec![],
            "index 99 out of range",
        ),
        (fixture("bad/nan_position.gltf"), vec![], "not finite"),
        (
            fixture("bad/missing_buffer.gltf"),
            vec![],
            "missing_buffer.bin', which does not exist",
        ),
        (fixture("bad/not_json.gltf"), vec![], "glTF"),
        (
            fixture("bad/draco_required.gltf"),
            vec![],
            "KHR_draco_mesh_compression",
        ),
        (
            fixture("bad/meshopt_required.gltf"),
            vec![],
            "EXT_meshopt_compression",
        ),
        (fixture("bad/buffer_too_short.gltf"), vec![], "past the end"),
        (fixture("bad/node_cycle.gltf"), vec![], "cycle"),
        (fixture("bad/garbage.obj"), vec![], "out of bounds"),
        (fixture("does_not_exist.gltf"), vec![], "cannot read"),
        (fixture("README.md"), vec![], "unsupported file type"),
        (cube.clone(), vec!["--rays", "BAD_RAYS"], "shape"),
        (
            cube.clone(),
            vec!["--rays", "NAN_RAYS", "--strict-rays"],
            "not finite",
        ),
        (cube.clone(), vec!["--camera", "nope"], "no camera 'nope'"),
    ];
    let bad_rays = fixture("bad/bad_rays.npy");
    let nan_rays = fixture("bad/nan_rays.npy");
    for (file, extra, message) in cases {
        let mut args = vec![arg(&file), "--out", arg(&out)];
        args.extend(extra.iter().map(|a| match *a {
            "BAD_RAYS" => arg(&bad_rays),
            "NAN_RAYS" => arg(&nan_rays),
            other => other,
        }));
        let result = raycast(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{file:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
        assert!(
            stderr.contains(message),
            "{file:?}: expected '{message}' in: {stderr}"
        );
        assert!(
            stderr.contains(file.file_name().unwrap().to_str().unwrap()) || !extra.is_empty(),
            "{stderr}"
        );
    }
    assert!(!out.exists(), "failed runs leave no output folder");
}

/// Documents broken anywhere, also where the render never reads (tinygltf's malformed files:
/// a dangling index under an image, an empty `asset.version`), and text that is not OBJ stop
/// `render` and `info` with one line naming the file, the place and the problem; nothing is
/// written. The expected places and indices are read off the files by hand.
#[test]
fn broken_documents_stop_before_any_output() {
    let not_obj = temp_file(
        "not-obj",
        "not_obj.obj",
        "# base64, not OBJ\naGVsbG8gd29ybGQsIG5vdCBhbiBPQko=\nbW9yZQ==\n",
    );
    let binary = temp_file(
        "binary-obj",
        "binary.obj",
        b"v 0 0 0\n\x89PNG\r\n\x1a\n\xff\xfe\n",
    );
    let cases = [
        (
            fixture("malformed/invalid-buffer-index.gltf"),
            "/bufferViews/1/buffer: refers to 1, which does not exist",
        ),
        (
            fixture("malformed/invalid-buffer-view-index.gltf"),
            "/accessors/0/bufferView: refers to 1, which does not exist",
        ),
        (
            fixture("malformed/invalid-primitive-indices.gltf"),
            "/accessors/0/bufferView: refers to 1, which does not exist",
        ),
        (
            fixture("malformed/issue-416.gltf"),
            "/asset/version: \"\" is not a version: it must look like \"MAJOR.MINOR\"",
        ),
        (
            not_obj,
            "line 2: 'aGVsbG8gd29ybGQsIG5vdCBh…' is not an OBJ statement, and no line of the file is one",
        ),
        (
            binary,
            "line 2: not UTF-8 text: this is no OBJ file (binary data?)",
        ),
    ];
    let out = temp_dir("broken-documents");
    for (file, message) in cases {
        let expected = format!("raycast: error: {}: {message}\n", file.display());
        let render = [arg(&file), "--aov", "depth", "--out", arg(&out)];
        let info = ["info", arg(&file)];
        for args in [&render[..], &info[..]] {
            let result = raycast(args);
            assert_eq!(result.status.code(), Some(1), "{args:?}");
            assert_eq!(
                String::from_utf8_lossy(&result.stderr),
                expected,
                "{args:?}"
            );
        }
        assert!(!out.exists(), "{}: no output is written", file.display());
    }
}

/// Unusual but valid documents keep rendering: tinygltf's issue-492 file (a skin and three
/// nodes, no mesh: an empty scene, with the warning), its issue-440 file (a GLB whose BIN
/// chunk is read correctly: one triangle), and an OBJ with a statement of its own (`vc`)
/// before its geometry and a byte-order mark.
#[test]
fn unusual_but_valid_documents_still_render() {
    let obj = temp_file(
        "extended-obj",
        "extended.obj",
        "\u{feff}# exporter extension first\nvc 1 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    let cases = [
        (fixture("malformed/issue-492.glb"), 0),
        (fixture("malformed/zero-sized-bin-chunk-issue-440.glb"), 1),
        (obj, 1),
    ];
    for (n, (file, triangles)) in cases.into_iter().enumerate() {
        let out = temp_dir(&format!("unusual-{n}"));
        let result = raycast_ok(&[arg(&file), "--aov", "depth", "--out", arg(&out)]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        let sidecar = std::fs::read(out.join("raycast.json")).unwrap();
        let json: serde_json::Value = serde_json::from_slice(&sidecar).unwrap();
        assert_eq!(json["stats"]["triangles"], triangles, "{}", file.display());
        assert_eq!(
            stderr.contains("warning: the scene holds no triangles or quadrics"),
            triangles == 0,
            "{stderr}"
        );
    }
}

#[test]
fn an_input_is_never_overwritten() {
    let dir = temp_dir("protect");
    std::fs::create_dir_all(&dir).unwrap();
    let rays = dir.join("depth.npy");
    write_rays(&rays, &[[0.0, 0.0, 5.0, 0.0, 0.0, -1.0]]);
    let before = std::fs::read(&rays).unwrap();
    let scene = fixture("gltf/cube.gltf");
    let result = raycast(&[arg(&scene), "--rays", arg(&rays), "--out", arg(&dir)]);
    // refused before any work, as other --out problems are (usage, exit 2)
    assert_eq!(result.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&result.stderr).contains("is an input of this run"));
    assert_eq!(
        std::fs::read(&rays).unwrap(),
        before,
        "the ray file is unchanged"
    );
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(left.len(), 1, "no other file was left behind");
}

#[test]
fn empty_scene_renders_all_misses() {
    let out = temp_dir("empty");
    raycast_ok(&[
        arg(&fixture("bad/empty.gltf")),
        "--format",
        "npy",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        arg(&out),
        "--quiet",
    ]);
    let (_, depth) = read_f64(&out.join("depth.npy"));
    assert!(depth.iter().all(|d| *d == f64::INFINITY));
}

#[test]
fn usage_errors_exit_with_2() {
    for args in [
        vec![],
        vec!["scene.gltf", "--aov", "colour"],
        vec!["scene.gltf", "--format", "tiff"],
        vec!["scene.gltf", "--eye", "1,2"],
        vec!["scene.gltf", "--fov", "40", "--ortho", "2"],
    ] {
        let result = raycast(&args);
        assert_eq!(result.status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn eye_target_and_orthographic_cameras() {
    let out = temp_dir("ortho");
    let scene = fixture("gltf/plane.gltf");
    raycast_ok(&[
        arg(&scene),
        "--eye",
        "0,0,3",
        "--target",
        "0,0,0",
        "--ortho",
        "4",
        "--width",
        "4",
        "--height",
        "4",
        "--aov",
        "depth,id",
        "--format",
        "npy",
        "--out",
        arg(&out),
        "--quiet",
    ]);
    let (_, depth) = read_f64(&out.join("depth.npy"));
    // Pixel centres at x, y = ±0.5, ±1.5: the inner 2×2 hit the plane at depth 3.
    let expected: Vec<f64> = (0..16)
        .map(|i| {
            if (1..3).contains(&(i % 4)) && (1..3).contains(&(i / 4)) {
                3.0
            } else {
                f64::INFINITY
            }
        })
        .collect();
    assert_eq!(depth, expected);
}

#[test]
fn info_reports_objects_cameras_and_extensions() {
    let result = raycast(&["info", arg(&fixture("gltf/quantized.gltf")), "--json"]);
    assert!(result.status.success());
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(json["triangles"], 4);
    assert_eq!(json["objects"][1]["name"], "ubyte");
    assert_eq!(json["extensions_used"][0], "KHR_mesh_quantization");
    let text = raycast(&["info", arg(&fixture("gltf/cameras.gltf"))]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("persp") && text.contains("orthographic"),
        "{text}"
    );
}

/// One path rule for render, `info` and `check`: a buffer outside the scene's folder is
/// refused by all three, naming the URI; `--root` widens the folder and `--allow-outside`
/// lifts the rule, for all three alike.
#[test]
fn a_buffer_outside_the_root_is_refused_by_render_info_and_check() {
    let dir = temp_dir("confine");
    std::fs::create_dir_all(dir.join("scene")).unwrap();
    let cube = std::fs::read(fixture("gltf/cube.gltf")).unwrap();
    let text = String::from_utf8(cube).unwrap();
    assert!(
        text.contains("\"cube.bin\""),
        "the fixture names its buffer cube.bin"
    );
    let scene = dir.join("scene/cube.gltf");
    std::fs::write(
        &scene,
        text.replace("\"cube.bin\"", "\"../elsewhere/cube.bin\""),
    )
    .unwrap();
    std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
    std::fs::copy(fixture("gltf/cube.bin"), dir.join("elsewhere/cube.bin")).unwrap();
    let out = dir.join("out");
    let runs = |extra: &[&str]| -> Vec<std::process::Output> {
        let scene = arg(&scene);
        let render = [&[scene, "--out", arg(&out), "--quiet"][..], extra].concat();
        let info = [&["info", scene][..], extra].concat();
        let check = [&["check", scene, "--json"][..], extra].concat();
        vec![raycast(&render), raycast(&info), raycast(&check)]
    };
    for (run, what) in runs(&[]).iter().zip(["render", "info", "check"]) {
        assert!(!run.status.success(), "{what} reads outside the folder");
        let said = String::from_utf8_lossy(if what == "check" {
            &run.stdout
        } else {
            &run.stderr
        });
        assert!(
            said.contains("../elsewhere/cube.bin") && said.contains("leads out of the folder"),
            "{what}: {said}"
        );
    }
    for extra in [&["--root", arg(&dir)][..], &["--allow-outside"]] {
        for (run, what) in runs(extra).iter().zip(["render", "info", "check"]) {
            assert!(
                run.status.success(),
                "{what} {extra:?}: {}{}",
                String::from_utf8_lossy(&run.stdout),
                String::from_utf8_lossy(&run.stderr)
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Parts a ray caster does not read cannot stop a render: a texture without `source` (as
/// with KHR_texture_basisu or EXT_texture_webp), an animation channel without a node
/// (KHR_animation_pointer), integers written as `1.0`, and a missing image file.
#[test]
fn parts_a_ray_caster_does_not_read_cannot_stop_a_render() {
    let dir = temp_dir("unread-parts");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(fixture("gltf/cube.bin"), dir.join("cube.bin")).unwrap();
    let mut json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixture("gltf/cube.gltf")).unwrap()).unwrap();
    json["textures"] = serde_json::json!([{"sampler": 0.0}]);
    json["samplers"] = serde_json::json!([{}]);
    json["images"] = serde_json::json!([{"uri": "missing.png"}]);
    json["animations"] = serde_json::json!([{
        "channels": [{"sampler": 0, "target": {"path": "pointer"}}],
        "samplers": [{"input": 0, "output": 0}]
    }]);
    json["nodes"][0]["mesh"] = serde_json::json!(0.0);
    let scene = dir.join("cube.gltf");
    std::fs::write(&scene, json.to_string()).unwrap();
    let out = dir.join("out");
    raycast_ok(&[arg(&scene), "--out", arg(&out), "--quiet"]);
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(sidecar["stats"]["triangles"], 12);
    let _ = std::fs::remove_dir_all(&dir);
}
