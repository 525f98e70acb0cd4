//! USD at a time code and with chosen variants (issue 28), against usd-core. The expected
//! values in fixtures/usd/posed/*.reference.json are usd-core's reading of the fixtures
//! (tools/raycast_tools/reference/usd_pose_reference.py, made by tools/make_usd_pose_fixtures.sh):
//! world-space mesh points through `UsdGeom.XformCache(time)` and `Get(time)`, PointInstancer
//! instances through `ComputeInstanceTransformsAtTime`, gprim sizes and world matrices, and
//! what usd-core composes with each variant selection. Nothing here poses with raycast's code:
//! the test only triangulates usd-core's faces as fans and, for spheres, intersects rays with
//! usd-core's sphere in its own frame.

use crate::common;
use common::*;
use glam::{DMat4, DVec3};
use raycast::import::{self, usd::Choice, LoadOptions};
use raycast::scene::Scene;
use serde_json::Value;

/// Largest difference allowed, relative to the scene's size (vertices) or to the depth.
const TOLERANCE: f64 = 1e-12;

fn reference(name: &str) -> Value {
    let path = fixture(&format!("usd/posed/{name}.reference.json"));
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn points(v: &Value) -> Vec<DVec3> {
    numbers(v)
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect()
}

/// A USD row-major matrix as glam's column-vector matrix (the same 16 numbers).
fn matrix(v: &Value) -> DMat4 {
    DMat4::from_cols_array(&numbers(v).try_into().unwrap())
}

/// usd-core's faces as triangle fans over its world points.
fn fans(mesh: &Value) -> Vec<[DVec3; 3]> {
    let p = points(&mesh["points"]);
    let indices = numbers(&mesh["faceVertexIndices"]);
    let mut start = 0;
    let mut triangles = Vec::new();
    for count in numbers(&mesh["faceVertexCounts"]) {
        let face = &indices[start..start + count as usize];
        for k in 1..face.len() - 1 {
            let corner = |i: f64| p[i as usize];
            triangles.push([corner(face[0]), corner(face[k]), corner(face[k + 1])]);
        }
        start += count as usize;
    }
    triangles
}

/// The world corners of usd-core's cube.
fn cube_corners(gprim: &Value) -> Vec<DVec3> {
    let h = gprim["size"].as_f64().unwrap() / 2.0;
    let world = matrix(&gprim["world"]);
    (0..8)
        .map(|i| {
            let s = |bit: i32| if i & bit == 0 { -h } else { h };
            world.transform_point3(DVec3::new(s(1), s(2), s(4)))
        })
        .collect()
}

/// Every point usd-core draws in a case, for the scene size.
fn all_points(case: &Value) -> Vec<DVec3> {
    let mut all = Vec::new();
    for m in case["meshes"].as_array().unwrap() {
        all.extend(points(&m["points"]));
    }
    for i in case["instances"].as_array().unwrap() {
        all.extend(points(&i["points"]));
    }
    for g in case["gprims"].as_array().unwrap() {
        if g["type"] == "Cube" {
            all.extend(cube_corners(g));
        } else {
            all.push(matrix(&g["world"]).transform_point3(DVec3::ZERO));
        }
    }
    all
}

fn diagonal(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::INFINITY, |a, &b| a.min(b));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &b| a.max(b));
    (hi - lo).length().max(1.0)
}

fn object_triangles(scene: &Scene, name: &str) -> Vec<[DVec3; 3]> {
    let object = scene
        .objects
        .iter()
        .find(|o| o.name == name)
        .unwrap_or_else(|| panic!("no object {name}"));
    scene.mesh_triangles(object)
}

/// Largest corner difference between our triangles and usd-core's (either winding).
fn triangle_difference(ours: &[[DVec3; 3]], expected: &[[DVec3; 3]], what: &str) -> f64 {
    assert_eq!(ours.len(), expected.len(), "{what}: triangle counts");
    let mut largest = 0.0f64;
    for (a, b) in ours.iter().zip(expected) {
        let d = |x: [DVec3; 3]| (0..3).map(|k| (x[k] - b[k]).length()).fold(0.0, f64::max);
        largest = largest.max(d(*a).min(d([a[0], a[2], a[1]])));
    }
    largest
}

/// The depth at which a ray meets usd-core's sphere (radius in the prim's frame, then its
/// world matrix), solved in the sphere's frame.
fn sphere_depth(gprim: &Value, origin: DVec3, dir: DVec3) -> Option<f64> {
    let r = gprim["radius"].as_f64().unwrap();
    let to_local = matrix(&gprim["world"]).inverse();
    let (o, d) = (
        to_local.transform_point3(origin),
        to_local.transform_vector3(dir),
    );
    let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - r * r);
    let disc = b * b - a * c;
    (disc >= 0.0).then(|| (-b - disc.sqrt()) / a)
}

/// Compares everything a case of a reference draws with what raycast draws; returns the
/// largest vertex difference relative to the scene size, and the largest sphere depth
/// difference relative to the depth.
fn compare(scene: &Scene, case: &Value, what: &str) -> (f64, f64) {
    let scale = diagonal(&all_points(case));
    let mut expected_objects = Vec::new();
    let mut largest = 0.0f64;
    for mesh in case["meshes"].as_array().unwrap() {
        let name = mesh["path"].as_str().unwrap();
        expected_objects.push(name.to_string());
        let d = triangle_difference(&object_triangles(scene, name), &fans(mesh), name);
        largest = largest.max(d / scale);
    }
    for instance in case["instances"].as_array().unwrap() {
        let name = instance["name"].as_str().unwrap();
        expected_objects.push(name.to_string());
        let p = points(&instance["points"]);
        let d = triangle_difference(&object_triangles(scene, name), &[[p[0], p[1], p[2]]], name);
        largest = largest.max(d / scale);
    }
    let mut depth_error = 0.0f64;
    for gprim in case["gprims"].as_array().unwrap() {
        let name = gprim["path"].as_str().unwrap();
        expected_objects.push(name.to_string());
        if gprim["type"] == "Cube" {
            let corners = cube_corners(gprim);
            let ours = object_triangles(scene, name);
            assert_eq!(ours.len(), 12, "{name}: a cube is 12 triangles");
            for v in ours.iter().flatten() {
                let nearest = corners
                    .iter()
                    .map(|c| (*c - *v).length())
                    .fold(f64::INFINITY, f64::min);
                largest = largest.max(nearest / scale);
            }
        } else {
            let centre = matrix(&gprim["world"]).transform_point3(DVec3::ZERO);
            let mut rng = Rng(0x5EED_0000 + expected_objects.len() as u64);
            for _ in 0..50 {
                let origin = centre + rng.direction() * 10.0;
                let dir = (centre + rng.point(-0.2, 0.2) - origin).normalize();
                let sample = cast_one(scene, origin.to_array(), dir.to_array());
                let expected = sphere_depth(gprim, origin, dir);
                // A ray that meets another object first says nothing of the sphere.
                let hit_this = sample.object.as_deref() == Some(name);
                match expected {
                    Some(t) if hit_this => {
                        depth_error = depth_error.max((sample.depth - t).abs() / t);
                    }
                    None => assert!(!hit_this, "{what}: {name}: a hit where usd-core's misses"),
                    Some(t) if sample.object.is_some() && sample.depth < t => {}
                    Some(t) => panic!("{what}: {name}: expected a hit at {t}, got {sample:?}"),
                }
            }
        }
    }
    let mut ours: Vec<String> = scene.objects.iter().map(|o| o.name.clone()).collect();
    ours.sort();
    expected_objects.sort();
    assert_eq!(ours, expected_objects, "{what}: the objects drawn");
    (largest, depth_error)
}

fn load(file: &str, time: Option<f64>, variants: &[(&str, &str)]) -> Scene {
    let options = LoadOptions {
        time,
        variants: variants
            .iter()
            .map(|(set, name)| Choice {
                set: set.to_string(),
                name: name.to_string(),
            })
            .collect(),
        ..LoadOptions::default()
    };
    import::load(&fixture(&format!("usd/posed/{file}")), &options)
        .unwrap_or_else(|e| panic!("{file} at {time:?} with {variants:?}: {e}"))
}

/// Time-sampled xformOps of every kind (translate, rotateXYZ, rotateY, scale in float and
/// half, translateX, orient as quatf, quatd and quath, transform, an inverted pivot), points,
/// a cube's size, a sphere's radius and a PointInstancer's positions, orientations and scales,
/// one moved on by its velocities, accelerations and angular velocities and one whose
/// velocities are not aligned with its positions (left out, with usd-core's warning), at the
/// default time code and five time codes (before, between, on and after the samples).
#[test]
fn time_samples_read_as_usd_core_reads_them() {
    let reference = reference("time_samples");
    for case in reference["cases"].as_array().unwrap() {
        let time = case["time"].as_f64();
        let scene = load("time_samples.usda", time, &[]);
        let (vertices, depths) = compare(&scene, case, &format!("time {time:?}"));
        eprintln!("time {time:?}: vertices {vertices:.1e}, sphere depths {depths:.1e}");
        assert!(
            vertices <= TOLERANCE,
            "time {time:?}: vertices off by {vertices:e}"
        );
        assert!(
            depths <= 1e-12,
            "time {time:?}: sphere depths off by {depths:e}"
        );
        let stage = scene.stage.as_ref().unwrap();
        assert_eq!(stage.time, time);
        let usd = &reference["stage"];
        assert_eq!(
            stage.time_codes_per_second,
            usd["timeCodesPerSecond"].as_f64()
        );
        let range = numbers(&usd["timeCodeRange"]);
        assert_eq!(stage.time_code_range, Some([range[0], range[1]]));
        let shown = lines(&scene);
        let misaligned = shown.iter().filter(|w| {
            w.starts_with("/World/Drift: velocities samples are not aligned with positions")
        });
        assert_eq!(
            misaligned.count(),
            time.is_some() as usize,
            "{:?}",
            lines(&scene)
        );
    }
}

/// Without `--time` a stage with time samples says once which pose was drawn.
#[test]
fn default_time_says_which_pose_was_drawn() {
    let scene = load("time_samples.usda", None, &[]);
    let shown = lines(&scene);
    let notes: Vec<&String> = shown
        .iter()
        .filter(|w| w.contains("drawn at the default time code"))
        .collect();
    assert_eq!(notes.len(), 1, "{:?}", lines(&scene));
    assert!(scene.stage.as_ref().unwrap().time_sampled_attributes > 0);
    let timed = load("time_samples.usda", Some(3.0), &[]);
    assert!(!lines(&timed)
        .iter()
        .any(|w| w.contains("default time code")));
}

/// `--variant` renders what usd-core composes with that selection, nested sets included, and
/// the stage records every set with its choices, authored and drawn selections.
#[test]
fn variants_compose_as_usd_core_composes_them() {
    let reference = reference("variants");
    for case in reference["cases"].as_array().unwrap() {
        let choices: Vec<(&str, &str)> = case["variants"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| (k.as_str(), v.as_str().unwrap()))
            .collect();
        let scene = load("variants.usda", None, &choices);
        let (vertices, depths) = compare(&scene, case, &format!("{choices:?}"));
        assert!(vertices <= TOLERANCE && depths <= 1e-12, "{choices:?}");
        let mut ours: Vec<(String, String, Vec<String>, Option<String>)> = scene
            .stage
            .as_ref()
            .unwrap()
            .variant_sets
            .iter()
            .map(|v| {
                (
                    v.prim.clone(),
                    v.set.clone(),
                    v.choices.clone(),
                    v.selected.clone(),
                )
            })
            .collect();
        let mut usd: Vec<(String, String, Vec<String>, Option<String>)> = case["sets"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| {
                let choices = v["choices"].as_array().unwrap();
                (
                    v["prim"].as_str().unwrap().to_string(),
                    v["set"].as_str().unwrap().to_string(),
                    choices
                        .iter()
                        .map(|c| c.as_str().unwrap().to_string())
                        .collect(),
                    v["selection"].as_str().map(str::to_string),
                )
            })
            .collect();
        ours.sort();
        usd.sort();
        assert_eq!(ours, usd, "{choices:?}: variant sets");
    }
}

/// An unknown set or variant is a one-line error that lists what there is.
#[test]
fn unknown_variants_are_errors_listing_the_choices() {
    let path = fixture("usd/posed/variants.usda");
    let try_load = |set: &str, name: &str| {
        let options = LoadOptions {
            variants: vec![Choice {
                set: set.into(),
                name: name.into(),
            }],
            ..LoadOptions::default()
        };
        import::load(&path, &options).unwrap_err().to_string()
    };
    let e = try_load("shape", "cone");
    assert!(
        e.contains("variants.usda") && e.contains("choices: ball, box, tri"),
        "{e}"
    );
    let e = try_load("colour", "red");
    assert!(e.contains("variant sets: placement, shape"), "{e}");
    assert!(!e.contains('\n'), "{e}");
}

/// A reference mesh or cube with usd-core's BakeSkinning values (`bakedPoints`, `bakedWorld`)
/// in place of the double-precision skinning; `None` where BakeSkinning baked nothing at that
/// time code (an animated skeleton at the default time code).
fn baked(item: &Value) -> Option<Value> {
    let mut copy = item.clone();
    for (key, baked) in [("points", "bakedPoints"), ("world", "bakedWorld")] {
        if let Some(value) = item.get(baked) {
            if value.is_null() {
                return None;
            }
            copy[key] = value.clone();
        }
    }
    Some(copy)
}

/// Möller–Trumbore in f64: the ray parameter at which `dir` from `origin` meets `tri`.
fn ray_triangle(origin: DVec3, dir: DVec3, tri: &[DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = origin - tri[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

/// Rays aimed at points of usd-core's skinned meshes hit what usd-core's triangles put first
/// (or a cube in front of them), at usd-core's depth; returns how many rays were compared.
fn hits_agree(scene: &Scene, case: &Value, what: &str) -> usize {
    let meshes: Vec<(String, Vec<[DVec3; 3]>)> = case["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["path"].as_str().unwrap().to_string(), fans(m)))
        .collect();
    let mut rng = Rng(0x5CE1_E70A);
    let mut compared = 0;
    for (name, triangles) in &meshes {
        for _ in 0..40 {
            let tri = triangles[(rng.next_u64() % triangles.len() as u64) as usize];
            let (a, b) = (rng.uniform(0.05, 0.9), rng.uniform(0.05, 0.9));
            let (a, b) = if a + b > 0.95 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let target = tri[0] + (tri[1] - tri[0]) * a * 0.9 + (tri[2] - tri[0]) * b * 0.9;
            let origin = target + rng.direction() * 30.0;
            let dir = (target - origin).normalize();
            let nearest = meshes
                .iter()
                .flat_map(|(n, ts)| {
                    ts.iter()
                        .filter_map(move |t| Some((n, ray_triangle(origin, dir, t)?)))
                })
                .min_by(|x, y| x.1.total_cmp(&y.1));
            let sample = cast_one(scene, origin.to_array(), dir.to_array());
            let Some((expected, t)) = nearest else {
                panic!("{what}: a ray aimed at {name} misses usd-core's triangles");
            };
            let ours = sample.object.as_deref().unwrap_or("nothing");
            if ours.ends_with("Cube") && sample.depth < t {
                continue;
            }
            assert_eq!(ours, expected, "{what}: ray aimed at {name}");
            assert!(
                (sample.depth - t).abs() <= 1e-9 * t,
                "{what}: {name}: depth {} vs {t}",
                sample.depth
            );
            compared += 1;
        }
    }
    compared
}

/// UsdSkel skinning (skel.usda, made with usd-core by tools/make_usd_skel_fixtures.sh) at the
/// default time code and five time codes: raycast's world-space vertices agree with usd-core's
/// skinning transforms and influences combined in double (1e-12 of the scene size), and with
/// usd-core's BakeSkinning, which stores float points (1e-6); rays hit what usd-core's triangles
/// put first, at the same depth. The fixture has an animation that poses two of three joints in
/// its own order, elementSize 2 weights, geomBindTransforms, rigid (constant) bindings of a mesh
/// and a cube, a mesh with its own `skel:joints`, a rest-pose skeleton with weights that do not
/// sum to one, bound meshes that usd-core does not skin (under an untyped prim, outside any
/// SkelRoot), and blend shapes (sparse with two inbetweens, one below 0, and dense) weighed by
/// the animation in its own order (the test fails with blend shapes left out).
#[test]
fn skel_poses_as_usd_core_skins() {
    let reference = reference("skel");
    for case in reference["cases"].as_array().unwrap() {
        let time = case["time"].as_f64();
        let what = format!("skel.usda at {time:?}");
        let scene = load("skel.usda", time, &[]);
        let (vertices, _) = compare(&scene, case, &what);
        let scale = diagonal(&all_points(case));
        let mut from_bake = 0.0f64;
        for mesh in case["meshes"].as_array().unwrap().iter().filter_map(baked) {
            let name = mesh["path"].as_str().unwrap();
            let d = triangle_difference(&object_triangles(&scene, name), &fans(&mesh), name);
            from_bake = from_bake.max(d / scale);
        }
        for cube in case["gprims"].as_array().unwrap().iter().filter_map(baked) {
            let ours = object_triangles(&scene, cube["path"].as_str().unwrap());
            let corners = cube_corners(&cube);
            for v in ours.iter().flatten() {
                let nearest = corners
                    .iter()
                    .map(|c| (*c - *v).length())
                    .fold(f64::INFINITY, f64::min);
                from_bake = from_bake.max(nearest / scale);
            }
        }
        let rays = hits_agree(&scene, case, &what);
        eprintln!("{what}: vertices {vertices:.1e} (double), {from_bake:.1e} (BakeSkinning); {rays} rays agree");
        assert!(
            vertices <= TOLERANCE,
            "{what}: vertices off by {vertices:e}"
        );
        assert!(from_bake <= 1e-6, "{what}: {from_bake:e} from BakeSkinning");
        let skeletons = &scene.stage.as_ref().unwrap().skeletons;
        let arm = skeletons
            .iter()
            .find(|s| s.path == "/World/Arm/Skel")
            .unwrap();
        assert_eq!(arm.joints, 3);
        assert_eq!(arm.animation.as_deref(), Some("/World/Arm/Skel/Anim"));
        assert_eq!(
            arm.skinned,
            [
                "/World/Arm/ArmMesh",
                "/World/Arm/Prop",
                "/World/Arm/Rigid/Cube",
                "/World/Arm/Tip"
            ]
        );
        // The weights are time samples only: none at the default time code.
        let blended: &[&str] = if time.is_some() {
            &["/World/Arm/ArmMesh"]
        } else {
            &[]
        };
        assert_eq!(arm.blend_shaped, blended, "{what}");
    }
}

/// What skinning leaves out says so, naming the prim: dual-quaternion skinning, and blend
/// shapes usd-core would not apply (names and targets of different counts); a skeleton that
/// cannot be posed leaves its prims unskinned with one warning.
#[test]
fn unsupported_skinning_is_named() {
    let text = std::fs::read_to_string(fixture("usd/posed/skel.usda")).unwrap();
    let edited = text
        .replace(
            "uniform token subdivisionScheme = \"none\"\n            matrix4d xformOp:transform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (10, 0, 0, 1) )",
            "uniform token primvars:skel:skinningMethod = \"dualQuaternion\"\n            uniform token subdivisionScheme = \"none\"\n            matrix4d xformOp:transform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (10, 0, 0, 1) )",
        )
        .replace("uniform token[] joints = [\"Root\", \"Root/Tip\"]", "uniform token[] joints = [\"Root/Tip\", \"Root\"]")
        .replace(
            "skel:blendShapes = [\"Bulge\", \"Stretch\"]",
            "skel:blendShapes = [\"Bulge\"]",
        );
    assert_ne!(edited, text);
    let path = temp_file("usd_skel_unsupported", "skel.usda", edited);
    let scene = import::load(
        &path,
        &LoadOptions {
            time: Some(4.0),
            ..LoadOptions::default()
        },
    )
    .unwrap();
    let has = |needle: &str| lines(&scene).iter().filter(|w| w.contains(needle)).count();
    assert_eq!(
        has("/World/Arm/ArmMesh: skel:skinningMethod dualQuaternion is not supported"),
        1,
        "{:?}",
        lines(&scene)
    );
    assert_eq!(
        has("/World/Arm/ArmMesh: 1 skel:blendShapes for 2 skel:blendShapeTargets: blend shapes not applied"),
        1,
        "{:?}",
        lines(&scene)
    );
    assert_eq!(
        has("/World/Rest/Skel: skeleton joint Root/Tip comes before its parent Root"),
        1,
        "{:?}",
        lines(&scene)
    );
    assert!(lines(&scene).iter().all(|w| !w.contains('\n')));
}
