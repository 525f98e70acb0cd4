//! Importer tests against the analytic answers documented in fixtures/README.md.

use crate::common;
use common::*;
use raycast::import::{self, LoadOptions};

const Z: [f64; 3] = [0.0, 0.0, 1.0];
const DOWN: [f64; 3] = [0.0, 0.0, -1.0];

#[test]
fn cube_in_all_three_buffer_forms() {
    for file in ["gltf/cube.gltf", "gltf/cube.glb", "gltf/cube_embedded.gltf"] {
        let scene = load(file);
        assert_eq!(scene.triangle_count(), 12, "{file}");
        assert_hit(
            &cast_one(&scene, [0.5, -0.25, 5.0], DOWN),
            "cube",
            4.0,
            Z,
            &[0],
        );
        assert_hit(
            &cast_one(&scene, [-0.5, 0.25, 5.0], DOWN),
            "cube",
            4.0,
            Z,
            &[1],
        );
        assert_hit(
            &cast_one(&scene, [0.0, 0.0, 5.0], DOWN),
            "cube",
            4.0,
            Z,
            &[0, 1],
        );
        assert_hit(
            &cast_one(&scene, [5.0, 0.25, -0.5], [-1.0, 0.0, 0.0]),
            "cube",
            4.0,
            [1.0, 0.0, 0.0],
            &[4],
        );
        assert_hit(
            &cast_one(&scene, [0.25, -5.0, 0.5], [0.0, 1.0, 0.0]),
            "cube",
            4.0,
            [0.0, -1.0, 0.0],
            &[11],
        );
        // From inside, direction not unit: depth is |hit - origin|, the normal is not flipped.
        let inside = cast_one(&scene, [0.25, 0.5, 0.0], [0.0, 0.0, 2.0]);
        assert_hit(&inside, "cube", 1.0, Z, &[1]);
        assert_eq!(inside.position.to_array(), [0.25, 0.5, 1.0]);
        assert_miss(&cast_one(&scene, [2.0, 0.0, 5.0], DOWN));
        assert_miss(&cast_one(&scene, [0.5, -0.25, 5.0], Z));
    }
}

#[test]
fn plane_is_hit_from_both_sides_with_its_front_normal() {
    let scene = load("gltf/plane.gltf");
    assert_hit(
        &cast_one(&scene, [0.5, -0.25, 3.0], DOWN),
        "plane",
        3.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [0.0, 0.5, -2.0], Z),
        "plane",
        2.0,
        Z,
        &[1],
    );
    assert_miss(&cast_one(&scene, [2.0, 0.0, 3.0], DOWN));
}

#[test]
fn triangle_list_strip_and_fan_and_skipped_points_lines() {
    let scene = load("gltf/modes.gltf");
    assert_eq!(scene.objects.len(), 3);
    assert_eq!(scene.triangle_count(), 8);
    assert!(
        lines(&scene).iter().any(|w| w.contains("Points")),
        "{:?}",
        lines(&scene)
    );
    let cases: [([f64; 2], &str, u32); 9] = [
        ([-3.5, 0.25], "tris", 1),
        ([-2.5, -0.25], "tris", 0),
        ([-0.5, -0.25], "strip", 0),
        ([0.5, 0.25], "strip", 1),
        ([3.0, -0.5], "fan", 0),
        ([3.5, 0.0], "fan", 1),
        ([3.0, 0.5], "fan", 2),
        ([2.5, 0.0], "fan", 3),
        ([-3.5, 0.25], "tris", 1),
    ];
    for ([x, y], object, prim) in cases {
        assert_hit(
            &cast_one(&scene, [x, y, 5.0], DOWN),
            object,
            5.0,
            Z,
            &[prim],
        );
    }
    for [x, y] in [[0.5, 2.5], [0.5, -3.5], [-1.5, 0.0]] {
        assert_miss(&cast_one(&scene, [x, y, 5.0], DOWN));
    }
}

#[test]
fn sparse_accessor_moves_vertices() {
    let scene = load("gltf/sparse.gltf");
    let n = [-1.0 / 5f64.sqrt(), 0.0, 2.0 / 5f64.sqrt()];
    assert_hit(
        &cast_one(&scene, [0.5, -0.25, 5.0], DOWN),
        "sparse",
        4.25,
        n,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [-0.5, 0.25, 5.0], DOWN),
        "sparse",
        4.75,
        n,
        &[1],
    );
}

#[test]
fn quantized_positions_are_normalized() {
    let scene = load("gltf/quantized.gltf");
    assert_hit(
        &cast_one(&scene, [0.5, -0.25, 5.0], DOWN),
        "short",
        5.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [-0.5, 0.25, 5.0], DOWN),
        "short",
        5.0,
        Z,
        &[1],
    );
    assert_hit(
        &cast_one(&scene, [3.5, -0.25, 5.0], DOWN),
        "ubyte",
        5.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [2.5, 0.25, 5.0], DOWN),
        "ubyte",
        5.0,
        Z,
        &[1],
    );
    assert_miss(&cast_one(&scene, [1.5, 0.0, 5.0], DOWN));
}

#[test]
fn instances_compose_trs_matrix_hierarchy_and_mirroring() {
    let scene = load("gltf/instances.gltf");
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c", "d", "mirror"]);
    let x = [1.0, 0.0, 0.0];
    assert_hit(
        &cast_one(&scene, [3.25, -0.125, 5.0], DOWN),
        "a",
        4.5,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [-2.75, -0.125, 5.0], DOWN),
        "b",
        4.5,
        Z,
        &[6],
    );
    assert_hit(
        &cast_one(&scene, [-6.0, 0.125, 0.25], x),
        "b",
        2.5,
        [-1.0, 0.0, 0.0],
        &[3],
    );
    assert_hit(
        &cast_one(&scene, [0.25, 3.25, -5.0], Z),
        "c",
        4.5,
        DOWN,
        &[2],
    );
    assert_hit(
        &cast_one(&scene, [0.25, 3.25, 5.0], DOWN),
        "d",
        2.5,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [0.25, 10.0, 2.375], [0.0, -1.0, 0.0]),
        "d",
        6.0,
        [0.0, 1.0, 0.0],
        &[8],
    );
    assert_hit(
        &cast_one(&scene, [0.25, -3.125, 5.0], DOWN),
        "mirror",
        4.5,
        Z,
        &[1],
    );
    assert_hit(
        &cast_one(&scene, [5.0, -3.125, 0.25], [-1.0, 0.0, 0.0]),
        "mirror",
        4.5,
        x,
        &[6],
    );
    assert_miss(&cast_one(&scene, [0.0, 1.5, 5.0], DOWN));
}

#[test]
fn scene_choice_by_default_index_and_name() {
    let default = load("gltf/scenes.gltf");
    assert_hit(
        &cast_one(&default, [0.5, -0.25, 5.0], DOWN),
        "second_quad",
        7.0,
        Z,
        &[0],
    );
    for choice in ["first", "0"] {
        let options = LoadOptions {
            scene: Some(choice.into()),
            ..Default::default()
        };
        let scene = import::load(&fixture("gltf/scenes.gltf"), &options).unwrap();
        assert_hit(
            &cast_one(&scene, [0.5, -0.25, 5.0], DOWN),
            "first_quad",
            5.0,
            Z,
            &[0],
        );
    }
    let options = LoadOptions {
        scene: Some("third".into()),
        ..Default::default()
    };
    let err = import::load(&fixture("gltf/scenes.gltf"), &options).unwrap_err();
    assert!(err.to_string().contains("no scene 'third'"), "{err}");
}

#[test]
fn far_from_origin_keeps_f64_placement() {
    let scene = load("gltf/far.gltf");
    let s = cast_one(&scene, [10000000.75, -3000000.75, 12345683.125], DOWN);
    assert_hit(&s, "cube", 4.0, Z, &[0]);
    assert_eq!(
        s.position.to_array(),
        [10000000.75, -3000000.75, 12345679.125]
    );
}

#[test]
fn obj_objects_groups_and_negative_indices() {
    let scene = load("obj/two_objects.obj");
    assert_hit(
        &cast_one(&scene, [0.5, -0.25, 5.0], DOWN),
        "quad",
        5.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [-0.5, 0.25, 5.0], DOWN),
        "quad",
        5.0,
        Z,
        &[1],
    );
    assert_hit(
        &cast_one(&scene, [3.5, -0.5, 5.0], DOWN),
        "penta",
        6.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&scene, [3.0, 0.0, 5.0], DOWN),
        "penta",
        6.0,
        Z,
        &[1],
    );
    assert_hit(
        &cast_one(&scene, [2.25, 0.25, 5.0], DOWN),
        "penta",
        6.0,
        Z,
        &[2],
    );
    assert_miss(&cast_one(&scene, [3.5, 1.25, 5.0], DOWN));
    let groups = load("obj/groups.obj");
    assert_hit(
        &cast_one(&groups, [-1.5, -0.5, 5.0], DOWN),
        "left",
        5.0,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&groups, [-2.5, 0.5, 5.0], DOWN),
        "left",
        5.0,
        Z,
        &[1],
    );
    assert_hit(
        &cast_one(&groups, [2.5, -0.75, 5.0], DOWN),
        "right",
        4.5,
        Z,
        &[0],
    );
    assert_hit(
        &cast_one(&groups, [1.5, 0.5, 5.0], DOWN),
        "right",
        4.5,
        Z,
        &[1],
    );
    assert_miss(&cast_one(&groups, [0.0, 0.0, 5.0], DOWN));
}

#[test]
fn cameras_are_read_with_their_projection() {
    use raycast::camera::Projection;
    let scene = load("gltf/cameras.gltf");
    assert_eq!(scene.cameras.len(), 2);
    let persp = &scene.cameras[0];
    assert_eq!(persp.name, "persp");
    assert_eq!(persp.aspect_ratio, Some(2.0));
    assert!(
        matches!(persp.projection, Projection::Perspective { yfov } if (yfov - 0.8).abs() < 1e-7)
    );
    let ortho = &scene.cameras[1];
    assert_eq!(ortho.projection, Projection::Orthographic { ymag: 1.0 });
    assert!((ortho.forward() - glam::DVec3::NEG_X).length() < 1e-12);
}

#[test]
fn real_assets_load_with_their_triangle_counts() {
    // Counts as trimesh 5.2.0 reports them (len(scene.dump(concatenate=True).faces)).
    for (file, triangles) in [
        ("assets/Box.glb", 12),
        ("assets/TriangleWithoutIndices.gltf", 1),
        ("assets/DamagedHelmet.glb", 15452),
        ("assets/chr_knight.glb", 1460),
        ("assets/ShapeCollection.glb", 3542),
        ("assets/many-cubes.gltf", 6012),
        ("assets/stanford-bunny.obj", 69451),
    ] {
        assert_eq!(load(file).triangle_count(), triangles, "{file}");
    }
}

/// The glTF files of the Khronos glTF-Validator suite (`fixtures/gltf-validator/`), each with
/// the validator's verdict: the codes and JSON pointers of its errors.
fn validator_suite() -> Vec<(std::path::PathBuf, Vec<(String, String)>)> {
    let mut files = Vec::new();
    let mut folders = vec![fixture("gltf-validator")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            let name = path.to_string_lossy();
            if path.is_dir() {
                folders.push(path);
            } else if name.ends_with(".gltf") || name.ends_with(".glb") {
                let report = std::fs::read_to_string(format!("{name}.report.json")).unwrap();
                let report: serde_json::Value = serde_json::from_str(&report).unwrap();
                let errors = report["issues"]["messages"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|m| m["severity"] == 0)
                    .map(|m| {
                        let text = |key: &str| m[key].as_str().unwrap_or("").to_string();
                        (text("code"), text("pointer"))
                    })
                    .collect();
                files.push((path, errors));
            }
        }
    }
    files.sort();
    files
}

/// The render's importer (not `check`) against the validator: every file it finds no error
/// in loads, and every file it calls broken as a whole (a reference to an object that does
/// not exist, anywhere, or a bad `asset.version`) is refused with an error that names the
/// file and one of the validator's pointers.
#[test]
fn importer_agrees_with_the_validator_on_clean_and_dangling_documents() {
    let fatal = |(code, pointer): &(String, String)| {
        code == "UNRESOLVED_REFERENCE"
            || code == "UNKNOWN_ASSET_MAJOR_VERSION"
            || pointer.starts_with("/asset")
    };
    let (mut clean, mut refused) = (0, 0);
    for (path, errors) in validator_suite() {
        let loaded = import::load(&path, &LoadOptions::default());
        if errors.is_empty() {
            assert!(
                loaded.is_ok(),
                "{}: {}",
                path.display(),
                loaded.unwrap_err()
            );
            clean += 1;
        } else if errors.iter().any(fatal) {
            let e = loaded
                .err()
                .unwrap_or_else(|| panic!("{} loads", path.display()));
            let line = e.to_string();
            assert!(line.starts_with(&path.display().to_string()), "{line}");
            assert!(
                // Our pointer is the validator's, or (a missing property) below it.
                errors.iter().any(|(_, p)| line.contains(&format!(": {p}"))),
                "{line}: none of {errors:?}"
            );
            refused += 1;
        }
    }
    assert_eq!(clean, 73, "validator-clean files in the suite");
    assert!(refused >= 30, "only {refused} broken documents");
}
