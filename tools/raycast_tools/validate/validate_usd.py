"""Validate raycast's USD import against usd-core + trimesh.

    python -m raycast_tools validate-usd SCENE_OR_DIR... [--rays N] [--seed S] [--segments N]
                                         [--json] [--raycast PATH]

For each USD scene (.usd/.usda/.usdc/.usdz; folders are searched recursively, files in a
`bad/` folder are skipped) the stage is opened with usd-core and flattened into world-space
triangles by export_usd_fixtures.flatten (raycast's rules: usd_counts.drawn_prims and
hidden_purpose, XformCache-equivalent ComputeLocalToWorldTransform, leftHanded winding,
instance proxies, PointInstancer instances from ComputeInstanceTransformsAtTime with
invisibleIds masked). Intrinsic gprims (Sphere, Cube, Cylinder, Cylinder_1, Cone, Capsule,
Capsule_1, Plane; axis and schema fallbacks) are tessellated here, caps included, twice:

* inner: every vertex on the surface (the body of the tessellation is inside the gprim),
* outer: the same mesh scaled radially about the axis / centre by 1/cos(delta), so that
  every face lies outside the surface (delta = 2 pi / segments, the angular step).

Both tessellations are cast with trimesh's float64 ray_triangle (validate.py's
`trace_f64`); general quadric prims (`raycast:quadric:*`) are intersected exactly with
quadric_reference.py and merged by nearest depth. The same rays (rays.py's
`make_rays`) go through `raycast SCENE --rays R.npy`.

Per scene: rays, hits, hit/miss disagreements, depth error against the tessellation
bound, object agreement (raycast's object name against the prim path of the reference
hit, `:caps`/`:top`/`:bottom` stripped). Ambiguous rays (counted, left out of the
checks): the inner and outer tessellations disagree on hit/miss or on the object (the
ray is within the tessellation's error band of a silhouette or of a cap rim); the hit
point is within AMBIG edge_rel * size of a triangle edge (mesh silhouettes, cube edges);
grazing hits; ties between objects; quadric tangent/clip hits.

Exit status: 0 every scene within TOL_USD, 1 a scene out of tolerance or raycast failed
on a scene usd-core opens, 2 usage error.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
from pxr import Usd, UsdGeom

from raycast_tools.cli import prog
from raycast_tools.paths import raycast_or_exit
from raycast_tools.rays import make_rays
from raycast_tools.reference import quadric_reference as qref
from raycast_tools.reference.usd_stage import (
    USD_EXTS,
    drawn_prims,
    flatten,
    hidden_purpose,
    open_stage,
    usd_files,
)
from raycast_tools.runner import run_rays
from raycast_tools.validate import validate
from raycast_tools.validate.metrics import edge_distance

SEGMENTS = 256  # default angular resolution of the gprim tessellation (around the axis)

# ---------------------------------------------------------------------------------
# Tolerances: the only place they are set.
#
# Depth bound, per ray (the tessellation bound):
#     bound = max(SAG / |cos|, d_inner - d_outer) + K * u32 * size / |cos| + 1e-12 * depth
# SAG is the scene's largest sagitta of the gprim tessellation in world units: a face of
# the inner tessellation spans at most an angle delta = 2 pi / segments on a curvature
# radius r, so it lies within r (1 - cos delta) ~ r delta^2 / 2 of the surface (the e^2/8r
# sagitta of an edge e = r delta, with a factor 4 of headroom for the faces' diagonals);
# SAG = max over gprims of r_max * (1 - cos delta) * (largest singular value of the world
# matrix). Along a ray that is SAG / |cos| (|cos| of the ray with the inner face). The
# outer tessellation brackets the true surface (union of convex bodies: d_outer <= d_true
# <= d_inner), which is the bound where 1/|cos| linearisation fails (grazing rays). The
# K u32 term is validate.py's float32 storage allowance for triangles (raycast stores
# meshes, cube faces and cap fans in f32 about an anchor). Meshes are exact: SAG = 0.
TOL_USD = {
    # non-ambiguous rays must agree on hit/miss (the band rays are already ambiguous)
    "hitmiss_agreement": 0.999,
    # object agreement on non-ambiguous rays both sides hit
    "object_agreement": 0.999,
    # max depth error / per-ray bound
    "depth_bound_ratio_max": 1.0,
    "depth_bound_k": validate.TOL["depth_bound_k"],
}
AMBIG = validate.AMBIG

SUFFIXES = (":caps", ":top", ":bottom")


def strip_suffix(name: str) -> str:
    for s in SUFFIXES:
        if name.endswith(s):
            return name[: -len(s)]
    return name


# ------------------------------------------------------------------ gprim tessellation

# (u, v, w) frame of an axis: w the axis, u and v the next two (cyclic), as raycast
FRAMES = {"X": (1, 2, 0), "Y": (2, 0, 1), "Z": (0, 1, 2)}


def _value(prim, name, fallback):
    attr = prim.GetAttribute(name)
    if attr and attr.HasAuthoredValue():
        v = attr.Get()
        if v is not None:
            return v
    return fallback


def _revolution(profile, n):
    """Vertices (k, 3) in (u, v, w) and faces of a surface of revolution.

    profile: [(rho, w)] from one end to the other; rho = 0 rows collapse to one vertex."""
    phi = 2 * np.pi * np.arange(n) / n
    c, s = np.cos(phi), np.sin(phi)
    tris = []
    rings = [np.stack([rho * c, rho * s, np.full(n, w)], axis=1) for rho, w in profile]
    for a, b in zip(rings[:-1], rings[1:]):
        a1, b1 = np.roll(a, -1, axis=0), np.roll(b, -1, axis=0)
        tris.append(np.stack([a, a1, b1], axis=1))
        tris.append(np.stack([a, b1, b], axis=1))
    return np.concatenate(tris) if tris else np.zeros((0, 3, 3))


def _disc(rho, w, n, up):
    phi = 2 * np.pi * np.arange(n) / n
    ring = np.stack([rho * np.cos(phi), rho * np.sin(phi), np.full(n, w)], axis=1)
    centre = np.repeat([[0.0, 0.0, w]], n, axis=0)
    nxt = np.roll(ring, -1, axis=0)
    t = np.stack([centre, ring, nxt], axis=1) if up else np.stack([centre, nxt, ring], axis=1)
    return t


def gprim_local(prim, n):
    """[(suffix, inner tris, outer tris)] in the prim's local space, and the sagitta
    (local units) of the inner tessellation; None when raycast draws nothing."""
    kind = prim.GetTypeName()
    delta = 2 * np.pi / n
    k = 1.0 / math.cos(delta)  # outer scale: faces spanning <= delta then lie outside
    axis = str(_value(prim, "axis", "Z"))
    if kind == "Sphere":
        r = float(_value(prim, "radius", 1.0))
        if r <= 0:
            return None
        m = n // 2
        theta = np.pi * np.arange(m + 1) / m
        t = _revolution([(r * math.sin(a), r * math.cos(a)) for a in theta[::-1]], n)
        return [("", t, t * k)], r * (1 - math.cos(delta)), "Z"
    if kind == "Cube":
        h = float(_value(prim, "size", 2.0)) / 2
        if h <= 0:
            return None
        corners = np.array([[x, y, z] for x in (-h, h) for y in (-h, h) for z in (-h, h)])
        quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
        t = np.array(
            [
                [corners[a], corners[b], corners[c]]
                for a, b, c, d in quads
                for a, b, c in ((a, b, c), (a, c, d))
            ]
        )
        return [("", t, t)], 0.0, "Z"
    if kind == "Plane":
        width = float(_value(prim, "width", 2.0))
        length = float(_value(prim, "length", 2.0))
        # usd-core's extents: X spans (y: length, z: width), Y (x: width, z: length),
        # Z (x: width, y: length); built directly in xyz, normal +axis
        half = {
            "X": (0.0, length / 2, width / 2),
            "Y": (width / 2, 0.0, length / 2),
            "Z": (width / 2, length / 2, 0.0),
        }[axis]
        a = {"X": 0, "Y": 1, "Z": 2}[axis]
        i, j = [x for x in range(3) if x != a]
        if a == 1:
            i, j = j, i  # keep (i, j, axis) right-handed: normal +axis
        p = []
        for si, sj in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            q = np.zeros(3)
            q[i], q[j] = si * half[i], sj * half[j]
            p.append(q)
        t = np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]])
        return [("", t, t)], 0.0, None
    if kind in ("Cylinder", "Cone", "Cylinder_1"):
        h = float(_value(prim, "height", 2.0))
        if kind == "Cylinder":
            bottom = top = float(_value(prim, "radius", 1.0))
        elif kind == "Cone":
            bottom, top = float(_value(prim, "radius", 1.0)), 0.0
        else:
            bottom = float(_value(prim, "radiusBottom", 1.0))
            top = float(_value(prim, "radiusTop", 1.0))
        if h == 0 or (bottom == 0 and top == 0):
            return None
        side = _revolution([(bottom, -h / 2), (top, h / 2)], n)
        caps = [
            c
            for c in (
                _disc(top, h / 2, n, True) if top > 0 else None,
                _disc(bottom, -h / 2, n, False) if bottom > 0 else None,
            )
            if c is not None
        ]
        caps = np.concatenate(caps)
        radial = np.array([k, k, 1.0])
        out = [("", side, side * radial), (":caps", caps, caps * radial)]
        return out, max(top, bottom) * (1 - math.cos(delta)), axis
    if kind in ("Capsule", "Capsule_1"):
        if kind == "Capsule":
            r = float(_value(prim, "radius", 0.5))
        else:
            r = float(_value(prim, "radiusTop", 0.5))
            if r != float(_value(prim, "radiusBottom", 0.5)):
                return None
        h = float(_value(prim, "height", 1.0))
        if r <= 0:
            return None
        m = max(1, n // 4)
        theta = (np.pi / 2) * np.arange(m + 1) / m
        hemi = [(r * math.sin(a), r * math.cos(a)) for a in theta[::-1]]  # equator first
        top = _revolution([(rho, w) for rho, w in hemi], n)
        bottom = _revolution([(rho, -w) for rho, w in hemi[::-1]], n)
        out = []
        if h > 0:
            side = _revolution([(r, -h / 2), (r, h / 2)], n)
            out.append(("", side, side * np.array([k, k, 1.0])))
        for suffix, t, w0 in ((":top", top, h / 2), (":bottom", bottom, -h / 2)):
            # built about their centre; outer scaled about it, both moved to w = w0
            out.append((suffix, t + [0, 0, w0], t * k + [0, 0, w0]))
        return out, r * (1 - math.cos(delta)), axis
    return None


def _drop_degenerate(t):
    if len(t) == 0:
        return t
    area = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    return t[area > 0]


class Tessellator:
    """flatten()'s gprim callback: world triangles of each gprim, inner and outer."""

    def __init__(self, segments):
        self.segments = segments
        self.outer = {}  # object name -> outer world triangles
        self.sagitta = 0.0  # largest world sagitta (SAG)
        self.count = 0

    def __call__(self, prim, matrix, name):
        res = gprim_local(prim, self.segments)
        if res is None:
            return []
        parts, sag, axis = res
        M = np.array(matrix, dtype=np.float64)  # row vectors: p_world = p M
        A, t0 = M[:3, :3], M[3, :3]
        perm = None
        if axis is not None:
            u, v, w = FRAMES[axis]
            perm = np.zeros((3, 3))
            perm[0, u] = perm[1, v] = perm[2, w] = 1.0  # (u, v, w) row -> xyz
        flip = np.linalg.det(A) < 0
        self.sagitta = max(self.sagitta, sag * float(np.linalg.svd(A, compute_uv=False)[0]))
        self.count += 1
        out = []
        for suffix, inner, outer in parts:
            world = []
            for t in (inner, outer):
                t = np.asarray(t, dtype=np.float64)
                if perm is not None:
                    t = t @ perm
                t = t @ A + t0
                if flip:
                    t = t[:, [0, 2, 1]]
                world.append(_drop_degenerate(t))
            self.outer[name + suffix] = world[1]
            out.append((name + suffix, world[0]))
        return out


# ------------------------------------------------------------------ quadric prims


def quadric_prims(stage):
    """qref.Quadric for each drawn prim carrying raycast:quadric:* (outside instancers)."""
    out = []
    excluded = set()
    for prim in drawn_prims(stage.GetPseudoRoot(), excluded):
        if prim.IsA(UsdGeom.PointInstancer):
            inst = UsdGeom.PointInstancer(prim)
            excluded.update(
                t for t in inst.GetPrototypesRel().GetTargets() if t.HasPrefix(prim.GetPath())
            )
            continue
        names = [
            a.GetName() for a in prim.GetAttributes() if a.GetName().startswith("raycast:quadric:")
        ]
        if not names or hidden_purpose(prim):
            continue
        get = lambda n: prim.GetAttribute(f"raycast:quadric:{n}").Get()  # noqa: E731
        ext = {}
        if "raycast:quadric:coefficients" in names:
            ext["coefficients"] = [float(x) for x in get("coefficients")]
        else:
            ext["Q"] = [float(x) for row in get("Q") for x in row]
            ext["P"] = [float(x) for x in get("P")]
            ext["R"] = float(get("R"))
        if "raycast:quadric:boundsMin" in names:
            ext["bounds"] = {
                "min": [float(x) for x in get("boundsMin")],
                "max": [float(x) for x in get("boundsMax")],
            }
        Q, P, R, bmin, bmax = qref.parse_quadric(ext)
        matrix = (
            UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(Usd.TimeCode.Default())
            if prim.IsA(UsdGeom.Xformable)
            else None
        )
        world = np.eye(4) if matrix is None else np.array(matrix, dtype=np.float64).T
        out.append(qref.Quadric(-1, str(prim.GetPath()), ext, [], world, Q, P, R, bmin, bmax))
    return out


# ------------------------------------------------------------------ one scene


def ref_scene(path, objects):
    objs = [
        validate.RefObject(
            f"usd:{name}", name, -1, np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3), False
        )
        for name, tris in objects
    ]
    ref = validate.RefScene(Path(path), objs)
    ref.finish()
    return ref


def trace(ref, origins, unit):
    depth, tri, tie = validate.trace_f64(ref, origins, unit)
    names = np.array([""] * len(origins), dtype=object)
    hit = tri >= 0
    names[hit] = [ref.objects[ref.tri_obj[t]].name for t in tri[hit]]
    return depth, tri, tie, names


def validate_scene(path, raycast, nrays=500, seed=0, segments=SEGMENTS):
    stage = open_stage(path)
    tess = Tessellator(segments)
    inner_objects = [(n, t) for n, t in flatten(stage, gprim=tess) if len(t)]
    outer_objects = [(n, tess.outer.get(n, t)) for n, t in inner_objects]
    quadrics = quadric_prims(stage)
    inner = ref_scene(path, inner_objects)
    outer = ref_scene(path, outer_objects)
    inner.quadrics = quadrics
    report = {
        "scene": str(path),
        "segments": segments,
        "gprims": tess.count,
        "quadric_prims": len(quadrics),
        "objects": len(inner_objects),
        "triangles": int(len(inner.tris)),
    }
    if inner.bounds() is None:
        report["skipped"] = "nothing drawn"
        return report
    origins, unit, dirs = make_rays(inner, nrays, seed)
    lo, hi = inner.bounds()
    size = float(np.linalg.norm(hi - lo)) or 1.0
    sag = tess.sagitta
    report.update(rays=nrays, size=size, sagitta=sag)

    di, ti, tie_i, ni = trace(inner, origins, unit)
    do, to, tie_o, no = trace(outer, origins, unit)
    reasons = [set() for _ in range(nrays)]
    cos = np.zeros(nrays)
    hi_ = ti >= 0
    cos[hi_] = np.abs(np.einsum("ij,ij->i", inner.normals[ti[hi_]], unit[hi_]))
    if quadrics:
        qres = qref.trace(quadrics, origins, unit)
        for ref_depth, ref_names, tri_ in ((di, ni, ti), (do, no, to)):
            use = qres["depth"] < ref_depth
            ref_depth[use] = qres["depth"][use]
            ref_names[use] = qres["name"][use]
            tri_[use] = -2
        qn = qres["normal"]
        qcos = np.abs(np.einsum("ij,ij->i", qn, unit)) / np.maximum(
            np.linalg.norm(qn, axis=1), 1e-300
        )
        cos = np.where(ti == -2, qcos, cos)
        for i in np.flatnonzero(qres["ambiguous"]):
            reasons[i].update(qres["reasons"][i])
    # ambiguity: tessellation band, edges, grazing, ties
    for i in np.flatnonzero(np.isfinite(di) != np.isfinite(do)):
        reasons[i].add("band")
    both = np.isfinite(di) & np.isfinite(do)
    for i in np.flatnonzero(both):
        if strip_suffix(ni[i]) != strip_suffix(no[i]):
            reasons[i].add("band")
    for i in np.flatnonzero(tie_i | tie_o):
        reasons[i].add("tie")
    m = ti >= 0
    if m.any():
        p = origins[m] + unit[m] * di[m, None]
        ed = edge_distance(inner.tris[ti[m]], p)
        for i in np.flatnonzero(m)[ed <= AMBIG["edge_rel"] * size]:
            reasons[i].add("edge")
        for i in np.flatnonzero(m)[cos[m] <= AMBIG["graze_cos"]]:
            reasons[i].add("graze")

    with tempfile.TemporaryDirectory() as tmp:
        rc = run_rays(raycast, path, origins, dirs, tmp)
    rdepth = np.asarray(rc["depth"], dtype=np.float64).reshape(-1)
    rid = np.asarray(rc["id"]).reshape(-1).astype(np.int64)
    id_name = {int(o["id"]): o["name"] for o in rc["sidecar"].get("objects", [])}
    rnames = np.array([id_name.get(int(k), "") if k else "" for k in rid], dtype=object)
    rhit = np.isfinite(rdepth) & (rid != 0)

    # raycast hits where the reference misses: the hit point's distance to a triangle edge
    # (a mesh silhouette just outside the reference) makes it ambiguous
    for i in np.flatnonzero(rhit & ~np.isfinite(di) & ~np.isfinite(do)):
        if len(inner.tris):
            p = origins[i] + unit[i] * rdepth[i]
            ed = edge_distance(inner.tris, np.repeat(p[None], len(inner.tris), 0))
            if ed.min() <= AMBIG["edge_rel"] * size:
                reasons[i].add("edge")
    amb = np.array([bool(r) for r in reasons])
    ok = ~amb
    ref_hit = np.isfinite(di)
    disagree = ok & (ref_hit != rhit)
    n_ok = int(ok.sum())
    hitmiss = 1.0 - disagree.sum() / n_ok if n_ok else 1.0
    cmp_ = ok & ref_hit & rhit
    obj_same = np.array([strip_suffix(rnames[i]) == strip_suffix(ni[i]) for i in range(nrays)])
    n_cmp = int(cmp_.sum())
    obj_agree = float(obj_same[cmp_].mean()) if n_cmp else 1.0
    # per-ray depth bound (see TOL_USD)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.maximum(cos, AMBIG["graze_cos"])
        bracket = np.where(np.isfinite(do), di - do, 0.0)
        bound = (
            np.maximum(sag / c, bracket)
            + TOL_USD["depth_bound_k"] * validate.U32 * size / c
            + 1e-12 * di
        )
        err = np.abs(rdepth - di)
    ratio = np.where(cmp_, err / bound, 0.0)
    reason_counts = {}
    for r in reasons:
        for x in r:
            reason_counts[x] = reason_counts.get(x, 0) + 1
    worst = int(np.argmax(ratio)) if n_cmp else None
    report.update(
        hits_reference=int(ref_hit.sum()),
        hits_raycast=int(rhit.sum()),
        ambiguous=int(amb.sum()),
        ambiguous_reasons=reason_counts,
        hitmiss_disagreements=int(disagree.sum()),
        hitmiss_agreement=float(hitmiss),
        compared=n_cmp,
        object_agreement=obj_agree,
        object_mismatches=[(ni[i], rnames[i]) for i in np.flatnonzero(cmp_ & ~obj_same)][:5],
        depth_err_max=float(err[cmp_].max()) if n_cmp else None,
        depth_err_rel_p99=float(np.percentile(err[cmp_] / di[cmp_], 99)) if n_cmp else None,
        depth_bound_ratio_max=float(ratio.max()) if n_cmp else None,
        depth_sag_ratio_max=(
            float((err[cmp_] / (sag / c[cmp_])).max()) if n_cmp and sag > 0 else None
        ),
        worst_ray=(
            None
            if worst is None
            else {
                "origin": origins[worst].tolist(),
                "direction": unit[worst].tolist(),
                "reference": float(di[worst]),
                "raycast": float(rdepth[worst]),
                "object": ni[worst],
            }
        ),
        disagreeing_rays=[
            {
                "origin": origins[i].tolist(),
                "direction": unit[i].tolist(),
                "reference": ni[i] or None,
                "raycast": rnames[i] or None,
            }
            for i in np.flatnonzero(disagree)[:5]
        ],
    )
    failures = []
    if hitmiss < TOL_USD["hitmiss_agreement"]:
        failures.append(f"hit/miss agreement {hitmiss:.4f}")
    if obj_agree < TOL_USD["object_agreement"]:
        failures.append(f"object agreement {obj_agree:.4f}")
    if n_cmp and ratio.max() > TOL_USD["depth_bound_ratio_max"]:
        failures.append(f"depth error / bound {ratio.max():.3g}")
    report["failures"] = failures
    report["pass"] = not failures
    return report


# ------------------------------------------------------------------ command line


def find_usd(arguments):
    for path, name in usd_files(arguments):
        if "bad" in Path(path).parts:
            continue
        if Path(path).suffix.lower()[1:] in USD_EXTS:
            yield path, name


def line(r):
    if "error" in r:
        return f"{r['scene']}: ERROR {r['error']}"
    if "skipped" in r:
        return f"{r['scene']}: skipped ({r['skipped']})"
    fmt = lambda x: "-" if x is None else f"{x:.2e}"  # noqa: E731
    return (
        f"{r['scene']}: {'ok  ' if r['pass'] else 'FAIL'} rays {r['rays']} "
        f"hits {r['hits_raycast']}/{r['hits_reference']} (raycast/ref) "
        f"ambiguous {r['ambiguous']} {r['ambiguous_reasons'] or ''} "
        f"hit/miss disagree {r['hitmiss_disagreements']} "
        f"object agree {r['object_agreement']:.4f} of {r['compared']} "
        f"depth err max {fmt(r['depth_err_max'])} (SAG {fmt(r['sagitta'])}, "
        f"err/bound {fmt(r['depth_bound_ratio_max'])})"
        + (f" -- {'; '.join(r['failures'])}" if r["failures"] else "")
    )


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("validate-usd"), description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--rays", type=int, default=500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--segments", type=int, default=SEGMENTS)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--raycast", default=None)
    args = ap.parse_args(argv)
    raycast = raycast_or_exit(args.raycast, "validate-usd")
    reports = []
    status = 0
    for path, name in find_usd(args.paths):
        try:
            r = validate_scene(path, raycast, args.rays, args.seed, args.segments)
        except Exception as error:  # noqa: BLE001 - report and go on
            r = {
                "scene": path,
                "error": str(error).strip().splitlines()[-1]
                if str(error)
                else type(error).__name__,
                "pass": False,
            }
        r["scene"] = name
        if not r.get("pass", True):
            status = 1
        reports.append(r)
        if not args.json:
            print(line(r), flush=True)
    if args.json:
        print(json.dumps(reports, indent=1, default=validate._json_default))
    if not reports:
        print("no USD scenes found", file=sys.stderr)
        return 2
    return status
