#!/usr/bin/env python3
"""Peer comparison (issue 4 item 6, issue 13 item 6): aperture against bare Embree (its own
--baseline), Open3D's RaycastingScene, Embree's viewer (Debian embree-tools) and Mitsuba 3
(llvm_ad_rgb), same mesh, camera and resolution, measured side by side in one run. Prints a
table and writes it as Markdown to OUT.md, with the CPU model (lscpu), the date, the thread count
and the exact command in its header.

    bash bench/install-peers.sh            # once, as root
    python3 bench/peers.py --aperture build/apps/aperture --repeat 3 --check out/peers out/peers.md

Every peer gets the same worker-thread count: --threads N, or all the CPUs this process may run on
(0); the number is passed explicitly to each and recorded. Per scene and repetition, one after
the other:
  aperture  `aperture bench --aov color --spp 1 --baseline` (16-wide packets): median Mrays/s of
            the render and of bare rtcIntersect16 on the same rays. The color AOV is the eye-light
            |N.D|, the work of the viewer's eyelight shader and Mitsuba's geo_normal AOV: the
            viewer and Mitsuba ratios use this figure.
  aperture  `aperture bench --aov distance,normal,primid,geomid`: median Mrays/s with the AOVs
            Open3D's cast_rays returns; the Open3D ratio uses this figure.
  open3d    bench/peers_open3d.py time: RaycastingScene.cast_rays on aperture's own rays (the
            pixel centres of the same camera, bench/peer_rays.py, built before the clock),
            median Mrays/s over the same number of frames (see that file).
  viewer    `viewer --shader eyelight --benchmark WARMUP FRAMES` (legacy mode: FRAMES timed frames);
            it prints BENCHMARK_RENDER_MRAYPS_AVG = W*H*fps/1e6, the mean over the timed frames
            (the viewer reports no median). eyelight is its cheapest shader, the same |N.D| as
            aperture's color AOV; the viewer traces one ray at a time (Debian's binary imports
            rtcIntersect1 and rtcOccluded1 only: `nm -D /usr/bin/viewer`).
  mitsuba   bench/peers_mitsuba.py time: median Mrays/s of the render alone (see that file).
Rays per frame are W*H (1 spp, primary rays only) for all.

Camera conventions (checked by --check, which renders one frame of each and compares, before any
timing; a failed Open3D check stops the run, since its rays would not be aperture's):
  aperture: right-handed, U = up x W right, row 0 at the top, --fov on --fov-axis.
  Open3D:   handed aperture's rays (bench/peer_rays.py); --check requires the same triangle on
            >= 99.9 % of pixels and distances within 1e-4 relative (bench/peers_check.py).
  viewer:   --vp/--vi (or --vd)/--vu; --fov is the VERTICAL field of view in degrees; the
            default --righthanded matches aperture (no mirroring). A horizontal fov (crown) is
            converted: fov_y = 2 atan(tan(fov_x / 2) * H / W). The viewer shoots rays through
            pixel corners, aperture through pixel centres: a half-pixel shift, visible only on
            silhouettes (coverage differs on a fraction of a percent of the pixels). Verified on
            the dragon: the viewer at 2048x2048, odd rows and columns (= the 1024x1024 pixel
            centres) against aperture at 1024x1024: identical coverage, |N.D| within 8-bit
            rounding (p99 3.9e-3). Its eyelight shader writes |N.D| to green on front faces and
            to red on back faces.
  Mitsuba:  perspective sensor, fov + fov_axis, look_at(eye, at, up); stratified sampler with
            jitter=false and 1 sample = pixel centres. Matches aperture to float precision.
"""
import argparse
import json
import math
import os
import platform
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# The reference cameras of shared/meshes/README.md. Sizes: the crown's and bathroom's are the
# authors'; the bunny and dragon have none there, 1024x1024 is ours.
SCENES = {
    "bunny": dict(mesh="stanford/bun_zipper.ply", eye=(-0.02, 0.11, 0.35), at=(-0.017, 0.11, 0.0),
                  up=(0, 1, 0), fov=30.0, axis="y", size=(1024, 1024)),
    "dragon": dict(mesh="stanford/dragon_vrip.ply", eye=(0, 0.12, 0.45), at=(0, 0.12, 0),
                   up=(0, 1, 0), fov=30.0, axis="y", size=(1024, 1024)),
    # The authors' render also mirrors x and uses a thin lens; here: a pinhole, not mirrored.
    "crown": dict(mesh="scenes/crown_flat.ply", eye=(0, 5.5, 24), at=(0, 11, -10), up=(0, 1, 0),
                  fov=47.0, axis="x", size=(1000, 1400)),
    "bathroom": dict(mesh="scenes/contemporary-bathroom_flat.ply", eye=(0.00724, 0.91240, -0.22758),
                     dir=(-0.751879, 0.015471, -0.659119), up=(0.0116337, 0.99988, 0.0101985),
                     fov=55.0, axis="y", size=(1024, 1024)),
}
# Targets, aperture's Mrays/s over the peer's: issue 13 item 6 (Open3D, viewer) and item 2 (bare
# Embree on the same rays). None for Mitsuba.
OPEN3D_TARGET = 4.0
VIEWER_TARGET = 2.5
BASELINE_TARGET = 0.95
# Untimed frames before the timed ones, for every peer (Mitsuba compiles its kernels in the first).
WARMUP = 3
# What Open3D's cast_rays returns, in aperture's AOV names (docs/aovs.md).
GEOMETRY_AOVS = ("distance", "normal", "primid", "geomid")


def csv(v):
    return ",".join(repr(float(x)) for x in v)


def vertical_fov(s):
    if s["axis"] == "y":
        return s["fov"]
    w, h = s["size"]
    return math.degrees(2 * math.atan(math.tan(math.radians(s["fov"]) / 2) * h / w))


def cpu_model():
    """lscpu's "Model name" (/proc/cpuinfo's "model name" without lscpu)."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    with open("/proc/cpuinfo") as f:
        return next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), platform.processor())


def worker_threads(requested):
    """The thread count every peer gets: the one asked for, else every CPU this process may use."""
    return requested if requested > 0 else len(os.sched_getaffinity(0))


def debian_version(package):
    p = subprocess.run(["dpkg-query", "-W", "-f=${Version}", package], capture_output=True, text=True)
    return p.stdout.strip() if p.returncode == 0 else "?"


def run(cmd, log):
    log.append(" ".join(shlex.quote(c) for c in cmd))
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.exit(f"peers: failed ({p.returncode}): {log[-1]}\n{p.stdout[-2000:]}{p.stderr[-2000:]}")
    return p.stdout + p.stderr


def camera_args_aperture(s, mesh, aovs):
    a = ["--mesh", mesh, "--eye", csv(s["eye"])]
    a += ["--at", csv(s["at"])] if "at" in s else ["--dir", csv(s["dir"])]
    a += ["--up", csv(s["up"]), "--fov", repr(s["fov"]), "--fov-axis", s["axis"],
          "--size", "%d,%d" % s["size"], "--spp", "1", "--aov", aovs]
    return a


def camera_args_viewer(s, mesh):
    a = ["viewer", "-i", mesh, "--vp", *map(repr, map(float, s["eye"]))]
    a += ["--vi", *map(repr, map(float, s["at"]))] if "at" in s else ["--vd", *map(repr, map(float, s["dir"]))]
    a += ["--vu", *map(repr, map(float, s["up"])), "--fov", repr(vertical_fov(s)),
          "--size", str(s["size"][0]), str(s["size"][1]), "--shader", "eyelight"]
    return a


def camera_args_python(s, mesh):
    """The camera flags of peers_mitsuba.py and peers_open3d.py."""
    # --opt=value: argparse would take "-0.02,..." for an option.
    a = ["--mesh=" + mesh, "--eye=" + csv(s["eye"])]
    a += ["--at=" + csv(s["at"])] if "at" in s else ["--dir=" + csv(s["dir"])]
    a += ["--up=" + csv(s["up"]), "--fov=" + repr(s["fov"]), "--fov-axis=" + s["axis"],
          "--size=%d,%d" % s["size"]]
    return a


def aperture_bench(name, tag, s, mesh, aovs, extra, args, tmp, log):
    j = os.path.join(tmp, f"{name}_aperture_{tag}.json")
    run([args.aperture, "bench", *camera_args_aperture(s, mesh, aovs), "--threads", str(args.threads),
         "--frames", str(args.frames), "--warmup", str(WARMUP), "--builds", "1", *extra, "--quiet", "--json", j], log)
    with open(j) as f:
        return json.load(f)


def python_peer(name, script, s, mesh, args, tmp, log):
    j = os.path.join(tmp, f"{name}_{os.path.splitext(script)[0]}.json")
    run([args.python, os.path.join(HERE, script), "time", *camera_args_python(s, mesh), "--threads", str(args.threads),
         "--frames", str(args.frames), "--warmup", str(WARMUP), "--json", j], log)
    with open(j) as f:
        return json.load(f)


def measure(name, s, mesh, args, tmp, log):
    out = {}
    a = aperture_bench(name, "color", s, mesh, "color", ["--baseline"], args, tmp, log)
    out["aperture"], out["baseline"] = a["mrays_per_s_median"], a["baseline_mrays_per_s_median"]
    out["isa"], out["threads"] = a["config"]["isa"], a["config"]["threads"]
    a = aperture_bench(name, "geometry", s, mesh, ",".join(GEOMETRY_AOVS), [], args, tmp, log)
    out["aperture_geometry"] = a["mrays_per_s_median"]

    o = python_peer(name, "peers_open3d.py", s, mesh, args, tmp, log)
    out["open3d"], out["open3d_version"] = o["mrays_per_s_median"], o["config"]["open3d"]

    viewer = [*camera_args_viewer(s, mesh), "--threads", str(args.threads), "--benchmark", str(WARMUP), str(args.frames)]
    text = run(viewer, log)
    m = re.search(r"BENCHMARK_RENDER_MRAYPS_AVG\s+([0-9.eE+-]+)", text)
    if not m:
        sys.exit(f"peers: no BENCHMARK_RENDER_MRAYPS_AVG in the viewer's output:\n{text[-2000:]}")
    out["viewer"] = float(m.group(1))

    o = python_peer(name, "peers_mitsuba.py", s, mesh, args, tmp, log)
    out["mitsuba"], out["mitsuba_version"] = o["mrays_per_s_median"], o["config"]["mitsuba"]
    return out


def check(name, s, mesh, args, log):
    """Renders one frame with every peer, compares with peers_check.py; exits if Open3D's differs."""
    d = args.check
    exr, ppm = os.path.join(d, f"{name}_aperture.exr"), os.path.join(d, f"{name}_viewer.ppm")
    npy, png = os.path.join(d, f"{name}_mitsuba.npy"), os.path.join(d, f"{name}_check.png")
    npz, stem = os.path.join(d, f"{name}_open3d.npz"), os.path.join(d, f"{name}_aperture")
    js = os.path.join(d, f"{name}_check.json")
    run([args.aperture, "render", *camera_args_aperture(s, mesh, "color"), "--quiet", "--out", exr], log)
    # One AOV per .npy: exact uint32 ids (an EXR reader may hand them back as float).
    for aov in GEOMETRY_AOVS:
        run([args.aperture, "render", *camera_args_aperture(s, mesh, aov), "--quiet", "--out", f"{stem}_{aov}.npy"],
            log)
    run([*camera_args_viewer(s, mesh), "-o", ppm], log)
    run([args.python, os.path.join(HERE, "peers_mitsuba.py"), "image", *camera_args_python(s, mesh), "--out", npy], log)
    run([args.python, os.path.join(HERE, "peers_open3d.py"), "image", *camera_args_python(s, mesh),
         "--threads", str(args.threads), "--out", npz], log)
    print(run([args.python, os.path.join(HERE, "peers_check.py"), "--aperture", exr, "--viewer", ppm,
               "--mitsuba", npy, "--aperture-geometry", stem, "--open3d", npz, "--mesh", mesh,
               "--png", png, "--json", js],
              log).rstrip())
    with open(js) as f:
        return json.load(f)


def busy_warning(load0):
    """A Markdown line (and stderr) when the load average at the start says other work was running
    (the one at the end counts the peers' own threads)."""
    if load0[0] < 0.5:
        return []
    line = (f"**Not an idle machine** (load average {load0[0]:.2f} at the start): other work shared the "
            "CPUs; do not quote these figures.")
    print("peers: " + line.replace("**", ""), file=sys.stderr)
    return [line, ""]


def fmt(x, nd=2):
    return "—" if x is None else f"{x:.{nd}f}"


def against(ratio, target, nd=2):
    return f"{ratio:.{nd}f} " + ("✓" if ratio >= target else "✗") + f" (≥{target:g})"


def table(h, rs):
    """Markdown table, first column left-aligned, the others right-aligned."""
    rule = "|" + "|".join("---" if i == 0 else "---:" for i in range(len(h))) + "|"
    return "\n".join(["| " + " | ".join(h) + " |", rule]
                     + ["| " + " | ".join(r) + " |" for r in rs])


def plain(h, rs):
    w = [max(len(h[i]), *(len(r[i]) for r in rs)) for i in range(len(h))]
    return "\n".join("  ".join(c.ljust(w[i]) if i == 0 else c.rjust(w[i]) for i, c in enumerate(r)) for r in [h, *rs])


def peer_row(m, targets):
    """aperture against Open3D, the viewer and Mitsuba: Mrays/s and ratios (targets marked or not)."""
    ro, rv, rm = m["aperture_geometry"] / m["open3d"], m["aperture"] / m["viewer"], m["aperture"] / m["mitsuba"]
    return [fmt(m["aperture_geometry"]), fmt(m["open3d"]), against(ro, OPEN3D_TARGET) if targets else f"{ro:.2f}",
            fmt(m["aperture"]), fmt(m["viewer"]), against(rv, VIEWER_TARGET) if targets else f"{rv:.2f}",
            fmt(m["mitsuba"]), f"{rm:.2f}"]


PEER_HEAD = ["aperture geometry AOVs Mrays/s", "Open3D Mrays/s", "× Open3D", "aperture color Mrays/s",
             "viewer Mrays/s", "× viewer", "Mitsuba Mrays/s", "× Mitsuba"]
KEYS = ("aperture", "aperture_geometry", "baseline", "open3d", "viewer", "mitsuba")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("markdown", help="write the tables here (Markdown)")
    ap.add_argument("--aperture", default=os.environ.get("APERTURE_BIN", os.path.join(ROOT, "build/apps/aperture")))
    ap.add_argument("--python", default=os.path.join(
        os.environ.get("APERTURE_PEERS_VENV", os.path.expanduser("~/.cache/aperture-peers/venv")), "bin/python"),
        help="python with mitsuba and open3d (bench/install-peers.sh)")
    ap.add_argument("--meshes", default=os.environ.get("APERTURE_MESHES", os.path.join(ROOT, "..", "shared", "meshes")))
    ap.add_argument("--scenes", default="dragon,crown,bathroom", help="comma list of " + ",".join(SCENES))
    ap.add_argument("--repeat", type=int, default=2, help="side-by-side runs per scene (medians reported)")
    ap.add_argument("--frames", type=int, default=10, help="timed frames per peer and run")
    ap.add_argument("--threads", type=int, default=0,
                    help="worker threads for every peer (0 = every CPU this process may use; the number is recorded)")
    ap.add_argument("--check", metavar="DIR",
                    help="first render one image per peer and compare them (PNGs here); stops if Open3D's differs")
    args = ap.parse_args()
    command = shlex.join([sys.executable, *sys.argv])
    args.threads = worker_threads(args.threads)
    scenes = [x for x in args.scenes.split(",") if x]
    for x in scenes:
        if x not in SCENES:
            sys.exit(f"peers: unknown scene {x!r}; known: {', '.join(SCENES)}")
    for exe in (args.aperture, args.python):
        if not os.access(exe, os.X_OK):
            sys.exit(f"peers: {exe} is not executable (build aperture; run bench/install-peers.sh)")
    if args.check:
        os.makedirs(args.check, exist_ok=True)

    log, runs, checks = [], {x: [] for x in scenes}, {}
    load0 = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="aperture-peers-") as tmp:
        for x in scenes:
            s, mesh = SCENES[x], os.path.abspath(os.path.join(args.meshes, SCENES[x]["mesh"]))
            if args.check:
                checks[x] = check(x, s, mesh, args, log)
            for r in range(args.repeat):
                t = time.time()
                m = measure(x, s, mesh, args, tmp, log)
                runs[x].append(m)
                print(f"{x} run {r + 1}: aperture {m['aperture']:.2f} (geometry AOVs {m['aperture_geometry']:.2f}), "
                      f"baseline {m['baseline']:.2f}, open3d {m['open3d']:.2f}, viewer {m['viewer']:.2f}, "
                      f"mitsuba {m['mitsuba']:.2f} Mrays/s ({time.time() - t:.0f} s)", file=sys.stderr)
    load1 = os.getloadavg()

    rows, bare, per_run = [], [], []
    for x in scenes:
        med = {k: statistics.median(m[k] for m in runs[x]) for k in KEYS}
        size = "%dx%d" % SCENES[x]["size"]
        rows.append([x, size, *peer_row(med, True)])
        bare.append([x, size, fmt(med["aperture"]), fmt(med["baseline"]),
                     against(med["aperture"] / med["baseline"], BASELINE_TARGET, 3)])
        for i, m in enumerate(runs[x]):
            per_run.append([x, str(i + 1), *peer_row(m, False), fmt(m["baseline"])])

    head = ["scene", "size", *PEER_HEAD]
    print(plain(head, rows))
    first = runs[scenes[0]][0]
    md = [f"## Peer comparison ({time.strftime('%Y-%m-%d %H:%M')})", "",
          "Command:", "", "```", command, "```", "",
          f"CPU: {cpu_model()} (lscpu), {os.cpu_count()} hardware threads; {args.threads} worker threads for every "
          f"peer; aperture's Embree ISA {first['isa']}; Open3D {first['open3d_version']} (open3d-cpu), "
          f"Mitsuba {first['mitsuba_version']} (llvm_ad_rgb), Embree viewer "
          f"(embree-tools {debian_version('embree-tools')}); "
          f"load average {load0[0]:.2f} at the start, {load1[0]:.2f} at the end. "
          f"Medians of {args.repeat} side-by-side run(s) per scene, {args.frames} timed frames each after "
          f"{WARMUP} untimed; "
          "1 spp primary rays, Mrays/s = W·H / seconds per frame. × Open3D: aperture with the AOVs "
          "cast_rays returns (distance, normal, primid, geomid) on the same rays; × viewer and × Mitsuba: "
          "aperture's color AOV (eye-light |N·D|, what the viewer's eyelight shader and Mitsuba's "
          "geo_normal AOV compute).", "",
          *busy_warning(load0),
          table(head, rows), "",
          "Against bare Embree (`aperture bench --baseline`: rtcIntersect16 on the same rays):", "",
          table(["scene", "size", "aperture color Mrays/s", "baseline Mrays/s", "aperture/baseline"], bare), "",
          "Each run:", "",
          table(["scene", "run", *PEER_HEAD, "baseline Mrays/s"], per_run), ""]
    if checks:
        ch = [[x, f"{100 * c['open3d']['same_triangle']:.3f}%", f"{c['open3d']['distance_rel_max']:.1e}",
               f"{100 * c['viewer']['coverage_mismatch']:.3f}%", f"{c['viewer']['eyelight_absdiff_median']:.1e}",
               f"{100 * c['mitsuba']['coverage_mismatch']:.3f}%", f"{c['mitsuba']['eyelight_absdiff_median']:.1e}"]
              for x, c in checks.items()]
        md += ["Same image? Against aperture's (`--check`; side-by-side PNGs in " + f"`{args.check}`):", "",
               table(["scene", "Open3D same triangle", "Open3D max rel Δ distance", "viewer coverage differs",
                      "viewer median abs Δ eye-light", "Mitsuba coverage differs", "Mitsuba median abs Δ eye-light"],
                     ch), "",
               "Open3D traces aperture's own rays (pass marks: the same triangle on ≥ 99.9 % of pixels, distances "
               "within 1e-4). The viewer samples pixel corners (aperture and Mitsuba pixel centres) and stores 8 "
               "bits, hence its small differences on silhouettes.", ""]
    commands = dict.fromkeys(c.replace(tmp, "$TMP") for c in log)
    md += ["Commands ($TMP: a temporary directory):", "", "```", *commands, "```", ""]
    with open(args.markdown, "w") as f:
        f.write("\n".join(md))
    print(f"peers: wrote {args.markdown}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
