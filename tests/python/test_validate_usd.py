"""`python -m raycast_tools validate-usd` on USD fixtures: usd-core flattening + tessellated
gprims vs raycast.

Run: .venv/bin/python -m pytest tests/python/test_validate_usd.py
Skips when target/release/raycast (or $RAYCAST) does not exist, or without usd-core.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

pytest.importorskip("pxr")

from binary import RAYCAST, ROOT, needs_binary

from raycast_tools.validate import validate_usd

USD = ROOT / "fixtures" / "usd"

# 64 segments keeps the tessellated gprims small (about 30k triangles for gprims.usda);
# the bound scales with the resolution, so the check is as strict relative to it.
SCENES = [
    "gprims.usda",
    "gprims.usdc",
    "composition.usda",
    "xforms.usda",
    "gltf_cube.usda",
    "gltf_mixed.usda",
]


@needs_binary
@pytest.mark.parametrize("scene", SCENES)
def test_scene_within_tolerance(scene):
    r = validate_usd.validate_scene(str(USD / scene), RAYCAST, nrays=300, seed=1, segments=64)
    assert "skipped" not in r and "error" not in r, r
    assert r["rays"] == 300 and r["hits_reference"] > 50
    assert r["failures"] == [], r
    assert r["hitmiss_disagreements"] == 0, r["disagreeing_rays"]
    assert r["object_agreement"] == 1.0, r["object_mismatches"]
    assert r["ambiguous"] < 0.1 * r["rays"]


@needs_binary
def test_command_line_json_and_exit_status(tmp_path):
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "raycast_tools",
            "validate-usd",
            str(USD / "gltf_cube.usda"),
            str(USD / "bad"),
            "--rays",
            "200",
            "--segments",
            "32",
            "--json",
            "--raycast",
            str(RAYCAST),
        ],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 0, p.stderr
    reports = json.loads(p.stdout)
    assert [r["scene"] for r in reports] == [str(USD / "gltf_cube.usda")]  # bad/ skipped
    assert reports[0]["pass"] and reports[0]["hits_raycast"] == reports[0]["hits_reference"]


@needs_binary
def test_wrong_answers_fail(tmp_path):
    """A raycast that answers for a different scene leaves the tolerance: exit 1."""
    fake = tmp_path / "raycast"
    # draw gprims.usda's xforms twin: same prim kinds, other places
    fake.write_text(f'#!/bin/sh\nscene=$1; shift\nexec {RAYCAST} {USD / "xforms.usda"} "$@"\n')
    fake.chmod(0o755)
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "raycast_tools",
            "validate-usd",
            str(USD / "composition.usda"),
            "--rays",
            "100",
            "--raycast",
            str(fake),
        ],
        capture_output=True,
        text=True,
    )
    assert p.returncode == 1, p.stdout + p.stderr
    assert "FAIL" in p.stdout


def test_gprim_tessellation_brackets_the_surface():
    """Inner vertices on the surface, outer faces outside it (unit sphere, cylinder)."""
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.CreateInMemory()
    sphere = UsdGeom.Sphere.Define(stage, "/S").GetPrim()
    cylinder = UsdGeom.Cylinder.Define(stage, "/C")
    cylinder.CreateAxisAttr("X")
    (parts, sag, axis) = validate_usd.gprim_local(sphere, 32)
    _, inner, outer = parts[0]
    assert np.allclose(np.linalg.norm(inner.reshape(-1, 3), axis=1), 1.0)
    centroids = outer.mean(axis=1)
    normals = np.cross(outer[:, 1] - outer[:, 0], outer[:, 2] - outer[:, 0])
    ok = np.linalg.norm(normals, axis=1) > 1e-12
    normals = normals[ok] / np.linalg.norm(normals[ok], axis=1)[:, None]
    # distance of each outer face plane from the centre is at least the radius
    assert (np.abs(np.einsum("ij,ij->i", centroids[ok], normals)) >= 1.0 - 1e-12).all()
    assert 0 < sag < 0.03
    parts, sag, axis = validate_usd.gprim_local(cylinder.GetPrim(), 32)
    assert axis == "X" and [p[0] for p in parts] == ["", ":caps"]
    assert validate_usd.strip_suffix("/C:caps") == "/C"
