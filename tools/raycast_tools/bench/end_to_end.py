"""End to end: a 1024x1024 depth render from the file, raycast's command line against Open3D
and trimesh + Embree doing the same from Python.

    python -m raycast_tools end-to-end [--side 1024] [--runs 3] [--out FILE]

The report goes to the repository's reports/end_to_end.md unless --out says otherwise.

Every method is a fresh process that reads the scene file, builds its acceleration structure,
casts one ray per pixel of the same pinhole camera (the bench's diagonal view, 40 degrees) and
writes the depth buffer as .npy; the figure is the whole process's wall time (interpreter
start-up and imports included for Python, as a user would wait for it), median of the runs.
The peers also report their own phase times. Scenes: the bunny (OBJ) and the helmet (GLB) of
fixtures/assets; the OpenChessSet from ../shared/assets for raycast only (neither peer reads
USD). Open3D (pip `open3d-cpu`, which needs Debian's libusb-1.0-0) is optional and skipped
with a message when it is not installed. The depth buffers are compared with raycast's as a
check that every method cast the same rays.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from raycast_tools.bench.bench import BUNNY, CHESS, HELMET, OPEN3D_MISSING
from raycast_tools.bench.machine import machine
from raycast_tools.cli import prog
from raycast_tools.paths import ROOT, raycast_or_exit
from raycast_tools.rays import FOV_DEGREES, framing, look_at_rays
from raycast_tools.runner import raycast_info

PEERS = ("open3d", "trimesh-embree")
NAMES = {
    "raycast": "raycast (CLI)",
    "open3d": "Open3D RaycastingScene",
    "trimesh-embree": "trimesh + Embree",
}


def peer(argv):
    """Runs inside the peer's own process: load, build, cast, write; prints phase times."""
    name, scene, out, eye, target, side = argv
    t = time.perf_counter()
    import trimesh

    if name == "open3d":
        import open3d as o3d
    phases = {"import_s": time.perf_counter() - t}
    t = time.perf_counter()
    mesh = trimesh.load(scene, force="mesh", process=False)
    eye, target = np.array(json.loads(eye)), np.array(json.loads(target))
    rays = look_at_rays(eye, target, FOV_DEGREES, int(side))
    phases["load_s"] = time.perf_counter() - t
    t = time.perf_counter()
    if name == "open3d":
        o3d_scene = o3d.t.geometry.RaycastingScene()
        o3d_scene.add_triangles(
            o3d.core.Tensor(mesh.vertices.astype(np.float32)),
            o3d.core.Tensor(mesh.faces.astype(np.uint32)),
        )
        depth = o3d_scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy().astype(np.float64)
    else:
        intersector = mesh.ray  # trimesh's Embree intersector when embreex is installed
        origins, dirs = rays[:, :3].astype(np.float64), rays[:, 3:].astype(np.float64)
        locations, index_ray, _ = intersector.intersects_location(
            origins, dirs, multiple_hits=False
        )
        depth = np.full(len(rays), np.inf)
        depth[index_ray] = np.linalg.norm(locations - origins[index_ray], axis=1)
        phases["intersector"] = type(intersector).__module__
    phases["build_and_cast_s"] = time.perf_counter() - t
    t = time.perf_counter()
    np.save(out, depth.reshape(int(side), int(side)))
    phases["write_s"] = time.perf_counter() - t
    print(json.dumps(phases))


def timed(cmd):
    """(wall seconds, completed process) of one run."""
    t = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True)
    return time.perf_counter() - t, res


def run_raycast(exe, scene, eye, target, side, tmp, runs):
    walls, sidecar = [], None
    for _ in range(runs):
        out = tmp / "raycast"
        cmd = [str(exe), str(scene), "--aov", "depth", "--format", "npy", "--quiet"]
        cmd += ["--width", str(side), "--height", str(side), "--out", str(out)]
        cmd += ["--eye", ",".join(map(repr, eye)), "--target", ",".join(map(repr, target))]
        cmd += ["--fov", repr(FOV_DEGREES)]
        wall, res = timed(cmd)
        if res.returncode != 0:
            return {"error": res.stderr.strip()[-500:]}
        walls.append(wall)
        sidecar = json.loads((out / "raycast.json").read_text())
    depth = np.load(tmp / "raycast" / "depth.npy")
    return {"wall_s": walls, "phases": sidecar["timings"], "depth": depth}


def run_peer(name, scene, eye, target, side, tmp, runs):
    if name == "open3d":
        try:
            import open3d  # noqa: F401
        except ImportError:
            return {"skipped": OPEN3D_MISSING}
    walls, phases = [], None
    out = tmp / f"{name}.npy"
    for _ in range(runs):
        cmd = [sys.executable, "-m", "raycast_tools", "end-to-end", "--peer", name, str(scene)]
        cmd += [str(out), json.dumps(list(eye)), json.dumps(list(target)), str(side)]
        wall, res = timed(cmd)
        if res.returncode != 0:
            return {"error": res.stderr.strip()[-500:]}
        walls.append(wall)
        phases = json.loads(res.stdout.strip().splitlines()[-1])
    return {"wall_s": walls, "phases": phases, "depth": np.load(out)}


def agreement(depth, reference):
    """Pixels whose hit or miss differs, and the largest depth difference where both hit."""
    hit, ref_hit = np.isfinite(depth), np.isfinite(reference)
    both = hit & ref_hit
    diff = float(np.abs(depth[both] - reference[both]).max()) if both.any() else 0.0
    return int((hit != ref_hit).sum()), diff


def measure(exe, title, scene, peers, side, runs):
    info = raycast_info(exe, scene)
    lo, hi = (np.array(v, dtype=np.float64) for v in info["bounds"])
    eye, target = (v.tolist() for v in framing(lo, hi))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        results = {"raycast": run_raycast(exe, scene, eye, target, side, tmp, runs)}
        for name in peers:
            results[name] = run_peer(name, scene, eye, target, side, tmp, runs)
    reference = results["raycast"].get("depth")
    for name, r in results.items():
        row = {"scene": title, "method": name}
        if "depth" in r:
            row["wall_s"] = r["wall_s"]
            row["median_s"] = statistics.median(r["wall_s"])
            row["phases"] = r["phases"]
            row["hits"] = float(np.isfinite(r["depth"]).mean())
            if reference is not None and name != "raycast":
                row["hit_miss_differ"], row["max_depth_diff"] = agreement(r["depth"], reference)
        else:
            row.update({k: v for k, v in r.items() if k in ("error", "skipped")})
        rows.append(row)
        print(f"end-to-end: {title} {name}: {row.get('median_s', row)}", file=sys.stderr)
    return rows


def report(rows, side, runs, host):
    load = " ".join(f"{x:.1f}" for x in host["loadavg"] or ())
    lines = [
        f"# End to end: a {side}×{side} depth render from the file",
        "",
        "Regenerate with `.venv/bin/python -m raycast_tools end-to-end`; raw figures in "
        "`reports/end_to_end.json`.",
        "",
        f"Machine: {host['nproc']} cores, {host['cpu']}, {host['memory_gib']} GiB, Python "
        f"{host['python']}, load average {load} at the end. Each figure is the wall time of a "
        f"fresh process (median of {runs}) "
        "that reads the file, builds, casts one ray per pixel and writes depth as .npy; Python "
        "start-up and imports are included, as a user waits for them. Every method uses all "
        "cores by default. Wall times on this shared machine vary by ±30%.",
        "",
        "| scene | method | wall s (median) | without imports s | runs | phases | hits "
        "| vs raycast |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        name = NAMES[r["method"]]
        if "median_s" not in r:
            lines.append(
                f"| {r['scene']} | {name} | – | – | – | {r.get('skipped') or r.get('error')} | – "
                "| – |"
            )
            continue
        phases = ", ".join(
            f"{k.removesuffix('_s')} {v:.3f}" for k, v in r["phases"].items() if k != "intersector"
        )
        runs_text = ", ".join(f"{w:.2f}" for w in r["wall_s"])
        versus = (
            f"{r['hit_miss_differ']} pixels hit/miss differ, depth Δ ≤ {r['max_depth_diff']:.1e}"
            if "hit_miss_differ" in r
            else "–"
        )
        bare = r["median_s"] - r["phases"].get("import_s", 0.0)
        lines.append(
            f"| {r['scene']} | {name} | {r['median_s']:.2f} | {bare:.2f} | {runs_text} "
            f"| {phases} | {r['hits']:.0%} | {versus} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["--peer"]:
        peer(argv[1:])
        return 0
    ap = argparse.ArgumentParser(prog=prog("end-to-end"), description=__doc__.split("\n\n")[0])
    ap.add_argument("--side", type=int, default=1024, help="image side in pixels (default 1024)")
    ap.add_argument("--runs", type=int, default=3, help="runs per method (default 3)")
    ap.add_argument("--raycast", help="raycast binary (default: target/release/raycast)")
    ap.add_argument("--out", type=Path, default=ROOT / "reports/end_to_end.md")
    args = ap.parse_args(argv)
    exe = raycast_or_exit(args.raycast, "end-to-end")
    scenes = [("bunny (OBJ)", BUNNY, PEERS), ("DamagedHelmet (GLB)", HELMET, PEERS)]
    if CHESS.exists():
        scenes.append(("OpenChessSet (USD)", CHESS, ()))
    else:
        print(f"end-to-end: {CHESS} not found; the chess set is skipped", file=sys.stderr)
    rows = []
    for title, scene, peers in scenes:
        rows += measure(exe, title, scene, peers, args.side, args.runs)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".json").write_text(json.dumps(rows, indent=1) + "\n")
    args.out.write_text(report(rows, args.side, args.runs, machine()))
    print(f"end-to-end: wrote {args.out}", file=sys.stderr)
    return 0
