"""The scale-out story of docs/python.md on a real engine: a distributed.LocalCluster of two
worker processes renders several scenes (the docs' dask.bag example) and casts ray batches
against one pickled Scene, and every result equals the same call made here, bit for bit.

Run: .venv/bin/python -m pytest tests/python/test_dask.py
"""

from pathlib import Path

import numpy as np
import pytest

import raycast

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"
SCENES = [
    FIXTURES / "gltf" / "cube.gltf",
    FIXTURES / "gltf" / "instances.gltf",
    FIXTURES / "obj" / "two_objects.obj",
]


def depth_image(path):
    # The docs' example, as written there.
    scene = raycast.load(path)
    lo, hi = scene.bounds
    eye = hi + (hi - lo)  # from above one corner
    cam = raycast.camera.look_at(eye, (lo + hi) / 2, yfov_deg=40)
    return path, scene.render(cam, 64, 48, aovs=("depth",))["depth"]


def cast_batch(scene, origins, directions):
    return scene.cast(origins, directions, aovs=("t", "id", "prim", "normal"))


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_many_scenes_on_worker_processes(client):
    import dask.bag as db

    images = dict(
        db.from_sequence([str(p) for p in SCENES], npartitions=len(SCENES))
        .map(depth_image)
        .compute()
    )
    for path in SCENES:
        _, here = depth_image(str(path))
        assert np.array_equal(images[str(path)], here)


def test_one_scene_many_ray_batches(client):
    scene = raycast.load(SCENES[1])
    rng = np.random.default_rng(4)
    batches = [(rng.uniform(-6, 6, (500, 3)), rng.normal(size=(500, 3))) for _ in range(6)]
    remote = client.scatter(scene, broadcast=True)
    futures = [client.submit(cast_batch, remote, o, d) for o, d in batches]
    for (o, d), future in zip(batches, futures):
        got, here = future.result(), cast_batch(scene, o, d)
        assert got.keys() == here.keys() and all(np.array_equal(got[k], here[k]) for k in here)
    # The workers are other processes: each loaded the scene from its pickle.
    pids = set(client.run(lambda: __import__("os").getpid()).values())
    assert len(pids) == 2 and __import__("os").getpid() not in pids
