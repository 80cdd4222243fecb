#!/usr/bin/env python3
"""Issue 15's speed figures for visibility, side by side in one run (bench/RESULTS.md).

  faces:  face visibility of C cameras (a ring around the mesh at the reference distance,
          elevations varied) at W x H with Scene.face_visibility, against rendering the same
          C primid images with Scene.render and bincounting them (what face_pixels is).
  points: point visibility of N points (mesh vertices moved off the surface by a small random
          offset, so some are hidden and some are not) in the same cameras: million
          point-camera queries per second.
  open3d: the approach users write today: Open3D's RaycastingScene.cast_rays of each camera's
          pixel-centre rays (aperture's own rays, bench/peer_rays.py) and a NumPy bincount of
          the primitive ids, summed over the cameras (needs open3d: the venv of
          bench/install-peers.sh).

Each measurement runs --repeats times, interleaved (faces, render, open3d, points, ...), and
the medians are reported. Run with PYTHONPATH=build/python and the peers venv's python, e.g.
  PYTHONPATH=build/python ~/.cache/aperture-peers/venv/bin/python bench/visibility.py \\
      --mesh ../shared/meshes/stanford/dragon_vrip.ply --threads 2
"""
import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_rays import pinhole_rays  # noqa: E402

import aperture  # noqa: E402


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def ring_cameras(count, target, distance, size, fov):
    """count (eye, at) pairs around `target` at `distance`, azimuth evenly spread and the
    elevation swinging between -30 and +50 degrees, with their aperture cameras."""
    views = []
    for k in range(count):
        azimuth = 2 * np.pi * k / count
        elevation = np.radians(10 + 40 * np.sin(3 * azimuth))
        eye = target + distance * np.array(
            [np.cos(elevation) * np.sin(azimuth), np.sin(elevation), np.cos(elevation) * np.cos(azimuth)])
        views.append((eye, aperture.Camera(eye=tuple(eye), at=tuple(target), up=(0, 1, 0), fov=fov,
                                           size=size)))
    return views


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--cameras", type=int, default=100)
    ap.add_argument("--size", default="640,480")
    ap.add_argument("--fov", type=float, default=30.0)
    ap.add_argument("--target", default="0,0.12,0", help="look-at point (the dragon's reference)")
    ap.add_argument("--distance", type=float, default=0.45)
    ap.add_argument("--points", type=int, default=200000)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-open3d", action="store_true")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split(","))
    target = np.array([float(v) for v in args.target.split(",")])

    scene = aperture.Scene(args.mesh)
    views = ring_cameras(args.cameras, target, args.distance, (w, h), args.fov)
    cams = [c for _, c in views]
    faces = scene.triangle_count

    rng = np.random.default_rng(1)
    o3d = None
    if not args.no_open3d:
        import open3d as o3d  # noqa: F811

        mesh = o3d.io.read_triangle_mesh(args.mesh)
        vertices = np.asarray(mesh.vertices, dtype=np.float32)
        o3d_scene = o3d.t.geometry.RaycastingScene(nthreads=args.threads)
        o3d_scene.add_triangles(o3d.core.Tensor(vertices),
                                o3d.core.Tensor(np.asarray(mesh.triangles, dtype=np.uint32)))
        rays = [o3d.core.Tensor(pinhole_rays(eye, (0, 1, 0), args.fov, w, h, at=target)) for eye, _ in views]
    # Points: mesh vertices (read by Open3D) moved off the surface by ~2 mm, so some are hidden
    # and some are not; without Open3D, uniform in the scene's bounds.
    if o3d is not None:
        picked = vertices[rng.integers(0, len(vertices), size=args.points)].astype(np.float64)
        points = picked + rng.normal(scale=0.002, size=picked.shape)
    else:
        lo, hi = (np.array(b) for b in scene.bounds)
        points = rng.uniform(lo, hi, size=(args.points, 3))

    def render_bincount():
        total = np.zeros(faces, dtype=np.int64)
        for k in range(0, len(cams), 25):
            prim = scene.render(cams[k:k + 25], aovs="primid", threads=args.threads)["primid"].ravel()
            total += np.bincount(prim[prim != 0xFFFFFFFF], minlength=faces)
        return total

    def open3d_bincount():
        total = np.zeros(faces, dtype=np.int64)
        for r in rays:
            prim = o3d_scene.cast_rays(r, nthreads=args.threads)["primitive_ids"].numpy().ravel()
            total += np.bincount(prim[prim != o3d_scene.INVALID_ID], minlength=faces)
        return total

    t = {"face_visibility": [], "render_primid": [], "render_primid_bincount": [], "open3d_bincount": [],
         "point_visibility": []}
    for _ in range(args.repeats):
        s, vis = timed(lambda: scene.face_visibility(cams, threads=args.threads))
        t["face_visibility"].append(s)
        s, _ = timed(lambda: [scene.render(cams[k:k + 25], aovs="primid", threads=args.threads)
                              for k in range(0, len(cams), 25)])
        t["render_primid"].append(s)
        s, mine = timed(render_bincount)
        t["render_primid_bincount"].append(s)
        if o3d is not None:
            s, theirs = timed(open3d_bincount)
            t["open3d_bincount"].append(s)
        s, pv = timed(lambda: scene.point_visibility(points, cams, threads=args.threads))
        t["point_visibility"].append(s)
    assert np.array_equal(vis["face_pixels"], mine), "face_pixels differs from the bincount"
    med = {k: statistics.median(v) for k, v in t.items() if v}
    queries = len(points) * len(cams)
    print(f"# {time.strftime('%Y-%m-%d')}, CPU: {cpu_model()}, threads {args.threads or 'all'}, "
          f"aperture {aperture.__version__}" + (f", Open3D {o3d.__version__}" if o3d else ""))
    print(f"# mesh {args.mesh}: {faces} faces; {len(cams)} cameras {w}x{h}; {len(points)} points; "
          f"medians of {args.repeats}")
    print("| what | seconds | ratio to render primid |")
    print("|---|---:|---:|")
    for k, v in med.items():
        print(f"| {k} | {v:.3f} | {v / med['render_primid']:.2f} |")
    print(f"\nfaces seen by >= 1 camera: {(vis['face_view_count'] > 0).sum()} of {faces}; "
          f"face-camera pairs {len(vis['camera_faces_indices'])}")
    print(f"point visibility: {queries / med['point_visibility'] * 1e-6:.1f} M point-camera queries/s "
          f"({len(pv['point_cameras_indices'])} of {queries} seen)")
    if o3d is not None:
        agree = np.mean(theirs == mine)
        print(f"Open3D cast_rays + bincount / aperture face_visibility: "
              f"{med['open3d_bincount'] / med['face_visibility']:.2f}x; "
              f"/ aperture render primid + bincount: {med['open3d_bincount'] / med['render_primid_bincount']:.2f}x "
              f"(per-face pixel counts equal on {100 * agree:.2f} % of faces)")


if __name__ == "__main__":
    main()
