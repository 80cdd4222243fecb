#!/usr/bin/env bash
# Issue 13: the frame loop's own cost, `aperture bench --null` (rays generated, every ray a fake
# hit, every requested AOV written, no Embree call), in ns/ray, for each camera model and the
# calibrated cameras of issue 11 (bench/null_cameras.sh). Target: <= 1 ns/ray at 2 threads.
# Prints a table: camera, AOVs, median ns/ray (median over frames, then over rounds).
#   bash bench/null_overhead.sh   (THREADS=2 ROUNDS=3 FRAMES=20 SIZE=1920,1080
#                                  AOVS='depth,normal color' by default)
set -euo pipefail
BIN=${BIN:-build/apps/aperture}
# The geometry is never traced; a small procedural mesh keeps loading out of the way.
MESH=${MESH:-procedural:spheres?tris=100000}
SIZE=${SIZE:-1920,1080}
source "$(dirname "$0")/null_cameras.sh"
out=${OUT:-/tmp/null_overhead}
mkdir -p "$out"
rm -f "$out"/*.json
read -r -a aovsets <<<"${AOVS:-depth,normal color}" # AOV sets, space-separated
for round in $(seq 1 "${ROUNDS:-3}"); do
  for cfg in "${NULL_CAMERAS[@]}"; do
    name=${cfg%%:*}
    flags=${cfg#*:}
    for aovs in "${aovsets[@]}"; do
      # shellcheck disable=SC2086 # the flags are words
      $BIN bench --null --mesh "$MESH" $POSE $flags --aov "$aovs" --threads "${THREADS:-2}" \
        --frames "${FRAMES:-20}" --warmup "${WARMUP:-3}" --builds 1 --quiet \
        --json "$out/$name+$aovs+$round.json" >/dev/null
    done
  done
done
python3 - "$out" <<'PY'
import glob, json, os, statistics, sys
rows = {}
for f in sorted(glob.glob(f'{sys.argv[1]}/*.json')):
    j = json.load(open(f))
    name, aovs, _ = f.rsplit('/', 1)[1][:-5].split('+')
    rows.setdefault((name, aovs), []).append(j['null_ns_per_ray_median'])
    cfg = j['config']
print(f"threads {cfg['threads']}, ISA {cfg['isa']}, packet {cfg['packet_width']}, "
      f"tile {cfg['tile_size']}, {cfg['width']}x{cfg['height']}")
print('| camera | AOVs | ns/ray (median) | rounds |')
print('|---|---|---|---|')
order = os.environ['NULL_CAMERA_ORDER'].split()
for (name, aovs), vals in sorted(rows.items(), key=lambda r: (order.index(r[0][0]), r[0][1])):
    print(f"| {name} | {aovs} | {statistics.median(vals):.3f} | {[round(v, 3) for v in vals]} |")
PY
