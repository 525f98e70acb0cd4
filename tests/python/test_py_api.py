"""The Python package `raycast` (python/): loading, cast, errors, pickling, render.

Expected values come from the fixtures' known geometry (analysis) or from trimesh, never
from raycast itself. Run: .venv/bin/python -m pytest tests/python/test_py_api.py
"""

import errno
import pickle
from pathlib import Path

import numpy as np
import pytest

import raycast

ROOT = Path(__file__).resolve().parents[2]
CUBE = ROOT / "fixtures" / "gltf" / "cube.gltf"
SPHERE = ROOT / "fixtures" / "quadrics" / "sphere_coefficients.gltf"


@pytest.fixture(scope="module")
def cube():
    return raycast.load(CUBE)


def test_cube_fixture_is_the_unit_cube(cube):
    # fixtures/README.md: cube.gltf is the cube [-1, 1]^3 at the origin.
    assert np.array_equal(cube.bounds, [[-1, -1, -1], [1, 1, 1]])
    assert len(cube.objects) == 1 and cube.objects[0]["id"] == 1
    assert cube.info()["triangles"] == 12


def test_cast_hits_the_faces_it_must(cube):
    origins = np.array([[0.25, 0.5, 5.0], [5.0, 0.1, -0.2], [0.0, 0.0, 0.0], [3.0, 3.0, 3.0]])
    directions = np.array([[0.0, 0.0, -2.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
    hits = raycast.Scene.cast(cube, origins, directions, aovs=raycast.CAST_OUTPUTS)
    # Analysis: the +z face at t = 4/2, the +x face at 4, the -y face from inside at 1, a miss.
    assert hits["t"].tolist() == [2.0, 4.0, 1.0, np.inf]
    assert hits["distance"].tolist() == [4.0, 4.0, 1.0, np.inf]
    assert hits["normal"].tolist() == [[0, 0, 1], [1, 0, 0], [0, -1, 0], [0, 0, 0]]
    assert hits["position"][:3].tolist() == [[0.25, 0.5, 1.0], [1.0, 0.1, -0.2], [0.0, -1.0, 0.0]]
    assert np.isinf(hits["position"][3]).all()
    assert hits["id"].tolist() == [1, 1, 1, 0]
    assert hits["prim"][:2].tolist() == [1, 4] and hits["prim"][2] in (10, 11)
    assert hits["id"].dtype == np.uint32 and hits["prim"].dtype == np.uint32
    assert hits["prim"][3] == raycast.INVALID_PRIM
    # Barycentric weights reproduce the hit point from the triangle's corners.
    bary = hits["bary"][:3]
    assert np.allclose(bary.sum(axis=1), 1.0) and (bary >= 0).all()
    assert (hits["bary"][3] == 0).all()


def test_tmin_tmax_select_the_range(cube):
    o = np.array([[0.2, 0.3, 5.0]] * 4)
    d = np.array([[0.0, 0.0, -1.0]] * 4)
    # The +z face is at t = 4, the -z face at t = 6.
    hits = cube.cast(
        o, d, tmin=[0.0, 4.0, 4.5, 0.0], tmax=[np.inf, np.inf, 5.9, 3.9], aovs=["t", "normal"]
    )
    assert hits["t"].tolist() == [4.0, 6.0, np.inf, np.inf]
    assert hits["normal"][1].tolist() == [0, 0, -1]


def test_quadric_sphere_exact():
    # fixtures/quadrics/README.md: the sphere of radius 2 about the origin.
    scene = raycast.load(SPHERE)
    radius = 2.0
    o = np.array([[0.0, 0.0, 3 * radius]])
    hits = scene.cast(o, np.array([[0.0, 0.0, -1.0]]), aovs=["distance", "normal", "bary"])
    assert hits["distance"][0] == pytest.approx(2 * radius, rel=1e-14)
    assert hits["normal"][0] == pytest.approx([0, 0, 1], abs=1e-14)
    assert (hits["bary"][0] == 0).all()
    # Both crossings of the sphere, nearest first.
    found = scene.list_intersections(o, np.array([[0.0, 0.0, -1.0]]))
    assert found["ray_splits"].tolist() == [0, 2]
    assert found["t"] == pytest.approx([2 * radius, 4 * radius], rel=1e-14)


def test_inputs_are_read_in_place_or_converted(cube):
    o = np.asfortranarray(np.array([[0.25, 0.5, 5.0], [0.5, 0.25, 5.0]]))
    d = np.array([[0.0, 0.0, -1.0, 9.0], [0.0, 0.0, -1.0, 9.0]])[:, :3]  # a strided view
    f32 = cube.cast(o.astype(np.float32), d.astype(np.float32), aovs=["t"])
    f64 = cube.cast(o, d, aovs=["t"])
    ints = cube.cast(np.array([[0, 0, 5]]), np.array([[0, 0, -1]]), aovs=["t"])
    assert f32["t"].tolist() == f64["t"].tolist() == [4.0, 4.0]
    assert ints["t"].tolist() == [4.0]
    empty = cube.cast(np.zeros((0, 3)), np.zeros((0, 3)), aovs=["t", "normal"])
    assert empty["t"].shape == (0,) and empty["normal"].shape == (0, 3)


@pytest.mark.parametrize(
    "origins, directions, error, text",
    [
        (
            np.zeros((2, 2)),
            np.zeros((2, 2)),
            ValueError,
            "origins must have shape (..., 3), got (2, 2)",
        ),
        (np.float64(0.0), np.ones(3), ValueError, "origins must have shape (..., 3), got ()"),
        (np.zeros((2, 3)), np.ones((3, 3)), ValueError, "same shape"),
        (np.array([["a", "b", "c"]]), np.ones((1, 3)), TypeError, "origins must hold real numbers"),
        (
            np.zeros((2, 3)),
            np.array([[0, 0, 1], [np.nan, 0, 1]]),
            ValueError,
            "ray 1: direction (NaN, 0, 1) is not finite",
        ),
        (
            np.array([[0, 0, np.inf]]),
            np.ones((1, 3)),
            ValueError,
            "ray 0: origin (0, 0, inf) is not finite",
        ),
        (np.zeros((1, 3)), np.zeros((1, 3)), ValueError, "ray 0: direction is zero"),
    ],
)
def test_bad_rays_raise_clear_errors(cube, origins, directions, error, text):
    with pytest.raises(error) as raised:
        cube.cast(origins, directions)
    assert text in str(raised.value)


def test_rays_of_any_batch_shape(cube):
    # Analysis as in test_cast_hits_the_faces_it_must: from (x, y, 5) straight down, the +z
    # face at t = 4 when |x|, |y| < 1, a miss outside.
    xs = np.array([[-0.5, 0.0, 0.5, 2.0], [0.25, -0.75, 3.0, 0.9]])
    origins = np.stack([xs, np.full_like(xs, 0.1), np.full_like(xs, 5.0)], axis=-1)  # (2, 4, 3)
    down = np.array([0.0, 0.0, -1.0])  # one direction for every origin: broadcast
    hits = cube.cast(origins, down, aovs=["t", "normal", "id"])
    expected = np.where(np.abs(xs) < 1, 4.0, np.inf)
    assert hits["t"].shape == (2, 4) and hits["t"].tolist() == expected.tolist()
    assert hits["normal"].shape == (2, 4, 3)
    assert hits["normal"][0, 0].tolist() == [0, 0, 1] and hits["id"][1, 2] == 0
    # Open3D's layout: whole rays (..., 6); a single ray of shape (6,) gives 0-d results.
    rays = np.concatenate([origins, np.broadcast_to(down, origins.shape)], axis=-1)
    assert cube.cast(rays, aovs=["t"])["t"].tolist() == expected.tolist()
    one = cube.cast(np.array([0.2, 0.3, 5.0, 0.0, 0.0, -2.0]), aovs=["t"])["t"]
    assert one.shape == () and one == 2.0
    # Per-ray ranges broadcast too; occluded, counts and contains keep the batch shape.
    ranged = cube.cast(origins, down, tmax=np.array([[3.9], [np.inf]]), aovs=["t"])["t"]
    assert ranged.tolist() == [[np.inf] * 4, expected[1].tolist()]
    assert cube.occluded(origins, down).tolist() == (np.abs(xs) < 1).tolist()
    counts = cube.count_intersections(origins, down)
    assert counts.shape == (2, 4) and counts.tolist() == np.where(np.abs(xs) < 1, 2, 0).tolist()
    points = np.zeros((2, 2, 3))
    points[1, 1] = [0.0, 0.0, 3.0]
    assert cube.contains(points).tolist() == [[True, True], [True, False]]
    # A bad ray is named by its place in the batch.
    bad = origins.copy()
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"ray \(1, 2\): origin \(NaN, 0.1, 5\) is not finite"):
        cube.cast(bad, down)


def test_bad_options_raise_clear_errors(cube):
    o, d = np.zeros((1, 3)), np.ones((1, 3))
    with pytest.raises(ValueError, match="unknown output 'depthh'"):
        cube.cast(o, d, aovs=["depthh"])
    with pytest.raises(ValueError, match="z output needs a camera"):
        cube.cast(o, d, aovs=["z"])
    with pytest.raises(ValueError, match="ray 0: tmin -1 is not a number >= 0"):
        cube.cast(o, d, tmin=-1.0)
    with pytest.raises(ValueError, match=r"tmax must be a number or have shape \(1,\)"):
        cube.cast(o, d, tmax=[1.0, 2.0])
    with pytest.raises(ValueError, match="points must have shape"):
        cube.contains(np.zeros((4, 2)))


def test_scene_warnings_are_python_warnings(tmp_path):
    empty = tmp_path / "empty.obj"
    empty.write_text("# nothing but a comment\n")
    with pytest.warns(raycast.RaycastWarning, match="no triangles or quadrics") as caught:
        scene = raycast.load(empty)
    assert caught[0].filename == __file__  # pointed at the caller of load()
    assert scene.info()["warnings"] == [str(w.message) for w in caught]


def test_load_errors_are_typed(tmp_path):
    missing = tmp_path / "missing.glb"
    with pytest.raises(raycast.SceneNotFoundError) as raised:
        raycast.load(missing)
    assert isinstance(raised.value, FileNotFoundError)
    assert str(missing) in str(raised.value)
    assert raised.value.errno == errno.ENOENT and raised.value.filename == str(missing)
    broken = tmp_path / "broken.gltf"
    broken.write_text("{ not json")
    with pytest.raises(raycast.SceneError) as raised:
        raycast.load(broken)
    assert not isinstance(raised.value, FileNotFoundError)
    assert str(broken) in str(raised.value)
    with pytest.raises(raycast.SceneError, match="unsupported file type"):
        raycast.load_bytes(b"<model/>", "x.3mf")
    with pytest.raises(raycast.SceneError, match="has no 'endsolid' line"):
        raycast.load_bytes(b"solid x", "x.stl")
    with pytest.raises(raycast.UsageError, match="USD scenes load from a file"):
        raycast.load_bytes(b"#usda 1.0\n", "x.usda")
    with pytest.raises(raycast.SceneError, match="no scene 'nope'|scene 'nope'"):
        raycast.load(CUBE, scene="nope")


def test_errors_carry_their_code(tmp_path):
    """Every exception has the stable code `raycast check` would report: the reader's own
    (the glTF-Validator's INVALID_JSON for a document that is not JSON, STL_TRUNCATED for an
    ASCII STL without its 'endsolid' line) or the class's."""
    with pytest.raises(raycast.SceneNotFoundError) as raised:
        raycast.load(tmp_path / "missing.glb")
    assert raised.value.code == "NOT_FOUND"
    broken = tmp_path / "broken.gltf"
    broken.write_text("{ not json")
    with pytest.raises(raycast.SceneError) as raised:
        raycast.load(broken)
    assert raised.value.code == "INVALID_JSON"
    with pytest.raises(raycast.UsageError) as raised:
        raycast.load_bytes(b"#usda 1.0\n", "x.usda")
    assert raised.value.code == "USAGE"
    with pytest.raises(raycast.SceneError) as raised:
        raycast.load_bytes(b"solid x", "x.stl")
    assert raised.value.code == "STL_TRUNCATED"


def test_load_bytes_matches_load(cube):
    glb = (ROOT / "fixtures" / "gltf" / "cube.glb").read_bytes()
    from_bytes = raycast.load_bytes(glb, "cube.glb")
    obj = raycast.load_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "tri.obj")
    o, d = np.array([[0.2, 0.3, 5.0]]), np.array([[0.0, 0.0, -1.0]])
    assert (
        from_bytes.cast(o, d, aovs=["t"])["t"].tolist() == cube.cast(o, d, aovs=["t"])["t"].tolist()
    )
    assert obj.cast(np.array([[0.2, 0.2, 1.0]]), d, aovs=["t"])["t"].tolist() == [1.0]


def test_scene_pickles_by_path_and_by_bytes(cube):
    o, d = np.array([[0.2, 0.3, 5.0]]), np.array([[0.0, 0.0, -1.0]])
    again = pickle.loads(pickle.dumps(cube))
    assert again.cast(o, d, aovs=["t"])["t"].tolist() == [4.0]
    memory = raycast.load_bytes((ROOT / "fixtures" / "gltf" / "cube.glb").read_bytes(), "cube.glb")
    blob = pickle.dumps(memory)
    assert b"glTF" in blob  # the bytes travel, not a path
    assert pickle.loads(blob).cast(o, d, aovs=["t"])["t"].tolist() == [4.0]


def test_render_look_at_and_pinhole_agree(cube):
    # A pinhole K with the principal point at the image centre and fy = fx is the same camera
    # as a look-at camera with that vertical field of view (the look-at camera looks down -Z
    # with +Y up, the pinhole down +Z with +Y down: the cam-to-world matrix flips Y and Z).
    w, h, yfov = 16, 12, 40.0
    look = raycast.camera.look_at([0.5, 0.7, 6.0], [0.5, 0.7, 0.0], yfov_deg=yfov)
    f = (h / 2) / np.tan(np.radians(yfov) / 2)
    K = [[f, 0, w / 2], [0, f, h / 2], [0, 0, 1]]
    cam_to_world = np.array(look.cam_to_world) @ np.diag([1.0, -1.0, -1.0, 1.0])
    pin = raycast.camera.pinhole(K, cam_to_world, w, h)
    a = cube.render(look, w, h, aovs=["depth", "z", "id"])
    b = cube.render(pin, w, h, aovs=["depth", "z", "id"])
    assert a["depth"].shape == (h, w) and a["id"].dtype == np.uint32
    assert np.allclose(a["depth"], b["depth"], rtol=1e-12) and (a["id"] == b["id"]).all()
    # Analysis: the centre pixels see the +z face, at z = 6 - 1 = 5 along the view axis.
    assert a["z"][h // 2, w // 2] == pytest.approx(5.0, rel=1e-12)
    with pytest.raises(ValueError, match="made for 16x12 pixels"):
        cube.render(pin, 8, 8)
    with pytest.raises(raycast.UsageError, match="eye and target are the same point"):
        raycast.camera.look_at([0, 0, 0], [0, 0, 0])


def test_file_cameras_render():
    scene = raycast.load(ROOT / "fixtures" / "gltf" / "cameras.gltf")
    assert len(scene.cameras) >= 1
    image = scene.render(scene.cameras[0], 8, 8, aovs=["depth", "normal"])
    assert image["normal"].shape == (8, 8, 3)


def test_load_poses_gltf_animations_at_a_time():
    """``time=`` plays the glTF animations as ``--time`` does: the bounds are those of three.js's
    vertices at that time (fixtures/posed/three, made by tools/make_pose_fixtures.sh), and a
    pickled scene keeps its time."""
    import json

    path = ROOT / "fixtures" / "posed" / "SimpleSkin.gltf"
    reference = json.loads((ROOT / "fixtures/posed/three/SimpleSkin.gltf.t0.65.json").read_text())
    points = np.concatenate(
        [np.reshape(p["positions"], (-1, 3)) for n in reference["nodes"] for p in n["primitives"]]
    )
    expected = np.array([points.min(axis=0), points.max(axis=0)])
    posed = raycast.load(path, time=0.65)
    assert np.allclose(posed.bounds, expected, rtol=0, atol=1e-12)
    assert not np.allclose(raycast.load(path).bounds, expected, rtol=0, atol=1e-3)
    assert np.array_equal(pickle.loads(pickle.dumps(posed)).bounds, posed.bounds)
    assert np.array_equal(raycast.load(path, time=0.65, animation=0).bounds, posed.bounds)
    with pytest.raises(ValueError, match="animation needs a time"):
        raycast.load(path, animation=0)
    with pytest.raises(raycast.SceneError, match="no animation 'run'"):
        raycast.load(path, time=1.0, animation="run")


def test_load_reads_usd_at_a_time_code_and_with_variants():
    """``time=`` reads a USD stage at a time code and ``variants=`` selects variants, as
    ``--time`` and ``--variant`` do: the bounds of the meshes are those of usd-core's world
    points (fixtures/usd/posed/*.reference.json, tools/make_usd_pose_fixtures.sh), and a pickled
    scene keeps both."""
    import json

    folder = ROOT / "fixtures" / "usd" / "posed"
    timed = json.loads((folder / "time_samples.reference.json").read_text())
    case = next(c for c in timed["cases"] if c["time"] == 30.5)
    scene = raycast.load(folder / "time_samples.usda", time=30.5)
    deform = next(o for o in scene.objects if o["name"] == "/World/Deform")
    points = np.reshape(case["meshes"][0]["points"], (-1, 3))
    assert case["meshes"][0]["path"] == "/World/Deform"
    assert np.allclose(
        deform["bounds"],
        [points.min(axis=0), points.max(axis=0)],
        rtol=0,
        atol=1e-12,
    )
    assert np.array_equal(pickle.loads(pickle.dumps(scene)).bounds, scene.bounds)

    chosen = json.loads((folder / "variants.reference.json").read_text())["cases"][3]
    assert chosen["variants"] == {"shape": "tri", "detail": "high"}
    tri = raycast.load(folder / "variants.usda", variants=chosen["variants"])
    points = np.reshape(chosen["meshes"][0]["points"], (-1, 3))
    assert np.allclose(tri.bounds, [points.min(axis=0), points.max(axis=0)], rtol=0, atol=1e-12)
    again = pickle.loads(pickle.dumps(tri))
    assert [o["name"] for o in again.objects] == ["/World/Thing/Tri"]
    with pytest.raises(raycast.SceneError, match="choices: ball, box, tri"):
        raycast.load(folder / "variants.usda", variants={"shape": "cone"})


def test_scene_from_arrays_equals_the_same_mesh_read_from_a_file(tmp_path):
    """`Scene.from_arrays` (issue 33): the hits of the same triangles written as an OBJ file
    and loaded, bit for bit; it pickles as its arrays; bad arrays are ValueErrors naming the
    first bad vertex or face."""
    rng = np.random.default_rng(7)
    vertices = rng.uniform(-1, 1, (60, 3))
    faces = rng.integers(0, 60, (40, 3))
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist())
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces.tolist())
    (tmp_path / "m.obj").write_text(text)
    from_file = raycast.load(tmp_path / "m.obj")
    scene = raycast.Scene.from_arrays(vertices, faces)
    o = rng.uniform(-2, 2, (500, 3))
    d = rng.uniform(-1, 1, (500, 3))
    a = scene.cast(o, d, aovs=("t", "prim", "normal"))
    b = from_file.cast(o, d, aovs=("t", "prim", "normal"))
    assert (np.isfinite(a["t"])).sum() > 50
    for key in a:
        assert np.array_equal(a[key], b[key]), key
    again = pickle.loads(pickle.dumps(scene))
    assert np.array_equal(again.cast(o, d, aovs=("t",))["t"], a["t"])
    assert "from arrays" in repr(scene)
    with pytest.raises(ValueError, match=r"face 1 is \[0, 1, 60\]"):
        raycast.Scene.from_arrays(vertices, [[0, 1, 2], [0, 1, 60]])
    with pytest.raises(ValueError, match="vertex 2 is not finite"):
        raycast.Scene.from_arrays([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], [[0, 1, 2]])
    with pytest.raises(ValueError, match="faces must be integers"):
        raycast.Scene.from_arrays(vertices, [[0.0, 1.0, 2.0]])
