"""Tessellate RAYCAST_quadric nodes into triangles (and write them as a glTF mesh).

    python -m raycast_tools tessellate SCENE.gltf OUT.gltf [--segments N | --edge E] [--rows M]
                                      [--only NAME ...]

A quadric node (docs/RAYCAST_quadric.md) is read with quadric_reference.py
(`quadrics_from_gltf`), brought to its principal axes in the node's LOCAL space and
parametrised there, so that every generated vertex satisfies f(p) = 0 up to float64
rounding; the node's world matrix is applied afterwards in float64.

Local canonical forms (eigen-decomposition Q = U diag(w) Uᵀ, y = Uᵀ (p - c)):

| type | parametrisation (u, v) | default grid |
| --- | --- | --- |
| ellipsoid | UV sphere on the principal axes: y = a ⊙ (sinθ cosφ, sinθ sinφ, cosθ) | n around, n/2 pole to pole |
| elliptic cylinder | y = (a_i cosφ, a_j sinφ, h), h over the clip box | n around, 1 along (straight) |
| cone | y = ρ (cosφ/√|w_i|, sinφ/√|w_j|, ±1/√|w_k|), ρ from the box, both nappes | n around, 1 along (straight) |
| hyperboloid, one sheet | y = (a_i √(1+h²/a_k²) cosφ, a_j √(1+h²/a_k²) sinφ, h) | n around, rows by arc length |
| hyperboloid, two sheets | y = (a_i ρ cosφ, a_j ρ sinφ, ±a_k √(1+ρ²)) | n around, rows by arc length |
| elliptic / hyperbolic paraboloid | y_k = -(w_i y_i² + w_j y_j² + k)/p over the box's (y_i, y_j) range | n × n |
| hyperbolic cylinder | y = (±a_i √(1+s²), a_j s, h) | n along s, 1 along h |
| parabolic cylinder | y_p = -(w y_i² + k)/p, y_q free | n along y_i, 1 along y_q |
| planes (plane, plane pairs) | flat grid over the box | 1 × 1 |

The parameter ranges cover the clip box (its corners expressed in y); triangles are
then clipped to the clip box (widened by 1e-9 of its largest side, as raycast does)
with Sutherland–Hodgman in local space, so the only vertices not on the surface are
the ones created on the box faces by clipping (on a chord, off the surface by at most
the sagitta).  When a parameter line coincides with a box face (cylinders, cones and
hyperboloids in their canonical orientation: h = box z range), nothing is clipped.

Resolution: `segments` = n (around an angular parameter, or along the first
parameter), `rows` = m (along the second; default as in the table), or `edge` = a
target edge length e from which n and m are chosen by arc length (a direction whose
parameter lines are straight gets one row).  The chordal (sagitta) error of an edge
of length e on a curvature radius r is about e²/(8r); a faceted normal is off by about
e/(2r) radians.

Triangles are wound so that their geometric normal (counter-clockwise = front, in
world space) points toward f > 0, the quadric normal convention of raycast.

`write_tessellated_gltf` copies a glTF, removes the RAYCAST_quadric extension from the
tessellated nodes and adds, per tessellated quadric, a root node with the same name
carrying the mesh.  Its POSITION data are float32 offsets from an anchor (the world
image of the clip-box centre, or of the ellipsoid centre) and the node's translation is
that anchor as an exact float64 JSON number, so a surface far from the origin keeps its
precision (float32 spacing is 1.0 at 1e7).
"""  # noqa: E501 (the table)

from __future__ import annotations

import argparse
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import quadric_reference as qref
from .cli import prog
from .gltf_writer import data_uri

EIG_REL = 1e-10  # eigenvalues below this fraction of the largest count as zero
TERM_REL = 1e-9  # linear/constant terms below this of the function scale count as zero
BOX_WIDEN = 1e-9  # clip box widening, relative to its largest side (as raycast)


@dataclass
class Tessellation:
    """World-space triangles of one quadric node."""

    name: str
    kind: str
    vertices: np.ndarray  # (V, 3) float64 world
    faces: np.ndarray  # (F, 3) int64
    local: np.ndarray  # (V, 3) float64 local (node) coordinates
    anchor: np.ndarray  # (3,) world anchor (clip-box or ellipsoid centre)
    segments: int
    rows: int
    info: dict = field(default_factory=dict)

    @property
    def triangles(self) -> np.ndarray:
        """(F, 3, 3) float64 world triangles."""
        return self.vertices[self.faces]

    def max_surface_residual(self) -> float:
        """max |f(p)| / |∇f(p)| over the vertices not created by clipping (local units)."""
        return self.info.get("residual", float("nan"))


# ------------------------------------------------------------------ canonical form


@dataclass
class _Patch:
    func: callable  # (U, V) arrays -> (..., 3) y-coordinates (principal frame)
    u: np.ndarray  # parameter values (periodic ones without the repeat)
    v: np.ndarray
    u_periodic: bool = False


def _scale_of(q: qref.Quadric, lo, hi):
    """Magnitude of f's terms over the box: for the zero tests of TERM_REL."""
    ext = np.max(np.abs(np.stack([lo, hi])))
    ext = max(ext, 1.0e-300)
    return max(np.abs(q.Q).max() * ext * ext, np.abs(q.P).max() * ext, abs(q.R), 1e-300)


def _box_in_frame(bmin, bmax, c, U):
    """AABB, in y = Uᵀ(p - c) coordinates, of the local clip box."""
    corners = np.array(
        [
            [x, y, z]
            for x in (bmin[0], bmax[0])
            for y in (bmin[1], bmax[1])
            for z in (bmin[2], bmax[2])
        ]
    )
    yc = (corners - c) @ U
    return yc.min(axis=0), yc.max(axis=0)


def _angles(n):
    k = np.arange(n)
    return 2.0 * math.pi * k / n


def _canonical(q: qref.Quadric):
    """(kind, c, U, patches, straight_v) for the quadric in its principal frame."""
    Q, P, R = q.Q, q.P, q.R
    w, U = np.linalg.eigh(Q)
    wmax = np.abs(w).max()
    nz = np.abs(w) > EIG_REL * wmax if wmax > 0 else np.zeros(3, bool)
    rank = int(nz.sum())
    lb = q.local_bounds()
    if lb is None and rank < 3:
        raise ValueError(f"{q.name}: unbounded quadric without bounds")
    if lb is None:  # definite Q but empty or a point
        return "empty", np.zeros(3), np.eye(3), [], True
    bmin, bmax = lb
    scale = _scale_of(q, bmin, bmax)

    # centre in the range space of Q (least squares): c = -Q⁺ P / 2
    winv = np.where(nz, 1.0 / np.where(nz, w, 1.0), 0.0)
    c = -0.5 * (U @ (winv * (U.T @ P)))
    k = float(q.f(c))
    Pn = U.T @ P  # linear term in the principal frame; the range part is absorbed by c
    lin_null = np.where(nz, 0.0, Pn)
    ext = float(np.max(bmax - bmin))
    if np.all(np.abs(lin_null) * ext <= TERM_REL * scale):
        lin_null = np.zeros(3)
    if abs(k) <= TERM_REL * scale:
        k = 0.0
    ylo, yhi = _box_in_frame(bmin, bmax, c, U)

    def order(idx):  # permutation putting the axes idx first, in U and y
        rest = [i for i in range(3) if i not in idx]
        return list(idx) + rest

    if rank == 3:
        if k == 0.0:
            pos = np.flatnonzero(w > 0)
            neg = np.flatnonzero(w < 0)
            if len(pos) in (0, 3):
                return "point", c, U, [], True
            # two of one sign (i, j), one of the other (axis)
            ij, kk = (pos, neg[0]) if len(pos) == 2 else (neg, pos[0])
            i, j = ij
            si, sk = 1 / math.sqrt(abs(w[i])), 1 / math.sqrt(abs(w[kk]))
            rho_max = max(abs(ylo[kk]), abs(yhi[kk])) / sk
            perm = [i, j, kk]
            patches = []
            for sgn in (1.0, -1.0):

                def f(PH, RH, sgn=sgn):
                    return np.stack(
                        [RH * si * np.cos(PH), RH * si * np.sin(PH), sgn * RH * sk], axis=-1
                    )

                patches.append(_Patch(f, _angles_placeholder(), np.array([0.0, rho_max]), True))
            return "cone", c, U[:, perm], patches, True
        alpha = w / -k
        pos = np.flatnonzero(alpha > 0)
        neg = np.flatnonzero(alpha < 0)
        a = 1.0 / np.sqrt(np.abs(alpha))
        if len(pos) == 3:

            def f(PH, TH):
                st = np.where((TH == 0.0) | (TH == math.pi), 0.0, np.sin(TH))
                ct = np.where(TH == 0.0, 1.0, np.where(TH == math.pi, -1.0, np.cos(TH)))
                return np.stack(
                    [a[0] * st * np.cos(PH), a[1] * st * np.sin(PH), a[2] * ct], axis=-1
                )

            return (
                "ellipsoid",
                c,
                U,
                [_Patch(f, _angles_placeholder(), np.array([0.0, math.pi]), True)],
                False,
            )
        if len(pos) == 2:
            i, j = pos
            kk = neg[0]
            perm = [i, j, kk]
            ai, aj, ak = a[i], a[j], a[kk]

            def f(PH, H):
                r = np.sqrt(1.0 + (H / ak) ** 2)
                return np.stack([ai * r * np.cos(PH), aj * r * np.sin(PH), H], axis=-1)

            return (
                "hyperboloid_one_sheet",
                c,
                U[:, perm],
                [_Patch(f, _angles_placeholder(), np.array([ylo[kk], yhi[kk]]), True)],
                False,
            )
        if len(pos) == 1:
            kk = pos[0]
            i, j = neg
            perm = [i, j, kk]
            ai, aj, ak = a[i], a[j], a[kk]
            ymk = max(abs(ylo[kk]), abs(yhi[kk]))
            if ymk < ak:
                return "hyperboloid_two_sheets", c, U[:, perm], [], False
            rho1 = math.sqrt((ymk / ak) ** 2 - 1.0)
            rho2 = math.hypot(
                max(abs(ylo[i]), abs(yhi[i])) / ai, max(abs(ylo[j]), abs(yhi[j])) / aj
            )
            rho_max = min(rho1, rho2)
            patches = []
            for sgn in (1.0, -1.0):

                def f(PH, RH, sgn=sgn):
                    return np.stack(
                        [
                            ai * RH * np.cos(PH),
                            aj * RH * np.sin(PH),
                            sgn * ak * np.sqrt(1.0 + RH * RH),
                        ],
                        axis=-1,
                    )

                patches.append(_Patch(f, _angles_placeholder(), np.array([0.0, rho_max]), True))
            return "hyperboloid_two_sheets", c, U[:, perm], patches, False
        return "empty", c, U, [], True

    if rank == 2:
        i, j = np.flatnonzero(nz)
        kk = int(np.flatnonzero(~nz)[0])
        perm = [i, j, kk]
        Up = U[:, perm]
        if lin_null[kk] != 0.0:
            # paraboloid: w_i y_i² + w_j y_j² + p y_k + k = 0
            p = float(lin_null[kk])
            wi, wj = w[i], w[j]
            kind = "elliptic_paraboloid" if wi * wj > 0 else "hyperbolic_paraboloid"

            def f(YI, YJ):
                return np.stack([YI, YJ, -(wi * YI * YI + wj * YJ * YJ + k) / p], axis=-1)

            return (
                kind,
                c,
                Up,
                [_Patch(f, np.array([ylo[i], yhi[i]]), np.array([ylo[j], yhi[j]]))],
                False,
            )
        if k == 0.0:
            if w[i] * w[j] > 0:
                return "line", c, Up, [], True
            r = math.sqrt(abs(w[j] / w[i]))
            patches = []
            for sgn in (1.0, -1.0):

                def f(YJ, H, sgn=sgn):
                    return np.stack([sgn * r * YJ, YJ, H], axis=-1)

                patches.append(_Patch(f, np.array([ylo[j], yhi[j]]), np.array([ylo[kk], yhi[kk]])))
            return "intersecting_planes", c, Up, patches, True
        alpha = np.array([w[i], w[j]]) / -k
        if np.all(alpha > 0):
            ai, aj = 1.0 / np.sqrt(alpha)

            def f(PH, H):
                return np.stack([ai * np.cos(PH) + 0.0 * H, aj * np.sin(PH) + 0.0 * H, H], axis=-1)

            return (
                "elliptic_cylinder",
                c,
                Up,
                [_Patch(f, _angles_placeholder(), np.array([ylo[kk], yhi[kk]]), True)],
                True,
            )
        if np.all(alpha < 0):
            return "empty", c, Up, [], True
        # hyperbolic cylinder: α_a > 0 (the axis crossing the curve), α_b < 0
        ia, ib = (0, 1) if alpha[0] > 0 else (1, 0)
        axes = [perm[ia], perm[ib]]
        aa, ab = 1.0 / math.sqrt(abs(alpha[ia])), 1.0 / math.sqrt(abs(alpha[ib]))
        Up = U[:, [axes[0], axes[1], kk]]
        sb = max(abs(ylo[axes[1]]), abs(yhi[axes[1]])) / ab
        patches = []
        for sgn in (1.0, -1.0):

            def f(S, H, sgn=sgn):
                return np.stack([sgn * aa * np.sqrt(1.0 + S * S), ab * S, H], axis=-1)

            patches.append(_Patch(f, np.array([-sb, sb]), np.array([ylo[kk], yhi[kk]])))
        return "hyperbolic_cylinder", c, Up, patches, True

    if rank == 1:
        i = int(np.flatnonzero(nz)[0])
        others = [t for t in range(3) if t != i]
        g = U[:, others] @ lin_null[others]  # linear term direction (local)
        gn = float(np.linalg.norm(g))
        if gn == 0.0:
            if k == 0.0:
                roots = [0.0]
                kind = "coincident_planes"
            elif -k / w[i] > 0:
                r = math.sqrt(-k / w[i])
                roots = [r, -r]
                kind = "parallel_planes"
            else:
                return "empty", c, U, [], True
            o1, o2 = others
            Up = U[:, [i, o1, o2]]
            patches = []
            for r0 in roots:

                def f(Y1, Y2, r0=r0):
                    return np.stack([r0 + 0.0 * Y1, Y1, Y2], axis=-1)

                patches.append(
                    _Patch(f, np.array([ylo[o1], yhi[o1]]), np.array([ylo[o2], yhi[o2]]))
                )
            return kind, c, Up, patches, True
        up = g / gn
        uq = np.cross(U[:, i], up)
        Up = np.stack([U[:, i], up, uq], axis=1)
        cl = c  # y_p measured from c along up
        ylo2, yhi2 = _box_in_frame(bmin, bmax, cl, Up)
        wi = w[i]

        def f(YI, YQ):
            return np.stack([YI, -(wi * YI * YI + k) / gn + 0.0 * YQ, YQ], axis=-1)

        return (
            "parabolic_cylinder",
            cl,
            Up,
            [_Patch(f, np.array([ylo2[0], yhi2[0]]), np.array([ylo2[2], yhi2[2]]))],
            True,
        )

    # rank 0: plane P·p + R = 0
    pn = float(np.linalg.norm(P))
    nrm = P / pn
    c0 = -R / pn * nrm
    t1 = np.cross(nrm, [1.0, 0, 0] if abs(nrm[0]) < 0.9 else [0, 1.0, 0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(nrm, t1)
    Up = np.stack([nrm, t1, t2], axis=1)
    ylo2, yhi2 = _box_in_frame(bmin, bmax, c0, Up)

    def f(Y1, Y2):
        return np.stack([0.0 * Y1, Y1, Y2], axis=-1)

    return (
        "plane",
        c0,
        Up,
        [_Patch(f, np.array([ylo2[1], yhi2[1]]), np.array([ylo2[2], yhi2[2]]))],
        True,
    )


def _angles_placeholder():
    # angular parameters are laid out by _grid (n from the resolution); the range is the
    # full circle
    return np.array([0.0, 2.0 * math.pi])


# ------------------------------------------------------------------ grids


def _arc_lengths(patch: _Patch, c, U, A):
    """World arc length of the middle u-line and v-line, and whether v-lines are straight."""
    s = np.linspace(0.0, 1.0, 513)
    u0, u1 = patch.u[0], patch.u[-1]
    v0, v1 = patch.v[0], patch.v[-1]
    um, vm = 0.5 * (u0 + u1), 0.5 * (v0 + v1)

    def world(y):
        return (c + y @ U.T) @ A.T

    lu = 0.0
    for vv in (v0, vm, v1):
        pu = world(patch.func(u0 + s * (u1 - u0), np.full_like(s, vv)))
        lu = max(lu, float(np.linalg.norm(np.diff(pu, axis=0), axis=1).sum()))
    lv = 0.0
    straight = True
    for uu in (u0, um, 0.37 * u0 + 0.63 * u1):
        pv = world(patch.func(np.full_like(s, uu), v0 + s * (v1 - v0)))
        seg = float(np.linalg.norm(pv[-1] - pv[0]))
        length = float(np.linalg.norm(np.diff(pv, axis=0), axis=1).sum())
        lv = max(lv, length)
        if length > seg * (1.0 + 1e-12) + 1e-300:
            straight = False
    return lu, lv, straight


def _grid(patch: _Patch, n, m):
    """Vertices (y-coords) and quad-split faces of one patch on an n × m grid."""
    if patch.u_periodic:
        uu = patch.u[0] + (patch.u[-1] - patch.u[0]) * (np.arange(n + 1) % n) / n
    else:
        uu = patch.u[0] + (patch.u[-1] - patch.u[0]) * np.arange(n + 1) / n
        uu[-1] = patch.u[-1]
    vv = patch.v[0] + (patch.v[-1] - patch.v[0]) * np.arange(m + 1) / m
    vv[-1] = patch.v[-1]
    UU, VV = np.meshgrid(uu, vv, indexing="ij")  # (n+1, m+1)
    Y = patch.func(UU, VV).reshape(-1, 3)
    idx = np.arange((n + 1) * (m + 1)).reshape(n + 1, m + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    cc, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, cc], 1), np.stack([a, cc, d], 1)])
    return Y, faces


def _merge(V, F):
    """Merge bit-identical vertices (seams, poles, apex); drop degenerate triangles."""
    uniq, inv = np.unique(V, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    F = inv[F]
    good = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])
    return uniq, F[good]


# ------------------------------------------------------------------ clipping


def _clip_to_box(V, F, lo, hi):
    """Sutherland–Hodgman clip of triangles (local coords) to the box [lo, hi].

    Returns new (V, F, created) where `created` flags vertices made on a box face.
    """
    if len(F) == 0:
        return V, F, np.zeros(len(V), bool)
    inside_v = np.all((V >= lo) & (V <= hi), axis=1)
    keep = inside_v[F].all(axis=1)
    out_faces = [F[keep]]
    # triangles entirely beyond one face plane are dropped
    rest = np.flatnonzero(~keep)
    if len(rest):
        T = V[F[rest]]
        beyond = np.zeros(len(rest), bool)
        for ax in range(3):
            beyond |= (T[:, :, ax] < lo[ax]).all(axis=1)
            beyond |= (T[:, :, ax] > hi[ax]).all(axis=1)
        rest = rest[~beyond]
    newV = [V]
    nv = len(V)
    created = []
    tri_out = []
    for fi in rest:
        poly = [(V[j], int(j)) for j in F[fi]]
        for ax in range(3):
            for sgn, bound in ((1.0, lo[ax]), (-1.0, hi[ax])):
                if not poly:
                    break
                res = []
                for k in range(len(poly)):
                    (p, ip), (q, _) = poly[k], poly[(k + 1) % len(poly)]
                    dp, dq = sgn * (p[ax] - bound), sgn * (q[ax] - bound)
                    if dp >= 0:
                        res.append((p, ip))
                    if (dp >= 0) != (dq >= 0):
                        t = dp / (dp - dq)
                        x = p + t * (q - p)
                        x[ax] = bound
                        res.append((x, -1))
                poly = res
        if len(poly) < 3:
            continue
        ids = []
        for p, ip in poly:
            if ip < 0:
                ids.append(nv)
                newV.append(p[None])
                created.append(nv)
                nv += 1
            else:
                ids.append(ip)
        for k in range(1, len(ids) - 1):
            tri_out.append((ids[0], ids[k], ids[k + 1]))
    if tri_out:
        out_faces.append(np.array(tri_out, dtype=np.int64))
    V2 = np.concatenate(newV)
    flag = np.zeros(len(V2), bool)
    flag[created] = True
    return V2, np.concatenate(out_faces), flag


# ------------------------------------------------------------------ public API


def resolution_for_edge(q: qref.Quadric, edge: float):
    """(segments, rows) giving world edge lengths of about `edge` on quadric q."""
    kind, c, U, patches, straight = _canonical(q)
    n = m = 1
    for p in patches:
        lu, lv, st = _arc_lengths(p, c, U, q.A)
        n = max(n, int(math.ceil(lu / edge)))
        m = max(m, 1 if st else int(math.ceil(lv / edge)))
    return max(n, 3), m


def tessellate_quadric(
    q: qref.Quadric,
    segments: int | None = None,
    rows: int | None = None,
    edge: float | None = None,
    clip: bool = True,
) -> Tessellation:
    """World-space triangles of quadric node q (a quadric_reference.Quadric).

    Give either `segments` (n, around or along the first parameter; `rows` m defaults
    per type: n/2 for the ellipsoid, 1 along straight rulings, else matched to the edge
    length) or `edge` (target world edge length).
    """
    kind, c, U, patches, straight = _canonical(q)
    if edge is not None:
        n, m = resolution_for_edge(q, edge)
        if rows is not None:
            m = rows
    else:
        if segments is None:
            raise ValueError("give segments or edge")
        n = int(segments)
        if rows is not None:
            m = int(rows)
        elif kind == "ellipsoid":
            m = max(2, n // 2)
        elif straight:
            m = 1
        else:
            # match the edge length of the u direction
            m = 1
            for p in patches:
                lu, lv, st = _arc_lengths(p, c, U, q.A)
                m = max(m, 1 if st else int(math.ceil(lv / (lu / n))))
    if (
        kind in ("plane", "parallel_planes", "coincident_planes", "intersecting_planes")
        and segments is None
        and edge is None
    ):
        n = m = 1
    Vs, Fs, off = [], [], 0
    for p in patches:
        Y, Fp = _grid(p, n, m)
        Vs.append(Y)
        Fs.append(Fp + off)
        off += len(Y)
    lb = q.local_bounds()
    if not Vs or lb is None:
        z = np.zeros((0, 3))
        return Tessellation(
            q.name, kind, z, np.zeros((0, 3), np.int64), z, q.t.copy(), n, m, {"residual": 0.0}
        )
    Y = np.concatenate(Vs)
    F = np.concatenate(Fs)
    L = c + Y @ U.T  # local points, on the surface
    L, F = _merge(L, F)
    created = np.zeros(len(L), bool)
    if clip and q.bmin is not None:
        w = BOX_WIDEN * float(np.max(q.bmax - q.bmin))
        L, F, created = _clip_to_box(L, F, q.bmin - w, q.bmax + w)
        used = np.unique(F)
        remap = np.full(len(L), -1, np.int64)
        remap[used] = np.arange(len(used))
        L, created, F = L[used], created[used], remap[F]
    # residual |f|/|∇f| of the on-surface vertices (a distance, local units)
    on = ~created
    if on.any():
        g = np.linalg.norm(q.grad(L[on]), axis=1)
        res = np.abs(q.f(L[on])) / np.where(g > 0, g, 1.0)
        residual = float(res.max())
    else:
        residual = 0.0
    W = L @ q.A.T + q.t  # float64 world
    # winding: geometric normal toward f > 0 (world gradient A⁻ᵀ ∇f at the centroid)
    if len(F):
        T = W[F]
        nw = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        cl = L[F].mean(axis=1)
        gw = q.grad(cl) @ q.Ainv
        flip = np.einsum("ij,ij->i", nw, gw) < 0
        F = F.copy()
        F[flip] = F[flip][:, [0, 2, 1]]
    lo, hi = lb
    anchor = q.A @ (0.5 * (lo + hi)) + q.t
    return Tessellation(
        q.name,
        kind,
        W,
        F.astype(np.int64),
        L,
        anchor,
        n,
        m,
        {"residual": residual, "clipped_vertices": int(created.sum())},
    )


def tessellate_gltf(path, segments=None, edge=None, rows=None, only=None, scene=None):
    """Tessellations of the quadric nodes of a glTF (optionally only those named in `only`)."""
    qs = qref.quadrics_from_gltf(path, scene)
    if only is not None:
        qs = [q for q in qs if q.name in set(only)]
    return [tessellate_quadric(q, segments=segments, rows=rows, edge=edge) for q in qs]


def triangles_of(tess: list[Tessellation]) -> np.ndarray:
    """(F, 3, 3) world triangles of several tessellations, concatenated."""
    parts = [t.triangles for t in tess if len(t.faces)]
    return np.concatenate(parts) if parts else np.zeros((0, 3, 3))


def _embed_buffers(header: dict, src_dir: Path):
    for b in header.get("buffers", []):
        uri = b.get("uri")
        if uri is None or uri.startswith("data:"):
            continue
        data = (src_dir / uri).read_bytes()
        b["uri"] = data_uri(data)


def write_tessellated_gltf(
    src,
    out,
    segments=None,
    edge=None,
    rows=None,
    only=None,
    drop_other_quadrics=False,
    scene=None,
    tessellations=None,
):
    """Write `out` (.gltf + .bin beside it): `src` with its quadric nodes tessellated.

    `only`: names of the quadric nodes to tessellate (default all).  The others keep
    their RAYCAST_quadric extension, or lose it when `drop_other_quadrics` is set (then
    the output shows only the tessellated ones, plus the meshes).  Returns the list of
    Tessellation objects written.
    """
    src, out = Path(src), Path(out)
    header = qref.load_gltf_json(src)
    if src.suffix.lower() == ".glb":
        raise ValueError("GLB input is not supported here (write a .gltf first)")
    _embed_buffers(header, src.parent)
    qs = qref.quadrics_from_header(header, scene)
    sel = [q for q in qs if only is None or q.name in set(only)]
    if tessellations is None:
        tessellations = [
            tessellate_quadric(q, segments=segments, rows=rows, edge=edge) for q in sel
        ]
    nodes = header["nodes"]
    for q in qs:
        if q in sel or drop_other_quadrics:
            ext = nodes[q.node].get("extensions", {})
            ext.pop(qref.EXT, None)
            if not ext:
                nodes[q.node].pop("extensions", None)
    header.setdefault("meshes", [])
    header.setdefault("accessors", [])
    header.setdefault("bufferViews", [])
    header.setdefault("buffers", [])
    blob = bytearray()
    bidx = len(header["buffers"])
    si = qref.scene_index(header, scene) or 0
    roots = header["scenes"][si].setdefault("nodes", [])
    for t in tessellations:
        if len(t.faces) == 0:
            continue
        pos = (t.vertices - t.anchor).astype(np.float32)
        idx = t.faces.astype(np.uint32)
        views = []
        for arr, target in ((pos, 34962), (idx, 34963)):
            while len(blob) % 4:
                blob.append(0)
            views.append(len(header["bufferViews"]))
            header["bufferViews"].append(
                {
                    "buffer": bidx,
                    "byteOffset": len(blob),
                    "byteLength": arr.nbytes,
                    "target": target,
                }
            )
            blob.extend(arr.tobytes())
        a_pos = len(header["accessors"])
        header["accessors"].append(
            {
                "bufferView": views[0],
                "componentType": 5126,
                "count": len(pos),
                "type": "VEC3",
                "min": [float(x) for x in pos.min(axis=0)],
                "max": [float(x) for x in pos.max(axis=0)],
            }
        )
        header["accessors"].append(
            {
                "bufferView": views[1],
                "componentType": 5125,
                "count": int(idx.size),
                "type": "SCALAR",
            }
        )
        header["meshes"].append(
            {
                "name": f"{t.name}_tess",
                "primitives": [
                    {"attributes": {"POSITION": a_pos}, "indices": a_pos + 1, "mode": 4}
                ],
            }
        )
        nodes.append(
            {
                "name": t.name,
                "mesh": len(header["meshes"]) - 1,
                "translation": [float(x) for x in t.anchor],
                "extras": {
                    "tessellation": {
                        "kind": t.kind,
                        "segments": t.segments,
                        "rows": t.rows,
                        "triangles": int(len(t.faces)),
                    }
                },
            }
        )
        roots.append(len(nodes) - 1)
    bin_path = out.with_suffix(".bin")
    header["buffers"].append({"uri": bin_path.name, "byteLength": len(blob)})
    if not any(qref.EXT in n.get("extensions", {}) for n in nodes):
        for key in ("extensionsUsed", "extensionsRequired"):
            if key in header:
                header[key] = [e for e in header[key] if e != qref.EXT]
                if not header[key]:
                    del header[key]
    out.parent.mkdir(parents=True, exist_ok=True)
    bin_path.write_bytes(bytes(blob))
    out.write_text(json.dumps(header, indent=1))
    return tessellations


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog=prog("tessellate"), description="Tessellate RAYCAST_quadric nodes into a glTF mesh"
    )
    ap.add_argument("scene")
    ap.add_argument("out")
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--segments", type=int)
    g.add_argument("--edge", type=float)
    ap.add_argument("--rows", type=int)
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--drop-other-quadrics", action="store_true")
    a = ap.parse_args(argv)
    ts = write_tessellated_gltf(
        a.scene,
        a.out,
        segments=a.segments,
        edge=a.edge,
        rows=a.rows,
        only=a.only,
        drop_other_quadrics=a.drop_other_quadrics,
    )
    for t in ts:
        print(
            f"{t.name}: {t.kind}, {t.segments}x{t.rows}, {len(t.faces)} triangles, "
            f"max vertex residual {t.info['residual']:.1e}"
        )
    return 0
