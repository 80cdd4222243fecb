#!/usr/bin/env python3
"""Face visibility's two ray methods against the primID renders (bench/RESULTS.md, issue 43
item 2): Scene.face_visibility with method="needed-rays" (the default) and "all-rays" (the
reference: one centre ray per face whose centroid projects inside the image), both sides and
front_only, against Scene.render(aovs="primid") of the same cameras (the ring of
bench/visibility.py). Each round runs every measurement once, alternating; medians are printed,
and every array of the two methods is asserted equal.

  PYTHONPATH=build/python /work/main/.venv/bin/python bench/visibility_rays.py \\
      --mesh ../shared/meshes/stanford/dragon_vrip.ply --cameras 20 --threads 2 --rounds 3
"""
import argparse
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from visibility import cpu_model, ring_cameras  # noqa: E402

import aperture  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--cameras", type=int, default=100)
    ap.add_argument("--size", default="640,480")
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split(","))
    scene = aperture.Scene(args.mesh)
    cams = [c for _, c in ring_cameras(args.cameras, np.array([0, 0.12, 0]), 0.45, (w, h), 30.0)]
    scene.render(cams[:1], aovs="primid", threads=args.threads)  # builds the BVH

    def render():
        for k in range(0, len(cams), 25):
            scene.render(cams[k:k + 25], aovs="primid", threads=args.threads)

    runs = {
        "render primid": render,
        "face_visibility needed-rays": lambda: scene.face_visibility(cams, threads=args.threads),
        "face_visibility all-rays": lambda: scene.face_visibility(cams, threads=args.threads,
                                                                  method="all-rays"),
        "face_visibility front_only needed-rays": lambda: scene.face_visibility(
            cams, front_only=True, threads=args.threads),
        "face_visibility front_only all-rays": lambda: scene.face_visibility(
            cams, front_only=True, threads=args.threads, method="all-rays"),
    }
    seconds = {k: [] for k in runs}
    out = {}
    for _ in range(args.rounds):
        for name, fn in runs.items():
            t0 = time.perf_counter()
            out[name] = fn()
            seconds[name].append(time.perf_counter() - t0)
    for side in ("", "front_only "):
        a, b = out[f"face_visibility {side}needed-rays"], out[f"face_visibility {side}all-rays"]
        for key in a:
            assert np.array_equal(a[key], b[key]), f"{side}{key} differs between the methods"
    med = {k: statistics.median(v) for k, v in seconds.items()}
    print(f"# {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, CPU: {cpu_model()}, threads "
          f"{args.threads or 'all'}, load average {os.getloadavg()[0]:.1f}")
    print(f"# {args.mesh}: {scene.triangle_count} faces; {len(cams)} cameras {w}x{h}; medians of "
          f"{args.rounds} alternating rounds; the methods' arrays equal")
    print("| what | seconds | x render primid |")
    print("|---|---:|---:|")
    for k, v in med.items():
        print(f"| {k} | {v:.3f} | {v / med['render primid']:.1f} |")


if __name__ == "__main__":
    main()
