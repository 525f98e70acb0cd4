"""raycast.trimesh.RayMeshIntersector against the expectations of trimesh's own ray tests
(tests/test_ray.py of trimesh: the cases are restated here for raycast, not copied), and
against trimesh's pure-numpy intersector on the same rays.

Run: .venv/bin/python -m pytest tests/python/test_py_trimesh.py
"""

import numpy as np
import pytest
import trimesh

import raycast.trimesh


def drop_in(mesh):
    mesh.ray = raycast.trimesh.RayMeshIntersector(mesh)
    return mesh


def test_contains_scaled_cube_vertices():
    # trimesh test_contains: vertices shrunk toward the centre are inside, grown are outside,
    # far points are outside, the centre of mass is inside.
    mesh = drop_in(trimesh.creation.box())
    assert mesh.ray.contains_points(mesh.vertices / 1.5).all()
    assert not mesh.ray.contains_points(mesh.vertices * 1.5).any()
    far = np.random.default_rng(1).random((30, 3)) * 100 + 1.0 + mesh.bounds[1]
    assert not mesh.ray.contains_points(far).any()
    assert mesh.ray.contains_points([mesh.center_mass]).all()


def test_rays_through_vertices_cross_once():
    # trimesh test_on_vertex: rays from the centre of a box toward each corner hit, and
    # (multiple hits) each ray crosses the surface exactly once.
    mesh = drop_in(trimesh.creation.box())
    origins = np.zeros_like(mesh.vertices)
    assert mesh.ray.intersects_any(origins, mesh.vertices).all()
    _, index_ray, _ = mesh.ray.intersects_location(origins, mesh.vertices)
    assert (np.bincount(index_ray, minlength=len(origins)) == 1).all()


def test_points_near_edges():
    # After trimesh test_on_edge, on a box [-1, 1]^3: a point just inside a face, points on
    # the diagonal edges the faces are split along, a point outside.
    mesh = drop_in(trimesh.creation.box(extents=[2, 2, 2]))
    points = [[0.0, -1 + 1e-6, 0.0], [0.5, 0.5, 0.0], [0.0, 0.0, 0.999], [4.5, 0.0, -23.0]]
    assert mesh.ray.contains_points(points).tolist() == [True, True, True, False]


def test_first_and_multiple_hits_on_a_box():
    # trimesh test_multiple_hits: a camera behind a 2x2x2 box; first hits land on the two
    # triangles of the near face, multiple hits also on the far face.
    grid = np.mgrid[-64:64:2.0, -64:64:2.0].reshape(2, -1).T
    directions = np.column_stack([grid, np.full(len(grid), 1000.0)])
    origins = np.tile([0.0, 0.0, -15.0], (len(directions), 1))
    mesh = drop_in(trimesh.creation.box(extents=[2, 2, 2]))
    first, _ = mesh.ray.intersects_id(origins, directions, multiple_hits=False)
    assert len(np.unique(first)) == 2
    every, _ = mesh.ray.intersects_id(origins, directions, multiple_hits=True)
    assert len(np.unique(every)) > 2


def test_box_hits_along_z():
    # trimesh test_box: rays along +Z over the box's XY profile hit at their own XY, on the
    # top or bottom face.
    mesh = drop_in(trimesh.creation.box())
    xy = np.stack(
        np.meshgrid(np.linspace(-0.52, 0.52, 60), np.linspace(-0.52, 0.52, 60)), -1
    ).reshape(-1, 2)
    origins = np.column_stack([xy, np.full(len(xy), -100.0)])
    vectors = np.tile([0.0, 0.0, 1.0], (len(origins), 1))
    pos, ray, _ = mesh.ray.intersects_location(origins, vectors)
    assert len(pos) > 0
    assert np.allclose(pos[:, :2], origins[ray][:, :2])
    assert np.isclose(pos[:, 2:3], mesh.bounds[:, 2]).any(axis=1).all()
    # Inside the profile exactly two crossings per ray, outside none.
    inside = (np.abs(xy) < 0.5).all(axis=1)
    counts = np.bincount(ray, minlength=len(origins))
    assert (counts[inside] == 2).all() and (counts[(np.abs(xy) > 0.5).any(axis=1)] == 0).all()


def test_large_box_exit_hit_only():
    # trimesh test_embree_duplicate_hits: a ray from the centre of the top face of a box of
    # side 10000 straight down crosses only the bottom face (hits need t > 0).
    mesh = trimesh.creation.box()
    mesh.apply_scale(10000.0)
    drop_in(mesh)
    index_tri, _ = mesh.ray.intersects_id(
        [[0.0, 0.0, 5000.0]], [[0.0, 0.0, -1.0]], multiple_hits=True
    )
    assert len(index_tri) == 1


def test_misses_return_empty_arrays():
    # trimesh test_empty: rays that never reach the sphere give empty arrays.
    mesh = drop_in(trimesh.creation.icosphere())
    origins = np.random.default_rng(2).random((100, 3))
    origins[:, 2] = -5
    directions = np.tile([0.0, 1.0, 0.0], (100, 1))
    for result in (
        mesh.ray.intersects_id(origins, directions),
        mesh.ray.intersects_location(origins, directions),
    ):
        assert all(isinstance(a, np.ndarray) and len(a) == 0 for a in result)
    assert mesh.ray.intersects_first(origins, directions).tolist() == [-1] * 100


def test_agrees_with_trimesh_on_a_sphere():
    # The same random rays through trimesh's own intersector (ray_triangle, pure numpy):
    # same first faces and hit points away from edges.
    sphere = trimesh.creation.icosphere(subdivisions=3)
    rng = np.random.default_rng(3)
    origins = rng.normal(size=(500, 3)) * 3
    directions = rng.normal(size=(500, 3)) * 0.1 - origins * 0.3
    reference = trimesh.ray.ray_triangle.RayMeshIntersector(sphere)
    ours = raycast.trimesh.RayMeshIntersector(sphere)
    ref_first = reference.intersects_first(origins, directions)
    our_first = ours.intersects_first(origins, directions)
    assert (ref_first == our_first).mean() > 0.99
    loc_ref, ray_ref, _ = reference.intersects_location(origins, directions, multiple_hits=False)
    loc, ray, _ = ours.intersects_location(origins, directions, multiple_hits=False)
    assert sorted(ray_ref) == sorted(ray)
    order_ref, order = np.argsort(ray_ref), np.argsort(ray)
    assert np.allclose(loc_ref[order_ref], loc[order], atol=1e-9)
    assert (ours.intersects_any(origins, directions) == (ref_first >= 0)).mean() > 0.99


def test_max_hits_limits_each_ray():
    mesh = drop_in(trimesh.creation.box())
    tri, ray = mesh.ray.intersects_id([[0.1, 0.2, -5]] * 2, [[0, 0, 1]] * 2, max_hits=1)
    assert ray.tolist() == [0, 1] and len(tri) == 2


@pytest.mark.parametrize("points_inside", [True, False])
def test_contains_matches_the_convex_reference(points_inside):
    # A convex polyhedron contains a point iff the point is behind every face plane.
    sphere = trimesh.creation.icosphere(subdivisions=2)
    rng = np.random.default_rng(4)
    points = rng.uniform(-1.1, 1.1, size=(2000, 3))
    offsets = np.einsum("fj,pj->pf", sphere.face_normals, points) - np.einsum(
        "fj,fj->f", sphere.face_normals, sphere.triangles[:, 0]
    )
    reference = (offsets < 0).all(axis=1)
    clear = np.abs(offsets).min(axis=1) > 1e-9
    assert clear.mean() > 0.99
    ours = raycast.trimesh.RayMeshIntersector(sphere).contains_points(points)
    keep = clear & (reference == points_inside)
    assert keep.sum() > 100
    assert (ours[keep] == reference[keep]).all()


def test_untraceable_rays_are_misses_as_in_trimesh():
    # Issue 33: embree (trimesh's default intersector) answers [-1, hit] for a zero and a
    # proper direction; a NaN origin is a miss too. The proper rays' answers are those of
    # trimesh's own numpy intersector, ray indices those of the rays given.
    mesh = trimesh.creation.box()
    reference = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
    mesh = drop_in(mesh)
    origins = [[0, 0, 5], [0, 0, 5], [np.nan, 0, 5], [0.1, 0.2, 5], [0, 0, 5]]
    directions = [[0, 0, 0], [0, 0, -1], [0, 0, -1], [0, 0, -1], [np.inf, 0, -1]]
    good = [1, 3]
    expected = reference.intersects_first(np.asarray(origins)[good], np.asarray(directions)[good])
    first = mesh.ray.intersects_first(origins, directions)
    assert first.tolist() == [-1, expected[0], -1, expected[1], -1]
    assert mesh.ray.intersects_any(origins, directions).tolist() == [0, 1, 0, 1, 0]
    locations, index_ray, index_tri = mesh.ray.intersects_location(origins, directions)
    assert sorted(set(index_ray.tolist())) == good
    tri, rays = mesh.ray.intersects_id(origins, directions, multiple_hits=False)
    assert rays.tolist() == good and tri.tolist() == expected.tolist()
    assert mesh.ray.intersects_first([], []).shape == (0,)


def test_unused_bad_vertices_and_scale_to_box_are_accepted():
    # Issue 33: trimesh's RayMeshIntersector takes scale_to_box (the tests pass it); a
    # non-finite vertex that no face uses does not stop a query (it raised SceneError).
    box = trimesh.creation.box()
    vertices = np.vstack([box.vertices, [[np.nan, 0.0, 0.0]]])
    mesh = trimesh.Trimesh(vertices, box.faces, process=False)
    mesh.ray = raycast.trimesh.RayMeshIntersector(mesh, scale_to_box=False)
    plain = drop_in(trimesh.creation.box())
    rng = np.random.default_rng(3)
    origins = rng.uniform(-2, 2, (200, 3)) + [0, 0, 5]
    directions = np.tile([0.0, 0.0, -1.0], (200, 1)) + rng.uniform(-0.2, 0.2, (200, 3))
    a = mesh.ray.intersects_first(origins, directions)
    assert (a == plain.ray.intersects_first(origins, directions)).all()
    assert (a >= 0).sum() > 20
