"""raycast's nearest points on clipped quadrics against a 50-digit mpmath reference that works
by another method (tools/raycast_tools/reference/quadric_distance_reference.py: sampling and
Newton in the quadric's own coordinates, nothing diagonalised), on random placements of every
kind of quadric: points random around the clip box, 1e-12 off the surface, at the centre and 1e-13
off it (on an axis), 1e6 away, and the same about a quadric placed 1e6 from the origin.

The bound is stated in ε (2⁻⁵³) times the scale `|p − c| + h + |c|`, `c` the clip box's
centre in the world and `h` its half-diagonal: the rounding of the query relative to the
quadric is already ε|p − c|, and that of the quadric's placement (the world image of its
anchor, which its coefficients are written about) ε|c|.

Run: .venv/bin/python -m pytest tests/python/test_quadric_distance.py
"""

import json
import math

import mpmath
import numpy as np
import pytest

import raycast
from raycast_tools.fixtures.gltf_writer import quadric_document
from raycast_tools.reference.quadric_distance_reference import Clipped

EPS = np.finfo(np.float64).eps / 2

# The bound on |d − d_ref| in units of EPS · scale (see the module docs).
BOUND = 8.0

# Canonical local forms: Q (diagonal), P, R and the clip box (None: unclipped).
KINDS = {
    "ellipsoid": ([1.0, 0.25, 4.0], [0, 0, 0], -1.0, None),
    "cut_ellipsoid": ([1.0, 0.25, 4.0], [0, 0, 0], -1.0, [[-2, -1, -2], [2, 3, 0.2]]),
    "elliptic_paraboloid": ([1.0, 0.5, 0.0], [0, 0, -1], 0.0, [[-2, -2, -1], [2, 2, 3]]),
    "hyperbolic_paraboloid": ([1.0, -1.0, 0.0], [0, 0, -1], 0.0, [[-2, -2, -2], [2, 2, 2]]),
    "hyperboloid_one_sheet": ([1.0, 1.0, -1.0], [0, 0, 0], -1.0, [[-2, -2, -2], [2, 2, 2]]),
    "hyperboloid_two_sheets": ([-1.0, -1.0, 1.0], [0, 0, 0], -1.0, [[-3, -3, -3], [3, 3, 3]]),
    "one_sheet_of_two": ([-1.0, -1.0, 1.0], [0, 0, 0], -1.0, [[-3, -3, 0.5], [3, 3, 3]]),
    "cone": ([1.0, 1.0, -1.0], [0, 0, 0], 0.0, [[-2, -2, -2], [2, 2, 2]]),
    "one_nappe": ([1.0, 1.0, -1.0], [0, 0, 0], 0.0, [[-2, -2, 0], [2, 2, 2]]),
    "elliptic_cylinder": ([1.0, 0.25, 0.0], [0, 0, 0], -1.0, [[-2, -3, -2], [2, 3, 2]]),
    "hyperbolic_cylinder": ([1.0, -1.0, 0.0], [0, 0, 0], -1.0, [[-3, -3, -2], [3, 3, 2]]),
    "parabolic_cylinder": ([1.0, 0.0, 0.0], [0, -1, 0], 0.0, [[-2, -1, -2], [2, 3, 2]]),
}


# The placements and query points are computed with one float operation at a time in a fixed
# order (no BLAS or LAPACK, whose kernels numpy picks by CPU and whose rounding differs from one
# CPU to another), so the test's inputs are the same bits on every machine.


def _matmul(a, b):
    """a @ b for 3×3 arrays, summed left to right."""
    return np.array(
        [
            [a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] for j in range(3)]
            for i in range(3)
        ]
    )


def _matvec(a, v):
    """a @ v for a 3×3 array and a 3-vector, summed left to right."""
    return np.array([a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2] for i in range(3)])


def _norm(v):
    """|v|, its squares summed left to right."""
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _orthonormal(m):
    """The columns of `m` made orthonormal by Gram-Schmidt: a rotation or a reflection."""
    cols = []
    for j in range(3):
        v = np.array([m[i][j] for i in range(3)])
        for c in cols:
            v = v - (c[0] * v[0] + c[1] * v[1] + c[2] * v[2]) * c
        cols.append(v / _norm(v))
    return np.array([[cols[j][i] for j in range(3)] for i in range(3)])


def placement(rng, offset):
    """A random rotation times scales 0.5..2 and shears up to 0.3, translated to `offset`
    plus up to 3 in each axis: a 3×4 row-major [A | t]."""
    rotation = _orthonormal(rng.normal(size=(3, 3)))
    shear = np.eye(3) + np.triu(rng.uniform(-0.3, 0.3, size=(3, 3)), 1)
    a = _matmul(_matmul(rotation, shear), np.diag(rng.uniform(0.5, 2.0, size=3)))
    t = np.asarray(offset, dtype=float) + rng.uniform(-3, 3, size=3)
    return np.hstack([a, t[:, None]])


def write_scene(path, q, p, r, box, affine):
    """A glTF file with the one quadric node."""
    matrix = np.eye(4)
    matrix[:3, :] = affine
    quadric = {"Q": [float(v) for v in np.diag(q).ravel()], "P": [float(v) for v in p]}
    quadric["R"] = float(r)
    if box is not None:
        quadric["bounds"] = {"min": [float(v) for v in box[0]], "max": [float(v) for v in box[1]]}
    doc = quadric_document(quadric, [float(v) for v in matrix.T.ravel()])
    path.write_text(json.dumps(doc))


def query_points(rng, clipped, affine, box):
    """The query points of one scene (world, float64) and the world box centre and
    half-diagonal the scale is measured from."""
    lo, hi = (np.array([-1.0, -2.0, -0.5]), np.array([1.0, 2.0, 0.5])) if box is None else box
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    a, t = affine[:, :3], affine[:, 3]
    centre = _matvec(a, (lo + hi) / 2) + t
    half = _norm(_matvec(a, (hi - lo) / 2))
    points = [
        _matvec(a, rng.uniform(lo - 0.5 * (hi - lo), hi + 0.5 * (hi - lo))) + t for _ in range(6)
    ]
    for _ in range(3):
        # 1e-12 off the surface along its normal, either side.
        d = [mpmath.mpf(v) for v in rng.normal(size=3)]
        for x in clipped.on_line(clipped.centre(), d):
            normal, _ = clipped.world_normal(x)
            if clipped.in_box(x) and normal is not None:
                side = 1e-12 if rng.uniform() < 0.5 else -1e-12
                w = clipped.world(x)
                points.append(np.array([float(w[i] + normal[i] * side) for i in range(3)]))
                break
    points.append(centre)
    points.append(centre + 1e-13 * rng.normal(size=3))
    for _ in range(2):
        u = rng.normal(size=3)
        points.append(centre + 1e6 * u / _norm(u))
    return np.array(points), centre, half


def measure(tmp_path, name, seed, offset):
    """Per point: raycast's distance, the reference's, and the scale; and raycast's points."""
    q, p, r, box = KINDS[name]
    rng = np.random.default_rng(seed)
    affine = placement(rng, offset)
    path = tmp_path / f"{name}.gltf"
    write_scene(path, q, p, r, box, affine)
    clipped = Clipped(np.diag(q), p, r, box, affine)
    points, centre, half = query_points(rng, clipped, affine, box)
    found = raycast.load(str(path)).closest_points(points)
    rows = []
    for i, point in enumerate(points):
        ref, _ = clipped.nearest(point)
        scale = _norm(point - centre) + half + _norm(centre)
        rows.append((found["distance"][i], float(ref), scale))
    return rows, found, points, clipped


ERRORS = {}


@pytest.mark.parametrize("offset", [0.0, 1e6], ids=["near_origin", "at_1e6"])
@pytest.mark.parametrize("name", sorted(KINDS))
def test_quadric_distances_agree_with_mpmath(tmp_path, name, offset):
    rows, found, points, clipped = measure(tmp_path, name, seed=len(name), offset=[offset] * 3)
    errors = [abs(d - ref) / (EPS * scale) for d, ref, scale in rows]
    ERRORS[(name, offset)] = max(errors)
    print(f"{name} at {offset:g}: max |d - d_ref| = {max(errors):.2f} eps * scale")
    for (d, ref, scale), e, point in zip(rows, errors, points):
        assert e <= BOUND, (
            f"{name}: point {point}: raycast {d!r}, mpmath {ref!r}, {e:.1f} eps·scale"
        )
    # The points returned are on the clipped surface and at the distance reported.
    for i, point in enumerate(points):
        x = clipped.local([mpmath.mpf(v) for v in found["point"][i]])
        scale = rows[i][2]
        assert clipped.in_box(x, slack=mpmath.mpf(1e-9)), (name, point)
        _, gradient = clipped.world_normal(x)
        off = abs(clipped.f(x)) / max(gradient, mpmath.mpf(10) ** -30)
        assert off <= BOUND * EPS * scale or abs(clipped.f(x)) < 1e-13, (name, point, off)
        assert abs(np.linalg.norm(found["point"][i] - point) - found["distance"][i]) <= (
            BOUND * EPS * scale
        )
        assert abs(np.linalg.norm(found["normal"][i]) - 1) < 1e-12


def test_a_sphere_by_hand(tmp_path):
    """A unit sphere at the origin: its centre (every point nearest), a point on an axis,
    one 1e-12 inside, one far away."""
    path = tmp_path / "sphere.gltf"
    write_scene(
        path, [1.0, 1.0, 1.0], [0, 0, 0], -1.0, None, np.hstack([np.eye(3), np.zeros((3, 1))])
    )
    scene = raycast.load(str(path))
    points = np.array([[0, 0, 0], [0, 0, 3], [1 - 1e-12, 0, 0], [1e6, 0, 0]], dtype=float)
    found = scene.closest_points(points)
    np.testing.assert_allclose(found["distance"], [1, 2, 1e-12, 1e6 - 1], rtol=1e-4, atol=0)
    assert abs(found["distance"][2] - 1e-12) <= 2 * EPS
    np.testing.assert_array_equal(found["point"][1], [0, 0, 1])
    np.testing.assert_allclose(found["normal"][1], [0, 0, 1])
    signed = scene.signed_distance(points)
    np.testing.assert_array_equal(np.sign(signed), [-1, 1, -1, 1])


def test_open_quadrics_have_no_sign(tmp_path):
    q, p, r, box = KINDS["hyperboloid_one_sheet"]
    path = tmp_path / "open.gltf"
    write_scene(path, q, p, r, box, np.hstack([np.eye(3), np.zeros((3, 1))]))
    scene = raycast.load(str(path))
    assert scene.distance(np.zeros((1, 3)))[0] == pytest.approx(1.0, abs=1e-15)
    with pytest.raises(ValueError, match="hyperboloid_one_sheet.*no inside"):
        scene.signed_distance(np.zeros((1, 3)))
    with pytest.raises(ValueError, match="winding.*quadric"):
        scene.signed_distance(np.zeros((1, 3)), sign="winding")
