"""Writing fixture files: unchanged files are left alone, every file is listed, and a
check-only run writes nothing."""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

from .gltf_writer import json_text


class FixtureFiles:
    """Writes the files of one fixture generator under `root` and remembers them."""

    def __init__(self, root: Path, check_only: bool = False) -> None:
        self.root = root
        self.check_only = check_only
        self.written: list[Path] = []

    def write_bytes(self, path: Path, data: bytes) -> None:
        """Write `data` unless the file holds it already; print what happened."""
        if self.check_only:
            return
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.exists() and path.read_bytes() == data:
            status = "same"
        else:
            path.write_bytes(data)
            status = "wrote"
        self.written.append(path)
        print(f"  {status:5} {path.relative_to(self.root)} ({len(data)} bytes)")

    def write_json(self, path: Path, doc, raw: dict[str, str] | None = None) -> None:
        """`doc` as gltf_writer.json_text plus a newline; each `raw` placeholder string (it
        must occur once) is replaced by a literal, for JSON no encoder writes (bad fixtures)."""
        text = json_text(doc) + "\n"
        for placeholder, literal in (raw or {}).items():
            assert text.count(json.dumps(placeholder)) == 1, placeholder
            text = text.replace(json.dumps(placeholder), literal)
        self.write_bytes(path, text.encode("utf-8"))

    def write_npy(self, path: Path, array: np.ndarray) -> None:
        buf = io.BytesIO()
        np.save(buf, array, allow_pickle=False)
        self.write_bytes(path, buf.getvalue())

    def kept(self, path: Path) -> None:
        """List a file that is kept as it is (a copy whose source is missing)."""
        self.written.append(path)

    def digest(self) -> str:
        """sha256 over the listed files' names and contents (16 hex digits)."""
        h = hashlib.sha256()
        for p in sorted(self.written):
            h.update(str(p.relative_to(self.root)).encode() + b"\0" + p.read_bytes())
        return h.hexdigest()[:16]
