//! Compressed and instanced glTF (fixtures/compressed, made by tools/make_compressed_fixtures.sh)
//! against the reference decodes next to them: `*.plain.glb`, written by glTF-Transform after the
//! official decoders (draco3dgltf, meshoptimizer) read the same file. Our Draco and meshopt
//! decoders must give the same positions and triangles, bit for bit.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::scene::Scene;

/// Each object's name and world triangles, in object and triangle order.
fn world_triangles(scene: &Scene) -> Vec<(String, Vec<[DVec3; 3]>)> {
    scene
        .objects
        .iter()
        .map(|o| {
            let triangles = scene.mesh_triangles(o);
            (o.name.clone(), triangles)
        })
        .collect()
}

/// Largest distance between corresponding corners of two scenes with the same objects
/// (same names unless `names` is false) and triangle counts.
fn largest_difference(ours: &Scene, reference: &Scene, names: bool) -> f64 {
    let (a, b) = (world_triangles(ours), world_triangles(reference));
    assert_eq!(a.len(), b.len(), "object counts differ");
    let mut largest = 0.0f64;
    for ((name_a, tris_a), (name_b, tris_b)) in a.iter().zip(&b) {
        if names {
            assert_eq!(name_a, name_b);
        }
        assert_eq!(
            tris_a.len(),
            tris_b.len(),
            "{name_a}: triangle counts differ"
        );
        for (ta, tb) in tris_a.iter().zip(tris_b) {
            for (va, vb) in ta.iter().zip(tb) {
                largest = largest.max((*va - *vb).length());
            }
        }
    }
    largest
}

/// Like [`largest_difference`] for scenes whose objects come in another order and may be
/// placed by another but equivalent transform (a mirrored cube is the same cube with its
/// corners in another order): each object of `ours` is matched with the reference object
/// whose centroid is nearest, and the two are compared as point sets (Hausdorff distance of
/// their corners).
fn largest_difference_unordered(ours: &Scene, reference: &Scene) -> f64 {
    let corners = |scene: &Scene| -> Vec<Vec<DVec3>> {
        world_triangles(scene)
            .into_iter()
            .map(|(_, t)| t.into_iter().flatten().collect())
            .collect()
    };
    let (a, b) = (corners(ours), corners(reference));
    assert_eq!(a.len(), b.len(), "object counts differ");
    let centroid = |p: &[DVec3]| p.iter().sum::<DVec3>() / p.len() as f64;
    let one_way = |x: &[DVec3], y: &[DVec3]| {
        x.iter()
            .map(|p| {
                y.iter()
                    .map(|q| (*p - *q).length())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0f64, f64::max)
    };
    a.iter()
        .map(|pa| {
            let c = centroid(pa);
            let pb = b
                .iter()
                .min_by(|x, y| {
                    (centroid(x) - c)
                        .length()
                        .total_cmp(&(centroid(y) - c).length())
                })
                .unwrap();
            one_way(pa, pb).max(one_way(pb, pa))
        })
        .fold(0.0f64, f64::max)
}

fn diagonal(scene: &Scene) -> f64 {
    let b = scene.world_bounds();
    (b.max - b.min).length()
}

/// Compressed fixtures whose reference decode must match exactly: Draco and meshopt decode to
/// the very values the official decoders give.
const EXACT: [(&str, &str); 13] = [
    ("helmet.draco-seq", "helmet.draco-seq"),
    ("helmet.draco-eb", "helmet.draco-eb"),
    ("knight.draco-seq", "knight.draco-seq"),
    ("knight.draco-eb", "knight.draco-eb"),
    ("knight.draco-optional", "knight.draco-seq"),
    ("shapes.draco-seq", "shapes.draco-seq"),
    ("shapes.draco-eb", "shapes.draco-eb"),
    ("helmet.meshopt", "helmet.meshopt"),
    ("helmet.meshopt-khr", "helmet.meshopt-khr"),
    ("knight.meshopt", "knight.meshopt"),
    ("knight.meshopt-fallback", "knight.meshopt-fallback"),
    ("shapes.meshopt", "shapes.meshopt"),
    ("cubes.instanced-meshopt", "cubes.instanced-meshopt"),
];

#[test]
fn decoded_geometry_equals_the_official_decoders() {
    for (file, reference) in EXACT {
        let ours = load(&format!("compressed/{file}.glb"));
        let plain = load(&format!("compressed/{reference}.plain.glb"));
        assert!(ours.triangle_count() > 0, "{file}");
        assert_eq!(ours.triangle_count(), plain.triangle_count(), "{file}");
        assert_eq!(ours.anchor, plain.anchor, "{file}");
        assert_eq!(largest_difference(&ours, &plain, true), 0.0, "{file}");
    }
}

#[test]
fn quantized_positions_agree_with_gltf_transform_dequantized() {
    // The reference holds f32 positions that glTF-Transform dequantized with the node
    // transform folded in; we dequantize in f64 and store f32 relative to the scene anchor.
    // Both round to f32 once or twice: agreement to 1e-6 of the scene size.
    for name in ["helmet", "shapes"] {
        let ours = load(&format!("compressed/{name}.quantized.glb"));
        let plain = load(&format!("compressed/{name}.quantized.plain.glb"));
        let d = largest_difference(&ours, &plain, true);
        println!(
            "{name}.quantized: largest corner difference {d:.3e} (scene diagonal {:.3})",
            diagonal(&plain)
        );
        assert!(d <= 1e-6 * diagonal(&plain), "{name}: {d}");
    }
}

#[test]
fn gpu_instances_become_named_objects_placed_like_the_original_nodes() {
    for file in ["cubes.instanced", "cubes.instanced-meshopt"] {
        let scene = load(&format!("compressed/{file}.glb"));
        assert_eq!(scene.objects.len(), 501, "{file}");
        assert_eq!(scene.objects[0].name, "node0[0]", "{file}");
        assert_eq!(scene.objects[500].name, "node0[500]", "{file}");
        for (k, o) in scene.objects.iter().enumerate() {
            assert_eq!(
                o.source,
                format!("/nodes/0/extensions/EXT_mesh_gpu_instancing/{k}")
            );
        }
        assert_eq!(
            scene.decoded.last().map(String::as_str),
            Some("EXT_mesh_gpu_instancing: 501 instances on 1 nodes"),
            "{file}"
        );
        // The same cubes as 501 separate nodes (gltfpack without instancing), in another
        // order. Instance transforms are quantized (rotations as 16-bit normalized integers,
        // or 12-bit through the quaternion filter), so placements agree to a few 1e-5 of the
        // scene size, not exactly.
        let nodes = load("compressed/cubes.nodes.glb");
        let d = largest_difference_unordered(&scene, &nodes);
        println!(
            "{file}: largest corner difference {d:.3e} (scene diagonal {:.3})",
            diagonal(&nodes)
        );
        assert!(d <= 1e-4 * diagonal(&nodes), "{file}: {d}");
    }
}

#[test]
fn info_says_what_was_decoded() {
    let cases = [
        (
            "helmet.draco-eb",
            "KHR_draco_mesh_compression: 1 primitives (0 sequential, 1 edgebreaker)",
        ),
        (
            "helmet.draco-seq",
            "KHR_draco_mesh_compression: 1 primitives (1 sequential, 0 edgebreaker)",
        ),
        ("helmet.meshopt", "EXT_meshopt_compression: 3 buffer views"),
        (
            "helmet.meshopt-khr",
            "KHR_meshopt_compression: 3 buffer views",
        ),
    ];
    for (file, line) in cases {
        let scene = load(&format!("compressed/{file}.glb"));
        assert_eq!(scene.decoded, [line], "{file}");
    }
    assert!(load("compressed/helmet.quantized.glb").decoded.is_empty());
}

#[test]
fn draco_with_a_fallback_reads_the_fallback() {
    let scene = load("compressed/knight.draco-fallback.glb");
    assert!(scene.decoded.is_empty(), "{:?}", scene.decoded);
    let reference = load("compressed/knight.draco-seq.plain.glb");
    assert_eq!(largest_difference(&scene, &reference, true), 0.0);
}

#[test]
fn meshopt_fallback_file_is_never_read() {
    let dir = std::env::temp_dir().join(format!("raycast-fallback-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let copy = dir.join("knight.meshopt-fallback.glb");
    std::fs::copy(fixture("compressed/knight.meshopt-fallback.glb"), &copy).unwrap();
    let scene = raycast::import::load(&copy, &Default::default());
    std::fs::remove_dir_all(&dir).unwrap();
    let reference = load("compressed/knight.meshopt-fallback.plain.glb");
    assert_eq!(largest_difference(&scene.unwrap(), &reference, true), 0.0);
}

#[test]
fn corrupted_compressed_data_is_an_error_not_a_crash() {
    // Random bytes of the BIN chunk (the Draco and meshopt streams, the instance data)
    // overwritten, 150 variants per file: each load must end in a scene with finite bounds
    // or an error, never a panic or an abort.
    let dir = std::env::temp_dir().join(format!("raycast-corrupt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for file in [
        "helmet.draco-seq",
        "knight.draco-eb",
        "helmet.meshopt",
        "helmet.meshopt-khr",
        "knight.meshopt",
        "cubes.instanced-meshopt",
    ] {
        let original = std::fs::read(fixture(&format!("compressed/{file}.glb"))).unwrap();
        let json_len = u32::from_le_bytes(original[12..16].try_into().unwrap()) as usize;
        let bin = 20 + json_len + 8;
        for variant in 0..150 {
            let mut bytes = original.clone();
            let flips = 1 + (rng.next_u64() % 8) as usize;
            for _ in 0..flips {
                let at = bin + (rng.next_u64() as usize) % (bytes.len() - bin);
                bytes[at] = rng.next_u64() as u8;
            }
            let path = dir.join(format!("{file}-{variant}.glb"));
            std::fs::write(&path, &bytes).unwrap();
            if let Ok(scene) = raycast::import::load(&path, &Default::default()) {
                let b = scene.world_bounds();
                assert!(
                    b.is_empty() || (b.min.is_finite() && b.max.is_finite()),
                    "{file} variant {variant}: non-finite bounds"
                );
            }
            std::fs::remove_file(&path).unwrap();
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn check_passes_every_compressed_fixture() {
    // The reference decodes too: the Khronos validator passes every file here, and the two
    // dequantized references have normals a few 1e-3 off unit length, inside its tolerance.
    for entry in std::fs::read_dir(fixture("compressed")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.ends_with(".glb") {
            continue;
        }
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_raycast"))
            .arg("check")
            .arg(&path)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{name}: {stdout}");
        assert!(!stdout.contains("warning"), "{name}: {stdout}");
    }
}
