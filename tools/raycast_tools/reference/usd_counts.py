"""Counts what a USD stage draws, with usd-core (pxr), to check raycast's USD importer.

For each file: the number of mesh triangles (polygons fan-triangulated, every instance
counted: scene-graph instances through their instance proxies, point instances once per
visible instance), the number of drawn meshes and of intrinsic gprims, and the point
instancers' visible instance counts, and the world-space bounds of up to 200 meshes drawn once
(by prim path). The rules are raycast's (docs/usd.md): defined,
active, loaded prims; not invisible; purpose neither guide nor proxy; values at the default
time code; meshes with malformed topology are not drawn; point-instancer prototypes that
live under their instancer are drawn only through it.

Usage:
    .venv/bin/python -m raycast_tools usd-counts FILE_OR_DIR... [--json]
"""

import argparse
import json

from pxr import Gf, Usd, UsdGeom

from raycast_tools.cli import prog
from raycast_tools.reference.usd_stage import (
    GPRIMS,
    drawn_prims,
    hidden_purpose,
    mesh_triangles,
    open_stage,
    usd_files,
)

# raycast draws gprims as quadrics plus triangles (docs/usd.md): a cube is 12 triangles, each
# cap disc of a cylinder or cone a fan of CAP_SEGMENTS triangles.
CAP_SEGMENTS = 512


def gprim_cost(prim):
    """(triangles, quadrics) raycast draws for an intrinsic gprim (fallbacks applied)."""
    type_name = prim.GetTypeName()

    def get(name, fallback):
        attribute = prim.GetAttribute(name)
        return attribute.Get() if attribute.HasAuthoredValue() else fallback

    if type_name == "Sphere":
        return (0, 1) if get("radius", 1.0) > 0 else (0, 0)
    if type_name == "Cube":
        return (12, 0) if get("size", 2.0) > 0 else (0, 0)
    if type_name == "Plane":
        return (0, 1)
    if type_name in ("Cylinder", "Cone", "Cylinder_1"):
        if type_name == "Cylinder":
            bottom = top = get("radius", 1.0)
        elif type_name == "Cone":
            bottom, top = get("radius", 1.0), 0.0
        else:
            bottom, top = get("radiusBottom", 1.0), get("radiusTop", 1.0)
        if get("height", 2.0) == 0 or (bottom == 0 and top == 0):
            return (0, 0)
        return (CAP_SEGMENTS * ((bottom > 0) + (top > 0)), 1)
    if type_name in ("Capsule", "Capsule_1"):
        if type_name == "Capsule":
            radius = get("radius", 0.5)
        else:
            radius = get("radiusTop", 0.5)
            if radius != get("radiusBottom", 0.5):
                return (0, 0)
        if radius == 0:
            return (0, 0)
        return (0, 3 if get("height", 1.0) > 0 else 2)
    return (0, 0)


def world_bounds(prim):
    """World-space box of the points a mesh's faces use, [[min], [max]], in double."""
    mesh = UsdGeom.Mesh(prim)
    points = mesh.GetPointsAttr().Get()
    used = sorted(set(mesh.GetFaceVertexIndicesAttr().Get()))
    matrix = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    world = [matrix.Transform(Gf.Vec3d(points[i])) for i in used]
    return [
        [min(p[k] for p in world) for k in range(3)],
        [max(p[k] for p in world) for k in range(3)],
    ]


class Counter:
    def __init__(self):
        self.triangles = 0
        self.meshes = 0
        self.gprims = 0
        self.gprim_triangles = 0
        self.quadrics = 0
        self.instances = {}
        self.bounds = {}

    def walk(self, root, multiplier, depth=0):
        """Counts the subtree at `root` (`multiplier` copies of it)."""
        excluded = set()
        for prim in drawn_prims(root, excluded):
            path = prim.GetPath()
            type_name = prim.GetTypeName()
            if type_name in ("Mesh",) or type_name in GPRIMS:
                if hidden_purpose(prim):
                    continue
            if type_name == "Mesh":
                triangles = mesh_triangles(prim)
                if triangles:
                    self.triangles += triangles * multiplier
                    self.meshes += multiplier
                    if multiplier == 1 and len(self.bounds) < 200:
                        self.bounds[str(path)] = world_bounds(prim)
            elif type_name in GPRIMS:
                self.gprims += multiplier
                triangles, quadrics = gprim_cost(prim)
                self.gprim_triangles += triangles * multiplier
                self.quadrics += quadrics * multiplier
            elif type_name == "PointInstancer":
                if hidden_purpose(prim):
                    continue
                instancer = UsdGeom.PointInstancer(prim)
                targets = instancer.GetPrototypesRel().GetTargets()
                for target in targets:
                    if target.HasPrefix(path) and target != path:
                        excluded.add(target)
                indices = instancer.GetProtoIndicesAttr().Get()
                positions = instancer.GetPositionsAttr().Get()
                if indices is None or positions is None or len(indices) != len(positions):
                    continue
                ids = instancer.GetIdsAttr().Get()
                invisible = set(instancer.GetInvisibleIdsAttr().Get() or [])
                per_proto = {}
                for i, k in enumerate(indices):
                    ident = ids[i] if ids is not None and len(ids) == len(indices) else i
                    if ident in invisible or not 0 <= k < len(targets):
                        continue
                    per_proto[k] = per_proto.get(k, 0) + 1
                self.instances[str(path)] = sum(per_proto.values()) * multiplier
                for k, count in sorted(per_proto.items()):
                    proto = prim.GetStage().GetPrimAtPath(targets[k])
                    if proto and depth < 16:
                        self.walk(proto, multiplier * count, depth + 1)


def count(path):
    stage = open_stage(path)

    counter = Counter()
    counter.walk(stage.GetPseudoRoot(), 1)
    return {
        "file": path,
        "triangles": counter.triangles,
        "meshes": counter.meshes,
        "gprims": counter.gprims,
        "raycast_triangles": counter.triangles + counter.gprim_triangles,
        "raycast_quadrics": counter.quadrics,
        "point_instances": counter.instances,
        "mesh_bounds": counter.bounds,
        "upAxis": str(UsdGeom.GetStageUpAxis(stage)),
        "metersPerUnit": UsdGeom.GetStageMetersPerUnit(stage),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("usd-counts"), description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="+", help="USD files or folders (searched recursively)")
    ap.add_argument("--json", action="store_true", help="machine-readable output")
    a = ap.parse_args(argv)
    results = []
    for path, name in usd_files(a.paths):
        try:
            result = count(path)
        except Exception as error:  # noqa: BLE001 - report and go on
            result = {"error": str(error).strip().splitlines()[-1].strip()}
        results.append({**result, "file": name})
    if a.json:
        print(json.dumps(results, indent=1))
    else:
        for r in results:
            if "error" in r:
                print(f"{r['file']}: error: {r['error']}")
            else:
                print(
                    f"{r['file']}: {r['triangles']} triangles, {r['meshes']} meshes, "
                    f"{r['gprims']} gprims"
                )
    return 0
