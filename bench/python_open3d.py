#!/usr/bin/env python3
"""aperture's Python module against Open3D's RaycastingScene (issue 12), same rays, same AOVs,
measured side by side in one run.

    bash bench/install-peers.sh   # once, as root: open3d-cpu in ~/.cache/aperture-peers/venv
    PYTHONPATH=<dir holding the aperture package> ~/.cache/aperture-peers/venv/bin/python \
        bench/python_open3d.py \
        --mesh ../shared/meshes/stanford/dragon_vrip.ply --cameras 100 --size 640,480 --rounds 3

Cameras: N views on a circle around the dragon's reference camera of shared/meshes/README.md
(eye (0, 0.12, 0.45) turned about the vertical axis through (0, 0.12, 0), vertical fov 30°).
Rays: aperture's pixel centres, u = ((j + ½)/W − ½)·vw, v = −((i + ½)/H − ½)·vh, d = 1,
computed in NumPy by bench/peer_rays.py (float64, then float32) and handed to Open3D's
cast_rays, so both trace the same rays; the script checks that both report the same triangle
on ≥ 99.9 % of pixels.
AOVs: ray distance, geometric normal, primitive id, geometry id (what cast_rays returns).

Timed, per round, one after the other:
  aperture  scene.render(all cameras, aovs=distance,normal,primid,geomid) — one call
  open3d    cast_rays(rays of camera k) for k in 0..N−1 (rays built before the clock starts)
Reports the median over rounds of Mrays/s for each and their ratio.
"""
import argparse
import math
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_rays import pinhole_rays  # noqa: E402
from peers import cpu_model  # noqa: E402


def orbit(n, centre=(0.0, 0.12, 0.0), radius=0.45):
    """Eyes on a horizontal circle, starting at the reference eye (0, 0.12, 0.45)."""
    cx, cy, cz = centre
    return [(cx + radius * math.sin(2 * math.pi * k / n), cy, cz + radius * math.cos(2 * math.pi * k / n))
            for k in range(n)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--cameras", type=int, default=100)
    ap.add_argument("--size", default="640,480")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    width, height = (int(x) for x in args.size.split(","))

    import aperture
    import open3d as o3d

    at, up, fov = (0.0, 0.12, 0.0), (0.0, 1.0, 0.0), 30.0
    eyes = orbit(args.cameras)
    cams = [aperture.Camera.look_at(eye=e, at=at, up=up, fov=fov, size=(width, height)) for e in eyes]
    rays = [o3d.core.Tensor(pinhole_rays(e, up, fov, width, height, at=at)) for e in eyes]

    t0 = time.perf_counter()
    scene = aperture.Scene(args.mesh)
    ap_load = time.perf_counter() - t0
    legacy = o3d.io.read_triangle_mesh(args.mesh)
    t0 = time.perf_counter()
    o3d_scene = o3d.t.geometry.RaycastingScene()
    o3d_scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(legacy))
    o3d_build = time.perf_counter() - t0

    aovs = ["distance", "normal", "primid", "geomid"]
    n_rays = args.cameras * width * height
    ap_rates, o3d_rates = [], []
    for _ in range(args.rounds):
        t0 = time.perf_counter()
        out = scene.render(cams, aovs=aovs)
        ap_rates.append(n_rays / (time.perf_counter() - t0) * 1e-6)
        t0 = time.perf_counter()
        results = [o3d_scene.cast_rays(r) for r in rays]
        o3d_rates.append(n_rays / (time.perf_counter() - t0) * 1e-6)

    # Same rays, same triangles: Open3D's primitive ids against aperture's primid.
    same = total = 0
    for k in range(args.cameras):
        ours = out["primid"][k]
        theirs = results[k]["primitive_ids"].numpy().astype(np.uint32)
        theirs[~np.isfinite(results[k]["t_hit"].numpy())] = 0xFFFFFFFF
        same += int(np.count_nonzero(ours == theirs))
        total += ours.size
    agreement = same / total

    a, o = statistics.median(ap_rates), statistics.median(o3d_rates)
    print(f"date {time.strftime('%Y-%m-%d')}  cpu {cpu_model()}  cores {os.cpu_count()}  "
          f"open3d {o3d.__version__}  aperture {aperture.__version__}")
    print(f"mesh {args.mesh}  cameras {args.cameras}  size {width}x{height}  rounds {args.rounds}  "
          f"aovs {','.join(aovs)}")
    print(f"scene set-up: aperture {ap_load:.2f} s (load + BVH), open3d {o3d_build:.2f} s (BVH; load not timed)")
    print(f"aperture  median {a:7.2f} Mrays/s  rounds {' '.join(f'{x:.2f}' for x in ap_rates)}")
    print(f"open3d    median {o:7.2f} Mrays/s  rounds {' '.join(f'{x:.2f}' for x in o3d_rates)}")
    print(f"ratio aperture / open3d = {a / o:.2f}   same triangle on {100 * agreement:.3f} % of pixels")
    if agreement < 0.999:
        raise SystemExit("the two disagree on more than 0.1 % of pixels: not the same rays")


if __name__ == "__main__":
    main()
