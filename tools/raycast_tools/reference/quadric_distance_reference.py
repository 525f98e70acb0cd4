"""The distance from a point to a clipped quadric, at 50 digits with mpmath, by a method of its
own: for checking raycast's `Quadric::closest` (the Lagrange condition in the eigenbasis of
the world matrix, the secular polynomial's roots, the clip box's conics and edges in f64).

Here nothing is diagonalised and nothing leaves the quadric's own coordinates: the surface is
`f(x) = x·Q·x + P·x + R = 0` in local coordinates `x`, placed by the affine map `w = A x + t`,
and the world distance is the metric `G = AᵀA` in local coordinates. The nearest point of the
clipped surface is the nearest of:

- points of the surface on lines through the query and through the box centre in many
  directions (64 by default; exact roots of a quadratic), kept when in the box: they bound
  the answer from above and are the starting points;
- Newton's method at 50 digits on the stationarity system `G(x − x_p) = ν(Qx + P/2)`,
  `f(x) = 0` from the nearest of those points, and on the same system restricted to each face
  plane `x_k = m` from points of the face's conic (on lines in the plane through the query's
  foot and through the face's centre), kept when they converge in the box;
- the roots of `f` along the box's twelve edges (exact), and the centre where `∇f = 0` when
  it lies on the surface (a cone's apex);
- on each face, golden-section search for the minima of the distance along the
  conic parametrised by the angle of a line through the face's centre.

Sampling covers where Newton may fail (the centre of a sphere, where the stationary points
form a continuum) and Newton the digits sampling cannot reach.
"""

import mpmath
from mpmath import mp

DIGITS = 50
TINY = mpmath.mpf(10) ** -40


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


def _apply(m, v):
    return [_dot(row, v) for row in m]


def _transpose(m):
    return [[m[j][i] for j in range(3)] for i in range(3)]


def _fibonacci(n):
    """n unit directions spread over the sphere."""
    golden = (1 + mpmath.sqrt(5)) / 2
    out = []
    for i in range(n):
        z = 1 - (2 * i + 1) / mpmath.mpf(n)
        r = mpmath.sqrt(1 - z * z)
        phi = 2 * mpmath.pi * i / golden
        out.append([r * mpmath.cos(phi), r * mpmath.sin(phi), z])
    return out


class Clipped:
    """A quadric `x·Q·x + P·x + R = 0` in local coordinates, clipped to the local box
    `[lo, hi]` (or not, `box=None`), placed by the 3×4 affine `[A | t]` (row-major).
    Vectors are lists of three mpf."""

    def __init__(self, q, p, r, box, placement):
        mp.dps = DIGITS
        self.q = [[mpmath.mpf(float(v)) for v in row] for row in q]
        self.p = [mpmath.mpf(float(v)) for v in p]
        self.r = mpmath.mpf(float(r))
        self.box = None
        if box is not None:
            self.box = [[mpmath.mpf(float(v)) for v in b] for b in box]
        self.a = [[mpmath.mpf(float(v)) for v in row[:3]] for row in placement]
        self.t = [mpmath.mpf(float(row[3])) for row in placement]
        inverse = mpmath.inverse(mpmath.matrix(self.a))
        self.a_inv = [[inverse[i, j] for j in range(3)] for i in range(3)]
        at = _transpose(self.a)
        self.g = [[_dot(at[i], at[j]) for j in range(3)] for i in range(3)]
        # The world length of the local gradient of x_k: a local offset h across the plane
        # x_k = m is a world distance h / |row k of A⁻¹|.
        self.across = [mpmath.sqrt(_dot(row, row)) for row in self.a_inv]

    def f(self, x):
        return _dot(x, _apply(self.q, x)) + _dot(self.p, x) + self.r

    def half_gradient(self, x):
        qx = _apply(self.q, x)
        return [qx[i] + self.p[i] / 2 for i in range(3)]

    def world(self, x):
        ax = _apply(self.a, x)
        return [ax[i] + self.t[i] for i in range(3)]

    def local(self, w):
        return _apply(self.a_inv, [w[i] - self.t[i] for i in range(3)])

    def world_normal(self, x):
        """The unit world normal (the world gradient's direction) at local `x` (None where
        the gradient vanishes) and the world gradient's length."""
        n = _apply(_transpose(self.a_inv), self.half_gradient(x))
        length = mpmath.sqrt(_dot(n, n))
        if length == 0:
            return None, length
        return [v / length for v in n], 2 * length

    def in_box(self, x, slack=mpmath.mpf(10) ** -30):
        if self.box is None:
            return True
        return all(self.box[0][i] - slack <= x[i] <= self.box[1][i] + slack for i in range(3))

    def on_line(self, x0, d):
        """The points of the surface on the line `x0 + s d`."""
        qd = _apply(self.q, d)
        a = _dot(d, qd)
        b = 2 * _dot(x0, qd) + _dot(self.p, d)
        c = self.f(x0)
        if abs(a) < TINY:
            if abs(b) < TINY:
                return []
            return [[x0[i] - d[i] * (c / b) for i in range(3)]]
        disc = b * b - 4 * a * c
        if disc < 0:
            return []
        root = mpmath.sqrt(disc)
        out = []
        for sign in (1, -1):
            s = (-b + sign * root) / (2 * a)
            out.append([x0[i] + s * d[i] for i in range(3)])
        return out

    def centre(self):
        """The box centre (local), or the ellipsoid's without a box."""
        if self.box is None:
            c = mpmath.lu_solve(mpmath.matrix(self.q), mpmath.matrix(self.p))
            return [-c[i] / 2 for i in range(3)]
        return [(self.box[0][i] + self.box[1][i]) / 2 for i in range(3)]

    def distance(self, x, xp):
        d = [x[i] - xp[i] for i in range(3)]
        return mpmath.sqrt(_dot(d, _apply(self.g, d)))

    def _equations(self, x, nu, xp, free):
        grad = self.half_gradient(x)
        g_dx = _apply(self.g, [x[i] - xp[i] for i in range(3)])
        return [g_dx[i] - nu * grad[i] for i in free] + [self.f(x)], grad

    def newton(self, x, xp, fixed=(), damped=True):
        """Newton on the stationarity system from `x` (`damped`: the step halved until the
        residual shrinks), with the local coordinates `fixed` held; the point if it
        converges in the box, else None."""
        free = [i for i in range(3) if i not in fixed]
        x = list(x)
        grad = self.half_gradient(x)
        resid = _apply(self.g, [x[i] - xp[i] for i in range(3)])
        norm = sum(grad[i] ** 2 for i in free)
        nu = sum(grad[i] * resid[i] for i in free) / norm if norm > TINY**2 else mpmath.mpf(0)
        n = len(free)
        equations, grad = self._equations(x, nu, xp, free)
        # Converged when the residual is at the working precision relative to the problem's
        # size: the stationarity equations hold terms of the query's distance, so a query 1e6
        # away cannot get them below 1e-45 absolute in 50 digits.
        tolerance = mpmath.mpf(10) ** -(DIGITS - 5) * (1 + max(abs(v) for v in xp)) ** 2
        for _ in range(80):
            size = max(abs(e) for e in equations)
            if size < tolerance:
                return x if self.in_box(x) else None
            jac = mpmath.matrix(n + 1, n + 1)
            for row, i in enumerate(free):
                for col, j in enumerate(free):
                    jac[row, col] = self.g[i][j] - nu * self.q[i][j]
                jac[row, n] = -grad[i]
            for col, j in enumerate(free):
                jac[n, col] = 2 * grad[j]
            try:
                step = mpmath.lu_solve(jac, mpmath.matrix(equations))
            except ZeroDivisionError:
                return None
            scale = mpmath.mpf(1)
            for _ in range(40):
                trial = list(x)
                for col, j in enumerate(free):
                    trial[j] -= scale * step[col]
                trial_nu = nu - scale * step[n]
                trial_eq, trial_grad = self._equations(trial, trial_nu, xp, free)
                if not damped or max(abs(e) for e in trial_eq) < size:
                    break
                scale /= 2
            else:
                return None
            x, nu, equations, grad = trial, trial_nu, trial_eq, trial_grad
        return None

    def nearest(self, query, directions=64):
        """The world distance from the world point `query` to the clipped surface (an mpf)
        and the nearest point (local); (inf, None) if nothing of it is found."""
        mp.dps = DIGITS
        xp = self.local([mpmath.mpf(float(v)) for v in query])
        dirs = [_apply(self.a_inv, d) for d in _fibonacci(directions)]
        samples = []
        for x0 in (xp, self.centre()):
            for d in dirs:
                samples.extend(x for x in self.on_line(x0, d) if self.in_box(x))
        found = list(samples)
        for start in sorted(samples, key=lambda x: self.distance(x, xp))[:6]:
            for damped in (True, False):
                x = self.newton(start, xp, damped=damped)
                if x is not None:
                    found.append(x)
        if self.box is not None:
            found.extend(self._on_edges())
            bound = min((self.distance(x, xp) for x in found), default=mpmath.inf)
            found.extend(self._on_faces(xp, directions // 2, bound))
        try:
            c = mpmath.lu_solve(mpmath.matrix(self.q), mpmath.matrix(self.p))
            c = [-c[i] / 2 for i in range(3)]
            if abs(self.f(c)) < TINY and self.in_box(c):
                found.append(c)
        except ZeroDivisionError:
            pass
        if not found:
            return mpmath.inf, None
        best = min(found, key=lambda x: self.distance(x, xp))
        return self.distance(best, xp), best

    def _on_faces(self, xp, directions, bound):
        """Candidates on the faces whose plane is nearer than `bound`."""
        out = []
        for k in range(3):
            for m in (self.box[0][k], self.box[1][k]):
                if abs(xp[k] - m) / self.across[k] > bound:
                    continue
                foot = list(xp)
                foot[k] = m
                middle = self.centre()
                middle[k] = m
                points = []
                for i in range(directions):
                    angle = mpmath.pi * i / directions
                    d = [mpmath.mpf(0)] * 3
                    d[(k + 1) % 3] = mpmath.cos(angle)
                    d[(k + 2) % 3] = mpmath.sin(angle)
                    for x0 in (foot, middle):
                        points.extend(x for x in self.on_line(x0, d) if self.in_box(x))
                out.extend(points)
                for start in sorted(points, key=lambda x: self.distance(x, xp))[:3]:
                    for damped in (True, False):
                        x = self.newton(start, xp, fixed=(k,), damped=damped)
                        if x is not None:
                            out.append(x)
                out.extend(self._golden_on_face(middle, k, xp, directions))
        return out

    def _face_point(self, middle, k, angle, branch):
        """The point of the face's conic on the line through `middle` at `angle` in the
        face, on root `branch` (0 or 1), or None."""
        d = [mpmath.mpf(0)] * 3
        d[(k + 1) % 3] = mpmath.cos(angle)
        d[(k + 2) % 3] = mpmath.sin(angle)
        points = self.on_line(middle, d)
        if len(points) != 2 or not self.in_box(points[branch]):
            return None
        return points[branch]

    def _golden_on_face(self, middle, k, xp, directions):
        """Minima of the distance along the face's conic, parametrised by the angle of the
        line through the face's centre: each sampled local minimum (of either root) refined by
        golden-section search between its neighbours."""
        out = []
        step = 2 * mpmath.pi / directions
        for branch in (0, 1):

            def dist(angle, branch=branch):
                x = self._face_point(middle, k, angle, branch)
                return mpmath.inf if x is None else self.distance(x, xp)

            values = [dist(i * step) for i in range(directions)]
            for i in range(directions):
                here, before, after = values[i], values[i - 1], values[(i + 1) % directions]
                if here == mpmath.inf or here > before or here > after:
                    continue
                lo, hi = (i - 1) * step, (i + 1) * step
                ratio = (mpmath.sqrt(5) - 1) / 2
                a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
                fa, fb = dist(a), dist(b)
                for _ in range(100):
                    if fa <= fb:
                        hi, b, fb = b, a, fa
                        a = hi - ratio * (hi - lo)
                        fa = dist(a)
                    else:
                        lo, a, fa = a, b, fb
                        b = lo + ratio * (hi - lo)
                        fb = dist(b)
                x = self._face_point(middle, k, (lo + hi) / 2, branch)
                if x is not None:
                    out.append(x)
        return out

    def _on_edges(self):
        out = []
        lo, hi = self.box
        for k in range(3):
            j, i = (k + 1) % 3, (k + 2) % 3
            for a in (lo[j], hi[j]):
                for b in (lo[i], hi[i]):
                    x0 = [mpmath.mpf(0)] * 3
                    x0[k], x0[j], x0[i] = lo[k], a, b
                    d = [mpmath.mpf(0)] * 3
                    d[k] = hi[k] - lo[k]
                    out.extend(x for x in self.on_line(x0, d) if self.in_box(x))
        return out
