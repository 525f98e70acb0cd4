"""Readers of OBJ and glTF files for `exact-depth` that share no code with raycast: each gives
the drawn objects as world triangles in float64, with the key that names each object in
raycast's sidecar (`name` or `source`).

- OBJ: trimesh (its text parser gives float64; `read_obj` checks every vertex against Python's
  own float parsing of the file's `v` lines and refuses the file if one differs). trimesh reads
  an OBJ as one mesh, so the reference has one object.
- glTF: a small reader written here with numpy and the glTF 2.0 specification: buffers (data
  URI, file, GLB chunk), accessors (byteStride, normalized integers as the specification's
  conversion table says, plain integers as their value), node `matrix` or T·R·S composed in
  float64 down the node tree of the default scene (rotations normalised: the specification
  says unit quaternion), EXT_mesh_gpu_instancing (one object per instance). It refuses what
  it does not read (sparse accessors, non-triangle modes, morph targets, skins, compressed
  geometry, unknown extensions): a reference must not silently draw something else.
"""

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path
from urllib.parse import unquote

import numpy as np


class RefuseError(Exception):
    """The reader cannot read this file exactly; the message says why."""


# --------------------------------------------------------------------------------------- OBJ


def python_obj_vertices(path) -> set[tuple[float, float, float]]:
    """The file's `v` coordinates parsed by Python's float() (correctly rounded)."""
    out = set()
    for line in Path(path).read_text().splitlines():
        words = line.split()
        if words and words[0] == "v":
            out.add(tuple(float(w) for w in words[1:4]))
    return out


def read_obj(path):
    """[(None, triangles)]: the OBJ's faces as trimesh reads them (one object, no name)."""
    import trimesh

    mesh = trimesh.load(str(path), force="mesh", process=False)
    v = np.asarray(mesh.vertices)
    if v.dtype != np.float64:
        raise RefuseError(f"trimesh read the vertices as {v.dtype}, not float64")
    text = python_obj_vertices(path)
    differ = [tuple(p) for p in v.tolist() if tuple(p) not in text]
    if differ:
        raise RefuseError(f"trimesh's vertex {differ[0]} is not a value the file's text gives")
    return [(None, v[np.asarray(mesh.faces)])]


# -------------------------------------------------------------------------------------- glTF

COMPONENT = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
# normalized integer -> float (glTF 2.0, "Animation" / "Meshes" conversion table)
NORMALIZE = {
    5120: lambda c: np.maximum(c / 127.0, -1.0),
    5121: lambda c: c / 255.0,
    5122: lambda c: np.maximum(c / 32767.0, -1.0),
    5123: lambda c: c / 65535.0,
}
INSTANCING = "EXT_mesh_gpu_instancing"
# extensions that change no vertex or transform (or that this reader implements)
HARMLESS = (INSTANCING, "KHR_mesh_quantization", "KHR_lights_punctual", "KHR_texture_transform")
HARMLESS_PREFIXES = ("KHR_materials_", "KHR_texture_", "EXT_texture_")
# raycast's analytic quadrics are not triangles: like exact-depth's USD reference, this one
# leaves them out (rays whose raycast hit is a quadric are not compared)
QUADRIC = "RAYCAST_quadric"


class GltfFile:
    """A glTF document and its buffers."""

    def __init__(self, path):
        path = Path(path)
        data = path.read_bytes()
        chunk = None
        if data[:4] == b"glTF":
            length = struct.unpack_from("<I", data, 12)[0]
            self.doc = json.loads(data[20 : 20 + length])
            at = 20 + length
            if at + 8 <= len(data):
                n, kind = struct.unpack_from("<II", data, at)
                if kind == 0x004E4942:
                    chunk = data[at + 8 : at + 8 + n]
        else:
            self.doc = json.loads(data)
        self.buffers = []
        for b in self.doc.get("buffers", []):
            uri = b.get("uri")
            if uri is None:
                self.buffers.append(chunk)
            elif uri.startswith("data:"):
                self.buffers.append(base64.b64decode(uri.split(",", 1)[1]))
            else:
                self.buffers.append((path.parent / unquote(uri)).read_bytes())
        self.check_supported()

    def check_supported(self):
        """Raise RefuseError for what this reader does not read."""
        for ext in self.doc.get("extensionsUsed", []):
            if ext not in HARMLESS and ext != QUADRIC and not ext.startswith(HARMLESS_PREFIXES):
                raise RefuseError(f"extension {ext} is not read by the reference")
        for i, a in enumerate(self.doc.get("accessors", [])):
            if "sparse" in a:
                raise RefuseError(f"accessor {i} is sparse")
        for m in self.doc.get("meshes", []):
            for p in m["primitives"]:
                if p.get("mode", 4) != 4:
                    raise RefuseError(f"mesh {m.get('name')!r}: primitive mode {p['mode']}")
                if p.get("targets") or p.get("extensions"):
                    raise RefuseError(f"mesh {m.get('name')!r}: morph targets or extensions")
        for i, n in enumerate(self.doc.get("nodes", [])):
            if "skin" in n or "weights" in n:
                raise RefuseError(f"node {i}: skin or morph weights")

    def accessor(self, index) -> np.ndarray:
        """Accessor `index` as float64 rows (count, components)."""
        a = self.doc["accessors"][index]
        dtype = np.dtype(COMPONENT[a["componentType"]])
        ncomp = NCOMP[a["type"]]
        count = a["count"]
        if "bufferView" not in a:
            return np.zeros((count, ncomp))
        view = self.doc["bufferViews"][a["bufferView"]]
        data = self.buffers[view["buffer"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        stride = view.get("byteStride", dtype.itemsize * ncomp)
        rows = np.ndarray(
            (count, ncomp), dtype, buffer=data, offset=start, strides=(stride, dtype.itemsize)
        )
        out = rows.astype(np.float64)
        if a.get("normalized"):
            out = NORMALIZE[a["componentType"]](out)
        return out

    def mesh_triangles(self, index) -> np.ndarray:
        """Mesh `index`'s triangles in its own frame, primitive after primitive."""
        tris = []
        for p in self.doc["meshes"][index]["primitives"]:
            v = self.accessor(p["attributes"]["POSITION"])
            if "indices" in p:
                idx = self.accessor(p["indices"]).astype(np.int64).reshape(-1)
            else:
                idx = np.arange(len(v))
            tris.append(v[idx[: len(idx) // 3 * 3].reshape(-1, 3)])
        return np.concatenate(tris) if tris else np.zeros((0, 3, 3))

    def instances(self, node) -> list[np.ndarray]:
        """The EXT_mesh_gpu_instancing matrices T·R·S of a node."""
        attrs = node["extensions"][INSTANCING]["attributes"]
        read = {
            k: self.accessor(i)
            for k, i in attrs.items()
            if k in ("TRANSLATION", "ROTATION", "SCALE")
        }
        count = len(next(iter(read.values())))
        out = []
        for k in range(count):
            t = read["TRANSLATION"][k] if "TRANSLATION" in read else None
            r = read["ROTATION"][k] if "ROTATION" in read else None
            s = read["SCALE"][k] if "SCALE" in read else None
            out.append(trs_matrix(t, r, s))
        return out

    def objects(self):
        """[(source pointer, world triangles)] of the default scene, depth first."""
        scenes = self.doc.get("scenes", [])
        if not scenes:
            raise RefuseError("no scenes")
        roots = scenes[self.doc.get("scene", 0)].get("nodes", [])
        out = []
        stack = [(i, np.eye(4)) for i in reversed(roots)]
        while stack:
            i, parent = stack.pop()
            node = self.doc["nodes"][i]
            world = parent @ local_matrix(node)
            if "mesh" in node:
                local = self.mesh_triangles(node["mesh"])
                if INSTANCING in node.get("extensions", {}):
                    for k, m in enumerate(self.instances(node)):
                        out.append(
                            (f"/nodes/{i}/extensions/{INSTANCING}/{k}", place(local, world @ m))
                        )
                else:
                    out.append((f"/nodes/{i}", place(local, world)))
            stack += [(c, world) for c in reversed(node.get("children", []))]
        return out


def quaternion_matrix(q) -> np.ndarray:
    """3x3 rotation of the glTF (x, y, z, w) quaternion, normalised first: the specification
    says a rotation is a unit quaternion, and a quantized one (EXT_mesh_gpu_instancing's
    normalized byte/short ROTATION) is unit only to about 1e-4. (three.js composes the stored
    values without normalising; on fixtures/compressed/cubes.instanced.glb the two readings
    differ by 4e-5 relative depth.)"""
    q = np.asarray(q, np.float64)
    norm = math.sqrt(float(q @ q))
    if not norm > 0:
        raise RefuseError(f"rotation {q.tolist()} is not a rotation")
    x, y, z, w = (float(c) / norm for c in q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def trs_matrix(t, r, s) -> np.ndarray:
    """The 4x4 matrix T·R·S (each part optional)."""
    m = np.eye(4)
    if r is not None:
        m[:3, :3] = quaternion_matrix(r)
    if s is not None:
        m[:3, :3] = m[:3, :3] * np.asarray(s, np.float64)  # columns scaled: R·S
    if t is not None:
        m[:3, 3] = t
    return m


def local_matrix(node) -> np.ndarray:
    """A node's local matrix: `matrix` (column-major) or T·R·S."""
    if "matrix" in node:
        return np.array(node["matrix"], np.float64).reshape(4, 4).T
    return trs_matrix(node.get("translation"), node.get("rotation"), node.get("scale"))


def place(tris, m) -> np.ndarray:
    """Triangles (n, 3, 3) moved by the 4x4 matrix `m`, in float64."""
    return tris @ m[:3, :3].T + m[:3, 3]


def read_gltf(path):
    """[(source pointer, world triangles)]: the glTF's drawn mesh objects."""
    return GltfFile(path).objects()
