"""`python -m raycast_tools exact-depth`: raycast's USD depths against usd-core's placement and
a float64 Möller–Trumbore test written in the tool (no code shared with raycast).

Run: .venv/bin/python -m pytest tests/python/test_exact_depth.py
Skips when target/release/raycast (or $RAYCAST) does not exist, or without usd-core.
"""

import numpy as np
import pytest

pytest.importorskip("pxr")

from binary import RAYCAST, ROOT, needs_binary

from raycast_tools import exact_depth

USD = ROOT / "fixtures" / "usd"


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
