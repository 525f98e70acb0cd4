"""`raycast SCENE --views transforms.json` against nerfstudio's camera conventions written
out here in numpy (pixel (i, j) looks along c2w[:3, :3] @ ((i + 0.5 - cx) / fx,
-(j + 0.5 - cy) / fy, -1), OpenGL axes), with trimesh's float64 ray-triangle test as the
intersection reference, and against the Python package's `camera.pinhole` (the same rays, bit
for bit, in OpenCV's axes).

Run: .venv/bin/python -m pytest tests/python/test_views.py
"""

import json
import subprocess

import numpy as np
import pytest
import trimesh
from binary import RAYCAST, ROOT, needs_binary
from trimesh.ray.ray_triangle import RayMeshIntersector

import raycast

SCENE = ROOT / "fixtures" / "gltf" / "cube.gltf"


def look_at(eye, target):
    """Camera-to-world in OpenGL axes (+Y up, looking down -Z) at `eye` looking at `target`."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    back = (eye - target) / np.linalg.norm(eye - target)
    right = np.cross([0.0, 1.0, 0.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, back, eye
    return m


FRAMES = [
    {
        "file_path": "images/frame_00001.png",
        "transform_matrix": look_at([2.5, 1.5, 4.0], [0, 0, 0]),
    },
    {
        "file_path": "images/frame_00002.png",
        "transform_matrix": look_at([-3.0, -1.0, 2.0], [0.2, 0.1, 0]),
        "fl_x": 30.0,
        "fl_y": 33.0,
        "cx": 18.5,
        "cy": 13.0,
    },
]
INTRINSICS = {"fl_x": 40.0, "fl_y": 40.0, "cx": 20.0, "cy": 15.0, "w": 40, "h": 30}


def nerfstudio_rays(frame):
    """Origins and directions of a frame's pixels as nerfstudio makes them (row-major)."""
    k = {**INTRINSICS, **{key: v for key, v in frame.items() if key in INTRINSICS}}
    c2w = np.asarray(frame["transform_matrix"])
    j, i = np.meshgrid(np.arange(k["h"]) + 0.5, np.arange(k["w"]) + 0.5, indexing="ij")
    local = np.stack([(i - k["cx"]) / k["fl_x"], -(j - k["cy"]) / k["fl_y"], -np.ones_like(i)], -1)
    directions = local.reshape(-1, 3) @ c2w[:3, :3].T
    origins = np.broadcast_to(c2w[:3, 3], directions.shape)
    return origins, directions, (k["h"], k["w"])


def render_views(tmp_path):
    views = tmp_path / "transforms.json"
    frames = [{**f, "transform_matrix": np.asarray(f["transform_matrix"]).tolist()} for f in FRAMES]
    views.write_text(json.dumps({**INTRINSICS, "camera_model": "OPENCV", "frames": frames}))
    out = tmp_path / "out"
    subprocess.run(
        [
            RAYCAST,
            SCENE,
            "--views",
            views,
            "--aov",
            "depth,z,id",
            "--format",
            "npy",
            "--out",
            out,
            "-q",
        ],
        check=True,
    )
    return out


@needs_binary
def test_views_agree_with_nerfstudio_rays_and_trimesh(tmp_path):
    out = render_views(tmp_path)
    mesh = trimesh.load(SCENE, force="mesh")
    for index, frame in enumerate(FRAMES):
        folder = out / f"{index:04d}-frame_{index + 1:05d}"
        depth = np.load(folder / "depth.npy")
        origins, directions, shape = nerfstudio_rays(frame)
        assert depth.shape == shape
        locations, rays, _ = RayMeshIntersector(mesh).intersects_location(
            origins, directions, multiple_hits=True
        )
        expected = np.full(len(directions), np.inf)
        distances = np.linalg.norm(locations - origins[rays], axis=1)
        np.minimum.at(expected, rays, distances)
        ours = depth.reshape(-1)
        both = np.isfinite(expected) & np.isfinite(ours)
        # Hit/miss may differ only for rays that graze an edge, where float64 tests disagree.
        assert (np.isfinite(expected) != np.isfinite(ours)).sum() <= 2
        assert both.sum() > 300
        assert np.allclose(ours[both], expected[both], rtol=1e-9, atol=0)


@needs_binary
def test_views_equal_the_python_pinhole_bit_for_bit(tmp_path):
    out = render_views(tmp_path)
    scene = raycast.load(SCENE)
    for index, frame in enumerate(FRAMES):
        k = {**INTRINSICS, **{key: v for key, v in frame.items() if key in INTRINSICS}}
        K = [[k["fl_x"], 0, k["cx"]], [0, k["fl_y"], k["cy"]], [0, 0, 1]]
        # OpenCV's camera-to-world from OpenGL's: Y and Z columns negated.
        cv = np.asarray(frame["transform_matrix"]) @ np.diag([1.0, -1.0, -1.0, 1.0])
        camera = raycast.camera.pinhole(K, cv, k["w"], k["h"])
        image = scene.render(camera, k["w"], k["h"], aovs=["depth", "z", "id"])
        folder = out / f"{index:04d}-frame_{index + 1:05d}"
        for aov in ("depth", "z", "id"):
            assert np.array_equal(image[aov], np.load(folder / f"{aov}.npy")), aov
        assert np.array_equal(np.asarray(camera.cam_to_world), cv)


@needs_binary
def test_16_bit_depth_reads_back_in_pillow(tmp_path):
    """`--depth-scale 0.001` writes z.png as millimetres (a scene in metres), read by Pillow
    (an independent PNG decoder) as 16-bit grey: within half a millimetre of z.npy, 0 where
    nothing is hit."""
    from PIL import Image

    views = tmp_path / "transforms.json"
    frame = {**FRAMES[0], "transform_matrix": np.asarray(FRAMES[0]["transform_matrix"]).tolist()}
    views.write_text(json.dumps({**INTRINSICS, "frames": [frame]}))
    out = tmp_path / "out"
    command = [RAYCAST, SCENE, "--views", views, "--aov", "z", "--format", "npy,png"]
    subprocess.run([*command, "--depth-scale", "0.001", "--out", out, "-q"], check=True)
    folder = out / "0000-frame_00001"
    image = Image.open(folder / "z.png")
    assert image.mode in ("I;16", "I;16B", "I")
    mm = np.asarray(image, dtype=np.int64)
    z = np.load(folder / "z.npy")
    hit = np.isfinite(z)
    assert hit.sum() > 300 and (~hit).sum() > 100
    assert (mm[~hit] == 0).all()
    assert np.abs(mm[hit] * 0.001 - z[hit]).max() <= 0.0005 + 1e-12
    assert json.loads((folder / "raycast.json").read_text())["depth_png_scale"] == 0.001


@needs_binary
def test_python_reads_the_views_file_as_the_command_line(tmp_path):
    """`camera.read_views` and `Scene.render_views` give the command line's folders bit for
    bit; a bad frame is an error naming it."""
    out = render_views(tmp_path)
    views = raycast.camera.read_views(tmp_path / "transforms.json")
    assert [name for name, _ in views] == ["frame_00001", "frame_00002"]
    assert views[1][1].size == (40, 30)
    scene = raycast.load(SCENE)
    rendered = list(scene.render_views(views, aovs=("depth", "z", "id")))
    for index, (name, images) in enumerate(rendered):
        folder = out / f"{index:04d}-{name}"
        for aov in ("depth", "z", "id"):
            assert np.array_equal(images[aov], np.load(folder / f"{aov}.npy")), (name, aov)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"fl_x": 10, "frames": [{"file_path": "x.png"}]}))
    with pytest.raises(raycast.SceneError, match=r"frames\[0\] \('x.png'\)"):
        raycast.camera.read_views(bad, 8, 8)


@needs_binary
def test_point_clouds_read_in_trimesh(tmp_path):
    """`--format ply`: trimesh's PLY reader (independent of raycast's writer) gives the hit
    positions of position.npy, in ray order, and the ids as a vertex attribute."""
    out = tmp_path / "out"
    command = [RAYCAST, SCENE, "--width", "32", "--height", "24", "--format", "ply,npy"]
    subprocess.run([*command, "--aov", "position,id", "--out", out, "-q"], check=True)
    cloud = trimesh.load(out / "position.ply")
    positions = np.load(out / "position.npy").reshape(-1, 3)
    ids = np.load(out / "id.npy").reshape(-1)
    hit = ids != 0
    assert np.array_equal(np.asarray(cloud.vertices), positions[hit])
    attributes = cloud.metadata["_ply_raw"]["vertex"]["data"]
    assert np.array_equal(attributes["id"], ids[hit])
    assert np.array_equal(attributes["ray"], np.flatnonzero(hit))
