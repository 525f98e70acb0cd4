"""How the Python package's long calls behave: the time from SIGINT to KeyboardInterrupt
during a long `cast` and `list_intersections`, and the memory `list_intersections` takes
beyond its output, each in a child process of its own (peak RSS from `resource`).

Usage: python -m raycast_tools python-calls [--rays N] [--trials K] [--scene PATH]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

from raycast_tools import paths

DEFAULT_SCENE = paths.ROOT / "fixtures/assets/stanford-bunny.obj"

# Run in a child: interrupt a call after `delay` seconds, print the latency.
INTERRUPT = r"""
import os, signal, sys, threading, time, numpy as np, raycast
scene = raycast.load(sys.argv[1]); n = int(sys.argv[2]); call = sys.argv[3]
lo, hi = scene.bounds
rng = np.random.default_rng(1)
o = rng.uniform(lo, hi, (n, 3)); d = rng.normal(size=(n, 3))
sent = []
def fire():
    sent.append(time.perf_counter()); os.kill(os.getpid(), signal.SIGINT)
threading.Timer(0.5, fire).start()
began = time.perf_counter()
try:
    getattr(scene, call)(o, d)
    print(json.dumps({"interrupted": False, "call_s": time.perf_counter() - began}))
except KeyboardInterrupt:
    print(json.dumps({"interrupted": True, "latency_s": time.perf_counter() - sent[0]}))
""".replace("import os", "import json, os")

# Run in a child: peak RSS of list_intersections beyond the scene, the rays and the output.
MEMORY = r"""
import json, resource, sys, numpy as np, raycast
scene = raycast.load(sys.argv[1]); n = int(sys.argv[2])
lo, hi = scene.bounds
rng = np.random.default_rng(1)
o = rng.uniform(lo, hi, (n, 3)); d = rng.normal(size=(n, 3))
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
found = scene.list_intersections(o, d)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
output = sum(v.nbytes for v in found.values())
print(json.dumps({"rays": n, "hits": int(len(found["t"])), "output_bytes": output,
                  "peak_growth_bytes": peak - before}))
"""


def child(script: str, *args) -> dict:
    run = subprocess.run(
        [sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True, check=True
    )
    return json.loads(run.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m raycast_tools python-calls", description=__doc__
    )
    parser.add_argument("--rays", type=int, default=6_000_000)
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--scene", type=str, default=str(DEFAULT_SCENE))
    args = parser.parse_args(argv)
    results = {"interrupt": {}, "memory": None}
    for call in ("cast", "list_intersections"):
        results["interrupt"][call] = [
            child(INTERRUPT, args.scene, args.rays, call) for _ in range(args.trials)
        ]
    results["memory"] = child(MEMORY, args.scene, args.rays)
    print(json.dumps(results, indent=1))
    return 0
