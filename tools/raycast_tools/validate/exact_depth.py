"""Depth against a float64 evaluation of a scene file's own numbers, ray by ray.

    python -m raycast_tools exact-depth [SCENE.usd|.gltf|.glb|.obj...] [--rays N] [--seed S]
                                        [--json] [--raycast PATH] [--limit REL]

The reference shares no code with raycast. It places every drawn mesh in float64 with a reader
of its own: USD through usd-core (usd_stage.flatten: ComputeLocalToWorldTransform,
PointInstancer instances from ComputeInstanceTransformsAtTime), each stored point transformed
by its float64 matrix; OBJ through trimesh (float64 text parsing, checked against Python's
float() of every `v` line); glTF through exact_readers.GltfFile, a numpy reader of the JSON and
buffers that composes node matrices and T·R·S in float64 as the glTF specification says (and
refuses what it does not read: sparse accessors, compression, morph targets, ...). A float64
Möller–Trumbore test written here in numpy then finds each ray's nearest triangle (objects
whose world box the ray misses are skipped). The same rays (rays.py's make_rays) go through
`raycast SCENE --rays R.npy`.

Per scene: hits on both sides, hit/miss disagreements (split into rays whose reference hit
point or raycast hit point lies within EDGE_REL * scene size of a triangle edge, where a
float64 evaluation may go either way, and the others), object disagreements (objects matched
by USD prim path or glTF node pointer; an OBJ is one object to trimesh, so none there), and
the relative depth error |d_raycast - d_ref| / d_ref: max, p99, p99.9 (rays where one side
stopped at an edge that the other went through to a farther triangle are counted apart, as
the edge hit/miss ones); and the drawn mesh objects found on one side only. Rays whose raycast
hit is a quadric object, or a USD object with a gprim, are left out (the reference has meshes
only). Default scene: the OpenChessSet (../shared/assets). Exit status 0 when every scene's
p99.9 is within --limit (default 1e-12), no ray away from an edge disagrees and both sides
draw the same objects, 1 otherwise (or when the reference refuses a file or finds no
triangles in it), 2 usage error.

Two float64 evaluations differ by about 1e-16 * |coordinates| / (depth * cos(incidence)): a
small object far from the origin seen at grazing incidence cannot agree to 1e-12, whoever
evaluates it (reports/instancing.md, "Exactness").
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
from pathlib import Path

import numpy as np

from raycast_tools.cli import prog
from raycast_tools.paths import ROOT, raycast_or_exit
from raycast_tools.rays import make_rays
from raycast_tools.reference.exact_readers import RefuseError, read_gltf, read_obj
from raycast_tools.runner import run_rays
from raycast_tools.validate.metrics import edge_distance

CHESS = ROOT.parent / "shared/assets/usd/full_assets/OpenChessSet/chess_set.usda"
EDGE_REL = 1e-9  # hit points this close to an edge (relative to the scene size) are edge rays
LIMIT = 1e-12  # relative depth error allowed at p99.9


class Objects:
    """The reference's drawn objects: world triangles (float64), their edges and boxes."""

    def __init__(self, objects):
        kept = [(name, np.asarray(t, np.float64).reshape(-1, 3, 3)) for name, t in objects]
        kept = [(name, t) for name, t in kept if len(t)]
        self.names = [name for name, _ in kept]
        self.tris = [t for _, t in kept]
        self.e1 = [t[:, 1] - t[:, 0] for t in self.tris]
        self.e2 = [t[:, 2] - t[:, 0] for t in self.tris]
        self.lo = np.array([t.reshape(-1, 3).min(axis=0) for t in self.tris])
        self.hi = np.array([t.reshape(-1, 3).max(axis=0) for t in self.tris])

    def candidates(self, o, d):
        """Objects whose box the ray o + t d (t >= 0) enters, by a float64 slab test."""
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
            t0, t1 = (self.lo - o) * inv, (self.hi - o) * inv
        near = np.nan_to_num(np.minimum(t0, t1), nan=-np.inf).max(axis=1)
        far = np.nan_to_num(np.maximum(t0, t1), nan=np.inf).min(axis=1)
        # widened a little: the box test only prunes, the triangle test decides
        slack = 1e-9 * (np.abs(near) + np.abs(far) + 1.0)
        return np.flatnonzero((far + slack >= np.maximum(near, 0.0) - slack))

    def nearest(self, o, d):
        """(t, object, triangle) of the nearest hit with t > 0, or (inf, -1, -1)."""
        best = (np.inf, -1, -1)
        for k in self.candidates(o, d):
            t, i = moller_trumbore(self.tris[k][:, 0], self.e1[k], self.e2[k], o, d)
            if i >= 0 and t < best[0]:
                best = (t, k, i)
        return best


def moller_trumbore(a, e1, e2, o, d):
    """Nearest hit (t, index) of the ray o + t d with triangles a + u e1 + v e2 (float64,
    u, v >= 0, u + v <= 1, t > 0; edges count as inside); (inf, -1) when none."""
    p = np.cross(d, e2)
    det = np.einsum("ij,ij->i", e1, p)
    s = o - a
    q = np.cross(s, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        u = np.einsum("ij,ij->i", s, p) * inv
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        ok = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
    if not ok.any():
        return np.inf, -1
    i = np.flatnonzero(ok)[np.argmin(t[ok])]
    return float(t[i]), int(i)


class RaySource:
    """What rays.make_rays needs of a scene: its triangles and bounds, no quadrics."""

    def __init__(self, objects: Objects):
        self.tris = np.concatenate(objects.tris)
        self.quadrics = []

    def bounds(self):
        flat = self.tris.reshape(-1, 3)
        return flat.min(axis=0), flat.max(axis=0)


def reference_objects(path):
    """(objects, sidecar key, unmodelled): the scene's drawn objects read by a reader that
    shares no code with raycast; the field of raycast's object table that their names match
    (`name` for USD prim paths and OBJ, `source` for glTF node pointers); and the names of
    objects that draw something this mesh-only reference leaves out (USD gprims, which raycast
    draws as quadrics or, for a Cube, triangles). An OBJ's single object has no name (None):
    object disagreements are then not counted."""
    suffix = Path(path).suffix.lower()
    if suffix in (".obj",):
        return read_obj(path), "name", set()
    if suffix in (".gltf", ".glb"):
        return read_gltf(path), "source", set()
    from raycast_tools.reference.usd_stage import flatten, open_stage

    unmodelled = set()

    def gprim(_prim, _matrix, name):
        # in place the object is the prim; in a point instancer's prototype, `path[i]...`
        unmodelled.add(re.match(r"[^\[]*(\[\d+\])?", name).group(0))
        return []

    from pxr import Tf

    try:
        stage = open_stage(path)
    except Tf.ErrorException as e:
        raise RefuseError(f"usd-core cannot open it: {str(e).strip().splitlines()[-1]}") from e
    return flatten(stage, gprim), "name", unmodelled


def check_scene(path, raycast, nrays, seed, limit):
    read, key, unmodelled = reference_objects(path)
    objects = Objects(read)
    if not objects.names:
        raise RefuseError("it draws no mesh triangles: nothing to compare")
    source = RaySource(objects)
    origins, unit, dirs = make_rays(source, nrays, seed)
    lo, hi = source.bounds()
    size = float(np.linalg.norm(hi - lo))
    ref = [objects.nearest(o, d) for o, d in zip(origins, unit)]
    depth = np.array([r[0] for r in ref])
    obj = np.array([r[1] for r in ref])
    tri = np.array([r[2] for r in ref])
    with tempfile.TemporaryDirectory() as tmp:
        rc = run_rays(raycast, path, origins, dirs, tmp, aov="depth,id")
    rdepth = np.asarray(rc["depth"], np.float64).reshape(-1)
    rid = np.asarray(rc["id"]).reshape(-1).astype(np.int64)
    names = {int(o["id"]): o[key] for o in rc["sidecar"]["objects"]}
    rname = np.array([names.get(int(k), "") for k in rid], dtype=object)
    # quadric objects (raycast:quadric prims, RAYCAST_quadric nodes) and objects with gprims
    # are not (all) in this mesh-only reference: rays whose raycast hit is one are left out
    left_out = {
        int(o["id"])
        for o in rc["sidecar"]["objects"]
        if o["kind"] == "quadric" or o[key] in unmodelled
    }
    keep = np.array([int(k) not in left_out for k in rid])

    def near_edge(i, t):
        """Whether the point at distance t along ray i lies within EDGE_REL * size of an
        edge of any triangle of the candidate objects."""
        p = origins[i] + unit[i] * t
        for k in objects.candidates(origins[i], unit[i]):
            tris = objects.tris[k]
            if edge_distance(tris, np.repeat(p[None], len(tris), 0)).min() <= EDGE_REL * size:
                return True
        return False

    rhit, fhit = np.isfinite(rdepth), np.isfinite(depth)
    both = rhit & fhit & keep
    differ = np.flatnonzero((rhit != fhit) & keep)
    at_edge = [i for i in differ if near_edge(i, depth[i] if fhit[i] else rdepth[i])]
    errors = np.zeros(len(depth))
    errors[both] = np.abs(rdepth[both] - depth[both]) / depth[both]
    # both hit, but one side went through an edge that the other stopped at (the other
    # found a farther triangle): an edge ray, counted apart like the hit/miss ones
    through_edge = [
        i
        for i in np.flatnonzero(both & (errors > limit))
        if near_edge(i, depth[i]) or near_edge(i, rdepth[i])
    ]
    counted = both.copy()
    counted[through_edge] = False
    rel = errors[counted]
    ref_name = np.array([objects.names[k] if k >= 0 else "" for k in obj], dtype=object)
    named = objects.names != [None]
    raycast_meshes = {
        o[key]
        for o in rc["sidecar"]["objects"]
        if o["kind"] != "quadric" and o["triangles"] and o[key] not in unmodelled
    }
    other_object = np.flatnonzero(both & (rname != ref_name)) if named else np.array([], int)
    objects_at_edge = [i for i in other_object if near_edge(i, depth[i]) or near_edge(i, rdepth[i])]
    worst = np.flatnonzero(counted)[np.argmax(rel)] if counted.any() else None
    report = {
        "scene": str(path),
        "objects": len(objects.names),
        "triangles": int(len(source.tris)),
        "rays": int(nrays),
        "hits_left_out": int((~keep).sum()),  # on quadric or gprim objects
        "hits_both": int(both.sum()),
        "depth_disagreements_at_edges": len(through_edge),  # left out of the statistics
        "misses_both": int((~rhit & ~fhit & keep).sum()),
        "hitmiss_disagreements": len(differ),
        "hitmiss_disagreements_at_edges": len(at_edge),
        "object_disagreements": len(other_object) if named else None,  # None: not compared
        "object_disagreements_at_edges": len(objects_at_edge),
        # drawn mesh objects one side has and the other has not (e.g. an invisible instance)
        "objects_only_raycast": sorted(raycast_meshes - set(objects.names)) if named else [],
        "objects_only_reference": sorted(set(objects.names) - raycast_meshes) if named else [],
        "depth_rel_max": float(rel.max()) if len(rel) else None,
        "depth_rel_p99": float(np.percentile(rel, 99)) if len(rel) else None,
        "depth_rel_p999": float(np.percentile(rel, 99.9)) if len(rel) else None,
        "worst_ray": None
        if worst is None
        else {
            "origin": origins[worst].tolist(),
            "direction": unit[worst].tolist(),
            "reference": float(depth[worst]),
            "raycast": float(rdepth[worst]),
            "object": ref_name[worst],
            "triangle": int(tri[worst]),
        },
        "disagreeing_rays": [
            {
                "origin": origins[i].tolist(),
                "direction": unit[i].tolist(),
                "reference": float(depth[i]),
                "raycast": float(rdepth[i]),
                "at_edge": i in at_edge,
            }
            for i in differ[:5]
        ],
    }
    failures = []
    if len(rel) and report["depth_rel_p999"] > limit:
        failures.append(f"depth p99.9 {report['depth_rel_p999']:.3g} > {limit:g}")
    if len(differ) > len(at_edge):
        failures.append(f"{len(differ) - len(at_edge)} hit/miss disagreements away from edges")
    if len(other_object) > len(objects_at_edge):
        failures.append(
            f"{len(other_object) - len(objects_at_edge)} object disagreements away from edges"
        )
    for side in ("raycast", "reference"):
        only = report[f"objects_only_{side}"]
        if only:
            failures.append(f"{len(only)} objects drawn by {side} only, e.g. {only[0]}")
    report["failures"] = failures
    report["pass"] = not failures
    return report


def line(r):
    fmt = lambda x: "-" if x is None else f"{x:.2e}"  # noqa: E731
    return (
        f"{r['scene']}: {'ok  ' if r['pass'] else 'FAIL'} rays {r['rays']} "
        f"hits {r['hits_both']} (both), hit/miss disagree {r['hitmiss_disagreements']} "
        f"({r['hitmiss_disagreements_at_edges']} at edges), "
        + (
            "objects not compared (one object to the reader), "
            if r["object_disagreements"] is None
            else f"object disagree {r['object_disagreements']} "
            f"({r['object_disagreements_at_edges']} at edges), "
        )
        + f"relative depth error max {fmt(r['depth_rel_max'])} p99 {fmt(r['depth_rel_p99'])} "
        + f"p99.9 {fmt(r['depth_rel_p999'])}"
        + f" ({r['depth_disagreements_at_edges']} rays through an edge left out)"
        + (f" -- {'; '.join(r['failures'])}" if r["failures"] else "")
    )


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("exact-depth"), description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--rays", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--limit", type=float, default=LIMIT)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--raycast", default=None)
    a = ap.parse_args(argv)
    scenes = a.scenes or [CHESS]
    missing = [s for s in scenes if not s.exists()]
    if missing:
        print(f"exact-depth: {missing[0]} not found", file=sys.stderr)
        return 2
    raycast = raycast_or_exit(a.raycast, "exact-depth")
    reports, refused = [], 0
    for scene in scenes:
        try:
            reports.append(check_scene(scene, raycast, a.rays, a.seed, a.limit))
        except RefuseError as e:
            print(f"exact-depth: {scene}: not compared: {e}", file=sys.stderr)
            refused += 1
    if a.json:
        print(json.dumps(reports, indent=1))
    else:
        for r in reports:
            print(line(r), flush=True)
    return 0 if all(r["pass"] for r in reports) and not refused else 1
