"""Memory and build time of instanced scenes, for two raycast binaries (before and after).

    python -m raycast_tools instancing-bench BEFORE_BINARY AFTER_BINARY [--runs 3]

Scenes: the bunny drawn by 1 and by 64 glTF nodes (one mesh), the 72-bunny bench scene
(tools/bench.py's generator) and the OpenChessSet (../shared/assets; skipped with a message
when missing). Each binary renders a 256x256 depth image; reported: the sidecar's load and
build seconds, the whole process's wall-clock and CPU seconds (GNU time's %e and %U + %S;
for USD this includes the child `raycast info` that reads the stage first), each the median
of the runs (made interleaved: before, after, before, ...), and the peak resident memory
(GNU time's %M).
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from raycast_tools.bench.bench import BUNNY, CHESS, instances, load_triangles, write_gltf
from raycast_tools.cli import prog


def run(binary, scene, out):
    """(load s, build s, wall s, CPU s, peak MiB) of one render."""
    cmd = [
        "/usr/bin/time",
        "-f",
        "%M %e %U %S",
        str(binary),
        str(scene),
        "--width",
        "256",
        "--height",
        "256",
        "--quiet",
        "--format",
        "png",
        "--out",
        str(out),
    ]
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    peak_kib, wall, user, system = done.stderr.strip().splitlines()[-1].split()
    timings = json.loads((out / "raycast.json").read_text())["timings"]
    cpu = float(user) + float(system)
    return timings["load"], timings["build"], float(wall), cpu, int(peak_kib) / 1024


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog=prog("instancing-bench"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument(
        "--chess",
        type=Path,
        default=CHESS,
        help="the OpenChessSet's chess_set.usda (default: ../shared/assets/...)",
    )
    a = parser.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="raycast-instancing-"))
    rng = np.random.default_rng(7)
    bunny = load_triangles(BUNNY)
    scenes = []
    for copies in (1, 64, 72):
        nodes, _ = instances(bunny, copies, rng)
        path = tmp / f"bunny_x{copies}.gltf"
        write_gltf(path, bunny, nodes)
        scenes.append((f"bunny drawn by {copies} node(s)", path))
    if a.chess.exists():
        scenes.append(("OpenChessSet", a.chess))
    else:
        print(
            f"instancing_bench: {a.chess} not found (../shared/assets missing): chess set skipped",
            file=sys.stderr,
        )
    print("| scene | binary | load s | build s | load+build s | wall s | CPU s | peak MiB |")
    print("|---|---|---|---|---|---|---|---|")
    binaries = (("before", a.before), ("after", a.after))
    for title, path in scenes:
        # Interleaved (before, after, before, ...), so that a change in the machine's load
        # touches both binaries alike.
        runs = {label: [] for label, _ in binaries}
        for _ in range(a.runs):
            for label, binary in binaries:
                runs[label].append(run(binary, path, tmp / f"out_{label}"))
        for label, _ in binaries:
            load, build, wall, cpu, peak = (
                statistics.median(r[k] for r in runs[label]) for k in range(5)
            )
            print(
                f"| {title} | {label} | {load:.3f} | {build:.3f} | {load + build:.3f} "
                f"| {wall:.2f} | {cpu:.2f} | {peak:.0f} |",
                flush=True,
            )
