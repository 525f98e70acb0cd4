//! Valid files that readers used to refuse (issue 29): OBJ continuations and empty or unknown
//! statements, OBJ files without faces. Expected counts are trimesh 5.2.0's reading of the
//! same fixture (`trimesh.load(..., split_objects=True, group_material=False,
//! maintain_order=True, process=False)`), not raycast's own output.

use crate::common;

use common::{assert_hit, cast_one, lines, load};

#[test]
fn obj_continuations_and_empty_usemtl_load_as_trimesh_reads_them() {
    let scene = load("obj/lenient.obj");
    // trimesh: grid 30 faces, penta 3.
    let objects: Vec<(&str, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.triangles))
        .collect();
    assert_eq!(objects, [("grid", 30), ("penta", 3)]);
    assert_eq!(scene.triangle_count(), 33);
    // One warning per kind of skipped statement, naming its first line.
    assert_eq!(
        lines(&scene),
        [
            "line 2: empty 'mtllib' statement skipped",
            "line 34: 'vc' is not an OBJ statement: skipped (and 1 more line)",
            "line 4: empty 'usemtl' statement skipped (and 1 more line)",
            "line 93: 'exporter_note' is not an OBJ statement: skipped",
        ]
    );
    // A vertex continued over two lines: v 4 \ 1 0 is (4, 1, 0); the quad (3..4, 1..2)
    // is triangles 16 and 17 of the grid.
    let s = cast_one(&scene, [3.75, 1.25, 5.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "grid", 5.0, [0.0, 0.0, 1.0], &[16]);
    let s = cast_one(&scene, [8.0, 1.0, 5.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "penta", 6.0, [0.0, 0.0, 1.0], &[1]);
}

#[test]
fn obj_without_faces_is_an_empty_scene_with_the_gltf_warning() {
    let gltf = load("bad/empty.gltf");
    let gltf_warning = "the scene holds no triangles or quadrics";
    assert!(
        lines(&gltf).iter().any(|w| w == gltf_warning),
        "{:?}",
        lines(&gltf)
    );
    // trimesh: no geometry (empty, comments only) or a PointCloud (vertices only).
    for name in ["empty", "comments_only", "vertices_only"] {
        let scene = load(&format!("obj/{name}.obj"));
        assert!(scene.objects.is_empty(), "{name}: {:?}", scene.objects);
        assert_eq!(lines(&scene), [gltf_warning], "{name}");
    }
}

/// `fixtures/usd/number_literals.usda` writes numbers as `.5`, `5.`, `-.5e1`, `5.e-1`, `-5.E-1`,
/// and attributes `inf`, `-inf`, `nan`. usd-core 26.11 reads the quad's world points as
/// (0, 4.5, -5), (1, 4.5, -5), (1, 5.5, -5), (0, 5.5, -5) (`UsdGeom.XformCache`); openusd 0.6
/// refused the layer (`Unexpected token Punctuation('.')`) before vendor/openusd's patch.
#[test]
fn usda_number_literals_read_as_usd_core_reads_them() {
    let scene = load("usd/number_literals.usda");
    assert!(lines(&scene).is_empty(), "{:?}", lines(&scene));
    let quad = &scene.objects[0];
    assert_eq!((quad.name.as_str(), quad.triangles), ("/World/quad", 2));
    let bounds = scene.object_bounds(quad);
    assert_eq!(bounds.min.to_array(), [0.0, 4.5, -5.0]);
    assert_eq!(bounds.max.to_array(), [1.0, 5.5, -5.0]);
    let s = cast_one(&scene, [0.25, 4.75, 0.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "/World/quad", 5.0, [0.0, 0.0, 1.0], &[0, 1]);
}

/// `fixtures/usd/type_names.usda` writes types with Sdf's legacy names (`Vec3d`, `Vec3f[]`,
/// `PointFloat[]`, `PointIndex[]`, `ColorFloat[]`, `Normal`, `Matrix4d`, `Vec2i`) and two
/// attributes of the unknown type `flaot`. usd-core 26.11 opens it without a diagnostic, reads the
/// legacy names as `double3`, `float3[]`, `point3f[]`, `int[]`, ... and the world points of
/// `/World/tri` as (1, 2, -5), (3, 2, -5), (1, 4, -5) and of `/World/quad` as (4, 2, -5) ..
/// (5, 3, -5), and keeps the `flaot` values unread (`Sdf.UnregisteredValue`). openusd 0.6 refused
/// the layer (`Cannot parse value for unrecognized type: Vec3d`) before vendor/openusd's patch.
#[test]
fn legacy_and_unknown_type_names_read_as_usd_core_reads_them() {
    let scene = load("usd/type_names.usda");
    assert_eq!(
        lines(&scene),
        [
            "2 attributes of value types USD does not know, values not read (as usd-core leaves \
             them): /World/tri.primvars:skel:jointWeights (flaot), /World/tri.raycast_test:typo \
             (flaot)"
        ]
    );
    let objects: Vec<(&str, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.triangles))
        .collect();
    assert_eq!(objects, [("/World/tri", 1), ("/World/quad", 2)]);
    let bounds = |name: &str| {
        let object = scene.objects.iter().find(|o| o.name == name).unwrap();
        let b = scene.object_bounds(object);
        (b.min.to_array(), b.max.to_array())
    };
    assert_eq!(bounds("/World/tri"), ([1.0, 2.0, -5.0], [3.0, 4.0, -5.0]));
    assert_eq!(bounds("/World/quad"), ([4.0, 2.0, -5.0], [5.0, 3.0, -5.0]));
    let s = cast_one(&scene, [1.5, 2.5, 0.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "/World/tri", 5.0, [0.0, 0.0, 1.0], &[0]);
    let check = common::raycast(&[
        "check",
        "--json",
        common::arg(&common::fixture("usd/type_names.usda")),
    ]);
    let stdout = String::from_utf8_lossy(&check.stdout);
    assert_eq!(check.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("\"USD_UNKNOWN_VALUE_TYPE\""), "{stdout}");
}

/// `fixtures/gltf/cube_unpadded.glb`: the cube with a 746-byte JSON chunk (not padded to a
/// multiple of 4, as older trimesh exporters wrote GLBs). trimesh 5.2.0 reads it as `cube`,
/// 12 triangles; the Khronos glTF-Validator 2.0.0-dev.3.10 reports GLB_CHUNK_LENGTH_UNALIGNED
/// (an error). Render and `info` read it with a warning; `check` keeps the validator's error.
#[test]
fn unpadded_glb_chunks_render_with_a_warning_and_fail_check() {
    let scene = load("gltf/cube_unpadded.glb");
    assert_eq!(scene.triangle_count(), 12);
    assert_eq!(
        lines(&scene),
        ["chunk 0 length 746 is not a multiple of 4: read anyway (`raycast check` reports it as an error)"]
    );
    let s = cast_one(&scene, [0.25, 0.5, 5.0], [0.0, 0.0, -1.0]);
    assert_hit(
        &s,
        "cube",
        4.0,
        [0.0, 0.0, 1.0],
        &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11],
    );
    let glb = common::fixture("gltf/cube_unpadded.glb");
    let info = common::raycast(&["info", common::arg(&glb)]);
    assert_eq!(info.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&info.stdout).contains("read anyway"));
    let check = common::raycast(&["check", "--json", common::arg(&glb)]);
    assert_eq!(check.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&check.stdout);
    assert!(
        stdout.contains("\"GLB_CHUNK_LENGTH_UNALIGNED\"") && stdout.contains("\"error\""),
        "{stdout}"
    );
}

/// The quad (0, 0, 0) .. (2, 1, 0) that every lenient PLY and OBJ fixture below draws as two
/// triangles, as trimesh 5.2.0 reads them (`trimesh.load(..., process=False)`: those four
/// vertices, 2 faces), with the one warning of its kind.
fn assert_quad(relative: &str, warning: &str) {
    let scene = load(relative);
    assert_eq!(lines(&scene), [warning], "{relative}");
    assert_eq!(scene.objects.len(), 1, "{relative}");
    assert_eq!(scene.triangle_count(), 2, "{relative}");
    let bounds = scene.object_bounds(&scene.objects[0]);
    assert_eq!(bounds.min.to_array(), [0.0, 0.0, 0.0], "{relative}");
    assert_eq!(bounds.max.to_array(), [2.0, 1.0, 0.0], "{relative}");
    let name = scene.objects[0].name.clone();
    for (x, y) in [(1.5, 0.25), (0.5, 0.75)] {
        let s = cast_one(&scene, [x, y, 3.0], [0.0, 0.0, -1.0]);
        assert_hit(&s, &name, 3.0, [0.0, 0.0, 1.0], &[0, 1]);
    }
}

/// Free-text header lines (assimp's Wuson.ply: `Created by Blender3D 247 ...`): trimesh skips
/// every header line that is not `element` or `property`.
#[test]
fn ply_free_text_header_lines_are_skipped_as_trimesh_skips_them() {
    assert_quad(
        "ply/free_text_header.ply",
        "PLY header line 3: 'Created by a hand-writte…' is not a PLY header line: skipped, as \
         trimesh skips it (and 1 more line)",
    );
}

/// Face lines with values the header does not declare (trimesh's fuze_ascii.ply, written by
/// VCG: a 9-value list after the declared properties) and a vertex list property no line holds
/// (assimp's issue623.ply): trimesh reads an ASCII body one record per line, ignoring values
/// past the declared properties and leaving out those a line lacks.
#[test]
fn ply_ascii_records_that_do_not_match_the_header_are_read_by_lines_as_trimesh() {
    assert_quad(
        "ply/extra_values.ply",
        "ASCII records do not follow the header as one stream of values (2 records end before \
         their line does (first: 'face' record 0)): read one record per line, as trimesh reads \
         them; 2 records do not fill their line exactly (first: 'face' record 0): values past \
         their properties ignored, missing values left out",
    );
    assert_quad(
        "ply/list_in_vertex.ply",
        "ASCII records do not follow the header as one stream of values (truncated: the file \
         ends in 'face' record 0 of 2): read one record per line, as trimesh reads them; 4 \
         records do not fill their line exactly (first: 'vertex' record 0): values past their \
         properties ignored, missing values left out",
    );
}

/// Exponents written with their sign before the `e` (assimp's number_formats.obj: `3.1+e2`),
/// which trimesh reads after deleting `+e` and `-e` signs, and vertex colours on only some
/// vertices (assimp's only_a_part_of_vertexcolors.obj), which trimesh drops; tobj refused both.
#[test]
fn obj_misspelt_exponents_and_partial_colours_read_as_trimesh() {
    assert_quad(
        "obj/number_formats.obj",
        "line 4: '1.0+e0' is not a number: read as 1.0e0, as trimesh reads it (and 1 more line)",
    );
    let scene = load("obj/partial_colours.obj");
    assert!(lines(&scene).is_empty(), "{:?}", lines(&scene));
    assert_eq!(scene.triangle_count(), 2);
    let s = cast_one(&scene, [1.5, 0.25, 3.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "quad", 3.0, [0.0, 0.0, 1.0], &[0]);
}
