"""Signed distances' signs on closed meshes against exact truth, at scale: random points,
and points pushed off faces, edges and vertices by 1e-12 (of the shape's size) to either
side, on a convex icosphere (inside: below every face's plane) and on a non-convex L-shaped
prism (inside: in one of its two boxes). The truth for a pushed point is the side it was
pushed to: the push is along the face normal (faces) or the mean of the adjacent faces'
normals (edges, vertices), and 1e-12 is 10^4 times the points' own rounding. Writes
reports/signed_distance.md (and .json).

Usage: python -m raycast_tools signed-check [--points N] [--seed S]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from raycast_tools import paths
from raycast_tools.bench import machine

REPORT = paths.ROOT / "reports/signed_distance.md"
PUSH = 1e-12


def l_prism():
    ring = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
    vertices = np.array([(x, y, 0.0) for x, y in ring] + [(x, y, 1.0) for x, y in ring])
    faces = []
    for k in range(1, 5):
        faces += [(0, k + 1, k), (6, 6 + k, 6 + k + 1)]
    for k in range(6):
        j = (k + 1) % 6
        faces += [(k, j, 6 + j), (k, 6 + j, 6 + k)]

    def inside(p):
        x, y, z = p[:, 0], p[:, 1], p[:, 2]
        a = (0 < x) & (x < 2) & (0 < y) & (y < 1)
        b = (0 < x) & (x < 1) & (0 < y) & (y < 2)
        return (0 < z) & (z < 1) & (a | b)

    return vertices, np.array(faces), inside, (np.zeros(3), np.array([2.0, 2.0, 1.0]))


def icosphere():
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=4, radius=1.0)
    v, f = m.vertices, m.faces
    a, b, c = (v[f[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    offsets = np.einsum("fk,fk->f", a, n)

    def inside(p):
        # Exact enough away from the planes; pushed points get their truth from the push.
        return (p @ n.T - offsets < 0).all(axis=1)

    def clear(p):
        return np.abs(p @ n.T - offsets).min(axis=1) > 1e-9

    return v, f, inside, clear


def pushed(rng, v, f, count):
    """Points on random faces, edges and vertices, pushed by +-PUSH along an outward
    direction there; returns the points and whether each was pushed inward."""
    normals = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    vertex_normal = np.zeros_like(v)
    for k in range(3):
        np.add.at(vertex_normal, f[:, k], normals)
    vertex_normal /= np.linalg.norm(vertex_normal, axis=1, keepdims=True)
    pick = rng.integers(len(f), size=count)
    kind = rng.integers(3, size=count)
    w = rng.dirichlet([1, 1, 1], size=count) * 0.8 + 0.2 / 3  # face interiors
    edge, corner = kind == 1, kind == 2
    s = rng.uniform(0.2, 0.8, edge.sum())  # along the edge from vertex 0 to vertex 1
    w[edge] = np.column_stack([1 - s, s, np.zeros(edge.sum())])
    w[corner] = [1, 0, 0]
    tri = v[f[pick]]
    on = np.einsum("ni,nij->nj", w, tri)
    direction = normals[pick].copy()
    direction[edge] = vertex_normal[f[pick[edge], 0]] + vertex_normal[f[pick[edge], 1]]
    direction[corner] = vertex_normal[f[pick[corner], 0]]
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    inward = rng.random(count) < 0.5
    step = np.where(inward, -PUSH, PUSH)[:, None]
    return on + step * direction, inward, kind


def check(name, scene, points, inside, certain_truth, signed):
    sign = np.sign(signed)
    expected = np.where(inside, -1.0, 1.0)
    wrong = (sign != 0) & (sign != expected) & certain_truth
    return {
        "shape": name,
        "points": int(len(points)),
        "judged": int(certain_truth.sum()),
        "wrong": int(wrong.sum()),
        "zero": int((sign == 0).sum()),
    }


def main(argv=None) -> int:
    import raycast

    parser = argparse.ArgumentParser(
        prog="python -m raycast_tools signed-check", description=__doc__
    )
    parser.add_argument("--points", type=int, default=1_000_000, help="points in all")
    parser.add_argument("--seed", type=int, default=5)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    quarter = args.points // 4
    rows, began = [], time.perf_counter()
    v, f, inside, clear = icosphere()
    scene = raycast.Scene.from_arrays(v, f)
    p = rng.uniform(-1.3, 1.3, (quarter, 3))
    rows.append(check("icosphere, random", scene, p, inside(p), clear(p), scene.signed_distance(p)))
    p, inward, _ = pushed(rng, v, f, quarter)
    rows.append(
        check(
            "icosphere, 1e-12 off faces, edges, vertices",
            scene,
            p,
            inward,
            np.ones(len(p), bool),
            scene.signed_distance(p),
        )
    )
    v, f, inside, (lo, hi) = l_prism()
    scene = raycast.Scene.from_arrays(v, f)
    p = rng.uniform(lo - 0.3, hi + 0.3, (quarter, 3))
    rows.append(
        check(
            "L prism, random", scene, p, inside(p), np.ones(len(p), bool), scene.signed_distance(p)
        )
    )
    p, inward, _ = pushed(rng, v, f, args.points - 3 * quarter)
    rows.append(
        check(
            "L prism, 1e-12 off faces, edges, vertices",
            scene,
            p,
            inward,
            np.ones(len(p), bool),
            scene.signed_distance(p),
        )
    )
    took = time.perf_counter() - began
    lines = [
        "# Signed distance: signs against exact truth on closed meshes",
        "",
        "`python -m raycast_tools signed-check` (tools/raycast_tools/validate/signed_check.py): "
        "`Scene.signed_distance(points)` (sign by crossings) on an icosphere (5,120 faces, "
        "convex: inside is below every face's plane) and on an L-shaped prism (non-convex: "
        "inside is inside one of its two boxes, exactly), for random points and for points "
        "pushed 1e-12 off random faces, edges and vertices to either side (the truth is the "
        "side of the push: along the face normal, or the mean of the vertex normals). Random "
        "icosphere points within 1e-9 of a face's plane are not judged (float64 truth).",
        "",
        "| points | count | judged | wrong sign | sign 0 (within the margin) |",
        "| --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['shape']} | {r['points']:,} | {r['judged']:,} | {r['wrong']} | {r['zero']:,} |"
        )
    m = machine.machine()
    total_wrong = sum(r["wrong"] for r in rows)
    lines += [
        "",
        f"**{total_wrong} wrong signs in {sum(r['points'] for r in rows):,} points.** "
        f"{took:.0f} s in all on {m['nproc']} CPUs ({m['cpu']}), load average {m['loadavg']}.",
        "",
    ]
    REPORT.write_text("\n".join(lines))
    REPORT.with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")
    print(f"wrote {REPORT}: {total_wrong} wrong")
    return 0
