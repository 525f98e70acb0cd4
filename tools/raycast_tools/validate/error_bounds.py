"""Checks raycast's `error` and `certain` AOVs against exact answers (issue 32).

    python -m raycast_tools error-bounds [--rays N] [--seed S] [--json OUT] [--raycast PATH]

Writes scenes (meshes far from the origin in OBJ, meshes placed once and instanced by glTF
node matrices, nested instances, random quadric scenes, the stiff quadric cases of
fixtures/stiff), casts rays at them (aimed, grazing, through edges and vertices, misses) with
`raycast --rays R.npy --aov depth,t,id,prim,error,certain`, and computes each ray's exact
answer with bound_truth (rational arithmetic for triangles, mpmath at 340 bits for quadrics).

Per ray: the decision (nearest object and primitive, or a miss) and the exact depth of the
crossing of the primitive raycast reports. Exceptions: a hit whose |depth − exact| exceeds
its `error`, or a ray whose decision differs from the exact one while `certain` is 1. Also the
tightness, `error / |depth − exact|` where that is not zero, and `error / depth`, and the
fraction of uncertain rays. Exit status 0 when no case has an exception.

`nested` (instances under a parent node matrix, the matrices composed in f64 by the importer)
is covered like the others: the bound carries the composition's rounding
(crates/core/src/bound/transform.rs) against the exact product of the file's matrices.
`nested TRS` gives every node a translation, a not exactly unit rotation and a scale instead:
the truth is the matrix of the exactly normalized quaternion (bound_truth.trs), the bound
carries the rounding of the normalization and of multiplying them out.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import mpmath
import numpy as np

from raycast_tools.cli import prog
from raycast_tools.fixtures import random_quadric_scenes
from raycast_tools.fixtures.gltf_writer import Gltf, quadric_document
from raycast_tools.paths import ROOT, raycast_or_exit
from raycast_tools.rays import quadric_rays
from raycast_tools.reference import bound_truth as bt
from raycast_tools.reference import quadric_reference
from raycast_tools.runner import run_rays

AOV = "depth,t,id,prim,error,certain"
STIFF = ROOT / "fixtures/stiff/cases.json"


# ------------------------------------------------------------------------ meshes and rays


def terrain(rng, n: int, size: float):
    """A jittered (n+1)² height field of 2n² triangles, size across, near the origin."""
    xs = np.linspace(0.0, size, n + 1)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    jitter = rng.uniform(-0.2, 0.2, size=(2, n + 1, n + 1)) * size / n
    z = rng.uniform(0.0, 0.2 * size, size=(n + 1, n + 1))
    pts = np.stack([x + jitter[0], y + jitter[1], z], axis=-1).reshape(-1, 3)
    faces = []
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            faces += [[a, b, b + 1], [a, b + 1, a + 1]]
    return pts, np.array(faces)


def world_triangles(truth: bt.Truth):
    return np.array([[[float(c) for c in v] for v in t.verts] for t in truth.triangles])


def mesh_rays(tris, n: int, rng):
    """Rays at world triangles `tris` (T, 3, 3): aimed at interior points (50 %), grazing
    (15 %), through edge midpoints and vertices (20 %), at the bounding box (misses, 15 %)."""
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    centre, size = 0.5 * (lo + hi), float(np.linalg.norm(hi - lo))
    kind = rng.choice(4, size=n, p=[0.5, 0.15, 0.2, 0.15])
    pick = tris[rng.integers(0, len(tris), n)]
    w = rng.dirichlet([1, 1, 1], size=n)
    targets = np.einsum("ni,nij->nj", w, pick)
    edge = rng.integers(0, 3, n)
    mid = 0.5 * (pick[np.arange(n), edge] + pick[np.arange(n), (edge + 1) % 3])
    vertex = pick[np.arange(n), edge]
    at_edge = rng.random(n) < 0.5
    targets[kind == 2] = np.where(at_edge[:, None], mid, vertex)[kind == 2]
    targets[kind == 3] = (lo + rng.random((n, 3)) * (hi - lo))[kind == 3]
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    origins = centre + 1.5 * size * u
    normal = np.cross(pick[:, 1] - pick[:, 0], pick[:, 2] - pick[:, 0])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    along = np.cross(normal, rng.normal(size=(n, 3)))
    along /= np.linalg.norm(along, axis=1)[:, None]
    tilt = 10.0 ** rng.uniform(-7, -2, n)
    graze = (kind == 1)[:, None]
    origins = np.where(graze, targets - size * (along + tilt[:, None] * normal), origins)
    return origins, targets - origins


# ------------------------------------------------------------------------ scenes


def obj_scene(path: Path, rng, offset: float, size: float):
    """An OBJ height field offset by `offset` (every coordinate written exactly)."""
    pts, faces = terrain(rng, 10, size)
    pts = pts + offset
    lines = ["o field"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in pts.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces.tolist()]
    path.write_text("\n".join(lines) + "\n")
    tris = [
        bt.Triangle([bt.frac3(pts[i]) for i in f], "field", k) for k, f in enumerate(faces.tolist())
    ]
    return bt.Truth(tris, [])


def random_matrix(rng, reach: float, scale: float):
    """A column-major affine matrix: rotation, non-uniform scale, translation up to `reach`."""
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    m = np.eye(4)
    m[:3, :3] = q @ np.diag(rng.uniform(0.5, 2.0, 3) * scale)
    m[:3, 3] = rng.uniform(-reach, reach, 3)
    return m.T.flatten().tolist()


def random_trs(rng, reach: float, scale: float):
    """A node's translation, rotation and scale as a file gives them: the quaternion not
    exactly unit (a random direction in 4-D, written to 8 decimals)."""
    q = rng.normal(size=4)
    q = [round(float(c), 8) for c in q / np.linalg.norm(q)]
    return {
        "translation": rng.uniform(-reach, reach, 3).tolist(),
        "rotation": q,
        "scale": (rng.uniform(0.5, 2.0, 3) * scale).tolist(),
    }


def trs_matrix(props):
    """The exact matrix of random_trs's properties (bound_truth.trs)."""
    return bt.trs(props["translation"], props["rotation"], props["scale"])


def gltf_scene(path: Path, rng, layout: str):
    """A glTF of one f32 mesh drawn by node matrices: `placed` (one node, the mesh placed in
    the world), `instanced` (three nodes: instances), `nested` (a parent matrix over three
    children: instances under composed matrices), `nested once` (a parent matrix over one
    child: the mesh placed in the world by the composed matrix), `nested TRS` (as `nested`,
    every node by translation, rotation and scale instead of a matrix)."""
    pts, faces = terrain(rng, 4, 2.0)
    pts32 = pts.astype(np.float32)
    g = Gltf("raycast_tools error-bounds")
    acc = g.positions(pts32)
    idx = g.indices(faces)
    mesh = g.mesh("m", [{"attributes": {"POSITION": acc}, "indices": idx}])
    local = [bt.frac3(p) for p in pts32.astype(np.float64)]
    draws = []  # (node name, exact column-major world matrix)
    if layout == "nested TRS":
        parent = random_trs(rng, 1e4, 50.0)
        kids = []
        for k in range(3):
            m = random_trs(rng, 3.0, 0.5)
            kids.append(g.node(f"leaf{k}", mesh=mesh, **m))
            draws.append((f"leaf{k}", bt.compose(trs_matrix(parent), trs_matrix(m))))
        roots = [g.node("parent", children=kids, **parent)]
    elif layout.startswith("nested"):
        parent = random_matrix(rng, 1e4, 50.0)
        kids = []
        for k in range(3 if layout == "nested" else 1):
            m = random_matrix(rng, 3.0, 0.5)
            kids.append(g.node(f"leaf{k}", mesh=mesh, matrix=m))
            draws.append((f"leaf{k}", bt.compose(parent, m)))
        roots = [g.node("parent", matrix=parent, children=kids)]
    else:
        roots = []
        for k in range(1 if layout == "placed" else 3):
            m = random_matrix(rng, 1e5, 3.0)
            roots.append(g.node(f"n{k}", mesh=mesh, matrix=m))
            draws.append((f"n{k}", m))
    g.scene(roots)
    path.write_text(json.dumps(g.embedded()))
    tris = []
    for name, m in draws:
        world = [bt.place(m, p) for p in local]
        tris += [bt.Triangle([world[i] for i in f], name, k) for k, f in enumerate(faces.tolist())]
    return bt.Truth(tris, [])


def f32(values):
    """Random values rounded to f32, as floats (written so that a reader gets them back)."""
    return [float(np.float32(v)) for v in values]


def usd_ops(ops) -> tuple[str, list]:
    """A prim's xform op lines and its exact column-major matrix: `ops` lists (kind, value)
    outermost first, the values already f32 where the attribute is a float type."""
    lines, order, m = [], [], bt.translation([0, 0, 0])
    for kind, value in ops:
        name = f"xformOp:{kind}"
        order.append(f'"{name}"')
        if kind == "translate":
            lines.append(f"double3 {name} = ({value[0]!r}, {value[1]!r}, {value[2]!r})")
            op = bt.translation(value)
        elif kind == "scale":
            lines.append(f"float3 {name} = ({value[0]!r}, {value[1]!r}, {value[2]!r})")
            op = bt.scaling(value)
        elif kind == "orient":
            lines.append(f"quatf {name} = ({', '.join(repr(c) for c in value)})")
            op = bt.usd_orient(*value)
        elif kind == "rotateXYZ":
            lines.append(f"float3 {name} = ({value[0]!r}, {value[1]!r}, {value[2]!r})")
            # X first, then Y, then Z: Rz·Ry·Rx.
            op = bt.compose(
                bt.usd_rotation(2, value[2]),
                bt.compose(bt.usd_rotation(1, value[1]), bt.usd_rotation(0, value[0])),
            )
        else:  # rotateX, rotateY, rotateZ
            lines.append(f"float {name} = {value!r}")
            op = bt.usd_rotation("XYZ".index(kind[-1]), value)
        m = bt.compose(m, op)
    lines.append(f"uniform token[] xformOpOrder = [{', '.join(order)}]")
    return "\n".join(lines), m


def usd_scene(path: Path, rng):
    """A .usda of one f32 mesh under a parent Xform (translate up to 1e4, rotateXYZ in
    degrees, scale) in three Mesh prims of their own ops (translate, orient quatf not exactly
    unit, rotateZ): USD's ops composed in f64 by the importer, exactly by the truth (rotations
    of the exact angles, bt.usd_rotation, bt.usd_orient), so the bound must carry the angles'
    conversion, libm's sin and cos, the orient reading and the products."""
    pts, faces = terrain(rng, 4, 2.0)
    pts32 = pts.astype(np.float32)
    local = [bt.frac3(p) for p in pts32.astype(np.float64)]
    parent_lines, parent = usd_ops(
        [
            ("translate", rng.uniform(-1e4, 1e4, 3).tolist()),
            ("rotateXYZ", f32(rng.uniform(-180, 180, 3))),
            ("scale", f32(rng.uniform(20.0, 80.0, 3))),
        ]
    )
    point_text = ", ".join(f"({x!r}, {y!r}, {z!r})" for x, y, z in pts32.astype(float).tolist())
    counts = ", ".join("3" for _ in faces)
    indices = ", ".join(str(i) for i in faces.flatten().tolist())
    meshes, draws = [], []
    for k in range(3):
        q = rng.normal(size=4)
        lines, m = usd_ops(
            [
                ("translate", rng.uniform(-3, 3, 3).tolist()),
                ("orient", f32(q / np.linalg.norm(q))),
                ("rotateZ", f32([rng.uniform(-360, 360)])[0]),
            ]
        )
        body = f"int[] faceVertexCounts = [{counts}]\nint[] faceVertexIndices = [{indices}]\n"
        body += f"point3f[] points = [{point_text}]\n{lines}"
        meshes.append(f'def Mesh "leaf{k}"\n{{\n{body}\n}}')
        draws.append((f"/parent/leaf{k}", bt.compose(parent, m)))
    children = "\n".join(meshes)
    text = f'#usda 1.0\n\ndef Xform "parent"\n{{\n{parent_lines}\n{children}\n}}\n'
    path.write_text(text)
    tris = []
    for name, m in draws:
        world = [bt.place(m, p) for p in local]
        tris += [bt.Triangle([world[i] for i in f], name, k) for k, f in enumerate(faces.tolist())]
    return bt.Truth(tris, [])


def quadric_prim(ext: dict, matrix, name: str) -> bt.QuadricPrim:
    """A RAYCAST_quadric extension (either form) as exact coefficients."""
    if "coefficients" in ext:
        c = list(ext["coefficients"])
    else:
        q, p = ext["Q"], ext["P"]
        c = [q[0], q[4], q[8], 2 * q[1], 2 * q[2], 2 * q[5], *p, ext["R"]]
    b = ext.get("bounds")
    bounds = None
    if b is not None:
        bounds = ([mpmath.mpf(x) for x in b["min"]], [mpmath.mpf(x) for x in b["max"]])
    return bt.QuadricPrim(c, bounds, list(matrix), name)


def quadric_scene(path: Path, rng):
    doc = random_quadric_scenes.scene(rng)
    path.write_text(json.dumps(doc))
    prims = [
        quadric_prim(n["extensions"]["RAYCAST_quadric"], n["matrix"], n["name"])
        for n in doc["nodes"]
    ]
    qs = quadric_reference.quadrics_from_gltf(path)
    boxes = [q.world_bounds() for q in qs]
    boxes = [
        None if b is None else (b[0] - 1e-6 * (1 + abs(b[0])), b[1] + 1e-6 * (1 + abs(b[1])))
        for b in boxes
    ]
    return bt.Truth([], prims, boxes), qs


def sphere_scene(path: Path, rng, n: int):
    """Unit spheres placed by scale r and a translation up to 1e4 (RAYCAST_quadric
    coefficients), and `n` rays at their silhouettes: aimed at a tangent point offset from the
    sphere by ±10^U(-16, -6)·r, so that the exact answer is a hit or a miss by a hair."""
    unit = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]
    centres = rng.uniform(-1e4, 1e4, size=(4, 3))
    radii = rng.uniform(0.5, 5.0, size=4)
    nodes, prims, boxes = [], [], []
    for k, (c, r) in enumerate(zip(centres, radii)):
        m = [r, 0, 0, 0, 0, r, 0, 0, 0, 0, r, 0, *c.tolist(), 1]
        m = [float(x) for x in m]
        nodes.append(
            {
                "name": f"s{k}",
                "matrix": m,
                "extensions": {"RAYCAST_quadric": {"coefficients": unit}},
            }
        )
        prims.append(quadric_prim({"coefficients": unit}, m, f"s{k}"))
        boxes.append((c - r * (1 + 1e-6), c + r * (1 + 1e-6)))
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["RAYCAST_quadric"],
        "extensionsRequired": ["RAYCAST_quadric"],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
    }
    path.write_text(json.dumps(doc))
    which = rng.integers(0, 4, n)
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1)[:, None]
    u = np.cross(w, rng.normal(size=(n, 3)))
    u /= np.linalg.norm(u, axis=1)[:, None]
    r = radii[which][:, None]
    offset = rng.choice([-1.0, 1.0], n) * 10.0 ** rng.uniform(-16, -6, n)
    tangent = w / 20.0 + np.sqrt(1.0 - 1.0 / 400.0) * u  # seen from 20 r away along w
    targets = centres[which] + r * tangent * (1 + offset[:, None])
    origins = centres[which] + 20.0 * r * w
    return bt.Truth([], prims, boxes), origins, targets - origins


# ------------------------------------------------------------------------ checking


class Tally:
    """Counts and distributions of one category."""

    def __init__(self, name: str):
        self.name = name
        self.rays = self.hits = self.uncertain = 0
        self.differ = self.depth_exceptions = self.decision_exceptions = 0
        self.no_crossing = self.unbounded = 0
        self.ratio: list[float] = []  # error / |depth - exact|
        self.relative: list[float] = []  # error / depth
        self.actual: list[float] = []  # |depth - exact| / depth

    def summary(self) -> dict:
        q = lambda v, p: float(np.percentile(v, p)) if v else None  # noqa: E731
        return {
            "category": self.name,
            "rays": self.rays,
            "hits": self.hits,
            "uncertain": self.uncertain,
            "decision_differs": self.differ,
            "depth_exceptions": self.depth_exceptions,
            "decision_exceptions": self.decision_exceptions,
            "hits_without_exact_crossing": self.no_crossing,
            "unbounded_hits": self.unbounded,
            "ratio_median": q(self.ratio, 50),
            "ratio_p99": q(self.ratio, 99),
            "ratio_min": min(self.ratio) if self.ratio else None,
            "relative_bound_median": q(self.relative, 50),
            "relative_error_median": q(self.actual, 50),
        }


def check(tally: Tally, truth: bt.Truth, origins, dirs, res: dict):
    names = [o["name"] for o in res["sidecar"]["objects"]]
    for i in range(len(origins)):
        o, d = origins[i].tolist(), dirs[i].tolist()
        oid, prim = int(res["id"][i]), int(res["prim"][i])
        depth, error, certain = (
            float(res["depth"][i]),
            float(res["error"][i]),
            int(res["certain"][i]),
        )
        crossings, nearest = truth.answer(o, d)
        decision = (names[oid - 1], prim) if oid else None
        same = decision in nearest if decision else not nearest
        tally.rays += 1
        tally.uncertain += certain == 0
        tally.differ += not same
        tally.decision_exceptions += (not same) and certain == 1
        if decision is None:
            continue
        tally.hits += 1
        exact = truth.same_primitive_depth(o, d, *decision, mpmath.mpf(float(res["t"][i])))
        if exact is None:
            tally.no_crossing += 1
            tally.decision_exceptions += certain == 1 and same
            continue
        if not np.isfinite(error):
            tally.unbounded += 1
            continue
        actual = abs(mpmath.mpf(depth) - exact)
        if actual > mpmath.mpf(error):
            tally.depth_exceptions += 1
        if actual > 0:
            tally.ratio.append(float(mpmath.mpf(error) / actual))
        tally.relative.append(error / depth)
        tally.actual.append(float(actual / exact))


def by_octant(origins, dirs):
    """The rays ordered by their direction's octant (stable): runs of eight then share one, and
    raycast traces them as packets, so that its packet search and the `certain` it decides
    from what that search offered each ray are checked as well as the one-ray path."""
    key = (np.asarray(dirs) < 0) @ np.array([1, 2, 4])
    order = np.argsort(key, kind="stable")
    return np.asarray(origins)[order], np.asarray(dirs)[order]


def run_case(raycast, scene: Path, truth, origins, dirs, tally: Tally, work: Path):
    origins, dirs = by_octant(origins, dirs)
    res = run_rays(raycast, scene, origins, dirs, work, aov=AOV, out_name=scene.stem)
    check(tally, truth, origins, dirs, res)


def stiff_cases(raycast, tally: Tally, work: Path):
    """Each valid case of fixtures/stiff as a one-node glTF and its one ray."""
    for case in json.loads(STIFF.read_text()):
        if case["expected"]["error"]:
            continue
        ext = dict(case["quadric"])
        if case["bounds"]:
            ext["bounds"] = {"min": case["bounds"][0], "max": case["bounds"][1]}
        path = work / f"stiff_{case['name']}.gltf"
        path.write_text(json.dumps(quadric_document(ext, case["world"])))
        truth = bt.Truth([], [quadric_prim(ext, case["world"], "q")], [None])
        o, d = np.array([case["origin"]]), np.array([case["dir"]])
        run_case(raycast, path, truth, o, d, tally, work / "stiff")


def run_all(raycast, n: int, seed: int, work: Path) -> list[Tally]:
    rng = np.random.default_rng(seed)
    tallies = []
    for offset in (0.0, 1e3, 1e6, 1e7):
        t = Tally(f"obj mesh at {offset:g}")
        path = work / f"far_{offset:g}.obj"
        truth = obj_scene(path, rng, offset, 10.0)
        o, d = mesh_rays(world_triangles(truth), n, rng)
        run_case(raycast, path, truth, o, d, t, work)
        tallies.append(t)
    for layout in ("placed", "instanced", "nested", "nested once", "nested TRS"):
        t = Tally(f"glTF {layout}")
        path = work / f"{layout.replace(' ', '_')}.gltf"
        truth = gltf_scene(path, rng, layout)
        o, d = mesh_rays(world_triangles(truth), n, rng)
        run_case(raycast, path, truth, o, d, t, work)
        tallies.append(t)
    t = Tally("random quadrics")
    for k in range(4):
        path = work / f"quadrics_{k}.gltf"
        truth, qs = quadric_scene(path, rng)
        o, d = quadric_rays(qs, n // 2, seed=seed + k)
        run_case(raycast, path, truth, o, d, t, work)
    tallies.append(t)
    t = Tally("sphere silhouettes")
    truth, o, d = sphere_scene(work / "spheres.gltf", rng, n)
    run_case(raycast, work / "spheres.gltf", truth, o, d, t, work)
    tallies.append(t)
    t = Tally("USD xform ops")
    truth = usd_scene(work / "usd_ops.usda", rng)
    o, d = mesh_rays(world_triangles(truth), n, rng)
    run_case(raycast, work / "usd_ops.usda", truth, o, d, t, work)
    tallies.append(t)
    t = Tally("stiff quadric cases")
    stiff_cases(raycast, t, work)
    tallies.append(t)
    return tallies


def plot(data: dict, out: Path) -> None:
    """Two panels: the distribution of error / |depth − exact| per scene group, and error /
    depth beside |depth − exact| / depth."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = {"meshes (OBJ, far)": [], "glTF placed / instanced": [], "quadrics": []}
    bounds, actual = [], []
    for name, d in data["distributions"].items():
        key = (
            "quadrics"
            if "quadric" in name
            else "glTF placed / instanced"
            if "glTF" in name
            else "meshes (OBJ, far)"
        )
        groups[key] += d["ratio"]
        bounds += d["relative"]
        actual += [a for a in d["actual"] if a > 0]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    bins = np.linspace(0, 6, 61)
    for key, ratio in groups.items():
        if ratio:
            med = np.median(ratio)
            left.hist(
                np.log10(ratio), bins=bins, histtype="step", label=f"{key}: median {med:.0f}×"
            )
    left.axvline(0, color="k", lw=0.8)
    left.set_xlabel("log10(error / |depth − exact depth|)   (≥ 0: contained)")
    left.set_ylabel("hits")
    left.set_title("How far the bound is above the actual error")
    left.legend(fontsize=8)
    bins = np.linspace(-18, -8, 81)
    right.hist(np.log10(actual), bins=bins, histtype="step", label="|depth − exact| / depth")
    right.hist(np.log10(bounds), bins=bins, histtype="step", label="error / depth")
    right.set_xlabel("log10(relative)")
    right.set_title("Bound and actual error, relative to depth")
    right.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("error-bounds"), description=__doc__.split("\n\n")[0])
    ap.add_argument("--rays", type=int, default=2000, help="rays per scene (default 2000)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", type=Path, help="write the summary and distributions here")
    ap.add_argument("--raycast", help="raycast binary (default: target/release/raycast)")
    ap.add_argument("--plot", type=Path, help="draw the tightness figure from a --json file here")
    args = ap.parse_args(argv)
    if args.plot:
        if not args.json or not args.json.exists():
            ap.error("--plot needs the --json file of an earlier run")
        plot(json.loads(args.json.read_text()), args.plot)
        return 0
    raycast = raycast_or_exit(args.raycast, "error-bounds")
    with tempfile.TemporaryDirectory() as tmp:
        tallies = run_all(raycast, args.rays, args.seed, Path(tmp))
    rows = [t.summary() for t in tallies]
    for row in rows:
        print(json.dumps(row))
    if args.json:
        dist = {
            t.name: {"ratio": t.ratio, "relative": t.relative, "actual": t.actual} for t in tallies
        }
        args.json.write_text(json.dumps({"summary": rows, "distributions": dist}))
    bad = sum(r["depth_exceptions"] + r["decision_exceptions"] for r in rows)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
