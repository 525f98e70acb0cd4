//! The command line's queries beyond the nearest hit from `t > 0`: the `t` and `bary` AOVs,
//! per-ray `tmin`/`tmax` from an (N, 8) ray file, `--hits` (a CSR `hits.npz`), and their bad
//! input. Expected values follow from the geometry (a single triangle, the cube [-1, 1]³).

use crate::common;
use common::*;
use std::io::Read;
use std::path::{Path, PathBuf};

/// One triangle (0, 0, 0), (1, 0, 0), (0, 1, 0) in the plane z = 0, as an OBJ file in `dir`:
/// the point (x, y, 0) inside it has barycentric weights (1 - x - y, x, y).
fn triangle(dir: &Path) -> PathBuf {
    let path = dir.join("triangle.obj");
    std::fs::write(&path, "o tri\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    path
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-15
}

#[test]
fn t_bary_and_ray_ranges_on_a_triangle() {
    let dir = temp_dir("t-bary");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = triangle(&dir);
    let inf = f64::INFINITY;
    let rays = dir.join("rays.npy");
    // Down onto (0.2, 0.3, 0) with |d| = 4 from z = 2: t = 2 / 4 = 0.5, distance 2.
    let down = [0.2, 0.3, 2.0, 0.0, 0.0, -4.0];
    let with = |tmin: f64, tmax: f64| {
        let mut row = [0.0; 8];
        row[..6].copy_from_slice(&down);
        row[6] = tmin;
        row[7] = tmax;
        row
    };
    write_rays(
        &rays,
        &[
            with(0.0, inf),
            // Up onto (0.25, 0.25, 0) from z = -1 with |d| = 0.5: t = 2, distance 1.
            [0.25, 0.25, -1.0, 0.0, 0.0, 0.5, 0.0, inf],
            with(0.0, 0.4),  // the hit lies beyond tmax
            with(0.5, inf),  // a hit needs t > tmin
            with(0.49, 0.5), // t = tmax counts
            [2.0, 2.0, 1.0, 0.0, 0.0, -1.0, 0.0, inf],
        ],
    );
    let out = dir.join("out");
    raycast_ok(&[
        arg(&scene),
        "--rays",
        arg(&rays),
        "--aov",
        "t,depth,bary,prim",
        "--out",
        arg(&out),
        "--quiet",
    ]);
    let (shape, t) = read_f64(&out.join("t.npy"));
    assert_eq!(shape, [6]);
    let expected_t = [0.5, 2.0, inf, inf, 0.5, inf];
    assert!(
        t.iter()
            .zip(expected_t)
            .all(|(&a, b)| a == b || close(a, b)),
        "{t:?}"
    );
    let depth = read_f64(&out.join("depth.npy")).1;
    let expected_depth = [2.0, 1.0, inf, inf, 2.0, inf];
    assert!(
        depth
            .iter()
            .zip(expected_depth)
            .all(|(&a, b)| a == b || close(a, b)),
        "{depth:?}"
    );
    let (shape, bary) = read_f64(&out.join("bary.npy"));
    assert_eq!(shape, [6, 3]);
    let expected_bary = [
        [0.5, 0.2, 0.3],
        [0.5, 0.25, 0.25],
        [0.0; 3],
        [0.0; 3],
        [0.5, 0.2, 0.3],
        [0.0; 3],
    ];
    for (got, want) in bary.chunks(3).zip(expected_bary) {
        assert!(
            got.iter().zip(want).all(|(&a, b)| close(a, b)),
            "{got:?} != {want:?}"
        );
    }
    assert_eq!(
        read_u32(&out.join("prim.npy")).1,
        [0, 0, u32::MAX, u32::MAX, 0, u32::MAX]
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
    assert!(json["conventions"]["bary"].is_string() && json["conventions"]["t"].is_string());
}

/// The members of an `.npz` archive: name to `.npy` bytes.
fn npz_members(path: &Path) -> Vec<(String, Vec<u8>)> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    (0..zip.len())
        .map(|i| {
            let mut member = zip.by_index(i).unwrap();
            let mut bytes = Vec::new();
            member.read_to_end(&mut bytes).unwrap();
            (member.name().to_string(), bytes)
        })
        .collect()
}

/// The values of the `.npy` member `name`, as f64 (`<f8`, `<u8` or `<u4` data).
fn member(members: &[(String, Vec<u8>)], name: &str) -> Vec<f64> {
    let (_, bytes) = members.iter().find(|(n, _)| n == name).unwrap();
    let (header, _, data) = parse_npy(bytes);
    if header.contains("'<u4'") {
        data.chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect()
    } else if header.contains("'<u8'") {
        data.chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect()
    } else {
        assert!(header.contains("'<f8'"), "{header}");
        data.chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }
}

#[test]
fn hits_list_each_crossing_of_the_cube_once() {
    let dir = temp_dir("hits");
    std::fs::create_dir_all(&dir).unwrap();
    let rays = dir.join("rays.npy");
    // Down through the cube [-1, 1]^3 from z = 5: crossings at t = 4 and 6, through a face's
    // interior and along both face diagonals (one of them an edge shared by the face's two
    // triangles); through two opposite corners (t = 1 and 3); and a miss.
    write_rays(
        &rays,
        &[
            [0.25, 0.5, 5.0, 0.0, 0.0, -1.0],
            [0.3, 0.3, 5.0, 0.0, 0.0, -1.0],
            [0.3, -0.3, 5.0, 0.0, 0.0, -1.0],
            [-2.0, -2.0, -2.0, 1.0, 1.0, 1.0],
            [5.0, 5.0, 5.0, 0.0, 0.0, 1.0],
        ],
    );
    let cube = fixture("gltf/cube.gltf");
    for (limit, splits, t) in [
        (
            "all",
            vec![0.0, 2.0, 4.0, 6.0, 8.0, 8.0],
            vec![4.0, 6.0, 4.0, 6.0, 4.0, 6.0, 1.0, 3.0],
        ),
        (
            "1",
            vec![0.0, 1.0, 2.0, 3.0, 4.0, 4.0],
            vec![4.0, 4.0, 4.0, 1.0],
        ),
    ] {
        let out = dir.join(format!("out-{limit}"));
        raycast_ok(&[
            arg(&cube),
            "--rays",
            arg(&rays),
            "--hits",
            limit,
            "--out",
            arg(&out),
            "--quiet",
        ]);
        let members = npz_members(&out.join("hits.npz"));
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["ray_splits.npy", "t.npy", "id.npy", "prim.npy"]);
        assert_eq!(member(&members, "ray_splits.npy"), splits, "--hits {limit}");
        let found = member(&members, "t.npy");
        assert!(
            found.iter().zip(&t).all(|(&a, &b)| (a - b).abs() <= 1e-12),
            "{found:?}"
        );
        assert_eq!(found.len(), t.len());
        assert!(member(&members, "id.npy").iter().all(|&id| id == 1.0));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("raycast.json")).unwrap()).unwrap();
        assert!(json["files"]
            .as_array()
            .unwrap()
            .contains(&"hits.npz".into()));
        assert_eq!(json["hits"]["crossings"], t.len());
        assert_eq!(file_names(&out), ["depth.npy", "hits.npz", "raycast.json"]);
    }
}

#[test]
fn bad_ray_ranges_and_hit_options_are_one_line_errors() {
    let dir = temp_dir("bad-ranges");
    std::fs::create_dir_all(&dir).unwrap();
    let cube = fixture("gltf/cube.gltf");
    let down = [0.0, 0.0, 5.0, 0.0, 0.0, -1.0];
    let range = |tmin: f64, tmax: f64| {
        let mut row = [0.0; 8];
        row[..6].copy_from_slice(&down);
        [row[6], row[7]] = [tmin, tmax];
        row
    };
    let seven = dir.join("seven.npy");
    write_rays(&seven, &[[0.0, 0.0, 5.0, 0.0, 0.0, -1.0, 1.0]]);
    let reversed = dir.join("reversed.npy");
    write_rays(&reversed, &[range(0.0, 1.0), range(2.0, 1.0)]);
    let nan = dir.join("nan.npy");
    write_rays(&nan, &[range(f64::NAN, 1.0)]);
    let ranged = dir.join("ranged.npy");
    write_rays(&ranged, &[range(0.5, 10.0)]);
    let out = dir.join("out");
    // (arguments, exit code, the error's first line; clap adds a usage hint after its own.)
    let cases: [(&[&str], i32, &str); 5] = [
        (
            &["--rays", arg(&seven)],
            1,
            "seven.npy: expected shape (N, 6) (origin, direction) or (N, 8)",
        ),
        (
            &["--rays", arg(&reversed)],
            1,
            "reversed.npy: ray 1: tmin 2 is greater than tmax 1",
        ),
        (
            &["--rays", arg(&nan)],
            1,
            "nan.npy: ray 0: tmin NaN is not a number >= 0",
        ),
        // The obvhs BVH is a test oracle now, not a choice of the command line.
        (
            &["--rays", arg(&ranged), "--accel", "bvh"],
            2,
            "unexpected argument '--accel' found",
        ),
        (
            &["--hits", "0"],
            2,
            "invalid value '0' for '--hits <all|N>': '0' is not a number of hits per ray",
        ),
    ];
    for (extra, code, message) in cases {
        let mut args = vec![arg(&cube), "--out", arg(&out)];
        args.extend_from_slice(extra);
        let result = raycast(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(code), "{extra:?}: {stderr}");
        assert!(
            stderr.lines().next().unwrap_or("").contains(message),
            "{extra:?}: {stderr}"
        );
        let ours = !extra.contains(&"0") && !extra.contains(&"--accel");
        assert!(!ours || stderr.lines().count() == 1, "{stderr}");
        assert!(!out.exists(), "{extra:?} left {}", out.display());
    }
}

/// `--depth-range` is in scene units and maps depth and z; the `t` preview, in units of each
/// ray's direction, spans its own percentile range. The cube seen obliquely from (3, 4, 5) has
/// t between about 5.4 and 7.8: over a depth range of 0..1000 every hit would be white (at
/// most 2 grey levels below 255), over its own range the far hits are dark.
#[test]
fn the_t_preview_maps_its_own_range() {
    let dir = temp_dir("t-preview");
    raycast_ok(&[
        arg(&fixture("gltf/cube.gltf")),
        "--aov",
        "t",
        "--width",
        "32",
        "--height",
        "32",
        "--format",
        "png",
        "--depth-range",
        "0,1000",
        "--eye",
        "3,4,5",
        "--target",
        "0,0,0",
        "--out",
        arg(&dir),
        "-q",
    ]);
    let png = image::open(dir.join("t.png")).unwrap().to_rgb8();
    let darkest = png.pixels().map(|p| p[0]).filter(|&g| g > 0).min().unwrap();
    assert!(darkest < 128, "darkest hit grey {darkest}");
}
