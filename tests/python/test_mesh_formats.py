"""PLY and STL read by raycast.load against trimesh 5.2.0's own readers (an independent
reference: no code shared with raycast): objects, triangle counts and every triangle's
vertices equal in float32, on the fixtures of fixtures/ply and fixtures/stl and on real
meshes: the Stanford bunny (a scan, 69k triangles) and, where the shared assets are present,
fandisk (a CAD part), written as PLY and STL by trimesh's exporters (the shared assets hold no
PLY or STL file of their own).

trimesh orders a PLY's quads apart from its triangles (all first halves, then all second
halves, each (c, d, a)), where raycast fans every polygon from its first corner as its OBJ
reader does; for files with polygons the triangles are compared as sets, each rotated to
start at its smallest corner (which keeps the winding).

Run: .venv/bin/python -m pytest tests/python/test_mesh_formats.py
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from raycast_tools.reference.open3d_meshes import canonical

raycast = pytest.importorskip("raycast")

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "fixtures"
SHARED = Path(os.environ.get("RAYCAST_SHARED_ASSETS", ROOT.parent / "shared" / "assets"))

# (fixture, whether trimesh keeps raycast's triangle order)
READABLE = [
    ("ply/cube_ascii_quads.ply", False),
    ("ply/cube_binary_le.ply", True),
    ("ply/cube_binary_be_double.ply", True),
    ("stl/cube_ascii.stl", True),
    ("stl/cube_binary.stl", True),
    ("stl/cube_binary_solid.stl", True),
    ("stl/two_solids.stl", True),
]


def trimesh_objects(path: Path) -> list[tuple[str, np.ndarray]]:
    """(name, (T, 3, 3) float64 triangles) per mesh, as trimesh reads the file."""
    scene = trimesh.load(str(path), force="scene", process=False)
    out = []
    for name, geom in scene.geometry.items():
        v = np.asarray(geom.vertices, dtype=np.float64)
        out.append((name, v[np.asarray(geom.faces)]))
    return out


def raycast_objects(path: Path) -> list[tuple[str, np.ndarray]]:
    scene = raycast.load(path)
    return [(o["name"], scene.triangles(o["id"])) for o in scene.objects]


def assert_same(path: Path, ordered: bool) -> int:
    ours, theirs = raycast_objects(path), trimesh_objects(path)
    assert [len(t) for _, t in ours] == [len(t) for _, t in theirs], path
    for (name, a), (_, b) in zip(ours, theirs):
        a32, b32 = a.astype(np.float32), b.astype(np.float32)
        if ordered:
            np.testing.assert_array_equal(a32, b32, err_msg=f"{path}: {name}")
        else:
            np.testing.assert_array_equal(canonical(a32), canonical(b32), err_msg=str(path))
    return sum(len(t) for _, t in ours)


@pytest.mark.parametrize("relative,ordered", READABLE)
def test_fixtures_read_as_trimesh_reads_them(relative, ordered):
    assert assert_same(FIX / relative, ordered) > 0


def test_stl_solids_are_named_as_trimesh_names_them():
    path = FIX / "stl" / "two_solids.stl"
    assert [n for n, _ in raycast_objects(path)] == [n for n, _ in trimesh_objects(path)]


def test_points_only_is_an_empty_scene_trimesh_reads_as_a_point_cloud():
    loaded = trimesh.load(str(FIX / "ply" / "points_only.ply"), process=False)
    assert isinstance(loaded, trimesh.PointCloud)
    scene = raycast.load(FIX / "ply" / "points_only.ply")
    assert scene.objects == []
    assert scene.info()["warnings"] == ["the scene holds no triangles or quadrics"]


def test_mixed_binary_polygons_which_trimesh_refuses_fan_by_hand():
    # trimesh's binary PLY reader takes the first list's length for every face.
    with pytest.raises(ValueError):
        trimesh.load(str(FIX / "ply" / "polygons_binary_le.ply"), process=False)
    scene = raycast.load(FIX / "ply" / "polygons_binary_le.ply")
    tris = scene.triangles(scene.objects[0]["id"])
    house = [[4, 0, 0], [6, 0, 0], [6, 1, 0], [5, 2, 0], [4, 1, 0]]
    fan = [[house[0], house[i], house[i + 1]] for i in (1, 2, 3)]
    np.testing.assert_array_equal(tris[3:], fan)


def real_meshes() -> list[Path]:
    found = [FIX / "assets" / "stanford-bunny.obj"]
    fandisk = SHARED / "obj" / "fandisk.obj"
    return found + ([fandisk] if fandisk.is_file() else [])


@pytest.mark.parametrize("source", real_meshes(), ids=lambda p: p.stem)
@pytest.mark.parametrize("encoding", ["ply", "ply-ascii", "stl", "stl-ascii"])
def test_real_meshes_written_by_trimesh(source, encoding, tmp_path):
    mesh = trimesh.load(str(source), force="mesh", process=False)
    kind, _, ascii_ = encoding.partition("-")
    path = tmp_path / f"{source.stem}.{kind}"
    if kind == "ply":
        data = trimesh.exchange.ply.export_ply(mesh, encoding="ascii" if ascii_ else "binary")
    elif ascii_:
        data = trimesh.exchange.stl.export_stl_ascii(mesh)
    else:
        data = trimesh.exchange.stl.export_stl(mesh)
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    count = assert_same(path, ordered=True)
    assert count == len(mesh.faces)


def test_triangles_of_an_unknown_id_is_a_value_error():
    scene = raycast.load(FIX / "stl" / "cube_ascii.stl")
    assert scene.triangles(1).shape == (12, 3, 3)
    for bad in (0, 2):
        with pytest.raises(ValueError, match=f"no object has id {bad}"):
            scene.triangles(bad)
