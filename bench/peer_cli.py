"""What every peer worker script (peers_open3d.py, peers_mitsuba.py) takes from
bench/peers.py: a mode, the mesh, the reference camera (eye, at or dir, up, fov), the image
size, frames and threads, and where to write; and the timing summary each reports."""
import argparse
import json
import statistics
import sys


def vec3(s):
    v = [float(x) for x in s.split(",")]
    if len(v) != 3:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z, got {s!r}")
    return v


def size2(s):
    v = [int(x) for x in s.split(",")]
    if len(v) != 2 or min(v) <= 0:
        raise argparse.ArgumentTypeError(f"expected W,H, got {s!r}")
    return v


def peer_arguments(doc, mesh_help, threads_help, out_help):
    """Parses the worker's arguments (sys.argv); the help texts name the peer's own reader,
    thread setting and image file."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["time", "image"])
    ap.add_argument("--mesh", required=True, help=mesh_help)
    ap.add_argument("--eye", type=vec3, required=True)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--at", type=vec3)
    g.add_argument("--dir", type=vec3)
    ap.add_argument("--up", type=vec3, default=[0.0, 1.0, 0.0])
    ap.add_argument("--fov", type=float, required=True, help="degrees")
    ap.add_argument("--fov-axis", choices=["x", "y"], default="y")
    ap.add_argument("--size", type=size2, required=True, help="W,H")
    ap.add_argument("--frames", type=int, default=10)
    ap.add_argument("--warmup", type=int, default=2)
    ap.add_argument("--threads", type=int, default=0, help=threads_help)
    ap.add_argument("--json", help="time: write the figures here")
    ap.add_argument("--out", help=out_help)
    return ap.parse_args()


def timing_summary(seconds, width, height):
    """Mrays/s of every timed frame of width x height primary rays: the median, min, max and
    coefficient of variation, as the JSON keys bench/peers.py reads."""
    mrays = [width * height / s / 1e6 for s in seconds]
    return {
        "mrays_per_s_median": statistics.median(mrays),
        "mrays_per_s_min": min(mrays),
        "mrays_per_s_max": max(mrays),
        "mrays_per_s_cv": statistics.pstdev(mrays) / statistics.mean(mrays),
    }


def report_timing(peer, what, res, frames, json_path):
    """Prints the peer's timing line on stderr and writes `res` as JSON when asked."""
    print(f"{peer}: median {res['mrays_per_s_median']:.2f} Mrays/s (min {res['mrays_per_s_min']:.2f}, "
          f"max {res['mrays_per_s_max']:.2f}, cv {100 * res['mrays_per_s_cv']:.1f}%, {frames} {what})",
          file=sys.stderr)
    if json_path:
        with open(json_path, "w") as f:
            json.dump(res, f, indent=2)
