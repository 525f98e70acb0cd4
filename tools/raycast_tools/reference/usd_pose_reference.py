"""usd-core's reading of the posed USD fixtures (issue 28): the reference of tests/it/usd_pose.rs.

For fixtures/usd/posed/time_samples.usda at several time codes (and the default one), and for
fixtures/usd/posed/variants.usda with several `--variant` selections, writes what usd-core
composes, in world space:

- every drawn Mesh's points transformed by `UsdGeom.XformCache(time)` (`Get(time)` on
  `points`; a mesh without points at that time is left out), with its face counts and indices;
- every Cube's `size` and Sphere's `radius` at the time, with the prim's world matrix;
- every PointInstancer's instances: `ComputeInstanceTransformsAtTime(time, time)` times the
  instancer's world matrix (rows, USD's row-vector convention), each with its prototype's
  points in world space;
- the stage's time range and rate, and every prim's variant sets (choices and selection).

Variant selections are made as a usd-core user makes them: `GetVariantSets().SetSelection` with
the session layer as edit target, repeated over the stage until nothing changes (a selection can
bring in nested variant sets).

Usage:
    .venv/bin/python -m raycast_tools usd-pose-reference [FIXTURE_DIR]
(tools/make_usd_pose_fixtures.sh runs it; default FIXTURE_DIR fixtures/usd/posed.)
"""

import argparse
import json
from pathlib import Path

from pxr import Gf, Usd, UsdGeom

from raycast_tools.cli import prog

# Time codes read from time_samples.usda: before the first sample, between samples, on a
# sample, after the last one; None is Usd.TimeCode.Default().
TIMES = [None, -5.0, 7.25, 30.5, 48.0, 60.0]

# --variant selections applied to variants.usda (set -> variant).
SELECTIONS = [
    {},
    {"shape": "ball"},
    {"shape": "tri"},
    {"shape": "tri", "detail": "high"},
    {"placement": "far", "shape": "tri", "detail": "high"},
]


def rows(matrix):
    """A Gf.Matrix4d as 16 numbers, row-major (as USD writes it)."""
    return [matrix[r][c] for r in range(4) for c in range(4)]


def world_points(points, matrix):
    """Points (any precision) transformed by a row-vector world matrix, in double."""
    out = []
    for p in points:
        q = matrix.Transform(Gf.Vec3d(p[0], p[1], p[2]))
        out += [q[0], q[1], q[2]]
    return out


def select(stage, choices):
    """Applies `choices` on the session layer until no selection changes."""
    changed = True
    with Usd.EditContext(stage, stage.GetSessionLayer()):
        while changed:
            changed = False
            for prim in stage.Traverse():
                sets = prim.GetVariantSets()
                for name in sets.GetNames():
                    wanted = choices.get(name)
                    if wanted and sets.GetVariantSet(name).GetVariantSelection() != wanted:
                        sets.SetSelection(name, wanted)
                        changed = True


def variant_sets(stage):
    """Every prim's variant sets: prim, set, choices, selection."""
    out = []
    for prim in stage.Traverse():
        sets = prim.GetVariantSets()
        for name in sets.GetNames():
            v = sets.GetVariantSet(name)
            out.append(
                {
                    "prim": str(prim.GetPath()),
                    "set": name,
                    "choices": list(v.GetVariantNames()),
                    "selection": v.GetVariantSelection() or None,
                }
            )
    return out


def read(stage, time):
    """What the stage draws at `time` (a number or None for the default time code)."""
    code = Usd.TimeCode.Default() if time is None else Usd.TimeCode(time)
    cache = UsdGeom.XformCache(code)
    meshes, gprims, instances = [], [], []
    for prim in stage.Traverse():
        world = cache.GetLocalToWorldTransform(prim)
        kind = prim.GetTypeName()
        if kind == "Mesh":
            mesh = UsdGeom.Mesh(prim)
            points = mesh.GetPointsAttr().Get(code)
            counts = mesh.GetFaceVertexCountsAttr().Get(code)
            indices = mesh.GetFaceVertexIndicesAttr().Get(code)
            if not points or not counts or not indices:
                continue
            if UsdGeom.PointInstancer(prim.GetParent().GetParent()):
                continue  # a prototype under its instancer: drawn only through it
            meshes.append(
                {
                    "path": str(prim.GetPath()),
                    "points": world_points(points, world),
                    "faceVertexCounts": list(counts),
                    "faceVertexIndices": list(indices),
                }
            )
        elif kind in ("Cube", "Sphere"):
            name = "size" if kind == "Cube" else "radius"
            gprims.append(
                {
                    "path": str(prim.GetPath()),
                    "type": kind,
                    name: prim.GetAttribute(name).Get(code),
                    "world": rows(world),
                }
            )
        elif kind == "PointInstancer":
            instancer = UsdGeom.PointInstancer(prim)
            xforms = instancer.ComputeInstanceTransformsAtTime(code, code)
            targets = instancer.GetPrototypesRel().GetTargets()
            indices = instancer.GetProtoIndicesAttr().Get(code) or []
            for i, xform in enumerate(xforms or []):
                proto = stage.GetPrimAtPath(targets[indices[i]])
                points = UsdGeom.Mesh(proto).GetPointsAttr().Get(code)
                instances.append(
                    {
                        "name": f"{prim.GetPath()}[{i}]",
                        "world": rows(xform * world),
                        "points": world_points(points, xform * world),
                    }
                )
    return {"meshes": meshes, "gprims": gprims, "instances": instances}


def stage_record(stage):
    """The stage's time metadata."""
    return {
        "timeCodesPerSecond": stage.GetTimeCodesPerSecond(),
        "timeCodeRange": [stage.GetStartTimeCode(), stage.GetEndTimeCode()]
        if stage.HasAuthoredTimeCodeRange()
        else None,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(prog=prog("usd-pose-reference"), description=__doc__)
    parser.add_argument("folder", nargs="?", default="fixtures/usd/posed")
    folder = Path(parser.parse_args(argv).folder)

    stage = Usd.Stage.Open(str(folder / "time_samples.usda"))
    timed = {
        "usdCore": Usd.GetVersion(),
        "stage": stage_record(stage),
        "cases": [{"time": t, **read(stage, t)} for t in TIMES],
    }
    variants = {"usdCore": Usd.GetVersion(), "cases": []}
    for choices in SELECTIONS:
        stage = Usd.Stage.Open(str(folder / "variants.usda"))
        before = variant_sets(stage)
        select(stage, choices)
        case = {"variants": choices, "authored": before, "sets": variant_sets(stage)}
        variants["cases"].append({**case, **read(stage, None)})
    for name, record in [("time_samples", timed), ("variants", variants)]:
        path = folder / f"{name}.reference.json"
        path.write_text(json.dumps(record, indent=1) + "\n")
        print(f"wrote {path}")
    return 0
