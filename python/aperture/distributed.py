"""aperture.distributed: rendering on the workers of Ray Data and Dask (docs/distributed.md).

``Renderer(scene, aovs=..., outputs=...)`` is a callable class that both can use as it is: Ray
Data's ``map_batches`` makes one per actor (``concurrency=N``); Dask's ``client.map`` and
``dask.bag.map_partitions`` send it pickled with each task. It pickles as the scene's
specification (aperture.Scene.__reduce__) and builds the scene once per worker process, at
the first batch, keeping it for every later batch and task.

A batch is a table of cameras: the keywords of ``Camera`` (``Camera.params``) as columns plus
``name``, as a dict of columns (Ray's "numpy" batches), a pandas DataFrame, a pyarrow Table, or
a sequence of rows (dicts or Camera objects; a Dask bag's partition). With ``outputs=None`` it
returns the rendered arrays; with output patterns it writes each AOV of each camera through
``aperture.write`` (the dataset writers of ``aperture batch``'s ``outputs``, atomic), keeps
files that exist (an atomic write leaves no partial file, so an existing file is complete, as
``batch --resume`` reasons) and returns the paths.
"""

from __future__ import annotations

import math
import os
import uuid
from collections import OrderedDict
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

import aperture as _package

from . import Camera, Scene, _aov_list, _scene_of_spec, write
from ._aperture import _dataset_extensions, _dead_temporaries

__all__ = ["Renderer", "camera_rows", "forget_scenes", "scene_builds"]

# The dataset formats a Renderer writes (core/io/dataset_image.h, as batch's `outputs`).
_DATASET_EXTENSIONS = tuple(_dataset_extensions())

# The scenes this process built for Renderers, by Renderer key, most recently used last: a
# worker that runs many tasks of one Renderer builds its scene once.
_SCENES: OrderedDict[str, Scene] = OrderedDict()
_SCENES_KEPT = 4


def scene_builds() -> int:
    """How many scenes this process built from a pickled specification (an unpickled Scene, or
    a Renderer's first batch on a worker). ``client.run(scene_builds)`` asks every Dask worker."""
    return _package._spec_builds


def forget_scenes() -> None:
    """Drops the scenes this process keeps for Renderers (the next batch builds again)."""
    _SCENES.clear()


def camera_rows(cameras: Iterable[Camera]) -> list[dict[str, Any]]:
    """One row per camera, ``name`` and the keywords of ``Camera.params``, every row with the
    same keys (None where a camera keeps the default): what ``ray.data.from_items``,
    ``pandas.DataFrame`` and ``dask.bag.from_sequence`` take to make a table of cameras."""
    rows = [{"name": c.name, **c.params} for c in cameras]
    keys: dict[str, None] = {}
    for row in rows:
        keys.update(dict.fromkeys(row))
    return [{k: row.get(k) for k in keys} for row in rows]


def _remember(key: str, scene: Scene) -> None:
    _SCENES[key] = scene
    _SCENES.move_to_end(key)
    while len(_SCENES) > _SCENES_KEPT:
        _SCENES.popitem(last=False)


def _is_missing(value: Any) -> bool:
    """A table's empty cell: None, NaN (pandas) or pandas.NA."""
    if value is None or type(value).__name__ == "NAType":
        return True
    return isinstance(value, (float, np.floating)) and math.isnan(value)


def _rows_of(batch: Any) -> tuple[list[dict[str, Any]], str]:
    """The rows of a batch and its kind ("columns", "pandas" or "rows"), which decides the kind
    of what the Renderer returns."""
    if isinstance(batch, Camera):
        batch = [batch]
    module = type(batch).__module__
    if module.startswith("pandas"):
        return batch.to_dict("records"), "pandas"
    if module.startswith("pyarrow"):
        return batch.to_pylist(), "columns"
    if isinstance(batch, Mapping):
        lengths = {k: len(v) for k, v in batch.items()}
        if len(set(lengths.values())) > 1:
            raise ValueError(f"Renderer: the columns of a batch differ in length: {lengths}")
        n = next(iter(lengths.values()), 0)
        return [{k: column[i] for k, column in batch.items()} for i in range(n)], "columns"
    rows = []
    for row in batch:
        if isinstance(row, Camera):
            rows.append({"name": row.name, **row.params})
        elif isinstance(row, Mapping):
            rows.append(dict(row))
        else:
            raise TypeError(
                f"Renderer: a batch row must be a Camera or a mapping of Camera keywords, not "
                f"{type(row).__name__}"
            )
    return rows, "rows"


def _camera_of(row: Mapping[str, Any]) -> Camera:
    keywords = {k: v for k, v in row.items() if k != "name" and not _is_missing(v)}
    camera = Camera(**keywords)
    name = row.get("name")
    camera.name = "" if _is_missing(name) else str(name)
    return camera


def _check_name(name: str) -> None:
    """A camera name goes into file names: not empty, not absolute, no '..'."""
    parts = name.replace("\\", "/").split("/")
    if not name or os.path.isabs(name) or ".." in parts or "" in parts:
        raise ValueError(
            f"Renderer: camera name {name!r} cannot name a file (empty, absolute, '..' or an "
            "empty folder)"
        )


def _output_patterns(outputs: str | Mapping[str, str], aovs: list[str]) -> dict[str, str]:
    """AOV -> absolute path pattern, checked: placeholders {name}, {image}, {aov} only, a
    dataset extension, {aov} in a pattern shared by several AOVs."""
    if isinstance(outputs, str):
        if "all" in aovs:
            raise ValueError("Renderer: with outputs, name the AOVs (aovs='all' has no file of its own)")
        if len(aovs) > 1 and "{aov}" not in outputs:
            raise ValueError(
                f"Renderer: outputs {outputs!r} is one pattern for the AOVs {aovs}: put {{aov}} in "
                "it or give a dict AOV -> pattern"
            )
        patterns = {aov: outputs for aov in aovs}
    else:
        patterns = {str(aov): str(p) for aov, p in outputs.items()}
        for aov in patterns:
            if aov not in aovs:
                raise ValueError(
                    f"Renderer: outputs names AOV {aov!r}, which is not among aovs {aovs} "
                    "(outputs never add AOVs)"
                )
    for aov, pattern in patterns.items():
        extension = os.path.splitext(pattern)[1].lower()
        if extension == ".exr":
            raise ValueError(
                f"Renderer: outputs {pattern!r}: an EXR records its render time in its header, so "
                "it is written by `aperture batch` only; use a dataset format "
                f"({' '.join(_DATASET_EXTENSIONS)})"
            )
        if extension not in _DATASET_EXTENSIONS:
            raise ValueError(
                f"Renderer: outputs {pattern!r}: unknown extension {extension!r} (known: "
                f"{' '.join(_DATASET_EXTENSIONS)})"
            )
        leftover = _fill(pattern, aov, "n").replace("{", "}")
        if "}" in leftover:
            raise ValueError(
                f"Renderer: outputs {pattern!r}: unknown placeholder (known: {{name}}, {{image}}, "
                "{aov})"
            )
        patterns[aov] = os.path.abspath(pattern)
    return patterns


def _fill(pattern: str, aov: str, name: str) -> str:
    """A pattern's path for one AOV of one camera: {name} as given, {image} without its
    extension (batch's {image}), {aov} the AOV's name."""
    image = os.path.splitext(name)[0]
    return pattern.replace("{name}", name).replace("{image}", image).replace("{aov}", aov)


def _remove_dead_temporaries(paths: list[str]) -> None:
    """Removes the temporaries of `paths` (".NAME.tmp-PID-N...") whose process is gone on this
    host, as ``batch --resume`` does: what a worker killed while writing left behind."""
    for temporary in _dead_temporaries(paths):
        try:
            os.remove(temporary)
        except FileNotFoundError:
            pass


class Renderer:
    """Renders tables of cameras on a worker with a scene it builds once per process.

    ``scene``: an aperture.Scene (it travels as its specification; mesh paths must be readable
    on the workers). ``aovs``: as Scene.render takes them. ``outputs``: None to return arrays;
    a path pattern (``"out/{aov}/{name}.png"``; placeholders ``{name}``, ``{image}`` (the name
    without its extension, batch's ``{image}``) and ``{aov}``) or a dict AOV -> pattern, each
    ending in a dataset extension (.png .pfm .npy .tif .tiff), to write files. Relative
    patterns are made absolute where the Renderer is made. ``depth_scale``: 16-bit PNG values
    per unit, as batch's ``depth_scale``. Other keywords go to Scene.render (``threads``,
    ``spp``, ``normal_frame``, ``packet``, ``tile``, ...): give ``threads`` the cores of one
    worker when several workers share a machine.

    A call takes a batch (module docstring) and returns the same kind: columns (a dict of NumPy
    arrays: ``name`` and per AOV the stacked arrays (N, H, W[, C]), or with outputs per AOV the
    paths and ``rendered``, False for a camera whose files all existed), a pandas DataFrame, or
    a list of row dicts.

    ``_fail_once=(mode, marker)`` is a test hook: the first call, over all processes, that
    creates the file ``marker`` fails after writing its first camera's files, by os._exit
    (mode "exit") or by raising RuntimeError (mode "raise")."""

    def __init__(
        self,
        scene: Scene,
        aovs: str | Iterable[str] = ("color", "depth"),
        outputs: str | Mapping[str, str] | None = None,
        *,
        depth_scale: float = 1000.0,
        _fail_once: tuple[str, str] | None = None,
        **render_options: Any,
    ) -> None:
        if not isinstance(scene, Scene):
            raise TypeError(f"Renderer: scene must be an aperture.Scene, not {type(scene).__name__}")
        self._aovs = _aov_list(aovs)
        names = [a.strip() for a in self._aovs.split(",") if a.strip()]
        self._patterns = None if outputs is None else _output_patterns(outputs, names)
        self._depth_scale = float(depth_scale)
        self._render_options = render_options
        self._fail_once = _fail_once
        self._spec = scene._spec
        self._key = uuid.uuid4().hex
        self._scene: Scene | None = scene  # kept by this object only: the cache is for workers

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_scene"] = None  # the worker builds it from _spec, once
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)

    def scene(self) -> Scene:
        """The scene, built at the first call in this process and kept."""
        if self._scene is None:
            cached = _SCENES.get(self._key)
            if cached is None:
                cached = _scene_of_spec(self._spec)
            _remember(self._key, cached)
            self._scene = cached
        return self._scene

    def __call__(self, batch: Any) -> Any:
        rows, kind = _rows_of(batch)
        cameras = [_camera_of(row) for row in rows]
        if self._patterns is None:
            columns = self._render_arrays(cameras)
        else:
            columns = self._render_files(cameras)
        return _shaped(columns, kind, len(cameras))

    def _render(self, cameras: list[Camera]) -> dict[str, Any]:
        return self.scene().render(cameras, self._aovs, **self._render_options)

    def _render_arrays(self, cameras: list[Camera]) -> dict[str, Any]:
        columns: dict[str, Any] = {"name": np.array([c.name for c in cameras], dtype=object)}
        if not cameras:
            return columns
        out = self._render(cameras)
        self._maybe_fail()
        for aov, value in out.items():
            if isinstance(value, list):  # cameras of different sizes
                column = np.empty(len(value), dtype=object)
                column[:] = value
                value = column
            columns[aov] = value
        return columns

    def _paths_of(self, camera: Camera) -> dict[str, str]:
        _check_name(camera.name)
        assert self._patterns is not None
        return {aov: _fill(p, aov, camera.name) for aov, p in self._patterns.items()}

    def _render_files(self, cameras: list[Camera]) -> dict[str, Any]:
        paths = [self._paths_of(c) for c in cameras]
        seen: dict[str, str] = {}
        for camera, files in zip(cameras, paths):
            for p in files.values():
                if p in seen:
                    raise ValueError(
                        f"Renderer: cameras {seen[p]!r} and {camera.name!r} would both write {p}"
                    )
                seen[p] = camera.name
        todo = [k for k, files in enumerate(paths) if not all(os.path.exists(p) for p in files.values())]
        if todo:
            wanted = [p for k in todo for p in paths[k].values()]
            _remove_dead_temporaries(wanted)
            out = self._render([cameras[k] for k in todo])
            for j, k in enumerate(todo):
                for aov, path in paths[k].items():
                    if os.path.exists(path):
                        continue  # complete (atomic writes): kept, not rewritten
                    os.makedirs(os.path.dirname(path), exist_ok=True)
                    write(path, out[aov][j], depth_scale=self._depth_scale, aov=aov)
                if j == 0:
                    self._maybe_fail()
        columns: dict[str, Any] = {"name": np.array([c.name for c in cameras], dtype=object)}
        assert self._patterns is not None
        for aov in self._patterns:
            columns[aov] = np.array([files[aov] for files in paths], dtype=object)
        rendered = set(todo)
        columns["rendered"] = np.array([k in rendered for k in range(len(cameras))], dtype=bool)
        return columns

    def _maybe_fail(self) -> None:
        if self._fail_once is None:
            return
        mode, marker = self._fail_once
        try:
            os.close(os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:
            return
        if mode == "exit":
            os._exit(70)
        raise RuntimeError("aperture.distributed.Renderer: the failure _fail_once injects")


def _shaped(columns: dict[str, Any], kind: str, n: int) -> Any:
    """The result in the kind of the batch: columns, a pandas DataFrame or a list of rows."""
    if kind == "columns":
        return columns
    rows = [{k: v[i] for k, v in columns.items()} for i in range(n)]
    if kind == "pandas":
        import pandas

        return pandas.DataFrame(rows, columns=list(columns))
    return rows
