"""UsdSkel fixtures and usd-core's skinning of them: the reference of tests/it/usd_pose.rs
(issue 28).

Writes fixtures/usd/posed/skel.usda with usd-core's authoring API, then, at the default time code
and several time codes, what usd-core poses from it, in world space:

- "bakedPoints" / "bakedWorld": `UsdSkel.BakeSkinning` applied to a copy of the stage (the
  file copied to a temporary folder), read back with `Get(time)` and `UsdGeom.XformCache(time)`.
  BakeSkinning stores skinned points as `point3f` and skins them in float, so these agree with
  a double-precision skinning to about 1e-7 only.
- "points" / "world": the same skinning in double precision from usd-core's own pieces:
  `UsdSkel.Cache` bindings, `SkeletonQuery.ComputeSkinningTransforms(time)` (double matrices),
  `SkinningQuery.ComputeVaryingJointInfluences`, `GetJointMapper().RemapTransforms`,
  `GetGeomBindTransform(time)` and the skeleton's world matrix, combined here by linear blend
  skinning as utils.cpp's `_SkinPointsLBS` combines them (p' = sum_k w_k * (p * G) * X_k, then
  * skelLocalToWorld), in numpy float64. For a rigidly bound prim (constant influences) the
  matrix is G * sum_k w_k X_k, its last column reset to (0, 0, 0, 1), as `SkinTransformLBS`.
  Prims that usd-core does not skin are read as usd_pose_reference reads them.
  Blend shapes move the rest points first, from usd-core's pieces too: the animation's
  `ComputeBlendShapeWeights(time)` through the mesh's `GetBlendShapeMapper()`, then
  `BlendShapeQuery.ComputeSubShapeWeights` (float weights, as usd-core computes them),
  `ComputeSubShapePointOffsets` and `ComputeBlendShapePointIndices`, summed in float64.

The fixture covers: a 3-joint arm whose SkelAnimation lists two of the joints in another order
(the third falls back to restTransforms), time-sampled translations, quatf rotations and half3
scales; a non-identity skeleton transform under a transformed SkelRoot; a mesh with elementSize 2
vertex influences and a non-identity geomBindTransform; a constant-interpolation (rigid) mesh;
a Cube inheriting constant influences from its parent Xform; a mesh with its own `skel:joints`
subset; a mesh under an untyped prim (not Imageable: usd-core does not skin it); a second
SkelRoot whose skeleton has no animation (rest pose) and a mesh whose weights do not sum to one;
a bound mesh outside any SkelRoot (not skinned); and blend shapes on the arm: a sparse one
(pointIndices) with two inbetweens, one at a negative weight, and a dense one without, weighed
by the animation in another order than the mesh's, with a third name the mesh does not have.

Usage:
    .venv/bin/python -m raycast_tools usd-skel-reference [FIXTURE_DIR]
(tools/make_usd_skel_fixtures.sh runs it; default FIXTURE_DIR fixtures/usd/posed.)
"""

import argparse
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
from pxr import Gf, Usd, UsdGeom, UsdSkel, Vt

from raycast_tools.cli import prog

# Time codes compared: the default, before the first sample, on a sample, between samples and
# on the last sample; all lie on the stage's playback frames, where BakeSkinning bakes.
TIMES = [None, 0.0, 2.0, 4.0, 7.0, 10.0]

ARM_JOINTS = ["Shoulder", "Shoulder/Elbow", "Shoulder/Elbow/Hand"]


def quat(axis, degrees):
    """A unit Gf.Quatf rotating `degrees` about `axis`."""
    q = Gf.Rotation(Gf.Vec3d(*axis), degrees).GetQuat()
    return Gf.Quatf(q.GetReal(), Gf.Vec3f(q.GetImaginary()))


def translate(x, y, z):
    return Gf.Matrix4d().SetTranslate(Gf.Vec3d(x, y, z))


def rotate(axis, degrees):
    return Gf.Matrix4d().SetRotate(Gf.Rotation(Gf.Vec3d(*axis), degrees))


def bar(x0, x1, rings, half):
    """A square tube along X: `rings` squares of side 2*half from x0 to x1, quads between."""
    points, counts, indices = [], [], []
    for r in range(rings):
        x = x0 + (x1 - x0) * r / (rings - 1)
        points += [(x, -half, -half), (x, half, -half), (x, half, half), (x, -half, half)]
    for r in range(rings - 1):
        for k in range(4):
            a, b = 4 * r + k, 4 * r + (k + 1) % 4
            counts.append(4)
            indices += [a, b, b + 4, a + 4]
    counts += [4, 4]
    last = 4 * (rings - 1)
    indices += [3, 2, 1, 0, last, last + 1, last + 2, last + 3]
    return points, counts, indices


def define_mesh(stage, path, mesh, xform=None):
    points, counts, indices = mesh
    m = UsdGeom.Mesh.Define(stage, path)
    m.CreatePointsAttr([Gf.Vec3f(*p) for p in points])
    m.CreateFaceVertexCountsAttr(counts)
    m.CreateFaceVertexIndicesAttr(indices)
    m.CreateSubdivisionSchemeAttr("none")
    if xform is not None:
        m.AddTransformOp().Set(xform)
    return m


def bind(prim, indices, weights, element_size, interpolation, skeleton=None):
    """Applies UsdSkelBindingAPI and authors joint influences (and a skeleton)."""
    binding = UsdSkel.BindingAPI.Apply(prim)
    binding.CreateJointIndicesPrimvar(interpolation == "constant", element_size).Set(indices)
    binding.CreateJointWeightsPrimvar(interpolation == "constant", element_size).Set(weights)
    if skeleton is not None:
        binding.CreateSkeletonRel().SetTargets([skeleton])
    return binding


def arm_weights(points):
    """elementSize 2: each point between the two joints nearest along X."""
    indices, weights = [], []
    for x, _, _ in points:
        if x <= 2.0:
            t = x / 2.0
            indices += [0, 1]
        else:
            t = min((x - 2.0) / 2.0, 1.0)
            indices += [1, 2]
        weights += [1.0 - t, t]
    return indices, weights


def author(path):
    """Writes the fixture stage."""
    stage = Usd.Stage.CreateNew(str(path))
    stage.SetStartTimeCode(0)
    stage.SetEndTimeCode(10)
    stage.SetTimeCodesPerSecond(24)
    stage.SetFramesPerSecond(24)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    world = UsdGeom.Xform.Define(stage, "/World")
    world.AddTranslateOp().Set(Gf.Vec3d(0.5, -1.0, 0.25))
    stage.SetDefaultPrim(world.GetPrim())

    root = UsdSkel.Root.Define(stage, "/World/Arm")
    root.AddRotateZOp().Set(15.0)
    UsdSkel.BindingAPI.Apply(root.GetPrim()).CreateSkeletonRel().SetTargets(["/World/Arm/Skel"])

    skel = UsdSkel.Skeleton.Define(stage, "/World/Arm/Skel")
    skel.AddTranslateOp().Set(Gf.Vec3d(0.25, 0.5, 0.0))
    skel.CreateJointsAttr(ARM_JOINTS)
    skel.CreateBindTransformsAttr(
        Vt.Matrix4dArray(
            [Gf.Matrix4d(1), rotate((1, 0, 0), 20) * translate(2, 0, 0), translate(4, 0, 0)]
        )
    )
    skel.CreateRestTransformsAttr(
        Vt.Matrix4dArray(
            [rotate((0, 0, 1), 5), translate(2, 0, 0), rotate((0, 1, 0), 15) * translate(2, 0, 0)]
        )
    )
    anim = UsdSkel.Animation.Define(stage, "/World/Arm/Skel/Anim")
    anim.CreateJointsAttr(["Shoulder/Elbow", "Shoulder"])
    t = anim.CreateTranslationsAttr()
    t.Set(Vt.Vec3fArray([Gf.Vec3f(2, 0, 0), Gf.Vec3f(0, 0, 0)]), 0)
    t.Set(Vt.Vec3fArray([Gf.Vec3f(2.5, 0, 0.5), Gf.Vec3f(0, 1, 0)]), 10)
    r = anim.CreateRotationsAttr()
    r.Set(Vt.QuatfArray([quat((0, 0, 1), 0), quat((0, 1, 0), 0)]), 0)
    r.Set(Vt.QuatfArray([quat((0, 0, 1), 60), quat((0, 1, 0), 30)]), 4)
    r.Set(Vt.QuatfArray([quat((1, 2, 3), 130), quat((0, 1, 0), -45)]), 10)
    s = anim.CreateScalesAttr()
    s.Set(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1), Gf.Vec3h(1, 1, 1)]), 0)
    s.Set(Vt.Vec3hArray([Gf.Vec3h(1, 2, 1), Gf.Vec3h(1.5, 1, 0.75)]), 10)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets([anim.GetPath()])

    # The arm: elementSize 2 influences, a geomBindTransform, and a transform of its own
    # (ignored by skinning: the skinned points are in the skeleton's space).
    mesh = bar(0.0, 6.0, 7, 0.3)
    arm = define_mesh(stage, "/World/Arm/ArmMesh", mesh, translate(10, 0, 0))
    binding = bind(arm.GetPrim(), *arm_weights(mesh[0]), 2, "vertex")
    binding.CreateGeomBindTransformAttr(rotate((0, 1, 0), 10) * translate(0.1, -0.2, 0.05))

    # Blend shapes on the arm, weighed by the animation (in another order, with a name the
    # mesh does not have), at weights inside, between and past the sub-shapes.
    points = mesh[0]
    bulge = UsdSkel.BlendShape.Define(stage, "/World/Arm/ArmMesh/Bulge")
    tip_points = [i for i, p in enumerate(points) if p[0] > 3.0]
    bulge.CreatePointIndicesAttr(tip_points)
    bulge.CreateOffsetsAttr([Gf.Vec3f(0.0, 0.4 + 0.05 * k, -0.2) for k in range(len(tip_points))])
    half = bulge.CreateInbetween("half")
    half.SetWeight(0.5)
    half.SetOffsets([Gf.Vec3f(0.1, 0.1 * (k % 3), 0.3) for k in range(len(tip_points))])
    under = bulge.CreateInbetween("under")
    under.SetWeight(-0.4)
    under.SetOffsets([Gf.Vec3f(-0.25, 0.0, 0.05 * k) for k in range(len(tip_points))])
    stretch = UsdSkel.BlendShape.Define(stage, "/World/Arm/ArmMesh/Stretch")
    stretch.CreateOffsetsAttr([Gf.Vec3f(0.1 * p[0], 0.0, 0.02 * p[1]) for p in points])
    binding.CreateBlendShapesAttr(["Bulge", "Stretch"])
    binding.CreateBlendShapeTargetsRel().SetTargets([bulge.GetPath(), stretch.GetPath()])
    anim.CreateBlendShapesAttr(["Stretch", "Other", "Bulge"])
    bw = anim.CreateBlendShapeWeightsAttr()
    bw.Set(Vt.FloatArray([0.0, 1.0, 0.25]), 0)
    bw.Set(Vt.FloatArray([0.6, 0.0, 0.8]), 4)
    bw.Set(Vt.FloatArray([-0.5, 0.3, 1.7]), 10)

    # A rigid prop on the hand: constant influences, its points about its own origin.
    prop = define_mesh(stage, "/World/Arm/Prop", bar(-0.4, 0.4, 2, 0.2), translate(0, 3, 0))
    prop_binding = bind(prop.GetPrim(), [2], [1.0], 1, "constant")
    prop_binding.CreateGeomBindTransformAttr(translate(4.5, 0, 0))

    # A cube inheriting constant influences (the elbow) from its parent Xform.
    rigid = UsdGeom.Xform.Define(stage, "/World/Arm/Rigid")
    bind(rigid.GetPrim(), [1], [1.0], 1, "constant")
    cube = UsdGeom.Cube.Define(stage, "/World/Arm/Rigid/Cube")
    cube.CreateSizeAttr(0.5)
    cube.AddTranslateOp().Set(Gf.Vec3d(3.0, 0.0, 0.0))

    # Its own joint order: index 0 is the hand, 1 the elbow.
    tip = bar(3.0, 5.0, 3, 0.1)
    tip_mesh = define_mesh(stage, "/World/Arm/Tip", tip)
    tip_indices = [1 if p[0] < 4.0 else 0 for p in tip[0]]
    tip_binding = bind(tip_mesh.GetPrim(), tip_indices, [1.0] * len(tip[0]), 1, "vertex")
    tip_binding.CreateJointsAttr(["Shoulder/Elbow/Hand", "Shoulder/Elbow"])

    # Under an untyped prim (not UsdGeomImageable): usd-core's skinning traversal stops there.
    stage.DefinePrim("/World/Arm/Loose")
    loose = bar(0.0, 2.0, 2, 0.1)
    loose_mesh = define_mesh(stage, "/World/Arm/Loose/Mesh", loose, translate(0, -2, 0))
    bind(loose_mesh.GetPrim(), [1] * len(loose[0]), [1.0] * len(loose[0]), 1, "vertex")

    # A second skel root: no animation (the rest pose), weights that do not sum to one.
    rest_root = UsdSkel.Root.Define(stage, "/World/Rest")
    rest_root.AddTranslateOp().Set(Gf.Vec3d(0, 4, 0))
    rest_skel = UsdSkel.Skeleton.Define(stage, "/World/Rest/Skel")
    rest_skel.CreateJointsAttr(["Root", "Root/Tip"])
    rest_skel.CreateBindTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(1), translate(1, 0, 0)]))
    rest_skel.CreateRestTransformsAttr(
        Vt.Matrix4dArray([rotate((1, 0, 0), 30), rotate((0, 0, 1), -40) * translate(1.2, 0, 0)])
    )
    blade = bar(0.0, 2.0, 5, 0.15)
    blade_mesh = define_mesh(stage, "/World/Rest/Blade", blade)
    indices, weights = [], []
    for x, _, _ in blade[0]:
        indices += [0, 1]
        weights += [0.7, 0.5] if x > 1.5 else [1.0 - x / 2.0, x / 2.0]
    bind(blade_mesh.GetPrim(), indices, weights, 2, "vertex", "/World/Rest/Skel")

    # Bound, but under no SkelRoot: not skinned.
    out = bar(0.0, 1.0, 2, 0.1)
    outside = define_mesh(stage, "/World/Outside", out, translate(0, -4, 0))
    bind(outside.GetPrim(), [0] * len(out[0]), [1.0] * len(out[0]), 1, "vertex", "/World/Arm/Skel")
    stage.GetRootLayer().Save()


def rows(matrix):
    """A Gf.Matrix4d as 16 numbers, row-major (as USD writes it)."""
    return [matrix[r][c] for r in range(4) for c in range(4)]


def np_matrix(matrix):
    return np.array([[matrix[r][c] for c in range(4)] for r in range(4)], dtype=np.float64)


def world_points(points, matrix):
    """Row-vector points (n x 3) through a numpy 4x4 row-vector matrix."""
    p = np.hstack([np.asarray(points, dtype=np.float64), np.ones((len(points), 1))])
    return (p @ matrix)[:, :3]


def blended(query, skel_query, points, code):
    """The rest points moved by the mesh's blend shapes (usd-core's weights), in float64."""
    anim = skel_query.GetAnimQuery()
    points = np.asarray(points, dtype=np.float64)
    if not anim or not query.HasBlendShapes():
        return points
    weights = anim.ComputeBlendShapeWeights(code)
    if not weights:
        return points
    mapper = query.GetBlendShapeMapper()
    if mapper is not None and not mapper.IsNull():
        weights = mapper.Remap(weights)
    shapes = UsdSkel.BlendShapeQuery(UsdSkel.BindingAPI(query.GetPrim()))
    sub_weights, shape_indices, sub_indices = shapes.ComputeSubShapeWeights(weights)
    offsets = shapes.ComputeSubShapePointOffsets()
    point_indices = shapes.ComputeBlendShapePointIndices()
    moved = points.copy()
    for w, shape, sub in zip(sub_weights, shape_indices, sub_indices):
        delta = np.asarray(offsets[sub], dtype=np.float64) * float(w)
        if len(delta) == 0:
            continue
        indices = list(point_indices[shape])
        if indices:
            moved[indices] += delta
        else:
            moved += delta
    return moved


def lbs(query, skel_query, skel_world, points, code):
    """usd-core's pieces combined by linear blend skinning in float64: world-space points."""
    points = blended(query, skel_query, points, code)
    xforms = skel_query.ComputeSkinningTransforms(code)
    mapper = query.GetJointMapper()
    if mapper is not None and not mapper.IsNull():
        xforms = mapper.RemapTransforms(xforms, Vt.Matrix4dArray())
    joints = [np_matrix(x) for x in xforms]
    indices, weights = query.ComputeVaryingJointInfluences(len(points), code)
    n = query.GetNumInfluencesPerComponent()
    bound = world_points(points, np_matrix(query.GetGeomBindTransform(code)))
    bound = np.hstack([bound, np.ones((len(points), 1))])
    skinned = np.zeros((len(points), 3))
    for i in range(len(points)):
        for k in range(n):
            w = float(weights[i * n + k])
            if w != 0.0:
                skinned[i] += w * (bound[i] @ joints[indices[i * n + k]])[:3]
    return world_points(skinned, skel_world)


def rigid(query, skel_query, skel_world, code):
    """The world matrix usd-core gives a rigidly bound prim, in float64."""
    xforms = skel_query.ComputeSkinningTransforms(code)
    mapper = query.GetJointMapper()
    if mapper is not None and not mapper.IsNull():
        xforms = mapper.RemapTransforms(xforms, Vt.Matrix4dArray())
    indices, weights = query.ComputeJointInfluences(code)
    blend = sum(float(w) * np_matrix(xforms[j]) for j, w in zip(indices, weights))
    m = np_matrix(query.GetGeomBindTransform(code)) @ blend
    m[:, 3] = [0, 0, 0, 1]
    return m @ skel_world


def skinned_by_usd_core(stage, code):
    """prim path -> ("points", world points) or ("world", world matrix), double precision, and
    whether its skeleton's animation has time samples."""
    cache = UsdSkel.Cache()
    cache_xf = UsdGeom.XformCache(code)
    out = {}
    for prim in stage.Traverse():
        if not prim.IsA(UsdSkel.Root):
            continue
        root = UsdSkel.Root(prim)
        cache.Populate(root, Usd.PrimDefaultPredicate)
        for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
            skel_query = cache.GetSkelQuery(binding.GetSkeleton())
            skel_world = np_matrix(cache_xf.GetLocalToWorldTransform(skel_query.GetPrim()))
            anim = skel_query.GetAnimQuery()
            animated = bool(anim) and anim.JointTransformsMightBeTimeVarying()
            for query in binding.GetSkinningTargets():
                target = query.GetPrim()
                if not query.HasJointInfluences():
                    continue
                if query.IsRigidlyDeformed():
                    world = rigid(query, skel_query, skel_world, code)
                    out[str(target.GetPath())] = ("world", world, animated)
                else:
                    points = UsdGeom.Mesh(target).GetPointsAttr().Get(code)
                    out[str(target.GetPath())] = (
                        "points",
                        lbs(query, skel_query, skel_world, points, code),
                        animated,
                    )
    return out


def read(stage, baked, time):
    """What the stage draws at `time`: baked and double-precision skinning side by side."""
    code = Usd.TimeCode.Default() if time is None else Usd.TimeCode(time)
    cache = UsdGeom.XformCache(code)
    baked_cache = UsdGeom.XformCache(code)
    skinned = skinned_by_usd_core(stage, code)
    meshes, gprims = [], []
    for prim in stage.Traverse():
        path = str(prim.GetPath())
        baked_prim = baked.GetPrimAtPath(path)
        world = np_matrix(cache.GetLocalToWorldTransform(prim))
        baked_world = np_matrix(baked_cache.GetLocalToWorldTransform(baked_prim))
        kind, value, animated = skinned.get(path, (None, None, False))
        # BakeSkinning bakes an animated skeleton's prims at its time samples and playback
        # frames only, not at the default time code (where usd-core's skinning queries pose
        # the rest transforms): there is no baked pose to compare with.
        unbaked = animated and time is None
        if kind == "world":
            world = value
        if prim.GetTypeName() == "Mesh":
            mesh = UsdGeom.Mesh(prim)
            points = mesh.GetPointsAttr().Get(code)
            ours = value if kind == "points" else world_points(points, world)
            baked_points = UsdGeom.Mesh(baked_prim).GetPointsAttr().Get(code)
            meshes.append(
                {
                    "path": path,
                    "skinned": kind is not None,
                    "points": ours.flatten().tolist(),
                    "bakedPoints": None
                    if unbaked
                    else world_points(baked_points, baked_world).flatten().tolist(),
                    "faceVertexCounts": list(mesh.GetFaceVertexCountsAttr().Get(code)),
                    "faceVertexIndices": list(mesh.GetFaceVertexIndicesAttr().Get(code)),
                }
            )
        elif prim.GetTypeName() == "Cube":
            gprims.append(
                {
                    "path": path,
                    "type": "Cube",
                    "skinned": kind is not None,
                    "size": prim.GetAttribute("size").Get(code),
                    "world": world.flatten().tolist(),
                    "bakedWorld": None if unbaked else baked_world.flatten().tolist(),
                }
            )
    return {"meshes": meshes, "gprims": gprims, "instances": []}


def bake(source, folder):
    """usd-core's BakeSkinning over a copy of `source` in `folder`; the baked stage."""
    copy = Path(folder) / source.name
    shutil.copy(source, copy)
    stage = Usd.Stage.Open(str(copy))
    for prim in list(stage.Traverse()):
        if prim.IsA(UsdSkel.Root):
            if not UsdSkel.BakeSkinning(UsdSkel.Root(prim), Gf.Interval.GetFullInterval()):
                raise SystemExit(f"BakeSkinning failed on {prim.GetPath()}")
    return stage


def main(argv=None):
    parser = argparse.ArgumentParser(prog=prog("usd-skel-reference"), description=__doc__)
    parser.add_argument("folder", nargs="?", default="fixtures/usd/posed")
    folder = Path(parser.parse_args(argv).folder)
    fixture = folder / "skel.usda"
    if fixture.exists():
        fixture.unlink()
    author(fixture)
    stage = Usd.Stage.Open(str(fixture))
    with tempfile.TemporaryDirectory() as tmp:
        baked = bake(fixture, tmp)
        cases = [{"time": t, **read(stage, baked, t)} for t in TIMES]
    record = {"usdCore": Usd.GetVersion(), "cases": cases}
    largest = 0.0
    for case in cases:
        for mesh in filter(lambda m: m["bakedPoints"] is not None, case["meshes"]):
            a, b = np.array(mesh["points"]), np.array(mesh["bakedPoints"])
            largest = max(largest, float(np.abs(a - b).max()))
    path = folder / "skel.reference.json"
    path.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {fixture} and {path}; double vs baked (float) skinning: {largest:.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
