"""Random scenes of every quadric type against the independent object-space reference.

The quadric issue's acceptance check: on random scenes (scale 0.5..2, shear up to 0.3, random
clip boxes, random rotations of the coefficient frame) and random rays, raycast agrees with
the object-space reference (tools/raycast_tools/reference/quadric_reference.py) on hit/miss
and id for every ray that is not within 1e-6 of a clip-box face or a tangent, with relative
depth error <= 1e-9 and normal angle <= 1e-6 rad (the tolerances live in
tools/raycast_tools/validate/validate.py's TOL).
"""

import os
from pathlib import Path

import pytest

from raycast_tools.fixtures import random_quadric_scenes
from raycast_tools.validate import validate

ROOT = Path(__file__).resolve().parents[2]

RAYCAST = Path(os.environ.get("RAYCAST", ROOT / "target" / "release" / "raycast"))


@pytest.mark.skipif(not RAYCAST.exists(), reason=f"raycast binary not built ({RAYCAST})")
@pytest.mark.parametrize("seed", [1, 2])
def test_random_quadric_scenes_agree_with_reference(tmp_path, seed):
    scenes = random_quadric_scenes.write_scenes(tmp_path, count=4, seed=seed)
    for scene in scenes:
        (report,) = validate.validate_scene(scene, str(RAYCAST), nrays=3000, seed=seed)
        assert report["status"] == "ok", report
        assert report["quadrics"] == 9
        assert report["quadric_depth_rel"]["max"] <= 1e-9, report
        assert report["quadric_normal_angle"]["max"] <= 1e-6, report
        assert report["quadric_hitmiss_disagree"] == 0, report
        assert report["hits_ref"] > 500, report
