"""`python -m raycast_tools COMMAND [ARGS...]`: one command line for every Python tool.

Each command lives in its own module with a `main(argv)`; the module is imported only
when its command runs, so `--help` and the standard-library-only commands (thread-scaling)
start without numpy, trimesh, usd-core or mpmath.
"""

from __future__ import annotations

import importlib
import sys

PROG = "python -m raycast_tools"

# command -> (module, one line on what it does)
COMMANDS = {
    "validate": (
        "validate.validate",
        "compare raycast with trimesh and the quadric reference, ray by ray",
    ),
    "validate-usd": (
        "validate.validate_usd",
        "compare raycast's USD import with usd-core + trimesh",
    ),
    "bench": ("bench.bench", "octree vs obvhs vs Embree vs trimesh (reports/bench.md)"),
    "end-to-end": (
        "bench.end_to_end",
        "1024² depth render from the file: raycast vs Open3D vs trimesh+Embree",
    ),
    "signed-check": (
        "validate.signed_check",
        "signed distance signs against exact truth on closed meshes (reports/signed_distance.md)",
    ),
    "python-calls": (
        "bench.python_calls",
        "Ctrl-C latency of long Python calls and list_intersections' transient memory",
    ),
    "python-bench": (
        "bench.python_bench",
        "raycast.load + cast vs trimesh and Open3D on the bunny (reports/python_bench.md)",
    ),
    "error-vs-time": (
        "validate.error_vs_time",
        "depth error against run time (reports/error_vs_time.md)",
    ),
    "fixtures": ("fixtures.make_fixtures", "write the glTF/OBJ fixtures under fixtures/"),
    "mesh-fixtures": (
        "fixtures.make_mesh_fixtures",
        "write the PLY and STL fixtures (ply/, stl/, bad/)",
    ),
    "exact-fixtures": (
        "fixtures.make_exact_fixtures",
        "write fixtures/exact/ (far OBJ, nested far glTF, PointInstancer)",
    ),
    "quadric-fixtures": ("fixtures.make_quadric_fixtures", "write the RAYCAST_quadric fixtures"),
    "usd-fixtures": ("fixtures.export_usd_fixtures", "write the USD fixtures under fixtures/usd/"),
    "stiff-cases": (
        "fixtures.stiff_cases",
        "write fixtures/stiff/cases.json (200-bit mpmath answers)",
    ),
    "tessellate": ("fixtures.tessellate", "tessellate a glTF's quadric nodes into a glTF mesh"),
    "tessellation-check": (
        "validate.tessellation_check",
        "tessellation error against the exact quadric",
    ),
    "quadric-reference": (
        "reference.quadric_reference",
        "trace rays with the object-space quadric reference",
    ),
    "random-quadrics": (
        "fixtures.random_quadric_scenes",
        "write random quadric scenes for validation",
    ),
    "usd-counts": ("reference.usd_counts", "count what a USD stage draws, with usd-core"),
    "usd-pose-reference": (
        "reference.usd_pose_reference",
        "usd-core's reading of fixtures/usd/posed at time codes and variants (issue 28)",
    ),
    "usd-skel-reference": (
        "reference.usd_skel_reference",
        "fixtures/usd/posed/skel.usda and usd-core's skinning of it at time codes (issue 28)",
    ),
    "views-bench": (
        "bench.views_bench",
        "N views in one --views run against N single runs (reports/views.md)",
    ),
    "thread-scaling": ("bench.thread_scaling", "octree and BVH2 trace time from 1 to 16 threads"),
    "check-scale": (
        "bench.check_scale",
        "raycast check shards, merge, throughput and the Khronos validator (check_scale.md)",
    ),
    "error-bounds": (
        "validate.error_bounds",
        "raycast's error and certain AOVs against exact answers (reports/error_bounds.md)",
    ),
    "exact-depth": (
        "validate.exact_depth",
        "USD/glTF/OBJ depth against an outside float64 reading + ray/triangle test (1e-12)",
    ),
    "corpus": (
        "validate.corpus",
        "render, info and check every file of a corpus beside the validator, usd-core, trimesh",
    ),
    "open3d-meshes": (
        "reference.open3d_meshes",
        "PLY/STL triangles beside Open3D's reader: dump (here), compare (Open3D's venv)",
    ),
    "instancing-bench": (
        "bench.instancing_bench",
        "memory and build time of instanced scenes, two binaries (reports/instancing.md)",
    ),
}


def usage() -> str:
    width = max(map(len, COMMANDS))
    lines = [
        f"usage: {PROG} COMMAND [ARGS...]   ({PROG} COMMAND --help for its options)",
        "",
        "commands:",
    ]
    lines += [f"  {name:<{width}}  {about}" for name, (_, about) in COMMANDS.items()]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the command named by argv[0] with the remaining arguments; its exit status."""
    argv = sys.argv[1:] if argv is None else argv
    if not argv:
        print(usage(), file=sys.stderr)
        return 2
    if argv[0] in ("-h", "--help"):
        print(usage())
        return 0
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        print(f"{PROG}: unknown command {name!r}\n\n{usage()}", file=sys.stderr)
        return 2
    module = importlib.import_module(f"raycast_tools.{COMMANDS[name][0]}")
    return module.main(rest) or 0


def prog(command: str) -> str:
    """The program name a command's argument parser shows in its usage line."""
    return f"{PROG} {command}"
