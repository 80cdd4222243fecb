#!/usr/bin/env bash
# Flat memory over a long batch (issue 6): a 1,000-frame orbit of a small procedural scene at
# 64x48, all AOVs. Reports the process's peak resident set (VmHWM) after frame 10 and at the
# end; a leak per frame shows as growth between the two. Not part of CI (~1-2 minutes).
#   bench/batch_memory.sh [BUILD_DIR] [FRAMES]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
frames=${2:-1000}
bin="$build/apps/aperture"
[[ -x $bin ]] || { echo "batch_memory: build first ($bin missing)"; exit 2; }
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cat >"$dir/job.json" <<JOB
{
  "scene": {"meshes": [{"path": "procedural:default?tris=20000"}]},
  "cameras": [{"name": "orbit", "orbit": {"centre": [0, 0, 0], "radius": 10, "elevation": 20},
               "frames": $frames, "fov": 45}],
  "aovs": "all",
  "size": [64, 48],
  "output": "out/{camera}_{frame:04d}.exr",
  "performance": {"threads": 2}
}
JOB
"$bin" batch --quiet "$dir/job.json" &
pid=$!
count() { { ls "$dir/out" 2>/dev/null || true; } | grep -c '^orbit_.*\.exr$' || true; }
hwm() { awk '/VmHWM/ {print $2}' "/proc/$pid/status" 2>/dev/null || echo 0; }
rss10="" last=0
while kill -0 "$pid" 2>/dev/null; do
  n=$(count)
  h=$(hwm)
  [[ -n $h && $h != 0 ]] && last=$h
  if [[ -z $rss10 && $n -ge 10 ]]; then rss10=$last; fi
  sleep 0.05
done
wait "$pid"
n=$(count)
echo "batch_memory: $n of $frames frames written"
echo "batch_memory: peak RSS after frame 10: $((rss10 / 1024)) MB (${rss10} kB)"
echo "batch_memory: peak RSS at frame $n (last sample before exit): $((last / 1024)) MB (${last} kB)"
