"""Side by side with Open3D: insideOf's and countIntersections' throughput
(bench/inside_speed.cpp, built as build/bench/aperture_inside_speed) and Open3D
RaycastingScene.compute_occupancy (nsamples 1 and 5) and count_intersections (rays from the
points in random directions) on 1M points spread uniformly over the mesh's box enlarged by 10 %
on each side, in alternating rounds; medians (bench/RESULTS.md, issue 44 items 2 and 5). For
count_intersections the "inside" column is the mean number of hits per ray.

    .venv/bin/python bench/inside_speed.py --mesh ../shared/meshes/stanford/dragon_vrip.ply
"""
import argparse
import re
import statistics
import subprocess
import time

import numpy as np
import open3d as o3d


def open3d_round(scene, points, nsamples, threads):
    start = time.perf_counter()
    occupancy = scene.compute_occupancy(points, nsamples=nsamples, nthreads=threads).numpy()
    return time.perf_counter() - start, float(occupancy.mean())


def open3d_count_round(scene, rays, threads):
    start = time.perf_counter()
    counts = scene.count_intersections(rays, nthreads=threads).numpy()
    return time.perf_counter() - start, float(counts.mean())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--mesh", required=True)
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--binary", default="build/bench/aperture_inside_speed")
    parser.add_argument("--beta", default="2", help="winding's beta; 0: no winding")
    parser.add_argument("--threads", type=int, default=2, help="Open3D's nthreads")
    args = parser.parse_args()

    mesh = o3d.t.io.read_triangle_mesh(args.mesh)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(mesh)
    lo = mesh.vertex.positions.min(0).numpy().astype(np.float64)
    hi = mesh.vertex.positions.max(0).numpy().astype(np.float64)
    pad = 0.1 * (hi - lo)
    rng = np.random.default_rng(1)
    points = (lo - pad + (hi - lo + 2 * pad) * rng.random((args.points, 3))).astype(np.float32)
    directions = rng.normal(size=(args.points, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    rays = o3d.core.Tensor(np.hstack([points, directions.astype(np.float32)]))
    points = o3d.core.Tensor(points)

    times = {"open3d nsamples 1": [], "open3d nsamples 5": [], "open3d count_intersections": []}
    fractions = {}
    ours = {}
    for _ in range(args.rounds):
        out = subprocess.run([args.binary, args.mesh, str(args.points), "1", args.beta], check=True,
                             capture_output=True, text=True).stdout
        for line in out.splitlines():
            m = re.match(r"(.+?)\s+median ([0-9.]+) s .*inside ([0-9.]+)", line)
            if m:
                ours.setdefault(m.group(1).strip(), []).append(float(m.group(2)))
                fractions[m.group(1).strip()] = float(m.group(3))
        for n in (1, 5):
            seconds, fraction = open3d_round(scene, points, n, args.threads)
            times[f"open3d nsamples {n}"].append(seconds)
            fractions[f"open3d nsamples {n}"] = fraction
        seconds, mean = open3d_count_round(scene, rays, args.threads)
        times["open3d count_intersections"].append(seconds)
        fractions["open3d count_intersections"] = mean
    print(f"{args.mesh}: {args.points} points, {args.rounds} rounds, "
          f"open3d {o3d.__version__}")
    for name, values in list(ours.items()) + list(times.items()):
        med = statistics.median(values)
        print(f"{name:32s} median {med:.3f} s  {args.points / med:.3g} points/s  "
              f"inside {fractions[name]:.4f}")


if __name__ == "__main__":
    main()
