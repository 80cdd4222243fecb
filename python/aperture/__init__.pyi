"""Type stubs of the Python module aperture (see docs/python.md)."""

import os
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

__version__: str

_PathLike = str | os.PathLike[str]
_Vec3 = Sequence[float]
_Aovs = str | Iterable[str]
# One camera: (H, W[, C]); cameras of one size: (N, H, W[, C]); of different sizes: a list.
_Result = dict[str, Any]

class Camera:
    """A camera: any model and parameter of the command line, checked by the same schema."""

    def __init__(self, **params: Any) -> None:
        """Camera(type='perspective', **params): keywords are the job file's camera keys
        (fov, size, eye, at, up, intrinsics, ...), checked by name and value (ValueError)."""

    @staticmethod
    def look_at(
        eye: _Vec3,
        at: _Vec3,
        up: _Vec3 = (0.0, 1.0, 0.0),
        fov: float | None = None,
        size: Sequence[int] | None = None,
        **params: Any,
    ) -> Camera:
        """Sugar for Camera(eye=, at=, up=, fov=, size=, **params)."""

    @property
    def params(self) -> dict[str, Any]:
        """The parameters that differ from the defaults: Camera(**cam.params) is the same camera."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def type(self) -> str: ...
    @property
    def spp(self) -> int: ...
    name: str
    """The image name (load_cameras), else ''."""
    def __getstate__(self) -> tuple[dict[str, Any], str]:
        """Pickles as (params, name): unpickling is Camera(**params) with the name set."""
    def __setstate__(self, state: tuple[dict[str, Any], str]) -> None: ...

    def describe(self) -> str:
        """The text of `aperture camera --describe` for this camera."""

class Scene:
    """Meshes by path (.ply, .obj, .gltf, .glb) or procedural spec (several as a list), or one
    mesh from arrays."""

    def __init__(
        self,
        path: _PathLike | Sequence[_PathLike] | None = None,
        *,
        vertices: npt.ArrayLike | None = None,
        faces: npt.ArrayLike | None = None,
        robust: bool = True,
        quality: str = "high",
        compact: bool = False,
        world_space: bool = False,
        bvh_chunk: int = ...,
        aovs: str | Iterable[str] = (),
        gltf_scene: int | None = None,
    ) -> None: ...
    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def ids(self) -> dict[str, list[str]]:
        """{"instance": [...], "mesh": [...], "material": [...]}: the names behind the ids."""

    def triangles(self) -> npt.NDArray[np.float64]:
        """Every triangle in world space, float64 (T, 3, 3), objects in scene order."""

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        """Pickles as the constructor's arguments (absolute paths, or the arrays: warns above
        64 MB), never the BVH; unpickling builds the scene again."""

    @property
    def last_render(self) -> dict[str, float]:
        """seconds, rays, hits, frames, mrays_per_second of the last render call."""

    def render(
        self,
        cameras: Camera | Iterable[Camera],
        aovs: _Aovs = ("color", "depth"),
        spp: int | None = None,
        layers: int = 0,
        normal_frame: str = "world",
        threads: int = 0,
        progress: Callable[[int, int], Any] | None = None,
        packet: int = 16,
        tile: int = 32,
        out: dict[str, np.ndarray] | None = None,
    ) -> _Result:
        """Renders every camera in one parallel loop with the GIL released; name -> array."""

    def render_iter(
        self,
        cameras: Iterable[Camera],
        aovs: _Aovs = ("color", "depth"),
        batch: int = 8,
        progress: Callable[[int, int], Any] | None = None,
        reuse: bool = True,
        **options: Any,
    ) -> Iterator[tuple[Camera, dict[str, np.ndarray]]]:
        """Yields (camera, name -> (H, W[, C]) array), batch cameras at a time; reuse: the next
        batch overwrites the arrays of the one before."""
    def face_visibility(
        self,
        cameras: Camera | Iterable[Camera],
        front_only: bool = False,
        threads: int = 0,
        method: Literal["needed-rays", "all-rays"] = "needed-rays",
    ) -> dict[str, np.ndarray]:
        """Per face: view count, pixels, best view; CSR camera <-> face lists (GIL released).
        method: which centre rays are traced ("all-rays": every one); the same arrays."""

    def point_visibility(
        self,
        points: Any,
        cameras: Camera | Iterable[Camera],
        tol: float = 0.01,
        threads: int = 0,
    ) -> dict[str, np.ndarray]:
        """Per point: the cameras that see it, as CSR index arrays (GIL released)."""
    def scan(
        self,
        lidar: _PathLike,
        trajectory: _PathLike | None = None,
        sweeps: int = 1,
        fields: Iterable[str] | None = None,
        *,
        trajectory_times: _PathLike | None = None,
        start: float | None = None,
        frame: str = "sensor",
        returns: str = "first",
        surfaces: int = 4,
        noise_sigma: float = 0.0,
        dropout: float = 0.0,
        seed: int = 0,
        threads: int = 0,
    ) -> dict[str, np.ndarray]:
        """LiDAR sweeps: one 1-D array per point field (docs/lidar.md; GIL released)."""

def load_cameras(
    path: _PathLike,
    images: Iterable[str] | None = None,
    *,
    width: int | None = None,
    height: int | None = None,
    gltf_scene: int | None = None,
) -> list[Camera]:
    """The cameras of a COLMAP model, transforms.json, OpenCV JSON/YAML or glTF scene (its
    camera nodes; width / height give their image size), each with .name."""

def camera_parameters() -> list[str]:
    """The keyword names Camera() accepts."""

def camera_types() -> list[str]:
    """The camera models Camera(type=...) accepts."""

def read_exr(path: _PathLike) -> dict[str, np.ndarray]:
    """Every AOV of an EXR written by aperture, by AOV name."""

def read(path: _PathLike) -> np.ndarray:
    """A .pfm or .npy written by aperture.write as an array (H, W[, C])."""

def write(path: _PathLike, array: npt.ArrayLike, depth_scale: float = 1000.0, aov: str | None = None) -> int:
    """Writes one AOV to .png (16-bit depth), .pfm, .npy or .tif; returns PNG values out of range."""
