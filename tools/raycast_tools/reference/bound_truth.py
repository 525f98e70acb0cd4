"""The exact answers that raycast's `error` and `certain` AOVs are checked against.

Shares no code with raycast. Every input is a float64 number taken as the exact real it
stands for (`fractions.Fraction(float)` is exact): triangle vertices (f32 or f64, placed by
their node matrix with exact rational arithmetic), ray origins and directions, quadric
coefficients, clip boxes and node matrices.

- Triangles: exact rational arithmetic. The ray meets the plane of (a, b, c) at
  `t = n·(a − o) / n·d`, `n = (b − a) × (c − a)`; the hit is inside (boundary included) when
  the three signed volumes `((v_{i+1} − v_i) × (p − v_i))·n` are all ≥ 0.
- Quadrics: mpmath at PREC bits (about 100 decimal digits): the local ray `A⁻¹(o − T)`,
  `A⁻¹d`, `K t² + L t + M = 0`, both roots, the clip box (inclusive, not widened).
- The depth is `t·|d|` in mpmath.

A float64 filter only chooses which primitives to evaluate exactly: a ray is tested exactly
against every triangle whose float64 barycentric weights are within FILTER of the triangle,
and every quadric whose padded world box it passes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import mpmath
import numpy as np

PREC = 340  # bits
FILTER = 1e-6  # float64 barycentric slack of the candidate filter
mpmath.mp.prec = PREC


def frac3(v):
    return [Fraction(float(x)) for x in v]


def sub(a, b):
    return [a[0] - b[0], a[1] - b[1], a[2] - b[2]]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def exact(x):
    """A number as a Fraction: a Fraction stays, a float is taken exactly."""
    return x if isinstance(x, Fraction) else Fraction(float(x))


def place(matrix_cols, point):
    """An exact column-major 4×4 affine matrix applied to a point (Fractions)."""
    m = [exact(x) for x in matrix_cols]
    return [
        m[r] * point[0] + m[4 + r] * point[1] + m[8 + r] * point[2] + m[12 + r] for r in range(3)
    ]


def compose(a_cols, b_cols):
    """The exact product a·b of two column-major 4×4 matrices (Fractions, column-major)."""
    a = [exact(x) for x in a_cols]
    b = [exact(x) for x in b_cols]
    out = [Fraction(0)] * 16
    for c in range(4):
        for r in range(4):
            out[c * 4 + r] = sum(a[k * 4 + r] * b[c * 4 + k] for k in range(4))
    return out


def trs(translation, rotation, scale):
    """The column-major matrix T·R·S of a glTF node's translation, rotation quaternion (x, y,
    z, w; normalized exactly, as the file means it) and scale: Fractions within 2⁻⁴⁰⁰ of the
    exact entries (the normalization's square root is irrational), from mpmath at 460 bits."""
    with mpmath.workprec(460):
        q = [mpmath.mpf(float(c)) for c in rotation]
        n = mpmath.sqrt(sum(c * c for c in q))
        x, y, z, w = (c / n for c in q)
        r = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]

        def frac(v):
            v = mpmath.mpf(v)
            man, exp = v.man_exp  # the magnitude's mantissa and exponent: the sign apart
            return (-1 if v < 0 else 1) * Fraction(man) * Fraction(2) ** exp if man else Fraction(0)

        cols = []
        for c in range(3):
            cols += [frac(r[row][c]) * exact(scale[c]) for row in range(3)] + [Fraction(0)]
    return cols + [exact(t) for t in translation] + [Fraction(1)]


def _mp_fraction(v):
    """An mpmath number as the exact Fraction of its binary value."""
    v = mpmath.mpf(v)
    man, exp = v.man_exp  # the magnitude's mantissa and exponent: the sign apart
    return (-1 if v < 0 else 1) * Fraction(man) * Fraction(2) ** exp if man else Fraction(0)


def _rotation_cols(r):
    """A 3×3 mpmath rotation (rows) as a column-major 4×4 list of Fractions."""
    cols = []
    for c in range(3):
        cols += [_mp_fraction(r[row][c]) for row in range(3)] + [Fraction(0)]
    return cols + [Fraction(0)] * 3 + [Fraction(1)]


def usd_rotation(axis: int, degrees: float):
    """USD's rotateX/Y/Z by `degrees` (the f64 value as read), the exact angle degrees·π/180:
    column-major Fractions within 2⁻⁴⁰⁰ of the exact entries (mpmath at 460 bits)."""
    with mpmath.workprec(460):
        a = mpmath.mpf(float(degrees)) * mpmath.pi / 180
        c, s = mpmath.cos(a), mpmath.sin(a)
        i, j = (axis + 1) % 3, (axis + 2) % 3
        r = [[mpmath.mpf(int(row == col)) for col in range(3)] for row in range(3)]
        r[i][i], r[j][j], r[j][i], r[i][j] = c, c, s, -s
        return _rotation_cols(r)


def usd_orient(w, x, y, z):
    """USD's `orient` as usd-core reads it (GfRotation): the real part clamped to [-1, 1] is the
    cosine of half the angle, the imaginary part only the axis; the exact rotation of that
    unit quaternion, as in usd_rotation."""
    with mpmath.workprec(460):
        w = min(max(mpmath.mpf(float(w)), -1), 1)
        v = [mpmath.mpf(float(c)) for c in (x, y, z)]
        k = mpmath.sqrt(1 - w * w) / mpmath.sqrt(sum(c * c for c in v))
        x, y, z = (c * k for c in v)
        r = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
        return _rotation_cols(r)


def translation(t):
    """The exact column-major matrix of a translation."""
    cols = [Fraction(int(r == c)) for c in range(3) for r in range(4)]
    return cols + [exact(x) for x in t] + [Fraction(1)]


def scaling(s):
    """The exact column-major matrix of a scale."""
    cols = []
    for c in range(3):
        cols += [exact(s[c]) if r == c else Fraction(0) for r in range(4)]
    return cols + [Fraction(0)] * 3 + [Fraction(1)]


@dataclass
class Triangle:
    """One world triangle, exact, with raycast's object name and prim number."""

    verts: list  # three [Fraction]*3
    name: str
    prim: int

    def crossing(self, o, d):
        """(t, inside) of the exact ray with the exact plane; None when parallel."""
        a, b, c = self.verts
        n = cross(sub(b, a), sub(c, a))
        denom = dot(n, d)
        if denom == 0:
            return None
        t = dot(n, sub(a, o)) / denom
        p = [o[i] + t * d[i] for i in range(3)]
        inside = all(
            dot(cross(sub(v1, v0), sub(p, v0)), n) >= 0 for v0, v1 in ((a, b), (b, c), (c, a))
        )
        return t, inside


@dataclass
class QuadricPrim:
    """One quadric node: coefficients, clip box and world matrix (column-major), exact."""

    coefficients: list
    bounds: tuple | None
    matrix: list
    name: str
    mp_q: object = field(init=False, default=None)

    def _prepare(self):
        mp = mpmath.mp
        a, b, c, d, e, f, g, h, i, j = (mp.mpf(float(x)) for x in self.coefficients)
        self.Q = mp.matrix([[a, d / 2, e / 2], [d / 2, b, f / 2], [e / 2, f / 2, c]])
        self.P = mp.matrix([g, h, i])
        self.R = j
        m = [
            mp.mpf(x) if isinstance(x, float) else mp.mpf(x.numerator) / x.denominator
            for x in self.matrix
        ]
        self.A = mp.matrix([[m[col * 4 + row] for col in range(3)] for row in range(3)])
        self.T = mp.matrix([m[12 + row] for row in range(3)])
        self.Ai = self.A**-1
        self.mp_q = True

    def roots(self, o, d):
        """Every real root t of the exact ray with the surface, with whether its point lies
        in the clip box (inclusive)."""
        mp = mpmath.mp
        if self.mp_q is None:
            self._prepare()
        om = mp.matrix([mp.mpf(float(x)) for x in o])
        dm = mp.matrix([mp.mpf(float(x)) for x in d])
        ol = self.Ai * (om - self.T)
        v = self.Ai * dm

        def mdot(u, w):
            return u[0] * w[0] + u[1] * w[1] + u[2] * w[2]

        qv = self.Q * v
        k = mdot(v, qv)
        lin = 2 * mdot(ol, qv) + mdot(self.P, v)
        m = mdot(ol, self.Q * ol) + mdot(self.P, ol) + self.R
        if k == 0:
            ts = [] if lin == 0 else [-m / lin]
        else:
            disc = lin * lin - 4 * k * m
            if disc < 0:
                return []
            s = mp.sqrt(disc)
            ts = sorted([(-lin - s) / (2 * k), (-lin + s) / (2 * k)])
        out = []
        for t in ts:
            p = ol + t * v
            inside = self.bounds is None or all(
                self.bounds[0][i] <= p[i] <= self.bounds[1][i] for i in range(3)
            )
            out.append((t, inside))
        return out


def to_mp(x):
    if isinstance(x, Fraction):
        return mpmath.mpf(x.numerator) / x.denominator
    return x


class Truth:
    """A scene's exact primitives, and the exact answer for each ray."""

    def __init__(self, triangles: list[Triangle], quadrics: list[QuadricPrim], quadric_boxes=None):
        self.triangles = triangles
        self.quadrics = quadrics
        self.boxes = quadric_boxes or []
        self.index = {(t.name, t.prim): t for t in triangles}
        self.by_name = {q.name: q for q in quadrics}
        if triangles:
            tri = np.array([[[float(c) for c in v] for v in t.verts] for t in triangles])
            self.a = tri[:, 0]
            self.e1 = tri[:, 1] - tri[:, 0]
            self.e2 = tri[:, 2] - tri[:, 0]

    def candidates(self, o, d):
        """Triangles the float64 filter keeps for one ray."""
        if not self.triangles:
            return []
        p = np.cross(d, self.e2)
        det = np.einsum("ij,ij->i", self.e1, p)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - self.a
            u = np.einsum("ij,ij->i", s, p) * inv
            q = np.cross(s, self.e1)
            v = (q @ d) * inv
            t = np.einsum("ij,ij->i", self.e2, q) * inv
        keep = (
            (u >= -FILTER)
            & (v >= -FILTER)
            & (u + v <= 1 + FILTER)
            & (t > -FILTER * np.abs(t).max(initial=1.0))
        )
        keep |= ~np.isfinite(det) | (np.abs(det) < 1e-300)
        return np.flatnonzero(keep)

    def quadric_candidates(self, o, d):
        out = []
        for k, box in enumerate(self.boxes):
            if box is None:
                out.append(k)
                continue
            lo, hi = box
            with np.errstate(divide="ignore", invalid="ignore"):
                t0 = (lo - o) / d
                t1 = (hi - o) / d
            tn = np.nanmax(np.minimum(t0, t1))
            tf = np.nanmin(np.maximum(t0, t1))
            if tn <= tf * (1 + 1e-9) + 1e-9 and tf >= -1e-9:
                out.append(k)
        return out

    def answer(self, o, d):
        """(crossings, nearest): every exact crossing of the candidates as (t as mpf, inside,
        name, prim), and the set of (name, prim) at the nearest valid t (empty: a miss)."""
        of, df = frac3(o), frac3(d)
        crossings = []
        for i in self.candidates(np.asarray(o), np.asarray(d)):
            tri = self.triangles[i]
            c = tri.crossing(of, df)
            if c is not None:
                crossings.append((c[0], c[1], tri.name, tri.prim))
        for k in self.quadric_candidates(np.asarray(o), np.asarray(d)):
            q = self.quadrics[k]
            for t, inside in q.roots(o, d):
                crossings.append((t, inside, q.name, 0))
        valid = [c for c in crossings if c[1] and to_mp(c[0]) > 0]
        if not valid:
            return crossings, set()
        best = min(to_mp(c[0]) for c in valid)
        nearest = {(c[2], c[3]) for c in valid if to_mp(c[0]) == best}
        return crossings, nearest

    def same_primitive_depth(self, o, d, name, prim, t_reported):
        """The exact depth of the crossing of primitive (name, prim) nearest `t_reported`, or
        None when the exact ray has none (parallel to a triangle, no real root)."""
        if (name, prim) in self.index:
            c = self.index[(name, prim)].crossing(frac3(o), frac3(d))
            ts = [] if c is None else [to_mp(c[0])]
        else:
            ts = [t for t, _ in self.by_name[name].roots(o, d)]
        if not ts:
            return None
        t = min(ts, key=lambda x: abs(x - t_reported))
        return t * dir_length(d)


def dir_length(d):
    return mpmath.sqrt(sum(mpmath.mpf(float(x)) ** 2 for x in d))
