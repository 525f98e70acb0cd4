"""Validate raycast against independent references.

    python -m raycast_tools validate SCENE_OR_DIR... [--rays N] [--seed S] [--json] [--raycast PATH]
                                   [--max-rays-f64 N] [--camera] [--keep DIR]

For each scene (.gltf/.glb/.obj/.ply/.stl; directories are searched recursively; files in a
`bad/` and `fuzz/` folders, files trimesh cannot load and files trimesh is known to load wrongly
are skipped with a stated reason) this generates N deterministic rays, runs
`raycast SCENE --rays rays.npy --aov depth,normal,id,prim --out TMP --quiet` and
compares its depth, normal, id and prim per ray against

* trimesh 5.2.0's float64 `ray_triangle.RayMeshIntersector` (the precision
  reference, on the first --max-rays-f64 rays) and `ray_pyembree` (embreex, fast,
  float32 traversal; the reference for rays beyond --max-rays-f64), both on the
  scene's world-space triangles built in float64 from trimesh's scene graph;
* quadric_reference.py for glTF nodes carrying RAYCAST_quadric (trimesh
  does not see them), merged with the mesh hits by nearest depth.

Rays whose answer is not well defined are counted as ambiguous and left out of the
tolerance checks (they are reported, per reason): the two trimesh backends
disagree; the ray grazes a hit triangle (|cos| < 1e-5, which ray_triangle drops);
the hit point is within 1e-6 * scene size of a triangle edge; two hits on
different objects within 1e-6 relative depth; quadric tangent or clip-face hits.

`--camera` also renders the scene in camera mode (64x64, npy), rebuilds each pixel's
ray from the sidecar's `camera` block as docs/buffers-and-cli.md defines it, and
compares those the same way.

Exit status: 0 all compared scenes within tolerance, 1 a scene out of tolerance or
raycast failed, 2 usage error.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import struct
import tempfile
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from raycast_tools.cli import prog
from raycast_tools.paths import raycast_or_exit
from raycast_tools.rays import camera_rays, make_rays
from raycast_tools.reference import quadric_reference as qref
from raycast_tools.reference.cast import ray_triangle_hits, trace_embree
from raycast_tools.runner import run_raycast, run_rays
from raycast_tools.validate.metrics import angle, edge_distance, stats

warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"trimesh\.visual.*")

U32 = 2.0**-24  # unit roundoff of float32

# ---------------------------------------------------------------------------------
# Tolerances: the only place they are set.
TOL = {
    # Hit/miss must agree on >= 99.9% of non-ambiguous rays: rays through edges,
    # grazing rays and ties are already excluded, so a disagreement is a traversal
    # or intersection bug; the 0.1% leaves room for silhouette rays whose
    # f32-rounded vertices (raycast stores vertices as f32 relative to an anchor)
    # move an edge across the ray by more than the 1e-6*size edge band.
    "hitmiss_agreement": 0.999,
    # Relative depth error p99 <= 1e-6: raycast intersects in f64 on vertices rounded
    # to f32 relative to a scene anchor; trimesh works in f64 on the same f32 file
    # data transformed in f64.  A vertex moves by <= u32*|v - anchor| <= 6e-8*size,
    # which moves a hit along a ray by that / |cos|; with origins about one scene
    # size away and typical |cos| > 0.1 this is well below 1e-6 relative.
    "depth_rel_p99": 1e-6,
    # Max depth error, per ray: |depth - ref| <= K * u32 * size / |cos| + 1e-12*ref,
    # K = 8 (a vertex moves by <= sqrt(3)*u32*size in the f32 anchor-relative
    # storage, the plane through three such vertices by no more than the largest
    # move; 8 leaves a factor ~4 of headroom).  Grazing rays (|cos| < 1e-5) are
    # ambiguous and excluded, so this bound is at most 8e-5*size / depth relative;
    # a flat relative bound could not be both honest for grazing hits and tight
    # for head-on ones.  Reported as the max ratio error/bound, which must be <= 1.
    "depth_bound_k": 8.0,
    "depth_bound_ratio_max": 1.0,
    # Normal angle p99 <= 1e-5 rad: the normal of a triangle whose vertices moved by
    # u32*size turns by about u32*size/edge, 6e-8*size/edge; 1e-5 allows edges down
    # to ~1/200 of the scene size at p99.
    "normal_angle_p99": 1e-5,
    # Normals pointing the opposite way (angle > pi/2) are a winding/convention bug,
    # never rounding: none allowed on non-ambiguous rays.
    "normal_flipped_max": 0,
    # Object id and triangle index must agree on >= 99.9% of non-ambiguous rays that
    # both sides hit (edge and tie rays are ambiguous already).
    "id_agreement": 0.999,
    "prim_agreement": 0.999,
    # Quadrics: the reference is independent f64 object-space intersection with
    # stable roots and a Newton step (~1e-14 relative), raycast is f64 in object
    # space or about a local anchor; numerics.md measured 3e-15 for that method.
    # 1e-9 leaves 5 orders of magnitude for a less careful but correct method and
    # still catches world-space baking (6e-7 at distance 1e5).
    "quadric_depth_rel_max": 1e-9,
    # Quadric normals: gradient from the same exact coefficients; 1e-6 rad.
    "quadric_normal_angle_max": 1e-6,
    # Non-ambiguous quadric rays (tangent and clip-face rays excluded) must agree
    # exactly on hit/miss and object.
    "quadric_hitmiss_agreement": 1.0,
    "quadric_id_agreement": 1.0,
}

# Ambiguity thresholds (what the reference cannot decide), not tolerances.
AMBIG = {
    "backend_depth_rel": 1e-4,  # ray_triangle vs embree depth disagreement
    "graze_cos": 1e-5,  # ray_triangle drops |d.n| <= 1e-5 (unit d, n)
    "edge_rel": 1e-6,  # hit point to triangle edge, times scene size
    "tie_rel": 1e-6,  # two hits on different objects, relative depth
}

# glTF features trimesh 5.2.0 ignores or cannot decode (would give a wrong reference)
TRIMESH_BAD_EXTENSIONS = {
    "KHR_mesh_quantization": "trimesh ignores normalized (quantized) attributes",
    "KHR_draco_mesh_compression": "trimesh cannot decode Draco",
    "EXT_meshopt_compression": "trimesh cannot decode meshopt",
    "KHR_meshopt_compression": "trimesh cannot decode meshopt",
}

SCENE_EXTS = {".gltf", ".glb", ".obj", ".ply", ".stl"}


# ------------------------------------------------------------------ scene discovery


def poses(path: Path) -> bool:
    """Whether a glTF or GLB has skins or morph targets (what raycast poses and trimesh does
    not); False for other files and for files whose JSON cannot be read."""
    if path.suffix.lower() not in (".gltf", ".glb"):
        return False
    try:
        data = path.read_bytes()
        if data[:4] == b"glTF":
            length = int.from_bytes(data[12:16], "little")
            data = data[20 : 20 + length]
        doc = json.loads(data)
    except (OSError, ValueError):
        return False
    try:
        meshes = doc.get("meshes", [])
        morphed = any(prim.get("targets") for mesh in meshes for prim in mesh.get("primitives", []))
        return bool(doc.get("skins")) or morphed
    except (AttributeError, TypeError):  # not a glTF document's shape: let the run say so
        return False


def find_scenes(paths):
    """[(path, skip_reason or None)] in a stable order."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            files = sorted(f for f in p.rglob("*") if f.suffix.lower() in SCENE_EXTS)
        else:
            files = [p]
        for f in files:
            if "bad" in f.parts[:-1]:
                out.append((f, "in a bad/ folder (expected to fail)"))
            elif {"fuzz", "fuzz-hang"} & set(f.parts[:-1]):
                # Inputs that once crashed a reader; tests/it/check.rs and tests/it/cli_messages.rs
                # hold what raycast must say about them.
                out.append((f, "in a fuzz/ folder (a fuzzing regression input)"))
            elif "posed" in f.parts[:-1]:
                # trimesh draws neither skins nor morph targets; three.js is the reference
                # for these (tests/it/gltf_pose.rs, fixtures/posed/three).
                out.append((f, "in a posed/ folder (three.js is its reference: gltf_pose.rs)"))
            elif poses(f):
                out.append((f, "skinned or morphed (trimesh poses neither; see gltf_pose.rs)"))
            elif f.suffix.lower() not in SCENE_EXTS:
                out.append((f, "not a .gltf/.glb/.obj/.ply/.stl file"))
            else:
                out.append((f, None))
    return out


def gltf_precheck(header: dict) -> str | None:
    """Reason trimesh would load this glTF wrongly, or None."""
    used = set(header.get("extensionsUsed", [])) | set(header.get("extensionsRequired", []))
    for ext, why in TRIMESH_BAD_EXTENSIONS.items():
        if ext in used:
            return f"{ext}: {why}"
    for i, a in enumerate(header.get("accessors", [])):
        if "sparse" in a:
            return f"accessor {i} is sparse: trimesh ignores sparse accessors"
    for m in header.get("meshes", []):
        for p in m.get("primitives", []):
            if p.get("mode", 4) == 6:
                return "TRIANGLE_FAN primitive: trimesh does not load fans"
            pos = p.get("attributes", {}).get("POSITION")
            if pos is not None and pos < len(header.get("accessors", [])):
                acc = header["accessors"][pos]
                if acc.get("normalized") or acc.get("componentType", 5126) != 5126:
                    return "quantized POSITION accessor: trimesh ignores normalization"
    if header.get("nodes") and not header.get("scenes"):
        return "no scenes: trimesh loads no nodes without a scene"
    return None


# ------------------------------------------------------------------ reference scene


@dataclass
class RefObject:
    key: str  # "/nodes/3" or "obj:name"
    name: str
    node: int  # glTF node index, -1 for OBJ
    tris: np.ndarray  # (n, 3, 3) float64 world
    flip: bool  # transform with negative determinant: front face is clockwise


@dataclass
class RefScene:
    path: Path
    objects: list
    tris: np.ndarray = field(init=False)  # (T,3,3) all world triangles
    tri_obj: np.ndarray = field(init=False)  # (T,) object index
    tri_local: np.ndarray = field(init=False)  # (T,) index inside object
    offsets: np.ndarray = field(init=False)
    normals: np.ndarray = field(init=False)  # (T,3) front-face unit normal (0 if degenerate)
    quadrics: list = field(default_factory=list)
    # Whether each object's triangles are in raycast's prim order (not for a PLY with polygons:
    # trimesh splits its quads apart from its triangles, raycast fans each face in file order).
    prim_order: bool = True
    header: dict | None = None
    notes: list = field(default_factory=list)

    def finish(self):
        counts = [len(o.tris) for o in self.objects]
        self.offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        self.tris = (
            np.concatenate([o.tris for o in self.objects]) if self.objects else np.zeros((0, 3, 3))
        )
        self.tri_obj = np.repeat(np.arange(len(self.objects)), counts).astype(np.int64)
        self.tri_local = (
            np.concatenate([np.arange(c) for c in counts]).astype(np.int64)
            if counts
            else np.zeros(0, np.int64)
        )
        t = self.tris
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        ln = np.linalg.norm(n, axis=1)
        good = ln > 0
        n[good] /= ln[good, None]
        n[~good] = 0
        flip = np.repeat([o.flip for o in self.objects], counts).astype(bool)
        n[flip] *= -1
        self.normals = n

    def bounds(self):
        pts = [self.tris.reshape(-1, 3)] if len(self.tris) else []
        for q in self.quadrics:
            wb = q.world_bounds()
            if wb is not None:
                pts.append(np.array(wb))
        if not pts:
            return None
        p = np.concatenate(pts)
        return p.min(axis=0), p.max(axis=0)


def _trimesh_node_names(header):
    """glTF node index -> trimesh frame name, reproducing trimesh 5.2.0's naming.

    trimesh names a frame after the node's `name`, or str(index) when unnamed, made
    unique with trimesh.util.unique_name in node order (so duplicate names become
    "name_1", ...), and renames a node called "world" (its base frame).  Calling
    the same function in the same order reproduces the names exactly.  Nodes whose
    mesh has several primitives get one child frame per primitive named
    "<frame>_<random 6 chars>": those are matched through their parent frame.
    """
    import trimesh
    from trimesh.util import unique_name

    base = getattr(trimesh.constants, "DEFAULT_BASE_FRAME", None) or "world"
    name_index, counts = {}, {}
    for i, n in enumerate(header.get("nodes", [])):
        name_index[unique_name(n.get("name", str(i)), name_index, counts=counts)] = i
    names = {v: k for k, v in name_index.items()}
    w = name_index.get(base)
    if w is not None:
        names[w] = unique_name(base, set(names.values()))
    return names


# Compression trimesh cannot decode: a file using one is checked against the reference decode
# next to it (`<stem>.plain.glb`, written by glTF-Transform with the official decoders; see
# tools/make_compressed_fixtures.sh), when there is one.
COMPRESSION = ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression")
INSTANCING = "EXT_mesh_gpu_instancing"


def _accessor(path: Path, header: dict, index: int) -> np.ndarray:
    """An uncompressed accessor as float64 rows, normalized integers divided out (glTF 2.0
    3.11: max(c / (2^(b-1) - 1), -1) for signed, c / (2^b - 1) for unsigned types)."""
    a = header["accessors"][index]
    types = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
    dtype = np.dtype(types[a["componentType"]])
    comps = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[a["type"]]
    view = header["bufferViews"][a["bufferView"]]
    buffer = header["buffers"][view["buffer"]]
    data = path.read_bytes()
    if "uri" in buffer:
        blob = (path.parent / buffer["uri"]).read_bytes()
    else:  # GLB: the BIN chunk after the JSON chunk
        (json_len,) = struct.unpack_from("<I", data, 12)
        (bin_len,) = struct.unpack_from("<I", data, 20 + json_len)
        blob = data[28 + json_len : 28 + json_len + bin_len]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * comps)
    rows = np.stack(
        [np.frombuffer(blob, dtype, comps, start + i * stride) for i in range(a["count"])]
    ).astype(np.float64)
    if a.get("normalized"):
        top = float(np.iinfo(dtype).max)
        rows = np.maximum(rows / top, -1.0)
    return rows


def _instance_matrices(path: Path, header: dict, ext: dict) -> list:
    """EXT_mesh_gpu_instancing: one T * R * S matrix per instance (node space)."""
    attrs = ext["attributes"]
    got = {k: _accessor(path, header, i) for k, i in attrs.items()}
    count = len(next(iter(got.values())))
    out = []
    for i in range(count):
        m = np.eye(4)
        r = qref._quat_matrix(got["ROTATION"][i]) if "ROTATION" in got else np.eye(3)
        s = got["SCALE"][i] if "SCALE" in got else np.ones(3)
        m[:3, :3] = r * s[None, :]
        if "TRANSLATION" in got:
            m[:3, 3] = got["TRANSLATION"][i]
        out.append(m)
    return out


def _expand_instances(path: Path, header: dict, per_node: dict):
    """Replaces each instanced node's single trimesh placement (trimesh ignores the
    extension) with one `<node name>[i]` part per instance: world = node world * instance."""
    instanced = {}
    for node, parts in list(per_node.items()):
        if node < 0:
            continue
        ext = header["nodes"][node].get("extensions", {}).get(INSTANCING)
        if ext is None:
            continue
        world = parts[0][4]
        to_node = np.linalg.inv(world)
        tris = np.concatenate([p[1] for p in sorted(parts, key=lambda x: x[0])])
        local = tris @ to_node[:3, :3].T + to_node[:3, 3]
        name = qref.node_name(header, node)
        for i, m in enumerate(_instance_matrices(path, header, ext)):
            w = world @ m
            placed = local @ w[:3, :3].T + w[:3, 3]
            flip = bool(np.linalg.det(w[:3, :3]) < 0)
            instanced[(node, i)] = (f"{name}[{i}]", placed, flip)
        del per_node[node]
    return instanced


def load_reference(path: Path) -> RefScene:
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".obj":
        return _load_obj(path)
    if suffix in (".ply", ".stl"):
        return _load_mesh_file(path)
    header = qref.load_gltf_json(path)
    used = set(header.get("extensionsUsed", []))
    plain = path.with_name(path.stem + ".plain.glb")
    if used & set(COMPRESSION) and plain.is_file():
        ref = load_reference(plain)
        ref.notes.append(f"reference: {plain.name} (glTF-Transform with the official decoders)")
        return ref
    return _load_gltf(path, header)


def _load_gltf(path: Path, header: dict) -> RefScene:
    import trimesh

    reason = gltf_precheck(header)
    if reason:
        raise SkipScene(reason)
    scene = trimesh.load(str(path), force="scene")
    names = _trimesh_node_names(header)
    frame_to_node = {v: k for k, v in names.items()}
    parents = scene.graph.transforms.parents
    geom_order = {g: i for i, g in enumerate(scene.geometry.keys())}
    per_node = {}  # node index -> list of (prim order, world tris)
    notes = []
    unmatched = 0
    for frame in scene.graph.nodes_geometry:
        T, gname = scene.graph[frame]
        geom = scene.geometry[gname]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        if frame in frame_to_node:
            node, order = frame_to_node[frame], 0
        elif parents.get(frame) in frame_to_node:
            node, order = frame_to_node[parents[frame]], geom_order.get(gname, 0)
        else:
            unmatched += 1
            node, order = -1 - unmatched, 0
        v = np.asarray(geom.vertices, dtype=np.float64)
        tris = v[np.asarray(geom.faces)]
        T = np.asarray(T, dtype=np.float64)
        tris = tris @ T[:3, :3].T + T[:3, 3]
        flip = bool(np.linalg.det(T[:3, :3]) < 0)
        per_node.setdefault(node, []).append((order, tris, flip, frame, T))
    if unmatched:
        notes.append(f"{unmatched} trimesh frames not matched to a glTF node")
    instanced = _expand_instances(path, header, per_node)
    objects = []
    for node in sorted(per_node):
        parts = sorted(per_node[node], key=lambda x: x[0])
        tris = np.concatenate([p[1] for p in parts])
        if node >= 0:
            key, name = f"/nodes/{node}", qref.node_name(header, node)
        else:
            key, name = f"trimesh:{parts[0][3]}", parts[0][3]
        objects.append(RefObject(key, name, node, tris, parts[0][2]))
    for (node, i), (name, tris, flip) in sorted(instanced.items()):
        key = f"/nodes/{node}/extensions/{INSTANCING}/{i}"  # raycast's source pointer
        objects.append(RefObject(key, name, node, tris, flip))
    ref = RefScene(path, objects, header=header, notes=notes)
    try:
        ref.quadrics = qref.quadrics_from_header(header)
    except Exception as e:  # malformed extension: report, do not guess
        raise SkipScene(f"RAYCAST_quadric not readable: {e}")
    ref.finish()
    return ref


def _load_obj(path: Path) -> RefScene:
    """OBJ through trimesh, one object per `o`/`g` name, faces in file order.

    trimesh's default OBJ load merges objects by material and reorders faces, so
    split_objects/split_groups, group_material=False and maintain_order=True are
    used; objects are named as trimesh names them, which are the OBJ names (made
    unique).  Object matching to raycast falls back to order and triangle counts.
    """
    import trimesh

    scene = trimesh.load(
        str(path),
        force="scene",
        split_objects=True,
        split_groups=True,
        group_material=False,
        maintain_order=True,
        process=False,
    )
    objects = [
        RefObject(f"obj:{gname}", str(gname), -1, tris, False)
        for gname, tris in _scene_triangles(scene)
    ]
    ref = RefScene(path, objects)
    ref.finish()
    return ref


def _scene_triangles(scene):
    """(geometry name, world triangles as float64 (n, 3, 3)) of each trimesh mesh with faces
    in a trimesh scene, placed by its node's transform."""
    import trimesh

    for frame in scene.graph.nodes_geometry:
        T, gname = scene.graph[frame]
        geom = scene.geometry[gname]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        v = np.asarray(geom.vertices, dtype=np.float64)
        yield gname, v[np.asarray(geom.faces)] @ np.asarray(T)[:3, :3].T + np.asarray(T)[:3, 3]


def _ply_face_count(path: Path) -> int | None:
    """The count of a PLY header's `face` element (None when it has none)."""
    with open(path, "rb") as f:
        for raw in f:
            words = raw.decode("ascii", "replace").split()
            if words[:2] == ["element", "face"] and len(words) == 3:
                return int(words[2])
            if words == ["end_header"]:
                return None
    return None


def _load_mesh_file(path: Path) -> RefScene:
    """PLY and STL through trimesh's readers (process=False: vertices and faces as read):
    one object per mesh, keyed as raycast's source (`ply:<file stem>`, `stl:<solid name>` or
    `stl:<file stem>` for a binary or unnamed solid)."""
    import trimesh

    kind = path.suffix.lower()[1:]
    scene = trimesh.load(str(path), force="scene", process=False)
    objects = []
    for gname, tris in _scene_triangles(scene):
        name = Path(str(gname)).stem if str(gname).lower().endswith(f".{kind}") else str(gname)
        objects.append(RefObject(f"{kind}:{name}", name, -1, tris, False))
    ref = RefScene(path, objects)
    if kind == "ply":
        faces = _ply_face_count(path)
        ref.prim_order = faces is None or faces == sum(len(o.tris) for o in objects)
    if not ref.prim_order:
        ref.notes.append("prims not compared: trimesh orders a PLY's polygons apart")
    ref.finish()
    return ref


class SkipScene(Exception):
    pass


# ------------------------------------------------------------------ rays

# ------------------------------------------------------------------ references


def trace_f64(ref: RefScene, origins, unit, chunk=32):
    """ray_triangle (float64) with all hits kept, so ties can be found.

    Returns depth (inf miss), tri (-1), tie (bool): a hit on another object within
    tie_rel of the nearest.  The nearest hit is the one multiple_hits=False would
    return (both take the smallest distance along the ray).
    """
    n = len(origins)
    depth = np.full(n, np.inf)
    tri = np.full(n, -1, dtype=np.int64)
    tie = np.zeros(n, dtype=bool)
    if len(ref.tris) == 0:
        return depth, tri, tie
    for s, it, ir, dist, first in ray_triangle_hits(ref.tris, origins, unit, chunk):
        for k, f0 in enumerate(first):
            end = first[k + 1] if k + 1 < len(first) else len(ir)
            r = s + ir[f0]
            depth[r] = dist[f0]
            tri[r] = it[f0]
            obj0 = ref.tri_obj[it[f0]]
            for g in range(f0 + 1, end):
                if dist[g] - dist[f0] > AMBIG["tie_rel"] * dist[f0]:
                    break
                if ref.tri_obj[it[g]] != obj0:
                    tie[r] = True
                    break
    return depth, tri, tie


# ------------------------------------------------------------------ raycast


def map_objects(ref: RefScene, sidecar_objects):
    """raycast object id (1-based) -> reference object index (-1 unknown).

    glTF: by the sidecar's `source` JSON pointer (/nodes/i), which is independent of
    names (trimesh renames duplicate and unnamed nodes and multi-primitive frames);
    then by name; last by order among objects with equal triangle counts.
    Returns (array, {method: count}, [triangle count mismatches]).
    """
    by_key = {o.key: k for k, o in enumerate(ref.objects)}
    by_name = {}
    for k, o in enumerate(ref.objects):
        by_name.setdefault(o.name, []).append(k)
    m = np.full(len(sidecar_objects) + 1, -1, dtype=np.int64)
    used = set()
    how = {"source": 0, "name": 0, "order": 0, "unmatched": 0}
    rest = []
    for so in sidecar_objects:
        oid = int(so["id"])
        if so.get("kind") == "quadric" and not so.get("triangles"):
            continue
        src = so.get("source", "")
        k = by_key.get(src)
        if k is not None and k not in used:
            m[oid] = k
            used.add(k)
            how["source"] += 1
            continue
        cand = [k for k in by_name.get(so.get("name"), []) if k not in used]
        if len(cand) >= 1:
            m[oid] = cand[0]
            used.add(cand[0])
            how["name"] += 1
            continue
        rest.append(so)
    free = [k for k in range(len(ref.objects)) if k not in used]
    for so in rest:
        cand = [k for k in free if len(ref.objects[k].tris) == so.get("triangles")]
        if cand:
            m[int(so["id"])] = cand[0]
            free.remove(cand[0])
            how["order"] += 1
        else:
            how["unmatched"] += 1
    mism = []
    for so in sidecar_objects:
        k = m[int(so["id"])]
        if (
            k >= 0
            and so.get("triangles") is not None
            and so["triangles"] != len(ref.objects[k].tris)
        ):
            mism.append(
                f"{so.get('name')}: raycast {so['triangles']} triangles, "
                f"trimesh {len(ref.objects[k].tris)}"
            )
    return m, how, mism


# ------------------------------------------------------------------ comparison


def compare(ref: RefScene, origins, unit, rc, max_f64, label="rays"):
    """Compare raycast results `rc` (flattened) with the references; a report dict."""
    n = len(origins)
    lo, hi = ref.bounds()
    size = float(np.linalg.norm(hi - lo)) or 1.0
    rep = {
        "mode": label,
        "rays": n,
        "triangles": int(len(ref.tris)),
        "quadrics": len(ref.quadrics),
        "notes": list(ref.notes),
    }

    # ---- trimesh
    nf = min(n, max_f64)
    t0 = time.perf_counter()
    d64, tri64, tie = trace_f64(ref, origins[:nf], unit[:nf])
    rep["time_f64"] = time.perf_counter() - t0
    rep["rays_f64"] = nf
    t0 = time.perf_counter()
    try:
        dem, _, triem = trace_embree(ref.tris, origins, unit)
        rep["time_embree"] = time.perf_counter() - t0
        have_embree = True
    except ImportError as e:
        rep["notes"].append(f"embree unavailable: {e}")
        dem, triem = np.full(n, np.inf), np.full(n, -1, dtype=np.int64)
        rep["time_embree"] = None
        have_embree = False

    mdepth = dem.copy()
    mtri = triem.copy()
    mdepth[:nf], mtri[:nf] = d64, tri64
    reasons = {
        k: np.zeros(n, dtype=bool)
        for k in ("backends", "graze", "edge", "tie", "quadric_tangent", "quadric_clip")
    }
    if have_embree:
        h64, hem = np.isfinite(d64), np.isfinite(dem[:nf])
        with np.errstate(invalid="ignore"):
            bad = (h64 != hem) | (
                h64 & hem & (np.abs(d64 - dem[:nf]) > AMBIG["backend_depth_rel"] * d64)
            )
        reasons["backends"][:nf] = bad
    reasons["tie"][:nf] = tie

    # ---- quadrics
    kind = np.where(np.isfinite(mdepth), "mesh", "")
    ref_depth, ref_tri = mdepth, mtri
    ref_normal = np.zeros((n, 3))
    okt = ref_tri >= 0
    ref_normal[okt] = ref.normals[ref_tri[okt]]
    ref_obj = np.full(n, -1, dtype=np.int64)  # reference object index, or -(node+2) for quadric
    ref_obj[okt] = ref.tri_obj[ref_tri[okt]]
    if ref.quadrics:
        t0 = time.perf_counter()
        qr = qref.trace(ref.quadrics, origins, unit)
        rep["time_quadric_ref"] = time.perf_counter() - t0
        use_q = qr["depth"] < mdepth
        ref_depth = np.where(use_q, qr["depth"], mdepth)
        ref_normal = np.where(use_q[:, None], qr["normal"], ref_normal)
        ref_obj = np.where(use_q, -(qr["node"] + 2), ref_obj)
        ref_tri = np.where(use_q, -1, ref_tri)
        kind = np.where(use_q, "quadric", kind)
        for i in range(n):
            rs = qr["reasons"][i]
            if "tangent" in rs:
                reasons["quadric_tangent"][i] = True
            if "clip" in rs:
                reasons["quadric_clip"][i] = True
            if "tie" in rs:
                reasons["tie"][i] = True
        both = np.isfinite(qr["depth"]) & np.isfinite(mdepth)
        with np.errstate(invalid="ignore"):
            reasons["tie"] |= both & (
                np.abs(qr["depth"] - mdepth) <= AMBIG["tie_rel"] * np.minimum(qr["depth"], mdepth)
            )

    # ---- raycast outputs
    rdepth = np.asarray(rc["depth"], dtype=np.float64).reshape(-1)
    rnormal = np.asarray(rc["normal"], dtype=np.float64).reshape(-1, 3)
    rid = np.asarray(rc["id"]).reshape(-1).astype(np.int64)
    rprim = np.asarray(rc["prim"]).reshape(-1).astype(np.int64)
    side = rc["sidecar"]
    sobjs = side.get("objects", [])
    omap, how, mism = map_objects(ref, sobjs)
    rep["object_match"] = how
    rep["triangle_count_mismatch"] = mism
    quad_node_of_id = {}
    for so in sobjs:
        if so.get("kind") == "quadric" and str(so.get("source", "")).startswith("/nodes/"):
            # "/nodes/3" or "/nodes/3/extensions/RAYCAST_quadric"; a node drawing a mesh
            # and a quadric is one object whose quadric is the prim after its triangles.
            quad_node_of_id[int(so["id"])] = (
                int(so["source"].split("/")[2]),
                int(so.get("triangles", 0)),
            )
    rc_obj = np.full(n, -1, dtype=np.int64)
    valid_id = (rid > 0) & (rid < len(omap))
    rc_obj[valid_id] = omap[rid[valid_id]]
    for oid, (node, triangles) in quad_node_of_id.items():
        rc_obj[(rid == oid) & (rprim >= triangles)] = -(node + 2)
    # raycast's own hit triangle, for graze and edge tests
    rc_tri = np.full(n, -1, dtype=np.int64)
    okr = (rc_obj >= 0) & ref.prim_order
    if okr.any():
        k = rc_obj[okr]
        counts = ref.offsets[k + 1] - ref.offsets[k]
        pr = rprim[okr]
        inr = (pr >= 0) & (pr < counts)
        idx = np.flatnonzero(okr)[inr]
        rc_tri[idx] = ref.offsets[k[inr]] + pr[inr]

    # grazing: on the reference triangle, embree's and raycast's triangle
    for trisel in (ref_tri, triem, rc_tri):
        ok = trisel >= 0
        cosv = np.abs(np.einsum("ij,ij->i", unit[ok], ref.normals[trisel[ok]]))
        reasons["graze"][np.flatnonzero(ok)[cosv < AMBIG["graze_cos"]]] = True
    # edges: reference hit point and raycast hit point
    band = AMBIG["edge_rel"] * size
    for trisel, dep in ((ref_tri, ref_depth), (rc_tri, rdepth), (triem, dem)):
        ok = (trisel >= 0) & np.isfinite(dep)
        if ok.any():
            p = origins[ok] + dep[ok, None] * unit[ok]
            reasons["edge"][np.flatnonzero(ok)[edge_distance(ref.tris[trisel[ok]], p) < band]] = (
                True
            )

    amb = np.zeros(n, dtype=bool)
    for v in reasons.values():
        amb |= v
    rep["ambiguous"] = int(amb.sum())
    rep["ambiguous_by_reason"] = {k: int(v.sum()) for k, v in reasons.items() if v.any()}
    na = ~amb
    ref_hit = np.isfinite(ref_depth)
    rc_hit = np.isfinite(rdepth) & (rid > 0)
    rep["hits_ref"] = int(ref_hit.sum())
    rep["hits_raycast"] = int(rc_hit.sum())
    rep["compared"] = int(na.sum())

    checks = {}

    def check(name, value, ok):
        checks[name] = {"value": value, "tol": TOL.get(name), "ok": bool(ok)}

    isq = kind == "quadric"
    for label_, sel, tol_hm, tol_id in (
        ("mesh", na & ~isq, TOL["hitmiss_agreement"], TOL["id_agreement"]),
        ("quadric", na & isq, TOL["quadric_hitmiss_agreement"], TOL["quadric_id_agreement"]),
    ):
        # rays whose reference result is a mesh hit or a miss count as "mesh"; a
        # raycast quadric hit where the reference misses is a quadric disagreement
        if label_ == "mesh":
            sel = sel & ~(~ref_hit & (rc_obj < -1))
        else:
            sel = sel | (na & ~ref_hit & (rc_obj < -1))
        nsel = int(sel.sum())
        if nsel == 0:
            continue
        dis = sel & (ref_hit != rc_hit)
        rep[f"{label_}_hitmiss_disagree"] = int(dis.sum())
        rep[f"{label_}_hitmiss_examples"] = [int(i) for i in np.flatnonzero(dis)[:5]]
        agree = 1.0 - dis.sum() / nsel
        check(
            "hitmiss_agreement" if label_ == "mesh" else "quadric_hitmiss_agreement",
            agree,
            agree >= tol_hm,
        )
        bh = sel & ref_hit & rc_hit
        if bh.any():
            idok = rc_obj[bh] == ref_obj[bh]
            rate = float(idok.mean())
            check(
                "id_agreement" if label_ == "mesh" else "quadric_id_agreement", rate, rate >= tol_id
            )
            if label_ == "mesh":
                bi = bh & (rc_obj == ref_obj)
                if bi.any() and ref.prim_order:
                    pok = float((rc_tri[bi] == ref_tri[bi]).mean())
                    check("prim_agreement", pok, pok >= TOL["prim_agreement"])
            err = np.abs(rdepth[bh] - ref_depth[bh])
            rel = err / ref_depth[bh]
            ang = angle(rnormal[bh], ref_normal[bh])
            rep[f"{label_}_depth_abs"] = stats(err)
            rep[f"{label_}_depth_rel"] = stats(rel)
            rep[f"{label_}_normal_angle"] = stats(ang)
            flipped = int((ang > math.pi / 2).sum())
            rep[f"{label_}_normal_flipped"] = flipped
            if label_ == "mesh":
                p99 = float(np.percentile(rel, 99))
                check("depth_rel_p99", p99, p99 <= TOL["depth_rel_p99"])
                cosv = np.abs(np.einsum("ij,ij->i", unit[bh], ref_normal[bh]))
                bound = (
                    TOL["depth_bound_k"] * U32 * size / np.maximum(cosv, AMBIG["graze_cos"])
                    + 1e-12 * ref_depth[bh]
                )
                ratio = float((err / bound).max())
                check("depth_bound_ratio_max", ratio, ratio <= TOL["depth_bound_ratio_max"])
                ap99 = float(np.percentile(ang, 99))
                check("normal_angle_p99", ap99, ap99 <= TOL["normal_angle_p99"])
                check("normal_flipped_max", flipped, flipped <= TOL["normal_flipped_max"])
            else:
                mx = float(rel.max())
                check("quadric_depth_rel_max", mx, mx <= TOL["quadric_depth_rel_max"])
                amx = float(ang.max())
                check("quadric_normal_angle_max", amx, amx <= TOL["quadric_normal_angle_max"])
    rep["checks"] = checks
    rep["time_raycast"] = rc.get("wall")
    rep["raycast_timings"] = side.get("timings")
    rep["raycast_warnings"] = side.get("warnings", [])
    rep["ok"] = all(c["ok"] for c in checks.values()) and not mism
    if mism:
        rep["notes"].append("triangle counts differ: " + "; ".join(mism[:3]))
    return rep


# ------------------------------------------------------------------ per scene


def validate_scene(path, raycast, nrays=2000, seed=0, max_f64=2000, camera=False, keep=None):
    """Validate one scene; returns a list of report dicts (rays mode, camera mode)."""
    path = Path(path)
    base = {"scene": str(path)}
    try:
        ref = load_reference(path)
    except SkipScene as e:
        return [dict(base, status="skip", reason=str(e))]
    except Exception as e:  # trimesh could not load it
        return [dict(base, status="skip", reason=f"trimesh cannot load: {type(e).__name__}: {e}")]
    return validate_reference(ref, raycast, nrays, seed, max_f64, camera, keep)


def validate_reference(ref, raycast, nrays=2000, seed=0, max_f64=2000, camera=False, keep=None):
    """validate_scene on a reference already loaded (load_reference): the list of report
    dicts (rays mode, camera mode), or one `skip` report when there is nothing to aim at."""
    path = ref.path
    base = {"scene": str(path)}
    if len(ref.tris) == 0 and not ref.quadrics:
        return [dict(base, status="skip", reason="no triangles or quadrics in the reference")]
    if ref.bounds() is None:
        return [dict(base, status="skip", reason="no bounded geometry to aim rays at")]
    reports = []
    tmp = Path(tempfile.mkdtemp(prefix="validate-"))
    try:
        origins, unit, rdirs = make_rays(ref, nrays, seed)
        try:
            rc = run_rays(raycast, path, origins, rdirs, tmp, out_name="rays")
        except Exception as e:
            reports.append(dict(base, mode="rays", status="error", reason=str(e), ok=False))
        else:
            rep = compare(ref, origins, unit, rc, max_f64, "rays")
            reports.append(dict(base, status="ok" if rep["ok"] else "FAIL", **rep))
        if camera:
            w = h = 64
            try:
                rc = run_raycast(
                    raycast,
                    path,
                    [
                        "--aov",
                        "depth,normal,id,prim",
                        "--format",
                        "npy",
                        "--width",
                        str(w),
                        "--height",
                        str(h),
                    ],
                    tmp / "camera",
                )
                cam = rc["sidecar"]["camera"]
                o, u, _ = camera_rays(cam, w, h)
            except Exception as e:
                reports.append(dict(base, mode="camera", status="error", reason=str(e), ok=False))
            else:
                rep = compare(ref, o, u, rc, max_f64, "camera")
                rep["camera_source"] = cam.get("source")
                reports.append(dict(base, status="ok" if rep["ok"] else "FAIL", **rep))
    finally:
        if keep:
            dst = Path(keep) / path.stem
            shutil.rmtree(dst, ignore_errors=True)
            shutil.copytree(tmp, dst)
        shutil.rmtree(tmp, ignore_errors=True)
    return reports


# ------------------------------------------------------------------ output


def _fmt(x, spec=".1e"):
    if x is None:
        return "-"
    if isinstance(x, float):
        return format(x, spec)
    return str(x)


def table(reports):
    cols = [
        "scene",
        "mode",
        "status",
        "rays",
        "hits",
        "amb",
        "hm-dis",
        "rel p99",
        "rel max",
        "bound",
        "ang p99",
        "id",
        "prim",
        "q-rel max",
        "q-ang",
        "t rc",
        "t f64",
        "t emb",
    ]
    rows = []
    for r in reports:
        name = Path(r["scene"]).name
        if r.get("status") in ("skip", "error"):
            rows.append([name, r.get("mode", ""), r["status"], r.get("reason", "")])
            continue
        c = r.get("checks", {})

        def cv(k, spec=".1e"):
            return _fmt(c[k]["value"], spec) + ("" if c[k]["ok"] else "!") if k in c else "-"

        rows.append(
            [
                name,
                r["mode"],
                r["status"],
                str(r["rays"]),
                f"{r['hits_raycast']}/{r['hits_ref']}",
                str(r["ambiguous"]),
                str(r.get("mesh_hitmiss_disagree", 0) + r.get("quadric_hitmiss_disagree", 0)),
                cv("depth_rel_p99"),
                _fmt((r.get("mesh_depth_rel") or {}).get("max")),
                cv("depth_bound_ratio_max", ".2f"),
                cv("normal_angle_p99"),
                cv("id_agreement", ".4f"),
                cv("prim_agreement", ".4f"),
                cv("quadric_depth_rel_max"),
                cv("quadric_normal_angle_max"),
                _fmt(r.get("time_raycast"), ".2f"),
                _fmt(r.get("time_f64"), ".2f"),
                _fmt(r.get("time_embree"), ".2f"),
            ]
        )
    widths = [
        max(len(cols[i]), *(len(row[i]) for row in rows if len(row) > i and len(row) == len(cols)))
        if rows
        else len(cols[i])
        for i in range(len(cols))
    ]
    lines = ["  ".join(c.ljust(w) for c, w in zip(cols, widths))]
    for row in rows:
        if len(row) == len(cols):
            lines.append("  ".join(v.ljust(w) for v, w in zip(row, widths)))
        else:
            lines.append(
                "  ".join(
                    [
                        row[0].ljust(widths[0]),
                        row[1].ljust(widths[1]),
                        row[2].ljust(widths[2]),
                        row[3],
                    ]
                )
            )
    for r in reports:
        extra = []
        if r.get("ambiguous_by_reason"):
            extra.append(
                "ambiguous: " + ", ".join(f"{k} {v}" for k, v in r["ambiguous_by_reason"].items())
            )
        extra += r.get("notes", [])
        bad = [k for k, v in r.get("checks", {}).items() if not v["ok"]]
        if bad:
            extra.append("out of tolerance: " + ", ".join(bad))
        if extra:
            lines.append(f"  {Path(r['scene']).name} [{r.get('mode', '')}]: " + "; ".join(extra))
    lines.append(
        "('!' = out of tolerance; hits = raycast/reference; bound = max depth error "
        "/ per-ray bound; times in s)"
    )
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(
        prog=prog("validate"),
        description="Validate raycast against trimesh and the quadric reference.",
    )
    ap.add_argument("scenes", nargs="+", help="scene files or directories")
    ap.add_argument("--rays", type=int, default=2000, help="rays per scene (default 2000)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", action="store_true", help="machine-readable output")
    ap.add_argument(
        "--raycast",
        default=None,
        help="raycast binary (default: $RAYCAST, target/release, target/debug, PATH)",
    )
    ap.add_argument(
        "--max-rays-f64",
        type=int,
        default=2000,
        help="rays given to trimesh's slow float64 ray_triangle (the rest use "
        "embree's triangle choice with a float64 plane hit; default 2000)",
    )
    ap.add_argument("--camera", action="store_true", help="also check camera mode (64x64)")
    ap.add_argument("--keep", default=None, help="keep rays and raycast outputs in this folder")
    a = ap.parse_args(argv)
    raycast = raycast_or_exit(a.raycast, "validate")
    reports = []
    for path, skip in find_scenes(a.scenes):
        if skip:
            reports.append({"scene": str(path), "status": "skip", "reason": skip})
            continue
        reports.extend(
            validate_scene(path, raycast, a.rays, a.seed, a.max_rays_f64, a.camera, a.keep)
        )
    failed = any(r.get("status") in ("FAIL", "error") for r in reports)
    if a.json:
        print(
            json.dumps(
                {"tolerances": TOL, "ambiguity": AMBIG, "reports": reports, "ok": not failed},
                indent=1,
                default=_json_default,
            )
        )
    else:
        print(table(reports))
    return 1 if failed else 0


def _json_default(o):
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, set):
        return sorted(o)
    return str(o)
