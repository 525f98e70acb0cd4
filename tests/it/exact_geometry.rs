//! Exactness with respect to the file (issue 12): f64 OBJ coordinates, f64 transforms applied
//! to meshes stored in their own frames, instances that answer exactly as their placed copies,
//! and one object per scene object.
//!
//! References are independent of the code under test: depths come from the plane equation of
//! the file's own numbers evaluated in f64 (not the watertight shear), hit/miss near an edge
//! from comparing the ray's coordinates with the edge's (a margin of 1e-7, far above f64
//! rounding at 1e6).

use crate::common;

use common::{cast, cast_one, fixture, load, ray, Rng};
use glam::{DMat4, DQuat, DVec3};
use raycast::accel::{brute_force, prepare_ray, Octree, OctreeParams, PACKET};
use raycast::import::{self, LoadOptions};
use raycast::scene::{Mesh, Scene, SceneBuilder};
use std::sync::Arc;

/// Depth along a unit ray `origin + t dir` to the plane through `tri`, in f64.
fn plane_depth(tri: &[DVec3; 3], origin: DVec3, dir: DVec3) -> f64 {
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
    n.dot(tri[0] - origin) / n.dot(dir)
}

/// The 99.9th percentile of `errors`.
fn p999(mut errors: Vec<f64>) -> f64 {
    errors.sort_by(f64::total_cmp);
    errors[((errors.len() - 1) as f64 * 0.999).round() as usize]
}

#[test]
fn far_obj_triangle_edges_are_decided_by_the_files_numbers() {
    let scene = load("obj/far_triangle.obj");
    let (x0, x1) = (1000000.1_f64, 1000001.1_f64);
    let tri = [
        DVec3::new(x0, 0.0, 0.0),
        DVec3::new(x1, 0.0, 0.3),
        DVec3::new(x0, 1.0, 0.7),
    ];
    let mid = (x0 + x1) / 2.0;
    // (x, y, inside): 1e-7 either side of each of the three edges.
    let points = [
        (x0 + 1e-7, 0.5, true),
        (x0 - 1e-7, 0.5, false),
        (x0 + 0.5, 1e-7, true),
        (x0 + 0.5, -1e-7, false),
        (mid - 1e-7, 0.5, true),
        (mid + 1e-7, 0.5, false),
        (x0 + 0.25, 0.25, true),
    ];
    let down = DVec3::NEG_Z;
    let rays: Vec<_> = points
        .iter()
        .map(|&(x, y, _)| ray([x, y, 10.0], down.to_array()))
        .collect();
    for (&(x, y, inside), s) in points.iter().zip(cast(&scene, &rays)) {
        assert_eq!(s.object.is_some(), inside, "ray at ({x}, {y}): {s:?}");
        if inside {
            let expected = plane_depth(&tri, DVec3::new(x, y, 10.0), down);
            let error = (s.depth - expected).abs() / expected;
            assert!(
                error <= 1e-12,
                "ray at ({x}, {y}): depth {} vs {expected}",
                s.depth
            );
        }
    }
}

/// Rays `margin` inside and outside the middle of each edge of the world triangle `tri`: the
/// point, whether it is inside, and a ray origin 10 units off the plane (tilted, so the ray is
/// not along the normal).
fn edge_rays(tri: &[DVec3; 3], margin: f64) -> Vec<(DVec3, bool, DVec3)> {
    let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
    let mut out = Vec::new();
    for k in 0..3 {
        let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        let mid = (a + b) * 0.5;
        let mut inward = n.cross(b - a).normalize();
        if inward.dot(c - mid) < 0.0 {
            inward = -inward;
        }
        for (sign, inside) in [(1.0, true), (-1.0, false)] {
            let p = mid + inward * (sign * margin);
            let origin = p + (n + (b - a).normalize() * 0.3) * 10.0;
            out.push((p, inside, origin));
        }
    }
    out
}

/// An f32 triangle (as a glTF accessor stores it) placed about 1e5 from the origin by a
/// non-uniform, rotated, mirrored f64 transform: rays 1e-7 inside and outside every edge are
/// decided by the exact placed triangle, whether the mesh is drawn once (placed in the world
/// in f64) or twice (an instance: the ray moves into the mesh frame). The expected side comes
/// from the world triangle computed here in f64 (its rounding, about 3e-11 at 2e5, is far
/// below the 1e-7 margin).
#[test]
fn f32_mesh_under_a_far_f64_transform_decides_every_edge() {
    let local = [
        DVec3::new(0.1, -0.35, 0.2),
        DVec3::new(1.3, 0.05, -0.4),
        DVec3::new(-0.2, 0.9, 0.6),
    ]
    .map(|p| p.as_vec3().as_dvec3());
    let world = DMat4::from_scale_rotation_translation(
        DVec3::new(1.7, -0.6, 2.3),
        DQuat::from_axis_angle(DVec3::new(0.3, -1.0, 0.5).normalize(), 1.1),
        DVec3::new(100000.3, -200000.7, 150000.1),
    );
    let far_away = DMat4::from_translation(DVec3::new(0.0, 0.0, 500.0)) * world;
    let tri = local.map(|p| world.transform_point3(p));
    // 15 more triangles, 40+ units away in the mesh frame, so that two uses make an instance
    let mut soup = vec![local];
    soup.extend((1..16).map(|k| local.map(|p| p + DVec3::new(40.0 * k as f64, 0.0, 0.0))));
    for copies in [1, 2] {
        let mesh = Arc::new(Mesh::from_soup(&soup));
        let mut builder = SceneBuilder::new();
        for (i, w) in [world, far_away].iter().take(copies).enumerate() {
            let id = builder.new_object(format!("copy{i}"), "test".into());
            builder.place_mesh(id, Arc::clone(&mesh), *w);
        }
        let scene = builder.finish("far f32 mesh".into());
        assert_eq!(scene.instances().len(), if copies == 1 { 0 } else { 2 });
        let cases = edge_rays(&tri, 1e-7);
        let rays: Vec<_> = cases
            .iter()
            .map(|(p, _, o)| ray(o.to_array(), (*p - *o).to_array()))
            .collect();
        for ((p, inside, origin), s) in cases.iter().zip(cast(&scene, &rays)) {
            let hit = s.object.as_deref() == Some("copy0") && s.prim == 0;
            assert_eq!(hit, *inside, "{copies} copies, point {p:?}: {s:?}");
            if *inside {
                let dir = (*p - *origin).normalize();
                let expected = plane_depth(&tri, *origin, dir);
                let error = (s.depth - expected).abs() / expected;
                assert!(
                    error <= 1e-10,
                    "{copies} copies: depth {} vs {expected}",
                    s.depth
                );
            }
        }
    }
}

/// A height field over `[lo, hi]²` with `cells²` quads, written with 17 significant digits.
fn write_height_field(path: &std::path::Path, lo: f64, hi: f64, cells: usize, rng: &mut Rng) {
    let step = (hi - lo) / cells as f64;
    let mut text = String::from("o field\n");
    let mut heights = Vec::new();
    for j in 0..=cells {
        for i in 0..=cells {
            let z = 3e5 + rng.uniform(-1.0, 1.0) * 0.2 * step;
            heights.push(z);
            let (x, y) = (lo + i as f64 * step, lo + j as f64 * step);
            let jitter = |v: f64, r: &mut Rng| v + r.uniform(-0.1, 0.1) * step;
            text += &format!(
                "v {:.17e} {:.17e} {z:.17e}\n",
                jitter(x, rng),
                jitter(y, rng)
            );
        }
    }
    let id = |i: usize, j: usize| j * (cells + 1) + i + 1;
    for j in 0..cells {
        for i in 0..cells {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            text += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    std::fs::write(path, text).unwrap();
}

/// The file's vertices, parsed by Rust's own f64 parser (not tobj), and its faces.
fn read_obj(path: &std::path::Path) -> Vec<[DVec3; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut v = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                v.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let i: Vec<usize> = words.map(|w| w.parse::<usize>().unwrap() - 1).collect();
                tris.push([v[i[0]], v[i[1]], v[i[2]]]);
            }
            _ => {}
        }
    }
    tris
}

#[test]
fn far_obj_depths_match_a_float64_evaluation_of_the_file() {
    let dir = std::env::temp_dir().join(format!("raycast-exact-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("far_field.obj");
    let mut rng = Rng(12);
    write_height_field(&path, 1e6, 1e7, 40, &mut rng);
    let scene = import::load(&path, &LoadOptions::default()).unwrap();
    let tris = read_obj(&path);
    std::fs::remove_dir_all(&dir).ok();
    // Rays straight down through interior points of known triangles (barycentric weights at
    // least 0.05, so no rounding decides which triangle is hit).
    let mut rays = Vec::new();
    let mut expected = Vec::new();
    for k in 0..4000 {
        let t = k % tris.len();
        let (mut u, mut v) = (rng.uniform(0.05, 0.9), rng.uniform(0.05, 0.9));
        if u + v > 0.95 {
            (u, v) = (0.95 - v, 0.95 - u);
        }
        let [a, b, c] = tris[t];
        let p = a + (b - a) * u + (c - a) * v;
        let origin = DVec3::new(p.x, p.y, 5e6);
        rays.push(ray(origin.to_array(), [0.0, 0.0, -1.0]));
        expected.push((t as u32, plane_depth(&tris[t], origin, DVec3::NEG_Z)));
    }
    let samples = cast(&scene, &rays);
    let mut errors = Vec::new();
    for (s, (t, depth)) in samples.iter().zip(expected) {
        assert_eq!(s.prim, t, "{s:?}");
        errors.push((s.depth - depth).abs() / depth);
    }
    let p = p999(errors);
    assert!(p <= 1e-12, "p99.9 relative depth error {p:e}");
}

/// A closed, irregular mesh around the origin (a jittered octahedron subdivided twice) as
/// f32 vertex values, like a glTF accessor.
fn f32_mesh(rng: &mut Rng) -> Vec<[DVec3; 3]> {
    let mut tris: Vec<[DVec3; 3]> = Vec::new();
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for signs in 0..8 {
        let s = |i: usize| if signs & (1 << i) != 0 { -1.0 } else { 1.0 };
        let [a, b, c] = [0, 1, 2].map(|i| axes[i] * s(i));
        let flip = s(0) * s(1) * s(2) < 0.0;
        tris.push(if flip { [a, c, b] } else { [a, b, c] });
    }
    for _ in 0..2 {
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let m = |p: DVec3, q: DVec3| ((p + q) * 0.5).normalize();
                let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    let mut jitter = std::collections::HashMap::new();
    tris.iter()
        .map(|t| {
            t.map(|p| {
                let key = p.to_array().map(f64::to_bits);
                *jitter
                    .entry(key)
                    .or_insert_with(|| (p * rng.uniform(0.8, 1.2)).as_vec3().as_dvec3())
            })
        })
        .collect()
}

/// `copies` nested, non-uniform, rotated (and some mirrored) placements `offset` away.
fn placements(rng: &mut Rng, copies: usize, offset: DVec3) -> Vec<DMat4> {
    let parent = DMat4::from_scale_rotation_translation(
        DVec3::new(1.5, 0.7, 1.1),
        DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.4),
        offset,
    );
    (0..copies)
        .map(|i| {
            let mirror = if i % 5 == 0 { -1.0 } else { 1.0 };
            let child = DMat4::from_scale_rotation_translation(
                DVec3::new(
                    mirror * rng.uniform(0.5, 2.0),
                    rng.uniform(0.5, 2.0),
                    rng.uniform(0.5, 2.0),
                ),
                DQuat::from_axis_angle(rng.direction(), rng.uniform(0.0, 3.0)),
                rng.point(-12.0, 12.0),
            );
            parent * child
        })
        .collect()
}

/// The same placements as instances of one stored mesh, and as triangles placed one by one.
fn instanced_and_flat(local: &[[DVec3; 3]], worlds: &[DMat4]) -> (Scene, Scene) {
    let mesh = Arc::new(Mesh::from_soup(local));
    let mut instanced = SceneBuilder::new();
    let mut flat = SceneBuilder::new();
    for (i, world) in worlds.iter().enumerate() {
        let id = instanced.new_object(format!("copy{i}"), "test".into());
        instanced.place_mesh(id, Arc::clone(&mesh), *world);
        let placed = local
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|p| world.transform_point3(p));
                if world.determinant() < 0.0 {
                    [a, c, b]
                } else {
                    [a, b, c]
                }
            })
            .collect();
        flat.add_mesh(format!("copy{i}"), "test".into(), placed);
    }
    (
        instanced.finish("instanced".into()),
        flat.finish("flat".into()),
    )
}

#[test]
fn instances_answer_as_their_placed_copies_far_from_the_origin() {
    let mut rng = Rng(99);
    let local = f32_mesh(&mut rng);
    let offset = DVec3::new(1e5, -2e5, 1.5e5);
    let worlds = placements(&mut rng, 64, offset);
    let (instanced, flat) = instanced_and_flat(&local, &worlds);
    assert_eq!(instanced.instances().len(), 64);
    assert_eq!(instanced.stored_triangle_count(), local.len());
    assert_eq!(instanced.triangle_count(), flat.triangle_count());
    assert_eq!(instanced.objects.len(), 64, "one object per placement");
    let mut rays = Vec::new();
    for k in 0..3000 {
        // Aimed at a point inside (or just around) one of the copies.
        let target = worlds[k % worlds.len()].transform_point3(rng.point(-1.0, 1.0));
        // From 1000 units: each f64 evaluation rounds world coordinates near 2e5 by about
        // 3e-11, which is 3e-14 of such a depth (more on grazing triangles).
        let origin = target + rng.direction() * 1000.0;
        rays.push(ray(
            origin.to_array(),
            (target - origin).normalize().to_array(),
        ));
    }
    let a = cast(&instanced, &rays);
    let b = cast(&flat, &rays);
    let mut errors = Vec::new();
    let mut hits = 0;
    for (x, y) in a.iter().zip(&b) {
        // A ray within rounding of an edge may pick the neighbouring triangle or miss by an
        // ulp in one frame and not the other: count those, never more than a few.
        if x.object != y.object {
            continue;
        }
        if x.object.is_some() {
            hits += 1;
            errors.push((x.depth - y.depth).abs() / y.depth);
            assert!(
                (x.normal - y.normal).length() < 1e-9 || x.prim != y.prim,
                "{x:?} {y:?}"
            );
        }
    }
    let same = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x.object == y.object)
        .count();
    assert!(
        same >= rays.len() - 3,
        "{same} of {} rays agree",
        rays.len()
    );
    assert!(hits > 1000, "{hits} hits");
    let p = p999(errors);
    assert!(p <= 1e-12, "p99.9 relative depth difference {p:e}");
}

#[test]
fn instanced_octree_equals_brute_force_exactly() {
    let mut rng = Rng(5);
    let local = f32_mesh(&mut rng);
    let worlds = placements(&mut rng, 40, DVec3::ZERO);
    let (scene, _) = instanced_and_flat(&local, &worlds);
    let octree = Octree::build(&scene, OctreeParams::default());
    let mut hits = 0;
    for k in 0..3000 {
        let origin = rng.point(-40.0, 40.0);
        let target = worlds[k % worlds.len()].transform_point3(rng.point(-1.0, 1.0));
        let dir = target - origin;
        let prepared = prepare_ray(&scene, origin - scene.anchor, dir);
        let expected = brute_force(&scene, &prepared);
        assert_eq!(octree.intersect(&scene, &prepared, f64::INFINITY), expected);
        hits += usize::from(expected.is_some());
    }
    assert!(hits > 500, "{hits}");
}

/// Packets of eight rays aimed at one copy (through the scene's octree together, and into
/// the instance's own octree together when four or more of them reach it) get exactly the
/// brute-force answers.
#[test]
fn instanced_packets_equal_brute_force_exactly() {
    let mut rng = Rng(6);
    let local = f32_mesh(&mut rng);
    let worlds = placements(&mut rng, 40, DVec3::ZERO);
    let (scene, _) = instanced_and_flat(&local, &worlds);
    let octree = Octree::build(&scene, OctreeParams::default());
    let (mut packets, mut hits) = (0, 0);
    for k in 0..1500 {
        let origin = rng.point(-40.0, 40.0);
        let centre = rng.point(-1.0, 1.0);
        let world = worlds[k % worlds.len()];
        let dirs: [DVec3; PACKET] =
            std::array::from_fn(|_| world.transform_point3(centre + rng.point(-0.2, 0.2)) - origin);
        let origins = [origin - scene.anchor; PACKET];
        let Some(found) =
            octree.intersect_packet(&scene, &origins, &dirs, &[f64::INFINITY; PACKET])
        else {
            continue;
        };
        packets += 1;
        for i in 0..PACKET {
            let expected = brute_force(&scene, &prepare_ray(&scene, origins[i], dirs[i]));
            assert_eq!(found[i], expected, "ray {i} of packet {k}");
            hits += usize::from(expected.is_some());
        }
    }
    assert!(
        packets > 1000 && hits > 3000,
        "{packets} packets, {hits} hits"
    );
}

#[test]
fn a_mesh_drawn_by_several_gltf_nodes_is_one_object_per_node_and_stored_once() {
    // fixtures/gltf/instances.gltf: one 12-triangle mesh drawn by five nodes (one a child).
    let scene = load("gltf/instances.gltf");
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c", "d", "mirror"]);
    assert!(scene.objects.iter().all(|o| o.triangles == 12));
}

#[test]
fn obj_vertices_keep_their_f64_digits() {
    let scene = load("obj/far_triangle.obj");
    let object = &scene.objects[0];
    let tris = scene.mesh_triangles(object);
    assert_eq!(tris, read_obj(&fixture("obj/far_triangle.obj")));
}

/// A PointInstancer's half-precision orientation goes into the rotation matrix as stored, not
/// normalised, as usd-core's ComputeInstanceTransformsAtTime does. Expected: the rows of the
/// matrix usd-core 25 computes for this file (Gf row vectors = images of the basis vectors);
/// the unit cube prototype (±1) then spans Σ|row_i[axis]| on each axis.
#[test]
fn point_instancer_orientations_are_not_normalised() {
    let dir = std::env::temp_dir().join(format!("raycast-pi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("pi.usda");
    std::fs::write(
        &path,
        "#usda 1.0\n\ndef PointInstancer \"pi\"\n{\n    rel prototypes = </pi/proto>\n    \
         int[] protoIndices = [0]\n    point3f[] positions = [(0, 0, 0)]\n    \
         quath[] orientations = [(0.9, 0.3, 0.2, 0.1)]\n\n    def Cube \"proto\"\n    {\n    }\n}\n",
    )
    .unwrap();
    let scene = import::load(&path, &LoadOptions::default()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let rows: [[f64; 3]; 3] = [
        [0.9000488221645355, 0.2999267578125, -0.29987794160842896],
        [
            -0.059946298599243164,
            0.7999511659145355,
            0.5800097584724426,
        ],
        [0.4198681712150574, -0.500048816204071, 0.7399804592132568],
    ];
    let half = DVec3::from_array([0, 1, 2].map(|axis| rows.iter().map(|r| r[axis].abs()).sum()));
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.objects[0].name, "/pi[0]");
    let b = scene.object_bounds(&scene.objects[0]);
    assert!(
        (b.max - half).abs().max_element() < 1e-12,
        "{:?} vs {half:?}",
        b.max
    );
    assert!(
        (b.min + half).abs().max_element() < 1e-12,
        "{:?} vs {:?}",
        b.min,
        -half
    );
}

/// A ray that crosses the edge a sliver (area 3.4e-14, from a real asset) shares with an
/// ordinary triangle: rounding lets the sliver take the hit (watertightness allows either),
/// and the depth must still be the plane's, x = X exactly for both triangles. Computed from
/// the sliver's edge functions, which are all rounding, it was 271.10 instead of 272.697.
#[test]
fn a_sliver_taking_a_hit_by_rounding_reports_the_planes_depth() {
    let scene = load("obj/sliver.obj");
    let x = 72.83469063193799;
    let origin = [193.82045915301438, -63.1049293464078, 358.4737645293767];
    let dir = [-0.3876974688498787, 0.258514894781906, -0.7392454277334576];
    let s = cast_one(&scene, origin, dir);
    let expected = (x - origin[0]) / dir[0] * DVec3::from_array(dir).length();
    assert!(s.object.is_some(), "{s:?}");
    let error = (s.depth - expected).abs() / expected;
    assert!(error <= 1e-12, "depth {} vs {expected}: {s:?}", s.depth);
}
