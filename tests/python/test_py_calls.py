"""How raycast.Scene's calls run: in pieces (so that Ctrl-C and progress hooks are heard during
a long call) without changing any result, on ``nthreads`` threads without changing any result.

Run: .venv/bin/python -m pytest tests/python/test_py_calls.py
"""

import signal
from pathlib import Path

import numpy as np
import pytest

import raycast
from raycast import _chunks

ROOT = Path(__file__).resolve().parents[2]
# Five instances of one mesh, placed by translations, a rotation, a parent's uneven scale and
# a mirror: every query runs through the top-level and the instances' octrees.
SCENE = ROOT / "fixtures" / "gltf" / "instances.gltf"


@pytest.fixture(scope="module")
def scene():
    return raycast.load(SCENE)


def rays(scene, n, seed=1):
    rng = np.random.default_rng(seed)
    lo, hi = scene.bounds
    origins = rng.uniform(lo - (hi - lo), hi + (hi - lo), (n, 3))
    targets = rng.uniform(lo, hi, (n, 3))
    return origins, targets - origins


def every_query(scene, n=20000, **kw):
    o, d = rays(scene, n)
    points = o[: n // 4]
    cam = raycast.camera.look_at(tuple(scene.bounds[1] * 3), tuple(scene.bounds.mean(axis=0)))
    return {
        "cast": scene.cast(o, d, aovs=raycast.CAST_OUTPUTS[:7], **kw),
        "occluded": scene.occluded(o, d, **kw),
        "list": scene.list_intersections(o, d, **kw),
        "count": scene.count_intersections(o, d, **kw),
        "contains": scene.contains(points, **kw),
        "closest": scene.closest_points(points, **kw),
        "signed": scene.signed_distance(points, **kw),
        "render": scene.render(cam, 96, 80, ("depth", "z", "id", "normal"), **kw),
    }


def same(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


def test_pieces_and_threads_change_no_result(scene, monkeypatch):
    whole = every_query(scene)
    # Many tiny pieces (a few rays, or one image row, each).
    monkeypatch.setattr(_chunks, "FIRST", 7)
    monkeypatch.setattr(_chunks, "SMALLEST", 1)
    monkeypatch.setattr(_chunks, "TARGET", 1e-9)
    assert same(every_query(scene), whole)
    assert same(every_query(scene, nthreads=1), whole)
    assert same(every_query(scene, nthreads=10_000), whole)


def test_progress_hears_each_piece(scene, monkeypatch):
    monkeypatch.setattr(_chunks, "FIRST", 1000)
    monkeypatch.setattr(_chunks, "TARGET", 1e-9)  # pieces shrink to SMALLEST
    heard = []
    o, d = rays(scene, 5000)
    scene.cast(o, d, progress=lambda done, total: heard.append((done, total)))
    assert heard[0] == (1000, 5000) and heard[-1] == (5000, 5000) and len(heard) > 5
    assert all(a[0] < b[0] for a, b in zip(heard, heard[1:]))

    class Bar:  # what tqdm offers: update(n)
        n = 0

        def update(self, k):
            self.n += k

    bar = Bar()
    scene.render(raycast.camera.look_at((0, 0, 5), (0, 0, 0)), 50, 40, progress=bar)
    assert bar.n == 40  # rows


def test_ctrl_c_stops_a_call_between_pieces(scene, monkeypatch):
    # The hook sends SIGINT after the first piece; Python raises KeyboardInterrupt before the
    # call has done all its rays (before this change it could only do so after the last).
    # Python leaves SIGINT ignored when it starts with it ignored (as under `nohup bash -c`
    # in the background), so the test installs Python's own handler for its duration; and
    # `raise_signal` delivers the signal to this thread, not to any thread of the process.
    monkeypatch.setattr(_chunks, "FIRST", 2000)
    o, d = rays(scene, 200_000)
    heard = []

    def interrupt(done, total):
        heard.append(done)
        if len(heard) == 1:
            signal.raise_signal(signal.SIGINT)

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            scene.cast(o, d, progress=interrupt)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert heard[-1] < 200_000


def test_nthreads_is_checked(scene):
    for bad in (-1, 1.5, "2", True):
        with pytest.raises((ValueError, TypeError), match="nthreads"):
            scene.occluded([[0, 0, 5]], [[0, 0, -1]], nthreads=bad)


def test_bad_rays_and_points_are_named_by_their_index_in_the_batch(scene, monkeypatch):
    monkeypatch.setattr(_chunks, "FIRST", 3)
    monkeypatch.setattr(_chunks, "SMALLEST", 1)
    o, d = rays(scene, 40)
    d[17] = 0.0
    with pytest.raises(ValueError, match=r"^ray 17: "):
        scene.cast(o, d)
    with pytest.raises(ValueError, match=r"^ray \(3, 2\): "):
        scene.cast(o.reshape(8, 5, 3), d.reshape(8, 5, 3))
    points = o.copy()
    points[23, 1] = np.inf
    with pytest.raises(ValueError, match=r"^point 23 is not finite"):
        scene.distance(points)
