"""The one command line of the tools: `python -m raycast_tools COMMAND`.

Run: .venv/bin/python -m pytest tests/python/test_cli.py
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from raycast_tools import paths
from raycast_tools.bench import thread_scaling
from raycast_tools.cli import COMMANDS, main


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_every_command_has_help(name, capsys):
    with pytest.raises(SystemExit) as done:
        main([name, "--help"])
    assert done.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: python -m raycast_tools {name} ")


def test_list_unknown_and_missing_command(capsys):
    assert main(["--help"]) == 0
    listed = capsys.readouterr().out
    assert all(f"  {name} " in listed for name in COMMANDS)
    assert main(["no-such-command"]) == 2
    assert "unknown command 'no-such-command'" in capsys.readouterr().err
    assert main([]) == 2


def test_module_entry_point():
    p = subprocess.run(
        [sys.executable, "-m", "raycast_tools", "--help"], capture_output=True, text=True
    )
    assert p.returncode == 0 and "thread-scaling" in p.stdout


def test_find_raycast_order(tmp_path, monkeypatch):
    fake = tmp_path / "raycast"
    monkeypatch.setenv("RAYCAST", str(fake))
    assert paths.find_raycast() == fake
    monkeypatch.delenv("RAYCAST")
    release, debug = tmp_path / "release", tmp_path / "debug"
    monkeypatch.setattr(paths, "RELEASE", release)
    monkeypatch.setattr(paths, "DEBUG", debug)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    assert paths.find_raycast() == release  # none exists: the release path, for the message
    debug.write_text("")
    assert paths.find_raycast() == debug
    release.write_text("")
    assert paths.find_raycast() == release


def test_missing_binary_is_a_usage_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as done:
        paths.raycast_or_exit(str(tmp_path / "nope"), "validate")
    assert done.value.code == 2
    assert capsys.readouterr().err == f"validate: raycast binary not found: {tmp_path / 'nope'}\n"


# A raycast double: writes the sidecar's timings (trace = threads + 0.25 s) into --out.
FAKE = """#!/bin/sh
while [ $# -gt 0 ]; do
  case "$1" in --out) out=$2; shift;; --threads) t=$2; shift;; esac; shift
done
mkdir -p "$out"
echo "{\\"timings\\": {\\"build\\": 0.5, \\"trace\\": $t.25}}" > "$out/raycast.json"
"""


def test_thread_scaling_writes_one_line_per_run(tmp_path):
    fake = tmp_path / "raycast"
    fake.write_text(FAKE)
    fake.chmod(0o755)
    out = tmp_path / "out"
    env = {k: v for k, v in os.environ.items() if k not in ("PINNING", "BIG_SCENE")}
    p = subprocess.run(
        [
            sys.executable,
            "-m",
            "raycast_tools",
            "thread-scaling",
            "--raycast",
            str(fake),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
    )
    assert p.returncode == 0, p.stderr
    rows = [line.split() for line in (out / "scaling.txt").read_text().splitlines()]
    runs = len(thread_scaling.ACCELS) * len(thread_scaling.THREADS) * len(thread_scaling.RUNS)
    assert len(rows) == len(thread_scaling.SCENES) * runs
    assert rows[0] == ["stanford-bunny.obj", "octree", "1", "1", "0.5", "1.25"]
    assert rows[-1] == ["DamagedHelmet.glb", "octree", "16", "3", "0.5", "16.25"]
    assert (out / "machine.txt").read_text().startswith(f"cpu: {os.cpu_count()} cores,")
    assert not (out / "pinning.txt").exists()
    assert Path(out / "topology.txt").exists()
