"""`raycast SCENE --cryptomatte --spp N` read by a Cryptomatte decoder written here from the
specification (v1.2.0), with `mmh3` (PyPI) for MurmurHash3 and OpenEXR's Python reader: the
manifest names every object with its hash, each id decodes to an object, coverage is the
share of the pixel's stratified samples, traced here from the sidecar's camera in numpy.

Run: .venv/bin/python -m pytest tests/python/test_cryptomatte.py
"""

import json
import subprocess

import mmh3
import numpy as np
import OpenEXR
from binary import RAYCAST, ROOT, needs_binary
from test_attributes import expected_gltf_materials

import raycast

SCENE = ROOT / "fixtures" / "gltf" / "instances.gltf"
W, H, SIDE = 48, 36, 4


def float_id(name: str) -> np.float32:
    """The specification's id of a name: MurmurHash3_32's bits as a float32, the exponent
    kept within 1..254."""
    h = mmh3.hash(name.encode(), 0, signed=False)
    exponent = min(max((h >> 23) & 0xFF, 1), 254)
    return np.array([(h & 0x807FFFFF) | (exponent << 23)], dtype=np.uint32).view(np.float32)[0]


def decode(path, layer="CryptoObject"):
    """The manifest (name -> float id) and the rank layers [(ids, coverage), ...] of the
    layer named `layer` (CryptoObject, CryptoMaterial)."""
    exr = OpenEXR.File(str(path))
    header = exr.header()
    key = f"{mmh3.hash(layer.encode(), 0, signed=False):08x}"[:7]
    assert header[f"cryptomatte/{key}/name"] == layer
    assert header[f"cryptomatte/{key}/hash"] == "MurmurHash3_32"
    assert header[f"cryptomatte/{key}/conversion"] == "uint32_to_float32"
    manifest = json.loads(header[f"cryptomatte/{key}/manifest"])
    for name, hex_hash in manifest.items():
        assert int(hex_hash, 16) == mmh3.hash(name.encode(), 0, signed=False)
    ranks = []
    channels = exr.channels()
    for level in range(3):
        rgba = channels[f"{layer}{level:02d}"].pixels
        ranks += [(rgba[..., 0], rgba[..., 1]), (rgba[..., 2], rgba[..., 3])]
    return {name: float_id(name) for name in manifest}, ranks


def sample_rays(camera):
    """The SIDE x SIDE grid of rays over each pixel, per pixel in row-major order."""
    m = np.asarray(camera["camera_to_world"])
    tan = np.tan(camera["yfov"] / 2)
    offsets = (np.arange(SIDE) + 0.5) / SIDE
    oy, ox = np.meshgrid(offsets, offsets, indexing="ij")
    rows, cols = np.meshgrid(np.arange(H), np.arange(W), indexing="ij")
    x = (cols[..., None] + ox.reshape(-1)).reshape(-1)
    y = (rows[..., None] + oy.reshape(-1)).reshape(-1)
    local = np.stack([(2 * x / W - 1) * tan * W / H, (1 - 2 * y / H) * tan, -np.ones_like(x)], 1)
    return np.broadcast_to(m[:3, 3], local.shape), local @ m[:3, :3].T


@needs_binary
def test_cryptomatte_decodes_to_the_objects_and_their_coverage(tmp_path):
    out = tmp_path / "out"
    command = [
        RAYCAST,
        SCENE,
        "--width",
        str(W),
        "--height",
        str(H),
        "--aov",
        "id",
        "--format",
        "npy",
    ]
    spp = str(SIDE * SIDE)
    subprocess.run([*command, "--cryptomatte", "--spp", spp, "--out", out, "-q"], check=True)
    sidecar = json.loads((out / "raycast.json").read_text())
    names = [o["name"] for o in sidecar["objects"]]
    manifest, ranks = decode(out / "cryptomatte.exr")
    assert sorted(manifest) == sorted(names)  # the instances' names are all different
    by_id = {float(v): name for name, v in manifest.items()}
    # The expected coverage, from the samples traced with the package's cast.
    origins, directions = sample_rays(sidecar["camera"])
    hit = raycast.load(SCENE).cast(origins, directions, aovs=("id",))["id"].reshape(H, W, -1)
    total = np.zeros((H, W))
    for ids, coverage in ranks:
        total += coverage
        for r, c in zip(*np.nonzero(coverage)):
            name = by_id[float(ids[r, c])]
            expected = (hit[r, c] == names.index(name) + 1).mean()
            assert coverage[r, c] == np.float32(expected), (r, c, name)
    assert np.allclose(total, (hit[..., :] != 0).mean(axis=2), atol=1e-6)
    # Rank 0 is the object covering most of the pixel: the centre ray's where it covers all.
    centre = np.load(out / "id.npy")
    full = ranks[0][1] == 1.0
    assert full.sum() > 100
    decoded = np.array([names.index(by_id[float(v)]) + 1 for v in ranks[0][0][full]])
    assert (decoded == centre[full]).all()
    assert (total[centre == 0] < 1).all()


@needs_binary
def test_material_layer_decodes_to_the_materials_and_their_coverage(tmp_path):
    """The CryptoMaterial layer of a scene whose every triangle has a material: each id
    decodes to a material of the manifest, which lists every material; the coverage is the
    share of samples on that material (from the glTF's own primitive materials, by object
    and triangle) and sums to 1 where every sample hits."""
    scene_path = ROOT / "fixtures" / "attributes" / "textured.gltf"
    out = tmp_path / "out"
    size = ["--width", str(W), "--height", str(H), "--eye", "1.5,1.5,8", "--target", "1.5,1.5,0"]
    spp = str(SIDE * SIDE)
    subprocess.run(
        [
            RAYCAST,
            scene_path,
            *size,
            "--aov",
            "id",
            "--cryptomatte",
            "--spp",
            spp,
            "--out",
            out,
            "-q",
        ],
        check=True,
    )
    sidecar = json.loads((out / "raycast.json").read_text())
    doc = json.loads(scene_path.read_text())
    names = [m.get("name", f"material{i}") for i, m in enumerate(doc["materials"])]
    assert sidecar["materials"] == names
    manifest, ranks = decode(out / "cryptomatte.exr", "CryptoMaterial")
    assert sorted(manifest) == sorted(names)
    by_id = {float(v): name for name, v in manifest.items()}
    per_object = expected_gltf_materials()  # each node's triangles' materials, from the JSON
    objects = [o["name"] for o in sidecar["objects"]]
    origins, directions = sample_rays(sidecar["camera"])
    hits = raycast.load(scene_path).cast(origins, directions, aovs=("id", "prim"))
    material = np.array(
        [per_object[objects[i - 1]][p] if i else "" for i, p in zip(hits["id"], hits["prim"])]
    ).reshape(H, W, -1)
    total = np.zeros((H, W))
    for ids, coverage in ranks:
        total += coverage
        for r, c in zip(*np.nonzero(coverage)):
            name = by_id[float(ids[r, c])]
            assert coverage[r, c] == np.float32((material[r, c] == name).mean()), (r, c, name)
    all_hit = (material != "").all(axis=2)
    assert all_hit.sum() > 100 and (material == "").any()
    assert np.allclose(total[all_hit], 1, atol=1e-6)
    assert np.allclose(total, (material != "").mean(axis=2), atol=1e-6)
    assert len({by_id[float(v)] for v in ranks[0][0][all_hit]}) == 2
