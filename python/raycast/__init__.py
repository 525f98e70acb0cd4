"""raycast: exact ray queries on glTF, USD, OBJ, PLY and STL scenes, for numpy users.

>>> import numpy as np, raycast
>>> scene = raycast.load("fixtures/gltf/cube.gltf")            # doctest: +SKIP
>>> hits = scene.cast(np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, -1.0]]))  # doctest: +SKIP
>>> hits["distance"]                                             # doctest: +SKIP

Every query takes float arrays of shape (N, 3) (any float dtype; float64 C- or Fortran-ordered
arrays and strided views are read in place, without a copy), releases the GIL while it
traces, and traces on all cores. Hits need ``tmin < t <= tmax`` where ``t`` is the ray
parameter in units of ``|direction|``. See docs/python.md.
"""

from __future__ import annotations

import errno
import json
import os
import warnings
from typing import Iterable

import numpy as np

from . import _raycast, camera, errors
from .errors import RaycastError, RaycastWarning, SceneError, SceneNotFoundError, UsageError

__all__ = [
    "CAST_OUTPUTS",
    "RENDER_OUTPUTS",
    "RaycastError",
    "RaycastWarning",
    "Scene",
    "SceneError",
    "SceneNotFoundError",
    "UsageError",
    "camera",
    "errors",
    "load",
    "load_bytes",
]

#: Outputs :meth:`Scene.cast` can return.
CAST_OUTPUTS = (
    "t",
    "distance",
    "normal",
    "position",
    "id",
    "prim",
    "bary",
    "error",
    "certain",
    "uv",
    "shading_normal",
    "material",
)
#: Outputs :meth:`Scene.render` can return (``depth`` is ``distance``, as on the command line).
RENDER_OUTPUTS = (*CAST_OUTPUTS[:2], "depth", "z", *CAST_OUTPUTS[2:])
#: The ``prim`` value of a miss.
INVALID_PRIM = 2**32 - 1


def load(
    path: str | os.PathLike,
    scene: str | int | None = None,
    time: float | None = None,
    animation: str | int | None = None,
    variants: dict[str, str] | None = None,
) -> Scene:
    """Loads a scene file and builds its octree.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.gltf``, ``.glb``, ``.obj``, ``.ply``, ``.stl``, ``.usda``, ``.usdc``, ``.usd`` or
        ``.usdz`` file.
    scene : str or int, optional
        glTF: the scene by index or name (default: the file's default scene); USD: a prim path
        whose subtree is drawn.
    time : float, optional
        glTF: play the animations to this time in seconds (default: none applied, the nodes'
        own transforms and default morph weights); USD: read the stage at this time code
        (default: the default time code, as usd-core's ``Usd.TimeCode.Default()``); as
        ``--time``.
    animation : str or int, optional
        glTF, with ``time``: the one animation to apply, by index or name (default: all).
    variants : dict of str to str, optional
        USD: variant selections, set name to variant name, applied to every prim that has the
        set (as ``--variant SET=NAME``).

    Returns
    -------
    Scene

    Raises
    ------
    raycast.SceneNotFoundError
        The file does not exist (also a ``FileNotFoundError``).
    raycast.SceneError
        The file cannot be read or is not a valid scene; the message names the file.
    """
    choice = None if scene is None else str(scene)
    which = None if animation is None else str(animation)
    chosen = None if variants is None else [(str(k), str(v)) for k, v in variants.items()]
    try:
        return Scene(_raycast.load_path(os.fspath(path), choice, time, which, chosen))
    except SceneNotFoundError as missing:
        missing.errno, missing.strerror = errno.ENOENT, os.strerror(errno.ENOENT)
        missing.filename = os.fspath(path)
        raise


def load_bytes(
    data: bytes,
    name: str = "scene.glb",
    scene: str | int | None = None,
    time: float | None = None,
    animation: str | int | None = None,
) -> Scene:
    """Loads a scene held in memory, as if it had been read from the file ``name``.

    Parameters
    ----------
    data : bytes
        The file's content: glTF, GLB, OBJ, PLY or STL (USD is read from files only).
    name : str
        A file name: its extension gives the format, it names the scene in messages, and its
        folder is where a glTF's external buffers are read from.
    scene : str or int, optional
        As for :func:`load`.
    time, animation : optional
        As for :func:`load`.

    Returns
    -------
    Scene
    """
    choice = None if scene is None else str(scene)
    which = None if animation is None else str(animation)
    return Scene(_raycast.load_bytes(bytes(data), os.fspath(name), choice, time, which))


def _batch(value, name: str, width: int) -> np.ndarray:
    """``value`` as a float64 array of shape ``(..., width)``."""
    array = np.asarray(value)
    if array.dtype.kind not in "fiu":
        raise TypeError(f"{name} must hold real numbers, got dtype {array.dtype}")
    if array.ndim == 0 or array.shape[-1] != width:
        raise ValueError(f"{name} must have shape (..., {width}), got {array.shape}")
    return array.astype(np.float64, copy=False)


class _Rays:
    """Rays of any batch shape, flattened for the compiled scene: ``flat`` is (origins
    (N, 3), directions (N, 3), tmin, tmax (N,) or (1,)) and ``shape`` the batch shape the
    results take again (:meth:`shaped`)."""

    def __init__(self, origins, directions, tmin, tmax):
        if directions is None:
            rays = _batch(origins, "rays", 6)
            o, d = rays[..., :3], rays[..., 3:]
        else:
            o, d = _batch(origins, "origins", 3), _batch(directions, "directions", 3)
        try:
            shape = np.broadcast_shapes(o.shape[:-1], d.shape[:-1])
        except ValueError:
            raise ValueError(
                "origins and directions must have the same shape (or shapes that broadcast),"
                f" got {o.shape} and {d.shape}"
            ) from None
        self.shape = shape
        # A view where the array is (N, 3) already (read in place, any strides), else a copy.
        flat = (np.broadcast_to(x, shape + (3,)).reshape(-1, 3) for x in (o, d))
        self.flat = (*flat, self._range(tmin, "tmin"), self._range(tmax, "tmax"))

    def _range(self, t, name: str) -> np.ndarray:
        """A range bound: one number for all rays, or one per ray (broadcast to the batch)."""
        array = np.asarray(t)
        if array.dtype.kind not in "fiu":
            raise TypeError(f"{name} must hold real numbers, got dtype {array.dtype}")
        if array.ndim == 0:
            return array.astype(np.float64).reshape(1)
        try:
            full = np.broadcast_to(array, self.shape)
        except ValueError:
            raise ValueError(
                f"{name} must be a number or have shape {self.shape}, got {array.shape}"
            ) from None
        return np.ascontiguousarray(full, dtype=np.float64).reshape(-1)

    def shaped(self, array: np.ndarray) -> np.ndarray:
        """A per-ray result (N, ...) in the batch shape."""
        return array.reshape(self.shape + array.shape[1:])

    def named(self, error: ValueError) -> ValueError:
        """A compiled scene's error about flat ray ``i``, naming the ray by its batch index."""
        text = str(error)
        head, sep, rest = text.partition(": ")
        if len(self.shape) > 1 and sep and head.startswith("ray ") and head[4:].isdigit():
            index = np.unravel_index(int(head[4:]), self.shape)
            return ValueError(f"ray {tuple(int(i) for i in index)}: {rest}")
        return error


def _names(outputs: Iterable[str] | str) -> list[str]:
    if isinstance(outputs, str):
        return [outputs]
    return list(dict.fromkeys(outputs))


class Scene:
    """A loaded scene with its octree, ready for queries. Made by :func:`load` or
    :func:`load_bytes`; pickles as its path (or its bytes) and loads again on unpickling."""

    def __init__(self, compiled: _raycast._Scene):
        self._scene = compiled
        self._warned: set[str] = set()
        for line in json.loads(compiled.info_json()).get("warnings", []):
            # stacklevel 3: the caller of load(), load_bytes(), at() or from_arrays().
            warnings.warn(line, RaycastWarning, stacklevel=3)

    @staticmethod
    def from_arrays(vertices, faces) -> Scene:
        """A scene of one mesh from arrays, without a file.

        Parameters
        ----------
        vertices : array_like, shape (N, 3)
            Vertex positions (float64; every vertex finite).
        faces : array_like, shape (M, 3)
            Triangles as indices into ``vertices`` (each in 0..N).

        Returns
        -------
        Scene
            One object, ``mesh``; ``prim`` is the face's row in ``faces``. Pickles as its
            arrays.

        Raises
        ------
        ValueError
            A wrong shape, a face index outside 0..N, or a vertex that is not finite (the
            message names the first).
        """
        v = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
        f = np.asarray(faces)
        if f.size and not np.issubdtype(f.dtype, np.integer):
            raise ValueError(f"faces must be integers, got {f.dtype}")
        f = np.ascontiguousarray(f, dtype=np.int64).reshape(-1, 3)
        return Scene(_raycast.load_arrays(v, f))

    def __reduce__(self):
        arrays = self._scene.arrays()
        if arrays is not None:
            return (Scene.from_arrays, arrays)
        data, name, choice, time, animation, variants = self._scene.source()
        if name is None:
            return (load, (data, choice, time, animation, dict(variants) or None))
        return (load_bytes, (data, name, choice, time, animation))

    def at(self, time: float) -> Scene:
        """The same scene posed at another time, as ``load(path, time=time)`` with this scene's
        other choices (``scene``, ``animation``, ``variants``) would give it, hit for hit.

        A glTF file is not read again: the parsed document, its buffers decoded, is kept and
        posed at ``time`` (except for a scene loaded without ``time``, whose animations' data
        were not read: the file is read once more, and the scene returned keeps it). A USD stage
        is opened again at that time code; an OBJ file has one pose.

        Parameters
        ----------
        time : float
            glTF seconds or USD time code (a finite number).

        Returns
        -------
        Scene
            A new scene; this one is unchanged.
        """
        return Scene(self._scene.at(float(time)))

    @property
    def objects(self) -> list[dict]:
        """The object table: one dict per object with ``id`` (1-based, as in the ``id``
        output), ``name``, ``kind`` (``mesh`` or ``quadric``), ``source``, ``triangles`` and
        ``bounds`` ([min, max])."""
        return self._scene.objects()

    @property
    def materials(self) -> list[str]:
        """The materials, named as the file names them (glTF material names, ``material<i>``
        when unnamed; OBJ ``usemtl`` names; USD material prim paths): the ``material``
        output's value ``m`` is ``materials[m - 1]``, 0 meaning a miss or no material."""
        return self._scene.materials()

    def _warn_missing(self, names: list[str]) -> None:
        """Warns once per scene and output when some objects lack what ``uv``,
        ``shading_normal`` or ``material`` read (their hits hold the miss value)."""
        for line in self._scene.attribute_warnings(names):
            if line not in self._warned:
                self._warned.add(line)
                # stacklevel 3: the caller of cast(), render() or render_views().
                warnings.warn(line, RaycastWarning, stacklevel=3)

    def triangles(self, id: int) -> np.ndarray:
        """Object ``id``'s triangles in world coordinates: a (T, 3, 3) float64 array, row ``i``
        the triangle whose ``prim`` is ``i`` (empty for a quadric). Raises ValueError for an
        id no object has."""
        return self._scene.triangles(int(id))

    @property
    def bounds(self) -> np.ndarray:
        """World bounds, a (2, 3) array ``[min, max]``."""
        return np.array(self._scene.bounds())

    @property
    def cameras(self) -> list[camera.Camera]:
        """The cameras the file defines, in file order."""
        return self._scene.cameras()

    def info(self) -> dict:
        """What ``raycast info --json`` prints for this scene, as a dict."""
        return json.loads(self._scene.info_json())

    def cast(
        self,
        origins,
        directions=None,
        tmin=0.0,
        tmax=np.inf,
        aovs=("t", "distance", "normal", "id", "prim"),
    ) -> dict:
        """The nearest hit of each ray ``origin + t * direction`` with ``tmin < t <= tmax``.

        Parameters
        ----------
        origins, directions : array_like, shape (..., 3)
            Ray origins and directions (any non-zero length; not normalised), of any batch
            shape; the two broadcast against each other (one origin for many directions).
            With ``directions`` left out, ``origins`` holds whole rays as Open3D's
            ``RaycastingScene`` takes them: shape (..., 6), origin then direction.
        tmin, tmax : float or array_like, broadcasting to the batch shape
            The parameter range, per ray or for all; ``t`` is in units of ``|direction|``.
            ``tmin >= 0``.
        aovs : sequence of str
            Outputs to compute, from :data:`CAST_OUTPUTS`.

        Returns
        -------
        dict of numpy.ndarray
            Each of the batch shape (written (N,) below) with the output's own axes after
            it. ``t`` (N,) float64, +inf on a miss; ``distance`` (N,) float64,
            ``|hit - origin|``, +inf on a miss; ``normal`` (N, 3) float64, the unit geometric
            normal (counter-clockwise winding is the front; not flipped toward the ray), zeros
            on a miss; ``position`` (N, 3) float64, +inf on a miss; ``id`` (N,) uint32, the
            1-based object id, 0 on a miss; ``prim`` (N,) uint32, the triangle index in the
            object, ``INVALID_PRIM`` on a miss; ``bary`` (N, 3) float64, the barycentric
            weights of the triangle's vertices, zeros on a miss or a quadric; ``error`` (N,)
            float64, a bound on ``|distance - exact distance|`` of the same primitive's
            crossing (+inf where none can be made, 0 on a miss); ``certain`` (N,) uint8, 1
            when no value within the bounds could change the ray's decision (see
            docs/buffers-and-cli.md, "Error bounds"); ``uv`` (N, 2) float64, the file's
            texture coordinates interpolated at the hit, as stored, +inf on a miss, a quadric
            or a mesh without them; ``shading_normal`` (N, 3) float64, the file's normals
            interpolated, in the world, unit length (quadrics: the analytic normal), zeros on
            a miss or a mesh without them; ``material`` (N,) uint32, 1-based index into
            :attr:`materials`, 0 on a miss or without material. An output that some objects
            have no data for warns once (:class:`RaycastWarning`).

        Raises
        ------
        ValueError
            Wrong shapes, an unknown output, or a ray with a non-finite origin or direction, a
            zero direction, or a NaN range (the message names the first such ray).
        TypeError
            Arrays that do not hold real numbers.
        """
        names = _names(aovs)
        rays = _Rays(origins, directions, tmin, tmax)
        self._warn_missing([n for n in names if n != "z"])
        try:
            hits = self._scene.cast(rays.flat, names)
        except ValueError as e:
            raise rays.named(e) from None
        return {k: rays.shaped(v) for k, v in hits.items()}

    def occluded(self, origins, directions=None, tmin=0.0, tmax=np.inf) -> np.ndarray:
        """Whether each ray hits anything with ``tmin < t <= tmax``: a bool array of the
        rays' batch shape. Arguments and errors as for :meth:`cast`."""
        rays = _Rays(origins, directions, tmin, tmax)
        try:
            return rays.shaped(self._scene.occluded(rays.flat))
        except ValueError as e:
            raise rays.named(e) from None

    def list_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf) -> dict:
        """Every surface crossing of each ray with ``tmin < t <= tmax``, nearest first.

        A ray through an edge or a vertex shared by triangles of a consistently wound mesh
        crosses it once: the triangles decide by an exact ownership rule, not by a tolerance.

        Returns
        -------
        dict of numpy.ndarray
            In CSR form over the rays flattened in C order (N of them; arguments as for
            :meth:`cast`): ``ray_splits`` (N + 1,) uint64, the hits of ray ``i`` are
            ``ray_splits[i]:ray_splits[i + 1]``; ``t`` float64; ``id`` uint32; ``prim``
            uint32; ``ray_ids`` uint32 (the ray of each hit).
        """
        rays = _Rays(origins, directions, tmin, tmax)
        try:
            splits, t, ids, prims = self._scene.crossings(rays.flat)
        except ValueError as e:
            raise rays.named(e) from None
        ray_ids = np.repeat(
            np.arange(len(splits) - 1, dtype=np.uint32), np.diff(splits).astype(np.int64)
        )
        return {"ray_splits": splits, "t": t, "id": ids, "prim": prims, "ray_ids": ray_ids}

    def count_intersections(self, origins, directions=None, tmin=0.0, tmax=np.inf) -> np.ndarray:
        """The number of surface crossings of each ray, as :meth:`list_intersections`
        counts them: a uint32 array of the rays' batch shape."""
        rays = _Rays(origins, directions, tmin, tmax)
        try:
            splits = self._scene.crossings(rays.flat)[0]
        except ValueError as e:
            raise rays.named(e) from None
        return rays.shaped(np.diff(splits).astype(np.uint32))

    def contains(self, points) -> np.ndarray:
        """Whether each point (an array of shape (..., 3)) lies inside the scene's closed
        surfaces: a bool array of the points' batch shape.

        The parity of the crossings of three rays from the point in fixed directions, by
        majority, so that a ray that grazes an edge cannot decide alone. Meaningful for
        closed, consistently wound surfaces; a point on a surface may count either way.
        """
        p = _batch(points, "points", 3)
        inside = self._scene.contains(np.ascontiguousarray(p.reshape(-1, 3)))
        return inside.reshape(p.shape[:-1])

    def render(self, camera: camera.Camera, width: int, height: int, aovs=("depth",)) -> dict:
        """An image seen by ``camera``: one ray per pixel through its centre, row 0 at the top.

        Parameters
        ----------
        camera : raycast.camera.Camera
            From :attr:`cameras`, :func:`raycast.camera.look_at` or
            :func:`raycast.camera.pinhole` (then ``width`` and ``height`` must be the ones it
            was made for).
        width, height : int
            Image size in pixels.
        aovs : sequence of str
            From :data:`RENDER_OUTPUTS`; ``z`` is the depth along the camera's view axis.

        Returns
        -------
        dict of numpy.ndarray
            Arrays of shape (height, width) or (height, width, 3), with the values and misses
            of :meth:`cast`; bit-identical to the command line's buffers for the same camera.
        """
        names = _names(aovs)
        self._warn_missing(names)
        return self._scene.render(camera, int(width), int(height), names)

    def render_views(self, views, aovs=("depth",)):
        """Renders each of ``views`` (from :func:`raycast.camera.read_views`) at its own size,
        one after another over this scene's one octree.

        Yields
        ------
        (str or None, dict of numpy.ndarray)
            The view's name and its images, as :meth:`render` gives them; one view at a time,
            so that a long list does not hold every image in memory.
        """
        names = _names(aovs)
        self._warn_missing(names)
        for name, view in views:
            width, height = view.size
            yield name, self._scene.render(view, width, height, names)

    def __repr__(self) -> str:
        if self._scene.is_arrays():
            return f"<raycast.Scene from arrays: {len(self.objects)} objects>"
        data, name, *_ = self._scene.source()
        where = data if name is None else f"{name} (bytes)"
        return f"<raycast.Scene {where!s}: {len(self.objects)} objects>"
