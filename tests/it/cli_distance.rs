//! `raycast distance` on quadric fixtures: the lecture's sphere of radius 2 at the origin
//! (closed: distances and signs), and clipped cylinders (open: signs refused, naming the
//! object; distances alone with `--sign none`). Expected values follow from the geometry.

use crate::common;
use common::*;
use std::path::{Path, PathBuf};

/// `raycast distance` on the fixture `scene` for `points`, in a fresh folder named for
/// `name`: the run and its output folder.
fn distance(name: &str, scene: &str, points: &[[f64; 3]]) -> (std::process::Output, PathBuf) {
    let dir = temp_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("points.npy");
    write_rays::<3>(&file, points);
    let out = dir.join("d");
    (distance_into(scene, &file, &out, &[]), out)
}

/// `raycast distance` on the fixture `scene` for the points file `points` into `out`, with
/// `extra` arguments.
fn distance_into(scene: &str, points: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let scene = fixture(scene);
    let mut args = vec![
        "distance",
        scene.to_str().unwrap(),
        points.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "-q",
    ];
    args.extend(extra);
    raycast(&args)
}

#[test]
fn distances_and_signs_on_the_lecture_s_sphere() {
    // From (0, 0, 10): 8 to (0, 0, 2); from the centre: 2 (every point is nearest); from
    // (3, 4, 0): 3 to (1.2, 1.6, 0); from (0, 1, 0), inside: 1 to (0, 2, 0).
    let points = [
        [0.0, 0.0, 10.0],
        [0.0, 0.0, 0.0],
        [3.0, 4.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let (run, out) = distance(
        "distance-sphere",
        "quadrics/sphere_coefficients.gltf",
        &points,
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let (_, distance) = read_f64(&out.join("distance.npy"));
    let (_, signed) = read_f64(&out.join("signed_distance.npy"));
    let (_, point) = read_f64(&out.join("point.npy"));
    let (_, normal) = read_f64(&out.join("normal.npy"));
    let (_, id) = read_u32(&out.join("id.npy"));
    let (_, prim) = read_u32(&out.join("prim.npy"));
    let want = [8.0, 2.0, 3.0, 1.0];
    for (got, want) in distance.iter().zip(want) {
        assert!(
            (got - want).abs() <= 4.0 * f64::EPSILON * 10.0,
            "{distance:?}"
        );
    }
    assert_eq!(
        signed.iter().map(|s| s.signum()).collect::<Vec<_>>(),
        [1.0, -1.0, 1.0, -1.0]
    );
    for (got, want) in point[6..9].iter().zip([1.2, 1.6, 0.0]) {
        assert!((got - want).abs() <= 1e-15, "{point:?}");
    }
    for (got, want) in normal[..3].iter().zip([0.0, 0.0, 1.0]) {
        assert!((got - want).abs() <= 1e-15, "{normal:?}");
    }
    // The centre's nearest point lies on the sphere, whichever it is.
    let centre_nearest = point[3..6].iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((centre_nearest - 2.0).abs() <= 1e-15);
    assert_eq!(id, [1, 1, 1, 1]);
    assert_eq!(prim, [0, 0, 0, 0]);
}

#[test]
fn an_open_quadric_s_sign_is_refused_naming_the_object() {
    let (run, out) = distance(
        "distance-open",
        "quadrics/cylinder.gltf",
        &[[0.0, 0.0, 0.0]],
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cylinder.gltf"), "{stderr}");
    assert!(stderr.contains("object 'scaled' (id 1)"), "{stderr}");
    assert!(
        stderr.contains("elliptic_cylinder") && stderr.contains("no inside"),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(!out.exists());
}

#[test]
fn sign_none_measures_an_open_quadric_and_writes_no_signs() {
    // The canonical tube x² + y² = 1, |z| ≤ 1 at the origin (the fixture's other tubes are 8
    // or more away): from its axis, 1; from (3, 0, 0), 2 to (1, 0, 0); from (0, 0, 5), √17 to
    // its rim at z = 1.
    let dir = temp_dir("distance-sign-none");
    std::fs::create_dir_all(&dir).unwrap();
    let points = dir.join("points.npy");
    write_rays::<3>(
        &points,
        &[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 5.0]],
    );
    let out = dir.join("d");
    let run = distance_into("quadrics/cylinder.gltf", &points, &out, &["--sign", "none"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let (_, distance) = read_f64(&out.join("distance.npy"));
    for (got, want) in distance.iter().zip([1.0, 2.0, 17f64.sqrt()]) {
        assert!(
            (got - want).abs() <= 8.0 * f64::EPSILON * 5.0,
            "{distance:?}"
        );
    }
    assert!(!out.join("signed_distance.npy").exists());
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert_eq!(sidecar["sign"], "none");
    assert!(sidecar["uncertain_signs"].is_null());
    let files = sidecar["files"].as_array().unwrap();
    assert_eq!(files.len(), 6);
    assert!(!files.iter().any(|f| f == "signed_distance.npy"));
}

#[test]
fn a_run_without_signs_removes_its_scene_s_earlier_signs() {
    let dir = temp_dir("distance-sign-rerun");
    std::fs::create_dir_all(&dir).unwrap();
    let points = dir.join("points.npy");
    write_rays::<3>(&points, &[[0.0, 0.0, 10.0]]);
    let out = dir.join("d");
    let scene = "quadrics/sphere_coefficients.gltf";
    assert!(distance_into(scene, &points, &out, &[]).status.success());
    assert!(out.join("signed_distance.npy").exists());
    let run = distance_into(scene, &points, &out, &["--sign", "none"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(!out.join("signed_distance.npy").exists());
    assert!(out.join("distance.npy").exists());
}
