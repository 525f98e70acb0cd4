# Type stubs of the compiled module raycast._raycast (python/src/*.rs). The public API is
# raycast/__init__.py, which checks shapes and dtypes and hands over float64 arrays.
import os
from typing import Any, final

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
#: A quadric for load_objects: name, coefficients A..J, clip box (min, max) or None, and the
#: object-to-world matrix column by column.
QuadricArgs = tuple[str, list[float], list[list[float]] | None, list[float]]
# (origins (N, 3), directions (N, 3), tmin (N,) or (1,), tmax (N,) or (1,)), all float64
Rays = tuple[F64, F64, F64, F64]

@final
class Camera:
    @property
    def name(self) -> str: ...
    @property
    def cam_to_world(self) -> list[list[float]]: ...
    @property
    def size(self) -> tuple[int, int] | None: ...

@final
class _Scene:
    def cast(self, rays: Rays, outputs: list[str], nthreads: int) -> dict[str, np.ndarray]: ...
    def occluded(self, rays: Rays, nthreads: int) -> npt.NDArray[np.bool_]: ...
    def crossings(
        self, rays: Rays, nthreads: int
    ) -> tuple[npt.NDArray[np.uint64], F64, npt.NDArray[np.uint32], npt.NDArray[np.uint32]]: ...
    def contains(self, points: F64, nthreads: int) -> npt.NDArray[np.bool_]: ...
    def render(
        self,
        camera: Camera,
        width: int,
        height: int,
        outputs: list[str],
        rows: tuple[int, int],
        nthreads: int,
    ) -> dict[str, np.ndarray]: ...
    def objects(self) -> list[dict]: ...
    def materials(self) -> list[str]: ...
    def attribute_warnings(self, outputs: list[str]) -> list[str]: ...
    def triangles(self, id: int) -> F64: ...
    def bounds(self) -> list[list[float]]: ...
    def cameras(self) -> list[Camera]: ...
    def info_json(self) -> str: ...
    def at(self, time: float) -> _Scene: ...
    def is_arrays(self) -> bool: ...
    def arrays(
        self,
    ) -> tuple[list[tuple[str, F64, npt.NDArray[np.int64]]], list[QuadricArgs]] | None: ...
    def source(
        self,
    ) -> tuple[
        os.PathLike | bytes,
        os.PathLike | None,
        str | None,
        float | None,
        str | None,
        list[tuple[str, str]],
    ]: ...

def load_path(
    path: str,
    scene: str | None = None,
    time: float | None = None,
    animation: str | None = None,
    variants: list[tuple[str, str]] | None = None,
) -> _Scene: ...
def load_bytes(
    data: bytes,
    name: str,
    scene: str | None = None,
    time: float | None = None,
    animation: str | None = None,
) -> _Scene: ...
def load_arrays(vertices: F64, faces: npt.NDArray[np.int64]) -> _Scene: ...
def load_objects(
    meshes: list[tuple[str, F64, npt.NDArray[np.int64]]], quadrics: list[QuadricArgs]
) -> _Scene: ...
def look_at(
    eye: tuple[float, float, float],
    target: tuple[float, float, float],
    up: tuple[float, float, float] = (0.0, 1.0, 0.0),
    yfov_deg: float = 45.0,
) -> Camera: ...
def pinhole(k: F64, cam_to_world: F64, width: int, height: int) -> Camera: ...
def read_views(
    path: str | os.PathLike, width: int | None = None, height: int | None = None
) -> list[tuple[str | None, Camera]]: ...
def closest_points(scene: _Scene, points: F64, nthreads: int) -> dict[str, npt.NDArray[Any]]: ...
def signed_distance(scene: _Scene, points: F64, sign: str, nthreads: int) -> F64: ...
