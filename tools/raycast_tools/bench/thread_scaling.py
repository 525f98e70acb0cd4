"""Thread scaling of raycast's octree.

The obvhs BVH2 rows of reports/thread_scaling.md were measured with the command line's
`--accel bvh`, which is gone (the BVH is a test and benchmark oracle now): `cargo bench --bench
trace -- SCENE --rays ... --backends bvh --threads 1,2,4,8,16` measures it.

2048x2048 primary rays, depth only, for 1, 2, 4, 8 and 16 threads, three runs each; trace
and build times come from the sidecar. Meant for a machine with many cores
(reports/thread_scaling.md was made on a 16-core machine); --big-scene adds a scene such as
the 1M-triangle one `python -m raycast_tools bench` writes.

--pinning adds a pinning experiment on the bunny and the helmet: one thread on CPU 0, two
threads on CPU 0 and its hyperthread sibling (CPU 0 alone when it has none), two threads on
CPU 0 and a CPU of another core (taskset, three runs each).

Writes OUT/machine.txt, OUT/scaling.txt (scene accel threads run build trace), OUT/topology.txt
and, with --pinning, OUT/pinning.txt (scene cpus=LIST accel threads run trace). Only the
standard library is used, so a bare python3 runs it (tools/thread_scaling.sh).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path

from raycast_tools.cli import prog
from raycast_tools.paths import RELEASE, ROOT

SCENES = [ROOT / "fixtures/assets/stanford-bunny.obj", ROOT / "fixtures/assets/DamagedHelmet.glb"]
ACCELS = ("octree",)
THREADS = (1, 2, 4, 8, 16)
RUNS = (1, 2, 3)
CPU = Path("/sys/devices/system/cpu")


def timings(raycast, scene, threads, work: Path, cpus: str | None = None) -> dict:
    """One 2048x2048 depth render; the sidecar's timings (seconds)."""
    cmd = [
        str(raycast),
        str(scene),
        "--width",
        "2048",
        "--height",
        "2048",
        "--aov",
        "depth",
        "--format",
        "npy",
        "--threads",
        str(threads),
        "--out",
        str(work),
        "--quiet",
    ]
    if cpus is not None:
        cmd = ["taskset", "-c", cpus, *cmd]
    subprocess.run(cmd, check=True)
    return json.loads((work / "raycast.json").read_text())["timings"]


def cpu_dirs() -> list[Path]:
    """/sys/devices/system/cpu/cpuN folders, in the shell's glob order."""
    return sorted(p for p in CPU.glob("cpu[0-9]*"))


def topology(cpu: Path, what: str) -> str:
    return (cpu / "topology" / what).read_text().strip()


def model_name() -> str:
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1]
    return ""


def write_topology(path: Path) -> None:
    """lscpu, then each CPU's core id and hyperthread siblings."""
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True)
    lines = [
        f"{c.name} core {topology(c, 'core_id')} siblings {topology(c, 'thread_siblings_list')}"
        for c in cpu_dirs()
    ]
    path.write_text(lscpu.stdout + lscpu.stderr + "".join(line + "\n" for line in lines))


def pin_sets() -> tuple[str, str, list[str]]:
    """(sibling of CPU 0, a CPU of another core, the three CPU lists to pin to)."""
    cpu0 = CPU / "cpu0"
    listed = topology(cpu0, "thread_siblings_list").replace("-", ",").split(",")
    sibling = next((c for c in listed if c != "0"), "0")
    core0 = topology(cpu0, "core_id")
    others = sorted(int(c.name[3:]) for c in cpu_dirs() if topology(c, "core_id") != core0)
    other = str(others[0]) if others else ""
    return sibling, other, ["0", f"0,{sibling}", f"0,{other}"]


def scaling(raycast, scenes, out: Path, work: Path) -> None:
    with open(out / "scaling.txt", "w") as f:
        for scene in scenes:
            for accel in ACCELS:
                for threads in THREADS:
                    for run in RUNS:
                        t = timings(raycast, scene, threads, work)
                        print(
                            Path(scene).name,
                            accel,
                            threads,
                            run,
                            t["build"],
                            t["trace"],
                            file=f,
                            flush=True,
                        )


def pinning(raycast, out: Path, work: Path) -> None:
    sibling, other, pins = pin_sets()
    with open(out / "pinning.txt", "w") as f:
        print(f"sibling of cpu0: {sibling}, another core: {other}", file=f, flush=True)
        for scene in SCENES:
            for cpus in pins:
                threads = len(set(cpus.split(",")))
                for accel in ACCELS:
                    for run in RUNS:
                        t = timings(raycast, scene, threads, work, cpus)
                        print(
                            scene.name,
                            f"cpus={cpus}",
                            accel,
                            threads,
                            run,
                            t["trace"],
                            file=f,
                            flush=True,
                        )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("thread-scaling"), description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--raycast",
        default=os.environ.get("RAYCAST", str(RELEASE)),
        help="raycast binary (default: $RAYCAST, else target/release/raycast)",
    )
    ap.add_argument(
        "--out",
        default=os.environ.get("OUT", str(ROOT / "reports/device")),
        help="output folder (default: $OUT, else reports/device)",
    )
    ap.add_argument(
        "--big-scene",
        default=os.environ.get("BIG_SCENE") or None,
        help="a further scene (default: $BIG_SCENE)",
    )
    ap.add_argument(
        "--pinning",
        action="store_true",
        default=os.environ.get("PINNING") == "1",
        help="add the pinning experiment (default: on when $PINNING is 1)",
    )
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "machine.txt").write_text(f"cpu: {os.cpu_count()} cores, {model_name()}\n")
    scenes = SCENES + ([Path(a.big_scene)] if a.big_scene else [])
    with tempfile.TemporaryDirectory() as tmp:
        scaling(a.raycast, scenes, out, Path(tmp))
        try:
            write_topology(out / "topology.txt")
        except OSError as e:
            (out / "topology.txt").write_text(f"{e}\n")
        if a.pinning:
            pinning(a.raycast, out, Path(tmp))
    return 0
