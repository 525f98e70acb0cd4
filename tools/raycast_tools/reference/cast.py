"""Ray casts on a world-space triangle soup (n, 3, 3) with trimesh: the float64
`ray_triangle` intersector (numpy + rtree, the precision reference) and Embree through
embreex (`ray_pyembree`: float32 traversal, the hit distance recomputed in float64)."""

from __future__ import annotations

import numpy as np


def tri_mesh(tris):
    """An (n, 3, 3) triangle soup as an unprocessed trimesh.Trimesh (face i = tris[i])."""
    import trimesh

    v = tris.reshape(-1, 3)
    f = np.arange(len(v)).reshape(-1, 3)
    return trimesh.Trimesh(vertices=v, faces=f, process=False, validate=False)


def tri_normals(tris):
    """Unit normals (b - a) × (c - a) of triangles (n, 3, 3); zero for degenerate ones."""
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    ln = np.linalg.norm(n, axis=1)
    return n / np.where(ln > 0, ln, 1.0)[:, None]


def ray_triangle_hits(tris, origins, unit, chunk):
    """All hits of trimesh's float64 ray_triangle, chunk rays at a time.

    Yields (s, it, ir, dist, first) for each chunk starting at ray s that hits
    anything: triangle, chunk-relative ray and distance of every hit, sorted by ray
    then distance, and `first`, the index of each ray's nearest hit in those arrays
    (the one multiple_hits=False would return).  `tris` must be non-empty.
    """
    from trimesh.ray.ray_triangle import RayMeshIntersector

    inter = RayMeshIntersector(tri_mesh(tris))
    for s in range(0, len(origins), chunk):
        o, d = origins[s : s + chunk], unit[s : s + chunk]
        it, ir, loc = inter.intersects_id(o, d, multiple_hits=True, return_locations=True)
        if len(it) == 0:
            continue
        dist = np.linalg.norm(loc - o[ir], axis=1)
        order = np.lexsort((dist, ir))
        it, ir, dist = it[order], ir[order], dist[order]
        first = np.flatnonzero(np.r_[True, ir[1:] != ir[:-1]])
        yield s, it, ir, dist, first


def _with_normals(tris, depth, tri):
    """(depth, unit normal of each hit triangle, zero on a miss, tri)."""
    normal = np.zeros((len(depth), 3))
    h = tri >= 0
    normal[h] = tri_normals(tris[tri[h]])
    return depth, normal, tri


def trace_ray_triangle(tris, origins, unit, chunk=64):
    """trimesh ray_triangle (float64): nearest hit depth (inf on a miss), unit normal of the
    hit triangle (zero on a miss) and triangle index (-1)."""
    n = len(origins)
    depth = np.full(n, np.inf)
    tri = np.full(n, -1, np.int64)
    if len(tris):
        for s, it, ir, dist, first in ray_triangle_hits(tris, origins, unit, chunk):
            depth[s + ir[first]] = dist[first]
            tri[s + ir[first]] = it[first]
    return _with_normals(tris, depth, tri)


def embree_intersector(tris):
    """trimesh's Embree intersector on the soup (the BVH is built on its first query)."""
    from trimesh.ray.ray_pyembree import RayMeshIntersector

    return RayMeshIntersector(tri_mesh(tris))


def embree_nearest(inter, origins, unit):
    """One Embree query: nearest hit depth (inf on a miss) and triangle index (-1)."""
    n = len(origins)
    depth = np.full(n, np.inf)
    tri = np.full(n, -1, np.int64)
    it, ir, loc = inter.intersects_id(origins, unit, multiple_hits=False, return_locations=True)
    if len(ir):
        depth[ir] = np.linalg.norm(loc - origins[ir], axis=1)
        tri[ir] = it
    return depth, tri


def trace_embree(tris, origins, unit):
    """trimesh + embreex (float32 traversal): nearest hit depth, unit normal, triangle."""
    if len(tris) == 0:
        n = len(origins)
        return _with_normals(tris, np.full(n, np.inf), np.full(n, -1, np.int64))
    depth, tri = embree_nearest(embree_intersector(tris), origins, unit)
    return _with_normals(tris, depth, tri)
