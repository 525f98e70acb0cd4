"""What a pickled scene checks when it loads again: a digest of the files it was read from
(the scene file, and a ``.gltf`` file's external buffers), so that a worker does not silently
draw a file that changed since the scene was pickled.

The digest is taken when the scene is pickled, after checking that the files still have the
size and modification time they had when the scene was loaded (a file changed in between is
refused then, not later). USD layers a stage composes and OBJ material files are not covered:
the stage's own file is."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from urllib.parse import unquote

from .errors import SceneError

#: Bytes read at a time while hashing.
BLOCK = 1 << 20


def files_of(path: Path) -> list[Path]:
    """The scene file and, for a ``.gltf``, the buffer files its ``buffers`` name (not
    ``data:`` URIs)."""
    files = [path]
    if path.suffix.lower() == ".gltf":
        try:
            document = json.loads(path.read_bytes())
            buffers = document.get("buffers", []) if isinstance(document, dict) else []
        except (OSError, ValueError):
            buffers = []
        for buffer in buffers:
            uri = buffer.get("uri") if isinstance(buffer, dict) else None
            if isinstance(uri, str) and not uri.startswith("data:"):
                files.append(path.parent / unquote(uri))
    return files


def stamp(path: Path) -> list[tuple[str, int, int]]:
    """Each file's name, size and modification time (missing files: -1, -1)."""
    out = []
    for f in files_of(path):
        try:
            st = os.stat(f)
            out.append((os.fspath(f), st.st_size, st.st_mtime_ns))
        except OSError:
            out.append((os.fspath(f), -1, -1))
    return out


def digest(path: Path) -> str:
    """BLAKE2b of the files' names (relative to the scene's folder) and contents."""
    h = hashlib.blake2b(digest_size=20)
    for f in files_of(path):
        h.update(os.path.relpath(f, path.parent).encode() + b"\0")
        try:
            with open(f, "rb") as stream:
                size = os.fstat(stream.fileno()).st_size
                h.update(size.to_bytes(8, "little"))
                while block := stream.read(BLOCK):
                    h.update(block)
        except OSError:
            h.update(b"missing\0")
    return h.hexdigest()


def digest_unchanged_since(path: Path, loaded: list) -> str:
    """The digest of the files, which must still be as they were when the scene was loaded
    (``loaded``, from :func:`stamp`)."""
    if stamp(path) != loaded:
        raise SceneError(
            f"{path}: the file changed since this scene was loaded; load it again before"
            " pickling, so that the pickle holds what the scene drew"
        )
    return digest(path)


def check(path: Path, expected: str, enabled: bool) -> None:
    """Refuses (``SceneError``) files whose digest is not ``expected``, unless not
    ``enabled``."""
    if enabled and digest(path) != expected:
        raise SceneError(
            f"{path}: the file changed since the scene was pickled (its content digest"
            " differs); set raycast.CHECK_PICKLED_FILES = False to load it as it is now"
        )
