#!/usr/bin/env python3
"""A test double for the raycast binary, used only to test `raycast_tools validate`'s plumbing.

It implements the rays-mode and camera-mode output contract of docs/buffers-and-cli.md
(depth/normal/id/prim .npy and a raycast.json with `objects` and `camera`) on top of
the references validate.py uses itself, so a correct validate.py must report it as
in tolerance.  `FAKE_RAYCAST_BREAK=depth|id|normal` perturbs one output so the
tests can check that validate.py notices.
"""

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

from raycast_tools.rays import camera_rays
from raycast_tools.reference import quadric_reference as qref
from raycast_tools.validate import validate


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--rays")
    ap.add_argument("--aov", default="depth")
    ap.add_argument("--out", required=True)
    ap.add_argument("--format", default="npy")
    ap.add_argument("--width", type=int, default=64)
    ap.add_argument("--height", type=int, default=64)
    ap.add_argument("--quiet", action="store_true")
    ap.add_argument("--allow-outside", action="store_true")  # the runner trusts its libraries
    a = ap.parse_args()
    ref = validate.load_reference(Path(a.scene))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    side = {"raycast_version": "fake", "scene": a.scene}
    if a.rays:
        rays = np.load(a.rays).astype(np.float64)
        o, d = rays[:, :3], rays[:, 3:]
        shape = (len(rays),)
        side.update(mode="rays", rays=len(rays))
    else:
        lo, hi = ref.bounds()
        c = 0.5 * (lo + hi)
        eye = c + np.array([0.3, 0.4, 1.0]) * np.linalg.norm(hi - lo)
        f = (c - eye) / np.linalg.norm(c - eye)
        r = np.cross(f, [0, 1, 0.0])
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        C = np.eye(4)
        C[:3, 0], C[:3, 1], C[:3, 2], C[:3, 3] = r, u, -f, eye
        cam = {
            "source": "auto",
            "type": "perspective",
            "yfov": 0.6,
            "aspect_ratio": a.width / a.height,
            "znear": 0.01,
            "zfar": None,
            "camera_to_world": C.tolist(),
        }
        o, _, d = camera_rays(cam, a.width, a.height)
        shape = (a.height, a.width)
        side.update(mode="camera", width=a.width, height=a.height, camera=cam)
    n = len(o)
    unit = d / np.linalg.norm(d, axis=1)[:, None]
    depth, tri, _ = validate.trace_f64(ref, o, unit)
    normal = np.zeros((n, 3))
    ok = tri >= 0
    normal[ok] = ref.normals[tri[ok]]
    ids = np.zeros(n, dtype=np.uint32)
    prim = np.full(n, 4294967295, dtype=np.uint32)
    ids[ok] = ref.tri_obj[tri[ok]] + 1
    prim[ok] = ref.tri_local[tri[ok]]
    objects = [
        {
            "id": k + 1,
            "name": ob.name,
            "kind": "mesh",
            "source": ob.key,
            "triangles": int(len(ob.tris)),
        }
        for k, ob in enumerate(ref.objects)
    ]
    if ref.quadrics:
        qr = qref.trace(ref.quadrics, o, d)
        base = len(objects)
        for k, q in enumerate(ref.quadrics):
            objects.append(
                {
                    "id": base + k + 1,
                    "name": q.name,
                    "kind": "quadric",
                    "source": f"/nodes/{q.node}",
                }
            )
        use = qr["depth"] < depth
        depth = np.where(use, qr["depth"], depth)
        normal[use] = qr["normal"][use]
        ids[use] = base + qr["index"][use] + 1
        prim[use] = 0
    brk = os.environ.get("FAKE_RAYCAST_BREAK")
    if brk == "depth":
        depth = depth * (1 + 1e-4)
    elif brk == "id":
        ids[ids > 0] = 1
    elif brk == "normal":
        normal = -normal
    aovs = a.aov.split(",")
    data = {"depth": depth, "normal": normal, "id": ids, "prim": prim}
    for k in aovs:
        v = data[k]
        np.save(out / f"{k}.npy", v.reshape(shape + v.shape[1:]))
    side.update(
        aovs=aovs,
        objects=objects,
        warnings=[],
        stats={
            "triangles": int(len(ref.tris)),
            "quadrics": len(ref.quadrics),
            "objects": len(objects),
        },
        timings={"load": 0, "build": 0, "trace": 0, "write": 0},
    )
    (out / "raycast.json").write_text(json.dumps(side))
    return 0


if __name__ == "__main__":
    sys.exit(main())
