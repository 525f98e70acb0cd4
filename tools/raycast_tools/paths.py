"""Where things are: the repository root and the raycast binary."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RELEASE = ROOT / "target" / "release" / "raycast"
DEBUG = ROOT / "target" / "debug" / "raycast"


def find_raycast() -> Path:
    """The raycast binary to test: $RAYCAST when set, else target/release, else target/debug,
    else `raycast` on PATH; target/release when there is none (callers check that it exists)."""
    env = os.environ.get("RAYCAST")
    if env:
        return Path(env)
    for path in (RELEASE, DEBUG):
        if path.exists():
            return path
    on_path = shutil.which("raycast")
    return Path(on_path) if on_path else RELEASE


def raycast_or_exit(given: str | None, command: str) -> Path:
    """The binary named by a --raycast option, or find_raycast(); when it does not exist,
    a one-line message naming it and exit status 2 (a usage error)."""
    path = Path(given) if given else find_raycast()
    if not path.exists() and not shutil.which(str(path)):
        print(f"{command}: raycast binary not found: {path}", file=sys.stderr)
        raise SystemExit(2)
    return path
