"""Benchmark raycast's octree against its obvhs backends, Embree (embreex: its robust and its
fast kernel), Open3D and trimesh.

    .venv/bin/python -m raycast_tools bench [--quick] [--big] [--out reports/bench.md]

Builds the Rust benchmark binary (benches/trace.rs), generates the scenes and ray sets in a
temporary folder, runs every method on the same rays (one process per scene and side), and
writes reports/bench.md plus the raw figures as reports/bench.json. Open3D's RaycastingScene is
an optional peer: install `open3d-cpu` (pip; it needs Debian's libusb-1.0-0) to include it, else
it is skipped with a message.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from raycast_tools.bench.machine import machine as machine_base
from raycast_tools.cli import prog
from raycast_tools.fixtures.gltf_writer import UNSIGNED_INT, Gltf
from raycast_tools.paths import RELEASE, ROOT
from raycast_tools.rays import in_tiles, pinhole_rays, random_rays
from raycast_tools.runner import raycast_info

BUNNY = ROOT / "fixtures/assets/stanford-bunny.obj"
HELMET = ROOT / "fixtures/assets/DamagedHelmet.glb"
# Too big for fixtures/: read from the shared assets next to the checkout when they are there.
CHESS = ROOT.parent / "shared/assets/usd/full_assets/OpenChessSet/chess_set.usda"


# ----------------------------------------------------------------------------- scenes


def load_triangles(path):
    """World-space triangles (N, 3, 3) float64 of an OBJ or glTF, through trimesh."""
    import trimesh

    if path.suffix == ".obj":
        mesh = trimesh.load(path, process=False)
    else:
        scene = trimesh.load(path, force="scene")
        mesh = (
            scene.to_geometry() if hasattr(scene, "to_geometry") else scene.dump(concatenate=True)
        )
    return np.asarray(mesh.triangles, dtype=np.float64)


def usd_triangles(path):
    """World-space triangles (N, 3, 3) float64 of a USD stage's meshes, placed by usd-core with
    raycast's drawing rules (usd_stage.flatten)."""
    from raycast_tools.reference.usd_stage import flatten, open_stage

    parts = [
        np.asarray(t, dtype=np.float64).reshape(-1, 3, 3)
        for _, t in flatten(open_stage(path))
        if len(t)
    ]
    return np.concatenate(parts)


def write_gltf(path, mesh_tris, nodes, quadrics=()):
    """A glTF (+ .bin) with one mesh (`mesh_tris`, (N,3,3), vertices shared where equal in
    float32) instanced at `nodes` (translation, scale) and `quadrics` nodes (coefficients,
    translation, scale)."""
    g = Gltf("raycast bench")
    roots = []
    if len(mesh_tris) and len(nodes):
        flat = mesh_tris.reshape(-1, 3).astype(np.float32)
        verts, index = np.unique(flat, axis=0, return_inverse=True)
        m = g.mesh(
            "mesh",
            [
                {
                    "attributes": {"POSITION": g.positions(verts)},
                    "indices": g.indices(index.reshape(-1), UNSIGNED_INT),
                }
            ],
        )
        roots += [
            g.node(f"copy{i}", mesh=m, translation=[float(x) for x in t], scale=[s, s, s])
            for i, (t, s) in enumerate(nodes)
        ]
    if len(quadrics):
        g.doc["extensionsUsed"].append("RAYCAST_quadric")
        roots += [
            g.node(
                f"q{i}",
                translation=[float(x) for x in t],
                scale=[float(x) for x in s],
                extensions={"RAYCAST_quadric": {"coefficients": coeffs}},
            )
            for i, (coeffs, t, s) in enumerate(quadrics)
        ]
    g.scene(roots)
    bin_path = path.with_suffix(".bin")
    doc, data = g.finish(bin_path.name)
    if data:
        bin_path.write_bytes(data)
    path.write_text(json.dumps(doc))


def instances(tris, copies, rng):
    """Grid placements of `copies` instances of `tris`, and the world triangles."""
    lo, hi = tris.reshape(-1, 3).min(0), tris.reshape(-1, 3).max(0)
    step = (hi - lo).max() * 1.1
    side = int(np.ceil(copies ** (1 / 3)))
    nodes, world = [], []
    for k in range(copies):
        cell = np.array([k % side, (k // side) % side, k // (side * side)], dtype=float)
        t = cell * step + rng.uniform(-0.05, 0.05, 3) * step
        nodes.append((t, 1.0))
        world.append(tris.astype(np.float32).astype(np.float64) + t)
    return nodes, np.concatenate(world)


def random_quadrics(count, rng, extent):
    sphere = [1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0]
    size = extent / count ** (1 / 3) * 0.35
    return [
        (sphere, rng.uniform(0, extent, 3), rng.uniform(0.3, 1.0, 3) * size) for _ in range(count)
    ]


# ----------------------------------------------------------------------------- rays


def bounds_of(rust_info):
    return np.array(rust_info["bounds"][0]), np.array(rust_info["bounds"][1])


# ----------------------------------------------------------------------------- peers


def peak_mib():
    """This process's peak RSS (VmHWM; ru_maxrss would carry the parent's peak across exec)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def median_time(fn, runs):
    fn()  # warm-up
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times)), times


def trace_record(rays, count, threads, median_s, runs_s, hit_ratio):
    """One peer's figures for one ray set and thread count."""
    return {
        "rays": rays,
        "count": count,
        "threads": threads,
        "median_s": median_s,
        "runs_s": runs_s,
        "mrays_per_s": count / median_s / 1e6,
        "hit_ratio": hit_ratio,
    }


def rss_mib():
    """This process's resident memory now (VmRSS)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def embree_method(tris, sets, spec, robust):
    """Embree through embreex on the same rays, with its robust kernel (embreex's default scene
    flag) or its fast one: build (the first call's `rtcCommitScene`), traces, and the resident
    memory the scene added (embreex's copy of the triangles and Embree's BVH)."""
    import embreex.mesh_construction as mc
    import embreex.rtcore_scene as rs

    # A one-triangle scene first, traced: the library's code and Embree's device are paged in
    # before the measured scene, so its resident growth is the scene's own.
    warm = rs.EmbreeScene(robust=robust)
    mc.TriangleMesh(warm, np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=np.float32))
    warm.run(np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32), output=1)
    before = rss_mib()
    scene = rs.EmbreeScene(robust=robust)
    mc.TriangleMesh(scene, tris)
    probe = sets[next(iter(sets))][:1]
    t = time.perf_counter()
    scene.run(probe[:, :3].copy(), probe[:, 3:].copy(), output=1)  # rtcCommitScene happens here
    commit = time.perf_counter() - t
    growth = rss_mib() - before
    traces = []
    for name, rays in sets.items():
        o, d = np.ascontiguousarray(rays[:, :3]), np.ascontiguousarray(rays[:, 3:])
        hits = float((scene.run(o, d, output=1)["primID"] >= 0).mean())
        for threads in spec["threads"]:
            parts = np.array_split(np.arange(len(rays)), threads)

            def run_all():
                if threads == 1:
                    scene.run(o, d, output=1)
                    return
                workers = [
                    threading.Thread(target=scene.run, args=(o[p], d[p]), kwargs={"output": 1})
                    for p in parts
                ]
                for w in workers:
                    w.start()
                for w in workers:
                    w.join()

            m, times = median_time(run_all, spec["runs"])
            traces.append(trace_record(name, len(rays), threads, m, times, hits))
    return {
        "backend": "embreex" if robust else "embreex-fast",
        "build_s": commit,
        "traces": traces,
        "peak_rss_mib": peak_mib(),
        "scene_rss_mib": growth,
    }


def peer_worker(spec):
    """Runs in its own process: Embree (robust and fast kernels) through embreex, Open3D and
    trimesh on one scene."""
    import trimesh

    tris = np.load(spec["triangles"]).astype(np.float32)
    out = {"methods": []}
    sets = {name: np.load(path) for name, path in spec["rays"].items()}
    # Each Embree scene is released (the method returns) before the next peer builds its own.
    out["methods"].append(embree_method(tris, sets, spec, robust=True))
    out["methods"].append(embree_method(tris, sets, spec, robust=False))
    out["methods"].append(open3d_method(tris, sets, spec))

    mesh = trimesh.Trimesh(
        vertices=tris.reshape(-1, 3).astype(np.float64),
        faces=np.arange(len(tris) * 3).reshape(-1, 3),
        process=False,
    )
    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector as EmbreeRMI

        rmi = EmbreeRMI(mesh)
        t = time.perf_counter()
        _ = rmi._scene  # builds the embree scene
        build = time.perf_counter() - t
        traces = []
        for name, rays in sets.items():
            o, d = rays[:, :3].astype(np.float64), rays[:, 3:].astype(np.float64)
            first = rmi.intersects_first(o[:1], d[:1])
            del first
            m, times = median_time(lambda: rmi.intersects_first(o, d), max(1, spec["runs"] - 1))
            hits = float((rmi.intersects_first(o, d) >= 0).mean())
            traces.append(
                {
                    "rays": name,
                    "count": len(rays),
                    "threads": 1,
                    "median_s": m,
                    "runs_s": times,
                    "mrays_per_s": len(rays) / m / 1e6,
                    "hit_ratio": hits,
                }
            )
        out["methods"].append(
            {
                "backend": "trimesh-embree",
                "build_s": build,
                "traces": traces,
                "peak_rss_mib": peak_mib(),
            }
        )
    except Exception as e:  # noqa: BLE001
        out["methods"].append({"backend": "trimesh-embree", "error": repr(e)})

    if spec["f64_rays"] and len(tris) <= spec["f64_max_triangles"]:
        from trimesh.ray.ray_triangle import RayMeshIntersector as F64RMI

        rmi = F64RMI(mesh)
        traces = []
        t = time.perf_counter()
        _ = mesh.triangles_tree  # rtree of the triangles
        build = time.perf_counter() - t
        for name, rays in sets.items():
            sub = rays[:: max(1, len(rays) // spec["f64_rays"])][: spec["f64_rays"]]
            o, d = sub[:, :3].astype(np.float64), sub[:, 3:].astype(np.float64)
            t = time.perf_counter()
            hit = rmi.intersects_first(o, d)
            s = time.perf_counter() - t
            traces.append(
                {
                    "rays": name,
                    "count": len(sub),
                    "threads": 1,
                    "median_s": s,
                    "mrays_per_s": len(sub) / s / 1e6,
                    "hit_ratio": float((hit >= 0).mean()),
                    "subset": True,
                }
            )
        out["methods"].append(
            {
                "backend": "trimesh-f64",
                "build_s": build,
                "traces": traces,
                "peak_rss_mib": peak_mib(),
            }
        )
    print(json.dumps(out))


OPEN3D_MISSING = "open3d not installed (pip install open3d-cpu; it needs Debian's libusb-1.0-0)"


def open3d_method(tris, sets, spec):
    """Open3D's RaycastingScene on the same rays: build (at the first cast) and traces."""
    try:
        import open3d as o3d
    except ImportError:
        return {"backend": "open3d", "skipped": OPEN3D_MISSING}
    vertices = o3d.core.Tensor(tris.reshape(-1, 3).astype(np.float32))
    faces = o3d.core.Tensor(np.arange(len(tris) * 3, dtype=np.uint32).reshape(-1, 3))
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(vertices, faces)
    probe = o3d.core.Tensor(sets[next(iter(sets))][:1].astype(np.float32))
    t = time.perf_counter()
    scene.cast_rays(probe)  # the scene is committed here
    build = time.perf_counter() - t
    traces = []
    for name, rays in sets.items():
        tensor = o3d.core.Tensor(np.ascontiguousarray(rays, dtype=np.float32))
        hits = float(np.isfinite(scene.cast_rays(tensor)["t_hit"].numpy()).mean())
        for threads in spec["threads"]:
            m, times = median_time(lambda: scene.cast_rays(tensor, nthreads=threads), spec["runs"])
            traces.append(trace_record(name, len(rays), threads, m, times, hits))
    return {
        "backend": "open3d",
        "version": o3d.__version__,
        "build_s": build,
        "traces": traces,
        "peak_rss_mib": peak_mib(),
    }


# ----------------------------------------------------------------------------- driver


def cargo_bench_binary():
    cmd = ["cargo", "bench", "--bench", "trace", "--no-run", "--message-format=json"]
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True)
    for line in res.stdout.splitlines():
        msg = json.loads(line)
        if (
            msg.get("reason") == "compiler-artifact"
            and msg.get("executable")
            and msg["target"]["name"] == "trace"
        ):
            return msg["executable"]
    raise SystemExit("bench: no trace executable from cargo")


def run_rust(exe, scene, rays, args):
    cmd = [exe, str(scene)] + [x for n, p in rays.items() for x in ("--rays", f"{n}={p}")] + args
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"bench: {' '.join(cmd)} failed:\n{res.stderr}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def run_peers(spec, tmp):
    spec_path = tmp / "peer_spec.json"
    spec_path.write_text(json.dumps(spec))
    res = subprocess.run(
        [sys.executable, "-m", "raycast_tools", "bench", "--peer-worker", str(spec_path)],
        capture_output=True,
        text=True,
    )
    if res.returncode != 0:
        return {"methods": [], "error": res.stderr[-2000:]}
    return json.loads(res.stdout.strip().splitlines()[-1])


def merge_rounds(rounds):
    """One result from several rounds of the same runs (run_rust's or run_peers' output): a
    median_s or build_s becomes the median over the rounds, runs_s lists every round's runs,
    mrays_per_s follows the median; everything else is the first round's."""
    first = rounds[0]
    if isinstance(first, dict):
        out = {}
        for key, value in first.items():
            if key in ("median_s", "build_s") and isinstance(value, (int, float)):
                out[key] = float(np.median([r[key] for r in rounds]))
            elif key == "runs_s":
                out[key] = [x for r in rounds for x in r[key]]
            else:
                out[key] = merge_rounds([r[key] for r in rounds])
        if "median_s" in out and "count" in out and out["median_s"] > 0:
            out["mrays_per_s"] = out["count"] / out["median_s"] / 1e6
        return out
    same_shape = all(isinstance(r, list) and len(r) == len(first) for r in rounds)
    if isinstance(first, list) and same_shape:
        return [merge_rounds(list(items)) for items in zip(*rounds)]
    return first


def machine():
    """machine.machine() and the Rust compiler's version."""
    rustc = subprocess.run(["rustc", "--version"], capture_output=True, text=True).stdout.strip()
    return {**machine_base(), "rustc": rustc}


def main(argv=None):
    ap = argparse.ArgumentParser(prog=prog("bench"), description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller ray sets, fewer runs and scenes")
    ap.add_argument("--big", action="store_true", help="add the 20M-triangle scene (slow)")
    ap.add_argument("--out", default=str(ROOT / "reports/bench.md"))
    ap.add_argument(
        "--rounds",
        type=int,
        default=1,
        help="run each scene's Rust process and peer process this many times, alternating, "
        "and report medians over the rounds (both sides then see the same phases of a "
        "shared machine)",
    )
    ap.add_argument("--peer-worker", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.peer_worker:
        peer_worker(json.loads(Path(a.peer_worker).read_text()))
        return 0

    started = time.time()
    exe = cargo_bench_binary()
    if not RELEASE.exists():
        subprocess.run(["cargo", "build", "--release"], cwd=ROOT, check=True)
    rng = np.random.default_rng(1234)
    quick = a.quick
    cam_side = 512 if quick else 1024
    n_random = 250_000 if quick else 1_000_000
    runs = 2 if quick else 3
    threads = [1, 2] if os.cpu_count() >= 2 else [1]
    tmp = Path(tempfile.mkdtemp(prefix="raycast-bench-"))
    bunny = load_triangles(BUNNY)

    scenes = []  # (key, title, path, triangles for peers or None, size-sweep member)
    scenes.append(("bunny", "stanford-bunny (OBJ)", BUNNY, bunny))
    scenes.append(("helmet", "DamagedHelmet (glb)", HELMET, load_triangles(HELMET)))
    missing = []
    if not quick and CHESS.exists():
        scenes.append(
            (
                "chess",
                "OpenChessSet (USD: payloads, crate geometry, instanced pawns)",
                CHESS,
                usd_triangles(CHESS),
            )
        )
    elif not quick:
        missing.append(f"OpenChessSet ({CHESS} not found: ../shared/assets is missing)")
        print(f"bench: {missing[-1]}; skipped", file=sys.stderr)
    gen = [(15, "1M"), (72, "5M")] if not quick else [(15, "1M")]
    if a.big:
        gen.append((288, "20M"))
    for copies, label in gen:
        nodes, world = instances(bunny, copies, rng)
        path = tmp / f"bunnies_{label}.gltf"
        write_gltf(path, bunny, nodes)
        scenes.append(
            (
                f"gen{label}",
                f"{copies} bunny instances ({len(world) / 1e6:.2f}M triangles)",
                path,
                world,
            )
        )
    q_count = 10_000
    path = tmp / "quadrics_10k.gltf"
    write_gltf(path, bunny[:0], [], random_quadrics(q_count, rng, 10.0))
    scenes.append(("quadrics", f"{q_count} random ellipsoids (RAYCAST_quadric)", path, None))
    nodes, _ = instances(bunny * 20, 4, rng)
    path = tmp / "mixed.gltf"
    ext = np.ptp((bunny * 20).reshape(-1, 3), axis=0).max() * 2.2
    write_gltf(path, bunny * 20, nodes, random_quadrics(1000, rng, ext))
    scenes.append(("mixed", "mixed: 4 bunnies (278k triangles) + 1000 ellipsoids", path, None))
    # Size sweep extras: patches of the bunny.
    sweep = []
    for n in [1_000, 10_000] if not quick else [1_000]:
        path = tmp / f"patch_{n}.gltf"
        write_gltf(path, bunny[:n], [(np.zeros(3), 1.0)])
        sweep.append((f"patch{n}", f"bunny patch {n}", path, bunny[:n]))

    rounds = max(1, a.rounds)
    results = {
        "machine": machine(),
        "quick": quick,
        "rounds": rounds,
        "scenes": [],
        "sweep": [],
        "missing": missing,
    }
    for group, items in (("scenes", scenes), ("sweep", sweep)):
        for key, title, path, tris in items:
            t0 = time.time()
            info = raycast_info(RELEASE, path)
            lo, hi = bounds_of(info)
            rays = {"coherent": tmp / f"{key}_cam.npy"}
            np.save(rays["coherent"], in_tiles(pinhole_rays(lo, hi, cam_side), cam_side))
            if group == "scenes":
                rays["incoherent"] = tmp / f"{key}_rnd.npy"
                np.save(rays["incoherent"], random_rays(lo, hi, n_random, rng))
            big = info["triangles"] >= 1_000_000
            args = [
                "--threads",
                ",".join(map(str, threads if group == "scenes" else [1])),
                "--runs",
                str(1 if big else runs),
                "--build-runs",
                str(0 if big else runs),
            ]
            if key in ("bunny", "mixed"):
                args += ["--aov-compare", "coherent"]
            peer_spec = None
            if tris is not None:
                tri_path = tmp / f"{key}_tris.npy"
                np.save(tri_path, tris.astype(np.float32))
                peer_spec = {
                    "triangles": str(tri_path),
                    "rays": {k: str(v) for k, v in rays.items()},
                    "threads": threads if group == "scenes" else [1],
                    "runs": 1 if big else runs,
                    "f64_rays": (200 if quick else 1000) if group == "scenes" else 0,
                    "f64_max_triangles": 100_000,
                }
            rust_rounds, peer_rounds = [], []
            for _ in range(rounds):
                rust_rounds.append(run_rust(exe, path, rays, args))
                if peer_spec is not None:
                    peer_rounds.append(run_peers(peer_spec, tmp))
            rust = merge_rounds(rust_rounds)
            peers = None
            if peer_rounds:
                peers = merge_rounds(peer_rounds)
                peers["triangles_loaded"] = int(len(tris))
            results[group].append(
                {
                    "key": key,
                    "title": title,
                    "info_triangles": info["triangles"],
                    "rust": rust,
                    "peers": peers,
                    "seconds": time.time() - t0,
                }
            )
            print(f"bench: {key} done in {time.time() - t0:.0f}s", file=sys.stderr)
            for p in rays.values():
                p.unlink()
    results["total_s"] = time.time() - started
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(results, indent=1))
    out.write_text(report(results))
    print(f"bench: wrote {out} in {results['total_s']:.0f}s", file=sys.stderr)
    return 0


# ----------------------------------------------------------------------------- report

NAMES = {
    "octree": "raycast octree",
    "bvh": "raycast + obvhs BVH2",
    "cwbvh": "raycast + obvhs CWBVH",
    "embreex": "Embree 4 robust (embreex default)",
    "embreex-fast": "Embree 4 fast (embreex robust=False)",
    "open3d": "Open3D RaycastingScene",
    "trimesh-embree": "trimesh + embree",
    "trimesh-f64": "trimesh ray_triangle (f64)",
}


def methods_of(entry):
    out = []
    for b in entry["rust"]["backends"]:
        st = b["stats"]
        out.append(
            {
                "name": b["backend"],
                "build_s": b["build_s"],
                "traces": b["traces"],
                "bpp": st.get("bytes_per_prim"),
                "peak": b.get("peak_rss_mib"),
                "raw": b,
            }
        )
    if entry["peers"]:
        for m in entry["peers"].get("methods", []):
            if "error" in m or "skipped" in m:
                continue
            out.append(
                {
                    "name": m["backend"],
                    "build_s": m["build_s"],
                    "traces": m["traces"],
                    "bpp": None,
                    "peak": m.get("peak_rss_mib"),
                    "raw": m,
                }
            )
    return out


def rate(method, rays, threads):
    for t in method["traces"]:
        if t["rays"] == rays and t["threads"] == threads:
            return t
    return None


def fmt(x, spec=".2f"):
    return "–" if x is None or (isinstance(x, float) and not np.isfinite(x)) else format(x, spec)


def skipped_peers(r):
    """One report line per optional peer that was not run, with the reason."""
    reasons = {
        m["skipped"]
        for e in r["scenes"]
        for m in (e["peers"] or {}).get("methods", [])
        if "skipped" in m
    }
    return [line for reason in sorted(reasons) for line in (f"Not run: {reason}.", "")]


def report(r):
    m = r["machine"]
    lines = [
        "# Benchmark: octree vs obvhs vs Embree",
        "",
        "Regenerate with `.venv/bin/python -m raycast_tools bench` (`--quick` for a short run, "
        "`--big` adds the 20M-triangle scene, `--rounds N` alternates the Rust and peer "
        "processes N times per scene and reports medians over the rounds); raw figures in "
        "`reports/bench.json`.",
        "",
        f"Machine: {m['nproc']} cores, {m['cpu']} ({m['mhz'] or '?'} MHz), {m['memory_gib']} GiB, "
        f"{m['rustc']}, Python {m['python']}, kernel {m['kernel']}. "
        f"Run: {'quick' if r['quick'] else 'full'}, {r['total_s']:.0f} s, "
        f"{r.get('rounds', 1)} round(s) per scene. "
        "The machine is a shared VM: two full runs an hour apart on the same triangle code "
        "differed by up to 30% in single ratios.",
        "",
        *([f"Skipped: {', '.join(r['missing'])}.", ""] if r.get("missing") else []),
        *skipped_peers(r),
        "Method: one process per scene for the Rust backends (benches/trace.rs) and one for the "
        "Python peers, on the same float32 rays (`coherent` = pinhole camera, one ray per pixel, "
        "in 4 × 2 pixel tiles: the order the CLI traces a camera in, given to every method; "
        "`incoherent` = origins uniform in the scene box, directions uniform). Warm-up run, then "
        "the median of several; builds likewise (one build without warm-up for scenes of 1M "
        "triangles and more). Rust tracing goes through the CLI's `render` path with `--aov depth` "
        "(f64 exact primitive tests in every raycast backend). Embree: both kernels, the robust "
        "one (embreex's default scene flag) and the fast one (`EmbreeScene(robust=False)`); one "
        "`run()` call for all rays (two Python threads over halves for 2 threads: embreex's "
        "`run` holds the GIL, so those rows are not a two-thread peer); its build is the "
        "`rtcCommitScene` of the first call and always uses all cores (embreex exposes no "
        "thread setting). "
        "Open3D (optional): `RaycastingScene.cast_rays` with `nthreads`; its build is the first "
        "cast. "
        "trimesh's f64 path runs on a ray subset and is scaled per ray. Bytes/prim: the "
        "acceleration structure only (octree nodes + references; obvhs nodes + indices), not "
        "the primitives. Peak: the process's VmHWM (Rust: reset per backend; Python: one "
        "process for all peers, so Open3D and trimesh rows include Embree's peak), scene and "
        "rays included. "
        "Two-thread figures are only as good as the machine is idle: other jobs share its "
        "2 cores.",
        "",
    ]
    targets = []
    for e in r["scenes"]:
        ms = methods_of(e)
        by = {x["name"]: x for x in ms}
        rust = e["rust"]
        lines += [
            f"## {e['title']}",
            "",
            f"{rust['triangles']} triangles, {rust['quadrics']} quadrics; load "
            f"{rust['load_s']:.2f} s.",
            "",
        ]
        if e["peers"] and e["peers"].get("triangles_loaded") not in (None, rust["triangles"]):
            lines += [f"Note: the peers loaded {e['peers']['triangles_loaded']} triangles.", ""]
        lines += [
            "| method | rays | threads | build s | Mrays/s | hits | bytes/prim | peak MiB "
            "| × embreex robust | × embreex fast | × obvhs BVH2 |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for x in ms:
            for t in x["traces"]:
                ref_e = rate(by["embreex"], t["rays"], t["threads"]) if "embreex" in by else None
                ref_f = (
                    rate(by["embreex-fast"], t["rays"], t["threads"])
                    if "embreex-fast" in by
                    else None
                )
                ref_b = rate(by["bvh"], t["rays"], t["threads"]) if "bvh" in by else None
                sub = " (subset)" if t.get("subset") else ""
                lines.append(
                    f"| {NAMES.get(x['name'], x['name'])} | {t['rays']}{sub} ({t['count']}) | "
                    f"{t['threads']} | {fmt(x['build_s'], '.3f')} | "
                    f"{fmt(t['mrays_per_s'], '.3g')} | "
                    f"{t['hit_ratio'] * 100:.0f}% | {fmt(x['bpp'], '.1f')} | "
                    f"{fmt(x['peak'], '.0f')} | "
                    f"{fmt(t['mrays_per_s'] / ref_e['mrays_per_s'] if ref_e else None)} | "
                    f"{fmt(t['mrays_per_s'] / ref_f['mrays_per_s'] if ref_f else None)} | "
                    f"{fmt(t['mrays_per_s'] / ref_b['mrays_per_s'] if ref_b else None)} |"
                )
        oc = by.get("octree")
        if oc:
            s = oc["raw"]["stats"]
            o = s.get("octree", {})
            lines += [
                "",
                f"Octree: {o.get('nodes')} stored cells, {o.get('leaves')} leaves "
                f"(plus {o.get('empty_leaves')} empty octants, not stored), "
                f"depth {o.get('depth')}, "
                f"{s.get('refs_per_prim', 0):.2f} references per primitive; params "
                f"`{json.dumps(s.get('params'))}`.",
            ]
            aov = oc["raw"].get("aov")
            if aov:
                d, a = aov["depth"], aov["all"]
                lines += [
                    "",
                    f"Depth only vs all AOVs (octree, {aov['rays']} rays, "
                    f"{aov['threads']} threads): {d['median_s'] * 1e3:.0f} ms vs "
                    f"{a['median_s'] * 1e3:.0f} ms; extra peak memory "
                    f"{fmt(d['peak_extra_mib'], '.0f')} "
                    f"MiB vs {fmt(a['peak_extra_mib'], '.0f')} MiB ({', '.join(a['aovs'])}).",
                ]
        lines.append("")
        targets.append((e, by))
    lines += sweep_section(r)
    lines += memory_section(targets) + targets_section(targets) + gap_section(targets)
    return "\n".join(lines) + "\n"


def sweep_section(r):
    pts = []
    for e in r["sweep"] + r["scenes"]:
        if e["rust"]["quadrics"] or e["key"] in ("helmet", "chess"):
            continue
        by = {x["name"]: x for x in methods_of(e)}
        pts.append((e["rust"]["triangles"], by))
    pts.sort(key=lambda p: p[0])
    lines = [
        "## Cost versus scene size (bunny patches and instances, coherent rays, 1 thread)",
        "",
        "| triangles | "
        + " | ".join(f"{n} build s | {n} µs/ray" for n in ("octree", "bvh", "embreex"))
        + " |",
        "|---|" + "---|" * 6,
    ]
    series = {n: ([], [], []) for n in ("octree", "bvh", "embreex")}
    for n, by in pts:
        row = [str(n)]
        for name in ("octree", "bvh", "embreex"):
            x = by.get(name)
            t = rate(x, "coherent", 1) if x else None
            row += [
                fmt(x["build_s"] if x else None, ".3f"),
                fmt(1e6 * t["median_s"] / t["count"] if t else None, ".3f"),
            ]
            if x and t:
                series[name][0].append(n)
                series[name][1].append(x["build_s"])
                series[name][2].append(t["median_s"] / t["count"])
        lines.append("| " + " | ".join(row) + " |")
    lines.append("")
    for name, (n, b, p) in series.items():
        if len(n) >= 3:
            sb = np.polyfit(np.log(n), np.log(b), 1)[0]
            sp = np.polyfit(np.log(n), np.log(p), 1)[0]
            lines.append(
                f"- {name}: log-log slope of build time {sb:.2f}, of time per ray {sp:.2f}."
            )
    lines += [
        "",
        "Camera framing changes with the scene (instances spread out), so per-ray cost "
        "mixes structure depth with hit ratio; the slopes are indicative.",
        "",
    ]
    return lines


# Embree's robust triangle data (Triangle4v: four triangles' 36 floats and their 8 ids in 176
# bytes) and its BVH8 nodes (256 bytes, about one per seven full leaves), and embreex's own copy
# of a triangle soup (three 16-byte vertices and a 12-byte index triple per triangle), per
# triangle, from the documented layouts: an estimate with every leaf full.
EMBREE_LAYOUT_BYTES = 176 / 4 + 256 / (4 * 7) + 3 * 16 + 12


def memory_row(e, by):
    """Bytes per triangle of what a trace reads, the octree's against Embree's: None without
    the figures (an older bench.json, or a scene with quadrics)."""
    oc = by.get("octree")
    stats = oc["raw"]["stats"] if oc else {}
    triangles = e["rust"]["triangles"]
    if "geometry_bytes" not in stats or e["rust"]["quadrics"] or not triangles:
        return None

    def measured(name):
        mib = by[name]["raw"].get("scene_rss_mib") if name in by else None
        return None if mib is None else mib * 1024 * 1024 / triangles

    octree, geometry = stats["bytes"] / triangles, stats["geometry_bytes"] / triangles
    return {
        "octree": octree,
        "geometry": geometry,
        "total": octree + geometry,
        "embree": measured("embreex"),
        "embree_fast": measured("embreex-fast"),
    }


def memory_section(entries):
    """Bytes per triangle of the octree (nodes, leaves, their filter boxes) plus the triangle
    data the trace reads, against Embree's resident growth and its layouts."""
    rows = []
    for e, by in entries:
        m = memory_row(e, by)
        if m:
            rows.append(
                f"| {e['key']} | {m['octree']:.1f} | {m['geometry']:.1f} | {m['total']:.1f} | "
                f"{fmt(m['embree'], '.1f')} | {fmt(m['embree_fast'], '.1f')} | "
                f"{EMBREE_LAYOUT_BYTES:.1f} |"
            )
    if not rows:
        return []
    return [
        "## Memory per triangle: everything the trace reads",
        "",
        "| scene | octree B/tri | triangle data (instanced meshes with their octrees) B/tri | "
        "raycast total | "
        "embreex robust, measured | embreex fast, measured | Embree layout estimate |",
        "|---|---|---|---|---|---|---|",
        *rows,
        "",
        "Per triangle of the scene (instances counted as placed). raycast: the top-level "
        "`Octree::bytes` (nodes, leaf headers, references, the leaves' filter boxes) and "
        "`Scene::trace_bytes` (vertices as stored, f32 or f64, index triples; each instanced "
        "mesh once, with its own octree), not the shading attributes. Embree, measured: the "
        "peer process's resident memory (VmRSS) after the scene's commit minus before the "
        "scene was made, which holds embreex's copy of the triangles (the bench hands it a "
        "triangle soup: three vertices per triangle) and Embree's BVH; page granularity and "
        "the allocator's reserve make it approximate on small scenes. Layout estimate: "
        "Triangle4v leaves of 176 bytes per four triangles, one 256-byte BVH8 node per seven "
        "leaves, and embreex's 16-byte vertices and 12-byte triples for a soup. The instance "
        "scenes' Embree figures are for their placed triangles (embreex has no instancing), so "
        "those rows compare instancing with none.",
        "",
    ]


def targets_section(entries):
    lines = [
        "## The issue's targets (octree, ratios measured in this run)",
        "",
        "| target | scene | measured | met |",
        "|---|---|---|---|",
    ]

    def add(name, scene, value, goal, text=None):
        ok = value is not None and value >= goal
        lines.append(
            f"| {name} | {scene} | {text or fmt(value)} | "
            f"{'met' if ok else ('not met' if value is not None else 'n/a')} |"
        )

    for e, by in entries:
        oc = by.get("octree")
        if not oc:
            continue
        tri = e["rust"]["quadrics"] == 0
        for rays, robust_goal, fast_goal in (("coherent", 1.2, 1.0), ("incoherent", 1.0, 0.8)):
            t = rate(oc, rays, 1)
            for peer, goal in (("embreex", robust_goal), ("embreex-fast", fast_goal)):
                ref = rate(by[peer], rays, 1) if tri and peer in by and t else None
                if ref:
                    add(
                        f"{rays} ≥ {goal}× {NAMES[peer]} (1t)",
                        e["key"],
                        t["mrays_per_s"] / ref["mrays_per_s"],
                        goal,
                    )
        if e["key"] == "quadrics" and "bvh" in by:
            for rays in ("coherent", "incoherent"):
                add(
                    f"10k quadrics ≥ 1.2× obvhs BVH2 ({rays}, 1t)",
                    e["key"],
                    rate(oc, rays, 1)["mrays_per_s"] / rate(by["bvh"], rays, 1)["mrays_per_s"],
                    1.2,
                )
        if tri and "embreex" in by:
            # Embree's commit uses every core; the octree's build runs on the same pool.
            ratio = by["embreex"]["build_s"] / oc["build_s"]
            measured = f"{oc['build_s']:.3f} s vs {by['embreex']['build_s']:.3f} s ({ratio:.2f}×)"
            add("build ≤ embreex commit", e["key"], ratio, 1.0, measured)
        memory = memory_row(e, by) or {}
        for kernel, key in (("robust", "embree"), ("fast", "embree_fast")):
            if memory.get(key):
                add(
                    f"memory (structure + triangles) < embreex {kernel}'s measured",
                    e["key"],
                    memory[key] / memory["total"],
                    1.0,
                    f"{memory['total']:.1f} vs {memory[key]:.1f} B/tri",
                )
        t1, t2 = rate(oc, "coherent", 1), rate(oc, "coherent", 2)
        if t1 and t2:
            add(
                "2 threads ≥ 1.8× one (coherent)",
                e["key"],
                t2["mrays_per_s"] / t1["mrays_per_s"],
                1.8,
            )
    lines += [
        "",
        "Targets marked not met are gaps of the octree at the time of this run; see the "
        "ratios above for their size.",
        "",
    ]
    return lines


def gap_section(entries):
    """The octree's gap to Embree, split with this run's own numbers: obvhs BVH2 runs the
    same exact f64 primitive tests as the octree, so BVH2/octree isolates the structures on
    equal tests and Embree/BVH2 the rest (Embree's wide SIMD f32 nodes and triangle tests)."""
    rows = []
    for e, by in entries:
        oc, bvh, emb = by.get("octree"), by.get("bvh"), by.get("embreex")
        if not (oc and bvh and emb):
            continue
        o, b, m = (rate(x, "coherent", 1) for x in (oc, bvh, emb))
        if o and b and m:
            rows.append(
                f"| {e['key']} | {m['mrays_per_s'] / b['mrays_per_s']:.2f} | "
                f"{b['mrays_per_s'] / o['mrays_per_s']:.2f} | "
                f"{m['mrays_per_s'] / o['mrays_per_s']:.2f} |"
            )
    if not rows:
        return []
    return [
        "## What limits the octree",
        "",
        "| scene | Embree / BVH2 (Embree's SIMD BVH and tests vs exact scalar) | "
        "BVH2 / octree (structures, same exact tests) | "
        "Embree / octree (total) |",
        "|---|---|---|---|",
        *rows,
        "",
        "Coherent rays, one thread. The first column compares Embree (an 8-wide BVH whose "
        "boxes and triangles are tested in f32 SIMD) with obvhs BVH2 (a binary BVH, one "
        "ray at a time) running raycast's exact f64 primitive tests; the second compares "
        "that BVH with the octree on the same tests. Where the instructions go inside "
        "raycast (cell traversal, primitive tests, ray set-up) is measured with callgrind "
        "in reports/octree_profile.md: primitive tests are about 15-24% of either "
        "backend's trace instructions, so faster triangle tests alone cannot close the "
        "gap; traversal is the larger share.",
        "",
    ]
