"""Write the RAYCAST_quadric glTF fixtures under fixtures/quadrics/ and the
invalid ones under fixtures/bad/quadric_*.gltf.

Run with the repo's venv:  .venv/bin/python -m raycast_tools quadric-fixtures

Only numpy and the standard library are used (mpmath, when installed, is used
for an extra high-precision check of the expectations). A rerun gives
byte-identical files. fixtures/quadrics/README.md documents every file;
fixtures/quadrics/expected_rays.json holds the documented rays and their answers
in machine-readable form (written by this script, so the two cannot drift).

Every expectation is built analytically (closed form in the quadric's local
space, mapped through the node matrix: the ray parameter t is the same in both
spaces, hit = T·p_local, normal = normalise(A⁻ᵀ ∇f)); the script then checks
each one by tracing the ray against every node of the file with an independent
object-space f64 intersector (quadrics and triangles), and refuses to write a
file whose documented answers it cannot reproduce to 1e-12.

Options: --check-only (verify, write nothing).
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from . import gltf_writer
from . import quadric_reference as qref
from .cli import prog
from .fixture_files import FixtureFiles
from .gltf_writer import json_text
from .paths import ROOT

QDIR = ROOT / "fixtures" / "quadrics"
BAD_DIR = ROOT / "fixtures" / "bad"
# Fixture content: it names the script's path before the tools became one package, and stays
# as it is so that the fixtures regenerate byte-identical.
GENERATOR = "raycast tools/make_quadric_fixtures.py"
EXT = "RAYCAST_quadric"

FILES = FixtureFiles(ROOT)
EXPECTED: dict[str, dict] = {}


def fl(v):
    """Numbers as Python floats (JSON `1.0`, never `1`), recursively."""
    if isinstance(v, (list, tuple, np.ndarray)):
        return [fl(x) for x in v]
    return float(v)


# --------------------------------------------------------------------------
# a tiny glTF writer


class Gltf(gltf_writer.Gltf):
    """gltf_writer's writer, plus RAYCAST_quadric nodes and the mesh triangles kept for
    the self-check."""

    def __init__(self) -> None:
        super().__init__(GENERATOR)
        # geometry kept for the self-check: mesh index -> (n, 3, 3) float64 triangles
        self.mesh_tris: dict[int, np.ndarray] = {}

    def indexed_mesh(self, name: str, verts, idx) -> int:
        """One triangle-list primitive: float32 positions, uint16 indices."""
        v = np.asarray(verts, dtype=np.float32).reshape(-1, 3)
        i = np.asarray(idx, dtype=np.uint16).reshape(-1)
        assert np.all(v.astype(np.float64) == np.asarray(verts, dtype=np.float64).reshape(-1, 3)), (
            "mesh vertices must be exact in float32"
        )
        pos = self.positions(v)
        m = self.mesh(
            name, [{"attributes": {"POSITION": pos}, "indices": self.indices(i), "mode": 4}]
        )
        self.mesh_tris[m] = v.astype(np.float64)[i.reshape(-1, 3)]
        return m

    def quadric_node(self, name: str, ext: dict, **props) -> int:
        props.setdefault("extensions", {})[EXT] = ext
        return self.node(name, **props)

    def camera(self, name: str, yfov: float, aspect: float, znear: float = 0.01, **props) -> int:
        cam = self.perspective(name, float(yfov), float(aspect), float(znear))
        return self.node(name, camera=cam, **props)

    def document(self, required: bool) -> dict:
        """The glTF JSON, buffer as a data URI, RAYCAST_quadric used (and required
        when `required`), one scene of all nodes unless a scene was added."""
        doc, _ = self.finish(
            "data",
            extensionsUsed=[EXT],
            extensionsRequired=[EXT] if required else self.doc["extensionsRequired"],
            scenes=self.doc["scenes"] or [{"nodes": list(range(len(self.doc["nodes"])))}],
        )
        return doc


# --------------------------------------------------------------------------
# math: an object-space reference intersector (node matrices and quadric
# parsing are quadric_reference.py's)


def q_f(Q, P, R, p):
    return p @ Q @ p + P @ p + R


def intersect_local(Q, P, R, bmin, bmax, o, v):
    """Smallest t > 0 of o + t v on the (clipped) quadric, object space. Returns
    (t, p_local) or None. Roots from the stable pair, refined by one Newton step."""
    K = v @ Q @ v
    L = 2 * (o @ Q @ v) + P @ v
    M = q_f(Q, P, R, o)
    scale = max(abs(Q).max() * (v @ v), 1e-300)
    roots = []
    if abs(K) <= 1e-14 * scale:
        if L != 0:
            roots = [-M / L]
    else:
        tc = -L / (2 * K)
        disc = -4 * K * q_f(Q, P, R, o + tc * v)
        if disc < 0:
            return None
        sq = math.sqrt(disc)
        q = -(L + math.copysign(sq, L)) / 2
        roots = sorted([q / K, M / q] if q != 0 else [tc])
    best = None
    for t in roots:
        # one Newton step on g(t) = f(o + t v)
        g = q_f(Q, P, R, o + t * v)
        dg = 2 * ((o + t * v) @ Q @ v) + P @ v
        if dg != 0:
            t = t - g / dg
        if not t > 0:
            continue
        p = o + t * v
        if bmin is not None:
            eps = 1e-9 * float((bmax - bmin).max())
            if np.any(p < bmin - eps) or np.any(p > bmax + eps):
                continue
        if best is None or t < best[0]:
            best = (t, p)
    return best


def tri_hit(tri, o, d, min_det: float = 1e-300):
    """Möller–Trumbore in float64: (t, unit normal, u, v) for the hit of o + t d
    (t > 0) on triangle (a, b, c) = a + u (b - a) + v (c - a), normal along
    (b - a) x (c - a); None on a miss or when |det| < min_det (parallel)."""
    a, b, c = tri
    e1, e2 = b - a, c - a
    pv = np.cross(d, e2)
    det = e1 @ pv
    if abs(det) < min_det:
        return None
    s = o - a
    u = (s @ pv) / det
    qv = np.cross(s, e1)
    w = (d @ qv) / det
    t = (e2 @ qv) / det
    if u < 0 or w < 0 or u + w > 1 or t <= 0:
        return None
    n = np.cross(e1, e2)
    return t, n / np.linalg.norm(n), u, w


def trace(g: Gltf, doc: dict, o, d):
    """Nearest hit over all nodes: (node name, kind, t, depth, normal, position) or None."""
    o, d = np.asarray(o, float), np.asarray(d, float)
    mats = qref.node_world_matrices(doc)
    best = None
    for i, T in mats.items():
        node = doc["nodes"][i]
        A, tr = T[:3, :3], T[:3, 3]
        if "mesh" in node:
            flip = np.linalg.det(A) < 0
            for k, tri in enumerate(g.mesh_tris[node["mesh"]]):
                wt = tri @ A.T + tr
                h = tri_hit(wt, o, d)
                if h and (best is None or h[0] < best[2]):
                    n = -h[1] if flip else h[1]
                    best = (
                        node["name"],
                        "mesh",
                        h[0],
                        h[0] * np.linalg.norm(d),
                        n,
                        o + h[0] * d,
                        k,
                    )
        ext = node.get("extensions", {}).get(EXT)
        if ext is not None:
            Q, P, R, bmin, bmax = qref.parse_quadric(ext)
            Ai = np.linalg.inv(A)
            h = intersect_local(Q, P, R, bmin, bmax, Ai @ (o - tr), Ai @ d)
            if h and (best is None or h[0] < best[2]):
                t, p = h
                n = Ai.T @ (2 * Q @ p + P)
                best = (
                    node["name"],
                    "quadric",
                    t,
                    t * np.linalg.norm(d),
                    n / np.linalg.norm(n),
                    o + t * d,
                    0,
                )
    return best


def mp_check(doc: dict, node_name: str, o, d, depth: float) -> float:
    """Relative difference between `depth` and a 120-bit mpmath solve of the
    quadric node `node_name` (nearest root inside the box), or 0 without mpmath."""
    try:
        import mpmath as mp
    except ImportError:
        return 0.0
    mp.mp.prec = 120
    mats = qref.node_world_matrices(doc)
    i = [k for k, n in enumerate(doc["nodes"]) if n["name"] == node_name][0]
    node = doc["nodes"][i]
    Q, P, R, bmin, bmax = qref.parse_quadric(node["extensions"][EXT])
    T = qref.mp_local_matrix(mp, node)  # exact node matrix from the JSON numbers
    assert np.allclose(np.array(T.tolist(), dtype=float), mats[i], atol=1e-12)  # root nodes only
    Ti = mp.inverse(T)
    ol = [sum(Ti[r, c] * mp.mpf(([*o, 1.0])[c]) for c in range(4)) for r in range(3)]
    vl = [sum(Ti[r, c] * mp.mpf(float(d[c])) for c in range(3)) for r in range(3)]
    Qm = [[mp.mpf(Q[r, c]) for c in range(3)] for r in range(3)]
    Pm = [mp.mpf(p) for p in P]

    def qf(p):
        return (
            sum(p[r] * Qm[r][c] * p[c] for r in range(3) for c in range(3))
            + sum(Pm[r] * p[r] for r in range(3))
            + mp.mpf(R)
        )

    K = sum(vl[r] * Qm[r][c] * vl[c] for r in range(3) for c in range(3))
    L = 2 * sum(ol[r] * Qm[r][c] * vl[c] for r in range(3) for c in range(3)) + sum(
        Pm[r] * vl[r] for r in range(3)
    )
    M = qf(ol)
    if abs(K) < mp.mpf(10) ** -25:
        ts = [-M / L]
    else:
        disc = L * L - 4 * K * M
        ts = sorted([(-L - mp.sqrt(disc)) / (2 * K), (-L + mp.sqrt(disc)) / (2 * K)])
    dn = mp.sqrt(sum(mp.mpf(float(c)) ** 2 for c in d))
    for t in ts:
        if t <= 0:
            continue
        p = [ol[r] + t * vl[r] for r in range(3)]
        if bmin is not None and any(
            p[r] < bmin[r] - 1e-9 or p[r] > bmax[r] + 1e-9 for r in range(3)
        ):
            continue
        return float(abs(t * dn - mp.mpf(depth)) / abs(t * dn))
    raise AssertionError("mpmath found no hit")


# --------------------------------------------------------------------------
# documented rays


class Rays:
    """Collects the documented rays of one file and checks each against trace()."""

    def __init__(self, g: Gltf, doc: dict, fname: str):
        self.g, self.doc, self.fname, self.rows = g, doc, fname, []

    def add(
        self,
        label: str,
        o,
        d,
        node: str | None,
        depth: float | None = None,
        normal=None,
        position=None,
        kind: str | None = None,
        prim: int | None = None,
        note: str = "",
    ):
        o, d = [float(x) for x in o], [float(x) for x in d]
        got = trace(self.g, self.doc, o, d)
        row = {"label": label, "origin": o, "direction": d}
        if node is None:
            assert got is None, (self.fname, label, got)
            row.update({"hit": None, "depth": None})
        else:
            assert got is not None, (self.fname, label, "expected a hit, got a miss")
            name, gkind, t, gdepth, gnormal, gpos, gprim = got
            assert name == node, (self.fname, label, name, node)
            if kind is not None:
                assert gkind == kind, (self.fname, label, gkind, kind)
            assert abs(gdepth - depth) <= 1e-12 * max(1.0, depth), (
                self.fname,
                label,
                gdepth,
                depth,
            )
            normal = np.asarray(normal, float)
            normal = normal / np.linalg.norm(normal)
            assert np.abs(gnormal - normal).max() <= 1e-12, (self.fname, label, gnormal, normal)
            if position is None:
                position = np.asarray(o) + (depth / np.linalg.norm(d)) * np.asarray(d)
            assert np.abs(gpos - position).max() <= 1e-12 * max(1.0, np.abs(position).max()), (
                self.fname,
                label,
                gpos,
                position,
            )
            if gkind == "quadric":
                rel = mp_check(self.doc, node, o, d, depth)
                assert rel <= 2e-15, (self.fname, label, "mpmath", rel)
            row.update(
                {
                    "hit": node,
                    "kind": gkind,
                    "depth": float(depth),
                    "normal": fl(normal),
                    "position": fl(position),
                }
            )
            if gkind == "mesh":
                row["prim"] = int(gprim if prim is None else prim)
                assert prim is None or prim == gprim, (self.fname, label, gprim, prim)
        if note:
            row["note"] = note
        self.rows.append(row)
        return row


def write_fixture(g: Gltf, fname: str, required: bool, build_rays, description: str) -> dict:
    doc = g.document(required)
    rays = Rays(g, doc, fname)
    build_rays(rays, doc)
    EXPECTED[fname] = {"description": description, "rays": rays.rows}
    FILES.write_json(QDIR / fname, doc)
    return doc


# --------------------------------------------------------------------------
# 1. the lecture's sphere, both JSON forms

SPHERE_COEFFS = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -4.0]
SPHERE_MATRIX = {
    "Q": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
    "P": [0.0, 0.0, 0.0],
    "R": -4.0,
}


def sphere_rays(r: Rays, doc) -> None:
    s3 = math.sqrt(3.0)
    r.add("centre ray", [0, 0, 10], [0, 0, -1], "sphere", 8.0, [0, 0, 1], [0, 0, 2])
    r.add("off-axis", [1, 0, 10], [0, 0, -1], "sphere", 10 - s3, [0.5, 0, s3 / 2], [1, 0, s3])
    r.add(
        "off-axis, non-unit direction",
        [0, -1, 10],
        [0, 0, -4],
        "sphere",
        10 - s3,
        [0, -0.5, s3 / 2],
        [0, -1, s3],
    )
    r.add("from the side", [-5, 0, 0], [1, 0, 0], "sphere", 3.0, [-1, 0, 0], [-2, 0, 0])
    r.add("from the centre (inside)", [0, 0, 0], [0, 1, 0], "sphere", 2.0, [0, 1, 0], [0, 2, 0])
    r.add("diagonal", [3, 4, 0], [-3, -4, 0], "sphere", 3.0, [0.6, 0.8, 0], [1.2, 1.6, 0])
    r.add("passes beside", [0, 3, 10], [0, 0, -1], None)
    r.add("sphere behind the origin", [0, 0, 10], [0, 0, 1], None)


def make_spheres() -> None:
    for fname, ext in [
        ("sphere_coefficients.gltf", {"coefficients": SPHERE_COEFFS}),
        ("sphere_matrices.gltf", dict(SPHERE_MATRIX)),
    ]:
        g = Gltf()
        g.quadric_node("sphere", ext)
        g.camera("cam", 0.5, 1.0, translation=[0.0, 0.0, 10.0])
        write_fixture(g, fname, True, sphere_rays, "sphere r = 2 at the origin, camera at (0,0,10)")


# --------------------------------------------------------------------------
# 2. one file per quadric family, five placements each

S3 = math.sqrt(3.0)
ROT_Q = [0.2, 0.4, 0.4, 0.8]  # unit quaternion (1,2,2,4)/5: a 73.74° rotation about (1,2,2)/3
SHEAR = [[1.0, 0.3, 0.0], [0.0, 1.0, 0.2], [0.25, 0.0, 1.0]]  # linear part of "sheared"


def placements() -> list[tuple[str, dict]]:
    sm = np.eye(4)
    sm[:3, :3] = SHEAR
    sm[:3, 3] = [16.0, -0.5, 0.25]
    return [
        ("scaled", {"translation": [-16.0, 0.0, 0.0], "scale": [0.5, 1.5, 2.0]}),
        ("rotated", {"translation": [-8.0, 0.0, 0.0], "rotation": ROT_Q}),
        ("canonical", {}),
        ("translated", {"translation": [8.0, 0.5, -0.75]}),
        ("sheared", {"matrix": fl(sm.T.reshape(-1))}),
    ]


# family: (file, equation, coefficients, bounds or None, local rays)
# local ray: (label, o_l, v_l, t, p_l) with p_l on the surface, or t = None for a miss
FAMILIES = [
    (
        "ellipsoid.gltf",
        "x²/4 + y² + z²/2.25 = 1, written ×9: 2.25x² + 9y² + 4z² − 9 = 0",
        [2.25, 9.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -9.0],
        None,
        [
            ("down the z axis", [0, 0, 5], [0, 0, -1], 3.5, [0, 0, 1.5]),
            ("along -x", [5, 0, 0], [-1, 0, 0], 3.0, [2, 0, 0]),
            ("along -y", [0, 5, 0], [0, -1, 0], 4.0, [0, 1, 0]),
        ],
    ),
    (
        "elliptic_paraboloid.gltf",
        "z = x² + y²/4, i.e. x² + 0.25y² − z = 0, 0 ≤ z ≤ 2",
        [1.0, 0.25, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
        ([-1.5, -3.0, 0.0], [1.5, 3.0, 2.0]),
        [
            ("down, parallel to the axis (K = 0)", [1, 0, 5], [0, 0, -1], 4.0, [1, 0, 1]),
            ("along +x", [-5, 0, 1], [1, 0, 0], 4.0, [-1, 0, 1]),
            ("along -y", [0, 5, 1], [0, -1, 0], 3.0, [0, 2, 1]),
        ],
    ),
    (
        "hyperbolic_paraboloid.gltf",
        "z = x² − y², i.e. x² − y² − z = 0, |x|, |y| ≤ 1 (−1 ≤ z ≤ 1)",
        [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
        ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
        [
            ("down (K = 0)", [0.5, 0.25, 5], [0, 0, -1], 4.8125, [0.5, 0.25, 0.1875]),
            ("along +x over the saddle", [-5, 0, 0.25], [1, 0, 0], 4.5, [-0.5, 0, 0.25]),
        ],
    ),
    (
        "hyperboloid_one_sheet.gltf",
        "x² + y² − z² = 1, |z| ≤ 1.5",
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        ([-2.0, -2.0, -1.5], [2.0, 2.0, 1.5]),
        [
            ("along -x at the waist", [5, 0, 0], [-1, 0, 0], 4.0, [1, 0, 0]),
            ("along -x at z = 1", [5, 0, 1], [-1, 0, 0], 5 - math.sqrt(2), [math.sqrt(2), 0, 1]),
            ("down the axis (through the hole)", [0, 0, 5], [0, 0, -1], None, None),
        ],
    ),
    (
        "hyperboloid_two_sheets.gltf",
        "−x² − y² + z² = 1, |z| ≤ 2.5",
        [-1.0, -1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        ([-2.5, -2.5, -2.5], [2.5, 2.5, 2.5]),
        [
            ("down the axis", [0, 0, 5], [0, 0, -1], 4.0, [0, 0, 1]),
            ("down at x = 1", [1, 0, 5], [0, 0, -1], 5 - math.sqrt(2), [1, 0, math.sqrt(2)]),
            ("along -x between the sheets", [5, 0, 0], [-1, 0, 0], None, None),
        ],
    ),
    (
        "cone.gltf",
        "x² + y² − z² = 0, |z| ≤ 1.5",
        [1.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ([-1.5, -1.5, -1.5], [1.5, 1.5, 1.5]),
        [
            ("along -x at z = 1", [5, 0, 1], [-1, 0, 0], 4.0, [1, 0, 1]),
            ("down at x = 0.5", [0.5, 0, 5], [0, 0, -1], 4.5, [0.5, 0, 0.5]),
        ],
    ),
    (
        "cylinder.gltf",
        "x² + y² = 1, |z| ≤ 1 (open tube)",
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
        [
            ("along -x", [5, 0, 0], [-1, 0, 0], 4.0, [1, 0, 0]),
            ("along -y at z = 0.5", [0.6, 5, 0.5], [0, -1, 0], 4.2, [0.6, 0.8, 0.5]),
            ("down the axis (K = L = 0)", [0.5, 0, 5], [0, 0, -1], None, None),
        ],
    ),
    (
        "elliptic_cylinder.gltf",
        "x²/4 + y² = 1, |z| ≤ 1",
        [0.25, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        ([-2.0, -1.0, -1.0], [2.0, 1.0, 1.0]),
        [
            ("along -x", [5, 0, 0], [-1, 0, 0], 3.0, [2, 0, 0]),
            ("along -y", [0, 5, 0.5], [0, -1, 0], 4.0, [0, 1, 0.5]),
            ("down the axis", [0.5, 0.25, 5], [0, 0, -1], None, None),
        ],
    ),
    (
        "hyperbolic_cylinder.gltf",
        "x² − y² = 1, |x| ≤ 2, |y| ≤ 1.5, |z| ≤ 1",
        [1.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
        ([-2.0, -1.5, -1.0], [2.0, 1.5, 1.0]),
        [
            ("along -x", [5, 0, 0], [-1, 0, 0], 4.0, [1, 0, 0]),
            ("along -x at y = 0.75", [5, 0.75, 0], [-1, 0, 0], 3.75, [1.25, 0.75, 0]),
            ("along -y between the sheets", [0, 5, 0], [0, -1, 0], None, None),
        ],
    ),
    (
        "parabolic_cylinder.gltf",
        "y = x², i.e. x² − y = 0, |x| ≤ 1.5, 0 ≤ y ≤ 2, |z| ≤ 1",
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0],
        ([-1.5, 0.0, -1.0], [1.5, 2.0, 1.0]),
        [
            ("along -y (K = 0)", [0.5, 5, 0], [0, -1, 0], 4.75, [0.5, 0.25, 0]),
            ("along +x", [-5, 1, 0.5], [1, 0, 0], 4.0, [-1, 1, 0.5]),
        ],
    ),
]


def gradient(coeffs, p):
    Q, P, _, _, _ = qref.parse_quadric({"coefficients": coeffs})
    return 2 * Q @ np.asarray(p, float) + P


def make_families() -> None:
    for fname, eq, coeffs, bounds, local_rays in FAMILIES:
        g = Gltf()
        ext = {"coefficients": coeffs}
        if bounds is not None:
            ext["bounds"] = {"min": bounds[0], "max": bounds[1]}
        for name, props in placements():
            g.quadric_node(name, json.loads(json.dumps(ext)), **props)
        g.camera("cam", 0.5, 3.0, rotation=CAM_Q, translation=CAM_T)
        # the clip boxes (or ellipsoid boxes) must not overlap in x
        doc0 = g.document(True)
        mats = qref.node_world_matrices(doc0)
        lo_box = np.array(bounds[0]) if bounds else np.array([-2.0, -1.0, -1.5])
        hi_box = np.array(bounds[1]) if bounds else np.array([2.0, 1.0, 1.5])
        corners = np.array(
            [
                [x, y, z]
                for x in (lo_box[0], hi_box[0])
                for y in (lo_box[1], hi_box[1])
                for z in (lo_box[2], hi_box[2])
            ]
        )
        spans = []
        for i in range(5):
            T = mats[i]
            w = corners @ T[:3, :3].T + T[:3, 3]
            spans.append((w[:, 0].min(), w[:, 0].max()))
        for a, b in zip(spans, spans[1:]):
            assert a[1] < b[0] - 0.5, (fname, spans)

        def build(r: Rays, doc, local_rays=local_rays, coeffs=coeffs):
            mats = qref.node_world_matrices(doc)
            for i, (name, _) in enumerate(placements()):
                T = mats[i]
                A, tr = T[:3, :3], T[:3, 3]
                for label, ol, vl, t, pl in local_rays:
                    o = A @ np.asarray(ol, float) + tr
                    d = A @ np.asarray(vl, float)
                    if name == "canonical":
                        o, d = np.asarray(ol, float), np.asarray(vl, float)
                    if t is None:
                        got = trace(r.g, doc, o, d)
                        if got is not None:
                            print(
                                f"  note: {fname} {name} '{label}' blocked by {got[0]}; not "
                                "documented"
                            )
                            continue
                        r.add(f"{name}: {label}", o, d, None)
                        continue
                    n = np.linalg.inv(A).T @ gradient(coeffs, pl)
                    pos = A @ np.asarray(pl, float) + tr
                    got = trace(r.g, doc, o, d)
                    if got is None or got[0] != name:
                        print(
                            f"  note: {fname} {name} '{label}' blocked by {got and got[0]}; not "
                            "documented"
                        )
                        continue
                    r.add(f"{name}: {label}", o, d, name, t * float(np.linalg.norm(d)), n, pos)

        write_fixture(g, fname, True, build, eq)


# family-file camera: 40 units from the origin, 20° above the XZ plane, looking at the origin
CAM_ALPHA = math.radians(20.0)
CAM_Q = [-math.sin(CAM_ALPHA / 2), 0.0, 0.0, math.cos(CAM_ALPHA / 2)]
CAM_T = [0.0, 40.0 * math.sin(CAM_ALPHA), 40.0 * math.cos(CAM_ALPHA)]


# --------------------------------------------------------------------------
# 3. quadrics and meshes together


def make_mixed() -> None:
    g = Gltf()
    ground = g.indexed_mesh(
        "ground", [[-6, -1, 5], [6, -1, 5], [6, -1, -5], [-6, -1, -5]], [0, 1, 2, 0, 2, 3]
    )
    h = 0.5
    cv = [
        [-h, -h, -h],
        [h, -h, -h],
        [h, h, -h],
        [-h, h, -h],
        [-h, -h, h],
        [h, -h, h],
        [h, h, h],
        [-h, h, h],
    ]
    cf = [
        4,
        5,
        6,
        4,
        6,
        7,
        0,
        2,
        1,
        0,
        3,
        2,
        1,
        2,
        6,
        1,
        6,
        5,
        0,
        4,
        7,
        0,
        7,
        3,
        3,
        7,
        6,
        3,
        6,
        2,
        0,
        1,
        5,
        0,
        5,
        4,
    ]
    cube = g.indexed_mesh("half_cube", cv, cf)
    tri = g.indexed_mesh(
        "small_triangle", [[0.5, -0.25, 0], [1.0, -0.25, 0], [0.75, 0.25, 0]], [0, 1, 2]
    )
    g.node("ground", mesh=ground)
    g.quadric_node("sphere", {"coefficients": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]})
    g.node("cube", mesh=cube, translation=[3.0, 0.0, 0.0])
    g.quadric_node(
        "cylinder",
        {
            "Q": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            "P": [0.0, 0.0, 0.0],
            "R": -0.25,
            "bounds": {"min": [-0.5, -1.0, -0.5], "max": [0.5, 1.0, 0.5]},
        },
        translation=[-3.0, 0.0, 0.0],
    )
    g.quadric_node(
        "both",
        {"coefficients": [6.25, 16.0, 16.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]},
        mesh=tri,
        translation=[0.0, 0.0, 2.5],
    )
    ang = math.atan2(3.0, 10.0)
    g.camera(
        "cam",
        0.7,
        1.5,
        rotation=[-math.sin(ang / 2), 0.0, 0.0, math.cos(ang / 2)],
        translation=[0.0, 3.0, 10.0],
    )

    def build(r: Rays, doc):
        s = math.sqrt(0.75)
        r.add("sphere", [0, 0.5, 10], [0, 0, -1], "sphere", 10 - s, [0, 0.5, s], [0, 0.5, s])
        r.add(
            "ellipsoid of 'both'",
            [0, 0, 10],
            [0, 0, -1],
            "both",
            7.25,
            [0, 0, 1],
            [0, 0, 2.75],
            kind="quadric",
        )
        r.add(
            "triangle of 'both'",
            [0.75, 0, 10],
            [0, 0, -1],
            "both",
            7.5,
            [0, 0, 1],
            [0.75, 0, 2.5],
            kind="mesh",
            prim=0,
        )
        r.add(
            "ellipsoid of 'both' from the side",
            [-5, 0, 2.5],
            [1, 0, 0],
            "both",
            4.6,
            [-1, 0, 0],
            [-0.4, 0, 2.5],
            kind="quadric",
        )
        r.add(
            "cube front face",
            [3.25, 0.125, 10],
            [0, 0, -1],
            "cube",
            9.5,
            [0, 0, 1],
            [3.25, 0.125, 0.5],
            prim=0,
        )
        r.add(
            "cylinder wall",
            [-2.7, 0, 10],
            [0, 0, -1],
            "cylinder",
            9.6,
            [0.6, 0, 0.8],
            [-2.7, 0, 0.4],
        )
        r.add(
            "down the open cylinder onto the ground",
            [-3, 5, 0],
            [0, -1, 0],
            "ground",
            6.0,
            [0, 1, 0],
            [-3, -1, 0],
        )
        r.add("ground", [1.5, 5, 1.5], [0, -1, 0], "ground", 6.0, [0, 1, 0], [1.5, -1, 1.5], prim=0)
        r.add("sphere from above", [0, 5, 0], [0, -1, 0], "sphere", 4.0, [0, 1, 0], [0, 1, 0])
        r.add("under the ground", [0, -2, 0], [0, 1, 0], "ground", 1.0, [0, 1, 0], [0, -1, 0])
        r.add("beside everything", [0, 5, 10], [0, 0, -1], None)

    # required: without the extension the sphere and the cylinder would vanish silently
    write_fixture(g, "mixed.gltf", True, build, "meshes and quadrics in one scene")


# --------------------------------------------------------------------------
# 4. far sphere

FAR_X = 6400000.0


def make_far_sphere() -> None:
    g = Gltf()
    g.quadric_node(
        "sphere",
        {"coefficients": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]},
        translation=[FAR_X, 0.0, 0.0],
    )
    s45 = math.sqrt(0.5)
    g.camera("cam", 0.5, 1.0, rotation=[0.0, s45, 0.0, s45], translation=[FAR_X + 5.0, 0.0, 0.0])

    def build(r: Rays, doc):
        r.add(
            "centre ray", [FAR_X + 5, 0, 0], [-1, 0, 0], "sphere", 4.0, [1, 0, 0], [FAR_X + 1, 0, 0]
        )
        r.add(
            "off-centre (y = 0.5)",
            [FAR_X + 5, 0.5, 0],
            [-1, 0, 0],
            "sphere",
            5 - math.sqrt(0.75),
            [math.sqrt(0.75), 0.5, 0],
            [FAR_X + math.sqrt(0.75), 0.5, 0],
        )
        r.add(
            "from the far side",
            [FAR_X - 5, 0, 0.5],
            [1, 0, 0],
            "sphere",
            5 - math.sqrt(0.75),
            [-math.sqrt(0.75), 0, 0.5],
            [FAR_X - math.sqrt(0.75), 0, 0.5],
        )
        r.add("beside", [FAR_X + 5, 1.5, 0], [-1, 0, 0], None)

    write_fixture(
        g, "far_sphere.gltf", True, build, "unit sphere at x = 6.4e6, camera 5 units away"
    )


# --------------------------------------------------------------------------
# 5. open cylinder seen through its end


def make_open_cylinder() -> None:
    g = Gltf()
    g.quadric_node(
        "tube",
        {
            "coefficients": [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            "bounds": {"min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]},
        },
    )
    g.camera("cam", 0.5, 1.0, translation=[0.0, 0.0, 5.0])

    def build(r: Rays, doc):
        r.add(
            "through the open top: near root (-1,0,2) clipped, far root inside wall",
            [-2, 0, 3],
            [1, 0, -1],
            "tube",
            3 * math.sqrt(2),
            [1, 0, 0],
            [1, 0, 0],
        )
        r.add(
            "brief's ray: (0,0,3) along (0.5,0,-1); root t = 2 lands on the rim (1,0,1)",
            [0, 0, 3],
            [0.5, 0, -1],
            "tube",
            math.sqrt(5),
            [1, 0, 0],
            [1, 0, 1],
            note="t = -2 is behind the origin; the hit lies on the clip-box face z = 1 and counts "
            "only because the box is inclusive and widened by 1e-9 (boundary case)",
        )
        r.add("outside wall", [-3, 0, 0.5], [1, 0, 0], "tube", 2.0, [-1, 0, 0], [-1, 0, 0.5])
        r.add(
            "from inside, near root behind", [0, 0, 0], [1, 0, 0], "tube", 1.0, [1, 0, 0], [1, 0, 0]
        )
        r.add("down the axis", [0, 0, 5], [0, 0, -1], None)
        r.add("above the tube, both roots clipped", [-3, 0, 1.5], [1, 0, 0], None)

    write_fixture(g, "open_cylinder_inside.gltf", True, build, "open tube x² + y² = 1, |z| ≤ 1")


# --------------------------------------------------------------------------
# 6. camera inside an ellipsoid


def make_inside_ellipsoid() -> None:
    g = Gltf()
    g.quadric_node(
        "ellipsoid", {"coefficients": [4.0, 9.0, 36.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -36.0]}
    )
    g.camera("cam", 0.5, 1.0)

    def build(r: Rays, doc):
        for axis, semi in [(0, 3.0), (1, 2.0), (2, 1.0)]:
            for sgn in (1.0, -1.0):
                d = [0.0, 0.0, 0.0]
                d[axis] = sgn
                n = list(d)
                p = [0.0, 0.0, 0.0]
                p[axis] = sgn * semi
                r.add(f"{'+-'[sgn < 0]}{'xyz'[axis]}", [0, 0, 0], d, "ellipsoid", semi, n, p)
        y = math.sqrt(32.0 / 9.0)
        r.add(
            "from (1,0,0) along +y",
            [1, 0, 0],
            [0, 1, 0],
            "ellipsoid",
            y,
            [8.0, 18 * y, 0],
            [1, y, 0],
        )

    write_fixture(
        g,
        "inside_ellipsoid.gltf",
        True,
        build,
        "x²/9 + y²/4 + z² = 1 (×36: 4x² + 9y² + 36z² − 36 = 0), camera at its centre",
    )


# --------------------------------------------------------------------------
# 7. octree boundary trap with a big quadric

TRAP_BOX = (np.array([-16.0, -16.0, -24.0]), np.array([16.0, 16.0, 8.0]))
TRAP_RAY_XY = (6.9375, 1.3125)  # exact in binary
TRAP_QUAD_Z = -8.1875


def trap_filler():
    """Tiny triangles: 4 at each corner of TRAP_BOX (fixing the scene box) and one
    small quad on a 4x4x4 lattice (so the octree subdivides)."""
    lo, hi = TRAP_BOX
    verts, faces = [], []
    for cx in (lo[0], hi[0]):
        for cy in (lo[1], hi[1]):
            for cz in (lo[2], hi[2]):
                c = np.array([cx, cy, cz])
                inward = np.sign((lo + hi) / 2 - c)
                for k in range(4):
                    e = 0.25 + 0.0625 * k
                    base = len(verts)
                    verts += [
                        c + inward * [0, 0, 0.0625 * k],
                        c + inward * [e, 0, 0.0625 * k],
                        c + inward * [0, e, 0.0625 * k],
                    ]
                    faces += [base, base + 1, base + 2]
    lattice = [-12.0, -4.0, 4.0, 12.0]
    for x in lattice:
        for y in lattice:
            for z in [-20.0, -12.0, -4.0, 4.0]:
                base = len(verts)
                verts += [
                    [x - 0.25, y - 0.25, z],
                    [x + 0.25, y - 0.25, z],
                    [x + 0.25, y + 0.25, z],
                    [x - 0.25, y + 0.25, z],
                ]
                faces += [base, base + 1, base + 2, base, base + 2, base + 3]
    return np.array(verts, float), faces


def make_trap() -> None:
    g = Gltf()
    fv, ff = trap_filler()
    filler = g.indexed_mesh("filler", fv, ff)
    x0, y0 = TRAP_RAY_XY
    e = 0.1875
    qx, qy = x0 + 0.0625, y0 - 0.0625  # quad centre: the ray misses the diagonal (prim 1)
    near = g.indexed_mesh(
        "near_quad",
        [
            [qx - e, qy - e, TRAP_QUAD_Z],
            [qx + e, qy - e, TRAP_QUAD_Z],
            [qx + e, qy + e, TRAP_QUAD_Z],
            [qx - e, qy + e, TRAP_QUAD_Z],
        ],
        [0, 1, 2, 0, 2, 3],
    )
    g.quadric_node(
        "big_sphere",
        {"coefficients": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -64.0]},
        translation=[0.0, 0.0, -12.0],
    )
    g.node("near", mesh=near)
    g.node("filler", mesh=filler)
    g.camera("cam", 0.9, 1.0, translation=[0.0, 0.0, 30.0])

    zs = -12 + math.sqrt(64 - x0 * x0 - y0 * y0)

    def build(r: Rays, doc):
        r.add(
            "trap ray",
            [x0, y0, 12],
            [0, 0, -1],
            "near",
            12 - TRAP_QUAD_Z,
            [0, 0, 1],
            [x0, y0, TRAP_QUAD_Z],
            prim=1,
        )
        r.add(
            "mirror ray (no quad)",
            [-x0, y0, 12],
            [0, 0, -1],
            "big_sphere",
            12 - zs,
            [-x0, y0, zs + 12],
            [-x0, y0, zs],
        )
        r.add(
            "sphere top",
            [0.5, 0.5, 12],
            [0, 0, -1],
            "big_sphere",
            12 - (-12 + math.sqrt(63.5)),
            [0.5, 0.5, math.sqrt(63.5)],
            [0.5, 0.5, -12 + math.sqrt(63.5)],
        )
        r.add(
            "from inside the sphere, up through the quad's spot",
            [x0, y0, -12],
            [0, 0, 1],
            "big_sphere",
            12 + zs,
            [x0, y0, zs + 12],
            [x0, y0, zs],
            note="the sphere (exit at z = %.6f) lies below the quad (z = -8.125)" % zs,
        )

    write_fixture(g, "trap_quadric.gltf", True, build, "octree boundary trap with a big sphere")
    return zs


def trap_cells(zs: float) -> list[str]:
    """For each octree depth 1..8 (cells split at centres, cubic root TRAP_BOX),
    the first cell the trap ray (down -z at TRAP_RAY_XY) visits that overlaps the
    sphere's world AABB, the first one its surface actually crosses, and the cell
    holding the quad's hit. Both sphere cells must come before the quad's cell."""
    lo, hi = TRAP_BOX
    x0, y0 = TRAP_RAY_XY
    c, rad = np.array([0.0, 0.0, -12.0]), 8.0
    out = []
    for depth in range(1, 9):
        n = 2**depth
        size = (hi - lo) / n
        ix, iy = int((x0 - lo[0]) // size[0]), int((y0 - lo[1]) // size[1])
        assert lo[0] + size[0] * ix < x0 < lo[0] + size[0] * (ix + 1)
        assert lo[1] + size[1] * iy < y0 < lo[1] + size[1] * (iy + 1)
        first_box = first_surf = None
        for iz in range(n - 1, -1, -1):  # visited top to bottom
            cmin = lo + size * [ix, iy, iz]
            cmax = cmin + size
            if first_box is None and np.all(cmax >= c - rad) and np.all(cmin <= c + rad):
                first_box = (cmin[2], cmax[2])
            near = np.clip(c, cmin, cmax)
            far = np.where(np.abs(cmin - c) > np.abs(cmax - c), cmin, cmax)
            if first_surf is None and np.linalg.norm(near - c) <= rad <= np.linalg.norm(far - c):
                first_surf = (cmin[2], cmax[2])
        qz = int((TRAP_QUAD_Z - lo[2]) // size[2])
        q = (lo[2] + size[2] * qz, lo[2] + size[2] * (qz + 1))
        assert q[0] < TRAP_QUAD_Z < q[1], depth
        assert q[1] <= first_surf[0] and q[1] <= first_box[0], depth
        out.append(
            f"| {depth} | {size[0]:g} | x [{lo[0] + size[0] * ix:g}, "
            f"{lo[0] + size[0] * (ix + 1):g}], "
            f"y [{lo[1] + size[1] * iy:g}, {lo[1] + size[1] * (iy + 1):g}] | "
            f"z [{first_box[0]:g}, {first_box[1]:g}] | z [{first_surf[0]:g}, {first_surf[1]:g}] | "
            f"z [{q[0]:g}, {q[1]:g}] |"
        )
    return out


# --------------------------------------------------------------------------
# 8. invalid files


def make_bad() -> list[tuple[str, str, str]]:
    rows = []

    def bad(
        fname: str,
        what: str,
        ext,
        message: str,
        node_props: dict | None = None,
        raw: dict[str, str] | None = None,
    ):
        doc = {
            "asset": {"version": "2.0", "generator": GENERATOR},
            "extensionsUsed": [EXT],
            "extensionsRequired": [EXT],
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [
                {
                    "name": "ok",
                    "translation": [-3.0, 0.0, 0.0],
                    "extensions": {
                        EXT: {"coefficients": [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]}
                    },
                },
                dict({"name": "bad"}, **(node_props or {}), extensions={EXT: ext}),
            ],
        }
        FILES.write_json(BAD_DIR / fname, doc, raw)
        rows.append((fname, what, message))

    unit = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]
    box = {"min": [-1.0, -1.0, -1.0], "max": [1.0, 1.0, 1.0]}
    bad(
        "quadric_both_forms.gltf",
        "`coefficients` and `Q`/`P`/`R` both given (same sphere twice)",
        {
            "coefficients": unit,
            "Q": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            "P": [0.0, 0.0, 0.0],
            "R": -1.0,
        },
        "both forms",
    )
    bad("quadric_neither_form.gltf", "only `bounds`, no surface", {"bounds": box}, "neither form")
    bad(
        "quadric_missing_r.gltf",
        "matrix form without `R`",
        {"Q": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "P": [0.0, 0.0, 0.0]},
        "missing R",
    )
    bad(
        "quadric_coefficient_count.gltf",
        "9 coefficients (J dropped)",
        {"coefficients": unit[:9]},
        "coefficients not 10 numbers",
    )
    bad(
        "quadric_nonfinite.gltf",
        "coefficient J written as the JSON number `-1e400` (parses to -inf)",
        {"coefficients": unit[:9] + ["__INF__"]},
        "non-finite number",
        raw={"__INF__": "-1e400"},
    )
    bad(
        "quadric_string_number.gltf",
        'coefficient J is the string `"-1"`',
        {"coefficients": unit[:9] + ["-1"]},
        "not a number",
    )
    bad(
        "quadric_not_symmetric.gltf",
        "Q = [[1,0.5,0],[0,1,0],[0,0,1]] (q01 ≠ q10)",
        {"Q": [1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "P": [0.0, 0.0, 0.0], "R": -1.0},
        "Q not symmetric",
    )
    bad(
        "quadric_zero_q_p.gltf",
        "Q = 0 and P = 0, R = -1 (the equation reads -1 = 0)",
        {"Q": [0.0] * 9, "P": [0.0, 0.0, 0.0], "R": -1.0, "bounds": box},
        "Q and P all zero",
    )
    bad(
        "quadric_unbounded.gltf",
        "cylinder x² + y² = 1 without `bounds`",
        {"coefficients": [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]},
        "unbounded surface needs bounds",
    )
    bad(
        "quadric_singular_transform.gltf",
        "unit sphere under node scale (1, 0, 1) (determinant 0)",
        {"coefficients": unit},
        "singular node matrix",
        node_props={"scale": [1.0, 0.0, 1.0]},
    )
    bad(
        "quadric_bounds_inverted.gltf",
        "cylinder with bounds.min z = 1 > bounds.max z = -1",
        {
            "coefficients": [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0],
            "bounds": {"min": [-1.0, -1.0, 1.0], "max": [1.0, 1.0, -1.0]},
        },
        "bounds min > max",
    )
    bad(
        "quadric_not_object.gltf",
        "the extension value is an array",
        [1.0, 1.0, 1.0],
        "not an object",
    )
    return rows


# --------------------------------------------------------------------------


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog=prog("quadric-fixtures"), description=__doc__.split("\n\n")[0].replace("\n", " ")
    )
    ap.add_argument(
        "--check-only", action="store_true", help="verify the expectations, write nothing"
    )
    ap.add_argument("--print-cells", action="store_true", help="print the trap fixture's cells")
    ap.add_argument("--print-bad", action="store_true", help="print the bad fixtures' rows")
    a = ap.parse_args(argv)
    FILES.check_only = a.check_only
    print("quadric fixtures:")
    make_spheres()
    make_families()
    make_mixed()
    make_far_sphere()
    make_open_cylinder()
    make_inside_ellipsoid()
    zs = make_trap()
    cells = trap_cells(zs)
    bad_rows = make_bad()
    FILES.write_bytes(QDIR / "expected_rays.json", (json_text(EXPECTED) + "\n").encode("utf-8"))
    if a.print_cells:
        print("\n".join(cells))
    if a.print_bad:
        for r in bad_rows:
            print(r)
    n = sum(len(v["rays"]) for v in EXPECTED.values())
    print(
        f"{len(EXPECTED)} files, {n} documented rays, all reproduced by the reference intersector"
        + (" and mpmath" if _has_mpmath() else "")
    )
    return 0


def _has_mpmath() -> bool:
    try:
        import mpmath  # noqa: F401

        return True
    except ImportError:
        return False
