"""Write the USD fixtures under fixtures/usd/ with usd-core (pxr) and their expected answers.

Run with the repo's venv (usd-core 26.11, numpy):

    .venv/bin/python -m raycast_tools usd-fixtures

Every scene is written twice, as text (`.usda`) and as binary crate (`.usdc`), from the same
stage. fixtures/usd/README.md documents the scenes; fixtures/usd/expected_rays.json holds
every documented ray and its answer in machine-readable form:
`{scene stem: [{"label", "origin", "direction", "hit" (object name or null), "depth",
"normal", "prim" (mesh hits, may be a list of allowed values)}]}`.

How the answers are made:

- `gltf_*`: glTF fixtures converted node for node (Xform/Mesh/Camera prims with the node's
  TRS as translate/orient/scale ops, or its matrix as a transform op; `RAYCAST_quadric` as
  `raycast:quadric:*` attributes). Their rays are the glTF fixture's own
  (fixtures/quadrics/expected_rays.json), with the object names turned into prim paths; the
  Rust test also compares whole buffers with the glTF scene.
- `gprims`: every intrinsic gprim with every axis, answers in closed form below.
- `xforms`, `composition`: meshes only (plus one quadric prim); the answers come from the
  scene as usd-core composes it (world transforms from `ComputeLocalToWorldTransform`,
  instance transforms from `ComputeInstanceTransformsAtTime`), intersected by brute force in
  numpy over all world triangles. Rays aim at the centroid of chosen triangles along their
  normals, so each hit is well inside a triangle.
- `bad/`: general quadric prims that must fail to load, each with the message expected.
"""

from __future__ import annotations

import argparse
import base64
import json
import math
import re
from pathlib import Path

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, Vt

from .cli import prog
from .make_quadric_fixtures import tri_hit
from .paths import ROOT
from .usd_stage import flatten

OUT = ROOT / "fixtures" / "usd"
EXPECTED: dict[str, list] = {}


def vec(v):
    return [float(x) for x in v]


# --------------------------------------------------------------------------------------
# glTF -> USD


def read_accessor(doc, base: Path, index: int) -> np.ndarray:
    accessor = doc["accessors"][index]
    view = doc["bufferViews"][accessor["bufferView"]]
    buffer = doc["buffers"][view["buffer"]]
    uri = buffer["uri"]
    if uri.startswith("data:"):
        data = base64.b64decode(uri.split(",", 1)[1])
    else:
        data = (base / uri).read_bytes()
    dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4", 5121: "u1"}[accessor["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3}[accessor["type"]]
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    count = accessor["count"] * width
    array = np.frombuffer(data, dtype=dtype, count=count, offset=start)
    return array.reshape(-1, width) if width > 1 else array


def prim_name(name: str, used: set) -> str:
    name = re.sub(r"[^A-Za-z0-9_]", "_", name) or "node"
    if name[0].isdigit():
        name = "_" + name
    candidate, k = name, 1
    while candidate in used:
        candidate = f"{name}_{k}"
        k += 1
    used.add(candidate)
    return candidate


def convert_gltf(source: Path, stem: str) -> dict:
    """Writes fixtures/usd/<stem>.usda/.usdc from a glTF fixture; returns node -> prim path."""
    doc = json.loads(source.read_text())
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    names: dict[str, str] = {}
    scene = doc["scenes"][doc.get("scene", 0)]

    def add(node_index: int, parent: str, used: set):
        node = doc["nodes"][node_index]
        name = prim_name(node.get("name", f"node{node_index}"), used)
        path = f"{parent}/{name}"
        names[node.get("name", f"node{node_index}")] = path
        if "mesh" in node:
            prim = UsdGeom.Mesh.Define(stage, path)
            points, faces = [], []
            for primitive in doc["meshes"][node["mesh"]]["primitives"]:
                assert primitive.get("mode", 4) == 4
                positions = read_accessor(doc, source.parent, primitive["attributes"]["POSITION"])
                indices = read_accessor(doc, source.parent, primitive["indices"])
                faces.extend(int(i) + len(points) for i in indices)
                points.extend(Gf.Vec3f(*map(float, p)) for p in positions)
            prim.CreatePointsAttr(Vt.Vec3fArray(points))
            prim.CreateFaceVertexCountsAttr([3] * (len(faces) // 3))
            prim.CreateFaceVertexIndicesAttr(faces)
            prim.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
        elif "camera" in node:
            prim = UsdGeom.Camera.Define(stage, path)
            camera = doc["cameras"][node["camera"]]
            if camera["type"] == "perspective":
                p = camera["perspective"]
                focal = 50.0
                vertical = 2.0 * focal * math.tan(p["yfov"] / 2.0)
                prim.CreateFocalLengthAttr(focal)
                prim.CreateVerticalApertureAttr(vertical)
                prim.CreateHorizontalApertureAttr(vertical * p.get("aspectRatio", 1.0))
                prim.CreateClippingRangeAttr(Gf.Vec2f(p["znear"], p.get("zfar", 1e6)))
            else:
                o = camera["orthographic"]
                prim.CreateProjectionAttr(UsdGeom.Tokens.orthographic)
                prim.CreateVerticalApertureAttr(20.0 * o["ymag"])
                prim.CreateHorizontalApertureAttr(20.0 * o["xmag"])
                prim.CreateClippingRangeAttr(Gf.Vec2f(o["znear"], o["zfar"]))
        else:
            prim = UsdGeom.Xform.Define(stage, path)
        xformable = UsdGeom.Xformable(prim)
        if "matrix" in node:
            # glTF's column-major array is USD's row-major row-vector matrix, number for number.
            m = node["matrix"]
            xformable.AddTransformOp().Set(Gf.Matrix4d(*m))
        else:
            if "translation" in node:
                xformable.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(
                    Gf.Vec3d(*node["translation"])
                )
            if "rotation" in node:
                x, y, z, w = node["rotation"]
                xformable.AddOrientOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Quatd(w, x, y, z))
            if "scale" in node:
                xformable.AddScaleOp(UsdGeom.XformOp.PrecisionDouble).Set(Gf.Vec3d(*node["scale"]))
        extension = node.get("extensions", {}).get("RAYCAST_quadric")
        if extension is not None:
            write_quadric(prim.GetPrim(), extension)
        child_names: set = set()
        for child in node.get("children", []):
            add(child, path, child_names)

    roots: set = set()
    for index in scene["nodes"]:
        add(index, "", roots)
    save(stage, stem)
    return names


def write_quadric(prim, extension: dict):
    def attr(name, type_name, value):
        prim.CreateAttribute(f"raycast:quadric:{name}", type_name, custom=True).Set(value)

    if "coefficients" in extension:
        attr(
            "coefficients",
            Sdf.ValueTypeNames.DoubleArray,
            Vt.DoubleArray(extension["coefficients"]),
        )
    else:
        q = extension["Q"]
        attr("Q", Sdf.ValueTypeNames.Matrix3d, Gf.Matrix3d(*q))
        attr("P", Sdf.ValueTypeNames.Double3, Gf.Vec3d(*extension["P"]))
        attr("R", Sdf.ValueTypeNames.Double, float(extension["R"]))
    if "bounds" in extension:
        attr("boundsMin", Sdf.ValueTypeNames.Double3, Gf.Vec3d(*extension["bounds"]["min"]))
        attr("boundsMax", Sdf.ValueTypeNames.Double3, Gf.Vec3d(*extension["bounds"]["max"]))


def save(stage, stem: str):
    OUT.mkdir(parents=True, exist_ok=True)
    layer = stage.GetRootLayer()
    # the old script path: fixture content, kept so that the fixtures stay byte-identical
    layer.documentation = "written by tools/export_usd_fixtures.py; do not edit"
    layer.Export(str(OUT / f"{stem}.usda"))
    layer.Export(str(OUT / f"{stem}.usdc"))
    print(f"wrote fixtures/usd/{stem}.usda, .usdc")


GLTF_SCENES = {
    "gltf_cube": "gltf/cube.gltf",
    "gltf_cameras": "gltf/cameras.gltf",
    "gltf_mixed": "quadrics/mixed.gltf",
    "gltf_sphere_coefficients": "quadrics/sphere_coefficients.gltf",
    "gltf_sphere_matrices": "quadrics/sphere_matrices.gltf",
    "gltf_ellipsoid": "quadrics/ellipsoid.gltf",
    "gltf_elliptic_paraboloid": "quadrics/elliptic_paraboloid.gltf",
    "gltf_hyperbolic_paraboloid": "quadrics/hyperbolic_paraboloid.gltf",
    "gltf_hyperboloid_one_sheet": "quadrics/hyperboloid_one_sheet.gltf",
    "gltf_hyperboloid_two_sheets": "quadrics/hyperboloid_two_sheets.gltf",
    "gltf_cone": "quadrics/cone.gltf",
    "gltf_cylinder": "quadrics/cylinder.gltf",
    "gltf_elliptic_cylinder": "quadrics/elliptic_cylinder.gltf",
    "gltf_hyperbolic_cylinder": "quadrics/hyperbolic_cylinder.gltf",
    "gltf_parabolic_cylinder": "quadrics/parabolic_cylinder.gltf",
    "gltf_far_sphere": "quadrics/far_sphere.gltf",
}


def export_gltf_scenes():
    quadric_rays = json.loads((ROOT / "fixtures/quadrics/expected_rays.json").read_text())
    for stem, relative in GLTF_SCENES.items():
        names = convert_gltf(ROOT / "fixtures" / relative, stem)
        rays = quadric_rays.get(Path(relative).name, {}).get("rays", [])
        EXPECTED[stem] = [
            {
                "label": r["label"],
                "origin": r["origin"],
                "direction": r["direction"],
                "hit": names.get(r["hit"]) if r["hit"] else None,
                "depth": r.get("depth"),
                "normal": r.get("normal", [0.0, 0.0, 0.0]),
                **(
                    {"prim": r["prim"] if isinstance(r["prim"], list) else [r["prim"]]}
                    if "prim" in r
                    else {}
                ),
            }
            for r in rays
        ]


# --------------------------------------------------------------------------------------
# every gprim with every axis

AXES = {"X": np.array([1.0, 0, 0]), "Y": np.array([0, 1.0, 0]), "Z": np.array([0, 0, 1.0])}
# a direction perpendicular to each axis (the canonical u of raycast's frame)
PERP = {"X": np.array([0, 1.0, 0]), "Y": np.array([0, 0, 1.0]), "Z": np.array([1.0, 0, 0])}
SPACING = 30.0


def ray(label, origin, direction, hit, depth, normal, prim=None):
    entry = {"label": label, "origin": vec(origin), "direction": vec(direction), "hit": hit}
    if hit is None:
        entry.update(depth=None, normal=[0.0, 0.0, 0.0])
    else:
        n = np.asarray(normal, dtype=float)
        entry.update(depth=float(depth), normal=vec(n / np.linalg.norm(n)))
    if prim is not None:
        entry["prim"] = prim
    return entry


def export_gprims():
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.Xform.Define(stage, "/World")
    rays = []

    def place(prim, centre):
        UsdGeom.Xformable(prim).AddTranslateOp(UsdGeom.XformOp.PrecisionDouble).Set(
            Gf.Vec3d(*centre)
        )

    def centre_of(row, col):
        return np.array([col * SPACING, row * SPACING, 0.0])

    def define(schema, row, col, name, create, value):
        """A gprim at grid cell (row, col), authoring `value` through the schema's `create`
        method unless it is None (the fallback); returns the cell's centre."""
        prim = schema.Define(stage, name)
        if value is not None:
            getattr(prim, create)(value)
        c = centre_of(row, col)
        place(prim, c)
        return c

    # Sphere: authored radius and the fallback radius 1.
    for col, radius in enumerate([1.5, None]):
        name = f"/World/Sphere{col}"
        c = define(UsdGeom.Sphere, 0, col, name, "CreateRadiusAttr", radius)
        r = radius or 1.0
        rays.append(ray(f"{name} from +Z", c + [0, 0, 10], [0, 0, -1], name, 10 - r, [0, 0, 1]))
        rays.append(ray(f"{name} from -X", c - [10, 0, 0], [1, 0, 0], name, 10 - r, [-1, 0, 0]))
    # Cube: size 3 and the fallback size 2.
    for col, size in enumerate([3.0, None]):
        name = f"/World/Cube{col}"
        c = define(UsdGeom.Cube, 1, col, name, "CreateSizeAttr", size)
        h = (size or 2.0) / 2
        rays.append(
            ray(
                f"{name} +Z face",
                c + [0.5 * h, -0.25 * h, 10],
                [0, 0, -1],
                name,
                10 - h,
                [0, 0, 1],
                prim=[0],
            )
        )
        rays.append(
            ray(
                f"{name} -Y face",
                c + [0.25 * h, -10, 0.5 * h],
                [0, 1, 0],
                name,
                10 - h,
                [0, -1, 0],
                prim=[11],
            )
        )
    # Shapes with an axis: rows 2.. by type, columns by axis (+ one with fallbacks).
    row = 2
    for type_name in ("Cylinder", "Cone", "Capsule", "Plane", "Cylinder_1"):
        for col, axis in enumerate(["X", "Y", "Z", None]):
            c = centre_of(row, col)
            name = f"/World/{type_name}{axis or 'Fallback'}"
            schema = getattr(UsdGeom, type_name)
            prim = schema.Define(stage, name)
            place(prim, c)
            a = AXES[axis or "Z"]
            u = PERP[axis or "Z"]
            if axis is not None:
                prim.CreateAxisAttr(axis)
            if type_name in ("Cylinder", "Cone"):
                r, h = (0.75, 3.0) if axis else (1.0, 2.0)
                if axis:
                    prim.CreateRadiusAttr(r)
                    prim.CreateHeightAttr(h)
                if type_name == "Cylinder":
                    rays.append(ray(f"{name} side", c + 10 * u, -u, name, 10 - r, u))
                    rays.append(
                        ray(
                            f"{name} top cap",
                            c + 10 * a + 0.3 * r * u,
                            -a,
                            name + ":caps",
                            10 - h / 2,
                            a,
                        )
                    )
                    rays.append(
                        ray(
                            f"{name} bottom cap",
                            c - 10 * a - 0.3 * r * u,
                            a,
                            name + ":caps",
                            10 - h / 2,
                            -a,
                        )
                    )
                else:
                    rho = r / 2  # the cone has radius r/2 at w = 0
                    grad = r * u + (r * r / h) * a
                    rays.append(
                        ray(
                            f"{name} side at half radius",
                            c + rho * u + 10 * a,
                            -a,
                            name,
                            10.0,
                            grad,
                        )
                    )
                    rays.append(
                        ray(
                            f"{name} base cap",
                            c - 10 * a + 0.3 * r * u,
                            a,
                            name + ":caps",
                            10 - h / 2,
                            -a,
                        )
                    )
                    rays.append(
                        ray(f"{name} side from the side", c + 10 * u, -u, name, 10 - rho, grad)
                    )
            elif type_name == "Cylinder_1":
                top, bottom, h = (0.5, 1.0, 2.0) if axis else (1.0, 1.0, 2.0)
                if axis:
                    prim.CreateRadiusTopAttr(top)
                    prim.CreateRadiusBottomAttr(bottom)
                    prim.CreateHeightAttr(h)
                radius_mid = (top + bottom) / 2
                b = (top - bottom) / h  # f = u² + v² − (radius_mid + b w)²
                grad = 2 * radius_mid * u - 2 * b * radius_mid * a
                rays.append(
                    ray(f"{name} side at w = 0", c + 10 * u, -u, name, 10 - radius_mid, grad)
                )
                rays.append(ray(f"{name} top cap", c + 10 * a, -a, name + ":caps", 10 - h / 2, a))
            elif type_name == "Capsule":
                r, h = (0.5, 2.0) if axis else (0.5, 1.0)
                if axis:
                    prim.CreateRadiusAttr(r)
                    prim.CreateHeightAttr(h)
                rays.append(ray(f"{name} side", c + 10 * u, -u, name, 10 - r, u))
                rays.append(ray(f"{name} top", c + 10 * a, -a, name + ":top", 10 - h / 2 - r, a))
                rays.append(
                    ray(f"{name} bottom", c - 10 * a, a, name + ":bottom", 10 - h / 2 - r, -a)
                )
                # on the seam-free part of the top hemisphere, 45 degrees up
                p = c + (h / 2) * a + r * (u + a) / math.sqrt(2)
                rays.append(
                    ray(
                        f"{name} top hemisphere at 45 degrees",
                        p + 10 * u,
                        -u,
                        name + ":top",
                        10.0,
                        u + a,
                    )
                )
            else:  # Plane
                width, length = (4.0, 6.0) if axis else (2.0, 2.0)
                if axis:
                    prim.CreateWidthAttr(width)
                    prim.CreateLengthAttr(length)
                # usd-core's extents: X spans (y: length, z: width), Y (x: width, z: length),
                # Z (x: width, y: length)
                width_dir = {"X": [0, 0, 1.0], "Y": [1.0, 0, 0], "Z": [1.0, 0, 0]}[axis or "Z"]
                length_dir = {"X": [0, 1.0, 0], "Y": [0, 0, 1.0], "Z": [0, 1.0, 0]}[axis or "Z"]
                width_dir, length_dir = np.array(width_dir), np.array(length_dir)
                inside = 0.45 * width * width_dir + 0.45 * length * length_dir
                rays.append(ray(f"{name} front", c + inside + 10 * a, -a, name, 10.0, a))
                rays.append(
                    ray(f"{name} back (normal not flipped)", c + inside - 10 * a, a, name, 10.0, a)
                )
                rays.append(
                    ray(
                        f"{name} just outside the width",
                        c + 0.55 * width * width_dir + 10 * a,
                        -a,
                        None,
                        None,
                        None,
                    )
                )
                rays.append(
                    ray(
                        f"{name} inside the length only",
                        c + 0.55 * length * length_dir + 0.1 * width * width_dir + 10 * a,
                        -a,
                        None,
                        None,
                        None,
                    )
                )
        row += 1
    save(stage, "gprims")
    EXPECTED["gprims"] = rays


# --------------------------------------------------------------------------------------
# meshes placed by usd-core: nested transforms, composition, instancing


def tetra_points(scale=1.0):
    return [
        Gf.Vec3f(*(scale * np.array(p))) for p in [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)]
    ]


TETRA_FACES = [0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2]


def define_tetra(stage, path, scale=1.0, left_handed=False):
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(tetra_points(scale))
    mesh.CreateFaceVertexCountsAttr([3, 3, 3, 3])
    faces = list(TETRA_FACES)
    if left_handed:
        faces = [faces[i + k] for i in range(0, 12, 3) for k in (0, 2, 1)]
        mesh.CreateOrientationAttr(UsdGeom.Tokens.leftHanded)
    mesh.CreateFaceVertexIndicesAttr(faces)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    return mesh


def define_quad_cube(stage, path, half=0.5):
    """A cube of quads (faces triangulated as fans by raycast), outward winding."""
    mesh = UsdGeom.Mesh.Define(stage, path)
    h = half
    mesh.CreatePointsAttr([Gf.Vec3f(x, y, z) for z in (-h, h) for y in (-h, h) for x in (-h, h)])
    mesh.CreateFaceVertexCountsAttr([4] * 6)
    mesh.CreateFaceVertexIndicesAttr(
        [4, 5, 7, 6, 0, 2, 3, 1, 1, 3, 7, 5, 0, 4, 6, 2, 2, 6, 7, 3, 0, 1, 5, 4]
    )
    return mesh


# fmt: off
# (the op table keeps its hand layout, one entry per few lines)
def export_xforms():
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.Xform.Define(stage, "/World")
    root = UsdGeom.Xform.Define(stage, "/World/Root")
    root.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    root.AddRotateXYZOp().Set(Gf.Vec3f(10, 20, 30))
    root.AddScaleOp().Set(Gf.Vec3f(2, 2, 2))
    # one leaf per op kind, each under its own child of Root
    ops = [
        ("translate", lambda x: x.AddTranslateOp(UsdGeom.XformOp.PrecisionDouble)
                                 .Set(Gf.Vec3d(4, 0, 0))),
        ("translateXYZ", lambda x: (x.AddTranslateXOp().Set(6.0), x.AddTranslateYOp().Set(1.0),
                                    x.AddTranslateZOp().Set(-1.0))),
        ("scale", lambda x: (x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(0, 4, 0)),
                             x.AddScaleOp().Set(Gf.Vec3f(0.5, 1.5, 1.0)))),
        ("scaleXYZ", lambda x: (x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(0, 8, 0)),
                                x.AddScaleXOp().Set(0.75), x.AddScaleYOp().Set(1.25),
                                x.AddScaleZOp().Set(0.5))),
        ("rotateXYZ_single", lambda x: (x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(0, 0, 4)),
                                        x.AddRotateXOp().Set(30.0), x.AddRotateYOp().Set(45.0),
                                        x.AddRotateZOp().Set(60.0))),
    ]
    for k, order in enumerate(("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")):
        ops.append((f"rotate{order}", lambda x, order=order, k=k: (
            x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(-4, 0, 4 * k + 4)),
            getattr(x, f"AddRotate{order}Op")().Set(Gf.Vec3f(25, 50, 75)))))
    ops += [
        ("orient", lambda x: (x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(4, 4, 0)),
                              x.AddOrientOp().Set(Gf.Quatf(0.8, 0.2, 0.4, 0.4)))),
        ("transform", lambda x: x.AddTransformOp().Set(Gf.Matrix4d(
            1, 0.25, 0, 0, 0.5, 1, 0, 0, 0, 0.3, 1.5, 0, -4, -4, 2, 1))),
        ("pivot_invert", lambda x: (
            x.AddTranslateOp(opSuffix="place").Set(Gf.Vec3d(4, -4, 0)),
            x.AddTranslateOp(opSuffix="pivot").Set(Gf.Vec3d(0.5, 0.5, 0)),
            x.AddRotateZOp().Set(90.0),
            x.AddTranslateOp(opSuffix="pivot", isInverseOp=True))),
        ("reset", lambda x: (x.SetResetXformStack(True),
                             x.AddTranslateOp().Set(Gf.Vec3d(20, 0, 0)))),
        ("mirror", lambda x: (x.AddTranslateOp(opSuffix="t").Set(Gf.Vec3d(8, -4, 0)),
                              x.AddScaleOp().Set(Gf.Vec3f(-1, 1, 1)))),
    ]
    for name, author in ops:
        group = UsdGeom.Xform.Define(stage, f"/World/Root/{name}")
        author(group)
        define_tetra(stage, f"/World/Root/{name}/tet", 0.5, left_handed=(name == "orient"))
    # a scope's and an untyped prim's xformOps are ignored (not Xformable)
    scope = UsdGeom.Scope.Define(stage, "/World/Scope")
    prim = scope.GetPrim()
    prim.CreateAttribute("xformOp:translate", Sdf.ValueTypeNames.Double3).Set(Gf.Vec3d(100, 0, 0))
    prim.CreateAttribute("xformOpOrder", Sdf.ValueTypeNames.TokenArray).Set(["xformOp:translate"])
    leaf = UsdGeom.Xform.Define(stage, "/World/Scope/Leaf")
    leaf.AddTranslateOp().Set(Gf.Vec3d(0, -20, 0))
    define_quad_cube(stage, "/World/Scope/Leaf/cube")
    save(stage, "xforms")
    EXPECTED["xforms"] = mesh_rays(stage)
# fmt: on


def export_composition():
    # the referenced layer: a model with a variant set and a quadric prim
    ref = Usd.Stage.CreateInMemory()
    model = UsdGeom.Xform.Define(ref, "/Model")
    ref.SetDefaultPrim(model.GetPrim())
    define_tetra(ref, "/Model/body", 1.0)
    variants = model.GetPrim().GetVariantSets().AddVariantSet("size")
    for variant, scale in (("small", 0.5), ("large", 1.5)):
        variants.AddVariant(variant)
        variants.SetVariantSelection(variant)
        with variants.GetVariantEditContext():
            define_quad_cube(ref, "/Model/hat", 0.5 * scale).AddTranslateOp().Set(Gf.Vec3d(0, 0, 2))
    variants.SetVariantSelection("small")
    ref.GetRootLayer().Export(str(OUT / "composition_model.usda"))

    stage = Usd.Stage.CreateInMemory()
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    camera = UsdGeom.Camera.Define(stage, "/World/Camera")
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 0, 40))
    camera.CreateFocalLengthAttr(35.0)
    camera.CreateClippingRangeAttr(Gf.Vec2f(0.5, 500))
    # referenced twice, with the two variants
    for name, variant, x in (("SmallModel", "small", -6.0), ("LargeModel", "large", -12.0)):
        prim = stage.DefinePrim(f"/World/{name}")
        prim.GetReferences().AddReference("./composition_model.usda")
        prim.GetVariantSets().GetVariantSet("size").SetVariantSelection(variant)
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(x, 0, 0))
    # scene-graph instancing: two instances of the referenced model
    for k, x in enumerate((6.0, 12.0)):
        prim = stage.DefinePrim(f"/World/Instance{k}")
        prim.GetReferences().AddReference("./composition_model.usda")
        prim.SetInstanceable(True)
        UsdGeom.Xformable(prim).AddTranslateOp().Set(Gf.Vec3d(x, 6.0, 0))
    # a point instancer with its prototypes under it, one invisible id
    instancer = UsdGeom.PointInstancer.Define(stage, "/World/Instancer")
    instancer.AddTranslateOp().Set(Gf.Vec3d(0, -8, 0))
    define_tetra(stage, "/World/Instancer/Prototypes/Tet", 0.75)
    cube = define_quad_cube(stage, "/World/Instancer/Prototypes/Box", 0.6)
    cube.AddRotateZOp().Set(15.0)  # the prototype's own transform applies to each instance
    instancer.CreatePrototypesRel().SetTargets(
        ["/World/Instancer/Prototypes/Tet", "/World/Instancer/Prototypes/Box"]
    )
    instancer.CreateProtoIndicesAttr([0, 1, 0, 1, 1])
    instancer.CreatePositionsAttr(
        [
            Gf.Vec3f(-8, 0, 0),
            Gf.Vec3f(-4, 0, 0),
            Gf.Vec3f(0, 0, 0),
            Gf.Vec3f(4, 0, 0),
            Gf.Vec3f(8, 0, 0),
        ]
    )
    instancer.CreateOrientationsAttr(
        [
            Gf.Quath(1, 0, 0, 0),
            Gf.Quath(0.5, 0.5, 0.5, 0.5),
            Gf.Quath(0, 0, 0, 1),
            Gf.Quath(1, 0, 0, 0),
            Gf.Quath(1, 0, 0, 0),
        ]
    )
    instancer.CreateScalesAttr(
        [
            Gf.Vec3f(1, 1, 1),
            Gf.Vec3f(1, 2, 1),
            Gf.Vec3f(1.5, 1.5, 1.5),
            Gf.Vec3f(1, 1, 1),
            Gf.Vec3f(1, 1, 1),
        ]
    )
    instancer.CreateInvisibleIdsAttr([3])
    # a general quadric prim (matrix form): an ellipsoid, and hidden things
    quadric = UsdGeom.Xform.Define(stage, "/World/Quadric")
    quadric.AddTranslateOp().Set(Gf.Vec3d(0, 14, 0))
    write_quadric(quadric.GetPrim(), {"Q": [1, 0, 0, 0, 4, 0, 0, 0, 1], "P": [0, 0, 0], "R": -4})
    hidden = define_tetra(stage, "/World/Hidden", 1.0)
    hidden.CreateVisibilityAttr(UsdGeom.Tokens.invisible)
    guide = define_tetra(stage, "/World/Guide", 1.0)
    guide.CreatePurposeAttr(UsdGeom.Tokens.guide)
    inactive = define_tetra(stage, "/World/Inactive", 1.0)
    inactive.GetPrim().SetActive(False)
    # a `def` under an `over` that nothing defines: not drawn
    under_over = define_tetra(stage, "/World/OverOnly/Mesh", 1.0)
    stage.GetRootLayer().GetPrimAtPath("/World/OverOnly").specifier = Sdf.SpecifierOver
    for p in (hidden, guide, inactive, under_over):
        UsdGeom.Xformable(p).AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    save(stage, "composition")
    # copy the referenced layer next to the binary too (same folder, so nothing to do)
    EXPECTED["composition"] = mesh_rays(
        Usd.Stage.Open(str(OUT / "composition.usda")), quadric_at=("/World/Quadric", [0, 14, 0])
    )


def intersect(origin, direction, objects):
    """Nearest hit over all triangles: (name, t, triangle index, unit normal) or None."""
    best = None
    for name, tris in objects:
        for index, tri in enumerate(tris):
            h = tri_hit(tri, origin, direction, min_det=1e-14)
            if h is not None and (best is None or h[0] < best[1]):
                t, n, u, v = h
                best = (name, t, index, n, min(u, v, 1 - u - v))
    return best


def mesh_rays(stage, quadric_at=None):
    objects = flatten(stage)
    rays = []
    for name, tris in objects:
        for index in range(0, len(tris), max(1, len(tris) // 4)):
            a, b, c = tris[index]
            n = np.cross(b - a, c - a)
            n /= np.linalg.norm(n)
            centroid = (a + b + c) / 3
            origin = centroid + 3.0 * n
            direction = -n
            hit = intersect(origin, direction, objects)
            if hit is None or hit[4] < 1e-3:
                continue  # missing or too close to an edge to be unambiguous
            rays.append(
                ray(
                    f"{name} triangle {index}",
                    origin,
                    direction,
                    hit[0],
                    hit[1] * np.linalg.norm(direction),
                    hit[3],
                    prim=[hit[2]],
                )
            )
    if quadric_at:
        name, centre = quadric_at
        c = np.array(centre, dtype=float)
        # x^2 + 4 y^2 + z^2 = 4: semi-axes 2, 1, 2
        rays.append(ray(f"{name} from +X", c + [10, 0, 0], [-1, 0, 0], name, 8.0, [1, 0, 0]))
        rays.append(ray(f"{name} from +Y", c + [0, 5, 0], [0, -1, 0], name, 4.0, [0, 1, 0]))
    # the hidden, guide, inactive and under-an-over tetrahedra sit at (0, 0, 5): nothing there
    if stage.GetPrimAtPath("/World/Hidden"):
        origin, direction = np.array([0, 0.01, 9.0]), np.array([0, 0, -1.0])
        assert intersect(origin, direction, objects) is None
        rays.append(
            ray(
                "hidden, guide and inactive prims are not drawn",
                origin,
                direction,
                None,
                None,
                None,
            )
        )
    return rays


# --------------------------------------------------------------------------------------
# invalid quadric prims

BAD = {
    "quadric_both_forms": (
        {"coefficients": [1, 1, 1, 0, 0, 0, 0, 0, 0, -1], "R": -1.0},
        "not both",
    ),
    "quadric_missing_r": (
        {"Q": [1, 0, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0, 0]},
        "missing raycast:quadric:R",
    ),
    "quadric_coefficient_count": ({"coefficients": [1, 1, 1, 0, 0, 0, 0, 0, -1]}, "9 numbers"),
    "quadric_unbounded": ({"coefficients": [1, 1, 0, 0, 0, 0, 0, 0, 0, -1]}, "needs `bounds`"),
    "quadric_not_symmetric": (
        {"Q": [1, 0.5, 0, 0, 1, 0, 0, 0, 1], "P": [0, 0, 0], "R": -1},
        "not symmetric",
    ),
    "quadric_zero_q_p": ({"coefficients": [0, 0, 0, 0, 0, 0, 0, 0, 0, 1]}, "not a surface"),
    "quadric_bounds_inverted": (
        {
            "coefficients": [1, 1, 1, 0, 0, 0, 0, 0, 0, -1],
            "bounds": {"min": [1, 0, 0], "max": [0, 1, 1]},
        },
        "exceeds",
    ),
}


def export_bad():
    bad = {}
    for stem, (extension, message) in BAD.items():
        stage = Usd.Stage.CreateInMemory()
        prim = UsdGeom.Xform.Define(stage, "/Q").GetPrim()
        if "R" in extension and "coefficients" in extension:
            write_quadric(prim, {"coefficients": extension["coefficients"]})
            prim.CreateAttribute("raycast:quadric:R", Sdf.ValueTypeNames.Double, custom=True).Set(
                -1.0
            )
        elif "Q" in extension and "R" not in extension:
            prim.CreateAttribute("raycast:quadric:Q", Sdf.ValueTypeNames.Matrix3d, custom=True).Set(
                Gf.Matrix3d(*extension["Q"])
            )
            prim.CreateAttribute("raycast:quadric:P", Sdf.ValueTypeNames.Double3, custom=True).Set(
                Gf.Vec3d(*extension["P"])
            )
        else:
            write_quadric(prim, extension)
        (OUT / "bad").mkdir(parents=True, exist_ok=True)
        stage.GetRootLayer().Export(str(OUT / "bad" / f"{stem}.usda"))
        bad[stem] = message
    (OUT / "bad" / "expected_errors.json").write_text(
        json.dumps(bad, indent=1, sort_keys=True) + "\n"
    )
    print(f"wrote {len(bad)} files in fixtures/usd/bad/")


def main(argv=None):
    argparse.ArgumentParser(
        prog=prog("usd-fixtures"), description=__doc__.split("\n\n")[0]
    ).parse_args(argv)
    OUT.mkdir(parents=True, exist_ok=True)
    export_gltf_scenes()
    export_gprims()
    export_xforms()
    export_composition()
    export_bad()
    text = json.dumps(EXPECTED, indent=1, sort_keys=True, allow_nan=False)
    (OUT / "expected_rays.json").write_text(text + "\n")
    print(f"wrote fixtures/usd/expected_rays.json ({sum(map(len, EXPECTED.values()))} rays)")
    return 0
