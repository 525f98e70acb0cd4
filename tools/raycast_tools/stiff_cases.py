"""Stiff and extreme ray/quadric cases with 200-bit reference answers.

Writes ``fixtures/stiff/cases.json`` (see ``fixtures/stiff/README.md``), read by the Rust test
suite so that ``cargo test`` needs no Python.  Run from the repository root:

    .venv/bin/python -m raycast_tools stiff-cases           # rebuild, check, write
    .venv/bin/python -m raycast_tools stiff-cases --check   # rebuild and check only; fail if
                                                            # the file differs

Method (per case), all in mpmath at 200 bits on the EXACT binary values of the float64 inputs
(``mpf(float)`` is exact):

1. ``T = [[A, w], [0, 1]]`` is the object->world matrix (16 numbers, column-major as glTF).
   A singular ``A`` (``|det A| <= 1e-14 * longest column**3``, the documented rule) is an
   error case.
2. The ray goes to local space with the exact inverse: ``o_l = A^-1 (o - w)``, ``v = A^-1 d``
   (``d`` not renormalised, so the parameter ``t`` is the same in both spaces).
3. ``g(t) = f(o_l + t v) = K t^2 + L t + M`` with ``K = v.Q.v``, ``L = 2 o_l.Q.v + P.v``,
   ``M = f(o_l)``; ``K = 0`` gives the linear root ``-M/L`` (none if ``L = 0``; the whole line on
   the surface if also ``M = 0``), a zero discriminant a double root.
4. Roots in increasing order; the first with ``t > 0`` whose local point lies in the clip box
   (inclusive, NOT widened) is the hit.  ``depth = t |d|``; the world normal is
   ``normalise(A^-T grad f(p))``, ``grad f = 2 Q p + P`` (toward f > 0).

Each case also gets a first-order error estimate (``error_estimate``, relative depth) from a
perturbation model of a careful float64 implementation, used to derive or to check its bound:
see ``estimate`` below and the README.  An independent float64 numpy intersector (object space,
plain numpy, no mpmath) must agree with the reference within every non-ambiguous case's bounds.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import mpmath
import numpy as np
from mpmath import mp, mpf

from .cli import prog
from .metrics import angle
from .paths import ROOT
from .quadric_reference import parse_quadric

PREC = 200  # mpmath bits for every reference answer (set by main)

EPS = 2.0**-53  # unit roundoff of float64
SAFETY = 16.0  # derived bound = nice_up(SAFETY * first-order estimate)
CHECK_FACTOR = 2.0  # a fixed family bound must be >= CHECK_FACTOR * estimate
DERIVED_FLOOR = 1e-14  # smallest derived depth bound (about 90 ulp)
NORMAL_FLOOR = 1e-12  # smallest normal bound (radians) written
SINGULAR_DETERMINANT = 1e-14  # docs/RAYCAST_quadric.md: det below 1e-14 * longest column**3
CLIP_REL = 1e-6  # a root's local point outside the box by less than this * side is ambiguous

OUT = ROOT / "fixtures" / "stiff" / "cases.json"


# --------------------------------------------------------------------------------------------
# Small exact-ish linear algebra on lists of mpf
# --------------------------------------------------------------------------------------------


def mpv(xs):
    return [mpf(float(x)) for x in xs]


def dot(a, b):
    return mpmath.fsum(x * y for x, y in zip(a, b))


def matvec(m, v):
    return [dot(row, v) for row in m]


def transpose(m):
    return [[m[j][i] for j in range(3)] for i in range(3)]


def norm(v):
    return mpmath.sqrt(dot(v, v))


def inverse3(m):
    mm = mpmath.matrix(m)
    inv = mm**-1
    return [[inv[i, j] for j in range(3)] for i in range(3)]


def det3(m):
    return mpmath.det(mpmath.matrix(m))


def f64(x) -> float:
    return float(x)


def nice_up(x: float) -> float:
    """Round up to one significant digit (2.3e-9 -> 3e-9)."""
    if x <= 0:
        return 0.0
    e = math.floor(math.log10(x))
    m = math.ceil(x / 10.0**e - 1e-12)
    return float(f"{m}e{e}")


# --------------------------------------------------------------------------------------------
# Quadric and transform helpers (inputs as Python floats)
# --------------------------------------------------------------------------------------------


def coeffs(a=0.0, b=0.0, c=0.0, d=0.0, e=0.0, f=0.0, g=0.0, h=0.0, i=0.0, j=0.0):
    return {"coefficients": [float(x) for x in (a, b, c, d, e, f, g, h, i, j)]}


def matrices(q, p, r):
    return {"Q": [float(x) for x in q], "P": [float(x) for x in p], "R": float(r)}


def spec_qpr(quadric):
    """Exact (mpf) Q (rows), P, R from the JSON quadric."""
    if "coefficients" in quadric:
        a, b, c, d, e, f, g, h, i, j = mpv(quadric["coefficients"])
        q = [[a, d / 2, e / 2], [d / 2, b, f / 2], [e / 2, f / 2, c]]
        return q, [g, h, i], j
    qq = mpv(quadric["Q"])
    q = [[(qq[3 * r + s] + qq[3 * s + r]) / 2 for s in range(3)] for r in range(3)]
    return q, mpv(quadric["P"]), mpf(float(quadric["R"]))


def box(lo, hi):
    return [[float(x) for x in lo], [float(x) for x in hi]]


def cube(h):
    return box([-h] * 3, [h] * 3)


def world_cols(linear_rows, trans=(0.0, 0.0, 0.0)):
    """16 numbers, column-major, from a 3x3 (rows) and a translation (all floats)."""
    cols = []
    for j in range(3):
        cols += [float(linear_rows[i][j]) for i in range(3)] + [0.0]
    cols += [float(x) for x in trans] + [1.0]
    return cols


IDENTITY = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def diag(x, y, z):
    return [[float(x), 0.0, 0.0], [0.0, float(y), 0.0], [0.0, 0.0, float(z)]]


def matmul_f(a, b):
    """float64 product of two 3x3 row lists (the product IS the input; rounding is irrelevant)."""
    return [[float(sum(a[i][k] * b[k][j] for k in range(3))) for j in range(3)] for i in range(3)]


def rot_axis_angle(axis, angle):
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    x, y, z = x / n, y / n, z / n
    c, s = math.cos(angle), math.sin(angle)
    C = 1 - c
    return [
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ]


def aim(linear_rows, trans, local_target, offset):
    """(origin, dir) in world floats: a ray from world(local_target) + offset back toward
    world(local_target).  The float rounding is irrelevant: the reference uses what is stored."""
    A = np.array(linear_rows, float)
    target = A @ np.array(local_target, float) + np.array(trans, float)
    origin = target + np.array(offset, float)
    return origin.tolist(), (-np.array(offset, float)).tolist()


SPHERE = coeffs(1, 1, 1, j=-1)
CYL_Z = coeffs(1, 1, 0, j=-1)  # x^2 + y^2 = 1 around z


# --------------------------------------------------------------------------------------------
# The reference intersector (mpmath, 200 bits)
# --------------------------------------------------------------------------------------------


class Geometry:
    """Everything the reference and the error model need for one case."""

    def __init__(self, case):
        self.q, self.p, self.r = spec_qpr(case["quadric"])
        self.bounds = None
        if case["bounds"] is not None:
            self.bounds = [mpv(case["bounds"][0]), mpv(case["bounds"][1])]
        w = mpv(case["world"])
        self.lin = [[w[4 * j + i] for j in range(3)] for i in range(3)]  # rows
        self.trans = [w[12], w[13], w[14]]
        self.last_row = [w[3], w[7], w[11], w[15]]
        self.origin = mpv(case["origin"])
        self.dir = mpv(case["dir"])

    def f(self, x):
        return dot(x, matvec(self.q, x)) + dot(self.p, x) + self.r

    def grad(self, x):
        qx = matvec(self.q, x)
        return [2 * qx[i] + self.p[i] for i in range(3)]


def q_definite(q) -> bool:
    ev = mpmath.eigsy(mpmath.matrix(q))[0]
    ev = [ev[i] for i in range(3)]
    return all(e > 0 for e in ev) or all(e < 0 for e in ev)


def spec_error(g: Geometry):
    """The spec errors of docs/RAYCAST_quadric.md that a case here can have."""
    if all(x == 0 for row in g.q for x in row) and all(x == 0 for x in g.p):
        return "Q and P are all zero"
    if g.bounds is None and not q_definite(g.q):
        return "unbounded surface without bounds"
    return None


def world_error(g: Geometry):
    if g.last_row != [0, 0, 0, 1]:
        return "not affine"
    longest = max(norm([g.lin[i][j] for i in range(3)]) for j in range(3))
    if abs(det3(g.lin)) <= SINGULAR_DETERMINANT * longest**3:
        return "singular world matrix"
    return None


def roots_of(K, L, M, kscale, lscale):
    """Real roots (sorted, with multiplicity flag) of K t^2 + L t + M in mpmath.

    Returns (kind, roots): kind is 'quadratic', 'double', 'linear', 'none' or 'line'
    ('line': K = L = M = 0, the whole line lies on the surface)."""
    tiny = mpf(2) ** -170
    if abs(K) <= tiny * kscale:
        if abs(L) <= tiny * lscale:
            return ("line", []) if M == 0 else ("none", [])
        return "linear", [-M / L]
    disc = L * L - 4 * K * M
    if abs(disc) <= tiny * (L * L + abs(4 * K * M)):
        return "double", [-L / (2 * K)]
    if disc < 0:
        return "none", []
    s = mpmath.sqrt(disc)
    t1, t2 = (-L - s) / (2 * K), (-L + s) / (2 * K)
    return "quadratic", sorted([t1, t2])


def clip_excess(g: Geometry, x):
    """Largest distance by which the local point x lies outside the clip box (<= 0 inside)."""
    if g.bounds is None:
        return mpf(-1)
    lo, hi = g.bounds
    return max(max(lo[i] - x[i], x[i] - hi[i]) for i in range(3))


def reference(case):
    g = Geometry(case)
    err = spec_error(g)
    if err is not None:
        return {"error": True, "error_stage": "spec", "why": err}, None
    err = world_error(g)
    if err is not None:
        return {"error": True, "error_stage": "new", "why": err}, None
    B = inverse3(g.lin)
    ow = [g.origin[i] - g.trans[i] for i in range(3)]
    ol = matvec(B, ow)
    v = matvec(B, g.dir)
    qv = matvec(g.q, v)
    K = dot(v, qv)
    L = 2 * dot(ol, qv) + dot(g.p, v)
    M = g.f(ol)
    absq = [[abs(x) for x in row] for row in g.q]
    av = [abs(x) for x in v]
    aol = [abs(x) for x in ol]
    kscale = dot(av, matvec(absq, av))
    lscale = 2 * dot(aol, matvec(absq, av)) + dot([abs(x) for x in g.p], av)
    kind, roots = roots_of(K, L, M, kscale, lscale)
    side = None
    if g.bounds is not None:
        side = max(g.bounds[1][i] - g.bounds[0][i] for i in range(3))
    info = {
        "g": g,
        "B": B,
        "ol": ol,
        "v": v,
        "K": K,
        "L": L,
        "M": M,
        "kind": kind,
        "roots": roots,
        "side": side,
        "candidates": [],
    }
    hit = None
    for t in roots:
        x = [ol[i] + t * v[i] for i in range(3)]
        ex = clip_excess(g, x)
        info["candidates"].append((t, x, ex))
        if hit is None and t > 0 and ex <= 0:
            hit = (t, x)
    dnorm = norm(g.dir)
    if hit is None:
        return {"error": False, "hit": False, "t": None, "depth": None, "normal": None}, info
    t, x = hit
    grad = g.grad(x)
    nw = matvec(transpose(B), grad)
    nn = norm(nw)
    normal = None if nn == 0 else [f64(c / nn) for c in nw]
    info["hit"] = hit
    info["grad"] = grad
    return {
        "error": False,
        "hit": True,
        "t": f64(t),
        "depth": f64(t * dnorm),
        "normal": normal,
    }, info


# --------------------------------------------------------------------------------------------
# First-order error model of a careful float64 implementation
# --------------------------------------------------------------------------------------------


def local_anchor(g: Geometry):
    if g.bounds is not None:
        return [(g.bounds[0][i] + g.bounds[1][i]) / 2 for i in range(3)]
    qi = inverse3(g.q)
    return [-x / 2 for x in matvec(qi, g.p)]


def perturbation(info, t):
    """(delta_g, delta_p_vec): an absolute perturbation of g(t) = f(o_l + t v) and a
    componentwise (local-coordinate) perturbation of the point, for a careful float64
    implementation that works about an anchor c (clip-box centre / ellipsoid centre).

    Componentwise first-order model (|.| entrywise, eps = 2^-53), each rounding dropped when it
    is exact for these inputs (exactly representable inverse, exact difference or product):
    * inverse:    |dB| <= eps (|B||A||B| + |B|)       (componentwise inverse bound + storing B)
    * start:      |B| (eps |o - c_w| + |round(c_w) - c_w|) + |dB| |o - c_w|
    * direction:  |dB| |d|, plus eps |B||d| for the product
    * the point:  eps (|o_l - c| + t |v|)             (forming o_l + t v, in any implementation)
    * coefficients about c: eps (|p-c|.|Q|.|p-c| + |2Qc+P|.|p-c| + |c|.|Q|.|c| + |P|.|c| + |R|)
    delta_g = |grad f(p)| . delta_p_vec + coefficient term."""
    g = info["g"]
    c = local_anchor(g)
    ol, v, B = info["ol"], info["v"], info["B"]

    def is_float(vec):
        return all(mpf(f64(x)) == x for x in vec)

    def fl(vec):
        return np.array([abs(f64(x)) for x in vec])

    absA = np.array([[abs(f64(x)) for x in row] for row in g.lin])
    absB = np.array([[abs(f64(x)) for x in row] for row in B])
    b_exact = all(is_float(row) for row in B)
    dB = np.zeros((3, 3)) if b_exact else EPS * (absB @ absA @ absB + absB)
    cw = [dot(g.lin[i], c) + g.trans[i] for i in range(3)]
    cw_f = [mpf(f64(x)) for x in cw]
    cw_round = fl([cw[i] - cw_f[i] for i in range(3)])
    diff = [g.origin[i] - cw_f[i] for i in range(3)]
    e_diff = np.zeros(3) if is_float(diff) else EPS * fl(diff)
    ldiff = matvec(B, diff)
    e_prod = np.zeros(3) if (b_exact and is_float(ldiff)) else EPS * (absB @ fl(diff))
    delta_o = absB @ (e_diff + cw_round) + dB @ fl(diff) + e_prod
    e_vprod = np.zeros(3) if (b_exact and is_float(v)) else EPS * (absB @ fl(g.dir))
    delta_v = dB @ fl(g.dir) + e_vprod
    tf = abs(float(t))
    x = [ol[i] + t * v[i] for i in range(3)]
    point_round = EPS * (fl([ol[i] - c[i] for i in range(3)]) + tf * fl(v))
    delta_p = delta_o + tf * delta_v + point_round
    pc = [abs(x[i] - c[i]) for i in range(3)]
    absq = [[abs(e) for e in row] for row in g.q]
    ac = [abs(e) for e in c]
    pprime = [abs(2 * dot(g.q[i], c) + g.p[i]) for i in range(3)]
    coef = (
        dot(pc, matvec(absq, pc))
        + dot(pprime, pc)
        + dot(ac, matvec(absq, ac))
        + dot([abs(e) for e in g.p], ac)
        + abs(g.r)
    )
    grad = g.grad(x)
    delta_g = float(fl(grad) @ delta_p) + EPS * float(coef)
    return delta_g, delta_p


def estimate(info, robust_double=False):
    """First-order relative depth error, relative normal angle error, and flags.

    Simple root:   dt = delta_g / |g'(t)|       (g'(t) = +-sqrt(disc), or L for K = 0)
    Double root:   dt = sqrt(delta_g / |K|) + |delta_p| / |v|
    A simple root is 'near-double' when SAFETY * delta_g * 4 |K| >= g'(t)^2 (the perturbed
    polynomial may lose it): such a case must be flagged ambiguous."""
    out = {"tangent": False, "near_zero_t": False, "clip_edge": False, "miss_margin": None}
    g, v = info["g"], info["v"]
    dv = float(norm(v))
    K = info["K"]
    # clip-edge: any real root whose point lies just outside the box
    if info["side"] is not None:
        for t, x, ex in info["candidates"]:
            if 0 < ex <= CLIP_REL * info["side"]:
                out["clip_edge"] = True
    hit = info.get("hit")
    if hit is None:
        # miss: how far is the ray from meeting the surface?  Look at the extremum of g.
        if info["kind"] in ("none",) and K != 0:
            tc = -info["L"] / (2 * K)
            gmin = K * tc * tc + info["L"] * tc + info["M"]
            dg, _ = perturbation(info, tc)
            out["miss_margin"] = float(abs(gmin) / (SAFETY * dg)) if dg > 0 else float("inf")
            if abs(gmin) <= SAFETY * dg:
                out["tangent"] = True
        for t, x, ex in info["candidates"]:
            dg, dpv = perturbation(info, t)
            if abs(t) * dv <= SAFETY * float(np.linalg.norm(dpv)):
                out["near_zero_t"] = True
        return None, None, out
    t, x = hit
    dg, dpv = perturbation(info, t)
    dp = float(np.linalg.norm(dpv))
    kind = info["kind"]
    if kind == "double":
        dt = math.sqrt(dg / abs(float(K))) + dp / dv
        out["tangent"] = not robust_double
    else:
        gp = abs(float(2 * K * t + info["L"]))
        if gp == 0:
            dt = float("inf")
            out["tangent"] = True
        else:
            dt = dg / gp  # >= dp/|v| already: |g'| <= |grad f| |v|
            if SAFETY * dg * 4 * abs(float(K)) >= gp * gp:
                out["tangent"] = True
                dt = max(dt, math.sqrt(dg / abs(float(K))) + dp / dv)
    if abs(float(t)) * dv <= SAFETY * dp:
        out["near_zero_t"] = True
    rel = dt / float(t) + 2 * EPS  # + rounding of |d|
    grad = info["grad"]
    ng = float(norm(grad))
    if ng == 0:
        nerr = None
    else:
        # componentwise local position error (inputs, rounding of the point, root error along
        # v); the local gradient error is 2 |Q| times it; the world normal is B^T grad f, whose
        # own rounding adds eps |B^T| |grad f|.
        B = info["B"]
        absBT = np.array([[abs(f64(B[j][i])) for j in range(3)] for i in range(3)])
        dvec = dpv + dt * np.array([abs(f64(e)) for e in v])
        absq = np.array([[abs(f64(e)) for e in row] for row in g.q])
        dgrad = 2 * absq @ dvec
        gabs = np.array([abs(f64(e)) for e in grad])
        nw = float(norm(matvec(transpose(B), grad)))
        nerr = float(np.linalg.norm(absBT @ (dgrad + EPS * gabs) + EPS * absBT @ gabs)) / nw

    return rel, nerr, out


# --------------------------------------------------------------------------------------------
# Independent float64 check (numpy, object space)
# --------------------------------------------------------------------------------------------


def numpy_intersect(case):
    """Plain float64: returns ('error',), ('miss',) or ('hit', t, depth, normal)."""
    Q, P, R, _, _ = parse_quadric(case["quadric"])
    Q = (Q + Q.T) / 2
    if not Q.any() and not P.any():
        return ("error",)
    if case["bounds"] is None:
        ev = np.linalg.eigvalsh(Q)
        if not (np.all(ev > 0) or np.all(ev < 0)):
            return ("error",)
    W = np.array(case["world"]).reshape(4, 4).T  # column-major -> matrix
    A, w = W[:3, :3], W[:3, 3]
    longest = max(np.linalg.norm(A[:, k]) for k in range(3))
    if abs(np.linalg.det(A)) <= SINGULAR_DETERMINANT * longest**3:
        return ("error",)
    B = np.linalg.inv(A)
    o = np.array(case["origin"])
    dw = np.array(case["dir"])
    ol = B @ (o - w)
    v = B @ dw
    K = v @ Q @ v
    L = 2 * ol @ Q @ v + P @ v
    M = ol @ Q @ ol + P @ ol + R
    kscale = np.abs(v) @ np.abs(Q) @ np.abs(v)
    lscale = 2 * np.abs(ol) @ np.abs(Q) @ np.abs(v) + np.abs(P) @ np.abs(v)
    roots = []
    if abs(K) <= 1e-13 * kscale:
        if abs(L) > 1e-13 * lscale:
            roots = [-M / L]
    else:
        tc = -L / (2 * K)
        m = ol + tc * v
        disc = -4 * K * (m @ Q @ m + P @ m + R)  # completed square
        if disc >= 0:
            s = math.sqrt(disc)
            qq = -0.5 * (L + math.copysign(s, L))
            if qq == 0:
                roots = [tc]
            else:
                roots = sorted([qq / K, M / qq])
    if case["bounds"] is not None:
        lo, hi = np.array(case["bounds"][0]), np.array(case["bounds"][1])
        pad = 1e-9 * float(np.max(hi - lo))
        lo, hi = lo - pad, hi + pad
    for t in roots:
        if not t > 0:
            continue
        x = ol + t * v
        if case["bounds"] is not None and not (np.all(x >= lo) and np.all(x <= hi)):
            continue
        n = B.T @ (2 * Q @ x + P)
        nn = np.linalg.norm(n)
        normal = n / nn if nn > 0 else None
        return ("hit", t, t * np.linalg.norm(dw), normal)
    return ("miss",)


# --------------------------------------------------------------------------------------------
# The cases
# --------------------------------------------------------------------------------------------

CASES: list[dict] = []


def add(
    name,
    family,
    description,
    quadric,
    bounds,
    world,
    origin,
    direction,
    *,
    bound=None,
    reason=None,
    ambiguous=False,
    ambiguous_kind=None,
    extra=None,
    robust_double=False,
    check_factor=CHECK_FACTOR,
):
    """bound=None: derive rel_depth_bound from the error model (SAFETY * estimate)."""
    case = {
        "name": name,
        "family": family,
        "description": description,
        "quadric": quadric,
        "bounds": bounds,
        "world": world,
        "origin": [float(x) for x in origin],
        "dir": [float(x) for x in direction],
        "_bound": bound,
        "_reason": reason,
        "ambiguous": ambiguous,
        "ambiguous_kind": ambiguous_kind,
        "same_depth_as": None,
        "depth_ratio": None,
        "_robust_double": robust_double,
        "_check_factor": check_factor,
    }
    if extra:
        case.update(extra)
    CASES.append(case)


# fmt: off
# (the case table keeps its hand layout, one entry per few lines)
def build_cases():
    identity = world_cols(IDENTITY)

    # ---- 1. exact binary scaling by 2^k ---------------------------------------------------
    base_sphere_c = (0.25, 0.5, -0.75)
    base_sphere_o = (0.75, 0.375, 63.0)
    base_sphere_d = (-0.0078125, 0.001953125, -1.0)
    base_cyl_t = (-1.5, 0.25, 0.5)
    base_cyl_o = (-2.125, -80.0, 0.75)
    base_cyl_d = (0.0078125, 1.0, 0.00390625)
    for k in (0, -20, -7, 3, 30):
        s = 2.0 ** k
        tag = f"2^{k}"
        why = ("the scene (world matrix and ray origin) is multiplied by an exact power of two, so "
               "the exact depth scales exactly (the float inputs are exact multiples); 1e-15 "
               "(4.5 ulp) is twice the first-order error estimate of this near-head-on hit "
               "63-80 units away (error_estimate, about 4.5e-16).")
        add(f"scale2k_sphere_k{k}", "scale_pow2",
            f"unit sphere at {base_sphere_c}, camera 63 units away, whole scene scaled by {tag}",
            SPHERE, None, world_cols(diag(s, s, s), [s * c for c in base_sphere_c]),
            [s * c for c in base_sphere_o], base_sphere_d, bound=1e-15, reason=why,
            extra={"same_depth_as": None if k == 0 else "scale2k_sphere_k0",
                   "depth_ratio": None if k == 0 else s})
        add(f"scale2k_cylinder_k{k}", "scale_pow2",
            f"clipped cylinder x^2+y^2=1, |z|<=2, at {base_cyl_t}, camera 80 units away, "
            f"whole scene scaled by {tag}",
            CYL_Z, box([-1, -1, -2], [1, 1, 2]),
            world_cols(diag(s, s, s), [s * c for c in base_cyl_t]),
            [s * c for c in base_cyl_o], base_cyl_d, bound=1e-15, reason=why,
            extra={"same_depth_as": None if k == 0 else "scale2k_cylinder_k0",
                   "depth_ratio": None if k == 0 else s})

    # ---- 2. decade scaling 1e-6 .. 1e6 ----------------------------------------------------
    for e in range(-6, 7):
        s = float(f"1e{e}")
        why = ("uniform scale by a decade (inexact in binary) of a well-conditioned hit; the "
               "first-order error is a few ulp, 1e-12 leaves a wide margin for rounding of the "
               "scaled matrix and its inverse.")
        add(f"decade_sphere_1e{e}", "scale_decade",
            f"unit sphere at (0.3,-0.2,0.1)*s, camera at (0.5,0.4,8)*s looking along -z, s=1e{e}",
            SPHERE, None, world_cols(diag(s, s, s), [0.3 * s, -0.2 * s, 0.1 * s]),
            [0.5 * s, 0.4 * s, 8.0 * s], [-0.01, 0.02, -1.0], bound=1e-12, reason=why,
            )
    for e in (-6, -3, 3, 6):
        s = float(f"1e{e}")
        add(f"decade_cylinder_1e{e}", "scale_decade",
            f"cylinder x^2+y^2=1, |z|<=1.5 rotated about x by 0.4 rad, scaled by 1e{e}, side view",
            CYL_Z, box([-1, -1, -1.5], [1, 1, 1.5]),
            world_cols([[s * x for x in row] for row in rot_axis_angle((1, 0, 0), 0.4)],
                       [0.1 * s, 0.2 * s, 0.3 * s]),
            [6.0 * s, 0.45 * s, 0.5 * s], [-1.0, 0.03, -0.02], bound=1e-12,
            reason="uniform decade scale of a rotated, well-conditioned cylinder hit; 1e-12 is far "
                   "above the few-ulp first-order error.")

    # ---- 3. far translations with non-integer offsets ---------------------------------------
    for e in (3, 5, 7):
        big = float(f"1e{e}")
        c = (big + 0.1, 0.5 * big - 0.3, -big + 0.7)
        add(f"translated_sphere_1e{e}", "translated",
            f"unit sphere centred at ({big:g}+0.1, {big / 2:g}-0.3, -{big:g}+0.7), camera 5 units "
            "away, oblique ray",
            SPHERE, None, world_cols(IDENTITY, c),
            (c[0] + 0.3, c[1] - 0.2, c[2] + 5.0), (-0.05, 0.03, -1.0), bound=1e-9,
            reason="world coordinates of size 1e{0} carry an absolute rounding of about "
                   "1e{0}*1.1e-16 in any anchor difference; over a 4-unit depth that is at most "
                   "about 2e-10 relative at 1e7, below 1e-9.".format(e))
        add(f"translated_cylinder_1e{e}", "translated",
            "cylinder x^2+y^2=0.25 (radius 0.5), box [-0.6,-0.5,-1.2]..[0.8,0.5,0.8] (centre "
            "(0.1,0,-0.2), off the origin), "
            f"node at ({big:g}+0.1, -{big:g}+0.1, {big / 4:g}+0.1), side view from 5 units",
            coeffs(4, 4, 0, j=-1), box([-0.6, -0.5, -1.2], [0.8, 0.5, 0.8]),
            world_cols(IDENTITY, (big + 0.1, -big + 0.1, big / 4 + 0.1)),
            (big + 0.1 - 5.0, -big + 0.1 + 0.1, big / 4 + 0.1 - 0.3), (1.0, 0.01, 0.02),
            bound=1e-9,
            reason="the clip-box centre's world image is rounded at 1e{0} (half an ulp, "
                   "about 1e{0}*1.1e-16) and every local coordinate inherits it; over a 4.5-unit "
                   "depth this stays below 1e-9 relative.".format(e))

    # ---- 4. small spheres far away, near the silhouette -------------------------------------
    r = 1e-3
    for idx, (cen, o_off, dvec) in enumerate([
        ((0.0, 0.0, 0.0), (-1e4, 0.999e-3, 0.0), (1.0, 0.0, 0.0)),
        ((1e4, 2e4, -3e4), (0.0, 0.0, 1e4), None),
        ((0.5, -0.25, 0.125), (7e3, -7e3, 2e3), None),
        ((-3.0, 2.0, 1e4), (0.0, 1e4, 0.0), None),
    ]):
        centre = np.array(cen)
        origin = centre + np.array(o_off)
        if dvec is None:
            # aim at a point 0.999 r off the centre, perpendicular to the line of sight
            to_c = centre - origin
            to_c = to_c / np.linalg.norm(to_c)
            perp = np.cross(to_c, [0.3, 0.5, 0.8])
            perp /= np.linalg.norm(perp)
            aim_point = centre + 0.999 * r * perp
            dvec = aim_point - origin
            dvec = dvec / np.linalg.norm(dvec)
        add(f"small_far_sphere_{idx}", "small_far",
            f"sphere r=1e-3 at {cen} seen from about 1e4 away, impact parameter about 0.999 r "
            "(grazing: cos of incidence about 0.045)",
            coeffs(1, 1, 1, j=-1e-6), None, world_cols(IDENTITY, cen), origin.tolist(),
            dvec.tolist() if isinstance(dvec, np.ndarray) else dvec,
            reason=None)

    # ---- 5. exactly tangent rays (ambiguous) ------------------------------------------------
    tangents = [
        ("tangent_sphere_y1", "unit sphere, ray along +x at y = 1 exactly", SPHERE, None, identity,
         (-5.0, 1.0, 0.0), (1.0, 0.0, 0.0)),
        ("tangent_sphere_z1_far", "unit sphere at (100.5,0,0), ray along -y at z = 1 from 1e3",
         SPHERE, None, world_cols(IDENTITY, (100.5, 0.0, 0.0)), (100.5, 1e3, 1.0),
         (0.0, -1.0, 0.0)),
        ("tangent_ellipsoid", "ellipsoid x^2/4+y^2+z^2/16=1, ray along +z at x = 2 exactly",
         coeffs(0.25, 1, 0.0625, j=-1), None, identity, (2.0, 0.0, -10.0), (0.0, 0.0, 1.0)),
        ("tangent_cylinder", "cylinder x^2+y^2=1 |z|<=2, ray along -y at x = 1 exactly",
         CYL_Z, box([-1, -1, -2], [1, 1, 2]), identity, (1.0, 5.0, 0.5), (0.0, -1.0, 0.0)),
    ]
    for name, desc, qd, bd, wd, o, d in tangents:
        add(name, "tangent_exact", desc, qd, bd, wd, o, d, ambiguous=True,
            ambiguous_kind="tangent", reason=None)

    # ---- 6. near tangency, inside (hit) and outside (miss) ----------------------------------
    for delta, tag in ((1e-3, "1e-3"), (1e-5, "1e-5"), (1e-7, "1e-7")):
        add(f"near_tangent_in_{tag}", "near_tangent",
            f"unit sphere, ray along +x from x=-5 at y = 1 - {tag} (hits, chord half-length "
            f"sqrt(2*{tag}))", SPHERE, None, identity, (-5.0, 1.0 - delta, 0.0), (1.0, 0.0, 0.0))
        add(f"near_tangent_out_{tag}", "near_tangent",
            f"unit sphere, ray along +x from x=-5 at y = 1 + {tag}: misses by {tag}",
            SPHERE, None, identity, (-5.0, 1.0 + delta, 0.0), (1.0, 0.0, 0.0))
    rot = rot_axis_angle((0.2, 0.3, 0.9), 0.7)
    for sign, tag in ((-1, "in"), (1, "out")):
        # cylinder rotated: world ray built in local space then mapped with the float matrix
        lo = np.array([1.0 + sign * 1e-7, -4.0, 0.3])
        ld = np.array([0.0, 1.0, 0.0])
        Rm = np.array(rot)
        add(f"near_tangent_cylinder_{tag}_1e-7", "near_tangent",
            f"cylinder x^2+y^2=1 |z|<=2, rotated 0.7 rad about (0.2,0.3,0.9), translated; ray "
            f"parallel to local y at local x = 1 {'-' if sign < 0 else '+'} 1e-7",
            CYL_Z, box([-1, -1, -2], [1, 1, 2]), world_cols(rot, (3.0, -2.0, 1.0)),
            (Rm @ lo + np.array([3.0, -2.0, 1.0])).tolist(), (Rm @ ld).tolist())

    # ---- 7. camera inside ---------------------------------------------------------------------
    ell = coeffs(1 / 9, 0.25, 1, j=-1)  # semi-axes 3, 2, 1
    add("inside_ellipsoid_a", "inside", "camera at the centre of ellipsoid (3,2,1), oblique ray: "
        "exits through the far wall; normal points outward (f > 0), i.e. along the ray",
        ell, None, identity, (0.0, 0.0, 0.0), (0.6, -0.3, 0.2), bound=1e-9,
        reason="well-conditioned exit root (only one positive root, steep incidence); 1e-9 is the "
               "default bound for well-conditioned cases.")
    add("inside_ellipsoid_b", "inside", "camera inside a rotated, translated ellipsoid (3,2,1), "
        "off-centre", ell, None, world_cols(rot_axis_angle((1, 1, 0), 1.1), (10.0, -20.0, 5.0)),
        (10.5, -19.7, 5.2), (-0.2, 0.9, -0.1), bound=1e-9,
        reason="well-conditioned exit root; default 1e-9.")
    add("inside_cylinder_wall", "inside", "camera inside cylinder x^2+y^2=1 |z|<=2, ray hits the "
        "inside wall at |z| < 2; normal points outward (away from the axis)",
        CYL_Z, box([-1, -1, -2], [1, 1, 2]), identity, (0.2, 0.1, 0.5), (1.0, 0.3, 0.2), bound=1e-9,
        reason="well-conditioned exit root; default 1e-9.")
    add("inside_cylinder_open_end", "inside", "camera inside cylinder x^2+y^2=1 |z|<=2, ray "
        "leaves through the open top (wall crossing at z > 2 is clipped): miss",
        CYL_Z, box([-1, -1, -2], [1, 1, 2]), identity, (0.2, 0.1, 0.5), (0.3, 0.1, 1.0), bound=1e-9,
        reason="the only positive root lies well outside the clip box (z about 3.3): robust miss.")
    add("outside_through_open_end", "inside", "camera above and beside an open cylinder "
        "x^2+y^2=1 |z|<=1: the near wall crossing (z=2) is clipped, the far root (inside wall, "
        "z=0) is the hit", CYL_Z, box([-1, -1, -1], [1, 1, 1]), identity, (-3.0, 0.0, 4.0),
        (1.0, 0.0, -1.0), bound=1e-9,
        reason="near root clipped by a wide margin, far root well-conditioned; default 1e-9.")

    # ---- 8. rays along / nearly along a cylinder axis ----------------------------------------
    tall = box([-1, -1, -1e9], [1, 1, 1e9])
    add("axis_on_axis", "cylinder_axis", "ray along the axis of x^2+y^2=1 (K = L = 0, M = -1): "
        "never meets the surface", CYL_Z, tall, identity, (0.0, 0.0, -5.0), (0.0, 0.0, 1.0),
        bound=1e-9, reason="K = L = 0 exactly and M = -1: no root at all; robust miss.")
    add("axis_parallel_inside", "cylinder_axis", "ray parallel to the axis at radius 0.5: miss",
        CYL_Z, tall, identity, (0.5, 0.0, -5.0), (0.0, 0.0, 1.0), bound=1e-9,
        reason="K = L = 0 exactly, M = -0.75: robust miss.")
    add("axis_parallel_outside", "cylinder_axis", "ray parallel to the axis at radius 2: miss",
        CYL_Z, tall, identity, (2.0, 0.0, -5.0), (0.0, 0.0, 1.0), bound=1e-9,
        reason="K = L = 0 exactly, M = 3: robust miss.")
    add("axis_parallel_on_surface", "cylinder_axis", "ray parallel to the axis at radius 1: the "
        "whole ray lies on the surface (K = L = M = 0); any answer accepted",
        CYL_Z, tall, identity, (1.0, 0.0, -5.0), (0.0, 0.0, 1.0), ambiguous=True,
        ambiguous_kind="on_surface",
        reason="the ray lies in the surface: every t > 0 is a root, hit or miss both acceptable.")
    add("axis_tilt_1e-8", "cylinder_axis", "ray from the axis tilted by 1e-8 (dir (1e-8,0,1)): "
        "meets x = 1 at t = 1e8, z about 1e8 inside |z| <= 1e9",
        CYL_Z, tall, identity, (0.0, 0.0, -5.0), (1e-8, 0.0, 1.0), bound=1e-9,
        reason="t = 1/1e-8 depends only on the transverse component, known to relative 1e-16 "
               "under an identity transform; default 1e-9.")
    add("axis_tilt_1e-8_offaxis", "cylinder_axis", "ray from (0.5,0.25,-5) with dir "
        "(1e-8,2e-8,1): hits far up the tube (t about 3.9e7)",
        CYL_Z, tall, identity, (0.5, 0.25, -5.0), (1e-8, 2e-8, 1.0), bound=1e-9,
        reason="K = 5e-16 exactly scaled, root relative condition about 1; default 1e-9.")
    Rt = rot_axis_angle((0.3, -0.5, 0.2), 0.9)
    Rn = np.array(Rt)
    add("axis_tilt_1e-8_rotated", "cylinder_axis", "as axis_tilt_1e-8 but the tube is rotated: "
        "the 1e-8 transverse direction now comes out of a rounded inverse",
        CYL_Z, tall, world_cols(Rt), (Rn @ [0.0, 0.0, -5.0]).tolist(),
        (Rn @ [1e-8, 0.0, 1.0]).tolist(),
        reason=None)

    # ---- 9. paraboloid along its axis (K = 0) -----------------------------------------------
    parab = coeffs(1, 1, 0, i=-1)  # x^2 + y^2 - z
    pb = box([-3, -3, -1], [3, 3, 9])
    add("paraboloid_vertex", "paraboloid_axis", "z = x^2+y^2 (f = x^2+y^2-z), from (0,0,5) along "
        "-z: linear case K = 0, hits the vertex at t = 5, normal (0,0,-1)", parab, pb, identity,
        (0.0, 0.0, 5.0), (0.0, 0.0, -1.0), bound=1e-9,
        reason="linear root -M/L with L = 1: exact; default 1e-9.")
    add("paraboloid_offaxis", "paraboloid_axis", "z = x^2+y^2 from (0.5,0,5) along -z: hits z = "
        "0.25 at t = 4.75, normal (1,0,-1)/sqrt2", parab, pb, identity, (0.5, 0.0, 5.0),
        (0.0, 0.0, -1.0), bound=1e-9,
        reason="linear root, exact in binary; default 1e-9.")
    add("paraboloid_axis_scaled_dir", "paraboloid_axis",
        "as paraboloid_offaxis with dir (0,0,-1e3) "
        "and a rotated, translated node", parab, pb,
        world_cols(rot_axis_angle((1, 2, 3), 0.5), (1.0, 2.0, 3.0)),
        (np.array(rot_axis_angle((1, 2, 3), 0.5)) @ [0.5, 0.0, 5.0] + [1.0, 2.0, 3.0]).tolist(),
        (np.array(rot_axis_angle((1, 2, 3), 0.5)) @ [0.0, 0.0, -1e3]).tolist(), bound=1e-9,
        reason="K is zero only to rounding of the rotated direction (|K| ~ 1e-16 K-scale, far "
               "below 1e-13) and the root is well-conditioned; default 1e-9.")

    # ---- 10. cone apex ------------------------------------------------------------------------
    cone = coeffs(1, 1, -1)
    cb = cube(1.0)
    add("cone_apex_axis", "cone_apex", "cone x^2+y^2-z^2=0 |z|<=1, ray along -z through the apex "
        "(double root t = 5, zero gradient: any unit normal)", cone, cb, identity, (0.0, 0.0, 5.0),
        (0.0, 0.0, -1.0), robust_double=True, reason=None)
    add("cone_apex_oblique", "cone_apex", "cone, ray through the apex from (0.3,0.2,2) inside the "
        "nappe (|v_xy| < |v_z|): double root at the apex", cone, cb, identity, (0.3, 0.2, 2.0),
        (-0.3, -0.2, -2.0), robust_double=True, reason=None)
    add("cone_apex_grazing", "cone_apex", "cone, ray through the apex from outside the nappes "
        "(direction (1,0,0.5)): touches only at the apex, a perturbed ray misses or hits twice",
        cone, cb, identity, (-2.0, 0.0, -1.0), (1.0, 0.0, 0.5), ambiguous=True,
        ambiguous_kind="tangent", reason=None)
    add("cone_generator_parallel", "cone_apex", "cone, ray parallel to the generator (1,0,1) from "
        "(0,0.5,-1.5): K = 0, linear root", cone, box([-2, -2, -2], [2, 2, 2]), identity,
        (0.0, 0.5, -1.5), (1.0, 0.0, 1.0), bound=1e-9,
        reason="K = 0 exactly, linear root with |L| = 3; default 1e-9.")

    # ---- 11. hyperboloid of one sheet ---------------------------------------------------------
    hyp = coeffs(1, 1, -1, j=-1)
    hb = cube(2.0)
    add("hyperboloid_waist_out", "hyperboloid", "x^2+y^2-z^2=1, ray along +y in z = 0 at x = "
        "1+1e-9: misses the waist circle by 1e-9", hyp, hb, identity, (1.0 + 1e-9, -5.0, 0.0),
        (0.0, 1.0, 0.0), bound=1e-9,
        reason="the minimum of f along the ray is 2e-9, about 1e5 times its rounding: robust miss.")
    add("hyperboloid_waist_in", "hyperboloid", "x^2+y^2-z^2=1, ray along +y in z = 0 at x = "
        "1-1e-9: grazing hit, chord half-length about 4.5e-5", hyp, hb, identity,
        (1.0 - 1e-9, -5.0, 0.0), (0.0, 1.0, 0.0))
    s2 = 1 / math.sqrt(2)
    add("hyperboloid_asymptote_a", "hyperboloid", "x^2+y^2-z^2=1 with dir (1,0,1)/sqrt2 (K = 0 "
        "exactly) from (0,0.5,-3)", hyp, hb, identity, (0.0, 0.5, -3.0), (s2, 0.0, s2), bound=1e-9,
        reason="K = 0 exactly (equal components), linear root with |L| about 4.2; default 1e-9.")
    add("hyperboloid_asymptote_b", "hyperboloid", "x^2+y^2-z^2=1 with dir (1,0,1)/sqrt2 from "
        "(0.5,0,0): hits at (1.25,0,0.75)", hyp, hb, identity, (0.5, 0.0, 0.0), (s2, 0.0, s2),
        bound=1e-9, reason="K = 0 exactly, linear root; default 1e-9.")
    add("hyperboloid_asymptote_line", "hyperboloid", "x^2+y^2-z^2=1, ray along the asymptote "
        "line x = z through the centre: f = -1 all along (K = L = 0): miss", hyp, hb, identity,
        (-1.5, 0.0, -1.5), (1.0, 0.0, 1.0), bound=1e-9,
        reason="K = L = 0 exactly with M = -1: no root, robust miss.")
    add("hyperboloid_ruling", "hyperboloid", "x^2+y^2-z^2=1, ray along the ruling x = 1, y = z: "
        "lies on the surface (K = L = M = 0); any answer accepted", hyp, hb, identity,
        (1.0, -1.5, -1.5), (0.0, 1.0, 1.0), ambiguous=True, ambiguous_kind="on_surface",
        reason="the ray lies in the surface: hit or miss both acceptable.")

    # ---- 12. coefficients spanning 1e-6 .. 1e6 -----------------------------------------------
    span = coeffs(1e6, 1, 1e-6, j=-1)  # semi-axes 1e-3, 1, 1e3
    for name, o, d, desc in [
        ("span_long_axis", (0.0, 0.0, -5e3), (0.0, 0.0, 1.0), "along the 1e3 axis from z=-5e3"),
        ("span_short_axis", (-1.0, 0.5, 0.0), (1.0, 0.0, 0.0), "along the 1e-3 axis at y=0.5"),
        ("span_oblique", (-0.0003, -3.0, -200.0), (0.0001, 1.0, 0.05), "oblique, grazing the thin "
         "axis"),
        ("span_middle", (0.0002, -4.0, 300.0), (0.0, 1.0, 0.0), "along y at x=2e-4, z=300"),
    ]:
        add(name, "coefficient_span", "ellipsoid 1e6 x^2 + y^2 + 1e-6 z^2 = 1 (semi-axes 1e-3, "
            f"1, 1e3), ray {desc}", span, None, identity, o, d)

    # ---- 13. ill-conditioned transforms -------------------------------------------------------
    flat_lin, flat_t = diag(1.0, 1.0, 1e-4), (0.1, 0.2, 0.3)
    flat = world_cols(flat_lin, flat_t)
    o, d = aim(flat_lin, flat_t, (0.2, -0.1, math.sqrt(0.95)), (0.01, 0.0, 1.0))
    add("flat_sphere_top", "ill_conditioned_transform", "unit sphere scaled by 1e-4 along z (a "
        "disc 2e-4 thick), ray from above", SPHERE, None, flat, o, d)
    add("flat_sphere_edge", "ill_conditioned_transform", "the 1e-4-flattened sphere hit near its "
        "rim from the side", SPHERE, None, flat, (-5.0, 0.25, 0.30002), (1.0, 0.01, 0.0))
    shear = [[1.0, 0.3, 0.0], [0.0, 1.0, 0.3], [0.0, 0.0, 1.0]]
    o, d = aim(shear, (1.0, -1.0, 2.0), (0.36, 0.48, 0.8), (0.2, 0.5, 6.0))
    add("shear_sphere", "ill_conditioned_transform", "unit sphere under shear 0.3 (xy, yz)",
        SPHERE, None, world_cols(shear, (1.0, -1.0, 2.0)), o, d)
    mixed = matmul_f(rot_axis_angle((1, -1, 2), 0.8), matmul_f(shear, diag(1.0, 1e-4, 1.0)))
    o, d = aim(mixed, (5.0, 6.0, 7.0), (0.6, -0.8, 0.3), (4.0, 0.5, -0.25))
    add("shear_flat_cylinder", "ill_conditioned_transform", "cylinder x^2+y^2=1 |z|<=1 under "
        "rotation * shear 0.3 * scale(1,1e-4,1) (a thin ribbon), oblique ray",
        CYL_Z, cube(1.0), world_cols(mixed, (5.0, 6.0, 7.0)), o, d)
    sp_lin = matmul_f(shear, diag(1e-4, 1.0, 1.0))
    o, d = aim(sp_lin, (0.0, 0.0, 0.0), (0.5, 1.0, 1.25), (0.0, 0.3, 6.0))
    add("shear_paraboloid", "ill_conditioned_transform", "paraboloid z = x^2+y^2 under shear 0.3 "
        "and a 1e-4 scale on x, ray from above", parab, pb, world_cols(sp_lin), o, d)

    # ---- 14. degenerate quadrics ------------------------------------------------------------
    plane = matrices([0] * 9, [0, 0, 1], 0)
    add("plane_hit", "degenerate", "plane z = 0 (Q = 0, P = (0,0,1)) clipped to [-1,1]^3, ray "
        "from above", plane, cube(1.0), identity, (0.25, 0.125, 3.0), (0.1, 0.2, -1.0), bound=1e-9,
        reason="linear root, |L| = 1; default 1e-9.")
    add("plane_hit_from_below", "degenerate", "plane z = 0 seen from below: normal still +z",
        plane, cube(1.0), identity, (-0.5, 0.3, -2.0), (0.05, -0.1, 1.0), bound=1e-9,
        reason="linear root; default 1e-9.")
    add("plane_parallel", "degenerate", "ray parallel to the plane z = 0 at z = 0.5: miss",
        plane, cube(1.0), identity, (-3.0, 0.0, 0.5), (1.0, 0.2, 0.0), bound=1e-9,
        reason="K = L = 0 exactly with M = 0.5: robust miss.")
    add("plane_in_plane", "degenerate", "ray inside the plane z = 0: on the surface; any answer "
        "accepted", plane, cube(1.0), identity, (-3.0, 0.0, 0.0), (1.0, 0.2, 0.0), ambiguous=True,
        ambiguous_kind="on_surface", reason="the ray lies in the surface: hit or miss accepted.")
    add("plane_outside_bounds", "degenerate", "plane z = 0 crossed at (2.5, 0, 0), outside the "
        "clip box [-1,1]^3: miss", plane, cube(1.0), identity, (2.5, 0.0, 4.0), (0.0, 0.0, -1.0),
        bound=1e-9, reason="the only root lies 1.5 outside the clip box: robust miss.")
    pair = coeffs(1, -1, 0)
    add("plane_pair_hit", "degenerate", "plane pair x^2-y^2=0, [-2,2]^3, ray crosses the plane "
        "x = y away from the crossing line", pair, cube(2.0), identity, (1.0, -0.5, 0.0),
        (0.0, 1.0, 0.1), bound=1e-9, reason="simple root, |g'| = 2 at x = 1; default 1e-9.")
    add("plane_pair_crossing_line", "degenerate", "plane pair x^2-y^2=0, ray along +x in y = 0 "
        "through the crossing line x = y = 0 (double root, zero gradient)", pair, cube(2.0),
        identity, (-1.5, 0.0, 0.5), (1.0, 0.0, 0.0), ambiguous=True, ambiguous_kind="tangent",
        reason=None)
    add("double_plane", "degenerate", "coincident planes z^2 = 0: every crossing is a double "
        "root (tangent everywhere, zero gradient)", coeffs(0, 0, 1), cube(1.0), identity,
        (0.2, 0.3, 2.0), (0.1, -0.1, -1.0), ambiguous=True, ambiguous_kind="tangent",
        reason=None)
    empty = coeffs(1, 1, 1, j=1)
    add("empty_sphere", "degenerate", "empty quadric x^2+y^2+z^2+1=0: miss", empty, None, identity,
        (0.0, 0.0, 5.0), (0.0, 0.0, -1.0), bound=1e-9, reason="f >= 1 everywhere: robust miss.")
    add("empty_cylinder", "degenerate", "empty x^2+y^2+1=0 with bounds: miss", coeffs(1, 1, 0, j=1),
        cube(1.0), identity, (3.0, 0.2, 0.1), (-1.0, 0.0, 0.0), bound=1e-9,
        reason="f >= 1 everywhere: robust miss.")
    point = coeffs(1, 1, 1)
    add("point_through", "degenerate", "point quadric x^2+y^2+z^2=0, ray through the point "
        "(double root, zero gradient)", point, None, identity, (0.0, 0.0, 5.0), (0.0, 0.0, -1.0),
        ambiguous=True, ambiguous_kind="tangent", reason=None)
    add("point_miss", "degenerate", "point quadric, ray passing 0.5 from the point: miss", point,
        None, identity, (0.5, 0.0, 5.0), (0.0, 0.0, -1.0), bound=1e-9,
        reason="f >= 0.25 along the ray: robust miss.")

    # ---- 15. errors ---------------------------------------------------------------------------
    add("singular_scale_zero", "error", "unit sphere with world scale 0 on z: Quadric::new must "
        "fail (singular world matrix)", SPHERE, None, world_cols(diag(1, 1, 0)), (0, 0, 5),
        (0, 0, -1), reason="error case: no bound.")
    add("singular_rank2", "error", "cylinder with a rank-2 world matrix (two equal columns): "
        "Quadric::new must fail", CYL_Z, cube(1.0),
        world_cols([[1, 1, 0], [0, 0, 1], [2, 2, 0]], (1, 2, 3)), (0, 0, 5), (0, 0, -1),
        reason="error case: no bound.")
    add("spec_unbounded", "error", "cylinder without bounds: QuadricSpec construction (or "
        "Quadric::new) must fail", CYL_Z, None, identity, (3, 0, 0), (-1, 0, 0),
        reason="error case: no bound.")
    add("spec_zero", "error", "Q and P all zero (R = 1): QuadricSpec construction must fail",
        coeffs(j=1), cube(1.0), identity, (3, 0, 0), (-1, 0, 0), reason="error case: no bound.")

    # ---- 16. non-unit directions --------------------------------------------------------------
    ud = (-0.0078125, 0.001953125, -1.0)
    for mag, tag in ((1e-3, "1e-3"), (1e3, "1e3")):
        add(f"dir_length_{tag}", "dir_length", f"scale2k_sphere_k0 with the direction multiplied "
            f"by {tag} (components rounded): depth equals that case's to a few ulp",
            SPHERE, None, world_cols(IDENTITY, base_sphere_c), base_sphere_o,
            [mag * x for x in ud], bound=1e-15,
            reason="depth = t |d| does not depend on |d|; only the rounding of the scaled "
                   "direction components (relative 1.1e-16) is added to the few-ulp error.",
            extra={"same_depth_as": "scale2k_sphere_k0", "depth_ratio": 1.0})
    add("dir_length_2^-40", "dir_length", "scale2k_sphere_k0 with the direction multiplied by "
        "2^-40 (exact): same depth, t = 2^40 times larger", SPHERE, None,
        world_cols(IDENTITY, base_sphere_c), base_sphere_o, [2.0 ** -40 * x for x in ud],
        bound=1e-15, reason="exact rescaling of the direction leaves the depth unchanged; 1e-15 "
        "allows the few-ulp error of the base case.",
        extra={"same_depth_as": "scale2k_sphere_k0", "depth_ratio": 1.0})

    # ---- 17. negative zeros -------------------------------------------------------------------
    add("negzero_sphere", "negative_zero", "unit sphere, origin (-0,-0,5), dir (-0,-0,-1): t = 4, "
        "normal (0,0,1)", SPHERE, None, identity, (-0.0, -0.0, 5.0), (-0.0, -0.0, -1.0), bound=1e-9,
        reason="head-on hit, exact in binary; default 1e-9.")
    add("negzero_cylinder", "negative_zero", "cylinder x^2+y^2=1 |z|<=1, dir (-1,-0,-0) from "
        "(3,0.5,-0): hits x = sqrt(0.75)", CYL_Z, cube(1.0), identity, (3.0, 0.5, -0.0),
        (-1.0, -0.0, -0.0), bound=1e-9, reason="well-conditioned hit; default 1e-9.")
    add("negzero_plane", "negative_zero", "plane z = 0, dir (0.5,-0,-1) from (0,-0,2)", plane,
        cube(1.0), identity, (0.0, -0.0, 2.0), (0.5, -0.0, -1.0), bound=1e-9,
        reason="linear root, exact; default 1e-9.")
# fmt: on


# --------------------------------------------------------------------------------------------
# Finishing each case
# --------------------------------------------------------------------------------------------


def finish(case):
    expected, info = reference(case)
    out = {k: v for k, v in case.items() if not k.startswith("_")}
    ambiguous = case["ambiguous"]
    fixed = case["_bound"]
    reason = case["_reason"]
    if expected["error"]:
        expected.pop("why")
        expected.update({"hit": None, "t": None, "depth": None, "normal": None})
        out.update(
            {
                "expected": expected,
                "rel_depth_bound": None,
                "normal_bound_rad": None,
                "error_estimate": None,
                "bound_reason": reason,
            }
        )
        return out
    expected["error_stage"] = None
    rel, nerr, flags = estimate(info, case["_robust_double"])
    robust_flags = [k for k in ("tangent", "near_zero_t", "clip_edge") if flags[k]]
    if robust_flags and not ambiguous:
        raise SystemExit(
            f"{case['name']}: flagged {robust_flags} by the error model but not marked ambiguous"
        )
    if case["ambiguous_kind"] == "on_surface":
        if info["kind"] != "line":
            raise SystemExit(f"{case['name']}: expected the ray to lie on the surface")
    if expected["hit"]:
        if fixed is not None:
            if fixed < case["_check_factor"] * rel:
                raise SystemExit(
                    f"{case['name']}: fixed bound {fixed:g} < {case['_check_factor']} x "
                    f"estimate {rel:.3g}"
                )
            bound = fixed
        else:
            bound = max(nice_up(SAFETY * rel), DERIVED_FLOOR)
            if reason is None:
                reason = derived_reason(case, info, rel, bound)
        nbound = (
            None
            if (nerr is None or expected["normal"] is None)
            else max(NORMAL_FLOOR, nice_up(SAFETY * nerr))
        )
        if nbound is None:
            expected["normal"] = None
    else:
        bound = fixed if fixed is not None else 1e-9
        nbound = None
        if reason is None:
            m = flags["miss_margin"]
            reason = "miss: " + (
                f"the closest approach keeps |f| at {m:.2g} times the "
                "(safety-multiplied) rounding level"
                if m
                else "no root of the ray polynomial lies in the clip box"
            )
    if not expected["hit"]:
        bound = None  # a number exactly when expected.depth is one
    out.update(
        {
            "expected": expected,
            "rel_depth_bound": bound,
            "normal_bound_rad": nbound,
            "error_estimate": None if rel is None else float(f"{rel:.3g}"),
            "bound_reason": reason,
        }
    )
    out["_info"] = info
    out["_nerr"] = nerr
    return out


def derived_reason(case, info, rel, bound):
    kind = info["kind"]
    t = info["hit"][0]
    if kind == "double" or case["ambiguous_kind"] == "tangent":
        return (
            f"tangent/double root: a perturbation dg of g(t) = f(o + t v) moves the root by "
            f"sqrt(dg/|K|) (|K| = {float(abs(info['K'])):.3g}), first-order relative "
            f"estimate {rel:.2g}; bound = 16 x estimate rounded up (floor 1e-14) = {bound:g}."
        )
    gp = abs(float(2 * info["K"] * t + info["L"]))
    slope = (
        f"|g'(t)| = |L| = {gp:.3g} (K = 0, linear root)"
        if kind == "linear"
        else f"|g'(t)| = sqrt(L^2 - 4KM) = {gp:.3g}"
    )
    return (
        f"root condition: dt = dg/|g'(t)| with {slope}, dg the first-order rounding of "
        f"g(t) = f(o + t v) at the hit (inputs, anchor, point); relative estimate "
        f"{rel:.2g}, bound = 16 x estimate rounded up (floor 1e-14) = {bound:g}."
    )


def check_numpy(done):
    """The independent float64 check.  Returns the worst (error / bound) ratio seen."""
    worst = 0.0
    for c in done:
        got = numpy_intersect(c)
        ex = c["expected"]
        name = c["name"]
        if ex["error"]:
            assert got[0] == "error", (name, got)
            continue
        assert got[0] != "error", name
        if c["ambiguous"]:
            if got[0] == "hit" and ex["depth"] is not None:
                err = abs(got[2] - ex["depth"]) / ex["depth"]
                assert err <= c["rel_depth_bound"], (name, err, c["rel_depth_bound"])
            continue
        assert (got[0] == "hit") == ex["hit"], (name, got, ex)
        if not ex["hit"]:
            continue
        err = abs(got[2] - ex["depth"]) / ex["depth"]
        assert err <= c["rel_depth_bound"], (name, err, c["rel_depth_bound"])
        if c["rel_depth_bound"] <= 1e-9:
            assert err <= 1e-9, (name, err)
        if err / c["rel_depth_bound"] > worst:
            worst = err / c["rel_depth_bound"]
            check_numpy.worst_name = name
        if c["normal_bound_rad"] is not None:
            a = angle(got[3], ex["normal"])
            assert a <= c["normal_bound_rad"], (name, a, c["normal_bound_rad"])
    return worst


def check_scaling(done):
    by_name = {c["name"]: c for c in done}
    for c in done:
        base = c.get("same_depth_as")
        if base:
            b = by_name[base]["expected"]["depth"]
            ratio = c["depth_ratio"]
            err = abs(c["expected"]["depth"] - ratio * b) / (ratio * b)
            # power-of-two scalings are exact: the reference depths agree to the last bit
            tol = 0.0 if c["family"] == "scale_pow2" or c["name"] == "dir_length_2^-40" else 4e-16
            assert err <= tol, (c["name"], err)


def sanity(done):
    """Spot checks of a few hand-computable answers."""
    by = {c["name"]: c["expected"] for c in done}
    assert by["paraboloid_vertex"]["t"] == 5.0 and by["paraboloid_vertex"]["normal"] == [0, 0, -1]
    assert by["paraboloid_offaxis"]["t"] == 4.75
    assert by["negzero_sphere"]["t"] == 4.0 and by["negzero_sphere"]["normal"] == [0, 0, 1]
    assert by["cone_apex_axis"]["t"] == 5.0 and by["cone_apex_axis"]["normal"] is None
    assert by["outside_through_open_end"]["t"] == 4.0
    assert abs(by["axis_tilt_1e-8"]["t"] - 1e8) < 1e-6
    assert by["hyperboloid_waist_out"]["hit"] is False
    assert by["near_tangent_out_1e-7"]["hit"] is False
    assert by["near_tangent_in_1e-7"]["hit"] is True
    assert by["inside_cylinder_open_end"]["hit"] is False


def dump(cases) -> str:
    """A JSON list, one key per line inside each case (arrays kept on one line)."""
    out = []
    for c in cases:
        items = [f"  {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in c.items()]
        out.append(" {\n" + ",\n".join(items) + "\n }")
    return "[\n" + ",\n".join(out) + "\n]\n"


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("stiff-cases"), description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="do not write; fail if the file differs")
    args = ap.parse_args(argv)
    mp.prec = PREC
    build_cases()
    names = [c["name"] for c in CASES]
    assert len(names) == len(set(names)), "duplicate case names"
    done = [finish(c) for c in CASES]
    sanity(done)
    check_scaling(done)
    worst = check_numpy(done)
    for c in done:
        c.pop("_info", None)
        c.pop("_nerr", None)
    for c in done:
        assert (c["rel_depth_bound"] is None) == (c["expected"]["depth"] is None), c["name"]
        assert (c["normal_bound_rad"] is None) == (c["expected"]["normal"] is None), c["name"]
    text = dump(done)
    fams: dict[str, int] = {}
    for c in done:
        fams[c["family"]] = fams.get(c["family"], 0) + 1
    print(
        f"{len(done)} cases; numpy float64 check: worst error/bound = {worst:.3g} "
        f"({getattr(check_numpy, 'worst_name', '-')})"
    )
    for k, v in fams.items():
        print(f"  {k:28s} {v}")
    if args.check:
        if not OUT.exists() or OUT.read_text() != text:
            sys.exit(f"{OUT} is out of date")
        return 0
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(text)
    print(f"wrote {OUT.relative_to(ROOT)}")
    return 0
