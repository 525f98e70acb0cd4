//! `raycast check` rules that disagreed with the Khronos glTF-Validator (issue 29), on the
//! fixtures of `fixtures/check/` (written by `fixtures/check/make.py`). Each expected set of
//! error codes is the validator's (2.0.0-dev.3.10, tools/npm), recorded in
//! `fixtures/check/README.md`.

use raycast::check::{check_asset, Asset, AssetReport, CheckOptions, Severity};
use raycast::import::{self, LoadOptions};
use std::collections::BTreeSet;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/check")
        .join(name)
}

fn report(name: &str) -> AssetReport {
    check_asset(&Asset::file(fixture(name)), &CheckOptions::default())
}

fn codes(report: &AssetReport, severity: Severity) -> BTreeSet<&str> {
    report
        .findings
        .iter()
        .filter(|f| f.severity == severity)
        .map(|f| f.code.name())
        .collect()
}

#[test]
fn errors_agree_with_the_validator() {
    let cases: [(&str, &[&str]); 18] = [
        // One POSITION accessor on a view without byteStride, read by two primitives.
        ("one_accessor_two_primitives.gltf", &[]),
        // Two accessors on that view.
        (
            "two_accessors_one_view.gltf",
            &["MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE"],
        ),
        // Weights that add up to 1 over three WEIGHTS_n sets, never in WEIGHTS_0 alone.
        ("weights_three_sets.gltf", &[]),
        // A negative weight: an error of its own, and left out of the sum (1 and -0.25 add up
        // to 1).
        (
            "weights_negative_left_out.gltf",
            &["ACCESSOR_WEIGHTS_NEGATIVE"],
        ),
        // The same with vertex 2's weights adding up to 0.6.
        (
            "weights_three_sets_short.gltf",
            &["ACCESSOR_WEIGHTS_NON_NORMALIZED"],
        ),
        // Materials (the validator's material.dart): a `normalTexture.scale` that is a
        // string; a texture info without `index`.
        ("normal_scale_string.gltf", &["TYPE_MISMATCH"]),
        ("texture_info_without_index.gltf", &["UNDEFINED_PROPERTY"]),
        // A normalTexture on a primitive without NORMAL and TANGENT: a viewer generates the
        // tangents (MESH_PRIMITIVE_GENERATED_TANGENT_SPACE, a warning).
        ("normal_texture_without_tangents.gltf", &[]),
        // A clearcoat normal map without a normalTexture to generate tangents from.
        (
            "clearcoat_normal_without_tangents.gltf",
            &["MESH_PRIMITIVE_NO_TANGENT_SPACE"],
        ),
        // Every index the UNSIGNED_SHORT restart value, past the last vertex too.
        (
            "all_indices_restart.gltf",
            &["ACCESSOR_INDEX_OOB", "ACCESSOR_INDEX_PRIMITIVE_RESTART"],
        ),
        // `"scene": "hello"`.
        ("scene_string.gltf", &["TYPE_MISMATCH"]),
        // Shader techniques required: appearance only, the geometry is drawn.
        ("techniques_webgl_required.gltf", &[]),
        // The codes check missed on the public corpora (reports/corpus.md), one file each.
        ("primitives_object.gltf", &["TYPE_MISMATCH"]),
        ("name_number.gltf", &["TYPE_MISMATCH"]),
        ("texture_index_negative.gltf", &["INVALID_INDEX"]),
        (
            "texcoord_1_only.gltf",
            &[
                "MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY",
                "MESH_PRIMITIVE_TOO_FEW_TEXCOORDS",
            ],
        ),
        (
            "indices_without_attributes.gltf",
            &[
                "ACCESSOR_INDEX_OOB",
                "BUFFER_VIEW_TARGET_OVERRIDE",
                "EMPTY_ENTITY",
            ],
        ),
        (
            "keyframes_on_vertex_view.gltf",
            &["BUFFER_VIEW_TARGET_OVERRIDE"],
        ),
    ];
    for (name, validator) in cases {
        let report = report(name);
        let errors = codes(&report, Severity::Error);
        let expected: BTreeSet<&str> = validator.iter().copied().collect();
        assert_eq!(errors, expected, "{name}: {:?}", report.findings);
    }
}

/// A structural property of the wrong JSON type (primitives an object) drops geometry if read
/// as absent: render refuses the file, naming the property, as check reports it.
#[test]
fn a_structural_type_mismatch_stops_a_render() {
    let Err(err) = import::load(&fixture("primitives_object.gltf"), &LoadOptions::default()) else {
        panic!("primitives_object.gltf was loaded");
    };
    let message = err.to_string();
    assert!(
        message.contains("/meshes/0/primitives") && message.contains("expected an array"),
        "{message}"
    );
}

#[test]
fn required_shader_techniques_do_not_stop_a_render() {
    let scene = import::load(
        &fixture("techniques_webgl_required.gltf"),
        &LoadOptions::default(),
    )
    .expect("loads");
    assert_eq!(scene.objects.len(), 1);
}

#[test]
fn a_generated_tangent_space_is_a_warning() {
    let report = report("normal_texture_without_tangents.gltf");
    let warnings = codes(&report, Severity::Warning);
    assert!(
        warnings.contains("MESH_PRIMITIVE_GENERATED_TANGENT_SPACE"),
        "{:?}",
        report.findings
    );
}

#[test]
fn a_flat_mesh_has_no_inverted_normals() {
    // The cube flattened by a rank-2 projective matrix: usd-core reads it (a valid stage);
    // its signed volume, -3.8e-15, is zero up to rounding.
    let path = fixture("flat_projective_cube.usda");
    let scene = import::load(&path, &LoadOptions::default()).expect("loads");
    let triangles = scene.mesh_triangles(&scene.objects[0]);
    let (volume, zero_below) = raycast::check::geometry::signed_volume_bound(&triangles);
    eprintln!("flat cube: volume {volume:e}, zero below {zero_below:e}");
    assert!(
        volume < 0.0 && -volume <= zero_below,
        "{volume:e} {zero_below:e}"
    );
    let report = report("flat_projective_cube.usda");
    assert!(
        !report
            .findings
            .iter()
            .any(|f| f.code.name() == "INVERTED_NORMALS"),
        "{:?}",
        report.findings
    );
    assert!(codes(&report, Severity::Error).is_empty());
}
