//! PLY and STL (issue 29): the fixtures of tools/raycast_tools/fixtures/make_mesh_fixtures.py read as
//! their geometry is worked out by hand (fixtures/ply/README.md, fixtures/stl/README.md, the
//! cube of fixtures/README.md), the broken ones refused with their check codes. The same
//! fixtures are compared with trimesh's readers in tests/python/test_mesh_formats.py.

use crate::common;

use common::{assert_hit, cast_one, fixture, lines, load};
use glam::DVec3;
use raycast::check::{check_asset, Asset, CheckOptions};
use raycast::import::{self, LoadOptions};
use std::time::{Duration, Instant};

/// The fixtures' cube: vertex `i` has x = +1 for i in {1,2,5,6}, y = +1 for {2,3,6,7},
/// z = +1 for i ≥ 4, else -1.
fn cube_vertex(i: u32) -> DVec3 {
    let s = |on: bool| if on { 1.0 } else { -1.0 };
    DVec3::new(
        s([1, 2, 5, 6].contains(&i)),
        s([2, 3, 6, 7].contains(&i)),
        s(i >= 4),
    )
}

/// The cube's 12 triangles in the fixtures' order.
const CUBE: [[u32; 3]; 12] = [
    [4, 5, 6],
    [4, 6, 7],
    [0, 2, 1],
    [0, 3, 2],
    [1, 2, 6],
    [1, 6, 5],
    [0, 4, 7],
    [0, 7, 3],
    [3, 7, 6],
    [3, 6, 2],
    [0, 1, 5],
    [0, 5, 4],
];

/// The cube's faces as the quads of `cube_ascii_quads.ply`.
const QUADS: [[u32; 4]; 6] = [
    [4, 5, 6, 7],
    [0, 3, 2, 1],
    [1, 2, 6, 5],
    [0, 4, 7, 3],
    [3, 7, 6, 2],
    [0, 1, 5, 4],
];

/// Asserts that the first object's triangles are `triangles` of the cube, placed by `f`.
fn assert_triangles(relative: &str, triangles: &[[u32; 3]], f: impl Fn(DVec3) -> DVec3) {
    let scene = load(relative);
    let got = scene.mesh_triangles(&scene.objects[0]);
    let want: Vec<[DVec3; 3]> = triangles
        .iter()
        .map(|t| t.map(|i| f(cube_vertex(i))))
        .collect();
    assert_eq!(got, want, "{relative}");
}

fn assert_cube(relative: &str, f: impl Fn(DVec3) -> DVec3) {
    assert_triangles(relative, &CUBE, f);
}

#[test]
fn every_ply_encoding_reads_the_cube_in_order() {
    // Quads fan from their first corner, as the OBJ reader triangulates them.
    let fans: Vec<[u32; 3]> = QUADS
        .iter()
        .flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]])
        .collect();
    assert_triangles("ply/cube_ascii_quads.ply", &fans, |p| p);
    assert_cube("ply/cube_binary_le.ply", |p| p);
    for name in ["cube_ascii_quads", "cube_binary_le"] {
        let scene = load(&format!("ply/{name}.ply"));
        assert_eq!(scene.objects.len(), 1);
        assert_eq!(scene.objects[0].name, name);
        assert!(lines(&scene).is_empty(), "{name}: {:?}", lines(&scene));
        // fixtures/README.md: (0.5,-0.25,5) along -Z hits prim 0 at depth 4.
        let s = cast_one(&scene, [0.5, -0.25, 5.0], [0.0, 0.0, -1.0]);
        assert_hit(&s, name, 4.0, [0.0, 0.0, 1.0], &[0]);
        let s = cast_one(&scene, [0.25, -5.0, 0.5], [0.0, 1.0, 0.0]);
        assert_hit(&s, name, 4.0, [0.0, -1.0, 0.0], &[11]);
    }
}

#[test]
fn doubles_keep_the_digits_f32_cannot_hold() {
    // The cube × 0.5 + 0.1, computed in f64 as the generator wrote it.
    assert_cube("ply/cube_binary_be_double.ply", |p| p * 0.5 + 0.1);
    let scene = load("ply/cube_binary_be_double.ply");
    let s = cast_one(&scene, [0.35, 0.0, 5.0], [0.0, 0.0, -1.0]);
    // The top face is at z = 0.5 + 0.1 (in f64: 0.6).
    assert_hit(
        &s,
        "cube_binary_be_double",
        5.0 - (0.5 + 0.1),
        [0.0, 0.0, 1.0],
        &[0, 1],
    );
}

#[test]
fn polygons_fan_from_their_first_corner() {
    let scene = load("ply/polygons_binary_le.ply");
    assert_eq!(scene.objects[0].triangles, 1 + 2 + 3);
    // The pentagon 7..11 = (4,0) (6,0) (6,1) (5,2) (4,1): fans (7,8,9) (7,9,10) (7,10,11).
    let tris = scene.mesh_triangles(&scene.objects[0]);
    let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
    assert_eq!(tris[3], [p(4.0, 0.0), p(6.0, 0.0), p(6.0, 1.0)]);
    assert_eq!(tris[4], [p(4.0, 0.0), p(6.0, 1.0), p(5.0, 2.0)]);
    assert_eq!(tris[5], [p(4.0, 0.0), p(5.0, 2.0), p(4.0, 1.0)]);
    // The quad 3..6: (3,4,5) (3,5,6).
    assert_eq!(tris[2], [p(2.0, 0.0), p(3.0, 1.0), p(2.0, 1.0)]);
}

#[test]
fn points_only_ply_is_an_empty_scene_with_the_gltf_warning() {
    let scene = load("ply/points_only.ply");
    assert!(scene.objects.is_empty());
    assert_eq!(lines(&scene), [import::EMPTY_SCENE]);
    let gltf = load("bad/empty.gltf");
    assert!(lines(&gltf).iter().any(|w| w == import::EMPTY_SCENE));
}

#[test]
fn unread_triangle_strips_are_one_warning() {
    // trimesh 5.2.0 reads the face and not the strip, too: one triangle.
    let scene = load("ply/tristrips.ply");
    assert_eq!(scene.objects[0].triangles, 1);
    assert_eq!(
        lines(&scene),
        ["1 'tristrips' records not read: raycast reads the 'face' element only"]
    );
}

#[test]
fn every_stl_encoding_reads_the_cube_in_order() {
    for (name, object) in [
        ("cube_ascii", "cube"),
        ("cube_binary", "cube_binary"),
        ("cube_binary_solid", "cube_binary_solid"),
    ] {
        assert_cube(&format!("stl/{name}.stl"), |p| p);
        let scene = load(&format!("stl/{name}.stl"));
        assert_eq!(scene.objects[0].name, object);
        let s = cast_one(&scene, [5.0, 0.25, -0.5], [-1.0, 0.0, 0.0]);
        assert_hit(&s, object, 4.0, [1.0, 0.0, 0.0], &[4]);
    }
}

#[test]
fn each_ascii_solid_is_an_object() {
    let scene = load("stl/two_solids.stl");
    let objects: Vec<(&str, u32)> = scene
        .objects
        .iter()
        .map(|o| (o.name.as_str(), o.triangles))
        .collect();
    assert_eq!(objects, [("cube", 12), ("plate", 2)]);
    let s = cast_one(&scene, [0.5, -0.25, -5.0], [0.0, 0.0, 1.0]);
    assert_hit(&s, "plate", 3.0, [0.0, 0.0, 1.0], &[0]);
}

#[test]
fn broken_files_fail_with_one_line_naming_the_file_and_their_check_code() {
    let cases = [
        (
            "bad/ply_truncated.ply",
            "PLY_TRUNCATED",
            "the file ends in 'face' record 10 of 12",
        ),
        (
            "bad/ply_huge_count.ply",
            "PLY_TRUNCATED",
            "declares 1000000000 'vertex' records",
        ),
        (
            "bad/ply_index_oob.ply",
            "INDEX_OOB",
            "face 5 refers to vertex 8",
        ),
        (
            "bad/ply_bad_header.ply",
            "PLY_HEADER_ERROR",
            "unknown property type 'half'",
        ),
        (
            "bad/stl_truncated.stl",
            "STL_TRUNCATED",
            "counts 12 triangles, 684 bytes",
        ),
        (
            "bad/stl_unterminated.stl",
            "STL_TRUNCATED",
            "has no 'endsolid' line",
        ),
    ];
    for (relative, code, words) in cases {
        let path = fixture(relative);
        let started = Instant::now();
        let e = import::load(&path, &LoadOptions::default()).unwrap_err();
        assert!(started.elapsed() < Duration::from_secs(1), "{relative}");
        let line = e.to_string();
        assert!(line.starts_with(&path.display().to_string()), "{line}");
        assert!(line.contains(words) && !line.contains('\n'), "{line}");
        let report = check_asset(&Asset::file(path), &CheckOptions::default());
        let codes: Vec<&str> = report.findings.iter().map(|f| f.code.name()).collect();
        assert_eq!(codes, [code], "{relative}");
    }
}

#[test]
fn a_ply_named_obj_is_named_for_what_it_is() {
    let path = common::temp_file(
        "mesh_formats",
        "scan.obj",
        std::fs::read(fixture("ply/cube_ascii_quads.ply")).unwrap(),
    );
    let e = import::load(&path, &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("a PLY mesh (ply)"), "{e}");
    let report = check_asset(&Asset::file(path), &CheckOptions::default());
    assert_eq!(report.findings[0].code.name(), "FILE_TYPE_MISMATCH");
}

#[test]
fn bytes_load_as_files_do() {
    for relative in ["ply/cube_binary_le.ply", "stl/two_solids.stl"] {
        let bytes = std::fs::read(fixture(relative)).unwrap();
        let from_bytes = import::load_bytes(bytes, &fixture(relative), &LoadOptions::default());
        let scene = from_bytes.unwrap();
        assert_eq!(scene.triangle_count(), load(relative).triangle_count());
    }
}

#[test]
fn ply_polygons_triangulate_as_the_same_obj_faces_do() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 3 1 0\nv 2 1 0\n\
               v 4 0 0\nv 6 0 0\nv 6 1 0\nv 5 2 0\nv 4 1 0\n\
               f 1 2 3\nf 4 5 6 7\nf 8 9 10 11 12\n";
    let options = LoadOptions::default();
    let obj = import::load_bytes(obj.into(), std::path::Path::new("p.obj"), &options).unwrap();
    let ply = load("ply/polygons_binary_le.ply");
    assert_eq!(
        ply.mesh_triangles(&ply.objects[0]),
        obj.mesh_triangles(&obj.objects[0])
    );
}

/// An ASCII solid of `n` facets: a strip of triangles along x.
fn strip_solid(name: &str, n: usize) -> String {
    let mut text = format!("solid {name}\n");
    for i in 0..n {
        let x = i as f64;
        text += &format!(
            "facet normal 0 0 1\nouter loop\nvertex {x} 0 0\nvertex {} 0 0\nvertex {x} 1 0\n\
             endloop\nendfacet\n",
            x + 1.0
        );
    }
    text + "endsolid\n"
}

#[test]
fn equal_solids_follow_the_instancing_rule() {
    let options = LoadOptions::default();
    let load_text = |text: String| {
        import::load_bytes(text.into_bytes(), std::path::Path::new("s.stl"), &options).unwrap()
    };
    // Two equal solids of 16 triangles: stored once, drawn twice, one id each.
    let scene = load_text(strip_solid("a", 16) + &strip_solid("b", 16));
    assert_eq!((scene.objects.len(), scene.triangle_count()), (2, 32));
    assert_eq!(scene.stored_triangle_count(), 16);
    // Below the rule's 16 triangles they are copied into the world mesh.
    let scene = load_text(strip_solid("a", 15) + &strip_solid("b", 15));
    assert_eq!(scene.stored_triangle_count(), 30);
}
