"""The `uv`, `shading_normal` and `material` outputs against references that share no code with
raycast: trimesh's reading of the file's texture coordinates and normals, interpolated at the
hit with trimesh's own ray test and barycentric weights; the glTF JSON's and OBJ text's
materials; usd-core's `ComputeBoundMaterial`. And the command line's files: the same values,
the sidecar's `materials`, the EXR channels.

Run: .venv/bin/python -m pytest tests/python/test_attributes.py
"""

import json
import subprocess
import warnings

import numpy as np
import OpenEXR
import pytest
import trimesh
from binary import RAYCAST, ROOT, needs_binary

import raycast

FIXTURES = ROOT / "fixtures" / "attributes"
GLTF, OBJ, SEAMS, PLY, USD = (
    FIXTURES / n for n in ("textured.gltf", "textured.obj", "seams.obj", "dome.ply", "bound.usda")
)


def rays_down(lo, hi, n, seed=3):
    """`n` rays from above the box [lo, hi] (xy), slightly tilted, pointing down."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(lo, hi, (n, 2))
    origins = np.column_stack([xy, np.full(n, 10.0)])
    directions = np.column_stack([rng.uniform(-0.02, 0.02, (n, 2)), -np.ones(n)])
    return origins, directions


def trimesh_reference(scene, origins, directions, flip_v):
    """The nearest hit of each ray over the world-placed geometries of a trimesh scene (its
    numpy ray test), with the uv and unit normal interpolated there from the file's values by
    trimesh's barycentric weights; NaN where there is no hit or the geometry has no uv."""
    n = len(origins)
    best = np.full(n, np.inf)
    uv = np.full((n, 2), np.nan)
    normal = np.full((n, 3), np.nan)
    point = np.full((n, 3), np.nan)
    for node in scene.graph.nodes_geometry:
        transform, name = scene.graph[node]
        mesh = scene.geometry[name]
        world = trimesh.Trimesh(
            trimesh.transform_points(mesh.vertices, transform), mesh.faces, process=False
        )
        intersector = trimesh.ray.ray_triangle.RayMeshIntersector(world)
        locations, ray, tri = intersector.intersects_location(
            origins, directions, multiple_hits=True
        )
        t = np.einsum("ij,ij->i", locations - origins[ray], directions[ray]) / np.einsum(
            "ij,ij->i", directions[ray], directions[ray]
        )
        weights = trimesh.triangles.points_to_barycentric(world.triangles[tri], locations)
        has_uv = getattr(mesh.visual, "uv", None) is not None
        normals = mesh.vertex_normals  # the file's, as trimesh read them (process=False)
        linear = np.linalg.inv(transform[:3, :3]).T
        for k in np.argsort(-t):  # nearest last, so that it wins
            r = ray[k]
            if t[k] >= best[r]:
                continue
            best[r] = t[k]
            point[r] = locations[k]
            corners = mesh.faces[tri[k]]
            uv[r] = weights[k] @ mesh.visual.uv[corners] if has_uv else np.nan
            if has_uv and flip_v:
                uv[r, 1] = 1 - uv[r, 1]  # trimesh moves glTF's top-left origin to the bottom left
            m = linear @ (weights[k] @ normals[corners])
            normal[r] = m / np.linalg.norm(m)
    return point, uv, normal


@pytest.mark.parametrize(
    ("path", "box", "flip_v"),
    [(GLTF, (-1.2, 4.2), True), (SEAMS, (-1.1, 1.1), False), (PLY, (-1.1, 1.1), False)],
    ids=["gltf", "obj", "ply"],
)
def test_uv_and_shading_normals_match_trimesh(path, box, flip_v):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference = trimesh.load(path, process=False)
    if isinstance(reference, trimesh.Trimesh):
        reference = trimesh.Scene(reference)
    origins, directions = rays_down(*box, 4000)
    point, uv, normal = trimesh_reference(reference, origins, directions, flip_v)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", raycast.RaycastWarning)  # a primitive without uv
        hits = raycast.load(path).cast(
            origins, directions, aovs=("position", "uv", "shading_normal")
        )
    # Rays that trimesh's tolerant test and the exact one see hitting the same point.
    same = np.isfinite(point[:, 0]) & (np.abs(hits["position"] - point).max(axis=1) < 1e-9)
    assert same.sum() > 0.9 * np.isfinite(point[:, 0]).sum() > 1000
    textured = same & np.isfinite(uv[:, 0])
    assert textured.sum() > 1000
    uv_error = np.abs(hits["uv"][textured] - uv[textured]).max()
    # The fixtures' primitives have NORMAL and TEXCOORD_0 together, or neither (where
    # trimesh makes normals of its own).
    normal_error = np.abs(hits["shading_normal"][textured] - normal[textured]).max()
    # The file's f32 values interpolated in f64 on both sides: only the weights differ.
    assert uv_error < 1e-6, uv_error
    assert normal_error < 1e-6, normal_error
    untextured = same & np.isnan(uv[:, 0])
    assert (hits["uv"][untextured] == np.inf).all()
    assert (hits["shading_normal"][untextured] == 0).all()
    print(f"{path.name}: {textured.sum()} rays, uv {uv_error:.2e}, normals {normal_error:.2e}")
    norms = np.linalg.norm(hits["shading_normal"][textured], axis=1)
    assert np.abs(norms - 1).max() < 1e-12


def expected_gltf_materials():
    """Each node's triangles' material names, from the glTF JSON: primitive by primitive."""
    doc = json.loads(GLTF.read_text())
    names = [m.get("name", f"material{i}") for i, m in enumerate(doc["materials"])]
    per_node = {}
    for node in doc["nodes"]:
        triangles = []
        for primitive in doc["meshes"][node["mesh"]]["primitives"]:
            count = doc["accessors"][primitive["indices"]]["count"] // 3
            triangles += [names[primitive["material"]]] * count
        per_node[node["name"]] = triangles
    return per_node


def obj_materials():
    """Each OBJ object's triangles' `usemtl` names, read from the text (faces fanned)."""
    per_object, current, name = {}, None, None
    for line in OBJ.read_text().splitlines():
        words = line.split()
        if words[:1] == ["o"]:
            name = words[1]
        elif words[:1] == ["usemtl"]:
            current = words[1]
        elif words[:1] == ["f"]:
            per_object.setdefault(name, []).extend([current] * (len(words) - 3))
    return per_object


@pytest.mark.parametrize("path", [GLTF, OBJ], ids=["gltf", "obj"])
def test_material_ids_match_the_files_bindings(path):
    expected = expected_gltf_materials() if path == GLTF else obj_materials()
    scene = raycast.load(path)
    origins, directions = rays_down(-1.2, 4.2 if path == GLTF else 1.2, 3000)
    hits = scene.cast(origins, directions, aovs=("id", "prim", "material"))
    hit = hits["id"] > 0
    assert hit.sum() > 500
    names = {o["id"]: o["name"] for o in scene.objects}
    for i in np.nonzero(hit)[0]:
        want = expected[names[hits["id"][i]]][hits["prim"][i]]
        assert scene.materials[hits["material"][i] - 1] == want
    assert (hits["material"][~hit] == 0).all()
    assert sorted(scene.materials) == sorted({m for v in expected.values() for m in v})


def test_usd_material_ids_match_usd_core():
    from pxr import Usd, UsdGeom, UsdShade

    stage = Usd.Stage.Open(str(USD))
    scene = raycast.load(USD)
    origins, directions = rays_down(-1.5, 5, 3000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", raycast.RaycastWarning)
        hits = scene.cast(origins, directions, aovs=("id", "prim", "material"))
    names = {o["id"]: o["name"] for o in scene.objects}
    seen = set()
    for i in np.nonzero(hits["id"])[0]:
        prim = stage.GetPrimAtPath(names[hits["id"][i]])
        bound = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()[0]
        if prim.IsA(UsdGeom.Mesh):
            # The face of the triangle (faces fanned, in order), and its subset's binding.
            counts = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get()
            face = np.repeat(np.arange(len(counts)), np.maximum(np.array(counts) - 2, 0))[
                hits["prim"][i]
            ]
            for subset in UsdShade.MaterialBindingAPI(prim).GetMaterialBindSubsets():
                if face in subset.GetIndicesAttr().Get():
                    bound = UsdShade.MaterialBindingAPI(subset.GetPrim()).ComputeBoundMaterial()[0]
        want = str(bound.GetPath()) if bound else None
        got = scene.materials[hits["material"][i] - 1] if hits["material"][i] else None
        assert got == want, names[hits["id"][i]]
        seen.add(got)
    assert seen == {"/World/Looks/Wood", "/World/Looks/Metal", "/World/Looks/Paint", None}


def test_usd_primvars_by_interpolation():
    """faceVarying and indexed vertex `st`, vertex and uniform normals, read back at the
    corners (rays straight down onto a corner's neighbourhood)."""
    scene = raycast.load(USD)
    origins = np.array(
        [[-0.999, -0.999, 5], [0.999, -0.999, 5], [-0.999, -0.999, -1], [-0.5, 0.9, -1]]
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", raycast.RaycastWarning)
        hits = scene.cast(origins, [0, 0, -1], aovs=("id", "uv", "shading_normal"))
    names = [scene.objects[i - 1]["name"] for i in hits["id"]]
    assert names == ["/World/Bound/Inherits"] * 2 + ["/World/Bound/Own"] * 2
    assert np.abs(hits["uv"][0] - [0, 0]).max() < 0.01  # faceVarying: face 0, corner 0
    assert np.abs(hits["uv"][1] - [1, 0]).max() < 0.01
    assert np.abs(hits["uv"][2] - [0, 1]).max() < 0.01  # st:indices [3, 2, 1, 0]: point 0 -> st[3]
    assert np.abs(hits["shading_normal"][0] - [0, 0, 1]).max() < 0.01
    unit = np.array([0.5, 0, 1]) / np.linalg.norm([0.5, 0, 1])
    assert np.abs(hits["shading_normal"][3] - unit).max() < 1e-12  # uniform: face 1's normal


def test_missing_attributes_warn_once_and_give_the_miss_value():
    scene = raycast.load(USD)
    ball = np.array([[4, 0, 5]])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hits = scene.cast(ball, [0, 0, -1], aovs=("uv", "shading_normal", "normal", "material"))
        scene.cast(ball, [0, 0, -1], aovs=("uv",))
    lines = [str(w.message) for w in caught if w.category is raycast.RaycastWarning]
    assert [line.split(":")[0] for line in lines] == ["uv", "shading_normal", "material"]
    assert lines[0].startswith("uv: 3 of 5 objects ('/World/Subsets' and 2 more)")
    assert (hits["uv"] == np.inf).all()  # a quadric: the miss value
    assert (hits["shading_normal"] == hits["normal"]).all()  # a quadric: its analytic normal
    assert scene.materials[hits["material"][0] - 1] == "/World/Looks/Paint"


@needs_binary
def test_the_command_line_writes_the_same_values(tmp_path):
    origins, directions = rays_down(-1.2, 4.2, 500)
    rays = tmp_path / "rays.npy"
    np.save(rays, np.column_stack([origins, directions]))
    aovs = ("uv", "shading_normal", "material")
    subprocess.run(
        [RAYCAST, GLTF, "--rays", rays, "--aov", ",".join(aovs), "--out", tmp_path / "r", "-q"],
        check=True,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", raycast.RaycastWarning)
        hits = raycast.load(GLTF).cast(origins, directions, aovs=aovs)
    for aov in aovs:
        assert np.array_equal(np.load(tmp_path / "r" / f"{aov}.npy"), hits[aov])
    sidecar = json.loads((tmp_path / "r" / "raycast.json").read_text())
    assert sidecar["materials"] == ["Red", "material1"]
    out = tmp_path / "c"
    subprocess.run(
        [
            RAYCAST,
            GLTF,
            "--aov",
            "uv,shading_normal,material",
            "--width",
            "16",
            "--height",
            "12",
            "--out",
            out,
            "-q",
        ],
        check=True,
    )
    channels = {name for path in out.glob("*.exr") for name in OpenEXR.File(str(path)).channels()}
    assert {"UV", "Ns", "material"} <= {c.split(".")[0] for c in channels}, channels
    assert {p.name for p in out.glob("*.png")} == {"shading_normal.png", "material.png"}


def test_an_unreadable_attribute_buffer_leaves_the_attribute_out(tmp_path):
    """NORMAL in a buffer whose file is missing: the render goes on, the normals are left out
    with a warning naming the buffer, the texture coordinates stay."""
    doc = json.loads(GLTF.read_text())
    normal = doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]
    doc["buffers"].append({"byteLength": 1024, "uri": "missing.bin"})
    doc["bufferViews"].append({"buffer": 1, "byteOffset": 0, "byteLength": 300})
    doc["accessors"][normal]["bufferView"] = len(doc["bufferViews"]) - 1
    for primitive in doc["meshes"][1]["primitives"]:
        primitive["attributes"].pop("NORMAL", None)
    path = tmp_path / "missing_normals.gltf"
    path.write_text(json.dumps(doc))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = raycast.load(path)
        hits = scene.cast([[0.1, 0.2, 5]], [0, 0, -1], aovs=("uv", "shading_normal"))
    lines = [str(w.message) for w in caught]
    assert any("/buffers/1" in line and "left out" in line for line in lines), lines
    assert any(line.startswith("shading_normal: 4 of 4 objects") for line in lines), lines
    assert (hits["shading_normal"] == 0).all()
    assert np.isfinite(hits["uv"]).all()


@pytest.mark.parametrize(
    ("name", "time"),
    [("CesiumMan.glb", 0.5), ("RiggedFigure.glb", 0.7), ("AnimatedMorphCube.glb", 0.5)],
)
def test_posed_shading_normals_follow_the_posed_surface(name, time):
    """Skinned normals (by the inverse transpose of the blended joint matrices) and morphed
    ones (NORMAL deltas) face as the posed triangles do: the file's normals left in the rest
    pose would not (CesiumMan's skin turns the whole figure)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", raycast.RaycastWarning)
        scene = raycast.load(ROOT / "fixtures" / "posed" / name, time=time)
    lo, hi = scene.bounds
    rng = np.random.default_rng(1)
    around = rng.normal(size=(5000, 3))
    origins = (lo + hi) / 2 + around / np.linalg.norm(
        around, axis=1, keepdims=True
    ) * np.linalg.norm(hi - lo)
    targets = lo + rng.uniform(size=(5000, 3)) * (hi - lo)
    hits = scene.cast(origins, targets - origins, aovs=("normal", "shading_normal", "id"))
    hit = hits["id"] > 0
    assert hit.sum() > 1000
    dot = np.einsum("ij,ij->i", hits["normal"][hit], hits["shading_normal"][hit])
    assert (dot > 0.5).mean() > 0.99
    assert np.median(dot) > 0.98
