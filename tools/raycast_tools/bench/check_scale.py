"""`raycast check` at library scale: shards, their merge, throughput and peak memory.

On an asset folder (default ../shared/assets; says so and exits 2 when it is missing):
1. an unsharded `raycast check DIR --json --junit` (wall time, peak memory, exit code);
2. for each N (default 1, 3, 7): the N shards one after another, then `--merge`; checks that
   the shards cover every asset exactly once and that the merge equals the unsharded run
   (the same JSON records without `seconds`, in the same order; the same JUnit testcases
   without `time`; the same exit code);
3. throughput on the glTF files alone, beside the Khronos glTF-Validator (npm
   `gltf-validator`, pinned in tools/npm, run through tools/npm/validate_codes.mjs) on the same
   files when tools/npm/node_modules holds it; skipped with a message otherwise.

Times are wall-clock seconds, the median of --runs runs; peak memory is GNU time's
"Maximum resident set size" (the largest process of the tree: raycast's USD children are
separate processes). Prints a Markdown report; --json FILE also writes the numbers.
"""

from __future__ import annotations

import argparse
import collections
import json
import re
import shutil
import statistics
import subprocess
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

from raycast_tools.cli import prog
from raycast_tools.paths import ROOT, raycast_or_exit

ASSETS = ROOT.parent / "shared" / "assets"
VALIDATOR = ROOT / "tools" / "npm" / "node_modules" / "gltf-validator"
# One JSON line per file: the validator's verdict (its error count, `errors`).
VALIDATE_CODES = ROOT / "tools" / "npm" / "validate_codes.mjs"
TIME = Path("/usr/bin/time")


def timed(cmd: list, cwd: Path, stdout_to: Path | None = None) -> dict:
    """Runs `cmd` under GNU time -v: exit code, wall seconds, peak RSS (MiB)."""
    out = open(stdout_to, "wb") if stdout_to else subprocess.DEVNULL
    try:
        run = subprocess.run(
            [str(TIME), "-v", *map(str, cmd)], cwd=cwd, stdout=out, stderr=subprocess.PIPE
        )
    finally:
        if stdout_to:
            out.close()
    err = run.stderr.decode(errors="replace")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", err)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", err)
    if not wall or not rss:
        raise SystemExit(f"check-scale: no GNU time output for {cmd[:3]}: {err[-300:]}")
    hours, minutes, seconds = wall.groups()
    return {
        "code": run.returncode,
        "seconds": int(hours or 0) * 3600 + int(minutes) * 60 + float(seconds),
        "peak_mib": int(rss.group(1)) / 1024,
        "stderr": err,
    }


def median_run(cmd: list, cwd: Path, runs: int, stdout_to: Path | None = None) -> dict:
    results = [timed(cmd, cwd, stdout_to) for _ in range(runs)]
    return {
        "code": results[-1]["code"],
        "seconds": statistics.median(r["seconds"] for r in results),
        "peak_mib": max(r["peak_mib"] for r in results),
        "all_seconds": [round(r["seconds"], 3) for r in results],
    }


def records(path: Path) -> list[dict]:
    out = []
    for line in path.read_text().splitlines():
        record = json.loads(line)
        if "raycast_check_shard" in record:
            continue
        record.pop("seconds", None)
        out.append(record)
    return out


def junit_cases(path: Path):
    suite = ET.parse(path).getroot().find("testsuite")
    counts = {k: v for k, v in suite.attrib.items() if k != "time"}
    cases = [
        ({k: v for k, v in c.attrib.items() if k != "time"}, [(x.tag, x.text) for x in c])
        for c in suite.findall("testcase")
    ]
    return counts, cases


def shards(raycast: Path, assets: Path, n: int, work: Path, full: list[dict]) -> dict:
    """N shards then the merge; what they cover and whether the merge equals `full`."""
    files, times, peaks = [], [], []
    for k in range(1, n + 1):
        file = work / f"shard-{k}-of-{n}.jsonl"
        run = timed([raycast, "check", assets, "--shard", f"{k}/{n}", "--json", "-q"], work, file)
        if run["code"] not in (0, 1):
            raise SystemExit(f"check-scale: shard {k}/{n} failed: {run['stderr'][-300:]}")
        files.append(file)
        times.append(run["seconds"])
        peaks.append(run["peak_mib"])
    seen = collections.Counter(r["path"] for f in files for r in records(f))
    expected = collections.Counter(r["path"] for r in full)
    merged_xml = work / f"merged-{n}.xml"
    merged_json = work / f"merged-{n}.jsonl"
    merge = timed(
        [raycast, "check", "--merge", *files, "--json", "--junit", merged_xml, "-q"],
        work,
        merged_json,
    )
    return {
        "n": n,
        "shard_sizes": [len(records(f)) for f in files],
        "every_asset_once": seen == expected and set(seen.values()) == {1},
        "slowest_shard_s": max(times),
        "shards_total_s": sum(times),
        "shard_peak_mib": max(peaks),
        "merge_s": merge["seconds"],
        "merge_code": merge["code"],
        "json_equal": records(merged_json) == full,
        "junit_equal": junit_cases(merged_xml) == junit_cases(work / "full.xml"),
    }


def root_layers(raycast: Path, assets: Path, work: Path, full: list[dict]) -> dict:
    """Assets and EMPTY_SCENE warnings with and without --root-layers-only."""
    cmd = [raycast, "check", assets, "--json", "-q", "--root-layers-only"]
    run = timed(cmd, work, work / "roots.jsonl")
    roots = records(work / "roots.jsonl")

    def empty(rs):
        return sum(f["code"] == "EMPTY_SCENE" for r in rs for f in r["findings"])

    return {
        "assets": (len(full), len(roots)),
        "empty_scene": (empty(full), empty(roots)),
        "seconds": run["seconds"],
    }


def gltf_files(assets: Path) -> list[Path]:
    return sorted(p for p in assets.rglob("*") if p.suffix.lower() in (".gltf", ".glb"))


def gltf_side_by_side(raycast: Path, files: list[Path], work: Path, runs: int) -> dict:
    ours = median_run([raycast, "check", *files, "--json", "-q"], work, runs, work / "g.jsonl")
    verdicts = {r["path"]: r["errors"] > 0 for r in records(work / "g.jsonl")}
    result = {"files": len(files), "raycast": ours}
    if not VALIDATOR.exists() or not shutil.which("node"):
        result["validator"] = (
            f"skipped: no {VALIDATOR.relative_to(ROOT)} (cd tools/npm && npm ci) or no node"
        )
        return result
    theirs = median_run(["node", VALIDATE_CODES, *files], work, runs, work / "v.jsonl")
    errors, thrown = {}, 0
    for line in (work / "v.jsonl").read_text().splitlines():
        v = json.loads(line)
        if "exception" in v:
            thrown += 1  # not glTF at all: an error for both
            errors[v["file"]] = True
        else:
            errors[v["file"]] = v["errors"] > 0
            result["validator_version"] = v["version"]
    differ = [f for f in map(str, files) if f in errors and errors[f] != verdicts.get(f)]
    result.update(
        {
            "validator": theirs,
            "validated": len(errors),
            "thrown": thrown,
            "same_verdict": len(errors) - len(differ),
            "differ": {f: {"validator": errors[f], "raycast": verdicts.get(f)} for f in differ},
        }
    )
    return result


def markdown(r: dict) -> str:
    full = r["unsharded"]
    rows = [
        "| N | shard sizes | every asset once | merge = unsharded (JSON, JUnit, exit) "
        "| slowest shard (s) | all shards (s) | merge (s) | peak MiB |",
        "| ---: | --- | --- | --- | ---: | ---: | ---: | ---: |",
    ]
    for s in r["shards"]:
        same = s["json_equal"] and s["junit_equal"] and s["merge_code"] == full["code"]
        rows.append(
            f"| {s['n']} | {', '.join(map(str, s['shard_sizes']))} | "
            f"{'yes' if s['every_asset_once'] else 'NO'} | "
            f"{'yes' if same else 'NO'} (exit {s['merge_code']}) | {s['slowest_shard_s']:.2f} | "
            f"{s['shards_total_s']:.2f} | {s['merge_s']:.2f} | {s['shard_peak_mib']:.0f} |"
        )
    g = r["gltf"]
    ours = g["raycast"]
    text = [
        f"Assets: {r['assets']} ({r['asset_count']} assets), raycast {r['raycast']}.",
        "",
        f"Unsharded: {full['seconds']:.2f} s (median of {full['all_seconds']}), "
        f"{r['asset_count'] / full['seconds']:.0f} assets/s, peak {full['peak_mib']:.0f} MiB, "
        f"exit {full['code']}.",
        "",
        *rows,
        "",
        f"glTF files alone ({g['files']}): raycast check {ours['seconds']:.2f} s "
        f"({g['files'] / ours['seconds']:.0f} files/s, peak {ours['peak_mib']:.0f} MiB).",
    ]
    roots = r["root_layers"]
    text += [
        "",
        f"--root-layers-only: {roots['assets'][0]} -> {roots['assets'][1]} assets, "
        f"EMPTY_SCENE warnings {roots['empty_scene'][0]} -> {roots['empty_scene'][1]} "
        f"({roots['seconds']:.2f} s, one run).",
        "",
    ]
    v = g["validator"]
    if isinstance(v, str):
        text.append(f"Khronos glTF-Validator: {v}.")
    else:
        text.append(
            f"Khronos glTF-Validator {g.get('validator_version', '?')} (node, one process): "
            f"{v['seconds']:.2f} s ({g['files'] / v['seconds']:.0f} files/s, peak "
            f"{v['peak_mib']:.0f} MiB); same error verdict on {g['same_verdict']} of "
            f"{g['validated']} files ({g['thrown']} it throws on, counted as errors)."
        )
        for f, d in g["differ"].items():
            text.append(
                f"- differs: `{Path(f).relative_to(r['assets_resolved'])}`: validator "
                f"{'error' if d['validator'] else 'no error'}, raycast "
                f"{'error' if d['raycast'] else 'no error'}"
            )
    return "\n".join(text) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=prog("check-scale"), description=__doc__.split("\n\n")[0])
    ap.add_argument("--assets", type=Path, default=ASSETS, help="asset folder (../shared/assets)")
    ap.add_argument("--shards", default="1,3,7", help="shard counts N (default 1,3,7)")
    ap.add_argument("--runs", type=int, default=3, help="runs per timing (median; default 3)")
    ap.add_argument("--raycast", help="raycast binary (default: target/release/raycast)")
    ap.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    args = ap.parse_args(argv)
    if not args.assets.is_dir():
        print(f"check-scale: no asset folder at {args.assets}: skipped", flush=True)
        return 2
    if not TIME.exists():
        print(f"check-scale: {TIME} (GNU time) is needed for peak memory", flush=True)
        return 2
    raycast = raycast_or_exit(args.raycast, "check-scale").resolve()
    assets = args.assets.resolve()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        full_cmd = [raycast, "check", assets, "--json", "--junit", "full.xml", "-q"]
        unsharded = median_run(full_cmd, work, args.runs, work / "full.jsonl")
        full = records(work / "full.jsonl")
        result = {
            "assets": str(args.assets),
            "asset_count": len(full),
            "assets_resolved": str(assets),
            "raycast": subprocess.run(
                [raycast, "--version"], capture_output=True, text=True
            ).stdout.split()[-1],
            "unsharded": unsharded,
            "shards": [shards(raycast, assets, int(n), work, full) for n in args.shards.split(",")],
            "gltf": gltf_side_by_side(raycast, gltf_files(assets), work, args.runs),
            "root_layers": root_layers(raycast, assets, work, full),
        }
    print(markdown(result), end="")
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    ok = all(
        s["every_asset_once"]
        and s["json_equal"]
        and s["junit_equal"]
        and s["merge_code"] == unsharded["code"]
        for s in result["shards"]
    )
    return 0 if ok else 1
