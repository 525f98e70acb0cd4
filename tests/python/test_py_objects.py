"""Scenes of several objects without a file: ``raycast.Scene.from_objects`` with meshes from
arrays and quadrics by coefficients, placed by a matrix. Expected values follow from the
geometry (distances to planes and spheres worked by hand).

Run: .venv/bin/python -m pytest tests/python/test_py_objects.py
"""

import pickle

import numpy as np
import pytest

import raycast

#: The unit sphere x² + y² + z² − 1 = 0.
UNIT_SPHERE = [1, 1, 1, 0, 0, 0, 0, 0, 0, -1]


def square(x0, z):
    """The square [x0, x0 + 1] × [0, 1] at height z, as two triangles facing +z."""
    v = np.array([[x0, 0, z], [x0 + 1, 0, z], [x0 + 1, 1, z], [x0, 1, z]], dtype=float)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def placed(scale, translation):
    """The 4×4 matrix that scales by ``scale`` and then translates by ``translation``."""
    m = np.diag([scale, scale, scale, 1.0])
    m[:3, 3] = translation
    return m


def cube(half):
    """The cube [−half, half]³, 12 triangles wound outward."""
    corners = np.array([[x, y, z] for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)]) * half
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    faces = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return corners.astype(float), np.array(faces)


def two_squares_and_a_sphere():
    sphere = raycast.Quadric(UNIT_SPHERE, matrix=placed(0.5, (10.0, 0.0, 0.0)))
    return raycast.Scene.from_objects(
        {"low": square(0.0, 0.0), "high": square(2.0, 1.0)}, {"ball": sphere}
    )


def down_rays(xy):
    origins = np.array([[x, y, 5.0] for x, y in xy])
    return origins, np.tile([0.0, 0.0, -1.0], (len(xy), 1))


def test_objects_get_ids_in_order_and_quadrics_are_placed_by_their_matrix():
    scene = two_squares_and_a_sphere()
    # Down from z = 5: the low square at z = 0, the high one at z = 1, the sphere of radius
    # 0.5 about (10, 0, 0) at its top z = 0.5, and nothing at x = 20.
    hits = scene.cast(*down_rays([(0.5, 0.5), (2.5, 0.5), (10.0, 0.0), (20.0, 0.0)]))
    np.testing.assert_array_equal(hits["id"], [1, 2, 3, 0])
    np.testing.assert_array_equal(hits["t"][:3], [5.0, 4.0, 4.5])
    assert np.isinf(hits["t"][3])
    assert hits["prim"][2] == 0
    assert [o["name"] for o in scene.info()["objects"]] == ["low", "high", "ball"]


def test_sequences_are_named_by_position():
    scene = raycast.Scene.from_objects([square(0.0, 0.0)], [raycast.Quadric(UNIT_SPHERE)])
    assert [o["name"] for o in scene.info()["objects"]] == ["mesh0", "quadric0"]


def test_a_scene_of_objects_pickles_as_its_arrays():
    scene = two_squares_and_a_sphere()
    again = pickle.loads(pickle.dumps(scene))
    rays = down_rays([(0.5, 0.5), (2.5, 0.5), (10.1, 0.1), (20.0, 0.0)])
    for key, value in scene.cast(*rays, aovs=("t", "id", "prim", "normal")).items():
        np.testing.assert_array_equal(again.cast(*rays, aovs=(key,))[key], value)


def test_contains_counts_a_closed_sphere_by_its_side():
    # A cube of half-size 2 holding the unit sphere: inside the cube and outside the sphere
    # is inside (one surface around the point), inside both is outside (two).
    scene = raycast.Scene.from_objects([cube(2.0)], [raycast.Quadric(UNIT_SPHERE)])
    points = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.3, -0.4, 0.5], [3.0, 0.0, 0.0]])
    np.testing.assert_array_equal(scene.contains(points), [False, True, False, False])
    rng = np.random.default_rng(7)
    points = rng.uniform(-2.5, 2.5, (20000, 3))
    r = np.linalg.norm(points, axis=1)
    in_cube = np.abs(points).max(axis=1) < 2.0
    clear = (np.abs(r - 1.0) > 1e-9) & (np.abs(np.abs(points).max(axis=1) - 2.0) > 1e-9)
    truth = in_cube & (r > 1.0)
    np.testing.assert_array_equal(scene.contains(points)[clear], truth[clear])
    signed = scene.signed_distance(np.array([[1.5, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    np.testing.assert_allclose(signed, [-0.5, 1.0], rtol=0, atol=4e-16)


@pytest.mark.parametrize(
    ("meshes", "quadrics", "message"),
    [
        ({"a": (np.zeros((3, 3)), [[0, 1, 3]])}, {}, "mesh 'a': face 0 is [0, 1, 3]"),
        ({"a": ([[0, 0, np.nan]] * 3, [[0, 1, 2]])}, {}, "mesh 'a': vertex 0 is not finite"),
        ({}, {"tube": raycast.Quadric([1, 1, 0, 0, 0, 0, 0, 0, 0, -1])}, "quadric 'tube': "),
        ({}, {"q": raycast.Quadric(UNIT_SPHERE[:9])}, "quadric 'q': coefficients must be 10"),
        ({}, {"q": raycast.Quadric(UNIT_SPHERE, matrix=np.zeros((4, 4)))}, "quadric 'q': "),
        ({}, {"q": raycast.Quadric(UNIT_SPHERE, bounds=([0, 0], [1, 1]))}, "quadric 'q': bounds"),
    ],
)
def test_a_wrong_object_is_named(meshes, quadrics, message):
    with pytest.raises(ValueError, match="^" + message.replace("[", r"\[").replace("]", r"\]")):
        raycast.Scene.from_objects(meshes, quadrics)
