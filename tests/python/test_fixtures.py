"""Check the documented ray-cast answers of fixtures/ (see fixtures/README.md)
against trimesh, an independent reference that shares no code with raycast.

trimesh 5.2.0 loads glTF node transforms, indexed/non-indexed TRIANGLES and
TRIANGLE_STRIP, and OBJ polygons. It does not decode TRIANGLE_FAN, sparse
accessors or normalized integer positions (KHR_mesh_quantization); for those
the test decodes the accessors itself (a few lines of numpy, following the
glTF spec) and still uses trimesh's ray caster for the answers.

Run: .venv/bin/python -m pytest tests/python
"""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from trimesh.ray.ray_triangle import RayMeshIntersector

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "fixtures"
TOL = 1e-6

PX, NX, PY, NY, PZ, NZ = (1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)
MISS = None
ANY = -1  # prim on a shared edge: either triangle is correct


# ---------------------------------------------------------------------------
# reference ray casting with trimesh


def scene_meshes(path: Path, **load_kw) -> list[tuple[str, trimesh.Trimesh]]:
    """(node name, world-space mesh) for every triangle mesh trimesh finds."""
    scene = trimesh.load(str(path), force="scene", process=False, **load_kw)
    out = []
    for node in sorted(scene.graph.nodes_geometry):
        transform, geom_name = scene.graph[node]
        geom = scene.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh):
            continue  # points / lines
        mesh = geom.copy()
        mesh.apply_transform(transform)  # flips winding when det < 0, as glTF specifies
        out.append((node, mesh))
    return out


def cast(meshes, origin, direction):
    """Nearest hit with t > 0: (name, depth, unit normal, prim) or None."""
    o = np.asarray([origin], float)
    d = np.asarray([direction], float)
    best = None
    for name, mesh in meshes:
        locs, _, tris = RayMeshIntersector(mesh).intersects_location(o, d, multiple_hits=True)
        for loc, tri in zip(locs, tris):
            t = float(np.dot(loc - o[0], d[0]))
            if t <= 0:
                continue
            depth = float(np.linalg.norm(loc - o[0]))
            if best is None or depth < best[1] - 1e-12:
                best = (name, depth, mesh.face_normals[tri], int(tri))
    return best


def check(meshes, case):
    origin, direction, expected = case
    got = cast(meshes, origin, direction)
    if expected is MISS:
        assert got is None, f"ray {origin} {direction}: expected a miss, got {got}"
        return
    name, depth, normal, prim = expected
    assert got is not None, f"ray {origin} {direction}: expected {expected}, got a miss"
    assert got[0] == name, (case, got)
    assert got[1] == pytest.approx(depth, abs=TOL), (case, got)
    n = np.asarray(normal, float)
    assert np.allclose(got[2], n / np.linalg.norm(n), atol=TOL), (case, got)
    if prim != ANY:
        assert got[3] == prim, (case, got)


# ---------------------------------------------------------------------------
# the documented rays (keep in sync with fixtures/README.md)

CUBE_RAYS = [
    ((0.5, -0.25, 5), (0, 0, -1), ("cube", 4.0, PZ, 0)),
    ((-0.5, 0.25, 5), (0, 0, -1), ("cube", 4.0, PZ, 1)),
    ((0, 0, 5), (0, 0, -1), ("cube", 4.0, PZ, ANY)),
    ((5, 0.25, -0.5), (-1, 0, 0), ("cube", 4.0, PX, 4)),
    ((0.25, -5, 0.5), (0, 1, 0), ("cube", 4.0, NY, 11)),
    ((0.25, 0.5, 0), (0, 0, 2), ("cube", 1.0, PZ, 1)),  # from inside, direction not unit
    ((2, 0, 5), (0, 0, -1), MISS),
    ((0.5, -0.25, 5), (0, 0, 1), MISS),  # cube is behind the origin
]

PLANE_RAYS = [
    ((0.5, -0.25, 3), (0, 0, -1), ("plane", 3.0, PZ, 0)),
    ((-0.5, 0.25, 3), (0, 0, -1), ("plane", 3.0, PZ, 1)),
    ((0, 0.5, -2), (0, 0, 1), ("plane", 2.0, PZ, 1)),  # back side: normal not flipped
    ((2, 0, 3), (0, 0, -1), MISS),
]

MODES_RAYS = [
    ((-3.5, 0.25, 5), (0, 0, -1), ("tris", 5.0, PZ, 1)),
    ((-2.5, -0.25, 5), (0, 0, -1), ("tris", 5.0, PZ, 0)),
    ((-0.5, -0.25, 5), (0, 0, -1), ("strip", 5.0, PZ, 0)),
    ((0.5, 0.25, 5), (0, 0, -1), ("strip", 5.0, PZ, 1)),
    ((3, -0.5, 5), (0, 0, -1), ("fan", 5.0, PZ, 0)),
    ((3.5, 0, 5), (0, 0, -1), ("fan", 5.0, PZ, 1)),
    ((3, 0.5, 5), (0, 0, -1), ("fan", 5.0, PZ, 2)),
    ((2.5, 0, 5), (0, 0, -1), ("fan", 5.0, PZ, 3)),
    ((0.5, 2.5, 5), (0, 0, -1), MISS),  # points node
    ((0.5, -3.5, 5), (0, 0, -1), MISS),  # lines node
    ((-1.5, 0, 5), (0, 0, -1), MISS),  # gap between tris and strip
]

INSTANCES_RAYS = [
    ((3.25, -0.125, 5), (0, 0, -1), ("a", 4.5, PZ, 0)),
    ((-2.75, -0.125, 5), (0, 0, -1), ("b", 4.5, PZ, 6)),
    ((-6, 0.125, 0.25), (1, 0, 0), ("b", 2.5, NX, 3)),
    ((0.25, 3.25, -5), (0, 0, 1), ("c", 4.5, NZ, 2)),
    ((0.25, 3.25, 5), (0, 0, -1), ("d", 2.5, PZ, 0)),
    ((0.25, 10, 2.375), (0, -1, 0), ("d", 6.0, PY, 8)),
    ((0.25, -3.125, 5), (0, 0, -1), ("mirror", 4.5, PZ, 1)),
    ((5, -3.125, 0.25), (-1, 0, 0), ("mirror", 4.5, PX, 6)),
    ((0, 1.5, 5), (0, 0, -1), MISS),
]

SCENES_RAYS = [  # default scene is "second"
    ((0.5, -0.25, 5), (0, 0, -1), ("second_quad", 7.0, PZ, 0)),
]

FAR = (10000000.25, -3000000.5, 12345678.125)
FAR_RAYS = [
    ((FAR[0] + 0.5, FAR[1] - 0.25, FAR[2] + 5), (0, 0, -1), ("cube", 4.0, PZ, 0)),
    ((FAR[0], FAR[1], FAR[2] + 5), (0, 0, -1), ("cube", 4.0, PZ, ANY)),
]

TRAP_S = 3 / 256
TRAP_N = (-TRAP_S, 0, 1)
TRAP_RAYS = [
    ((-12, 0.25, 0.25), (1, 0, 0), ("near", 14.0, NX, 0)),
    ((12, 0.25, 0.25), (-1, 0, 0), ("big", 4.0, TRAP_N, 0)),
    ((8, 0.25, 5), (0, 0, -1), ("big", 4.75, TRAP_N, 0)),
]

SPARSE_RAYS = [
    ((0.5, -0.25, 5), (0, 0, -1), ("sparse", 4.25, (-1, 0, 2), 0)),
    ((-0.5, 0.25, 5), (0, 0, -1), ("sparse", 4.75, (-1, 0, 2), 1)),
]

QUANTIZED_RAYS = [
    ((0.5, -0.25, 5), (0, 0, -1), ("short", 5.0, PZ, 0)),
    ((-0.5, 0.25, 5), (0, 0, -1), ("short", 5.0, PZ, 1)),
    ((3.5, -0.25, 5), (0, 0, -1), ("ubyte", 5.0, PZ, 0)),
    ((2.5, 0.25, 5), (0, 0, -1), ("ubyte", 5.0, PZ, 1)),
    ((1.5, 0, 5), (0, 0, -1), MISS),
]


@pytest.mark.parametrize("name", ["cube.gltf", "cube.glb", "cube_embedded.gltf", "cameras.gltf"])
@pytest.mark.parametrize("case", CUBE_RAYS, ids=str)
def test_cube(name, case):
    check(scene_meshes(FIX / "gltf" / name), case)


@pytest.mark.parametrize("case", PLANE_RAYS, ids=str)
def test_plane(case):
    check(scene_meshes(FIX / "gltf" / "plane.gltf"), case)


@pytest.mark.parametrize("case", INSTANCES_RAYS, ids=str)
def test_instances(case):
    check(scene_meshes(FIX / "gltf" / "instances.gltf"), case)


@pytest.mark.parametrize("case", SCENES_RAYS, ids=str)
def test_scenes_default(case):
    meshes = scene_meshes(FIX / "gltf" / "scenes.gltf")
    assert [n for n, _ in meshes] == ["second_quad"]
    check(meshes, case)


@pytest.mark.parametrize("case", FAR_RAYS, ids=str)
def test_far(case):
    check(scene_meshes(FIX / "gltf" / "far.gltf"), case)


@pytest.mark.parametrize("case", TRAP_RAYS, ids=str)
def test_trap(case):
    check(scene_meshes(FIX / "gltf" / "trap.gltf"), case)


def test_trap_far_hit_behind_near_quad():
    """Without the near quad the +X ray hits the big triangle at depth 20."""
    meshes = [m for m in scene_meshes(FIX / "gltf" / "trap.gltf") if m[0] != "near"]
    check(meshes, ((-12, 0.25, 0.25), (1, 0, 0), ("big", 20.0, TRAP_N, 0)))


def test_trap_bounds():
    meshes = scene_meshes(FIX / "gltf" / "trap.gltf")
    v = np.concatenate([m.vertices for _, m in meshes])
    assert v.min(axis=0).tolist() == [-10, -10, -10]
    assert v.max(axis=0).tolist() == [10, 10, 10]
    assert sum(len(m.faces) for _, m in meshes) == 1 + 2 + 256


# --- modes.gltf: trimesh reads TRIANGLES and TRIANGLE_STRIP; the fan is decoded here.


@pytest.mark.parametrize("case", MODES_RAYS, ids=str)
def test_modes(case):
    meshes = [m for m in scene_meshes(FIX / "gltf" / "modes.gltf")]
    assert sorted(n for n, _ in meshes) == ["strip", "tris"]  # points/lines are not Trimesh
    doc = load_gltf(FIX / "gltf" / "modes.gltf")
    fan_node = doc["nodes"][2]
    prim = doc["meshes"][fan_node["mesh"]]["primitives"][0]
    assert prim["mode"] == 6 and "indices" not in prim
    v = read_accessor(doc, prim["attributes"]["POSITION"]) + fan_node["translation"]
    # glTF fan: triangle i = (v[i+1], v[i+2], v[0])
    faces = [[i + 1, i + 2, 0] for i in range(len(v) - 2)]
    meshes.append(("fan", trimesh.Trimesh(v, faces, process=False)))
    check(meshes, case)


def test_modes_points_lines_present():
    doc = load_gltf(FIX / "gltf" / "modes.gltf")
    modes = {
        n["name"]: doc["meshes"][n["mesh"]]["primitives"][0].get("mode", 4) for n in doc["nodes"]
    }
    assert modes == {"tris": 4, "strip": 5, "fan": 6, "points": 0, "lines": 1}


# --- sparse.gltf and quantized.gltf: decode the accessors here, cast with trimesh


def test_sparse_positions():
    doc = load_gltf(FIX / "gltf" / "sparse.gltf")
    v = read_accessor(doc, doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"])
    assert v.tolist() == [[-1, -1, 0], [1, -1, 1], [1, 1, 1], [-1, 1, 0]]
    base = read_accessor(
        doc, doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"], sparse=False
    )
    assert base[:, 2].tolist() == [0, 0, 0, 0]


@pytest.mark.parametrize("case", SPARSE_RAYS, ids=str)
def test_sparse(case):
    check(decoded_meshes(FIX / "gltf" / "sparse.gltf"), case)


def test_quantized_positions():
    doc = load_gltf(FIX / "gltf" / "quantized.gltf")
    assert doc["extensionsRequired"] == ["KHR_mesh_quantization"]
    assert doc["extensionsUsed"] == ["KHR_mesh_quantization"]
    world = {
        name: m.vertices.tolist() for name, m in decoded_meshes(FIX / "gltf" / "quantized.gltf")
    }
    assert world == {
        "short": [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
        "ubyte": [[2, -1, 0], [4, -1, 0], [4, 1, 0], [2, 1, 0]],
    }


@pytest.mark.parametrize("case", QUANTIZED_RAYS, ids=str)
def test_quantized(case):
    check(decoded_meshes(FIX / "gltf" / "quantized.gltf"), case)


# --- OBJ: trimesh merges all objects/groups of a file into one mesh (faces in file
# order), so the object is found from the face index.

OBJ_RAYS = {
    "two_objects.obj": (
        [("quad", 2), ("penta", 3)],
        [
            ((0.5, -0.25, 5), (0, 0, -1), ("quad", 5.0, PZ, 0)),
            ((-0.5, 0.25, 5), (0, 0, -1), ("quad", 5.0, PZ, 1)),
            ((3.5, -0.5, 5), (0, 0, -1), ("penta", 6.0, PZ, 0)),
            ((3, 0, 5), (0, 0, -1), ("penta", 6.0, PZ, 1)),
            ((2.25, 0.25, 5), (0, 0, -1), ("penta", 6.0, PZ, 2)),
            ((3.5, 1.25, 5), (0, 0, -1), MISS),
        ],
    ),
    "groups.obj": (
        [("left", 2), ("right", 2)],
        [
            ((-1.5, -0.5, 5), (0, 0, -1), ("left", 5.0, PZ, 0)),
            ((-2.5, 0.5, 5), (0, 0, -1), ("left", 5.0, PZ, 1)),
            ((2.5, -0.75, 5), (0, 0, -1), ("right", 4.5, PZ, 0)),
            ((1.5, 0.5, 5), (0, 0, -1), ("right", 4.5, PZ, 1)),
            ((0, 0, 5), (0, 0, -1), MISS),
        ],
    ),
}


@pytest.mark.parametrize("name", sorted(OBJ_RAYS))
def test_obj(name):
    objects, rays = OBJ_RAYS[name]
    meshes = scene_meshes(FIX / "obj" / name)
    assert len(meshes) == 1
    mesh = meshes[0][1]
    assert len(mesh.faces) == sum(n for _, n in objects)
    starts = np.cumsum([0] + [n for _, n in objects])
    for origin, direction, expected in rays:
        got = cast([("merged", mesh)], origin, direction)
        if got is not None:
            k = int(np.searchsorted(starts, got[3], side="right") - 1)
            got = (objects[k][0], got[1], got[2], got[3] - int(starts[k]))
        if expected is MISS:
            assert got is None, (origin, got)
            continue
        assert got is not None, (origin, expected)
        assert got[0] == expected[0] and got[3] == expected[3], (origin, got, expected)
        assert got[1] == pytest.approx(expected[1], abs=TOL)
        assert np.allclose(got[2], expected[2], atol=TOL)


# --- structure of the other fixtures


def test_cameras():
    doc = load_gltf(FIX / "gltf" / "cameras.gltf")
    cams = {c["name"]: c for c in doc["cameras"]}
    assert cams["persp"]["perspective"] == {"aspectRatio": 2.0, "yfov": 0.8, "znear": 0.1}
    assert (
        cams["ortho"]["orthographic"]["xmag"] == 2.0
        and cams["ortho"]["orthographic"]["ymag"] == 1.0
    )
    ortho = next(n for n in doc["nodes"] if n["name"] == "ortho")
    r = trimesh.transformations.quaternion_matrix([ortho["rotation"][3], *ortho["rotation"][:3]])[
        :3, :3
    ]
    assert np.allclose(r @ [0, 0, -1], [-1, 0, 0])  # looks down -X
    assert np.allclose(r @ [0, 1, 0], [0, 1, 0])  # +Y up
    assert np.allclose(r @ [1, 0, 0], [0, 0, -1])  # image right is world -Z


def test_far_transform_is_double_precision():
    text = (FIX / "gltf" / "far.gltf").read_text()
    assert "10000000.25" in text and "12345678.125" in text and "12345683.125" in text
    doc = json.loads(text)
    assert doc["nodes"][0]["translation"] == list(FAR)


def test_scenes_structure():
    doc = load_gltf(FIX / "gltf" / "scenes.gltf")
    assert [s["name"] for s in doc["scenes"]] == ["first", "second"] and doc["scene"] == 1


def test_bad_npy_shapes():
    bad = np.load(FIX / "bad" / "bad_rays.npy")
    assert bad.shape == (3, 5)
    nan = np.load(FIX / "bad" / "nan_rays.npy")
    assert nan.shape == (2, 6) and nan.dtype == np.float64 and np.isnan(nan).sum() == 1


def test_fixtures_are_reproducible(tmp_path, monkeypatch):
    """Rerunning the generator gives byte-identical files."""
    from raycast_tools.fixtures import make_fixtures as mod
    from raycast_tools.fixtures.fixture_files import FixtureFiles

    monkeypatch.setattr(mod, "FILES", FixtureFiles(tmp_path))
    for attr in ("FIX", "GLTF_DIR", "OBJ_DIR", "BAD_DIR"):
        monkeypatch.setattr(mod, attr, tmp_path / getattr(mod, attr).relative_to(FIX))
    for fn in (
        mod.make_cube,
        mod.make_plane,
        mod.make_modes,
        mod.make_sparse,
        mod.make_quantized,
        mod.make_instances,
        mod.make_scenes,
        mod.make_cameras,
        mod.make_far,
        mod.make_trap,
        mod.make_obj,
        mod.make_bad,
    ):
        fn()
    fresh = sorted(p for p in tmp_path.rglob("*") if p.is_file())
    assert fresh
    for p in fresh:
        committed = FIX / p.relative_to(tmp_path)
        assert committed.read_bytes() == p.read_bytes(), f"{committed} differs from a fresh run"


# ---------------------------------------------------------------------------
# minimal glTF accessor decoding (for the parts trimesh does not decode)

COMPONENT = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def load_gltf(path: Path) -> dict:
    doc = json.loads(path.read_text())
    bufs = []
    for b in doc.get("buffers", []):
        uri = b["uri"]
        if uri.startswith("data:"):
            bufs.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            bufs.append((path.parent / uri).read_bytes())
    doc["_buffers"] = bufs
    return doc


def view_bytes(doc, index):
    v = doc["bufferViews"][index]
    off = v.get("byteOffset", 0)
    return doc["_buffers"][v["buffer"]][off : off + v["byteLength"]], v.get("byteStride")


def read_accessor(doc, index, sparse=True) -> np.ndarray:
    a = doc["accessors"][index]
    dt = np.dtype(COMPONENT[a["componentType"]])
    n = NCOMP[a["type"]]
    count = a["count"]
    out = np.zeros((count, n), dt)
    if "bufferView" in a:
        data, stride = view_bytes(doc, a["bufferView"])
        stride = stride or dt.itemsize * n
        off = a.get("byteOffset", 0)
        for i in range(count):
            out[i] = np.frombuffer(data, dt, n, off + i * stride)
    if sparse and "sparse" in a:
        s = a["sparse"]
        idata, _ = view_bytes(doc, s["indices"]["bufferView"])
        idx = np.frombuffer(
            idata,
            COMPONENT[s["indices"]["componentType"]],
            s["count"],
            s["indices"].get("byteOffset", 0),
        )
        vdata, _ = view_bytes(doc, s["values"]["bufferView"])
        out[idx] = np.frombuffer(
            vdata, dt, s["count"] * n, s["values"].get("byteOffset", 0)
        ).reshape(-1, n)
    res = out.astype(np.float64)
    if a.get("normalized"):
        if dt.kind == "u":
            res = res / np.iinfo(dt).max
        else:
            res = np.maximum(res / np.iinfo(dt).max, -1.0)
    return res


def node_matrix(node) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], float).reshape(4, 4).T
    t = trimesh.transformations
    m = t.translation_matrix(node.get("translation", [0, 0, 0]))
    q = node.get("rotation", [0, 0, 0, 1])
    m = m @ t.quaternion_matrix([q[3], q[0], q[1], q[2]])
    return m @ np.diag(list(node.get("scale", [1, 1, 1])) + [1])


def decoded_meshes(path: Path):
    """World meshes of a flat scene (root nodes only, TRIANGLES), decoded here."""
    doc = load_gltf(path)
    out = []
    for ni in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        node = doc["nodes"][ni]
        prim = doc["meshes"][node["mesh"]]["primitives"][0]
        assert prim.get("mode", 4) == 4
        v = read_accessor(doc, prim["attributes"]["POSITION"])
        f = read_accessor(doc, prim["indices"]).astype(np.int64).reshape(-1, 3)
        mesh = trimesh.Trimesh(v, f, process=False)
        mesh.apply_transform(node_matrix(node))
        out.append((node["name"], mesh))
    return out
