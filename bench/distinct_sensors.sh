#!/usr/bin/env bash
# A batch where every image has its own distorted sensor, as COLMAP calibrates by default (one
# camera per image): each image pays for its sensor's direction table (every pixel's ray by
# the lens's exact inverse) before its first ray. Writes a COLMAP text model of N images of
# the bunny, each with its own OPENCV camera (1920x1080, focal length 1500 + k), and renders
# it with `batch --cameras` (depth only), alternating two builds, ROUNDS times; prints each
# run's wall time and peak resident size.
#   BEFORE=/tmp/before/build/apps/aperture bash bench/distinct_sensors.sh
#   (AFTER=build/apps/aperture N=100 ROUNDS=2 by default; SHARED=../shared; FLAGS: more batch
#   flags for both builds, e.g. FLAGS=--preview, whose automatic depth range locates every
#   camera before the first image; RESUME=1: after each render, time `--resume` of the same
#   build, which finds every image up to date)
set -euo pipefail
cd "$(dirname "$0")/.."
: "${BEFORE:?BEFORE=path of the aperture binary to compare with}"
AFTER=${AFTER:-build/apps/aperture}
N=${N:-100}
mesh=${SHARED:-../shared}/meshes/stanford/bun_zipper.ply
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/sparse"
python3 - "$work/sparse" "$N" <<'PY'
import sys
out, n = sys.argv[1], int(sys.argv[2])
with open(f'{out}/cameras.txt', 'w') as f:
    for c in range(1, n + 1):
        f.write(f'{c} OPENCV 1920 1080 {1500 + c} {1500 + c} 960 540 -0.1 0.01 0.0001 -0.0001\n')
with open(f'{out}/images.txt', 'w') as f:
    for c in range(1, n + 1):  # identity rotation, the bunny 0.45 in front of the camera
        f.write(f'{c} 1 0 0 0 0.0 -0.12 0.45 {c} img{c:04d}.png\n\n')
open(f'{out}/points3D.txt', 'w').close()
PY
for round in $(seq 1 "${ROUNDS:-2}"); do
  for side in before after; do
    bin=$BEFORE
    [[ $side == after ]] && bin=$AFTER
    rm -rf "$work/out"
    runs=("")
    [[ ${RESUME:-0} == 1 ]] && runs+=(--resume)
    for resume in "${runs[@]}"; do
      # shellcheck disable=SC2086 # FLAGS are words
      /usr/bin/time -f "$side round $round${resume:+ $resume}: %e s wall, %M KiB peak" "$bin" \
        batch --quiet $resume --mesh "$mesh" --cameras "$work/sparse" --out "$work/out" \
        --aov depth ${FLAGS:-} 2>&1 >/dev/null | tail -1
    done
  done
done
