"""`--colormap`: the depth previews in grey (one channel, the default), viridis and turbo
(three channels), near at the map's top end, misses black, read back with Pillow.

Run: .venv/bin/python -m pytest tests/python/test_previews.py
"""

import json
import subprocess

import numpy as np
import pytest
from binary import RAYCAST, ROOT, needs_binary
from PIL import Image

SCENE = ROOT / "fixtures" / "assets" / "DamagedHelmet.glb"


@needs_binary
@pytest.mark.parametrize(
    ("colormap", "mode", "near", "far"),
    [
        (None, "L", (255,), (40,)),
        ("viridis", "RGB", (253, 231, 37), (68, 1, 84)),
        ("turbo", "RGB", (122, 4, 3), (48, 18, 59)),
    ],
)
def test_previews_map_near_to_the_top_of_the_colour_map(tmp_path, colormap, mode, near, far):
    command = [
        RAYCAST,
        SCENE,
        "--aov",
        "depth",
        "--format",
        "png,npy",
        "--width",
        "48",
        "--height",
        "40",
    ]
    if colormap:
        command += ["--colormap", colormap]
    subprocess.run([*command, "--out", tmp_path, "-q"], check=True)
    image = Image.open(tmp_path / "depth.png")
    assert image.mode == mode
    pixels = np.asarray(image).reshape(40, 48, -1).astype(int)
    depth = np.load(tmp_path / "depth.npy")
    lo, hi = json.loads((tmp_path / "raycast.json").read_text())["depth_png_range"]
    assert (pixels[~np.isfinite(depth)] == 0).all()
    # The published end colours, within what the polynomial fits miss them by (Turbo's by
    # up to 32 steps at its ends: (35, 23, 27) and (144, 13, 0)).
    tolerance = 33 if colormap == "turbo" else 4
    assert np.abs(pixels[depth <= lo] - near).max() <= tolerance
    assert np.abs(pixels[np.isfinite(depth) & (depth >= hi)] - far).max() <= tolerance
