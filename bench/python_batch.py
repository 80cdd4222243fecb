#!/usr/bin/env python3
"""Python against the command line's batch on the same 100 cameras of the dragon.

Renders N cameras on an orbit around the dragon's reference camera (../shared/meshes/README.md:
eye (0, 0.12, 0.45), look-at (0, 0.12, 0), up y, vertical fov 30) at 640x480, AOVs
depth,normal, once from Python (Scene.render: one call, every camera) and once through
`aperture batch` with a job file this script writes (the same cameras, one EXR each), and
prints Mrays/s of both and their ratio (target: Python >= 0.95 of the batch).

Mrays/s are rays traced / render seconds of the frame loop (batch: the summary's
render_seconds, writes excluded; Python: Scene.last_render, the render call without the
conversion to arrays), and end to end (batch: elapsed with its EXR writes; Python: the
render call returning arrays). Python runs a warm-up, then the median of --repeat calls.

    .venv/bin/python bench/python_batch.py                      # the lead's measurement
    .venv/bin/python bench/python_batch.py --size 64x48 --cameras 10 --repeat 1   # smoke run
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "build" / "python"))  # the CMake tree's module, if built there

import aperture  # noqa: E402
import peer_rays  # noqa: E402  (bench/, the script's own folder)

EYE, AT, FOV = (0.0, 0.12, 0.45), (0.0, 0.12, 0.0), 30.0


def orbit(n: int) -> list[tuple[float, float, float]]:
    """n eyes on the circle through the reference eye around the vertical axis through AT."""
    return peer_rays.orbit(EYE, AT, n)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default=str(REPO.parent / "shared" / "meshes" / "stanford" / "dragon_vrip.ply"))
    ap.add_argument("--binary", default=str(REPO / "build" / "apps" / "aperture"))
    ap.add_argument("--cameras", type=int, default=100)
    ap.add_argument("--size", default="640x480")
    ap.add_argument("--aovs", default="depth,normal")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    width, height = (int(x) for x in a.size.lower().split("x"))
    eyes = orbit(a.cameras)

    with tempfile.TemporaryDirectory() as tmp:
        job = {
            "scene": {"meshes": [{"path": str(Path(a.mesh).resolve())}]},
            "cameras": [
                {"name": f"c{k:03d}", "eye": list(e), "at": list(AT), "up": [0, 1, 0], "fov": FOV}
                for k, e in enumerate(eyes)
            ],
            "output": str(Path(tmp) / "out" / "{camera}.exr"),
            "aovs": a.aovs,
            "size": [width, height],
        }
        job_path, summary_path = Path(tmp) / "job.json", Path(tmp) / "summary.json"
        job_path.write_text(json.dumps(job))
        subprocess.run([a.binary, "batch", str(job_path), "--quiet", "--summary", str(summary_path)], check=True)
        summary = json.loads(summary_path.read_text())

    scene = aperture.Scene(a.mesh)
    cameras = [aperture.Camera(eye=e, at=AT, up=(0, 1, 0), fov=FOV, size=(width, height)) for e in eyes]
    scene.render(cameras[: min(4, len(cameras))], aovs=a.aovs)  # warm-up
    loop, whole = [], []
    for _ in range(a.repeat):
        start = time.perf_counter()
        out = scene.render(cameras, aovs=a.aovs)
        whole.append(time.perf_counter() - start)
        loop.append(scene.last_render["seconds"])
        rays = scene.last_render["rays"]
        del out

    cli_loop = summary["rays"] / summary["render_seconds"] * 1e-6
    cli_whole = summary["rays"] / summary["elapsed_seconds"] * 1e-6
    py_loop = rays / statistics.median(loop) * 1e-6
    py_whole = rays / statistics.median(whole) * 1e-6
    print(f"{len(cameras)} cameras {width}x{height}, AOVs {a.aovs}, mesh {Path(a.mesh).name}, "
          f"threads {summary.get('threads')}, isa {summary.get('isa')}")
    print(f"rays: python {rays}, batch {summary['rays']}")
    print(f"frame loop : python {py_loop:8.1f} Mrays/s   batch {cli_loop:8.1f} Mrays/s   ratio {py_loop / cli_loop:.3f}")
    print(f"end to end : python {py_whole:8.1f} Mrays/s   batch {cli_whole:8.1f} Mrays/s   ratio {py_whole / cli_whole:.3f}"
          "   (batch writes EXRs; python returns arrays)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
