#!/usr/bin/env bash
# A batch whose EXR writes matter: 16 views of the bathroom (an orbit of 5 cm radius about its
# reference camera's eye, 40 degrees of sweep, fov 55), 1920x1080, depth,normal, 2 threads,
# written uncompressed and with zip (the default). Two builds side by side: runs alternate
# between BEFORE and AFTER, ROUNDS times (8 by default), and the table gives each build's median
# of the batch's elapsed_seconds (summary.json: the renders and writes, not the load) and the
# ratio. Without BEFORE, only AFTER runs.
#   BEFORE=/tmp/before/build/apps/aperture bash bench/batch_write.sh
#   (AFTER=build/apps/aperture ROUNDS=8 THREADS=2 SHARED=../shared by default)
set -euo pipefail
cd "$(dirname "$0")/.."
AFTER=${AFTER:-build/apps/aperture}
mesh=$(realpath "${SHARED:-../shared}")/meshes/scenes/contemporary-bathroom_flat.ply
[[ -f $mesh ]] || { echo "batch_write: $mesh missing (../shared/meshes)"; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
for compression in none zip; do
  cat >"$dir/$compression.json" <<EOF
{
  "scene": { "meshes": [ { "path": "$mesh" } ] },
  "cameras": [
    { "name": "bath", "orbit": { "centre": [0.00724, 0.91240, -0.22758], "radius": 0.05,
                                 "elevation": 0, "start": 0, "sweep": 40 },
      "frames": 16, "up": [0, 1, 0], "fov": 55 }
  ],
  "aovs": ["depth", "normal"],
  "size": [1920, 1080],
  "output": "$dir/out/{camera}_{frame:04d}.exr",
  "compression": "$compression",
  "performance": { "threads": ${THREADS:-2} }
}
EOF
done
sides=(after)
[[ -n ${BEFORE:-} ]] && sides=(before after)
for round in $(seq 1 "${ROUNDS:-8}"); do
  for compression in none zip; do
    for side in "${sides[@]}"; do
      bin=$AFTER
      [[ $side == before ]] && bin=$BEFORE
      rm -rf "$dir/out"
      "$bin" batch "$dir/$compression.json" --quiet >/dev/null
      python3 -c 'import json, sys; print(sys.argv[1], sys.argv[2], json.load(open(sys.argv[3]))["elapsed_seconds"])' \
        "$compression" "$side" "$dir/out/summary.json" >>"$dir/times"
    done
  done
done
python3 - "$dir/times" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    compression, side, seconds = line.split()
    runs[compression, side].append(float(seconds))
print("| compression | before s (min–max) | after s (min–max) | before / after |")
print("|---|---|---|---:|")
for c in ("none", "zip"):
    cell = lambda v: f"{statistics.median(v):.3f} ({min(v):.3f}–{max(v):.3f})" if v else "—"
    b, a = runs.get((c, "before"), []), runs[c, "after"]
    ratio = f"{statistics.median(b) / statistics.median(a):.2f}" if b else "—"
    print(f"| {c} | {cell(b)} | {cell(a)} | {ratio} |")
PY
