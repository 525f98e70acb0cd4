"""The rays the tools cast: validation rays aimed at a scene's triangles and quadrics, the
pixel rays of a raycast camera (from the sidecar), and the bench's ray sets."""

from __future__ import annotations

import math

import numpy as np


def make_rays(ref, n: int, seed: int):
    """The validation rays of a reference scene (validate.RefScene: `bounds()`, `tris`,
    `quadrics`), deterministic from seed: (origins, unit dirs, raycast dirs of random lengths).
    Origins lie on a sphere of radius 0.75 x the box diagonal about its centre; targets are
    points on triangles (by index or by area), inside a quadric's box, or in the scene box."""
    rng = np.random.default_rng(seed)
    lo, hi = ref.bounds()
    center = 0.5 * (lo + hi)
    size = float(np.linalg.norm(hi - lo)) or 1.0
    radius = 0.75 * size  # 1.5x the half diagonal: outside the box
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    origins = center + radius * u
    targets = lo + rng.random((n, 3)) * (hi - lo)  # box rays (some miss)
    kind = rng.random(n)
    ntri = len(ref.tris)
    if ntri:
        # 35%: uniform triangle index (small triangles, edges); 35%: area-weighted
        aim = kind < 0.7
        area = 0.5 * np.linalg.norm(
            np.cross(ref.tris[:, 1] - ref.tris[:, 0], ref.tris[:, 2] - ref.tris[:, 0]), axis=1
        )
        by_index = rng.integers(0, ntri, n)
        p = area / area.sum() if area.sum() > 0 else None
        by_area = rng.choice(ntri, n, p=p)
        tri = np.where(kind < 0.35, by_index, by_area)
        r1, r2 = rng.random(n), rng.random(n)
        s = np.sqrt(r1)
        b = np.stack([1 - s, s * (1 - r2), s * r2], axis=1)
        pts = np.einsum("ij,ijk->ik", b, ref.tris[tri])
        targets[aim] = pts[aim]
    if ref.quadrics:
        # 30% aimed at a point inside a quadric's local box (world-transformed)
        qa = (kind >= 0.7) & (kind < 1.0) if ntri == 0 else (kind >= 0.4) & (kind < 0.7)
        for i in np.flatnonzero(qa):
            q = ref.quadrics[rng.integers(len(ref.quadrics))]
            lb = q.local_bounds()
            if lb is None:
                continue
            pl = lb[0] + rng.random(3) * (lb[1] - lb[0])
            targets[i] = q.A @ pl + q.t
    d = targets - origins
    dn = np.linalg.norm(d, axis=1)
    dn[dn == 0] = 1
    unit = d / dn[:, None]
    scale = np.exp(rng.uniform(np.log(0.5), np.log(2.0), n))  # raycast must not assume |d| = 1
    return origins, unit, unit * scale[:, None]


def camera_rays(cam: dict, width: int, height: int):
    """Per-pixel (origins, unit dirs, dirs) from the sidecar's camera block, rows in image
    order (docs/buffers-and-cli.md)."""
    C = np.array(cam["camera_to_world"], dtype=np.float64).reshape(4, 4)
    i = np.arange(width) + 0.5
    j = np.arange(height) + 0.5
    sx = 2.0 * i / width - 1.0
    sy = 1.0 - 2.0 * j / height
    SX, SY = np.meshgrid(sx, sy)  # (H, W): row j, column i
    SX, SY = SX.ravel(), SY.ravel()
    n = SX.size
    if cam.get("type", "perspective") == "perspective":
        tan = math.tan(float(cam["yfov"]) / 2.0)
        aspect = width / height
        local = np.stack([SX * tan * aspect, SY * tan, -np.ones(n), np.zeros(n)], axis=1)
        dirs = local @ C.T
        origins = np.repeat(C[None, :3, 3], n, axis=0)
    else:
        ymag = float(cam["ymag"])
        xmag = ymag * width / height
        local = np.stack([SX * xmag, SY * ymag, np.zeros(n), np.ones(n)], axis=1)
        origins = (local @ C.T)[:, :3]
        dirs = np.repeat((C @ np.array([0, 0, -1.0, 0]))[None], n, axis=0)
    dirs = dirs[:, :3]
    unit = dirs / np.linalg.norm(dirs, axis=1)[:, None]
    return origins, unit, dirs


def quadric_rays(quadrics, n, seed=0, frac_aimed=1.0):
    """Deterministic rays (origins, unit dirs) from a sphere around the quadrics' world box,
    aimed at uniform points inside a random quadric's local box (mapped to world)."""
    rng = np.random.default_rng(seed)
    boxes = [q.world_bounds() for q in quadrics]
    lo = np.min([b[0] for b in boxes], axis=0)
    hi = np.max([b[1] for b in boxes], axis=0)
    center = 0.5 * (lo + hi)
    size = float(np.linalg.norm(hi - lo)) or 1.0
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    origins = center + 0.75 * size * u
    targets = lo + rng.random((n, 3)) * (hi - lo)
    aimed = rng.random(n) < frac_aimed
    which = rng.integers(0, len(quadrics), n)
    for i in np.flatnonzero(aimed):
        q = quadrics[which[i]]
        llo, lhi = q.local_bounds()
        pl = llo + rng.random(3) * (lhi - llo)
        targets[i] = q.A @ pl + q.t
    d = targets - origins
    d /= np.linalg.norm(d, axis=1)[:, None]
    return origins, d


FOV_DEGREES = 40.0


def framing(lo, hi):
    """Eye and target of the bench's diagonal view that frames the box [lo, hi] with a
    FOV_DEGREES vertical field of view."""
    centre, radius = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    forward = -np.array([0.45, 0.35, 0.82])
    forward /= np.linalg.norm(forward)
    return centre - forward * radius / np.sin(np.radians(FOV_DEGREES) / 2), centre


def look_at_rays(eye, target, fov_degrees, side):
    """A pinhole camera at eye looking at target (+Y up, vertical field of view in degrees),
    one ray per pixel centre of a side x side image, row 0 at the top (raycast's camera
    convention): float32 rows origin|unit direction."""
    forward = np.asarray(target, dtype=np.float64) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    s = np.tan(np.radians(fov_degrees) / 2)
    px = (np.arange(side) + 0.5) / side * 2 - 1
    xs, ys = np.meshgrid(px * s, -px * s)
    dirs = forward + xs[..., None] * right + ys[..., None] * up
    dirs = dirs.reshape(-1, 3)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    origins = np.broadcast_to(eye, dirs.shape)
    return np.hstack([origins, dirs]).astype(np.float32)


def pinhole_rays(lo, hi, side):
    """The bench's coherent rays: look_at_rays from framing(lo, hi)."""
    eye, target = framing(lo, hi)
    return look_at_rays(eye, target, FOV_DEGREES, side)


def in_tiles(rays, side):
    """A side x side image's rays (row-major rows) reordered into 4 x 2 pixel tiles, left to
    right along each pair of rows: the order the CLI traces a camera's pixels in, so that each
    run of eight rays is a tile. Rows unchanged when side is not a multiple of 4."""
    if side % 4:
        return rays
    tiles = rays.reshape(side // 2, 2, side // 4, 4, rays.shape[-1])
    return tiles.transpose(0, 2, 1, 3, 4).reshape(rays.shape)


def random_rays(lo, hi, count, rng):
    """Origins uniform in the box [lo, hi], directions uniform on the sphere: float32 rows
    origin|unit direction (the bench's incoherent rays)."""
    origins = rng.uniform(lo, hi, (count, 3))
    dirs = rng.normal(size=(count, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    return np.hstack([origins, dirs]).astype(np.float32)
