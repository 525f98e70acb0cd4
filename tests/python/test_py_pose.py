"""``Scene.at(time)``: a loaded scene posed at another time without reading the file again.

Each posed scene is compared with ``raycast.load(path, time=t)``, which reads and decodes the
file anew (another code path), on 2000 rays: identical hits, bit for bit. Run:
.venv/bin/python -m pytest tests/python/test_py_pose.py
"""

import pickle
import shutil
from pathlib import Path

import numpy as np
import pytest

import raycast

ROOT = Path(__file__).resolve().parents[2]
POSED = ROOT / "fixtures" / "posed"
OUTPUTS = ("t", "normal", "id", "prim", "bary")
TIMES = (0.0, 0.3, 0.77, 1.5)


def rays(scene, count=2000, seed=7):
    """Rays from a sphere around the scene's bounds toward points inside them."""
    rng = np.random.default_rng(seed)
    low, high = scene.bounds
    center, radius = (low + high) / 2, np.linalg.norm(high - low)
    start = rng.normal(size=(count, 3))
    start = center + 2 * radius * start / np.linalg.norm(start, axis=1, keepdims=True)
    aim = low + rng.random((count, 3)) * (high - low)
    return start, aim - start


def same_hits(a, b, origins, directions):
    """Whether two scenes give the same outputs, bit for bit, on the rays."""
    one = a.cast(origins, directions, aovs=OUTPUTS)
    two = b.cast(origins, directions, aovs=OUTPUTS)
    return all(np.array_equal(one[k], two[k]) for k in OUTPUTS)


@pytest.mark.parametrize("name", ["CesiumMan.glb", "BoxAnimated.glb", "SimpleSkin.gltf"])
def test_at_equals_load_at_that_time(name, tmp_path):
    path = POSED / name
    expected = {t: raycast.load(path, time=t) for t in TIMES}
    origins, directions = rays(expected[TIMES[0]])
    # The poses differ, so equal hits say something.
    first, last = (expected[t].cast(origins, directions) for t in (TIMES[0], TIMES[-1]))
    assert not np.array_equal(first["t"], last["t"]), name

    # A copy of the file, removed once loaded: the posed scenes cannot have read it again.
    copy = tmp_path / name
    shutil.copy(path, copy)
    if name.endswith(".gltf"):
        for extra in path.parent.glob(path.stem + "*.bin"):
            shutil.copy(extra, tmp_path / extra.name)
    loaded = raycast.load(copy, time=TIMES[0])
    for extra in tmp_path.iterdir():
        extra.unlink()
    for t in TIMES:
        posed = loaded.at(t)
        assert same_hits(posed, expected[t], origins, directions), f"{name} at {t}"
        assert posed.info() == expected[t].info() | {"scene": str(copy)}, f"{name} at {t}"
    # Chained, and from a scene at another time.
    chained = loaded.at(TIMES[2]).at(TIMES[1])
    assert same_hits(chained, expected[TIMES[1]], origins, directions)


def test_at_from_a_scene_loaded_without_time_or_from_bytes():
    path = POSED / "CesiumMan.glb"
    expected = raycast.load(path, time=0.77)
    origins, directions = rays(expected)
    rest = raycast.load(path)
    assert not same_hits(rest, expected, origins, directions)
    assert same_hits(rest.at(0.77), expected, origins, directions)
    data = raycast.load_bytes(path.read_bytes(), "CesiumMan.glb", time=0.0)
    assert same_hits(data.at(0.77), expected, origins, directions)
    # A posed scene pickles as the load at its time.
    again = pickle.loads(pickle.dumps(rest.at(0.77)))
    assert same_hits(again, expected, origins, directions)


def test_at_chooses_the_animation_and_reads_usd_again():
    path = POSED / "BoxAnimated.glb"
    one = raycast.load(path, time=0.0, animation=0).at(1.5)
    expected = raycast.load(path, time=1.5, animation=0)
    origins, directions = rays(expected)
    assert same_hits(one, expected, origins, directions)

    stage = ROOT / "fixtures" / "usd" / "posed" / "time_samples.usda"
    expected = raycast.load(stage, time=30.5)
    origins, directions = rays(expected)
    assert same_hits(raycast.load(stage).at(30.5), expected, origins, directions)


def test_at_refuses_a_time_that_is_no_number():
    scene = raycast.load(POSED / "BoxAnimated.glb", time=0.0)
    with pytest.raises(ValueError, match="finite"):
        scene.at(float("nan"))
