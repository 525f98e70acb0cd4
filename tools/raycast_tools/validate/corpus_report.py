"""The verdicts and the Markdown report of `python -m raycast_tools corpus` (corpus.py): which
files are valid, which of raycast's answers disagree with the outside readers, the summary
counts per corpus folder and one table row per file."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

from raycast_tools.paths import ROOT

CODE = re.compile(r'"([A-Z][A-Z0-9]*(?:_[A-Z0-9]+)+)"')


def raycast_codes(src: Path = ROOT / "src") -> set[str]:
    """Every finding code raycast's sources spell (string literals such as "NODE_LOOP"): a
    missed validator code that is among them is a rule that did not fire, one that is not is
    a rule raycast does not have."""
    codes = set()
    for path in src.rglob("*.rs"):
        codes.update(CODE.findall(path.read_text(errors="replace")))
    return codes


def valid(record: dict) -> bool | None:
    """Whether the outside reader accepts the file (None: it gave no verdict)."""
    if record["kind"] == "gltf":
        v = record.get("validator", {})
        return None if "failed" in v else not v["errors"]
    return record["reference"].get("loads")


def refused(record: dict) -> bool:
    return record["render"]["status"] != 0


def false_errors(record: dict) -> list[str]:
    """check's error codes on a valid file."""
    return record["check"]["errors"] if valid(record) else []


def missed(record: dict) -> list[str]:
    """The validator's error codes that check does not give (glTF only). A file the validator
    throws on counts as missed when check finds no error at all."""
    v = record.get("validator", {})
    ours = set(record["check"]["errors"])
    if "exception" in v:
        return [] if ours else ["(exception)"]
    return sorted(set(v.get("errors", [])) - ours)


def triangles_differ(record: dict) -> bool:
    ours, theirs = record["info"]["triangles"], record["reference"].get("triangles")
    return ours is not None and theirs is not None and ours != theirs


# Checks of validate.py (and validate_usd.py's failure lines) that judge the geometry: whether a
# ray hits, and how far. The others judge numbering (prim, id, object agreement: trimesh and
# usd-core reorder and regroup faces) and normals (their sign follows the face order).
GEOMETRY_CHECKS = ("hitmiss", "quadric_hitmiss", "depth", "quadric_depth", "hit/miss")


def depth_verdict(record: dict) -> str | None:
    """`geometry` when a hit/miss or depth check failed, `numbering` when only prim, id,
    object or normal checks did, `agrees`, or None when depth was not compared."""
    depth = record["reference"].get("depth") or {}
    if not depth.get("compared"):
        return None
    if depth.get("ok"):
        return "agrees"
    failed = depth.get("failed_checks", [])
    return "geometry" if any(c.startswith(GEOMETRY_CHECKS) for c in failed) else "numbering"


def corpus_of(record: dict) -> str:
    return Path(record["file"]).parts[0]


def summarize(records: list, too_large: list) -> dict:
    """Counts per corpus folder and in all, and the lists the summary names."""
    known = raycast_codes()
    per = {}
    for r in records:
        c = per.setdefault(corpus_of(r), Counter())
        c["files"] += 1
        c[r["kind"]] += 1
        c["valid"] += valid(r) is True
        c["refused valid"] += bool(valid(r) and refused(r))
        c["refused"] += refused(r)
        c["timeouts"] += any(r[k]["status"] is None for k in ("render", "info", "check"))
        c["false check errors"] += bool(r["kind"] == "gltf" and false_errors(r))
        c["check errors on readable files"] += bool(r["kind"] != "gltf" and false_errors(r))
        c["missed codes"] += len(missed(r))
        c["triangle counts differ"] += triangles_differ(r)
        verdict = depth_verdict(r)
        c["depth compared"] += verdict is not None
        c["geometry differs"] += verdict == "geometry"
        c["numbering or normals differ"] += verdict == "numbering"
    missed_codes = Counter(code for r in records for code in missed(r))
    return {
        "per_corpus": per,
        "total": sum(per.values(), Counter()),
        "too_large": too_large,
        "missed_codes": missed_codes,
        "unknown_codes": sorted(c for c in missed_codes if c not in known),
    }


SUMMARY_COLUMNS = (
    "files",
    "gltf",
    "obj",
    "ply",
    "stl",
    "usd",
    "valid",
    "refused valid",
    "false check errors",
    "check errors on readable files",
    "missed codes",
    "timeouts",
    "triangle counts differ",
    "depth compared",
    "geometry differs",
    "numbering or normals differ",
)


def _usd(c: Counter) -> int:
    return sum(c[k] for k in ("usd", "usda", "usdc", "usdz"))


def summary_table(summary: dict) -> list[str]:
    head = "| corpus | " + " | ".join(SUMMARY_COLUMNS) + " |"
    lines = [head, "|" + " --- |" * (len(SUMMARY_COLUMNS) + 1)]
    rows = sorted(summary["per_corpus"].items()) + [("**all**", summary["total"])]
    for name, c in rows:
        cells = [str(_usd(c) if k == "usd" else c[k]) for k in SUMMARY_COLUMNS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def _render_cell(r: dict) -> str:
    s = r["render"]["status"]
    if s == 0:
        return "0"
    return "timeout" if s is None else f"**{s}**: {r['render']['message']}"


def _check_cell(r: dict) -> str:
    c = r["check"]
    if c["verdict"] is None:
        return f"**failed** ({c['status']}): {c.get('message', '')}"
    return ", ".join(c["errors"]) or c["verdict"]


def _reference_cell(r: dict) -> str:
    if r["kind"] == "gltf":
        v = r["validator"]
        if "failed" in v:
            return f"validator failed: {v['failed']}"
        if "exception" in v:
            return f"validator: {v['exception']}"
        return "validator: " + (", ".join(v["errors"]) or "no error")
    ref = r["reference"]
    if "failed" in ref:
        return f"{'usd-core' if r['kind'].startswith('usd') else 'trimesh'} failed: {ref['failed']}"
    return f"{ref['reader']}: " + ("loads" if ref["loads"] else f"**fails**: {ref['error']}")


def _triangles_cell(r: dict) -> str:
    ours, theirs = r["info"]["triangles"], r["reference"].get("triangles")
    if theirs is None:
        return "-" if ours is None else str(ours)
    mark = "**" if ours != theirs else ""
    return f"{mark}{ours if ours is not None else '-'} / {theirs}{mark}"


def _depth_cell(r: dict) -> str:
    d = r["reference"].get("depth") or {}
    if not d.get("compared"):
        return f"- {d.get('reason', '')}".strip()
    hits = (
        f"hits {d['hits_raycast']}/{d['hits_reference']}, hit/miss differ {d['hitmiss_disagree']}"
    )
    if d.get("depth_rel_max") is not None:
        hits += f", rel depth max {d['depth_rel_max']:.1e}"
    if d.get("depth_abs_max") is not None:
        hits += f", depth err max {d['depth_abs_max']:.1e}"
    failed = ", ".join(d.get("failed_checks", []))
    verdict = {
        "agrees": "agrees",
        "geometry": f"**geometry differs** ({failed})",
        "numbering": f"numbering or normals differ ({failed})",
    }[depth_verdict(r)]
    return f"{verdict}: {hits}"


def file_table(records: list) -> list[str]:
    lines = [
        "| file | render exit | check errors | reference verdict | triangles raycast / trimesh "
        "| depth (2000 rays, f64 reference) |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in records:
        cells = [
            f"`{r['file']}`",
            _render_cell(r),
            _check_cell(r),
            _reference_cell(r),
            _triangles_cell(r),
            _depth_cell(r),
        ]
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return lines


def findings(records: list, summary: dict) -> list[str]:
    """The files behind the summary's disagreement counts, by kind."""
    lines = []
    groups = (
        ("Valid files refused by render", lambda r: valid(r) and refused(r)),
        (
            "check errors where the validator has none",
            lambda r: r["kind"] == "gltf" and false_errors(r),
        ),
        (
            "check errors on files usd-core or trimesh reads",
            lambda r: r["kind"] != "gltf" and false_errors(r),
        ),
        ("Validator error codes check misses", missed),
    )
    for title, picks in groups:
        hit = [r for r in records if picks(r)]
        lines += ["", f"### {title} ({len(hit)})", ""]
        for r in hit:
            detail = (
                ", ".join(missed(r))
                if picks is missed
                else (_render_cell(r) if "refused" in title else ", ".join(false_errors(r)))
            )
            lines.append(f"- `{r['file']}`: {detail}")
    counts = ", ".join(f"{c} ({n})" for c, n in summary["missed_codes"].most_common())
    lines += ["", f"Missed codes, by files: {counts or 'none'}."]
    if summary["unknown_codes"]:
        lines.append(
            f"Of these, raycast's sources have no rule for: {', '.join(summary['unknown_codes'])}."
        )
    return lines


def sources_lines(sources: dict, summary: dict) -> list[str]:
    lines = [
        f"- `{name}`: {s['repository']} at `{s['commit']}` ({' '.join(s['paths'][:6])}"
        f"{' ...' if len(s['paths']) > 6 else ''})"
        for name, s in sorted(sources.items())
    ]
    if summary.get("absent"):
        lines.append(
            f"- absent from the mirrors (large files, not exported): {len(summary['absent'])} "
            f"files ({', '.join(summary['absent'][:10])})"
        )
    if summary["too_large"]:
        lines.append(
            f"- left out for their size: {len(summary['too_large'])} files "
            f"({', '.join(summary['too_large'][:10])})"
        )
    return lines


def markdown(records: list, summary: dict, sources: dict, opts) -> str:
    """The whole report."""
    versions = sorted(
        {r["validator"]["version"] for r in records if r.get("validator", {}).get("version")}
    )
    validator = ", ".join(versions) or "(not run)"
    lines = [
        "# raycast on public corpora",
        "",
        "Written by `python -m raycast_tools corpus` (tools/raycast_tools/validate/corpus.py; "
        "docs/corpus.md). Per file: `raycast` render (64x64 depth), `info` and `check` (each "
        f"stopped after {opts.timeout:g} s), the Khronos glTF-Validator {validator} on glTF, "
        "`Usd.Stage.Open` (usd-core) on USD, trimesh 5.2.0 on the rest (and on glTF for the "
        f"triangle count), and depth on {opts.rays} rays against trimesh's float64 `ray_triangle` "
        "(on trimesh's world triangles; for USD on usd-core's stage flattened by "
        "validate_usd.py). Files over "
        f"{opts.max_mb:g} MB are left out.",
        "",
        "A file is valid when the validator finds no error (glTF), usd-core opens it (USD) or "
        "trimesh loads it (OBJ, PLY, STL). *false check errors*: glTF files the validator passes "
        "that check gives an error; *missed codes*: (file, code) pairs of validator errors that "
        "check does not give; *geometry differs*: validate.py's hit/miss or depth tolerances "
        "broken; *numbering or normals differ*: only its prim, id, object or normal checks broken "
        "(trimesh and usd-core number and orient faces their own way).",
        "",
        "## Sources",
        "",
        *sources_lines(sources, summary),
        "",
        "## Summary",
        "",
        *summary_table(summary),
        *findings(records, summary),
        "",
        "## Files",
        "",
        *file_table(records),
    ]
    return "\n".join(lines) + "\n"
