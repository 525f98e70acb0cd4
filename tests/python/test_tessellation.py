"""Tests of tools/raycast_tools/fixtures/tessellate.py and the tessellation convergence check.

Run: .venv/bin/python -m pytest tests/python/test_tessellation.py
The raycast part of the convergence check skips when target/release/raycast is absent.
"""

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from raycast_tools.fixtures import tessellate as tess
from raycast_tools.reference import quadric_reference as qr
from raycast_tools.validate import tessellation_check as tc

ROOT = Path(__file__).resolve().parents[2]

RAYCAST = Path(os.environ.get("RAYCAST", ROOT / "target" / "release" / "raycast"))
QFIX = ROOT / "fixtures" / "quadrics"

KINDS = {
    "sphere_coefficients.gltf": "ellipsoid",
    "ellipsoid.gltf": "ellipsoid",
    "cylinder.gltf": "elliptic_cylinder",
    "elliptic_cylinder.gltf": "elliptic_cylinder",
    "cone.gltf": "cone",
    "hyperboloid_one_sheet.gltf": "hyperboloid_one_sheet",
    "hyperboloid_two_sheets.gltf": "hyperboloid_two_sheets",
    "elliptic_paraboloid.gltf": "elliptic_paraboloid",
    "hyperbolic_paraboloid.gltf": "hyperbolic_paraboloid",
    "hyperbolic_cylinder.gltf": "hyperbolic_cylinder",
    "parabolic_cylinder.gltf": "parabolic_cylinder",
}


@pytest.mark.parametrize("fname", sorted(KINDS))
def test_vertices_on_surface_and_inside_box(fname):
    for q in qr.quadrics_from_gltf(QFIX / fname):
        t = tess.tessellate_quadric(q, segments=24)
        assert t.kind == KINDS[fname]
        assert len(t.faces) > 0
        # vertices not created by clipping lie on the surface (distance |f|/|grad f|)
        assert t.info["residual"] < 1e-13
        lo, hi = q.local_bounds()
        slack = 1e-8 * float(np.max(hi - lo))
        assert np.all(t.local >= lo - slack) and np.all(t.local <= hi + slack)
        # world vertices are the node matrix applied to the local ones
        np.testing.assert_allclose(t.vertices, t.local @ q.A.T + q.t, rtol=0, atol=1e-12)
        # winding: geometric normal toward f > 0
        tri = t.triangles
        nw = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        gw = q.grad(t.local[t.faces].mean(axis=1)) @ q.Ainv
        assert np.all(np.einsum("ij,ij->i", nw, gw) >= 0)


def test_sphere_area_and_sagitta():
    q = qr.quadrics_from_gltf(QFIX / "sphere_coefficients.gltf")[0]  # r = 2
    for n in (16, 64):
        t = tess.tessellate_quadric(q, segments=n)
        assert t.rows == n // 2
        tri = t.triangles
        area = (
            0.5
            * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum()
        )
        assert area < 4 * math.pi * 4 and area > 4 * math.pi * 4 * (1 - 2 * (math.pi / n) ** 2)
        # farthest inward point of a facet: the centroid distance from the centre
        dmin = np.linalg.norm(tri.mean(axis=1), axis=1).min()
        e = 2 * math.pi * 2 / n
        assert 2 - dmin <= 2 * e * e / (8 * 2)


def test_edge_length_resolution():
    q = qr.quadrics_from_gltf(QFIX / "cylinder.gltf")[2]  # canonical, r = 1, |z| <= 1
    n, m = tess.resolution_for_edge(q, 0.1)
    assert m == 1  # straight rulings
    assert abs(n - math.ceil(2 * math.pi / 0.1)) <= 1
    t = tess.tessellate_quadric(q, edge=0.1)
    assert t.segments == n


def test_write_gltf_roundtrip(tmp_path):
    src = QFIX / "mixed.gltf"
    out = tmp_path / "mixed_tess.gltf"
    ts = tess.write_tessellated_gltf(src, out, segments=16)
    h = json.loads(out.read_text())
    assert not any(qr.EXT in n.get("extensions", {}) for n in h["nodes"])
    assert qr.EXT not in h.get("extensionsUsed", [])
    names = [n.get("name") for n in h["nodes"]]
    for t in ts:
        assert t.name in names
    # the written positions + node translation reproduce the float64 vertices to f32 rounding
    binary = (tmp_path / "mixed_tess.bin").read_bytes()
    t = ts[0]
    node = [n for n in h["nodes"] if n.get("name") == t.name and "mesh" in n][-1]
    acc = h["accessors"][h["meshes"][node["mesh"]]["primitives"][0]["attributes"]["POSITION"]]
    bv = h["bufferViews"][acc["bufferView"]]
    pos = np.frombuffer(binary, np.float32, acc["count"] * 3, bv["byteOffset"]).reshape(-1, 3)
    np.testing.assert_allclose(pos + np.array(node["translation"]), t.vertices, atol=1e-6)


def _small_check(use_raycast):
    return tc.run_check(
        fixtures=["sphere_coefficients.gltf", "cylinder.gltf:canonical"],
        segments=[8, 16, 32, 64],
        nrays=300,
        nrays_f64=150,
        seed=1,
        raycast=str(RAYCAST),
        use_raycast=use_raycast,
    )


def test_convergence_slope_trimesh():
    rows, sl, ok = _small_check(False)
    for (fx, m), s in sl.items():
        assert tc.SLOPE_RANGE[0] <= s["depth_median"] <= tc.SLOPE_RANGE[1], (fx, m, s)
        assert tc.SLOPE_RANGE[0] <= s["depth_p99"] <= tc.SLOPE_RANGE[1], (fx, m, s)
        assert 0.7 <= s["normal_median"] <= 1.3, (fx, m, s)
    assert ok


@pytest.mark.skipif(not RAYCAST.exists(), reason=f"raycast binary not built ({RAYCAST})")
def test_convergence_slope_raycast():
    rows, sl, ok = _small_check(True)
    assert ok, sl
    assert any(m == "raycast" for (_, m) in sl)
    # raycast on the tessellation and embree/ray_triangle see the same facets
    for r in rows:
        if r["method"] == "raycast" and r["segments"] >= 32:
            assert r["depth_rel_median"] < 1e-2
