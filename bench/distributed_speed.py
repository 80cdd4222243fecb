#!/usr/bin/env python3
"""The cost of the scale-out (issue 43, item 4): the same cameras rendered to the same files by
`aperture batch`, by aperture.distributed.Renderer on a local Dask cluster of 2 worker
processes and on a local Ray (Ray Data map_batches, 2 actors), on this machine.

Each round renders every way once, in turn, into fresh folders, each with a new Renderer (so
each worker builds its scene in every round, as every batch run builds its own):
  batch            aperture batch JOB --quiet (all cores: the reference)
  dask-big/-small  client.map over tasks of BIG and of 1 camera(s), workers of 1 thread
  ray-big/-small   map_batches(concurrency=2, batch_size=BIG and 1), actors of 1 CPU
Reported: medians over rounds of the wall time; the overhead per task, (small - big) / (tasks
of small - tasks of big); and the scene build per worker (APERTURE_SCENE_BUILD_LOG) beside
batch's own load + build (its summary.json). Cluster start-up is timed once, apart.

    .venv/bin/python bench/distributed_speed.py --aperture build/apps/aperture \\
        --mesh ../shared/meshes/stanford/dragon_vrip.ply --rounds 5
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def camera_keywords(k: int, n: int, centre: list[float], radius: float) -> dict:
    angle = 2 * math.pi * k / n
    eye = [centre[0] + radius * math.sin(angle), centre[1] + 0.3 * radius, centre[2] + radius * math.cos(angle)]
    return dict(eye=eye, at=centre, fov=40.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--aperture", default="build/apps/aperture")
    parser.add_argument("--mesh", default="../shared/meshes/stanford/dragon_vrip.ply")
    parser.add_argument("--cameras", type=int, default=64)
    parser.add_argument("--size", default="320x240")
    parser.add_argument("--big", type=int, default=16, help="cameras per task of the big tasks")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()

    import aperture
    from aperture.distributed import Renderer, camera_rows

    work = Path(tempfile.mkdtemp(prefix="distributed_speed."))
    log = work / "builds.log"
    os.environ["APERTURE_SCENE_BUILD_LOG"] = str(log)  # inherited by the workers started below
    width, height = (int(v) for v in args.size.split("x"))
    mesh = str(Path(args.mesh).resolve())
    scene = aperture.Scene(mesh)
    lo, hi = scene.bounds
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = 1.6 * max(b - a for a, b in zip(lo, hi))
    n = args.cameras
    cameras = []
    for k in range(n):
        c = aperture.Camera(size=(width, height), **camera_keywords(k, n, centre, radius))
        c.name = f"view{k:03d}"
        cameras.append(c)
    rows = camera_rows(cameras)

    def job(out: Path) -> Path:
        path = work / "job.json"
        path.write_text(json.dumps({
            "scene": {"meshes": [{"path": mesh}]},
            "cameras": [{"name": f"view{k:03d}", **camera_keywords(k, n, centre, radius)} for k in range(n)],
            "aovs": "depth", "size": [width, height],
            "outputs": [{"aov": "depth", "path": f"{out}/{{camera}}.png"}],
        }))
        return path

    def fresh(name: str) -> Path:
        out = work / name
        shutil.rmtree(out, ignore_errors=True)
        return out

    def builds_since(mark: int) -> list[float]:
        lines = log.read_text().splitlines()[mark:] if log.exists() else []
        return [float(line.split()[2]) for line in lines]

    def log_mark() -> int:
        return len(log.read_text().splitlines()) if log.exists() else 0

    from dask.distributed import Client, LocalCluster
    import ray

    start = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                           silence_logs=40)
    client = Client(cluster)
    dask_start = time.perf_counter() - start
    start = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    ray.data.DataContext.get_current().enable_progress_bars = False
    ray_start = time.perf_counter() - start

    def run_batch() -> tuple[float, list[float]]:
        out = fresh("batch")
        summary = work / "summary.json"
        start = time.perf_counter()
        done = subprocess.run([args.aperture, "batch", str(job(out)), "--quiet", "--summary", str(summary)],
                              capture_output=True, text=True)
        wall = time.perf_counter() - start
        if done.returncode != 0:
            sys.exit(done.stderr)
        s = json.loads(summary.read_text())
        return wall, [s["load_seconds"] + s["build_seconds"]]

    def run_dask(per_task: int) -> tuple[float, list[float]]:
        out = fresh(f"dask{per_task}")
        mark = log_mark()
        start = time.perf_counter()
        renderer = Renderer(scene, aovs="depth", outputs=f"{out}/{{name}}.png", threads=1)
        tables = [rows[i : i + per_task] for i in range(0, n, per_task)]
        client.gather(client.map(renderer, tables, pure=False))
        return time.perf_counter() - start, builds_since(mark)

    def run_ray(per_task: int) -> tuple[float, list[float]]:
        out = fresh(f"ray{per_task}")
        mark = log_mark()
        start = time.perf_counter()
        ray.data.from_items(rows).map_batches(
            Renderer,
            fn_constructor_kwargs=dict(scene=scene, aovs="depth", outputs=f"{out}/{{name}}.png", threads=1),
            compute=ray.data.ActorPoolStrategy(size=2), num_cpus=1, batch_size=per_task,
        ).materialize()
        return time.perf_counter() - start, builds_since(mark)

    ways = {
        "batch": run_batch,
        f"dask, {args.big} cameras a task": lambda: run_dask(args.big),
        "dask, 1 camera a task": lambda: run_dask(1),
        f"ray, {args.big} cameras a task": lambda: run_ray(args.big),
        "ray, 1 camera a task": lambda: run_ray(1),
    }
    walls: dict[str, list[float]] = {w: [] for w in ways}
    builds: dict[str, list[float]] = {w: [] for w in ways}
    for r in range(args.rounds + 1):  # round 0 warms the page cache and the workers' imports
        for name, way in ways.items():
            wall, b = way()
            if r > 0:
                walls[name].append(wall)
                builds[name].extend(b)
        print(f"round {r}: " + ", ".join(f"{w} {walls[w][-1]:.2f}s" for w in ways if r > 0), file=sys.stderr)

    ray.shutdown()
    client.close()
    cluster.close()
    shutil.rmtree(work, ignore_errors=True)

    med = {w: statistics.median(v) for w, v in walls.items()}
    big_tasks, small_tasks = math.ceil(n / args.big), n
    print(f"mesh {Path(args.mesh).name} ({scene.triangle_count} triangles), {n} cameras {args.size}, depth PNG, "
          f"medians of {args.rounds} rounds")
    print(f"start-up (once): Dask LocalCluster 2 workers {dask_start:.2f} s, ray.init {ray_start:.2f} s")
    print("| way | wall s | / batch | builds per round | build s (median) |")
    print("|---|---:|---:|---:|---:|")
    for w in ways:
        per_round = len(builds[w]) / args.rounds
        b = statistics.median(builds[w]) if builds[w] else float("nan")
        print(f"| {w} | {med[w]:.3f} | {med[w] / med['batch']:.2f} | {per_round:.1f} | {b:.3f} |")
    for system in ("dask", "ray"):
        big = med[f"{system}, {args.big} cameras a task"]
        small = med[f"{system}, 1 camera a task"]
        print(f"{system}: overhead per task {(small - big) / (small_tasks - big_tasks) * 1e3:.1f} ms "
              f"(({small:.3f} - {big:.3f}) s / ({small_tasks} - {big_tasks}) tasks)")


if __name__ == "__main__":
    main()
