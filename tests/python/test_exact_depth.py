"""`python -m raycast_tools exact-depth`: raycast's depths against a float64 reading of the
file by readers that share no code with raycast (usd-core for USD, trimesh for OBJ, the tool's
own numpy glTF reader) and a float64 Möller–Trumbore test written in the tool.

Run: .venv/bin/python -m pytest tests/python/test_exact_depth.py
Skips when target/release/raycast (or $RAYCAST) does not exist, or without usd-core.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("pxr")
pytest.importorskip("trimesh")

import trimesh
from binary import RAYCAST, ROOT, needs_binary

from raycast_tools.fixtures import make_exact_fixtures
from raycast_tools.rays import make_rays
from raycast_tools.reference import exact_readers
from raycast_tools.validate import exact_depth

USD = ROOT / "fixtures" / "usd"
EXACT = ROOT / "fixtures" / "exact"


def test_moller_trumbore_against_a_hand_computed_hit():
    # triangle in the plane z = 2; the ray from the origin along +z hits at t = 2
    a = np.array([[-1.0, -1.0, 2.0], [5.0, 5.0, 9.0]])
    e1 = np.array([[2.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    e2 = np.array([[0.0, 2.0, 0.0], [0.0, 1.0, 0.0]])
    t, i = exact_depth.moller_trumbore(a, e1, e2, np.zeros(3), np.array([0.0, 0.0, 1.0]))
    assert (t, i) == (2.0, 0)
    t, i = exact_depth.moller_trumbore(a, e1, e2, np.zeros(3), np.array([0.0, 0.0, -1.0]))
    assert (t, i) == (np.inf, -1)


@needs_binary
@pytest.mark.parametrize("scene", ["xforms.usda", "composition.usda"])
def test_fixture_depths_agree_to_1e_12(scene):
    r = exact_depth.check_scene(USD / scene, RAYCAST, nrays=300, seed=3, limit=1e-12)
    assert r["hits_both"] > 100, r
    assert r["failures"] == [], r
    assert r["depth_rel_p999"] <= 1e-12


@needs_binary
def test_gprims_are_left_out_of_the_mesh_only_comparison():
    """complex_transform.usda (usd-wg) references three Cube gprims, which raycast draws as
    12-triangle mesh objects and the mesh-only reference leaves out: they are not counted as
    objects drawn by raycast only."""
    scene = USD / "assets/usd-wg/test_assets/schemaTests/usdGeom/transforms/complex_transform.usda"
    r = exact_depth.check_scene(scene, RAYCAST, nrays=300, seed=3, limit=1e-12)
    assert r["objects"] == 1 and r["objects_only_raycast"] == [], r
    assert r["failures"] == [], r


# ------------------------------------------------------------------ fixtures/exact (issue 12)


@needs_binary
@pytest.mark.parametrize(
    "scene, objects",
    [
        ("far_field.obj", 1),
        ("nested_far.gltf", 16),
        # 24 instances, less invisibleIds 103 and 110, inactiveIds 107 and 115, and the two of
        # the invisible prototype; and 6 of a second instancer
        ("point_instancer.usda", 24),
    ],
)
def test_far_scenes_agree_with_outside_readers_to_1e_12(scene, objects):
    r = exact_depth.check_scene(EXACT / scene, RAYCAST, nrays=2000, seed=1, limit=1e-12)
    assert r["objects"] == objects, r
    assert r["hits_both"] > 1200, r
    assert r["hitmiss_disagreements"] == 0, r
    # trimesh reads an OBJ as one object: objects are not compared there
    assert r["object_disagreements"] == (None if scene.endswith(".obj") else 0), r
    assert r["objects_only_raycast"] == r["objects_only_reference"] == [], r
    assert r["failures"] == [], r
    assert r["depth_rel_p999"] <= 1e-12


@needs_binary
def test_inactive_ids_composed_over_layers_match_usd_core(tmp_path):
    """A binary layer over the fixture appends two inactiveIds (an int64 list op over the text
    layer's explicit one): raycast draws what usd-core's mask leaves."""
    from pxr import Sdf, Usd, UsdGeom

    layer = Sdf.Layer.CreateNew(str(tmp_path / "over.usdc"))
    layer.subLayerPaths.append(str(EXACT / "point_instancer.usda"))
    stage = Usd.Stage.Open(layer)
    UsdGeom.PointInstancer(stage.GetPrimAtPath("/world/pi")).DeactivateIds([121, 104])
    layer.Save()
    r = exact_depth.check_scene(tmp_path / "over.usdc", RAYCAST, nrays=500, seed=2, limit=1e-12)
    assert r["objects"] == 22, r
    assert r["failures"] == [], r


@pytest.mark.parametrize("scene", ["far_field.obj", "nested_far.gltf", "point_instancer.usda"])
def test_f32_world_triangles_would_fail_the_check(scene):
    """The check can fail: the same reference with world triangles rounded to f32 (what raycast
    stored before issue 12) is off by far more than 1e-12 on these scenes."""
    read, _, _ = exact_depth.reference_objects(EXACT / scene)
    exact = exact_depth.Objects(read)
    rounded = exact_depth.Objects(
        [(k, np.asarray(t, np.float32).astype(np.float64)) for k, t in read]
    )
    origins, unit, _ = make_rays(exact_depth.RaySource(exact), 300, 1)
    a = np.array([exact.nearest(o, d)[0] for o, d in zip(origins, unit)])
    b = np.array([rounded.nearest(o, d)[0] for o, d in zip(origins, unit)])
    both = np.isfinite(a) & np.isfinite(b)
    assert both.sum() > 150
    assert np.percentile(np.abs(a[both] - b[both]) / a[both], 99.9) > 1e-9


def test_obj_reader_keeps_the_files_17_digits():
    path = EXACT / "far_field.obj"
    [(name, tris)] = exact_readers.read_obj(path)
    assert name is None and tris.dtype == np.float64
    text = exact_readers.python_obj_vertices(path)
    assert {tuple(p) for p in tris.reshape(-1, 3).tolist()} == text
    # none of the x, y coordinates is an f32 value, all lie 1e6..1e7 from the origin
    xy = tris.reshape(-1, 3)[:, :2]
    assert (xy.astype(np.float32).astype(np.float64) != xy).all()
    assert xy.min() > 8e5 and xy.max() < 1.1e7


def test_gltf_reader_agrees_with_trimesh():
    """The numpy glTF reader against trimesh's scene graph (its float64 node transforms) on the
    nested fixture: every node's world triangles, to the rounding of coordinates near 2e5."""
    path = EXACT / "nested_far.gltf"
    ours = dict(exact_readers.read_gltf(path))
    doc = json.loads(path.read_text())
    scene = trimesh.load(str(path), force="scene", process=False)
    assert len(scene.graph.nodes_geometry) == len(ours) == 16
    for node in scene.graph.nodes_geometry:
        matrix, geometry = scene.graph.get(node)
        mesh = scene.geometry[geometry]
        theirs = exact_readers.place(np.asarray(mesh.vertices)[mesh.faces], matrix)
        index = next(i for i, n in enumerate(doc["nodes"]) if n.get("name") == node)
        np.testing.assert_allclose(ours[f"/nodes/{index}"], theirs, rtol=0, atol=1e-9)
        assert np.abs(theirs).max() > 5e4  # really 1e5 from the origin


def test_gltf_reader_refuses_what_it_does_not_read(tmp_path):
    for name, why in [("sparse.gltf", "sparse"), ("modes.gltf", "mode")]:
        with pytest.raises(exact_readers.RefuseError, match=why):
            exact_readers.read_gltf(ROOT / "fixtures" / "gltf" / name)
    doc = json.loads((EXACT / "nested_far.gltf").read_text())
    doc["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    (tmp_path / "draco.gltf").write_text(json.dumps(doc))
    with pytest.raises(exact_readers.RefuseError, match="KHR_draco_mesh_compression"):
        exact_readers.read_gltf(tmp_path / "draco.gltf")


def test_gltf_reader_reads_quantized_positions_and_gpu_instances():
    # quantized.gltf (fixtures/README.md): the unit square as normalized SHORT (byteStride 8)
    # and UNSIGNED_BYTE (byteStride 4) positions, scaled by (2,2,1) and moved to (-1,-1,0) and
    # (2,-1,0); triangles 0 1 2 and 0 2 3
    objects = dict(exact_readers.read_gltf(ROOT / "fixtures" / "gltf" / "quantized.gltf"))
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0], [1, 1, 0], [0, 1, 0]]
    for node, move in [("/nodes/0", [-1, -1, 0]), ("/nodes/1", [2, -1, 0])]:
        expected = np.array(square, float) * [2, 2, 1] + move
        assert (objects[node].reshape(-1, 3) == expected).all(), node
    # cubes.instanced.glb: one object per GPU instance
    path = ROOT / "fixtures" / "compressed" / "cubes.instanced.glb"
    glb = dict(exact_readers.read_gltf(path))
    assert len(glb) > 100
    assert all("/extensions/EXT_mesh_gpu_instancing/" in k for k in glb)


def test_exact_fixtures_regenerate_byte_identical(tmp_path, monkeypatch):
    monkeypatch.setattr(make_exact_fixtures, "EXACT_DIR", tmp_path)
    monkeypatch.setattr(make_exact_fixtures, "FILES", make_exact_fixtures.FixtureFiles(tmp_path))
    make_exact_fixtures.main([])
    fresh = sorted(p.name for p in tmp_path.iterdir())
    assert fresh == sorted(p.name for p in EXACT.iterdir() if p.name != "README.md")
    for name in fresh:
        assert (tmp_path / name).read_bytes() == (EXACT / name).read_bytes(), name


@pytest.mark.parametrize(
    "kernel",
    [
        # numpy's linear algebra on OpenBLAS's oldest x86 kernel, numpy's own SIMD dispatch
        # limited to the baseline: the arithmetic of another CPU. (Values from BLAS or from
        # numpy's normal draws reach the files on today's main, and differ here.)
        {
            "OPENBLAS_CORETYPE": "Prescott",
            "NPY_DISABLE_CPU_FEATURES": "AVX512F AVX512CD AVX512_SKX AVX2 FMA3 F16C AVX",
        },
        {"OPENBLAS_CORETYPE": "Haswell"},
    ],
    ids=["prescott-baseline", "haswell"],
)
def test_exact_fixtures_regenerate_byte_identical_on_other_kernels(tmp_path, kernel):
    env = {**os.environ, **kernel}
    cmd = [sys.executable, "-m", "raycast_tools", "exact-fixtures", "--out", str(tmp_path)]
    subprocess.run(cmd, env=env, check=True, capture_output=True, cwd=ROOT)
    for path in sorted(tmp_path.iterdir()):
        assert path.read_bytes() == (EXACT / path.name).read_bytes(), (path.name, kernel)
