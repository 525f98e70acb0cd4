"""The raycast binary the Python tests run: $RAYCAST, else target/release/raycast; tests that
need it are marked `needs_binary` and skip, saying so, when it is not built."""

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RAYCAST = Path(os.environ.get("RAYCAST", ROOT / "target" / "release" / "raycast"))
needs_binary = pytest.mark.skipif(
    not RAYCAST.exists(),
    reason=f"raycast binary not built ({RAYCAST}); run cargo build --release first",
)
