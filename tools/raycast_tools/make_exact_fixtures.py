"""Write fixtures/exact/: scenes whose depths `exact-depth` checks against readers that share no
code with raycast (issue 12, "exact with respect to the file").

    .venv/bin/python -m raycast_tools exact-fixtures

- `far_field.obj`: a height field 1e6 to 1e7 units from the origin, every coordinate written
  with 17 significant digits (none of them an f32 value).
- `nested_far.gltf`: one f32 mesh drawn by 16 nodes nested three deep about 1e5 from the origin:
  non-uniform scales, rotations, some mirrored, as full-precision `matrix` and TRS nodes.
- `point_instancer.usda`: a PointInstancer under a rotated parent 1e5 away, with half-precision
  orientations that are not unit length (some far from it), non-uniform and mirrored scales,
  a prototype with its own transform, an invisible prototype, a guide mesh, `invisibleIds`
  and `inactiveIds`; and a second PointInstancer with float orientations whose prototypes
  live in an invisible scope elsewhere.

A seeded generator, so a rerun gives byte-identical files, on any CPU: the random values are
numpy's uniform draws (integer bits scaled, the same everywhere), and every value composed from
them is made by IEEE-rounded scalar arithmetic (+, -, *, /, sqrt) in a fixed order, or by
mpmath (sin and cos correctly rounded). numpy's linear algebra (BLAS: the summation order and
fused multiply-adds depend on the CPU's kernel), its SIMD-dispatched ufuncs and the platform's
libm are not used for any value that reaches a file. fixtures/exact/README.md says what each
holds.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import mpmath
import numpy as np

from .cli import prog
from .fixture_files import FixtureFiles
from .gltf_writer import TRIANGLES, UNSIGNED_SHORT, Gltf
from .paths import ROOT

EXACT_DIR = ROOT / "fixtures" / "exact"
GENERATOR = "raycast tools/raycast_tools/make_exact_fixtures.py"
FILES = FixtureFiles(ROOT)


def blob(rng) -> tuple[np.ndarray, np.ndarray]:
    """An irregular closed mesh about the origin (an octahedron subdivided twice, each vertex
    pushed out by 0.8-1.2), as f32 vertex values and u16 faces."""
    verts = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    verts = [np.array(v, float) for v in verts]
    faces = []
    for sx, sy, sz in np.ndindex(2, 2, 2):
        a, b, c = 0 + sx, 2 + sy, 4 + sz
        faces.append((a, c, b) if (sx + sy + sz) % 2 else (a, b, c))
    for _ in range(2):
        mid, out = {}, []

        def middle(i, j):
            key = (min(i, j), max(i, j))
            if key not in mid:
                verts.append(unit(verts[i] + verts[j]))
                mid[key] = len(verts) - 1
            return mid[key]

        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        faces = out
    v = np.array(verts) * rng.uniform(0.8, 1.2, (len(verts), 1))
    return v.astype(np.float32), np.array(faces, np.uint16)


def unit(v) -> np.ndarray:
    """`v` / |v|, |v| by scalar IEEE arithmetic in a fixed order (not BLAS)."""
    comps = [float(c) for c in v]
    length = math.sqrt(math.fsum(c * c for c in comps))
    return np.array([c / length for c in comps])


def sin_cos(angle: float) -> tuple[float, float]:
    """sin and cos of `angle`, correctly rounded to double (mpmath at 120 bits, then rounded):
    the same bits on every machine, where libm's may differ in the last place."""
    with mpmath.workprec(120):
        a = mpmath.mpf(angle)
        return float(mpmath.sin(a)), float(mpmath.cos(a))


def rotation(axis, angle) -> np.ndarray:
    """3x3 rotation about `axis` by `angle` radians (Rodrigues: I + s K + (1 - c) K², each entry
    summed in a fixed order)."""
    kx, ky, kz = (float(c) for c in unit(axis))
    s, c = sin_cos(angle)
    k = [[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]]
    k2 = [[math.fsum(k[i][m] * k[m][j] for m in range(3)) for j in range(3)] for i in range(3)]
    eye = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
    entry = lambda i, j: eye[i][j] + s * k[i][j] + (1 - c) * k2[i][j]  # noqa: E731
    return np.array([[entry(i, j) for j in range(3)] for i in range(3)])


def quaternion(axis, angle) -> list[float]:
    """glTF (x, y, z, w) unit quaternion of a rotation about `axis`."""
    k = unit(axis)
    s, c = sin_cos(angle / 2)
    return [float(k[0] * s), float(k[1] * s), float(k[2] * s), c]


def direction(rng, n: int = 3) -> np.ndarray:
    """A random direction (not normalised) from uniform draws: numpy's normal draws go through
    libm's exp and log, which differ in the last place between CPUs."""
    return rng.uniform(-1.0, 1.0, n)


def random_trs(rng, spread: float, mirror: bool) -> dict:
    """A node's translation, rotation and non-uniform scale (x negated when `mirror`)."""
    scale = rng.uniform(0.5, 2.0, 3)
    if mirror:
        scale[0] = -scale[0]
    return {
        "translation": [float(x) for x in rng.uniform(-spread, spread, 3)],
        "rotation": quaternion(direction(rng), rng.uniform(0.2, 3.0)),
        "scale": [float(x) for x in scale],
    }


def random_matrix(rng, spread: float, mirror: bool) -> list[float]:
    """A column-major 4x4 node matrix T R S, in full double precision."""
    trs = random_trs(rng, spread, mirror)
    m = np.eye(4)
    m[:3, :3] = rotation(direction(rng), rng.uniform(0.2, 3.0)) * np.array(trs["scale"])
    m[:3, 3] = trs["translation"]
    return [float(x) for x in m.T.reshape(-1)]


def make_far_field() -> None:
    rng = np.random.default_rng(12)
    cells, lo, hi = 12, 1e6, 1e7
    step = (hi - lo) / cells
    lines = ["# raycast exact-fixtures: height field 1e6-1e7 from the origin, 17 digits", "o field"]
    for j in range(cells + 1):
        for i in range(cells + 1):
            x = lo + i * step + rng.uniform(-0.1, 0.1) * step
            y = lo + j * step + rng.uniform(-0.1, 0.1) * step
            z = 3e5 + rng.uniform(-0.2, 0.2) * step
            assert float(np.float32(x)) != x and float(np.float32(y)) != y
            lines.append(f"v {x:.16e} {y:.16e} {z:.16e}")
    for j in range(cells):
        for i in range(cells):
            a = j * (cells + 1) + i + 1
            b, c, d = a + 1, a + cells + 2, a + cells + 1
            lines += [f"f {a} {b} {c}", f"f {a} {c} {d}"]
    FILES.write_bytes(EXACT_DIR / "far_field.obj", ("\n".join(lines) + "\n").encode())


FAR = (100000.3, -200000.7, 150000.1)


def make_nested_far() -> None:
    rng = np.random.default_rng(7)
    v, f = blob(rng)
    g = Gltf(GENERATOR)
    prim = {"attributes": {"POSITION": g.positions(v)}, "indices": g.indices(f, UNSIGNED_SHORT)}
    prim["mode"] = TRIANGLES
    mesh = g.mesh("blob", [prim])
    leaves = []
    groups = []
    for k in range(4):
        kids = []
        for m in range(3):
            mirror = (k + m) % 3 == 0
            trs = random_trs(rng, 6.0, mirror)
            kids.append(g.node(f"leaf{k}{m}", mesh=mesh, **trs))
        leaves += kids
        matrix = random_matrix(rng, 60.0, mirror=k == 1)
        node = g.node(f"group{k}", mesh=mesh, matrix=matrix, children=kids)
        groups.append(node)
    far = g.node(
        "far",
        translation=list(FAR),
        rotation=quaternion([1.0, 2.0, 3.0], 0.4),
        scale=[1500.0, 700.0, 1100.0],
        children=groups,
    )
    g.scene([far])
    assert len(leaves) + len(groups) == 16
    FILES.write_json(EXACT_DIR / "nested_far.gltf", g.embedded())


def usda_list(values, fmt) -> str:
    return "[" + ", ".join(fmt(x) for x in values) + "]"


def usda_mesh(name: str, v: np.ndarray, f: np.ndarray, extra: str = "") -> str:
    pts = usda_list(v, lambda p: "(" + ", ".join(repr(float(c)) for c in p) + ")")
    return (
        f'def Mesh "{name}"\n{{\n{extra}'
        '    uniform token subdivisionScheme = "none"\n'
        f"    int[] faceVertexCounts = {usda_list(f, lambda _: '3')}\n"
        f"    int[] faceVertexIndices = {usda_list(f.reshape(-1), str)}\n"
        f"    point3f[] points = {pts}\n}}\n"
    )


def indent(text: str, levels: int) -> str:
    pad = "    " * levels
    return "".join(pad + line if line.strip() else line for line in text.splitlines(True))


def half(x) -> str:
    """`x` rounded to half precision, written exactly (what a quath holds)."""
    return repr(float(np.float16(x)))


def f32(values) -> np.ndarray:
    """`values` rounded to f32, so that their text is an f32 value exactly. (A longer decimal
    can round differently: usd-core parses float text through double, openusd directly, and
    the two differ where the double falls on a midpoint between two floats.)"""
    return np.asarray(values, np.float64).astype(np.float32)


def make_point_instancer() -> None:
    rng = np.random.default_rng(5)
    v, f = blob(rng)
    n = 24
    proto = np.array([0, 1] * 11 + [2, 2])
    positions = rng.uniform(-20, 20, (n, 3)).astype(np.float32)
    quats = []
    for i in range(n):
        q = unit(direction(rng, 4))
        # every quath is a little off unit length; some are far from it
        q *= [1.0, 0.9, 1.1, 0.8][i % 4]
        quats.append(q)
    scales = rng.uniform(0.6, 1.8, (n, 3)).astype(np.float32)
    scales[::5, 1] *= -1  # mirrored
    ids = 100 + np.arange(n)
    vec = lambda p: "(" + ", ".join(repr(float(c)) for c in p) + ")"  # noqa: E731
    quath = lambda q: "(" + ", ".join(half(c) for c in q) + ")"  # noqa: E731
    tilted_v = (v * np.float32(0.5)).astype(np.float32)
    protos = (
        usda_mesh("blob", v, f)
        + 'def Xform "tilted"\n{\n'
        + "    double3 xformOp:translate = (0.25, -0.5, 1.0)\n"
        + "    float3 xformOp:rotateXYZ = (15, -40, 70)\n"
        + '    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]\n'
        + indent(
            usda_mesh(
                "inner",
                tilted_v,
                f,
                "    double3 xformOp:scale = (2, 1, 0.5)\n"
                '    uniform token[] xformOpOrder = ["xformOp:scale"]\n',
            ),
            1,
        )
        + indent(usda_mesh("guide", v, f, '    uniform token purpose = "guide"\n'), 1)
        + "}\n"
        + usda_mesh("hidden", v, f, '    token visibility = "invisible"\n')
    )
    text = (
        '#usda 1.0\n(\n    upAxis = "Z"\n)\n\n'
        'def Xform "world"\n{\n'
        f"    double3 xformOp:translate = {vec(FAR)}\n"
        "    double3 xformOp:rotateXYZ = (10, 20, 30)\n"
        "    double3 xformOp:scale = (1500, 700, 1100)\n"
        '    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ", '
        '"xformOp:scale"]\n\n'
        # explicit list op: openusd 0.6 cannot parse `append inactiveIds` in a text layer
        '    def PointInstancer "pi" (\n        inactiveIds = [107, 115]\n    )\n    {\n'
        "        rel prototypes = [</world/pi/protos/blob>, </world/pi/protos/tilted>, "
        "</world/pi/protos/hidden>]\n"
        f"        int[] protoIndices = {usda_list(proto, str)}\n"
        f"        int64[] ids = {usda_list(ids, str)}\n"
        "        int64[] invisibleIds = [103, 110]\n"
        f"        point3f[] positions = {usda_list(positions, vec)}\n"
        f"        quath[] orientations = {usda_list(quats, quath)}\n"
        f"        float3[] scales = {usda_list(scales, vec)}\n\n"
        '        def Xform "protos"\n        {\n' + indent(protos, 3) + "        }\n    }\n\n"
        # the usual idiom: prototypes kept in an invisible scope elsewhere (not drawn in place,
        # drawn through the instancer); float orientations, the first two not unit
        '    def PointInstancer "pi_shared"\n    {\n'
        "        rel prototypes = [</world/library/blob>, </world/library/tilted>]\n"
        "        int[] protoIndices = [0, 1, 1, 0, 1, 0]\n"
        f"        point3f[] positions = {usda_list(f32(positions[:6] + [0, 0, 45]), vec)}\n"
        f"        quatf[] orientationsf = {usda_list(f32(quats[-6:]), vec)}\n"
        f"        float3[] scales = {usda_list(scales[-6:], vec)}\n"
        "    }\n\n"
        '    def Xform "library"\n    {\n        token visibility = "invisible"\n'
        + indent(protos, 2)
        + "    }\n}\n"
    )
    FILES.write_bytes(EXACT_DIR / "point_instancer.usda", text.encode())


def main(argv=None) -> int:
    global EXACT_DIR, FILES
    parser = argparse.ArgumentParser(
        prog=prog("exact-fixtures"), description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--out", type=Path, help="write the files to this folder instead (default fixtures/exact)"
    )
    args = parser.parse_args(argv)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        EXACT_DIR, FILES = args.out, FixtureFiles(args.out)
    make_far_field()
    make_nested_far()
    make_point_instancer()
    print(f"exact-fixtures: {len(FILES.written)} files, sha256 of all: {FILES.digest()}")
    return 0
