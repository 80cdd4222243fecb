#!/usr/bin/env bash
# Many meshes in one batch (issue 13, item 5): does loading and building scene k+1 while scene k
# renders hide the loads? Two jobs of several scenes ("scenes", docs/batch.md):
#   small: SMALL scans of the Stanford bunny (69,451 triangles), each placed differently (turned
#          about +Y by 7.2 degrees per scan), CAMS_SMALL orbit cameras each;
#   large: LARGE scenes cycling dragon, crown, bathroom (../shared/meshes), each at its reference
#          camera (bench/run_benchmarks.sh) and CAMS_LARGE cameras stepped slightly from it.
# Without ../shared/meshes both jobs use procedural:spheres (69k and 2M triangles) instead.
#
# Definitions (all times from the runs' summary.json, so process start-up is left out):
#   R       = rays of all images of the job (summary "rays").
#   T_pipe  = elapsed_seconds of `aperture batch` on the K-scene job: from the moment scene 0 is
#             built (nothing can hide its load) to the last image written, while scenes 1..K-1
#             load and build on a background thread during the renders.
#   S_k     = elapsed_seconds of `aperture batch` on scene k alone (a one-scene job with the same
#             cameras, settings and outputs): its images rendered and written with the scene
#             already built; its load and build are outside elapsed_seconds.
#   steady-state throughput summed over meshes = R / sum_k S_k;  pipelined throughput = R / T_pipe.
#   ratio = pipelined / steady-state = sum_k S_k / T_pipe (target >= 0.9): 1 when the loads are
#   completely hidden and steal nothing from the renders.
# Also printed: L = sum over scenes of load + build seconds (what K separate runs would add,
# sum_k S_k + L, and what the pipeline hides).
#
# Usage: bench/many_meshes.sh [--tiny] [BUILD_DIR]
#   --tiny: 3 small and 2 large scenes, 2 cameras each, 64x48 (checks the script works; its
#   figures mean nothing). Environment: SMALL (50), LARGE (5), CAMS_SMALL (4), CAMS_LARGE (16),
#   SIZE (1920,1080), AOVS (depth,normal), THREADS (0 = all cores).
# Not part of CI; run on an idle machine. Writes into a temporary directory, removed at exit.
set -euo pipefail
cd "$(dirname "$0")/.."
tiny=0
if [[ ${1:-} == --tiny ]]; then
  tiny=1
  shift
fi
build=${1:-build}
bin="$(pwd)/$build/apps/aperture"
[[ -x $bin ]] || { echo "many_meshes: build first ($bin missing)"; exit 2; }
if ((tiny)); then
  SMALL=3 LARGE=2 CAMS_SMALL=2 CAMS_LARGE=2 SIZE=64,48
fi
export SMALL=${SMALL:-50} LARGE=${LARGE:-5} CAMS_SMALL=${CAMS_SMALL:-4} CAMS_LARGE=${CAMS_LARGE:-16}
export SIZE=${SIZE:-1920,1080} AOVS=${AOVS:-depth,normal} THREADS=${THREADS:-0}
export MESHES
MESHES=$(cd .. && pwd)/shared/meshes
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

python3 - "$dir" <<'PY'
import json, os, sys
out = sys.argv[1]
meshes = os.environ["MESHES"]
have = lambda rel: os.path.isfile(os.path.join(meshes, rel))
w, h = (int(v) for v in os.environ["SIZE"].split(","))
shared = {"aovs": os.environ["AOVS"], "size": [w, h], "compression": "none",
          "performance": {"threads": int(os.environ["THREADS"])}}

def small_job(n, cams):
    if have("stanford/bun_zipper.ply"):
        mesh, centre, radius = os.path.join(meshes, "stanford/bun_zipper.ply"), [-0.017, 0.11, 0], 0.35
    else:
        print("many_meshes: ../shared/meshes absent: small scans are procedural:spheres?tris=69000")
        mesh, centre, radius = "procedural:spheres?tris=69000", [0, 0, 0], 12
    scenes = [{"name": f"scan{k:03d}",
               "scene": {"meshes": [{"path": mesh, "transform": {
                   "rotate": {"axis": [0, 1, 0], "angle": 7.2 * k}}}]}}
              for k in range(n)]
    cameras = [{"name": "orbit", "orbit": {"centre": centre, "radius": radius, "height": 0.02 * radius},
                "frames": cams, "fov": 30}]
    return dict(shared, scenes=scenes, cameras=cameras)

# Reference cameras of bench/run_benchmarks.sh; camera i steps the eye by i * step.
LARGE = [
    ("dragon", "stanford/dragon_vrip.ply",
     {"eye": [0, 0.12, 0.45], "at": [0, 0.12, 0], "up": [0, 1, 0], "fov": 30}, 0.004),
    ("crown", "scenes/crown_flat.ply",
     {"eye": [0, 5.5, 24], "at": [0, 11, -10], "up": [0, 1, 0], "fov": 47, "fov_axis": "x"}, 0.2),
    ("bathroom", "scenes/contemporary-bathroom_flat.ply",
     {"eye": [0.00724, 0.91240, -0.22758], "dir": [-0.751879, 0.015471, -0.659119],
      "up": [0.0116337, 0.99988, 0.0101985], "fov": 55}, 0.01),
]

def large_job(n, cams):
    scenes = []
    for k in range(n):
        name, rel, ref, step = LARGE[k % len(LARGE)]
        if have(rel):
            mesh = os.path.join(meshes, rel)
        else:
            mesh, ref, step = "procedural:spheres?tris=2000000", {"eye": [0, 2, 14], "at": [0, 0, 0], "fov": 45}, 0.1
        cameras = []
        for i in range(cams):
            c = dict(ref, name=f"c{i}")
            c["eye"] = [ref["eye"][0] + i * step, ref["eye"][1], ref["eye"][2]]
            cameras.append(c)
        scenes.append({"name": f"{name}{k}", "scene": {"meshes": [{"path": mesh}]}, "cameras": cameras})
    return dict(shared, scenes=scenes)

def write_jobs(label, job):
    d = os.path.join(out, label)
    os.makedirs(d)
    job["output"] = "pipe/{scene}/{camera}_{frame}.exr"
    json.dump(job, open(os.path.join(d, "many.json"), "w"), indent=1)
    # Scene k alone: the entry merged over the shared keys, as readJobFile merges it.
    for k, entry in enumerate(job["scenes"]):
        one = {key: v for key, v in job.items() if key != "scenes"}
        one.update({key: v for key, v in entry.items() if key != "name"})
        one["output"] = f"alone/{entry['name']}/{{camera}}_{{frame}}.exr"
        json.dump(one, open(os.path.join(d, f"alone{k:03d}.json"), "w"), indent=1)

write_jobs("small", small_job(int(os.environ["SMALL"]), int(os.environ["CAMS_SMALL"])))
if int(os.environ["LARGE"]) > 0:
    write_jobs("large", large_job(int(os.environ["LARGE"]), int(os.environ["CAMS_LARGE"])))
PY

echo "many_meshes: $(date -u '+%Y-%m-%d %H:%M UTC'); CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'); $(nproc) cores; SIZE=$SIZE AOVS=$AOVS"
for label in small large; do
  [[ -d $dir/$label ]] || continue
  "$bin" batch --quiet "$dir/$label/many.json" --summary "$dir/$label/many.summary.json"
  for one in "$dir/$label"/alone*.json; do
    "$bin" batch --quiet "$one" --summary "${one%.json}.summary.json"
  done
done

python3 - "$dir" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
print("| job | scenes | images | triangles/scene (max) | L = load+build s | sum S_k s | T_pipe s | "
      "steady Mrays/s | pipelined Mrays/s | ratio | K separate runs (sum S_k + L) s |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for label in ("small", "large"):
    d = os.path.join(out, label)
    if not os.path.isdir(d):
        continue
    many = json.load(open(os.path.join(d, "many.summary.json")))
    assert many["images_ok"] == many["images_in_job"], f"{label}: images failed"
    alone = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(d, "alone*.summary.json")))]
    rays = many["rays"]
    assert rays == sum(a["rays"] for a in alone), f"{label}: the runs traced different rays"
    steady = sum(a["elapsed_seconds"] for a in alone)
    loads = sum(s.get("load_seconds", 0) + s.get("build_seconds", 0) for s in many["scenes"])
    pipe = many["elapsed_seconds"]
    tris = max(s.get("triangles", 0) for s in many["scenes"])
    print(f"| {label} | {many['scene_count']} | {many['images_ok']} | {tris:,} | {loads:.3f} | "
          f"{steady:.3f} | {pipe:.3f} | {rays / steady * 1e-6:.1f} | {rays / pipe * 1e-6:.1f} | "
          f"{steady / pipe:.3f} | {steady + loads:.3f} |")
PY
