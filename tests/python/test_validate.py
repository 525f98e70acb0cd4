"""Tests of `python -m raycast_tools validate` (tools/raycast_tools/validate/validate.py) and
the quadric reference (tools/raycast_tools/reference/quadric_reference.py).

Run: .venv/bin/python -m pytest tests/python
The end-to-end checks against the real binary skip when target/release/raycast
does not exist; validate's own plumbing is exercised with tests/python/fake_raycast.py.
"""

import json
import math
import os
import stat
import subprocess
import sys

import numpy as np
import pytest
from binary import RAYCAST, ROOT, needs_binary

from raycast_tools.rays import camera_rays
from raycast_tools.reference import quadric_reference as qr
from raycast_tools.validate import validate

FIXTURES = ROOT / "fixtures"


# ------------------------------------------------------------------ helpers


def header(*nodes):
    return {
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "scene": 0,
        "nodes": list(nodes),
    }


def qnode(name, ext, **trs):
    n = {"name": name, "extensions": {qr.EXT: ext}}
    n.update(trs)
    return n


SPHERE2 = {"coefficients": [1, 1, 1, 0, 0, 0, 0, 0, 0, -4]}


@pytest.fixture
def fake_raycast(tmp_path):
    script = tmp_path / "raycast"
    script.write_text(
        f'#!/bin/sh\nexec {sys.executable} {ROOT / "tests" / "python" / "fake_raycast.py"} "$@"\n'
    )
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    return script


def quadric_scene(tmp_path):
    h = header(
        qnode("ball", SPHERE2),
        qnode(
            "tube",
            {
                "Q": [1, 0, 0, 0, 1, 0, 0, 0, 0],
                "P": [0, 0, 0],
                "R": -1,
                "bounds": {"min": [-1, -1, -2], "max": [1, 1, 2]},
            },
            translation=[6, 0, 0],
            rotation=[0.2, 0.3, 0.1, 0.927],
            scale=[1, 1.5, 0.7],
        ),
    )
    h["asset"] = {"version": "2.0"}
    h["extensionsUsed"] = [qr.EXT]
    p = tmp_path / "quadrics.gltf"
    p.write_text(json.dumps(h))
    return p


# ------------------------------------------------------------------ quadric reference


def test_sphere_hand_computed():
    q = qr.quadrics_from_header(header(qnode("s", SPHERE2)))[0]
    o = np.array([[0, 0, 5.0], [0, 0, 5.0], [0, 0, 0.0], [0, 3, 5.0], [0, 0, 5.0]])
    d = np.array([[0, 0, -1.0], [0, 0, -10.0], [1, 0, 0.0], [0, 0, -1.0], [0, 0, 1.0]])
    r = qr.intersect_quadric(q, o, d)
    assert r["depth"][0] == pytest.approx(3.0, rel=1e-15)
    assert r["depth"][1] == pytest.approx(3.0, rel=1e-15)  # |d| = 10: depth = t|d|
    assert r["t"][1] == pytest.approx(0.3, rel=1e-15)
    assert r["depth"][2] == pytest.approx(2.0, rel=1e-15)  # from inside: far root
    assert np.allclose(r["normal"][2], [1, 0, 0])  # toward f > 0 (outward)
    assert not np.isfinite(r["depth"][3])  # passes at distance 3 > 2
    assert not np.isfinite(r["depth"][4])  # sphere behind the origin
    assert np.allclose(r["normal"][0], [0, 0, 1])
    assert not r["tangent"][:3].any()


def test_sphere_tangent_flagged():
    q = qr.quadrics_from_header(header(qnode("s", SPHERE2)))[0]
    o = np.array([[2.0, 0, 5.0], [2.0 + 1e-8, 0, 5.0], [1.0, 0, 5.0]])
    d = np.array([[0, 0, -1.0]] * 3)
    r = qr.intersect_quadric(q, o, d)
    assert r["tangent"][0] and r["tangent"][1]
    assert not r["tangent"][2]


def test_transformed_sphere_and_translation_far_away():
    # radius-2 sphere scaled by 3 and moved to x = 1e5: radius 6, hit from 10 units away
    h = header(qnode("s", SPHERE2, translation=[1e5, 0, 0], scale=[3, 3, 3]))
    q = qr.quadrics_from_header(h)[0]
    r = qr.intersect_quadric(q, np.array([[1e5, 0, 16.0]]), np.array([[0, 0, -2.0]]))
    assert r["depth"][0] == pytest.approx(10.0, rel=1e-14)
    assert np.allclose(r["normal"][0], [0, 0, 1], atol=1e-15)


def test_clipped_cylinder_near_then_far_root():
    # infinite cylinder x²+y² = 1 clipped to z in [-1, 1]
    cyl = {
        "Q": [1, 0, 0, 0, 1, 0, 0, 0, 0],
        "P": [0, 0, 0],
        "R": -1,
        "bounds": {"min": [-2, -2, -1], "max": [2, 2, 1]},
    }
    q = qr.quadrics_from_header(header(qnode("c", cyl)))[0]
    # slanted ray: near root at z > 1 (clipped away), far root inside the box
    o = np.array([[-5.0, 0, 3.5]])
    d = np.array([[1.0, 0, -0.5]])
    r = qr.intersect_quadric(q, o, d)
    # roots at x = -1 (t = 4, z = 1.5: clipped) and x = 1 (t = 6, z = 0.5)
    assert r["t"][0] == pytest.approx(6.0, rel=1e-15)
    assert np.allclose(r["normal"][0], [1, 0, 0])  # gradient, not flipped to the ray
    # along the axis: K = 0, no hit on the infinite side wall
    r = qr.intersect_quadric(q, np.array([[0.0, 0, 5]]), np.array([[0, 0, -1.0]]))
    assert not np.isfinite(r["t"][0])


def test_clip_face_flagged():
    cyl = {
        "coefficients": [1, 1, 0, 0, 0, 0, 0, 0, 0, -1],
        "bounds": {"min": [-2, -2, -1], "max": [2, 2, 1]},
    }
    q = qr.quadrics_from_header(header(qnode("c", cyl)))[0]
    r = qr.intersect_quadric(
        q, np.array([[-5.0, 0, 1.0], [-5.0, 0, 0.0]]), np.array([[1.0, 0, 0], [1.0, 0, 0]])
    )
    assert r["clip"][0] and not r["clip"][1]


def test_cross_terms_enter_halved():
    # x² + y² + z² + 2xy - 4 = (x+y)² + z² - 4: the ray along y=-x lies in a cylinder
    # of radius 2 around that line; from (0,0,5) straight down hits z = 2
    q = qr.quadrics_from_header(
        header(
            qnode(
                "s",
                {
                    "coefficients": [1, 1, 1, 2, 0, 0, 0, 0, 0, -4],
                    "bounds": {"min": [-5, -5, -5], "max": [5, 5, 5]},
                },
            )
        )
    )[0]
    r = qr.intersect_quadric(q, np.array([[0.0, 0, 5]]), np.array([[0, 0, -1.0]]))
    assert r["depth"][0] == pytest.approx(3.0, rel=1e-15)


def test_matrix_node_and_children():
    h = {
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {
                "name": "parent",
                "matrix": [2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 10, 0, 0, 1],
                "children": [1],
            },
            qnode("child", SPHERE2, translation=[0, 1, 0]),
        ],
    }
    q = qr.quadrics_from_header(h)[0]
    assert np.allclose(q.world[:3, 3], [10, 2, 0])
    r = qr.trace([q], np.array([[10.0, 2, 10]]), np.array([[0, 0, -1.0]]))
    assert r["depth"][0] == pytest.approx(6.0, rel=1e-15)  # radius 4 after scale 2
    assert r["name"][0] == "child" and r["node"][0] == 1


def test_ellipsoid_bounds():
    h = header(qnode("e", {"coefficients": [1, 4, 9, 0, 0, 0, 0, 0, 0, -1]}, translation=[1, 2, 3]))
    lo, hi = qr.quadrics_from_header(h)[0].world_bounds()
    assert np.allclose(lo, [0, 1.5, 3 - 1 / 3]) and np.allclose(hi, [2, 2.5, 3 + 1 / 3])


@pytest.mark.parametrize("seed", range(4))
def test_float64_matches_mpmath(seed):
    rng = np.random.default_rng(seed)
    # random symmetric Q (mixed signs: hyperboloids too), random TRS, clip box
    c = rng.normal(size=10)
    c[9] = -abs(c[9]) - 0.5
    ext = {"coefficients": c.tolist(), "bounds": {"min": [-3, -3, -3], "max": [3, 3, 3]}}
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    h = header(
        qnode(
            "q",
            ext,
            translation=(rng.normal(size=3) * 100).tolist(),
            rotation=quat.tolist(),
            scale=rng.uniform(0.3, 3, 3).tolist(),
        )
    )
    q = qr.quadrics_from_header(h)[0]
    n = 40
    origins = q.t + rng.normal(size=(n, 3)) * 20
    targets = q.t + rng.normal(size=(n, 3)) * 2
    dirs = (targets - origins) * rng.uniform(0.2, 5, (n, 1))
    f = qr.intersect_quadric(q, origins, dirs)
    hits = 0
    for i in range(n):
        t, depth, normal, _ = qr.intersect_quadric_mp(q, origins[i], dirs[i], prec=120)
        if f["tangent"][i] or f["clip"][i]:
            continue
        assert np.isfinite(depth) == np.isfinite(f["depth"][i]), i
        if np.isfinite(depth):
            hits += 1
            assert f["depth"][i] == pytest.approx(depth, rel=1e-12)
            ang = math.atan2(
                np.linalg.norm(np.cross(normal, f["normal"][i])), np.dot(normal, f["normal"][i])
            )
            assert ang < 1e-10
    assert hits > 0


def test_trace_nearest_and_ties():
    h = header(
        qnode("a", SPHERE2), qnode("b", SPHERE2, translation=[0, 0, -10]), qnode("c", SPHERE2)
    )  # c coincides with a: a tie
    qs = qr.quadrics_from_header(h)
    r = qr.trace(qs, np.array([[0, 0, 5.0], [0, 0, -20.0]]), np.array([[0, 0, -1.0], [0, 0, 1.0]]))
    assert r["depth"][0] == pytest.approx(3.0) and "tie" in r["reasons"][0]
    assert r["name"][1] == "b" and r["depth"][1] == pytest.approx(8.0)
    assert not r["ambiguous"][1]


def test_merge_with_mesh_hits():
    qs = qr.quadrics_from_header(header(qnode("a", SPHERE2)))
    r = qr.trace(qs, np.array([[0, 0, 5.0], [0, 0, 5.0]]), np.array([[0, 0, -1.0]] * 2))
    m = qr.merge_hits(
        r, np.array([1.0, np.inf]), np.array([[0, 0, 1.0], [0, 0, 0]]), np.array([7, -1])
    )
    assert list(m["kind"]) == ["mesh", "quadric"]
    assert m["depth"][0] == 1.0 and m["node"][0] == 7 and m["depth"][1] == pytest.approx(3.0)


# ------------------------------------------------------------------ validate internals


def test_camera_rays_contract():
    C = np.eye(4)
    C[2, 3] = 5
    cam = {"type": "perspective", "yfov": math.pi / 2, "camera_to_world": C.tolist()}
    o, u, d = camera_rays(cam, 4, 2)
    assert o.shape == (8, 3) and np.allclose(o, [0, 0, 5])
    # pixel (i=0, j=0): sx = -0.75, sy = 0.5; tan(45°) = 1, aspect 2
    assert np.allclose(d[0], [-0.75 * 2, 0.5, -1])
    # row 0 is the top row: y > 0; last pixel bottom right
    assert np.allclose(d[7], [0.75 * 2, -0.5, -1])
    cam = {"type": "orthographic", "xmag": 9, "ymag": 1.0, "camera_to_world": C.tolist()}
    o, u, d = camera_rays(cam, 4, 2)
    assert np.allclose(o[0], [-0.75 * 2, 0.5, 5])  # xmag recomputed as ymag * W / H
    assert np.allclose(d, [0, 0, -1])


def test_precheck_reasons():
    assert "sparse" in validate.gltf_precheck({"accessors": [{"sparse": {}}]})
    assert "Draco" in validate.gltf_precheck({"extensionsUsed": ["KHR_draco_mesh_compression"]})
    assert validate.gltf_precheck({"scenes": [{"nodes": []}], "nodes": [{}]}) is None


def test_find_scenes_skips_bad_folder():
    found = dict((p.name, r) for p, r in validate.find_scenes([FIXTURES]))
    bad = [n for n, r in found.items() if r and ("bad/" in r or "fuzz/" in r)]
    if (FIXTURES / "bad").exists():
        assert bad
    assert "tobj_texcoord_index_overflow.obj" in bad
    assert all(r is None for n, r in found.items() if n.endswith(".obj") and n not in bad)


def test_node_names_reproduce_trimesh():
    import trimesh

    p = FIXTURES / "gltf" / "instances.gltf"
    if not p.exists():
        pytest.skip("fixtures/gltf/instances.gltf missing")
    ref = validate.load_reference(p)
    scene = trimesh.load(str(p), force="scene")
    assert sum(len(o.tris) for o in ref.objects) == sum(
        len(scene.geometry[scene.graph[f][1]].faces) for f in scene.graph.nodes_geometry
    )
    assert all(o.node >= 0 for o in ref.objects)


def scenes_for_plumbing():
    names = [
        "gltf/cube.gltf",
        "gltf/instances.gltf",
        "obj/two_objects.obj",
        "assets/ShapeCollection.glb",
    ]
    return [FIXTURES / n for n in names if (FIXTURES / n).exists()]


@pytest.mark.parametrize("scene", scenes_for_plumbing(), ids=lambda p: p.name)
def test_validate_with_fake_raycast(scene, fake_raycast):
    reps = validate.validate_scene(scene, fake_raycast, nrays=300, seed=1, camera=True)
    assert [r["mode"] for r in reps] == ["rays", "camera"]
    for r in reps:
        assert r["status"] == "ok", r
        assert r["checks"]["hitmiss_agreement"]["value"] == 1.0
        assert r["object_match"]["unmatched"] == 0


def test_validate_notices_broken_outputs(fake_raycast, monkeypatch):
    scene = FIXTURES / "assets" / "ShapeCollection.glb"
    if not scene.exists():
        pytest.skip("fixture missing")
    for brk, check in (
        ("depth", "depth_rel_p99"),
        ("id", "id_agreement"),
        ("normal", "normal_flipped_max"),
    ):
        monkeypatch.setenv("FAKE_RAYCAST_BREAK", brk)
        r = validate.validate_scene(scene, fake_raycast, nrays=200, seed=2)[0]
        assert r["status"] == "FAIL" and not r["checks"][check]["ok"], (brk, r["checks"])


def test_validate_quadric_scene_with_fake(tmp_path, fake_raycast):
    p = quadric_scene(tmp_path)
    r = validate.validate_scene(p, fake_raycast, nrays=400, seed=3)[0]
    assert r["status"] == "ok", r
    assert r["quadrics"] == 2 and r["hits_ref"] > 100
    assert r["checks"]["quadric_depth_rel_max"]["value"] < 1e-12


def test_cli_exit_codes(tmp_path, fake_raycast):
    scene = FIXTURES / "gltf" / "cube.gltf"
    if not scene.exists():
        pytest.skip("fixture missing")
    cmd = [
        sys.executable,
        "-m",
        "raycast_tools",
        "validate",
        str(scene),
        "--rays",
        "100",
        "--raycast",
        str(fake_raycast),
        "--json",
    ]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["ok"] is True
    p = subprocess.run(
        cmd, capture_output=True, text=True, env=dict(os.environ, FAKE_RAYCAST_BREAK="depth")
    )
    assert p.returncode == 1
    p = subprocess.run(
        cmd[:4] + [str(scene), "--raycast", str(tmp_path / "nope")], capture_output=True, text=True
    )
    assert p.returncode == 2


# ------------------------------------------------------------------ the real binary


def real_scenes():
    out = []
    for sub in ("gltf", "obj", "ply", "stl"):
        d = FIXTURES / sub
        if d.exists():
            out += [p for p, skip in validate.find_scenes([d]) if skip is None]
    return out


@needs_binary
@pytest.mark.parametrize("scene", real_scenes(), ids=lambda p: p.name)
def test_raycast_within_tolerance(scene):
    reps = validate.validate_scene(scene, RAYCAST, nrays=500, seed=0, camera=True)
    for r in reps:
        assert r["status"] in ("ok", "skip"), json.dumps(r, default=str)[:2000]


@needs_binary
def test_raycast_quadrics_within_tolerance(tmp_path):
    p = quadric_scene(tmp_path)
    r = validate.validate_scene(p, RAYCAST, nrays=1000, seed=0)[0]
    assert r["status"] == "ok", json.dumps(r, default=str)[:2000]


def mixed_scene(tmp_path):
    """fixtures/gltf/cube.gltf plus two quadric nodes: a sphere beside the cube and an
    ellipsoid half-buried in it."""
    import shutil

    src = FIXTURES / "gltf" / "cube.gltf"
    if not src.exists():
        pytest.skip("fixtures/gltf/cube.gltf missing")
    h = json.loads(src.read_text())
    shutil.copy(FIXTURES / "gltf" / "cube.bin", tmp_path / "cube.bin")
    n = len(h["nodes"])
    h["nodes"].append(qnode("ball", SPHERE2, translation=[4, 0, 0]))
    h["nodes"].append(
        qnode("egg", {"coefficients": [1, 4, 1, 0, 0, 0, 0, 0, 0, -1]}, translation=[0, 1, 0])
    )
    h["scenes"][0]["nodes"] += [n, n + 1]
    h.setdefault("extensionsUsed", []).append(qr.EXT)
    p = tmp_path / "mixed.gltf"
    p.write_text(json.dumps(h))
    return p


def test_validate_mixed_scene_with_fake(tmp_path, fake_raycast):
    p = mixed_scene(tmp_path)
    r = validate.validate_scene(p, fake_raycast, nrays=400, seed=4)[0]
    assert r["status"] == "ok", r
    assert r["triangles"] == 12 and r["quadrics"] == 2
    assert "id_agreement" in r["checks"] and "quadric_id_agreement" in r["checks"]


@needs_binary
def test_raycast_mixed_within_tolerance(tmp_path):
    p = mixed_scene(tmp_path)
    r = validate.validate_scene(p, RAYCAST, nrays=1000, seed=0)[0]
    assert r["status"] == "ok", json.dumps(r, default=str)[:2000]


def test_reference_expands_gpu_instances_like_the_per_node_original():
    # trimesh draws an EXT_mesh_gpu_instancing node once; the reference must expand it. The
    # same 501 cubes as plain nodes (gltfpack without instancing) are the independent answer.
    inst = validate.load_reference(FIXTURES / "compressed" / "cubes.instanced.glb")
    nodes = validate.load_reference(FIXTURES / "compressed" / "cubes.nodes.glb")
    assert len(inst.objects) == len(nodes.objects) == 501
    assert [o.name for o in inst.objects[:2]] == ["node0[0]", "node0[1]"]
    assert inst.objects[7].key == "/nodes/0/extensions/EXT_mesh_gpu_instancing/7"

    def centroids(ref):
        return np.array(sorted(tuple(o.tris.reshape(-1, 3).mean(axis=0)) for o in ref.objects))

    size = np.linalg.norm(np.subtract(*nodes.bounds()))
    assert np.abs(centroids(inst) - centroids(nodes)).max() < 1e-4 * size


def test_compressed_files_use_the_reference_decode_next_to_them():
    ref = validate.load_reference(FIXTURES / "compressed" / "helmet.draco-eb.glb")
    assert any("helmet.draco-eb.plain.glb" in n for n in ref.notes)
    with pytest.raises(validate.SkipScene):  # Draco without a reference decode
        validate.load_reference(FIXTURES / "compressed" / "knight.draco-optional.glb")


def test_bench_rays_in_tiles_are_4x2_pixel_tiles():
    # The bench's coherent rays go in the CLI's tile order: each run of eight rows is the
    # 4 x 2 block of pixels (x..x+3, y..y+1), pixels identified by their row-major index.
    from raycast_tools.rays import in_tiles

    side = 8
    index = np.arange(side * side, dtype=np.float32)
    rays = np.repeat(index[:, None], 6, axis=1)
    tiled = in_tiles(rays, side)[:, 0].astype(int)
    assert sorted(tiled) == list(range(side * side))
    for k, tile in enumerate(tiled.reshape(-1, 8)):
        y, x = 2 * (k // (side // 4)), 4 * (k % (side // 4))
        assert list(tile) == [(y + r) * side + x + c for r in (0, 1) for c in range(4)]
    assert np.array_equal(in_tiles(rays[:36], 6), rays[:36])


def test_bench_rounds_merge_into_medians():
    # Three rounds of one backend: times 2, 1 and 4 s for 1e6 rays give the median 2 s and
    # 0.5 Mrays/s; every round's runs are kept; names and counts come through unchanged.
    from raycast_tools.bench.bench import merge_rounds

    def round_(t, build):
        trace = {"rays": "coherent", "count": 1_000_000, "median_s": t, "runs_s": [t, t + 1]}
        trace["mrays_per_s"] = 1.0 / t
        return {"backends": [{"backend": "octree", "build_s": build, "traces": [trace]}]}

    merged = merge_rounds([round_(2.0, 0.3), round_(1.0, 0.1), round_(4.0, 0.2)])
    (backend,) = merged["backends"]
    assert backend["backend"] == "octree"
    assert backend["build_s"] == 0.2
    (trace,) = backend["traces"]
    assert trace["median_s"] == 2.0
    assert trace["mrays_per_s"] == 0.5
    assert trace["runs_s"] == [2.0, 3.0, 1.0, 2.0, 4.0, 5.0]
    assert trace["rays"] == "coherent" and trace["count"] == 1_000_000
