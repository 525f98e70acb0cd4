"""The outside readers' side of one corpus file (raycast_tools.corpus), run in a child process
so that a reader that crashes or hangs on a public file costs that file only:

    python -m raycast_tools.reference.corpus_reference FILE --raycast PATH [--rays N]

prints one JSON object: `reader` (trimesh or usd-core), `loads` (whether that reader opens
the file without an error), `error` (its message when it does not), `triangles` (trimesh's
count, glTF/OBJ/PLY/STL) and `depth`: raycast's hits on N rays (default 2000) against a
float64 reference, from validate.py (trimesh's `ray_triangle` on trimesh's world triangles)
and validate_usd.py (usd-core's stage flattened, the same `ray_triangle` test), or the reason
it was not compared.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

USD_SUFFIXES = {".usd", ".usda", ".usdc", ".usdz"}


def _error(e: BaseException) -> str:
    """An exception as one line: its type and the first line of its message."""
    text = str(e).strip().splitlines()
    return f"{type(e).__name__}: {text[0] if text else ''}"[:300]


def mesh_depth(reports: list) -> dict:
    """The rays-mode report of validate.validate_reference, reduced to what the corpus shows."""
    rep = reports[0]
    if rep.get("status") in ("skip", "error"):
        return {"compared": False, "reason": rep.get("reason", "")}
    checks = rep.get("checks", {})
    return {
        "compared": True,
        "ok": bool(rep.get("ok")),
        "rays": rep.get("rays_f64"),
        "hits_reference": rep.get("hits_ref"),
        "hits_raycast": rep.get("hits_raycast"),
        "hitmiss_disagree": rep.get("mesh_hitmiss_disagree", 0),
        "depth_rel_max": (rep.get("mesh_depth_rel") or {}).get("max"),
        "failed_checks": sorted(k for k, c in checks.items() if not c["ok"]),
        "notes": rep.get("notes", []),
    }


def usd_depth(rep: dict) -> dict:
    """validate_usd.validate_scene's report, reduced to what the corpus shows."""
    if "skipped" in rep:
        return {"compared": False, "reason": rep["skipped"]}
    return {
        "compared": True,
        "ok": bool(rep["pass"]),
        "rays": rep["rays"],
        "hits_reference": rep["hits_reference"],
        "hits_raycast": rep["hits_raycast"],
        "hitmiss_disagree": rep["hitmiss_disagreements"],
        "depth_rel_max": None,
        "depth_abs_max": rep.get("depth_err_max"),
        "failed_checks": rep["failures"],
        "notes": [],
    }


def mesh_reference(path: Path, raycast: Path, rays: int) -> dict:
    """trimesh's reading (loads, triangles) and the depth comparison on it."""
    from raycast_tools.validate import validate

    out = {"reader": "trimesh"}
    try:
        ref = validate.load_reference(path)
    except validate.SkipScene as e:  # trimesh reads it, but wrongly: no reference
        return {**out, "loads": True, "depth": {"compared": False, "reason": str(e)}}
    except Exception as e:
        return {**out, "loads": False, "error": _error(e), "depth": {"compared": False}}
    out.update(loads=True, triangles=int(len(ref.tris)))
    if path.suffix.lower() in (".gltf", ".glb") and validate.poses(path):
        reason = "skinned or morphed: trimesh poses neither"
        return {**out, "depth": {"compared": False, "reason": reason}}
    try:
        out["depth"] = mesh_depth(validate.validate_reference(ref, raycast, nrays=rays))
    except Exception as e:
        out["depth"] = {"compared": False, "reason": f"raycast --rays failed: {_error(e)}"}
    return out


def usd_reference(path: Path, raycast: Path, rays: int) -> dict:
    """Whether usd-core opens the stage, and the depth comparison on its flattening."""
    from raycast_tools.reference.usd_stage import open_stage
    from raycast_tools.validate import validate_usd

    out = {"reader": "usd-core"}
    try:
        if open_stage(path) is None:
            return {**out, "loads": False, "error": "Usd.Stage.Open returned None"}
    except Exception as e:
        return {**out, "loads": False, "error": _error(e), "depth": {"compared": False}}
    out["loads"] = True
    try:
        out["depth"] = usd_depth(validate_usd.validate_scene(path, raycast, nrays=rays))
    except Exception as e:
        out["depth"] = {"compared": False, "reason": _error(e)}
    return out


def reference(path: Path, raycast: Path, rays: int) -> dict:
    """The outside readers' verdict on one file (see the module's doc)."""
    if path.suffix.lower() in USD_SUFFIXES:
        return usd_reference(path, raycast, rays)
    return mesh_reference(path, raycast, rays)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m raycast_tools.reference.corpus_reference")
    ap.add_argument("file", type=Path)
    ap.add_argument("--raycast", type=Path, required=True)
    ap.add_argument("--rays", type=int, default=2000)
    args = ap.parse_args(argv)
    print(json.dumps(reference(args.file, args.raycast, args.rays)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
