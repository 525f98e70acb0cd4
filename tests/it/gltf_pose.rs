//! glTF posing without an animation playing (issue 28): morph targets at their default weights
//! and skinned meshes placed by their joints, against three.js's GLTFLoader. The expected
//! vertices in fixtures/posed/three/*.json are three.js's world-space vertices of every mesh
//! (tools/npm/pose_reference.mjs, made by tools/make_pose_fixtures.sh); nothing here computes a
//! pose with raycast's code. Ray answers are checked against a plain ray-triangle test over
//! three.js's triangles, ids and prims included: a hit must name, by its object's glTF node and
//! its prim, a triangle of the file's numbering that the ray crosses at that depth.

use crate::common;
use common::*;
use glam::DVec3;
use raycast::geometry::Ray;
use raycast::scene::Scene;
use serde_json::Value;

/// The files of fixtures/posed with a three.js reference of their rest pose.
const FILES: &[&str] = &[
    "AnimatedMorphCube.glb",
    "AnimatedTriangle.gltf",
    "BoxAnimated.glb",
    "CesiumMan.glb",
    "Fox.glb",
    "InterpolationTest.glb",
    "RiggedFigure.glb",
    "SimpleSkin.gltf",
    "morph-sparse.gltf",
    "morph-sparse.draco.glb",
    "morph-sparse.meshopt.glb",
    "skins-shared.gltf",
    "skins-shared.draco.glb",
    "morph-animated.gltf",
    "morph-animated.draco.glb",
    "morph-animated.meshopt.glb",
    "skins-animated.gltf",
    "skins-animated.draco.glb",
    "skins-animated.meshopt.glb",
];

/// Largest vertex difference allowed, relative to the scene's size.
const TOLERANCE: f64 = 1e-9;

/// The three.js references at a time: (the fixture, the reference's name, time, animation).
fn timed_cases() -> Vec<(String, String, f64, Option<String>)> {
    let mut cases = Vec::new();
    for entry in std::fs::read_dir(fixture("posed/three")).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        let stem = name.trim_end_matches(".json").to_string();
        let json = read_json(&stem);
        let Some(time) = json["time"].as_f64() else {
            continue;
        };
        let end = [".glb", ".gltf"]
            .iter()
            .filter_map(|e| stem.find(e).map(|i| i + e.len()))
            .min()
            .unwrap();
        let animation = json["animation"].as_u64().map(|a| a.to_string());
        cases.push((stem[..end].to_string(), stem, time, animation));
    }
    cases.sort_by(|a, b| a.1.cmp(&b.1));
    cases
}

/// Reference `name` (fixtures/posed/three/NAME.json).
fn read_json(name: &str) -> Value {
    let path = fixture(&format!("posed/three/{name}.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    serde_json::from_str(&text).unwrap()
}

/// A fixture of fixtures/posed posed at `time` by `animation` (all: `None`).
fn load_at(file: &str, time: f64, animation: Option<String>) -> Scene {
    let options = raycast::import::LoadOptions {
        time: Some(time),
        animation,
        ..Default::default()
    };
    raycast::import::load(&fixture(&format!("posed/{file}")), &options)
        .unwrap_or_else(|e| panic!("{file} at {time}: {e}"))
}

/// three.js's world triangles of each glTF node it draws: (node index, triangles).
fn reference(name: &str) -> Vec<(usize, Vec<[DVec3; 3]>)> {
    let json = read_json(name);
    let numbers = |v: &Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|node| {
            let mut triangles = Vec::new();
            for prim in node["primitives"].as_array().unwrap() {
                let p = numbers(&prim["positions"]);
                let vertex = |i: f64| {
                    let i = i as usize * 3;
                    DVec3::new(p[i], p[i + 1], p[i + 2])
                };
                let indices = numbers(&prim["indices"]);
                triangles.extend(
                    indices
                        .chunks_exact(3)
                        .map(|c| [vertex(c[0]), vertex(c[1]), vertex(c[2])]),
                );
            }
            (node["node"].as_u64().unwrap() as usize, triangles)
        })
        .collect()
}

/// The diagonal of the bounds of all triangles.
fn size(triangles: &[[DVec3; 3]]) -> f64 {
    let corners = triangles.iter().flatten();
    let lo = corners.clone().fold(DVec3::INFINITY, |a, &b| a.min(b));
    let hi = corners.fold(DVec3::NEG_INFINITY, |a, &b| a.max(b));
    (hi - lo).length()
}

/// Largest corner difference between our triangles and three.js's, node by node, relative to
/// the scene size. A mirroring node transform makes us store a triangle's last two corners
/// swapped (so that counter-clockwise stays the front): either order is accepted.
fn vertex_difference(scene: &Scene, reference: &[(usize, Vec<[DVec3; 3]>)]) -> f64 {
    let all: Vec<[DVec3; 3]> = reference.iter().flat_map(|(_, t)| t.clone()).collect();
    let scale = size(&all);
    let mut largest = 0.0f64;
    for (node, expected) in reference {
        let source = format!("/nodes/{node}");
        let object = scene
            .objects
            .iter()
            .find(|o| o.source == source)
            .unwrap_or_else(|| panic!("no object for {source}"));
        let ours = scene.mesh_triangles(object);
        assert_eq!(ours.len(), expected.len(), "{source}: triangle counts");
        for (a, b) in ours.iter().zip(expected) {
            let d = |x: [DVec3; 3]| (0..3).map(|k| (x[k] - b[k]).length()).fold(0.0, f64::max);
            largest = largest.max(d(*a).min(d([a[0], a[2], a[1]])));
        }
    }
    largest / scale
}

/// The ray parameter where `ray` crosses triangle `[a, b, c]` (Möller–Trumbore in f64), and
/// its least barycentric coordinate (negative outside), if the ray is not parallel to it.
fn crossing([a, b, c]: &[DVec3; 3], origin: DVec3, dir: DVec3) -> Option<(f64, f64)> {
    let (e1, e2) = (*b - *a, *c - *a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = origin - *a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    Some((t, u.min(v).min(1.0 - u - v)))
}

/// The nearest hit's ray parameter on the reference's triangles, and whether the ray passes
/// within `margin` (in barycentric terms) of some triangle's edge.
fn reference_hit(
    reference: &[(usize, Vec<[DVec3; 3]>)],
    origin: DVec3,
    dir: DVec3,
    margin: f64,
) -> (Option<f64>, bool) {
    let (mut nearest, mut near_edge) = (None::<f64>, false);
    for triangle in reference.iter().flat_map(|(_, t)| t) {
        let Some((t, least)) = crossing(triangle, origin, dir).filter(|c| c.0 > 0.0) else {
            continue;
        };
        near_edge |= least.abs() <= margin;
        if least >= 0.0 && nearest.is_none_or(|n| t < n) {
            nearest = Some(t);
        }
    }
    (nearest, near_edge)
}

/// Whether the sample's object and prim name a reference triangle (the object drawn from its
/// glTF node, the prim its index among that node's triangles: the file's numbering, which
/// posing must not change) that the ray crosses at the sample's depth.
fn names_the_hit_triangle(
    scene: &Scene,
    reference: &[(usize, Vec<[DVec3; 3]>)],
    sample: &Sample,
    (origin, dir): (DVec3, DVec3),
    tolerance: f64,
) -> bool {
    let Some(source) = source_of(scene, sample) else {
        return false;
    };
    let triangle = reference
        .iter()
        .find(|(node, _)| format!("/nodes/{node}") == source)
        .and_then(|(_, triangles)| triangles.get(sample.prim as usize));
    triangle
        .and_then(|triangle| crossing(triangle, origin, dir))
        .is_some_and(|(t, least)| {
            least >= -1e-9 && (t * dir.length() - sample.depth).abs() <= tolerance
        })
}

/// 2000 rays from a sphere around the reference bounds toward points inside them: how many
/// agree in hit or miss and depth (to 1e-9 of the scene size) with the reference, how many were left out for passing
/// within 1e-9 of an edge, and the hits among the agreeing rays. A hit agrees only where its
/// object and prim name a reference triangle the ray crosses at that depth (coincident
/// triangles, as BoxAnimated's two-sided faces, tie: either is the hit).
fn ray_agreement(scene: &Scene, reference: &[(usize, Vec<[DVec3; 3]>)]) -> (usize, usize, usize) {
    let all: Vec<[DVec3; 3]> = reference.iter().flat_map(|(_, t)| t.clone()).collect();
    let corners = all.iter().flatten();
    let lo = corners.clone().fold(DVec3::INFINITY, |a, &b| a.min(b));
    let hi = corners.fold(DVec3::NEG_INFINITY, |a, &b| a.max(b));
    let (centre, radius) = ((lo + hi) / 2.0, (hi - lo).length().max(1e-6));
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let rays: Vec<(DVec3, DVec3)> = (0..2000)
        .map(|_| {
            let origin = centre + rng.direction() * radius * 1.5;
            let target = DVec3::new(
                rng.uniform(lo.x, hi.x),
                rng.uniform(lo.y, hi.y),
                rng.uniform(lo.z, hi.z),
            );
            (origin, target - origin)
        })
        .collect();
    let samples = cast(
        scene,
        &rays
            .iter()
            .map(|&(o, d)| Ray::new(o, d))
            .collect::<Vec<_>>(),
    );
    let (mut agree, mut skipped, mut hits) = (0, 0, 0);
    for ((origin, dir), sample) in rays.iter().zip(&samples) {
        let (expected, near_edge) = reference_hit(reference, *origin, *dir, 1e-9);
        if near_edge {
            skipped += 1;
            continue;
        }
        let same = match expected {
            None => sample.depth == f64::INFINITY,
            Some(t) => {
                let tolerance = TOLERANCE * radius;
                (sample.depth - t * dir.length()).abs() <= tolerance
                    && names_the_hit_triangle(scene, reference, sample, (*origin, *dir), tolerance)
            }
        };
        agree += same as usize;
        hits += (same && expected.is_some()) as usize;
    }
    (agree, skipped, hits)
}

/// The source (`/nodes/N`) of the object a sample hit.
fn source_of(scene: &Scene, sample: &Sample) -> Option<String> {
    let name = sample.object.as_deref()?;
    let object = scene.objects.iter().find(|o| o.name == name)?;
    Some(object.source.clone())
}

#[test]
fn posed_vertices_agree_with_three_js() {
    let mut failed = Vec::new();
    for file in FILES {
        let scene = load(&format!("posed/{file}"));
        let reference = reference(file);
        let d = vertex_difference(&scene, &reference);
        println!("{file}: largest vertex difference {d:.2e} of the scene size");
        if d > TOLERANCE {
            failed.push(format!("{file}: {d:.2e}"));
        }
    }
    assert!(failed.is_empty(), "vertices differ: {failed:?}");
}

#[test]
fn rays_agree_with_three_js_triangles() {
    let mut failed = Vec::new();
    for file in FILES {
        let scene = load(&format!("posed/{file}"));
        let (agree, skipped, hits) = ray_agreement(&scene, &reference(file));
        println!(
            "{file}: {agree} of 2000 rays agree ({hits} hits), {skipped} within 1e-9 of an edge"
        );
        if agree + skipped != 2000 || skipped >= 20 {
            failed.push(format!(
                "{file}: {} disagree, {skipped} skipped",
                2000 - agree - skipped
            ));
        }
    }
    assert!(failed.is_empty(), "rays disagree: {failed:?}");
}

#[test]
fn animated_vertices_and_rays_agree_with_three_js() {
    let cases = timed_cases();
    assert!(cases.len() >= 26, "{} timed references", cases.len());
    let mut failed = Vec::new();
    for (file, name, time, animation) in cases {
        let scene = load_at(&file, time, animation);
        let reference = reference(&name);
        let d = vertex_difference(&scene, &reference);
        let (agree, skipped, hits) = ray_agreement(&scene, &reference);
        println!(
            "{name}: largest vertex difference {d:.2e}; {agree} of 2000 rays agree ({hits} hits), {skipped} within 1e-9 of an edge"
        );
        if d > TOLERANCE || agree + skipped != 2000 || skipped >= 20 {
            failed.push(format!(
                "{name}: {d:.2e}, {} rays disagree",
                2000 - agree - skipped
            ));
        }
    }
    assert!(failed.is_empty(), "{failed:?}");
}

#[test]
fn skinned_meshes_no_longer_warn_of_a_bind_pose() {
    let scene = load("posed/CesiumMan.glb");
    assert!(
        !lines(&scene).iter().any(|w| w.contains("bind pose")),
        "{:?}",
        lines(&scene)
    );
}
