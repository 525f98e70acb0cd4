"""PLY and STL triangles as raycast reads them beside Open3D's reader (issue 29): a measuring
tool, not a CI test (Open3D's CPU wheel needs Debian's libusb-1.0-0, which CI does not install).

Two steps, in two Python environments (raycast's package is built into the project's .venv;
Open3D lives in one of its own, e.g. ``python3.11 -m venv o3d && o3d/bin/pip install
open3d-cpu==0.20.0 "numpy<2"``):

    .venv/bin/python -m raycast_tools open3d-meshes dump DIR... --out TRIS/
    PYTHONPATH=tools o3d/bin/python -m raycast_tools.reference.open3d_meshes compare TRIS/ \
        --report reports/open3d_readers.md

``dump`` writes, for every .ply and .stl file below the folders, raycast.load's triangles
((T, 3, 3) float64, all objects in order) to ``TRIS/<n>.npy`` and the list to
``TRIS/files.json`` (a file raycast refuses is listed with its error). ``compare`` reads each
file with ``open3d.io.read_triangle_mesh(path, enable_post_processing=False)`` and compares:
triangle counts, and the triangles as sets with every vertex equal in float32 (each triangle
rotated to start at its smallest corner, which keeps the winding; Open3D and raycast order a
polygon's triangles their own ways).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from raycast_tools.cli import prog


def mesh_files(folders: list[Path]) -> list[tuple[Path, str]]:
    """Every .ply and .stl file below `folders`, sorted, each with the name the report gives
    it: its path below an absolute folder (a corpus), or as given below a relative one."""
    out = []
    for folder in folders:
        for p in folder.rglob("*"):
            if p.suffix.lower() in (".ply", ".stl"):
                out.append((p, str(p.relative_to(folder) if folder.is_absolute() else p)))
    return sorted(out)


def dump(folders: list[Path], out: Path) -> int:
    import raycast

    out.mkdir(parents=True, exist_ok=True)
    listed = []
    for n, (path, name) in enumerate(mesh_files(folders)):
        entry = {"file": str(path), "name": name, "npy": f"{n}.npy"}
        try:
            scene = raycast.load(path)
            tris = [scene.triangles(o["id"]) for o in scene.objects]
            tris = np.concatenate(tris) if tris else np.zeros((0, 3, 3))
            np.save(out / entry["npy"], tris)
        except Exception as e:  # noqa: BLE001 - a refusal is a result to report
            entry["error"] = str(e).splitlines()[0].replace(str(path.resolve()), name)
        listed.append(entry)
    (out / "files.json").write_text(json.dumps(listed, indent=1) + "\n")
    print(f"open3d-meshes: {len(listed)} files dumped to {out}")
    return 0


def canonical(tris: np.ndarray) -> np.ndarray:
    """Triangles rotated to start at their smallest corner (which keeps the winding), then
    sorted: equal for two lists of the same triangles in any order."""
    out = np.empty_like(tris)
    for i, t in enumerate(tris):
        first = min(range(3), key=lambda k: tuple(t[k]))
        out[i] = np.roll(t, -first, axis=0)
    flat = out.reshape(len(out), 9)
    return flat[np.lexsort(flat.T[::-1])]


def open3d_triangles(path: Path, scratch: Path):
    """Open3D's triangles of `path`, read in a child process (Open3D crashes on some files):
    the (T, 3, 3) array, or the child's exit status when it did not finish."""
    out = scratch / "open3d.npy"
    out.unlink(missing_ok=True)
    child = subprocess.run(
        [
            sys.executable,
            "-m",
            "raycast_tools.reference.open3d_meshes",
            "read",
            str(path),
            str(out),
        ],
        capture_output=True,
    )
    if child.returncode != 0:
        return child.returncode
    return np.load(out)


def failure(status: int) -> str:
    """How Open3D's child process ended without triangles."""
    return f"crashed (signal {-status})" if status < 0 else f"failed (exit {status})"


def read(path: Path, out: Path) -> int:
    import open3d as o3d

    mesh = o3d.io.read_triangle_mesh(str(path), enable_post_processing=False)
    v = np.asarray(mesh.vertices, dtype=np.float64)
    f = np.asarray(mesh.triangles, dtype=np.int64)
    np.save(out, v[f] if len(f) else np.zeros((0, 3, 3)))
    return 0


def trimesh_triangles(path: Path) -> np.ndarray | str:
    """trimesh's triangles of `path` (every mesh of the scene it loads, in order), or why it
    refused the file."""
    import trimesh

    try:
        scene = trimesh.load(str(path), force="scene", process=False)
    except Exception as e:  # noqa: BLE001 - a refusal is a result to report
        return "refused: " + str(e).splitlines()[0][:60]
    tris = [
        np.asarray(g.vertices, dtype=np.float64)[np.asarray(g.faces)]
        for g in scene.geometry.values()
        if hasattr(g, "faces") and len(g.faces)
    ]
    return np.concatenate(tris) if tris else np.zeros((0, 3, 3))


def same_triangles(a: np.ndarray, b) -> str:
    """ "yes" when `b` (an array) holds `a`'s triangles, every vertex equal in float32."""
    if isinstance(b, (int, str)):
        return "-"
    if len(a) == len(b) and np.array_equal(
        canonical(a.astype(np.float32)), canonical(b.astype(np.float32))
    ):
        return "yes"
    return "no"


def compare(folder: Path, report: Path | None) -> int:
    import open3d as o3d  # here for its version; files are read in child processes

    rows, agree, agree_trimesh, counted = [], 0, 0, 0
    for entry in json.loads((folder / "files.json").read_text()):
        path, name = Path(entry["file"]), entry["name"]
        theirs = open3d_triangles(path, folder)
        theirs_n = failure(theirs) if isinstance(theirs, int) else len(theirs)
        if "error" in entry:
            rows.append((name, "refused: " + entry["error"], theirs_n, "-", "-", "-"))
            continue
        ours = np.load(folder / entry["npy"])
        counted += 1
        tm = trimesh_triangles(path)
        tm_n = tm if isinstance(tm, str) else len(tm)
        same, same_tm = same_triangles(ours, theirs), same_triangles(ours, tm)
        agree += same == "yes"
        agree_trimesh += same_tm == "yes"
        rows.append((name, len(ours), theirs_n, same, tm_n, same_tm))
    lines = [
        "# PLY and STL: raycast's reader beside Open3D's",
        "",
        "Written by `tools/raycast_tools/reference/open3d_meshes.py` (its docstring says how)."
        f" Open3D {o3d.__version__}, `read_triangle_mesh(enable_post_processing=False)`; triangles"
        " compared as sets, every vertex equal in float32.",
        "",
        f"- Files read by raycast: {counted}; triangles equal to Open3D's:"
        f" **{agree} of {counted}**; to trimesh's: **{agree_trimesh} of {counted}**.",
        "",
        "| file | raycast | Open3D | same as Open3D? | trimesh | same as trimesh? |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for name, ours, theirs, same, tm, same_tm in rows:
        lines.append(f"| `{name}` | {ours} | {theirs} | {same} | {tm} | {same_tm} |")
    text = "\n".join(lines) + "\n"
    if report:
        report.write_text(text)
    print(text)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("open3d-meshes"), description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="step", required=True)
    d = sub.add_parser("dump")
    d.add_argument("folders", nargs="+", type=Path)
    d.add_argument("--out", type=Path, required=True)
    c = sub.add_parser("compare")
    c.add_argument("folder", type=Path)
    c.add_argument("--report", type=Path)
    r = sub.add_parser("read", help="one file through Open3D (compare's child process)")
    r.add_argument("file", type=Path)
    r.add_argument("out", type=Path)
    opts = ap.parse_args(argv)
    if opts.step == "dump":
        return dump(opts.folders, opts.out)
    if opts.step == "read":
        return read(opts.file, opts.out)
    return compare(opts.folder, opts.report)


if __name__ == "__main__":
    sys.exit(main())
