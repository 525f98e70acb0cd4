"""Write the hand-checkable test fixtures under fixtures/.

Run with the repo's venv:  .venv/bin/python -m raycast_tools fixtures

Only numpy and the standard library are used. The glTF JSON and binary buffers
are written directly (struct/base64), so every byte is under our control and a
rerun produces byte-identical files. fixtures/README.md documents each fixture
and the ray-cast answers that can be worked out by hand; tests/python/
test_fixtures.py checks those answers with trimesh as an independent reference.

The script also copies a few third-party assets from the shared asset folder
(<repo>/../shared/assets, or $RAYCAST_SHARED_ASSETS) into fixtures/assets/.
When that folder is missing (a bare clone), copies already in fixtures/assets/
are kept as they are.
"""

from __future__ import annotations

import argparse
import math
import os
import struct
import sys
from pathlib import Path

import numpy as np

from .cli import prog
from .fixture_files import FixtureFiles
from .gltf_writer import (
    ARRAY_BUFFER,
    FLOAT,
    LINES,
    POINTS,
    SHORT,
    TRIANGLE_FAN,
    TRIANGLE_STRIP,
    TRIANGLES,
    UNSIGNED_BYTE,
    UNSIGNED_INT,
    UNSIGNED_SHORT,
    Gltf,
    fminmax,
    iminmax,
)
from .paths import ROOT

FIX = ROOT / "fixtures"
GLTF_DIR = FIX / "gltf"
OBJ_DIR = FIX / "obj"
BAD_DIR = FIX / "bad"
ASSET_DIR = FIX / "assets"
SHARED_ASSETS = Path(os.environ.get("RAYCAST_SHARED_ASSETS", ROOT.parent / "shared" / "assets"))

# Fixture content: it names the script's path before the tools became one package, and stays
# as it is so that the fixtures regenerate byte-identical.
GENERATOR = "raycast tools/make_fixtures.py"

# sin(45 deg) == cos(45 deg) in double precision; the quaternion (0, S, 0, S)
# is a 90 degree rotation about +Y: it maps +X -> -Z and +Z -> +X.
S45 = math.sqrt(0.5)
ROT_Y90 = [0.0, S45, 0.0, S45]

FILES = FixtureFiles(ROOT)


# --------------------------------------------------------------------------
# geometry


def cube(h: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Cube [-h,h]^3: 8 vertices, 12 outward counter-clockwise triangles.

    Vertex i: x = +h if i in {1,2,5,6}, y = +h if i in {2,3,6,7}, z = +h if i >= 4.
    Triangle order (prim index): 0,1 +Z; 2,3 -Z; 4,5 +X; 6,7 -X; 8,9 +Y; 10,11 -Y.
    """
    v = (
        np.array(
            [
                [-1, -1, -1],
                [1, -1, -1],
                [1, 1, -1],
                [-1, 1, -1],
                [-1, -1, 1],
                [1, -1, 1],
                [1, 1, 1],
                [-1, 1, 1],
            ],
            dtype=np.float64,
        )
        * h
    )
    f = np.array(
        [
            [4, 5, 6],
            [4, 6, 7],  # +Z
            [0, 2, 1],
            [0, 3, 2],  # -Z
            [1, 2, 6],
            [1, 6, 5],  # +X
            [0, 4, 7],
            [0, 7, 3],  # -X
            [3, 7, 6],
            [3, 6, 2],  # +Y
            [0, 1, 5],
            [0, 5, 4],
        ],  # -Y
        dtype=np.int64,
    )
    check_outward(v, f)
    return v, f


def check_outward(v: np.ndarray, f: np.ndarray) -> None:
    tri = v[f]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    centre = v.mean(axis=0)
    assert (np.einsum("ij,ij->i", n, tri.mean(axis=1) - centre) > 0).all(), "winding not outward"


# 2x2 quad in z = 0, normal +Z. Triangle 0 = (0,1,2) covers y < x, triangle 1 = (0,2,3)
# covers y > x.
QUAD_V = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=np.float64)
QUAD_F = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)


def add_cube_mesh(g: Gltf, name: str = "cube", h: float = 1.0) -> int:
    v, f = cube(h)
    pos = g.positions(v)
    idx = g.indices(f, UNSIGNED_SHORT)
    return g.mesh(name, [{"attributes": {"POSITION": pos}, "indices": idx, "mode": TRIANGLES}])


def add_quad_mesh(g: Gltf, name: str, z: float = 0.0, ctype: int = UNSIGNED_SHORT) -> int:
    pos = g.positions(QUAD_V + [0, 0, z])
    idx = g.indices(QUAD_F, ctype)
    return g.mesh(name, [{"attributes": {"POSITION": pos}, "indices": idx}])


# --------------------------------------------------------------------------
# glTF fixtures


def make_cube() -> None:
    def build() -> Gltf:
        g = Gltf(GENERATOR)
        m = add_cube_mesh(g)
        c = g.perspective("cam", yfov=0.5, aspect=1.0, znear=0.1)
        n0 = g.node("cube", mesh=m)
        n1 = g.node("cam", camera=c, translation=[0.0, 0.0, 5.0])
        g.scene([n0, n1])
        return g

    doc, data = build().finish("cube.bin")
    FILES.write_json(GLTF_DIR / "cube.gltf", doc)
    FILES.write_bytes(GLTF_DIR / "cube.bin", data)
    FILES.write_bytes(GLTF_DIR / "cube.glb", build().glb_bytes())
    FILES.write_json(GLTF_DIR / "cube_embedded.gltf", build().embedded())


def make_plane() -> None:
    g = Gltf(GENERATOR)
    m = add_quad_mesh(g, "plane", ctype=UNSIGNED_INT)
    g.scene([g.node("plane", mesh=m)])
    FILES.write_json(GLTF_DIR / "plane.gltf", g.embedded())


def make_modes() -> None:
    g = Gltf(GENERATOR)
    # TRIANGLES, non-indexed: the quad's two triangles as 6 vertices.
    tris = g.mesh(
        "tris",
        [{"attributes": {"POSITION": g.positions(QUAD_V[QUAD_F.reshape(-1)])}, "mode": TRIANGLES}],
    )
    # TRIANGLE_STRIP, indexed: strip order (-1,-1) (1,-1) (-1,1) (1,1) through the quad's vertices.
    strip = g.mesh(
        "strip",
        [
            {
                "attributes": {"POSITION": g.positions(QUAD_V)},
                "indices": g.indices([0, 1, 3, 2], UNSIGNED_SHORT),
                "mode": TRIANGLE_STRIP,
            }
        ],
    )
    # TRIANGLE_FAN, non-indexed: centre (0,0) then the 4 corners, closing on the first corner:
    # 4 triangles (bottom, right, top, left).
    fan_v = np.array(
        [[0, 0, 0], [-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0], [-1, -1, 0]], float
    )
    fan = g.mesh("fan", [{"attributes": {"POSITION": g.positions(fan_v)}, "mode": TRIANGLE_FAN}])
    # POINTS / LINES: must be skipped. If either were wrongly read as TRIANGLES its first
    # three vertices would make a real triangle (lower-right half of the quad).
    pts = g.mesh("points", [{"attributes": {"POSITION": g.positions(QUAD_V[:3])}, "mode": POINTS}])
    lines = g.mesh("lines", [{"attributes": {"POSITION": g.positions(QUAD_V)}, "mode": LINES}])
    nodes = [
        g.node("tris", mesh=tris, translation=[-3.0, 0.0, 0.0]),
        g.node("strip", mesh=strip),
        g.node("fan", mesh=fan, translation=[3.0, 0.0, 0.0]),
        g.node("points", mesh=pts, translation=[0.0, 3.0, 0.0]),
        g.node("lines", mesh=lines, translation=[0.0, -3.0, 0.0]),
    ]
    g.scene(nodes)
    FILES.write_json(GLTF_DIR / "modes.gltf", g.embedded())


def make_sparse() -> None:
    g = Gltf(GENERATOR)
    base = np.asarray(QUAD_V, np.float32)
    final = base.copy()
    final[1] = [1, -1, 1]
    final[2] = [1, 1, 1]
    base_view = g.view(base.tobytes(), ARRAY_BUFFER)
    sp_idx = g.view(np.array([1, 2], np.uint16).tobytes())
    sp_val = g.view(final[[1, 2]].tobytes())
    pos = g.accessor(
        base_view,
        FLOAT,
        4,
        "VEC3",
        min=fminmax(final, 0),
        max=fminmax(final, 1),
        sparse={
            "count": 2,
            "indices": {"bufferView": sp_idx, "componentType": UNSIGNED_SHORT},
            "values": {"bufferView": sp_val},
        },
    )
    idx = g.indices(QUAD_F, UNSIGNED_SHORT)
    m = g.mesh("sparse", [{"attributes": {"POSITION": pos}, "indices": idx}])
    g.scene([g.node("sparse", mesh=m)])
    FILES.write_json(GLTF_DIR / "sparse.gltf", g.embedded())


def make_quantized() -> None:
    g = Gltf(GENERATOR)
    g.require("KHR_mesh_quantization")
    unit = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.int64)

    def strided(raw: np.ndarray, dtype, stride: int) -> bytes:
        """Vertex attributes must start on 4-byte boundaries: pad each vertex to `stride`."""
        out = bytearray()
        for row in raw:
            b = np.asarray(row, dtype=dtype).tobytes()
            out += b + b"\0" * (stride - len(b))
        return bytes(out)

    meshes = []
    for name, ctype, dtype, full, stride in [
        ("short", SHORT, np.int16, 32767, 8),
        ("ubyte", UNSIGNED_BYTE, np.uint8, 255, 4),
    ]:
        raw = unit * full
        v = g.view(strided(raw, dtype, stride), ARRAY_BUFFER, stride=stride)
        pos = g.accessor(
            v, ctype, 4, "VEC3", normalized=True, min=iminmax(raw, 0), max=iminmax(raw, 1)
        )
        idx = g.indices(QUAD_F, UNSIGNED_BYTE)
        meshes.append(g.mesh(name, [{"attributes": {"POSITION": pos}, "indices": idx}]))
    n0 = g.node("short", mesh=meshes[0], translation=[-1.0, -1.0, 0.0], scale=[2.0, 2.0, 1.0])
    n1 = g.node("ubyte", mesh=meshes[1], translation=[2.0, -1.0, 0.0], scale=[2.0, 2.0, 1.0])
    g.scene([n0, n1])
    FILES.write_json(GLTF_DIR / "quantized.gltf", g.embedded())


def make_instances() -> None:
    g = Gltf(GENERATOR)
    m = add_cube_mesh(g, "half_cube", 0.5)
    a = g.node("a", mesh=m, translation=[3.0, 0.0, 0.0])
    b = g.node("b", mesh=m, rotation=ROT_Y90, translation=[-3.0, 0.0, 0.0])
    # column-major: scale (1,2,1), translation (0,3,0)
    c = g.node(
        "c",
        mesh=m,
        matrix=[1.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 0.0, 1.0],
    )
    d = g.node("d", mesh=m, translation=[0.0, 0.0, 2.0])
    g.doc["nodes"][c]["children"] = [d]
    mirror = g.node("mirror", mesh=m, translation=[0.0, -3.0, 0.0], scale=[-1.0, 1.0, 1.0])
    g.scene([a, b, c, mirror])
    FILES.write_json(GLTF_DIR / "instances.gltf", g.embedded())


def make_scenes() -> None:
    g = Gltf(GENERATOR)
    m = add_quad_mesh(g, "quad")
    n0 = g.node("first_quad", mesh=m)
    n1 = g.node("second_quad", mesh=m, translation=[0.0, 0.0, -2.0])
    g.scene([n0], "first")
    g.scene([n1], "second")
    g.doc["scene"] = 1
    FILES.write_json(GLTF_DIR / "scenes.gltf", g.embedded())


def make_cameras() -> None:
    g = Gltf(GENERATOR)
    m = add_cube_mesh(g)
    cp = g.perspective("persp", yfov=0.8, aspect=2.0, znear=0.1)
    co = g.orthographic("ortho", xmag=2.0, ymag=1.0, znear=0.1, zfar=100.0)
    nodes = [
        g.node("cube", mesh=m),
        g.node("persp", camera=cp, translation=[0.0, 0.0, 5.0]),
        g.node("ortho", camera=co, rotation=ROT_Y90, translation=[5.0, 0.0, 0.0]),
    ]
    g.scene(nodes)
    FILES.write_json(GLTF_DIR / "cameras.gltf", g.embedded())


FAR = (10000000.25, -3000000.5, 12345678.125)


def make_far() -> None:
    # x and z are not representable in f32 (they round to 10000000 and 12345678); y is.
    assert [float(np.float32(x)) == x for x in FAR] == [False, True, False]
    g = Gltf(GENERATOR)
    m = add_cube_mesh(g)
    c = g.perspective("cam", yfov=0.5, aspect=1.0, znear=0.1)
    n0 = g.node("cube", mesh=m, translation=list(FAR))
    n1 = g.node("cam", camera=c, translation=[FAR[0], FAR[1], FAR[2] + 5.0])
    g.scene([n0, n1])
    FILES.write_json(GLTF_DIR / "far.gltf", g.embedded())


# trap.gltf constants (all exact in f32)
TRAP_SLOPE = 3.0 / 256.0  # big triangle plane: z - 0.25 = TRAP_SLOPE * (x - 8)


def trap_z(x: float) -> float:
    return 0.25 + TRAP_SLOPE * (x - 8.0)


def corner_filler() -> tuple[np.ndarray, np.ndarray]:
    """256 tiny triangles, 32 at each corner of [-10,10]^3, one vertex on the corner.
    They pin the scene bounds to exactly [-10,10]^3 and give the octree enough
    triangles to subdivide; no documented ray comes near them."""
    verts, faces = [], []
    for corner in range(8):
        sx, sy, sz = (1 if corner & 1 else -1), (1 if corner & 2 else -1), (1 if corner & 4 else -1)
        c = np.array([10.0 * sx, 10.0 * sy, 10.0 * sz])
        inward = -np.array([sx, sy, sz], float)
        for k in range(32):
            a = 0.25 + k / 128.0  # 0.25 .. 0.4921875
            p1 = c + inward * [a, 0.5, 0.0]
            p2 = c + inward * [0.0, a, 0.5]
            base = len(verts)
            verts += [c, p1, p2]
            faces.append([base, base + 1, base + 2])
    return np.array(verts), np.array(faces)


def make_trap() -> None:
    g = Gltf(GENERATOR)
    big_v = np.array(
        [[-9.5, -0.5, trap_z(-9.5)], [9.5, 0.25, trap_z(9.5)], [-9.5, 1.0, trap_z(-9.5)]]
    )
    # counter-clockwise seen from +Z: normal points up (+Z side, tilted slightly toward -X)
    big = g.mesh("big", [{"attributes": {"POSITION": g.positions(big_v)}}])
    near_v = np.array([[2, 0.2, 0.2], [2, 0.2, 0.3], [2, 0.4, 0.3], [2, 0.4, 0.2]], float)
    # normal -X (faces a ray travelling +X)
    near = g.mesh(
        "near",
        [
            {
                "attributes": {"POSITION": g.positions(near_v)},
                "indices": g.indices([[0, 1, 2], [0, 2, 3]], UNSIGNED_SHORT),
            }
        ],
    )
    fv, ff = corner_filler()
    filler = g.mesh(
        "corners",
        [{"attributes": {"POSITION": g.positions(fv)}, "indices": g.indices(ff, UNSIGNED_SHORT)}],
    )
    nodes = [g.node("big", mesh=big), g.node("near", mesh=near), g.node("corners", mesh=filler)]
    g.scene(nodes)
    FILES.write_json(GLTF_DIR / "trap.gltf", g.embedded())


# --------------------------------------------------------------------------
# OBJ fixtures

TWO_OBJECTS_OBJ = """\
# two objects with polygon faces (triangulated by the importer as fans from the first vertex)
# object "quad": 2x2 square in z = 0, counter-clockwise seen from +Z
o quad
v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
f 1 2 3 4
# object "penta": convex pentagon ("house") in z = -1, x in [2, 4]
o penta
v 2 -1 -1
v 4 -1 -1
v 4 0.5 -1
v 3 1.5 -1
v 2 0.5 -1
f 5 6 7 8 9
"""

GROUPS_OBJ = """\
# two groups; "left" uses v//vn face syntax, "right" uses negative (relative) indices
v -3 -1 0
v -1 -1 0
v -1 1 0
v -3 1 0
vn 0 0 1
g left
f 1//1 2//1 3//1 4//1
g right
v 1 -1 0.5
v 3 -1 0.5
v 3 1 0.5
v 1 1 0.5
f -4 -3 -2
f -4 -2 -1
"""


def make_obj() -> None:
    FILES.write_bytes(OBJ_DIR / "two_objects.obj", TWO_OBJECTS_OBJ.encode())
    FILES.write_bytes(OBJ_DIR / "groups.obj", GROUPS_OBJ.encode())


# --------------------------------------------------------------------------
# bad inputs


def plane_doc(g: Gltf) -> Gltf:
    m = add_quad_mesh(g, "plane")
    g.scene([g.node("plane", mesh=m)])
    return g


def make_bad() -> None:
    # truncated.glb: header claims the full length, file ends halfway through the JSON chunk
    full = Gltf(GENERATOR)
    m = add_cube_mesh(full)
    full.scene([full.node("cube", mesh=m)])
    data = full.glb_bytes()
    json_len = struct.unpack_from("<I", data, 12)[0]
    FILES.write_bytes(BAD_DIR / "truncated.glb", data[: 20 + json_len // 2])

    # bad_index.gltf: 4 vertices, an index of 99
    g = Gltf(GENERATOR)
    pos = g.positions(QUAD_V)
    idx = g.indices([0, 1, 2, 0, 2, 99], UNSIGNED_SHORT)
    m = g.mesh("bad_index", [{"attributes": {"POSITION": pos}, "indices": idx}])
    g.scene([g.node("bad_index", mesh=m)])
    FILES.write_json(BAD_DIR / "bad_index.gltf", g.embedded())

    # nan_position.gltf: vertex 2 is (NaN, 1, 0); min/max computed from the other vertices
    g = Gltf(GENERATOR)
    v = QUAD_V.copy()
    v[2, 0] = np.nan
    pos = g.positions(v)
    idx = g.indices(QUAD_F, UNSIGNED_SHORT)
    m = g.mesh("nan_position", [{"attributes": {"POSITION": pos}, "indices": idx}])
    g.scene([g.node("nan_position", mesh=m)])
    FILES.write_json(BAD_DIR / "nan_position.gltf", g.embedded())

    # missing_buffer.gltf: the cube, external buffer that does not exist
    g = Gltf(GENERATOR)
    m = add_cube_mesh(g)
    g.scene([g.node("cube", mesh=m)])
    doc, _ = g.finish("missing_buffer.bin")
    FILES.write_json(BAD_DIR / "missing_buffer.gltf", doc)

    # not_json.gltf
    FILES.write_bytes(
        BAD_DIR / "not_json.gltf",
        b'this is not a glTF file {\n  "asset": oops\n}}}\n\x01\x02\x03 garbage\n',
    )

    # draco_required.gltf: Draco-compressed primitive (payload is not real Draco data)
    g = Gltf(GENERATOR)
    g.require("KHR_draco_mesh_compression")
    payload = g.view(b"DRACO\x02\x02\x01\x01\x00\x00\x00" + bytes(20))
    pos = g.accessor(None, FLOAT, 4, "VEC3", min=[-1.0, -1.0, 0.0], max=[1.0, 1.0, 0.0])
    idx = g.accessor(None, UNSIGNED_SHORT, 6, "SCALAR")
    m = g.mesh(
        "draco",
        [
            {
                "attributes": {"POSITION": pos},
                "indices": idx,
                "extensions": {
                    "KHR_draco_mesh_compression": {
                        "bufferView": payload,
                        "attributes": {"POSITION": 0},
                    }
                },
            }
        ],
    )
    g.scene([g.node("draco", mesh=m)])
    FILES.write_json(BAD_DIR / "draco_required.gltf", g.embedded())

    # meshopt_required.gltf: meshopt-compressed bufferView (payload is not real meshopt data)
    g = Gltf(GENERATOR)
    g.require("EXT_meshopt_compression")
    g.bin += b"\xa0" + bytes(47)  # 48 bytes of "compressed" data
    g.doc["bufferViews"].append(
        {
            "buffer": 0,
            "byteOffset": 0,
            "byteLength": 48,
            "byteStride": 12,
            "target": ARRAY_BUFFER,
            "extensions": {
                "EXT_meshopt_compression": {
                    "buffer": 0,
                    "byteOffset": 0,
                    "byteLength": 48,
                    "byteStride": 12,
                    "count": 4,
                    "mode": "ATTRIBUTES",
                }
            },
        }
    )
    pos = g.accessor(0, FLOAT, 4, "VEC3", min=[-1.0, -1.0, 0.0], max=[1.0, 1.0, 0.0])
    m = g.mesh("meshopt", [{"attributes": {"POSITION": pos}, "mode": TRIANGLE_FAN}])
    g.scene([g.node("meshopt", mesh=m)])
    FILES.write_json(BAD_DIR / "meshopt_required.gltf", g.embedded())

    # buffer_too_short.gltf: non-indexed POSITION with count 6 (72 bytes) over a 48-byte view/buffer
    g = Gltf(GENERATOR)
    v = g.view(np.asarray(QUAD_V, np.float32).tobytes(), ARRAY_BUFFER)
    pos = g.accessor(v, FLOAT, 6, "VEC3", min=[-1.0, -1.0, 0.0], max=[1.0, 1.0, 0.0])
    m = g.mesh("too_short", [{"attributes": {"POSITION": pos}}])
    g.scene([g.node("too_short", mesh=m)])
    FILES.write_json(BAD_DIR / "buffer_too_short.gltf", g.embedded())

    # node_cycle.gltf: node 0 -> node 1 -> node 0
    g = Gltf(GENERATOR)
    m = add_quad_mesh(g, "plane")
    n0 = g.node("loop_a", mesh=m, children=[1])
    g.node("loop_b", mesh=m, children=[0], translation=[0.0, 0.0, -1.0])
    g.scene([n0])
    FILES.write_json(BAD_DIR / "node_cycle.gltf", g.embedded())

    # empty.gltf: valid, one scene with one node that has no mesh (no meshes at all)
    FILES.write_json(
        BAD_DIR / "empty.gltf",
        {
            "asset": {"version": "2.0", "generator": GENERATOR},
            "scene": 0,
            "scenes": [{"name": "empty", "nodes": [0]}],
            "nodes": [{"name": "nothing", "translation": [0.0, 0.0, 1.0]}],
        },
    )

    # rays with the wrong shape / a NaN
    FILES.write_npy(BAD_DIR / "bad_rays.npy", np.arange(15, dtype=np.float64).reshape(3, 5))
    FILES.write_npy(
        BAD_DIR / "nan_rays.npy",
        np.array([[0, 0, 5, 0, 0, -1], [0, 0, 5, np.nan, 0, -1]], np.float64),
    )

    # garbage.obj: three vertices, a face that references vertex 100
    FILES.write_bytes(BAD_DIR / "garbage.obj", b"o broken\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 100\n")


# --------------------------------------------------------------------------
# third-party assets

ASSETS = [
    "gltf/Box.glb",
    "gltf/TriangleWithoutIndices.gltf",
    "gltf/chr_knight.glb",
    "gltf/ShapeCollection.glb",
    "gltf/DamagedHelmet.glb",
    "gltf/many-cubes.gltf",
    "gltf/many-cubes.bin",
    "gltf/DenseSphere.glb",
    "gltf/BoxDraco.gltf",
    "gltf/BoxMeshopt.glb",
    "obj/stanford-bunny.obj",
    "obj/suzanne.obj",
]

# Fixture content: it names the script's path before the tools became one package, and stays
# as it is so that the fixtures regenerate byte-identical.
LICENSES_MD = """\
# Third-party assets in this folder

Copied unchanged by `tools/make_fixtures.py` from the project's shared asset
folder (`shared/assets/`, whose README.md is the source of what follows).
Nobody on this project wrote them. Do not edit them here; change the script
and the shared copy instead.

| file | from (in shared/assets) | origin | licence |
| --- | --- | --- | --- |
| `Box.glb` | `gltf/Box.glb` | Khronos glTF sample model (via glTF-Transform test inputs) | Khronos sample-model licence |
| `TriangleWithoutIndices.gltf` | `gltf/TriangleWithoutIndices.gltf` | Khronos glTF sample model | Khronos sample-model licence |
| `chr_knight.glb` | `gltf/chr_knight.glb` | voxel character; glTF-Transform test inputs / cgltf fuzz data | Khronos sample-model licences, as listed for `gltf/` |
| `ShapeCollection.glb` | `gltf/ShapeCollection.glb` | glTF-Transform test inputs / cgltf fuzz data | as listed for `gltf/` |
| `DamagedHelmet.glb` | `gltf/DamagedHelmet.glb` | Khronos glTF sample model (classic PBR sample, ~46k triangles) | CC-BY 4.0 |
| `many-cubes.gltf`, `many-cubes.bin` | `gltf/many-cubes.*` | glTF-Transform test inputs / cgltf fuzz data (1.1 MB of JSON, many nodes) | as listed for `gltf/` |
| `DenseSphere.glb` | `gltf/DenseSphere.glb` | glTF-Transform test inputs / cgltf fuzz data | as listed for `gltf/` |
| `BoxDraco.gltf` | `gltf/BoxDraco.gltf` | Khronos Box with `KHR_draco_mesh_compression` | Khronos sample-model licence |
| `BoxMeshopt.glb` | `gltf/BoxMeshopt.glb` | Khronos Box with `EXT_meshopt_compression` | Khronos sample-model licence |
| `stanford-bunny.obj` | `obj/stanford-bunny.obj` | alecjacobson/common-3d-test-models (Stanford 3D Scanning Repository bunny, 69k triangles) | research/test model; see the original source listed there |
| `suzanne.obj` | `obj/suzanne.obj` | alecjacobson/common-3d-test-models (Blender's Suzanne) | research/test model; see the original source listed there |

The shared README gives the licence per folder, not per file: for `gltf/` it
says "see the Khronos sample-model licenses (CC-BY 4.0 for DamagedHelmet)",
and for `obj/` "research/test models; see the original sources listed there".
The licence column repeats that. The origin column adds only what the shared
README does not say per file but is well known (Box and TriangleWithoutIndices
are Khronos sample models, the bunny is from the Stanford 3D Scanning
Repository, Suzanne is Blender's test monkey); check the upstream pages before
redistributing any of these outside this repository. `BoxDraco.gltf` refers to
an external `0.bin` that the shared folder does not have either.
"""  # noqa: E501 (fixture text, kept byte-identical)


def copy_assets() -> None:
    ASSET_DIR.mkdir(parents=True, exist_ok=True)
    have_source = SHARED_ASSETS.is_dir()
    if not have_source:
        print(f"  note  shared assets not found at {SHARED_ASSETS}; keeping existing copies")
    missing = []
    for rel in ASSETS:
        src = SHARED_ASSETS / rel
        dst = ASSET_DIR / Path(rel).name
        if src.is_file():
            data = src.read_bytes()
            FILES.write_bytes(dst, data)
        elif dst.is_file():
            FILES.kept(dst)
            print(f"  kept  {dst.relative_to(ROOT)} (source {src} missing)")
        else:
            missing.append(rel)
    FILES.write_bytes(ASSET_DIR / "LICENSES.md", LICENSES_MD.encode())
    if missing:
        sys.exit(f"fixtures: assets missing from {SHARED_ASSETS} and from {ASSET_DIR}: {missing}")


# --------------------------------------------------------------------------


def main(argv=None) -> int:
    argparse.ArgumentParser(prog=prog("fixtures"), description=__doc__.split("\n\n")[0]).parse_args(
        argv
    )
    print(f"fixtures: writing into {FIX.relative_to(ROOT)}/")
    make_cube()
    make_plane()
    make_modes()
    make_sparse()
    make_quantized()
    make_instances()
    make_scenes()
    make_cameras()
    make_far()
    make_trap()
    make_obj()
    make_bad()
    copy_assets()
    print(f"fixtures: {len(FILES.written)} files, sha256 of all: {FILES.digest()}")
    return 0
