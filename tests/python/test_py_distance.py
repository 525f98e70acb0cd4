"""raycast.Scene's distance queries against exact answers: nearest points and distances
against exact rational arithmetic (a different method from raycast's region test: the
minimum of the squared distance over the triangle's interior stationary point, its edges and
its vertices), and signed distances against exact membership of shapes whose inside is known
by construction (a convex polyhedron's half-spaces, an L-shaped prism's two boxes).

Run: .venv/bin/python -m pytest tests/python/test_py_distance.py
"""

from fractions import Fraction
from pathlib import Path

import mpmath
import numpy as np
import pytest
import trimesh

import raycast

EPS = np.finfo(np.float64).eps / 2


def exact_squared_distance(p, tri):
    """The exact squared distance from point p to triangle tri (Fractions of the floats)."""
    p = [Fraction(x) for x in p]
    a, b, c = ([Fraction(x) for x in v] for v in tri)

    def sub(u, v):
        return [x - y for x, y in zip(u, v)]

    def dot(u, v):
        return sum(x * y for x, y in zip(u, v))

    def at(s, t):
        # The point a + s (b - a) + t (c - a), and its squared distance from p.
        q = [a[i] + s * (b[i] - a[i]) + t * (c[i] - a[i]) for i in range(3)]
        d = sub(q, p)
        return dot(d, d)

    ab, ac, ap = sub(b, a), sub(c, a), sub(p, a)
    candidates = [at(0, 0), at(1, 0), at(0, 1)]
    # The interior stationary point of |a + s ab + t ac - p|^2 (Cramer's rule).
    g11, g12, g22 = dot(ab, ab), dot(ab, ac), dot(ac, ac)
    r1, r2 = dot(ab, ap), dot(ac, ap)
    det = g11 * g22 - g12 * g12
    if det != 0:
        s = (r1 * g22 - r2 * g12) / det
        t = (g11 * r2 - g12 * r1) / det
        if s >= 0 and t >= 0 and s + t <= 1:
            candidates.append(at(s, t))
    # Each edge's clamped projection.
    for u, v in ((a, b), (b, c), (c, a)):
        e, w = sub(v, u), sub(p, u)
        ee = dot(e, e)
        if ee != 0:
            s = min(max(dot(e, w) / ee, Fraction(0)), Fraction(1))
            q = [u[i] + s * e[i] for i in range(3)]
            d = sub(q, p)
            candidates.append(dot(d, d))
    return min(candidates)


def exact_distance(p, triangles):
    """The exact distance (as mpmath at 50 digits) to the nearest of `triangles`, and its
    index."""
    squared = [exact_squared_distance(p, t) for t in triangles]
    best = min(range(len(squared)), key=squared.__getitem__)
    with mpmath.workdps(50):
        value = squared[best]
        return mpmath.sqrt(mpmath.mpf(value.numerator) / value.denominator), best


def random_mesh(rng, count, offset):
    """`count` random triangles of size about 1 around `offset`, as vertices and faces."""
    centres = rng.uniform(-2, 2, (count, 1, 3))
    vertices = (centres + rng.normal(scale=0.6, size=(count, 3, 3))).reshape(-1, 3) + offset
    return vertices, np.arange(3 * count).reshape(-1, 3)


def near_features(rng, vertices, faces, count, scale):
    """Points on random faces, edges and vertices, pushed off by about `scale`."""
    tri = vertices[faces[rng.integers(len(faces), size=count)]]
    w = rng.dirichlet([1, 1, 1], size=count)
    kind = rng.integers(3, size=count)
    w[kind == 1, 2] = 0  # on an edge
    w[kind == 2] = [1, 0, 0]  # on a vertex
    w /= w.sum(axis=1, keepdims=True)
    on = np.einsum("ni,nij->nj", w, tri)
    return on + rng.normal(size=(count, 3)) * scale


@pytest.mark.parametrize("offset", [0.0, 1e3, 1e6])
def test_nearest_distances_agree_with_exact_arithmetic(offset):
    rng = np.random.default_rng(int(offset) % 1000 + 11)
    vertices, faces = random_mesh(rng, 40, offset)
    scene = raycast.Scene.from_arrays(vertices, faces)
    triangles = vertices[faces]
    points = np.concatenate(
        [
            rng.uniform(-4, 4, (60, 3)) + offset,  # anywhere
            near_features(rng, vertices, faces, 60, 1e-12 * max(1.0, offset)),
            near_features(rng, vertices, faces, 30, 1e-6),
        ]
    )
    found = scene.closest_points(points)
    worst = 0.0
    for i, p in enumerate(points):
        truth, index = exact_distance(p, triangles)
        # Allowed: a few ulps of the triangle's size and the query's distance from it.
        size = max(np.abs(triangles[index] - triangles[index][0]).max(), float(truth))
        error = abs(mpmath.mpf(found["distance"][i]) - truth)
        worst = max(worst, float(error / (EPS * size)))
        assert error <= 16 * EPS * size, (i, p, found["distance"][i], truth)
        # The reported triangle is at that distance too (ties may pick another).
        got = exact_squared_distance(p, triangles[found["prim"][i]])
        with mpmath.workdps(50):
            other = mpmath.sqrt(mpmath.mpf(got.numerator) / got.denominator)
        assert abs(other - truth) <= 16 * EPS * size
    # The point, the barycentric weights and the triangle agree.
    tri = triangles[found["prim"]]
    rebuilt = np.einsum("ni,nij->nj", found["bary"], tri)
    assert np.allclose(rebuilt, found["point"], rtol=0, atol=1e-13 * max(1.0, offset))
    assert np.allclose(
        np.linalg.norm(found["point"] - points, axis=1), found["distance"], atol=1e-9
    )
    assert worst < 16


def test_shapes_misses_and_refusals():
    vertices = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    scene = raycast.Scene.from_arrays(vertices, np.array([[0, 1, 2]]))
    out = scene.closest_points(np.zeros((4, 5, 3)))
    assert out["point"].shape == (4, 5, 3) and out["distance"].shape == (4, 5)
    assert scene.signed_distance(np.zeros((2, 3, 3))).shape == (2, 3)
    assert scene.occupancy(np.zeros((7, 3))).dtype == np.float32
    with pytest.raises(ValueError, match="point 1 is not finite"):
        scene.distance([[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match="unknown sign rule"):
        scene.signed_distance([[0, 0, 0]], sign="votes")


def test_quadric_signs_only_where_the_quadric_is_closed():
    """The lecture's sphere (radius 2, closed) has distances and signs; the clipped cylinder
    fixture's objects are open: distances, and a one-line refusal of the sign naming the
    object (tests/python/test_quadric_distance.py checks the distances against mpmath)."""
    root = Path(__file__).resolve().parents[2] / "fixtures" / "quadrics"
    sphere = raycast.load(root / "sphere_coefficients.gltf")
    points = np.array([[0.0, 0.0, 5.0], [0.0, 1.0, 0.0]])
    assert np.allclose(sphere.signed_distance(points), [3.0, -1.0], rtol=0, atol=1e-15)
    cylinder = raycast.load(root / "cylinder.gltf")
    assert cylinder.distance(points).shape == (2,)
    with pytest.raises(ValueError, match=r"object 'scaled' \(id 1\).*no inside"):
        cylinder.signed_distance(points)


def convex_truth(mesh, points):
    """-1 strictly inside, +1 strictly outside, 0 on the surface of a convex mesh, exactly:
    the signs of (p - a) . n for every face's plane, in rationals."""
    out = []
    planes = []
    for face in mesh.faces:
        a, b, c = ([Fraction(x) for x in mesh.vertices[i]] for i in face)
        u = [b[i] - a[i] for i in range(3)]
        v = [c[i] - a[i] for i in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        planes.append((a, n))
    for p in points:
        p = [Fraction(x) for x in p]
        heights = [sum((p[i] - a[i]) * n[i] for i in range(3)) for a, n in planes]
        if any(h > 0 for h in heights):
            out.append(1)
        elif all(h < 0 for h in heights):
            out.append(-1)
        else:
            out.append(0)
    return np.array(out)


def l_prism():
    """A closed L-shaped prism (x, y in the L of [0,2]x[0,1] and [0,1]x[0,2], z in [0, 1]),
    wound outward, and its exact inside test."""
    ring = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    vertices = [(x, y, 0.0) for x, y in ring] + [(x, y, 1.0) for x, y in ring]
    faces = []
    for k in range(1, 5):  # fans from the corner (0, 0): the L is star-shaped from it
        faces.append((0, k + 1, k))  # bottom, facing -z
        faces.append((6, 6 + k, 6 + k + 1))  # top, facing +z
    for k in range(6):
        j = (k + 1) % 6
        faces.append((k, j, 6 + j))
        faces.append((k, 6 + j, 6 + k))
    mesh = trimesh.Trimesh(np.array(vertices, dtype=float), np.array(faces), process=False)

    def truth(points):
        x, y, z = (np.asarray(points)[:, i] for i in range(3))
        inside = (
            (0 < z)
            & (z < 1)
            & (((0 < x) & (x < 2) & (0 < y) & (y < 1)) | ((0 < x) & (x < 1) & (0 < y) & (y < 2)))
        )
        return inside

    return mesh, truth


def test_the_l_prism_is_closed_and_outward():
    mesh, _ = l_prism()
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume == pytest.approx(3.0)


def test_signed_distance_signs_are_never_wrong_on_closed_meshes():
    rng = np.random.default_rng(23)
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=1.3)
    scene = raycast.Scene.from_arrays(sphere.vertices, sphere.faces)
    points = np.concatenate(
        [
            rng.uniform(-1.6, 1.6, (1500, 3)),
            near_features(rng, sphere.vertices, sphere.faces, 1500, 1e-12),
            sphere.vertices[:50],  # exactly on vertices
        ]
    )
    truth = convex_truth(sphere, points)
    for rule in ("crossings", "winding"):
        signed = scene.signed_distance(points, sign=rule)
        sign = np.sign(signed)
        wrong = (sign != 0) & (sign != truth)
        assert not wrong.any(), (rule, points[wrong][:5], signed[wrong][:5])
        if rule == "crossings":
            # Beyond the rounding margin (about 2.4e-14 here) every side is certain.
            assert (sign != 0)[np.abs(signed) > 1e-13].all()
            assert (sign != 0)[scene.distance(points) > 1e-13].all()
    mesh, inside = l_prism()
    scene = raycast.Scene.from_arrays(mesh.vertices, mesh.faces)
    grid = np.stack(np.meshgrid(*[np.linspace(-0.5, 2.5, 31)] * 2, np.linspace(-0.5, 1.5, 21)), -1)
    points = np.concatenate(
        [grid.reshape(-1, 3), near_features(rng, mesh.vertices, mesh.faces, 3000, 1e-12)]
    )
    signed = scene.signed_distance(points)
    expected = np.where(inside(points), -1, 1)
    sign = np.sign(signed)
    assert not ((sign != 0) & (sign != expected)).any()
    certain = sign != 0
    assert np.array_equal((scene.occupancy(points) == 1)[certain], (sign < 0)[certain])


def test_instances_are_measured_as_placed():
    # One cube mesh drawn by five nodes (translated, rotated, scaled unevenly by a parent,
    # mirrored): raycast stores it once and places each instance; trimesh places the
    # triangles itself.
    path = Path(__file__).resolve().parents[2] / "fixtures" / "gltf" / "instances.gltf"
    bodies = trimesh.load(path, force="scene").dump()
    placed = trimesh.util.concatenate(bodies)
    triangles = placed.vertices[placed.faces]
    scene = raycast.load(path)
    rng = np.random.default_rng(3)
    points = np.concatenate(
        [rng.uniform(-5, 5, (150, 3)), near_features(rng, placed.vertices, placed.faces, 50, 1e-9)]
    )
    found = scene.closest_points(points)
    for i, p in enumerate(points):
        truth, _ = exact_distance(p, triangles)
        # A few ulps of the cubes' size, plus the two placements' rounding.
        assert abs(mpmath.mpf(found["distance"][i]) - truth) <= 1e-14, (
            p,
            found["distance"][i],
            truth,
        )
    # The cubes are convex and apart: inside one of them, exactly, is inside the scene.
    for body in bodies:
        if body.volume < 0:
            body.invert()  # the mirrored one, if trimesh kept its winding
    truth = np.min([convex_truth(body, points) for body in bodies], axis=0)
    sign = np.sign(scene.signed_distance(points))
    assert not ((sign != 0) & (sign != truth)).any()
    assert (sign != 0).mean() > 0.95


def test_info_says_which_meshes_are_closed_as_trimesh_does():
    mesh, _ = l_prism()
    sphere = trimesh.creation.icosphere(subdivisions=1)
    holed = trimesh.Trimesh(sphere.vertices, sphere.faces[1:], process=False)
    flipped = trimesh.Trimesh(
        sphere.vertices, np.concatenate([sphere.faces[:1, ::-1], sphere.faces[1:]])
    )
    for m in (mesh, sphere, holed, flipped):
        closed = m.is_watertight and m.is_winding_consistent
        info = raycast.Scene.from_arrays(m.vertices, m.faces).info()
        assert info["objects"][0]["closed"] is closed
    assert [m.is_watertight and m.is_winding_consistent for m in (holed, flipped)] == [False, False]


def test_the_command_line_gives_the_exact_distances_and_signs(tmp_path):
    import json
    import subprocess

    from raycast_tools.paths import find_raycast

    mesh, inside = l_prism()
    obj = tmp_path / "prism.obj"
    mesh.export(obj)
    rng = np.random.default_rng(8)
    points = np.concatenate(
        [
            rng.uniform(-0.5, 2.5, (200, 3)),
            near_features(rng, mesh.vertices, mesh.faces, 100, 1e-12),
        ]
    )
    np.save(tmp_path / "points.npy", points)
    binary = find_raycast()
    for _ in range(2):  # a second run replaces the first's files
        run = subprocess.run(
            [binary, "distance", obj, tmp_path / "points.npy", "--out", tmp_path / "d", "-q"],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 0, run.stderr
    d = {
        n: np.load(tmp_path / "d" / f"{n}.npy")
        for n in ("distance", "signed_distance", "point", "id", "prim")
    }
    triangles = trimesh.load(obj, process=False).triangles
    for i, p in enumerate(points):
        truth, _ = exact_distance(p, triangles)
        assert abs(mpmath.mpf(d["distance"][i]) - truth) <= 16 * EPS * 2
    sign = np.sign(d["signed_distance"])
    assert not ((sign != 0) & (sign != np.where(inside(points), -1, 1))).any()
    scene = raycast.load(obj)
    assert np.array_equal(d["signed_distance"], scene.signed_distance(points))
    assert np.array_equal(d["point"], scene.closest_points(points)["point"])
    sidecar = json.loads((tmp_path / "d" / "raycast.json").read_text())
    assert sidecar["points"] == len(points) and sidecar["sign"] == "crossings"
    assert sidecar["meshes"][0]["closed"] is True
    # A clipped cylinder is open: no sign, so the run (which writes signs) is refused.
    quadrics = Path(__file__).resolve().parents[2] / "fixtures" / "quadrics" / "cylinder.gltf"
    refused = subprocess.run(
        [binary, "distance", quadrics, tmp_path / "points.npy", "--out", tmp_path / "q"],
        capture_output=True,
        text=True,
    )
    assert refused.returncode == 2 and "no inside" in refused.stderr
    assert not (tmp_path / "q").exists()
