//! The automatic camera and camera choice as a user meets them.

use crate::common;
use common::*;

/// The rows and columns of an (H, W) id buffer that hold a hit: (first row, last row, first
/// column, last column).
fn hit_extent(ids: &[u32], width: usize) -> (usize, usize, usize, usize) {
    let hits: Vec<(usize, usize)> = ids
        .iter()
        .enumerate()
        .filter(|(_, &id)| id != 0)
        .map(|(i, _)| (i / width, i % width))
        .collect();
    assert!(!hits.is_empty(), "nothing hit");
    let rows = hits.iter().map(|h| h.0);
    let cols = hits.iter().map(|h| h.1);
    (
        rows.clone().min().unwrap(),
        rows.max().unwrap(),
        cols.clone().min().unwrap(),
        cols.max().unwrap(),
    )
}

/// Renders `scene` with the automatic camera into id.npy; returns the ids.
fn auto_ids(scene: &std::path::Path, out: &std::path::Path, size: [&str; 2]) -> Vec<u32> {
    raycast_ok(&[
        arg(scene),
        "--width",
        size[0],
        "--height",
        size[1],
        "--aov",
        "id",
        "--format",
        "npy",
        "--out",
        arg(out),
        "--quiet",
    ]);
    read_u32(&out.join("id.npy")).1
}

#[test]
fn the_automatic_camera_frames_a_wide_scene_across_a_wide_image() {
    let dir = temp_dir("wide");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("row.obj");
    // A strip 20 wide and 1 high in the plane z = 0.
    std::fs::write(
        &scene,
        "v -10 -0.5 0\nv 10 -0.5 0\nv 10 0.5 0\nv -10 0.5 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let ids = auto_ids(&scene, &dir.join("out"), ["1024", "256"]);
    let (_, _, left, right) = hit_extent(&ids, 1024);
    let filled = (right - left + 1) as f64 / 1024.0;
    // The view is oblique (from the right and above) and keeps a 5% margin, so the near end of
    // the strip binds; main's sphere framing filled 0.21.
    assert!(filled > 0.6, "the strip fills {filled:.2} of the width");
}

#[test]
fn a_z_up_stage_renders_upright() {
    let dir = temp_dir("z-up");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("tower.usda");
    // A tower 10 high along +Z and 1 wide along X.
    std::fs::write(
        &scene,
        "#usda 1.0\n(\n    upAxis = \"Z\"\n)\n\ndef Mesh \"Tower\" {\n    \
         point3f[] points = [(-0.5, 0, 0), (0.5, 0, 0), (0.5, 0, 10), (-0.5, 0, 10)]\n    \
         int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n}\n",
    )
    .unwrap();
    let ids = auto_ids(&scene, &dir.join("out"), ["256", "256"]);
    let (top, bottom, left, right) = hit_extent(&ids, 256);
    let (tall, wide) = (bottom - top + 1, right - left + 1);
    assert!(
        tall > 4 * wide,
        "{tall} rows by {wide} columns: not upright"
    );
}

#[test]
fn an_unknown_camera_name_lists_the_files_cameras() {
    let out = temp_dir("no-camera");
    let result = raycast(&[
        arg(&fixture("gltf/cube.gltf")),
        "--camera",
        "nope",
        "--out",
        arg(&out),
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the file's cameras are 0 'cam'"),
        "{stderr}"
    );
}

/// The automatic view fits the scene's projected vertices, centred: a wide flat board with a
/// thin post at one corner (a bounding box mostly empty, as a chess set's is) at 320x180 and
/// 1024x256 fills 95 % of the binding axis and leaves equal margins (to a pixel) on both
/// sides of both axes. (It fitted the box's corners: at 1920x1080 the chess set left the top
/// third empty and off-centre, and ShapeCollection filled under 60 % of a 1024x256 width.)
#[test]
fn the_automatic_view_fills_the_image_and_is_centred() {
    let mut obj =
        String::from("o board\nv -4 0 -3\nv 4 0 -3\nv 4 0 3\nv -4 0 3\nf 1 2 3\nf 1 3 4\n");
    obj += "o post\nv 3.9 0 2.9\nv 4 0 2.9\nv 4 3 2.9\nv 3.9 3 2.9\nf 5 6 7\nf 5 7 8\n";
    let scene = temp_file("framing", "board.obj", obj);
    for (width, height) in [(320usize, 180usize), (1024, 256)] {
        let out = temp_dir(&format!("framing-{width}"));
        let (w, h) = (width.to_string(), height.to_string());
        raycast_ok(&[
            arg(&scene),
            "--aov",
            "id",
            "--format",
            "npy",
            "--width",
            &w,
            "--height",
            &h,
            "--out",
            arg(&out),
            "--quiet",
        ]);
        let (_, ids) = read_u32(&out.join("id.npy"));
        let hit = |x: usize, y: usize| ids[y * width + x] != 0;
        let columns: Vec<usize> = (0..width)
            .filter(|&x| (0..height).any(|y| hit(x, y)))
            .collect();
        let rows: Vec<usize> = (0..height)
            .filter(|&y| (0..width).any(|x| hit(x, y)))
            .collect();
        let (left, right) = (columns[0], width - 1 - columns[columns.len() - 1]);
        let (top, bottom) = (rows[0], height - 1 - rows[rows.len() - 1]);
        assert!(
            left.abs_diff(right) <= 1,
            "{width}x{height}: left {left}, right {right}"
        );
        assert!(
            top.abs_diff(bottom) <= 1,
            "{width}x{height}: top {top}, bottom {bottom}"
        );
        let fill_x = (width - left - right) as f64 / width as f64;
        let fill_y = (height - top - bottom) as f64 / height as f64;
        assert!(
            (fill_x.max(fill_y) - 1.0 / 1.05).abs() < 0.01,
            "{width}x{height}: fills {fill_x} x {fill_y}"
        );
    }
}

/// A file camera's aspect ratio overridden by --width and --height is said once in the
/// warnings (it was silent); giving one side keeps the camera's aspect, with no warning.
#[test]
fn an_overridden_camera_aspect_is_said_once() {
    let cube = fixture("gltf/cube.gltf"); // camera "cam", aspectRatio 1.0
    let out = temp_dir("aspect-override");
    let sidecar = |size: &[&str]| {
        let mut args = vec![arg(&cube), "--format", "npy", "--out", arg(&out), "--quiet"];
        args.extend(size);
        raycast_ok(&args);
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
        json["warnings"].as_array().unwrap().clone()
    };
    let stretched = sidecar(&["--width", "40", "--height", "20"]);
    let said: Vec<_> = stretched
        .iter()
        .filter(|w| w.as_str().unwrap().contains("has aspect ratio 1.0000"))
        .collect();
    assert_eq!(said.len(), 1, "{stretched:?}");
    assert!(said[0].as_str().unwrap().contains("40x20 image (2.0000)"));
    assert!(sidecar(&["--width", "40"])
        .iter()
        .all(|w| !w.as_str().unwrap().contains("aspect")));
    assert!(sidecar(&["--width", "30", "--height", "30"]).is_empty());
}
