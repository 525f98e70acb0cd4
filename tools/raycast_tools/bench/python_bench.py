"""End-to-end Python comparison on the bunny: `raycast.load` + `Scene.cast` against trimesh's
`intersects_location` (Embree through embreex, and its pure-numpy intersector on a subset)
and, when it is installed, Open3D's `RaycastingScene.cast_rays`, on the same rays; the
per-ray cost of `cast()` against the command line's own trace time (raycast.json); and
distance queries (closest points, signed distance) on the same points against Open3D's.

Writes reports/python_bench.md (and .json). Wall times on a shared machine: medians of
several runs, interleaved.

Usage: python -m raycast_tools python-bench [--rays N] [--runs K] [--raycast BIN]
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from raycast_tools import paths, rays, runner
from raycast_tools.bench import machine

BUNNY = paths.ROOT / "fixtures/assets/stanford-bunny.obj"
REPORT = paths.ROOT / "reports/python_bench.md"
#: Where the report's sections written by hand begin; regenerating keeps them.
HAND = "## By hand"


def timed(fn, runs):
    """Median wall seconds of `runs` calls of `fn`, and its last result."""
    times, result = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def ray_sets(lo, hi, n, seed):
    """Coherent (a pinhole camera) and incoherent (random) rays: float64 origins, directions."""
    side = int(round(np.sqrt(n)))
    sets = {
        "coherent": rays.pinhole_rays(lo, hi, side),
        "incoherent": rays.random_rays(lo, hi, side * side, np.random.default_rng(seed)),
    }
    return {k: (v[:, :3].astype(np.float64), v[:, 3:].astype(np.float64)) for k, v in sets.items()}


def engines(mesh_path, subset):
    """name -> (setup() -> state, cast(state, origins, directions) -> distances)."""
    import trimesh

    import raycast

    def rc_setup():
        return raycast.load(mesh_path)

    def rc_cast(scene, o, d):
        return scene.cast(o, d, aovs=("distance",))["distance"]

    def tm_setup(kind):
        mesh = trimesh.load(mesh_path, force="mesh", process=False)
        if kind == "embree":
            intersector = trimesh.ray.ray_pyembree.RayMeshIntersector(mesh)
        else:
            intersector = trimesh.ray.ray_triangle.RayMeshIntersector(mesh)
        # Both build their structure (Embree scene, r-tree) on the first query: part of setup.
        intersector.intersects_any([mesh.centroid], [[0.0, 0.0, 1.0]])
        return intersector

    def tm_cast(intersector, o, d):
        loc, index_ray, _ = intersector.intersects_location(o, d, multiple_hits=False)
        out = np.full(len(o), np.inf)
        out[index_ray] = np.linalg.norm(np.reshape(loc, (-1, 3)) - o[index_ray], axis=1)
        return out

    found = {
        "raycast (load + cast)": (rc_setup, rc_cast, None),
        "trimesh + embreex (intersects_location)": (lambda: tm_setup("embree"), tm_cast, None),
        "trimesh ray_triangle (intersects_location)": (
            lambda: tm_setup("numpy"),
            tm_cast,
            subset,
        ),
    }
    try:
        import open3d as o3d

        def o3d_setup():
            mesh = o3d.io.read_triangle_mesh(str(mesh_path))
            scene = o3d.t.geometry.RaycastingScene()
            scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(mesh))
            return scene

        def o3d_cast(scene, o, d):
            r = np.concatenate([o, d], axis=1).astype(np.float32)
            t = scene.cast_rays(o3d.core.Tensor(r))["t_hit"].numpy().astype(np.float64)
            return t * np.linalg.norm(d, axis=1)

        found["Open3D RaycastingScene (cast_rays)"] = (o3d_setup, o3d_cast, None)
    except ImportError:
        pass
    return found


def measure(n, runs, binary, seed=1):
    import raycast

    scene = raycast.load(BUNNY)
    lo, hi = scene.bounds
    sets = ray_sets(lo, hi, n, seed)
    results = {"rays": {k: len(v[0]) for k, v in sets.items()}, "engines": {}, "cli": {}}
    subset = max(1, len(sets["coherent"][0]) // 200)
    for name, (setup, cast, limit) in engines(BUNNY, subset).items():
        setup_s, state = timed(setup, runs)
        entry = {"setup_s": setup_s}
        for kind, (o, d) in sets.items():
            m = limit or len(o)
            cast_s, dist = timed(lambda: cast(state, o[:m], d[:m]), runs)
            reference = scene.cast(o[:m], d[:m], aovs=("distance",))["distance"]
            both = np.isfinite(dist) & np.isfinite(reference)
            entry[kind] = {
                "rays": m,
                "cast_s": cast_s,
                "ns_per_ray": cast_s / m * 1e9,
                "hit_agreement": float(np.mean(np.isfinite(dist) == np.isfinite(reference))),
                "max_distance_difference": float(np.max(np.abs(dist[both] - reference[both])))
                if both.any()
                else 0.0,
            }
        results["engines"][name] = entry
    with tempfile.TemporaryDirectory() as tmp:
        for kind, (o, d) in sets.items():
            traces = []
            for i in range(runs):
                res = runner.run_rays(
                    binary, BUNNY, o, d, Path(tmp) / kind, aov="depth", out_name=f"out{i}"
                )
                traces.append(res["sidecar"]["timings"]["trace"])
            trace = statistics.median(traces)
            results["cli"][kind] = {"trace_s": trace, "ns_per_ray": trace / len(o) * 1e9}
    results["machine"] = machine.machine()
    return results


def measure_distances(n, runs, seed=2):
    """Closest points and signed distances of `n` points around the bunny, raycast and (when
    installed) Open3D, with their agreement."""
    import raycast

    scene = raycast.load(BUNNY)
    lo, hi = scene.bounds
    pad = 0.1 * (hi - lo)
    points = np.random.default_rng(seed).uniform(lo - pad, hi + pad, (n, 3))
    out = {"points": n, "closed": [o["closed"] for o in scene.info()["objects"]]}
    closest_s, found = timed(lambda: scene.closest_points(points), runs)
    signed_s, signed = timed(lambda: scene.signed_distance(points), runs)
    out["raycast"] = {"closest_s": closest_s, "signed_s": signed_s}
    try:
        import open3d as o3d
    except ImportError:
        return out
    mesh = o3d.io.read_triangle_mesh(str(BUNNY))
    o3d_scene = o3d.t.geometry.RaycastingScene()
    o3d_scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(mesh))
    query = o3d.core.Tensor(points.astype(np.float32))
    closest_s, theirs = timed(lambda: o3d_scene.compute_closest_points(query), runs)
    signed_s, their_signed = timed(lambda: o3d_scene.compute_signed_distance(query), runs)
    their_distance = np.linalg.norm(theirs["points"].numpy() - points.astype(np.float32), axis=1)
    their_signed = their_signed.numpy().astype(np.float64)
    certain = signed != 0
    out["open3d"] = {
        "closest_s": closest_s,
        "signed_s": signed_s,
        "max_distance_difference": float(np.max(np.abs(their_distance - found["distance"]))),
        "same_triangle": float(np.mean(theirs["primitive_ids"].numpy() == found["prim"])),
        "sign_agreement": float(
            np.mean(np.sign(their_signed[certain]) == np.sign(signed[certain]))
        ),
        "raycast_sign_zero": int(np.sum(~certain)),
    }
    return out


def distance_lines(d) -> list[str]:
    """The report's section on distance queries."""
    n = d["points"]
    lines = [
        "",
        "## Distances",
        "",
        f"{n:,} points uniform in the bunny's box grown by 10 % on each side, float64 for "
        "raycast, float32 for Open3D (its only precision). Medians of the runs; all threads. "
        f"The bunny is {'closed' if all(d['closed']) else 'not closed'} by `info`'s test "
        "(it has holes in its base), so neither engine's sign is certain everywhere here: "
        "the sign agreement below compares two parity votes.",
        "",
        "| engine | closest points Mpoints/s | signed distance Mpoints/s |",
        "| --- | --- | --- |",
    ]
    for name in ("raycast", "open3d"):
        if name in d:
            e = d[name]
            lines.append(
                f"| {'raycast' if name == 'raycast' else 'Open3D RaycastingScene'} | "
                f"{n / e['closest_s'] / 1e6:.2f} | {n / e['signed_s'] / 1e6:.2f} |"
            )
    if "open3d" in d:
        o = d["open3d"]
        lines += [
            "",
            f"Agreement: largest distance difference {o['max_distance_difference']:.2e} "
            f"(Open3D's float32), same nearest triangle for {o['same_triangle']:.4f} of the "
            f"points (ties and float32 near-ties aside), same sign for {o['sign_agreement']:.4f} "
            f"of the points raycast gives a sign ({o['raycast_sign_zero']} points within its "
            "rounding margin get 0).",
        ]
    else:
        lines += ["", "Open3D was not installed in this environment: no Open3D row."]
    return lines


def report(r) -> str:
    lines = [
        "# Python end to end on the bunny",
        "",
        "`python -m raycast_tools python-bench` (tools/raycast_tools/bench/python_bench.py): the "
        "Stanford bunny (fixtures/assets/stanford-bunny.obj), the same float64 rays for every "
        "engine, coherent (a pinhole camera framing the bunny) and incoherent (origins in its "
        "box, random directions). *setup* is loading the file and building the structure; "
        "*cast* is the query alone, returning hit distances. Medians of the runs; all threads.",
        "",
        "| engine | setup s | coherent ns/ray | incoherent ns/ray | rays | "
        "hit agreement with raycast | max distance difference |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    for name, e in r["engines"].items():
        c, i = e["coherent"], e["incoherent"]
        lines.append(
            f"| {name} | {e['setup_s']:.3f} | {c['ns_per_ray']:.0f} | {i['ns_per_ray']:.0f} | "
            f"{c['rays']} | {min(c['hit_agreement'], i['hit_agreement']):.4f} | "
            f"{max(c['max_distance_difference'], i['max_distance_difference']):.2e} |"
        )
    cli = r["cli"]
    rc = r["engines"]["raycast (load + cast)"]
    lines += [
        "",
        "## `cast()` against the command line's trace",
        "",
        "The CLI's `timings.trace` (raycast.json) covers tracing only (no load, build or write); "
        "`cast()` here includes checking the rays, tracing and filling the `distance` array.",
        "",
        "| rays | CLI trace ns/ray | cast() ns/ray | ratio cast/CLI |",
        "| --- | --- | --- | --- |",
    ]
    for kind in ("coherent", "incoherent"):
        ours, theirs = rc[kind]["ns_per_ray"], cli[kind]["ns_per_ray"]
        lines.append(f"| {kind} | {theirs:.0f} | {ours:.0f} | {ours / theirs:.2f} |")
    if not any("Open3D" in k for k in r["engines"]):
        lines += ["", "Open3D was not installed in this environment: no Open3D row."]
    if "distances" in r:
        lines += distance_lines(r["distances"])
    m = r["machine"]
    lines += [
        "",
        f"Machine: {m['nproc']} CPUs ({m['cpu']}), {m['memory_gib']} GiB, load average "
        f"{m['loadavg']}; Python {m.get('python', '?')}. The machine is shared: wall times "
        "vary by some 30 %.",
        "",
    ]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m raycast_tools python-bench", description=__doc__
    )
    parser.add_argument("--rays", type=int, default=262144, help="rays per set (default 512^2)")
    parser.add_argument("--runs", type=int, default=3, help="runs per measurement (median)")
    parser.add_argument(
        "--points", type=int, default=1_000_000, help="query points for distances (default 1M)"
    )
    parser.add_argument("--raycast", help="raycast binary (default: target/release/raycast)")
    parser.add_argument("--out", type=Path, default=REPORT, help="report path (.md; .json beside)")
    args = parser.parse_args(argv)
    binary = paths.raycast_or_exit(args.raycast, "python-bench")
    results = measure(args.rays, args.runs, binary)
    results["distances"] = measure_distances(args.points, args.runs)
    # Sections written by hand after the generated ones (from "## By hand" on) are kept.
    kept = ""
    if args.out.exists():
        text = args.out.read_text()
        at = text.find(HAND)
        kept = text[at:] if at >= 0 else ""
    args.out.write_text(report(results) + ("\n" + kept if kept else ""))
    args.out.with_suffix(".json").write_text(json.dumps(results, indent=1) + "\n")
    print(f"wrote {args.out}")
    return 0
