"""Run raycast over a corpus of public scene files, beside the readers users trust.

    python -m raycast_tools corpus DIR [--out reports/corpus.md] [--list FILE] [--jobs N]
                                       [--timeout S] [--max-mb MB] [--rays N] [--raycast PATH]

For every scene file below DIR (.gltf .glb .obj .ply .stl .usd .usda .usdc .usdz, at most
--max-mb megabytes; larger ones are counted and left out) it runs, each in its own process
stopped after --timeout seconds (a hang is a finding, not a stuck run):

* `raycast FILE --width 64 --height 64 --aov depth --format npy` (the render's exit status),
  `raycast info FILE --json` (its triangle count) and `raycast check FILE --json` (its
  verdict and error codes), all with `--allow-outside`, as the validator reads resources;
* for glTF, the Khronos glTF-Validator (npm gltf-validator, pinned in tools/npm, through
  tools/npm/validate_codes.mjs);
* corpus_reference.py: whether trimesh (glTF, OBJ, PLY, STL) or usd-core (`Usd.Stage.Open`)
  reads the file, trimesh's triangle count, and raycast's depth on --rays rays (default 2000)
  against the float64 reference (trimesh's `ray_triangle`).

A file is *valid* when the validator finds no error (glTF), usd-core opens it (USD) or trimesh
loads it (OBJ, PLY, STL). The Markdown report (corpus_report.py) has the summary first: valid
files render refuses, check errors on files the validator passes, validator error codes check
does not give. When DIR holds a SOURCES file (tools/export_corpus.sh writes it: one line per
top folder, `NAME REPOSITORY COMMIT PATHS...`), the report names the source of each folder.
--list FILE writes the files examined, one a line: path, bytes, source repository and commit.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from raycast_tools.cli import prog
from raycast_tools.paths import ROOT, raycast_or_exit
from raycast_tools.validate.corpus_report import markdown, summarize

SUFFIXES = {".gltf", ".glb", ".obj", ".ply", ".stl", ".usd", ".usda", ".usdc", ".usdz"}
GLTF = {".gltf", ".glb"}
NPM = ROOT / "tools" / "npm"
VALIDATE_CODES = NPM / "validate_codes.mjs"


@dataclass
class Ran:
    """One tool run: exit status (None when it was stopped at the timeout or could not
    start), seconds, stdout and the last line it wrote to stderr."""

    status: int | None
    seconds: float
    stdout: str
    last_line: str

    @property
    def timed_out(self) -> bool:
        return self.status is None


def run(cmd: list, timeout: float) -> Ran:
    """Runs cmd in its own process group, which is killed whole at the timeout (raycast's
    USD child, trimesh's raycast run)."""
    t0 = time.perf_counter()
    try:
        p = subprocess.Popen(
            [str(c) for c in cmd],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            errors="replace",
            start_new_session=True,
        )
    except OSError as e:
        return Ran(None, 0.0, "", f"cannot start: {e}")
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        return Ran(None, time.perf_counter() - t0, "", f"stopped after {timeout:g} s")
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    return Ran(p.returncode, time.perf_counter() - t0, out, lines[-1][:300] if lines else "")


def json_line(text: str) -> dict | None:
    """The first line of text that is a JSON object, or None."""
    for line in text.splitlines():
        if line.startswith("{"):
            try:
                return json.loads(line)
            except json.JSONDecodeError:
                return None
    return None


def render(raycast: Path, path: Path, timeout: float) -> dict:
    with tempfile.TemporaryDirectory(prefix="corpus-") as out:
        args = ["--width", "64", "--height", "64", "--aov", "depth", "--format", "npy"]
        r = run([raycast, path, *args, "--allow-outside", "--quiet", "--out", out], timeout)
    return {"status": r.status, "seconds": r.seconds, "message": r.last_line}


def info(raycast: Path, path: Path, timeout: float) -> dict:
    r = run([raycast, "info", path, "--json", "--allow-outside"], timeout)
    try:
        triangles = json.loads(r.stdout)["triangles"] if r.status == 0 else None
    except (json.JSONDecodeError, KeyError, TypeError):
        triangles = None
    return {"status": r.status, "triangles": triangles, "message": r.last_line}


def check(raycast: Path, path: Path, timeout: float) -> dict:
    r = run([raycast, "check", path, "--json", "--allow-outside", "--quiet"], timeout)
    record = json_line(r.stdout) if r.status in (0, 1) else None
    if record is None:
        return {"status": r.status, "verdict": None, "errors": [], "message": r.last_line}
    errors = sorted({f["code"] for f in record["findings"] if f["severity"] == "error"})
    return {"status": r.status, "verdict": record["status"], "errors": errors}


def validator(path: Path, timeout: float) -> dict:
    """The Khronos validator's verdict: `errors` (its error codes) or `failed` (why none)."""
    r = run(["node", VALIDATE_CODES, path], timeout)
    v = json_line(r.stdout)
    if v is None:
        return {"failed": r.last_line or f"exit {r.status}"}
    if "exception" in v:  # not glTF at all: the validator refuses it
        return {"errors": ["(exception)"], "exception": v["exception"][:200]}
    errors = sorted(code for code, severity in v["codes"].items() if severity == 0)
    return {"errors": errors, "version": v["version"]}


def reference(raycast: Path, path: Path, timeout: float, rays: int) -> dict:
    cmd = [
        sys.executable,
        "-m",
        "raycast_tools.reference.corpus_reference",
        path,
        "--raycast",
        raycast,
    ]
    r = run([*cmd, "--rays", str(rays)], timeout)
    return json_line(r.stdout) or {"failed": r.last_line or f"exit {r.status}"}


def examine(path: Path, name: str, raycast: Path, opts) -> dict:
    """Everything the report holds about one file."""
    record = {
        "file": name,
        "kind": "gltf" if path.suffix.lower() in GLTF else path.suffix.lower()[1:],
        "render": render(raycast, path, opts.timeout),
        "info": info(raycast, path, opts.timeout),
        "check": check(raycast, path, opts.timeout),
        "reference": reference(raycast, path, opts.timeout, opts.rays),
    }
    if record["kind"] == "gltf":
        record["validator"] = validator(path, opts.timeout)
    return record


def scene_files(root: Path, max_bytes: int) -> tuple[list[Path], list[Path]]:
    """(files to examine, files left out for their size), sorted."""
    found = sorted(p for p in root.rglob("*") if p.is_file() and p.suffix.lower() in SUFFIXES)
    small = [p for p in found if p.stat().st_size <= max_bytes]
    return small, [p for p in found if p.stat().st_size > max_bytes]


def read_sources(root: Path) -> dict:
    """Top folder -> {"repository", "commit", "paths"} from DIR/SOURCES, if there is one."""
    sources = {}
    path = root / "SOURCES"
    if path.is_file():
        for line in path.read_text().splitlines():
            name, repository, commit, *paths = line.split()
            sources[name] = {"repository": repository, "commit": commit, "paths": paths}
    return sources


def write_list(path: Path, root: Path, files: list[Path], sources: dict) -> None:
    lines = ["# file\tbytes\trepository\tcommit"]
    for f in files:
        rel = f.relative_to(root)
        src = sources.get(rel.parts[0], {})
        lines.append(
            f"{rel}\t{f.stat().st_size}\t{src.get('repository', '-')}\t{src.get('commit', '-')}"
        )
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("corpus"), description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", type=Path)
    ap.add_argument("--out", type=Path, default=ROOT / "reports" / "corpus.md")
    ap.add_argument("--list", type=Path, help="also write the files examined here")
    ap.add_argument("--json", type=Path, help="also write the per-file records here")
    ap.add_argument("--jobs", type=int, default=2, help="files examined at once (default 2)")
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per step and file")
    ap.add_argument("--max-mb", type=float, default=20.0, help="largest file examined (MB)")
    ap.add_argument("--rays", type=int, default=2000)
    ap.add_argument("--raycast", help="binary (default: paths.find_raycast)")
    opts = ap.parse_args(argv)
    raycast = raycast_or_exit(opts.raycast, prog("corpus"))
    if not opts.dir.is_dir():
        print(f"{prog('corpus')}: not a folder: {opts.dir}", file=sys.stderr)
        return 2
    if not shutil.which("node") or not (NPM / "node_modules" / "gltf-validator").is_dir():
        print(f"{prog('corpus')}: needs node and `npm ci` in {NPM}", file=sys.stderr)
        return 2
    root = opts.dir.resolve()
    files, too_large = scene_files(root, int(opts.max_mb * 1e6))
    sources = read_sources(root)
    with ThreadPoolExecutor(max(1, opts.jobs)) as pool:
        records = list(
            pool.map(lambda f: examine(f, str(f.relative_to(root)), raycast, opts), files)
        )
    summary = summarize(records, too_large=[str(f.relative_to(root)) for f in too_large])
    absent = root / "ABSENT"  # tools/export_corpus.sh: files the mirror lacked
    summary["absent"] = absent.read_text().split() if absent.is_file() else []
    opts.out.parent.mkdir(parents=True, exist_ok=True)
    opts.out.write_text(markdown(records, summary, sources, opts))
    if opts.list:
        write_list(opts.list, root, files, sources)
    if opts.json:
        opts.json.write_text(json.dumps(records, indent=1) + "\n")
    print(f"{prog('corpus')}: {len(records)} files, report in {opts.out}")
    return 0
