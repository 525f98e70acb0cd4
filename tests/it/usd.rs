//! USD importer: analytic answers on the fixtures in `fixtures/usd/` (written by
//! `raycast_tools usd-fixtures`, answers in `fixtures/usd/README.md`), the cross-format
//! comparison with the glTF fixtures, and the real usd-wg assets against usd-core's counts.

use crate::common;

use common::*;
use raycast::import::{self, LoadOptions};
use raycast::scene::{ObjectKind, Scene};
use std::path::{Path, PathBuf};

/// The shared usd-wg assets (not in the repository; tests that need them skip without them,
/// or when `RAYCAST_NO_SHARED_ASSETS` is set).
fn shared_assets() -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/usd");
    (root.is_dir() && std::env::var_os("RAYCAST_NO_SHARED_ASSETS").is_none()).then_some(root)
}

/// Loads an asset of a library whose files reference each other across the library's folders
/// (usd-wg's test assets read `../../../_common`): the library's folder is the root.
fn load_in(path: &Path, library: &Path) -> Scene {
    let options = LoadOptions {
        root: Some(library.to_path_buf()),
        ..LoadOptions::default()
    };
    import::load(path, &options).unwrap_or_else(|e| panic!("{} should load: {e}", path.display()))
}

/// Every usd-wg asset loads, and draws as many triangles and quadrics as usd-core counts
/// (`raycast_tools usd-counts`, stored in `fixtures/usd/asset_counts.json`), with its meshes where
/// usd-core places them. Uses ../shared/assets/usd when present, else the few assets copied
/// into fixtures/usd/assets/usd-wg.
#[test]
fn real_assets_match_usd_core_counts() {
    let (root, all) = match shared_assets() {
        Some(root) => (root, true),
        None => (fixture("usd/assets/usd-wg"), false),
    };
    let counts: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixture("usd/asset_counts.json")).unwrap())
            .unwrap();
    let mut compared = 0;
    let mut bounds_compared = 0;
    let mut mismatches = Vec::new();
    for entry in counts.as_array().unwrap() {
        let file = entry["file"].as_str().unwrap();
        let path = root.join(file);
        if !all && !path.is_file() {
            continue;
        }
        if entry.get("error").is_some() {
            // usd-core cannot open it; raycast must not fail either way with a panic.
            let _ = import::load(
                &path,
                &LoadOptions {
                    root: Some(root.clone()),
                    ..LoadOptions::default()
                },
            );
            continue;
        }
        let scene = load_in(&path, &root);
        let quadrics = scene.quadrics().len() as u64;
        let expected = (
            entry["raycast_triangles"].as_u64().unwrap(),
            entry["raycast_quadrics"].as_u64().unwrap(),
        );
        let got = (scene.triangle_count() as u64, quadrics);
        if got != expected {
            mismatches.push(format!("{file}: raycast {got:?}, usd-core {expected:?}"));
        }
        // Mesh placement: world bounds of each mesh's points as usd-core transforms them.
        for (name, bounds) in entry["mesh_bounds"].as_object().unwrap() {
            let Some(object) = scene.objects.iter().find(|o| &o.name == name) else {
                mismatches.push(format!("{file}: no object {name}"));
                continue;
            };
            let b = scene.object_bounds(object);
            let corner = |k: usize| -> glam::DVec3 {
                let v: Vec<f64> = bounds[k]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect();
                glam::DVec3::from_slice(&v)
            };
            let (min, max) = (corner(0), corner(1));
            let scale = 1e-6
                * (max - min)
                    .max_element()
                    .max(min.abs().max_element())
                    .max(1.0);
            if (b.min - min).abs().max_element() > scale
                || (b.max - max).abs().max_element() > scale
            {
                mismatches.push(format!(
                    "{file}: {name} bounds {:?}..{:?}, usd-core {min:?}..{max:?}",
                    b.min, b.max
                ));
            }
            bounds_compared += 1;
        }
        compared += 1;
    }
    let (files, meshes) = if all { (150, 200) } else { (9, 10) };
    assert!(compared >= files, "only {compared} assets compared");
    assert!(
        bounds_compared >= meshes,
        "only {bounds_compared} meshes placed"
    );
    assert!(mismatches.is_empty(), "{}", mismatches.join("\n"));
}

/// The expected answers written by `raycast_tools usd-fixtures`.
fn expected_rays() -> serde_json::Map<String, serde_json::Value> {
    let text = std::fs::read_to_string(fixture("usd/expected_rays.json")).unwrap();
    serde_json::from_str::<serde_json::Value>(&text)
        .unwrap()
        .as_object()
        .unwrap()
        .clone()
}

fn array3(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [0, 1, 2].map(|k| a[k].as_f64().unwrap())
}

/// Casts the documented rays of `stem` at its `.usda` and `.usdc` files; returns the number
/// of rays checked. Depth and normal tolerances: 1e-9 for quadric hits (relative depth),
/// 1e-6 for triangles (the reference's cube and caps are closed-form, raycast's are
/// tessellated). The fixture names the surface hit as usd-core's tessellation calls it
/// (`/World/Cylinder:caps`, `/World/Capsule:top`); raycast draws the prim as one object and
/// tells the surfaces apart by `prim`: the side quadric is 0, the caps' triangles follow
/// (`1 + ` their index), a capsule's top and bottom hemispheres are 1 and 2.
fn check_rays(stem: &str, rays: &[serde_json::Value]) -> usize {
    let mut checked = 0;
    for extension in ["usda", "usdc"] {
        let scene = load(&format!("usd/{stem}.{extension}"));
        let cast_rays: Vec<_> = rays
            .iter()
            .map(|r| ray(array3(&r["origin"]), array3(&r["direction"])))
            .collect();
        let samples = cast(&scene, &cast_rays);
        for (r, s) in rays.iter().zip(samples) {
            let label = format!("{stem}.{extension}: {}", r["label"].as_str().unwrap());
            let Some(hit) = r["hit"].as_str() else {
                assert_eq!(s.object, None, "{label}: expected a miss, got {s:?}");
                assert_eq!(s.depth, f64::INFINITY, "{label}");
                continue;
            };
            let (prim_path, surface) = hit.split_once(':').unwrap_or((hit, ""));
            assert_eq!(s.object.as_deref(), Some(prim_path), "{label}: {s:?}");
            let object = scene.objects.iter().find(|o| o.name == prim_path).unwrap();
            let tolerance = match (object.kind, surface) {
                (ObjectKind::Quadric, "" | "top" | "bottom") => 1e-9,
                _ => 1e-6,
            };
            let first_prim = match surface {
                "caps" | "top" => 1,
                "bottom" => 2,
                _ => 0,
            };
            if surface == "caps" {
                assert!(s.prim >= first_prim, "{label}: prim {} on the caps", s.prim);
            }
            if matches!(surface, "top" | "bottom") {
                assert_eq!(
                    s.prim, first_prim,
                    "{label}: prim of the {surface} hemisphere"
                );
            }
            let depth = r["depth"].as_f64().unwrap();
            assert!(
                (s.depth - depth).abs() <= tolerance * depth.max(1.0),
                "{label}: depth {} != {depth}",
                s.depth
            );
            let normal = glam::DVec3::from_array(array3(&r["normal"]));
            assert!(
                (s.normal - normal).length() <= tolerance,
                "{label}: normal {:?} != {normal:?}",
                s.normal
            );
            if let Some(prims) = r.get("prim").and_then(|p| p.as_array()) {
                let prims: Vec<u32> = prims
                    .iter()
                    .map(|p| first_prim + p.as_u64().unwrap() as u32)
                    .collect();
                assert!(
                    prims.contains(&s.prim),
                    "{label}: prim {} not in {prims:?}",
                    s.prim
                );
            }
            checked += 1;
        }
    }
    checked
}

/// Every intrinsic gprim with every axis and with its fallbacks (closed-form answers).
#[test]
fn gprims_answer_documented_rays() {
    let expected = expected_rays();
    let n = check_rays("gprims", expected["gprims"].as_array().unwrap());
    assert!(n >= 100, "{n}");
}

/// Nested transforms with every op kind, `!invert!`, `!resetXformStack!`, a mirror, and the
/// ignored ops of a Scope: raycast places the meshes where usd-core does.
#[test]
fn xforms_match_usd_core_placement() {
    let expected = expected_rays();
    let n = check_rays("xforms", expected["xforms"].as_array().unwrap());
    assert!(n >= 100, "{n}");
}

/// References, variants, scene-graph instances, a point instancer (with an invisible id and
/// a prototype transform), a general quadric prim, and hidden prims.
#[test]
fn composition_matches_usd_core() {
    let expected = expected_rays();
    let n = check_rays("composition", expected["composition"].as_array().unwrap());
    assert!(n >= 60, "{n}");
    let scene = load("usd/composition.usda");
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    for name in [
        "/World/Instancer[0]",
        "/World/Instancer[1]",
        "/World/Instancer[2]",
        "/World/Instancer[4]",
        "/World/Instance0/body",
        "/World/Instance1/hat",
        "/World/Quadric",
    ] {
        assert!(names.contains(&name), "{name} missing from {names:?}");
    }
    // invisible id 3; prototypes never drawn in place; hidden, guide, inactive, under an over
    for name in [
        "/World/Instancer[3]",
        "/World/Instancer/Prototypes/Tet",
        "/World/Hidden",
        "/World/Guide",
        "/World/Inactive",
        "/World/OverOnly/Mesh",
    ] {
        assert!(!names.contains(&name), "{name} should not be drawn");
    }
    let warnings = lines(&scene).join("\n");
    for note in [
        "invisible prims skipped: /World/Hidden",
        "guide or proxy prims skipped: /World/Guide",
        "inactive prims skipped: /World/Inactive",
    ] {
        assert!(warnings.contains(note), "no note '{note}' in:\n{warnings}");
    }
    // Camera: UsdGeomCamera fallbacks for the apertures, focalLength 35.
    let camera = &scene.cameras[0];
    assert_eq!(camera.name, "/World/Camera");
    let raycast::camera::Projection::Perspective { yfov } = camera.projection else {
        panic!("perspective expected");
    };
    assert!((yfov - 2.0 * (15.2908f64 / 70.0).atan()).abs() < 1e-12);
    assert!((camera.aspect_ratio.unwrap() - 20.955 / 15.2908).abs() < 1e-12);
    assert_eq!(camera.znear, 0.5);
    assert_eq!(camera.zfar, Some(500.0));
    assert_eq!(camera.eye(), glam::DVec3::new(0.0, 0.0, 40.0));
}

/// The glTF quadric fixtures' documented rays, on their USD exports.
#[test]
fn gltf_exports_answer_the_gltf_rays() {
    let expected = expected_rays();
    let mut total = 0;
    for (stem, rays) in &expected {
        if stem.starts_with("gltf_") {
            total += check_rays(stem, rays.as_array().unwrap());
        }
    }
    assert!(total >= 250, "{total}");
}

/// The same scene as glTF, USDA and USDC gives the same depth, normal and id buffers, seen
/// from the file's first camera (64×48 pixels): depth within 1e-9 relative on quadrics and
/// 1e-6 on triangles, ids equal, object names equal up to the prim path's leading `/`.
#[test]
fn cross_format_buffers_agree() {
    let pairs = [
        ("gltf/cube.gltf", "gltf_cube"),
        ("gltf/cameras.gltf", "gltf_cameras"),
        ("quadrics/mixed.gltf", "gltf_mixed"),
        (
            "quadrics/sphere_coefficients.gltf",
            "gltf_sphere_coefficients",
        ),
        ("quadrics/ellipsoid.gltf", "gltf_ellipsoid"),
        (
            "quadrics/elliptic_paraboloid.gltf",
            "gltf_elliptic_paraboloid",
        ),
        (
            "quadrics/hyperbolic_paraboloid.gltf",
            "gltf_hyperbolic_paraboloid",
        ),
        (
            "quadrics/hyperboloid_one_sheet.gltf",
            "gltf_hyperboloid_one_sheet",
        ),
        (
            "quadrics/hyperboloid_two_sheets.gltf",
            "gltf_hyperboloid_two_sheets",
        ),
        ("quadrics/cone.gltf", "gltf_cone"),
        ("quadrics/cylinder.gltf", "gltf_cylinder"),
        ("quadrics/elliptic_cylinder.gltf", "gltf_elliptic_cylinder"),
        (
            "quadrics/hyperbolic_cylinder.gltf",
            "gltf_hyperbolic_cylinder",
        ),
        (
            "quadrics/parabolic_cylinder.gltf",
            "gltf_parabolic_cylinder",
        ),
        ("quadrics/far_sphere.gltf", "gltf_far_sphere"),
    ];
    let (width, height) = (64, 48);
    let mut hits = 0;
    let mut worst = [0.0f64; 2];
    for (gltf, stem) in pairs {
        let reference = load(gltf);
        let camera = reference
            .cameras
            .first()
            .cloned()
            .unwrap_or_else(|| raycast::camera::Camera::framing(&reference.world_bounds()));
        let rays: Vec<_> = (0..height)
            .flat_map(|row| (0..width).map(move |col| (col, row)))
            .map(|(col, row)| camera.pixel_ray(col, row, width, height))
            .collect();
        let expected = cast(&reference, &rays);
        for extension in ["usda", "usdc"] {
            let scene = load(&format!("usd/{stem}.{extension}"));
            assert_eq!(
                scene.objects.len(),
                reference.objects.len(),
                "{stem}.{extension}"
            );
            for (a, b) in reference.objects.iter().zip(&scene.objects) {
                assert_eq!(format!("/{}", a.name), b.name, "{stem}.{extension}");
                assert_eq!(
                    (a.kind, a.triangles),
                    (b.kind, b.triangles),
                    "{stem}.{extension}"
                );
            }
            // The USD camera gives the same rays up to USD's `float` camera attributes (the
            // aperture that encodes yfov is rounded to f32): 1e-7. The buffers below are
            // cast with the glTF camera's rays on both scenes.
            assert_eq!(scene.cameras.len(), reference.cameras.len());
            for (a, b) in reference.cameras.iter().zip(&scene.cameras) {
                let (ra, rb) = (
                    a.pixel_ray(5, 7, width, height),
                    b.pixel_ray(5, 7, width, height),
                );
                assert!((ra.origin - rb.origin).length() < 1e-12 * ra.origin.length().max(1.0));
                let (da, db) = (ra.dir.normalize(), rb.dir.normalize());
                assert!((da - db).length() < 1e-7, "{stem}: camera {da:?} {db:?}");
            }
            let got = cast(&scene, &rays);
            for (i, (e, g)) in expected.iter().zip(&got).enumerate() {
                let at = format!("{stem}.{extension} pixel {i}");
                assert_eq!(e.object.as_ref().map(|n| format!("/{n}")), g.object, "{at}");
                if e.object.is_none() {
                    continue;
                }
                let quadric = e.prim == 0
                    && reference.objects.iter().any(|o| {
                        Some(&o.name) == e.object.as_ref() && o.kind == ObjectKind::Quadric
                    });
                let slot = usize::from(!quadric);
                let tolerance = if quadric { 1e-9 } else { 1e-6 };
                let depth_error = (e.depth - g.depth).abs() / e.depth.max(1.0);
                let normal_error = (e.normal - g.normal).length();
                worst[slot] = worst[slot].max(depth_error).max(normal_error);
                assert!(
                    depth_error <= tolerance,
                    "{at}: depth {} vs {}",
                    e.depth,
                    g.depth
                );
                assert!(
                    normal_error <= tolerance,
                    "{at}: normal {:?} vs {:?}",
                    e.normal,
                    g.normal
                );
                assert_eq!(e.prim, g.prim, "{at}");
                hits += 1;
            }
        }
    }
    eprintln!(
        "cross-format: {hits} hits, worst relative difference quadrics {:.1e}, meshes {:.1e}",
        worst[0], worst[1]
    );
    assert!(hits > 15_000, "{hits}");
}

/// Invalid general quadric prims fail to load with the glTF extension's messages, naming
/// the file and the prim.
#[test]
fn bad_quadric_prims_are_errors() {
    let text = std::fs::read_to_string(fixture("usd/bad/expected_errors.json")).unwrap();
    let expected: serde_json::Value = serde_json::from_str(&text).unwrap();
    for (stem, message) in expected.as_object().unwrap() {
        let path = fixture(&format!("usd/bad/{stem}.usda"));
        let error = import::load(&path, &LoadOptions::default())
            .expect_err(stem)
            .to_string();
        assert!(error.contains(&format!("{stem}.usda")), "{error}");
        assert!(error.contains("/Q: raycast:quadric:"), "{error}");
        assert!(error.contains(message.as_str().unwrap()), "{stem}: {error}");
    }
}

/// A `raycast:quadric:` attribute of the wrong type is an error naming the prim once, then
/// the attribute alone: `/Q: raycast:quadric: raycast:quadric:boundsMin: ...` (the value
/// reader's location `/Q.raycast:quadric:boundsMin` loses its prim, which the prefix names).
#[test]
fn a_quadric_attribute_of_the_wrong_type_names_the_prim_once() {
    let path = temp_file(
        "quadric-wrong-type",
        "q.usda",
        "#usda 1.0\n\ndef Xform \"Q\"\n{\n\
         \x20   custom double3 raycast:quadric:P = (0, 0, 0)\n\
         \x20   custom matrix3d raycast:quadric:Q = ( (1, 0, 0), (0, 1, 0), (0, 0, 1) )\n\
         \x20   custom double raycast:quadric:R = -1\n\
         \x20   custom double raycast:quadric:boundsMin = -2\n\
         \x20   custom double3 raycast:quadric:boundsMax = (2, 2, 2)\n}\n",
    );
    let error = import::load(&path, &LoadOptions::default())
        .expect_err("a double is no 3-vector")
        .to_string();
    assert!(
        error.ends_with(
            "q.usda: /Q: raycast:quadric: raycast:quadric:boundsMin: expected a 3-vector, \
             found Double"
        ),
        "{error}"
    );
}

/// A missing or malformed file is an error naming it, never a panic.
#[test]
fn unreadable_files_are_errors() {
    let dir = std::env::temp_dir().join(format!("raycast-usd-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases = [
        (
            "garbage.usda",
            b"#usda 1.0\ndef Xform \"A\" {{{{ nonsense".to_vec(),
        ),
        ("garbage.usdc", b"PXR-USDC garbage garbage".to_vec()),
        ("empty.usd", Vec::new()),
        ("truncated.usdz", b"PK\x03\x04".to_vec()),
    ];
    for (name, bytes) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let error = import::load(&path, &LoadOptions::default()).expect_err(name);
        assert_eq!(error.path.as_deref(), Some(path.as_path()), "{error}");
    }
    let missing = dir.join("missing.usda");
    let error = import::load(&missing, &LoadOptions::default()).expect_err("missing");
    assert!(error.to_string().contains("missing.usda"), "{error}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `--scene PATH` draws one prim's subtree, keeping its ancestors' transforms.
#[test]
fn scene_option_selects_a_prim() {
    let options = LoadOptions {
        scene: Some("/World/Root/translate".into()),
        ..Default::default()
    };
    let scene = import::load(&fixture("usd/xforms.usda"), &options).unwrap();
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["/World/Root/translate/tet"]);
    let full = load("usd/xforms.usda");
    let object = full.objects.iter().find(|o| o.name == names[0]).unwrap();
    assert_eq!(
        full.object_bounds(object),
        scene.object_bounds(&scene.objects[0])
    );
    let bad = LoadOptions {
        scene: Some("/World/Nothing".into()),
        ..Default::default()
    };
    let error = import::load(&fixture("usd/xforms.usda"), &bad).unwrap_err();
    assert!(
        error.to_string().contains("no prim '/World/Nothing'"),
        "{error}"
    );
}

/// OpenChessSet: payloads, binary crate files, variants and the PointInstancer pawns, one
/// object per pawn (needs ../shared/assets/usd).
#[test]
fn chess_set_draws_every_pawn() {
    let Some(root) = shared_assets() else {
        eprintln!("skipped: ../shared/assets/usd is not present");
        return;
    };
    let scene = load_in(&root.join("full_assets/OpenChessSet/chess_set.usda"), &root);
    let pawns: Vec<_> = scene
        .objects
        .iter()
        .filter(|o| o.name.contains("/Pawns["))
        .collect();
    assert_eq!(
        pawns.len(),
        16,
        "{:?}",
        scene.objects.iter().map(|o| &o.name).collect::<Vec<_>>()
    );
    assert!(pawns
        .iter()
        .all(|p| p.triangles == pawns[0].triangles && p.triangles > 0));
    assert_eq!(scene.triangle_count(), 1_430_784);
}

/// Stage metadata reaches the scene (and from there the sidecar and `info`), with USD's
/// fallbacks when it is not authored. Expected values are read from the files' own headers.
#[test]
fn stage_metadata_is_reported() {
    let authored = load("usd/gltf_sphere_matrices.usda");
    let stage = authored.stage.expect("USD scenes carry stage metadata");
    let text = std::fs::read_to_string(fixture("usd/gltf_sphere_matrices.usda")).unwrap();
    assert!(
        text.contains(&format!("upAxis = \"{}\"", stage.up_axis)),
        "{stage:?}"
    );
    assert!(
        text.contains(&format!("metersPerUnit = {}", stage.meters_per_unit)),
        "{stage:?}"
    );
    assert!(load("gltf/cube.gltf").stage.is_none());
    let z_up = load_in(
        &fixture(
            "usd/assets/usd-wg/test_assets/foundation/stage_configuration/upAxis/upAxis_Z.usda",
        ),
        &fixture("usd/assets/usd-wg"),
    );
    assert_eq!(z_up.stage.unwrap().up_axis, "Z");
    // composition.usda authors neither: USD's fallbacks apply.
    let fallback = load("usd/composition.usda").stage.unwrap();
    assert_eq!(
        (fallback.up_axis.as_str(), fallback.meters_per_unit),
        ("Y", 0.01)
    );
}

/// fixtures/exact/point_instancer.usda (fixtures/exact/README.md): of `/world/pi`'s 24
/// instances with ids 100..123, `invisibleIds` hides 103 and 110, the `inactiveIds` metadata
/// deactivates 107 and 115, and 122 and 123 use the invisible prototype: the other 18 are
/// drawn, one object each, as usd-core's ComputeMaskAtTime says (tests/python/
/// test_exact_depth.py compares with it). `/world/pi_shared`'s 6 instances are all drawn
/// although their prototypes live in an invisible scope, which itself draws nothing.
#[test]
fn point_instancer_skips_invisible_and_inactive_ids() {
    let scene = load("exact/point_instancer.usda");
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    let expected: Vec<String> = (0..24)
        .filter(|i| ![3, 10, 7, 15, 22, 23].contains(i))
        .map(|i| format!("/world/pi[{i}]"))
        .chain((0..6).map(|i| format!("/world/pi_shared[{i}]")))
        .collect();
    assert_eq!(names, expected);
}
