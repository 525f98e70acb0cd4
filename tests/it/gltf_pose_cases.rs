//! glTF posing cases three.js cannot be the reference for, with values worked out by hand:
//! two skin influence sets (three.js reads JOINTS_0 only), and what bad skin data and bad
//! `--time` / `--animation` requests give (one-line errors naming the file, never a panic).

use crate::common;
use common::*;
use glam::DVec3;
use raycast::import::{self, LoadOptions};
use serde_json::{json, Value};

/// A skinned triangle (corners (1,0,0), (0,1,0), (0,0,1)) on five joints translated by
/// (1,0,0) ... (5,0,0), no inverse bind matrices; JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1 as
/// given (u8 joints, f32 weights, the same for every vertex); `patch` edits the JSON.
fn skinned_triangle(
    test: &str,
    sets: &[([u8; 4], [f32; 4])],
    patch: impl Fn(&mut Value),
) -> std::path::PathBuf {
    let mut bin = Vec::new();
    for p in [[1f32, 0., 0.], [0., 1., 0.], [0., 0., 1.]] {
        p.iter().for_each(|c| bin.extend(c.to_le_bytes()));
    }
    let mut views = vec![json!({"buffer": 0, "byteOffset": 0, "byteLength": 36})];
    let mut accessors = vec![
        json!({"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [0, 0, 0], "max": [1, 1, 1]}),
    ];
    let mut attributes = json!({"POSITION": 0});
    for (set, (joints, weights)) in sets.iter().enumerate() {
        let start = bin.len();
        for _ in 0..3 {
            bin.extend(joints);
        }
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": 12}));
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5121, "count": 3, "type": "VEC4"}));
        attributes[format!("JOINTS_{set}")] = json!(accessors.len() - 1);
        let start = bin.len();
        for _ in 0..3 {
            weights.iter().for_each(|w| bin.extend(w.to_le_bytes()));
        }
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": 48}));
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126, "count": 3, "type": "VEC4"}));
        attributes[format!("WEIGHTS_{set}")] = json!(accessors.len() - 1);
    }
    let mut nodes: Vec<Value> = (1..=5)
        .map(|k| json!({"name": format!("J{k}"), "translation": [k, 0, 0]}))
        .collect();
    nodes.push(json!({"name": "skinned", "mesh": 0, "skin": 0, "translation": [100, 100, 100]}));
    let mut gltf = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4, 5]}],
        "nodes": nodes,
        "skins": [{"joints": [0, 1, 2, 3, 4]}],
        "meshes": [{"primitives": [{"attributes": attributes}]}],
        "buffers": [{"byteLength": bin.len(), "uri": "skin.bin"}],
        "bufferViews": views,
        "accessors": accessors,
    });
    patch(&mut gltf);
    let path = temp_file(test, "skin.bin", &bin);
    let gltf_path = path.with_file_name("skin.gltf");
    std::fs::write(&gltf_path, gltf.to_string()).unwrap();
    gltf_path
}

fn corners(path: &std::path::Path) -> Vec<DVec3> {
    let scene = import::load(path, &LoadOptions::default()).unwrap();
    scene
        .mesh_triangles(&scene.objects[0])
        .into_iter()
        .flatten()
        .collect()
}

#[test]
fn two_influence_sets_are_summed() {
    // 1/8 · 1 + 1/4 · 2 + 1/8 · 3 + 1/4 · 4 from set 0, 1/4 · 5 from set 1: every corner moves
    // by (3.25, 0, 0); the mesh node's own translation (100, 100, 100) is ignored.
    let sets = [
        ([0, 1, 2, 3], [0.125, 0.25, 0.125, 0.25]),
        ([4, 0, 0, 0], [0.25, 0.0, 0.0, 0.0]),
    ];
    let path = skinned_triangle("two_sets", &sets, |_| {});
    let expected = [
        DVec3::new(4.25, 0.0, 0.0),
        DVec3::new(3.25, 1.0, 0.0),
        DVec3::new(3.25, 0.0, 1.0),
    ];
    assert_eq!(corners(&path), expected);
    // With set 0 alone the weights sum to 3/4: the corners are 3/4 · v + (2, 0, 0).
    let path = skinned_triangle("one_set", &sets[..1], |_| {});
    let expected = [
        DVec3::new(2.75, 0.0, 0.0),
        DVec3::new(2.0, 0.75, 0.0),
        DVec3::new(2.0, 0.0, 0.75),
    ];
    assert_eq!(corners(&path), expected);
}

#[test]
fn bad_skin_data_is_a_one_line_error() {
    let sets = [([0, 1, 7, 3], [0.25, 0.25, 0.25, 0.25])];
    let path = skinned_triangle("joint_oob", &sets, |_| {});
    let err = import::load(&path, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("skin.gltf") && err.contains("JOINTS_0") && err.contains("joint 7"),
        "{err}"
    );
    assert!(!err.contains('\n'), "{err}");
    let sets = [([0, 1, 2, 3], [0.25, 0.25, 0.25, 0.25])];
    let no_weights = skinned_triangle("no_weights", &sets, |g| {
        g["meshes"][0]["primitives"][0]["attributes"]
            .as_object_mut()
            .unwrap()
            .remove("WEIGHTS_0");
    });
    let err = import::load(&no_weights, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("JOINTS_0 without WEIGHTS_0"), "{err}");
    let bad_joint = skinned_triangle("bad_joint", &sets, |g| {
        g["skins"][0]["joints"][2] = json!(99)
    });
    let err = import::load(&bad_joint, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("skin.gltf"), "{err}");
}

#[test]
fn time_and_animation_on_the_command_line() {
    let scene = fixture("posed/SimpleSkin.gltf");
    let out = temp_dir("pose_time");
    // Renders the scene with `extra` options; returns the sidecar.
    let render = |extra: &[&str]| -> Value {
        let mut args = vec![
            arg(&scene),
            "--format",
            "npy",
            "--width",
            "8",
            "--height",
            "8",
        ];
        args.extend(extra);
        args.extend(["--out", arg(&out), "--quiet"]);
        raycast_ok(&args);
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap()
    };
    let sidecar = render(&["--time", "1.25"]);
    assert_eq!(sidecar["pose"]["time"], json!(1.25), "{}", sidecar["pose"]);
    assert_eq!(sidecar["pose"]["animations"][0]["applied"], json!(true));
    assert_eq!(sidecar["pose"]["skins"], json!(1));
    // Without --time the sidecar says no animation was applied, and a warning says so once.
    let sidecar = render(&[]);
    assert_eq!(sidecar["pose"]["time"], Value::Null);
    let warnings = sidecar["warnings"].as_array().unwrap();
    assert_eq!(
        warnings
            .iter()
            .filter(|w| w.as_str().unwrap().contains("without --time"))
            .count(),
        1,
        "{warnings:?}"
    );
    // --animation needs --time; an unknown one lists the file's; a time must be finite.
    let r = raycast(&[arg(&scene), "--animation", "0", "--out", arg(&out)]);
    assert_eq!(r.status.code(), Some(2));
    let r = raycast(&[
        arg(&scene),
        "--time",
        "1",
        "--animation",
        "walk",
        "--out",
        arg(&out),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("SimpleSkin.gltf") && err.contains("no animation 'walk'"),
        "{err}"
    );
    let r = raycast(&[arg(&scene), "--time", "nan", "--out", arg(&out)]);
    assert_eq!(r.status.code(), Some(2));
    // info lists the animation.
    let r = raycast_ok(&["info", arg(&scene)]);
    let text = String::from_utf8_lossy(&r.stdout);
    assert!(
        text.contains("1 animations, 1 skins") && text.contains("0 .. 5.5 s, 1 channels"),
        "{text}"
    );
    std::fs::remove_dir_all(&out).ok();
}
