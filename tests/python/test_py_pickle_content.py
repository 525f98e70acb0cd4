"""A pickled scene refuses a file that changed since it was pickled (a content digest of the
scene file and a .gltf's buffers), unless raycast.CHECK_PICKLED_FILES is False; a file that
changed between loading and pickling is refused at pickling.

Run: .venv/bin/python -m pytest tests/python/test_py_pickle_content.py
"""

import os
import pickle
import shutil
from pathlib import Path

import numpy as np
import pytest

import raycast

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures" / "gltf"


@pytest.fixture
def copied(tmp_path):
    for name in ("cube.gltf", "cube.bin"):
        shutil.copy(FIXTURES / name, tmp_path / name)
    return tmp_path / "cube.gltf"


def nudge(path: Path):
    """Changes one byte of the file in place, and its time, keeping its size."""
    data = bytearray(path.read_bytes())
    data[-1] ^= 1
    path.write_bytes(bytes(data))
    st = os.stat(path)
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000_000))


def test_an_unchanged_file_loads_again(copied):
    scene = raycast.load(copied)
    again = pickle.loads(pickle.dumps(scene))
    assert np.array_equal(again.bounds, scene.bounds)


@pytest.mark.parametrize("which", ["cube.gltf", "cube.bin"])
def test_a_changed_file_or_buffer_is_refused_unless_asked(copied, which, monkeypatch):
    blob = pickle.dumps(raycast.load(copied))
    nudge(copied.parent / which)
    with pytest.raises(raycast.SceneError, match="changed since the scene was pickled"):
        pickle.loads(blob)
    monkeypatch.setattr(raycast, "CHECK_PICKLED_FILES", False)
    try:
        pickle.loads(blob)  # loads the file as it is now (or says why it cannot)
    except raycast.SceneError as e:
        assert "changed since" not in str(e)


def test_a_file_changed_before_pickling_is_refused_then(copied):
    scene = raycast.load(copied)
    nudge(copied.parent / "cube.bin")
    with pytest.raises(raycast.SceneError, match="changed since this scene was loaded"):
        pickle.dumps(scene)
