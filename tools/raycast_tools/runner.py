"""Running the raycast binary and reading what it wrote (docs/buffers-and-cli.md)."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

import numpy as np

AOVS = ("depth", "t", "normal", "id", "prim", "error", "certain")


def run_raycast(raycast, scene, args, out) -> dict:
    """`raycast SCENE ARGS... --out OUT --quiet`: each AOV file it wrote (depth, normal, id,
    prim) as an array, `sidecar` (raycast.json) and `wall` (whole-process seconds).
    Raises RuntimeError with raycast's last line of output when it fails. The scenes compared
    are trusted fixtures and libraries (usd-wg's test assets reference `../../../_common`), so
    external files are read wherever they are (`--allow-outside`)."""
    out = Path(out)
    cmd = [str(raycast), str(scene), *args, "--allow-outside", "--out", str(out), "--quiet"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        msg = (p.stderr.strip() or p.stdout.strip()).splitlines()
        raise RuntimeError(f"raycast exit {p.returncode}: {msg[-1] if msg else ''}")
    res = {"wall": wall}
    for aov in AOVS:
        f = out / f"{aov}.npy"
        if f.exists():
            res[aov] = np.load(f)
    res["sidecar"] = json.loads((out / "raycast.json").read_text())
    return res


def run_rays(
    raycast, scene, origins, dirs, workdir, threads=None, aov="depth,normal,id,prim", out_name="out"
) -> dict:
    """raycast in rays mode: writes WORKDIR/rays.npy (float64 origin|direction rows), runs
    raycast into WORKDIR/OUT_NAME and returns run_raycast's dict."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    rays = workdir / "rays.npy"
    np.save(rays, np.concatenate([origins, dirs], axis=1).astype(np.float64))
    args = ["--rays", str(rays), "--aov", aov]
    if threads:
        args += ["--threads", str(threads)]
    return run_raycast(raycast, scene, args, workdir / out_name)


def raycast_info(raycast, scene) -> dict:
    """`raycast info SCENE --json --allow-outside` (see run_raycast), parsed."""
    res = subprocess.run(
        [str(raycast), "info", str(scene), "--json", "--allow-outside"],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(res.stdout)
