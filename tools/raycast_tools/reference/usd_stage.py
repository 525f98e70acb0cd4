"""Reading USD stages with usd-core as raycast does: opening one quietly, finding the USD
files under a folder, and flattening a stage into world-space triangles."""

from __future__ import annotations

import os

import numpy as np
from pxr import Gf, Usd, UsdGeom

USD_EXTS = ("usd", "usda", "usdc", "usdz")
GPRIMS = {"Sphere", "Cube", "Cylinder", "Cylinder_1", "Cone", "Capsule", "Capsule_1", "Plane"}


def open_stage(path):
    """Usd.Stage.Open with usd-core's own messages on stderr silenced (its errors still raise)."""
    with open(os.devnull, "w") as devnull:
        saved = os.dup(2)
        os.dup2(devnull.fileno(), 2)
        try:
            return Usd.Stage.Open(str(path))
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def usd_files(arguments):
    """(path to open, name to report): files under a folder are named relative to it."""
    for argument in arguments:
        if os.path.isdir(argument):
            for folder, _, names in sorted(os.walk(argument)):
                for name in sorted(names):
                    if name.rsplit(".", 1)[-1].lower() in USD_EXTS:
                        path = os.path.join(folder, name)
                        yield path, os.path.relpath(path, argument)
        else:
            yield argument, argument


def mesh_triangles(prim):
    """How many fan triangles a mesh draws at the default time; None when it is not drawn."""
    try:
        return checked_mesh_triangles(prim)
    except TypeError:
        # A value of the wrong type (usd-wg pointsTypes.usda) is not drawn.
        return None


def checked_mesh_triangles(prim):
    """mesh_triangles, raising TypeError on a value of the wrong type."""
    mesh = UsdGeom.Mesh(prim)
    points = mesh.GetPointsAttr().Get()
    counts = mesh.GetFaceVertexCountsAttr().Get()
    indices = mesh.GetFaceVertexIndicesAttr().Get()
    if points is None or counts is None or indices is None:
        return None
    if len(points) == 0 or len(counts) == 0 or len(indices) == 0:
        return None
    if len(points[0]) != 3:
        return None
    if any(c < 0 for c in counts) or sum(counts) != len(indices):
        return None
    if any(i < 0 or i >= len(points) for i in indices):
        return None
    triangles = sum(c - 2 for c in counts if c >= 3)
    return triangles or None


def hidden_purpose(prim):
    """Whether the prim's computed purpose is guide or proxy (raycast does not draw those)."""
    imageable = UsdGeom.Imageable(prim)
    if not imageable:
        return False
    return imageable.ComputePurpose() in (UsdGeom.Tokens.guide, UsdGeom.Tokens.proxy)


def drawn_prims(root, excluded):
    """Prims of the subtree at `root`, instance proxies included, without invisible
    subtrees or the subtrees at the paths in `excluded`, a set the caller may add to
    while iterating (a point instancer's own prototypes)."""
    predicate = Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate)
    it = iter(Usd.PrimRange(root, predicate))
    for prim in it:
        if prim.GetPath() in excluded:
            it.PruneChildren()
            continue
        imageable = UsdGeom.Imageable(prim)
        if imageable and imageable.GetVisibilityAttr().Get() == UsdGeom.Tokens.invisible:
            it.PruneChildren()
            continue
        yield prim


def flatten(stage, gprim=None):
    """(object name, world triangles) drawn, by raycast's rules, with usd-core placing them.

    Meshes only by default. `gprim`, when given, is called as `gprim(prim, world matrix,
    object name)` for each drawn intrinsic gprim (GPRIMS), in place and in
    point-instancer prototypes, and returns a list of (object name, triangles) to add
    (validate_usd.py tessellates them). Meshes whose topology raycast rejects
    (mesh_triangles is None) give no triangles."""
    objects = []

    def mesh_tris(prim, matrix):
        if mesh_triangles(prim) is None:
            return []
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get()
        counts = mesh.GetFaceVertexCountsAttr().Get()
        indices = mesh.GetFaceVertexIndicesAttr().Get()
        if not points or not counts:
            return []
        left = mesh.GetOrientationAttr().Get() == UsdGeom.Tokens.leftHanded
        flip = matrix.GetDeterminant() < 0
        world = [np.array(matrix.Transform(Gf.Vec3d(p))) for p in points]
        tris, start = [], 0
        for c in counts:
            face = indices[start : start + c]
            start += c
            for k in range(1, c - 1):
                t = [world[face[0]], world[face[k]], world[face[k + 1]]]
                if left != flip:
                    t = [t[0], t[2], t[1]]
                tris.append(t)
        return tris

    excluded = set()
    for prim in drawn_prims(stage.GetPseudoRoot(), excluded):
        if hidden_purpose(prim):
            continue
        if prim.IsA(UsdGeom.Mesh):
            matrix = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
            objects.append((str(prim.GetPath()), mesh_tris(prim, matrix)))
        elif gprim is not None and prim.GetTypeName() in GPRIMS:
            matrix = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
            objects += gprim(prim, matrix, str(prim.GetPath()))
        elif prim.IsA(UsdGeom.PointInstancer):
            instancer = UsdGeom.PointInstancer(prim)
            targets = instancer.GetPrototypesRel().GetTargets()
            excluded.update(t for t in targets if t.HasPrefix(prim.GetPath()))
            transforms = instancer.ComputeInstanceTransformsAtTime(
                Usd.TimeCode.Default(),
                Usd.TimeCode.Default(),
                UsdGeom.PointInstancer.IncludeProtoXform,
                UsdGeom.PointInstancer.IgnoreMask,
            )
            mask = instancer.ComputeMaskAtTime(Usd.TimeCode.Default())
            indices = instancer.GetProtoIndicesAttr().Get()
            parent = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
            for i, (m, k) in enumerate(zip(transforms, indices)):
                if mask and not mask[i]:
                    continue
                proto = stage.GetPrimAtPath(targets[k])
                tris, extra = [], []
                for sub in drawn_prims(proto, set()):
                    is_gprim = gprim is not None and sub.GetTypeName() in GPRIMS
                    if (sub.IsA(UsdGeom.Mesh) or is_gprim) and not hidden_purpose(sub):
                        # the prototype root's own transform is in m (IncludeProtoXform);
                        # below it, the path from the root
                        below = Gf.Matrix4d(1)
                        p = sub
                        while p.GetPath() != proto.GetPath():
                            below = below * UsdGeom.Xformable(p).GetLocalTransformation()
                            p = p.GetParent()
                        world = below * m * parent if sub != proto else m * parent
                        if is_gprim:
                            relative = str(sub.GetPath())[len(str(proto.GetPath())) :]
                            extra += gprim(sub, world, f"{prim.GetPath()}[{i}]{relative}")
                        else:
                            tris += mesh_tris(sub, world)
                objects.append((f"{prim.GetPath()}[{i}]", tris))
                objects += extra
    return objects
