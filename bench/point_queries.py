"""Point queries per second (issue 44, item 5): aperture's Scene.closest_points,
signed_distance and occupancy against Open3D's RaycastingScene (compute_closest_points,
compute_distance, compute_signed_distance and compute_occupancy with nsamples 1 and 5) on the
same triangles and the same points, side by side in alternating rounds, and trimesh's
proximity queries on a subset where they finish in reasonable time.

    .venv/bin/python bench/point_queries.py --points 1e6,1e7 --meshes dragon,crown --rounds 3

Points: uniform in the mesh's bounding box grown by 10 % on each side (what SDF and occupancy
training samples draw from), float32-representable (Open3D takes float32). Both libraries use
every core the process may use (``--threads``, default 2: aperture's threads= and Open3D's
nthreads=). Prints one table row per (mesh, points, query) with medians and the ratio, as
Markdown for bench/RESULTS.md."""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import aperture

REPO = Path(__file__).resolve().parents[1]
MESHES = {
    "dragon": REPO.parent / "shared" / "meshes" / "stanford" / "dragon_vrip.ply",
    "crown": REPO.parent / "shared" / "meshes" / "scenes" / "crown_flat.ply",
    "bunny": REPO.parent / "shared" / "meshes" / "stanford" / "bun_zipper.ply",
}


def timed(f):
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def query_points(scene: aperture.Scene, n: int, seed: int) -> np.ndarray:
    lo, hi = (np.array(b) for b in scene.bounds)
    pad = 0.1 * (hi - lo)
    rng = np.random.default_rng(seed)
    return rng.uniform(lo - pad, hi + pad, (n, 3)).astype(np.float32)


def open3d_scene(o3d, scene: aperture.Scene):
    tris = scene.triangles().reshape(-1, 3).astype(np.float32)
    rs = o3d.t.geometry.RaycastingScene()
    rs.add_triangles(o3d.core.Tensor(tris), o3d.core.Tensor(np.arange(len(tris), dtype=np.uint32).reshape(-1, 3)))
    return rs


def sign_works(scene: aperture.Scene) -> bool:
    try:
        scene.signed_distance(np.zeros((1, 3)))
        return True
    except ValueError as e:
        print(f"# aperture's sign is not available here: {e}")
        return False


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--points", default="1e6,1e7", help="comma-separated point counts")
    ap.add_argument("--meshes", default="dragon,crown", help=f"comma-separated, of {', '.join(MESHES)}")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--queries", default="closest,distance,signed,occupancy",
                    help="closest, distance, signed (signed distance), occupancy")
    ap.add_argument("--nsamples", default="1,5", help="Open3D's nsamples for signed distance and occupancy")
    ap.add_argument("--trimesh-points", type=int, default=20000,
                    help="points for trimesh's closest_point and signed_distance (0: skip)")
    ap.add_argument("--sign-method", default=None,
                    help="aperture's method for signed distance and occupancy (parity, winding; default: automatic)")
    ap.add_argument("--no-open3d", action="store_true")
    args = ap.parse_args()
    o3d = None
    if not args.no_open3d:
        import open3d as o3d  # noqa: PLC0415
    queries = args.queries.split(",")
    nsamples = [int(s) for s in args.nsamples.split(",")]
    print("| mesh | triangles | points | query | aperture (method) M/s | peer | peer M/s | ratio |")
    print("|---|---:|---:|---|---:|---|---:|---:|")
    for name in args.meshes.split(","):
        scene = aperture.Scene(MESHES[name])
        rs = open3d_scene(o3d, scene) if o3d else None
        signs = sign_works(scene)
        for n in (int(float(s)) for s in args.points.split(",")):
            p32 = query_points(scene, n, 1)
            p64 = p32.astype(np.float64)
            t3 = o3d.core.Tensor(p32) if o3d else None
            ours = {
                "closest": lambda: scene.closest_points(p64, threads=args.threads),
                "distance": lambda: scene.distance(p64, threads=args.threads),
                "signed": lambda: scene.signed_distance(p64, args.sign_method, threads=args.threads),
                "occupancy": lambda: scene.occupancy(p64, args.sign_method, threads=args.threads),
            }
            peers = {
                "closest": [("open3d compute_closest_points", lambda: rs.compute_closest_points(t3, nthreads=args.threads))],
                "distance": [("open3d compute_distance", lambda: rs.compute_distance(t3, nthreads=args.threads))],
                "signed": [(f"open3d compute_signed_distance nsamples={k}",
                            lambda k=k: rs.compute_signed_distance(t3, nthreads=args.threads, nsamples=k)) for k in nsamples],
                "occupancy": [(f"open3d compute_occupancy nsamples={k}",
                               lambda k=k: rs.compute_occupancy(t3, nthreads=args.threads, nsamples=k)) for k in nsamples],
            }
            for q in queries:
                if q in ("signed", "occupancy") and not signs:
                    continue
                times_ours: list[float] = []
                times_peer: dict[str, list[float]] = {label: [] for label, _ in (peers[q] if rs else [])}
                method = ""
                for _ in range(args.rounds):  # alternating: ours, then each peer, each round
                    times_ours.append(timed(ours[q]))
                    method = scene.last_query.get("method") or ""
                    for label, f in peers[q] if rs else []:
                        times_peer[label].append(timed(f))
                ours_rate = n / statistics.median(times_ours) / 1e6
                label_ours = f"{ours_rate:.2f}" + (f" ({method})" if method else "")
                if not times_peer:
                    print(f"| {name} | {scene.triangle_count} | {n:.0e} | {q} | {label_ours} | | | |", flush=True)
                for label, ts in times_peer.items():
                    peer_rate = n / statistics.median(ts) / 1e6
                    print(f"| {name} | {scene.triangle_count} | {n:.0e} | {q} | {label_ours} | {label} | "
                          f"{peer_rate:.2f} | {ours_rate / peer_rate:.2f} |", flush=True)
            del p32, p64, t3
        if args.trimesh_points:
            trimesh_rows(scene, name, args.trimesh_points, signs, args.threads, args.sign_method)


def trimesh_rows(scene: aperture.Scene, name: str, n: int, signs: bool, threads: int, method: str | None) -> None:
    import trimesh  # noqa: PLC0415

    tris = scene.triangles()
    mesh = trimesh.Trimesh(vertices=tris.reshape(-1, 3), faces=np.arange(3 * len(tris)).reshape(-1, 3), process=True)
    p = query_points(scene, n, 2).astype(np.float64)
    rows = [("closest", "trimesh proximity.closest_point", lambda: trimesh.proximity.closest_point(mesh, p),
             lambda: scene.closest_points(p, threads=threads))]
    if signs:
        rows.append(("signed", "trimesh proximity.signed_distance", lambda: trimesh.proximity.signed_distance(mesh, p),
                     lambda: scene.signed_distance(p, method, threads=threads)))
    for q, label, peer, ours in rows:
        tp, to = timed(peer), timed(ours)
        if q == "signed":
            label += f" (ours: {scene.last_query['method']})"
        print(f"| {name} | {scene.triangle_count} | {n:.0e} | {q} | {n / to / 1e6:.2f} | {label} | "
              f"{n / tp / 1e6:.4f} | {tp / to:.0f} |", flush=True)


if __name__ == "__main__":
    main()
