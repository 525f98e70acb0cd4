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

import dataclasses
import errno
import json
import os
import warnings
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from . import _chunks, _content, _raycast, camera, errors
from .errors import RaycastError, RaycastWarning, SceneError, SceneNotFoundError, UsageError

__all__ = [
    "CAST_OUTPUTS",
    "RENDER_OUTPUTS",
    "Quadric",
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
#: Whether a pickled scene refuses to load a file that changed since it was pickled (its
#: content digest differs). Set it to False to load the files as they are now.
CHECK_PICKLED_FILES = True


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
        scene = Scene(_raycast.load_path(os.fspath(path), choice, time, which, chosen))
    except SceneNotFoundError as missing:
        missing.errno, missing.strerror = errno.ENOENT, os.strerror(errno.ENOENT)
        missing.filename = os.fspath(path)
        raise
    scene._files = _content.stamp(Path(path))
    return scene


def _load_pickled(path, digest, scene, time, animation, variants) -> Scene:
    """Unpickles a scene loaded from a file: the file must hold what it held when the scene
    was pickled (unless :data:`CHECK_PICKLED_FILES` is False)."""
    _content.check(Path(path), digest, CHECK_PICKLED_FILES)
    return load(path, scene, time, animation, variants)


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

    def __len__(self) -> int:
        return len(self.flat[0])

    def piece(self, start: int, stop: int) -> tuple:
        """The flat rays ``start..stop``, as the compiled scene takes them."""
        o, d, tmin, tmax = self.flat
        cut = (x[start:stop] if len(x) > 1 else x for x in (tmin, tmax))
        return (o[start:stop], d[start:stop], *cut)

    def shaped(self, array: np.ndarray) -> np.ndarray:
        """A per-ray result (N, ...) in the batch shape."""
        return array.reshape(self.shape + array.shape[1:])

    def named(self, error: ValueError, offset: int = 0) -> ValueError:
        """A compiled scene's error about flat ray ``i`` of a piece starting at ``offset``,
        naming the ray by its batch index."""
        return _renamed(error, "ray", offset, self.shape)

    def run(self, call, progress) -> dict:
        """``call(rays)`` over every ray, in pieces (see ``_chunks``), with ray errors named."""

        def piece(start, stop):
            try:
                return call(self.piece(start, stop))
            except ValueError as e:
                raise self.named(e, start) from None

        found = _chunks.gather(len(self), piece, progress)
        return {k: self.shaped(v) for k, v in found.items()}


def _threads(nthreads) -> int:
    """``nthreads`` checked: a whole number, 0 for all cores."""
    if isinstance(nthreads, bool) or int(nthreads) != nthreads or nthreads < 0:
        raise ValueError(f"nthreads must be a whole number >= 0 (0: all cores), got {nthreads!r}")
    return int(nthreads)


def _renamed(error: ValueError, word: str, offset: int, shape: tuple) -> ValueError:
    """A compiled scene's error about ``word`` ``i`` (``ray 7: ...``) of a piece starting at
    ``offset``, naming it by its index in the batch ``shape``."""
    head, sep, rest = str(error).partition(" ")
    number, space, tail = rest.partition(" ")
    if head != word or not sep or not number.rstrip(":").isdigit():
        return error
    index = np.unravel_index(int(number.rstrip(":")) + offset, shape)
    where = tuple(int(i) for i in index) if len(shape) > 1 else int(index[0])
    return ValueError(f"{word} {where}{':' if number.endswith(':') else ''}{space}{tail}")


def _per_point(points, call, progress) -> dict:
    """``call`` over the (N, 3) rows of ``points`` (shape (..., 3)) in pieces, each result in
    the points' batch shape."""
    p = _batch(points, "points", 3)
    flat = np.ascontiguousarray(p.reshape(-1, 3))

    def piece(start, stop):
        try:
            return call(flat[start:stop])
        except ValueError as e:
            raise _renamed(e, "point", start, p.shape[:-1]) from None

    found = _chunks.gather(len(flat), piece, progress)
    return {k: v.reshape(p.shape[:-1] + v.shape[1:]) for k, v in found.items()}


@dataclasses.dataclass(frozen=True)
class Quadric:
    """A quadric surface for :meth:`Scene.from_objects`, as a file's ``RAYCAST_quadric`` node
    gives one.

    ``coefficients`` are the ten numbers A..J of A x² + B y² + C z² + D xy + E xz + F yz
    + G x + H y + I z + J = 0 in the quadric's own coordinates; ``bounds``, ``(min, max)``
    in those coordinates, clips it to a box (every surface but an ellipsoid needs one);
    ``matrix``, a 4×4 affine matrix acting on column vectors (world = matrix @ [x, y, z, 1]),
    places it in the world (None: as written).
    """

    coefficients: Sequence[float]
    bounds: tuple[Sequence[float], Sequence[float]] | None = None
    matrix: Sequence[Sequence[float]] | np.ndarray | None = None

    def _args(self, name: str) -> tuple:
        """The quadric as ``_raycast.load_objects`` takes it (the matrix column by column)."""
        c = np.asarray(self.coefficients, dtype=np.float64)
        if c.shape != (10,):
            raise ValueError(f"quadric {name!r}: coefficients must be 10 numbers, got {c.shape}")
        bounds = None
        if self.bounds is not None:
            box = np.asarray(self.bounds, dtype=np.float64)
            if box.shape != (2, 3):
                raise ValueError(f"quadric {name!r}: bounds must be (min, max), got {box.shape}")
            bounds = [list(map(float, box[0])), list(map(float, box[1]))]
        m = np.eye(4) if self.matrix is None else np.asarray(self.matrix, dtype=np.float64)
        if m.shape != (4, 4):
            raise ValueError(f"quadric {name!r}: matrix must be 4x4, got {m.shape}")
        return (name, [float(x) for x in c], bounds, [float(x) for x in m.T.ravel()])


def _named(objects, prefix: str) -> list[tuple[str, object]]:
    """``(name, object)`` pairs of a mapping, or of a sequence named ``<prefix>0``, ..."""
    if isinstance(objects, Mapping):
        return [(str(name), value) for name, value in objects.items()]
    return [(f"{prefix}{k}", value) for k, value in enumerate(objects)]


def _mesh_arrays(vertices, faces) -> tuple[np.ndarray, np.ndarray]:
    """``vertices`` as (N, 3) float64 and ``faces`` as (M, 3) int64, C-ordered."""
    v = np.ascontiguousarray(vertices, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces)
    if f.size and not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"faces must be integers, got {f.dtype}")
    return v, np.ascontiguousarray(f, dtype=np.int64).reshape(-1, 3)


def _load_objects(meshes, quadrics) -> Scene:
    """A pickled scene made from arrays, made again."""
    return Scene(_raycast.load_objects(meshes, quadrics))


def _names(outputs: Iterable[str] | str) -> list[str]:
    if isinstance(outputs, str):
        return [outputs]
    return list(dict.fromkeys(outputs))


class Scene:
    """A loaded scene with its octree, ready for queries. Made by :func:`load` or
    :func:`load_bytes`; pickles as its path (or its bytes) and loads again on unpickling."""

    def __init__(self, compiled: _raycast._Scene):
        self._scene = compiled
        # For a scene loaded from a file: its files' sizes and times when it was loaded.
        self._files = None
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
        return Scene(_raycast.load_arrays(*_mesh_arrays(vertices, faces)))

    @staticmethod
    def from_objects(meshes=(), quadrics=()) -> Scene:
        """A scene of several objects from arrays and coefficients, without a file.

        Parameters
        ----------
        meshes : mapping or sequence
            ``{name: (vertices, faces)}``, or a sequence of ``(vertices, faces)`` (named
            ``mesh0``, ``mesh1``, ...), each as :meth:`from_arrays` takes them.
        quadrics : mapping or sequence of Quadric
            ``{name: Quadric}``, or a sequence of :class:`Quadric` (named ``quadric0``, ...).

        Returns
        -------
        Scene
            One object per mesh, then one per quadric, with ids 1, 2, ... in that order;
            ``prim`` is a face's row in its ``faces``, 0 for a quadric. Pickles as its arrays.

        Raises
        ------
        ValueError
            The first mesh or quadric that is wrong, named, and what is wrong with it (as
            :meth:`from_arrays` for a mesh; for a quadric, coefficients that are not finite
            or describe no surface, an unbounded surface without ``bounds``, a box whose min
            exceeds its max, a matrix that is not affine and invertible).
        """
        mesh_args = [(name, *_mesh_arrays(v, f)) for name, (v, f) in _named(meshes, "mesh")]
        quadric_args = [q._args(name) for name, q in _named(quadrics, "quadric")]
        return Scene(_raycast.load_objects(mesh_args, quadric_args))

    def __reduce__(self):
        arrays = self._scene.arrays()
        if arrays is not None:
            return (_load_objects, arrays)
        data, name, choice, time, animation, variants = self._scene.source()
        if name is None:
            digest = _content.digest_unchanged_since(Path(data), self._files)
            return (_load_pickled, (data, digest, choice, time, animation, dict(variants) or None))
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
        posed = Scene(self._scene.at(float(time)))
        posed._files = self._files
        return posed

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
        *,
        nthreads: int = 0,
        progress=None,
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
        nthreads : int
            Threads to trace on (0, the default: one per core; more than the cores are
            brought down to the cores). The results do not depend on it.
        progress : callable or tqdm-like, optional
            Told how far a long call got: called as ``progress(done, total)`` (rays), or, for
            an object with ``update`` (a ``tqdm`` bar), given the rays done since the last
            report. Every query and :meth:`render` take ``nthreads`` and ``progress``; all of
            them run in pieces of a few hundredths of a second, so that Ctrl-C interrupts
            them (``KeyboardInterrupt``) within about 0.1 s.

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
        threads = _threads(nthreads)
        return rays.run(lambda flat: self._scene.cast(flat, names, threads), progress)

    def occluded(
        self, origins, directions=None, tmin=0.0, tmax=np.inf, *, nthreads=0, progress=None
    ) -> np.ndarray:
        """Whether each ray hits anything with ``tmin < t <= tmax``: a bool array of the
        rays' batch shape. Arguments and errors as for :meth:`cast`."""
        rays = _Rays(origins, directions, tmin, tmax)
        threads = _threads(nthreads)
        found = rays.run(lambda flat: {"hit": self._scene.occluded(flat, threads)}, progress)
        return found["hit"]

    def list_intersections(
        self, origins, directions=None, tmin=0.0, tmax=np.inf, *, nthreads=0, progress=None
    ) -> dict:
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
        threads = _threads(nthreads)

        def piece(start, stop):
            try:
                return self._scene.crossings(rays.piece(start, stop), threads)
            except ValueError as e:
                raise rays.named(e, start) from None

        # Each piece's lists are kept per column and joined column by column, each piece's
        # column let go once copied: the peak is the output plus one column.
        splits = np.zeros(len(rays) + 1, dtype=np.uint64)
        parts = []
        for start, stop, (own, t, ids, prims) in _chunks.pieces(len(rays), piece, progress):
            splits[start + 1 : stop + 1] = own[1:] + splits[start]
            counts = np.diff(own).astype(np.intp)
            ray_ids = np.repeat(np.arange(start, stop, dtype=np.uint32), counts)
            parts.append([t, ids, prims, ray_ids])

        def joined(k):
            whole = np.concatenate([part[k] for part in parts])
            for part in parts:
                part[k] = None
            return whole

        t, ids, prims, ray_ids = (joined(k) for k in range(4))
        return {"ray_splits": splits, "t": t, "id": ids, "prim": prims, "ray_ids": ray_ids}

    def count_intersections(
        self, origins, directions=None, tmin=0.0, tmax=np.inf, *, nthreads=0, progress=None
    ) -> np.ndarray:
        """The number of surface crossings of each ray, as :meth:`list_intersections`
        counts them: a uint32 array of the rays' batch shape."""
        rays = _Rays(origins, directions, tmin, tmax)
        threads = _threads(nthreads)

        def count(flat):
            return {"n": np.diff(self._scene.crossings(flat, threads)[0]).astype(np.uint32)}

        return rays.run(count, progress)["n"]

    def contains(self, points, *, nthreads=0, progress=None) -> np.ndarray:
        """Whether each point (an array of shape (..., 3)) lies inside the scene's closed
        surfaces: a bool array of the points' batch shape.

        The parity of the crossings of three rays from the point in fixed directions, by
        majority, so that a ray that grazes an edge cannot decide alone; a closed ellipsoid
        counts by the sign of its polynomial at the point instead, so a ray tangent to it
        cannot flip the count. Meaningful for closed, consistently wound surfaces; a point on
        a surface may count either way.
        """
        threads = _threads(nthreads)
        found = _per_point(points, lambda p: {"in": self._scene.contains(p, threads)}, progress)
        return found["in"]

    def closest_points(self, points, *, nthreads=0, progress=None) -> dict:
        """The nearest surface point of each query point (an array of shape (..., 3)).

        Found through the octree and measured exactly in float64 on the triangle (the error
        is a few ulps of the triangle's size; on the face, of the distance itself), and on a
        clipped quadric by the Lagrange condition in its eigenbasis and its clip box's faces
        and edges (a few ulps of the point's distance from the box centre plus the box's size
        and position; docs/python.md, "Distances").

        Returns
        -------
        dict of numpy.ndarray
            In the points' batch shape (written (N,)): ``point`` (N, 3) float64;
            ``distance`` (N,) float64; ``id`` (N,) uint32, the 1-based object id; ``prim``
            (N,) uint32, the triangle's (or quadric's) index in the object; ``bary`` (N, 3)
            float64, the nearest point's barycentric weights of the triangle's vertices (for a
            quadric: the point in the quadric's own coordinates); ``normal`` (N, 3) float64,
            the triangle's unit geometric normal (a quadric's unit gradient). An empty scene
            gives +inf points and distances, id 0 and ``INVALID_PRIM``.
        """
        threads = _threads(nthreads)
        return _per_point(
            points, lambda p: _raycast.closest_points(self._scene, p, threads), progress
        )

    def distance(self, points, *, nthreads=0, progress=None) -> np.ndarray:
        """The distance from each point (shape (..., 3)) to the nearest surface: the
        ``distance`` of :meth:`closest_points`."""
        return self.closest_points(points, nthreads=nthreads, progress=progress)["distance"]

    def signed_distance(
        self, points, sign: str = "crossings", *, nthreads=0, progress=None
    ) -> np.ndarray:
        """The signed distance of each point (shape (..., 3)): negative inside, positive
        outside, and exactly 0 where the side cannot be certain.

        ``sign="crossings"``: the parity of exact watertight crossing counts (see
        :meth:`contains`), exact for closed, consistently wound meshes; a point nearer to a
        surface than the test's rounding margin (about 1e-14 of the scene's size) gets 0.
        ``sign="winding"``: the generalised winding number above 1/2, for meshes that are not
        closed (it visits every triangle for every point). Quadrics: an ellipsoid that its clip
        box leaves whole has the side of its polynomial's sign; any other quadric is open, with
        no inside, and raises ValueError naming the object (as does ``sign="winding"`` on any
        quadric); :meth:`distance` is defined for them.
        """
        threads = _threads(nthreads)

        def signed(p):
            return {"d": _raycast.signed_distance(self._scene, p, sign, threads)}

        return _per_point(points, signed, progress)["d"]

    def occupancy(self, points, nsamples: int = 1, *, nthreads=0, progress=None) -> np.ndarray:
        """1.0 for each point (shape (..., 3)) inside the closed surfaces, else 0.0 (float32,
        as Open3D's ``compute_occupancy``): :meth:`contains`. ``nsamples`` is accepted for
        Open3D's signature; the crossing parity is exact, so no votes are needed."""
        if int(nsamples) < 1:
            raise ValueError(f"nsamples must be at least 1, got {nsamples}")
        return self.contains(points, nthreads=nthreads, progress=progress).astype(np.float32)

    def render(
        self,
        camera: camera.Camera,
        width: int,
        height: int,
        aovs=("depth",),
        *,
        nthreads: int = 0,
        progress=None,
    ) -> dict:
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
            ``nthreads`` and ``progress`` (told image rows) as for :meth:`cast`.
        """
        width, height, names = int(width), int(height), _names(aovs)
        self._warn_missing(names)
        threads = _threads(nthreads)

        def rows(first, last):
            return self._scene.render(camera, width, height, names, (first, last), threads)

        return _chunks.gather(height, rows, progress, unit=max(1, width))

    def render_views(self, views, aovs=("depth",), *, nthreads=0):
        """Renders each of ``views`` (from :func:`raycast.camera.read_views`) at its own size,
        one after another over this scene's one octree.

        Yields
        ------
        (str or None, dict of numpy.ndarray)
            The view's name and its images, as :meth:`render` gives them; one view at a time,
            so that a long list does not hold every image in memory.
        """
        for name, view in views:
            width, height = view.size
            yield name, self.render(view, width, height, aovs, nthreads=nthreads)

    def __repr__(self) -> str:
        if self._scene.is_arrays():
            return f"<raycast.Scene from arrays: {len(self.objects)} objects>"
        data, name, *_ = self._scene.source()
        where = data if name is None else f"{name} (bytes)"
        return f"<raycast.Scene {where!s}: {len(self.objects)} objects>"
