"""Cameras for :meth:`raycast.Scene.render`.

Two conventions, as their users expect them:

- :func:`look_at` makes a glTF-style camera: it looks down its local -Z axis with +Y up, and
  ``yfov_deg`` is the *vertical* field of view (Open3D's ``create_rays_pinhole`` takes a
  horizontal one).
- :func:`pinhole` takes an intrinsic matrix ``K`` in the computer-vision convention (OpenCV,
  Open3D): the camera looks down +Z with +Y down, pixel ``(u, v)`` is centred at
  ``(u + 0.5, v + 0.5)``. Unlike Open3D, which takes the world-to-camera extrinsic, it takes
  the camera-to-world matrix.
"""

from __future__ import annotations

import numpy as np

from . import _raycast

Camera = _raycast.Camera

__all__ = ["Camera", "look_at", "pinhole", "read_views"]


def look_at(eye, target, up=(0.0, 1.0, 0.0), yfov_deg: float = 45.0) -> Camera:
    """A perspective camera at ``eye`` looking at ``target``.

    Parameters
    ----------
    eye, target, up : array_like, shape (3,)
        Camera position, the point it looks at, and the world direction that appears upward.
    yfov_deg : float
        Vertical field of view in degrees, strictly between 0 and 180.

    Returns
    -------
    Camera

    Raises
    ------
    raycast.errors.UsageError
        ``eye`` equals ``target``, or ``up`` is parallel to the view direction.
    """
    vec = [
        tuple(float(x) for x in np.asarray(v, dtype=np.float64).reshape(3))
        for v in (eye, target, up)
    ]
    return _raycast.look_at(vec[0], vec[1], vec[2], float(yfov_deg))


def pinhole(K, cam_to_world, width: int, height: int) -> Camera:
    """A pinhole camera from its intrinsic matrix, for an image of ``width`` x ``height``.

    Parameters
    ----------
    K : array_like, shape (3, 3)
        Intrinsic matrix ``[[fx, s, cx], [0, fy, cy], [0, 0, 1]]`` in pixels.
    cam_to_world : array_like, shape (4, 4)
        Camera-to-world matrix (the inverse of Open3D's ``extrinsic``).
    width, height : int
        Image size in pixels; :meth:`raycast.Scene.render` must be called with the same.

    Returns
    -------
    Camera
    """
    k = np.ascontiguousarray(K, dtype=np.float64)
    m = np.ascontiguousarray(cam_to_world, dtype=np.float64)
    return _raycast.pinhole(k, m, int(width), int(height))


def read_views(path, width: int | None = None, height: int | None = None) -> list:
    """The cameras of a views file, as the command line's ``--views`` reads it.

    Parameters
    ----------
    path : str or os.PathLike
        A nerfstudio / instant-ngp ``transforms.json`` (``frames``, OpenGL axes) or a plain
        list ``{"axes": "opencv"|"opengl", "K": ..., "width": ..., "height": ..., "views":
        [{"name": ..., "cam_to_world": ...}]}`` (docs/buffers-and-cli.md).
    width, height : int, optional
        The image size for frames that do not give one.

    Returns
    -------
    list of (str or None, Camera)
        Each view's name (a frame's image stem) and its pinhole camera; ``camera.size`` is
        the size to render it at, and the images equal the command line's, bit for bit.

    Raises
    ------
    raycast.errors.SceneError
        The file is not a views file, or a frame is wrong (the message names it).
    """
    if (width is None) != (height is None):
        raise ValueError("give both width and height, or neither")
    return _raycast.read_views(path, width, height)
