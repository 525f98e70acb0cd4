"""A tiny glTF writer whose every byte is under our control (struct/base64), so a rerun
writes byte-identical files: the fixtures' and the bench's scenes are written with it."""

from __future__ import annotations

import base64
import json
import struct

import numpy as np

# glTF enums
BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, UNSIGNED_INT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
POINTS, LINES, TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 0, 1, 4, 5, 6

NP_TYPE = {
    BYTE: np.int8,
    UNSIGNED_BYTE: np.uint8,
    SHORT: np.int16,
    UNSIGNED_SHORT: np.uint16,
    UNSIGNED_INT: np.uint32,
    FLOAT: np.float32,
}


def json_text(value, indent: int = 0) -> str:
    """json.dumps(indent=2), except that lists of plain numbers/strings stay on
    one line. Python's float repr is the shortest string that round-trips the
    double, so transforms keep full double precision (see far.gltf)."""
    pad, inner = "  " * indent, "  " * (indent + 1)
    if isinstance(value, dict) and value:
        items = [f"{inner}{json.dumps(k)}: {json_text(v, indent + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(value, list) and value and any(isinstance(v, (dict, list)) for v in value):
        items = [inner + json_text(v, indent + 1) for v in value]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(value, allow_nan=False)


def pad4(data: bytes, fill: bytes = b"\0") -> bytes:
    """`data` padded with `fill` to a multiple of 4 bytes (glTF's alignment)."""
    return data + fill * ((-len(data)) % 4)


def data_uri(data: bytes) -> str:
    """`data` as a base64 `data:` URI, the form of an embedded glTF buffer."""
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode("ascii")


class Gltf:
    """Accumulates one binary buffer plus the JSON that describes it."""

    def __init__(self, generator: str) -> None:
        self.bin = bytearray()
        self.doc: dict = {
            "asset": {"version": "2.0", "generator": generator},
            "extensionsUsed": [],
            "extensionsRequired": [],
            "scene": 0,
            "scenes": [],
            "nodes": [],
            "meshes": [],
            "cameras": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }

    # -- buffer data -------------------------------------------------------
    def view(self, data: bytes, target: int | None = None, stride: int | None = None) -> int:
        self.bin += b"\0" * ((-len(self.bin)) % 4)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride is not None:
            view["byteStride"] = stride
        if target is not None:
            view["target"] = target
        self.bin += data
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, view: int | None, ctype: int, count: int, atype: str, **extra) -> int:
        acc = {}
        if view is not None:
            acc["bufferView"] = view
        acc.update({"componentType": ctype, "count": count, "type": atype})
        acc.update(extra)
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def positions(self, pts) -> int:
        """float32 VEC3 positions, tightly packed, with min/max."""
        a = np.asarray(pts, dtype=np.float32).reshape(-1, 3)
        v = self.view(a.tobytes(), ARRAY_BUFFER)
        return self.accessor(v, FLOAT, len(a), "VEC3", min=fminmax(a, 0), max=fminmax(a, 1))

    def indices(self, idx, ctype: int = UNSIGNED_SHORT) -> int:
        a = np.asarray(idx, dtype=NP_TYPE[ctype]).reshape(-1)
        v = self.view(a.tobytes(), ELEMENT_ARRAY_BUFFER)
        return self.accessor(v, ctype, len(a), "SCALAR")

    # -- scene structure ---------------------------------------------------
    def mesh(self, name: str, primitives: list[dict]) -> int:
        self.doc["meshes"].append({"name": name, "primitives": primitives})
        return len(self.doc["meshes"]) - 1

    def node(self, name: str, **props) -> int:
        n = {"name": name}
        n.update(props)
        self.doc["nodes"].append(n)
        return len(self.doc["nodes"]) - 1

    def scene(self, nodes: list[int], name: str | None = None) -> int:
        s = {"name": name} if name else {}
        s["nodes"] = nodes
        self.doc["scenes"].append(s)
        return len(self.doc["scenes"]) - 1

    def perspective(
        self,
        name: str,
        yfov: float,
        aspect: float | None = None,
        znear: float = 0.1,
        zfar: float | None = None,
    ) -> int:
        p = {}
        if aspect is not None:
            p["aspectRatio"] = aspect
        p["yfov"] = yfov
        p["znear"] = znear
        if zfar is not None:
            p["zfar"] = zfar
        self.doc["cameras"].append({"name": name, "type": "perspective", "perspective": p})
        return len(self.doc["cameras"]) - 1

    def orthographic(self, name: str, xmag: float, ymag: float, znear: float, zfar: float) -> int:
        o = {"xmag": xmag, "ymag": ymag, "znear": znear, "zfar": zfar}
        self.doc["cameras"].append({"name": name, "type": "orthographic", "orthographic": o})
        return len(self.doc["cameras"]) - 1

    def require(self, ext: str) -> None:
        self.doc["extensionsUsed"].append(ext)
        self.doc["extensionsRequired"].append(ext)

    # -- output ------------------------------------------------------------
    def finish(self, uri: str | None, byte_length: int | None = None, **top) -> tuple[dict, bytes]:
        """Return (json document, binary buffer). uri None = GLB BIN chunk,
        "data" = base64 data URI, else the external file name. `top` replaces
        top-level entries of the document (in place, before empty arrays are dropped)."""
        data = bytes(self.bin)
        doc = json.loads(json.dumps(self.doc))  # deep copy
        doc.update(json.loads(json.dumps(top)))
        if data:
            buf = {"byteLength": len(data) if byte_length is None else byte_length}
            if uri == "data":
                buf["uri"] = data_uri(data)
            elif uri is not None:
                buf["uri"] = uri
            doc["buffers"] = [buf]
        # glTF arrays must not be empty when present
        for key in [k for k, v in doc.items() if isinstance(v, list) and not v]:
            del doc[key]
        return doc, data

    def embedded(self) -> dict:
        """The document with its buffer as a base64 data URI."""
        return self.finish("data")[0]

    def glb_bytes(self) -> bytes:
        doc, data = self.finish(None)
        return glb(doc, data)


def glb(doc: dict, data: bytes) -> bytes:
    """A GLB file: the header, the JSON chunk (space-padded) and the BIN chunk when `data`."""
    js = pad4(json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("utf-8"), b" ")
    out = struct.pack("<II", len(js), 0x4E4F534A) + js  # "JSON"
    if data:
        bn = pad4(data)
        out += struct.pack("<II", len(bn), 0x004E4942) + bn  # "BIN\0"
    return struct.pack("<III", 0x46546C67, 2, 12 + len(out)) + out  # "glTF"


def fminmax(a: np.ndarray, which: int) -> list[float]:
    """Per-component min (`which` 0) or max (1) of the rows without NaN, as floats."""
    a = np.asarray(a, dtype=np.float64)
    a = a[~np.isnan(a).any(axis=1)]
    v = a.min(axis=0) if which == 0 else a.max(axis=0)
    return [float(x) for x in v]


def iminmax(a: np.ndarray, which: int) -> list[int]:
    """Per-component min (`which` 0) or max (1) of integer rows, as ints."""
    v = a.min(axis=0) if which == 0 else a.max(axis=0)
    return [int(x) for x in v]


def quadric_document(quadric: dict, matrix: list) -> dict:
    """A glTF document of one node, named `q`, holding the RAYCAST_quadric extension object
    `quadric` placed by the column-major `matrix` (16 numbers)."""
    return {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["RAYCAST_quadric"],
        "extensionsRequired": ["RAYCAST_quadric"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "q", "matrix": matrix, "extensions": {"RAYCAST_quadric": quadric}}],
    }
