"""aperture: the fastest CPU route from a mesh and a set of cameras to a dataset.

Embree ray casting of meshes into depth, distance, normals, positions and ids, with every
camera model and camera file of the ``aperture`` command line. The work is done by the same
C++ libraries (``aperture._aperture``); this package only converts arguments.

    import aperture
    scene = aperture.Scene("mesh.ply")
    cams = aperture.load_cameras("sparse/0")
    out = scene.render(cams, aovs=["depth", "normal", "primid"])
    out["depth"]  # float32 (len(cams), H, W)

See docs/python.md for conventions, memory ownership, the GIL and errors.
"""

from __future__ import annotations

import os
import socket
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from ._aperture import (
    _BVH_CHUNK_DEFAULT,
    Camera,
    __version__,
    _Scene,
    _write,
    _write_npy,
    camera_parameters,
    camera_types,
    load_cameras as _load_cameras,
    read as _read,
    read_exr as _read_exr,
)

__all__ = [
    "Camera",
    "Scene",
    "__version__",
    "camera_parameters",
    "camera_types",
    "load_cameras",
    "read",
    "read_exr",
    "write",
]


def _look_at(
    eye: Sequence[float],
    at: Sequence[float],
    up: Sequence[float] = (0.0, 1.0, 0.0),
    fov: float | None = None,
    size: Sequence[int] | None = None,
    **params: Any,
) -> Camera:
    """A camera at ``eye`` looking at ``at``: sugar for ``Camera(eye=, at=, up=, fov=, size=,
    **params)`` (fov in degrees along fov_axis, vertical by default; size (width, height))."""
    keywords: dict[str, Any] = dict(eye=eye, at=at, up=up, **params)
    if fov is not None:
        keywords["fov"] = fov
    if size is not None:
        keywords["size"] = size
    return Camera(**keywords)


Camera.look_at = staticmethod(_look_at)  # type: ignore[attr-defined]


def load_cameras(
    path: str | os.PathLike[str],
    images: Iterable[str] | None = None,
    *,
    width: int | None = None,
    height: int | None = None,
    gltf_scene: int | None = None,
) -> list[Camera]:
    """The cameras of a camera file the command line accepts: a COLMAP model folder (text or
    binary), a transforms.json (nerfstudio, NeRF, instant-ngp), an OpenCV JSON/YAML, or the
    camera nodes of a glTF scene (.gltf, .glb; ``gltf_scene`` picks the scene, default the
    file's). Each Camera has ``.name``, the image's name (a glTF camera's: its node's).
    ``images`` selects images by name, in that order (default: all, in the file's order, which
    is the order ``aperture batch`` renders). A glTF camera carries no image size: ``width``
    and ``height`` give it; with one of them the other follows the camera's aspect ratio
    (aspectRatio, or xmag / ymag), with neither the height is 540 (docs/cameras.md, glTF
    cameras). Raises FileNotFoundError for a missing path, ValueError for bad contents or an
    unknown image name."""
    return _load_cameras(
        os.fspath(path),
        None if images is None else [str(i) for i in images],
        width,
        height,
        gltf_scene,
    )


def read_exr(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Every AOV of an EXR written by aperture (render, batch), by AOV name as render returns
    them: float32 or uint32 arrays (H, W) or (H, W, C), row 0 at the top. OSError for a
    missing or unreadable file, ValueError for a bad one."""
    return _read_exr(os.fspath(path))


def read(path: str | os.PathLike[str]) -> np.ndarray:
    """A .pfm or .npy written by aperture.write (or the command line) as an array (H, W) or
    (H, W, C), row 0 at the top (a PFM's bottom-to-top rows are turned over)."""
    return _read(os.fspath(path))


def _aov_list(aovs: str | Iterable[str]) -> str:
    return aovs if isinstance(aovs, str) else ",".join(str(a) for a in aovs)


def _camera_list(cameras: Camera | Iterable[Camera]) -> list[Camera]:
    return [cameras] if isinstance(cameras, Camera) else list(cameras)


class Scene:
    """A scene to render: meshes by path (``.ply``, ``.obj``, ``.gltf``, ``.glb``) or procedural
    spec (``"procedural:sphere?radius=2"``), several at once as a list, or one mesh from arrays
    (``vertices`` (n, 3) float32/float64 world positions, ``faces`` (m, 3) integer indices).
    ``Scene()`` is the command line's default procedural scene. Options are the scene flags of
    the command line: ``robust`` (watertight traversal, ``--no-robust`` when False),
    ``quality`` (``--bvh-quality``: low, medium, high), ``compact``, ``world_space`` and
    ``bvh_chunk`` (``--bvh-chunk``: a mesh of more triangles is built as BVHs of this many, put
    in spatial order first when its order is scattered, primIDs unchanged; 0: one BVH).
    ``aovs``: the AOVs renders will ask for, so that the mesh data they read (face./vertex.
    properties, vertex normals for shading-normal) is loaded with the meshes; without it, the
    first render that needs more loads the files again with it (once). ``gltf_scene``: the
    scene of the glTF files to load (``--gltf-scene``; default: each file's own)."""

    def __init__(
        self,
        path: str | os.PathLike[str] | Sequence[str | os.PathLike[str]] | None = None,
        *,
        vertices: Any = None,
        faces: Any = None,
        robust: bool = True,
        quality: str = "high",
        compact: bool = False,
        world_space: bool = False,
        bvh_chunk: int = _BVH_CHUNK_DEFAULT,
        aovs: str | Iterable[str] = (),
        gltf_scene: int | None = None,
    ) -> None:
        options = dict(
            robust=robust, quality=quality, compact=compact, world_space=world_space, bvh_chunk=bvh_chunk
        )
        if vertices is not None or faces is not None:
            if path is not None:
                raise ValueError("Scene: give a path or vertices= and faces=, not both")
            if vertices is None or faces is None:
                raise ValueError("Scene: vertices= and faces= go together")
            v, f = _mesh_arrays(vertices, faces)
            self._spec: dict[str, Any] = dict(vertices=v, faces=f, **options)
            self._scene = _Scene._from_arrays(v, f, name="arrays", **options)
            return
        if path is None:
            paths: list[str] = []
        elif isinstance(path, (str, os.PathLike)):
            paths = [os.fspath(path)]
        else:
            paths = [os.fspath(p) for p in path]
        self._spec = dict(path=[_absolute_mesh_path(p) for p in paths], aovs=_aov_list(aovs),
                          gltf_scene=gltf_scene, **options)
        self._scene = _Scene._from_paths(paths, aovs=_aov_list(aovs), gltf_scene=gltf_scene, **options)

    @property
    def bounds(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """World bounds of the scene: ((x, y, z) low, (x, y, z) high)."""
        return self._scene.bounds

    @property
    def triangle_count(self) -> int:
        """Triangles in the scene."""
        return self._scene.triangle_count

    @property
    def ids(self) -> dict[str, list[str]]:
        """The names behind the id AOVs: ``{"instance": [...], "mesh": [...], "material":
        [...]}``, each list indexed by its id (the ``instance``, ``mesh`` and ``material`` AOVs).
        A glTF file gives its nodes, meshes and materials (unnamed ones ``node_<k>``, ...), an
        OBJ its objects and materials, a PLY its stem; several files are numbered one after the
        other."""
        return self._scene.ids

    def triangles(self) -> np.ndarray:
        """Every triangle of the scene in world space, a new float64 array (T, 3, 3): [t, c]
        is corner c (index order) of triangle t. Objects in scene order (the files in order; a
        glTF file's mesh nodes depth first, a mesh placed by several nodes once per node),
        each object's triangles in primID order. Positions are the float32 vertices as stored
        (relative to their anchor), placed in double: compare to float precision."""
        return self._scene.triangles()

    @property
    def last_render(self) -> dict[str, float]:
        """What the last render call measured: seconds (wall), rays, hits, frames and
        mrays_per_second (rays traced / seconds)."""
        return self._scene.last_render

    def render(
        self,
        cameras: Camera | Iterable[Camera],
        aovs: str | Iterable[str] = ("color", "depth"),
        spp: int | None = None,
        layers: int = 0,
        normal_frame: str = "world",
        threads: int = 0,
        progress: Callable[[int, int], Any] | None = None,
        packet: int = 16,
        tile: int = 32,
        out: dict[str, np.ndarray] | None = None,
    ) -> dict[str, Any]:
        """Renders every camera in one parallel loop over (camera, tile), with the GIL released.

        ``aovs``: names as ``--aov`` takes them (color depth distance normal position primid
        geomid shading-normal, ``all``, face.NAME, vertex.NAME), a list or a comma-separated
        string. ``spp`` overrides every camera's samples per pixel; ``layers`` records the
        first K surfaces; ``normal_frame`` is world, opencv or opengl; ``threads`` 0 uses every
        core; ``progress(done, total)`` is called after each finished frame (an exception it
        raises stops the render and is raised here).

        Returns name -> array. One Camera: (H, W) or (H, W, C). A list of cameras of one size:
        (N, H, W) or (N, H, W, C). A list of cameras of different sizes: name -> list of
        (H, W[, C]) arrays. float32 (color, depth, distance, normal, position,
        shading-normal) or uint32 (primid, geomid, face./vertex. properties; 0xFFFFFFFF for a
        miss); depth and distance are +inf for a miss, normals 0.

        ``out``: name -> array to render that AOV into (some or all of them), of the shape and
        dtype the AOV is returned with, C-contiguous and writeable (one camera or cameras of
        one size; not the layered ``layers.*``). The result holds those very arrays (no copy);
        a wrong shape or dtype is a ValueError naming the AOV. Every value is written, misses
        included."""
        single = isinstance(cameras, Camera)
        cams: Any = cameras if single else _camera_list(cameras)
        return self._scene._render(
            cams, _aov_list(aovs), spp, layers, normal_frame, threads, progress, packet, tile, out
        )

    def render_iter(
        self,
        cameras: Iterable[Camera],
        aovs: str | Iterable[str] = ("color", "depth"),
        batch: int = 8,
        progress: Callable[[int, int], Any] | None = None,
        reuse: bool = True,
        **options: Any,
    ) -> Iterator[tuple[Camera, dict[str, Any]]]:
        """Yields (camera, name -> (H, W[, C]) array) per camera, rendering ``batch`` cameras
        at a time (one parallel loop each), so memory stays that of one batch however many
        cameras there are. ``cameras`` may be any iterable (a generator too); ``progress``
        gets (done, total) with total the number known so far. Other options as render.

        ``reuse`` (default True): each batch renders into the arrays of the batch before
        (``render(..., out=...)``) when its cameras have the same size, so the arrays a
        batch yielded are OVERWRITTEN by the next batch: copy what you keep
        (``arr.copy()``). ``reuse=False`` renders every batch into new arrays."""
        cams = iter(cameras)
        done = 0
        if batch < 1:
            raise ValueError(f"render_iter: batch {batch} must be >= 1")
        if "out" in options:
            raise TypeError("render_iter: out= is not an option here (see reuse)")
        previous: dict[str, Any] | None = None
        while True:
            chunk = [c for _, c in zip(range(batch), cams)]
            if not chunk:
                return
            start = done

            def chunk_progress(k: int, n: int, start: int = start) -> None:
                if progress is not None:
                    progress(start + k, start + n)

            into = _reusable(previous, chunk) if reuse else None
            out = self.render(chunk, aovs, progress=chunk_progress, out=into, **options)
            done += len(chunk)
            for k, camera in enumerate(chunk):
                yield camera, {name: value[k] for name, value in out.items()}
            previous = out if reuse else None
            del out

    def face_visibility(
        self,
        cameras: Camera | Iterable[Camera],
        front_only: bool = False,
        threads: int = 0,
        method: str = "needed-rays",
    ) -> dict[str, np.ndarray]:
        """Which faces of the scene's one mesh each camera sees, with the GIL released; the
        arrays of ``aperture visibility``'s .npz (docs/visibility.md), camera k being the k-th
        of ``cameras``. A camera sees a face when the face's centroid projects inside its image
        (through the full lens model, where it is invertible) and the centre ray through that
        position hits the face first; ``front_only`` also requires the ray to meet the side the
        counter-clockwise winding faces.

        Returns ``face_view_count`` (uint32, per face), ``face_pixels`` (uint64: pixel-centre
        rays over all cameras whose first hit is the face, the bincount of the primid renders),
        ``best_view`` (int32: the camera seeing the face with the largest projected area in
        pixels, -1 if none) and scipy-style CSR index arrays ``camera_faces_indptr`` /
        ``camera_faces_indices`` and ``face_cameras_indptr`` / ``face_cameras_indices``.

        ``method`` only changes which centre rays are traced, never the result:
        ``"needed-rays"`` (default) skips the rays that cannot change it (with ``front_only``,
        those meeting a face from behind); ``"all-rays"`` traces one per face whose centroid
        projects inside the image, the reference the first is tested against."""
        return self._scene._face_visibility(_camera_list(cameras), front_only, threads, method)

    def point_visibility(
        self,
        points: Any,
        cameras: Camera | Iterable[Camera],
        tol: float = 0.01,
        threads: int = 0,
    ) -> dict[str, np.ndarray]:
        """Which cameras see each world point of ``points`` ((N, 3), converted to float64), with
        the GIL released. Camera c sees point p when p projects inside its image and no surface
        lies on the camera's ray to p closer than d * (1 - tol), d the distance from the ray's
        origin to p (``--occlusion-tolerance``). Returns ``point_cameras_indptr`` (uint64,
        N + 1) and ``point_cameras_indices`` (uint32), scipy-style CSR index arrays."""
        p = np.ascontiguousarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"point_visibility: points must have shape (N, 3), not {p.shape}")
        return self._scene._point_visibility(p, _camera_list(cameras), tol, threads)

    def scan(
        self,
        lidar: str | os.PathLike[str],
        trajectory: str | os.PathLike[str] | None = None,
        sweeps: int = 1,
        fields: Iterable[str] | None = None,
        *,
        trajectory_times: str | os.PathLike[str] | None = None,
        start: float | None = None,
        frame: str = "sensor",
        returns: str = "first",
        surfaces: int = 4,
        noise_sigma: float = 0.0,
        dropout: float = 0.0,
        seed: int = 0,
        threads: int = 0,
    ) -> dict[str, np.ndarray]:
        """LiDAR sweeps of the scene (``aperture scan``; docs/lidar.md): ``lidar`` a sensor spec
        (aperture JSON, Ouster metadata JSON, Velodyne YAML, Livox CSV) or a preset name,
        ``trajectory`` TUM or KITTI poses (with ``trajectory_times``; None: a static sensor at
        the origin). Returns a dict of 1-D NumPy arrays, one per field, the hits of every
        sweep in firing order: x y z (in ``frame``: sensor, world, sweep-start), range (m),
        time (ns from the sweep's start), ring, column, azimuth (rad), incidence, intensity,
        primid, geomid, instance, return_number and returns (``returns="all"``), the face
        properties named in ``fields``, and sweep. ``fields`` keeps only the named ones (a name
        that is no standard field is a face property of the mesh). The scan traces this
        Scene's own BVH, so every option it was built with holds (``gltf_scene``,
        ``bvh_chunk``, ...). What a scan reads beyond positions is loaded as a render's mesh
        data is: the face properties of ``fields`` (and ``reflectance``, when every mesh is a
        PLY file with it) up front with ``aovs=["face.NAME", ...]``, else the first scan that
        needs one loads the files again with it (once); a property a file lacks is a ValueError
        naming it, and a Scene of arrays has none (a ValueError naming the property). The first
        scan asking for last, strongest or all returns builds the BVH again (files: loads
        them again) with Embree's context filter, which the layers' search of surfaces uses.
        The GIL is released while it loads and traces."""
        wanted = None if fields is None else [str(f) for f in fields]
        return self._scene._scan(
            os.fspath(lidar),
            None if trajectory is None else os.fspath(trajectory),
            "" if trajectory_times is None else os.fspath(trajectory_times),
            sweeps,
            start,
            frame,
            returns,
            surfaces,
            wanted,
            noise_sigma,
            dropout,
            seed,
            threads,
        )

    def closest_points(self, points: Any, threads: int = 0) -> dict[str, np.ndarray]:
        """The closest surface point to each of ``points`` ((N, 3) float32 or float64, world
        coordinates; docs/queries.md). Returns ``points`` (N, 3) float64 (the closest points),
        ``distance`` (N) float64, ``primid`` (N) uint32 (the triangle as loaded),
        ``barycentric`` (N, 3) float64 (the weights of its three corners), ``geomid`` (N)
        uint32 (the object) and ``instance`` (N) uint32 (the instance id). Computed in double on
        every core (``threads``: 0 = all), the GIL released. A point that is not finite gets NaN
        and ids 0xFFFFFFFF (a RuntimeWarning counts them)."""
        arrays, _ = self._point_queries("closest_points", points, "closest,distance", None, 1, threads)
        return arrays

    def distance(self, points: Any, threads: int = 0) -> np.ndarray:
        """The unsigned distance from each of ``points`` ((N, 3)) to the surface, (N) float64."""
        arrays, _ = self._point_queries("distance", points, "distance", None, 1, threads)
        return arrays["distance"]

    def signed_distance(
        self, points: Any, method: str | None = None, parity_directions: int = 1, threads: int = 0
    ) -> np.ndarray:
        """The distance to the surface, negative inside, (N) float64 (docs/queries.md).
        ``method``: how inside is decided: ``"parity"`` (ray crossings; ``parity_directions``
        odd: the majority over that many fixed directions), ``"winding"`` (generalized winding
        number) or None (parity for a closed mesh, else winding). The method that ran is
        ``scene.last_query["method"]``."""
        arrays, _ = self._point_queries("signed_distance", points, "sign", method, parity_directions, threads)
        return arrays["signed_distance"]

    def occupancy(
        self, points: Any, method: str | None = None, parity_directions: int = 1, threads: int = 0
    ) -> np.ndarray:
        """1 where a point of ``points`` is inside the surface, else 0, (N) uint8; ``method`` as
        signed_distance's, the one that ran in ``scene.last_query["method"]``. A point that is
        not finite gets 0."""
        arrays, _ = self._point_queries("occupancy", points, "occupancy", method, parity_directions, threads)
        return arrays["occupancy"]

    @property
    def last_query(self) -> dict[str, Any]:
        """What the last point query of this scene did: ``what`` (the method called),
        ``points``, ``non_finite`` (points that got NaN) and ``method`` (the inside method that
        ran, ``"parity"`` or ``"winding"``; None for queries without a sign)."""
        return dict(self.__dict__.get("_last_query", {}))

    def count_intersections(self, origins: Any, directions: Any, threads: int = 0) -> np.ndarray:
        """The number of surfaces each ray crosses, (N) uint32: rays from ``origins`` along
        ``directions`` (both (N, 3), float32 or float64, world; directions need not be unit),
        from t = 0 on. A triangle counts once; triangles met at exactly the same float t count
        once (a ray through a shared edge). A ray that is not finite counts 0."""
        o, d = self._rays("count_intersections", origins, directions)
        counts, non_finite = self._scene._count_intersections(o, d, threads)
        _warn_non_finite("count_intersections", non_finite, len(o), "rays")
        return counts

    def list_intersections(self, origins: Any, directions: Any, threads: int = 0) -> dict[str, np.ndarray]:
        """Every surface along each ray, nearest first, as count_intersections counts them:
        ``ray_splits`` (N + 1) uint64 (ray k's hits are [ray_splits[k], ray_splits[k + 1])),
        ``ray_ids`` uint32, ``t`` float64 (in units of |direction|), ``primid`` and ``geomid``
        uint32."""
        o, d = self._rays("list_intersections", origins, directions)
        arrays, non_finite = self._scene._list_intersections(o, d, threads)
        _warn_non_finite("list_intersections", non_finite, len(o), "rays")
        return arrays

    def signed_distance_grid(
        self,
        bounds: Any,
        resolution: int | Sequence[int],
        path: str | os.PathLike[str] | None = None,
        method: str | None = None,
        threads: int = 0,
    ) -> np.ndarray:
        """Signed distances on a regular grid, (Z, Y, X) float32: ``bounds`` ((x0, y0, z0),
        (x1, y1, z1)), ``resolution`` the samples per axis (one int, or (nx, ny, nz), each >=
        2), sample (i, j, k) at (x0 + k (x1 - x0) / (nx - 1), y0 + j ..., z0 + i ...): both
        bounds are samples. Computed as signed_distance, one z slab at a time; ``path``: also
        written there as .npy (atomically)."""
        lo, hi = _grid_bounds(bounds)
        n = _grid_resolution(resolution)
        if path is not None and not os.fspath(path).lower().endswith(".npy"):
            raise ValueError(f"signed_distance_grid: path '{os.fspath(path)}' must end in .npy")
        xs, ys, zs = (np.linspace(lo[a], hi[a], n[a]) for a in range(3))
        out = np.empty((n[2], n[1], n[0]), dtype=np.float32)
        gy, gx = np.meshgrid(ys, xs, indexing="ij")
        slab = np.empty((n[1] * n[0], 3), dtype=np.float64)
        slab[:, 0], slab[:, 1] = gx.ravel(), gy.ravel()
        methods = set()
        for i, z in enumerate(zs):
            slab[:, 2] = z
            out[i] = self.signed_distance(slab, method, threads=threads).reshape(n[1], n[0])
            methods.add(self.last_query["method"])
        self._last_query = {"what": "signed_distance_grid", "points": out.size,
                            "non_finite": 0, "method": methods.pop() if methods else None}
        if path is not None:
            _write_npy(os.fspath(path), out)
        return out

    def _point_queries(
        self, fn: str, points: Any, what: str, method: str | None, parity_directions: int, threads: int
    ) -> tuple[dict[str, np.ndarray], str]:
        p = _query_points(fn, "points", points)
        arrays, non_finite, used = self._scene._point_queries(
            p, what, "automatic" if method is None else method, parity_directions, threads
        )
        _warn_non_finite(fn, non_finite, len(p), "points")
        self._last_query = {"what": fn, "points": len(p), "non_finite": non_finite, "method": used or None}
        return arrays, used

    @staticmethod
    def _rays(fn: str, origins: Any, directions: Any) -> tuple[np.ndarray, np.ndarray]:
        o = _query_points(fn, "origins", origins)
        d = _query_points(fn, "directions", directions)
        if len(o) != len(d):
            raise ValueError(f"{fn}: origins has {len(o)} rows, directions {len(d)}")
        return o, d

    def __repr__(self) -> str:
        return f"Scene({self._scene.mesh_names!r}, triangles={self.triangle_count})"

    def __reduce__(self) -> tuple[Any, tuple[dict[str, Any]]]:
        """A scene pickles as its specification, the constructor's arguments (mesh paths made
        absolute, or the vertex and face arrays), never its BVH: unpickling builds it again
        (aperture.distributed.Renderer builds it once per worker). Arrays of more than
        _PICKLE_WARN_BYTES warn, as they travel with every pickle."""
        if "vertices" in self._spec:
            size = self._spec["vertices"].nbytes + self._spec["faces"].nbytes
            if size > _PICKLE_WARN_BYTES:
                warnings.warn(
                    f"Scene: pickling {size / 2**20:.0f} MB of vertex and face arrays, which travel "
                    "with every pickle of this scene (each task or worker it is sent to); write the "
                    "mesh to a file (e.g. a .ply) on storage the workers share and make the scene "
                    "with Scene(path)",
                    stacklevel=2,
                )
        return (_scene_of_spec, (self._spec,))


# A scene holding vertex and face arrays of more bytes than this warns when pickled.
_PICKLE_WARN_BYTES = 64 * 2**20


def _absolute_mesh_path(path: str) -> str:
    """A mesh path as a pickled scene records it: absolute, so that a worker with another
    current directory finds it; procedural specs as given."""
    return path if path.startswith("procedural:") else os.path.abspath(path)


# Scenes this process built from a pickled specification (aperture.distributed.scene_builds).
_spec_builds = 0


def _scene_of_spec(spec: dict[str, Any]) -> Scene:
    """The scene of a pickled specification (Scene.__reduce__), built again. Counted in
    _spec_builds and, when the environment variable APERTURE_SCENE_BUILD_LOG names a file, one
    line appended to it: host, PID, seconds the build took, triangles (docs/distributed.md)."""
    global _spec_builds
    start = time.perf_counter()
    scene = Scene(**spec)
    seconds = time.perf_counter() - start
    _spec_builds += 1
    log = os.environ.get("APERTURE_SCENE_BUILD_LOG")
    if log:
        with open(log, "a", encoding="utf-8") as f:
            f.write(f"{socket.gethostname()} {os.getpid()} {seconds:.6f} {scene.triangle_count}\n")
    return scene


def _query_points(fn: str, name: str, values: Any) -> np.ndarray:
    """``values`` as C-contiguous float64 (N, 3); ValueError naming ``fn`` and ``name`` for
    another dtype or shape."""
    a = np.asarray(values)
    if a.dtype not in (np.float32, np.float64):
        raise ValueError(f"{fn}: {name} must be float32 or float64, not {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{fn}: {name} must have shape (N, 3), not {a.shape}")
    return np.ascontiguousarray(a, dtype=np.float64)


def _warn_non_finite(fn: str, count: int, total: int, what: str) -> None:
    if count:
        warnings.warn(
            f"{fn}: {count} of {total} {what} are not finite (or beyond float range): their results are NaN",
            RuntimeWarning,
            stacklevel=3,
        )


def _grid_bounds(bounds: Any) -> tuple[np.ndarray, np.ndarray]:
    b = np.asarray(bounds, dtype=np.float64)
    if b.shape != (2, 3) or not np.all(np.isfinite(b)) or not np.all(b[1] > b[0]):
        raise ValueError(f"signed_distance_grid: bounds must be ((x0, y0, z0), (x1, y1, z1)) with x1 > x0 ..., not {bounds!r}")
    return b[0], b[1]


def _grid_resolution(resolution: int | Sequence[int]) -> tuple[int, int, int]:
    r = [resolution] * 3 if np.isscalar(resolution) else list(resolution)
    if len(r) != 3 or any(int(v) != v or v < 2 for v in r):
        raise ValueError(f"signed_distance_grid: resolution must be an int >= 2 or three of them, not {resolution!r}")
    return int(r[0]), int(r[1]), int(r[2])


def _reusable(previous: dict[str, Any] | None, chunk: list[Camera]) -> dict[str, np.ndarray] | None:
    """The arrays of the batch before to render `chunk` into (its first len(chunk) frames), or
    None when there is none or the sizes differ. Layered hits are not reused (render's out=
    does not take them)."""
    if previous is None:
        return None
    size = (chunk[0].height, chunk[0].width)
    if any((c.height, c.width) != size for c in chunk):
        return None
    into: dict[str, np.ndarray] = {}
    for name, array in previous.items():
        if name.startswith("layers.") or not isinstance(array, np.ndarray):
            continue
        if array.shape[1:3] != size or array.shape[0] < len(chunk):
            return None
        into[name] = array[: len(chunk)]
    return into


def _mesh_arrays(vertices: Any, faces: Any) -> tuple[np.ndarray, np.ndarray]:
    """Vertices as C-contiguous float32 or float64 (n, 3) and faces as C-contiguous uint32
    (m, 3), without a copy when they already are."""
    v = np.asarray(vertices)
    if v.dtype not in (np.float32, np.float64):
        if not np.issubdtype(v.dtype, np.number):
            raise ValueError(f"Scene: vertices must be numbers, not {v.dtype}")
        v = v.astype(np.float64)
    v = np.ascontiguousarray(v)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"Scene: vertices must have shape (n, 3), not {v.shape}")
    f = np.asarray(faces)
    if not np.issubdtype(f.dtype, np.integer):
        raise ValueError(f"Scene: faces must be integers, not {f.dtype}")
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"Scene: faces must have shape (m, 3), not {f.shape}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        bad = f.min() if f.min() < 0 else f.max()
        raise ValueError(f"Scene: face index {bad} out of range [0, {len(v)})")
    return v, np.ascontiguousarray(f, dtype=np.uint32)


def write(
    path: str | os.PathLike[str],
    array: Any,
    depth_scale: float = 1000.0,
    aov: str | None = None,
) -> int:
    """Writes one AOV array (H, W) or (H, W, C) to a dataset image, by extension: ``.png``
    16-bit depth (round(value * depth_scale), 0 for misses and values that do not fit),
    ``.pfm`` float32, ``.npy`` float32 or uint32, ``.tif`` float32/uint32. Float arrays are
    written as float32, integer arrays as uint32. ``aov`` names the AOV in messages and
    format checks (default: from the layout). Returns the number of PNG values out of range
    (also warned about). Written atomically; OSError when the directory is missing."""
    a = np.asarray(array)
    if np.issubdtype(a.dtype, np.floating):
        a = a.astype(np.float32, copy=False)
    elif np.issubdtype(a.dtype, np.integer):
        if a.size and (a.min() < 0 or a.max() > 0xFFFFFFFF):
            raise ValueError(f"{os.fspath(path)}: integer values must fit in uint32")
        a = a.astype(np.uint32, copy=False)
    else:
        raise ValueError(f"{os.fspath(path)}: cannot write an array of {a.dtype}")
    out_of_range = _write(os.fspath(path), np.ascontiguousarray(a), depth_scale, aov)
    if out_of_range:
        warnings.warn(
            f"{os.fspath(path)}: {out_of_range} values did not fit in 16 bits at depth_scale "
            f"{depth_scale} and were written as 0",
            stacklevel=2,
        )
    return out_of_range
