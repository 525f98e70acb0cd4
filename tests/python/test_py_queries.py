"""raycast.Scene's multiple-hit queries, containment, the GIL release, and agreement with the
command line's rays mode.

Run: .venv/bin/python -m pytest tests/python/test_py_queries.py
"""

import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh

import raycast
from raycast_tools.paths import find_raycast

ROOT = Path(__file__).resolve().parents[2]
CUBE = ROOT / "fixtures" / "gltf" / "cube.gltf"


@pytest.fixture(scope="module")
def cube():
    return raycast.load(CUBE)


def test_rays_through_shared_edges_and_vertices_cross_twice(cube):
    # Every line through the interior of the closed cube [-1, 1]^3 crosses its surface twice:
    # through the faces' diagonal edges (x = y on +-Z), through the cube's edges' midpoints
    # and through opposite corners.
    s = np.linspace(-0.75, 0.75, 7)
    origins = np.concatenate(
        [
            np.column_stack([s, s, np.full(7, 5.0)]),  # on the diagonal of the +Z and -Z faces
            np.column_stack([s, -s, np.full(7, 5.0)]),
            [[-2.0, -2.0, -2.0], [3.0, 3.0, -3.0], [0.0, -3.0, -3.0]],  # corners, edge midpoints
        ]
    )
    directions = np.concatenate(
        [np.tile([0.0, 0.0, -1.0], (14, 1)), [[1, 1, 1], [-1, -1, 1], [0, 1, 1]]]
    )
    counts = cube.count_intersections(origins, directions)
    assert counts.tolist() == [2] * len(origins)
    found = cube.list_intersections(origins[:1], directions[:1])
    assert found["t"].tolist() == [4.0, 6.0] and found["id"].tolist() == [1, 1]
    # The near crossing is on the +Z face (prims 0, 1), the far one on -Z (prims 2, 3).
    assert found["prim"][0] in (0, 1) and found["prim"][1] in (2, 3)


def test_crossings_match_trimesh_counts_on_a_sphere():
    # Random lines through an icosphere: 2 crossings when trimesh's intersector finds hits
    # (it reports entry and exit), 0 otherwise; tmin/tmax cut the list.
    sphere = trimesh.creation.icosphere(subdivisions=3)
    scene = raycast.load_bytes(sphere.export(file_type="glb"), "sphere.glb")
    rng = np.random.default_rng(5)
    origins = rng.normal(size=(400, 3)) * 0 + [0.0, 0.0, -4.0]
    directions = np.column_stack([rng.uniform(-0.3, 0.3, (400, 2)), np.ones(400)])
    reference = trimesh.ray.ray_triangle.RayMeshIntersector(sphere)
    _, index_ray = reference.intersects_id(origins, directions, multiple_hits=True)
    ref_counts = np.bincount(index_ray, minlength=400)
    counts = scene.count_intersections(origins, directions)
    assert set(counts.tolist()) <= {0, 2}
    clear = ref_counts != 1  # trimesh may drop one of two hits at an edge
    assert (counts[clear] == ref_counts[clear]).all()
    found = scene.list_intersections(origins, directions)
    first = scene.cast(origins, directions, aovs=["t"])["t"]
    hit = counts > 0
    assert (found["t"][found["ray_splits"][:-1][hit]] == first[hit]).all()
    cut = scene.count_intersections(origins, directions, tmax=first + 1e-9)
    assert (cut[hit] == 1).all()


def test_contains_on_a_grid(cube):
    # Analysis: inside the cube [-1, 1]^3 iff every |coordinate| < 1.
    g = np.linspace(-1.5, 1.5, 13)
    points = np.stack(np.meshgrid(g, g, g), -1).reshape(-1, 3)
    expected = (np.abs(points) < 1).all(axis=1)
    away = (np.abs(np.abs(points) - 1) > 1e-9).all(axis=1)
    assert (cube.contains(points)[away] == expected[away]).all()
    assert cube.occluded(points[:1], [[1.0, 0.0, 0.0]]).tolist() == [False]


def test_cast_releases_the_gil(cube):
    # While one thread is inside cast(), another runs Python code: the main thread records
    # the times of its loop iterations, and some fall inside the middle of the cast call.
    n = 1_500_000
    rng = np.random.default_rng(6)
    origins = np.tile([0.0, 0.0, 5.0], (n, 1))
    directions = np.column_stack([rng.uniform(-0.3, 0.3, (n, 2)), -np.ones(n)])
    span = {}
    started = threading.Event()

    def work():
        started.set()
        span["start"] = time.perf_counter()
        cube.cast(origins, directions, aovs=["t", "normal", "id"])
        span["end"] = time.perf_counter()

    thread = threading.Thread(target=work)
    ticks = []
    thread.start()
    started.wait()
    while thread.is_alive():
        ticks.append(time.perf_counter())
    thread.join()
    start, end = span["start"], span["end"]
    assert end - start > 0.02, "the cast is too short for the test to mean anything"
    middle = [t for t in ticks if start + (end - start) / 3 < t < end - (end - start) / 3]
    assert len(middle) > 10


def test_cast_is_bit_identical_to_the_cli_rays_mode(tmp_path):
    # The same rays through `raycast SCENE --rays` and through cast(): equal bits in every
    # buffer, misses included.
    binary = find_raycast()
    if not binary.exists():
        pytest.fail(f"raycast binary not found at {binary}: build it with cargo build --release")
    rng = np.random.default_rng(7)
    scene_path = ROOT / "fixtures" / "gltf" / "instances.gltf"
    scene = raycast.load(scene_path)
    lo, hi = scene.bounds
    origins = rng.uniform(lo - 1, hi + 1, (3000, 3))
    directions = rng.uniform(lo, hi, (3000, 3)) - origins
    rays = np.concatenate([origins, directions], axis=1)
    np.save(tmp_path / "rays.npy", rays)
    out = tmp_path / "out"
    aovs = ["depth", "normal", "position", "id", "prim"]
    subprocess.run(
        [
            binary,
            scene_path,
            "--rays",
            tmp_path / "rays.npy",
            "--aov",
            ",".join(aovs),
            "--out",
            out,
            "--quiet",
        ],
        check=True,
    )
    ours = scene.cast(origins, directions, aovs=aovs)
    for aov in aovs:
        cli = np.load(out / f"{aov}.npy")
        assert cli.dtype == ours[aov].dtype and cli.shape == ours[aov].shape
        assert cli.tobytes() == ours[aov].tobytes(), aov
    assert (ours["id"] > 0).sum() > 100


def test_render_is_bit_identical_to_the_cli(tmp_path, cube):
    binary = find_raycast()
    out = tmp_path / "out"
    subprocess.run(
        [
            binary,
            CUBE,
            "--aov",
            "depth,normal,id",
            "--format",
            "npy",
            "--width",
            "24",
            "--height",
            "16",
            "--out",
            out,
            "--quiet",
        ],
        check=True,
    )
    ours = cube.render(cube.cameras[0], 24, 16, aovs=["depth", "normal", "id"])
    for aov in ("depth", "normal", "id"):
        assert np.load(out / f"{aov}.npy").tobytes() == ours[aov].tobytes(), aov


def _ranged_rays(scene, n, seed):
    """Random rays through the scene's box with per-ray ranges: some from 0, some cut short,
    some starting past their first hit."""
    rng = np.random.default_rng(seed)
    lo, hi = scene.bounds
    origins = rng.uniform(lo - 1, hi + 1, (n, 3))
    directions = rng.uniform(lo, hi, (n, 3)) - origins
    tmin = np.where(rng.random(n) < 0.3, 0.0, rng.uniform(0.0, 0.8, n))
    tmax = np.where(rng.random(n) < 0.3, np.inf, tmin + rng.uniform(0.0, 1.5, n))
    return origins, directions, tmin, tmax


def _run_cli(scene_path, rays, out, *extra):
    subprocess.run(
        [find_raycast(), scene_path, "--rays", rays, "--out", out, "--quiet", *extra],
        check=True,
    )


def test_cli_ranges_t_and_bary_are_bit_identical_to_cast(tmp_path):
    # An (N, 8) ray file (origin, direction, tmin, tmax) through the CLI and the same rays and
    # ranges through cast(): equal bits in every output, t and bary included.
    scene_path = ROOT / "fixtures" / "gltf" / "instances.gltf"
    scene = raycast.load(scene_path)
    origins, directions, tmin, tmax = _ranged_rays(scene, 3000, 11)
    np.save(tmp_path / "rays.npy", np.column_stack([origins, directions, tmin, tmax]))
    aovs = ["t", "depth", "normal", "position", "bary", "id", "prim"]
    _run_cli(scene_path, tmp_path / "rays.npy", tmp_path / "out", "--aov", ",".join(aovs))
    ours = scene.cast(origins, directions, tmin=tmin, tmax=tmax, aovs=aovs)
    for aov in aovs:
        cli = np.load(tmp_path / "out" / f"{aov}.npy")
        assert cli.dtype == ours[aov].dtype and cli.shape == ours[aov].shape, aov
        assert cli.tobytes() == ours[aov].tobytes(), aov
    hit = ours["id"] > 0
    assert 100 < hit.sum() < len(hit)
    # The ranges were applied: every hit lies in (tmin, tmax], and some rays that hit from 0
    # miss in their range.
    assert ((ours["t"][hit] > tmin[hit]) & (ours["t"][hit] <= tmax[hit])).all()
    from_zero = scene.cast(origins, directions, aovs=["id"])["id"] > 0
    assert (from_zero & ~hit).sum() > 100


def test_cli_hits_are_bit_identical_to_list_intersections(tmp_path):
    scene_path = ROOT / "fixtures" / "gltf" / "instances.gltf"
    scene = raycast.load(scene_path)
    origins, directions, tmin, tmax = _ranged_rays(scene, 2000, 12)
    np.save(tmp_path / "rays.npy", np.column_stack([origins, directions, tmin, tmax]))
    ours = scene.list_intersections(origins, directions, tmin=tmin, tmax=tmax)
    counts = np.diff(ours["ray_splits"])
    assert counts.max() >= 3 and (counts == 0).any()
    _run_cli(scene_path, tmp_path / "rays.npy", tmp_path / "all", "--hits", "all")
    with np.load(tmp_path / "all" / "hits.npz") as cli:
        assert sorted(cli.files) == ["id", "prim", "ray_splits", "t"]
        for key in ("ray_splits", "t", "id", "prim"):
            assert cli[key].dtype == ours[key].dtype, key
            assert cli[key].tobytes() == ours[key].tobytes(), key
    # --hits 2: the nearest two of each ray's list.
    _run_cli(scene_path, tmp_path / "rays.npy", tmp_path / "two", "--hits", "2")
    keep = np.concatenate(
        [
            np.arange(a, min(b, a + 2))
            for a, b in zip(ours["ray_splits"][:-1], ours["ray_splits"][1:])
        ]
    ).astype(np.int64)
    with np.load(tmp_path / "two" / "hits.npz") as cli:
        assert (np.diff(cli["ray_splits"]) == np.minimum(counts, 2)).all()
        for key in ("t", "id", "prim"):
            assert cli[key].tobytes() == ours[key][keep].tobytes(), key


def test_occluded_agrees_with_cast_under_ranges():
    # occluded() stops at the first crossing in range; cast() looks for the nearest: the same
    # rays must be occluded exactly where cast() finds a hit.
    scene = raycast.load(ROOT / "fixtures" / "gltf" / "instances.gltf")
    origins, directions, tmin, tmax = _ranged_rays(scene, 3000, 13)
    occluded = scene.occluded(origins, directions, tmin=tmin, tmax=tmax)
    hit = scene.cast(origins, directions, tmin=tmin, tmax=tmax, aovs=["id"])["id"] > 0
    assert (occluded == hit).all()
    assert 100 < hit.sum() < len(hit) - 100
