"""A drop-in for trimesh's ray interface, answered by raycast's exact ray caster.

>>> import trimesh, raycast.trimesh                                   # doctest: +SKIP
>>> mesh = trimesh.creation.icosphere()                               # doctest: +SKIP
>>> mesh.ray = raycast.trimesh.RayMeshIntersector(mesh)               # doctest: +SKIP

Triangle indices are indices into ``mesh.faces``; hits need ``t > 0`` along the ray. A ray
through an edge shared by two faces reports one of them, never both and never neither; with
``multiple_hits`` each surface crossing is listed once. The mesh is handed to raycast as its
float64 arrays (:meth:`raycast.Scene.from_arrays`); the scene is rebuilt when the mesh changes
(by its hash, as trimesh's own intersectors do).

As trimesh's Embree intersector does, a ray with a non-finite origin or direction, or a zero
direction, is a miss (raycast's own ``cast`` refuses it), and vertices that no face uses are
left out, so a NaN vertex nothing touches does not stop a query. ``scale_to_box`` is accepted
and ignored: trimesh scales the mesh for Embree's float32 arithmetic; raycast's float64 test
needs no scaling.
"""

from __future__ import annotations

import numpy as np

from . import Scene

__all__ = ["RayMeshIntersector"]


def _used(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` without those no face uses, and ``faces`` renumbered to them (the faces'
    order, which the triangle indices refer to, is kept)."""
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.reshape(-1)] = True
    if used.all():
        return vertices, faces
    return vertices[used], (np.cumsum(used) - 1)[faces]


class RayMeshIntersector:
    """trimesh's ``RayMeshIntersector`` interface over raycast.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        The mesh to intersect; its faces are triangles.
    scale_to_box : bool
        Accepted for trimesh's signature and ignored (see the module's notes).
    """

    def __init__(self, mesh, scale_to_box=True):
        self.mesh = mesh
        self._key = None
        self._scene = None

    @property
    def scene(self):
        """The raycast scene of the mesh as it is now (rebuilt when the mesh changed)."""
        key = self.mesh.__hash__()
        if self._scene is None or key != self._key:
            vertices = np.asarray(self.mesh.vertices, dtype=np.float64)
            faces = np.asarray(self.mesh.faces, dtype=np.int64)
            if len(faces) and 0 <= faces.min() and faces.max() < len(vertices):
                vertices, faces = _used(vertices, faces)
            self._scene = Scene.from_arrays(vertices, faces)
            self._key = key
        return self._scene

    def intersects_first(self, ray_origins, ray_directions, **kwargs) -> np.ndarray:
        """The index of the first face each ray hits, -1 for a miss: (N,) int64."""
        origins, directions, ok = _rays(ray_origins, ray_directions)
        first = np.full(len(ok), -1, dtype=np.int64)
        hits = self.scene.cast(origins[ok], directions[ok], aovs=("id", "prim"))
        first[ok] = np.where(hits["id"] == 0, -1, hits["prim"].astype(np.int64))
        return first

    def intersects_any(self, ray_origins, ray_directions, **kwargs) -> np.ndarray:
        """Whether each ray hits the mesh: (N,) bool."""
        origins, directions, ok = _rays(ray_origins, ray_directions)
        hit = np.zeros(len(ok), dtype=bool)
        hit[ok] = self.scene.occluded(origins[ok], directions[ok])
        return hit

    def intersects_id(
        self,
        ray_origins,
        ray_directions,
        multiple_hits=True,
        max_hits=None,
        return_locations=False,
        **kwargs,
    ):
        """Faces the rays hit.

        Parameters
        ----------
        ray_origins, ray_directions : (N, 3) float
        multiple_hits : bool
            Every crossing of each ray (nearest first), or only the first hit.
        max_hits : int, optional
            With ``multiple_hits``, keep at most this many hits per ray.
        return_locations : bool
            Also return the hit points.

        Returns
        -------
        index_tri : (M,) int64
            Face index of each hit.
        index_ray : (M,) int64
            Ray index of each hit.
        locations : (M, 3) float64
            Hit points, when ``return_locations``.
        """
        origins, directions, ok = _rays(ray_origins, ray_directions)
        # Results of the traceable rays, their indices mapped back to the rays given.
        traced = np.flatnonzero(ok)
        if multiple_hits:
            found = self.scene.list_intersections(origins[ok], directions[ok])
            index_ray = traced[found["ray_ids"].astype(np.int64)]
            index_tri = found["prim"].astype(np.int64)
            t = found["t"]
            if max_hits is not None:
                rank = np.arange(len(t)) - found["ray_splits"][:-1].astype(np.int64)[index_ray]
                keep = rank < max_hits
                index_ray, index_tri, t = index_ray[keep], index_tri[keep], t[keep]
        else:
            hits = self.scene.cast(origins[ok], directions[ok], aovs=("t", "id", "prim"))
            hit = np.nonzero(hits["id"])[0]
            index_ray = traced[hit].astype(np.int64)
            index_tri = hits["prim"][hit].astype(np.int64)
            t = hits["t"][hit]
        if not return_locations:
            return index_tri, index_ray
        return index_tri, index_ray, origins[index_ray] + directions[index_ray] * t[:, None]

    def intersects_location(self, ray_origins, ray_directions, multiple_hits=True, **kwargs):
        """Hit points of the rays.

        Returns
        -------
        locations : (M, 3) float64
        index_ray : (M,) int64
        index_tri : (M,) int64
        """
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins,
            ray_directions,
            multiple_hits=multiple_hits,
            return_locations=True,
            **kwargs,
        )
        return locations, index_ray, index_tri

    def contains_points(self, points) -> np.ndarray:
        """Whether each point lies inside the (closed) mesh: (N,) bool."""
        return self.scene.contains(points)


def _rays(ray_origins, ray_directions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origins and directions as (N, 3) float64, and which rays can be traced: a finite
    origin and a finite, non-zero direction (the others are misses, as in trimesh)."""
    origins = np.asarray(ray_origins, dtype=np.float64).reshape(-1, 3)
    directions = np.asarray(ray_directions, dtype=np.float64).reshape(-1, 3)
    if origins.shape != directions.shape:
        raise ValueError(
            f"ray_origins {origins.shape} and ray_directions {directions.shape} differ in shape"
        )
    finite = np.isfinite(origins).all(axis=1) & np.isfinite(directions).all(axis=1)
    return origins, directions, finite & (directions != 0).any(axis=1)
