"""Random quadric scenes for the validation against the independent reference.

    .venv/bin/python -m raycast_tools random-quadrics OUT_DIR [--scenes K] [--seed S]

Writes K glTF files, each holding one quadric of every type (the lecture's six plus the
elliptic, hyperbolic and parabolic cylinders) under a random node transform (rotation,
non-uniform scale 0.5..2, shear up to 0.3, translation), with the coefficient frame itself
rotated at random (Q' = R Q R^T, P' = R P: the surface turns inside its own axis-aligned clip
box) and a random clip box. Deterministic for a seed. validate.py compares raycast on them with
quadric_reference.py (object-space float64).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from .cli import prog

# Canonical forms (Q diagonal, P, R) of each type; scaled later by random semi-axes.
CANONICAL = {
    "ellipsoid": ([1, 1, 1], [0, 0, 0], -1),
    "elliptic_paraboloid": ([1, 1, 0], [0, 0, -1], 0),
    "hyperbolic_paraboloid": ([1, -1, 0], [0, 0, -1], 0),
    "hyperboloid_one_sheet": ([1, 1, -1], [0, 0, 0], -1),
    "hyperboloid_two_sheets": ([-1, -1, 1], [0, 0, 0], -1),
    "cone": ([1, 1, -1], [0, 0, 0], 0),
    "elliptic_cylinder": ([1, 1, 0], [0, 0, 0], -1),
    "hyperbolic_cylinder": ([1, -1, 0], [0, 0, 0], -1),
    "parabolic_cylinder": ([1, 0, 0], [0, -1, 0], 0),
}


def random_rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def random_quadric(kind: str, rng):
    diag, p, r = CANONICAL[kind]
    axes = rng.uniform(0.5, 1.5, size=3)
    q = np.diag(np.array(diag, float) / axes**2)
    p = np.array(p, float) / axes
    rot = random_rotation(rng)
    q = rot @ q @ rot.T
    q = (q + q.T) / 2
    p = rot @ p
    half = rng.uniform(0.6, 2.0, size=3)
    centre = rng.uniform(-0.3, 0.3, size=3)
    ext = {"Q": q.flatten().tolist(), "P": p.tolist(), "R": float(r)}
    if kind != "ellipsoid" or rng.random() < 0.5:
        ext["bounds"] = {"min": (centre - half).tolist(), "max": (centre + half).tolist()}
    return ext


def random_matrix(rng, offset) -> list[float]:
    rot = random_rotation(rng)
    scale = np.diag(rng.uniform(0.5, 2.0, size=3))
    shear = np.eye(3)
    i, j = rng.choice(3, size=2, replace=False)
    shear[i, j] = rng.uniform(-0.3, 0.3)
    m = np.eye(4)
    m[:3, :3] = rot @ shear @ scale
    m[:3, 3] = offset + rng.uniform(-0.5, 0.5, size=3)
    return m.T.flatten().tolist()  # glTF matrices are column-major


def scene(rng) -> dict:
    nodes = []
    for i, kind in enumerate(CANONICAL):
        offset = np.array([(i % 3) * 7.0, (i // 3) * 7.0, 0.0]) - 7.0
        nodes.append(
            {
                "name": f"{kind}",
                "matrix": random_matrix(rng, offset),
                "extensions": {"RAYCAST_quadric": random_quadric(kind, rng)},
            }
        )
    return {
        "asset": {"version": "2.0", "generator": "raycast_tools random-quadrics"},
        "extensionsUsed": ["RAYCAST_quadric"],
        "extensionsRequired": ["RAYCAST_quadric"],
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
    }


def write_scenes(out: Path, count: int, seed: int) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    paths = []
    for k in range(count):
        path = out / f"random_quadrics_{seed}_{k}.gltf"
        path.write_text(json.dumps(scene(rng), indent=1))
        paths.append(path)
    return paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("random-quadrics"), description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--scenes", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    for path in write_scenes(args.out, args.scenes, args.seed):
        print(path)
    return 0
