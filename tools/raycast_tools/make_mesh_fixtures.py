"""Write the PLY and STL fixtures under fixtures/ply, fixtures/stl and fixtures/bad.

Run with the repo's venv:  .venv/bin/python -m raycast_tools mesh-fixtures

Only numpy, struct and the standard library: every byte is written here, so a rerun gives
byte-identical files. The geometry is the fixtures' cube ([-1,1]^3, fixtures/README.md)
written in each encoding the readers must take; fixtures/ply/README.md and
fixtures/stl/README.md say what each file holds. The answers are checked against trimesh's
readers by tests/python/test_mesh_formats.py and worked out by hand in
tests/it/mesh_formats.rs.
"""

from __future__ import annotations

import argparse
import struct

import numpy as np

from .cli import prog
from .fixture_files import FixtureFiles
from .make_fixtures import cube
from .paths import ROOT

FIX = ROOT / "fixtures"
PLY_DIR = FIX / "ply"
STL_DIR = FIX / "stl"
BAD_DIR = FIX / "bad"
FILES = FixtureFiles(ROOT)

# The cube's faces as quads, face by face in the cube's order; their fans (0,1,2), (0,2,3) are
# the cube's triangles, but for -Z, whose two triangles come in the other order.
CUBE_QUADS = [[4, 5, 6, 7], [0, 3, 2, 1], [1, 2, 6, 5], [0, 4, 7, 3], [3, 7, 6, 2], [0, 1, 5, 4]]

PLY_TYPES = {
    "char": "b",
    "uchar": "B",
    "uint8": "B",
    "short": "h",
    "ushort": "H",
    "uint16": "H",
    "int": "i",
    "uint": "I",
    "float": "f",
    "double": "d",
}


def ply_header(fmt: str, vertex_props, n_vertices: int, faces, index: str, extra: str = "") -> str:
    """A PLY header: `vertex_props` [(type, name)], a face list `index` = (count, item, name)."""
    lines = [
        "ply",
        f"format {fmt} 1.0",
        "comment raycast tools/raycast_tools/make_mesh_fixtures.py",
    ]
    lines.append(f"element vertex {n_vertices}")
    lines += [f"property {t} {name}" for t, name in vertex_props]
    if faces is not None:
        count, item, name = index
        lines += [f"element face {len(faces)}", f"property list {count} {item} {name}"]
    lines += [extra] if extra else []
    lines.append("end_header")
    return "\n".join(lines) + "\n"


def ply_binary(endian: str, vertex_props, vertices, faces, index, extra_records=b"") -> bytes:
    """A binary PLY body: vertex records of `vertex_props` (values: position then extras),
    face lists of `index` types."""
    order = "<" if endian == "little" else ">"
    out = bytearray()
    for row in vertices:
        for (t, _), value in zip(vertex_props, row):
            out += struct.pack(order + PLY_TYPES[t], value)
    count, item, _ = index
    for face in faces:
        out += struct.pack(order + PLY_TYPES[count], len(face))
        out += struct.pack(order + PLY_TYPES[item] * len(face), *face)
    return bytes(out) + extra_records


def make_ply() -> None:
    v, f = cube()
    xyz_float = [("float", "x"), ("float", "y"), ("float", "z")]
    # ASCII: quads, uchar counts and int indices, an extra colour property, comments.
    props = xyz_float + [("uchar", "red")]
    head = ply_header("ascii", props, 8, CUBE_QUADS, ("uchar", "int", "vertex_indices"))
    body = "".join(f"{x:g} {y:g} {z:g} 200\n" for x, y, z in v)
    body += "".join(f"{len(q)} " + " ".join(map(str, q)) + "\n" for q in CUBE_QUADS)
    FILES.write_bytes(PLY_DIR / "cube_ascii_quads.ply", (head + body).encode())

    # Binary little endian: float positions with a scanner's confidence and colour, uchar/int
    # triangles, and an element after the faces (a material) that the reader must read past.
    props = xyz_float + [("float", "confidence"), ("uchar", "red")]
    rows = [list(p) + [0.5, 7] for p in v]
    material = "element material 1\nproperty uchar diffuse_red\nproperty float shininess"
    head = ply_header(
        "binary_little_endian", props, 8, f, ("uchar", "int", "vertex_indices"), material
    )
    body = ply_binary("little", props, rows, f.tolist(), ("uchar", "int", "vertex_indices"))
    body += struct.pack("<Bf", 255, 0.25)
    FILES.write_bytes(PLY_DIR / "cube_binary_le.ply", head.encode() + body)

    # Binary big endian: double positions that f32 cannot hold (the cube halved and moved by
    # 0.1), `vertex_index` lists of uchar/uint.
    props = [("double", "x"), ("double", "y"), ("double", "z")]
    moved = v * 0.5 + 0.1
    head = ply_header("binary_big_endian", props, 8, f, ("uchar", "uint", "vertex_index"))
    body = ply_binary("big", props, moved, f.tolist(), ("uchar", "uint", "vertex_index"))
    FILES.write_bytes(PLY_DIR / "cube_binary_be_double.ply", head.encode() + body)

    # Binary little endian with faces of 3, 4 and 5 corners (uint8 counts, ushort indices):
    # a triangle, a quad and a pentagon ("house") side by side in z = 0.
    points = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]  # triangle 0 1 2
    points += [[2, 0, 0], [3, 0, 0], [3, 1, 0], [2, 1, 0]]  # quad 3 4 5 6
    points += [[4, 0, 0], [6, 0, 0], [6, 1, 0], [5, 2, 0], [4, 1, 0]]  # pentagon 7..11
    faces = [[0, 1, 2], [3, 4, 5, 6], [7, 8, 9, 10, 11]]
    head = ply_header(
        "binary_little_endian", xyz_float, 12, faces, ("uint8", "ushort", "vertex_indices")
    )
    body = ply_binary("little", xyz_float, points, faces, ("uint8", "ushort", "vertex_indices"))
    FILES.write_bytes(PLY_DIR / "polygons_binary_le.ply", head.encode() + body)

    # Points only (a scan without faces): an empty scene with a warning.
    head = ply_header("ascii", [("double", "x"), ("double", "y"), ("double", "z")], 3, None, None)
    FILES.write_bytes(PLY_DIR / "points_only.ply", (head + "0 0 0\n1 0 0\n0 1 0\n").encode())

    # A triangle face and a `tristrips` element (the square as one strip, -1 ending it),
    # which raycast does not read (nor does trimesh): one triangle and a warning.
    xyz = [("float", "x"), ("float", "y"), ("float", "z")]
    head = ply_header("ascii", xyz, 4, [[0, 1, 2]], ("uchar", "int", "vertex_indices"))
    strips = "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
    head = head.replace("end_header\n", strips)
    body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n5 0 1 3 2 -1\n"
    FILES.write_bytes(PLY_DIR / "tristrips.ply", (head + body).encode())


def stl_facets(tris: np.ndarray) -> str:
    out = []
    for t in tris:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n = n / np.linalg.norm(n)
        out.append(f"  facet normal {n[0]:g} {n[1]:g} {n[2]:g}\n    outer loop\n")
        out += [f"      vertex {x:g} {y:g} {z:g}\n" for x, y, z in t]
        out.append("    endloop\n  endfacet\n")
    return "".join(out)


def stl_binary(header: bytes, tris: np.ndarray) -> bytes:
    out = bytearray(header.ljust(80, b" ")[:80])
    out += struct.pack("<I", len(tris))
    for t in tris:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n = n / np.linalg.norm(n)
        out += struct.pack("<12f", *n, *t.reshape(-1))
        out += b"\0\0"
    return bytes(out)


def make_stl() -> None:
    v, f = cube()
    tris = v[f]
    text = f"solid cube\n{stl_facets(tris)}endsolid cube\n"
    FILES.write_bytes(STL_DIR / "cube_ascii.stl", text.encode())
    FILES.write_bytes(STL_DIR / "cube_binary.stl", stl_binary(b"binary STL cube", tris))
    # A binary file whose header begins with `solid`, as many CAD exporters write it.
    header = b"solid cube exported as binary"
    FILES.write_bytes(STL_DIR / "cube_binary_solid.stl", stl_binary(header, tris))
    # Two solids: the cube, and a plate (the quad at z = -2, 2 triangles), upper-case keywords.
    plate = np.array(
        [[[-1, -1, -2], [1, -1, -2], [1, 1, -2]], [[-1, -1, -2], [1, 1, -2], [-1, 1, -2]]]
    )
    text = f"solid cube\n{stl_facets(tris)}endsolid cube\n"
    text += f"SOLID plate\n{stl_facets(plate.astype(float)).upper()}ENDSOLID plate\n"
    FILES.write_bytes(STL_DIR / "two_solids.stl", text.encode())


def make_bad() -> None:
    v, f = cube()
    xyz = [("float", "x"), ("float", "y"), ("float", "z")]
    index = ("uchar", "int", "vertex_indices")
    whole = ply_header("binary_little_endian", xyz, 8, f, index).encode()
    whole += ply_binary("little", xyz, v, f.tolist(), index)
    FILES.write_bytes(BAD_DIR / "ply_truncated.ply", whole[: len(whole) - 20])
    # A header that claims 10^9 vertices in a file of about 1 KiB.
    head = ply_header("binary_little_endian", xyz, 10**9, f, index).encode()
    FILES.write_bytes(BAD_DIR / "ply_huge_count.ply", head + bytes(1024 - len(head)))
    bad = f.copy()
    bad[5, 2] = 8
    head = ply_header("ascii", xyz, 8, bad, index)
    body = "".join(f"{x:g} {y:g} {z:g}\n" for x, y, z in v)
    body += "".join("3 " + " ".join(map(str, t)) + "\n" for t in bad)
    FILES.write_bytes(BAD_DIR / "ply_index_oob.ply", (head + body).encode())
    FILES.write_bytes(
        BAD_DIR / "ply_bad_header.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty half x\nend_header\n0\n",
    )
    tris = v[f]
    FILES.write_bytes(BAD_DIR / "stl_truncated.stl", stl_binary(b"cut", tris)[: 84 + 50 * 5])
    text = f"solid cut\n{stl_facets(tris[:3])}"
    FILES.write_bytes(BAD_DIR / "stl_unterminated.stl", text.encode())


def main(argv=None) -> int:
    argparse.ArgumentParser(
        prog=prog("mesh-fixtures"), description=__doc__.split("\n\n")[0]
    ).parse_args(argv)
    make_ply()
    make_stl()
    make_bad()
    print(f"mesh-fixtures: {len(FILES.written)} files, sha256 of all: {FILES.digest()}")
    return 0
