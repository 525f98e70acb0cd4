"""That trimesh's tests beside this file run with raycast's drop-in (conftest.py)."""

import trimesh

import raycast.trimesh


def test_the_drop_in_is_in_place():
    mesh = trimesh.creation.box()
    assert isinstance(mesh.ray, raycast.trimesh.RayMeshIntersector)
    assert isinstance(
        trimesh.ray.ray_pyembree.RayMeshIntersector(mesh), raycast.trimesh.RayMeshIntersector
    )
