//! Pinhole cameras (`--K`, `--cam-to-world`, `--camera-axes`) and many views in one run
//! (`--views FILE`): each view's folder equals a single run of that view (every file, the
//! sidecar but for its timings); depths and z of a pinhole camera agree with the analytic
//! intersection of its rays, as the convention defines them (pixel (u, v) centred at
//! (u + ½, v + ½), ray K⁻¹ (u + ½, v + ½, 1) in OpenCV's axes), with a plane; bad view files
//! are one-line errors naming the frame.

use crate::common;
use common::{arg, file_names, fixture, raycast, raycast_ok, read_f64, temp_dir, temp_file};
use glam::{DMat3, DVec3};
use std::path::Path;

/// A sidecar without its timings (the only part that differs from run to run).
fn sidecar_without_timings(dir: &Path) -> serde_json::Value {
    let text = std::fs::read(dir.join("raycast.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&text).unwrap();
    json.as_object_mut().unwrap().remove("timings");
    json
}

/// A camera-to-world matrix (OpenGL axes) at `eye` looking at `target` with +Y up, rows.
fn look_at(eye: DVec3, target: DVec3) -> [[f64; 4]; 4] {
    let back = (eye - target).normalize();
    let right = DVec3::Y.cross(back).normalize();
    let up = back.cross(right);
    let mut rows = [[0.0, 0.0, 0.0, 1.0]; 4];
    for r in 0..3 {
        rows[r] = [right[r], up[r], back[r], eye[r]];
    }
    rows
}

/// The 16 numbers of `rows`, comma-separated, with Rust's shortest round-trip digits.
fn matrix_arg(rows: &[[f64; 4]; 4]) -> String {
    let values: Vec<String> = rows.iter().flatten().map(|v| format!("{v:?}")).collect();
    values.join(",")
}

/// Three frames of a transforms.json: a focal length from camera_angle_x at the top, a frame
/// with its own fl_x, fl_y, cx, cy, w and h, and one from another side.
fn transforms() -> (serde_json::Value, Vec<[[f64; 4]; 4]>) {
    let poses = vec![
        look_at(DVec3::new(0.3, -0.2, 4.0), DVec3::new(0.3, -0.2, 0.0)),
        look_at(DVec3::new(1.5, 1.0, 3.0), DVec3::ZERO),
        look_at(DVec3::new(-2.0, 0.5, 2.5), DVec3::new(0.1, 0.0, 0.0)),
    ];
    let json = serde_json::json!({
        "camera_angle_x": 0.9,
        "w": 40,
        "h": 30,
        "frames": [
            {"file_path": "./train/r_0.png", "transform_matrix": poses[0]},
            {"file_path": "./train/r_1.png", "transform_matrix": poses[1],
             "fl_x": 35.5, "fl_y": 37.25, "cx": 17.0, "cy": 16.5, "w": 36, "h": 32},
            {"file_path": "./train/r_2.png", "transform_matrix": poses[2]},
        ]
    });
    (json, poses)
}

const RENDER: [&str; 4] = ["--aov", "depth,z,normal,id,prim", "--format", "npy,exr,png"];

/// Every frame of a transforms.json, rendered in one run, equals a single run with that
/// frame's --K, --cam-to-world and size.
#[test]
fn each_view_equals_a_single_run_of_its_camera() {
    let (json, poses) = transforms();
    let views = temp_file("views-equal", "transforms.json", json.to_string());
    let dir = views.parent().unwrap();
    let all = dir.join("all");
    let scene = fixture("gltf/plane.gltf");
    let mut args = vec![
        arg(&scene),
        "--views",
        arg(&views),
        "--out",
        arg(&all),
        "-q",
    ];
    args.extend(RENDER);
    raycast_ok(&args);
    let folders = ["0000-r_0", "0001-r_1", "0002-r_2"];
    assert_eq!(file_names(&all), folders);
    // The intrinsics each frame means, written out by hand: fx = w / (2 tan(angle / 2)),
    // the principal point at the centre, fy = fx; or the frame's own.
    let fx = 40.0 / (2.0 * (0.45f64).tan());
    let intrinsics = [
        (format!("{fx:?},{fx:?},20,15"), 40, 30),
        ("35.5,37.25,17,16.5".to_string(), 36, 32),
        (format!("{fx:?},{fx:?},20,15"), 40, 30),
    ];
    for ((folder, (k, w, h)), pose) in folders.iter().zip(&intrinsics).zip(&poses) {
        let single = dir.join(format!("single-{folder}"));
        let (w, h, m) = (w.to_string(), h.to_string(), matrix_arg(pose));
        let mut args = vec![
            arg(&scene),
            "--K",
            k,
            "--width",
            &w,
            "--height",
            &h,
            "--cam-to-world",
            &m,
            "--camera-axes",
            "opengl",
            "--out",
            arg(&single),
            "-q",
        ];
        args.extend(RENDER);
        raycast_ok(&args);
        let view = all.join(folder);
        assert_eq!(file_names(&view), file_names(&single));
        for name in file_names(&single) {
            if name != "raycast.json" {
                let same = std::fs::read(view.join(&name)).unwrap()
                    == std::fs::read(single.join(&name)).unwrap();
                assert!(same, "{folder}/{name} differs from the single run's");
            }
        }
        assert_eq!(
            sidecar_without_timings(&view),
            sidecar_without_timings(&single)
        );
    }
    // The scene was read and its octree built once: every view records the same times.
    let timings: Vec<serde_json::Value> = folders
        .iter()
        .map(|f| {
            let text = std::fs::read(all.join(f).join("raycast.json")).unwrap();
            let json: serde_json::Value = serde_json::from_slice(&text).unwrap();
            serde_json::json!([json["timings"]["load"], json["timings"]["build"]])
        })
        .collect();
    assert!(timings.iter().all(|t| *t == timings[0]), "{timings:?}");
}

/// The pinhole convention against the analytic intersection with the plane z = 0 (the
/// square |x|, |y| ≤ 1): z is the distance along the view axis and depth the distance to the
/// hit, for a tilted camera with an off-centre principal point and fx ≠ fy.
#[test]
fn pinhole_depth_is_the_analytic_plane_depth() {
    let dir = temp_dir("views-analytic");
    let eye = DVec3::new(0.4, -0.3, 3.0);
    let pose = look_at(eye, DVec3::new(0.1, 0.2, 0.0));
    let (fx, fy, cx, cy, w, h) = (30.0, 27.5, 21.25, 14.0, 44usize, 32usize);
    let k = format!("{fx},{fy},{cx},{cy}");
    let (ws, hs, m) = (w.to_string(), h.to_string(), matrix_arg(&pose));
    let scene = fixture("gltf/plane.gltf");
    let args = [
        arg(&scene),
        "--K",
        &k,
        "--width",
        &ws,
        "--height",
        &hs,
        "--cam-to-world",
        &m,
        "--camera-axes",
        "opengl",
        "--aov",
        "depth,z",
        "--format",
        "npy",
        "--out",
        arg(&dir),
        "-q",
    ];
    raycast_ok(&args);
    let (shape, depth) = read_f64(&dir.join("depth.npy"));
    assert_eq!(shape, [h, w]);
    let (_, z) = read_f64(&dir.join("z.npy"));
    let rotation = DMat3::from_cols_array_2d(&[0, 1, 2].map(|c| [0, 1, 2].map(|r| pose[r][c])));
    let forward = -rotation.z_axis;
    let (mut hits, mut checked) = (0, 0);
    for v in 0..h {
        for u in 0..w {
            // OpenCV's camera frame (+Y down, +Z forward) in OpenGL's (+Y up, -Z forward).
            let x = (u as f64 + 0.5 - cx) / fx;
            let y = (v as f64 + 0.5 - cy) / fy;
            let d = rotation * DVec3::new(x, -y, -1.0);
            let t = -eye.z / d.z;
            let p = eye + d * t;
            let i = v * w + u;
            let margin = 1.0 - p.x.abs().max(p.y.abs());
            if margin.abs() < 1e-9 {
                continue; // on the square's edge: either answer is right
            }
            checked += 1;
            if margin > 0.0 {
                hits += 1;
                let expected = t * d.length();
                assert!(
                    (depth[i] - expected).abs() <= 1e-12 * expected,
                    "depth at {u},{v}"
                );
                let expected_z = (p - eye).dot(forward);
                assert!(
                    (z[i] - expected_z).abs() <= 1e-12 * expected_z,
                    "z at {u},{v}"
                );
            } else {
                assert!(
                    depth[i].is_infinite() && z[i].is_infinite(),
                    "miss at {u},{v}"
                );
            }
        }
    }
    assert!(
        hits > 100 && checked - hits > 100,
        "{hits} hits of {checked}"
    );
}

/// OpenCV's axes are OpenGL's with Y and Z turned round: the same camera written either way
/// draws the same buffers, and a plain view list in OpenCV's axes equals the single run.
#[test]
fn opencv_axes_draw_the_same_camera() {
    let dir = temp_dir("views-axes");
    let gl = look_at(DVec3::new(1.0, 0.5, 3.0), DVec3::ZERO);
    let mut cv = gl;
    for row in cv.iter_mut().take(3) {
        row[1] = -row[1];
        row[2] = -row[2];
    }
    let scene = fixture("gltf/plane.gltf");
    let run = |out: &Path, matrix: &[[f64; 4]; 4], axes: &str| {
        let m = matrix_arg(matrix);
        raycast_ok(&[
            arg(&scene),
            "--K",
            "20,20,12,10",
            "--width",
            "24",
            "--height",
            "20",
            "--cam-to-world",
            &m,
            "--camera-axes",
            axes,
            "--aov",
            "depth,normal",
            "--format",
            "npy",
            "--out",
            arg(out),
            "-q",
        ]);
    };
    run(&dir.join("gl"), &gl, "opengl");
    run(&dir.join("cv"), &cv, "opencv");
    let list = serde_json::json!({
        "axes": "opencv",
        "K": [[20.0, 0.0, 12.0], [0.0, 20.0, 10.0], [0.0, 0.0, 1.0]],
        "width": 24,
        "height": 20,
        "views": [{"name": "front", "cam_to_world": cv}],
    });
    let views = dir.join("views.json");
    std::fs::write(&views, list.to_string()).unwrap();
    let many = dir.join("many");
    raycast_ok(&[
        arg(&scene),
        "--views",
        arg(&views),
        "--aov",
        "depth,normal",
        "--format",
        "npy",
        "--out",
        arg(&many),
        "-q",
    ]);
    for name in ["depth.npy", "normal.npy"] {
        let gl = std::fs::read(dir.join("gl").join(name)).unwrap();
        assert_eq!(
            gl,
            std::fs::read(dir.join("cv").join(name)).unwrap(),
            "{name}"
        );
        assert_eq!(
            gl,
            std::fs::read(many.join("0000-front").join(name)).unwrap()
        );
    }
}

/// A view file that cannot be drawn as it says is a one-line error naming the file and the
/// frame, and nothing is written.
#[test]
fn bad_view_files_are_one_line_errors_naming_the_frame() {
    let scene = fixture("gltf/plane.gltf");
    let identity = [[1, 0, 0, 0], [0, 1, 0, 3], [0, 0, 1, 0], [0, 0, 0, 1]];
    let cases = [
        (
            serde_json::json!({"fl_x": 10, "w": 8, "h": 8, "k1": 0.02,
                "frames": [{"file_path": "a.png", "transform_matrix": identity}]}),
            "frames[0] ('a.png'): lens distortion k1 = 0.02 is not supported",
        ),
        (
            serde_json::json!({"fl_x": 10, "frames": [
                {"file_path": "a.png", "transform_matrix": identity, "w": 8, "h": 8},
                {"file_path": "b.png", "transform_matrix": identity}]}),
            "frames[1] ('b.png'): no image size (w and h)",
        ),
        (
            serde_json::json!({"fl_x": 10, "w": 8, "h": 8, "camera_model": "OPENCV_FISHEYE",
                "frames": [{"transform_matrix": identity}]}),
            "frames[0]: camera_model \"OPENCV_FISHEYE\" is not a pinhole",
        ),
        (
            serde_json::json!({"fl_x": 10, "w": 8, "h": 8,
                "frames": [{"transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]}]}),
            "frames[0]: the camera-to-world matrix is not invertible",
        ),
        (
            serde_json::json!({"K": [[10, 0, 4], [0, 10, 4], [0, 0, 1]], "width": 8, "height": 8,
                "views": [{"cam_to_world": identity}]}),
            "no 'axes'",
        ),
        (
            serde_json::json!({"axes": "opencv", "width": 8, "height": 8,
                "views": [{"name": "v", "K": [[0, 0, 4], [0, 10, 4], [0, 0, 1]], "cam_to_world": identity}]}),
            "views[0] ('v'): K is not invertible",
        ),
        (
            serde_json::json!({"frames": []}),
            "the views file lists no views",
        ),
    ];
    for (i, (json, expected)) in cases.iter().enumerate() {
        let views = temp_file(&format!("views-bad-{i}"), "views.json", json.to_string());
        let out = views.parent().unwrap().join("out");
        let result = raycast(&[arg(&scene), "--views", arg(&views), "--out", arg(&out)]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains("views.json") && stderr.contains(expected),
            "{stderr}"
        );
        assert!(!out.exists(), "case {i} wrote {out:?}");
    }
}

/// --views with a sequence of times, or with rays, is refused before anything is read.
#[test]
fn views_refuse_a_time_sequence_and_rays() {
    let scene = fixture("gltf/plane.gltf");
    let (json, _) = transforms();
    let views = temp_file("views-refused", "transforms.json", json.to_string());
    let out = views.parent().unwrap().join("out");
    for extra in [["--time", "0:1:0.5"], ["--rays", "rays.npy"]] {
        let mut args = vec![arg(&scene), "--views", arg(&views), "--out", arg(&out)];
        args.extend(extra);
        let result = raycast(&args);
        assert_eq!(result.status.code(), Some(2), "{extra:?}");
        assert!(!out.exists());
    }
}
