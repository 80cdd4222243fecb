#!/usr/bin/env python3
"""The Python user's wall time against the render's own, and against Open3D (issue 43, item 1).

8 views of the dragon at 1280x720 with depth, normal and primid (the issue's case), on an orbit
around the dragon's reference camera (../shared/meshes/README.md: eye (0, 0.12, 0.45), look-at
(0, 0.12, 0), up y, vertical fov 30). Per round, one after the other (alternating, so a change of
the host's load touches all three alike):

  fresh   scene.render(cameras, aovs) returning new arrays
  out     scene.render(cameras, aovs, out=arrays) into the arrays of the call before
  open3d  RaycastingScene.cast_rays of the same rays, all cameras in one (N, H, W, 6) tensor
          (rays built in NumPy by bench/peer_rays.py before the clock starts)

For fresh and out: the wall time of the call (time.perf_counter around it) over the render's own
seconds (scene.last_render["seconds"], the frame loop with the GIL released): target <= 1.05.
Reports medians over rounds, the ratios, and checks both trace the same triangles (>= 99.9 %).
Run it against the module `pip install .` built:

    /work/main/.venv/bin/python -m pip install --no-build-isolation -q --target /tmp/site .
    PYTHONPATH=/tmp/site /work/main/.venv/bin/python bench/python_wall.py --rounds 7
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.append(str(REPO / "bench"))
import peer_rays  # noqa: E402
from peer_rays import pinhole_rays  # noqa: E402
from peers import cpu_model  # noqa: E402

EYE, AT, UP, FOV = (0.0, 0.12, 0.45), (0.0, 0.12, 0.0), (0.0, 1.0, 0.0), 30.0


def orbit(n: int) -> list[tuple[float, float, float]]:
    """n eyes on the circle through the reference eye around the vertical axis through AT."""
    return peer_rays.orbit(EYE, AT, n)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", default=str(REPO.parent / "shared" / "meshes" / "stanford" / "dragon_vrip.ply"))
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--aovs", default="depth,normal,primid")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--modes", default="fresh,out", help="fresh,out or fresh alone (a module without out=)")
    ap.add_argument("--no-open3d", action="store_true", help="time aperture only")
    a = ap.parse_args()
    modes = a.modes.split(",")
    width, height = (int(x) for x in a.size.lower().split("x"))

    import aperture

    eyes = orbit(a.cameras)
    cameras = [aperture.Camera.look_at(eye=e, at=AT, up=UP, fov=FOV, size=(width, height)) for e in eyes]
    scene = aperture.Scene(a.mesh)
    out = scene.render(cameras, aovs=a.aovs)  # warm-up; its arrays are the out= arrays
    o3d_scene = rays = None
    if not a.no_open3d:
        import open3d as o3d

        legacy = o3d.io.read_triangle_mesh(a.mesh)
        o3d_scene = o3d.t.geometry.RaycastingScene()
        o3d_scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(legacy))
        rays = o3d.core.Tensor(np.stack([pinhole_rays(e, UP, FOV, width, height, at=AT) for e in eyes]))
        o3d_scene.cast_rays(rays)  # warm-up

    wall: dict[str, list[float]] = {"fresh": [], "out": [], "open3d": []}
    inner: dict[str, list[float]] = {"fresh": [], "out": []}
    for _ in range(a.rounds):
        for mode in modes:
            t0 = time.perf_counter()
            if mode == "out":
                result = scene.render(cameras, aovs=a.aovs, out=out)
            else:
                result = scene.render(cameras, aovs=a.aovs)
            wall[mode].append(time.perf_counter() - t0)
            inner[mode].append(scene.last_render["seconds"])
            if mode == "out":
                assert all(result[n] is out[n] for n in out)
            del result
        if o3d_scene is not None:
            t0 = time.perf_counter()
            hits = o3d_scene.cast_rays(rays)
            wall["open3d"].append(time.perf_counter() - t0)

    rays_n = a.cameras * width * height
    print(f"date {time.strftime('%Y-%m-%d %H:%M %Z')}  cpu {cpu_model()}  cores {os.cpu_count()}  "
          f"load {' '.join(f'{x:.1f}' for x in os.getloadavg())}  aperture {aperture.__version__} "
          f"({Path(aperture.__file__).parent})")
    print(f"mesh {a.mesh}  cameras {a.cameras}  size {width}x{height}  aovs {a.aovs}  rounds {a.rounds}")
    for mode in modes:
        w, s = statistics.median(wall[mode]), statistics.median(inner[mode])
        ratios = [x / y for x, y in zip(wall[mode], inner[mode])]
        print(f"{mode:6s}  wall median {w * 1e3:7.1f} ms  last_render {s * 1e3:7.1f} ms  "
              f"wall/last_render median {statistics.median(ratios):.3f} (rounds "
              f"{' '.join(f'{r:.3f}' for r in ratios)})  {rays_n / w * 1e-6:.1f} Mrays/s wall")
    if o3d_scene is not None:
        o = statistics.median(wall["open3d"])
        print(f"open3d  wall median {o * 1e3:7.1f} ms  {rays_n / o * 1e-6:.1f} Mrays/s  rounds "
              f"{' '.join(f'{x * 1e3:.0f}' for x in wall['open3d'])}")
        for mode in modes:
            per_round = [x / y for x, y in zip(wall["open3d"], wall[mode])]
            print(f"open3d / aperture {mode}: median of per-round ratios {statistics.median(per_round):.2f} "
                  f"(ratio of medians {o / statistics.median(wall[mode]):.2f})")
        theirs = hits["primitive_ids"].numpy().astype(np.uint32)
        theirs[~np.isfinite(hits["t_hit"].numpy())] = 0xFFFFFFFF
        agreement = float(np.count_nonzero(out["primid"] == theirs)) / theirs.size
        print(f"same triangle on {100 * agreement:.3f} % of pixels")
        if agreement < 0.999:
            print("the two disagree on more than 0.1 % of pixels: not the same rays")
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
