#!/usr/bin/env python3
"""Mitsuba 3 side of the peer comparison (run with the venv python of bench/install-peers.sh).

  time:  renders the scene with variant llvm_ad_rgb, the `aov` integrator (AOV geo_normal, the
         input of aperture's eye-light colour), 1 spp from the `stratified` sampler with
         jitter=false (sample_count 1: the sample is the stratum centre, i.e. the pixel centre,
         like aperture's spp 1) and a `box` reconstruction filter (each sample lands in its own
         pixel only). Scene loading, BVH build and the first render (LLVM kernel compilation) are
         not timed: after --warmup untimed renders, --frames renders are timed one by one
         (render + evaluation + sync) and Mrays/s = W*H*spp / seconds per render.
  image: renders AOVs geo_normal and position once and writes the eye-light |N.D| (D from the
         eye to the hit point) and coverage as a .npy (H x W x 2) for bench/peers_check.py.

Camera: `perspective` sensor, fov + fov_axis as given, to_world = look_at(eye, at, up) (with
--dir, at = eye + dir). Verified against aperture by bench/peers_check.py: identical coverage and
eye-light equal to ~1e-7 on the dragon, so there is no mirroring between the two.
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from peer_cli import peer_arguments, report_timing, timing_summary  # noqa: E402


def main():
    args = peer_arguments(__doc__, "PLY file (Mitsuba's ply plugin)", "Dr.Jit worker threads (0 = all cores)", "image: .npy to write")

    import drjit as dr
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    if args.threads > 0:
        dr.set_thread_count(args.threads)

    at = args.at if args.at is not None else [e + d for e, d in zip(args.eye, args.dir)]
    w, h = args.size
    aovs = "nn:geo_normal" if args.mode == "time" else "nn:geo_normal,pp:position"
    t0 = time.perf_counter()
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "aov", "aovs": aovs},
        "sensor": {
            "type": "perspective",
            "fov": args.fov,
            "fov_axis": args.fov_axis,
            # aperture starts rays at t = 0; Mitsuba needs near > 0: keep it far below any hit.
            "near_clip": 1e-4,
            "far_clip": 1e7,
            "to_world": mi.ScalarTransform4f().look_at(origin=args.eye, target=at, up=args.up),
            "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}},
            "sampler": {"type": "stratified", "sample_count": 1, "jitter": False},
        },
        # face_normals: skip Mitsuba's vertex-normal computation at load (not timed anyway).
        "mesh": {"type": "ply", "filename": args.mesh, "face_normals": True},
    })
    load_s = time.perf_counter() - t0

    def render():
        img = mi.render(scene, spp=1)
        dr.eval(img)
        dr.sync_thread()
        return img

    if args.mode == "image":
        import numpy as np
        a = np.array(render())
        n, p = a[..., 0:3], a[..., 3:6]
        d = p - np.array(args.eye, dtype=np.float64)
        length = np.linalg.norm(d, axis=-1)
        hit = np.linalg.norm(n, axis=-1) > 0.5
        eyelight = np.where(hit, np.abs((n * d).sum(-1)) / np.maximum(length, 1e-30), 0.0)
        np.save(args.out, np.stack([eyelight, hit.astype(np.float64)], axis=-1).astype(np.float32))
        return 0

    for _ in range(args.warmup):
        render()
    secs = []
    for _ in range(args.frames):
        t = time.perf_counter()
        render()
        secs.append(time.perf_counter() - t)
    timing = timing_summary(secs, w, h)
    res = {
        **timing,
        "frames": args.frames,
        "warmup": args.warmup,
        "load_and_build_seconds": load_s,
        "config": {"variant": "llvm_ad_rgb", "integrator": "aov " + aovs,
                   "sampler": "stratified, sample_count 1, jitter false", "rfilter": "box",
                   "width": w, "height": h, "spp": 1, "mitsuba": mi.__version__,
                   "threads": dr.thread_count()},
    }
    report_timing("mitsuba", "renders", res, args.frames, args.json)
    return 0


if __name__ == "__main__":
    sys.exit(main())
