//! Valid files that readers used to refuse (issue 29): OBJ continuations and empty or unknown
//! statements, OBJ files without faces. Expected counts are trimesh 5.2.0's reading of the
//! same fixture (`trimesh.load(..., split_objects=True, group_material=False,
//! maintain_order=True, process=False)`), not raycast's own output.

mod common;

use common::{assert_hit, cast_one, load};

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
        scene.warnings,
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
        gltf.warnings.iter().any(|w| w == gltf_warning),
        "{:?}",
        gltf.warnings
    );
    // trimesh: no geometry (empty, comments only) or a PointCloud (vertices only).
    for name in ["empty", "comments_only", "vertices_only"] {
        let scene = load(&format!("obj/{name}.obj"));
        assert!(scene.objects.is_empty(), "{name}: {:?}", scene.objects);
        assert_eq!(scene.warnings, [gltf_warning], "{name}");
    }
}
