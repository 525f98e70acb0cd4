//! The automatic camera and camera choice as a user meets them.

mod common;
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
