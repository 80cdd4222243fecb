"""Shared fixtures of the pytest suite. CTest runs it against the module built in the CMake
tree (PYTHONPATH=build/python) with APERTURE_BINARY naming the command line and
APERTURE_SHARED_DIR the ../shared folder; run by hand, an installed module is used and the
tests that need the command line or ../shared skip with a message."""

from __future__ import annotations

import os
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `aperture` executable (APERTURE_BINARY, else build/apps/aperture)."""
    path = Path(os.environ.get("APERTURE_BINARY", REPO / "build" / "apps" / "aperture"))
    if not path.is_file():
        pytest.skip(f"the aperture command line is not built ({path}); set APERTURE_BINARY")
    return path


def run_cli(cli: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """Runs the command line; returns the finished process (stdout, stderr as text)."""
    return subprocess.run([str(cli), *args], capture_output=True, text=True, timeout=300)


def uv_sphere(
    rings: int = 24,
    segments: int = 48,
    radius: float = 1.0,
    bumps: float = 0.0,
    seed: int = 7,
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere built here (not by aperture): float64 vertices (rings + 1 rows of `segments`,
    y up, at `centre`) and int64 faces. `bumps` > 0 scales each vertex's radius by 1 + bumps
    times a standard normal drawn with `seed`."""
    theta = np.linspace(0, np.pi, rings + 1)[:, None]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)[None, :]
    r = np.full((rings + 1, segments), radius)
    if bumps:
        r = radius * (1.0 + bumps * np.random.default_rng(seed).standard_normal((rings + 1, segments)))
    v = np.stack([r * np.sin(theta) * np.cos(phi), r * np.cos(theta), r * np.sin(theta) * np.sin(phi)], -1)
    faces = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, c, b), (b, c, d)]
    return v.reshape(-1, 3) + np.asarray(centre, dtype=np.float64), np.array(faces, dtype=np.int64)


def bits(a: np.ndarray) -> np.ndarray:
    """The array's values as raw bits: equal bits means equal floats, NaN and inf included."""
    return a.view(np.uint32)


def assert_same_bits(a: dict[str, np.ndarray], b: dict[str, np.ndarray], same_order: bool = False) -> None:
    """The two dicts hold the same names (in the same order with `same_order`) and, per name,
    arrays of one dtype and shape with equal bits."""
    assert (list(a) == list(b)) if same_order else (sorted(a) == sorted(b)), (list(a), list(b))
    for name in a:
        assert a[name].dtype == b[name].dtype and a[name].shape == b[name].shape, name
        assert np.array_equal(bits(a[name]), bits(b[name])), name


def cli_error(cli: Path, *args: str) -> str:
    """The message of a failing command line: stderr's 'aperture: error: ' line, without it."""
    done = run_cli(cli, *args)
    assert done.returncode != 0, f"expected the command line to fail: {args}"
    lines = [l for l in done.stderr.splitlines() if l.startswith("aperture: error: ")]
    assert lines, done.stderr
    return lines[-1][len("aperture: error: ") :]


def count_during(call: Callable[[], object]) -> tuple[float, int]:
    """Runs call() while a Python thread counts as fast as it can; returns the seconds the call
    took and how far the counter advanced meanwhile. With the GIL held for the whole call the
    counter only advances in the few switch intervals before the call takes it; released, it
    counts millions a second."""
    count = 0
    stop = threading.Event()

    def counter() -> None:
        nonlocal count
        while not stop.is_set():
            count += 1

    thread = threading.Thread(target=counter)
    thread.start()
    time.sleep(0.05)  # the thread is running
    before = count
    start = time.perf_counter()
    try:
        call()
    finally:
        seconds = time.perf_counter() - start
        during = count - before
        stop.set()
        thread.join()
    return seconds, during


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """../shared beside the project (APERTURE_SHARED_DIR, else REPO/../shared)."""
    path = Path(os.environ.get("APERTURE_SHARED_DIR", REPO.parent / "shared"))
    if not (path / "meshes").is_dir():
        pytest.skip(f"{path}/meshes is absent (no ../shared beside the project); this test needs it")
    return path


@pytest.fixture(scope="session")
def bunny(shared_dir: Path) -> Path:
    """The Stanford bunny at its coarsest resolution (948 faces)."""
    return shared_dir / "meshes" / "stanford" / "bun_zipper_res4.ply"


@pytest.fixture(scope="session")
def pycolmap():
    """pycolmap, COLMAP's own Python bindings (pip; scripts/venv.sh installs it), the reference
    the camera-model tests check against; they skip with this message when it cannot be
    imported."""
    try:
        import pycolmap as module
    except ImportError as e:
        pytest.skip(f"pycolmap cannot be imported ({e}); pip install 'pycolmap>=4.2' (scripts/venv.sh does)")
    return module
