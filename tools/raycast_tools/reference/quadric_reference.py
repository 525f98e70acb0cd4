"""Independent object-space reference intersector for RAYCAST_quadric glTF nodes.

Written from the formulas in shared/notes/numerics.md, sharing no code with the
Rust implementation, so that a bug has to be made twice to go unnoticed.

A quadric node carries ``extensions.RAYCAST_quadric`` in one of two forms:

* ``{"coefficients": [A, B, C, D, E, F, G, H, I, J], "bounds": {...}}`` for
  A x² + B y² + C z² + D xy + E xz + F yz + G x + H y + I z + J; the cross terms
  enter Q halved;
* ``{"Q": [9 numbers, row-major], "P": [3], "R": r, "bounds": {...}}`` for
  f(x) = xᵀ Q x + P·x + R.

``bounds`` (``{"min": [..], "max": [..]}``) is a clip box in the node's LOCAL
space; it may be omitted (then the surface is unclipped, which only makes sense
for ellipsoids).

Method, per ray and quadric node (node world matrix T = [[A, t], [0, 1]],
composed in float64 from the JSON numbers, quaternions normalised):

1. local ray: o_l = A⁻¹ (o - t), v = A⁻¹ d (d not renormalised, so the ray
   parameter t is the same in both spaces);
2. K = vᵀQv, L = 2 o_lᵀQv + P·v, M = f(o_l); the discriminant by completing the
   square, Δ = -4K f(o_l + t_c v) with t_c = -L/(2K) (exact algebra, no
   L² - 4KM cancellation); the stable roots q = -(L + sign(L)√Δ)/2, q/K, M/q,
   each refined by one Newton step on g(t) = f(o_l + t v) evaluated directly;
   K = 0 falls back to the linear root -M/L;
3. the near root, then the far root, is accepted when t > 0 and the local point
   is inside the clip box;
4. depth = t |d|; world normal = normalise(A⁻ᵀ ∇f(p_l)), ∇f = 2Qp + P (points
   toward f > 0); where the gradient vanishes (cone apex, ...) the normal is
   (0, 0, 0) and the ray is flagged ambiguous.

Ambiguity flags (the reference does not pretend to know the answer there):

* ``clip``: a root's local point lies within CLIP_REL·(largest box extent) of a
  clip-box face, so near/far root or hit/miss may flip under rounding;
* ``tangent``: the ray is near-tangent.  Measure τ: for Δ ≥ 0 the squared cosine
  between ray and surface normal at the roots, Δ / (|∇f(root)|² |v|²) (since
  g'(t) = ±√Δ there, taking the larger gradient of the two roots); for Δ < 0,
  |Δ| / (|∇f(m)|² |v|²) at the closest-approach point m = o_l + t_c v.  For a
  sphere this is (r² - b²)/r² or (b² - r²)/b² with b the impact parameter: it
  does not depend on how far the origin is.  (The plain |Δ| < 1e-6·L² test with L
  taken at the ray origin scales with the squared distance to the surface and flags every ray that
  reaches a small quadric from far away; ``tangent_L2`` keeps that measure as
  information only.)  Flagged when τ < TANGENT_REL.

A float64 path (numpy, vectorised over rays) and an mpmath path (default 100
bits, one ray at a time, for small ray counts and for testing the float64 path)
are provided.  Meshes in the same file are not handled here: pass their hits
(e.g. from trimesh) to ``merge_hits``.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from raycast_tools.cli import prog

EXT = "RAYCAST_quadric"
CLIP_REL = 1e-6
TANGENT_REL = 1e-6


# ---------------------------------------------------------------- glTF JSON


def load_gltf_json(path) -> dict:
    """The JSON header of a .gltf or .glb file (buffers are not needed here)."""
    data = Path(path).read_bytes()
    if data[:4] == b"glTF":
        # GLB: 12-byte header, then chunks (length, type, data); JSON first.
        length, ctype = struct.unpack_from("<II", data, 12)
        if ctype != 0x4E4F534A:
            raise ValueError(f"{path}: first GLB chunk is not JSON")
        return json.loads(data[20 : 20 + length].decode("utf-8"))
    return json.loads(data.decode("utf-8"))


def node_name(header: dict, index: int) -> str:
    """Object name per docs/buffers-and-cli.md: node name or node<index>."""
    name = header.get("nodes", [])[index].get("name")
    return name if name else f"node{index}"


def _quat_matrix(q):
    x, y, z, w = (float(c) for c in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n == 0.0:
        return np.eye(3)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def node_local_matrix(node: dict) -> np.ndarray:
    """4x4 float64 local matrix from `matrix` (column-major) or T·R·S."""
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T
    m = np.eye(4)
    r = _quat_matrix(node.get("rotation", [0, 0, 0, 1]))
    s = np.array(node.get("scale", [1, 1, 1]), dtype=np.float64)
    m[:3, :3] = r * s[None, :]
    m[:3, 3] = np.array(node.get("translation", [0, 0, 0]), dtype=np.float64)
    return m


def scene_index(header: dict, scene=None) -> int | None:
    scenes = header.get("scenes", [])
    if not scenes:
        return None
    if scene is None:
        return int(header.get("scene", 0))
    if isinstance(scene, int) or str(scene).isdigit():
        return int(scene)
    for i, s in enumerate(scenes):
        if s.get("name") == scene:
            return i
    raise ValueError(f"no scene named {scene!r}")


def node_world_matrices(header: dict, scene=None) -> dict[int, np.ndarray]:
    """World matrix (float64, parent @ local) of every node reachable from the scene."""
    nodes = header.get("nodes", [])
    si = scene_index(header, scene)
    roots = header["scenes"][si].get("nodes", []) if si is not None else []
    out: dict[int, np.ndarray] = {}
    stack = [(r, np.eye(4)) for r in reversed(roots)]
    while stack:
        i, parent = stack.pop()
        if i in out:  # a node reachable twice is invalid glTF; keep the first
            continue
        world = parent @ node_local_matrix(nodes[i])
        out[i] = world
        for c in reversed(nodes[i].get("children", [])):
            stack.append((c, world))
    return out


# ---------------------------------------------------------------- quadrics


def parse_quadric(ext: dict):
    """(Q 3x3, P 3, R, bmin or None, bmax or None) as float64 from the extension."""
    if "coefficients" in ext:
        a, b, c, d, e, f, g, h, i, j = (float(x) for x in ext["coefficients"])
        Q = np.array([[a, d / 2, e / 2], [d / 2, b, f / 2], [e / 2, f / 2, c]])
        P = np.array([g, h, i])
        R = j
    else:
        Q = np.array(ext["Q"], dtype=np.float64).reshape(3, 3)
        P = np.array(ext.get("P", [0, 0, 0]), dtype=np.float64)
        R = float(ext.get("R", 0.0))
    bounds = ext.get("bounds")
    if bounds is None:
        return Q, P, R, None, None
    return (
        Q,
        P,
        R,
        np.array(bounds["min"], dtype=np.float64),
        np.array(bounds["max"], dtype=np.float64),
    )


@dataclass
class Quadric:
    node: int
    name: str
    ext: dict  # the raw extension JSON (for the mpmath path)
    node_json: list  # local JSON nodes from root to this node (for the mpmath path)
    world: np.ndarray  # 4x4 float64
    Q: np.ndarray
    P: np.ndarray
    R: float
    bmin: np.ndarray | None
    bmax: np.ndarray | None
    A: np.ndarray = field(init=False)
    Ainv: np.ndarray = field(init=False)
    t: np.ndarray = field(init=False)

    def __post_init__(self):
        self.A = self.world[:3, :3].copy()
        self.t = self.world[:3, 3].copy()
        self.Ainv = np.linalg.inv(self.A)

    def f(self, p):
        """f at local points (..., 3)."""
        return np.einsum("...i,ij,...j->...", p, self.Q, p) + p @ self.P + self.R

    def grad(self, p):
        return 2.0 * p @ self.Q + self.P  # Q symmetric

    def local_bounds(self):
        """Local AABB: the clip box, or the ellipsoid's box when unclipped (else None)."""
        if self.bmin is not None:
            return self.bmin, self.bmax
        try:
            w = np.linalg.eigvalsh(self.Q)
            if not (np.all(w > 0) or np.all(w < 0)):
                return None
            Qi = np.linalg.inv(self.Q)
            c = -0.5 * Qi @ self.P
            rr = self.f(c)  # f(x) = (x-c)ᵀQ(x-c) + f(c)
            if rr * w[0] >= 0:  # empty (or a point)
                return None
            half = np.sqrt(np.abs(rr) * np.abs(np.diag(Qi)))
            return c - half, c + half
        except np.linalg.LinAlgError:
            return None

    def world_bounds(self):
        lb = self.local_bounds()
        if lb is None:
            return None
        lo, hi = lb
        corners = np.array(
            [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
        )
        w = corners @ self.A.T + self.t
        return w.min(axis=0), w.max(axis=0)


def quadrics_from_header(header: dict, scene=None) -> list[Quadric]:
    nodes = header.get("nodes", [])
    worlds = node_world_matrices(header, scene)
    parents = {}
    for i, n in enumerate(nodes):
        for c in n.get("children", []):
            parents[c] = i
    out = []
    for i in sorted(worlds):
        ext = nodes[i].get("extensions", {}).get(EXT)
        if ext is None:
            continue
        chain = [i]
        while chain[-1] in parents:
            chain.append(parents[chain[-1]])
        Q, P, R, bmin, bmax = parse_quadric(ext)
        out.append(
            Quadric(
                i,
                node_name(header, i),
                ext,
                [nodes[k] for k in reversed(chain)],
                worlds[i],
                Q,
                P,
                R,
                bmin,
                bmax,
            )
        )
    return out


def quadrics_from_gltf(path, scene=None) -> list[Quadric]:
    return quadrics_from_header(load_gltf_json(path), scene)


def has_quadrics(header: dict) -> bool:
    return any(EXT in n.get("extensions", {}) for n in header.get("nodes", []))


# ---------------------------------------------------------------- float64 path


def _box_margin(q: Quadric, p):
    """Signed distance of local points to the clip-box boundary (>0 inside); +inf unclipped."""
    if q.bmin is None:
        return np.full(p.shape[:-1], np.inf)
    return np.minimum(p - q.bmin, q.bmax - p).min(axis=-1)


def intersect_quadric(q: Quadric, origins, dirs, newton: bool = True):
    """Nearest valid hit of each ray with one quadric, float64.

    Returns a dict of arrays: t (inf = miss), depth, normal (world, unit),
    p_local, tangent (bool), clip (bool), tau, tangent_L2.
    """
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(dirs, dtype=np.float64)
    n = len(o)
    ol = (o - q.t) @ q.Ainv.T
    v = d @ q.Ainv.T
    Qv = v @ q.Q
    K = np.einsum("ij,ij->i", v, Qv)
    L = 2.0 * np.einsum("ij,ij->i", ol, Qv) + v @ q.P
    M = q.f(ol)
    scaleK = np.abs(q.Q).max() * np.einsum("ij,ij->i", v, v)
    lin = np.abs(K) <= 1e-13 * scaleK

    with np.errstate(all="ignore"):
        tc = np.where(lin, 0.0, -L / (2.0 * K))
        m = ol + tc[:, None] * v
        fm = q.f(m)
        disc = np.where(lin, L * L, -4.0 * K * fm)
        # tangency measure tau: for a hit, cos² between ray and surface normal at the
        # roots, Δ/(|∇f(root)|²|v|²) (g'(t) = ±√Δ there); for a miss, |Δ|/(|∇f(m)|²|v|²)
        # at the point of closest approach m (where g'(t) = 0)
        vv = np.einsum("ij,ij->i", v, v)
        sq0 = np.sqrt(np.maximum(disc, 0.0))
        gr2 = np.zeros(n)
        for sgn in (-1.0, 1.0):
            pr = ol + (tc + sgn * sq0 / (2.0 * np.abs(np.where(lin, 1.0, K))))[:, None] * v
            gr = q.grad(pr)
            gr2 = np.maximum(gr2, np.einsum("ij,ij->i", gr, gr))
        gm = q.grad(m)
        gm2 = np.where(disc >= 0.0, gr2, np.einsum("ij,ij->i", gm, gm)) * vv
        tau = np.where(gm2 > 0.0, np.abs(disc) / gm2, np.where(disc == 0.0, 0.0, np.inf))
        tau = np.where(lin, np.inf, tau)
        tangent_L2 = np.abs(disc) < TANGENT_REL * L * L
        sq = np.sqrt(np.maximum(disc, 0.0))
        qq = -0.5 * (L + np.copysign(sq, L))
        r1 = np.where(lin, -M / L, qq / K)
        r2 = np.where(lin, np.inf, np.where(qq == 0.0, np.where(K != 0, -L / K, np.inf), M / qq))
        has = np.where(lin, L != 0.0, disc >= 0.0)
        roots = np.stack([np.minimum(r1, r2), np.maximum(r1, r2)], axis=1)
        roots[~has] = np.nan
        if lin.any():
            roots[lin, 1] = np.nan
        if newton:
            for k in range(2):
                tk = roots[:, k]
                pk = ol + tk[:, None] * v
                g = q.f(pk)
                dg = np.einsum("ij,ij->i", q.grad(pk), v)
                step = np.where((dg != 0.0) & np.isfinite(tk), g / dg, 0.0)
                # accept only a small correction (a Newton step near a double root can jump)
                ok = np.abs(step) <= 1e-6 * np.maximum(np.abs(tk), 1e-300)
                roots[:, k] = np.where(ok, tk - step, tk)

    t = np.full(n, np.inf)
    plocal = np.full((n, 3), np.nan)
    clip = np.zeros(n, dtype=bool)
    band = CLIP_REL * (np.max(q.bmax - q.bmin) if q.bmin is not None else 0.0)
    for k in range(2):
        tk = roots[:, k]
        pk = ol + tk[:, None] * v
        marg = _box_margin(q, pk)
        fwd = np.isfinite(tk) & (tk > 0)
        clip |= fwd & (np.abs(marg) < band)
        take = fwd & (marg >= 0) & ~np.isfinite(t)
        t[take] = tk[take]
        plocal[take] = pk[take]

    hit = np.isfinite(t)
    normal = np.zeros((n, 3))
    if hit.any():
        g = q.grad(plocal[hit]) @ q.Ainv  # A⁻ᵀ ∇f, row form
        gn = np.linalg.norm(g, axis=1)
        good = gn > 0
        nn = np.zeros_like(g)
        nn[good] = g[good] / gn[good, None]
        normal[hit] = nn
        bad = np.zeros(n, dtype=bool)
        bad[np.flatnonzero(hit)[~good]] = True
        tau = np.where(bad, 0.0, tau)
    tangent = tau < TANGENT_REL
    depth = t * np.linalg.norm(d, axis=1)
    return {
        "t": t,
        "depth": depth,
        "normal": normal,
        "p_local": plocal,
        "tangent": tangent,
        "clip": clip,
        "tau": tau,
        "tangent_L2": tangent_L2,
    }


def trace(quadrics: list[Quadric], origins, dirs, newton: bool = True):
    """Nearest hit over all quadric nodes (float64).

    Returns dict: depth (inf miss), normal, node (-1 miss), name ('' miss),
    ambiguous (bool), reasons (per-ray set of strings), index (quadric index, -1 miss),
    depths_all (n, nq).
    """
    o = np.asarray(origins, dtype=np.float64)
    n = len(o)
    nq = len(quadrics)
    depth_all = np.full((n, nq), np.inf)
    normals = np.zeros((n, nq, 3))
    amb_tan = np.zeros((n, nq), dtype=bool)
    amb_clip = np.zeros((n, nq), dtype=bool)
    for k, q in enumerate(quadrics):
        r = intersect_quadric(q, o, dirs, newton=newton)
        depth_all[:, k] = r["depth"]
        normals[:, k] = r["normal"]
        amb_tan[:, k] = r["tangent"]
        amb_clip[:, k] = r["clip"]
    return _nearest(quadrics, depth_all, normals, amb_tan, amb_clip)


def _nearest(quadrics, depth_all, normals, amb_tan, amb_clip):
    n, nq = depth_all.shape
    out_depth = np.full(n, np.inf)
    out_normal = np.zeros((n, 3))
    out_node = np.full(n, -1, dtype=np.int64)
    out_index = np.full(n, -1, dtype=np.int64)
    names = np.array([""] * n, dtype=object)
    reasons = [set() for _ in range(n)]
    if nq:
        k = np.argmin(depth_all, axis=1)
        rows = np.arange(n)
        dk = depth_all[rows, k]
        hit = np.isfinite(dk)
        out_depth[hit] = dk[hit]
        out_normal[hit] = normals[rows, k][hit]
        out_index[hit] = k[hit]
        out_node[hit] = np.array([quadrics[j].node for j in k[hit]], dtype=np.int64)
        names[hit] = [quadrics[j].name for j in k[hit]]
        # a tangent or clip-face problem on any quadric that is not clearly behind the
        # nearest hit can change the answer
        near = depth_all <= (np.where(hit, dk, np.inf) * (1 + 1e-6))[:, None]
        near |= ~np.isfinite(depth_all)
        for i in np.flatnonzero((amb_tan & near).any(axis=1)):
            reasons[i].add("tangent")
        for i in np.flatnonzero((amb_clip & near).any(axis=1)):
            reasons[i].add("clip")
        if nq > 1:
            srt = np.sort(depth_all, axis=1)
            with np.errstate(invalid="ignore"):
                tie = np.isfinite(srt[:, 1]) & (srt[:, 1] - srt[:, 0] <= 1e-6 * srt[:, 0])
            for i in np.flatnonzero(tie):
                reasons[i].add("tie")
    amb = np.array([bool(r) for r in reasons], dtype=bool)
    return {
        "depth": out_depth,
        "normal": out_normal,
        "node": out_node,
        "name": names,
        "index": out_index,
        "ambiguous": amb,
        "reasons": reasons,
    }


def merge_hits(
    qres: dict, mesh_depth, mesh_normal, mesh_node, mesh_ambiguous=None, mesh_names=None
):
    """Nearest of the quadric result and mesh hits (depth inf = miss).

    Adds kind ('quadric'/'mesh'/''), and flags a tie between a quadric and a mesh
    (within 1e-6 relative depth) as ambiguous.
    """
    n = len(qres["depth"])
    md = np.asarray(mesh_depth, dtype=np.float64)
    qd = qres["depth"]
    use_mesh = md < qd
    out = {k: (v.copy() if hasattr(v, "copy") else list(v)) for k, v in qres.items()}
    out["reasons"] = [set(r) for r in qres["reasons"]]
    out["depth"] = np.where(use_mesh, md, qd)
    out["normal"] = np.where(use_mesh[:, None], mesh_normal, qres["normal"])
    out["node"] = np.where(use_mesh, mesh_node, qres["node"])
    if mesh_names is not None:
        out["name"] = np.where(use_mesh, mesh_names, qres["name"])
    kind = np.array([""] * n, dtype=object)
    kind[np.isfinite(qd) & ~use_mesh] = "quadric"
    kind[use_mesh] = "mesh"
    out["kind"] = kind
    both = np.isfinite(md) & np.isfinite(qd)
    tie = both & (np.abs(md - qd) <= 1e-6 * np.minimum(md, qd))
    for i in np.flatnonzero(tie):
        out["reasons"][i].add("tie")
    if mesh_ambiguous is not None:
        for i in np.flatnonzero(np.asarray(mesh_ambiguous) & use_mesh):
            out["reasons"][i].add("mesh")
    out["ambiguous"] = np.array([bool(r) for r in out["reasons"]], dtype=bool)
    return out


# ---------------------------------------------------------------- mpmath path


def _mp():
    import mpmath

    return mpmath


def mp_local_matrix(mp, node):
    """A node's local matrix in mpmath from its JSON numbers (matrix, or TRS with the
    quaternion normalised in mpmath; a zero quaternion is the identity)."""
    if "matrix" in node:
        m = [mp.mpf(x) for x in node["matrix"]]
        return mp.matrix([[m[c * 4 + r] for c in range(4)] for r in range(4)])
    x, y, z, w = (mp.mpf(c) for c in node.get("rotation", [0, 0, 0, 1]))
    nrm = mp.sqrt(x * x + y * y + z * z + w * w)
    if nrm != 0:
        x, y, z, w = x / nrm, y / nrm, z / nrm, w / nrm
    else:
        x, y, z, w = mp.mpf(0), mp.mpf(0), mp.mpf(0), mp.mpf(1)
    rot = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    s = [mp.mpf(c) for c in node.get("scale", [1, 1, 1])]
    tr = [mp.mpf(c) for c in node.get("translation", [0, 0, 0])]
    m = mp.eye(4)
    for r in range(3):
        for c in range(3):
            m[r, c] = rot[r][c] * s[c]
        m[r, 3] = tr[r]
    return m


def intersect_quadric_mp(q: Quadric, origin, direction, prec: int = 100, exact: bool = False):
    """One ray against one quadric with mpmath at `prec` bits, from the exact JSON inputs.

    Returns (t, depth, normal(3 floats), p_local) as floats; t = inf on a miss. With `exact`,
    the depth stays an mpmath number (not rounded to float64).
    """
    mp = _mp()
    with mp.workprec(prec):
        world = mp.eye(4)
        for nd in q.node_json:
            world = world * mp_local_matrix(mp, nd)
        A = mp.matrix([[world[r, c] for c in range(3)] for r in range(3)])
        tt = mp.matrix([world[r, 3] for r in range(3)])
        Ai = A**-1
        ext = q.ext
        if "coefficients" in ext:
            a, b, c, d, e, f, g, h, i, j = (mp.mpf(x) for x in ext["coefficients"])
            Q = mp.matrix([[a, d / 2, e / 2], [d / 2, b, f / 2], [e / 2, f / 2, c]])
            P = mp.matrix([g, h, i])
            R = j
        else:
            Q = mp.matrix(3, 3)
            for k, x in enumerate(ext["Q"]):
                Q[k // 3, k % 3] = mp.mpf(x)
            P = mp.matrix([mp.mpf(x) for x in ext.get("P", [0, 0, 0])])
            R = mp.mpf(ext.get("R", 0))
        o = mp.matrix([mp.mpf(float(x)) for x in origin])
        dd = mp.matrix([mp.mpf(float(x)) for x in direction])
        ol = Ai * (o - tt)
        v = Ai * dd

        def dot(u, w):
            return sum(u[k] * w[k] for k in range(3))

        Qv = Q * v
        K = dot(v, Qv)
        L = 2 * dot(ol, Qv) + dot(P, v)
        M = dot(ol, Q * ol) + dot(P, ol) + R
        roots = []
        if K == 0:
            if L != 0:
                roots = [-M / L]
        else:
            disc = L * L - 4 * K * M
            if disc >= 0:
                s = mp.sqrt(disc)
                roots = sorted([(-L - s) / (2 * K), (-L + s) / (2 * K)])
        for tk in roots:
            if tk <= 0:
                continue
            p = ol + tk * v
            if q.bmin is not None:
                inside = all(
                    mp.mpf(float(q.bmin[k])) <= p[k] <= mp.mpf(float(q.bmax[k])) for k in range(3)
                )
                if not inside:
                    continue
            g = 2 * (Q * p) + P
            nw = Ai.T * g
            nn = mp.sqrt(dot(nw, nw))
            normal = [float(nw[k] / nn) for k in range(3)] if nn != 0 else [0.0, 0.0, 0.0]
            dlen = mp.sqrt(dot(dd, dd))
            depth = tk * dlen if exact else float(tk * dlen)
            return float(tk), depth, normal, [float(p[k]) for k in range(3)]
        return math.inf, math.inf, [0.0, 0.0, 0.0], [math.nan] * 3


def trace_mp(quadrics: list[Quadric], origins, dirs, prec: int = 100):
    """mpmath version of `trace` (ambiguity flags taken from the float64 path)."""
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(dirs, dtype=np.float64)
    n, nq = len(o), len(quadrics)
    depth_all = np.full((n, nq), np.inf)
    normals = np.zeros((n, nq, 3))
    amb_tan = np.zeros((n, nq), dtype=bool)
    amb_clip = np.zeros((n, nq), dtype=bool)
    for k, q in enumerate(quadrics):
        r = intersect_quadric(q, o, d)
        amb_tan[:, k] = r["tangent"]
        amb_clip[:, k] = r["clip"]
        for i in range(n):
            _, dep, nrm, _ = intersect_quadric_mp(q, o[i], d[i], prec)
            depth_all[i, k] = dep
            normals[i, k] = nrm
    return _nearest(quadrics, depth_all, normals, amb_tan, amb_clip)


# ---------------------------------------------------------------- command line


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("quadric-reference"), description=__doc__.split("\n")[0])
    ap.add_argument("scene", help=".gltf/.glb with RAYCAST_quadric nodes")
    ap.add_argument("rays", help="(N,6) .npy: origin xyz, direction xyz")
    ap.add_argument("--out", help="write depth.npy, normal.npy, node.npy, ambiguous.npy here")
    ap.add_argument("--mpmath", action="store_true", help="use the mpmath path (slow)")
    ap.add_argument("--prec", type=int, default=100, help="mpmath bits (default 100)")
    ap.add_argument("--scene-index", default=None)
    a = ap.parse_args(argv)
    rays = np.load(a.rays).astype(np.float64)
    qs = quadrics_from_gltf(a.scene, a.scene_index)
    if a.mpmath:
        r = trace_mp(qs, rays[:, :3], rays[:, 3:], a.prec)
    else:
        r = trace(qs, rays[:, :3], rays[:, 3:])
    hit = np.isfinite(r["depth"])
    print(
        f"{len(qs)} quadrics, {len(rays)} rays, {int(hit.sum())} hits, "
        f"{int(r['ambiguous'].sum())} ambiguous"
    )
    if a.out:
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        np.save(out / "depth.npy", r["depth"])
        np.save(out / "normal.npy", r["normal"])
        np.save(out / "node.npy", r["node"])
        np.save(out / "ambiguous.npy", r["ambiguous"])
    return 0
