#!/usr/bin/env bash
# Issue 42 item 7: the scan loop's points per second against bare Embree on the same rays
# (`aperture scan --bench`: best of 15 of each, alternating, one sweep's rays), for an OS1-128 at
# 2048 columns (262144 rays a sweep) inside the crown (3.5M triangles) and inside a 10M-triangle
# procedural scene. The scan loop traces first returns and fills the fields of the --out format
# (FORMAT=ply: every field; FORMAT=bin: KITTI x y z intensity instance); bare Embree is
# rtcIntersect16 over the same float rays, nothing else. Each line gives wall and CPU seconds
# (the process's, the steadier on a loaded machine) and the time to make the sweep's rays.
# Run on an idle machine:
#   bash bench/scan_speed.sh            (ROUNDS=3 by default)
set -euo pipefail
BIN=${BIN:-build/apps/aperture}
SHARED=${SHARED:-../shared/meshes}
out=${OUT:-/tmp/scan_speed}; mkdir -p "$out"
# The sensor's z (spin axis) along the world's y (the crown's up), at the crown's middle.
printf '0 0 10 0 -0.7071067811865476 0 0 0.7071067811865476\n' > "$out/crown_pose.txt"
printf '0 0 0 0 0 0 0 1\n' > "$out/origin_pose.txt"
lscpu | grep 'Model name' || true
for round in $(seq 1 "${ROUNDS:-3}"); do
  echo "round $round, load $(cut -d' ' -f1 /proc/loadavg)"
  "$BIN" scan --mesh "$SHARED/scenes/crown_flat.ply" --lidar OS1-128 --columns 2048 \
    --trajectory "$out/crown_pose.txt" --out "$out/crown.${FORMAT:-ply}" --bench --quiet --threads 2
  "$BIN" scan --mesh 'procedural:spheres?tris=10000000' --lidar OS1-128 --columns 2048 \
    --trajectory "$out/origin_pose.txt" --out "$out/spheres.${FORMAT:-ply}" --bench --quiet --threads 2
done
