"""Error measures shared by the validation and the reports."""

from __future__ import annotations

import numpy as np


def angle(a, b):
    """Angle between vectors along the last axis, atan2(|a×b|, a·b) (accurate near 0 and π)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...i,...i->...", a, b))


def stats(x) -> dict:
    """max, p99 and mean of a sample (None for each when it is empty)."""
    x = np.asarray(x, dtype=np.float64)
    if x.size == 0:
        return {"max": None, "p99": None, "mean": None}
    return {"max": float(x.max()), "p99": float(np.percentile(x, 99)), "mean": float(x.mean())}


def fit_slope(x, y) -> float:
    """Least-squares slope of log y against log x over the positive finite points (NaN with
    fewer than two)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (x > 0) & (y > 0) & np.isfinite(y)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def edge_distance(tris, p):
    """Distance from points p (n, 3) to the nearest edge segment of triangles tris (n, 3, 3)."""
    best = np.full(len(p), np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        A, B = tris[:, a], tris[:, b]
        ab = B - A
        ll = np.einsum("ij,ij->i", ab, ab)
        with np.errstate(all="ignore"):
            t = np.clip(np.einsum("ij,ij->i", p - A, ab) / ll, 0, 1)
        t = np.where(ll > 0, t, 0)
        c = A + t[:, None] * ab
        best = np.minimum(best, np.linalg.norm(p - c, axis=1))
    return best
