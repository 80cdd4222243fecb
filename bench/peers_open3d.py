#!/usr/bin/env python3
"""Open3D side of the peer comparison (run with the venv python of bench/install-peers.sh).

  time:  traces aperture's own rays (bench/peer_rays.py: the pixel centres of the camera given,
         float32) with `RaycastingScene.cast_rays`, which returns the AOVs aperture renders with
         --aov distance,normal,primid,geomid: t_hit, primitive_normals, primitive_ids,
         geometry_ids (and primitive_uvs, which it always computes). The mesh is read with
         Open3D's own reader and added as one geometry; loading, the BVH build and the rays are
         done before the clock starts. After --warmup untimed casts, --frames casts of the whole
         image are timed one by one, and Mrays/s = W*H / seconds per cast. Each cast allocates
         its output tensors (cast_rays takes no buffers to reuse; aperture's bench reuses its
         framebuffer); the result is freed after the clock stops. --threads goes to both the
         scene build and cast_rays (`nthreads`; 0 = Open3D's automatic choice).
  image: casts once and writes the four AOVs to a .npz (t_hit, normal, primid, geomid) for
         bench/peers_check.py --open3d.
"""
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_cli import peer_arguments, report_timing, timing_summary  # noqa: E402
from peer_rays import pinhole_rays  # noqa: E402


def read_mesh(o3d, path):
    """Vertices (N, 3) float32 and triangles (M, 3) uint32 of the mesh at path, by Open3D's reader
    (the triangles in the file's order, as aperture's primid numbers them)."""
    mesh = o3d.io.read_triangle_mesh(path)
    vertices = np.asarray(mesh.vertices, dtype=np.float32)
    triangles = np.asarray(mesh.triangles, dtype=np.uint32)
    if len(triangles) == 0:
        sys.exit(f"peers_open3d: {path}: Open3D read no triangles")
    return vertices, triangles


def load_scene(o3d, path, threads):
    """A RaycastingScene holding the mesh at path as geometry 0; returns it and its triangle count."""
    vertices, triangles = read_mesh(o3d, path)
    scene = o3d.t.geometry.RaycastingScene(nthreads=threads)
    scene.add_triangles(o3d.core.Tensor(vertices), o3d.core.Tensor(triangles))
    return scene, len(triangles)


def main():
    args = peer_arguments(__doc__, "PLY or OBJ file (Open3D's reader)", "Open3D nthreads (0 = automatic)", "image: .npz to write")

    import open3d as o3d

    w, h = args.size
    rays = o3d.core.Tensor(pinhole_rays(args.eye, args.up, args.fov, w, h, at=args.at, view=args.dir,
                                        fov_axis=args.fov_axis))
    t0 = time.perf_counter()
    scene, triangles = load_scene(o3d, args.mesh, args.threads)
    load_s = time.perf_counter() - t0

    if args.mode == "image":
        r = scene.cast_rays(rays, nthreads=args.threads)
        np.savez(args.out, t_hit=r["t_hit"].numpy(), normal=r["primitive_normals"].numpy(),
                 primid=r["primitive_ids"].numpy(), geomid=r["geometry_ids"].numpy())
        return 0

    for _ in range(args.warmup):
        scene.cast_rays(rays, nthreads=args.threads)
    secs = []
    for _ in range(args.frames):
        t = time.perf_counter()
        r = scene.cast_rays(rays, nthreads=args.threads)
        secs.append(time.perf_counter() - t)
        del r  # freed outside the clock
    timing = timing_summary(secs, w, h)
    res = {
        **timing,
        "frames": args.frames,
        "warmup": args.warmup,
        "load_and_build_seconds": load_s,
        "triangles": triangles,
        "config": {"call": "RaycastingScene.cast_rays", "rays": "aperture's pixel centres, float32",
                   "outputs": "t_hit, geometry_ids, primitive_ids, primitive_uvs, primitive_normals",
                   "width": w, "height": h, "spp": 1, "open3d": o3d.__version__,
                   "nthreads": args.threads},
    }
    report_timing("open3d", "casts", res, args.frames, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
