//! Quadric surfaces end to end: every documented ray of fixtures/quadrics (answers computed
//! analytically by `raycast_tools quadric-fixtures` and checked there against mpmath), both
//! coefficient forms, the clip box, cameras inside surfaces, the far sphere, the boundary trap
//! with a large quadric, the mixed octree against brute force, and the extension's errors.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::accel::{brute_force, prepare_ray, Octree, OctreeParams};
use raycast::camera::{Camera, Projection};
use raycast::render::{self, Aov, CameraView};
use raycast::trace::Tracer;
use serde_json::Value;

fn vec3(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|i| v[i].as_f64().unwrap())
}

#[test]
fn every_documented_ray_matches_its_analytic_answer() {
    let text = std::fs::read_to_string(fixture("quadrics/expected_rays.json")).unwrap();
    let expected: serde_json::Map<String, Value> = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (file, entry) in &expected {
        let scene = load(&format!("quadrics/{file}"));
        for r in entry["rays"].as_array().unwrap() {
            let s = cast_one(&scene, vec3(&r["origin"]), vec3(&r["direction"]));
            let label = format!("{file}: {}", r["label"]);
            match r["hit"].as_str() {
                None => assert_miss(&s),
                Some(object) => {
                    assert_eq!(s.object.as_deref(), Some(object), "{label}");
                    let depth = r["depth"].as_f64().unwrap();
                    assert!(
                        (s.depth - depth).abs() <= 1e-12 * depth,
                        "{label}: depth {} vs {depth}",
                        s.depth
                    );
                    let normal = DVec3::from_array(vec3(&r["normal"]));
                    let angle = s.normal.cross(normal).length().atan2(s.normal.dot(normal));
                    assert!(
                        angle <= 1e-10,
                        "{label}: normal {:?} vs {normal:?}",
                        s.normal
                    );
                    if let Some(prim) = r["prim"].as_u64() {
                        assert_eq!(s.prim as u64, prim, "{label}");
                    }
                    if r["kind"] == "quadric" {
                        // A node's quadric is numbered after its mesh's triangles.
                        let owner = scene.objects.iter().find(|o| o.name == object).unwrap();
                        assert_eq!(
                            s.prim, owner.triangles,
                            "{label}: quadric after the triangles"
                        );
                    }
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 150, "{checked} rays");
}

fn render_view(file: &str, eye: DVec3, size: usize) -> render::Buffers {
    let scene = load(file);
    let octree = Octree::build(&scene, OctreeParams::default());
    let tracer = Tracer {
        scene: &scene,
        octree: &octree,
    };
    let camera = Camera::look_at(
        eye,
        DVec3::ZERO,
        DVec3::Y,
        Projection::Perspective { yfov: 0.5 },
    )
    .unwrap();
    let view = CameraView::new(camera, size, size);
    render::render(&tracer, &view, &[Aov::Depth, Aov::Normal, Aov::Id], |_| {})
}

#[test]
fn both_coefficient_forms_give_identical_buffers() {
    let eye = DVec3::new(0.5, 1.0, 10.0);
    let a = render_view("quadrics/sphere_coefficients.gltf", eye, 65);
    let b = render_view("quadrics/sphere_matrices.gltf", eye, 65);
    assert_eq!(a, b);
    assert!(
        a.labels(Aov::Id)
            .unwrap()
            .iter()
            .filter(|&&i| i == 1)
            .count()
            > 1000
    );
}

#[test]
fn sphere_centre_pixel_and_normal() {
    let b = render_view(
        "quadrics/sphere_coefficients.gltf",
        DVec3::new(0.0, 0.0, 10.0),
        65,
    );
    let centre = 32 * 65 + 32;
    assert_eq!(b.floats(Aov::Depth).unwrap()[centre], 8.0);
    assert_eq!(b.vectors(Aov::Normal).unwrap()[centre], [0.0, 0.0, 1.0]);
}

#[test]
fn far_sphere_keeps_its_digits() {
    // A unit sphere at x = 6.4e6 seen from 5 units away: the centre ray's depth is exactly 4.
    let scene = load("quadrics/far_sphere.gltf");
    let s = cast_one(&scene, [6_400_000.0, 0.0, 5.0], [0.0, 0.0, -1.0]);
    assert!((s.depth - 4.0).abs() <= 1e-9 * 4.0, "{}", s.depth);
    let off = cast_one(&scene, [6_400_000.5, 0.0, 5.0], [0.0, 0.0, -1.0]);
    let exact = 5.0 - 0.75f64.sqrt();
    assert!(
        (off.depth - exact).abs() <= 1e-9 * exact,
        "{} vs {exact}",
        off.depth
    );
}

/// Transforming the node equals transforming the rays: the `translated` node of each family is
/// the `canonical` one moved by a known offset, so moving the ray by the same offset must give
/// the same depth. Offsets are read from the files.
#[test]
fn moving_the_node_equals_moving_the_ray() {
    for family in [
        "ellipsoid",
        "cone",
        "hyperboloid_one_sheet",
        "elliptic_paraboloid",
    ] {
        let file = format!("quadrics/{family}.gltf");
        let json: Value = serde_json::from_slice(&std::fs::read(fixture(&file)).unwrap()).unwrap();
        let node = |name: &str| {
            json["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .find(|n| n["name"] == name)
                .unwrap()
                .clone()
        };
        let translation = |name: &str| {
            let t = &node(name)["translation"];
            if t.is_null() {
                DVec3::ZERO
            } else {
                DVec3::from_array(vec3(t))
            }
        };
        let base = translation("canonical");
        let offset = translation("translated") - base;
        let scene = load(&file);
        let mut rng = Rng(11);
        let mut compared = 0;
        for _ in 0..200 {
            let o = base + rng.point(-3.0, 3.0) + DVec3::new(0.0, 0.0, 6.0);
            let d = (base + rng.point(-1.0, 1.0) - o).normalize();
            let a = cast_one(&scene, o.to_array(), d.to_array());
            let b = cast_one(&scene, (o + offset).to_array(), d.to_array());
            if a.object.as_deref() == Some("canonical") {
                assert_eq!(b.object.as_deref(), Some("translated"), "{family}");
                assert!(
                    (a.depth - b.depth).abs() <= 1e-12 * a.depth,
                    "{family}: {} vs {}",
                    a.depth,
                    b.depth
                );
                compared += 1;
            }
        }
        assert!(compared >= 40, "{family}: only {compared} rays hit");
    }
}

#[test]
fn mixed_scene_octree_equals_brute_force() {
    for file in ["quadrics/mixed.gltf", "quadrics/trap_quadric.gltf"] {
        let scene = load(file);
        let octree = Octree::build(&scene, OctreeParams::default());
        let mut rng = Rng(3);
        let bounds = scene.world_bounds();
        for _ in 0..4000 {
            let o = bounds.center() + rng.point(-1.0, 1.0) * bounds.size();
            let d = rng.direction();
            let ray = prepare_ray(&scene, o - scene.anchor, d);
            assert_eq!(
                octree.intersect(&scene, &ray, f64::INFINITY),
                brute_force(&scene, &ray),
                "{file}"
            );
        }
    }
}

#[test]
fn boundary_trap_with_a_large_quadric() {
    let scene = load("quadrics/trap_quadric.gltf");
    let octree = Octree::build(&scene, OctreeParams::default());
    let origin = DVec3::new(6.9375, 1.3125, 12.0) - scene.anchor;
    let dir = DVec3::NEG_Z;
    let ray = prepare_ray(&scene, origin, dir);
    let (prim, t, exit) = naive_first_hit(&scene, &octree, &ray);
    assert_eq!(
        scene.object(prim).name,
        "big_sphere",
        "the sphere is found first"
    );
    assert!(
        t > exit,
        "its hit (t = {t}) lies beyond the cell it was found in (exit {exit})"
    );
    let s = cast_one(&scene, [6.9375, 1.3125, 12.0], [0.0, 0.0, -1.0]);
    assert_hit(&s, "near", 20.1875, [0.0, 0.0, 1.0], &[1]);
}

#[test]
fn bad_quadric_extensions_name_the_node() {
    let dir = std::fs::read_dir(fixture("bad")).unwrap();
    let mut seen = 0;
    for entry in dir {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if !name.starts_with("quadric_") {
            continue;
        }
        let err = raycast::import::load(&path, &Default::default()).expect_err(&name);
        let text = err.to_string();
        assert!(text.contains(&name), "{text}");
        if name != "quadric_nonfinite.gltf" {
            assert!(
                text.contains("/nodes/1") && text.contains("RAYCAST_quadric"),
                "{name}: {text}"
            );
        }
        seen += 1;
    }
    assert!(seen >= 10);
}

#[test]
fn info_classifies_each_family() {
    for (file, kind) in [
        ("ellipsoid", "ellipsoid"),
        ("elliptic_paraboloid", "elliptic_paraboloid"),
        ("hyperbolic_paraboloid", "hyperbolic_paraboloid"),
        ("hyperboloid_one_sheet", "hyperboloid_one_sheet"),
        ("hyperboloid_two_sheets", "hyperboloid_two_sheets"),
        ("cone", "cone"),
        ("cylinder", "elliptic_cylinder"),
        ("hyperbolic_cylinder", "hyperbolic_cylinder"),
        ("parabolic_cylinder", "parabolic_cylinder"),
    ] {
        let scene = load(&format!("quadrics/{file}.gltf"));
        assert_eq!(scene.quadrics().len(), 5, "{file}");
        for q in scene.quadrics() {
            assert_eq!(q.kind().name(), kind, "{file}");
        }
    }
}
