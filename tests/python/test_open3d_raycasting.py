# ----------------------------------------------------------------------------
# -                        Open3D: www.open3d.org                            -
# ----------------------------------------------------------------------------
# Copyright (c) 2018-2024 www.open3d.org
# SPDX-License-Identifier: MIT
# ----------------------------------------------------------------------------
"""Open3D's RaycastingScene tests (python/test/t/geometry/test_raycasting_scene.py of
isl-org/Open3D at 00572f0aeb36281179d962b2b4822dd1bc1e6974, MIT licence above), every test
ported to raycast, with their inputs and expected values unchanged; and the cases of the
Open3D issues about wrong signs and occupancy (#5105, #5669, #6919) as tests.

The port, call by call: ``RaycastingScene()`` + ``add_triangles(v, f)`` is
``raycast.Scene.from_arrays(v, f)``; raycast's object ids start at 1 (0 is a miss, Open3D's
``INVALID_ID``); ``cast_rays`` is ``cast`` (``t_hit`` is ``t``, ``geometry_ids`` ``id``);
``test_occlusions(rays, tnear, tfar)`` is ``occluded(rays, tmin=, tmax=)``; the list keys
``t_hit``, ``geometry_ids``, ``primitive_ids`` and ``primitive_uvs`` are ``t``, ``id``,
``prim`` and ``bary`` (all three weights, so 3 wide where Open3D gives 2);
``compute_closest_points``, ``compute_distance``, ``compute_signed_distance`` and
``compute_occupancy`` are ``closest_points`` (key ``point``), ``distance``,
``signed_distance`` and ``occupancy``. Open3D's ``create_box()`` (the unit cube at the
origin) and ``create_sphere(0.8)`` (a UV sphere of resolution 20) are built here, from their
documented shapes. The ``device`` parameter is dropped: raycast runs on the CPU.
Run: .venv/bin/python -m pytest tests/python/test_open3d_raycasting.py
"""

import numpy as np
import pytest
import trimesh

import raycast

INVALID_ID = 0


def triangle_scene():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], dtype=np.float32)
    triangles = np.array([[0, 1, 2]], dtype=np.uint32)
    return raycast.Scene.from_arrays(vertices, triangles), 1


def create_box():
    """Open3D's create_box(): the cube [0, 1]^3, 12 triangles wound outward."""
    box = trimesh.creation.box(extents=(1, 1, 1))
    box.apply_translation((0.5, 0.5, 0.5))
    return box.vertices, box.faces


def create_sphere(radius, resolution=20):
    """Open3D's create_sphere(radius, resolution): the two poles on z and ``resolution - 1``
    rings of ``2 resolution`` vertices at equal steps of latitude and longitude, the caps as
    fans and the bands as quads cut in two, wound outward."""
    vertices = [(0.0, 0.0, radius), (0.0, 0.0, -radius)]
    ring = 2 * resolution
    for i in range(1, resolution):
        alpha = np.pi * i / resolution
        for j in range(ring):
            theta = 2 * np.pi * j / ring
            vertices.append(
                (
                    radius * np.sin(alpha) * np.cos(theta),
                    radius * np.sin(alpha) * np.sin(theta),
                    radius * np.cos(alpha),
                )
            )

    def at(i, j):
        return 2 + (i - 1) * ring + j % ring

    faces = []
    for j in range(ring):
        faces.append((0, at(1, j), at(1, j + 1)))
        faces.append((1, at(resolution - 1, j + 1), at(resolution - 1, j)))
    for i in range(1, resolution - 1):
        for j in range(ring):
            faces.append((at(i, j), at(i + 1, j), at(i + 1, j + 1)))
            faces.append((at(i, j), at(i + 1, j + 1), at(i, j + 1)))
    return np.array(vertices), np.array(faces)


def test_the_built_shapes_are_closed_and_outward():
    for vertices, faces in (create_box(), create_sphere(0.8)):
        mesh = trimesh.Trimesh(vertices, faces, process=False)
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0


# test intersection with a single triangle
def test_cast_rays():
    scene, geom_id = triangle_scene()
    rays = np.array([[0.2, 0.1, 1, 0, 0, -1], [10, 10, 10, 1, 0, 0]], dtype=np.float32)
    ans = scene.cast(rays, aovs=("t", "id"))
    # first ray hits the triangle
    assert geom_id == ans["id"][0]
    assert np.isclose(ans["t"][0], 1.0)
    # second ray misses
    assert INVALID_ID == ans["id"][1]
    assert np.isinf(ans["t"][1])


# cast lots of random rays to test the internal batching
# we expect no errors for this test
def test_cast_lots_of_rays():
    scene, _ = triangle_scene()
    rs = np.random.RandomState(123)
    rays = rs.rand(7654321, 6).astype(np.float32)
    _ = scene.cast(rays, aovs=("t",))


# test occlusion with a single triangle
def test_test_occlusions():
    scene, _ = triangle_scene()
    rays = np.array([[0.2, 0.1, 1, 0, 0, -1], [10, 10, 10, 1, 0, 0]], dtype=np.float32)
    ans = scene.occluded(rays)
    # first ray is occluded by the triangle
    assert ans[0]
    # second ray is not occluded
    assert not ans[1]
    # set tfar such that no ray is occluded
    ans = scene.occluded(rays, tmax=0.5)
    assert not ans.any()
    # set tnear such that no ray is occluded
    ans = scene.occluded(rays, tmin=1.5)
    assert not ans.any()


# test lots of random rays for occlusions to test the internal batching
# we expect no errors for this test
def test_test_lots_of_occlusions():
    scene, _ = triangle_scene()
    rs = np.random.RandomState(123)
    rays = rs.rand(7654321, 6).astype(np.float32)
    _ = scene.occluded(rays)


CUBE_RAYS = np.array(
    [[0.5, 0.5, -1, 0, 0, 1], [0.5, 0.5, 0.5, 0, 0, 1], [10, 10, 10, 1, 0, 0]], dtype=np.float32
)


def test_add_triangle_mesh():
    scene = raycast.Scene.from_arrays(*create_box())
    ans = scene.count_intersections(CUBE_RAYS)
    np.testing.assert_equal(ans, [2, 1, 0])


def test_count_intersections():
    vertices, faces = create_box()
    scene = raycast.Scene.from_arrays(vertices.astype(np.float32), faces.astype(np.uint32))
    ans = scene.count_intersections(CUBE_RAYS)
    np.testing.assert_equal(ans, [2, 1, 0])


# count lots of random ray intersections to test the internal batching
# we expect no errors for this test
def test_count_lots_of_intersections():
    scene = raycast.Scene.from_arrays(*create_box())
    rs = np.random.RandomState(123)
    rays = rs.rand(1234567, 6).astype(np.float32)
    _ = scene.count_intersections(rays)


def test_list_intersections():
    scene = raycast.Scene.from_arrays(*create_box())
    ans = scene.list_intersections(CUBE_RAYS)
    np.testing.assert_allclose(ans["t"], np.array([1.0, 2.0, 0.5]), rtol=1e-6, atol=1e-6)


# list lots of random ray intersections to test the internal batching
# we expect no errors for this test
def test_list_lots_of_intersections():
    scene = raycast.Scene.from_arrays(*create_box())
    rs = np.random.RandomState(123)
    rays = rs.rand(123456, 6).astype(np.float32)
    _ = scene.list_intersections(rays)


def test_compute_closest_points():
    scene, geom_id = triangle_scene()
    query_points = np.array([[0.2, 0.1, 1], [10, 10, 10]], dtype=np.float32)
    ans = scene.closest_points(query_points)
    assert (geom_id == ans["id"]).all()
    assert (0 == ans["prim"]).all()
    np.testing.assert_allclose(
        ans["point"], np.array([[0.2, 0.1, 0.0], [1, 1, 0]]), rtol=1e-6, atol=1e-6
    )


# compute lots of closest points to test the internal batching
# we expect no errors for this test
def test_compute_lots_of_closest_points():
    scene, _ = triangle_scene()
    rs = np.random.RandomState(123)
    query_points = rs.rand(1234567, 3).astype(np.float32)
    _ = scene.closest_points(query_points)


def test_compute_distance():
    scene = raycast.Scene.from_arrays(*create_box())
    query_points = np.array([[0.5, 0.5, 0.5], [-0.5, -0.5, -0.5], [0, 0, 0]], dtype=np.float32)
    ans = scene.distance(query_points)
    np.testing.assert_allclose(ans, [0.5, np.sqrt(3 * 0.5**2), 0.0])


def test_compute_signed_distance():
    scene = raycast.Scene.from_arrays(*create_box())
    query_points = np.array([[0.5, 0.5, 0.5], [-0.5, -0.5, -0.5], [0, 0, 0]], dtype=np.float32)
    ans = scene.signed_distance(query_points)
    np.testing.assert_allclose(ans, [-0.5, np.sqrt(3 * 0.5**2), 0.0])


def test_compute_occupancy():
    scene = raycast.Scene.from_arrays(*create_box())
    query_points = np.array([[0.5, 0.5, 0.5], [-0.5, -0.5, -0.5]], dtype=np.float32)
    ans = scene.occupancy(query_points)
    np.testing.assert_allclose(ans, [1.0, 0.0])


@pytest.mark.parametrize("shape", ([11], [1, 2, 3], [32, 14]))
def test_output_shapes(shape):
    scene, _ = triangle_scene()
    rs = np.random.RandomState(123)
    rays = rs.uniform(size=shape + [6]).astype(np.float32)
    query_points = rs.uniform(size=shape + [3]).astype(np.float32)

    ans = scene.count_intersections(rays)
    assert list(ans.shape) == shape
    ans = scene.distance(query_points)
    assert list(ans.shape) == shape
    ans = scene.signed_distance(query_points)
    assert list(ans.shape) == shape
    ans = scene.occupancy(query_points)
    assert list(ans.shape) == shape

    # some outputs append a specific last dim
    last_dim = {
        "t": [],
        "distance": [],
        "id": [],
        "prim": [],
        "bary": [3],
        "normal": [3],
        "position": [3],
        "point": [3],
        "ray_ids": [],
        "ray_splits": [],
    }
    ans = scene.cast(rays, aovs=("t", "id", "prim", "bary", "normal", "position"))
    for k, v in ans.items():
        expected_shape = shape + last_dim[k]
        assert list(v.shape) == expected_shape, (k, v.shape)

    ans = scene.closest_points(query_points)
    for k, v in ans.items():
        expected_shape = shape + last_dim[k]
        assert list(v.shape) == expected_shape, (k, v.shape)

    ans = scene.list_intersections(rays)
    nx = np.sum(scene.count_intersections(rays)).tolist()
    for k, v in ans.items():
        if k == "ray_splits":
            alt_shape = [np.prod(rays.shape[:-1]) + 1]
        else:
            alt_shape = [nx]
        expected_shape = np.append(alt_shape, last_dim[k]).tolist()
        assert list(v.shape) == expected_shape, (k, v.shape)


def sphere_grid(num):
    vertices, faces = create_sphere(0.8)
    min_bound = vertices.min(0) * 1.1
    max_bound = vertices.max(0) * 1.1
    xyz_range = np.linspace(min_bound, max_bound, num=num)
    query_points = np.stack(np.meshgrid(*xyz_range.T), axis=-1).astype(np.float32)
    return raycast.Scene.from_arrays(vertices, faces), query_points, (vertices, faces)


def test_sphere_wrong_occupancy():
    # This test checks a specific scenario where the old implementation
    # without ray jitter produced wrong results for a sphere because some
    # rays miss hitting exactly a vertex or an edge.
    scene, query_points, _ = sphere_grid(6)
    occupancy = scene.occupancy(query_points)
    expected = np.array(
        [
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 1.0, 1.0, 1.0, 1.0, 0.0],
                [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            [
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
        ],
        dtype=np.float32,
    )
    np.testing.assert_equal(occupancy, expected)
    # we should get the same result with more samples
    occupancy_3samples = scene.occupancy(query_points, nsamples=3)
    np.testing.assert_equal(occupancy_3samples, expected)


# The Open3D issues, as tests.


def test_issue_5105_a_ray_through_the_cube_corner_does_not_flip_the_sign():
    # Open3D cast one ray along (1, 1, 1): from (-1, -1, 0) it touches the cube at the corner
    # (0, 0, 1) and Open3D returned -sqrt(2). Every ray through the corner crosses it an even
    # number of times here, so the sign cannot flip.
    scene = raycast.Scene.from_arrays(*create_box())
    points = np.array([[-1, -1, 0], [-1, -1, -1], [0.5, 0.5, 0.5]], dtype=np.float32)
    np.testing.assert_allclose(
        scene.signed_distance(points), [np.sqrt(2), np.sqrt(3), -0.5], rtol=1e-15
    )
    count = scene.count_intersections([[-1, -1, 0]], [[1, 1, 1]])
    assert count[0] % 2 == 0


def test_issue_5669_no_sign_artifacts_on_the_sphere_grid():
    # Open3D's 64^3 grid around create_sphere(0.8) showed wrong signs in slices. The sphere is
    # convex: a point is inside when it is below every face's plane. Points within 1e-9 of a
    # plane are left to the exact tests of test_py_distance.py.
    scene, query_points, (vertices, faces) = sphere_grid(64)
    points = query_points.reshape(-1, 3).astype(np.float64)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    heights = np.einsum("pk,fk->pf", points, normals) - np.einsum("fk,fk->f", a, normals)
    clear = np.abs(heights).min(axis=1) > 1e-9
    inside = (heights < 0).all(axis=1)
    signed = scene.signed_distance(points)
    assert clear.mean() > 0.99
    assert np.array_equal((signed < 0)[clear], inside[clear])
    assert (signed != 0)[clear].all()


def test_issue_6919_interior_points_are_occupied():
    # Open3D reported occupancy 0 and positive signed distances for every point of a closed
    # mesh (the user's mesh is not public). Interior points of the sphere, and of the cube
    # wound inward (every triangle reversed): the crossing parity does not depend on winding.
    scene, query_points, _ = sphere_grid(6)
    centre = np.array([[0.0, 0.0, 0.0], [0.1, -0.2, 0.3]])
    assert scene.occupancy(centre).tolist() == [1.0, 1.0]
    assert (scene.signed_distance(centre) < 0).all()
    vertices, faces = create_box()
    flipped = raycast.Scene.from_arrays(vertices, faces[::-1, ::-1])
    assert flipped.occupancy([[0.5, 0.5, 0.5]]).tolist() == [1.0]
    assert flipped.signed_distance([[0.5, 0.5, 0.5]]).tolist() == [-0.5]
