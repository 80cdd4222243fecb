#!/usr/bin/env bash
# A batch whose writes matter: 16 views of the bathroom (an orbit of 5 cm radius about its
# reference camera's eye, 40 degrees of sweep, fov 55), 1920x1080, depth,normal, 2 threads,
# written as EXR uncompressed ("none") and with zip (the default, "zip"), and as a dataset
# ("dataset": depth as 16-bit PNG in millimetres, normal as NPY, no EXR). MESH=path picks
# another mesh, seen from an orbit of radius 0.45 about (0, 0.12, 0) with fov 30 (the dragon's
# reference camera, turned about +Y). Two builds side by side: runs alternate between BEFORE
# and AFTER, ROUNDS times (8 by default), and the table gives each build's median of the
# batch's elapsed_seconds (summary.json: the renders and writes, not the load) and the ratio.
# Without BEFORE, only AFTER runs.
#   BEFORE=/tmp/before/build/apps/aperture bash bench/batch_write.sh
#   (AFTER=build/apps/aperture ROUNDS=8 THREADS=2 SHARED=../shared by default)
set -euo pipefail
cd "$(dirname "$0")/.."
AFTER=${AFTER:-build/apps/aperture}
mesh=$(realpath "${SHARED:-../shared}")/meshes/scenes/contemporary-bathroom_flat.ply
orbit='"centre": [0.00724, 0.91240, -0.22758], "radius": 0.05, "elevation": 0, "start": 0, "sweep": 40'
fov=55
if [[ -n ${MESH:-} ]]; then
  mesh=$(realpath "$MESH")
  orbit='"centre": [0, 0.12, 0], "radius": 0.45, "elevation": 0, "start": 0, "sweep": 360'
  fov=30
fi
[[ -f $mesh ]] || { echo "batch_write: $mesh missing (../shared/meshes)"; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
variants=(none zip dataset)
for variant in "${variants[@]}"; do
  files="\"output\": \"$dir/out/{camera}_{frame:04d}.exr\", \"compression\": \"$variant\""
  if [[ $variant == dataset ]]; then
    files="\"outputs\": [{\"aov\": \"depth\", \"path\": \"$dir/out/{camera}_{frame:04d}.png\"},
              {\"aov\": \"normal\", \"path\": \"$dir/out/{camera}_{frame:04d}.npy\"}]"
  fi
  cat >"$dir/$variant.json" <<JOB
{
  "scene": { "meshes": [ { "path": "$mesh" } ] },
  "cameras": [ { "name": "view", "orbit": { $orbit }, "frames": 16, "up": [0, 1, 0], "fov": $fov } ],
  "aovs": ["depth", "normal"],
  "size": [1920, 1080],
  $files,
  "performance": { "threads": ${THREADS:-2} }
}
JOB
done
sides=(after)
[[ -n ${BEFORE:-} ]] && sides=(before after)
for round in $(seq 1 "${ROUNDS:-8}"); do
  for variant in "${variants[@]}"; do
    for side in "${sides[@]}"; do
      bin=$AFTER
      [[ $side == before ]] && bin=$BEFORE
      rm -rf "$dir/out"
      # Depths beyond 65.535 m (through the bathroom's window) are PNG's zeros: its warning is
      # not wanted here.
      "$bin" batch "$dir/$variant.json" --quiet >/dev/null 2>&1
      python3 -c 'import json, sys; print(sys.argv[1], sys.argv[2], json.load(open(sys.argv[3]))["elapsed_seconds"])' \
        "$variant" "$side" "$dir/out/summary.json" >>"$dir/times"
    done
  done
done
python3 - "$dir/times" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    variant, side, seconds = line.split()
    runs[variant, side].append(float(seconds))
print("| files | before s (min–max) | after s (min–max) | before / after |")
print("|---|---|---|---:|")
for c in ("none", "zip", "dataset"):
    cell = lambda v: f"{statistics.median(v):.3f} ({min(v):.3f}–{max(v):.3f})" if v else "—"
    b, a = runs.get((c, "before"), []), runs[c, "after"]
    ratio = f"{statistics.median(b) / statistics.median(a):.2f}" if b else "—"
    print(f"| {c} | {cell(b)} | {cell(a)} | {ratio} |")
PY
