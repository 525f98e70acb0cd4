"""docs/ci.md's workflows run locally: the `raycast check` lines of its GitHub Actions and
GitLab YAML, as written, for N shards and then the merge, compared with an unsharded run of
the same folder; and the merged `--summary` rendered as GitHub Markdown (CommonMark with GFM
tables) and read back against the JSON records.

Run: .venv/bin/python -m pytest tests/python/test_check_ci.py
"""

from __future__ import annotations

import collections
import json
import os
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml
from markdown_it import MarkdownIt

from raycast_tools import paths

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "ci.md"
# Fixture folders making a small library: valid and broken glTF, OBJ and USD.
LIBRARY = ["gltf", "obj", "usd", "bad", "malformed"]
# An asset whose name needs escaping in Markdown and in GitHub annotations.
ODD_NAME = "we|ird_*name*.obj"

RAYCAST = paths.find_raycast()
pytestmark = pytest.mark.skipif(
    not RAYCAST.exists(), reason=f"no raycast binary at {RAYCAST} (cargo build --release)"
)


def yaml_block(heading: str) -> dict:
    """The first ```yaml block after `## heading` in docs/ci.md, parsed."""
    section = DOC.read_text().split(f"## {heading}\n", 1)[1]
    return yaml.safe_load(section.split("```yaml\n", 1)[1].split("```", 1)[0])


def only(commands: list[str], what: str) -> str:
    assert len(commands) == 1, f"docs/ci.md: expected one {what} line, found {commands}"
    return commands[0]


def github_steps() -> tuple[dict, list[int], str, str]:
    """(env, matrix, shard line, merge line) of the GitHub workflow."""
    flow = yaml_block("GitHub Actions")
    check, merge = flow["jobs"]["check"], flow["jobs"]["merge"]
    assert merge["needs"] == "check"

    def runs(job):
        return [s["run"] for s in job["steps"] if "raycast check" in s.get("run", "")]

    return (
        flow["env"],
        check["strategy"]["matrix"]["shard"],
        only(runs(check), "shard"),
        only(runs(merge), "merge"),
    )


def gitlab_steps() -> tuple[dict, int, str, str]:
    """(variables, parallel, shard line, merge line) of the GitLab pipeline."""
    flow = yaml_block("GitLab CI")
    shard, merge = flow["check-shard"], flow["check-merge"]
    assert merge["needs"] == ["check-shard"]

    def lines(job):
        return [line for line in job["script"] if "raycast check" in line]

    return (
        flow["variables"],
        shard["parallel"],
        only(lines(shard), "shard"),
        only(lines(merge), "merge"),
    )


def make_library(work: Path, folder: str) -> None:
    for name in LIBRARY:
        shutil.copytree(ROOT / "fixtures" / name, work / folder / name)
    shutil.copy(ROOT / "fixtures" / "bad" / "garbage.obj", work / folder / ODD_NAME)


def bash(command: str, work: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    full = {**os.environ, **env, "PATH": f"{RAYCAST.parent}{os.pathsep}{os.environ['PATH']}"}
    return subprocess.run(
        ["bash", "-e", "-c", command], cwd=work, env=full, capture_output=True, text=True
    )


def records(path: Path) -> list[dict]:
    """JSON Lines records without their timing."""
    out = []
    for line in path.read_text().splitlines():
        record = json.loads(line)
        record.pop("seconds", None)
        out.append(record)
    return out


def junit_cases(path: Path) -> tuple[dict, list]:
    """The suite's counts and every testcase without its time."""
    root = ET.parse(path).getroot()
    suite = root.find("testsuite")
    counts = {k: v for k, v in suite.attrib.items() if k != "time"}
    cases = []
    for case in suite.findall("testcase"):
        attrs = {k: v for k, v in case.attrib.items() if k != "time"}
        cases.append((attrs, [(child.tag, child.attrib, child.text) for child in case]))
    return counts, cases


def unsharded(work: Path, folder: str) -> tuple[int, list[dict]]:
    """Exit code and records of a plain run; also writes full.xml."""
    run = subprocess.run(
        [RAYCAST, "check", folder, "--json", "--junit", "full.xml", "-q"],
        cwd=work,
        capture_output=True,
        text=True,
    )
    assert run.returncode in (0, 1), run.stderr
    (work / "full.jsonl").write_text(run.stdout)
    return run.returncode, records(work / "full.jsonl")


def check_shards(work: Path, n: int, full: list[dict]) -> None:
    """The N shard files cover every asset of the plain run exactly once."""
    seen = collections.Counter()
    for k in range(1, n + 1):
        lines = (work / f"shard-{k}.jsonl").read_text().splitlines()
        header = json.loads(lines[0])["raycast_check_shard"]
        assert (header["index"], header["count"], header["total"]) == (k, n, len(full))
        assert header["assets"] == len(lines) - 1
        seen.update(json.loads(line)["path"] for line in lines[1:])
    assert seen == collections.Counter(r["path"] for r in full)
    assert set(seen.values()) == {1}


def compare_merge(work: Path, merge: subprocess.CompletedProcess, code: int, full: list[dict]):
    assert merge.returncode == code, merge.stderr
    assert records(work / "check.jsonl") == full
    assert junit_cases(work / "check.xml") == junit_cases(work / "full.xml")


@pytest.mark.parametrize("n", [1, 3, None])  # None: the doc's own matrix
def test_github_workflow(tmp_path, n):
    env, matrix, shard_line, merge_line = github_steps()
    shards = list(range(1, n + 1)) if n else matrix
    make_library(tmp_path, env["ASSETS"])
    code, full = unsharded(tmp_path, env["ASSETS"])
    for k in shards:
        line = shard_line.replace("${{ matrix.shard }}", str(k))
        line = line.replace("${{ strategy.job-total }}", str(len(shards)))
        assert "${{" not in line, line
        run = bash(line, tmp_path, env)
        assert run.returncode == 0, run.stderr
    check_shards(tmp_path, len(shards), full)
    merge = bash(merge_line, tmp_path, env)
    compare_merge(tmp_path, merge, code, full)
    # Annotations: GitHub's caps of 10 per type, then a notice pointing to the summary.
    kinds = collections.Counter(line.split(" ", 1)[0] for line in merge.stderr.splitlines())
    assert kinds["::error"] == 10 and kinds["::warning"] <= 10, merge.stderr
    assert kinds["::notice"] == 1 and "summary.md" in merge.stderr
    check_summary(tmp_path / "summary.md", full)


@pytest.mark.parametrize("n", [1, 3, None])  # None: the doc's own `parallel:`
def test_gitlab_pipeline(tmp_path, n):
    variables, parallel, shard_line, merge_line = gitlab_steps()
    total = n or parallel
    make_library(tmp_path, variables["ASSETS"])
    code, full = unsharded(tmp_path, variables["ASSETS"])
    for k in range(1, total + 1):
        node = {"CI_NODE_INDEX": str(k), "CI_NODE_TOTAL": str(total)}
        run = bash(shard_line, tmp_path, {**variables, **node})
        assert run.returncode == 0, run.stderr
    check_shards(tmp_path, total, full)
    compare_merge(tmp_path, bash(merge_line, tmp_path, variables), code, full)


def tables(markdown: str) -> list[list[list[str]]]:
    """Every table as rows of cell texts (header row first), as a GFM renderer sees them."""
    tokens = MarkdownIt("commonmark").enable("table").parse(markdown)
    out, table, row = [], None, None
    for token in tokens:
        if token.type == "table_open":
            table = []
        elif token.type == "table_close":
            out.append(table)
            table = None
        elif token.type == "tr_open":
            row = []
        elif token.type == "tr_close":
            table.append(row)
            row = None
        elif token.type == "inline" and row is not None and table is not None:
            text = "".join(c.content for c in token.children or [])
            row.append(text)
    return out


def check_summary(path: Path, full: list[dict]) -> None:
    """The summary's tables, read by a Markdown parser, agree with the JSON records."""
    found = tables(path.read_text())
    assert len(found) == 4, path.read_text()
    status, codes, worst, slowest = found
    for table in found:
        assert all(len(row) == len(table[0]) for row in table), table
    by_status = collections.Counter(r["status"] for r in full)
    assert {row[0]: int(row[1]) for row in status[1:]} == {
        s: by_status[s] for s in ("error", "warning", "ok")
    }
    by_code = collections.Counter()
    assets_by_code = collections.Counter()
    for r in full:
        for key in {(f["severity"], f["code"]) for f in r["findings"]}:
            assets_by_code[key] += 1
        by_code.update((f["severity"], f["code"]) for f in r["findings"])
    assert {(row[0], row[1]): (int(row[2]), int(row[3])) for row in codes[1:]} == {
        key: (by_code[key], assets_by_code[key]) for key in by_code
    }
    by_path = {r["path"]: r for r in full}
    most = max((r["errors"], r["warnings"]) for r in full)
    assert worst[1][1:3] == [str(most[0]), str(most[1])]
    for row in worst[1:]:
        record = by_path[re.sub(r" ✗$", "", row[0])]
        assert (int(row[1]), int(row[2])) == (record["errors"], record["warnings"])
    assert len(slowest) == 11 and all(row[0] in by_path for row in slowest[1:])


def test_summary_escapes_odd_names(tmp_path):
    library = tmp_path / "lib"
    library.mkdir()
    shutil.copy(ROOT / "fixtures" / "obj" / "two_objects.obj", library / "plain.obj")
    shutil.copy(ROOT / "fixtures" / "bad" / "garbage.obj", library / ODD_NAME)
    run = subprocess.run(
        [RAYCAST, "check", library, "--summary", tmp_path / "s.md", "--json", "-q"],
        capture_output=True,
        text=True,
    )
    assert run.returncode == 1, run.stderr
    full = [json.loads(line) for line in run.stdout.splitlines()]
    _, _, worst, slowest = tables((tmp_path / "s.md").read_text())
    assert [row[0] for row in worst[1:]] == [f"{library / ODD_NAME} ✗"]
    assert sorted(row[0] for row in slowest[1:]) == sorted(r["path"] for r in full)
